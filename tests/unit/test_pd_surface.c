/* Unit tests of the PD surface correction (src/pd/surface.c, peridynamics.surface_correction:
 * energy): the corrected operator is still the gradient of its energy (assembled K against the
 * matrix-free columns, symmetry, rigid-body null space, energy, diagonal blocks, row ranges);
 * every node, surface nodes included, has the continuum energy under uniaxial stress along an
 * axis (which the uncorrected LPS misses near the surface); deep nodes are unchanged up to the
 * quadrature error of the EXACT rule; the model reader takes the key. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static double max_abs(const double *x, cupid_int n) {
  double m = 0;
  for (cupid_int i = 0; i < n; i++) m = fabs(x[i]) > m ? fabs(x[i]) : m;
  return m;
}

static cupid_box box3(double x0, double x1, double y0, double y1, double z0, double z1) {
  cupid_box b = {.lo = {x0, y0, z0}, .hi = {x1, y1, z1}, .has = {1, 1, 1}};
  return b;
}

static cupid_pd_operator make_op(cupid_pd_grid g, cupid_pd_model_kind model, cupid_influence infl,
                                 cupid_partial_volume pvr, double delta,
                                 cupid_surface_correction sc, const cupid_pd_material *mats,
                                 int nmat) {
  cupid_pd_operator_options o = {.horizon = delta, .model = model, .influence = infl,
                                 .partial_volume = pvr, .materials = mats, .n_materials = nmat,
                                 .surface_correction = sc};
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(g, &o, &op));
  return op;
}

/* K (assembled) against the columns of the matrix-free map (apply is linear, so its FD
 * Jacobian is exactly its columns), symmetry, rigid modes, energy, diagonal and ranges. */
static void check_consistency(cupid_pd_grid g, cupid_pd_operator op, const char *label) {
  const cupid_int nn = cupid_pd_grid_num_nodes(g), n = 3 * nn;
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(op, &K));
  double *D = calloc((size_t)(n * n), sizeof *D);
  assert_non_null(D);
  for (cupid_int r = 0; r < nn; r++)
    for (cupid_int q = K->rowptr[r]; q < K->rowptr[r + 1]; q++)
      for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) D[(3 * r + i) * n + 3 * K->col[q] + j] = K->val[9 * q + 3 * i + j];
  const double kmax = max_abs(D, n * n);
  double *e = calloc((size_t)n, sizeof *e), *f = calloc((size_t)n, sizeof *f);
  assert_true(e && f);
  /* Columns: round-off of sums of ~1e3 terms of size kmax; 1e-10 kmax leaves a wide margin
   * while a wrong factor on any bond (>= 1e-3 relative) fails. */
  double worst = 0;
  for (cupid_int c = 0; c < n; c++) {
    e[c] = 1.0;
    CUPID_ASSERT_OK(cupid_pd_operator_apply(op, e, f));
    e[c] = 0.0;
    for (cupid_int r = 0; r < n; r++) worst = fmax(worst, fabs(f[r] - D[r * n + c]));
  }
  printf("%s: K vs apply columns %.2g of max K\n", label, worst / kmax);
  if (worst > 1e-10 * kmax) fail_msg("%s: K differs from the columns of apply by %.3g (|K| %.3g)", label, worst, kmax);
  /* Symmetry (the Hessian of an energy), same tolerance. */
  for (cupid_int r = 0; r < n; r++)
    for (cupid_int c = 0; c < r; c++)
      if (fabs(D[r * n + c] - D[c * n + r]) > 1e-10 * kmax)
        fail_msg("%s: K not symmetric at (%lld, %lld): %.6g vs %.6g", label, (long long)r,
                 (long long)c, D[r * n + c], D[c * n + r]);
  /* Rigid modes: 3 translations and 3 linearised rotations give no force (1e-10 of |K||u|). */
  const double *x = cupid_pd_grid_coords(g);
  for (int mode = 0; mode < 6; mode++) {
    double umax = 0;
    for (cupid_int p = 0; p < nn; p++) {
      double u[3] = {0, 0, 0};
      if (mode < 3) {
        u[mode] = 1.0;
      } else {
        const int a = mode - 3, b = (a + 1) % 3, c = (a + 2) % 3; /* rotation about axis a */
        u[b] = -x[3 * p + c];
        u[c] = x[3 * p + b];
      }
      for (int k = 0; k < 3; k++) e[3 * p + k] = u[k];
    }
    umax = max_abs(e, n);
    CUPID_ASSERT_OK(cupid_pd_operator_apply(op, e, f));
    if (max_abs(f, n) > 1e-10 * kmax * umax) fail_msg("%s: rigid mode %d gives force %.3g", label, mode, max_abs(f, n));
  }
  /* Energy = u.Ku/2 from its own formula, and the diagonal blocks and row ranges. */
  uint64_t seed = 11;
  for (cupid_int i = 0; i < n; i++) e[i] = cupid_test_random(&seed) - 0.5;
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, e, f));
  double uKu = 0, En = 0;
  for (cupid_int i = 0; i < n; i++) uKu += e[i] * f[i];
  CUPID_ASSERT_OK(cupid_pd_operator_energy(op, e, &En));
  ASSERT_NEAR(En, 0.5 * uKu, 1e-12 * fabs(uKu)); /* same sums in another order */
  /* Finite differences of the energy along a random v against v.f: the force is the gradient
   * of the corrected energy (central differences are exact for a quadratic up to round-off;
   * 1e-9 of the energy scale). */
  {
    double *v = malloc((size_t)n * sizeof *v), *w = malloc((size_t)n * sizeof *w);
    assert_true(v && w);
    for (cupid_int i = 0; i < n; i++) v[i] = cupid_test_random(&seed) - 0.5;
    const double eps = 1e-3;
    double Ep, Em, vf = 0;
    for (cupid_int i = 0; i < n; i++) w[i] = e[i] + eps * v[i];
    CUPID_ASSERT_OK(cupid_pd_operator_energy(op, w, &Ep));
    for (cupid_int i = 0; i < n; i++) w[i] = e[i] - eps * v[i];
    CUPID_ASSERT_OK(cupid_pd_operator_energy(op, w, &Em));
    for (cupid_int i = 0; i < n; i++) vf += v[i] * f[i];
    if (fabs((Ep - Em) / (2 * eps) - vf) > 1e-9 * fabs(En) / eps)
      fail_msg("%s: FD gradient %.15g vs v.f %.15g", label, (Ep - Em) / (2 * eps), vf);
    free(v);
    free(w);
  }
  double *blk = malloc(9 * (size_t)nn * sizeof *blk);
  assert_non_null(blk);
  CUPID_ASSERT_OK(cupid_pd_operator_diagonal(op, blk));
  for (cupid_int p = 0; p < nn; p++)
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) ASSERT_NEAR(blk[9 * p + 3 * i + j], D[(3 * p + i) * n + 3 * p + j], 1e-12 * kmax);
  double *fr = calloc((size_t)n, sizeof *fr);
  assert_non_null(fr);
  const cupid_int a = nn / 3, b = 2 * nn / 3;
  CUPID_ASSERT_OK(cupid_pd_operator_apply_range(op, a, b, e, fr));
  for (cupid_int i = 0; i < 3 * (b - a); i++) ASSERT_NEAR(fr[i], f[3 * a + i], 1e-14 * max_abs(f, n));
  free(fr);
  free(blk);
  free(e);
  free(f);
  free(D);
  cupid_csr_destroy(&K);
}

static void test_consistency(void **state) {
  (void)state;
  /* A box and an L-shaped two-material union (edges, re-entrant corner, material jump). */
  const cupid_pd_material mats[2] = {{1000.0, 0.3}, {2500.0, 0.1}};
  cupid_box L[2] = {box3(0, 5, 0, 4, 0, 3), box3(0, 2, 4, 7, 0, 3)};
  int matL[2] = {0, 1};
  cupid_box B = box3(0, 4, 0, 5, 0, 4);
  int mat0 = 0;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  for (int geo = 0; geo < 2; geo++) {
    cupid_pd_grid g = NULL;
    CUPID_ASSERT_OK(cupid_pd_grid_create(&go, geo ? 2 : 1, geo ? L : &B, geo ? matL : &mat0, &g));
    for (int model = 0; model < 2; model++)
      for (int pv = 1; pv <= 2; pv++)
        for (int infl = 0; infl < 3; infl += 2) {
          cupid_pd_operator op = make_op(g, (cupid_pd_model_kind)model, (cupid_influence)infl,
                                         (cupid_partial_volume)pv, 2.0, CUPID_SURFACE_ENERGY, mats, 2);
          char label[128];
          snprintf(label, sizeof label, "%s %s pv %d influence %d", geo ? "L" : "box",
                   model ? "bond" : "lps", pv, infl);
          check_consistency(g, op, label);
          cupid_pd_operator_destroy(&op);
        }
    cupid_pd_grid_destroy(&g);
  }
}

/* max over nodes of |sigma_i : eps - 2 W(eps)| / 2 W(eps) under the affine field of the
 * normal strain eps (W the continuum energy density); *nbad counts nodes off by > 1e-10. */
static double normal_strain_error(cupid_pd_grid g, cupid_pd_operator op, double E, double nu,
                                  const double eps[3], int *nbad) {
  const cupid_int nn = cupid_pd_grid_num_nodes(g);
  const double *x = cupid_pd_grid_coords(g);
  double *u = malloc(3 * (size_t)nn * sizeof *u), *s = malloc(6 * (size_t)nn * sizeof *s);
  assert_true(u && s);
  for (cupid_int p = 0; p < nn; p++)
    for (int c = 0; c < 3; c++) u[3 * p + c] = eps[c] * x[3 * p + c];
  CUPID_ASSERT_OK(cupid_pd_operator_stress(op, u, s));
  const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
  const double tr = eps[0] + eps[1] + eps[2];
  const double W2 = lambda * tr * tr + 2 * mu * (eps[0] * eps[0] + eps[1] * eps[1] + eps[2] * eps[2]);
  double worst = 0;
  *nbad = 0;
  for (cupid_int p = 0; p < nn; p++) {
    const double se = s[6 * p] * eps[0] + s[6 * p + 1] * eps[1] + s[6 * p + 2] * eps[2];
    const double d = fabs(se - W2) / W2;
    worst = fmax(worst, d);
    *nbad += d > 1e-10;
  }
  free(u);
  free(s);
  return worst;
}

/* sigma_i : eps = 2 W_i for a quadratic energy, and the fit makes W_i the continuum E eps^2/2
 * under uniaxial stress along each axis at every node (surface, edge and corner nodes too). */
static void test_uniaxial_energy(void **state) {
  (void)state;
  const double E = 1000.0, nu = 0.2;
  const cupid_pd_material mat = {E, nu};
  cupid_box B = box3(0, 6, 0, 7, 0, 5);
  int mat0 = 0;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &B, &mat0, &g));
  for (int pv = 1; pv <= 2; pv++) {
    cupid_pd_operator op = make_op(g, CUPID_PD_LPS, CUPID_INFLUENCE_GAUSSIAN, (cupid_partial_volume)pv,
                                   3.0, CUPID_SURFACE_ENERGY, &mat, 1);
    cupid_pd_operator raw = make_op(g, CUPID_PD_LPS, CUPID_INFLUENCE_GAUSSIAN, (cupid_partial_volume)pv,
                                    3.0, CUPID_SURFACE_NONE, &mat, 1);
    /* Uniaxial stress along x, y, z, and two other normal strains. */
    const double states[5][3] = {{1, -nu, -nu}, {-nu, 1, -nu}, {-nu, -nu, 1}, {0.3, -0.7, 1.1}, {1, 1, 1}};
    for (int k = 0; k < 5; k++) {
      int nbad, nbad_raw;
      const double ec = normal_strain_error(g, op, E, nu, states[k], &nbad);
      const double er = normal_strain_error(g, raw, E, nu, states[k], &nbad_raw);
      printf("pv %d state %d: corrected %.3g (%d nodes off), uncorrected %.3g (%d nodes off)\n", pv, k,
             ec, nbad, er, nbad_raw);
      /* Exact by construction: only round-off of the fits and the sums (1e-10). */
      if (ec > 1e-10) fail_msg("pv %d state %d: corrected sigma:eps off by %.3g", pv, k, ec);
      /* The uncorrected LPS is off by tens of percent at the surface (measured 0.2-0.6): the
       * check above is not trivially met (except the pure dilatation, exact without it). */
      if (k < 4 && er < 0.05) fail_msg("pv %d state %d: uncorrected error only %.3g", pv, k, er);
    }
    cupid_pd_operator_destroy(&op);
    cupid_pd_operator_destroy(&raw);
  }
  cupid_pd_grid_destroy(&g);
}

/* Deep nodes (whose rows only see full families) keep their forces: D = 1 exactly by cubic
 * symmetry and G = 1 up to how far the EXACT stencil's fourth moment is from isotropic. */
static void test_bulk_unchanged(void **state) {
  (void)state;
  const double delta = 3.0, h = 1.0;
  const cupid_pd_material mat = {1000.0, 0.25};
  cupid_box B = box3(0, 18, 0, 18, 0, 18);
  int mat0 = 0;
  cupid_pd_grid_options go = {.spacing = h, .dimension = 3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &B, &mat0, &g));
  const cupid_int nn = cupid_pd_grid_num_nodes(g), n = 3 * nn;
  /* A row reads the factors of the nodes within one family radius, whose own factors read
   * theirs: two radii (EXACT reaches delta + sqrt(3)/2 h). */
  unsigned char *deep = malloc((size_t)nn);
  double *u = malloc((size_t)n * sizeof *u), *f0 = malloc((size_t)n * sizeof *f0), *f1 = malloc((size_t)n * sizeof *f1);
  assert_true(deep && u && f0 && f1);
  CUPID_ASSERT_OK(cupid_pd_grid_interior(g, 2 * (delta + 0.5 * sqrt(3.0) * h), deep));
  uint64_t seed = 5;
  for (cupid_int i = 0; i < n; i++) u[i] = cupid_test_random(&seed) - 0.5;
  cupid_pd_operator a = make_op(g, CUPID_PD_LPS, CUPID_INFLUENCE_GAUSSIAN, CUPID_PARTIAL_EXACT, delta,
                                CUPID_SURFACE_NONE, &mat, 1);
  cupid_pd_operator b = make_op(g, CUPID_PD_LPS, CUPID_INFLUENCE_GAUSSIAN, CUPID_PARTIAL_EXACT, delta,
                                CUPID_SURFACE_ENERGY, &mat, 1);
  CUPID_ASSERT_OK(cupid_pd_operator_apply(a, u, f0));
  CUPID_ASSERT_OK(cupid_pd_operator_apply(b, u, f1));
  double worst = 0, fm = max_abs(f0, n), worst_all = 0;
  cupid_int ndeep = 0;
  for (cupid_int p = 0; p < nn; p++) {
    for (int c = 0; c < 3; c++) {
      const double d = fabs(f1[3 * p + c] - f0[3 * p + c]) / fm;
      worst_all = fmax(worst_all, d);
      if (deep[p]) worst = fmax(worst, d);
    }
    ndeep += deep[p];
  }
  assert_true(ndeep > 0);
  /* Measured 2.0e-4 at m = 3 (6.4e-3 at m = 2: the EXACT stencil's fourth moment is less
   * isotropic, test_pd_moduli); 1e-3 bounds it, while the surface rows change by far more
   * (measured 0.25). */
  printf("bulk: deep rows change by %.3g of max |f|, all rows by %.3g\n", worst, worst_all);
  assert_true(worst < 1e-3);
  assert_true(worst_all > 0.05);
  cupid_pd_operator_destroy(&a);
  cupid_pd_operator_destroy(&b);
  free(deep);
  free(u);
  free(f0);
  free(f1);
  cupid_pd_grid_destroy(&g);
}

/* The model key: default none, energy accepted, a typo named with file:line:col. */
static void test_model_key(void **state) {
  (void)state;
  const char *base =
      "materials:\n  m: {E: 1000, nu: 0.2}\n"
      "peridynamics:\n  spacing: 1.0\n  horizon: 3.0\n%s  regions:\n    - {x: [0, 4], y: [0, 4], z: [0, 4]}\n"
      "constraints:\n  - fix: {box: {y: [0, 1]}}\nanalysis: {type: static}\n";
  const char *keys[3] = {"", "  surface_correction: energy\n", "  surface_correction: energie\n"};
  for (int c = 0; c < 3; c++) {
    char text[1024];
    snprintf(text, sizeof text, base, keys[c]);
    cupid_model m = NULL;
    cupid_status st = cupid_model_read_string(text, strlen(text), "sc.yaml", &m);
    if (c < 2) {
      CUPID_ASSERT_OK(st);
      assert_int_equal(m->pd.surface_correction, c ? CUPID_SURFACE_ENERGY : CUPID_SURFACE_NONE);
    } else {
      assert_int_equal(st, CUPID_ERR_MODEL);
      const char *msg = cupid_error_message();
      if (!strstr(msg, "sc.yaml:6:23: peridynamics.surface_correction: must be one of none | energy"))
        fail_msg("unexpected message: %s", msg);
    }
    cupid_model_destroy(&m);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_consistency), cmocka_unit_test(test_uniaxial_energy),
      cmocka_unit_test(test_bulk_unchanged), cmocka_unit_test(test_model_key)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
