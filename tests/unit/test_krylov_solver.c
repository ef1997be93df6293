/* The kept Krylov solve of a matrix-free operator (solvers.h, cupid_krylov_solver; issue 17):
 * set up once, solved again as the operator changes under it (a spring weakened: a broken
 * bond) and as DOFs are fixed after the set-up (a node held), each solve against CHOLMOD on
 * the current system; a solve cut by the iteration limit fails and leaves its iterate.
 * The operator: a chain of N nodes of 3 DOFs joined by anisotropic springs, k_e (I + a a^T),
 * node 0 fixed; the last 2 nodes stand for a beam's DOFs (after n_pd_dofs). The preconditioner
 * matrix is the chain with every other spring 1.5 times stiffer, so CG iterates. Without
 * PETSc only the refusal is checked. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cupid_config.h"
#include "testutil.h"

#define N 40
#define NDOF (3 * N)

typedef struct {
  double k[N - 1];
  double a[3];
} chain;

/* The 3x3 block of spring e (k_e (I + a a^T)) times s. */
static void spring_block(const chain *c, int e, double s, double B[9]) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) B[3 * i + j] = s * c->k[e] * ((i == j) + c->a[i] * c->a[j]);
}

static void chain_apply(const chain *c, const double *x, double *y) {
  memset(y, 0, NDOF * sizeof *y);
  for (int e = 0; e < N - 1; e++) {
    double B[9];
    spring_block(c, e, 1.0, B);
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) {
        const double d = B[3 * i + j] * (x[3 * e + 3 + j] - x[3 * e + j]);
        y[3 * e + i] -= d;
        y[3 * e + 3 + i] += d;
      }
  }
}

static cupid_status op_apply(void *ctx, const double *x, double *y) {
  chain_apply(ctx, x, y);
  return CUPID_SUCCESS;
}

static cupid_status op_rows(void *ctx, const double *x, cupid_int d0, cupid_int d1, double *y) {
  double all[NDOF];
  chain_apply(ctx, x, all);
  for (cupid_int d = d0; d < d1; d++) y[d] = all[d];
  return CUPID_SUCCESS;
}

/* The block-tridiagonal matrix of the chain, spring e scaled by scale[e]. */
static cupid_csr chain_matrix(const chain *c, const double *scale) {
  cupid_int rowptr[N + 1], col[3 * N], k = 0;
  for (int r = 0; r < N; r++) {
    rowptr[r] = k;
    for (int q = r - 1; q <= r + 1; q++)
      if (q >= 0 && q < N) col[k++] = q;
  }
  rowptr[N] = k;
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_csr_create(N, N, 3, rowptr, col, &K));
  for (int e = 0; e < N - 1; e++) {
    double B[9];
    spring_block(c, e, scale ? scale[e] : 1.0, B);
    double *ii = cupid_csr_find(K, e, e), *jj = cupid_csr_find(K, e + 1, e + 1);
    double *ij = cupid_csr_find(K, e, e + 1), *ji = cupid_csr_find(K, e + 1, e);
    for (int t = 0; t < 9; t++) ii[t] += B[t], jj[t] += B[t], ij[t] -= B[t], ji[t] -= B[t];
  }
  return K;
}

/* |u - CHOLMOD's solution of the current chain| / |that solution| (max norms). */
static double error_against_direct(const chain *c, const cupid_dirichlet_t *bc, const double *f,
                                   const double *u) {
  cupid_csr K = chain_matrix(c, NULL);
  double ud[NDOF], e = 0.0, s = 0.0;
  CUPID_ASSERT_OK(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, ud, NULL));
  for (int d = 0; d < NDOF; d++) e = fmax(e, fabs(u[d] - ud[d])), s = fmax(s, fabs(ud[d]));
  cupid_csr_destroy(&K);
  return e / s;
}

static void test_kept_solve(void **state) {
  (void)state;
  chain c = {.a = {0.6, -0.3, 0.2}};
  double scale[N - 1], f[NDOF], u[NDOF];
  for (int e = 0; e < N - 1; e++) c.k[e] = 1.0 + 0.1 * (e % 5), scale[e] = e % 2 ? 1.5 : 1.0;
  for (int d = 0; d < NDOF; d++) f[d] = 0.0;
  f[NDOF - 1] = 1.0, f[NDOF - 3] = -0.5; /* pulled at the far end */
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(NDOF, &bc));
  for (int d = 0; d < 3; d++) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, d, 0.0));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  cupid_csr P = chain_matrix(&c, scale);
  cupid_linear_operator L = {.n = NDOF, .apply = op_apply, .apply_rows = op_rows, .ctx = &c,
                             .symmetric = 1, .n_pd_dofs = NDOF - 6};
  const cupid_krylov_options ko = {.rtol = 1e-12, .factor_package = "mumps"};
  cupid_krylov_solver S = NULL;
  cupid_status st = cupid_krylov_solver_create(&L, P, bc, &ko, &S);
  if (!CUPID_HAVE_PETSC) { /* the refusal, named */
    assert_int_equal(st, CUPID_ERR_UNSUPPORTED);
    assert_non_null(strstr(cupid_error_message(), "PETSc"));
    cupid_error_clear();
    cupid_csr_destroy(&P);
    cupid_dirichlet_destroy(&bc);
    return;
  }
  CUPID_ASSERT_OK(st);
  cupid_csr_destroy(&P); /* in PETSc's factor now: the solver keeps no pointer to it */
  cupid_solve_info info;

  /* 1. from zero: the solution; the set-up charged to this first solve */
  CUPID_ASSERT_OK(cupid_krylov_solver_solve(S, f, 0, u, &info));
  double e = error_against_direct(&c, bc, f, u);
  printf("  first solve: %d iterations, residual %.2e, set-up %.3f s, error %.2e\n",
         info.iterations, info.residual, info.time_factor, e);
  assert_true(info.iterations > 1 && info.residual <= 2e-12 && e <= 1e-9);
  assert_true(info.time_factor > 0.0);
  assert_int_equal(info.n, NDOF - 3);
  const int first = info.iterations;

  /* 2. a spring weakened a thousandfold under the kept solver (the operator read at every
   *    product), solved from the last solution */
  c.k[20] *= 1e-3;
  CUPID_ASSERT_OK(cupid_krylov_solver_solve(S, f, 1, u, &info));
  e = error_against_direct(&c, bc, f, u);
  printf("  spring weakened: %d iterations, residual %.2e, error %.2e\n", info.iterations,
         info.residual, e);
  assert_true(info.residual <= 2e-12 && e <= 1e-9 && info.time_factor == 0.0);

  /* 3. a node held at its displacement after the set-up (a fixed row of the kept system) */
  const double held[3] = {u[3 * 30], u[3 * 30 + 1], u[3 * 30 + 2]};
  for (int d = 0; d < 3; d++) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, 3 * 30 + d, held[d]));
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  c.k[10] *= 0.5;
  CUPID_ASSERT_OK(cupid_krylov_solver_solve(S, f, 1, u, &info));
  e = error_against_direct(&c, bc, f, u);
  printf("  node held: %d iterations, residual %.2e, error %.2e\n", info.iterations, info.residual, e);
  assert_true(info.residual <= 2e-12 && e <= 1e-9);
  for (int d = 0; d < 3; d++) assert_true(u[3 * 30 + d] == held[d]);

  /* 4. cut at one iteration, the system changed again: an error, u the (finite) iterate */
  cupid_krylov_solver_limit(S, 1);
  c.k[5] *= 1e-2;
  double before[NDOF];
  memcpy(before, u, sizeof before);
  st = cupid_krylov_solver_solve(S, f, 1, u, &info);
  assert_int_equal(st, CUPID_ERR_NUMERIC);
  cupid_error_clear();
  int moved = 0;
  for (int d = 0; d < NDOF; d++) assert_true(isfinite(u[d])), moved |= u[d] != before[d];
  assert_true(moved && info.iterations == 1 && first > 1);
  cupid_krylov_solver_destroy(&S);
  assert_null(S);
  cupid_dirichlet_destroy(&bc);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_kept_solve)};
  int rc = cmocka_run_group_tests(tests, NULL, NULL);
#if CUPID_HAVE_PETSC
  cupid_petsc_finalize();
#endif
  return rc;
}
