/* The fictitious-node K of crack growth solved by block elimination (issue 34; docs/coupling.md,
 * "Growth with fictitious nodes"): a symmetric factor that broken bonds downdate, as Arlequin's.
 *
 * Paper 000's Eq. 38 is not symmetric, but only in its FE rows (the fits of Eqs. 33-36 and the
 * balance's -W C^T, whose W is zero on the PD rows): the block of the real PD DOFs is the grid's
 * own PD operator with the fictitious nodes held, symmetric and positive definite. With the
 * free DOFs split into real PD (p) and FE (f),
 *
 *   K' = [A  B ]   A = K_pp (CHOLMOD, downdated as bonds break),  B = K_pf,
 *        [C' D']   C' = K_fp - W_f C_p^T,  D' = K_ff - W_f C_f^T  (balance.c; W = 0 unbalanced),
 *
 * and a solve is x_f = S^-1 (r_f - C' A^-1 r_p), x_p = A^-1 (r_p - B x_f), with the Schur
 * complement S = D' - C' A^-1 B on the FE DOFs. C' has few rows (the interface FE nodes' fits
 * and W's rows, nic: 162 on the SENB) and B few columns (the fictitious elements' FE DOFs, nib:
 * 648): G = A^-1 C'^T (nic columns) is kept, so that C' A^-1 r_p = G^T r_p and a solve costs
 * one solve with the Cholesky factor (which holds half of an LU's entries), and
 *
 *   S = D' - U E V^T,   E = (C' A^-1 B)(ic, ib)  (nic x nib, dense),
 *   S^-1 = D'^-1 + Y H^-1 E V^T D'^-1,   Y = D'^-1 U,   H = I - E Y(ib, :)  (nic x nic)
 *
 * (Sherman-Morrison-Woodbury; U and V pick the rows ic and ib): D' is the beam's sparse block,
 * factorised once (UMFPACK), and only E and the small H change as bonds break. A broken bond
 * outside the coupling zone changes A alone, by -v v^T (growth_downdate.c; docs/theory.md): the
 * factor is downdated (cholmod_updown), and with Z = A^-1 V on the downdated A,
 *
 *   A_old^-1 = A^-1 - Z N Z^T, N = (I + V^T Z)^-1,  so  G += Z N (C' Z)^T,
 *   E += (C' Z) N (B^T Z)^T,
 *
 * rank-k changes, after which H is updated and its LU made again (nic^3 / 3). A round costs its
 * downdate (as Arlequin's) and one solve with k right-hand sides; nothing grows with the bonds
 * broken, where Sherman-Morrison-Woodbury on an LU of the whole K (growth_smw.c) kept a column
 * of n per bond and solved each with the LU. Every loop has a fixed order (no threaded
 * reductions), so the same bonds break for any thread count. */
#include <math.h>
#include <string.h>

#include "problem_internal.h"

#define BLOCK_CHUNK 64       /* columns of G = A^-1 C'^T solved at once (bounds the work space) */
#define BLOCK_SYMMETRY 1e-12 /* |x^T A y - y^T A x| against sum |x_i A_ij y_j|: round-off of
                                the assembly, where a non-symmetric block differs at O(1) */

struct cupid_growth_block_private {
  cupid_int n, fe0;          /* all DOFs; the first FE DOF (3 n_pd) */
  cupid_dirichlet bcA;       /* FE DOFs and fixed PD DOFs fixed: A's free DOFs */
  cupid_direct_factor A;     /* CHOLMOD of A */
  cupid_int na, *pd;         /* A's size, the global DOF of each of its unknowns */
  cupid_int ns, *fe;         /* free FE DOFs (S's size), the global DOF of each */
  cupid_int *fe_index;       /* per FE DOF (global - fe0): its index in S, or -1 (fixed) */
  /* B by rows (na + 1 pointers; columns S indices) and by columns (ns + 1; rows A indices) */
  cupid_int *b_ptr, *b_col, *bt_ptr, *bt_row;
  double *b_val, *bt_val;
  /* K_fp by rows (ns + 1 pointers; columns A indices) */
  cupid_int *c_ptr, *c_col;
  double *c_val;
  /* the balance: k columns of W_f (ns each), C_p (na each), C_f (ns each) */
  int k;
  double *Wf, *Cp, *Cf;
  /* the interface: S rows that read a PD column (K_fp or W_f), S columns that a PD row reads */
  cupid_int nic, nib, *ic, *ib;
  double *Gc;                /* nic columns of na: A^-1 C'^T (C' row ic[a] as a PD vector) */
  double *E;                 /* nic x nib, row-major: C' A^-1 B on them = Gc^T B */
  cupid_csr D;               /* D', scalar, ns x ns */
  cupid_direct_factor Df;    /* its UMFPACK LU */
  double *Y;                 /* nic columns of ns: D'^-1 on the unit vectors of ic */
  double *Yb;                /* nib x nic, row-major: Y's rows ib */
  double *H, *Hlu;           /* nic x nic, row-major: I - E Yb, and its LU */
  int *Hpiv;
  double *ya, *ta, *xa, *ts, *xs; /* work: na, na, na, ns, ns */
  double *hs;                /* work: nic */
  double pivot_ratio_a, pivot_ratio_s; /* A's (L_kk^2) and D''s (UMFPACK's rcond) */
};

/* Every scalar entry (d, c, value) of row d of K. */
#define FOR_ROW(K, d, c, v, ...)                                                                  \
  do {                                                                                             \
    const int bs_ = (K)->bs;                                                                       \
    const cupid_int br_ = (d) / bs_;                                                               \
    const int a_ = (int)((d) % bs_);                                                               \
    for (cupid_int q_ = (K)->rowptr[br_]; q_ < (K)->rowptr[br_ + 1]; q_++)                         \
      for (int b_ = 0; b_ < bs_; b_++) {                                                           \
        const cupid_int c = (K)->col[q_] * bs_ + b_;                                               \
        const double v = (K)->val[(q_ * bs_ + a_) * bs_ + b_];                                     \
        (void)v;                                                                                   \
        __VA_ARGS__;                                                                               \
      }                                                                                            \
  } while (0)

void cupid_growth_block_destroy(cupid_growth_block *M) {
  if (!M || !*M) return;
  cupid_growth_block m = *M;
  cupid_direct_factor_destroy(&m->A);
  cupid_direct_factor_destroy(&m->Df);
  cupid_dirichlet_destroy(&m->bcA);
  cupid_csr_destroy(&m->D);
  cupid_free(&m->pd), cupid_free(&m->fe), cupid_free(&m->fe_index);
  cupid_free(&m->b_ptr), cupid_free(&m->b_col), cupid_free(&m->b_val);
  cupid_free(&m->bt_ptr), cupid_free(&m->bt_row), cupid_free(&m->bt_val);
  cupid_free(&m->c_ptr), cupid_free(&m->c_col), cupid_free(&m->c_val);
  cupid_free(&m->Wf), cupid_free(&m->Cp), cupid_free(&m->Cf);
  cupid_free(&m->ic), cupid_free(&m->ib);
  cupid_free(&m->Gc), cupid_free(&m->E), cupid_free(&m->Y), cupid_free(&m->Yb);
  cupid_free(&m->H), cupid_free(&m->Hlu), cupid_free(&m->Hpiv), cupid_free(&m->hs);
  cupid_free(&m->ya), cupid_free(&m->ta), cupid_free(&m->xa), cupid_free(&m->ts), cupid_free(&m->xs);
  cupid_free(M);
}

/* Is K_pp symmetric (the lower triangle is what CHOLMOD reads)? x^T K_pp y against y^T K_pp x
 * for two fixed vectors: a non-symmetric block shows up unless it is so by round-off. */
static cupid_status pd_block_symmetric(const cupid_csr_t *K, cupid_int fe0, int *sym) {
  double *x = NULL, *y = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_malloc((size_t)fe0 + 1, sizeof *x, "symmetry check", &x));
  CUPID_TRY(cupid_malloc((size_t)fe0 + 1, sizeof *y, "symmetry check", &y));
  cupid_pseudo_random(x, fe0, 0x9E3779B97F4A7C15ull);
  cupid_pseudo_random(y, fe0, 0xD1B54A32D192ED03ull);
  double xay = 0.0, yax = 0.0, scale = 0.0;
  for (cupid_int d = 0; d < fe0; d++)
    FOR_ROW(K, d, c, v, if (c < fe0) {
      xay += x[d] * v * y[c];
      yax += y[d] * v * x[c];
      scale += fabs(x[d] * v * y[c]);
    });
  *sym = fabs(xay - yax) <= BLOCK_SYMMETRY * scale;
cleanup:
  cupid_free(&x);
  cupid_free(&y);
  return st;
}

/* The numbering: A's unknowns (free PD DOFs, in increasing order, as bcA numbers them) and S's
 * (free FE DOFs). */
static cupid_status number(cupid_growth_block m, const cupid_dirichlet_t *bc) {
  const cupid_int n = m->n, fe0 = m->fe0;
  CUPID_CALL(cupid_dirichlet_create(n, &m->bcA));
  for (cupid_int d = 0; d < n; d++) m->bcA->fixed[d] = bc->fixed[d] || d >= fe0;
  CUPID_CALL(cupid_dirichlet_finalize(m->bcA));
  m->na = m->bcA->n_free;
  CUPID_CALL(cupid_malloc((size_t)m->na + 1, sizeof *m->pd, "PD unknowns", &m->pd));
  CUPID_CALL(cupid_malloc((size_t)(n - fe0) + 1, sizeof *m->fe_index, "FE unknowns", &m->fe_index));
  m->ns = 0;
  for (cupid_int d = 0, a = 0; d < n; d++) {
    if (d < fe0) {
      if (!bc->fixed[d]) m->pd[a++] = d;
    } else
      m->fe_index[d - fe0] = bc->fixed[d] ? -1 : m->ns++;
  }
  CUPID_CALL(cupid_malloc((size_t)m->ns + 1, sizeof *m->fe, "FE unknowns", &m->fe));
  for (cupid_int d = fe0; d < n; d++)
    if (m->fe_index[d - fe0] >= 0) m->fe[m->fe_index[d - fe0]] = d;
  return CUPID_SUCCESS;
}

/* B = K_pf by rows and by columns, K_fp by rows, in A's and S's numbering. */
static cupid_status split_blocks(cupid_growth_block m, const cupid_csr_t *K) {
  const cupid_int fe0 = m->fe0, *ai = m->bcA->free_index, *si = m->fe_index;
  CUPID_CALL(cupid_calloc((size_t)m->na + 1, sizeof *m->b_ptr, "coupling block", &m->b_ptr));
  CUPID_CALL(cupid_calloc((size_t)m->ns + 1, sizeof *m->bt_ptr, "coupling block", &m->bt_ptr));
  CUPID_CALL(cupid_calloc((size_t)m->ns + 1, sizeof *m->c_ptr, "coupling block", &m->c_ptr));
  for (cupid_int a = 0; a < m->na; a++)
    FOR_ROW(K, m->pd[a], c, v, if (c >= fe0 && si[c - fe0] >= 0 && v != 0.0) {
      m->b_ptr[a + 1]++;
      m->bt_ptr[si[c - fe0] + 1]++;
    });
  for (cupid_int s = 0; s < m->ns; s++)
    FOR_ROW(K, m->fe[s], c, v, if (c < fe0 && ai[c] >= 0 && v != 0.0) m->c_ptr[s + 1]++);
  for (cupid_int a = 0; a < m->na; a++) m->b_ptr[a + 1] += m->b_ptr[a];
  for (cupid_int s = 0; s < m->ns; s++) m->bt_ptr[s + 1] += m->bt_ptr[s], m->c_ptr[s + 1] += m->c_ptr[s];
  const size_t nb = (size_t)m->b_ptr[m->na], nc = (size_t)m->c_ptr[m->ns];
  CUPID_CALL(cupid_malloc(nb + 1, sizeof *m->b_col, "coupling block", &m->b_col));
  CUPID_CALL(cupid_malloc(nb + 1, sizeof *m->b_val, "coupling block", &m->b_val));
  CUPID_CALL(cupid_malloc(nb + 1, sizeof *m->bt_row, "coupling block", &m->bt_row));
  CUPID_CALL(cupid_malloc(nb + 1, sizeof *m->bt_val, "coupling block", &m->bt_val));
  CUPID_CALL(cupid_malloc(nc + 1, sizeof *m->c_col, "coupling block", &m->c_col));
  CUPID_CALL(cupid_malloc(nc + 1, sizeof *m->c_val, "coupling block", &m->c_val));
  cupid_int *fill = NULL;
  CUPID_CALL(cupid_malloc((size_t)m->ns + 1, sizeof *fill, "coupling block", &fill));
  memcpy(fill, m->bt_ptr, (size_t)m->ns * sizeof *fill);
  for (cupid_int a = 0; a < m->na; a++) { /* rows in order: each column's rows ascend */
    cupid_int t = m->b_ptr[a];
    FOR_ROW(K, m->pd[a], c, v, if (c >= fe0 && si[c - fe0] >= 0 && v != 0.0) {
      const cupid_int s = si[c - fe0];
      m->b_col[t] = s, m->b_val[t++] = v;
      m->bt_row[fill[s]] = a, m->bt_val[fill[s]++] = v;
    });
  }
  cupid_free(&fill);
  for (cupid_int s = 0; s < m->ns; s++) {
    cupid_int t = m->c_ptr[s];
    FOR_ROW(K, m->fe[s], c, v, if (c < fe0 && ai[c] >= 0 && v != 0.0) {
      m->c_col[t] = ai[c], m->c_val[t++] = v;
    });
  }
  return CUPID_SUCCESS;
}

/* The balance's columns in A's and S's numbering; the interface rows and columns. */
static cupid_status interface(cupid_growth_block m, const cupid_coupling_balance Bal) {
  const double *C = NULL, *W = NULL;
  cupid_coupling_balance_terms(Bal, &m->k, &C, &W);
  const size_t k = (size_t)m->k, na = (size_t)m->na, ns = (size_t)m->ns, n = (size_t)m->n;
  CUPID_CALL(cupid_malloc(k * ns + 1, sizeof *m->Wf, "balance terms", &m->Wf));
  CUPID_CALL(cupid_malloc(k * na + 1, sizeof *m->Cp, "balance terms", &m->Cp));
  CUPID_CALL(cupid_malloc(k * ns + 1, sizeof *m->Cf, "balance terms", &m->Cf));
  for (size_t c = 0; c < k; c++) {
    for (size_t a = 0; a < na; a++) m->Cp[c * na + a] = C[c * n + (size_t)m->pd[a]];
    for (size_t s = 0; s < ns; s++) {
      m->Cf[c * ns + s] = C[c * n + (size_t)m->fe[s]];
      m->Wf[c * ns + s] = W[c * n + (size_t)m->fe[s]];
    }
  }
  CUPID_CALL(cupid_malloc(ns + 1, sizeof *m->ic, "interface rows", &m->ic));
  CUPID_CALL(cupid_malloc(ns + 1, sizeof *m->ib, "interface columns", &m->ib));
  m->nic = m->nib = 0;
  for (cupid_int s = 0; s < m->ns; s++) {
    int w = 0;
    for (size_t c = 0; c < k && !w; c++) w = m->Wf[c * ns + (size_t)s] != 0.0;
    if (w || m->c_ptr[s + 1] > m->c_ptr[s]) m->ic[m->nic++] = s;
    if (m->bt_ptr[s + 1] > m->bt_ptr[s]) m->ib[m->nib++] = s;
  }
  return CUPID_SUCCESS;
}

/* out[a] (a over the interface rows) = (C' y)[ic[a]] = (K_fp y - W_f (C_p^T y))[ic[a]]. */
static void interface_rows(const cupid_growth_block m, const double *y, double *out,
                           double *cy /* k */) {
  for (int c = 0; c < m->k; c++) cy[c] = cupid_dot(m->na, m->Cp + (size_t)c * (size_t)m->na, y);
  for (cupid_int a = 0; a < m->nic; a++) {
    const cupid_int s = m->ic[a];
    double v = 0.0;
    for (cupid_int t = m->c_ptr[s]; t < m->c_ptr[s + 1]; t++) v += m->c_val[t] * y[m->c_col[t]];
    for (int c = 0; c < m->k; c++) v -= m->Wf[(size_t)c * (size_t)m->ns + (size_t)s] * cy[c];
    out[a] = v;
  }
}

/* Gc = A^-1 C'^T (BLOCK_CHUNK rows of C' at a time: the interface rows are fewer than B's
 * columns, 162 against 648 on the SENB) and E = Gc^T B. */
static cupid_status schur_block(cupid_growth_block m) {
  const size_t na = (size_t)m->na, ns = (size_t)m->ns;
  const cupid_int nib = m->nib, nic = m->nic;
  double *R = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_malloc((size_t)nic * na + 1, sizeof *m->Gc, "interface solves", &m->Gc));
  CUPID_TRY(cupid_malloc((size_t)nic * (size_t)nib + 1, sizeof *m->E, "interface Schur block", &m->E));
  CUPID_TRY(cupid_malloc(na * BLOCK_CHUNK + 1, sizeof *R, "interface solves", &R));
  for (cupid_int a0 = 0; a0 < nic; a0 += BLOCK_CHUNK) {
    const cupid_int w = nic - a0 < BLOCK_CHUNK ? nic - a0 : BLOCK_CHUNK;
    for (cupid_int j = 0; j < w; j++) { /* row ic[a] of C' = K_fp - W_f C_p^T */
      const cupid_int s = m->ic[a0 + j];
      double *rj = R + (size_t)j * na;
      for (size_t q = 0; q < na; q++) {
        double v = 0.0;
        for (int c = 0; c < m->k; c++) v -= m->Wf[(size_t)c * ns + (size_t)s] * m->Cp[(size_t)c * na + q];
        rj[q] = v;
      }
      for (cupid_int t = m->c_ptr[s]; t < m->c_ptr[s + 1]; t++) rj[m->c_col[t]] += m->c_val[t];
    }
    CUPID_TRY(cupid_direct_factor_solve_free_many(m->A, w, R, m->Gc + (size_t)a0 * na));
  }
  for (cupid_int a = 0; a < nic; a++) {
    const double *g = m->Gc + (size_t)a * na;
    for (cupid_int b = 0; b < nib; b++) {
      const cupid_int s = m->ib[b];
      double v = 0.0;
      for (cupid_int t = m->bt_ptr[s]; t < m->bt_ptr[s + 1]; t++) v += g[m->bt_row[t]] * m->bt_val[t];
      m->E[(size_t)a * (size_t)nib + (size_t)b] = v;
    }
  }
cleanup:
  cupid_free(&R);
  return st;
}

/* D' = K_ff - W_f C_f^T on the free FE DOFs. */
static cupid_status d_matrix(cupid_growth_block m, const cupid_csr_t *K) {
  const cupid_int fe0 = m->fe0, ns = m->ns;
  const size_t nsz = (size_t)ns;
  cupid_int *ti = NULL, *tj = NULL, *wrows = NULL, *crows = NULL;
  double *tv = NULL;
  cupid_status st = CUPID_SUCCESS;
  /* the balance's rows (W_f != 0) and columns (C_f != 0) */
  cupid_int nw = 0, ncf = 0;
  CUPID_TRY(cupid_malloc(nsz + 1, sizeof *wrows, "balance rows", &wrows));
  CUPID_TRY(cupid_malloc(nsz + 1, sizeof *crows, "balance columns", &crows));
  for (cupid_int s = 0; s < ns; s++) {
    int w = 0, c = 0;
    for (int q = 0; q < m->k; q++) {
      w |= m->Wf[(size_t)q * nsz + (size_t)s] != 0.0;
      c |= m->Cf[(size_t)q * nsz + (size_t)s] != 0.0;
    }
    if (w) wrows[nw++] = s;
    if (c) crows[ncf++] = s;
  }
  size_t nnz = (size_t)nw * (size_t)ncf;
  for (cupid_int s = 0; s < ns; s++) FOR_ROW(K, m->fe[s], c, v, if (c >= fe0 && m->fe_index[c - fe0] >= 0) nnz++);
  CUPID_TRY(cupid_malloc(nnz + 1, sizeof *ti, "FE block", &ti));
  CUPID_TRY(cupid_malloc(nnz + 1, sizeof *tj, "FE block", &tj));
  CUPID_TRY(cupid_malloc(nnz + 1, sizeof *tv, "FE block", &tv));
  size_t t = 0;
  for (cupid_int s = 0; s < ns; s++)
    FOR_ROW(K, m->fe[s], c, v, if (c >= fe0 && m->fe_index[c - fe0] >= 0) {
      ti[t] = s, tj[t] = m->fe_index[c - fe0], tv[t++] = v;
    });
  for (cupid_int a = 0; a < nw; a++)
    for (cupid_int b = 0; b < ncf; b++) {
      double v = 0.0;
      for (int q = 0; q < m->k; q++)
        v += m->Wf[(size_t)q * nsz + (size_t)wrows[a]] * m->Cf[(size_t)q * nsz + (size_t)crows[b]];
      ti[t] = wrows[a], tj[t] = crows[b], tv[t++] = -v;
    }
  CUPID_TRY(cupid_csr_from_triplets(ns, ns, (cupid_int)t, ti, tj, tv, &m->D));
cleanup:
  cupid_free(&ti);
  cupid_free(&tj);
  cupid_free(&tv);
  cupid_free(&wrows);
  cupid_free(&crows);
  return st;
}

/* H = I - E Y(ib, :) from the current E, and its LU; 0 when H is singular (then so is K:
 * det K = det A det D' det H). */
static int factorise_h(cupid_growth_block m) {
  const cupid_int nic = m->nic, nib = m->nib;
  const size_t h2 = (size_t)nic * (size_t)nic;
  memcpy(m->Hlu, m->H, h2 * sizeof *m->H);
  return cupid_dense_lu((int)nic, m->Hlu, m->Hpiv, 1e-13 * (double)(nib > 1 ? nib : 1) *
                                                        cupid_dense_max_abs((int)nic, m->H));
}

/* D' factorised, Y = D'^-1 U, H = I - E Y(ib, :). *ok = 0 when D' is singular (the caller
 * factorises K whole) or H is (a singular K: failed_dof named). */
static cupid_status interface_inverse(cupid_growth_block m, cupid_solve_info *info, int *ok) {
  const cupid_int ns = m->ns, nic = m->nic, nib = m->nib;
  cupid_solve_info di;
  double *e = NULL;
  cupid_status st = cupid_direct_factor_create_kind(m->D, CUPID_MATRIX_GENERAL, NULL, &m->Df, &di);
  *ok = st == CUPID_SUCCESS;
  if (st == CUPID_ERR_NUMERIC) {
    cupid_error_clear();
    return CUPID_SUCCESS;
  }
  CUPID_CALL(st);
  info->nnz_factor += di.nnz_factor;
  info->flops_factor += di.flops_factor + 4.0 * di.nnz_factor * (double)nic;
  info->memory_factor += di.memory_factor;
  m->pivot_ratio_s = di.pivot_ratio;
  CUPID_TRY(cupid_malloc((size_t)ns * (size_t)nic + 1, sizeof *m->Y, "interface solves", &m->Y));
  CUPID_TRY(cupid_malloc((size_t)nib * (size_t)nic + 1, sizeof *m->Yb, "interface solves", &m->Yb));
  CUPID_TRY(cupid_calloc((size_t)ns + 1, sizeof *e, "interface solves", &e));
  for (cupid_int a = 0; a < nic; a++) {
    e[m->ic[a]] = 1.0;
    CUPID_TRY(cupid_direct_factor_solve_free(m->Df, e, m->Y + (size_t)a * (size_t)ns));
    e[m->ic[a]] = 0.0;
    for (cupid_int b = 0; b < nib; b++)
      m->Yb[(size_t)b * (size_t)nic + (size_t)a] = m->Y[(size_t)a * (size_t)ns + (size_t)m->ib[b]];
  }
  const size_t h2 = (size_t)nic * (size_t)nic;
  CUPID_TRY(cupid_malloc(h2 + 1, sizeof *m->H, "interface capacitance", &m->H));
  CUPID_TRY(cupid_malloc(h2 + 1, sizeof *m->Hlu, "interface capacitance", &m->Hlu));
  CUPID_TRY(cupid_malloc((size_t)nic + 1, sizeof *m->Hpiv, "interface capacitance", &m->Hpiv));
  CUPID_TRY(cupid_malloc((size_t)nic + 1, sizeof *m->hs, "interface capacitance", &m->hs));
#pragma omp parallel for schedule(static) if ((double)nic * (double)nic * (double)nib > 1e6)
  for (cupid_int a = 0; a < nic; a++)
    for (cupid_int c = 0; c < nic; c++) {
      double v = a == c ? 1.0 : 0.0;
      for (cupid_int b = 0; b < nib; b++)
        v -= m->E[(size_t)a * (size_t)nib + (size_t)b] * m->Yb[(size_t)b * (size_t)nic + (size_t)c];
      m->H[(size_t)a * (size_t)nic + (size_t)c] = v;
    }
  if (!factorise_h(m)) { /* K singular: the weakest pivot of A names the node */
    *ok = 0;
    CUPID_TRY(cupid_direct_factor_weakest_dof(m->A, &info->failed_dof));
    st = CUPID_ERROR(CUPID_ERR_NUMERIC, "the matrix is singular (the interface's Schur complement "
                     "of the block elimination; weakest PD pivot at DOF %lld): the model may be "
                     "unconstrained", (long long)info->failed_dof);
  }
cleanup:
  cupid_free(&e);
  return st;
}

/* x = S^-1 g in S's numbering (g is kept): D'^-1 g, then + Y H^-1 E (D'^-1 g)(ib). */
static cupid_status schur_solve(cupid_growth_block m, const double *g, double *x) {
  const cupid_int nic = m->nic, nib = m->nib;
  CUPID_CALL(cupid_direct_factor_solve_free(m->Df, g, x));
  for (cupid_int a = 0; a < nic; a++) {
    const double *ea = m->E + (size_t)a * (size_t)nib;
    double v = 0.0;
    for (cupid_int b = 0; b < nib; b++) v += ea[b] * x[m->ib[b]];
    m->hs[a] = v;
  }
  cupid_dense_lu_solve((int)nic, m->Hlu, m->Hpiv, m->hs);
  for (cupid_int a = 0; a < nic; a++) {
    const double *ya = m->Y + (size_t)a * (size_t)m->ns, h = m->hs[a];
    for (cupid_int s = 0; s < m->ns; s++) x[s] += ya[s] * h;
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_growth_block_create(const cupid_csr_t *K, cupid_int fe0, const cupid_dirichlet_t *bc,
                                       const cupid_coupling_balance Bal, cupid_growth_block *out,
                                       cupid_solve_info *info) {
  cupid_growth_block m = NULL;
  cupid_status st = CUPID_SUCCESS;
  const double t0 = cupid_wtime();
  *out = NULL;
  memset(info, 0, sizeof *info);
  info->failed_dof = -1;
  info->method = "cholmod + schur";
  const cupid_int n = K->nrows * K->bs;
  CUPID_CHECK(bc && bc->n == n, CUPID_ERR_ARGUMENT, "block factor: conditions on %lld DOFs for %lld",
              (long long)(bc ? bc->n : 0), (long long)n);
  if (fe0 <= 0 || fe0 >= n) return CUPID_SUCCESS; /* not two blocks */
  int sym = 0;
  CUPID_CALL(pd_block_symmetric(K, fe0, &sym));
  if (!sym) return CUPID_SUCCESS; /* the caller factorises the whole K */
  CUPID_CALL(cupid_calloc(1, sizeof *m, "block factor", &m));
  m->n = n, m->fe0 = fe0;
  CUPID_TRY(number(m, bc));
  cupid_solve_info ai;
  st = cupid_direct_factor_create(K, m->bcA, &m->A, &ai);
  info->failed_dof = ai.failed_dof; /* global: the PD node a breaking left loose */
  CUPID_TRY(st);
  info->nnz_factor = ai.nnz_factor, info->flops_factor = ai.flops_factor;
  info->memory_factor = ai.memory_factor;
  m->pivot_ratio_a = ai.pivot_ratio;
  CUPID_TRY(split_blocks(m, K));
  CUPID_TRY(interface(m, Bal));
  CUPID_TRY(schur_block(m));
  CUPID_TRY(d_matrix(m, K));
  int ok = 0;
  CUPID_TRY(interface_inverse(m, info, &ok));
  if (!ok) { /* D' singular: not this elimination (K whole instead) */
    cupid_growth_block_destroy(&m);
    return CUPID_SUCCESS;
  }
  info->flops_factor += 4.0 * ai.nnz_factor * (double)m->nic; /* G's solves */
  info->pivot_ratio = fmin(m->pivot_ratio_a, m->pivot_ratio_s);
  info->n = m->na + m->ns;
  info->nnz_matrix = cupid_csr_nnz(K);
  CUPID_TRY(cupid_malloc((size_t)m->na + 1, sizeof *m->ya, "block work", &m->ya));
  CUPID_TRY(cupid_malloc((size_t)m->na + 1, sizeof *m->ta, "block work", &m->ta));
  CUPID_TRY(cupid_malloc((size_t)m->na + 1, sizeof *m->xa, "block work", &m->xa));
  CUPID_TRY(cupid_malloc((size_t)m->ns + 1, sizeof *m->ts, "block work", &m->ts));
  CUPID_TRY(cupid_malloc((size_t)m->ns + 1, sizeof *m->xs, "block work", &m->xs));
  info->time_factor = cupid_wtime() - t0;
  *out = m;
  m = NULL;
cleanup:
  cupid_growth_block_destroy(&m);
  return st;
}

cupid_int cupid_growth_block_interface(const cupid_growth_block M, cupid_int *nic, cupid_int *nib) {
  *nic = M->nic, *nib = M->nib;
  return M->ns;
}

cupid_status cupid_growth_block_solve(cupid_growth_block m, const double *r, double *z) {
  const cupid_int na = m->na, ns = m->ns, nic = m->nic;
  for (cupid_int a = 0; a < na; a++) m->ta[a] = r[m->pd[a]];
  /* x_f = S^-1 (r_f - C' A^-1 r_p), C' A^-1 r_p = Gc^T r_p on the interface rows */
  for (cupid_int s = 0; s < ns; s++) m->ts[s] = r[m->fe[s]];
  for (cupid_int a = 0; a < nic; a++) m->ts[m->ic[a]] -= cupid_dot(na, m->Gc + (size_t)a * (size_t)na, m->ta);
  CUPID_CALL(schur_solve(m, m->ts, m->xs));
  /* x_p = A^-1 (r_p - B x_f): the one solve with the Cholesky factor */
  for (cupid_int a = 0; a < na; a++) {
    double v = m->ta[a];
    for (cupid_int t = m->b_ptr[a]; t < m->b_ptr[a + 1]; t++) v -= m->b_val[t] * m->xs[m->b_col[t]];
    m->ya[a] = v;
  }
  CUPID_CALL(cupid_direct_factor_solve_free(m->A, m->ya, m->xa));
  for (cupid_int d = 0; d < m->n; d++) z[d] = 0.0; /* the factor's fixed DOFs */
  for (cupid_int a = 0; a < na; a++) z[m->pd[a]] = m->xa[a];
  for (cupid_int s = 0; s < ns; s++) z[m->fe[s]] = m->xs[s];
  return CUPID_SUCCESS;
}

cupid_status cupid_growth_block_downdate(cupid_growth_block m, const cupid_growth_downdate *dd, int *ok) {
  const cupid_int r = dd->r, nic = m->nic, nib = m->nib;
  const size_t na = (size_t)m->na;
  const cupid_int *ai = m->bcA->free_index;
  double *V = NULL, *Z = NULL, *N = NULL, *work = NULL, *P = NULL, *Q = NULL, *PN = NULL, *QY = NULL;
  double *col = NULL;
  double cy[CUPID_BALANCE_MODES * CUPID_BALANCE_GROUPS_MAX];
  cupid_status st = CUPID_SUCCESS;
  *ok = 1;
  if (r == 0) return CUPID_SUCCESS;
  st = cupid_direct_factor_downdate(m->A, r, dd->colptr, dd->rows, dd->vals);
  if (st == CUPID_ERR_NUMERIC) { /* A - V V^T is singular: a node lost its support */
    cupid_error_clear();
    *ok = 0;
    return CUPID_SUCCESS;
  }
  CUPID_CALL(st);
  /* Z = A^-1 V on the downdated A (V's rows on fixed DOFs dropped, as the downdate drops them) */
  CUPID_TRY(cupid_calloc(na * (size_t)r + 1, sizeof *V, "downdate columns", &V));
  CUPID_TRY(cupid_malloc(na * (size_t)r + 1, sizeof *Z, "downdate solves", &Z));
  for (cupid_int c = 0; c < r; c++)
    for (cupid_int q = dd->colptr[c]; q < dd->colptr[c + 1]; q++) {
      const cupid_int d = dd->rows[q];
      if (d >= 0 && d < m->fe0 && ai[d] >= 0) V[(size_t)c * na + (size_t)ai[d]] += dd->vals[q];
    }
  CUPID_TRY(cupid_direct_factor_solve_free_many(m->A, r, V, Z));
  /* N = (I + V^T Z)^-1 */
  CUPID_TRY(cupid_malloc((size_t)(r * r) + 1, sizeof *N, "downdate capacitance", &N));
  CUPID_TRY(cupid_malloc((size_t)(r * r) + 1, sizeof *work, "downdate capacitance", &work));
  for (cupid_int a = 0; a < r; a++)
    for (cupid_int c = 0; c < r; c++) {
      double v = a == c ? 1.0 : 0.0;
      for (cupid_int q = dd->colptr[a]; q < dd->colptr[a + 1]; q++) {
        const cupid_int d = dd->rows[q];
        if (d >= 0 && d < m->fe0 && ai[d] >= 0) v += dd->vals[q] * Z[(size_t)c * na + (size_t)ai[d]];
      }
      N[a * r + c] = v;
    }
  if (!cupid_dense_invert((int)r, N, work, 1e-12)) { /* SPD while A is: a failure means the
                                                        downdate went wrong */
    *ok = 0;
    goto cleanup;
  }
  /* P = C' Z (nic x r), Q = B^T Z (nib x r), then E += (P N) Q^T */
  CUPID_TRY(cupid_malloc((size_t)nic * (size_t)r + 1, sizeof *P, "interface change", &P));
  CUPID_TRY(cupid_malloc((size_t)nic * (size_t)r + 1, sizeof *PN, "interface change", &PN));
  CUPID_TRY(cupid_malloc((size_t)nib * (size_t)r + 1, sizeof *Q, "interface change", &Q));
  CUPID_TRY(cupid_malloc((size_t)nic + 1, sizeof *col, "interface change", &col));
  for (cupid_int c = 0; c < r; c++) {
    const double *z = Z + (size_t)c * na;
    interface_rows(m, z, col, cy);
    for (cupid_int a = 0; a < nic; a++) P[(size_t)a * (size_t)r + (size_t)c] = col[a];
    for (cupid_int b = 0; b < nib; b++) {
      const cupid_int s = m->ib[b];
      double v = 0.0;
      for (cupid_int t = m->bt_ptr[s]; t < m->bt_ptr[s + 1]; t++) v += m->bt_val[t] * z[m->bt_row[t]];
      Q[(size_t)b * (size_t)r + (size_t)c] = v;
    }
  }
  for (cupid_int a = 0; a < nic; a++)
    for (cupid_int c = 0; c < r; c++) {
      double v = 0.0;
      for (cupid_int e = 0; e < r; e++) v += P[(size_t)a * (size_t)r + (size_t)e] * N[e * r + c];
      PN[(size_t)a * (size_t)r + (size_t)c] = v;
    }
  /* Gc += Z (P N)^T (A_old^-1 = A^-1 - Z N Z^T, Z^T C'^T = P^T; N symmetric), by chunks of
   * rows, the columns of Z in order within each */
  {
    const cupid_int chunk = 1024, nchunks = (cupid_int)((na + chunk - 1) / chunk);
#pragma omp parallel for schedule(static) if ((double)na * (double)nic * (double)r > 1e6)
    for (cupid_int q = 0; q < nchunks; q++) {
      const size_t j0 = (size_t)q * (size_t)chunk, j1 = j0 + (size_t)chunk < na ? j0 + (size_t)chunk : na;
      for (cupid_int a = 0; a < nic; a++) {
        double *g = m->Gc + (size_t)a * na;
        for (cupid_int c = 0; c < r; c++) {
          const double f = PN[(size_t)a * (size_t)r + (size_t)c], *z = Z + (size_t)c * na;
          for (size_t j = j0; j < j1; j++) g[j] += z[j] * f;
        }
      }
    }
  }
  /* QY = Q^T Y(ib, :) (r x nic), for H -= (P N) QY, and E += (P N) Q^T */
  CUPID_TRY(cupid_calloc((size_t)r * (size_t)nic + 1, sizeof *QY, "interface change", &QY));
  for (cupid_int b = 0; b < nib; b++) {
    const double *yb = m->Yb + (size_t)b * (size_t)nic;
    for (cupid_int c = 0; c < r; c++) {
      const double q = Q[(size_t)b * (size_t)r + (size_t)c];
      double *qy = QY + (size_t)c * (size_t)nic;
      for (cupid_int a = 0; a < nic; a++) qy[a] += q * yb[a];
    }
  }
#pragma omp parallel for schedule(static) if ((double)nic * (double)(nib + nic) * (double)r > 1e6)
  for (cupid_int a = 0; a < nic; a++) {
    const double *pa = PN + (size_t)a * (size_t)r;
    for (cupid_int b = 0; b < nib; b++) {
      const double *qb = Q + (size_t)b * (size_t)r;
      double v = 0.0;
      for (cupid_int c = 0; c < r; c++) v += pa[c] * qb[c];
      m->E[(size_t)a * (size_t)nib + (size_t)b] += v;
    }
    double *ha = m->H + (size_t)a * (size_t)nic;
    for (cupid_int c = 0; c < r; c++) {
      const double *qy = QY + (size_t)c * (size_t)nic;
      for (cupid_int e = 0; e < nic; e++) ha[e] -= pa[c] * qy[e];
    }
  }
  *ok = factorise_h(m); /* 0: det K = det A det D' det H = 0, the caller factorises */
cleanup:
  cupid_free(&V);
  cupid_free(&Z);
  cupid_free(&N);
  cupid_free(&work);
  cupid_free(&P);
  cupid_free(&PN);
  cupid_free(&Q);
  cupid_free(&QY);
  cupid_free(&col);
  return st;
}

cupid_status cupid_growth_block_weakest_dof(const cupid_growth_block m, cupid_int *dof) {
  return cupid_direct_factor_weakest_dof(m->A, dof); /* a PD part that breaking left loose */
}
