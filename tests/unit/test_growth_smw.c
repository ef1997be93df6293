/* The exact re-solve of crack growth on a non-symmetric K (issue 34; src/problem/growth_smw.c and
 * growth_downdate.c): a factor of K_old brought to K_new = K_old - V V^T, V the broken bonds'
 * rank-one terms, by Sherman-Morrison-Woodbury with its capacitance inverse grown by bordering.
 * The matrix: 40 nodes of 3 DOFs, a symmetric bond-based-like stiffness (pair terms k e e^T,
 * springs to ground) plus a non-symmetric block on the first 6 nodes (as Eq. 38's FE rows and
 * fictitious columns), well conditioned (cond ~ 1e2). Checks:
 *  - the terms read off K_old - K_new (both triangles) are the removed bonds, and
 *    K_old x - V V^T x = K_new x to 1e-13 |K| |x|;
 *  - a lower block that did not change as its upper pair did (a non-symmetric change) is no sum
 *    of bond terms: ok = 0;
 *  - after two rounds of breaks (the second grows the capacitance by bordering), the corrected
 *    solve of the old factor equals the new K's own LU solve to 1e-10 (the round-off of solves
 *    with condition ~1e2, times the r = 7 columns);
 *  - a column that makes K_new singular (v scaled so that v^T K^-1 v = 1) is refused (ok = 0)
 *    and leaves the update as it was; a node held since the factorisation makes it inexact but
 *    harmless (GMRES in growth_lu.c), which is not this test's. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "problem/problem_internal.h"
#include "testutil.h"

#define NN 40

typedef struct { cupid_int i, j; double k, e[3]; } bond;

/* K: the pair terms of bonds (i, i+1), (i, i+2), ground springs, and the non-symmetric part. */
static cupid_csr build(const bond *bonds, int nb, int skip_from) {
  cupid_int rowptr[NN + 1], col[NN * 5], t = 0;
  rowptr[0] = 0;
  for (cupid_int i = 0; i < NN; i++) {
    for (cupid_int j = i - 2; j <= i + 2; j++)
      if (j >= 0 && j < NN) col[t++] = j;
    rowptr[i + 1] = t;
  }
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_csr_create(NN, NN, 3, rowptr, col, &K));
  for (cupid_int i = 0; i < NN; i++) {
    double *d = cupid_csr_find(K, i, i);
    for (int a = 0; a < 3; a++) d[4 * a] += 0.5;
  }
  for (int b = 0; b < nb; b++) {
    if (b >= skip_from) continue; /* broken */
    const bond *q = bonds + b;
    double *ii = cupid_csr_find(K, q->i, q->i), *jj = cupid_csr_find(K, q->j, q->j);
    double *ij = cupid_csr_find(K, q->i, q->j), *ji = cupid_csr_find(K, q->j, q->i);
    for (int a = 0; a < 3; a++)
      for (int c = 0; c < 3; c++) {
        const double v = q->k * q->e[a] * q->e[c];
        ii[3 * a + c] += v, jj[3 * a + c] += v, ij[3 * a + c] -= v, ji[3 * a + c] -= v;
      }
  }
  uint64_t seed = 7;
  for (cupid_int i = 0; i < 6; i++) /* the non-symmetric part */
    for (cupid_int j = i; j <= i + 2 && j < 6; j++) {
      double *b = cupid_csr_find(K, i, j);
      for (int a = 0; a < 9; a++) b[a] += 0.3 * (cupid_test_random(&seed) - 0.5);
    }
  return K;
}

static int make_bonds(bond *bonds) {
  int nb = 0;
  uint64_t seed = 3;
  for (cupid_int i = 0; i < NN; i++)
    for (cupid_int s = 1; s <= 2 && i + s < NN; s++) {
      bond *q = bonds + nb++;
      q->i = i, q->j = i + s, q->k = 1.0 + cupid_test_random(&seed);
      double n = 0.0;
      for (int a = 0; a < 3; a++) q->e[a] = cupid_test_random(&seed) - 0.5, n += q->e[a] * q->e[a];
      for (int a = 0; a < 3; a++) q->e[a] /= sqrt(n);
    }
  return nb;
}

static void swap(bond *bonds, int a, int b) {
  bond t = bonds[a];
  bonds[a] = bonds[b];
  bonds[b] = t;
}

typedef struct {
  cupid_direct_factor F;
  cupid_int n;
} plain_pc;

static cupid_status plain_solve(void *ctx, const double *b, double *x) {
  const plain_pc *p = ctx;
  return cupid_direct_factor_solve(p->F, b, x);
}

static double max_abs(const double *x, cupid_int n) {
  double m = 0.0;
  for (cupid_int d = 0; d < n; d++) m = fmax(m, fabs(x[d]));
  return m;
}

static void terms_and_solves(void **state) {
  (void)state;
  bond bonds[2 * NN];
  const int nb = make_bonds(bonds);
  /* the bonds to break (nodes 10 to 39, away from the non-symmetric part) moved to the end: the
   * last 3 break in round 1, the 4 before them in round 2 */
  const int breaks[6] = {20, 31, 44, 52, 60, 33};
  for (int b = 0; b < 6; b++) swap(bonds, breaks[b], nb - 7 + b);
  const cupid_int n = 3 * NN;
  cupid_csr K0 = build(bonds, nb, nb), K1 = build(bonds, nb, nb - 3), K2 = build(bonds, nb, nb - 7);
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));

  /* round 1 (the last 3 bonds) and round 2 (4 more): the terms of both triangles */
  cupid_growth_downdate dd1 = {0}, dd2 = {0};
  int ok = 0;
  CUPID_ASSERT_OK(cupid_growth_downdate_terms(K0, K1, &dd1, &ok));
  assert_true(ok);
  assert_int_equal(dd1.r, 3);
  CUPID_ASSERT_OK(cupid_growth_downdate_terms(K1, K2, &dd2, &ok));
  assert_true(ok);
  assert_int_equal(dd2.r, 4);
  double x[3 * NN], y[3 * NN], z[3 * NN], w[3 * NN];
  uint64_t seed = 11;
  for (cupid_int d = 0; d < n; d++) x[d] = cupid_test_random(&seed) - 0.5;
  cupid_csr_matvec(K0, x, y);
  for (cupid_int c = 0; c < dd1.r; c++) {
    double s = 0.0;
    for (cupid_int t = dd1.colptr[c]; t < dd1.colptr[c + 1]; t++) s += dd1.vals[t] * x[dd1.rows[t]];
    for (cupid_int t = dd1.colptr[c]; t < dd1.colptr[c + 1]; t++) y[dd1.rows[t]] -= dd1.vals[t] * s;
  }
  cupid_csr_matvec(K1, x, z);
  for (cupid_int d = 0; d < n; d++) w[d] = y[d] - z[d];
  printf("  |K_old x - V V^T x - K_new x| / |K_new x| = %.2e\n", max_abs(w, n) / max_abs(z, n));
  assert_true(max_abs(w, n) <= 1e-13 * max_abs(z, n) * 10.0);

  /* negative control: a lower block changed otherwise than its upper pair */
  cupid_csr Kbad = NULL;
  CUPID_ASSERT_OK(cupid_csr_duplicate(K1, &Kbad));
  const bond *q = bonds + nb - 1;
  cupid_csr_find(Kbad, q->j, q->i)[1] += 1e-3;
  cupid_growth_downdate ddb = {0};
  CUPID_ASSERT_OK(cupid_growth_downdate_terms(K0, Kbad, &ddb, &ok));
  assert_false(ok);

  /* the old factor, updated in two rounds, against the new K's own LU */
  cupid_direct_factor F0 = NULL, F2 = NULL;
  cupid_solve_info info;
  CUPID_ASSERT_OK(cupid_direct_factor_create_kind(K0, CUPID_MATRIX_GENERAL, bc, &F0, &info));
  CUPID_ASSERT_OK(cupid_direct_factor_create_kind(K2, CUPID_MATRIX_GENERAL, bc, &F2, &info));
  plain_pc pc = {F0, n};
  cupid_growth_smw u = {0};
  CUPID_ASSERT_OK(cupid_growth_smw_add(&u, n, &dd1, plain_solve, &pc, &ok));
  assert_true(ok && u.r == 3);
  CUPID_ASSERT_OK(cupid_growth_smw_add(&u, n, &dd2, plain_solve, &pc, &ok));
  assert_true(ok && u.r == 7);
  CUPID_ASSERT_OK(cupid_direct_factor_solve(F0, x, y));
  cupid_growth_smw_correct(&u, y);
  CUPID_ASSERT_OK(cupid_direct_factor_solve(F2, x, z));
  for (cupid_int d = 0; d < n; d++) w[d] = y[d] - z[d];
  printf("  updated LU solve against the new K's LU: %.2e relative\n", max_abs(w, n) / max_abs(z, n));
  assert_true(max_abs(w, n) <= 1e-10 * max_abs(z, n));
  /* without the update the old factor is off by far more (the check can fail) */
  CUPID_ASSERT_OK(cupid_direct_factor_solve(F0, x, y));
  for (cupid_int d = 0; d < n; d++) w[d] = y[d] - z[d];
  assert_true(max_abs(w, n) > 1e-3 * max_abs(z, n));

  /* a column that makes the matrix singular: refused, the update as it was */
  cupid_growth_downdate dds = {0};
  dds.r = 1, dds.cap = 1;
  cupid_int colptr[2] = {0, 6}, rows[6] = {30, 31, 32, 33, 34, 35};
  double vals[6] = {0.3, -0.2, 0.5, -0.3, 0.2, -0.5};
  dds.colptr = colptr, dds.rows = rows, dds.vals = vals;
  double v[3 * NN] = {0}, kv[3 * NN];
  for (int t = 0; t < 6; t++) v[rows[t]] = vals[t];
  double a = 0.0; /* v^T K2^-1 v, K2^-1 = the updated old factor's inverse */
  CUPID_ASSERT_OK(cupid_direct_factor_solve(F0, v, kv));
  cupid_growth_smw_correct(&u, kv);
  for (int t = 0; t < 6; t++) a += vals[t] * kv[rows[t]];
  assert_true(a > 0.0);
  for (int t = 0; t < 6; t++) vals[t] /= sqrt(a);
  CUPID_ASSERT_OK(cupid_growth_smw_add(&u, n, &dds, plain_solve, &pc, &ok));
  assert_false(ok);
  assert_int_equal(u.r, 7);
  CUPID_ASSERT_OK(cupid_direct_factor_solve(F0, x, y)); /* still K2's inverse */
  cupid_growth_smw_correct(&u, y);
  for (cupid_int d = 0; d < n; d++) w[d] = y[d] - z[d];
  assert_true(max_abs(w, n) <= 1e-10 * max_abs(z, n));

  cupid_growth_smw_free(&u);
  cupid_direct_factor_destroy(&F0);
  cupid_direct_factor_destroy(&F2);
  cupid_growth_downdate_free(&dd1);
  cupid_growth_downdate_free(&dd2);
  cupid_growth_downdate_free(&ddb);
  cupid_csr_destroy(&Kbad);
  cupid_csr_destroy(&K0);
  cupid_csr_destroy(&K1);
  cupid_csr_destroy(&K2);
  cupid_dirichlet_destroy(&bc);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(terms_and_solves)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
