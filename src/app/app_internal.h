/* Private to src/app: the state of one `cupid run` and the stages that fill it. */
#ifndef CUPID_APP_INTERNAL_H
#define CUPID_APP_INTERNAL_H

#include "cupid/app.h"
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

  /* The linear system: 3 DOFs per PD node (later issues append FE DOFs). */
  cupid_int ndof;
  cupid_csr K;
  cupid_dirichlet bc;
  double *u;               /**< displacements */
  double *f_ext;           /**< applied loads */
  double *f_int;           /**< K u (internal force; = loads + reactions at equilibrium) */
  double *pd_stress;       /**< 6 per PD node, or NULL */
  cupid_solve_info solve;
  int solved;              /**< a linear solve was done */

  double load_sum[3], reaction_sum[3];
  cupid_phase_record phases[CUPID_PHASE_COUNT];
  double t_start;
} cupid_job;

/* run.c */
void cupid_job_progress(const cupid_job *job, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
void cupid_job_phase_end(cupid_job *job, cupid_phase phase, double t0);

/* pd_bc.c: constraints and loads on PD nodes (volume layers, faces, points). */
cupid_status cupid_app_pd_constraints(cupid_job *job);
cupid_status cupid_app_pd_loads(cupid_job *job);

/* sample.c: displacement (and stress) at a point, by trilinear interpolation of the grid. */
cupid_status cupid_app_sample(const cupid_job *job, const double p[3], double u[3],
                              double sigma[6], cupid_region_kind *region);

/* report.c: every file of output: (summary.json, lines, pd_nodes.csv, VTU, plots). */
cupid_status cupid_app_write_outputs(cupid_job *job);
/** Every output point must lie inside the model (checked before solving). */
cupid_status cupid_app_check_points(const cupid_job *job);

/* check.c: `cupid check` and the memory guard of `cupid run`. */
cupid_status cupid_app_estimate(const cupid_job *job, int print);
/** Before the grid is built: refuse a model whose grid, neighbour lists (and, for a solve, matrix
 *  and factor) cannot fit, from lower bounds computed from the regions alone (no allocation);
 *  also grids whose overlapping regions would take hours to build, and output lines of more
 *  than 10^8 points (or 2x10^8 point-region tests) in all. */
cupid_status cupid_app_guard_size(const cupid_job *job);

#endif
