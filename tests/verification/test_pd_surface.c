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

typedef cupid_test_bar_result bar_result;

static bar_result solve_bar(cupid_pd_model_kind model, cupid_partial_volume pvr, double nu,
                            cupid_surface_correction sc) {
  return cupid_test_pd_bar(W, NY, model, pvr, nu, sc, 1e-8);
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
