/* The hooks of a dynamic run (cupid_dynamics_hooks): time-dependent conditions against
 * closed-form solutions (a support moving at constant speed; a harmonic load), with the
 * energy balance including the supports' work, for both integrators; an after-forces hook
 * that removes a spring (a broken bond) with its energy counted as dissipated. */
#include <math.h>
#include <string.h>

#include "cupid/dynamics.h"
#include "testutil.h"

typedef struct {
  double speed, F0, Omega;
} drive;

/* DOF 0: a support moving at `speed`; DOF 1: free, loaded by F0 sin(Omega t). */
static cupid_status conditions(void *ctx, double t, double *u_fixed, double *f) {
  const drive *d = ctx;
  u_fixed[0] = d->speed * t;
  u_fixed[1] = 0.0;
  f[0] = 0.0;
  f[1] = d->F0 * sin(d->Omega * t);
  return CUPID_SUCCESS;
}

/* K = k [[1, -1], [-1, 1]]: a mass on a spring to the support. */
static cupid_csr spring(double k) {
  cupid_csr K = NULL;
  cupid_int rowptr[3] = {0, 2, 4}, col[4] = {0, 1, 0, 1};
  double val[4] = {k, -k, -k, k};
  CUPID_ASSERT_OK(cupid_csr_create(2, 2, 1, rowptr, col, &K));
  memcpy(K->val, val, sizeof val);
  return K;
}

/* x(t) of the mass from rest: support motion V t - V/w sin(w t) plus the harmonic load's
 * F0/(k - m W^2) (sin W t - W/w sin w t). */
static double exact(const drive *d, double k, double m, double t) {
  const double w = sqrt(k / m);
  return d->speed * t - d->speed / w * sin(w * t) +
         d->F0 / (k - m * d->Omega * d->Omega) * (sin(d->Omega * t) - d->Omega / w * sin(w * t));
}

static void run_case(cupid_integrator integ, double speed, double F0) {
  const double k = 4.0, m = 1.0, w = 2.0, T = 2 * 3.14159265358979323846 / w;
  drive d = {.speed = speed, .F0 = F0, .Omega = 0.7 * w};
  cupid_csr K = spring(k);
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(2, &bc));
  CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 0, 0.0));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  double mass[2] = {1.0, m}, u[2] = {0, 0}, v[2] = {0, 0};
  cupid_dynamics_hooks hooks = {.conditions = conditions, .ctx = &d};
  cupid_dynamics_options o = cupid_dynamics_defaults();
  o.integrator = integ;
  o.dt = T / 400;
  o.steps = 1000; /* 2.5 periods */
  o.hooks = &hooks;
  cupid_dynamics_system sys = {.K = K, .m_lumped = mass, .bc = bc};
  cupid_dynamics_info info;
  CUPID_ASSERT_OK(cupid_dynamics_run(&sys, &o, u, v, NULL, NULL, &info));
  const double t = o.dt * (double)o.steps, x = exact(&d, k, m, t);
  /* Both schemes are second order: phase error ~ (w dt)^2 / 24 ~ 1e-5 per radian, 16 radians:
   * 1e-3 of the amplitude (V/w + F0/(k - m W^2) ~ 1). */
  print_message("%s speed %g F0 %g: u(t) %.8f exact %.8f, u_support %.6f, balance %.2e\n",
                integ == CUPID_INTEGRATOR_CENTRAL ? "central" : "newmark", speed, F0, u[1], x,
                u[0], info.max_balance);
  ASSERT_NEAR(u[1], x, 1e-3);
  ASSERT_NEAR(u[0], speed * t, 1e-12);
  /* energy balance with the supports' work: trapezoidal reactions, O(dt^2) */
  assert_true(info.max_balance < 1e-3);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
}

static void test_moving_support(void **state) {
  (void)state;
  run_case(CUPID_INTEGRATOR_CENTRAL, 0.5, 0.0);
  run_case(CUPID_INTEGRATOR_NEWMARK, 0.5, 0.0);
}

static void test_harmonic_load(void **state) {
  (void)state;
  run_case(CUPID_INTEGRATOR_CENTRAL, 0.0, 1.5);
  run_case(CUPID_INTEGRATOR_NEWMARK, 0.0, 1.5);
  run_case(CUPID_INTEGRATOR_CENTRAL, 0.3, 1.5);
}

/* Two free masses joined by a spring that breaks at step 40: the spring's energy at that
 * moment goes to `fracture`, and kinetic + strain + fracture stays the initial energy. */
typedef struct {
  double k;
  cupid_int breaks_at;
  int update_ku; /* the hook updates K u itself (1) or asks for a new product (0) */
} breakable;

static cupid_status two_masses(void *ctx, const double *x, double *y) {
  const breakable *b = ctx;
  y[0] = b->k * (x[0] - x[1]);
  y[1] = -y[0];
  return CUPID_SUCCESS;
}

static cupid_status break_spring(void *ctx, cupid_int step, double t, const double *u,
                                 double *ku, double *dissipated, int *changed) {
  (void)t;
  breakable *b = ctx;
  *dissipated = 0.0;
  if (step == b->breaks_at) {
    *dissipated = 0.5 * b->k * (u[0] - u[1]) * (u[0] - u[1]);
    b->k = 0.0;
    if (b->update_ku) ku[0] = ku[1] = 0.0; /* the new K's product: no spring left */
    *changed = b->update_ku ? 1 : 2;
  }
  return CUPID_SUCCESS;
}

static cupid_status last_energy(void *ctx, cupid_int step, double t, int output, const double *u,
                                const double *v, const double *a, const cupid_dynamics_energy *e) {
  (void)step, (void)t, (void)u, (void)v, (void)a;
  if (output) *(cupid_dynamics_energy *)ctx = *e;
  return CUPID_SUCCESS;
}

/* The spring breaks at step 40 with the hook updating K u itself (update_ku) or asking for a
 * new product: the same run either way. */
static void run_breaking(int update_ku, double u[2], double v[2], cupid_dynamics_energy *e,
                         cupid_dynamics_info *info) {
  breakable b = {.k = 3.0, .breaks_at = 40, .update_ku = update_ku};
  cupid_dynamics_hooks hooks = {.after_forces = break_spring, .ctx = &b};
  double mass[2] = {1.0, 2.0};
  u[0] = 0.1, u[1] = -0.1, v[0] = v[1] = 0.0;
  cupid_dynamics_explicit_system es = {.n = 2, .apply = two_masses, .ctx = &b, .m_lumped = mass};
  cupid_dynamics_options o = cupid_dynamics_defaults();
  o.integrator = CUPID_INTEGRATOR_CENTRAL;
  o.dt = 0.01;
  o.steps = 100;
  o.hooks = &hooks;
  CUPID_ASSERT_OK(cupid_dynamics_run_explicit(&es, &o, u, v, last_energy, e, info));
  assert_true(b.k == 0.0);
  /* Newmark refuses the hook (it factors K once) */
  o.integrator = CUPID_INTEGRATOR_NEWMARK;
  cupid_csr K = spring(3.0);
  cupid_dynamics_system sys = {.K = K, .m_lumped = mass};
  assert_int_equal(cupid_dynamics_run(&sys, &o, u, v, NULL, NULL, NULL), CUPID_ERR_ARGUMENT);
  cupid_csr_destroy(&K);
}

static void test_after_forces(void **state) {
  (void)state;
  for (int update = 0; update < 2; update++) {
    double u[2], v[2];
    cupid_dynamics_energy e = {0};
    cupid_dynamics_info info;
    run_breaking(update, u, v, &e, &info);
    assert_true(e.fracture > 0.0);
    assert_true(e.strain == 0.0);
    /* E0 = 1/2 k 0.2^2 = 0.06; velocity Verlet keeps the balance to O(dt^2) ~ 1e-4 */
    ASSERT_NEAR(e.kinetic + e.fracture, 0.06, 1e-4);
    assert_true(info.max_balance < 2e-3);
  }
  /* the updated K u and the new product give the same run, to the last bit here (0 - 0) */
  double u0[2], v0[2], u1[2], v1[2];
  cupid_dynamics_energy e0 = {0}, e1 = {0};
  cupid_dynamics_info i0, i1;
  run_breaking(0, u0, v0, &e0, &i0);
  run_breaking(1, u1, v1, &e1, &i1);
  for (int k = 0; k < 2; k++) {
    assert_true(u0[k] == u1[k]);
    assert_true(v0[k] == v1[k]);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_moving_support),
                                     cmocka_unit_test(test_harmonic_load),
                                     cmocka_unit_test(test_after_forces)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
