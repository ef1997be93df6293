/* Private data of the peridynamics subsystem (src/pd); the public API is include/cupid/pd.h. */
#ifndef CUPID_PD_INTERNAL_H
#define CUPID_PD_INTERNAL_H

#include <stdatomic.h>
#include <stdint.h>

#include "cupid/pd.h"

/* Grid: nodes at the centres of the cells of a union of boxes on one lattice.
 * Nodes are numbered in lexicographic order of their cell (i, j, k) with x (i) fastest
 * and z (k) slowest, the same order as the dense index, so node order is monotone in the
 * dense cell index. In 1D the lattice has ncells = {1, ny, 1}. */
struct cupid_pd_grid_private {
  int dim;
  double h;          /* spacing */
  double area;       /* 1D cross-section area */
  double volume;     /* cell volume: h^3 or area*h */
  double origin[3];  /* lowest corner of the lattice */
  cupid_int n[3];    /* cells of the bounding box per axis */
  cupid_int nnodes;
  double *coords;    /* 3 per node */
  int *material;     /* per node */
  int32_t *ijk;      /* lattice position, 3 per node */
  cupid_int *dense;  /* n[0]*n[1]*n[2]: node index of a cell or -1 */
  cupid_pd_grid_partition part; /* place in the whole union (issue 6: slabs for MPI) */
  double *vfrac;     /* per node: its volume over the cell volume (cut cells of a shaped body,
                        cut_volume.c), or NULL: every node has the whole cell */
  double cut_lost;   /* body volume in cut cells with no node around (not given to any) */
};

/* Loops over fewer nodes run on one thread (thread start-up and barriers cost more). */
#define PD_OMP_MIN_NODES 1024

/* Build the grid; on a problem with box b, *bad_box = b and msg holds the reason (no
 * "box b" prefix) so that the caller can report it against the model file. */
cupid_status pd_grid_build(const cupid_pd_grid_options *opts, int n_boxes, const cupid_box *boxes,
                           const int *materials, int *bad_box, char *msg, size_t len,
                           cupid_pd_grid *grid);

/* The cut-cell volumes of a shaped body (cut_volume.c): g->vfrac, left NULL when every node
 * keeps its whole cell. */
cupid_status pd_grid_cut_volumes(struct cupid_pd_grid_private *g, const cupid_pd_grid_options *opts,
                                 int n_boxes, const cupid_box *boxes);

/* Node at lattice position (i, j, k), or -1 outside the union (no bounds assumed). */
static inline cupid_int pd_grid_lookup(const struct cupid_pd_grid_private *g, cupid_int i,
                                       cupid_int j, cupid_int k) {
  if (i < 0 || j < 0 || k < 0 || i >= g->n[0] || j >= g->n[1] || k >= g->n[2]) return -1;
  return g->dense[i + g->n[0] * (j + g->n[1] * k)];
}

/* The fixed integer stencil of a uniform grid: every lattice offset with beta > 0
 * (the node itself excluded), sorted lexicographically (dk, dj, di) so that each node's
 * neighbour list comes out sorted by node index. */
typedef struct {
  int n;            /* offsets */
  int32_t *off;     /* 3 per offset */
  double *x;        /* |xi| */
  double *nrm;      /* unit vector xi/|xi|, 3 per offset */
  double *wb;       /* omega * beta */
  double *wxn;      /* omega * beta * |xi| * n, 3 per offset (dilatation weights) */
} pd_stencil;

cupid_status pd_stencil_build(int dim, double h, double delta, cupid_partial_volume rule,
                              cupid_influence influence, pd_stencil *st);
void pd_stencil_free(pd_stencil *st);

/* The set {a + b : a, b in stencil + {0}} (lexicographic): the columns a row of the
 * assembled LPS matrix can reach. With only_first, the stencil + {0} itself (bond-based). */
cupid_status pd_stencil_sum(const pd_stencil *st, int only_first, int *n, int32_t **off);

/* Bonds in CSR (64-bit offsets): neighbours of node i are nbr[ptr[i] .. ptr[i+1]),
 * sorted by node index, each with its stencil entry. */
cupid_status pd_neighbors_build(const struct cupid_pd_grid_private *g, const pd_stencil *st,
                                cupid_int **ptr, cupid_int **nbr, int32_t **sidx);

/* A run of consecutive nodes at consecutive cells of one x row (with the padded lattice a
 * whole row, else all with full families or all without; full = 1 if all are): nodes
 * i0 .. i0+len-1 at cells c0 .. c0+len-1 (cp0 .. in the padded lattice, see padded below).
 * For every stencil entry s the neighbours of a full run are consecutive nodes too (the
 * cells c + clin[s] all exist and nothing lies between them in cell order), and in the
 * padded lattice the neighbour cells of any run are consecutive, so the stencil kernels
 * sweep a run with contiguous, vectorisable loads. */
typedef struct {
  cupid_int i0, c0, cp0;
  int len, full;
  int ub0, ub1; /* nodes i0 + [ub0, ub1): each with b equal over its whole family (LPS,
                   padded; pd_uniform_build), the run's longest such stretch; else 0, 0 */
} pd_run;

/* A segment of a run's non-full nodes: nodes i0 .. i0+n-1, ranks rank .. rank+n-1 (see
 * cupid_pd_operator_private's gseg). */
typedef struct {
  cupid_int i0;
  int32_t rank, n;
} pd_ghost_seg;

/* Longest run: the kernels keep a run's accumulators on the stack. */
#define PD_RUN_MAX 256

/* The LPS kernels' walk over the stencil's pairs (stencil.c, pd_pair_plan_build): the pairs
 * (s, n-1-s), s < n/2, by chunks of PD_PAIR_CHUNK in stencil order, each chunk's pairs
 * grouped by which components of n_s are nonzero (PD_PAIR_CLASSES: xyz, yz, xz, xy, x, y,
 * z). A class skips the loads and products of its zero components: in a ball of 3 spacings
 * 33 of the 61 pairs lie in a lattice plane or on an axis, and the first pass is bound by
 * those loads and products. On an axis n_s = +-1 (exactly), folded into w1. */
#define PD_PAIR_CHUNK 64 /* pairs whose neighbour offsets are tabled at a time */
#define PD_PAIR_CLASSES 7
typedef struct {
  int n;              /* pairs: st.n / 2 */
  int *s;             /* stencil entry (the + side) of each pair, in walk order */
  int *seg;           /* chunk c's pairs of class q: [seg[c (Q+1) + q], seg[c (Q+1) + q + 1]) */
  double *nrm, *wxn;  /* entry s's n and omega beta |xi| n, 3 per pair */
  double *w1;         /* omega beta |xi| (times n's sign on an axis) */
  double *nw;         /* 15 omega beta n (times n's sign on an axis), 3 per pair */
  cupid_int *pp, *pm; /* padded cell offsets of the + and - neighbours */
} pd_pair_plan;

struct cupid_pd_operator_private {
  const struct cupid_pd_grid_private *grid; /* borrowed: must outlive the operator */
  cupid_pd_model_kind model;
  cupid_influence influence;
  cupid_partial_volume rule;
  double delta, h, V;
  double m_full, S_full; /* a full family's sum omega beta |xi|^2 V and omega beta |xi| V */
  int dim;
  cupid_int nnodes;
  pd_stencil st;
  cupid_int *clin;        /* dense-cell offset of each stencil entry (the lattice neighbour) */
  cupid_int nbonds;       /* bonds (ordered pairs) */
  /* Families without per-bond storage for the bulk: a node whose whole stencil lies in the
   * grid ("full", the interior) stores nothing, the others (near the surface) the stencil
   * entries present, fidx[fptr[i] .. fptr[i+1]) (empty for full nodes). A neighbour is
   * dense[cell(i) + clin[s]] (pd_family_*). */
  unsigned char *full;
  cupid_int *fptr;
  int32_t *fidx;
  pd_run *runs;           /* every node, in runs of at most PD_RUN_MAX, ascending */
  cupid_int nruns;
  /* Padded lattice: the bounding box grown by the stencil reach r[a] on each side, so that
   * every stencil neighbour of every node has a cell index (pclin[s] its offset). With
   * padded = 1 the stencil kernels work on cell-indexed copies of the data in which absent
   * cells read 0 (their bonds corrected per node); else (a sparse union, whose padded box
   * would hold more than PD_PAD_RATIO cells a node) near-surface nodes walk their families. */
  int padded;
  /* Ghost-bond corrections of the padded kernels for non-full nodes (ghosts.c): records of
   * PD_GHOST_STRIDE values stored by component, ncorr[PD_GHOST_SLACK + c gstride + k]: the
   * sum over the node's absent entries of w n n^T (c = 0..5: xx yy zz yz xz xy; w = 15 omega
   * beta for LPS, omega beta / (2|xi|) bond-based), then the present entries' sum of g
   * (gself, c = 6..8). The non-full nodes of run r come in segments of consecutive nodes,
   * gseg[gptr[r] .. gptr[r + 1]); a segment's records are consecutive from its rank, shared
   * by every segment with the same content. The kernels correct a segment a lane block at a
   * time (node by node behind a branch on each node's flag, mispredicted at every segment's
   * end, and from 72 bytes a node, the corrections cost an eighth of an explicit LPS step). */
  double *ncorr;
  cupid_int gstride; /* the records + PD_GHOST_SLACK: a lane block around a segment's
                        records stays inside the arrays */
  cupid_int *gptr, nseg;
  pd_ghost_seg *gseg;
  cupid_int pn[3];        /* padded cells per axis */
  int32_t pr[3];          /* reach per axis */
  cupid_int *pclin;
  cupid_int *pclin_opp;   /* pclin[n-1-s]: the offset of entry s's opposite (the kernels' pairs) */
  pd_pair_plan plan;      /* the LPS passes' order of the pairs */
  /* Work arrays of the stencil path, kept between applies (a fresh allocation per apply
   * costs page faults comparable to the apply); one apply at a time takes them, a
   * concurrent one allocates its own. */
  void *work;
  atomic_int work_busy;
  /* Hook: when set, apply/apply_range use the bond-list kernels (pd_lps_*, pd_bond_apply)
   * on the explicit bond lists below, e.g. for per-bond modifications of the pair terms
   * that the uniform stencil cannot express. Set it through pd_operator_use_bond_lists(). */
  int stencil_off;
  /* Explicit bond lists in CSR (neighbour and stencil entry per bond, 12 bytes a bond):
   * NULL unless pd_operator_use_bond_lists() built them (or the grid is 1D). */
  cupid_int *bptr, *bnbr;
  int32_t *bst;
  double *m;              /* weighted volume (Eq. 18) */
  double *kappa;          /* 3K - 5mu per node (LPS) */
  double *mu;             /* shear modulus per node */
  double *c;              /* micromodulus per node (bond-based) */
  double *gself;          /* sum_j omega beta x D_ij n_ij, 3 per node (LPS: -dtheta_i/du_i m_i/(3V)) */
  cupid_surface_correction surface;
  double *sf;             /* surface factors, PD_SF per node (d[3], g[3], q[3]), or NULL */
  /* Node volumes over V (the grid's cut cells, cut_volume.c; borrowed), or NULL: all 1. Node
   * i's energy is V phi_i W_i and its family sums weigh neighbour j by V phi_j (m_i, theta_i),
   * so every bond term of K carries phi_i phi_j (pd_phi). Like the surface factors, they run on
   * the bond lists (the stencil kernels assume equal volumes). */
  const double *phi;
  /* Broken bonds (fracture.c): the families stay the geometric ones and a node with broken
   * bonds gets a slot (bslot[i] >= 0, else -1) holding a mask of its broken stencil entries
   * (bwords 64-bit words, bit s = entry s), their count and the sum of their dilatation
   * weights wxn (3). Kept symmetric: (i, s) is broken iff (j, n-1-s) is. Every family walker
   * skips broken entries; the stencil kernels sweep the whole stencil and subtract the broken
   * bonds of the nodes that have some (pd_broken_*). m holds the intact families' sums, and
   * gself stays the geometric one (the padded kernels' ghost correction needs it; the intact
   * sum is pd_gself_intact). NULL until a bond is removed. */
  int32_t *bslot;
  uint64_t *bmask;
  double *bgsum;
  int *bcount;
  int *bpre;              /* of bcount, the entries pre-cracks removed */
  int bwords;
  int32_t nslots, slot_cap;
  cupid_int nbroken;      /* bonds (unordered pairs) removed: pre-cracks and breaking */
  cupid_int gen;          /* bumped when m changes (the stencil work arrays cache mu/m) */
  /* The nodes whose bonds were removed since cupid_pd_operator_take_changed() last read them
   * (both ends of each bond; repeats allowed), so that a caller that keeps an assembled K can
   * assemble again only their rows (quasi-static growth). changed_all: the record is lost (out
   * of memory) or every row changed (the moduli scaled). Kept from the first take on (an
   * explicit run, which never reads it, does not grow it). */
  cupid_int *changed;
  size_t n_changed, changed_cap;
  int changed_all, changed_on;
};

/* 1 if the bond of node i at stencil entry s is broken. */
static inline int pd_bond_broken(const struct cupid_pd_operator_private *op, cupid_int i, int s) {
  if (!op->bslot) return 0;
  const int32_t k = op->bslot[i];
  if (k < 0) return 0;
  return (int)((op->bmask[(size_t)k * (size_t)op->bwords + (size_t)(s >> 6)] >> (s & 63)) & 1u);
}

/* The dilatation self weight of node i over its intact bonds: gself minus the broken
 * entries' wxn (tmp holds it when they differ). */
static inline const double *pd_gself_intact(const struct cupid_pd_operator_private *op,
                                            cupid_int i, double tmp[3]) {
  if (!op->bslot || op->bslot[i] < 0) return op->gself + 3 * i;
  const double *b = op->bgsum + 3 * (size_t)op->bslot[i];
  for (int c = 0; c < 3; c++) tmp[c] = op->gself[3 * i + c] - b[c];
  return tmp;
}

/* Fracture state of the operator (fracture.c). */
void pd_fracture_free(struct cupid_pd_operator_private *op);
/* 1: the stretch criterion scans bond by bond instead of the stencil path's vectorised scan
 * (tests compare the two). */
void pd_fracture_force_plain_scan(int on);

/* Surface factors per node: d (dilatation), g and q (deviatoric or pair energy). */
#define PD_SF 9

/* Surface factors (surface.c): fills op->sf (and, for LPS, rebuilds op->gself with them). */
cupid_status pd_surface_factors(struct cupid_pd_operator_private *op);

/* Factors of bond i -> j along n (surface.c): D_ij multiplies the bond in theta_i, G_ij in
 * node i's deviatoric (bond-based: pair) energy; each node's own factors as the forms
 * D_ij = sum_k d_ik n_k^2, G_ij = sum_k (g_ik n_k^2 + q_ik n_k^4). F = {D_ij, D_ji, G_ij, G_ji},
 * all 1 without a correction. */
static inline void pd_surface_bond(const struct cupid_pd_operator_private *op, cupid_int i,
                                   cupid_int j, const double *n, double F[4]) {
  if (!op->sf) {
    F[0] = F[1] = F[2] = F[3] = 1.0;
    return;
  }
  const double *a = op->sf + PD_SF * i, *b = op->sf + PD_SF * j;
  const double n0 = n[0] * n[0], n1 = n[1] * n[1], n2 = n[2] * n[2];
  const double q0 = n0 * n0, q1 = n1 * n1, q2 = n2 * n2;
  F[0] = a[0] * n0 + a[1] * n1 + a[2] * n2;
  F[1] = b[0] * n0 + b[1] * n1 + b[2] * n2;
  F[2] = a[3] * n0 + a[4] * n1 + a[5] * n2 + a[6] * q0 + a[7] * q1 + a[8] * q2;
  F[3] = b[3] * n0 + b[4] * n1 + b[5] * n2 + b[6] * q0 + b[7] * q1 + b[8] * q2;
}

/* Dense cell index of node i. */
static inline cupid_int pd_node_cell(const struct cupid_pd_grid_private *g, cupid_int i) {
  const int32_t *q = g->ijk + 3 * i;
  return q[0] + g->n[0] * (q[1] + g->n[1] * (cupid_int)q[2]);
}

/* The family of a node: its stencil entries (all of them for a full node) and its cell.
 *   pd_family F = pd_family_of(op, i);
 *   for (int q = 0; q < F.n; q++) { int s = pd_family_entry(&F, q);
 *                                   cupid_int j = pd_family_node(op, &F, s); ... }
 * Entries come in stencil order, i.e. neighbours ascending by node index. */
typedef struct {
  const int32_t *s; /* NULL for a full family */
  int n;
  cupid_int cell;
} pd_family;

static inline pd_family pd_family_of(const struct cupid_pd_operator_private *op, cupid_int i) {
  pd_family F;
  F.cell = pd_node_cell(op->grid, i);
  if (op->full[i]) {
    F.s = NULL;
    F.n = op->st.n;
  } else {
    F.s = op->fidx + op->fptr[i];
    F.n = (int)(op->fptr[i + 1] - op->fptr[i]);
  }
  return F;
}

static inline int pd_family_entry(const pd_family *F, int q) { return F->s ? F->s[q] : q; }

static inline cupid_int pd_family_node(const struct cupid_pd_operator_private *op,
                                       const pd_family *F, int s) {
  return op->grid->dense[F->cell + op->clin[s]];
}

#define PD_GHOST_STRIDE 9
#define PD_GHOST_SLACK 8 /* the widest lane block (stencil.c, PD_LANES_MAX) */
#define PD_PAD_RATIO 8
/* Padded rows hold a multiple of PD_ROW_ALIGN cells (64 bytes of doubles), so that cells of
 * the same x are equally aligned in every row (stencil.c). */
#define PD_ROW_ALIGN 8

/* Padded cell index of node i. */
static inline cupid_int pd_node_pcell(const struct cupid_pd_operator_private *op, cupid_int i) {
  const int32_t *q = op->grid->ijk + 3 * i;
  return (q[0] + op->pr[0]) + op->pn[0] * ((q[1] + op->pr[1]) + op->pn[1] * (cupid_int)(q[2] + op->pr[2]));
}

/* The first run whose last node is >= p (binary search: runs ascend and cover every node,
 * so run r ends where run r + 1 starts); nruns if none. */
static inline cupid_int pd_first_run(const struct cupid_pd_operator_private *op, cupid_int p) {
  cupid_int a = 0, b = op->nruns;
  while (a < b) {
    const cupid_int m = a + (b - a) / 2;
    if (op->runs[m].i0 + op->runs[m].len <= p) a = m + 1;
    else b = m;
  }
  return a;
}

/* Build the families (full flags, near-surface lists, runs, padding) of the operator. */
cupid_status pd_families_build(struct cupid_pd_operator_private *op);

/* The ghost-bond corrections: segments and records (ghosts.c), after the node data. */
cupid_status pd_ghosts_build(struct cupid_pd_operator_private *op);

/* The runs' stretches of uniform b (pd_run ub0, ub1; uniform.c), after the node data; and
 * node i with its family out of them (i's m changed: a bond of it was removed). */
cupid_status pd_uniform_build(struct cupid_pd_operator_private *op);
void pd_uniform_exclude(struct cupid_pd_operator_private *op, cupid_int i);

/* The rows [first, last) of the assembled K (cupid_pd_operator_assemble() is all of them):
 * nrows = last - first, ncols = nodes, each row as the whole assembly has it. Tests compare
 * the matrix-free products with it on grids whose whole K would not fit. */
cupid_status pd_assemble_rows(const struct cupid_pd_operator_private *op, cupid_int first,
                              cupid_int last, cupid_csr *K);

/* Record that the rows of nodes i and j changed (a bond between them removed). */
void pd_record_changed(struct cupid_pd_operator_private *op, cupid_int i, cupid_int j);

/* Build the explicit bond lists (if not there yet) and switch apply to the bond-list
 * kernels (stencil_off = 1). Not thread-safe: call before sharing the operator. */
cupid_status pd_operator_use_bond_lists(struct cupid_pd_operator_private *op);

/* Stencil path (stencil.c): rows [first, last) of f = K u (f indexed by i - first), u read
 * on the dependency range only; theta (indexed by node, may be NULL) receives the LPS
 * dilatations computed on the way (the rows' neighbours). */
cupid_status pd_stencil_apply(const struct cupid_pd_operator_private *op, cupid_int first,
                              cupid_int last, const double *u, double *f, double *theta);
/* A bond found by a scan: node and stencil entry. */
typedef struct {
  cupid_int i;
  int s;
} pd_hit;

/* The stretch scan of the stencil path (fracture.c's candidates): the bonds (i, s >= n/2)
 * whose extension at u, from the kernels' shifted copies, exceeds lim |xi_s|, in ascending
 * (i, s) order; the list may hold absent neighbours (padded cells) and broken bonds, which the
 * caller drops while it confirms each on u itself. *hits: cupid_free() it. *n = -1: the scan
 * gave up (a run with too many candidates): scan bond by bond instead. */
cupid_status pd_stencil_stretch_scan(const struct cupid_pd_operator_private *op, const double *u,
                                     double lim, pd_hit **hits, cupid_int *n);

/* Free the kept work arrays (operator destroy). */
void pd_stencil_work_free(struct cupid_pd_operator_private *op);
/* The pair plan of the stencil and its padded offsets (pd_families_build, after pclin). */
cupid_status pd_pair_plan_build(struct cupid_pd_operator_private *op);
void pd_pair_plan_free(pd_pair_plan *P);
/* The stencil kernels come in one instance per x86-64 instruction set (AVX-512, AVX2,
 * baseline), the CPU's best picked at run time. pd_stencil_force_isa(level) caps the choice
 * for the whole process (0: the CPU's best; 1 baseline, 3 AVX2, 4 AVX-512), so that tests
 * check every instance the machine can run and benchmarks can compare them; both return
 * the lanes (nodes per vector) of the instance now picked. Also read from CUPID_PD_ISA. */
int pd_stencil_force_isa(int level);
int pd_stencil_kernel_lanes(void);

/* Smallest and largest+1 neighbour index over the nodes [first, last) (themselves included). */
void pd_neighbour_span(const struct cupid_pd_operator_private *op, cupid_int first, cupid_int last,
                       cupid_int *lo, cupid_int *hi);

/* Node i's volume over V (1 without cut cells). */
static inline double pd_phi(const struct cupid_pd_operator_private *op, cupid_int i) {
  return op->phi ? op->phi[i] : 1.0;
}

/* Bond-based pair coefficient c_ij omega beta V^2 / |xi| and LPS pair coefficient
 * 15 (mu_i/m_i + mu_j/m_j) omega beta V^2: the stiffness of the bond spring along n (times
 * phi_i phi_j with cut cells). */
static inline double pd_pair_coefficient(const struct cupid_pd_operator_private *op,
                                         cupid_int i, cupid_int j, int s) {
  const double V2 = op->phi ? op->V * op->V * op->phi[i] * op->phi[j] : op->V * op->V;
  if (op->sf) { /* the surface factors G_ij, G_ji weigh the two nodes' energies */
    double F[4];
    pd_surface_bond(op, i, j, op->st.nrm + 3 * s, F);
    if (op->model == CUPID_PD_BOND)
      return 0.25 * (op->c[i] + op->c[j]) * (F[2] + F[3]) * op->st.wb[s] * V2 / op->st.x[s];
    return 15.0 * (op->mu[i] / op->m[i] * F[2] + op->mu[j] / op->m[j] * F[3]) * op->st.wb[s] * V2;
  }
  if (op->model == CUPID_PD_BOND)
    return 0.5 * (op->c[i] + op->c[j]) * op->st.wb[s] * V2 / op->st.x[s];
  return 15.0 * (op->mu[i] / op->m[i] + op->mu[j] / op->m[j]) * op->st.wb[s] * V2;
}

/* Model kernels (lps.c, bond.c): u, f 3 per node, sigma 6 per node.
 * Bond-list range kernels (need op->bptr, see pd_operator_use_bond_lists): nodes
 * [first, last); theta is indexed by global node, f by i - first. Energy and stress walk
 * the families (any storage). */
void pd_lps_dilatation(const struct cupid_pd_operator_private *op, cupid_int first, cupid_int last,
                       const double *u, double *theta);
void pd_lps_apply(const struct cupid_pd_operator_private *op, cupid_int first, cupid_int last,
                  const double *u, const double *theta, double *f);
double pd_lps_energy(const struct cupid_pd_operator_private *op, const double *u,
                     const double *theta);
void pd_lps_stress(const struct cupid_pd_operator_private *op, const double *u, const double *theta,
                   double *sigma);
void pd_bond_apply(const struct cupid_pd_operator_private *op, cupid_int first, cupid_int last,
                   const double *u, double *f);
double pd_bond_energy(const struct cupid_pd_operator_private *op, const double *u);
void pd_bond_stress(const struct cupid_pd_operator_private *op, const double *u, double *sigma);

/* Bond extension e_ij = n_ij . (u_j - u_i) (Eq. 17 linearised). */
static inline double pd_extension(const double *n, const double *u, cupid_int i, cupid_int j) {
  return n[0] * (u[3 * j] - u[3 * i]) + n[1] * (u[3 * j + 1] - u[3 * i + 1]) +
         n[2] * (u[3 * j + 2] - u[3 * i + 2]);
}

#endif
