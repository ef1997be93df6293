/* Rows of the matrix-free PD operator by node range (the building block of the distributed
 * product) against the whole product, and the dependency range: a field that is garbage
 * outside [lo, hi) must give the same rows. */
#include <math.h>
#include <string.h>

#include "testutil.h"

static void check_model(cupid_pd_model_kind model) {
  cupid_box box = {{0, 0, 0}, {6, 5, 9}, {1, 1, 1}};
  int mat = 0;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  cupid_pd_grid grid = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &box, &mat, &grid));
  cupid_pd_material pm = {.E = 1000.0, .nu = 0.3};
  cupid_pd_operator_options oo = {.horizon = 2.0, .model = model,
                                  .influence = CUPID_INFLUENCE_GAUSSIAN,
                                  .partial_volume = CUPID_PARTIAL_PDLAMMPS,
                                  .materials = &pm, .n_materials = 1};
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(grid, &oo, &op));
  const cupid_int n = cupid_pd_grid_num_nodes(grid);
  double *u = NULL, *v = NULL, *f = NULL, *g = NULL;
  CUPID_ASSERT_OK(cupid_malloc(3 * (size_t)n, sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_malloc(3 * (size_t)n, sizeof *v, "v", &v));
  CUPID_ASSERT_OK(cupid_malloc(3 * (size_t)n, sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_malloc(3 * (size_t)n, sizeof *g, "g", &g));
  uint64_t seed = 7;
  for (cupid_int i = 0; i < 3 * n; i++) u[i] = cupid_test_random(&seed) - 0.5;
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, u, f));
  double fmax = 0;
  for (cupid_int i = 0; i < 3 * n; i++) fmax = fmax > fabs(f[i]) ? fmax : fabs(f[i]);
  /* Three slabs of z layers (30 nodes a layer) and an unaligned range. */
  const cupid_int ranges[4][2] = {{0, 90}, {90, 180}, {180, n}, {37, 201}};
  for (int r = 0; r < 4; r++) {
    const cupid_int a = ranges[r][0], b = ranges[r][1];
    cupid_int lo, hi;
    CUPID_ASSERT_OK(cupid_pd_operator_dependency_range(op, a, b, &lo, &hi));
    assert_true(lo <= a && hi >= b && lo >= 0 && hi <= n);
    /* Poison what the rows must not read. */
    for (cupid_int i = 0; i < 3 * n; i++) v[i] = (i >= 3 * lo && i < 3 * hi) ? u[i] : NAN;
    CUPID_ASSERT_OK(cupid_pd_operator_apply_range(op, a, b, v, g));
    /* Same arithmetic in the same order: identical up to round-off (1e-14 of max |f|). */
    for (cupid_int i = 0; i < 3 * (b - a); i++)
      ASSERT_NEAR(g[i], f[3 * a + i], 1e-14 * fmax);
  }
  /* LPS reaches two horizons: the dependency of one middle layer is wider than its family. */
  cupid_int lo, hi;
  CUPID_ASSERT_OK(cupid_pd_operator_dependency_range(op, 120, 150, &lo, &hi));
  const cupid_int reach = (model == CUPID_PD_LPS ? 4 : 2) * 30;
  assert_int_equal(lo, 120 - reach);
  assert_int_equal(hi, 150 + reach);
  assert_int_equal(cupid_pd_operator_apply_range(op, 5, n + 1, u, g), CUPID_ERR_ARGUMENT);
  cupid_free(&u);
  cupid_free(&v);
  cupid_free(&f);
  cupid_free(&g);
  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&grid);
}

static void test_lps(void **state) {
  (void)state;
  check_model(CUPID_PD_LPS);
}

static void test_bond(void **state) {
  (void)state;
  check_model(CUPID_PD_BOND);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_lps), cmocka_unit_test(test_bond)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
