/* Patch tests of the fictitious-node coupling with PD regions over part of the cross-section
 * (interfaces parallel to the beam axis, paper 000 section 4.4): a 12 x 12 section of 3 x 3 LE
 * elements, beam FE [0,6] | [6,12] | [12,18] (y), the PD region (h = 1) replacing some section
 * elements over y in [6, 12]:
 *  - middle: x, z in [4, 8] (four parallel interfaces and their edges, no outer face);
 *  - corner: x, z in [0, 4] (two parallel interfaces meeting at an edge, two outer faces);
 *  - strip: x in [0, 12], z in [4, 8] (two parallel interfaces, cut across the section);
 *  - two corners: [0, 4]^2 and [8, 12]^2 (two regions, as the panel's two stringers).
 * Checks, for an affine field:
 *  - every real PD row equals the force of an all-PD block (the fictitious PD nodes carry the
 *    exact field), hence 0 on nodes with complete 2 delta families: no ghost forces;
 *  - every row of a real FE node equals the row of the full FE model (the removed section
 *    elements are fed the exact field from the PD nodes), hence 0 away from the outer surface;
 *  - solve (nu = 0, uniaxial traction field, exact for FE and PD): ends and PD nodes within
 *    2 delta of the outer faces prescribed (their PD surface effect is not part of the
 *    coupling), the coupled solve reproduces the field.
 * Tolerances: 1e-10 relative (round-off of sums of ~1e3 terms of mixed sign; condition of these
 * small systems ~1e4). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cupid/coupling.h"
#include "test_cuf_common.h"

#define XW 12.0
#define YL 18.0
#define FSCALE (1000.0 * 1e-3) /* E * strain * cell area */

typedef struct {
  int le_nodes, p;
  cupid_pd_model_kind kind;
  double delta, nu;
  double lo[2], hi[2]; /* region x, z */
  int two;             /* a second region: x, z in [8, 12] (as the panel's two stringers) */
} par_case;

typedef struct {
  tb_beam tb;
  cupid_cuf_beam beam, full_beam;
  cupid_pd_grid grid, full;
  cupid_pd_operator full_op;
  cupid_pd_material mat;
  cupid_pd_operator_options pdo;
  cupid_coupling_h cpl;
  cupid_csr K, Kfe;
  cupid_box region[2];
  int region_mat[2], n_regions;
  cupid_int n_pd, ndof;
} par_model;

static void build(par_model *m, const par_case *pc) {
  memset(m, 0, sizeof *m);
  tb_init(&m->tb, 1000.0, pc->nu);
  tb_le(&m->tb, pc->le_nodes);
  tb_rect(&m->tb, 0, XW, 3, 0, XW, 3, -1);
  static const double axes[4] = {0, 6, 12, YL};
  tb_axis_spans(&m->tb, 4, axes);
  m->tb.def.element_nodes = pc->p;
  m->beam = tb_create(&m->tb);
  m->full_beam = tb_create(&m->tb);
  CUPID_ASSERT_OK(cupid_cuf_assemble(m->full_beam, &m->Kfe));

  m->region[0] = (cupid_box){.lo = {pc->lo[0], 6, pc->lo[1]},
                             .hi = {pc->hi[0], 12, pc->hi[1]},
                             .has = {1, 1, 1}};
  m->region[1] = (cupid_box){.lo = {8, 6, 8}, .hi = {12, 12, 12}, .has = {1, 1, 1}};
  m->n_regions = pc->two ? 2 : 1;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, m->n_regions, m->region, m->region_mat, &m->grid));
  m->n_pd = cupid_pd_grid_num_nodes(m->grid);
  CUPID_ASSERT_OK(cupid_coupling_deactivate(m->beam, m->n_regions, m->region));
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(m->beam, 3 * m->n_pd));
  m->ndof = 3 * m->n_pd + cupid_cuf_num_dofs(m->beam);

  m->mat = (cupid_pd_material){.E = 1000.0, .nu = pc->nu};
  m->pdo = (cupid_pd_operator_options){.horizon = pc->delta,
                                       .model = pc->kind,
                                       .influence = CUPID_INFLUENCE_GAUSSIAN,
                                       .partial_volume = CUPID_PARTIAL_PDLAMMPS,
                                       .materials = &m->mat,
                                       .n_materials = 1};
  cupid_coupling_options co = {.beam_def = &m->tb.def,
                               .materials = m->tb.mat,
                               .n_materials = m->tb.n_mat,
                               .n_regions = m->n_regions,
                               .regions = m->region,
                               .region_materials = m->region_mat,
                               .spacing = 1.0,
                               .pd = m->pdo};
  CUPID_ASSERT_OK(cupid_coupling_create(m->beam, m->grid, &co, &m->cpl, &m->K));
  assert_int_equal(m->K->nrows, m->ndof / 3);
  cupid_coupling_info ci;
  cupid_coupling_get_info(m->cpl, &ci);
  printf("  %lld real PD, %lld fictitious PD, %d interfaces, %lld fictitious FE nodes\n",
         (long long)ci.n_real_pd, (long long)ci.n_fictitious_pd, ci.n_interfaces,
         (long long)ci.n_fictitious_fe);
  /* B3/B4 put beam nodes inside the region: the removed pairs have fictitious FE nodes. */
  assert_true(ci.n_fictitious_pd > 0 && ci.n_fictitious_fe > 0);

  cupid_box whole = {.lo = {0, 0, 0}, .hi = {XW, YL, XW}, .has = {1, 1, 1}};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &whole, m->region_mat, &m->full));
  CUPID_ASSERT_OK(cupid_pd_operator_create(m->full, &m->pdo, &m->full_op));
}

static void destroy(par_model *m) {
  cupid_coupling_destroy(&m->cpl);
  cupid_csr_destroy(&m->K);
  cupid_csr_destroy(&m->Kfe);
  cupid_pd_operator_destroy(&m->full_op);
  cupid_pd_grid_destroy(&m->full);
  cupid_pd_grid_destroy(&m->grid);
  cupid_cuf_beam_destroy(&m->beam);
  cupid_cuf_beam_destroy(&m->full_beam);
}


static void field_vector(const par_model *m, const cupid_test_affine *a, double *u) {
  memset(u, 0, (size_t)m->ndof * sizeof *u);
  const double *x = cupid_pd_grid_coords(m->grid);
  for (cupid_int i = 0; i < m->n_pd; i++) cupid_test_affine_eval(a, x + 3 * i, u + 3 * i);
  CUPID_ASSERT_OK(cupid_cuf_interpolate(m->beam, cupid_test_affine_fn, (void *)a, u));
}

static cupid_int full_node(const par_model *m, const double *x) {
  cupid_int ijk[3];
  for (int d = 0; d < 3; d++) ijk[d] = (cupid_int)floor(x[d]);
  cupid_int j = cupid_pd_grid_node_at(m->full, ijk[0], ijk[1], ijk[2]);
  assert_true(j >= 0);
  return j;
}

/* Max |coupled row - reference row| over real PD nodes and real FE nodes for field a. */
static void compare_rows(const par_model *m, const cupid_test_affine *a, double *worst_pd, double *worst_fe,
                         double *worst_interior) {
  cupid_int nf = cupid_pd_grid_num_nodes(m->full);
  cupid_cuf_info info;
  cupid_cuf_get_info(m->beam, &info);
  double *u = NULL, *f = NULL, *uf = NULL, *ff = NULL, *fe = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)m->ndof, sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_calloc((size_t)m->ndof, sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_calloc((size_t)(3 * nf), sizeof *uf, "uf", &uf));
  CUPID_ASSERT_OK(cupid_calloc((size_t)(3 * nf), sizeof *ff, "ff", &ff));
  CUPID_ASSERT_OK(cupid_calloc((size_t)info.n_dofs, sizeof *fe, "fe", &fe));
  field_vector(m, a, u);
  cupid_csr_matvec(m->K, u, f);
  const double *xf = cupid_pd_grid_coords(m->full);
  for (cupid_int i = 0; i < nf; i++) cupid_test_affine_eval(a, xf + 3 * i, uf + 3 * i);
  CUPID_ASSERT_OK(cupid_pd_operator_apply(m->full_op, uf, ff));
  cupid_csr_matvec(m->Kfe, u + 3 * m->n_pd, fe);
  const double *x = cupid_pd_grid_coords(m->grid);
  *worst_pd = *worst_fe = *worst_interior = 0.0;
  for (cupid_int i = 0; i < m->n_pd; i++) {
    cupid_int j = full_node(m, x + 3 * i);
    for (int c = 0; c < 3; c++) *worst_pd = fmax(*worst_pd, fabs(f[3 * i + c] - ff[3 * j + c]));
  }
  for (cupid_int n = 0; n < info.n_fe_nodes; n++) {
    int tau = (int)(n % info.M);
    cupid_int bn = n / info.M;
    if (!cupid_cuf_node_used(m->beam, tau, bn)) continue;
    double xz[2], hh, y = cupid_cuf_beam_node_y(m->beam, bn);
    cupid_cuf_section_node(m->beam, tau, xz, &hh);
    int inner = y > 1e-9 && y < YL - 1e-9 && xz[0] > 1e-9 && xz[0] < XW - 1e-9 &&
                xz[1] > 1e-9 && xz[1] < XW - 1e-9;
    for (int c = 0; c < 3; c++) {
      double fc = f[3 * m->n_pd + 3 * n + c];
      *worst_fe = fmax(*worst_fe, fabs(fc - fe[3 * n + c]));
      if (inner) *worst_interior = fmax(*worst_interior, fabs(fc));
    }
  }
  cupid_free(&u);
  cupid_free(&f);
  cupid_free(&uf);
  cupid_free(&ff);
  cupid_free(&fe);
}

static void check_case(const par_case *pc) {
  par_model m;
  build(&m, pc);
  cupid_cuf_info info;
  cupid_cuf_get_info(m.beam, &info);
  double wpd, wfe, wint;
  cupid_test_affine a = cupid_test_random_affine(11);
  compare_rows(&m, &a, &wpd, &wfe, &wint);
  printf("  cupid_test_affine: PD rows vs all-PD %.2e, FE rows vs full FE %.2e, interior FE |f| %.2e "
         "(scale %.1e)\n", wpd, wfe, wint, FSCALE);
  assert_true(wpd <= 1e-10 * FSCALE);
  assert_true(wfe <= 1e-10 * FSCALE * XW * XW);
  assert_true(wint <= 1e-10 * FSCALE * XW * XW);

  /* Solve: nu = 0 uniaxial traction field u_y = e y (traction-free lateral faces). */
  cupid_test_affine b;
  memset(&b, 0, sizeof b);
  b.B[1][1] = 1e-3;
  b.c[1] = 2e-4;
  b.B[1][0] = 0.0;
  double *u = NULL, *sol = NULL, *zero = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)m.ndof, sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_calloc((size_t)m.ndof, sizeof *sol, "sol", &sol));
  CUPID_ASSERT_OK(cupid_calloc((size_t)m.ndof, sizeof *zero, "zero", &zero));
  field_vector(&m, &b, u);
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(m.ndof, &bc));
  const double *x = cupid_pd_grid_coords(m.grid);
  cupid_int n_free_pd = 0;
  for (cupid_int i = 0; i < m.n_pd; i++) {
    int outer = 0;
    for (int d = 0; d < 3; d += 2)
      outer |= x[3 * i + d] < 2 * pc->delta || x[3 * i + d] > XW - 2 * pc->delta;
    if (outer)
      for (int c = 0; c < 3; c++) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 3 * i + c, u[3 * i + c]));
    else
      n_free_pd++;
  }
  assert_true(n_free_pd > 0);
  for (cupid_int n = 0; n < info.n_fe_nodes; n++) {
    cupid_int bn = n / info.M;
    double y = cupid_cuf_beam_node_y(m.beam, bn);
    int used = cupid_cuf_node_used(m.beam, (int)(n % info.M), bn);
    if (y < 1e-9 || y > YL - 1e-9 || !used)
      for (int c = 0; c < 3; c++) {
        cupid_int d = 3 * m.n_pd + 3 * n + c;
        CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, d, used ? u[d] : 0.0));
      }
  }
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  cupid_solve_info si;
  CUPID_ASSERT_OK(cupid_direct_solve(m.K, CUPID_MATRIX_GENERAL, zero, bc, sol, &si));
  double err = 0.0, umax = 0.0;
  for (cupid_int d = 0; d < m.ndof; d++) {
    if (d >= 3 * m.n_pd) {
      cupid_int n = (d - 3 * m.n_pd) / 3;
      if (!cupid_cuf_node_used(m.beam, (int)(n % info.M), n / info.M)) continue;
    }
    err = fmax(err, fabs(sol[d] - u[d]));
    umax = fmax(umax, fabs(u[d]));
  }
  printf("  solve: %lld free PD nodes, max |u - u_exact| / max |u| = %.2e\n",
         (long long)n_free_pd, err / umax);
  assert_true(err <= 1e-10 * umax);
  cupid_dirichlet_destroy(&bc);
  cupid_free(&u);
  cupid_free(&sol);
  cupid_free(&zero);
  destroy(&m);
}

static void middle_l9_lps(void **state) {
  (void)state;
  check_case(&(par_case){.le_nodes = 9, .p = 3, .kind = CUPID_PD_LPS, .delta = 1.5, .nu = 0.0,
                         .lo = {4, 4}, .hi = {8, 8}});
}
static void middle_l9_b4_bond(void **state) {
  (void)state;
  check_case(&(par_case){.le_nodes = 9, .p = 4, .kind = CUPID_PD_BOND, .delta = 1.5, .nu = 0.0,
                         .lo = {4, 4}, .hi = {8, 8}});
}
static void corner_l4_b3_lps(void **state) {
  (void)state;
  check_case(&(par_case){.le_nodes = 4, .p = 3, .kind = CUPID_PD_LPS, .delta = 1.5, .nu = 0.0,
                         .lo = {0, 0}, .hi = {4, 4}});
}
static void strip_l9_lps(void **state) {
  (void)state;
  check_case(&(par_case){.le_nodes = 9, .p = 3, .kind = CUPID_PD_LPS, .delta = 1.5, .nu = 0.0,
                         .lo = {0, 4}, .hi = {12, 8}});
}

static void two_corners_l9_b4_lps(void **state) {
  (void)state;
  check_case(&(par_case){.le_nodes = 9, .p = 4, .kind = CUPID_PD_LPS, .delta = 1.5, .nu = 0.0,
                         .lo = {0, 0}, .hi = {4, 4}, .two = 1});
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(middle_l9_lps),
      cmocka_unit_test(middle_l9_b4_bond),
      cmocka_unit_test(corner_l4_b3_lps),
      cmocka_unit_test(strip_l9_lps),
      cmocka_unit_test(two_corners_l9_b4_lps),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
