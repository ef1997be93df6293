/* The inverse of a factorised matrix M brought to M - V V^T exactly, by Sherman-Morrison-
 * Woodbury, as bonds break (growth_lu.c: the UMFPACK LU of the non-symmetric fictitious-node K,
 * which SuiteSparse cannot downdate as CHOLMOD downdates the Arlequin factor; issue 34).
 *
 *   (M - V V^T)^-1 = M^-1 + Z S^-1 V^T M^-1,  Z = M^-1 V,  S = I - V^T Z   (r x r)
 *
 * Each column v (a broken bond's rank-one term, growth_downdate.c: 6 entries) costs one solve
 * with M when it arrives; an application costs the solve with M, V^T y (6 r products), S^-1
 * (r^2) and Z c (n r). S^-1 is kept explicitly and grown by bordering: with the k new columns,
 *
 *   S' = [S B; C D],  Sigma = D - C S^-1 B,
 *   S'^-1 = [S^-1 + S^-1 B Sigma^-1 C S^-1, -S^-1 B Sigma^-1; -Sigma^-1 C S^-1, Sigma^-1],
 *
 * O(r^2 k) a round, in plain loops of a fixed order (no threaded BLAS; Sigma by
 * cupid_dense_solve), so that the iterates, hence the bonds that break, are the same for any
 * thread count. det S' = det S det Sigma and
 * det(M - V V^T) = det M det S: a round whose Sigma is singular (a pivot under SMW_PIVOT_MIN)
 * left the matrix singular (a part that breaking left loose), and the caller factorises afresh,
 * whose pivot names the node. */
#include <math.h>
#include <string.h>

#include "problem_internal.h"

/* Sigma's pivots are relative changes of the stiffness the broken bonds took away (S = I at no
 * break): a node left with under 1e-10 of it is loose for any purpose. */
#define SMW_PIVOT_MIN 1e-10

/* Room for r_new columns: every buffer made anew and filled before any is swapped in, so that
 * a failed allocation leaves u as it was. */
static cupid_status grow(cupid_growth_smw *u, cupid_int r_new) {
  if (r_new <= u->cap) return CUPID_SUCCESS;
  cupid_int cap = u->cap ? 2 * u->cap : 64;
  while (cap < r_new) cap *= 2;
  const size_t n = (size_t)u->n, r = (size_t)u->r;
  double *Si = NULL, *Z = NULL, *vals = NULL, *w = NULL;
  cupid_int *rows = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_calloc((size_t)cap * (size_t)cap + 1, sizeof *Si, "SMW inverse", &Si));
  CUPID_TRY(cupid_malloc((size_t)cap * n + 1, sizeof *Z, "SMW columns", &Z));
  CUPID_TRY(cupid_malloc(6 * (size_t)cap, sizeof *rows, "SMW columns", &rows));
  CUPID_TRY(cupid_malloc(6 * (size_t)cap, sizeof *vals, "SMW columns", &vals));
  CUPID_TRY(cupid_calloc(2 * (size_t)cap + 1, sizeof *w, "SMW work", &w));
  for (size_t a = 0; a < r; a++) memcpy(Si + a * (size_t)cap, u->Si + a * (size_t)u->cap, r * sizeof *Si);
  if (r) {
    memcpy(Z, u->Z, r * n * sizeof *Z);
    memcpy(rows, u->rows, 6 * r * sizeof *rows);
    memcpy(vals, u->vals, 6 * r * sizeof *vals);
  }
  cupid_free(&u->Si), cupid_free(&u->Z), cupid_free(&u->rows), cupid_free(&u->vals), cupid_free(&u->w);
  u->Si = Si, u->Z = Z, u->rows = rows, u->vals = vals, u->w = w;
  Si = Z = vals = w = NULL, rows = NULL;
  u->cap = cap;
cleanup:
  cupid_free(&Si), cupid_free(&Z), cupid_free(&rows), cupid_free(&vals), cupid_free(&w);
  return st;
}

/* v_a^T x: the column's 6 entries. */
static double vdot(const cupid_growth_smw *u, cupid_int a, const double *x) {
  double s = 0.0;
  for (int t = 0; t < 6; t++) s += u->vals[6 * a + t] * x[u->rows[6 * a + t]];
  return s;
}

cupid_status cupid_growth_smw_add(cupid_growth_smw *u, cupid_int n, const cupid_growth_downdate *dd,
                                  cupid_status (*solve)(void *ctx, const double *b, double *x),
                                  void *ctx, int *ok) {
  const cupid_int r0 = u->r, k = dd->r, r1 = r0 + k;
  double *sig = NULL, *work = NULL, *P = NULL, *Q = NULL;
  double *b = NULL; /* a column v, then r0-long scratch, zero again at the end */
  cupid_status st = CUPID_SUCCESS;
  *ok = 1;
  if (k == 0) return CUPID_SUCCESS;
  CUPID_CHECK(u->r == 0 || u->n == n, CUPID_ERR_ARGUMENT, "SMW update: %lld DOFs, its columns %lld",
              (long long)n, (long long)u->n);
  u->n = n;
  CUPID_CALL(grow(u, r1));
  const cupid_int cap = u->cap;
  /* the new columns and Z = M^-1 v */
  CUPID_TRY(cupid_calloc((size_t)(n > r0 ? n : r0) + 1, sizeof *b, "SMW column", &b));
  for (cupid_int c = 0; c < k; c++) {
    const cupid_int a = r0 + c, q = dd->colptr[c];
    for (int t = 0; t < 6; t++) u->rows[6 * a + t] = dd->rows[q + t], u->vals[6 * a + t] = dd->vals[q + t];
    for (int t = 0; t < 6; t++) b[u->rows[6 * a + t]] += u->vals[6 * a + t];
    CUPID_TRY(solve(ctx, b, u->Z + (size_t)a * n));
    for (int t = 0; t < 6; t++) b[u->rows[6 * a + t]] = 0.0;
  }
  /* S' = [S B; C D]: B = -V_old^T Z_new (r0 x k), C = -V_new^T Z_old (k x r0),
   * D = I - V_new^T Z_new; Sigma = D - C S^-1 B; P = S^-1 B, Q = C S^-1 */
  CUPID_TRY(cupid_calloc((size_t)(k * k) + 1, sizeof *sig, "SMW Schur", &sig));
  CUPID_TRY(cupid_calloc((size_t)(k * k) + 1, sizeof *work, "SMW Schur", &work));
  CUPID_TRY(cupid_calloc((size_t)(r0 * k) + 1, sizeof *P, "SMW border", &P));
  CUPID_TRY(cupid_calloc((size_t)(r0 * k) + 1, sizeof *Q, "SMW border", &Q));
  for (cupid_int c = 0; c < k; c++) {
    const double *z = u->Z + (size_t)(r0 + c) * n;
    for (cupid_int a = 0; a < k; a++) sig[a * k + c] = (a == c) - vdot(u, r0 + a, z);
    for (cupid_int e = 0; e < r0; e++) b[e] = -vdot(u, e, z); /* B(:, c) */
    for (cupid_int a = 0; a < r0; a++) {
      double s = 0.0;
      for (cupid_int e = 0; e < r0; e++) s += u->Si[(size_t)a * cap + e] * b[e];
      P[a * k + c] = s;
    }
  }
  for (cupid_int a = 0; a < k; a++) {
    for (cupid_int e = 0; e < r0; e++) b[e] = -vdot(u, r0 + a, u->Z + (size_t)e * n); /* C(a, :) */
    for (cupid_int e = 0; e < r0; e++) {
      double s = 0.0;
      for (cupid_int d = 0; d < r0; d++) s += b[d] * u->Si[(size_t)d * cap + e];
      Q[a * r0 + e] = s;
    }
    for (cupid_int c = 0; c < k; c++) {
      double s = 0.0;
      for (cupid_int e = 0; e < r0; e++) s += b[e] * P[e * k + c];
      sig[a * k + c] -= s;
    }
  }
  for (cupid_int e = 0; e < r0; e++) b[e] = 0.0;
  *ok = cupid_dense_invert((int)k, sig, work, SMW_PIVOT_MIN);
  if (!*ok) goto cleanup; /* left as it was; the caller drops the factor */
  /* S'^-1: the old block gains P Sigma^-1 Q; the borders -P Sigma^-1 and -Sigma^-1 Q */
  for (cupid_int a = 0; a < r0; a++) {
    double *psa = work; /* row a of P Sigma^-1 (Sigma^-1 is in sig now) */
    for (cupid_int c = 0; c < k; c++) {
      double s = 0.0;
      for (cupid_int e = 0; e < k; e++) s += P[a * k + e] * sig[e * k + c];
      psa[c] = s;
    }
    double *row = u->Si + (size_t)a * cap;
    for (cupid_int e = 0; e < r0; e++) {
      double s = 0.0;
      for (cupid_int c = 0; c < k; c++) s += psa[c] * Q[c * r0 + e];
      row[e] += s;
    }
    for (cupid_int c = 0; c < k; c++) row[r0 + c] = -psa[c];
  }
  for (cupid_int c = 0; c < k; c++) {
    double *row = u->Si + (size_t)(r0 + c) * cap;
    for (cupid_int e = 0; e < r0; e++) {
      double s = 0.0;
      for (cupid_int d = 0; d < k; d++) s += sig[c * k + d] * Q[d * r0 + e];
      row[e] = -s;
    }
    for (cupid_int d = 0; d < k; d++) row[r0 + d] = sig[c * k + d];
  }
  u->r = r1;
cleanup:
  cupid_free(&b);
  cupid_free(&sig);
  cupid_free(&work);
  cupid_free(&P);
  cupid_free(&Q);
  return st;
}

void cupid_growth_smw_correct(const cupid_growth_smw *u, double *y) {
  const cupid_int r = u->r, n = u->n, cap = u->cap;
  if (r == 0) return;
  double *w = u->w, *c = u->w + r;
  for (cupid_int a = 0; a < r; a++) w[a] = vdot(u, a, y);
  for (cupid_int a = 0; a < r; a++) {
    double s = 0.0;
    for (cupid_int e = 0; e < r; e++) s += u->Si[(size_t)a * cap + e] * w[e];
    c[a] = s;
  }
  /* y += Z c by chunks of rows, the columns in order within each: the same sums for any thread
   * count, and each column read as a stream */
  const cupid_int chunk = 2048, nchunks = (n + chunk - 1) / chunk;
#pragma omp parallel for schedule(static) if (n > 20000)
  for (cupid_int q = 0; q < nchunks; q++) {
    const cupid_int j0 = q * chunk, j1 = j0 + chunk < n ? j0 + chunk : n;
    for (cupid_int a = 0; a < r; a++) {
      const double *z = u->Z + (size_t)a * n, ca = c[a];
      for (cupid_int j = j0; j < j1; j++) y[j] += z[j] * ca;
    }
  }
}

void cupid_growth_smw_reset(cupid_growth_smw *u) { u->r = 0; }

void cupid_growth_smw_free(cupid_growth_smw *u) {
  cupid_free(&u->Si);
  cupid_free(&u->Z);
  cupid_free(&u->rows);
  cupid_free(&u->vals);
  cupid_free(&u->w);
  memset(u, 0, sizeof *u);
}
