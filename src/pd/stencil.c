/* Matrix-free PD kernels on the uniform stencil (issue 6): no per-bond storage for the bulk.
 *
 * On the uniform grid every node with a full family (all stencil offsets inside the grid)
 * has the same bonds: the stencil entry s gives the unit vector n_s, |xi_s| and omega beta
 * (pd_stencil), and the neighbour is the node of cell c + clin[s]. Consecutive nodes at
 * consecutive cells of a row form runs (pd_run, built by pd_families_build); along a run
 * the neighbours at entry s are consecutive too. So the kernels sweep, for each run and
 * each pair of opposite stencil entries, a contiguous, branch-free loop over the run (SIMD
 * over nodes, the run's accumulators in L1) on structure-of-arrays copies of u and of the
 * per-node factors.
 *
 * Padded lattice (the usual case): the copies live on the bounding box grown by the
 * stencil reach, absent cells read 0, and every run, near the surface or not, takes the
 * same loop; the ghost bonds of non-full nodes are removed per node afterwards (see the
 * run kernels). Sparse unions (pd_internal.h, PD_PAD_RATIO): copies by node, full runs as
 * above with neighbours through the dense cell map, near-surface nodes walk their stored
 * stencil entries.
 *
 * Each node's bonds are summed in stencil order (pairs of opposites, four pairs at a time),
 * as the bond-list kernels of lps.c and bond.c do bond by bond, so the two paths agree to
 * round-off (tests/unit/test_pd_stencil.c).
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

/* Structure-of-arrays copies of the data the rows depend on. Padded: indexed by padded
 * cell - base, absent cells zero; else by node - base. */
typedef struct {
  int padded;
  cupid_int base, n, cap;
  cupid_int filled[4];  /* padded: base, n, lo, hi of the last fill (its zeros still hold) */
  double *x, *y, *z; /* displacement components */
  double *a;         /* LPS: kappa theta / m; bond-based: micromodulus c */
  double *b;         /* LPS: mu / m; NULL for bond-based */
  double *b_store;   /* the b array (b is NULL for bond-based) */
} pd_work;

static void work_free(pd_work *w) {
  cupid_free(&w->x);
  cupid_free(&w->y);
  cupid_free(&w->z);
  cupid_free(&w->a);
  cupid_free(&w->b_store);
  w->b = NULL;
  w->cap = 0;
}

void pd_stencil_work_free(struct cupid_pd_operator_private *op) {
  pd_work *w = op->work;
  if (w) work_free(w);
  cupid_free(&op->work);
}

/* Arrays for n entries (grown as needed; separate arrays, 8 bytes an entry each). */
static cupid_status work_reserve(pd_work *w, int padded, cupid_int base, cupid_int n, int lps) {
  if (w->cap < n) {
    work_free(w);
    w->filled[1] = -1;
    cupid_status st = CUPID_SUCCESS;
    double **arrays[5] = {&w->x, &w->y, &w->z, &w->a, &w->b_store};
    for (int k = 0; k < 5; k++)
      CUPID_TRY(cupid_malloc((size_t)n, sizeof(double), "PD stencil work arrays", arrays[k]));
    w->cap = n;
  cleanup:
    if (st != CUPID_SUCCESS) {
      work_free(w);
      return st;
    }
  }
  w->padded = padded;
  w->base = base;
  w->n = n;
  w->b = lps ? w->b_store : NULL;
  return CUPID_SUCCESS;
}

/* Copy u on the nodes [lo, hi) (b = mu/m for LPS, a = c for bond-based); padded: zero the
 * whole window first (absent cells read 0). */
static void work_fill(const struct cupid_pd_operator_private *op, pd_work *w, cupid_int lo,
                      cupid_int hi, const double *u) {
  const int lps = w->b != NULL;
  /* Padded: zero the window (absent cells must read 0) unless
   * the last fill had the same window and nodes: the kernels write node cells only, so its
   * zeros still hold (every apply of a time loop). */
  const cupid_int key[4] = {w->base, w->n, lo, hi};
  if (w->padded && memcmp(key, w->filled, sizeof key) != 0) {
    double *arrays[5] = {w->x, w->y, w->z, w->a, w->b};
#pragma omp parallel for schedule(static) if (w->n > 8 * PD_OMP_MIN_NODES)
    for (int k = 0; k < 5; k++)
      if (arrays[k]) memset(arrays[k], 0, (size_t)w->n * sizeof(double));
    memcpy(w->filled, key, sizeof key);
  }
  /* K annihilates translations (every row depends on differences only), so the copy is
   * shifted by the displacement of the middle node: the ghost corrections then cancel
   * terms of size |u - u_mid| (the variation of u across the range) instead of |u|, e.g.
   * exactly nothing for a rigid translation. */
  const cupid_int mid = lo + (hi - lo) / 2;
  const double r0 = w->padded ? u[3 * mid] : 0.0, r1 = w->padded ? u[3 * mid + 1] : 0.0,
               r2 = w->padded ? u[3 * mid + 2] : 0.0;
#pragma omp parallel for schedule(static) if (hi - lo > PD_OMP_MIN_NODES)
  for (cupid_int i = lo; i < hi; i++) {
    const cupid_int q = (w->padded ? pd_node_pcell(op, i) : i) - w->base;
    w->x[q] = u[3 * i] - r0;
    w->y[q] = u[3 * i + 1] - r1;
    w->z[q] = u[3 * i + 2] - r2;
    if (lps)
      w->b[q] = op->mu[i] / op->m[i];
    else
      w->a[q] = op->c[i];
  }
}

/* Position in the work arrays of node i (run R, t = i - R->i0) and of its neighbour at
 * stencil entry s (for t = 0: consecutive along the run). */
static inline cupid_int work_index(const pd_work *w, const pd_run *R, cupid_int i) {
  return (w->padded ? R->cp0 : R->i0) + (i - R->i0) - w->base;
}

static inline cupid_int work_neighbour(const struct cupid_pd_operator_private *op,
                                       const pd_work *w, const pd_run *R, cupid_int i, int s) {
  if (w->padded) return R->cp0 + (i - R->i0) + op->pclin[s] - w->base;
  return op->grid->dense[R->c0 + (i - R->i0) + op->clin[s]] - w->base;
}

/* ---- The run kernels: nodes i .. i+len-1 of run R. ----
 *
 * The stencil is symmetric (entry n-1-s is -offset of entry s, pd_families_build checks),
 * so each kernel walks the pairs (s, s'), s < n/2, with j+ the neighbour at offset o_s and
 * j- the one at -o_s: with n = n_s, d+ = n.(u+ - u_i), d- = n.(u- - u_i),
 *   dilatation:  g_s.(u+ - u_i) + g_s'.(u- - u_i) = g_s.(u+ - u-)            (g = omega beta xi)
 *   LPS force:   (q_s - q_s') n = [wx (a+ - a-) + w15 ((b_i + b+) d+ + (b_i + b-) d-)] n
 *   bond force:  (q_s - q_s') n = wc ((c_i + c+) d+ + (c_i + c-) d-) n
 * (wx = omega beta |xi|, w15 = 15 omega beta, wc = omega beta / (2|xi|)): about 40% fewer
 * operations than bond by bond, which is what bounds these loops. Pairs go four at a time
 * (the node's own data and its accumulators loaded once per eight bonds).
 *
 * Padded lattice, every run in one branch-free form: absent cells hold u = a = b = c = 0,
 * and a node whose family is not full gets the exact excess of those ghost bonds removed
 * per node afterwards (pd_correction_*): with G_i = sum over present entries of g
 * (op->gself) and C_i = sum over absent entries of w N (N = n n^T, w = w15 or wc),
 *   theta: sum - G_i.u_i;  LPS: sum + a_i G_i + b_i C_i u_i;  bond: sum + c_i C_i u_i.
 * These cancel terms of size |u_i| (not |u_j - u_i|), so the copy of u is shifted by a
 * reference displacement (work_fill): near the surface the round-off is then relative to
 * the variation of u over the range rather than to the strain. */

#define PD_PAIR_ENTRY(k)                                                                     \
  const cupid_int jp##k = work_neighbour(op, w, R, i, s + k);                               \
  const cupid_int jm##k = work_neighbour(op, w, R, i, S->n - 1 - (s + k));                   \
  const double n0##k = S->nrm[3 * (s + k)], n1##k = S->nrm[3 * (s + k) + 1],                 \
               n2##k = S->nrm[3 * (s + k) + 2];                                              \
  (void)n0##k, (void)n1##k, (void)n2##k
#define PD_DP(k) (n0##k * (X[jp##k + t] - xt) + n1##k * (Y[jp##k + t] - yt) + n2##k * (Z[jp##k + t] - zt))
#define PD_DM(k) (n0##k * (X[jm##k + t] - xt) + n1##k * (Y[jm##k + t] - yt) + n2##k * (Z[jm##k + t] - zt))

/* a = kappa theta / m with theta = 3V/m sum_s omega beta xi_s . (u_j - u_i) (Eq. 19). */
PD_CLONES
static void run_dilatation(const struct cupid_pd_operator_private *op, const pd_work *w,
                           const pd_run *R, cupid_int i, int len, double *restrict theta) {
  const pd_stencil *S = &op->st;
  const cupid_int li = work_index(w, R, i);
  const double *restrict X = w->x, *restrict Y = w->y, *restrict Z = w->z;
  double acc[PD_RUN_MAX];
  for (int t = 0; t < len; t++) acc[t] = 0.0;
  const int half = S->n / 2;
  int s = 0;
#define PD_DIL_ENTRY(k)                                                                      \
  const cupid_int jp##k = work_neighbour(op, w, R, i, s + k);                               \
  const cupid_int jm##k = work_neighbour(op, w, R, i, S->n - 1 - (s + k));                   \
  const double g0##k = S->wxn[3 * (s + k)], g1##k = S->wxn[3 * (s + k) + 1],                 \
               g2##k = S->wxn[3 * (s + k) + 2]
#define PD_DIL_TERM(k)                                                                       \
  (g0##k * (X[jp##k + t] - X[jm##k + t]) + g1##k * (Y[jp##k + t] - Y[jm##k + t]) +           \
   g2##k * (Z[jp##k + t] - Z[jm##k + t]))
  for (; s + 4 <= half; s += 4) {
    PD_DIL_ENTRY(0);
    PD_DIL_ENTRY(1);
    PD_DIL_ENTRY(2);
    PD_DIL_ENTRY(3);
#pragma omp simd
    for (int t = 0; t < len; t++)
      acc[t] += ((PD_DIL_TERM(0) + PD_DIL_TERM(1)) + PD_DIL_TERM(2)) + PD_DIL_TERM(3);
  }
  for (; s < half; s++) {
    PD_DIL_ENTRY(0);
#pragma omp simd
    for (int t = 0; t < len; t++) acc[t] += PD_DIL_TERM(0);
  }
#undef PD_DIL_TERM
#undef PD_DIL_ENTRY
  double *restrict a = w->a + li;
  for (int t = 0; t < len; t++) {
    const cupid_int n = i + t;
    double sum = acc[t];
    if (!R->full && !op->full[n]) { /* ghost bonds: -(sum over them of g).(0 - u_i) */
      const double *G = op->gself + 3 * n;
      sum -= G[0] * X[li + t] + G[1] * Y[li + t] + G[2] * Z[li + t];
    }
    const double th = 3.0 * op->V * sum / op->m[n];
    a[t] = op->kappa[n] * th / op->m[n];
    if (theta) theta[n] = th;
  }
}

/* Accumulate the pairs of a block into (gx, gy, gz), then into f[t]. */
#define PD_FORCE_LOOP(TERMS)                                                                 \
  _Pragma("omp simd") for (int t = 0; t < len; t++) {                                        \
    const cupid_int q = li + t;                                                              \
    const double xt = X[q], yt = Y[q], zt = Z[q];                                            \
    PD_NODE_LOAD                                                                             \
    double gx = 0.0, gy = 0.0, gz = 0.0;                                                     \
    TERMS                                                                                    \
    fx[t] += gx;                                                                             \
    fy[t] += gy;                                                                             \
    fz[t] += gz;                                                                             \
  }
#define PD_ADD(k)                                                                            \
  {                                                                                          \
    const double qk = PD_PAIR(k);                                                            \
    gx += qk * n0##k;                                                                        \
    gy += qk * n1##k;                                                                        \
    gz += qk * n2##k;                                                                        \
  }
#define PD_FORCE_PAIRS(ENTRY_CONSTS)                                                         \
  const int half = S->n / 2;                                                                 \
  int s = 0;                                                                                 \
  for (; s + 4 <= half; s += 4) {                                                            \
    PD_PAIR_ENTRY(0);                                                                        \
    PD_PAIR_ENTRY(1);                                                                        \
    PD_PAIR_ENTRY(2);                                                                        \
    PD_PAIR_ENTRY(3);                                                                        \
    ENTRY_CONSTS(0);                                                                         \
    ENTRY_CONSTS(1);                                                                         \
    ENTRY_CONSTS(2);                                                                         \
    ENTRY_CONSTS(3);                                                                         \
    PD_FORCE_LOOP(PD_ADD(0) PD_ADD(1) PD_ADD(2) PD_ADD(3))                                   \
  }                                                                                          \
  for (; s < half; s++) {                                                                    \
    PD_PAIR_ENTRY(0);                                                                        \
    ENTRY_CONSTS(0);                                                                         \
    PD_FORCE_LOOP(PD_ADD(0))                                                                 \
  }

/* f = -V^2 sum, with the ghost correction k_i G_i + b_i C_i u_i (k_i = a_i for LPS, 0 for
 * bond-based with b_i = c_i) for nodes without a full family. */
static inline void run_store(const struct cupid_pd_operator_private *op, const pd_work *w,
                             const pd_run *R, cupid_int i, int len, double *fx, double *fy,
                             double *fz, double *restrict f) {
  const double V2 = op->V * op->V;
  const cupid_int li = work_index(w, R, i);
  const int lps = op->model == CUPID_PD_LPS;
  for (int t = 0; t < len; t++) {
    const cupid_int n = i + t;
    if (!R->full && !op->full[n]) {
      const double *C = op->ncorr + 6 * (size_t)op->crank[n];
      const double u0 = w->x[li + t], u1 = w->y[li + t], u2 = w->z[li + t];
      const double bi = lps ? w->b[li + t] : w->a[li + t];
      fx[t] += bi * (C[0] * u0 + C[5] * u1 + C[4] * u2);
      fy[t] += bi * (C[5] * u0 + C[1] * u1 + C[3] * u2);
      fz[t] += bi * (C[4] * u0 + C[3] * u1 + C[2] * u2);
      if (lps) {
        const double *G = op->gself + 3 * n, ai = w->a[li + t];
        fx[t] += ai * G[0];
        fy[t] += ai * G[1];
        fz[t] += ai * G[2];
      }
    }
    f[3 * t] = -V2 * fx[t];
    f[3 * t + 1] = -V2 * fy[t];
    f[3 * t + 2] = -V2 * fz[t];
  }
}

/* f = -V^2 sum_s omega beta [ (a_i + a_j) x_s + 15 (b_i + b_j) e ] n_s (LPS, Eq. 21). */
PD_CLONES
static void run_lps_force(const struct cupid_pd_operator_private *op, const pd_work *w,
                          const pd_run *R, cupid_int i, int len, double *restrict f) {
  const pd_stencil *S = &op->st;
  const cupid_int li = work_index(w, R, i);
  const double *restrict X = w->x, *restrict Y = w->y, *restrict Z = w->z;
  const double *restrict A = w->a, *restrict B = w->b;
  double fx[PD_RUN_MAX], fy[PD_RUN_MAX], fz[PD_RUN_MAX];
  for (int t = 0; t < len; t++) fx[t] = fy[t] = fz[t] = 0.0;
#define PD_NODE_LOAD const double bt = B[q];
#define PD_CONSTS(k) const double wx##k = S->wb[s + k] * S->x[s + k], w15##k = 15.0 * S->wb[s + k]
#define PD_PAIR(k)                                                                           \
  (wx##k * (A[jp##k + t] - A[jm##k + t]) +                                                   \
   w15##k * ((bt + B[jp##k + t]) * PD_DP(k) + (bt + B[jm##k + t]) * PD_DM(k)))
  PD_FORCE_PAIRS(PD_CONSTS)
#undef PD_NODE_LOAD
#undef PD_CONSTS
#undef PD_PAIR
  run_store(op, w, R, i, len, fx, fy, fz, f);
}

/* f = -V^2 sum_s omega beta / x_s (c_i + c_j)/2 e n_s (bond-based). */
PD_CLONES
static void run_bond_force(const struct cupid_pd_operator_private *op, const pd_work *w,
                           const pd_run *R, cupid_int i, int len, double *restrict f) {
  const pd_stencil *S = &op->st;
  const cupid_int li = work_index(w, R, i);
  const double *restrict X = w->x, *restrict Y = w->y, *restrict Z = w->z;
  const double *restrict A = w->a;
  double fx[PD_RUN_MAX], fy[PD_RUN_MAX], fz[PD_RUN_MAX];
  for (int t = 0; t < len; t++) fx[t] = fy[t] = fz[t] = 0.0;
#define PD_NODE_LOAD const double ct = A[q];
#define PD_CONSTS(k) const double wc##k = 0.5 * S->wb[s + k] / S->x[s + k]
#define PD_PAIR(k) (wc##k * ((ct + A[jp##k + t]) * PD_DP(k) + (ct + A[jm##k + t]) * PD_DM(k)))
  PD_FORCE_PAIRS(PD_CONSTS)
#undef PD_NODE_LOAD
#undef PD_CONSTS
#undef PD_PAIR
  run_store(op, w, R, i, len, fx, fy, fz, f);
}

#undef PD_PAIR_ENTRY
#undef PD_DP
#undef PD_DM
#undef PD_FORCE_LOOP
#undef PD_ADD
#undef PD_FORCE_PAIRS

/* ---- Near-surface nodes without padding: their stored stencil entries, same formulas
 * and order (work arrays indexed by node). ---- */

static inline double work_extension(const pd_work *w, const double *n, cupid_int li,
                                    cupid_int lj) {
  return n[0] * (w->x[lj] - w->x[li]) + n[1] * (w->y[lj] - w->y[li]) +
         n[2] * (w->z[lj] - w->z[li]);
}

static void edge_dilatation(const struct cupid_pd_operator_private *op, const pd_work *w,
                            cupid_int i, double *theta) {
  const pd_stencil *S = &op->st;
  const pd_family F = pd_family_of(op, i);
  const cupid_int li = i - w->base;
  double acc = 0.0;
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    const cupid_int lj = pd_family_node(op, &F, s) - w->base;
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
  const cupid_int li = i - w->base;
  const int lps = op->model == CUPID_PD_LPS;
  double fi[3] = {0, 0, 0};
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    const cupid_int lj = pd_family_node(op, &F, s) - w->base;
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

/* ---- Sweeps over a node range: the runs, clipped to it. ---- */

/* First run whose last node is >= p (binary search; runs are ascending and cover every
 * node, so run r ends where run r + 1 starts). */
static cupid_int first_run(const struct cupid_pd_operator_private *op, cupid_int p) {
  cupid_int a = 0, b = op->nruns;
  while (a < b) {
    const cupid_int m = a + (b - a) / 2;
    if (op->runs[m].i0 + op->runs[m].len <= p) a = m + 1;
    else b = m;
  }
  return a;
}

typedef enum { PASS_DILATATION, PASS_LPS_FORCE, PASS_BOND_FORCE } pd_pass;

/* One pass over the nodes [p, q) (out: f indexed by i - fbase, or theta by node). Inside a
 * parallel region: work-shared; the implicit barrier at the end separates the passes.
 * Dynamic schedule: runs differ in length and in cost (corrections, or family walks). */
static void sweep(const struct cupid_pd_operator_private *op, const pd_work *w, pd_pass pass,
                  cupid_int p, cupid_int q, double *out, cupid_int fbase) {
  const cupid_int r0 = first_run(op, p), r1 = first_run(op, q);
#pragma omp for schedule(dynamic, 16)
  for (cupid_int r = r0; r < r1 + (r1 < op->nruns && op->runs[r1].i0 < q); r++) {
    const pd_run *R = &op->runs[r];
    const cupid_int a = R->i0 > p ? R->i0 : p, b = R->i0 + R->len < q ? R->i0 + R->len : q;
    const int len = (int)(b - a);
    if (R->full || w->padded) {
      if (pass == PASS_DILATATION) run_dilatation(op, w, R, a, len, out);
      else if (pass == PASS_LPS_FORCE) run_lps_force(op, w, R, a, len, out + 3 * (a - fbase));
      else run_bond_force(op, w, R, a, len, out + 3 * (a - fbase));
      continue;
    }
    for (cupid_int i = a; i < b; i++) {
      if (pass == PASS_DILATATION) edge_dilatation(op, w, i, out);
      else edge_force(op, w, i, out + 3 * (i - fbase));
    }
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
  /* The window of the work arrays: padded, every stencil cell of the nodes swept
   * ([lo1, hi1) for LPS, [first, last) else; they hold the nodes [lo, hi)). */
  cupid_int base = lo, len = hi - lo;
  if (op->padded) {
    cupid_int mn = 0, mx = 0;
    for (int s = 0; s < op->st.n; s++) {
      if (op->pclin[s] < mn) mn = op->pclin[s];
      if (op->pclin[s] > mx) mx = op->pclin[s];
    }
    const cupid_int s0 = lps ? lo1 : first, s1 = lps ? hi1 : last;
    base = pd_node_pcell(op, s0) + mn;
    len = pd_node_pcell(op, s1 - 1) + mx + 1 - base;
  }
  /* The kept arrays if free, else (a concurrent apply) our own. The operator object is
   * not const (only the handle's users see it so): the cache is its private state. */
  struct cupid_pd_operator_private *mop = (struct cupid_pd_operator_private *)op;
  pd_work local = {0}, *w = &local;
  const int kept = !atomic_exchange(&mop->work_busy, 1);
  cupid_status st = CUPID_SUCCESS;
  if (kept) {
    if (!mop->work) CUPID_TRY(cupid_calloc(1, sizeof(pd_work), "PD stencil work", &mop->work));
    w = mop->work;
  }
  CUPID_TRY(work_reserve(w, op->padded, base, len, lps));
  work_fill(op, w, lo, hi, u);
#pragma omp parallel if (hi - lo > PD_OMP_MIN_NODES)
  {
    if (lps) {
      sweep(op, w, PASS_DILATATION, lo1, hi1, theta, 0);
      sweep(op, w, PASS_LPS_FORCE, first, last, f, first);
    } else {
      sweep(op, w, PASS_BOND_FORCE, first, last, f, first);
    }
  }
cleanup:
  work_free(&local);
  if (kept) atomic_store(&mop->work_busy, 0);
  return st;
}
