/* Linearised LPS (paper 000 Eqs. 16-21) with per-node constants: dilatation, matrix-free
 * force on explicit bond lists (a gather over each node's bonds, so no atomics; the
 * reference and fallback of the stencil kernels in stencil.c), energy and nodal stress
 * (over the families, any storage). */
#include "pd/pd_internal.h"

/* theta_i = 3/m_i sum_j omega x D_ij e beta V phi_j (Eq. 19, e from Eq. 17; D_ij the surface factor,
 * 1 without a correction), on the bond lists when they exist (the bond-list path; always with
 * a correction), else on the families. The kernel is instantiated with corr = 0 and 1 so that
 * the uncorrected loop carries no factor work. */
static inline void lps_dilatation(const struct cupid_pd_operator_private *op, cupid_int first,
                                  cupid_int last, const double *u, double *theta, const int corr) {
  const pd_stencil *S = &op->st;
  if (!op->bptr) { /* no correction here: operator_create builds bond lists for one */
#pragma omp parallel for schedule(static) if (last - first > PD_OMP_MIN_NODES)
    for (cupid_int i = first; i < last; i++) {
      const pd_family F = pd_family_of(op, i);
      double t = 0.0;
      for (int q = 0; q < F.n; q++) {
        const int s = pd_family_entry(&F, q);
        if (pd_bond_broken(op, i, s)) continue;
        const cupid_int j = pd_family_node(op, &F, s);
        t += S->wb[s] * S->x[s] * pd_phi(op, j) * pd_extension(S->nrm + 3 * s, u, i, j);
      }
      theta[i] = 3.0 * op->V * t / op->m[i];
    }
    return;
  }
#pragma omp parallel for schedule(static) if (last - first > PD_OMP_MIN_NODES)
  for (cupid_int i = first; i < last; i++) {
    double t = 0.0;
    for (cupid_int b = op->bptr[i]; b < op->bptr[i + 1]; b++) {
      const cupid_int j = op->bnbr[b];
      const int s = op->bst[b];
      if (pd_bond_broken(op, i, s)) continue;
      double F[4] = {1.0, 1.0, 1.0, 1.0};
      if (corr) pd_surface_bond(op, i, j, S->nrm + 3 * s, F);
      t += S->wb[s] * S->x[s] * F[0] * pd_phi(op, j) * pd_extension(S->nrm + 3 * s, u, i, j);
    }
    theta[i] = 3.0 * op->V * t / op->m[i];
  }
}

void pd_lps_dilatation(const struct cupid_pd_operator_private *op, cupid_int first, cupid_int last,
                       const double *u, double *theta) {
  if (op->sf)
    lps_dilatation(op, first, last, u, theta, 1);
  else
    lps_dilatation(op, first, last, u, theta, 0);
}

/* (K u)_i = -sum_j beta V^2 omega [ kappa_i x theta_i/m_i + kappa_j x theta_j/m_j
 *                                   + 15 (mu_i/m_i + mu_j/m_j) e_ij ] n_ij,
 * i.e. -(T_ij - T_ji) beta V^2 of Eq. 21 with T of Eq. 20, kappa = 3K - 5mu. With a surface
 * correction the i terms carry D_ij, G_ij and the j terms D_ji, G_ji (the gradient of the
 * corrected energy); with cut cells every term phi_i phi_j. */
static inline void lps_apply(const struct cupid_pd_operator_private *op, cupid_int first,
                             cupid_int last, const double *u, const double *theta, double *f,
                             const int corr) {
  const pd_stencil *S = &op->st;
  const double V2 = op->V * op->V;
#pragma omp parallel for schedule(static) if (last - first > PD_OMP_MIN_NODES)
  for (cupid_int i = first; i < last; i++) {
    const double ai = op->kappa[i] * theta[i] / op->m[i], bi = op->mu[i] / op->m[i];
    double fi[3] = {0, 0, 0};
    for (cupid_int b = op->bptr[i]; b < op->bptr[i + 1]; b++) {
      const cupid_int j = op->bnbr[b];
      const int s = op->bst[b];
      if (pd_bond_broken(op, i, s)) continue;
      const double *n = S->nrm + 3 * s;
      const double aj = op->kappa[j] * theta[j] / op->m[j], bj = op->mu[j] / op->m[j];
      double F[4] = {1.0, 1.0, 1.0, 1.0};
      if (corr) pd_surface_bond(op, i, j, n, F);
      const double t = S->wb[s] * pd_phi(op, j) *
                       ((ai * F[0] + aj * F[1]) * S->x[s] +
                        15.0 * (bi * F[2] + bj * F[3]) * pd_extension(n, u, i, j));
      for (int c = 0; c < 3; c++) fi[c] += t * n[c];
    }
    const double Vi = V2 * pd_phi(op, i);
    for (int c = 0; c < 3; c++) f[3 * (i - first) + c] = -Vi * fi[c];
  }
}

void pd_lps_apply(const struct cupid_pd_operator_private *op, cupid_int first, cupid_int last,
                  const double *u, const double *theta, double *f) {
  if (op->sf)
    lps_apply(op, first, last, u, theta, f, 1);
  else
    lps_apply(op, first, last, u, theta, f, 0);
}

/* E = sum_i V phi_i [ kappa_i/6 theta_i^2 + 15 mu_i/(2 m_i) sum_j omega G_ij e^2 beta V phi_j ]. */
double pd_lps_energy(const struct cupid_pd_operator_private *op, const double *u,
                     const double *theta) {
  const pd_stencil *S = &op->st;
  double E = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : E) if (op->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < op->nnodes; i++) {
    double q = 0.0;
    const pd_family F = pd_family_of(op, i);
    for (int k = 0; k < F.n; k++) {
      const int s = pd_family_entry(&F, k);
      if (pd_bond_broken(op, i, s)) continue;
      const cupid_int j = pd_family_node(op, &F, s);
      const double e = pd_extension(S->nrm + 3 * s, u, i, j);
      double sfb[4];
      pd_surface_bond(op, i, j, S->nrm + 3 * s, sfb);
      q += S->wb[s] * sfb[2] * pd_phi(op, j) * e * e;
    }
    E += op->V * pd_phi(op, i) *
         (op->kappa[i] / 6.0 * theta[i] * theta[i] + 7.5 * op->mu[i] / op->m[i] * q * op->V);
  }
  return E;
}

/* sigma_i = sum_j T_ij (x) xi_ij beta V phi_j with T_ij = omega/m_i (kappa_i theta_i x + 15 mu_i e) n
 * (Eq. 20; with a surface correction D_ij on the first term and G_ij on the second: the
 * derivative of node i's corrected energy by e_ij); T is along n and xi = x n, so sigma is
 * symmetric. Order xx yy zz yz xz xy. */
void pd_lps_stress(const struct cupid_pd_operator_private *op, const double *u, const double *theta,
                   double *sigma) {
  const pd_stencil *S = &op->st;
#pragma omp parallel for schedule(static) if (op->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < op->nnodes; i++) {
    double sg[6] = {0, 0, 0, 0, 0, 0};
    const pd_family F = pd_family_of(op, i);
    for (int k = 0; k < F.n; k++) {
      const int s = pd_family_entry(&F, k);
      if (pd_bond_broken(op, i, s)) continue;
      const double *n = S->nrm + 3 * s;
      const double x = S->x[s];
      const cupid_int j = pd_family_node(op, &F, s);
      const double e = pd_extension(n, u, i, j);
      double sfb[4];
      pd_surface_bond(op, i, j, n, sfb);
      const double t = S->wb[s] * pd_phi(op, j) * x *
                       (op->kappa[i] * theta[i] * x * sfb[0] + 15.0 * op->mu[i] * e * sfb[2]);
      sg[0] += t * n[0] * n[0];
      sg[1] += t * n[1] * n[1];
      sg[2] += t * n[2] * n[2];
      sg[3] += t * n[1] * n[2];
      sg[4] += t * n[0] * n[2];
      sg[5] += t * n[0] * n[1];
    }
    for (int c = 0; c < 6; c++) sigma[6 * i + c] = sg[c] * op->V / op->m[i];
  }
}
