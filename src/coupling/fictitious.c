/* The improved PD-CUF coupling with fictitious nodes (paper 000, section 4; see coupling.h):
 * fictitious PD nodes in the beam up to 2 delta from each interface (Eqs. 29-30), one
 * fictitious FE element per interface (by default the beam element the region removed next
 * to it, section 4.1; cupid_fictitious_fe) whose nodes in the region are fitted to the real
 * PD nodes on the planes around their sections (Eqs. 31-36), and the non-symmetric coupled
 * matrix of Eq. 38. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "coupling_internal.h"
#include "cupid/coupling.h"

#define TOL 1e-9

static int any_partial_region(cupid_cuf_beam beam, const cupid_coupling_options *o);

/* ------------------------------------------------------------------------------ geometry */

static void section_bbox(const cupid_cuf_beam beam, double bb[4]) {
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  bb[0] = bb[2] = INFINITY;
  bb[1] = bb[3] = -INFINITY;
  for (cupid_int se = 0; se < info.n_section_elements; se++) {
    int npe, mat;
    double box[4];
    cupid_cuf_section_element(beam, se, &npe, NULL, &mat, box);
    bb[0] = fmin(bb[0], box[0]);
    bb[1] = fmax(bb[1], box[1]);
    bb[2] = fmin(bb[2], box[2]);
    bb[3] = fmax(bb[3], box[3]);
  }
}

/* The beam node at y if it ends a beam element, else -1; *below / *above get the nearest ends. */
static cupid_int element_end_at(const cupid_cuf_beam beam, double y, double *below, double *above) {
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  *below = -INFINITY;
  *above = INFINITY;
  for (cupid_int e = 0; e < info.n_beam_elements; e++) {
    cupid_int first;
    double y0, y1;
    cupid_cuf_beam_element(beam, e, &first, &y0, &y1);
    double tol = TOL * (info.y_max - info.y_min);
    if (fabs(y0 - y) <= tol) return first;
    if (fabs(y1 - y) <= tol) return first + info.element_nodes - 1;
    if (y0 < y) *below = fmax(*below, y0);
    if (y1 < y) *below = fmax(*below, y1);
    if (y0 > y) *above = fmin(*above, y0);
    if (y1 > y) *above = fmin(*above, y1);
  }
  return -1;
}

int cpl_region_full(const cupid_cuf_beam beam, const cupid_box *b) {
  double bb[4];
  section_bbox(beam, bb);
  double stol = TOL * fmax(bb[1] - bb[0], bb[3] - bb[2]);
  return (!b->has[0] || (b->lo[0] <= bb[0] + stol && b->hi[0] >= bb[1] - stol)) &&
         (!b->has[2] || (b->lo[2] <= bb[2] + stol && b->hi[2] >= bb[3] - stol));
}

int cupid_coupling_region_spans_section(const cupid_cuf_beam beam, const cupid_box *region) {
  return cpl_region_full(beam, region);
}

/* A region over part of the section (paper 000 section 4.4): the section elements inside its
 * x/z box give way over its y range, the others stay. Its x/z bounds must be section-element
 * edges and no element may straddle them (LE only: a TE expansion spans the whole section
 * and cannot lose a part of it). */
static cupid_status deactivate_partial(cupid_cuf_beam beam, int r, const cupid_box *b,
                                       const double bb[4], double stol) {
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  if (info.expansion == CUPID_EXPANSION_TE)
    return CUPID_ERROR(CUPID_ERR_MODEL,
                       "PD region %d covers part of the cross-section (x in [%g, %g], z in [%g, "
                       "%g] of [%g, %g] x [%g, %g]); a TE expansion spans the whole section and "
                       "cannot be removed in part: use an LE section (L4/L9/L16) whose element "
                       "edges lie on the region's x/z bounds, or make the region span the section",
                       r, b->lo[0], b->hi[0], b->lo[2], b->hi[2], bb[0], bb[1], bb[2], bb[3]);
  double lo[2] = {b->has[0] ? b->lo[0] : bb[0], b->has[2] ? b->lo[2] : bb[2]};
  double hi[2] = {b->has[0] ? b->hi[0] : bb[1], b->has[2] ? b->hi[2] : bb[3]};
  static const char axis[2] = {'x', 'z'};
  /* Every bound must be an edge of some section element. */
  for (int a = 0; a < 2; a++)
    for (int side = 0; side < 2; side++) {
      double v = side ? hi[a] : lo[a], below = -INFINITY, above = INFINITY;
      int found = 0;
      for (cupid_int se = 0; se < info.n_section_elements && !found; se++) {
        int npe, mat;
        double box[4];
        cupid_cuf_section_element(beam, se, &npe, NULL, &mat, box);
        for (int k = 0; k < 2; k++) {
          double edge = box[2 * a + k];
          if (fabs(edge - v) <= stol) found = 1;
          if (edge < v) below = fmax(below, edge);
          if (edge > v) above = fmin(above, edge);
        }
      }
      if (!found)
        return CUPID_ERROR(CUPID_ERR_MODEL,
                           "PD region %d: its bound %c = %g is not a section-element edge "
                           "(nearest edges %g and %g); a region over part of the section must "
                           "replace whole section elements: move the bound or the section "
                           "breakpoints so that they coincide",
                           r, axis[a], v, below, above);
    }
  cupid_int removed = 0;
  for (cupid_int se = 0; se < info.n_section_elements; se++) {
    int npe, mat;
    double box[4];
    cupid_cuf_section_element(beam, se, &npe, NULL, &mat, box);
    int inside = 1, overlap = 1;
    for (int a = 0; a < 2; a++) {
      inside &= box[2 * a] >= lo[a] - stol && box[2 * a + 1] <= hi[a] + stol;
      overlap &= box[2 * a] < hi[a] - stol && box[2 * a + 1] > lo[a] + stol;
    }
    if (overlap && !inside)
      return CUPID_ERROR(CUPID_ERR_MODEL,
                         "PD region %d: its x/z box [%g, %g] x [%g, %g] cuts the section element "
                         "[%g, %g] x [%g, %g]; a region over part of the section must replace "
                         "whole section elements",
                         r, lo[0], hi[0], lo[1], hi[1], box[0], box[1], box[2], box[3]);
    if (!inside) continue;
    removed++;
    for (cupid_int e = 0; e < info.n_beam_elements; e++) {
      cupid_int first;
      double y0, y1;
      cupid_cuf_beam_element(beam, e, &first, &y0, &y1);
      double len = info.y_max - info.y_min;
      if (y0 < b->lo[1] - TOL * len || y1 > b->hi[1] + TOL * len) continue;
      CUPID_CALL(cupid_cuf_set_active(beam, e, se, 0));
    }
  }
  CUPID_CHECK(removed > 0, CUPID_ERR_MODEL,
              "PD region %d: its x/z box [%g, %g] x [%g, %g] holds no section element", r, lo[0],
              hi[0], lo[1], hi[1]);
  return CUPID_SUCCESS;
}

cupid_status cupid_coupling_deactivate(cupid_cuf_beam beam, int n_regions,
                                       const cupid_box *regions) {
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  double bb[4], len = info.y_max - info.y_min;
  section_bbox(beam, bb);
  double stol = TOL * fmax(bb[1] - bb[0], bb[3] - bb[2]);
  for (int r = 0; r < n_regions; r++) {
    const cupid_box *b = &regions[r];
    CUPID_CHECK(b->has[1], CUPID_ERR_MODEL, "PD region %d: needs y bounds", r);
    double ylo = b->lo[1], yhi = b->hi[1];
    CUPID_CHECK(ylo >= info.y_min - TOL * len && yhi <= info.y_max + TOL * len, CUPID_ERR_MODEL,
                "PD region %d: y in [%g, %g] reaches beyond the beam (y in [%g, %g]); a PD "
                "region must lie inside the beam it replaces",
                r, ylo, yhi, info.y_min, info.y_max);
    for (int side = 0; side < 2; side++) {
      double y = side ? yhi : ylo, below, above;
      if (element_end_at(beam, y, &below, &above) < 0)
        return CUPID_ERROR(CUPID_ERR_MODEL,
                           "PD region %d: its bound y = %g is not a beam-element end (nearest "
                           "ends %g and %g); move the region bound or the beam's axis "
                           "breakpoints so that they coincide",
                           r, y, below, above);
    }
    if (cpl_region_full(beam, b)) {
      for (cupid_int e = 0; e < info.n_beam_elements; e++) {
        cupid_int first;
        double y0, y1;
        cupid_cuf_beam_element(beam, e, &first, &y0, &y1);
        if (y0 < ylo - TOL * len || y1 > yhi + TOL * len) continue;
        for (cupid_int se = 0; se < info.n_section_elements; se++)
          CUPID_CALL(cupid_cuf_set_active(beam, e, se, 0));
      }
    } else {
      CUPID_CALL(deactivate_partial(beam, r, b, bb, stol));
    }
  }
  return CUPID_SUCCESS;
}

/* ------------------------------------------------------------------ fictitious FE element */

/* Solve B X = R in place (B n x n, R n x m, row-major) by Gaussian elimination with partial
 * pivoting; a pivot below 1e-12 of the largest entry of B is CUPID_ERR_NUMERIC. */
static cupid_status dense_solve(int n, double *B, cupid_int m, double *R) {
  double bmax = 0.0;
  for (int i = 0; i < n * n; i++) bmax = fmax(bmax, fabs(B[i]));
  for (int k = 0; k < n; k++) {
    int p = k;
    for (int i = k + 1; i < n; i++)
      if (fabs(B[i * n + k]) > fabs(B[p * n + k])) p = i;
    CUPID_CHECK(fabs(B[p * n + k]) > 1e-12 * bmax, CUPID_ERR_NUMERIC,
                "the section fit [A I] is singular at expansion term %d", k);
    if (p != k) {
      for (int j = 0; j < n; j++) {
        double t = B[k * n + j];
        B[k * n + j] = B[p * n + j];
        B[p * n + j] = t;
      }
      for (cupid_int j = 0; j < m; j++) {
        double t = R[k * m + j];
        R[k * m + j] = R[p * m + j];
        R[p * m + j] = t;
      }
    }
    for (int i = k + 1; i < n; i++) {
      double f = B[i * n + k] / B[k * n + k];
      if (f == 0.0) continue;
      for (int j = k; j < n; j++) B[i * n + j] -= f * B[k * n + j];
      for (cupid_int j = 0; j < m; j++) R[i * m + j] -= f * R[k * m + j];
    }
  }
  for (int k = n - 1; k >= 0; k--) {
    for (cupid_int j = 0; j < m; j++) {
      double s = R[k * m + j];
      for (int i = k + 1; i < n; i++) s -= B[k * n + i] * R[i * m + j];
      R[k * m + j] = s / B[k * n + k];
    }
  }
  return CUPID_SUCCESS;
}

/* G = [A I]^{-1} A (Eq. 35) for the n_q real PD nodes q of one PD plane, fitted to the section
 * of node @p k of the fictitious element @p aux (N_k = 1 there): I_{q,tau} = F_tau(x_q, z_q),
 * A_{tau,q} = |I_{q,tau}| / sum_q |.| (Eq. 33). With @p signed_weights A uses F_tau itself:
 * then [A I] = I^T I up to row scaling and Eq. 35 is the least-squares fit of the expansion to
 * the PD nodes. TE needs this: its monomials are centred on the section (cuf.h), so an odd term
 * has sum_q |F| F = 0 on a symmetric section and the |F| rows of [A I] coincide (singular).
 * Both are exact for fields in the span of the expansion (the patch test). *G is M x n_q. */
static cupid_status section_fit(cupid_cuf_beam aux, int k, double y_k, const double *x,
                                const cupid_int *q, cupid_int n_q, int M, int p,
                                int signed_weights, double **G) {
  cupid_status st = CUPID_SUCCESS;
  double *I = NULL, *A = NULL, *B = NULL, *w = NULL;
  cupid_int *node = NULL;
  CUPID_TRY(cupid_calloc((size_t)(n_q * M), sizeof *I, "section fit I", &I));
  CUPID_TRY(cupid_calloc((size_t)(n_q * M), sizeof *A, "section fit A", &A));
  CUPID_TRY(cupid_calloc((size_t)(M * M), sizeof *B, "section fit [A I]", &B));
  CUPID_TRY(cupid_malloc((size_t)(M * p), sizeof *w, "shape weights", &w));
  CUPID_TRY(cupid_malloc((size_t)(M * p), sizeof *node, "shape nodes", &node));
  for (cupid_int j = 0; j < n_q; j++) {
    const double *xq = x + 3 * q[j];
    int count;
    CUPID_TRY(cupid_cuf_shape_at(aux, xq[0], y_k, xq[2], node, w, &count));
    for (int n = 0; n < count; n++)
      if (node[n] / M == k) I[j * M + node[n] % M] += w[n];
  }
  for (int t = 0; t < M; t++) {
    double s = 0.0;
    for (cupid_int j = 0; j < n_q; j++) s += fabs(I[j * M + t]);
    CUPID_TRY_CHECK(s > 0.0, CUPID_ERR_MODEL,
                    "fictitious section y = %g: expansion term %d is zero at every PD node of "
                    "the plane that feeds it (too few PD nodes for the section mesh)",
                    y_k, t);
    for (cupid_int j = 0; j < n_q; j++)
      A[t * n_q + j] = (signed_weights ? I[j * M + t] : fabs(I[j * M + t])) / s;
  }
  for (int t = 0; t < M; t++)
    for (int u = 0; u < M; u++) {
      double s = 0.0;
      for (cupid_int j = 0; j < n_q; j++) s += A[t * n_q + j] * I[j * M + u];
      B[t * M + u] = s;
    }
  /* Solve in place: A becomes G. */
  st = dense_solve(M, B, n_q, A);
  if (st != CUPID_SUCCESS) {
    char msg[512];
    snprintf(msg, sizeof msg, "%s", cupid_error_message());
    st = CUPID_ERROR(st, "fictitious section y = %g: %s", y_k, msg);
    goto cleanup;
  }
  *G = A;
  A = NULL;
cleanup:
  cupid_free(&I);
  cupid_free(&A);
  cupid_free(&B);
  cupid_free(&w);
  cupid_free(&node);
  return st;
}

/* The real PD nodes of region r on the plane y (*q allocated, *n_q of them). */
static cupid_status plane_nodes(const cupid_coupling_options *o, cupid_pd_grid grid, int r,
                                double y, cupid_int **q, cupid_int *n_q) {
  const double *x = cupid_pd_grid_coords(grid);
  cupid_int n = cupid_pd_grid_num_nodes(grid);
  double h = o->spacing;
  const cupid_box *rb = &o->regions[r];
  for (int pass = 0; pass < 2; pass++) {
    cupid_int k = 0;
    for (cupid_int i = 0; i < n; i++) {
      const double *xi = x + 3 * i;
      if (fabs(xi[1] - y) > TOL * h) continue;
      double pt[3] = {xi[0], y, xi[2]};
      if (!cupid_box_contains(rb, pt, TOL * h)) continue;
      if (pass) (*q)[k] = i;
      k++;
    }
    if (!pass) {
      CUPID_CHECK(k > 0, CUPID_ERR_MODEL, "PD region %d: no real PD node on the plane y = %g", r,
                  y);
      *n_q = k;
      CUPID_CALL(cupid_malloc((size_t)k, sizeof **q, "section PD nodes", q));
    }
  }
  return CUPID_SUCCESS;
}

/* The first and last planes of real PD nodes of region r (along y). */
static cupid_status region_planes(const cupid_coupling_options *o, cupid_pd_grid grid, int r,
                                  double *first, double *last) {
  const double *x = cupid_pd_grid_coords(grid);
  cupid_int n = cupid_pd_grid_num_nodes(grid);
  const cupid_box *rb = &o->regions[r];
  *first = INFINITY;
  *last = -INFINITY;
  for (cupid_int i = 0; i < n; i++)
    if (cupid_box_contains(rb, x + 3 * i, TOL * o->spacing)) {
      *first = fmin(*first, x[3 * i + 1]);
      *last = fmax(*last, x[3 * i + 1]);
    }
  CUPID_CHECK(*first <= *last, CUPID_ERR_MODEL, "PD region %d holds no real PD node", r);
  return CUPID_SUCCESS;
}

/* Fictitious node k of the interface's element, on the section y_k inside the region: its
 * DOFs are the section fit (Eqs. 33-35) of the PD field there, U = G U^PD. On a PD plane the
 * fit of that plane; between two planes the linear interpolation of the fits of the two planes
 * around it (paper 000 section 4.1: the fictitious node is interpolated from the real PD nodes
 * around it); within h/2 of a region face, beyond the outermost plane, the linear
 * extrapolation from the two outermost planes (as for the fictitious FE nodes of partial
 * regions, partial.c). All three are exact for fields affine in y (the patch test). */
static cupid_status fit_node(interface_t *it, int k, const cupid_coupling_options *o,
                             cupid_pd_grid grid, int M, int p, int signed_weights) {
  const double *x = cupid_pd_grid_coords(grid);
  double h = o->spacing, first, last, y = cupid_cuf_beam_node_y(it->aux, k);
  CUPID_CALL(region_planes(o, grid, it->region, &first, &last));
  CUPID_CHECK(y >= first - 0.5 * h - TOL * h && y <= last + 0.5 * h + TOL * h, CUPID_ERR_MODEL,
              "fictitious FE node y = %g of the interface y = %g lies outside PD region %d "
              "(its PD planes span [%g, %g])",
              y, it->y_i, it->region, first, last);
  int n_planes = (int)floor((last - first) / h + 0.5) + 1;
  double t = (y - first) / h;
  double planes[2], wts[2];
  int np;
  double kr = floor(t + 0.5);
  if (fabs(t - kr) <= 1e-6 && kr >= 0 && kr <= n_planes - 1) {
    np = 1; /* on a plane */
    planes[0] = first + kr * h;
    wts[0] = 1.0;
  } else {
    CUPID_CHECK(n_planes >= 2, CUPID_ERR_MODEL,
                "fictitious FE node y = %g of the interface y = %g: PD region %d has one plane "
                "of nodes along y, two are needed to interpolate the node's section; make the "
                "region at least 2 spacings long or use the nearest-plane fictitious element",
                y, it->y_i, it->region);
    double k0 = fmin(fmax(floor(t), 0.0), (double)(n_planes - 2)), fr = t - k0;
    np = 2;
    planes[0] = first + k0 * h;
    planes[1] = planes[0] + h;
    wts[0] = 1.0 - fr;
    wts[1] = fr;
  }
  cupid_status st = CUPID_SUCCESS;
  cupid_int *qs[2] = {NULL, NULL}, nq[2] = {0, 0};
  double *Gs[2] = {NULL, NULL};
  cpl_fnode *fn = &it->fn[k];
  for (int j = 0; j < np; j++) {
    CUPID_TRY(plane_nodes(o, grid, it->region, planes[j], &qs[j], &nq[j]));
    CUPID_TRY(section_fit(it->aux, k, y, x, qs[j], nq[j], M, p, signed_weights, &Gs[j]));
  }
  if (np == 1) {
    fn->q = qs[0];
    fn->G = Gs[0];
    fn->n_q = nq[0];
    qs[0] = NULL;
    Gs[0] = NULL;
  } else {
    fn->n_q = nq[0] + nq[1];
    CUPID_TRY(cupid_malloc((size_t)fn->n_q, sizeof *fn->q, "section PD nodes", &fn->q));
    CUPID_TRY(cupid_malloc((size_t)(M * fn->n_q), sizeof *fn->G, "section fit", &fn->G));
    for (int j = 0, off = 0; j < 2; off += (int)nq[j], j++)
      for (cupid_int i = 0; i < nq[j]; i++) {
        fn->q[off + i] = qs[j][i];
        for (int s = 0; s < M; s++) fn->G[s * fn->n_q + off + i] = wts[j] * Gs[j][s * nq[j] + i];
      }
  }
cleanup:
  for (int j = 0; j < 2; j++) {
    cupid_free(&qs[j]);
    cupid_free(&Gs[j]);
  }
  return st;
}

/* The ends [*y0, *y1] of the beam element next to the interface: on the beam's side (fe_side)
 * or inside the region (removed). */
static void element_next_to(const cupid_cuf_beam beam, const interface_t *it, int fe_side,
                            double *y0, double *y1) {
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  double tol = TOL * (info.y_max - info.y_min);
  /* the region lies above y_i when side == 0 */
  int want_below = (it->side == 0) == (fe_side != 0);
  *y0 = *y1 = it->y_i;
  for (cupid_int e = 0; e < info.n_beam_elements; e++) {
    cupid_int first;
    double a, b;
    cupid_cuf_beam_element(beam, e, &first, &a, &b);
    if ((want_below && fabs(b - it->y_i) <= tol) || (!want_below && fabs(a - it->y_i) <= tol)) {
      *y0 = a;
      *y1 = b;
    }
  }
}

cupid_status cpl_fictitious_fe_choice(const cupid_coupling_options *o, cupid_fictitious_fe *kind,
                                      double *length) {
  *kind = o->fictitious_fe;
  *length = o->fictitious_length;
  CUPID_CHECK(*kind >= CUPID_FICTITIOUS_FE_REMOVED && *kind <= CUPID_FICTITIOUS_FE_LENGTH,
              CUPID_ERR_ARGUMENT, "unknown fictitious FE element kind %d", (int)*kind);
  CUPID_CHECK(*kind != CUPID_FICTITIOUS_FE_LENGTH || *length > 0.0, CUPID_ERR_ARGUMENT,
              "fictitious FE element of a given length: the length must be > 0 (got %g)",
              *length);
  return CUPID_SUCCESS;
}

/* The fictitious FE element of one interface (paper 000 sections 4.1, 4.3) and the fits of its
 * nodes inside the region. */
static cupid_status build_interface(interface_t *it, const cupid_coupling_options *o,
                                    cupid_cuf_beam beam, cupid_pd_grid grid, int M,
                                    cupid_fictitious_fe kind, double length) {
  cupid_cuf_info binfo;
  cupid_cuf_get_info(beam, &binfo);
  cupid_beam def = *o->beam_def;
  double h = o->spacing, dir = it->side ? -1.0 : 1.0, len = 0.5 * h, first, last;
  int nodes = 2;
  CUPID_CALL(region_planes(o, grid, it->region, &first, &last));
  /* the region's extent from the interface to its far face */
  double room = it->side ? it->y_i - (first - 0.5 * h) : (last + 0.5 * h) - it->y_i;
  if (kind == CUPID_FICTITIOUS_FE_ADJACENT || kind == CUPID_FICTITIOUS_FE_REMOVED) {
    double y0, y1;
    element_next_to(beam, it, kind == CUPID_FICTITIOUS_FE_ADJACENT, &y0, &y1);
    len = fmin(y1 - y0, room);
    nodes = binfo.element_nodes;
  } else if (kind == CUPID_FICTITIOUS_FE_LENGTH) {
    len = fmin(length, room);
  }
  CUPID_CHECK(len > 0.0, CUPID_ERR_MODEL, "interface y = %g: no room for a fictitious element",
              it->y_i);
  double ys[2] = {fmin(it->y_i, it->y_i + dir * len), fmax(it->y_i, it->y_i + dir * len)};
  int one = 1;
  def.axis_y = ys;
  def.axis_elements = &one;
  def.n_axis = 2;
  def.element_nodes = nodes;
  CUPID_CALL(cupid_cuf_beam_create_from(&def, o->materials, o->n_materials, &it->aux));
  it->n_nodes = nodes;
  it->end_i = it->side ? nodes - 1 : 0;
  CUPID_CALL(cupid_calloc((size_t)nodes, sizeof *it->fn, "fictitious FE nodes", &it->fn));
  cupid_cuf_info info;
  cupid_cuf_get_info(it->aux, &info);
  int te = info.expansion == CUPID_EXPANSION_TE;
  for (int k = 0; k < nodes; k++)
    if (k != it->end_i) CUPID_CALL(fit_node(it, k, o, grid, M, nodes, te));
  return CUPID_SUCCESS;
}

/* ----------------------------------------------------------------- fictitious PD nodes */

/* Extended grid: real regions first (so real nodes keep their materials), then, for every
 * interface, a slab of the region's section reaching 2 delta (whole spacings) into the beam. */
static cupid_status extended_grid(const cupid_coupling_options *o, const interface_t *iface,
                                  int n_iface, double y_min, double y_max,
                                  const cupid_pd_grid_partition *cut, cupid_pd_grid *ext) {
  cupid_status st = CUPID_SUCCESS;
  int nb = o->n_regions + n_iface;
  cupid_box *boxes = NULL;
  int *mats = NULL;
  double h = o->spacing;
  /* LPS couples nodes two family radii apart; with EXACT partial volumes a family reaches
   * delta + sqrt(3)/2 h (pd.h). Bond-based needs one radius, the slab is kept the same. */
  double radius = o->pd.horizon + (o->pd.partial_volume == CUPID_PARTIAL_EXACT ? 0.5 * sqrt(3.0) * h : 0.0);
  double L = h * ceil(2.0 * radius / h - TOL);
  CUPID_TRY(cupid_calloc((size_t)nb, sizeof *boxes, "extended boxes", &boxes));
  CUPID_TRY(cupid_calloc((size_t)nb, sizeof *mats, "extended materials", &mats));
  for (int r = 0; r < o->n_regions; r++) {
    boxes[r] = o->regions[r];
    mats[r] = o->region_materials[r];
  }
  int k = o->n_regions;
  for (int f = 0; f < n_iface; f++) {
    const interface_t *it = &iface[f];
    cupid_box b = o->regions[it->region];
    if (it->side == 0) { /* PD above: fictitious nodes below */
      double room = h * floor((it->y_i - y_min) / h + TOL);
      b.lo[1] = it->y_i - fmin(L, room);
      b.hi[1] = it->y_i;
    } else {
      double room = h * floor((y_max - it->y_i) / h + TOL);
      b.lo[1] = it->y_i;
      b.hi[1] = it->y_i + fmin(L, room);
    }
    if (b.hi[1] - b.lo[1] < 0.5 * h) continue;
    boxes[k] = b;
    mats[k++] = o->region_materials[it->region];
  }
  cupid_pd_grid_options go = cpl_ext_grid_options(h, cut);
  CUPID_TRY(cupid_pd_grid_create(&go, k, boxes, mats, ext));
cleanup:
  cupid_free(&boxes);
  cupid_free(&mats);
  return st;
}

cupid_pd_grid_options cpl_ext_grid_options(double h, const cupid_pd_grid_partition *cut) {
  cupid_pd_grid_options go = {.spacing = h, .dimension = 3, .area = 0.0};
  if (cut && cut->parts > 1) {
    go.parts = cut->parts;
    go.part = cut->part;
    go.halo_layers = cut->halo_layers;
    go.own_z[0] = cut->own_z[0];
    go.own_z[1] = cut->own_z[1];
  }
  return go;
}

void cpl_ext_map_free(ext_map *m) {
  cupid_free(&m->real);
  cupid_free(&m->fptr);
  cupid_free(&m->fnode);
  cupid_free(&m->fw);
}

cupid_status cpl_map_extended(cupid_pd_grid ext, cupid_pd_grid grid, cupid_cuf_beam beam,
                                 int M, int p, ext_map *m, cupid_int *n_fict) {
  cupid_int n_ext = cupid_pd_grid_num_nodes(ext);
  const double *xe = cupid_pd_grid_coords(ext), *xr = cupid_pd_grid_coords(grid);
  double o[3], h = cupid_pd_grid_spacing(grid);
  cupid_pd_grid_origin(grid, o);
  CUPID_CALL(cupid_malloc((size_t)n_ext, sizeof *m->real, "extended map", &m->real));
  CUPID_CALL(cupid_calloc((size_t)n_ext + 1, sizeof *m->fptr, "fictitious pointers", &m->fptr));
  cupid_int cap = 1024, nw = 0;
  CUPID_CALL(cupid_malloc((size_t)cap, sizeof *m->fnode, "fictitious weights", &m->fnode));
  CUPID_CALL(cupid_malloc((size_t)cap, sizeof *m->fw, "fictitious weights", &m->fw));
  cupid_int *node = NULL;
  double *w = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_malloc((size_t)(M * p), sizeof *node, "shape nodes", &node));
  CUPID_TRY(cupid_malloc((size_t)(M * p), sizeof *w, "shape weights", &w));
  *n_fict = 0;
  for (cupid_int i = 0; i < n_ext; i++) {
    const double *x = xe + 3 * i;
    cupid_int ijk[3];
    for (int a = 0; a < 3; a++) ijk[a] = (cupid_int)floor((x[a] - o[a]) / h);
    cupid_int r = cupid_pd_grid_node_at(grid, ijk[0], ijk[1], ijk[2]);
    if (r >= 0) {
      const double *y = xr + 3 * r;
      for (int a = 0; a < 3; a++)
        CUPID_TRY_CHECK(fabs(y[a] - x[a]) < 1e-6 * h, CUPID_ERR_ARGUMENT,
                        "extended and real PD lattices differ at (%g, %g, %g)", x[0], x[1], x[2]);
    }
    m->real[i] = r;
    if (r < 0) {
      int count;
      st = cupid_cuf_shape_at(beam, x[0], x[1], x[2], node, w, &count);
      if (st != CUPID_SUCCESS) {
        st = CUPID_ERROR(CUPID_ERR_MODEL,
                         "fictitious PD node (%g, %g, %g), within 2 delta of an interface, lies "
                         "outside the beam's active part; keep PD regions at least 2 delta "
                         "from the beam ends and from each other",
                         x[0], x[1], x[2]);
        goto cleanup;
      }
      (*n_fict)++;
      for (int n = 0; n < count; n++) {
        if (w[n] == 0.0) continue;
        if (nw == cap) {
          cap *= 2;
          CUPID_TRY(cupid_realloc((size_t)cap, sizeof *m->fnode, "fictitious weights", &m->fnode));
          CUPID_TRY(cupid_realloc((size_t)cap, sizeof *m->fw, "fictitious weights", &m->fw));
        }
        m->fnode[nw] = node[n];
        m->fw[nw++] = w[n];
      }
    }
    m->fptr[i + 1] = nw;
  }
cleanup:
  cupid_free(&node);
  cupid_free(&w);
  return st;
}

/* ------------------------------------------------------------------------- assembly */

/* Rows of real PD nodes: K^PD on real columns, K^{f-PD} I^{f-PD} on FE columns (Eq. 38). */
cupid_status cpl_pd_rows(cpl_rowbuild *rb, const cupid_csr_t *Ke, const ext_map *m,
                            cupid_int n_ext, cupid_int n_pd) {
  cupid_int *ext_of = NULL;
  CUPID_CALL(cupid_malloc((size_t)n_pd, sizeof *ext_of, "real -> extended", &ext_of));
  for (cupid_int i = 0; i < n_ext; i++)
    if (m->real[i] >= 0) ext_of[m->real[i]] = i;
  cupid_status st = CUPID_SUCCESS;
  for (cupid_int r = 0; r < n_pd; r++) {
    cupid_int I = ext_of[r];
    for (cupid_int k = Ke->rowptr[I]; k < Ke->rowptr[I + 1]; k++) {
      cupid_int J = Ke->col[k];
      const double *blk = Ke->val + 9 * k;
      if (m->real[J] >= 0) {
        CUPID_TRY(cpl_rowbuild_add(rb, m->real[J], 1.0, blk));
      } else {
        for (cupid_int n = m->fptr[J]; n < m->fptr[J + 1]; n++)
          CUPID_TRY(cpl_rowbuild_add(rb, n_pd + m->fnode[n], m->fw[n], blk));
      }
    }
    CUPID_TRY(cpl_rowbuild_end_row(rb, r));
  }
cleanup:
  cupid_free(&ext_of);
  return st;
}

/* Rows of FE nodes: K^FE, plus on interface nodes the fictitious element: its real-real block
 * and K^{f-FE} I^{f-FE} on PD columns (Eq. 38). */
static cupid_status fe_rows(cpl_rowbuild *rb, const cupid_csr_t *Kb, const interface_t *iface,
                            int n_iface, cupid_int n_pd, int M, cupid_int n_fe_nodes,
                            cupid_csr *Kaux) {
  for (cupid_int a = 0; a < n_fe_nodes; a++) {
    for (cupid_int k = Kb->rowptr[a]; k < Kb->rowptr[a + 1]; k++)
      CUPID_CALL(cpl_rowbuild_add(rb, n_pd + Kb->col[k], 1.0, Kb->val + 9 * k));
    cupid_int bn = a / M;
    int tau = (int)(a % M);
    for (int f = 0; f < n_iface; f++) {
      const interface_t *it = &iface[f];
      if (it->beam_node != bn) continue;
      const cupid_csr_t *Ka = Kaux[f];
      cupid_int row = (cupid_int)it->end_i * M + tau;
      for (cupid_int k = Ka->rowptr[row]; k < Ka->rowptr[row + 1]; k++) {
        cupid_int c = Ka->col[k];
        const double *blk = Ka->val + 9 * k;
        int s = (int)(c % M), node = (int)(c / M);
        if (node == it->end_i) {
          CUPID_CALL(cpl_rowbuild_add(rb, n_pd + bn * M + s, 1.0, blk));
        } else {
          const cpl_fnode *fn = &it->fn[node];
          for (cupid_int q = 0; q < fn->n_q; q++) {
            double g = fn->G[s * fn->n_q + q];
            if (g != 0.0) CUPID_CALL(cpl_rowbuild_add(rb, fn->q[q], g, blk));
          }
        }
      }
    }
    CUPID_CALL(cpl_rowbuild_end_row(rb, n_pd + a));
  }
  return CUPID_SUCCESS;
}

/* The interfaces: region y bounds whose beam node is still used by an active pair. */
cupid_status cpl_find_interfaces(cupid_cuf_beam beam, const cupid_coupling_options *o,
                                    cupid_coupling_h c) {
  CUPID_CALL(cupid_calloc((size_t)(2 * o->n_regions), sizeof *c->iface, "interfaces", &c->iface));
  for (int r = 0; r < o->n_regions; r++)
    for (int side = 0; side < 2; side++) {
      double y = side ? o->regions[r].hi[1] : o->regions[r].lo[1], below, above;
      cupid_int bn = element_end_at(beam, y, &below, &above);
      if (bn < 0 || !cupid_cuf_node_used(beam, 0, bn)) continue;
      interface_t *it = &c->iface[c->n_iface++];
      it->y_i = cupid_cuf_beam_node_y(beam, bn);
      it->side = side;
      it->region = r;
      it->beam_node = bn;
    }
  return CUPID_SUCCESS;
}

/* The parts of a coupling whose regions all span the section: interfaces normal to the axis,
 * one fictitious B2 element each, fictitious PD slabs. */
static cupid_status full_parts(cupid_cuf_beam beam, cupid_pd_grid grid,
                               const cupid_coupling_options *o, cupid_coupling_h c, cpl_parts *p) {
  cupid_status st = CUPID_SUCCESS;
  cupid_csr Kb = NULL, *Kaux = NULL;
  int n_aux = 0;
  cpl_rowbuild rb = {0};
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  int M = info.M, pe = info.element_nodes;
  cupid_int n_pd = p->n_pd, n_ffe = 0;
  cupid_fictitious_fe kind;
  double length;
  CUPID_TRY(cpl_fictitious_fe_choice(o, &kind, &length));
  CUPID_TRY(cpl_find_interfaces(beam, o, c));
  for (int f = 0; f < c->n_iface; f++) {
    CUPID_TRY(build_interface(&c->iface[f], o, beam, grid, M, kind, length));
    n_ffe += (cupid_int)(c->iface[f].n_nodes - 1) * M;
  }

  CUPID_TRY(extended_grid(o, c->iface, c->n_iface, info.y_min, info.y_max, NULL, &p->ext));
  p->n_ext = cupid_pd_grid_num_nodes(p->ext);
  CUPID_TRY(cpl_map_extended(p->ext, grid, beam, M, pe, &p->map, &p->n_fict));
  CUPID_TRY_CHECK(p->n_ext - p->n_fict == n_pd, CUPID_ERR_ARGUMENT,
                  "extended grid holds %lld real nodes, expected %lld",
                  (long long)(p->n_ext - p->n_fict), (long long)n_pd);

  CUPID_TRY(cupid_cuf_assemble(beam, &Kb));
  CUPID_TRY(cupid_calloc((size_t)(c->n_iface + 1), sizeof *Kaux, "fictitious elements", &Kaux));
  n_aux = c->n_iface;
  for (int f = 0; f < n_aux; f++) CUPID_TRY(cupid_cuf_assemble(c->iface[f].aux, &Kaux[f]));
  cupid_int N = n_pd + info.n_fe_nodes;
  CUPID_TRY(cpl_rowbuild_init(&rb, info.n_fe_nodes, N));
  CUPID_TRY(fe_rows(&rb, Kb, c->iface, c->n_iface, n_pd, M, info.n_fe_nodes, Kaux));
  CUPID_TRY(cpl_rowbuild_finish(&rb, &p->Kfe));

  c->info = (cupid_coupling_info){.n_real_pd = n_pd,
                                  .n_fictitious_pd = p->n_fict,
                                  .n_interfaces = c->n_iface,
                                  .n_fictitious_fe = n_ffe,
                                  .fictitious_fe = kind};
cleanup:
  for (int f = 0; f < n_aux; f++) cupid_csr_destroy(&Kaux[f]);
  cupid_free(&Kaux);
  cupid_csr_destroy(&Kb);
  cpl_rowbuild_free(&rb);
  return st;
}

/* The parts on a whole real grid. */
static cupid_status whole_parts(cupid_cuf_beam beam, cupid_pd_grid grid,
                                const cupid_coupling_options *o, cupid_coupling_h c, cpl_parts *p) {
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  memset(p, 0, sizeof *p);
  p->n_pd = cupid_pd_grid_num_nodes(grid);
  CUPID_CHECK(info.dof_offset == 3 * p->n_pd, CUPID_ERR_ARGUMENT,
              "the beam's DOF offset (%lld) must be 3 x the real PD nodes (%lld)",
              (long long)info.dof_offset, (long long)(3 * p->n_pd));
  cupid_status st = any_partial_region(beam, o) ? cpl_partial_parts(beam, grid, o, c, p)
                                                : full_parts(beam, grid, o, c, p);
  if (st != CUPID_SUCCESS) cpl_parts_free(p);
  return st;
}

static int any_partial_region(cupid_cuf_beam beam, const cupid_coupling_options *o) {
  int any = 0;
  for (int r = 0; r < o->n_regions; r++) any |= !cpl_region_full(beam, &o->regions[r]);
  return any;
}

/* This slab's share of the whole FE rows F (block columns [G real PD nodes | FE nodes]): the
 * PD columns of its owned nodes (local indices), the FE columns on the last slab only, so
 * that the shares sum over the slabs to F. */
static cupid_status fe_rows_share(const cupid_csr_t *F, const cupid_pd_grid_partition *cut,
                                  cupid_int n_local, cpl_rowbuild *rb, cupid_csr *share) {
  const cupid_int G = cut->global_nodes, g0 = cut->first_global + cut->owned_first,
                  g1 = cut->first_global + cut->owned_last;
  const int last = cut->part == cut->parts - 1;
  CUPID_CALL(cpl_rowbuild_init(rb, F->nrows, n_local + F->nrows));
  for (cupid_int a = 0; a < F->nrows; a++) {
    for (cupid_int k = F->rowptr[a]; k < F->rowptr[a + 1]; k++) {
      cupid_int col = F->col[k];
      const double *blk = F->val + 9 * k;
      if (col < G && col >= g0 && col < g1)
        CUPID_CALL(cpl_rowbuild_add(rb, col - cut->first_global, 1.0, blk));
      else if (col >= G && last)
        CUPID_CALL(cpl_rowbuild_add(rb, n_local + col - G, 1.0, blk));
    }
    CUPID_CALL(cpl_rowbuild_end_row(rb, n_local + a));
  }
  return cpl_rowbuild_finish(rb, share);
}

/* A slab of a partitioned real grid (issue 6). The FE rows are built on the whole real grid,
 * whose coordinates are cheap next to its PD operator (the section fits of Eqs. 33-35 and
 * the fictitious FE nodes of regions over part of the section read whole planes of PD nodes,
 * which span the slabs), then cut to this slab's share (fe_rows_share). The extended grid is
 * cut like the real slab (the same z window and halo), so its owned real nodes are the real
 * slab's, and the PD rows of the owned nodes are the whole operator's. The interfaces and
 * the info in c are the whole model's. */
static cupid_status slab_parts(cupid_cuf_beam beam, cupid_pd_grid grid,
                               const cupid_pd_grid_partition *cut, const cupid_coupling_options *o,
                               cupid_coupling_h c, cpl_parts *p) {
  cupid_status st = CUPID_SUCCESS;
  cupid_pd_grid whole = NULL;
  cpl_parts wp = {0};
  cpl_rowbuild rb = {0};
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  const cupid_int n_local = cupid_pd_grid_num_nodes(grid);
  CUPID_CHECK(info.dof_offset == 3 * n_local, CUPID_ERR_ARGUMENT,
              "the beam's DOF offset (%lld) must be 3 x the slab's PD nodes (%lld)",
              (long long)info.dof_offset, (long long)(3 * n_local));
  cupid_pd_grid_options go = {.spacing = o->spacing, .dimension = 3};
  CUPID_TRY(cupid_pd_grid_create(&go, o->n_regions, o->regions, o->region_materials, &whole));
  CUPID_TRY_CHECK(cupid_pd_grid_num_nodes(whole) == cut->global_nodes, CUPID_ERR_ARGUMENT,
                  "the regions give %lld PD nodes, the slab's grid %lld",
                  (long long)cupid_pd_grid_num_nodes(whole), (long long)cut->global_nodes);
  CUPID_TRY(cupid_cuf_set_dof_offset(beam, 3 * cut->global_nodes));
  st = whole_parts(beam, whole, o, c, &wp);
  (void)cupid_cuf_set_dof_offset(beam, 3 * n_local); /* back, whatever happened */
  CUPID_TRY(st);
  CUPID_TRY(fe_rows_share(wp.Kfe, cut, n_local, &rb, &p->Kfe));
  p->n_pd = n_local;
  if (any_partial_region(beam, o))
    CUPID_TRY(cpl_partial_extended_grid(beam, o, cut, &p->ext));
  else
    CUPID_TRY(extended_grid(o, c->iface, c->n_iface, info.y_min, info.y_max, cut, &p->ext));
  p->n_ext = cupid_pd_grid_num_nodes(p->ext);
  CUPID_TRY(cpl_map_extended(p->ext, grid, beam, info.M, info.element_nodes, &p->map, &p->n_fict));
  CUPID_TRY_CHECK(p->n_ext - p->n_fict == n_local, CUPID_ERR_ARGUMENT,
                  "the extended slab holds %lld real nodes, the real slab %lld",
                  (long long)(p->n_ext - p->n_fict), (long long)n_local);
cleanup:
  cpl_parts_free(&wp);
  cpl_rowbuild_free(&rb);
  cupid_pd_grid_destroy(&whole);
  return st;
}

cupid_status cpl_parts_build(cupid_cuf_beam beam, cupid_pd_grid grid,
                             const cupid_coupling_options *o, cupid_coupling_h c, cpl_parts *p) {
  cupid_pd_grid_partition cut;
  cupid_pd_grid_get_partition(grid, &cut);
  if (cut.parts <= 1) return whole_parts(beam, grid, o, c, p);
  memset(p, 0, sizeof *p);
  cupid_status st = slab_parts(beam, grid, &cut, o, c, p);
  if (st != CUPID_SUCCESS) cpl_parts_free(p);
  return st;
}

void cpl_parts_free(cpl_parts *p) {
  cupid_pd_grid_destroy(&p->ext);
  cpl_ext_map_free(&p->map);
  cupid_csr_destroy(&p->Kfe);
}

cupid_status cpl_parts_assemble(const cpl_parts *p, const cupid_pd_operator_options *pd,
                                cupid_csr *K) {
  cupid_pd_operator op = NULL;
  CUPID_CALL(cupid_pd_operator_create(p->ext, pd, &op));
  cupid_status st = cpl_parts_assemble_op(p, op, K);
  cupid_pd_operator_destroy(&op);
  return st;
}

cupid_status cpl_parts_assemble_op(const cpl_parts *p, const cupid_pd_operator op, cupid_csr *K) {
  cupid_status st = CUPID_SUCCESS;
  cupid_csr Ke = NULL;
  cpl_rowbuild rb = {0};
  cupid_int n_pd = p->n_pd, N = n_pd + p->Kfe->nrows;
  CUPID_TRY(cupid_pd_operator_assemble(op, &Ke));
  CUPID_TRY(cpl_rowbuild_init(&rb, N, N));
  CUPID_TRY(cpl_pd_rows(&rb, Ke, &p->map, p->n_ext, n_pd));
  cupid_csr_destroy(&Ke);
  const cupid_csr_t *F = p->Kfe;
  for (cupid_int a = 0; a < F->nrows; a++) {
    for (cupid_int k = F->rowptr[a]; k < F->rowptr[a + 1]; k++)
      CUPID_TRY(cpl_rowbuild_add(&rb, F->col[k], 1.0, F->val + 9 * k));
    CUPID_TRY(cpl_rowbuild_end_row(&rb, n_pd + a));
  }
  CUPID_TRY(cpl_rowbuild_finish(&rb, K));
cleanup:
  cupid_csr_destroy(&Ke);
  cpl_rowbuild_free(&rb);
  return st;
}

cupid_status cupid_coupling_create(cupid_cuf_beam beam, cupid_pd_grid grid,
                                   const cupid_coupling_options *o, cupid_coupling_h *out,
                                   cupid_csr *K) {
  cupid_status st = CUPID_SUCCESS;
  cupid_coupling_h c = NULL;
  cpl_parts parts = {0};
  CUPID_CALL(cupid_calloc(1, sizeof *c, "coupling", &c));
  CUPID_TRY(cpl_parts_build(beam, grid, o, c, &parts));
  CUPID_TRY(cpl_parts_assemble(&parts, &o->pd, K));
  *out = c;
  c = NULL;
cleanup:
  cpl_parts_free(&parts);
  cupid_coupling_destroy(&c);
  return st;
}

void cupid_coupling_destroy(cupid_coupling_h *c) {
  if (!c || !*c) return;
  for (int f = 0; f < (*c)->n_iface; f++) {
    interface_t *it = &(*c)->iface[f];
    cupid_cuf_beam_destroy(&it->aux);
    for (int k = 0; it->fn && k < it->n_nodes; k++) {
      cupid_free(&it->fn[k].q);
      cupid_free(&it->fn[k].G);
    }
    cupid_free(&it->fn);
  }
  cupid_free(&(*c)->iface);
  cupid_free(&(*c)->tied);
  cupid_free(&(*c)->tptr);
  cupid_free(&(*c)->tnode);
  cupid_free(&(*c)->tw);
  cupid_free(&(*c)->tied_of);
  cupid_free(&(*c)->fptr);
  cupid_free(&(*c)->flist);
  cupid_free(&(*c)->fw);
  cupid_csr_destroy(&(*c)->Kb);
  cupid_free(c);
}

void cupid_coupling_get_info(const cupid_coupling_h c, cupid_coupling_info *info) {
  *info = c->info;
}
