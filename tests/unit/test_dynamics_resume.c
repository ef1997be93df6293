/* The integrator's restart contract (issue 36; cupid_dynamics_hooks.safe_point and
 * cupid_dynamics_options.resume): a run stopped at an output step's safe point and continued
 * from the state the hook gave ends with the same u, v, energies, balance and stable-step
 * figures, to the bit, as the run that never stopped. Cases: central differences on a chain of
 * springs in free vibration (the merged half-kicks between outputs), with a moving support and
 * a load in t (the reactions and the load in the state), and with Rayleigh damping; Newmark
 * with damping and the moving support. Each can fail: a piece of state left out of the restart
 * changes the bits (checked while writing it: leaving out the energy shares, or the load,
 * fails). A state of another size is refused. */
#include <math.h>
#include <string.h>

#include "cupid/dynamics.h"
#include "testutil.h"

#define N 12 /* a chain of N masses: N - 1 springs */
#define STOP 300

/* DOF 0: a support moving in t; DOF N-1 loaded by a harmonic force. */
static cupid_status conditions(void *ctx, double t, double *u_fixed, double *f) {
  (void)ctx;
  memset(f, 0, sizeof(double) * N);
  u_fixed[0] = 1e-2 * sin(3.0 * t);
  f[N - 1] = 0.5 * sin(1.7 * t);
  return CUPID_SUCCESS;
}

/* The state of the safe point at step STOP, copied out; the run stops there. */
typedef struct {
  cupid_dynamics_restart r;
  double u[N], v[N], a[N], react[N], load[N];
} saved;

static cupid_status save(void *ctx, const cupid_dynamics_restart *r) {
  saved *s = ctx;
  if (r->step != STOP) return CUPID_SUCCESS;
  s->r = *r;
  memcpy(s->u, r->u, sizeof s->u);
  memcpy(s->v, r->v, sizeof s->v);
  memcpy(s->a, r->a, sizeof s->a);
  if (r->react) memcpy(s->react, r->react, sizeof s->react), s->r.react = s->react;
  if (r->load) memcpy(s->load, r->load, sizeof s->load), s->r.load = s->load;
  s->r.u = s->u, s->r.v = s->v, s->r.a = s->a;
  return CUPID_ERR_INTERRUPTED; /* as a checkpoint after a signal */
}

static cupid_csr chain(void) {
  cupid_int rowptr[N + 1], col[3 * N];
  double val[3 * N];
  cupid_int nnz = 0;
  for (int i = 0; i < N; i++) {
    rowptr[i] = nnz;
    const double k = 2.0 + 0.1 * i;
    if (i > 0) col[nnz] = i - 1, val[nnz++] = -k;
    col[nnz] = i, val[nnz++] = (i > 0 ? k : 0.0) + (i < N - 1 ? 2.0 + 0.1 * (i + 1) : 0.0);
    if (i < N - 1) col[nnz] = i + 1, val[nnz++] = -(2.0 + 0.1 * (i + 1));
  }
  rowptr[N] = nnz;
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_csr_create(N, N, 1, rowptr, col, &K));
  memcpy(K->val, val, sizeof(double) * (size_t)nnz);
  return K;
}

/* The chain's masses and initial state, and the runs' options (700 steps of 0.02, an output
 * every 50). */
static void chain_state(double *mass, double *u0, double *v0) {
  for (int i = 0; i < N; i++) mass[i] = 1.0 + 0.05 * i, u0[i] = 1e-3 * sin(i), v0[i] = 1e-3 * cos(2.0 * i);
}

static cupid_dynamics_options chain_options(cupid_integrator integ, double damping) {
  cupid_dynamics_options o = cupid_dynamics_defaults();
  o.integrator = integ;
  o.dt = 0.02;
  o.steps = 700;
  o.every = 50;
  o.rayleigh_mass = damping;
  o.rayleigh_stiffness = damping * 0.01;
  return o;
}

/* The run that never stops, from (u0, v0): its final u, v and info. */
static void run_whole(const cupid_dynamics_system *sys, const cupid_dynamics_options *o,
                      const double *u0, const double *v0, double *u, double *v,
                      cupid_dynamics_info *info) {
  memcpy(u, u0, sizeof(double) * N), memcpy(v, v0, sizeof(double) * N);
  CUPID_ASSERT_OK(cupid_dynamics_run(sys, o, u, v, NULL, NULL, info));
}

static void run_case(cupid_integrator integ, int moving, double damping) {
  cupid_csr K = chain();
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(N, &bc));
  if (moving) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 0, 0.0));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  double mass[N], u0[N], v0[N];
  chain_state(mass, u0, v0);
  cupid_dynamics_hooks plain = {.conditions = moving ? conditions : NULL};
  cupid_dynamics_options o = chain_options(integ, damping);
  o.velocity_at_outputs = 1;
  o.hooks = moving ? &plain : NULL;
  cupid_dynamics_system sys = {.K = K, .m_lumped = mass, .bc = bc};
  double u[N], v[N];
  cupid_dynamics_info whole;
  run_whole(&sys, &o, u0, v0, u, v, &whole);
  /* stopped at step STOP by its safe point, then resumed from the saved state */
  saved s;
  memset(&s, 0, sizeof s);
  cupid_dynamics_hooks hooks = plain;
  hooks.safe_point = save;
  hooks.ctx = &s; /* conditions ignores its context */
  o.hooks = &hooks;
  double u2[N], v2[N];
  memcpy(u2, u0, sizeof u2), memcpy(v2, v0, sizeof v2);
  cupid_dynamics_info first, second;
  assert_int_equal(cupid_dynamics_run(&sys, &o, u2, v2, NULL, NULL, &first), CUPID_ERR_INTERRUPTED);
  cupid_error_clear();
  assert_int_equal(s.r.step, STOP);
  hooks.safe_point = NULL;
  o.resume = &s.r;
  memset(u2, 0, sizeof u2), memset(v2, 0, sizeof v2); /* the state brings them */
  CUPID_ASSERT_OK(cupid_dynamics_run(&sys, &o, u2, v2, NULL, NULL, &second));
  assert_memory_equal(u, u2, sizeof u);
  assert_memory_equal(v, v2, sizeof v);
  assert_memory_equal(&whole.max_balance, &second.max_balance, sizeof(double));
  assert_memory_equal(&whole.dt_critical, &second.dt_critical, sizeof(double));
  assert_memory_equal(&whole.omega_max, &second.omega_max, sizeof(double));
  print_message("%s, %s, damping %g: u[N-1] %.12g resumed at step %d, the same bits\n",
                integ == CUPID_INTEGRATOR_CENTRAL ? "central" : "newmark",
                moving ? "moving support and load" : "free", damping, u2[N - 1], STOP);
  /* a state of another system is refused */
  s.r.n = N + 1;
  assert_int_equal(cupid_dynamics_run(&sys, &o, u2, v2, NULL, NULL, &second), CUPID_ERR_ARGUMENT);
  cupid_error_clear();
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
}

static void test_central(void **state) {
  (void)state;
  run_case(CUPID_INTEGRATOR_CENTRAL, 0, 0.0);  /* free: merged half-kicks */
  run_case(CUPID_INTEGRATOR_CENTRAL, 1, 0.0);  /* moving support, load in t */
  run_case(CUPID_INTEGRATOR_CENTRAL, 1, 0.05); /* and damping */
}

static void test_newmark(void **state) {
  (void)state;
  run_case(CUPID_INTEGRATOR_NEWMARK, 0, 0.05);
  run_case(CUPID_INTEGRATOR_NEWMARK, 1, 0.05);
}

/* ---- A changed system (restart.changed; issue 37's adaptive zones) ---- */

/* hooks->pause stops the run at step STOP; hooks->stopped copies the state out. */
static cupid_status pause_at(void *ctx, cupid_int step, const double *u, const double *v, int *stop) {
  (void)ctx, (void)u, (void)v;
  *stop = step == STOP;
  return CUPID_SUCCESS;
}

static cupid_status keep(void *ctx, const cupid_dynamics_restart *r) {
  saved *s = ctx;
  s->r = *r;
  memcpy(s->u, r->u, sizeof s->u);
  memcpy(s->v, r->v, sizeof s->v);
  s->r.u = s->u, s->r.v = s->v, s->r.a = NULL, s->r.react = NULL, s->r.load = NULL;
  return CUPID_SUCCESS;
}

/* Records the energies of the output steps (the last one's balance). */
static cupid_status last_energy(void *ctx, cupid_int step, double t, int output, const double *u,
                                const double *v, const double *a, const cupid_dynamics_energy *e) {
  (void)step, (void)t, (void)u, (void)v, (void)a;
  if (output) *(cupid_dynamics_energy *)ctx = *e;
  return CUPID_SUCCESS;
}

/* Stopped by pause at step STOP and resumed as a changed system: (1) the same K: the run that
 * never stopped, to round-off (the acceleration made again from K u equals the kick's), and a
 * change of no energy; (2) K stiffer by 30%: the change's energy is u.(K2 - K1) u / 2 at the
 * step, booked as conversion, and the balance with it stays at the run's own level (without
 * it the balance would miss by that energy). */
static void test_changed(void **state) {
  (void)state;
  cupid_csr K = chain(), K2 = chain();
  for (cupid_int k = 0; k < K2->rowptr[N]; k++) K2->val[k] *= 1.3;
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(N, &bc));
  CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 0, 0.0));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  double mass[N], u0[N], v0[N];
  chain_state(mass, u0, v0);
  cupid_dynamics_hooks plain = {.conditions = conditions};
  cupid_dynamics_options o = chain_options(CUPID_INTEGRATOR_CENTRAL, 0.0);
  o.hooks = &plain;
  cupid_dynamics_system sys = {.K = K, .m_lumped = mass, .bc = bc};
  double u[N], v[N];
  cupid_dynamics_info whole;
  run_whole(&sys, &o, u0, v0, u, v, &whole);

  saved s;
  memset(&s, 0, sizeof s);
  cupid_dynamics_hooks hooks = plain;
  hooks.pause = pause_at, hooks.stopped = keep, hooks.ctx = &s;
  o.hooks = &hooks;
  double u2[N], v2[N];
  memcpy(u2, u0, sizeof u2), memcpy(v2, v0, sizeof v2);
  cupid_dynamics_info first, second;
  CUPID_ASSERT_OK(cupid_dynamics_run(&sys, &o, u2, v2, NULL, NULL, &first));
  assert_int_equal(first.stopped_at, STOP);
  assert_int_equal(s.r.step, STOP);
  const saved at = s; /* the state at the step, for the second case */
  s.r.changed = 1;
  o.resume = &s.r;
  hooks.pause = NULL;
  cupid_dynamics_energy e = {0};
  CUPID_ASSERT_OK(cupid_dynamics_run(&sys, &o, u2, v2, last_energy, &e, &second));
  assert_int_equal(second.stopped_at, 0);
  for (int i = 0; i < N; i++) {
    assert_true(fabs(u2[i] - u[i]) <= 1e-12 * fabs(u[N - 1]) + 1e-300);
    assert_true(fabs(v2[i] - v[i]) <= 1e-12 * fabs(v[N - 1]) + 1e-300);
  }
  const double level = e.kinetic + e.strain;
  assert_true(fabs(second.changed_energy) <= 1e-14 * level);
  print_message("changed, the same K: u[N-1] %.12g against %.12g, change energy %.2e of %.2e\n",
                u2[N - 1], u[N - 1], second.changed_energy, level);

  /* the stiffer K from STOP on */
  s = at;
  s.r.changed = 1;
  sys.K = K2;
  double ku1[N], ku2[N], expect = 0.0;
  cupid_csr_matvec(K, s.u, ku1);
  cupid_csr_matvec(K2, s.u, ku2);
  for (int i = 0; i < N; i++) expect += 0.5 * s.u[i] * (ku2[i] - ku1[i]);
  CUPID_ASSERT_OK(cupid_dynamics_run(&sys, &o, u2, v2, last_energy, &e, &second));
  print_message("changed, K x 1.3: change energy %.6e (u.dK u / 2 = %.6e), conversion %.6e, "
                "balance %.2e of %.2e (the unchanged run's %.2e)\n",
                second.changed_energy, expect, e.conversion, e.balance, e.kinetic + e.strain,
                whole.max_balance);
  assert_true(fabs(second.changed_energy - expect) <= 1e-12 * fabs(expect));
  assert_true(fabs(e.conversion - expect) <= 1e-12 * fabs(expect));
  /* the balance's bound: the unchanged run's own worst (relative) times 10, far below the
   * change's energy it would miss by if the change were not booked */
  assert_true(second.max_balance <= 10.0 * whole.max_balance + 1e-12);
  assert_true(fabs(expect) > 100.0 * second.max_balance * (e.kinetic + e.strain));
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  cupid_csr_destroy(&K2);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_central), cmocka_unit_test(test_newmark),
                                     cmocka_unit_test(test_changed)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
