/* Small dense systems: the balance's Gram and capacitance matrices (src/coupling/balance.c),
 * the surface correction's fits (src/pd/surface.c) and the capacitance of growth's updated LU
 * (src/problem/growth_smw.c) and of the block factor's interface (src/problem/growth_block.c),
 * each a few to a few hundred unknowns. One elimination for every
 * right-hand side; plain loops in a fixed order, so that the same inputs give the same bits for
 * any thread count (a growth's iterates decide which bonds break). */
#include <math.h>

#include "cupid/base.h"

int cupid_dense_solve(int n, double *A, double *B, int nrhs, double pivot_min) {
  for (int c = 0; c < n; c++) {
    int p = c;
    for (int r = c + 1; r < n; r++)
      if (fabs(A[r * n + c]) > fabs(A[p * n + c])) p = r;
    if (!(fabs(A[p * n + c]) > pivot_min)) return 0;
    if (p != c) {
      for (int k = 0; k < n; k++) {
        const double t = A[c * n + k];
        A[c * n + k] = A[p * n + k];
        A[p * n + k] = t;
      }
      for (int j = 0; j < nrhs; j++) {
        const double t = B[c * nrhs + j];
        B[c * nrhs + j] = B[p * nrhs + j];
        B[p * nrhs + j] = t;
      }
    }
    for (int r = c + 1; r < n; r++) {
      const double f = A[r * n + c] / A[c * n + c];
      for (int k = c; k < n; k++) A[r * n + k] -= f * A[c * n + k];
      for (int j = 0; j < nrhs; j++) B[r * nrhs + j] -= f * B[c * nrhs + j];
    }
  }
  for (int c = n - 1; c >= 0; c--)
    for (int j = 0; j < nrhs; j++) {
      double t = B[c * nrhs + j];
      for (int k = c + 1; k < n; k++) t -= A[c * n + k] * B[k * nrhs + j];
      B[c * nrhs + j] = t / A[c * n + c];
    }
  return 1;
}

int cupid_dense_invert(int n, double *A, double *work, double pivot_min) {
  for (int q = 0; q < n * n; q++) work[q] = 0.0;
  for (int a = 0; a < n; a++) work[a * n + a] = 1.0;
  if (!cupid_dense_solve(n, A, work, n, pivot_min)) return 0;
  for (int q = 0; q < n * n; q++) A[q] = work[q];
  return 1;
}

int cupid_dense_lu(int n, double *A, int *piv, double pivot_min) {
  for (int c = 0; c < n; c++) {
    int p = c;
    for (int r = c + 1; r < n; r++)
      if (fabs(A[r * n + c]) > fabs(A[p * n + c])) p = r;
    piv[c] = p;
    if (!(fabs(A[p * n + c]) > pivot_min)) return 0;
    if (p != c)
      for (int k = 0; k < n; k++) {
        const double t = A[c * n + k];
        A[c * n + k] = A[p * n + k];
        A[p * n + k] = t;
      }
    const double inv = 1.0 / A[c * n + c];
    for (int r = c + 1; r < n; r++) {
      double *ar = A + r * n;
      const double f = ar[c] * inv, *ac = A + c * n;
      ar[c] = f;
      for (int k = c + 1; k < n; k++) ar[k] -= f * ac[k];
    }
  }
  return 1;
}

void cupid_dense_lu_solve(int n, const double *A, const int *piv, double *b) {
  for (int c = 0; c < n; c++) /* P b: the rows of L were swapped with later pivots too */
    if (piv[c] != c) {
      const double t = b[c];
      b[c] = b[piv[c]];
      b[piv[c]] = t;
    }
  for (int r = 1; r < n; r++) {
    double t = b[r];
    for (int c = 0; c < r; c++) t -= A[r * n + c] * b[c];
    b[r] = t;
  }
  for (int c = n - 1; c >= 0; c--) {
    double t = b[c];
    for (int k = c + 1; k < n; k++) t -= A[c * n + k] * b[k];
    b[c] = t / A[c * n + c];
  }
}

double cupid_dense_max_abs(int n, const double *A) {
  double m = 0.0;
  for (int q = 0; q < n * n; q++) m = fmax(m, fabs(A[q]));
  return m;
}
