/* The operator-consistency matrix (issue 32): every matrix-free operator of cupid, applied to
 * random vectors, equals its assembled twin K x, on every instruction-set instance of the PD
 * kernels that this CPU runs (pd_stencil_force_isa: baseline, AVX2, AVX-512; the test prints
 * which it ran and which the CPU lacks). A kernel optimisation lands only with this passing on
 * the instruction sets of the machine (docs/development.md).
 *
 * The bound: |y_free - K x|_2 <= 1e-12 |K x|_2 for x uniform in [-1, 1). The two sum the same
 * terms in other orders (the kernels by stencil pairs and lane blocks, the assembly by rows of
 * 3x3 blocks); an LPS row has up to ~2,000 terms of mixed sign (two horizons), each rounding
 * ~1e-16 relative: measured 1e-15 to 3e-14 here. A wrong term is O(1) of its row: the uniform-b
 * stretches across an Arlequin ramp (issue 32) gave 1e-3 to 1e-1.
 *
 * 1. The PD operator alone (the kernels): LPS and bond-based; horizon/spacing m in {1.5, 2,
 *    3.015, 4}; influence gaussian, inverse, constant; partial volumes pdlammps and exact;
 *    a thin body (near-surface families only, or nearly) and a deep one (LPS: runs of uniform
 *    b, asserted to be there). Each in four states, in this order: intact; node-weighted
 *    energy (cupid_pd_operator_scale_energy with a ramp of weights along x, the Arlequin
 *    weighting: the bug of issue 32); pre-cracked; with bonds broken by the stretch criterion.
 *    Both the whole product and a range of rows (apply_range, what a slab computes). Where
 *    the whole K would not fit a test (deep bodies at m >= 3) the twin is the assembly's own
 *    rows of a bottom and a middle z layer (pd_assemble_rows: the same code per row).
 * 2. Coupled models through the problem's own stages (the method tables, src/problem): for
 *    each of four horizons (every influence and partial volume among them; one bond-based):
 *    - Arlequin: the explicit-dynamics operator and the growth operator (matrix-free) against
 *      the assembled K; with a pre-crack, and after every round of breaks the growth operator
 *      (its PD bonds copied as growth.c copies them) against K assembled anew;
 *    - fictitious nodes: the matrix-free Eq. 38 against its assembly, and with `balance:
 *      momentum` the balanced matrix-free operator (C = K^T R by its transpose products)
 *      against the assembled K with the correction built from the assembled K;
 *    - Lagrange: no matrix-free path in cupid yet; its assembled T^T diag(K_PD, K_FE) T against
 *      the composition of the tie (recover, lagrange_load), the matrix-free PD operator and the
 *      beam's K;
 *    - a PD-only model's explicit operator (method none) against its assembled K;
 *    - the growth re-solves of the direct path for bond-based models: the factor's downdate
 *      terms (growth_downdate.c) with K_old - C C^T = K_new after each round of breaks.
 * Fictitious nodes and Lagrange refuse cracks in this version (issue 34): their cracked
 * operators come with it.
 *
 * CUPID_TEST_SMALL (valgrind): m in {1.5, 3.015}, one influence and partial volume, the
 * smaller coupled cases. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pd/pd_internal.h"
#include "problem/method.h"
#include "testutil.h"

#define TOL 1e-12

static int isa_levels[3], n_isa;
static double worst; /* the largest relative difference seen, for the report */

static void find_instances(void) {
  static const int levels[3] = {1, 3, 4}, lanes[3] = {2, 4, 8};
  static const char *names[3] = {"baseline (SSE2)", "AVX2", "AVX-512"};
  n_isa = 0;
  for (int l = 0; l < 3; l++) {
    const int got = pd_stencil_force_isa(levels[l]);
    if (got == lanes[l]) {
      isa_levels[n_isa++] = levels[l];
      print_message("kernel instance %s (CUPID_PD_ISA=%d, %d lanes): checked\n", names[l],
                    levels[l], got);
    } else {
      print_message("kernel instance %s (CUPID_PD_ISA=%d): not run, this CPU lacks it\n",
                    names[l], levels[l]);
    }
  }
  pd_stencil_force_isa(0);
  assert_true(n_isa >= 1 && isa_levels[0] == 1);
}

static int small(void) { return getenv("CUPID_TEST_SMALL") != NULL; }

static double *vec(cupid_int n) {
  double *v = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)n + 1, sizeof *v, "test vector", &v));
  return v;
}

static void random_fill(double *x, cupid_int n, uint64_t seed) {
  for (cupid_int i = 0; i < n; i++) x[i] = cupid_test_random(&seed);
}

/* |a - b|_2 <= TOL |b|_2, else fail naming the case. */
static void check(const char *what, const double *a, const double *b, cupid_int n) {
  double d = 0.0, s = 0.0;
  for (cupid_int i = 0; i < n; i++) {
    d += (a[i] - b[i]) * (a[i] - b[i]);
    s += b[i] * b[i];
  }
  assert_true(isfinite(d) && s > 0.0);
  const double rel = sqrt(d / s);
  if (rel > worst) worst = rel;
  if (!(rel <= TOL)) fail_msg("%s: |y - K x| / |K x| = %.3e > %.0e", what, rel, TOL);
}

/* ------------------------------------------------------------- 1. the PD operator alone */

typedef struct {
  cupid_pd_model_kind model;
  double m;
  cupid_influence infl;
  cupid_partial_volume pv;
  int deep;
} pd_case;

static const char *infl_name(cupid_influence i) {
  return i == CUPID_INFLUENCE_GAUSSIAN ? "gaussian" : i == CUPID_INFLUENCE_INVERSE ? "inverse" : "constant";
}

static void case_name(const pd_case *c, const char *state, int isa, char *buf, size_t len) {
  snprintf(buf, len, "%s m=%g %s %s %s body, %s, CUPID_PD_ISA=%d",
           c->model == CUPID_PD_LPS ? "LPS" : "bond-based", c->m, infl_name(c->infl),
           c->pv == CUPID_PARTIAL_EXACT ? "exact" : "pdlammps", c->deep ? "deep" : "thin", state, isa);
}

/* Rows of the twin: all of them on small grids, else a bottom and a middle z layer. */
typedef struct {
  int n;
  cupid_int first[2], last[2];
} row_windows;

static row_windows windows(cupid_int nodes, cupid_int layer, cupid_int layers) {
  if (nodes <= 4000) return (row_windows){1, {0, 0}, {nodes, 0}};
  const cupid_int mid = layers / 2;
  return (row_windows){2, {0, mid * layer}, {layer, (mid + 1) * layer}};
}

/* The twin's rows against the whole product and against apply_range over each window, on
 * every instance. */
static void compare_pd(const pd_case *c, cupid_pd_operator op, const row_windows *W,
                       const char *state) {
  const cupid_int n = op->nnodes;
  double *x = vec(3 * n), *y = vec(3 * n), *r = vec(3 * n);
  random_fill(x, 3 * n, 1234 + (uint64_t)n);
  cupid_csr K[2] = {NULL, NULL};
  double *ky[2] = {NULL, NULL};
  for (int w = 0; w < W->n; w++) {
    CUPID_ASSERT_OK(pd_assemble_rows(op, W->first[w], W->last[w], &K[w]));
    ky[w] = vec(3 * (W->last[w] - W->first[w]));
    cupid_csr_matvec(K[w], x, ky[w]);
  }
  for (int l = 0; l < n_isa; l++) {
    pd_stencil_force_isa(isa_levels[l]);
    char name[256];
    CUPID_ASSERT_OK(cupid_pd_operator_apply(op, x, y));
    for (int w = 0; w < W->n; w++) {
      const cupid_int a = W->first[w], b = W->last[w];
      case_name(c, state, isa_levels[l], name, sizeof name);
      check(name, y + 3 * a, ky[w], 3 * (b - a));
      CUPID_ASSERT_OK(cupid_pd_operator_apply_range(op, a, b, x, r));
      strncat(name, ", apply_range", sizeof name - strlen(name) - 1);
      check(name, r, ky[w], 3 * (b - a));
    }
  }
  pd_stencil_force_isa(0);
  for (int w = 0; w < W->n; w++) {
    cupid_csr_destroy(&K[w]);
    cupid_free(&ky[w]);
  }
  cupid_free(&x);
  cupid_free(&y);
  cupid_free(&r);
}

static cupid_int uniform_nodes(const struct cupid_pd_operator_private *op) {
  cupid_int t = 0;
  for (cupid_int r = 0; r < op->nruns; r++) t += op->runs[r].ub1 - op->runs[r].ub0;
  return t;
}

/* An nx x ny x nz box of spacing 1 and its PD operator. */
static void box_operator(int nx, int ny, int nz, const pd_case *c, cupid_pd_grid *grid,
                         cupid_pd_operator *op) {
  const cupid_box box = {.lo = {0, 0, 0}, .hi = {nx, ny, nz}, .has = {1, 1, 1}};
  const int mat = 0;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &box, &mat, grid));
  const cupid_pd_material pm = {.E = 1000.0, .nu = 0.27};
  cupid_pd_operator_options oo = {.horizon = c->m, .model = c->model, .influence = c->infl,
                                  .partial_volume = c->pv, .materials = &pm, .n_materials = 1};
  CUPID_ASSERT_OK(cupid_pd_operator_create(*grid, &oo, op));
}

static void run_pd_case(const pd_case *c) {
  /* reach r: the largest lattice offset along an axis with a partial volume > 0 */
  const int r = (int)ceil(c->m + 0.5 - 1e-9) - 1;
  /* deep: 2 r inside every face for a uniform family, and along x room for a whole lane block
   * of 8 past them; thin: two layers along y, families near the surface only */
  const int nx = c->deep ? 4 * r + 16 : 2 * r + 8, ny = c->deep ? 4 * r + 2 : 2,
            nz = c->deep ? 4 * r + 1 : 2 * r + 2;
  cupid_pd_grid grid = NULL;
  cupid_pd_operator op = NULL;
  box_operator(nx, ny, nz, c, &grid, &op);
  const cupid_int n = op->nnodes;
  const row_windows W = windows(n, (cupid_int)nx * ny, nz);
  if (c->deep && c->model == CUPID_PD_LPS) assert_true(uniform_nodes(op) >= 8);
  compare_pd(c, op, &W, "intact");

  /* Node-weighted energy (Arlequin's Eq. 12 node by node): 1 on the lower half in x, a ramp
   * down to 0.25 across the upper half, so that uniform stretches end inside a run. */
  double *w = vec(n);
  const double *X = cupid_pd_grid_coords(grid);
  for (cupid_int i = 0; i < n; i++) {
    const double s = (X[3 * i] - 0.5 * nx) / (0.5 * nx);
    w[i] = s <= 0.0 ? 1.0 : 1.0 - 0.75 * s;
  }
  CUPID_ASSERT_OK(cupid_pd_operator_scale_energy(op, w));
  cupid_free(&w);
  compare_pd(c, op, &W, "node-weighted");

  /* A pre-crack on the plane x = nx/2 over the lower half in z. */
  cupid_pd_precrack pc = {.normal = 0, .at = 0.5 * nx, .lo = {0, -1, -1}, .hi = {0, ny + 1, 0.5 * nz}};
  cupid_int removed = 0;
  CUPID_ASSERT_OK(cupid_pd_operator_precrack(op, &pc, &removed));
  assert_true(removed > 0);
  compare_pd(c, op, &W, "pre-cracked");

  /* Bonds broken at a random field: the most stretched one, three times (a growth step's
   * only_most), then every one over a limit that a few per cent pass. */
  double *u = vec(3 * n);
  random_fill(u, 3 * n, 77);
  cupid_pd_fracture_options fo = {.criterion = CUPID_PD_BREAK_STRETCH, .critical_stretch = 1e-12};
  cupid_int broken = 0, total = 0;
  double diss = 0.0;
  for (int k = 0; k < 3; k++) {
    CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(op, u, &fo, 1, &broken, &diss));
    total += broken;
  }
  fo.critical_stretch = 1.0; /* u in [-1, 1) on h = 1: some per cent of the bonds pass it */
  CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(op, u, &fo, 0, &broken, &diss));
  total += broken;
  if (total <= 3) fail_msg("only %lld bonds broke", (long long)total);
  cupid_free(&u);
  compare_pd(c, op, &W, "bonds broken");

  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&grid);
}

static void test_pd_matrix(void **state) {
  (void)state;
  static const double ms[4] = {1.5, 2.0, 3.015, 4.0};
  static const cupid_influence infl[3] = {CUPID_INFLUENCE_GAUSSIAN, CUPID_INFLUENCE_INVERSE,
                                          CUPID_INFLUENCE_CONSTANT};
  static const cupid_partial_volume pv[2] = {CUPID_PARTIAL_PDLAMMPS, CUPID_PARTIAL_EXACT};
  int cases = 0;
  worst = 0.0;
  for (int model = 0; model < 2; model++)
    for (int k = 0; k < 4; k++) {
      if (small() && k != 0 && k != 2) continue;
      for (int a = 0; a < 3; a++)
        for (int b = 0; b < 2; b++) {
          if (small() && (a || b)) continue;
          for (int deep = 0; deep < 2; deep++) {
            pd_case c = {model ? CUPID_PD_BOND : CUPID_PD_LPS, ms[k], infl[a], pv[b], deep};
            run_pd_case(&c);
            cases++;
          }
        }
    }
  print_message("PD operator: %d cases x 4 states x %d instances, largest |y - K x| / |K x| "
                "%.2e\n", cases, n_isa, worst);
}

/* ------------------------------------------------------------- 2. coupled models */

typedef struct {
  double m;
  const char *model, *infl, *pv;
  int W, D; /* the section (x, z) in spacings */
} coupled_case;

/* A bar: beam axis y in [0, 40], the PD region y in [10, 30] over the whole section. */
static cupid_problem make_problem(const coupled_case *c, const char *coupling, const char *extra,
                                  int pd_only) {
  char yaml[4096];
  int len = snprintf(yaml, sizeof yaml,
                     "title: operator consistency\n"
                     "materials:\n  m: {E: 1000, nu: 0.25, density: 1.0e-6}\n");
  if (!pd_only)
    len += snprintf(yaml + len, sizeof yaml - (size_t)len,
                    "beam:\n  material: m\n"
                    "  axis: {y: [0, 10, 14, 26, 30, 40], elements: [1, 1, 2, 1, 1], type: B3}\n"
                    "  section:\n    expansion: LE\n    element: L9\n"
                    "    components:\n      - {x: [0, %d], z: [0, %d]}\n",
                    c->W, c->D);
  len += snprintf(yaml + len, sizeof yaml - (size_t)len,
                  "peridynamics:\n  spacing: 1.0\n  horizon: %g\n  model: %s\n  influence: %s\n"
                  "  partial_volume: %s\n  material: m\n"
                  "  regions:\n    - {x: [0, %d], y: [10, 30], z: [0, %d]}\n%s"
                  "%s"
                  "%s"
                  "analysis: {type: static, solver: direct}\n"
                  "output: {directory: /tmp/cupid_consistency_unused}\n",
                  c->m, c->model, c->infl, c->pv, c->W, c->D, extra ? extra : "",
                  coupling ? coupling : "",
                  pd_only ? "constraints:\n  - fix: {box: {y: [10, 11]}, components: [x, y, z]}\n"
                          : "constraints:\n  - clamp: {y: 0}\n"
                            "loads:\n  - traction: {y: 40, value: [0, 1, 0]}\n");
  assert_true(len < (int)sizeof yaml);
  cupid_run_options ro = cupid_run_options_default();
  ro.quiet = 1;
  ro.solver = CUPID_SOLVER_DIRECT;
  cupid_problem p = NULL;
  CUPID_ASSERT_OK(cupid_problem_create_from_string(yaml, "consistency.yaml", &ro, &p));
  CUPID_ASSERT_OK(cupid_problem_setup(p));
  return p;
}

static void coupled_name(const coupled_case *c, const char *what, int isa, char *buf, size_t len) {
  snprintf(buf, len, "%s, %s m=%g %s %s, section %d x %d, CUPID_PD_ISA=%d", what, c->model, c->m,
           c->infl, c->pv, c->W, c->D, isa);
}

typedef cupid_status (*apply_fn)(void *ctx, const double *x, double *y);

/* y = apply(x) against K x (with @p B: K x corrected by B, the balanced twin) on every
 * instance. */
static void compare_twin(const coupled_case *c, const char *what, apply_fn apply, void *ctx,
                         const cupid_csr_t *K, cupid_coupling_balance B, cupid_int n) {
  double *x = vec(n), *y = vec(n), *k = vec(n);
  random_fill(x, n, 99 + (uint64_t)n);
  cupid_csr_matvec(K, x, k);
  if (B) cupid_coupling_balance_correct(B, x, k);
  for (int l = 0; l < n_isa; l++) {
    pd_stencil_force_isa(isa_levels[l]);
    CUPID_ASSERT_OK(apply(ctx, x, y));
    char name[320];
    coupled_name(c, what, isa_levels[l], name, sizeof name);
    check(name, y, k, n);
  }
  pd_stencil_force_isa(0);
  cupid_free(&x);
  cupid_free(&y);
  cupid_free(&k);
}

static void compare_system(const coupled_case *c, const char *what, apply_fn apply, void *ctx,
                           const cupid_csr_t *K, cupid_int n) {
  compare_twin(c, what, apply, ctx, K, NULL, n);
}

static cupid_status method_apply(void *ctx, const double *x, double *y) {
  const cupid_method_operator *op = ctx;
  return op->apply(op->ctx, x, y);
}

static cupid_status linear_apply(void *ctx, const double *x, double *y) {
  const cupid_linear_operator *L = ctx;
  return L->apply(L->ctx, x, y);
}

/* The downdate of the direct path: K_old x - C C^T x against K_new x (bond-based). */
static void check_downdate(const coupled_case *c, const cupid_csr_t *Kold, const cupid_csr_t *Knew,
                           cupid_int n) {
  cupid_growth_downdate dd = {0};
  int ok = 0;
  CUPID_ASSERT_OK(cupid_growth_downdate_terms(Kold, Knew, &dd, &ok));
  assert_true(ok && dd.r > 0);
  double *x = vec(n), *y = vec(n), *k = vec(n);
  random_fill(x, n, 5);
  cupid_csr_matvec(Kold, x, y);
  for (cupid_int col = 0; col < dd.r; col++) {
    double dot = 0.0;
    for (cupid_int t = dd.colptr[col]; t < dd.colptr[col + 1]; t++) dot += dd.vals[t] * x[dd.rows[t]];
    for (cupid_int t = dd.colptr[col]; t < dd.colptr[col + 1]; t++) y[dd.rows[t]] -= dd.vals[t] * dot;
  }
  cupid_csr_matvec(Knew, x, k);
  char name[320];
  coupled_name(c, "growth, direct path: K_old - C C^T (factor downdate) against K_new", 0, name,
               sizeof name);
  check(name, y, k, n);
  cupid_growth_downdate_free(&dd);
  cupid_free(&x);
  cupid_free(&y);
  cupid_free(&k);
}

/* Arlequin: the explicit operator and the growth operator, intact, pre-cracked, and after
 * each of three rounds of breaks (the most stretched bond outside the protected overlaps). */
static void check_arlequin(const coupled_case *c) {
  char extra[256];
  snprintf(extra, sizeof extra,
           "  precracks:\n    - {normal: y, at: 20, x: [0, %g], z: [0, %d]}\n"
           "  fracture: {criterion: stretch, critical_stretch: 0.01}\n",
           0.5 * c->W, c->D);
  cupid_problem p = make_problem(c, "coupling:\n  method: arlequin\n  arlequin: {penalty: 1.0e4, "
                                 "overlap: [{y: [10, 14]}, {y: [26, 30]}], weight: linear}\n",
                                 extra, 0);
  cupid_problem_state *prob = p;
  assert_true(prob->precrack_bonds > 0);
  CUPID_ASSERT_OK(prob->method->assemble(prob));
  const cupid_int n = prob->ndof;
  cupid_method_operator ex = {0};
  CUPID_ASSERT_OK(prob->method->explicit_operator(prob, &ex));
  compare_system(c, "Arlequin, explicit-dynamics operator, pre-cracked", method_apply, &ex, prob->K, n);
  ex.destroy(&ex.ctx);
  prob->crack_copy = NULL;

  cupid_linear_operator L;
  cupid_csr P = NULL;
  cupid_method_operator owner = {0};
  CUPID_ASSERT_OK(prob->method->growth_operator(prob, &L, &P, &owner));
  assert_true(prob->crack_copy != NULL);
  compare_system(c, "Arlequin, growth operator, pre-cracked", linear_apply, &L, prob->K, n);
  double *u = vec(n);
  random_fill(u, n, 3);
  cupid_pd_fracture_options fo = prob->fracture;
  fo.critical_stretch = 1e-12, fo.node_stretch = NULL;
  for (int round = 0; round < 3; round++) {
    cupid_int broken = 0;
    double diss = 0.0;
    CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(prob->op, u, &fo, 1, &broken, &diss));
    assert_int_equal(broken, 1);
    CUPID_ASSERT_OK(cupid_pd_operator_copy_broken(prob->crack_copy, prob->op));
    cupid_csr Kold = prob->K;
    prob->K = NULL;
    CUPID_ASSERT_OK(prob->method->assemble(prob));
    char what[96];
    snprintf(what, sizeof what, "Arlequin, growth operator after break round %d", round + 1);
    compare_system(c, what, linear_apply, &L, prob->K, n);
    if (strcmp(c->model, "bond") == 0) check_downdate(c, Kold, prob->K, n);
    cupid_csr_destroy(&Kold);
  }
  cupid_free(&u);
  owner.destroy(&owner.ctx);
  prob->crack_copy = NULL;
  cupid_csr_destroy(&P);
  cupid_problem_destroy(&p);
}

/* Fictitious nodes: the matrix-free Eq. 38 against its assembly; balanced: the wrapped
 * operator against the assembled K with the correction of the assembled K. */
static void check_fictitious(const coupled_case *c, int balanced) {
  cupid_problem p = make_problem(c, balanced ? "coupling: {method: fictitious, balance: momentum}\n"
                                             : "coupling: {method: fictitious}\n",
                                 NULL, 0);
  cupid_problem_state *prob = p;
  cupid_coupling_options co;
  cupid_box *boxes = NULL;
  int *mats = NULL;
  CUPID_ASSERT_OK(cupid_method_coupling_options(prob, &co, &boxes, &mats));
  cupid_coupling_operator A = NULL;
  CUPID_ASSERT_OK(cupid_coupling_operator_create(prob->beam, prob->grid, &co, &A));
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_coupling_operator_assemble(A, NULL, &K));
  cupid_linear_operator L;
  cupid_coupling_operator_linear(A, &L);
  const cupid_int n = cupid_coupling_operator_size(A);
  assert_int_equal(n, prob->ndof);
  if (!balanced) {
    compare_system(c, "fictitious nodes (Eq. 38), matrix-free", linear_apply, &L, K, n);
  } else {
    cupid_coupling_balance Bf = NULL, Ba = NULL;
    cupid_linear_operator Lb;
    CUPID_ASSERT_OK(cupid_problem_balanced_operator(prob, A, &L, &Bf, &Lb));
    CUPID_ASSERT_OK(cupid_problem_balance_assembled(prob, K, &Ba));
    compare_twin(c, "fictitious nodes, balance: momentum (K - W C^T), matrix-free", linear_apply,
                 &Lb, K, Ba, n);
    cupid_coupling_balance_destroy(&Bf);
    cupid_coupling_balance_destroy(&Ba);
  }
  cupid_csr_destroy(&K);
  cupid_coupling_operator_destroy(&A);
  cupid_free(&boxes);
  cupid_free(&mats);
  cupid_problem_destroy(&p);
}

/* Lagrange: T^T diag(K_PD, K_FE) T x by the tie and the matrix-free PD operator. */
typedef struct {
  cupid_problem_state *prob;
  cupid_csr_t *Kfe;
  double *t;
} lagrange_free;

static cupid_status lagrange_apply(void *ctx, const double *x, double *y) {
  const lagrange_free *L = ctx;
  const cupid_problem_state *prob = L->prob;
  memcpy(L->t, x, (size_t)prob->ndof * sizeof *x);
  cupid_coupling_recover(prob->coupling, L->t); /* u_tied = T u_FE */
  CUPID_CALL(cupid_pd_operator_apply(prob->op, L->t, y));
  cupid_csr_matvec(L->Kfe, L->t + prob->fe_offset, y + prob->fe_offset);
  cupid_coupling_lagrange_load(prob->coupling, y); /* T^T: the tied rows onto the beam */
  return CUPID_SUCCESS;
}

static void check_lagrange(const coupled_case *c) {
  cupid_problem p = make_problem(c, "coupling: {method: lagrange}\n", NULL, 0);
  cupid_problem_state *prob = p;
  CUPID_ASSERT_OK(prob->method->assemble(prob));
  lagrange_free L = {.prob = prob, .t = vec(prob->ndof)};
  CUPID_ASSERT_OK(cupid_cuf_assemble(prob->beam, &L.Kfe));
  compare_system(c, "Lagrange (T^T diag(K_PD, K_FE) T)", lagrange_apply, &L, prob->K, prob->ndof);
  cupid_csr_destroy(&L.Kfe);
  cupid_free(&L.t);
  cupid_problem_destroy(&p);
}

/* PD only: the explicit operator of method none (the PD operator) against its K. */
static void check_pd_only(const coupled_case *c) {
  cupid_problem p = make_problem(c, NULL, NULL, 1);
  cupid_problem_state *prob = p;
  CUPID_ASSERT_OK(prob->method->assemble(prob));
  cupid_method_operator ex = {0};
  CUPID_ASSERT_OK(prob->method->explicit_operator(prob, &ex));
  assert_non_null(ex.apply);
  compare_system(c, "PD only, explicit-dynamics operator", method_apply, &ex, prob->K, prob->ndof);
  cupid_problem_destroy(&p);
}

static const coupled_case coupled_cases[] = {
    {1.5, "lps", "gaussian", "pdlammps", 20, 5},  /* deep: uniform runs */
    {2.0, "lps", "inverse", "exact", 24, 9},      /* deep: uniform runs */
    {3.015, "bond", "constant", "pdlammps", 12, 4},
    {4.0, "lps", "gaussian", "exact", 10, 4},
};

static void test_coupled_matrix(void **state) {
  (void)state;
  worst = 0.0;
  int ran = 0;
  for (size_t k = 0; k < sizeof coupled_cases / sizeof *coupled_cases; k++) {
    const coupled_case *c = &coupled_cases[k];
    if (small() && c->m != 1.5 && c->m != 3.015) continue;
    check_arlequin(c);
    check_fictitious(c, 0);
    check_fictitious(c, 1);
    check_lagrange(c);
    check_pd_only(c);
    ran++;
  }
  print_message("coupled operators: %d horizons x 5 methods x %d instances, largest |y - K x| / "
                "|K x| %.2e\n", ran, n_isa, worst);
}

/* The uniform stretches see the weights themselves: after scale_energy, a run of uniform b
 * never spans nodes of different b (the root of issue 32, checked node by node). */
static void test_uniform_after_weights(void **state) {
  (void)state;
  const pd_case c = {CUPID_PD_LPS, 1.5, CUPID_INFLUENCE_GAUSSIAN, CUPID_PARTIAL_PDLAMMPS, 1};
  cupid_pd_grid grid = NULL;
  cupid_pd_operator op = NULL;
  box_operator(24, 6, 5, &c, &grid, &op);
  const cupid_int before = uniform_nodes(op);
  assert_true(before >= 16);
  double *w = vec(op->nnodes);
  const double *X = cupid_pd_grid_coords(grid);
  for (cupid_int i = 0; i < op->nnodes; i++) w[i] = X[3 * i] < 12.0 ? 1.0 : 0.5 + 0.01 * X[3 * i];
  CUPID_ASSERT_OK(cupid_pd_operator_scale_energy(op, w));
  cupid_free(&w);
  cupid_int after = 0;
  for (cupid_int r = 0; r < op->nruns; r++) {
    const pd_run *R = &op->runs[r];
    for (cupid_int i = R->i0 + R->ub0; i < R->i0 + R->ub1; i++) {
      const double bi = op->mu[i] / op->m[i];
      const pd_family F = pd_family_of(op, i);
      for (int s = 0; s < op->st.n; s++) {
        const cupid_int j = pd_family_node(op, &F, s);
        assert_true(j >= 0 && op->mu[j] / op->m[j] == bi);
      }
      after++;
    }
  }
  assert_true(after > 0 && after < before); /* the w = 1 part keeps its stretch */
  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&grid);
}

int main(void) {
  find_instances();
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_uniform_after_weights),
                                     cmocka_unit_test(test_pd_matrix),
                                     cmocka_unit_test(test_coupled_matrix)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
