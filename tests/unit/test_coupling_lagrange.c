/* The Lagrange-multiplier coupling (eliminated): on the bar FE [0,6] | PD [6,12] | FE [12,18]
 * (section 8 x 8, h = 1, delta = 1.5, TE2 / L9):
 *  - the eliminated matrix T^T diag(K_PD, K_FE) T is symmetric (asymmetry <= 1e-13: the same
 *    products summed in different orders);
 *  - its solve (ends clamped / pulled, CHOLMOD) gives tied PD nodes that follow the beam's
 *    interface section exactly after cupid_coupling_recover() (1e-12 relative);
 *  - global equilibrium holds: the reaction balances the applied end load to 1e-9 relative
 *    (a symmetric coupling conserves momentum; the fictitious-node method does not). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cupid/coupling.h"
#include "test_cuf_common.h"

static void run_case(int le) {
  tb_beam tb;
  tb_init(&tb, 1000.0, 0.2);
  if (le) {
    tb_le(&tb, 9);
    tb_rect(&tb, 0, 8, 1, 0, 8, 1, -1);
  } else {
    tb_te(&tb, 2);
    tb_rect(&tb, 0, 8, 1, 0, 8, 1, -1);
  }
  double ys[4] = {0, 6, 12, 18};
  for (int k = 0; k < 4; k++) tb.axis_y[k] = ys[k];
  for (int k = 0; k < 3; k++) tb.axis_el[k] = 1;
  tb.def.n_axis = 4;
  tb.def.element_nodes = 2;
  cupid_cuf_beam beam = tb_create(&tb);
  cupid_box region = {.lo = {0, 6, 0}, .hi = {8, 12, 8}, .has = {1, 1, 1}};
  int rmat = 0;
  cupid_pd_grid grid = NULL;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &region, &rmat, &grid));
  cupid_int n_pd = cupid_pd_grid_num_nodes(grid);
  CUPID_ASSERT_OK(cupid_coupling_deactivate(beam, 1, &region));
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(beam, 3 * n_pd));
  cupid_int ndof = 3 * n_pd + cupid_cuf_num_dofs(beam);
  cupid_pd_material mat = {.E = 1000.0, .nu = 0.2};
  cupid_coupling_options co = {.beam_def = &tb.def, .materials = tb.mat, .n_materials = 1,
                               .n_regions = 1, .regions = &region, .region_materials = &rmat,
                               .spacing = 1.0,
                               .pd = {.horizon = 1.5, .model = CUPID_PD_LPS,
                                      .influence = CUPID_INFLUENCE_GAUSSIAN,
                                      .partial_volume = CUPID_PARTIAL_PDLAMMPS,
                                      .materials = &mat, .n_materials = 1}};
  cupid_coupling_h c = NULL;
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_coupling_lagrange_create(beam, grid, &co, &c, &K));
  double asym = cupid_csr_asymmetry(K);
  const cupid_int *tied;
  cupid_int nt;
  cupid_coupling_tied(c, &tied, &nt);
  assert_int_equal(nt, 2 * 8 * 8); /* the planes y = 6.5 and 11.5 */

  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(ndof, &bc));
  for (cupid_int t = 0; t < nt; t++)
    for (int k = 0; k < 3; k++) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 3 * tied[t] + k, 0.0));
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  for (cupid_int n = 0; n < info.n_fe_nodes; n++) {
    cupid_int bn = n / info.M;
    int used = cupid_cuf_node_used(beam, (int)(n % info.M), bn);
    if (!used || cupid_cuf_beam_node_y(beam, bn) < 1e-9)
      for (int k = 0; k < 3; k++) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 3 * n_pd + 3 * n + k, 0.0));
  }
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  double *f = NULL, *u = NULL, *r = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *r, "r", &r));
  double P = 640.0; /* 10 MPa on the 8 x 8 end face */
  double at[3] = {4, 18, 4}, load[3] = {0, P, 0};
  CUPID_ASSERT_OK(cupid_cuf_point_load_add(beam, at, load, f));
  cupid_solve_info si;
  CUPID_ASSERT_OK(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, &si));
  cupid_coupling_recover(c, u);
  /* Tied nodes follow the interface section. */
  const double *x = cupid_pd_grid_coords(grid);
  double err = 0.0, umax = 0.0;
  for (cupid_int t = 0; t < nt; t++) {
    const double *p = x + 3 * tied[t];
    double yi = p[1] < 9 ? 6.0 : 12.0, v[3];
    CUPID_ASSERT_OK(cupid_cuf_displacement_at(beam, u, p[0], yi, p[2], v));
    for (int k = 0; k < 3; k++) {
      err = fmax(err, fabs(v[k] - u[3 * tied[t] + k]));
      umax = fmax(umax, fabs(v[k]));
    }
  }
  /* Reaction at the clamp: K u on the fixed FE DOFs of y = 0, projected on a y translation
   * (the constant expansion term carries it: TE term 0, every LE node). */
  cupid_csr_matvec(K, u, r);
  double *t = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)ndof, sizeof *t, "t", &t));
  for (cupid_int n = 0; n < info.n_fe_nodes; n++)
    if (cupid_cuf_beam_node_y(beam, n / info.M) < 1e-9)
      t[3 * n_pd + 3 * n + 1] = le || n % info.M == 0 ? 1.0 : 0.0;
  double reaction = 0.0;
  for (cupid_int d = 0; d < ndof; d++) reaction += t[d] * r[d];
  printf("  %s: asymmetry %.2e, tied-node misfit %.2e, reaction %.10g vs load %g\n",
         le ? "L9" : "TE2", asym, err / umax, reaction, P);
  assert_true(asym <= 1e-13);
  assert_true(err <= 1e-12 * umax);
  assert_true(fabs(reaction + P) <= 1e-9 * P);
  cupid_free(&t);
  cupid_free(&f);
  cupid_free(&u);
  cupid_free(&r);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  cupid_coupling_destroy(&c);
  cupid_pd_grid_destroy(&grid);
  cupid_cuf_beam_destroy(&beam);
}

static void te2(void **state) {
  (void)state;
  run_case(0);
}
static void l9(void **state) {
  (void)state;
  run_case(1);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(te2), cmocka_unit_test(l9)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
