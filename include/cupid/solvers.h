/**
 * @file solvers.h
 * @brief Sparse matrices (scalar or 3x3-block CSR, 64-bit indices), Dirichlet
 *        conditions, and the embedded direct solvers (CHOLMOD for SPD, UMFPACK otherwise).
 *
 * Matrices are plain data (like cholmod_sparse): block CSR with block size bs (1 or 3),
 * rows/cols counted in blocks, column indices sorted within each row, values stored
 * block after block, each block row-major (bs*bs doubles).
 */
#ifndef CUPID_SOLVERS_H
#define CUPID_SOLVERS_H

#include "cupid/base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cupid_csr_s {
  cupid_int nrows, ncols; /**< in blocks */
  int bs;                 /**< block size: 1 or 3 */
  cupid_int *rowptr;      /**< nrows + 1 */
  cupid_int *col;         /**< rowptr[nrows] block column indices, sorted per row */
  double *val;            /**< rowptr[nrows] * bs * bs values */
} cupid_csr_t;
typedef cupid_csr_t *cupid_csr;

/** A matrix with the given pattern (copied; columns must be sorted per row), values zero. */
cupid_status cupid_csr_create(cupid_int nrows, cupid_int ncols, int bs, const cupid_int *rowptr,
                              const cupid_int *col, cupid_csr *A);

/** A scalar (bs = 1) matrix from triplets (i, j, v); duplicates are summed. */
cupid_status cupid_csr_from_triplets(cupid_int nrows, cupid_int ncols, cupid_int n,
                                     const cupid_int *i, const cupid_int *j, const double *v,
                                     cupid_csr *A);

void cupid_csr_destroy(cupid_csr *A);

/** Pointer to block (row, col) values, or NULL if not in the pattern (binary search). */
double *cupid_csr_find(const cupid_csr_t *A, cupid_int row, cupid_int col);

/** Row r's values set to zero (its pattern kept). */
void cupid_csr_zero_row(cupid_csr A, cupid_int r);

/** Row pr of P added into row r of A (one block size; A's row must hold every column of P's:
 *  an error otherwise, A's row then part-added). */
cupid_status cupid_csr_add_row(cupid_csr A, cupid_int r, const cupid_csr_t *P, cupid_int pr);

/** y = A x (OpenMP over rows). x has ncols*bs entries, y nrows*bs. */
void cupid_csr_matvec(const cupid_csr_t *A, const double *x, double *y);

/** y = A x where the caller knows that the block rows not marked are zero (their columns meet
 *  none of x's non-zeros: x a few prescribed values, the marked rows their neighbours). The
 *  marked rows (mark[r] != 0) are computed to the bit as cupid_csr_matvec() computes them. */
void cupid_csr_matvec_marked(const cupid_csr_t *A, const double *x, const unsigned char *mark,
                             double *y);

/** Only the scalar rows [d0, d1) of y = A x, where A's scalar row r is y[off + r] (a block
 *  of rows inside a longer vector, as a coupled operator's FE rows are); the other entries
 *  of y are left as they were. x has ncols*bs entries. OpenMP over block rows. */
void cupid_csr_matvec_rows(const cupid_csr_t *A, const double *x, cupid_int off, cupid_int d0,
                           cupid_int d1, double *y);

/** The same matrix with bs = 1. */
cupid_status cupid_csr_to_scalar(const cupid_csr_t *A, cupid_csr *S);

/** max |A_ij - A_ji| / max |A_ij| over the scalar entries (square matrices). */
double cupid_csr_asymmetry(const cupid_csr_t *A);

/** Number of stored scalar entries (nnz blocks * bs^2). */
cupid_int cupid_csr_nnz(const cupid_csr_t *A);

/** Bytes used by the matrix arrays. */
int64_t cupid_csr_bytes(const cupid_csr_t *A);

/** y = A^T x (serial scatter). x has nrows*bs entries, y ncols*bs. */
void cupid_csr_matvec_transpose(const cupid_csr_t *A, const double *x, double *y);

/** A deep copy of A. */
cupid_status cupid_csr_duplicate(const cupid_csr_t *A, cupid_csr *B);

/** Set every stored value to zero (keeps the pattern, e.g. before re-assembly). */
void cupid_csr_zero(cupid_csr_t *A);

/** A *= alpha. */
void cupid_csr_scale(cupid_csr_t *A, double alpha);

/** Y += alpha X for matrices with the same pattern (else CUPID_ERR_ARGUMENT), e.g. C = a M + b K. */
cupid_status cupid_csr_axpy(double alpha, const cupid_csr_t *X, cupid_csr_t *Y);

/** The scalar diagonal d (nrows*bs entries; 0 where not stored) of a square matrix. */
cupid_status cupid_csr_diagonal(const cupid_csr_t *A, double *d);

/** Dirichlet conditions on scalar DOFs. Fill fixed[]/value[], then cupid_dirichlet_finalize(). */
typedef struct cupid_dirichlet_s {
  cupid_int n;            /**< total scalar DOFs */
  unsigned char *fixed;   /**< n flags */
  double *value;          /**< n prescribed values (used where fixed) */
  cupid_int n_free;       /**< set by finalize */
  cupid_int *free_index;  /**< n: index among free DOFs, or -1 (set by finalize) */
} cupid_dirichlet_t;
typedef cupid_dirichlet_t *cupid_dirichlet;

/** Conditions on n DOFs, none fixed yet (free_index is the identity until finalize). */
cupid_status cupid_dirichlet_create(cupid_int n, cupid_dirichlet *bc);
/** Fix DOF @p dof to @p value (same as setting fixed[dof] and value[dof]); finalize afterwards. */
cupid_status cupid_dirichlet_fix(cupid_dirichlet bc, cupid_int dof, double value);
/** Number the free DOFs in increasing global order; rejects non-finite prescribed values. */
cupid_status cupid_dirichlet_finalize(cupid_dirichlet bc);
void cupid_dirichlet_destroy(cupid_dirichlet *bc);

/**
 * Reactions r = K u - f on the fixed DOFs of @p bc, 0 on the free ones (f may be NULL = 0).
 * Summing r over the x (y, z) components gives the total support force.
 */
cupid_status cupid_csr_reactions(const cupid_csr_t *K, const double *u, const double *f,
                                 const cupid_dirichlet_t *bc, double *r);

typedef enum { CUPID_MATRIX_SPD = 0, CUPID_MATRIX_GENERAL = 1 } cupid_matrix_kind;

/**
 * A factorisation whose smallest/largest pivot ratio (CHOLMOD: L_kk^2; UMFPACK: |U_kk| of the
 * row-scaled matrix) is below CUPID_DIRECT_PIVOT_TOL * max(n, 64), n the number of equations,
 * is taken as singular: the pivot is round-off rather than an exact zero. Measured on singular
 * symmetric grid Laplacians (64..27,000 equations) the ratio was at most ~1.1e-17 n (a margin
 * of ~100), on regular ones above 0.1. A stiffness contrast (or penalty factor) near
 * 1/(1.8e-15 n) would trip it. Strongly non-symmetric singular matrices can keep a larger
 * ratio; there the residual check (with an inconsistent load) is what catches them.
 */
#define CUPID_DIRECT_PIVOT_TOL 1.8e-15

/** What a direct solve did, for summary.json. */
typedef struct {
  const char *method;      /**< "cholmod" or "umfpack" */
  cupid_int n;             /**< equations solved (free DOFs) */
  cupid_int nnz_matrix;    /**< scalar non-zeros of the reduced matrix */
  double nnz_factor;       /**< non-zeros of the factor(s) */
  double time_factor, time_solve; /**< seconds (analysis counted in factor) */
  int64_t memory_factor;   /**< peak bytes reported by the library (0 = unknown) */
  double residual;         /**< ||K_ff u_f - b_f|| / ||b_f|| (0 when b_f = 0) */
  cupid_int failed_dof;    /**< global scalar DOF where factorisation broke down, or -1 */
  double flops_factor;     /**< floating-point operations of the factorisation (0 = unknown) */
  double pivot_ratio;      /**< min/max pivot magnitude (CHOLMOD: L_kk^2; UMFPACK: |U_kk|) */
  int refinements;         /**< iterative refinement steps done by cupid (direct: 0 or 1; Krylov: restarts from the true residual after the estimate met rtol) */
  double backward_error;   /**< |r|_inf / (|K_ff|_inf |u_f|_inf + |b_f|_inf): the failure test
                                (the solve fails above 1e-10) */
  /* Iterative (PETSc) solves only (issue 6); zero for the direct solvers. */
  int iterations;          /**< Krylov iterations */
  int ranks;               /**< MPI ranks that took part */
  int matrix_free;         /**< 1: PD operator applied matrix-free (MATSHELL) */
  char ksp_type[32], pc_type[32]; /**< PETSc KSP and PC types actually used */
  char converged_reason[48];      /**< PETSc's KSPConvergedReason name */
} cupid_solve_info;

/**
 * Solve K u = f with Dirichlet conditions: unknowns are the free DOFs, fixed DOFs take
 * bc->value; the system K_ff u_f = f_f - K_fc u_c is factored with CHOLMOD (SPD) or
 * UMFPACK (GENERAL) and checked: one step of iterative refinement when the relative residual
 * exceeds 1e-12, CUPID_ERR_NUMERIC when the normwise backward error stays above 1e-10 or the
 * relative residual above 1e-4 (a singular system with an inconsistent load).
 * A singular or indefinite K_ff gives CUPID_ERR_NUMERIC with info->failed_dof set; so do a
 * pivot ratio below the CUPID_DIRECT_PIVOT_TOL bound (a matrix singular up to round-off) and a
 * residual failure (failed_dof is then the DOF of the smallest pivot). A non-finite (NaN or
 * Inf) load vector entry, right-hand side f_f - K_fc u_c, entry of K_ff or solution entry is
 * CUPID_ERR_NUMERIC too, its message naming the cause and the first such DOF (failed_dof
 * stays -1: no factorisation broke down).
 * u (K->nrows*bs entries) receives the full solution. bc may be NULL (no fixed DOFs) and
 * info may be NULL. CHOLMOD uses one triangle of K_ff (K must be symmetric; an asymmetric
 * K shows up as a residual failure).
 */
cupid_status cupid_direct_solve(const cupid_csr_t *K, cupid_matrix_kind kind, const double *f,
                                const cupid_dirichlet_t *bc, double *u, cupid_solve_info *info);


/* ---- Reusable SPD factorisation (src/solvers/factor.c; added for dynamics, issue 5) ----
 * One CHOLMOD factorisation of K_ff, solved many times (implicit time stepping with a
 * constant step). cupid_direct_solve() is unchanged. */

/** A factorisation of the free-DOF block K_ff of an SPD matrix (opaque). */
typedef struct cupid_direct_factor_private *cupid_direct_factor;

/**
 * Factor K_ff (CHOLMOD LL', one triangle of K used; K symmetric) for the free DOFs of @p bc
 * (NULL: all free; bc must be finalized). K is copied: it may be freed afterwards.
 * CUPID_ERR_NUMERIC if K_ff is not positive definite or its pivot ratio is below the
 * CUPID_DIRECT_PIVOT_TOL bound; info (may be NULL) receives method, n, nnz, time_factor,
 * pivot_ratio, failed_dof.
 */
cupid_status cupid_direct_factor_create(const cupid_csr_t *K, const cupid_dirichlet_t *bc,
                                        cupid_direct_factor *F, cupid_solve_info *info);

/** As cupid_direct_factor_create() for @p kind SPD (CHOLMOD) or GENERAL (UMFPACK LU of K_ff;
 *  CUPID_ERR_NUMERIC on a zero pivot). */
cupid_status cupid_direct_factor_create_kind(const cupid_csr_t *K, cupid_matrix_kind kind,
                                             const cupid_dirichlet_t *bc,
                                             cupid_direct_factor *F, cupid_solve_info *info);
/** The free DOFs the factor solves for. */
cupid_int cupid_direct_factor_size(const cupid_direct_factor F);
/** The DOF (global numbering) of a factor's smallest pivot (LU: |U_kk|; Cholesky: L_kk^2, or
 *  |D_kk| once downdated): where a nearly singular matrix, whose factorisation passed the
 *  pivot bound but whose solves cannot be refined, is weakest (crack growth holds that node). */
cupid_status cupid_direct_factor_weakest_dof(const cupid_direct_factor F, cupid_int *dof);
/** Solve K_ff x = b in the free numbering (b and x of cupid_direct_factor_size() entries, the
 *  free DOFs in increasing global order; b and x must not alias). */
cupid_status cupid_direct_factor_solve_free(cupid_direct_factor F, const double *b, double *x);

/** As cupid_direct_factor_solve_free() for @p nrhs right-hand sides at once (b and x column
 *  after column, cupid_direct_factor_size() entries each; must not alias): a Cholesky factor
 *  is read once for all of them. */
cupid_status cupid_direct_factor_solve_free_many(cupid_direct_factor F, cupid_int nrhs,
                                                const double *b, double *x);

/**
 * Solve K_ff x_f = b_f for full-length vectors: b and x have K->nrows*bs entries, only the
 * free entries of b are read and only the free entries of x are written (the caller moves
 * K_fc u_c to the right-hand side if prescribed values are non-zero). b and x may alias.
 */
cupid_status cupid_direct_factor_solve(cupid_direct_factor F, const double *b, double *x);

/**
 * z = M^-1 r through the factor, restricted to the DOFs @p bc leaves free (a preconditioner:
 * crack growth's CG on its own factor, and on the kept twin's, whose nodes held since the
 * factorisation are fixed in @p bc but not in F): r read on those DOFs only, z written on
 * every DOF of bc, zero on the fixed ones. The principal part of an SPD factor's inverse, so
 * still SPD on the free DOFs. F's DOFs must be free in bc or fixed since (bc->n = F's rows).
 */
cupid_status cupid_direct_factor_solve_masked(cupid_direct_factor F, const cupid_dirichlet_t *bc,
                                            const double *r, double *z);

/**
 * Downdate an SPD factor (CHOLMOD's cholmod_updown): afterwards F factors K_ff - C_f C_f^T,
 * where C is n_full x r, given by columns (colptr[r + 1], rows: global DOFs, vals) and C_f its
 * free rows (rows on fixed DOFs are dropped). Each downdate costs about the length of the
 * elimination-tree paths of C's rows, far below a factorisation: a broken bond-based bond is a
 * rank-one term (quasi-static crack growth, src/problem/growth.c). The first call converts the
 * factor to simplicial LDL'. CUPID_ERR_NUMERIC when the result is not positive definite to the
 * CUPID_DIRECT_PIVOT_TOL bound (the factor must then be destroyed); CUPID_ERR_ARGUMENT for an
 * LU factor.
 */
cupid_status cupid_direct_factor_downdate(cupid_direct_factor F, cupid_int r, const cupid_int *colptr,
                                          const cupid_int *rows, const double *vals);

/**
 * Update an SPD factor: afterwards F factors K_ff + C_f C_f^T (C as for
 * cupid_direct_factor_downdate, whose checks it makes too). Crack growth ties a node that
 * completes a mechanism of a few nodes by a weak spring, sqrt(k) e_d per DOF d (growth.c).
 */
cupid_status cupid_direct_factor_update(cupid_direct_factor F, cupid_int r, const cupid_int *colptr,
                                        const cupid_int *rows, const double *vals);

/** The DOF (global numbering) whose pivot the last cupid_direct_factor_update() or _downdate()
 *  of @p F left non-positive or below the pivot bound, where it returned CUPID_ERR_NUMERIC; -1
 *  after one that passed. Crack growth ties that DOF's node before it factorises again
 *  (growth.c): the downdate names the node a factorisation would break down at. */
cupid_int cupid_direct_factor_failed_dof(const cupid_direct_factor F);

/**
 * Hold DOFs in an SPD factor: the rows of the DOFs that @p bc fixes and the factor still solves
 * for are deleted (CHOLMOD's cholmod_rowdel: their row and column become the identity's), so
 * that F factors the K_ff of @p bc's free DOFs (the identity on the held rows) without a
 * factorisation: crack growth holds a node that breaking left loose before it downdates the
 * bonds, where the downdate alone would leave the matrix singular. Later downdates drop the
 * held rows, as fixed ones; cupid_direct_factor_solve() neither reads nor writes them (the free
 * numbering's solves see the identity there). *held: the DOFs held by this call. The first
 * call that holds converts the factor to simplicial LDL'. CUPID_ERR_ARGUMENT for an LU factor.
 */
cupid_status cupid_direct_factor_hold(cupid_direct_factor F, const cupid_dirichlet_t *bc,
                                      cupid_int *held);

/** Destroy and set *F to NULL (NULL-safe). */
void cupid_direct_factor_destroy(cupid_direct_factor *F);
/* ---- end of the reusable factorisation block ---- */


/* ---- PETSc/MPI engine (src/solvers/petsc.c; issue 6) ----
 * Optional: with CUPID_HAVE_PETSC == 0 (cupid_config.h) every function below is a stub and the
 * solves return CUPID_ERR_UNSUPPORTED. Every rank holds the whole (replicated) model, except for
 * 3D static models on several ranks solved matrix-free (PD-only: cupid_petsc_solve_pd; coupled
 * by fictitious nodes or Arlequin: cupid_krylov_solve in coupling.h), where each rank holds
 * one slab of the PD grid (cupid_pd_grid_partition). The solves are collective over
 * PETSC_COMM_WORLD. */

/** 1 when cupid was built with PETSc (CMake option CUPID_WITH_PETSC). */
int cupid_petsc_available(void);

/** 1 when the process was started by an MPI launcher with more than one rank (environment). */
int cupid_petsc_launched_parallel(void);

/**
 * Initialise PETSc (and MPI) once; later calls do nothing. argv[0] is the program name, the rest
 * PETSc run-time options (-ksp_type, -pc_type, -log_view, ...): they reach every KSP through
 * KSPSetFromOptions. argv must stay valid until cupid_petsc_finalize(). argv NULL: the arguments
 * given to cupid_petsc_set_args() (none if never called). PETSc's own error printing is replaced
 * by cupid's messages.
 */
/** Remember the PETSc options for a later (lazy) cupid_petsc_initialize(0, NULL). */
void cupid_petsc_set_args(int argc, char **argv);

cupid_status cupid_petsc_initialize(int argc, char **argv);
/** 1 between cupid_petsc_initialize() and cupid_petsc_finalize(). */
int cupid_petsc_initialized(void);
/** Finalise PETSc (and MPI) if it was initialised here. */
void cupid_petsc_finalize(void);
/** This process's rank in PETSC_COMM_WORLD (0 when PETSc is not initialised). */
int cupid_petsc_rank(void);
/** Number of ranks (1 when PETSc is not initialised). */
int cupid_petsc_size(void);
/** The largest of @p v over all ranks (collective; @p v itself when not initialised). */
int cupid_petsc_max_int(int v);
/** 1 when the PETSc run-time option @p name (e.g. "-cupid_coupled_assembled") was given
 *  (0 when PETSc is not initialised or absent). */
int cupid_petsc_has_option(const char *name);
/** Sums over all ranks of @p n doubles, in place (collective; nothing when not initialised). */
void cupid_petsc_sum_doubles(double *v, int n);
/** Maxima over all ranks of @p n doubles, in place (collective; nothing when not initialised). */
void cupid_petsc_max_doubles(double *v, int n);
/**
 * Concatenate every rank's @p count doubles on rank 0, in rank order (MPI_Gatherv; collective):
 * rank 0 passes @p root with room for the total, the others NULL. Without PETSc (or one rank)
 * a copy. CUPID_ERR_UNSUPPORTED when a rank's count exceeds 2^31 - 1 (MPI's int counts).
 */
cupid_status cupid_petsc_gather_root(const double *local, cupid_int count, double *root);
/** Abort every rank with exit status @p code (MPI_Abort; plain exit when not initialised). */
void cupid_petsc_abort(int code);

/** The copies (halo) of a distributed vector: each rank holds n local entries, owns
 *  [owned_first, owned_last) of them, and local entry d is global entry global_first + d; the
 *  owned ranges follow the rank order (as the slabs of a grid do). */
typedef struct cupid_petsc_halo_s *cupid_petsc_halo;
/** Create the exchange (collective; CUPID_ERR_UNSUPPORTED without PETSc). */
cupid_status cupid_petsc_halo_create(cupid_int n, cupid_int owned_first, cupid_int owned_last,
                                     cupid_int global_first, cupid_petsc_halo *h);
/** Overwrite x's entries outside the owned range with their owners' values (collective). */
cupid_status cupid_petsc_halo_update(cupid_petsc_halo h, double *x);
void cupid_petsc_halo_destroy(cupid_petsc_halo *h);

/** Options of the PETSc solves (zero-initialise; every field optional). */
typedef struct {
  /** Node coordinates, 3 per node, for DOFs 3i..3i+2, i < n_coord_nodes; when they cover every
   *  DOF (3 n_coord_nodes = K->nrows * bs) GAMG gets the rigid-body near null space. */
  const double *coords;
  cupid_int n_coord_nodes;
} cupid_petsc_options;

/**
 * The contract of cupid_direct_solve() with PETSc KSP: K is replicated (every rank passes the
 * same K, f, bc); each rank inserts its block of rows into an MPIAIJ matrix (block size 3 when
 * the DOFs come in threes) with the Dirichlet DOFs as scaled identity rows, columns eliminated
 * into the right-hand side (symmetry kept). Defaults: SPD -> CG + GAMG (rigid-body near null
 * space when opts->coords covers every DOF), GENERAL -> GMRES(200), right-preconditioned,
 * + block Jacobi/ILU(0) (measured in docs/scale.md);
 * rtol 1e-12 on the unpreconditioned residual; every -ksp_* / -pc_* option overrides them.
 * CUPID_ERR_NUMERIC when the KSP diverges (reason and iterations in the message) or the true
 * relative residual exceeds max(100 rtol, 1e-10). u (full length) holds the solution on every rank.
 * info->method is "petsc"; iterations, ranks, ksp_type, pc_type, converged_reason are set.
 */
cupid_status cupid_petsc_solve(const cupid_csr_t *K, cupid_matrix_kind kind, const double *f,
                               const cupid_dirichlet_t *bc, double *u,
                               const cupid_petsc_options *opts, cupid_solve_info *info);

/* The matrix-free PD solve: cupid_petsc_solve_nodes() below, over a cupid_node_operator (pd.h's
 * cupid_pd_node_operator() makes one of a PD operator). */

/**
 * Where a grid sits in the whole union (issue 6). A slab grid (options.parts > 1) holds the
 * z layers [k0 - halo, k1 + halo) of the union, where part p owns the layers [k0, k1): the
 * z layers are split into parts contiguous slabs of nearly equal node counts (each at least
 * one layer). Nodes are numbered x fastest and z slowest in the union and in the slab alike,
 * so local node l is global node first_global + l, and the owned nodes are the local range
 * [owned_first, owned_last). A whole grid has first_global 0 and owns all its nodes.
 */
typedef struct {
  cupid_int global_nodes;  /**< nodes of the whole union */
  cupid_int first_global;  /**< global index of local node 0 */
  cupid_int owned_first, owned_last; /**< owned local nodes */
  int parts, part;
  int halo_layers;         /**< as the grid's options gave it */
  double own_z[2];         /**< the owned layers' z range (their outer cell faces) */
} cupid_pd_grid_partition;

/* ---- Matrix-free Krylov solves on PETSc (src/solvers/krylov.c) ---- */

/** Options of a Krylov solve of a matrix-free system. */
typedef struct {
  double rtol;            /**< |b - A u| / |b| on the free DOFs (right preconditioning, so the
                               true residual); <= 0: 1e-10 */
  int max_it;             /**< <= 0: 2000 */
  int restart;            /**< GMRES restart; <= 0: 200 */
  const char *pc;         /**< PETSc PC type for the cheap matrix ("lu", "ilu", "gamg",
                               "hypre"; "fieldsplit": two fields "pd" and "fe", sub-solvers
                               from -fieldsplit_pd_* / -fieldsplit_fe_*; NULL: "lu", or
                               "cholesky" for a symmetric operator); run-time options
                               (-ksp_*, -pc_*) override */
  const char *factor_package; /**< for lu/ilu: "umfpack", "mumps", "petsc" (NULL: umfpack on
                                   one rank, mumps on several); cholesky: mumps */
} cupid_krylov_options;


/** A linear operator for cupid_krylov_solve(): n DOFs, y = A x, and optionally only the rows
 *  [d0, d1) of it (what an MPI rank computes; NULL: the whole product). */
typedef struct {
  cupid_int n;
  cupid_status (*apply)(void *ctx, const double *x, double *y);
  cupid_status (*apply_rows)(void *ctx, const double *x, cupid_int d0, cupid_int d1, double *y);
  void *ctx;
  int symmetric;        /**< 1: symmetric positive definite (CG), 0: GMRES */
  cupid_int n_pd_dofs;  /**< DOFs [0, n_pd_dofs) form the "pd" field of pc fieldsplit */
  /** NULL or a whole grid: the operator is replicated on every rank. A slab of a partitioned
   *  grid (issue 6, parts = the MPI ranks): the operator holds this rank's slab, n = 3 per
   *  slab node (owned and halo) + the FE DOFs, and apply_rows gives the owned PD rows and
   *  this slab's share of the FE rows, whose sum over the slabs is the whole FE rows. */
  const cupid_pd_grid_partition *part;
} cupid_linear_operator;

/** y = A x. Replicated: the whole product. A slab (A->part): its owned PD rows and the whole
 *  FE rows, summed over the ranks (collective); the halo rows of y are left as they were. */
cupid_status cupid_krylov_apply(const cupid_linear_operator *A, const double *x, double *y);

/**
 * Solve A u = f as cupid_coupling_krylov_solve() does, for any matrix-free operator: CG when
 * A->symmetric (the unpreconditioned residual norm; the preconditioner from @p P must be
 * symmetric too: LU of a symmetric P is), else right-preconditioned GMRES. On a slab
 * (A->part), @p P, @p bc, @p f and @p u are the slab's (local DOFs as A's): P's owned PD rows
 * and its share of the FE rows (summed over the ranks, like A's), bc on every local DOF (the
 * halo's as on their owner), f on the owned DOFs and the FE DOFs (the same on every rank);
 * u gets every local DOF (owned, halo and FE), the same FE part on every rank.
 */
cupid_status cupid_krylov_solve(const cupid_linear_operator *A, const cupid_csr_t *P,
                                const cupid_dirichlet_t *bc, const double *f, double *u,
                                const cupid_krylov_options *opts,
                                cupid_solve_info *info);

/**
 * The solve of cupid_krylov_solve() on the slab layout (fixed DOFs kept as scaled identity
 * rows, read from @p bc at every product) kept for a sequence of systems whose operator
 * changes a little between them (crack growth: bonds break, nodes are held): the shell, the
 * preconditioner matrix and its factor are built once by _create and reused by every _solve
 * (the factor stays the intact system's, still symmetric positive definite). A slab (A->part,
 * parts = the MPI ranks) or a whole model on one process; @p A is copied, @p bc must outlive
 * the solver. _solve starts from u (guess != 0: its free values) or from 0, to the same
 * absolute target |b - A u| <= rtol |b| either way; u gets every local DOF. info->time_factor
 * of the first solve is the set-up. A solve that does not converge (CUPID_ERR_NUMERIC) leaves
 * the Krylov method's last iterate in u. Collective. Builds without PETSc: UNSUPPORTED.
 */
typedef struct cupid_krylov_solver_private *cupid_krylov_solver;
cupid_status cupid_krylov_solver_create(const cupid_linear_operator *A, const cupid_csr_t *P,
                                        const cupid_dirichlet_t *bc,
                                        const cupid_krylov_options *opts,
                                        cupid_krylov_solver *out);
cupid_status cupid_krylov_solver_solve(cupid_krylov_solver S, const double *f, int guess,
                                       double *u, cupid_solve_info *info);
/** Lower the solves' iteration limit to @p max_iterations (as cupid_petsc_nodes_solver_limit). */
void cupid_krylov_solver_limit(cupid_krylov_solver S, int max_iterations);
void cupid_krylov_solver_destroy(cupid_krylov_solver *S);


/* ---- end of the PETSc block ---- */


/**
 * An operator on nodes of 3 DOFs (a PD operator, local to a whole grid or a slab with its
 * halo) as the matrix-free PETSc solve reads it: products of row ranges, the node range those
 * rows read, the diagonal blocks, and the rows of a cheap preconditioner matrix. The solvers
 * see it only through these functions (src/pd fills it: cupid_pd_node_operator in pd.h).
 */
typedef struct cupid_node_operator cupid_node_operator;
struct cupid_node_operator {
  const void *op, *grid, *materials; /**< the provider's objects */
  cupid_int nodes;                   /**< local nodes */
  cupid_pd_grid_partition part;      /**< where they sit in the whole (slabs: issue 6) */
  int dimension;
  double spacing;
  const double *coords;              /**< 3 per local node (the rigid-body modes of GAMG) */
  /** y = rows [3 n0, 3 n1) of K x (x: local DOFs, y: 3 (n1 - n0) values). */
  cupid_status (*apply_range)(const cupid_node_operator *A, cupid_int n0, cupid_int n1,
                              const double *x, double *y);
  /** The local nodes [*lo, *hi) that rows of nodes [n0, n1) read. */
  cupid_status (*dependency_range)(const cupid_node_operator *A, cupid_int n0, cupid_int n1,
                                   cupid_int *lo, cupid_int *hi);
  /** The 3x3 diagonal blocks, 9 per local node. */
  cupid_status (*diagonal)(const cupid_node_operator *A, double *blocks);
  /** Rows of nodes [n0, n1) of a cheap SPD matrix of bond radius @p radius (the PC's). */
  cupid_status (*preconditioner_rows)(const cupid_node_operator *A, double radius, cupid_int n0,
                                      cupid_int n1, cupid_csr *rows);
};

/**
 * Solve K u = f for a node operator by CG on PETSc, K never assembled: a MATSHELL whose product
 * computes the owned rows after a VecScatter of their dependency range (halo exchange);
 * Dirichlet DOFs as scaled identity rows with the right-hand side lifted. Preconditioned by
 * GAMG on the operator's cheap rows (radius 1.5 h, option -cupid_pc_radius R in units of h)
 * with the rigid-body near null space; -ksp_* / -pc_* options apply. f, bc and u are local to
 * the operator: a whole grid (u gets the whole solution on every rank) or, with one slab per
 * rank (A->part.parts > 1), f and bc read on the owned nodes (bc also on the halo) and u
 * getting the owned nodes and their dependency range. Same checks and outputs as
 * cupid_petsc_solve() (info->matrix_free = 1). Collective; dimension 3 only. Builds without
 * PETSc: CUPID_ERR_UNSUPPORTED.
 */
cupid_status cupid_petsc_solve_nodes(const cupid_node_operator *A, const double *f,
                                     const cupid_dirichlet_t *bc, double *u,
                                     cupid_solve_info *info);

/**
 * The same solve kept for a sequence of systems whose operator changes a little between them
 * (crack growth: bonds break, nodes are held): the shell, the preconditioner matrix and GAMG
 * are built once by _create and reused by every _solve (the operator's product and @p bc are
 * read at each solve, so broken bonds and newly fixed DOFs count at once; the preconditioner
 * stays the intact grid's, which keeps it symmetric positive definite). @p A is copied; @p bc
 * must outlive the solver. _solve starts CG from u (guess != 0: its owned values, the
 * prescribed ones on fixed DOFs) or from 0, to the same absolute target |b - K u| <= rtol |b|
 * either way; info->time_factor of the first solve is the set-up. A solve that does not
 * converge (CUPID_ERR_NUMERIC) leaves CG's last iterate in u: a part of the model that lost
 * its support shows there as the displacement that ran away. Collective.
 */
typedef struct cupid_petsc_nodes_solver_private *cupid_petsc_nodes_solver;
cupid_status cupid_petsc_nodes_solver_create(const cupid_node_operator *A,
                                             const cupid_dirichlet_t *bc,
                                             cupid_petsc_nodes_solver *out);
cupid_status cupid_petsc_nodes_solver_solve(cupid_petsc_nodes_solver S, const double *f, int guess,
                                            double *u, cupid_solve_info *info);
/** Lower the solves' iteration limit (the default or -ksp_max_it) to @p max_iterations: a
 *  re-solve that needs far more than the first did is on a mechanism, not converging. */
void cupid_petsc_nodes_solver_limit(cupid_petsc_nodes_solver S, int max_iterations);
void cupid_petsc_nodes_solver_destroy(cupid_petsc_nodes_solver *S);

/* ---- Solver engines as a table (src/solvers/engine.c) ----
 * Each engine fills one cupid_solver_type; the problem (problem.h) picks one by name or by cost
 * (`auto`) and solves through it, so no code outside the table asks which engine it is. */

/** What a path is expected to cost (problem.h's estimates). */
typedef struct {
  double bytes;     /**< peak memory, one rank */
  double seconds;   /**< set-up + solve */
  char what[96];    /**< the path, e.g. "CHOLMOD" or "matrix-free GMRES + LU of a bond-based twin" */
} cupid_solver_cost;

typedef struct {
  const char *name;   /**< as in the model file and --solver: "direct", "petsc" */
  int kind;           /**< its cupid_solver_kind (model.h) */
  int iterative;      /**< 1: Krylov, the matrix-free paths are its own */
  int distributed;    /**< 1: solves over MPI ranks (PD grids in slabs) */
  /** 1 when this build has the engine. */
  int (*available)(void);
  /** Ready the engine (PETSc and MPI start here when not already started). */
  cupid_status (*start)(void);
  /** Solve K u = f on the free DOFs of @p bc (finalized); @p hints may be NULL. */
  cupid_status (*solve_matrix)(const cupid_csr_t *K, cupid_matrix_kind kind, const double *f,
                               const cupid_dirichlet_t *bc, double *u,
                               const cupid_petsc_options *hints, cupid_solve_info *info);
  /** The matrix-free PD solve of a node operator (NULL: the engine has none). */
  cupid_status (*solve_nodes)(const cupid_node_operator *A, const double *f,
                              const cupid_dirichlet_t *bc, double *u, cupid_solve_info *info);
  /** Solve the matrix-free A u = f preconditioned by the matrix @p P (NULL: the engine has
   *  no matrix-free solve). */
  cupid_status (*solve_operator)(const cupid_linear_operator *A, const cupid_csr_t *P,
                                 const cupid_dirichlet_t *bc, const double *f, double *u,
                                 const cupid_krylov_options *opts, cupid_solve_info *info);
} cupid_solver_type;

/**
 * The built-in matrix-free Krylov solve (the `krylov` engine, src/solvers/iterative.c): as
 * cupid_krylov_solve() on one process without PETSc. A->symmetric: CG preconditioned by the
 * CHOLMOD factor of P_ff; else right-preconditioned restarted GMRES with the UMFPACK LU of P_ff.
 * Fixed DOFs eliminated; rtol, max_it and restart of @p opts (0: 1e-10, 2000, 200); pc and
 * factor_package ignored. Not converged: CUPID_ERR_NUMERIC. info: method "krylov", ksp_type,
 * pc_type ("cholmod"/"umfpack"), iterations, residual (true, recomputed), times.
 */
cupid_status cupid_iterative_solve(const cupid_linear_operator *A, const cupid_csr_t *P,
                                   const cupid_dirichlet_t *bc, const double *f, double *u,
                                   const cupid_krylov_options *opts, cupid_solve_info *info);

/**
 * A re-solve of a system that changed a little since its preconditioner was made (crack growth
 * with a non-symmetric coupling: the LU of the last factorised K, src/problem/growth_lu.c):
 * right-preconditioned restarted GMRES on the free DOFs of @p bc (A_ff u_f = f_f - A_fc u_c)
 * from u's free values, to |b - A u| <= rtol |b| by the true residual (as
 * cupid_iterative_solve()). @p pc applies M^-1 to full-length vectors (r zero on the fixed
 * DOFs; z read on the free ones). At most @p max_it iterations, restarted every
 * min(max_it, 200). Returns CUPID_SUCCESS whether or not it converged: the caller reads
 * info->converged_reason ("CONVERGED_*" or not) and keeps u only then; u holds the last
 * iterate (fixed DOFs: their values). The scalar products are the same for any thread count
 * (cupid_dot). A non-finite iterate: CUPID_ERR_NUMERIC.
 */
cupid_status cupid_gmres_resolve(const cupid_linear_operator *A, const cupid_dirichlet_t *bc,
                                 cupid_status (*pc)(void *ctx, const double *r, double *z),
                                 void *pc_ctx, const double *f, double *u, double rtol,
                                 int max_it, cupid_solve_info *info);

/**
 * As cupid_gmres_resolve(), by CG where @p A is symmetric (GMRES otherwise): the re-solves of
 * crack growth on the built-in `krylov` engine, matrix-free, preconditioned by the kept factor
 * of the intact twin (src/problem/growth_matrix_free.c). From u's free values to |b - A u| <=
 * rtol |b|, as from zero, by the true residual (CG's recurrence checked, and CG run again
 * from there while that at least halves it: a preconditioner far from A lets it drift). A CG
 * breakdown (p'Ap <= 0: a mechanism) is CUPID_ERR_NUMERIC; u then holds the last iterate, where a part that lost its support ran away (non-finite: untouched).
 * @p pc must be symmetric positive definite on the free DOFs for CG.
 */
cupid_status cupid_krylov_resolve(const cupid_linear_operator *A, const cupid_dirichlet_t *bc,
                                  cupid_status (*pc)(void *ctx, const double *r, double *z),
                                  void *pc_ctx, const double *f, double *u, double rtol,
                                  int max_it, cupid_solve_info *info);

/** The engine of a cupid_solver_kind (DIRECT or PETSC; NULL otherwise). */
const cupid_solver_type *cupid_solver_type_get(int kind);
/** The k-th engine of the table (0, 1, ...; NULL past the end): the factorisation first, then
 *  the iterative engines (the built-in one before PETSc). */
const cupid_solver_type *cupid_solver_type_at(int k);
/** The engine named @p name ("direct", "petsc"; NULL if unknown). */
const cupid_solver_type *cupid_solver_type_find(const char *name);
/* ---- end of the engine table ---- */

#ifdef __cplusplus
}
#endif
#endif
