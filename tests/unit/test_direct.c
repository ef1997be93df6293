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

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_spd_known_solution),
                                     cmocka_unit_test(test_general_known_solution)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
