/* Coupling by fictitious nodes (paper 000 section 4; src/coupling/fictitious.c): the beam gives
 * way inside the PD regions, constraints and loads go to the part they touch, and the coupled
 * matrix of Eq. 38 is solved by UMFPACK (it is not symmetric), or without the PD matrix by the
 * PETSc engine: GMRES preconditioned by the LU of a cheap bond-based twin (src/coupling/
 * operator.c, solvers/krylov.c; issue 6), on one rank or several (the PD grid in z slabs).
 *
 * Fracture (issue 34): with pre-cracks or bond breaking the method keeps one matrix-free
 * operator for the run (its state), whose PD operator on the extended grid (real + fictitious
 * nodes) loses every bond prob->op loses (cupid_pd_operator_copy_broken_mapped, through
 * prob->crack_copy and crack_map). The coupling zone, whose bonds never break, is the span of
 * the fictitious FE elements (the PD nodes their fits read, and what lies between them and the
 * interface) and every real node whose family reaches a fictitious node
 * (cupid_coupling_operator_zone): a bond broken outside it changes Eq. 38 in real rows and
 * columns only, by the same symmetric, rigid-mode-free terms as on the model grid, so the fits
 * of Eqs. 33-36 and the balance's C = K^T R stay valid without rebuilding (docs/theory.md,
 * "Fracture with fictitious nodes"). The assembled K is the kept operator's, assembled again
 * after breaks; growth re-solves it by GMRES on the last LU (growth_lu.c), or on the PETSc
 * engine by the kept matrix-free solve. */
#include <stdio.h>
#include <string.h>

#include "method.h"

/* The method's state (prob->method_state) when the model has pre-cracks or fracture. */
typedef struct {
  cupid_coupling_operator A; /* the fictitious-node operator, kept for the run */
} fict_state;

static void free_state(cupid_problem_state *prob) {
  fict_state *s = prob->method_state;
  if (!s) return;
  cupid_coupling_operator_destroy(&s->A);
  cupid_free(&s);
  prob->method_state = NULL;
  prob->crack_copy = NULL;
  prob->crack_map = NULL;
}

/* The state: the coupled operator of the model, built once (timed as the coupling phase);
 * crack_copy and crack_map point into it, so that every fracture step's breaks reach it. */
static cupid_status create_state(cupid_problem_state *prob) {
  cupid_status st = CUPID_SUCCESS;
  fict_state *s = NULL;
  cupid_box *boxes = NULL;
  int *mats = NULL;
  cupid_coupling_options co;
  const double t0 = cupid_wtime();
  CUPID_TRY(cupid_calloc(1, sizeof *s, "fictitious-node state", &s));
  CUPID_TRY(cupid_method_coupling_options(prob, &co, &boxes, &mats));
  st = cupid_coupling_operator_create(prob->beam, prob->grid, &co, &s->A);
  CUPID_TRY(prob->slab ? cupid_problem_slab_agree(st) : st);
  cupid_coupling_info ci;
  cupid_coupling_operator_get_info(s->A, &ci);
  prob->n_fictitious = ci.n_fictitious_pd;
  prob->crack_copy = cupid_coupling_operator_pd(s->A);
  prob->crack_map = cupid_coupling_operator_extended_nodes(s->A);
  prob->method_state = s;
  s = NULL;
  cupid_problem_phase_end(prob, CUPID_PHASE_COUPLING, t0);
cleanup:
  if (s) cupid_coupling_operator_destroy(&s->A);
  cupid_free(&s);
  cupid_free(&boxes);
  cupid_free(&mats);
  return st;
}

/* The kept operator, its PD bonds brought to prob->op's: the pre-cracks, and on a path that did
 * not see them, the breaks (crack_copy carries those of each fracture step as they happen). */
static cupid_status kept_operator(cupid_problem_state *prob, cupid_coupling_operator *out) {
  if (!prob->method_state) CUPID_CALL(create_state(prob));
  CUPID_CALL(cupid_pd_operator_copy_broken_mapped(prob->crack_copy, prob->op, prob->crack_map));
  *out = ((fict_state *)prob->method_state)->A;
  return CUPID_SUCCESS;
}

static cupid_status check(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  /* the fictitious nodes and elements need a 3D grid */
  if (m->pd.dimension != 3)
    return cupid_model_error(m, &m->pd.mark,
                             "a coupled model needs a 3D peridynamic grid (dimension: 3) with "
                             "method fictitious (1D grids: methods lagrange and arlequin)");
  if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC)
    return cupid_model_error(m, &m->analysis.mark,
                             "type dynamic is not supported with coupling method fictitious: its "
                             "coupled operator (paper 000 Eq. 38) is a static, non-symmetric "
                             "construction with massless fictitious nodes (see docs/dynamics.md); "
                             "use `coupling: {method: lagrange}` or `{method: arlequin}` for "
                             "coupled dynamics, or type static or evaluate");
  return CUPID_SUCCESS;
}

static cupid_status constraints(cupid_problem_state *prob) {
  return cupid_method_split_constraints(prob, NULL);
}

/* With pre-cracks or fracture: the kept operator's K (its PD bonds those of prob->op). */
static cupid_status assemble_kept(cupid_problem_state *prob, cupid_coupling_info *ci) {
  cupid_coupling_operator A = NULL;
  CUPID_CALL(kept_operator(prob, &A));
  const double t0 = cupid_wtime();
  CUPID_CALL(cupid_coupling_operator_assemble(A, NULL, &prob->K));
  cupid_problem_phase_end(prob, CUPID_PHASE_COUPLING, t0);
  cupid_coupling_operator_get_info(A, ci);
  return CUPID_SUCCESS;
}

static cupid_status assemble(cupid_problem_state *prob) {
  if (prob->K) return CUPID_SUCCESS;
  cupid_coupling_info ci;
  if (prob->damage) CUPID_CALL(assemble_kept(prob, &ci));
  else CUPID_CALL(cupid_method_build_coupling(prob, cupid_coupling_create, &ci));
  prob->n_fictitious = ci.n_fictitious_pd;
  cupid_problem_progress(prob,
                         "coupling (fictitious nodes): %d interfaces, %lld fictitious PD nodes, "
                         "%lld fictitious FE nodes; %lld non-zeros (%.1f MB)",
                         ci.n_interfaces, (long long)ci.n_fictitious_pd,
                         (long long)ci.n_fictitious_fe, (long long)cupid_csr_nnz(prob->K),
                         (double)cupid_csr_bytes(prob->K) / 1e6);
  return CUPID_SUCCESS;
}

/* `balance: momentum`: K' = K - W C^T by the factor of K_ff and six more solves (balance.c);
 * else the engine's solve of Eq. 38. */
static cupid_status solve_assembled(cupid_problem_state *prob) {
  if (!cupid_problem_balanced(prob)) return cupid_problem_assembled_solve(prob);
  /* the balanced solve reuses a SuiteSparse factor; an iterative engine's assembled path
   * (--assembled) has none, and silently factoring instead would not be what was asked */
  CUPID_CHECK(!prob->engine->iterative, CUPID_ERR_UNSUPPORTED,
              "coupling.balance (momentum, the default, or global) runs on the direct solver or "
              "the matrix-free path of solver %s, not on its assembled path (--assembled): drop "
              "--assembled, or set coupling.balance: none for paper 000's Eq. 38 as printed",
              prob->engine->name);
  return cupid_problem_balanced_direct_solve(prob);
}

/* An iterative engine (krylov, petsc), static, 3D: matrix-free unless --assembled asks for
 * Eq. 38 assembled (PETSc: its rows split over the ranks, GMRES + block Jacobi/ILU). */
static int matrix_free(const cupid_problem_state *prob, const cupid_solver_type *engine) {
  return engine->solve_operator && !prob->opts->assembled && prob->grid &&
         cupid_pd_grid_dimension(prob->grid) == 3;
}

static void destroy_operator(void **ctx) {
  cupid_coupling_operator A = *ctx;
  cupid_coupling_operator_destroy(&A);
  *ctx = NULL;
}

static cupid_status solve_matrix_free(cupid_problem_state *prob) {
  cupid_status st = CUPID_SUCCESS;
  cupid_box *boxes = NULL;
  int *mats = NULL;
  cupid_coupling_options co;
  cupid_coupling_operator A = NULL, kept = NULL; /* pre-cracks: the kept operator has them */
  cupid_coupling_balance B = NULL;
  cupid_csr P = NULL;
  double t0 = cupid_wtime();
  if (prob->damage) CUPID_TRY(kept_operator(prob, &kept));
  CUPID_TRY(cupid_method_coupling_options(prob, &co, &boxes, &mats));
  /* a slab: every rank's failure stops all of them before the next collective call */
  st = kept ? CUPID_SUCCESS : cupid_coupling_operator_create(prob->beam, prob->grid, &co, &A);
  if (st == CUPID_SUCCESS) st = cupid_coupling_preconditioner(kept ? kept : A, 1.5, &P);
  CUPID_TRY(prob->slab ? cupid_problem_slab_agree(st) : st);
  const cupid_coupling_operator use = kept ? kept : A;
  cupid_coupling_info ci; /* the whole model's, on a slab too */
  cupid_coupling_operator_get_info(use, &ci);
  prob->n_fictitious = ci.n_fictitious_pd;
  cupid_problem_phase_end(prob, CUPID_PHASE_COUPLING, t0);
  cupid_problem_progress(prob,
                         "coupling (fictitious nodes, matrix-free): %d interfaces, %lld fictitious "
                         "PD nodes, %lld fictitious FE nodes; operator %.1f MB, preconditioner "
                         "matrix %.1f MB%s",
                         ci.n_interfaces, (long long)ci.n_fictitious_pd, (long long)ci.n_fictitious_fe,
                         (double)cupid_coupling_operator_bytes(use) / 1e6,
                         (double)cupid_csr_bytes(P) / 1e6, prob->slab ? " (rank 0's slab)" : "");
  cupid_linear_operator L;
  cupid_coupling_operator_linear(use, &L); /* on a slab: its rows (cupid_krylov_solve) */
  if (cupid_problem_balanced(prob)) /* K' = K - W C^T around L (P stays K's twin) */
    CUPID_TRY(cupid_problem_balanced_operator(prob, use, &L, &B, &L));
  /* the kept operator is the state's: the solve frees neither it nor its owner */
  cupid_method_operator owner = {.ctx = A, .destroy = A ? destroy_operator : NULL};
  st = cupid_method_krylov_solve(prob, &L, &P, &owner);
  A = owner.ctx; /* NULL once a slab freed it */
cleanup:
  cupid_coupling_balance_destroy(&B);
  cupid_csr_destroy(&P);
  cupid_coupling_operator_destroy(&A);
  cupid_free(&boxes);
  cupid_free(&mats);
  return st;
}

/* Growth on the matrix-free path (the PETSc engine, one process or PD slabs): the kept
 * operator (its bonds break with prob->op's through crack_copy), balanced around it when the
 * model asks, and the LU of its cheap twin, made on the intact grid (growth_matrix_free.c). */
typedef struct {
  cupid_coupling_balance B;
} growth_owner;

static void destroy_growth_owner(void **ctx) {
  growth_owner *o = *ctx;
  if (o) cupid_coupling_balance_destroy(&o->B);
  cupid_free(&o);
  *ctx = NULL;
}

static cupid_status growth_operator(cupid_problem_state *prob, cupid_linear_operator *L, cupid_csr *P,
                                    cupid_method_operator *owner) {
  cupid_coupling_operator A = NULL;
  growth_owner *o = NULL;
  cupid_status st = kept_operator(prob, &A);
  if (st == CUPID_SUCCESS) st = cupid_coupling_preconditioner(A, 1.5, P);
  if (st == CUPID_SUCCESS) st = cupid_calloc(1, sizeof *o, "growth operator", &o);
  CUPID_TRY(prob->slab ? cupid_problem_slab_agree(st) : st);
  cupid_coupling_operator_linear(A, L);
  if (cupid_problem_balanced(prob)) CUPID_TRY(cupid_problem_balanced_operator(prob, A, L, &o->B, L));
  *owner = (cupid_method_operator){.ctx = o, .destroy = destroy_growth_owner};
  return CUPID_SUCCESS;
cleanup:
  if (o) cupid_coupling_balance_destroy(&o->B);
  cupid_free(&o);
  cupid_csr_destroy(P);
  return st;
}

/* The nodes inside the span of a fictitious FE element (the fit boxes of the FE rows that read
 * PD columns; on slabs joined over the ranks): *core, one flag per PD node of the grid. */
static cupid_status fit_core(cupid_problem_state *prob, cupid_coupling_operator A, unsigned char *core) {
  const cupid_int nfe = prob->fe_info.n_fe_nodes;
  double *b = NULL;
  cupid_status st = cupid_malloc(6 * (size_t)nfe + 1, sizeof *b, "fit boxes", &b);
  if (st == CUPID_SUCCESS) st = cupid_coupling_operator_fit_boxes(A, prob->beam, b);
  if (prob->slab) CUPID_TRY(cupid_problem_slab_agree(st));
  CUPID_TRY(st);
  if (prob->slab) { /* lo by the max of -lo */
    for (cupid_int a = 0; a < nfe; a++)
      for (int c = 0; c < 3; c++) b[6 * a + c] = -b[6 * a + c];
    cupid_petsc_max_doubles(b, 6 * nfe);
    for (cupid_int a = 0; a < nfe; a++)
      for (int c = 0; c < 3; c++) b[6 * a + c] = -b[6 * a + c];
  }
  /* the distinct boxes (the section nodes of one interface share theirs, nearly) */
  cupid_int nb = 0;
  const double tol = 1e-9 * prob->model->pd.spacing;
  for (cupid_int a = 0; a < nfe; a++) {
    const double *q = b + 6 * a;
    if (!(q[0] <= q[3])) continue;
    int seen = 0;
    for (cupid_int k = 0; k < nb && !seen; k++) {
      const double *p = b + 6 * k;
      seen = p[0] <= q[0] + tol && p[1] <= q[1] + tol && p[2] <= q[2] + tol &&
             p[3] >= q[3] - tol && p[4] >= q[4] - tol && p[5] >= q[5] - tol;
    }
    if (!seen) memmove(b + 6 * nb++, q, 6 * sizeof *b);
  }
  const double *x = cupid_pd_grid_coords(prob->grid);
  for (cupid_int i = 0; i < prob->n_pd; i++)
    for (cupid_int k = 0; k < nb && !core[i]; k++) {
      const double *p = b + 6 * k, *xi = x + 3 * i;
      core[i] = xi[0] >= p[0] - tol && xi[0] <= p[3] + tol && xi[1] >= p[1] - tol &&
                xi[1] <= p[4] + tol && xi[2] >= p[2] - tol && xi[2] <= p[5] + tol;
    }
cleanup:
  cupid_free(&b);
  return st;
}

/* The coupling zone, whose bonds never break: the real nodes inside a fictitious FE element's
 * span (a crack between an interface and the planes its element reads would be bridged by the
 * beam's stiffness; a crack may come up to those planes) and every node whose family reaches a
 * fictitious node (their rows of Eq. 38 read the beam through Eqs. 29-30). A pre-crack there is a model error, a crack
 * that comes there stops the run (growth.c, check_blocked). */
static cupid_status fracture_protect(const cupid_problem_state *prob, unsigned char *protect) {
  cupid_problem_state *p = (cupid_problem_state *)prob; /* the state is the problem's */
  cupid_coupling_operator A = NULL;
  unsigned char *core = NULL;
  CUPID_CALL(kept_operator(p, &A));
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_calloc((size_t)prob->n_pd + 1, 1, "fit spans", &core));
  CUPID_TRY(fit_core(p, A, core));
  CUPID_TRY(cupid_coupling_operator_zone(A, core, protect));
cleanup:
  cupid_free(&core);
  return st;
}

/* The stop message's name of the zone at x: the region holding it, with its line. */
static void protected_zone(const cupid_problem_state *prob, const double x[3], char *buf, size_t len) {
  const cupid_model_t *m = prob->model;
  const double h = m->pd.spacing;
  for (int r = 0; r < m->pd.n_regions; r++)
    if (cupid_box_contains(&m->pd.regions[r].box, x, 1e-9 * h)) {
      snprintf(buf, len, "the fictitious-node coupling zone of PD region %d (peridynamics.regions[%d], "
               "line %d: the span of its fictitious FE elements and the families of its "
               "fictitious nodes, near "
               "(%g, %g, %g); a shorter coupling.fictitious_fe or finer beam elements next to "
               "the region narrow it)",
               r, r, m->pd.regions[r].mark.line, x[0], x[1], x[2]);
      return;
    }
  snprintf(buf, len, "the fictitious-node coupling zone (the span of the fictitious FE elements "
           "and the families of the fictitious nodes, near (%g, %g, %g))", x[0], x[1], x[2]);
}

/* Matrix-free Eq. 38 + LU of the cheap twin. Memory: ~1.6 kB a PD node for the operator and
 * the cheap matrix, ~40 kB for its factor (MUMPS on cbeam_web200, 10^5 PD nodes: 4.3 GB,
 * bench/README_coupled.md; UMFPACK, solver krylov: 0.16 GB for the 4,000 nodes of the coupled
 * bar). Time: ~25 operator products at ~1.5e7 bonds a second a pass (LPS: two passes; GMRES
 * took 23-32 iterations on the bar, the C-beam and the panel) and the twin's factor, ~2e-4 s a
 * PD node (measured 0.7-2.3 s on those three, loaded 2-core machine). */
static int estimate_matrix_free(const cupid_problem_state *prob, double *bytes, double *seconds,
                                const char **what) {
  if (prob->model->analysis.type != CUPID_ANALYSIS_STATIC || !prob->grid ||
      cupid_pd_grid_dimension(prob->grid) != 3)
    return 0;
  const double passes = prob->model->pd.model == CUPID_PD_LPS ? 2.0 : 1.0;
  *bytes = 42e3 * (double)prob->n_pd + 30.0 * (double)prob->ndof * 8.0;
  *seconds = 1.0 + 25.0 * passes * (double)prob->n_bonds / 1.5e7 + 2e-4 * (double)prob->n_pd;
  *what = "matrix-free GMRES + LU of a bond-based twin";
  return 1;
}

const cupid_method_ops cupid_method_fictitious = {
    .name = "fictitious",
    .caps = CUPID_METHOD_SLABS | CUPID_METHOD_GUARD_MATRIX_FREE | CUPID_METHOD_FRACTURE |
            CUPID_METHOD_ADAPTIVE,
    .matrix = CUPID_MATRIX_GENERAL, /* Eq. 38 is not symmetric: UMFPACK, GMRES */
    .check = check,
    .prepare = cupid_method_deactivate_regions,
    .constraints = constraints,
    .loads = cupid_method_split_loads,
    .assemble = assemble,
    .solve_assembled = solve_assembled,
    .matrix_free = matrix_free,
    .solve_matrix_free = solve_matrix_free,
    .report = cupid_method_print_equilibrium,
    .estimate_matrix_free = estimate_matrix_free,
    .fracture_protect = fracture_protect,
    .protected_zone = protected_zone,
    .growth_operator = growth_operator,
    .free_state = free_state,
};
