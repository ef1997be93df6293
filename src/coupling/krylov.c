/* Krylov solve of the fictitious-node coupled system (paper 000 Eq. 38) on PETSc: GMRES (the
 * matrix is not symmetric) on the free DOFs, the operator a MATSHELL over the matrix-free
 * coupled operator (operator.c), the preconditioner built from the cheap matrix (Eq. 38 with a
 * short bond-based PD operator) by a PETSc PC: LU through UMFPACK by default (the cheap matrix
 * has ~19 blocks a PD row, so its factor is ~1/50 of the LPS one), ILU, GAMG or hypre on
 * request. Right preconditioning: GMRES minimises the true residual, so rtol is what the
 * caller gets. Dirichlet DOFs are eliminated: A_ff u_f = f_f - A_fc u_c. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "coupling_internal.h"
#include "cupid/coupling.h"
#include "cupid_config.h"

#if CUPID_HAVE_PETSC
#include <petscksp.h>

#define PCALL(expr)                                                                           \
  do {                                                                                        \
    PetscErrorCode ierr_ = (expr);                                                            \
    if (ierr_) {                                                                              \
      st = CUPID_ERROR(CUPID_ERR_NUMERIC, "PETSc error %d in %s", (int)ierr_, #expr);         \
      goto cleanup;                                                                           \
    }                                                                                         \
  } while (0)

typedef struct {
  cupid_coupling_operator A;
  cupid_int n, n_free;
  const cupid_int *gidx; /* free -> global DOF */
  double *xf, *yf;       /* full-length work vectors */
} shell_ctx;

/* y_f = (A [x_f ; 0])_f. */
static PetscErrorCode shell_mult(Mat M, Vec x, Vec y) {
  shell_ctx *s;
  const PetscScalar *xa;
  PetscScalar *ya;
  PetscCall(MatShellGetContext(M, &s));
  PetscCall(VecGetArrayRead(x, &xa));
  memset(s->xf, 0, (size_t)s->n * sizeof *s->xf);
  for (cupid_int k = 0; k < s->n_free; k++) s->xf[s->gidx[k]] = xa[k];
  PetscCall(VecRestoreArrayRead(x, &xa));
  if (cupid_coupling_operator_apply(s->A, s->xf, s->yf) != CUPID_SUCCESS)
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "coupled operator: %s", cupid_error_message());
  PetscCall(VecGetArray(y, &ya));
  for (cupid_int k = 0; k < s->n_free; k++) ya[k] = s->yf[s->gidx[k]];
  PetscCall(VecRestoreArray(y, &ya));
  return 0;
}

/* The free-free block of the block-CSR P as a PETSc AIJ matrix (scalar rows). */
static cupid_status free_block_aij(const cupid_csr_t *P, const cupid_dirichlet_t *bc, Mat *out) {
  cupid_status st = CUPID_SUCCESS;
  PetscInt *nnz = NULL, *cols = NULL;
  PetscScalar *vals = NULL;
  Mat M = NULL;
  const int bs = P->bs;
  cupid_int n_free = bc->n_free, maxrow = 0;
  CUPID_TRY(cupid_calloc((size_t)n_free + 1, sizeof *nnz, "preconditioner row counts", &nnz));
  for (cupid_int R = 0; R < P->nrows; R++) {
    cupid_int len = 0;
    for (cupid_int k = P->rowptr[R]; k < P->rowptr[R + 1]; k++)
      for (int b = 0; b < bs; b++) len += bc->free_index[P->col[k] * bs + b] >= 0;
    for (int a = 0; a < bs; a++) {
      cupid_int fi = bc->free_index[R * bs + a];
      if (fi >= 0) nnz[fi] = (PetscInt)len;
    }
    if (len > maxrow) maxrow = len;
  }
  CUPID_TRY(cupid_malloc((size_t)maxrow + 1, sizeof *cols, "preconditioner row", &cols));
  CUPID_TRY(cupid_malloc((size_t)maxrow + 1, sizeof *vals, "preconditioner row", &vals));
  PCALL(MatCreateSeqAIJ(PETSC_COMM_SELF, (PetscInt)n_free, (PetscInt)n_free, 0, nnz, &M));
  for (cupid_int R = 0; R < P->nrows; R++)
    for (int a = 0; a < bs; a++) {
      cupid_int fi = bc->free_index[R * bs + a];
      if (fi < 0) continue;
      PetscInt len = 0;
      for (cupid_int k = P->rowptr[R]; k < P->rowptr[R + 1]; k++)
        for (int b = 0; b < bs; b++) {
          cupid_int fc = bc->free_index[P->col[k] * bs + b];
          if (fc < 0) continue;
          cols[len] = (PetscInt)fc;
          vals[len++] = P->val[(size_t)k * bs * bs + a * bs + b];
        }
      PetscInt row = (PetscInt)fi;
      PCALL(MatSetValues(M, 1, &row, len, cols, vals, INSERT_VALUES));
    }
  /* Block size 3 (GAMG's default near null space: the translations) when every node is
   * free or fixed as a whole. */
  int whole = 1;
  for (cupid_int d = 0; d < bc->n && whole; d += 3)
    whole = bc->fixed[d] == bc->fixed[d + 1] && bc->fixed[d] == bc->fixed[d + 2];
  if (whole && bs == 3) PCALL(MatSetBlockSize(M, 3));
  PCALL(MatAssemblyBegin(M, MAT_FINAL_ASSEMBLY));
  PCALL(MatAssemblyEnd(M, MAT_FINAL_ASSEMBLY));
  *out = M;
  M = NULL;
cleanup:
  if (M) MatDestroy(&M);
  cupid_free(&nnz);
  cupid_free(&cols);
  cupid_free(&vals);
  return st;
}

cupid_status cupid_coupling_krylov_solve(const cupid_coupling_operator A, const cupid_csr_t *P,
                                         const cupid_dirichlet_t *bc, const double *f, double *u,
                                         const cupid_coupling_krylov_options *opts,
                                         cupid_coupling_krylov_info *info) {
  cupid_status st = CUPID_SUCCESS;
  cupid_coupling_krylov_info inf;
  memset(&inf, 0, sizeof inf);
  cupid_int n = cupid_coupling_operator_size(A);
  CUPID_CHECK(bc->n == n && P->nrows * P->bs == n, CUPID_ERR_ARGUMENT,
              "operator (%lld DOFs), preconditioner (%lld) and conditions (%lld) differ",
              (long long)n, (long long)(P->nrows * P->bs), (long long)bc->n);
  PetscBool init = PETSC_FALSE;
  if (PetscInitialized(&init) || !init)
    CUPID_CHECK(PetscInitializeNoArguments() == 0, CUPID_ERR_UNSUPPORTED,
                "PETSc could not be initialised");
  cupid_int *gidx = NULL;
  double *xf = NULL, *yf = NULL;
  Mat S = NULL, Pm = NULL;
  Vec x = NULL, b = NULL;
  KSP ksp = NULL;
  IS is_pd = NULL, is_fe = NULL;
  PC pc;
  cupid_int n_free = bc->n_free;
  CUPID_TRY(cupid_malloc((size_t)n_free + 1, sizeof *gidx, "free DOFs", &gidx));
  CUPID_TRY(cupid_calloc((size_t)n, sizeof *xf, "work vector", &xf));
  CUPID_TRY(cupid_calloc((size_t)n, sizeof *yf, "work vector", &yf));
  for (cupid_int d = 0; d < n; d++)
    if (bc->free_index[d] >= 0) gidx[bc->free_index[d]] = d;
  shell_ctx ctx = {.A = A, .n = n, .n_free = n_free, .gidx = gidx, .xf = xf, .yf = yf};

  /* b_f = f_f - (A u_c)_f */
  for (cupid_int d = 0; d < n; d++) xf[d] = bc->fixed[d] ? bc->value[d] : 0.0;
  CUPID_TRY(cupid_coupling_operator_apply(A, xf, yf));
  PCALL(VecCreateSeq(PETSC_COMM_SELF, (PetscInt)n_free, &b));
  PCALL(VecDuplicate(b, &x));
  PetscScalar *ba;
  PCALL(VecGetArray(b, &ba));
  for (cupid_int k = 0; k < n_free; k++) ba[k] = f[gidx[k]] - yf[gidx[k]];
  PCALL(VecRestoreArray(b, &ba));
  PetscReal bnorm;
  PCALL(VecNorm(b, NORM_2, &bnorm));

  double t0 = cupid_wtime();
  PCALL(MatCreateShell(PETSC_COMM_SELF, (PetscInt)n_free, (PetscInt)n_free, (PetscInt)n_free,
                       (PetscInt)n_free, &ctx, &S));
  PCALL(MatShellSetOperation(S, MATOP_MULT, (void (*)(void))shell_mult));
  CUPID_TRY(free_block_aij(P, bc, &Pm));
  PCALL(KSPCreate(PETSC_COMM_SELF, &ksp));
  PCALL(KSPSetOperators(ksp, S, Pm));
  PCALL(KSPSetType(ksp, KSPGMRES));
  PCALL(KSPGMRESSetRestart(ksp, opts && opts->restart > 0 ? opts->restart : 200));
  PCALL(KSPSetPCSide(ksp, PC_RIGHT));
  PCALL(KSPSetTolerances(ksp, opts && opts->rtol > 0 ? opts->rtol : 1e-10, 1e-300, PETSC_DEFAULT,
                         opts && opts->max_it > 0 ? opts->max_it : 2000));
  PCALL(KSPGetPC(ksp, &pc));
  const char *pct = opts && opts->pc ? opts->pc : "lu";
  PCALL(PCSetType(pc, pct));
  if (!strcmp(pct, "lu") || !strcmp(pct, "ilu")) {
    const char *pkg = opts && opts->factor_package ? opts->factor_package
                                                   : (!strcmp(pct, "lu") ? "umfpack" : "petsc");
    PCALL(PCFactorSetMatSolverType(pc, pkg));
  }
  if (!strcmp(pct, "fieldsplit")) {
    /* Two fields: PD DOFs and FE DOFs (sub-solvers from -fieldsplit_pd_* / -fieldsplit_fe_*). */
    cupid_coupling_info ci;
    cupid_coupling_operator_get_info(A, &ci);
    cupid_int n_pd_free = 0;
    while (n_pd_free < n_free && gidx[n_pd_free] < 3 * ci.n_real_pd) n_pd_free++;
    PetscInt *idx = NULL;
    CUPID_TRY(cupid_malloc((size_t)n_free + 1, sizeof *idx, "field indices", &idx));
    for (cupid_int k = 0; k < n_free; k++) idx[k] = (PetscInt)k;
    PCALL(ISCreateGeneral(PETSC_COMM_SELF, (PetscInt)n_pd_free, idx, PETSC_COPY_VALUES, &is_pd));
    PCALL(ISCreateGeneral(PETSC_COMM_SELF, (PetscInt)(n_free - n_pd_free), idx + n_pd_free,
                          PETSC_COPY_VALUES, &is_fe));
    cupid_free(&idx);
    if (n_pd_free % 3 == 0) PCALL(ISSetBlockSize(is_pd, 3));
    PCALL(PCFieldSplitSetIS(pc, "pd", is_pd));
    PCALL(PCFieldSplitSetIS(pc, "fe", is_fe));
  }
  PCALL(KSPSetFromOptions(ksp));
  PCALL(KSPSetUp(ksp));
  PCALL(PCSetUp(pc));
  inf.time_setup = cupid_wtime() - t0;

  t0 = cupid_wtime();
  PCALL(KSPSolve(ksp, b, x));
  inf.time_solve = cupid_wtime() - t0;
  PetscInt its;
  KSPConvergedReason reason;
  PCALL(KSPGetIterationNumber(ksp, &its));
  PCALL(KSPGetConvergedReason(ksp, &reason));
  inf.iterations = (int)its;
  inf.converged = reason > 0;
  PCType used;
  PCALL(PCGetType(pc, &used));
  snprintf(inf.method, sizeof inf.method, "gmres+%s", used);

  /* u = [x_f ; u_c]; the true residual, recomputed. */
  const PetscScalar *xa;
  PCALL(VecGetArrayRead(x, &xa));
  for (cupid_int d = 0; d < n; d++) u[d] = bc->fixed[d] ? bc->value[d] : 0.0;
  for (cupid_int k = 0; k < n_free; k++) u[gidx[k]] = xa[k];
  PCALL(VecRestoreArrayRead(x, &xa));
  CUPID_TRY(cupid_coupling_operator_apply(A, u, yf));
  double r2 = 0.0, f2 = 0.0;
  for (cupid_int k = 0; k < n_free; k++) {
    double r = f[gidx[k]] - yf[gidx[k]];
    r2 += r * r;
    f2 += f[gidx[k]] * f[gidx[k]];
  }
  double scale = bnorm > 0 ? (double)bnorm : sqrt(f2);
  inf.residual = scale > 0 ? sqrt(r2) / scale : sqrt(r2);
  if (!inf.converged)
    st = CUPID_ERROR(CUPID_ERR_NUMERIC,
                     "GMRES (%s) did not converge: reason %d after %d iterations, relative "
                     "residual %.2e",
                     inf.method, (int)reason, inf.iterations, inf.residual);
cleanup:
  if (info) *info = inf;
  if (ksp) KSPDestroy(&ksp);
  if (is_pd) ISDestroy(&is_pd);
  if (is_fe) ISDestroy(&is_fe);
  if (S) MatDestroy(&S);
  if (Pm) MatDestroy(&Pm);
  if (x) VecDestroy(&x);
  if (b) VecDestroy(&b);
  cupid_free(&gidx);
  cupid_free(&xf);
  cupid_free(&yf);
  return st;
}

#else

cupid_status cupid_coupling_krylov_solve(const cupid_coupling_operator A, const cupid_csr_t *P,
                                         const cupid_dirichlet_t *bc, const double *f, double *u,
                                         const cupid_coupling_krylov_options *opts,
                                         cupid_coupling_krylov_info *info) {
  (void)A, (void)P, (void)bc, (void)f, (void)u, (void)opts;
  if (info) memset(info, 0, sizeof *info);
  return CUPID_ERROR(CUPID_ERR_UNSUPPORTED,
                     "the matrix-free coupled solve needs the PETSc engine: configure with "
                     "-DCUPID_WITH_PETSC=ON");
}

#endif
