/* Weighted CUF stiffness and mass for the Arlequin coupling (paper 004 Eqs. 12 and 14): the
 * beam's internal and kinetic energies enter the coupled Hamiltonian multiplied by alpha
 * (Eq. 8). alpha is a separable sum c + sum_t a_t(y) s_t(x, z) (cupid_cuf_weight), so the
 * nucleus keeps its separable form term by term: axis integrals
 * I^t = int a_t H_dt(N_j) H_dr(N_i) dy and A^t = int a_t N_j N_i dy, section integrals
 * weighted by s_t, and the pair matrix is the sum of the terms' pair matrices (it is linear in
 * each). The axis rule has p + 2 Gauss points and the weighted section rule sec_ng + 2 per
 * direction: exact for weights of degree <= 3 on each element (the linear and cubic ramps of
 * the Arlequin weights, whose kinks lie on element boundaries). */
#include <string.h>

#include "cuf/cuf_internal.h"

typedef struct cupid_cuf_beam_private beam_t;

/* One term of the weight as the kernels see it: scale * a(y) * s(x, z), NULL functions 1. */
typedef struct {
  cupid_cuf_weight_fn axis;
  void *axis_ctx;
  cupid_cuf_section_weight_fn section;
  void *section_ctx;
  double scale;
} term_t;

/* Weighted axis integrals of beam element e, layout of cuf_axis_integrals(). Reduced parts
 * keep their p - 1 point rule (the weight is sampled there). Returns 1 if any is non-zero. */
static int weighted_axis_integrals(const beam_t *b, cupid_int e, const term_t *t, double *I) {
  int p = b->p, any = 0;
  double y0 = b->by[e * (p - 1)], y1 = b->by[(e + 1) * (p - 1)], J = 0.5 * (y1 - y0);
  memset(I, 0, sizeof *I * (size_t)b->n_parts * 4 * p * p);
  for (int P = 0; P < b->n_parts; P++) {
    int ng = b->parts[P].reduced ? p - 1 : p + 2;
    double gx[CUF_MAX_GAUSS], gw[CUF_MAX_GAUSS];
    cuf_gauss(ng, gx, gw);
    for (int g = 0; g < ng; g++) {
      double H[2][CUF_MAX_P], y = y0 + (gx[g] + 1.0) * J;
      double w = gw[g] * J * t->scale * (t->axis ? t->axis(t->axis_ctx, y) : 1.0);
      if (w == 0.0) continue;
      any = 1;
      cuf_axis_shape(b, e, gx[g], H[0], H[1]);
      for (int dt = 0; dt < 2; dt++)
        for (int dr = 0; dr < 2; dr++) {
          double *Id = I + ((size_t)P * 4 + 2 * dt + dr) * p * p;
          for (int j = 0; j < p; j++)
            for (int i = 0; i < p; i++) Id[j * p + i] += w * H[dt][j] * H[dr][i];
        }
    }
  }
  return any;
}

/* Weighted axis mass integrals A[j p + i] = int scale a N_j N_i dy; 1 if any is non-zero. */
static int weighted_axis_mass(const beam_t *b, cupid_int e, const term_t *t, double *A) {
  int p = b->p, ng = p + 2, any = 0;
  double gx[CUF_MAX_GAUSS], gw[CUF_MAX_GAUSS], N[CUF_MAX_P];
  double y0 = b->by[e * (p - 1)], y1 = b->by[(e + 1) * (p - 1)], J = 0.5 * (y1 - y0);
  cuf_gauss(ng, gx, gw);
  memset(A, 0, sizeof *A * (size_t)(p * p));
  for (int g = 0; g < ng; g++) {
    double y = y0 + (gx[g] + 1.0) * J;
    double w = gw[g] * J * t->scale * (t->axis ? t->axis(t->axis_ctx, y) : 1.0);
    if (w == 0.0) continue;
    any = 1;
    cuf_axis_shape(b, e, gx[g], N, NULL);
    for (int j = 0; j < p; j++)
      for (int i = 0; i < p; i++) A[j * p + i] += w * N[j] * N[i];
  }
  return any;
}

/* Section integrals of section element se weighted by the term's s(x, z) (unweighted: the
 * stiffness rule, TE cells from their cache); 1 if any is non-zero. */
static int term_section_integrals(const beam_t *b, cupid_int se, const term_t *t, double *E) {
  int m = cuf_local_m(b);
  size_t per = 9 * (size_t)m * m;
  if (!t->section && b->expansion == CUPID_EXPANSION_TE) memcpy(E, b->te_E + per * se, sizeof *E * per);
  else if (!t->section) cuf_section_integrals(b, se, b->sec_ng, E);
  else {
    int ng = b->sec_ng + 2 < CUF_MAX_GAUSS ? b->sec_ng + 2 : CUF_MAX_GAUSS;
    cuf_section_integrals_weighted(b, se, ng, t->section, t->section_ctx, E);
  }
  for (size_t q = 0; q < per; q++)
    if (E[q] != 0.0) return 1;
  return 0;
}

/* The kernels' terms of w: the constant (if any) first. *n = how many. */
static cupid_status terms_of(const cupid_cuf_weight *w, term_t **out, int *n) {
  CUPID_CHECK(w->n_terms >= 0 && (w->n_terms == 0 || w->terms), CUPID_ERR_ARGUMENT,
              "weighted CUF matrices: %d weight terms without a term array", w->n_terms);
  CUPID_CALL(cupid_malloc((size_t)w->n_terms + 1, sizeof **out, "weight terms", out));
  *n = 0;
  if (w->constant != 0.0) (*out)[(*n)++] = (term_t){.scale = w->constant};
  for (int k = 0; k < w->n_terms; k++)
    (*out)[(*n)++] = (term_t){w->terms[k].axis, w->terms[k].axis_ctx, w->terms[k].section,
                              w->terms[k].section_ctx, 1.0};
  return CUPID_SUCCESS;
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

static cupid_status stiffness_impl(const beam_t *b, const cupid_cuf_weight *w, cupid_csr K,
                                   cupid_int boff) {
  CUPID_CHECK(b->integration != CUPID_CUF_MITC, CUPID_ERR_UNSUPPORTED,
              "weighted CUF stiffness (Arlequin): MITC integration is not yet supported (use "
              "full or reduced)");
  cupid_status st = CUPID_SUCCESS;
  int m = cuf_local_m(b), p = b->p, nt = 0;
  size_t per = 9 * (size_t)m * m, nK = (size_t)(3 * m * p) * (3 * m * p);
  size_t nI = (size_t)b->n_parts * 4 * p * p;
  double *I = NULL, *E = NULL, *Ke = NULL, *Kt = NULL;
  term_t *t = NULL;
  int *live = NULL;
  CUPID_TRY(terms_of(w, &t, &nt));
  CUPID_TRY(cupid_malloc(nI * (size_t)(nt + 1), sizeof *I, "axis integrals", &I));
  CUPID_TRY(cupid_malloc((size_t)nt + 1, sizeof *live, "live terms", &live));
  CUPID_TRY(cupid_malloc(per, sizeof *E, "section integrals", &E));
  CUPID_TRY(cupid_malloc(nK, sizeof *Ke, "element matrix", &Ke));
  CUPID_TRY(cupid_malloc(nK, sizeof *Kt, "term matrix", &Kt));
  for (cupid_int be = 0; be < b->n_belem; be++) {
    int any_axis = 0;
    for (int k = 0; k < nt; k++) any_axis |= live[k] = weighted_axis_integrals(b, be, &t[k], I + nI * k);
    if (!any_axis) continue;
    for (cupid_int se = 0; se < b->n_selem; se++) {
      if (!b->active[be * b->n_selem + se]) continue;
      int any = 0;
      for (int k = 0; k < nt; k++) {
        if (!live[k] || !term_section_integrals(b, se, &t[k], E)) continue;
        cuf_pair_matrix(b, m, E, b->smat[se], I + nI * k, any ? Kt : Ke);
        if (any)
          for (size_t q = 0; q < nK; q++) Ke[q] += Kt[q];
        any = 1;
      }
      if (any) CUPID_TRY(scatter(b, K, boff, be, b->expansion == CUPID_EXPANSION_TE ? -1 : se, m, Ke));
    }
  }
cleanup:
  cupid_free(&I);
  cupid_free(&E);
  cupid_free(&Ke);
  cupid_free(&Kt);
  cupid_free(&t);
  cupid_free(&live);
  return st;
}

static cupid_status check_beam_matrix(const cupid_cuf_beam b, const cupid_cuf_weight *w,
                                      cupid_csr A, const char *fn) {
  CUPID_CHECK(b && w && A && A->bs == 3, CUPID_ERR_ARGUMENT,
              "%s: need a beam, a weight and a bs = 3 matrix", fn);
  CUPID_CHECK(A->nrows >= b->dof_offset / 3 + b->n_bnodes * b->M, CUPID_ERR_ARGUMENT,
              "%s: matrix too small for the beam at DOF offset %lld", fn, (long long)b->dof_offset);
  return CUPID_SUCCESS;
}

cupid_status cupid_cuf_assemble_weight_add(const cupid_cuf_beam b, const cupid_cuf_weight *w,
                                           cupid_csr K) {
  CUPID_CALL(check_beam_matrix(b, w, K, "cupid_cuf_assemble_weight_add"));
  return stiffness_impl(b, w, K, b->dof_offset / 3);
}

/* The axis-only weight fn(ctx, y) as a cupid_cuf_weight (one term). */
#define AXIS_WEIGHT(name, fn, ctx)                                                                 \
  cupid_cuf_weight_term name##_term = {.axis = (fn), .axis_ctx = (ctx)};                        \
  cupid_cuf_weight name = {.n_terms = 1, .terms = &name##_term}

cupid_status cupid_cuf_assemble_weighted_add(const cupid_cuf_beam b, cupid_cuf_weight_fn fn,
                                             void *ctx, cupid_csr K) {
  CUPID_CHECK(fn, CUPID_ERR_ARGUMENT, "cupid_cuf_assemble_weighted_add: NULL weight");
  AXIS_WEIGHT(w, fn, ctx);
  return cupid_cuf_assemble_weight_add(b, &w, K);
}

cupid_status cupid_cuf_assemble_weighted(const cupid_cuf_beam b, cupid_cuf_weight_fn fn, void *ctx,
                                         cupid_csr *K) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int *rowptr = NULL, *col = NULL;
  CUPID_CHECK(b && fn && K, CUPID_ERR_ARGUMENT, "cupid_cuf_assemble_weighted: NULL argument");
  *K = NULL;
  AXIS_WEIGHT(w, fn, ctx);
  cupid_int n = b->n_bnodes * b->M;
  CUPID_TRY(cupid_cuf_pattern(b, &rowptr, &col));
  CUPID_TRY(cupid_csr_create(n, n, 3, rowptr, col, K));
  st = stiffness_impl(b, &w, *K, 0);
  if (st != CUPID_SUCCESS) cupid_csr_destroy(K);
cleanup:
  cupid_free(&rowptr);
  cupid_free(&col);
  return st;
}

/* Section mass integrals S[s m + t] = rho int s F_s F_t dA of section element se, weighted
 * by the term's s(x, z); 1 if any is non-zero. */
static int section_mass(const beam_t *b, cupid_int se, const term_t *t, double *E, double *S) {
  int m = cuf_local_m(b);
  size_t mm = (size_t)m * m;
  if (!term_section_integrals(b, se, t, E)) return 0;
  double rho = b->mat[b->smat[se]].density;
  for (size_t q = 0; q < mm; q++) S[q] = rho * E[4 * mm + q]; /* the G_1 G_1 entry */
  return 1;
}

/* HRZ lumping of one pair (as in mass.c): the diagonal of its weighted consistent mass
 * sum_t S_t (x) A_t scaled so that the translational functions carry the pair's weighted
 * mass. */
static void lump_pair(const beam_t *b, cupid_int be, cupid_int se, int nt, const double *S,
                      const double *A, double *d) {
  int m = cuf_local_m(b), p = b->p, le = b->expansion == CUPID_EXPANSION_LE;
  size_t mm = (size_t)m * m, pp = (size_t)p * p;
  double mass = 0.0, trans = 0.0;
  for (int k = 0; k < nt; k++) {
    const double *Sk = S + mm * k, *Ak = A + pp * k;
    double asum = 0.0, srow = 0.0;
    for (size_t q = 0; q < pp; q++) asum += Ak[q];
    if (le)
      for (size_t q = 0; q < mm; q++) srow += Sk[q];
    else srow = Sk[0];
    mass += asum * srow;
    for (int s = 0; s < (le ? m : 1); s++)
      for (int j = 0; j < p; j++) trans += Sk[s * m + s] * Ak[j * p + j];
  }
  if (trans <= 0.0) return;
  double scale = mass / trans;
  cupid_int j0 = be * (p - 1);
  for (int s = 0; s < m; s++)
    for (int j = 0; j < p; j++) {
      double diag = 0.0;
      for (int k = 0; k < nt; k++) diag += S[mm * k + s * m + s] * A[pp * k + j * p + j];
      cupid_int dof = b->dof_offset + 3 * ((j0 + j) * b->M + cuf_tau(b, se, s));
      for (int c = 0; c < 3; c++) d[dof + c] += scale * diag;
    }
}

/* Add the pair's weighted consistent mass sum_t S_t (x) A_t into M. */
static cupid_status add_pair_mass(const beam_t *b, cupid_int be, cupid_int se, int nt,
                                  const double *S, const double *A, cupid_csr M) {
  int m = cuf_local_m(b), p = b->p;
  size_t mm = (size_t)m * m, pp = (size_t)p * p;
  cupid_int boff = b->dof_offset / 3, j0 = be * (p - 1);
  for (int s = 0; s < m; s++)
    for (int j = 0; j < p; j++) {
      cupid_int row = boff + (j0 + j) * b->M + cuf_tau(b, se, s);
      for (int t = 0; t < m; t++)
        for (int i = 0; i < p; i++) {
          double v = 0.0;
          for (int k = 0; k < nt; k++) v += S[mm * k + s * m + t] * A[pp * k + j * p + i];
          if (v == 0.0) continue;
          double *blk = cupid_csr_find(M, row, boff + (j0 + i) * b->M + cuf_tau(b, se, t));
          CUPID_CHECK(blk, CUPID_ERR_ARGUMENT, "the matrix pattern lacks blocks of the CUF mass");
          for (int c = 0; c < 3; c++) blk[4 * c] += v;
        }
    }
  return CUPID_SUCCESS;
}

/* Visit the active pairs with their weighted mass terms: lumped (d != NULL) or consistent
 * (into M). A term whose axis or section weight vanishes on the pair enters as zero. */
static cupid_status mass_impl(const beam_t *b, const cupid_cuf_weight *w, cupid_csr M, double *d) {
  cupid_status st = CUPID_SUCCESS;
  int m = cuf_local_m(b), p = b->p, nt = 0;
  size_t mm = (size_t)m * m, pp = (size_t)p * p;
  double *E = NULL, *S = NULL, *A = NULL;
  term_t *t = NULL;
  CUPID_TRY(terms_of(w, &t, &nt));
  CUPID_TRY(cupid_malloc(9 * mm, sizeof *E, "section integrals", &E));
  CUPID_TRY(cupid_malloc(mm * (size_t)(nt + 1), sizeof *S, "section mass integrals", &S));
  CUPID_TRY(cupid_malloc(pp * (size_t)(nt + 1), sizeof *A, "axis mass integrals", &A));
  for (cupid_int be = 0; be < b->n_belem; be++) {
    int any_axis = 0;
    for (int k = 0; k < nt; k++) any_axis |= weighted_axis_mass(b, be, &t[k], A + pp * k);
    if (!any_axis) continue;
    for (cupid_int se = 0; se < b->n_selem; se++) {
      if (!b->active[be * b->n_selem + se]) continue;
      for (int k = 0; k < nt; k++)
        if (!section_mass(b, se, &t[k], E, S + mm * k)) memset(S + mm * k, 0, sizeof *S * mm);
      if (d) lump_pair(b, be, se, nt, S, A, d);
      else CUPID_TRY(add_pair_mass(b, be, se, nt, S, A, M));
    }
  }
cleanup:
  cupid_free(&E);
  cupid_free(&S);
  cupid_free(&A);
  cupid_free(&t);
  return st;
}

cupid_status cupid_cuf_mass_weight_add(const cupid_cuf_beam b, const cupid_cuf_weight *w,
                                       cupid_csr M) {
  CUPID_CALL(check_beam_matrix(b, w, M, "cupid_cuf_mass_weight_add"));
  return mass_impl(b, w, M, NULL);
}

cupid_status cupid_cuf_mass_lumped_weight(const cupid_cuf_beam b, const cupid_cuf_weight *w,
                                          double *d) {
  CUPID_CHECK(b && w && d, CUPID_ERR_ARGUMENT, "cupid_cuf_mass_lumped_weight: NULL argument");
  return mass_impl(b, w, NULL, d);
}

cupid_status cupid_cuf_mass_weighted_add(const cupid_cuf_beam b, cupid_cuf_weight_fn fn, void *ctx,
                                         cupid_csr M) {
  CUPID_CHECK(fn, CUPID_ERR_ARGUMENT, "cupid_cuf_mass_weighted_add: NULL weight");
  AXIS_WEIGHT(w, fn, ctx);
  return cupid_cuf_mass_weight_add(b, &w, M);
}

cupid_status cupid_cuf_mass_lumped_weighted(const cupid_cuf_beam b, cupid_cuf_weight_fn fn,
                                            void *ctx, double *d) {
  CUPID_CHECK(fn, CUPID_ERR_ARGUMENT, "cupid_cuf_mass_lumped_weighted: NULL weight");
  AXIS_WEIGHT(w, fn, ctx);
  return cupid_cuf_mass_lumped_weight(b, &w, d);
}
