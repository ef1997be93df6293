/* Unit tests of the quadrature coefficients (partial volumes) and influence functions
 * (src/pd/partial_volume.c), with reference numbers from coupling.md section 5.4. */
#include <math.h>

#include "testutil.h"

static const double PI = 3.14159265358979323846;

static double pv(cupid_partial_volume r, double i, double j, double k, double h, double d) {
  return cupid_pd_partial_volume(r, i * h, j * h, k * h, h, d);
}

static void test_none_rule(void **state) {
  (void)state;
  ASSERT_NEAR(pv(CUPID_PARTIAL_NONE, 3, 0, 0, 1, 3), 1.0, 0);
  ASSERT_NEAR(pv(CUPID_PARTIAL_NONE, 2, 2, 1, 1, 3), 1.0, 0); /* |xi| = 3 exactly */
  ASSERT_NEAR(pv(CUPID_PARTIAL_NONE, 3, 0, 0, 1, 2.999), 0.0, 0);
  ASSERT_NEAR(pv(CUPID_PARTIAL_NONE, 3, 1, 0, 1, 3), 0.0, 0);
  ASSERT_NEAR(pv(CUPID_PARTIAL_NONE, 1, 1, 0, 0.1, 0.15), 1.0, 0);
}

/* Parks et al.: 1 up to delta - h/2, (delta + h/2 - r)/h up to delta, 0 beyond. */
static void test_pdlammps_rule(void **state) {
  (void)state;
  ASSERT_NEAR(pv(CUPID_PARTIAL_PDLAMMPS, 2, 1, 0, 1, 3), 1.0, 0);           /* r = 2.236 */
  ASSERT_NEAR(pv(CUPID_PARTIAL_PDLAMMPS, 2, 2, 0, 1, 3), 3.5 - sqrt(8), 1e-15);
  ASSERT_NEAR(pv(CUPID_PARTIAL_PDLAMMPS, 3, 0, 0, 1, 3), 0.5, 1e-15);
  ASSERT_NEAR(pv(CUPID_PARTIAL_PDLAMMPS, 2, 2, 1, 1, 3), 0.5, 1e-15);
  ASSERT_NEAR(pv(CUPID_PARTIAL_PDLAMMPS, 3, 1, 0, 1, 3), 0.0, 0);            /* beyond delta */
  ASSERT_NEAR(pv(CUPID_PARTIAL_PDLAMMPS, 3, 0, 0, 1, 3.015), 0.515, 1e-14);
  ASSERT_NEAR(pv(CUPID_PARTIAL_PDLAMMPS, 3, 0, 0, 0.2, 0.7), 0.5 + 0.1 / 0.2, 1e-14);
}

/* EXACT: the cells meeting the ball partition it, so sum beta h^3 = 4/3 pi delta^3.
 * Tolerance 1e-9 relative (the target accuracy of beta is ~1e-13 absolute per cell). */
static void test_exact_sums_to_ball(void **state) {
  (void)state;
  const double cases[][2] = {{1, 3.0}, {1, 3.015}, {1, 2.7}, {1, 1.3}, {0.2, 0.83}, {2.0, 8.9}};
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    const double h = cases[c][0], d = cases[c][1];
    const int R = (int)ceil(d / h + 1);
    double sum = 0.0;
    for (int k = -R; k <= R; k++)
      for (int j = -R; j <= R; j++)
        for (int i = -R; i <= R; i++) sum += pv(CUPID_PARTIAL_EXACT, i, j, k, h, d) * h * h * h;
    const double ball = 4.0 / 3.0 * PI * d * d * d;
    ASSERT_NEAR(sum / ball, 1.0, 1e-9);
  }
}

static void test_exact_single_offsets(void **state) {
  (void)state;
  /* Ball inside the node's own cell. */
  ASSERT_NEAR(pv(CUPID_PARTIAL_EXACT, 0, 0, 0, 1, 0.4), 4.0 / 3.0 * PI * 0.064, 1e-13);
  /* Cell [0,h]^3 with delta <= h holds one octant of the ball; [0,h]^2 x [-h/2,h/2] with
   * delta <= h/2 a quarter. */
  ASSERT_NEAR(cupid_pd_partial_volume(CUPID_PARTIAL_EXACT, 0.5, 0.5, 0.5, 1, 0.7),
              PI * 0.343 / 6.0, 1e-13);
  ASSERT_NEAR(cupid_pd_partial_volume(CUPID_PARTIAL_EXACT, 0.5, -0.5, 0, 1, 0.45),
              PI * pow(0.45, 3) / 3.0, 1e-13);
  /* A spherical cap of height t = 0.01 h through the face of a cell on the z axis
   * (cap radius 0.245 h < h/2, so the cap lies inside the cell's cross-section). */
  const double d = 3.0, t = 0.01, cap = PI * t * t * (3 * d - t) / 3.0;
  ASSERT_NEAR(cupid_pd_partial_volume(CUPID_PARTIAL_EXACT, 0, 0, d - t + 0.5, 1, d) / cap, 1.0,
              1e-10);
  /* Fully inside, fully outside, touching. */
  ASSERT_NEAR(pv(CUPID_PARTIAL_EXACT, 1, 1, 1, 1, 3), 1.0, 0);
  ASSERT_NEAR(pv(CUPID_PARTIAL_EXACT, 4, 0, 0, 1, 3), 0.0, 0);
  ASSERT_NEAR(pv(CUPID_PARTIAL_EXACT, 3, 3, 0, 1, 2.5 * sqrt(2) - 1e-9), 0.0, 0);
  /* Cells beyond delta that meet the ball are kept: centre at 3.2 > 3. */
  double b = cupid_pd_partial_volume(CUPID_PARTIAL_EXACT, 3.2, 0, 0, 1, 3);
  assert_true(b > 0 && b < 0.5);
  /* Exactly symmetric under sign changes and permutations (keeps K symmetric). */
  const double ref = pv(CUPID_PARTIAL_EXACT, 3, 1, 2, 1, 3.2);
  assert_true(ref > 0 && ref < 1);
  assert_true(pv(CUPID_PARTIAL_EXACT, -1, 2, -3, 1, 3.2) == ref);
  assert_true(pv(CUPID_PARTIAL_EXACT, 2, -3, 1, 1, 3.2) == ref);
}

/* Discrete family volume and bond-based stiffness with the analytic micromodulus
 * (constant omega), against coupling.md 5.4 (4 digits given there). */
static void test_family_sums_against_table(void **state) {
  (void)state;
  const struct {
    cupid_partial_volume rule;
    double delta, vol, keff;
  } rows[] = {{CUPID_PARTIAL_NONE, 3.0, 1.0876, 1.1209},     {CUPID_PARTIAL_PDLAMMPS, 3.0, 0.9201, 0.9002},
              {CUPID_PARTIAL_EXACT, 3.0, 1.0000, 1.0178},    {CUPID_PARTIAL_NONE, 3.015, 1.0714, 1.0987},
              {CUPID_PARTIAL_PDLAMMPS, 3.015, 0.9119, 0.8896}, {CUPID_PARTIAL_EXACT, 4.015, 1.0000, 1.0102},
              {CUPID_PARTIAL_PDLAMMPS, 4.015, 0.8891, 0.8555}};
  for (size_t r = 0; r < sizeof rows / sizeof rows[0]; r++) {
    const double d = rows[r].delta;
    const int R = (int)ceil(d + 1);
    double vol = 0, s = 0;
    for (int k = -R; k <= R; k++)
      for (int j = -R; j <= R; j++)
        for (int i = -R; i <= R; i++) {
          double b = pv(rows[r].rule, i, j, k, 1, d);
          vol += b;
          s += b * sqrt((double)(i * i + j * j + k * k));
        }
    /* The table is rounded to 4 decimals: 0.6e-4 absolute. */
    ASSERT_NEAR(vol / (4.0 / 3.0 * PI * d * d * d), rows[r].vol, 6e-5);
    ASSERT_NEAR(s / (PI * d * d * d * d), rows[r].keff, 6e-5);
  }
}

static void test_1d_rules(void **state) {
  (void)state;
  ASSERT_NEAR(cupid_pd_partial_volume_1d(CUPID_PARTIAL_EXACT, 3, 1, 3), 0.5, 1e-15);
  ASSERT_NEAR(cupid_pd_partial_volume_1d(CUPID_PARTIAL_EXACT, -2, 1, 3), 1.0, 0);
  ASSERT_NEAR(cupid_pd_partial_volume_1d(CUPID_PARTIAL_EXACT, 3.4, 1, 3), 0.1, 1e-14);
  ASSERT_NEAR(cupid_pd_partial_volume_1d(CUPID_PARTIAL_EXACT, 3.5, 1, 3), 0.0, 0);
  ASSERT_NEAR(cupid_pd_partial_volume_1d(CUPID_PARTIAL_PDLAMMPS, 2.6, 1, 3), 0.9, 1e-14);
  ASSERT_NEAR(cupid_pd_partial_volume_1d(CUPID_PARTIAL_PDLAMMPS, 3.4, 1, 3), 0.0, 0);
  ASSERT_NEAR(cupid_pd_partial_volume_1d(CUPID_PARTIAL_NONE, 3, 1, 3), 1.0, 0);
  /* EXACT segments partition [-delta, delta]. */
  const double h = 0.3, d = 1.37;
  double sum = 0;
  for (int j = -10; j <= 10; j++) sum += cupid_pd_partial_volume_1d(CUPID_PARTIAL_EXACT, j * h, h, d);
  ASSERT_NEAR(sum * h, 2 * d, 1e-14);
}

static void test_influence(void **state) {
  (void)state;
  ASSERT_NEAR(cupid_pd_influence(CUPID_INFLUENCE_GAUSSIAN, 3, 3), exp(-1.0), 1e-16);
  ASSERT_NEAR(cupid_pd_influence(CUPID_INFLUENCE_GAUSSIAN, 1.5, 3), exp(-0.25), 1e-16);
  ASSERT_NEAR(cupid_pd_influence(CUPID_INFLUENCE_INVERSE, 2, 3), 0.5, 0);
  ASSERT_NEAR(cupid_pd_influence(CUPID_INFLUENCE_CONSTANT, 2, 3), 1.0, 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_none_rule),         cmocka_unit_test(test_pdlammps_rule),
      cmocka_unit_test(test_exact_sums_to_ball), cmocka_unit_test(test_exact_single_offsets),
      cmocka_unit_test(test_family_sums_against_table), cmocka_unit_test(test_1d_rules),
      cmocka_unit_test(test_influence)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
