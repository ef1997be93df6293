/* Coupled models (beam + peridynamics) inside a run: the beam gives way inside the PD regions,
 * constraints and loads go to the part they touch, the coupled matrix of paper 000 Eq. 38
 * (src/coupling) is solved by UMFPACK (it is not symmetric). Methods: fictitious (default) and
 * lagrange (eliminated, SPD, CHOLMOD; also in dynamics: cupid_app_run_dynamic() with the tied
 * PD masses carried by the beam); arlequin dispatches to coupled_arlequin.c. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "app_internal.h"
#include "coupled_setup.h"
#include "coupled_arlequin.h"
#include "cupid/coupling.h"


int cupid_app_is_coupled(const cupid_job *job) {
  return job->model->has_beam && job->model->has_peridynamics;
}

cupid_status cupid_app_coupled_check(const cupid_job *job) {
  const cupid_model_t *m = job->model;
  if (cupid_app_is_arlequin(job)) return cupid_app_arlequin_check(job); /* coupled_arlequin.c */
  /* Lagrange ties nodes to the beam field, whatever the grid's dimension (a 1D grid: a bar
   * along the axis, its nodes on the axis); the fictitious nodes and elements need 3D. */
  if (m->pd.dimension != 3 && m->coupling.method != CUPID_COUPLING_LAGRANGE)
    return cupid_model_error(m, &m->pd.mark,
                             "a coupled model needs a 3D peridynamic grid (dimension: 3) with "
                             "method fictitious (1D grids: methods lagrange and arlequin)");
  if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC && m->coupling.method != CUPID_COUPLING_LAGRANGE)
    return cupid_model_error(m, &m->analysis.mark,
                             "type dynamic is not supported with coupling method fictitious: its "
                             "coupled operator (paper 000 Eq. 38) is a static, non-symmetric "
                             "construction with massless fictitious nodes (see docs/dynamics.md); "
                             "use `coupling: {method: lagrange}` or `{method: arlequin}` for "
                             "coupled dynamics, or type static or evaluate");
  if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC) return cupid_app_dynamic_check(job);
  return CUPID_SUCCESS;
}

/* The beam gives way inside every PD region (region by region, so errors name the region). */
cupid_status cupid_app_coupled_prepare(cupid_job *job) {
  const cupid_model_t *m = job->model;
  if (cupid_app_is_arlequin(job)) return cupid_app_arlequin_prepare(job); /* the beam stays */
  for (int r = 0; r < m->pd.n_regions; r++) {
    cupid_status st = cupid_coupling_deactivate(job->beam, 1, &m->pd.regions[r].box);
    if (st != CUPID_SUCCESS) {
      char msg[1024];
      const char *e = cupid_error_message();
      /* The library names the region "PD region 0" (it saw one box); the mark names it here. */
      const char *tail = strstr(e, "PD region 0");
      if (tail) {
        tail += strlen("PD region 0");
        if (*tail == ':') tail++;
        while (*tail == ' ') tail++;
      }
      snprintf(msg, sizeof msg, "%s", tail ? tail : e);
      st = cupid_model_error(m, &m->pd.regions[r].mark, "%s", msg);
      return st;
    }
  }
  return CUPID_SUCCESS;
}

/* ------------------------------------------------------------ constraints and loads */

static int is_lagrange(const cupid_job *job) {
  return job->model->coupling.method == CUPID_COUPLING_LAGRANGE;
}

cupid_status cupid_app_coupled_apply_constraints(cupid_job *job) {
  const cupid_model_t *m = job->model;
  cupid_status st = CUPID_SUCCESS;
  cupid_constraint *pd = NULL;
  int npd = 0;
  CUPID_CALL(cupid_calloc((size_t)m->n_constraints + 1, sizeof *pd, "PD constraints", &pd));
  for (int k = 0; k < m->n_constraints; k++) {
    const cupid_constraint *c = &m->constraints[k];
    int on_fe, on_pd;
    if (c->kind == CUPID_CONSTRAINT_CLAMP) {
      on_fe = cupid_app_fe_node_at(job, c->plane_y);
      on_pd = !on_fe;
    } else {
      on_fe = cupid_app_fe_node_in_box(job, &c->box);
      on_pd = cupid_app_pd_node_in_box(job, &c->box);
    }
    if (!on_fe && !on_pd) {
      st = cupid_model_error(m, &c->mark,
                             "the constraint touches neither the beam (outside the PD regions) "
                             "nor a PD node");
      goto cleanup;
    }
    if (on_fe) CUPID_TRY(cupid_cuf_constraint_apply(job->beam, m, c, job->bc));
    if (on_pd) pd[npd++] = *c;
  }
  CUPID_TRY(cupid_app_pd_stage(job, pd, npd, NULL, 0, 1));
  /* FE nodes inside the PD regions carry no stiffness: hold them at zero. */
  for (cupid_int n = 0; n < job->fe_info.n_fe_nodes; n++) {
    int tau = (int)(n % job->fe_info.M);
    if (cupid_cuf_node_used(job->beam, tau, n / job->fe_info.M)) continue;
    for (int c = 0; c < 3; c++) CUPID_TRY(cupid_dirichlet_fix(job->bc, job->fe_offset + 3 * n + c, 0.0));
  }
cleanup:
  cupid_free(&pd);
  return st;
}

cupid_status cupid_app_coupled_apply_loads(cupid_job *job) {
  const cupid_model_t *m = job->model;
  cupid_status st = CUPID_SUCCESS;
  cupid_load *pd = NULL;
  int npd = 0;
  CUPID_CALL(cupid_calloc((size_t)m->n_loads + 1, sizeof *pd, "PD loads", &pd));
  for (int k = 0; k < m->n_loads; k++) {
    const cupid_load *l = &m->loads[k];
    int on_fe = 0, on_pd = 0;
    switch (l->kind) {
    case CUPID_LOAD_TRACTION: on_fe = cupid_app_fe_node_at(job, l->plane_y); on_pd = !on_fe; break;
    case CUPID_LOAD_POINT:
      on_fe = cupid_cuf_contains(job->beam, l->at[0], l->at[1], l->at[2]);
      on_pd = !on_fe;
      break;
    case CUPID_LOAD_BODY:
      on_fe = cupid_app_fe_node_in_box(job, &l->box);
      on_pd = cupid_app_pd_node_in_box(job, &l->box);
      break;
    }
    if (on_fe) CUPID_TRY(cupid_cuf_load_add(job->beam, m, l, job->f_ext));
    if (on_pd) pd[npd++] = *l;
  }
  CUPID_TRY(cupid_app_pd_stage(job, NULL, 0, pd, npd, 0));
  /* Lagrange: a load on a tied PD node acts on the beam through the tie (T^T f). */
  if (is_lagrange(job)) cupid_coupling_lagrange_load(job->coupling, job->f_ext);
cleanup:
  cupid_free(&pd);
  return st;
}

/* ----------------------------------------------------------------------- assembly */

/* The coupling's options from the model; *boxes and *mats (one per region) are the caller's
 * to free, also after a failure. */
static cupid_status coupling_options(const cupid_job *job, cupid_coupling_options *co,
                                     cupid_box **boxes, int **mats) {
  const cupid_model_t *m = job->model;
  const int nr = m->pd.n_regions;
  CUPID_CALL(cupid_calloc((size_t)nr, sizeof **boxes, "region boxes", boxes));
  CUPID_CALL(cupid_calloc((size_t)nr, sizeof **mats, "region materials", mats));
  for (int r = 0; r < nr; r++) {
    (*boxes)[r] = m->pd.regions[r].box;
    (*mats)[r] = m->pd.regions[r].material;
  }
  *co = (cupid_coupling_options){.beam_def = &m->beam,
                                 .materials = m->materials,
                                 .n_materials = m->n_materials,
                                 .n_regions = nr,
                                 .regions = *boxes,
                                 .region_materials = *mats,
                                 .spacing = m->pd.spacing,
                                 .pd = job->pd_options};
  return CUPID_SUCCESS;
}

static cupid_status assemble(cupid_job *job) {
  double t0 = cupid_wtime();
  cupid_status st = CUPID_SUCCESS;
  cupid_box *boxes = NULL;
  int *mats = NULL;
  cupid_coupling_options co;
  CUPID_TRY(coupling_options(job, &co, &boxes, &mats));
  if (is_lagrange(job))
    CUPID_TRY(cupid_coupling_lagrange_create(job->beam, job->grid, &co, &job->coupling, &job->K));
  else
    CUPID_TRY(cupid_coupling_create(job->beam, job->grid, &co, &job->coupling, &job->K));
  cupid_coupling_info ci;
  cupid_coupling_get_info(job->coupling, &ci);
  job->n_fictitious = ci.n_fictitious_pd;
  cupid_job_phase_end(job, CUPID_PHASE_COUPLING, t0);
  if (is_lagrange(job)) {
    const cupid_int *tied;
    cupid_int nt;
    cupid_coupling_tied(job->coupling, &tied, &nt);
    cupid_job_progress(job, "coupling (Lagrange multipliers, eliminated): %d interfaces, %lld "
                       "tied PD nodes; %lld non-zeros (%.1f MB)", ci.n_interfaces, (long long)nt,
                       (long long)cupid_csr_nnz(job->K), (double)cupid_csr_bytes(job->K) / 1e6);
  } else {
    cupid_job_progress(job,
                       "coupling (fictitious nodes): %d interfaces, %lld fictitious PD nodes, "
                       "%lld fictitious FE nodes; %lld non-zeros (%.1f MB)",
                       ci.n_interfaces, (long long)ci.n_fictitious_pd,
                       (long long)ci.n_fictitious_fe, (long long)cupid_csr_nnz(job->K),
                       (double)cupid_csr_bytes(job->K) / 1e6);
  }
cleanup:
  cupid_free(&boxes);
  cupid_free(&mats);
  return st;
}

static cupid_status evaluate(cupid_job *job) {
  const cupid_model_t *m = job->model;
  const double *x = cupid_pd_grid_coords(job->grid);
  for (cupid_int i = 0; i < job->n_pd; i++)
    for (int c = 0; c < 3; c++)
      job->u[3 * i + c] =
          cupid_value_eval(&m->analysis.field[c], x[3 * i], x[3 * i + 1], x[3 * i + 2], 0.0, 0.0);
  CUPID_CALL(cupid_app_fe_impose_field(job));
  /* FE nodes inside the PD regions are not part of the model. */
  for (cupid_int n = 0; n < job->fe_info.n_fe_nodes; n++)
    if (!cupid_cuf_node_used(job->beam, (int)(n % job->fe_info.M), n / job->fe_info.M))
      for (int c = 0; c < 3; c++) job->u[job->fe_offset + 3 * n + c] = 0.0;
  CUPID_CALL(assemble(job));
  cupid_csr_matvec(job->K, job->u, job->f_int);
  cupid_job_progress(job, "evaluate: internal forces of the imposed field computed");
  return CUPID_SUCCESS;
}

/* |R + P| / |P| along y (the axis; x, z printed too): the fictitious-node method does not
 * conserve momentum (docs/coupling.md), so the imbalance is a figure of merit of the run. */
static cupid_status print_equilibrium(const cupid_job *job) {
  double *t = NULL, load[3], reac[3];
  CUPID_CALL(cupid_calloc((size_t)(3 * job->ndof), sizeof *t, "translation vectors", &t));
  cupid_status st = cupid_app_translations(job, t);
  for (int k = 0; k < 3; k++) {
    const double *tk = t + (size_t)k * (size_t)job->ndof;
    load[k] = reac[k] = 0.0;
    for (cupid_int d = 0; d < job->ndof; d++) {
      load[k] += job->f_ext[d] * tk[d];
      if (job->bc->fixed[d]) reac[k] += (job->f_int[d] - job->f_ext[d]) * tk[d];
    }
  }
  cupid_free(&t);
  CUPID_CALL(st);
  double pn = sqrt(load[0] * load[0] + load[1] * load[1] + load[2] * load[2]);
  double in = sqrt((load[0] + reac[0]) * (load[0] + reac[0]) + (load[1] + reac[1]) * (load[1] + reac[1]) +
                   (load[2] + reac[2]) * (load[2] + reac[2]));
  cupid_job_progress(job, "equilibrium: load (%.6g, %.6g, %.6g), reaction (%.6g, %.6g, %.6g), "
                     "|R + P| / |P| = %.3e", load[0], load[1], load[2], reac[0], reac[1], reac[2],
                     pn > 0 ? in / pn : in);
  return CUPID_SUCCESS;
}

static cupid_status solve(cupid_job *job) {
  /* Eq. 38 is not symmetric (UMFPACK); the eliminated Lagrange system is SPD (CHOLMOD). */
  cupid_status st =
      cupid_app_linear_solve(job, is_lagrange(job) ? CUPID_MATRIX_SPD : CUPID_MATRIX_GENERAL);
  job->phases[CUPID_PHASE_FACTORISATION] =
      (cupid_phase_record){job->solve.time_factor, cupid_peak_memory(), 1};
  job->phases[CUPID_PHASE_SOLVE] =
      (cupid_phase_record){job->solve.time_solve, cupid_peak_memory(), 1};
  CUPID_CALL(st);
  job->solved = 1;
  if (is_lagrange(job)) cupid_coupling_recover(job->coupling, job->u);
  cupid_csr_matvec(job->K, job->u, job->f_int);
  cupid_job_progress(job, "solve: %s, %lld equations, residual %.2e", job->solve.method,
                     (long long)job->solve.n, job->solve.residual);
  if (!job->quiet) CUPID_CALL(print_equilibrium(job));
  return CUPID_SUCCESS;
}

/* --solver petsc: the fictitious-node system (Eq. 38) without the PD matrix, GMRES
 * preconditioned by the LU of a cheap bond-based twin (src/coupling/operator.c, krylov.c;
 * issue 6), on one rank or several (the PD grid in z slabs, slab.c; MUMPS's parallel LU). The PETSc option
 * -cupid_coupled_assembled takes the assembled path instead (solve(): Eq. 38 assembled, its
 * rows split over the ranks, GMRES + block Jacobi/ILU). */
int cupid_app_coupled_matrix_free(const cupid_job *job) {
  return job->solver == CUPID_SOLVER_PETSC && !cupid_app_is_arlequin(job) && !is_lagrange(job) &&
         job->model->analysis.type == CUPID_ANALYSIS_STATIC && job->grid &&
         cupid_pd_grid_dimension(job->grid) == 3 &&
         !cupid_petsc_has_option("-cupid_coupled_assembled");
}

static cupid_status solve_matrix_free(cupid_job *job) {
  cupid_status st = CUPID_SUCCESS;
  cupid_box *boxes = NULL;
  int *mats = NULL;
  cupid_coupling_options co;
  CUPID_TRY(coupling_options(job, &co, &boxes, &mats));
  /* MUMPS: PETSc's UMFPACK interface has 32-bit indices and ran out of them at 10^5 PD
   * nodes (bench/README_coupled.md); -pc_factor_mat_solver_type overrides it. */
  cupid_coupling_krylov_options ko = {.factor_package = "mumps"};
  CUPID_TRY(cupid_app_coupled_solve_mf(job, &co, &ko));
  if (!job->quiet && !job->slab) CUPID_TRY(print_equilibrium(job)); /* a slab: rank 0 is whole */
cleanup:
  cupid_free(&boxes);
  cupid_free(&mats);
  return st;
}

cupid_status cupid_app_coupled_run(cupid_job *job) {
  if (cupid_app_is_arlequin(job)) return cupid_app_arlequin_run(job);
  if (job->model->analysis.type == CUPID_ANALYSIS_EVALUATE) return evaluate(job);
  CUPID_CALL(cupid_app_estimate(job, 0));
  if (cupid_app_coupled_matrix_free(job)) {
    CUPID_CALL(cupid_app_coupled_apply_constraints(job));
    CUPID_CALL(cupid_dirichlet_finalize(job->bc));
    CUPID_CALL(cupid_app_coupled_apply_loads(job));
    return solve_matrix_free(job);
  }
  CUPID_CALL(assemble(job));
  CUPID_CALL(cupid_app_coupled_apply_constraints(job));
  if (is_lagrange(job)) { /* tied PD nodes follow the beam: eliminated, recovered after */
    const cupid_int *tied;
    cupid_int nt;
    cupid_coupling_tied(job->coupling, &tied, &nt);
    for (cupid_int t = 0; t < nt; t++)
      for (int c = 0; c < 3; c++) CUPID_CALL(cupid_dirichlet_fix(job->bc, 3 * tied[t] + c, 0.0));
  }
  CUPID_CALL(cupid_dirichlet_finalize(job->bc));
  CUPID_CALL(cupid_app_coupled_apply_loads(job));
  if (job->model->analysis.type == CUPID_ANALYSIS_DYNAMIC) { /* Lagrange only (checked) */
    CUPID_CALL(cupid_app_run_dynamic(job));
    cupid_coupling_recover(job->coupling, job->u);
    cupid_csr_matvec(job->K, job->u, job->f_int);
    return CUPID_SUCCESS;
  }
  return solve(job);
}
