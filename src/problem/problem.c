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


cupid_run_options cupid_run_options_default(void) { return (cupid_run_options){.solver = -1}; }



/* ----------------------------------------------------------------------- the set-up */

/* A slab run agrees on every rank's status before the next collective call (slab.c). */
static cupid_status agreed(const cupid_problem_state *prob, cupid_status st) {
  return prob->slab ? cupid_problem_slab_agree(st) : st;
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
  CUPID_CALL(cupid_problem_adaptive_check(prob));
  CUPID_CHECK(!prob->opts->resume || model->analysis.type == CUPID_ANALYSIS_DYNAMIC ||
                  (model->analysis.type == CUPID_ANALYSIS_STATIC && model->has_peridynamics &&
                   model->pd.fracture.has_fracture),
              CUPID_ERR_UNSUPPORTED, "--resume: only dynamic runs and crack growth write "
              "checkpoints in cupid %s (this model is type %s%s); run it without --resume",
              cupid_version(), model->analysis.type == CUPID_ANALYSIS_STATIC ? "static" : "evaluate",
              model->analysis.type == CUPID_ANALYSIS_STATIC ? " without fracture" : "");
  CUPID_CALL(cupid_problem_fracture_check(prob));
  CUPID_CALL(cupid_problem_check_engine_request(prob));
  CUPID_CALL(cupid_problem_guard_size(prob)); /* before anything that scales with the model */
  prob->slab = cupid_problem_slab_wanted(prob);
  /* an adaptive zone that starts empty (regions: []) has no grid until it grows */
  if (model->has_peridynamics && model->pd.n_regions > 0) CUPID_CALL(agreed(prob, cupid_problem_build_pd(prob)));
  if (model->has_beam) CUPID_CALL(cupid_problem_fe_build(prob));
  if (prob->method->prepare) CUPID_CALL(prob->method->prepare(prob));
  if (model->has_peridynamics) CUPID_CALL(agreed(prob, cupid_problem_fracture_setup(prob)));
  if (prob->adaptive) CUPID_CALL(cupid_problem_adaptive_begin(prob));
  prob->fe_offset = 3 * prob->n_pd;
  prob->ndof = prob->fe_offset + prob->n_fe_dofs;
  CUPID_CALL(prob->slab ? cupid_problem_slab_check_points(prob) : cupid_problem_check_points(prob));
  if (prob->opts->check_only) {
    /* `cupid check`: the constraints and loads resolved on the built grid and beam by the
     * run's own code, so that check refuses what run would (no solver started) */
    prob->engine = cupid_solver_type_at(0);
    CUPID_CALL(cupid_problem_allocate_fields(prob));
    if (model->analysis.type != CUPID_ANALYSIS_EVALUATE &&
        !(prob->method->caps & CUPID_METHOD_CONDITIONS_ASSEMBLE)) {
      CUPID_CALL(cupid_problem_apply_conditions(prob));
      CUPID_CALL(check_before_solving(prob));
    }
    prob->stage = CUPID_STAGE_SET_UP;
    return CUPID_SUCCESS;
  }
  CUPID_CALL(cupid_problem_choose_solver(prob));
  cupid_problem_progress(prob, "solver: %s (%s)", prob->engine->name, prob->solver_reason);
  CUPID_CALL(cupid_problem_guard_run(prob));
  CUPID_CALL(cupid_problem_allocate_fields(prob));
  if (model->analysis.type != CUPID_ANALYSIS_EVALUATE) CUPID_CALL(cupid_problem_apply_conditions(prob));
  /* --resume: an adaptive zone as its checkpoint has it (the stage reads its state on it) */
  if (prob->adaptive) CUPID_CALL(agreed(prob, cupid_problem_adaptive_resume(prob)));
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
    if (cupid_problem_balanced(prob)) { /* K' = K - W C^T (balance.c) */
      CUPID_CALL(cupid_problem_balanced_evaluate(prob));
    } else {
      CUPID_CALL(cupid_problem_patch_test_assembled(prob));
      cupid_csr_matvec(prob->K, prob->u, prob->f_int);
    }
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
  if (cupid_problem_runs_steps(prob)) {
    /* load steps, crack growth: assembled K and the direct path, re-solved as bonds break, or
     * (PD only, slabs under mpirun) the kept matrix-free solve */
    if (!prob->slab) CUPID_CALL(cupid_problem_estimate(prob, 0));
    /* the steps' rows are written as the run goes; every rank stops if rank 0 cannot */
    const cupid_status st = begin_outputs(prob);
    CUPID_CALL(cupid_petsc_size() > 1 ? cupid_problem_slab_agree(st) : st);
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


/* The run's files go to a staging folder beside the output folder until write_outputs
 * publishes them (io.h, cupid_output_set): a failed or interrupted run leaves the previous
 * results as they were. Rank 0 writes. */
static cupid_status begin_outputs(cupid_problem_state *prob) {
  if (prob->outputs || cupid_petsc_rank() != 0) return CUPID_SUCCESS;
  /* a dynamic run or crack growth can stop at a checkpoint and be resumed (resume.c): its
   * staging folder has a fixed name and outlives a signal */
  const cupid_model_t *m = prob->model;
  const int growth = m->analysis.type == CUPID_ANALYSIS_STATIC && cupid_problem_growth_resumable(prob);
  if ((m->analysis.type == CUPID_ANALYSIS_DYNAMIC || growth) && !prob->outputs_written)
    CUPID_CALL(cupid_output_set_begin_resumable(prob->outdir, prob->opts->resume, &prob->outputs));
  else
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
  /* breaking changes the operator as the run goes: an assembled K could not follow (an
   * adaptive zone that starts empty: the beam alone has no bond until the zone grows) */
  if (prob->model->has_peridynamics && prob->model->pd.fracture.has_fracture && !op.apply &&
      prob->grid) {
    st = CUPID_ERROR(CUPID_ERR_UNSUPPORTED, "bond breaking needs the method's matrix-free "
                     "explicit operator (coupling method %s has none for this model)",
                     prob->method->name);
    goto cleanup;
  }
  if (!prob->opts->check_only) { /* the series, as it goes; every rank stops if rank 0 cannot
                                     (another run's lock, nothing to resume) */
    st = begin_outputs(prob);
    CUPID_TRY(cupid_petsc_size() > 1 ? cupid_problem_slab_agree(st) : st);
  }
  CUPID_TRY(cupid_problem_run_dynamic(prob, &op));
  if (prob->opts->check_only) goto cleanup; /* cupid check: no step, nothing to report */
  if (prob->method->recover) { /* the eliminated unknowns, and K u with them */
    prob->method->recover(prob, prob->u);
    cupid_csr_matvec(prob->K, prob->u, prob->f_int);
  }
  if (prob->method->report) CUPID_TRY(prob->method->report(prob));
cleanup:
  prob->crack_copy = NULL; /* it goes with the operator */
  prob->crack_map = NULL;
  if (op.destroy) op.destroy(&op.ctx);
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
  if (prob->method) cupid_problem_free_layout(prob);
  cupid_free(&prob->history);
  /* kept for --resume: an interrupted run's checkpoint, and a failed resumption's (refused, or
   * stopped again: the checkpoint it started from stays for another try) */
  if (prob->ckpt.interrupted || prob->opts->resume) cupid_output_set_suspend(&prob->outputs);
  cupid_output_set_abort(&prob->outputs); /* not published: the previous results stay */
  cupid_problem_checkpoint_end(prob);
  cupid_petsc_halo_destroy(&prob->break_halo);
  cupid_free(&prob->break_words);
  cupid_free(&prob->growth.peak);
  cupid_free(&prob->growth.held);
  cupid_problem_adaptive_free(&prob->adaptive);
}

cupid_status cupid_problem_create(const cupid_model_t *model, const cupid_run_options *opts,
                                  cupid_problem *p) {
  CUPID_CHECK(p, CUPID_ERR_ARGUMENT, "cupid_problem_create: NULL result pointer");
  *p = NULL;
  CUPID_CHECK(model, CUPID_ERR_ARGUMENT, "cupid_problem_create: NULL model");
  cupid_problem_state *prob = NULL;
  CUPID_CALL(cupid_calloc(1, sizeof *prob, "problem", &prob));
  /* an adaptive zone changes the model's regions: the run works on its own copy */
  prob->model = cupid_problem_adaptive_model(model, &prob->adaptive);
  if (!prob->model) {
    cupid_free(&prob);
    return CUPID_ERR_MEMORY;
  }
  prob->options = opts ? *opts : cupid_run_options_default();
  prob->opts = &prob->options;
  prob->method = cupid_problem_method_of(model);
  /* an adaptive zone that starts empty: the beam alone until it grows (cupid_problem_rebuild) */
  if (prob->adaptive && model->pd.n_regions == 0) prob->method = &cupid_method_none;
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
