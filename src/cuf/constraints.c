/* Dirichlet conditions of a CUF beam: clamp of a section at a beam node (all generalised DOFs,
 * hence u = 0 on the whole section for TE and LE, cuf.md 1.4), fixed or prescribed components
 * on LE nodes in a box, and prescribed fields on whole TE sections (L2 projection). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "cuf/cuf_internal.h"

typedef struct cupid_cuf_beam_private beam_t;

static int in_range(const cupid_box *box, int a, double v, double tol) {
  return !box || !box->has[a] || (v >= box->lo[a] - tol && v <= box->hi[a] + tol);
}

static cupid_status check_bc(const beam_t *b, const cupid_dirichlet_t *bc) {
  CUPID_CHECK(bc && bc->n >= b->dof_offset + 3 * b->n_bnodes * b->M, CUPID_ERR_ARGUMENT,
              "Dirichlet set too small for the beam (%lld DOFs at offset %lld)",
              (long long)(3 * b->n_bnodes * b->M), (long long)b->dof_offset);
  return CUPID_SUCCESS;
}

cupid_status cupid_cuf_clamp_node(const cupid_cuf_beam b, cupid_int node, cupid_dirichlet bc) {
  CUPID_CALL(check_bc(b, bc));
  CUPID_CHECK(node >= 0 && node < b->n_bnodes, CUPID_ERR_ARGUMENT, "beam node %lld out of range",
              (long long)node);
  for (int tau = 0; tau < b->M; tau++)
    for (int k = 0; k < 3; k++) {
      cupid_int d = cupid_cuf_dof(b, tau, node, k);
      bc->fixed[d] = 1;
      bc->value[d] = 0.0;
    }
  return CUPID_SUCCESS;
}

/* Small dense Cholesky solve (in place) of the TE Gram system, nrhs right-hand sides stored
 * as rhs[i * nrhs + r]. */
static int cholesky_solve(int n, double *A, int nrhs, double *rhs) {
  for (int j = 0; j < n; j++) {
    double d = A[j * n + j];
    for (int k = 0; k < j; k++) d -= A[j * n + k] * A[j * n + k];
    if (!(d > 0)) return 1;
    d = sqrt(d);
    A[j * n + j] = d;
    for (int i = j + 1; i < n; i++) {
      double v = A[i * n + j];
      for (int k = 0; k < j; k++) v -= A[i * n + k] * A[j * n + k];
      A[i * n + j] = v / d;
    }
  }
  for (int r = 0; r < nrhs; r++) {
    for (int i = 0; i < n; i++) {
      double v = rhs[i * nrhs + r];
      for (int k = 0; k < i; k++) v -= A[i * n + k] * rhs[k * nrhs + r];
      rhs[i * nrhs + r] = v / A[i * n + i];
    }
    for (int i = n - 1; i >= 0; i--) {
      double v = rhs[i * nrhs + r];
      for (int k = i + 1; k < n; k++) v -= A[k * n + i] * rhs[k * nrhs + r];
      rhs[i * nrhs + r] = v / A[i * n + i];
    }
  }
  return 0;
}

cupid_status cuf_te_project(const beam_t *b, double y, cupid_cuf_field_fn fn, void *ctx, double *c) {
  cupid_status st = CUPID_SUCCESS;
  int M = b->M, ng = b->sec_ng + 2;
  double *G = NULL, *F = NULL, gx[CUF_MAX_GAUSS], gw[CUF_MAX_GAUSS];
  size_t per = 9 * (size_t)M * M;
  CUPID_TRY(cupid_calloc((size_t)M * M, sizeof *G, "TE Gram matrix", &G));
  CUPID_TRY(cupid_malloc((size_t)M, sizeof *F, "TE values", &F));
  memset(c, 0, sizeof *c * 3 * (size_t)M);
  cuf_gauss(ng, gx, gw);
  for (cupid_int e = 0; e < b->n_selem; e++) {
    const double *E11 = b->te_E + per * e + 4 * (size_t)M * M; /* int F_s F_tau */
    for (size_t q = 0; q < (size_t)M * M; q++) G[q] += E11[q];
    double dens = b->mat[b->smat[e]].density;
    for (int i = 0; i < ng; i++)
      for (int j = 0; j < ng; j++) {
        double p[3], det, g[3];
        cuf_section_functions(b, e, gx[i], gx[j], F, NULL, NULL, &p[0], &p[2], &det);
        p[1] = y;
        fn(ctx, p, dens, g);
        double w = gw[i] * gw[j] * det;
        for (int t = 0; t < M; t++)
          for (int k = 0; k < 3; k++) c[3 * t + k] += w * F[t] * g[k];
      }
  }
  CUPID_TRY_CHECK(!cholesky_solve(M, G, 3, c), CUPID_ERR_NUMERIC,
                  "TE%d projection: the section Gram matrix is not positive definite", b->te_order);
cleanup:
  cupid_free(&G);
  cupid_free(&F);
  return st;
}

cupid_status cupid_cuf_prescribe(const cupid_cuf_beam b, const cupid_box *box, const int mask[3],
                                 cupid_cuf_field_fn fn, void *ctx, cupid_dirichlet bc,
                                 cupid_int *count) {
  cupid_status st = CUPID_SUCCESS;
  double *c = NULL;
  cupid_int n = 0;
  CUPID_CALL(check_bc(b, bc));
  if (b->expansion == CUPID_EXPANSION_TE) {
    /* generalised DOFs act on the whole section: the box must hold all of it */
    double t = b->tol_xz;
    int whole = in_range(box, 0, b->bbox[0], t) && in_range(box, 0, b->bbox[1], t) &&
                in_range(box, 2, b->bbox[2], t) && in_range(box, 2, b->bbox[3], t);
    CUPID_CHECK(whole, CUPID_ERR_MODEL,
                "a TE section can only be constrained as a whole: the box must contain the "
                "section [%g, %g] x [%g, %g] (use an LE section to constrain part of it)",
                b->bbox[0], b->bbox[1], b->bbox[2], b->bbox[3]);
    CUPID_TRY(cupid_calloc(3 * (size_t)b->M, sizeof *c, "TE coefficients", &c));
  }
  for (cupid_int i = 0; i < b->n_bnodes; i++) {
    double y = b->by[i];
    if (!in_range(box, 1, y, b->tol_y)) continue;
    if (b->expansion == CUPID_EXPANSION_TE) {
      if (fn) CUPID_TRY(cuf_te_project(b, y, fn, ctx, c));
      for (int tau = 0; tau < b->M; tau++)
        for (int k = 0; k < 3; k++) {
          if (!mask[k]) continue;
          cupid_int d = cupid_cuf_dof(b, tau, i, k);
          bc->fixed[d] = 1;
          bc->value[d] = c[3 * tau + k];
          n++;
        }
      continue;
    }
    for (cupid_int tau = 0; tau < b->n_snodes; tau++) {
      double p[3] = {b->sxz[2 * tau], y, b->sxz[2 * tau + 1]}, v[3] = {0, 0, 0};
      if (!in_range(box, 0, p[0], b->tol_xz) || !in_range(box, 2, p[2], b->tol_xz)) continue;
      if (fn) fn(ctx, p, b->mat[b->smat[b->n2e[b->n2e_ptr[tau]]]].density, v);
      for (int k = 0; k < 3; k++) {
        if (!mask[k]) continue;
        cupid_int d = cupid_cuf_dof(b, (int)tau, i, k);
        bc->fixed[d] = 1;
        bc->value[d] = v[k];
        n++;
      }
    }
  }
  if (count) *count = n;
cleanup:
  cupid_free(&c);
  return st;
}

static void value_field(void *ctx, const double p[3], double density, double out[3]) {
  const cuf_values_at *at = ctx;
  for (int k = 0; k < 3; k++) out[k] = cuf_value(&at->v[k], p, density, at->t);
}

cupid_status cupid_cuf_constraint_apply(const cupid_cuf_beam b, const cupid_model_t *model,
                                        const cupid_constraint *c, cupid_dirichlet bc) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int count = 0;
  switch (c->kind) {
    case CUPID_CONSTRAINT_CLAMP: {
      cupid_int node = cupid_cuf_beam_node_at(b, c->plane_y);
      if (node < 0)
        return cupid_model_error(model, &c->mark,
                               "clamp plane y = %g is not a beam node (put an axis breakpoint there; "
                               "the beam spans y in [%g, %g])",
                               c->plane_y, b->ymin, b->ymax);
      return cupid_cuf_clamp_node(b, node, bc);
    }
    case CUPID_CONSTRAINT_FIX:
      st = cupid_cuf_prescribe(b, &c->box, c->components, NULL, NULL, bc, &count);
      break;
    case CUPID_CONSTRAINT_DISPLACEMENT: {
      int mask[3];
      for (int k = 0; k < 3; k++) mask[k] = c->value[k].kind != CUPID_VALUE_NONE;
      cuf_values_at at = {c->value, b->time};
      st = cupid_cuf_prescribe(b, &c->box, mask, value_field, &at, bc, &count);
      break;
    }
    default: return CUPID_ERROR(CUPID_ERR_ARGUMENT, "unknown constraint kind %d", (int)c->kind);
  }
  if (st == CUPID_ERR_MODEL) {
    char msg[1024];
    snprintf(msg, sizeof msg, "%s", cupid_error_message());
    return cupid_model_error(model, &c->mark, "%s", msg);
  }
  if (st == CUPID_SUCCESS && count == 0)
    return cupid_model_error(model, &c->mark, "the box contains no node of the beam");
  return st;
}

cupid_status cupid_cuf_apply_constraints(const cupid_cuf_beam b, const cupid_model_t *model,
                                         cupid_dirichlet bc) {
  for (int k = 0; k < model->n_constraints; k++)
    CUPID_CALL(cupid_cuf_constraint_apply(b, model, &model->constraints[k], bc));
  return CUPID_SUCCESS;
}
