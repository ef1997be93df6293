/* Values at arbitrary points (output lines and points): inside the beam, the CUF expansion
 * (paper 000 Eqs. 23-24) and its stress; inside a PD region, trilinear
 * interpolation of the grid nodes (model-format.md, output.lines). Corners missing from the
 * grid (near region faces, where the point is less than h/2 from the surface) are dropped and
 * the weights renormalised, which extrapolates constantly over that last half cell. */
#include <math.h>

#include "problem_internal.h"

static int inside_pd(const cupid_problem_state *prob, const double p[3]) {
  const cupid_model_t *m = prob->model;
  double tol = 1e-9 * m->pd.spacing;
  for (int r = 0; r < m->pd.n_regions; r++) {
    cupid_box b = m->pd.regions[r].box;
    if (m->pd.dimension == 1) b.has[0] = b.has[2] = 0;
    if (cupid_box_contains(&b, p, tol)) return 1;
  }
  return 0;
}

cupid_status cupid_problem_sample_point(const cupid_problem_state *prob, const double *sol,
                                        const double p[3], double u[3],
                              double sigma[6], cupid_region_kind *region) {
  for (int c = 0; c < 3; c++) u[c] = NAN;
  if (sigma)
    for (int c = 0; c < 6; c++) sigma[c] = NAN;
  *region = CUPID_REGION_NONE;
  if (prob->beam && cupid_cuf_contains(prob->beam, p[0], p[1], p[2])) {
    *region = CUPID_REGION_FE;
    if (!sol) return CUPID_SUCCESS;
    CUPID_CALL(cupid_cuf_displacement_at(prob->beam, sol, p[0], p[1], p[2], u));
    if (sigma) CUPID_CALL(cupid_cuf_stress_at(prob->beam, sol, p[0], p[1], p[2], sigma));
    return CUPID_SUCCESS;
  }
  if (!prob->grid || !inside_pd(prob, p)) return CUPID_SUCCESS;
  if (!sol) { /* before the solve: only say where the point lies */
    *region = CUPID_REGION_PD;
    return CUPID_SUCCESS;
  }

  double o[3], h = cupid_pd_grid_spacing(prob->grid);
  cupid_pd_grid_origin(prob->grid, o);
  int dim = cupid_pd_grid_dimension(prob->grid);
  cupid_int base[3] = {0, 0, 0};
  double w[3] = {0, 0, 0};
  for (int a = 0; a < 3; a++) {
    if (dim == 1 && a != 1) continue;
    double q = (p[a] - o[a]) / h - 0.5;
    base[a] = (cupid_int)floor(q);
    w[a] = q - (double)base[a];
  }
  double acc_u[3] = {0, 0, 0}, acc_s[6] = {0, 0, 0, 0, 0, 0}, wsum = 0.0;
  for (int corner = 0; corner < 8; corner++) {
    int d[3] = {corner & 1, (corner >> 1) & 1, (corner >> 2) & 1};
    if (dim == 1 && (d[0] || d[2])) continue;
    double wt = 1.0;
    for (int a = 0; a < 3; a++)
      if (dim == 3 || a == 1) wt *= d[a] ? w[a] : 1.0 - w[a];
    cupid_int node = cupid_pd_grid_node_at(prob->grid, base[0] + d[0], base[1] + d[1], base[2] + d[2]);
    if (node < 0 || wt == 0.0) continue;
    wsum += wt;
    for (int c = 0; c < 3; c++) acc_u[c] += wt * sol[3 * node + c];
    if (sigma && prob->pd_stress)
      for (int c = 0; c < 6; c++) acc_s[c] += wt * prob->pd_stress[6 * node + c];
  }
  if (wsum <= 0.0) {
    /* Exactly on a node-free corner: take the node whose cell contains the point. */
    cupid_int ijk[3];
    for (int a = 0; a < 3; a++) ijk[a] = (dim == 1 && a != 1) ? 0 : (cupid_int)floor((p[a] - o[a]) / h);
    cupid_int node = cupid_pd_grid_node_at(prob->grid, ijk[0], ijk[1], ijk[2]);
    if (node < 0) return CUPID_SUCCESS;
    wsum = 1.0;
    for (int c = 0; c < 3; c++) acc_u[c] = sol[3 * node + c];
    if (sigma && prob->pd_stress)
      for (int c = 0; c < 6; c++) acc_s[c] = prob->pd_stress[6 * node + c];
  }
  for (int c = 0; c < 3; c++) u[c] = acc_u[c] / wsum;
  if (sigma && prob->pd_stress)
    for (int c = 0; c < 6; c++) sigma[c] = acc_s[c] / wsum;
  *region = CUPID_REGION_PD;
  return CUPID_SUCCESS;
}

/* Before the solve: output points and lines against the model's regions and the beam. */
cupid_status cupid_problem_check_points(const cupid_problem_state *prob) {
  const cupid_output *o = &prob->model->output;
  for (int k = 0; k < o->n_points; k++) {
    double u[3];
    cupid_region_kind region;
    CUPID_CALL(cupid_problem_sample_point(prob, NULL, o->points[k].at, u, NULL, &region));
    if (region == CUPID_REGION_NONE)
      return cupid_model_error(prob->model, &o->points[k].mark,
                               "the point (%g, %g, %g) lies outside the model",
                               o->points[k].at[0], o->points[k].at[1], o->points[k].at[2]);
  }
  /* A line with no point inside the model would only hold NaN (and gnuplot fails on it after
   * the whole solve): refuse it now. Stops at the first point inside. */
  for (int k = 0; k < o->n_lines; k++) {
    const cupid_output_line *line = &o->lines[k];
    cupid_region_kind region = CUPID_REGION_NONE;
    for (int i = 0; i < line->points && region == CUPID_REGION_NONE; i++) {
      double t = line->points > 1 ? (double)i / (line->points - 1) : 0.0, p[3], u[3];
      for (int a = 0; a < 3; a++) p[a] = line->from[a] + t * (line->to[a] - line->from[a]);
      CUPID_CALL(cupid_problem_sample_point(prob, NULL, p, u, NULL, &region));
    }
    if (region == CUPID_REGION_NONE)
      return cupid_model_error(prob->model, &line->mark,
                               "the line from (%g, %g, %g) to (%g, %g, %g) lies outside the model "
                               "(none of its %d points is inside)",
                               line->from[0], line->from[1], line->from[2], line->to[0],
                               line->to[1], line->to[2], line->points);
  }
  return CUPID_SUCCESS;
}
