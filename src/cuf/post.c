/* Post-processing of a CUF beam: point location, displacement and stress anywhere inside the
 * beam (3D strain of the expansion, sigma = C eps), field interpolation, and the 3D
 * reconstruction as hexahedra for VTK. */
#include <math.h>
#include <string.h>

#include "cuf/cuf_internal.h"

typedef struct cupid_cuf_beam_private beam_t;

int cuf_locate(const beam_t *b, double x, double y, double z, cupid_int *be, cupid_int *se,
               double *xi, double *r, double *s) {
  double x0;
  cupid_int e0 = cuf_axis_locate(b, y, &x0);
  if (e0 < 0) return 0;
  /* at a shared node the upper element is a candidate too */
  int two = e0 + 1 < b->n_belem && fabs(y - b->by[(e0 + 1) * (b->p - 1)]) <= b->tol_y;
  for (cupid_int e = 0; e < b->n_selem; e++) {
    double R, S;
    if (!cuf_section_invert(b, e, x, z, &R, &S)) continue;
    for (int c = 0; c <= two; c++) {
      cupid_int eb = e0 + c;
      if (!b->active[eb * b->n_selem + e]) continue;
      *be = eb;
      *se = e;
      *xi = c ? -1.0 : x0;
      *r = R;
      *s = S;
      return 1;
    }
  }
  return 0;
}

int cupid_cuf_contains(const cupid_cuf_beam b, double x, double y, double z) {
  cupid_int be, se;
  double xi, r, s;
  return cuf_locate(b, x, y, z, &be, &se, &xi, &r, &s);
}

cupid_status cupid_cuf_shape_at(const cupid_cuf_beam b, double x, double y, double z,
                                cupid_int *node, double *w, int *count) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int be, se;
  double xi, r, s, N[CUF_MAX_P], *F = NULL;
  CUPID_CHECK(cuf_locate(b, x, y, z, &be, &se, &xi, &r, &s), CUPID_ERR_MODEL,
              "point (%g, %g, %g) is outside the beam", x, y, z);
  int m = cuf_local_m(b), n = 0;
  CUPID_TRY(cupid_malloc((size_t)m, sizeof *F, "expansion values", &F));
  cuf_section_functions(b, se, r, s, F, NULL, NULL, NULL, NULL, NULL);
  cuf_axis_shape(b, be, xi, N, NULL);
  for (int j = 0; j < b->p; j++)
    for (int a = 0; a < m; a++) {
      node[n] = (be * (b->p - 1) + j) * b->M + cuf_tau(b, se, a);
      w[n++] = N[j] * F[a];
    }
  *count = n;
cleanup:
  cupid_free(&F);
  return st;
}

/* g[3][3] is followed by g0, the constant-term (tau = 0) part of du_y/dy (TE1 Poisson
 * correction), in a gradient of 10 entries. */
static void evaluate(const beam_t *b, const double *u, cupid_int be, cupid_int se, double xi,
                     double r, double s, double *F, double *Fx, double *Fz, double out[3],
                     double g[10]) {
  double N[CUF_MAX_P], dN[CUF_MAX_P];
  int m = cuf_local_m(b);
  cuf_section_functions(b, se, r, s, F, Fx, Fz, NULL, NULL, NULL);
  cuf_axis_shape(b, be, xi, N, dN);
  memset(g, 0, 10 * sizeof *g);
  out[0] = out[1] = out[2] = 0;
  for (int j = 0; j < b->p; j++)
    for (int a = 0; a < m; a++) {
      const double *q = u + b->dof_offset + 3 * ((be * (b->p - 1) + j) * b->M + cuf_tau(b, se, a));
      double v = N[j] * F[a], vx = N[j] * Fx[a], vy = dN[j] * F[a], vz = N[j] * Fz[a];
      for (int k = 0; k < 3; k++) {
        out[k] += v * q[k];
        g[3 * k + 0] += vx * q[k];
        g[3 * k + 1] += vy * q[k];
        g[3 * k + 2] += vz * q[k];
      }
      if (b->poisson_split && a == 0) g[9] += vy * q[1]; /* TE: term 0 is F = 1 */
    }
}

/* sigma = C eps; with the TE1 Poisson correction plus R eps0, eps0 = eps with eps_yy replaced
 * by its constant-term part (the law of the stiffness, cuf_pair_matrix). */
static void stress_from_gradient(const beam_t *b, int mat, const double g[10], double sig[6]) {
  double eps[6] = {0};
  for (int k = 0; k < 3; k++)
    for (int d = 0; d < 3; d++) eps[cuf_vidx[k][d]] += g[3 * k + d]; /* engineering shears */
  const double *C = b->mat[mat].C;
  for (int i = 0; i < 6; i++) {
    sig[i] = 0;
    for (int j = 0; j < 6; j++) sig[i] += C[6 * i + j] * eps[j];
  }
  if (!b->poisson_split) return;
  eps[CUF_YY] = g[9];
  const double *R = b->mat[mat].R;
  for (int i = 0; i < 6; i++)
    for (int j = 0; j < 6; j++) sig[i] += R[6 * i + j] * eps[j];
}

static cupid_status at_point(const beam_t *b, const double *u, double x, double y, double z,
                             double disp[3], double sig[6]) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int be, se;
  double xi, r, s, g[10], d[3], *F = NULL;
  CUPID_CHECK(cuf_locate(b, x, y, z, &be, &se, &xi, &r, &s), CUPID_ERR_MODEL,
              "point (%g, %g, %g) is outside the beam", x, y, z);
  int m = cuf_local_m(b);
  CUPID_TRY(cupid_malloc(3 * (size_t)m, sizeof *F, "expansion values", &F));
  evaluate(b, u, be, se, xi, r, s, F, F + m, F + 2 * m, d, g);
  if (disp) memcpy(disp, d, sizeof d);
  if (sig) stress_from_gradient(b, b->smat[se], g, sig);
cleanup:
  cupid_free(&F);
  return st;
}

cupid_status cupid_cuf_displacement_at(const cupid_cuf_beam b, const double *u, double x, double y,
                                       double z, double out[3]) {
  return at_point(b, u, x, y, z, out, NULL);
}

cupid_status cupid_cuf_stress_at(const cupid_cuf_beam b, const double *u, double x, double y,
                                 double z, double out[6]) {
  return at_point(b, u, x, y, z, NULL, out);
}

/* The largest eigenvalue of the symmetric strain of gradient g (g[3 k + d] = du_k / dx_d), by
 * the trigonometric closed form of a symmetric 3x3. */
static double max_principal(const double g[10]) {
  const double a = g[0], b = g[4], c = g[8];
  const double d = 0.5 * (g[1] + g[3]), e = 0.5 * (g[5] + g[7]), f = 0.5 * (g[2] + g[6]); /* xy yz xz */
  const double q = (a + b + c) / 3.0, p1 = d * d + e * e + f * f;
  const double p2 = (a - q) * (a - q) + (b - q) * (b - q) + (c - q) * (c - q) + 2.0 * p1;
  if (p2 <= 1e-300) return q; /* a multiple of the identity */
  const double p = sqrt(p2 / 6.0);
  const double A = (a - q) / p, B = (b - q) / p, C = (c - q) / p, D = d / p, E = e / p, F = f / p;
  const double det = A * (B * C - E * E) - D * (D * C - E * F) + F * (D * E - B * F);
  const double r = fmax(-1.0, fmin(1.0, 0.5 * det));
  return q + 2.0 * p * cos(acos(r) / 3.0);
}

cupid_status cupid_cuf_strain_peaks(const cupid_cuf_beam b, const double *u, double *peak) {
  CUPID_CHECK(b && u && peak, CUPID_ERR_ARGUMENT, "strain peaks need a beam, u and an output");
  const int m = cuf_local_m(b), ng = b->sec_ng, na = b->p;
  double ga[CUF_MAX_GAUSS], gs[CUF_MAX_GAUSS], w[CUF_MAX_GAUSS];
  cuf_gauss(na, ga, w);
  cuf_gauss(ng, gs, w);
  cupid_status st = CUPID_SUCCESS;
#pragma omp parallel
  {
    double *F = NULL, g[10], d[3];
    if (cupid_malloc(3 * (size_t)m, sizeof *F, "expansion values", &F) != CUPID_SUCCESS) {
#pragma omp critical(cuf_strain_peaks)
      st = CUPID_ERR_MEMORY;
    }
#pragma omp for schedule(dynamic, 1)
    for (cupid_int be = 0; be < b->n_belem; be++)
      for (cupid_int se = 0; se < b->n_selem; se++) {
        double best = -INFINITY;
        if (F && b->active[be * b->n_selem + se])
          for (int i = 0; i < na; i++)
            for (int j = 0; j < ng; j++)
              for (int k = 0; k < ng; k++) {
                evaluate(b, u, be, se, ga[i], gs[j], gs[k], F, F + m, F + 2 * m, d, g);
                best = fmax(best, max_principal(g));
              }
        peak[be * b->n_selem + se] = best;
      }
    cupid_free(&F);
  }
  return st == CUPID_SUCCESS ? CUPID_SUCCESS : CUPID_ERROR(st, "out of memory for the strain peaks");
}

cupid_status cupid_cuf_interpolate(const cupid_cuf_beam b, cupid_cuf_field_fn fn, void *ctx, double *u) {
  cupid_status st = CUPID_SUCCESS;
  double *c = NULL;
  if (b->expansion == CUPID_EXPANSION_TE) {
    CUPID_TRY(cupid_malloc(3 * (size_t)b->M, sizeof *c, "TE coefficients", &c));
    for (cupid_int i = 0; i < b->n_bnodes; i++) {
      CUPID_TRY(cuf_te_project(b, b->by[i], fn, ctx, c));
      memcpy(u + b->dof_offset + 3 * i * b->M, c, sizeof *c * 3 * (size_t)b->M);
    }
  } else {
    for (cupid_int i = 0; i < b->n_bnodes; i++)
      for (cupid_int t = 0; t < b->n_snodes; t++) {
        double p[3] = {b->sxz[2 * t], b->by[i], b->sxz[2 * t + 1]};
        fn(ctx, p, b->mat[b->smat[b->n2e[b->n2e_ptr[t]]]].density, u + cupid_cuf_dof(b, (int)t, i, 0));
      }
  }
cleanup:
  cupid_free(&c);
  return st;
}

/* ---------------------------------------------------------------- VTU reconstruction */

void cupid_cuf_vtu_destroy(cupid_cuf_vtu **vtu) {
  if (!vtu || !*vtu) return;
  cupid_cuf_vtu *v = *vtu;
  cupid_free(&v->points);
  cupid_free(&v->displacement);
  cupid_free(&v->stress);
  cupid_free(&v->connectivity);
  cupid_free(&v->offsets);
  cupid_free(&v->types);
  cupid_free(vtu);
}

cupid_status cupid_cuf_vtu_build(const cupid_cuf_beam b, const double *u, int subdivisions,
                                 cupid_cuf_vtu **out) {
  cupid_status st = CUPID_SUCCESS;
  cupid_cuf_vtu *v = NULL;
  cupid_int *pairs = NULL, np = 0;
  double *zero = NULL;
  CUPID_CHECK(out, CUPID_ERR_ARGUMENT, "cupid_cuf_vtu_build: NULL argument");
  *out = NULL;
  if (!u) {
    CUPID_TRY(cupid_calloc((size_t)(b->dof_offset + 3 * b->n_bnodes * b->M), sizeof *zero, "zero field", &zero));
    u = zero;
  }
  int ns = b->expansion == CUPID_EXPANSION_LE ? b->quad.n - 1 : (subdivisions > 0 ? subdivisions : b->te_order + 1);
  int p = b->p, pps = (ns + 1) * (ns + 1) * p, cps = ns * ns * (p - 1);
  double sg[CUF_MAX_GAUSS + 1];
  for (int a = 0; a <= ns; a++) sg[a] = b->expansion == CUPID_EXPANSION_LE ? b->quad.grid[a] : -1.0 + 2.0 * a / ns;
  CUPID_TRY(cupid_malloc((size_t)(b->n_belem * b->n_selem), sizeof *pairs, "active pairs", &pairs));
  for (cupid_int k = 0; k < b->n_belem * b->n_selem; k++)
    if (b->active[k]) pairs[np++] = k;
  CUPID_TRY(cupid_calloc(1, sizeof *v, "VTU reconstruction", &v));
  v->n_points = np * pps;
  v->n_cells = np * cps;
  CUPID_TRY(cupid_malloc((size_t)(3 * v->n_points), sizeof *v->points, "VTU points", &v->points));
  CUPID_TRY(cupid_malloc((size_t)(3 * v->n_points), sizeof *v->displacement, "VTU displacement", &v->displacement));
  CUPID_TRY(cupid_malloc((size_t)(6 * v->n_points), sizeof *v->stress, "VTU stress", &v->stress));
  CUPID_TRY(cupid_malloc((size_t)(8 * v->n_cells), sizeof *v->connectivity, "VTU cells", &v->connectivity));
  CUPID_TRY(cupid_malloc((size_t)v->n_cells, sizeof *v->offsets, "VTU offsets", &v->offsets));
  CUPID_TRY(cupid_malloc((size_t)v->n_cells, 1, "VTU types", &v->types));
  int m = cuf_local_m(b), nomem = 0;
#pragma omp parallel reduction(| : nomem) if (v->n_points > 20000)
  {
    double *F = NULL;
    if (cupid_malloc(3 * (size_t)m, sizeof *F, "expansion values", &F)) {
      nomem = 1;
    } else {
#pragma omp for schedule(dynamic)
      for (cupid_int q = 0; q < np; q++) {
        cupid_int be = pairs[q] / b->n_selem, se = pairs[q] % b->n_selem, p0 = q * pps;
        double xi[CUF_MAX_P];
        cuf_beam_nodes(p, xi);
        for (int a = 0; a < p; a++)
          for (int j = 0; j <= ns; j++)
            for (int i = 0; i <= ns; i++) {
              cupid_int pt = p0 + (a * (ns + 1) + j) * (ns + 1) + i;
              double x, z, g[10];
              cuf_section_map(b, se, sg[i], sg[j], &x, &z, NULL);
              double *X = v->points + 3 * pt;
              X[0] = x;
              X[1] = b->by[be * (p - 1) + a];
              X[2] = z;
              evaluate(b, u, be, se, xi[a], sg[i], sg[j], F, F + m, F + 2 * m, v->displacement + 3 * pt, g);
              double sig[6], *so = v->stress + 6 * pt;
              stress_from_gradient(b, b->smat[se], g, sig);
              /* VTK's symmetric-tensor order XX YY ZZ XY YZ XZ (ParaView labels) */
              so[0] = sig[CUF_XX], so[1] = sig[CUF_YY], so[2] = sig[CUF_ZZ];
              so[3] = sig[CUF_XY], so[4] = sig[CUF_YZ], so[5] = sig[CUF_XZ];
            }
        cupid_int c0 = q * cps;
        for (int a = 0; a + 1 < p; a++)
          for (int j = 0; j < ns; j++)
            for (int i = 0; i < ns; i++) {
              cupid_int c = c0 + (a * ns + j) * ns + i, *cn = v->connectivity + 8 * c;
              /* (r0,s0) (r0,s1) (r1,s1) (r1,s0): normal along +y for a counter-clockwise
               * x-z element, so the bottom face (y_a) points to the top one (VTK rule) */
              for (int lev = 0; lev < 2; lev++) {
                cupid_int base = p0 + (cupid_int)(a + lev) * (ns + 1) * (ns + 1);
                cn[4 * lev + 0] = base + j * (ns + 1) + i;
                cn[4 * lev + 1] = base + (j + 1) * (ns + 1) + i;
                cn[4 * lev + 2] = base + (j + 1) * (ns + 1) + i + 1;
                cn[4 * lev + 3] = base + j * (ns + 1) + i + 1;
              }
              v->offsets[c] = 8 * (c + 1);
              v->types[c] = CUPID_VTK_HEXAHEDRON;
            }
      }
    }
    cupid_free(&F);
  }
  CUPID_TRY_CHECK(!nomem, CUPID_ERR_MEMORY, "out of memory building the VTU reconstruction");
  v->point_data[0] = (cupid_vtu_array){"displacement", 3, v->displacement};
  v->point_data[1] = (cupid_vtu_array){"stress", 6, v->stress};
  v->mesh = (cupid_vtu_mesh){.n_points = v->n_points,
                             .points = v->points,
                             .n_cells = v->n_cells,
                             .connectivity = v->connectivity,
                             .offsets = v->offsets,
                             .types = v->types,
                             .point_data = v->point_data,
                             .n_point_data = 2};
  *out = v;
  v = NULL;
cleanup:
  cupid_cuf_vtu_destroy(&v);
  cupid_free(&pairs);
  cupid_free(&zero);
  return st;
}
