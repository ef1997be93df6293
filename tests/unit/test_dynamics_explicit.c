/* Matrix-free central differences (cupid_dynamics_run_explicit with the PD operator's
 * product) against central differences on the assembled PD stiffness (cupid_dynamics_run):
 * a small LPS and a bond-based block, one face held, a body force, an initial velocity field
 * and Rayleigh damping (both terms). Same steps, so the same states to round-off. Also the
 * merged half-kicks of velocity_at_outputs, and a failing product. */
#include <math.h>
#include <string.h>

#include "cupid/dynamics.h"
#include "testutil.h"

typedef struct {
  cupid_dynamics_energy last;
  cupid_int calls;
} record;

static cupid_status observe(void *ctx, cupid_int step, double t, int output, const double *u,
                            const double *v, const double *a, const cupid_dynamics_energy *e) {
  (void)step, (void)t, (void)u, (void)v, (void)a;
  record *r = ctx;
  r->calls++;
  if (output) r->last = *e;
  return CUPID_SUCCESS;
}

/* Checks what a velocity_at_outputs run promises: v and a at step 0 and the output steps,
 * NULL at the others; u always. */
typedef struct {
  record r;
  int every, steps, bad;
} lazy_record;

static cupid_status observe_lazy(void *ctx, cupid_int step, double t, int output,
                                 const double *u, const double *v, const double *a,
                                 const cupid_dynamics_energy *e) {
  lazy_record *l = ctx;
  const int out = step % l->every == 0 || step == l->steps;
  if (output != out || !u || (v == NULL) == out || (a == NULL) == out) l->bad++;
  return observe(&l->r, step, t, output, u, v, a, e);
}

static cupid_status pd_apply(void *ctx, const double *x, double *y) {
  return cupid_pd_operator_apply(ctx, x, y);
}

/* K = I that fails from call number limit on: the run must stop with that status. */
static cupid_status failing_apply(void *ctx, const double *x, double *y) {
  int *calls = ctx;
  memcpy(y, x, 3 * sizeof *y);
  return ++calls[0] >= calls[1] ? CUPID_ERR_NUMERIC : CUPID_SUCCESS;
}

/* A partition of one process (exchange, sum and max do nothing). */
static cupid_status no_exchange(void *ctx, double *x) {
  (void)ctx, (void)x;
  return CUPID_SUCCESS;
}

static void no_sum(void *ctx, double *values, int count) { (void)ctx, (void)values, (void)count; }

static double max_abs(cupid_int n, const double *x) {
  double m = 0.0;
  for (cupid_int i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
  return m;
}

/* The tests' block: 6 x 5 x 7 nodes, h = 0.5, delta = 1, E = 2000 (nu 0.3 LPS, 0.25
 * bond-based: its only one). */
static cupid_pd_operator block_operator(cupid_pd_model_kind model, cupid_pd_grid *grid) {
  cupid_box box = {{0, 0, 0}, {3.0, 2.5, 3.5}, {1, 1, 1}};
  int mat = 0;
  cupid_pd_grid_options go = {.spacing = 0.5, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &box, &mat, grid));
  cupid_pd_material pm = {.E = 2000.0, .nu = model == CUPID_PD_BOND ? 0.25 : 0.3};
  cupid_pd_operator_options oo = {.horizon = 1.0, .model = model,
                                  .influence = CUPID_INFLUENCE_INVERSE,
                                  .partial_volume = CUPID_PARTIAL_PDLAMMPS, .materials = &pm,
                                  .n_materials = 1};
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(*grid, &oo, &op));
  return op;
}

static void compare(cupid_pd_model_kind model) {
  cupid_pd_grid grid = NULL;
  cupid_pd_operator op = block_operator(model, &grid);
  const cupid_int nn = cupid_pd_grid_num_nodes(grid), n = 3 * nn;
  const double *x = cupid_pd_grid_coords(grid);
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(op, &K));
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
  double *m = NULL, *f = NULL, *u0 = NULL, *v0 = NULL, *u1 = NULL, *v1 = NULL, *ui = NULL,
         *vi = NULL, *rbound = NULL;
  double **arrays[] = {&m, &f, &u0, &v0, &u1, &v1, &ui, &vi, &rbound};
  for (int k = 0; k < 9; k++) CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof(double), "t", arrays[k]));
  for (cupid_int i = 0; i < nn; i++) {
    const double *p = x + 3 * i;
    for (int c = 0; c < 3; c++) {
      m[3 * i + c] = 7.0 * cupid_pd_grid_cell_volume(grid);
      f[3 * i + c] = c == 2 ? -0.3 : 0.05 * c;
      u0[3 * i + c] = 1e-3 * sin(1.3 * p[0] + c) * p[2];
      v0[3 * i + c] = 0.02 * cos(0.7 * p[1] - c) * p[2];
    }
    if (p[2] < 0.5)
      for (int c = 0; c < 3; c++) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 3 * i + c, 0.0));
  }
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  memcpy(u1, u0, (size_t)n * sizeof *u1);
  memcpy(v1, v0, (size_t)n * sizeof *v1);
  memcpy(ui, u0, (size_t)n * sizeof *ui);
  memcpy(vi, v0, (size_t)n * sizeof *vi);

  cupid_dynamics_options o = cupid_dynamics_defaults();
  o.integrator = CUPID_INTEGRATOR_CENTRAL;
  o.steps = 60;
  o.every = 20;
  o.rayleigh_mass = 0.05;
  o.rayleigh_stiffness = 1e-4;
  /* dt: half the critical step of the assembled run (a first run with a huge dt reports it). */
  o.dt = 1e3;
  cupid_dynamics_system sys = {.K = K, .m_lumped = m, .bc = bc, .f = f};
  cupid_dynamics_info ia, ib;
  assert_int_equal(cupid_dynamics_run(&sys, &o, u0, v0, NULL, NULL, &ia), CUPID_ERR_ARGUMENT);
  o.dt = 0.5 * ia.dt_critical;
  record ra = {0}, rb = {0};
  CUPID_ASSERT_OK(cupid_dynamics_run(&sys, &o, u0, v0, observe, &ra, &ia));
  cupid_dynamics_explicit_system es = {.n = n, .apply = pd_apply, .ctx = op, .m_lumped = m,
                                       .bc = bc, .f = f};
  CUPID_ASSERT_OK(cupid_dynamics_run_explicit(&es, &o, u1, v1, observe, &rb, &ib));
  /* Same recurrences, K products differing by round-off (assembled CSR vs stencil sums):
   * states and energies agree to 1e-11 relative after 60 steps (a stable scheme does not
   * amplify round-off beyond the O(steps) growth; observed ~1e-14). */
  const double umax = max_abs(n, u0), vmax = max_abs(n, v0);
  assert_true(umax > 1e-3 && vmax > 1e-3);
  for (cupid_int d = 0; d < n; d++) {
    ASSERT_NEAR(u1[d], u0[d], 1e-11 * umax);
    ASSERT_NEAR(v1[d], v0[d], 1e-11 * vmax);
  }
  assert_int_equal(ra.calls, rb.calls);
  const double escale = ra.last.kinetic + ra.last.strain;
  ASSERT_NEAR(rb.last.kinetic, ra.last.kinetic, 1e-11 * escale);
  ASSERT_NEAR(rb.last.strain, ra.last.strain, 1e-11 * escale);
  ASSERT_NEAR(rb.last.damping, ra.last.damping, 1e-11 * escale);
  ASSERT_NEAR(rb.last.external, ra.last.external, 1e-11 * escale);
  /* The power iteration sees the same products: the same critical step (1e-9 relative: 200
   * iterations of a converging Rayleigh quotient); no Gershgorin bound matrix-free. */
  ASSERT_NEAR(ib.omega_max, ia.omega_max, 1e-9 * ia.omega_max);
  assert_true(ia.dt_bound > 0 && ib.dt_bound == 0.0);
  /* Unstable steps are refused matrix-free too; Newmark is refused. */
  o.dt = 1.01 * ib.dt_critical;
  assert_int_equal(cupid_dynamics_run_explicit(&es, &o, u1, v1, NULL, NULL, NULL), CUPID_ERR_ARGUMENT);
  assert_non_null(strstr(cupid_error_message(), "unstable"));
  o.integrator = CUPID_INTEGRATOR_NEWMARK;
  o.dt = 0.5 * ib.dt_critical;
  assert_int_equal(cupid_dynamics_run_explicit(&es, &o, u1, v1, NULL, NULL, NULL), CUPID_ERR_ARGUMENT);
  o.integrator = CUPID_INTEGRATOR_CENTRAL;
  /* With the operator's row bound (cupid_pd_operator_row_bound): its guaranteed step lies
   * below the estimate; a dt within it runs without Lanczos and steps exactly as the run
   * without the bound; a dt above it, below the estimate, runs Lanczos; one above both is
   * refused. */
  CUPID_ASSERT_OK(cupid_pd_operator_row_bound(op, rbound));
  cupid_dynamics_explicit_system eb = es;
  eb.row_bound = rbound;
  cupid_dynamics_info ic, id;
  o.dt = 1.01 * ib.dt_critical;
  assert_int_equal(cupid_dynamics_run_explicit(&eb, &o, u1, v1, NULL, NULL, &ic), CUPID_ERR_ARGUMENT);
  const double dtb = ic.dt_bound;
  assert_true(dtb > 0.1 * ib.dt_critical && dtb <= ib.dt_critical);
  o.dt = 0.99 * dtb;
  memcpy(u0, ui, (size_t)n * sizeof *u0), memcpy(v0, vi, (size_t)n * sizeof *v0);
  memcpy(u1, ui, (size_t)n * sizeof *u1), memcpy(v1, vi, (size_t)n * sizeof *v1);
  CUPID_ASSERT_OK(cupid_dynamics_run_explicit(&es, &o, u0, v0, NULL, NULL, &ic));
  CUPID_ASSERT_OK(cupid_dynamics_run_explicit(&eb, &o, u1, v1, NULL, NULL, &id));
  assert_true(ic.lanczos_steps > 0 && id.lanczos_steps == 0);
  assert_true(isnan(id.omega_max) && isnan(id.dt_critical) && id.dt_bound == dtb);
  assert_memory_equal(u0, u1, (size_t)n * sizeof *u0);
  assert_memory_equal(v0, v1, (size_t)n * sizeof *v0);
  o.dt = 0.5 * (dtb + ib.dt_critical);
  CUPID_ASSERT_OK(cupid_dynamics_run_explicit(&eb, &o, u1, v1, NULL, NULL, &id));
  assert_true(id.lanczos_steps > 0 && id.dt_bound == dtb);
  ASSERT_NEAR(id.omega_max, ib.omega_max, 1e-9 * ib.omega_max);
  /* A partition (here of one process) needs max for the bound; with it, the same run. */
  cupid_dynamics_partition part = {.owned_first = 0, .owned_last = n, .exchange = no_exchange,
                                   .sum = no_sum};
  eb.part = &part;
  assert_int_equal(cupid_dynamics_run_explicit(&eb, &o, u1, v1, NULL, NULL, NULL), CUPID_ERR_ARGUMENT);
  assert_non_null(strstr(cupid_error_message(), "row_bound"));
  part.max = no_sum;
  o.dt = 0.99 * dtb;
  memcpy(u1, ui, (size_t)n * sizeof *u1), memcpy(v1, vi, (size_t)n * sizeof *v1);
  CUPID_ASSERT_OK(cupid_dynamics_run_explicit(&eb, &o, u1, v1, NULL, NULL, &id));
  assert_true(id.lanczos_steps == 0 && id.dt_bound == dtb);
  assert_memory_equal(u0, u1, (size_t)n * sizeof *u0);
  for (int k = 0; k < 9; k++) cupid_free(arrays[k]);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&grid);
}

static void test_lps(void **state) {
  (void)state;
  compare(CUPID_PD_LPS);
}

static void test_bond(void **state) {
  (void)state;
  compare(CUPID_PD_BOND);
}

/* velocity_at_outputs (the half-kicks between outputs merged into one pass): on a free LPS
 * block (no load, fixed DOF or damping) the same states and energies as the plain run to
 * round-off, over output intervals of 20 (a uniform mass) and of 7 (a varying one; the last
 * step then an output of its own),
 * with v and a NULL only at the steps between outputs. With a fixed DOF nothing merges: the
 * same numbers to the bit as without the option. */
static void test_merged_kicks(void **state) {
  (void)state;
  cupid_pd_grid grid = NULL;
  cupid_pd_operator op = block_operator(CUPID_PD_LPS, &grid);
  const cupid_int nn = cupid_pd_grid_num_nodes(grid), n = 3 * nn;
  const double *x = cupid_pd_grid_coords(grid);
  double *m = NULL, *u0 = NULL, *v0 = NULL, *u1 = NULL, *v1 = NULL;
  double **arrays[] = {&m, &u0, &v0, &u1, &v1};
  for (int k = 0; k < 5; k++) CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof(double), "t", arrays[k]));
  for (int fixed = 0; fixed < 2; fixed++)
    for (int every = 20; every > 0; every -= 13) {
      cupid_dirichlet bc = NULL;
      CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
      if (fixed) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 0, 0.0));
      CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
      for (cupid_int i = 0; i < nn; i++)
        for (int c = 0; c < 3; c++) {
          const double *p = x + 3 * i;
          /* every 20: a uniform mass (its own merged loop), every 7: not */
          m[3 * i + c] = 7.0 * cupid_pd_grid_cell_volume(grid) * (every == 20 ? 1.0 : 1.0 + 0.2 * (i % 3));
          u0[3 * i + c] = u1[3 * i + c] = 1e-3 * sin(1.3 * p[0] + c) * p[2];
          v0[3 * i + c] = v1[3 * i + c] = 0.02 * cos(0.7 * p[1] - c) * p[2];
        }
      cupid_dynamics_explicit_system es = {.n = n, .apply = pd_apply, .ctx = op, .m_lumped = m,
                                           .bc = bc};
      cupid_dynamics_options o = cupid_dynamics_defaults();
      o.integrator = CUPID_INTEGRATOR_CENTRAL;
      o.steps = 60;
      o.every = every;
      o.dt = 1e3;
      cupid_dynamics_info ia, ib;
      assert_int_equal(cupid_dynamics_run_explicit(&es, &o, u0, v0, NULL, NULL, &ia), CUPID_ERR_ARGUMENT);
      o.dt = 0.5 * ia.dt_critical;
      record ra = {0};
      lazy_record rb = {.every = every, .steps = 60};
      CUPID_ASSERT_OK(cupid_dynamics_run_explicit(&es, &o, u0, v0, observe, &ra, &ia));
      o.velocity_at_outputs = 1;
      CUPID_ASSERT_OK(cupid_dynamics_run_explicit(&es, &o, u1, v1, observe_lazy, &rb, &ib));
      assert_int_equal(rb.bad, 0);
      assert_int_equal(ra.calls, rb.r.calls);
      if (fixed) { /* nothing merged */
        assert_memory_equal(u0, u1, (size_t)n * sizeof *u0);
        assert_memory_equal(v0, v1, (size_t)n * sizeof *v0);
      }
      /* The merged kick adds dt a once where the plain run adds dt/2 a twice: round-off,
       * 1e-13 of the largest values after 60 steps (observed ~1e-16). */
      const double umax = max_abs(n, u0), vmax = max_abs(n, v0);
      assert_true(umax > 1e-3 && vmax > 1e-3);
      for (cupid_int d = 0; d < n; d++) {
        ASSERT_NEAR(u1[d], u0[d], 1e-13 * umax);
        ASSERT_NEAR(v1[d], v0[d], 1e-13 * vmax);
      }
      const double escale = ra.last.kinetic + ra.last.strain;
      ASSERT_NEAR(rb.r.last.kinetic, ra.last.kinetic, 1e-13 * escale);
      ASSERT_NEAR(rb.r.last.strain, ra.last.strain, 1e-13 * escale);
      ASSERT_NEAR(rb.r.last.balance, ra.last.balance, 1e-13 * escale);
      cupid_dirichlet_destroy(&bc);
    }
  for (int k = 0; k < 5; k++) cupid_free(arrays[k]);
  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&grid);
}

/* A failing product stops the run with its status, and at once: in the stable-step check
 * (call 2: E0, then the first Lanczos product), in the time loop (call L + 4: E0, the L
 * Lanczos products of a run that succeeds, the initial acceleration, the energies of step 0,
 * the forces of step 1; or of step 3, two products on), or never (the run succeeds); the
 * same with the half-kicks between outputs merged. */
static cupid_status run_failing(int fail_at, int merge, int *calls_made,
                                cupid_dynamics_info *info) {
  double m[3] = {1, 1, 1}, u[3] = {0}, v[3] = {0};
  int calls[2] = {0, fail_at};
  cupid_dynamics_explicit_system es = {.n = 3, .apply = failing_apply, .ctx = calls, .m_lumped = m};
  cupid_dynamics_options o = cupid_dynamics_defaults();
  o.integrator = CUPID_INTEGRATOR_CENTRAL;
  o.dt = 0.1;
  o.steps = 5;
  o.every = 5;
  o.velocity_at_outputs = merge; /* a failure inside the merged steps stops the run too */
  cupid_status st = cupid_dynamics_run_explicit(&es, &o, u, v, NULL, NULL, info);
  *calls_made = calls[0];
  return st;
}

static void test_apply_failure(void **state) {
  (void)state;
  cupid_dynamics_info info;
  int calls = 0;
  for (int merge = 0; merge < 2; merge++) {
    CUPID_ASSERT_OK(run_failing(1000, merge, &calls, &info)); /* K = I: Lanczos ends after 1 */
    assert_int_equal(info.lanczos_steps, 1);
    assert_int_equal(run_failing(2, merge, &calls, NULL), CUPID_ERR_NUMERIC);
    assert_int_equal(calls, 2);
    for (int at = 0; at < 2; at++) { /* at the forces of step 1, then of step 3 */
      const int in_loop = info.lanczos_steps + 4 + 2 * at;
      assert_int_equal(run_failing(in_loop, merge, &calls, NULL), CUPID_ERR_NUMERIC);
      assert_int_equal(calls, in_loop);
    }
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_lps), cmocka_unit_test(test_bond),
                                     cmocka_unit_test(test_merged_kicks),
                                     cmocka_unit_test(test_apply_failure)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
