/* Matrix-free PD kernels on the uniform stencil (issue 6): no per-bond storage for the bulk.
 *
 * On the uniform grid every node with a full family (all stencil offsets inside the grid)
 * has the same bonds: the stencil entry s gives the unit vector n_s, |xi_s| and omega beta
 * (pd_stencil), and the neighbour is the node of cell c + clin[s]. Consecutive full nodes
 * with consecutive cells form runs (pd_run, operator.c builds them); along a run the
 * neighbours at entry s are consecutive nodes too. So the kernels sweep, for each run and
 * each stencil entry, a contiguous, branch-free inner loop over the run (SIMD over nodes,
 * the run's accumulators in L1), on structure-of-arrays copies of u and of the per-node
 * factors. Nodes near the surface (partial families) walk their stored stencil entries.
 *
 * Both sum each node's bonds in stencil order, as the bond-list kernels of lps.c and
 * bond.c do, so the two paths agree to round-off (tests/unit/test_pd_stencil.c).
 *
 * LPS (paper 000 Eqs. 17-21), two passes: a_j = kappa_j theta_j / m_j on the nodes the rows
 * need, then (K u)_i = -V^2 sum_s omega beta [ (a_i + a_j) x_s + 15 (b_i + b_j) e_ij ] n_s,
 * b = mu / m. Bond-based (paper 004 section 2.2), one pass:
 * (K u)_i = -V^2 sum_s omega beta / x_s (c_i + c_j)/2 e_ij n_s. */
#include <string.h>

#include "pd/pd_internal.h"

/* Hot loops in several instruction-set versions, picked at load time (the build uses -O2
 * and no -march; `omp simd` asks for the vectorisation). */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define PD_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define PD_CLONES
#endif

/* Structure-of-arrays copies of the data the rows depend on, indexed by node - lo. */
typedef struct {
  cupid_int lo, hi;
  double *x, *y, *z; /* displacement components */
  double *a;         /* LPS: kappa theta / m; bond-based: micromodulus c */
  double *b;         /* LPS: mu / m */
} pd_work;

static void work_free(pd_work *w) {
  cupid_free(&w->x);
  cupid_free(&w->y);
  cupid_free(&w->z);
  cupid_free(&w->a);
  cupid_free(&w->b);
}

/* Separate arrays of 8 bytes a node (not one block): each stays below the allocator's
 * mmap threshold for longer, so repeated applies reuse heap pages instead of faulting. */
static cupid_status work_alloc(pd_work *w, cupid_int lo, cupid_int hi, int with_b) {
  memset(w, 0, sizeof *w);
  w->lo = lo;
  w->hi = hi;
  const size_t n = (size_t)(hi - lo);
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_malloc(n, sizeof *w->x, "PD stencil work arrays", &w->x));
  CUPID_TRY(cupid_malloc(n, sizeof *w->y, "PD stencil work arrays", &w->y));
  CUPID_TRY(cupid_malloc(n, sizeof *w->z, "PD stencil work arrays", &w->z));
  CUPID_TRY(cupid_malloc(n, sizeof *w->a, "PD stencil work arrays", &w->a));
  if (with_b) CUPID_TRY(cupid_malloc(n, sizeof *w->b, "PD stencil work arrays", &w->b));
cleanup:
  if (st != CUPID_SUCCESS) work_free(w);
  return st;
}

/* Split u into components over [lo, hi); b = mu/m (LPS) or a = c (bond-based). */
static void work_fill(const struct cupid_pd_operator_private *op, pd_work *w, const double *u) {
  const cupid_int lo = w->lo, n = w->hi - w->lo;
#pragma omp parallel for schedule(static) if (n > PD_OMP_MIN_NODES)
  for (cupid_int q = 0; q < n; q++) {
    const cupid_int i = lo + q;
    w->x[q] = u[3 * i];
    w->y[q] = u[3 * i + 1];
    w->z[q] = u[3 * i + 2];
    if (w->b)
      w->b[q] = op->mu[i] / op->m[i];
    else
      w->a[q] = op->c[i];
  }
}

/* ---- The run kernels: nodes i .. i+len-1 at cells c .. c+len-1, all full. ---- */

/* a = kappa theta / m with theta = 3V/m sum_s omega beta xi_s . (u_j - u_i) (Eq. 19). */
PD_CLONES
static void run_dilatation(const struct cupid_pd_operator_private *op, const pd_work *w,
                           cupid_int i, cupid_int c, int len, double *restrict theta) {
  const pd_stencil *S = &op->st;
  const cupid_int *restrict dense = op->grid->dense;
  const cupid_int li = i - w->lo;
  const double *restrict xi = w->x + li, *restrict yi = w->y + li, *restrict zi = w->z + li;
  double acc[PD_RUN_MAX];
  for (int t = 0; t < len; t++) acc[t] = 0.0;
  for (int s = 0; s < S->n; s++) {
    const cupid_int lj = dense[c + op->clin[s]] - w->lo;
    const double *restrict xj = w->x + lj, *restrict yj = w->y + lj, *restrict zj = w->z + lj;
    const double g0 = S->wxn[3 * s], g1 = S->wxn[3 * s + 1], g2 = S->wxn[3 * s + 2];
#pragma omp simd
    for (int t = 0; t < len; t++)
      acc[t] += g0 * (xj[t] - xi[t]) + g1 * (yj[t] - yi[t]) + g2 * (zj[t] - zi[t]);
  }
  double *restrict a = w->a + li;
  for (int t = 0; t < len; t++) {
    const double th = 3.0 * op->V * acc[t] / op->m[i + t];
    a[t] = op->kappa[i + t] * th / op->m[i + t];
    if (theta) theta[i + t] = th;
  }
}

/* f = -V^2 sum_s omega beta [ (a_i + a_j) x_s + 15 (b_i + b_j) e ] n_s (LPS, Eq. 21). */
PD_CLONES
static void run_lps_force(const struct cupid_pd_operator_private *op, const pd_work *w,
                          cupid_int i, cupid_int c, int len, double *restrict f) {
  const pd_stencil *S = &op->st;
  const cupid_int *restrict dense = op->grid->dense;
  const cupid_int li = i - w->lo;
  const double *restrict xi = w->x + li, *restrict yi = w->y + li, *restrict zi = w->z + li;
  const double *restrict ai = w->a + li, *restrict bi = w->b + li;
  double fx[PD_RUN_MAX], fy[PD_RUN_MAX], fz[PD_RUN_MAX];
  for (int t = 0; t < len; t++) fx[t] = fy[t] = fz[t] = 0.0;
  for (int s = 0; s < S->n; s++) {
    const cupid_int lj = dense[c + op->clin[s]] - w->lo;
    const double *restrict xj = w->x + lj, *restrict yj = w->y + lj, *restrict zj = w->z + lj;
    const double *restrict aj = w->a + lj, *restrict bj = w->b + lj;
    const double n0 = S->nrm[3 * s], n1 = S->nrm[3 * s + 1], n2 = S->nrm[3 * s + 2];
    const double wx = S->wb[s] * S->x[s], w15 = 15.0 * S->wb[s];
#pragma omp simd
    for (int t = 0; t < len; t++) {
      const double e = n0 * (xj[t] - xi[t]) + n1 * (yj[t] - yi[t]) + n2 * (zj[t] - zi[t]);
      const double q = wx * (ai[t] + aj[t]) + w15 * (bi[t] + bj[t]) * e;
      fx[t] += q * n0;
      fy[t] += q * n1;
      fz[t] += q * n2;
    }
  }
  const double V2 = op->V * op->V;
  for (int t = 0; t < len; t++) {
    f[3 * t] = -V2 * fx[t];
    f[3 * t + 1] = -V2 * fy[t];
    f[3 * t + 2] = -V2 * fz[t];
  }
}

/* f = -V^2 sum_s omega beta / x_s (c_i + c_j)/2 e n_s (bond-based). */
PD_CLONES
static void run_bond_force(const struct cupid_pd_operator_private *op, const pd_work *w,
                           cupid_int i, cupid_int c, int len, double *restrict f) {
  const pd_stencil *S = &op->st;
  const cupid_int *restrict dense = op->grid->dense;
  const cupid_int li = i - w->lo;
  const double *restrict xi = w->x + li, *restrict yi = w->y + li, *restrict zi = w->z + li;
  const double *restrict ci = w->a + li;
  double fx[PD_RUN_MAX], fy[PD_RUN_MAX], fz[PD_RUN_MAX];
  for (int t = 0; t < len; t++) fx[t] = fy[t] = fz[t] = 0.0;
  for (int s = 0; s < S->n; s++) {
    const cupid_int lj = dense[c + op->clin[s]] - w->lo;
    const double *restrict xj = w->x + lj, *restrict yj = w->y + lj, *restrict zj = w->z + lj;
    const double *restrict cj = w->a + lj;
    const double n0 = S->nrm[3 * s], n1 = S->nrm[3 * s + 1], n2 = S->nrm[3 * s + 2];
    const double wc = 0.5 * S->wb[s] / S->x[s];
#pragma omp simd
    for (int t = 0; t < len; t++) {
      const double e = n0 * (xj[t] - xi[t]) + n1 * (yj[t] - yi[t]) + n2 * (zj[t] - zi[t]);
      const double q = wc * (ci[t] + cj[t]) * e;
      fx[t] += q * n0;
      fy[t] += q * n1;
      fz[t] += q * n2;
    }
  }
  const double V2 = op->V * op->V;
  for (int t = 0; t < len; t++) {
    f[3 * t] = -V2 * fx[t];
    f[3 * t + 1] = -V2 * fy[t];
    f[3 * t + 2] = -V2 * fz[t];
  }
}

/* ---- Near-surface nodes: their stored stencil entries, same formulas and order. ---- */

static inline double work_extension(const pd_work *w, const double *n, cupid_int li,
                                    cupid_int lj) {
  return n[0] * (w->x[lj] - w->x[li]) + n[1] * (w->y[lj] - w->y[li]) +
         n[2] * (w->z[lj] - w->z[li]);
}

static void edge_dilatation(const struct cupid_pd_operator_private *op, const pd_work *w,
                            cupid_int i, double *theta) {
  const pd_stencil *S = &op->st;
  const pd_family F = pd_family_of(op, i);
  const cupid_int li = i - w->lo;
  double acc = 0.0;
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    const cupid_int lj = pd_family_node(op, &F, s) - w->lo;
    acc += work_extension(w, S->wxn + 3 * s, li, lj);
  }
  const double th = 3.0 * op->V * acc / op->m[i];
  w->a[li] = op->kappa[i] * th / op->m[i];
  if (theta) theta[i] = th;
}

static void edge_force(const struct cupid_pd_operator_private *op, const pd_work *w,
                       cupid_int i, double *f) {
  const pd_stencil *S = &op->st;
  const pd_family F = pd_family_of(op, i);
  const cupid_int li = i - w->lo;
  const int lps = op->model == CUPID_PD_LPS;
  double fi[3] = {0, 0, 0};
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    const cupid_int lj = pd_family_node(op, &F, s) - w->lo;
    const double *n = S->nrm + 3 * s;
    const double e = work_extension(w, n, li, lj);
    const double t = lps ? S->wb[s] * ((w->a[li] + w->a[lj]) * S->x[s] +
                                       15.0 * (w->b[li] + w->b[lj]) * e)
                         : 0.5 * S->wb[s] / S->x[s] * (w->a[li] + w->a[lj]) * e;
    for (int k = 0; k < 3; k++) fi[k] += t * n[k];
  }
  const double V2 = op->V * op->V;
  for (int k = 0; k < 3; k++) f[k] = -V2 * fi[k];
}

/* ---- Sweeps over a node range: the runs (clipped) and the edge nodes inside it. ---- */

/* First run that ends after node p (end = 1) or starts at p or later (end = 0), first edge
 * node >= p (binary searches; runs and edge nodes are ascending). */
static cupid_int first_run(const struct cupid_pd_operator_private *op, cupid_int p, int end) {
  cupid_int a = 0, b = op->nruns;
  while (a < b) {
    const cupid_int m = a + (b - a) / 2;
    const pd_run *R = &op->runs[m];
    if (end ? R->i0 + R->len <= p : R->i0 < p) a = m + 1;
    else b = m;
  }
  return a;
}

static cupid_int first_edge(const struct cupid_pd_operator_private *op, cupid_int p) {
  cupid_int a = 0, b = op->nedge;
  while (a < b) {
    const cupid_int m = a + (b - a) / 2;
    if (op->edge[m] < p) a = m + 1;
    else b = m;
  }
  return a;
}

typedef enum { PASS_DILATATION, PASS_LPS_FORCE, PASS_BOND_FORCE } pd_pass;

/* One pass over the nodes [p, q) (out: f indexed by i - fbase, or theta by node). Inside a
 * parallel region: work-shared, the caller's barrier separates the passes. */
static void sweep(const struct cupid_pd_operator_private *op, const pd_work *w, pd_pass pass,
                  cupid_int p, cupid_int q, double *out, cupid_int fbase) {
  const cupid_int r0 = first_run(op, p, 1), r1 = first_run(op, q, 0);
  const cupid_int e0 = first_edge(op, p), e1 = first_edge(op, q);
#pragma omp for schedule(static) nowait
  for (cupid_int r = r0; r < r1; r++) {
    const pd_run *R = &op->runs[r];
    const cupid_int a = R->i0 > p ? R->i0 : p, b = R->i0 + R->len < q ? R->i0 + R->len : q;
    if (a >= b) continue;
    const cupid_int c = R->c0 + (a - R->i0);
    const int len = (int)(b - a);
    if (pass == PASS_DILATATION) run_dilatation(op, w, a, c, len, out);
    else if (pass == PASS_LPS_FORCE) run_lps_force(op, w, a, c, len, out + 3 * (a - fbase));
    else run_bond_force(op, w, a, c, len, out + 3 * (a - fbase));
  }
#pragma omp for schedule(dynamic, 64)
  for (cupid_int k = e0; k < e1; k++) {
    const cupid_int i = op->edge[k];
    if (pass == PASS_DILATATION) edge_dilatation(op, w, i, out);
    else edge_force(op, w, i, out + 3 * (i - fbase));
  }
}

cupid_status pd_stencil_apply(const struct cupid_pd_operator_private *op, cupid_int first,
                              cupid_int last, const double *u, double *f, double *theta) {
  if (first == last) return CUPID_SUCCESS;
  const int lps = op->model == CUPID_PD_LPS;
  /* Rows [first, last) read a (and u) on [lo1, hi1); LPS computes a there from u on [lo, hi). */
  cupid_int lo1 = 0, hi1 = op->nnodes, lo = 0, hi = op->nnodes;
  if (first > 0 || last < op->nnodes) {
    pd_neighbour_span(op, first, last, &lo1, &hi1);
    lo = lo1, hi = hi1;
    if (lps) pd_neighbour_span(op, lo1, hi1, &lo, &hi);
  }
  pd_work w;
  CUPID_CALL(work_alloc(&w, lo, hi, lps));
  work_fill(op, &w, u);
#pragma omp parallel if (last - first > PD_OMP_MIN_NODES)
  {
    if (lps) {
      sweep(op, &w, PASS_DILATATION, lo1, hi1, theta, 0);
      /* the implicit barrier of sweep's last loop: every a is ready */
      sweep(op, &w, PASS_LPS_FORCE, first, last, f, first);
    } else {
      sweep(op, &w, PASS_BOND_FORCE, first, last, f, first);
    }
  }
  work_free(&w);
  return CUPID_SUCCESS;
}
