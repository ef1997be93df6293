/* Surface-effect correction of the PD operator: the energy method (Le & Bobaru 2018, Comput.
 * Mech. 61:499), split for the state-based model into a dilatation and a deviatoric part as
 * Madenci & Oterkus do (Peridynamic Theory and Its Applications, 2014, surface effects).
 *
 * A node near a free surface has a truncated family, so its PD sums do not reproduce the
 * continuum values under a uniform strain (LPS: harder along the surface). The corrected LPS
 * energy of node i (the operator is its gradient, lps.c) is
 *   W_i = kappa_i/6 theta_i^2 + 15 mu_i/(2 m_i) sum_j omega G_ij e_ij^2 beta V,
 *   theta_i = 3/m_i sum_j omega D_ij x e_ij beta V,
 * with per-bond factors from each node's own factors (n = the bond direction)
 *   D_ij = sum_k d_ik n_k^2,   G_ij = sum_k (g_ik n_k^2 + q_ik n_k^4),
 * fitted per node (c_j = omega beta V x^2):
 *  - d (3x3 solve): theta_i exact under the uniaxial strains along x, y, z, hence under every
 *    normal strain: sum_j c_j D_ij n_k^2 = m_i/3;
 *  - g, q (6x6 solve): the deviatoric energy is the isotropic continuum one,
 *    15 mu/(2 m_i) m_i/15 ((tr eps)^2 + 2 eps:eps), under every normal strain:
 *    sum_j c_j G_ij n_k^2 n_l^2 = m_i (1 + 2 delta_kl)/15 for the six pairs k <= l.
 * So every node has the continuum energy under any normal strain (uniaxial stress along an
 * axis with the right lateral contraction included: the state of bars and beams). Where the
 * 6x6 fit is singular or gives G <= 0 on a bond, g alone (q = 0, 3x3 solve) is fitted to the
 * uniaxial stress states along x, y, z with the node's nu; where a 3x3 fit is singular or not
 * positive, the per-axis ratios target / sum (Madenci & Oterkus). The targets are the continuum
 * values, not the full discrete stencil's, so the fit also removes the bulk quadrature error
 * of normal strains (PDLAMMPS with Gaussian influence is ~7% soft in the bulk for uniaxial
 * stress); shear energies are not fitted. In the bulk d = 1 exactly for every partial-volume
 * rule (cubic symmetry: sum c n n^T = m/3 I), G = 1 to the quadrature error of the rule
 * (EXACT, m = 3: deep rows change by 1e-4).
 *
 * Measured on the 10 x 10 PD bar (examples/pd_bar, tests/verification/test_pd_surface.c;
 * axial strain against F/(EA), lateral contraction nu_eff for nu = 0.2), PDLAMMPS / EXACT:
 *  - none: -5.5% / -12.3%, nu_eff 0.225 / 0.204;
 *  - this fit: +0.52% / +0.68%, nu_eff 0.194 / 0.192 (nu = 0: +0.50%, nu_eff -0.005);
 *  - g only, on the uniaxial stress states: +0.47% / +0.38%, nu_eff 0.218 / 0.193;
 *  - g only, on the uniaxial strain states: +2.7% / -0.09% (misses the PDLAMMPS anisotropy);
 *  - Madenci-Oterkus ratios (target / sum on each axis) with the ellipsoid rule on the mean of
 *    the two nodes' vectors: -1.1% / -3.8% (uniaxial strain), -2.6% / -2.7% (uniaxial stress).
 *
 * Bond-based: d = 1 and G fitted the same way on the pair energy (c_j = omega beta V x)
 * against the calibrated value S (1 + 2 delta_kl)/15 (3D; S = the full-stencil sum of
 * operator.c, fallback: uniaxial stress with nu = 1/4) or S (1D, the y axis only). The pair
 * coefficient takes c_ij (G_ij + G_ji)/2.
 *
 * With cut cells (pd_phi) every sum weighs the neighbour's volume, so the fit targets the
 * node's own weighted volume m_i as it is.
 *
 * K stays symmetric (it is the Hessian of an energy) and rigid motions stay force-free (e_ij
 * vanishes for them whatever the factors). */
#include <math.h>
#include <string.h>

#include "pd/pd_internal.h"

/* Solve the 3x3 system A f = t by Cramer's rule; 0 when A is (nearly) singular. */
static int solve3(const double A[9], const double t[3], double f[3]) {
  const double det = A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
                     A[2] * (A[3] * A[7] - A[4] * A[6]);
  double scale = 0.0;
  for (int q = 0; q < 9; q++) scale = fmax(scale, fabs(A[q]));
  if (!(fabs(det) > 1e-12 * scale * scale * scale)) return 0;
  for (int c = 0; c < 3; c++) {
    double M[9];
    memcpy(M, A, sizeof M);
    for (int r = 0; r < 3; r++) M[3 * r + c] = t[r];
    f[c] = (M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
            M[2] * (M[3] * M[7] - M[4] * M[6])) /
           det;
  }
  return 1;
}

/* Factors of one part: the fit sum_l f_l M_kl = target (M_kl the node's sum for state k and
 * weight n_l^2). Where the family does not reach every axis (a body one cell thin, or 1D),
 * or the fit is singular or not positive (a very truncated family, e.g. a fictitious node of a
 * thin coupled skin), the ratio target / sum_l M_kl on each axis the family reaches (the
 * Madenci-Oterkus factor, positive), 1 elsewhere. */
static void part_factors(const double M[9], double target, const int axes[3], double f[3]) {
  if (axes[0] && axes[1] && axes[2]) {
    const double t[3] = {target, target, target};
    if (solve3(M, t, f) && f[0] > 0 && f[1] > 0 && f[2] > 0) return;
  }
  for (int k = 0; k < 3; k++) {
    const double r = M[3 * k] + M[3 * k + 1] + M[3 * k + 2];
    f[k] = axes[k] && r > 0 ? target / r : 1.0;
  }
}

/* Fourth-moment target factor ((1-2nu)^2 + 2(1+2nu^2))/15 of the uniaxial stress state. */
static double stress_target(double nu) {
  return ((1.0 - 2.0 * nu) * (1.0 - 2.0 * nu) + 2.0 * (1.0 + 2.0 * nu * nu)) / 15.0;
}

/* The 3x3 sums of node i: M2 (dilatation, uniaxial strains) and M4 (energy, uniaxial stress
 * with Poisson's ratio nu); c = omega beta V x^p with p = 2 (LPS) or 1 (bond-based). */
static void node_sums(const struct cupid_pd_operator_private *op, cupid_int i, int p, double nu,
                      double M2[9], double M4[9]) {
  const pd_stencil *S = &op->st;
  memset(M2, 0, 9 * sizeof *M2);
  memset(M4, 0, 9 * sizeof *M4);
  for (cupid_int b = op->bptr[i]; b < op->bptr[i + 1]; b++) {
    const int s = op->bst[b];
    const double *n = S->nrm + 3 * s;
    const double c = S->wb[s] * (p == 2 ? S->x[s] * S->x[s] : S->x[s]) * op->V * pd_phi(op, op->bnbr[b]);
    const double n2[3] = {n[0] * n[0], n[1] * n[1], n[2] * n[2]};
    for (int k = 0; k < 3; k++) {
      const double ek = (1.0 + nu) * n2[k] - nu; /* n.eps n, uniaxial stress along k */
      for (int l = 0; l < 3; l++) {
        M2[3 * k + l] += c * n2[k] * n2[l];
        M4[3 * k + l] += c * ek * ek * n2[l];
      }
    }
  }
}

/* Solve the n x n system A x = b (row-major, overwritten); 0 when a pivot is below 1e-12 of
 * the largest entry (singular). */
static int solve_n(int n, double *A, double *b) {
  return cupid_dense_solve(n, A, b, 1, 1e-12 * cupid_dense_max_abs(n, A));
}

/* The six-parameter energy fit of node i: G(n) = sum_k g_k n_k^2 + q_k n_k^4 such that
 * sum_j c G n_k^2 n_l^2 = scale (1 + 2 delta_kl)/15 for the six pairs k <= l, i.e. the energy
 * is the isotropic one under every normal strain (uniaxial stress along any axis with any
 * Poisson ratio included). 0 (f untouched) when singular or when G would not be positive on
 * every bond of the node (the energy must stay positive). */
static int fit6(const struct cupid_pd_operator_private *op, cupid_int i, int p, double scale,
                double f[6]) {
  const pd_stencil *S = &op->st;
  static const int pk[6] = {0, 1, 2, 0, 0, 1}, pl[6] = {0, 1, 2, 1, 2, 2};
  double A[36] = {0}, b[6];
  for (cupid_int bb = op->bptr[i]; bb < op->bptr[i + 1]; bb++) {
    const int s = op->bst[bb];
    const double *n = S->nrm + 3 * s;
    const double c = S->wb[s] * (p == 2 ? S->x[s] * S->x[s] : S->x[s]) * op->V * pd_phi(op, op->bnbr[bb]);
    const double n2[3] = {n[0] * n[0], n[1] * n[1], n[2] * n[2]};
    const double phi[6] = {n2[0], n2[1], n2[2], n2[0] * n2[0], n2[1] * n2[1], n2[2] * n2[2]};
    for (int e = 0; e < 6; e++) {
      const double w = c * n2[pk[e]] * n2[pl[e]];
      for (int u = 0; u < 6; u++) A[6 * e + u] += w * phi[u];
    }
  }
  for (int e = 0; e < 6; e++) b[e] = scale * (pk[e] == pl[e] ? 3.0 : 1.0) / 15.0;
  if (!solve_n(6, A, b)) return 0;
  for (cupid_int bb = op->bptr[i]; bb < op->bptr[i + 1]; bb++) {
    const double *n = S->nrm + 3 * op->bst[bb];
    double G = 0.0;
    for (int k = 0; k < 3; k++) G += (b[k] + b[3 + k] * n[k] * n[k]) * n[k] * n[k];
    if (!(G > 0)) return 0;
  }
  memcpy(f, b, sizeof b);
  return 1;
}

cupid_status pd_surface_factors(struct cupid_pd_operator_private *op) {
  const pd_stencil *S = &op->st;
  const cupid_int nn = op->nnodes;
  CUPID_CALL(cupid_malloc(PD_SF * (size_t)nn, sizeof *op->sf, "PD surface factors", &op->sf));
  double Sfull = 0.0;
  for (int s = 0; s < S->n; s++) Sfull += S->wb[s] * S->x[s] * op->V;
  const int lps = op->model == CUPID_PD_LPS;
  const int axes[3] = {op->dim == 3, 1, op->dim == 3};
  cupid_int bad = -1;
#pragma omp parallel for schedule(static) if (nn > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < nn; i++) {
    double M2[9], M4[9], *f = op->sf + PD_SF * i;
    f[6] = f[7] = f[8] = 0.0;
    if (lps) {
      const double K = (op->kappa[i] + 5.0 * op->mu[i]) / 3.0, mu = op->mu[i];
      const double nu = (3.0 * K - 2.0 * mu) / (2.0 * (3.0 * K + mu));
      node_sums(op, i, 2, nu, M2, M4);
      part_factors(M2, op->m[i] / 3.0, axes, f);
      if (!(op->dim == 3 && fit6(op, i, 2, op->m[i], f + 3)))
        part_factors(M4, op->m[i] * stress_target(nu), axes, f + 3);
    } else {
      const double nu = op->dim == 3 ? 0.25 : 0.0; /* 1D: only the y state, n_y = +-1 */
      node_sums(op, i, 1, nu, M2, M4);
      f[0] = f[1] = f[2] = 1.0;
      if (!(op->dim == 3 && fit6(op, i, 1, Sfull, f + 3)))
        part_factors(M4, op->dim == 3 ? Sfull * stress_target(nu) : Sfull, axes, f + 3);
    }
    /* With q = 0 the factors must be positive; fit6 checked G > 0 on every bond itself. */
    const int nchk = f[6] == 0.0 && f[7] == 0.0 && f[8] == 0.0 ? 6 : 3;
    for (int k = 0; k < nchk; k++)
      if (!(isfinite(f[k]) && f[k] > 0)) {
#pragma omp critical(pd_surface_bad)
        bad = i;
      }
  }
  if (bad >= 0) {
    const double *x = op->grid->coords + 3 * bad, *f = op->sf + PD_SF * bad;
    return CUPID_ERROR(CUPID_ERR_MODEL,
                       "PD node %lld at (%g, %g, %g): the surface correction gives a factor "
                       "that is not positive (%g %g %g %g %g %g): its family is too truncated",
                       (long long)bad, x[0], x[1], x[2], f[0], f[1], f[2], f[3], f[4], f[5]);
  }
  if (!lps) return CUPID_SUCCESS;
  /* gself_i = sum_j omega beta x D_ij n_ij: the self weight of the corrected theta_i. */
#pragma omp parallel for schedule(static) if (nn > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < nn; i++) {
    double gs[3] = {0, 0, 0};
    for (cupid_int b = op->bptr[i]; b < op->bptr[i + 1]; b++) {
      const int s = op->bst[b];
      double F[4];
      pd_surface_bond(op, i, op->bnbr[b], S->nrm + 3 * s, F);
      for (int c = 0; c < 3; c++) gs[c] += F[0] * pd_phi(op, op->bnbr[b]) * S->wxn[3 * s + c];
    }
    for (int c = 0; c < 3; c++) op->gself[3 * i + c] = gs[c];
  }
  return CUPID_SUCCESS;
}
