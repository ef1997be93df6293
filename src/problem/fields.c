/* What a problem gives back (include/cupid/problem.h): fields as arrays, values at points,
 * counts and figures of the run, and the system for programs that go further (bench/). */
#include <math.h>
#include <string.h>

#include "method.h"

/* Fields need a stage: the coordinates after setup, the solution after solve. */
static cupid_status need_stage(const cupid_problem_state *prob, int stage, const char *what) {
  CUPID_CHECK(prob, CUPID_ERR_ARGUMENT, "%s: NULL problem", what);
  CUPID_CHECK(prob->stage >= stage, CUPID_ERR_ARGUMENT, "%s: %s first", what,
              stage == CUPID_STAGE_SOLVED ? "solve the problem" : "set the problem up");
  return CUPID_SUCCESS;
}

/* The beam's 3D reconstruction (the points of beam.vtu) with the displacements of prob->u. */
static cupid_status build_beam_points(cupid_problem_state *prob) {
  if (prob->beam_points && (prob->beam_u || prob->stage < CUPID_STAGE_SOLVED)) return CUPID_SUCCESS;
  cupid_cuf_vtu *vtu = NULL;
  CUPID_CALL(cupid_cuf_vtu_build(prob->beam, prob->stage >= CUPID_STAGE_SOLVED ? prob->u : NULL, 0,
                                 &vtu));
  size_t n = 3 * (size_t)vtu->n_points;
  cupid_status st = CUPID_SUCCESS;
  cupid_free(&prob->beam_points);
  cupid_free(&prob->beam_u);
  CUPID_TRY(cupid_malloc(n + 1, sizeof(double), "beam points", &prob->beam_points));
  memcpy(prob->beam_points, vtu->points, n * sizeof(double));
  if (prob->stage >= CUPID_STAGE_SOLVED) {
    CUPID_TRY(cupid_malloc(n + 1, sizeof(double), "beam displacements", &prob->beam_u));
    memcpy(prob->beam_u, vtu->displacement, n * sizeof(double));
  }
  prob->n_beam_points = vtu->n_points;
cleanup:
  cupid_cuf_vtu_destroy(&vtu);
  return st;
}

cupid_status cupid_problem_get_field(cupid_problem_state *prob, cupid_field field,
                                     const double **values, cupid_int *n, int *components) {
  CUPID_CHECK(values && n && components, CUPID_ERR_ARGUMENT, "cupid_problem_get_field: NULL output");
  *values = NULL, *n = 0, *components = 3;
  CUPID_CHECK(field >= 0 && field < CUPID_FIELD_COUNT, CUPID_ERR_ARGUMENT,
              "cupid_problem_get_field: unknown field %d", (int)field);
  int solved = field == CUPID_FIELD_PD_DISPLACEMENT || field == CUPID_FIELD_PD_FORCE ||
               field == CUPID_FIELD_PD_STRESS || field == CUPID_FIELD_BEAM_DISPLACEMENT;
  CUPID_CALL(need_stage(prob, solved ? CUPID_STAGE_SOLVED : CUPID_STAGE_SET_UP,
                        "cupid_problem_get_field"));
  if (field == CUPID_FIELD_PD_DAMAGE) {
    if (!prob->damage || prob->slab) return CUPID_SUCCESS;
    CUPID_CALL(cupid_problem_fracture_damage(prob));
    *values = prob->damage;
    *n = prob->n_pd;
    *components = 1;
    return CUPID_SUCCESS;
  }
  int pd = field <= CUPID_FIELD_PD_STRESS;
  if (pd && (!prob->grid || prob->slab)) return CUPID_SUCCESS; /* no grid (or not rank 0's) */
  if (!pd && !prob->beam) return CUPID_SUCCESS;
  switch (field) {
  case CUPID_FIELD_PD_COORDINATES: *values = cupid_pd_grid_coords(prob->grid); break;
  case CUPID_FIELD_PD_DISPLACEMENT: *values = prob->u; break;
  case CUPID_FIELD_PD_FORCE: *values = prob->f_int; break;
  case CUPID_FIELD_PD_LOAD: *values = prob->f_ext; break;
  case CUPID_FIELD_PD_STRESS:
    CUPID_CALL(cupid_problem_pd_stress(prob));
    *values = prob->pd_stress;
    *components = 6;
    break;
  default:
    CUPID_CALL(build_beam_points(prob));
    *values = field == CUPID_FIELD_BEAM_POINTS ? prob->beam_points : prob->beam_u;
    *n = prob->n_beam_points;
    return CUPID_SUCCESS;
  }
  CUPID_CHECK(*values, CUPID_ERR_ARGUMENT,
              "cupid_problem_get_field: the problem has no such field (check-only set-up?)");
  *n = prob->n_pd;
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_sample(cupid_problem_state *prob, cupid_int n, const double *xyz,
                                  double *u, double *stress, int *region) {
  CUPID_CALL(need_stage(prob, CUPID_STAGE_SET_UP, "cupid_problem_sample"));
  CUPID_CHECK(prob->u, CUPID_ERR_ARGUMENT, "cupid_problem_sample: a check-only problem has no solution");
  CUPID_CHECK(n >= 0 && (n == 0 || (xyz && u)), CUPID_ERR_ARGUMENT,
              "cupid_problem_sample: NULL points or results");
  CUPID_CHECK(!prob->slab, CUPID_ERR_ARGUMENT,
              "cupid_problem_sample: this MPI rank holds one slab; rank 0 holds the whole model");
  if (stress) CUPID_CALL(cupid_problem_pd_stress(prob));
  for (cupid_int k = 0; k < n; k++) {
    cupid_region_kind where;
    CUPID_CALL(cupid_problem_sample_point(prob, prob->u, xyz + 3 * k, u + 3 * k, stress ? stress + 6 * k : NULL,
                                          &where));
    if (region) region[k] = (int)where;
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_get_info(cupid_problem_state *prob, cupid_problem_info *info) {
  CUPID_CHECK(prob && info, CUPID_ERR_ARGUMENT, "cupid_problem_get_info: NULL argument");
  static const char *analyses[3] = {"static", "dynamic", "evaluate"};
  memset(info, 0, sizeof *info);
  info->stage = prob->stage;
  info->analysis = analyses[prob->model->analysis.type];
  info->coupling = prob->method->name;
  info->solver = prob->engine ? prob->engine->name : "";
  info->solver_reason = prob->solver_reason;
  info->method = prob->solved ? prob->solve.method : "none";
  info->pd_nodes = prob->n_pd;
  info->bonds = prob->n_bonds;
  info->fictitious_nodes = prob->n_fictitious;
  info->fe_nodes = prob->beam ? prob->fe_info.n_fe_nodes : 0;
  info->fe_dofs = prob->n_fe_dofs;
  info->dofs = prob->ndof;
  for (cupid_int d = 0; d < prob->ndof && prob->bc; d++) info->constrained_dofs += prob->bc->fixed[d];
  info->matrix_free = prob->solved ? prob->solve.matrix_free : prob->dyn.matrix_free;
  info->iterations = prob->solved ? prob->solve.iterations : 0;
  info->residual = prob->solved ? prob->solve.residual : 0.0;
  double pn = 0.0, in = 0.0;
  for (int c = 0; c < 3; c++) {
    info->load_sum[c] = prob->load_sum[c];
    info->reaction_sum[c] = prob->reaction_sum[c];
    pn += prob->load_sum[c] * prob->load_sum[c];
    in += (prob->load_sum[c] + prob->reaction_sum[c]) * (prob->load_sum[c] + prob->reaction_sum[c]);
  }
  info->imbalance = pn > 0 ? sqrt(in / pn) : 0.0;
  for (int p = 0; p < CUPID_PHASE_COUNT && p < 6; p++)
    info->phase_seconds[p] = prob->phases[p].used ? prob->phases[p].seconds : 0.0;
  info->total_seconds = cupid_wtime() - prob->t_start;
  info->peak_memory_bytes = cupid_peak_memory();
  info->ghost_force = prob->quality.patch_done ? prob->quality.ghost : -1.0;
  info->quality_warnings = prob->quality.ghost_warning | prob->quality.imbalance_warning << 1;
  info->stopped = prob->growth.stopped_step ? prob->growth.stopped : NULL;
  if (prob->growth.peak && prob->model->n_constraints > 0) {
    info->peak_load_factor = prob->growth.peak[1];
    for (int c = 0; c < 3; c++) info->peak_reaction[c] = prob->growth.peak[3 + c];
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_get_system(cupid_problem_state *prob, cupid_problem_system *s) {
  CUPID_CALL(need_stage(prob, CUPID_STAGE_SET_UP, "cupid_problem_get_system"));
  CUPID_CHECK(s, CUPID_ERR_ARGUMENT, "cupid_problem_get_system: NULL result");
  *s = (cupid_problem_system){.grid = prob->grid, .op = prob->op, .beam = prob->beam,
                              .ndof = prob->ndof, .fe_offset = prob->fe_offset, .bc = prob->bc,
                              .f_ext = prob->f_ext, .u = prob->u, .f_int = prob->f_int};
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_coupling_options(cupid_problem_state *prob, cupid_coupling_options *co) {
  CUPID_CALL(need_stage(prob, CUPID_STAGE_SET_UP, "cupid_problem_coupling_options"));
  CUPID_CHECK(co, CUPID_ERR_ARGUMENT, "cupid_problem_coupling_options: NULL result");
  cupid_free(&prob->region_boxes);
  cupid_free(&prob->region_materials);
  return cupid_method_coupling_options(prob, co, &prob->region_boxes, &prob->region_materials);
}

int cupid_problem_output_point_count(cupid_problem_state *prob) {
  return prob ? prob->model->output.n_points : 0;
}

cupid_status cupid_problem_output_point(cupid_problem_state *prob, int k, const char **name,
                                        double xyz[3], int *stress) {
  CUPID_CHECK(prob && k >= 0 && k < prob->model->output.n_points, CUPID_ERR_ARGUMENT,
              "cupid_problem_output_point: no output point %d", k);
  const cupid_output_point *pt = &prob->model->output.points[k];
  if (name) *name = pt->name;
  for (int a = 0; a < 3; a++) xyz[a] = pt->at[a];
  if (stress) *stress = pt->stress;
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_get_history(cupid_problem_state *prob, const double **rows,
                                       cupid_int *n_rows, int *n_cols) {
  CUPID_CALL(need_stage(prob, CUPID_STAGE_SOLVED, "cupid_problem_get_history"));
  CUPID_CHECK(rows && n_rows && n_cols, CUPID_ERR_ARGUMENT, "cupid_problem_get_history: NULL output");
  *rows = prob->history;
  *n_rows = prob->history_rows;
  *n_cols = prob->history_rows ? prob->history_cols : 1 + 3 * prob->model->output.n_points;
  return CUPID_SUCCESS;
}
