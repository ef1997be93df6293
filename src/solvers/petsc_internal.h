/* Private to src/solvers: the one error convention of the PETSc code (petsc.c, krylov.c). */
#ifndef CUPID_SOLVERS_PETSC_INTERNAL_H
#define CUPID_SOLVERS_PETSC_INTERNAL_H

#include "cupid/base.h"

/** PETSc's error @p ierr in the call @p what as a cupid status and message (out of memory:
 *  CUPID_ERR_MEMORY; anything else CUPID_ERR_NUMERIC). */
cupid_status cupid_petsc_error(int ierr, const char *what);

/* A PETSc call inside a function with `st` and `cleanup:`: PETSc's message becomes cupid's. */
#define PTRY(expr)                                                                             \
  do {                                                                                         \
    PetscErrorCode ierr_ = (expr);                                                             \
    if (ierr_) {                                                                               \
      st = cupid_petsc_error((int)ierr_, #expr);                                               \
      goto cleanup;                                                                            \
    }                                                                                          \
  } while (0)

#endif
