/* Distributed PD-only runs (issue 6): under `mpirun -n N` a static 3D PD model solved by PETSc
 * is split into N slabs of z layers. Each rank builds only its slab and the halo its rows read
 * (cupid_pd_grid_create_part_from_model, cupid_pd_operator_halo_layers), applies constraints
 * and loads to it, and solves its rows matrix-free (cupid_petsc_solve_nodes). Afterwards each rank
 * sends the fields of its owned nodes to rank 0, which rebuilds the whole grid (coordinates
 * only, no operator) to write the outputs as in a one-process run.
 *
 * Every decision that can fail is agreed over the ranks before the next collective call, so
 * an error on one rank stops all of them (the lowest failing rank prints it, cli.c). */
#include <math.h>
#include <stdio.h>

#include "method.h"

int cupid_problem_slab_wanted(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  /* auto, or an engine that solves over the ranks */
  const cupid_solver_type *engine = cupid_solver_type_get(
      prob->opts->solver >= 0 ? prob->opts->solver : (int)m->analysis.solver);
  /* the methods whose matrix-free solve runs on slabs (PD only, fictitious nodes, Arlequin);
   * Lagrange multipliers and the assembled paths (--assembled) keep the replicated model, and
   * --replicate keeps the whole model on every rank */
  int slabs = (prob->method->caps & CUPID_METHOD_SLABS) && !(m->has_beam && prob->opts->assembled);
  const cupid_analysis *a = &m->analysis;
  /* static: the matrix-free solve of a distributed engine; load steps and crack growth too
   * (growth_matrix_free.c: a kept solve re-run as bonds break) on a PD-only model and with a
   * method that keeps its operator (growth_operator: Arlequin), while the others' growth
   * assembles K on the replicated model; dynamic: central differences on a PD-only model, each
   * rank stepping its slab with the stencil operator and a halo exchange a step */
  const int growth = a->steps > 0 || m->pd.fracture.has_fracture;
  const int solve = a->type == CUPID_ANALYSIS_STATIC &&
                    (!growth || !m->has_beam || prob->method->growth_operator) &&
                    (!engine || engine->distributed);
  const int explicit_pd = a->type == CUPID_ANALYSIS_DYNAMIC && !m->has_beam &&
                          a->dynamic.integrator == CUPID_INTEGRATOR_CENTRAL;
  return slabs && !prob->opts->replicate && cupid_petsc_size() > 1 && !prob->opts->check_only &&
         m->has_peridynamics && m->pd.dimension == 3 && (solve || explicit_pd);
}


/* Output points and lines are checked on rank 0: before the solve the check only locates
 * them against the model's regions and the beam (cupid_problem_sample_point without a
 * solution), which every slab knows in whole. */
cupid_status cupid_problem_slab_check_points(cupid_problem_state *prob) {
  cupid_status st = CUPID_SUCCESS;
  if (cupid_petsc_rank() == 0) st = cupid_problem_check_points(prob);
  return cupid_problem_slab_agree(st);
}

/* Gather n_per_node values of every owned node of every rank on rank 0 (into *whole, which
 * rank 0 allocates for the global nodes). A 3-per-node field of a coupled model also takes
 * the FE DOFs, the same on every rank (rank 0's copy), after the global nodes' DOFs. */
static cupid_status gather_nodes(const cupid_problem_state *prob, const double *local, int n_per_node,
                                 double **whole) {
  const cupid_int first = prob->part.owned_first, owned = prob->part.owned_last - first;
  const cupid_int pd = n_per_node * prob->part.global_nodes, fe = n_per_node == 3 ? prob->n_fe_dofs : 0;
  cupid_status st = CUPID_SUCCESS;
  if (cupid_petsc_rank() == 0)
    st = cupid_calloc((size_t)(pd + fe) + 1, sizeof **whole, "gathered PD fields", whole);
  CUPID_CALL(cupid_problem_slab_agree(st));
  if (cupid_petsc_rank() == 0)
    for (cupid_int d = 0; d < fe; d++) (*whole)[pd + d] = local[prob->fe_offset + d];
  return cupid_petsc_gather_root(local + (size_t)n_per_node * (size_t)first, n_per_node * owned,
                                 *whole);
}

cupid_status cupid_problem_slab_gather(const cupid_problem_state *prob, const double *local,
                                       int n_per_node, double **whole) {
  *whole = NULL;
  return gather_nodes(prob, local, n_per_node, whole);
}

/* Each output point sampled by the rank that owns the node whose cell holds it (its
 * neighbours' copies are current), or by rank 0 in a beam (whose DOFs every rank holds
 * whole), and summed over the ranks. */
cupid_status cupid_problem_slab_points(const cupid_problem_state *prob, double *u) {
  const cupid_output *out = &prob->model->output;
  const int np = out->n_points;
  double *buf = NULL;
  CUPID_CALL(cupid_calloc((size_t)(4 * np) + 1, sizeof *buf, "output points", &buf));
  double o[3], h = cupid_pd_grid_spacing(prob->grid);
  cupid_pd_grid_origin(prob->grid, o);
  for (int k = 0; k < np; k++) {
    const double *p = out->points[k].at;
    cupid_int ijk[3];
    for (int a = 0; a < 3; a++) ijk[a] = (cupid_int)floor((p[a] - o[a]) / h);
    const cupid_int node = cupid_pd_grid_node_at(prob->grid, ijk[0], ijk[1], ijk[2]);
    const int in_beam = prob->beam && cupid_cuf_contains(prob->beam, p[0], p[1], p[2]);
    const int mine = (in_beam ? cupid_petsc_rank() == 0 : node >= 0 && cupid_problem_pd_owned(prob, node)) &&
                     u[3 * k] == u[3 * k];
    for (int c = 0; c < 3 && mine; c++) buf[3 * k + c] = u[3 * k + c];
    buf[3 * np + k] = mine;
  }
  cupid_petsc_sum_doubles(buf, 4 * np);
  for (int k = 0; k < np; k++)
    for (int c = 0; c < 3; c++) u[3 * k + c] = buf[3 * np + k] > 0 ? buf[3 * k + c] : NAN;
  cupid_free(&buf);
  return CUPID_SUCCESS;
}

static cupid_status halo_exchange(void *ctx, double *x) { return cupid_petsc_halo_update(ctx, x); }

static void sum_over_ranks(void *ctx, double *values, int count) {
  (void)ctx;
  cupid_petsc_sum_doubles(values, count);
}

static void max_over_ranks(void *ctx, double *values, int count) {
  (void)ctx;
  cupid_petsc_max_doubles(values, count);
}

cupid_status cupid_problem_slab_partition(const cupid_problem_state *prob, cupid_petsc_halo *halo,
                                          cupid_dynamics_partition *part) {
  const cupid_pd_grid_partition *p = &prob->part;
  /* the PD DOFs (a beam's DOFs, after them, are whole on every rank) */
  CUPID_CALL(cupid_problem_slab_agree(cupid_petsc_halo_create(
      3 * prob->n_pd, 3 * p->owned_first, 3 * p->owned_last, 3 * p->first_global, halo)));
  *part = (cupid_dynamics_partition){.owned_first = 3 * p->owned_first,
                                     .owned_last = 3 * p->owned_last,
                                     .global_first = 3 * p->first_global,
                                     .exchange = halo_exchange,
                                     .sum = sum_over_ranks,
                                     .ctx = *halo,
                                     .max = max_over_ranks};
  return CUPID_SUCCESS;
}

/* The Dirichlet flags and values as doubles (MPI moves one type here). */
static cupid_status bc_as_doubles(const cupid_problem_state *prob, double **flags, double **values) {
  const cupid_int nd = prob->ndof;
  CUPID_CALL(cupid_malloc((size_t)nd, sizeof **flags, "constraint flags", flags));
  CUPID_CALL(cupid_malloc((size_t)nd, sizeof **values, "constraint values", values));
  for (cupid_int d = 0; d < nd; d++) {
    (*flags)[d] = prob->bc->fixed[d];
    (*values)[d] = prob->bc->value[d];
  }
  return CUPID_SUCCESS;
}

/* Rank 0 becomes a whole-grid prob: the whole grid (no operator), the gathered fields (and
 * the beam, for a coupled model). */
static cupid_status become_whole(cupid_problem_state *prob, double *g[7]) {
  double *u = g[0], *f_ext = g[1], *f_int = g[2], *flags = g[3], *values = g[4], *stress = g[5];
  cupid_pd_operator_destroy(&prob->op);
  cupid_pd_grid_destroy(&prob->grid);
  CUPID_CALL(cupid_pd_grid_create_from_model(prob->model, &prob->grid));
  prob->n_pd = cupid_pd_grid_num_nodes(prob->grid);
  prob->fe_offset = 3 * prob->n_pd;
  prob->ndof = prob->fe_offset + prob->n_fe_dofs;
  if (prob->beam) { /* the beam's DOFs follow the whole grid's now */
    CUPID_CALL(cupid_cuf_set_dof_offset(prob->beam, prob->fe_offset));
    cupid_cuf_get_info(prob->beam, &prob->fe_info);
  }
  cupid_dirichlet_destroy(&prob->bc);
  CUPID_CALL(cupid_dirichlet_create(prob->ndof, &prob->bc));
  for (cupid_int d = 0; d < prob->ndof; d++) {
    prob->bc->fixed[d] = flags[d] != 0.0;
    prob->bc->value[d] = values[d];
  }
  CUPID_CALL(cupid_dirichlet_finalize(prob->bc));
  cupid_free(&prob->u);
  cupid_free(&prob->f_ext);
  cupid_free(&prob->f_int);
  cupid_free(&prob->pd_stress);
  prob->u = u, prob->f_ext = f_ext, prob->f_int = f_int, prob->pd_stress = stress;
  g[0] = g[1] = g[2] = g[5] = NULL; /* now the prob's */
  if (prob->damage) { /* the gathered damage (cupid_problem_fracture_damage reads it now) */
    cupid_free(&prob->damage);
    prob->damage = g[6];
    g[6] = NULL;
  }
  return CUPID_SUCCESS;
}

/* The nodes that growth held (growth.held, one flag per slab node) to rank 0, over the whole
 * grid, where force_sums keeps their forces apart from the constraints' reactions. */
static cupid_status gather_held(cupid_problem_state *prob) {
  double *mine = NULL, *all = NULL;
  cupid_status st = cupid_malloc((size_t)prob->n_pd + 1, sizeof *mine, "held flags", &mine);
  CUPID_CALL(cupid_problem_slab_agree(st));
  for (cupid_int i = 0; i < prob->n_pd; i++) mine[i] = prob->growth.held[i];
  st = gather_nodes(prob, mine, 1, &all);
  cupid_free(&mine);
  cupid_free(&prob->growth.held);
  if (st == CUPID_SUCCESS && cupid_petsc_rank() == 0) {
    const cupid_int n = prob->part.global_nodes;
    st = cupid_calloc((size_t)n + 1, 1, "held nodes", &prob->growth.held);
    for (cupid_int i = 0; i < n && st == CUPID_SUCCESS; i++) prob->growth.held[i] = all[i] != 0.0;
  }
  cupid_free(&all);
  return st;
}

cupid_status cupid_problem_slab_collect(cupid_problem_state *prob) {
  cupid_status st = CUPID_SUCCESS;
  double *g[7] = {NULL, NULL, NULL, NULL, NULL, NULL, NULL}, *flags = NULL, *values = NULL;
  /* Bonds and slab sizes for the summary, summed and maximised over the ranks. */
  double sums[2] = {(double)cupid_pd_operator_num_bonds_range(prob->op, prob->part.owned_first,
                                                               prob->part.owned_last), 0.0};
  cupid_petsc_sum_doubles(sums, 1);
  prob->n_bonds = (cupid_int)sums[0];
  prob->slab_ranks = prob->part.parts;
  prob->slab_nodes_max = cupid_petsc_max_int((int)prob->n_pd);
  if (cupid_problem_needs_stress(prob)) {
    st = cupid_calloc((size_t)(6 * prob->n_pd), sizeof(double), "PD stresses", &prob->pd_stress);
    if (st == CUPID_SUCCESS) st = cupid_pd_operator_stress(prob->op, prob->u, prob->pd_stress);
    CUPID_TRY(cupid_problem_slab_agree(st));
  }
  CUPID_TRY(cupid_problem_slab_agree(bc_as_doubles(prob, &flags, &values)));
  CUPID_TRY(gather_nodes(prob, prob->u, 3, &g[0]));
  CUPID_TRY(gather_nodes(prob, prob->f_ext, 3, &g[1]));
  CUPID_TRY(gather_nodes(prob, prob->f_int, 3, &g[2]));
  CUPID_TRY(gather_nodes(prob, flags, 3, &g[3]));
  CUPID_TRY(gather_nodes(prob, values, 3, &g[4]));
  if (prob->pd_stress) CUPID_TRY(gather_nodes(prob, prob->pd_stress, 6, &g[5]));
  if (prob->damage) {
    CUPID_TRY(cupid_problem_slab_agree(cupid_problem_fracture_damage(prob)));
    CUPID_TRY(gather_nodes(prob, prob->damage, 1, &g[6]));
  }
  if (prob->growth.held) CUPID_TRY(gather_held(prob));
  if (cupid_petsc_rank() == 0) {
    CUPID_TRY(become_whole(prob, g));
    prob->slab = 0; /* rank 0 now holds the whole model; the others stop here */
  }
cleanup:
  for (int k = 0; k < 7; k++) cupid_free(&g[k]);
  cupid_free(&flags);
  cupid_free(&values);
  return st;
}
