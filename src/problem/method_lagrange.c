/* Coupling by Lagrange multipliers, eliminated (src/coupling/lagrange.c): the beam gives way
 * inside the PD regions and the PD nodes of each interface layer follow the beam field
 * (u_tied = T u_FE). The tied nodes are eliminated from the system (fixed in it, recovered
 * from the beam after the solve), so the system T^T K T is symmetric positive definite
 * (CHOLMOD). Any grid dimension (a 1D grid is a bar along the axis), statics and dynamics
 * (the tied nodes' mass moves onto the beam through the tie). */
#include <math.h>
#include <stdio.h>

#include "method.h"

static cupid_status check(const cupid_problem_state *prob) {
  if (prob->model->analysis.type == CUPID_ANALYSIS_DYNAMIC) return cupid_problem_dynamic_check(prob);
  return CUPID_SUCCESS;
}

/* The tie and the eliminated K are built first: the constraints hold the tied nodes and the
 * loads on them act through the tie. K_PD is assembled from prob->op itself, so that its
 * pre-cracks and broken bonds are K's; crack growth assembles again after breaks (the tie,
 * geometry alone, comes out the same). */
static cupid_status assemble(cupid_problem_state *prob) {
  if (prob->K) return CUPID_SUCCESS;
  cupid_coupling_info ci = {0};
  if (prob->coupling) { /* the tie and the beam's K kept (fracture_protect's build, or the last
                           assembly before breaks): K_PD from prob->op again */
    double t0 = cupid_wtime();
    CUPID_CALL(cupid_coupling_lagrange_update(prob->coupling, prob->op, &prob->K));
    cupid_problem_phase_end(prob, CUPID_PHASE_COUPLING, t0);
    cupid_coupling_get_info(prob->coupling, &ci);
  } else {
    CUPID_CALL(cupid_method_build_coupling(prob, cupid_coupling_lagrange_create, &ci));
  }
  const cupid_int *tied;
  cupid_int nt;
  cupid_coupling_tied(prob->coupling, &tied, &nt);
  /* growth runs its re-solves quiet: this reports the first assembly only */
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

/* The coupling zone, whose bonds never break: the tied nodes (they follow the beam) and every
 * node within a horizon of one (its family reaches the tie, where the PD families are cut
 * short by the interface). A crack that comes there stops the run (growth.c, check_blocked).
 * The tie is built here for its nodes and kept; its K, assembled before the pre-cracks are
 * cut, is dropped, and assemble() makes K from the cut operator on the kept tie. */
static cupid_status fracture_protect(const cupid_problem_state *prob, unsigned char *protect) {
  cupid_problem_state *p = (cupid_problem_state *)prob; /* the tie is the problem's */
  cupid_coupling_info ci;
  if (!p->coupling) CUPID_CALL(cupid_method_build_coupling(p, cupid_coupling_lagrange_create, &ci));
  cupid_csr_destroy(&p->K);
  const cupid_int *tied = NULL;
  cupid_int nt = 0;
  cupid_coupling_tied(p->coupling, &tied, &nt);
  /* the lattice points within the horizon of each tied node (the grid is a lattice) */
  const cupid_pd_grid g = prob->grid;
  const double h = cupid_pd_grid_spacing(g), m = prob->model->pd.horizon / h;
  const cupid_int reach = (cupid_int)floor(m + 1e-9), d1 = cupid_pd_grid_dimension(g) == 1;
  for (cupid_int t = 0; t < nt; t++) {
    cupid_int q[3];
    cupid_pd_grid_node_lattice(g, tied[t], q);
    for (cupid_int a = d1 ? 0 : -reach; a <= (d1 ? 0 : reach); a++)
      for (cupid_int b = -reach; b <= reach; b++)
        for (cupid_int e = d1 ? 0 : -reach; e <= (d1 ? 0 : reach); e++) {
          if ((double)(a * a + b * b + e * e) > m * m * (1.0 + 1e-9)) continue;
          const cupid_int i = cupid_pd_grid_node_at(g, q[0] + a, q[1] + b, q[2] + e);
          if (i >= 0) protect[i] = 1;
        }
  }
  return CUPID_SUCCESS;
}

/* The stop message's name of the zone at x. */
static void protected_zone(const cupid_problem_state *prob, const double x[3], char *buf, size_t len) {
  (void)prob;
  snprintf(buf, len, "the Lagrange tie (the tied PD nodes and those within a horizon of them, "
           "near (%g, %g, %g))", x[0], x[1], x[2]);
}

const cupid_method_ops cupid_method_lagrange = {
    .name = "lagrange",
    .caps = CUPID_METHOD_DYNAMIC | CUPID_METHOD_GRID_1D | CUPID_METHOD_CONDITIONS_ASSEMBLE |
            CUPID_METHOD_FRACTURE,
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
    .fracture_protect = fracture_protect,
    .protected_zone = protected_zone,
};
