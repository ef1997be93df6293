/* Size, memory and time estimates: printed by `cupid check`, and the guard that makes
 * `cupid run` refuse a model that cannot fit before it allocates the big arrays.
 *
 * Stored matrix: one 3x3 block (72 B of values + 8 B of column index) per coupled node pair,
 * counted by cupid_pd_operator_estimate (exact for bond-based; for LPS, which couples nodes up
 * to 2 delta apart, the grid nodes within two stencil hops: an upper bound).
 * Direct factor: nested dissection on a 3D grid gives nnz(L) ~ c n^(4/3) and flops ~ n^2;
 * c and the time scale are fitted to the CHOLMOD measurements on this class of machine in
 * shared/reference/dependencies.md (bond-based, delta = 3h: 20^3 -> 5.3e7 nnz(L), 3.7 s;
 * 40^3 -> 1.23e9, 232 s). LPS couples nodes 2 delta apart: bench/bench_pd_cube measured
 * 15^3 -> 2.38e7 nnz(L), 3.3 s and 20^3 -> 1.08e8, 19 s, i.e. about 3x the fill and 7.5x the
 * time of the bond-based fit. An estimate to decide what fits, not a promise. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "method.h"

/* Limits of a dynamic run without --allow-large (cupid_problem_guard_run). */
#define RUN_SECONDS_LIMIT 86400.0
#define OUTPUT_BYTES_LIMIT 50e9
#define OUTPUT_FILES_LIMIT 1e5

typedef struct {
  double matrix_blocks, matrix_bytes;
  double factor_nnz, factor_bytes, factor_seconds;
  double total_bytes;
  double growth_bytes; /* crack growth's peak on this path (the downdated factor's copy), or 0 */
  /* The PETSc path (docs/scale.md): bytes per rank with one rank, seconds of setup + solve. */
  int iterative_matrix_free;
  double iterative_bytes, iterative_seconds;
  const char *direct_name, *iterative_what;
} cupid_estimate;

/* UMFPACK's LU of the non-symmetric coupled matrix (paper 000 Eq. 38, with CHOLMOD's ordering,
 * src/solvers/direct.c) against the CHOLMOD fit, measured peak / factorisation time: the
 * coupled bar (examples/bar/bar.yaml) 1.73 GB / 5.5 s where the fit says 0.76 GB of factor,
 * 1.02 GB in all, 6.9 s (memory factor 1.9, time 0.8); the C-beam (cbeam_pd_l9) 2.63 GB / 9 s
 * against 1.35, 1.69 GB, 15.7 s (1.7, 0.6); the panel (panel_pd_l9) 1.27 GB / 2.8 s against
 * 0.60, 0.76 GB, 4.6 s (1.85, 0.6). Rounded up, so that solver auto errs towards the safe
 * side. */
#define CUPID_UMFPACK_FILL_FACTOR 2.0
#define CUPID_UMFPACK_TIME_FACTOR 1.0

/* Crack growth on the direct path downdates CHOLMOD's factor, which cholmod_updown needs as a
 * simplicial LDL' (a value and a 64-bit row index per entry): the supernodal factor is copied
 * into that form at the first round of breaks, both alive while it is (factor.c
 * simplicial_ldl). Measured on the coupled SENB (Arlequin, corrected; bench/
 * fracture_senb_scale.sh, senb_study.py): the growth's peak over the static estimate, per entry
 * of the estimated factor, 5.7, 5.8, 5.4, 6.9 and 7.8 bytes at h = 1, 5/6, 1/2, 5/12 and 1/3
 * (0.315, 0.622, 2.6, 5.7 and 14.3 GB against 0.227, 0.442, 1.86, 3.77 and 8.99 GB). */
#define GROWTH_COPY_BYTES_PER_ENTRY 8.0

/* Matrix and factor sizes for n PD nodes and the given number of stored 3x3 blocks. */
static void estimate_sizes(const cupid_model_t *m, double n, double blocks, cupid_estimate *e) {
  double ndof = 3.0 * n;
  double ratio = m->pd.horizon / m->pd.spacing;
  e->matrix_blocks = blocks;
  e->matrix_bytes = e->matrix_blocks * 80.0 + 8.0 * n;
  double fill = m->pd.model == CUPID_PD_LPS ? 3.0 : 1.0;
  if (m->pd.dimension == 1) {
    e->factor_nnz = ndof * 3.0 * (2 * ratio + 1); /* banded */
    e->factor_seconds = 1e-7 * e->factor_nnz;
  } else {
    e->factor_nnz = fill * 77.0 * pow(ndof, 4.0 / 3.0);
    double slow = m->pd.model == CUPID_PD_LPS ? 7.5 : 1.0;
    e->factor_seconds = slow * 3.7 * (ndof / 24000.0) * (ndof / 24000.0);
  }
  double dense = 0.5 * ndof * ndof;
  if (e->factor_nnz > dense) e->factor_nnz = dense;
  e->factor_bytes = 12.0 * e->factor_nnz;
  /* K, its reduced one-triangle copy for CHOLMOD (about half of K at 12 B/entry), factor. */
  e->total_bytes = e->matrix_bytes + 0.5 * 9.0 * e->matrix_blocks * 12.0 + e->factor_bytes +
                   10.0 * ndof * 8.0;
}

/* The direct path's peak: a growth run's when its factor is copied for the downdates. */
static double direct_peak(const cupid_estimate *e) {
  return e->growth_bytes > 0 ? e->growth_bytes : e->total_bytes;
}

static cupid_status estimate(const cupid_problem_state *prob, cupid_estimate *e) {
  cupid_pd_estimate pe;
  CUPID_CALL(cupid_pd_operator_estimate(prob->grid, &prob->pd_options, &pe));
  estimate_sizes(prob->model, (double)prob->n_pd, (double)pe.blocks, e);
  return CUPID_SUCCESS;
}

static double physical_memory(void) {
  long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
  return pages > 0 && size > 0 ? (double)pages * (double)size : 0.0;
}

/* The beam's matrix: its exact pattern (cheap to build) and a banded-profile bound for the
 * factor, since the beam axis orders the DOFs into a band of a few elements' width. */
static cupid_status estimate_fe(const cupid_problem_state *prob, cupid_estimate *e) {
  cupid_int *rowptr = NULL, *col = NULL;
  CUPID_CALL(cupid_cuf_pattern(prob->beam, &rowptr, &col));
  cupid_int nb = prob->fe_info.n_fe_nodes;
  double blocks = (double)rowptr[nb];
  cupid_free(&rowptr);
  cupid_free(&col);
  double ndof = (double)prob->n_fe_dofs, bw = 9.0 * blocks / ndof;
  e->matrix_blocks += blocks;
  e->matrix_bytes += blocks * 80.0 + 8.0 * (double)nb;
  e->factor_nnz += 2.0 * ndof * bw;
  e->factor_bytes += 24.0 * ndof * bw;
  e->factor_seconds += 4e-10 * ndof * bw * bw;
  e->total_bytes += 1.5 * blocks * 80.0 + 24.0 * ndof * bw + 10.0 * ndof * 8.0;
  return CUPID_SUCCESS;
}

double cupid_problem_memory_limit(const cupid_problem_state *prob) {
  return prob->opts->max_memory_gb > 0 ? prob->opts->max_memory_gb * 1e9 : 0.9 * physical_memory();
}
#define memory_limit cupid_problem_memory_limit

/* The direct engine factors a non-symmetric system (fictitious nodes, Eq. 38) by UMFPACK. */
static int general_matrix(const cupid_problem_state *prob) {
  return prob->method->matrix == CUPID_MATRIX_GENERAL;
}

/* ... but load steps and crack growth by block elimination (growth_block.c): CHOLMOD of the PD
 * block, within the CHOLMOD fit (the SENB at h = 1: 7.4 M entries against the whole K's LU's
 * 14.1 M), and the beam's small LU. */
static int block_elimination(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  return general_matrix(prob) && prob->beam && prob->grid &&
         (m->analysis.steps > 0 || (m->has_peridynamics && m->pd.fracture.has_fracture));
}

/* The iterative path: the method's matrix-free estimate where it has one (method_*.c), else
 * the assembled Krylov solve: cupid's K, PETSc's AIJ copy (12 B per entry) and ~50% more for
 * the preconditioner (GAMG hierarchy or ILU factors); per iteration about one pass over the
 * matrix at ~2 GB/s; 40 CG or 150 GMRES iterations. An estimate, not a promise. */
static void estimate_iterative(const cupid_problem_state *prob, cupid_estimate *e) {
  double ndof = (double)prob->ndof;
  const char *what = NULL;
  e->iterative_matrix_free = prob->method->estimate_matrix_free &&
                             prob->method->estimate_matrix_free(prob, &e->iterative_bytes,
                                                                &e->iterative_seconds, &what);
  e->iterative_what = e->iterative_matrix_free ? what : "Krylov + AMG/ILU, assembled";
  if (e->iterative_matrix_free) return;
  double entries = 9.0 * e->matrix_blocks;
  e->iterative_bytes = e->matrix_bytes + 1.5 * 12.0 * entries + 30.0 * ndof * 8.0;
  e->iterative_seconds = 1.0 + (general_matrix(prob) ? 150.0 : 40.0) * 12.0 * entries / 2e9 +
                         3.0 * 12.0 * entries / 2e9;
}

/* Both paths' figures (the direct one with UMFPACK's measured fill for a general matrix). */
static cupid_status estimate_all(const cupid_problem_state *prob, cupid_estimate *e) {
  memset(e, 0, sizeof *e);
  if (prob->grid) CUPID_CALL(estimate(prob, e));
  if (prob->beam) CUPID_CALL(estimate_fe(prob, e));
  e->direct_name = "CHOLMOD";
  if (block_elimination(prob)) e->direct_name = "CHOLMOD + Schur";
  else if (general_matrix(prob)) { /* UMFPACK LU, measured above the CHOLMOD fit */
    e->total_bytes += (CUPID_UMFPACK_FILL_FACTOR - 1.0) * e->factor_bytes;
    e->factor_bytes *= CUPID_UMFPACK_FILL_FACTOR;
    e->factor_nnz *= CUPID_UMFPACK_FILL_FACTOR;
    e->factor_seconds *= CUPID_UMFPACK_TIME_FACTOR;
    e->direct_name = "UMFPACK";
  }
  estimate_iterative(prob, e);
  const cupid_model_t *m = prob->model;
  if (m->analysis.type == CUPID_ANALYSIS_STATIC && m->has_peridynamics && m->pd.fracture.has_fracture &&
      (!general_matrix(prob) || block_elimination(prob))) /* a CHOLMOD factor is downdated */
    e->growth_bytes = e->total_bytes + GROWTH_COPY_BYTES_PER_ENTRY * e->factor_nnz;
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_costs(const cupid_problem_state *prob, cupid_solver_cost *direct,
                                 cupid_solver_cost *iterative) {
  cupid_estimate e;
  CUPID_CALL(estimate_all(prob, &e));
  *direct = (cupid_solver_cost){.bytes = direct_peak(&e), .seconds = e.factor_seconds};
  *iterative = (cupid_solver_cost){.bytes = e.iterative_bytes, .seconds = e.iterative_seconds};
  snprintf(direct->what, sizeof direct->what, "%s", e.direct_name);
  snprintf(iterative->what, sizeof iterative->what, "%s", e.iterative_what);
  return CUPID_SUCCESS;
}

/* How crack growth would re-solve after each round of breaks on @p e (growth.c chooses so:
 * the kept matrix-free solve where the method solves the model matrix-free on that engine,
 * the run's own downdated factor on an assembled SPD K, the engine's solve otherwise), with
 * what it cost on the coupled SENB (bench/README.md). */
static void print_growth_path(const cupid_problem_state *prob, const cupid_solver_type *e) {
  const cupid_model_t *m = prob->model;
  if (!(m->has_peridynamics && m->pd.fracture.has_fracture)) return;
  const int kept = prob->method->matrix_free(prob, e) && e->iterative &&
                   (!prob->beam || prob->method->growth_operator);
  if (kept)
    printf("crack growth on %s: each re-solve iterates from the last solution on the kept "
           "preconditioner of the intact grid (the coupled SENB: 35-45 CG iterations a "
           "re-solve, some 25 times the direct path's growth where both fit)\n", e->name);
  else if (prob->method->matrix == CUPID_MATRIX_SPD && !e->distributed)
    printf("crack growth on %s: one factorisation, downdated by each round's broken bonds "
           "(the coupled SENB: its whole growth 20-21 static solves)\n", e->name);
  else if (!e->iterative)
    printf("crack growth on %s: the LU of the last factorised K, updated by the broken bonds, "
           "and GMRES\n", e->name);
  else
    printf("crack growth on %s: the engine's solve at every re-solve\n", e->name);
}

/* When a run estimated to take @p seconds writes checkpoints (resume.c; issue 36). */
static void print_checkpoints(const cupid_problem_state *prob, double seconds) {
  const double period = cupid_problem_checkpoint_period(prob, seconds);
  if (period > 0) printf("checkpoints: every %g s (output.checkpoint), and on SIGINT or SIGTERM\n", period);
  else printf("checkpoints: on SIGINT or SIGTERM only (output.checkpoint: 0, or a run estimated "
              "under 10 minutes)\n");
}

cupid_status cupid_problem_estimate(const cupid_problem_state *prob, int print) {
  cupid_estimate e;
  CUPID_CALL(estimate_all(prob, &e));
  const char *direct_name = e.direct_name;
  double limit = memory_limit(prob);
  int iterative = prob->engine && prob->engine->iterative;
  if (print && cupid_petsc_rank() != 0) print = 0, iterative = -1; /* rank 0 prints */
  if (iterative < 0) return CUPID_SUCCESS;
  if (print) {
    const cupid_model_t *m = prob->model;
    printf("model: %s", m->file);
    if (m->title[0]) { /* the title's control bytes escaped: a terminal prints them raw */
      printf(" - ");
      for (const unsigned char *c = (const unsigned char *)m->title; *c; c++)
        if (*c < 0x20 || *c == 0x7f) printf("\\x%02x", *c);
        else putchar(*c);
    }
    putchar('\n');
    if (prob->beam)
      printf("beam: %lld nodes, %lld FE nodes, %lld FE DOFs%s\n",
             (long long)prob->fe_info.n_beam_nodes, (long long)prob->fe_info.n_fe_nodes,
             (long long)prob->n_fe_dofs,
             prob->fe_info.poisson_corrected ? "; Poisson-locking correction on (TE0/TE1, "
                                               "sigma_xx = sigma_zz = 0; beam.poisson_correction)"
                                             : "");
    if (prob->beam && m->beam.section_mesh)
      printf("section: %d L%d elements, %d nodes, from %s (Gmsh)\n", m->beam.n_section_elements,
             m->beam.le_nodes, m->beam.n_section_nodes, m->beam.section_mesh);
    if (prob->grid)
      printf("PD nodes: %lld\nbonds: %lld\n", (long long)prob->n_pd, (long long)prob->n_bonds);
    if (prob->grid && prob->n_cut_nodes > 0) {
      printf("PD volume: %.10g (%lld nodes with cut-cell volumes", prob->pd_volume,
             (long long)prob->n_cut_nodes);
      const double lost = cupid_pd_grid_unassigned_volume(prob->grid);
      if (lost > 0) printf("; %.3g of the body in cut cells with no node around is left out", lost);
      printf(")\n");
    }
    for (int k = 0; prob->grid && k < m->pd.n_regions + m->pd.n_holes; k++) {
      const int region = k < m->pd.n_regions;
      const cupid_shape *sh = region ? &m->pd.regions[k].shape : &m->pd.holes[k - m->pd.n_regions].shape;
      if (sh->kind == CUPID_SHAPE_GEOMETRY)
        printf("PD %s %d: the volume of %s, a surface of %lld triangles (Gmsh)\n",
               region ? "region" : "hole", region ? k : k - m->pd.n_regions, sh->file,
               (long long)cupid_surface_num_triangles(sh->surface));
    }
    if (prob->grid && cupid_problem_has_damage(prob)) cupid_problem_fracture_print(prob);
    cupid_problem_adaptive_print(prob, e.total_bytes);
    printf("DOFs: %lld\n", (long long)prob->ndof);
    printf("stiffness matrix: about %.3g stored 3x3 blocks, %.3g GB\n", e.matrix_blocks,
           e.matrix_bytes / 1e9);
    printf("direct solver (%s): about %.3g factor entries, %.3g GB, %.3g s\n", direct_name,
           e.factor_nnz, e.factor_bytes / 1e9, e.factor_seconds);
    printf("estimated peak memory, direct path: %.3g GB (limit %.3g GB)\n", e.total_bytes / 1e9,
           limit / 1e9);
    if (e.growth_bytes > 0)
      printf("estimated peak memory, crack growth on the direct path: %.3g GB (the factor "
             "copied for its downdates)\n", e.growth_bytes / 1e9);
    /* the engines of this build that take the iterative path */
    char takers[96] = "";
    for (int k = 0; cupid_solver_type_at(k); k++) {
      const cupid_solver_type *s = cupid_solver_type_at(k);
      int takes = s->iterative && s->available() &&
                  (prob->method->matrix_free(prob, s) || (!e.iterative_matrix_free && s->distributed));
      if (takes)
        snprintf(takers + strlen(takers), sizeof takers - strlen(takers), "%s%s",
                 takers[0] ? ", " : "", s->name);
    }
    printf("iterative path (%s): about %.3g GB on one rank, %.3g s (%s)\n", e.iterative_what,
           e.iterative_bytes / 1e9, e.iterative_seconds,
           takers[0] ? takers : "no engine of this build takes it: rebuild with PETSc");
    const cupid_solver_type *pick;
    char why[256];
    CUPID_CALL(cupid_problem_auto_engine(prob, &pick, why, sizeof why));
    printf("solver auto would pick: %s (%s)\n", pick->name, why);
    if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC) {
      double rs, rb, rf;
      cupid_problem_run_cost(prob, &rs, &rb, &rf);
      printf("dynamic run: about %.3g s of time stepping, %.3g GB of output in %.0f files%s\n",
             rs, rb / 1e9, rf,
             rs > RUN_SECONDS_LIMIT || rb > OUTPUT_BYTES_LIMIT || rf > OUTPUT_FILES_LIMIT
                 ? " (over the limits: run refuses it without --allow-large)" : "");
      print_checkpoints(prob, rs);
    } else if (m->analysis.type == CUPID_ANALYSIS_STATIC && cupid_problem_growth_resumable(prob)) {
      /* crack growth: at least a solve of the chosen engine per load step */
      const cupid_solver_kind req = prob->opts->solver >= 0 ? (cupid_solver_kind)prob->opts->solver
                                                            : m->analysis.solver;
      const cupid_solver_type *asked = req != CUPID_SOLVER_AUTO ? cupid_solver_type_get(req) : NULL;
      print_growth_path(prob, asked ? asked : pick);
      print_checkpoints(prob, prob->estimate.seconds * (m->analysis.steps > 0 ? m->analysis.steps : 1));
    }
    printf("the model is valid%s\n", limit > 0 && direct_peak(&e) > limit
                                          ? ", but too large for the direct solver on this machine"
                                          : "");
  }
  if (!print && iterative) {
    if (limit > 0 && e.iterative_bytes > limit)
      return CUPID_ERROR(CUPID_ERR_MODEL,
                         "%s: the PETSc path needs about %.3g GB (%lld PD nodes), more than the "
                         "limit of %.3g GB; use --max-memory GB to raise the limit, more ranks "
                         "on more machines, or a coarser grid",
                         prob->model->file, e.iterative_bytes / 1e9, (long long)prob->n_pd,
                         limit / 1e9);
    return CUPID_SUCCESS;
  }
  if (!print && limit > 0 && direct_peak(&e) > limit)
    return CUPID_ERROR(CUPID_ERR_MODEL,
                       "%s: the model needs about %.3g GB (%lld PD nodes; stiffness %.3g GB, "
                       "factor %.3g GB%s), more than the limit of %.3g GB; use --max-memory GB to "
                       "raise the limit, or a coarser grid",
                       prob->model->file, direct_peak(&e) / 1e9, (long long)prob->n_pd,
                       e.matrix_bytes / 1e9, e.factor_bytes / 1e9,
                       e.growth_bytes > 0 ? ", copied for crack growth's downdates" : "",
                       limit / 1e9);
  return CUPID_SUCCESS;
}

/* Lattice offsets o != 0 with |o| <= r (a lower bound of the bonds of a node with a full
 * family, whatever the partial-volume rule): counted exactly up to r = 64 (the largest ratio
 * src/pd accepts), beyond that the ball of radius r - sqrt(3)/2 (volume 4.18879 r^3), which
 * the unit cubes of those offsets cover. */
static double stencil_lower_bound(int dimension, double r) {
  if (dimension == 1) return 2.0 * floor(r + 1e-9);
  if (r > 64) return 4.18879020478639098 * pow(r - 0.8660254037844386, 3);
  int k = (int)floor(r + 1e-9);
  double count = 0, r2 = r * r * (1 + 1e-12);
  for (int a = -k; a <= k; a++)
    for (int b = -k; b <= k; b++)
      for (int c = -k; c <= k; c++) count += (double)(a * a + b * b + c * c) <= r2;
  return count - 1;
}

/* Cells of [lo, hi] on a lattice of spacing h (rounded down: a lower bound). */
static double span_cells(double lo, double hi, double h) {
  double n = floor((hi - lo) / h + 1e-9);
  return n > 0 ? n : 0;
}

/* Output lines: every point is a CSV row (~100 B) sampled against every PD region (each test
 * ~5 ns: 2e8 of them take about a second, in `check` and again when the outputs are written). */
static cupid_status guard_output(const cupid_model_t *m) {
  const cupid_output *o = &m->output;
  double points = o->n_points;
  for (int k = 0; k < o->n_lines; k++) points += o->lines[k].points;
  double regions = m->has_peridynamics && m->pd.n_regions > 0 ? m->pd.n_regions : 1;
  if (points > 1e8)
    return cupid_model_error(m, &o->mark,
                             "the output lines hold %.0f points in all, more than 100000000 "
                             "(about 10 GB of CSV); use fewer points per line",
                             points);
  if (points * regions > 2e8)
    return cupid_model_error(m, &o->mark,
                             "sampling the %.0f output points against the %.0f PD regions would "
                             "take %.3g region tests (at most 2e8); merge regions or use fewer "
                             "points",
                             points, regions, points * regions);
  return CUPID_SUCCESS;
}

/* The beam: DOFs = 3 x beam nodes x expansion terms M, and at least M coupled blocks per FE
 * node for TE (every term couples with every term of its beam node) or le_nodes for LE. A lower
 * bound from the model alone, so a beam that cannot fit is refused before it is built. */
static cupid_status guard_beam(const cupid_problem_state *prob, double limit) {
  const cupid_model_t *m = prob->model;
  const cupid_beam *b = &m->beam;
  if (!m->has_beam || !(limit > 0)) return CUPID_SUCCESS;
  double beam_nodes = 1, terms = 0;
  for (int s = 0; s + 1 < b->n_axis; s++) beam_nodes += (double)b->axis_elements[s] * (b->element_nodes - 1);
  if (b->expansion == CUPID_EXPANSION_TE) {
    terms = 0.5 * (b->te_order + 1) * (b->te_order + 2);
  } else if (b->n_section_nodes > 0) {
    terms = b->n_section_nodes;
  } else {
    double p = b->le_nodes == 16 ? 3 : b->le_nodes == 9 ? 2 : 1; /* nodes per element edge - 1 */
    for (int c = 0; c < b->n_components; c++) /* the largest component: a lower bound */
      terms = fmax(terms, ((b->components[c].nx - 1) * p + 1) * ((b->components[c].nz - 1) * p + 1));
  }
  double dofs = 3 * beam_nodes * terms, fe_nodes = beam_nodes * terms;
  double coupled = b->expansion == CUPID_EXPANSION_TE ? terms : fmin(terms, b->le_nodes);
  double bytes = 40 * dofs + 80 * fe_nodes * coupled; /* vectors + stiffness blocks */
  if (bytes <= limit) return CUPID_SUCCESS;
  return cupid_model_error(m, &b->mark,
                           "the beam has %.0f nodes x %.0f expansion terms = %.3g DOFs and needs "
                           "at least %.3g GB, more than the limit of %.3g GB; use --max-memory GB "
                           "to raise the limit, or fewer elements or a lower expansion order",
                           beam_nodes, terms, dofs, bytes / 1e9, limit / 1e9);
}

/* The volume of a sphere or a bounded cylinder (0 for other shapes). */
static double shape_volume(const cupid_shape *s) {
  const double pi = acos(-1.0), r = s->radius;
  if (s->kind == CUPID_SHAPE_SPHERE) return 4.0 / 3.0 * pi * r * r * r;
  if (s->kind == CUPID_SHAPE_CYLINDER && s->box.has[s->axis])
    return pi * r * r * (s->box.hi[s->axis] - s->box.lo[s->axis]);
  return 0.0;
}

cupid_status cupid_problem_guard_size(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  const cupid_peridynamics *pd = &m->pd;
  CUPID_CALL(guard_output(m));
  CUPID_CALL(guard_beam(prob, memory_limit(prob)));
  double limit = memory_limit(prob), h = pd->spacing;
  if (!m->has_peridynamics || pd->n_regions <= 0 || !(h > 0) || !(limit > 0)) return CUPID_SUCCESS;
  double ratio = pd->horizon / h, reach = ceil(ratio - 1e-9);
  /* Bounding box (the dense cell index is 8 B per cell), the largest region (the union has at
   * least its nodes) and that region's nodes farther than a horizon from its faces. */
  double cells = 1, nodes = 0, bonds = 0, visits = 0;
  double stencil = stencil_lower_bound(pd->dimension, ratio);
  /* Neighbours of a corner node inside its region: at least the lattice cube of side
   * r/sqrt(3) (or the whole region when smaller), which lies within the horizon. */
  double cube = floor(ratio / (pd->dimension == 1 ? 1.0 : sqrt(3.0)) + 1e-9);
  for (int a = 0; a < 3; a++) {
    if (pd->dimension == 1 && a != 1) continue;
    double lo = INFINITY, hi = -INFINITY;
    for (int r = 0; r < pd->n_regions; r++) {
      lo = fmin(lo, pd->regions[r].box.lo[a]);
      hi = fmax(hi, pd->regions[r].box.hi[a]);
    }
    cells *= span_cells(lo, hi, h);
  }
  /* Each region alone: its nodes and the bonds among them are in the union too. Bonds: every
   * node farther than a horizon from the region's faces has the full stencil, every node at
   * least the corner cube. */
  for (int r = 0; r < pd->n_regions; r++) {
    double n = 1, inner = 1, corner = 1;
    for (int a = 0; a < 3; a++) {
      if (pd->dimension == 1 && a != 1) continue;
      double na = span_cells(pd->regions[r].box.lo[a], pd->regions[r].box.hi[a], h);
      n *= na;
      inner *= fmax(0, na - 2 * reach);
      corner *= fmin(na - 1, cube) + 1;
    }
    visits += n;
    if (pd->regions[r].shape.kind != CUPID_SHAPE_BOX || pd->n_holes > 0) {
      /* a shape holds fewer nodes than its box, and holes may take any of them: half the
       * solid's volume is a floor (a sphere's or cylinder's cells whose centres lie inside;
       * a geometry's, or any region with holes: none known) */
      nodes = fmax(nodes, pd->n_holes > 0 ? 0.0 : 0.5 * shape_volume(&pd->regions[r].shape) / (h * h * h));
      continue;
    }
    nodes = fmax(nodes, n);
    bonds = fmax(bonds, fmax(inner * stencil, n * (corner - 1)));
  }
  if (!isfinite(cells) || !isfinite(nodes)) return CUPID_SUCCESS; /* the grid reports it */
  /* The grid builder visits every cell of every region: many overlapping copies of a region
   * (e.g. one anchor aliased 75000 times) would keep it busy for hours in a few KB of file. */
  if (visits > 1e9 && visits > 8 * cells)
    return cupid_model_error(m, &pd->mark,
                             "the %d PD regions overlap so much that building the grid would "
                             "visit %.3g cells, %.3g times the %.0f cells of their bounding box; "
                             "merge the overlapping regions",
                             pd->n_regions, visits, visits / cells, cells);
  /* The LPS matrix pattern pairs every two stencil offsets (pd_stencil_sum, O(stencil^2)):
   * 18 s at horizon/spacing 30 on a 2-core machine, hours at 64 (the largest src/pd accepts);
   * bounded to a few seconds. */
  if (pd->model == CUPID_PD_LPS && pd->dimension == 3 && stencil * stencil > 4e9)
    return cupid_model_error(m, &pd->mark,
                             "horizon/spacing = %g gives an LPS stencil of %.3g offsets: pairing "
                             "them for the matrix pattern would take %.3g steps (at most 4e9, "
                             "about horizon/spacing 24); use a larger spacing",
                             ratio, stencil, stencil * stencil);
  /* Grid: cell index, coordinates, material, lattice position. Operator: a neighbour index and
   * a stencil entry per bond, offsets and per-node data (cupid_pd_operator_estimate). */
  double grid_bytes = 8 * cells + 40 * nodes, op_bytes = 12 * bonds + 80 * nodes;
  double total = grid_bytes + op_bytes, solver_bytes = 0;
  /* The direct solver's matrix and factor count unless PETSc may take the solve (requested, or
   * auto in a build with PETSc: auto then picks it for a model this large). */
  const cupid_solver_type *req = cupid_solver_type_get(
      prob->opts->solver >= 0 ? prob->opts->solver : (int)m->analysis.solver); /* NULL: auto */
  int petsc_may_solve = 0; /* auto: when this build has a matrix-free PD solve */
  for (int k = 0; !req && cupid_solver_type_at(k); k++)
    petsc_may_solve |= cupid_solver_type_at(k)->solve_nodes && cupid_solver_type_at(k)->available();
  if (req) petsc_may_solve = req->solve_nodes != NULL;
  /* central differences on an operator need no matrix either (explicit PD: issue 19) */
  const int explicit_mf = m->analysis.type == CUPID_ANALYSIS_DYNAMIC &&
                          m->analysis.dynamic.integrator == CUPID_INTEGRATOR_CENTRAL &&
                          prob->method->explicit_operator;
  if (!prob->opts->check_only && m->analysis.type != CUPID_ANALYSIS_EVALUATE && !petsc_may_solve &&
      !explicit_mf) {
    cupid_estimate e;
    estimate_sizes(m, nodes, nodes + bonds, &e);
    solver_bytes = e.total_bytes;
  }
  total += solver_bytes + 3 * 3 * 8 * nodes; /* u, loads, internal forces */
  if (total <= limit) return CUPID_SUCCESS;
  char solver[192] = "";
  if (solver_bytes > 0) /* the direct solver counted: PETSc would need far less */
    snprintf(solver, sizeof solver, ", stiffness matrix and factor %.3g GB: the iterative PETSc "
             "engine needs neither (scripts/build.sh --with-petsc, --solver petsc)",
             solver_bytes / 1e9);
  return cupid_model_error(m, &pd->mark,
                           "the model has at least %.0f PD nodes and %.3g bonds and needs at "
                           "least %.3g GB (grid %.3g GB, neighbour lists %.3g GB%s), more than "
                           "the limit of %.3g GB; use --max-memory GB to raise the limit, or a "
                           "coarser grid",
                           nodes, bonds, total / 1e9, grid_bytes / 1e9, op_bytes / 1e9, solver,
                           limit / 1e9);
}

/* ------------------------------------------------------------ the run's time and output
 * A dynamic run of many steps with outputs every step can run for days and write terabytes
 * from a few lines of model file (issue 19). Estimated from the steps, the outputs asked for and
 * the model's size; refused beyond a day, 50 GB or 10^5 files unless --allow-large. The time
 * per step: an operator product at ~3e7 bonds a second a pass on 2 cores (LPS: two passes; the
 * stencil kernels, bench/README.md) or, with an assembled K, ~2 GB/s over its entries. */

void cupid_problem_run_cost(const cupid_problem_state *prob, double *seconds, double *bytes,
                            double *files) {
  const cupid_model_t *m = prob->model;
  *seconds = *bytes = *files = 0.0;
  if (m->analysis.type != CUPID_ANALYSIS_DYNAMIC) return;
  const cupid_dynamic *d = &m->analysis.dynamic;
  const double steps = d->dt > 0 ? floor(d->duration / d->dt + 0.5) : 0.0;
  const double outputs = steps / (d->every > 0 ? d->every : 1) + 1.0;
  const double passes = m->pd.model == CUPID_PD_LPS ? 2.0 : 1.0;
  const double per_step = passes * (double)prob->n_bonds / 3e7 + 9.0 * 12.0 * (double)prob->n_fe_dofs / 2e9;
  *seconds = steps * per_step;
  /* VTU: coordinates, displacement, velocity (base64: 4/3), per output; energies.csv a line
   * per output; history.csv a line per step */
  const double points = (double)prob->n_pd + (prob->beam ? 8.0 * (double)prob->fe_info.n_fe_nodes : 0.0);
  if (m->output.vtu) {
    *bytes += outputs * points * 9.0 * 8.0 * 4.0 / 3.0;
    *files += outputs;
  }
  *bytes += outputs * 150.0 + (m->output.n_points ? steps * (1.0 + 3.0 * m->output.n_points) * 18.0 : 0.0);
}

cupid_status cupid_problem_guard_run(const cupid_problem_state *prob) {
  double seconds, bytes, files;
  cupid_problem_run_cost(prob, &seconds, &bytes, &files);
  if (prob->opts->allow_large) return CUPID_SUCCESS;
  const cupid_model_t *m = prob->model;
  if (seconds > RUN_SECONDS_LIMIT || bytes > OUTPUT_BYTES_LIMIT || files > OUTPUT_FILES_LIMIT)
    return cupid_model_error(m, &m->analysis.dynamic.mark,
                             "this run would take about %.3g hours and write about %.3g GB in "
                             "%.3g files (limits: 24 hours, 50 GB, 1e5 files): raise `every`, "
                             "shorten `duration`, or pass --allow-large to run it anyway",
                             seconds / 3600.0, bytes / 1e9, files);
  return CUPID_SUCCESS;
}

/* ------------------------------------------------------------- the engine auto picks
 * (solver.c uses it; `cupid check` prints it) */

/* The estimate of @p e's path for this problem: the factorisation, the method's matrix-free
 * path where the engine takes it, or (an engine that solves assembled systems by Krylov)
 * the assembled Krylov solve. */
const cupid_solver_cost *cupid_problem_path_cost(const cupid_problem_state *prob,
                                          const cupid_solver_type *e,
                                          const cupid_solver_cost *factor,
                                          const cupid_solver_cost *krylov) {
  if (!e->iterative) return factor;
  if (prob->method->matrix_free(prob, e)) return krylov;
  return e->distributed ? krylov : factor; /* krylov: assembled systems are factored */
}

/* auto: the engine whose estimated time is the smallest among those whose estimated memory
 * stays below a quarter of the limit (a margin: fill-in and iteration counts are estimated,
 * not known; ties: the table's order, the factorisation first); when none does, the one of
 * least memory (the size guard then says what it needs). Analyses other than static take the
 * first engine (the integrators factor or need no solve). */
#define AUTO_MEMORY_SHARE 0.25
/* Load steps and crack growth: the factorisation up to three quarters of the limit (the rest
 * for what the estimate leaves out: outputs, the system). Its re-solves are a downdate and a
 * triangular solve each, where the krylov engine's kept solve takes ~35-45 CG iterations (the
 * twin's factor is the intact grid's): the coupled SENB at h = 1 grew its crack in 15 s on the
 * direct path and 400-800 s on the matrix-free one (493 re-solves, 22,283 iterations;
 * verification.fracture_krylov, bench/README.md). The growth's estimate includes the factor's
 * copy for the downdates (GROWTH_COPY_BYTES_PER_ENTRY): 14.4 GB for the SENB at h = 1/3,
 * whose growth peaked at 14.3 GB (8.99 GB estimated for a static solve, 9.24 measured). */
#define AUTO_GROWTH_MEMORY_SHARE 0.75
cupid_status cupid_problem_auto_engine(const cupid_problem_state *prob,
                                       const cupid_solver_type **engine, char *why, size_t len) {
  const cupid_solver_type *first = cupid_solver_type_at(0), *pick = NULL, *lean = NULL;
  if (prob->model->analysis.type != CUPID_ANALYSIS_STATIC) {
    snprintf(why, len, "auto: the only engine for this analysis");
    *engine = first;
    return CUPID_SUCCESS;
  }
  cupid_solver_cost factor, krylov;
  CUPID_CALL(cupid_problem_costs(prob, &factor, &krylov));
  const double limit = cupid_problem_memory_limit(prob);
  const cupid_model_t *m = prob->model;
  if (!first->iterative && (m->analysis.steps > 0 || (m->has_peridynamics && m->pd.fracture.has_fracture))) {
    /* load steps and crack growth solve many times with one K, changed by few bonds: one
     * factorisation serves them all (downdated as bonds break, growth.c), where an iterative
     * engine iterates afresh at every re-solve */
    const cupid_solver_cost *c = cupid_problem_path_cost(prob, first, &factor, &krylov);
    if (c->bytes <= AUTO_GROWTH_MEMORY_SHARE * limit) {
      snprintf(why, len, "auto: %s (%s; load steps reuse one factorisation), estimate %.3g s and "
               "%.3g GB", first->name, c->what, c->seconds, c->bytes / 1e9);
      *engine = first;
      return CUPID_SUCCESS;
    }
  }
  const cupid_solver_cost *best = NULL, *least = NULL;
  for (int k = 0; cupid_solver_type_at(k); k++) {
    const cupid_solver_type *e = cupid_solver_type_at(k);
    if (!e->available()) continue;
    const cupid_solver_cost *c = cupid_problem_path_cost(prob, e, &factor, &krylov);
    if (!least || c->bytes < least->bytes) least = c, lean = e;
    if (c->bytes <= AUTO_MEMORY_SHARE * limit && (!best || c->seconds < best->seconds))
      best = c, pick = e;
  }
  if (!pick) pick = lean, best = least;
  int n = snprintf(why, len, "auto: %s (%s), estimate %.3g s and %.3g GB", pick->name, best->what,
                   best->seconds, best->bytes / 1e9);
  for (int k = 0; cupid_solver_type_at(k) && n > 0 && (size_t)n < len; k++) { /* the others */
    const cupid_solver_type *e = cupid_solver_type_at(k);
    const cupid_solver_cost *c = e->available() ? cupid_problem_path_cost(prob, e, &factor, &krylov) : NULL;
    if (c && c != best)
      n += snprintf(why + n, len - (size_t)n, "; %s (%s): %.3g s, %.3g GB", e->name, c->what,
                    c->seconds, c->bytes / 1e9);
  }
  *engine = pick;
  return CUPID_SUCCESS;
}
