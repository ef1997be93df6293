/* The matrix-free coupled operator (cupid_coupling_operator_*, paper 000 Eq. 38) against the
 * assembled coupled matrix of cupid_coupling_create(), on small models of both kinds:
 *  - full section (interfaces normal to the axis, fictitious B2 elements): a 12 x 12 section,
 *    beam FE [0,6] | PD [6,12] | FE [12,18];
 *  - part of the section (parallel interfaces, removed section elements as fictitious FE
 *    elements): the same beam with PD in x, z in [4, 8] (middle), [0, 4] (corner, two outer
 *    faces) or two corners (two regions);
 * LPS (PDLAMMPS and EXACT partial volumes) and bond-based. Checks:
 *  - |A x - K x| / |K x| <= 1e-12 for random x (round-off: the assembled matrix sums the
 *    fictitious columns K_IJ w_Jn per FE column, the operator sums K_IJ (w_Jn x_n); a row has
 *    ~10^3 terms of mixed sign, each rounding ~1e-16 relative);
 *  - cupid_coupling_operator_assemble(A, NULL) is cupid_coupling_create()'s matrix bit for bit
 *    (the same assembly code on the same parts);
 *  - the preconditioner matrix (cheap bond-based operator, delta' = 1.5 h) has at most 19 PD
 *    blocks in a row of an interior PD node and an average well below the LPS matrix's;
 *  - GMRES on the operator, right-preconditioned by LU of the cheap matrix (rtol 1e-12 on the
 *    true residual, met without restarts from it), the built-in engine and (PETSc builds)
 *    PETSc's, reproduces the direct solve (UMFPACK) of the assembled matrix to 1e-8 relative
 *    (max norm; the criterion; measured 1e-14 to 1e-12: condition ~1e4-1e6 times the
 *    residual). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cupid/coupling.h"
#include "cupid_config.h"
#include "test_cuf_common.h"
#include "test_slabs.h"

#define XW 12.0
#define YL 18.0

typedef struct {
  int te;          /* 0: LE with le_nodes; else TE order */
  int le_nodes, p; /* section element nodes (4, 9), beam element nodes */
  cupid_pd_model_kind kind;
  cupid_partial_volume pv;
  double delta;
  int regions;     /* 0: full section; 1: middle; 2: corner; 3: two corners */
} op_case;

typedef struct {
  tb_beam tb;
  cupid_cuf_beam beam;
  cupid_pd_grid grid;
  cupid_pd_material mat;
  cupid_coupling_options co;
  cupid_box region[2];
  int region_mat[2];
  cupid_int n_pd, ndof;
} op_model;

static void build(op_model *m, const op_case *pc) {
  memset(m, 0, sizeof *m);
  tb_init(&m->tb, 1000.0, 0.25);
  if (pc->te) {
    tb_te(&m->tb, pc->te);
    tb_rect(&m->tb, 0, XW, 1, 0, XW, 1, -1);
  } else {
    tb_le(&m->tb, pc->le_nodes);
    tb_rect(&m->tb, 0, XW, 3, 0, XW, 3, -1);
  }
  static const double axes[4] = {0, 6, 12, YL};
  tb_axis_spans(&m->tb, 4, axes);
  m->tb.def.element_nodes = pc->p;
  m->beam = tb_create(&m->tb);
  static const double box[4][2][2] = {{{0, 12}, {0, 12}}, {{4, 8}, {4, 8}}, {{0, 4}, {0, 4}},
                                      {{0, 4}, {0, 4}}};
  const double(*b)[2] = box[pc->regions];
  m->region[0] = (cupid_box){.lo = {b[0][0], 6, b[1][0]}, .hi = {b[0][1], 12, b[1][1]},
                             .has = {1, 1, 1}};
  m->region[1] = (cupid_box){.lo = {8, 6, 8}, .hi = {12, 12, 12}, .has = {1, 1, 1}};
  int nr = pc->regions == 3 ? 2 : 1;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, nr, m->region, m->region_mat, &m->grid));
  m->n_pd = cupid_pd_grid_num_nodes(m->grid);
  CUPID_ASSERT_OK(cupid_coupling_deactivate(m->beam, nr, m->region));
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(m->beam, 3 * m->n_pd));
  m->ndof = 3 * m->n_pd + cupid_cuf_num_dofs(m->beam);
  m->mat = (cupid_pd_material){.E = 1000.0, .nu = 0.25};
  m->co = (cupid_coupling_options){.beam_def = &m->tb.def,
                                   .materials = m->tb.mat,
                                   .n_materials = m->tb.n_mat,
                                   .n_regions = nr,
                                   .regions = m->region,
                                   .region_materials = m->region_mat,
                                   .spacing = 1.0,
                                   .pd = {.horizon = pc->delta,
                                          .model = pc->kind,
                                          .influence = CUPID_INFLUENCE_GAUSSIAN,
                                          .partial_volume = pc->pv,
                                          .materials = &m->mat,
                                          .n_materials = 1}};
}

static void destroy(op_model *m) {
  cupid_pd_grid_destroy(&m->grid);
  cupid_cuf_beam_destroy(&m->beam);
}

static double norm(const double *v, cupid_int n) {
  double s = 0.0;
  for (cupid_int i = 0; i < n; i++) s += v[i] * v[i];
  return sqrt(s);
}

/* The real grid split into z slabs (issue 6, test_slabs.h): on each slab (its extended grid
 * cut by the same z planes) the owned PD rows and the share of the FE rows (PD columns of the
 * owned nodes, FE columns on the last slab) of the operator and of the twin against the whole
 * model's; the info is the whole model's on every slab. */
typedef struct {
  op_model *m;
  cupid_coupling_info whole;
} fict_slab_ctx;

static cupid_status fict_create(void *ctx, cupid_pd_grid g, void **op, cupid_csr *P) {
  fict_slab_ctx *c = ctx;
  cupid_coupling_operator A = NULL;
  CUPID_CALL(cupid_coupling_operator_create(c->m->beam, g, &c->m->co, &A));
  *op = A;
  cupid_coupling_info info;
  cupid_coupling_operator_get_info(A, &info);
  assert_true(memcmp(&info, &c->whole, sizeof info) == 0);
  return cupid_coupling_preconditioner(A, 1.5, P);
}

static cupid_status fict_rows(void *op, const double *x, cupid_int d0, cupid_int d1, double *y) {
  return cupid_coupling_operator_apply_rows(op, x, d0, d1, y);
}

static void fict_destroy(void *op) {
  cupid_coupling_operator A = op;
  cupid_coupling_operator_destroy(&A);
}

static void check_slabs(op_model *m, cupid_coupling_operator A, int parts) {
  int halo = 0;
  CUPID_ASSERT_OK(cupid_pd_operator_halo_layers(&m->co.pd, 1.0, &halo));
  fict_slab_ctx ctx = {.m = m};
  cupid_coupling_operator_get_info(A, &ctx.whole);
  const slab_operator so = {.create = fict_create, .apply_rows = fict_rows,
                            .destroy = fict_destroy, .ctx = &ctx};
  slab_check("  fictitious nodes", &so, m->beam, m->co.n_regions, m->region, m->region_mat, halo,
             parts);
}

/* Clamp y = 0 (FE), pull the end y = 18 along z and y; GMRES vs UMFPACK on the assembled K:
 * the built-in engine (every build) and PETSc's (PETSc builds). Both must meet rtol on the
 * true residual without restarts: the twin's LU is checked for its backward error and
 * refactored with partial pivoting when UMFPACK's threshold pivoting made it inaccurate
 * (full_l9_lps: pivot ratio 1e-5, backward error 7e-8; GMRES then stopped on its estimate
 * with a true residual of 6e-5 (built-in) and 1.6e-3 (PETSc)). */
static void check_krylov(const op_model *m, cupid_coupling_operator A, const cupid_csr_t *K) {
  cupid_int n = m->ndof;
  cupid_dirichlet bc = NULL;
  double *f = NULL, *u = NULL, *ud = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *ud, "ud", &ud));
  cupid_cuf_info info;
  cupid_cuf_get_info(m->beam, &info);
  for (cupid_int a = 0; a < info.n_fe_nodes; a++) {
    cupid_int bn = a / info.M;
    double y = cupid_cuf_beam_node_y(m->beam, bn);
    int used = cupid_cuf_node_used(m->beam, (int)(a % info.M), bn);
    for (int c = 0; c < 3; c++) {
      cupid_int d = 3 * m->n_pd + 3 * a + c;
      if (!used || y < 1e-9) CUPID_ASSERT_OK(cupid_dirichlet_fix(bc, d, 0.0));
      if (used && y > YL - 1e-9) f[d] = c == 2 ? -1.0 : 0.3;
    }
  }
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  CUPID_ASSERT_OK(cupid_direct_solve(K, CUPID_MATRIX_GENERAL, f, bc, ud, NULL));
  cupid_csr P = NULL;
  CUPID_ASSERT_OK(cupid_coupling_preconditioner(A, 1.5, &P));
  cupid_krylov_options ko = {.rtol = 1e-12};
  double s = 0.0;
  for (cupid_int d = 0; d < n; d++) s = fmax(s, fabs(ud[d]));
  for (int engine = 0; engine < 1 + CUPID_HAVE_PETSC; engine++) {
    cupid_solve_info ki;
    memset(u, 0, (size_t)n * sizeof *u);
    if (engine == 0) {
      cupid_linear_operator L;
      cupid_coupling_operator_linear(A, &L);
      CUPID_ASSERT_OK(cupid_iterative_solve(&L, P, bc, f, u, &ko, &ki));
    } else {
      CUPID_ASSERT_OK(cupid_coupling_krylov_solve(A, P, bc, f, u, &ko, &ki));
    }
    double e = 0.0;
    for (cupid_int d = 0; d < n; d++) e = fmax(e, fabs(u[d] - ud[d]));
    printf("  %s %s + %s: %d iterations, %d restarts, true residual %.2e, |u - u_direct|/|u| = "
           "%.2e\n", ki.method, ki.ksp_type, ki.pc_type, ki.iterations, ki.refinements,
           ki.residual, e / s);
    assert_true(!strncmp(ki.converged_reason, "CONVERGED", 9));
    assert_true(ki.residual <= 2e-12);
    assert_int_equal(ki.refinements, 0);
    assert_true(e <= 1e-8 * s);
  }
  cupid_csr_destroy(&P);
  cupid_dirichlet_destroy(&bc);
  cupid_free(&f);
  cupid_free(&u);
  cupid_free(&ud);
}

static void check_case(const op_case *pc) {
  op_model m;
  build(&m, pc);
  cupid_coupling_h c = NULL;
  cupid_csr K = NULL, K2 = NULL, P = NULL;
  cupid_coupling_operator A = NULL;
  CUPID_ASSERT_OK(cupid_coupling_create(m.beam, m.grid, &m.co, &c, &K));
  CUPID_ASSERT_OK(cupid_coupling_operator_create(m.beam, m.grid, &m.co, &A));
  assert_int_equal(cupid_coupling_operator_size(A), m.ndof);
  cupid_coupling_info ci, ca;
  cupid_coupling_get_info(c, &ci);
  cupid_coupling_operator_get_info(A, &ca);
  assert_true(memcmp(&ci, &ca, sizeof ci) == 0);
  assert_true(ci.n_fictitious_pd > 0);

  /* Random x: the matrix-free product against the assembled one. */
  cupid_int n = m.ndof;
  double *x = NULL, *y = NULL, *z = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *x, "x", &x));
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *y, "y", &y));
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *z, "z", &z));
  uint64_t seed = 7;
  double worst = 0.0;
  for (int trial = 0; trial < 3; trial++) {
    for (cupid_int i = 0; i < n; i++) x[i] = 2.0 * cupid_test_random(&seed) - 1.0;
    cupid_csr_matvec(K, x, y);
    CUPID_ASSERT_OK(cupid_coupling_operator_apply(A, x, z));
    for (cupid_int i = 0; i < n; i++) z[i] -= y[i];
    worst = fmax(worst, norm(z, n) / norm(y, n));
  }
  /* Row ranges (what each MPI rank computes of a Krylov product): the same arithmetic as the
   * whole product, so equal to round-off of the PD kernels' reference shift (1e-13 of |Ax|),
   * for ranges that cut a node's three rows, that hold only PD or only FE rows, and empty. */
  CUPID_ASSERT_OK(cupid_coupling_operator_apply(A, x, y));
  const cupid_int npd3 = 3 * m.n_pd;
  const cupid_int ranges[6][2] = {{0, n}, {0, npd3 / 2 + 1}, {npd3 / 2 + 1, n},
                                  {npd3 / 3 + 2, npd3 - 4}, {npd3 - 1, n - 5}, {7, 7}};
  const double ymax = norm(y, n);
  for (int r = 0; r < 6; r++) {
    const cupid_int d0 = ranges[r][0], d1 = ranges[r][1];
    for (cupid_int i = 0; i < n; i++) z[i] = NAN;
    CUPID_ASSERT_OK(cupid_coupling_operator_apply_rows(A, x, d0, d1, z));
    for (cupid_int i = d0; i < d1; i++) ASSERT_NEAR(z[i], y[i], 1e-13 * ymax);
  }
  assert_int_equal(cupid_coupling_operator_apply_rows(A, x, 5, n + 1, z), CUPID_ERR_ARGUMENT);

  /* The operator's own assembly is the coupled matrix, bit for bit. */
  CUPID_ASSERT_OK(cupid_coupling_operator_assemble(A, NULL, &K2));
  assert_int_equal(K2->nrows, K->nrows);
  assert_true(memcmp(K2->rowptr, K->rowptr, (size_t)(K->nrows + 1) * sizeof *K->rowptr) == 0);
  cupid_int nb = K->rowptr[K->nrows];
  assert_true(memcmp(K2->col, K->col, (size_t)nb * sizeof *K->col) == 0);
  assert_true(memcmp(K2->val, K->val, (size_t)nb * 9 * sizeof *K->val) == 0);

  /* The cheap matrix: at most 19 PD blocks (self + 18 neighbours within 1.5 h) in a PD row. */
  CUPID_ASSERT_OK(cupid_coupling_preconditioner(A, 1.5, &P));
  assert_int_equal(P->nrows, K->nrows);
  cupid_int max_pd = 0;
  for (cupid_int r = 0; r < m.n_pd; r++) {
    cupid_int cnt = 0;
    for (cupid_int k = P->rowptr[r]; k < P->rowptr[r + 1]; k++) cnt += P->col[k] < m.n_pd;
    max_pd = cnt > max_pd ? cnt : max_pd;
  }
  double avg_p = (double)P->rowptr[m.n_pd] / (double)m.n_pd;
  double avg_k = (double)K->rowptr[m.n_pd] / (double)m.n_pd;
  printf("  %lld real + %lld fictitious PD nodes, %lld FE nodes: |Ax - Kx|/|Kx| = %.2e; blocks "
         "a PD row: K %.1f, cheap %.1f (max %lld PD)\n",
         (long long)ci.n_real_pd, (long long)ci.n_fictitious_pd, (long long)(K->nrows - m.n_pd),
         worst, avg_k, avg_p, (long long)max_pd);
  assert_true(worst <= 1e-12);
  assert_true(max_pd <= 19);
  assert_true(avg_p < avg_k);
  check_krylov(&m, A, K);
  check_slabs(&m, A, 2);
  if (pc->regions != 3) check_slabs(&m, A, 3); /* two corners leave z layers empty */
  cupid_free(&x);
  cupid_free(&y);
  cupid_free(&z);
  cupid_csr_destroy(&K);
  cupid_csr_destroy(&K2);
  cupid_csr_destroy(&P);
  cupid_coupling_operator_destroy(&A);
  cupid_coupling_destroy(&c);
  destroy(&m);
}

/* CUPID_TEST_SMALL (valgrind, the sanitizers): the full-section LPS case is left to the plain
 * build (7 s of the test's 9.5 natively, most in UMFPACK's LU of its 2,016 PD nodes; 1,673 s
 * under valgrind on 2 busy cores): the full section is checked bond-based (EXACT volumes), LPS
 * over part of the section. */
static int small(void) { return getenv("CUPID_TEST_SMALL") != NULL; }

static void full_l9_lps(void **state) {
  if (small()) skip();
  check_case(&(op_case){.le_nodes = 9, .p = 3, .kind = CUPID_PD_LPS,
                        .pv = CUPID_PARTIAL_PDLAMMPS, .delta = 2.0, .regions = 0});
}
static void full_te2_bond_exact(void **state) {
  check_case(&(op_case){.te = 2, .p = 2, .kind = CUPID_PD_BOND, .pv = CUPID_PARTIAL_EXACT,
                        .delta = 3.0, .regions = 0});
}
static void middle_l9_lps(void **state) {
  check_case(&(op_case){.le_nodes = 9, .p = 3, .kind = CUPID_PD_LPS,
                        .pv = CUPID_PARTIAL_PDLAMMPS, .delta = 2.0, .regions = 1});
}
static void corner_l4_b4_bond(void **state) {
  check_case(&(op_case){.le_nodes = 4, .p = 4, .kind = CUPID_PD_BOND,
                        .pv = CUPID_PARTIAL_PDLAMMPS, .delta = 3.0, .regions = 2});
}
static void two_corners_l9_lps_exact(void **state) {
  check_case(&(op_case){.le_nodes = 9, .p = 3, .kind = CUPID_PD_LPS, .pv = CUPID_PARTIAL_EXACT,
                        .delta = 1.5, .regions = 3});
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(full_l9_lps),       cmocka_unit_test(full_te2_bond_exact),
      cmocka_unit_test(middle_l9_lps),     cmocka_unit_test(corner_l4_b4_bond),
      cmocka_unit_test(two_corners_l9_lps_exact),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
