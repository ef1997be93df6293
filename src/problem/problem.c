/* The problem object (include/cupid/problem.h): model -> grid and beam -> coupling layout ->
 * constraints and loads (setup) -> assembly or operator -> solve, integrate or evaluate (solve)
 * -> outputs (report.c). The coupling method is a table (method.h) and the solver engine another
 * (cupid_solver_type, solvers.h): the stages below call through them. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "cupid/io.h"
#include "method.h"

void cupid_problem_progress(const cupid_problem_state *prob, const char *fmt, ...) {
  if (prob->quiet) return;
  va_list ap;
  va_start(ap, fmt);
  fprintf(stderr, "cupid [%7.2f s] ", cupid_wtime() - prob->t_start);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
}

void cupid_problem_phase_end(cupid_problem_state *prob, cupid_phase phase, double t0) {
  prob->phases[phase].seconds += cupid_wtime() - t0;
  prob->phases[phase].peak_memory = cupid_peak_memory();
  prob->phases[phase].used = 1;
}

void cupid_problem_record_solve(cupid_problem_state *prob) {
  prob->phases[CUPID_PHASE_FACTORISATION] =
      (cupid_phase_record){prob->solve.time_factor, cupid_peak_memory(), 1};
  prob->phases[CUPID_PHASE_SOLVE] = (cupid_phase_record){prob->solve.time_solve, cupid_peak_memory(), 1};
}

cupid_run_options cupid_run_options_default(void) { return (cupid_run_options){.solver = -1}; }

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
static cupid_status check_engine_request(const cupid_problem_state *prob) {
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

/* The estimate of @p e's path for this problem: the factorisation, the method's matrix-free
 * path where the engine takes it, or (an engine that solves assembled systems by Krylov)
 * the assembled Krylov solve. */
static const cupid_solver_cost *path_cost(const cupid_problem_state *prob,
                                          const cupid_solver_type *e,
                                          const cupid_solver_cost *factor,
                                          const cupid_solver_cost *krylov) {
  if (!e->iterative) return factor;
  if (prob->method->matrix_free(prob, e)) return krylov;
  return e->distributed ? krylov : factor; /* krylov: assembled systems are factored */
}

/* auto: the engine whose estimated time is the smallest among those whose estimated memory
 * stays below a quarter of the limit (a margin: fill-in and iteration counts are estimated,
 * not known; ties: the table's order, the factorisation first); when none does, the one of
 * least memory (the size guard then says what it needs). Analyses other than static take the
 * first engine (the integrators factor or need no solve). */
#define AUTO_MEMORY_SHARE 0.25
cupid_status cupid_problem_auto_engine(const cupid_problem_state *prob,
                                       const cupid_solver_type **engine, char *why, size_t len) {
  const cupid_solver_type *first = cupid_solver_type_at(0), *pick = NULL, *lean = NULL;
  if (prob->model->analysis.type != CUPID_ANALYSIS_STATIC) {
    snprintf(why, len, "auto: the only engine for this analysis");
    *engine = first;
    return CUPID_SUCCESS;
  }
  cupid_solver_cost factor, krylov;
  CUPID_CALL(cupid_problem_costs(prob, &factor, &krylov));
  const double limit = cupid_problem_memory_limit(prob);
  const cupid_model_t *m = prob->model;
  if (!first->iterative && (m->analysis.steps > 0 || (m->has_peridynamics && m->pd.fracture.has_fracture))) {
    /* load steps and crack growth solve many times with one K, changed by few bonds: one
     * factorisation serves them all (downdated as bonds break, growth.c), where an iterative
     * engine would start every solve from nothing */
    const cupid_solver_cost *c = path_cost(prob, first, &factor, &krylov);
    if (c->bytes <= AUTO_MEMORY_SHARE * limit) {
      snprintf(why, len, "auto: %s (%s; load steps reuse one factorisation), estimate %.3g s and "
               "%.3g GB", first->name, c->what, c->seconds, c->bytes / 1e9);
      *engine = first;
      return CUPID_SUCCESS;
    }
  }
  const cupid_solver_cost *best = NULL, *least = NULL;
  for (int k = 0; cupid_solver_type_at(k); k++) {
    const cupid_solver_type *e = cupid_solver_type_at(k);
    if (!e->available()) continue;
    const cupid_solver_cost *c = path_cost(prob, e, &factor, &krylov);
    if (!least || c->bytes < least->bytes) least = c, lean = e;
    if (c->bytes <= AUTO_MEMORY_SHARE * limit && (!best || c->seconds < best->seconds))
      best = c, pick = e;
  }
  if (!pick) pick = lean, best = least;
  int n = snprintf(why, len, "auto: %s (%s), estimate %.3g s and %.3g GB", pick->name, best->what,
                   best->seconds, best->bytes / 1e9);
  for (int k = 0; cupid_solver_type_at(k) && n > 0 && (size_t)n < len; k++) { /* the others */
    const cupid_solver_type *e = cupid_solver_type_at(k);
    const cupid_solver_cost *c = e->available() ? path_cost(prob, e, &factor, &krylov) : NULL;
    if (c && c != best)
      n += snprintf(why + n, len - (size_t)n, "; %s (%s): %.3g s, %.3g GB", e->name, c->what,
                    c->seconds, c->bytes / 1e9);
  }
  *engine = pick;
  return CUPID_SUCCESS;
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
  prob->estimate = *path_cost(prob, prob->engine, &factor, &krylov);
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

static cupid_status choose_solver(cupid_problem_state *prob) {
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

cupid_status cupid_problem_check_finite(const cupid_problem_state *prob, const double *v,
                                        const cupid_mark *mark, const char *what) {
  cupid_int d = 0;
  while (d < prob->ndof && isfinite(v[d])) d++;
  if (d == prob->ndof) return CUPID_SUCCESS;
  char where[160];
  const char comp = "xyz"[d % 3];
  if (d < prob->fe_offset) {
    const double *x = cupid_pd_grid_coords(prob->grid) + 3 * (d / 3);
    snprintf(where, sizeof where, "PD node (%g, %g, %g), component %c", x[0], x[1], x[2], comp);
  } else {
    cupid_int node = (d - prob->fe_offset) / 3 / prob->fe_info.M;
    snprintf(where, sizeof where, "beam node %lld (y = %g), component %c", (long long)node,
             cupid_cuf_beam_node_y(prob->beam, node), comp);
  }
  if (!mark)
    return CUPID_ERROR(CUPID_ERR_NUMERIC, "%s is not finite (%g) at %s", what, v[d], where);
  return cupid_model_error(prob->model, mark,
                           "%s is not finite (%g) at %s: an expression is undefined or overflows "
                           "there",
                           what, v[d], where);
}

/* ----------------------------------------------------------------------- the set-up */

/* PD regions need isotropic materials (the LPS and bond-based models take E and nu). */
static cupid_status check_isotropic(const cupid_model_t *m) {
  for (int r = 0; r < m->pd.n_regions; r++) {
    const cupid_material *mat = &m->materials[m->pd.regions[r].material];
    if (mat->orthotropic)
      return cupid_model_error(m, &m->pd.regions[r].mark,
                               "material '%s' is orthotropic; peridynamics needs an isotropic "
                               "material {E, nu}",
                               mat->name);
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_pd_options(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  CUPID_CALL(check_isotropic(m));
  CUPID_CALL(cupid_calloc((size_t)m->n_materials, sizeof *prob->pd_materials, "PD materials",
                          &prob->pd_materials));
  for (int i = 0; i < m->n_materials; i++)
    prob->pd_materials[i] = (cupid_pd_material){.E = m->materials[i].E, .nu = m->materials[i].nu};
  prob->pd_options = (cupid_pd_operator_options){.horizon = m->pd.horizon,
                                                 .model = m->pd.model,
                                                 .influence = m->pd.influence,
                                                 .partial_volume = m->pd.partial_volume,
                                                 .surface_correction = m->pd.surface_correction,
                                                 .materials = prob->pd_materials,
                                                 .n_materials = m->n_materials};
  return CUPID_SUCCESS;
}

static cupid_status build_pd(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  double t0 = cupid_wtime();
  CUPID_CALL(cupid_problem_pd_options(prob));
  if (prob->slab) { /* this rank's z layers and the halo its rows read (slab.c) */
    int halo = 0;
    CUPID_CALL(cupid_pd_operator_halo_layers(&prob->pd_options, m->pd.spacing, &halo));
    CUPID_CALL(cupid_pd_grid_create_part_from_model(m, cupid_petsc_size(), cupid_petsc_rank(),
                                                    halo, &prob->grid));
  } else {
    CUPID_CALL(cupid_pd_grid_create_from_model(m, &prob->grid));
  }
  cupid_pd_grid_get_partition(prob->grid, &prob->part);
  prob->n_pd = cupid_pd_grid_num_nodes(prob->grid);
  CUPID_CALL(cupid_pd_operator_create(prob->grid, &prob->pd_options, &prob->op));
  prob->n_bonds = cupid_pd_operator_num_bonds(prob->op);
  cupid_problem_phase_end(prob, CUPID_PHASE_GRID, t0);
  if (prob->slab)
    cupid_problem_progress(prob, "grid: %lld PD nodes in %d z slabs; rank 0 holds %lld (%lld owned)",
                           (long long)prob->part.global_nodes, prob->part.parts,
                           (long long)prob->n_pd,
                           (long long)(prob->part.owned_last - prob->part.owned_first));
  else
    cupid_problem_progress(prob, "grid: %lld PD nodes, %lld bonds", (long long)prob->n_pd,
                           (long long)prob->n_bonds);
  return CUPID_SUCCESS;
}

static cupid_status allocate_fields(cupid_problem_state *prob) {
  size_t n = (size_t)prob->ndof;
  CUPID_CALL(cupid_calloc(n, sizeof(double), "displacements", &prob->u));
  CUPID_CALL(cupid_calloc(n, sizeof(double), "applied loads", &prob->f_ext));
  CUPID_CALL(cupid_calloc(n, sizeof(double), "internal forces", &prob->f_int));
  CUPID_CALL(cupid_dirichlet_create(prob->ndof, &prob->bc));
  return CUPID_SUCCESS;
}

/* A slab run agrees on every rank's status before the next collective call (slab.c). */
static cupid_status agreed(const cupid_problem_state *prob, cupid_status st) {
  return prob->slab ? cupid_problem_slab_agree(st) : st;
}

/* Constraints (finalized) and loads of a static or dynamic analysis, through the method. */
static cupid_status apply_conditions(cupid_problem_state *prob) {
  CUPID_CALL(prob->method->constraints(prob));
  CUPID_CALL(cupid_dirichlet_finalize(prob->bc));
  return agreed(prob, prob->method->loads(prob));
}

static cupid_status require_constraints(const cupid_problem_state *prob);
static cupid_status run_dynamic(cupid_problem_state *prob);

/* `cupid check`: what a run checks before its first solve or step, by the run's own code
 * (issue 33: check said "valid" to a dt that run refused as unstable): the constraints of a
 * static analysis, and central differences' stable step, found as a run finds it (the method's
 * operator, the mass, the integrator's check before step 1: a dynamic run of no step). */
static cupid_status check_before_solving(cupid_problem_state *prob) {
  const cupid_analysis *a = &prob->model->analysis;
  if (a->type == CUPID_ANALYSIS_STATIC) return require_constraints(prob);
  if (a->type == CUPID_ANALYSIS_DYNAMIC && a->dynamic.integrator == CUPID_INTEGRATOR_CENTRAL)
    return run_dynamic(prob);
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_setup(cupid_problem_state *prob) {
  const cupid_model_t *model = prob->model;
  CUPID_CHECK(prob->stage == CUPID_STAGE_CREATED, CUPID_ERR_ARGUMENT,
              "cupid_problem_setup: the problem is already set up");
  CUPID_CALL(prob->method->check(prob));
  CUPID_CALL(cupid_problem_fracture_check(prob));
  CUPID_CALL(check_engine_request(prob));
  CUPID_CALL(cupid_problem_guard_size(prob)); /* before anything that scales with the model */
  prob->slab = cupid_problem_slab_wanted(prob);
  if (model->has_peridynamics) CUPID_CALL(agreed(prob, build_pd(prob)));
  if (model->has_beam) CUPID_CALL(cupid_problem_fe_build(prob));
  if (prob->method->prepare) CUPID_CALL(prob->method->prepare(prob));
  if (model->has_peridynamics) CUPID_CALL(agreed(prob, cupid_problem_fracture_setup(prob)));
  prob->fe_offset = 3 * prob->n_pd;
  prob->ndof = prob->fe_offset + prob->n_fe_dofs;
  CUPID_CALL(prob->slab ? cupid_problem_slab_check_points(prob) : cupid_problem_check_points(prob));
  if (prob->opts->check_only) {
    /* `cupid check`: the constraints and loads resolved on the built grid and beam by the
     * run's own code, so that check refuses what run would (no solver started) */
    prob->engine = cupid_solver_type_at(0);
    CUPID_CALL(allocate_fields(prob));
    if (model->analysis.type != CUPID_ANALYSIS_EVALUATE &&
        !(prob->method->caps & CUPID_METHOD_CONDITIONS_ASSEMBLE)) {
      CUPID_CALL(apply_conditions(prob));
      CUPID_CALL(check_before_solving(prob));
    }
    prob->stage = CUPID_STAGE_SET_UP;
    return CUPID_SUCCESS;
  }
  CUPID_CALL(choose_solver(prob));
  cupid_problem_progress(prob, "solver: %s (%s)", prob->engine->name, prob->solver_reason);
  CUPID_CALL(cupid_problem_guard_run(prob));
  CUPID_CALL(allocate_fields(prob));
  if (model->analysis.type != CUPID_ANALYSIS_EVALUATE) CUPID_CALL(apply_conditions(prob));
  prob->stage = CUPID_STAGE_SET_UP;
  return CUPID_SUCCESS;
}

/* --------------------------------------------------------------------- the analyses */

void cupid_problem_pd_field(const cupid_problem_state *prob, const cupid_value v[3], double t,
                            double *u) {
  const double *x = cupid_pd_grid_coords(prob->grid);
  const int *mat = cupid_pd_grid_materials(prob->grid);
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    const double *p = x + 3 * i;
    double rho = prob->model->materials[mat[i]].density;
    for (int c = 0; c < 3; c++) u[3 * i + c] = cupid_value_eval(&v[c], p[0], p[1], p[2], t, rho);
  }
}

/* `evaluate`: impose the field everywhere and compute the internal forces K u. A PD-only
 * model applies the operator; anything with a beam assembles the method's K. */
static cupid_status run_evaluate(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  double t0 = cupid_wtime();
  if (prob->grid) {
    /* evaluate's field expressions take no density (0) */
    const double *x = cupid_pd_grid_coords(prob->grid);
    for (cupid_int i = 0; i < prob->n_pd; i++)
      for (int c = 0; c < 3; c++)
        prob->u[3 * i + c] = cupid_value_eval(&m->analysis.field[c], x[3 * i], x[3 * i + 1],
                                              x[3 * i + 2], 0.0, 0.0);
  }
  if (!prob->beam) {
    CUPID_CALL(cupid_problem_check_finite(prob, prob->u, &m->analysis.mark, "the field"));
    CUPID_CALL(cupid_pd_operator_apply(prob->op, prob->u, prob->f_int));
  } else {
    CUPID_CALL(cupid_problem_fe_impose_field(prob));
    CUPID_CALL(cupid_problem_check_finite(prob, prob->u, &m->analysis.mark, "the field"));
    /* FE nodes where the beam gave way are not part of the model. */
    for (cupid_int n = 0; n < prob->fe_info.n_fe_nodes; n++)
      if (!cupid_cuf_node_used(prob->beam, (int)(n % prob->fe_info.M), n / prob->fe_info.M))
        for (int c = 0; c < 3; c++) prob->u[prob->fe_offset + 3 * n + c] = 0.0;
    CUPID_CALL(prob->method->assemble(prob));
    CUPID_CALL(cupid_problem_patch_test_assembled(prob));
    cupid_csr_matvec(prob->K, prob->u, prob->f_int);
  }
  cupid_problem_phase_end(prob, CUPID_PHASE_SOLVE, t0);
  cupid_problem_progress(prob, "evaluate: internal forces of the imposed field computed");
  return prob->method->report ? prob->method->report(prob) : CUPID_SUCCESS;
}

static cupid_status require_constraints(const cupid_problem_state *prob) {
  int fixed[3] = {0, 0, 0};
  for (cupid_int d = 0; d < prob->ndof; d++)
    if (prob->bc->fixed[d]) fixed[d % 3] = 1;
  if (prob->slab)
    for (int c = 0; c < 3; c++) fixed[c] = cupid_petsc_max_int(fixed[c]);
  if (fixed[0] && fixed[1] && fixed[2]) return CUPID_SUCCESS;
  char free_axes[8] = "";
  for (int c = 0; c < 3; c++)
    if (!fixed[c]) {
      size_t n = strlen(free_axes);
      if (n) free_axes[n++] = ' ';
      free_axes[n] = "xyz"[c];
      free_axes[n + 1] = '\0';
    }
  return CUPID_ERROR(CUPID_ERR_NUMERIC,
                     "the model is unconstrained: no constraint fixes the %s displacement "
                     "anywhere, so the stiffness matrix is singular (rigid-body motion); add "
                     "`fix`, `clamp` or `displacement` constraints",
                     free_axes);
}

/* `static`: the method's matrix-free solve, or its assembled K through the engine. */
static cupid_status begin_outputs(cupid_problem_state *prob);

static cupid_status run_static(cupid_problem_state *prob) {
  CUPID_CALL(require_constraints(prob));
  const cupid_model_t *m = prob->model;
  if (m->analysis.steps > 0 || (m->has_peridynamics && m->pd.fracture.has_fracture)) {
    /* load steps, crack growth: assembled K and the direct path, re-solved as bonds break, or
     * (PD only, slabs under mpirun) the kept matrix-free solve */
    if (!prob->slab) CUPID_CALL(cupid_problem_estimate(prob, 0));
    CUPID_CALL(begin_outputs(prob)); /* the steps' rows are written as the run goes */
    return cupid_problem_run_growth(prob);
  }
  if (prob->method->matrix_free(prob, prob->engine)) {
    /* the memory guard where the matrix-free path's estimate is calibrated */
    if (prob->method->caps & CUPID_METHOD_GUARD_MATRIX_FREE) CUPID_CALL(cupid_problem_estimate(prob, 0));
    CUPID_CALL(prob->method->solve_matrix_free(prob));
    if (prob->slab || !prob->method->report) return CUPID_SUCCESS; /* rank 0 reports whole */
    return prob->method->report(prob);
  }
  CUPID_CALL(cupid_problem_estimate(prob, 0)); /* before anything scales with the stiffness */
  CUPID_CALL(prob->method->assemble(prob));
  CUPID_CALL(prob->method->solve_assembled ? prob->method->solve_assembled(prob)
                                           : cupid_problem_assembled_solve(prob));
  return prob->method->report ? prob->method->report(prob) : CUPID_SUCCESS;
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

/* The run's files go to a staging folder beside the output folder until write_outputs
 * publishes them (io.h, cupid_output_set): a failed or interrupted run leaves the previous
 * results as they were. Rank 0 writes. */
static cupid_status begin_outputs(cupid_problem_state *prob) {
  if (prob->outputs || cupid_petsc_rank() != 0) return CUPID_SUCCESS;
  CUPID_CALL(cupid_output_set_begin(prob->outdir, &prob->outputs));
  prob->writedir = cupid_output_set_dir(prob->outputs);
  return CUPID_SUCCESS;
}

/* `dynamic`: central differences (which need a lumped mass) on the method's operator when it
 * has one for this model: no K, no factor, memory O(nodes); otherwise on the assembled K
 * (dynamic.c). */
static cupid_status run_dynamic(cupid_problem_state *prob) {
  const cupid_dynamic *d = &prob->model->analysis.dynamic;
  cupid_method_operator op = {0};
  cupid_status st = CUPID_SUCCESS;
  if (d->integrator == CUPID_INTEGRATOR_CENTRAL && prob->method->explicit_operator)
    CUPID_TRY(prob->method->explicit_operator(prob, &op));
  if (!op.apply) {
    CUPID_TRY(cupid_problem_estimate(prob, 0)); /* before anything scales with the stiffness */
    CUPID_TRY(prob->method->assemble(prob));
  }
  CUPID_TRY(op.apply ? cupid_problem_patch_test(prob, op.apply, op.ctx)
                     : cupid_problem_patch_test_assembled(prob));
  /* breaking changes the operator as the run goes: an assembled K could not follow */
  if (prob->model->has_peridynamics && prob->model->pd.fracture.has_fracture && !op.apply) {
    st = CUPID_ERROR(CUPID_ERR_UNSUPPORTED, "bond breaking needs the method's matrix-free "
                     "explicit operator (coupling method %s has none for this model)",
                     prob->method->name);
    goto cleanup;
  }
  if (!prob->opts->check_only) CUPID_TRY(begin_outputs(prob)); /* the series, as it goes */
  CUPID_TRY(cupid_problem_run_dynamic(prob, op.apply ? &op : NULL));
  if (prob->opts->check_only) goto cleanup; /* cupid check: no step, nothing to report */
  if (prob->method->recover) { /* the eliminated unknowns, and K u with them */
    prob->method->recover(prob, prob->u);
    cupid_csr_matvec(prob->K, prob->u, prob->f_int);
  }
  if (prob->method->report) CUPID_TRY(prob->method->report(prob));
cleanup:
  prob->crack_copy = NULL; /* it goes with the operator */
  if (op.destroy) op.destroy(&op.ctx);
  return st;
}

cupid_status cupid_problem_force_sums(cupid_problem_state *prob, double load[3],
                                      double reaction[3]) {
  double *t = NULL;
  /* The unit translation along k: 1 at every PD DOF of component k, the beam's own
   * interpolation elsewhere (cupid_problem_translations); without a beam the PD DOFs are all
   * there is, and their sums need no vector (three of the DOF count were written and read). */
  if (prob->beam)
    CUPID_CALL(cupid_calloc((size_t)(3 * prob->ndof), sizeof *t, "translation vectors", &t));
  cupid_status st = t ? cupid_problem_translations(prob, t) : CUPID_SUCCESS;
  for (int k = 0; k < 3 && st == CUPID_SUCCESS; k++) {
    const double *tk = t ? t + (size_t)k * (size_t)prob->ndof : NULL;
    const cupid_int first = tk ? 0 : k, step = tk ? 1 : 3;
    const cupid_int end = tk ? prob->ndof : 3 * prob->n_pd;
    load[k] = reaction[k] = 0.0;
    for (cupid_int d = first; d < end; d += step) {
      const double w = tk ? tk[d] : 1.0;
      load[k] += prob->f_ext[d] * w;
      /* a node that growth held is no support of the model's: its force is apart
       * (growth.held_reaction, summary.json's held_reaction_sum) */
      const int held = prob->growth.held && d < 3 * prob->n_pd && prob->growth.held[d / 3];
      if (prob->bc->fixed[d] && !held) reaction[k] += (prob->f_int[d] - prob->f_ext[d]) * w;
    }
  }
  cupid_free(&t);
  return st;
}

cupid_status cupid_problem_solve(cupid_problem_state *prob) {
  CUPID_CHECK(prob->stage == CUPID_STAGE_SET_UP && !prob->opts->check_only, CUPID_ERR_ARGUMENT,
              "cupid_problem_solve: %s",
              prob->stage == CUPID_STAGE_SOLVED ? "the problem is already solved"
              : prob->opts->check_only          ? "a check-only problem solves nothing"
                                                : "call cupid_problem_setup first");
  switch (prob->model->analysis.type) {
  case CUPID_ANALYSIS_EVALUATE: CUPID_CALL(run_evaluate(prob)); break;
  case CUPID_ANALYSIS_DYNAMIC: CUPID_CALL(run_dynamic(prob)); break;
  default: CUPID_CALL(run_static(prob));
  }
  prob->stage = CUPID_STAGE_SOLVED;
  if (prob->slab) return CUPID_SUCCESS; /* a slab rank other than 0: rank 0 holds the model */
  /* a non-finite result is a failure, never a result (an unstable or overflowing analysis) */
  CUPID_CALL(cupid_problem_check_finite(prob, prob->u, NULL,
                                        "the displacement (the analysis diverged or overflowed)"));
  CUPID_CALL(cupid_problem_check_finite(prob, prob->f_int, NULL, "the internal force"));
  CUPID_CALL(cupid_problem_force_sums(prob, prob->load_sum, prob->reaction_sum));
  cupid_problem_quality_report(prob);
  return CUPID_SUCCESS;
}

/* -------------------------------------------------------------------- the life cycle */

void cupid_problem_state_free(cupid_problem_state *prob) {
  cupid_coupling_destroy(&prob->coupling);
  cupid_pd_operator_destroy(&prob->op);
  cupid_pd_grid_destroy(&prob->grid);
  cupid_cuf_beam_destroy(&prob->beam);
  cupid_csr_destroy(&prob->K);
  cupid_dirichlet_destroy(&prob->bc);
  cupid_free(&prob->u);
  cupid_free(&prob->f_ext);
  cupid_free(&prob->f_int);
  cupid_free(&prob->pd_stress);
  cupid_free(&prob->pd_materials);
  cupid_free(&prob->arlequin_regions);
  cupid_free(&prob->beam_points);
  cupid_free(&prob->beam_u);
  cupid_free(&prob->history);
  cupid_output_set_abort(&prob->outputs); /* not published: the previous results stay */
  cupid_free(&prob->region_boxes);
  cupid_free(&prob->region_materials);
  cupid_free(&prob->protect);
  cupid_free(&prob->no_fail);
  cupid_free(&prob->node_stretch);
  cupid_petsc_halo_destroy(&prob->break_halo);
  cupid_free(&prob->break_words);
  cupid_free(&prob->damage);
  cupid_free(&prob->growth.peak);
  cupid_free(&prob->growth.held);
}

cupid_status cupid_problem_create(const cupid_model_t *model, const cupid_run_options *opts,
                                  cupid_problem *p) {
  CUPID_CHECK(p, CUPID_ERR_ARGUMENT, "cupid_problem_create: NULL result pointer");
  *p = NULL;
  CUPID_CHECK(model, CUPID_ERR_ARGUMENT, "cupid_problem_create: NULL model");
  cupid_problem_state *prob = NULL;
  CUPID_CALL(cupid_calloc(1, sizeof *prob, "problem", &prob));
  prob->model = model;
  prob->options = opts ? *opts : cupid_run_options_default();
  prob->opts = &prob->options;
  prob->method = cupid_problem_method_of(model);
  /* Under MPI every rank runs the stages, on the replicated model or on its slab of the PD
   * grid (slab.c); rank 0 speaks and writes. Progress goes to stderr in batch runs too (a
   * log under nohup or a batch system), unless quiet. */
  prob->quiet = prob->options.quiet || cupid_petsc_rank() != 0;
  prob->t_start = cupid_wtime();
  prob->outdir = prob->options.output_dir ? prob->options.output_dir : model->output.directory;
  cupid_set_num_threads(prob->options.threads);
  *p = prob;
  return CUPID_SUCCESS;
}

static cupid_status adopt_model(cupid_model model, const cupid_run_options *opts, cupid_problem *p) {
  cupid_status st = cupid_problem_create(model, opts, p);
  if (st != CUPID_SUCCESS) {
    cupid_model_destroy(&model);
    return st;
  }
  (*p)->owned_model = model;
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_create_from_file(const char *path, const cupid_run_options *opts,
                                            cupid_problem *p) {
  CUPID_CHECK(p, CUPID_ERR_ARGUMENT, "cupid_problem_create_from_file: NULL result pointer");
  *p = NULL;
  cupid_model model = NULL;
  CUPID_CALL(cupid_model_read_with(path, opts ? opts->sets : NULL, opts ? opts->n_sets : 0, &model));
  return adopt_model(model, opts, p);
}

cupid_status cupid_problem_create_from_string(const char *yaml, const char *name,
                                              const cupid_run_options *opts, cupid_problem *p) {
  CUPID_CHECK(p, CUPID_ERR_ARGUMENT, "cupid_problem_create_from_string: NULL result pointer");
  *p = NULL;
  CUPID_CHECK(yaml, CUPID_ERR_ARGUMENT, "cupid_problem_create_from_string: NULL text");
  cupid_model model = NULL;
  CUPID_CALL(cupid_model_read_string_with(yaml, strlen(yaml), name ? name : "<string>",
                                          opts ? opts->sets : NULL, opts ? opts->n_sets : 0,
                                          &model));
  return adopt_model(model, opts, p);
}

void cupid_problem_destroy(cupid_problem *p) {
  if (!p || !*p) return;
  cupid_problem_state_free(*p);
  cupid_model_destroy(&(*p)->owned_model);
  cupid_free(p);
}

const cupid_model_t *cupid_problem_model(cupid_problem p) { return p ? p->model : NULL; }

const char *cupid_problem_output_directory(cupid_problem p) { return p ? p->outdir : NULL; }

cupid_status cupid_problem_write_outputs(cupid_problem_state *prob) {
  CUPID_CHECK(prob && prob->stage == CUPID_STAGE_SOLVED, CUPID_ERR_ARGUMENT,
              "cupid_problem_write_outputs: solve the problem first");
  if (prob->slab || cupid_petsc_rank() != 0) return CUPID_SUCCESS; /* rank 0 writes */
  CUPID_CALL(begin_outputs(prob));
  /* a second call writes the report again beside what the first published: the files the
   * solve wrote as it ran (steps, time series, frames) are there only (issue 33: they were
   * removed as stale) */
  if (prob->outputs_written) cupid_output_set_keep_others(prob->outputs);
  CUPID_CALL(cupid_problem_report(prob));
  CUPID_CALL(cupid_output_set_publish(&prob->outputs));
  prob->outputs_written = 1;
  prob->writedir = NULL;
  cupid_problem_progress(prob, "done: results in %s", prob->outdir);
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_print_estimate(cupid_problem_state *prob) {
  CUPID_CHECK(prob && prob->stage >= CUPID_STAGE_SET_UP, CUPID_ERR_ARGUMENT,
              "cupid_problem_print_estimate: set the problem up first");
  return cupid_problem_estimate(prob, 1);
}

cupid_status cupid_run_model(const cupid_model_t *model, const cupid_run_options *opts) {
  cupid_problem p = NULL;
  CUPID_CALL(cupid_problem_create(model, opts, &p));
  cupid_status st = cupid_problem_setup(p);
  if (st == CUPID_SUCCESS && p->opts->check_only) st = cupid_problem_print_estimate(p);
  else if (st == CUPID_SUCCESS) st = cupid_problem_solve(p);
  if (st == CUPID_SUCCESS && !p->opts->check_only) st = cupid_problem_write_outputs(p);
  cupid_problem_destroy(&p);
  return st;
}
