/* Coupled models with `coupling: {method: arlequin}` inside a run (paper 004 section 3;
 * src/coupling/arlequin.c for the method). Layouts supported: the beam and one PD region (LPS
 * or bond-based, 1D or 3D) overlap on [lo, hi] = the `overlap` box's y range (its x/z bounds
 * are not used: every PD node of that y range is tied and must lie in the beam); or, with
 * `overlap` a list of two boxes, the PD region sits inside the beam with one overlap at each
 * end and the beam gives way between them (the coupled bar). The PD region starts
 * on one edge of the overlap and extends beyond the other; the beam extends beyond the first
 * edge and either ends on the second (beam [0, 0.6], PD [0.4, 1], overlap [0.4, 0.6]: nothing
 * is deactivated) or runs on inside the PD region, where it gives way (beam [0, 1]: the pairs
 * on [0.6, 1] are made inactive, their FE nodes held at zero). Constraints and loads go to
 * the part they touch; body and point loads reaching into an overlap are shared, alpha to the
 * beam and 1 - alpha to the PD nodes (a traction inside an overlap acts on no free surface:
 * refused). Static (CHOLMOD, or PETSc CG + GAMG: the system is symmetric), evaluate, and
 * dynamic runs (through cupid_app_run_dynamic() with the weighted masses of
 * cupid_app_arlequin_mass()). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "coupled_arlequin.h"

#define ARL_TOL 1e-9

int cupid_app_is_arlequin(const cupid_job *job) {
  const cupid_model_t *m = job->model;
  return m->has_beam && m->has_peridynamics && m->coupling.method == CUPID_COUPLING_ARLEQUIN;
}

cupid_status cupid_app_arlequin_check(const cupid_job *job) {
  const cupid_model_t *m = job->model;
  const cupid_coupling *c = &m->coupling;
  if (m->pd.n_regions != 1)
    return cupid_model_error(m, &m->pd.mark,
                             "method arlequin supports one PD region (this model has %d)",
                             m->pd.n_regions);
  if (!c->overlap.has[1] || (c->n_overlaps == 2 && !c->overlap2.has[1]))
    return cupid_model_error(m, &c->mark, "coupling.arlequin.overlap needs a y range");
  if (m->beam.integration == CUPID_CUF_MITC)
    return cupid_model_error(m, &c->mark,
                             "method arlequin: MITC beam integration is not yet supported (use "
                             "full or reduced)");
  if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC) return cupid_app_dynamic_check(job);
  return CUPID_SUCCESS;
}

/* The overlaps of the model in ascending y (two: one at each end of the PD region). */
static int overlaps(const cupid_coupling *c, const cupid_box *ov[2]) {
  ov[0] = &c->overlap;
  ov[1] = &c->overlap2;
  if (c->n_overlaps != 2) return 1;
  if (c->overlap2.lo[1] < c->overlap.lo[1]) ov[0] = &c->overlap2, ov[1] = &c->overlap;
  return 2;
}

/* The options of the run: the overlaps, which side is FE-only, the weight and the penalty. */
static cupid_arlequin_options options(const cupid_job *job) {
  const cupid_coupling *c = &job->model->coupling;
  const cupid_box *ov[2];
  int n = overlaps(c, ov);
  cupid_arlequin_options o = {.weight = {.lo = ov[0]->lo[1], .hi = ov[0]->hi[1], .kind = c->weight},
                              .penalty = c->penalty,
                              .n_overlaps = n};
  /* the PD region starts on the overlap's lower edge: the FE-only side is below */
  double tol = ARL_TOL * (job->fe_info.y_max - job->fe_info.y_min);
  o.weight.fe_below = job->model->pd.regions[0].box.lo[1] >= o.weight.lo - tol;
  if (n == 2) /* the PD region between the two: FE-only below the first, above the second */
    o.weight.fe_below = 1,
    o.second = (cupid_arlequin_weight){.lo = ov[1]->lo[1], .hi = ov[1]->hi[1], .fe_below = 0,
                                       .kind = c->weight};
  return o;
}

static int close_to(double a, double b, double scale) { return fabs(a - b) <= ARL_TOL * scale; }

/* The weight has kinks at the overlap bounds: they must be beam nodes (element ends) for the
 * axis quadrature to be exact. */
static cupid_status bounds_on_nodes(const cupid_job *job, const double *ends, int n) {
  for (int k = 0; k < n; k++)
    if (cupid_cuf_beam_node_at(job->beam, ends[k]) < 0)
      return cupid_model_error(job->model, &job->model->coupling.mark,
                               "the overlap bound y = %g is not a beam-node position: move it "
                               "to an element end (the weight's kinks must fall between "
                               "elements)",
                               ends[k]);
  return CUPID_SUCCESS;
}

/* Two overlaps: the PD region spans from the lower edge of the first to the upper edge of the
 * second, the beam reaches beyond both, and gives way between them. */
static cupid_status prepare_two(cupid_job *job) {
  const cupid_model_t *m = job->model;
  const cupid_mark *mk = &m->coupling.mark;
  const cupid_box *ov[2];
  overlaps(&m->coupling, ov);
  double lo1 = ov[0]->lo[1], hi1 = ov[0]->hi[1], lo2 = ov[1]->lo[1], hi2 = ov[1]->hi[1];
  double b0 = job->fe_info.y_min, b1 = job->fe_info.y_max, L = b1 - b0, tol = ARL_TOL * L;
  const cupid_box *r = &m->pd.regions[0].box;
  if (hi1 > lo2 + tol)
    return cupid_model_error(m, mk, "the two overlaps y in [%g, %g] and [%g, %g] overlap each other",
                             lo1, hi1, lo2, hi2);
  if (!close_to(r->lo[1], lo1, L) || !close_to(r->hi[1], hi2, L) || b0 > lo1 - tol || b1 < hi2 + tol)
    return cupid_model_error(m, &m->pd.regions[0].mark,
                             "with two overlaps [%g, %g] and [%g, %g] the PD region y in [%g, %g] "
                             "must span from the lower edge of the first to the upper edge of "
                             "the second, and the beam [%g, %g] must extend beyond both",
                             lo1, hi1, lo2, hi2, r->lo[1], r->hi[1], b0, b1);
  const double ends[4] = {lo1, hi1, lo2, hi2};
  CUPID_CALL(bounds_on_nodes(job, ends, 4));
  if (lo2 - hi1 <= tol) return CUPID_SUCCESS; /* no PD-only part between the overlaps */
  cupid_box give = {.lo = {0, hi1, 0}, .hi = {0, lo2, 0}, .has = {0, 1, 0}};
  cupid_status st = cupid_coupling_deactivate(job->beam, 1, &give);
  if (st != CUPID_SUCCESS)
    return cupid_model_error(m, mk, "the beam cannot give way between the overlaps: %s",
                             cupid_error_message());
  cupid_job_progress(job, "Arlequin: the beam gives way on y in [%g, %g] (PD only there)", hi1, lo2);
  return CUPID_SUCCESS;
}

cupid_status cupid_app_arlequin_prepare(cupid_job *job) {
  const cupid_model_t *m = job->model;
  const cupid_mark *mk = &m->coupling.mark;
  if (m->coupling.n_overlaps == 2) return prepare_two(job);
  double lo = m->coupling.overlap.lo[1], hi = m->coupling.overlap.hi[1];
  double b0 = job->fe_info.y_min, b1 = job->fe_info.y_max, L = b1 - b0, tol = ARL_TOL * L;
  const cupid_box *r = &m->pd.regions[0].box;
  if (lo < b0 - tol || hi > b1 + tol)
    return cupid_model_error(m, mk, "the overlap y in [%g, %g] must lie inside the beam [%g, %g]",
                             lo, hi, b0, b1);
  /* The PD region starts on one edge of the overlap and extends beyond the other; the beam
   * extends beyond the first edge (its FE-only side). */
  int below = close_to(r->lo[1], lo, L) && r->hi[1] > hi + tol && b0 < lo - tol;
  int above = close_to(r->hi[1], hi, L) && r->lo[1] < lo - tol && b1 > hi + tol;
  if (!below && !above)
    return cupid_model_error(m, &m->pd.regions[0].mark,
                             "the PD region y in [%g, %g] must start on one edge of the overlap "
                             "[%g, %g] and extend beyond the other, and the beam [%g, %g] must "
                             "extend beyond the first edge",
                             r->lo[1], r->hi[1], lo, hi, b0, b1);
  /* The weight has kinks at lo and hi: they must be element ends for exact integration. */
  const double ends[2] = {lo, hi};
  CUPID_CALL(bounds_on_nodes(job, ends, 2));
  /* Beyond the overlap, inside the PD region, the beam gives way (alpha = 0 there). */
  cupid_box give = {.lo = {0, below ? hi : b0, 0}, .hi = {0, below ? b1 : lo, 0}, .has = {0, 1, 0}};
  if (give.hi[1] - give.lo[1] <= tol) return CUPID_SUCCESS; /* the beam ends on the overlap */
  if ((below && b1 > r->hi[1] + tol) || (above && b0 < r->lo[1] - tol))
    return cupid_model_error(m, mk,
                             "the beam [%g, %g] runs through the PD region [%g, %g] and out of "
                             "it: give the second interface its own overlap (overlap: [{y: "
                             "[..]}, {y: [..]}])",
                             b0, b1, r->lo[1], r->hi[1]);
  cupid_status st = cupid_coupling_deactivate(job->beam, 1, &give);
  if (st != CUPID_SUCCESS)
    return cupid_model_error(m, mk, "the beam cannot give way beyond the overlap: %s",
                             cupid_error_message());
  cupid_job_progress(job, "Arlequin: the beam gives way on y in [%g, %g] (PD only there)",
                     give.lo[1], give.hi[1]);
  return CUPID_SUCCESS;
}

/* --------------------------------------------------------------- constraints and loads */

static int pd_node_near(const cupid_job *job, double y, double layer) {
  const double *x = cupid_pd_grid_coords(job->grid);
  for (cupid_int i = 0; i < job->n_pd; i++)
    if (fabs(x[3 * i + 1] - y) < layer) return 1;
  return 0;
}

static cupid_status apply_constraints(cupid_job *job) {
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
      on_pd = pd_node_near(job, c->plane_y, c->layer > 0 ? c->layer : m->pd.horizon);
    } else {
      on_fe = cupid_app_fe_node_in_box(job, &c->box);
      on_pd = cupid_app_pd_node_in_box(job, &c->box);
    }
    if (!on_fe && !on_pd) {
      st = cupid_model_error(m, &c->mark, "the constraint touches neither the beam nor a PD node");
      goto cleanup;
    }
    if (on_fe) CUPID_TRY(cupid_cuf_constraint_apply(job->beam, m, c, job->bc));
    if (on_pd) pd[npd++] = *c;
  }
  CUPID_TRY(cupid_app_pd_stage(job, pd, npd, NULL, 0, 1)); /* also holds x, z of the 1D grid */
  /* FE nodes where the beam gave way carry nothing: hold them at zero. */
  for (cupid_int n = 0; n < job->fe_info.n_fe_nodes; n++) {
    if (cupid_cuf_node_used(job->beam, (int)(n % job->fe_info.M), n / job->fe_info.M)) continue;
    for (int c = 0; c < 3; c++)
      CUPID_TRY(cupid_dirichlet_fix(job->bc, job->fe_offset + 3 * n + c, 0.0));
  }
cleanup:
  cupid_free(&pd);
  return st;
}

/* 1 if the load acts inside the overlap [lo, hi] (both models there). */
static int load_in_overlap(const cupid_load *l, double lo, double hi, double tol) {
  switch (l->kind) {
  case CUPID_LOAD_TRACTION: return l->plane_y > lo + tol && l->plane_y < hi - tol;
  case CUPID_LOAD_POINT: return l->at[1] >= lo - tol && l->at[1] <= hi + tol;
  case CUPID_LOAD_BODY:
  default: return !l->box.has[1] || (l->box.lo[1] < hi - tol && l->box.hi[1] > lo + tol);
  }
}

/* The external work is shared like the energy (paper 004 Eq. 8: alpha W_FE + (1 - alpha)
 * W_PD): a body or point load that reaches into an overlap goes to the beam times alpha and
 * to the PD nodes times 1 - alpha (alpha = 1 on the FE-only side, 0 on the PD-only side, so
 * outside the overlaps this is the plain split). */
typedef struct {
  const cupid_value *value;
  const cupid_arlequin_options *o;
} alpha_load;

static void alpha_field(void *ctx, const double p[3], double density, double out[3]) {
  const alpha_load *w = ctx;
  double a = cupid_arlequin_alpha_of(w->o, p[1]);
  for (int k = 0; k < 3; k++)
    out[k] = a * cupid_value_eval(&w->value[k], p[0], p[1], p[2], 0.0, density);
}

/* The PD share: the load applied to the PD nodes as in a PD-only model (into a scratch vector,
 * with its checks), then scaled by 1 - alpha: at each node for a body load (the integrand),
 * at the load's point for a point load (so that the two shares sum to the load). */
static cupid_status add_pd_share(cupid_job *job, const cupid_load *l, const cupid_arlequin_options *o) {
  cupid_status st = CUPID_SUCCESS;
  double *scratch = NULL, *keep = job->f_ext;
  cupid_load copy = *l;
  CUPID_CALL(cupid_calloc((size_t)job->ndof, sizeof *scratch, "PD load share", &scratch));
  job->f_ext = scratch;
  st = cupid_app_pd_stage(job, NULL, 0, &copy, 1, 0);
  job->f_ext = keep;
  if (st == CUPID_SUCCESS) {
    const double *x = cupid_pd_grid_coords(job->grid);
    for (cupid_int i = 0; i < job->n_pd; i++) {
      double y = l->kind == CUPID_LOAD_POINT ? l->at[1] : x[3 * i + 1];
      double w = 1.0 - cupid_arlequin_alpha_of(o, y);
      for (int c = 0; c < 3; c++) keep[3 * i + c] += w * scratch[3 * i + c];
    }
  }
  cupid_free(&scratch);
  return st;
}

/* A body or point load reaching into an overlap: the two shares. */
static cupid_status add_shared_load(cupid_job *job, const cupid_load *l, const cupid_arlequin_options *o) {
  const cupid_model_t *m = job->model;
  alpha_load ctx = {.value = l->value, .o = o};
  int on_fe = l->kind == CUPID_LOAD_BODY ? cupid_app_fe_node_in_box(job, &l->box)
                                         : cupid_cuf_contains(job->beam, l->at[0], l->at[1], l->at[2]);
  int on_pd = l->kind == CUPID_LOAD_BODY ? cupid_app_pd_node_in_box(job, &l->box) : 1;
  if (!on_fe && !on_pd) return cupid_model_error(m, &l->mark, "the load touches neither the beam nor a PD node");
  if (on_fe && l->kind == CUPID_LOAD_BODY) {
    cupid_status st = cupid_cuf_body_force_add(job->beam, &l->box, alpha_field, &ctx, job->f_ext, NULL);
    if (st != CUPID_SUCCESS) return cupid_model_error(m, &l->mark, "%s", cupid_error_message());
  } else if (on_fe) {
    double P[3];
    alpha_field(&ctx, l->at, 0.0, P);
    CUPID_CALL(cupid_cuf_point_load_add(job->beam, l->at, P, job->f_ext));
  }
  return on_pd ? add_pd_share(job, l, o) : CUPID_SUCCESS;
}

static cupid_status apply_loads(cupid_job *job) {
  const cupid_model_t *m = job->model;
  cupid_status st = CUPID_SUCCESS;
  cupid_load *pd = NULL;
  int npd = 0;
  const cupid_box *ov[2];
  int nov = overlaps(&m->coupling, ov);
  const cupid_arlequin_options o = options(job);
  double tol = ARL_TOL * (job->fe_info.y_max - job->fe_info.y_min);
  CUPID_CALL(cupid_calloc((size_t)m->n_loads + 1, sizeof *pd, "PD loads", &pd));
  for (int k = 0; k < m->n_loads; k++) {
    const cupid_load *l = &m->loads[k];
    int shared = 0;
    for (int v = 0; v < nov; v++) {
      double lo = ov[v]->lo[1], hi = ov[v]->hi[1];
      if (!load_in_overlap(l, lo, hi, tol)) continue;
      if (l->kind == CUPID_LOAD_TRACTION) {
        st = cupid_model_error(m, &l->mark,
                               "a traction on the plane y = %g inside the Arlequin overlap [%g, "
                               "%g] acts on no free surface (move it to an end face)",
                               l->plane_y, lo, hi);
        goto cleanup;
      }
      shared = 1;
    }
    if (shared) {
      CUPID_TRY(add_shared_load(job, l, &o));
      continue;
    }
    int on_fe = 0;
    switch (l->kind) {
    case CUPID_LOAD_TRACTION: on_fe = cupid_app_fe_node_at(job, l->plane_y); break;
    case CUPID_LOAD_POINT: on_fe = cupid_cuf_contains(job->beam, l->at[0], l->at[1], l->at[2]); break;
    case CUPID_LOAD_BODY: on_fe = cupid_app_fe_node_in_box(job, &l->box); break;
    }
    if (on_fe) CUPID_TRY(cupid_cuf_load_add(job->beam, m, l, job->f_ext));
    if (!on_fe || (l->kind == CUPID_LOAD_BODY && cupid_app_pd_node_in_box(job, &l->box))) pd[npd++] = *l;
  }
  CUPID_TRY(cupid_app_pd_stage(job, NULL, 0, pd, npd, 0));
cleanup:
  cupid_free(&pd);
  return st;
}

/* ------------------------------------------------------------------------ the runs */

static cupid_status assemble(cupid_job *job) {
  double t0 = cupid_wtime();
  cupid_arlequin_options o = options(job);
  cupid_arlequin_info info;
  CUPID_CALL(cupid_arlequin_assemble(job->beam, job->grid, job->op, &o, &job->K, &info));
  cupid_job_phase_end(job, CUPID_PHASE_COUPLING, t0);
  static const char *wn[] = {"linear", "constant", "smooth"};
  char second[64] = "";
  if (o.n_overlaps == 2) snprintf(second, sizeof second, " and [%g, %g]", o.second.lo, o.second.hi);
  cupid_job_progress(job,
                     "coupling (Arlequin, penalty): overlap y in [%g, %g]%s, %s weight, kappa = "
                     "%g N/m, %lld tied PD nodes (%d components), min PD weight %.3g; %lld "
                     "non-zeros",
                     o.weight.lo, o.weight.hi, second, wn[o.weight.kind], o.penalty,
                     (long long)info.n_tied, info.components, info.pd_weight_min,
                     (long long)cupid_csr_nnz(job->K));
  return CUPID_SUCCESS;
}

static cupid_status report_gap(const cupid_job *job) {
  cupid_arlequin_options o = options(job);
  double gap, umax = 0.0;
  CUPID_CALL(cupid_arlequin_gap(job->beam, job->grid, &o, job->u, &gap));
  for (cupid_int d = 0; d < job->ndof; d++)
    if (fabs(job->u[d]) > umax) umax = fabs(job->u[d]);
  cupid_job_progress(job, "Arlequin constraint gap max |d - N u| = %.3e (%.3e of max |u|)", gap,
                     umax > 0 ? gap / umax : 0.0);
  return CUPID_SUCCESS;
}

static cupid_status evaluate(cupid_job *job) {
  const cupid_model_t *m = job->model;
  const double *x = cupid_pd_grid_coords(job->grid);
  for (cupid_int i = 0; i < job->n_pd; i++)
    for (int c = 0; c < 3; c++)
      job->u[3 * i + c] =
          cupid_value_eval(&m->analysis.field[c], x[3 * i], x[3 * i + 1], x[3 * i + 2], 0.0, 0.0);
  CUPID_CALL(cupid_app_fe_impose_field(job));
  for (cupid_int n = 0; n < job->fe_info.n_fe_nodes; n++) /* where the beam gave way */
    if (!cupid_cuf_node_used(job->beam, (int)(n % job->fe_info.M), n / job->fe_info.M))
      for (int c = 0; c < 3; c++) job->u[job->fe_offset + 3 * n + c] = 0.0;
  CUPID_CALL(assemble(job));
  cupid_csr_matvec(job->K, job->u, job->f_int);
  cupid_job_progress(job, "evaluate: internal forces of the imposed field computed");
  return report_gap(job);
}

static cupid_status solve(cupid_job *job) {
  /* symmetric positive definite once held: CHOLMOD, or CG + GAMG through PETSc (run.c) */
  cupid_status st = cupid_app_linear_solve(job, CUPID_MATRIX_SPD);
  job->phases[CUPID_PHASE_FACTORISATION] =
      (cupid_phase_record){job->solve.time_factor, cupid_peak_memory(), 1};
  job->phases[CUPID_PHASE_SOLVE] =
      (cupid_phase_record){job->solve.time_solve, cupid_peak_memory(), 1};
  CUPID_CALL(st);
  job->solved = 1;
  cupid_csr_matvec(job->K, job->u, job->f_int);
  cupid_job_progress(job, "solve: %s, %lld equations, residual %.2e, pivot ratio %.2e",
                     job->solve.method, (long long)job->solve.n, job->solve.residual,
                     job->solve.pivot_ratio);
  return report_gap(job);
}

cupid_status cupid_app_arlequin_run(cupid_job *job) {
  if (job->model->analysis.type == CUPID_ANALYSIS_EVALUATE) return evaluate(job);
  CUPID_CALL(cupid_app_estimate(job, 0));
  CUPID_CALL(assemble(job));
  CUPID_CALL(apply_constraints(job));
  CUPID_CALL(cupid_dirichlet_finalize(job->bc));
  CUPID_CALL(apply_loads(job));
  if (job->model->analysis.type == CUPID_ANALYSIS_DYNAMIC) {
    CUPID_CALL(cupid_app_run_dynamic(job));
    return report_gap(job);
  }
  return solve(job);
}

cupid_status cupid_app_arlequin_mass(cupid_job *job, cupid_csr *M, double **m_lumped) {
  const cupid_model_t *m = job->model;
  cupid_status st = CUPID_SUCCESS;
  double *pd_mass = NULL;
  cupid_arlequin_options o = options(job);
  const int *mat = cupid_pd_grid_materials(job->grid);
  double vol = cupid_pd_grid_cell_volume(job->grid);
  CUPID_TRY(cupid_malloc((size_t)job->n_pd + 1, sizeof *pd_mass, "PD masses", &pd_mass));
  for (cupid_int i = 0; i < job->n_pd; i++) pd_mass[i] = m->materials[mat[i]].density * vol;
  if (m->analysis.dynamic.lumped_mass) {
    CUPID_TRY(cupid_calloc((size_t)job->ndof, sizeof **m_lumped, "lumped mass", m_lumped));
    CUPID_TRY(cupid_arlequin_mass(job->beam, job->grid, &o, pd_mass, NULL, *m_lumped));
  } else {
    CUPID_TRY(cupid_csr_duplicate(job->K, M));
    cupid_csr_zero(*M);
    CUPID_TRY(cupid_arlequin_mass(job->beam, job->grid, &o, pd_mass, *M, NULL));
  }
cleanup:
  cupid_free(&pd_mass);
  return st;
}
