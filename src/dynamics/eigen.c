/* Spectral tools for dynamics: the largest eigenvalue of M^-1 K (stable step of central
 * differences) and a small dense generalised eigen solver (verification of frequencies). */
#include <math.h>
#include <string.h>

#include "dynamics/dynamics_internal.h"

/* Gershgorin bound of the symmetric M^-1/2 K M^-1/2 on the free rows. */
static double gershgorin(const cupid_csr_t *K, const double *m, const cupid_dirichlet_t *bc) {
  int bs = K->bs;
  double best = 0.0;
  for (cupid_int row = 0; row < K->nrows; row++)
    for (int a = 0; a < bs; a++) {
      cupid_int i = row * bs + a;
      if (dyn_fixed(bc, i) || !(m[i] > 0.0)) continue;
      double sum = 0.0;
      for (cupid_int q = K->rowptr[row]; q < K->rowptr[row + 1]; q++)
        for (int b = 0; b < bs; b++) {
          cupid_int j = K->col[q] * bs + b;
          if (dyn_fixed(bc, j) || !(m[j] > 0.0)) continue;
          sum += fabs(K->val[(q * bs + a) * bs + b]) / sqrt(m[i] * m[j]);
        }
      if (sum > best) best = sum;
    }
  return best;
}

/* y = K x for the assembled K (the callback form of the power iteration). */
static cupid_status csr_apply(void *ctx, const double *x, double *y) {
  cupid_csr_matvec(ctx, x, y);
  return CUPID_SUCCESS;
}

/* The largest eigenvalue of the symmetric tridiagonal matrix with diagonal a[0..k) and
 * off-diagonal b[0..k-1), by bisection on the Sturm count (Golub & Van Loan, 4th ed., 8.4.1):
 * the number of negative pivots of T - x I is the number of eigenvalues below x. */
static double tridiagonal_max(const double *a, const double *b, int k) {
  double lo = a[0], hi = a[0];
  for (int i = 0; i < k; i++) { /* Gershgorin interval */
    const double r = (i > 0 ? fabs(b[i - 1]) : 0.0) + (i + 1 < k ? fabs(b[i]) : 0.0);
    lo = fmin(lo, a[i] - r);
    hi = fmax(hi, a[i] + r);
  }
  for (int it = 0; it < 200 && hi - lo > 4e-16 * fmax(fabs(lo), fabs(hi)); it++) {
    const double x = 0.5 * (lo + hi);
    int below = 0;
    double d = 1.0;
    for (int i = 0; i < k; i++) {
      d = a[i] - x - (i > 0 ? b[i - 1] * b[i - 1] / d : 0.0);
      if (fabs(d) < 1e-300) d = -1e-300;
      below += d < 0.0;
    }
    if (below == k) hi = x;
    else lo = x;
  }
  return 0.5 * (lo + hi);
}

/* x . y over the owned DOFs, summed over the processes. */
static double part_dot(const cupid_dynamics_partition *part, cupid_int n, const double *x,
                       const double *y) {
  if (!part) return dyn_dot(n, x, y);
  double s = dyn_dot(part->owned_last - part->owned_first, x + part->owned_first,
                     y + part->owned_first);
  part->sum(part->ctx, &s, 1);
  return s;
}

/* A start with every free component, alternating in sign (a large part on the most
 * oscillatory modes), a hash of the global index so that the split does not change it. */
static double start_component(cupid_int global) {
  uint64_t z = (uint64_t)global + 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  z ^= z >> 31;
  const double r = 0.5 + (double)(z >> 11) / 9007199254740992.0;
  return global % 2 ? r : -r;
}

/* Lanczos on A = M^-1/2 K M^-1/2 restricted to the free DOFs (the three-term recurrence
 * without reorthogonalisation: lost orthogonality only repeats converged Ritz values, and the
 * largest one still rises monotonically towards lambda_max). It converges to the extreme
 * eigenvalue far faster than the power iteration (Saad, Numerical Methods for Large
 * Eigenvalue Problems, 6.6): tens of products where the power iteration took 200. */
cupid_status dyn_lambda_max_fn(cupid_dynamics_stiffness_fn apply, void *ctx, cupid_int n,
                               const double *m, const cupid_dirichlet_t *bc,
                               const cupid_dynamics_partition *part, int iterations,
                               double *estimate, int *steps) {
  double *q = NULL, *qp = NULL, *w = NULL, *y = NULL, *dinv = NULL, *al = NULL, *be = NULL;
  cupid_status st = CUPID_SUCCESS;
  *estimate = 0.0;
  if (steps) *steps = 0;
  double **vecs[] = {&q, &qp, &w, &y, &dinv};
  for (size_t k = 0; k < sizeof vecs / sizeof *vecs; k++)
    CUPID_TRY(cupid_calloc((size_t)n + 1, sizeof(double), "Lanczos vectors", vecs[k]));
  CUPID_TRY(cupid_calloc((size_t)iterations + 1, sizeof *al, "Lanczos coefficients", &al));
  CUPID_TRY(cupid_calloc((size_t)iterations + 1, sizeof *be, "Lanczos coefficients", &be));
  const cupid_int g0 = part ? part->global_first : 0;
  for (cupid_int d = 0; d < n; d++) {
    const int free_dof = !dyn_fixed(bc, d) && m[d] > 0.0;
    dinv[d] = free_dof ? 1.0 / sqrt(m[d]) : 0.0;
    q[d] = free_dof ? start_component(g0 + d) : 0.0;
  }
  double nq = sqrt(part_dot(part, n, q, q)), beta = 0.0, theta = 0.0, ritz[10] = {0};
  if (!(nq > 0.0)) goto cleanup;
  for (cupid_int d = 0; d < n; d++) q[d] /= nq;
  for (int k = 0; k < iterations; k++) {
#pragma omp parallel for schedule(static) if (n > DYN_OMP_MIN)
    for (cupid_int d = 0; d < n; d++) y[d] = dinv[d] * q[d];
    if (part) CUPID_TRY(part->exchange(part->ctx, y));
    CUPID_TRY(apply(ctx, y, w));
#pragma omp parallel for schedule(static) if (n > DYN_OMP_MIN)
    for (cupid_int d = 0; d < n; d++) w[d] = dinv[d] * w[d] - beta * qp[d];
    const double alpha = part_dot(part, n, w, q);
#pragma omp parallel for schedule(static) if (n > DYN_OMP_MIN)
    for (cupid_int d = 0; d < n; d++) w[d] -= alpha * q[d];
    al[k] = alpha;
    beta = sqrt(part_dot(part, n, w, w));
    be[k] = beta;
    theta = tridiagonal_max(al, be, k + 1);
    if (steps) *steps = k + 1;
    /* Done when it rose by less than 3e-4 over the last 10 products (the top of a lattice's
     * spectrum is a dense band: the Ritz value creeps up; on the 64,000-node lattice of
     * bench/fracture_lammps.sh it stops after 55 products with omega_max 1.8e-4 below its
     * value after 196), or at an invariant subspace (beta ~ 0). The estimate serves a
     * stability check on a step users choose with a margin: a per-mille is plenty, and the
     * products it saves are a quarter of a 200-step run's. */
    ritz[k % 10] = theta;
    if (k >= 10 && theta - ritz[(k + 1) % 10] <= 3e-4 * fabs(theta)) break;
    if (!(beta > 1e-14 * fabs(theta))) break;
#pragma omp parallel for schedule(static) if (n > DYN_OMP_MIN)
    for (cupid_int d = 0; d < n; d++) {
      qp[d] = q[d];
      q[d] = w[d] / beta;
    }
  }
  *estimate = theta;
cleanup:
  for (size_t k = 0; k < sizeof vecs / sizeof *vecs; k++) cupid_free(vecs[k]);
  cupid_free(&al);
  cupid_free(&be);
  return st;
}

cupid_status cupid_dynamics_lambda_max(const cupid_csr_t *K, const double *m,
                                       const cupid_dirichlet_t *bc, int iterations,
                                       double *estimate, double *bound) {
  CUPID_CHECK(K && m, CUPID_ERR_ARGUMENT, "cupid_dynamics_lambda_max: NULL argument");
  cupid_int n = K->nrows * K->bs;
  if (bound) *bound = gershgorin(K, m, bc);
  if (!estimate) return CUPID_SUCCESS;
  return dyn_lambda_max_fn(csr_apply, (void *)K, n, m, bc, NULL, iterations, estimate, NULL);
}

/* Dense free-DOF matrix of a CSR (n_free x n_free, row-major). */
static void dense_free(const cupid_csr_t *A, const cupid_dirichlet_t *bc, const cupid_int *fi,
                       cupid_int nf, double *D) {
  int bs = A->bs;
  memset(D, 0, sizeof *D * (size_t)nf * (size_t)nf);
  for (cupid_int row = 0; row < A->nrows; row++)
    for (int a = 0; a < bs; a++) {
      cupid_int i = fi[row * bs + a];
      if (i < 0) continue;
      for (cupid_int q = A->rowptr[row]; q < A->rowptr[row + 1]; q++)
        for (int b = 0; b < bs; b++) {
          cupid_int j = fi[A->col[q] * bs + b];
          if (j >= 0) D[i * nf + j] += A->val[(q * bs + a) * bs + b];
        }
    }
}

/* Cyclic Jacobi on the symmetric A (n x n, destroyed: its diagonal ends as the eigenvalues);
 * V receives the eigenvectors as columns. */
static void jacobi(cupid_int n, double *A, double *V) {
  for (cupid_int i = 0; i < n; i++)
    for (cupid_int j = 0; j < n; j++) V[i * n + j] = i == j;
  for (int sweep = 0; sweep < 100; sweep++) {
    double off = 0.0, diag = 0.0;
    for (cupid_int i = 0; i < n; i++) {
      diag += A[i * n + i] * A[i * n + i];
      for (cupid_int j = i + 1; j < n; j++) off += A[i * n + j] * A[i * n + j];
    }
    if (off <= 1e-30 * diag) break;
    for (cupid_int p = 0; p < n; p++)
      for (cupid_int q = p + 1; q < n; q++) {
        double apq = A[p * n + q];
        if (fabs(apq) < 1e-300) continue;
        double theta = (A[q * n + q] - A[p * n + p]) / (2.0 * apq);
        double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
        double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
        for (cupid_int k = 0; k < n; k++) { /* columns p, q */
          double akp = A[k * n + p], akq = A[k * n + q];
          A[k * n + p] = c * akp - s * akq;
          A[k * n + q] = s * akp + c * akq;
        }
        for (cupid_int k = 0; k < n; k++) { /* rows p, q */
          double apk = A[p * n + k], aqk = A[q * n + k];
          A[p * n + k] = c * apk - s * aqk;
          A[q * n + k] = s * apk + c * aqk;
        }
        for (cupid_int k = 0; k < n; k++) {
          double vkp = V[k * n + p], vkq = V[k * n + q];
          V[k * n + p] = c * vkp - s * vkq;
          V[k * n + q] = s * vkp + c * vkq;
        }
      }
  }
}

/* In-place Cholesky M = L L^T (lower triangle of M overwritten); 0 if not positive definite. */
static int cholesky(cupid_int n, double *M) {
  for (cupid_int j = 0; j < n; j++) {
    double d = M[j * n + j];
    for (cupid_int k = 0; k < j; k++) d -= M[j * n + k] * M[j * n + k];
    if (!(d > 0.0)) return 0;
    d = sqrt(d);
    M[j * n + j] = d;
    for (cupid_int i = j + 1; i < n; i++) {
      double s = M[i * n + j];
      for (cupid_int k = 0; k < j; k++) s -= M[i * n + k] * M[j * n + k];
      M[i * n + j] = s / d;
    }
  }
  return 1;
}

cupid_status cupid_dynamics_eigen_dense(const cupid_csr_t *K, const cupid_csr_t *M,
                                        const double *m_lumped, const cupid_dirichlet_t *bc,
                                        int nev, double *omega, double *modes) {
  CUPID_CHECK(K && omega && nev > 0 && (M || m_lumped), CUPID_ERR_ARGUMENT,
              "cupid_dynamics_eigen_dense: bad argument");
  cupid_status st = CUPID_SUCCESS;
  cupid_int n = K->nrows * K->bs, nf = 0, *fi = NULL, *order = NULL;
  double *A = NULL, *B = NULL, *V = NULL;
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *fi, "free index", &fi));
  for (cupid_int d = 0; d < n; d++) fi[d] = dyn_fixed(bc, d) ? -1 : nf++;
  CUPID_TRY_CHECK(nf >= nev && nf <= 3000, CUPID_ERR_ARGUMENT,
                  "dense eigen solve: %lld free DOFs (need %d..3000)", (long long)nf, nev);
  size_t nn = (size_t)nf * (size_t)nf;
  CUPID_TRY(cupid_malloc(nn, sizeof *A, "dense K", &A));
  CUPID_TRY(cupid_calloc(nn, sizeof *B, "dense M", &B));
  CUPID_TRY(cupid_malloc(nn, sizeof *V, "dense eigenvectors", &V));
  CUPID_TRY(cupid_malloc((size_t)nf, sizeof *order, "eigen order", &order));
  dense_free(K, bc, fi, nf, A);
  if (M) dense_free(M, bc, fi, nf, B);
  else
    for (cupid_int d = 0; d < n; d++)
      if (fi[d] >= 0) B[fi[d] * nf + fi[d]] = m_lumped[d];
  CUPID_TRY_CHECK(cholesky(nf, B), CUPID_ERR_NUMERIC, "the mass matrix is not positive definite");
  /* A <- L^-1 A L^-T: solve L X = A (columns), then L Y^T = X^T. */
  for (int pass = 0; pass < 2; pass++) {
    for (cupid_int c = 0; c < nf; c++)
      for (cupid_int i = 0; i < nf; i++) {
        double s = A[i * nf + c];
        for (cupid_int k = 0; k < i; k++) s -= B[i * nf + k] * A[k * nf + c];
        A[i * nf + c] = s / B[i * nf + i];
      }
    for (cupid_int i = 0; i < nf; i++) /* transpose */
      for (cupid_int j = i + 1; j < nf; j++) {
        double t = A[i * nf + j];
        A[i * nf + j] = A[j * nf + i];
        A[j * nf + i] = t;
      }
  }
  jacobi(nf, A, V);
  for (cupid_int k = 0; k < nf; k++) order[k] = k;
  for (cupid_int k = 1; k < nf; k++) /* insertion sort by eigenvalue */
    for (cupid_int c = k; c > 0 && A[order[c - 1] * (nf + 1)] > A[order[c] * (nf + 1)]; c--) {
      cupid_int t = order[c];
      order[c] = order[c - 1];
      order[c - 1] = t;
    }
  for (int k = 0; k < nev; k++) {
    double lam = A[order[k] * (nf + 1)];
    omega[k] = lam > 0.0 ? sqrt(lam) : 0.0;
    if (!modes) continue;
    /* x = L^-T y */
    double *x = modes + (size_t)k * (size_t)n;
    memset(x, 0, sizeof *x * (size_t)n);
    for (cupid_int i = nf - 1; i >= 0; i--) {
      double s = V[i * nf + order[k]];
      for (cupid_int j = i + 1; j < nf; j++) s -= B[j * nf + i] * V[j * nf + order[k]];
      V[i * nf + order[k]] = s / B[i * nf + i];
    }
    for (cupid_int d = 0; d < n; d++)
      if (fi[d] >= 0) x[d] = V[fi[d] * nf + order[k]];
  }
cleanup:
  cupid_free(&fi);
  cupid_free(&order);
  cupid_free(&A);
  cupid_free(&B);
  cupid_free(&V);
  return st;
}
