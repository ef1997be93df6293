/* Private helpers of src/dynamics: vectors on the free DOFs and mass products. */
#ifndef CUPID_DYNAMICS_INTERNAL_H
#define CUPID_DYNAMICS_INTERNAL_H

#include "cupid/dynamics.h"

/* Vectors longer than this are swept by OpenMP threads (shorter ones: the start-up costs
 * more than the sweep). */
#define DYN_OMP_MIN 100000

/* 1 if scalar DOF d is fixed. */
static inline int dyn_fixed(const cupid_dirichlet_t *bc, cupid_int d) {
  return bc && bc->fixed[d];
}

/* Whether any DOF is fixed (n_free is set by cupid_dirichlet_finalize; else assume so). */
static inline int dyn_any_fixed(const cupid_dirichlet_t *bc) {
  return bc && !(bc->n_free == bc->n && bc->n > 0);
}

/* y = M x (consistent or lumped), n entries. */
void dyn_mass_apply(const cupid_dynamics_system *sys, cupid_int n, const double *x, double *y);

/* The Lanczos estimate of cupid_dynamics_lambda_max() for a matrix-free K, on one process or
 * over a partition (part may be NULL); *steps (may be NULL): the products it took. */
cupid_status dyn_lambda_max_fn(cupid_dynamics_stiffness_fn apply, void *ctx, cupid_int n,
                               const double *m, const cupid_dirichlet_t *bc,
                               const cupid_dynamics_partition *part, int iterations,
                               double *estimate, int *steps);

/* x . y over all n entries. */
double dyn_dot(cupid_int n, const double *x, const double *y);

#endif
