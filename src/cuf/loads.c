/* Consistent nodal forces of a CUF beam (cuf.md section 1.4): point loads
 * f_{tau i k} = F_tau(x0, z0) N_i(y0) P_k, tractions on a section plane (patch clipped to the
 * section elements) and body forces in a box, integrated with Gauss rules. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "cuf/cuf_internal.h"

typedef struct cupid_cuf_beam_private beam_t;

#define CUF_SUBCELLS 8 /* parametric sub-cells per direction for clipping curved elements */

/* Quadrature points of section element e clipped to rect = [xlo, xhi, zlo, zhi]: parametric
 * (r, s) and weights including det J. Exact clipping for affine rectangles; curved elements
 * that straddle the rectangle are integrated on sub-cells, keeping the points inside (an
 * approximation whose error falls with the sub-cell size). Arrays hold CUF_SUBCELLS^2 ng^2. */
int cuf_clip_rule(const beam_t *b, cupid_int e, const double rect[4], int ng, double *r, double *s,
                  double *w) {
  double gx[CUF_MAX_GAUSS], gw[CUF_MAX_GAUSS];
  cuf_gauss(ng, gx, gw);
  const double *bx = b->sbox + 4 * e;
  double tol = b->tol_xz;
  double x0 = fmax(rect[0], bx[0]), x1 = fmin(rect[1], bx[1]);
  double z0 = fmax(rect[2], bx[2]), z1 = fmin(rect[3], bx[3]);
  if (x1 - x0 <= tol || z1 - z0 <= tol) return 0;
  int n = 0;
  if (b->srect[e]) {
    double hx = 0.5 * (x1 - x0), hz = 0.5 * (z1 - z0);
    double jr = 2.0 / (bx[1] - bx[0]), js = 2.0 / (bx[3] - bx[2]);
    for (int i = 0; i < ng; i++)
      for (int j = 0; j < ng; j++) {
        double x = x0 + hx * (gx[i] + 1), z = z0 + hz * (gx[j] + 1);
        r[n] = (x - bx[0]) * jr - 1;
        s[n] = (z - bx[2]) * js - 1;
        w[n++] = gw[i] * gw[j] * hx * hz;
      }
    return n;
  }
  int inside = rect[0] <= bx[0] + tol && rect[1] >= bx[1] - tol && rect[2] <= bx[2] + tol &&
               rect[3] >= bx[3] - tol;
  int nsub = inside ? 1 : CUF_SUBCELLS;
  double h = 2.0 / nsub;
  for (int a = 0; a < nsub; a++)
    for (int c = 0; c < nsub; c++)
      for (int i = 0; i < ng; i++)
        for (int j = 0; j < ng; j++) {
          double R = -1 + h * (a + 0.5 * (gx[i] + 1)), S = -1 + h * (c + 0.5 * (gx[j] + 1));
          double x, z, det = cuf_section_map(b, e, R, S, &x, &z, NULL);
          if (!inside && (x < rect[0] || x > rect[1] || z < rect[2] || z > rect[3])) continue;
          r[n] = R;
          s[n] = S;
          w[n++] = gw[i] * gw[j] * det * 0.25 * h * h;
        }
  return n;
}

static void box_rect(const cupid_box *box, double rect[4]) {
  rect[0] = (box && box->has[0]) ? box->lo[0] : -INFINITY;
  rect[1] = (box && box->has[0]) ? box->hi[0] : INFINITY;
  rect[2] = (box && box->has[2]) ? box->lo[2] : -INFINITY;
  rect[3] = (box && box->has[2]) ? box->hi[2] : INFINITY;
}

/* An active beam element containing y for section element se (-1 if none). */
static cupid_int active_element_at(const beam_t *b, cupid_int se, double y, double *xi) {
  cupid_int e = cuf_axis_locate(b, y, xi);
  if (e < 0) return -1;
  if (b->active[e * b->n_selem + se]) return e;
  double y1 = b->by[(e + 1) * (b->p - 1)];
  if (e + 1 < b->n_belem && fabs(y - y1) <= b->tol_y && b->active[(e + 1) * b->n_selem + se]) {
    *xi = -1.0;
    return e + 1;
  }
  return -1;
}

cupid_status cupid_cuf_point_load_add(const cupid_cuf_beam b, const double at[3], const double P[3],
                                      double *f) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int *node = NULL;
  double *w = NULL;
  int cnt = 0;
  CUPID_TRY(cupid_malloc((size_t)(b->M * b->p), sizeof *node, "shape nodes", &node));
  CUPID_TRY(cupid_malloc((size_t)(b->M * b->p), sizeof *w, "shape weights", &w));
  CUPID_TRY(cupid_cuf_shape_at(b, at[0], at[1], at[2], node, w, &cnt));
  for (int q = 0; q < cnt; q++)
    for (int k = 0; k < 3; k++) f[b->dof_offset + 3 * node[q] + k] += w[q] * P[k];
cleanup:
  cupid_free(&node);
  cupid_free(&w);
  return st;
}

cupid_status cupid_cuf_traction_add(const cupid_cuf_beam b, double y, const cupid_box *patch,
                                    cupid_cuf_field_fn fn, void *ctx, double *f, double *area) {
  cupid_status st = CUPID_SUCCESS;
  double rect[4], *r = NULL, *s = NULL, *w = NULL, *F = NULL, total = 0;
  box_rect(patch, rect);
  int ng = b->sec_ng + 2, m = cuf_local_m(b), maxq = CUF_SUBCELLS * CUF_SUBCELLS * ng * ng;
  CUPID_CHECK(y >= b->ymin - b->tol_y && y <= b->ymax + b->tol_y, CUPID_ERR_MODEL,
              "traction plane y = %g is outside the beam (y in [%g, %g])", y, b->ymin, b->ymax);
  CUPID_TRY(cupid_malloc((size_t)maxq, sizeof *r, "quadrature", &r));
  CUPID_TRY(cupid_malloc((size_t)maxq, sizeof *s, "quadrature", &s));
  CUPID_TRY(cupid_malloc((size_t)maxq, sizeof *w, "quadrature", &w));
  CUPID_TRY(cupid_malloc((size_t)m, sizeof *F, "expansion values", &F));
  for (cupid_int se = 0; se < b->n_selem; se++) {
    double xi, N[CUF_MAX_P];
    cupid_int be = active_element_at(b, se, y, &xi);
    if (be < 0) continue;
    int nq = cuf_clip_rule(b, se, rect, ng, r, s, w);
    if (nq == 0) continue;
    cuf_axis_shape(b, be, xi, N, NULL);
    cupid_int j0 = be * (b->p - 1);
    double dens = b->mat[b->smat[se]].density;
    for (int q = 0; q < nq; q++) {
      double p[3], t[3];
      cuf_section_functions(b, se, r[q], s[q], F, NULL, NULL, &p[0], &p[2], NULL);
      p[1] = y;
      fn(ctx, p, dens, t);
      total += w[q];
      for (int a = 0; a < m; a++) {
        int tau = cuf_tau(b, se, a);
        for (int j = 0; j < b->p; j++) {
          double c = w[q] * F[a] * N[j];
          if (c == 0.0) continue;
          double *fd = f + b->dof_offset + 3 * ((j0 + j) * b->M + tau);
          fd[0] += c * t[0], fd[1] += c * t[1], fd[2] += c * t[2];
        }
      }
    }
  }
  if (area) *area = total;
  CUPID_TRY_CHECK(total > 0, CUPID_ERR_MODEL, "the traction patch does not meet the beam section at y = %g", y);
cleanup:
  cupid_free(&r);
  cupid_free(&s);
  cupid_free(&w);
  cupid_free(&F);
  return st;
}

cupid_status cupid_cuf_body_force_add(const cupid_cuf_beam b, const cupid_box *box,
                                      cupid_cuf_field_fn fn, void *ctx, double *f, double *volume) {
  cupid_status st = CUPID_SUCCESS;
  double rect[4], *r = NULL, *s = NULL, *w = NULL, *F = NULL, total = 0;
  box_rect(box, rect);
  double ylo = (box && box->has[1]) ? box->lo[1] : -INFINITY, yhi = (box && box->has[1]) ? box->hi[1] : INFINITY;
  int ng = b->sec_ng + 2, nga = b->p + 2, m = cuf_local_m(b), maxq = CUF_SUBCELLS * CUF_SUBCELLS * ng * ng;
  double gx[CUF_MAX_GAUSS], gw[CUF_MAX_GAUSS];
  cuf_gauss(nga, gx, gw);
  CUPID_TRY(cupid_malloc((size_t)maxq, sizeof *r, "quadrature", &r));
  CUPID_TRY(cupid_malloc((size_t)maxq, sizeof *s, "quadrature", &s));
  CUPID_TRY(cupid_malloc((size_t)maxq, sizeof *w, "quadrature", &w));
  CUPID_TRY(cupid_malloc((size_t)m, sizeof *F, "expansion values", &F));
  for (cupid_int se = 0; se < b->n_selem; se++) {
    int nq = cuf_clip_rule(b, se, rect, ng, r, s, w);
    if (nq == 0) continue;
    double dens = b->mat[b->smat[se]].density;
    for (cupid_int be = 0; be < b->n_belem; be++) {
      if (!b->active[be * b->n_selem + se]) continue;
      double y0 = b->by[be * (b->p - 1)], y1 = b->by[(be + 1) * (b->p - 1)];
      double c0 = fmax(y0, ylo), c1 = fmin(y1, yhi);
      if (c1 - c0 <= b->tol_y) continue;
      cupid_int j0 = be * (b->p - 1);
      for (int g = 0; g < nga; g++) {
        double y = c0 + 0.5 * (c1 - c0) * (gx[g] + 1), wy = 0.5 * (c1 - c0) * gw[g];
        double xi = (2 * y - y0 - y1) / (y1 - y0), N[CUF_MAX_P];
        cuf_axis_shape(b, be, xi, N, NULL);
        for (int q = 0; q < nq; q++) {
          double p[3], t[3];
          cuf_section_functions(b, se, r[q], s[q], F, NULL, NULL, &p[0], &p[2], NULL);
          p[1] = y;
          fn(ctx, p, dens, t);
          total += wy * w[q];
          for (int a = 0; a < m; a++) {
            int tau = cuf_tau(b, se, a);
            for (int j = 0; j < b->p; j++) {
              double c = wy * w[q] * F[a] * N[j];
              double *fd = f + b->dof_offset + 3 * ((j0 + j) * b->M + tau);
              fd[0] += c * t[0], fd[1] += c * t[1], fd[2] += c * t[2];
            }
          }
        }
      }
    }
  }
  if (volume) *volume = total;
  CUPID_TRY_CHECK(total > 0, CUPID_ERR_MODEL, "the body-force box does not meet the beam");
cleanup:
  cupid_free(&r);
  cupid_free(&s);
  cupid_free(&w);
  cupid_free(&F);
  return st;
}

/* ---------------------------------------------------------------- model loads */

static void value_field(void *ctx, const double p[3], double density, double out[3]) {
  const cuf_values_at *at = ctx;
  for (int k = 0; k < 3; k++) out[k] = cuf_value(&at->v[k], p, density, at->t);
}

cupid_status cupid_cuf_load_add(const cupid_cuf_beam b, const cupid_model_t *model,
                                const cupid_load *load, double *f) {
  cupid_status st;
  cuf_values_at at = {load->value, b->time};
  void *ctx = &at;
  switch (load->kind) {
    case CUPID_LOAD_TRACTION:
      st = cupid_cuf_traction_add(b, load->plane_y, &load->patch, value_field, ctx, f, NULL);
      break;
    case CUPID_LOAD_POINT: {
      double P[3];
      value_field(ctx, load->at, 0.0, P);
      st = cupid_cuf_point_load_add(b, load->at, P, f);
      break;
    }
    case CUPID_LOAD_BODY:
      st = cupid_cuf_body_force_add(b, &load->box, value_field, ctx, f, NULL);
      break;
    default: return CUPID_ERROR(CUPID_ERR_ARGUMENT, "unknown load kind %d", (int)load->kind);
  }
  if (st == CUPID_ERR_MODEL) {
    char msg[1024];
    snprintf(msg, sizeof msg, "%s", cupid_error_message());
    return cupid_model_error(model, &load->mark, "%s", msg);
  }
  return st;
}

cupid_status cupid_cuf_load_vector(const cupid_cuf_beam b, const cupid_model_t *model, double *f) {
  for (int k = 0; k < model->n_loads; k++) CUPID_CALL(cupid_cuf_load_add(b, model, &model->loads[k], f));
  return CUPID_SUCCESS;
}
