/*
 * Unit tests of the direct solvers (src/solvers/direct.c): CHOLMOD (SPD) and UMFPACK
 * (general) on grid matrices with known solutions, Dirichlet DOFs, singular and indefinite
 * matrices, reactions, and one larger problem for timing.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

/* A symmetric positive definite 3x3 block (eigenvalues about 0.9 to 3.5: mild anisotropy). */
static const double B_SPD[9] = {2.0, 0.5, 0.2, 0.5, 3.0, -0.4, 0.2, -0.4, 1.5};
/* A non-symmetric block with eigenvalues of positive real part (diagonally dominant). */
static const double B_GEN[9] = {2.0, 0.7, -0.3, 0.1, 3.0, 0.6, 0.4, -0.2, 1.5};
static const double ONE[1] = {1.0};

typedef struct {
  int nx, ny, nz;
  int bs;
  const double *B;   /* bs x bs block multiplying every stencil weight */
  double shift;      /* added to every diagonal stencil weight (0: singular without BCs) */
  double convection; /* upwind x-convection weight (non-symmetric; 0: symmetric) */
  int cut;           /* > 0: no edges between ix = cut-1 and ix = cut (two components) */
} grid_spec;

static cupid_int node_of(const grid_spec *g, int ix, int iy, int iz) {
  return ix + (cupid_int)g->nx * (iy + (cupid_int)g->ny * iz);
}

/* Edge weight in [0.5, 1.5], a symmetric function of the two nodes (deterministic). */
static double edge_weight(cupid_int a, cupid_int b) {
  uint64_t s = (uint64_t)(a < b ? a : b) * 1000003u + (uint64_t)(a < b ? b : a);
  return 1.0 + 0.5 * cupid_test_random(&s);
}

/*
 * K = (L + shift I + convection D) (x) B on an nx*ny*nz grid: L the weighted 7-point graph
 * Laplacian (zero row sums), D the upwind difference u_i - u_{i-x} on nodes with an x
 * neighbour behind them (also zero row sums), so shift = 0 makes K singular.
 */
static cupid_csr grid_matrix(const grid_spec *g) {
  const cupid_int n = (cupid_int)g->nx * g->ny * g->nz;
  const int bs = g->bs, bs2 = bs * bs;
  cupid_int *rowptr = malloc((size_t)(n + 1) * sizeof *rowptr);
  cupid_int *col = malloc((size_t)(7 * n) * sizeof *col);
  double *w = malloc((size_t)(7 * n) * sizeof *w);
  assert_non_null(rowptr);
  assert_non_null(col);
  assert_non_null(w);
  rowptr[0] = 0;
  cupid_int nnz = 0;
  for (int iz = 0; iz < g->nz; iz++)
    for (int iy = 0; iy < g->ny; iy++)
      for (int ix = 0; ix < g->nx; ix++) {
        const cupid_int i = node_of(g, ix, iy, iz);
        /* neighbours in increasing index order: -z, -y, -x, self, +x, +y, +z */
        const int d[7][3] = {{0, 0, -1}, {0, -1, 0}, {-1, 0, 0}, {0, 0, 0},
                             {1, 0, 0},  {0, 1, 0},  {0, 0, 1}};
        cupid_int self = -1;
        double diag = g->shift;
        for (int k = 0; k < 7; k++) {
          const int jx = ix + d[k][0], jy = iy + d[k][1], jz = iz + d[k][2];
          if (jx < 0 || jy < 0 || jz < 0 || jx >= g->nx || jy >= g->ny || jz >= g->nz) continue;
          if (k == 3) {
            self = nnz;
            col[nnz++] = i;
            continue;
          }
          if (g->cut > 0 && ((ix == g->cut - 1 && jx == g->cut) || (ix == g->cut && jx == g->cut - 1)))
            continue;
          const cupid_int j = node_of(g, jx, jy, jz);
          double v = -edge_weight(i, j);
          diag -= v;
          if (k == 2 && g->convection != 0.0) { /* upwind: c (u_i - u_{i-x}) */
            v -= g->convection;
            diag += g->convection;
          }
          col[nnz] = j;
          w[nnz++] = v;
        }
        w[self] = diag;
        rowptr[i + 1] = nnz;
      }
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_csr_create(n, n, bs, rowptr, col, &K));
  for (cupid_int p = 0; p < nnz; p++)
    for (int e = 0; e < bs2; e++) K->val[p * bs2 + e] = w[p] * g->B[e];
  free(rowptr);
  free(col);
  free(w);
  return K;
}

static double rel_error(cupid_int n, const double *u, const double *ref) {
  double num = 0.0, den = 0.0;
  for (cupid_int k = 0; k < n; k++) {
    num += (u[k] - ref[k]) * (u[k] - ref[k]);
    den += ref[k] * ref[k];
  }
  return den > 0.0 ? sqrt(num / den) : sqrt(num);
}

/* Fix every DOF of the nodes with ix = 0 to u_exact there, and every 7th DOF elsewhere. */
static cupid_dirichlet face_bc(const grid_spec *g, const double *uexact, int scattered) {
  const cupid_int n = (cupid_int)g->nx * g->ny * g->nz * g->bs;
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
  for (cupid_int dof = 0; dof < n; dof++) {
    const cupid_int node = dof / g->bs;
    if (node % g->nx == 0 || (scattered && dof % 7 == 3))
      CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, dof, uexact[dof]));
  }
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  return bc;
}

/*
 * Solve K u = K u_exact for a random u_exact, the fixed DOFs prescribed to u_exact.
 * Tolerance 1e-10 on the relative error: the forward error is bounded by cond(K_ff) times
 * the backward error (~1e-16 after refinement); cond(K_ff) of these grids (at most 12 nodes
 * per side, weights in [0.5, 1.5], cond(B) < 5) is below ~1e4, so the error is ~1e-12. A wrong
 * reduction (sign of K_fc u_c, free-DOF mapping, triangle) gives O(1) errors.
 */
static void check_known_solution(const grid_spec *g, cupid_matrix_kind kind, int with_bc,
                                 uint64_t seed) {
  cupid_csr K = grid_matrix(g);
  const cupid_int n = K->nrows * K->bs;
  double *ue = malloc((size_t)n * sizeof *ue), *f = malloc((size_t)n * sizeof *f);
  double *u = malloc((size_t)n * sizeof *u);
  for (cupid_int k = 0; k < n; k++) ue[k] = cupid_test_random(&seed);
  cupid_csr_matvec(K, ue, f);
  cupid_dirichlet bc = with_bc ? face_bc(g, ue, 1) : NULL;
  cupid_solve_info info;
  CUPID_ASSERT_OK(cupid_direct_solve(K, kind, f, bc, u, &info));
  const double err = rel_error(n, u, ue);
  print_message("  %s n=%lld nnz=%lld nnz(factor)=%.0f residual=%.2e error=%.2e pivots=%.2e\n",
                info.method, (long long)info.n, (long long)info.nnz_matrix, info.nnz_factor,
                info.residual, err, info.pivot_ratio);
  assert_true(err < 1e-10);
  assert_true(info.residual < 1e-12); /* after at most one refinement step: ~1e-16 expected */
  assert_int_equal(info.failed_dof, -1);
  assert_string_equal(info.method, kind == CUPID_MATRIX_SPD ? "cholmod" : "umfpack");
  assert_int_equal(info.n, with_bc ? bc->n_free : n);
  assert_true(info.nnz_factor >= (double)info.n);
  if (bc) /* prescribed values exactly */
    for (cupid_int k = 0; k < n; k++)
      if (bc->fixed[k]) assert_true(u[k] == ue[k]);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  free(ue);
  free(f);
  free(u);
}

static void test_spd_known_solution(void **state) {
  (void)state;
  const grid_spec shifted3 = {8, 7, 6, 3, B_SPD, 0.5, 0.0, 0};
  check_known_solution(&shifted3, CUPID_MATRIX_SPD, 0, 1);
  check_known_solution(&shifted3, CUPID_MATRIX_SPD, 1, 2);
  const grid_spec pure3 = {10, 6, 5, 3, B_SPD, 0.0, 0.0, 0}; /* singular without the BCs */
  check_known_solution(&pure3, CUPID_MATRIX_SPD, 1, 3);
  const grid_spec scalar1d = {40, 1, 1, 1, ONE, 0.0, 0.0, 0};
  check_known_solution(&scalar1d, CUPID_MATRIX_SPD, 1, 4);
  const grid_spec scalar3d = {12, 11, 10, 1, ONE, 0.0, 0.0, 0};
  check_known_solution(&scalar3d, CUPID_MATRIX_SPD, 1, 5);
}

static void test_general_known_solution(void **state) {
  (void)state;
  const grid_spec cd1 = {12, 10, 9, 1, ONE, 0.0, 3.0, 0}; /* convection-diffusion */
  check_known_solution(&cd1, CUPID_MATRIX_GENERAL, 1, 6);
  const grid_spec cd3 = {8, 6, 5, 3, B_GEN, 0.2, 2.0, 0};
  check_known_solution(&cd3, CUPID_MATRIX_GENERAL, 0, 7);
  check_known_solution(&cd3, CUPID_MATRIX_GENERAL, 1, 8);
  /* UMFPACK on a symmetric matrix gives the same answer as CHOLMOD */
  const grid_spec pure3 = {7, 6, 5, 3, B_SPD, 0.0, 0.0, 0};
  check_known_solution(&pure3, CUPID_MATRIX_GENERAL, 1, 9);
}

/* A singular K must fail with CUPID_ERR_NUMERIC and name a DOF; returns that DOF. */
static cupid_int check_singular(const grid_spec *g, cupid_matrix_kind kind, int fix_face) {
  cupid_csr K = grid_matrix(g);
  const cupid_int n = K->nrows * K->bs;
  double *f = malloc((size_t)n * sizeof *f), *u = malloc((size_t)n * sizeof *u);
  uint64_t seed = 77;
  for (cupid_int k = 0; k < n; k++) f[k] = cupid_test_random(&seed);
  double *zero = calloc((size_t)n, sizeof *zero);
  cupid_dirichlet bc = fix_face ? face_bc(g, zero, 0) : NULL;
  cupid_solve_info info;
  const cupid_status st = cupid_direct_solve(K, kind, f, bc, u, &info);
  print_message("  %s %dx%dx%d bs=%d: status %d, failed DOF %lld, pivots %.2e, residual %.2e, "
                "backward error %.2e: %s\n",
                info.method, g->nx, g->ny, g->nz, g->bs, (int)st, (long long)info.failed_dof,
                info.pivot_ratio, info.residual, info.backward_error, cupid_error_message());
  assert_int_equal(st, CUPID_ERR_NUMERIC);
  assert_true(info.failed_dof >= 0 && info.failed_dof < n);
  assert_true(bc == NULL || !bc->fixed[info.failed_dof]);
  assert_non_null(strstr(cupid_error_message(), "singular"));
  assert_non_null(strstr(cupid_error_message(), "node"));
  if (g->bs == 3) assert_non_null(strstr(cupid_error_message(), "component"));
  const cupid_int dof = info.failed_dof;
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  free(f);
  free(u);
  free(zero);
  return dof;
}

static void test_singular(void **state) {
  (void)state;
  const int sizes[][3] = {{2, 2, 2}, {6, 5, 4}, {12, 10, 9}, {20, 20, 20}};
  const int nsizes = getenv("CUPID_TEST_SMALL") ? 3 : 4; /* see test_size */
  for (int s = 0; s < nsizes; s++) {
    grid_spec g = {sizes[s][0], sizes[s][1], sizes[s][2], 3, B_SPD, 0.0, 0.0, 0};
    check_singular(&g, CUPID_MATRIX_SPD, 0);
    check_singular(&g, CUPID_MATRIX_GENERAL, 0);
    g.bs = 1;
    g.B = ONE;
    check_singular(&g, CUPID_MATRIX_SPD, 0);
    check_singular(&g, CUPID_MATRIX_GENERAL, 0);
    g.convection = 2.0;
    check_singular(&g, CUPID_MATRIX_GENERAL, 0);
  }
}

/* A component cut off from the supports: the failing DOF must lie in it (ix >= cut). */
static void test_floating_component(void **state) {
  (void)state;
  const grid_spec g3 = {9, 5, 4, 3, B_SPD, 0.0, 0.0, 5};
  cupid_int dof = check_singular(&g3, CUPID_MATRIX_SPD, 1);
  assert_true((dof / 3) % g3.nx >= g3.cut);
  dof = check_singular(&g3, CUPID_MATRIX_GENERAL, 1);
  assert_true((dof / 3) % g3.nx >= g3.cut);
  const grid_spec g1 = {12, 8, 7, 1, ONE, 0.0, 0.0, 4};
  dof = check_singular(&g1, CUPID_MATRIX_SPD, 1);
  assert_true(dof % g1.nx >= g1.cut);
  const grid_spec c1 = {12, 8, 7, 1, ONE, 0.0, 1.0, 4};
  dof = check_singular(&c1, CUPID_MATRIX_GENERAL, 1);
  assert_true(dof % c1.nx >= c1.cut);
}

/*
 * An indefinite matrix for CHOLMOD: an SPD matrix with one negative diagonal entry. Every
 * principal submatrix without that DOF is still positive definite, so LL' breaks down exactly
 * at that DOF whatever the ordering.
 */
static void test_indefinite(void **state) {
  (void)state;
  const grid_spec g = {7, 6, 5, 3, B_SPD, 0.3, 0.0, 0};
  const cupid_int bad = 3 * 101 + 1;
  cupid_csr K = grid_matrix(&g);
  const cupid_int n = K->nrows * 3;
  cupid_csr_find(K, bad / 3, bad / 3)[4] = -10.0; /* component y of node 101 */
  double *f = calloc((size_t)n, sizeof *f), *u = malloc((size_t)n * sizeof *u);
  f[0] = 1.0;
  cupid_solve_info info;
  assert_int_equal(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, NULL, u, &info), CUPID_ERR_NUMERIC);
  print_message("  %s\n", cupid_error_message());
  assert_int_equal(info.failed_dof, bad);
  assert_non_null(strstr(cupid_error_message(), "DOF 304 = node 101, component y"));
  /* the same DOF through the free-DOF numbering, with the face ix = 0 fixed */
  double *zero = calloc((size_t)n, sizeof *zero);
  cupid_dirichlet bc = face_bc(&g, zero, 0);
  assert_false(bc->fixed[bad]);
  assert_int_equal(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, &info), CUPID_ERR_NUMERIC);
  assert_int_equal(info.failed_dof, bad);
  /* UMFPACK pivots its way through an indefinite (non-singular) matrix */
  CUPID_ASSERT_OK(cupid_direct_solve(K, CUPID_MATRIX_GENERAL, f, bc, u, &info));
  assert_true(info.residual < 1e-12);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  free(f);
  free(u);
  free(zero);
}

/* CHOLMOD reads one triangle: a non-symmetric K declared SPD must fail the residual check. */
static void test_spd_not_symmetric(void **state) {
  (void)state;
  const grid_spec g = {6, 5, 4, 1, ONE, 0.2, 1.0, 0};
  cupid_csr K = grid_matrix(&g);
  const cupid_int n = K->nrows;
  double *f = malloc((size_t)n * sizeof *f), *u = malloc((size_t)n * sizeof *u);
  uint64_t seed = 4;
  for (cupid_int k = 0; k < n; k++) f[k] = cupid_test_random(&seed);
  cupid_solve_info info;
  assert_int_equal(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, NULL, u, &info), CUPID_ERR_NUMERIC);
  assert_non_null(strstr(cupid_error_message(), "not symmetric"));
  assert_true(info.residual > 1e-8);
  cupid_csr_destroy(&K);
  free(f);
  free(u);
}

/* Expect CUPID_ERR_NUMERIC naming @p what at @p dof ("DOF 37 = node 12, component y"). */
static void expect_non_finite(const cupid_csr_t *K, cupid_matrix_kind kind, const double *f,
                              const cupid_dirichlet_t *bc, const char *what, cupid_int dof) {
  const cupid_int n = K->nrows * K->bs;
  double *u = malloc((size_t)n * sizeof *u);
  cupid_solve_info info;
  const cupid_status st = cupid_direct_solve(K, kind, f, bc, u, &info);
  const char *msg = cupid_error_message();
  print_message("  %s: status %d, residual %.3g: %s\n", info.method, (int)st, info.residual, msg);
  assert_int_equal(st, CUPID_ERR_NUMERIC);
  assert_int_equal(info.failed_dof, -1); /* no factorisation broke down: the message names it */
  assert_non_null(strstr(msg, what));
  char where[64];
  snprintf(where, sizeof where, "DOF %lld = node %lld, component %c", (long long)dof,
           (long long)(dof / 3), "xyz"[dof % 3]);
  assert_non_null(strstr(msg, where));
  assert_null(strstr(msg, "singular or not positive definite"));
  assert_null(strstr(msg, "singular or ill-conditioned"));
  free(u);
}

/*
 * Non-finite numbers fail with their cause and DOF. A NaN load used to come back as a success
 * with residual 0 and NaN displacements (a NaN norm fails no comparison, and bnorm > 0 was
 * false), an infinite one as "the stiffness matrix is singular".
 */
static void test_non_finite(void **state) {
  (void)state;
  const grid_spec g = {5, 4, 3, 3, B_SPD, 0.5, 0.0, 0};
  cupid_csr K = grid_matrix(&g);
  const cupid_int n = K->nrows * 3;
  double *f = malloc((size_t)n * sizeof *f), *u = malloc((size_t)n * sizeof *u);
  uint64_t seed = 19;
  for (cupid_int k = 0; k < n; k++) f[k] = cupid_test_random(&seed);
  const double bad[] = {NAN, INFINITY, -INFINITY};
  for (int kind = 0; kind < 2; kind++)
    for (int b = 0; b < 3; b++) {
      const double keep = f[37];
      f[37] = bad[b];
      expect_non_finite(K, (cupid_matrix_kind)kind, f, NULL, "non-finite load vector entry", 37);
      f[37] = keep;
    }
  /* Prescribed displacements on node 0 (and a NaN load there: the reactions would be NaN). */
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
  for (int c = 0; c < 3; c++) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, c, 1e-3 * (c + 1)));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  f[1] = NAN;
  expect_non_finite(K, CUPID_MATRIX_SPD, f, bc, "non-finite load vector entry", 1);
  f[1] = 0.0;
  /* A NaN coupling node 1 (free) to node 0 (prescribed): in K_fc u_c, not in K_ff. */
  double *block = cupid_csr_find(K, 1, 0);
  assert_non_null(block);
  const double keep = block[0];
  block[0] = NAN;
  expect_non_finite(K, CUPID_MATRIX_SPD, f, bc, "non-finite right-hand side", 3);
  expect_non_finite(K, CUPID_MATRIX_GENERAL, f, bc, "non-finite right-hand side", 3);
  block[0] = keep;
  /* A NaN in K_ff (the diagonal of node 5, component y). */
  block = cupid_csr_find(K, 5, 5);
  const double diag = block[4];
  block[4] = NAN;
  expect_non_finite(K, CUPID_MATRIX_SPD, f, NULL, "non-finite stiffness matrix entry", 16);
  expect_non_finite(K, CUPID_MATRIX_GENERAL, f, NULL, "non-finite stiffness matrix entry", 16);
  block[4] = diag;
  /* Finite but overflowing: K scaled by 1e-20 and loads of 1e300 give |u| ~ 1e320. */
  for (cupid_int p = 0; p < K->rowptr[K->nrows] * 9; p++) K->val[p] *= 1e-20;
  for (cupid_int k = 0; k < n; k++) f[k] = 1e300;
  cupid_solve_info info;
  assert_int_equal(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, NULL, u, &info), CUPID_ERR_NUMERIC);
  print_message("  %s\n", cupid_error_message());
  assert_non_null(strstr(cupid_error_message(), "non-finite solution"));
  assert_null(strstr(cupid_error_message(), "singular or"));
  assert_int_equal(info.failed_dof, -1);
  /* The same system with finite numbers still solves. */
  for (cupid_int p = 0; p < K->rowptr[K->nrows] * 9; p++) K->val[p] *= 1e20;
  for (cupid_int k = 0; k < n; k++) f[k] = cupid_test_random(&seed);
  CUPID_ASSERT_OK(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, &info));
  assert_true(info.residual < 1e-12);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  free(f);
  free(u);
}

/* A random sparse SPD matrix (symmetric, strictly diagonally dominant) from triplets. */
static void test_random_spd(void **state) {
  (void)state;
  enum { N = 400, T = 3000 };
  uint64_t seed = 99;
  cupid_int *I = malloc((2 * T + N) * sizeof *I), *J = malloc((2 * T + N) * sizeof *J);
  double *V = malloc((2 * T + N) * sizeof *V), rowsum[N] = {0};
  cupid_int t = 0;
  for (int k = 0; k < T; k++) {
    const cupid_int a = (cupid_int)((cupid_test_random(&seed) + 1.0) * 0.5 * N);
    const cupid_int b = (cupid_int)((cupid_test_random(&seed) + 1.0) * 0.5 * N);
    const double v = cupid_test_random(&seed);
    I[t] = a, J[t] = b, V[t++] = v;
    I[t] = b, J[t] = a, V[t++] = v;
    rowsum[a] += fabs(v);
    rowsum[b] += fabs(v);
  }
  for (cupid_int k = 0; k < N; k++) I[t] = J[t] = k, V[t++] = 2.0 * rowsum[k] + 0.1;
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_csr_from_triplets(N, N, t, I, J, V, &K));
  assert_true(cupid_csr_asymmetry(K) < 1e-15); /* sums of equal values in different order */
  double ue[N], f[N], u[N];
  for (int k = 0; k < N; k++) ue[k] = cupid_test_random(&seed);
  cupid_csr_matvec(K, ue, f);
  cupid_solve_info info;
  for (int kind = 0; kind < 2; kind++) {
    CUPID_ASSERT_OK(cupid_direct_solve(K, (cupid_matrix_kind)kind, f, NULL, u, &info));
    /* diagonal dominance by a factor 2 bounds cond(K) by ~3 * max/min diagonal: error ~1e-15 */
    assert_true(rel_error(N, u, ue) < 1e-10);
    assert_true(info.residual < 1e-12);
  }
  cupid_csr_destroy(&K);
  free(I);
  free(J);
  free(V);
}

/* Add the 3 x 3 block M to block (i, j) of K (in its pattern). */
static void add_block(cupid_csr K, cupid_int i, cupid_int j, const double *M, double scale) {
  for (cupid_int q = K->rowptr[i]; q < K->rowptr[i + 1]; q++)
    if (K->col[q] == j) {
      for (int e = 0; e < 9; e++) K->val[9 * q + e] += scale * M[e];
      return;
    }
  fail_msg("block (%lld, %lld) is not in the pattern", (long long)i, (long long)j);
}

/* A bond-like term w w^T between nodes i and j (w random) added to K, and its downdate
 * column b (w at i, -w at j) into colptr / rows / vals. */
static void add_bond(cupid_csr K, cupid_int i, cupid_int j, int b, uint64_t *seed,
                     cupid_int *colptr, cupid_int *rows, double *vals) {
  double w[3], M[9];
  for (int a = 0; a < 3; a++) w[a] = cupid_test_random(seed);
  for (int a = 0; a < 3; a++)
    for (int c = 0; c < 3; c++) M[3 * a + c] = w[a] * w[c];
  add_block(K, i, i, M, 1.0), add_block(K, j, j, M, 1.0);
  add_block(K, i, j, M, -1.0), add_block(K, j, i, M, -1.0);
  colptr[b] = 6 * b;
  for (int a = 0; a < 3; a++) {
    rows[6 * b + a] = 3 * i + a, vals[6 * b + a] = w[a];
    rows[6 * b + 3 + a] = 3 * j + a, vals[6 * b + 3 + a] = -w[a];
  }
}

/*
 * cupid_direct_factor_downdate (growth's re-solves after broken bonds): the factor of
 * K = A + sum_b v_b v_b^T downdated by the v_b (bond terms: w at node i, -w at node j, some
 * on fixed DOFs, which are dropped) solves A u = f like a factor of A. Tolerance 1e-10 on the
 * relative error as test_random_spd: cond(A_ff) of this grid is below ~1e3 and a downdate is
 * backward stable; a wrong permutation or sign gives O(1). A downdate that leaves the matrix
 * indefinite is CUPID_ERR_NUMERIC; an LU factor cannot be downdated.
 */
static void test_factor_downdate(void **state) {
  (void)state;
  const grid_spec g = {6, 5, 4, 3, B_SPD, 0.05, 0.0, 0};
  cupid_csr A = grid_matrix(&g), K = grid_matrix(&g);
  const cupid_int nn = (cupid_int)g.nx * g.ny * g.nz, n = 3 * nn;
  enum { NB = 12 };
  cupid_int colptr[NB + 1], rows[6 * NB];
  double vals[6 * NB];
  uint64_t seed = 7;
  for (int b = 0; b < NB; b++) { /* a bond along +x from node i (ix 0 .. 4, some on the face) */
    const int ix = b % 5, iy = (b * 3) % g.ny, iz = (b * 7) % g.nz;
    add_bond(K, node_of(&g, ix, iy, iz), node_of(&g, ix + 1, iy, iz), b, &seed, colptr, rows, vals);
  }
  colptr[NB] = 6 * NB;
  double *ue = malloc((size_t)n * sizeof *ue), *f = malloc((size_t)n * sizeof *f);
  double *u = malloc((size_t)n * sizeof *u);
  assert_non_null(ue), assert_non_null(f), assert_non_null(u);
  for (cupid_int k = 0; k < n; k++) ue[k] = cupid_test_random(&seed);
  cupid_dirichlet bc = face_bc(&g, ue, 0);
  for (cupid_int k = 0; k < n; k++) ue[k] = bc->fixed[k] ? 0.0 : ue[k]; /* homogeneous */
  cupid_csr_matvec(A, ue, f);
  cupid_direct_factor F = NULL;
  CUPID_ASSERT_OK(cupid_direct_factor_create(K, bc, &F, NULL));
  CUPID_ASSERT_OK(cupid_direct_factor_solve(F, f, u));
  double e0 = 0.0;
  for (cupid_int k = 0; k < n; k++) u[k] = bc->fixed[k] ? 0.0 : u[k];
  e0 = rel_error(n, u, ue);
  assert_true(e0 > 1e-3); /* the bonds matter: K's solve is not A's */
  /* downdated in two calls (5 then 7 columns): as one */
  CUPID_ASSERT_OK(cupid_direct_factor_downdate(F, 5, colptr, rows, vals));
  cupid_int colptr2[NB - 5 + 1];
  for (int b = 0; b <= NB - 5; b++) colptr2[b] = colptr[5 + b] - colptr[5];
  CUPID_ASSERT_OK(cupid_direct_factor_downdate(F, NB - 5, colptr2, rows + colptr[5], vals + colptr[5]));
  CUPID_ASSERT_OK(cupid_direct_factor_solve(F, f, u));
  for (cupid_int k = 0; k < n; k++) u[k] = bc->fixed[k] ? 0.0 : u[k];
  assert_true(rel_error(n, u, ue) < 1e-10);
  /* a term larger than the matrix: indefinite */
  double big[6];
  for (int a = 0; a < 6; a++) big[a] = 100.0 * vals[6 + a];
  cupid_int one[2] = {0, 6};
  assert_int_equal(cupid_direct_factor_downdate(F, 1, one, rows + 6, big), CUPID_ERR_NUMERIC);
  cupid_error_clear();
  cupid_direct_factor_destroy(&F);
  /* LU: refused */
  CUPID_ASSERT_OK(cupid_direct_factor_create_kind(A, CUPID_MATRIX_GENERAL, bc, &F, NULL));
  assert_int_equal(cupid_direct_factor_downdate(F, 1, one, rows + 6, vals + 6), CUPID_ERR_ARGUMENT);
  cupid_error_clear();
  cupid_direct_factor_destroy(&F);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&A);
  cupid_csr_destroy(&K);
  free(ue), free(f), free(u);
}

/*
 * cupid_direct_factor_update (crack growth ties a node that completes a mechanism by weak
 * springs, src/problem/growth.c): the factor of A updated by bond terms and by springs of
 * stiffness k on one node's DOFs (columns sqrt(k) e_d) solves K u = f, K = A + the terms + the
 * springs, as a fresh factor of K would: to 1e-10 (test_factor_downdate's bound, for the same
 * reasons). A spring of 1e-8 of the diagonal on a node whose every other term was downdated
 * away (a mechanism) keeps the factor definite where the downdate alone is CUPID_ERR_NUMERIC.
 */
static void test_factor_update(void **state) {
  (void)state;
  const grid_spec g = {6, 5, 4, 3, B_SPD, 0.05, 0.0, 0};
  cupid_csr A = grid_matrix(&g), K = grid_matrix(&g);
  const cupid_int nn = (cupid_int)g.nx * g.ny * g.nz, n = 3 * nn;
  enum { NB = 6 };
  cupid_int colptr[NB + 4], rows[6 * NB + 3];
  double vals[6 * NB + 3];
  uint64_t seed = 11;
  for (int b = 0; b < NB; b++) {
    const int ix = b % 5, iy = (b * 2) % g.ny, iz = (b * 5) % g.nz;
    add_bond(K, node_of(&g, ix, iy, iz), node_of(&g, ix + 1, iy, iz), b, &seed, colptr, rows, vals);
  }
  const cupid_int t = node_of(&g, 3, 2, 1); /* the tied node */
  const double k = 0.37;
  for (int c = 0; c < 3; c++) {
    double *a = cupid_csr_find(K, t, t);
    assert_non_null(a);
    a[4 * c] += k;
    colptr[NB + c] = 6 * NB + c, rows[6 * NB + c] = 3 * t + c, vals[6 * NB + c] = sqrt(k);
  }
  colptr[NB + 3] = 6 * NB + 3;
  double *ue = malloc((size_t)n * sizeof *ue), *f = malloc((size_t)n * sizeof *f);
  double *u = malloc((size_t)n * sizeof *u);
  assert_non_null(ue), assert_non_null(f), assert_non_null(u);
  for (cupid_int d = 0; d < n; d++) ue[d] = cupid_test_random(&seed);
  cupid_dirichlet bc = face_bc(&g, ue, 0);
  for (cupid_int d = 0; d < n; d++) ue[d] = bc->fixed[d] ? 0.0 : ue[d];
  cupid_csr_matvec(K, ue, f);
  cupid_direct_factor F = NULL;
  CUPID_ASSERT_OK(cupid_direct_factor_create(A, bc, &F, NULL));
  CUPID_ASSERT_OK(cupid_direct_factor_solve(F, f, u));
  for (cupid_int d = 0; d < n; d++) u[d] = bc->fixed[d] ? 0.0 : u[d];
  assert_true(rel_error(n, u, ue) > 1e-3); /* the terms matter */
  CUPID_ASSERT_OK(cupid_direct_factor_update(F, NB + 3, colptr, rows, vals));
  CUPID_ASSERT_OK(cupid_direct_factor_solve(F, f, u));
  for (cupid_int d = 0; d < n; d++) u[d] = bc->fixed[d] ? 0.0 : u[d];
  assert_true(rel_error(n, u, ue) < 1e-10);
  cupid_direct_factor_destroy(&F);
  /* a mechanism: diag(a) downdated by sqrt(a_0) e_0 is singular at DOF 0; a spring of 1e-8
   * of the largest a there first keeps it definite (pivot ratio 1e-8, above the bound), and
   * DOF 0 then moves as the spring alone lets it */
  cupid_csr D = NULL;
  enum { ND = 50 };
  cupid_int di[ND], dj[ND];
  double dv[ND];
  for (int d = 0; d < ND; d++) di[d] = dj[d] = d, dv[d] = 2.0 + d;
  CUPID_ASSERT_OK(cupid_csr_from_triplets(ND, ND, ND, di, dj, dv, &D));
  cupid_dirichlet free_bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(ND, &free_bc));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(free_bc));
  const cupid_int c01[2] = {0, 1}, r0[1] = {0};
  const double all[1] = {sqrt(dv[0])}, spring[1] = {sqrt(1e-8 * dv[ND - 1])};
  CUPID_ASSERT_OK(cupid_direct_factor_create(D, free_bc, &F, NULL));
  assert_int_equal(cupid_direct_factor_failed_dof(F), -1);
  assert_int_equal(cupid_direct_factor_downdate(F, 1, c01, r0, all), CUPID_ERR_NUMERIC);
  assert_int_equal(cupid_direct_factor_failed_dof(F), 0); /* the DOF growth.c ties */
  cupid_error_clear();
  cupid_direct_factor_destroy(&F);
  /* ... as any DOF whose support a downdate removes: DOF 17, named, wherever the ordering
   * put it */
  const cupid_int r17[1] = {17};
  const double all17[1] = {sqrt(dv[17])};
  CUPID_ASSERT_OK(cupid_direct_factor_create(D, free_bc, &F, NULL));
  assert_int_equal(cupid_direct_factor_downdate(F, 1, c01, r17, all17), CUPID_ERR_NUMERIC);
  assert_int_equal(cupid_direct_factor_failed_dof(F), 17);
  cupid_error_clear();
  cupid_direct_factor_destroy(&F);
  CUPID_ASSERT_OK(cupid_direct_factor_create(D, free_bc, &F, NULL));
  CUPID_ASSERT_OK(cupid_direct_factor_update(F, 1, c01, r0, spring));
  CUPID_ASSERT_OK(cupid_direct_factor_downdate(F, 1, c01, r0, all));
  assert_int_equal(cupid_direct_factor_failed_dof(F), -1);
  double b[ND], x[ND];
  for (int d = 0; d < ND; d++) b[d] = 1.0;
  CUPID_ASSERT_OK(cupid_direct_factor_solve(F, b, x));
  assert_true(fabs(x[0] * 1e-8 * dv[ND - 1] - 1.0) < 1e-6); /* the spring alone holds DOF 0 */
  cupid_direct_factor_destroy(&F);
  cupid_dirichlet_destroy(&free_bc);
  cupid_csr_destroy(&D);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&A);
  cupid_csr_destroy(&K);
  free(ue), free(f), free(u);
}

/*
 * cupid_direct_factor_hold (crack growth holds a node that breaking left loose before it
 * downdates): the factor of K under conditions bc, with node h's DOFs held and then downdated
 * by bond terms (some touching h, whose entries there are dropped), solves A_ff u = f of the
 * conditions bc + h, A = K less the terms: as a fresh factor of A under them, to 1e-10 (as
 * test_factor_downdate: a rank-two modification per row is backward stable, cond(A_ff) < 1e3;
 * a row left in, or a term entry on h kept, gives O(1)). The solve leaves h's entries as they
 * were; a term that alone would leave the factor indefinite, on h's DOF only, is dropped once h
 * is held; the weakest pivot is never a held row (their pivot is the identity's 1).
 */
static void test_factor_hold(void **state) {
  (void)state;
  const grid_spec g = {6, 5, 4, 3, B_SPD, 0.05, 0.0, 0};
  cupid_csr A = grid_matrix(&g), K = grid_matrix(&g);
  const cupid_int nn = (cupid_int)g.nx * g.ny * g.nz, n = 3 * nn;
  const cupid_int h = node_of(&g, 2, 2, 2); /* the node held: interior */
  enum { NB = 4 };
  cupid_int colptr[NB + 1], rows[6 * NB];
  double vals[6 * NB];
  uint64_t seed = 11;
  const int ends[NB][2][3] = {{{1, 2, 2}, {2, 2, 2}}, {{2, 2, 2}, {3, 2, 2}}, /* two on h */
                              {{3, 1, 1}, {4, 1, 1}}, {{1, 3, 2}, {2, 3, 2}}};
  for (int b = 0; b < NB; b++) {
    const cupid_int i = node_of(&g, ends[b][0][0], ends[b][0][1], ends[b][0][2]);
    const cupid_int j = node_of(&g, ends[b][1][0], ends[b][1][1], ends[b][1][2]);
    add_bond(K, i, j, b, &seed, colptr, rows, vals);
  }
  colptr[NB] = 6 * NB;
  double *ue = malloc((size_t)n * sizeof *ue), *f = malloc((size_t)n * sizeof *f);
  double *u = malloc((size_t)n * sizeof *u), *ur = malloc((size_t)n * sizeof *ur);
  assert_non_null(ue), assert_non_null(f), assert_non_null(u), assert_non_null(ur);
  for (cupid_int k = 0; k < n; k++) ue[k] = cupid_test_random(&seed);
  cupid_dirichlet bc = face_bc(&g, ue, 0);
  cupid_direct_factor F = NULL, R = NULL;
  CUPID_ASSERT_OK(cupid_direct_factor_create(K, bc, &F, NULL));
  cupid_int held = -1;
  CUPID_ASSERT_OK(cupid_direct_factor_hold(F, bc, &held)); /* nothing new: nothing held */
  assert_int_equal(held, 0);
  for (int c = 0; c < 3; c++) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 3 * h + c, 0.0));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  for (cupid_int k = 0; k < n; k++) ue[k] = bc->fixed[k] ? 0.0 : ue[k]; /* homogeneous */
  cupid_csr_matvec(A, ue, f);
  CUPID_ASSERT_OK(cupid_direct_factor_hold(F, bc, &held));
  assert_int_equal(held, 3);
  CUPID_ASSERT_OK(cupid_direct_factor_hold(F, bc, &held)); /* held once */
  assert_int_equal(held, 0);
  CUPID_ASSERT_OK(cupid_direct_factor_downdate(F, NB, colptr, rows, vals));
  for (cupid_int k = 0; k < n; k++) u[k] = 7.0;
  CUPID_ASSERT_OK(cupid_direct_factor_solve(F, f, u));
  for (int c = 0; c < 3; c++) assert_true(u[3 * h + c] == 7.0); /* not written */
  CUPID_ASSERT_OK(cupid_direct_factor_create(A, bc, &R, NULL));
  CUPID_ASSERT_OK(cupid_direct_factor_solve(R, f, ur));
  for (cupid_int k = 0; k < n; k++) u[k] = bc->fixed[k] ? 0.0 : u[k], ur[k] = bc->fixed[k] ? 0.0 : ur[k];
  assert_true(rel_error(n, u, ue) < 1e-10);
  assert_true(rel_error(n, u, ur) < 1e-10);
  cupid_int weakest = -1;
  CUPID_ASSERT_OK(cupid_direct_factor_weakest_dof(F, &weakest));
  assert_true(weakest >= 0 && weakest / 3 != h && !bc->fixed[weakest]);
  /* a term far larger than h's stiffness on h's DOF alone: dropped with the held row */
  cupid_int one[2] = {0, 1}, row_h = 3 * h;
  double big = 1e3;
  CUPID_ASSERT_OK(cupid_direct_factor_downdate(F, 1, one, &row_h, &big));
  cupid_direct_factor_destroy(&R);
  cupid_dirichlet bc0 = face_bc(&g, ue, 0); /* h free: the same term leaves it indefinite */
  CUPID_ASSERT_OK(cupid_direct_factor_create(K, bc0, &R, NULL));
  assert_int_equal(cupid_direct_factor_downdate(R, 1, one, &row_h, &big), CUPID_ERR_NUMERIC);
  cupid_error_clear();
  cupid_direct_factor_destroy(&R);
  cupid_dirichlet_destroy(&bc0);
  /* an LU factor: refused */
  CUPID_ASSERT_OK(cupid_direct_factor_create_kind(A, CUPID_MATRIX_GENERAL, bc, &R, NULL));
  assert_int_equal(cupid_direct_factor_hold(R, bc, &held), CUPID_ERR_ARGUMENT);
  cupid_error_clear();
  cupid_direct_factor_destroy(&R);
  cupid_direct_factor_destroy(&F);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&A);
  cupid_csr_destroy(&K);
  free(ue), free(f), free(u), free(ur);
}

/* Every DOF prescribed: u = prescribed values, nothing factored. Empty matrix: nothing to do. */
static void test_all_fixed_and_empty(void **state) {
  (void)state;
  const grid_spec g = {3, 3, 3, 3, B_SPD, 0.0, 0.0, 0};
  cupid_csr K = grid_matrix(&g);
  const cupid_int n = K->nrows * 3;
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
  for (cupid_int k = 0; k < n; k++) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, k, 0.1 * (double)k));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  double *f = calloc((size_t)n, sizeof *f), *u = malloc((size_t)n * sizeof *u);
  cupid_solve_info info;
  for (int kind = 0; kind < 2; kind++) {
    CUPID_ASSERT_OK(cupid_direct_solve(K, (cupid_matrix_kind)kind, f, bc, u, &info));
    for (cupid_int k = 0; k < n; k++) assert_true(u[k] == 0.1 * (double)k);
    assert_int_equal(info.n, 0);
    assert_true(info.residual == 0.0);
  }
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);

  const cupid_int rp[1] = {0};
  CUPID_ASSERT_OK(cupid_csr_create(0, 0, 3, rp, NULL, &K));
  CUPID_ASSERT_OK(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, NULL, u, &info));
  assert_int_equal(info.n, 0);
  cupid_csr_destroy(&K);
  free(f);
  free(u);
}

static void test_bad_arguments(void **state) {
  (void)state;
  const grid_spec g = {3, 3, 2, 3, B_SPD, 1.0, 0.0, 0};
  cupid_csr K = grid_matrix(&g);
  const cupid_int n = K->nrows * 3;
  double *f = calloc((size_t)n, sizeof *f), *u = malloc((size_t)n * sizeof *u);
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(n - 1, &bc));
  assert_int_equal(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, NULL), CUPID_ERR_ARGUMENT);
  cupid_dirichlet_destroy(&bc);
  CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
  bc->fixed[5] = 1; /* not finalized */
  assert_int_equal(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, NULL), CUPID_ERR_ARGUMENT);
  assert_non_null(strstr(cupid_error_message(), "finalize"));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  CUPID_ASSERT_OK(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, NULL));
  assert_int_equal(cupid_direct_solve(K, (cupid_matrix_kind)7, f, bc, u, NULL),
                   CUPID_ERR_ARGUMENT);
  assert_int_equal(cupid_direct_solve(NULL, CUPID_MATRIX_SPD, f, bc, u, NULL), CUPID_ERR_ARGUMENT);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  free(f);
  free(u);
}

/*
 * Equilibrium: for K = L (x) B with L 1 = 0, the rigid translations t_a satisfy K t_a = 0, so
 * sum over all DOFs of component a of (K u - f) = -sum_a f. With K u = f on the free DOFs the
 * reactions balance the applied load: sum_a r + sum_a f = 0, up to the solve's residual.
 */
static void test_reactions(void **state) {
  (void)state;
  const grid_spec g = {8, 6, 5, 3, B_SPD, 0.0, 0.0, 0};
  cupid_csr K = grid_matrix(&g);
  const cupid_int n = K->nrows * 3;
  double *f = malloc((size_t)n * sizeof *f), *u = malloc((size_t)n * sizeof *u);
  double *r = malloc((size_t)n * sizeof *r), *pres = malloc((size_t)n * sizeof *pres);
  uint64_t seed = 17;
  for (cupid_int k = 0; k < n; k++) {
    f[k] = cupid_test_random(&seed);
    pres[k] = 0.01 * cupid_test_random(&seed); /* non-zero prescribed displacements */
  }
  cupid_dirichlet bc = face_bc(&g, pres, 0);
  cupid_solve_info info;
  CUPID_ASSERT_OK(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, &info));
  CUPID_ASSERT_OK(cupid_csr_reactions(K, u, f, bc, r));
  double load[3] = {0}, react[3] = {0}, scale = 0.0;
  for (cupid_int k = 0; k < n; k++) {
    load[k % 3] += f[k];
    react[k % 3] += r[k];
    scale += fabs(f[k]);
    if (!bc->fixed[k]) assert_true(r[k] == 0.0);
  }
  print_message("  load (%.6g %.6g %.6g) reactions (%.6g %.6g %.6g)\n", load[0], load[1],
                load[2], react[0], react[1], react[2]);
  /* |sum of residuals| <= sqrt(n) ||r_f|| ~ 1e-13 scale; 1e-10 leaves room for round-off */
  for (int a = 0; a < 3; a++) ASSERT_NEAR(react[a] + load[a], 0.0, 1e-10 * scale);
  /* without f: K u on the fixed DOFs, i.e. the reactions plus f there */
  double *ku = malloc((size_t)n * sizeof *ku);
  CUPID_ASSERT_OK(cupid_csr_reactions(K, u, NULL, bc, ku));
  for (cupid_int k = 0; k < n; k++) ASSERT_NEAR(ku[k], bc->fixed[k] ? r[k] + f[k] : 0.0, 1e-14);
  free(ku);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  free(f);
  free(u);
  free(r);
  free(pres);
}

/*
 * Size check (not a timed assertion): the 7-point Laplacian on 30^3 nodes (27,000 unknowns
 * after one face is fixed: 26,100), and a bs = 3 version on 20^3 nodes. Prints the figures.
 * CUPID_TEST_SMALL=1 shrinks the grids (for valgrind runs).
 */
static void test_size(void **state) {
  (void)state;
  grid_spec cases[2] = {{30, 30, 30, 1, ONE, 0.0, 0.0, 0}, {20, 20, 20, 3, B_SPD, 0.0, 0.0, 0}};
  if (getenv("CUPID_TEST_SMALL")) {
    cases[0].nx = cases[0].ny = cases[0].nz = 8;
    cases[1].nx = cases[1].ny = cases[1].nz = 5;
  }
  for (int c = 0; c < 2; c++) {
    for (int kind = 0; kind < 2; kind++) {
      cupid_csr K = grid_matrix(&cases[c]);
      const cupid_int n = K->nrows * K->bs;
      double *ue = malloc((size_t)n * sizeof *ue), *f = malloc((size_t)n * sizeof *f);
      double *u = malloc((size_t)n * sizeof *u);
      uint64_t seed = 5;
      for (cupid_int k = 0; k < n; k++) ue[k] = cupid_test_random(&seed);
      cupid_csr_matvec(K, ue, f);
      cupid_dirichlet bc = face_bc(&cases[c], ue, 0);
      cupid_solve_info info;
      const double t0 = cupid_wtime();
      CUPID_ASSERT_OK(cupid_direct_solve(K, (cupid_matrix_kind)kind, f, bc, u, &info));
      const double t = cupid_wtime() - t0;
      print_message("  %s bs=%d: n=%lld nnz(K_ff)=%lld nnz(factor)=%.3g flops=%.3g "
                    "memory=%.1f MB factor %.3f s solve %.3f s total %.3f s residual %.1e "
                    "error %.1e\n",
                    info.method, K->bs, (long long)info.n, (long long)info.nnz_matrix,
                    info.nnz_factor, info.flops_factor, (double)info.memory_factor / 1e6,
                    info.time_factor, info.time_solve, t, info.residual, rel_error(n, u, ue));
      /* cond(K_ff) ~ (2 nx / pi)^2 * cond(B) * 3 (weights) < 1e4: error ~1e-12 */
      assert_true(rel_error(n, u, ue) < 1e-10);
      cupid_dirichlet_destroy(&bc);
      cupid_csr_destroy(&K);
      free(ue);
      free(f);
      free(u);
    }
  }
}

/* ---- the built-in Krylov engine (solver krylov, src/solvers/iterative.c) ----
 * K applied matrix-free, preconditioned by the factor of a different matrix P (the "cheap
 * twin"), against the direct solve of K. rtol 1e-12 on the residual gives a forward error of
 * at most cond(K_ff) 1e-12 ~ 1e-8 (cond below ~1e4 here, as above): 1e-7 leaves a margin and
 * still catches a wrong right-hand side (the sign of A_fc u_c) or preconditioner (O(1)). */

static cupid_status csr_apply(void *ctx, const double *x, double *y) {
  cupid_csr_matvec(ctx, x, y);
  return CUPID_SUCCESS;
}

static cupid_status neg_apply(void *ctx, const double *x, double *y) {
  cupid_csr_matvec(ctx, x, y);
  for (cupid_int k = 0; k < ((const cupid_csr_t *)ctx)->nrows * ((const cupid_csr_t *)ctx)->bs; k++)
    y[k] = -y[k];
  return CUPID_SUCCESS;
}

/* The kept twin factor of crack growth on the krylov engine (growth_matrix_free.c): M^-1 r
 * through P's factor on the free DOFs it was made for, zero on every DOF fixed now. */
typedef struct {
  cupid_direct_factor F;
  cupid_dirichlet_t *bc;
} twin_pc;

static cupid_status twin_apply(void *ctx, const double *r, double *z) {
  twin_pc *p = ctx;
  return cupid_direct_factor_solve_masked(p->F, p->bc, r, z);
}

/* cupid_krylov_resolve (CG where L is symmetric, GMRES otherwise) from a guess: from the
 * solution (ud, the direct one) no iteration; from the solution perturbed by 1e-6 fewer than
 * from zero (it0) to the same answer; with a DOF fixed after the factorisation (a node held in
 * crack growth) the new system's answer through the masked factor; a CG on an indefinite
 * operator breaks down (CUPID_ERR_NUMERIC) and leaves its last iterate in u. */
static void check_resolve(const cupid_linear_operator *L, const cupid_csr_t *P, cupid_dirichlet bc,
                          const double *f, const double *ud, int it0, int symmetric) {
  const cupid_int n = L->n;
  twin_pc pc = {.bc = bc};
  double *u = malloc((size_t)n * sizeof *u), *uh = malloc((size_t)n * sizeof *uh);
  CUPID_ASSERT_OK(cupid_direct_factor_create_kind(P, symmetric ? CUPID_MATRIX_SPD : CUPID_MATRIX_GENERAL,
                                                  bc, &pc.F, NULL));
  cupid_solve_info info;
  memcpy(u, ud, (size_t)n * sizeof *u);
  CUPID_ASSERT_OK(cupid_krylov_resolve(L, bc, twin_apply, &pc, f, u, 1e-10, 500, &info));
  assert_int_equal(info.iterations, 0);
  assert_string_equal(info.ksp_type, symmetric ? "cg" : "gmres");
  uint64_t seed = 11;
  for (cupid_int k = 0; k < n; k++) u[k] = ud[k] * (1.0 + 1e-6 * cupid_test_random(&seed));
  CUPID_ASSERT_OK(cupid_krylov_resolve(L, bc, twin_apply, &pc, f, u, 1e-12, 500, &info));
  print_message("  resolve (%s) from 1e-6 off: %d iterations (%d from zero), |u - u_direct| %.1e\n",
                info.ksp_type, info.iterations, it0, rel_error(n, u, ud));
  assert_string_equal(info.converged_reason, "CONVERGED_RTOL");
  assert_true(info.iterations > 0 && info.iterations < it0);
  assert_true(rel_error(n, u, ud) < 1e-7);
  /* a free DOF fixed at its value in the direct solution of another load: u there */
  cupid_int d = 0;
  while (bc->fixed[d]) d++;
  CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, d, 0.5));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  const cupid_csr_t *K = L->ctx;
  CUPID_ASSERT_OK(cupid_direct_solve(K, symmetric ? CUPID_MATRIX_SPD : CUPID_MATRIX_GENERAL, f, bc,
                                     uh, NULL));
  memcpy(u, ud, (size_t)n * sizeof *u);
  CUPID_ASSERT_OK(cupid_krylov_resolve(L, bc, twin_apply, &pc, f, u, 1e-12, 500, &info));
  print_message("  resolve with a DOF held after the factorisation: %d iterations, error %.1e\n",
                info.iterations, rel_error(n, u, uh));
  assert_string_equal(info.converged_reason, "CONVERGED_RTOL");
  assert_true(u[d] == 0.5 && rel_error(n, u, uh) < 1e-7);
  if (symmetric) { /* -K: p'Ap < 0 at the first step */
    cupid_linear_operator neg = *L;
    neg.apply = neg_apply;
    memcpy(u, ud, (size_t)n * sizeof *u);
    u[d] = 0.5;
    for (cupid_int k = 0; k < n; k++) uh[k] = u[k];
    assert_int_equal(cupid_krylov_resolve(&neg, bc, twin_apply, &pc, f, u, 1e-12, 500, &info),
                     CUPID_ERR_NUMERIC);
    cupid_error_clear();
    int moved = 0;
    for (cupid_int k = 0; k < n; k++) moved |= u[k] != uh[k] && !bc->fixed[k];
    assert_false(moved); /* the breakdown came before the first step: u is the guess */
  }
  cupid_direct_factor_destroy(&pc.F);
  free(u);
  free(uh);
}

static void check_iterative(const grid_spec *gk, const grid_spec *gp, int symmetric, int restart) {
  cupid_csr K = grid_matrix(gk), P = grid_matrix(gp);
  const cupid_int n = K->nrows * K->bs;
  uint64_t seed = 7;
  double *ue = malloc((size_t)n * sizeof *ue), *f = malloc((size_t)n * sizeof *f);
  double *u = malloc((size_t)n * sizeof *u), *ud = malloc((size_t)n * sizeof *ud);
  for (cupid_int k = 0; k < n; k++) ue[k] = cupid_test_random(&seed);
  cupid_csr_matvec(K, ue, f);
  cupid_dirichlet bc = face_bc(gk, ue, 1);
  cupid_linear_operator L = {.n = n, .apply = csr_apply, .ctx = K, .symmetric = symmetric};
  cupid_krylov_options ko = {.rtol = 1e-12, .restart = restart};
  cupid_solve_info info, dinfo;
  CUPID_ASSERT_OK(cupid_iterative_solve(&L, P, bc, f, u, &ko, &info));
  CUPID_ASSERT_OK(cupid_direct_solve(K, symmetric ? CUPID_MATRIX_SPD : CUPID_MATRIX_GENERAL, f, bc,
                                     ud, &dinfo));
  const double err = rel_error(n, u, ud);
  print_message("  krylov %s + %s, restart %d: %d iterations, residual %.2e, |u - u_direct| %.2e\n",
                info.ksp_type, info.pc_type, restart, info.iterations, info.residual, err);
  assert_true(err < 1e-7);
  assert_true(info.residual <= 1e-12);
  assert_true(info.iterations > 1); /* P differs from K: more than one step */
  const int it_full = info.iterations;
  assert_string_equal(info.method, "krylov");
  assert_string_equal(info.ksp_type, symmetric ? "cg" : "gmres");
  assert_int_equal(info.n, bc->n_free);
  for (cupid_int k = 0; k < n; k++)
    if (bc->fixed[k]) assert_true(u[k] == ue[k]);
  /* too few iterations: a numerical failure, not a silent answer */
  cupid_krylov_options short_run = {.rtol = 1e-12, .max_it = 1, .restart = restart};
  assert_int_equal(cupid_iterative_solve(&L, P, bc, f, u, &short_run, &info), CUPID_ERR_NUMERIC);
  assert_string_equal(info.converged_reason, "DIVERGED_ITS");
  check_resolve(&L, P, bc, f, ud, it_full, symmetric);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  cupid_csr_destroy(&P);
  free(ue);
  free(f);
  free(u);
  free(ud);
}

static void test_iterative_engine(void **state) {
  (void)state;
  /* GMRES: a convected (non-symmetric) grid, preconditioned by the factor of a twin with
   * other convection and shift; restart 4 exercises the restarts, 200 none */
  const grid_spec gk = {6, 6, 5, 3, B_GEN, 0.1, 0.6, 0}, gp = {6, 6, 5, 3, B_GEN, 0.4, 0.2, 0};
  check_iterative(&gk, &gp, 0, 4);
  check_iterative(&gk, &gp, 0, 200);
  /* CG: SPD grid, SPD twin with another shift and block */
  const grid_spec sk = {7, 6, 5, 3, B_SPD, 0.1, 0.0, 0}, sp = {7, 6, 5, 3, B_SPD, 0.8, 0.0, 0};
  check_iterative(&sk, &sp, 1, 0);
  /* a slab operator is refused (the engine runs on one process) */
  cupid_pd_grid_partition part = {.parts = 2};
  cupid_linear_operator L = {.n = 3, .apply = csr_apply, .part = &part};
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(3, &bc));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  cupid_csr K = NULL;
  double f[3] = {0, 0, 0}, u[3];
  CUPID_ASSERT_OK(cupid_csr_create(1, 1, 3, (cupid_int[]){0, 1}, (cupid_int[]){0}, &K));
  assert_int_equal(cupid_iterative_solve(&L, K, bc, f, u, NULL, NULL), CUPID_ERR_UNSUPPORTED);
  cupid_csr_destroy(&K);
  cupid_dirichlet_destroy(&bc);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_spd_known_solution),
                                     cmocka_unit_test(test_general_known_solution),
                                     cmocka_unit_test(test_singular),
                                     cmocka_unit_test(test_floating_component),
                                     cmocka_unit_test(test_indefinite),
                                     cmocka_unit_test(test_spd_not_symmetric),
                                     cmocka_unit_test(test_non_finite),
                                     cmocka_unit_test(test_random_spd),
                                     cmocka_unit_test(test_factor_downdate),
                                     cmocka_unit_test(test_factor_hold),
                                     cmocka_unit_test(test_factor_update),
                                     cmocka_unit_test(test_all_fixed_and_empty),
                                     cmocka_unit_test(test_bad_arguments),
                                     cmocka_unit_test(test_reactions),
                                     cmocka_unit_test(test_iterative_engine),
                                     cmocka_unit_test(test_size)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
