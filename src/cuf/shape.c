/* Quadrature and shape functions of the CUF beam: Gauss-Legendre rules, 1D Lagrange polynomials
 * (beam elements B2/B3/B4, cuf.md section 4), tensor-product quadrilaterals L4/L9/L16 in the
 * MUL2_new node order (cuf.md section 3.1). */
#include <math.h>

#include "cuf/cuf_internal.h"

const int cuf_vidx[3][3] = {
    {CUF_XX, CUF_XY, CUF_XZ}, /* u_x,x u_x,y u_x,z */
    {CUF_XY, CUF_YY, CUF_YZ}, /* u_y,x u_y,y u_y,z */
    {CUF_XZ, CUF_YZ, CUF_ZZ}, /* u_z,x u_z,y u_z,z */
};

void cuf_gauss(int n, double *x, double *w) {
  /* Newton on the Legendre polynomial P_n from the Chebyshev-like initial guess; symmetric. */
  for (int i = 0; i < (n + 1) / 2; i++) {
    double t = cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; it++) {
      double p0 = 1.0, p1 = t;
      for (int k = 2; k <= n; k++) {
        double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      if (n == 1) p1 = t, p0 = 1.0;
      dp = n * (t * p1 - p0) / (t * t - 1.0);
      double dt = p1 / dp;
      t -= dt;
      if (fabs(dt) < 1e-16) break;
    }
    {
      double p0 = 1.0, p1 = t;
      for (int k = 2; k <= n; k++) {
        double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (t * p1 - p0) / (t * t - 1.0);
    }
    x[i] = -t;
    x[n - 1 - i] = t;
    w[i] = w[n - 1 - i] = 2.0 / ((1.0 - t * t) * dp * dp);
  }
  if (n % 2 == 1) x[n / 2] = 0.0;
}

void cuf_lagrange(int n, const double *nodes, double xi, double *N, double *dN) {
  for (int a = 0; a < n; a++) {
    double v = 1.0, d = 0.0;
    for (int b = 0; b < n; b++) {
      if (b == a) continue;
      double f = 1.0 / (nodes[a] - nodes[b]);
      d = d * (xi - nodes[b]) * f + v * f; /* product rule, accumulated */
      v *= (xi - nodes[b]) * f;
    }
    N[a] = v;
    if (dN) dN[a] = d;
  }
}

void cuf_beam_nodes(int p, double *xi) {
  for (int a = 0; a < p; a++) xi[a] = -1.0 + 2.0 * a / (p - 1);
}

void cuf_quad_init(cuf_quad *q, int n) {
  q->n = n;
  q->npe = n * n;
  cuf_beam_nodes(n, q->grid);
  for (int k = 0; k < q->npe; k++) cupid_le_node_grid(q->npe, k, &q->ia[k], &q->ib[k]);
}

void cuf_quad_shape(const cuf_quad *q, double r, double s, double *F, double *Fr, double *Fs) {
  double Lr[CUF_MAX_N], dLr[CUF_MAX_N], Ls[CUF_MAX_N], dLs[CUF_MAX_N];
  cuf_lagrange(q->n, q->grid, r, Lr, dLr);
  cuf_lagrange(q->n, q->grid, s, Ls, dLs);
  for (int k = 0; k < q->npe; k++) {
    int a = q->ia[k], b = q->ib[k];
    F[k] = Lr[a] * Ls[b];
    if (Fr) Fr[k] = dLr[a] * Ls[b];
    if (Fs) Fs[k] = Lr[a] * dLs[b];
  }
}
