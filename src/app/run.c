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

/* ------------------------------------------------------------- the solver engine (issue 6)
 * The command line wins over the model file. auto: the direct solver while its estimated peak
 * memory stays below a quarter of the memory limit and its factorisation below two minutes
 * (cupid_app_auto_picks_direct, check.c), PETSc above (when cupid was built with it): Krylov +
 * AMG costs O(n) memory where the factor grows like n^(4/3) (docs/scale.md). */

static cupid_solver_kind requested_solver(const cupid_job *job) {
  return job->opts->solver >= 0 ? (cupid_solver_kind)job->opts->solver : job->model->analysis.solver;
}

/* Only static solves go through PETSc: refuse an explicit request elsewhere. */
static cupid_status check_petsc_request(const cupid_job *job) {
  const cupid_model_t *m = job->model;
  if (requested_solver(job) != CUPID_SOLVER_PETSC) return CUPID_SUCCESS;
  if (!cupid_petsc_available())
    return CUPID_ERROR(CUPID_ERR_UNSUPPORTED,
                       "solver petsc: this build of cupid has no PETSc engine: rebuild with "
                       "scripts/build.sh --with-petsc, or use 'direct' or 'auto'");
  if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC)
    return cupid_model_error(m, &m->analysis.mark,
                             "solver petsc serves static analyses; type dynamic uses its own "
                             "integrators (use solver auto or direct)");
  return CUPID_SUCCESS;
}

static cupid_status use_petsc(cupid_job *job) {
  job->solver = CUPID_SOLVER_PETSC;
  return cupid_petsc_initialize(0, NULL); /* no-op when the CLI did it (mpirun) */
}

cupid_status cupid_app_choose_solver(cupid_job *job) {
  const cupid_model_t *m = job->model;
  cupid_solver_kind req = requested_solver(job);
  job->solver = CUPID_SOLVER_DIRECT;
  if (job->slab) {
    snprintf(job->solver_reason, sizeof job->solver_reason,
             "%s: %d MPI ranks, each holding one z slab of the PD grid",
             req == CUPID_SOLVER_PETSC ? "requested" : "auto", job->part.parts);
    return use_petsc(job);
  }
  if (req == CUPID_SOLVER_DIRECT) {
    snprintf(job->solver_reason, sizeof job->solver_reason, "requested");
    return CUPID_SUCCESS;
  }
  if (req == CUPID_SOLVER_PETSC) {
    snprintf(job->solver_reason, sizeof job->solver_reason, "requested");
    return use_petsc(job);
  }
  /* auto */
  if (m->analysis.type != CUPID_ANALYSIS_STATIC) {
    snprintf(job->solver_reason, sizeof job->solver_reason, "auto: the only engine for this analysis");
    return CUPID_SUCCESS;
  }
  double bytes, seconds, limit = cupid_app_memory_limit(job);
  CUPID_CALL(cupid_app_direct_cost(job, &bytes, &seconds));
  int small = cupid_app_auto_picks_direct(job, bytes, seconds);
  if (small || !cupid_petsc_available()) {
    snprintf(job->solver_reason, sizeof job->solver_reason,
             "auto: direct estimate %.3g GB, %.3g s%s", bytes / 1e9, seconds,
             small ? " (below the limits)" : "; PETSc would fit better but this build has none");
    return CUPID_SUCCESS;
  }
  snprintf(job->solver_reason, sizeof job->solver_reason,
           "auto: the direct solver would need %.3g GB and %.3g s (limits %.3g GB, %.0f s)",
           bytes / 1e9, seconds, CUPID_AUTO_DIRECT_MEMORY_SHARE * limit / 1e9,
           CUPID_AUTO_DIRECT_SECONDS);
  return use_petsc(job);
}

/* PD-only 3D models go matrix-free: the 2-delta LPS matrix is never formed. */
static int matrix_free(const cupid_job *job) {
  return job->solver == CUPID_SOLVER_PETSC && job->grid && !job->beam &&
         cupid_pd_grid_dimension(job->grid) == 3;
}

cupid_status cupid_app_linear_solve(cupid_job *job, cupid_matrix_kind kind) {
  if (job->solver != CUPID_SOLVER_PETSC)
    return cupid_direct_solve(job->K, kind, job->f_ext, job->bc, job->u, &job->solve);
  /* Coordinates give GAMG the rigid-body modes when every DOF is a PD node's. */
  cupid_petsc_options po = {0};
  if (job->grid && !job->beam) {
    po.coords = cupid_pd_grid_coords(job->grid);
    po.n_coord_nodes = job->n_pd;
  }
  cupid_status st = cupid_petsc_solve(job->K, kind, job->f_ext, job->bc, job->u, &po, &job->solve);
  if (st == CUPID_SUCCESS)
    cupid_job_progress(job, "PETSc: %s + %s, %d iterations on %d rank%s, %s", job->solve.ksp_type,
                       job->solve.pc_type, job->solve.iterations, job->solve.ranks,
                       job->solve.ranks == 1 ? "" : "s", job->solve.converged_reason);
  return st;
}

/* What this version can run; everything else is parsed and validated but refused plainly. */
static cupid_status check_supported(const cupid_job *job) {
  const cupid_model_t *m = job->model;
  if (cupid_app_is_coupled(job)) return cupid_app_coupled_check(job);
  if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC) return cupid_app_dynamic_check(job);
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

cupid_status cupid_app_pd_options(cupid_job *job) {
  const cupid_model_t *m = job->model;
  CUPID_CALL(check_isotropic(m));
  CUPID_CALL(cupid_calloc((size_t)m->n_materials, sizeof *job->pd_materials, "PD materials",
                          &job->pd_materials));
  for (int i = 0; i < m->n_materials; i++)
    job->pd_materials[i] = (cupid_pd_material){.E = m->materials[i].E, .nu = m->materials[i].nu};
  job->pd_options = (cupid_pd_operator_options){.horizon = m->pd.horizon,
                                                .model = m->pd.model,
                                                .influence = m->pd.influence,
                                                .partial_volume = m->pd.partial_volume,
                                                .surface_correction = m->pd.surface_correction,
                                                .materials = job->pd_materials,
                                                .n_materials = m->n_materials};
  return CUPID_SUCCESS;
}

static cupid_status build_pd(cupid_job *job) {
  const cupid_model_t *m = job->model;
  double t0 = cupid_wtime();

  CUPID_CALL(cupid_app_pd_options(job));
  if (job->slab) { /* this rank's z layers and the halo its rows read (slab.c) */
    int halo = 0;
    CUPID_CALL(cupid_pd_operator_halo_layers(&job->pd_options, m->pd.spacing, &halo));
    CUPID_CALL(cupid_pd_grid_create_part_from_model(m, cupid_petsc_size(), cupid_petsc_rank(),
                                                    halo, &job->grid));
  } else {
    CUPID_CALL(cupid_pd_grid_create_from_model(m, &job->grid));
  }
  cupid_pd_grid_get_partition(job->grid, &job->part);
  job->n_pd = cupid_pd_grid_num_nodes(job->grid);
  CUPID_CALL(cupid_pd_operator_create(job->grid, &job->pd_options, &job->op));
  job->n_bonds = cupid_pd_operator_num_bonds(job->op);
  cupid_job_phase_end(job, CUPID_PHASE_GRID, t0);
  if (job->slab)
    cupid_job_progress(job, "grid: %lld PD nodes in %d z slabs; rank 0 holds %lld (%lld owned)",
                       (long long)job->part.global_nodes, job->part.parts, (long long)job->n_pd,
                       (long long)(job->part.owned_last - job->part.owned_first));
  else
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
  double t0 = cupid_wtime();
  if (job->grid) {
    const double *x = cupid_pd_grid_coords(job->grid);
    for (cupid_int i = 0; i < job->n_pd; i++)
      for (int c = 0; c < 3; c++)
        job->u[3 * i + c] = cupid_value_eval(&m->analysis.field[c], x[3 * i], x[3 * i + 1],
                                             x[3 * i + 2], 0.0, 0.0);
    CUPID_CALL(cupid_pd_operator_apply(job->op, job->u, job->f_int));
  }
  if (job->beam) {
    CUPID_CALL(cupid_app_fe_impose_field(job));
    CUPID_CALL(cupid_cuf_assemble(job->beam, &job->K));
    cupid_csr_matvec(job->K, job->u + job->fe_offset, job->f_int + job->fe_offset);
  }
  cupid_job_phase_end(job, CUPID_PHASE_SOLVE, t0);
  cupid_job_progress(job, "evaluate: internal forces of the imposed field computed");
  return CUPID_SUCCESS;
}

/* Name the node (PD) or beam node and expansion term (FE) where a factorisation broke
 * down (exit status 2). */
static cupid_status explain_singular(const cupid_job *job, cupid_status st) {
  cupid_int dof = job->solve.failed_dof;
  if (dof < 0 || dof >= job->ndof) return st;
  char msg[1024];
  snprintf(msg, sizeof msg, "%s", cupid_error_message());
  char comp = "xyz"[dof % 3];
  if (!job->beam || dof < job->fe_offset) {
    const double *x = cupid_pd_grid_coords(job->grid);
    cupid_int node = dof / 3;
    return CUPID_ERROR(st,
                       "%s; PD node %lld at (%g, %g, %g), component %c: check that every PD "
                       "region is constrained against rigid motion (fix, clamp or displacement)",
                       msg, (long long)node, x[3 * node], x[3 * node + 1], x[3 * node + 2], comp);
  }
  cupid_int fe_node = (dof - job->fe_offset) / 3, M = job->fe_info.M;
  cupid_int beam_node = fe_node / M;
  return CUPID_ERROR(st,
                     "%s; beam node %lld at y = %g, expansion term %lld, component %c: check "
                     "that the beam is clamped or fixed against rigid motion",
                     msg, (long long)beam_node, cupid_cuf_beam_node_y(job->beam, beam_node),
                     (long long)(fe_node % M), comp);
}

static cupid_status require_constraints(const cupid_job *job) {
  int fixed[3] = {0, 0, 0};
  for (cupid_int d = 0; d < job->ndof; d++)
    if (job->bc->fixed[d]) fixed[d % 3] = 1;
  if (job->slab)
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

/* `static` on a 3D PD-only model with PETSc: K is never assembled (cupid_petsc_solve_pd). */
static cupid_status run_static_matrix_free(cupid_job *job) {
  cupid_status st = cupid_petsc_solve_pd(job->op, job->grid, job->pd_materials, job->f_ext,
                                         job->bc, job->u, &job->solve);
  job->phases[CUPID_PHASE_FACTORISATION] =
      (cupid_phase_record){job->solve.time_factor, cupid_peak_memory(), 1};
  job->phases[CUPID_PHASE_SOLVE] = (cupid_phase_record){job->solve.time_solve, cupid_peak_memory(), 1};
  CUPID_CALL(st);
  job->solved = 1;
  cupid_job_progress(job, "solve: PETSc matrix-free, %s + %s, %d iterations on %d rank%s, "
                     "%lld equations, residual %.2e", job->solve.ksp_type, job->solve.pc_type,
                     job->solve.iterations, job->solve.ranks, job->solve.ranks == 1 ? "" : "s",
                     (long long)job->solve.n, job->solve.residual);
  if (!job->slab) return cupid_pd_operator_apply(job->op, job->u, job->f_int);
  /* A slab: K u of its owned rows (u holds their dependency range), then rank 0 gathers. */
  const cupid_int a = job->part.owned_first, b = job->part.owned_last;
  CUPID_CALL(cupid_pd_operator_apply_range(job->op, a, b, job->u, job->f_int + 3 * a));
  return cupid_app_slab_collect(job);
}

/* `static`: assemble K, solve K u = f with the Dirichlet conditions, reactions. */
static cupid_status run_static(cupid_job *job) {
  double t0 = cupid_wtime();
  CUPID_CALL(require_constraints(job));
  if (matrix_free(job)) return run_static_matrix_free(job);
  CUPID_CALL(cupid_app_estimate(job, 0));
  if (job->grid)
    CUPID_CALL(cupid_pd_operator_assemble(job->op, &job->K));
  else
    CUPID_CALL(cupid_cuf_assemble(job->beam, &job->K));
  cupid_job_phase_end(job, CUPID_PHASE_ASSEMBLY, t0);
  cupid_job_progress(job, "assembly: %lld non-zeros (%.1f MB)", (long long)cupid_csr_nnz(job->K),
                     (double)cupid_csr_bytes(job->K) / 1e6);

  cupid_status st = cupid_app_linear_solve(job, CUPID_MATRIX_SPD);
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

/* Resultants of the applied loads and of the reactions (K u - f on constrained DOFs): each
 * is the work against a unit translation, whose generalised DOFs are 1 on PD nodes and the
 * interpolated constant field on the beam (for TE only the constant term carries it). */
static cupid_status sum_forces(cupid_job *job) {
  double *t = NULL;
  CUPID_CALL(cupid_calloc((size_t)(3 * job->ndof), sizeof *t, "translation vectors", &t));
  cupid_status st = cupid_app_translations(job, t);
  for (int k = 0; k < 3 && st == CUPID_SUCCESS; k++) {
    const double *tk = t + (size_t)k * (size_t)job->ndof;
    double load = 0.0, reaction = 0.0;
    for (cupid_int d = 0; d < job->ndof; d++) {
      load += job->f_ext[d] * tk[d];
      if (job->bc->fixed[d]) reaction += (job->f_int[d] - job->f_ext[d]) * tk[d];
    }
    job->load_sum[k] = load;
    job->reaction_sum[k] = reaction;
  }
  cupid_free(&t);
  return st;
}

void cupid_app_job_destroy(cupid_job *job) {
  cupid_coupling_destroy(&job->coupling);
  cupid_pd_operator_destroy(&job->op);
  cupid_pd_grid_destroy(&job->grid);
  cupid_cuf_beam_destroy(&job->beam);
  cupid_csr_destroy(&job->K);
  cupid_dirichlet_destroy(&job->bc);
  cupid_free(&job->u);
  cupid_free(&job->f_ext);
  cupid_free(&job->f_int);
  cupid_free(&job->pd_stress);
  cupid_free(&job->pd_materials);
  cupid_free(&job->arlequin_regions);
}

cupid_status cupid_run_model(const cupid_model_t *model, const cupid_run_options *opts) {
  /* Under MPI every rank runs the pipeline, on the replicated model or on its slab of the PD
   * grid (slab.c); rank 0 speaks and writes. */
  int rank = cupid_petsc_rank();
  cupid_job job = {.model = model, .opts = opts, .quiet = opts->quiet || !isatty(2) || rank != 0};
  cupid_status st = CUPID_SUCCESS;
  job.t_start = cupid_wtime();
  job.outdir = opts->output_dir ? opts->output_dir : model->output.directory;
  cupid_set_num_threads(opts->threads);

  CUPID_TRY(check_supported(&job));
  CUPID_TRY(check_petsc_request(&job));
  CUPID_TRY(cupid_app_guard_size(&job)); /* before anything that scales with the model */
  job.slab = cupid_app_slab_wanted(&job);
  if (model->has_peridynamics) {
    st = build_pd(&job);
    CUPID_TRY(job.slab ? cupid_app_slab_agree(st) : st);
  }
  if (model->has_beam) CUPID_TRY(cupid_app_fe_build(&job));
  if (cupid_app_is_coupled(&job)) CUPID_TRY(cupid_app_coupled_prepare(&job));
  job.fe_offset = 3 * job.n_pd;
  job.ndof = job.fe_offset + job.n_fe_dofs;
  CUPID_TRY(job.slab ? cupid_app_slab_check_points(&job) : cupid_app_check_points(&job));
  if (!opts->check_only) {
    CUPID_TRY(cupid_app_choose_solver(&job));
    cupid_job_progress(&job, "solver: %s (%s)", job.solver == CUPID_SOLVER_PETSC ? "petsc" : "direct",
                       job.solver_reason);
  }
  if (opts->check_only) {
    st = cupid_app_estimate(&job, 1);
    goto cleanup;
  }
  CUPID_TRY(allocate_fields(&job));
  if (cupid_app_is_coupled(&job)) {
    CUPID_TRY(cupid_app_coupled_run(&job));
  } else if (model->analysis.type == CUPID_ANALYSIS_EVALUATE) {
    CUPID_TRY(run_evaluate(&job));
  } else {
    if (job.grid) CUPID_TRY(cupid_app_pd_constraints(&job));
    if (job.beam) CUPID_TRY(cupid_app_fe_constraints(&job));
    CUPID_TRY(cupid_dirichlet_finalize(job.bc));
    if (job.grid) {
      st = cupid_app_pd_loads(&job);
      CUPID_TRY(job.slab ? cupid_app_slab_agree(st) : st);
    }
    if (job.beam) CUPID_TRY(cupid_app_fe_loads(&job));
    if (model->analysis.type == CUPID_ANALYSIS_DYNAMIC) CUPID_TRY(cupid_app_run_dynamic(&job));
    else CUPID_TRY(run_static(&job));
  }
  if (job.slab) goto cleanup; /* a slab rank other than 0: rank 0 writes (slab.c) */
  CUPID_TRY(sum_forces(&job));
  if (rank == 0) CUPID_TRY(cupid_app_write_outputs(&job));
  cupid_job_progress(&job, "done: results in %s", job.outdir);
cleanup:
  cupid_app_job_destroy(&job);
  return st;
}
