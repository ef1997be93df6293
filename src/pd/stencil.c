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
 * same loop; the ghost bonds of non-full nodes are removed afterwards, by segments of
 * those nodes (ghosts.c, the kernels' ghost_*). Sparse unions (pd_internal.h, PD_PAD_RATIO): copies by node, full runs as
 * above with neighbours through the dense cell map, near-surface nodes walk their stored
 * stencil entries.
 *
 * Each node's bonds are summed by pairs of opposites, one pair at a time (in stencil order,
 * or for the LPS passes in the order of the pair plan, pd_pair_plan), the same terms as the
 * bond-list kernels of lps.c and bond.c sum bond by bond, so the two paths agree to
 * round-off (tests/unit/test_pd_stencil.c).
 *
 * LPS (paper 000 Eqs. 17-21), two passes: a_j = kappa_j theta_j / m_j on the nodes the rows
 * need, then (K u)_i = -V^2 sum_s omega beta [ (a_i + a_j) x_s + 15 (b_i + b_j) e_ij ] n_s,
 * b = mu / m. The first pass also sums the terms in b (they need no a), so each pass loads
 * a neighbour's u once; the second adds the terms in a. Bond-based (paper 004 section 2.2),
 * one pass: (K u)_i = -V^2 sum_s omega beta / x_s (c_i + c_j)/2 e_ij n_s. */
#define _DEFAULT_SOURCE /* posix_memalign, madvise */
#include <stdlib.h>
#include <math.h>
#include <string.h>
#include <sys/mman.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "pd/pd_internal.h"

/* Lanes: the kernels (stencil_kernels.h) treat PD_KLANES consecutive nodes of a run as
 * one vector (GNU C vector extensions), keep a lane block's accumulators in registers over
 * all the stencil pairs and address every neighbour from one base pointer plus the pair's
 * offset. The last block of a run may reach up to PD_KLANES - 1 cells past the run: those
 * lanes read the slack that work_reserve adds to the window and are never stored. */
#define PD_LANES_MAX 8
#if PD_ROW_ALIGN % PD_LANES_MAX != 0
#error "padded rows must be whole lane blocks"
#endif

/* Structure-of-arrays copies of the data the rows depend on. Padded: indexed by padded
 * cell - base, absent cells zero; else by node - base. The arrays start `lead` entries into
 * 64-byte aligned blocks, chosen so that the cells of x = 0 (where the runs of a box start)
 * are aligned: the lane loads of the node itself and of every neighbour in the same x
 * column (padded rows are a multiple of PD_ROW_ALIGN cells) then touch one cache line. */
typedef struct {
  int padded, lead;
  cupid_int base, n, cap;
  cupid_int filled[5];  /* base, n, lo, hi and op->gen of the last fill (its zeros and
                           constants hold; gen changes with m when bonds break) */
  double *x, *y, *z; /* displacement components */
  double *a;         /* LPS: kappa theta / m; bond-based: micromodulus c */
  double *b;         /* LPS: mu / m; NULL for bond-based */
  double *gx, *gy, *gz; /* LPS: the force's sums without the a terms, between the passes */
  double *raw[8];    /* the starts of x, y, z, a, b, gx, gy, gz (LPS only from b on) */
  void *block;       /* one allocation holds them all (work_reserve) */
  cupid_int *absent;      /* the stretch scan: the window's cells without a node, */
  cupid_int n_absent;     /* for the window absent_key (base, n, lead) */
  cupid_int absent_key[3];
} pd_work;

static void work_free(pd_work *w) {
  for (int k = 0; k < 8; k++) w->raw[k] = NULL;
  free(w->block);
  w->block = NULL;
  cupid_free(&w->absent);
  w->n_absent = 0;
  w->absent_key[1] = -1;
  w->x = w->y = w->z = w->a = w->b = w->gx = w->gy = w->gz = NULL;
  w->cap = 0;
}

void pd_stencil_work_free(struct cupid_pd_operator_private *op) {
  pd_work *w = op->work;
  if (w) work_free(w);
  cupid_free(&op->work);
}

/* Arrays for n entries from `lead` on, plus PD_LANES_MAX of zeroed slack (grown as needed;
 * 8 bytes an entry each: 5 arrays, 8 for LPS), in one block. A block of some megabytes is
 * aligned to and asked for in 2 MB pages (Linux transparent huge pages): a run's neighbours
 * span some 30 rows of each array, 4 KB pages apart, more than the first-level TLB holds;
 * with huge pages the apply takes about a tenth less (bench_pd_apply). The arrays start
 * 320 bytes apart modulo 4 KB, so that the same cell of each falls in another L1 set. */
#define PD_HUGE_PAGE ((size_t)2 << 20)
static cupid_status work_reserve(pd_work *w, int padded, cupid_int base, cupid_int n, int lead,
                                 int lps) {
  const int arrays_n = lps ? 8 : 5;
  if (w->cap < n || !w->raw[arrays_n - 1]) {
    work_free(w);
    w->filled[1] = -1;
    const size_t bytes = ((size_t)n + PD_ROW_ALIGN + PD_LANES_MAX) * sizeof(double);
    const size_t stride = (bytes + 4095) / 4096 * 4096 + 320;
    size_t total = stride * (size_t)arrays_n, align = 64;
    if (total >= 2 * PD_HUGE_PAGE) {
      total = (total + PD_HUGE_PAGE - 1) / PD_HUGE_PAGE * PD_HUGE_PAGE;
      align = PD_HUGE_PAGE;
    }
    if (posix_memalign(&w->block, align, total) != 0) {
      w->block = NULL;
      return CUPID_ERROR(CUPID_ERR_MEMORY,
                         "out of memory for the PD stencil work arrays (%zu bytes)", total);
    }
#ifdef MADV_HUGEPAGE
    if (align == PD_HUGE_PAGE) (void)madvise(w->block, total, MADV_HUGEPAGE); /* a hint */
#endif
    for (int k = 0; k < arrays_n; k++) w->raw[k] = (double *)((char *)w->block + stride * (size_t)k);
    w->cap = n;
  }
  if (lead != w->lead) w->filled[1] = -1; /* the data moved */
  w->padded = padded;
  w->lead = lead;
  w->base = base;
  w->n = n;
  double **arrays[8] = {&w->x, &w->y, &w->z, &w->a, &w->b, &w->gx, &w->gy, &w->gz};
  for (int k = 0; k < 8; k++) {
    *arrays[k] = w->raw[k] ? w->raw[k] + lead : NULL;
    if (*arrays[k]) memset(*arrays[k] + n, 0, PD_LANES_MAX * sizeof(double));
  }
  if (!lps) w->b = w->gx = w->gy = w->gz = NULL;
  return CUPID_SUCCESS;
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
 *                (its b terms summed in the dilatation's pass, with wx (d+ - d-) for theta)
 *   bond force:  (q_s - q_s') n = wc ((c_i + c+) d+ + (c_i + c-) d-) n
 * (wx = omega beta |xi|, w15 = 15 omega beta, wc = omega beta / (2|xi|)): about 40% fewer
 * operations than bond by bond, which is what bounds these loops. A block of PD_KLANES nodes
 * keeps its own data and accumulators in registers over all the pairs.
 *
 * Padded lattice, every run in one branch-free form: absent cells hold u = a = b = c = 0,
 * and a node whose family is not full gets the exact excess of those ghost bonds removed
 * afterwards (the kernels' ghost_first, ghost_second, ghost_bond from the records of
 * ghosts.c): with G_i = sum over present entries of g (op->gself) and C_i = sum over
 * absent entries of w N (N = n n^T, w = w15 or wc),
 *   theta: sum - G_i.u_i;  LPS: sum + a_i G_i + b_i C_i u_i;  bond: sum + c_i C_i u_i.
 * These cancel terms of size |u_i| (not |u_j - u_i|), so the copy of u is shifted by a
 * reference displacement (work_fill): near the surface the round-off is then relative to
 * the variation of u over the range rather than to the strain. */


/* The pairs [s0, s1) of the run starting at node i, in stencil order or (planned) in the
 * order of the pair plan: offsets of the neighbours at +o_s (*rp) and -o_s (*rm) relative to
 * node i in the work arrays, from s0 on. Padded, they are the stencil's (or the plan's) cell
 * offsets (no table per run); else tabled into bp and bm. */
static inline void pair_offsets(const struct cupid_pd_operator_private *op, const pd_work *w,
                                const pd_run *R, cupid_int i, int s0, int s1, int planned,
                                cupid_int *bp, cupid_int *bm, const cupid_int **rp,
                                const cupid_int **rm) {
  if (w->padded) {
    *rp = (planned ? op->plan.pp : op->pclin) + s0;
    *rm = (planned ? op->plan.pm : op->pclin_opp) + s0;
    return;
  }
  const cupid_int li = work_index(w, R, i);
  for (int k = s0; k < s1; k++) {
    const int s = planned ? op->plan.s[k] : k;
    bp[k - s0] = work_neighbour(op, w, R, i, s) - li;
    bm[k - s0] = work_neighbour(op, w, R, i, op->st.n - 1 - s) - li;
  }
  *rp = bp;
  *rm = bm;
}

/* The class of a pair by its nonzero offset components (pd_pair_plan). */
static int pair_class(const int32_t *o) {
  static const int cls[8] = {-1, 4, 5, 3, 6, 2, 1, 0}; /* by x + 2y + 4z nonzero */
  return cls[(o[0] != 0) + 2 * (o[1] != 0) + 4 * (o[2] != 0)];
}

void pd_pair_plan_free(pd_pair_plan *P) {
  cupid_free(&P->s);
  cupid_free(&P->seg);
  cupid_free(&P->nrm);
  cupid_free(&P->wxn);
  cupid_free(&P->w1);
  cupid_free(&P->nw);
  cupid_free(&P->pp);
  cupid_free(&P->pm);
  P->n = 0;
}

cupid_status pd_pair_plan_build(struct cupid_pd_operator_private *op) {
  const pd_stencil *S = &op->st;
  pd_pair_plan *P = &op->plan;
  const int half = S->n / 2, chunks = (half + PD_PAIR_CHUNK - 1) / PD_PAIR_CHUNK;
  pd_pair_plan_free(P);
  cupid_status st = CUPID_SUCCESS;
  const size_t np = (size_t)half + 1;
  CUPID_TRY(cupid_malloc(np, sizeof *P->s, "PD pair plan", &P->s));
  CUPID_TRY(cupid_malloc((size_t)chunks * (PD_PAIR_CLASSES + 1) + 1, sizeof *P->seg, "PD pair plan",
                         &P->seg));
  CUPID_TRY(cupid_malloc(3 * np, sizeof *P->nrm, "PD pair plan", &P->nrm));
  CUPID_TRY(cupid_malloc(3 * np, sizeof *P->wxn, "PD pair plan", &P->wxn));
  CUPID_TRY(cupid_malloc(np, sizeof *P->w1, "PD pair plan", &P->w1));
  CUPID_TRY(cupid_malloc(3 * np, sizeof *P->nw, "PD pair plan", &P->nw));
  CUPID_TRY(cupid_malloc(np, sizeof *P->pp, "PD pair plan", &P->pp));
  CUPID_TRY(cupid_malloc(np, sizeof *P->pm, "PD pair plan", &P->pm));
  P->n = half;
  int k = 0;
  for (int c = 0; c < chunks; c++) {
    const int s0 = c * PD_PAIR_CHUNK, s1 = s0 + PD_PAIR_CHUNK < half ? s0 + PD_PAIR_CHUNK : half;
    int *seg = P->seg + c * (PD_PAIR_CLASSES + 1);
    for (int q = 0; q < PD_PAIR_CLASSES; q++) { /* stencil order within a class */
      seg[q] = k;
      for (int s = s0; s < s1; s++)
        if (pair_class(S->off + 3 * s) == q) P->s[k++] = s;
    }
    seg[PD_PAIR_CLASSES] = k;
  }
  CUPID_TRY_CHECK(k == half, CUPID_ERR_INTERNAL, "PD pair plan: %d of %d pairs classed", k, half);
  for (k = 0; k < half; k++) {
    const int s = P->s[k];
    const int32_t *o = S->off + 3 * s;
    const int axis = pair_class(o) >= 4;
    double sign = 1.0;
    for (int a = 0; a < 3; a++) {
      P->nrm[3 * k + a] = S->nrm[3 * s + a];
      P->wxn[3 * k + a] = S->wxn[3 * s + a];
      if (axis && o[a] < 0) sign = -1.0;
    }
    P->w1[k] = S->wb[s] * S->x[s] * sign;
    for (int a = 0; a < 3; a++) P->nw[3 * k + a] = 15.0 * S->wb[s] * S->nrm[3 * s + a] * sign;
    P->pp[k] = op->pclin[s];
    P->pm[k] = op->pclin[S->n - 1 - s];
  }
  return CUPID_SUCCESS;
cleanup:
  pd_pair_plan_free(P);
  return st;
}

/* u_j - u_i along n from the work arrays. */
static inline double work_extension(const pd_work *w, const double *n, cupid_int li,
                                    cupid_int lj) {
  return n[0] * (w->x[lj] - w->x[li]) + n[1] * (w->y[lj] - w->y[li]) +
         n[2] * (w->z[lj] - w->z[li]);
}

/* Broken bonds (pd_internal.h): the run kernels sweep every stencil entry, so what a node
 * with broken bonds has lost is subtracted afterwards, term by term with the formulas of
 * the sweep: sum over its broken entries of g_s.(u_j - u_i) (dilatation), and of the pair
 * term (LPS: omega beta [(a_i + a_j) x_s + 15 (b_i + b_j) e] n_s, a_i included since the
 * a_i terms of the intact family no longer cancel; bond-based omega beta/(2 x_s) (c_i + c_j)
 * e n_s). Few nodes have broken bonds; for the others this costs one test per node. */
#define PD_FOR_BROKEN(op, i, s, BODY)                                                        \
  do {                                                                                       \
    const uint64_t *mask_ = (op)->bmask + (size_t)(op)->bslot[i] * (size_t)(op)->bwords;     \
    for (int w_ = 0; w_ < (op)->bwords; w_++)                                                \
      for (uint64_t bits_ = mask_[w_]; bits_; bits_ &= bits_ - 1) {                          \
        const int s = 64 * w_ + __builtin_ctzll(bits_);                                      \
        BODY                                                                                 \
      }                                                                                      \
  } while (0)

static double broken_dilatation(const struct cupid_pd_operator_private *op, const pd_work *w,
                                const pd_run *R, cupid_int i) {
  const cupid_int li = work_index(w, R, i);
  double acc = 0.0;
  PD_FOR_BROKEN(op, i, s, {
    acc += work_extension(w, op->st.wxn + 3 * s, li, work_neighbour(op, w, R, i, s));
  });
  return acc;
}

static void broken_force(const struct cupid_pd_operator_private *op, const pd_work *w,
                         const pd_run *R, cupid_int i, double g[3]) {
  const pd_stencil *S = &op->st;
  const cupid_int li = work_index(w, R, i);
  const int lps = op->model == CUPID_PD_LPS;
  g[0] = g[1] = g[2] = 0.0;
  PD_FOR_BROKEN(op, i, s, {
    const cupid_int lj = work_neighbour(op, w, R, i, s);
    const double *n = S->nrm + 3 * s;
    const double e = work_extension(w, n, li, lj);
    const double t = lps ? S->wb[s] * ((w->a[li] + w->a[lj]) * S->x[s] +
                                       15.0 * (w->b[li] + w->b[lj]) * e)
                         : 0.5 * S->wb[s] / S->x[s] * (w->a[li] + w->a[lj]) * e;
    for (int k = 0; k < 3; k++) g[k] += t * n[k];
  });
}

/* A candidate of the stretch scan: the neighbour exists and the bond is intact. */
static inline int scan_keeps(const struct cupid_pd_operator_private *op, cupid_int i, int s) {
  if (pd_bond_broken(op, i, s)) return 0;
  const int32_t *q = op->grid->ijk + 3 * i, *o = op->st.off + 3 * s;
  return pd_grid_lookup(op->grid, q[0] + o[0], q[1] + o[1], q[2] + o[2]) >= 0;
}

/* The end of a run's dilatation: acc holds sum_s g_s.(u_j - u_i) over the padded stencil,
 * less the ghost bonds (the kernel's ghost_theta); less the broken bonds, theta = 3V/m acc
 * and a = kappa theta / m (into w->a and, if asked, theta). Always inlined, as run_store. */
__attribute__((always_inline)) static inline void
run_theta(const struct cupid_pd_operator_private *op, const pd_work *w, const pd_run *R,
          cupid_int i, int len, double *restrict acc, double *theta) {
  const cupid_int li = work_index(w, R, i);
  if (op->bslot)
    for (int t = 0; t < len; t++)
      if (op->bslot[i + t] >= 0) acc[t] -= broken_dilatation(op, w, R, i + t);
  double *restrict a = w->a + li;
  const double *restrict mi = op->m + i, *restrict ki = op->kappa + i;
  const double V3 = 3.0 * op->V;
  for (int t = 0; t < len; t++) {
    const double th = V3 * acc[t] / mi[t];
    a[t] = ki[t] * th / mi[t];
    acc[t] = th;
  }
  if (theta) memcpy(theta + i, acc, (size_t)len * sizeof(double));
}

/* f = -V^2 sum, the sum with the ghost corrections (the kernel's ghost_force) and less the
 * broken bonds. Always inlined: compiled with each kernel instance's instruction set (the
 * store loop vectorises with it). */
__attribute__((always_inline)) static inline void
run_store(const struct cupid_pd_operator_private *op, const pd_work *w, const pd_run *R,
          cupid_int i, int len, double *restrict fx, double *restrict fy, double *restrict fz,
          double *restrict f) {
  const double V2 = op->V * op->V;
  if (op->bslot)
    for (int t = 0; t < len; t++) {
      if (op->bslot[i + t] < 0) continue;
      double g[3];
      broken_force(op, w, R, i + t, g);
      fx[t] -= g[0];
      fy[t] -= g[1];
      fz[t] -= g[2];
    }
  for (int t = 0; t < len; t++) {
    f[3 * t] = -V2 * fx[t];
    f[3 * t + 1] = -V2 * fy[t];
    f[3 * t + 2] = -V2 * fz[t];
  }
}


/* ---- The kernels, one instance per instruction set (stencil_kernels.h). ---- */

typedef void (*pd_run_kernel)(const struct cupid_pd_operator_private *op, const pd_work *w,
                              const pd_run *R, cupid_int i, int len, double *restrict out);
typedef int (*pd_scan_kernel)(const struct cupid_pd_operator_private *op, const pd_work *w,
                              const pd_run *R, cupid_int i, int len, double lim, pd_hit *hits,
                              int cap);
typedef void (*pd_copy_kernel)(cupid_int len, const double *restrict u, double r0, double r1,
                               double r2, double *restrict x, double *restrict y,
                               double *restrict z);
typedef struct {
  pd_run_kernel dilatation, bond_force, lps_first, lps_second;
  pd_scan_kernel stretch;
  pd_copy_kernel copy;
  int lanes;
} pd_kernel_set;

/* x86-64 with GCC: AVX-512 (8 lanes), AVX2 + FMA (4) and the SSE2 baseline (2), picked at
 * run time; the build itself uses no -march. Elsewhere one portable instance of 4 lanes,
 * which the compiler maps onto whatever vectors the target has. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define PD_MULTI_ISA 1
#pragma GCC push_options
#pragma GCC target("arch=x86-64-v4")
#define PD_KLANES 8
#define PD_KNAME(x) pd_v4_##x
#include "pd/stencil_kernels.h"
#undef PD_KNAME
#undef PD_KLANES
#pragma GCC pop_options
#pragma GCC push_options
#pragma GCC target("arch=x86-64-v3")
#define PD_KLANES 4
#define PD_KNAME(x) pd_v3_##x
#include "pd/stencil_kernels.h"
#undef PD_KNAME
#undef PD_KLANES
#pragma GCC pop_options
#define PD_KLANES 2
#else
#define PD_MULTI_ISA 0
#define PD_KLANES 4
#endif
#define PD_KNAME(x) pd_base_##x
#include "pd/stencil_kernels.h"
#undef PD_KNAME
#undef PD_KLANES

/* The instance for this CPU, or the one pd_stencil_force_isa() or else the environment
 * variable CUPID_PD_ISA asked for (tests, benchmarks: 0 = the CPU's best, 1 = baseline,
 * 3 = AVX2, 4 = AVX-512; one the CPU lacks falls back to the next below). */
static atomic_int pd_isa_forced;

int pd_stencil_force_isa(int level) {
  atomic_store(&pd_isa_forced, level);
  return pd_stencil_kernel_lanes();
}

#if PD_MULTI_ISA
/* The CPU's levels and the environment's cap, read once (every apply asks). */
static atomic_int pd_isa_cpu = -1, pd_isa_env = -1;
#endif

static const pd_kernel_set *kernels_pick(void) {
#if PD_MULTI_ISA
  int cpu = atomic_load(&pd_isa_cpu), env = atomic_load(&pd_isa_env);
  if (cpu < 0) {
    __builtin_cpu_init();
    cpu = __builtin_cpu_supports("x86-64-v4") ? 4 : __builtin_cpu_supports("x86-64-v3") ? 3 : 1;
    atomic_store(&pd_isa_cpu, cpu);
  }
  if (env < 0) { /* the environment's cap, for benchmarks of a whole run */
    const char *e = getenv("CUPID_PD_ISA");
    env = e ? atoi(e) : 0;
    atomic_store(&pd_isa_env, env);
  }
  const int forced = atomic_load(&pd_isa_forced), cap = forced ? forced : env;
  const int level = cap > 0 && cap < cpu ? cap : cpu;
  if (level >= 4) return &pd_v4_kernels;
  if (level >= 3) return &pd_v3_kernels;
#endif
  return &pd_base_kernels;
}

int pd_stencil_kernel_lanes(void) { return kernels_pick()->lanes; }

/* ---- Near-surface nodes without padding: their stored stencil entries, same formulas
 * and order (work arrays indexed by node). ---- */

static void edge_dilatation(const struct cupid_pd_operator_private *op, const pd_work *w,
                            cupid_int i, double *theta) {
  const pd_stencil *S = &op->st;
  const pd_family F = pd_family_of(op, i);
  const cupid_int li = i - w->base;
  double acc = 0.0;
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    if (pd_bond_broken(op, i, s)) continue;
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
    if (pd_bond_broken(op, i, s)) continue;
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

/* ---- Sweeps over a node range: the runs, clipped to it (pd_first_run). ---- */

/* Copy u on the nodes [lo, hi) into the work arrays, with b = mu/m (LPS) or a = c
 * (bond-based); padded, absent cells read 0. The node constants and the zeros are written
 * only when the window or the nodes differ from the last fill: the kernels write a (LPS)
 * at node cells only, so both still hold on every apply of a time loop or a Krylov solve. */
static void work_fill(const struct cupid_pd_operator_private *op, const pd_kernel_set *K,
                      pd_work *w, cupid_int lo, cupid_int hi, const double *u) {
  const int lps = w->b != NULL;
  const cupid_int key[5] = {w->base, w->n, lo, hi, op->gen};
  const int fresh = memcmp(key, w->filled, sizeof key) != 0;
  if (fresh && w->padded) {
    double *arrays[8] = {w->x, w->y, w->z, w->a, w->b, w->gx, w->gy, w->gz};
#pragma omp parallel for schedule(static) if (w->n > 8 * PD_OMP_MIN_NODES)
    for (int k = 0; k < 8; k++)
      if (arrays[k]) memset(arrays[k], 0, (size_t)w->n * sizeof(double));
  }
  /* K annihilates translations (every row depends on differences only), so the copy is
   * shifted by the displacement of the middle node: the ghost corrections then cancel
   * terms of size |u - u_mid| (the variation of u across the range) instead of |u|, e.g.
   * exactly nothing for a rigid translation. */
  const cupid_int mid = lo + (hi - lo) / 2;
  const double r0 = w->padded ? u[3 * mid] : 0.0, r1 = w->padded ? u[3 * mid + 1] : 0.0,
               r2 = w->padded ? u[3 * mid + 2] : 0.0;
  /* By runs: consecutive nodes at consecutive positions, a contiguous copy each. */
  const cupid_int rlo = pd_first_run(op, lo), rhi = pd_first_run(op, hi - 1) + 1;
#pragma omp parallel for schedule(static) if (hi - lo > PD_OMP_MIN_NODES)
  for (cupid_int r = rlo; r < rhi; r++) {
    const pd_run *R = &op->runs[r];
    const cupid_int a = R->i0 > lo ? R->i0 : lo, b = R->i0 + R->len < hi ? R->i0 + R->len : hi;
    const cupid_int q = work_index(w, R, a);
    K->copy(b - a, u + 3 * a, r0, r1, r2, w->x + q, w->y + q, w->z + q);
    if (!fresh) continue;
    for (cupid_int t = 0; t < b - a; t++) {
      if (lps) w->b[q + t] = op->mu[a + t] / op->m[a + t];
      else w->a[q + t] = op->c[a + t];
    }
  }
  memcpy(w->filled, key, sizeof key);
}

/* LPS: PASS_LPS_FIRST (theta and the force without a) then PASS_LPS_SECOND (the a terms),
 * with PASS_DILATATION on nodes whose a is read but whose force is not asked. */
typedef enum { PASS_DILATATION, PASS_LPS_FIRST, PASS_LPS_SECOND, PASS_BOND_FORCE } pd_pass;

/* One pass over the nodes [p, q) (out: f indexed by i - fbase, or theta by node). Inside a
 * parallel region: work-shared; the implicit barrier at the end separates the passes.
 * Dynamic schedule: runs differ in length and in cost (corrections, or family walks). */
static void sweep(const struct cupid_pd_operator_private *op, const pd_work *w,
                  const pd_kernel_set *K, pd_pass pass, cupid_int p, cupid_int q, double *out,
                  cupid_int fbase) {
  if (p >= q) return; /* the same on every thread: none meets the loop's barrier */
  const cupid_int r0 = pd_first_run(op, p), r1 = pd_first_run(op, q);
#pragma omp for schedule(dynamic, 16)
  for (cupid_int r = r0; r < r1 + (r1 < op->nruns && op->runs[r1].i0 < q); r++) {
    const pd_run *R = &op->runs[r];
    const cupid_int a = R->i0 > p ? R->i0 : p, b = R->i0 + R->len < q ? R->i0 + R->len : q;
    const int len = (int)(b - a);
    if (R->full || w->padded) {
      if (pass == PASS_DILATATION) K->dilatation(op, w, R, a, len, out);
      else if (pass == PASS_LPS_FIRST) K->lps_first(op, w, R, a, len, out);
      else if (pass == PASS_LPS_SECOND) K->lps_second(op, w, R, a, len, out + 3 * (a - fbase));
      else K->bond_force(op, w, R, a, len, out + 3 * (a - fbase));
      continue;
    }
    for (cupid_int i = a; i < b; i++) {
      if (pass == PASS_DILATATION || pass == PASS_LPS_FIRST) edge_dilatation(op, w, i, out);
      else edge_force(op, w, i, out + 3 * (i - fbase));
    }
  }
}

/* The padded work window of the nodes [s0, s1) swept: every stencil cell of them (base,
 * length) and the lead that aligns the cells of x = 0 (see pd_work). */
static void padded_window(const struct cupid_pd_operator_private *op, cupid_int s0, cupid_int s1,
                          cupid_int *base, cupid_int *len, int *lead) {
  cupid_int mn = 0, mx = 0;
  for (int s = 0; s < op->st.n; s++) {
    if (op->pclin[s] < mn) mn = op->pclin[s];
    if (op->pclin[s] > mx) mx = op->pclin[s];
  }
  *base = pd_node_pcell(op, s0) + mn;
  *len = pd_node_pcell(op, s1 - 1) + mx + 1 - *base;
  *lead = (int)(((*base - op->pr[0]) % PD_ROW_ALIGN + PD_ROW_ALIGN) % PD_ROW_ALIGN);
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
  int lead = 0;
  if (op->padded) padded_window(op, lps ? lo1 : first, lps ? hi1 : last, &base, &len, &lead);
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
  const pd_kernel_set *K = kernels_pick();
  CUPID_TRY(work_reserve(w, op->padded, base, len, lead, lps));
  work_fill(op, K, w, lo, hi, u);
#pragma omp parallel if (hi - lo > PD_OMP_MIN_NODES)
  {
    if (lps) {
      sweep(op, w, K, PASS_DILATATION, lo1, first, theta, 0);
      sweep(op, w, K, PASS_LPS_FIRST, first, last, theta, 0);
      sweep(op, w, K, PASS_DILATATION, last, hi1, theta, 0);
      sweep(op, w, K, PASS_LPS_SECOND, first, last, f, first);
    } else {
      sweep(op, w, K, PASS_BOND_FORCE, first, last, f, first);
    }
  }
cleanup:
  work_free(&local);
  if (kept) atomic_store(&mop->work_busy, 0);
  return st;
}

/* ---- The stretch scan (fracture.c): candidates of bond breaking on the work arrays ---- */

static int hit_order(const void *a, const void *b) {
  const pd_hit *x = a, *y = b;
  if (x->i != y->i) return (x->i > y->i) - (x->i < y->i);
  return (x->s > y->s) - (x->s < y->s);
}

/* A node of an unpadded grid without a full family: its stored entries s >= n/2. */
static int edge_stretch(const struct cupid_pd_operator_private *op, const pd_work *w, cupid_int i,
                        double lim, pd_hit *hits, int cap) {
  const pd_stencil *S = &op->st;
  const pd_family F = pd_family_of(op, i);
  const cupid_int li = i - w->base;
  int nh = 0;
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    if (s < S->n / 2) continue;
    const cupid_int lj = pd_family_node(op, &F, s) - w->base;
    if (work_extension(w, S->nrm + 3 * s, li, lj) > lim * S->x[s]) {
      if (nh == cap) return -1;
      hits[nh++] = (pd_hit){i, s};
    }
  }
  return nh;
}

typedef struct {
  pd_hit *h;
  cupid_int n, cap;
  int failed;
} hit_list;

static void hits_add(hit_list *L, const pd_hit *h, int n) {
  if (L->n + n > L->cap) {
    cupid_int cap = L->cap ? 2 * L->cap : 1024;
    while (cap < L->n + n) cap *= 2;
    pd_hit *p = realloc(L->h, (size_t)cap * sizeof *p);
    if (!p) {
      L->failed = 1;
      return;
    }
    L->h = p, L->cap = cap;
  }
  memcpy(L->h + L->n, h, (size_t)n * sizeof *h);
  L->n += n;
}

/* The scan reads absent padded cells as NaN, which no comparison finds over a limit: else
 * their zeros (the force kernels' ghost convention) make every lane block at a surface look
 * stretched as soon as |u| exceeds the limit, and each such block is walked node by node
 * (most of the scan's time on the 40^3 bar of bench/fracture_lammps.sh). The cells are listed
 * once per window; scan_absent_zero puts the zeros back, so the next apply's fill stays a copy
 * of u. */
static cupid_status scan_absent_nan(const struct cupid_pd_operator_private *op, pd_work *w) {
  const cupid_int key[3] = {w->base, w->n, w->lead};
  if (memcmp(key, w->absent_key, sizeof key) != 0) {
    unsigned char *present = NULL;
    cupid_free(&w->absent);
    w->n_absent = 0;
    CUPID_CALL(cupid_calloc((size_t)w->n + 1, 1, "PD scan cells", &present));
    for (cupid_int r = 0; r < op->nruns; r++) {
      const pd_run *R = &op->runs[r];
      memset(present + work_index(w, R, R->i0), 1, (size_t)R->len);
    }
    cupid_int count = 0;
    for (cupid_int c = 0; c < w->n; c++) count += !present[c];
    cupid_status st = cupid_malloc((size_t)count + 1, sizeof *w->absent, "PD scan cells", &w->absent);
    for (cupid_int c = 0; c < w->n && st == CUPID_SUCCESS; c++)
      if (!present[c]) w->absent[w->n_absent++] = c;
    cupid_free(&present);
    CUPID_CALL(st);
    memcpy(w->absent_key, key, sizeof key);
  }
  for (cupid_int k = 0; k < w->n_absent; k++) {
    const cupid_int c = w->absent[k];
    w->x[c] = w->y[c] = w->z[c] = NAN;
  }
  return CUPID_SUCCESS;
}

static void scan_absent_zero(pd_work *w) {
  for (cupid_int k = 0; k < w->n_absent; k++) {
    const cupid_int c = w->absent[k];
    w->x[c] = w->y[c] = w->z[c] = 0.0;
  }
}

cupid_status pd_stencil_stretch_scan(const struct cupid_pd_operator_private *op, const double *u,
                                     double lim, pd_hit **hits, cupid_int *n) {
  *hits = NULL, *n = 0;
  const cupid_int nn = op->nnodes;
  if (nn == 0) return CUPID_SUCCESS;
  const int lps = op->model == CUPID_PD_LPS;
  cupid_int base = 0, len = nn;
  int lead = 0;
  if (op->padded) padded_window(op, 0, nn, &base, &len, &lead); /* a whole apply's window */
  struct cupid_pd_operator_private *mop = (struct cupid_pd_operator_private *)op;
  pd_work local = {0}, *w = &local;
  const int kept = !atomic_exchange(&mop->work_busy, 1);
  cupid_status st = CUPID_SUCCESS;
  int nt = 1, nan_cells = 0;
#ifdef _OPENMP
  nt = nn > PD_OMP_MIN_NODES ? omp_get_max_threads() : 1;
#endif
  hit_list *per = calloc((size_t)nt, sizeof *per);
  if (!per) {
    st = CUPID_ERROR(CUPID_ERR_MEMORY, "out of memory for the bond scan");
    goto cleanup;
  }
  if (kept) {
    if (!mop->work) CUPID_TRY(cupid_calloc(1, sizeof(pd_work), "PD stencil work", &mop->work));
    w = mop->work;
  }
  const pd_kernel_set *K = kernels_pick();
  CUPID_TRY(work_reserve(w, op->padded, base, len, lead, lps));
  work_fill(op, K, w, 0, nn, u);
  if (w->padded) {
    CUPID_TRY(scan_absent_nan(op, w));
    nan_cells = 1;
  }
#pragma omp parallel num_threads(nt)
  {
    int tid = 0;
#ifdef _OPENMP
    tid = omp_get_thread_num();
#endif
    pd_hit buf[4096];
#pragma omp for schedule(dynamic, 16)
    for (cupid_int r = 0; r < op->nruns; r++) {
      const pd_run *R = &op->runs[r];
      int got = 0;
      if (R->full || w->padded) {
        got = K->stretch(op, w, R, R->i0, R->len, lim, buf, 4096);
        if (got > 0) hits_add(&per[tid], buf, got);
      } else {
        for (cupid_int i = R->i0; i < R->i0 + R->len; i++) {
          got = edge_stretch(op, w, i, lim, buf, 4096);
          if (got > 0) hits_add(&per[tid], buf, got);
          if (got < 0) break;
        }
      }
      if (got < 0) per[tid].failed = 1; /* more than 4096 in one run: the caller scans */
    }
  }
  cupid_int total = 0;
  int failed = 0;
  for (int t = 0; t < nt; t++) total += per[t].n, failed |= per[t].failed;
  if (failed) { /* a run with too many hits, or no memory: the caller does the plain scan */
    *n = -1;
    goto cleanup;
  }
  CUPID_TRY(cupid_malloc((size_t)total + 1, sizeof **hits, "bond scan hits", hits));
  for (int t = 0; t < nt; t++) {
    if (per[t].n == 0) continue; /* its list was never allocated: no memcpy from NULL */
    memcpy(*hits + *n, per[t].h, (size_t)per[t].n * sizeof **hits);
    *n += per[t].n;
  }
  qsort(*hits, (size_t)*n, sizeof **hits, hit_order); /* the order of the plain scan */
cleanup:
  if (nan_cells) scan_absent_zero(w);
  for (int t = 0; per && t < nt; t++) free(per[t].h);
  free(per);
  work_free(&local);
  if (kept) atomic_store(&mop->work_busy, 0);
  return st;
}
