/* Coupling by fictitious nodes (paper 000 section 4; src/coupling/fictitious.c): the beam gives
 * way inside the PD regions, constraints and loads go to the part they touch, and the coupled
 * matrix of Eq. 38 is solved by UMFPACK (it is not symmetric), or without the PD matrix by the
 * PETSc engine: GMRES preconditioned by the LU of a cheap bond-based twin (src/coupling/
 * operator.c, solvers/krylov.c; issue 6), on one rank or several (the PD grid in z slabs). */
#include "method.h"

static cupid_status check(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  /* the fictitious nodes and elements need a 3D grid */
  if (m->pd.dimension != 3)
    return cupid_model_error(m, &m->pd.mark,
                             "a coupled model needs a 3D peridynamic grid (dimension: 3) with "
                             "method fictitious (1D grids: methods lagrange and arlequin)");
  if (m->coupling.balance && m->analysis.type == CUPID_ANALYSIS_DYNAMIC)
    return cupid_model_error(m, &m->coupling.mark,
                             "balance: momentum runs static solves (load steps too) and type "
                             "evaluate, not type dynamic; use balance: none there");
  if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC)
    return cupid_model_error(m, &m->analysis.mark,
                             "type dynamic is not supported with coupling method fictitious: its "
                             "coupled operator (paper 000 Eq. 38) is a static, non-symmetric "
                             "construction with massless fictitious nodes (see docs/dynamics.md); "
                             "use `coupling: {method: lagrange}` or `{method: arlequin}` for "
                             "coupled dynamics, or type static or evaluate");
  return CUPID_SUCCESS;
}

static cupid_status constraints(cupid_problem_state *prob) {
  return cupid_method_split_constraints(prob, NULL);
}

static cupid_status assemble(cupid_problem_state *prob) {
  if (prob->K) return CUPID_SUCCESS;
  cupid_coupling_info ci;
  CUPID_CALL(cupid_method_build_coupling(prob, cupid_coupling_create, &ci));
  prob->n_fictitious = ci.n_fictitious_pd;
  cupid_problem_progress(prob,
                         "coupling (fictitious nodes): %d interfaces, %lld fictitious PD nodes, "
                         "%lld fictitious FE nodes; %lld non-zeros (%.1f MB)",
                         ci.n_interfaces, (long long)ci.n_fictitious_pd,
                         (long long)ci.n_fictitious_fe, (long long)cupid_csr_nnz(prob->K),
                         (double)cupid_csr_bytes(prob->K) / 1e6);
  return CUPID_SUCCESS;
}

/* `balance: momentum`: K' = K - W C^T by the factor of K_ff and six more solves (balance.c);
 * else the engine's solve of Eq. 38. */
static cupid_status solve_assembled(cupid_problem_state *prob) {
  if (!cupid_problem_balanced(prob)) return cupid_problem_assembled_solve(prob);
  /* the balanced solve reuses a SuiteSparse factor; an iterative engine's assembled path
   * (--assembled) has none, and silently factoring instead would not be what was asked */
  CUPID_CHECK(!prob->engine->iterative, CUPID_ERR_UNSUPPORTED,
              "coupling.balance: momentum runs on the direct solver or the matrix-free path of "
              "solver %s, not on its assembled path (--assembled)", prob->engine->name);
  return cupid_problem_balanced_direct_solve(prob);
}

/* An iterative engine (krylov, petsc), static, 3D: matrix-free unless --assembled asks for
 * Eq. 38 assembled (PETSc: its rows split over the ranks, GMRES + block Jacobi/ILU). */
static int matrix_free(const cupid_problem_state *prob, const cupid_solver_type *engine) {
  return engine->solve_operator && !prob->opts->assembled && prob->grid &&
         cupid_pd_grid_dimension(prob->grid) == 3;
}

static void destroy_operator(void **ctx) {
  cupid_coupling_operator A = *ctx;
  cupid_coupling_operator_destroy(&A);
  *ctx = NULL;
}

static cupid_status solve_matrix_free(cupid_problem_state *prob) {
  cupid_status st = CUPID_SUCCESS;
  cupid_box *boxes = NULL;
  int *mats = NULL;
  cupid_coupling_options co;
  cupid_coupling_operator A = NULL;
  cupid_coupling_balance B = NULL;
  cupid_csr P = NULL;
  double t0 = cupid_wtime();
  CUPID_TRY(cupid_method_coupling_options(prob, &co, &boxes, &mats));
  /* a slab: every rank's failure stops all of them before the next collective call */
  st = cupid_coupling_operator_create(prob->beam, prob->grid, &co, &A);
  if (st == CUPID_SUCCESS) st = cupid_coupling_preconditioner(A, 1.5, &P);
  CUPID_TRY(prob->slab ? cupid_problem_slab_agree(st) : st);
  cupid_coupling_info ci; /* the whole model's, on a slab too */
  cupid_coupling_operator_get_info(A, &ci);
  prob->n_fictitious = ci.n_fictitious_pd;
  cupid_problem_phase_end(prob, CUPID_PHASE_COUPLING, t0);
  cupid_problem_progress(prob,
                         "coupling (fictitious nodes, matrix-free): %d interfaces, %lld fictitious "
                         "PD nodes, %lld fictitious FE nodes; operator %.1f MB, preconditioner "
                         "matrix %.1f MB%s",
                         ci.n_interfaces, (long long)ci.n_fictitious_pd, (long long)ci.n_fictitious_fe,
                         (double)cupid_coupling_operator_bytes(A) / 1e6,
                         (double)cupid_csr_bytes(P) / 1e6, prob->slab ? " (rank 0's slab)" : "");
  cupid_linear_operator L;
  cupid_coupling_operator_linear(A, &L); /* on a slab: its rows (cupid_krylov_solve) */
  if (cupid_problem_balanced(prob)) /* K' = K - W C^T around L (P stays K's twin) */
    CUPID_TRY(cupid_problem_balanced_operator(prob, A, &L, &B, &L));
  cupid_method_operator owner = {.ctx = A, .destroy = destroy_operator};
  st = cupid_method_krylov_solve(prob, &L, &P, &owner);
  A = owner.ctx; /* NULL once a slab freed it */
cleanup:
  cupid_coupling_balance_destroy(&B);
  cupid_csr_destroy(&P);
  cupid_coupling_operator_destroy(&A);
  cupid_free(&boxes);
  cupid_free(&mats);
  return st;
}

/* Matrix-free Eq. 38 + LU of the cheap twin. Memory: ~1.6 kB a PD node for the operator and
 * the cheap matrix, ~40 kB for its factor (MUMPS on cbeam_web200, 10^5 PD nodes: 4.3 GB,
 * bench/README_coupled.md; UMFPACK, solver krylov: 0.16 GB for the 4,000 nodes of the coupled
 * bar). Time: ~25 operator products at ~1.5e7 bonds a second a pass (LPS: two passes; GMRES
 * took 23-32 iterations on the bar, the C-beam and the panel) and the twin's factor, ~2e-4 s a
 * PD node (measured 0.7-2.3 s on those three, loaded 2-core machine). */
static int estimate_matrix_free(const cupid_problem_state *prob, double *bytes, double *seconds,
                                const char **what) {
  if (prob->model->analysis.type != CUPID_ANALYSIS_STATIC || !prob->grid ||
      cupid_pd_grid_dimension(prob->grid) != 3)
    return 0;
  const double passes = prob->model->pd.model == CUPID_PD_LPS ? 2.0 : 1.0;
  *bytes = 42e3 * (double)prob->n_pd + 30.0 * (double)prob->ndof * 8.0;
  *seconds = 1.0 + 25.0 * passes * (double)prob->n_bonds / 1.5e7 + 2e-4 * (double)prob->n_pd;
  *what = "matrix-free GMRES + LU of a bond-based twin";
  return 1;
}

const cupid_method_ops cupid_method_fictitious = {
    .name = "fictitious",
    .caps = CUPID_METHOD_SLABS | CUPID_METHOD_GUARD_MATRIX_FREE,
    .matrix = CUPID_MATRIX_GENERAL, /* Eq. 38 is not symmetric: UMFPACK, GMRES */
    .check = check,
    .prepare = cupid_method_deactivate_regions,
    .constraints = constraints,
    .loads = cupid_method_split_loads,
    .assemble = assemble,
    .solve_assembled = solve_assembled,
    .matrix_free = matrix_free,
    .solve_matrix_free = solve_matrix_free,
    .report = cupid_method_print_equilibrium,
    .estimate_matrix_free = estimate_matrix_free,
};
