/* The CUF mass matrix (paper 004 Eq. 3, M = int rho N^T N dV, in CUF form): the fundamental
 * nucleus of the mass is M_ij^{tau s} = delta_kl int_A rho F_tau F_s dA int_l N_i N_j dy,
 * which separates into the section integral int F_tau F_s dA of each section element (the
 * G_1 G_1 entry of cuf_section_integrals) and an axis integral per beam element. Assembled
 * into the stiffness pattern (bs = 3; every (tau,i)-(s,j) pair of the mass shares an active
 * section element and a beam element, so the stiffness pattern holds it). */
#include <math.h>
#include <string.h>

#include "cuf/cuf_internal.h"

typedef struct cupid_cuf_beam_private beam_t;

/* Axis mass integrals of beam element e: A[j p + i] = int N_j N_i dy (p Gauss points are
 * exact for the degree 2(p-1) product on a straight element). */
static void axis_mass(const beam_t *b, cupid_int e, double *A) {
  int p = b->p, ng = p;
  double xg[CUF_MAX_GAUSS], wg[CUF_MAX_GAUSS], N[CUF_MAX_P];
  cuf_gauss(ng, xg, wg);
  double J = 0.5 * (b->by[(e + 1) * (p - 1)] - b->by[e * (p - 1)]);
  memset(A, 0, sizeof *A * (size_t)(p * p));
  for (int g = 0; g < ng; g++) {
    cuf_axis_shape(b, e, xg[g], N, NULL);
    for (int j = 0; j < p; j++)
      for (int i = 0; i < p; i++) A[j * p + i] += wg[g] * J * N[j] * N[i];
  }
}

/* Visit every active (beam element, section element) pair with its section mass integrals
 * S[s m + tau] = rho int F_s F_tau dA (local functions) and axis integrals A. */
typedef cupid_status (*pair_fn)(const beam_t *b, void *ctx, cupid_int be, cupid_int se, int m,
                                const double *S, const double *A);

static cupid_status for_each_pair(const beam_t *b, pair_fn fn, void *ctx) {
  cupid_status st = CUPID_SUCCESS;
  int m = cuf_local_m(b);
  size_t per = 9 * (size_t)m * m;
  double *E = NULL, *S = NULL, A[CUF_MAX_P * CUF_MAX_P];
  CUPID_TRY(cupid_malloc(per, sizeof *E, "section integrals", &E));
  CUPID_TRY(cupid_malloc((size_t)m * m, sizeof *S, "section mass integrals", &S));
  for (cupid_int be = 0; be < b->n_belem; be++) {
    axis_mass(b, be, A);
    for (cupid_int se = 0; se < b->n_selem; se++) {
      if (!b->active[be * b->n_selem + se]) continue;
      const double *src;
      if (b->expansion == CUPID_EXPANSION_TE) {
        src = b->te_E + per * se;
      } else {
        cuf_section_integrals(b, se, b->sec_ng, E);
        src = E;
      }
      double rho = b->mat[b->smat[se]].density;
      for (size_t q = 0; q < (size_t)m * m; q++) S[q] = rho * src[4 * (size_t)m * m + q];
      CUPID_TRY(fn(b, ctx, be, se, m, S, A));
    }
  }
cleanup:
  cupid_free(&E);
  cupid_free(&S);
  return st;
}

static cupid_status add_consistent(const beam_t *b, void *ctx, cupid_int be, cupid_int se, int m,
                                   const double *S, const double *A) {
  cupid_csr K = ctx;
  cupid_int boff = b->dof_offset / 3, j0 = be * (b->p - 1), M = b->M;
  int p = b->p;
  for (int s = 0; s < m; s++)
    for (int j = 0; j < p; j++) {
      cupid_int row = boff + (j0 + j) * M + cuf_tau(b, se, s);
      for (int t = 0; t < m; t++)
        for (int i = 0; i < p; i++) {
          double v = S[s * m + t] * A[j * p + i];
          if (v == 0.0) continue;
          double *blk = cupid_csr_find(K, row, boff + (j0 + i) * M + cuf_tau(b, se, t));
          CUPID_CHECK(blk, CUPID_ERR_ARGUMENT, "the matrix pattern lacks blocks of the CUF mass");
          for (int k = 0; k < 3; k++) blk[4 * k] += v;
        }
    }
  return CUPID_SUCCESS;
}

cupid_status cupid_cuf_mass_add(const cupid_cuf_beam b, cupid_csr M) {
  CUPID_CHECK(b && M && M->bs == 3, CUPID_ERR_ARGUMENT, "cupid_cuf_mass_add: need a bs = 3 matrix");
  cupid_int boff = b->dof_offset / 3;
  CUPID_CHECK(M->nrows >= boff + b->n_bnodes * b->M, CUPID_ERR_ARGUMENT,
              "matrix too small for the beam at DOF offset %lld", (long long)b->dof_offset);
  return for_each_pair(b, add_consistent, M);
}

cupid_status cupid_cuf_mass_assemble(const cupid_cuf_beam b, cupid_csr *M) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int *rowptr = NULL, *col = NULL, n = b->n_bnodes * b->M;
  CUPID_CHECK(M, CUPID_ERR_ARGUMENT, "cupid_cuf_mass_assemble: NULL argument");
  *M = NULL;
  cupid_int saved = b->dof_offset;
  CUPID_TRY(cupid_cuf_pattern(b, &rowptr, &col));
  CUPID_TRY(cupid_csr_create(n, n, 3, rowptr, col, M));
  b->dof_offset = 0; /* local numbering, like cupid_cuf_assemble */
  st = for_each_pair(b, add_consistent, *M);
  b->dof_offset = saved;
  if (st != CUPID_SUCCESS) cupid_csr_destroy(M);
cleanup:
  cupid_free(&rowptr);
  cupid_free(&col);
  return st;
}

/* HRZ lumping of one pair: the diagonal of its consistent matrix, scaled so that the
 * translational DOFs of one direction carry the pair's mass. "Translational" are the functions
 * that sum to the rigid translation: every LE node (partition of unity), the constant TE term. */
static cupid_status add_lumped(const beam_t *b, void *ctx, cupid_int be, cupid_int se, int m,
                               const double *S, const double *A) {
  double *d = ctx;
  int p = b->p;
  double mass = 0.0, trans = 0.0;
  for (int j = 0; j < p; j++)
    for (int i = 0; i < p; i++) mass += A[j * p + i];
  double srow = 0.0;
  if (b->expansion == CUPID_EXPANSION_LE) {
    for (int q = 0; q < m * m; q++) srow += S[q];
    for (int s = 0; s < m; s++)
      for (int j = 0; j < p; j++) trans += S[s * m + s] * A[j * p + j];
  } else {
    srow = S[0]; /* F_0 = 1: rho times the area of the cell */
    for (int j = 0; j < p; j++) trans += S[0] * A[j * p + j];
  }
  mass *= srow;
  if (trans <= 0.0) return CUPID_SUCCESS; /* zero density */
  double scale = mass / trans;
  cupid_int j0 = be * (p - 1), M = b->M;
  for (int s = 0; s < m; s++)
    for (int j = 0; j < p; j++) {
      cupid_int dof = b->dof_offset + 3 * ((j0 + j) * M + cuf_tau(b, se, s));
      for (int k = 0; k < 3; k++) d[dof + k] += scale * S[s * m + s] * A[j * p + j];
    }
  return CUPID_SUCCESS;
}

cupid_status cupid_cuf_mass_lumped(const cupid_cuf_beam b, double *d) {
  CUPID_CHECK(b && d, CUPID_ERR_ARGUMENT, "cupid_cuf_mass_lumped: NULL argument");
  return for_each_pair(b, add_lumped, d);
}

/* Pair mass: rho times the pair volume (LE: the functions sum to one; TE: F_0 = 1). */
static cupid_status add_total(const beam_t *b, void *ctx, cupid_int be, cupid_int se, int m,
                              const double *S, const double *A) {
  double *total = ctx, axial = 0.0, sec = 0.0;
  for (int q = 0; q < b->p * b->p; q++) axial += A[q];
  if (b->expansion == CUPID_EXPANSION_LE)
    for (int q = 0; q < m * m; q++) sec += S[q];
  else
    sec = S[0];
  *total += axial * sec;
  return CUPID_SUCCESS;
}

cupid_status cupid_cuf_mass_total(const cupid_cuf_beam b, double *total) {
  CUPID_CHECK(b && total, CUPID_ERR_ARGUMENT, "cupid_cuf_mass_total: NULL argument");
  *total = 0.0;
  return for_each_pair(b, add_total, total);
}
