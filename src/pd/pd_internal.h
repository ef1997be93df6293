/* Private data of the peridynamics subsystem (src/pd); the public API is include/cupid/pd.h. */
#ifndef CUPID_PD_INTERNAL_H
#define CUPID_PD_INTERNAL_H

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
};

/* Loops over fewer nodes run on one thread (thread start-up and barriers cost more). */
#define PD_OMP_MIN_NODES 1024

/* Build the grid; on a problem with box b, *bad_box = b and msg holds the reason (no
 * "box b" prefix) so that the caller can report it against the model file. */
cupid_status pd_grid_build(const cupid_pd_grid_options *opts, int n_boxes, const cupid_box *boxes,
                           const int *materials, int *bad_box, char *msg, size_t len,
                           cupid_pd_grid *grid);

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

struct cupid_pd_operator_private {
  const struct cupid_pd_grid_private *grid; /* borrowed: must outlive the operator */
  cupid_pd_model_kind model;
  cupid_influence influence;
  cupid_partial_volume rule;
  double delta, h, V;
  int dim;
  cupid_int nnodes;
  pd_stencil st;
  cupid_int *bptr, *bnbr; /* bonds, CSR */
  int32_t *bst;           /* stencil entry of each bond */
  double *m;              /* weighted volume (Eq. 18) */
  double *kappa;          /* 3K - 5mu per node (LPS) */
  double *mu;             /* shear modulus per node */
  double *c;              /* micromodulus per node (bond-based) */
  double *gself;          /* sum_j omega beta x D_ij n_ij, 3 per node (LPS: -dtheta_i/du_i m_i/(3V)) */
  cupid_surface_correction surface;
  double *sf;             /* surface factors, PD_SF per node (d[3], g[3], q[3]), or NULL */
};

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

/* Bond-based pair coefficient c_ij omega beta V^2 / |xi| and LPS pair coefficient
 * 15 (mu_i/m_i + mu_j/m_j) omega beta V^2: the stiffness of the bond spring along n. */
static inline double pd_pair_coefficient(const struct cupid_pd_operator_private *op,
                                         cupid_int i, cupid_int j, int s) {
  const double V2 = op->V * op->V;
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

/* Model kernels (lps.c, bond.c): u, f 3 per node, sigma 6 per node. */
/* Range kernels: nodes [first, last); theta is indexed by global node, f by i - first. */
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
