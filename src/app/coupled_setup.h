/* Private to src/app and bench/: a fictitious-node coupled model set up to its linear system
 * without assembling anything that scales with the PD stiffness (for the matrix-free solve of
 * include/cupid/coupling.h, issue 6). */
#ifndef CUPID_APP_COUPLED_SETUP_H
#define CUPID_APP_COUPLED_SETUP_H

#include "app_internal.h"

typedef struct {
  cupid_job job;               /**< grid, pd_options, beam (deactivated), u, f_ext, bc */
  cupid_coupling_options co;   /**< the coupling's options (points into the arrays below) */
  cupid_box *boxes;
  int *mats;
} cupid_coupled_setup;

/**
 * Read nothing, solve nothing: for a coupled model (method fictitious, type static) build the
 * PD grid (no operator on it), the beam with the regions removed, the fields and the Dirichlet
 * conditions (finalized) and the loads, as `cupid run` does (coupled.c), and the coupling
 * options. Other models: CUPID_ERR_UNSUPPORTED. @p s is zeroed first; free with
 * cupid_app_coupled_setup_free() (also after a failure).
 */
cupid_status cupid_app_coupled_setup(const cupid_model_t *model, const cupid_run_options *opts,
                                     cupid_coupled_setup *s);
void cupid_app_coupled_setup_free(cupid_coupled_setup *s);

/**
 * The fictitious-node static solve without the PD matrix, for `--solver petsc`: on a job set up
 * as coupled.c does up to its loads (beam deactivated, bc finalized, f_ext filled; no
 * assemble()), build the matrix-free operator (cupid_coupling_operator_create()) and the cheap
 * preconditioner matrix, solve by GMRES (cupid_coupling_krylov_solve(), @p ko may be NULL) and
 * fill job->u, job->f_int (= A u), job->n_fictitious, job->solve (method "petsc", matrix_free 1, ksp_type gmres, n,
 * residual, times), the coupling / factorisation / solve phases and job->solved. job->K stays
 * NULL. Builds without PETSc: CUPID_ERR_UNSUPPORTED.
 */
cupid_status cupid_app_coupled_solve_mf(cupid_job *job, const cupid_coupling_options *co,
                                        const cupid_coupling_krylov_options *ko);

/** Solve the job's system K u = f_ext with its conditions by cupid_krylov_solve() on the
 *  matrix-free @p L, preconditioned by @p P, and record it: job->u, job->f_int (= K u),
 *  job->solve (method "petsc", matrix_free 1, ksp and pc types, n, residual, iterations,
 *  times), the factorisation / solve phases and job->solved. */
cupid_status cupid_app_krylov_solve(cupid_job *job, const cupid_linear_operator *L,
                                    const cupid_csr_t *P, const cupid_coupling_krylov_options *ko);

#endif
