/* Coupling by Lagrange multipliers, eliminated (src/coupling/lagrange.c): the beam gives way
 * inside the PD regions and the PD nodes of each interface layer follow the beam field
 * (u_tied = T u_FE). The tied nodes are eliminated from the system (fixed in it, recovered
 * from the beam after the solve), so the system T^T K T is symmetric positive definite
 * (CHOLMOD). Any grid dimension (a 1D grid is a bar along the axis), statics and dynamics
 * (the tied nodes' mass moves onto the beam through the tie). */
#include "method.h"

static cupid_status check(const cupid_problem_state *prob) {
  if (prob->model->analysis.type == CUPID_ANALYSIS_DYNAMIC) return cupid_problem_dynamic_check(prob);
  return CUPID_SUCCESS;
}

/* The tie and the eliminated K are built first: the constraints hold the tied nodes and the
 * loads on them act through the tie. */
static cupid_status assemble(cupid_problem_state *prob) {
  if (prob->K) return CUPID_SUCCESS;
  cupid_coupling_info ci;
  CUPID_CALL(cupid_method_build_coupling(prob, cupid_coupling_lagrange_create, &ci));
  const cupid_int *tied;
  cupid_int nt;
  cupid_coupling_tied(prob->coupling, &tied, &nt);
  cupid_problem_progress(prob, "coupling (Lagrange multipliers, eliminated): %d interfaces, %lld "
                         "tied PD nodes; %lld non-zeros (%.1f MB)", ci.n_interfaces, (long long)nt,
                         (long long)cupid_csr_nnz(prob->K), (double)cupid_csr_bytes(prob->K) / 1e6);
  return CUPID_SUCCESS;
}

static cupid_status constraints(cupid_problem_state *prob) {
  CUPID_CALL(cupid_problem_estimate(prob, 0)); /* before anything scales with the stiffness */
  CUPID_CALL(assemble(prob));
  CUPID_CALL(cupid_method_split_constraints(prob, NULL));
  const cupid_int *tied; /* they follow the beam: eliminated, recovered after the solve */
  cupid_int nt;
  cupid_coupling_tied(prob->coupling, &tied, &nt);
  for (cupid_int t = 0; t < nt; t++)
    for (int c = 0; c < 3; c++) CUPID_CALL(cupid_dirichlet_fix(prob->bc, 3 * tied[t] + c, 0.0));
  return CUPID_SUCCESS;
}

/* A load on a tied PD node acts on the beam through the tie (T^T f). */
static cupid_status loads(cupid_problem_state *prob) {
  CUPID_CALL(cupid_method_split_loads(prob));
  cupid_coupling_lagrange_load(prob->coupling, prob->f_ext);
  return CUPID_SUCCESS;
}

static int never(const cupid_problem_state *prob, const cupid_solver_type *engine) {
  (void)prob, (void)engine;
  return 0;
}

static cupid_status mass(cupid_problem_state *prob, cupid_csr *M, double **m_lumped) {
  return cupid_method_plain_mass(prob, 1, M, m_lumped);
}

static void recover(const cupid_problem_state *prob, double *u) {
  cupid_coupling_recover(prob->coupling, u);
}

const cupid_method_ops cupid_method_lagrange = {
    .name = "lagrange",
    .caps = CUPID_METHOD_DYNAMIC | CUPID_METHOD_GRID_1D | CUPID_METHOD_CONDITIONS_ASSEMBLE,
    .matrix = CUPID_MATRIX_SPD,
    .check = check,
    .prepare = cupid_method_deactivate_regions,
    .constraints = constraints,
    .loads = loads,
    .assemble = assemble,
    .matrix_free = never,
    .mass = mass,
    .recover = recover,
    .report = cupid_method_print_equilibrium,
};
