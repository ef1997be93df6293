/* The uniform PD grid of a union of boxes (paper 000 section 2.2: nodes at cell centres), or of
 * cylinders and spheres less holes (issue 35: the cells whose centres lie inside). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "pd/pd_internal.h"

/* The largest bounding box we index densely (8 bytes per cell). */
#define PD_MAX_CELLS ((cupid_int)1 << 31)

static const char axis_name[3] = {'x', 'y', 'z'};

/* Lattice index of a box bound into *idx; 0 with a reason in msg when it is off the lattice. */
static int bound_index(double value, double origin, double h, int axis, const char *which,
                       char *msg, size_t len, cupid_int *idx) {
  double t = (value - origin) / h;
  double r = nearbyint(t);
  /* Tolerance 1e-9 h: bounds written with a few digits must still land on the lattice. */
  if (fabs(t - r) > 1e-9 || !isfinite(t)) {
    snprintf(msg, len,
             "%c %s bound %.15g is not on the lattice (origin %.15g, spacing %.15g): nearest "
             "lattice planes %.15g and %.15g",
             axis_name[axis], which, value, origin, h, origin + floor(t) * h,
             origin + ceil(t) * h);
    return 0;
  }
  /* Converting a double beyond the int64 range is undefined behaviour: refuse it first (the
   * grid itself refuses bounding boxes over 2^31 cells later, with the count). */
  if (fabs(r) > 4.0e18) {
    snprintf(msg, len, "%c %s bound %.15g lies %.3g spacings from the grid origin (at most 4e18)",
             axis_name[axis], which, value, fabs(r));
    return 0;
  }
  *idx = (cupid_int)r;
  return 1;
}

/* The box whose shape holds cell (i, j, k) of the lattice (origin, h), the first one when
 * several do, or -1 (none, or a hole holds its centre). */
static int cell_owner(const cupid_pd_grid_options *opts, int n_boxes, const cupid_int *range,
                      const double origin[3], double h, cupid_int i, cupid_int j, cupid_int k) {
  const cupid_int ijk[3] = {i, j, k};
  double p[3];
  for (int a = 0; a < 3; a++)
    p[a] = (opts->dimension == 3 || a == 1) ? origin[a] + ((double)ijk[a] + 0.5) * h : 0.0;
  int owner = -1;
  for (int b = 0; b < n_boxes && owner < 0; b++) {
    const cupid_int *r = range + 6 * b;
    if (i >= r[0] && i < r[1] && j >= r[2] && j < r[3] && k >= r[4] && k < r[5] &&
        (!opts->shapes || cupid_shape_contains(&opts->shapes[b], p)))
      owner = b;
  }
  for (int q = 0; q < opts->n_holes && owner >= 0; q++)
    if (cupid_shape_contains(&opts->holes[q], p)) owner = -1;
  return owner;
}

/* Nodes of the union in each z layer [0, nk) of the bounding box (a cell is a node when some
 * box holds it), for splitting the layers into slabs. O(cells x boxes), no per-cell memory. */
static cupid_status layer_counts(const cupid_pd_grid_options *opts, int n_boxes,
                                 const cupid_int *range, const struct cupid_pd_grid_private *g,
                                 cupid_int **counts) {
  const cupid_int *n = g->n;
  CUPID_CALL(cupid_calloc((size_t)n[2] + 1, sizeof **counts, "PD layer counts", counts));
  cupid_int *cnt = *counts;
#pragma omp parallel for schedule(dynamic, 1)
  for (cupid_int k = 0; k < n[2]; k++) {
    cupid_int c = 0;
    for (cupid_int j = 0; j < n[1]; j++)
      for (cupid_int i = 0; i < n[0]; i++) c += cell_owner(opts, n_boxes, range, g->origin, g->h, i, j, k) >= 0;
    cnt[k] = c;
  }
  return CUPID_SUCCESS;
}

/* A slab grid (opts->parts > 1, issue 6): part p owns the z layers [k0, k1) that split the
 * union's nodes into parts nearly equal slabs, and keeps halo_layers more on each side. The
 * bounding box and the box ranges are cut to the window [w0, w1) and shifted to start at 0
 * (a box outside it gets an empty z range); g->part gets the global counts, with owned_first
 * already local and owned_last holding the nodes of the layers [k1, w1), which the caller
 * subtracts from the slab's node count. */
static cupid_status apply_partition(const cupid_pd_grid_options *opts, int n_boxes,
                                    cupid_int *range, struct cupid_pd_grid_private *g) {
  if (opts->parts <= 1) return CUPID_SUCCESS;
  CUPID_CHECK(g->dim == 3, CUPID_ERR_UNSUPPORTED, "only 3D grids are split into slabs");
  CUPID_CHECK(opts->part >= 0 && opts->part < opts->parts && opts->halo_layers >= 0,
              CUPID_ERR_ARGUMENT, "slab %d of %d with %d halo layers", opts->part, opts->parts,
              opts->halo_layers);
  const cupid_int nk = g->n[2];
  if (opts->parts > nk)
    return CUPID_ERROR(CUPID_ERR_MODEL,
                       "%d MPI ranks for a PD grid of %lld z layers: each rank needs at least one "
                       "layer (use fewer ranks)",
                       opts->parts, (long long)nk);
  cupid_int *cnt = NULL;
  CUPID_CALL(layer_counts(opts, n_boxes, range, g, &cnt));
  /* prefix: cnt[k] becomes the nodes of the layers below k */
  cupid_int total = 0;
  for (cupid_int k = 0; k <= nk; k++) {
    cupid_int c = k < nk ? cnt[k] : 0;
    cnt[k] = total;
    total += c;
  }
  /* Slab boundaries: the first layer whose prefix reaches p total / parts, kept increasing so
   * that every part owns at least one layer. */
  cupid_int bound[2];
  for (int e = 0; e < 2; e++) {
    int p = opts->part + e;
    cupid_int k = 0;
    if (p >= opts->parts) {
      k = nk;
    } else if (p > 0) {
      cupid_int target = (cupid_int)((double)total * p / opts->parts + 0.5);
      while (k < nk && cnt[k] < target) k++;
      if (k < p) k = p;                                  /* parts below own >= 1 layer each */
      if (k > nk - (opts->parts - p)) k = nk - (opts->parts - p); /* and those above */
    }
    bound[e] = k;
  }
  if (opts->own_z[1] > opts->own_z[0]) /* an explicit window (another grid's slab) */
    for (int e = 0; e < 2; e++) {
      cupid_int k = (cupid_int)floor((opts->own_z[e] - g->origin[2]) / g->h + 0.5);
      bound[e] = k < 0 ? 0 : k > nk ? nk : k;
    }
  if (cnt[bound[1]] == cnt[bound[0]]) {
    cupid_free(&cnt);
    return CUPID_ERROR(CUPID_ERR_MODEL,
                       "MPI rank %d of %d would own only empty z layers of the PD grid (the "
                       "regions leave a gap along z): use fewer ranks",
                       opts->part, opts->parts);
  }
  cupid_int w0 = bound[0] - opts->halo_layers, w1 = bound[1] + opts->halo_layers;
  if (w0 < 0) w0 = 0;
  if (w1 > nk) w1 = nk;
  g->part = (cupid_pd_grid_partition){.global_nodes = total,
                                      .first_global = cnt[w0],
                                      .owned_first = cnt[bound[0]] - cnt[w0],
                                      .owned_last = cnt[w1] - cnt[bound[1]],
                                      .parts = opts->parts,
                                      .part = opts->part,
                                      .halo_layers = opts->halo_layers,
                                      .own_z = {g->origin[2] + (double)bound[0] * g->h,
                                                g->origin[2] + (double)bound[1] * g->h}};
  cupid_free(&cnt);
  g->origin[2] += (double)w0 * g->h;
  g->n[2] = w1 - w0;
  for (int b = 0; b < n_boxes; b++) {
    cupid_int *r = range + 6 * b;
    cupid_int lo = r[4] > w0 ? r[4] : w0, hi = r[5] < w1 ? r[5] : w1;
    r[4] = lo - w0;
    r[5] = hi > lo ? hi - w0 : lo - w0;
  }
  return CUPID_SUCCESS;
}

void cupid_pd_grid_destroy(cupid_pd_grid *grid) {
  if (!grid || !*grid) return;
  struct cupid_pd_grid_private *g = *grid;
  cupid_free(&g->coords);
  cupid_free(&g->material);
  cupid_free(&g->ijk);
  cupid_free(&g->dense);
  cupid_free(&g->vfrac);
  cupid_free(grid);
}

cupid_status pd_grid_build(const cupid_pd_grid_options *opts, int n_boxes, const cupid_box *boxes,
                           const int *materials, int *bad_box, char *msg, size_t len,
                           cupid_pd_grid *grid) {
  cupid_status st = CUPID_SUCCESS;
  struct cupid_pd_grid_private *g = NULL;
  cupid_int *range = NULL; /* 6 per box: lo/hi cell index per axis */
  *bad_box = -1;
  msg[0] = '\0';
  *grid = NULL;
  CUPID_CHECK(opts && boxes && materials && n_boxes > 0, CUPID_ERR_ARGUMENT,
              "the grid needs options and at least one box");
  const int dim = opts->dimension;
  const double h = opts->spacing;
  CUPID_CHECK(dim == 1 || dim == 3, CUPID_ERR_MODEL, "dimension must be 1 or 3, got %d", dim);
  CUPID_CHECK(isfinite(h) && h > 0, CUPID_ERR_MODEL, "spacing must be positive, got %g", h);
  CUPID_CHECK(dim == 3 || (isfinite(opts->area) && opts->area > 0), CUPID_ERR_MODEL,
              "a 1D grid needs a positive cross-section area, got %g", opts->area);

  CUPID_TRY(cupid_calloc(1, sizeof *g, "the PD grid", &g));
  g->dim = dim;
  g->h = h;
  g->area = dim == 1 ? opts->area : h * h;
  g->volume = dim == 1 ? opts->area * h : h * h * h;

  /* Lattice origin: the lowest corner of all boxes per axis (of the box-shaped ones when
   * some are: a cylinder's or a sphere's bounding box need not be on the lattice). */
  int any_box = 0;
  for (int b = 0; b < n_boxes; b++) any_box |= !opts->shapes || opts->shapes[b].kind == CUPID_SHAPE_BOX;
  for (int a = 0; a < 3; a++) {
    int used = dim == 3 || a == 1;
    if (!used) {
      g->origin[a] = -0.5 * h; /* cell centre at 0 */
      continue;
    }
    double lo = INFINITY;
    for (int b = 0; b < n_boxes; b++) {
      if (!boxes[b].has[a] || !isfinite(boxes[b].lo[a]) || !isfinite(boxes[b].hi[a])) {
        *bad_box = b;
        snprintf(msg, len, "the %c range must be given (PD regions are bounded boxes)",
                 axis_name[a]);
        st = CUPID_ERR_MODEL;
        goto cleanup;
      }
      const int is_box = !opts->shapes || opts->shapes[b].kind == CUPID_SHAPE_BOX;
      if ((is_box || !any_box) && boxes[b].lo[a] < lo) lo = boxes[b].lo[a];
    }
    for (int b = 0; opts->shapes && b < n_boxes; b++) /* whole cells down to the lowest shape */
      if (boxes[b].lo[a] < lo) lo -= ceil((lo - boxes[b].lo[a]) / h - 1e-9) * h;
    if (opts->has_anchor) { /* the anchor's lattice, down to the lowest bound of all */
      for (int b = 0; b < n_boxes; b++) lo = fmin(lo, boxes[b].lo[a]);
      lo = opts->anchor[a] + floor((lo - opts->anchor[a]) / h + 1e-9) * h;
    }
    g->origin[a] = lo;
  }

  /* Cell ranges of every box, and the bounding box. */
  CUPID_TRY(cupid_calloc(6 * (size_t)n_boxes, sizeof *range, "box ranges", &range));
  for (int a = 0; a < 3; a++) g->n[a] = 1;
  for (int b = 0; b < n_boxes; b++) {
    for (int a = 0; a < 3; a++) {
      if (!(dim == 3 || a == 1)) {
        range[6 * b + 2 * a] = 0;
        range[6 * b + 2 * a + 1] = 1;
        continue;
      }
      cupid_int lo = 0, hi = 0;
      if (opts->shapes && opts->shapes[b].kind != CUPID_SHAPE_BOX) { /* the cells it may hold */
        lo = (cupid_int)floor((boxes[b].lo[a] - g->origin[a]) / h + 1e-9);
        hi = (cupid_int)ceil((boxes[b].hi[a] - g->origin[a]) / h - 1e-9);
      } else if (opts->has_anchor) { /* the cells whose centres lie in the box */
        lo = (cupid_int)ceil((boxes[b].lo[a] - g->origin[a]) / h - 0.5 - 1e-9);
        hi = (cupid_int)floor((boxes[b].hi[a] - g->origin[a]) / h - 0.5 + 1e-9) + 1;
      } else if (!bound_index(boxes[b].lo[a], g->origin[a], h, a, "lower", msg, len, &lo) ||
                 !bound_index(boxes[b].hi[a], g->origin[a], h, a, "upper", msg, len, &hi)) {
        *bad_box = b;
        st = CUPID_ERR_MODEL;
        goto cleanup;
      }
      if (hi <= lo) {
        *bad_box = b;
        snprintf(msg, len, "the box holds no node: %c range [%.15g, %.15g] spans %lld cells",
                 axis_name[a], boxes[b].lo[a], boxes[b].hi[a], (long long)(hi - lo));
        st = CUPID_ERR_MODEL;
        goto cleanup;
      }
      range[6 * b + 2 * a] = lo;
      range[6 * b + 2 * a + 1] = hi;
      if (hi > g->n[a]) g->n[a] = hi;
    }
  }
  CUPID_TRY(apply_partition(opts, n_boxes, range, g));
  double cells = (double)g->n[0] * (double)g->n[1] * (double)g->n[2];
  if (cells > (double)PD_MAX_CELLS) {
    st = CUPID_ERROR(CUPID_ERR_MODEL,
                     "the bounding box of the PD regions has %.0f cells (%lld x %lld x %lld), "
                     "more than the limit of %lld: check spacing and regions",
                     cells, (long long)g->n[0], (long long)g->n[1], (long long)g->n[2],
                     (long long)PD_MAX_CELLS);
    goto cleanup;
  }
  const cupid_int ncell = g->n[0] * g->n[1] * g->n[2];
  CUPID_TRY(cupid_malloc((size_t)ncell, sizeof *g->dense, "the PD cell index", &g->dense));
  for (cupid_int c = 0; c < ncell; c++) g->dense[c] = -1;

  /* Mark owners: the first box containing a cell gives its material (boxes in reverse so
   * that earlier boxes overwrite later ones). dense holds the box index for now. With shapes
   * or holes, cell by cell (cell_owner). */
  if (opts->shapes || opts->n_holes > 0) {
#pragma omp parallel for schedule(static) if (ncell > PD_OMP_MIN_NODES)
    for (cupid_int c = 0; c < ncell; c++) {
      const cupid_int i = c % g->n[0], j = (c / g->n[0]) % g->n[1], k = c / (g->n[0] * g->n[1]);
      g->dense[c] = cell_owner(opts, n_boxes, range, g->origin, h, i, j, k);
    }
  }
  for (int b = n_boxes - 1; b >= 0 && !(opts->shapes || opts->n_holes > 0); b--) {
    const cupid_int *r = range + 6 * b;
    if (r[5] <= r[4]) continue; /* outside this slab */
#pragma omp parallel for collapse(2) schedule(static) if ((r[5] - r[4]) * (r[3] - r[2]) * (r[1] - r[0]) > PD_OMP_MIN_NODES)
    for (cupid_int k = r[4]; k < r[5]; k++)
      for (cupid_int j = r[2]; j < r[3]; j++)
        for (cupid_int i = r[0]; i < r[1]; i++) g->dense[i + g->n[0] * (j + g->n[1] * k)] = b;
  }
  cupid_int nn = 0;
  for (cupid_int c = 0; c < ncell; c++)
    if (g->dense[c] >= 0) nn++;
  g->nnodes = nn;
  for (int b = 0; opts->shapes && b < n_boxes; b++) { /* a shape between the cell centres */
    if (opts->shapes[b].kind == CUPID_SHAPE_BOX || opts->parts > 1) continue;
    const cupid_int *r = range + 6 * b;
    int held = 0;
    for (cupid_int k = r[4]; k < r[5] && !held; k++)
      for (cupid_int j = r[2]; j < r[3] && !held; j++)
        for (cupid_int i = r[0]; i < r[1] && !held; i++) {
          const double p[3] = {g->origin[0] + ((double)i + 0.5) * h,
                               g->origin[1] + ((double)j + 0.5) * h,
                               g->origin[2] + ((double)k + 0.5) * h};
          held = cupid_shape_contains(&opts->shapes[b], p);
        }
    if (!held) {
      *bad_box = b;
      snprintf(msg, len, "the %s holds no cell centre of the lattice (spacing %.15g): make it "
               "larger, or the spacing smaller",
               opts->shapes[b].kind == CUPID_SHAPE_CYLINDER ? "cylinder"
               : opts->shapes[b].kind == CUPID_SHAPE_SPHERE ? "sphere" : "geometry's volume", h);
      st = CUPID_ERR_MODEL;
      goto cleanup;
    }
  }
  if (nn == 0 && opts->parts <= 1) {
    st = CUPID_ERROR(CUPID_ERR_MODEL, "the regions hold no node%s", opts->n_holes > 0
                     ? ": the holes remove all of them" : "");
    goto cleanup;
  }
  if (opts->parts <= 1) {
    g->part = (cupid_pd_grid_partition){
        .global_nodes = nn, .owned_last = nn, .parts = 1,
        .own_z = {g->origin[2], g->origin[2] + (double)g->n[2] * g->h}};
  } else {
    /* apply_partition left the global counts; the owned range ends where the owned layers do */
    g->part.owned_last = nn - g->part.owned_last;
  }
  CUPID_TRY(cupid_malloc(3 * (size_t)nn, sizeof *g->coords, "PD node coordinates", &g->coords));
  CUPID_TRY(cupid_malloc((size_t)nn, sizeof *g->material, "PD node materials", &g->material));
  CUPID_TRY(cupid_malloc(3 * (size_t)nn, sizeof *g->ijk, "PD lattice positions", &g->ijk));
  nn = 0;
  for (cupid_int k = 0; k < g->n[2]; k++)
    for (cupid_int j = 0; j < g->n[1]; j++)
      for (cupid_int i = 0; i < g->n[0]; i++) {
        cupid_int c = i + g->n[0] * (j + g->n[1] * k);
        if (g->dense[c] < 0) continue;
        int b = (int)g->dense[c];
        g->material[nn] = materials[b];
        g->ijk[3 * nn] = (int32_t)i;
        g->ijk[3 * nn + 1] = (int32_t)j;
        g->ijk[3 * nn + 2] = (int32_t)k;
        const cupid_int ijk[3] = {i, j, k};
        for (int a = 0; a < 3; a++)
          g->coords[3 * nn + a] =
              (dim == 3 || a == 1) ? g->origin[a] + ((double)ijk[a] + 0.5) * h : 0.0;
        g->dense[c] = nn++;
      }
  if (opts->cut_volumes) CUPID_TRY(pd_grid_cut_volumes(g, opts, n_boxes, boxes));
  *grid = g;
  g = NULL;
cleanup:
  cupid_free(&range);
  cupid_pd_grid_destroy(&g);
  return st;
}

cupid_status cupid_pd_grid_create(const cupid_pd_grid_options *opts, int n_boxes,
                                  const cupid_box *boxes, const int *materials,
                                  cupid_pd_grid *grid) {
  char msg[512];
  int bad = -1;
  cupid_status st = pd_grid_build(opts, n_boxes, boxes, materials, &bad, msg, sizeof msg, grid);
  if (st != CUPID_SUCCESS && bad >= 0) return CUPID_ERROR(st, "PD box %d: %s", bad, msg);
  return st;
}

cupid_int cupid_pd_grid_num_nodes(const cupid_pd_grid grid) { return grid->nnodes; }
void cupid_pd_grid_get_partition(const cupid_pd_grid grid, cupid_pd_grid_partition *part) {
  *part = grid->part;
}
const double *cupid_pd_grid_coords(const cupid_pd_grid grid) { return grid->coords; }
const int *cupid_pd_grid_materials(const cupid_pd_grid grid) { return grid->material; }
cupid_status cupid_pd_grid_map_nodes(const cupid_pd_grid from, const cupid_pd_grid to,
                                     cupid_int *map) {
  CUPID_CHECK(from && to && map, CUPID_ERR_ARGUMENT, "the node map needs two grids and an output");
  CUPID_CHECK(from->dim == to->dim && fabs(from->h - to->h) <= 1e-12 * to->h, CUPID_ERR_ARGUMENT,
              "the node map needs grids of one dimension and spacing (%g, %g)", from->h, to->h);
  cupid_int shift[3];
  for (int a = 0; a < 3; a++) { /* to's lattice index of from's cell 0 */
    const double t = (from->origin[a] - to->origin[a]) / to->h;
    CUPID_CHECK(fabs(t - nearbyint(t)) <= 1e-9, CUPID_ERR_ARGUMENT,
                "the grids' lattices differ along %c: their origins are %g spacings apart",
                axis_name[a], t);
    shift[a] = (cupid_int)nearbyint(t);
  }
#pragma omp parallel for schedule(static) if (from->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < from->nnodes; i++) {
    const int32_t *q = from->ijk + 3 * i;
    map[i] = pd_grid_lookup(to, q[0] + shift[0], q[1] + shift[1], q[2] + shift[2]);
  }
  return CUPID_SUCCESS;
}

double cupid_pd_grid_cell_volume(const cupid_pd_grid grid) { return grid->volume; }
const double *cupid_pd_grid_volume_fractions(const cupid_pd_grid grid) { return grid->vfrac; }
double cupid_pd_grid_node_volume(const cupid_pd_grid grid, cupid_int node) {
  return grid->vfrac ? grid->volume * grid->vfrac[node] : grid->volume;
}
double cupid_pd_grid_unassigned_volume(const cupid_pd_grid grid) { return grid->cut_lost; }
double cupid_pd_grid_spacing(const cupid_pd_grid grid) { return grid->h; }
int cupid_pd_grid_dimension(const cupid_pd_grid grid) { return grid->dim; }

cupid_int cupid_pd_grid_node_at(const cupid_pd_grid grid, cupid_int i, cupid_int j, cupid_int k) {
  return pd_grid_lookup(grid, i, j, k);
}

void cupid_pd_grid_origin(const cupid_pd_grid grid, double origin[3]) {
  for (int a = 0; a < 3; a++) origin[a] = grid->origin[a];
}

void cupid_pd_grid_extent(const cupid_pd_grid grid, cupid_int ncells[3]) {
  for (int a = 0; a < 3; a++) ncells[a] = grid->n[a];
}

void cupid_pd_grid_node_lattice(const cupid_pd_grid grid, cupid_int node, cupid_int ijk[3]) {
  for (int a = 0; a < 3; a++) ijk[a] = grid->ijk[3 * node + a];
}

cupid_status cupid_pd_grid_interior(const cupid_pd_grid grid, double radius, unsigned char *flags) {
  const struct cupid_pd_grid_private *g = grid;
  int32_t *off = NULL;
  CUPID_CHECK(radius >= 0 && isfinite(radius), CUPID_ERR_ARGUMENT, "radius must be >= 0, got %g",
              radius);
  const double rr = radius / g->h * (1.0 + 1e-12);
  const int R = (int)floor(rr);
  const int Rx = g->dim == 3 ? R : 0;
  const size_t side = 2 * (size_t)R + 1, sidex = 2 * (size_t)Rx + 1;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_malloc(3 * sidex * side * sidex, sizeof *off, "stencil offsets", &off));
  int n = 0;
  for (int dk = -Rx; dk <= Rx; dk++)
    for (int dj = -R; dj <= R; dj++)
      for (int di = -Rx; di <= Rx; di++)
        if ((double)(di * di + dj * dj + dk * dk) <= rr * rr) {
          off[3 * n] = di;
          off[3 * n + 1] = dj;
          off[3 * n + 2] = dk;
          n++;
        }
#pragma omp parallel for schedule(static) if (g->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int p = 0; p < g->nnodes; p++) {
    const int32_t *q = g->ijk + 3 * p;
    unsigned char in = 1;
    for (int s = 0; s < n && in; s++)
      if (pd_grid_lookup(g, q[0] + off[3 * s], q[1] + off[3 * s + 1], q[2] + off[3 * s + 2]) < 0)
        in = 0;
    flags[p] = in;
  }
cleanup:
  cupid_free(&off);
  return st;
}
