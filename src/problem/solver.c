/* The solver engine of a problem (issue 6): which engine (requested, or auto from the
 * estimates of estimate.c), and the linear solves through it, with a breakdown named at its
 * node. Below the stages (growth, the methods' solves) and above the estimates. */
#include <stdio.h>

#include "method.h"

/* ------------------------------------------------------------- the solver engine (issue 6)
 * The command line wins over the model file. auto: the direct engine while its estimated peak
 * memory stays below a quarter of the memory limit and its factorisation below two minutes,
 * PETSc above (when cupid was built with it): Krylov + AMG costs O(n) memory where the factor
 * grows like n^(4/3) (docs/scale.md). */

static cupid_solver_kind requested_solver(const cupid_problem_state *prob) {
  return prob->opts->solver >= 0 ? (cupid_solver_kind)prob->opts->solver
                                 : prob->model->analysis.solver;
}

/* Only static solves go through PETSc: refuse an explicit request elsewhere. */
cupid_status cupid_problem_check_engine_request(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  const cupid_solver_type *e = cupid_solver_type_get(requested_solver(prob));
  if (!e || !e->iterative) return CUPID_SUCCESS;
  if (!e->available())
    return CUPID_ERROR(CUPID_ERR_UNSUPPORTED,
                       "solver %s: this build of cupid has no PETSc engine: rebuild with "
                       "scripts/build.sh --with-petsc, or use 'direct' or 'auto'", e->name);
  if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC)
    return cupid_model_error(m, &m->analysis.mark,
                             "solver %s serves static analyses; type dynamic uses its own "
                             "integrators (use solver auto or direct)", e->name);
  return CUPID_SUCCESS;
}

static cupid_status use_engine(cupid_problem_state *prob, const cupid_solver_type *e) {
  prob->engine = e;
  prob->solver = (cupid_solver_kind)e->kind;
  return e->start();
}

/* The first engine this build has that solves over MPI ranks (NULL: none). */
static const cupid_solver_type *distributed_engine(void) {
  for (int k = 0; cupid_solver_type_at(k); k++)
    if (cupid_solver_type_at(k)->distributed && cupid_solver_type_at(k)->available())
      return cupid_solver_type_at(k);
  return NULL;
}

static cupid_status choose_automatically(cupid_problem_state *prob) {
  const cupid_solver_type *e = NULL;
  CUPID_CALL(cupid_problem_auto_engine(prob, &e, prob->solver_reason, sizeof prob->solver_reason));
  return use_engine(prob, e);
}

/* The chosen engine's estimate, for summary.json and bench/estimates.sh (static only). */
static cupid_status record_estimate(cupid_problem_state *prob) {
  if (prob->model->analysis.type != CUPID_ANALYSIS_STATIC || prob->slab) return CUPID_SUCCESS;
  cupid_solver_cost factor, krylov;
  CUPID_CALL(cupid_problem_costs(prob, &factor, &krylov));
  prob->estimate = *cupid_problem_path_cost(prob, prob->engine, &factor, &krylov);
  return CUPID_SUCCESS;
}

static cupid_status choose_engine(cupid_problem_state *prob) {
  cupid_solver_kind req = requested_solver(prob);
  if (prob->slab) { /* only a distributed engine runs on slabs (slab.c) */
    snprintf(prob->solver_reason, sizeof prob->solver_reason,
             "%s: %d MPI ranks, each holding one z slab of the PD grid",
             req == CUPID_SOLVER_AUTO ? "auto" : "requested", prob->part.parts);
    return use_engine(prob, distributed_engine());
  }
  if (req != CUPID_SOLVER_AUTO) {
    snprintf(prob->solver_reason, sizeof prob->solver_reason, "requested");
    return use_engine(prob, cupid_solver_type_get(req));
  }
  return choose_automatically(prob);
}

cupid_status cupid_problem_choose_solver(cupid_problem_state *prob) {
  CUPID_CALL(choose_engine(prob));
  return record_estimate(prob);
}

/* Name the node (PD) or beam node and expansion term (FE) where a factorisation broke
 * down (exit status 2). */
static cupid_status explain_singular(const cupid_problem_state *prob, cupid_status st) {
  cupid_int dof = prob->solve.failed_dof;
  if (dof < 0 || dof >= prob->ndof) return st;
  char msg[1024];
  snprintf(msg, sizeof msg, "%s", cupid_error_message());
  char comp = "xyz"[dof % 3];
  if (!prob->beam || dof < prob->fe_offset) {
    const double *x = cupid_pd_grid_coords(prob->grid);
    cupid_int node = dof / 3;
    return CUPID_ERROR(st,
                       "%s; PD node %lld at (%g, %g, %g), component %c: check that every PD "
                       "region is constrained against rigid motion (fix, clamp or displacement)",
                       msg, (long long)node, x[3 * node], x[3 * node + 1], x[3 * node + 2], comp);
  }
  cupid_int fe_node = (dof - prob->fe_offset) / 3, M = prob->fe_info.M;
  cupid_int beam_node = fe_node / M;
  return CUPID_ERROR(st,
                     "%s; beam node %lld at y = %g, expansion term %lld, component %c: check "
                     "that the beam is clamped or fixed against rigid motion",
                     msg, (long long)beam_node, cupid_cuf_beam_node_y(prob->beam, beam_node),
                     (long long)(fe_node % M), comp);
}

cupid_status cupid_problem_linear_solve(cupid_problem_state *prob, cupid_matrix_kind kind) {
  /* Coordinates give GAMG the rigid-body modes when every DOF is a PD node's. */
  cupid_petsc_options hints = {0};
  if (prob->grid && !prob->beam) {
    hints.coords = cupid_pd_grid_coords(prob->grid);
    hints.n_coord_nodes = prob->n_pd;
  }
  cupid_status st = prob->engine->solve_matrix(prob->K, kind, prob->f_ext, prob->bc, prob->u,
                                               &hints, &prob->solve);
  cupid_problem_record_solve(prob);
  if (st == CUPID_ERR_NUMERIC) return explain_singular(prob, st);
  CUPID_CALL(st);
  if (prob->engine->iterative)
    cupid_problem_progress(prob, "PETSc: %s + %s, %d iterations on %d rank%s, %s",
                           prob->solve.ksp_type, prob->solve.pc_type, prob->solve.iterations,
                           prob->solve.ranks, prob->solve.ranks == 1 ? "" : "s",
                           prob->solve.converged_reason);
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_assembled_solve(cupid_problem_state *prob) {
  CUPID_CALL(cupid_problem_patch_test_assembled(prob));
  CUPID_CALL(cupid_problem_linear_solve(prob, prob->method->matrix));
  prob->solved = 1;
  if (prob->method->recover) prob->method->recover(prob, prob->u);
  cupid_csr_matvec(prob->K, prob->u, prob->f_int);
  cupid_problem_progress(prob, "solve: %s, %lld equations, residual %.2e", prob->solve.method,
                         (long long)prob->solve.n, prob->solve.residual);
  return CUPID_SUCCESS;
}
