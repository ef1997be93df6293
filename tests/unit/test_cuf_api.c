/* Unit tests of the CUF beam API: traction patches clipped to the section (one or several
 * components), point loads, point queries outside the beam, DOF offsets with assemble_add,
 * the activity mask, prescribed displacements (LE nodal, TE projection), orthotropic
 * materials, and the VTU reconstruction. */
#include <stdlib.h>

#include "unit/test_cuf_common.h"

/* C-section of examples.md section 2 (web x in [0,5] over the full height split at +-45 so
 * that the flanges x in [5,50] share its nodes). */
static void c_section(tb_beam *t, int le, int nflange) {
  tb_init(t, 200000.0, 0.2);
  if (le) tb_le(t, 9);
  else tb_te(t, 4);
  tb_axis(t, 0, 1000, 4, 4);
  int c = t->def.n_components++;
  double zw[] = {-50, -45, 45, 50};
  t->xs[c][0] = 0, t->xs[c][1] = 5;
  for (int k = 0; k < 4; k++) t->zs[c][k] = zw[k];
  t->comp[c].x = t->xs[c], t->comp[c].z = t->zs[c], t->comp[c].nx = 2, t->comp[c].nz = 4;
  t->comp[c].material = -1;
  tb_rect(t, 5, 50, nflange, 45, 50, 1, -1);
  tb_rect(t, 5, 50, nflange, -50, -45, 1, -1);
}

/* Patch resultants: sum of the consistent forces (LE: all nodes; TE: the constant term) is
 * the traction times the clipped area, for a patch inside one component, one spanning two,
 * and one partly outside the section. */
static void test_traction_patches(void **state) {
  (void)state;
  struct { double x0, x1, z0, z1, area; } patches[] = {
      {40, 50, 45, 50, 50.0},       /* the loaded patch of examples.md 2 (inside a flange) */
      {3, 12.5, 40, 50, 2 * 10 + 7.5 * 5}, /* web x [3,5] z [40,50] + flange x [5,12.5] z [45,50] */
      {-10, 2, -60, 60, 200.0},     /* sticks out of the section: clipped to x [0,2] full height */
      {20.3, 33.1, 46.1, 48.2, 12.8 * 2.1}}; /* cuts through flange cells */
  for (int le = 0; le < 2; le++) {
    tb_beam t;
    c_section(&t, le, 4);
    cupid_cuf_beam b = tb_create(&t);
    cupid_cuf_info info;
    cupid_cuf_get_info(b, &info);
    cupid_int n = cupid_cuf_num_dofs(b);
    double *f = NULL;
    CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f, "f", &f));
    for (size_t k = 0; k < sizeof patches / sizeof patches[0]; k++) {
      memset(f, 0, sizeof *f * (size_t)n);
      cupid_box patch = {{patches[k].x0, 0, patches[k].z0}, {patches[k].x1, 0, patches[k].z1}, {1, 0, 1}};
      double tv[3] = {0, 0, -20.0}, area;
      CUPID_ASSERT_OK(cupid_cuf_traction_add(b, 1000, &patch, tb_const, tv, f, &area));
      /* clipping of rectangles is exact: 1e-12 relative */
      ASSERT_NEAR(area, patches[k].area, 1e-12 * patches[k].area);
      double sum = 0;
      for (cupid_int q = 0; q < n / 3; q++)
        if (le || q % info.M == 0) sum += f[3 * q + 2];
      ASSERT_NEAR(sum, -20.0 * patches[k].area, 1e-12 * 20 * patches[k].area);
    }
    /* a patch that misses the section is a model error */
    cupid_box off = {{60, 0, 0}, {70, 0, 10}, {1, 0, 1}};
    double tv[3] = {0, 0, 1};
    assert_int_equal(cupid_cuf_traction_add(b, 1000, &off, tb_const, tv, f, NULL), CUPID_ERR_MODEL);
    assert_int_equal(cupid_cuf_traction_add(b, 1200, NULL, tb_const, tv, f, NULL), CUPID_ERR_MODEL);
    cupid_free(&f);
    cupid_cuf_beam_destroy(&b);
  }
}

/* Point loads: LE at a section node and a beam node loads that single FE node; outside the
 * beam is a model error; queries outside fail the same way. */
static void test_point_load(void **state) {
  (void)state;
  tb_beam t;
  c_section(&t, 1, 4);
  cupid_cuf_beam b = tb_create(&t);
  cupid_int n = cupid_cuf_num_dofs(b);
  double *f = NULL, P[3] = {1, 2, 3};
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f, "f", &f));
  double at[3] = {50, 500, 50}; /* a corner node of the top flange at beam node 6 */
  CUPID_ASSERT_OK(cupid_cuf_point_load_add(b, at, P, f));
  int nz = 0;
  for (cupid_int q = 0; q < n; q++)
    if (fabs(f[q]) > 1e-14) nz++;
  assert_int_equal(nz, 3);
  double out[3], sig[6];
  double bad[3] = {30, 500, 0}; /* in the C's opening */
  assert_int_equal(cupid_cuf_point_load_add(b, bad, P, f), CUPID_ERR_MODEL);
  assert_int_equal(cupid_cuf_displacement_at(b, f, 30, 500, 0, out), CUPID_ERR_MODEL);
  assert_int_equal(cupid_cuf_stress_at(b, f, 2, 1001, 0, sig), CUPID_ERR_MODEL);
  assert_false(cupid_cuf_contains(b, 30, 500, 0));
  assert_true(cupid_cuf_contains(b, 2.5, 1000, 0));
  assert_true(cupid_cuf_contains(b, 45, 1000, 47.5));
  cupid_free(&f);
  cupid_cuf_beam_destroy(&b);
}

/* DOF offset: the beam assembled into a larger matrix at block offset 2 equals the stand-alone
 * matrix; loads and constraints move with the offset. */
static void test_offset_and_mask(void **state) {
  (void)state;
  tb_beam t;
  c_section(&t, 1, 2);
  cupid_cuf_beam b = tb_create(&t);
  cupid_csr K = NULL, B = NULL;
  CUPID_ASSERT_OK(cupid_cuf_assemble(b, &K));
  cupid_int *rp = NULL, *col = NULL, nb = K->nrows, off = 2;
  CUPID_ASSERT_OK(cupid_cuf_pattern(b, &rp, &col));
  cupid_int *rp2 = NULL, *col2 = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)(nb + off + 1), sizeof *rp2, "rp2", &rp2));
  CUPID_ASSERT_OK(cupid_malloc((size_t)rp[nb] + (size_t)off, sizeof *col2, "col2", &col2));
  for (cupid_int r = 0; r < off; r++) rp2[r + 1] = r + 1, col2[r] = r;
  for (cupid_int r = 0; r < nb; r++) {
    rp2[off + r + 1] = rp2[off + r] + (rp[r + 1] - rp[r]);
    for (cupid_int q = rp[r]; q < rp[r + 1]; q++) col2[rp2[off + r] + q - rp[r]] = col[q] + off;
  }
  CUPID_ASSERT_OK(cupid_csr_create(nb + off, nb + off, 3, rp2, col2, &B));
  assert_int_equal(cupid_cuf_set_dof_offset(b, 4), CUPID_ERR_ARGUMENT);
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(b, 3 * off));
  CUPID_ASSERT_OK(cupid_cuf_assemble_add(b, B));
  double dmax = 0;
  for (cupid_int r = 0; r < nb; r++)
    for (cupid_int q = K->rowptr[r]; q < K->rowptr[r + 1]; q++) {
      double *blk = cupid_csr_find(B, r + off, K->col[q] + off);
      assert_non_null(blk);
      for (int k = 0; k < 9; k++) dmax = fmax(dmax, fabs(blk[k] - K->val[9 * q + k]));
    }
  assert_true(dmax == 0.0);
  assert_int_equal(cupid_cuf_dof(b, 0, 0, 0), 3 * off);
  /* a clamp writes after the offset */
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(3 * (nb + off), &bc));
  CUPID_ASSERT_OK(cupid_cuf_clamp_node(b, 0, bc));
  for (int k = 0; k < 3 * off; k++) assert_int_equal(bc->fixed[k], 0);
  assert_int_equal(bc->fixed[3 * off], 1);
  cupid_dirichlet_destroy(&bc);
  /* mask: switch off every section element of beam element 0 -> nodes interior to element 0
   * are no longer used; the nodes it shares with element 1 still are */
  cupid_cuf_info info;
  cupid_cuf_get_info(b, &info);
  for (cupid_int se = 0; se < info.n_section_elements; se++) CUPID_ASSERT_OK(cupid_cuf_set_active(b, 0, se, 0));
  assert_false(cupid_cuf_node_used(b, 0, 1));
  assert_true(cupid_cuf_node_used(b, 0, 3));
  assert_false(cupid_cuf_contains(b, 2.5, 100, 0));
  assert_true(cupid_cuf_contains(b, 2.5, 250, 0)); /* the shared node plane y = 250 */
  assert_true(cupid_cuf_contains(b, 2.5, 300, 0));
  cupid_free(&rp);
  cupid_free(&col);
  cupid_free(&rp2);
  cupid_free(&col2);
  cupid_csr_destroy(&K);
  cupid_csr_destroy(&B);
  cupid_cuf_beam_destroy(&b);
}

/* Orthotropic tension (material axes x y z): eps_y = s / Ey, eps_x = -nu_yx s / Ey with
 * nu_yx = nu_xy Ey / Ex (S_xy = -nu_xy / Ex); exact for TE1 and LE (1e-10 relative). The
 * constraint is a prescribed u_y = 0 at y = 0 (model "displacement") plus the TE/LE rigid
 * restraints; the TE prescribed field goes through the projection. */
static void test_orthotropic_tension(void **state) {
  (void)state;
  for (int le = 0; le < 2; le++) {
    tb_beam t;
    tb_init(&t, 1.0, 0.3);
    cupid_material *m = &t.mat[0];
    m->orthotropic = 1;
    m->Ex = 10e3, m->Ey = 150e3, m->Ez = 12e3;
    m->nu_xy = 0.02, m->nu_xz = 0.4, m->nu_yz = 0.3;
    m->Gxy = 5e3, m->Gxz = 4e3, m->Gyz = 6e3;
    if (le) tb_le(&t, 9);
    else tb_te(&t, 1);
    tb_axis(&t, 0, 10, 2, 3);
    tb_rect(&t, -1, 1, 2, -0.5, 0.5, 2, -1);
    cupid_cuf_beam b = tb_create(&t);
    cupid_int n = cupid_cuf_num_dofs(b);
    double *f = NULL, s = 50.0, tv[3] = {0, s, 0};
    CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f, "f", &f));
    CUPID_ASSERT_OK(cupid_cuf_traction_add(b, 10, NULL, tb_const, tv, f, NULL));
    cupid_dirichlet bc = NULL;
    CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
    cupid_constraint c = {.kind = CUPID_CONSTRAINT_DISPLACEMENT, .box = {{-2, 0, -2}, {2, 0, 2}, {1, 1, 1}}};
    c.value[1].kind = CUPID_VALUE_CONSTANT; /* u_y = 0 */
    CUPID_ASSERT_OK(cupid_cuf_constraint_apply(b, NULL, &c, bc));
    if (le) { /* centre node (0, 0, 0): u_x = u_z = 0; node (0, 0, 0.5): u_x = 0 */
      int m1[3] = {1, 0, 1}, m2[3] = {1, 0, 0};
      cupid_box b1 = {{-0.01, 0, -0.01}, {0.01, 0, 0.01}, {1, 1, 1}}, b2 = {{-0.01, 0, 0.49}, {0.01, 0, 0.51}, {1, 1, 1}};
      CUPID_ASSERT_OK(cupid_cuf_prescribe(b, &b1, m1, NULL, NULL, bc, NULL));
      CUPID_ASSERT_OK(cupid_cuf_prescribe(b, &b2, m2, NULL, NULL, bc, NULL));
    } else {
      bc->fixed[cupid_cuf_dof(b, 0, 0, 0)] = bc->fixed[cupid_cuf_dof(b, 0, 0, 2)] = 1;
      bc->fixed[cupid_cuf_dof(b, 2, 0, 0)] = 1;
    }
    double *u = tb_solve(b, f, bc, NULL), d[3], sig[6];
    double ey = s / m->Ey, ex = -m->nu_xy / m->Ex * s, ez = -m->nu_yz / m->Ey * s;
    CUPID_ASSERT_OK(cupid_cuf_displacement_at(b, u, 0.7, 8, -0.3, d));
    ASSERT_NEAR(d[0], ex * 0.7, 1e-10 * fabs(ey * 8));
    ASSERT_NEAR(d[1], ey * 8, 1e-10 * fabs(ey * 8));
    ASSERT_NEAR(d[2], ez * -0.3, 1e-10 * fabs(ey * 8));
    CUPID_ASSERT_OK(cupid_cuf_stress_at(b, u, 0.7, 8, -0.3, sig));
    for (int k = 0; k < 6; k++) ASSERT_NEAR(sig[k], k == 1 ? s : 0.0, 1e-10 * s);
    cupid_free(&u);
    cupid_free(&f);
    cupid_dirichlet_destroy(&bc);
    cupid_cuf_beam_destroy(&b);
  }
}

/* Prescribed linear field through the TE projection (exact for degree <= N) and LE nodes. */
static void linear_field(void *ctx, const double p[3], double density, double out[3]) {
  (void)ctx;
  (void)density;
  out[0] = 1e-3 * p[2];
  out[1] = 2e-3 * p[0] - 1e-3 * p[2] + 0.5;
  out[2] = -3e-3 * p[0];
}

static void test_prescribe_projection(void **state) {
  (void)state;
  for (int le = 0; le < 2; le++) {
    tb_beam t;
    c_section(&t, le, 2);
    cupid_cuf_beam b = tb_create(&t);
    cupid_int n = cupid_cuf_num_dofs(b);
    cupid_dirichlet bc = NULL;
    CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
    int mask[3] = {1, 1, 1};
    cupid_box box = {{0, 500, 0}, {0, 500, 0}, {0, 1, 0}};
    cupid_int count = 0;
    CUPID_ASSERT_OK(cupid_cuf_prescribe(b, &box, mask, linear_field, NULL, bc, &count));
    cupid_cuf_info info;
    cupid_cuf_get_info(b, &info);
    assert_int_equal(count, 3 * info.M);
    /* evaluate the prescribed values as a field at beam node y = 500 */
    double *u = NULL;
    CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *u, "u", &u));
    for (cupid_int q = 0; q < n; q++) u[q] = bc->fixed[q] ? bc->value[q] : 0.0;
    double pts[][2] = {{2.5, 0}, {45, 47.5}, {10, -46}};
    for (int k = 0; k < 3; k++) {
      double d[3], ex[3], p[3] = {pts[k][0], 500, pts[k][1]};
      CUPID_ASSERT_OK(cupid_cuf_displacement_at(b, u, p[0], p[1], p[2], d));
      linear_field(NULL, p, 0, ex);
      for (int c = 0; c < 3; c++) ASSERT_NEAR(d[c], ex[c], 1e-12);
    }
    cupid_free(&u);
    cupid_dirichlet_destroy(&bc);
    cupid_cuf_beam_destroy(&b);
  }
}

/* VTU reconstruction: counts, positive hexahedra, and point data equal to the field. */
static void test_vtu(void **state) {
  (void)state;
  for (int le = 0; le < 2; le++) {
    tb_beam t;
    c_section(&t, le, 2);
    cupid_cuf_beam b = tb_create(&t);
    cupid_int n = cupid_cuf_num_dofs(b);
    double *u = NULL;
    CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *u, "u", &u));
    CUPID_ASSERT_OK(cupid_cuf_interpolate(b, linear_field, NULL, u));
    CUPID_ASSERT_OK(cupid_cuf_set_active(b, 1, 0, 0));
    cupid_cuf_vtu *v = NULL;
    CUPID_ASSERT_OK(cupid_cuf_vtu_build(b, u, 3, &v));
    cupid_cuf_info info;
    cupid_cuf_get_info(b, &info);
    cupid_int pairs = info.n_beam_elements * info.n_section_elements - 1;
    int ns = le ? 2 : 3;
    assert_int_equal(v->n_cells, pairs * ns * ns * (info.element_nodes - 1));
    assert_int_equal(v->n_points, pairs * (ns + 1) * (ns + 1) * info.element_nodes);
    assert_int_equal(v->mesh.n_point_data, 2);
    assert_int_equal(v->offsets[v->n_cells - 1], 8 * v->n_cells);
    for (cupid_int c = 0; c < v->n_cells; c++) {
      const cupid_int *cn = v->connectivity + 8 * c;
      const double *p0 = v->points + 3 * cn[0], *p1 = v->points + 3 * cn[1], *p3 = v->points + 3 * cn[3],
                   *p4 = v->points + 3 * cn[4];
      double a[3], bb[3], h[3];
      for (int k = 0; k < 3; k++) a[k] = p1[k] - p0[k], bb[k] = p3[k] - p0[k], h[k] = p4[k] - p0[k];
      double vol = (a[1] * bb[2] - a[2] * bb[1]) * h[0] + (a[2] * bb[0] - a[0] * bb[2]) * h[1] +
                   (a[0] * bb[1] - a[1] * bb[0]) * h[2];
      assert_true(vol > 0);
      assert_int_equal(v->types[c], CUPID_VTK_HEXAHEDRON);
    }
    /* the field is linear (in every space): point data equal to it (1e-12) and the stress of
     * its constant strain gamma_xy = 2e-3, gamma_yz = -1e-3, gamma_xz = 1e-3 - 3e-3, eps_xx = 0 */
    double G = 200000.0 / 2.4;
    for (cupid_int q = 0; q < v->n_points; q++) {
      double ex[3];
      linear_field(NULL, v->points + 3 * q, 0, ex);
      for (int k = 0; k < 3; k++) ASSERT_NEAR(v->displacement[3 * q + k], ex[k], 1e-12);
      /* VTK order xx yy zz xy yz xz */
      ASSERT_NEAR(v->stress[6 * q + 3], G * 2e-3, 1e-9);
      ASSERT_NEAR(v->stress[6 * q + 4], G * -1e-3, 1e-9);
      ASSERT_NEAR(v->stress[6 * q + 5], G * (1e-3 - 3e-3), 1e-9);
      ASSERT_NEAR(v->stress[6 * q + 0], 0.0, 1e-9);
    }
    cupid_cuf_vtu_destroy(&v);
    assert_null(v);
    cupid_free(&u);
    cupid_cuf_beam_destroy(&b);
  }
}

/* The model path (cupid_cuf_load_vector) gives the same forces as the direct calls for a
 * traction patch, a point load and a body force (constants; 1e-14 relative). */
static void test_model_loads(void **state) {
  (void)state;
  tb_beam t;
  c_section(&t, 1, 2);
  t.mat[0].density = 7.8e-9;
  t.mat[0].has_density = 1;
  cupid_model_t model = {0};
  model.materials = t.mat;
  model.n_materials = 1;
  model.has_beam = 1;
  model.beam = t.def;
  cupid_load loads[3] = {{0}};
  loads[0].kind = CUPID_LOAD_TRACTION;
  loads[0].plane_y = 1000;
  loads[0].patch = (cupid_box){{40, 0, 45}, {50, 0, 50}, {1, 0, 1}};
  loads[0].value[2] = (cupid_value){CUPID_VALUE_CONSTANT, -20.0, NULL};
  loads[1].kind = CUPID_LOAD_POINT;
  loads[1].at[0] = 2.5, loads[1].at[1] = 700, loads[1].at[2] = 10;
  loads[1].value[0] = (cupid_value){CUPID_VALUE_CONSTANT, 100.0, NULL};
  loads[2].kind = CUPID_LOAD_BODY;
  loads[2].box = (cupid_box){{0, 100, 0}, {0, 300, 0}, {0, 1, 0}};
  loads[2].value[1] = (cupid_value){CUPID_VALUE_CONSTANT, -9.81e3 * 7.8e-9, NULL};
  model.loads = loads;
  model.n_loads = 3;
  cupid_cuf_beam b = NULL;
  CUPID_ASSERT_OK(cupid_cuf_beam_create(&model, &b));
  cupid_int n = cupid_cuf_num_dofs(b);
  double *f1 = NULL, *f2 = NULL, vol;
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f1, "f1", &f1));
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f2, "f2", &f2));
  CUPID_ASSERT_OK(cupid_cuf_load_vector(b, &model, f1));
  double t0[3] = {0, 0, -20}, P[3] = {100, 0, 0}, g[3] = {0, -9.81e3 * 7.8e-9, 0};
  CUPID_ASSERT_OK(cupid_cuf_traction_add(b, 1000, &loads[0].patch, tb_const, t0, f2, NULL));
  CUPID_ASSERT_OK(cupid_cuf_point_load_add(b, loads[1].at, P, f2));
  CUPID_ASSERT_OK(cupid_cuf_body_force_add(b, &loads[2].box, tb_const, g, f2, &vol));
  ASSERT_NEAR(vol, 200.0 * 950.0, 1e-9 * 1.9e5); /* section area 950 (5 x 100 + 2 x 45 x 5) */
  double fmax = 0;
  for (cupid_int q = 0; q < n; q++) fmax = fmax > fabs(f2[q]) ? fmax : fabs(f2[q]);
  for (cupid_int q = 0; q < n; q++) ASSERT_NEAR(f1[q], f2[q], 1e-14 * fmax);
  /* a point load outside the beam is reported against the load's mark */
  strcpy(loads[1].mark.key, "loads[1]");
  loads[1].at[0] = 30;
  assert_int_equal(cupid_cuf_load_add(b, &model, &loads[1], f1), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "loads[1]"));
  cupid_free(&f1);
  cupid_free(&f2);
  cupid_cuf_beam_destroy(&b);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_traction_patches), cmocka_unit_test(test_point_load),
      cmocka_unit_test(test_offset_and_mask),  cmocka_unit_test(test_orthotropic_tension),
      cmocka_unit_test(test_prescribe_projection), cmocka_unit_test(test_vtu),
      cmocka_unit_test(test_model_loads)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
