/* Slab grids for MPI (issue 6): each rank builds only its z layers plus a halo of
 * cupid_pd_operator_halo_layers(), and on its owned nodes the slab's operator must be the whole
 * grid's operator. Checked here without MPI, part by part against the whole grid:
 *  - the owned ranges tile the global numbering, and local node l is global node
 *    first_global + l (coordinates and materials equal);
 *  - rows of K u, nodal stress, diagonal blocks and weighted volumes of the owned nodes equal
 *    the whole grid's, for LPS and bond-based, with the surface correction (the longest
 *    dependency: factors of the neighbours) and with exact partial volumes (the widest stencil);
 *  - a halo one layer short breaks the equality (the halo is needed, not just generous);
 *  - more parts than layers is a model error.
 * Tolerance 1e-12 of the largest entry: the slab walks the same families in the same order, so
 * only the padded kernels' reference shift (stencil.c work_fill: the middle node of the range)
 * differs; it cancels in exact arithmetic and leaves ~1e-15 relative. */
#include <math.h>
#include <string.h>

#include "testutil.h"

/* An L-shaped union (two materials) whose layers hold different node counts, so that the
 * split by nodes differs from a split by layers. */
static const cupid_box boxes[2] = {{{0, 0, 0}, {7, 6, 20}, {1, 1, 1}},
                                   {{0, 6, 10}, {7, 9, 20}, {1, 1, 1}}};
static const int mats[2] = {0, 1};
static const cupid_pd_material pm[2] = {{.E = 1000.0, .nu = 0.3}, {.E = 1500.0, .nu = 0.25}};

static double max_abs(const double *a, cupid_int n) {
  double m = 0.0;
  for (cupid_int i = 0; i < n; i++) m = fmax(m, fabs(a[i]));
  return m;
}

typedef struct {
  cupid_pd_grid grid;
  cupid_pd_operator op;
  double *f, *sigma, *diag;
} whole_result;

static void whole(const cupid_pd_operator_options *oo, const double *u, whole_result *w) {
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 2, boxes, mats, &w->grid));
  CUPID_ASSERT_OK(cupid_pd_operator_create(w->grid, oo, &w->op));
  cupid_int n = cupid_pd_grid_num_nodes(w->grid);
  CUPID_ASSERT_OK(cupid_malloc(3 * (size_t)n, sizeof(double), "f", &w->f));
  CUPID_ASSERT_OK(cupid_malloc(6 * (size_t)n, sizeof(double), "sigma", &w->sigma));
  CUPID_ASSERT_OK(cupid_malloc(9 * (size_t)n, sizeof(double), "diag", &w->diag));
  CUPID_ASSERT_OK(cupid_pd_operator_apply(w->op, u, w->f));
  CUPID_ASSERT_OK(cupid_pd_operator_stress(w->op, u, w->sigma));
  CUPID_ASSERT_OK(cupid_pd_operator_diagonal(w->op, w->diag));
}

static void whole_free(whole_result *w) {
  cupid_free(&w->f);
  cupid_free(&w->sigma);
  cupid_free(&w->diag);
  cupid_pd_operator_destroy(&w->op);
  cupid_pd_grid_destroy(&w->grid);
}

/* Largest difference of the owned rows of one part from the whole grid's, relative to the
 * largest entry of each quantity; also checks the numbering. Returns the owned count. */
static cupid_int check_part(const cupid_pd_operator_options *oo, const whole_result *w,
                            const double *u, int parts, int part, int halo, double *worst) {
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3, .parts = parts, .part = part,
                              .halo_layers = halo};
  cupid_pd_grid g = NULL;
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 2, boxes, mats, &g));
  cupid_pd_grid_partition P;
  cupid_pd_grid_get_partition(g, &P);
  const cupid_int N = cupid_pd_grid_num_nodes(w->grid), n = cupid_pd_grid_num_nodes(g);
  assert_int_equal(P.global_nodes, N);
  assert_int_equal(P.parts, parts > 1 ? parts : 1);
  assert_true(P.owned_first >= 0 && P.owned_first < P.owned_last && P.owned_last <= n);
  assert_true(P.first_global >= 0 && P.first_global + n <= N);
  const double *xs = cupid_pd_grid_coords(g), *xw = cupid_pd_grid_coords(w->grid);
  const int *ms = cupid_pd_grid_materials(g), *mw = cupid_pd_grid_materials(w->grid);
  for (cupid_int l = 0; l < n; l++) {
    for (int a = 0; a < 3; a++) assert_true(xs[3 * l + a] == xw[3 * (P.first_global + l) + a]);
    assert_int_equal(ms[l], mw[P.first_global + l]);
  }
  CUPID_ASSERT_OK(cupid_pd_operator_create(g, oo, &op));
  const cupid_int a = P.owned_first, b = P.owned_last, g0 = P.first_global;
  double *f = NULL, *sigma = NULL, *diag = NULL;
  CUPID_ASSERT_OK(cupid_malloc(3 * (size_t)(b - a), sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_malloc(6 * (size_t)n, sizeof *sigma, "sigma", &sigma));
  CUPID_ASSERT_OK(cupid_malloc(9 * (size_t)n, sizeof *diag, "diag", &diag));
  const double *ul = u + 3 * g0; /* the slab's view of the global field */
  CUPID_ASSERT_OK(cupid_pd_operator_apply_range(op, a, b, ul, f));
  CUPID_ASSERT_OK(cupid_pd_operator_stress(op, ul, sigma));
  CUPID_ASSERT_OK(cupid_pd_operator_diagonal(op, diag));
  const double *m_s = cupid_pd_operator_weighted_volume(op), *m_w = cupid_pd_operator_weighted_volume(w->op);
  double sf = max_abs(w->f, 3 * N), ss = max_abs(w->sigma, 6 * N), sd = max_abs(w->diag, 9 * N);
  double e = 0.0;
  for (cupid_int i = a; i < b; i++) {
    for (int c = 0; c < 3; c++) e = fmax(e, fabs(f[3 * (i - a) + c] - w->f[3 * (g0 + i) + c]) / sf);
    for (int c = 0; c < 6; c++) e = fmax(e, fabs(sigma[6 * i + c] - w->sigma[6 * (g0 + i) + c]) / ss);
    for (int c = 0; c < 9; c++) e = fmax(e, fabs(diag[9 * i + c] - w->diag[9 * (g0 + i) + c]) / sd);
    e = fmax(e, fabs(m_s[i] - m_w[g0 + i]) / m_w[g0 + i]);
  }
  *worst = e;
  cupid_free(&f);
  cupid_free(&sigma);
  cupid_free(&diag);
  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&g);
  return b - a;
}

static void check_model(cupid_pd_model_kind model, cupid_partial_volume rule,
                        cupid_surface_correction sc) {
  /* delta = 2h reaches 2 layers; exact partial volumes at delta = 2.6h reach 3 (the cell at
   * offset 3 has its near face at 2.5h, inside the ball), PDLAMMPS would stop at 2. */
  const double delta = rule == CUPID_PARTIAL_EXACT ? 2.6 : 2.0;
  cupid_pd_operator_options oo = {.horizon = delta, .model = model,
                                  .influence = CUPID_INFLUENCE_GAUSSIAN, .partial_volume = rule,
                                  .materials = pm, .n_materials = 2, .surface_correction = sc};
  int halo = -1;
  CUPID_ASSERT_OK(cupid_pd_operator_halo_layers(&oo, 1.0, &halo));
  assert_int_equal(halo, rule == CUPID_PARTIAL_EXACT ? 6 : 4);
  whole_result w = {0};
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 2, boxes, mats, &w.grid));
  const cupid_int N = cupid_pd_grid_num_nodes(w.grid);
  cupid_pd_grid_destroy(&w.grid);
  double *u = NULL;
  CUPID_ASSERT_OK(cupid_malloc(3 * (size_t)N, sizeof *u, "u", &u));
  uint64_t seed = 11;
  for (cupid_int i = 0; i < 3 * N; i++) u[i] = cupid_test_random(&seed) - 0.5;
  whole(&oo, u, &w);
  for (int parts = 1; parts <= 4; parts++) {
    cupid_int owned = 0;
    double worst = 0.0;
    for (int p = 0; p < parts; p++) {
      double e;
      owned += check_part(&oo, &w, u, parts, p, halo, &e);
      worst = fmax(worst, e);
    }
    assert_int_equal(owned, N); /* the owned ranges tile the nodes */
    print_message("model %d rule %d correction %d, %d parts: max relative difference %.2e\n",
                  (int)model, (int)rule, (int)sc, parts, worst);
    assert_true(worst <= 1e-12);
  }
  /* One layer short of the halo: the owned rows next to the cut see a truncated neighbour. */
  double e0, e1, short_worst = 0.0;
  check_part(&oo, &w, u, 3, 0, halo - 1, &e0);
  check_part(&oo, &w, u, 3, 1, halo - 1, &e1);
  short_worst = fmax(e0, e1);
  print_message("  halo %d instead of %d: %.2e\n", halo - 1, halo, short_worst);
  assert_true(short_worst > 1e-6);
  cupid_free(&u);
  whole_free(&w);
}

static void test_lps_corrected(void **state) {
  (void)state;
  check_model(CUPID_PD_LPS, CUPID_PARTIAL_PDLAMMPS, CUPID_SURFACE_ENERGY);
}

static void test_lps_exact(void **state) {
  (void)state;
  check_model(CUPID_PD_LPS, CUPID_PARTIAL_EXACT, CUPID_SURFACE_NONE);
}

static void test_bond_corrected(void **state) {
  (void)state;
  check_model(CUPID_PD_BOND, CUPID_PARTIAL_PDLAMMPS, CUPID_SURFACE_ENERGY);
}

static void test_too_many_parts(void **state) {
  (void)state;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3, .parts = 21, .part = 0,
                              .halo_layers = 2};
  cupid_pd_grid g = NULL;
  assert_int_equal(cupid_pd_grid_create(&go, 2, boxes, mats, &g), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "20 z layers"));
  assert_null(g);
  go.parts = 20; /* one layer each works */
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 2, boxes, mats, &g));
  cupid_pd_grid_partition P;
  cupid_pd_grid_get_partition(g, &P);
  assert_int_equal(P.owned_last - P.owned_first, 42); /* layer 0: 7 x 6 nodes */
  cupid_pd_grid_destroy(&g);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_lps_corrected), cmocka_unit_test(test_lps_exact),
      cmocka_unit_test(test_bond_corrected), cmocka_unit_test(test_too_many_parts)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
