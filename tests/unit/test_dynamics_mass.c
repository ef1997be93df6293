/* Unit tests of the CUF mass matrix (src/cuf/mass.c): symmetry, the rigid-translation mass
 * t.M t = rho V for TE and LE sections with two materials, HRZ lumping keeps rho V per
 * direction, and the mass follows the DOF offset (coupled layouts). */
#include <math.h>
#include <stdlib.h>

#include "cupid/dynamics.h"
#include "unit/test_cuf_common.h"

static void unit_field(void *ctx, const double p[3], double density, double out[3]) {
  const int *k = ctx;
  for (int c = 0; c < 3; c++) out[c] = c == *k ? 1.0 : 0.0;
}

/* Two components of different densities: 2 x 1 of rho 3 and 1 x 1 of rho 5, length 4:
 * mass (2 * 3 + 1 * 5) * 4 = 44. Tolerances 1e-12 relative (exact quadrature). */
static void check_beam(tb_beam *t) {
  t->mat[0].density = 3.0;
  t->mat[0].has_density = 1;
  t->mat[1] = t->mat[0];
  t->mat[1].density = 5.0;
  t->n_mat = 2;
  tb_axis(t, 0.0, 4.0, 3, 3);
  tb_rect(t, 0.0, 2.0, 2, 0.0, 1.0, 1, 0);
  tb_rect(t, 2.0, 3.0, 1, 0.0, 1.0, 1, 1);
  cupid_cuf_beam b = tb_create(t);
  cupid_csr M = NULL;
  CUPID_ASSERT_OK(cupid_cuf_mass_assemble(b, &M));
  assert_true(cupid_csr_asymmetry(M) < 1e-14);
  cupid_int n = cupid_cuf_num_dofs(b);
  double *tr = NULL, *Mt = NULL, *d = NULL, total;
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *tr, "t", &tr));
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *Mt, "Mt", &Mt));
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *d, "d", &d));
  CUPID_ASSERT_OK(cupid_cuf_mass_total(b, &total));
  ASSERT_NEAR(total, 44.0, 44e-12);
  CUPID_ASSERT_OK(cupid_cuf_mass_lumped(b, d));
  for (int k = 0; k < 3; k++) {
    for (cupid_int q = 0; q < n; q++) tr[q] = 0.0;
    CUPID_ASSERT_OK(cupid_cuf_interpolate(b, unit_field, &k, tr));
    cupid_csr_matvec(M, tr, Mt);
    double m = 0.0, ml = 0.0;
    for (cupid_int q = 0; q < n; q++) m += tr[q] * Mt[q], ml += tr[q] * d[q] * tr[q];
    ASSERT_NEAR(m, 44.0, 44e-12);  /* consistent: exact rigid-body mass */
    ASSERT_NEAR(ml, 44.0, 44e-12); /* HRZ: the translational DOFs carry rho V */
  }
  /* at a DOF offset the matrix lands shifted by offset / 3 blocks */
  cupid_int off = 6, nb = n / 3 + off / 3;
  cupid_int *rowptr = NULL, *col = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)nb + 1, sizeof *rowptr, "rowptr", &rowptr));
  CUPID_ASSERT_OK(cupid_calloc((size_t)nb * nb, sizeof *col, "col", &col));
  for (cupid_int r = 0; r < nb; r++) {
    rowptr[r + 1] = rowptr[r] + nb;
    for (cupid_int c = 0; c < nb; c++) col[r * nb + c] = c;
  }
  cupid_csr G = NULL;
  CUPID_ASSERT_OK(cupid_csr_create(nb, nb, 3, rowptr, col, &G));
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(b, off));
  CUPID_ASSERT_OK(cupid_cuf_mass_add(b, G));
  for (cupid_int r = 0; r < n / 3; r++)
    for (cupid_int q = M->rowptr[r]; q < M->rowptr[r + 1]; q++) {
      const double *g = cupid_csr_find(G, r + 2, M->col[q] + 2);
      for (int e = 0; e < 9; e++) ASSERT_NEAR(g[e], M->val[9 * q + e], 1e-14);
    }
  cupid_free(&rowptr);
  cupid_free(&col);
  cupid_free(&tr);
  cupid_free(&Mt);
  cupid_free(&d);
  cupid_csr_destroy(&G);
  cupid_csr_destroy(&M);
  cupid_cuf_beam_destroy(&b);
}

static void test_mass_te2(void **state) {
  tb_beam t;
  tb_init(&t, 1e3, 0.3);
  tb_te(&t, 2);
  check_beam(&t);
}

static void test_mass_l9(void **state) {
  tb_beam t;
  tb_init(&t, 1e3, 0.3);
  tb_le(&t, 9);
  check_beam(&t);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_mass_te2), cmocka_unit_test(test_mass_l9)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
