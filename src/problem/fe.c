/* The CUF beam of a model inside a run: the beam's DOFs sit after the PD DOFs in the global
 * system (offset fe_offset), so the same vectors serve PD-only, FE-only and coupled models. */
#include <string.h>

#include "problem_internal.h"

cupid_status cupid_problem_fe_build(cupid_problem_state *prob) {
  double t0 = cupid_wtime();
  CUPID_CALL(cupid_cuf_beam_create(prob->model, &prob->beam));
  prob->fe_offset = 3 * prob->n_pd;
  CUPID_CALL(cupid_cuf_set_dof_offset(prob->beam, prob->fe_offset));
  cupid_cuf_get_info(prob->beam, &prob->fe_info);
  prob->n_fe_dofs = prob->fe_info.n_dofs;
  cupid_problem_phase_end(prob, CUPID_PHASE_GRID, t0);
  cupid_problem_progress(prob, "beam: %lld FE nodes, %lld DOFs%s", (long long)prob->fe_info.n_fe_nodes,
                     (long long)prob->n_fe_dofs,
                     prob->fe_info.poisson_corrected ? ", Poisson-locking correction on" : "");
  return CUPID_SUCCESS;
}

static void field_of_model(void *ctx, const double p[3], double density, double out[3]) {
  const cupid_value *v = ctx;
  for (int c = 0; c < 3; c++) out[c] = cupid_value_eval(&v[c], p[0], p[1], p[2], 0.0, density);
}

/* `evaluate`: the generalised DOFs that represent the imposed field (LE: nodal values; TE:
 * the section-wise L2 projection, exact for polynomials up to the expansion order). */
cupid_status cupid_problem_fe_impose_field(cupid_problem_state *prob) {
  return cupid_cuf_interpolate(prob->beam, field_of_model, (void *)prob->model->analysis.field,
                               prob->u);
}

static void unit_field(void *ctx, const double p[3], double density, double out[3]) {
  const int *k = ctx;
  for (int c = 0; c < 3; c++) out[c] = c == *k ? 1.0 : 0.0;
}

cupid_status cupid_problem_system_field(const cupid_problem_state *prob, cupid_cuf_field_fn fn,
                                        void *ctx, double *x) {
  const double *xp = prob->grid ? cupid_pd_grid_coords(prob->grid) : NULL;
  for (cupid_int i = 0; i < prob->n_pd; i++) fn(ctx, xp + 3 * i, 0.0, x + 3 * i);
  if (!prob->beam) return CUPID_SUCCESS;
  CUPID_CALL(cupid_cuf_interpolate(prob->beam, fn, ctx, x));
  for (cupid_int n = 0; n < prob->fe_info.n_fe_nodes; n++)
    if (!cupid_cuf_node_used(prob->beam, (int)(n % prob->fe_info.M), n / prob->fe_info.M))
      for (int c = 0; c < 3; c++) x[prob->fe_offset + 3 * n + c] = 0.0;
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_translations(const cupid_problem_state *prob, double *t) {
  for (int k = 0; k < 3; k++) {
    double *tk = t + (size_t)k * (size_t)prob->ndof;
    for (cupid_int i = 0; i < prob->n_pd; i++) tk[3 * i + k] = 1.0;
    if (prob->beam) CUPID_CALL(cupid_cuf_interpolate(prob->beam, unit_field, &k, tk));
  }
  return CUPID_SUCCESS;
}
