/*
 * Direct solution of K u = f with Dirichlet conditions (include/cupid/solvers.h):
 * CHOLMOD (supernodal LL') for SPD matrices, UMFPACK for general ones, both with the
 * 64-bit SuiteSparse APIs. Only the free DOFs are factored: K_ff u_f = f_f - K_fc u_c.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <cholmod.h>
#include <umfpack.h>

#include "cupid/solvers.h"
#include "solvers_internal.h"

/* cupid_int and SuiteSparse_long must be the same type: arrays are handed over as they are. */
_Static_assert(sizeof(SuiteSparse_long) == sizeof(cupid_int), "SuiteSparse_long is not 64-bit");

/* Residual thresholds (solvers.h): refine above the first, fail above the second. */
#define REFINE_ABOVE 1e-12
/* Two failure tests after refinement.
 * 1. The normwise backward error eta = |r|_inf / (|K_ff|_inf |u_f|_inf + |b_f|_inf): a
 *    backward-stable factorisation gives eta ~ 1e-16 times a modest growth factor whatever
 *    the conditioning; 1e-10 leaves six orders of margin and rejects unstable solves and
 *    non-symmetric matrices passed as SPD.
 * 2. The relative residual |r|/|b|: for a correct solve it is at most about eta cond(K), so it
 *    grows with the conditioning (slender beams reach 1e-7, stiff penalties more) and cannot be
 *    held to 1e-8; but a singular system with an inconsistent load leaves |r|/|b| = O(1) while
 *    eta stays tiny (the huge |u| hides it). 1e-4 passes condition numbers up to ~1e12. */
#define FAIL_ABOVE 1e-10
#define RESIDUAL_FAIL_ABOVE 1e-4

/* The singularity bound on the pivot ratio for n equations (solvers.h). */
static double pivot_ratio_min(cupid_int n) {
  return CUPID_DIRECT_PIVOT_TOL * (double)(n > 64 ? n : 64);
}

/* The reduced matrix rows of K_ff (scalar CSR with free-DOF numbering), possibly one triangle. */
typedef struct {
  cupid_int n;     /* free DOFs */
  cupid_int *p;    /* n + 1 */
  cupid_int *i;    /* column indices, sorted per row */
  double *x;       /* values */
  cupid_int nnz_full; /* scalar non-zeros of K_ff (both triangles) */
} reduced_matrix;

/* A factorisation by either library. */
typedef struct {
  cupid_matrix_kind kind;
  reduced_matrix A;
  cholmod_common cc;
  int cc_started;
  cholmod_sparse Ac; /* a view of A (not owned by CHOLMOD) */
  cholmod_factor *L;
  cupid_int weakest; /* CHOLMOD: free DOF of the smallest pivot */
  void *symbolic, *numeric;
  double control[UMFPACK_CONTROL], uinfo[UMFPACK_INFO];
} direct_factor;

static _Thread_local char cholmod_message[256];

/* CHOLMOD reports problems through this hook; keep the text for our own message. */
static void cholmod_record(int status, const char *file, int line, const char *message) {
  snprintf(cholmod_message, sizeof cholmod_message, "%s", message ? message : "");
}

/* "DOF 1234 = node 411, component y" */
static void describe_dof(char *buf, size_t size, cupid_int dof, int bs) {
  static const char comp[] = "xyz";
  if (bs == 3)
    snprintf(buf, size, "DOF %lld = node %lld, component %c", (long long)dof,
             (long long)(dof / 3), comp[dof % 3]);
  else
    snprintf(buf, size, "DOF %lld = node %lld", (long long)(dof), (long long)(dof / bs));
}

static cupid_status singular_error(cupid_int dof, int bs, const char *how) {
  char where[96];
  describe_dof(where, sizeof where, dof, bs);
  return CUPID_ERROR(CUPID_ERR_NUMERIC,
                     "the stiffness matrix is singular or not positive definite (%s at %s): the "
                     "model may be unconstrained or a region disconnected",
                     how, where);
}

/*
 * A NaN or Inf would otherwise slip through: a NaN norm fails no comparison (|r|/|b| was
 * reported as 0 and NaN displacements as a success), an infinite load reads as a singular
 * matrix. Name the first non-finite entry of @p v (n values; DOF global[k], or k if global is
 * NULL) and what it is; CUPID_SUCCESS if all are finite. info->failed_dof stays -1: nothing
 * broke down in a factorisation (the message names the DOF).
 */
static cupid_status check_finite(cupid_int n, const double *v, const cupid_int *global, int bs,
                                 const char *what, const char *hint, const char *method) {
  for (cupid_int k = 0; k < n; k++) {
    if (isfinite(v[k])) continue;
    char where[96];
    describe_dof(where, sizeof where, global ? global[k] : k, bs);
    return CUPID_ERROR(CUPID_ERR_NUMERIC, "%s: non-finite %s %g at %s: %s", method, what, v[k],
                       where, hint);
  }
  return CUPID_SUCCESS;
}

/*
 * Rows of K_ff from the block rows of K. Free DOFs are numbered in increasing global order,
 * so mapped column indices stay sorted. With lower_only, row k keeps columns >= k, which is
 * column k of the lower triangle of the (symmetric) K_ff in compressed-column form.
 */
static cupid_status reduce_matrix(const cupid_csr_t *K, const cupid_dirichlet_t *bc,
                                  const cupid_int *global, int lower_only, reduced_matrix *R) {
  const int bs = K->bs;
  const cupid_int n = bc->n_free;
  const cupid_int *fi = bc->free_index;
  R->n = n;
  CUPID_CALL(cupid_malloc((size_t)n + 1, sizeof *R->p, "reduced matrix pointers", &R->p));
  cupid_int full = 0;
#pragma omp parallel for schedule(static) reduction(+ : full)
  for (cupid_int k = 0; k < n; k++) {
    const cupid_int g = global[k], row = g / bs;
    cupid_int kept = 0, all = 0;
    for (cupid_int q = K->rowptr[row]; q < K->rowptr[row + 1]; q++)
      for (int b = 0; b < bs; b++) {
        const cupid_int c = fi[K->col[q] * bs + b];
        all += c >= 0;
        kept += c >= 0 && (!lower_only || c >= k);
      }
    R->p[k + 1] = kept;
    full += all;
  }
  R->nnz_full = full;
  R->p[0] = 0;
  for (cupid_int k = 0; k < n; k++) R->p[k + 1] += R->p[k];
  const cupid_int nnz = R->p[n];
  CUPID_CALL(cupid_malloc((size_t)nnz, sizeof *R->i, "reduced matrix indices", &R->i));
  CUPID_CALL(cupid_malloc((size_t)nnz, sizeof *R->x, "reduced matrix values", &R->x));
#pragma omp parallel for schedule(static) if (n > 65536)
  for (cupid_int k = 0; k < n; k++) {
    const cupid_int g = global[k], row = g / bs;
    const int a = (int)(g % bs);
    cupid_int t = R->p[k];
    for (cupid_int q = K->rowptr[row]; q < K->rowptr[row + 1]; q++)
      for (int b = 0; b < bs; b++) {
        const cupid_int c = fi[K->col[q] * bs + b];
        if (c >= 0 && (!lower_only || c >= k)) {
          R->i[t] = c;
          R->x[t++] = K->val[(q * bs + a) * bs + b];
        }
      }
  }
  return CUPID_SUCCESS;
}

static void reduced_free(reduced_matrix *R) {
  cupid_free(&R->p);
  cupid_free(&R->i);
  cupid_free(&R->x);
}

static cupid_status cholmod_failure(const direct_factor *F, const char *step) {
  const cholmod_common *c = &F->cc;
  if (c->status == CHOLMOD_OUT_OF_MEMORY || c->status == CHOLMOD_TOO_LARGE)
    return CUPID_ERROR(CUPID_ERR_MEMORY,
                       "CHOLMOD %s ran out of memory (%lld equations, %lld stored non-zeros; "
                       "%.3g GB in use, %.3g GB peak, nnz(L) estimate %.3g): %s",
                       step, (long long)F->A.n, (long long)F->A.p[F->A.n],
                       (double)c->memory_inuse / 1e9, (double)c->memory_usage / 1e9, c->lnz,
                       cholmod_message);
  return CUPID_ERROR(CUPID_ERR_INTERNAL, "CHOLMOD %s failed (status %d): %s", step, c->status,
                     cholmod_message);
}

/* Pivots L_kk^2 of a CHOLMOD LL' factor (or D of LDL'), in factor (permuted) order: min/max. */
static double cholmod_pivot_ratio(const cholmod_factor *L, cupid_int *kmin, double *nnz) {
  const double *x = L->x;
  double lo = INFINITY, hi = 0.0;
  *kmin = 0;
  *nnz = 0.0;
  if (L->is_super) {
    const SuiteSparse_long *super = L->super, *pi = L->pi, *px = L->px;
    for (size_t s = 0; s < L->nsuper; s++) {
      const SuiteSparse_long k1 = super[s], k2 = super[s + 1];
      const SuiteSparse_long nscol = k2 - k1, nsrow = pi[s + 1] - pi[s];
      *nnz += (double)nscol * (double)nsrow - 0.5 * (double)nscol * (double)(nscol - 1);
      for (SuiteSparse_long j = k1; j < k2; j++) {
        const double d = x[px[s] + (j - k1) * (nsrow + 1)];
        const double piv = d * d;
        if (piv < lo) {
          lo = piv;
          *kmin = j;
        }
        if (piv > hi) hi = piv;
      }
    }
  } else {
    const SuiteSparse_long *p = L->p, *nz = L->nz;
    for (size_t j = 0; j < L->n; j++) {
      const double d = x[p[j]];
      const double piv = L->is_ll ? d * d : fabs(d);
      *nnz += (double)nz[j];
      if (piv < lo) {
        lo = piv;
        *kmin = (cupid_int)j;
      }
      if (piv > hi) hi = piv;
    }
  }
  return hi > 0.0 ? lo / hi : 0.0;
}

static cupid_status factor_cholmod(direct_factor *F, const cupid_int *global, int bs,
                                   cupid_solve_info *info) {
  cholmod_common *c = &F->cc;
  const cupid_int n = F->A.n;
  cholmod_message[0] = '\0';
  if (!cholmod_l_start(c)) return CUPID_ERROR(CUPID_ERR_INTERNAL, "CHOLMOD could not start");
  F->cc_started = 1;
  c->print = 0; /* errors are reported by cupid */
  c->error_handler = cholmod_record;
  c->supernodal = CHOLMOD_SUPERNODAL;
  c->quick_return_if_not_posdef = 1;

  cholmod_sparse *A = &F->Ac;
  memset(A, 0, sizeof *A);
  A->nrow = A->ncol = (size_t)n;
  A->nzmax = (size_t)F->A.p[n];
  A->p = F->A.p;
  A->i = F->A.i;
  A->x = F->A.x;
  A->stype = -1; /* lower triangle stored: half the memory of the full K_ff */
  A->itype = CHOLMOD_LONG;
  A->xtype = CHOLMOD_REAL;
  A->dtype = CHOLMOD_DOUBLE;
  A->sorted = 1;
  A->packed = 1;

  F->L = cholmod_l_analyze(A, c);
  if (!F->L || c->status < CHOLMOD_OK) return cholmod_failure(F, "analysis");
  const int ok = cholmod_l_factorize(A, F->L, c);
  info->flops_factor = c->fl;
  info->memory_factor = (int64_t)c->memory_usage;
  if (c->status == CHOLMOD_NOT_POSDEF || F->L->minor < (size_t)n) {
    const SuiteSparse_long *perm = F->L->Perm;
    const size_t k = F->L->minor < (size_t)n ? F->L->minor : (size_t)n - 1;
    const cupid_int col = perm ? perm[k] : (cupid_int)k;
    info->failed_dof = global[col];
    return singular_error(info->failed_dof, bs, "factorisation broke down");
  }
  if (!ok || c->status < CHOLMOD_OK) return cholmod_failure(F, "factorisation");

  cupid_int kmin;
  info->pivot_ratio = cholmod_pivot_ratio(F->L, &kmin, &info->nnz_factor);
  const SuiteSparse_long *perm = F->L->Perm;
  F->weakest = perm ? perm[kmin] : kmin;
  if (info->pivot_ratio < pivot_ratio_min(n)) {
    info->failed_dof = global[F->weakest];
    char how[96];
    snprintf(how, sizeof how, "pivot ratio %.3g", info->pivot_ratio);
    return singular_error(info->failed_dof, bs, how);
  }
  return CUPID_SUCCESS;
}

static const char *umfpack_status_text(SuiteSparse_long status) {
  switch (status) {
  case UMFPACK_OK: return "ok";
  case UMFPACK_WARNING_singular_matrix: return "singular matrix";
  case UMFPACK_ERROR_out_of_memory: return "out of memory";
  case UMFPACK_ERROR_invalid_matrix: return "invalid matrix";
  case UMFPACK_ERROR_different_pattern: return "different pattern";
  case UMFPACK_ERROR_ordering_failed: return "ordering failed";
  default: return "error";
  }
}

static cupid_status umfpack_failure(const direct_factor *F, const char *step,
                                    SuiteSparse_long status) {
  const double unit = F->uinfo[UMFPACK_SIZE_OF_UNIT] > 0 ? F->uinfo[UMFPACK_SIZE_OF_UNIT] : 8.0;
  if (status == UMFPACK_ERROR_out_of_memory)
    return CUPID_ERROR(CUPID_ERR_MEMORY,
                       "UMFPACK %s ran out of memory (%lld equations, %lld non-zeros; estimated "
                       "peak %.3g GB)",
                       step, (long long)F->A.n, (long long)F->A.p[F->A.n],
                       F->uinfo[UMFPACK_PEAK_MEMORY_ESTIMATE] * unit / 1e9);
  return CUPID_ERROR(CUPID_ERR_INTERNAL, "UMFPACK %s failed (status %ld: %s)", step,
                     (long)status, umfpack_status_text(status));
}

/* The free DOF of the smallest |U_kk| (a zero pivot of a singular matrix). */
static cupid_status umfpack_weakest_pivot(const direct_factor *F, cupid_int *col) {
  return cupid_umfpack_weakest_pivot(F->numeric, F->A.n, col);
}

/*
 * UMFPACK takes compressed columns; the rows of K_ff read as columns are K_ff^T, so the
 * solve uses sys = UMFPACK_At (no transposed copy needed).
 */
static cupid_status factor_umfpack(direct_factor *F, const cupid_int *global, int bs,
                                   cupid_solve_info *info) {
  const cupid_int n = F->A.n;
  umfpack_dl_defaults(F->control);
  F->control[UMFPACK_PRL] = 0;
  /* CHOLMOD's ordering: AMD/COLAMD, and METIS too when the fill is high, the better one kept
   * (UMFPACK's default is AMD/COLAMD alone). On the coupled bar of the README (Eq. 38, 13k
   * equations of 3D LPS) it halves nnz(LU) (128 M -> 54 M): factorisation 20.6 s -> 5.8 s,
   * peak 3.6 -> 1.7 GB; the C-beam and the panel keep their AMD factors. */
  F->control[UMFPACK_ORDERING] = UMFPACK_ORDERING_CHOLMOD;
  SuiteSparse_long s = umfpack_dl_symbolic(n, n, F->A.p, F->A.i, F->A.x, &F->symbolic,
                                           F->control, F->uinfo);
  if (s != UMFPACK_OK) return umfpack_failure(F, "analysis", s);
  s = umfpack_dl_numeric(F->A.p, F->A.i, F->A.x, F->symbolic, &F->numeric, F->control, F->uinfo);
  info->memory_factor = (int64_t)(F->uinfo[UMFPACK_PEAK_MEMORY] * F->uinfo[UMFPACK_SIZE_OF_UNIT]);
  info->flops_factor = F->uinfo[UMFPACK_FLOPS];
  info->nnz_factor = F->uinfo[UMFPACK_LNZ] + F->uinfo[UMFPACK_UNZ] - (double)n; /* unit diag */
  info->pivot_ratio = F->uinfo[UMFPACK_RCOND];
  if (s != UMFPACK_OK && s != UMFPACK_WARNING_singular_matrix)
    return umfpack_failure(F, "factorisation", s);
  if (s == UMFPACK_WARNING_singular_matrix || !(info->pivot_ratio >= pivot_ratio_min(n))) {
    cupid_int col = 0;
    CUPID_CALL(umfpack_weakest_pivot(F, &col));
    info->failed_dof = global[col];
    char how[96];
    if (s == UMFPACK_WARNING_singular_matrix)
      snprintf(how, sizeof how, "zero pivot");
    else
      snprintf(how, sizeof how, "pivot ratio %.3g", info->pivot_ratio);
    return singular_error(info->failed_dof, bs, how);
  }
  return CUPID_SUCCESS;
}

/* x = K_ff^{-1} b with the factorisation. */
static cupid_status factor_solve(direct_factor *F, double *b, double *x) {
  const cupid_int n = F->A.n;
  if (F->kind == CUPID_MATRIX_SPD) {
    cholmod_dense B;
    memset(&B, 0, sizeof B);
    B.nrow = B.nzmax = B.d = (size_t)n;
    B.ncol = 1;
    B.x = b;
    B.xtype = CHOLMOD_REAL;
    B.dtype = CHOLMOD_DOUBLE;
    cholmod_dense *X = cholmod_l_solve(CHOLMOD_A, F->L, &B, &F->cc);
    if (!X || F->cc.status < CHOLMOD_OK) {
      cholmod_l_free_dense(&X, &F->cc);
      return cholmod_failure(F, "solve");
    }
    memcpy(x, X->x, (size_t)n * sizeof *x);
    cholmod_l_free_dense(&X, &F->cc);
  } else {
    double sinfo[UMFPACK_INFO];
    const SuiteSparse_long s = umfpack_dl_solve(UMFPACK_At, F->A.p, F->A.i, F->A.x, x, b,
                                                F->numeric, F->control, sinfo);
    if (s != UMFPACK_OK) return umfpack_failure(F, "solve", s);
  }
  return CUPID_SUCCESS;
}

static void factor_free(direct_factor *F) {
  if (F->cc_started) {
    cholmod_l_free_factor(&F->L, &F->cc);
    cholmod_l_finish(&F->cc);
    F->cc_started = 0;
  }
  if (F->numeric) umfpack_dl_free_numeric(&F->numeric);
  if (F->symbolic) umfpack_dl_free_symbolic(&F->symbolic);
  reduced_free(&F->A);
}

static double norm2(cupid_int n, const double *v) {
  double s = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : s)
  for (cupid_int k = 0; k < n; k++) s += v[k] * v[k];
  return sqrt(s);
}

/* r_f = f_f - (K u)_f, i.e. b_f - K_ff u_f while u holds u_c on the fixed DOFs; returns ||r_f||. */
static double free_residual(const cupid_csr_t *K, const double *f, const double *u,
                            const cupid_int *global, cupid_int n, double *w, double *r) {
  cupid_csr_matvec(K, u, w);
#pragma omp parallel for schedule(static) if (n > 65536)
  for (cupid_int k = 0; k < n; k++) r[k] = f[global[k]] - w[global[k]];
  return norm2(n, r);
}

/* |K_ff|_inf: the largest absolute row sum over free rows and free columns. */
static double free_norm_inf(const cupid_csr_t *K, const cupid_dirichlet_t *bc) {
  const int bs = K->bs;
  double nrm = 0.0;
#pragma omp parallel for schedule(static) reduction(max : nrm) if (K->nrows > 4096)
  for (cupid_int I = 0; I < K->nrows; I++) {
    for (int a = 0; a < bs; a++) {
      cupid_int g = I * bs + a;
      if (bc->fixed[g]) continue;
      double sum = 0.0;
      for (cupid_int p = K->rowptr[I]; p < K->rowptr[I + 1]; p++)
        for (int c = 0; c < bs; c++)
          if (!bc->fixed[K->col[p] * bs + c]) sum += fabs(K->val[(size_t)p * bs * bs + a * bs + c]);
      if (sum > nrm) nrm = sum;
    }
  }
  return nrm;
}

static double max_abs(cupid_int n, const double *v) {
  double m = 0.0;
  for (cupid_int k = 0; k < n; k++) m = fmax(m, fabs(v[k]));
  return m;
}

static double backward_error(const cupid_csr_t *K, const cupid_dirichlet_t *bc, const double *u,
                             const cupid_int *global, cupid_int n, const double *r, double bmax,
                             double knorm) {
  double umax = 0.0;
  for (cupid_int k = 0; k < n; k++) umax = fmax(umax, fabs(u[global[k]]));
  double denom = knorm * umax + bmax;
  return denom > 0.0 ? max_abs(n, r) / denom : 0.0;
}

/* The caller's bc must be finalized and unchanged since; an O(n) check catches misuse. */
static cupid_status check_dirichlet(const cupid_dirichlet_t *bc) {
  cupid_int k = 0;
  for (cupid_int i = 0; i < bc->n; i++) {
    const cupid_int expect = bc->fixed[i] ? -1 : k++;
    CUPID_CHECK(bc->free_index[i] == expect, CUPID_ERR_ARGUMENT,
                "Dirichlet conditions changed after cupid_dirichlet_finalize (DOF %lld)",
                (long long)i);
  }
  CUPID_CHECK(k == bc->n_free, CUPID_ERR_ARGUMENT,
              "Dirichlet conditions: n_free = %lld but %lld DOFs are free", (long long)bc->n_free,
              (long long)k);
  return CUPID_SUCCESS;
}

cupid_status cupid_direct_solve(const cupid_csr_t *K, cupid_matrix_kind kind, const double *f,
                                const cupid_dirichlet_t *bc, double *u, cupid_solve_info *info) {
  cupid_solve_info local;
  if (!info) info = &local;
  memset(info, 0, sizeof *info);
  info->failed_dof = -1;
  info->method = kind == CUPID_MATRIX_SPD ? "cholmod" : "umfpack";
  CUPID_CHECK(K && f && u, CUPID_ERR_ARGUMENT, "cupid_direct_solve: NULL argument");
  CUPID_CHECK(kind == CUPID_MATRIX_SPD || kind == CUPID_MATRIX_GENERAL, CUPID_ERR_ARGUMENT,
              "cupid_direct_solve: unknown matrix kind %d", (int)kind);
  CUPID_CHECK(K->nrows == K->ncols, CUPID_ERR_ARGUMENT,
              "cupid_direct_solve: the matrix is %lld x %lld blocks, not square",
              (long long)K->nrows, (long long)K->ncols);
  const int bs = K->bs;
  const cupid_int N = K->nrows * bs;
  CUPID_CHECK(!bc || bc->n == N, CUPID_ERR_ARGUMENT,
              "cupid_direct_solve: %lld Dirichlet DOFs for a matrix of %lld DOFs",
              bc ? (long long)bc->n : 0LL, (long long)N);

  cupid_status st = CUPID_SUCCESS;
  cupid_dirichlet own = NULL;
  cupid_int *global = NULL;
  double *w = NULL, *b = NULL, *x = NULL;
  direct_factor F;
  memset(&F, 0, sizeof F);
  F.kind = kind;
  if (!bc) {
    CUPID_TRY(cupid_dirichlet_create(N, &own));
    bc = own;
  }
  CUPID_TRY(check_dirichlet(bc));
  CUPID_TRY(check_finite(N, f, NULL, bs, "load vector entry",
                         "a load (or an expression in one) is not finite", info->method));
  const cupid_int n = bc->n_free;
  info->n = n;
  int any_prescribed = 0;
  for (cupid_int g = 0; g < N; g++) {
    u[g] = bc->fixed[g] ? bc->value[g] : 0.0;
    any_prescribed |= bc->fixed[g] && bc->value[g] != 0.0;
  }
  if (n == 0) goto cleanup; /* everything prescribed */

  CUPID_TRY(cupid_malloc((size_t)n, sizeof *global, "free DOF list", &global));
  for (cupid_int g = 0; g < N; g++)
    if (!bc->fixed[g]) global[bc->free_index[g]] = g;
  CUPID_TRY(cupid_malloc((size_t)N, sizeof *w, "solver work vector", &w));
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *b, "reduced right-hand side", &b));
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *x, "reduced solution", &x));

  /* b_f = f_f - K_fc u_c: K times the vector holding only the prescribed values. */
  if (any_prescribed)
    cupid_csr_matvec(K, u, w);
  else
    memset(w, 0, (size_t)N * sizeof *w);
  for (cupid_int k = 0; k < n; k++) b[k] = f[global[k]] - w[global[k]];
  CUPID_TRY(check_finite(n, b, global, bs, "right-hand side f - K u_c",
                         "the stiffness coupling this DOF to prescribed displacements is not "
                         "finite",
                         info->method));
  const double bnorm = norm2(n, b), bmax = max_abs(n, b);

  double t0 = cupid_wtime();
  CUPID_TRY(reduce_matrix(K, bc, global, kind == CUPID_MATRIX_SPD, &F.A));
  info->nnz_matrix = F.A.nnz_full;
  for (cupid_int k = 0; k < n && st == CUPID_SUCCESS; k++) /* entries of row/column k */
    for (cupid_int t = F.A.p[k]; t < F.A.p[k + 1]; t++)
      if (!isfinite(F.A.x[t])) {
        char where[96], other[96] = "itself (the diagonal)";
        describe_dof(where, sizeof where, global[k], bs);
        if (F.A.i[t] != k) describe_dof(other, sizeof other, global[F.A.i[t]], bs);
        st = CUPID_ERROR(CUPID_ERR_NUMERIC,
                         "%s: non-finite stiffness matrix entry %g coupling %s to %s",
                         info->method, F.A.x[t], where, other);
        break;
      }
  if (st != CUPID_SUCCESS) goto cleanup;
  if (kind == CUPID_MATRIX_SPD)
    st = factor_cholmod(&F, global, bs, info);
  else
    st = factor_umfpack(&F, global, bs, info);
  info->time_factor = cupid_wtime() - t0;
  if (st != CUPID_SUCCESS) goto cleanup;

  t0 = cupid_wtime();
  CUPID_TRY(factor_solve(&F, b, x));
  for (cupid_int k = 0; k < n; k++) u[global[k]] = x[k];
  /* b now receives the residual r_f = b_f - K_ff u_f (computed with the full K). */
  double rnorm = free_residual(K, f, u, global, n, w, b);
  info->residual = bnorm > 0.0 ? rnorm / bnorm : 0.0;
  if (info->residual > REFINE_ABOVE) {
    /* One step of iterative refinement: K_ff d = r_f, u_f += d. */
    CUPID_TRY(factor_solve(&F, b, x));
    for (cupid_int k = 0; k < n; k++) u[global[k]] += x[k];
    rnorm = free_residual(K, f, u, global, n, w, b);
    info->residual = rnorm / bnorm;
    info->refinements = 1;
  }
  info->time_solve = cupid_wtime() - t0;
  for (cupid_int k = 0; k < n; k++) x[k] = u[global[k]];
  CUPID_TRY(check_finite(n, x, global, bs, "solution",
                         "the solve overflowed (a badly scaled or singular stiffness matrix)",
                         info->method));
  info->backward_error = backward_error(K, bc, u, global, n, b, bmax, free_norm_inf(K, bc));
  if (!(info->backward_error <= FAIL_ABOVE) || !(info->residual <= RESIDUAL_FAIL_ABOVE)) {
    /* Point at the smallest pivot: where a near-singularity shows up. */
    cupid_int weak = F.weakest;
    if (kind == CUPID_MATRIX_GENERAL) CUPID_TRY(umfpack_weakest_pivot(&F, &weak));
    info->failed_dof = global[weak];
    char where[96];
    describe_dof(where, sizeof where, info->failed_dof, bs);
    st = CUPID_ERROR(CUPID_ERR_NUMERIC,
                     "%s: backward error %.3g, relative residual %.3g (limits %.0e, %.0e) after "
                     "iterative refinement: the "
                     "stiffness matrix is singular or ill-conditioned%s (smallest pivot ratio "
                     "%.3g at %s): the model may be unconstrained or a region disconnected",
                     info->method, info->backward_error, info->residual, FAIL_ABOVE,
                     RESIDUAL_FAIL_ABOVE,
                     kind == CUPID_MATRIX_SPD ? ", or not symmetric" : "", info->pivot_ratio,
                     where);
  }
cleanup:
  factor_free(&F);
  cupid_free(&global);
  cupid_free(&w);
  cupid_free(&b);
  cupid_free(&x);
  cupid_dirichlet_destroy(&own);
  return st;
}
