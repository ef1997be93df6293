/* The PETSc/MPI engine (issue 6): Krylov solves of replicated cupid systems, assembled (MPIAIJ)
 * or matrix-free for node operators such as PD (MATSHELL over cupid_node_operator products). The only file that
 * includes petsc.h; without PETSc (CUPID_HAVE_PETSC 0) every entry point is a stub.
 *
 * Layout: every rank holds the whole model. The unknowns are all DOFs (fixed ones as scaled
 * identity rows, their columns moved to the right-hand side), split in contiguous blocks of
 * whole nodes: for a PD grid numbered z slowest, each rank owns a z-slab. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cupid/solvers.h"
#include "cupid_config.h"

int cupid_petsc_available(void) { return CUPID_HAVE_PETSC; }

int cupid_petsc_launched_parallel(void) {
  static const char *const vars[] = {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"};
  for (size_t k = 0; k < sizeof vars / sizeof *vars; k++) {
    const char *v = getenv(vars[k]);
    if (v && atoi(v) > 1) return 1;
  }
  return 0;
}

static int g_argc = 0;
static char **g_argv = NULL;

void cupid_petsc_set_args(int argc, char **argv) {
  g_argc = argc;
  g_argv = argv;
}

#if CUPID_HAVE_PETSC
#include <limits.h>
#include <math.h>
#include <petscksp.h>

#include "petsc_internal.h"

static int g_initialized = 0;

/* PTRY: petsc_internal.h. */
cupid_status cupid_petsc_error(int ierr, const char *what) {
  const char *text = NULL;
  PetscErrorMessage((PetscErrorCode)ierr, &text, NULL);
  cupid_status code = ierr == PETSC_ERR_MEM ? CUPID_ERR_MEMORY : CUPID_ERR_NUMERIC;
  return CUPID_ERROR(code, "PETSc error %d (%s) in %s", ierr, text ? text : "unknown", what);
}

cupid_status cupid_petsc_initialize(int argc, char **argv) {
  if (g_initialized) return CUPID_SUCCESS;
  static int s_argc;
  static char **s_argv;
  s_argc = argv ? argc : g_argc;
  s_argv = argv ? argv : g_argv;
  PetscErrorCode ierr = s_argv ? PetscInitialize(&s_argc, &s_argv, NULL, NULL)
                               : PetscInitializeNoArguments();
  if (ierr) return CUPID_ERROR(CUPID_ERR_INTERNAL, "PetscInitialize failed (error %d)", (int)ierr);
  /* Errors come back as codes; cupid prints one message (rank 0) instead of PETSc's trace. */
  PetscPushErrorHandler(PetscReturnErrorHandler, NULL);
  g_initialized = 1;
  return CUPID_SUCCESS;
}

int cupid_petsc_initialized(void) { return g_initialized; }

void cupid_petsc_finalize(void) {
  if (!g_initialized) return;
  PetscPopErrorHandler();
  PetscFinalize();
  g_initialized = 0;
}

int cupid_petsc_rank(void) {
  if (!g_initialized) return 0;
  PetscMPIInt r = 0;
  MPI_Comm_rank(PETSC_COMM_WORLD, &r);
  return r;
}

int cupid_petsc_size(void) {
  if (!g_initialized) return 1;
  PetscMPIInt n = 1;
  MPI_Comm_size(PETSC_COMM_WORLD, &n);
  return n;
}

int cupid_petsc_max_int(int v) {
  if (!g_initialized) return v;
  int out = v;
  MPI_Allreduce(&v, &out, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD);
  return out;
}

int cupid_petsc_has_option(const char *name) {
  PetscBool set = PETSC_FALSE;
  if (!g_initialized || PetscOptionsHasName(NULL, NULL, name, &set)) return 0;
  return set == PETSC_TRUE;
}

void cupid_petsc_sum_doubles(double *v, int n) {
  if (g_initialized && n > 0) MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
}

void cupid_petsc_max_doubles(double *v, int n) {
  if (g_initialized && n > 0) MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_DOUBLE, MPI_MAX, PETSC_COMM_WORLD);
}

cupid_status cupid_petsc_gather_root(const double *local, cupid_int count, double *root) {
  int size = cupid_petsc_size(), rank = cupid_petsc_rank();
  if (size == 1) {
    if (count > 0) memcpy(root, local, (size_t)count * sizeof *root);
    return CUPID_SUCCESS;
  }
  /* Every check is agreed by all ranks before the collective, so that none waits alone. */
  double total = (double)count;
  cupid_petsc_sum_doubles(&total, 1);
  CUPID_CHECK(total <= (double)INT_MAX, CUPID_ERR_UNSUPPORTED,
              "gathering %.0f values on rank 0: more than MPI's 2^31 - 1", total);
  int n = (int)count, *counts = NULL, *displs = NULL;
  cupid_status st = CUPID_SUCCESS;
  if (rank == 0) {
    st = cupid_malloc((size_t)size, sizeof *counts, "gather counts", &counts);
    if (st == CUPID_SUCCESS) st = cupid_malloc((size_t)size, sizeof *displs, "gather offsets", &displs);
  }
  if (cupid_petsc_max_int(st != CUPID_SUCCESS)) {
    if (st == CUPID_SUCCESS) st = CUPID_ERROR(CUPID_ERR_MEMORY, "rank 0 could not gather the results");
    goto cleanup;
  }
  MPI_Gather(&n, 1, MPI_INT, counts, 1, MPI_INT, 0, PETSC_COMM_WORLD);
  if (rank == 0)
    for (int r = 0, off = 0; r < size; r++) displs[r] = off, off += counts[r];
  MPI_Gatherv(local, n, MPI_DOUBLE, root, counts, displs, MPI_DOUBLE, 0, PETSC_COMM_WORLD);
cleanup:
  cupid_free(&counts);
  cupid_free(&displs);
  return st;
}

void cupid_petsc_abort(int code) {
  if (g_initialized) MPI_Abort(PETSC_COMM_WORLD, code);
  exit(code);
}

/* The copies of a process's local vector: a global PETSc vector of the owned entries (in rank
 * order, as the slabs are) and one scatter from it to the entries this process holds but does
 * not own. */
struct cupid_petsc_halo_s {
  cupid_int n, owned_first, owned_last;
  cupid_int n_copies;
  cupid_int *copies; /* local indices of the copies, ascending */
  Vec global, local;
  VecScatter scatter;
};

void cupid_petsc_halo_destroy(cupid_petsc_halo *h) {
  if (!h || !*h) return;
  if ((*h)->scatter) VecScatterDestroy(&(*h)->scatter);
  if ((*h)->global) VecDestroy(&(*h)->global);
  if ((*h)->local) VecDestroy(&(*h)->local);
  cupid_free(&(*h)->copies);
  cupid_free(h);
}

cupid_status cupid_petsc_halo_create(cupid_int n, cupid_int owned_first, cupid_int owned_last,
                                     cupid_int global_first, cupid_petsc_halo *out) {
  CUPID_CHECK(out && owned_first >= 0 && owned_first <= owned_last && owned_last <= n,
              CUPID_ERR_ARGUMENT, "cupid_petsc_halo_create: owned range outside [0, n)");
  CUPID_CHECK(g_initialized, CUPID_ERR_ARGUMENT, "cupid_petsc_halo_create: PETSc not initialised");
  *out = NULL;
  cupid_petsc_halo h = NULL;
  PetscInt *idx = NULL;
  IS from = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_CALL(cupid_calloc(1, sizeof *h, "halo", &h));
  h->n = n, h->owned_first = owned_first, h->owned_last = owned_last;
  h->n_copies = n - (owned_last - owned_first);
  CUPID_TRY(cupid_malloc((size_t)h->n_copies + 1, sizeof *h->copies, "halo indices", &h->copies));
  CUPID_TRY(cupid_malloc((size_t)h->n_copies + 1, sizeof *idx, "halo indices", &idx));
  cupid_int k = 0;
  for (cupid_int d = 0; d < n; d++)
    if (d < owned_first || d >= owned_last) h->copies[k] = d, idx[k++] = (PetscInt)(global_first + d);
  PTRY(VecCreateMPI(PETSC_COMM_WORLD, (PetscInt)(owned_last - owned_first), PETSC_DETERMINE,
                    &h->global));
  PetscInt lo = 0;
  PTRY(VecGetOwnershipRange(h->global, &lo, NULL));
  CUPID_TRY_CHECK(lo == (PetscInt)(global_first + owned_first), CUPID_ERR_ARGUMENT,
                  "cupid_petsc_halo_create: the owned ranges are not in rank order");
  PTRY(VecCreateSeq(PETSC_COMM_SELF, (PetscInt)h->n_copies, &h->local));
  PTRY(ISCreateGeneral(PETSC_COMM_SELF, (PetscInt)h->n_copies, idx, PETSC_USE_POINTER, &from));
  PTRY(VecScatterCreate(h->global, from, h->local, NULL, &h->scatter));
  *out = h;
  h = NULL;
cleanup:
  if (from) ISDestroy(&from);
  cupid_free(&idx);
  cupid_petsc_halo_destroy(&h);
  return st;
}

cupid_status cupid_petsc_halo_update(cupid_petsc_halo h, double *x) {
  cupid_status st = CUPID_SUCCESS;
  PetscScalar *g = NULL;
  const PetscScalar *l = NULL;
  PTRY(VecGetArray(h->global, &g));
  memcpy(g, x + h->owned_first, sizeof *x * (size_t)(h->owned_last - h->owned_first));
  PTRY(VecRestoreArray(h->global, &g));
  PTRY(VecScatterBegin(h->scatter, h->global, h->local, INSERT_VALUES, SCATTER_FORWARD));
  PTRY(VecScatterEnd(h->scatter, h->global, h->local, INSERT_VALUES, SCATTER_FORWARD));
  PTRY(VecGetArrayRead(h->local, &l));
  for (cupid_int k = 0; k < h->n_copies; k++) x[h->copies[k]] = l[k];
  PTRY(VecRestoreArrayRead(h->local, &l));
cleanup:
  return st;
}

/* ------------------------------------------------------------------ the distributed layout */

/* Rows [*first, *last) of n DOFs owned by this rank: whole blocks of bs, split evenly. */
static void owned_rows(cupid_int n, int bs, cupid_int *first, cupid_int *last) {
  PetscMPIInt rank, size;
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  MPI_Comm_size(PETSC_COMM_WORLD, &size);
  cupid_int nb = n / bs, q = nb / size, r = nb % size;
  cupid_int b0 = rank * q + (rank < r ? rank : r);
  cupid_int b1 = b0 + q + (rank < r ? 1 : 0);
  *first = b0 * bs;
  *last = b1 * bs;
}

/* The scale of the identity rows of fixed DOFs: the mean |diagonal| of the free DOFs, so the
 * fixed block neither dominates nor vanishes in the AMG strength tests. */
static double identity_scale(const double *diag, cupid_int n, const cupid_dirichlet_t *bc) {
  double sum = 0.0;
  cupid_int count = 0;
  for (cupid_int d = 0; d < n; d++)
    if (!(bc && bc->fixed[d]) && diag[d] != 0.0) sum += fabs(diag[d]), count++;
  return count ? sum / (double)count : 1.0;
}

/* Rigid-body near null space from node coordinates (3 per owned node), for GAMG. */
static cupid_status set_rigid_body(Mat A, const double *coords, cupid_int first, cupid_int last) {
  cupid_status st = CUPID_SUCCESS;
  Vec xc = NULL;
  MatNullSpace ns = NULL;
  PTRY(VecCreateMPI(PETSC_COMM_WORLD, (PetscInt)(last - first), PETSC_DETERMINE, &xc));
  PTRY(VecSetBlockSize(xc, 3));
  PetscScalar *a;
  PTRY(VecGetArray(xc, &a));
  memcpy(a, coords + first, (size_t)(last - first) * sizeof *a);
  PTRY(VecRestoreArray(xc, &a));
  PTRY(MatNullSpaceCreateRigidBody(xc, &ns));
  PTRY(MatSetNearNullSpace(A, ns));
cleanup:
  MatNullSpaceDestroy(&ns);
  VecDestroy(&xc);
  return st;
}

/* --------------------------------------------------------------------- the Krylov solve */

typedef struct {
  KSPType ksp;
  PCType pc;
  int gmres_restart;
} solver_defaults;

#define CUPID_PETSC_REFINEMENTS 3

/* r = b - A x; info->residual = ||r|| / ||b||, info->backward_error (|A|_inf known only when A
 * is assembled: A == P). */
static cupid_status true_residual(Mat A, Mat P, Vec b, Vec x, Vec r, cupid_solve_info *info) {
  cupid_status st = CUPID_SUCCESS;
  PetscReal rn, bn, an = 0.0, xn, rin, bin;
  PTRY(MatMult(A, x, r));
  PTRY(VecAYPX(r, -1.0, b));
  PTRY(VecNorm(r, NORM_2, &rn));
  PTRY(VecNorm(b, NORM_2, &bn));
  PTRY(VecNorm(r, NORM_INFINITY, &rin));
  PTRY(VecNorm(b, NORM_INFINITY, &bin));
  PTRY(VecNorm(x, NORM_INFINITY, &xn));
  if (A == P) PTRY(MatNorm(A, NORM_INFINITY, &an));
  info->residual = bn > 0 ? rn / bn : rn;
  info->backward_error = (an * xn + bin) > 0 ? rin / (an * xn + bin) : 0.0;
cleanup:
  return st;
}

/* The tolerances a KSP was set up with (cupid's, then the user's options): restored before
 * each solve of a kept KSP, whose refinement passes below change them. */
typedef struct {
  PetscReal rtol, atol, dtol;
  PetscInt maxit;
} ksp_tolerances;

/* KSP on A (operator) and P (preconditioner matrix) with cupid's defaults, then the user's
 * -ksp_* / -pc_* options, set up (the preconditioner built): *seconds the time it took. */
static cupid_status krylov_create(Mat A, Mat P, const solver_defaults *def, KSP *out,
                                  ksp_tolerances *tol, double *seconds) {
  cupid_status st = CUPID_SUCCESS;
  KSP ksp = NULL;
  PC pc;
  double t0 = cupid_wtime();
  PTRY(KSPCreate(PETSC_COMM_WORLD, &ksp));
  PTRY(KSPSetOperators(ksp, A, P));
  PTRY(KSPSetType(ksp, def->ksp));
  PTRY(KSPGetPC(ksp, &pc));
  PTRY(PCSetType(pc, def->pc));
  /* Unpreconditioned residual: rtol then bounds ||b - A x|| / ||b||, the figure compared with
   * the direct solve (1e-12 keeps the solution within ~1e-10 relative at condition ~1e2-1e4 of
   * the preconditioned system; 1e-8 is what the MPI test demands). */
  if (!strcmp(def->ksp, KSPGMRES)) {
    PTRY(KSPSetPCSide(ksp, PC_RIGHT));
    PTRY(KSPGMRESSetRestart(ksp, def->gmres_restart));
    PTRY(KSPGMRESSetOrthogonalization(ksp, KSPGMRESModifiedGramSchmidtOrthogonalization));
  } else {
    PTRY(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED));
  }
  PTRY(KSPSetTolerances(ksp, 1e-12, 0.0, PETSC_DEFAULT, 10000));
  PTRY(KSPSetFromOptions(ksp));
  PTRY(KSPSetUp(ksp));
  PTRY(KSPSetUpOnBlocks(ksp));
  PTRY(KSPGetTolerances(ksp, &tol->rtol, &tol->atol, &tol->dtol, &tol->maxit));
  *seconds = cupid_wtime() - t0;
  *out = ksp;
  ksp = NULL;
cleanup:
  KSPDestroy(&ksp);
  return st;
}

/* Solve with a set-up KSP (from x when guess, else from 0), check the reason and the true
 * residual, fill info (info->time_factor is the caller's). */
static cupid_status krylov_run(KSP ksp, const ksp_tolerances *tol, Vec b, Vec x, int guess,
                               cupid_solve_info *info) {
  cupid_status st = CUPID_SUCCESS;
  Mat A, P;
  PC pc;
  Vec r = NULL;
  PTRY(KSPGetOperators(ksp, &A, &P));
  PTRY(KSPGetPC(ksp, &pc));
  PTRY(KSPSetTolerances(ksp, tol->rtol, tol->atol, tol->dtol, tol->maxit));
  PTRY(KSPSetInitialGuessNonzero(ksp, guess ? PETSC_TRUE : PETSC_FALSE));
  double t1 = cupid_wtime();
  PTRY(KSPSolve(ksp, b, x));
  double t2 = cupid_wtime();

  KSPConvergedReason reason;
  PetscInt its;
  PTRY(KSPGetConvergedReason(ksp, &reason));
  PTRY(KSPGetIterationNumber(ksp, &its));
  KSPType kt;
  PCType pt;
  PTRY(KSPGetType(ksp, &kt));
  PTRY(PCGetType(pc, &pt));
  snprintf(info->ksp_type, sizeof info->ksp_type, "%s", kt ? kt : "?");
  snprintf(info->pc_type, sizeof info->pc_type, "%s", pt ? pt : "?");
  snprintf(info->converged_reason, sizeof info->converged_reason, "%s", KSPConvergedReasons[reason]);
  info->iterations = (int)its;
  info->time_solve = t2 - t1;
  if (reason < 0) {
    st = CUPID_ERROR(CUPID_ERR_NUMERIC,
                     "the PETSc solve did not converge: %s after %d iterations (KSP %s, PC %s); "
                     "try other -ksp_type / -pc_type options, or --solver direct",
                     KSPConvergedReasons[reason], (int)its, info->ksp_type, info->pc_type);
    goto cleanup;
  }
  /* The true residual: a recurrence residual can drift from it (CG on ill-conditioned systems).
   * Up to CUPID_PETSC_REFINEMENTS restarts from x recompute r = b - A x exactly (iterative
   * refinement); a residual still above the limit is accepted only at a normwise backward error
   * below 1e-12 (assembled operators: as good as the matrix allows, cf. the direct solve's 1e-10). */
  PetscReal rtol, atol, dtol;
  PetscInt maxit;
  PTRY(KSPGetTolerances(ksp, &rtol, &atol, &dtol, &maxit));
  double limit = fmax(100.0 * rtol, 1e-10);
  PTRY(VecDuplicate(b, &r));
  for (int pass = 0;; pass++) {
    CUPID_TRY(true_residual(A, P, b, x, r, info));
    if (info->residual <= limit || pass == CUPID_PETSC_REFINEMENTS) break;
    if (!strcmp(info->ksp_type, KSPPREONLY)) break; /* a direct solve: no restart from x */
    /* From x, KSP's rtol would be relative to the (small) residual of x: aim at the same
     * absolute target as the first solve instead. */
    PetscReal bnorm;
    PTRY(VecNorm(b, NORM_2, &bnorm));
    PTRY(KSPSetTolerances(ksp, 0.0, fmax(atol, 0.5 * rtol * bnorm), dtol, maxit));
    PTRY(KSPSetInitialGuessNonzero(ksp, PETSC_TRUE));
    PTRY(KSPSolve(ksp, b, x));
    PTRY(KSPGetConvergedReason(ksp, &reason));
    PTRY(KSPGetIterationNumber(ksp, &its));
    info->iterations += (int)its;
    if (reason < 0) break;
  }
  info->time_solve = cupid_wtime() - t1;
  if (info->residual > limit && !(A == P && info->backward_error <= 1e-12)) {
    st = CUPID_ERROR(CUPID_ERR_NUMERIC,
                     "the PETSc solve stopped (%s, %d iterations, %d restarts) but the true "
                     "relative residual is %.3e > %.1e (backward error %.1e): the system is "
                     "singular or badly conditioned (check the constraints; thin-walled beams "
                     "solve better with --solver direct), or the tolerance too loose",
                     KSPConvergedReasons[reason], info->iterations, CUPID_PETSC_REFINEMENTS,
                     info->residual, limit, info->backward_error);
    goto cleanup;
  }
cleanup:
  VecDestroy(&r);
  return st;
}

/* A one-off solve: krylov_create, krylov_run from 0. */
static cupid_status krylov_solve(Mat A, Mat P, Vec b, Vec x, const solver_defaults *def,
                                 cupid_solve_info *info) {
  KSP ksp = NULL;
  ksp_tolerances tol;
  double setup = 0.0;
  CUPID_CALL(krylov_create(A, P, def, &ksp, &tol, &setup));
  cupid_status st = krylov_run(ksp, &tol, b, x, 0, info);
  info->time_factor = setup;
  KSPDestroy(&ksp);
  return st;
}

/* The full solution on every rank. */
static cupid_status gather(Vec x, cupid_int n, double *u) {
  cupid_status st = CUPID_SUCCESS;
  VecScatter sc = NULL;
  Vec all = NULL;
  const PetscScalar *a;
  PTRY(VecScatterCreateToAll(x, &sc, &all));
  PTRY(VecScatterBegin(sc, x, all, INSERT_VALUES, SCATTER_FORWARD));
  PTRY(VecScatterEnd(sc, x, all, INSERT_VALUES, SCATTER_FORWARD));
  PTRY(VecGetArrayRead(all, &a));
  memcpy(u, a, (size_t)n * sizeof *u);
  PTRY(VecRestoreArrayRead(all, &a));
cleanup:
  VecScatterDestroy(&sc);
  VecDestroy(&all);
  return st;
}

static cupid_status check_sizes(cupid_int n) {
  CUPID_CHECK(n < (cupid_int)PETSC_MAX_INT / 4, CUPID_ERR_UNSUPPORTED,
              "%lld equations exceed this PETSc's 32-bit indices (PetscInt); use a PETSc built "
              "with 64-bit indices (Debian libpetsc64-real-dev)", (long long)n);
  CUPID_CHECK(g_initialized, CUPID_ERR_INTERNAL, "PETSc is not initialised");
  return CUPID_SUCCESS;
}

static void info_begin(cupid_solve_info *info, cupid_int n_free) {
  memset(info, 0, sizeof *info);
  info->method = "petsc";
  info->n = n_free;
  info->failed_dof = -1;
  info->ranks = cupid_petsc_size();
}

/* ------------------------------------------------------------------- the assembled path */

/* Insert the owned rows of K (Dirichlet rows -> s * identity, fixed columns -> b) into A. */
static cupid_status fill_rows(const cupid_csr_t *K, const cupid_dirichlet_t *bc, double s,
                              const double *f, cupid_int first, cupid_int last, Mat A, Vec b) {
  cupid_status st = CUPID_SUCCESS;
  int bs = K->bs;
  cupid_int maxlen = 0;
  for (cupid_int br = first / bs; br < (last + bs - 1) / bs; br++)
    if (K->rowptr[br + 1] - K->rowptr[br] > maxlen) maxlen = K->rowptr[br + 1] - K->rowptr[br];
  PetscInt *cols = NULL;
  PetscScalar *vals = NULL;
  CUPID_TRY(cupid_malloc((size_t)(maxlen * bs + 1), sizeof *cols, "PETSc row columns", &cols));
  CUPID_TRY(cupid_malloc((size_t)(maxlen * bs + 1), sizeof *vals, "PETSc row values", &vals));
  for (cupid_int row = first; row < last; row++) {
    PetscInt prow = (PetscInt)row;
    double rhs = f ? f[row] : 0.0;
    if (bc && bc->fixed[row]) {
      PetscScalar v = s;
      PTRY(MatSetValues(A, 1, &prow, 1, &prow, &v, INSERT_VALUES));
      PTRY(VecSetValue(b, prow, s * bc->value[row], INSERT_VALUES));
      continue;
    }
    cupid_int br = row / bs, a = row % bs;
    PetscInt n = 0;
    for (cupid_int k = K->rowptr[br]; k < K->rowptr[br + 1]; k++)
      for (int c = 0; c < bs; c++) {
        cupid_int col = K->col[k] * bs + c;
        double v = K->val[k * bs * bs + a * bs + c];
        if (bc && bc->fixed[col]) {
          rhs -= v * bc->value[col];
        } else {
          cols[n] = (PetscInt)col;
          vals[n++] = v;
        }
      }
    PTRY(MatSetValues(A, 1, &prow, n, cols, vals, INSERT_VALUES));
    PTRY(VecSetValue(b, prow, rhs, INSERT_VALUES));
  }
cleanup:
  cupid_free(&cols);
  cupid_free(&vals);
  return st;
}

/* Non-zeros per owned row, split into the diagonal and off-diagonal blocks of MPIAIJ. */
static cupid_status count_rows(const cupid_csr_t *K, const cupid_dirichlet_t *bc, cupid_int first,
                               cupid_int last, PetscInt *dnz, PetscInt *onz) {
  int bs = K->bs;
  for (cupid_int row = first; row < last; row++) {
    PetscInt d = 0, o = 0;
    if (bc && bc->fixed[row]) {
      d = 1;
    } else {
      cupid_int br = row / bs;
      for (cupid_int k = K->rowptr[br]; k < K->rowptr[br + 1]; k++)
        for (int c = 0; c < bs; c++) {
          cupid_int col = K->col[k] * bs + c;
          if (bc && bc->fixed[col]) continue;
          if (col >= first && col < last) d++;
          else o++;
        }
    }
    dnz[row - first] = d;
    onz[row - first] = o;
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_petsc_solve(const cupid_csr_t *K, cupid_matrix_kind kind, const double *f,
                               const cupid_dirichlet_t *bc, double *u,
                               const cupid_petsc_options *opts, cupid_solve_info *info) {
  cupid_solve_info local;
  if (!info) info = &local;
  CUPID_CHECK(K && u && K->nrows == K->ncols, CUPID_ERR_ARGUMENT, "square matrix and u required");
  cupid_int n = K->nrows * K->bs;
  CUPID_CALL(check_sizes(n));
  info_begin(info, bc ? bc->n_free : n);
  cupid_status st = CUPID_SUCCESS;
  int bs = n % 3 == 0 ? 3 : 1;
  cupid_int first, last;
  owned_rows(n, bs, &first, &last);
  cupid_int nloc = last - first;
  Mat A = NULL;
  Vec b = NULL, x = NULL;
  PetscInt *dnz = NULL, *onz = NULL;
  double *diag = NULL;
  CUPID_TRY(cupid_calloc((size_t)nloc + 1, sizeof *dnz, "PETSc preallocation", &dnz));
  CUPID_TRY(cupid_calloc((size_t)nloc + 1, sizeof *onz, "PETSc preallocation", &onz));
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *diag, "diagonal", &diag));
  CUPID_TRY(cupid_csr_diagonal(K, diag));
  double s = identity_scale(diag, n, bc);
  CUPID_TRY(count_rows(K, bc, first, last, dnz, onz));

  double t0 = cupid_wtime();
  PTRY(MatCreate(PETSC_COMM_WORLD, &A));
  PTRY(MatSetSizes(A, (PetscInt)nloc, (PetscInt)nloc, (PetscInt)n, (PetscInt)n));
  PTRY(MatSetType(A, MATAIJ)); /* AIJ + block size, not BAIJ: GAMG in 3.18 (dependencies.md) */
  PTRY(MatSetBlockSize(A, bs));
  PTRY(MatSeqAIJSetPreallocation(A, 0, dnz));
  PTRY(MatMPIAIJSetPreallocation(A, 0, dnz, 0, onz));
  PTRY(MatSetOption(A, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  if (kind == CUPID_MATRIX_SPD) PTRY(MatSetOption(A, MAT_SYMMETRIC, PETSC_TRUE));
  PTRY(MatCreateVecs(A, &x, &b));
  CUPID_TRY(fill_rows(K, bc, s, f, first, last, A, b));
  PTRY(MatAssemblyBegin(A, MAT_FINAL_ASSEMBLY));
  PTRY(MatAssemblyEnd(A, MAT_FINAL_ASSEMBLY));
  PTRY(VecAssemblyBegin(b));
  PTRY(VecAssemblyEnd(b));
  if (opts && opts->coords && 3 * opts->n_coord_nodes == n && bs == 3)
    CUPID_TRY(set_rigid_body(A, opts->coords, first, last));
  MatInfo mi;
  PTRY(MatGetInfo(A, MAT_GLOBAL_SUM, &mi));
  info->nnz_matrix = (cupid_int)mi.nz_used;
  double t_assemble = cupid_wtime() - t0;

  /* SPD: CG + GAMG. Eq. 38 (fictitious nodes) is non-symmetric and its fictitious rows are
   * interpolation constraints, not elliptic: GMRES + block Jacobi/ILU(0) (docs/scale.md). */
  solver_defaults def = kind == CUPID_MATRIX_SPD
                            ? (solver_defaults){KSPCG, PCGAMG, 0}
                            : (solver_defaults){KSPGMRES, PCBJACOBI, 200};
  CUPID_TRY(krylov_solve(A, A, b, x, &def, info));
  info->time_factor += t_assemble;
  CUPID_TRY(gather(x, n, u));
cleanup:
  MatDestroy(&A);
  VecDestroy(&b);
  VecDestroy(&x);
  cupid_free(&dnz);
  cupid_free(&onz);
  cupid_free(&diag);
  return st;
}

/* ------------------------------------------------------------------ the matrix-free path
 *
 * Arrays are local to the grid: a whole grid on every rank (replicated model) or one slab of
 * z layers and its halo per rank (issue 6; cupid_pd_grid_partition). Local DOF d is global DOF
 * goff + d; this rank owns the local DOFs [first, last) (a whole grid: an even split). */

typedef struct {
  const cupid_node_operator *op;
  const cupid_dirichlet_t *bc; /* local DOFs */
  double s;               /* identity-row scale */
  cupid_int goff;         /* global DOF of local DOF 0 */
  cupid_int first, last;  /* owned local DOFs (3 per node) */
  cupid_int lo, hi;       /* dependency range (local nodes) */
  VecScatter halo;        /* global x -> the dependency range */
  Vec xdep;               /* sequential, 3 (hi - lo) */
  double *work;           /* local DOFs: x with the dependency range filled, fixed DOFs zero */
} shell_ctx;

/* y = K x on the owned rows, fixed rows and columns replaced by s * identity (symmetric). */
static PetscErrorCode shell_mult(Mat A, Vec x, Vec y) {
  shell_ctx *c;
  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(A, &c));
  PetscCall(VecScatterBegin(c->halo, x, c->xdep, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(c->halo, x, c->xdep, INSERT_VALUES, SCATTER_FORWARD));
  const PetscScalar *xd, *xl;
  PetscScalar *yl;
  PetscCall(VecGetArrayRead(c->xdep, &xd));
  cupid_int d0 = 3 * c->lo, nd = 3 * (c->hi - c->lo);
  const unsigned char *fixed = c->bc ? c->bc->fixed : NULL;
#pragma omp parallel for schedule(static)
  for (cupid_int k = 0; k < nd; k++) c->work[d0 + k] = (fixed && fixed[d0 + k]) ? 0.0 : xd[k];
  PetscCall(VecRestoreArrayRead(c->xdep, &xd));
  PetscCall(VecGetArray(y, &yl));
  if (c->op->apply_range(c->op, c->first / 3, c->last / 3, c->work, yl) != CUPID_SUCCESS)
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "the node operator's product failed");
  if (fixed) {
    PetscCall(VecGetArrayRead(x, &xl));
    for (cupid_int d = c->first; d < c->last; d++)
      if (fixed[d]) yl[d - c->first] = c->s * xl[d - c->first];
    PetscCall(VecRestoreArrayRead(x, &xl));
  }
  PetscCall(VecRestoreArray(y, &yl));
  PetscFunctionReturn(0);
}

/* Halo exchange: a scatter of the global DOFs of the dependency range into a sequential
 * vector. */
static cupid_status make_halo(Vec x, shell_ctx *c) {
  cupid_status st = CUPID_SUCCESS;
  IS from = NULL;
  PetscInt nd = (PetscInt)(3 * (c->hi - c->lo));
  PTRY(VecCreateSeq(PETSC_COMM_SELF, nd, &c->xdep));
  PTRY(ISCreateStride(PETSC_COMM_SELF, nd, (PetscInt)(c->goff + 3 * c->lo), 1, &from));
  PTRY(VecScatterCreate(x, from, c->xdep, NULL, &c->halo));
cleanup:
  ISDestroy(&from);
  return st;
}

/* Rows per chunk of the preconditioner assembly: the bond-based rows are built and copied into
 * PETSc a chunk at a time, so cupid's CSR never coexists whole with PETSc's matrix (at 10^6
 * nodes each is ~2 GB). */
#define PC_CHUNK_NODES 32768

/* One pass over the owned rows of the bond-based stiffness, chunk by chunk: count the
 * non-zeros of each local row into dnz/onz and sum the free diagonal into diag (P NULL), or
 * insert them into P. Dirichlet rows and columns eliminated as in the operator (rows:
 * s * identity). */
static cupid_status pc_pass(double radius, const shell_ctx *c, double s, PetscInt *dnz,
                            PetscInt *onz, double diag[2], Mat P) {
  cupid_status st = CUPID_SUCCESS;
  cupid_csr Kr = NULL;
  PetscInt *cols = NULL;
  PetscScalar *vals = NULL;
  const unsigned char *fixed = c->bc ? c->bc->fixed : NULL;
  cupid_int cap = 0;
  for (cupid_int n0 = c->first / 3; n0 < c->last / 3; n0 += PC_CHUNK_NODES) {
    cupid_int n1 = n0 + PC_CHUNK_NODES < c->last / 3 ? n0 + PC_CHUNK_NODES : c->last / 3;
    CUPID_TRY(c->op->preconditioner_rows(c->op, radius, n0, n1, &Kr));
    for (cupid_int r = 0; r < Kr->nrows; r++) {
      cupid_int len = 3 * (Kr->rowptr[r + 1] - Kr->rowptr[r]) + 1;
      if (P && len > cap) {
        cupid_free(&cols);
        cupid_free(&vals);
        CUPID_TRY(cupid_malloc((size_t)len, sizeof *cols, "PETSc row columns", &cols));
        CUPID_TRY(cupid_malloc((size_t)len, sizeof *vals, "PETSc row values", &vals));
        cap = len;
      }
      for (int a = 0; a < 3; a++) {
        cupid_int row = 3 * (n0 + r) + a; /* local */
        PetscInt grow = (PetscInt)(c->goff + row), m = 0;
        if (fixed && fixed[row]) {
          if (P) {
            PetscScalar v = s;
            PTRY(MatSetValues(P, 1, &grow, 1, &grow, &v, INSERT_VALUES));
          } else {
            dnz[row - c->first] = 1;
          }
          continue;
        }
        for (cupid_int k = Kr->rowptr[r]; k < Kr->rowptr[r + 1]; k++)
          for (int b = 0; b < 3; b++) {
            cupid_int col = 3 * Kr->col[k] + b;
            if (fixed && fixed[col]) continue;
            if (P) {
              cols[m] = (PetscInt)(c->goff + col);
              vals[m++] = Kr->val[9 * k + 3 * a + b];
            } else if (col >= c->first && col < c->last) {
              dnz[row - c->first]++;
              if (col == row) diag[0] += fabs(Kr->val[9 * k + 3 * a + b]), diag[1] += 1;
            } else {
              onz[row - c->first]++;
            }
          }
        if (P) PTRY(MatSetValues(P, 1, &grow, m, cols, vals, INSERT_VALUES));
      }
    }
    cupid_csr_destroy(&Kr);
  }
cleanup:
  cupid_csr_destroy(&Kr);
  cupid_free(&cols);
  cupid_free(&vals);
  return st;
}

/* The preconditioner matrix: owned rows of the short-range bond-based stiffness, its identity
 * rows scaled like the operator's (same ratio to the diagonal: the mean free diagonal of the
 * bond-based matrix over all ranks). */
static cupid_status pc_matrix(double radius, const shell_ctx *c, cupid_int n, Mat *P) {
  cupid_status st = CUPID_SUCCESS;
  PetscInt *dnz = NULL, *onz = NULL;
  cupid_int nloc = c->last - c->first;
  double diag[2] = {0.0, 0.0};
  CUPID_TRY(cupid_calloc((size_t)nloc + 1, sizeof *dnz, "PETSc preallocation", &dnz));
  CUPID_TRY(cupid_calloc((size_t)nloc + 1, sizeof *onz, "PETSc preallocation", &onz));
  CUPID_TRY(pc_pass(radius, c, 0.0, dnz, onz, diag, NULL));
  MPI_Allreduce(MPI_IN_PLACE, diag, 2, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
  PTRY(MatCreate(PETSC_COMM_WORLD, P));
  PTRY(MatSetSizes(*P, (PetscInt)nloc, (PetscInt)nloc, (PetscInt)n, (PetscInt)n));
  PTRY(MatSetType(*P, MATAIJ));
  PTRY(MatSetBlockSize(*P, 3));
  PTRY(MatSeqAIJSetPreallocation(*P, 0, dnz));
  PTRY(MatMPIAIJSetPreallocation(*P, 0, dnz, 0, onz));
  PTRY(MatSetOption(*P, MAT_SYMMETRIC, PETSC_TRUE));
  CUPID_TRY(pc_pass(radius, c, diag[1] > 0 ? diag[0] / diag[1] : 1.0, NULL, NULL, NULL, *P));
  PTRY(MatAssemblyBegin(*P, MAT_FINAL_ASSEMBLY));
  PTRY(MatAssemblyEnd(*P, MAT_FINAL_ASSEMBLY));
cleanup:
  cupid_free(&dnz);
  cupid_free(&onz);
  return st;
}

/* The mean |diagonal| of the operator over the free owned DOFs of all ranks. */
static cupid_status operator_scale(const cupid_node_operator *op, cupid_int nodes,
                                   const shell_ctx *c, double *s) {
  double *blocks = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_malloc((size_t)(9 * nodes), sizeof *blocks, "operator diagonal", &blocks));
  CUPID_TRY(op->diagonal(op, blocks));
  double sc[2] = {0.0, 0.0};
  for (cupid_int d = c->first; d < c->last; d++) {
    double v = blocks[9 * (d / 3) + 4 * (d % 3)];
    if (!(c->bc && c->bc->fixed[d]) && v != 0.0) sc[0] += fabs(v), sc[1] += 1;
  }
  MPI_Allreduce(MPI_IN_PLACE, sc, 2, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
  *s = sc[1] > 0 ? sc[0] / sc[1] : 1.0;
cleanup:
  cupid_free(&blocks);
  return st;
}

/* The solution on the grid's local DOFs: a whole grid gets every DOF; a slab its owned DOFs
 * and the dependency range (what K u and the stress of the owned nodes read). */
static cupid_status local_solution(Vec x, const shell_ctx *c, int slab, cupid_int n, double *u) {
  cupid_status st = CUPID_SUCCESS;
  if (!slab) return gather(x, n, u);
  const PetscScalar *a;
  PTRY(VecScatterBegin(c->halo, x, c->xdep, INSERT_VALUES, SCATTER_FORWARD));
  PTRY(VecScatterEnd(c->halo, x, c->xdep, INSERT_VALUES, SCATTER_FORWARD));
  PTRY(VecGetArrayRead(c->xdep, &a));
  memcpy(u + 3 * c->lo, a, (size_t)(3 * (c->hi - c->lo)) * sizeof *u);
  PTRY(VecRestoreArrayRead(c->xdep, &a));
cleanup:
  return st;
}

/* A kept matrix-free solve (solvers.h, cupid_petsc_nodes_solver): the operator (a copy of
 * the caller's description), the shell, the preconditioner matrix and the set-up KSP. */
struct cupid_petsc_nodes_solver_private {
  cupid_node_operator op;
  shell_ctx c;
  int slab;
  cupid_int n;        /* global DOFs */
  Mat A, P;
  Vec b, x;
  KSP ksp;
  ksp_tolerances tol;
  double setup_s;     /* given to the first solve's info (time_factor) */
  double nnz_p;
  double *uc, *kuc;   /* the prescribed values, their lifted load (owned rows) */
};

cupid_status cupid_petsc_nodes_solver_create(const cupid_node_operator *op,
                                             const cupid_dirichlet_t *bc,
                                             cupid_petsc_nodes_solver *out) {
  *out = NULL;
  const cupid_pd_grid_partition part = op->part;
  const int slab = part.parts > 1;
  const cupid_int nodes = op->nodes, nl = 3 * nodes, n = 3 * part.global_nodes;
  CUPID_CHECK(op->dimension == 3, CUPID_ERR_UNSUPPORTED,
              "the matrix-free PETSc path needs a 3D grid");
  CUPID_CHECK(!slab || part.parts == cupid_petsc_size(), CUPID_ERR_ARGUMENT,
              "a grid of %d slabs on %d MPI ranks", part.parts, cupid_petsc_size());
  CUPID_CALL(check_sizes(n));
  cupid_petsc_nodes_solver S = NULL;
  CUPID_CALL(cupid_calloc(1, sizeof *S, "matrix-free solver", &S));
  cupid_status st = CUPID_SUCCESS;
  double t0 = cupid_wtime();
  S->op = *op;
  S->slab = slab;
  S->n = n;
  shell_ctx *c = &S->c;
  *c = (shell_ctx){.op = &S->op, .bc = bc};
  if (slab) {
    c->goff = 3 * part.first_global;
    c->first = 3 * part.owned_first;
    c->last = 3 * part.owned_last;
  } else {
    owned_rows(n, 3, &c->first, &c->last);
  }
  CUPID_TRY(op->dependency_range(op, c->first / 3, c->last / 3, &c->lo, &c->hi));
  CUPID_TRY(cupid_calloc((size_t)nl, sizeof *c->work, "matrix-free work vector", &c->work));
  CUPID_TRY(cupid_calloc((size_t)nl, sizeof *S->uc, "prescribed displacements", &S->uc));
  CUPID_TRY(cupid_calloc((size_t)(c->last - c->first + 1), sizeof *S->kuc, "lifted load", &S->kuc));
  CUPID_TRY(operator_scale(op, nodes, c, &c->s));

  PTRY(MatCreateShell(PETSC_COMM_WORLD, (PetscInt)(c->last - c->first),
                      (PetscInt)(c->last - c->first), (PetscInt)n, (PetscInt)n, c, &S->A));
  PTRY(MatShellSetOperation(S->A, MATOP_MULT, (void (*)(void))shell_mult));
  PTRY(MatSetBlockSize(S->A, 3));
  PTRY(MatSetOption(S->A, MAT_SYMMETRIC, PETSC_TRUE));
  PTRY(MatCreateVecs(S->A, &S->x, &S->b));
  CUPID_TRY(make_halo(S->x, c));

  PetscReal radius = 1.5;
  PetscBool set;
  PTRY(PetscOptionsGetReal(NULL, NULL, "-cupid_pc_radius", &radius, &set));
  CUPID_TRY(pc_matrix(radius * op->spacing, c, n, &S->P));
  CUPID_TRY(set_rigid_body(S->P, op->coords, c->first, c->last));
  MatInfo mi;
  PTRY(MatGetInfo(S->P, MAT_GLOBAL_SUM, &mi));
  S->nnz_p = mi.nz_used;
  solver_defaults def = {KSPCG, PCGAMG, 0};
  double t_pc = 0.0;
  CUPID_TRY(krylov_create(S->A, S->P, &def, &S->ksp, &S->tol, &t_pc));
  /* the preconditioner is kept as the operator changes (bonds break, DOFs are held) */
  PTRY(KSPSetReusePreconditioner(S->ksp, PETSC_TRUE));
  S->setup_s = cupid_wtime() - t0;
  *out = S;
  S = NULL;
cleanup:
  cupid_petsc_nodes_solver_destroy(&S);
  return st;
}

cupid_status cupid_petsc_nodes_solver_solve(cupid_petsc_nodes_solver S, const double *f, int guess,
                                            double *u, cupid_solve_info *info) {
  cupid_solve_info local;
  if (!info) info = &local;
  CUPID_CHECK(S && u, CUPID_ERR_ARGUMENT, "cupid_petsc_nodes_solver_solve needs a solver and u");
  shell_ctx *c = &S->c;
  const cupid_dirichlet_t *bc = c->bc;
  const cupid_int nl = 3 * S->op.nodes;
  double n_free = 0.0;
  for (cupid_int d = c->first; d < c->last; d++) n_free += !(bc && bc->fixed[d]);
  MPI_Allreduce(MPI_IN_PLACE, &n_free, 1, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
  info_begin(info, (cupid_int)n_free);
  info->matrix_free = 1;
  cupid_status st = CUPID_SUCCESS;

  /* Right-hand side: f - K u_c on free DOFs (u_c the prescribed values), s * value on fixed;
   * the first guess u's owned values (the prescribed ones on fixed DOFs), or 0. */
  int lifted = 0;
  for (cupid_int d = 0; d < nl; d++) {
    S->uc[d] = bc && bc->fixed[d] ? bc->value[d] : 0.0;
    lifted |= S->uc[d] != 0.0;
  }
  lifted = cupid_petsc_max_int(lifted);
  if (lifted) CUPID_TRY(S->op.apply_range(&S->op, c->first / 3, c->last / 3, S->uc, S->kuc));
  PetscScalar *bl, *xl;
  PTRY(VecGetArray(S->b, &bl));
  PTRY(VecGetArray(S->x, &xl));
  for (cupid_int d = c->first; d < c->last; d++) {
    const int fx = bc && bc->fixed[d];
    bl[d - c->first] = fx ? c->s * bc->value[d] : (f ? f[d] : 0.0) - (lifted ? S->kuc[d - c->first] : 0.0);
    xl[d - c->first] = !guess ? 0.0 : fx ? bc->value[d] : u[d];
  }
  PTRY(VecRestoreArray(S->x, &xl));
  PTRY(VecRestoreArray(S->b, &bl));

  st = krylov_run(S->ksp, &S->tol, S->b, S->x, guess, info);
  info->time_factor = S->setup_s; /* the preconditioner's set-up: charged to the first solve */
  S->setup_s = 0.0;
  info->nnz_matrix = (cupid_int)S->nnz_p; /* of the preconditioner matrix */
  if (st != CUPID_SUCCESS && st != CUPID_ERR_NUMERIC) goto cleanup;
  /* a solve that failed leaves its last iterate: where it ran away shows what lost support */
  cupid_status st2 = local_solution(S->x, c, S->slab, S->n, u);
  if (st == CUPID_SUCCESS) st = st2;
cleanup:
  return st;
}

void cupid_petsc_nodes_solver_limit(cupid_petsc_nodes_solver S, int max_iterations) {
  if (S && max_iterations > 0 && max_iterations < S->tol.maxit) S->tol.maxit = max_iterations;
}

void cupid_petsc_nodes_solver_destroy(cupid_petsc_nodes_solver *S) {
  if (!S || !*S) return;
  cupid_petsc_nodes_solver s = *S;
  KSPDestroy(&s->ksp);
  MatDestroy(&s->A);
  MatDestroy(&s->P);
  VecDestroy(&s->b);
  VecDestroy(&s->x);
  VecScatterDestroy(&s->c.halo);
  VecDestroy(&s->c.xdep);
  cupid_free(&s->c.work);
  cupid_free(&s->uc);
  cupid_free(&s->kuc);
  cupid_free(S);
}

cupid_status cupid_petsc_solve_nodes(const cupid_node_operator *op, const double *f,
                                     const cupid_dirichlet_t *bc, double *u,
                                     cupid_solve_info *info) {
  cupid_petsc_nodes_solver S = NULL;
  CUPID_CALL(cupid_petsc_nodes_solver_create(op, bc, &S));
  cupid_status st = cupid_petsc_nodes_solver_solve(S, f, 0, u, info);
  cupid_petsc_nodes_solver_destroy(&S);
  return st;
}

#else /* !CUPID_HAVE_PETSC */

#define NO_PETSC                                                                               \
  CUPID_ERROR(CUPID_ERR_UNSUPPORTED,                                                           \
              "cupid was built without PETSc: rebuild with scripts/build.sh --with-petsc")

cupid_status cupid_petsc_initialize(int argc, char **argv) { return NO_PETSC; }
int cupid_petsc_initialized(void) { return 0; }
void cupid_petsc_finalize(void) {}
int cupid_petsc_rank(void) { return 0; }
int cupid_petsc_size(void) { return 1; }
int cupid_petsc_max_int(int v) { return v; }
int cupid_petsc_has_option(const char *name) {
  (void)name;
  return 0;
}
void cupid_petsc_sum_doubles(double *v, int n) {
  (void)v;
  (void)n;
}
void cupid_petsc_max_doubles(double *v, int n) {
  (void)v;
  (void)n;
}
cupid_status cupid_petsc_gather_root(const double *local, cupid_int count, double *root) {
  if (count > 0) memcpy(root, local, (size_t)count * sizeof *root);
  return CUPID_SUCCESS;
}
void cupid_petsc_abort(int code) { exit(code); }

cupid_status cupid_petsc_halo_create(cupid_int n, cupid_int owned_first, cupid_int owned_last,
                                     cupid_int global_first, cupid_petsc_halo *out) {
  (void)n, (void)owned_first, (void)owned_last, (void)global_first, (void)out;
  return NO_PETSC;
}
cupid_status cupid_petsc_halo_update(cupid_petsc_halo h, double *x) {
  (void)h, (void)x;
  return NO_PETSC;
}
void cupid_petsc_halo_destroy(cupid_petsc_halo *h) { (void)h; }

cupid_status cupid_petsc_solve(const cupid_csr_t *K, cupid_matrix_kind kind, const double *f,
                               const cupid_dirichlet_t *bc, double *u,
                               const cupid_petsc_options *opts, cupid_solve_info *info) {
  return NO_PETSC;
}

cupid_status cupid_petsc_solve_nodes(const cupid_node_operator *op, const double *f,
                                     const cupid_dirichlet_t *bc, double *u,
                                     cupid_solve_info *info) {
  return NO_PETSC;
}

cupid_status cupid_petsc_nodes_solver_create(const cupid_node_operator *op,
                                             const cupid_dirichlet_t *bc,
                                             cupid_petsc_nodes_solver *out) {
  (void)op, (void)bc;
  *out = NULL;
  return NO_PETSC;
}
cupid_status cupid_petsc_nodes_solver_solve(cupid_petsc_nodes_solver S, const double *f, int guess,
                                            double *u, cupid_solve_info *info) {
  (void)S, (void)f, (void)guess, (void)u, (void)info;
  return NO_PETSC;
}
void cupid_petsc_nodes_solver_limit(cupid_petsc_nodes_solver S, int max_iterations) {
  (void)S, (void)max_iterations;
}
void cupid_petsc_nodes_solver_destroy(cupid_petsc_nodes_solver *S) { (void)S; }

#endif
