/* Unit tests of block CSR matrices and Dirichlet conditions (src/solvers/csr.c, dirichlet.c). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

/* Dense row-major copy of a block CSR matrix (scalar entries), for reference products. */
static double *to_dense(const cupid_csr_t *A) {
  const int bs = A->bs;
  const cupid_int m = A->nrows * bs, n = A->ncols * bs;
  double *D = calloc((size_t)(m * n) + 1, sizeof *D);
  assert_non_null(D);
  for (cupid_int r = 0; r < A->nrows; r++)
    for (cupid_int p = A->rowptr[r]; p < A->rowptr[r + 1]; p++)
      for (int a = 0; a < bs; a++)
        for (int b = 0; b < bs; b++)
          D[(r * bs + a) * n + A->col[p] * bs + b] = A->val[(p * bs + a) * bs + b];
  return D;
}

/* A random block matrix with about density*ncols blocks per row (the diagonal always present). */
static cupid_csr random_csr(cupid_int nrows, cupid_int ncols, int bs, double density,
                            uint64_t *seed) {
  cupid_int *rowptr = malloc((size_t)(nrows + 1) * sizeof *rowptr);
  cupid_int *col = malloc((size_t)(nrows * ncols) * sizeof *col + 1);
  assert_non_null(rowptr);
  assert_non_null(col);
  rowptr[0] = 0;
  cupid_int nnz = 0;
  for (cupid_int r = 0; r < nrows; r++) {
    for (cupid_int c = 0; c < ncols; c++)
      if (c == r || 0.5 * (cupid_test_random(seed) + 1.0) < density) col[nnz++] = c;
    rowptr[r + 1] = nnz;
  }
  cupid_csr A = NULL;
  CUPID_ASSERT_OK(cupid_csr_create(nrows, ncols, bs, rowptr, col, &A));
  for (cupid_int k = 0; k < cupid_csr_nnz(A); k++) A->val[k] = cupid_test_random(seed);
  free(rowptr);
  free(col);
  return A;
}

static void test_triplets_duplicates(void **state) {
  (void)state;
  enum { M = 7, N = 5, T = 60 };
  uint64_t seed = 1;
  cupid_int I[T], J[T];
  double V[T], dense[M][N] = {{0}};
  int hit[M][N] = {{0}};
  for (int t = 0; t < T; t++) {
    I[t] = (cupid_int)((cupid_test_random(&seed) + 1.0) * 0.5 * M);
    J[t] = (cupid_int)((cupid_test_random(&seed) + 1.0) * 0.5 * N);
    V[t] = cupid_test_random(&seed);
    dense[I[t]][J[t]] += V[t];
    hit[I[t]][J[t]] = 1;
  }
  cupid_csr A = NULL;
  CUPID_ASSERT_OK(cupid_csr_from_triplets(M, N, T, I, J, V, &A));
  assert_int_equal(A->bs, 1);
  cupid_int expected_nnz = 0;
  for (int r = 0; r < M; r++)
    for (int c = 0; c < N; c++) {
      expected_nnz += hit[r][c];
      const double *v = cupid_csr_find(A, r, c);
      if (!hit[r][c]) {
        assert_null(v);
        continue;
      }
      assert_non_null(v);
      /* sums of at most T numbers in [-1, 1): order-dependent round-off only */
      ASSERT_NEAR(*v, dense[r][c], 1e-14);
    }
  assert_int_equal(cupid_csr_nnz(A), expected_nnz);
  for (int r = 0; r < M; r++)
    for (cupid_int p = A->rowptr[r] + 1; p < A->rowptr[r + 1]; p++)
      assert_true(A->col[p] > A->col[p - 1]);
  cupid_csr_destroy(&A);
  assert_null(A);
  cupid_csr_destroy(&A); /* harmless */

  /* empty matrix and zero triplets */
  CUPID_ASSERT_OK(cupid_csr_from_triplets(3, 3, 0, NULL, NULL, NULL, &A));
  assert_int_equal(cupid_csr_nnz(A), 0);
  double x[3] = {1, 2, 3}, y[3] = {9, 9, 9};
  cupid_csr_matvec(A, x, y);
  for (int k = 0; k < 3; k++) assert_true(y[k] == 0.0);
  cupid_csr_destroy(&A);

  /* out-of-range triplet */
  cupid_int bi[1] = {3}, bj[1] = {0};
  double bv[1] = {1};
  assert_int_equal(cupid_csr_from_triplets(3, 3, 1, bi, bj, bv, &A), CUPID_ERR_ARGUMENT);
  assert_null(A);
}

/* y = A x against the dense product, for bs = 1 and 3 (and the transpose product). */
static void check_matvec(int bs, uint64_t seed) {
  const cupid_int m = 9, n = 7;
  cupid_csr A = random_csr(m, n, bs, 0.4, &seed);
  double *D = to_dense(A);
  const cupid_int M = m * bs, N = n * bs;
  double *x = malloc((size_t)N * sizeof *x), *y = malloc((size_t)M * sizeof *y);
  double *xt = malloc((size_t)M * sizeof *xt), *yt = malloc((size_t)N * sizeof *yt);
  for (cupid_int k = 0; k < N; k++) x[k] = cupid_test_random(&seed);
  for (cupid_int k = 0; k < M; k++) xt[k] = cupid_test_random(&seed);
  cupid_csr_matvec(A, x, y);
  cupid_csr_matvec_transpose(A, xt, yt);
  for (cupid_int r = 0; r < M; r++) {
    double s = 0.0;
    for (cupid_int c = 0; c < N; c++) s += D[r * N + c] * x[c];
    ASSERT_NEAR(y[r], s, 1e-13); /* <= 21 products of numbers in [-1,1): round-off ~1e-15 */
  }
  for (cupid_int c = 0; c < N; c++) {
    double s = 0.0;
    for (cupid_int r = 0; r < M; r++) s += D[r * N + c] * xt[r];
    ASSERT_NEAR(yt[c], s, 1e-13);
  }
  /* Row ranges of y placed at an offset inside a longer vector (cupid_csr_matvec_rows): the
   * whole product's rows to 1e-13 (the bs = 3 product sums in its own order; same bound as
   * above); entries outside the range, and the parts of ranges beyond A's rows, untouched.
   * Ranges cut blocks of rows. */
  const cupid_int off = 5, L = off + M + 4;
  double *z = malloc((size_t)L * sizeof *z);
  const cupid_int ranges[4][2] = {{0, L}, {off + 1, off + M - 2}, {off + M - 1, L}, {3, 3}};
  for (int q = 0; q < 4; q++) {
    for (cupid_int d = 0; d < L; d++) z[d] = -7.0;
    const cupid_int d0 = ranges[q][0], d1 = ranges[q][1];
    cupid_csr_matvec_rows(A, x, off, d0, d1, z);
    for (cupid_int d = 0; d < L; d++) {
      int in = d >= d0 && d < d1 && d >= off && d < off + M;
      if (in) ASSERT_NEAR(z[d], y[d - off], 1e-13);
      else assert_true(z[d] == -7.0);
    }
  }
  free(z);
  free(D);
  free(x);
  free(y);
  free(xt);
  free(yt);
  cupid_csr_destroy(&A);
}

static void test_matvec(void **state) {
  (void)state;
  check_matvec(1, 11);
  check_matvec(3, 12);
}

static void test_to_scalar(void **state) {
  (void)state;
  uint64_t seed = 5;
  cupid_csr A = random_csr(6, 8, 3, 0.3, &seed), S = NULL;
  CUPID_ASSERT_OK(cupid_csr_to_scalar(A, &S));
  assert_int_equal(S->bs, 1);
  assert_int_equal(S->nrows, 18);
  assert_int_equal(S->ncols, 24);
  assert_int_equal(cupid_csr_nnz(S), cupid_csr_nnz(A));
  double *DA = to_dense(A), *DS = to_dense(S);
  assert_memory_equal(DA, DS, 18 * 24 * sizeof(double)); /* a pure copy: exact */
  for (cupid_int r = 0; r < S->nrows; r++)
    for (cupid_int p = S->rowptr[r] + 1; p < S->rowptr[r + 1]; p++)
      assert_true(S->col[p] > S->col[p - 1]);
  free(DA);
  free(DS);
  /* bs = 1 gives a copy */
  cupid_csr S2 = NULL;
  CUPID_ASSERT_OK(cupid_csr_to_scalar(S, &S2));
  assert_int_equal(cupid_csr_nnz(S2), cupid_csr_nnz(S));
  assert_memory_equal(S2->val, S->val, (size_t)cupid_csr_nnz(S) * sizeof(double));
  cupid_csr_destroy(&S2);
  cupid_csr_destroy(&S);
  cupid_csr_destroy(&A);
}

static void test_find(void **state) {
  (void)state;
  /* [x . x ; . x . ; x x x] in 3x3 blocks */
  const cupid_int rowptr[] = {0, 2, 3, 6}, col[] = {0, 2, 1, 0, 1, 2};
  cupid_csr A = NULL;
  CUPID_ASSERT_OK(cupid_csr_create(3, 3, 3, rowptr, col, &A));
  for (cupid_int k = 0; k < cupid_csr_nnz(A); k++) assert_true(A->val[k] == 0.0);
  for (cupid_int k = 0; k < cupid_csr_nnz(A); k++) A->val[k] = (double)k;
  assert_ptr_equal(cupid_csr_find(A, 0, 0), A->val);
  assert_ptr_equal(cupid_csr_find(A, 0, 2), A->val + 9);
  assert_ptr_equal(cupid_csr_find(A, 2, 1), A->val + 9 * 4);
  assert_ptr_equal(cupid_csr_find(A, 2, 2), A->val + 9 * 5);
  assert_null(cupid_csr_find(A, 0, 1));
  assert_null(cupid_csr_find(A, 1, 0));
  assert_null(cupid_csr_find(A, 1, 2));
  assert_null(cupid_csr_find(A, 3, 0));
  assert_null(cupid_csr_find(A, -1, 0));
  assert_null(cupid_csr_find(A, 0, 3));
  assert_int_equal(cupid_csr_nnz(A), 54);
  assert_true(cupid_csr_bytes(A) >= (int64_t)(4 * 8 + 6 * 8 + 54 * 8));
  double d[9];
  CUPID_ASSERT_OK(cupid_csr_diagonal(A, d));
  for (int a = 0; a < 3; a++) {
    assert_true(d[a] == (double)(4 * a));          /* block 0 */
    assert_true(d[3 + a] == (double)(18 + 4 * a)); /* block 2 */
    assert_true(d[6 + a] == (double)(45 + 4 * a)); /* block 5 */
  }
  cupid_csr_destroy(&A);
}

static cupid_csr small_scalar(const double (*v)[3], int n) {
  cupid_int I[9], J[9];
  double V[9];
  int t = 0;
  for (int r = 0; r < n; r++)
    for (int c = 0; c < n; c++)
      if (v[r][c] != 0.0) {
        I[t] = r;
        J[t] = c;
        V[t++] = v[r][c];
      }
  cupid_csr A = NULL;
  CUPID_ASSERT_OK(cupid_csr_from_triplets(n, n, t, I, J, V, &A));
  return A;
}

static void test_asymmetry(void **state) {
  (void)state;
  const double sym[3][3] = {{4, -1, 0.5}, {-1, 3, 0}, {0.5, 0, 2}};
  const double nonsym[3][3] = {{4, -1, 0.5}, {-2, 3, 0}, {0.5, 0, 2}};
  const double pattern[3][3] = {{4, 0, 0.5}, {-1, 3, 0}, {0.5, 0, 2}};
  cupid_csr A = small_scalar(sym, 3);
  assert_true(cupid_csr_asymmetry(A) == 0.0);
  cupid_csr_destroy(&A);
  A = small_scalar(nonsym, 3);
  ASSERT_NEAR(cupid_csr_asymmetry(A), 1.0 / 4.0, 1e-15); /* |-1 - -2| / 4 */
  cupid_csr_destroy(&A);
  A = small_scalar(pattern, 3); /* (1,0) stored, (0,1) not */
  ASSERT_NEAR(cupid_csr_asymmetry(A), 1.0 / 4.0, 1e-15);
  cupid_csr_destroy(&A);

  /* a bs = 3 Kronecker product of symmetric matrices is symmetric; perturb one entry */
  uint64_t seed = 9;
  const cupid_int rowptr[] = {0, 2, 4}, col[] = {0, 1, 0, 1};
  CUPID_ASSERT_OK(cupid_csr_create(2, 2, 3, rowptr, col, &A));
  const double L[2][2] = {{2, -1}, {-1, 2}};
  double B[3][3];
  for (int a = 0; a < 3; a++)
    for (int b = 0; b <= a; b++) B[a][b] = B[b][a] = cupid_test_random(&seed);
  for (int r = 0; r < 2; r++)
    for (int c = 0; c < 2; c++) {
      double *blk = cupid_csr_find(A, r, c);
      for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) blk[3 * a + b] = L[r][c] * B[a][b];
    }
  assert_true(cupid_csr_asymmetry(A) == 0.0);
  double maxabs = 0;
  for (cupid_int k = 0; k < cupid_csr_nnz(A); k++) maxabs = fmax(maxabs, fabs(A->val[k]));
  cupid_csr_find(A, 0, 1)[1] += 1e-3; /* entry (0, 4) */
  ASSERT_NEAR(cupid_csr_asymmetry(A), 1e-3 / fmax(maxabs, fabs(cupid_csr_find(A, 0, 1)[1])),
              1e-15);
  cupid_csr_destroy(&A);
}

static void test_bad_patterns(void **state) {
  (void)state;
  cupid_csr A = (cupid_csr)1;
  const cupid_int rp[] = {0, 2, 3};
  const cupid_int unsorted[] = {1, 0, 1}, duplicate[] = {1, 1, 0}, out[] = {0, 2, 1},
                  negative[] = {-1, 0, 1};
  assert_int_equal(cupid_csr_create(2, 2, 1, rp, unsorted, &A), CUPID_ERR_ARGUMENT);
  assert_null(A);
  assert_non_null(strstr(cupid_error_message(), "sorted"));
  assert_int_equal(cupid_csr_create(2, 2, 1, rp, duplicate, &A), CUPID_ERR_ARGUMENT);
  assert_int_equal(cupid_csr_create(2, 2, 1, rp, out, &A), CUPID_ERR_ARGUMENT);
  assert_non_null(strstr(cupid_error_message(), "outside"));
  assert_int_equal(cupid_csr_create(2, 2, 1, rp, negative, &A), CUPID_ERR_ARGUMENT);
  const cupid_int good[] = {0, 1, 1};
  assert_int_equal(cupid_csr_create(2, 2, 2, rp, good, &A), CUPID_ERR_ARGUMENT); /* bs = 2 */
  assert_int_equal(cupid_csr_create(-1, 2, 1, rp, good, &A), CUPID_ERR_ARGUMENT);
  const cupid_int rp_bad0[] = {1, 2, 3}, rp_decr[] = {0, 2, 1};
  assert_int_equal(cupid_csr_create(2, 2, 1, rp_bad0, good, &A), CUPID_ERR_ARGUMENT);
  assert_int_equal(cupid_csr_create(2, 2, 1, rp_decr, good, &A), CUPID_ERR_ARGUMENT);
  assert_null(A);
  CUPID_ASSERT_OK(cupid_csr_create(2, 2, 1, rp, good, &A));
  cupid_csr_destroy(&A);
}

static void test_scale_axpy(void **state) {
  (void)state;
  uint64_t seed = 21;
  cupid_csr K = random_csr(5, 5, 3, 0.5, &seed), M = NULL, C = NULL;
  CUPID_ASSERT_OK(cupid_csr_duplicate(K, &M));
  assert_memory_equal(M->val, K->val, (size_t)cupid_csr_nnz(K) * sizeof(double));
  for (cupid_int k = 0; k < cupid_csr_nnz(M); k++) M->val[k] = cupid_test_random(&seed);
  /* Rayleigh damping C = a M + b K */
  const double a = 0.3, b = 2e-3;
  CUPID_ASSERT_OK(cupid_csr_duplicate(K, &C));
  cupid_csr_scale(C, b);
  CUPID_ASSERT_OK(cupid_csr_axpy(a, M, C));
  for (cupid_int k = 0; k < cupid_csr_nnz(C); k++)
    ASSERT_NEAR(C->val[k], a * M->val[k] + b * K->val[k], 1e-16); /* two roundings of O(1) */
  cupid_csr_zero(C);
  for (cupid_int k = 0; k < cupid_csr_nnz(C); k++) assert_true(C->val[k] == 0.0);
  cupid_csr other = random_csr(5, 5, 3, 0.5, &seed);
  assert_int_equal(cupid_csr_axpy(1.0, other, C), CUPID_ERR_ARGUMENT);
  cupid_csr_destroy(&other);
  other = random_csr(5, 5, 1, 1.0, &seed);
  assert_int_equal(cupid_csr_axpy(1.0, other, C), CUPID_ERR_ARGUMENT);
  cupid_csr_destroy(&other);
  other = random_csr(5, 4, 1, 0.5, &seed); /* rectangular: no diagonal */
  double d[5];
  assert_int_equal(cupid_csr_diagonal(other, d), CUPID_ERR_ARGUMENT);
  cupid_csr_destroy(&other);
  cupid_csr_destroy(&C);
  cupid_csr_destroy(&M);
  cupid_csr_destroy(&K);
}

static void test_dirichlet(void **state) {
  (void)state;
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(6, &bc));
  assert_int_equal(bc->n_free, 6);
  CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 1, 0.5));
  bc->fixed[4] = 1;
  bc->value[4] = -2.0;
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  const cupid_int expect[6] = {0, -1, 1, 2, -1, 3};
  assert_int_equal(bc->n_free, 4);
  for (int i = 0; i < 6; i++) assert_int_equal(bc->free_index[i], expect[i]);
  assert_int_equal(cupid_dirichlet_fix(bc, 6, 0.0), CUPID_ERR_ARGUMENT);
  assert_int_equal(cupid_dirichlet_fix(bc, -1, 0.0), CUPID_ERR_ARGUMENT);
  bc->fixed[0] = 1;
  bc->value[0] = NAN;
  assert_int_equal(cupid_dirichlet_finalize(bc), CUPID_ERR_ARGUMENT);
  cupid_dirichlet_destroy(&bc);
  assert_null(bc);
  cupid_dirichlet_destroy(&bc);
  assert_int_equal(cupid_dirichlet_create(-1, &bc), CUPID_ERR_ARGUMENT);
  CUPID_ASSERT_OK(cupid_dirichlet_create(0, &bc));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  assert_int_equal(bc->n_free, 0);
  cupid_dirichlet_destroy(&bc);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_triplets_duplicates), cmocka_unit_test(test_matvec),
      cmocka_unit_test(test_to_scalar),           cmocka_unit_test(test_find),
      cmocka_unit_test(test_asymmetry),           cmocka_unit_test(test_bad_patterns),
      cmocka_unit_test(test_scale_axpy),          cmocka_unit_test(test_dirichlet)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
