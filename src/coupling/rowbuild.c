/* Row-by-row assembly of block CSR matrices for the coupled system: rows of the coupled
 * matrix mix PD blocks, FE blocks and blocks scattered through interpolation weights, so they
 * are gathered one row at a time (a dense column -> slot marker), sorted and appended. */
#include <stdlib.h>
#include <string.h>

#include "coupling_internal.h"

cupid_status cpl_rowbuild_init(cpl_rowbuild *rb, cupid_int nrows, cupid_int ncols) {
  memset(rb, 0, sizeof *rb);
  rb->nrows = nrows;
  rb->ncols = ncols;
  CUPID_CALL(cupid_malloc((size_t)ncols, sizeof *rb->slot, "row builder marker", &rb->slot));
  for (cupid_int c = 0; c < ncols; c++) rb->slot[c] = -1;
  CUPID_CALL(cupid_calloc((size_t)nrows + 1, sizeof *rb->rowptr, "row pointers", &rb->rowptr));
  rb->cap = 64;
  CUPID_CALL(cupid_malloc((size_t)rb->cap, sizeof *rb->cols, "row columns", &rb->cols));
  CUPID_CALL(cupid_malloc((size_t)rb->cap * 9, sizeof *rb->vals, "row blocks", &rb->vals));
  rb->cap_out = 1024;
  CUPID_CALL(cupid_malloc((size_t)rb->cap_out, sizeof *rb->col, "coupled columns", &rb->col));
  CUPID_CALL(cupid_malloc((size_t)rb->cap_out * 9, sizeof *rb->val, "coupled values", &rb->val));
  return CUPID_SUCCESS;
}

cupid_status cpl_rowbuild_add(cpl_rowbuild *rb, cupid_int c, double s, const double *blk) {
  CUPID_CHECK(c >= 0 && c < rb->ncols, CUPID_ERR_ARGUMENT, "column %lld out of range",
              (long long)c);
  cupid_int k = rb->slot[c];
  if (k < 0) {
    if (rb->n == rb->cap) {
      rb->cap *= 2;
      CUPID_CALL(cupid_realloc((size_t)rb->cap, sizeof *rb->cols, "row columns", &rb->cols));
      CUPID_CALL(cupid_realloc((size_t)rb->cap * 9, sizeof *rb->vals, "row blocks", &rb->vals));
    }
    k = rb->n++;
    rb->slot[c] = k;
    rb->cols[k] = c;
    memset(rb->vals + 9 * k, 0, 9 * sizeof(double));
  }
  double *v = rb->vals + 9 * k;
  for (int a = 0; a < 9; a++) v[a] += s * blk[a];
  return CUPID_SUCCESS;
}

static int cmp_int(const void *a, const void *b) {
  cupid_int x = *(const cupid_int *)a, y = *(const cupid_int *)b;
  return x < y ? -1 : x > y;
}

cupid_status cpl_rowbuild_end_row(cpl_rowbuild *rb, cupid_int diag) {
  static const double zero[9] = {0};
  if (diag >= 0) CUPID_CALL(cpl_rowbuild_add(rb, diag, 0.0, zero));
  if (rb->nnz + rb->n > rb->cap_out) {
    while (rb->nnz + rb->n > rb->cap_out) rb->cap_out *= 2;
    CUPID_CALL(cupid_realloc((size_t)rb->cap_out, sizeof *rb->col, "coupled columns", &rb->col));
    CUPID_CALL(cupid_realloc((size_t)rb->cap_out * 9, sizeof *rb->val, "coupled values", &rb->val));
  }
  /* Sort a copy of the columns; the slots still point at the unsorted blocks. */
  cupid_int *dst = rb->col + rb->nnz;
  memcpy(dst, rb->cols, (size_t)rb->n * sizeof *dst);
  qsort(dst, (size_t)rb->n, sizeof *dst, cmp_int);
  for (cupid_int k = 0; k < rb->n; k++) {
    cupid_int s = rb->slot[dst[k]];
    memcpy(rb->val + 9 * (rb->nnz + k), rb->vals + 9 * s, 9 * sizeof(double));
    rb->slot[dst[k]] = -1;
  }
  rb->nnz += rb->n;
  rb->n = 0;
  rb->rowptr[++rb->nrows_done] = rb->nnz;
  return CUPID_SUCCESS;
}

cupid_status cpl_rowbuild_finish(cpl_rowbuild *rb, cupid_csr *K) {
  CUPID_CHECK(rb->nrows_done == rb->nrows, CUPID_ERR_ARGUMENT, "%lld of %lld rows built",
              (long long)rb->nrows_done, (long long)rb->nrows);
  cupid_csr A = NULL;
  CUPID_CALL(cupid_calloc(1, sizeof *A, "coupled matrix", &A));
  A->nrows = rb->nrows;
  A->ncols = rb->ncols;
  A->bs = 3;
  A->rowptr = rb->rowptr;
  A->col = rb->col;
  A->val = rb->val;
  /* Shrink to size (the doubling may have left up to half unused). */
  if (rb->nnz > 0) {
    cupid_status st = cupid_realloc((size_t)rb->nnz, sizeof *A->col, "coupled columns", &A->col);
    if (st == CUPID_SUCCESS)
      st = cupid_realloc((size_t)rb->nnz * 9, sizeof *A->val, "coupled values", &A->val);
    rb->col = A->col;
    rb->val = A->val;
    if (st != CUPID_SUCCESS) {
      cupid_free(&A);
      return st;
    }
  }
  rb->rowptr = NULL;
  rb->col = NULL;
  rb->val = NULL;
  *K = A;
  return CUPID_SUCCESS;
}

void cpl_rowbuild_free(cpl_rowbuild *rb) {
  cupid_free(&rb->slot);
  cupid_free(&rb->cols);
  cupid_free(&rb->vals);
  cupid_free(&rb->rowptr);
  cupid_free(&rb->col);
  cupid_free(&rb->val);
}
