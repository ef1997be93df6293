/* Dirichlet conditions on scalar DOFs (include/cupid/solvers.h). */
#include <math.h>

#include "cupid/solvers.h"

cupid_status cupid_dirichlet_create(cupid_int n, cupid_dirichlet *bc) {
  CUPID_CHECK(bc != NULL, CUPID_ERR_ARGUMENT, "cupid_dirichlet_create: NULL output");
  *bc = NULL;
  CUPID_CHECK(n >= 0, CUPID_ERR_ARGUMENT, "Dirichlet conditions: negative DOF count %lld",
              (long long)n);
  cupid_status st = CUPID_SUCCESS;
  cupid_dirichlet b = NULL;
  CUPID_TRY(cupid_calloc(1, sizeof *b, "Dirichlet conditions", &b));
  b->n = n;
  CUPID_TRY(cupid_calloc((size_t)n, sizeof *b->fixed, "Dirichlet flags", &b->fixed));
  CUPID_TRY(cupid_calloc((size_t)n, sizeof *b->value, "Dirichlet values", &b->value));
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *b->free_index, "free DOF numbering", &b->free_index));
  /* Nothing fixed yet: already a valid finalized state (every DOF free). */
  for (cupid_int i = 0; i < n; i++) b->free_index[i] = i;
  b->n_free = n;
  *bc = b;
  return CUPID_SUCCESS;
cleanup:
  cupid_dirichlet_destroy(&b);
  return st;
}

cupid_status cupid_dirichlet_fix(cupid_dirichlet bc, cupid_int dof, double value) {
  CUPID_CHECK(bc && dof >= 0 && dof < bc->n, CUPID_ERR_ARGUMENT,
              "Dirichlet condition on DOF %lld outside [0, %lld)", (long long)dof,
              bc ? (long long)bc->n : 0LL);
  bc->fixed[dof] = 1;
  bc->value[dof] = value;
  return CUPID_SUCCESS;
}

/* Free DOFs are numbered in increasing global order, so reduced matrices keep sorted indices. */
cupid_status cupid_dirichlet_finalize(cupid_dirichlet bc) {
  CUPID_CHECK(bc != NULL, CUPID_ERR_ARGUMENT, "cupid_dirichlet_finalize: NULL argument");
  cupid_int k = 0;
  for (cupid_int i = 0; i < bc->n; i++) {
    if (bc->fixed[i]) {
      CUPID_CHECK(isfinite(bc->value[i]), CUPID_ERR_ARGUMENT,
                  "Dirichlet condition on DOF %lld has the non-finite value %g", (long long)i,
                  bc->value[i]);
      bc->free_index[i] = -1;
    } else {
      bc->free_index[i] = k++;
    }
  }
  bc->n_free = k;
  return CUPID_SUCCESS;
}

void cupid_dirichlet_destroy(cupid_dirichlet *bc) {
  if (!bc || !*bc) return;
  cupid_free(&(*bc)->fixed);
  cupid_free(&(*bc)->value);
  cupid_free(&(*bc)->free_index);
  cupid_free(bc);
}
