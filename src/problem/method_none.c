/* Models with one part (method.h, cupid_method_none): a PD grid alone or a beam alone. The
 * constraints and loads go to that part; PD-only 3D static models solve matrix-free on the
 * PETSc engine (the 2-delta LPS matrix is never formed: cupid_petsc_solve_nodes, CG + GAMG, in
 * slabs under mpirun) and PD-only central differences run on the PD operator. */
#include "method.h"

static cupid_status check(const cupid_problem_state *prob) {
  if (prob->model->analysis.type == CUPID_ANALYSIS_DYNAMIC) return cupid_problem_dynamic_check(prob);
  return CUPID_SUCCESS;
}

static cupid_status constraints(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  if (prob->grid) CUPID_CALL(cupid_problem_pd_constraints(prob, m->constraints, m->n_constraints));
  for (int k = 0; k < m->n_constraints && prob->beam; k++) { /* one by one: errors name it */
    CUPID_CALL(cupid_cuf_constraint_apply(prob->beam, m, &m->constraints[k], prob->bc));
    CUPID_CALL(cupid_problem_check_finite(prob, prob->bc->value, &m->constraints[k].mark,
                                          "the prescribed displacement"));
  }
  return CUPID_SUCCESS;
}

static cupid_status loads(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  if (prob->grid) CUPID_CALL(cupid_problem_pd_loads(prob, m->loads, m->n_loads, prob->f_ext));
  for (int k = 0; k < m->n_loads && prob->beam; k++) {
    CUPID_CALL(cupid_cuf_load_add(prob->beam, m, &m->loads[k], prob->f_ext));
    CUPID_CALL(cupid_problem_check_finite(prob, prob->f_ext, &m->loads[k].mark, "the load"));
  }
  return CUPID_SUCCESS;
}

static cupid_status assemble(cupid_problem_state *prob) {
  if (prob->K) return CUPID_SUCCESS;
  double t0 = cupid_wtime();
  if (prob->grid) CUPID_CALL(cupid_pd_operator_assemble(prob->op, &prob->K));
  else CUPID_CALL(cupid_cuf_assemble(prob->beam, &prob->K));
  cupid_problem_phase_end(prob, CUPID_PHASE_ASSEMBLY, t0);
  cupid_problem_progress(prob, "assembly: %lld non-zeros (%.1f MB)", (long long)cupid_csr_nnz(prob->K),
                         (double)cupid_csr_bytes(prob->K) / 1e6);
  return CUPID_SUCCESS;
}

/* PD only: K is the operator's, so its rows are the operator's rows. */
static cupid_status update_rows(cupid_problem_state *prob, const cupid_int *nodes, cupid_int n) {
  CUPID_CHECK(prob->K && prob->grid && !prob->beam, CUPID_ERR_INTERNAL,
              "update_rows: no PD-only K to update");
  cupid_csr R = NULL;
  CUPID_CALL(cupid_pd_operator_assemble_node_rows(prob->op, NULL, nodes, n, &R));
  cupid_status st = CUPID_SUCCESS;
  for (cupid_int k = 0; k < n && st == CUPID_SUCCESS; k++) {
    cupid_csr_zero_row(prob->K, nodes[k]);
    st = cupid_csr_add_row(prob->K, nodes[k], R, k);
  }
  cupid_csr_destroy(&R);
  return st;
}

static int is_pd_3d(const cupid_problem_state *prob) {
  return prob->grid && !prob->beam && cupid_pd_grid_dimension(prob->grid) == 3;
}

static int matrix_free(const cupid_problem_state *prob, const cupid_solver_type *engine) {
  return engine->solve_nodes && is_pd_3d(prob);
}

/* K u = f by CG on the PD operator (PETSc); a slab computes its owned rows, rank 0 gathers. */
static cupid_status solve_matrix_free(cupid_problem_state *prob) {
  cupid_node_operator A;
  cupid_pd_node_operator(prob->op, prob->grid, prob->pd_materials, &A);
  cupid_status st = prob->engine->solve_nodes(&A, prob->f_ext, prob->bc, prob->u, &prob->solve);
  cupid_problem_record_solve(prob);
  CUPID_CALL(st);
  prob->solved = 1;
  cupid_problem_progress(prob, "solve: PETSc matrix-free, %s + %s, %d iterations on %d rank%s, "
                         "%lld equations, residual %.2e", prob->solve.ksp_type, prob->solve.pc_type,
                         prob->solve.iterations, prob->solve.ranks, prob->solve.ranks == 1 ? "" : "s",
                         (long long)prob->solve.n, prob->solve.residual);
  if (!prob->slab) return cupid_pd_operator_apply(prob->op, prob->u, prob->f_int);
  const cupid_int a = prob->part.owned_first, b = prob->part.owned_last;
  CUPID_CALL(cupid_pd_operator_apply_range(prob->op, a, b, prob->u, prob->f_int + 3 * a));
  return cupid_problem_slab_collect(prob);
}

static cupid_status pd_apply(void *op, const double *x, double *y) {
  return cupid_pd_operator_apply(op, x, y);
}

static cupid_status pd_row_bound(void *op, double *r) { return cupid_pd_operator_row_bound(op, r); }

/* PD only: the PD operator (borrowed); a beam alone has none (its K is assembled). */
static cupid_status explicit_operator(cupid_problem_state *prob, cupid_method_operator *op) {
  if (prob->grid && !prob->beam)
    *op = (cupid_method_operator){.apply = pd_apply, .ctx = prob->op, .row_bound = pd_row_bound};
  return CUPID_SUCCESS;
}

static cupid_status mass(cupid_problem_state *prob, cupid_csr *M, double **m_lumped) {
  return cupid_method_plain_mass(prob, 0, M, m_lumped);
}

/* Matrix-free PD: no K, a 19-block bond-based preconditioner matrix (x2.5 with its GAMG
 * hierarchy and PETSc copies), setup + ~32 CG iterations worth 25 operator products at ~1.5e7
 * bonds per second per pass (LPS: two passes). Calibrated on the LPS cubes of docs/scale.md
 * (100^3: 6.3 GB and 439 s measured, 6.0 GB and 435 s estimated). */
static int estimate_matrix_free(const cupid_problem_state *prob, double *bytes, double *seconds,
                                const char **what) {
  if (!is_pd_3d(prob)) return 0;
  double n = (double)prob->n_pd, passes = prob->model->pd.model == CUPID_PD_LPS ? 2.0 : 1.0;
  *bytes = 2.5 * 19.0 * 9.0 * 12.0 * n + 30.0 * (double)prob->ndof * 8.0;
  *seconds = 2.0 + 25.0 * passes * (double)prob->n_bonds / 1.5e7 + 2e-5 * n;
  *what = "matrix-free CG + GAMG";
  return 1;
}

const cupid_method_ops cupid_method_none = {
    .name = "none",
    .caps = CUPID_METHOD_DYNAMIC | CUPID_METHOD_GRID_1D | CUPID_METHOD_SLABS | CUPID_METHOD_FRACTURE,
    .matrix = CUPID_MATRIX_SPD,
    .check = check,
    .constraints = constraints,
    .loads = loads,
    .assemble = assemble,
    .update_rows = update_rows,
    .matrix_free = matrix_free,
    .solve_matrix_free = solve_matrix_free,
    .explicit_operator = explicit_operator,
    .mass = mass,
    .estimate_matrix_free = estimate_matrix_free,
};
