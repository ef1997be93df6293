/* Unit tests of the PD grid (src/pd/grid.c): unions of boxes on one lattice, node order,
 * lookups, errors for off-lattice bounds, empty and unbounded boxes, huge grids, 1D bars. */
#include <math.h>
#include <string.h>

#include "testutil.h"

static cupid_box box3(double x0, double x1, double y0, double y1, double z0, double z1) {
  cupid_box b = {.lo = {x0, y0, z0}, .hi = {x1, y1, z1}, .has = {1, 1, 1}};
  return b;
}

/* Two boxes sharing the face y = 3: 4 x 6 x 2 nodes, x fastest, materials per box. */
static void test_two_boxes_sharing_a_face(void **state) {
  (void)state;
  cupid_box b[2] = {box3(0, 4, 0, 3, 0, 2), box3(0, 4, 3, 6, 0, 2)};
  int mats[2] = {0, 1};
  cupid_pd_grid_options o = {.spacing = 1.0, .dimension = 3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 2, b, mats, &g));
  assert_int_equal(cupid_pd_grid_num_nodes(g), 48);
  const double *x = cupid_pd_grid_coords(g);
  const int *m = cupid_pd_grid_materials(g);
  /* Node order: x fastest, then y, then z. */
  ASSERT_NEAR(x[0], 0.5, 0);
  ASSERT_NEAR(x[1], 0.5, 0);
  ASSERT_NEAR(x[2], 0.5, 0);
  ASSERT_NEAR(x[3], 1.5, 0);
  ASSERT_NEAR(x[3 * 4 + 1], 1.5, 0);
  ASSERT_NEAR(x[3 * 24 + 2], 1.5, 0);
  for (cupid_int i = 0; i < 48; i++) assert_int_equal(m[i], x[3 * i + 1] < 3 ? 0 : 1);
  for (cupid_int k = 0; k < 2; k++)
    for (cupid_int j = 0; j < 6; j++)
      for (cupid_int i = 0; i < 4; i++) {
        cupid_int n = cupid_pd_grid_node_at(g, i, j, k);
        assert_int_equal(n, i + 4 * (j + 6 * k));
        cupid_int ijk[3];
        cupid_pd_grid_node_lattice(g, n, ijk);
        assert_int_equal(ijk[0], i);
        assert_int_equal(ijk[1], j);
        assert_int_equal(ijk[2], k);
      }
  assert_int_equal(cupid_pd_grid_node_at(g, 4, 0, 0), -1);
  assert_int_equal(cupid_pd_grid_node_at(g, -1, 0, 0), -1);
  ASSERT_NEAR(cupid_pd_grid_cell_volume(g), 1.0, 0);
  cupid_pd_grid_destroy(&g);
  assert_null(g);
  cupid_pd_grid_destroy(&g); /* harmless */
}

/* L-shaped union of overlapping boxes, lattice anchored at the lowest corner per axis,
 * the first box wins the material where they overlap. */
static void test_l_shape_and_anchor(void **state) {
  (void)state;
  const double h = 0.5;
  cupid_box b[2] = {box3(1.0, 4.0, 0.5, 1.5, -1.0, 0.0), box3(1.0, 2.0, 0.5, 4.0, -1.0, 0.0)};
  int mats[2] = {3, 7};
  cupid_pd_grid_options o = {.spacing = h, .dimension = 3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 2, b, mats, &g));
  /* A: 6 x 2 x 2 = 24 cells; B: 2 x 7 x 2 = 28 cells, 8 of them shared. */
  assert_int_equal(cupid_pd_grid_num_nodes(g), 24 + 28 - 8);
  double origin[3];
  cupid_int n[3];
  cupid_pd_grid_origin(g, origin);
  cupid_pd_grid_extent(g, n);
  ASSERT_NEAR(origin[0], 1.0, 0);
  ASSERT_NEAR(origin[1], 0.5, 0);
  ASSERT_NEAR(origin[2], -1.0, 0);
  assert_int_equal(n[0], 6);
  assert_int_equal(n[1], 7);
  assert_int_equal(n[2], 2);
  const double *x = cupid_pd_grid_coords(g);
  const int *m = cupid_pd_grid_materials(g);
  for (cupid_int i = 0; i < cupid_pd_grid_num_nodes(g); i++) {
    int in_a = x[3 * i + 1] < 1.5;
    assert_int_equal(m[i], in_a ? 3 : 7);
    assert_true(in_a || x[3 * i] < 2.0);
  }
  /* Cell (5, 6, 0) lies in neither box. */
  assert_int_equal(cupid_pd_grid_node_at(g, 5, 6, 0), -1);
  cupid_int c = cupid_pd_grid_node_at(g, 1, 6, 1);
  assert_true(c >= 0);
  ASSERT_NEAR(x[3 * c], 1.75, 1e-15);
  ASSERT_NEAR(x[3 * c + 1], 3.75, 1e-15);
  ASSERT_NEAR(x[3 * c + 2], -0.25, 1e-15);
  cupid_pd_grid_destroy(&g);
}

static void test_off_lattice_bound(void **state) {
  (void)state;
  cupid_box b[2] = {box3(0, 4, 0, 3, 0, 2), box3(0, 4, 3, 5.3, 0, 2)};
  int mats[2] = {0, 0};
  cupid_pd_grid_options o = {.spacing = 0.5, .dimension = 3};
  cupid_pd_grid g = NULL;
  assert_int_equal(cupid_pd_grid_create(&o, 2, b, mats, &g), CUPID_ERR_MODEL);
  assert_null(g);
  const char *msg = cupid_error_message();
  assert_non_null(strstr(msg, "box 1"));
  assert_non_null(strstr(msg, "y upper bound 5.3"));
  assert_non_null(strstr(msg, "not on the lattice"));
  /* Within the tolerance 1e-9 h the bound is accepted (rounding of decimal input). */
  b[1].hi[1] = 5.0 + 1e-12;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 2, b, mats, &g));
  assert_int_equal(cupid_pd_grid_num_nodes(g), 8 * 10 * 4);
  cupid_pd_grid_destroy(&g);
  /* A lower bound off the lattice of the other box. */
  b[1].hi[1] = 5.0;
  b[1].lo[0] = 0.25;
  assert_int_equal(cupid_pd_grid_create(&o, 2, b, mats, &g), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "x lower bound 0.25"));
}

static void test_empty_and_unbounded_boxes(void **state) {
  (void)state;
  cupid_box b[2] = {box3(0, 4, 0, 3, 0, 2), box3(0, 4, 3, 3, 0, 2)};
  int mats[2] = {0, 0};
  cupid_pd_grid_options o = {.spacing = 1, .dimension = 3};
  cupid_pd_grid g = NULL;
  assert_int_equal(cupid_pd_grid_create(&o, 2, b, mats, &g), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "box 1"));
  assert_non_null(strstr(cupid_error_message(), "no node"));
  b[1] = box3(0, 4, 3, 5, 0, 2);
  b[1].has[2] = 0;
  assert_int_equal(cupid_pd_grid_create(&o, 2, b, mats, &g), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "box 1"));
  assert_non_null(strstr(cupid_error_message(), "z range"));
  o.spacing = 0;
  assert_int_equal(cupid_pd_grid_create(&o, 1, b, mats, &g), CUPID_ERR_MODEL);
}

static void test_huge_grid_refused(void **state) {
  (void)state;
  cupid_box b = box3(0, 1, 0, 1, 0, 1);
  int mat = 0;
  cupid_pd_grid_options o = {.spacing = 1e-4, .dimension = 3};
  cupid_pd_grid g = NULL;
  assert_int_equal(cupid_pd_grid_create(&o, 1, &b, &mat, &g), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "1000000000000 cells"));
}

static void test_bar_1d(void **state) {
  (void)state;
  cupid_box b = {.lo = {0, 2, 0}, .hi = {0, 12, 0}, .has = {0, 1, 0}};
  int mat = 0;
  cupid_pd_grid_options o = {.spacing = 0.5, .dimension = 1, .area = 2.0};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 1, &b, &mat, &g));
  assert_int_equal(cupid_pd_grid_dimension(g), 1);
  assert_int_equal(cupid_pd_grid_num_nodes(g), 20);
  ASSERT_NEAR(cupid_pd_grid_cell_volume(g), 1.0, 1e-15);
  const double *x = cupid_pd_grid_coords(g);
  for (cupid_int j = 0; j < 20; j++) {
    assert_int_equal(cupid_pd_grid_node_at(g, 0, j, 0), j);
    ASSERT_NEAR(x[3 * j], 0, 0);
    ASSERT_NEAR(x[3 * j + 1], 2.25 + 0.5 * (double)j, 1e-14);
    ASSERT_NEAR(x[3 * j + 2], 0, 0);
  }
  cupid_pd_grid_destroy(&g);
  o.area = 0;
  assert_int_equal(cupid_pd_grid_create(&o, 1, &b, &mat, &g), CUPID_ERR_MODEL);
  assert_null(g);
}

/* Interior flags: in a 10^3 box, radius 3 leaves lattice positions 3..6 per axis. */
static void test_interior_flags(void **state) {
  (void)state;
  cupid_box b = box3(0, 10, 0, 10, 0, 10);
  int mat = 0;
  cupid_pd_grid_options o = {.spacing = 1, .dimension = 3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 1, &b, &mat, &g));
  unsigned char flags[1000];
  CUPID_ASSERT_OK(cupid_pd_grid_interior(g, 3.0, flags));
  int count = 0;
  for (int i = 0; i < 1000; i++) {
    cupid_int ijk[3];
    cupid_pd_grid_node_lattice(g, i, ijk);
    int expect = 1;
    for (int a = 0; a < 3; a++) expect &= ijk[a] >= 3 && ijk[a] <= 6;
    assert_int_equal(flags[i], expect);
    count += flags[i];
  }
  assert_int_equal(count, 64);
  cupid_pd_grid_destroy(&g);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_two_boxes_sharing_a_face), cmocka_unit_test(test_l_shape_and_anchor),
      cmocka_unit_test(test_off_lattice_bound),       cmocka_unit_test(test_empty_and_unbounded_boxes),
      cmocka_unit_test(test_huge_grid_refused),       cmocka_unit_test(test_bar_1d),
      cmocka_unit_test(test_interior_flags)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
