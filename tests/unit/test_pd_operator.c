/* Unit tests of the PD operators (src/pd): the analytically assembled K against the
 * matrix-free map and finite differences of the energy, symmetry, rigid-body null space,
 * patch test, estimates and argument errors, for both models, every influence function
 * and every partial-volume rule, on a box, an L-shaped two-material union and a 1D bar. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

/* Dense copy of a small block matrix (3n x 3n, row-major). */
static double *csr_dense(const cupid_csr_t *A) {
  const cupid_int n = 3 * A->nrows;
  double *D = calloc((size_t)(n * n), sizeof *D);
  assert_non_null(D);
  for (cupid_int r = 0; r < A->nrows; r++) {
    for (cupid_int q = A->rowptr[r]; q < A->rowptr[r + 1]; q++) {
      if (q > A->rowptr[r]) assert_true(A->col[q] > A->col[q - 1]); /* sorted, no duplicates */
      for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) D[(3 * r + i) * n + 3 * A->col[q] + j] = A->val[9 * q + 3 * i + j];
    }
  }
  return D;
}

/* ||A||_inf: the largest absolute row sum. */
static double csr_norm_inf(const cupid_csr_t *A) {
  double m = 0;
  for (cupid_int r = 0; r < A->nrows; r++)
    for (int i = 0; i < 3; i++) {
      double s = 0;
      for (cupid_int q = A->rowptr[r]; q < A->rowptr[r + 1]; q++)
        for (int j = 0; j < 3; j++) s += fabs(A->val[9 * q + 3 * i + j]);
      m = s > m ? s : m;
    }
  return m;
}

static double max_abs(const double *x, cupid_int n) {
  double m = 0;
  for (cupid_int i = 0; i < n; i++) m = fabs(x[i]) > m ? fabs(x[i]) : m;
  return m;
}

static double dot(const double *a, const double *b, cupid_int n) {
  double s = 0;
  for (cupid_int i = 0; i < n; i++) s += a[i] * b[i];
  return s;
}

static cupid_box box3(double x0, double x1, double y0, double y1, double z0, double z1) {
  cupid_box b = {.lo = {x0, y0, z0}, .hi = {x1, y1, z1}, .has = {1, 1, 1}};
  return b;
}

static const char *model_name[] = {"lps", "bond"};
static const char *infl_name[] = {"gaussian", "inverse", "constant"};
static const char *pv_name[] = {"none", "pdlammps", "exact"};

static cupid_pd_material materials[2] = {{2.0e3, 0.3}, {6.0e3, 0.2}};

static cupid_pd_operator make_op(cupid_pd_grid g, int model, int infl, int pvr, double delta) {
  cupid_pd_operator_options o = {.horizon = delta, .model = (cupid_pd_model_kind)model,
                                 .influence = (cupid_influence)infl,
                                 .partial_volume = (cupid_partial_volume)pvr,
                                 .materials = materials, .n_materials = 2};
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(g, &o, &op));
  /* The estimate counts the same bonds, and bounds (bond-based: equals) the blocks. */
  cupid_pd_estimate est;
  CUPID_ASSERT_OK(cupid_pd_operator_estimate(g, &o, &est));
  assert_int_equal(est.nodes, cupid_pd_grid_num_nodes(g));
  assert_int_equal(est.bonds, cupid_pd_operator_num_bonds(op));
  return op;
}

/* The checks that hold for any grid and options:
 *  - K e_k == apply(e_k) for every DOF k: exact in exact arithmetic; 1e-13 of max |K_ij|
 *    allows for the different summation orders (~100s of terms of rounding 1e-16);
 *  - K symmetric: max |K_ij - K_ji| <= 1e-14 max |K_ij| (same terms, different order);
 *  - apply is the gradient of the energy and K its Hessian: central differences of the
 *    quadratic energy are exact but for rounding, eps_mach E / eps^2 ~ 1e-12 of the scale
 *    at eps = 0.1 (tolerance 1e-9);
 *  - rigid translations (and in 3D the 3 infinitesimal rotations) are in the null space:
 *    ||K r||_inf <= 1e-12 ||K||_inf ||r||_inf (rounding ~1e-15 of the row sums).
 * Returns K for further checks. */
static cupid_csr check_operator(cupid_pd_grid g, cupid_pd_operator op, const char *label) {
  const cupid_int nn = cupid_pd_grid_num_nodes(g), n = 3 * nn;
  const int dim = cupid_pd_grid_dimension(g);
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(op, &K));
  assert_int_equal(K->nrows, nn);
  assert_int_equal(K->bs, 3);
  double *D = csr_dense(K);
  const double kmax = max_abs(D, n * n);
  assert_true(kmax > 0);
  double *e = calloc((size_t)n, sizeof *e), *f = calloc((size_t)n, sizeof *f);
  double worst_col = 0, worst_sym = 0;
  for (cupid_int k = 0; k < n; k++) {
    e[k] = 1.0;
    CUPID_ASSERT_OK(cupid_pd_operator_apply(op, e, f));
    e[k] = 0.0;
    for (cupid_int i = 0; i < n; i++) {
      double d = fabs(f[i] - D[i * n + k]);
      worst_col = d > worst_col ? d : worst_col;
      double s = fabs(D[i * n + k] - D[k * n + i]);
      worst_sym = s > worst_sym ? s : worst_sym;
    }
  }
  if (worst_col > 1e-13 * kmax || worst_sym > 1e-14 * kmax)
    fail_msg("%s: |K e_k - apply(e_k)| = %.3g, asymmetry %.3g (max |K| %.3g)", label, worst_col,
             worst_sym, kmax);
  /* Diagonal blocks. */
  double *blk = malloc(9 * (size_t)nn * sizeof *blk);
  CUPID_ASSERT_OK(cupid_pd_operator_diagonal(op, blk));
  for (cupid_int r = 0; r < nn; r++)
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++)
        if (fabs(blk[9 * r + 3 * i + j] - D[(3 * r + i) * n + 3 * r + j]) > 1e-14 * kmax)
          fail_msg("%s: diagonal block %lld differs from K", label, (long long)r);
  free(blk);

  /* Finite differences of the energy. */
  uint64_t seed = 12345;
  double *u = malloc((size_t)n * sizeof *u), *v = malloc((size_t)n * sizeof *v);
  double *w = malloc((size_t)n * sizeof *w), *t = malloc((size_t)n * sizeof *t);
  double *Kv = malloc((size_t)n * sizeof *Kv), *fp = malloc((size_t)n * sizeof *fp);
  for (cupid_int i = 0; i < n; i++) {
    u[i] = cupid_test_random(&seed);
    v[i] = cupid_test_random(&seed);
    w[i] = cupid_test_random(&seed);
    if (dim == 1 && i % 3 != 1) u[i] = v[i] = w[i] = 0.0; /* a 1D bar moves along y */
  }
  const double eps = 0.1;
  double Ep, Em, Epp, Epm, Emp, Emm;
#define AT(dst, a, b, c)                                                                       \
  do {                                                                                         \
    for (cupid_int i = 0; i < n; i++) t[i] = u[i] + (a) * v[i] + (b) * w[i];                   \
    CUPID_ASSERT_OK(cupid_pd_operator_energy(op, t, &(dst)));                                  \
    (void)(c);                                                                                 \
  } while (0)
  AT(Ep, eps, 0, 0);
  AT(Em, -eps, 0, 0);
  AT(Epp, eps, eps, 0);
  AT(Epm, eps, -eps, 0);
  AT(Emp, -eps, eps, 0);
  AT(Emm, -eps, -eps, 0);
#undef AT
  double E0;
  CUPID_ASSERT_OK(cupid_pd_operator_energy(op, u, &E0));
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, u, f));
  cupid_csr_matvec(K, v, Kv);
  const double grad_fd = (Ep - Em) / (2 * eps), grad = dot(v, f, n);
  const double hess_fd = (Epp - Epm - Emp + Emm) / (4 * eps * eps), hess = dot(w, Kv, n);
  const double escale = fabs(E0) + 1e-300;
  if (fabs(grad_fd - grad) > 1e-9 * escale || fabs(hess_fd - hess) > 1e-9 * escale)
    fail_msg("%s: FD gradient %.15g vs v.f %.15g, FD Hessian %.15g vs w.Kv %.15g (E %.3g)", label,
             grad_fd, grad, hess_fd, hess, E0);
  /* Directional FD of the (linear) matrix-free map against the assembled K. */
  for (cupid_int i = 0; i < n; i++) t[i] = u[i] + eps * v[i];
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, t, fp));
  for (cupid_int i = 0; i < n; i++) t[i] = u[i] - eps * v[i];
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, t, f));
  double fdmax = 0, kvmax = max_abs(Kv, n);
  for (cupid_int i = 0; i < n; i++) {
    double d = fabs((fp[i] - f[i]) / (2 * eps) - Kv[i]);
    fdmax = d > fdmax ? d : fdmax;
  }
  if (fdmax > 1e-10 * kvmax) fail_msg("%s: FD of apply differs from K v by %.3g (|Kv| %.3g)", label, fdmax, kvmax);

  /* Rigid-body modes. */
  const double knorm = csr_norm_inf(K);
  const double *x = cupid_pd_grid_coords(g);
  const int nmodes = dim == 3 ? 6 : 1;
  for (int mode = 0; mode < nmodes; mode++) {
    for (cupid_int p = 0; p < nn; p++) {
      const double *xp = x + 3 * p;
      double r[3] = {0, 0, 0};
      if (dim == 1) r[1] = 1.0;
      else if (mode < 3) r[mode] = 1.0;
      else { /* omega x x with omega = e_(mode-3) */
        const int a = mode - 3, b = (a + 1) % 3, c = (a + 2) % 3;
        r[b] = -xp[c];
        r[c] = xp[b];
      }
      for (int c = 0; c < 3; c++) t[3 * p + c] = r[c];
    }
    cupid_csr_matvec(K, t, Kv);
    CUPID_ASSERT_OK(cupid_pd_operator_apply(op, t, f));
    const double rn = max_abs(t, n);
    if (max_abs(Kv, n) > 1e-12 * knorm * rn || max_abs(f, n) > 1e-12 * knorm * rn)
      fail_msg("%s: rigid mode %d: |K r| = %.3g, |apply r| = %.3g, |K| |r| = %.3g", label, mode,
               max_abs(Kv, n), max_abs(f, n), knorm * rn);
  }
  free(D);
  free(e);
  free(f);
  free(u);
  free(v);
  free(w);
  free(t);
  free(Kv);
  free(fp);
  return K;
}

static void all_options_on(cupid_pd_grid g, const double *deltas, int ndeltas, int models) {
  char label[160];
  for (int model = 0; model < 2; model++) {
    if (!(models & (1 << model))) continue;
    for (int infl = 0; infl < 3; infl++)
      for (int pvr = 0; pvr < 3; pvr++)
        for (int d = 0; d < ndeltas; d++) {
          snprintf(label, sizeof label, "%s/%s/%s/delta=%g", model_name[model], infl_name[infl],
                   pv_name[pvr], deltas[d]);
          cupid_pd_operator op = make_op(g, model, infl, pvr, deltas[d]);
          cupid_csr K = check_operator(g, op, label);
          /* The block estimate: exact for bond-based, an upper bound for LPS. */
          cupid_pd_operator_options o = {.horizon = deltas[d], .model = (cupid_pd_model_kind)model,
                                         .influence = (cupid_influence)infl,
                                         .partial_volume = (cupid_partial_volume)pvr,
                                         .materials = materials, .n_materials = 2};
          cupid_pd_estimate est;
          CUPID_ASSERT_OK(cupid_pd_operator_estimate(g, &o, &est));
          if (model == CUPID_PD_BOND) assert_int_equal(est.blocks, K->rowptr[K->nrows]);
          else assert_true(est.blocks >= K->rowptr[K->nrows]);
          cupid_csr_destroy(&K);
          cupid_pd_operator_destroy(&op);
          assert_null(op);
        }
  }
}

/* CUPID_TEST_SMALL (valgrind, the sanitizers: the same code, 831 s under valgrind on 2 busy
 * cores): the box with one horizon, the patch test with each influence and each partial volume
 * once per model, not the L-shaped union's. */
static int small(void) { return getenv("CUPID_TEST_SMALL") != NULL; }

/* A 6 x 5 x 7 box, delta = 2.5 h and 3.015 h (m = 3 with the usual offset). */
static void test_box_all_options(void **state) {
  (void)state;
  cupid_box b = box3(0, 6, 0, 5, 0, 7);
  int mat = 0;
  cupid_pd_grid_options o = {.spacing = 1.0, .dimension = 3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 1, &b, &mat, &g));
  const double deltas[] = {2.5, 3.015};
  all_options_on(g, deltas, small() ? 1 : 2, 3);
  cupid_pd_grid_destroy(&g);
}

/* An L-shaped union of two boxes of different materials (per-node constants), h = 0.5. */
static void test_l_shape_two_materials(void **state) {
  (void)state;
  cupid_box b[2] = {box3(0, 4, 0, 1.5, 0, 2), box3(0, 1.5, 1.5, 4, 0, 2)};
  int mats[2] = {0, 1};
  cupid_pd_grid_options o = {.spacing = 0.5, .dimension = 3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 2, b, mats, &g));
  assert_int_equal(cupid_pd_grid_num_nodes(g), 8 * 3 * 4 + 3 * 5 * 4);
  const double deltas[] = {1.25};
  all_options_on(g, deltas, 1, 3);
  cupid_pd_grid_destroy(&g);
}

static void test_bar_1d_bond(void **state) {
  (void)state;
  cupid_box b = {.lo = {0, 0, 0}, .hi = {0, 5, 0}, .has = {0, 1, 0}};
  int mat = 1;
  cupid_pd_grid_options o = {.spacing = 0.25, .dimension = 1, .area = 0.3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 1, &b, &mat, &g));
  const double deltas[] = {0.75, 0.8};
  all_options_on(g, deltas, 2, 2);
  cupid_pd_grid_destroy(&g);
}

/* Patch test: u = A x + b gives zero force at nodes farther than 2 delta (LPS) or delta
 * (bond-based) from the surface (with EXACT the family reaches delta + sqrt(3)/2 h, which
 * replaces delta), relative 1e-12 of the node's force scale
 * sum_j |K_ij| |u_j| (the size of the terms that cancel). Also theta = tr A there. */
static void patch_test(cupid_pd_grid g, int model, int infl, int pvr, double delta) {
  const cupid_int nn = cupid_pd_grid_num_nodes(g), n = 3 * nn;
  cupid_pd_operator op = make_op(g, model, infl, pvr, delta);
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(op, &K));
  uint64_t seed = 777;
  double A[9], b[3];
  for (int i = 0; i < 9; i++) A[i] = 1e-3 * cupid_test_random(&seed);
  for (int i = 0; i < 3; i++) b[i] = 1e-3 * cupid_test_random(&seed);
  const double *x = cupid_pd_grid_coords(g);
  double *u = malloc((size_t)n * sizeof *u), *f = malloc((size_t)n * sizeof *f);
  double *theta = malloc((size_t)nn * sizeof *theta);
  for (cupid_int p = 0; p < nn; p++)
    for (int i = 0; i < 3; i++)
      u[3 * p + i] = b[i] + A[3 * i] * x[3 * p] + A[3 * i + 1] * x[3 * p + 1] + A[3 * i + 2] * x[3 * p + 2];
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, u, f));
  CUPID_ASSERT_OK(cupid_pd_operator_dilatation(op, u, theta));
  unsigned char *in2 = malloc((size_t)nn), *in1 = malloc((size_t)nn);
  const double reach = pvr == CUPID_PARTIAL_EXACT ? delta + 0.5 * sqrt(3.0) * cupid_pd_grid_spacing(g) : delta;
  CUPID_ASSERT_OK(cupid_pd_grid_interior(g, model == CUPID_PD_LPS ? 2 * reach : reach, in2));
  CUPID_ASSERT_OK(cupid_pd_grid_interior(g, reach, in1));
  int checked = 0;
  double worst = 0;
  for (cupid_int r = 0; r < nn; r++) {
    if (in1[r] && model == CUPID_PD_LPS) /* full family: theta = tr A up to rounding */
      ASSERT_NEAR(theta[r], A[0] + A[4] + A[8], 1e-12 * max_abs(A, 9));
    if (!in2[r]) continue;
    checked++;
    for (int i = 0; i < 3; i++) {
      double scale = 0;
      for (cupid_int q = K->rowptr[r]; q < K->rowptr[r + 1]; q++)
        for (int j = 0; j < 3; j++) scale += fabs(K->val[9 * q + 3 * i + j] * u[3 * K->col[q] + j]);
      double rel = fabs(f[3 * r + i]) / scale;
      worst = rel > worst ? rel : worst;
    }
  }
  if (!(checked > 0 && worst < 1e-12))
    fail_msg("patch test %s/%s/%s: %d interior nodes, worst relative force %.3g", model_name[model],
             infl_name[infl], pv_name[pvr], checked, worst);
  /* Near the surface the force is not zero (so the check above can fail). */
  double fmax = max_abs(f, n);
  assert_true(fmax > 1e-6 * csr_norm_inf(K) * max_abs(u, n));
  free(u);
  free(f);
  free(theta);
  free(in1);
  free(in2);
  cupid_csr_destroy(&K);
  cupid_pd_operator_destroy(&op);
}

static void test_patch(void **state) {
  (void)state;
  /* Box: 2 delta = 4 (5.7 for EXACT) leaves a 4 x 3 x 5 (2 x 1 x 3) interior. */
  cupid_box b = box3(0, 12, 0, 11, 0, 13);
  int mat = 0;
  cupid_pd_grid_options o = {.spacing = 1.0, .dimension = 3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 1, &b, &mat, &g));
  for (int model = 0; model < 2; model++)
    for (int infl = 0; infl < 3; infl++)
      for (int pvr = 0; pvr < 3; pvr++)
        if (!small() || infl == pvr) patch_test(g, model, infl, pvr, 2.0);
  cupid_pd_grid_destroy(&g);
  if (small()) return;
  /* L-shaped union of one material (the interior flags follow the re-entrant corner). */
  cupid_box l[2] = {box3(0, 14, 0, 12, 0, 12), box3(0, 12, 12, 18, 0, 12)};
  int mats[2] = {1, 1};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 2, l, mats, &g));
  for (int model = 0; model < 2; model++) patch_test(g, model, CUPID_INFLUENCE_GAUSSIAN, CUPID_PARTIAL_EXACT, 2.0);
  cupid_pd_grid_destroy(&g);
}

static void test_errors(void **state) {
  (void)state;
  cupid_box b = {.lo = {0, 0, 0}, .hi = {0, 5, 0}, .has = {0, 1, 0}};
  int mat = 0;
  cupid_pd_grid_options o = {.spacing = 1, .dimension = 1, .area = 1};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 1, &b, &mat, &g));
  cupid_pd_operator_options oo = {.horizon = 3, .model = CUPID_PD_LPS, .materials = materials,
                                  .n_materials = 1};
  cupid_pd_operator op = NULL;
  assert_int_equal(cupid_pd_operator_create(g, &oo, &op), CUPID_ERR_UNSUPPORTED);
  assert_null(op);
  oo.model = CUPID_PD_BOND;
  oo.horizon = 0.9; /* below the spacing: no neighbour */
  assert_int_equal(cupid_pd_operator_create(g, &oo, &op), CUPID_ERR_MODEL);
  oo.horizon = 3;
  cupid_pd_material bad = {1.0, 0.5};
  oo.materials = &bad;
  assert_int_equal(cupid_pd_operator_create(g, &oo, &op), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "Poisson"));
  /* a material no node uses is not read (a beam's orthotropic material has no E, nu: issue
   * 19): the same bad material as the second of two, the nodes on the first */
  cupid_pd_material two[2] = {{1.0, 0.25}, {0.0, 0.0}};
  oo.materials = two;
  oo.n_materials = 2;
  CUPID_ASSERT_OK(cupid_pd_operator_create(g, &oo, &op));
  cupid_pd_operator_destroy(&op);
  two[0] = (cupid_pd_material){-1.0, 0.25}; /* ... but the one the nodes use is */
  assert_int_equal(cupid_pd_operator_create(g, &oo, &op), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "Young"));
  oo.n_materials = 1;
  cupid_pd_grid_destroy(&g);
  mat = 3; /* material index beyond the list */
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 1, &b, &mat, &g));
  oo.materials = materials;
  oo.n_materials = 2;
  assert_int_equal(cupid_pd_operator_create(g, &oo, &op), CUPID_ERR_ARGUMENT);
  cupid_pd_grid_destroy(&g);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_box_all_options), cmocka_unit_test(test_l_shape_two_materials),
      cmocka_unit_test(test_bar_1d_bond),     cmocka_unit_test(test_patch),
      cmocka_unit_test(test_errors)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
