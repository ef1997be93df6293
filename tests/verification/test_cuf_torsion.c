/* Verification: torsion of a square section. The twist per unit length far from the ends
 * gives an effective torsion constant J = T / (G theta') that must converge to Saint-Venant's
 * 0.1405770 a^4, with TE order (nested spaces: J decreases monotonically) and with LE section
 * refinement (rate 2 for L4; for L9/L16 about 4, capped by the r^2 log r term of the warping
 * function at the convex corners). Cross-section convergence rates are checked here. */
#include <stdlib.h>

#include "unit/test_cuf_common.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static const double A = 1.0, LEN = 10.0, YOUNG = 1.0, NU = 0.3;

/* Saint-Venant: J = beta a^4, beta = (1 - 192/pi^5 sum_{n odd} tanh(n pi / 2) / n^5) / 3. */
static double saint_venant(void) {
  double s = 0;
  for (int n = 1; n < 200; n += 2) s += tanh(n * M_PI / 2) / pow(n, 5);
  return (1 - 192 / pow(M_PI, 5) * s) / 3 * pow(A, 4);
}

/* Shear traction k (-z, 0, x) on the end face: torque T = k Ip, Ip = a^4 / 6. */
static void torque(void *ctx, const double p[3], double density, double out[3]) {
  double k = *(const double *)ctx;
  (void)density;
  out[0] = -k * p[2];
  out[1] = 0;
  out[2] = k * p[0];
}

/* J from the twist rate at mid-length; *work = f.u (the compliance under the end torque). */
static double effective_J(int te, int N, int ln, int nsec, double *work) {
  tb_beam t;
  tb_init(&t, YOUNG, NU);
  if (te) tb_te(&t, N);
  else tb_le(&t, ln);
  tb_axis(&t, 0, LEN, 10, 4);
  tb_rect(&t, -A / 2, A / 2, nsec, -A / 2, A / 2, nsec, -1);
  cupid_cuf_beam b = tb_create(&t);
  cupid_int n = cupid_cuf_num_dofs(b);
  double *f = NULL, k = 1.0;
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_cuf_traction_add(b, LEN, NULL, torque, &k, f, NULL));
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
  CUPID_ASSERT_OK(cupid_cuf_clamp_node(b, 0, bc));
  double *u = tb_solve(b, f, bc, NULL);
  /* rotation of the section from u_z at x = +-a/2 on z = 0, at 0.4 L and 0.6 L (the clamp
   * and load end effects decay within about one section width) */
  double th[2], ys[2] = {0.4 * LEN, 0.6 * LEN};
  for (int q = 0; q < 2; q++) {
    double d1[3], d2[3];
    CUPID_ASSERT_OK(cupid_cuf_displacement_at(b, u, A / 2, ys[q], 0, d1));
    CUPID_ASSERT_OK(cupid_cuf_displacement_at(b, u, -A / 2, ys[q], 0, d2));
    th[q] = (d1[2] - d2[2]) / A;
  }
  double G = YOUNG / (2 * (1 + NU)), T = k * pow(A, 4) / 6;
  *work = 0;
  for (cupid_int q = 0; q < n; q++) *work += f[q] * u[q];
  cupid_free(&u);
  cupid_free(&f);
  cupid_dirichlet_destroy(&bc);
  cupid_cuf_beam_destroy(&b);
  return T / (G * (th[1] - th[0]) / (ys[1] - ys[0]));
}

static void test_torsion_te(void **state) {
  (void)state;
  double J = saint_venant(), prev = 0, Jn[11];
  printf("  square section, Saint-Venant J = %.7f a^4\n  %-6s %10s %10s %14s\n", J, "model", "J/a^4", "rel. err", "f.u");
  for (int N = 1; N <= 10; N++) {
    double w;
    Jn[N] = effective_J(1, N, 0, 1, &w);
    printf("  TE%-4d %10.6f %10.2e %14.10f\n", N, Jn[N], Jn[N] / J - 1, w);
    /* nested spaces: the compliance can only grow (minimum of the potential energy; 1e-10
     * relative for round-off). The point-measured twist need not be monotone. */
    assert_true(w >= prev * (1 - 1e-10));
    prev = w;
  }
  /* TE1-3 cannot warp (the warping function is odd in x and z, degree >= 4): J = Ip =
   * a^4 / 6 exactly (1e-6: end effects at 4 a from the ends) */
  for (int N = 1; N <= 3; N++) ASSERT_NEAR(Jn[N], 1.0 / 6, 1e-6);
  /* converges: TE4 within 2e-3 (the first warping order), TE10 within 1e-4 (observed 1.7e-5) */
  assert_true(fabs(Jn[4] / J - 1) < 2e-3 && fabs(Jn[10] / J - 1) < 1e-4);
}

static void test_torsion_le(void **state) {
  (void)state;
  double J = saint_venant();
  struct { int ln, max; double rate; } rows[] = {{4, 16, 1.8}, {9, 8, 3.4}, {16, 4, 3.4}};
  for (size_t r = 0; r < 3; r++) {
    double err[8], prev = 0;
    int k = 0;
    for (int s = 1; s <= rows[r].max; s *= 2, k++) {
      double w, Je = effective_J(0, 0, rows[r].ln, s, &w);
      err[k] = fabs(Je / J - 1);
      printf("  L%-2d %2dx%-2d %10.6f %10.2e", rows[r].ln, s, s, Je, err[k]);
      if (k && err[k - 1] > 1e-12 && err[k] > 0) printf("  rate %.2f", log2(err[k - 1] / err[k]));
      printf("\n");
      /* nested meshes: the compliance can only grow (1e-10 relative: round-off) */
      assert_true(w >= prev * (1 - 1e-10));
      prev = w;
    }
    /* rate over the last refinement: L4 2 (margin 0.2), L9 and L16 ~ 3.7-3.9 (margin from 4) */
    assert_true(err[k - 1] < (rows[r].ln == 4 ? 5e-3 : 1e-4));
    double rate = log2(err[k - 2] / err[k - 1]);
    if (!(rate > rows[r].rate)) fail_msg("L%d: rate %.2f <= %.2f", rows[r].ln, rate, rows[r].rate);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_torsion_te), cmocka_unit_test(test_torsion_le)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
