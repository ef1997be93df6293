/* Cut-cell volumes of a shaped PD body (issue 35, `partial_volume: exact`): each node carries
 * the volume of the body nearest it instead of the whole cell.
 *
 * The body is the union of the regions (boxes, cylinders, spheres, geometry files) less the
 * holes; a cell is a node when its centre lies in the body (grid.c). Where the surface cuts a
 * cell, the body's volume in it is integrated along x: on CUT_LINES x CUT_LINES lines through
 * the cell (midpoints in y and z), the exact length of the line inside the body (the shapes'
 * chords, cupid_shape_chords: unions of the regions' chords less the holes'), so the error is
 * the midpoint rule's in y and z only: second order where the lengths vary smoothly, and where
 * a surface parallel to x makes them jump (a cylinder along x, a plane normal to y or z), the
 * jump is placed by bisection (cut_integrate); over z the same on the sections' areas.
 *
 * A node keeps the body's volume in its cell; the body's volume in a cell whose centre lies
 * outside (no node) goes to the node cells around it (its 26 neighbours, weighted by
 * 1/|offset|^2), so that the nodes' volumes sum to the body's: summing only the node cells'
 * parts would lose the slivers of the cells just outside, 5% of a sphere of radius 5 h.
 *
 * Which cells are cut: among the cells that a shape's or a hole's bounding box touches, those
 * that a solid's surface passes within half a cell diagonal of (cupid_shape_cuts_cell), or
 * that a geometry's triangle passes through (cupid_surface_cut_cells; a facet in a cell's
 * face, as a STEP plate's faces on the lattice planes, cuts nothing). A test of the cell's corners alone would miss a sphere
 * that bulges into a cell through a face. The cells just outside a slab's window count too
 * (from the geometry, not from the grid), so that a slab's nodes get the volumes the whole
 * grid gives them. */
#include <math.h>
#include <string.h>

#include "pd/pd_internal.h"

#define CUT_LINES 8    /* integration lines per cell side */
#define CUT_JUMP 0.1   /* a step: neighbouring samples differ by this much of h (h^2) */
#define CUT_BISECT 12  /* halvings that place a step */
#define CUT_CHORDS 64  /* chords per shape and line */
#define CUT_MIN 1e-3   /* a node keeps at least this fraction of its cell (its row of K must
                          not vanish: a centre on the surface may have almost no volume) */

typedef struct {
  const cupid_pd_grid_options *opts;
  int n_boxes;
  const cupid_box *boxes;
} cut_body;

static int is_shape(const cut_body *B, int b) {
  return B->opts->shapes && B->opts->shapes[b].kind != CUPID_SHAPE_BOX;
}

/* Shape s of the body's list: the regions' (NULL for a box region) then the holes. */
static const cupid_shape *shape_at(const cut_body *B, int s) {
  if (s >= B->n_boxes) return &B->opts->holes[s - B->n_boxes];
  return is_shape(B, s) ? &B->opts->shapes[s] : NULL;
}

/* 1 if p lies in the body (a region's shape, or its box, and no hole), as grid.c's cells. */
static int body_contains(const cut_body *B, const double p[3]) {
  int in = 0;
  for (int b = 0; b < B->n_boxes && !in; b++)
    in = is_shape(B, b) ? cupid_shape_contains(&B->opts->shapes[b], p)
                        : cupid_box_contains(&B->boxes[b], p, 0.0);
  for (int q = 0; q < B->opts->n_holes && in; q++) in = !cupid_shape_contains(&B->opts->holes[q], p);
  return in;
}

/* Sort intervals (pairs) by their start, clip them to [x0, x1] and merge overlaps: n disjoint
 * sorted intervals out. */
static int merge(double *iv, int n, double x0, double x1) {
  for (int a = 1; a < n; a++) /* insertion sort: a few intervals */
    for (int b = a; b > 0 && iv[2 * b] < iv[2 * b - 2]; b--) {
      const double s = iv[2 * b], e = iv[2 * b + 1];
      iv[2 * b] = iv[2 * b - 2], iv[2 * b + 1] = iv[2 * b - 1];
      iv[2 * b - 2] = s, iv[2 * b - 1] = e;
    }
  int m = 0;
  for (int k = 0; k < n; k++) {
    const double s = fmax(iv[2 * k], x0), e = fmin(iv[2 * k + 1], x1);
    if (!(e > s)) continue;
    if (m > 0 && s <= iv[2 * m - 1]) iv[2 * m - 1] = fmax(iv[2 * m - 1], e);
    else iv[2 * m] = s, iv[2 * m + 1] = e, m++;
  }
  return m;
}

/* The chords of a list of shapes on the line (y, z), appended to iv (cap intervals in all);
 * -1 when they do not fit. */
static int gather(const cupid_shape *shapes, int n, double y, double z, double *iv, int have, int cap) {
  for (int q = 0; q < n; q++) {
    const int c = cupid_shape_chords(&shapes[q], y, z, iv + 2 * have, cap - have);
    if (c < 0) return -1;
    have += c;
  }
  return have;
}

/* Length of the line (y, z) inside the body within [x0, x1]; -1 if a shape crossed it more
 * often than the buffers hold. */
static double body_length(const cut_body *B, double y, double z, double x0, double x1,
                          double *R, double *H, int cap) {
  int nr = 0;
  for (int b = 0; b < B->n_boxes; b++) {
    if (is_shape(B, b)) {
      nr = gather(&B->opts->shapes[b], 1, y, z, R, nr, cap);
      if (nr < 0) return -1.0;
      continue;
    }
    const cupid_box *bx = &B->boxes[b];
    if (y < bx->lo[1] || y > bx->hi[1] || z < bx->lo[2] || z > bx->hi[2]) continue;
    if (nr == cap) return -1.0;
    R[2 * nr] = bx->lo[0], R[2 * nr + 1] = bx->hi[0], nr++;
  }
  nr = merge(R, nr, x0, x1);
  int nh = gather(B->opts->holes, B->opts->n_holes, y, z, H, 0, cap);
  if (nh < 0) return -1.0;
  nh = merge(H, nh, x0, x1);
  double len = 0.0;
  for (int a = 0, b = 0; a < nr; a++) { /* |R| - |R and H|, both disjoint and sorted */
    len += R[2 * a + 1] - R[2 * a];
    while (b < nh && H[2 * b + 1] <= R[2 * a]) b++;
    for (int c = b; c < nh && H[2 * c] < R[2 * a + 1]; c++)
      len -= fmin(H[2 * c + 1], R[2 * a + 1]) - fmax(H[2 * c], R[2 * a]);
  }
  return len;
}

/* A function of one variable integrated by cut_integrate: ctx's lengths along x. */
typedef struct {
  const cut_body *B;
  double x[2], y, z; /* the cell's x range; the line's y (set by cut_row) and z */
  double *R, *H;
  int cap, crowded;
} cut_line;

typedef double (*cut_fn)(cut_line *L, double t);

/* Midpoint rule of n intervals over [a, b], with f also next to a and b: where two neighbouring
 * samples differ by more than thr, bisection (CUT_BISECT halvings) looks for a step between
 * them, and where f still jumps there (not a steep but continuous stretch, as a chord near
 * a tangent), the rule is corrected by (f_left - f_right)(step - the rule's own boundary
 * between them). So a surface parallel to the lines (lengths that jump) costs no
 * more than a first-order error of 2^-CUT_BISECT of a sample's interval. */
static double cut_integrate(cut_fn f, cut_line *L, double a, double b, int n, double thr) {
  double t[CUT_LINES + 2], v[CUT_LINES + 2], sum = 0.0;
  const double e = (b - a) / n;
  t[0] = a + 1e-9 * e, t[n + 1] = b - 1e-9 * e; /* just inside: a face on the cell's own edge
                                                    is no step within it */
  for (int k = 1; k <= n; k++) t[k] = a + (k - 0.5) * e;
  for (int k = 0; k <= n + 1; k++) v[k] = f(L, t[k]);
  for (int k = 1; k <= n; k++) sum += e * v[k];
  for (int k = 0; k <= n; k++) {
    if (!(fabs(v[k] - v[k + 1]) > thr)) continue;
    double lo = t[k], hi = t[k + 1], flo = v[k], fhi = v[k + 1];
    for (int q = 0; q < CUT_BISECT; q++) {
      const double m = 0.5 * (lo + hi), fm = f(L, m);
      if (fabs(fm - v[k]) <= fabs(fm - v[k + 1])) lo = m, flo = fm;
      else hi = m, fhi = fm;
    }
    if (!(fabs(fhi - flo) > 0.5 * thr)) continue; /* steep but continuous: no step */
    const double step = 0.5 * (lo + hi);
    /* the rule's boundary: the midpoint between two interior samples; an end sample's
     * interval is empty (the rule gives [a, t_1] to v_1) */
    const double mid = k == 0 ? a : k == n ? b : 0.5 * (t[k] + t[k + 1]);
    sum += (v[k] - v[k + 1]) * (step - mid);
  }
  return sum;
}

/* The length of the line (y, z) inside the body within the cell's x range. */
static double cut_length(cut_line *L, double y) {
  const double l = body_length(L->B, y, L->z, L->x[0], L->x[1], L->R, L->H, L->cap);
  if (l < 0) L->crowded = 1;
  return l < 0 ? 0.0 : l;
}

/* The area of the body's section z within the cell: its lines' lengths over y. */
static double cut_row(cut_line *L, double z) {
  L->z = z;
  const double h = L->x[1] - L->x[0];
  return cut_integrate(cut_length, L, L->y, L->y + h, CUT_LINES, CUT_JUMP * h);
}

/* The body's volume in cell lo .. lo + h (its fraction of h^3), or -1 as body_length. */
static double cell_fraction(const cut_body *B, const double lo[3], double h, double *R, double *H,
                            int cap) {
  cut_line L = {.B = B, .x = {lo[0], lo[0] + h}, .y = lo[1], .R = R, .H = H, .cap = cap};
  const double v = cut_integrate(cut_row, &L, lo[2], lo[2] + h, CUT_LINES, CUT_JUMP * h * h);
  return L.crowded ? -1.0 : v / (h * h * h);
}

static int solid_cuts(const cupid_shape *s, const double lo[3], double h) {
  return s->kind != CUPID_SHAPE_GEOMETRY && cupid_shape_cuts_cell(s, lo, h);
}

/* 1 if a region's or a hole's solid (not a geometry: flag_geometry) may cut the cell at lo
 * (cupid_shape_cuts_cell: its surface within the cell's half diagonal of its centre). Box
 * regions lie on the lattice and cut no cell. */
static int cell_is_cut(const cut_body *B, const double lo[3], double h) {
  for (int b = 0; b < B->n_boxes; b++)
    if (is_shape(B, b) && solid_cuts(&B->opts->shapes[b], lo, h)) return 1;
  for (int q = 0; q < B->opts->n_holes; q++)
    if (solid_cuts(&B->opts->holes[q], lo, h)) return 1;
  return 0;
}

/* The cells that a geometry's triangles pass through, flagged in a byte per cell of the
 * tested range (a solid's are tested cell by cell: cheap; a geometry's cell by cell would
 * ask its triangles at every cell of its box). */
typedef struct {
  unsigned char *flag;
  cupid_int lo[3], n[3];
} cut_flags;

static size_t flag_index(const cut_flags *F, int64_t i, int64_t j, int64_t k) {
  return (size_t)(i - F->lo[0]) +
         (size_t)F->n[0] * ((size_t)(j - F->lo[1]) + (size_t)F->n[1] * (size_t)(k - F->lo[2]));
}

static void flag_cell(void *ctx, int64_t i, int64_t j, int64_t k) {
  cut_flags *F = ctx;
  const size_t c = flag_index(F, i, j, k);
#pragma omp atomic write
  F->flag[c] = 1;
}

static cupid_status flag_geometry(const cut_body *B, const struct cupid_pd_grid_private *g,
                                  cut_flags *F) {
  const size_t total = (size_t)F->n[0] * (size_t)F->n[1] * (size_t)F->n[2];
  int any = 0;
  for (int s = 0; s < B->n_boxes + B->opts->n_holes; s++) {
    const cupid_shape *sh = shape_at(B, s);
    if (!sh || sh->kind != CUPID_SHAPE_GEOMETRY) continue;
    if (!any++) CUPID_CALL(cupid_calloc(total + 1, 1, "cut-cell flags", &F->flag));
    const int64_t c0[3] = {F->lo[0], F->lo[1], F->lo[2]};
    const int64_t c1[3] = {F->lo[0] + F->n[0], F->lo[1] + F->n[1], F->lo[2] + F->n[2]};
    cupid_surface_cut_cells(sh->surface, g->origin, g->h, c0, c1, flag_cell, F);
  }
  return CUPID_SUCCESS;
}

/* The cell range [c0, c1) per axis that a shape's bounding box (grown by a cell) touches;
 * the whole extended range [-1, n] where the box is unbounded. */
static void shape_cells(const struct cupid_pd_grid_private *g, const cupid_box *box,
                        cupid_int c0[3], cupid_int c1[3]) {
  for (int a = 0; a < 3; a++) {
    c0[a] = -1, c1[a] = g->n[a] + 1;
    if (!box->has[a]) continue;
    const double lo = floor((box->lo[a] - g->origin[a]) / g->h) - 1;
    const double hi = ceil((box->hi[a] - g->origin[a]) / g->h) + 1;
    if (lo > (double)c0[a]) c0[a] = lo > (double)c1[a] ? c1[a] : (cupid_int)lo;
    if (hi < (double)c1[a]) c1[a] = hi < (double)c0[a] ? c0[a] : (cupid_int)hi;
  }
}

/* A cut cell whose centre lies outside: its body volume, to share among the nodes around. */
typedef struct {
  cupid_int ijk[3];
  double frac;
} cut_spill;

typedef struct {
  cut_spill *v;
  cupid_int n, cap;
} spill_list;

static cupid_status spill_push(spill_list *L, const cupid_int ijk[3], double frac) {
  if (L->n == L->cap) {
    const cupid_int cap = L->cap ? 2 * L->cap : 64;
    CUPID_CALL(cupid_realloc((size_t)cap, sizeof *L->v, "cut cells", &L->v));
    L->cap = cap;
  }
  L->v[L->n].frac = frac;
  for (int a = 0; a < 3; a++) L->v[L->n].ijk[a] = ijk[a];
  L->n++;
  return CUPID_SUCCESS;
}

/* Share a spilled cell's volume among the node cells of its 26 neighbours (1/|o|^2), those of
 * this grid taking theirs; *lost += the volume of a cell with no node around. */
static void spill_share(const cut_body *B, struct cupid_pd_grid_private *g, const cut_spill *c,
                        double *phi, double *lost) {
  double w[27], sum = 0.0;
  for (int q = 0; q < 27; q++) {
    const int o[3] = {q % 3 - 1, (q / 3) % 3 - 1, q / 9 - 1};
    w[q] = 0.0;
    if (q == 13) continue;
    double p[3];
    for (int a = 0; a < 3; a++) p[a] = g->origin[a] + ((double)(c->ijk[a] + o[a]) + 0.5) * g->h;
    if (!body_contains(B, p)) continue;
    w[q] = 1.0 / (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
    sum += w[q];
  }
  if (!(sum > 0)) {
    *lost += c->frac;
    return;
  }
  for (int q = 0; q < 27; q++) {
    if (w[q] == 0.0) continue;
    const cupid_int node = pd_grid_lookup(g, c->ijk[0] + q % 3 - 1, c->ijk[1] + (q / 3) % 3 - 1,
                                          c->ijk[2] + q / 9 - 1);
    if (node >= 0) phi[node] += c->frac * w[q] / sum;
  }
}

cupid_status pd_grid_cut_volumes(struct cupid_pd_grid_private *g, const cupid_pd_grid_options *opts,
                                 int n_boxes, const cupid_box *boxes) {
  cupid_status st = CUPID_SUCCESS;
  const cut_body B = {opts, n_boxes, boxes};
  double *phi = NULL;
  spill_list *lists = NULL;
  if (g->dim != 3 || !(opts->shapes || opts->n_holes > 0)) return CUPID_SUCCESS;
  /* The cells to test: those the non-box regions' and the holes' boxes touch. */
  cupid_int lo[3] = {g->n[0] + 1, g->n[1] + 1, g->n[2] + 1}, hi[3] = {-1, -1, -1};
  for (int s = 0; s < n_boxes + opts->n_holes; s++) {
    const cupid_shape *sh = shape_at(&B, s);
    if (!sh) continue;
    cupid_int c0[3], c1[3];
    shape_cells(g, &sh->box, c0, c1);
    for (int a = 0; a < 3; a++) {
      lo[a] = c0[a] < lo[a] ? c0[a] : lo[a];
      hi[a] = c1[a] > hi[a] ? c1[a] : hi[a];
    }
  }
  if (hi[0] <= lo[0] || hi[1] <= lo[1] || hi[2] <= lo[2]) return CUPID_SUCCESS;
  const cupid_int nk = hi[2] - lo[2];
  cut_flags F = {.lo = {lo[0], lo[1], lo[2]}, .n = {hi[0] - lo[0], hi[1] - lo[1], nk}};
  CUPID_TRY(flag_geometry(&B, g, &F));
  CUPID_TRY(cupid_malloc((size_t)g->nnodes + 1, sizeof *phi, "PD node volumes", &phi));
  for (cupid_int i = 0; i < g->nnodes; i++) phi[i] = 1.0;
  CUPID_TRY(cupid_calloc((size_t)nk, sizeof *lists, "cut cells", &lists));
  int failed = 0, crowded = 0;
#pragma omp parallel for schedule(dynamic, 1)
  for (cupid_int kk = 0; kk < nk; kk++) {
    double R[2 * CUT_CHORDS * 4], H[2 * CUT_CHORDS * 4];
    const cupid_int k = lo[2] + kk;
    for (cupid_int j = lo[1]; j < hi[1]; j++)
      for (cupid_int i = lo[0]; i < hi[0]; i++) {
        const cupid_int ijk[3] = {i, j, k};
        double c[3];
        for (int a = 0; a < 3; a++) c[a] = g->origin[a] + (double)ijk[a] * g->h;
        if (!(F.flag && F.flag[flag_index(&F, i, j, k)]) && !cell_is_cut(&B, c, g->h)) continue;
        const double mid[3] = {c[0] + 0.5 * g->h, c[1] + 0.5 * g->h, c[2] + 0.5 * g->h};
        const int centre = body_contains(&B, mid);
        double f = cell_fraction(&B, c, g->h, R, H, CUT_CHORDS * 4);
        if (f < 0) {
#pragma omp atomic write
          crowded = 1;
          continue;
        }
        if (fabs(f - 1.0) < 1e-12) f = 1.0;
        if (!centre) {
          if (f > 1e-12 && spill_push(&lists[kk], ijk, f) != CUPID_SUCCESS) {
#pragma omp atomic write
            failed = 1;
          }
          continue;
        }
        const cupid_int node = pd_grid_lookup(g, i, j, k);
        if (node >= 0) phi[node] = f;
      }
  }
  if (failed) CUPID_TRY(CUPID_ERROR(CUPID_ERR_MEMORY, "out of memory for the cut cells"));
  if (crowded)
    CUPID_TRY(CUPID_ERROR(CUPID_ERR_MODEL,
                          "the cut-cell volumes: a line along x crosses a shape's surface more "
                          "than %d times within one cell (spacing %g): use a smaller spacing",
                          2 * CUT_CHORDS, g->h));
  double lost = 0.0;
  for (cupid_int kk = 0; kk < nk; kk++) /* in layer order: the same sums on every run */
    for (cupid_int q = 0; q < lists[kk].n; q++) spill_share(&B, g, &lists[kk].v[q], phi, &lost);
  int uniform = 1;
  for (cupid_int i = 0; i < g->nnodes; i++) {
    if (phi[i] < CUT_MIN) phi[i] = CUT_MIN;
    uniform &= phi[i] == 1.0;
  }
  g->cut_lost = lost * g->volume;
  if (!uniform) g->vfrac = phi, phi = NULL;
cleanup:
  cupid_free(&F.flag);
  if (lists)
    for (cupid_int kk = 0; kk < nk; kk++) cupid_free(&lists[kk].v);
  cupid_free(&lists);
  cupid_free(&phi);
  return st;
}
