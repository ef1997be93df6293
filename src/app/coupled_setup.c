/* A fictitious-node coupled model set up to its linear system for the matrix-free solve
 * (coupled_setup.h): the stages of `cupid run` (run.c, coupled.c) that do not assemble. The
 * constraint and load split repeats coupled.c's (static there). */
#include <stdio.h>
#include <string.h>

#include "coupled_setup.h"

static cupid_status setup_pd(cupid_job *job) {
  const cupid_model_t *m = job->model;
  double t0 = cupid_wtime();
  CUPID_CALL(cupid_pd_grid_create_from_model(m, &job->grid));
  job->n_pd = cupid_pd_grid_num_nodes(job->grid);
  CUPID_CALL(cupid_app_pd_options(job)); /* run.c */
  cupid_job_phase_end(job, CUPID_PHASE_GRID, t0);
  return CUPID_SUCCESS;
}

static cupid_status setup_constraints(cupid_job *job) {
  CUPID_CALL(cupid_app_coupled_apply_constraints(job));
  return cupid_dirichlet_finalize(job->bc);
}

cupid_status cupid_app_coupled_setup(const cupid_model_t *model, const cupid_run_options *opts,
                                     cupid_coupled_setup *s) {
  memset(s, 0, sizeof *s);
  cupid_job *job = &s->job;
  job->model = model;
  job->opts = opts;
  job->quiet = 1;
  job->t_start = cupid_wtime();
  job->outdir = opts->output_dir ? opts->output_dir : model->output.directory;
  CUPID_CHECK(cupid_app_is_coupled(job) && model->coupling.method == CUPID_COUPLING_FICTITIOUS &&
                  model->analysis.type == CUPID_ANALYSIS_STATIC && model->pd.dimension == 3,
              CUPID_ERR_UNSUPPORTED,
              "the matrix-free coupled solve takes static beam + 3D peridynamics models with "
              "coupling method fictitious");
  CUPID_CALL(setup_pd(job));
  CUPID_CALL(cupid_app_fe_build(job));
  CUPID_CALL(cupid_app_coupled_prepare(job));
  job->fe_offset = 3 * job->n_pd;
  job->ndof = job->fe_offset + job->n_fe_dofs;
  CUPID_CALL(cupid_app_check_points(job));
  size_t n = (size_t)job->ndof;
  CUPID_CALL(cupid_calloc(n, sizeof(double), "displacements", &job->u));
  CUPID_CALL(cupid_calloc(n, sizeof(double), "applied loads", &job->f_ext));
  CUPID_CALL(cupid_calloc(n, sizeof(double), "internal forces", &job->f_int));
  CUPID_CALL(cupid_dirichlet_create(job->ndof, &job->bc));
  CUPID_CALL(setup_constraints(job));
  CUPID_CALL(cupid_app_coupled_apply_loads(job));
  int nr = model->pd.n_regions;
  CUPID_CALL(cupid_calloc((size_t)nr, sizeof *s->boxes, "region boxes", &s->boxes));
  CUPID_CALL(cupid_calloc((size_t)nr, sizeof *s->mats, "region materials", &s->mats));
  for (int r = 0; r < nr; r++) {
    s->boxes[r] = model->pd.regions[r].box;
    s->mats[r] = model->pd.regions[r].material;
  }
  s->co = (cupid_coupling_options){.beam_def = &model->beam,
                                   .materials = model->materials,
                                   .n_materials = model->n_materials,
                                   .n_regions = nr,
                                   .regions = s->boxes,
                                   .region_materials = s->mats,
                                   .spacing = model->pd.spacing,
                                   .pd = job->pd_options};
  return CUPID_SUCCESS;
}

void cupid_app_coupled_setup_free(cupid_coupled_setup *s) {
  cupid_app_job_destroy(&s->job);
  cupid_free(&s->boxes);
  cupid_free(&s->mats);
}

/* Record a matrix-free Krylov solve in the job: job->solve and the factorisation / solve
 * phases. */
static void record_krylov(cupid_job *job, const cupid_coupling_krylov_info *ki) {
  job->phases[CUPID_PHASE_FACTORISATION] =
      (cupid_phase_record){ki->time_setup, cupid_peak_memory(), 1};
  job->phases[CUPID_PHASE_SOLVE] = (cupid_phase_record){ki->time_solve, cupid_peak_memory(), 1};
  job->solve.method = "petsc"; /* matrix_free, ksp_type and pc_type tell the path */
  job->solve.n = job->bc->n_free;
  if (job->slab) { /* the owned free DOFs of every slab, and the FE ones once */
    cupid_int own = 0;
    for (cupid_int d = 0; d < job->ndof; d++)
      own += !job->bc->fixed[d] && (d >= job->fe_offset ? cupid_petsc_rank() == 0
                                                        : cupid_app_pd_owned(job, d / 3));
    job->solve.n = cupid_app_global_count(job, own);
  }
  job->solve.residual = ki->residual;
  job->solve.time_factor = ki->time_setup;
  job->solve.time_solve = ki->time_solve;
  job->solve.failed_dof = -1;
  job->solve.iterations = ki->iterations;
  job->solve.ranks = cupid_petsc_size();
  job->solve.matrix_free = 1;
  const char *pc = strchr(ki->method, '+'); /* ki->method is "<ksp>+<pc>" */
  snprintf(job->solve.ksp_type, sizeof job->solve.ksp_type, "%.*s",
           pc ? (int)(pc - ki->method) : 31, ki->method);
  snprintf(job->solve.pc_type, sizeof job->solve.pc_type, "%.31s", pc ? pc + 1 : ki->method);
  snprintf(job->solve.converged_reason, sizeof job->solve.converged_reason, "%s",
           ki->converged ? "CONVERGED" : "DIVERGED");
}

cupid_status cupid_app_krylov_solve(cupid_job *job, const cupid_linear_operator *L,
                                    const cupid_csr_t *P, const cupid_coupling_krylov_options *ko) {
  cupid_coupling_krylov_info ki;
  cupid_status st = cupid_krylov_solve(L, P, job->bc, job->f_ext, job->u, ko, &ki);
  record_krylov(job, &ki);
  CUPID_CALL(st);
  job->solved = 1;
  CUPID_CALL(cupid_krylov_apply(L, job->u, job->f_int)); /* a slab: owned and FE rows */
  cupid_job_progress(job, "solve: %s, %lld equations, %d iterations, residual %.2e", ki.method,
                     (long long)job->solve.n, ki.iterations, ki.residual);
  return CUPID_SUCCESS;
}

cupid_status cupid_app_coupled_solve_mf(cupid_job *job, const cupid_coupling_options *co,
                                        const cupid_coupling_krylov_options *ko) {
  cupid_status st = CUPID_SUCCESS;
  cupid_coupling_operator A = NULL;
  cupid_csr P = NULL;
  double t0 = cupid_wtime();
  /* a slab (job->slab): every rank's failure stops all of them before the next collective */
  st = cupid_coupling_operator_create(job->beam, job->grid, co, &A);
  if (st == CUPID_SUCCESS) st = cupid_coupling_preconditioner(A, 1.5, &P);
  CUPID_TRY(job->slab ? cupid_app_slab_agree(st) : st);
  cupid_coupling_info ci; /* the whole model's, on a slab too */
  cupid_coupling_operator_get_info(A, &ci);
  job->n_fictitious = ci.n_fictitious_pd;
  cupid_job_phase_end(job, CUPID_PHASE_COUPLING, t0);
  cupid_job_progress(job,
                     "coupling (fictitious nodes, matrix-free): %d interfaces, %lld fictitious PD "
                     "nodes, %lld fictitious FE nodes; operator %.1f MB, preconditioner matrix "
                     "%.1f MB%s",
                     ci.n_interfaces, (long long)ci.n_fictitious_pd, (long long)ci.n_fictitious_fe,
                     (double)cupid_coupling_operator_bytes(A) / 1e6, (double)cupid_csr_bytes(P) / 1e6,
                     job->slab ? " (rank 0's slab)" : "");
  cupid_linear_operator L;
  cupid_coupling_operator_linear(A, &L); /* on a slab: its rows (cupid_krylov_solve) */
  CUPID_TRY(cupid_app_krylov_solve(job, &L, P, ko));
  if (job->slab) { /* rank 0 gathers the slabs into the whole model; the others stop */
    cupid_csr_destroy(&P);
    cupid_coupling_operator_destroy(&A);
    CUPID_TRY(cupid_app_slab_collect(job));
  }
cleanup:
  cupid_csr_destroy(&P);
  cupid_coupling_operator_destroy(&A);
  return st;
}
