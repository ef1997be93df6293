/* `peridynamics.fracture.calibration: grid` (issue 38, item 1): the critical stretch s0 at
 * which cutting a plane through this lattice releases G0 per unit area, checked by brute force.
 *
 * A bond-based block (E = 22350, nu = 1/4, G0 = 0.01006: the SENB's), spacing 1: m = 3 with
 * exact partial volumes and a constant influence, m = 2 with none and the Gaussian influence. After setup, s0 of the model
 * (grid, then continuum) is read from the problem, and the energy released by cutting planes
 * is summed pair by pair on an unbounded lattice: for 200 planes (40 under CUPID_TEST_SMALL)
 * of pseudo-random normals and
 * positions (fixed seed), every pair of lattice nodes (cell centres) with partial volume beta
 * whose segment crosses the plane inside a disk of radius 8 around the plane's centre, each
 * pair's energy c omega beta s0^2 |xi| V^2 / 2 (c the operator's micromodulus, 18 K / S_full),
 * summed and divided by the disks' area. For a plane placed at random the expected count of
 * crossings in the disk is exact; the sampling spread of the mean is printed (about 0.3%).
 * Checks:
 *  - grid: the cut releases G0 to 1% (the bound: 3 times the sampling spread);
 *  - continuum: the cut releases the fraction summary.json reports (g_eff_over_g0_continuum,
 *    here computed by the same formula the problem uses) to 1%, and that fraction differs from
 *    1 by more than the tolerance for at least one lattice (so the two calibrations are told
 *    apart: measured 1.030 and 0.946; the cut released 0.9994 and 0.9976 G0 with grid). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "problem/method.h"
#include "testutil.h"

static int small(void) { return getenv("CUPID_TEST_SMALL") != NULL; }

static cupid_problem make_block(const char *calibration, double m, const char *pv,
                                const char *influence) {
  char yaml[1024];
  const int len = snprintf(
      yaml, sizeof yaml,
      "title: calibration\nmaterials:\n  c: {E: 22350, nu: 0.25}\n"
      "peridynamics:\n  spacing: 1.0\n  horizon: %.17g\n  model: bond\n  partial_volume: %s\n"
      "  influence: %s\n"
      "  material: c\n  regions:\n    - {x: [0, 8], y: [0, 8], z: [0, 8]}\n"
      "  fracture: {energy_release_rate: 0.01006, calibration: %s}\n"
      "constraints:\n  - fix: {box: {x: [0, 1]}, components: [x, y, z]}\n"
      "analysis: {type: static, solver: direct}\n"
      "output: {directory: /tmp/cupid_calibration_unused}\n",
      m * 1.005, pv, influence, calibration);
  assert_true(len < (int)sizeof yaml);
  cupid_run_options ro = cupid_run_options_default();
  ro.quiet = 1;
  cupid_problem p = NULL;
  CUPID_ASSERT_OK(cupid_problem_create_from_string(yaml, "calibration.yaml", &ro, &p));
  CUPID_ASSERT_OK(cupid_problem_setup(p));
  return p;
}

static double uniform(uint64_t *s) {
  *s ^= *s << 13, *s ^= *s >> 7, *s ^= *s << 17;
  return (double)(*s >> 11) / 9007199254740992.0;
}

/* The energy per unit area that cutting the lattice (spacing 1, V = 1) at stretch s releases,
 * by brute force over planes (see the header). */
static double cut_energy(cupid_partial_volume rule, cupid_influence infl, double delta, double c,
                         double s, double *spread) {
  const double rho = 8.0;
  const int reach = (int)ceil(delta + 1.0);
  /* the family's offsets and partial volumes, once */
  int nf = 0;
  static double off[2197][5]; /* xi, |xi|, beta */
  for (int a = -reach; a <= reach; a++)
    for (int b = -reach; b <= reach; b++)
      for (int d = -reach; d <= reach; d++) {
        const double beta = cupid_pd_partial_volume(rule, a, b, d, 1.0, delta);
        if (beta <= 0.0 || (a == 0 && b == 0 && d == 0)) continue;
        const double r = sqrt((double)(a * a + b * b + d * d));
        off[nf][0] = a, off[nf][1] = b, off[nf][2] = d;
        off[nf][3] = r, off[nf][4] = cupid_pd_influence(infl, r, delta) * beta; /* omega beta */
        nf++;
      }
  uint64_t seed = 0x9E3779B97F4A7C15ull;
  double sum = 0.0, sum2 = 0.0;
  const int planes = small() ? 40 : 200;
  const int R = (int)ceil(rho + delta) + 1;
  for (int p = 0; p < planes; p++) {
    double n[3], z = 2.0 * uniform(&seed) - 1.0, phi = 6.283185307179586 * uniform(&seed);
    n[0] = sqrt(1 - z * z) * cos(phi), n[1] = sqrt(1 - z * z) * sin(phi), n[2] = z;
    const double o[3] = {uniform(&seed), uniform(&seed), uniform(&seed)}; /* the plane's centre */
    double e = 0.0;
    for (int i = -R; i <= R; i++)
      for (int j = -R; j <= R; j++)
        for (int k = -R; k <= R; k++) {
          const double x[3] = {i + 0.5 - o[0], j + 0.5 - o[1], k + 0.5 - o[2]};
          const double dx = x[0] * n[0] + x[1] * n[1] + x[2] * n[2];
          if (dx >= 0.0 || dx < -delta - 1.0) continue; /* i on the negative side, near it */
          if (x[0] * x[0] + x[1] * x[1] + x[2] * x[2] - dx * dx > (rho + delta) * (rho + delta))
            continue;
          for (int f = 0; f < nf; f++) {
            const double *xi = off[f];
            const double dn = xi[0] * n[0] + xi[1] * n[1] + xi[2] * n[2];
            if (dx + dn <= 0.0) continue; /* j not across */
            const double t = -dx / dn;
            double r2 = 0.0; /* the crossing point's distance from the plane's centre */
            for (int c3 = 0; c3 < 3; c3++) {
              const double q = x[c3] + t * xi[c3];
              r2 += q * q;
            }
            if (r2 > rho * rho) continue;
            e += 0.5 * c * xi[4] * s * s * xi[3]; /* V = 1 */
          }
        }
    const double g = e / (3.141592653589793 * rho * rho);
    sum += g, sum2 += g * g;
  }
  const double mean = sum / planes;
  *spread = sqrt(fmax(sum2 / planes - mean * mean, 0.0) / planes) / mean;
  return mean;
}

typedef struct {
  double m;
  const char *pv, *infl;
  cupid_partial_volume rule;
  cupid_influence influence;
} lattice;

static void grid_releases_g0(void **state) {
  (void)state;
  const lattice cases[2] = {
      {3.0, "exact", "constant", CUPID_PARTIAL_EXACT, CUPID_INFLUENCE_CONSTANT},
      {2.0, "none", "gaussian", CUPID_PARTIAL_NONE, CUPID_INFLUENCE_GAUSSIAN}};
  const double G0 = 0.01006, K = 22350.0 / (3.0 * (1.0 - 0.5));
  int told_apart = 0;
  for (int k = 0; k < 2; k++) {
    double s0[2], frac = 0.0, c = 0.0;
    for (int g = 0; g < 2; g++) { /* 0 continuum, 1 grid */
      cupid_problem p = make_block(g ? "grid" : "continuum", cases[k].m, cases[k].pv, cases[k].infl);
      cupid_problem_state *prob = p;
      s0[g] = prob->node_stretch[0];
      double m_full = 0.0, S_full = 0.0;
      cupid_pd_operator_full_family(prob->op, &m_full, &S_full);
      c = 18.0 * K / S_full;
      frac = 5.0 * (m_full / S_full) / (4.0 * prob->model->pd.horizon);
      cupid_problem_destroy(&p);
    }
    const double delta = cases[k].m * 1.005;
    double spread_g = 0.0, spread_c = 0.0;
    const double Gg = cut_energy(cases[k].rule, cases[k].influence, delta, c, s0[1], &spread_g);
    const double Gc = cut_energy(cases[k].rule, cases[k].influence, delta, c, s0[0], &spread_c);
    printf("  m = %g, partial volumes %s, influence %s: s0 continuum %.6g, grid %.6g; the cut releases "
           "%.4f G0 (grid, spread %.1e) and %.4f G0 (continuum; the formula's fraction %.4f)\n",
           cases[k].m, cases[k].pv, cases[k].infl, s0[0], s0[1], Gg / G0, spread_g, Gc / G0, frac);
    assert_true(fabs(Gg / G0 - 1.0) <= 0.01);
    assert_true(fabs(Gc / G0 / frac - 1.0) <= 0.01);
    told_apart += fabs(frac - 1.0) > 0.01;
  }
  assert_true(told_apart >= 1);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(grid_releases_g0)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
