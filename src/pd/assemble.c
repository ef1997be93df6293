/* Analytic assembly of K in 3x3-block CSR (not finite differences).
 *
 * K = K_pair + sum_p c_p g_p g_p^T, the Hessian of the energy in operator.c:
 *  - K_pair: each bond i-j is a spring along n_ij with stiffness w_ij
 *    (pd_pair_coefficient): blocks (i,i) += w n n^T, (i,j) -= w n n^T;
 *  - LPS dilatation term: c_p = V (3K_p - 5mu_p)/3 and g_p = d theta_p / dU, non-zero on
 *    p (g_p[p] = -3V/m_p sum_j omega beta x n_pj) and on its neighbours
 *    (g_p[j] = 3V/m_p omega beta x n_pj). It couples nodes up to 2 delta apart.
 * Row-wise gather, no atomics: row r collects block(r,k) += c_p g_p[r] (x) g_p[k] for
 * p in H_r + {r}, k in H_p + {p}. A per-thread marker (node -> row stamp) finds the row's
 * columns, which come out sorted by scanning the stencil sum (pd_stencil_sum) in
 * lexicographic order; a per-thread slot array then maps each column to its place. */
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "pd/pd_internal.h"

static inline void add_outer(double *blk, double w, const double *a, const double *b) {
  for (int r = 0; r < 3; r++)
    for (int c = 0; c < 3; c++) blk[3 * r + c] += w * a[r] * b[c];
}

/* Stamp every column of row r in mark[] (with value r). */
static void mark_row(const struct cupid_pd_operator_private *op, cupid_int r, cupid_int *mark) {
  mark[r] = r;
  for (cupid_int b = op->bptr[r]; b < op->bptr[r + 1]; b++) {
    const cupid_int p = op->bnbr[b];
    mark[p] = r;
    if (op->model == CUPID_PD_BOND) continue;
    for (cupid_int bb = op->bptr[p]; bb < op->bptr[p + 1]; bb++) mark[op->bnbr[bb]] = r;
  }
}

/* The sorted columns of row r: count them, and with col/slot given, store them. */
static cupid_int scan_row(const struct cupid_pd_operator_private *op, cupid_int r, int nd,
                          const int32_t *doff, const cupid_int *mark, cupid_int *col,
                          int32_t *slot) {
  const struct cupid_pd_grid_private *g = op->grid;
  const int32_t *q = g->ijk + 3 * r;
  cupid_int n = 0;
  for (int d = 0; d < nd; d++) {
    const cupid_int k = pd_grid_lookup(g, q[0] + doff[3 * d], q[1] + doff[3 * d + 1],
                                       q[2] + doff[3 * d + 2]);
    if (k < 0 || mark[k] != r) continue;
    if (col) {
      col[n] = k;
      slot[k] = (int32_t)n;
    }
    n++;
  }
  return n;
}

/* Values of row r into blocks val (9 per column, zeroed), columns located through slot. */
static void fill_row(const struct cupid_pd_operator_private *op, cupid_int r, const int32_t *slot,
                     double *val) {
  const pd_stencil *S = &op->st;
  double *diag = val + 9 * (size_t)slot[r];
  for (cupid_int b = op->bptr[r]; b < op->bptr[r + 1]; b++) {
    const cupid_int q = op->bnbr[b];
    const int s = op->bst[b];
    const double *n = S->nrm + 3 * s;
    const double w = pd_pair_coefficient(op, r, q, s);
    add_outer(diag, w, n, n);
    add_outer(val + 9 * (size_t)slot[q], -w, n, n);
  }
  if (op->model == CUPID_PD_BOND) return;
  /* p = r itself, then p over the neighbours of r. */
  for (cupid_int b = op->bptr[r] - 1; b < op->bptr[r + 1]; b++) {
    const cupid_int p = b < op->bptr[r] ? r : op->bnbr[b];
    const double Gp = 3.0 * op->V / op->m[p], cp = op->V * op->kappa[p] / 3.0;
    const double *dir = p == r ? op->gself + 3 * r : S->wxn + 3 * op->bst[b];
    double v[3]; /* c_p g_p[r] Gp: g_p[r] = -Gp gself_r, or -Gp wxn(r->p) */
    for (int c = 0; c < 3; c++) v[c] = -cp * Gp * dir[c] * Gp;
    double mgs[3]; /* g_p[p]/Gp = -gself_p */
    for (int c = 0; c < 3; c++) mgs[c] = -op->gself[3 * p + c];
    add_outer(val + 9 * (size_t)slot[p], 1.0, v, mgs);
    for (cupid_int bb = op->bptr[p]; bb < op->bptr[p + 1]; bb++)
      add_outer(val + 9 * (size_t)slot[op->bnbr[bb]], 1.0, v, S->wxn + 3 * op->bst[bb]);
  }
}

static int num_threads(void) {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

static int thread_id(void) {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

cupid_status cupid_pd_operator_assemble(const cupid_pd_operator op, cupid_csr *Kout) {
  cupid_status st = CUPID_SUCCESS;
  cupid_csr_t *K = NULL;
  cupid_int *mark = NULL;
  int32_t *slot = NULL, *doff = NULL;
  int nd = 0;
  CUPID_CHECK(op && Kout, CUPID_ERR_ARGUMENT, "assemble needs an operator and an output");
  *Kout = NULL;
  const cupid_int nn = op->nnodes;
  const int nt = nn > PD_OMP_MIN_NODES ? num_threads() : 1;
  CUPID_TRY(pd_stencil_sum(&op->st, op->model == CUPID_PD_BOND, &nd, &doff));
  CUPID_TRY(cupid_malloc((size_t)nt * (size_t)nn, sizeof *mark, "assembly markers", &mark));
  CUPID_TRY(cupid_malloc((size_t)nt * (size_t)nn, sizeof *slot, "assembly slots", &slot));
  for (size_t q = 0; q < (size_t)nt * (size_t)nn; q++) mark[q] = -1;
  CUPID_TRY(cupid_calloc(1, sizeof *K, "the PD stiffness matrix", &K));
  K->nrows = K->ncols = nn;
  K->bs = 3;
  CUPID_TRY(cupid_malloc((size_t)nn + 1, sizeof *K->rowptr, "PD matrix row pointers", &K->rowptr));
  K->rowptr[0] = 0;
#pragma omp parallel num_threads(nt)
  {
    cupid_int *mk = mark + (size_t)thread_id() * (size_t)nn;
#pragma omp for schedule(dynamic, 64)
    for (cupid_int r = 0; r < nn; r++) {
      mark_row(op, r, mk);
      K->rowptr[r + 1] = scan_row(op, r, nd, doff, mk, NULL, NULL);
    }
  }
  for (cupid_int r = 0; r < nn; r++) K->rowptr[r + 1] += K->rowptr[r];
  const cupid_int nblk = K->rowptr[nn];
  CUPID_TRY(cupid_malloc((size_t)nblk, sizeof *K->col, "PD matrix columns", &K->col));
  CUPID_TRY(cupid_malloc(9 * (size_t)nblk, sizeof *K->val, "PD matrix values", &K->val));
  for (size_t q = 0; q < (size_t)nt * (size_t)nn; q++) mark[q] = -1;
#pragma omp parallel num_threads(nt)
  {
    cupid_int *mk = mark + (size_t)thread_id() * (size_t)nn;
    int32_t *sl = slot + (size_t)thread_id() * (size_t)nn;
#pragma omp for schedule(dynamic, 64)
    for (cupid_int r = 0; r < nn; r++) {
      const cupid_int start = K->rowptr[r];
      double *val = K->val + 9 * (size_t)start;
      memset(val, 0, 9 * (size_t)(K->rowptr[r + 1] - start) * sizeof *val);
      mark_row(op, r, mk);
      scan_row(op, r, nd, doff, mk, K->col + start, sl);
      fill_row(op, r, sl, val);
    }
  }
  *Kout = K;
  K = NULL;
cleanup:
  if (K) {
    cupid_free(&K->rowptr);
    cupid_free(&K->col);
    cupid_free(&K->val);
    cupid_free(&K);
  }
  cupid_free(&mark);
  cupid_free(&slot);
  cupid_free(&doff);
  return st;
}

cupid_status cupid_pd_operator_diagonal(const cupid_pd_operator op, double *blocks) {
  CUPID_CHECK(op && blocks, CUPID_ERR_ARGUMENT, "diagonal needs an operator and an output");
  const pd_stencil *S = &op->st;
#pragma omp parallel for schedule(static) if (op->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int r = 0; r < op->nnodes; r++) {
    double *blk = blocks + 9 * (size_t)r;
    memset(blk, 0, 9 * sizeof *blk);
    for (cupid_int b = op->bptr[r]; b < op->bptr[r + 1]; b++) {
      const double *n = S->nrm + 3 * op->bst[b];
      add_outer(blk, pd_pair_coefficient(op, r, op->bnbr[b], op->bst[b]), n, n);
    }
    if (op->model == CUPID_PD_BOND) continue;
    for (cupid_int b = op->bptr[r] - 1; b < op->bptr[r + 1]; b++) {
      const cupid_int p = b < op->bptr[r] ? r : op->bnbr[b];
      const double Gp = 3.0 * op->V / op->m[p], cp = op->V * op->kappa[p] / 3.0;
      const double *dir = p == r ? op->gself + 3 * r : S->wxn + 3 * op->bst[b];
      add_outer(blk, cp * Gp * Gp, dir, dir); /* c_p g_p[r] g_p[r]^T, sign squared away */
    }
  }
  return CUPID_SUCCESS;
}
