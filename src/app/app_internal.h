/* Private to src/app: the state of one `cupid run` and the stages that fill it. */
#ifndef CUPID_APP_INTERNAL_H
#define CUPID_APP_INTERNAL_H

#include "cupid/app.h"
#include "cupid/coupling.h"
#include "cupid/cuf.h"
#include "cupid/dynamics.h"
#include "cupid/model.h"
#include "cupid/pd.h"
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
} cupid_job_dynamic;

/** Where a sampled point lies. */
typedef enum { CUPID_REGION_NONE = 0, CUPID_REGION_PD = 1, CUPID_REGION_FE = 2 } cupid_region_kind;

typedef struct {
  const cupid_model_t *model;
  const cupid_run_options *opts;
  const char *outdir;
  int quiet;

  /* Peridynamics */
  cupid_pd_grid grid;
  cupid_pd_operator op;
  cupid_pd_operator_options pd_options; /**< kept for size estimates */
  cupid_pd_material *pd_materials;      /**< owned; pd_options.materials points here */
  cupid_int n_pd;          /**< PD nodes */
  cupid_int n_bonds;

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

  cupid_job_dynamic dyn;   /**< type: dynamic */

  /* Coupled models (coupled.c) */
  cupid_coupling_h coupling;
  cupid_arlequin_region *arlequin_regions; /**< method arlequin: the layout (owned) */
  int n_arlequin_regions;
  /** A matrix-free K of the whole system (a coupled model's operator, borrowed): explicit
   *  dynamics applies it instead of assembling job->K. */
  cupid_status (*k_apply)(void *ctx, const double *x, double *y);
  void *k_ctx;
  cupid_int n_fictitious;  /**< fictitious PD nodes */

  double load_sum[3], reaction_sum[3];
  cupid_phase_record phases[CUPID_PHASE_COUNT];
  double t_start;

  /* Solver engine (issue 6): DIRECT or PETSC once chosen (AUTO until then), and why. */
  cupid_solver_kind solver;
  char solver_reason[160];

  /* Distributed PD (issue 6, slab.c): this rank holds one z slab of the grid (slab = 1 until
   * rank 0 gathers the results); the grid's n_pd, u, f_ext, f_int, bc are then the slab's. */
  int slab;
  cupid_pd_grid_partition part;  /**< of job->grid */
  int slab_ranks;                /**< > 1: the run was split into this many slabs */
  int slab_nodes_max;            /**< the largest slab (nodes incl. halo) */
} cupid_job;

/* run.c */
void cupid_job_progress(const cupid_job *job, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
void cupid_job_phase_end(cupid_job *job, cupid_phase phase, double t0);

/** run.c: the PD materials and operator options of the model (job->pd_materials,
 *  job->pd_options); a PD region with an orthotropic material is a model error. */
cupid_status cupid_app_pd_options(cupid_job *job);

/* pd_bc.c: constraints and loads on PD nodes (volume layers, faces, points). */
cupid_status cupid_app_pd_constraints(cupid_job *job);
cupid_status cupid_app_pd_loads(cupid_job *job);

/* split.c: which part (beam, PD grid) a constraint or load of a coupled model touches. */
/** A used beam node lies on the plane y. */
int cupid_app_fe_node_at(const cupid_job *job, double y);
/** A used beam node lies in the box's y range. */
int cupid_app_fe_node_in_box(const cupid_job *job, const cupid_box *b);
/** A PD node lies in the box (only y counts on a 1D grid). */
int cupid_app_pd_node_in_box(const cupid_job *job, const cupid_box *b);
/** Run cupid_app_pd_constraints (constraints != 0) or cupid_app_pd_loads on these items only. */
cupid_status cupid_app_pd_stage(cupid_job *job, cupid_constraint *cons, int nc,
                                cupid_load *loads, int nl, int constraints);

/* sample.c: displacement (and stress) at a point, by trilinear interpolation of the grid. */
cupid_status cupid_app_sample(const cupid_job *job, const double p[3], double u[3],
                              double sigma[6], cupid_region_kind *region);

/* slab.c (issue 6): PD-only static models split into z slabs over the MPI ranks. */
/** Several ranks, PD only, 3D, static, solver petsc or auto: split the grid. */
int cupid_app_slab_wanted(const cupid_job *job);
/** The status of every rank agreed (collective): an error on any rank is an error on all, so
 *  that none waits alone in the next collective call (the failing rank keeps its message). */
cupid_status cupid_app_slab_agree(cupid_status st);
/** Node i counts on this rank (always, unless a slab does not own it). */
int cupid_app_pd_owned(const cupid_job *job, cupid_int node);
/** A count of owned nodes summed over the ranks of a slab run (collective there). */
cupid_int cupid_app_global_count(const cupid_job *job, cupid_int count);
/** cupid_app_check_points against the whole grid, built on rank 0 for the check (collective). */
cupid_status cupid_app_slab_check_points(cupid_job *job);
/** After the solve: stresses of the slab, every owned field gathered on rank 0, which then
 *  holds the whole grid and fields (job->slab = 0 there) for the outputs (collective). */
cupid_status cupid_app_slab_collect(cupid_job *job);

/* report.c: every file of output: (summary.json, lines, pd_nodes.csv, VTU, plots). */
/** The outputs need nodal PD stresses (VTU, or a point with stress). */
int cupid_app_needs_stress(const cupid_job *job);
cupid_status cupid_app_write_outputs(cupid_job *job);
/** Every output point must lie inside the model (checked before solving). */
cupid_status cupid_app_check_points(const cupid_job *job);

/* fe.c: the CUF beam of a model: creation, constraints, loads, sampling, VTU. */
cupid_status cupid_app_fe_build(cupid_job *job);
cupid_status cupid_app_fe_constraints(cupid_job *job);
cupid_status cupid_app_fe_loads(cupid_job *job);
cupid_status cupid_app_fe_impose_field(cupid_job *job);
/** Unit-translation vectors: t[k * ndof + d] = generalised DOF d of the field e_k. */
cupid_status cupid_app_translations(const cupid_job *job, double *t);
cupid_status cupid_app_fe_write_vtu(cupid_job *job, const char *path);

/* dynamic.c: type dynamic (FE-only and PD-only models). */
cupid_status cupid_app_dynamic_check(const cupid_job *job);
/** Assemble K (unless job->K is already set, e.g. a coupled global K) and M, integrate, write
 *  history.csv, energies.csv, the VTU series and plots. */
cupid_status cupid_app_run_dynamic(cupid_job *job);
/** The "dynamic" block of summary.json. */
void cupid_app_dynamic_json(cupid_json js, const cupid_job *job);

/* coupled.c: beam + peridynamics models (paper 000 section 4, fictitious nodes). */
int cupid_app_is_coupled(const cupid_job *job);
/** Refuse what coupled models cannot do yet (methods, 1D grids, dynamics). */
cupid_status cupid_app_coupled_check(const cupid_job *job);
/** Make the beam give way inside the PD regions (after the beam is built). */
cupid_status cupid_app_coupled_prepare(cupid_job *job);
/** Constraints, loads, the coupled matrix and the solve (or `evaluate`). */
cupid_status cupid_app_coupled_run(cupid_job *job);

/* check.c: `cupid check` and the memory guard of `cupid run`. */
cupid_status cupid_app_estimate(const cupid_job *job, int print);
/** Before the grid is built: refuse a model whose grid, neighbour lists (and, for a solve, matrix
 *  and factor) cannot fit, from lower bounds computed from the regions alone (no allocation);
 *  also grids whose overlapping regions would take hours to build, and output lines of more
 *  than 10^8 points (or 2x10^8 point-region tests) in all. */
cupid_status cupid_app_guard_size(const cupid_job *job);

/* run.c (issue 6): the engine of this run and the linear solve through it. */
/** Resolve --solver / analysis.solver (auto: direct below the size limit, PETSc above when
 *  built with it) into job->solver and job->solver_reason; initialises PETSc when it is picked. */
cupid_status cupid_app_choose_solver(cupid_job *job);

/** Free everything a job owns (run.c); the job's struct itself is the caller's. */
void cupid_app_job_destroy(cupid_job *job);

/** 1 when a coupled model is solved matrix-free (--solver petsc on one rank, fictitious nodes,
 *  static, 3D PD): coupled.c; the estimate (check.c) follows it. */
int cupid_app_coupled_matrix_free(const cupid_job *job);

/** The coupled model's constraints (beam / PD split, FE nodes inside the regions fixed at 0;
 *  not finalized) and loads (split likewise; Lagrange: loads on tied nodes through the tie):
 *  coupled.c, shared with the matrix-free setup (coupled_setup.c). */
cupid_status cupid_app_coupled_apply_constraints(cupid_job *job);
cupid_status cupid_app_coupled_apply_loads(cupid_job *job);
/** check.c: the memory limit (--max-memory, else 90% of the physical memory) and the estimated
 *  peak bytes and factorisation seconds of the direct path (the grid and beam built). */
double cupid_app_memory_limit(const cupid_job *job);
cupid_status cupid_app_direct_cost(const cupid_job *job, double *bytes, double *seconds);
/** `solver: auto` keeps the direct solver while its estimated peak memory stays below this share
 *  of the memory limit and its factorisation below these seconds. */
#define CUPID_AUTO_DIRECT_MEMORY_SHARE 0.25
#define CUPID_AUTO_DIRECT_SECONDS 120.0
int cupid_app_auto_picks_direct(const cupid_job *job, double bytes, double seconds);
/** Solve job->K u = f_ext with job->bc by the chosen engine into job->u and job->solve. */
cupid_status cupid_app_linear_solve(cupid_job *job, cupid_matrix_kind kind);

#endif
