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

static void run_case(cupid_integrator integ, int moving, double damping) {
  cupid_csr K = chain();
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(N, &bc));
  if (moving) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 0, 0.0));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  double mass[N], u0[N], v0[N];
  for (int i = 0; i < N; i++) mass[i] = 1.0 + 0.05 * i, u0[i] = 1e-3 * sin(i), v0[i] = 1e-3 * cos(2.0 * i);
  cupid_dynamics_hooks plain = {.conditions = moving ? conditions : NULL};
  cupid_dynamics_options o = cupid_dynamics_defaults();
  o.integrator = integ;
  o.dt = 0.02;
  o.steps = 700;
  o.every = 50;
  o.rayleigh_mass = damping;
  o.rayleigh_stiffness = damping * 0.01;
  o.velocity_at_outputs = 1;
  o.hooks = moving ? &plain : NULL;
  cupid_dynamics_system sys = {.K = K, .m_lumped = mass, .bc = bc};
  /* the run that never stops */
  double u[N], v[N];
  memcpy(u, u0, sizeof u), memcpy(v, v0, sizeof v);
  cupid_dynamics_info whole;
  CUPID_ASSERT_OK(cupid_dynamics_run(&sys, &o, u, v, NULL, NULL, &whole));
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

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_central), cmocka_unit_test(test_newmark)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
