/* Unit tests of the balanced coupling operator K' = K - W C^T (src/coupling/balance.c;
 * issue 18), on a random non-symmetric K with K R = 0 for six random "rigid modes" R (the
 * algebra does not depend on what R is):
 *  - R^T K' = 0 (momentum conserved) and K' R = 0 (rigid modes free of force);
 *  - K' x = K x when R^T K x = 0 (the patch test's fields are kept);
 *  - the Sherman-Morrison-Woodbury solve with the factor of K_ff solves K'_ff u_f = f_f - K'_fc u_c;
 *  - two groups (each interface balanced apart, `balance: momentum`): every column of K'
 *    self-equilibrated, each column's correction on its own group's weighted DOFs only, the
 *    solve with 12 modes, a group whose weights cannot span the modes refused;
 *  - weights that do not span the modes, and a slab without its share (set_slab), are refused.
 * Tolerances: 1e-11 relative to |K| |x| (dense sums of 30 terms of O(1), condition of the
 * 21 x 21 free block ~1e3 on these seeds). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cupid/coupling.h"
#include "testutil.h"

#define NB 10        /* blocks */
#define N (3 * NB)   /* DOFs */
#define NR CUPID_BALANCE_MODES

typedef struct {
  cupid_csr K;
  double R[NR * N], C[NR * N], d[N];
  double Kd[N][N];   /* dense copy */
  cupid_coupling_balance B;
} fixture;

/* Solve the m x m system A z = b in place (Gaussian elimination, partial pivoting). */
static void dense_solve(int m, double *A, double *b) {
  for (int c = 0; c < m; c++) {
    int p = c;
    for (int r = c + 1; r < m; r++)
      if (fabs(A[r * m + c]) > fabs(A[p * m + c])) p = r;
    for (int k = 0; k < m; k++) {
      double t = A[c * m + k];
      A[c * m + k] = A[p * m + k];
      A[p * m + k] = t;
    }
    double t = b[c];
    b[c] = b[p];
    b[p] = t;
    for (int r = c + 1; r < m; r++) {
      double f = A[r * m + c] / A[c * m + c];
      for (int k = c; k < m; k++) A[r * m + k] -= f * A[c * m + k];
      b[r] -= f * b[c];
    }
  }
  for (int c = m - 1; c >= 0; c--) {
    for (int k = c + 1; k < m; k++) b[c] -= A[c * m + k] * b[k];
    b[c] /= A[c * m + c];
  }
}

static void build(fixture *fx, int weights_span) {
  memset(fx, 0, sizeof *fx);
  uint64_t seed = 42;
  static double A[N][N];
  for (int i = 0; i < N; i++)
    for (int j = 0; j < N; j++) A[i][j] = cupid_test_random(&seed) + (i == j ? 8.0 : 0.0);
  for (int k = 0; k < NR * N; k++) fx->R[k] = cupid_test_random(&seed);
  /* K = A (I - R (R^T R)^-1 R^T): K R = 0 */
  double G[NR * NR];
  for (int a = 0; a < NR; a++)
    for (int b = 0; b < NR; b++) {
      G[a * NR + b] = 0.0;
      for (int j = 0; j < N; j++) G[a * NR + b] += fx->R[a * N + j] * fx->R[b * N + j];
    }
  static double P[N][N]; /* I - R G^-1 R^T */
  for (int j = 0; j < N; j++) {
    double g[NR], Gc[NR * NR];
    for (int a = 0; a < NR; a++) g[a] = fx->R[a * N + j];
    memcpy(Gc, G, sizeof Gc);
    dense_solve(NR, Gc, g);
    for (int i = 0; i < N; i++) {
      double v = 0.0;
      for (int a = 0; a < NR; a++) v += fx->R[a * N + i] * g[a];
      P[i][j] = (i == j) - v;
    }
  }
  for (int i = 0; i < N; i++)
    for (int j = 0; j < N; j++) {
      double v = 0.0;
      for (int k = 0; k < N; k++) v += A[i][k] * P[k][j];
      fx->Kd[i][j] = v;
    }
  cupid_int rowptr[NB + 1], col[NB * NB];
  for (int r = 0; r <= NB; r++) rowptr[r] = (cupid_int)r * NB;
  for (int k = 0; k < NB * NB; k++) col[k] = k % NB;
  CUPID_ASSERT_OK(cupid_csr_create(NB, NB, 3, rowptr, col, &fx->K));
  for (int br = 0; br < NB; br++)
    for (int bc = 0; bc < NB; bc++)
      for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
          fx->K->val[((size_t)(br * NB + bc) * 3 + a) * 3 + b] = fx->Kd[3 * br + a][3 * bc + b];
  for (int k = 0; k < NR; k++) cupid_csr_matvec_transpose(fx->K, fx->R + k * N, fx->C + k * N);
  /* weights on the last 12 DOFs (the "interface"), or on 3 only (cannot span 6 modes) */
  for (int j = 0; j < N; j++) fx->d[j] = j >= N - (weights_span ? 12 : 3) ? 1.0 + 0.5 * (j % 3) : 0.0;
}

static double kscale(const fixture *fx) {
  double s = 0.0;
  for (int i = 0; i < N; i++)
    for (int j = 0; j < N; j++) s = fmax(s, fabs(fx->Kd[i][j]));
  return s;
}

/* y = K' x */
static void kprime(const fixture *fx, const double *x, double *y) {
  cupid_csr_matvec(fx->K, x, y);
  cupid_coupling_balance_correct(fx->B, x, y);
}

static void balanced_and_rigid(void **state) {
  (void)state;
  fixture fx;
  build(&fx, 1);
  CUPID_ASSERT_OK(cupid_coupling_balance_create(N, fx.R, fx.C, fx.d, &fx.B));
  const double ks = kscale(&fx);
  double y[N], worst_left = 0.0, worst_right = 0.0, imb_before = 0.0;
  for (int j = 0; j < N; j++) { /* column j of K': R^T K' e_j */
    double e[N] = {0};
    e[j] = 1.0;
    kprime(&fx, e, y);
    for (int k = 0; k < NR; k++) {
      double s = 0.0;
      for (int i = 0; i < N; i++) s += fx.R[k * N + i] * y[i];
      worst_left = fmax(worst_left, fabs(s));
      imb_before = fmax(imb_before, fabs(fx.C[k * N + j]));
    }
  }
  for (int k = 0; k < NR; k++) {
    kprime(&fx, fx.R + k * N, y);
    for (int i = 0; i < N; i++) worst_right = fmax(worst_right, fabs(y[i]));
  }
  printf("  |R^T K| = %.2e before, |R^T K'| = %.2e, |K' R| = %.2e (|K| = %.2e)\n", imb_before,
         worst_left, worst_right, ks);
  assert_true(imb_before > 1e-2 * ks); /* K itself is not balanced */
  assert_true(worst_left <= 1e-11 * ks * N);
  assert_true(worst_right <= 1e-11 * ks * N);
  cupid_coupling_balance_destroy(&fx.B);
  cupid_csr_destroy(&fx.K);
}

static void patch_fields_kept(void **state) {
  (void)state;
  fixture fx;
  build(&fx, 1);
  CUPID_ASSERT_OK(cupid_coupling_balance_create(N, fx.R, fx.C, fx.d, &fx.B));
  /* x = u - M^T (M M^T)^-1 M u with M = R^T K = C^T: then R^T K x = 0 */
  uint64_t seed = 7;
  double x[N], MMt[NR * NR], g[NR];
  for (int j = 0; j < N; j++) x[j] = cupid_test_random(&seed);
  for (int a = 0; a < NR; a++) {
    g[a] = 0.0;
    for (int j = 0; j < N; j++) g[a] += fx.C[a * N + j] * x[j];
    for (int b = 0; b < NR; b++) {
      MMt[a * NR + b] = 0.0;
      for (int j = 0; j < N; j++) MMt[a * NR + b] += fx.C[a * N + j] * fx.C[b * N + j];
    }
  }
  dense_solve(NR, MMt, g);
  for (int j = 0; j < N; j++)
    for (int a = 0; a < NR; a++) x[j] -= fx.C[a * N + j] * g[a];
  double y[N], z[N], worst = 0.0;
  cupid_csr_matvec(fx.K, x, y);
  kprime(&fx, x, z);
  for (int i = 0; i < N; i++) worst = fmax(worst, fabs(y[i] - z[i]));
  printf("  |K' x - K x| = %.2e for R^T K x = 0\n", worst);
  assert_true(worst <= 1e-11 * kscale(&fx) * N);
  cupid_coupling_balance_destroy(&fx.B);
  cupid_csr_destroy(&fx.K);
}

static void smw_solve(void **state) {
  (void)state;
  fixture fx;
  build(&fx, 1);
  CUPID_ASSERT_OK(cupid_coupling_balance_create(N, fx.R, fx.C, fx.d, &fx.B));
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(N, &bc));
  uint64_t seed = 3;
  for (int j = 0; j < 9; j++) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, j, cupid_test_random(&seed)));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  double f[N], u[N], y[N];
  for (int j = 0; j < N; j++) f[j] = cupid_test_random(&seed);
  cupid_direct_factor F = NULL;
  CUPID_ASSERT_OK(cupid_direct_factor_create_kind(fx.K, CUPID_MATRIX_GENERAL, bc, &F, NULL));
  CUPID_ASSERT_OK(cupid_coupling_balance_solve(fx.B, fx.K, F, bc, f, u));
  kprime(&fx, u, y);
  double res = 0.0, fn = 0.0, fixed = 0.0;
  for (int j = 0; j < N; j++) {
    if (bc->fixed[j]) {
      fixed = fmax(fixed, fabs(u[j] - bc->value[j]));
      continue;
    }
    res = fmax(res, fabs(y[j] - f[j]));
    fn = fmax(fn, fabs(f[j]));
  }
  printf("  SMW solve: max |K' u - f| on the free DOFs = %.2e (|f| %.2e), fixed values %.1e\n",
         res, fn, fixed);
  assert_true(res <= 1e-11 * kscale(&fx) * N);
  assert_true(fixed == 0.0);
  cupid_direct_factor_destroy(&F);
  cupid_dirichlet_destroy(&bc);
  cupid_coupling_balance_destroy(&fx.B);
  cupid_csr_destroy(&fx.K);
}

/* Two groups (the interfaces of balance: momentum): DOFs [0, 15) and [15, 30), weights on
 * 6..14 and 18..29. Every column of K' is self-equilibrated (R^T K' = 0, as with one group),
 * the correction of a column stays on its own group's weighted DOFs (K' e_j - K e_j is zero
 * elsewhere: no force at one interface from a displacement at the other), and the SMW solve
 * (12 modes) solves K'. A group with entries of C but too few weights is refused. */
static void grouped(void **state) {
  (void)state;
  fixture fx;
  build(&fx, 1);
  int group[N];
  for (int j = 0; j < N; j++) {
    group[j] = j < N / 2 ? 0 : 1;
    fx.d[j] = (j >= 6 && j < 15) || j >= 18 ? 1.0 + 0.5 * (j % 3) : 0.0;
  }
  CUPID_ASSERT_OK(cupid_coupling_balance_create_grouped(N, fx.R, fx.C, fx.d, 2, group, &fx.B));
  const double ks = kscale(&fx);
  double y[N], k0[N], worst_left = 0.0, worst_far = 0.0;
  for (int j = 0; j < N; j++) {
    double e[N] = {0};
    e[j] = 1.0;
    kprime(&fx, e, y);
    cupid_csr_matvec(fx.K, e, k0);
    for (int k = 0; k < NR; k++) {
      double s = 0.0;
      for (int i = 0; i < N; i++) s += fx.R[k * N + i] * y[i];
      worst_left = fmax(worst_left, fabs(s));
    }
    for (int i = 0; i < N; i++)
      if (group[i] != group[j] || fx.d[i] == 0.0) worst_far = fmax(worst_far, fabs(y[i] - k0[i]));
  }
  printf("  two groups: |R^T K'| = %.2e, correction away from the column's group %.2e\n",
         worst_left, worst_far);
  assert_true(worst_left <= 1e-11 * ks * N);
  assert_true(worst_far == 0.0);
  /* the solve with 12 modes */
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(N, &bc));
  uint64_t seed = 5; /* 9 fixed DOFs hold the 6 modes (R^T K' = 0 makes K' singular else) */
  for (int j = 0; j < 9; j++) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, j, cupid_test_random(&seed)));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  double f[N], u[N], res = 0.0;
  for (int j = 0; j < N; j++) f[j] = cupid_test_random(&seed);
  cupid_direct_factor F = NULL;
  CUPID_ASSERT_OK(cupid_direct_factor_create_kind(fx.K, CUPID_MATRIX_GENERAL, bc, &F, NULL));
  CUPID_ASSERT_OK(cupid_coupling_balance_solve(fx.B, fx.K, F, bc, f, u));
  kprime(&fx, u, y);
  for (int j = 0; j < N; j++)
    if (!bc->fixed[j]) res = fmax(res, fabs(y[j] - f[j]));
  printf("  two groups, SMW solve: max |K' u - f| = %.2e\n", res);
  assert_true(res <= 1e-11 * ks * N);
  cupid_direct_factor_destroy(&F);
  cupid_dirichlet_destroy(&bc);
  cupid_coupling_balance_destroy(&fx.B);
  /* group 0 with weights on 3 DOFs only */
  for (int j = 0; j < N / 2; j++) fx.d[j] = j < 3 ? 1.0 : 0.0;
  assert_int_equal(cupid_coupling_balance_create_grouped(N, fx.R, fx.C, fx.d, 2, group, &fx.B),
                   CUPID_ERR_MODEL);
  assert_null(fx.B);
  assert_non_null(strstr(cupid_error_message(), "of an interface"));
  cupid_error_clear();
  cupid_csr_destroy(&fx.K);
}

static cupid_status nothing(void *ctx, const double *x, double *y) {
  (void)ctx, (void)x, (void)y;
  return CUPID_SUCCESS;
}

static void refusals(void **state) {
  (void)state;
  fixture fx;
  build(&fx, 0);
  cupid_status st = cupid_coupling_balance_create(N, fx.R, fx.C, fx.d, &fx.B);
  assert_int_equal(st, CUPID_ERR_MODEL);
  assert_null(fx.B);
  assert_non_null(strstr(cupid_error_message(), "rigid-body modes"));
  for (int j = 0; j < N; j++) fx.d[j] = 1.0;
  CUPID_ASSERT_OK(cupid_coupling_balance_create(N, fx.R, fx.C, fx.d, &fx.B));
  cupid_pd_grid_partition part = {.parts = 2};
  cupid_linear_operator L = {.n = N, .apply = nothing, .part = &part}, out;
  assert_int_equal(cupid_coupling_balance_linear(fx.B, &L, &out), CUPID_ERR_ARGUMENT);
  cupid_error_clear();
  L.part = NULL;
  CUPID_ASSERT_OK(cupid_coupling_balance_linear(fx.B, &L, &out));
  assert_null(out.apply_rows);
  cupid_coupling_balance_destroy(&fx.B);
  cupid_csr_destroy(&fx.K);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(balanced_and_rigid),
      cmocka_unit_test(patch_fields_kept),
      cmocka_unit_test(smw_solve),
      cmocka_unit_test(grouped),
      cmocka_unit_test(refusals),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
