/* The built-in iterative engine (solver `krylov`, issue 20): matrix-free Krylov solves of the
 * coupled systems on one process without PETSc, so that the default build has the fast path.
 * The same scheme as the PETSc engine's matrix-free solve (krylov.c): the operator A applied
 * matrix-free, preconditioned by a direct factorisation of the cheap twin P (the same system
 * with a short bond-based PD operator, ~19 blocks a PD row; its factor is ~1/50 of the LPS
 * one): CHOLMOD for a symmetric positive definite system (CG), UMFPACK otherwise
 * (right-preconditioned restarted GMRES, so that the residual it minimises is the true one).
 * Dirichlet DOFs are eliminated: A_ff u_f = f_f - A_fc u_c. The true residual is recomputed at
 * the end. GMRES: Saad, Iterative Methods for Sparse Linear Systems, 2nd ed., Alg. 9.5 (right
 * preconditioning) with modified Gram-Schmidt and Givens rotations; CG: Alg. 9.1. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "cupid/solvers.h"

#define DEFAULT_RTOL 1e-10
#define DEFAULT_MAX_IT 2000
#define DEFAULT_RESTART 200

/* The free DOFs of a system: y_f = (A [x_f ; 0])_f through full-length work vectors. */
typedef struct {
  const cupid_linear_operator *A;
  cupid_int n, nf;
  cupid_int *global; /* free index -> DOF */
  double *xw, *yw;   /* full length */
  cupid_direct_factor F;
  /* or a preconditioner on full-length vectors (cupid_gmres_resolve): r with zero fixed
   * entries in, z out */
  cupid_status (*pc)(void *ctx, const double *r, double *z);
  void *pc_ctx;
  double *pr, *pz;   /* full length, for pc */
} system_free;

/* z = M^-1 r on the free DOFs: the factor's solve, or the caller's preconditioner. */
static cupid_status precondition(system_free *S, const double *r, double *z) {
  if (S->F) return cupid_direct_factor_solve_free(S->F, r, z);
  memset(S->pr, 0, (size_t)S->n * sizeof *S->pr);
  for (cupid_int k = 0; k < S->nf; k++) S->pr[S->global[k]] = r[k];
  CUPID_CALL(S->pc(S->pc_ctx, S->pr, S->pz));
  for (cupid_int k = 0; k < S->nf; k++) z[k] = S->pz[S->global[k]];
  return CUPID_SUCCESS;
}

/* the same to the bit for any thread count (crack growth's re-solves decide bonds with it) */
static double dot(cupid_int n, const double *a, const double *b) { return cupid_dot(n, a, b); }

static void axpy(cupid_int n, double a, const double *x, double *y) {
#pragma omp parallel for schedule(static) if (n > 32768)
  for (cupid_int k = 0; k < n; k++) y[k] += a * x[k];
}

static cupid_status apply_free(system_free *S, const double *x, double *y) {
  for (cupid_int k = 0; k < S->nf; k++) S->xw[S->global[k]] = x[k];
  CUPID_CALL(S->A->apply(S->A->ctx, S->xw, S->yw));
  for (cupid_int k = 0; k < S->nf; k++) y[k] = S->yw[S->global[k]];
  return CUPID_SUCCESS;
}

/* Preconditioned CG on the free DOFs (x holds the initial guess, 0). */
/* CG from x (guess: x's values, else x = 0) to |b - A x| <= rtol |b|, as from zero: a guess
 * does not change what "solved" means. A breakdown (p'Ap <= 0: not positive definite, e.g. a
 * mechanism) is CUPID_ERR_NUMERIC with x the last iterate. */
static cupid_status solve_cg(system_free *S, const double *b, double *x, int guess, double rtol,
                             int max_it, cupid_solve_info *info) {
  const cupid_int n = S->nf;
  cupid_status st = CUPID_SUCCESS;
  double *r = NULL, *z = NULL, *p = NULL, *q = NULL;
  CUPID_TRY(cupid_calloc((size_t)n + 1, sizeof *r, "CG vectors", &r));
  CUPID_TRY(cupid_calloc((size_t)n + 1, sizeof *z, "CG vectors", &z));
  CUPID_TRY(cupid_calloc((size_t)n + 1, sizeof *p, "CG vectors", &p));
  CUPID_TRY(cupid_calloc((size_t)n + 1, sizeof *q, "CG vectors", &q));
  memcpy(r, b, (size_t)n * sizeof *r);
  if (guess) { /* r = b - A x */
    CUPID_TRY(apply_free(S, x, q));
    axpy(n, -1.0, q, r);
  }
  const double bnorm = sqrt(dot(n, b, b));
  double rnorm = guess ? sqrt(dot(n, r, r)) : bnorm;
  CUPID_TRY(precondition(S, r, z));
  memcpy(p, z, (size_t)n * sizeof *p);
  double rz = dot(n, r, z);
  int it = 0;
  while (rnorm > rtol * bnorm && it < max_it) {
    CUPID_TRY(apply_free(S, p, q));
    const double pq = dot(n, p, q);
    CUPID_TRY_CHECK(pq > 0.0, CUPID_ERR_NUMERIC,
                    "CG: the system is not positive definite (p'Ap = %g at iteration %d)", pq, it);
    const double alpha = rz / pq;
    axpy(n, alpha, p, x);
    axpy(n, -alpha, q, r);
    rnorm = sqrt(dot(n, r, r));
    it++;
    CUPID_TRY(precondition(S, r, z));
    const double rz_new = dot(n, r, z), beta = rz_new / rz;
    rz = rz_new;
#pragma omp parallel for schedule(static) if (n > 32768)
    for (cupid_int k = 0; k < n; k++) p[k] = z[k] + beta * p[k];
  }
  info->iterations = it;
  snprintf(info->converged_reason, sizeof info->converged_reason, "%s",
           rnorm <= rtol * bnorm ? "CONVERGED_RTOL" : "DIVERGED_ITS");
cleanup:
  cupid_free(&r);
  cupid_free(&z);
  cupid_free(&p);
  cupid_free(&q);
  return st;
}

/* The round-off of the product at x, relative to |b|: |A x - (A (x + z) - A z)| / |b| for z =
 * x scaled entry by entry by fixed factors in [0.5, 1.5) (Ax in w). A true residual at this
 * level is as small as b - A x can be computed: the stiffened panel's matrix-free LPS product
 * has 2e-8 of |b| (docs/scale.md), above rtol 1e-10 however many restarts. */
static cupid_status product_noise(system_free *S, const double *x, const double *w,
                                  double bnorm, double *noise) {
  const cupid_int n = S->nf;
  cupid_status st = CUPID_SUCCESS;
  double *z = NULL, *xz = NULL, *az = NULL, *axz = NULL;
  CUPID_TRY(cupid_malloc((size_t)n + 1, sizeof *z, "round-off probe", &z));
  CUPID_TRY(cupid_malloc((size_t)n + 1, sizeof *xz, "round-off probe", &xz));
  CUPID_TRY(cupid_malloc((size_t)n + 1, sizeof *az, "round-off probe", &az));
  CUPID_TRY(cupid_malloc((size_t)n + 1, sizeof *axz, "round-off probe", &axz));
  uint64_t s = 0x9E3779B97F4A7C15ull;
  for (cupid_int k = 0; k < n; k++) {
    s ^= s << 13, s ^= s >> 7, s ^= s << 17;
    z[k] = x[k] * (0.5 + (double)(s >> 11) / 9007199254740992.0);
    xz[k] = x[k] + z[k];
  }
  CUPID_TRY(apply_free(S, z, az));
  CUPID_TRY(apply_free(S, xz, axz));
  double e = 0.0;
  for (cupid_int k = 0; k < n; k++) {
    const double d = w[k] - (axz[k] - az[k]);
    e += d * d;
  }
  *noise = bnorm > 0 ? sqrt(e) / bnorm : sqrt(e);
cleanup:
  cupid_free(&z);
  cupid_free(&xz);
  cupid_free(&az);
  cupid_free(&axz);
  return st;
}

/* Restarts from the true residual after GMRES met rtol on its estimate (at most). */
#define KRYLOV_REFINEMENTS 3

/* Right-preconditioned restarted GMRES(m): x = M^{-1} (V y), M^{-1} by the twin's factor.
 * A cycle stops on GMRES's own residual estimate |g_{j+1}|, which is the true residual only
 * if M^{-1} is applied exactly: x = M^{-1} (V y) is one more solve, whose error the estimate
 * never sees (an LU solve of backward error eta leaves |b - A x| ~ eta kappa |b|). So every
 * cycle starts from the true residual r = b - A x, and the solve ends only on it:
 *  - at or below rtol |b| (2 rtol |b| after a cycle that met rtol on its estimate):
 *    CONVERGED_RTOL;
 *  - after a cycle that met rtol on its estimate, at most twice the round-off of the product
 *    (product_noise()): CONVERGED_ROUNDOFF, b - A x cannot be computed closer;
 *  - else a refinement cycle from r (aiming at rtol / 2), KRYLOV_REFINEMENTS of them at most
 *    and while each at least halves the true residual; then CONVERGED_RTOL up to
 *    max(100 rtol, 1e-10), DIVERGED_TRUE_RESIDUAL above. */
static cupid_status solve_gmres(system_free *S, const double *b, double *x, double rtol,
                                int max_it, int m, cupid_solve_info *info) {
  const cupid_int n = S->nf;
  cupid_status st = CUPID_SUCCESS;
  double *V = NULL, *H = NULL, *cs = NULL, *sn = NULL, *g = NULL, *w = NULL, *z = NULL, *y = NULL;
  CUPID_TRY(cupid_malloc((size_t)(m + 1) * (size_t)n + 1, sizeof *V, "GMRES basis", &V));
  CUPID_TRY(cupid_calloc((size_t)(m + 1) * (size_t)m + 1, sizeof *H, "GMRES Hessenberg", &H));
  CUPID_TRY(cupid_calloc((size_t)m + 1, sizeof *cs, "GMRES rotations", &cs));
  CUPID_TRY(cupid_calloc((size_t)m + 1, sizeof *sn, "GMRES rotations", &sn));
  CUPID_TRY(cupid_calloc((size_t)m + 2, sizeof *g, "GMRES residuals", &g));
  CUPID_TRY(cupid_calloc((size_t)m + 1, sizeof *y, "GMRES coefficients", &y));
  CUPID_TRY(cupid_calloc((size_t)n + 1, sizeof *w, "GMRES vectors", &w));
  CUPID_TRY(cupid_calloc((size_t)n + 1, sizeof *z, "GMRES vectors", &z));
  const double bnorm = sqrt(dot(n, b, b)), limit = fmax(100.0 * rtol, 1e-10);
  const char *reason = "DIVERGED_ITS";
  int it = 0, met = 0; /* met: the last cycle reached rtol on its estimate */
  double prev = INFINITY, noise = -1.0; /* the last cycle's true residual; product round-off */
  info->refinements = 0;
  for (;;) {
    /* r = b - A x, v1 = r / |r| */
    CUPID_TRY(apply_free(S, x, w));
    for (cupid_int k = 0; k < n; k++) V[k] = b[k] - w[k];
    const double rnorm0 = sqrt(dot(n, V, V));
    if (rnorm0 <= rtol * bnorm || (met && rnorm0 <= 2.0 * rtol * bnorm)) {
      reason = "CONVERGED_RTOL";
      break;
    }
    if (met) {
      if (noise < 0.0) CUPID_TRY(product_noise(S, x, w, bnorm, &noise));
      if (rnorm0 <= 2.0 * noise * bnorm) {
        reason = "CONVERGED_ROUNDOFF";
        break;
      }
      if (info->refinements == KRYLOV_REFINEMENTS || rnorm0 > 0.5 * prev) {
        reason = rnorm0 <= limit * bnorm ? "CONVERGED_RTOL" : "DIVERGED_TRUE_RESIDUAL";
        break;
      }
    }
    if (it >= max_it) break;
    prev = rnorm0;
    if (met) info->refinements++;
    const double target = (met ? 0.5 : 1.0) * rtol * bnorm;
    met = 0;
    for (cupid_int k = 0; k < n; k++) V[k] /= rnorm0;
    memset(g, 0, (size_t)(m + 2) * sizeof *g);
    g[0] = rnorm0;
    int j = 0;
    for (; j < m && it < max_it; j++, it++) {
      double *vj = V + (size_t)j * (size_t)n, *vn = V + (size_t)(j + 1) * (size_t)n;
      CUPID_TRY(precondition(S, vj, z));
      CUPID_TRY(apply_free(S, z, vn));
      for (int i = 0; i <= j; i++) { /* modified Gram-Schmidt */
        const double *vi = V + (size_t)i * (size_t)n;
        const double hij = dot(n, vn, vi);
        H[i * m + j] = hij;
        axpy(n, -hij, vi, vn);
      }
      const double hn = sqrt(dot(n, vn, vn));
      H[(j + 1) * m + j] = hn;
      if (hn > 0.0)
        for (cupid_int k = 0; k < n; k++) vn[k] /= hn;
      for (int i = 0; i < j; i++) { /* the earlier rotations on the new column */
        const double a = H[i * m + j], c = H[(i + 1) * m + j];
        H[i * m + j] = cs[i] * a + sn[i] * c;
        H[(i + 1) * m + j] = -sn[i] * a + cs[i] * c;
      }
      const double a = H[j * m + j], c = H[(j + 1) * m + j], r = hypot(a, c);
      cs[j] = r > 0.0 ? a / r : 1.0;
      sn[j] = r > 0.0 ? c / r : 0.0;
      H[j * m + j] = r;
      H[(j + 1) * m + j] = 0.0;
      g[j + 1] = -sn[j] * g[j];
      g[j] = cs[j] * g[j];
      if (fabs(g[j + 1]) <= target || hn == 0.0) {
        met = 1;
        j++;
        it++;
        break;
      }
    }
    /* y = H^{-1} g (upper triangular, j columns), x += M^{-1} V y */
    for (int i = j - 1; i >= 0; i--) {
      double s = g[i];
      for (int k = i + 1; k < j; k++) s -= H[i * m + k] * y[k];
      y[i] = H[i * m + i] != 0.0 ? s / H[i * m + i] : 0.0;
    }
    memset(w, 0, (size_t)n * sizeof *w);
    for (int i = 0; i < j; i++) axpy(n, y[i], V + (size_t)i * (size_t)n, w);
    CUPID_TRY(precondition(S, w, z));
    axpy(n, 1.0, z, x);
  }
  info->iterations = it;
  snprintf(info->converged_reason, sizeof info->converged_reason, "%s", reason);
cleanup:
  cupid_free(&V);
  cupid_free(&H);
  cupid_free(&cs);
  cupid_free(&sn);
  cupid_free(&g);
  cupid_free(&y);
  cupid_free(&w);
  cupid_free(&z);
  return st;
}

/* The free system of @p bc: S's DOF map and work vectors, b_f = f_f - A_fc u_c (A times the
 * vector holding only the prescribed values; S->xw left zero: fixed DOFs stay 0 in products). */
static cupid_status free_system(system_free *S, const cupid_dirichlet_t *bc, const double *f,
                                double *b) {
  CUPID_CALL(cupid_malloc((size_t)S->nf + 1, sizeof *S->global, "free DOFs", &S->global));
  CUPID_CALL(cupid_calloc((size_t)S->n + 1, sizeof *S->xw, "work vector", &S->xw));
  CUPID_CALL(cupid_calloc((size_t)S->n + 1, sizeof *S->yw, "work vector", &S->yw));
  for (cupid_int d = 0, k = 0; d < S->n; d++)
    if (!bc->fixed[d]) S->global[k++] = d;
  for (cupid_int d = 0; d < S->n; d++) S->xw[d] = bc->fixed[d] ? bc->value[d] : 0.0;
  CUPID_CALL(S->A->apply(S->A->ctx, S->xw, S->yw));
  for (cupid_int k = 0; k < S->nf; k++) b[k] = f[S->global[k]] - S->yw[S->global[k]];
  memset(S->xw, 0, (size_t)S->n * sizeof *S->xw);
  return CUPID_SUCCESS;
}

/* The true relative residual |b_f - A_ff x_f| / |b_f| into info, recomputed (ax: scratch);
 * a non-finite x is a NUMERIC error naming its DOF. */
static cupid_status true_residual(system_free *S, const double *b, const double *x, double *ax,
                                  cupid_solve_info *info) {
  CUPID_CALL(apply_free(S, x, ax));
  double r2 = 0.0, b2 = 0.0;
  for (cupid_int k = 0; k < S->nf; k++) {
    const double r = b[k] - ax[k];
    r2 += r * r;
    b2 += b[k] * b[k];
  }
  info->residual = b2 > 0 ? sqrt(r2 / b2) : sqrt(r2);
  for (cupid_int k = 0; k < S->nf; k++)
    CUPID_CHECK(isfinite(x[k]), CUPID_ERR_NUMERIC, "the Krylov solve: non-finite solution at DOF %lld",
                (long long)S->global[k]);
  return CUPID_SUCCESS;
}

cupid_status cupid_iterative_solve(const cupid_linear_operator *A, const cupid_csr_t *P,
                                   const cupid_dirichlet_t *bc, const double *f, double *u,
                                   const cupid_krylov_options *opts, cupid_solve_info *info) {
  cupid_solve_info local;
  if (!info) info = &local;
  memset(info, 0, sizeof *info);
  info->method = "krylov";
  info->failed_dof = -1;
  info->ranks = 1;
  info->matrix_free = 1;
  CUPID_CHECK(A && P && bc && f && u, CUPID_ERR_ARGUMENT, "cupid_iterative_solve: NULL argument");
  CUPID_CHECK(!A->part || A->part->parts <= 1, CUPID_ERR_UNSUPPORTED,
              "solver krylov runs on one process: a PD grid split into slabs needs solver petsc");
  CUPID_CHECK(bc->n == A->n, CUPID_ERR_ARGUMENT, "cupid_iterative_solve: %lld conditions for %lld DOFs",
              (long long)bc->n, (long long)A->n);
  const double rtol = opts && opts->rtol > 0 ? opts->rtol : DEFAULT_RTOL;
  const int max_it = opts && opts->max_it > 0 ? opts->max_it : DEFAULT_MAX_IT;
  const int restart = opts && opts->restart > 0 ? opts->restart : DEFAULT_RESTART;
  snprintf(info->ksp_type, sizeof info->ksp_type, "%s", A->symmetric ? "cg" : "gmres");
  snprintf(info->pc_type, sizeof info->pc_type, "%s", A->symmetric ? "cholmod" : "umfpack");
  system_free S = {.A = A, .n = A->n, .nf = bc->n_free};
  cupid_status st = CUPID_SUCCESS;
  double *b = NULL, *x = NULL, *ax = NULL, t0 = cupid_wtime();
  info->n = S.nf;
  CUPID_TRY(cupid_calloc((size_t)S.nf + 1, sizeof *b, "right-hand side", &b));
  CUPID_TRY(cupid_calloc((size_t)S.nf + 1, sizeof *x, "solution", &x));
  CUPID_TRY(free_system(&S, bc, f, b));
  for (cupid_int d = 0; d < S.n; d++) u[d] = bc->fixed[d] ? bc->value[d] : 0.0;
  CUPID_TRY(cupid_direct_factor_create_kind(P, A->symmetric ? CUPID_MATRIX_SPD : CUPID_MATRIX_GENERAL,
                                            bc, &S.F, NULL));
  info->time_factor = cupid_wtime() - t0;
  t0 = cupid_wtime();
  if (A->symmetric) CUPID_TRY(solve_cg(&S, b, x, 0, rtol, max_it, info));
  else CUPID_TRY(solve_gmres(&S, b, x, rtol, max_it, restart, info));
  /* u = [x_f ; u_c]; the true residual, recomputed */
  for (cupid_int k = 0; k < S.nf; k++) u[S.global[k]] = x[k];
  CUPID_TRY(cupid_calloc((size_t)S.nf + 1, sizeof *ax, "residual", &ax));
  CUPID_TRY(true_residual(&S, b, x, ax, info));
  info->time_solve = cupid_wtime() - t0;
  CUPID_TRY_CHECK(strcmp(info->converged_reason, "DIVERGED_TRUE_RESIDUAL"), CUPID_ERR_NUMERIC,
                  "the Krylov solve (%s + %s) met its tolerance on its residual estimate, but "
                  "the true relative residual is %.2e after %d iterations and %d restarts (rtol "
                  "%.0e): the preconditioner is inaccurate; use --solver direct",
                  info->ksp_type, info->pc_type, info->residual, info->iterations,
                  info->refinements, rtol);
  CUPID_TRY_CHECK(!strncmp(info->converged_reason, "CONVERGED", 9), CUPID_ERR_NUMERIC,
                  "the Krylov solve (%s + %s) did not converge in %d iterations: relative "
                  "residual %.2e (rtol %.0e); use --solver direct",
                  info->ksp_type, info->pc_type, info->iterations, info->residual, rtol);
cleanup:
  cupid_direct_factor_destroy(&S.F);
  cupid_free(&S.global);
  cupid_free(&S.xw);
  cupid_free(&S.yw);
  cupid_free(&b);
  cupid_free(&x);
  cupid_free(&ax);
  return st;
}

/* CG from x, then checked by the true residual (left in info->residual): CG's own residual is a recurrence, which a
 * preconditioner far from A (the intact twin of a cracked K) lets drift from b - A x. While the
 * true one is above rtol and its CG run converged, CG again from x (a refinement: at most
 * KRYLOV_REFINEMENTS, each while it at least halves the true residual; info->iterations counts
 * them all); above max(100 rtol, 1e-10) at the end: DIVERGED_TRUE_RESIDUAL, as GMRES. */
static cupid_status cg_refined(system_free *S, const double *b, double *x, double *ax, double rtol,
                               int max_it, cupid_solve_info *info) {
  int total = 0;
  double prev = INFINITY;
  info->refinements = 0;
  for (;;) {
    CUPID_CALL(solve_cg(S, b, x, 1, rtol, max_it - total, info));
    total += info->iterations;
    info->iterations = total;
    CUPID_CALL(true_residual(S, b, x, ax, info));
    if (strncmp(info->converged_reason, "CONVERGED", 9) || info->residual <= rtol)
      return CUPID_SUCCESS;
    if (info->refinements == KRYLOV_REFINEMENTS || info->residual > 0.5 * prev || total >= max_it)
      break;
    prev = info->residual;
    info->refinements++;
  }
  if (info->residual > fmax(100.0 * rtol, 1e-10))
    snprintf(info->converged_reason, sizeof info->converged_reason, "DIVERGED_TRUE_RESIDUAL");
  return CUPID_SUCCESS;
}

/* A re-solve from u (cupid_gmres_resolve, cupid_krylov_resolve): CG or GMRES. */
static cupid_status resolve(const cupid_linear_operator *A, const cupid_dirichlet_t *bc,
                            cupid_status (*pc)(void *ctx, const double *r, double *z), void *pc_ctx,
                            const double *f, double *u, double rtol, int max_it, int cg,
                            cupid_solve_info *info) {
  CUPID_CHECK(A && A->apply && bc && pc && f && u && info && bc->n == A->n && rtol > 0 && max_it > 0,
              CUPID_ERR_ARGUMENT, "cupid_krylov_resolve: bad arguments");
  memset(info, 0, sizeof *info);
  info->method = cg ? "cg" : "gmres";
  info->failed_dof = -1;
  info->ranks = 1;
  snprintf(info->ksp_type, sizeof info->ksp_type, "%s", cg ? "cg" : "gmres");
  snprintf(info->pc_type, sizeof info->pc_type, "given");
  system_free S = {.A = A, .n = A->n, .nf = bc->n_free, .pc = pc, .pc_ctx = pc_ctx};
  cupid_status st = CUPID_SUCCESS;
  double *b = NULL, *x = NULL, *ax = NULL, t0 = cupid_wtime();
  int have_x = 0;
  info->n = S.nf;
  CUPID_TRY(cupid_calloc((size_t)S.n + 1, sizeof *S.pr, "work vector", &S.pr));
  CUPID_TRY(cupid_calloc((size_t)S.n + 1, sizeof *S.pz, "work vector", &S.pz));
  CUPID_TRY(cupid_calloc((size_t)S.nf + 1, sizeof *b, "right-hand side", &b));
  CUPID_TRY(cupid_calloc((size_t)S.nf + 1, sizeof *x, "solution", &x));
  CUPID_TRY(cupid_calloc((size_t)S.nf + 1, sizeof *ax, "residual", &ax));
  CUPID_TRY(free_system(&S, bc, f, b));
  for (cupid_int k = 0; k < S.nf; k++) x[k] = u[S.global[k]]; /* the guess: u's free values */
  have_x = 1;
  const int restart = max_it < DEFAULT_RESTART ? max_it : DEFAULT_RESTART;
  if (cg) CUPID_TRY(cg_refined(&S, b, x, ax, rtol, max_it, info)); /* its true residual */
  else {
    CUPID_TRY(solve_gmres(&S, b, x, rtol, max_it, restart, info));
    CUPID_TRY(true_residual(&S, b, x, ax, info));
  }
  info->time_solve = cupid_wtime() - t0;
cleanup: /* u: the last iterate, converged or not (a CG breakdown's too), if finite */
  for (cupid_int k = 0; have_x && st == CUPID_ERR_NUMERIC && k < S.nf; k++)
    if (!isfinite(x[k])) have_x = 0;
  if (have_x && (st == CUPID_SUCCESS || st == CUPID_ERR_NUMERIC)) {
    for (cupid_int d = 0; d < S.n; d++)
      if (bc->fixed[d]) u[d] = bc->value[d];
    for (cupid_int k = 0; k < S.nf; k++) u[S.global[k]] = x[k];
  }
  cupid_free(&S.global);
  cupid_free(&S.xw);
  cupid_free(&S.yw);
  cupid_free(&S.pr);
  cupid_free(&S.pz);
  cupid_free(&b);
  cupid_free(&x);
  cupid_free(&ax);
  return st;
}

cupid_status cupid_gmres_resolve(const cupid_linear_operator *A, const cupid_dirichlet_t *bc,
                                 cupid_status (*pc)(void *ctx, const double *r, double *z),
                                 void *pc_ctx, const double *f, double *u, double rtol,
                                 int max_it, cupid_solve_info *info) {
  return resolve(A, bc, pc, pc_ctx, f, u, rtol, max_it, 0, info);
}

cupid_status cupid_krylov_resolve(const cupid_linear_operator *A, const cupid_dirichlet_t *bc,
                                  cupid_status (*pc)(void *ctx, const double *r, double *z),
                                  void *pc_ctx, const double *f, double *u, double rtol,
                                  int max_it, cupid_solve_info *info) {
  return resolve(A, bc, pc, pc_ctx, f, u, rtol, max_it, A && A->symmetric, info);
}
