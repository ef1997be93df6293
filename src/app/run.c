/* The run pipeline: model -> grid -> constraints and loads -> assembly -> solve -> outputs.
 * Each stage is a short function; the job struct carries the state between them. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "app_internal.h"
#include "cupid/io.h"

void cupid_job_progress(const cupid_job *job, const char *fmt, ...) {
  if (job->quiet) return;
  va_list ap;
  va_start(ap, fmt);
  fprintf(stderr, "cupid [%7.2f s] ", cupid_wtime() - job->t_start);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
}

void cupid_job_phase_end(cupid_job *job, cupid_phase phase, double t0) {
  job->phases[phase].seconds += cupid_wtime() - t0;
  job->phases[phase].peak_memory = cupid_peak_memory();
  job->phases[phase].used = 1;
}

/* Solver choice: the command line wins over the model file. PETSc arrives with issue 6. */
static cupid_status choose_solver(const cupid_job *job) {
  const cupid_model_t *m = job->model;
  int solver = job->opts->solver >= 0 ? job->opts->solver : (int)m->analysis.solver;
  if (solver == CUPID_SOLVER_PETSC)
    return CUPID_ERROR(CUPID_ERR_UNSUPPORTED,
                       "solver petsc: this build of cupid has no PETSc engine; use 'direct' or "
                       "'auto' (the embedded SuiteSparse solver)");
  return CUPID_SUCCESS;
}

/* What this version can run; everything else is parsed and validated but refused plainly. */
static cupid_status check_supported(const cupid_job *job) {
  const cupid_model_t *m = job->model;
  if (m->has_beam)
    return cupid_model_error(m, &m->beam.mark,
                             "CUF beam models are not yet supported by cupid %s (the model was "
                             "validated; remove `beam:` to run the peridynamics part alone)",
                             cupid_version());
  if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC)
    return cupid_model_error(m, &m->analysis.mark,
                             "type dynamic is not yet supported by cupid %s (allowed now: static, "
                             "evaluate)",
                             cupid_version());
  if (!m->has_peridynamics)
    return cupid_model_error(m, &m->analysis.mark, "the model has nothing to solve");
  return CUPID_SUCCESS;
}

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

static cupid_status build_pd(cupid_job *job) {
  const cupid_model_t *m = job->model;
  double t0 = cupid_wtime();

  CUPID_CALL(cupid_app_guard_size(job)); /* before anything that scales with the model */
  CUPID_CALL(cupid_pd_grid_create_from_model(m, &job->grid));
  job->n_pd = cupid_pd_grid_num_nodes(job->grid);
  CUPID_CALL(check_isotropic(m));
  CUPID_CALL(cupid_calloc((size_t)m->n_materials, sizeof *job->pd_materials, "PD materials",
                          &job->pd_materials));
  for (int i = 0; i < m->n_materials; i++)
    job->pd_materials[i] = (cupid_pd_material){.E = m->materials[i].E, .nu = m->materials[i].nu};
  job->pd_options = (cupid_pd_operator_options){.horizon = m->pd.horizon,
                                                .model = m->pd.model,
                                                .influence = m->pd.influence,
                                                .partial_volume = m->pd.partial_volume,
                                                .materials = job->pd_materials,
                                                .n_materials = m->n_materials};
  CUPID_CALL(cupid_pd_operator_create(job->grid, &job->pd_options, &job->op));
  job->n_bonds = cupid_pd_operator_num_bonds(job->op);
  job->ndof = 3 * job->n_pd;
  cupid_job_phase_end(job, CUPID_PHASE_GRID, t0);
  cupid_job_progress(job, "grid: %lld PD nodes, %lld bonds", (long long)job->n_pd,
                     (long long)job->n_bonds);
  return CUPID_SUCCESS;
}

static cupid_status allocate_fields(cupid_job *job) {
  size_t n = (size_t)job->ndof;
  CUPID_CALL(cupid_calloc(n, sizeof(double), "displacements", &job->u));
  CUPID_CALL(cupid_calloc(n, sizeof(double), "applied loads", &job->f_ext));
  CUPID_CALL(cupid_calloc(n, sizeof(double), "internal forces", &job->f_int));
  CUPID_CALL(cupid_dirichlet_create(job->ndof, &job->bc));
  return CUPID_SUCCESS;
}

/* `evaluate`: impose the field everywhere and compute the internal forces K u. */
static cupid_status run_evaluate(cupid_job *job) {
  const cupid_model_t *m = job->model;
  const double *x = cupid_pd_grid_coords(job->grid);
  double t0 = cupid_wtime();
  for (cupid_int i = 0; i < job->n_pd; i++)
    for (int c = 0; c < 3; c++)
      job->u[3 * i + c] = cupid_value_eval(&m->analysis.field[c], x[3 * i], x[3 * i + 1],
                                           x[3 * i + 2], 0.0, 0.0);
  CUPID_CALL(cupid_pd_operator_apply(job->op, job->u, job->f_int));
  cupid_job_phase_end(job, CUPID_PHASE_SOLVE, t0);
  cupid_job_progress(job, "evaluate: internal forces of the imposed field computed");
  return CUPID_SUCCESS;
}

/* Name the node and region where a factorisation broke down (exit status 2). */
static cupid_status explain_singular(const cupid_job *job, cupid_status st) {
  cupid_int dof = job->solve.failed_dof;
  if (dof < 0 || dof >= job->ndof) return st;
  char msg[1024];
  snprintf(msg, sizeof msg, "%s", cupid_error_message());
  const double *x = cupid_pd_grid_coords(job->grid);
  cupid_int node = dof / 3;
  return CUPID_ERROR(st,
                     "%s; PD node %lld at (%g, %g, %g), component %c: check that every PD region "
                     "is constrained against rigid motion (fix, clamp or displacement)",
                     msg, (long long)node, x[3 * node], x[3 * node + 1], x[3 * node + 2],
                     "xyz"[dof % 3]);
}

static cupid_status require_constraints(const cupid_job *job) {
  int fixed[3] = {0, 0, 0};
  for (cupid_int d = 0; d < job->ndof; d++)
    if (job->bc->fixed[d]) fixed[d % 3] = 1;
  if (fixed[0] && fixed[1] && fixed[2]) return CUPID_SUCCESS;
  return CUPID_ERROR(CUPID_ERR_NUMERIC,
                     "the model is unconstrained: no constraint fixes the %s%s%s displacement of "
                     "any PD node, so the stiffness matrix is singular (rigid-body motion); add "
                     "`fix`, `clamp` or `displacement` constraints",
                     fixed[0] ? "" : "x ", fixed[1] ? "" : "y ", fixed[2] ? "" : "z ");
}

/* `static`: assemble K, solve K u = f with the Dirichlet conditions, reactions. */
static cupid_status run_static(cupid_job *job) {
  double t0 = cupid_wtime();
  CUPID_CALL(require_constraints(job));
  CUPID_CALL(cupid_app_estimate(job, 0));
  CUPID_CALL(cupid_pd_operator_assemble(job->op, &job->K));
  cupid_job_phase_end(job, CUPID_PHASE_ASSEMBLY, t0);
  cupid_job_progress(job, "assembly: %lld non-zeros (%.1f MB)", (long long)cupid_csr_nnz(job->K),
                     (double)cupid_csr_bytes(job->K) / 1e6);

  cupid_status st = cupid_direct_solve(job->K, CUPID_MATRIX_SPD, job->f_ext, job->bc, job->u,
                                       &job->solve);
  job->phases[CUPID_PHASE_FACTORISATION] =
      (cupid_phase_record){job->solve.time_factor, cupid_peak_memory(), 1};
  job->phases[CUPID_PHASE_SOLVE] = (cupid_phase_record){job->solve.time_solve, cupid_peak_memory(), 1};
  if (st == CUPID_ERR_NUMERIC) return explain_singular(job, st);
  CUPID_CALL(st);
  job->solved = 1;
  cupid_csr_matvec(job->K, job->u, job->f_int);
  cupid_job_progress(job, "solve: %s, %lld equations, residual %.2e", job->solve.method,
                     (long long)job->solve.n, job->solve.residual);
  return CUPID_SUCCESS;
}

/* Applied-load sum and reaction sum (reactions = K u - f on constrained DOFs). */
static void sum_forces(cupid_job *job) {
  for (int c = 0; c < 3; c++) job->load_sum[c] = job->reaction_sum[c] = 0.0;
  for (cupid_int d = 0; d < job->ndof; d++) {
    job->load_sum[d % 3] += job->f_ext[d];
    if (job->bc->fixed[d]) job->reaction_sum[d % 3] += job->f_int[d] - job->f_ext[d];
  }
}

static void job_destroy(cupid_job *job) {
  cupid_pd_operator_destroy(&job->op);
  cupid_pd_grid_destroy(&job->grid);
  cupid_csr_destroy(&job->K);
  cupid_dirichlet_destroy(&job->bc);
  cupid_free(&job->u);
  cupid_free(&job->f_ext);
  cupid_free(&job->f_int);
  cupid_free(&job->pd_stress);
  cupid_free(&job->pd_materials);
}

cupid_status cupid_run_model(const cupid_model_t *model, const cupid_run_options *opts) {
  cupid_job job = {.model = model, .opts = opts, .quiet = opts->quiet || !isatty(2)};
  cupid_status st = CUPID_SUCCESS;
  job.t_start = cupid_wtime();
  job.outdir = opts->output_dir ? opts->output_dir : model->output.directory;
  cupid_set_num_threads(opts->threads);

  CUPID_TRY(check_supported(&job));
  CUPID_TRY(choose_solver(&job));
  CUPID_TRY(build_pd(&job));
  CUPID_TRY(cupid_app_check_points(&job));
  if (opts->check_only) {
    st = cupid_app_estimate(&job, 1);
    goto cleanup;
  }
  CUPID_TRY(allocate_fields(&job));
  if (model->analysis.type == CUPID_ANALYSIS_EVALUATE) {
    CUPID_TRY(run_evaluate(&job));
  } else {
    CUPID_TRY(cupid_app_pd_constraints(&job));
    CUPID_TRY(cupid_dirichlet_finalize(job.bc));
    CUPID_TRY(cupid_app_pd_loads(&job));
    CUPID_TRY(run_static(&job));
  }
  sum_forces(&job);
  CUPID_TRY(cupid_app_write_outputs(&job));
  cupid_job_progress(&job, "done: results in %s", job.outdir);
cleanup:
  job_destroy(&job);
  return st;
}
