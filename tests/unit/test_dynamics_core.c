/* Unit tests of the time integrators (src/dynamics) on a single-DOF oscillator, where the
 * discrete solutions are known in closed form. */
#include <math.h>
#include <string.h>

#include "cupid/dynamics.h"
#include "testutil.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* A 1x1 scalar CSR holding value (stiffness or mass of one DOF). */
static cupid_csr sdof_matrix(double value) {
  cupid_int rowptr[2] = {0, 1}, col[1] = {0};
  cupid_csr A = NULL;
  CUPID_ASSERT_OK(cupid_csr_create(1, 1, 1, rowptr, col, &A));
  A->val[0] = value;
  return A;
}

typedef struct {
  double max_rel_balance, e0;
  double u_prev2, u_prev, t_prev;
  double peaks[64];
  int n_peaks;
  double last_u;
} record;

static cupid_status observe(void *ctx, cupid_int step, double t, int output, const double *u,
                            const double *v, const double *a, const cupid_dynamics_energy *e) {
  record *r = ctx;
  if (step == 0) r->e0 = e->kinetic + e->strain;
  double rel = fabs(e->balance) / r->e0;
  if (rel > r->max_rel_balance) r->max_rel_balance = rel;
  /* local maxima of u (for the logarithmic decrement) */
  if (step >= 2 && r->u_prev > r->u_prev2 && r->u_prev >= u[0] && r->n_peaks < 64)
    r->peaks[r->n_peaks++] = r->u_prev;
  r->u_prev2 = r->u_prev;
  r->u_prev = u[0];
  r->last_u = u[0];
  return CUPID_SUCCESS;
}

/* Newmark average acceleration, undamped: it is the trapezoidal rule, so the discrete energy
 * is conserved exactly (tolerance 1e-12: round-off over 1000 steps) and the solution is
 * cos(omega_h t) with the known period elongation omega_h dt = 2 atan(omega dt / 2). */
static void test_newmark_sdof_exact(void **state) {
  double k = 4.0, m = 0.25, omega = sqrt(k / m), T = 2 * M_PI / omega;
  cupid_csr K = sdof_matrix(k);
  double mass = m, u = 1.0, v = 0.0;
  cupid_dynamics_system sys = {.K = K, .m_lumped = &mass};
  cupid_dynamics_options o = cupid_dynamics_defaults();
  o.dt = T / 20;
  o.steps = 1000; /* 50 periods */
  record r = {0};
  cupid_dynamics_info info;
  CUPID_ASSERT_OK(cupid_dynamics_run(&sys, &o, &u, &v, observe, &r, &info));
  assert_true(r.max_rel_balance < 1e-12);
  double wh = 2.0 * atan(omega * o.dt / 2.0) / o.dt;
  ASSERT_NEAR(u, cos(wh * o.dt * (double)o.steps), 1e-9);
  assert_true(info.max_balance < 1e-12);
  cupid_csr_destroy(&K);
}

/* The same with a consistent (CSR) mass and a prescribed-value DOF elsewhere: a 2-DOF system
 * where DOF 1 is fixed at 0.5 and does not move. */
static void test_newmark_fixed_dof(void **state) {
  cupid_int rowptr[3] = {0, 2, 4}, col[4] = {0, 1, 0, 1};
  cupid_csr K = NULL, M = NULL;
  CUPID_ASSERT_OK(cupid_csr_create(2, 2, 1, rowptr, col, &K));
  CUPID_ASSERT_OK(cupid_csr_create(2, 2, 1, rowptr, col, &M));
  double kv[4] = {2, -1, -1, 2}, mv[4] = {2, 1, 1, 2};
  memcpy(K->val, kv, sizeof kv);
  memcpy(M->val, mv, sizeof mv);
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(2, &bc));
  CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 1, 0.5));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  /* free DOF: 2 u0'' + 2 u0 = 0.5 (from -K01 u1): equilibrium u0 = 0.25, omega = 1 */
  double u[2] = {1.25, 0.0}, v[2] = {0, 0};
  cupid_dynamics_system sys = {.K = K, .M = M, .bc = bc};
  cupid_dynamics_options o = cupid_dynamics_defaults();
  o.dt = 0.01;
  o.steps = 314; /* ~ half a period: u0 = 0.25 + cos(omega_h t) */
  CUPID_ASSERT_OK(cupid_dynamics_run(&sys, &o, u, v, NULL, NULL, NULL));
  double wh = 2.0 * atan(o.dt / 2.0) / o.dt;
  ASSERT_NEAR(u[0], 0.25 + cos(wh * o.dt * 314), 1e-9);
  ASSERT_NEAR(u[1], 0.5, 0.0);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  cupid_csr_destroy(&M);
}

/* Central differences conserve E = v^2/2 + omega^2 u^2 (1 - (omega dt)^2/4)/2 exactly, so the
 * physical energy error stays bounded by (omega dt)^2/4 / (1 - (omega dt)^2/4) relative (the
 * tolerance takes 1.01 of it) over 100 periods and does not grow. */
static void test_central_sdof_bounded(void **state) {
  double k = 9.0, m = 1.0, omega = 3.0, T = 2 * M_PI / omega;
  cupid_csr K = sdof_matrix(k);
  double mass = m, u = 1.0, v = 0.0;
  cupid_dynamics_system sys = {.K = K, .m_lumped = &mass};
  cupid_dynamics_options o = cupid_dynamics_defaults();
  o.integrator = CUPID_INTEGRATOR_CENTRAL;
  o.dt = T / 10;
  o.steps = 1000;
  record r = {0};
  cupid_dynamics_info info;
  CUPID_ASSERT_OK(cupid_dynamics_run(&sys, &o, &u, &v, observe, &r, &info));
  double wd2 = pow(omega * o.dt, 2) / 4.0, bound = wd2 / (1.0 - wd2);
  assert_true(r.max_rel_balance < 1.01 * bound);
  assert_true(r.max_rel_balance > 0.5 * bound); /* the error is really there (test can fail) */
  ASSERT_NEAR(info.omega_max, omega, 1e-12);
  ASSERT_NEAR(info.dt_critical, 2.0 / omega, 1e-12);
  cupid_csr_destroy(&K);
}

/* The stable step is enforced: just above 2/omega is refused, just below accepted. */
static void test_central_refuses_unstable(void **state) {
  cupid_csr K = sdof_matrix(4.0);
  double mass = 1.0, u = 1.0, v = 0.0;
  cupid_dynamics_system sys = {.K = K, .m_lumped = &mass};
  cupid_dynamics_options o = cupid_dynamics_defaults();
  o.integrator = CUPID_INTEGRATOR_CENTRAL;
  o.steps = 10;
  o.dt = 1.01;
  assert_int_equal(cupid_dynamics_run(&sys, &o, &u, &v, NULL, NULL, NULL), CUPID_ERR_ARGUMENT);
  assert_non_null(strstr(cupid_error_message(), "unstable"));
  o.dt = 0.99;
  CUPID_ASSERT_OK(cupid_dynamics_run(&sys, &o, &u, &v, NULL, NULL, NULL));
  cupid_csr_destroy(&K);
}

/* Rayleigh damping: the logarithmic decrement over 10 periods gives zeta = a/(2w) + b w/2.
 * dt = T/400 puts the sampling error of the peaks at ~(2 pi/400)^2/2 ~ 1e-4; tolerance 1 %
 * of zeta. The energy balance (with the dissipated energy) stays exact to round-off. */
static void test_rayleigh_decrement(void **state) {
  double omega = 2.0, a = 0.05, b = 0.02;
  cupid_csr K = sdof_matrix(omega * omega);
  double mass = 1.0, u = 1.0, v = 0.0;
  cupid_dynamics_system sys = {.K = K, .m_lumped = &mass};
  cupid_dynamics_options o = cupid_dynamics_defaults();
  o.rayleigh_mass = a;
  o.rayleigh_stiffness = b;
  o.dt = 2 * M_PI / omega / 400;
  o.steps = 400 * 12;
  record r = {0};
  CUPID_ASSERT_OK(cupid_dynamics_run(&sys, &o, &u, &v, observe, &r, NULL));
  assert_true(r.n_peaks >= 11);
  double delta = log(r.peaks[0] / r.peaks[10]) / 10.0;
  double zeta = delta / sqrt(4 * M_PI * M_PI + delta * delta);
  double expect = cupid_dynamics_rayleigh_zeta(a, b, omega);
  ASSERT_NEAR(zeta, expect, 0.01 * expect);
  assert_true(r.max_rel_balance < 1e-11);
  cupid_csr_destroy(&K);
}

/* Dense eigen solver: a 3-DOF spring chain with known eigenvalues 2 - 2 cos(k pi / 4). */
static void test_eigen_dense_chain(void **state) {
  cupid_int rowptr[4] = {0, 2, 5, 7}, col[7] = {0, 1, 0, 1, 2, 1, 2};
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_csr_create(3, 3, 1, rowptr, col, &K));
  double kv[7] = {2, -1, -1, 2, -1, -1, 2};
  memcpy(K->val, kv, sizeof kv);
  double m[3] = {1, 1, 1}, omega[3], modes[9];
  CUPID_ASSERT_OK(cupid_dynamics_eigen_dense(K, NULL, m, NULL, 3, omega, modes));
  for (int k = 0; k < 3; k++) ASSERT_NEAR(omega[k], sqrt(2 - 2 * cos((k + 1) * M_PI / 4)), 1e-12);
  /* M-normalised mode 1: (1, sqrt2, 1)/2 up to sign */
  ASSERT_NEAR(fabs(modes[1]), sqrt(2) / 2, 1e-12);
  double est, bound;
  CUPID_ASSERT_OK(cupid_dynamics_lambda_max(K, m, NULL, 200, &est, &bound));
  ASSERT_NEAR(est, 2 + sqrt(2), 1e-9);
  assert_true(bound >= 2 + sqrt(2));
  cupid_csr_destroy(&K);
}

/* The reusable factorisation solves like cupid_direct_solve on the free DOFs. */
static void test_factor_reuse(void **state) {
  cupid_int rowptr[4] = {0, 2, 5, 7}, col[7] = {0, 1, 0, 1, 2, 1, 2};
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_csr_create(3, 3, 1, rowptr, col, &K));
  double kv[7] = {2, -1, -1, 2, -1, -1, 2};
  memcpy(K->val, kv, sizeof kv);
  cupid_direct_factor F = NULL;
  cupid_solve_info info;
  CUPID_ASSERT_OK(cupid_direct_factor_create(K, NULL, &F, &info));
  for (int rep = 0; rep < 3; rep++) {
    double b[3] = {1.0 + rep, 0, 0}, x[3];
    CUPID_ASSERT_OK(cupid_direct_factor_solve(F, b, x));
    /* inverse of the chain matrix, first column: (3, 2, 1)/4 */
    ASSERT_NEAR(x[0], 0.75 * (1 + rep), 1e-14);
    ASSERT_NEAR(x[2], 0.25 * (1 + rep), 1e-14);
  }
  cupid_direct_factor_destroy(&F);
  assert_null(F);
  K->val[0] = K->val[6] = 1.0; /* the graph Laplacian [1 -1 0; -1 2 -1; 0 -1 1]: singular */
  assert_int_equal(cupid_direct_factor_create(K, NULL, &F, NULL), CUPID_ERR_NUMERIC);
  cupid_csr_destroy(&K);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_newmark_sdof_exact),    cmocka_unit_test(test_newmark_fixed_dof),
      cmocka_unit_test(test_central_sdof_bounded),  cmocka_unit_test(test_central_refuses_unstable),
      cmocka_unit_test(test_rayleigh_decrement),    cmocka_unit_test(test_eigen_dense_chain),
      cmocka_unit_test(test_factor_reuse)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
