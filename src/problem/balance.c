/* The balanced fictitious-node coupling at the problem level (`coupling.balance: momentum`;
 * src/coupling/balance.c has the operator and docs/coupling.md the measurements): the six
 * rigid modes of the model's layout, C = K^T R from the assembled K or the matrix-free
 * operator, and the two solves (the factor of K_ff with Sherman-Morrison-Woodbury, or the
 * Krylov solve of the wrapped operator).
 *
 * The patch test of a balanced model reads Eq. 38 itself, K, not K': the balance moves forces
 * between the FE nodes of the interfaces, by each interface's mismatch of the forces the two
 * sides carry. Under the patch test's uniform strain that mismatch is the PD region's stiffness
 * against the beam's (its surface effect: 17% on the small bar of verification.
 * coupling_balance), a real difference that the balanced solve resolves by straining the PD
 * region more, not a ghost force of the coupling. The reads of each other's fields, which the
 * patch test is for, are Eq. 38's; the balance's identities (R^T K' = 0, K' R = 0, K' x = K x
 * when no interface is out of balance) are unit.coupling_balance's. */
#include <math.h>
#include <string.h>

#include "method.h"

typedef struct {
  int k;          /* 0-2: translation along k; 3-5: rotation about axis k - 3 */
  double p0[3];   /* the rotations' centre */
} rigid_mode;

static void rigid_fn(void *ctx, const double p[3], double density, double u[3]) {
  const rigid_mode *m = ctx;
  (void)density;
  u[0] = u[1] = u[2] = 0.0;
  if (m->k < 3) {
    u[m->k] = 1.0;
    return;
  }
  const int a = m->k - 3, b = (a + 1) % 3, c = (a + 2) % 3; /* u = e_a x (p - p0) */
  u[c] = p[b] - m->p0[b];
  u[b] = -(p[c] - m->p0[c]);
}

/* A system's DOF layout: [3 per PD node | the beam's], the PD nodes at x. prob's own, or on a
 * slab the whole model's (slab_balance). */
typedef struct {
  cupid_int n_pd, fe_offset, ndof;
  const double *x;
} layout;

static layout prob_layout(const cupid_problem_state *prob) {
  return (layout){prob->n_pd, prob->fe_offset, prob->ndof, cupid_pd_grid_coords(prob->grid)};
}

/* R: the rigid modes in the layout (inactive FE nodes 0, as the solve holds them; the beam's
 * DOF offset must be the layout's), rotations about the middle of the beam's axis (any centre
 * spans the same space; the middle keeps the columns' scales alike). */
static cupid_status rigid_modes(const cupid_problem_state *prob, const layout *L, double *R) {
  rigid_mode m = {0, {0.0, 0.5 * (prob->fe_info.y_min + prob->fe_info.y_max), 0.0}};
  for (m.k = 0; m.k < CUPID_BALANCE_MODES; m.k++) {
    double *r = R + (size_t)m.k * (size_t)L->ndof;
    for (cupid_int i = 0; i < L->n_pd; i++) rigid_fn(&m, L->x + 3 * i, 0.0, r + 3 * i);
    CUPID_CALL(cupid_cuf_interpolate(prob->beam, rigid_fn, &m, r));
    for (cupid_int n = 0; n < prob->fe_info.n_fe_nodes; n++)
      if (!cupid_cuf_node_used(prob->beam, (int)(n % prob->fe_info.M), n / prob->fe_info.M))
        for (int c = 0; c < 3; c++) r[L->fe_offset + 3 * n + c] = 0.0;
  }
  return CUPID_SUCCESS;
}

int cupid_problem_balanced(const cupid_problem_state *prob) {
  return prob->model->coupling.balance != 0 && prob->beam && prob->grid;
}

/* The interface planes of `balance: momentum` (*planes, *np): the y bounds of the regions,
 * all of which span the section, where the beam goes on (a bound shared by two regions is
 * none); *np = 0 when some region covers part of the section (its end planes and lateral
 * faces are one connected interface: the whole model is then one group). */
static cupid_status interface_planes(const cupid_problem_state *prob, double *planes, int *np) {
  const cupid_model_t *m = prob->model;
  const double tol = 1e-9 * (prob->fe_info.y_max - prob->fe_info.y_min);
  *np = 0;
  for (int r = 0; r < m->pd.n_regions; r++)
    if (!cupid_coupling_region_spans_section(prob->beam, &m->pd.regions[r].box)) return CUPID_SUCCESS;
  for (int r = 0; r < m->pd.n_regions; r++)
    for (int side = 0; side < 2; side++) {
      const double y = side ? m->pd.regions[r].box.hi[1] : m->pd.regions[r].box.lo[1];
      if (!cupid_problem_fe_node_at(prob, y)) continue;
      int seen = 0;
      for (int k = 0; k < *np; k++) seen |= fabs(planes[k] - y) <= tol;
      if (seen) continue;
      CUPID_CHECK(*np < CUPID_BALANCE_GROUPS_MAX, CUPID_ERR_UNSUPPORTED,
                  "coupling.balance: momentum balances at most %d interfaces apart",
                  CUPID_BALANCE_GROUPS_MAX);
      planes[(*np)++] = y;
    }
  return CUPID_SUCCESS;
}

/* The y of DOF d: its PD node's, or its FE node's beam node's. */
static double dof_y(const cupid_problem_state *prob, const layout *L, cupid_int d) {
  if (d < L->fe_offset) return L->x[3 * (d / 3) + 1];
  const cupid_int fe_node = (d - L->fe_offset) / 3;
  return cupid_cuf_beam_node_y(prob->beam, fe_node / prob->fe_info.M);
}

/* The y span [z[0], z[1]] of the DOFs whose columns the coupling at the plane y_p makes out of
 * balance: the PD nodes its FE rows read (the fictitious FE element's fits, @p fe_rows), the
 * beam elements its fictitious PD nodes fall in (2 (delta + h) beyond the plane, a bound of
 * the extended grid's reach for either PD model), and the PD nodes whose families reach those
 * (as far again on the region's side). */
static void plane_zone(const cupid_problem_state *prob, const layout *L, const cupid_csr_t *fe_rows,
                       double y_p, double z[2]) {
  const double *x = L->x;
  const double h = prob->model->pd.spacing, reach = 2.0 * (prob->model->pd.horizon + h);
  const double tol = 1e-9 * (prob->fe_info.y_max - prob->fe_info.y_min);
  const cupid_int M = prob->fe_info.M;
  z[0] = y_p - reach, z[1] = y_p + reach;
  for (cupid_int a = 0; a < fe_rows->nrows; a++) {
    if (fabs(cupid_cuf_beam_node_y(prob->beam, a / M) - y_p) > tol) continue;
    for (cupid_int k = fe_rows->rowptr[a]; k < fe_rows->rowptr[a + 1]; k++) {
      const cupid_int c = fe_rows->col[k];
      if (c >= L->n_pd) continue;
      z[0] = fmin(z[0], x[3 * c + 1]), z[1] = fmax(z[1], x[3 * c + 1]);
    }
  }
  for (cupid_int e = 0; e < prob->fe_info.n_beam_elements; e++) {
    cupid_int first;
    double y0, y1;
    cupid_cuf_beam_element(prob->beam, e, &first, &y0, &y1);
    if (y1 < y_p - reach - tol || y0 > y_p + reach + tol) continue;
    int active = 0; /* the elements inside a region gave way: they hold no fictitious node */
    for (cupid_int se = 0; se < prob->fe_info.n_section_elements && !active; se++)
      active = cupid_cuf_is_active(prob->beam, e, se);
    if (!active) continue;
    z[0] = fmin(z[0], y0), z[1] = fmax(z[1], y1);
  }
}

/* The balance's groups: `momentum` with interface planes whose zones (plane_zone) are apart,
 * each DOF in the group of the zone holding it (else the nearest plane's: its column is in
 * balance); else one group (`global`, a region over part of the section, or zones that meet:
 * a fictitious FE element that reaches across the region, as the one B2 element of a bar,
 * reads PD nodes the other interface's coupling also makes out of balance). *group is the
 * caller's (NULL for one group). */
static cupid_status balance_groups(const cupid_problem_state *prob, const layout *L,
                                   const cupid_csr_t *fe_rows, int *ng, int **group) {
  double planes[CUPID_BALANCE_GROUPS_MAX], zone[CUPID_BALANCE_GROUPS_MAX][2];
  int np = 0;
  *ng = 1;
  *group = NULL;
  if (prob->model->coupling.balance == 1) CUPID_CALL(interface_planes(prob, planes, &np));
  if (np < 2) return CUPID_SUCCESS;
  for (int k = 0; k < np; k++) plane_zone(prob, L, fe_rows, planes[k], zone[k]);
  for (int a = 0; a < np; a++)
    for (int b = a + 1; b < np; b++)
      if (zone[a][0] <= zone[b][1] && zone[b][0] <= zone[a][1]) {
        cupid_problem_progress(prob, "balance: the coupling zones of the interfaces at y = %g and "
                               "%g meet (y in [%g, %g] and [%g, %g]): one balance for the model",
                               planes[a], planes[b], zone[a][0], zone[a][1], zone[b][0], zone[b][1]);
        return CUPID_SUCCESS;
      }
  CUPID_CALL(cupid_malloc((size_t)L->ndof, sizeof **group, "balance groups", group));
  for (cupid_int d = 0; d < L->ndof; d++) {
    const double y = dof_y(prob, L, d);
    int best = 0;
    for (int k = 1; k < np; k++)
      if (fabs(planes[k] - y) < fabs(planes[best] - y)) best = k;
    for (int k = 0; k < np; k++)
      if (y >= zone[k][0] && y <= zone[k][1]) best = k;
    (*group)[d] = best;
  }
  *ng = np;
  return CUPID_SUCCESS;
}

typedef cupid_status (*transpose_fn)(void *ctx, const double *w, double *z);

/* R, C = K^T R (by @p transpose), the weights d of the FE rows @p fe_rows and the groups, in
 * the layout L (*R, *C, *d, *group: the caller's to free, also after a failure). */
static cupid_status balance_parts(const cupid_problem_state *prob, const layout *L,
                                  transpose_fn transpose, void *ctx, const cupid_csr_t *fe_rows,
                                  double **R, double **C, double **d, int *ng, int **group) {
  const size_t n = (size_t)L->ndof, sz = CUPID_BALANCE_MODES * n;
  CUPID_CALL(cupid_calloc(sz, sizeof **R, "rigid modes", R));
  CUPID_CALL(cupid_calloc(sz, sizeof **C, "K^T R", C));
  CUPID_CALL(cupid_calloc(n, sizeof **d, "balance weights", d));
  CUPID_CALL(rigid_modes(prob, L, *R));
  for (int k = 0; k < CUPID_BALANCE_MODES; k++) CUPID_CALL(transpose(ctx, *R + k * n, *C + k * n));
  CUPID_CALL(cupid_coupling_balance_weights(fe_rows, L->n_pd, *d));
  return balance_groups(prob, L, fe_rows, ng, group);
}

/* B on prob's own layout (a whole grid). */
static cupid_status balance_create(const cupid_problem_state *prob, transpose_fn transpose,
                                   void *ctx, const cupid_csr_t *fe_rows, cupid_coupling_balance *B) {
  const layout L = prob_layout(prob);
  double *R = NULL, *C = NULL, *d = NULL;
  int *group = NULL, ng = 1;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(balance_parts(prob, &L, transpose, ctx, fe_rows, &R, &C, &d, &ng, &group));
  CUPID_TRY(cupid_coupling_balance_create_grouped(L.ndof, R, C, d, ng, group, B));
cleanup:
  cupid_free(&group);
  cupid_free(&R);
  cupid_free(&C);
  cupid_free(&d);
  return st;
}

static cupid_status csr_transpose(void *ctx, const double *w, double *z) {
  cupid_csr_matvec_transpose(ctx, w, z);
  return CUPID_SUCCESS;
}

static cupid_status operator_transpose(void *ctx, const double *w, double *z) {
  return cupid_coupling_operator_apply_transpose(ctx, w, z);
}

typedef struct {
  const cupid_csr_t *K;
  cupid_coupling_balance B;
} balanced_csr;

static cupid_status balanced_csr_apply(void *ctx, const double *x, double *y) {
  const balanced_csr *b = ctx;
  cupid_csr_matvec(b->K, x, y);
  cupid_coupling_balance_correct(b->B, x, y);
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_balance_assembled(const cupid_problem_state *prob, const cupid_csr_t *K,
                                             cupid_coupling_balance *B) {
  /* K's FE rows: block rows n_pd.. (rowptr holds absolute offsets into col and val) */
  cupid_csr_t fe = {.nrows = K->nrows - prob->n_pd, .ncols = K->ncols, .bs = K->bs,
                    .rowptr = K->rowptr + prob->n_pd, .col = K->col, .val = K->val};
  return balance_create(prob, csr_transpose, (void *)K, &fe, B);
}

cupid_status cupid_problem_balanced_evaluate(cupid_problem_state *prob) {
  cupid_coupling_balance B = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_problem_balance_assembled(prob, prob->K, &B));
  balanced_csr bk = {prob->K, B};
  CUPID_TRY(cupid_problem_patch_test_assembled(prob)); /* Eq. 38 itself (the head) */
  CUPID_TRY(balanced_csr_apply(&bk, prob->u, prob->f_int));
cleanup:
  cupid_coupling_balance_destroy(&B);
  return st;
}

cupid_status cupid_problem_balanced_direct_solve(cupid_problem_state *prob) {
  cupid_coupling_balance B = NULL;
  cupid_direct_factor F = NULL;
  cupid_status st = CUPID_SUCCESS;
  const cupid_csr_t *K = prob->K;
  CUPID_TRY(cupid_problem_balance_assembled(prob, K, &B));
  balanced_csr bk = {K, B};
  CUPID_TRY(cupid_problem_patch_test_assembled(prob)); /* Eq. 38 itself (the head) */
  cupid_solve_info si = {0};
  double t0 = cupid_wtime();
  CUPID_TRY(cupid_direct_factor_create_kind(K, prob->method->matrix, prob->bc, &F, &si));
  double t1 = cupid_wtime();
  CUPID_TRY(cupid_coupling_balance_solve(B, K, F, prob->bc, prob->f_ext, prob->u));
  si.time_solve = cupid_wtime() - t1;
  si.time_factor = t1 - t0;
  CUPID_TRY(balanced_csr_apply(&bk, prob->u, prob->f_int));
  /* the residual of the balanced system on the free DOFs */
  double rn = 0.0, fn = 0.0;
  for (cupid_int d = 0; d < prob->ndof; d++)
    if (!prob->bc->fixed[d]) {
      double r = prob->f_ext[d] - prob->f_int[d];
      rn += r * r;
      fn += prob->f_ext[d] * prob->f_ext[d];
    }
  si.residual = fn > 0 ? sqrt(rn / fn) : sqrt(rn);
  prob->solve = si;
  prob->solved = 1;
  cupid_problem_record_solve(prob);
  cupid_problem_progress(prob, "solve: %s with the momentum balance (6 rigid modes, "
                         "Sherman-Morrison-Woodbury), %lld equations, residual %.2e",
                         si.method, (long long)si.n, si.residual);
cleanup:
  cupid_direct_factor_destroy(&F);
  cupid_coupling_balance_destroy(&B);
  return st;
}

static cupid_status linear_apply(void *ctx, const double *x, double *y) {
  return cupid_krylov_apply(ctx, x, y); /* a slab: its owned and FE rows */
}

/* The whole model's DOF of the slab's local DOF d (G: the whole grid's nodes). */
static cupid_int whole_dof(const cupid_problem_state *prob, cupid_int G, cupid_int d) {
  if (d < prob->fe_offset) return 3 * (prob->part.first_global + d / 3) + d % 3;
  return 3 * G + (d - prob->fe_offset);
}

/* On a slab: R, C = K^T R, the weights and the groups of the whole model on every rank (the
 * whole grid and the coupling operator on it, for six transposed products once per run: C
 * does not change as bonds break), then this slab's share: R, the weights and the groups on
 * every local DOF, C on its owned PD DOFs and, on the last slab (which adds the FE rows'
 * FE columns, krylov.c), its FE DOFs, so that the shares' C^T x sum to the whole C^T x. */
static cupid_status slab_balance(cupid_problem_state *prob, cupid_coupling_balance *B) {
  cupid_pd_grid whole = NULL;
  cupid_coupling_operator A = NULL;
  cupid_box *boxes = NULL;
  int *mats = NULL, *gw = NULL, *g = NULL, ng = 1;
  double *Rw = NULL, *Cw = NULL, *dw = NULL, *R = NULL, *C = NULL, *d = NULL;
  cupid_coupling_options co;
  cupid_status st = cupid_pd_grid_create_from_model(prob->model, &whole);
  const cupid_int G = whole ? cupid_pd_grid_num_nodes(whole) : 0;
  const cupid_int n_fe = prob->ndof - prob->fe_offset, n = prob->ndof;
  if (st == CUPID_SUCCESS) st = cupid_cuf_set_dof_offset(prob->beam, 3 * G);
  if (st == CUPID_SUCCESS) st = cupid_method_coupling_options(prob, &co, &boxes, &mats);
  if (st == CUPID_SUCCESS) st = cupid_coupling_operator_create(prob->beam, whole, &co, &A);
  const layout Lw = {G, 3 * G, 3 * G + n_fe, whole ? cupid_pd_grid_coords(whole) : NULL};
  if (st == CUPID_SUCCESS)
    st = balance_parts(prob, &Lw, operator_transpose, A, cupid_coupling_operator_fe_rows(A), &Rw,
                       &Cw, &dw, &ng, &gw);
  const cupid_status back = cupid_cuf_set_dof_offset(prob->beam, prob->fe_offset);
  if (st == CUPID_SUCCESS) st = back;
  CUPID_TRY(cupid_problem_slab_agree(st));
  const size_t sz = CUPID_BALANCE_MODES * (size_t)n;
  st = cupid_calloc(sz + 1, sizeof *R, "rigid modes", &R);
  if (st == CUPID_SUCCESS) st = cupid_calloc(sz + 1, sizeof *C, "K^T R", &C);
  if (st == CUPID_SUCCESS) st = cupid_calloc((size_t)n + 1, sizeof *d, "balance weights", &d);
  if (st == CUPID_SUCCESS && gw) st = cupid_calloc((size_t)n + 1, sizeof *g, "balance groups", &g);
  CUPID_TRY(cupid_problem_slab_agree(st));
  const int last = prob->part.part == prob->part.parts - 1;
  const cupid_int o0 = 3 * prob->part.owned_first, o1 = 3 * prob->part.owned_last;
  for (cupid_int j = 0; j < n; j++) {
    const cupid_int w = whole_dof(prob, G, j);
    const int counted = (j >= o0 && j < o1) || (j >= prob->fe_offset && last);
    for (int k = 0; k < CUPID_BALANCE_MODES; k++) {
      R[(size_t)k * n + j] = Rw[(size_t)k * Lw.ndof + w];
      C[(size_t)k * n + j] = counted ? Cw[(size_t)k * Lw.ndof + w] : 0.0;
    }
    d[j] = dw[w];
    if (g) g[j] = gw[w];
  }
  st = cupid_coupling_balance_create_grouped(n, R, C, d, ng, g, B);
  CUPID_TRY(cupid_problem_slab_agree(st));
  cupid_coupling_balance_set_slab(*B, cupid_petsc_sum_doubles, last);
cleanup:
  cupid_coupling_operator_destroy(&A);
  cupid_pd_grid_destroy(&whole);
  cupid_free(&boxes);
  cupid_free(&mats);
  cupid_free(&gw);
  cupid_free(&g);
  cupid_free(&Rw);
  cupid_free(&Cw);
  cupid_free(&dw);
  cupid_free(&R);
  cupid_free(&C);
  cupid_free(&d);
  return st;
}

cupid_status cupid_problem_balanced_operator(cupid_problem_state *prob, cupid_coupling_operator A,
                                             const cupid_linear_operator *L,
                                             cupid_coupling_balance *B, cupid_linear_operator *out) {
  /* the patch test reads Eq. 38 itself (see the head of this file) */
  CUPID_CALL(cupid_problem_patch_test(prob, linear_apply, (void *)L));
  if (prob->slab) {
    CUPID_CALL(slab_balance(prob, B));
    return cupid_coupling_balance_linear(*B, L, out);
  }
  CUPID_CALL(balance_create(prob, operator_transpose, A, cupid_coupling_operator_fe_rows(A), B));
  return cupid_coupling_balance_linear(*B, L, out);
}
