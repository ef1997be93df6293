/**
 * @file problem.h
 * @brief One model, from its file to its results: the problem object.
 *
 * The life cycle follows PETSc's Create / SetUp / Solve / Destroy:
 *
 *     cupid_problem p = NULL;
 *     CUPID_CALL(cupid_problem_create_from_file("bar.yaml", NULL, &p));
 *     CUPID_CALL(cupid_problem_setup(p));     // grid, beam, coupling layout, constraints, loads
 *     CUPID_CALL(cupid_problem_solve(p));     // static solve, dynamics or `evaluate`
 *     const double *u; cupid_int n; int nc;
 *     CUPID_CALL(cupid_problem_get_field(p, CUPID_FIELD_PD_DISPLACEMENT, &u, &n, &nc));
 *     CUPID_CALL(cupid_problem_write_outputs(p)); // the model's `output:` files (optional)
 *     cupid_problem_destroy(&p);
 *
 * The problem owns every object it builds (grid, PD operator, beam, coupling, matrices, fields);
 * pointers returned by the getters stay valid until the next stage call or destroy. Errors
 * follow base.h: a status, and cupid_error_message() for the text (model errors name the
 * file, line, column and key). Calling a stage out of order is CUPID_ERR_ARGUMENT.
 *
 * The command line (`cupid run`) is create, setup, solve, write_outputs, destroy
 * (src/app/cli.c). docs/architecture.md shows the stages and the tables behind them.
 */
#ifndef CUPID_PROBLEM_H
#define CUPID_PROBLEM_H

#include "cupid/base.h"
#include "cupid/coupling.h"
#include "cupid/cuf.h"
#include "cupid/model.h"
#include "cupid/pd.h"
#include "cupid/solvers.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Options of a run beyond the model file (the command line's flags). Zero-initialise and
 *  set solver = -1 to keep the model's; cupid_run_options_default() does both. */
typedef struct {
  const char *output_dir;   /**< -o DIR, overrides output.directory (NULL: keep) */
  int solver;               /**< -1 keep the model's; else a cupid_solver_kind */
  int threads;              /**< --threads N (0 = default) */
  double max_memory_gb;     /**< --max-memory (0 = default limit) */
  int quiet;                /**< --quiet: no progress messages on stderr */
  int check_only;           /**< `cupid check`: set up the layout and estimate; solve nothing */
  int replicate;            /**< --replicate: under mpirun keep the whole model on every rank */
  int assembled;            /**< --assembled: PETSc solves of coupled models on the assembled
                                 matrix instead of the matrix-free operator */
  int allow_large;          /**< --allow-large: run a dynamic analysis estimated beyond a day,
                                 50 GB or 10^5 output files */
  int resume;               /**< --resume: continue an interrupted run from its checkpoint
                                 (issue 36; CUPID_ERR_IO when there is none) */
  const char *const *sets;  /**< --set key.path=value overrides of the model file (create_from_
                                 file, create_from_string; model.h cupid_model_read_with) */
  int n_sets;
} cupid_run_options;

/** The defaults: keep the model's solver, every other option off. */
cupid_run_options cupid_run_options_default(void);

/** A problem: a model being built, solved and reported. */
typedef struct cupid_problem_private *cupid_problem;

/** Create a problem for @p model (borrowed: it must outlive the problem). @p opts may be NULL
 *  (the defaults); it is copied. */
cupid_status cupid_problem_create(const cupid_model_t *model, const cupid_run_options *opts,
                                  cupid_problem *p);
/** Read the model file @p path (the problem owns the model) and create the problem. */
cupid_status cupid_problem_create_from_file(const char *path, const cupid_run_options *opts,
                                            cupid_problem *p);
/** Read a model from YAML text (@p name stands for the file in error messages). */
cupid_status cupid_problem_create_from_string(const char *yaml, const char *name,
                                              const cupid_run_options *opts, cupid_problem *p);

/** Everything before the solve: the checks of what this version can run, the size guard, the
 *  PD grid and operator, the beam, the coupling layout, the output points, the solver choice,
 *  the constraints and the loads. With opts.check_only the constraints and loads are skipped
 *  and cupid_problem_print_estimate() may follow. */
cupid_status cupid_problem_setup(cupid_problem p);
/** The analysis: the static solve (direct or PETSc, assembled or matrix-free), the time
 *  integration (type dynamic, which writes its time series to the output directory) or
 *  `evaluate`; then the reactions. Under mpirun every rank calls it; afterwards rank 0 holds
 *  the whole model. */
cupid_status cupid_problem_solve(cupid_problem p);
/** Write the files of the model's `output:` section (summary.json, lines, pd_nodes.csv, VTU,
 *  plots) into the output directory. Rank 0 writes; other ranks return at once. */
cupid_status cupid_problem_write_outputs(cupid_problem p);
/** `cupid check`: print counts, the solver choice and the memory estimate to stdout (after
 *  setup). */
cupid_status cupid_problem_print_estimate(cupid_problem p);
/** Free everything; *p becomes NULL (NULL is accepted). */
void cupid_problem_destroy(cupid_problem *p);

/** Fields of a problem. PD fields have one row per real PD node (fictitious nodes excluded);
 *  beam fields one row per point of the beam's 3D reconstruction (the points of beam.vtu). */
typedef enum {
  CUPID_FIELD_PD_COORDINATES = 0, /**< x, y, z of the PD nodes (after setup) */
  CUPID_FIELD_PD_DISPLACEMENT,    /**< ux, uy, uz (after solve) */
  CUPID_FIELD_PD_FORCE,           /**< K u: the internal force = load + reaction (after solve) */
  CUPID_FIELD_PD_LOAD,            /**< the applied load vector's PD part (after setup) */
  CUPID_FIELD_PD_STRESS,          /**< sxx syy szz syz sxz sxy, nodal (after solve) */
  CUPID_FIELD_BEAM_POINTS,        /**< x, y, z of the beam's reconstruction points (after setup) */
  CUPID_FIELD_BEAM_DISPLACEMENT,  /**< ux, uy, uz at those points (after solve) */
  CUPID_FIELD_PD_DAMAGE,          /**< damage per PD node, 1 component (after setup: the
                                       pre-cracks'; after solve: with the broken bonds); *n = 0
                                       for a model without pre-cracks or fracture */
  CUPID_FIELD_COUNT
} cupid_field;

/** The field's values (row-major, *n rows of *components; borrowed, valid until the next stage
 *  call or destroy). A field the model lacks (PD fields of a beam-only model) gives *n = 0. */
cupid_status cupid_problem_get_field(cupid_problem p, cupid_field field, const double **values,
                                     cupid_int *n, int *components);

/** Type dynamic: the history of the output points, one row a step (*n_rows rows of *n_cols =
 *  1 + 3 n_points: t, then ux uy uz of each output point in the model's order), as
 *  history.csv holds it (borrowed; after solve; *n_rows = 0 for other analyses). */
cupid_status cupid_problem_get_history(cupid_problem p, const double **rows, cupid_int *n_rows,
                                       int *n_cols);

/** Where a sampled point lies. */
typedef enum { CUPID_REGION_NONE = 0, CUPID_REGION_PD = 1, CUPID_REGION_FE = 2 } cupid_region_kind;

/** Displacement u[3 * k ..] (and, when @p stress is not NULL, stress[6 * k ..] in the order of
 *  CUPID_FIELD_PD_STRESS) at n points xyz[3 * k ..], as the output lines and points sample them
 *  (model-format.md): the CUF expansion inside the beam, trilinear interpolation of the grid in
 *  a PD region, NaN outside the model (region NONE). @p region may be NULL. Of the current
 *  solution: after solve (or after a program filled u of cupid_problem_get_system). */
cupid_status cupid_problem_sample(cupid_problem p, cupid_int n, const double *xyz, double *u,
                                  double *stress, int *region);

/** Resultants of the applied loads and of the reactions (K u - f on constrained DOFs) for the
 *  problem's current u and internal forces: the work against a unit translation (after solve,
 *  or after a program filled u and f_int of cupid_problem_get_system). */
cupid_status cupid_problem_force_sums(cupid_problem p, double load[3], double reaction[3]);

/** What the problem holds and what the run did (cupid_problem_get_info). */
typedef struct {
  int stage;                    /**< 0 created, 1 set up, 2 solved */
  const char *analysis;         /**< "static", "dynamic", "evaluate" */
  const char *coupling;         /**< "none", "fictitious", "lagrange", "arlequin" */
  const char *solver;           /**< "direct" or "petsc" (after setup; check_only: the choice) */
  const char *solver_reason;    /**< why (auto's estimate, or "requested") */
  const char *method;           /**< after solve: "cholmod", "umfpack", "petsc", "none" */
  cupid_int pd_nodes, bonds, fictitious_nodes, fe_nodes, fe_dofs, dofs, constrained_dofs;
  int matrix_free;              /**< the solve never assembled the PD stiffness */
  int iterations;               /**< Krylov iterations (0 for a direct solve) */
  double residual;              /**< |f - K u| / |f| on the free DOFs */
  double load_sum[3];           /**< resultant of the applied loads */
  double reaction_sum[3];       /**< resultant of the reactions */
  double imbalance;             /**< |load + reaction| / |load| (0 when no load) */
  double phase_seconds[6];      /**< grid, assembly, coupling, factorisation, solve, output */
  double total_seconds;
  int64_t peak_memory_bytes;
  /* The coupling's quality (coupled models; docs/coupling.md, "The quality report of a coupled
   * run"): */
  double ghost_force;           /**< patch test: the largest ghost force over its scale (-1:
                                     not run: uncoupled, materials differ, or not solved) */
  int quality_warnings;         /**< bits: 1 ghost force over 1e-2, 2 imbalance over 1e-2 */
  /* Static crack growth (analysis.steps with fracture): */
  const char *stopped;          /**< why the growth stopped before its last step (a crack
                                     reached a coupling zone, whose bonds never break), or
                                     NULL when it ran to the end; the results are written and
                                     the command line exits with status 2 */
  double peak_load_factor;      /**< the load factor of the largest reaction of constraint 0
                                     on the sawtooth envelope (growth.c), 0 when none */
  double peak_reaction[3];      /**< that reaction */
} cupid_problem_info;

cupid_status cupid_problem_get_info(cupid_problem p, cupid_problem_info *info);

/** The pieces of a set-up problem, for programs that go beyond its stages (benchmarks,
 *  studies): borrowed, valid until the problem is destroyed. u and f_int are written by the
 *  solve; a program may also fill them itself. */
typedef struct {
  cupid_pd_grid grid;          /**< NULL without peridynamics */
  cupid_pd_operator op;
  cupid_cuf_beam beam;         /**< NULL without a beam; inside the regions it gave way */
  cupid_int ndof, fe_offset;   /**< [3 per PD node | FE DOFs from fe_offset] */
  const cupid_dirichlet_t *bc; /**< finalized */
  const double *f_ext;         /**< the loads */
  double *u, *f_int;
} cupid_problem_system;

cupid_status cupid_problem_get_system(cupid_problem p, cupid_problem_system *system);
/** The coupling's options for the src/coupling constructors (region arrays owned by the
 *  problem). */
cupid_status cupid_problem_coupling_options(cupid_problem p, cupid_coupling_options *co);

/** The model's output points (output.points): how many, and point k's name (borrowed),
 *  coordinates and whether it asks for the stress. */
int cupid_problem_output_point_count(cupid_problem p);
cupid_status cupid_problem_output_point(cupid_problem p, int k, const char **name, double xyz[3],
                                        int *stress);

/** Where cupid_problem_write_outputs() writes: -o, else the model's output.directory. */
const char *cupid_problem_output_directory(cupid_problem p);

/** The model a problem was created with (borrowed). */
const cupid_model_t *cupid_problem_model(cupid_problem p);

/** Run a model as `cupid run` does: create, setup, solve, write_outputs, destroy (with
 *  opts->check_only: create, setup, print_estimate). */
cupid_status cupid_run_model(const cupid_model_t *model, const cupid_run_options *opts);

#ifdef __cplusplus
}
#endif
#endif
