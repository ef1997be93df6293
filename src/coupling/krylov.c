/* Krylov solve of a matrix-free coupled system on PETSc, on the free DOFs: the fictitious-node
 * system (paper 000 Eq. 38) by GMRES (not symmetric), the Arlequin system (paper 004 Eq. 18) by
 * CG (symmetric positive definite). The operator is a MATSHELL over a cupid_linear_operator
 * (operator.c, arlequin_operator.c); the preconditioner is built from the cheap twin (the same
 * system with a short bond-based PD operator) by a PETSc PC: by default an LU (UMFPACK on one
 * rank, MUMPS on several) for GMRES, a MUMPS Cholesky for CG (the twin has ~19 blocks a PD row,
 * so its factor is ~1/50 of the LPS one); ILU, GAMG or hypre on request. GMRES is right
 * preconditioned, so it minimises the true residual and rtol is what the caller gets; the true
 * residual is recomputed at the end either way. Dirichlet DOFs are eliminated:
 * A_ff u_f = f_f - A_fc u_c. On several MPI ranks (replicated model) the vectors, the rows of
 * the product and the preconditioner's rows are split over the ranks and the factor is MUMPS's
 * (parallel); every rank gets the whole solution. */
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

/* On several MPI ranks the model is replicated; each rank owns the free DOFs [f0, f1) of the
 * PETSc vectors and computes only their rows of the product (cupid_coupling_operator_apply_rows:
 * the PD rows of its range of extended nodes), from the gathered x. */
typedef struct {
  const cupid_linear_operator *A;
  cupid_int n, n_free, f0, f1;
  const cupid_int *gidx; /* free -> global DOF */
  double *xf, *yf;       /* full-length work vectors */
  VecScatter toall;      /* x -> xall, every free DOF on every rank */
  Vec xall;
} shell_ctx;

/* y_f = (A [x_f ; 0])_f on the owned rows. */
static PetscErrorCode shell_mult(Mat M, Vec x, Vec y) {
  shell_ctx *s;
  const PetscScalar *xa;
  PetscScalar *ya;
  PetscCall(MatShellGetContext(M, &s));
  PetscCall(VecScatterBegin(s->toall, x, s->xall, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(s->toall, x, s->xall, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGetArrayRead(s->xall, &xa));
  memset(s->xf, 0, (size_t)s->n * sizeof *s->xf);
  for (cupid_int k = 0; k < s->n_free; k++) s->xf[s->gidx[k]] = xa[k];
  PetscCall(VecRestoreArrayRead(s->xall, &xa));
  /* The owned rows only (free DOFs ascend with the global DOFs). */
  const cupid_int d0 = s->f1 > s->f0 ? s->gidx[s->f0] : 0,
                  d1 = s->f1 > s->f0 ? s->gidx[s->f1 - 1] + 1 : 0;
  cupid_status st = s->A->apply_rows ? s->A->apply_rows(s->A->ctx, s->xf, d0, d1, s->yf)
                                     : s->A->apply(s->A->ctx, s->xf, s->yf);
  if (st != CUPID_SUCCESS)
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "coupled operator: %s", cupid_error_message());
  PetscCall(VecGetArray(y, &ya));
  for (cupid_int k = s->f0; k < s->f1; k++) ya[k - s->f0] = s->yf[s->gidx[k]];
  PetscCall(VecRestoreArray(y, &ya));
  return 0;
}

/* The free-free block of the block-CSR P as a PETSc AIJ matrix (scalar rows), the owned rows
 * [f0, f1) of it on each rank. */
static cupid_status free_block_aij(const cupid_csr_t *P, const cupid_dirichlet_t *bc,
                                   cupid_int f0, cupid_int f1, Mat *out) {
  cupid_status st = CUPID_SUCCESS;
  PetscInt *dnz = NULL, *onz = NULL, *cols = NULL;
  PetscScalar *vals = NULL;
  Mat M = NULL;
  const int bs = P->bs;
  cupid_int n_free = bc->n_free, nloc = f1 - f0, maxrow = 0;
  CUPID_TRY(cupid_calloc((size_t)nloc + 1, sizeof *dnz, "preconditioner row counts", &dnz));
  CUPID_TRY(cupid_calloc((size_t)nloc + 1, sizeof *onz, "preconditioner row counts", &onz));
  for (cupid_int R = 0; R < P->nrows; R++) {
    cupid_int len = 0, din = 0;
    for (cupid_int k = P->rowptr[R]; k < P->rowptr[R + 1]; k++)
      for (int b = 0; b < bs; b++) {
        cupid_int fc = bc->free_index[P->col[k] * bs + b];
        len += fc >= 0;
        din += fc >= f0 && fc < f1;
      }
    for (int a = 0; a < bs; a++) {
      cupid_int fi = bc->free_index[R * bs + a];
      if (fi >= f0 && fi < f1) dnz[fi - f0] = (PetscInt)din, onz[fi - f0] = (PetscInt)(len - din);
    }
    if (len > maxrow) maxrow = len;
  }
  CUPID_TRY(cupid_malloc((size_t)maxrow + 1, sizeof *cols, "preconditioner row", &cols));
  CUPID_TRY(cupid_malloc((size_t)maxrow + 1, sizeof *vals, "preconditioner row", &vals));
  PCALL(MatCreate(PETSC_COMM_WORLD, &M));
  PCALL(MatSetSizes(M, (PetscInt)nloc, (PetscInt)nloc, (PetscInt)n_free, (PetscInt)n_free));
  PCALL(MatSetType(M, MATAIJ));
  PCALL(MatSeqAIJSetPreallocation(M, 0, dnz));
  PCALL(MatMPIAIJSetPreallocation(M, 0, dnz, 0, onz));
  for (cupid_int R = 0; R < P->nrows; R++)
    for (int a = 0; a < bs; a++) {
      cupid_int fi = bc->free_index[R * bs + a];
      if (fi < f0 || fi >= f1) continue;
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
  int whole = f0 == 0 && f1 == n_free; /* one rank (local sizes need not be multiples of 3) */
  for (cupid_int d = 0; d < bc->n && whole; d += 3)
    whole = bc->fixed[d] == bc->fixed[d + 1] && bc->fixed[d] == bc->fixed[d + 2];
  if (whole && bs == 3) PCALL(MatSetBlockSize(M, 3));
  PCALL(MatAssemblyBegin(M, MAT_FINAL_ASSEMBLY));
  PCALL(MatAssemblyEnd(M, MAT_FINAL_ASSEMBLY));
  *out = M;
  M = NULL;
cleanup:
  if (M) MatDestroy(&M);
  cupid_free(&dnz);
  cupid_free(&onz);
  cupid_free(&cols);
  cupid_free(&vals);
  return st;
}

cupid_status cupid_krylov_solve(const cupid_linear_operator *A, const cupid_csr_t *P,
                                const cupid_dirichlet_t *bc, const double *f, double *u,
                                const cupid_coupling_krylov_options *opts,
                                cupid_coupling_krylov_info *info) {
  cupid_status st = CUPID_SUCCESS;
  cupid_coupling_krylov_info inf;
  memset(&inf, 0, sizeof inf);
  CUPID_CHECK(A && A->apply && P && bc && f && u, CUPID_ERR_ARGUMENT, "Krylov solve: NULL argument");
  cupid_int n = A->n;
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
  shell_ctx ctx = {0}; /* complete once the work vectors exist */
  PetscMPIInt rank = 0, size = 1;
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  MPI_Comm_size(PETSC_COMM_WORLD, &size);
  const cupid_int f0 = n_free * rank / size, f1 = n_free * (rank + 1) / size;
  CUPID_TRY(cupid_malloc((size_t)n_free + 1, sizeof *gidx, "free DOFs", &gidx));
  CUPID_TRY(cupid_calloc((size_t)n, sizeof *xf, "work vector", &xf));
  CUPID_TRY(cupid_calloc((size_t)n, sizeof *yf, "work vector", &yf));
  for (cupid_int d = 0; d < n; d++)
    if (bc->free_index[d] >= 0) gidx[bc->free_index[d]] = d;
  ctx = (shell_ctx){.A = A, .n = n, .n_free = n_free, .f0 = f0, .f1 = f1, .gidx = gidx,
                    .xf = xf, .yf = yf};

  /* b_f = f_f - (A u_c)_f */
  for (cupid_int d = 0; d < n; d++) xf[d] = bc->fixed[d] ? bc->value[d] : 0.0;
  CUPID_TRY(A->apply(A->ctx, xf, yf));
  PCALL(VecCreateMPI(PETSC_COMM_WORLD, (PetscInt)(f1 - f0), (PetscInt)n_free, &b));
  PCALL(VecDuplicate(b, &x));
  PCALL(VecScatterCreateToAll(x, &ctx.toall, &ctx.xall));
  PetscScalar *ba;
  PCALL(VecGetArray(b, &ba));
  for (cupid_int k = f0; k < f1; k++) ba[k - f0] = f[gidx[k]] - yf[gidx[k]];
  PCALL(VecRestoreArray(b, &ba));
  PetscReal bnorm;
  PCALL(VecNorm(b, NORM_2, &bnorm));

  double t0 = cupid_wtime();
  PCALL(MatCreateShell(PETSC_COMM_WORLD, (PetscInt)(f1 - f0), (PetscInt)(f1 - f0),
                       (PetscInt)n_free, (PetscInt)n_free, &ctx, &S));
  PCALL(MatShellSetOperation(S, MATOP_MULT, (void (*)(void))shell_mult));
  CUPID_TRY(free_block_aij(P, bc, f0, f1, &Pm));
  PCALL(KSPCreate(PETSC_COMM_WORLD, &ksp));
  PCALL(KSPSetOperators(ksp, S, Pm));
  if (A->symmetric) { /* CG: left preconditioning only; the true residual is recomputed below */
    PCALL(KSPSetType(ksp, KSPCG));
    PCALL(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED));
  } else {
    PCALL(KSPSetType(ksp, KSPGMRES));
    PCALL(KSPGMRESSetRestart(ksp, opts && opts->restart > 0 ? opts->restart : 200));
    PCALL(KSPSetPCSide(ksp, PC_RIGHT));
  }
  PCALL(KSPSetTolerances(ksp, opts && opts->rtol > 0 ? opts->rtol : 1e-10, 1e-300, PETSC_DEFAULT,
                         opts && opts->max_it > 0 ? opts->max_it : 2000));
  PCALL(KSPGetPC(ksp, &pc));
  /* A symmetric operator gets a Cholesky factor of its (symmetric positive definite) twin:
   * MUMPS's LL^T, about 2/3 of the LU's memory (the Arlequin panel at h = 0.5: 2.6 GB
   * against 3.7 GB in all). */
  const char *pct = opts && opts->pc ? opts->pc : A->symmetric ? "cholesky" : "lu";
  PCALL(PCSetType(pc, pct));
  if (A->symmetric) PCALL(MatSetOption(Pm, MAT_SPD, PETSC_TRUE));
  if (!strcmp(pct, "cholesky")) {
    PCALL(PCFactorSetMatSolverType(pc, opts && opts->factor_package ? opts->factor_package : "mumps"));
  } else if (!strcmp(pct, "lu") || !strcmp(pct, "ilu")) {
    /* UMFPACK and PETSc's own LU are sequential: MUMPS on several ranks */
    const char *pkg = opts && opts->factor_package ? opts->factor_package
                      : size > 1                   ? "mumps"
                                                   : (!strcmp(pct, "lu") ? "umfpack" : "petsc");
    PCALL(PCFactorSetMatSolverType(pc, pkg));
  }
  if (!strcmp(pct, "fieldsplit")) {
    /* Two fields: PD DOFs and FE DOFs (sub-solvers from -fieldsplit_pd_* / -fieldsplit_fe_*). */
    cupid_int n_pd_free = 0;
    while (n_pd_free < n_free && gidx[n_pd_free] < A->n_pd_dofs) n_pd_free++;
    /* the owned part of each field (PD DOFs come first) */
    cupid_int p0 = f0 < n_pd_free ? f0 : n_pd_free, p1 = f1 < n_pd_free ? f1 : n_pd_free;
    PetscInt *idx = NULL;
    CUPID_TRY(cupid_malloc((size_t)(f1 - f0) + 1, sizeof *idx, "field indices", &idx));
    for (cupid_int k = f0; k < f1; k++) idx[k - f0] = (PetscInt)k;
    PCALL(ISCreateGeneral(PETSC_COMM_WORLD, (PetscInt)(p1 - p0), idx + (p0 - f0),
                          PETSC_COPY_VALUES, &is_pd));
    PCALL(ISCreateGeneral(PETSC_COMM_WORLD, (PetscInt)(f1 - p1), idx + (p1 - f0),
                          PETSC_COPY_VALUES, &is_fe));
    cupid_free(&idx);
    if (size == 1 && n_pd_free % 3 == 0) PCALL(ISSetBlockSize(is_pd, 3));
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
  snprintf(inf.method, sizeof inf.method, "%s+%s", A->symmetric ? "cg" : "gmres", used);

  /* u = [x_f ; u_c]; the true residual, recomputed. */
  const PetscScalar *xa;
  PCALL(VecScatterBegin(ctx.toall, x, ctx.xall, INSERT_VALUES, SCATTER_FORWARD));
  PCALL(VecScatterEnd(ctx.toall, x, ctx.xall, INSERT_VALUES, SCATTER_FORWARD));
  PCALL(VecGetArrayRead(ctx.xall, &xa));
  for (cupid_int d = 0; d < n; d++) u[d] = bc->fixed[d] ? bc->value[d] : 0.0;
  for (cupid_int k = 0; k < n_free; k++) u[gidx[k]] = xa[k];
  PCALL(VecRestoreArrayRead(ctx.xall, &xa));
  CUPID_TRY(A->apply(A->ctx, u, yf));
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
                     "the Krylov solve (%s) did not converge: %s after %d iterations, relative "
                     "residual %.2e; try other -ksp_type / -pc_type options, or --solver direct",
                     inf.method, KSPConvergedReasons[reason], inf.iterations, inf.residual);
cleanup:
  if (info) *info = inf;
  if (ksp) KSPDestroy(&ksp);
  if (is_pd) ISDestroy(&is_pd);
  if (is_fe) ISDestroy(&is_fe);
  if (S) MatDestroy(&S);
  if (Pm) MatDestroy(&Pm);
  if (x) VecDestroy(&x);
  if (b) VecDestroy(&b);
  if (ctx.toall) VecScatterDestroy(&ctx.toall);
  if (ctx.xall) VecDestroy(&ctx.xall);
  cupid_free(&gidx);
  cupid_free(&xf);
  cupid_free(&yf);
  return st;
}

#else

cupid_status cupid_krylov_solve(const cupid_linear_operator *A, const cupid_csr_t *P,
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

/* The fictitious-node operator as a cupid_linear_operator. */
static cupid_status fict_apply(void *ctx, const double *x, double *y) {
  return cupid_coupling_operator_apply(ctx, x, y);
}

static cupid_status fict_apply_rows(void *ctx, const double *x, cupid_int d0, cupid_int d1, double *y) {
  return cupid_coupling_operator_apply_rows(ctx, x, d0, d1, y);
}

void cupid_coupling_operator_linear(const cupid_coupling_operator A, cupid_linear_operator *L) {
  cupid_coupling_info ci;
  cupid_coupling_operator_get_info(A, &ci);
  *L = (cupid_linear_operator){.n = cupid_coupling_operator_size(A),
                               .apply = fict_apply,
                               .apply_rows = fict_apply_rows,
                               .ctx = A,
                               .symmetric = 0,
                               .n_pd_dofs = 3 * ci.n_real_pd};
}

cupid_status cupid_coupling_krylov_solve(const cupid_coupling_operator A, const cupid_csr_t *P,
                                         const cupid_dirichlet_t *bc, const double *f, double *u,
                                         const cupid_coupling_krylov_options *opts,
                                         cupid_coupling_krylov_info *info) {
  CUPID_CHECK(A, CUPID_ERR_ARGUMENT, "Krylov solve: NULL operator");
  cupid_linear_operator L;
  cupid_coupling_operator_linear(A, &L);
  return cupid_krylov_solve(&L, P, bc, f, u, opts, info);
}
