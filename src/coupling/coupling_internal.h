/* Private to src/coupling: a row-by-row builder of bs = 3 block-CSR matrices (each row's
 * blocks are gathered through a column -> slot marker, then sorted and appended). */
#ifndef CUPID_COUPLING_INTERNAL_H
#define CUPID_COUPLING_INTERNAL_H

#include "cupid/base.h"
#include "cupid/solvers.h"

typedef struct {
  cupid_int ncols;
  cupid_int *slot;    /* ncols: slot of a column in the current row, or -1 */
  cupid_int *cols;    /* current row's columns */
  double *vals;       /* current row's blocks, 9 each */
  cupid_int n, cap;
  cupid_int nrows_done, nrows;
  cupid_int *rowptr;  /* nrows + 1 */
  cupid_int *col;     /* all rows */
  double *val;
  cupid_int nnz, cap_out;
} cpl_rowbuild;

cupid_status cpl_rowbuild_init(cpl_rowbuild *rb, cupid_int nrows, cupid_int ncols);
/** Add s * blk (3x3 row-major) at column c of the current row. */
cupid_status cpl_rowbuild_add(cpl_rowbuild *rb, cupid_int c, double s, const double *blk);
/** Close the current row (a zero diagonal block is added when @p diag >= 0 and absent). */
cupid_status cpl_rowbuild_end_row(cpl_rowbuild *rb, cupid_int diag);
/** Hand the matrix over as *K (the builder's arrays move into it). */
cupid_status cpl_rowbuild_finish(cpl_rowbuild *rb, cupid_csr *K);
void cpl_rowbuild_free(cpl_rowbuild *rb);

#endif
