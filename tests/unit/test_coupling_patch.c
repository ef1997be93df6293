/* Patch tests of the fictitious-node coupling (paper 000, section 4): a bar
 * FE [0,6] | PD [6,12] | FE [12,18], section 8 x 8, h = 1 (and the layouts of patch_case).
 * Every kind of fictitious FE element (cupid_fictitious_fe: the removed element, the adjacent
 * element's copy, the h/2 element to the nearest plane, a given length) on a mesh where they
 * differ (FE [0,4] | PD [4,12] | FE [12,18], B4: fictitious nodes between PD planes and on the
 * region's far face, where their sections are interpolated / extrapolated from two planes).
 *  - Ghost forces: for an affine field the coupled force on every real PD node equals the
 *    force of an all-PD bar (the fictitious nodes carry the exact field), which is zero on
 *    nodes with complete 2 delta families; for the uniaxial-stress field (traction-free
 *    lateral faces, an exact FE solution) the force on every FE DOF away from the ends is 0.
 *  - Solve: with the ends and the PD nodes near the lateral faces prescribed (their PD
 *    surface effect is not part of the coupling), the coupled solve reproduces the affine
 *    field to round-off.
 * Tolerances: 1e-10 relative (round-off of sums of ~1e3 terms of mixed sign, condition of the
 * small systems ~1e4). */
#define _POSIX_C_SOURCE 200809L /* setenv */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cupid/coupling.h"
#include "test_cuf_common.h"

#define XW 8.0
#define YL 18.0

typedef struct {
  int te;          /* TE order, or 0 for LE */
  int le_nodes, le_n; /* LE: element type, elements per side */
  int p;           /* beam element nodes */
  cupid_pd_model_kind kind;
  double delta;
  double nu;
  int layout;      /* 0: FE|PD|FE on [0,6,12,18]; 1: two PD regions [3,6] and [12,15] on
                      [0,3,6,12,15,18]; 2: two touching PD regions [6,9] and [9,12];
                      3: FE|PD|FE on [0,4,12,18] (unequal elements) */
  cupid_fictitious_fe fict; /* the fictitious FE element (0: the default, the removed one) */
  double flen;              /* its length for CUPID_FICTITIOUS_FE_LENGTH */
} patch_case;

typedef struct {
  tb_beam tb;
  cupid_cuf_beam beam;
  cupid_pd_grid grid, full;
  cupid_pd_operator full_op;
  cupid_pd_material mat;
  cupid_pd_operator_options pdo;
  cupid_coupling_h cpl;
  cupid_csr K;
  cupid_box region[2];
  int n_regions;
  int region_mat[2];
  cupid_int n_pd, ndof;
} patch_model;

static void build(patch_model *m, const patch_case *pc) {
  memset(m, 0, sizeof *m);
  tb_init(&m->tb, 1000.0, pc->nu);
  if (pc->te >= 1) {
    tb_te(&m->tb, pc->te);
    tb_rect(&m->tb, 0, XW, 1, 0, XW, 1, -1);
  } else {
    tb_le(&m->tb, pc->le_nodes);
    tb_rect(&m->tb, 0, XW, pc->le_n, 0, XW, pc->le_n, -1);
  }
  static const double axes[4][6] = {
      {0, 6, 12, YL}, {0, 3, 6, 12, 15, YL}, {0, 6, 9, 12, YL}, {0, 4, 12, YL}};
  static const int n_axis[4] = {4, 6, 5, 4};
  static const double reg[4][2][2] = {{{6, 12}}, {{3, 6}, {12, 15}}, {{6, 9}, {9, 12}}, {{4, 12}}};
  int L = pc->layout;
  tb_axis_spans(&m->tb, n_axis[L], axes[L]);
  m->tb.def.element_nodes = pc->p;
  m->beam = tb_create(&m->tb);

  m->n_regions = L == 0 || L == 3 ? 1 : 2;
  for (int r = 0; r < m->n_regions; r++)
    m->region[r] = (cupid_box){.lo = {0, reg[L][r][0], 0}, .hi = {XW, reg[L][r][1], XW}, .has = {1, 1, 1}};
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
                               .pd = m->pdo,
                               .fictitious_fe = pc->fict,
                               .fictitious_length = pc->flen};
  CUPID_ASSERT_OK(cupid_coupling_create(m->beam, m->grid, &co, &m->cpl, &m->K));
  assert_int_equal(m->K->nrows, m->ndof / 3);

  /* The all-PD bar: the reference for the PD rows. */
  cupid_box whole = {.lo = {0, 0, 0}, .hi = {XW, YL, XW}, .has = {1, 1, 1}};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &whole, m->region_mat, &m->full));
  cupid_coupling_info ci;
  cupid_coupling_get_info(m->cpl, &ci);
  assert_int_equal(ci.n_interfaces, L == 2 ? 2 : 2 * m->n_regions); /* touching: none between */
  assert_int_equal(ci.fictitious_fe, pc->fict);
  /* fictitious FE nodes: p - 1 per interface (one for the B2 kinds), M section DOF groups each */
  cupid_cuf_info bi;
  cupid_cuf_get_info(m->beam, &bi);
  int per = pc->fict == CUPID_FICTITIOUS_FE_REMOVED || pc->fict == CUPID_FICTITIOUS_FE_ADJACENT
                ? pc->p - 1
                : 1;
  assert_int_equal(ci.n_fictitious_fe, (cupid_int)ci.n_interfaces * per * bi.M);
  CUPID_ASSERT_OK(cupid_pd_operator_create(m->full, &m->pdo, &m->full_op));
}

static void destroy(patch_model *m) {
  cupid_coupling_destroy(&m->cpl);
  cupid_csr_destroy(&m->K);
  cupid_pd_operator_destroy(&m->full_op);
  cupid_pd_grid_destroy(&m->full);
  cupid_pd_grid_destroy(&m->grid);
  cupid_cuf_beam_destroy(&m->beam);
}


/* Uniaxial stress sigma_yy with Poisson contraction: an exact FE solution with free lateral
 * faces (no traction on x = const or z = const). */
static cupid_test_affine uniaxial(double nu) {
  cupid_test_affine a;
  memset(&a, 0, sizeof a);
  double e = 1e-3;
  a.B[1][1] = e;
  a.B[0][0] = a.B[2][2] = -nu * e;
  a.c[0] = a.c[2] = nu * e * XW / 2;
  a.c[1] = 2e-4;
  return a;
}

static void field_vector(const patch_model *m, const cupid_test_affine *a, double *u) {
  memset(u, 0, (size_t)m->ndof * sizeof *u);
  const double *x = cupid_pd_grid_coords(m->grid);
  for (cupid_int i = 0; i < m->n_pd; i++) cupid_test_affine_eval(a, x + 3 * i, u + 3 * i);
  CUPID_ASSERT_OK(cupid_cuf_interpolate(m->beam, cupid_test_affine_fn, (void *)a, u));
}

/* Force scale: E * strain * cell area. */
#define FSCALE (1000.0 * 1e-3)

static void check_ghost_forces(const patch_case *pc) {
  patch_model m;
  build(&m, pc);
  double *u = NULL, *f = NULL, *uf = NULL, *ff = NULL;
  cupid_int nf = cupid_pd_grid_num_nodes(m.full);
  CUPID_ASSERT_OK(cupid_calloc((size_t)m.ndof, sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_calloc((size_t)m.ndof, sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_calloc((size_t)(3 * nf), sizeof *uf, "uf", &uf));
  CUPID_ASSERT_OK(cupid_calloc((size_t)(3 * nf), sizeof *ff, "ff", &ff));
  unsigned char *interior = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)nf, 1, "interior", &interior));
  CUPID_ASSERT_OK(cupid_pd_grid_interior(m.full, 2 * pc->delta, interior));

  /* PD rows under a general affine field (TE1 and up and LE hold every affine field). */
  cupid_test_affine a = cupid_test_random_affine(7);
  field_vector(&m, &a, u);
  cupid_csr_matvec(m.K, u, f);
  const double *xf = cupid_pd_grid_coords(m.full);
  for (cupid_int i = 0; i < nf; i++) cupid_test_affine_eval(&a, xf + 3 * i, uf + 3 * i);
  CUPID_ASSERT_OK(cupid_pd_operator_apply(m.full_op, uf, ff));
  const double *x = cupid_pd_grid_coords(m.grid);
  double worst = 0.0, worst_interior = 0.0;
  int n_interior = 0;
  for (cupid_int i = 0; i < m.n_pd; i++) {
    cupid_int ijk[3];
    for (int d = 0; d < 3; d++) ijk[d] = (cupid_int)floor(x[3 * i + d]);
    cupid_int j = cupid_pd_grid_node_at(m.full, ijk[0], ijk[1], ijk[2]);
    assert_true(j >= 0);
    for (int c = 0; c < 3; c++) {
      worst = fmax(worst, fabs(f[3 * i + c] - ff[3 * j + c]));
      if (interior[j]) worst_interior = fmax(worst_interior, fabs(f[3 * i + c]));
    }
    n_interior += interior[j];
  }
  printf("  PD rows: max |f - f_allPD| = %.2e, max |f| on %d interior nodes = %.2e (scale %.1e)\n",
         worst, n_interior, worst_interior, FSCALE);
  assert_true(worst <= 1e-10 * FSCALE);
  assert_true(worst_interior <= 1e-10 * FSCALE);

  /* FE rows under uniaxial stress: zero away from the loaded/clamped ends. */
  cupid_test_affine b = uniaxial(pc->nu);
  field_vector(&m, &b, u);
  cupid_csr_matvec(m.K, u, f);
  cupid_cuf_info info;
  cupid_cuf_get_info(m.beam, &info);
  double worst_fe = 0.0, worst_pd = 0.0;
  for (cupid_int n = 0; n < info.n_fe_nodes; n++) {
    cupid_int bn = n / info.M;
    double y = cupid_cuf_beam_node_y(m.beam, bn);
    if (y < 1e-9 || y > YL - 1e-9) continue;
    for (int c = 0; c < 3; c++) worst_fe = fmax(worst_fe, fabs(f[3 * m.n_pd + 3 * n + c]));
  }
  for (cupid_int i = 0; i < nf; i++) cupid_test_affine_eval(&b, xf + 3 * i, uf + 3 * i);
  CUPID_ASSERT_OK(cupid_pd_operator_apply(m.full_op, uf, ff));
  for (cupid_int i = 0; i < m.n_pd; i++) {
    cupid_int ijk[3];
    for (int d = 0; d < 3; d++) ijk[d] = (cupid_int)floor(x[3 * i + d]);
    cupid_int j = cupid_pd_grid_node_at(m.full, ijk[0], ijk[1], ijk[2]);
    for (int c = 0; c < 3; c++) worst_pd = fmax(worst_pd, fabs(f[3 * i + c] - ff[3 * j + c]));
  }
  printf("  uniaxial: max |f| on FE DOFs off the ends = %.2e, PD rows vs all-PD %.2e\n", worst_fe,
         worst_pd);
  assert_true(worst_fe <= 1e-10 * FSCALE * XW * XW);
  assert_true(worst_pd <= 1e-10 * FSCALE);

  /* Solve: prescribe the ends and the PD nodes that are not interior (surface effect). */
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(m.ndof, &bc));
  for (cupid_int i = 0; i < m.n_pd; i++) {
    cupid_int ijk[3];
    for (int d = 0; d < 3; d++) ijk[d] = (cupid_int)floor(x[3 * i + d]);
    cupid_int j = cupid_pd_grid_node_at(m.full, ijk[0], ijk[1], ijk[2]);
    int lateral = 0;
    for (int d = 0; d < 3; d += 2)
      lateral |= x[3 * i + d] < 2 * pc->delta || x[3 * i + d] > XW - 2 * pc->delta;
    (void)j;
    if (lateral)
      for (int c = 0; c < 3; c++) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 3 * i + c, u[3 * i + c]));
  }
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
  double *sol = NULL, *zero = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)m.ndof, sizeof *sol, "sol", &sol));
  CUPID_ASSERT_OK(cupid_calloc((size_t)m.ndof, sizeof *zero, "zero", &zero));
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
  printf("  solve: %lld free DOFs, max |u - u_exact| / max |u| = %.2e\n", (long long)bc->n_free,
         err / umax);
  assert_true(err <= 1e-10 * umax);

  cupid_dirichlet_destroy(&bc);
  cupid_free(&sol);
  cupid_free(&zero);
  cupid_free(&u);
  cupid_free(&f);
  cupid_free(&uf);
  cupid_free(&ff);
  cupid_free(&interior);
  destroy(&m);
}

static void te1_lps(void **state) {
  (void)state;
  check_ghost_forces(&(patch_case){.te = 1, .p = 2, .kind = CUPID_PD_LPS, .delta = 1.5, .nu = 0.2});
}
static void te2_b3_lps(void **state) {
  (void)state;
  check_ghost_forces(&(patch_case){.te = 2, .p = 3, .kind = CUPID_PD_LPS, .delta = 1.5, .nu = 0.3});
}
static void te3_b4_bond(void **state) {
  (void)state;
  check_ghost_forces(&(patch_case){.te = 3, .p = 4, .kind = CUPID_PD_BOND, .delta = 2.0, .nu = 0.25});
}
static void l9_lps(void **state) {
  (void)state;
  check_ghost_forces(
      &(patch_case){.le_nodes = 9, .le_n = 1, .p = 2, .kind = CUPID_PD_LPS, .delta = 1.5, .nu = 0.2});
}
static void l4_2x2_bond(void **state) {
  (void)state;
  check_ghost_forces(
      &(patch_case){.le_nodes = 4, .le_n = 2, .p = 3, .kind = CUPID_PD_BOND, .delta = 1.5, .nu = 0.0});
}
static void two_regions_te2_lps(void **state) {
  (void)state;
  check_ghost_forces(
      &(patch_case){.te = 2, .p = 2, .kind = CUPID_PD_LPS, .delta = 1.5, .nu = 0.2, .layout = 1});
}
static void touching_regions_l9_bond(void **state) {
  (void)state;
  check_ghost_forces(&(patch_case){
      .le_nodes = 9, .le_n = 1, .p = 3, .kind = CUPID_PD_BOND, .delta = 1.5, .nu = 0.25, .layout = 2});
}
static void l9_2x2_b4_lps_nu0(void **state) {
  (void)state;
  check_ghost_forces(
      &(patch_case){.le_nodes = 9, .le_n = 2, .p = 4, .kind = CUPID_PD_LPS, .delta = 2.0, .nu = 0.0});
}

/* The kinds of fictitious FE element on unequal elements (FE [0,4] | PD [4,12] | FE [12,18]):
 * removed (length 8, B4: nodes at 6.67 and 9.33 between PD planes, the far node on the other
 * face, extrapolated), adjacent (B4 copies of lengths 4 and 6), nearest plane (B2, h/2) and a
 * given length (B2, 2.5: its node between two planes). */
static void unequal_removed_l9_b4(void **state) {
  (void)state;
  check_ghost_forces(&(patch_case){.le_nodes = 9, .le_n = 1, .p = 4, .kind = CUPID_PD_LPS,
                                   .delta = 1.5, .nu = 0.2, .layout = 3});
}
static void unequal_adjacent_te2_b4(void **state) {
  (void)state;
  check_ghost_forces(&(patch_case){.te = 2, .p = 4, .kind = CUPID_PD_LPS, .delta = 1.5, .nu = 0.3,
                                   .layout = 3, .fict = CUPID_FICTITIOUS_FE_ADJACENT});
}
static void unequal_plane_l9_b3(void **state) {
  (void)state;
  check_ghost_forces(&(patch_case){.le_nodes = 9, .le_n = 1, .p = 3, .kind = CUPID_PD_LPS,
                                   .delta = 1.5, .nu = 0.2, .layout = 3,
                                   .fict = CUPID_FICTITIOUS_FE_PLANE});
}
static void unequal_length_te1_b2(void **state) {
  (void)state;
  check_ghost_forces(&(patch_case){.te = 1, .p = 2, .kind = CUPID_PD_BOND, .delta = 2.0, .nu = 0.25,
                                   .layout = 3, .fict = CUPID_FICTITIOUS_FE_LENGTH, .flen = 2.5});
}

/* The options choose the fictitious FE element (the model's coupling.fictitious_fe); a kind
 * they do not know, or a given length that is not positive, is an argument error. */
static void fictitious_fe_options(void **state) {
  (void)state;
  static const cupid_fictitious_fe kinds[] = {CUPID_FICTITIOUS_FE_REMOVED,
                                              CUPID_FICTITIOUS_FE_ADJACENT,
                                              CUPID_FICTITIOUS_FE_PLANE, CUPID_FICTITIOUS_FE_LENGTH};
  for (size_t i = 0; i < sizeof kinds / sizeof kinds[0]; i++) {
    patch_model m;
    patch_case pc = {.te = 1, .p = 2, .kind = CUPID_PD_BOND, .delta = 1.5, .nu = 0.2,
                     .layout = 3, .fict = kinds[i], .flen = 2.5};
    build(&m, &pc); /* asserts info.fictitious_fe == kinds[i] */
    destroy(&m);
  }
  patch_model m;
  memset(&m, 0, sizeof m);
  tb_init(&m.tb, 1000.0, 0.2);
  tb_te(&m.tb, 1);
  tb_rect(&m.tb, 0, XW, 1, 0, XW, 1, -1);
  static const double axes[4] = {0, 6, 12, YL};
  tb_axis_spans(&m.tb, 4, axes);
  m.tb.def.element_nodes = 2;
  m.beam = tb_create(&m.tb);
  cupid_box region = {.lo = {0, 6, 0}, .hi = {XW, 12, XW}, .has = {1, 1, 1}};
  int mat = 0;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &region, &mat, &m.grid));
  CUPID_ASSERT_OK(cupid_coupling_deactivate(m.beam, 1, &region));
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(m.beam, 3 * cupid_pd_grid_num_nodes(m.grid)));
  m.mat = (cupid_pd_material){.E = 1000.0, .nu = 0.2};
  cupid_coupling_options co = {.beam_def = &m.tb.def,
                               .materials = m.tb.mat,
                               .n_materials = m.tb.n_mat,
                               .n_regions = 1,
                               .regions = &region,
                               .region_materials = &mat,
                               .spacing = 1.0,
                               .pd = {.horizon = 1.5,
                                      .model = CUPID_PD_BOND,
                                      .influence = CUPID_INFLUENCE_GAUSSIAN,
                                      .materials = &m.mat,
                                      .n_materials = 1}};
  co.fictitious_fe = (cupid_fictitious_fe)7;
  assert_int_equal(cupid_coupling_create(m.beam, m.grid, &co, &m.cpl, &m.K), CUPID_ERR_ARGUMENT);
  assert_non_null(strstr(cupid_error_message(), "unknown fictitious FE element kind 7"));
  co.fictitious_fe = CUPID_FICTITIOUS_FE_LENGTH;
  co.fictitious_length = 0.0;
  assert_int_equal(cupid_coupling_create(m.beam, m.grid, &co, &m.cpl, &m.K), CUPID_ERR_ARGUMENT);
  assert_non_null(strstr(cupid_error_message(), "the length must be > 0"));
  destroy(&m);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(te1_lps),     cmocka_unit_test(te2_b3_lps),
      cmocka_unit_test(te3_b4_bond), cmocka_unit_test(l9_lps),
      cmocka_unit_test(l4_2x2_bond), cmocka_unit_test(l9_2x2_b4_lps_nu0),
      cmocka_unit_test(two_regions_te2_lps), cmocka_unit_test(touching_regions_l9_bond),
      cmocka_unit_test(unequal_removed_l9_b4), cmocka_unit_test(unequal_adjacent_te2_b4),
      cmocka_unit_test(unequal_plane_l9_b3), cmocka_unit_test(unequal_length_te1_b2),
      cmocka_unit_test(fictitious_fe_options),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
