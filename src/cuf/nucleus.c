/* The 3x3 fundamental nucleus of the CUF beam (paper 000 Eq. 27; cuf.md section 1.3) in the
 * separable form: K^{tau s i j}_{kh} = sum_{d,d'} C[v(k,d)][v(h,d')] E^{dd'}_{s tau} I^{dd'}_{j i},
 * where E are section integrals of products of F (differentiated along x or z) and I axis
 * integrals of products of N (differentiated along y). This is B^T C B written component by
 * component, valid for any 6x6 C (isotropic, orthotropic, or rotated). Locking treatments
 * split C into "parts" whose axis integrals use other rules or tied (MITC) functions. */
#include <math.h>
#include <string.h>

#include "cuf/cuf_internal.h"

typedef struct cupid_cuf_beam_private beam_t;

cupid_status cuf_material_stiffness(const cupid_material *m, double C[36]) {
  const char *name = m->name ? m->name : "?";
  memset(C, 0, 36 * sizeof *C);
  if (!m->orthotropic) {
    double E = m->E, nu = m->nu;
    CUPID_CHECK(E > 0 && nu > -1 && nu < 0.5, CUPID_ERR_MODEL,
                "material %s: need E > 0 and -1 < nu < 0.5 (E = %g, nu = %g)", name, E, nu);
    double lam = E * nu / ((1 + nu) * (1 - 2 * nu)), G = E / (2 * (1 + nu));
    for (int i = 0; i < 3; i++) {
      for (int j = 0; j < 3; j++) C[6 * i + j] = lam;
      C[7 * i] = lam + 2 * G;
      C[7 * (i + 3)] = G;
    }
    return CUPID_SUCCESS;
  }
  /* compliance of the normal block with S_ij = -nu_ij / E_i (nu_ij / E_i = nu_ji / E_j) */
  CUPID_CHECK(m->Ex > 0 && m->Ey > 0 && m->Ez > 0 && m->Gxy > 0 && m->Gxz > 0 && m->Gyz > 0,
              CUPID_ERR_MODEL, "material %s: orthotropic moduli must be positive", name);
  double S[9] = {1 / m->Ex,         -m->nu_xy / m->Ex, -m->nu_xz / m->Ex,
                 -m->nu_xy / m->Ex, 1 / m->Ey,         -m->nu_yz / m->Ey,
                 -m->nu_xz / m->Ex, -m->nu_yz / m->Ey, 1 / m->Ez};
  double c0 = S[4] * S[8] - S[5] * S[7], c1 = S[5] * S[6] - S[3] * S[8], c2 = S[3] * S[7] - S[4] * S[6];
  double det = S[0] * c0 + S[1] * c1 + S[2] * c2;
  /* positive definite compliance: leading minors positive */
  CUPID_CHECK(det > 0 && S[0] * S[4] - S[1] * S[3] > 0, CUPID_ERR_MODEL,
              "material %s: orthotropic constants do not give a positive definite stiffness", name);
  double inv[9] = {c0 / det,
                   (S[2] * S[7] - S[1] * S[8]) / det,
                   (S[1] * S[5] - S[2] * S[4]) / det,
                   c1 / det,
                   (S[0] * S[8] - S[2] * S[6]) / det,
                   (S[2] * S[3] - S[0] * S[5]) / det,
                   c2 / det,
                   (S[1] * S[6] - S[0] * S[7]) / det,
                   (S[0] * S[4] - S[1] * S[3]) / det};
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) C[6 * i + j] = inv[3 * i + j];
  C[6 * CUF_YZ + CUF_YZ] = m->Gyz;
  C[6 * CUF_XZ + CUF_XZ] = m->Gxz;
  C[6 * CUF_XY + CUF_XY] = m->Gxy;
  return CUPID_SUCCESS;
}

/* Invert the n x n matrix A (row-major, n <= 6) in place by Gauss-Jordan with partial
 * pivoting; 0 if it is singular to working precision. */
static int invert_small(int n, double *A) {
  double W[6][12];
  for (int i = 0; i < n; i++)
    for (int j = 0; j < 2 * n; j++) W[i][j] = j < n ? A[n * i + j] : (double)(j - n == i);
  for (int c = 0; c < n; c++) {
    int piv = c;
    for (int r = c + 1; r < n; r++)
      if (fabs(W[r][c]) > fabs(W[piv][c])) piv = r;
    if (!(fabs(W[piv][c]) > 0.0)) return 0;
    for (int j = 0; j < 2 * n; j++) {
      double t = W[c][j];
      W[c][j] = W[piv][j];
      W[piv][j] = t;
    }
    double d = W[c][c];
    for (int j = 0; j < 2 * n; j++) W[c][j] /= d;
    for (int r = 0; r < n; r++) {
      if (r == c || W[r][c] == 0.0) continue;
      double f = W[r][c];
      for (int j = 0; j < 2 * n; j++) W[r][j] -= f * W[c][j];
    }
  }
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) A[n * i + j] = W[i][n + j];
  return 1;
}

/* The Poisson-locking correction (docs/theory.md, "Poisson locking"): the in-section normal
 * stresses sigma_xx = sigma_zz = 0 are imposed on the 3D law, so the remaining stresses
 * (yy, yz, xz, xy) follow from the compliance S = C^-1 restricted to them, inverted; eps_xx and
 * eps_zz then carry no stress. Isotropic: sigma_yy = E eps_yy, shears G. Orthotropic (axes
 * x y z): sigma_yy = E_y eps_yy, shears unchanged. Any symmetric positive definite C works. */
cupid_status cuf_poisson_correct(double C[36], double R[36]) {
  static const int keep[4] = {CUF_YY, CUF_YZ, CUF_XZ, CUF_XY};
  double S[36], Sk[16];
  memcpy(S, C, sizeof S);
  CUPID_CHECK(invert_small(6, S), CUPID_ERR_MODEL, "Poisson correction: singular material stiffness");
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) Sk[4 * i + j] = S[6 * keep[i] + keep[j]];
  CUPID_CHECK(invert_small(4, Sk), CUPID_ERR_MODEL, "Poisson correction: singular reduced compliance");
  memcpy(R, C, 36 * sizeof *R);
  memset(C, 0, 36 * sizeof *C);
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) {
      /* symmetrise: the two halves of Sk^-1 differ by round-off only */
      C[6 * keep[i] + keep[j]] = 0.5 * (Sk[4 * i + j] + Sk[4 * j + i]);
    }
  /* R = C_3D - C = [C_D; C_KD] C_DD^-1 [C_DD C_DK] (D = xx, zz): positive semi-definite */
  for (int k = 0; k < 36; k++) R[k] -= C[k];
  for (int i = 0; i < 6; i++)
    for (int j = 0; j < i; j++) R[6 * i + j] = R[6 * j + i] = 0.5 * (R[6 * i + j] + R[6 * j + i]);
  return CUPID_SUCCESS;
}

/* The transverse-shear strains, which contain d/dy and lock (cuf.md section 4). */
static const int tied[6] = {0, 0, 0, 1, 0, 1};

void cuf_parts_init(beam_t *b) {
  memset(b->parts, 0, sizeof b->parts);
  if (b->integration == CUPID_CUF_FULL || b->p < 2) {
    b->n_parts = 1;
    memset(b->parts[0].cmask, 1, 36);
  } else if (b->integration == CUPID_CUF_REDUCED) {
    /* selective: everything touching a shear row/column with the reduced rule */
    b->n_parts = 2;
    for (int r = 0; r < 6; r++)
      for (int c = 0; c < 6; c++) {
        int sh = tied[r] || tied[c];
        b->parts[0].cmask[6 * r + c] = (unsigned char)!sh;
        b->parts[1].cmask[6 * r + c] = (unsigned char)sh;
      }
    b->parts[1].reduced = 1;
  } else {
    /* MITC: B~^T C B~ with the tied rows interpolated; four blocks by (row tied, col tied) */
    b->n_parts = 4;
    for (int P = 0; P < 4; P++) {
      int rt = P / 2, ct = P % 2;
      b->parts[P].tilde_test = rt;
      b->parts[P].tilde_trial = ct;
      for (int r = 0; r < 6; r++)
        for (int c = 0; c < 6; c++)
          b->parts[P].cmask[6 * r + c] = (unsigned char)(tied[r] == rt && tied[c] == ct);
    }
  }
}

/* Axis functions at xi: H[0] = N, H[1] = dN/dy, plain or MITC-tied. */
static void axis_functions(const beam_t *b, cupid_int e, double xi, int tilde, double H[2][CUF_MAX_P]) {
  if (!tilde) {
    cuf_axis_shape(b, e, xi, H[0], H[1]);
    return;
  }
  /* tying points (cuf.md section 4, MUL2_new tab:tying): p - 1 of them */
  static const double t2[1] = {0.0};
  static const double t3[2] = {-0.57735026918962576451, 0.57735026918962576451};
  static const double t4[3] = {-0.77459666924148337704, 0.0, 0.77459666924148337704};
  const double *tp = b->p == 2 ? t2 : b->p == 3 ? t3 : t4;
  int nt = b->p - 1;
  double Mt[CUF_MAX_P] = {1.0};
  if (nt > 1) cuf_lagrange(nt, tp, xi, Mt, NULL);
  for (int a = 0; a < b->p; a++) H[0][a] = H[1][a] = 0.0;
  for (int l = 0; l < nt; l++) {
    double N[CUF_MAX_P], dN[CUF_MAX_P];
    cuf_axis_shape(b, e, tp[l], N, dN);
    for (int a = 0; a < b->p; a++) {
      H[0][a] += Mt[l] * N[a];
      H[1][a] += Mt[l] * dN[a];
    }
  }
}

void cuf_axis_integrals(const beam_t *b, cupid_int e, double *I) {
  int p = b->p;
  double y0 = b->by[e * (p - 1)], y1 = b->by[(e + 1) * (p - 1)], J = 0.5 * (y1 - y0);
  memset(I, 0, sizeof *I * (size_t)b->n_parts * 4 * p * p);
  for (int P = 0; P < b->n_parts; P++) {
    const cuf_part *pt = &b->parts[P];
    int ng = pt->reduced ? p - 1 : p;
    double gx[CUF_MAX_P], gw[CUF_MAX_P];
    cuf_gauss(ng, gx, gw);
    for (int g = 0; g < ng; g++) {
      double Ht[2][CUF_MAX_P], Hr[2][CUF_MAX_P];
      axis_functions(b, e, gx[g], pt->tilde_test, Ht);
      axis_functions(b, e, gx[g], pt->tilde_trial, Hr);
      double w = gw[g] * J;
      for (int dt = 0; dt < 2; dt++)
        for (int dr = 0; dr < 2; dr++) {
          double *Id = I + ((size_t)P * 4 + 2 * dt + dr) * p * p;
          for (int j = 0; j < p; j++)
            for (int i = 0; i < p; i++) Id[j * p + i] += w * Ht[dt][j] * Hr[dr][i];
        }
    }
  }
}

void cuf_pair_matrix(const beam_t *b, int m, const double *E, int mat, const double *I, double *Ke) {
  int p = b->p, n = 3 * m * p;
  size_t mm = (size_t)m * m;
  memset(Ke, 0, sizeof *Ke * (size_t)n * n);
  const double *C = b->mat[mat].C;
  for (int P = 0; P < b->n_parts; P++) {
    /* Q[d][d'][k][h] = C_P[v(k,d)][v(h,d')] */
    double Q[3][3][9];
    int nonzero[3][3];
    for (int d = 0; d < 3; d++)
      for (int dd = 0; dd < 3; dd++) {
        nonzero[d][dd] = 0;
        for (int k = 0; k < 3; k++)
          for (int h = 0; h < 3; h++) {
            int r = cuf_vidx[k][d], c = cuf_vidx[h][dd];
            double v = b->parts[P].cmask[6 * r + c] ? C[6 * r + c] : 0.0;
            Q[d][dd][3 * k + h] = v;
            nonzero[d][dd] |= v != 0.0;
          }
      }
    /* TE1 Poisson correction (docs/theory.md): the contraction part R of the 3D law acts on
     * eps_xx, eps_zz and the constant-term (tau = 0) part of eps_yy only; the yy row (test,
     * u_y along d/dy) needs s = 0, the yy column t = 0. */
    double QR[3][3][9];
    int split = b->poisson_split && b->parts[P].cmask[6 * CUF_YY + CUF_YY];
    for (int d = 0; d < 3 && split; d++)
      for (int dd = 0; dd < 3; dd++)
        for (int k = 0; k < 3; k++)
          for (int h = 0; h < 3; h++) {
            int r = cuf_vidx[k][d], c = cuf_vidx[h][dd];
            QR[d][dd][3 * k + h] = b->parts[P].cmask[6 * r + c] ? b->mat[mat].R[6 * r + c] : 0.0;
            if (QR[d][dd][3 * k + h] != 0.0) nonzero[d][dd] = 1;
          }
    const double *IP = I + (size_t)P * 4 * p * p;
    for (int s = 0; s < m; s++)
      for (int t = 0; t < m; t++) {
        double W[4][9] = {{0}};
        int any = 0;
        for (int d = 0; d < 3; d++)
          for (int dd = 0; dd < 3; dd++) {
            if (!nonzero[d][dd]) continue;
            double e = E[(3 * d + dd) * mm + (size_t)s * m + t];
            if (e == 0.0) continue;
            any = 1;
            double *w = W[2 * (d == 1) + (dd == 1)];
            for (int q = 0; q < 9; q++) w[q] += Q[d][dd][q] * e;
            if (!split) continue;
            for (int k = 0; k < 3; k++)
              for (int h = 0; h < 3; h++) {
                if ((s != 0 && cuf_vidx[k][d] == CUF_YY) || (t != 0 && cuf_vidx[h][dd] == CUF_YY))
                  continue;
                w[3 * k + h] += QR[d][dd][3 * k + h] * e;
              }
          }
        if (!any) continue;
        for (int j = 0; j < p; j++)
          for (int i = 0; i < p; i++) {
            double a[4];
            for (int k = 0; k < 4; k++) a[k] = IP[(size_t)k * p * p + j * p + i];
            double *row = Ke + (size_t)((s * p + j) * 3) * n + (t * p + i) * 3;
            for (int k = 0; k < 3; k++)
              for (int h = 0; h < 3; h++)
                row[(size_t)k * n + h] += a[0] * W[0][3 * k + h] + a[1] * W[1][3 * k + h] +
                                          a[2] * W[2][3 * k + h] + a[3] * W[3][3 * k + h];
          }
      }
  }
}
