/*
 * A reusable factorisation of K_ff (include/cupid/solvers.h, "reusable factorisation" block):
 * factored once, solved many times: at every step of an implicit time integration with a
 * constant step (Newmark, CHOLMOD), or at every iteration of a Krylov solve preconditioned by
 * a cheap twin (src/solvers/iterative.c: CHOLMOD for SPD twins, UMFPACK LU for the others).
 * Only the free DOFs are factored; SPD: lower triangle stored.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cholmod.h>
#include <umfpack.h>

#include "cupid/solvers.h"
#include "solvers_internal.h"

_Static_assert(sizeof(SuiteSparse_long) == sizeof(cupid_int), "SuiteSparse_long is not 64-bit");

struct cupid_direct_factor_private {
  cupid_matrix_kind kind; /* SPD: CHOLMOD LL'; GENERAL: UMFPACK LU */
  cupid_int n_full, n;  /* all scalar DOFs, free DOFs */
  cupid_int *global;    /* free index -> global DOF */
  cupid_int *p, *i;     /* lower triangle of K_ff, compressed column */
  double *x;
  cholmod_common cc;
  int cc_started;
  cholmod_factor *L;
  void *symbolic, *numeric; /* UMFPACK (GENERAL) */
  double control[UMFPACK_CONTROL];
  double *work, *work2; /* n: right-hand side / solution in free numbering */
  cupid_int *pivot_of;  /* downdates: global DOF -> its row in the permuted factor, -1 fixed */
  unsigned char *held;  /* per row of the permuted factor: deleted by cupid_direct_factor_hold
                           (the identity's row), or NULL while none is */
  cupid_int failed_dof; /* the DOF whose pivot the last update or downdate left non-positive or
                           below the bound, -1 if none (cupid_direct_factor_failed_dof) */
};

/* The rows of K_ff in compressed form, in free numbering (free DOFs are numbered in increasing
 * global order, so indices stay sorted). With lower, row k keeps the columns >= k: column k of
 * the lower triangle of the symmetric K_ff (CHOLMOD). Without, every column: read as columns
 * the rows are K_ff^T, which UMFPACK solves with UMFPACK_At (no transposed copy). */
static cupid_status reduce(cupid_direct_factor F, const cupid_csr_t *K, const cupid_int *fi,
                           int lower) {
  const int bs = K->bs;
  CUPID_CALL(cupid_calloc((size_t)F->n + 1, sizeof *F->p, "factor pointers", &F->p));
  for (int pass = 0; pass < 2; pass++) {
    for (cupid_int k = 0; k < F->n; k++) {
      cupid_int g = F->global[k], row = g / bs, t = pass ? F->p[k] : 0;
      int a = (int)(g % bs);
      for (cupid_int q = K->rowptr[row]; q < K->rowptr[row + 1]; q++)
        for (int b = 0; b < bs; b++) {
          cupid_int c = fi ? fi[K->col[q] * bs + b] : K->col[q] * bs + b;
          if (c < 0 || (lower && c < k)) continue;
          if (pass) {
            F->i[t] = c;
            F->x[t] = K->val[(q * bs + a) * bs + b];
          }
          t++;
        }
      if (!pass) F->p[k + 1] = t;
    }
    if (!pass) {
      for (cupid_int k = 0; k < F->n; k++) F->p[k + 1] += F->p[k];
      CUPID_CALL(cupid_malloc((size_t)F->p[F->n] + 1, sizeof *F->i, "factor indices", &F->i));
      CUPID_CALL(cupid_malloc((size_t)F->p[F->n] + 1, sizeof *F->x, "factor values", &F->x));
    }
  }
  return CUPID_SUCCESS;
}

/* The normwise backward error of a solve with the factor: for b = K_ff e (e a fixed
 * pseudo-random vector), |b - K_ff x|_inf / (|K_ff|_inf |x|_inf + |b|_inf); about n eps for a
 * stable factorisation. */
static cupid_status lu_backward_error(cupid_direct_factor F, double *eta) {
  const cupid_int n = F->n;
  double *e = F->work, *x = F->work2, *b = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_CALL(cupid_malloc((size_t)n, sizeof *b, "factor check", &b));
  cupid_pseudo_random(e, n, 0x9E3779B97F4A7C15ull);
  /* column k of the stored matrix is row k of K_ff */
  double anorm = 0.0, bnorm = 0.0, xnorm = 0.0, rnorm = 0.0;
  for (cupid_int k = 0; k < n; k++) {
    double v = 0.0, a = 0.0;
    for (cupid_int t = F->p[k]; t < F->p[k + 1]; t++) v += F->x[t] * e[F->i[t]], a += fabs(F->x[t]);
    b[k] = v;
    anorm = fmax(anorm, a);
    bnorm = fmax(bnorm, fabs(v));
  }
  double sinfo[UMFPACK_INFO];
  SuiteSparse_long r = umfpack_dl_solve(UMFPACK_At, F->p, F->i, F->x, x, b, F->numeric,
                                        F->control, sinfo);
  CUPID_TRY_CHECK(r == UMFPACK_OK, CUPID_ERR_INTERNAL, "UMFPACK solve failed (status %ld)", (long)r);
  for (cupid_int k = 0; k < n; k++) xnorm = fmax(xnorm, fabs(x[k]));
  for (cupid_int k = 0; k < n; k++) {
    double v = b[k];
    for (cupid_int t = F->p[k]; t < F->p[k + 1]; t++) v -= F->x[t] * x[F->i[t]];
    rnorm = fmax(rnorm, fabs(v));
  }
  *eta = rnorm / (anorm * xnorm + bnorm);
cleanup:
  cupid_free(&b);
  return st;
}

/* A backward error above this after the factorisation with UMFPACK's default threshold
 * pivoting: refactor with partial pivoting (stable solves cost more fill). */
#define LU_BACKWARD_ERROR_MAX 1e-12

/* UMFPACK LU of K_ff^T (the rows read as columns), CHOLMOD's ordering as in direct.c.
 * UMFPACK's threshold pivoting (a pivot down to 0.1 of its column's largest entry) can grow
 * the factor's entries without bound on a non-symmetric matrix: the cheap twin of the
 * fictitious-node system (paper 000 Eq. 38) whose fictitious FE element is the removed beam
 * element (its FE rows read PD planes across the region, away from the PD rows that read the
 * FE node) factored with a pivot ratio of 1e-5 and solves with a backward error of 1e-9,
 * though its condition number is 1e4: GMRES right-preconditioned by it stalled at a true
 * residual of 6e-5 (tests/unit/test_coupling_operator.c, full_l9_lps). The factor is checked
 * by one solve; a backward error above LU_BACKWARD_ERROR_MAX refactors with partial pivoting
 * (pivot tolerance 1), and if that is still above, the solves refine iteratively. */
cupid_status cupid_umfpack_weakest_pivot(void *numeric, cupid_int n, cupid_int *col) {
  cupid_status st = CUPID_SUCCESS;
  SuiteSparse_long *Q = NULL, do_recip;
  double *D = NULL;
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *Q, "UMFPACK column order", &Q));
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *D, "UMFPACK pivots", &D));
  const SuiteSparse_long s = umfpack_dl_get_numeric(NULL, NULL, NULL, NULL, NULL, NULL, NULL, Q,
                                                    D, &do_recip, NULL, numeric);
  CUPID_TRY_CHECK(s == UMFPACK_OK, CUPID_ERR_INTERNAL, "UMFPACK get_numeric failed (status %ld)",
                  (long)s);
  cupid_int kmin = 0;
  for (cupid_int k = 1; k < n; k++)
    if (fabs(D[k]) < fabs(D[kmin])) kmin = k;
  *col = Q[kmin];
cleanup:
  cupid_free(&Q);
  cupid_free(&D);
  return st;
}

static cupid_status factorise_lu(cupid_direct_factor F, cupid_solve_info *info) {
  umfpack_dl_defaults(F->control);
  F->control[UMFPACK_PRL] = 0;
  F->control[UMFPACK_ORDERING] = UMFPACK_ORDERING_CHOLMOD;
  /* No iterative refinement in the solves: each step costs a product with K_ff and a solve
   * (measured: 60% of a Krylov solve preconditioned by this factor, where the Krylov method
   * itself corrects the residual). */
  F->control[UMFPACK_IRSTEP] = 0;
  double uinfo[UMFPACK_INFO];
  SuiteSparse_long s = umfpack_dl_symbolic(F->n, F->n, F->p, F->i, F->x, &F->symbolic,
                                           F->control, uinfo);
  CUPID_CHECK(s == UMFPACK_OK, s == UMFPACK_ERROR_out_of_memory ? CUPID_ERR_MEMORY : CUPID_ERR_INTERNAL,
              "UMFPACK analysis failed (status %ld)", (long)s);
  for (int attempt = 0;; attempt++) {
    s = umfpack_dl_numeric(F->p, F->i, F->x, F->symbolic, &F->numeric, F->control, uinfo);
    if (info) {
      info->nnz_factor = uinfo[UMFPACK_LNZ] + uinfo[UMFPACK_UNZ] - (double)F->n;
      info->flops_factor = uinfo[UMFPACK_FLOPS];
      info->memory_factor = (int64_t)(uinfo[UMFPACK_PEAK_MEMORY] * uinfo[UMFPACK_SIZE_OF_UNIT]);
      info->pivot_ratio = uinfo[UMFPACK_RCOND];
    }
    /* singular, or to round-off (the bound of the CHOLMOD path and the direct solver): the
     * weakest pivot's DOF named (crack growth holds its node) */
    const double bound = CUPID_DIRECT_PIVOT_TOL * (double)(F->n > 64 ? F->n : 64);
    if (s == UMFPACK_WARNING_singular_matrix || !(uinfo[UMFPACK_RCOND] >= bound)) {
      cupid_int col = 0;
      CUPID_CALL(cupid_umfpack_weakest_pivot(F->numeric, F->n, &col));
      if (info) info->failed_dof = F->global[col];
      return CUPID_ERROR(CUPID_ERR_NUMERIC,
                         "the matrix is singular%s (%s in its LU factorisation at DOF %lld): the "
                         "model may be unconstrained",
                         s == UMFPACK_WARNING_singular_matrix ? "" : " to round-off",
                         s == UMFPACK_WARNING_singular_matrix ? "zero pivot" : "pivot ratio below the bound",
                         (long long)F->global[col]);
    }
    CUPID_CHECK(s == UMFPACK_OK, s == UMFPACK_ERROR_out_of_memory ? CUPID_ERR_MEMORY : CUPID_ERR_INTERNAL,
                "UMFPACK factorisation failed (status %ld)", (long)s);
    double eta = 0.0;
    CUPID_CALL(lu_backward_error(F, &eta));
    if (eta <= LU_BACKWARD_ERROR_MAX) break;
    if (attempt == 1) { /* partial pivoting was not enough: refine every solve */
      F->control[UMFPACK_IRSTEP] = 2;
      break;
    }
    umfpack_dl_free_numeric(&F->numeric);
    F->control[UMFPACK_PIVOT_TOLERANCE] = 1.0;
    F->control[UMFPACK_SYM_PIVOT_TOLERANCE] = 1.0;
  }
  return CUPID_SUCCESS;
}

/* min/max of the pivots L_kk^2 (supernodal or simplicial LL'), or |D_kk| (simplicial LDL'),
 * the rows that cupid_direct_factor_hold deleted left out (their pivot is the identity's 1,
 * which says nothing of the matrix). */
static double pivot_ratio(const cholmod_factor *L, const unsigned char *held, cupid_int *kmin) {
  const double *x = L->x;
  double lo = INFINITY, hi = 0.0;
  *kmin = 0;
  if (L->is_super) {
    const SuiteSparse_long *super = L->super, *pi = L->pi, *px = L->px;
    for (size_t s = 0; s < L->nsuper; s++) {
      SuiteSparse_long k1 = super[s], k2 = super[s + 1], nsrow = pi[s + 1] - pi[s];
      for (SuiteSparse_long j = k1; j < k2; j++) {
        double d = x[px[s] + (j - k1) * (nsrow + 1)], piv = d * d;
        if (piv < lo) lo = piv, *kmin = j;
        if (piv > hi) hi = piv;
      }
    }
  } else {
    const SuiteSparse_long *p = L->p;
    for (size_t j = 0; j < L->n; j++) {
      if (held && held[j]) continue;
      double d = x[p[j]], piv = L->is_ll ? d * d : fabs(d);
      if (piv < lo) lo = piv, *kmin = (cupid_int)j;
      if (piv > hi) hi = piv;
    }
  }
  return hi > 0.0 ? lo / hi : 0.0;
}

static cupid_status factorise(cupid_direct_factor F, cupid_solve_info *info) {
  cholmod_common *c = &F->cc;
  CUPID_CHECK(cholmod_l_start(c), CUPID_ERR_INTERNAL, "CHOLMOD could not start");
  F->cc_started = 1;
  c->print = 0;
  c->supernodal = CHOLMOD_AUTO;
  c->quick_return_if_not_posdef = 1;
  cholmod_sparse A;
  memset(&A, 0, sizeof A);
  A.nrow = A.ncol = (size_t)F->n;
  A.nzmax = (size_t)F->p[F->n];
  A.p = F->p;
  A.i = F->i;
  A.x = F->x;
  A.stype = -1;
  A.itype = CHOLMOD_LONG;
  A.xtype = CHOLMOD_REAL;
  A.dtype = CHOLMOD_DOUBLE;
  A.sorted = A.packed = 1;
  F->L = cholmod_l_analyze(&A, c);
  CUPID_CHECK(F->L && c->status >= CHOLMOD_OK, CUPID_ERR_INTERNAL,
              "CHOLMOD analysis failed (status %d)", c->status);
  int ok = cholmod_l_factorize(&A, F->L, c);
  const SuiteSparse_long *perm = F->L->Perm;
  if (c->status == CHOLMOD_NOT_POSDEF || F->L->minor < (size_t)F->n) {
    size_t k = F->L->minor < (size_t)F->n ? F->L->minor : (size_t)F->n - 1;
    if (info) info->failed_dof = F->global[perm ? perm[k] : (cupid_int)k];
    return CUPID_ERROR(CUPID_ERR_NUMERIC,
                       "the matrix is not positive definite (factorisation broke down at DOF "
                       "%lld): the model may be unconstrained",
                       (long long)F->global[perm ? perm[k] : (cupid_int)k]);
  }
  CUPID_CHECK(ok && c->status >= CHOLMOD_OK, CUPID_ERR_INTERNAL,
              "CHOLMOD factorisation failed (status %d)", c->status);
  cupid_int kmin;
  double ratio = pivot_ratio(F->L, NULL, &kmin);
  cupid_int weakest = F->global[perm ? perm[kmin] : kmin];
  if (info) {
    info->pivot_ratio = ratio;
    info->nnz_factor = (double)c->lnz;
    info->flops_factor = c->fl;
    info->memory_factor = (int64_t)c->memory_usage;
  }
  double bound = CUPID_DIRECT_PIVOT_TOL * (double)(F->n > 64 ? F->n : 64);
  if (ratio < bound) {
    if (info) info->failed_dof = weakest;
    return CUPID_ERROR(CUPID_ERR_NUMERIC,
                       "the matrix is singular to round-off (pivot ratio %.3g at DOF %lld): the "
                       "model may be unconstrained",
                       ratio, (long long)weakest);
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_direct_factor_create(const cupid_csr_t *K, const cupid_dirichlet_t *bc,
                                        cupid_direct_factor *out, cupid_solve_info *info) {
  return cupid_direct_factor_create_kind(K, CUPID_MATRIX_SPD, bc, out, info);
}

cupid_status cupid_direct_factor_create_kind(const cupid_csr_t *K, cupid_matrix_kind kind,
                                             const cupid_dirichlet_t *bc,
                                             cupid_direct_factor *out, cupid_solve_info *info) {
  cupid_status st = CUPID_SUCCESS;
  cupid_direct_factor F = NULL;
  CUPID_CHECK(K && out && K->nrows == K->ncols, CUPID_ERR_ARGUMENT,
              "cupid_direct_factor_create: need a square matrix");
  *out = NULL;
  double t0 = cupid_wtime();
  cupid_int n_full = K->nrows * K->bs;
  CUPID_CHECK(!bc || bc->n == n_full, CUPID_ERR_ARGUMENT,
              "cupid_direct_factor_create: the conditions have %lld DOFs, the matrix %lld",
              (long long)(bc ? bc->n : 0), (long long)n_full);
  CUPID_CHECK(kind == CUPID_MATRIX_SPD || kind == CUPID_MATRIX_GENERAL, CUPID_ERR_ARGUMENT,
              "cupid_direct_factor_create: unknown matrix kind %d", (int)kind);
  if (info) {
    memset(info, 0, sizeof *info);
    info->method = kind == CUPID_MATRIX_SPD ? "cholmod" : "umfpack";
    info->failed_dof = -1;
  }
  CUPID_TRY(cupid_calloc(1, sizeof *F, "factorisation", &F));
  F->failed_dof = -1;
  F->kind = kind;
  F->n_full = n_full;
  F->n = bc ? bc->n_free : n_full;
  CUPID_TRY_CHECK(F->n > 0, CUPID_ERR_NUMERIC, "no free DOF to solve for");
  CUPID_TRY(cupid_malloc((size_t)F->n, sizeof *F->global, "free DOF map", &F->global));
  CUPID_TRY(cupid_malloc((size_t)F->n, sizeof *F->work, "factor work", &F->work));
  CUPID_TRY(cupid_malloc((size_t)F->n, sizeof *F->work2, "factor work", &F->work2));
  for (cupid_int d = 0, k = 0; d < n_full; d++)
    if (!bc || !bc->fixed[d]) F->global[k++] = d;
  if (kind == CUPID_MATRIX_SPD) {
    CUPID_TRY(reduce(F, K, bc ? bc->free_index : NULL, 1));
    CUPID_TRY(factorise(F, info));
  } else {
    CUPID_TRY(reduce(F, K, bc ? bc->free_index : NULL, 0));
    CUPID_TRY(factorise_lu(F, info));
  }
  if (info) {
    info->n = F->n;
    info->nnz_matrix = kind == CUPID_MATRIX_SPD ? 2 * F->p[F->n] - F->n : F->p[F->n];
    info->time_factor = cupid_wtime() - t0;
  }
  *out = F;
  F = NULL;
cleanup:
  cupid_direct_factor_destroy(&F);
  return st;
}

cupid_status cupid_direct_factor_solve(cupid_direct_factor F, const double *b, double *x) {
  CUPID_CHECK(F && b && x, CUPID_ERR_ARGUMENT, "cupid_direct_factor_solve: NULL argument");
  const cupid_int *held_at = F->held ? F->pivot_of : NULL; /* a held DOF: no row of K_ff now */
  for (cupid_int k = 0; k < F->n; k++)
    F->work[k] = held_at && held_at[F->global[k]] < 0 ? 0.0 : b[F->global[k]];
  CUPID_CALL(cupid_direct_factor_solve_free(F, F->work, F->work2));
  for (cupid_int k = 0; k < F->n; k++)
    if (!held_at || held_at[F->global[k]] >= 0) x[F->global[k]] = F->work2[k];
  return CUPID_SUCCESS;
}

cupid_status cupid_direct_factor_solve_masked(cupid_direct_factor F, const cupid_dirichlet_t *bc,
                                            const double *r, double *z) {
  CUPID_CHECK(F && bc && r && z, CUPID_ERR_ARGUMENT, "cupid_direct_factor_solve_masked: NULL argument");
  const cupid_int *held_at = F->held ? F->pivot_of : NULL;
  for (cupid_int k = 0; k < F->n; k++) {
    const cupid_int d = F->global[k];
    F->work[k] = bc->fixed[d] || (held_at && held_at[d] < 0) ? 0.0 : r[d];
  }
  CUPID_CALL(cupid_direct_factor_solve_free(F, F->work, F->work2));
  for (cupid_int d = 0; d < bc->n; d++)
    if (bc->fixed[d]) z[d] = 0.0;
  for (cupid_int k = 0; k < F->n; k++) {
    const cupid_int d = F->global[k];
    if (!bc->fixed[d] && (!held_at || held_at[d] >= 0)) z[d] = F->work2[k];
  }
  return CUPID_SUCCESS;
}

cupid_int cupid_direct_factor_size(const cupid_direct_factor F) { return F ? F->n : 0; }

cupid_status cupid_direct_factor_weakest_dof(const cupid_direct_factor F, cupid_int *dof) {
  CUPID_CHECK(F && dof, CUPID_ERR_ARGUMENT, "cupid_direct_factor_weakest_dof: NULL argument");
  if (F->kind == CUPID_MATRIX_SPD) { /* the smallest L_kk^2 (or |D_kk| once downdated) */
    cupid_int kmin = 0;
    (void)pivot_ratio(F->L, F->held, &kmin);
    const SuiteSparse_long *perm = F->L->Perm;
    *dof = F->global[perm ? perm[kmin] : kmin];
    return CUPID_SUCCESS;
  }
  cupid_int col = 0;
  CUPID_CALL(cupid_umfpack_weakest_pivot(F->numeric, F->n, &col));
  *dof = F->global[col];
  return CUPID_SUCCESS;
}

/* CHOLMOD's solve of nrhs columns (column after column, n each): one pass over the factor for
 * all of them (supernodal: BLAS-3 triangular solves; simplicial: up to four columns a sweep). */
static cupid_status cholmod_solve_columns(cupid_direct_factor F, cupid_int nrhs, const double *b,
                                          double *x) {
  const size_t n = (size_t)F->n;
  cholmod_dense B;
  memset(&B, 0, sizeof B);
  B.nrow = B.d = n;
  B.ncol = (size_t)nrhs;
  B.nzmax = n * (size_t)nrhs;
  B.x = (double *)b;
  B.xtype = CHOLMOD_REAL;
  B.dtype = CHOLMOD_DOUBLE;
  cholmod_dense *X = cholmod_l_solve(CHOLMOD_A, F->L, &B, &F->cc);
  if (!X || F->cc.status < CHOLMOD_OK) {
    cholmod_l_free_dense(&X, &F->cc);
    return CUPID_ERROR(F->cc.status == CHOLMOD_OUT_OF_MEMORY ? CUPID_ERR_MEMORY : CUPID_ERR_INTERNAL,
                       "CHOLMOD solve of %lld right-hand side(s) failed (status %d)", (long long)nrhs,
                       F->cc.status);
  }
  memcpy(x, X->x, n * (size_t)nrhs * sizeof *x);
  cholmod_l_free_dense(&X, &F->cc);
  return CUPID_SUCCESS;
}

cupid_status cupid_direct_factor_solve_free(cupid_direct_factor F, const double *b, double *x) {
  CUPID_CHECK(F && b && x, CUPID_ERR_ARGUMENT, "cupid_direct_factor_solve_free: NULL argument");
  if (F->kind == CUPID_MATRIX_GENERAL) {
    double sinfo[UMFPACK_INFO];
    const SuiteSparse_long s = umfpack_dl_solve(UMFPACK_At, F->p, F->i, F->x, x, b, F->numeric,
                                                F->control, sinfo);
    CUPID_CHECK(s == UMFPACK_OK, CUPID_ERR_INTERNAL, "UMFPACK solve failed (status %ld)", (long)s);
    return CUPID_SUCCESS;
  }
  return cholmod_solve_columns(F, 1, b, x);
}

cupid_status cupid_direct_factor_solve_free_many(cupid_direct_factor F, cupid_int nrhs,
                                                const double *b, double *x) {
  CUPID_CHECK(F && nrhs >= 0 && (nrhs == 0 || (b && x)), CUPID_ERR_ARGUMENT,
              "cupid_direct_factor_solve_free_many: NULL argument");
  const size_t n = (size_t)F->n;
  if (nrhs == 0) return CUPID_SUCCESS;
  if (F->kind == CUPID_MATRIX_GENERAL) { /* UMFPACK solves one right-hand side at a time */
    for (cupid_int c = 0; c < nrhs; c++)
      CUPID_CALL(cupid_direct_factor_solve_free(F, b + (size_t)c * n, x + (size_t)c * n));
    return CUPID_SUCCESS;
  }
  return cholmod_solve_columns(F, nrhs, b, x);
}

/* Row indices ascending within each column (insertion sort: a column holds a few entries). */
static void sort_column(SuiteSparse_long *i, double *x, SuiteSparse_long n) {
  for (SuiteSparse_long a = 1; a < n; a++)
    for (SuiteSparse_long b = a; b > 0 && i[b - 1] > i[b]; b--) {
      SuiteSparse_long ti = i[b];
      double tx = x[b];
      i[b] = i[b - 1], x[b] = x[b - 1];
      i[b - 1] = ti, x[b - 1] = tx;
    }
}

/* F->pivot_of: CHOLMOD wants a modification's rows in the factor's permuted order. */
static cupid_status row_map(cupid_direct_factor F) {
  if (F->pivot_of) return CUPID_SUCCESS;
  CUPID_CALL(cupid_malloc((size_t)F->n_full, sizeof *F->pivot_of, "factor row map", &F->pivot_of));
  for (cupid_int d = 0; d < F->n_full; d++) F->pivot_of[d] = -1;
  const SuiteSparse_long *perm = F->L->Perm;
  for (cupid_int k = 0; k < F->n; k++) F->pivot_of[F->global[perm ? perm[k] : k]] = k;
  return CUPID_SUCCESS;
}

/* A factor CHOLMOD modifies: simplicial LDL' (what cholmod_updown makes of it too). */
static cupid_status simplicial_ldl(cupid_direct_factor F) {
  if (!F->L->is_super && !F->L->is_ll) return CUPID_SUCCESS;
  const int ok = cholmod_l_change_factor(CHOLMOD_REAL, 0, 0, 0, 0, F->L, &F->cc);
  CUPID_CHECK(ok && F->cc.status >= CHOLMOD_OK,
              F->cc.status == CHOLMOD_OUT_OF_MEMORY ? CUPID_ERR_MEMORY : CUPID_ERR_INTERNAL,
              "CHOLMOD could not make the factor simplicial (status %d)", F->cc.status);
  return CUPID_SUCCESS;
}

/* Each row deleted is a rank-two modification (cholmod_rowdel): about a downdate column's cost
 * for a row of the factor's usual length, where a factorisation is thousands of them. */
cupid_status cupid_direct_factor_hold(cupid_direct_factor F, const cupid_dirichlet_t *bc,
                                      cupid_int *held) {
  CUPID_CHECK(F && bc && held, CUPID_ERR_ARGUMENT, "cupid_direct_factor_hold: NULL argument");
  CUPID_CHECK(F->kind == CUPID_MATRIX_SPD, CUPID_ERR_ARGUMENT,
              "cupid_direct_factor_hold: only a Cholesky factor can hold DOFs");
  CUPID_CHECK(bc->n == F->n_full, CUPID_ERR_ARGUMENT,
              "cupid_direct_factor_hold: the conditions have %lld DOFs, the factor %lld",
              (long long)bc->n, (long long)F->n_full);
  *held = 0;
  CUPID_CALL(row_map(F));
  for (cupid_int d = 0; d < F->n_full; d++) {
    if (!bc->fixed[d] || F->pivot_of[d] < 0) continue;
    if (!F->held) { /* the first row held: the factor CHOLMOD can modify, and the flags */
      CUPID_CALL(simplicial_ldl(F));
      CUPID_CALL(cupid_calloc((size_t)F->n + 1, 1, "held rows", &F->held));
    }
    const cupid_int k = F->pivot_of[d];
    const int ok = cholmod_l_rowdel((size_t)k, NULL, F->L, &F->cc);
    CUPID_CHECK(ok && F->cc.status >= CHOLMOD_OK,
                F->cc.status == CHOLMOD_OUT_OF_MEMORY ? CUPID_ERR_MEMORY : CUPID_ERR_INTERNAL,
                "CHOLMOD could not delete the factor's row of DOF %lld (status %d)", (long long)d,
                F->cc.status);
    F->held[k] = 1;
    F->pivot_of[d] = -1; /* a later downdate drops the row, as a DOF fixed from the start */
    (*held)++;
  }
  return CUPID_SUCCESS;
}

/* F += C_f C_f^T (update = 1) or F -= C_f C_f^T (0): cupid_direct_factor_update / _downdate. */
static cupid_status updown(cupid_direct_factor F, int update, cupid_int r, const cupid_int *colptr,
                           const cupid_int *rows, const double *vals) {
  CUPID_CHECK(F && (r == 0 || (colptr && rows && vals)), CUPID_ERR_ARGUMENT,
              "cupid_direct_factor_%s: NULL argument", update ? "update" : "downdate");
  CUPID_CHECK(F->kind == CUPID_MATRIX_SPD, CUPID_ERR_ARGUMENT,
              "cupid_direct_factor_%s: only a Cholesky factor can be %sdated", update ? "update" : "downdate",
              update ? "up" : "down");
  if (r == 0) return CUPID_SUCCESS;
  CUPID_CALL(row_map(F));
  cholmod_common *c = &F->cc;
  cholmod_sparse *C = cholmod_l_allocate_sparse((size_t)F->n, (size_t)r, (size_t)colptr[r], 1, 1, 0,
                                                CHOLMOD_REAL, c);
  CUPID_CHECK(C, CUPID_ERR_MEMORY, "CHOLMOD could not allocate the downdate (%lld columns)",
              (long long)r);
  SuiteSparse_long *cp = C->p, *ci = C->i, t = 0;
  double *cx = C->x;
  for (cupid_int k = 0; k < r; k++) {
    cp[k] = t;
    for (cupid_int q = colptr[k]; q < colptr[k + 1]; q++) {
      cupid_int row = rows[q];
      if (row < 0 || row >= F->n_full || F->pivot_of[row] < 0) continue; /* a fixed DOF */
      ci[t] = F->pivot_of[row];
      cx[t++] = vals[q];
    }
    sort_column(ci + cp[k], cx + cp[k], t - cp[k]);
  }
  cp[r] = t;
  const int ok = cholmod_l_updown(update, C, F->L, c);
  cholmod_l_free_sparse(&C, c);
  F->failed_dof = -1;
  CUPID_CHECK(ok && c->status >= CHOLMOD_OK, c->status == CHOLMOD_NOT_POSDEF ? CUPID_ERR_NUMERIC : CUPID_ERR_INTERNAL,
              "CHOLMOD %s failed (status %d)", update ? "update" : "downdate", c->status);
  /* a downdate that removes all support of some DOF leaves a pivot of D at round-off, or
   * negative (which pivot_ratio's |d| would hide) */
  const SuiteSparse_long *perm = F->L->Perm, *lp = F->L->p;
  const double *lx = F->L->x;
  for (cupid_int k = 0; k < F->n && !F->L->is_ll; k++) {
    if (lx[lp[k]] > 0.0 || (F->held && F->held[k])) continue;
    F->failed_dof = F->global[perm ? perm[k] : k];
    return CUPID_ERROR(CUPID_ERR_NUMERIC, "the downdated matrix is not positive definite (pivot "
                       "%.3g at DOF %lld)", lx[lp[k]], (long long)F->failed_dof);
  }
  cupid_int kmin;
  const double ratio = pivot_ratio(F->L, F->held, &kmin);
  if (ratio < CUPID_DIRECT_PIVOT_TOL * (double)(F->n > 64 ? F->n : 64)) {
    F->failed_dof = F->global[perm ? perm[kmin] : kmin];
    return CUPID_ERROR(CUPID_ERR_NUMERIC, "the downdated matrix is singular to round-off (pivot "
                       "ratio %.3g at DOF %lld)", ratio, (long long)F->failed_dof);
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_direct_factor_downdate(cupid_direct_factor F, cupid_int r, const cupid_int *colptr,
                                          const cupid_int *rows, const double *vals) {
  return updown(F, 0, r, colptr, rows, vals);
}

cupid_status cupid_direct_factor_update(cupid_direct_factor F, cupid_int r, const cupid_int *colptr,
                                        const cupid_int *rows, const double *vals) {
  return updown(F, 1, r, colptr, rows, vals);
}

cupid_int cupid_direct_factor_failed_dof(const cupid_direct_factor F) {
  return F ? F->failed_dof : -1;
}

void cupid_direct_factor_destroy(cupid_direct_factor *F) {
  if (!F || !*F) return;
  cupid_direct_factor f = *F;
  if (f->cc_started) {
    cholmod_l_free_factor(&f->L, &f->cc);
    cholmod_l_finish(&f->cc);
  }
  if (f->numeric) umfpack_dl_free_numeric(&f->numeric);
  if (f->symbolic) umfpack_dl_free_symbolic(&f->symbolic);
  cupid_free(&f->global);
  cupid_free(&f->pivot_of);
  cupid_free(&f->held);
  cupid_free(&f->work);
  cupid_free(&f->work2);
  cupid_free(&f->p);
  cupid_free(&f->i);
  cupid_free(&f->x);
  cupid_free(F);
}
