/* Fracture with fictitious nodes (issue 34): the coupled operator's own PD operator on the
 * extended grid loses exactly the bonds the model grid's operator loses, and bonds broken
 * outside the coupling zone leave the rest of paper 000's Eq. 38 as it was. A bar-like beam
 * (LE section 4 x 4, one L9 element; axis [0, 6] FE | [6, 30] PD | [30, 36] FE) with a pre-crack
 * half through the section at y = 18, bond-based (delta = 3.015, whole cells) and LPS
 * (delta = 2, EXACT partial volumes: the wider families). Checks:
 *  - the coupling zone (cupid_coupling_operator_zone) is, bond-based, exactly the real nodes
 *    within delta of a fictitious node: the three layers next to each interface plane;
 *  - after cupid_pd_operator_copy_broken_mapped, K_cracked - K_intact of the coupled matrix
 *    (cupid_coupling_operator_assemble(A, NULL)) equals the model grid's PD matrix change
 *    on the real PD rows and columns, and is zero on every FE row and FE column, to 1e-12 of
 *    max |K| (round-off of sums of ~10^2 terms): the fits of Eqs. 33-36 and the fictitious
 *    columns do not change;
 *  - that change annihilates the rigid modes from both sides (|dK R| <= 1e-12 |K| |R|), so the
 *    balance's C = K^T R is unchanged (docs/theory.md, "Fracture with fictitious nodes");
 *  - the negative control: LPS, a pre-crack through the coupling zone (y = 7) does change FE
 *    columns (by more than 1e-6 of max |K|: the dilatations of nodes whose families hold
 *    fictitious nodes), which is why the zone's bonds never break; bond-based, a bond's pair
 *    term reaches its two real nodes only (no FE change), and the zone keeps the crack away
 *    from the interface, whose bonds to fictitious nodes cannot break;
 *  - a wrong map, or operators of two horizons, are ARGUMENT errors. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cupid/coupling.h"
#include "test_cuf_common.h"

typedef struct {
  tb_beam tb;
  cupid_cuf_beam beam;
  cupid_pd_grid grid;
  cupid_pd_material mat;
  cupid_coupling_options co;
  cupid_box region;
  int region_mat;
  cupid_int n_pd;
} fr_model;

static void build(fr_model *m, cupid_pd_model_kind kind, cupid_partial_volume pv, double delta) {
  memset(m, 0, sizeof *m);
  tb_init(&m->tb, 1000.0, 0.25);
  tb_le(&m->tb, 9);
  tb_rect(&m->tb, 0, 4, 1, 0, 4, 1, -1);
  static const double axes[4] = {0, 6, 30, 36};
  tb_axis_spans(&m->tb, 4, axes);
  m->tb.def.element_nodes = 3;
  m->beam = tb_create(&m->tb);
  m->region = (cupid_box){.lo = {0, 6, 0}, .hi = {4, 30, 4}, .has = {1, 1, 1}};
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &m->region, &m->region_mat, &m->grid));
  m->n_pd = cupid_pd_grid_num_nodes(m->grid);
  CUPID_ASSERT_OK(cupid_coupling_deactivate(m->beam, 1, &m->region));
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(m->beam, 3 * m->n_pd));
  m->mat = (cupid_pd_material){.E = 1000.0, .nu = 0.25};
  m->co = (cupid_coupling_options){.beam_def = &m->tb.def,
                                   .materials = m->tb.mat,
                                   .n_materials = m->tb.n_mat,
                                   .n_regions = 1,
                                   .regions = &m->region,
                                   .region_materials = &m->region_mat,
                                   .spacing = 1.0,
                                   .pd = {.horizon = delta,
                                          .model = kind,
                                          .influence = CUPID_INFLUENCE_CONSTANT,
                                          .partial_volume = pv,
                                          .materials = &m->mat,
                                          .n_materials = 1}};
}

static void destroy(fr_model *m) {
  cupid_pd_grid_destroy(&m->grid);
  cupid_cuf_beam_destroy(&m->beam);
}

static double max_abs(const cupid_csr_t *K) {
  double t = 0.0;
  for (cupid_int k = 0; k < K->rowptr[K->nrows] * 9; k++) t = fmax(t, fabs(K->val[k]));
  return t;
}

static const double *block(const cupid_csr_t *K, cupid_int r, cupid_int c) {
  return cupid_csr_find((cupid_csr_t *)K, r, c);
}

/* max over the blocks of K1 and K0 of |K1 - K0 - E| where E is dP (P1 - P0, the model grid's
 * PD change) on PD rows and columns (both < n_pd), else 0; *fe_change: the largest |K1 - K0|
 * in an FE row or FE column. */
static double change_error(const cupid_csr_t *K0, const cupid_csr_t *K1, const cupid_csr_t *P0,
                           const cupid_csr_t *P1, cupid_int n_pd, double *fe_change) {
  double err = 0.0;
  *fe_change = 0.0;
  for (int pass = 0; pass < 2; pass++) { /* the blocks of K1, then those of K0 not in K1 */
    const cupid_csr_t *A = pass ? K0 : K1;
    for (cupid_int r = 0; r < A->nrows; r++)
      for (cupid_int k = A->rowptr[r]; k < A->rowptr[r + 1]; k++) {
        const cupid_int c = A->col[k];
        if (pass && block(K1, r, c)) continue;
        const double *a = block(K1, r, c), *b = block(K0, r, c);
        const int pd = r < n_pd && c < n_pd;
        const double *p1 = pd ? block(P1, r, c) : NULL, *p0 = pd ? block(P0, r, c) : NULL;
        for (int e = 0; e < 9; e++) {
          const double d = (a ? a[e] : 0.0) - (b ? b[e] : 0.0);
          const double want = (p1 ? p1[e] : 0.0) - (p0 ? p0[e] : 0.0);
          err = fmax(err, fabs(d - want));
          if (!pd) *fe_change = fmax(*fe_change, fabs(d));
        }
      }
  }
  return err;
}

/* The six rigid modes at the real PD nodes (3 n_pd each). */
static void rigid_pd(const fr_model *m, double *R) {
  const double *x = cupid_pd_grid_coords(m->grid);
  const cupid_int n = 3 * m->n_pd;
  memset(R, 0, 6 * (size_t)n * sizeof *R);
  for (cupid_int i = 0; i < m->n_pd; i++) {
    const double *p = x + 3 * i;
    for (int k = 0; k < 3; k++) R[k * n + 3 * i + k] = 1.0;
    for (int a = 0; a < 3; a++) { /* e_a x p */
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      R[(3 + a) * n + 3 * i + c] = p[b];
      R[(3 + a) * n + 3 * i + b] = -p[c];
    }
  }
}

static void check_crack(cupid_pd_model_kind kind, cupid_partial_volume pv, double delta) {
  fr_model m;
  build(&m, kind, pv, delta);
  cupid_coupling_operator A = NULL;
  cupid_pd_operator op = NULL;
  cupid_csr K0 = NULL, K1 = NULL, P0 = NULL, P1 = NULL;
  unsigned char *zone = NULL;
  CUPID_ASSERT_OK(cupid_coupling_operator_create(m.beam, m.grid, &m.co, &A));
  CUPID_ASSERT_OK(cupid_pd_operator_create(m.grid, &m.co.pd, &op));
  CUPID_ASSERT_OK(cupid_calloc((size_t)m.n_pd, 1, "zone", &zone));
  CUPID_ASSERT_OK(cupid_coupling_operator_zone(A, NULL, zone));
  const double *x = cupid_pd_grid_coords(m.grid);
  cupid_int in_zone = 0;
  for (cupid_int i = 0; i < m.n_pd; i++) {
    const double y = x[3 * i + 1];
    in_zone += zone[i];
    if (kind == CUPID_PD_BOND && pv == CUPID_PARTIAL_NONE) /* 3 layers at each end */
      assert_int_equal(zone[i], y < 9.0 || y > 27.0);
  }
  assert_true(in_zone > 0 && in_zone < m.n_pd);

  CUPID_ASSERT_OK(cupid_coupling_operator_assemble(A, NULL, &K0));
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(op, &P0));
  /* half through the section, far from the zone */
  cupid_pd_precrack c = {.normal = 1, .at = 18.0, .lo = {0, 0, 0}, .hi = {2, 0, 4}};
  cupid_int removed = 0;
  CUPID_ASSERT_OK(cupid_pd_operator_precrack(op, &c, &removed));
  assert_true(removed > 10);
  CUPID_ASSERT_OK(cupid_pd_operator_copy_broken_mapped(cupid_coupling_operator_pd(A), op,
                                                       cupid_coupling_operator_extended_nodes(A)));
  assert_int_equal(cupid_pd_operator_num_broken(cupid_coupling_operator_pd(A)), removed);
  /* a second copy adds nothing */
  CUPID_ASSERT_OK(cupid_pd_operator_copy_broken_mapped(cupid_coupling_operator_pd(A), op,
                                                       cupid_coupling_operator_extended_nodes(A)));
  assert_int_equal(cupid_pd_operator_num_broken(cupid_coupling_operator_pd(A)), removed);
  CUPID_ASSERT_OK(cupid_coupling_operator_assemble(A, NULL, &K1));
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(op, &P1));
  const double scale = max_abs(K0);
  double fe_change = 0.0;
  const double err = change_error(K0, K1, P0, P1, m.n_pd, &fe_change);
  printf("  %s: %lld bonds cut, %lld of %lld PD nodes in the zone; |dK - dP| %.2e, FE change "
         "%.2e of max |K| %.3g\n",
         kind == CUPID_PD_LPS ? "LPS" : "bond", (long long)removed, (long long)in_zone,
         (long long)m.n_pd, err / scale, fe_change / scale, scale);
  assert_true(err <= 1e-12 * scale);
  assert_true(fe_change <= 1e-12 * scale);

  /* dP annihilates the rigid modes: C = K^T R does not change */
  const cupid_int n = 3 * m.n_pd;
  double *R = NULL, *y0 = NULL, *y1 = NULL;
  CUPID_ASSERT_OK(cupid_calloc(6 * (size_t)n, sizeof *R, "rigid modes", &R));
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *y0, "products", &y0));
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *y1, "products", &y1));
  rigid_pd(&m, R);
  for (int k = 0; k < 6; k++) {
    double rn = 0.0, dn = 0.0;
    cupid_csr_matvec(P0, R + k * n, y0);
    cupid_csr_matvec(P1, R + k * n, y1);
    for (cupid_int d = 0; d < n; d++) rn = fmax(rn, fabs(R[k * n + d])), dn = fmax(dn, fabs(y1[d] - y0[d]));
    cupid_csr_matvec_transpose(P0, R + k * n, y0);
    cupid_csr_matvec_transpose(P1, R + k * n, y1);
    for (cupid_int d = 0; d < n; d++) dn = fmax(dn, fabs(y1[d] - y0[d]));
    assert_true(dn <= 1e-12 * scale * rn * 100.0); /* a row holds ~10^2 blocks */
  }
  cupid_free(&R);
  cupid_free(&y0);
  cupid_free(&y1);

  /* the negative control: a crack through the zone changes the FE columns */
  cupid_coupling_operator A2 = NULL;
  cupid_pd_operator op2 = NULL;
  cupid_csr K2 = NULL, P2 = NULL;
  CUPID_ASSERT_OK(cupid_coupling_operator_create(m.beam, m.grid, &m.co, &A2));
  CUPID_ASSERT_OK(cupid_pd_operator_create(m.grid, &m.co.pd, &op2));
  cupid_pd_precrack cz = {.normal = 1, .at = 7.0, .lo = {0, 0, 0}, .hi = {2, 0, 4}};
  CUPID_ASSERT_OK(cupid_pd_operator_precrack(op2, &cz, &removed));
  CUPID_ASSERT_OK(cupid_pd_operator_copy_broken_mapped(cupid_coupling_operator_pd(A2), op2,
                                                       cupid_coupling_operator_extended_nodes(A2)));
  CUPID_ASSERT_OK(cupid_coupling_operator_assemble(A2, NULL, &K2));
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(op2, &P2));
  change_error(K0, K2, P0, P2, m.n_pd, &fe_change);
  printf("  a crack in the zone: FE change %.2e of max |K|\n", fe_change / scale);
  if (kind == CUPID_PD_LPS) assert_true(fe_change > 1e-6 * scale);
  else assert_true(fe_change == 0.0); /* a bond's own pair term: real columns only */

  /* a map that does not carry the bonds onto the extended grid, and two horizons */
  cupid_int *bad = NULL;
  CUPID_ASSERT_OK(cupid_malloc((size_t)m.n_pd, sizeof *bad, "map", &bad));
  const cupid_int *map = cupid_coupling_operator_extended_nodes(A);
  for (cupid_int i = 0; i < m.n_pd; i++) bad[i] = map[m.n_pd - 1 - i]; /* a point reflection */
  cupid_coupling_operator A3 = NULL;
  CUPID_ASSERT_OK(cupid_coupling_operator_create(m.beam, m.grid, &m.co, &A3));
  assert_int_equal(cupid_pd_operator_copy_broken_mapped(cupid_coupling_operator_pd(A3), op, bad),
                   CUPID_ERR_ARGUMENT);
  cupid_error_clear();
  cupid_pd_operator_options other = m.co.pd;
  other.horizon = delta + 1.0;
  cupid_pd_operator wide = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(m.grid, &other, &wide));
  assert_int_equal(cupid_pd_operator_copy_broken_mapped(wide, op, NULL), CUPID_ERR_ARGUMENT);
  cupid_error_clear();

  cupid_pd_operator_destroy(&wide);
  cupid_free(&bad);
  cupid_coupling_operator_destroy(&A3);
  cupid_csr_destroy(&K2);
  cupid_csr_destroy(&P2);
  cupid_pd_operator_destroy(&op2);
  cupid_coupling_operator_destroy(&A2);
  cupid_free(&zone);
  cupid_csr_destroy(&K0);
  cupid_csr_destroy(&K1);
  cupid_csr_destroy(&P0);
  cupid_csr_destroy(&P1);
  cupid_pd_operator_destroy(&op);
  cupid_coupling_operator_destroy(&A);
  destroy(&m);
}

static void bond_based(void **state) {
  (void)state;
  check_crack(CUPID_PD_BOND, CUPID_PARTIAL_NONE, 3.015);
}

static void lps_exact(void **state) {
  (void)state;
  check_crack(CUPID_PD_LPS, CUPID_PARTIAL_EXACT, 2.0);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(bond_based), cmocka_unit_test(lps_exact)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
