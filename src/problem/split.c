/* Coupled models split every constraint and load between the beam and the PD grid: these
 * helpers say which part an item touches (method_coupled.c, method_arlequin.c). */
#include "problem_internal.h"

/* Relative tolerance on node positions (box bounds on cell faces or beam-node planes). */
#define SPLIT_TOL 1e-9

static int fe_node_used(const cupid_problem_state *prob, cupid_int bn) {
  for (int tau = 0; tau < prob->fe_info.M; tau++)
    if (cupid_cuf_node_used(prob->beam, tau, bn)) return 1;
  return 0;
}

int cupid_problem_fe_node_at(const cupid_problem_state *prob, double y) {
  cupid_int bn = cupid_cuf_beam_node_at(prob->beam, y);
  return bn >= 0 && fe_node_used(prob, bn);
}

int cupid_problem_fe_node_in_box(const cupid_problem_state *prob, const cupid_box *b) {
  double tol = SPLIT_TOL * (prob->fe_info.y_max - prob->fe_info.y_min);
  for (cupid_int bn = 0; bn < prob->fe_info.n_beam_nodes; bn++) {
    double y = cupid_cuf_beam_node_y(prob->beam, bn);
    if (b->has[1] && (y < b->lo[1] - tol || y > b->hi[1] + tol)) continue;
    if (fe_node_used(prob, bn)) return 1;
  }
  return 0;
}

int cupid_problem_pd_node_in_box(const cupid_problem_state *prob, const cupid_box *b) {
  const double *x = cupid_pd_grid_coords(prob->grid);
  double h = cupid_pd_grid_spacing(prob->grid);
  cupid_box bb = *b;
  if (cupid_pd_grid_dimension(prob->grid) == 1) bb.has[0] = bb.has[2] = 0; /* a bar along y */
  int found = 0;
  for (cupid_int i = 0; i < prob->n_pd && !found; i++)
    found = cupid_box_contains(&bb, x + 3 * i, SPLIT_TOL * h);
  return cupid_problem_global_count(prob, found) > 0; /* a slab: some rank's slab (collective) */
}
