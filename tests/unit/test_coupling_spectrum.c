/* Why explicit dynamics with fictitious nodes is refused (issue 34, item 2): the spectrum of
 * M^-1 K for paper 000's coupled operator (Eq. 38), measured. A bar (E = 1000, nu = 0.25,
 * density 1; section 3 x 3, one L9 element; axis [0, 6] FE | [6, 6 + L] PD | [6 + L, 12 + L] FE,
 * L = 18, 12 under CUPID_TEST_SMALL) clamped at y = 0, bond-based PD (delta = 3.015, spacing 1),
 * lumped masses (PD: rho V per real node; CUF: HRZ lumping of the active pairs; the fictitious
 * nodes are interpolated and massless), with `balance: none` (Eq. 38 as printed) and
 * `momentum` (K' = K - W C^T, the default).
 *
 * Undamped dynamics M u'' = -K u conserves an energy and stays bounded only when every
 * eigenvalue lambda of M^-1 K is real and positive (then u is a sum of modes cos(omega t),
 * omega^2 = lambda). A complex pair lambda = a +- i b gives omega = sqrt(lambda) an imaginary
 * part: one mode of the pair grows as exp(|Im omega| t), at any time step.
 *
 * Checks (dense LAPACK dgeev of M^-1 K_ff, the clamped DOFs removed; every free DOF has mass):
 *  - control: the symmetric part (K + K^T) / 2 has a real spectrum, to 1e-8 of its largest
 *    eigenvalue (M^-1 times a symmetric matrix is similar to a symmetric one: the measure works;
 *    it is indefinite, min lambda about -0.2 lambda_max, so it is no energy either);
 *  - Eq. 38, either balance, has complex pairs (measured: 38 and 27; max |Im lambda| 2e-3 of
 *    lambda_max), and the undamped solution's fastest-growing mode gains a factor e within a
 *    million central-difference steps of 0.9 dt_crit (measured: every 49 steps unbalanced, 128
 *    balanced). The numbers are printed; docs/coupling.md and docs/dynamics.md quote them. */
#include <complex.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "problem/method.h"
#include "testutil.h"

/* LAPACK (Debian's liblapack / OpenBLAS): the eigenvalues of a general matrix. */
extern void dgeev_(const char *jobvl, const char *jobvr, const int *n, double *a, const int *lda,
                   double *wr, double *wi, double *vl, const int *ldvl, double *vr,
                   const int *ldvr, double *work, const int *lwork, int *info);

static int small(void) { return getenv("CUPID_TEST_SMALL") != NULL; }

/* The bar: a beam along y clamped at y = 0, PD on [6, 6 + L] over its whole section. */
static cupid_problem make_bar(const char *balance) {
  const int side = 3, length = small() ? 12 : 18;
  char yaml[2048];
  const int len = snprintf(
      yaml, sizeof yaml,
      "title: spectrum\nmaterials:\n  m: {E: 1000, nu: 0.25, density: 1.0}\n"
      "beam:\n  material: m\n  axis: {y: [0, 6, %d, %d], elements: [1, 1, 1], type: B3}\n"
      "  section:\n    expansion: LE\n    element: L9\n    components:\n"
      "      - {x: [0, %d], z: [0, %d]}\n"
      "peridynamics:\n  spacing: 1.0\n  horizon: 3.015\n  model: bond\n  influence: constant\n"
      "  material: m\n  regions:\n    - {x: [0, %d], y: [6, %d], z: [0, %d]}\n"
      "coupling: {method: fictitious, balance: %s}\n"
      "constraints:\n  - clamp: {y: 0}\n"
      "analysis: {type: static, solver: direct}\n"
      "output: {directory: /tmp/cupid_spectrum_unused}\n",
      6 + length, 12 + length, side, side, side, 6 + length, side, balance);
  assert_true(len < (int)sizeof yaml);
  cupid_run_options ro = cupid_run_options_default();
  ro.quiet = 1;
  ro.solver = CUPID_SOLVER_DIRECT;
  cupid_problem p = NULL;
  CUPID_ASSERT_OK(cupid_problem_create_from_string(yaml, "spectrum.yaml", &ro, &p));
  CUPID_ASSERT_OK(cupid_problem_setup(p));
  return p;
}

/* The eigenvalues of the dense n x n matrix A (column-major, overwritten). */
static void eigenvalues(double *A, int n, double *wr, double *wi) {
  int info = 0, lwork = -1, one = 1;
  double q = 0.0, dummy = 0.0;
  dgeev_("N", "N", &n, A, &n, wr, wi, &dummy, &one, &dummy, &one, &q, &lwork, &info);
  lwork = (int)q;
  double *work = malloc((size_t)lwork * sizeof *work);
  assert_non_null(work);
  dgeev_("N", "N", &n, A, &n, wr, wi, &dummy, &one, &dummy, &one, work, &lwork, &info);
  free(work);
  assert_int_equal(info, 0);
}

typedef struct {
  double lam_max, im_max, re_min; /* |lambda|max, max |Im lambda|, min Re lambda */
  double grow;                    /* max |Im sqrt(lambda)|: the fastest growth rate */
  int complex_pairs;
} spectrum;

static spectrum measure(double *A, int n) {
  double *wr = malloc((size_t)n * sizeof *wr), *wi = malloc((size_t)n * sizeof *wi);
  assert_true(wr && wi);
  eigenvalues(A, n, wr, wi);
  spectrum s = {0.0, 0.0, INFINITY, 0.0, 0};
  for (int k = 0; k < n; k++) s.lam_max = fmax(s.lam_max, hypot(wr[k], wi[k]));
  for (int k = 0; k < n; k++) {
    const double complex lam = wr[k] + I * wi[k], om = csqrt(lam);
    s.im_max = fmax(s.im_max, fabs(wi[k]));
    s.re_min = fmin(s.re_min, wr[k]);
    s.complex_pairs += wi[k] > 1e-12 * s.lam_max; /* above round-off */
    s.grow = fmax(s.grow, fabs(cimag(om)));
  }
  free(wr);
  free(wi);
  return s;
}

/* M^-1 K'_ff of the bar, dense (column-major), K' = K - W C^T when balanced, or its symmetric
 * part (K' + K'^T) / 2; *nout its order. */
static double *system_matrix(cupid_problem_state *prob, int symmetric_part, int *nout) {
  if (!prob->K) CUPID_ASSERT_OK(prob->method->assemble(prob));
  const cupid_csr_t *K = prob->K;
  const cupid_int N = prob->ndof, n_pd3 = 3 * cupid_pd_grid_num_nodes(prob->grid);
  double *mass = calloc((size_t)N, sizeof *mass); /* PD: rho V = 1; CUF: HRZ lumping */
  for (cupid_int d = 0; d < n_pd3; d++) mass[d] = 1.0;
  CUPID_ASSERT_OK(cupid_cuf_mass_lumped(prob->beam, mass));
  int *keep = malloc((size_t)N * sizeof *keep), n = 0, massless = 0;
  for (cupid_int d = 0; d < N; d++) {
    keep[d] = (!prob->bc->fixed[d] && mass[d] > 0.0) ? n++ : -1;
    massless += !prob->bc->fixed[d] && !(mass[d] > 0.0);
  }
  assert_int_equal(massless, 0); /* every free DOF carries mass */
  cupid_coupling_balance B = NULL;
  if (cupid_problem_balanced(prob)) CUPID_ASSERT_OK(cupid_problem_balance_assembled(prob, K, &B));
  double *A = calloc((size_t)n * n, sizeof *A), *x = calloc((size_t)N, sizeof *x);
  double *y = calloc((size_t)N, sizeof *y);
  for (cupid_int c = 0; c < N; c++) { /* column c of K' */
    if (keep[c] < 0) continue;
    x[c] = 1.0;
    cupid_csr_matvec(K, x, y);
    if (B) cupid_coupling_balance_correct(B, x, y);
    x[c] = 0.0;
    for (cupid_int r = 0; r < N; r++)
      if (keep[r] >= 0) A[(size_t)keep[c] * n + keep[r]] = y[r];
  }
  if (symmetric_part)
    for (int i = 0; i < n; i++)
      for (int j = 0; j < i; j++) {
        const double v = 0.5 * (A[(size_t)j * n + i] + A[(size_t)i * n + j]);
        A[(size_t)j * n + i] = A[(size_t)i * n + j] = v;
      }
  for (cupid_int r = 0; r < N; r++) /* M^-1 */
    if (keep[r] >= 0)
      for (int j = 0; j < n; j++) A[(size_t)j * n + keep[r]] /= mass[r];
  cupid_coupling_balance_destroy(&B);
  free(mass);
  free(keep);
  free(x);
  free(y);
  *nout = n;
  return A;
}

/* Central-difference steps per e-fold of the fastest-growing mode at 0.9 of the critical step
 * 2 / sqrt(lambda_max). */
static double steps_per_efold(const spectrum *s) {
  return s->grow > 0.0 ? 1.0 / (s->grow * 0.9 * 2.0 / sqrt(s->lam_max)) : INFINITY;
}

static void report(const char *what, const spectrum *s, int n) {
  printf("  %-32s %3d DOFs: %2d complex pairs, max |Im lambda| %.2e |lambda|max, min Re "
         "lambda %+.2e |lambda|max; central differences at 0.9 dt_crit grow e-fold every %.3g "
         "steps\n",
         what, n, s->complex_pairs, s->im_max / s->lam_max, s->re_min / s->lam_max,
         steps_per_efold(s));
}

static void spectrum_of_eq38(void **state) {
  (void)state;
  static const char *balances[2] = {"none", "momentum"};
  for (int b = 0; b < 2; b++) {
    cupid_problem p = make_bar(balances[b]);
    int n = 0;
    double *A = system_matrix(p, 1, &n);
    const spectrum sym = measure(A, n);
    free(A);
    A = system_matrix(p, 0, &n);
    const spectrum full = measure(A, n);
    free(A);
    char what[96];
    snprintf(what, sizeof what, "balance %s, symmetric part:", balances[b]);
    report(what, &sym, n);
    snprintf(what, sizeof what, "balance %s, Eq. 38:", balances[b]);
    report(what, &full, n);
    assert_true(sym.im_max <= 1e-8 * sym.lam_max && sym.complex_pairs == 0);
    assert_true(full.complex_pairs > 0 && full.im_max > 1e-6 * full.lam_max);
    assert_true(steps_per_efold(&full) < 1e6); /* a run of a million steps would blow up */
    cupid_problem_destroy(&p);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(spectrum_of_eq38)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
