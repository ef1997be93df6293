/* Weighted CUF stiffness and mass for the Arlequin coupling (paper 004 Eqs. 12 and 14): the
 * beam's internal and kinetic energies enter the coupled Hamiltonian multiplied by alpha(y)
 * (Eq. 8), so the nucleus keeps its separable form with weighted axis integrals
 * I^alpha = int alpha H_dt(N_j) H_dr(N_i) dy and A^alpha = int alpha N_j N_i dy, the section
 * integrals being unchanged. The axis rule has p + 2 Gauss points: exact for a weight of
 * degree <= 3 on each element (the linear and cubic ramps of the Arlequin weights). */
#include <string.h>

#include "cuf/cuf_internal.h"

typedef struct cupid_cuf_beam_private beam_t;

/* Weighted axis integrals of beam element e, layout of cuf_axis_integrals(). Reduced parts
 * keep their p - 1 point rule (the weight is sampled there). */
static void weighted_axis_integrals(const beam_t *b, cupid_int e, cupid_cuf_weight_fn fn,
                                    void *ctx, double *I) {
  int p = b->p;
  double y0 = b->by[e * (p - 1)], y1 = b->by[(e + 1) * (p - 1)], J = 0.5 * (y1 - y0);
  memset(I, 0, sizeof *I * (size_t)b->n_parts * 4 * p * p);
  for (int P = 0; P < b->n_parts; P++) {
    int ng = b->parts[P].reduced ? p - 1 : p + 2;
    double gx[CUF_MAX_GAUSS], gw[CUF_MAX_GAUSS];
    cuf_gauss(ng, gx, gw);
    for (int g = 0; g < ng; g++) {
      double H[2][CUF_MAX_P];
      cuf_axis_shape(b, e, gx[g], H[0], H[1]);
      double w = gw[g] * J * fn(ctx, y0 + (gx[g] + 1.0) * J);
      for (int dt = 0; dt < 2; dt++)
        for (int dr = 0; dr < 2; dr++) {
          double *Id = I + ((size_t)P * 4 + 2 * dt + dr) * p * p;
          for (int j = 0; j < p; j++)
            for (int i = 0; i < p; i++) Id[j * p + i] += w * H[dt][j] * H[dr][i];
        }
    }
  }
}

/* Weighted axis mass integrals A[j p + i] = int alpha N_j N_i dy. */
static void weighted_axis_mass(const beam_t *b, cupid_int e, cupid_cuf_weight_fn fn, void *ctx,
                               double *A) {
  int p = b->p, ng = p + 2;
  double gx[CUF_MAX_GAUSS], gw[CUF_MAX_GAUSS], N[CUF_MAX_P];
  double y0 = b->by[e * (p - 1)], y1 = b->by[(e + 1) * (p - 1)], J = 0.5 * (y1 - y0);
  cuf_gauss(ng, gx, gw);
  memset(A, 0, sizeof *A * (size_t)(p * p));
  for (int g = 0; g < ng; g++) {
    cuf_axis_shape(b, e, gx[g], N, NULL);
    double w = gw[g] * J * fn(ctx, y0 + (gx[g] + 1.0) * J);
    for (int j = 0; j < p; j++)
      for (int i = 0; i < p; i++) A[j * p + i] += w * N[j] * N[i];
  }
}

/* Add a dense pair matrix (layout of cuf_pair_matrix) at block offset boff (binary searches:
 * this path serves small coupled beams, not the production assembly). */
static cupid_status scatter(const beam_t *b, cupid_csr K, cupid_int boff, cupid_int be,
                            cupid_int se, int m, const double *Ke) {
  int p = b->p, n = 3 * m * p;
  cupid_int j0 = be * (p - 1), M = b->M;
  for (int s = 0; s < m; s++)
    for (int j = 0; j < p; j++) {
      cupid_int row = boff + (j0 + j) * M + cuf_tau(b, se, s);
      for (int t = 0; t < m; t++)
        for (int i = 0; i < p; i++) {
          double *blk = cupid_csr_find(K, row, boff + (j0 + i) * M + cuf_tau(b, se, t));
          CUPID_CHECK(blk, CUPID_ERR_ARGUMENT, "the matrix pattern lacks blocks of the CUF beam");
          const double *src = Ke + (size_t)((s * p + j) * 3) * n + (t * p + i) * 3;
          for (int k = 0; k < 3; k++)
            for (int h = 0; h < 3; h++) blk[3 * k + h] += src[(size_t)k * n + h];
        }
    }
  return CUPID_SUCCESS;
}

static cupid_status stiffness_impl(const beam_t *b, cupid_cuf_weight_fn fn, void *ctx,
                                   cupid_csr K, cupid_int boff) {
  CUPID_CHECK(b->integration != CUPID_CUF_MITC, CUPID_ERR_UNSUPPORTED,
              "weighted CUF stiffness (Arlequin): MITC integration is not yet supported (use "
              "full or reduced)");
  cupid_status st = CUPID_SUCCESS;
  int m = cuf_local_m(b), p = b->p;
  size_t per = 9 * (size_t)m * m, nK = (size_t)(3 * m * p) * (3 * m * p);
  double *I = NULL, *E = NULL, *Ke = NULL;
  CUPID_TRY(cupid_malloc((size_t)b->n_parts * 4 * p * p, sizeof *I, "axis integrals", &I));
  CUPID_TRY(cupid_malloc(per, sizeof *E, "section integrals", &E));
  CUPID_TRY(cupid_malloc(nK, sizeof *Ke, "element matrix", &Ke));
  for (cupid_int be = 0; be < b->n_belem; be++) {
    weighted_axis_integrals(b, be, fn, ctx, I);
    for (cupid_int se = 0; se < b->n_selem; se++) {
      if (!b->active[be * b->n_selem + se]) continue;
      if (b->expansion == CUPID_EXPANSION_TE) memcpy(E, b->te_E + per * se, sizeof *E * per);
      else cuf_section_integrals(b, se, b->sec_ng, E);
      cuf_pair_matrix(b, m, E, b->smat[se], I, Ke);
      CUPID_TRY(scatter(b, K, boff, be, b->expansion == CUPID_EXPANSION_TE ? -1 : se, m, Ke));
    }
  }
cleanup:
  cupid_free(&I);
  cupid_free(&E);
  cupid_free(&Ke);
  return st;
}

cupid_status cupid_cuf_assemble_weighted_add(const cupid_cuf_beam b, cupid_cuf_weight_fn fn,
                                             void *ctx, cupid_csr K) {
  CUPID_CHECK(b && fn && K && K->bs == 3, CUPID_ERR_ARGUMENT,
              "cupid_cuf_assemble_weighted_add: need a beam, a weight and a bs = 3 matrix");
  cupid_int boff = b->dof_offset / 3;
  CUPID_CHECK(K->nrows >= boff + b->n_bnodes * b->M, CUPID_ERR_ARGUMENT,
              "matrix too small for the beam at DOF offset %lld", (long long)b->dof_offset);
  return stiffness_impl(b, fn, ctx, K, boff);
}

cupid_status cupid_cuf_assemble_weighted(const cupid_cuf_beam b, cupid_cuf_weight_fn fn, void *ctx,
                                         cupid_csr *K) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int *rowptr = NULL, *col = NULL;
  CUPID_CHECK(b && fn && K, CUPID_ERR_ARGUMENT, "cupid_cuf_assemble_weighted: NULL argument");
  *K = NULL;
  cupid_int n = b->n_bnodes * b->M;
  CUPID_TRY(cupid_cuf_pattern(b, &rowptr, &col));
  CUPID_TRY(cupid_csr_create(n, n, 3, rowptr, col, K));
  st = stiffness_impl(b, fn, ctx, *K, 0);
  if (st != CUPID_SUCCESS) cupid_csr_destroy(K);
cleanup:
  cupid_free(&rowptr);
  cupid_free(&col);
  return st;
}

/* Section mass integrals S[s m + t] = rho int F_s F_t dA of section element se. */
static void section_mass(const beam_t *b, cupid_int se, double *E, double *S) {
  int m = cuf_local_m(b);
  size_t per = 9 * (size_t)m * m, mm = (size_t)m * m;
  const double *src = E;
  if (b->expansion == CUPID_EXPANSION_TE) src = b->te_E + per * se;
  else cuf_section_integrals(b, se, b->sec_ng, E);
  double rho = b->mat[b->smat[se]].density;
  for (size_t q = 0; q < mm; q++) S[q] = rho * src[4 * mm + q]; /* the G_1 G_1 entry */
}

/* Visit the active pairs with weighted axis mass integrals: lumped (d != NULL, HRZ as in
 * mass.c) or consistent (into M). */
static cupid_status mass_impl(const beam_t *b, cupid_cuf_weight_fn fn, void *ctx, cupid_csr M,
                              double *d) {
  cupid_status st = CUPID_SUCCESS;
  int m = cuf_local_m(b), p = b->p;
  double *E = NULL, *S = NULL, A[CUF_MAX_P * CUF_MAX_P];
  cupid_int boff = b->dof_offset / 3, Mf = b->M;
  CUPID_TRY(cupid_malloc(9 * (size_t)m * m, sizeof *E, "section integrals", &E));
  CUPID_TRY(cupid_malloc((size_t)m * m, sizeof *S, "section mass integrals", &S));
  for (cupid_int be = 0; be < b->n_belem; be++) {
    weighted_axis_mass(b, be, fn, ctx, A);
    cupid_int j0 = be * (p - 1);
    for (cupid_int se = 0; se < b->n_selem; se++) {
      if (!b->active[be * b->n_selem + se]) continue;
      section_mass(b, se, E, S);
      if (d) {
        /* HRZ: the pair's (weighted) mass over the translational diagonal */
        double mass = 0.0, trans = 0.0, srow = 0.0;
        for (int q = 0; q < p * p; q++) mass += A[q];
        if (b->expansion == CUPID_EXPANSION_LE) {
          for (int q = 0; q < m * m; q++) srow += S[q];
          for (int s = 0; s < m; s++)
            for (int j = 0; j < p; j++) trans += S[s * m + s] * A[j * p + j];
        } else {
          srow = S[0];
          for (int j = 0; j < p; j++) trans += S[0] * A[j * p + j];
        }
        if (trans <= 0.0) continue;
        double scale = mass * srow / trans;
        for (int s = 0; s < m; s++)
          for (int j = 0; j < p; j++) {
            cupid_int dof = b->dof_offset + 3 * ((j0 + j) * Mf + cuf_tau(b, se, s));
            for (int k = 0; k < 3; k++) d[dof + k] += scale * S[s * m + s] * A[j * p + j];
          }
        continue;
      }
      for (int s = 0; s < m; s++)
        for (int j = 0; j < p; j++) {
          cupid_int row = boff + (j0 + j) * Mf + cuf_tau(b, se, s);
          for (int t = 0; t < m; t++)
            for (int i = 0; i < p; i++) {
              double v = S[s * m + t] * A[j * p + i];
              if (v == 0.0) continue;
              double *blk = cupid_csr_find(M, row, boff + (j0 + i) * Mf + cuf_tau(b, se, t));
              CUPID_TRY_CHECK(blk, CUPID_ERR_ARGUMENT,
                              "the matrix pattern lacks blocks of the CUF mass");
              for (int k = 0; k < 3; k++) blk[4 * k] += v;
            }
        }
    }
  }
cleanup:
  cupid_free(&E);
  cupid_free(&S);
  return st;
}

cupid_status cupid_cuf_mass_weighted_add(const cupid_cuf_beam b, cupid_cuf_weight_fn fn, void *ctx,
                                         cupid_csr M) {
  CUPID_CHECK(b && fn && M && M->bs == 3, CUPID_ERR_ARGUMENT,
              "cupid_cuf_mass_weighted_add: need a beam, a weight and a bs = 3 matrix");
  CUPID_CHECK(M->nrows >= b->dof_offset / 3 + b->n_bnodes * b->M, CUPID_ERR_ARGUMENT,
              "matrix too small for the beam at DOF offset %lld", (long long)b->dof_offset);
  return mass_impl(b, fn, ctx, M, NULL);
}

cupid_status cupid_cuf_mass_lumped_weighted(const cupid_cuf_beam b, cupid_cuf_weight_fn fn,
                                            void *ctx, double *d) {
  CUPID_CHECK(b && fn && d, CUPID_ERR_ARGUMENT, "cupid_cuf_mass_lumped_weighted: NULL argument");
  return mass_impl(b, fn, ctx, NULL, d);
}
