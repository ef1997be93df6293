/* Verification of the PD surface correction (peridynamics.surface_correction: energy,
 * src/pd/surface.c) on the PD bar of examples/pd_bar: 3D LPS, h = 1, delta = 3 h, Gaussian
 * influence, a square section of 10 x 10 nodes, 40 nodes long (the paper-000 bar's PD part).
 * The end layer y = 0 is fixed axially (plus the rigid modes), a uniform traction sigma acts
 * on the end layer y = L (force sigma h^2 per node); the axial strain between the sections
 * 12 h and 27 h, averaged over the section, is compared with F/(EA) = sigma/E.
 *
 * Without the correction the bar is 4.5-12% stiff (the LPS surface skin plus, for PDLAMMPS,
 * the bulk quadrature anisotropy: test_pd_bar, docs/verification.md); with it every node has
 * the continuum energy under uniaxial stress along an axis, so the uniform field of the
 * continuum solution has exactly the continuum energy and the PD solution, which minimises the
 * potential energy, can only be softer (up to the discretisation of the loaded ends), by what
 * relaxes near the surfaces and ends. Measured
 * (this test prints the table): +0.52% (PDLAMMPS, nu = 0.2), +0.68% (EXACT, nu = 0.2), +0.50%
 * (PDLAMMPS, nu = 0); uncorrected 0.9449 (PDLAMMPS, nu = 0.2), 0.8772 (EXACT), 0.9553 (nu = 0).
 * The measured Poisson ratio becomes 0.194 / 0.192 / -0.005 (uncorrected 0.225 / 0.204 / 0.014).
 * The bound 1% (the target of issue 4) leaves 0.3% of margin, and the strain must not be
 * below sigma/E by more than 0.1% (the energy argument above; the 0.1% covers the CG
 * tolerance). The uncorrected strain (PDLAMMPS, nu = 0.2) must lie below 0.97 sigma/E, so that
 * the check cannot pass without the correction. The solve is a Jacobi-preconditioned CG on the
 * matrix-free operator. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

enum { NY = 40, W = 10 };

typedef struct {
  double strain; /* interior axial strain / (sigma/E) */
  double nu;     /* measured -eps_xx/eps_yy at the middle section */
  int iterations;
} bar_result;

static bar_result solve_bar(cupid_pd_model_kind model, cupid_partial_volume pvr, double nu,
                            cupid_surface_correction sc) {
  cupid_box box = {.lo = {0, 0, 0}, .hi = {W, NY, W}, .has = {1, 1, 1}};
  int mzero = 0;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &box, &mzero, &g));
  const double E = 1.0e4, sigma = 1.0, delta = 3.0;
  cupid_pd_material mat = {E, nu};
  cupid_pd_operator_options o = {.horizon = delta, .model = model, .influence = CUPID_INFLUENCE_GAUSSIAN,
                                 .partial_volume = pvr, .materials = &mat, .n_materials = 1,
                                 .surface_correction = sc};
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(g, &o, &op));
  const cupid_int nn = cupid_pd_grid_num_nodes(g), n = 3 * nn;
  unsigned char *fixed = calloc((size_t)n, 1);
  double *b = calloc((size_t)n, sizeof *b), *u = calloc((size_t)n, sizeof *u);
  double *diag = malloc((size_t)n * sizeof *diag), *blk = malloc(9 * (size_t)nn * sizeof *blk);
  assert_true(fixed && b && u && diag && blk);
  CUPID_ASSERT_OK(cupid_pd_operator_diagonal(op, blk));
  for (cupid_int p = 0; p < nn; p++)
    for (int c = 0; c < 3; c++) diag[3 * p + c] = blk[9 * p + 4 * c];
  for (int k = 0; k < W; k++)
    for (int i = 0; i < W; i++) {
      fixed[3 * cupid_pd_grid_node_at(g, i, 0, k) + 1] = 1;           /* u_y = 0 at y = 0 */
      b[3 * cupid_pd_grid_node_at(g, i, NY - 1, k) + 1] = sigma * 1.0; /* sigma h^2 */
    }
  const cupid_int a = cupid_pd_grid_node_at(g, W / 2, 0, W / 2), c2 = cupid_pd_grid_node_at(g, W / 2, 0, 0);
  fixed[3 * a] = fixed[3 * a + 2] = 1; /* translations x, z */
  fixed[3 * c2] = 1;                   /* rotation about y */
  bar_result res;
  res.iterations = cupid_test_pd_pcg(op, n, fixed, diag, b, u, 1e-8, 20000);
  const int j1 = 12, j2 = 27;
  double s = 0;
  for (int k = 0; k < W; k++)
    for (int i = 0; i < W; i++)
      s += u[3 * cupid_pd_grid_node_at(g, i, j2, k) + 1] - u[3 * cupid_pd_grid_node_at(g, i, j1, k) + 1];
  const double eyy = s / (W * W) / (j2 - j1);
  res.strain = eyy / (sigma / E);
  const int jm = (j1 + j2) / 2;
  double sxx = 0, sxu = 0, xm = (W - 1) / 2.0;
  for (int k = 0; k < W; k++)
    for (int i = 0; i < W; i++) {
      sxx += (i - xm) * (i - xm);
      sxu += (i - xm) * u[3 * cupid_pd_grid_node_at(g, i, jm, k)];
    }
  res.nu = -(sxu / sxx) / eyy;
  free(fixed);
  free(b);
  free(u);
  free(diag);
  free(blk);
  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&g);
  return res;
}

static void test_corrected_bar(void **state) {
  (void)state;
  const struct {
    cupid_partial_volume pv;
    double nu;
  } cases[] = {
      {CUPID_PARTIAL_PDLAMMPS, 0.2},
      {CUPID_PARTIAL_EXACT, 0.2},
      {CUPID_PARTIAL_PDLAMMPS, 0.0},
  };
  printf("\n| partial volume | nu | strain / (F/EA), none | energy | nu measured, none | energy | CG its |\n"
         "|---|---|---|---|---|---|---|\n");
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    /* The uncorrected bar once (test_pd_bar covers the others): the check must fail without
     * the correction. */
    const bar_result r0 = c == 0 ? solve_bar(CUPID_PD_LPS, cases[c].pv, cases[c].nu, CUPID_SURFACE_NONE)
                                 : (bar_result){NAN, NAN, 0};
    const bar_result r1 = solve_bar(CUPID_PD_LPS, cases[c].pv, cases[c].nu, CUPID_SURFACE_ENERGY);
    printf("| %s | %.2f | %.4f | %.4f | %.4f | %.4f | %d, %d |\n",
           cases[c].pv == CUPID_PARTIAL_EXACT ? "exact" : "pdlammps", cases[c].nu, r0.strain,
           r1.strain, r0.nu, r1.nu, r0.iterations, r1.iterations);
    if (c == 0) assert_true(r0.strain < 0.97);
    assert_true(r1.strain <= 1.01 && r1.strain >= 0.999);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_corrected_bar)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
