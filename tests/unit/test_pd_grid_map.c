/* A grid that grows on its lattice (issue 37's adaptive zones: src/pd/grid.c, has_anchor and
 * cupid_pd_grid_map_nodes) and the bonds its operator takes from the old one
 * (cupid_pd_operator_copy_broken_mapped). Checks:
 *  - anchored at the old grid's origin, a grown grid with boxes off the lattice (cells whose
 *    centres lie in them) keeps the old nodes at the same coordinates (exactly): every old
 *    node maps to a new one there, and the new grid has the extra cells' nodes (counted);
 *  - without the anchor the same boxes are refused (their bounds are off the lattice), and
 *    with it, bounds on the lattice give the same grid as without;
 *  - a pre-crack in the old operator copied onto the grown one removes the same bonds (their
 *    count, and each one absent in the new operator at the mapped pair), and the rows of K of
 *    the old nodes whose two-hop reach (2 delta, LPS) sees nothing new are the old ones to
 *    1e-13 (the same families, volumes and broken bonds);
 *  - grids on different lattices are refused by the map. */
#include <math.h>
#include <stdlib.h>

#include "cupid/pd.h"
#include "testutil.h"

static cupid_box box3(double x0, double x1, double y0, double y1, double z0, double z1) {
  cupid_box b = {.lo = {x0, y0, z0}, .hi = {x1, y1, z1}, .has = {1, 1, 1}};
  return b;
}

static cupid_pd_grid grid(int n, const cupid_box *boxes, int anchored, const double anchor[3]) {
  int mats[4] = {0, 0, 0, 0};
  cupid_pd_grid_options o = {.spacing = 1.0, .dimension = 3, .has_anchor = anchored};
  for (int a = 0; a < 3 && anchor; a++) o.anchor[a] = anchor[a];
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, n, boxes, mats, &g));
  return g;
}

/* The block (r, c) of K, or NULL. */
static const double *block(const cupid_csr_t *K, cupid_int r, cupid_int c) {
  for (cupid_int q = K->rowptr[r]; q < K->rowptr[r + 1]; q++)
    if (K->col[q] == c) return K->val + 9 * q;
  return NULL;
}

static void grown_grid(void **state) {
  (void)state;
  const cupid_box old_box = box3(0, 8, 0, 12, 0, 6);
  const double anchor[3] = {0, 0, 0};
  cupid_pd_grid a = grid(1, &old_box, 0, NULL);
  /* grown along y (to 17.3: cells up to the centre 16.5) and down x (from -1.7: centres -1.5
   * and -0.5) */
  const cupid_box grown[3] = {old_box, box3(0, 8, 12, 17.3, 0, 6), box3(-1.7, 0, 0, 12, 0, 6)};
  cupid_pd_grid b = grid(3, grown, 1, anchor);
  const cupid_int na = cupid_pd_grid_num_nodes(a), nb = cupid_pd_grid_num_nodes(b);
  assert_int_equal(nb, na + 8 * 5 * 6 + 2 * 12 * 6);
  cupid_int *map = malloc(sizeof *map * (size_t)na);
  CUPID_ASSERT_OK(cupid_pd_grid_map_nodes(a, b, map));
  const double *xa = cupid_pd_grid_coords(a), *xb = cupid_pd_grid_coords(b);
  for (cupid_int i = 0; i < na; i++) {
    assert_true(map[i] >= 0);
    for (int c = 0; c < 3; c++) assert_true(xa[3 * i + c] == xb[3 * map[i] + c]);
  }
  /* off-lattice bounds without the anchor: refused; on-lattice with it: the same grid */
  cupid_pd_grid bad = NULL;
  int mats[3] = {0, 0, 0};
  cupid_pd_grid_options plain = {.spacing = 1.0, .dimension = 3};
  assert_int_equal(cupid_pd_grid_create(&plain, 3, grown, mats, &bad), CUPID_ERR_MODEL);
  cupid_pd_grid same = grid(1, &old_box, 1, anchor);
  assert_int_equal(cupid_pd_grid_num_nodes(same), na);
  const double *xs = cupid_pd_grid_coords(same);
  for (cupid_int i = 0; i < 3 * na; i++) assert_true(xs[i] == xa[i]);
  cupid_pd_grid_destroy(&same);

  /* a pre-crack copied onto the grown operator */
  cupid_pd_material mat = {.E = 1000.0, .nu = 0.25};
  cupid_pd_operator_options o = {.horizon = 2.015, .model = CUPID_PD_LPS,
                                 .influence = CUPID_INFLUENCE_GAUSSIAN,
                                 .partial_volume = CUPID_PARTIAL_PDLAMMPS, .materials = &mat,
                                 .n_materials = 1};
  cupid_pd_operator opa = NULL, opb = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(a, &o, &opa));
  CUPID_ASSERT_OK(cupid_pd_operator_create(b, &o, &opb));
  cupid_pd_precrack crack = {.normal = 1, .at = 6.0, .lo = {0, 0, 0}, .hi = {3.5, 0, 6}};
  cupid_int removed = 0;
  CUPID_ASSERT_OK(cupid_pd_operator_precrack(opa, &crack, &removed));
  assert_true(removed > 0);
  CUPID_ASSERT_OK(cupid_pd_operator_copy_broken_mapped(opb, opa, map));
  assert_int_equal(cupid_pd_operator_num_broken(opb), cupid_pd_operator_num_broken(opa));
  for (cupid_int i = 0; i < na; i++)
    for (cupid_int j = i + 1; j < na; j++)
      if (fabs(xa[3 * i + 1] - xa[3 * j + 1]) < 2.1 && fabs(xa[3 * i] - xa[3 * j]) < 2.1 &&
          fabs(xa[3 * i + 2] - xa[3 * j + 2]) < 2.1)
        assert_int_equal(cupid_pd_operator_bond_intact(opb, map[i], map[j]),
                         cupid_pd_operator_bond_intact(opa, i, j));
  cupid_csr Ka = NULL, Kb = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(opa, &Ka));
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(opb, &Kb));
  double kmax = 0.0;
  for (cupid_int q = 0; q < 9 * Ka->rowptr[na]; q++) kmax = fmax(kmax, fabs(Ka->val[q]));
  cupid_int rows = 0;
  for (cupid_int i = 0; i < na; i++) {
    const double *p = xa + 3 * i;
    /* two horizons (4.03) from the new cells (y >= 12, x <= 0) */
    if (!(p[1] < 12 - 4.03 && p[0] > 4.03)) continue;
    rows++;
    assert_int_equal(Ka->rowptr[i + 1] - Ka->rowptr[i], Kb->rowptr[map[i] + 1] - Kb->rowptr[map[i]]);
    for (cupid_int q = Ka->rowptr[i]; q < Ka->rowptr[i + 1]; q++) {
      const double *B = block(Kb, map[i], map[Ka->col[q]]);
      assert_non_null(B);
      for (int k = 0; k < 9; k++) assert_true(fabs(B[k] - Ka->val[9 * q + k]) <= 1e-13 * kmax);
    }
  }
  assert_true(rows > 0);
  cupid_csr_destroy(&Ka);
  cupid_csr_destroy(&Kb);
  cupid_pd_operator_destroy(&opa);
  cupid_pd_operator_destroy(&opb);

  /* another lattice: refused */
  const double half[3] = {0.5, 0, 0};
  cupid_pd_grid c = grid(1, &old_box, 1, half);
  assert_int_equal(cupid_pd_grid_map_nodes(a, c, map), CUPID_ERR_ARGUMENT);
  cupid_pd_grid_destroy(&c);
  free(map);
  cupid_pd_grid_destroy(&a);
  cupid_pd_grid_destroy(&b);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(grown_grid)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
