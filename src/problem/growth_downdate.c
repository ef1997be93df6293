/* The change of K by broken bonds as rank-one terms, for downdating the factor of the last
 * factorisation instead of renewing it (quasi-static growth, growth.c; issue 17 item 3).
 *
 * A bond-based bond between nodes i and j adds k e e^T to the blocks (i, i) and (j, j) and
 * -k e e^T to (i, j) and (j, i) (e its unit direction, k > 0 its stiffness with volumes and
 * weights: the Arlequin weighting scales k and keeps the form). So its removal is
 * K_new = K_old - v v^T with v = sqrt(k) (e at i, -e at j). The terms are read off the
 * difference of the two assembled matrices: an off-diagonal block that changed is -k e e^T,
 * and the diagonal blocks must have changed by exactly the sum of the removed terms. Anything
 * else (LPS, where a bond enters the dilatation of both families and so couples their
 * neighbours) is no sum of such terms, and the caller keeps its Krylov re-solves. K need not be
 * symmetric (the fictitious-node K of paper 000 Eq. 38 is not): each lower block that changed
 * must have changed by its pair's term, so Kold - Knew = C C^T holds in both triangles. */
#include <math.h>
#include <string.h>

#include "problem_internal.h"

/* Relative bounds: an off-diagonal block of an unchanged pair holds one bond's term, assembled
 * the same way twice, so it is equal to the bit; a diagonal block sums a family in some order,
 * so its change differs from the removed terms by round-off of the family's size. */
#define RANK_ONE_TOL 1e-10
#define DIAGONAL_TOL 1e-9

typedef struct {
  const double *a; /* old block or NULL */
  const double *b; /* new block or NULL */
} block_pair;

/* old - new of one 3 x 3 block (absent blocks are zero). */
static void block_diff(block_pair p, double d[9]) {
  for (int t = 0; t < 9; t++) d[t] = (p.a ? p.a[t] : 0.0) - (p.b ? p.b[t] : 0.0);
}

static double max_abs(const double *x, int n) {
  double m = 0.0;
  for (int t = 0; t < n; t++) m = fmax(m, fabs(x[t]));
  return m;
}

/* M = -(old - new) of an off-diagonal block as w w^T (M = k e e^T): *ok = 0 when it is not. */
static void rank_one(const double d[9], double w[3], int *ok) {
  double m[9];
  for (int t = 0; t < 9; t++) m[t] = -d[t];
  int c = 0;
  for (int a = 1; a < 3; a++)
    if (m[4 * a] > m[4 * c]) c = a;
  *ok = m[4 * c] > 0.0;
  if (!*ok) return;
  const double s = sqrt(m[4 * c]);
  for (int a = 0; a < 3; a++) w[a] = m[3 * a + c] / s;
  const double scale = max_abs(m, 9);
  for (int a = 0; a < 3 && *ok; a++)
    for (int b = 0; b < 3 && *ok; b++) *ok = fabs(m[3 * a + b] - w[a] * w[b]) <= RANK_ONE_TOL * scale;
}

/* Append a column v (w at node i, -w at node j) to the downdate. */
static cupid_status push_column(cupid_growth_downdate *u, cupid_int i, cupid_int j, const double w[3]) {
  if (u->r + 1 > u->cap) {
    cupid_int cap = u->cap ? 2 * u->cap : 256;
    CUPID_CALL(cupid_realloc((size_t)cap + 1, sizeof *u->colptr, "downdate columns", &u->colptr));
    CUPID_CALL(cupid_realloc(6 * (size_t)cap, sizeof *u->rows, "downdate rows", &u->rows));
    CUPID_CALL(cupid_realloc(6 * (size_t)cap, sizeof *u->vals, "downdate values", &u->vals));
    u->cap = cap;
  }
  cupid_int t = 6 * u->r;
  u->colptr[u->r] = t;
  for (int a = 0; a < 3; a++) {
    u->rows[t + a] = 3 * i + a, u->vals[t + a] = w[a];
    u->rows[t + 3 + a] = 3 * j + a, u->vals[t + 3 + a] = -w[a];
  }
  u->r++;
  u->colptr[u->r] = 6 * u->r;
  return CUPID_SUCCESS;
}

/* The change d = old - new of the lower block (i, j), j < i, is -w w^T of the column pushed for
 * the pair (j, i): the columns are in the order of their pairs, found by bisection. */
static int lower_matches(const cupid_growth_downdate *u, cupid_int i, cupid_int j, const double d[9]) {
  cupid_int lo = 0, hi = u->r;
  while (lo < hi) {
    const cupid_int mid = lo + (hi - lo) / 2, a = u->rows[6 * mid] / 3, b = u->rows[6 * mid + 3] / 3;
    if (a < j || (a == j && b < i)) lo = mid + 1;
    else hi = mid;
  }
  if (lo == u->r || u->rows[6 * lo] / 3 != j || u->rows[6 * lo + 3] / 3 != i) return 0;
  const double *w = u->vals + 6 * lo;
  const double scale = max_abs(d, 9);
  for (int a = 0; a < 3; a++)
    for (int b = 0; b < 3; b++)
      if (fabs(d[3 * a + b] + w[a] * w[b]) > RANK_ONE_TOL * scale) return 0;
  return 1;
}

/* Block q of a 3 x 3 block matrix. */
static const double *block_at(const cupid_csr_t *A, cupid_int q) { return A->val + 9 * q; }

cupid_status cupid_growth_downdate_terms(const cupid_csr_t *Kold, const cupid_csr_t *Knew,
                                         cupid_growth_downdate *u, int *ok) {
  return cupid_growth_downdate_rows(Kold, Knew, NULL, Kold->nrows, u, ok);
}

cupid_status cupid_growth_downdate_rows(const cupid_csr_t *Kold, const cupid_csr_t *Knew,
                                        const cupid_int *rows, cupid_int n_rows,
                                        cupid_growth_downdate *u, int *ok) {
  u->r = 0;
  *ok = Kold->bs == 3 && Knew->bs == 3 && Kold->nrows == Knew->nrows;
  if (!*ok) return CUPID_SUCCESS;
  const cupid_int nb = Kold->nrows;
  cupid_int lower = 0; /* changed blocks below the diagonal */
  double *diag = NULL; /* per node: the old - new change of its diagonal block, less the terms */
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_calloc(9 * (size_t)nb + 1, sizeof *diag, "downdate check", &diag));
  for (cupid_int k = 0; k < n_rows && *ok; k++) {
    const cupid_int i = rows ? rows[k] : k;
    cupid_int p = Kold->rowptr[i], pe = Kold->rowptr[i + 1];
    cupid_int q = Knew->rowptr[i], qe = Knew->rowptr[i + 1];
    while ((p < pe || q < qe) && *ok) {
      const cupid_int cp = p < pe ? Kold->col[p] : nb, cq = q < qe ? Knew->col[q] : nb;
      const cupid_int j = cp < cq ? cp : cq;
      block_pair bp = {cp == j ? block_at(Kold, p) : NULL, cq == j ? block_at(Knew, q) : NULL};
      if (cp == j) p++;
      if (cq == j) q++;
      double d[9];
      block_diff(bp, d);
      if (j == i) {
        for (int t = 0; t < 9; t++) diag[9 * i + t] += d[t];
        continue;
      }
      if (max_abs(d, 9) == 0.0) continue;
      if (j < i) { /* the lower block: the transpose of its pair's upper term (a K that is not
                      symmetric, as Eq. 38's, changes so only where bonds broke) */
        lower++;
        *ok = lower_matches(u, i, j, d);
        continue;
      }
      double w[3];
      rank_one(d, w, ok);
      if (!*ok) break;
      CUPID_TRY(push_column(u, i, j, w));
      for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
          diag[9 * i + 3 * a + b] -= w[a] * w[b];
          diag[9 * j + 3 * a + b] -= w[a] * w[b];
        }
    }
  }
  *ok = *ok && lower == u->r; /* every pair's lower block changed, by the same term */
  /* every diagonal block changed by the removed terms alone (a pushed column's nodes are both
     rows of the list: the blocks of a broken bond changed in both) */
  for (cupid_int k = 0; k < n_rows && *ok; k++) {
    const cupid_int i = rows ? rows[k] : k;
    const cupid_int q = Knew->rowptr[i];
    double scale = 0.0;
    for (cupid_int t = q; t < Knew->rowptr[i + 1]; t++)
      if (Knew->col[t] == i) scale = max_abs(block_at(Knew, t), 9);
    for (cupid_int t = Kold->rowptr[i]; t < Kold->rowptr[i + 1]; t++)
      if (Kold->col[t] == i) scale = fmax(scale, max_abs(block_at(Kold, t), 9));
    *ok = max_abs(diag + 9 * i, 9) <= DIAGONAL_TOL * scale;
  }
cleanup:
  cupid_free(&diag);
  if (!*ok) u->r = 0;
  return st;
}

cupid_status cupid_growth_rows_copy(const cupid_csr_t *K, const cupid_int *rows, cupid_int n_rows,
                                    cupid_csr *out) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int *rowptr = NULL, *col = NULL;
  const size_t b2 = (size_t)K->bs * (size_t)K->bs;
  *out = NULL;
  CUPID_TRY(cupid_calloc((size_t)K->nrows + 1, sizeof *rowptr, "K rows", &rowptr));
  for (cupid_int t = 0; t < n_rows; t++) rowptr[rows[t] + 1] = K->rowptr[rows[t] + 1] - K->rowptr[rows[t]];
  for (cupid_int r = 0; r < K->nrows; r++) rowptr[r + 1] += rowptr[r];
  CUPID_TRY(cupid_malloc((size_t)rowptr[K->nrows] + 1, sizeof *col, "K rows", &col));
  for (cupid_int t = 0; t < n_rows; t++) {
    const cupid_int r = rows[t], n = K->rowptr[r + 1] - K->rowptr[r];
    memcpy(col + rowptr[r], K->col + K->rowptr[r], (size_t)n * sizeof *col);
  }
  CUPID_TRY(cupid_csr_create(K->nrows, K->ncols, K->bs, rowptr, col, out));
  for (cupid_int t = 0; t < n_rows; t++) {
    const cupid_int r = rows[t], n = K->rowptr[r + 1] - K->rowptr[r];
    memcpy((*out)->val + b2 * (size_t)rowptr[r], K->val + b2 * (size_t)K->rowptr[r], b2 * (size_t)n * sizeof *K->val);
  }
cleanup:
  cupid_free(&rowptr);
  cupid_free(&col);
  return st;
}

void cupid_growth_downdate_free(cupid_growth_downdate *u) {
  cupid_free(&u->colptr);
  cupid_free(&u->rows);
  cupid_free(&u->vals);
  memset(u, 0, sizeof *u);
}
