/* Private to src/problem: the state of one problem (include/cupid/problem.h) and the stages
 * that fill it. The coupling method of a model is a table of functions (method.h); the solver
 * engine another (cupid_solver_type, solvers.h): the stages call through them and never test
 * which method or engine it is. */
#ifndef CUPID_PROBLEM_INTERNAL_H
#define CUPID_PROBLEM_INTERNAL_H

#include "cupid/coupling.h"
#include "cupid/cuf.h"
#include "cupid/dynamics.h"
#include "cupid/io.h"
#include "cupid/model.h"
#include "cupid/pd.h"
#include "cupid/problem.h"
#include "cupid/solvers.h"

/** Phases reported in summary.json (model-format.md: grid, assembly, coupling,
 *  factorisation, solve, output). */
typedef enum {
  CUPID_PHASE_GRID = 0,
  CUPID_PHASE_ASSEMBLY,
  CUPID_PHASE_COUPLING,
  CUPID_PHASE_FACTORISATION,
  CUPID_PHASE_SOLVE,
  CUPID_PHASE_OUTPUT,
  CUPID_PHASE_COUNT
} cupid_phase;

typedef struct {
  double seconds;
  int64_t peak_memory; /**< process peak RSS at the end of the phase */
  int used;
} cupid_phase_record;

/** State of a `type: dynamic` run (src/app/dynamic.c). */
typedef struct {
  cupid_dynamics_info info;
  cupid_dynamics_energy energy; /**< at the last step */
  cupid_int steps;
  int lumped, done;
  int matrix_free; /**< central differences on a matrix-free operator (no assembled K) */
} cupid_problem_dynamic;

typedef struct cupid_method_ops cupid_method_ops; /* method.h */

/* The quality of a coupled run (quality.c; docs/coupling.md "The quality report of a coupled
 * run"). Bounds: the patch test's ghost forces are round-off (< 1e-12) for a consistent
 * coupling, so 1e-6 flags a real one with room for ill-conditioned products; 1% of the load
 * is the imbalance issue 18 asks of a coupling (paper 000's bar: 0.43%). */
#define CUPID_QUALITY_GHOST_BOUND 1e-2
#define CUPID_QUALITY_IMBALANCE_BOUND 1e-2
/* The energy balance of a dynamic run, relative to its largest energy, above which it warns:
 * central differences hold it to 3e-5 on the truss (docs/dynamics.md), 1.5e-6 on the notched
 * plate; every bond breaking at the first step, the worst case of its O(dt) error, 5.4e-3. */
#define CUPID_ENERGY_BALANCE_BOUND 1e-2
typedef struct {
  int patch_done;             /**< the patch test ran */
  const char *patch_skipped;  /**< why it did not (NULL: not asked yet) */
  double strain, ghost_fe, ghost_pd, ghost, patch_seconds;
  cupid_int fe_checked, pd_checked;
  int has_imbalance;          /**< a static solve with loads */
  double imbalance;
  int ghost_warning, imbalance_warning;
} cupid_problem_quality;

/** The stages a problem has passed (cupid_problem_info.stage). */
enum { CUPID_STAGE_CREATED = 0, CUPID_STAGE_SET_UP = 1, CUPID_STAGE_SOLVED = 2 };

/** Adaptive PD zones (adaptive.c; issue 37): the run's zone, its conversions. */
typedef struct cupid_problem_adaptive_private cupid_problem_adaptive;
/** One conversion: when, and what it added. */
typedef struct {
  int step;            /**< the load step (dynamics: time step) it happened at */
  double load_factor;  /**< (dynamics: the time) */
  cupid_int added_nodes, pd_nodes;
  double y_lo, y_hi;   /**< the span of the elements it turned to PD */
  int elements;        /**< beam elements (partial: units, beam element x section element) */
  int partial;         /**< a zone over part of the section: */
  double x_lo, x_hi, z_lo, z_hi; /**< the span of the section elements it added */
  double energy;       /**< dynamics: the energy it added (kinetic + strain after less before) */
  int has_energy;
  const char *why;     /**< "strain", "stretch in an overlap" (fictitious nodes: "in the
                            coupling zone"), "crack near an overlap", "an overlap's (a coupling
                            zone's) bond reached its limit" or "pre-crack near an overlap" */
} cupid_problem_conversion;

typedef struct cupid_problem_private {
  const cupid_model_t *model; /**< the model read, or an adaptive run's copy (adaptive.c) */
  cupid_problem_adaptive *adaptive; /**< peridynamics.adaptive: the zone (NULL: fixed) */
  cupid_model owned_model;  /**< created from a file or string: the problem's to free */
  cupid_run_options options;
  const cupid_run_options *opts; /**< = &options */
  const cupid_method_ops *method; /**< the coupling method's table (method.h) */
  int stage;
  const char *outdir;       /**< where the results go (-o, else output.directory) */
  cupid_output_set outputs; /**< the run's files, staged until write_outputs publishes them */
  int outputs_written;              /**< write_outputs published once (keep_others then) */
  const char *writedir;     /**< the staging folder the files are written to (NULL: none on this
                                 MPI rank) */
  int quiet;

  /* Peridynamics */
  cupid_pd_grid grid;
  cupid_pd_operator op;
  cupid_pd_operator_options pd_options; /**< kept for size estimates */
  cupid_pd_material *pd_materials;      /**< owned; pd_options.materials points here */
  cupid_int n_pd;          /**< PD nodes */
  cupid_int n_bonds;
  double pd_volume;        /**< the PD nodes' volumes summed (all ranks) */
  cupid_int n_cut_nodes;   /**< nodes with cut-cell volumes (partial_volume: exact; all ranks) */

  /* CUF beam (FE): its DOFs follow the PD DOFs, from fe_offset = 3 n_pd. */
  cupid_cuf_beam beam;
  cupid_cuf_info fe_info;
  cupid_int fe_offset, n_fe_dofs;

  /* The linear system: [3 DOFs per PD node | FE DOFs]. */
  cupid_int ndof;
  cupid_csr K;
  cupid_dirichlet bc;
  double *u;               /**< displacements */
  double *f_ext;           /**< applied loads */
  double *f_int;           /**< K u (internal force; = loads + reactions at equilibrium) */
  double *pd_stress;       /**< 6 per PD node, or NULL */
  cupid_solve_info solve;
  int solved;              /**< a linear solve was done */

  cupid_problem_dynamic dyn;   /**< type: dynamic */
  /* Checkpoints of a resumable run (resume.c, issue 36). */
  struct {
    double period;   /**< seconds between periodic checkpoints (0: on a signal only) */
    double last;     /**< when the last one was written (or the run began) */
    char *path;      /**< this rank's checkpoint file, in the resumable staging folder */
    int armed;       /**< signals ask for a checkpoint (cupid_interrupt_arm) */
    int interrupted; /**< the run stopped at a checkpoint: keep its staging folder */
    cupid_int written;
    double seconds;  /**< spent writing them (the stage times them) */
  } ckpt;

  /* Coupled models (method_*.c) */
  cupid_coupling_h coupling;
  cupid_arlequin_region *arlequin_regions; /**< method arlequin: the layout (owned) */
  int n_arlequin_regions;
  double arlequin_penalty;       /**< method arlequin: kappa in use (given, or `auto`'s choice) */
  double arlequin_node_stiffness; /**< method arlequin: k_node (cupid_arlequin_node_stiffness) */
  cupid_int n_fictitious;  /**< fictitious PD nodes */
  void *method_state;      /**< what the method keeps between its stages (freed by its
                                free_state; method.h) */

  double load_sum[3], reaction_sum[3];
  cupid_problem_quality quality; /**< coupled models (quality.c) */
  cupid_phase_record phases[CUPID_PHASE_COUNT];
  double t_start;

  /* Solver engine (issue 6): DIRECT or PETSC once chosen (AUTO until then), its table and
   * why it was chosen. */
  cupid_solver_kind solver;
  const cupid_solver_type *engine;
  cupid_solver_cost estimate;   /**< static: the chosen engine's path as estimated (seconds 0:
                                     none) */
  char solver_reason[320];

  /* Distributed PD (issue 6, slab.c): this rank holds one z slab of the grid (slab = 1 until
   * rank 0 gathers the results); the grid's n_pd, u, f_ext, f_int, bc are then the slab's. */
  int slab;
  cupid_pd_grid_partition part;  /**< of prob->grid */
  int slab_ranks;                /**< > 1: the run was split into this many slabs */
  int slab_nodes_max;            /**< the largest slab (nodes incl. halo) */

  /* Fields served by cupid_problem_get_field (built on demand). */
  double *beam_points, *beam_u; /**< the beam's 3D reconstruction: points, displacements */
  cupid_int n_beam_points;
  double *history;              /**< type dynamic: t and u at the output points, per step */
  cupid_int history_rows, history_cap;
  int history_cols;
  cupid_box *region_boxes;      /**< cupid_problem_coupling_options: one per PD region */
  /** Tractions on a shaped PD body (pd_bc.c): the scale of each plane and patch's loaded faces
   *  to the true section, made once (time-dependent loads are assembled every time step). */
  struct cupid_traction_scale {
    double plane_y;
    cupid_box patch;
    double scale;
  } *traction_scales;
  int n_traction_scales;
  int *region_materials;

  /* Time-dependent conditions (dynamic.c): the time the model's expressions are evaluated at
   * (0 but during a dynamic run that has expressions in t). */
  double time;

  /* Fracture (fracture.c): pre-cracks and bond breaking on prob->op. */
  cupid_int precrack_bonds;         /**< bonds the pre-cracks removed */
  cupid_pd_fracture_options fracture; /**< the breaking rule (criterion, limits, protection) */
  unsigned char *protect;           /**< per PD node: its bonds never break (method stage) */
  uint32_t *no_fail;                /**< per PD node: the no-fail boxes holding it */
  double *node_stretch;             /**< per PD node s0 (from G0), or NULL */
  double lattice_ratio;             /**< bond-based: m / S of a full family (fracture.c's
                                         calibrations), taken when s0 is, 0 before */
  double s0_calibrations[2];        /**< bond-based, the first node's material: s0 continuum
                                         and grid (the reports; 0 when not from G0) */
  /* A slab run with the critical-energy criterion, or a static one (fracture.c): each rank
   * decides the bonds of its owned nodes and sends their bits to the ranks that hold them as
   * halo. */
  cupid_petsc_halo break_halo;
  double *break_words;              /**< the bits of every slab node (broken_words each) */
  cupid_int broken_bonds;           /**< broken during the run (pre-cracks not counted) */
  cupid_int first_break_step;       /**< -1: none */
  double first_break_t, fracture_energy;
  double first_break_at[3];         /**< centroid of the nodes of the first broken bonds */
  double first_break_load;          /**< static growth: the load factor of the first break,
                                         found by scaling the linear solution (0: none) */
  double *damage;                   /**< per PD node, for the outputs (NULL: no fracture) */
  cupid_pd_operator crack_copy;     /**< a method's own PD operator that must lose the same
                                         bonds as prob->op (borrowed, during its run), or NULL */
  const cupid_int *crack_map;       /**< crack_copy on another grid: its node of each prob->op
                                         node (cupid_pd_operator_copy_broken_mapped); NULL: the
                                         same grid */
  cupid_int damaged_nodes;
  double max_damage;
  /* static growth (growth.c): how the solves went, for summary.json's fracture block */
  struct {
    const char *resolve;            /**< "downdate" (the last factor downdated by the broken
                                         bonds), "krylov" (CG on the last factor), "factor",
                                         "block downdate" / "lu update" / "gmres" (a
                                         non-symmetric K: the last block factor downdated or
                                         LU updated by the broken bonds / GMRES on it; the
                                         downdate fields count them), "matrix-free",
                                         or "engine" (every solve by an iterative engine) */
    cupid_int solves, factorisations, cg_solves, cg_iterations, downdates, downdate_columns;
    cupid_int held_rows; /* factor rows deleted for held nodes (no factorisation for them) */
    cupid_int tied_nodes; /* nodes tied by a weak spring (growth.c, tie_mechanisms) */
    cupid_int tied_singular; /* of them, named by a failed downdate or factorisation */
    cupid_int failed_factorisations; /* the run's own that broke down (growth.c) */
    double tie_stiffness; /* ... of this stiffness */
    double tie_share;     /* their springs' share of the forces on the body, at the end */
    double factor_s, cg_s, downdate_s;
    /* per constraint k, peak[6 k ..]: the largest reaction (by magnitude) of the sawtooth
     * envelope, its load factor, step, and x, y, z (growth.c, next_break) */
    double *peak;
    double held_reaction[3];        /**< the held nodes' forces summed (growth.c, held_forces) */
    unsigned char *held;            /**< per PD node, nonzero: held (NULL: none was) */
    cupid_int held_count;
    double held_share;              /**< the held nodes' share of the forces, last solve */
    int collapse_step;              /**< the step the body collapsed (0: it did not) */
    double collapse_load, collapse_share;
    const char *collapse_cause;     /**< "held nodes carry load" or "runaway" */
    cupid_int collapse_held;
    int stopped_step;               /**< the step a crack reaching a coupling zone stopped
                                         (0: ran to the end) */
    char stopped[1024];              /**< then: why, for the message and summary.json */
  } growth;
} cupid_problem_state;

/* quality.c: the coupling's patch test and imbalance, against their bounds. */
/** y = K x for the whole system's layout (a slab: its owned PD rows and the FE rows). */
typedef cupid_status (*cupid_system_apply)(void *ctx, const double *x, double *y);
/** 1 for a model with both a beam and a PD grid. */
int cupid_problem_is_coupled(const cupid_problem_state *prob);
/** The patch test on the coupled operator @p apply (once; nothing for an uncoupled model):
 *  collective on a slab. */
cupid_status cupid_problem_patch_test(cupid_problem_state *prob, cupid_system_apply apply,
                                      void *ctx);
/** The same on the assembled prob->K (nothing when there is none). */
cupid_status cupid_problem_patch_test_assembled(cupid_problem_state *prob);
/** After the solve and the force sums: the imbalance, the figures on stderr, the warnings. */
void cupid_problem_quality_report(cupid_problem_state *prob);
/** The "coupling_quality" block of summary.json (coupled models). */
void cupid_problem_quality_json(cupid_json js, const cupid_problem_state *prob);

/* balance.c: `coupling.balance: momentum` (the balanced fictitious-node operator). */
/** The model asks for the balanced operator (and is coupled). */
int cupid_problem_balanced(const cupid_problem_state *prob);
/** The correction of the assembled @p K (C = K^T R from K itself): K' x = K x, then
 *  cupid_coupling_balance_correct(*B, x, .); *B is the caller's. */
cupid_status cupid_problem_balance_assembled(const cupid_problem_state *prob, const cupid_csr_t *K,
                                             cupid_coupling_balance *B);
/** The resultant of f_int along x, y, z (sum of f_int T_k) and the sum of the terms'
 *  magnitudes (quality.c). */
cupid_status cupid_problem_internal_force_sum(const cupid_problem_state *prob, double sum[3],
                                              double *scale);
/** `type: evaluate` on the assembled K: the patch test and f_int = K' u of the imposed u. */
cupid_status cupid_problem_balanced_evaluate(cupid_problem_state *prob);
/** The assembled path: patch test, factor of K_ff, the balanced solve, f_int = K' u. */
cupid_status cupid_problem_balanced_direct_solve(cupid_problem_state *prob);
/** The matrix-free path: *out = K' around L (the operator of A); *B is the caller's. */
cupid_status cupid_problem_balanced_operator(cupid_problem_state *prob, cupid_coupling_operator A,
                                             const cupid_linear_operator *L,
                                             cupid_coupling_balance *B, cupid_linear_operator *out);

/* growth.c: `type: static` with load steps or fracture (sequentially linear growth). */
cupid_status cupid_problem_run_growth(cupid_problem_state *prob);
/** The largest ratio of a bond to its limit at u (cupid_pd_operator_max_ratio), over the
 *  ranks of a slab run (collective there). */
cupid_status cupid_problem_max_ratio(const cupid_problem_state *prob, const double *u, double *r);

/* growth_downdate.c: the change Kold - Knew that broken bonds made, as the rank-one columns of
 * C (Kold - Knew = C C^T, columns of 6 entries: w at node i, -w at node j), for
 * cupid_direct_factor_downdate(); *ok = 0 when the change is no such sum (LPS). */
typedef struct {
  cupid_int r, cap;
  cupid_int *colptr, *rows;
  double *vals;
} cupid_growth_downdate;
cupid_status cupid_growth_downdate_terms(const cupid_csr_t *Kold, const cupid_csr_t *Knew,
                                         cupid_growth_downdate *u, int *ok);
/* The same over the sorted block rows @p rows alone (where K changed: the ends of the broken
 * bonds; Kold may hold only those rows, cupid_growth_rows_copy): the same columns in the same
 * order as over all rows. */
cupid_status cupid_growth_downdate_rows(const cupid_csr_t *Kold, const cupid_csr_t *Knew,
                                        const cupid_int *rows, cupid_int n_rows,
                                        cupid_growth_downdate *u, int *ok);
/* A copy of K with only the block rows @p rows (sorted) filled, the others empty. */
cupid_status cupid_growth_rows_copy(const cupid_csr_t *K, const cupid_int *rows, cupid_int n_rows,
                                    cupid_csr *out);
void cupid_growth_downdate_free(cupid_growth_downdate *u);

/* growth_smw.c: the inverse of a factorised M brought to M - V V^T exactly by Sherman-Morrison-
 * Woodbury (V: the broken bonds' columns of cupid_growth_downdate_terms), for a factor that
 * cannot be downdated (the LU of growth_lu.c). */
typedef struct {
  cupid_int n, r, cap; /* DOFs, columns held, room */
  cupid_int *rows;     /* 6 per column: its DOFs */
  double *vals;        /* ... and entries */
  double *Z;           /* n per column: M^-1 v */
  double *Si;          /* (I - V^T Z)^-1, rows of cap */
  double *w;           /* 2 cap work */
} cupid_growth_smw;
/** Append dd's columns: each solved by solve(ctx, v, z) (z = M^-1 v, the factor's own inverse),
 *  S^-1 grown by bordering. *ok = 0 when M - V V^T is singular (a pivot of the new block under
 *  1e-10: a part that breaking left loose); u is then as it was. */
cupid_status cupid_growth_smw_add(cupid_growth_smw *u, cupid_int n, const cupid_growth_downdate *dd,
                                  cupid_status (*solve)(void *ctx, const double *b, double *x),
                                  void *ctx, int *ok);
/** y = M^-1 b to (M - V V^T)^-1 b, in place: y += Z S^-1 V^T y. */
void cupid_growth_smw_correct(const cupid_growth_smw *u, double *y);
void cupid_growth_smw_reset(cupid_growth_smw *u);
void cupid_growth_smw_free(cupid_growth_smw *u);

/* growth_block.c: the fictitious-node K' = [A B; C' D'] by block elimination: CHOLMOD of its
 * symmetric PD block A, downdated as bonds break, and the UMFPACK LU of the Schur complement
 * S = D' - C' A^-1 B on the FE DOFs (the balance's W C^T folded into C' and D'). */
typedef struct cupid_growth_block_private *cupid_growth_block;
/** Factor @p K (balanced by @p B when not NULL; its PD DOFs first, the FE DOFs from @p fe0) for
 *  the free DOFs of @p bc. *M stays NULL (and CUPID_SUCCESS) when K is not two such blocks (no
 *  FE DOFs, a PD block that is not symmetric, or a singular D'): the caller factorises K whole.
 *  A singular K: CUPID_ERR_NUMERIC with info->failed_dof (global). */
cupid_status cupid_growth_block_create(const cupid_csr_t *K, cupid_int fe0, const cupid_dirichlet_t *bc,
                                       const cupid_coupling_balance B, cupid_growth_block *M,
                                       cupid_solve_info *info);
/** z = K'^-1 r on the factor's free DOFs (r full-length, its free entries read; z full-length,
 *  zero on the factor's fixed DOFs; no aliasing). */
cupid_status cupid_growth_block_solve(cupid_growth_block M, const double *r, double *z);
/** The factor brought to K - V V^T (dd's columns, on PD DOFs): A downdated, S changed by the
 *  rank-r term and factorised again. *ok = 0 when that K is singular (the caller drops M). */
cupid_status cupid_growth_block_downdate(cupid_growth_block M, const cupid_growth_downdate *dd, int *ok);
/** The DOF of the weaker factor's smallest pivot (A's or S's). */
cupid_status cupid_growth_block_weakest_dof(const cupid_growth_block M, cupid_int *dof);
/** S's size; *nic and *nib the interface rows and columns of its dense block. */
cupid_int cupid_growth_block_interface(const cupid_growth_block M, cupid_int *nic, cupid_int *nib);
void cupid_growth_block_destroy(cupid_growth_block *M);

/* growth_lu.c: the re-solves of a non-symmetric coupling (fictitious nodes, Eq. 38, either
 * balance) on the direct engine: the UMFPACK LU of the last factorised K (or the balanced
 * K' = K - W C^T), brought to the current K by the broken bonds' terms (growth_smw.c), one step
 * per re-solve; GMRES on the last LU where the change is no sum of bond terms (LPS). */
typedef struct {
  cupid_growth_block M;         /* the last factorisation by block elimination (growth_block.c),
                                   downdated to the current K; or NULL and ... */
  int whole;                    /* ... K is not two such blocks: */
  cupid_direct_factor F;        /* LU of K_ff at the last factorisation (its own free DOFs) */
  cupid_coupling_balance_smw smw; /* balanced: F's K' inverted exactly (SMW), or NULL */
  cupid_coupling_balance B;     /* balanced: W and C = K^T R, built at the first solve and kept:
                                   breaks outside the coupling zone change neither, and held
                                   nodes change the conditions, not K (docs/theory.md) */
  cupid_int bonds_at_factor;    /* broken bonds then */
  double factor_flops;          /* the factorisation's operations ... */
  double iteration_flops;       /* ... and one GMRES iteration's (two triangular solves, K x) */
  double since_factor;          /* solves since the last factorisation: GMRES iterations, the
                                   update's columns, its products (in solves) */
  cupid_growth_smw upd;         /* the factor brought to the current K by the broken bonds */
  cupid_growth_downdate dd;     /* a round's bond terms */
  int no_update;                /* a change was no sum of bond terms (LPS): GMRES alone */
  cupid_int updates, update_columns; /* rounds and columns applied by the update */
  cupid_int updates_since;      /* rounds since the factorisation */
  double t_update;
  cupid_int factorisations, resolves, iterations;
  double t_factor, t_resolve;
  double *t, *z, *w;            /* ndof work vectors (w: two) */
  cupid_solve_info factor_info; /* the last factorisation's (summary.json's solver block) */
  int patch_tested;
} cupid_growth_lu;
/** 1 when s holds a factor (block or LU). */
static inline int cupid_growth_lu_has_factor(const cupid_growth_lu *s) { return s->M || s->F; }
/** 1 when growth solves prob's assembled system by cupid_growth_lu_solve (a non-symmetric
 *  method on the direct engine). */
int cupid_growth_lu_applies(const cupid_problem_state *prob);
/** Solve the assembled prob->K (balanced when the model asks) at the current load and
 *  conditions: prob->u (the last solution is GMRES's guess), f_int = K u (K' u), prob->solve.
 *  A factorisation that breaks down: CUPID_ERR_NUMERIC with prob->solve.failed_dof. */
cupid_status cupid_growth_lu_solve(cupid_problem_state *prob, cupid_growth_lu *s);
/** Before the solve after bonds broke (prob->K assembled again; Kold the K of the last solve):
 *  the factor brought to the current K by the bonds' terms, or dropped. */
cupid_status cupid_growth_lu_update(cupid_problem_state *prob, cupid_growth_lu *s,
                                    const cupid_csr_t *Kold);
/** Drop the factor (a new load step after breaks starts from a fresh one, as growth.c's CG). */
void cupid_growth_lu_renew(cupid_growth_lu *s);
/** The work vectors and, balanced, W and C of prob->K (the first solve's K), kept for the run:
 *  a resumption makes them on the intact K before it restores the broken bonds. */
cupid_status cupid_growth_lu_prepare(cupid_problem_state *prob, cupid_growth_lu *s);
/** Factorise prob->K under prob->bc now, as a solve does (a resumption's replay). */
cupid_status cupid_growth_lu_factorise(cupid_problem_state *prob, cupid_growth_lu *s);
void cupid_growth_lu_free(cupid_growth_lu *s);

/* growth_matrix_free.c: load steps and crack growth on the petsc engine, matrix-free (the
 * whole model on one process, or slabs under mpirun): one kept PETSc solve re-run from the last
 * solution after each round of breaks (a PD-only 3D model: CG + GAMG, the preconditioner built
 * once on the intact grid; a coupled one: the method's operator, CG + the Cholesky factor of
 * its bond-based twin, factored once), and on slabs the search for nodes that lost their
 * support over the ranks. A coupled model on the built-in krylov engine: the same, with the
 * twin's SuiteSparse factor and cupid_krylov_resolve. */
typedef struct {
  cupid_petsc_nodes_solver solver; /* PD only */
  cupid_node_operator op;
  cupid_krylov_solver coupled;     /* a coupled model: the method's operator (growth_operator) */
  cupid_direct_factor twin;        /* ... on the built-in krylov engine: its twin's factor, kept */
  const cupid_dirichlet_t *bc;     /* ... and the conditions its preconditioner reads */
  double twin_setup_s;             /* ... its factorisation's seconds, until the first solve */
  cupid_linear_operator L;
  void *owner;                     /* ... its owner, freed by owner_destroy */
  void (*owner_destroy)(void **ctx);
  cupid_petsc_halo halo;        /* the DOFs' exchange: owned -> the other ranks' halo copies */
  double *flags;                /* a DOF-sized buffer: node flags in their first DOF */
  double *u_last;               /* the last solution (CG's first guess) */
  cupid_int iterations;         /* CG iterations over the run */
  double setup_s, solve_s;
  int limit;                    /* the iteration limit set after the first solve (0: none) */
} cupid_growth_mf;
/** The kept solver built now, as the first solve builds it (a resumption, before it restores
 *  the broken bonds: the preconditioner is the intact grid's; collective). */
cupid_status cupid_growth_mf_prepare(cupid_problem_state *prob, cupid_growth_mf *gs);
/** The limit of iterations a resumed run's solves had (cupid_growth_mf.limit). */
cupid_status cupid_growth_mf_set_limit(cupid_growth_mf *gs, int limit);
/** Solve at the current load and conditions (u: the last solution, CG's first guess after the
 *  first solve): u on every DOF of the slab (owned from the solve, halo by the exchange, the
 *  beam's the same on every rank), exactly the prescribed values on fixed DOFs, f_int on the
 *  owned rows and a beam's rows (collective). */
cupid_status cupid_growth_mf_solve(cupid_problem_state *prob, cupid_growth_mf *gs);
/** cupid_pd_operator_unsupported over the whole distributed grid: each rank decides its owned
 *  nodes, @p release then agrees on every copy; *fresh counts the newly released nodes of all
 *  ranks (collective). */
cupid_status cupid_growth_mf_unsupported(cupid_problem_state *prob, cupid_growth_mf *gs,
                                           const unsigned char *anchored, unsigned char *release,
                                           cupid_int *fresh);
/** After a solve that found no equilibrium (a mechanism the support search missed): the node
 *  whose displacement ran furthest from the last solution in CG's iterate (over the ranks, the
 *  lowest global index among equals) is held there, release = 1 on every copy, u restored to
 *  the last solution; x its position, *held = 0 when no free node moved (collective). */
cupid_status cupid_growth_mf_hold_runaway(cupid_problem_state *prob, cupid_growth_mf *gs,
                                            unsigned char *release, double x[3], int *held);
void cupid_growth_mf_free(cupid_growth_mf *gs);

/* fracture.c */
/** Model errors of pre-cracks and fracture this version cannot run (before anything is
 *  built): an analysis, integrator, method or surface correction without bond breaking. */
cupid_status cupid_problem_fracture_check(const cupid_problem_state *prob);
/** After prob->op is built: remove the pre-cracks' bonds (a pre-crack that cuts none, or
 *  reaches a protected node, is a model error) and set up the breaking rule. */
cupid_status cupid_problem_fracture_setup(cupid_problem_state *prob);
/** The after-forces stage of a dynamic run: break what is over its limit at u (the PD part of
 *  a system vector); *dissipated = the energy the broken bonds held. */
cupid_status cupid_problem_fracture_step(cupid_problem_state *prob, cupid_int step, double t,
                                         const double *u, int only_most, cupid_int *n_broken,
                                         double *dissipated);
/** prob->damage, damaged_nodes, max_damage from the operator's broken bonds (outputs); on a
 *  slab the counts are the whole grid's (collective), and after a slab run rank 0 counts its
 *  gathered field. */
cupid_status cupid_problem_fracture_damage(cupid_problem_state *prob);
/** Nodes that lost a bond to breaking, over the whole grid (collective on a slab). */
cupid_int cupid_problem_fracture_nodes_broken(const cupid_problem_state *prob);
/** 1 when the model has pre-cracks or fracture (damage is an output). */
int cupid_problem_has_damage(const cupid_problem_state *prob);
/** The critical stretch of @p material: given, or from G0 by the continuum formula (before
 *  any grid exists: an adaptive zone that starts empty). */
double cupid_problem_fracture_s0_of(const cupid_problem_state *prob, int material);
/** A pre-crack that reaches a node whose bonds never break (the coupling zone): a model error
 *  naming the pre-crack and the zone. */
cupid_status cupid_problem_fracture_check_protected(cupid_problem_state *prob);
/** `cupid check`: the pre-cracks' bonds and the breaking rule, on stdout. */
void cupid_problem_fracture_print(const cupid_problem_state *prob);
/** The "fracture" block of summary.json. */
void cupid_problem_fracture_json(cupid_json js, const cupid_problem_state *prob);

/* adaptive.c: adaptive PD zones (issue 37). */
/** The model a run works on: @p model, or with peridynamics.adaptive a copy whose regions the
 *  run changes (*a its state, freed by cupid_problem_adaptive_free). NULL: out of memory. */
const cupid_model_t *cupid_problem_adaptive_model(const cupid_model_t *model,
                                                  cupid_problem_adaptive **a);
void cupid_problem_adaptive_free(cupid_problem_adaptive **a);
/** What this version runs with adaptive (model errors, before anything is built). */
cupid_status cupid_problem_adaptive_check(const cupid_problem_state *prob);
/** After the grid, the beam and the layout are built: the initial zone, its lattice. */
cupid_status cupid_problem_adaptive_begin(cupid_problem_state *prob);
/** After a settled load step (or a crack blocked at an overlap), prob->damage up to date:
 *  mark the beam elements (or units) the trigger turns to PD (the strain against threshold
 *  s0; broken bonds within margin horizons of an overlap); *count of them. */
cupid_status cupid_problem_adaptive_trigger(cupid_problem_state *prob, cupid_int *count);
/** A crack asks to enter the overlap at @p x: mark the elements around it; *count 0 when none
 *  may turn (outside `within`): the run stops as a fixed zone's does. */
cupid_status cupid_problem_adaptive_blocked(cupid_problem_state *prob, const double x[3],
                                            cupid_int *count);
/** Turn the marked elements to PD and rebuild the problem around the new zone; *stopped = 1
 *  (prob->growth.stopped says why) when the zone would pass max_nodes. @p load_factor: in
 *  dynamics the time. carry[0..n_carry): fields of the old layout (its DOFs) that the new one
 *  keeps, as u (dynamics: the velocity), each replaced by its new copy. */
cupid_status cupid_problem_adaptive_convert(cupid_problem_state *prob, int step, double load_factor,
                                            double **carry, int n_carry, int *stopped);
/** A checkpoint's "adaptive" section: the zone (cores, footprints, regions, overlaps) and its
 *  conversions. */
cupid_status cupid_problem_adaptive_save(const cupid_problem_state *prob, cupid_checkpoint_writer w);
/** --resume, at the end of the set-up: the zone of the checkpoint, the problem built again
 *  around it when it grew since the start (the stage then reads its state on that layout). */
cupid_status cupid_problem_adaptive_resume(cupid_problem_state *prob);
/** Dynamics: the energy the last conversion added (the integrator's book of it). */
void cupid_problem_adaptive_energy(cupid_problem_state *prob, double energy);
/** Dynamics: the steps between two tests of the trigger. */
int cupid_problem_adaptive_every(const cupid_problem_state *prob);
/** The last conversion's map: old PD node -> new (*n old nodes). */
const cupid_int *cupid_problem_adaptive_map(const cupid_problem_state *prob, cupid_int *n);
/** `cupid check`: the settings and the largest zone `within` allows (its memory scaled from
 *  the model's estimated peak @p bytes by the PD nodes), on stdout. */
void cupid_problem_adaptive_print(const cupid_problem_state *prob, double bytes);
/** The "adaptive" block of summary.json. */
void cupid_problem_adaptive_json(cupid_json js, const cupid_problem_state *prob);
/* build.c: the set-up's building stages. */
/** The PD grid (or this rank's slab) and its operator, from the model's regions. */
cupid_status cupid_problem_build_pd(cupid_problem_state *prob);
/** u, f_ext, f_int and the conditions, for prob->ndof DOFs. */
cupid_status cupid_problem_allocate_fields(cupid_problem_state *prob);
/** Constraints (finalized) and loads of a static or dynamic analysis, through the method. */
cupid_status cupid_problem_apply_conditions(cupid_problem_state *prob);
/** Free what the set-up built from the model (the method's state, grid, operator, beam,
 *  coupling, K, conditions, fields, the layout's arrays); the run's own state stays. */
void cupid_problem_free_layout(cupid_problem_state *prob);
/** An adaptive zone's model changed: build everything from it again; with @p fields also the
 *  fields and the conditions (during the set-up: not yet). */
cupid_status cupid_problem_rebuild(cupid_problem_state *prob, int fields);

/* support.c: below the stages. */
void cupid_problem_progress(const cupid_problem_state *prob, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
void cupid_problem_phase_end(cupid_problem_state *prob, cupid_phase phase, double t0);
/** The factorisation and solve phases from prob->solve (a linear solve just done). */
void cupid_problem_record_solve(cupid_problem_state *prob);
/** The first non-finite entry of @p v (a vector of the system's layout, ndof entries) as a
 *  model error at @p mark: "<what> is not finite (nan) at PD node (x, y, z)" or "... at beam
 *  node N (y = ...)" (an expression undefined where it was evaluated). CUPID_SUCCESS if all are
 *  finite. With mark NULL: a numerical failure (exit 2) instead. */
cupid_status cupid_problem_check_finite(const cupid_problem_state *prob, const double *v,
                                        const cupid_mark *mark, const char *what);
/** The status of every rank agreed (collective): an error on any rank is an error on all, so
 *  that none waits alone in the next collective call (the failing rank keeps its message). */
cupid_status cupid_problem_slab_agree(cupid_status st);
/** Node i counts on this rank (always, unless a slab does not own it). */
int cupid_problem_pd_owned(const cupid_problem_state *prob, cupid_int node);
/** The lowest rank whose @p mine is nonzero, or the number of ranks when none (collective):
 *  which rank acts on a choice that ties over the ranks (the lowest holds the lower nodes). */
int cupid_problem_lowest_rank(int mine);
/** A count of owned nodes summed over the ranks of a slab run (collective there). */
cupid_int cupid_problem_global_count(const cupid_problem_state *prob, cupid_int count);
/** The outputs need nodal PD stresses (VTU, or a point with stress). */
int cupid_problem_needs_stress(const cupid_problem_state *prob);
/** "u_x, u_y" for the components whose largest |value| is not zero to 1e-12 of the largest
 *  (the ones cupid_plot keeps): a plot's y label. */
void cupid_plot_component_label(const double umax[3], char *label, size_t len);

/* solver.c: the solver engine of a problem. */
/** The engine a static solve may ask for (solver petsc in a build without PETSc, or in a
 *  dynamic analysis: refused). */
cupid_status cupid_problem_check_engine_request(const cupid_problem_state *prob);
/** The engine (requested, or auto) into prob->engine, why into prob->solver_reason, its
 *  estimate into prob->estimate. */
cupid_status cupid_problem_choose_solver(cupid_problem_state *prob);
/** The static solve of the assembled prob->K (a method's default): the patch test, the engine's
 *  solve, the eliminated unknowns, f_int = K u. */
cupid_status cupid_problem_assembled_solve(cupid_problem_state *prob);
/** Solve prob->K u = f_ext with prob->bc by the chosen engine into prob->u and prob->solve;
 *  a breakdown names the node (PD) or beam node and expansion term (FE). */
cupid_status cupid_problem_linear_solve(cupid_problem_state *prob, cupid_matrix_kind kind);

/* problem.c: the stages. */
/** The initial or imposed field of the model's expressions @p v on the PD nodes (into u). */
void cupid_problem_pd_field(const cupid_problem_state *prob, const cupid_value v[3], double t,
                            double *u);


/** The PD materials and operator options of the model (prob->pd_materials,
 *  prob->pd_options); a PD region with an orthotropic material is a model error. */
cupid_status cupid_problem_pd_options(cupid_problem_state *prob);

/* pd_bc.c: constraints and loads on PD nodes (volume layers, faces, points). */
cupid_status cupid_problem_pd_constraints(cupid_problem_state *prob, const cupid_constraint *cons,
                                          int n);
/** The prescribed values of one constraint on the PD nodes at prob->time, into prob->bc. */
cupid_status cupid_problem_pd_prescribe(cupid_problem_state *prob, const cupid_constraint *c);
/* The PD nodes a constraint holds (*nodes allocated, ascending), and its values on them at
 * prob->time: a time loop finds the nodes once and evaluates only there. */
cupid_status cupid_problem_pd_constraint_nodes(const cupid_problem_state *prob,
                                               const cupid_constraint *c, cupid_int **nodes,
                                               cupid_int *n);
void cupid_problem_pd_prescribe_nodes(cupid_problem_state *prob, const cupid_constraint *c,
                                      const cupid_int *nodes, cupid_int n);
/** Add the loads to f (3 per PD node, in the layout of prob->f_ext), at prob->time. */
cupid_status cupid_problem_pd_loads(cupid_problem_state *prob, const cupid_load *loads, int n,
                                    double *f);

/* split.c: which part (beam, PD grid) a constraint or load of a coupled model touches. */
/** A used beam node lies on the plane y. */
int cupid_problem_fe_node_at(const cupid_problem_state *prob, double y);
/** A used beam node lies in the box's y range. */
int cupid_problem_fe_node_in_box(const cupid_problem_state *prob, const cupid_box *b);
/** A PD node lies in the box (only y counts on a 1D grid). */
int cupid_problem_pd_node_in_box(const cupid_problem_state *prob, const cupid_box *b);

/* sample.c: displacement (and stress) at a point, by trilinear interpolation of the grid. */
/** Every output point must lie inside the model (checked before solving). */
cupid_status cupid_problem_check_points(const cupid_problem_state *prob);

/** @p sol: the solution vector sampled (NULL: only say where the point lies). */
cupid_status cupid_problem_sample_point(const cupid_problem_state *prob, const double *sol,
                                        const double p[3],
                                        double u[3], double sigma[6], cupid_region_kind *region);

/* slab.c (issue 6): PD models split into z slabs over the MPI ranks. */
/** Several ranks, 3D, a method that runs on slabs, and a static solve by a distributed engine
 *  (petsc or auto; load steps and crack growth on PD-only models) or explicit dynamics of a
 *  PD-only model. */
int cupid_problem_slab_wanted(const cupid_problem_state *prob);
/** cupid_problem_check_points against the whole grid, built on rank 0 for the check
 *  (collective). */
cupid_status cupid_problem_slab_check_points(cupid_problem_state *prob);
/** After the solve: stresses of the slab, every owned field gathered on rank 0, which then
 *  holds the whole grid and fields (prob->slab = 0 there) for the outputs (collective). */
cupid_status cupid_problem_slab_collect(cupid_problem_state *prob);
/** n_per_node values of every owned node of every rank into *whole on rank 0 (allocated
 *  there; NULL on the others), in global node order (collective). */
cupid_status cupid_problem_slab_gather(const cupid_problem_state *prob, const double *local,
                                       int n_per_node, double **whole);
/** The output points' values u (3 each, NaN where this rank's sampling found none) made the
 *  whole grid's on every rank: each taken from the rank owning its cell's node (collective). */
cupid_status cupid_problem_slab_points(const cupid_problem_state *prob, double *u);
/** The partition of an explicit run on this rank's slab: owned DOFs, the halo exchange
 *  (*halo, destroyed by the caller) and sums over the ranks (collective). */
cupid_status cupid_problem_slab_partition(const cupid_problem_state *prob, cupid_petsc_halo *halo,
                                          cupid_dynamics_partition *part);

/* report.c: every file of output (summary.json, lines, pd_nodes.csv, VTU, plots). */
/** prob->pd_stress from prob->u (once). */
cupid_status cupid_problem_pd_stress(cupid_problem_state *prob);
cupid_status cupid_problem_report(cupid_problem_state *prob);

/* fe.c: the CUF beam of a model: creation, constraints, loads, sampling, VTU. */
cupid_status cupid_problem_fe_build(cupid_problem_state *prob);
cupid_status cupid_problem_fe_impose_field(cupid_problem_state *prob);
/** The vector field @p fn on every DOF of the system: its value at each PD node, the beam's
 *  generalised DOFs (cupid_cuf_interpolate), 0 on the FE nodes where the beam gave way (as the
 *  solve holds them). */
cupid_status cupid_problem_system_field(const cupid_problem_state *prob, cupid_cuf_field_fn fn,
                                        void *ctx, double *x);
/** Unit-translation vectors: t[k * ndof + d] = generalised DOF d of the field e_k. */
cupid_status cupid_problem_translations(const cupid_problem_state *prob, double *t);

/* frames.c: what a run hands its output writers (io.h, "Output writers"). */
/** The PD nodes as VTK vertices (made once per run): connectivity, offsets, cell types, the
 *  nodes' volumes (the Exodus SPHERE elements' attribute). */
typedef struct {
  cupid_pd_grid grid;
  cupid_int *conn, *offs;
  unsigned char *types;
  double *volume;
} cupid_problem_vertices;
cupid_status cupid_problem_vertices_build(cupid_pd_grid grid, cupid_problem_vertices *v);
void cupid_problem_vertices_free(cupid_problem_vertices *v);
/** The vertices' mesh with @p n_data point-data arrays. */
cupid_vtu_mesh cupid_problem_vertices_mesh(const cupid_problem_vertices *v,
                                           const cupid_vtu_array *data, int n_data);
/** The most PD fields of a frame. */
#define CUPID_FRAME_FIELDS 4
/** An output step's frame to every writer (NULL ones skipped: a rank that writes no files):
 *  the beam's 3D reconstruction at @p u (with a beam, on the rank that writes) and the PD nodes
 *  (@p verts) with @p fields (this process's values; NULL values: left out). A slab run gathers
 *  the fields on rank 0 (collective) and agrees on the status. */
cupid_status cupid_problem_frame_write(cupid_problem_state *prob, const cupid_problem_vertices *verts,
                                       cupid_int step, double t, const double *u,
                                       const cupid_vtu_array *fields, int n_fields,
                                       cupid_writer *writers, int n_writers);

/** 1 when a static analysis runs load steps (analysis.steps) or crack growth (growth.c). */
int cupid_problem_runs_steps(const cupid_problem_state *prob);
/** 1 when the run writes its frames as it goes (dynamics, load steps and crack growth: their
 *  model.exo time steps), 0 when the report writes the one frame of a static solve. */
int cupid_problem_writes_frames(const cupid_problem_state *prob);

/* dynamic.c: type dynamic. */
/** What type dynamic needs of any model (densities, integrator settings, loads constant). */
cupid_status cupid_problem_dynamic_check(const cupid_problem_state *prob);
/** The "dynamic" block of summary.json. */
void cupid_problem_dynamic_json(cupid_json js, const cupid_problem_state *prob);

/* resume.c: checkpoints and resumption of long runs (issue 36; docs/hardening.md). */
/** Start a resumable run's checkpoints: the period (output.checkpoint, or 600 s when the run is
 *  estimated over 10 minutes), this rank's file, interrupts armed. */
cupid_status cupid_problem_checkpoint_begin(cupid_problem_state *prob, double estimated_seconds);
/** The seconds between periodic checkpoints of a run estimated to take @p estimated_seconds
 *  (output.checkpoint, or its default; 0: on a signal only). */
double cupid_problem_checkpoint_period(const cupid_problem_state *prob, double estimated_seconds);
/** Disarm the interrupts, free the path (at the end of the run, whatever its status). */
void cupid_problem_checkpoint_end(cupid_problem_state *prob);
/** At a stage's safe point: a checkpoint when one is due (collective), @p fill writing the
 *  stage's sections and this file the common ones; after a signal's, CUPID_ERR_INTERRUPTED
 *  saying the run stopped @p where ("at step 40 of 100 (t = 0.02)"). */
cupid_status cupid_problem_checkpoint_save(cupid_problem_state *prob, cupid_int step,
                                           cupid_status (*fill)(void *ctx, cupid_checkpoint_writer w),
                                           void *ctx, const char *where);
/** Open this rank's checkpoint for --resume (every rank: the same step @p step_section, a
 *  cupid_int, else CUPID_ERR_IO); the counts and history restored into prob. */
cupid_status cupid_problem_checkpoint_open(cupid_problem_state *prob, const char *step_section,
                                           cupid_checkpoint *ck);
/** Before a stage opens its checkpoint (--resume): a copy of this rank's checkpoint's @p
 *  section (*data allocated, *bytes long), its identity checked (an adaptive zone's layout,
 *  which the set-up builds again before the stage reads its state). */
cupid_status cupid_problem_checkpoint_peek(cupid_problem_state *prob, const char *section,
                                           void **data, size_t *bytes);
/** The checkpoint's broken bonds into prob->op (and a method's copy of it) and the damage. */
cupid_status cupid_problem_checkpoint_fracture(cupid_problem_state *prob, const cupid_checkpoint ck);
/** 1 for a run of load steps that grows cracks (PD with fracture): it writes checkpoints and
 *  can be resumed, on every path (growth_resume.c does it). */
int cupid_problem_growth_resumable(const cupid_problem_state *prob);

/* estimate.c: `cupid check` and the memory guard of `cupid run`. */
cupid_status cupid_problem_estimate(const cupid_problem_state *prob, int print);
/** Before the grid is built: refuse a model whose grid, neighbour lists (and, for a solve, matrix
 *  and factor) cannot fit, from lower bounds computed from the regions alone (no allocation);
 *  also grids whose overlapping regions would take hours to build, and output lines of more
 *  than 10^8 points (or 2x10^8 point-region tests) in all. */
cupid_status cupid_problem_guard_size(const cupid_problem_state *prob);
/** A dynamic run's estimated time stepping (s), output bytes and files (0 for others). */
void cupid_problem_run_cost(const cupid_problem_state *prob, double *seconds, double *bytes,
                            double *files);
/** Refuse a run beyond a day, 50 GB or 10^5 output files (unless --allow-large). */
cupid_status cupid_problem_guard_run(const cupid_problem_state *prob);
/** The memory limit (--max-memory, else 90% of the physical memory). */
double cupid_problem_memory_limit(const cupid_problem_state *prob);
/** The estimated cost of each engine for this problem (cupid_solver_cost per engine kind). */
cupid_status cupid_problem_costs(const cupid_problem_state *prob, cupid_solver_cost *direct,
                                 cupid_solver_cost *iterative);

/** The estimate of engine @p e's path for this problem: the factorisation, the method's
 *  matrix-free path where the engine takes it, or the assembled Krylov solve. */
const cupid_solver_cost *cupid_problem_path_cost(const cupid_problem_state *prob,
                                                 const cupid_solver_type *e,
                                                 const cupid_solver_cost *factor,
                                                 const cupid_solver_cost *krylov);
/** `solver: auto` (estimate.c): the available engine of the smallest estimated time whose
 *  estimated memory fits the limit, and why (for the log and summary.json). */
cupid_status cupid_problem_auto_engine(const cupid_problem_state *prob,
                                       const cupid_solver_type **engine, char *why, size_t len);

/** Free everything a problem owns; the struct itself is the caller's. */
void cupid_problem_state_free(cupid_problem_state *prob);

#endif
