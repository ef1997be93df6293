/* cupid_pd_operator_row_bound (src/pd/assemble.c): a guaranteed bound of K's block rows for the
 * stable step of explicit dynamics, without K. Against the assembled K of small grids:
 *  - r_i equals its formula evaluated from independent pieces (reference_bound: the assembled
 *    K and the dilatation map probed column by column), to 1e-10 relative;
 *  - r_i >= sum_j |K_ij|_2 for every node (the bound's promise; |.|_2 of each 3x3 block by the
 *    eigenvalues of B^T B, so the check itself does not over-estimate; 1e-12 relative slack
 *    for the different summation orders);
 *  - r_i <= 2.5 sum_j |K_ij|_2: the bound is useful, not only true. Its only slack is the
 *    triangle inequality (blocks of the pair and dilatation terms, and of the g_p g_p^T
 *    terms, added by norms: they partly cancel where g_p's blocks point opposite ways), at
 *    most 2x on a row when the two parts are equal; measured at most 1.74 here (printed). A
 *    wrong coefficient (a missing V, m or factor 2) breaks one side or the other;
 *  - with a lumped mass, max r_i / m_i >= the Lanczos estimate of lambda_max(M^-1 K) (the
 *    ratio printed: Gershgorin's own gap, up to ~5 on these small grids).
 * Every model, influence and partial-volume rule, two materials (nu = 0.2: 3K - 5mu < 0), a
 * surface correction, pre-cracks (broken bonds change m and the families), nodes with the
 * full stencil, a 1D bar. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "cupid/dynamics.h"
#include "testutil.h"

static cupid_box box3(double x0, double x1, double y0, double y1, double z0, double z1) {
  cupid_box b = {.lo = {x0, y0, z0}, .hi = {x1, y1, z1}, .has = {1, 1, 1}};
  return b;
}

/* |B|_2 of a 3x3 block: the square root of B^T B's largest eigenvalue (symmetric 3x3, by
 * the trigonometric closed form). */
static double block_norm(const double *B) {
  double A[9];
  for (int r = 0; r < 3; r++)
    for (int c = 0; c < 3; c++) {
      double s = 0.0;
      for (int k = 0; k < 3; k++) s += B[3 * k + r] * B[3 * k + c];
      A[3 * r + c] = s;
    }
  const double p1 = A[1] * A[1] + A[2] * A[2] + A[5] * A[5];
  const double q = (A[0] + A[4] + A[8]) / 3.0;
  const double p2 = (A[0] - q) * (A[0] - q) + (A[4] - q) * (A[4] - q) + (A[8] - q) * (A[8] - q) + 2 * p1;
  const double p = sqrt(p2 / 6.0);
  if (p == 0.0) return sqrt(fmax(q, 0.0));
  double Bm[9];
  for (int k = 0; k < 9; k++) Bm[k] = (A[k] - (k % 4 == 0 ? q : 0.0)) / p;
  const double det = Bm[0] * (Bm[4] * Bm[8] - Bm[5] * Bm[7]) - Bm[1] * (Bm[3] * Bm[8] - Bm[5] * Bm[6]) +
                     Bm[2] * (Bm[3] * Bm[7] - Bm[4] * Bm[6]);
  const double r = fmax(-1.0, fmin(1.0, det / 2.0));
  const double lmax = q + 2 * p * cos(acos(r) / 3.0);
  return sqrt(fmax(lmax, 0.0));
}

static double worst_ratio = 0.0, worst_lambda_ratio = 0.0;

/* The bound's own formula from independent pieces: g_p[k] = d theta_p / d u_k probed column by
 * column through cupid_pd_operator_dilatation, K_dil = sum_p c_p g_p g_p^T (c_p = V kappa_p / 3
 * from the node's material), K_pair = K - K_dil from the assembled K; then
 * ref_i = 2 sum_{j != i} |K_pair,ij| + sum_p |c_p| |g_p[i]| sum_k |g_p[k]|. */
static double *reference_bound(cupid_pd_grid g, cupid_pd_operator op, const cupid_csr_t *K,
                               int lps, const cupid_pd_material *mats) {
  const cupid_int nn = cupid_pd_grid_num_nodes(g), n = 3 * nn;
  double *Kd = calloc((size_t)n * (size_t)n, sizeof *Kd), *ref = calloc((size_t)nn, sizeof *ref);
  double *gm = calloc((size_t)nn * (size_t)n, sizeof *gm), *c = calloc((size_t)nn, sizeof *c);
  double *u = calloc((size_t)n, sizeof *u), *th = calloc((size_t)nn, sizeof *th);
  cupid_int *sup = malloc((size_t)n * sizeof *sup);
  assert_true(Kd && ref && gm && c && u && th && sup);
  const double V = cupid_pd_grid_cell_volume(g);
  const int *mat = cupid_pd_grid_materials(g);
  if (lps) {
    for (cupid_int k = 0; k < n; k++) {
      u[k] = 1.0;
      CUPID_ASSERT_OK(cupid_pd_operator_dilatation(op, u, th));
      u[k] = 0.0;
      for (cupid_int p = 0; p < nn; p++) gm[p * n + k] = th[p];
    }
    for (cupid_int p = 0; p < nn; p++) {
      const cupid_pd_material *M = &mats[mat[p]];
      const double Kb = M->E / (3 * (1 - 2 * M->nu)), mu = M->E / (2 * (1 + M->nu));
      c[p] = V * (3 * Kb - 5 * mu) / 3.0;
      cupid_int ns = 0;
      for (cupid_int k = 0; k < n; k++)
        if (gm[p * n + k] != 0.0) sup[ns++] = k;
      for (cupid_int a = 0; a < ns; a++)
        for (cupid_int b = 0; b < ns; b++)
          Kd[sup[a] * n + sup[b]] += c[p] * gm[p * n + sup[a]] * gm[p * n + sup[b]];
    }
  }
  for (cupid_int i = 0; i < nn; i++) {
    for (cupid_int b = K->rowptr[i]; b < K->rowptr[i + 1]; b++) {
      const cupid_int j = K->col[b];
      if (j == i) continue;
      double B[9];
      for (int r = 0; r < 3; r++)
        for (int q = 0; q < 3; q++) B[3 * r + q] = K->val[9 * b + 3 * r + q] - Kd[(3 * i + r) * n + 3 * j + q];
      ref[i] += 2.0 * block_norm(B);
    }
    if (!lps) continue;
    for (cupid_int p = 0; p < nn; p++) {
      const double *gp = gm + p * n;
      const double gi = sqrt(gp[3 * i] * gp[3 * i] + gp[3 * i + 1] * gp[3 * i + 1] + gp[3 * i + 2] * gp[3 * i + 2]);
      if (gi == 0.0) continue;
      double G = 0.0;
      for (cupid_int k = 0; k < nn; k++)
        G += sqrt(gp[3 * k] * gp[3 * k] + gp[3 * k + 1] * gp[3 * k + 1] + gp[3 * k + 2] * gp[3 * k + 2]);
      ref[i] += fabs(c[p]) * gi * G;
    }
  }
  free(Kd), free(gm), free(c), free(u), free(th), free(sup);
  return ref;
}

/* The checks of the header on one operator. */
static void check_bound(cupid_pd_grid g, cupid_pd_operator op, const char *label, int lps,
                        const cupid_pd_material *mats) {
  const cupid_int nn = cupid_pd_grid_num_nodes(g), n = 3 * nn;
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(op, &K));
  double *r = malloc((size_t)n * sizeof *r), *m = malloc((size_t)n * sizeof *m);
  assert_non_null(r);
  assert_non_null(m);
  CUPID_ASSERT_OK(cupid_pd_operator_row_bound(op, r));
  double ratio = 0.0, lam_bound = 0.0;
  double *ref = reference_bound(g, op, K, lps, mats);
  for (cupid_int i = 0; i < nn; i++) {
    /* 1e-10: the probed g and the assembled K carry round-off of the sums of ~100 terms, and
     * K_pair is K minus K_dil (cancellation up to |K_dil| / |K_pair| ~ 10) */
    if (!(fabs(r[3 * i] - ref[i]) <= 1e-10 * ref[i]))
      fail_msg("%s: node %lld: bound %.15g, its formula from K and theta %.15g", label,
               (long long)i, r[3 * i], ref[i]);
    double exact = 0.0;
    for (cupid_int b = K->rowptr[i]; b < K->rowptr[i + 1]; b++) exact += block_norm(K->val + 9 * b);
    assert_true(r[3 * i] == r[3 * i + 1] && r[3 * i] == r[3 * i + 2]);
    if (!(r[3 * i] >= exact * (1 - 1e-12)))
      fail_msg("%s: node %lld: bound %.15g below the row's block norms %.15g", label,
               (long long)i, r[3 * i], exact);
    if (exact > 0) ratio = fmax(ratio, r[3 * i] / exact);
    for (int c = 0; c < 3; c++) m[3 * i + c] = 2.5 + 0.1 * (double)(i % 7); /* uneven nodes */
    lam_bound = fmax(lam_bound, r[3 * i] / m[3 * i]);
  }
  if (ratio > 2.5) fail_msg("%s: the bound is %.3g times a row's block norms", label, ratio);
  worst_ratio = fmax(worst_ratio, ratio);
  double est = 0.0, gersh = 0.0;
  CUPID_ASSERT_OK(cupid_dynamics_lambda_max(K, m, NULL, 200, &est, &gersh));
  if (!(lam_bound >= est * (1 - 1e-9)))
    fail_msg("%s: lambda bound %.6g against the Lanczos estimate %.6g", label, lam_bound, est);
  worst_lambda_ratio = fmax(worst_lambda_ratio, lam_bound / est);
  free(r);
  free(m);
  free(ref);
  cupid_csr_destroy(&K);
}

static cupid_pd_material materials[2] = {{2.0e3, 0.3}, {6.0e3, 0.2}};

static cupid_pd_operator make_op(cupid_pd_grid g, int model, int infl, int pvr, double delta,
                                 cupid_surface_correction sc) {
  cupid_pd_operator_options o = {.horizon = delta, .model = (cupid_pd_model_kind)model,
                                 .influence = (cupid_influence)infl,
                                 .partial_volume = (cupid_partial_volume)pvr,
                                 .materials = materials, .n_materials = 2,
                                 .surface_correction = sc};
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(g, &o, &op));
  return op;
}

/* Every option on a box and on an L of two materials; a surface correction; a pre-crack. */
static void test_against_assembled(void **state) {
  (void)state;
  cupid_box b[2] = {box3(0, 4, 0, 1.5, 0, 2), box3(0, 1.5, 1.5, 4, 0, 2)};
  int mats[2] = {0, 1};
  cupid_pd_grid_options go = {.spacing = 0.5, .dimension = 3};
  cupid_pd_grid grids[2] = {NULL, NULL};
  cupid_box box = box3(0, 6, 0, 5, 0, 7);
  int mat0 = 0;
  cupid_pd_grid_options g1 = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&g1, 1, &box, &mat0, &grids[0]));
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 2, b, mats, &grids[1]));
  const double deltas[2] = {3.015, 1.25};
  char label[160];
  /* CUPID_TEST_SMALL (valgrind): the inverse influence and PDLAMMPS volumes only */
  const int small = getenv("CUPID_TEST_SMALL") != NULL;
  for (int gi = 0; gi < 2; gi++)
    for (int model = 0; model < 2; model++)
      for (int infl = small; infl < (small ? 2 : 3); infl++)
        for (int pvr = small; pvr < (small ? 2 : 3); pvr++)
          for (int sc = 0; sc < 2; sc++) {
            snprintf(label, sizeof label, "grid %d model %d influence %d volumes %d correction %d",
                     gi, model, infl, pvr, sc);
            cupid_pd_operator op = make_op(grids[gi], model, infl, pvr, deltas[gi],
                                           sc ? CUPID_SURFACE_ENERGY : CUPID_SURFACE_NONE);
            check_bound(grids[gi], op, label, model == 0, materials);
            if (!sc) { /* a pre-crack through the middle: broken bonds, smaller m */
              cupid_pd_precrack c = {.normal = 1, .at = gi ? 0.75 : 2.0, .lo = {0, 0, 0},
                                     .hi = {gi ? 1.0 : 3.0, 0, 7}};
              cupid_int removed = 0;
              CUPID_ASSERT_OK(cupid_pd_operator_precrack(op, &c, &removed));
              assert_true(removed > 0);
              snprintf(label, sizeof label, "grid %d model %d influence %d volumes %d pre-cracked",
                       gi, model, infl, pvr);
              check_bound(grids[gi], op, label, model == 0, materials);
            }
            cupid_pd_operator_destroy(&op);
          }
  for (int gi = 0; gi < 2; gi++) cupid_pd_grid_destroy(&grids[gi]);
  print_message("row bound / sum of block norms: at most %.3f; lambda bound / Lanczos: at most %.3f\n",
                worst_ratio, worst_lambda_ratio);
}

/* An 8 x 8 x 8 lattice (delta = 3.015 h): its 8 middle nodes have the full stencil, the
 * shortcut of the bound for full, intact families without surface factors. */
static void test_full_stencil(void **state) {
  (void)state;
  cupid_box box = box3(0, 8, 0, 8, 0, 8);
  int mat = 0;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &box, &mat, &g));
  assert_int_equal(cupid_pd_grid_num_nodes(g), 512);
  for (int model = 0; model < 2; model++) {
    cupid_pd_operator op = make_op(g, model, CUPID_INFLUENCE_INVERSE, CUPID_PARTIAL_PDLAMMPS,
                                   3.015, CUPID_SURFACE_NONE);
    check_bound(g, op, model == 0 ? "8^3 LPS" : "8^3 bond-based", model == 0, materials);
    cupid_pd_operator_destroy(&op);
  }
  cupid_pd_grid_destroy(&g);
}

/* A 1D bond-based bar (3 DOFs a node, motion along y). */
static void test_bar(void **state) {
  (void)state;
  cupid_box b = {.lo = {0, 0, 0}, .hi = {0, 5, 0}, .has = {0, 1, 0}};
  int mat = 1;
  cupid_pd_grid_options go = {.spacing = 0.25, .dimension = 1, .area = 0.3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &b, &mat, &g));
  cupid_pd_operator op = make_op(g, CUPID_PD_BOND, CUPID_INFLUENCE_CONSTANT, CUPID_PARTIAL_NONE,
                                 0.8, CUPID_SURFACE_NONE);
  check_bound(g, op, "1D bar", 0, materials);
  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&g);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_against_assembled),
                                     cmocka_unit_test(test_full_stencil),
                                     cmocka_unit_test(test_bar)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
