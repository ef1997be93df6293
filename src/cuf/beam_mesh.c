/* The beam axis: breakpoints along y split into B2/B3/B4 Lagrange elements with equally spaced
 * nodes (paper 000 Eq. 24; cuf.md section 4). Element e has nodes e (p-1) .. e (p-1) + p - 1. */
#include <math.h>

#include "cuf/cuf_internal.h"

typedef struct cupid_cuf_beam_private beam_t;

cupid_status cuf_axis_build(beam_t *b, const cupid_beam *def, const cupid_model_t *model) {
  if (def->element_nodes < 2 || def->element_nodes > 4)
    return cupid_model_error(model, &def->mark, "beam element type must be B2, B3 or B4 (got %d nodes)",
                           def->element_nodes);
  if (def->n_axis < 2 || !def->axis_y || !def->axis_elements)
    return cupid_model_error(model, &def->mark, "the beam axis needs at least two breakpoints");
  cupid_int ne = 0;
  for (int k = 0; k + 1 < def->n_axis; k++) {
    if (!(def->axis_y[k + 1] > def->axis_y[k]))
      return cupid_model_error(model, &def->mark, "axis breakpoints must increase (%g then %g)",
                             def->axis_y[k], def->axis_y[k + 1]);
    if (def->axis_elements[k] < 1)
      return cupid_model_error(model, &def->mark, "axis span %d needs at least one element", k);
    ne += def->axis_elements[k];
  }
  b->p = def->element_nodes;
  b->n_belem = ne;
  b->n_bnodes = ne * (b->p - 1) + 1;
  CUPID_CALL(cupid_malloc((size_t)b->n_bnodes, sizeof *b->by, "beam node coordinates", &b->by));
  cupid_int node = 0;
  for (int k = 0; k + 1 < def->n_axis; k++) {
    double y0 = def->axis_y[k], y1 = def->axis_y[k + 1];
    int nk = def->axis_elements[k], steps = nk * (b->p - 1);
    for (int t = 0; t < steps; t++) b->by[node++] = y0 + (y1 - y0) * t / steps;
  }
  b->by[node] = def->axis_y[def->n_axis - 1];
  b->ymin = b->by[0];
  b->ymax = b->by[b->n_bnodes - 1];
  b->tol_y = 1e-9 * (b->ymax - b->ymin);
  return CUPID_SUCCESS;
}

cupid_int cuf_axis_locate(const beam_t *b, double y, double *xi) {
  if (y < b->ymin - b->tol_y || y > b->ymax + b->tol_y) return -1;
  /* binary search on element ends */
  cupid_int lo = 0, hi = b->n_belem - 1;
  while (lo < hi) {
    cupid_int mid = (lo + hi) / 2;
    if (y > b->by[(mid + 1) * (b->p - 1)] + b->tol_y) lo = mid + 1;
    else hi = mid;
  }
  double y0 = b->by[lo * (b->p - 1)], y1 = b->by[(lo + 1) * (b->p - 1)];
  double x = (2 * y - y0 - y1) / (y1 - y0);
  if (xi) *xi = fmin(1.0, fmax(-1.0, x));
  return lo;
}

void cuf_axis_shape(const beam_t *b, cupid_int e, double xi, double *N, double *dNdy) {
  double nodes[CUF_MAX_P], dN[CUF_MAX_P];
  cuf_beam_nodes(b->p, nodes);
  cuf_lagrange(b->p, nodes, xi, N, dN);
  double y0 = b->by[e * (b->p - 1)], y1 = b->by[(e + 1) * (b->p - 1)];
  double J = 0.5 * (y1 - y0);
  if (dNdy)
    for (int a = 0; a < b->p; a++) dNdy[a] = dN[a] / J;
}
