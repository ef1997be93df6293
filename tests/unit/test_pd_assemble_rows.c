/* Unit tests of the owned-row bond-based preconditioner matrix (src/pd/assemble_rows.c), the
 * matrix GAMG coarsens in the matrix-free PETSc solve (issue 6). No PETSc needed. */
#include <math.h>

#include "cupid/pd.h"
#include "testutil.h"

/* An L-shaped union of two boxes (surface nodes with partial families), two materials. */
static cupid_pd_grid make_grid(void) {
  cupid_pd_grid g = NULL;
  cupid_pd_grid_options o = {.spacing = 0.5, .dimension = 3};
  cupid_box b[2] = {{.lo = {0, 0, 0}, .hi = {3, 2, 2}, .has = {1, 1, 1}},
                    {.lo = {0, 2, 0}, .hi = {1.5, 4, 2}, .has = {1, 1, 1}}};
  int mats[2] = {0, 1};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 2, b, mats, &g));
  return g;
}

static const cupid_pd_material materials[2] = {{.E = 1000.0, .nu = 0.3}, {.E = 3000.0, .nu = 0.25}};

/* K u for the rows [first, last) of A (bs 3) and a full-length u. */
static void row_product(const cupid_csr_t *A, const double *u, double *y) {
  for (cupid_int r = 0; r < A->nrows; r++)
    for (int a = 0; a < 3; a++) {
      double s = 0.0;
      for (cupid_int k = A->rowptr[r]; k < A->rowptr[r + 1]; k++)
        for (int b = 0; b < 3; b++) s += A->val[9 * k + 3 * a + b] * u[3 * A->col[k] + b];
      y[3 * r + a] = s;
    }
}

/* Rigid motions give zero force (the matrix of a linearised central-force network), so the
 * rigid-body near null space that GAMG gets is exact for it; rows split in two ranges equal
 * the full matrix's; the matrix is symmetric. Tolerance 1e-12 relative to the row scale
 * (sums of ~19 terms of equal magnitude). */
static void test_rows_rigid_symmetric_split(void **state) {
  (void)state;
  cupid_pd_grid g = make_grid();
  cupid_int n = cupid_pd_grid_num_nodes(g), half = n / 2 + 7;
  cupid_csr full = NULL, lo = NULL, hi = NULL;
  CUPID_ASSERT_OK(cupid_pd_assemble_rows_bond(g, materials, 0.75, 0, n, &full));
  CUPID_ASSERT_OK(cupid_pd_assemble_rows_bond(g, materials, 0.75, 0, half, &lo));
  CUPID_ASSERT_OK(cupid_pd_assemble_rows_bond(g, materials, 0.75, half, n, &hi));
  assert_int_equal(full->bs, 3);
  assert_int_equal(full->nrows, n);
  assert_int_equal(lo->nrows + hi->nrows, n);
  /* 1.5 h: at most the node and its 18 face and edge neighbours. */
  for (cupid_int r = 0; r < n; r++) assert_true(full->rowptr[r + 1] - full->rowptr[r] <= 19);
  assert_true(cupid_csr_asymmetry(full) < 1e-14);

  const double *x = cupid_pd_grid_coords(g);
  double *u = NULL, *y = NULL, *y2 = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)(3 * n), sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_calloc((size_t)(3 * n), sizeof *y, "y", &y));
  CUPID_ASSERT_OK(cupid_calloc((size_t)(3 * n), sizeof *y2, "y2", &y2));
  double dmax = 0.0;
  for (cupid_int r = 0; r < n; r++) dmax = fmax(dmax, fabs(cupid_csr_find(full, r, r)[0]));
  /* A translation plus a rotation about an arbitrary point. */
  double t[3] = {0.3, -0.2, 0.7}, w[3] = {0.05, -0.11, 0.08}, c[3] = {1, 2, 0.5};
  for (cupid_int i = 0; i < n; i++) {
    double d[3] = {x[3 * i] - c[0], x[3 * i + 1] - c[1], x[3 * i + 2] - c[2]};
    u[3 * i] = t[0] + w[1] * d[2] - w[2] * d[1];
    u[3 * i + 1] = t[1] + w[2] * d[0] - w[0] * d[2];
    u[3 * i + 2] = t[2] + w[0] * d[1] - w[1] * d[0];
  }
  row_product(full, u, y);
  for (cupid_int k = 0; k < 3 * n; k++) assert_true(fabs(y[k]) < 1e-12 * dmax);
  /* A random field: the split rows reproduce the full product exactly. */
  uint64_t seed = 42;
  for (cupid_int k = 0; k < 3 * n; k++) u[k] = cupid_test_random(&seed) - 0.5;
  row_product(full, u, y);
  row_product(lo, u, y2);
  row_product(hi, u, y2 + 3 * half);
  for (cupid_int k = 0; k < 3 * n; k++) assert_true(y[k] == y2[k]);
  /* Positive semi-definite with energy > 0 for a non-rigid field. */
  double e = 0.0;
  for (cupid_int k = 0; k < 3 * n; k++) e += u[k] * y[k];
  assert_true(e > 0.0);
  cupid_free(&u);
  cupid_free(&y);
  cupid_free(&y2);
  cupid_csr_destroy(&full);
  cupid_csr_destroy(&lo);
  cupid_csr_destroy(&hi);
  cupid_pd_grid_destroy(&g);
}

static void test_rows_errors(void **state) {
  (void)state;
  cupid_pd_grid g = make_grid();
  cupid_int n = cupid_pd_grid_num_nodes(g);
  cupid_csr K = NULL;
  assert_int_equal(cupid_pd_assemble_rows_bond(g, materials, 0.75, 5, n + 1, &K), CUPID_ERR_ARGUMENT);
  assert_int_equal(cupid_pd_assemble_rows_bond(g, materials, 0.25, 0, n, &K), CUPID_ERR_ARGUMENT);
  assert_null(K);
  cupid_pd_grid_destroy(&g);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_rows_rigid_symmetric_split),
      cmocka_unit_test(test_rows_errors),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
