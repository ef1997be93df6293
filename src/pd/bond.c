/* Linearised bond-based micro-elastic PD (paper 004 section 2.2): pair forces along the
 * bond, c_ij = (c_i + c_j)/2 with c calibrated on the full discrete family (operator.c). */
#include "pd/pd_internal.h"

/* (K u)_i = -sum_j c_ij omega beta V^2 (e_ij / x_ij) n_ij. */
void pd_bond_apply(const struct cupid_pd_operator_private *op, cupid_int first, cupid_int last,
                   const double *u, double *f) {
  const pd_stencil *S = &op->st;
#pragma omp parallel for schedule(static) if (last - first > PD_OMP_MIN_NODES)
  for (cupid_int i = first; i < last; i++) {
    double fi[3] = {0, 0, 0};
    for (cupid_int b = op->bptr[i]; b < op->bptr[i + 1]; b++) {
      const cupid_int j = op->bnbr[b];
      const int s = op->bst[b];
      if (pd_bond_broken(op, i, s)) continue;
      const double *n = S->nrm + 3 * s;
      const double t = pd_pair_coefficient(op, i, j, s) * pd_extension(n, u, i, j);
      for (int c = 0; c < 3; c++) fi[c] += t * n[c];
    }
    for (int c = 0; c < 3; c++) f[3 * (i - first) + c] = -fi[c];
  }
}

/* E = sum_i V phi_i/4 sum_j c_ij omega beta V phi_j e^2 / x (each pair appears twice; with a
 * surface correction times (G_ij + G_ji)/2; both folded into the pair coefficient). */
double pd_bond_energy(const struct cupid_pd_operator_private *op, const double *u) {
  const pd_stencil *S = &op->st;
  double E = 0.0;
#pragma omp parallel for schedule(static) if (op->nnodes > PD_OMP_MIN_NODES) reduction(+ : E)
  for (cupid_int i = 0; i < op->nnodes; i++) {
    const pd_family F = pd_family_of(op, i);
    for (int q = 0; q < F.n; q++) {
      const int s = pd_family_entry(&F, q);
      if (pd_bond_broken(op, i, s)) continue;
      const cupid_int j = pd_family_node(op, &F, s);
      const double e = pd_extension(S->nrm + 3 * s, u, i, j);
      E += 0.25 * pd_pair_coefficient(op, i, j, s) * e * e;
    }
  }
  return E;
}

/* sigma_i = 1/2 sum_j f_ij (x) xi_ij beta V phi_j, f_ij = c_ij omega (e/x) n the pair force
 * density (times (G_ij + G_ji)/2 with a surface correction): 1/2 V sum_j c_ij omega beta e n (x) n. */
void pd_bond_stress(const struct cupid_pd_operator_private *op, const double *u, double *sigma) {
  const pd_stencil *S = &op->st;
#pragma omp parallel for schedule(static) if (op->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < op->nnodes; i++) {
    double sg[6] = {0, 0, 0, 0, 0, 0};
    const pd_family F = pd_family_of(op, i);
    for (int q = 0; q < F.n; q++) {
      const int s = pd_family_entry(&F, q);
      if (pd_bond_broken(op, i, s)) continue;
      const cupid_int j = pd_family_node(op, &F, s);
      const double *n = S->nrm + 3 * s;
      double sfb[4];
      pd_surface_bond(op, i, j, n, sfb);
      const double t = 0.25 * (op->c[i] + op->c[j]) * (sfb[2] + sfb[3]) * S->wb[s] * pd_phi(op, j) *
                       pd_extension(n, u, i, j);
      sg[0] += t * n[0] * n[0];
      sg[1] += t * n[1] * n[1];
      sg[2] += t * n[2] * n[2];
      sg[3] += t * n[1] * n[2];
      sg[4] += t * n[0] * n[2];
      sg[5] += t * n[0] * n[1];
    }
    for (int c = 0; c < 6; c++) sigma[6 * i + c] = 0.5 * op->V * sg[c];
  }
}
