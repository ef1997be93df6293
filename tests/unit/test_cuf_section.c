/* Unit tests of the CUF section builder: node merging between components, explicit node and
 * element lists, materials per component, TE integration over several components, and the
 * model errors (non-matching components, overlaps, clockwise elements, bad clamp planes). */
#include <stdlib.h>

#include "unit/test_cuf_common.h"

static void test_merge_and_counts(void **state) {
  (void)state;
  tb_beam t;
  tb_init(&t, 1.0, 0.3);
  tb_le(&t, 9);
  tb_axis(&t, 0, 1, 2, 3);
  tb_rect(&t, 0, 1, 1, 0, 1, 1, -1);
  tb_rect(&t, 1, 2, 1, 0, 1, 1, -1); /* shares the edge x = 1: 3 nodes merged */
  cupid_cuf_beam b = tb_create(&t);
  cupid_cuf_info info;
  cupid_cuf_get_info(b, &info);
  assert_int_equal(info.M, 15);
  assert_int_equal(info.n_section_elements, 2);
  assert_int_equal(info.n_beam_nodes, 5);
  assert_int_equal(info.n_fe_nodes, 75);
  assert_int_equal(info.n_dofs, 225);
  ASSERT_NEAR(info.section_area, 2.0, 1e-14);
  cupid_cuf_beam_destroy(&b);
  assert_null(b);
  cupid_cuf_beam_destroy(&b); /* NULL-safe */
}

static cupid_status try_create(tb_beam *t) {
  cupid_cuf_beam b = NULL;
  cupid_status st = cupid_cuf_beam_create_from(&t->def, t->mat, t->n_mat, &b);
  cupid_cuf_beam_destroy(&b);
  return st;
}

static void test_errors(void **state) {
  (void)state;
  tb_beam t;
  /* a node of one component inside an edge of another: non-matching interface */
  tb_init(&t, 1.0, 0.3);
  tb_le(&t, 4);
  tb_axis(&t, 0, 1, 1, 2);
  tb_rect(&t, 0, 1, 1, 0, 2, 1, -1);
  tb_rect(&t, 1, 2, 1, 0, 2, 2, -1);
  assert_int_equal(try_create(&t), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "inside an edge"));
  /* overlapping components */
  tb_init(&t, 1.0, 0.3);
  tb_te(&t, 2);
  tb_axis(&t, 0, 1, 1, 2);
  tb_rect(&t, 0, 2, 1, 0, 2, 1, -1);
  tb_rect(&t, 1, 3, 1, 1, 3, 1, -1);
  assert_int_equal(try_create(&t), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "overlap"));
  /* decreasing breakpoints, bad element type, bad axis, bad TE order, bad material */
  tb_init(&t, 1.0, 0.3);
  tb_le(&t, 9);
  tb_axis(&t, 0, 1, 1, 2);
  tb_rect(&t, 0, 1, 1, 0, 1, 1, -1);
  t.xs[0][1] = -1;
  assert_int_equal(try_create(&t), CUPID_ERR_MODEL);
  t.xs[0][1] = 1;
  t.def.le_nodes = 6;
  assert_int_equal(try_create(&t), CUPID_ERR_MODEL);
  t.def.le_nodes = 9;
  t.def.element_nodes = 5;
  assert_int_equal(try_create(&t), CUPID_ERR_MODEL);
  t.def.element_nodes = 2;
  t.axis_y[1] = 0;
  assert_int_equal(try_create(&t), CUPID_ERR_MODEL);
  t.axis_y[1] = 1;
  t.comp[0].material = 3;
  assert_int_equal(try_create(&t), CUPID_ERR_MODEL);
  t.comp[0].material = -1;
  t.mat[0].nu = 0.5;
  assert_int_equal(try_create(&t), CUPID_ERR_MODEL);
  t.mat[0].nu = 0.3;
  tb_te(&t, -1);
  assert_int_equal(try_create(&t), CUPID_ERR_MODEL);
  tb_te(&t, 3);
  assert_int_equal(try_create(&t), CUPID_SUCCESS);
  /* clamp plane that is not a beam node */
  cupid_cuf_beam b = tb_create(&t);
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(cupid_cuf_num_dofs(b), &bc));
  cupid_constraint c = {.kind = CUPID_CONSTRAINT_CLAMP, .plane_y = 0.5};
  strcpy(c.mark.key, "constraints[0]");
  assert_int_equal(cupid_cuf_constraint_apply(b, NULL, &c, bc), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "not a beam node"));
  assert_non_null(strstr(cupid_error_message(), "constraints[0]"));
  c.plane_y = 1.0;
  CUPID_ASSERT_OK(cupid_cuf_constraint_apply(b, NULL, &c, bc));
  /* a TE fix box must hold the whole section */
  cupid_constraint fx = {.kind = CUPID_CONSTRAINT_FIX, .box = {{0, 0, 0}, {0.5, 1, 1}, {1, 1, 1}}, .components = {1, 1, 1}};
  assert_int_equal(cupid_cuf_constraint_apply(b, NULL, &fx, bc), CUPID_ERR_MODEL);
  cupid_dirichlet_destroy(&bc);
  cupid_cuf_beam_destroy(&b);
}

/* Clockwise explicit elements are rejected; counter-clockwise ones give the same model as
 * the equivalent components. */
static double tip_w(tb_beam *t) {
  cupid_cuf_beam b = tb_create(t);
  cupid_int n = cupid_cuf_num_dofs(b);
  double *f = NULL, tv[3] = {0, 0, -1.0};
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_cuf_traction_add(b, 10, NULL, tb_const, tv, f, NULL));
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
  CUPID_ASSERT_OK(cupid_cuf_clamp_node(b, 0, bc));
  double *u = tb_solve(b, f, bc, NULL), d[3];
  CUPID_ASSERT_OK(cupid_cuf_displacement_at(b, u, 0.75, 10, 0.5, d));
  cupid_free(&u);
  cupid_free(&f);
  cupid_dirichlet_destroy(&bc);
  cupid_cuf_beam_destroy(&b);
  return d[2];
}

static void test_explicit_section(void **state) {
  (void)state;
  tb_beam a, e;
  tb_init(&a, 100.0, 0.25);
  tb_le(&a, 9);
  tb_axis(&a, 0, 10, 4, 3);
  tb_rect(&a, 0, 2, 2, 0, 1, 1, -1);
  double wa = tip_w(&a);
  /* the same two L9 elements, listed explicitly (node order of cuf.h) */
  tb_init(&e, 100.0, 0.25);
  tb_le(&e, 9);
  tb_axis(&e, 0, 10, 4, 3);
  double nodes[15][2];
  for (int j = 0; j < 3; j++)
    for (int i = 0; i < 5; i++) nodes[j * 5 + i][0] = 0.5 * i, nodes[j * 5 + i][1] = 0.5 * j;
  /* grid index (i, j) -> node id j*5+i; L9 order: (0,0) (1,0) (2,0) (2,1) (2,2) (1,2) (0,2) (0,1) (1,1) */
  static const int gi[9] = {0, 1, 2, 2, 2, 1, 0, 0, 1}, gj[9] = {0, 0, 0, 1, 2, 2, 2, 1, 1};
  int elems[18];
  for (int k = 0; k < 2; k++)
    for (int q = 0; q < 9; q++) elems[9 * k + q] = gj[q] * 5 + 2 * k + gi[q];
  int mats[2] = {-1, -1};
  e.def.section_nodes = &nodes[0][0];
  e.def.n_section_nodes = 15;
  e.def.section_elements = elems;
  e.def.section_element_material = mats;
  e.def.n_section_elements = 2;
  double we = tip_w(&e);
  /* same discretisation: equal to round-off (1e-12 relative) */
  ASSERT_NEAR(we, wa, 1e-12 * fabs(wa));
  /* clockwise listing: reversed order of the boundary nodes */
  int cw[18];
  static const int rev[9] = {0, 7, 6, 5, 4, 3, 2, 1, 8};
  for (int k = 0; k < 2; k++)
    for (int q = 0; q < 9; q++) cw[9 * k + q] = elems[9 * k + rev[q]];
  e.def.section_elements = cw;
  assert_int_equal(try_create(&e), CUPID_ERR_MODEL);
  assert_non_null(strstr(cupid_error_message(), "clockwise"));
  /* a distorted (trapezoidal) explicit L4: exact area, and not flagged as a rectangle */
  tb_beam q;
  tb_init(&q, 1.0, 0.3);
  tb_le(&q, 4);
  tb_axis(&q, 0, 1, 1, 2);
  double tn[4][2] = {{0, 0}, {3, 0}, {2, 1}, {0.5, 1}};
  int te[4] = {0, 1, 2, 3};
  q.def.section_nodes = &tn[0][0];
  q.def.n_section_nodes = 4;
  q.def.section_elements = te;
  q.def.n_section_elements = 1;
  cupid_cuf_beam b = tb_create(&q);
  cupid_cuf_info info;
  cupid_cuf_get_info(b, &info);
  ASSERT_NEAR(info.section_area, 2.25, 1e-14);
  assert_true(cupid_cuf_contains(b, 2.4, 0.5, 0.5));
  assert_false(cupid_cuf_contains(b, 2.6, 0.5, 0.5));
  cupid_cuf_beam_destroy(&b);
}

/* TE integrates over the components: the same L-shaped section split in two different ways
 * gives the same beam (to round-off). */
static void test_te_integration_domain(void **state) {
  (void)state;
  tb_beam a, c;
  tb_init(&a, 100.0, 0.25);
  tb_te(&a, 3);
  tb_axis(&a, 0, 10, 4, 3);
  tb_rect(&a, 0, 1, 1, 0, 2, 1, -1);
  tb_rect(&a, 1, 2, 1, 0, 1, 1, -1);
  tb_init(&c, 100.0, 0.25);
  tb_te(&c, 3);
  tb_axis(&c, 0, 10, 4, 3);
  tb_rect(&c, 0, 2, 2, 0, 1, 1, -1);
  tb_rect(&c, 0, 1, 1, 1, 2, 1, -1);
  double wa = tip_w(&a), wc = tip_w(&c);
  ASSERT_NEAR(wa, wc, 1e-10 * fabs(wa));
}

/* Materials per component: a bar of two materials (nu = 0) pulled by the tractions E_i eps0
 * is uniformly strained (exact for TE1 and LE, 1e-10 relative). */
static void bimat_traction(void *ctx, const double p[3], double density, double out[3]) {
  (void)ctx;
  (void)density;
  out[0] = out[2] = 0;
  out[1] = (p[0] < 1 ? 100.0 : 300.0) * 1e-3;
}

static void test_bimaterial_tension(void **state) {
  (void)state;
  for (int le = 0; le < 2; le++) {
    tb_beam t;
    tb_init(&t, 100.0, 0.0);
    t.mat[1] = t.mat[0];
    t.mat[1].E = 300.0;
    t.n_mat = 2;
    if (le) tb_le(&t, 9);
    else tb_te(&t, 1);
    tb_axis(&t, 0, 10, 2, 2);
    tb_rect(&t, 0, 1, 1, 0, 1, 1, -1);
    tb_rect(&t, 1, 3, 1, 0, 1, 1, 1);
    cupid_cuf_beam b = tb_create(&t);
    cupid_int n = cupid_cuf_num_dofs(b);
    double *f = NULL, area;
    CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f, "f", &f));
    CUPID_ASSERT_OK(cupid_cuf_traction_add(b, 10, NULL, bimat_traction, NULL, f, &area));
    ASSERT_NEAR(area, 3.0, 1e-14);
    cupid_dirichlet bc = NULL;
    CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
    CUPID_ASSERT_OK(cupid_cuf_clamp_node(b, 0, bc));
    double *u = tb_solve(b, f, bc, NULL), d[3], s[6];
    double eps = 1e-3;
    CUPID_ASSERT_OK(cupid_cuf_displacement_at(b, u, 0.5, 10, 0.5, d));
    ASSERT_NEAR(d[1], 10 * eps, 1e-10 * 10 * eps);
    CUPID_ASSERT_OK(cupid_cuf_stress_at(b, u, 2.0, 5, 0.5, s));
    ASSERT_NEAR(s[1], 300 * eps, 1e-10 * 300 * eps);
    CUPID_ASSERT_OK(cupid_cuf_stress_at(b, u, 0.5, 5, 0.5, s));
    ASSERT_NEAR(s[1], 100 * eps, 1e-10 * 300 * eps);
    cupid_free(&u);
    cupid_free(&f);
    cupid_dirichlet_destroy(&bc);
    cupid_cuf_beam_destroy(&b);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_merge_and_counts), cmocka_unit_test(test_errors),
                                     cmocka_unit_test(test_explicit_section),
                                     cmocka_unit_test(test_te_integration_domain),
                                     cmocka_unit_test(test_bimaterial_tension)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
