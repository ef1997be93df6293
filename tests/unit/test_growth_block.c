/* The block factor of crack growth with fictitious nodes (issue 34; src/problem/growth_block.c):
 * K' = [A B; C' D'] solved by CHOLMOD of the symmetric PD block A, the LU of the FE block D' and
 * the small interface capacitance, and brought to K - V V^T by downdating A as bonds break.
 * The matrix: 30 "PD" nodes (bond pair terms k e e^T, ground springs but on node 5) and 10 "FE"
 * nodes (a chain, stiffer springs to ground), PD rows 25-29 reading FE columns 30-33 (B) and FE
 * rows 30-31 reading PD columns 25-29 (C, other values: K is not symmetric), a non-symmetric
 * perturbation of the FE rows 30-31, and a balance K' = K - W C_b^T whose W lives on the FE
 * rows 30-31 (as balance.c's interface FE nodes). Condition ~1e2. Checks:
 *  - a solve meets K' z = r on the free DOFs to 1e-13 |K'| |z| (exact elimination), balanced
 *    and not, with fixed PD and FE DOFs;
 *  - after two rounds of downdates (a break next to the coupled nodes in the second) the solve
 *    equals the fresh block factor of the new K to 1e-11 and meets the new K' to 1e-13; the
 *    old factor is off by more than 1e-3 (the check can fail);
 *  - breaking every bond of node 5 (no ground spring) leaves A singular: ok = 0;
 *  - a PD block that is not symmetric is not taken (M NULL: the caller's LU of K whole). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cupid/coupling.h"
#include "problem/problem_internal.h"
#include "testutil.h"

#define NP 30
#define NF 10
#define NN (NP + NF)
#define N3 (3 * NN)

typedef struct { cupid_int i, j; double k, e[3]; } bond;

static int coupled(cupid_int i, cupid_int j) { /* B (PD rows 25-29, FE 30-33) and C */
  return (i >= 25 && i < NP && j >= NP && j <= 33) || (j >= 25 && j < NP && i >= NP && i <= 31);
}

/* K without the bonds of @p broken (flags per bond), @p skew: A made non-symmetric. */
static cupid_csr build(const bond *bonds, int nb, const int *broken, int skew) {
  cupid_int rowptr[NN + 1], col[NN * NN], t = 0;
  rowptr[0] = 0;
  for (cupid_int i = 0; i < NN; i++) {
    for (cupid_int j = 0; j < NN; j++)
      if ((llabs(i - j) <= 2 && (i < NP) == (j < NP)) || coupled(i, j)) col[t++] = j;
    rowptr[i + 1] = t;
  }
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_csr_create(NN, NN, 3, rowptr, col, &K));
  for (cupid_int i = 0; i < NN; i++) {
    double *d = cupid_csr_find(K, i, i);
    for (int a = 0; a < 3; a++) d[4 * a] += i == 5 ? 0.0 : i < NP ? 0.5 : 3.0;
  }
  for (int b = 0; b < nb; b++) {
    if (broken && broken[b]) continue;
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
  for (cupid_int i = 0; i < NN; i++)
    for (cupid_int j = 0; j < NN; j++) {
      double *b = cupid_csr_find(K, i, j);
      if (!b) continue;
      if (coupled(i, j)) /* B and C: independent values */
        for (int a = 0; a < 9; a++) b[a] += 0.3 * (cupid_test_random(&seed) - 0.5);
      if (i >= NP && i <= 31 && j >= NP) /* the fits' FE rows: not symmetric */
        for (int a = 0; a < 9; a++) b[a] += 0.2 * (cupid_test_random(&seed) - 0.5);
    }
  if (skew) cupid_csr_find(K, 3, 4)[1] += 1e-3;
  return K;
}

static int make_bonds(bond *bonds) {
  int nb = 0;
  uint64_t seed = 3;
  for (cupid_int i = 0; i < NP; i++)
    for (cupid_int s = 1; s <= 2 && i + s < NP; s++) {
      bond *q = bonds + nb++;
      q->i = i, q->j = i + s, q->k = 1.0 + cupid_test_random(&seed);
      double n = 0.0;
      for (int a = 0; a < 3; a++) q->e[a] = cupid_test_random(&seed) - 0.5, n += q->e[a] * q->e[a];
      for (int a = 0; a < 3; a++) q->e[a] /= sqrt(n);
    }
  for (cupid_int i = NP; i < NN; i++) /* the FE chain (its stiffness is not broken) */
    for (cupid_int s = 1; s <= 2 && i + s < NN; s++) {
      bond *q = bonds + nb++;
      q->i = i, q->j = i + s, q->k = 2.0;
      q->e[0] = q->e[1] = q->e[2] = 1.0 / sqrt(3.0);
    }
  return nb;
}

static int find_bond(const bond *bonds, int nb, cupid_int i, cupid_int j) {
  for (int b = 0; b < nb; b++)
    if (bonds[b].i == i && bonds[b].j == j) return b;
  return -1;
}

static double max_abs(const double *x, cupid_int n) {
  double m = 0.0;
  for (cupid_int d = 0; d < n; d++) m = fmax(m, fabs(x[d]));
  return m;
}

/* The balance: R and C_b random, weights on the FE rows 30-31 (W lives there). */
static cupid_coupling_balance make_balance(void) {
  static double R[6 * N3], C[6 * N3], d[N3];
  uint64_t seed = 19;
  for (int a = 0; a < 6; a++)
    for (cupid_int j = 0; j < N3; j++) {
      R[a * N3 + j] = cupid_test_random(&seed) - 0.5;
      const cupid_int node = j / 3;
      C[a * N3 + j] = (node >= 25 && node <= 33) ? 0.2 * (cupid_test_random(&seed) - 0.5) : 0.0;
    }
  for (cupid_int j = 0; j < N3; j++) d[j] = (j / 3 == 30 || j / 3 == 31) ? 3.0 : 0.0;
  cupid_coupling_balance B = NULL;
  CUPID_ASSERT_OK(cupid_coupling_balance_create(N3, R, C, d, &B));
  return B;
}

/* |K' z - r| on the free DOFs against |K'| |z| (inf norms; |K'| by a row sum bound). */
static double residual(const cupid_csr_t *K, cupid_coupling_balance B, const cupid_dirichlet_t *bc,
                       const double *z, const double *r) {
  double y[N3], kabs = 0.0;
  cupid_csr_matvec(K, z, y);
  if (B) cupid_coupling_balance_correct(B, z, y);
  for (cupid_int d = 0; d < N3; d++) y[d] = bc->fixed[d] ? 0.0 : y[d] - r[d];
  for (cupid_int q = 0; q < K->rowptr[K->nrows] * 9; q++) kabs = fmax(kabs, fabs(K->val[q]));
  return max_abs(y, N3) / (30.0 * kabs * max_abs(z, N3));
}

static void solve_check(cupid_growth_block M, const cupid_csr_t *K, cupid_coupling_balance B,
                        const cupid_dirichlet_t *bc, const double *r, double *z, const char *what) {
  CUPID_ASSERT_OK(cupid_growth_block_solve(M, r, z));
  for (cupid_int d = 0; d < N3; d++)
    if (bc->fixed[d]) assert_true(z[d] == 0.0);
  const double res = residual(K, B, bc, z, r);
  printf("  %s: |K' z - r| / (|K'| |z|) = %.2e\n", what, res);
  assert_true(res <= 1e-13);
}

static void downdates(void **state) {
  (void)state;
  bond bonds[4 * NN];
  const int nb = make_bonds(bonds);
  int broken[4 * NN] = {0};
  cupid_csr K0 = build(bonds, nb, NULL, 0);
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(N3, &bc));
  for (int a = 0; a < 3; a++) bc->fixed[a] = 1;   /* PD node 0 */
  bc->fixed[3 * (NN - 1)] = 1;                     /* an FE DOF */
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  double r[N3], z[N3], z2[N3], w[N3];
  uint64_t seed = 11;
  for (cupid_int d = 0; d < N3; d++) r[d] = bc->fixed[d] ? 0.0 : cupid_test_random(&seed) - 0.5;

  cupid_coupling_balance B = make_balance();
  for (int balanced = 0; balanced < 2; balanced++) {
    cupid_coupling_balance Bb = balanced ? B : NULL;
    cupid_growth_block M = NULL, M2 = NULL;
    cupid_solve_info info;
    CUPID_ASSERT_OK(cupid_growth_block_create(K0, 3 * NP, bc, Bb, &M, &info));
    assert_non_null(M);
    cupid_int nic = 0, nib = 0;
    assert_int_equal(cupid_growth_block_interface(M, &nic, &nib), 3 * NF - 1);
    printf("  %s: interface %lld rows x %lld columns\n", balanced ? "balanced" : "unbalanced",
           (long long)nic, (long long)nib);
    assert_int_equal(nic, 6);  /* FE rows 30-31 (C and W) */
    assert_int_equal(nib, 12); /* FE columns 30-33 */
    solve_check(M, K0, Bb, bc, r, z, "the factor of K");

    /* two rounds: 3 bonds in the middle, then 4 more, one of them at the coupled node 25 */
    const cupid_int round1[3][2] = {{10, 11}, {10, 12}, {14, 15}};
    const cupid_int round2[4][2] = {{24, 25}, {23, 25}, {18, 19}, {17, 19}};
    memset(broken, 0, sizeof broken);
    for (int b = 0; b < 3; b++) broken[find_bond(bonds, nb, round1[b][0], round1[b][1])] = 1;
    cupid_csr K1 = build(bonds, nb, broken, 0);
    for (int b = 0; b < 4; b++) broken[find_bond(bonds, nb, round2[b][0], round2[b][1])] = 1;
    cupid_csr K2 = build(bonds, nb, broken, 0);
    cupid_growth_downdate dd = {0};
    int ok = 0;
    CUPID_ASSERT_OK(cupid_growth_downdate_terms(K0, K1, &dd, &ok));
    assert_true(ok && dd.r == 3);
    CUPID_ASSERT_OK(cupid_growth_block_downdate(M, &dd, &ok));
    assert_true(ok);
    CUPID_ASSERT_OK(cupid_growth_downdate_terms(K1, K2, &dd, &ok));
    assert_true(ok && dd.r == 4);
    CUPID_ASSERT_OK(cupid_growth_block_downdate(M, &dd, &ok));
    assert_true(ok);
    solve_check(M, K2, Bb, bc, r, z, "downdated twice, against the new K");
    CUPID_ASSERT_OK(cupid_growth_block_create(K2, 3 * NP, bc, Bb, &M2, &info));
    CUPID_ASSERT_OK(cupid_growth_block_solve(M2, r, z2));
    for (cupid_int d = 0; d < N3; d++) w[d] = z[d] - z2[d];
    printf("  downdated against the fresh block factor of the new K: %.2e relative\n",
           max_abs(w, N3) / max_abs(z2, N3));
    assert_true(max_abs(w, N3) <= 1e-11 * max_abs(z2, N3));
    /* the old K's solve is far from it: the check can fail */
    cupid_growth_block M0 = NULL;
    CUPID_ASSERT_OK(cupid_growth_block_create(K0, 3 * NP, bc, Bb, &M0, &info));
    CUPID_ASSERT_OK(cupid_growth_block_solve(M0, r, w));
    for (cupid_int d = 0; d < N3; d++) w[d] -= z2[d];
    assert_true(max_abs(w, N3) > 1e-3 * max_abs(z2, N3));

    /* node 5 (no ground spring) loses all of its bonds: A singular, refused */
    const cupid_int cut[4][2] = {{3, 5}, {4, 5}, {5, 6}, {5, 7}};
    for (int b = 0; b < 4; b++) broken[find_bond(bonds, nb, cut[b][0], cut[b][1])] = 1;
    cupid_csr K3 = build(bonds, nb, broken, 0);
    CUPID_ASSERT_OK(cupid_growth_downdate_terms(K2, K3, &dd, &ok));
    assert_true(ok && dd.r == 4);
    CUPID_ASSERT_OK(cupid_growth_block_downdate(M2, &dd, &ok));
    assert_false(ok);

    cupid_growth_downdate_free(&dd);
    cupid_growth_block_destroy(&M);
    cupid_growth_block_destroy(&M2);
    cupid_growth_block_destroy(&M0);
    cupid_csr_destroy(&K1);
    cupid_csr_destroy(&K2);
    cupid_csr_destroy(&K3);
  }

  /* a PD block that is not symmetric: not taken */
  cupid_csr Ks = build(bonds, nb, NULL, 1);
  cupid_growth_block M = NULL;
  cupid_solve_info info;
  CUPID_ASSERT_OK(cupid_growth_block_create(Ks, 3 * NP, bc, NULL, &M, &info));
  assert_null(M);

  cupid_csr_destroy(&Ks);
  cupid_coupling_balance_destroy(&B);
  cupid_csr_destroy(&K0);
  cupid_dirichlet_destroy(&bc);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(downdates)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
