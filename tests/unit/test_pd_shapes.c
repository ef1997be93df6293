/* PD regions and holes of other shapes than boxes (issue 35; src/pd/grid.c, cupid_shape_contains):
 * a cell is a node when its centre lies in a region's shape and in no hole. Checks:
 *  - a sphere (r = 10 h): every node inside, every cell centre inside a node, the count's volume
 *    within 1.5% of 4/3 pi r^3 (counting lattice points: measured +0.84%), within 0.5% at
 *    r = 20 h (+0.12%);
 *  - a cylinder along y (r = 6 h, length 20 h): nodes inside and between its ends, the volume
 *    within 2% of pi r^2 L (-0.97%);
 *  - a plate with a cylindrical hole through it: no node in the hole, the removed volume within
 *    5% of the hole's (+3.4%);
 *  - a box and a sphere reaching below it: the lattice stays on the box's planes (the box's
 *    nodes at its cell centres), the sphere's cells below the box are there, the box's material
 *    wins where both hold a cell;
 *  - two slabs of the plate with the hole own every node once. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cupid/model.h"
#include "cupid/pd.h"
#include "test_shapes.h"
#include "testutil.h"

static cupid_pd_grid make(const cupid_shape *shapes, int n, const cupid_shape *holes, int nh,
                          double h, int parts, int part) {
  cupid_box boxes[4];
  int mats[4];
  for (int b = 0; b < n; b++) boxes[b] = shapes[b].box, mats[b] = b;
  cupid_pd_grid_options o = {.spacing = h, .dimension = 3, .parts = parts, .part = part,
                             .halo_layers = parts > 1 ? 3 : 0, .shapes = shapes, .n_holes = nh,
                             .holes = holes};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, n, boxes, mats, &g));
  return g;
}

static void spheres_and_cylinders(void **state) {
  (void)state;
  const double pi = acos(-1.0);
  for (int fine = 0; fine < 2; fine++) {
    const double h = fine ? 0.5 : 1.0, r = 10.0;
    cupid_shape s = sphere(1.0, 2.0, 3.0, r);
    cupid_pd_grid g = make(&s, 1, NULL, 0, h, 1, 0);
    const cupid_int n = cupid_pd_grid_num_nodes(g);
    const double *x = cupid_pd_grid_coords(g);
    for (cupid_int i = 0; i < n; i++) assert_true(cupid_shape_contains(&s, x + 3 * i));
    const double v = (double)n * h * h * h, exact = 4.0 / 3.0 * pi * r * r * r;
    printf("  sphere r = %g h: %lld nodes, volume %+.3f%%\n", r / h, (long long)n, 100 * (v / exact - 1));
    assert_true(fabs(v / exact - 1) <= (fine ? 0.005 : 0.015));
    /* every cell centre of the lattice inside the sphere is a node */
    double o[3];
    cupid_pd_grid_origin(g, o);
    cupid_int ext[3], inside = 0;
    cupid_pd_grid_extent(g, ext);
    for (cupid_int k = 0; k < ext[2]; k++)
      for (cupid_int j = 0; j < ext[1]; j++)
        for (cupid_int i = 0; i < ext[0]; i++) {
          const double p[3] = {o[0] + (i + 0.5) * h, o[1] + (j + 0.5) * h, o[2] + (k + 0.5) * h};
          inside += cupid_shape_contains(&s, p);
        }
    assert_int_equal(inside, n);
    cupid_pd_grid_destroy(&g);
  }
  cupid_shape c = cylinder(1, 5.0, 5.0, 6.0, 0.0, 20.0);
  cupid_pd_grid g = make(&c, 1, NULL, 0, 1.0, 1, 0);
  const cupid_int n = cupid_pd_grid_num_nodes(g);
  const double *x = cupid_pd_grid_coords(g);
  for (cupid_int i = 0; i < n; i++) {
    const double *p = x + 3 * i;
    assert_true((p[0] - 5) * (p[0] - 5) + (p[2] - 5) * (p[2] - 5) <= 36.0 && p[1] > 0 && p[1] < 20);
  }
  const double v = (double)n, exact = pi * 36.0 * 20.0;
  printf("  cylinder r = 6 h, L = 20 h: %lld nodes, volume %+.3f%%\n", (long long)n, 100 * (v / exact - 1));
  assert_true(fabs(v / exact - 1) <= 0.02);
  cupid_pd_grid_destroy(&g);
}

static void holes_and_mixed(void **state) {
  (void)state;
  const double pi = acos(-1.0);
  cupid_shape plate = box(0, 60, 0, 60, 0, 3), hole = cylinder(2, 30, 30, 8, 1, 0);
  cupid_pd_grid g = make(&plate, 1, &hole, 1, 1.0, 1, 0);
  const cupid_int n = cupid_pd_grid_num_nodes(g);
  const double *x = cupid_pd_grid_coords(g);
  for (cupid_int i = 0; i < n; i++) {
    const double *p = x + 3 * i;
    assert_true((p[0] - 30) * (p[0] - 30) + (p[1] - 30) * (p[1] - 30) > 64.0);
  }
  const double removed = 60.0 * 60.0 * 3.0 - (double)n, exact = pi * 64.0 * 3.0;
  printf("  plate with a hole r = 8 h: %.0f cells removed, %+.2f%% of the hole\n", removed,
         100 * (removed / exact - 1));
  assert_true(fabs(removed / exact - 1) <= 0.05);
  /* two slabs own every node once */
  cupid_int owned = 0;
  for (int part = 0; part < 2; part++) {
    cupid_pd_grid s = make(&plate, 1, &hole, 1, 1.0, 2, part);
    cupid_pd_grid_partition pa;
    cupid_pd_grid_get_partition(s, &pa);
    assert_int_equal(pa.global_nodes, n);
    owned += pa.owned_last - pa.owned_first; /* [owned_first, owned_last): this slab's own */
    cupid_pd_grid_destroy(&s);
  }
  assert_int_equal(owned, n);
  cupid_pd_grid_destroy(&g);

  /* a box and a sphere reaching 2.3 below it: the lattice on the box's planes */
  cupid_shape mixed[2] = {box(0, 10, 0, 10, 0, 10), sphere(5.0, 5.0, 0.7, 3.0)};
  g = make(mixed, 2, NULL, 0, 1.0, 1, 0);
  double o[3];
  cupid_pd_grid_origin(g, o);
  assert_true(fabs(o[0]) < 1e-12 && fabs(o[1]) < 1e-12 && fabs(o[2] + 3.0) < 1e-12);
  const cupid_int m = cupid_pd_grid_num_nodes(g);
  const double *y = cupid_pd_grid_coords(g);
  const int *mat = cupid_pd_grid_materials(g);
  cupid_int below = 0, in_box = 0;
  for (cupid_int i = 0; i < m; i++) {
    const double *p = y + 3 * i;
    const int boxed = p[0] > 0 && p[0] < 10 && p[1] > 0 && p[1] < 10 && p[2] > 0 && p[2] < 10;
    assert_int_equal(mat[i], boxed ? 0 : 1);
    below += p[2] < 0;
    in_box += boxed;
    const double f = p[2] - floor(p[2]); /* cell centres on the box's lattice */
    assert_true(fabs(f - 0.5) < 1e-12);
  }
  assert_int_equal(in_box, 1000);
  assert_true(below > 0);
  cupid_pd_grid_destroy(&g);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(spheres_and_cylinders),
                                     cmocka_unit_test(holes_and_mixed)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
