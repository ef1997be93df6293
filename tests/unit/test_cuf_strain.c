/* cupid_cuf_strain_peaks (src/cuf/post.c): the largest principal strain of a beam solution at
 * the stiffness's quadrature points of every (beam element, section element) pair, the trigger
 * of adaptive PD zones (issue 37). Checks:
 *  - an affine field u = (R diag(l) R^T + W) x, a rotated strain plus a rigid rotation, on an
 *    L9 beam (which holds it exactly): every pair's peak is max(l) to 1e-12 (the rotation and
 *    the frame change nothing; a strain taken from the gradient without symmetrising, or an
 *    eigenvalue formula off, fails);
 *  - pure bending on a TE2 beam, u_y = k y z, u_z = -k y^2 / 2 (eps_yy = k z only): each
 *    pair's peak is k times the highest Gauss point's z of its section element (the section's
 *    own rule, cuf_gauss(sec_ng)), and the bottom row's elements (z < 0) have their peak at 0,
 *    the largest eigenvalue of a uniaxial compression; to 1e-8 of k (measured 5.4e-9: the TE
 *    section-wise projection of the field leaves round-off shears);
 *  - an inactive pair reads -inf. */
#include <math.h>
#include <stdlib.h>

#include "cuf/cuf_internal.h"
#include "test_cuf_common.h"

typedef struct {
  double G[9];
} affine;

static void affine_field(void *ctx, const double p[3], double density, double out[3]) {
  const affine *a = ctx;
  (void)density;
  for (int i = 0; i < 3; i++) out[i] = a->G[3 * i] * p[0] + a->G[3 * i + 1] * p[1] + a->G[3 * i + 2] * p[2];
}

static void bending_field(void *ctx, const double p[3], double density, double out[3]) {
  const double k = *(const double *)ctx;
  (void)density;
  out[0] = 0.0;
  out[1] = k * p[1] * p[2];
  out[2] = -0.5 * k * p[1] * p[1];
}

static double *solution(cupid_cuf_beam b, cupid_cuf_field_fn fn, void *ctx) {
  double *u = calloc((size_t)cupid_cuf_num_dofs(b), sizeof *u);
  CUPID_ASSERT_OK(cupid_cuf_interpolate(b, fn, ctx, u));
  return u;
}

static void affine_strain(void **state) {
  (void)state;
  tb_beam t;
  tb_init(&t, 1000.0, 0.3);
  tb_le(&t, 9);
  tb_axis(&t, 0.0, 6.0, 3, 3);
  tb_rect(&t, -1.0, 2.0, 2, -0.5, 1.0, 2, -1);
  cupid_cuf_beam b = tb_create(&t);
  /* R: rotations by 0.4 about z and 0.7 about x; l = (2e-3, -1e-3, 5e-4); W: a rotation */
  const double l[3] = {2e-3, -1e-3, 5e-4};
  const double cz = cos(0.4), sz = sin(0.4), cx = cos(0.7), sx = sin(0.7);
  const double Rz[9] = {cz, -sz, 0, sz, cz, 0, 0, 0, 1}, Rx[9] = {1, 0, 0, 0, cx, -sx, 0, sx, cx};
  double R[9] = {0}, G[9] = {0};
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++)
      for (int k = 0; k < 3; k++) R[3 * i + j] += Rz[3 * i + k] * Rx[3 * k + j];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++)
      for (int k = 0; k < 3; k++) G[3 * i + j] += R[3 * i + k] * l[k] * R[3 * j + k];
  const double W[9] = {0, 3e-3, -1e-3, -3e-3, 0, 2e-3, 1e-3, -2e-3, 0};
  affine a;
  for (int k = 0; k < 9; k++) a.G[k] = G[k] + W[k];
  double *u = solution(b, affine_field, &a);
  cupid_cuf_info fi;
  cupid_cuf_get_info(b, &fi);
  const cupid_int n = fi.n_beam_elements * fi.n_section_elements;
  double *peak = malloc(sizeof *peak * (size_t)n);
  CUPID_ASSERT_OK(cupid_cuf_strain_peaks(b, u, peak));
  for (cupid_int q = 0; q < n; q++) ASSERT_NEAR(peak[q], l[0], 1e-12 * l[0]);
  /* an inactive pair */
  CUPID_ASSERT_OK(cupid_cuf_set_active(b, 1, 2, 0));
  CUPID_ASSERT_OK(cupid_cuf_strain_peaks(b, u, peak));
  assert_true(isinf(peak[1 * fi.n_section_elements + 2]) && peak[1 * fi.n_section_elements + 2] < 0);
  ASSERT_NEAR(peak[0], l[0], 1e-12 * l[0]);
  free(peak);
  free(u);
  cupid_cuf_beam_destroy(&b);
}

static void bending_strain(void **state) {
  (void)state;
  tb_beam t;
  tb_init(&t, 1000.0, 0.3);
  tb_te(&t, 2);
  tb_axis(&t, 0.0, 8.0, 4, 3);
  tb_rect(&t, -1.0, 1.0, 1, -1.0, 1.0, 4, -1);
  cupid_cuf_beam b = tb_create(&t);
  double k = 1e-3;
  double *u = solution(b, bending_field, &k);
  cupid_cuf_info fi;
  cupid_cuf_get_info(b, &fi);
  const cupid_int ns = fi.n_section_elements, n = fi.n_beam_elements * ns;
  double *peak = malloc(sizeof *peak * (size_t)n);
  CUPID_ASSERT_OK(cupid_cuf_strain_peaks(b, u, peak));
  double gx[CUF_MAX_GAUSS], gw[CUF_MAX_GAUSS];
  cuf_gauss(b->sec_ng, gx, gw);
  double gmax = -1.0;
  for (int i = 0; i < b->sec_ng; i++) gmax = fmax(gmax, gx[i]);
  int below = 0;
  for (cupid_int se = 0; se < ns; se++) {
    double bx[4];
    int npe, mat;
    cupid_cuf_section_element(b, se, &npe, NULL, &mat, bx);
    const double ztop = bx[2] + 0.5 * (1.0 + gmax) * (bx[3] - bx[2]);
    const double expect = fmax(k * ztop, 0.0);
    below += ztop < 0;
    for (cupid_int be = 0; be < fi.n_beam_elements; be++)
      ASSERT_NEAR(peak[be * ns + se], expect, 1e-8 * k);
  }
  assert_true(below > 0);
  free(peak);
  free(u);
  cupid_cuf_beam_destroy(&b);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(affine_strain), cmocka_unit_test(bending_strain)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
