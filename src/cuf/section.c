/* The cross-section mesh of a CUF beam: components (rectangles split by breakpoints) and
 * explicit elements become one isoparametric quadrilateral mesh with merged coincident nodes
 * (the component-wise approach, cuf.md section 3.2). For LE its nodes carry the expansion
 * functions; for TE its cells are only the integration domain (per material). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cuf/cuf_internal.h"

typedef struct cupid_cuf_beam_private beam_t;

/* ---------------------------------------------------------------- node merging */

static _Thread_local const double *sort_xz; /* qsort has no context argument */
static int cmp_x(const void *pa, const void *pb) {
  cupid_int a = *(const cupid_int *)pa, b = *(const cupid_int *)pb;
  double xa = sort_xz[2 * a], xb = sort_xz[2 * b];
  if (xa != xb) return xa < xb ? -1 : 1;
  double za = sort_xz[2 * a + 1], zb = sort_xz[2 * b + 1];
  if (za != zb) return za < zb ? -1 : 1;
  return a < b ? -1 : a > b;
}

/* rep[k] = representative candidate of candidate k (coincident within tol). */
static cupid_status merge_points(cupid_int n, const double *xz, double tol, cupid_int *rep) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int *order = NULL, *uniq = NULL, nu = 0;
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *order, "section node order", &order));
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *uniq, "section unique nodes", &uniq));
  for (cupid_int k = 0; k < n; k++) order[k] = k;
  sort_xz = xz;
  qsort(order, (size_t)n, sizeof *order, cmp_x);
  sort_xz = NULL;
  for (cupid_int q = 0; q < n; q++) {
    cupid_int k = order[q], found = -1;
    /* unique points were created in increasing x: scan back while within tol in x */
    for (cupid_int u = nu - 1; u >= 0; u--) {
      cupid_int c = uniq[u];
      if (xz[2 * c] < xz[2 * k] - tol) break;
      if (fabs(xz[2 * c + 1] - xz[2 * k + 1]) <= tol) {
        found = c;
        break;
      }
    }
    if (found < 0) {
      uniq[nu++] = k;
      found = k;
    }
    rep[k] = found;
  }
cleanup:
  cupid_free(&order);
  cupid_free(&uniq);
  return st;
}

/* ---------------------------------------------------------------- geometry */

double cuf_section_map(const beam_t *b, cupid_int e, double r, double s, double *x, double *z,
                       double inv[4]) {
  const cuf_quad *q = &b->quad;
  double F[16], Fr[16], Fs[16];
  cuf_quad_shape(q, r, s, F, Fr, Fs);
  double X = 0, Z = 0, xr = 0, xs = 0, zr = 0, zs = 0;
  const cupid_int *c = b->sconn + e * q->npe;
  for (int k = 0; k < q->npe; k++) {
    const double *p = b->sxz + 2 * c[k];
    X += F[k] * p[0];
    Z += F[k] * p[1];
    xr += Fr[k] * p[0];
    xs += Fs[k] * p[0];
    zr += Fr[k] * p[1];
    zs += Fs[k] * p[1];
  }
  double det = xr * zs - xs * zr;
  if (x) *x = X;
  if (z) *z = Z;
  if (inv) {
    /* [r_x s_x; r_z s_z] = inverse of [x_r x_s; z_r z_s] */
    inv[0] = zs / det;  /* dr/dx */
    inv[1] = -zr / det; /* ds/dx */
    inv[2] = -xs / det; /* dr/dz */
    inv[3] = xr / det;  /* ds/dz */
  }
  return det;
}

int cuf_section_functions(const beam_t *b, cupid_int e, double r, double s, double *F,
                          double *Fx, double *Fz, double *x, double *z, double *detJ) {
  double inv[4], X, Z;
  double det = cuf_section_map(b, e, r, s, &X, &Z, inv);
  if (x) *x = X;
  if (z) *z = Z;
  if (detJ) *detJ = det;
  if (b->expansion == CUPID_EXPANSION_LE) {
    double Fr[16], Fs[16];
    cuf_quad_shape(&b->quad, r, s, F, Fr, Fs);
    for (int k = 0; k < b->quad.npe; k++) {
      if (Fx) Fx[k] = Fr[k] * inv[0] + Fs[k] * inv[1];
      if (Fz) Fz[k] = Fr[k] * inv[2] + Fs[k] * inv[3];
    }
    return b->quad.npe;
  }
  /* TE: monomials of the centred, scaled coordinates; powers built once per point */
  double xh = (X - b->xc) / b->h, zh = (Z - b->zc) / b->h;
  double px[CUF_MAX_GAUSS + 1], pz[CUF_MAX_GAUSS + 1];
  px[0] = pz[0] = 1.0;
  for (int k = 1; k <= b->te_order; k++) px[k] = px[k - 1] * xh, pz[k] = pz[k - 1] * zh;
  for (int t = 0; t < b->M; t++) {
    int a = b->te_a[t], c = b->te_b[t];
    F[t] = px[a] * pz[c];
    if (Fx) Fx[t] = a ? a * px[a - 1] * pz[c] / b->h : 0.0;
    if (Fz) Fz[t] = c ? c * px[a] * pz[c - 1] / b->h : 0.0;
  }
  return b->M;
}

int cuf_section_invert(const beam_t *b, cupid_int e, double x, double z, double *r, double *s) {
  const double *bx = b->sbox + 4 * e;
  double tol = b->tol_xz;
  if (x < bx[0] - tol || x > bx[1] + tol || z < bx[2] - tol || z > bx[3] + tol) return 0;
  double R = 0, S = 0;
  if (b->srect[e]) {
    R = (2 * x - bx[0] - bx[1]) / (bx[1] - bx[0]);
    S = (2 * z - bx[2] - bx[3]) / (bx[3] - bx[2]);
  } else {
    for (int it = 0; it < 30; it++) { /* Newton on the isoparametric map */
      double X, Z, inv[4];
      cuf_section_map(b, e, R, S, &X, &Z, inv);
      double dx = x - X, dz = z - Z;
      double dR = inv[0] * dx + inv[2] * dz, dS = inv[1] * dx + inv[3] * dz;
      R += dR;
      S += dS;
      if (fabs(R) > 3 || fabs(S) > 3) return 0;
      if (fabs(dR) + fabs(dS) < 1e-14) break;
    }
  }
  double ptol = 1e-9;
  if (fabs(R) > 1 + ptol || fabs(S) > 1 + ptol) return 0;
  *r = fmin(1.0, fmax(-1.0, R));
  *s = fmin(1.0, fmax(-1.0, S));
  return 1;
}

void cuf_section_integrals(const beam_t *b, cupid_int e, int ng, double *E) {
  cuf_section_integrals_weighted(b, e, ng, NULL, NULL, E);
}

void cuf_section_integrals_weighted(const beam_t *b, cupid_int e, int ng,
                                    cupid_cuf_section_weight_fn fn, void *ctx, double *E) {
  int m = cuf_local_m(b);
  double gx[CUF_MAX_GAUSS], gw[CUF_MAX_GAUSS];
  cuf_gauss(ng, gx, gw);
  memset(E, 0, sizeof *E * 9 * (size_t)m * (size_t)m);
  double F[3][256]; /* G_0 F = F_x, G_1 F = F, G_2 F = F_z; m <= 256 (TE up to N = 21) */
  for (int gi = 0; gi < ng; gi++)
    for (int gj = 0; gj < ng; gj++) {
      double det, x, z;
      cuf_section_functions(b, e, gx[gi], gx[gj], F[1], F[0], F[2], &x, &z, &det);
      double w = gw[gi] * gw[gj] * det * (fn ? fn(ctx, x, z) : 1.0);
      if (w == 0.0) continue;
      for (int d = 0; d < 3; d++)
        for (int dd = 0; dd < 3; dd++) {
          double *Ed = E + (size_t)(3 * d + dd) * m * m;
          const double *Fs = F[d], *Ft = F[dd];
          for (int s = 0; s < m; s++) {
            double ws = w * Fs[s];
            if (ws == 0.0) continue;
            double *row = Ed + (size_t)s * m;
            for (int t = 0; t < m; t++) row[t] += ws * Ft[t];
          }
        }
    }
}

/* ---------------------------------------------------------------- building */

static cupid_status sec_error(const cupid_model_t *model, const cupid_mark *mark, const char *what) {
  return cupid_model_error(model, mark, "%s", what);
}

/* Candidate nodes and elements from explicit lists and components. */
typedef struct {
  cupid_int nc, ne;
  double *xz;      /* candidates */
  cupid_int *conn; /* per element, candidate indices */
  int *mat;
} candidates;

static cupid_status collect(const cupid_beam *def, const cupid_model_t *model, int n_mat,
                            const cuf_quad *q, candidates *c) {
  cupid_status st = CUPID_SUCCESS;
  int npe = q->npe;
  cupid_int nc = def->n_section_nodes, ne = def->n_section_elements;
  for (int k = 0; k < def->n_components; k++) {
    const cupid_section_component *cp = &def->components[k];
    if (cp->nx < 2 || cp->nz < 2)
      return cupid_model_error(model, &cp->mark, "a component needs at least 2 x and 2 z breakpoints");
    cupid_int cells = (cupid_int)(cp->nx - 1) * (cp->nz - 1);
    ne += cells;
    nc += cells * npe;
  }
  CUPID_CALL(cupid_malloc((size_t)(2 * nc), sizeof *c->xz, "section candidate nodes", &c->xz));
  CUPID_CALL(cupid_malloc((size_t)(ne * npe), sizeof *c->conn, "section connectivity", &c->conn));
  CUPID_CALL(cupid_malloc((size_t)ne, sizeof *c->mat, "section materials", &c->mat));
  c->nc = nc;
  c->ne = ne;
  /* explicit nodes and elements first, so their numbering survives for simple meshes */
  if (def->n_section_nodes > 0)
    memcpy(c->xz, def->section_nodes, sizeof *c->xz * 2 * (size_t)def->n_section_nodes);
  cupid_int e = 0, nxt = def->n_section_nodes;
  for (int k = 0; k < def->n_section_elements; k++, e++) {
    for (int a = 0; a < npe; a++) {
      int id = def->section_elements[(size_t)k * npe + a];
      if (id < 0 || id >= def->n_section_nodes)
        return cupid_model_error(model, &def->mark,
                               "section element %d refers to node %d (there are %d nodes)", k, id,
                               def->n_section_nodes);
      c->conn[e * npe + a] = id;
    }
    int m = def->section_element_material ? def->section_element_material[k] : -1;
    c->mat[e] = m < 0 ? def->material : m;
  }
  for (int k = 0; k < def->n_components; k++) {
    const cupid_section_component *cp = &def->components[k];
    for (int i = 0; i + 1 < cp->nx; i++)
      if (!(cp->x[i + 1] > cp->x[i]))
        return cupid_model_error(model, &cp->mark, "x breakpoints must increase");
    for (int j = 0; j + 1 < cp->nz; j++)
      if (!(cp->z[j + 1] > cp->z[j]))
        return cupid_model_error(model, &cp->mark, "z breakpoints must increase");
    int mat = cp->material < 0 ? def->material : cp->material;
    if (mat < 0 || mat >= n_mat)
      return cupid_model_error(model, &cp->mark, "material index %d out of range", mat);
    for (int j = 0; j + 1 < cp->nz; j++)
      for (int i = 0; i + 1 < cp->nx; i++, e++) {
        for (int a = 0; a < npe; a++) {
          double r = q->grid[q->ia[a]], s = q->grid[q->ib[a]];
          c->xz[2 * nxt] = cp->x[i] + 0.5 * (r + 1) * (cp->x[i + 1] - cp->x[i]);
          c->xz[2 * nxt + 1] = cp->z[j] + 0.5 * (s + 1) * (cp->z[j + 1] - cp->z[j]);
          c->conn[e * npe + a] = nxt++;
        }
        c->mat[e] = mat;
      }
  }
  return st;
}

/* Does element e look like an affine axis-aligned rectangle (exact clipping and inversion)? */
static int is_rect(const beam_t *b, cupid_int e) {
  const cuf_quad *q = &b->quad;
  const double *bx = b->sbox + 4 * e;
  double tol = b->tol_xz;
  for (int a = 0; a < q->npe; a++) {
    const double *p = b->sxz + 2 * b->sconn[e * q->npe + a];
    double x = bx[0] + 0.5 * (q->grid[q->ia[a]] + 1) * (bx[1] - bx[0]);
    double z = bx[2] + 0.5 * (q->grid[q->ib[a]] + 1) * (bx[3] - bx[2]);
    if (fabs(p[0] - x) > tol || fabs(p[1] - z) > tol) return 0;
  }
  return 1;
}

static cupid_status check_mesh(beam_t *b, const cupid_model_t *model, const cupid_mark *mark) {
  const cuf_quad *q = &b->quad;
  double gx[CUF_MAX_N], gw[CUF_MAX_N];
  cuf_gauss(q->n, gx, gw);
  /* positive Jacobian at the Gauss points and the corners */
  for (cupid_int e = 0; e < b->n_selem; e++) {
    for (int i = 0; i < q->n * q->n + 4; i++) {
        double r, s;
        if (i < q->n * q->n) r = gx[i % q->n], s = gx[i / q->n];
        else r = (i - q->n * q->n) % 2 ? 1.0 : -1.0, s = (i - q->n * q->n) / 2 ? 1.0 : -1.0;
        double det = cuf_section_map(b, e, r, s, NULL, NULL, NULL);
        if (!(det > 0)) {
          char msg[200];
          snprintf(msg, sizeof msg,
                   "section element %lld is degenerate or ordered clockwise (det J = %g); "
                   "list nodes counter-clockwise in the x-z plane",
                   (long long)e, det);
          return sec_error(model, mark, msg);
        }
    }
  }
  /* hanging nodes: a node strictly inside an edge of an element it does not belong to (LE
   * only: TE cells are just the integration domain, they need not match). Nodes sorted by x,
   * so each element scans only the nodes in its x strip. */
  if (b->expansion == CUPID_EXPANSION_LE) {
    cupid_int *order = NULL;
    CUPID_CALL(cupid_malloc((size_t)b->n_snodes, sizeof *order, "section node order", &order));
    for (cupid_int v = 0; v < b->n_snodes; v++) order[v] = v;
    sort_xz = b->sxz;
    qsort(order, (size_t)b->n_snodes, sizeof *order, cmp_x);
    sort_xz = NULL;
    cupid_status st = CUPID_SUCCESS;
    for (cupid_int e = 0; e < b->n_selem && st == CUPID_SUCCESS; e++) {
      const cupid_int *c = b->sconn + e * q->npe;
      int corner[4] = {0, 0, 0, 0};
      for (int a = 0; a < q->npe; a++) {
        int ia = q->ia[a], ib = q->ib[a], last = q->n - 1;
        if (ia == 0 && ib == 0) corner[0] = a;
        if (ia == last && ib == 0) corner[1] = a;
        if (ia == last && ib == last) corner[2] = a;
        if (ia == 0 && ib == last) corner[3] = a;
      }
      const double *bx = b->sbox + 4 * e;
      double tol = b->tol_xz;
      cupid_int lo = 0, hi = b->n_snodes;
      while (lo < hi) { /* first node with x >= xmin - tol */
        cupid_int mid = (lo + hi) / 2;
        if (b->sxz[2 * order[mid]] < bx[0] - tol) lo = mid + 1;
        else hi = mid;
      }
      for (cupid_int k = lo; k < b->n_snodes && st == CUPID_SUCCESS; k++) {
        cupid_int v = order[k];
        const double *p = b->sxz + 2 * v;
        if (p[0] > bx[1] + tol) break;
        if (p[1] < bx[2] - tol || p[1] > bx[3] + tol) continue;
        int own = 0;
        for (int a = 0; a < q->npe; a++) own |= c[a] == v;
        if (own) continue;
        for (int k2 = 0; k2 < 4; k2++) {
          const double *A = b->sxz + 2 * c[corner[k2]], *B = b->sxz + 2 * c[corner[(k2 + 1) % 4]];
          double ex = B[0] - A[0], ez = B[1] - A[1], L2 = ex * ex + ez * ez;
          double t = ((p[0] - A[0]) * ex + (p[1] - A[1]) * ez) / L2;
          double dx = A[0] + t * ex - p[0], dz = A[1] + t * ez - p[1];
          double L = sqrt(L2);
          if (t * L > tol && (1 - t) * L > tol && sqrt(dx * dx + dz * dz) <= tol) {
            char msg[300];
            snprintf(msg, sizeof msg,
                     "section node (%g, %g) lies inside an edge of section element %lld "
                     "(components do not match there: add breakpoints so edges share nodes)",
                     p[0], p[1], (long long)e);
            st = sec_error(model, mark, msg);
            break;
          }
        }
      }
    }
    cupid_free(&order);
    CUPID_CALL(st);
  }
  /* overlapping rectangles (components that cover the same area) */
  for (cupid_int e = 0; e < b->n_selem; e++) {
    if (!b->srect[e]) continue;
    const double *A = b->sbox + 4 * e;
    for (cupid_int f = e + 1; f < b->n_selem; f++) {
      if (!b->srect[f]) continue;
      const double *B = b->sbox + 4 * f;
      double ox = fmin(A[1], B[1]) - fmax(A[0], B[0]), oz = fmin(A[3], B[3]) - fmax(A[2], B[2]);
      if (ox > b->tol_xz && oz > b->tol_xz) {
        char msg[300];
        snprintf(msg, sizeof msg,
                 "section elements %lld and %lld overlap ([%g, %g] x [%g, %g] and [%g, %g] x "
                 "[%g, %g]); components must not overlap",
                 (long long)e, (long long)f, A[0], A[1], A[2], A[3], B[0], B[1], B[2], B[3]);
        return sec_error(model, mark, msg);
      }
    }
  }
  return CUPID_SUCCESS;
}

static cupid_status build_adjacency(beam_t *b) {
  int npe = b->quad.npe;
  CUPID_CALL(cupid_calloc((size_t)b->n_snodes + 1, sizeof *b->n2e_ptr, "node-element map", &b->n2e_ptr));
  for (cupid_int e = 0; e < b->n_selem; e++)
    for (int a = 0; a < npe; a++) b->n2e_ptr[b->sconn[e * npe + a] + 1]++;
  for (cupid_int v = 0; v < b->n_snodes; v++) b->n2e_ptr[v + 1] += b->n2e_ptr[v];
  CUPID_CALL(cupid_malloc((size_t)b->n2e_ptr[b->n_snodes], sizeof *b->n2e, "node-element map", &b->n2e));
  cupid_int *fill = NULL;
  CUPID_CALL(cupid_calloc((size_t)b->n_snodes, sizeof *fill, "node-element fill", &fill));
  for (cupid_int e = 0; e < b->n_selem; e++)
    for (int a = 0; a < npe; a++) {
      cupid_int v = b->sconn[e * npe + a];
      b->n2e[b->n2e_ptr[v] + fill[v]++] = e;
    }
  cupid_free(&fill);
  return CUPID_SUCCESS;
}

/* Area, centroid, bounding box; TE centring and scale. */
static void section_measures(beam_t *b) {
  double gx[CUF_MAX_GAUSS], gw[CUF_MAX_GAUSS];
  int n = b->quad.n + 1;
  cuf_gauss(n, gx, gw);
  double A = 0, Sx = 0, Sz = 0;
  for (cupid_int e = 0; e < b->n_selem; e++)
    for (int i = 0; i < n; i++)
      for (int j = 0; j < n; j++) {
        double x, z, det = cuf_section_map(b, e, gx[i], gx[j], &x, &z, NULL);
        double w = gw[i] * gw[j] * det;
        A += w;
        Sx += w * x;
        Sz += w * z;
      }
  b->area = A;
  b->xc = Sx / A;
  b->zc = Sz / A;
  double h = 0;
  for (cupid_int v = 0; v < b->n_snodes; v++)
    h = fmax(h, fmax(fabs(b->sxz[2 * v] - b->xc), fabs(b->sxz[2 * v + 1] - b->zc)));
  b->h = h;
}

cupid_status cuf_section_build(beam_t *b, const cupid_beam *def, const cupid_model_t *model) {
  cupid_status st = CUPID_SUCCESS;
  candidates c = {0};
  cupid_int *rep = NULL, *id = NULL;
  int n = 2;
  if (def->n_section_elements > 0 || def->expansion == CUPID_EXPANSION_LE) {
    int ln = def->le_nodes;
    if (ln != 4 && ln != 9 && ln != 16) {
      st = cupid_model_error(model, &def->mark, "section element must be L4, L9 or L16 (got %d nodes)", ln);
      goto cleanup;
    }
    n = ln == 4 ? 2 : ln == 9 ? 3 : 4;
  }
  if (def->n_section_elements > 0 && (!def->section_nodes || !def->section_elements)) {
    st = cupid_model_error(model, &def->mark, "section elements need a node list");
    goto cleanup;
  }
  cuf_quad_init(&b->quad, n);
  CUPID_TRY(collect(def, model, b->n_mat, &b->quad, &c));
  if (c.ne == 0) {
    st = cupid_model_error(model, &def->mark, "the beam section has no component and no element");
    goto cleanup;
  }
  /* geometric tolerance from the extent of the candidates */
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (cupid_int k = 0; k < c.nc; k++)
    for (int d = 0; d < 2; d++) lo[d] = fmin(lo[d], c.xz[2 * k + d]), hi[d] = fmax(hi[d], c.xz[2 * k + d]);
  b->size = fmax(hi[0] - lo[0], hi[1] - lo[1]);
  b->tol_xz = 1e-9 * b->size;
  b->bbox[0] = lo[0], b->bbox[1] = hi[0], b->bbox[2] = lo[1], b->bbox[3] = hi[1];

  CUPID_TRY(cupid_malloc((size_t)c.nc, sizeof *rep, "node merge", &rep));
  CUPID_TRY(merge_points(c.nc, c.xz, b->tol_xz, rep));
  /* number referenced representatives in order of first use by the elements */
  CUPID_TRY(cupid_malloc((size_t)c.nc, sizeof *id, "node ids", &id));
  for (cupid_int k = 0; k < c.nc; k++) id[k] = -1;
  int npe = b->quad.npe;
  b->n_selem = c.ne;
  CUPID_TRY(cupid_malloc((size_t)(c.ne * npe), sizeof *b->sconn, "section connectivity", &b->sconn));
  cupid_int nn = 0;
  for (cupid_int k = 0; k < c.ne * npe; k++) {
    cupid_int r = rep[c.conn[k]];
    if (id[r] < 0) id[r] = nn++;
    b->sconn[k] = id[r];
  }
  b->n_snodes = nn;
  CUPID_TRY(cupid_malloc((size_t)(2 * nn), sizeof *b->sxz, "section nodes", &b->sxz));
  for (cupid_int k = 0; k < c.nc; k++)
    if (rep[k] == k && id[k] >= 0) {
      b->sxz[2 * id[k]] = c.xz[2 * k];
      b->sxz[2 * id[k] + 1] = c.xz[2 * k + 1];
    }
  for (cupid_int e = 0; e < c.ne; e++)
    for (int a = 0; a < npe; a++)
      for (int a2 = 0; a2 < a; a2++)
        if (b->sconn[e * npe + a] == b->sconn[e * npe + a2]) {
          st = cupid_model_error(model, &def->mark, "section element %lld has two coincident nodes",
                               (long long)e);
          goto cleanup;
        }
  CUPID_TRY(cupid_malloc((size_t)c.ne, sizeof *b->smat, "section materials", &b->smat));
  CUPID_TRY(cupid_malloc((size_t)(4 * c.ne), sizeof *b->sbox, "section boxes", &b->sbox));
  CUPID_TRY(cupid_malloc((size_t)c.ne, sizeof *b->srect, "section rectangles", &b->srect));
  for (cupid_int e = 0; e < c.ne; e++) {
    b->smat[e] = c.mat[e];
    if (c.mat[e] < 0 || c.mat[e] >= b->n_mat) {
      st = cupid_model_error(model, &def->mark, "section element %lld: material index %d out of range",
                           (long long)e, c.mat[e]);
      goto cleanup;
    }
    double *bx = b->sbox + 4 * e;
    bx[0] = bx[2] = INFINITY;
    bx[1] = bx[3] = -INFINITY;
    for (int a = 0; a < npe; a++) {
      const double *p = b->sxz + 2 * b->sconn[e * npe + a];
      bx[0] = fmin(bx[0], p[0]), bx[1] = fmax(bx[1], p[0]);
      bx[2] = fmin(bx[2], p[1]), bx[3] = fmax(bx[3], p[1]);
    }
    b->srect[e] = (unsigned char)is_rect(b, e);
  }
  CUPID_TRY(check_mesh(b, model, &def->mark));
  CUPID_TRY(build_adjacency(b));
  section_measures(b);
cleanup:
  cupid_free(&c.xz);
  cupid_free(&c.conn);
  cupid_free(&c.mat);
  cupid_free(&rep);
  cupid_free(&id);
  return st;
}
