/* The PD operator: families, weighted volumes, material constants, and the dispatch of the
 * matrix-free operations to the stencil kernels (stencil.c; the default) or the bond-list
 * kernels (lps.c, bond.c; with stencil_off), and of energy and stress (lps.c, bond.c). */
#include <math.h>
#include <string.h>

#include "pd/pd_internal.h"

void cupid_pd_operator_destroy(cupid_pd_operator *op) {
  if (!op || !*op) return;
  struct cupid_pd_operator_private *o = *op;
  pd_stencil_free(&o->st);
  cupid_free(&o->clin);
  cupid_free(&o->full);
  cupid_free(&o->fptr);
  cupid_free(&o->fidx);
  cupid_free(&o->runs);
  cupid_free(&o->pclin);
  cupid_free(&o->pclin_opp);
  pd_pair_plan_free(&o->plan);
  cupid_free(&o->ncorr);
  cupid_free(&o->gptr);
  cupid_free(&o->gseg);
  pd_stencil_work_free(o);
  cupid_free(&o->bptr);
  cupid_free(&o->bnbr);
  cupid_free(&o->bst);
  cupid_free(&o->m);
  cupid_free(&o->kappa);
  cupid_free(&o->mu);
  cupid_free(&o->c);
  cupid_free(&o->gself);
  cupid_free(&o->sf);
  pd_fracture_free(o);
  cupid_free(op);
}

/* The materials the grid's nodes use must be valid elastic PD materials; the others (a
 * model's beam-only materials, orthotropic ones included) are not read. */
static cupid_status check_materials(const struct cupid_pd_grid_private *g,
                                    const cupid_pd_operator_options *opts) {
  CUPID_CHECK(opts->materials && opts->n_materials > 0, CUPID_ERR_ARGUMENT,
              "the PD operator needs materials");
  unsigned char *used = NULL;
  CUPID_CALL(cupid_calloc((size_t)opts->n_materials, 1, "material flags", &used));
  for (cupid_int i = 0; i < g->nnodes; i++)
    if (g->material[i] >= 0 && g->material[i] < opts->n_materials) used[g->material[i]] = 1;
  cupid_status st = CUPID_SUCCESS;
  for (int k = 0; k < opts->n_materials && st == CUPID_SUCCESS; k++) {
    const cupid_pd_material *mat = &opts->materials[k];
    if (!used[k]) continue;
    if (!(isfinite(mat->E) && mat->E > 0))
      st = CUPID_ERROR(CUPID_ERR_MODEL, "PD material %d: Young's modulus must be positive, got %g",
                       k, mat->E);
    else if (!(isfinite(mat->nu) && mat->nu > -1 && mat->nu < 0.5))
      st = CUPID_ERROR(CUPID_ERR_MODEL, "PD material %d: Poisson's ratio must lie in (-1, 0.5), got %g",
                       k, mat->nu);
  }
  cupid_free(&used);
  CUPID_CALL(st);
  for (cupid_int i = 0; i < g->nnodes; i++)
    CUPID_CHECK(g->material[i] >= 0 && g->material[i] < opts->n_materials, CUPID_ERR_ARGUMENT,
                "PD node %lld has material %d, but only %d materials were given", (long long)i,
                g->material[i], opts->n_materials);
  return CUPID_SUCCESS;
}

/* m_i (Eq. 18), per-node constants, micromoduli and dilatation self-weights. */
static cupid_status node_data(struct cupid_pd_operator_private *op,
                              const cupid_pd_operator_options *opts) {
  const struct cupid_pd_grid_private *g = op->grid;
  const pd_stencil *S = &op->st;
  const cupid_int nn = op->nnodes;
  CUPID_CALL(cupid_malloc((size_t)nn, sizeof *op->m, "PD weighted volumes", &op->m));
  CUPID_CALL(cupid_malloc((size_t)nn, sizeof *op->kappa, "PD constants", &op->kappa));
  CUPID_CALL(cupid_malloc((size_t)nn, sizeof *op->mu, "PD constants", &op->mu));
  if (op->model == CUPID_PD_BOND)
    CUPID_CALL(cupid_malloc((size_t)nn, sizeof *op->c, "PD micromoduli", &op->c));
  else
    CUPID_CALL(cupid_malloc(3 * (size_t)nn, sizeof *op->gself, "PD dilatation weights", &op->gself));
  /* Bond-based calibration on the full stencil: S = sum omega x beta V. */
  double Sfull = 0.0;
  for (int s = 0; s < S->n; s++) Sfull += S->wb[s] * S->x[s] * op->V;
  /* A full family's sums, the same for every full node: summed once, in the same order. */
  double m_full = 0.0, gs_full[3] = {0, 0, 0};
  for (int s = 0; s < S->n; s++) {
    m_full += S->wb[s] * S->x[s] * S->x[s] * op->V;
    for (int c = 0; c < 3; c++) gs_full[c] += S->wxn[3 * s + c];
  }
  op->m_full = m_full, op->S_full = Sfull;
  cupid_int empty = -1;
#pragma omp parallel for schedule(static) if (nn > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < nn; i++) {
    double m = m_full, gs[3] = {gs_full[0], gs_full[1], gs_full[2]};
    if (!op->full[i] || op->phi) { /* cut cells: every family weighs its neighbours' volumes */
      const pd_family F = pd_family_of(op, i);
      m = gs[0] = gs[1] = gs[2] = 0.0;
      for (int q = 0; q < F.n; q++) {
        const int s = pd_family_entry(&F, q);
        const double phj = pd_phi(op, pd_family_node(op, &F, s));
        m += S->wb[s] * S->x[s] * S->x[s] * op->V * phj;
        for (int c = 0; c < 3; c++) gs[c] += S->wxn[3 * s + c] * phj;
      }
    }
    op->m[i] = m;
    if (!(m > 0)) {
#pragma omp critical(pd_empty)
      empty = i;
    }
    const cupid_pd_material *mat = &opts->materials[g->material[i]];
    const double K = mat->E / (3.0 * (1.0 - 2.0 * mat->nu)), mu = mat->E / (2.0 * (1.0 + mat->nu));
    op->kappa[i] = 3.0 * K - 5.0 * mu;
    op->mu[i] = mu;
    if (op->c) op->c[i] = (op->dim == 3 ? 18.0 * K : 2.0 * mat->E) / Sfull;
    if (op->gself)
      for (int c = 0; c < 3; c++) op->gself[3 * i + c] = gs[c];
  }
  if (empty >= 0) {
    const double *x = g->coords + 3 * empty;
    return CUPID_ERROR(CUPID_ERR_MODEL,
                       "PD node %lld at (%g, %g, %g) has no neighbour within the horizon %g",
                       (long long)empty, x[0], x[1], x[2], op->delta);
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_pd_operator_create(const cupid_pd_grid grid,
                                      const cupid_pd_operator_options *opts,
                                      cupid_pd_operator *op) {
  cupid_status st = CUPID_SUCCESS;
  struct cupid_pd_operator_private *o = NULL;
  CUPID_CHECK(grid && opts && op, CUPID_ERR_ARGUMENT, "operator needs grid, options and output");
  *op = NULL;
  CUPID_CHECK(opts->model == CUPID_PD_LPS || opts->model == CUPID_PD_BOND, CUPID_ERR_ARGUMENT,
              "unknown PD model %d", (int)opts->model);
  CUPID_CHECK(opts->model == CUPID_PD_BOND || grid->dim == 3, CUPID_ERR_UNSUPPORTED,
              "the LPS model needs a 3D grid; use model: bond for a 1D bar");
  CUPID_CHECK(opts->influence >= CUPID_INFLUENCE_GAUSSIAN && opts->influence <= CUPID_INFLUENCE_CONSTANT,
              CUPID_ERR_ARGUMENT, "unknown influence function %d", (int)opts->influence);
  CUPID_CHECK(opts->partial_volume >= CUPID_PARTIAL_NONE && opts->partial_volume <= CUPID_PARTIAL_EXACT,
              CUPID_ERR_ARGUMENT, "unknown partial-volume rule %d", (int)opts->partial_volume);
  CUPID_CHECK(opts->surface_correction == CUPID_SURFACE_NONE ||
                  opts->surface_correction == CUPID_SURFACE_ENERGY,
              CUPID_ERR_ARGUMENT, "unknown surface correction %d", (int)opts->surface_correction);
  CUPID_CALL(check_materials(grid, opts));
  CUPID_TRY(cupid_calloc(1, sizeof *o, "the PD operator", &o));
  o->grid = grid;
  o->model = opts->model;
  o->influence = opts->influence;
  o->rule = opts->partial_volume;
  o->delta = opts->horizon;
  o->h = grid->h;
  o->V = grid->volume;
  o->phi = grid->vfrac;
  o->dim = grid->dim;
  o->nnodes = grid->nnodes;
  CUPID_TRY(pd_stencil_build(o->dim, o->h, o->delta, o->rule, o->influence, &o->st));
  CUPID_TRY(pd_families_build(o));
  CUPID_TRY(node_data(o, opts));
  CUPID_TRY(pd_ghosts_build(o));
  CUPID_TRY(pd_uniform_build(o));
  o->surface = opts->surface_correction;
  /* The corrected kernels and cut cells carry per-bond factors: they run on explicit bond
   * lists (the stencil path assumes every full family is the same). */
  if (o->surface != CUPID_SURFACE_NONE || o->phi) CUPID_TRY(pd_operator_use_bond_lists(o));
  if (o->surface != CUPID_SURFACE_NONE) CUPID_TRY(pd_surface_factors(o));
  *op = o;
  o = NULL;
cleanup:
  cupid_pd_operator_destroy(&o);
  return st;
}

cupid_status pd_operator_use_bond_lists(struct cupid_pd_operator_private *op) {
  if (!op->bptr) CUPID_CALL(pd_neighbors_build(op->grid, &op->st, &op->bptr, &op->bnbr, &op->bst));
  op->stencil_off = 1;
  return CUPID_SUCCESS;
}

cupid_int cupid_pd_operator_num_bonds(const cupid_pd_operator op) { return op->nbonds; }

cupid_int cupid_pd_operator_num_bonds_range(const cupid_pd_operator op, cupid_int first,
                                            cupid_int last) {
  cupid_int n = 0;
  for (cupid_int i = first; i < last; i++) n += pd_family_of(op, i).n;
  return n;
}

cupid_status cupid_pd_operator_halo_layers(const cupid_pd_operator_options *opts, double h,
                                           int *layers) {
  CUPID_CHECK(opts && layers, CUPID_ERR_ARGUMENT, "halo layers need options");
  pd_stencil S = {0};
  CUPID_CALL(pd_stencil_build(3, h, opts->horizon, opts->partial_volume, opts->influence, &S));
  int reach = 0;
  for (int s = 0; s < S.n; s++) {
    int dk = S.off[3 * s + 2] < 0 ? -S.off[3 * s + 2] : S.off[3 * s + 2];
    if (dk > reach) reach = dk;
  }
  pd_stencil_free(&S);
  /* Row i reads theta_j, m_j and the surface factors of every neighbour j, each of which
   * reads j's own family: two hops, for both models (bond-based with the surface correction
   * reads G_ji of the neighbour). */
  *layers = 2 * reach;
  return CUPID_SUCCESS;
}

const double *cupid_pd_operator_weighted_volume(const cupid_pd_operator op) { return op->m; }

cupid_status cupid_pd_operator_dilatation(const cupid_pd_operator op, const double *u,
                                          double *theta) {
  CUPID_CHECK(op && u && theta, CUPID_ERR_ARGUMENT, "dilatation needs operator, u and theta");
  if (op->model == CUPID_PD_LPS)
    pd_lps_dilatation(op, 0, op->nnodes, u, theta);
  else
    memset(theta, 0, (size_t)op->nnodes * sizeof *theta);
  return CUPID_SUCCESS;
}

/* The bond-list path (stencil_off): rows [first, last) from the explicit bonds. */
static cupid_status apply_bond_lists(const struct cupid_pd_operator_private *op, cupid_int first,
                                     cupid_int last, const double *u, double *f) {
  if (op->model == CUPID_PD_BOND) {
    pd_bond_apply(op, first, last, u, f);
    return CUPID_SUCCESS;
  }
  cupid_int lo = 0, hi = op->nnodes;
  if (first > 0 || last < op->nnodes) pd_neighbour_span(op, first, last, &lo, &hi);
  double *theta = NULL;
  /* theta is indexed by global node (8 bytes a node); only [lo, hi) is computed and read. */
  CUPID_CALL(cupid_malloc((size_t)op->nnodes, sizeof *theta, "PD dilatations", &theta));
  pd_lps_dilatation(op, lo, hi, u, theta);
  pd_lps_apply(op, first, last, u, theta, f);
  cupid_free(&theta);
  return CUPID_SUCCESS;
}

cupid_status cupid_pd_operator_apply(const cupid_pd_operator op, const double *u, double *f) {
  CUPID_CHECK(op && u && f, CUPID_ERR_ARGUMENT, "apply needs operator, u and f");
  return cupid_pd_operator_apply_range(op, 0, op->nnodes, u, f);
}

cupid_status cupid_pd_operator_dependency_range(const cupid_pd_operator op, cupid_int first,
                                                cupid_int last, cupid_int *lo, cupid_int *hi) {
  CUPID_CHECK(op && lo && hi, CUPID_ERR_ARGUMENT, "dependency range needs operator and outputs");
  CUPID_CHECK(first >= 0 && first <= last && last <= op->nnodes, CUPID_ERR_ARGUMENT,
              "node range [%lld, %lld) outside [0, %lld)", (long long)first, (long long)last,
              (long long)op->nnodes);
  if (first == last) {
    *lo = *hi = first;
    return CUPID_SUCCESS;
  }
  pd_neighbour_span(op, first, last, lo, hi);
  if (op->model == CUPID_PD_LPS) pd_neighbour_span(op, *lo, *hi, lo, hi); /* theta_j needs j's family */
  return CUPID_SUCCESS;
}

cupid_status cupid_pd_operator_apply_range(const cupid_pd_operator op, cupid_int first,
                                           cupid_int last, const double *u, double *f) {
  CUPID_CHECK(op && u && f, CUPID_ERR_ARGUMENT, "apply_range needs operator, u and f");
  CUPID_CHECK(first >= 0 && first <= last && last <= op->nnodes, CUPID_ERR_ARGUMENT,
              "node range [%lld, %lld) outside [0, %lld)", (long long)first, (long long)last,
              (long long)op->nnodes);
  if (first == last) return CUPID_SUCCESS;
  if (op->stencil_off) return apply_bond_lists(op, first, last, u, f);
  return pd_stencil_apply(op, first, last, u, f, NULL);
}

cupid_status cupid_pd_operator_energy(const cupid_pd_operator op, const double *u, double *energy) {
  CUPID_CHECK(op && u && energy, CUPID_ERR_ARGUMENT, "energy needs operator, u and output");
  if (op->model == CUPID_PD_BOND) {
    *energy = pd_bond_energy(op, u);
    return CUPID_SUCCESS;
  }
  double *theta = NULL;
  CUPID_CALL(cupid_malloc((size_t)op->nnodes, sizeof *theta, "PD dilatations", &theta));
  pd_lps_dilatation(op, 0, op->nnodes, u, theta);
  *energy = pd_lps_energy(op, u, theta);
  cupid_free(&theta);
  return CUPID_SUCCESS;
}

cupid_status cupid_pd_operator_stress(const cupid_pd_operator op, const double *u, double *sigma) {
  CUPID_CHECK(op && u && sigma, CUPID_ERR_ARGUMENT, "stress needs operator, u and sigma");
  if (op->model == CUPID_PD_BOND) {
    pd_bond_stress(op, u, sigma);
    return CUPID_SUCCESS;
  }
  double *theta = NULL;
  CUPID_CALL(cupid_malloc((size_t)op->nnodes, sizeof *theta, "PD dilatations", &theta));
  pd_lps_dilatation(op, 0, op->nnodes, u, theta);
  pd_lps_stress(op, u, theta, sigma);
  cupid_free(&theta);
  return CUPID_SUCCESS;
}

/* ------------------------------------------------- the PD operator as a node operator
 * What the matrix-free PETSc solve reads of it (solvers.h, cupid_node_operator). */

static cupid_status node_apply_range(const cupid_node_operator *A, cupid_int n0, cupid_int n1,
                                     const double *x, double *y) {
  return cupid_pd_operator_apply_range((cupid_pd_operator)A->op, n0, n1, x, y);
}

static cupid_status node_dependency_range(const cupid_node_operator *A, cupid_int n0, cupid_int n1,
                                          cupid_int *lo, cupid_int *hi) {
  return cupid_pd_operator_dependency_range((cupid_pd_operator)A->op, n0, n1, lo, hi);
}

static cupid_status node_diagonal(const cupid_node_operator *A, double *blocks) {
  return cupid_pd_operator_diagonal((cupid_pd_operator)A->op, blocks);
}

static cupid_status node_preconditioner_rows(const cupid_node_operator *A, double radius,
                                             cupid_int n0, cupid_int n1, cupid_csr *rows) {
  return cupid_pd_assemble_rows_bond((cupid_pd_grid)A->grid, A->materials, radius, n0, n1, rows);
}

void cupid_pd_node_operator(const cupid_pd_operator op, const cupid_pd_grid grid,
                            const cupid_pd_material *materials, cupid_node_operator *A) {
  *A = (cupid_node_operator){.op = op, .grid = grid, .materials = materials,
                             .nodes = cupid_pd_grid_num_nodes(grid),
                             .dimension = cupid_pd_grid_dimension(grid),
                             .spacing = cupid_pd_grid_spacing(grid),
                             .coords = cupid_pd_grid_coords(grid),
                             .apply_range = node_apply_range,
                             .dependency_range = node_dependency_range,
                             .diagonal = node_diagonal,
                             .preconditioner_rows = node_preconditioner_rows};
  cupid_pd_grid_get_partition(grid, &A->part);
}

void cupid_pd_operator_full_family(const cupid_pd_operator op, double *m, double *S) {
  *m = op->m_full;
  *S = op->S_full;
}
