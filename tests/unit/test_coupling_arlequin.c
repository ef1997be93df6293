/* The Arlequin coupling (paper 004 section 3) on the truss of examples/truss/truss_arlequin.yaml:
 * CUF TE0 rod on [0, 0.6] (39 B2), 1D bond-based PD on [0.4, 1] (h = 0.015, delta = 3h),
 * overlap [0.4, 0.6], E = 1e9, A = 1, rho = 7800.
 *  - alpha: the three weights at the edges and inside, mirrored when the FE side is above;
 *  - weighted CUF stiffness and mass: weight 1 gives the unweighted matrices and 0.5 half of
 *    them (1e-13 relative: the same products summed with another Gauss rule);
 *  - the coupled K is symmetric (1e-14 relative asymmetry) and a rigid translation along the
 *    axis gives zero force (1e-12 of |K|: the penalty forces cancel since sum N_a = 1 and the
 *    weighted PD rows still sum to zero: momentum is conserved);
 *  - the weighted mass of a translation is int alpha rho A dy + sum (1 - alpha_i) rho V
 *    (1e-12 relative);
 *  - static end load F at the PD end, clamp at y = 0: the reaction balances F (1e-9) and the
 *    FE-only span [0, 0.4] carries exactly F, so u(y) = F y / (EA) there (1e-9 relative,
 *    whatever the penalty);
 *  - 3D: a bar 4 x 4 (h = 1), TE1 rod (nu = 0) + 3D PD (delta = 1.5, bond-based and LPS) on
 *    [8, 20], one overlap [8, 12] or two ([8, 12], [16, 20], the beam through and beyond the
 *    region): K symmetric and free of all three rigid translations (1e-12), end load: reaction
 *    (1e-9) and the FE-only spans carry exactly F (1e-9);
 *  - a general layout (a region over part of the section, overlaps along y and x): see
 *    case_partial();
 *  - the node-weighted PD stiffness: w = 1 is K, linear in w, symmetric, translation-free,
 *    bond-based (w_i + w_j)/2 per bond, the operator left unchanged. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cupid/coupling.h"
#include "test_cuf_common.h"
#include "test_slabs.h"

#define E_MOD 1e9
#define RHO 7800.0

typedef struct {
  tb_beam tb;
  cupid_cuf_beam beam;
  cupid_pd_grid grid;
  cupid_pd_operator op;
  cupid_pd_material mat;
  cupid_pd_operator_options po;
  cupid_int n_pd, ndof;
  cupid_arlequin_options o;
} truss;

static void truss_build(truss *t, double kappa) {
  memset(t, 0, sizeof *t);
  tb_init(&t->tb, E_MOD, 0.0);
  t->tb.mat[0].density = RHO;
  t->tb.mat[0].has_density = 1;
  tb_te(&t->tb, 0);
  tb_rect(&t->tb, -0.5, 0.5, 1, -0.5, 0.5, 1, -1);
  tb_axis(&t->tb, 0.0, 0.6, 39, 2);
  t->beam = tb_create(&t->tb);
  cupid_box region = {.lo = {0, 0.4, 0}, .hi = {0, 1.0, 0}, .has = {0, 1, 0}};
  int rmat = 0;
  cupid_pd_grid_options go = {.spacing = 0.015, .dimension = 1, .area = 1.0};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &region, &rmat, &t->grid));
  t->mat = (cupid_pd_material){.E = E_MOD, .nu = 0.0};
  t->po = (cupid_pd_operator_options){.horizon = 0.045, .model = CUPID_PD_BOND,
                                      .influence = CUPID_INFLUENCE_CONSTANT,
                                      .partial_volume = CUPID_PARTIAL_NONE, .materials = &t->mat,
                                      .n_materials = 1};
  CUPID_ASSERT_OK(cupid_pd_operator_create(t->grid, &t->po, &t->op));
  t->n_pd = cupid_pd_grid_num_nodes(t->grid);
  assert_int_equal(t->n_pd, 40);
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(t->beam, 3 * t->n_pd));
  t->ndof = 3 * t->n_pd + cupid_cuf_num_dofs(t->beam);
  t->o = (cupid_arlequin_options){
      .weight = {.lo = 0.4, .hi = 0.6, .fe_below = 1, .kind = CUPID_WEIGHT_LINEAR},
      .penalty = kappa};
}

static void truss_free(truss *t) {
  cupid_pd_operator_destroy(&t->op);
  cupid_pd_grid_destroy(&t->grid);
  cupid_cuf_beam_destroy(&t->beam);
}

static void test_alpha(void **state) {
  (void)state;
  cupid_arlequin_weight w = {.lo = 0.4, .hi = 0.6, .fe_below = 1, .kind = CUPID_WEIGHT_LINEAR};
  ASSERT_NEAR(cupid_arlequin_alpha(&w, 0.1), 1.0, 0);
  ASSERT_NEAR(cupid_arlequin_alpha(&w, 0.9), 0.0, 0);
  ASSERT_NEAR(cupid_arlequin_alpha(&w, 0.45), 0.75, 1e-15);
  w.kind = CUPID_WEIGHT_SMOOTH;
  ASSERT_NEAR(cupid_arlequin_alpha(&w, 0.5), 0.5, 1e-15);
  ASSERT_NEAR(cupid_arlequin_alpha(&w, 0.45), 1.0 - 3 * 0.0625 + 2 * 0.015625, 1e-15);
  w.kind = CUPID_WEIGHT_CONSTANT;
  ASSERT_NEAR(cupid_arlequin_alpha(&w, 0.41), 0.5, 0);
  ASSERT_NEAR(cupid_arlequin_alpha(&w, 0.39), 1.0, 0);
  w.fe_below = 0; /* FE above: alpha = 1 beyond hi */
  w.kind = CUPID_WEIGHT_LINEAR;
  ASSERT_NEAR(cupid_arlequin_alpha(&w, 0.7), 1.0, 0);
  ASSERT_NEAR(cupid_arlequin_alpha(&w, 0.45), 0.25, 1e-15);
}

static double w_one(void *ctx, double y) { (void)ctx, (void)y; return 1.0; }
static double w_half(void *ctx, double y) { (void)ctx, (void)y; return 0.5; }

static double max_abs(const cupid_csr_t *A) {
  double m = 0.0;
  for (cupid_int q = 0; q < 9 * A->rowptr[A->nrows]; q++) m = fmax(m, fabs(A->val[q]));
  return m;
}

/* max |A - s B| over A's pattern (B found block by block). */
static double diff_scaled(const cupid_csr_t *A, const cupid_csr_t *B, double s) {
  double d = 0.0;
  for (cupid_int r = 0; r < A->nrows; r++)
    for (cupid_int q = A->rowptr[r]; q < A->rowptr[r + 1]; q++) {
      const double *b = cupid_csr_find(B, r, A->col[q]);
      for (int e = 0; e < 9; e++) d = fmax(d, fabs(A->val[9 * q + e] - s * (b ? b[e] : 0.0)));
    }
  return d;
}

/* The matrix-free operator against the assembled K: K x to 1e-13 of |K| |x| (the PD rows are
 * summed in another order), rows split in three ranges equal to the whole product (1e-13:
 * apply_range sums a row's bonds in another order than the stencil sweep), and the cheap
 * preconditioner symmetric with no more blocks than K. */
static void check_operator(cupid_cuf_beam beam, cupid_pd_grid grid,
                           const cupid_pd_operator_options *po, const cupid_arlequin_options *o,
                           const cupid_csr_t *K) {
  cupid_arlequin_operator A = NULL;
  CUPID_ASSERT_OK(cupid_arlequin_operator_create(beam, grid, po, o, &A, NULL));
  cupid_int n = cupid_arlequin_operator_size(A);
  assert_int_equal(n, 3 * K->nrows);
  double *x = NULL, *y = NULL, *z = NULL, *yr = NULL;
  CUPID_ASSERT_OK(cupid_malloc((size_t)n, sizeof *x, "x", &x));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n, sizeof *y, "y", &y));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n, sizeof *z, "z", &z));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n, sizeof *yr, "yr", &yr));
  uint64_t seed = 11;
  double xm = 0.0;
  for (cupid_int d = 0; d < n; d++) x[d] = cupid_test_random(&seed), xm = fmax(xm, fabs(x[d]));
  cupid_csr_matvec(K, x, z);
  CUPID_ASSERT_OK(cupid_arlequin_operator_apply(A, x, y));
  double e = 0.0;
  for (cupid_int d = 0; d < n; d++) e = fmax(e, fabs(y[d] - z[d]));
  const cupid_int cut[4] = {0, n / 3 + 1, 2 * n / 3 - 1, n};
  for (int k = 0; k < 3; k++) CUPID_ASSERT_OK(cupid_arlequin_operator_apply_rows(A, x, cut[k], cut[k + 1], yr));
  double er = 0.0;
  for (cupid_int d = 0; d < n; d++) er = fmax(er, fabs(yr[d] - y[d]));
  cupid_csr P = NULL;
  CUPID_ASSERT_OK(cupid_arlequin_preconditioner(A, 0.0, &P));
  printf("matrix-free Arlequin: max |A x - K x| %.1e of |K| |x|, rows in 3 ranges %.1e; "
         "preconditioner %lld blocks (K %lld), asymmetry %.1e\n",
         e / (max_abs(K) * xm), er / (max_abs(K) * xm), (long long)cupid_csr_nnz(P), (long long)cupid_csr_nnz(K),
         cupid_csr_asymmetry(P));
  assert_true(e <= 1e-13 * max_abs(K) * xm);
  assert_true(er <= 1e-13 * max_abs(K) * xm);
  assert_true(cupid_csr_asymmetry(P) <= 1e-14);
  assert_true(cupid_csr_nnz(P) <= cupid_csr_nnz(K)); /* equal when the model is the cheap one */
  cupid_csr_destroy(&P);
  cupid_free(&x);
  cupid_free(&y);
  cupid_free(&z);
  cupid_free(&yr);
  cupid_arlequin_operator_destroy(&A);
}


static void test_weighted_cuf(void **state) {
  (void)state;
  truss t;
  truss_build(&t, 1e9);
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(t.beam, 0));
  cupid_csr K = NULL, Kw = NULL, Kh = NULL, M = NULL, Mw = NULL;
  CUPID_ASSERT_OK(cupid_cuf_assemble(t.beam, &K));
  CUPID_ASSERT_OK(cupid_cuf_assemble_weighted(t.beam, w_one, NULL, &Kw));
  CUPID_ASSERT_OK(cupid_cuf_assemble_weighted(t.beam, w_half, NULL, &Kh));
  double s = max_abs(K);
  assert_true(diff_scaled(Kw, K, 1.0) <= 1e-13 * s);
  assert_true(diff_scaled(Kh, K, 0.5) <= 1e-13 * s);
  CUPID_ASSERT_OK(cupid_cuf_mass_assemble(t.beam, &M));
  CUPID_ASSERT_OK(cupid_csr_duplicate(M, &Mw));
  cupid_csr_zero(Mw);
  CUPID_ASSERT_OK(cupid_cuf_mass_weighted_add(t.beam, w_half, NULL, Mw));
  assert_true(diff_scaled(Mw, M, 0.5) <= 1e-13 * max_abs(M));
  cupid_csr_destroy(&K);
  cupid_csr_destroy(&Kw);
  cupid_csr_destroy(&Kh);
  cupid_csr_destroy(&M);
  cupid_csr_destroy(&Mw);
  truss_free(&t);
}

/* The rigid translation along y: 1 on every PD y and on every FE y (TE0: u = u_y(y)). */
static double *translation_y(const truss *t) {
  double *v = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)t->ndof, sizeof *v, "translation", &v));
  for (cupid_int d = 1; d < t->ndof; d += 3) v[d] = 1.0;
  return v;
}

static void test_coupled_matrix(void **state) {
  (void)state;
  truss t;
  truss_build(&t, 1e11);
  cupid_csr K = NULL, M = NULL;
  cupid_arlequin_info info;
  CUPID_ASSERT_OK(cupid_arlequin_assemble(t.beam, t.grid, t.op, &t.o, &K, &info));
  assert_int_equal(info.n_tied, 13); /* PD nodes at 0.4075 + 0.015 k, k = 0..12 */
  assert_int_equal(info.components, 1);
  double asym = cupid_csr_asymmetry(K);
  printf("Arlequin K: asymmetry %.2e, %lld tied nodes\n", asym, (long long)info.n_tied);
  assert_true(asym <= 1e-14);
  double *v = translation_y(&t), *f = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)t.ndof, sizeof *f, "force", &f));
  cupid_csr_matvec(K, v, f);
  double fm = 0.0;
  for (cupid_int d = 0; d < t.ndof; d++) fm = fmax(fm, fabs(f[d]));
  printf("Arlequin K: max |K t| = %.2e (|K| = %.2e)\n", fm, max_abs(K));
  assert_true(fm <= 1e-12 * max_abs(K));

  /* weighted mass of the translation */
  double *pd_mass = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)t.n_pd, sizeof *pd_mass, "PD mass", &pd_mass));
  double V = cupid_pd_grid_cell_volume(t.grid), expect = RHO * 0.5; /* int alpha rho A dy */
  const double *x = cupid_pd_grid_coords(t.grid);
  for (cupid_int i = 0; i < t.n_pd; i++) {
    pd_mass[i] = RHO * V;
    expect += (1.0 - cupid_arlequin_alpha(&t.o.weight, x[3 * i + 1])) * RHO * V;
  }
  check_operator(t.beam, t.grid, &t.po, &t.o, K);
  CUPID_ASSERT_OK(cupid_csr_duplicate(K, &M));
  cupid_csr_zero(M);
  CUPID_ASSERT_OK(cupid_arlequin_mass(t.beam, t.grid, &t.o, pd_mass, M, NULL));
  cupid_csr_matvec(M, v, f);
  double mt = 0.0;
  for (cupid_int d = 1; d < t.ndof; d += 3) mt += f[d];
  printf("Arlequin mass of the bar: %.10g (expected %.10g, rho A L = %g)\n", mt, expect, RHO);
  ASSERT_NEAR(mt, expect, 1e-12 * expect);
  /* lumped: the same total */
  memset(f, 0, sizeof *f * (size_t)t.ndof);
  CUPID_ASSERT_OK(cupid_arlequin_mass(t.beam, t.grid, &t.o, pd_mass, NULL, f));
  mt = 0.0;
  for (cupid_int d = 1; d < t.ndof; d += 3) mt += f[d];
  ASSERT_NEAR(mt, expect, 1e-12 * expect);
  cupid_free(&pd_mass);
  cupid_free(&v);
  cupid_free(&f);
  cupid_csr_destroy(&K);
  cupid_csr_destroy(&M);
  truss_free(&t);
}

static void static_case(double kappa) {
  truss t;
  truss_build(&t, kappa);
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_arlequin_assemble(t.beam, t.grid, t.op, &t.o, &K, NULL));
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(t.ndof, &bc));
  for (cupid_int i = 0; i < t.n_pd; i++) { /* 1D PD: x, z carry nothing */
    CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 3 * i, 0.0));
    CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 3 * i + 2, 0.0));
  }
  CUPID_ASSERT_OK(cupid_cuf_clamp_node(t.beam, 0, bc));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  double *f = NULL, *u = NULL, *r = NULL, F = 1e6;
  CUPID_ASSERT_OK(cupid_calloc((size_t)t.ndof, sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_calloc((size_t)t.ndof, sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_calloc((size_t)t.ndof, sizeof *r, "r", &r));
  f[3 * (t.n_pd - 1) + 1] = F; /* the PD end node */
  cupid_solve_info si;
  CUPID_ASSERT_OK(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, &si));
  cupid_csr_matvec(K, u, r);
  double reaction = 0.0;
  for (cupid_int d = 1; d < t.ndof; d += 3)
    if (bc->fixed[d]) reaction += r[d] - f[d];
  ASSERT_NEAR(reaction, -F, 1e-9 * F);
  double umax = 0.0;
  for (cupid_int bn = 0; bn < 40; bn++) {
    double y = cupid_cuf_beam_node_y(t.beam, bn), uy = u[3 * t.n_pd + 3 * bn + 1];
    double ex = F * y / E_MOD;
    if (y <= 0.4 + 1e-12) umax = fmax(umax, fabs(uy - ex));
  }
  double gap;
  CUPID_ASSERT_OK(cupid_arlequin_gap(t.beam, t.grid, &t.o, u, &gap));
  double tip = u[3 * (t.n_pd - 1) + 1], ytip = cupid_pd_grid_coords(t.grid)[3 * (t.n_pd - 1) + 1];
  printf("kappa %.0e: pivot ratio %.2e, max |u - Fy/EA| on [0, 0.4] = %.2e, gap %.2e, tip "
         "error %.3f%%\n",
         kappa, si.pivot_ratio, umax, gap, 100 * (tip - F * ytip / E_MOD) / (F * ytip / E_MOD));
  assert_true(umax <= 1e-9 * F * 0.4 / E_MOD);
  cupid_free(&f);
  cupid_free(&u);
  cupid_free(&r);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  truss_free(&t);
}

static void test_static(void **state) {
  (void)state;
  static_case(1e9);
  static_case(1e11);
  static_case(1e13);
}

/* A 4 x 4 bar (h = 1), TE1 rod (nu = 0) with 2-node B2 elements of length 1 and a 3D PD region
 * (delta = 1.5, nu = 0): one overlap (beam [0, 12], PD [8, 20], overlap [8, 12]) or two (beam
 * [0, 28], PD [8, 20], overlaps [8, 12] and [16, 20], the beam giving way on [12, 16]). End
 * load F at the free end (the PD end plane, or the beam's last node). Checks: K symmetric and
 * free of the three rigid translations (1e-12 of |K|: momentum conserved); the reaction
 * balances F (1e-9); every FE-only span carries exactly F: u_y = F y / (EA) + const there
 * (1e-9 of u(8)). */
/* The kept assembly (crack growth): its first K is cupid_arlequin_assemble()'s to the bit, and
 * after bonds break a K assembled again is a fresh assembly's to the bit, pattern and values
 * (a run resumed from a checkpoint assembles afresh: it must meet the same K). */
static void check_kept_assembly(cupid_cuf_beam beam, cupid_pd_grid grid, cupid_pd_operator op,
                                const cupid_arlequin_options *o, const cupid_csr_t *K) {
  cupid_arlequin_assembly A = NULL;
  cupid_csr K1 = NULL, K2 = NULL, K3 = NULL;
  CUPID_ASSERT_OK(cupid_arlequin_assembly_create(beam, grid, op, o, &A, &K1, NULL));
  const cupid_csr_t *pairs[2][2] = {{K1, K}, {NULL, NULL}};
  /* a crack across the whole section through the PD core */
  cupid_pd_precrack crack = {.normal = 1, .at = 14.0, .lo = {-1, 0, -1}, .hi = {5, 0, 5}};
  cupid_int removed = 0;
  CUPID_ASSERT_OK(cupid_pd_operator_precrack(op, &crack, &removed));
  assert_true(removed > 0);
  CUPID_ASSERT_OK(cupid_arlequin_assembly_matrix(A, op, &K2));
  CUPID_ASSERT_OK(cupid_arlequin_assemble(beam, grid, op, o, &K3, NULL));
  pairs[1][0] = K2, pairs[1][1] = K3;
  for (int k = 0; k < 2; k++) {
    const cupid_csr_t *X = pairs[k][0], *Y = pairs[k][1];
    const cupid_int nnzb = Y->rowptr[Y->nrows];
    assert_int_equal(X->nrows, Y->nrows);
    assert_memory_equal(X->rowptr, Y->rowptr, ((size_t)Y->nrows + 1) * sizeof *Y->rowptr);
    assert_memory_equal(X->col, Y->col, (size_t)nnzb * sizeof *Y->col);
    assert_memory_equal(X->val, Y->val, 9 * (size_t)nnzb * sizeof *Y->val);
  }
  assert_true(K3->rowptr[K3->nrows] < K->rowptr[K->nrows]); /* pairs with no bond left */
  printf("kept assembly: %lld bonds cut; K assembled again = a fresh K to the bit (%lld blocks "
         "against %lld before)\n",
         (long long)removed, (long long)K3->rowptr[K3->nrows], (long long)K->rowptr[K->nrows]);
  cupid_csr_destroy(&K1);
  cupid_csr_destroy(&K2);
  cupid_csr_destroy(&K3);
  cupid_arlequin_assembly_destroy(&A);
}

static void case_3d(cupid_pd_model_kind model, int two) {
  tb_beam tb;
  tb_init(&tb, 1000.0, 0.0);
  tb_te(&tb, 1);
  tb_rect(&tb, 0, 4, 1, 0, 4, 1, -1);
  const double L = two ? 28.0 : 12.0;
  tb_axis(&tb, 0.0, L, (int)L, 2);
  cupid_cuf_beam beam = tb_create(&tb);
  cupid_box region = {.lo = {0, 8, 0}, .hi = {4, 20, 4}, .has = {1, 1, 1}};
  int rmat = 0;
  cupid_pd_grid grid = NULL;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &region, &rmat, &grid));
  cupid_pd_material mat = {.E = 1000.0, .nu = model == CUPID_PD_BOND ? 0.25 : 0.0};
  cupid_pd_operator_options po = {.horizon = 1.5, .model = model,
                                  .influence = CUPID_INFLUENCE_CONSTANT,
                                  .partial_volume = CUPID_PARTIAL_NONE, .materials = &mat,
                                  .n_materials = 1};
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(grid, &po, &op));
  if (two) {
    cupid_box give = {.lo = {0, 12, 0}, .hi = {0, 16, 0}, .has = {0, 1, 0}};
    CUPID_ASSERT_OK(cupid_coupling_deactivate(beam, 1, &give));
  }
  cupid_int n_pd = cupid_pd_grid_num_nodes(grid), ndof, nbn = (cupid_int)L + 1; /* B2: 2-node */
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(beam, 3 * n_pd));
  ndof = 3 * n_pd + cupid_cuf_num_dofs(beam);
  cupid_arlequin_options o = {
      .weight = {.lo = 8, .hi = 12, .fe_below = 1, .kind = CUPID_WEIGHT_SMOOTH}, .penalty = 1e5};
  if (two)
    o.n_overlaps = 2,
    o.second = (cupid_arlequin_weight){.lo = 16, .hi = 20, .fe_below = 0, .kind = CUPID_WEIGHT_SMOOTH};
  cupid_csr K = NULL;
  cupid_arlequin_info info;
  CUPID_ASSERT_OK(cupid_arlequin_assemble(beam, grid, op, &o, &K, &info));
  assert_int_equal(info.n_tied, (two ? 2 : 1) * 4 * 4 * 4);
  assert_int_equal(info.components, 3);
  assert_true(cupid_csr_asymmetry(K) <= 1e-14);
  double *v = NULL, *f = NULL, *u = NULL, *r = NULL, s = max_abs(K);
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *v, "v", &v));
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *r, "r", &r));
  for (int k = 0; k < 3; k++) { /* rigid translations: PD 1, TE1 constant term 1 */
    memset(v, 0, sizeof *v * (size_t)ndof);
    for (cupid_int i = 0; i < n_pd; i++) v[3 * i + k] = 1.0;
    for (cupid_int bn = 0; bn < nbn; bn++) v[cupid_cuf_dof(beam, 0, bn, k)] = 1.0;
    cupid_csr_matvec(K, v, r);
    double fm = 0.0;
    for (cupid_int d = 0; d < ndof; d++) fm = fmax(fm, fabs(r[d]));
    assert_true(fm <= 1e-12 * s);
  }
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(ndof, &bc));
  CUPID_ASSERT_OK(cupid_cuf_clamp_node(beam, 0, bc));
  for (cupid_int bn = 0; bn < nbn; bn++) /* beam nodes where the beam gave way */
    for (int tau = 0; tau < 3; tau++)
      if (!cupid_cuf_node_used(beam, tau, bn))
        for (int k = 0; k < 3; k++)
          CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, cupid_cuf_dof(beam, tau, bn, k), 0.0));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  const double *x = cupid_pd_grid_coords(grid);
  double F = 16.0, EA = 1000.0 * 16.0;
  if (two)
    f[cupid_cuf_dof(beam, 0, nbn - 1, 1)] = F; /* TE1 constant term of the end node */
  else
    for (cupid_int i = 0; i < n_pd; i++)
      if (x[3 * i + 1] > 19.0) f[3 * i + 1] = F / 16.0; /* the end plane y = 19.5 */
  cupid_solve_info si;
  CUPID_ASSERT_OK(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, &si));
  cupid_csr_matvec(K, u, r);
  double reaction = 0.0;
  for (cupid_int d = 1; d < ndof; d += 3)
    if (bc->fixed[d]) reaction += r[d] - f[d];
  ASSERT_NEAR(reaction, -F, 1e-9 * F);
  double err = 0.0, ex8 = F * 8.0 / EA;
  for (cupid_int bn = 0; bn <= 8; bn++) { /* [0, 8] */
    double y = cupid_cuf_beam_node_y(beam, bn), uy = u[cupid_cuf_dof(beam, 0, bn, 1)];
    err = fmax(err, fabs(uy - F * y / EA));
  }
  if (two) { /* [20, 28]: the same strain */
    cupid_int b20 = 20;
    double u20 = u[cupid_cuf_dof(beam, 0, b20, 1)];
    for (cupid_int bn = b20; bn < nbn; bn++) {
      double y = cupid_cuf_beam_node_y(beam, bn), uy = u[cupid_cuf_dof(beam, 0, bn, 1)];
      err = fmax(err, fabs(uy - u20 - F * (y - 20.0) / EA));
    }
  }
  double gap;
  CUPID_ASSERT_OK(cupid_arlequin_gap(beam, grid, &o, u, &gap));
  printf("3D %s, %d overlap%s: max FE-only error vs F/(EA) %.2e (u(8) = %.3e), gap %.2e, "
         "pivot ratio %.2e\n",
         model == CUPID_PD_LPS ? "LPS" : "bond-based", two ? 2 : 1, two ? "s" : "", err, ex8, gap,
         si.pivot_ratio);
  assert_true(err <= 1e-9 * ex8);
  cupid_free(&v);
  cupid_free(&f);
  cupid_free(&u);
  cupid_free(&r);
  cupid_dirichlet_destroy(&bc);
  if (two) check_kept_assembly(beam, grid, op, &o, K); /* last: it cuts bonds of op */
  cupid_csr_destroy(&K);
  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&grid);
  cupid_cuf_beam_destroy(&beam);
}

static void test_3d(void **state) {
  (void)state;
  case_3d(CUPID_PD_BOND, 0);
  case_3d(CUPID_PD_LPS, 0);
  case_3d(CUPID_PD_LPS, 1);
  case_3d(CUPID_PD_BOND, 1);
}

/* A general layout: a region over part of the section, with overlaps normal and parallel to
 * the axis. 8 x 8 bar, LE L4 section (x breakpoints 0 2 4 6 8, z 0 4 8), 12 B2 elements on
 * [0, 24]; PD region x [0, 4], y [8, 16], z [0, 8] (h = 1, delta = 1.5, nu = 0), overlaps
 * y [8, 10], y [14, 16] and x [2, 4] (the face x = 4 meets the beam beside the region; x = 0
 * and z = 0, 8 are free surfaces); the core x [0, 2], y [10, 14] gives way. Checks:
 *  - K symmetric (1e-14) and free of the three rigid translations (1e-12 of |K|);
 *  - the weights: the PD weight of each node is the product of its ramps (computed here);
 *    the weighted mass of a translation (consistent and lumped) is
 *    rho (V_beam - int w dV) + sum_i w_i rho V, with int w dV = 3 x 6 x 8 = 144 for the
 *    linear (LPS case) and smooth (bond-based case) ramps (both ramp integrals are W/2): the
 *    section-weighted quadrature of the beam is exact (1e-12 relative);
 *  - the matrix-free operator (check_operator());
 *  - end traction F at y = 24, clamp at y = 0: the reaction balances F (1e-9), and the gap
 *    between the tied PD nodes and the beam is small against u (< 1e-3 of max |u|). */
static double ramp_w(double c, double lo, double hi, int fe_below, cupid_weight kind) {
  double s = fe_below ? (c - lo) / (hi - lo) : (hi - c) / (hi - lo);
  if (s <= 0) return 0.0;
  if (s >= 1) return 1.0;
  return kind == CUPID_WEIGHT_SMOOTH ? s * s * (3.0 - 2.0 * s) : s;
}

/* The grid split into z slabs (issue 6, test_slabs.h): each slab's owned PD rows and its
 * share of the FE rows (the last slab adds the weighted beam, each slab the penalty of its
 * owned tied nodes) against the whole operator and preconditioner. */
typedef struct {
  cupid_cuf_beam beam;
  const cupid_pd_operator_options *po;
  const cupid_arlequin_options *o;
} arl_slab_ctx;

static cupid_status arl_create(void *ctx, cupid_pd_grid g, void **op, cupid_csr *P) {
  const arl_slab_ctx *c = ctx;
  cupid_arlequin_operator A = NULL;
  CUPID_CALL(cupid_arlequin_operator_create(c->beam, g, c->po, c->o, &A, NULL));
  *op = A;
  return cupid_arlequin_preconditioner(A, 0.0, P);
}

static cupid_status arl_rows(void *op, const double *x, cupid_int d0, cupid_int d1, double *y) {
  return cupid_arlequin_operator_apply_rows(op, x, d0, d1, y);
}

static void arl_destroy(void *op) {
  cupid_arlequin_operator A = op;
  cupid_arlequin_operator_destroy(&A);
}

static void check_slabs(cupid_cuf_beam beam, const cupid_box *box, const cupid_pd_operator_options *po,
                        const cupid_arlequin_options *o, int parts) {
  int rmat = 0, halo = 0;
  CUPID_ASSERT_OK(cupid_pd_operator_halo_layers(po, 1.0, &halo));
  arl_slab_ctx ctx = {.beam = beam, .po = po, .o = o};
  const slab_operator so = {.create = arl_create, .apply_rows = arl_rows, .destroy = arl_destroy,
                            .ctx = &ctx};
  slab_check("Arlequin", &so, beam, 1, box, &rmat, halo, parts);
}

static void case_partial(cupid_pd_model_kind model) {
  const double rho = 2.0, Eb = 1000.0;
  tb_beam tb;
  tb_init(&tb, Eb, 0.0);
  tb.mat[0].density = rho;
  tb.mat[0].has_density = 1;
  tb_le(&tb, 4);
  tb_rect(&tb, 0, 8, 4, 0, 8, 2, -1);
  tb_axis(&tb, 0.0, 24.0, 12, 2);
  cupid_cuf_beam beam = tb_create(&tb);
  cupid_weight kind = model == CUPID_PD_LPS ? CUPID_WEIGHT_LINEAR : CUPID_WEIGHT_SMOOTH;
  cupid_arlequin_region R = {.box = {.lo = {0, 8, 0}, .hi = {4, 16, 8}, .has = {1, 1, 1}}, .n_ramps = 3};
  R.ramps[0] = (cupid_arlequin_ramp){1, {.lo = 8, .hi = 10, .fe_below = 1, .kind = kind}};
  R.ramps[1] = (cupid_arlequin_ramp){1, {.lo = 14, .hi = 16, .fe_below = 0, .kind = kind}};
  R.ramps[2] = (cupid_arlequin_ramp){0, {.lo = 2, .hi = 4, .fe_below = 0, .kind = kind}};
  int rmat = 0;
  cupid_pd_grid grid = NULL;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &R.box, &rmat, &grid));
  cupid_pd_material mat = {.E = Eb, .nu = model == CUPID_PD_BOND ? 0.25 : 0.0};
  cupid_pd_operator_options po = {.horizon = 1.5, .model = model,
                                  .influence = CUPID_INFLUENCE_CONSTANT,
                                  .partial_volume = CUPID_PARTIAL_NONE, .materials = &mat,
                                  .n_materials = 1};
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(grid, &po, &op));
  cupid_box core = {.lo = {0, 10, 0}, .hi = {2, 14, 8}, .has = {1, 1, 1}};
  CUPID_ASSERT_OK(cupid_coupling_deactivate(beam, 1, &core));
  cupid_int n_pd = cupid_pd_grid_num_nodes(grid), nbn = 13, ndof;
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(beam, 3 * n_pd));
  ndof = 3 * n_pd + cupid_cuf_num_dofs(beam);
  cupid_cuf_info fi;
  cupid_cuf_get_info(beam, &fi);
  cupid_arlequin_options o = {.penalty = 1e5, .n_regions = 1, .regions = &R}; /* 100 E h */
  const double corner[3] = {3, 9, 4}, beside[3] = {6, 12, 4}, inner[3] = {1, 12, 4};
  double wc = ramp_w(9, 8, 10, 1, kind) * ramp_w(3, 2, 4, 0, kind); /* two ramps cross */
  ASSERT_NEAR(cupid_arlequin_alpha_at(&o, corner), 1.0 - wc, 1e-15);
  ASSERT_NEAR(cupid_arlequin_alpha_at(&o, beside), 1.0, 0);
  ASSERT_NEAR(cupid_arlequin_alpha_at(&o, inner), 0.0, 0);
  cupid_csr K = NULL, M = NULL;
  cupid_arlequin_info info;
  CUPID_ASSERT_OK(cupid_arlequin_assemble(beam, grid, op, &o, &K, &info));
  const double *x = cupid_pd_grid_coords(grid);
  cupid_int tied = 0;
  for (cupid_int i = 0; i < n_pd; i++) {
    const double *p = x + 3 * i;
    tied += p[1] <= 10 || p[1] >= 14 || p[0] >= 2;
  }
  assert_int_equal(info.n_tied, tied);
  assert_true(cupid_csr_asymmetry(K) <= 1e-14);
  double *v = NULL, *r = NULL, *f = NULL, *u = NULL, *d = NULL, *pm = NULL, s = max_abs(K);
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *v, "v", &v));
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *r, "r", &r));
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *d, "d", &d));
  CUPID_ASSERT_OK(cupid_calloc((size_t)n_pd, sizeof *pm, "pm", &pm));
  double V = cupid_pd_grid_cell_volume(grid), pd_expect = 0.0;
  for (cupid_int i = 0; i < n_pd; i++) {
    const double *p = x + 3 * i;
    pm[i] = rho * V;
    pd_expect += pm[i] * ramp_w(p[1], 8, 10, 1, kind) * ramp_w(p[1], 14, 16, 0, kind) *
                 ramp_w(p[0], 2, 4, 0, kind);
  }
  double expect = rho * (64.0 * 24.0 - 144.0) + pd_expect;
  for (int k = 0; k < 3; k++) { /* translations: every PD node and LE node moves by 1 */
    memset(v, 0, sizeof *v * (size_t)ndof);
    for (cupid_int i = 0; i < n_pd; i++) v[3 * i + k] = 1.0;
    for (cupid_int bn = 0; bn < nbn; bn++)
      for (int tau = 0; tau < fi.M; tau++) v[cupid_cuf_dof(beam, tau, bn, k)] = 1.0;
    cupid_csr_matvec(K, v, r);
    double fm = 0.0;
    for (cupid_int q = 0; q < ndof; q++) fm = fmax(fm, fabs(r[q]));
    assert_true(fm <= 1e-12 * s);
  }
  check_operator(beam, grid, &po, &o, K);
  for (int parts = 2; parts <= 3; parts++) check_slabs(beam, &R.box, &po, &o, parts);
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(beam, 3 * n_pd));
  CUPID_ASSERT_OK(cupid_csr_duplicate(K, &M));
  cupid_csr_zero(M);
  CUPID_ASSERT_OK(cupid_arlequin_mass(beam, grid, &o, pm, M, NULL));
  CUPID_ASSERT_OK(cupid_arlequin_mass(beam, grid, &o, pm, NULL, d));
  cupid_csr_matvec(M, v, r); /* v: the z translation */
  double mc = 0.0, ml = 0.0;
  for (cupid_int q = 2; q < ndof; q += 3) mc += r[q], ml += d[q];
  printf("partial region (%s): weighted mass of a translation %.12g (consistent) %.12g "
         "(lumped), expected %.12g\n",
         model == CUPID_PD_LPS ? "LPS" : "bond-based", mc, ml, expect);
  ASSERT_NEAR(mc, expect, 1e-12 * expect);
  ASSERT_NEAR(ml, expect, 1e-12 * expect);
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(ndof, &bc));
  CUPID_ASSERT_OK(cupid_cuf_clamp_node(beam, 0, bc));
  for (cupid_int bn = 0; bn < nbn; bn++) /* FE nodes where the beam gave way */
    for (int tau = 0; tau < fi.M; tau++)
      if (!cupid_cuf_node_used(beam, tau, bn))
        for (int k = 0; k < 3; k++)
          CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, cupid_cuf_dof(beam, tau, bn, k), 0.0));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  double F = 64.0;
  for (int tau = 0; tau < fi.M; tau++) f[cupid_cuf_dof(beam, tau, nbn - 1, 1)] = F / fi.M;
  cupid_solve_info si;
  CUPID_ASSERT_OK(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, &si));
  cupid_csr_matvec(K, u, r);
  double reaction = 0.0, umax = 0.0, gap;
  for (cupid_int q = 1; q < ndof; q += 3)
    if (bc->fixed[q]) reaction += r[q] - f[q];
  for (cupid_int q = 0; q < ndof; q++) umax = fmax(umax, fabs(u[q]));
  CUPID_ASSERT_OK(cupid_arlequin_gap(beam, grid, &o, u, &gap));
  printf("partial region (%s): %lld tied nodes, reaction %.12g of F = %g, gap %.2e of max |u|\n",
         model == CUPID_PD_LPS ? "LPS" : "bond-based", (long long)info.n_tied, -reaction, F,
         gap / umax);
  ASSERT_NEAR(reaction, -F, 1e-9 * F);
  assert_true(gap <= 1e-3 * umax);
  cupid_free(&v);
  cupid_free(&r);
  cupid_free(&f);
  cupid_free(&u);
  cupid_free(&d);
  cupid_free(&pm);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  cupid_csr_destroy(&M);
  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&grid);
  cupid_cuf_beam_destroy(&beam);
}

static void test_partial(void **state) {
  (void)state;
  case_partial(CUPID_PD_LPS);
  case_partial(CUPID_PD_BOND);
}

/* The node-weighted PD stiffness (cupid_pd_operator_assemble_weighted) on an LPS block with
 * the surface correction: w = 1 gives K (bit for bit: the same arithmetic), K(w) is linear in
 * w (K(a + b) = K(a) + K(b) to 1e-13 of |K|), symmetric and free of translations for any
 * w >= 0, and the operator is left as it was (K assembled again is bit-identical). For
 * bond-based with one material, block ij of K(w) is (w_i + w_j)/2 times that of K (1e-13). */
static void check_weighted(cupid_pd_model_kind model) {
  cupid_box region = {.lo = {0, 0, 0}, .hi = {5, 6, 5}, .has = {1, 1, 1}};
  int rmat = 0;
  cupid_pd_grid grid = NULL;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &region, &rmat, &grid));
  cupid_pd_material mat = {.E = 1000.0, .nu = 0.3};
  cupid_pd_operator_options po = {.horizon = 2.0, .model = model,
                                  .influence = CUPID_INFLUENCE_GAUSSIAN,
                                  .partial_volume = CUPID_PARTIAL_PDLAMMPS, .materials = &mat,
                                  .n_materials = 1,
                                  .surface_correction = model == CUPID_PD_LPS ? CUPID_SURFACE_ENERGY
                                                                              : CUPID_SURFACE_NONE};
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(grid, &po, &op));
  cupid_int n = cupid_pd_grid_num_nodes(grid);
  double *one = NULL, *a = NULL, *b = NULL, *ab = NULL;
  CUPID_ASSERT_OK(cupid_malloc((size_t)n, sizeof *one, "w", &one));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n, sizeof *a, "w", &a));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n, sizeof *b, "w", &b));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n, sizeof *ab, "w", &ab));
  uint64_t seed = 5;
  for (cupid_int i = 0; i < n; i++) {
    one[i] = 1.0;
    a[i] = fabs(cupid_test_random(&seed));
    b[i] = i % 3 == 0 ? 0.0 : fabs(cupid_test_random(&seed)); /* zero weights too */
    ab[i] = a[i] + b[i];
  }
  cupid_csr K = NULL, K1 = NULL, Ka = NULL, Kb = NULL, Kab = NULL, K2 = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(op, &K));
  CUPID_ASSERT_OK(cupid_pd_operator_assemble_weighted(op, one, &K1));
  CUPID_ASSERT_OK(cupid_pd_operator_assemble_weighted(op, a, &Ka));
  CUPID_ASSERT_OK(cupid_pd_operator_assemble_weighted(op, b, &Kb));
  CUPID_ASSERT_OK(cupid_pd_operator_assemble_weighted(op, ab, &Kab));
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(op, &K2));
  double s = max_abs(K);
  assert_true(diff_scaled(K1, K, 1.0) == 0.0);
  assert_true(diff_scaled(K2, K, 1.0) == 0.0);
  double lin = 0.0;
  for (cupid_int r = 0; r < n; r++)
    for (cupid_int q = Kab->rowptr[r]; q < Kab->rowptr[r + 1]; q++) {
      const double *pa = cupid_csr_find(Ka, r, Kab->col[q]), *pb = cupid_csr_find(Kb, r, Kab->col[q]);
      for (int e = 0; e < 9; e++)
        lin = fmax(lin, fabs(Kab->val[9 * q + e] - (pa ? pa[e] : 0) - (pb ? pb[e] : 0)));
    }
  assert_true(lin <= 1e-13 * s);
  assert_true(cupid_csr_asymmetry(Ka) <= 1e-14);
  assert_true(cupid_csr_asymmetry(Kb) <= 1e-14);
  double *v = NULL, *r = NULL;
  CUPID_ASSERT_OK(cupid_calloc(3 * (size_t)n, sizeof *v, "v", &v));
  CUPID_ASSERT_OK(cupid_calloc(3 * (size_t)n, sizeof *r, "r", &r));
  for (int k = 0; k < 3; k++) {
    for (cupid_int d = 0; d < 3 * n; d++) v[d] = d % 3 == k;
    cupid_csr_matvec(Kb, v, r);
    for (cupid_int d = 0; d < 3 * n; d++) assert_true(fabs(r[d]) <= 1e-12 * s);
  }
  if (model == CUPID_PD_BOND) {
    double e = 0.0;
    for (cupid_int i = 0; i < n; i++)
      for (cupid_int q = K->rowptr[i]; q < K->rowptr[i + 1]; q++) {
        cupid_int j = K->col[q];
        if (j == i) continue;
        const double *w = cupid_csr_find(Ka, i, j);
        for (int c = 0; c < 9; c++) e = fmax(e, fabs(w[c] - 0.5 * (a[i] + a[j]) * K->val[9 * q + c]));
      }
    assert_true(e <= 1e-13 * s);
  }
  printf("weighted PD stiffness (%s): linearity %.1e of |K|\n",
         model == CUPID_PD_LPS ? "LPS, surface correction" : "bond-based", lin / s);
  /* a negative weight is refused */
  a[3] = -0.5;
  cupid_csr Kbad = NULL;
  assert_int_equal(cupid_pd_operator_assemble_weighted(op, a, &Kbad), CUPID_ERR_ARGUMENT);
  assert_null(Kbad);
  cupid_csr *all[] = {&K, &K1, &Ka, &Kb, &Kab, &K2};
  for (int k = 0; k < 6; k++) cupid_csr_destroy(all[k]);
  cupid_free(&one);
  cupid_free(&a);
  cupid_free(&b);
  cupid_free(&ab);
  cupid_free(&v);
  cupid_free(&r);
  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&grid);
}

static void test_weighted_pd(void **state) {
  (void)state;
  check_weighted(CUPID_PD_LPS);
  check_weighted(CUPID_PD_BOND);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_alpha),
      cmocka_unit_test(test_weighted_cuf),
      cmocka_unit_test(test_coupled_matrix),
      cmocka_unit_test(test_static),
      cmocka_unit_test(test_3d),
      cmocka_unit_test(test_partial),
      cmocka_unit_test(test_weighted_pd),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
