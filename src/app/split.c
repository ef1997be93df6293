/* Coupled models split every constraint and load between the beam and the PD grid: these
 * helpers say which part an item touches and run the PD stages of pd_bc.c on a subset of the
 * model's items. Shared by coupled.c (fictitious nodes, Lagrange) and coupled_arlequin.c. */
#include "app_internal.h"

/* Relative tolerance on node positions (box bounds on cell faces or beam-node planes). */
#define SPLIT_TOL 1e-9

static int fe_node_used(const cupid_job *job, cupid_int bn) {
  for (int tau = 0; tau < job->fe_info.M; tau++)
    if (cupid_cuf_node_used(job->beam, tau, bn)) return 1;
  return 0;
}

int cupid_app_fe_node_at(const cupid_job *job, double y) {
  cupid_int bn = cupid_cuf_beam_node_at(job->beam, y);
  return bn >= 0 && fe_node_used(job, bn);
}

int cupid_app_fe_node_in_box(const cupid_job *job, const cupid_box *b) {
  double tol = SPLIT_TOL * (job->fe_info.y_max - job->fe_info.y_min);
  for (cupid_int bn = 0; bn < job->fe_info.n_beam_nodes; bn++) {
    double y = cupid_cuf_beam_node_y(job->beam, bn);
    if (b->has[1] && (y < b->lo[1] - tol || y > b->hi[1] + tol)) continue;
    if (fe_node_used(job, bn)) return 1;
  }
  return 0;
}

int cupid_app_pd_node_in_box(const cupid_job *job, const cupid_box *b) {
  const double *x = cupid_pd_grid_coords(job->grid);
  double h = cupid_pd_grid_spacing(job->grid);
  cupid_box bb = *b;
  if (cupid_pd_grid_dimension(job->grid) == 1) bb.has[0] = bb.has[2] = 0; /* a bar along y */
  int found = 0;
  for (cupid_int i = 0; i < job->n_pd && !found; i++)
    found = cupid_box_contains(&bb, x + 3 * i, SPLIT_TOL * h);
  return cupid_app_global_count(job, found) > 0; /* a slab: some rank's slab (collective) */
}

cupid_status cupid_app_pd_stage(cupid_job *job, cupid_constraint *cons, int nc,
                                cupid_load *loads, int nl, int constraints) {
  cupid_model_t part = *job->model; /* a shallow copy holding only the PD items */
  part.constraints = cons;
  part.n_constraints = nc;
  part.loads = loads;
  part.n_loads = nl;
  const cupid_model_t *saved = job->model;
  job->model = &part;
  cupid_status st = constraints ? cupid_app_pd_constraints(job) : cupid_app_pd_loads(job);
  job->model = saved;
  return st;
}
