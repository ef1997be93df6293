/* Analytic assembly of K in 3x3-block CSR (not finite differences).
 *
 * K = K_pair + sum_p c_p g_p g_p^T, the Hessian of the energy in operator.c:
 *  - K_pair: each bond i-j is a spring along n_ij with stiffness w_ij
 *    (pd_pair_coefficient): blocks (i,i) += w n n^T, (i,j) -= w n n^T;
 *  - LPS dilatation term: c_p = V (3K_p - 5mu_p)/3 and g_p = d theta_p / dU, non-zero on
 *    p (g_p[p] = -3V/m_p sum_j omega beta x D_pj n_pj) and on its neighbours
 *    (g_p[j] = 3V/m_p omega beta x D_pj n_pj; D the surface factor, 1 without a
 *    correction). It couples nodes up to 2 delta apart.
 *
 * Row-wise gather, no atomics: row r collects block(r,k) += c_p g_p[r] (x) g_p[k] for
 * p in H_r + {r}, k in H_p + {p}. On the uniform grid every column k of row r sits at a
 * lattice offset k - r in the stencil sum D (pd_stencil_sum, sorted like node indices),
 * so each thread accumulates the row in a small dense buffer indexed by that offset
 * (found with one table look-up per pair, all in cache), then copies the touched entries
 * out in D order: the columns come out sorted. A first pass counts the touched entries to
 * size the rows. Work and memory are O(nodes). */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "pd/pd_internal.h"

static inline void add_outer(double *blk, double w, const double *a, const double *b) {
  for (int r = 0; r < 3; r++)
    for (int c = 0; c < 3; c++) blk[3 * r + c] += w * a[r] * b[c];
}

/* blk += v (x) b with v in registers (the hot loop of the assembly). */
static inline void add_vb(double *restrict blk, double v0, double v1, double v2,
                          const double *restrict b) {
  const double b0 = b[0], b1 = b[1], b2 = b[2];
  blk[0] += v0 * b0;
  blk[1] += v0 * b1;
  blk[2] += v0 * b2;
  blk[3] += v1 * b0;
  blk[4] += v1 * b1;
  blk[5] += v1 * b2;
  blk[6] += v2 * b0;
  blk[7] += v2 * b1;
  blk[8] += v2 * b2;
}

/* Offsets of the stencil sum D, addressed through a dense cube around the zero offset:
 * dindex[center + lin(o)] = position of offset o in D (or -1); lin(o) = ox + side (oy +
 * side oz), precomputed for every stencil entry in lin[]. */
typedef struct {
  int nd;
  int32_t *doff;     /* 3 per D entry */
  int32_t *dindex;   /* side^3 */
  cupid_int center;  /* position of the zero offset in the cube */
  cupid_int *lin;    /* per stencil entry */
} offset_table;

static void offset_table_free(offset_table *t) {
  cupid_free(&t->doff);
  cupid_free(&t->dindex);
  cupid_free(&t->lin);
}

static cupid_status offset_table_build(const struct cupid_pd_operator_private *op, offset_table *t) {
  cupid_status st = CUPID_SUCCESS;
  memset(t, 0, sizeof *t);
  const pd_stencil *S = &op->st;
  CUPID_TRY(pd_stencil_sum(S, op->model == CUPID_PD_BOND, &t->nd, &t->doff));
  int R2 = 0;
  for (int q = 0; q < 3 * t->nd; q++) R2 = abs(t->doff[q]) > R2 ? abs(t->doff[q]) : R2;
  const cupid_int side = 2 * (cupid_int)R2 + 1;
  CUPID_TRY(cupid_malloc((size_t)(side * side * side), sizeof *t->dindex, "PD offset table", &t->dindex));
  for (cupid_int q = 0; q < side * side * side; q++) t->dindex[q] = -1;
  t->center = R2 + side * (R2 + side * R2);
  for (int d = 0; d < t->nd; d++) {
    const int32_t *o = t->doff + 3 * d;
    t->dindex[t->center + o[0] + side * (o[1] + side * o[2])] = d;
  }
  CUPID_TRY(cupid_malloc((size_t)S->n, sizeof *t->lin, "PD offset table", &t->lin));
  for (int s = 0; s < S->n; s++) {
    const int32_t *o = S->off + 3 * s;
    t->lin[s] = o[0] + side * (o[1] + side * o[2]);
  }
cleanup:
  if (st != CUPID_SUCCESS) offset_table_free(t);
  return st;
}

/* Per-thread row buffer: 9 doubles and a touched flag per D entry. */
typedef struct {
  double *acc;
  unsigned char *hit;
} row_buffer;

/* acc[d(s2)] += v (x) wxn_s2 over the family of p (d relative to row r through dp): the
 * hot loop, split so that full families run without an index list. */
static void add_family(const struct cupid_pd_operator_private *op, const offset_table *t,
                       cupid_int p, const pd_family *Fp, const int32_t *dp, const double v[3],
                       unsigned char *hit, double *acc) {
  const cupid_int *lin = t->lin;
  const double *wxn = op->st.wxn;
  if (op->sf || op->phi) { /* surface factors, cut cells: g_p[k] = Gp D_pk phi_k wxn(p->k) */
    for (int q = 0; q < Fp->n; q++) {
      const int s2 = pd_family_entry(Fp, q);
      if (pd_bond_broken(op, p, s2)) continue;
      const int32_t d = dp[lin[s2]];
      const cupid_int k = pd_family_node(op, Fp, s2);
      double sfb[4];
      pd_surface_bond(op, p, k, op->st.nrm + 3 * s2, sfb);
      const double f = sfb[0] * pd_phi(op, k);
      hit[d] = 1;
      add_vb(acc + 9 * (size_t)d, f * v[0], f * v[1], f * v[2], wxn + 3 * s2);
    }
    return;
  }
  if (!Fp->s) {
    for (int s2 = 0; s2 < Fp->n; s2++) {
      if (pd_bond_broken(op, p, s2)) continue;
      const int32_t d = dp[lin[s2]];
      hit[d] = 1;
      add_vb(acc + 9 * (size_t)d, v[0], v[1], v[2], wxn + 3 * s2);
    }
    return;
  }
  for (int q = 0; q < Fp->n; q++) {
    const int s2 = Fp->s[q];
    if (pd_bond_broken(op, p, s2)) continue;
    const int32_t d = dp[lin[s2]];
    hit[d] = 1;
    add_vb(acc + 9 * (size_t)d, v[0], v[1], v[2], wxn + 3 * s2);
  }
}

/* Mark (and with acc, accumulate) row r in the D-indexed buffer. */
static void gather_row(const struct cupid_pd_operator_private *op, const offset_table *t,
                       cupid_int r, row_buffer *buf, int values) {
  const pd_stencil *S = &op->st;
  const int32_t *dx = t->dindex + t->center;
  unsigned char *hit = buf->hit;
  double *acc = buf->acc;
  const pd_family Fr = pd_family_of(op, r);
  hit[dx[0]] = 1;
  for (int q = 0; q < Fr.n; q++) {
    const int s = pd_family_entry(&Fr, q);
    if (pd_bond_broken(op, r, s)) continue;
    const int32_t d = dx[t->lin[s]];
    hit[d] = 1;
    if (!values) continue;
    const double *n = S->nrm + 3 * s;
    const double w = pd_pair_coefficient(op, r, pd_family_node(op, &Fr, s), s);
    add_outer(acc + 9 * (size_t)dx[0], w, n, n);
    add_outer(acc + 9 * (size_t)d, -w, n, n);
  }
  if (op->model == CUPID_PD_BOND) return;
  /* p = r itself, then p over the neighbours of r. */
  for (int q = -1; q < Fr.n; q++) {
    const int self = q < 0;
    const int sr = self ? 0 : pd_family_entry(&Fr, q);
    if (!self && pd_bond_broken(op, r, sr)) continue;
    const cupid_int p = self ? r : pd_family_node(op, &Fr, sr);
    const int32_t *dp = dx + (self ? 0 : t->lin[sr]); /* offsets relative to p - r */
    const pd_family Fp = pd_family_of(op, p);
    if (!values) {
      hit[dp[0]] = 1;
      for (int qq = 0; qq < Fp.n; qq++) {
        const int s2 = pd_family_entry(&Fp, qq);
        if (!pd_bond_broken(op, p, s2)) hit[dp[t->lin[s2]]] = 1;
      }
      continue;
    }
    const double Gp = 3.0 * op->V / op->m[p], cp = op->V * pd_phi(op, p) * op->kappa[p] / 3.0;
    double gr[3], gp[3]; /* intact self weights (broken bonds leave theta's sums) */
    const double *dir = self ? pd_gself_intact(op, r, gr) : S->wxn + 3 * sr;
    const double *gsp = pd_gself_intact(op, p, gp);
    double Dpr = 1.0; /* surface factor of bond p -> r in theta_p (times phi_r) */
    if (!self && op->sf) {
      double sfb[4];
      pd_surface_bond(op, r, p, S->nrm + 3 * sr, sfb);
      Dpr = sfb[1];
    }
    if (!self) Dpr *= pd_phi(op, r);
    double v[3]; /* c_p g_p[r] Gp, with g_p[r] = -Gp gself_r, or -Gp D_pr phi_r wxn(r->p) */
    for (int c = 0; c < 3; c++) v[c] = -cp * Gp * Gp * Dpr * dir[c];
    double mgs[3]; /* g_p[p] / Gp = -gself_p */
    for (int c = 0; c < 3; c++) mgs[c] = -gsp[c];
    hit[dp[0]] = 1;
    add_outer(acc + 9 * (size_t)dp[0], 1.0, v, mgs);
    add_family(op, t, p, &Fp, dp, v, hit, acc);
  }
}

/* Copy the touched entries of the buffer out in D order (sorted columns), clearing them;
 * with col == NULL only count them. */
static cupid_int flush_row(const struct cupid_pd_operator_private *op, const offset_table *t,
                           cupid_int r, row_buffer *buf, cupid_int *col, double *val) {
  const struct cupid_pd_grid_private *g = op->grid;
  const int32_t *q = g->ijk + 3 * r;
  cupid_int n = 0;
  for (int d = 0; d < t->nd; d++) {
    if (!buf->hit[d]) continue;
    buf->hit[d] = 0;
    if (col) {
      const int32_t *o = t->doff + 3 * d;
      col[n] = pd_grid_lookup(g, q[0] + o[0], q[1] + o[1], q[2] + o[2]);
      memcpy(val + 9 * (size_t)n, buf->acc + 9 * (size_t)d, 9 * sizeof *val);
      memset(buf->acc + 9 * (size_t)d, 0, 9 * sizeof *val);
    }
    n++;
  }
  return n;
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

/* Rows of K: row k is node first + k, or nodes[k] with a list (each row as the whole
 * assembly has it, to the bit: a row is gathered from its own families alone). */
static cupid_status assemble_list(const struct cupid_pd_operator_private *op, cupid_int first,
                                  const cupid_int *nodes, cupid_int nr, cupid_csr *Kout) {
  cupid_status st = CUPID_SUCCESS;
  cupid_csr_t *K = NULL;
  offset_table t = {0};
  double *acc = NULL;
  unsigned char *hit = NULL;
  *Kout = NULL;
  const int nt = nr > PD_OMP_MIN_NODES ? num_threads() : 1;
  CUPID_TRY(offset_table_build(op, &t));
  CUPID_TRY(cupid_calloc((size_t)nt * 9 * (size_t)t.nd, sizeof *acc, "assembly buffers", &acc));
  CUPID_TRY(cupid_calloc((size_t)nt * (size_t)t.nd, 1, "assembly buffers", &hit));
  CUPID_TRY(cupid_calloc(1, sizeof *K, "the PD stiffness matrix", &K));
  K->nrows = nr;
  K->ncols = op->nnodes;
  K->bs = 3;
  CUPID_TRY(cupid_malloc((size_t)nr + 1, sizeof *K->rowptr, "PD matrix row pointers", &K->rowptr));
  K->rowptr[0] = 0;
#pragma omp parallel num_threads(nt)
  {
    row_buffer buf = {acc + 9 * (size_t)thread_id() * (size_t)t.nd, hit + (size_t)thread_id() * (size_t)t.nd};
#pragma omp for schedule(dynamic, 64)
    for (cupid_int k = 0; k < nr; k++) {
      const cupid_int r = nodes ? nodes[k] : first + k;
      gather_row(op, &t, r, &buf, 0);
      K->rowptr[k + 1] = flush_row(op, &t, r, &buf, NULL, NULL);
    }
  }
  for (cupid_int r = 0; r < nr; r++) K->rowptr[r + 1] += K->rowptr[r];
  const cupid_int nblk = K->rowptr[nr];
  CUPID_TRY(cupid_malloc((size_t)nblk + 1, sizeof *K->col, "PD matrix columns", &K->col));
  CUPID_TRY(cupid_malloc(9 * (size_t)nblk + 1, sizeof *K->val, "PD matrix values", &K->val));
#pragma omp parallel num_threads(nt)
  {
    row_buffer buf = {acc + 9 * (size_t)thread_id() * (size_t)t.nd, hit + (size_t)thread_id() * (size_t)t.nd};
#pragma omp for schedule(dynamic, 64)
    for (cupid_int k = 0; k < nr; k++) {
      const cupid_int r = nodes ? nodes[k] : first + k, q = K->rowptr[k];
      gather_row(op, &t, r, &buf, 1);
      flush_row(op, &t, r, &buf, K->col + q, K->val + 9 * (size_t)q);
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
  offset_table_free(&t);
  cupid_free(&acc);
  cupid_free(&hit);
  return st;
}

cupid_status pd_assemble_rows(const struct cupid_pd_operator_private *op, cupid_int first,
                              cupid_int last, cupid_csr *K) {
  CUPID_CHECK(op && K, CUPID_ERR_ARGUMENT, "assemble needs an operator and an output");
  CUPID_CHECK(first >= 0 && first <= last && last <= op->nnodes, CUPID_ERR_ARGUMENT,
              "assemble: rows [%lld, %lld) outside the %lld nodes", (long long)first,
              (long long)last, (long long)op->nnodes);
  return assemble_list(op, first, NULL, last - first, K);
}

cupid_status cupid_pd_operator_assemble(const cupid_pd_operator op, cupid_csr *K) {
  CUPID_CHECK(op && K, CUPID_ERR_ARGUMENT, "assemble needs an operator and an output");
  return pd_assemble_rows(op, 0, op->nnodes, K);
}

/* Weights must be finite and >= 0. */
static cupid_status check_weights(const struct cupid_pd_operator_private *op, const double *w) {
  for (cupid_int i = 0; i < op->nnodes; i++)
    CUPID_CHECK(w[i] >= 0.0 && isfinite(w[i]), CUPID_ERR_ARGUMENT,
                "energy weight %g of PD node %lld: weights must be finite and >= 0", w[i],
                (long long)i);
  return CUPID_SUCCESS;
}

/* The moduli enter every node's energy linearly (E_p = V [kappa_p/6 theta_p^2 + 15 mu_p /
 * (2 m_p) sum omega e^2 beta V], bond-based c_p), and theta_p, m_p and the surface factors do
 * not depend on them: scaling node p's moduli by w_p is weighting node p's energy by w_p. */
static void scale_moduli(struct cupid_pd_operator_private *op, const double *w) {
  double *moduli[3] = {op->kappa, op->mu, op->c};
  for (int k = 0; k < 3; k++)
    if (moduli[k])
      for (cupid_int i = 0; i < op->nnodes; i++) moduli[k][i] *= w[i];
}

/* b = mu / m changes with the moduli: the stencil path's copies of it are refreshed (gen) and
 * its stretches of uniform b found again (uniform.c; issue 32: kept from before the scaling,
 * they spanned an Arlequin overlap's ramp of weights). */
cupid_status cupid_pd_operator_scale_energy(cupid_pd_operator op, const double *w) {
  CUPID_CHECK(op && w, CUPID_ERR_ARGUMENT, "energy scaling needs an operator and weights");
  CUPID_CALL(check_weights(op, w));
  scale_moduli(op, w);
  op->gen++;
  op->changed_all = 1; /* every row of an assembled K */
  return pd_uniform_build(op);
}

/* The moduli are scaled in place for the assembly and restored from copies (bit-exact: the
 * stencil path's copies of b and its uniform stretches hold again, and the assembly reads
 * neither). */
static cupid_status assemble_weighted(cupid_pd_operator op, const double *w, const cupid_int *nodes,
                                      cupid_int nr, cupid_csr *K) {
  CUPID_CALL(check_weights(op, w));
  const cupid_int n = op->nnodes;
  double *moduli[3] = {op->kappa, op->mu, op->c}, *saved[3] = {NULL, NULL, NULL};
  cupid_status st = CUPID_SUCCESS;
  for (int k = 0; k < 3; k++) {
    if (!moduli[k]) continue;
    CUPID_TRY(cupid_malloc((size_t)n, sizeof *saved[k], "saved PD moduli", &saved[k]));
    memcpy(saved[k], moduli[k], (size_t)n * sizeof *saved[k]);
  }
  scale_moduli(op, w);
  st = assemble_list(op, 0, nodes, nr, K);
cleanup:
  for (int k = 0; k < 3; k++)
    if (saved[k]) memcpy(moduli[k], saved[k], (size_t)n * sizeof *saved[k]);
  for (int k = 0; k < 3; k++) cupid_free(&saved[k]);
  return st;
}

cupid_status cupid_pd_operator_assemble_weighted(cupid_pd_operator op, const double *w,
                                                 cupid_csr *K) {
  CUPID_CHECK(op && w && K, CUPID_ERR_ARGUMENT, "weighted assembly needs operator, weights, output");
  return assemble_weighted(op, w, NULL, op->nnodes, K);
}

cupid_status cupid_pd_operator_assemble_node_rows(cupid_pd_operator op, const double *w,
                                                  const cupid_int *nodes, cupid_int n, cupid_csr *K) {
  CUPID_CHECK(op && (nodes || n == 0) && n >= 0 && K, CUPID_ERR_ARGUMENT,
              "row assembly needs an operator, the nodes and an output");
  for (cupid_int k = 0; k < n; k++)
    CUPID_CHECK(nodes[k] >= 0 && nodes[k] < op->nnodes, CUPID_ERR_ARGUMENT,
                "row assembly: node %lld outside the %lld nodes", (long long)nodes[k],
                (long long)op->nnodes);
  return w ? assemble_weighted(op, w, nodes, n, K) : assemble_list(op, 0, nodes, n, K);
}

cupid_status cupid_pd_operator_diagonal(const cupid_pd_operator op, double *blocks) {
  CUPID_CHECK(op && blocks, CUPID_ERR_ARGUMENT, "diagonal needs an operator and an output");
  const pd_stencil *S = &op->st;
#pragma omp parallel for schedule(static) if (op->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int r = 0; r < op->nnodes; r++) {
    double *blk = blocks + 9 * (size_t)r;
    memset(blk, 0, 9 * sizeof *blk);
    const pd_family F = pd_family_of(op, r);
    for (int q = 0; q < F.n; q++) {
      const int s = pd_family_entry(&F, q);
      if (pd_bond_broken(op, r, s)) continue;
      const double *n = S->nrm + 3 * s;
      add_outer(blk, pd_pair_coefficient(op, r, pd_family_node(op, &F, s), s), n, n);
    }
    if (op->model == CUPID_PD_BOND) continue;
    for (int q = -1; q < F.n; q++) {
      const int s = q < 0 ? 0 : pd_family_entry(&F, q);
      if (q >= 0 && pd_bond_broken(op, r, s)) continue;
      const cupid_int p = q < 0 ? r : pd_family_node(op, &F, s);
      const double Gp = 3.0 * op->V / op->m[p], cp = op->V * pd_phi(op, p) * op->kappa[p] / 3.0;
      double gr[3];
      const double *dir = q < 0 ? pd_gself_intact(op, r, gr) : S->wxn + 3 * s;
      double Dpr = 1.0; /* surface factor of bond p -> r in theta_p (times phi_r) */
      if (q >= 0 && op->sf) {
        double sfb[4];
        pd_surface_bond(op, r, p, S->nrm + 3 * s, sfb);
        Dpr = sfb[1];
      }
      if (q >= 0) Dpr *= pd_phi(op, r);
      add_outer(blk, cp * Gp * Gp * Dpr * Dpr, dir, dir); /* c_p g_p[r] g_p[r]^T, sign squared away */
    }
  }
  return CUPID_SUCCESS;
}

/* The sum of the 2-norms of g_p's blocks: |g_p[p]| + sum_j |g_p[j]| (g_p as in the header). */
static double dilatation_gradient_norm(const struct cupid_pd_operator_private *op, cupid_int p,
                                       double wx_full) {
  const pd_stencil *S = &op->st;
  const pd_family F = pd_family_of(op, p);
  double gp[3], sum = 0.0;
  const double *self = pd_gself_intact(op, p, gp);
  const int intact = !op->bslot || op->bslot[p] < 0;
  if (!op->sf && !op->phi && intact && !F.s) sum = wx_full; /* a full, intact family */
  else
    for (int q = 0; q < F.n; q++) {
      const int s = pd_family_entry(&F, q);
      if (pd_bond_broken(op, p, s)) continue;
      const cupid_int j = pd_family_node(op, &F, s);
      double D = 1.0;
      if (op->sf) {
        double sfb[4];
        pd_surface_bond(op, p, j, S->nrm + 3 * s, sfb);
        D = sfb[0];
      }
      sum += S->wb[s] * S->x[s] * fabs(D) * pd_phi(op, j);
    }
  return 3.0 * op->V / op->m[p] * (sum + sqrt(self[0] * self[0] + self[1] * self[1] + self[2] * self[2]));
}

/* Row i's bound with surface factors or cut cells: every bond's coefficients through
 * pd_surface_bond and pd_phi (|c_j g_j[i]| = |kappa_j| V^2 phi_j / m_j omega beta x D_ji phi_i). */
static double row_bound_corrected(const struct cupid_pd_operator_private *op, cupid_int i,
                                  const double *G) {
  const pd_stencil *S = &op->st;
  const pd_family F = pd_family_of(op, i);
  double sum = 0.0;
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    if (pd_bond_broken(op, i, s)) continue;
    const cupid_int j = pd_family_node(op, &F, s);
    sum += 2.0 * fabs(pd_pair_coefficient(op, i, j, s));
    if (!G) continue;
    double sfb[4]; /* sfb[1]: the factor of bond j -> i in theta_j */
    pd_surface_bond(op, i, j, S->nrm + 3 * s, sfb);
    sum += fabs(op->kappa[j]) * op->V * op->V / op->m[j] * S->wb[s] * S->x[s] * fabs(sfb[1]) * G[j] *
           pd_phi(op, i) * pd_phi(op, j);
  }
  return sum;
}

/* The row bound's per-node tables (cupid_pd_operator_row_bound): pair and dilatation
 * terms by node (pq, kq) and, on the padded lattice, by cell (ppq, pkq; else NULL). */
typedef struct {
  int lps;
  const double *G, *pq, *kq, *ppq, *pkq;
} row_bound_terms;

/* p = i: |c_i| |g_i[i]| G_i (LPS; 0 bond-based). */
static double row_bound_self(const struct cupid_pd_operator_private *op, const row_bound_terms *T,
                             cupid_int i) {
  if (!T->lps) return 0.0;
  double gi[3];
  const double *self = pd_gself_intact(op, i, gi);
  /* 0.0 + as the running sum it replaces began: a -0.0 term comes out +0.0, bit for bit */
  return 0.0 + T->kq[i] * sqrt(self[0] * self[0] + self[1] * self[1] + self[2] * self[2]);
}

/* The bonds' terms of row i, walked over its family (or with surface factors). */
static double row_bound_family(const struct cupid_pd_operator_private *op,
                               const row_bound_terms *T, cupid_int i) {
  if (op->sf || op->phi) return row_bound_corrected(op, i, T->G);
  const pd_stencil *S = &op->st;
  const pd_family F = pd_family_of(op, i);
  double pair = 0.0, dil = 0.0;
  if (T->ppq) { /* padded: the neighbours' terms at their cells (no node lookup) */
    const cupid_int c = pd_node_pcell(op, i);
    for (int q = 0; q < F.n; q++) {
      const int s = pd_family_entry(&F, q);
      if (pd_bond_broken(op, i, s)) continue;
      const double wp = T->lps ? S->wb[s] : S->wb[s] / S->x[s];
      pair += wp * (T->pq[i] + T->ppq[c + op->pclin[s]]);
      dil += S->wb[s] * S->x[s] * T->pkq[c + op->pclin[s]];
    }
    return 2.0 * pair + dil;
  }
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    if (pd_bond_broken(op, i, s)) continue;
    const cupid_int j = pd_family_node(op, &F, s);
    const double wp = T->lps ? S->wb[s] : S->wb[s] / S->x[s];
    pair += wp * (T->pq[i] + T->pq[j]);
    dil += S->wb[s] * S->x[s] * T->kq[j];
  }
  return 2.0 * pair + dil;
}

/* The bonds' sums of the len consecutive full, intact families from node i0 on (consecutive
 * padded cells), read at the stencil's cell offsets with the nodes innermost (vectorised; a
 * node at a time the two sums chained every bond): each node's terms in stencil order, as
 * row_bound_family sums them. */
static void row_bound_full(const struct cupid_pd_operator_private *op, const row_bound_terms *T,
                           cupid_int i0, int len, double *restrict pair, double *restrict dil) {
  const pd_stencil *S = &op->st;
  const cupid_int c0 = pd_node_pcell(op, i0);
  const double *restrict pi = T->pq + i0;
  for (int t = 0; t < len; t++) pair[t] = dil[t] = 0.0;
  for (int s = 0; s < S->n; s++) {
    const double wp = T->lps ? S->wb[s] : S->wb[s] / S->x[s], wx = S->wb[s] * S->x[s];
    const double *restrict pj = T->ppq + c0 + op->pclin[s], *restrict kj = T->pkq + c0 + op->pclin[s];
    for (int t = 0; t < len; t++) {
      pair[t] += wp * (pi[t] + pj[t]);
      dil[t] += wx * kj[t];
    }
  }
}

/* Block Gershgorin (the header's K = K_pair + sum_p c_p g_p g_p^T, each block's 2-norm
 * bounded by the triangle inequality): row i of K_pair has |K_ii| + sum_j |K_ij| <= 2 sum_j
 * |w_ij| (|n n^T| = 1); row i of c_p g_p g_p^T has sum_k |c_p| |g_p[i]| |g_p[k]| = |c_p|
 * |g_p[i]| G_p, G_p = sum_k |g_p[k]|, non-zero for p = i and p in i's family, where
 * |c_j g_j[i]| = |kappa_j| V^2 / m_j omega beta x D_ji. Without surface factors the per-node
 * parts are tabled first (pair: 15 mu/m V^2 LPS, c V^2 / 2 bond-based; dilatation: |kappa|
 * V^2 G / m), so a bond costs two look-ups. */
cupid_status cupid_pd_operator_row_bound(const cupid_pd_operator op, double *r) {
  CUPID_CHECK(op && r, CUPID_ERR_ARGUMENT, "row bound needs an operator and an output");
  const pd_stencil *S = &op->st;
  const cupid_int nn = op->nnodes;
  const int lps = op->model != CUPID_PD_BOND;
  const double V2 = op->V * op->V;
  double *G = NULL, *pq = NULL, *kq = NULL, *ppq = NULL, *pkq = NULL, wx_full = 0.0;
  for (int s = 0; s < S->n; s++) wx_full += S->wb[s] * S->x[s];
  cupid_status st = CUPID_SUCCESS;
  if (lps) CUPID_TRY(cupid_malloc((size_t)nn + 1, sizeof *G, "dilatation gradient norms", &G));
  CUPID_TRY(cupid_malloc((size_t)nn + 1, sizeof *pq, "row bound terms", &pq));
  CUPID_TRY(cupid_malloc((size_t)nn + 1, sizeof *kq, "row bound terms", &kq));
#pragma omp parallel for schedule(static) if (nn > PD_OMP_MIN_NODES)
  for (cupid_int p = 0; p < nn; p++) {
    if (lps) G[p] = dilatation_gradient_norm(op, p, wx_full);
    pq[p] = lps ? 15.0 * op->mu[p] / op->m[p] * V2 : 0.5 * op->c[p] * V2;
    kq[p] = lps ? fabs(op->kappa[p]) * V2 / op->m[p] * G[p] * pd_phi(op, p) : 0.0;
  }
  /* On the padded lattice, the neighbours' terms of full, intact families are read at the
   * stencil's cell offsets (no node lookup a bond): the same terms in the same order. */
  if (op->padded && !op->sf && !op->phi) {
    const size_t pcells = (size_t)op->pn[0] * (size_t)op->pn[1] * (size_t)op->pn[2];
    CUPID_TRY(cupid_calloc(pcells + 1, sizeof *ppq, "row bound terms", &ppq));
    CUPID_TRY(cupid_calloc(pcells + 1, sizeof *pkq, "row bound terms", &pkq));
#pragma omp parallel for schedule(static) if (nn > PD_OMP_MIN_NODES)
    for (cupid_int p = 0; p < nn; p++) {
      ppq[pd_node_pcell(op, p)] = pq[p];
      pkq[pd_node_pcell(op, p)] = kq[p];
    }
  }
  const row_bound_terms T = {lps, G, pq, kq, ppq, pkq};
#pragma omp parallel for schedule(dynamic, 16) if (nn > PD_OMP_MIN_NODES)
  for (cupid_int k = 0; k < op->nruns; k++) {
    const pd_run *R = &op->runs[k];
    const cupid_int end = R->i0 + R->len;
    double pair[PD_RUN_MAX], dil[PD_RUN_MAX];
    for (cupid_int i = R->i0; i < end;) {
      cupid_int e = i; /* [i, e): consecutive full, intact families (consecutive cells) */
      while (e < end && ppq && op->full[e] && (!op->bslot || op->bslot[e] < 0)) e++;
      if (e == i) {
        r[3 * i] = r[3 * i + 1] = r[3 * i + 2] = row_bound_self(op, &T, i) + row_bound_family(op, &T, i);
        i++;
        continue;
      }
      row_bound_full(op, &T, i, (int)(e - i), pair, dil);
      for (cupid_int q = i; q < e; q++)
        r[3 * q] = r[3 * q + 1] = r[3 * q + 2] =
            row_bound_self(op, &T, q) + (2.0 * pair[q - i] + dil[q - i]);
      i = e;
    }
  }
cleanup:
  cupid_free(&G);
  cupid_free(&pq);
  cupid_free(&kq);
  cupid_free(&ppq);
  cupid_free(&pkq);
  return st;
}
