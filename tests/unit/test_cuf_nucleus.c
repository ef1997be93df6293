/* Unit tests of the CUF fundamental nucleus (paper 000 Eq. 27, cuf.md 1.3): the separable
 * assembly against a brute-force Gauss integral of B^T C B, the published component formula,
 * the symmetry rule, the sparsity pattern and the rigid-body null space. */
#include <stdlib.h>

#include "unit/test_cuf_common.h"

#include "cuf/cuf_internal.h"

/* Brute force: int over the element of (B a_test e_k)^T C (B b_trial e_h) with the 3D strain
 * operator written out (cuf.md 1.1), ng points per section direction and nga along the axis.
 * With the TE1 Poisson correction also + (B0 a e_k)^T R (B0 b e_h), B0 the strain with eps_yy
 * kept only for the constant term (docs/theory.md, "Poisson locking"). */
static void brute_force(const struct cupid_cuf_beam_private *b, cupid_int be, cupid_int se,
                        int ng, int nga, double *Kb) {
  int m = cuf_local_m(b), p = b->p, n = 3 * m * p;
  memset(Kb, 0, sizeof *Kb * (size_t)n * n);
  double gx[CUF_MAX_GAUSS], gw[CUF_MAX_GAUSS], ax[CUF_MAX_GAUSS], aw[CUF_MAX_GAUSS];
  cuf_gauss(ng, gx, gw);
  cuf_gauss(nga, ax, aw);
  double y0 = b->by[be * (p - 1)], y1 = b->by[(be + 1) * (p - 1)], J = 0.5 * (y1 - y0);
  const double *C = b->mat[b->smat[se]].C, *R = b->mat[b->smat[se]].R;
  for (int ga = 0; ga < nga; ga++)
    for (int gi = 0; gi < ng; gi++)
      for (int gj = 0; gj < ng; gj++) {
        double F[256], Fx[256], Fz[256], det, N[4], dN[4];
        cuf_section_functions(b, se, gx[gi], gx[gj], F, Fx, Fz, NULL, NULL, &det);
        cuf_axis_shape(b, be, ax[ga], N, dN);
        double w = aw[ga] * J * gw[gi] * gw[gj] * det;
        /* strain columns: Bcol[(a*p + j)*3 + k][6] for unit displacement component k */
        static double Bc[3 * 256 * 4][6];
        for (int a = 0; a < m; a++)
          for (int j = 0; j < p; j++) {
            double g[3] = {N[j] * Fx[a], dN[j] * F[a], N[j] * Fz[a]};
            double *u = Bc[(a * p + j) * 3 + 0], *v = Bc[(a * p + j) * 3 + 1], *z = Bc[(a * p + j) * 3 + 2];
            /* Voigt xx yy zz yz xz xy */
            double bu[6] = {g[0], 0, 0, 0, g[2], g[1]};
            double bv[6] = {0, g[1], 0, g[2], 0, g[0]};
            double bw[6] = {0, 0, g[2], g[1], g[0], 0};
            memcpy(u, bu, sizeof bu);
            memcpy(v, bv, sizeof bv);
            memcpy(z, bw, sizeof bw);
          }
        for (int r = 0; r < n; r++) {
          double CB[6], RB[6], B0r[6];
          memcpy(B0r, Bc[r], sizeof B0r);
          if (r / (3 * p) != 0) B0r[CUF_YY] = 0; /* local function a = r / (3 p) */
          for (int i = 0; i < 6; i++) {
            CB[i] = RB[i] = 0;
            for (int k = 0; k < 6; k++) CB[i] += C[6 * i + k] * Bc[r][k];
            for (int k = 0; k < 6 && b->poisson_split; k++) RB[i] += R[6 * i + k] * B0r[k];
          }
          for (int c = 0; c < n; c++) {
            double v = 0;
            for (int i = 0; i < 6; i++) v += Bc[c][i] * CB[i];
            for (int i = 0; i < 6 && b->poisson_split; i++)
              v += (i == CUF_YY && c / (3 * p) != 0 ? 0.0 : Bc[c][i]) * RB[i];
            Kb[(size_t)c * n + r] += w * v; /* row = test (c), column = trial (r) */
          }
        }
      }
}

static double max_abs(const double *a, size_t n) {
  double m = 0;
  for (size_t i = 0; i < n; i++) m = fmax(m, fabs(a[i]));
  return m;
}

/* Random anisotropic SPD C = A A^T + I (tests the generic 6x6 path) or random orthotropic. */
static void random_C(double *C, uint64_t *rng, int orthotropic) {
  if (orthotropic) {
    cupid_material m = {0};
    m.orthotropic = 1;
    m.Ex = 100 + 50 * cupid_test_random(rng);
    m.Ey = 10 + 5 * cupid_test_random(rng);
    m.Ez = 12 + 5 * cupid_test_random(rng);
    m.nu_xy = 0.25 + 0.05 * cupid_test_random(rng);
    m.nu_xz = 0.3 + 0.05 * cupid_test_random(rng);
    m.nu_yz = 0.35 + 0.05 * cupid_test_random(rng);
    m.Gxy = 5 + cupid_test_random(rng);
    m.Gxz = 6 + cupid_test_random(rng);
    m.Gyz = 4 + cupid_test_random(rng);
    CUPID_ASSERT_OK(cuf_material_stiffness(&m, C));
    return;
  }
  double A[36];
  for (int i = 0; i < 36; i++) A[i] = cupid_test_random(rng);
  for (int i = 0; i < 6; i++)
    for (int j = 0; j < 6; j++) {
      double v = i == j ? 1.0 : 0.0;
      for (int k = 0; k < 6; k++) v += A[6 * i + k] * A[6 * j + k];
      C[6 * i + j] = v;
    }
}

static void check_pair(tb_beam *t, int orthotropic, int distort, uint64_t seed) {
  cupid_cuf_beam b = tb_create(t);
  uint64_t rng = seed;
  random_C(b->mat[0].C, &rng, orthotropic);
  /* TE1 (Poisson correction on by default): the corrected law of this C and its remainder */
  if (b->poisson_corrected) CUPID_ASSERT_OK(cuf_poisson_correct(b->mat[0].C, b->mat[0].R));
  if (distort) { /* move the interior nodes of the single LE element: a curved, non-affine map */
    for (cupid_int v = 0; v < b->n_snodes; v++) {
      double *p = b->sxz + 2 * v;
      if (p[0] > t->xs[0][0] + 1e-12 && p[0] < t->xs[0][1] - 1e-12) p[1] += 0.03 * cupid_test_random(&rng);
    }
    b->srect[0] = 0;
  }
  int m = cuf_local_m(b), p = b->p, n = 3 * m * p;
  double *E, *I, *Ke, *Kb;
  CUPID_ASSERT_OK(cupid_malloc(9 * (size_t)m * m, sizeof *E, "E", &E));
  CUPID_ASSERT_OK(cupid_malloc(16 * (size_t)p * p, sizeof *I, "I", &I));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n * n, sizeof *Ke, "Ke", &Ke));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n * n, sizeof *Kb, "Kb", &Kb));
  /* same section rule as the brute force: for curved maps the integrand is rational */
  int ng = distort ? b->sec_ng : b->sec_ng + 2;
  cuf_section_integrals(b, 0, ng, E);
  cuf_axis_integrals(b, 0, I);
  cuf_pair_matrix(b, m, E, 0, I, Ke);
  brute_force(b, 0, 0, ng, p + 1, Kb);
  double scale = max_abs(Kb, (size_t)n * n), err = 0, asym = 0;
  for (size_t q = 0; q < (size_t)n * n; q++) err = fmax(err, fabs(Ke[q] - Kb[q]));
  /* symmetry rule [K^{tau s i j}]_{kh} = [K^{s tau j i}]_{hk}: Ke symmetric */
  for (int r = 0; r < n; r++)
    for (int c = 0; c < n; c++) asym = fmax(asym, fabs(Ke[(size_t)r * n + c] - Ke[(size_t)c * n + r]));
  /* 1e-13 relative: both are sums of O(100) products of O(1) terms; round-off only */
  if (!(err <= 1e-13 * scale && asym <= 1e-13 * scale))
    fail_msg("nucleus vs brute force: err %.3g, asym %.3g, scale %.3g", err, asym, scale);
  if (orthotropic && !distort && !b->poisson_split) {
    /* the published component (cuf.md 1.3, convention A): K_xy = C12 E^{tau s,x} I^{i,y j}
     * + C66 E^{tau,x s} I^{i j,y}, checked for every (tau, s, i, j) */
    const double *C = b->mat[0].C;
    size_t mm = (size_t)m * m;
    for (int s = 0; s < m; s++)
      for (int tau = 0; tau < m; tau++)
        for (int j = 0; j < p; j++)
          for (int i = 0; i < p; i++) {
            double E_t_sx = E[(3 * 0 + 1) * mm + (size_t)s * m + tau]; /* F_s,x F_tau */
            double E_tx_s = E[(3 * 1 + 0) * mm + (size_t)s * m + tau]; /* F_s F_tau,x */
            double I_iy_j = I[(2 * 0 + 1) * p * p + j * p + i];        /* N_j N_i,y */
            double I_i_jy = I[(2 * 1 + 0) * p * p + j * p + i];        /* N_j,y N_i */
            double ref = C[6 * CUF_XX + CUF_YY] * E_t_sx * I_iy_j + C[6 * CUF_XY + CUF_XY] * E_tx_s * I_i_jy;
            double got = Ke[(size_t)((s * p + j) * 3 + 0) * n + (tau * p + i) * 3 + 1];
            ASSERT_NEAR(got, ref, 1e-13 * scale);
          }
  }
  cupid_free(&E);
  cupid_free(&I);
  cupid_free(&Ke);
  cupid_free(&Kb);
  cupid_cuf_beam_destroy(&b);
}

static void test_nucleus_brute_force(void **state) {
  (void)state;
  for (int p = 2; p <= 4; p++)
    for (int orth = 0; orth < 2; orth++) {
      tb_beam t;
      /* TE2 and TE3 on one rectangle cell, beam element not at the origin */
      for (int N = 1; N <= 3; N++) {
        tb_init(&t, 1.0, 0.3);
        tb_te(&t, N);
        tb_axis(&t, 0.2, 1.1, 1, p);
        tb_rect(&t, 0.1, 0.4, 1, -0.2, 0.3, 1, -1);
        check_pair(&t, orth, 0, 11 + (uint64_t)p);
      }
      for (int ln = 4; ln <= 16; ln = ln == 4 ? 9 : 16) {
        tb_init(&t, 1.0, 0.3);
        tb_le(&t, ln);
        tb_axis(&t, 0.2, 1.1, 1, p);
        tb_rect(&t, 0.1, 0.4, 1, -0.2, 0.3, 1, -1);
        check_pair(&t, orth, 0, 7 + (uint64_t)p);
        if (ln > 4) check_pair(&t, orth, 1, 5 + (uint64_t)p);
        if (ln == 16) break;
      }
    }
}

/* Rigid-body modes are in the null space of the unconstrained stiffness. */
static void check_rigid(tb_beam *t, const char *what) {
  cupid_cuf_beam b = tb_create(t);
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_cuf_assemble(b, &K));
  cupid_int n = cupid_cuf_num_dofs(b);
  double *u, *r;
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *r, "r", &r));
  double kmax = 0;
  for (cupid_int q = 0; q < K->rowptr[K->nrows] * 9; q++) kmax = fmax(kmax, fabs(K->val[q]));
  for (int mode = 0; mode < 6; mode++) {
    CUPID_ASSERT_OK(cupid_cuf_interpolate(b, tb_rigid, &mode, u));
    cupid_csr_matvec(K, u, r);
    double rn = max_abs(r, (size_t)n), un = max_abs(u, (size_t)n);
    /* K r must vanish to round-off: 1e-10 of |K| |u| allows for the cancellation of ~100
     * terms and for the TE projection (a dense solve) */
    if (!(rn <= 1e-10 * kmax * un)) fail_msg("%s: rigid mode %d: |K r| = %.3g vs |K||r| = %.3g", what, mode, rn, kmax * un);
  }
  /* and a non-rigid field is not: stretching along y must cost energy */
  cupid_cuf_info info;
  cupid_cuf_get_info(b, &info);
  cupid_free(&u);
  cupid_free(&r);
  cupid_csr_destroy(&K);
  cupid_cuf_beam_destroy(&b);
}

static void test_rigid_body_modes(void **state) {
  (void)state;
  char what[64];
  for (int integ = 0; integ < 3; integ++)
    for (int p = 2; p <= 4; p++) {
      tb_beam t;
      for (int N = 1; N <= 4; N++) {
        tb_init(&t, 70e3, 0.3);
        tb_te(&t, N);
        tb_axis(&t, 0.0, 10.0, 3, p);
        t.def.integration = integ;
        tb_rect(&t, -0.5, 0.5, 1, -1.0, 1.0, 2, -1);
        snprintf(what, sizeof what, "TE%d B%d int %d", N, p, integ);
        check_rigid(&t, what);
      }
      for (int ln = 4; ln <= 16; ln += ln == 4 ? 5 : 7) {
        tb_init(&t, 70e3, 0.3);
        tb_le(&t, ln);
        tb_axis(&t, 0.0, 10.0, 3, p);
        t.def.integration = integ;
        tb_rect(&t, 0.0, 1.0, 2, 0.0, 2.0, 2, -1);
        tb_rect(&t, 1.0, 3.0, 1, 1.0, 2.0, 1, -1); /* a second component sharing nodes */
        snprintf(what, sizeof what, "L%d B%d int %d", ln, p, integ);
        check_rigid(&t, what);
      }
    }
}

/* LE: blocks exist exactly for nodes sharing a section element (and beam element). */
static void test_pattern(void **state) {
  (void)state;
  tb_beam t;
  tb_init(&t, 1.0, 0.3);
  tb_le(&t, 4);
  tb_axis(&t, 0.0, 3.0, 3, 2);
  tb_rect(&t, 0.0, 3.0, 3, 0.0, 1.0, 1, -1); /* 3 L4 cells in a row: 8 section nodes */
  cupid_cuf_beam b = tb_create(&t);
  cupid_cuf_info info;
  cupid_cuf_get_info(b, &info);
  assert_int_equal(info.M, 8);
  assert_int_equal(info.n_beam_nodes, 4);
  assert_int_equal(info.n_dofs, 3 * 8 * 4);
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_cuf_assemble(b, &K));
  int hits = 0, misses = 0;
  for (int t1 = 0; t1 < 8; t1++)
    for (int t2 = 0; t2 < 8; t2++) {
      double x1[2], x2[2];
      cupid_cuf_section_node(b, t1, x1, NULL);
      cupid_cuf_section_node(b, t2, x2, NULL);
      int share = fabs(x1[0] - x2[0]) <= 1.0 + 1e-12; /* adjacent columns share a cell */
      for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
          double *blk = cupid_csr_find(K, i * 8 + t1, j * 8 + t2);
          int expect = share && abs(i - j) <= 1;
          if (expect) hits += blk != NULL;
          else misses += blk == NULL;
          assert_true((blk != NULL) == expect);
        }
    }
  assert_true(hits > 0 && misses > 0);
  assert_true(cupid_csr_asymmetry(K) < 1e-14);
  /* deactivating the middle cell of beam element 1 removes the couplings it carried */
  CUPID_ASSERT_OK(cupid_cuf_set_active(b, 1, 1, 0));
  cupid_csr K2 = NULL;
  CUPID_ASSERT_OK(cupid_cuf_assemble(b, &K2));
  assert_true(cupid_csr_nnz(K2) < cupid_csr_nnz(K));
  cupid_csr_destroy(&K);
  cupid_csr_destroy(&K2);
  cupid_cuf_beam_destroy(&b);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_nucleus_brute_force),
                                     cmocka_unit_test(test_rigid_body_modes),
                                     cmocka_unit_test(test_pattern)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
