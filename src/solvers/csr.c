/* Block CSR matrices (include/cupid/solvers.h): construction, products, inspection. */
#include <math.h>
#include <string.h>

#include "cupid/solvers.h"

/* Below a few thousand block rows a parallel region costs more than the loop it runs. */
#define CUPID_CSR_PARALLEL(M) ((M)->nrows > 2048)

/* Allocate a matrix of nnzb blocks; values zeroed, rowptr/col left for the caller. */
static cupid_status csr_alloc(cupid_int nrows, cupid_int ncols, int bs, cupid_int nnzb,
                              cupid_csr *out) {
  cupid_status st = CUPID_SUCCESS;
  cupid_csr A = NULL;
  const size_t bs2 = (size_t)bs * (size_t)bs;
  CUPID_TRY(cupid_calloc(1, sizeof *A, "sparse matrix", &A));
  A->nrows = nrows;
  A->ncols = ncols;
  A->bs = bs;
  CUPID_TRY(cupid_malloc((size_t)nrows + 1, sizeof *A->rowptr, "sparse matrix row pointers",
                         &A->rowptr));
  CUPID_TRY(cupid_malloc((size_t)nnzb, sizeof *A->col, "sparse matrix column indices", &A->col));
  CUPID_TRY_CHECK((size_t)nnzb <= SIZE_MAX / bs2, CUPID_ERR_MEMORY,
                  "sparse matrix values: %lld blocks of %dx%d overflow", (long long)nnzb, bs, bs);
  CUPID_TRY(cupid_calloc((size_t)nnzb * bs2, sizeof *A->val, "sparse matrix values", &A->val));
  A->rowptr[0] = 0;
  *out = A;
  return CUPID_SUCCESS;
cleanup:
  cupid_csr_destroy(&A);
  return st;
}

static cupid_status check_shape(cupid_int nrows, cupid_int ncols, int bs) {
  CUPID_CHECK(nrows >= 0 && ncols >= 0, CUPID_ERR_ARGUMENT,
              "sparse matrix: negative size %lld x %lld", (long long)nrows, (long long)ncols);
  CUPID_CHECK(bs == 1 || bs == 3, CUPID_ERR_ARGUMENT,
              "sparse matrix: block size must be 1 or 3, got %d", bs);
  return CUPID_SUCCESS;
}

cupid_status cupid_csr_create(cupid_int nrows, cupid_int ncols, int bs, const cupid_int *rowptr,
                              const cupid_int *col, cupid_csr *A) {
  CUPID_CHECK(A != NULL && rowptr != NULL, CUPID_ERR_ARGUMENT, "cupid_csr_create: NULL argument");
  *A = NULL;
  CUPID_CALL(check_shape(nrows, ncols, bs));
  CUPID_CHECK(rowptr[0] == 0, CUPID_ERR_ARGUMENT, "sparse matrix: rowptr[0] = %lld, not 0",
              (long long)rowptr[0]);
  CUPID_CHECK(col != NULL || rowptr[nrows] == 0, CUPID_ERR_ARGUMENT,
              "sparse matrix: NULL column indices");
  for (cupid_int r = 0; r < nrows; r++) {
    CUPID_CHECK(rowptr[r + 1] >= rowptr[r], CUPID_ERR_ARGUMENT,
                "sparse matrix: row pointers decrease at row %lld", (long long)r);
    for (cupid_int p = rowptr[r]; p < rowptr[r + 1]; p++) {
      CUPID_CHECK(col[p] >= 0 && col[p] < ncols, CUPID_ERR_ARGUMENT,
                  "sparse matrix: row %lld has column %lld outside [0, %lld)", (long long)r,
                  (long long)col[p], (long long)ncols);
      CUPID_CHECK(p == rowptr[r] || col[p] > col[p - 1], CUPID_ERR_ARGUMENT,
                  "sparse matrix: row %lld columns are not sorted and unique (%lld after %lld)",
                  (long long)r, (long long)col[p], (long long)col[p - 1]);
    }
  }
  const cupid_int nnzb = rowptr[nrows];
  CUPID_CALL(csr_alloc(nrows, ncols, bs, nnzb, A));
  memcpy((*A)->rowptr, rowptr, ((size_t)nrows + 1) * sizeof *rowptr);
  if (nnzb > 0) memcpy((*A)->col, col, (size_t)nnzb * sizeof *col);
  return CUPID_SUCCESS;
}

/*
 * Two stable counting sorts (by column, then by row) order the triplets by (row, column) in
 * O(n + nrows + ncols); one linear pass then sums the duplicates.
 */
cupid_status cupid_csr_from_triplets(cupid_int nrows, cupid_int ncols, cupid_int n,
                                     const cupid_int *i, const cupid_int *j, const double *v,
                                     cupid_csr *A) {
  CUPID_CHECK(A != NULL, CUPID_ERR_ARGUMENT, "cupid_csr_from_triplets: NULL output");
  *A = NULL;
  CUPID_CALL(check_shape(nrows, ncols, 1));
  CUPID_CHECK(n >= 0, CUPID_ERR_ARGUMENT, "triplets: negative count %lld", (long long)n);
  CUPID_CHECK(n == 0 || (i && j && v), CUPID_ERR_ARGUMENT, "triplets: NULL arrays");
  for (cupid_int t = 0; t < n; t++)
    CUPID_CHECK(i[t] >= 0 && i[t] < nrows && j[t] >= 0 && j[t] < ncols, CUPID_ERR_ARGUMENT,
                "triplet %lld: (%lld, %lld) outside the %lld x %lld matrix", (long long)t,
                (long long)i[t], (long long)j[t], (long long)nrows, (long long)ncols);

  cupid_status st = CUPID_SUCCESS;
  cupid_int *count = NULL, *bycol = NULL, *rowstart = NULL, *scol = NULL;
  double *sval = NULL;
  cupid_csr B = NULL;
  const cupid_int nmax = nrows > ncols ? nrows : ncols;
  CUPID_TRY(cupid_calloc((size_t)nmax + 1, sizeof *count, "triplet counts", &count));
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *bycol, "triplet order", &bycol));
  CUPID_TRY(cupid_calloc((size_t)nrows + 1, sizeof *rowstart, "triplet rows", &rowstart));
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *scol, "sorted triplet columns", &scol));
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *sval, "sorted triplet values", &sval));

  /* 1: stable order by column */
  for (cupid_int t = 0; t < n; t++) count[j[t] + 1]++;
  for (cupid_int c = 0; c < ncols; c++) count[c + 1] += count[c];
  for (cupid_int t = 0; t < n; t++) bycol[count[j[t]]++] = t;
  /* 2: stable bucket by row -> (row, column) order */
  for (cupid_int t = 0; t < n; t++) rowstart[i[t] + 1]++;
  for (cupid_int r = 0; r < nrows; r++) rowstart[r + 1] += rowstart[r];
  memcpy(count, rowstart, (size_t)nrows * sizeof *count);
  for (cupid_int s = 0; s < n; s++) {
    const cupid_int t = bycol[s];
    const cupid_int q = count[i[t]]++;
    scol[q] = j[t];
    sval[q] = v[t];
  }
  /* 3: sum duplicates in place, row by row */
  cupid_int nnz = 0;
  for (cupid_int r = 0; r < nrows; r++) {
    const cupid_int begin = nnz;
    for (cupid_int q = rowstart[r]; q < rowstart[r + 1]; q++) {
      if (nnz > begin && scol[nnz - 1] == scol[q]) {
        sval[nnz - 1] += sval[q];
      } else {
        scol[nnz] = scol[q];
        sval[nnz] = sval[q];
        nnz++;
      }
    }
    count[r] = nnz; /* end of row r */
  }
  CUPID_TRY(csr_alloc(nrows, ncols, 1, nnz, &B));
  for (cupid_int r = 0; r < nrows; r++) B->rowptr[r + 1] = count[r];
  if (nnz > 0) {
    memcpy(B->col, scol, (size_t)nnz * sizeof *scol);
    memcpy(B->val, sval, (size_t)nnz * sizeof *sval);
  }
  *A = B;
cleanup:
  cupid_free(&count);
  cupid_free(&bycol);
  cupid_free(&rowstart);
  cupid_free(&scol);
  cupid_free(&sval);
  return st;
}

void cupid_csr_destroy(cupid_csr *A) {
  if (!A || !*A) return;
  cupid_free(&(*A)->rowptr);
  cupid_free(&(*A)->col);
  cupid_free(&(*A)->val);
  cupid_free(A);
}

cupid_status cupid_csr_duplicate(const cupid_csr_t *A, cupid_csr *B) {
  CUPID_CHECK(A && B, CUPID_ERR_ARGUMENT, "cupid_csr_duplicate: NULL argument");
  *B = NULL;
  const cupid_int nnzb = A->rowptr[A->nrows];
  CUPID_CALL(csr_alloc(A->nrows, A->ncols, A->bs, nnzb, B));
  memcpy((*B)->rowptr, A->rowptr, ((size_t)A->nrows + 1) * sizeof *A->rowptr);
  if (nnzb > 0) {
    memcpy((*B)->col, A->col, (size_t)nnzb * sizeof *A->col);
    memcpy((*B)->val, A->val, (size_t)cupid_csr_nnz(A) * sizeof *A->val);
  }
  return CUPID_SUCCESS;
}

/* Position of column c in row r, or -1. */
static cupid_int csr_position(const cupid_csr_t *A, cupid_int r, cupid_int c) {
  cupid_int lo = A->rowptr[r], hi = A->rowptr[r + 1];
  while (lo < hi) {
    const cupid_int mid = lo + (hi - lo) / 2;
    if (A->col[mid] < c)
      lo = mid + 1;
    else
      hi = mid;
  }
  return (lo < A->rowptr[r + 1] && A->col[lo] == c) ? lo : -1;
}

double *cupid_csr_find(const cupid_csr_t *A, cupid_int row, cupid_int col) {
  if (!A || row < 0 || row >= A->nrows || col < 0 || col >= A->ncols) return NULL;
  const cupid_int p = csr_position(A, row, col);
  return p < 0 ? NULL : A->val + (size_t)p * (size_t)(A->bs * A->bs);
}

void cupid_csr_zero_row(cupid_csr A, cupid_int r) {
  const size_t b2 = (size_t)A->bs * (size_t)A->bs;
  memset(A->val + b2 * (size_t)A->rowptr[r], 0, b2 * (size_t)(A->rowptr[r + 1] - A->rowptr[r]) * sizeof *A->val);
}

/* Both rows sorted: walked together. */
cupid_status cupid_csr_add_row(cupid_csr A, cupid_int r, const cupid_csr_t *P, cupid_int pr) {
  CUPID_CHECK(A && P && A->bs == P->bs && r >= 0 && r < A->nrows && pr >= 0 && pr < P->nrows,
              CUPID_ERR_ARGUMENT, "cupid_csr_add_row: rows %lld and %lld of matrices of one block size",
              (long long)r, (long long)pr);
  const size_t b2 = (size_t)A->bs * (size_t)A->bs;
  cupid_int p = A->rowptr[r];
  const cupid_int end = A->rowptr[r + 1];
  for (cupid_int q = P->rowptr[pr]; q < P->rowptr[pr + 1]; q++) {
    while (p < end && A->col[p] < P->col[q]) p++;
    CUPID_CHECK(p < end && A->col[p] == P->col[q], CUPID_ERR_ARGUMENT,
                "cupid_csr_add_row: row %lld lacks column %lld of the row added", (long long)r,
                (long long)P->col[q]);
    double *dst = A->val + b2 * (size_t)p;
    const double *src = P->val + b2 * (size_t)q;
    for (size_t e = 0; e < b2; e++) dst[e] += src[e];
  }
  return CUPID_SUCCESS;
}

/* Row r of the 3x3-block product (one code for the whole product and the marked rows, so
 * that both give the same bits). */
static inline void row3(const cupid_csr_t *A, const double *x, cupid_int r, double *y) {
  double y0 = 0.0, y1 = 0.0, y2 = 0.0;
  for (cupid_int p = A->rowptr[r]; p < A->rowptr[r + 1]; p++) {
    const double *a = A->val + 9 * p;
    const double *xc = x + 3 * A->col[p];
    y0 += a[0] * xc[0] + a[1] * xc[1] + a[2] * xc[2];
    y1 += a[3] * xc[0] + a[4] * xc[1] + a[5] * xc[2];
    y2 += a[6] * xc[0] + a[7] * xc[1] + a[8] * xc[2];
  }
  y[3 * r] = y0;
  y[3 * r + 1] = y1;
  y[3 * r + 2] = y2;
}

/* The 3x3-block product, the hot case (PD and beam stiffness). */
static void matvec3(const cupid_csr_t *A, const double *x, double *y) {
#pragma omp parallel for schedule(static) if (CUPID_CSR_PARALLEL(A))
  for (cupid_int r = 0; r < A->nrows; r++) row3(A, x, r, y);
}

static void matvec1(const cupid_csr_t *A, const double *x, double *y) {
#pragma omp parallel for schedule(static) if (CUPID_CSR_PARALLEL(A))
  for (cupid_int r = 0; r < A->nrows; r++) {
    double s = 0.0;
    for (cupid_int p = A->rowptr[r]; p < A->rowptr[r + 1]; p++) s += A->val[p] * x[A->col[p]];
    y[r] = s;
  }
}

/* Any block size (the struct is public, so do not rely on bs being 1 or 3). */
static void matvec_general(const cupid_csr_t *A, const double *x, double *y) {
  const int bs = A->bs;
#pragma omp parallel for schedule(static) if (CUPID_CSR_PARALLEL(A))
  for (cupid_int r = 0; r < A->nrows; r++) {
    for (int a = 0; a < bs; a++) {
      double s = 0.0;
      for (cupid_int p = A->rowptr[r]; p < A->rowptr[r + 1]; p++)
        for (int b = 0; b < bs; b++)
          s += A->val[(p * bs + a) * bs + b] * x[A->col[p] * bs + b];
      y[r * bs + a] = s;
    }
  }
}

void cupid_csr_matvec(const cupid_csr_t *A, const double *x, double *y) {
  if (A->bs == 3)
    matvec3(A, x, y);
  else if (A->bs == 1)
    matvec1(A, x, y);
  else
    matvec_general(A, x, y);
}

void cupid_csr_matvec_marked(const cupid_csr_t *A, const double *x, const unsigned char *mark,
                             double *y) {
  if (A->bs != 3) { /* the whole product: the unmarked rows are zero there too */
    cupid_csr_matvec(A, x, y);
    return;
  }
  for (cupid_int r = 0; r < A->nrows; r++) {
    if (mark[r]) row3(A, x, r, y);
    else y[3 * r] = y[3 * r + 1] = y[3 * r + 2] = 0.0;
  }
}

void cupid_csr_matvec_rows(const cupid_csr_t *A, const double *x, cupid_int off, cupid_int d0,
                           cupid_int d1, double *y) {
  const int bs = A->bs;
  if (d0 < off) d0 = off;
  if (d1 > off + A->nrows * bs) d1 = off + A->nrows * bs;
  if (d0 >= d1) return;
  const cupid_int r0 = (d0 - off) / bs, r1 = (d1 - off + bs - 1) / bs;
#pragma omp parallel for schedule(static) if (r1 - r0 > 4096)
  for (cupid_int r = r0; r < r1; r++)
    for (int a = 0; a < bs; a++) {
      const cupid_int d = off + r * bs + a;
      if (d < d0 || d >= d1) continue;
      double s = 0.0;
      for (cupid_int p = A->rowptr[r]; p < A->rowptr[r + 1]; p++)
        for (int b = 0; b < bs; b++)
          s += A->val[((size_t)p * bs + a) * bs + b] * x[(size_t)A->col[p] * bs + b];
      y[d] = s;
    }
}

/* A scatter: serial, since the rows of A^T are not at hand (a gather would need A^T). */
void cupid_csr_matvec_transpose(const cupid_csr_t *A, const double *x, double *y) {
  const int bs = A->bs;
  memset(y, 0, (size_t)(A->ncols * bs) * sizeof *y);
  for (cupid_int r = 0; r < A->nrows; r++)
    for (cupid_int p = A->rowptr[r]; p < A->rowptr[r + 1]; p++)
      for (int a = 0; a < bs; a++)
        for (int b = 0; b < bs; b++)
          y[A->col[p] * bs + b] += A->val[(p * bs + a) * bs + b] * x[r * bs + a];
}

cupid_status cupid_csr_to_scalar(const cupid_csr_t *A, cupid_csr *S) {
  CUPID_CHECK(A && S, CUPID_ERR_ARGUMENT, "cupid_csr_to_scalar: NULL argument");
  *S = NULL;
  if (A->bs == 1) return cupid_csr_duplicate(A, S);
  const cupid_int bs = A->bs;
  CUPID_CALL(csr_alloc(A->nrows * bs, A->ncols * bs, 1, cupid_csr_nnz(A), S));
  cupid_csr B = *S;
#pragma omp parallel for schedule(static) if (CUPID_CSR_PARALLEL(A))
  for (cupid_int r = 0; r < A->nrows; r++) {
    const cupid_int len = A->rowptr[r + 1] - A->rowptr[r];
    for (cupid_int a = 0; a < bs; a++) {
      cupid_int q = A->rowptr[r] * bs * bs + a * len * bs; /* start of scalar row r*bs+a */
      B->rowptr[r * bs + a + 1] = q + len * bs;
      for (cupid_int p = A->rowptr[r]; p < A->rowptr[r + 1]; p++)
        for (cupid_int b = 0; b < bs; b++, q++) {
          B->col[q] = A->col[p] * bs + b;
          B->val[q] = A->val[(p * bs + a) * bs + b];
        }
    }
  }
  return CUPID_SUCCESS;
}

double cupid_csr_asymmetry(const cupid_csr_t *A) {
  if (A->nrows != A->ncols) return NAN;
  const int bs = A->bs;
  double maxdiff = 0.0, maxabs = 0.0;
#pragma omp parallel for schedule(static) reduction(max : maxdiff, maxabs) if (CUPID_CSR_PARALLEL(A))
  for (cupid_int r = 0; r < A->nrows; r++) {
    for (cupid_int p = A->rowptr[r]; p < A->rowptr[r + 1]; p++) {
      const cupid_int q = csr_position(A, A->col[p], r); /* block (col, row) */
      for (int a = 0; a < bs; a++)
        for (int b = 0; b < bs; b++) {
          const double v = A->val[(p * bs + a) * bs + b];
          const double w = q < 0 ? 0.0 : A->val[(q * bs + b) * bs + a];
          maxabs = fmax(maxabs, fabs(v));
          maxdiff = fmax(maxdiff, fabs(v - w));
        }
    }
  }
  return maxabs > 0.0 ? maxdiff / maxabs : 0.0;
}

cupid_int cupid_csr_nnz(const cupid_csr_t *A) {
  return A->rowptr[A->nrows] * (cupid_int)A->bs * (cupid_int)A->bs;
}

int64_t cupid_csr_bytes(const cupid_csr_t *A) {
  return (int64_t)sizeof *A + (int64_t)(A->nrows + 1) * (int64_t)sizeof *A->rowptr +
         (int64_t)A->rowptr[A->nrows] * (int64_t)sizeof *A->col +
         (int64_t)cupid_csr_nnz(A) * (int64_t)sizeof *A->val;
}

void cupid_csr_zero(cupid_csr_t *A) {
  const cupid_int n = cupid_csr_nnz(A);
#pragma omp parallel for schedule(static) if (CUPID_CSR_PARALLEL(A))
  for (cupid_int k = 0; k < n; k++) A->val[k] = 0.0;
}

void cupid_csr_scale(cupid_csr_t *A, double alpha) {
  const cupid_int n = cupid_csr_nnz(A);
#pragma omp parallel for schedule(static) if (CUPID_CSR_PARALLEL(A))
  for (cupid_int k = 0; k < n; k++) A->val[k] *= alpha;
}

/* Same pattern: same shape and block size, and identical (or shared) index arrays. */
static int same_pattern(const cupid_csr_t *X, const cupid_csr_t *Y) {
  if (X->nrows != Y->nrows || X->ncols != Y->ncols || X->bs != Y->bs) return 0;
  if (X->rowptr != Y->rowptr &&
      memcmp(X->rowptr, Y->rowptr, ((size_t)X->nrows + 1) * sizeof *X->rowptr) != 0)
    return 0;
  const cupid_int nnzb = X->rowptr[X->nrows];
  return X->col == Y->col || nnzb == 0 ||
         memcmp(X->col, Y->col, (size_t)nnzb * sizeof *X->col) == 0;
}

cupid_status cupid_csr_axpy(double alpha, const cupid_csr_t *X, cupid_csr_t *Y) {
  CUPID_CHECK(X && Y, CUPID_ERR_ARGUMENT, "cupid_csr_axpy: NULL argument");
  CUPID_CHECK(same_pattern(X, Y), CUPID_ERR_ARGUMENT,
              "cupid_csr_axpy: the matrices have different sparsity patterns");
  const cupid_int n = cupid_csr_nnz(X);
#pragma omp parallel for schedule(static) if (CUPID_CSR_PARALLEL(X))
  for (cupid_int k = 0; k < n; k++) Y->val[k] += alpha * X->val[k];
  return CUPID_SUCCESS;
}

cupid_status cupid_csr_diagonal(const cupid_csr_t *A, double *d) {
  CUPID_CHECK(A && d, CUPID_ERR_ARGUMENT, "cupid_csr_diagonal: NULL argument");
  CUPID_CHECK(A->nrows == A->ncols, CUPID_ERR_ARGUMENT,
              "cupid_csr_diagonal: the matrix is %lld x %lld blocks, not square",
              (long long)A->nrows, (long long)A->ncols);
  const int bs = A->bs;
#pragma omp parallel for schedule(static) if (CUPID_CSR_PARALLEL(A))
  for (cupid_int r = 0; r < A->nrows; r++) {
    const cupid_int p = csr_position(A, r, r);
    for (int a = 0; a < bs; a++) d[r * bs + a] = p < 0 ? 0.0 : A->val[(p * bs + a) * bs + a];
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_csr_reactions(const cupid_csr_t *K, const double *u, const double *f,
                                 const cupid_dirichlet_t *bc, double *r) {
  CUPID_CHECK(K && u && bc && r, CUPID_ERR_ARGUMENT, "cupid_csr_reactions: NULL argument");
  const int bs = K->bs;
  CUPID_CHECK(K->nrows == K->ncols && K->nrows * bs == bc->n, CUPID_ERR_ARGUMENT,
              "cupid_csr_reactions: %lld x %lld blocks of size %d do not match %lld DOFs",
              (long long)K->nrows, (long long)K->ncols, bs, (long long)bc->n);
#pragma omp parallel for schedule(static) if (CUPID_CSR_PARALLEL(K))
  for (cupid_int row = 0; row < K->nrows; row++) {
    for (int a = 0; a < bs; a++) {
      const cupid_int g = row * bs + a;
      double s = 0.0;
      if (bc->fixed[g]) {
        for (cupid_int p = K->rowptr[row]; p < K->rowptr[row + 1]; p++)
          for (int b = 0; b < bs; b++) s += K->val[(p * bs + a) * bs + b] * u[K->col[p] * bs + b];
        if (f) s -= f[g];
      }
      r[g] = s;
    }
  }
  return CUPID_SUCCESS;
}
