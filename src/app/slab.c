/* Distributed PD-only runs (issue 6): under `mpirun -n N` a static 3D PD model solved by PETSc
 * is split into N slabs of z layers. Each rank builds only its slab and the halo its rows read
 * (cupid_pd_grid_create_part_from_model, cupid_pd_operator_halo_layers), applies constraints
 * and loads to it, and solves its rows matrix-free (cupid_petsc_solve_pd). Afterwards each rank
 * sends the fields of its owned nodes to rank 0, which rebuilds the whole grid (coordinates
 * only, no operator) to write the outputs as in a one-process run.
 *
 * Every decision that can fail is agreed over the ranks before the next collective call, so
 * an error on one rank stops all of them (the lowest failing rank prints it, cli.c). */
#include <stdio.h>

#include "app_internal.h"

int cupid_app_slab_wanted(const cupid_job *job) {
  const cupid_model_t *m = job->model;
  cupid_solver_kind req = job->opts->solver >= 0 ? (cupid_solver_kind)job->opts->solver
                                                 : m->analysis.solver;
  /* coupled: the matrix-free solves, Arlequin (coupled_arlequin.c) and fictitious nodes
   * (coupled.c); Lagrange multipliers and the assembled paths keep the replicated model */
  int coupled_mf = m->has_beam && m->coupling.method != CUPID_COUPLING_LAGRANGE &&
                   !cupid_petsc_has_option("-cupid_coupled_assembled");
  if (cupid_petsc_has_option("-cupid_replicate")) return 0; /* every rank the whole model */
  return cupid_petsc_size() > 1 && !job->opts->check_only && m->has_peridynamics &&
         (!m->has_beam || coupled_mf) && m->pd.dimension == 3 &&
         m->analysis.type == CUPID_ANALYSIS_STATIC && req != CUPID_SOLVER_DIRECT;
}

int cupid_app_pd_owned(const cupid_job *job, cupid_int node) {
  return !job->slab || (node >= job->part.owned_first && node < job->part.owned_last);
}

cupid_int cupid_app_global_count(const cupid_job *job, cupid_int count) {
  if (!job->slab) return count;
  double c = (double)count;
  cupid_petsc_sum_doubles(&c, 1);
  return (cupid_int)c;
}

cupid_status cupid_app_slab_agree(cupid_status st) {
  if (!cupid_petsc_max_int(st != CUPID_SUCCESS)) return CUPID_SUCCESS;
  if (st != CUPID_SUCCESS) return st;
  return CUPID_ERROR(CUPID_ERR_MODEL, "another MPI rank reported an error");
}

/* Output points and lines are checked against the whole grid: rank 0 builds it for the check
 * (coordinates only, freed at once), before anything expensive. */
cupid_status cupid_app_slab_check_points(cupid_job *job) {
  cupid_status st = CUPID_SUCCESS;
  if (cupid_petsc_rank() == 0) {
    cupid_pd_grid slab = job->grid, whole = NULL;
    st = cupid_pd_grid_create_from_model(job->model, &whole);
    if (st == CUPID_SUCCESS) {
      job->grid = whole;
      st = cupid_app_check_points(job);
      job->grid = slab;
    }
    cupid_pd_grid_destroy(&whole);
  }
  return cupid_app_slab_agree(st);
}

/* Gather n_per_node values of every owned node of every rank on rank 0 (into *whole, which
 * rank 0 allocates for the global nodes). A 3-per-node field of a coupled model also takes
 * the FE DOFs, the same on every rank (rank 0's copy), after the global nodes' DOFs. */
static cupid_status gather_nodes(const cupid_job *job, const double *local, int n_per_node,
                                 double **whole) {
  const cupid_int first = job->part.owned_first, owned = job->part.owned_last - first;
  const cupid_int pd = n_per_node * job->part.global_nodes, fe = n_per_node == 3 ? job->n_fe_dofs : 0;
  cupid_status st = CUPID_SUCCESS;
  if (cupid_petsc_rank() == 0)
    st = cupid_calloc((size_t)(pd + fe) + 1, sizeof **whole, "gathered PD fields", whole);
  CUPID_CALL(cupid_app_slab_agree(st));
  if (cupid_petsc_rank() == 0)
    for (cupid_int d = 0; d < fe; d++) (*whole)[pd + d] = local[job->fe_offset + d];
  return cupid_petsc_gather_root(local + (size_t)n_per_node * (size_t)first, n_per_node * owned,
                                 *whole);
}

/* The Dirichlet flags and values as doubles (MPI moves one type here). */
static cupid_status bc_as_doubles(const cupid_job *job, double **flags, double **values) {
  const cupid_int nd = job->ndof;
  CUPID_CALL(cupid_malloc((size_t)nd, sizeof **flags, "constraint flags", flags));
  CUPID_CALL(cupid_malloc((size_t)nd, sizeof **values, "constraint values", values));
  for (cupid_int d = 0; d < nd; d++) {
    (*flags)[d] = job->bc->fixed[d];
    (*values)[d] = job->bc->value[d];
  }
  return CUPID_SUCCESS;
}

/* Rank 0 becomes a whole-grid job: the whole grid (no operator), the gathered fields (and
 * the beam, for a coupled model). */
static cupid_status become_whole(cupid_job *job, double *g[6]) {
  double *u = g[0], *f_ext = g[1], *f_int = g[2], *flags = g[3], *values = g[4], *stress = g[5];
  cupid_pd_operator_destroy(&job->op);
  cupid_pd_grid_destroy(&job->grid);
  CUPID_CALL(cupid_pd_grid_create_from_model(job->model, &job->grid));
  job->n_pd = cupid_pd_grid_num_nodes(job->grid);
  job->fe_offset = 3 * job->n_pd;
  job->ndof = job->fe_offset + job->n_fe_dofs;
  if (job->beam) { /* the beam's DOFs follow the whole grid's now */
    CUPID_CALL(cupid_cuf_set_dof_offset(job->beam, job->fe_offset));
    cupid_cuf_get_info(job->beam, &job->fe_info);
  }
  cupid_dirichlet_destroy(&job->bc);
  CUPID_CALL(cupid_dirichlet_create(job->ndof, &job->bc));
  for (cupid_int d = 0; d < job->ndof; d++) {
    job->bc->fixed[d] = flags[d] != 0.0;
    job->bc->value[d] = values[d];
  }
  CUPID_CALL(cupid_dirichlet_finalize(job->bc));
  cupid_free(&job->u);
  cupid_free(&job->f_ext);
  cupid_free(&job->f_int);
  cupid_free(&job->pd_stress);
  job->u = u, job->f_ext = f_ext, job->f_int = f_int, job->pd_stress = stress;
  g[0] = g[1] = g[2] = g[5] = NULL; /* now the job's */
  return CUPID_SUCCESS;
}

cupid_status cupid_app_slab_collect(cupid_job *job) {
  cupid_status st = CUPID_SUCCESS;
  double *g[6] = {NULL, NULL, NULL, NULL, NULL, NULL}, *flags = NULL, *values = NULL;
  /* Bonds and slab sizes for the summary, summed and maximised over the ranks. */
  double sums[2] = {(double)cupid_pd_operator_num_bonds_range(job->op, job->part.owned_first,
                                                               job->part.owned_last), 0.0};
  cupid_petsc_sum_doubles(sums, 1);
  job->n_bonds = (cupid_int)sums[0];
  job->slab_ranks = job->part.parts;
  job->slab_nodes_max = cupid_petsc_max_int((int)job->n_pd);
  if (cupid_app_needs_stress(job)) {
    st = cupid_calloc((size_t)(6 * job->n_pd), sizeof(double), "PD stresses", &job->pd_stress);
    if (st == CUPID_SUCCESS) st = cupid_pd_operator_stress(job->op, job->u, job->pd_stress);
    CUPID_TRY(cupid_app_slab_agree(st));
  }
  CUPID_TRY(cupid_app_slab_agree(bc_as_doubles(job, &flags, &values)));
  CUPID_TRY(gather_nodes(job, job->u, 3, &g[0]));
  CUPID_TRY(gather_nodes(job, job->f_ext, 3, &g[1]));
  CUPID_TRY(gather_nodes(job, job->f_int, 3, &g[2]));
  CUPID_TRY(gather_nodes(job, flags, 3, &g[3]));
  CUPID_TRY(gather_nodes(job, values, 3, &g[4]));
  if (job->pd_stress) CUPID_TRY(gather_nodes(job, job->pd_stress, 6, &g[5]));
  if (cupid_petsc_rank() == 0) {
    CUPID_TRY(become_whole(job, g));
    job->slab = 0; /* rank 0 now holds the whole model; the others stop here */
  }
cleanup:
  for (int k = 0; k < 6; k++) cupid_free(&g[k]);
  cupid_free(&flags);
  cupid_free(&values);
  return st;
}
