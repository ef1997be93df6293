/* A closed triangulated surface and whether a point lies inside it (issue 35: PD regions and
 * holes from CAD or mesh files, {geometry: FILE}). The test casts a ray from the point along
 * +x and counts the triangles it crosses (odd: inside). Triangles are found through a bucket
 * grid over their (y, z) projections; a point whose (y, z) falls on a projected edge or vertex
 * is counted once by the fill rule of rasterisers (an edge belongs to the triangle on its left,
 * or above a horizontal one), so that shared edges of a closed surface never count twice.
 * A point on the surface counts as inside, as for the other shapes. Queries only read: the
 * lattice asks from many threads at once. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "io_internal.h"

struct cupid_surface_private {
  double *xyz;         /* 3 per node */
  int64_t *tri;        /* 3 per triangle */
  int64_t n_nodes, n_tri;
  double lo[3], hi[3]; /* the bounding box */
  double tol;          /* on-surface tolerance along x: 1e-12 of the box's size */
  int nb[2];           /* buckets along y, z */
  double blo[2], bsize[2];
  int64_t *start;      /* CSR: the triangles of bucket b are list[start[b] .. start[b+1]) */
  int64_t *list;
};

void cupid_surface_destroy(cupid_surface *surface) {
  if (!surface || !*surface) return;
  cupid_surface s = *surface;
  cupid_free(&s->xyz);
  cupid_free(&s->tri);
  cupid_free(&s->start);
  cupid_free(&s->list);
  cupid_free(surface);
}

void cupid_surface_bounds(const cupid_surface s, double lo[3], double hi[3]) {
  for (int a = 0; a < 3; a++) lo[a] = s->lo[a], hi[a] = s->hi[a];
}

int64_t cupid_surface_num_triangles(const cupid_surface s) { return s->n_tri; }

static void bucket_range(const cupid_surface s, const double *p0, const double *p1,
                         const double *p2, int r[4]) {
  for (int d = 0; d < 2; d++) {
    const int a = d + 1; /* y, z */
    double mn = fmin(p0[a], fmin(p1[a], p2[a])), mx = fmax(p0[a], fmax(p1[a], p2[a]));
    int b0 = (int)floor((mn - s->blo[d]) / s->bsize[d]);
    int b1 = (int)floor((mx - s->blo[d]) / s->bsize[d]);
    r[2 * d] = b0 < 0 ? 0 : b0 >= s->nb[d] ? s->nb[d] - 1 : b0;
    r[2 * d + 1] = b1 < 0 ? 0 : b1 >= s->nb[d] ? s->nb[d] - 1 : b1;
  }
}

/* Every edge of a closed surface is shared by an even number of triangles (two, in a
 * manifold): *open_edges counts the others (edges as sorted node pairs). */
static int cmp_pair(const void *a, const void *b) {
  const int64_t *x = a, *y = b;
  if (x[0] != y[0]) return x[0] < y[0] ? -1 : 1;
  return (x[1] > y[1]) - (x[1] < y[1]);
}

static cupid_status count_open_edges(const cupid_surface s, int64_t *open_edges) {
  int64_t *e = NULL;
  CUPID_CALL(cupid_malloc(6 * (size_t)s->n_tri + 2, sizeof *e, "surface edges", &e));
  for (int64_t t = 0; t < s->n_tri; t++)
    for (int k = 0; k < 3; k++) {
      int64_t a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
      e[6 * t + 2 * k] = a < b ? a : b, e[6 * t + 2 * k + 1] = a < b ? b : a;
    }
  qsort(e, 3 * (size_t)s->n_tri, 2 * sizeof *e, cmp_pair);
  int64_t open = 0;
  for (int64_t k = 0; k < 3 * s->n_tri;) {
    int64_t j = k + 1;
    while (j < 3 * s->n_tri && !cmp_pair(e + 2 * k, e + 2 * j)) j++;
    if ((j - k) % 2) open++;
    k = j;
  }
  cupid_free(&e);
  *open_edges = open;
  return CUPID_SUCCESS;
}

cupid_status cupid_surface_create(const double *xyz, int64_t n_nodes, const int64_t *tri,
                                  int64_t n_tri, cupid_surface *surface, int64_t *open_edges) {
  CUPID_CHECK(n_nodes >= 3 && n_tri >= 1, CUPID_ERR_ARGUMENT, "a surface needs triangles");
  cupid_surface s = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_CALL(cupid_calloc(1, sizeof *s, "surface", &s));
  s->n_nodes = n_nodes, s->n_tri = n_tri;
  CUPID_TRY(cupid_malloc(3 * (size_t)n_nodes, sizeof *s->xyz, "surface nodes", &s->xyz));
  CUPID_TRY(cupid_malloc(3 * (size_t)n_tri, sizeof *s->tri, "surface triangles", &s->tri));
  memcpy(s->xyz, xyz, 3 * (size_t)n_nodes * sizeof *xyz);
  memcpy(s->tri, tri, 3 * (size_t)n_tri * sizeof *tri);
  for (int a = 0; a < 3; a++) s->lo[a] = INFINITY, s->hi[a] = -INFINITY;
  for (int64_t t = 0; t < 3 * n_tri; t++) {
    CUPID_TRY_CHECK(tri[t] >= 0 && tri[t] < n_nodes, CUPID_ERR_ARGUMENT,
                    "surface triangle %lld refers to node %lld of %lld", (long long)(t / 3),
                    (long long)tri[t], (long long)n_nodes);
    for (int a = 0; a < 3; a++) {
      s->lo[a] = fmin(s->lo[a], xyz[3 * tri[t] + a]);
      s->hi[a] = fmax(s->hi[a], xyz[3 * tri[t] + a]);
    }
  }
  double size = 0.0;
  for (int a = 0; a < 3; a++) size = fmax(size, s->hi[a] - s->lo[a]);
  s->tol = 1e-12 * size;
  /* about two triangles a bucket, at most 2048 x 2048 buckets */
  const double per = sqrt((double)n_tri / 2.0);
  for (int d = 0; d < 2; d++) {
    const double span = s->hi[d + 1] - s->lo[d + 1];
    s->nb[d] = per < 1 ? 1 : per > 2048 ? 2048 : (int)per;
    s->blo[d] = s->lo[d + 1];
    s->bsize[d] = span > 0 ? span / s->nb[d] * (1 + 1e-12) : 1.0;
  }
  const int64_t nbk = (int64_t)s->nb[0] * s->nb[1];
  CUPID_TRY(cupid_calloc((size_t)nbk + 1, sizeof *s->start, "surface buckets", &s->start));
  for (int pass = 0; pass < 2; pass++) {
    int64_t *fill = NULL;
    if (pass) {
      for (int64_t b = 0; b < nbk; b++) s->start[b + 1] += s->start[b];
      CUPID_TRY(cupid_malloc((size_t)s->start[nbk] + 1, sizeof *s->list, "surface bucket lists",
                             &s->list));
      CUPID_TRY(cupid_malloc((size_t)nbk + 1, sizeof *fill, "surface bucket fill", &fill));
      memcpy(fill, s->start, (size_t)nbk * sizeof *fill);
    }
    for (int64_t t = 0; t < n_tri; t++) {
      int r[4];
      bucket_range(s, xyz + 3 * tri[3 * t], xyz + 3 * tri[3 * t + 1], xyz + 3 * tri[3 * t + 2], r);
      for (int j = r[2]; j <= r[3]; j++)
        for (int i = r[0]; i <= r[1]; i++) {
          const int64_t b = (int64_t)j * s->nb[0] + i;
          if (pass) s->list[fill[b]++] = t;
          else s->start[b + 1]++;
        }
    }
    cupid_free(&fill);
  }
  if (open_edges) CUPID_TRY(count_open_edges(s, open_edges));
  *surface = s;
  return CUPID_SUCCESS;
cleanup:
  cupid_surface_destroy(&s);
  return st;
}

/* The fill rule: a point on edge (a -> b) of a counter-clockwise triangle (in y, z) belongs to
 * it when the edge is a "left" edge (going down in z) or a "top" edge (horizontal, going left
 * in y); a clockwise triangle's edges are taken reversed. */
static int owns_edge(double ay, double az, double by, double bz) {
  return bz < az || (bz == az && by < ay);
}

/* Is (y, z) inside triangle t's projection (the fill rule on its edges)? */
static int covers(const cupid_surface s, int64_t t, double y, double z, double *x) {
  const double *p[3] = {s->xyz + 3 * s->tri[3 * t], s->xyz + 3 * s->tri[3 * t + 1],
                        s->xyz + 3 * s->tri[3 * t + 2]};
  const double area = (p[1][1] - p[0][1]) * (p[2][2] - p[0][2]) - (p[2][1] - p[0][1]) * (p[1][2] - p[0][2]);
  if (area == 0.0) return 0; /* edge-on to the ray: no crossing */
  const int sgn = area > 0 ? 1 : -1;
  double w[3];
  for (int k = 0; k < 3; k++) {
    const double *a = p[(k + 1) % 3], *b = p[(k + 2) % 3];
    /* the edge opposite vertex k, oriented counter-clockwise */
    const double ay = sgn > 0 ? a[1] : b[1], az = sgn > 0 ? a[2] : b[2];
    const double by = sgn > 0 ? b[1] : a[1], bz = sgn > 0 ? b[2] : a[2];
    const double e = (by - ay) * (z - az) - (bz - az) * (y - ay); /* > 0: left of the edge */
    if (e < 0.0 || (e == 0.0 && !owns_edge(ay, az, by, bz))) return 0;
    w[k] = e;
  }
  const double sum = w[0] + w[1] + w[2];
  *x = (w[0] * p[0][0] + w[1] * p[1][0] + w[2] * p[2][0]) / sum;
  return 1;
}

/* The bucket of (y, z) (clamped to the grid). */
static int64_t bucket_of(const cupid_surface s, double y, double z) {
  int i = (int)floor((y - s->blo[0]) / s->bsize[0]), j = (int)floor((z - s->blo[1]) / s->bsize[1]);
  i = i < 0 ? 0 : i >= s->nb[0] ? s->nb[0] - 1 : i;
  j = j < 0 ? 0 : j >= s->nb[1] ? s->nb[1] - 1 : j;
  return (int64_t)j * s->nb[0] + i;
}

int cupid_surface_contains(const cupid_surface s, const double p[3]) {
  for (int a = 0; a < 3; a++)
    if (p[a] < s->lo[a] - s->tol || p[a] > s->hi[a] + s->tol) return 0;
  const int64_t b = bucket_of(s, p[1], p[2]);
  int crossings = 0;
  for (int64_t k = s->start[b]; k < s->start[b + 1]; k++) {
    double x;
    if (!covers(s, s->list[k], p[1], p[2], &x)) continue;
    if (fabs(x - p[0]) <= s->tol) return 1; /* on the surface */
    if (x > p[0]) crossings++;
  }
  return crossings & 1;
}

static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

int cupid_surface_chords(const cupid_surface s, double y, double z, double *x, int cap) {
  if (y < s->lo[1] || y > s->hi[1] || z < s->lo[2] || z > s->hi[2]) return 0;
  const int64_t b = bucket_of(s, y, z);
  int n = 0;
  for (int64_t k = s->start[b]; k < s->start[b + 1]; k++) {
    double xc;
    if (!covers(s, s->list[k], y, z, &xc)) continue;
    if (n == 2 * cap) return -1;
    x[n++] = xc;
  }
  /* a closed surface is crossed an even number of times (the fill rule counts a shared edge
   * once); an odd count is a ray through a gap the closedness check let pass: no chord */
  if (n & 1) return 0;
  qsort(x, (size_t)n, sizeof *x, cmp_double);
  return n / 2;
}

/* 1 if triangle (a, b, c) meets the open box centred at m with half sides e: no separating
 * axis among the box's three, the triangle's normal and the nine edge cross products
 * (Akenine-Moeller), with touching (a facet in the box's face plane) counted as apart. */
static int triangle_meets_box(const double *a, const double *b, const double *c, const double m[3],
                              const double e[3]) {
  double v[3][3], f[3][3];
  for (int k = 0; k < 3; k++) v[0][k] = a[k] - m[k], v[1][k] = b[k] - m[k], v[2][k] = c[k] - m[k];
  for (int k = 0; k < 3; k++)
    f[0][k] = v[1][k] - v[0][k], f[1][k] = v[2][k] - v[1][k], f[2][k] = v[0][k] - v[2][k];
  double axes[13][3];
  int n = 0;
  for (int k = 0; k < 3; k++) { /* the box's axes */
    axes[n][0] = axes[n][1] = axes[n][2] = 0.0;
    axes[n++][k] = 1.0;
  }
  axes[n][0] = f[0][1] * f[1][2] - f[0][2] * f[1][1]; /* the triangle's normal */
  axes[n][1] = f[0][2] * f[1][0] - f[0][0] * f[1][2];
  axes[n][2] = f[0][0] * f[1][1] - f[0][1] * f[1][0];
  n++;
  for (int i = 0; i < 3; i++) /* box axis i x edge j */
    for (int j = 0; j < 3; j++) {
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
      axes[n][i] = 0.0, axes[n][i1] = -f[j][i2], axes[n][i2] = f[j][i1];
      n++;
    }
  for (int q = 0; q < n; q++) {
    const double *u = axes[q];
    const double r = e[0] * fabs(u[0]) + e[1] * fabs(u[1]) + e[2] * fabs(u[2]);
    if (r == 0.0) continue; /* a degenerate axis (parallel edge and box axis) */
    double lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < 3; k++) {
      const double p = v[k][0] * u[0] + v[k][1] * u[1] + v[k][2] * u[2];
      lo = fmin(lo, p), hi = fmax(hi, p);
    }
    if (lo >= r * (1 - 1e-12) || hi <= -r * (1 - 1e-12)) return 0; /* apart, or only touching */
  }
  return 1;
}

void cupid_surface_cut_cells(const cupid_surface s, const double origin[3], double h,
                             const int64_t c0[3], const int64_t c1[3],
                             void (*mark)(void *ctx, int64_t i, int64_t j, int64_t k), void *ctx) {
#pragma omp parallel for schedule(dynamic, 64) if (s->n_tri > 256)
  for (int64_t t = 0; t < s->n_tri; t++) {
    const double *p[3] = {s->xyz + 3 * s->tri[3 * t], s->xyz + 3 * s->tri[3 * t + 1],
                          s->xyz + 3 * s->tri[3 * t + 2]};
    int64_t lo[3], hi[3];
    int empty = 0;
    for (int a = 0; a < 3; a++) { /* the cells the triangle's box reaches into */
      const double mn = fmin(p[0][a], fmin(p[1][a], p[2][a])), mx = fmax(p[0][a], fmax(p[1][a], p[2][a]));
      lo[a] = (int64_t)floor((mn - origin[a]) / h), hi[a] = (int64_t)floor((mx - origin[a]) / h) + 1;
      lo[a] = lo[a] < c0[a] ? c0[a] : lo[a], hi[a] = hi[a] > c1[a] ? c1[a] : hi[a];
      empty |= hi[a] <= lo[a];
    }
    if (empty) continue;
    for (int64_t k = lo[2]; k < hi[2]; k++)
      for (int64_t j = lo[1]; j < hi[1]; j++)
        for (int64_t i = lo[0]; i < hi[0]; i++) {
          const double m[3] = {origin[0] + ((double)i + 0.5) * h, origin[1] + ((double)j + 0.5) * h,
                               origin[2] + ((double)k + 0.5) * h};
          const double e[3] = {0.5 * h, 0.5 * h, 0.5 * h};
          if (triangle_meets_box(p[0], p[1], p[2], m, e)) mark(ctx, i, j, k);
        }
  }
}

