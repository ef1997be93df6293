/* Krylov solve of a matrix-free system on PETSc (the coupled systems of src/coupling), on the free DOFs: the fictitious-node
 * system (paper 000 Eq. 38) by GMRES (not symmetric), the Arlequin system (paper 004 Eq. 18) by
 * CG (symmetric positive definite). The operator is a MATSHELL over a cupid_linear_operator
 * (operator.c, arlequin_operator.c); the preconditioner is built from the cheap twin (the same
 * system with a short bond-based PD operator) by a PETSc PC: by default an LU (UMFPACK on one
 * rank, MUMPS on several) for GMRES, a MUMPS Cholesky for CG (the twin has ~19 blocks a PD row,
 * so its factor is ~1/50 of the LPS one); ILU, GAMG or hypre on request. GMRES is right
 * preconditioned, so it minimises the true residual and rtol is what the caller gets; the true
 * residual is recomputed at the end either way. Dirichlet DOFs are eliminated:
 * A_ff u_f = f_f - A_fc u_c. On several MPI ranks with a replicated model the vectors, the
 * rows of the product and the preconditioner's rows are split over the ranks and the factor is
 * MUMPS's (parallel); every rank gets the whole solution. With a slab of the PD grid per rank
 * (the operator's part, issue 6) each rank holds only its slab's DOFs and the FE DOFs: the
 * product gathers the halo through a VecScatter and sums the FE rows over the ranks, and the
 * fixed DOFs stay in the system as scaled identity rows (solve_slabs below). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "cupid/solvers.h"
#include "cupid_config.h"

#if CUPID_HAVE_PETSC
#include <petscksp.h>

#include "petsc_internal.h"

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

/* The work arrays of building an AIJ matrix: row counts (diagonal and off-diagonal blocks)
 * of the owned rows, one row's columns and values. */
typedef struct {
  PetscInt *dnz, *onz, *cols;
  PetscScalar *vals;
} aij_rows;

static cupid_status aij_rows_alloc(cupid_int nloc, cupid_int maxrow, aij_rows *r) {
  CUPID_CALL(cupid_calloc((size_t)nloc + 1, sizeof *r->dnz, "preconditioner row counts", &r->dnz));
  CUPID_CALL(cupid_calloc((size_t)nloc + 1, sizeof *r->onz, "preconditioner row counts", &r->onz));
  CUPID_CALL(cupid_malloc((size_t)maxrow + 1, sizeof *r->cols, "preconditioner row", &r->cols));
  return cupid_malloc((size_t)maxrow + 1, sizeof *r->vals, "preconditioner row", &r->vals);
}

static void aij_rows_free(aij_rows *r) {
  cupid_free(&r->dnz);
  cupid_free(&r->onz);
  cupid_free(&r->cols);
  cupid_free(&r->vals);
}

/* The longest scalar row of the block-CSR P. */
static cupid_int block_row_max(const cupid_csr_t *P) {
  cupid_int m = 1;
  for (cupid_int R = 0; R < P->nrows; R++)
    if ((P->rowptr[R + 1] - P->rowptr[R]) * P->bs > m) m = (P->rowptr[R + 1] - P->rowptr[R]) * P->bs;
  return m;
}

/* A parallel AIJ matrix of nloc owned rows (of N), preallocated by row counts. */
static cupid_status create_aij(PetscInt nloc, PetscInt N, const PetscInt *dnz,
                               const PetscInt *onz, Mat *M) {
  cupid_status st = CUPID_SUCCESS;
  PTRY(MatCreate(PETSC_COMM_WORLD, M));
  PTRY(MatSetSizes(*M, nloc, nloc, N, N));
  PTRY(MatSetType(*M, MATAIJ));
  PTRY(MatSeqAIJSetPreallocation(*M, 0, dnz));
  PTRY(MatMPIAIJSetPreallocation(*M, 0, dnz, 0, onz));
cleanup:
  return st;
}

/* Assemble *M and hand it over as *out. */
static cupid_status finish_aij(Mat *M, Mat *out) {
  cupid_status st = CUPID_SUCCESS;
  PTRY(MatAssemblyBegin(*M, MAT_FINAL_ASSEMBLY));
  PTRY(MatAssemblyEnd(*M, MAT_FINAL_ASSEMBLY));
  *out = *M;
  *M = NULL;
cleanup:
  return st;
}

/* The free-free block of the block-CSR P as a PETSc AIJ matrix (scalar rows), the owned rows
 * [f0, f1) of it on each rank. */
static cupid_status free_block_aij(const cupid_csr_t *P, const cupid_dirichlet_t *bc,
                                   cupid_int f0, cupid_int f1, Mat *out) {
  cupid_status st = CUPID_SUCCESS;
  aij_rows r = {0};
  Mat M = NULL;
  const int bs = P->bs;
  cupid_int n_free = bc->n_free, nloc = f1 - f0;
  CUPID_TRY(aij_rows_alloc(nloc, block_row_max(P), &r));
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
      if (fi >= f0 && fi < f1) r.dnz[fi - f0] = (PetscInt)din, r.onz[fi - f0] = (PetscInt)(len - din);
    }
  }
  CUPID_TRY(create_aij((PetscInt)nloc, (PetscInt)n_free, r.dnz, r.onz, &M));
  for (cupid_int R = 0; R < P->nrows; R++)
    for (int a = 0; a < bs; a++) {
      cupid_int fi = bc->free_index[R * bs + a];
      if (fi < f0 || fi >= f1) continue;
      PetscInt len = 0;
      for (cupid_int k = P->rowptr[R]; k < P->rowptr[R + 1]; k++)
        for (int b = 0; b < bs; b++) {
          cupid_int fc = bc->free_index[P->col[k] * bs + b];
          if (fc < 0) continue;
          r.cols[len] = (PetscInt)fc;
          r.vals[len++] = P->val[(size_t)k * bs * bs + a * bs + b];
        }
      PetscInt row = (PetscInt)fi;
      PTRY(MatSetValues(M, 1, &row, len, r.cols, r.vals, INSERT_VALUES));
    }
  /* Block size 3 (GAMG's default near null space: the translations) when every node is
   * free or fixed as a whole. */
  int whole = f0 == 0 && f1 == n_free; /* one rank (local sizes need not be multiples of 3) */
  for (cupid_int d = 0; d < bc->n && whole; d += 3)
    whole = bc->fixed[d] == bc->fixed[d + 1] && bc->fixed[d] == bc->fixed[d + 2];
  if (whole && bs == 3) PTRY(MatSetBlockSize(M, 3));
  CUPID_TRY(finish_aij(&M, out));
cleanup:
  if (M) MatDestroy(&M);
  aij_rows_free(&r);
  return st;
}

/* The PETSc objects of one solve. */
typedef struct {
  Mat S, Pm;      /* the shell operator, the preconditioner matrix */
  Vec x, b;
  KSP ksp;
  IS is_pd, is_fe; /* the fields of pc fieldsplit */
  PetscBool lu;    /* the PC is an LU ... */
  int umfpack;     /* ... by UMFPACK */
} ksp_objects;

static void ksp_objects_destroy(ksp_objects *k) {
  if (k->ksp) KSPDestroy(&k->ksp);
  if (k->is_pd) ISDestroy(&k->is_pd);
  if (k->is_fe) ISDestroy(&k->is_fe);
  if (k->S) MatDestroy(&k->S);
  if (k->Pm) MatDestroy(&k->Pm);
  if (k->x) VecDestroy(&k->x);
  if (k->b) VecDestroy(&k->b);
}

/* The owned ranges of the two fields of pc fieldsplit, in PETSc's global numbering. */
typedef struct {
  PetscInt pd_first, pd_last, fe_first, fe_last;
  int pd_blocks; /* the PD field is whole nodes (block size 3) */
} ksp_fields;

/* The KSP for A (matrix-free S) preconditioned from Pm: CG or right-preconditioned GMRES, the
 * default PC (a Cholesky factor for CG, an LU for GMRES), the fields of pc fieldsplit, then
 * the run-time options, into k->ksp (and the fields' k->is_pd, k->is_fe). */
static cupid_status configure_ksp_once(const cupid_linear_operator *A,
                                  const cupid_krylov_options *opts,
                                  const ksp_fields *fields, ksp_objects *k) {
  Mat S = k->S, Pm = k->Pm;
  IS *is_pd = &k->is_pd, *is_fe = &k->is_fe;
  KSP *out = &k->ksp;
  cupid_status st = CUPID_SUCCESS;
  KSP ksp = NULL;
  PC pc;
  PetscMPIInt size = 1;
  MPI_Comm_size(PETSC_COMM_WORLD, &size);
  PTRY(KSPCreate(PETSC_COMM_WORLD, &ksp));
  PTRY(KSPSetOperators(ksp, S, Pm));
  if (A->symmetric) { /* CG: left preconditioning only; the true residual is recomputed after */
    PTRY(KSPSetType(ksp, KSPCG));
    PTRY(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED));
  } else {
    PTRY(KSPSetType(ksp, KSPGMRES));
    PTRY(KSPGMRESSetRestart(ksp, opts && opts->restart > 0 ? opts->restart : 200));
    PTRY(KSPSetPCSide(ksp, PC_RIGHT));
  }
  PTRY(KSPSetTolerances(ksp, opts && opts->rtol > 0 ? opts->rtol : 1e-10, 1e-300, PETSC_DEFAULT,
                         opts && opts->max_it > 0 ? opts->max_it : 2000));
  PTRY(KSPGetPC(ksp, &pc));
  /* A symmetric operator gets a Cholesky factor of its (symmetric positive definite) twin:
   * MUMPS's LL^T, about 2/3 of the LU's memory (the Arlequin panel at h = 0.5: 2.6 GB
   * against 3.7 GB in all). */
  const char *pct = opts && opts->pc ? opts->pc : A->symmetric ? "cholesky" : "lu";
  PTRY(PCSetType(pc, pct));
  if (A->symmetric) PTRY(MatSetOption(Pm, MAT_SPD, PETSC_TRUE));
  if (!strcmp(pct, "cholesky")) {
    PTRY(PCFactorSetMatSolverType(pc, opts && opts->factor_package ? opts->factor_package : "mumps"));
  } else if (!strcmp(pct, "lu") || !strcmp(pct, "ilu")) {
    /* UMFPACK and PETSc's own LU are sequential: MUMPS on several ranks */
    const char *pkg = opts && opts->factor_package ? opts->factor_package
                      : size > 1                   ? "mumps"
                                                   : (!strcmp(pct, "lu") ? "umfpack" : "petsc");
    PTRY(PCFactorSetMatSolverType(pc, pkg));
  }
  if (!strcmp(pct, "fieldsplit")) {
    /* Two fields: PD DOFs and FE DOFs (sub-solvers from -fieldsplit_pd_* / -fieldsplit_fe_*). */
    PTRY(ISCreateStride(PETSC_COMM_WORLD, fields->pd_last - fields->pd_first, fields->pd_first,
                         1, is_pd));
    PTRY(ISCreateStride(PETSC_COMM_WORLD, fields->fe_last - fields->fe_first, fields->fe_first,
                         1, is_fe));
    if (fields->pd_blocks) PTRY(ISSetBlockSize(*is_pd, 3));
    PTRY(PCFieldSplitSetIS(pc, "pd", *is_pd));
    PTRY(PCFieldSplitSetIS(pc, "fe", *is_fe));
  }
  PTRY(KSPSetFromOptions(ksp));
  PTRY(KSPSetUp(ksp));
  PTRY(PCSetUp(pc));
  PTRY(PetscObjectTypeCompare((PetscObject)pc, PCLU, &k->lu));
  if (k->lu) {
    MatSolverType pkg = NULL;
    PTRY(PCFactorGetMatSolverType(pc, &pkg));
    k->umfpack = pkg && !strcmp(pkg, MATSOLVERUMFPACK);
  }
  *out = ksp;
  ksp = NULL;
cleanup:
  if (ksp) KSPDestroy(&ksp);
  return st;
}

/* The normwise backward error of the PC's solve with Pm: for b = Pm e (e fixed, entries in
 * [-0.5, 0.5]), |b - Pm z|_inf / (|Pm|_inf |z|_inf + |b|_inf) with z = PC(b); about n eps for
 * a stable factorisation. */
static cupid_status pc_backward_error(PC pc, Mat Pm, double *eta) {
  cupid_status st = CUPID_SUCCESS;
  Vec e = NULL, b = NULL, z = NULL;
  PetscInt lo, hi;
  PetscScalar *ea;
  PetscReal an, bn, zn, rn;
  PTRY(MatCreateVecs(Pm, &e, &b));
  PTRY(VecDuplicate(b, &z));
  PTRY(VecGetOwnershipRange(e, &lo, &hi));
  PTRY(VecGetArray(e, &ea));
  for (PetscInt i = lo; i < hi; i++) {
    uint64_t s = 0x9E3779B97F4A7C15ull * (uint64_t)(i + 1);
    s ^= s >> 29, s *= 0xBF58476D1CE4E5B9ull, s ^= s >> 32;
    ea[i - lo] = (double)(s >> 11) / 9007199254740992.0 - 0.5;
  }
  PTRY(VecRestoreArray(e, &ea));
  PTRY(MatMult(Pm, e, b));
  PTRY(PCApply(pc, b, z));
  PTRY(MatMult(Pm, z, e)); /* e = Pm z */
  PTRY(VecAYPX(e, -1.0, b));
  PTRY(MatNorm(Pm, NORM_INFINITY, &an));
  PTRY(VecNorm(b, NORM_INFINITY, &bn));
  PTRY(VecNorm(z, NORM_INFINITY, &zn));
  PTRY(VecNorm(e, NORM_INFINITY, &rn));
  *eta = (an * zn + bn) > 0 ? (double)(rn / (an * zn + bn)) : 0.0;
cleanup:
  if (e) VecDestroy(&e);
  if (b) VecDestroy(&b);
  if (z) VecDestroy(&z);
  return st;
}

/* A backward error of the twin's LU above this: refactor with partial pivoting. */
#define LU_BACKWARD_ERROR_MAX 1e-12

/* configure_ksp_once(), and for a UMFPACK LU of the twin whose solves are inaccurate (UMFPACK's
 * threshold pivoting, a pivot down to 0.1 of its column's largest entry, grew the factor of
 * the fictitious-node twin of the paper's bar to a pivot ratio of 1e-5 and a backward error
 * of 7e-8 at condition 1e4; factor.c does the same check for the built-in engine) the KSP
 * again with -mat_umfpack_pivot_tolerance 1 (partial pivoting: 2.5% more fill there), unless
 * the options already set it. */
static cupid_status configure_ksp(const cupid_linear_operator *A,
                                  const cupid_krylov_options *opts,
                                  const ksp_fields *fields, ksp_objects *k) {
  cupid_status st = CUPID_SUCCESS;
  PetscBool set = PETSC_FALSE;
  int added = 0;
  CUPID_CALL(configure_ksp_once(A, opts, fields, k));
  if (!k->umfpack) return CUPID_SUCCESS;
  PC pc;
  double eta = 0.0;
  PTRY(KSPGetPC(k->ksp, &pc));
  CUPID_TRY(pc_backward_error(pc, k->Pm, &eta));
  PTRY(PetscOptionsHasName(NULL, NULL, "-mat_umfpack_pivot_tolerance", &set));
  if (eta <= LU_BACKWARD_ERROR_MAX || set) goto cleanup;
  PTRY(PetscOptionsSetValue(NULL, "-mat_umfpack_pivot_tolerance", "1.0"));
  added = 1;
  KSPDestroy(&k->ksp);
  if (k->is_pd) ISDestroy(&k->is_pd);
  if (k->is_fe) ISDestroy(&k->is_fe);
  CUPID_TRY(configure_ksp_once(A, opts, fields, k));
cleanup:
  if (added) PetscOptionsClearValue(NULL, "-mat_umfpack_pivot_tolerance");
  return st;
}

/* Solve, and what the solve did into *inf (iterations, convergence, time, method). */
static cupid_status run_ksp(KSP ksp, const cupid_linear_operator *A, Vec b, Vec x,
                            cupid_solve_info *inf) {
  cupid_status st = CUPID_SUCCESS;
  PetscInt its;
  KSPConvergedReason reason;
  PC pc;
  PCType used;
  double t0 = cupid_wtime();
  PTRY(KSPSolve(ksp, b, x));
  inf->time_solve = cupid_wtime() - t0;
  PTRY(KSPGetIterationNumber(ksp, &its));
  PTRY(KSPGetConvergedReason(ksp, &reason));
  inf->iterations = (int)its;
  PTRY(KSPGetPC(ksp, &pc));
  PTRY(PCGetType(pc, &used));
  PetscMPIInt size = 1;
  MPI_Comm_size(PETSC_COMM_WORLD, &size);
  inf->method = "petsc";
  inf->matrix_free = 1;
  inf->ranks = (int)size;
  inf->failed_dof = -1;
  snprintf(inf->ksp_type, sizeof inf->ksp_type, "%s", A->symmetric ? "cg" : "gmres");
  snprintf(inf->pc_type, sizeof inf->pc_type, "%s", used);
  snprintf(inf->converged_reason, sizeof inf->converged_reason, "%s", KSPConvergedReasons[reason]);
cleanup:
  return st;
}

/* The error of a solve that did not converge (CUPID_SUCCESS if it did). */
static cupid_status not_converged(const cupid_solve_info *inf) {
  if (!strncmp(inf->converged_reason, "CONVERGED", 9)) return CUPID_SUCCESS;
  if (!strcmp(inf->converged_reason, "DIVERGED_TRUE_RESIDUAL"))
    return CUPID_ERROR(CUPID_ERR_NUMERIC,
                       "the Krylov solve (%s + %s) met its tolerance on its residual estimate, "
                       "but the true relative residual is %.2e after %d iterations and %d "
                       "restarts (an inaccurate preconditioner?); try other -ksp_type / "
                       "-pc_type options, or --solver direct",
                       inf->ksp_type, inf->pc_type, inf->residual, inf->iterations,
                       inf->refinements);
  return CUPID_ERROR(CUPID_ERR_NUMERIC,
                     "the Krylov solve (%s + %s) did not converge: %s after %d iterations, "
                     "relative residual %.2e; try other -ksp_type / -pc_type options, or "
                     "--solver direct",
                     inf->ksp_type, inf->pc_type, inf->converged_reason, inf->iterations,
                     inf->residual);
}

/* Restarts of a solve whose true residual misses the tolerance (KRYLOV_REFINEMENTS at most). */
#define KRYLOV_REFINEMENTS 3

/* The true relative residual |b - S x| / |b| of the PETSc system. */
static cupid_status ksp_true_residual(Mat S, Vec b, Vec x, Vec r, double *rel) {
  cupid_status st = CUPID_SUCCESS;
  PetscReal rn, bn;
  PTRY(MatMult(S, x, r));
  PTRY(VecAYPX(r, -1.0, b));
  PTRY(VecNorm(r, NORM_2, &rn));
  PTRY(VecNorm(b, NORM_2, &bn));
  *rel = bn > 0 ? (double)(rn / bn) : (double)rn;
cleanup:
  return st;
}

/* The round-off of the product at x, relative to |b|: |S x - (S (x + z) - S z)| / |b| for z =
 * x scaled entry by entry by fixed factors in [0.5, 1.5) (as iterative.c's product_noise()). */
static cupid_status ksp_product_noise(Mat S, Vec b, Vec x, double *noise) {
  cupid_status st = CUPID_SUCCESS;
  Vec z = NULL, xz = NULL, y = NULL, t = NULL;
  PetscInt lo, hi;
  PetscScalar *za;
  const PetscScalar *xa;
  PetscReal en, bn;
  PTRY(VecDuplicate(x, &z));
  PTRY(VecDuplicate(x, &xz));
  PTRY(VecDuplicate(b, &y));
  PTRY(VecDuplicate(b, &t));
  PTRY(VecGetOwnershipRange(z, &lo, &hi));
  PTRY(VecGetArray(z, &za));
  PTRY(VecGetArrayRead(x, &xa));
  for (PetscInt i = lo; i < hi; i++) {
    uint64_t s = 0x9E3779B97F4A7C15ull * (uint64_t)(i + 1);
    s ^= s >> 29, s *= 0xBF58476D1CE4E5B9ull, s ^= s >> 32;
    za[i - lo] = xa[i - lo] * (0.5 + (double)(s >> 11) / 9007199254740992.0);
  }
  PTRY(VecRestoreArrayRead(x, &xa));
  PTRY(VecRestoreArray(z, &za));
  PTRY(VecWAXPY(xz, 1.0, x, z));
  PTRY(MatMult(S, xz, y));
  PTRY(MatMult(S, z, t));
  PTRY(VecAXPY(y, -1.0, t)); /* S (x + z) - S z */
  PTRY(MatMult(S, x, t));
  PTRY(VecAXPY(y, -1.0, t));
  PTRY(VecNorm(y, NORM_2, &en));
  PTRY(VecNorm(b, NORM_2, &bn));
  *noise = bn > 0 ? (double)(en / bn) : (double)en;
cleanup:
  if (z) VecDestroy(&z);
  if (xz) VecDestroy(&xz);
  if (y) VecDestroy(&y);
  if (t) VecDestroy(&t);
  return st;
}

/* After KSPSolve: the Krylov method stops on its own estimate of the residual (GMRES's
 * least-squares residual, CG's recurrence), which drifts from the true one when the
 * preconditioner is applied inexactly: with right preconditioning x = M^{-1} (V y) is
 * preconditioned once more at the end, and an LU whose solves have a backward error eta
 * leaves |b - A x| / |b| ~ eta kappa(M) however small the estimate (the twin of the
 * fictitious-node bar, factored by UMFPACK's threshold pivoting: estimate 5e-12, true residual
 * 1.6e-3). So the true residual is checked, as the built-in engine does (iterative.c):
 * at most 2 rtol: converged; at most twice the round-off of the product (ksp_product_noise()):
 * CONVERGED_ROUNDOFF; else restarts from x (r = b - A x recomputed exactly: iterative
 * refinement) for the absolute target of the first solve, KRYLOV_REFINEMENTS of them at most
 * and while each halves the true residual; then converged up to max(100 rtol, 1e-10),
 * DIVERGED_TRUE_RESIDUAL above (not_converged() makes it an error). inf->refinements counts
 * the restarts. */
static cupid_status refine_true_residual(KSP ksp, Mat S, Vec b, Vec x, cupid_solve_info *inf) {
  cupid_status st = CUPID_SUCCESS;
  Vec r = NULL;
  PetscReal rtol, atol, dtol, bnorm;
  PetscInt maxit, its;
  KSPConvergedReason reason;
  PTRY(KSPGetTolerances(ksp, &rtol, &atol, &dtol, &maxit));
  PTRY(VecNorm(b, NORM_2, &bnorm));
  PTRY(VecDuplicate(b, &r));
  double rel = 0.0, prev = INFINITY, noise = -1.0, limit = fmax(100.0 * rtol, 1e-10);
  if (strncmp(inf->converged_reason, "CONVERGED", 9)) goto cleanup; /* reported as it is */
  for (int pass = 0;; pass++) {
    CUPID_TRY(ksp_true_residual(S, b, x, r, &rel));
    if (rel <= 2.0 * rtol) break;
    if (noise < 0.0) CUPID_TRY(ksp_product_noise(S, b, x, &noise));
    if (rel <= 2.0 * noise) {
      snprintf(inf->converged_reason, sizeof inf->converged_reason, "CONVERGED_ROUNDOFF");
      break;
    }
    if (pass == KRYLOV_REFINEMENTS || rel > 0.5 * prev) {
      if (rel > limit)
        snprintf(inf->converged_reason, sizeof inf->converged_reason, "DIVERGED_TRUE_RESIDUAL");
      break;
    }
    prev = rel;
    PTRY(KSPSetTolerances(ksp, 0.0, fmax(atol, 0.5 * rtol * bnorm), dtol, maxit));
    PTRY(KSPSetInitialGuessNonzero(ksp, PETSC_TRUE));
    double t0 = cupid_wtime();
    PTRY(KSPSolve(ksp, b, x));
    inf->time_solve += cupid_wtime() - t0;
    PTRY(KSPGetConvergedReason(ksp, &reason));
    PTRY(KSPGetIterationNumber(ksp, &its));
    inf->iterations += (int)its;
    inf->refinements++;
    if (reason < 0) {
      snprintf(inf->converged_reason, sizeof inf->converged_reason, "%s", KSPConvergedReasons[reason]);
      goto cleanup;
    }
  }
  PTRY(KSPSetTolerances(ksp, rtol, atol, dtol, maxit));
  PTRY(KSPSetInitialGuessNonzero(ksp, PETSC_FALSE));
cleanup:
  if (r) VecDestroy(&r);
  return st;
}

/* The model replicated on every rank: the free DOFs only, split evenly over the ranks. */
static cupid_status solve_replicated(const cupid_linear_operator *A, const cupid_csr_t *P,
                                     const cupid_dirichlet_t *bc, const double *f, double *u,
                                     const cupid_krylov_options *opts,
                                     cupid_solve_info *info) {
  cupid_status st = CUPID_SUCCESS;
  cupid_solve_info inf;
  memset(&inf, 0, sizeof inf);
  cupid_int n = A->n;
  cupid_int *gidx = NULL;
  double *xf = NULL, *yf = NULL;
  ksp_objects obj = {0};
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
  PTRY(VecCreateMPI(PETSC_COMM_WORLD, (PetscInt)(f1 - f0), (PetscInt)n_free, &obj.b));
  PTRY(VecDuplicate(obj.b, &obj.x));
  PTRY(VecScatterCreateToAll(obj.x, &ctx.toall, &ctx.xall));
  PetscScalar *ba;
  PTRY(VecGetArray(obj.b, &ba));
  for (cupid_int k = f0; k < f1; k++) ba[k - f0] = f[gidx[k]] - yf[gidx[k]];
  PTRY(VecRestoreArray(obj.b, &ba));
  PetscReal bnorm;
  PTRY(VecNorm(obj.b, NORM_2, &bnorm));

  double t0 = cupid_wtime();
  PTRY(MatCreateShell(PETSC_COMM_WORLD, (PetscInt)(f1 - f0), (PetscInt)(f1 - f0),
                       (PetscInt)n_free, (PetscInt)n_free, &ctx, &obj.S));
  PTRY(MatShellSetOperation(obj.S, MATOP_MULT, (void (*)(void))shell_mult));
  CUPID_TRY(free_block_aij(P, bc, f0, f1, &obj.Pm));
  {
    /* the owned part of each field (PD DOFs come first) */
    cupid_int n_pd_free = 0;
    while (n_pd_free < n_free && gidx[n_pd_free] < A->n_pd_dofs) n_pd_free++;
    cupid_int p0 = f0 < n_pd_free ? f0 : n_pd_free, p1 = f1 < n_pd_free ? f1 : n_pd_free;
    const ksp_fields fields = {p0, p1, p1, f1, size == 1 && n_pd_free % 3 == 0};
    CUPID_TRY(configure_ksp(A, opts, &fields, &obj));
  }
  CUPID_TRY(run_ksp(obj.ksp, A, obj.b, obj.x, &inf));
  inf.time_factor = cupid_wtime() - t0 - inf.time_solve;
  CUPID_TRY(refine_true_residual(obj.ksp, obj.S, obj.b, obj.x, &inf));
  inf.n = n_free;

  /* u = [x_f ; u_c]; the true residual, recomputed. */
  const PetscScalar *xa;
  PTRY(VecScatterBegin(ctx.toall, obj.x, ctx.xall, INSERT_VALUES, SCATTER_FORWARD));
  PTRY(VecScatterEnd(ctx.toall, obj.x, ctx.xall, INSERT_VALUES, SCATTER_FORWARD));
  PTRY(VecGetArrayRead(ctx.xall, &xa));
  for (cupid_int d = 0; d < n; d++) u[d] = bc->fixed[d] ? bc->value[d] : 0.0;
  for (cupid_int k = 0; k < n_free; k++) u[gidx[k]] = xa[k];
  PTRY(VecRestoreArrayRead(ctx.xall, &xa));
  CUPID_TRY(A->apply(A->ctx, u, yf));
  double r2 = 0.0, f2 = 0.0;
  for (cupid_int k = 0; k < n_free; k++) {
    double r = f[gidx[k]] - yf[gidx[k]];
    r2 += r * r;
    f2 += f[gidx[k]] * f[gidx[k]];
  }
  double scale = bnorm > 0 ? (double)bnorm : sqrt(f2);
  inf.residual = scale > 0 ? sqrt(r2) / scale : sqrt(r2);
  st = not_converged(&inf);
cleanup:
  if (info) *info = inf;
  ksp_objects_destroy(&obj);
  if (ctx.toall) VecScatterDestroy(&ctx.toall);
  if (ctx.xall) VecDestroy(&ctx.xall);
  cupid_free(&gidx);
  cupid_free(&xf);
  cupid_free(&yf);
  return st;
}

/* ------------------------------------------------------------ a slab per rank (issue 6) */

/* The grid partitioned into slabs (A->part): local DOFs [3 per slab node (owned + halo) | FE
 * DOFs], global DOFs [3 per grid node | FE DOFs]; local PD DOF d is global 3 first_global + d.
 * Rank r owns the global DOFs of its owned nodes, the last rank also the FE DOFs (contiguous
 * ranges in rank order, as PETSc lays out a vector). A fixed DOF stays in the system as a
 * row s * identity with its column dropped (symmetric, no renumbering): it solves for the
 * correction to the fixed values, which is zero. The FE rows are the sum of the slabs'
 * shares (cupid_arlequin_assemble() on a slab), reduced after each product. */
typedef struct {
  const cupid_linear_operator *A;
  const cupid_dirichlet_t *bc; /* local */
  cupid_int n, n_pd, pd0, pd1;  /* local DOFs, local PD DOFs, owned local PD DOFs [pd0, pd1) */
  PetscInt g0, nloc;           /* owned global DOFs [g0, g0 + nloc) */
  PetscInt fe_global;          /* global index of the first FE DOF */
  int fe_owner;                /* this rank owns the FE DOFs */
  double s;                    /* diagonal of the fixed rows */
  double *xw, *yw;             /* local work vectors */
  VecScatter halo;             /* global x -> every local DOF */
  Vec xl;
} slab_ctx;

/* Global DOF of local DOF d. */
static PetscInt slab_global(const slab_ctx *c, cupid_int d) {
  return d < c->n_pd ? (PetscInt)(3 * c->A->part->first_global + d)
                     : c->fe_global + (PetscInt)(d - c->n_pd);
}

/* y = A x on the owned PD rows and the whole FE rows (summed over the ranks). */
static cupid_status slab_product(const cupid_linear_operator *A, const double *x, double *y) {
  const cupid_pd_grid_partition *p = A->part;
  CUPID_CALL(A->apply_rows(A->ctx, x, 3 * p->owned_first, 3 * p->owned_last, y));
  CUPID_CALL(A->apply_rows(A->ctx, x, A->n_pd_dofs, A->n, y));
  int n_fe = (int)(A->n - A->n_pd_dofs);
  CUPID_CHECK(MPI_Allreduce(MPI_IN_PLACE, y + A->n_pd_dofs, n_fe, MPI_DOUBLE, MPI_SUM,
                            PETSC_COMM_WORLD) == MPI_SUCCESS,
              CUPID_ERR_NUMERIC, "MPI_Allreduce of the FE rows failed");
  return CUPID_SUCCESS;
}

/* x (global) -> c->xl (every local DOF). */
static PetscErrorCode slab_gather(slab_ctx *c, Vec x) {
  PetscCall(VecScatterBegin(c->halo, x, c->xl, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(c->halo, x, c->xl, INSERT_VALUES, SCATTER_FORWARD));
  return 0;
}

/* The owned entries of the local vector v into the PETSc array a. */
static void slab_owned(const slab_ctx *c, const double *v, PetscScalar *a) {
  PetscInt k = 0;
  for (cupid_int d = c->pd0; d < c->pd1; d++) a[k++] = v[d];
  if (c->fe_owner)
    for (cupid_int d = c->n_pd; d < c->n; d++) a[k++] = v[d];
}

static PetscErrorCode slab_mult(Mat M, Vec x, Vec y) {
  slab_ctx *c;
  const PetscScalar *xa;
  PetscScalar *ya;
  PetscCall(MatShellGetContext(M, &c));
  PetscCall(slab_gather(c, x));
  PetscCall(VecGetArrayRead(c->xl, &xa));
  for (cupid_int d = 0; d < c->n; d++) c->xw[d] = c->bc->fixed[d] ? 0.0 : xa[d];
  cupid_status st = slab_product(c->A, c->xw, c->yw);
  if (st != CUPID_SUCCESS)
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "coupled operator: %s", cupid_error_message());
  for (cupid_int d = 0; d < c->n; d++)
    if (c->bc->fixed[d]) c->yw[d] = c->s * xa[d];
  PetscCall(VecRestoreArrayRead(c->xl, &xa));
  PetscCall(VecGetArray(y, &ya));
  slab_owned(c, c->yw, ya);
  PetscCall(VecRestoreArray(y, &ya));
  return 0;
}

/* Row counts of the preconditioner's owned rows, split into the diagonal and off-diagonal
 * blocks of MPIAIJ: the owned PD rows from this slab, the FE rows summed over the slabs
 * (an over-count: each slab's FE columns are counted, capped at the row's length). */
static cupid_status slab_counts(const slab_ctx *c, const cupid_csr_t *P, PetscInt *dnz,
                                PetscInt *onz, PetscInt N) {
  const int bs = P->bs;
  const cupid_int n_fe = c->n - c->n_pd;
  double *fe = NULL; /* per FE row: columns in the owner's range, the others */
  CUPID_CALL(cupid_calloc((size_t)(2 * n_fe) + 1, sizeof *fe, "preconditioner row counts", &fe));
  for (cupid_int R = 0; R < P->nrows; R++)
    for (int a = 0; a < bs; a++) {
      cupid_int d = R * bs + a;
      int pd_row = d >= c->pd0 && d < c->pd1, fe_row = d >= c->n_pd;
      if ((!pd_row && !fe_row) || c->bc->fixed[d]) continue;
      cupid_int din = 0, dout = 0;
      for (cupid_int k = P->rowptr[R]; k < P->rowptr[R + 1]; k++)
        for (int b = 0; b < bs; b++) {
          cupid_int e = P->col[k] * bs + b;
          if (c->bc->fixed[e]) continue;
          PetscInt g = slab_global(c, e);
          /* FE rows belong to the FE owner: its FE columns are diagonal, a PD column may lie
           * in its range or not (count it in both) */
          if (fe_row) din++, dout += e < c->n_pd;
          else if (g >= c->g0 && g < c->g0 + c->nloc) din++;
          else dout++;
        }
      if (pd_row) dnz[d - c->pd0] = (PetscInt)din, onz[d - c->pd0] = (PetscInt)dout;
      else fe[2 * (d - c->n_pd)] = (double)din, fe[2 * (d - c->n_pd) + 1] = (double)dout;
    }
  cupid_status st = CUPID_SUCCESS;
  if (MPI_Allreduce(MPI_IN_PLACE, fe, (int)(2 * n_fe), MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD) !=
      MPI_SUCCESS)
    st = CUPID_ERROR(CUPID_ERR_NUMERIC, "MPI_Allreduce of the row counts failed");
  if (st == CUPID_SUCCESS && c->fe_owner)
    for (cupid_int i = 0; i < n_fe; i++) {
      PetscInt k = c->pd1 - c->pd0 + (PetscInt)i;
      double din = fe[2 * i], dout = fe[2 * i + 1];
      dnz[k] = (PetscInt)(din > (double)c->nloc ? (double)c->nloc : din) + 1;
      onz[k] = (PetscInt)(dout > (double)(N - c->nloc) ? (double)(N - c->nloc) : dout);
    }
  for (PetscInt k = 0; k < c->nloc; k++)
    if (dnz[k] == 0) dnz[k] = 1; /* a fixed row's diagonal */
  cupid_free(&fe);
  return st;
}

/* The preconditioner matrix: this slab's rows of P in global numbering (ADD_VALUES: the FE
 * rows' shares meet on their owner), fixed rows s * identity, fixed columns dropped. */
static cupid_status slab_matrix(const slab_ctx *c, const cupid_csr_t *P, PetscInt N, Mat *out) {
  cupid_status st = CUPID_SUCCESS;
  const int bs = P->bs;
  aij_rows r = {0};
  Mat M = NULL;
  CUPID_TRY(aij_rows_alloc(c->nloc, block_row_max(P), &r));
  CUPID_TRY(slab_counts(c, P, r.dnz, r.onz, N));
  CUPID_TRY(create_aij(c->nloc, N, r.dnz, r.onz, &M));
  for (cupid_int R = 0; R < P->nrows; R++)
    for (int a = 0; a < bs; a++) {
      cupid_int d = R * bs + a;
      if (!(d >= c->pd0 && d < c->pd1) && d < c->n_pd) continue; /* a halo row */
      PetscInt row = slab_global(c, d), len = 0;
      if (c->bc->fixed[d]) {
        if (d < c->n_pd || c->fe_owner) PTRY(MatSetValue(M, row, row, c->s, ADD_VALUES));
        continue;
      }
      for (cupid_int k = P->rowptr[R]; k < P->rowptr[R + 1]; k++)
        for (int b = 0; b < bs; b++) {
          cupid_int e = P->col[k] * bs + b;
          double v = P->val[(size_t)k * bs * bs + a * bs + b];
          /* an FE row's share holds the beam's pattern on every slab but its values only on
           * the last: the zeros are not sent to the owner */
          if (c->bc->fixed[e] || (d >= c->n_pd && v == 0.0)) continue;
          r.cols[len] = slab_global(c, e);
          r.vals[len++] = v;
        }
      PTRY(MatSetValues(M, 1, &row, len, r.cols, r.vals, ADD_VALUES));
    }
  CUPID_TRY(finish_aij(&M, out));
cleanup:
  if (M) MatDestroy(&M);
  aij_rows_free(&r);
  return st;
}

/* The fixed rows' diagonal: the mean |diagonal| of P over the free owned PD DOFs of all
 * ranks (the scale of the other rows, so the fixed rows neither dominate nor vanish). */
static double slab_fixed_scale(const slab_ctx *c, const cupid_csr_t *P) {
  double sum[2] = {0.0, 0.0};
  for (cupid_int d = c->pd0; d < c->pd1; d++) {
    if (c->bc->fixed[d]) continue;
    const double *blk = cupid_csr_find((cupid_csr)P, d / 3, d / 3);
    if (blk) sum[0] += fabs(blk[4 * (d % 3)]), sum[1] += 1.0;
  }
  MPI_Allreduce(MPI_IN_PLACE, sum, 2, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
  return sum[1] > 0 && sum[0] > 0 ? sum[0] / sum[1] : 1.0;
}

/* The scatter from the global vector x to every local DOF. */
static cupid_status slab_halo(slab_ctx *c, Vec x) {
  cupid_status st = CUPID_SUCCESS;
  PetscInt *idx = NULL;
  IS from = NULL;
  CUPID_CALL(cupid_malloc((size_t)c->n + 1, sizeof *idx, "halo indices", &idx));
  for (cupid_int d = 0; d < c->n; d++) idx[d] = slab_global(c, d);
  PTRY(ISCreateGeneral(PETSC_COMM_SELF, (PetscInt)c->n, idx, PETSC_USE_POINTER, &from));
  PTRY(VecCreateSeq(PETSC_COMM_SELF, (PetscInt)c->n, &c->xl));
  PTRY(VecScatterCreate(x, from, c->xl, NULL, &c->halo));
cleanup:
  if (from) ISDestroy(&from);
  cupid_free(&idx);
  return st;
}

/* A kept solve on the slab layout (solvers.h, cupid_krylov_solver): the operator (a copy, its
 * partition the caller's or, on one process, the whole grid as one part), the shell and the
 * set-up KSP with its preconditioner. */
struct cupid_krylov_solver_private {
  cupid_linear_operator A;
  cupid_pd_grid_partition whole; /* the one part of a whole grid on one process */
  slab_ctx c;
  ksp_objects obj;
  PetscInt max_it;
  double setup_s; /* given to the first solve's info (time_factor) */
};

cupid_status cupid_krylov_solver_create(const cupid_linear_operator *A, const cupid_csr_t *P,
                                        const cupid_dirichlet_t *bc,
                                        const cupid_krylov_options *opts,
                                        cupid_krylov_solver *out) {
  *out = NULL;
  CUPID_CHECK(A && A->apply_rows && P && bc, CUPID_ERR_ARGUMENT,
              "a kept Krylov solve needs an operator with apply_rows, a preconditioner and conditions");
  CUPID_CHECK(bc->n == A->n && P->nrows * P->bs == A->n, CUPID_ERR_ARGUMENT,
              "operator (%lld DOFs), preconditioner (%lld) and conditions (%lld) differ",
              (long long)A->n, (long long)(P->nrows * P->bs), (long long)bc->n);
  PetscBool init = PETSC_FALSE;
  if (PetscInitialized(&init) || !init)
    CUPID_CHECK(PetscInitializeNoArguments() == 0, CUPID_ERR_UNSUPPORTED,
                "PETSc could not be initialised");
  PetscMPIInt size = 1;
  MPI_Comm_size(PETSC_COMM_WORLD, &size);
  const int slab = A->part && A->part->parts > 1;
  CUPID_CHECK(slab ? A->part->parts == size : size == 1, CUPID_ERR_ARGUMENT,
              "a kept Krylov solve of %d slab(s) on %d MPI ranks (a whole model: one rank)",
              slab ? A->part->parts : 1, (int)size);
  cupid_krylov_solver S = NULL;
  CUPID_CALL(cupid_calloc(1, sizeof *S, "Krylov solver", &S));
  cupid_status st = CUPID_SUCCESS;
  const double t0 = cupid_wtime();
  S->A = *A;
  if (!slab) {
    const cupid_int nodes = A->n_pd_dofs / 3;
    S->whole = (cupid_pd_grid_partition){.global_nodes = nodes, .owned_last = nodes, .parts = 1};
    S->A.part = &S->whole;
  }
  const cupid_pd_grid_partition *p = S->A.part;
  slab_ctx *c = &S->c;
  *c = (slab_ctx){.A = &S->A, .bc = bc, .n = A->n, .n_pd = A->n_pd_dofs,
                  .pd0 = 3 * p->owned_first, .pd1 = 3 * p->owned_last,
                  .fe_owner = p->part == p->parts - 1};
  const PetscInt N = (PetscInt)(3 * p->global_nodes + (A->n - A->n_pd_dofs));
  c->g0 = (PetscInt)(3 * (p->first_global + p->owned_first));
  c->nloc = (PetscInt)(c->pd1 - c->pd0) + (c->fe_owner ? (PetscInt)(A->n - A->n_pd_dofs) : 0);
  c->fe_global = (PetscInt)(3 * p->global_nodes);
  CUPID_TRY(cupid_calloc((size_t)c->n + 1, sizeof *c->xw, "work vector", &c->xw));
  CUPID_TRY(cupid_calloc((size_t)c->n + 1, sizeof *c->yw, "work vector", &c->yw));
  c->s = slab_fixed_scale(c, P);
  PTRY(VecCreateMPI(PETSC_COMM_WORLD, c->nloc, N, &S->obj.b));
  PTRY(VecDuplicate(S->obj.b, &S->obj.x));
  CUPID_TRY(slab_halo(c, S->obj.x));
  PTRY(MatCreateShell(PETSC_COMM_WORLD, c->nloc, c->nloc, N, N, c, &S->obj.S));
  PTRY(MatShellSetOperation(S->obj.S, MATOP_MULT, (void (*)(void))slab_mult));
  CUPID_TRY(slab_matrix(c, P, N, &S->obj.Pm));
  const PetscInt pd_owned = (PetscInt)(c->pd1 - c->pd0);
  const ksp_fields fields = {c->g0, c->g0 + pd_owned, c->g0 + pd_owned, c->g0 + c->nloc, 1};
  CUPID_TRY(configure_ksp(&S->A, opts, &fields, &S->obj));
  /* the factor is kept as the operator changes (bonds break, DOFs are held) */
  PTRY(KSPSetReusePreconditioner(S->obj.ksp, PETSC_TRUE));
  PetscReal rtol, atol, dtol;
  PTRY(KSPGetTolerances(S->obj.ksp, &rtol, &atol, &dtol, &S->max_it));
  S->setup_s = cupid_wtime() - t0;
  *out = S;
  S = NULL;
cleanup:
  cupid_krylov_solver_destroy(&S);
  return st;
}

cupid_status cupid_krylov_solver_solve(cupid_krylov_solver S, const double *f, int guess,
                                       double *u, cupid_solve_info *info) {
  cupid_status st = CUPID_SUCCESS;
  cupid_solve_info inf;
  memset(&inf, 0, sizeof inf);
  CUPID_CHECK(S && f && u, CUPID_ERR_ARGUMENT, "cupid_krylov_solver_solve: NULL argument");
  slab_ctx *c = &S->c;
  const cupid_dirichlet_t *bc = c->bc;
  ksp_objects *obj = &S->obj;
  PetscReal rtol, atol, dtol;
  PetscInt maxit;
  PTRY(KSPGetTolerances(obj->ksp, &rtol, &atol, &dtol, &maxit));
  PTRY(KSPSetTolerances(obj->ksp, rtol, atol, dtol, S->max_it));

  /* b = f - A u_c on the free owned DOFs, 0 on the fixed ones; x = u's free values or 0 (the
   * fixed rows solve for the correction to the prescribed values: 0) */
  for (cupid_int d = 0; d < c->n; d++) c->xw[d] = bc->fixed[d] ? bc->value[d] : 0.0;
  CUPID_TRY(slab_product(&S->A, c->xw, c->yw));
  for (cupid_int d = 0; d < c->n; d++) {
    c->yw[d] = bc->fixed[d] ? 0.0 : f[d] - c->yw[d];
    c->xw[d] = guess && !bc->fixed[d] ? u[d] : 0.0;
  }
  PetscScalar *ba, *xa0;
  PTRY(VecGetArray(obj->b, &ba));
  slab_owned(c, c->yw, ba);
  PTRY(VecRestoreArray(obj->b, &ba));
  PTRY(VecGetArray(obj->x, &xa0));
  slab_owned(c, c->xw, xa0);
  PTRY(VecRestoreArray(obj->x, &xa0));
  PetscReal bnorm;
  PTRY(VecNorm(obj->b, NORM_2, &bnorm));
  /* from a guess, PETSc's rtol is still relative to |b|: the same target as from zero */
  PTRY(KSPSetInitialGuessNonzero(obj->ksp, guess ? PETSC_TRUE : PETSC_FALSE));
  CUPID_TRY(run_ksp(obj->ksp, &S->A, obj->b, obj->x, &inf));
  inf.time_factor = S->setup_s; /* the factorisation: charged to the first solve */
  S->setup_s = 0.0;
  CUPID_TRY(refine_true_residual(obj->ksp, obj->S, obj->b, obj->x, &inf));

  /* u = u_c + x on every local DOF (a solve that failed: its last iterate, where a part that
   * lost its support ran away); the true residual over the free owned DOFs, recomputed */
  const PetscScalar *xa;
  PTRY(slab_gather(c, obj->x));
  PTRY(VecGetArrayRead(c->xl, &xa));
  for (cupid_int d = 0; d < c->n; d++) u[d] = bc->fixed[d] ? bc->value[d] : xa[d];
  PTRY(VecRestoreArrayRead(c->xl, &xa));
  CUPID_TRY(slab_product(&S->A, u, c->yw));
  double sums[3] = {0.0, 0.0, 0.0}; /* |r|^2, |f|^2, free DOFs */
  for (cupid_int d = 0; d < c->n; d++) {
    int owned = (d >= c->pd0 && d < c->pd1) || (d >= c->n_pd && c->fe_owner);
    if (!owned || bc->fixed[d]) continue;
    sums[0] += (f[d] - c->yw[d]) * (f[d] - c->yw[d]);
    sums[1] += f[d] * f[d];
    sums[2] += 1.0;
  }
  MPI_Allreduce(MPI_IN_PLACE, sums, 3, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
  double scale = bnorm > 0 ? (double)bnorm : sqrt(sums[1]);
  inf.residual = scale > 0 ? sqrt(sums[0]) / scale : sqrt(sums[0]);
  inf.n = (cupid_int)sums[2];
  st = not_converged(&inf);
cleanup:
  if (info) *info = inf;
  return st;
}

void cupid_krylov_solver_limit(cupid_krylov_solver S, int max_iterations) {
  if (S && max_iterations > 0 && max_iterations < S->max_it) S->max_it = max_iterations;
}

void cupid_krylov_solver_destroy(cupid_krylov_solver *S) {
  if (!S || !*S) return;
  cupid_krylov_solver s = *S;
  ksp_objects_destroy(&s->obj);
  if (s->c.halo) VecScatterDestroy(&s->c.halo);
  if (s->c.xl) VecDestroy(&s->c.xl);
  cupid_free(&s->c.xw);
  cupid_free(&s->c.yw);
  cupid_free(S);
}

/* The PD grid in slabs, one a rank (slab_ctx above): the kept solve, once. */
static cupid_status solve_slabs(const cupid_linear_operator *A, const cupid_csr_t *P,
                                const cupid_dirichlet_t *bc, const double *f, double *u,
                                const cupid_krylov_options *opts,
                                cupid_solve_info *info) {
  cupid_krylov_solver S = NULL;
  if (info) memset(info, 0, sizeof *info);
  CUPID_CALL(cupid_krylov_solver_create(A, P, bc, opts, &S));
  cupid_status st = cupid_krylov_solver_solve(S, f, 0, u, info);
  cupid_krylov_solver_destroy(&S);
  return st;
}

static int is_slab(const cupid_linear_operator *A) { return A->part && A->part->parts > 1; }

cupid_status cupid_krylov_solve(const cupid_linear_operator *A, const cupid_csr_t *P,
                                const cupid_dirichlet_t *bc, const double *f, double *u,
                                const cupid_krylov_options *opts,
                                cupid_solve_info *info) {
  if (info) memset(info, 0, sizeof *info);
  CUPID_CHECK(A && A->apply && P && bc && f && u, CUPID_ERR_ARGUMENT, "Krylov solve: NULL argument");
  CUPID_CHECK(bc->n == A->n && P->nrows * P->bs == A->n, CUPID_ERR_ARGUMENT,
              "operator (%lld DOFs), preconditioner (%lld) and conditions (%lld) differ",
              (long long)A->n, (long long)(P->nrows * P->bs), (long long)bc->n);
  CUPID_CHECK(!is_slab(A) || A->apply_rows, CUPID_ERR_ARGUMENT,
              "Krylov solve: an operator on a slab needs apply_rows");
  PetscBool init = PETSC_FALSE;
  if (PetscInitialized(&init) || !init)
    CUPID_CHECK(PetscInitializeNoArguments() == 0, CUPID_ERR_UNSUPPORTED,
                "PETSc could not be initialised");
  return is_slab(A) ? solve_slabs(A, P, bc, f, u, opts, info)
                    : solve_replicated(A, P, bc, f, u, opts, info);
}

cupid_status cupid_krylov_apply(const cupid_linear_operator *A, const double *x, double *y) {
  CUPID_CHECK(A && x && y, CUPID_ERR_ARGUMENT, "cupid_krylov_apply: NULL argument");
  return is_slab(A) ? slab_product(A, x, y) : A->apply(A->ctx, x, y);
}

#else

cupid_status cupid_krylov_solve(const cupid_linear_operator *A, const cupid_csr_t *P,
                                const cupid_dirichlet_t *bc, const double *f, double *u,
                                const cupid_krylov_options *opts,
                                cupid_solve_info *info) {
  (void)A, (void)P, (void)bc, (void)f, (void)u, (void)opts;
  if (info) memset(info, 0, sizeof *info);
  return CUPID_ERROR(CUPID_ERR_UNSUPPORTED,
                     "the matrix-free coupled solve needs the PETSc engine: configure with "
                     "-DCUPID_WITH_PETSC=ON");
}

cupid_status cupid_krylov_apply(const cupid_linear_operator *A, const double *x, double *y) {
  CUPID_CHECK(A && x && y, CUPID_ERR_ARGUMENT, "cupid_krylov_apply: NULL argument");
  CUPID_CHECK(!A->part || A->part->parts <= 1, CUPID_ERR_UNSUPPORTED,
              "an operator on a slab needs the PETSc engine (MPI)");
  return A->apply(A->ctx, x, y);
}

cupid_status cupid_krylov_solver_create(const cupid_linear_operator *A, const cupid_csr_t *P,
                                        const cupid_dirichlet_t *bc,
                                        const cupid_krylov_options *opts,
                                        cupid_krylov_solver *out) {
  (void)A, (void)P, (void)bc, (void)opts;
  *out = NULL;
  return CUPID_ERROR(CUPID_ERR_UNSUPPORTED,
                     "a kept matrix-free coupled solve needs the PETSc engine: configure with "
                     "-DCUPID_WITH_PETSC=ON");
}

cupid_status cupid_krylov_solver_solve(cupid_krylov_solver S, const double *f, int guess,
                                       double *u, cupid_solve_info *info) {
  (void)S, (void)f, (void)guess, (void)u;
  if (info) memset(info, 0, sizeof *info);
  return CUPID_ERROR(CUPID_ERR_UNSUPPORTED, "a kept matrix-free coupled solve needs the PETSc engine");
}

void cupid_krylov_solver_limit(cupid_krylov_solver S, int max_iterations) { (void)S, (void)max_iterations; }

void cupid_krylov_solver_destroy(cupid_krylov_solver *S) {
  if (S) *S = NULL;
}

#endif
