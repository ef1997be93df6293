/* Effective moduli of the discrete PD operators at an interior node (m = delta/h = 3):
 * bulk modulus exact for every partial-volume rule (LPS with discrete m, bond-based with
 * the discretely calibrated micromodulus), and the shear moduli for eps_xy and for
 * (eps_xx - eps_yy)/2, printed as a table and checked against coupling.md 5.4 (constant
 * influence) and the 1% isotropy of EXACT partial volumes. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "testutil.h"

static const char *infl_name[] = {"gaussian", "inverse", "constant"};
static const char *pv_name[] = {"none", "pdlammps", "exact"};

typedef struct {
  double bulk, mu_xy, mu_d; /* ratios to the continuum values */
  double off;               /* largest spurious stress component / expected */
} moduli;

/* Stress at the centre node for u = G x, for three gradients G. */
static moduli measure(cupid_pd_grid g, cupid_pd_model_kind model, int infl, int pvr, double nu) {
  const double E = 7.0e4, delta = 3.0, eps = 1e-3;
  cupid_pd_material mat = {E, nu};
  cupid_pd_operator_options o = {.horizon = delta, .model = model, .influence = (cupid_influence)infl,
                                 .partial_volume = (cupid_partial_volume)pvr, .materials = &mat,
                                 .n_materials = 1};
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(g, &o, &op));
  const cupid_int nn = cupid_pd_grid_num_nodes(g);
  cupid_int ext[3];
  cupid_pd_grid_extent(g, ext);
  const cupid_int c = cupid_pd_grid_node_at(g, ext[0] / 2, ext[1] / 2, ext[2] / 2);
  const double *x = cupid_pd_grid_coords(g);
  const double *xc = x + 3 * c;
  double *u = malloc(3 * (size_t)nn * sizeof *u), *s = malloc(6 * (size_t)nn * sizeof *s);
  const double K = E / (3 * (1 - 2 * nu)), mu = model == CUPID_PD_LPS ? E / (2 * (1 + nu)) : 0.6 * K;
  const double G[3][9] = {{eps, 0, 0, 0, eps, 0, 0, 0, eps},  /* dilatation */
                          {0, eps, 0, eps, 0, 0, 0, 0, 0},    /* eps_xy = eps */
                          {eps, 0, 0, 0, -eps, 0, 0, 0, 0}};  /* (eps_xx - eps_yy)/2 = eps */
  double val[3], off = 0;
  for (int k = 0; k < 3; k++) {
    for (cupid_int p = 0; p < nn; p++)
      for (int i = 0; i < 3; i++) {
        double d[3] = {x[3 * p] - xc[0], x[3 * p + 1] - xc[1], x[3 * p + 2] - xc[2]};
        u[3 * p + i] = G[k][3 * i] * d[0] + G[k][3 * i + 1] * d[1] + G[k][3 * i + 2] * d[2];
      }
    CUPID_ASSERT_OK(cupid_pd_operator_stress(op, u, s));
    const double *sc = s + 6 * c;
    double spur;
    if (k == 0) { /* sigma = 3 K eps I */
      val[0] = sc[0] / (3 * K * eps);
      spur = fmax(fmax(fabs(sc[0] - sc[1]), fabs(sc[0] - sc[2])),
                  fmax(fabs(sc[3]), fmax(fabs(sc[4]), fabs(sc[5])))) / (3 * K * eps);
    } else if (k == 1) { /* sigma_xy = 2 mu eps */
      val[1] = sc[5] / (2 * mu * eps);
      spur = fmax(fmax(fabs(sc[0]), fabs(sc[1])), fmax(fabs(sc[2]), fmax(fabs(sc[3]), fabs(sc[4])))) /
             (2 * mu * eps);
    } else { /* sigma_xx - sigma_yy = 4 mu eps */
      val[2] = (sc[0] - sc[1]) / (4 * mu * eps);
      spur = fmax(fabs(sc[0] + sc[1]), fmax(fabs(sc[3]), fmax(fabs(sc[4]), fabs(sc[5])))) / (2 * mu * eps);
    }
    off = fmax(off, spur);
  }
  free(u);
  free(s);
  cupid_pd_operator_destroy(&op);
  return (moduli){val[0], val[1], val[2], off};
}

/* coupling.md 5.4, delta/h = 3, constant influence: mu_xy/mu and mu_d/mu, 4 decimals. */
static const double table_const[3][2] = {{1.1102, 0.8348}, {1.0833, 0.8750}, {0.9959, 1.0062}};

static void test_moduli_table(void **state) {
  (void)state;
  /* 11^3 cells: the centre node lies 5.5 h from the faces, beyond the EXACT reach
   * delta + sqrt(3)/2 h = 3.87 h, so its family is complete. */
  cupid_box b = {.lo = {0, 0, 0}, .hi = {11, 11, 11}, .has = {1, 1, 1}};
  int m = 0;
  cupid_pd_grid_options o = {.spacing = 1.0, .dimension = 3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, 1, &b, &m, &g));
  double aniso[2][3][3];
  printf("\n| model | influence | partial volume | K_eff/K | mu_xy/mu | mu_d/mu |\n");
  printf("|---|---|---|---|---|---|\n");
  for (int model = 0; model < 2; model++)
    for (int infl = 0; infl < 3; infl++)
      for (int pvr = 0; pvr < 3; pvr++) {
        const double nu = model == CUPID_PD_LPS ? 0.3 : 0.25;
        moduli r = measure(g, (cupid_pd_model_kind)model, infl, pvr, nu);
        printf("| %s | %s | %s | %.6f | %.5f | %.5f |\n", model == 0 ? "LPS" : "bond", infl_name[infl],
               pv_name[pvr], r.bulk, r.mu_xy, r.mu_d);
        /* Bulk: exact by construction (discrete m / discrete calibration), up to rounding
         * of ~100 terms: 1e-12. Spurious components vanish by cubic symmetry: 1e-12. */
        ASSERT_NEAR(r.bulk, 1.0, 1e-12);
        ASSERT_NEAR(r.off, 0.0, 1e-12);
        if (model == CUPID_PD_LPS && infl == CUPID_INFLUENCE_CONSTANT) {
          /* The table has 4 decimals and is itself ~1e-4 accurate: for NONE, where no
           * integration enters, the exact sum is 15 sum x^2 (nx^2-ny^2)^2 / (4 sum x^2) =
           * 0.834746 (by hand, and here), printed there as 0.8348. Tolerance 1.5e-4. */
          ASSERT_NEAR(r.mu_xy, table_const[pvr][0], 1.5e-4);
          ASSERT_NEAR(r.mu_d, table_const[pvr][1], 1.5e-4);
          if (pvr == CUPID_PARTIAL_NONE) ASSERT_NEAR(r.mu_d, 0.8347457627118645, 1e-12);
        }
        aniso[model][infl][pvr] = fmax(fabs(r.mu_xy - 1), fabs(r.mu_d - 1));
        if (model == CUPID_PD_LPS && pvr == CUPID_PARTIAL_EXACT && infl != CUPID_INFLUENCE_INVERSE) {
          /* Exact partial volumes make the LPS quadrature nearly isotropic: within 1% of
           * mu for the default gaussian and the constant influence. With 1/|xi| the
           * measured mu_d/mu is 1.0101 and bond-based (moments weighted by omega x, not
           * omega x^2) reaches 1.5%: those are checked relatively below. */
          ASSERT_NEAR(r.mu_xy, 1.0, 0.01);
          ASSERT_NEAR(r.mu_d, 1.0, 0.01);
        }
      }
  /* LPS: for every influence, EXACT is at least 5 times closer to isotropy than the other
   * rules. Not so for bond-based with 1/|xi| (moments weighted by beta alone, 3.4% with
   * EXACT, as much as with PDLAMMPS): the quadrature point stays at the cell centre, and
   * that error dominates the cut cells; the table above is the record. */
  for (int model = 0; model < 1; model++)
    for (int infl = 0; infl < 3; infl++)
      for (int pvr = 0; pvr < 2; pvr++)
        if (!(5 * aniso[model][infl][CUPID_PARTIAL_EXACT] < aniso[model][infl][pvr]))
          fail_msg("%s/%s: exact anisotropy %.4f vs %s %.4f", model ? "bond" : "LPS", infl_name[infl],
                   aniso[model][infl][CUPID_PARTIAL_EXACT], pv_name[pvr], aniso[model][infl][pvr]);
  /* The bulk modulus stays exact for another Poisson's ratio (LPS: 3K - 5mu changes sign). */
  for (int pvr = 0; pvr < 3; pvr++) {
    moduli r = measure(g, CUPID_PD_LPS, CUPID_INFLUENCE_GAUSSIAN, pvr, 0.1);
    ASSERT_NEAR(r.bulk, 1.0, 1e-12);
  }
  cupid_pd_grid_destroy(&g);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_moduli_table)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
