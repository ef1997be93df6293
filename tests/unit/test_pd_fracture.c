/* Fracture in the PD operator (src/pd/fracture.c): pre-crack geometry against a brute-force
 * count; the operator of a cracked body (stencil kernels with their broken-bond masks, on a
 * padded box and on a sparse union, every instruction set) against the bond-list kernels, the
 * assembled K, the energy and the diagonal; a body cracked through its uniform-b stretches; the stretch criterion at and just above s0;
 * irreversibility, protection and no-fail boxes; damage; the energy a break dissipates;
 * the same broken bonds for 1 and 2 threads; a node that loses every bond; the nodes that
 * lose their support, on a whole grid and on slabs; K's rows that breaks changed, assembled
 * again in place, against K assembled whole. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "pd/pd_internal.h"
#include "testutil.h"

static const cupid_pd_material mats[2] = {{.E = 1000.0, .nu = 0.25}, {.E = 400.0, .nu = 0.3}};

typedef struct {
  cupid_pd_grid grid;
  cupid_pd_operator op;
  cupid_int n;
} body;

/* ... with the surface correction @p surface */
static body make_corrected(int n_boxes, const cupid_box *boxes, cupid_pd_model_kind model,
                           cupid_partial_volume pv, double horizon, cupid_surface_correction surface) {
  body b = {0};
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  int m[4] = {0, 1, 0, 1};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, n_boxes, boxes, m, &b.grid));
  cupid_pd_operator_options oo = {.horizon = horizon, .model = model,
                                  .influence = CUPID_INFLUENCE_GAUSSIAN, .partial_volume = pv,
                                  .surface_correction = surface, .materials = mats,
                                  .n_materials = 2};
  CUPID_ASSERT_OK(cupid_pd_operator_create(b.grid, &oo, &b.op));
  b.n = cupid_pd_grid_num_nodes(b.grid);
  return b;
}

static body make(int n_boxes, const cupid_box *boxes, cupid_pd_model_kind model,
                 cupid_partial_volume pv, double horizon) {
  return make_corrected(n_boxes, boxes, model, pv, horizon, CUPID_SURFACE_NONE);
}

static void destroy(body *b) {
  cupid_pd_operator_destroy(&b->op);
  cupid_pd_grid_destroy(&b->grid);
}

static cupid_box box3(double x0, double x1, double y0, double y1, double z0, double z1) {
  return (cupid_box){.lo = {x0, y0, z0}, .hi = {x1, y1, z1}, .has = {1, 1, 1}};
}

/* Brute force over all node pairs within the horizon (beta = 1 there: partial volume none). */
static cupid_int brute_crossings(const body *b, const cupid_pd_precrack *c, double delta) {
  const double *x = cupid_pd_grid_coords(b->grid);
  cupid_int count = 0;
  for (cupid_int i = 0; i < b->n; i++)
    for (cupid_int j = i + 1; j < b->n; j++) {
      const double *p = x + 3 * i, *q = x + 3 * j;
      double r2 = 0;
      for (int k = 0; k < 3; k++) r2 += (q[k] - p[k]) * (q[k] - p[k]);
      if (r2 > delta * delta * (1 + 1e-12)) continue;
      const int a = c->normal;
      double dp = p[a] - c->at, dq = q[a] - c->at;
      /* either order: the rule is symmetric in the ends */
      int cross = (dp < 0 && dq > 0) || (dp > 0 && dq < 0) || (dp == 0 && dq > 0) ||
                  (dq == 0 && dp > 0);
      if (!cross) continue;
      double t = dp / (dp - dq);
      for (int k = 0; k < 3 && cross; k++)
        if (k != a) {
          double y = p[k] + t * (q[k] - p[k]);
          cross = y >= c->lo[k] && y <= c->hi[k];
        }
      count += cross;
    }
  return count;
}

static void test_precrack_count(void **state) {
  (void)state;
  cupid_box bx = box3(0, 8, 0, 8, 0, 6);
  const double delta = 3.0;
  /* between two layers, through a layer of nodes (y = 3.5), a partial rectangle in x and z,
   * and a plane normal to x */
  cupid_pd_precrack cracks[4] = {
      {.normal = 1, .at = 4.0, .lo = {0, 0, 0}, .hi = {3, 0, 6}},
      {.normal = 1, .at = 3.5, .lo = {0, 0, 0}, .hi = {8, 0, 6}},
      {.normal = 1, .at = 4.0, .lo = {2.2, 0, 1.3}, .hi = {5.1, 0, 3.9}},
      {.normal = 0, .at = 2.0, .lo = {0, 0, 0}, .hi = {0, 5, 6}}};
  for (int c = 0; c < 4; c++)
    for (int model = 0; model < 2; model++) {
      body b = make(1, &bx, (cupid_pd_model_kind)model, CUPID_PARTIAL_NONE, delta);
      const cupid_int expect = brute_crossings(&b, &cracks[c], delta);
      cupid_int removed;
      CUPID_ASSERT_OK(cupid_pd_operator_precrack(b.op, &cracks[c], &removed));
      print_message("precrack %d model %d: %lld bonds cut (brute force %lld)\n", c, model,
                    (long long)removed, (long long)expect);
      assert_true(expect > 0);
      assert_int_equal(removed, expect);
      assert_int_equal(cupid_pd_operator_num_broken(b.op), expect);
      /* again: nothing left to cut */
      CUPID_ASSERT_OK(cupid_pd_operator_precrack(b.op, &cracks[c], &removed));
      assert_int_equal(removed, 0);
      destroy(&b);
    }
}

static int cmp_node(const void *a, const void *b) {
  const cupid_int x = *(const cupid_int *)a, y = *(const cupid_int *)b;
  return (x > y) - (x < y);
}

static double max_abs(cupid_int n, const double *x) {
  double m = 0.0;
  for (cupid_int i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
  return m;
}

/* A cracked body: a pre-crack plus bonds broken by a random field. */
static void crack_body(body *b, double s0) {
  cupid_pd_precrack c = {.normal = 1, .at = 4.0, .lo = {0, 0, -1}, .hi = {3, 0, 9}};
  cupid_int removed, broken;
  CUPID_ASSERT_OK(cupid_pd_operator_precrack(b->op, &c, &removed));
  assert_true(removed > 0);
  double *u = malloc(3 * (size_t)b->n * sizeof *u), diss;
  uint64_t seed = 3;
  for (cupid_int i = 0; i < 3 * b->n; i++) u[i] = cupid_test_random(&seed) - 0.5;
  cupid_pd_fracture_options fo = {.criterion = CUPID_PD_BREAK_STRETCH, .critical_stretch = s0};
  CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(b->op, u, &fo, 0, &broken, &diss));
  assert_true(broken > 0);
  free(u);
}

/* Stencil path with masks = bond lists = assembled K = energy form = diagonal. */
static void check_cracked(int n_boxes, const cupid_box *boxes, cupid_pd_model_kind model,
                          cupid_partial_volume pv, int isa, cupid_surface_correction surface) {
  body b = make_corrected(n_boxes, boxes, model, pv, 3.0, surface);
  crack_body(&b, 0.3);
  const cupid_int n = b.n;
  double *u = malloc(3 * (size_t)n * sizeof *u), *f = malloc(3 * (size_t)n * sizeof *f);
  double *g = malloc(3 * (size_t)n * sizeof *g), *d = malloc(9 * (size_t)n * sizeof *d);
  uint64_t seed = 17;
  for (cupid_int i = 0; i < 3 * n; i++) u[i] = cupid_test_random(&seed) - 0.5;
  pd_stencil_force_isa(isa);
  CUPID_ASSERT_OK(cupid_pd_operator_apply(b.op, u, f));
  pd_stencil_force_isa(0);
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(b.op, &K));
  cupid_csr_matvec(K, u, g);
  const double fm = max_abs(3 * n, g);
  /* the same sums in another order (sweep minus the broken terms, or rows of K): round-off,
   * 1e-12 of max |f| (terms O(max |f|), the subtraction adds a few ulps of each) */
  for (cupid_int i = 0; i < 3 * n; i++) ASSERT_NEAR(f[i], g[i], 1e-12 * fm);
  double E, uKu = 0;
  CUPID_ASSERT_OK(cupid_pd_operator_energy(b.op, u, &E));
  for (cupid_int i = 0; i < 3 * n; i++) uKu += u[i] * g[i];
  ASSERT_NEAR(E, 0.5 * uKu, 1e-12 * fabs(E));
  CUPID_ASSERT_OK(cupid_pd_operator_diagonal(b.op, d));
  for (cupid_int r = 0; r < n; r++) {
    const double *blk = cupid_csr_find(K, r, r);
    assert_non_null(blk);
    for (int k = 0; k < 9; k++) ASSERT_NEAR(d[9 * r + k], blk[k], 1e-12 * fm);
  }
  CUPID_ASSERT_OK(pd_operator_use_bond_lists(b.op));
  CUPID_ASSERT_OK(cupid_pd_operator_apply(b.op, u, g));
  for (cupid_int i = 0; i < 3 * n; i++) ASSERT_NEAR(f[i], g[i], 1e-12 * fm);
  /* ranges on the bond lists and on the stencil path */
  const cupid_int a = n / 4, e = n / 4 + n / 3;
  CUPID_ASSERT_OK(cupid_pd_operator_apply_range(b.op, a, e, u, g));
  for (cupid_int i = 0; i < 3 * (e - a); i++) ASSERT_NEAR(g[i], f[3 * a + i], 1e-12 * fm);
  if (surface == CUPID_SURFACE_NONE) { /* a corrected operator runs on its bond lists alone */
    b.op->stencil_off = 0;
    CUPID_ASSERT_OK(cupid_pd_operator_apply_range(b.op, a, e, u, g));
    for (cupid_int i = 0; i < 3 * (e - a); i++) ASSERT_NEAR(g[i], f[3 * a + i], 1e-12 * fm);
  }
  /* still no force from a rigid motion */
  for (cupid_int i = 0; i < n; i++) u[3 * i] = 2.0, u[3 * i + 1] = -1.0, u[3 * i + 2] = 0.5;
  CUPID_ASSERT_OK(cupid_pd_operator_apply(b.op, u, f));
  assert_true(max_abs(3 * n, f) < 1e-12 * fm);
  cupid_csr_destroy(&K);
  free(u), free(f), free(g), free(d);
  destroy(&b);
}

static void test_cracked_operator(void **state) {
  (void)state;
  const cupid_box box = box3(0, 9, 0, 8, 0, 5);
  /* two boxes far apart: the padded lattice would be mostly empty, so the operator takes
   * the unpadded path (full runs by the kernels, near-surface nodes by family walks) */
  const cupid_box sparse[2] = {box3(0, 9, 0, 8, 0, 5), box3(40, 46, 30, 36, 0, 5)};
  for (int model = 0; model < 2; model++)
    for (int isa = 1; isa <= 4; isa += (isa == 1 ? 2 : 1)) {
      check_cracked(1, &box, (cupid_pd_model_kind)model, CUPID_PARTIAL_PDLAMMPS, isa, CUPID_SURFACE_NONE);
      check_cracked(2, sparse, (cupid_pd_model_kind)model, CUPID_PARTIAL_NONE, isa, CUPID_SURFACE_NONE);
    }
  /* bond-based with the surface correction (issue 38; its operator runs on bond lists): each
   * pair coefficient carries its factor, and a broken bond leaves with it in the apply, K, the
   * energy and the diagonal */
  check_cracked(1, &box, CUPID_PD_BOND, CUPID_PARTIAL_PDLAMMPS, 1, CUPID_SURFACE_ENERGY);
  check_cracked(2, sparse, CUPID_PD_BOND, CUPID_PARTIAL_NONE, 1, CUPID_SURFACE_ENERGY);
}

/* LPS with the surface correction: breaking refused with the reason (its corrected dilatation
 * is not kept as bonds break), on the pre-crack as on a break */
/* K patched in the rows that breaks changed (quasi-static growth, growth.c patch_rows): the
 * changed rows are both ends of every bond removed since the last take, and K assembled once,
 * then its changed rows assembled again in place (weighted, with the surface correction, and
 * plain), equals K assembled whole after the breaks to the bit, but for the zero blocks of the
 * broken bonds it keeps; LPS, whose breaks change the rows of both families' neighbours,
 * says so (all). */
static void patch_and_compare(cupid_pd_model_kind model, cupid_surface_correction surface, int weighted) {
  const cupid_box box = box3(0, 9, 0, 8, 0, 5);
  body b = make_corrected(1, &box, model, CUPID_PARTIAL_PDLAMMPS, 3.0, surface);
  double *w = malloc((size_t)b.n * sizeof *w);
  for (cupid_int i = 0; i < b.n; i++) w[i] = 0.25 + 0.75 * (double)(i % 7) / 6.0;
  const double *wk = weighted ? w : NULL;
  cupid_csr K = NULL, Kw = NULL, R = NULL;
  cupid_int *rows = NULL, n = 0;
  int all = 1;
  CUPID_ASSERT_OK(cupid_pd_operator_take_changed(b.op, &rows, &n, &all)); /* starts the record */
  assert_int_equal(n, 0);
  assert_true(all); /* nothing was recorded before */
  CUPID_ASSERT_OK(cupid_pd_operator_take_changed(b.op, &rows, &n, &all)); /* nothing since */
  assert_int_equal(n, 0);
  assert_int_equal(all, model != CUPID_PD_BOND);
  if (wk) CUPID_ASSERT_OK(cupid_pd_operator_assemble_weighted(b.op, w, &K));
  else CUPID_ASSERT_OK(cupid_pd_operator_assemble(b.op, &K));
  const cupid_int before = cupid_pd_operator_num_broken(b.op);
  cupid_pd_precrack c = {.normal = 1, .at = 4.0, .lo = {0, 0, -1}, .hi = {3, 0, 9}};
  cupid_int removed;
  CUPID_ASSERT_OK(cupid_pd_operator_precrack(b.op, &c, &removed)); /* a few rows' bonds */
  CUPID_ASSERT_OK(cupid_pd_operator_take_changed(b.op, &rows, &n, &all));
  if (model != CUPID_PD_BOND) {
    assert_true(all);
    goto done;
  }
  assert_false(all);
  assert_true(n > 0 && cupid_pd_operator_num_broken(b.op) > before);
  for (cupid_int k = 1; k < n; k++) assert_true(rows[k] > rows[k - 1]); /* sorted, unique */
  CUPID_ASSERT_OK(cupid_pd_operator_assemble_node_rows(b.op, wk, rows, n, &R));
  for (cupid_int k = 0; k < n; k++) {
    cupid_csr_zero_row(K, rows[k]);
    CUPID_ASSERT_OK(cupid_csr_add_row(K, rows[k], R, k));
  }
  if (wk) CUPID_ASSERT_OK(cupid_pd_operator_assemble_weighted(b.op, w, &Kw));
  else CUPID_ASSERT_OK(cupid_pd_operator_assemble(b.op, &Kw));
  cupid_int zeros = 0, changed = 0;
  for (cupid_int r = 0; r < b.n; r++) {
    const int listed = bsearch(&r, rows, (size_t)n, sizeof *rows, cmp_node) != NULL;
    for (cupid_int p = K->rowptr[r]; p < K->rowptr[r + 1]; p++) {
      const double *a = K->val + 9 * p, *e = cupid_csr_find(Kw, r, K->col[p]);
      if (!e) { /* a broken bond's block, zero */
        for (int t = 0; t < 9; t++) assert_true(a[t] == 0.0);
        zeros++;
        assert_true(listed);
        continue;
      }
      for (int t = 0; t < 9; t++) assert_true(a[t] == e[t]); /* to the bit */
    }
    changed += listed;
  }
  assert_int_equal(cupid_csr_nnz(K), cupid_csr_nnz(Kw) + 9 * zeros);
  print_message("patched K (surface %d, weighted %d): %lld of %lld rows again, %lld zero blocks\n",
                (int)surface, weighted, (long long)changed, (long long)b.n, (long long)zeros);
  assert_true(zeros > 0 && changed < b.n);
  /* a row that lacks a column of the row added: an error, not a write out of the pattern */
  assert_int_equal(cupid_csr_add_row(Kw, rows[0], K, rows[0]), CUPID_ERR_ARGUMENT);
  cupid_error_clear();
done:
  cupid_free(&rows);
  cupid_csr_destroy(&K), cupid_csr_destroy(&Kw), cupid_csr_destroy(&R);
  free(w);
  destroy(&b);
}

/* The energy that cutting the plane y = 4 releases at stretch s in a slab B = 5 thick (faces
 * z = 0 and 5; h = 1, delta = 3.015, constant influence, PDLAMMPS volumes: the SENB's lattice),
 * each crossing pair's energy w (s |xi|)^2 / 2 with the operator's pair coefficient w (with
 * its surface factors), over the pairs whose lower node lies in x in [5, 15) (clear of the x
 * faces by more than a horizon), per unit area of that strip, against an unbounded lattice's
 * (a bulk node's offsets with o_y > 0, each o_y times, per column area h^2). The ratio is
 * the share of G0 a crack normal to y releases through the thickness (issue 38: the SENB's
 * G_eff / G0; examples/fracture/senb_study.py's surface_fraction counts it without partial
 * volumes, 0.777 at h = 1, against 0.790 here): with the energy method's factors it must lie
 * within 2% of 1 (measured 0.989; the factors are fitted to the strain energy, not to the cut,
 * so 1 is not exact), which is what the corrected SENB's peak rise of about 1 / g rests on.
 * And the unbounded lattice's cut normal to y against the orientation average that
 * `calibration: grid` fits. */
static double slab_cut_share(cupid_surface_correction surface, double *axis_over_mean) {
  const cupid_box box = box3(0, 20, 0, 8, 0, 5);
  body b = {0};
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  int m0 = 0;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &box, &m0, &b.grid));
  cupid_pd_operator_options oo = {.horizon = 3.015, .model = CUPID_PD_BOND,
                                  .influence = CUPID_INFLUENCE_CONSTANT,
                                  .partial_volume = CUPID_PARTIAL_PDLAMMPS,
                                  .surface_correction = surface, .materials = mats, .n_materials = 1};
  CUPID_ASSERT_OK(cupid_pd_operator_create(b.grid, &oo, &b.op));
  b.n = cupid_pd_grid_num_nodes(b.grid);
  const struct cupid_pd_operator_private *op = b.op;
  const double *x = cupid_pd_grid_coords(b.grid);
  double cut = 0.0, bulk = 0.0, c_bulk = 0.0;
  cupid_int inner = -1; /* a node whose family is whole: its c is the bulk's */
  for (cupid_int i = 0; i < b.n; i++) {
    const pd_family F = pd_family_of(op, i);
    if (F.n == op->st.n && inner < 0) inner = i;
    if (!(x[3 * i + 1] < 4.0 && x[3 * i] >= 5.0 && x[3 * i] < 15.0)) continue;
    for (int q = 0; q < F.n; q++) {
      const int sx = pd_family_entry(&F, q);
      const cupid_int j = pd_family_node(op, &F, sx);
      if (x[3 * j + 1] < 4.0) continue;
      const double r = op->st.x[sx];
      cut += 0.5 * pd_pair_coefficient(op, i, j, sx) * r * r;
    }
  }
  c_bulk = inner >= 0 ? op->c[inner] : op->c[b.n / 2];
  double mean = 0.0; /* the orientation average (calibration: grid): |xi . n| -> |xi| / 2 */
  for (int sx = 0; sx < op->st.n; sx++) {
    const int oy = op->st.off[3 * sx + 1];
    const double r = op->st.x[sx], e = 0.5 * c_bulk * op->st.wb[sx] * op->V * op->V / r * r * r;
    mean += 0.5 * 0.5 * r * e; /* half the offsets: one side of the plane */
    if (oy > 0) bulk += oy * e;
  }
  *axis_over_mean = bulk / mean;
  destroy(&b);
  return (cut / (10.0 * 5.0)) / bulk; /* bulk: per column of area h^2 = 1 */
}

static void test_corrected_cut(void **state) {
  (void)state;
  double axis = 0.0;
  const double g = slab_cut_share(CUPID_SURFACE_NONE, &axis);
  const double gc = slab_cut_share(CUPID_SURFACE_ENERGY, &axis);
  print_message("the cut's share of G0 through B = 5 (h = 1): %.4f uncorrected, %.4f with the "
                "energy method's factors; an unbounded lattice's cut normal to y releases %.4f "
                "of its orientation average (calibration: grid)\n", g, gc, axis);
  assert_true(g > 0.5 && g < 0.95);
  /* the factors restore the cut to 2% (measured 1.1% short): 2% of G is 1% of a peak load
     (P ~ sqrt(E G)), the resolution the SENB study reads its errors at */
  assert_true(fabs(gc - 1.0) < 0.02 && fabs(gc - 1.0) < fabs(g - 1.0));
  /* a lattice-axis cut against the orientation average that `calibration: grid` fits
     (measured 0.985): the calibration holds for a crack along a lattice plane to 2% */
  assert_true(fabs(axis - 1.0) < 0.02);
}

static void test_patched_rows(void **state) {
  (void)state;
  patch_and_compare(CUPID_PD_BOND, CUPID_SURFACE_NONE, 0);
  patch_and_compare(CUPID_PD_BOND, CUPID_SURFACE_NONE, 1);
  patch_and_compare(CUPID_PD_BOND, CUPID_SURFACE_ENERGY, 1);
  patch_and_compare(CUPID_PD_LPS, CUPID_SURFACE_NONE, 0);
}

static void test_corrected_lps_refused(void **state) {
  (void)state;
  const cupid_box box = box3(0, 9, 0, 8, 0, 5);
  body b = make_corrected(1, &box, CUPID_PD_LPS, CUPID_PARTIAL_PDLAMMPS, 3.0, CUPID_SURFACE_ENERGY);
  cupid_pd_precrack c = {.normal = 1, .at = 4.0, .lo = {0, 0, -1}, .hi = {3, 0, 9}};
  cupid_int removed = 0;
  assert_int_equal(cupid_pd_operator_precrack(b.op, &c, &removed), CUPID_ERR_UNSUPPORTED);
  assert_non_null(strstr(cupid_error_message(), "need model: bond"));
  cupid_error_clear();
  destroy(&b);
}

/* A body deep enough for the LPS first pass's uniform-b stretches (pd_run ub0, ub1: a node
 * and its whole family with one b = mu/m), cracked through them: a removed bond changes the
 * m, so the b, of its two nodes, and the stretches must give way around them (else the
 * kernel would take 2 b_j for b_j + b_i). Stencil path against the bond lists, every
 * instruction set, for the pre-crack and then for bonds broken one at a time. */
static void test_cracked_uniform(void **state) {
  (void)state;
  const cupid_box box = box3(0, 30, 0, 15, 0, 15);
  for (int isa = 1; isa <= 4; isa += (isa == 1 ? 2 : 1)) {
    body b = make(1, &box, CUPID_PD_LPS, CUPID_PARTIAL_PDLAMMPS, 3.0);
    cupid_int uniform = 0, removed, broken;
    for (cupid_int r = 0; r < b.op->nruns; r++) uniform += b.op->runs[r].ub1 - b.op->runs[r].ub0;
    assert_true(uniform > 0);
    const cupid_int n = b.n;
    double *u = malloc(3 * (size_t)n * sizeof *u), *f = malloc(3 * (size_t)n * sizeof *f);
    double *g = malloc(3 * (size_t)n * sizeof *g), diss;
    uint64_t seed = 29;
    for (cupid_int i = 0; i < 3 * n; i++) u[i] = cupid_test_random(&seed) - 0.5;
    for (int stage = 0; stage < 2; stage++) {
      if (stage == 0) { /* a pre-crack across the middle of the bulk */
        cupid_pd_precrack c = {.normal = 1, .at = 7.0, .lo = {10, 0, -1}, .hi = {20, 0, 16}};
        CUPID_ASSERT_OK(cupid_pd_operator_precrack(b.op, &c, &removed));
        assert_true(removed > 0);
      } else { /* then the most strained bond alone, a few times */
        cupid_pd_fracture_options fo = {.criterion = CUPID_PD_BREAK_STRETCH,
                                        .critical_stretch = 0.05};
        for (int k = 0; k < 5; k++) {
          CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(b.op, u, &fo, 1, &broken, &diss));
          assert_int_equal(broken, 1);
        }
      }
      b.op->stencil_off = 0;
      pd_stencil_force_isa(isa);
      CUPID_ASSERT_OK(cupid_pd_operator_apply(b.op, u, f));
      pd_stencil_force_isa(0);
      CUPID_ASSERT_OK(pd_operator_use_bond_lists(b.op));
      CUPID_ASSERT_OK(cupid_pd_operator_apply(b.op, u, g));
      const double fm = max_abs(3 * n, g);
      /* as check_cracked: round-off, 1e-12 of max |f| */
      for (cupid_int i = 0; i < 3 * n; i++) ASSERT_NEAR(f[i], g[i], 1e-12 * fm);
    }
    free(u), free(f), free(g);
    destroy(&b);
  }
}

/* u_y = s y (s = 1/2, coordinates half-integers: every stretch exact): bonds along y have
 * stretch exactly s, all others less. At s0 = s none breaks; at u (1 + 2^-10) exactly the
 * y bonds do; then nothing heals or breaks at u = 0. */
static void test_stretch_threshold(void **state) {
  (void)state;
  cupid_box bx = box3(0, 5, 0, 6, 0, 4);
  body b = make(1, &bx, CUPID_PD_BOND, CUPID_PARTIAL_NONE, 2.5);
  const double *x = cupid_pd_grid_coords(b.grid);
  double *u = calloc(3 * (size_t)b.n, sizeof *u), diss;
  for (cupid_int i = 0; i < b.n; i++) u[3 * i + 1] = 0.5 * x[3 * i + 1];
  cupid_pd_fracture_options fo = {.criterion = CUPID_PD_BREAK_STRETCH, .critical_stretch = 0.5};
  cupid_int broken;
  CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(b.op, u, &fo, 0, &broken, &diss));
  assert_int_equal(broken, 0);
  for (cupid_int i = 0; i < 3 * b.n; i++) u[i] *= 1.0 + 1.0 / 1024.0;
  CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(b.op, u, &fo, 0, &broken, &diss));
  /* y bonds: pairs on one (x, z) column at y distance 1 or 2 (<= 2.5) */
  const cupid_int columns = 5 * 4, expect = columns * (5 + 4);
  assert_int_equal(broken, expect);
  assert_true(diss > 0);
  assert_int_equal(cupid_pd_operator_bond_intact(b.op, 0, 5), 0);  /* (0.5,0.5) - (0.5,1.5) */
  assert_int_equal(cupid_pd_operator_bond_intact(b.op, 0, 1), 1);  /* along x */
  memset(u, 0, 3 * (size_t)b.n * sizeof *u);
  CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(b.op, u, &fo, 0, &broken, &diss));
  assert_int_equal(broken, 0);
  assert_int_equal(cupid_pd_operator_num_broken(b.op), expect);
  assert_int_equal(cupid_pd_operator_bond_intact(b.op, 0, 5), 0); /* irreversible */
  free(u);
  destroy(&b);
}

/* Protected nodes and no-fail boxes; only_most; damage; dissipated energy = energy drop. */
static void test_protect_damage_energy(void **state) {
  (void)state;
  cupid_box bx = box3(0, 6, 0, 6, 0, 4);
  for (int model = 0; model < 2; model++) {
    body b = make(1, &bx, (cupid_pd_model_kind)model, CUPID_PARTIAL_PDLAMMPS, 2.5);
    const double *x = cupid_pd_grid_coords(b.grid);
    double *u = calloc(3 * (size_t)b.n, sizeof *u), *dmg = calloc((size_t)b.n, sizeof *dmg);
    uint32_t *nf = calloc((size_t)b.n, sizeof *nf);
    unsigned char *prot = calloc((size_t)b.n, 1);
    for (cupid_int i = 0; i < b.n; i++) {
      u[3 * i + 1] = x[3 * i + 1] > 3 ? 0.1 : 0.0; /* a jump across y = 3 */
      nf[i] = x[3 * i] < 2 ? 1u : 0u;               /* no-fail box x < 2 */
      prot[i] = x[3 * i] > 5 ? 1 : 0;               /* protected column x > 5 */
    }
    cupid_pd_fracture_options fo = {.criterion = CUPID_PD_BREAK_STRETCH, .critical_stretch = 0.01,
                                    .protect = prot, .no_fail = nf};
    cupid_int broken, damaged;
    double diss, E0, E1, maxd;
    CUPID_ASSERT_OK(cupid_pd_operator_energy(b.op, u, &E0));
    CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(b.op, u, &fo, 1, &broken, &diss));
    assert_int_equal(broken, 1);
    CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(b.op, u, &fo, 0, &broken, &diss));
    assert_true(broken > 0);
    CUPID_ASSERT_OK(cupid_pd_operator_energy(b.op, u, &E1));
    /* the energy left plus the energy of the second batch: its drop (the first batch's
     * energy is E0 - E1 - diss, positive) */
    assert_true(diss > 0 && E0 - E1 > diss);
    double E2;
    fo.critical_stretch = 1e-6; /* the rest of the breakable bonds across the jump */
    CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(b.op, u, &fo, 0, &broken, &diss));
    CUPID_ASSERT_OK(cupid_pd_operator_energy(b.op, u, &E2));
    ASSERT_NEAR(E1 - E2, diss, 1e-12 * E0);
    for (cupid_int i = 0; i < b.n; i++)
      for (cupid_int j = 0; j < b.n; j++) {
        const double *p = x + 3 * i, *q = x + 3 * j;
        if (!((p[1] < 3) && (q[1] > 3))) continue;
        const int may = !(p[0] < 2 && q[0] < 2) && !(p[0] > 5 || q[0] > 5);
        double r2 = 0;
        for (int k = 0; k < 3; k++) r2 += (q[k] - p[k]) * (q[k] - p[k]);
        if (r2 > 2.4 * 2.4) continue; /* bonded for sure (beta 1 within delta - h/2 = 2) */
        if (fabs(q[0] - p[0]) > 1e-9 || fabs(q[2] - p[2]) > 1e-9) continue; /* along y */
        assert_int_equal(cupid_pd_operator_bond_intact(b.op, i, j), !may);
      }
    /* what is left over its limit: only bonds the protection keeps (cupid_pd_operator_blocked,
     * the growth's stop at a coupling zone), none the criterion may break (max_ratio) */
    double r = -1.0;
    CUPID_ASSERT_OK(cupid_pd_operator_max_ratio(b.op, u, &fo, &r));
    assert_true(r == 0.0);
    cupid_int blocked = 0, node = -1, expect = 0;
    CUPID_ASSERT_OK(cupid_pd_operator_blocked(b.op, u, &fo, &blocked, &node, &r));
    for (cupid_int i = 0; i < b.n; i++)
      for (cupid_int j = i + 1; j < b.n; j++) {
        const double *p = x + 3 * i, *q = x + 3 * j;
        const int across = (p[1] < 3) != (q[1] < 3);
        expect += across && (p[0] > 5 || q[0] > 5) && cupid_pd_operator_bond_intact(b.op, i, j);
      }
    assert_true(expect > 0);
    assert_int_equal(blocked, expect);
    assert_true(node >= 0 && x[3 * node] > 5 && r > 1.0);
    fo.protect = NULL; /* nothing protected: nothing blocked */
    CUPID_ASSERT_OK(cupid_pd_operator_blocked(b.op, u, &fo, &blocked, &node, &r));
    assert_true(blocked == 0 && node == -1);
    fo.protect = prot;
    CUPID_ASSERT_OK(cupid_pd_operator_damage(b.op, dmg, &damaged, &maxd));
    assert_true(damaged > 0 && maxd > 0 && maxd < 1);
    for (cupid_int i = 0; i < b.n; i++) {
      const double *p = x + 3 * i;
      if (p[0] > 5) assert_true(dmg[i] == 0.0); /* protected */
      if (p[1] < 1 || p[1] > 5) assert_true(dmg[i] == 0.0); /* too far from the jump */
    }
    free(u), free(dmg), free(nf), free(prot);
    destroy(&b);
  }
}

/* Per node, the largest ratio of the bonds only the protection keeps (the adaptive zone's
 * overlap trigger): a uniform strain e along y stretches a bond along y by e, every node has
 * one, so a protected node reads e / s0 and the others 0; cut bonds and no-fail pairs are
 * not read. */
static void test_protected_ratios(void **state) {
  (void)state;
  cupid_box bx = box3(0, 6, 0, 6, 0, 4);
  for (int model = 0; model < 2; model++) {
    body b = make(1, &bx, (cupid_pd_model_kind)model, CUPID_PARTIAL_PDLAMMPS, 2.5);
    const double *x = cupid_pd_grid_coords(b.grid);
    double *u = calloc(3 * (size_t)b.n, sizeof *u), *r = calloc((size_t)b.n, sizeof *r);
    uint32_t *nf = calloc((size_t)b.n, sizeof *nf);
    unsigned char *prot = calloc((size_t)b.n, 1);
    const double e = 0.002, s0 = 0.01;
    for (cupid_int i = 0; i < b.n; i++) {
      u[3 * i + 1] = e * x[3 * i + 1];
      prot[i] = x[3 * i] > 5 ? 1 : 0;
    }
    cupid_pd_fracture_options fo = {.criterion = CUPID_PD_BREAK_STRETCH, .critical_stretch = s0,
                                    .protect = prot, .no_fail = nf};
    CUPID_ASSERT_OK(cupid_pd_operator_protected_ratios(b.op, u, &fo, r));
    for (cupid_int i = 0; i < b.n; i++) ASSERT_NEAR(r[i], prot[i] ? e / s0 : 0.0, 1e-12);
    cupid_pd_precrack crack = {.normal = 1, .at = 3.0, .lo = {-1, 0, -1}, .hi = {7, 0, 5}};
    cupid_int removed = 0;
    CUPID_ASSERT_OK(cupid_pd_operator_precrack(b.op, &crack, &removed));
    assert_true(removed > 0);
    CUPID_ASSERT_OK(cupid_pd_operator_protected_ratios(b.op, u, &fo, r));
    for (cupid_int i = 0; i < b.n; i++) ASSERT_NEAR(r[i], prot[i] ? e / s0 : 0.0, 1e-12);
    /* the bonds across the cut: a jump there is read by no node */
    for (cupid_int i = 0; i < b.n; i++) u[3 * i + 1] = x[3 * i + 1] > 3 ? 0.5 : 0.0;
    CUPID_ASSERT_OK(cupid_pd_operator_protected_ratios(b.op, u, &fo, r));
    for (cupid_int i = 0; i < b.n; i++) assert_true(r[i] == 0.0);
    for (cupid_int i = 0; i < b.n; i++) u[3 * i + 1] = e * x[3 * i + 1], nf[i] = 1u;
    CUPID_ASSERT_OK(cupid_pd_operator_protected_ratios(b.op, u, &fo, r)); /* all no-fail */
    for (cupid_int i = 0; i < b.n; i++) assert_true(r[i] == 0.0);
    fo.criterion = CUPID_PD_BREAK_ENERGY;
    assert_int_equal(cupid_pd_operator_protected_ratios(b.op, u, &fo, r), CUPID_ERR_ARGUMENT);
    free(u), free(r), free(nf), free(prot);
    destroy(&b);
  }
}

/* The vectorised stretch scan of the stencil path and the plain bond-by-bond scan break the
 * same bonds: a padded box and a sparse union, random fields over several rounds (bonds already
 * broken must be skipped), the stretch given and per node. */
static void test_scan_paths(void **state) {
  (void)state;
  const cupid_box box = box3(0, 12, 0, 10, 0, 6);
  const cupid_box sparse[2] = {box3(0, 9, 0, 8, 0, 5), box3(40, 46, 30, 36, 0, 5)};
  for (int g = 0; g < 2; g++)
    for (int per_node = 0; per_node < 2; per_node++) {
      body b[2];
      double dmg[2][1000];
      for (int path = 0; path < 2; path++) {
        b[path] = make(g ? 2 : 1, g ? sparse : &box, CUPID_PD_BOND, CUPID_PARTIAL_PDLAMMPS, 3.0);
        assert_true(b[path].n <= 1000);
        double *u = malloc(3 * (size_t)b[path].n * sizeof *u), *ns = malloc((size_t)b[path].n * sizeof *ns);
        for (cupid_int i = 0; i < b[path].n; i++) ns[i] = 0.3 + 0.1 * (double)(i % 3);
        cupid_pd_fracture_options fo = {.criterion = CUPID_PD_BREAK_STRETCH, .critical_stretch = 0.35,
                                        .node_stretch = per_node ? ns : NULL};
        pd_fracture_force_plain_scan(path);
        cupid_int total = 0;
        for (int round = 0; round < 3; round++) {
          uint64_t seed = 21 + (uint64_t)round;
          for (cupid_int i = 0; i < 3 * b[path].n; i++) u[i] = 100.0 + cupid_test_random(&seed) - 0.5;
          cupid_int broken;
          double diss;
          CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(b[path].op, u, &fo, 0, &broken, &diss));
          total += broken;
        }
        pd_fracture_force_plain_scan(0);
        assert_true(total > 0);
        CUPID_ASSERT_OK(cupid_pd_operator_damage(b[path].op, dmg[path], NULL, NULL));
        free(u), free(ns);
      }
      assert_int_equal(cupid_pd_operator_num_broken(b[0].op), cupid_pd_operator_num_broken(b[1].op));
      assert_memory_equal(dmg[0], dmg[1], (size_t)b[0].n * sizeof(double));
      destroy(&b[0]);
      destroy(&b[1]);
    }
}

/* The same broken bonds for 1 and 2 threads (a large enough body for the parallel scan). */
static void test_threads(void **state) {
  (void)state;
#ifdef _OPENMP
  cupid_box bx = box3(0, 16, 0, 16, 0, 8);
  double dmg[2][2048];
  cupid_int nb[2];
  const int saved = omp_get_max_threads();
  for (int t = 0; t < 2; t++) {
    omp_set_num_threads(t + 1);
    body b = make(1, &bx, CUPID_PD_LPS, CUPID_PARTIAL_PDLAMMPS, 3.0);
    assert_true(b.n <= 2048);
    double *u = malloc(3 * (size_t)b.n * sizeof *u), diss;
    uint64_t seed = 9;
    for (cupid_int i = 0; i < 3 * b.n; i++) u[i] = cupid_test_random(&seed) - 0.5;
    cupid_pd_fracture_options fo = {.criterion = CUPID_PD_BREAK_STRETCH, .critical_stretch = 0.4};
    CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(b.op, u, &fo, 0, &nb[t], &diss));
    fo.criterion = CUPID_PD_BREAK_ENERGY;
    fo.critical_energy = 2.0;
    cupid_int more;
    CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(b.op, u, &fo, 0, &more, &diss));
    nb[t] += more;
    CUPID_ASSERT_OK(cupid_pd_operator_damage(b.op, dmg[t], NULL, NULL));
    free(u);
    destroy(&b);
  }
  omp_set_num_threads(saved);
  assert_true(nb[0] > 0);
  assert_int_equal(nb[0], nb[1]);
  assert_memory_equal(dmg[0], dmg[1], sizeof dmg[0]);
#endif
}

/* A node that loses every bond: no force on it, nothing non-finite anywhere. */
static void test_isolated_node(void **state) {
  (void)state;
  cupid_box bx = box3(0, 5, 0, 5, 0, 5);
  for (int model = 0; model < 2; model++) {
    body b = make(1, &bx, (cupid_pd_model_kind)model, CUPID_PARTIAL_PDLAMMPS, 2.0);
    double *u = calloc(3 * (size_t)b.n, sizeof *u), *f = malloc(3 * (size_t)b.n * sizeof *f);
    const cupid_int c = 62; /* (2.5, 2.5, 2.5) */
    cupid_pd_fracture_options fo = {.criterion = CUPID_PD_BREAK_STRETCH, .critical_stretch = 0.5};
    cupid_int broken, total = 0;
    double diss;
    /* pulled along +-x, +-y, +-z in turn: every bond of c is stretched by one of them
     * (by 10 |n_k| / x >= 10 / (sqrt 3 * 2) > s0 for its largest component k) */
    for (int d = 0; d < 6; d++) {
      u[3 * c] = u[3 * c + 1] = u[3 * c + 2] = 0.0;
      u[3 * c + d / 2] = d % 2 ? -10.0 : 10.0;
      CUPID_ASSERT_OK(cupid_pd_operator_break_bonds(b.op, u, &fo, 0, &broken, &diss));
      total += broken;
    }
    assert_true(total > 0);
    assert_true(isinf(b.op->m[c]));
    /* the scale: the forces of the same field on the intact body */
    body intact = make(1, &bx, (cupid_pd_model_kind)model, CUPID_PARTIAL_PDLAMMPS, 2.0);
    CUPID_ASSERT_OK(cupid_pd_operator_apply(intact.op, u, f));
    const double scale = max_abs(3 * b.n, f);
    destroy(&intact);
    CUPID_ASSERT_OK(cupid_pd_operator_apply(b.op, u, f));
    for (cupid_int i = 0; i < 3 * b.n; i++) assert_true(isfinite(f[i]));
    /* c's force is the sweep minus all its bonds, the others rest (u = 0 there): zero to
     * round-off of the intact forces */
    assert_true(max_abs(3 * b.n, f) < 1e-13 * scale);
    double dmg[125];
    CUPID_ASSERT_OK(cupid_pd_operator_damage(b.op, dmg, NULL, NULL));
    assert_true(dmg[c] == 1.0);
    free(u), free(f);
    destroy(&b);
  }
}

/* A second operator on the same grid loses the same bonds (the Arlequin operator's copy). */
static void test_copy_broken(void **state) {
  (void)state;
  cupid_box bx = box3(0, 9, 0, 8, 0, 5);
  body a = make(1, &bx, CUPID_PD_LPS, CUPID_PARTIAL_PDLAMMPS, 3.0);
  crack_body(&a, 0.3);
  cupid_pd_operator_options oo = {.horizon = 3.0, .model = CUPID_PD_LPS,
                                  .influence = CUPID_INFLUENCE_GAUSSIAN,
                                  .partial_volume = CUPID_PARTIAL_PDLAMMPS, .materials = mats,
                                  .n_materials = 2};
  cupid_pd_operator b = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(a.grid, &oo, &b));
  CUPID_ASSERT_OK(cupid_pd_operator_copy_broken(b, a.op));
  assert_int_equal(cupid_pd_operator_num_broken(b), cupid_pd_operator_num_broken(a.op));
  double *u = malloc(3 * (size_t)a.n * sizeof *u), *f = malloc(3 * (size_t)a.n * sizeof *f);
  double *g = malloc(3 * (size_t)a.n * sizeof *g);
  uint64_t seed = 5;
  for (cupid_int i = 0; i < 3 * a.n; i++) u[i] = cupid_test_random(&seed) - 0.5;
  CUPID_ASSERT_OK(cupid_pd_operator_apply(a.op, u, f));
  CUPID_ASSERT_OK(cupid_pd_operator_apply(b, u, g));
  for (cupid_int i = 0; i < 3 * a.n; i++) ASSERT_NEAR(f[i], g[i], 1e-12 * max_abs(3 * a.n, f));
  CUPID_ASSERT_OK(cupid_pd_operator_copy_broken(b, a.op)); /* again: nothing new */
  assert_int_equal(cupid_pd_operator_num_broken(b), cupid_pd_operator_num_broken(a.op));
  free(u), free(f), free(g);
  cupid_pd_operator_destroy(&b);
  destroy(&a);
}

/* ---- Nodes that lost their support (cupid_pd_operator_unsupported and its two halves) ----
 * A bar 6 x 6 x 12 cut through at z = 6 by a pre-crack, with one node of the lower part
 * isolated by six small pre-cracks around its cell, anchored at its bottom layer: every node
 * above the cut (a fragment) and the isolated node (no bond left) lose their support, nothing
 * else does. Then the same search as slabs of a distributed grid run it (growth_matrix_free.c): each
 * slab decides its owned nodes' weakness, searches from the anchored nodes and the flags its
 * neighbours sent, and the owned flags go to the other slabs' copies until none changes; the
 * owners' flags must be the whole grid's, and the middle slab (no anchored node) must need
 * the exchange. */
static const cupid_box support_box = {.lo = {0, 0, 0}, .hi = {6, 6, 12}, .has = {1, 1, 1}};
static const double support_isolated[3] = {2.5, 2.5, 2.5};

static void support_cracks(cupid_pd_operator op) {
  cupid_int removed = 0;
  cupid_pd_precrack cut = {.normal = 2, .at = 6.0, .lo = {0, 0, 0}, .hi = {6, 6, 0}};
  CUPID_ASSERT_OK(cupid_pd_operator_precrack(op, &cut, &removed));
  for (int a = 0; a < 3; a++) /* the faces of the isolated node's cell */
    for (int side = 0; side < 2; side++) {
      cupid_pd_precrack c = {.normal = a, .at = support_isolated[a] + (side ? 0.5 : -0.5)};
      for (int b = 0; b < 3; b++)
        if (b != a) c.lo[b] = support_isolated[b] - 0.5, c.hi[b] = support_isolated[b] + 0.5;
      CUPID_ASSERT_OK(cupid_pd_operator_precrack(op, &c, &removed));
    }
}

static body support_body(int parts, int part, int halo) {
  body b = {0};
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3, .parts = parts, .part = part,
                              .halo_layers = halo};
  int m = 0;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &support_box, &m, &b.grid));
  cupid_pd_operator_options oo = {.horizon = 2.0, .model = CUPID_PD_BOND,
                                  .influence = CUPID_INFLUENCE_CONSTANT,
                                  .partial_volume = CUPID_PARTIAL_NONE, .materials = mats,
                                  .n_materials = 1};
  CUPID_ASSERT_OK(cupid_pd_operator_create(b.grid, &oo, &b.op));
  b.n = cupid_pd_grid_num_nodes(b.grid);
  support_cracks(b.op);
  return b;
}

/* Owned flags of every slab to the other slabs' copies (by global index): copy = owner's, or
 * copy |= owner's; returns how many copies that raised. */
#define SUPPORT_PARTS 3
static cupid_int support_share(body *s, const cupid_pd_grid_partition *pt, unsigned char **flag,
                               int or) {
  cupid_int changed = 0;
  for (int p = 0; p < SUPPORT_PARTS; p++)
    for (cupid_int i = 0; i < s[p].n; i++) {
      if (i >= pt[p].owned_first && i < pt[p].owned_last) continue;
      const cupid_int g = pt[p].first_global + i;
      int q = 0;
      while (!(g >= pt[q].first_global + pt[q].owned_first && g < pt[q].first_global + pt[q].owned_last)) q++;
      const unsigned char v = flag[q][g - pt[q].first_global];
      if (!or) flag[p][i] = v;
      else if (v && !flag[p][i]) flag[p][i] = v, changed++;
    }
  return changed;
}

static void test_support(void **state) {
  (void)state;
  body w = support_body(1, 0, 0);
  const double *x = cupid_pd_grid_coords(w.grid);
  unsigned char *anchored = calloc((size_t)w.n, 1), *release = calloc((size_t)w.n, 1);
  for (cupid_int i = 0; i < w.n; i++) anchored[i] = x[3 * i + 2] < 1.0;
  cupid_int count = 0, expected = 0;
  CUPID_ASSERT_OK(cupid_pd_operator_unsupported(w.op, anchored, release, &count));
  for (cupid_int i = 0; i < w.n; i++) {
    const double *xi = x + 3 * i;
    const int isolated = xi[0] == support_isolated[0] && xi[1] == support_isolated[1] &&
                         xi[2] == support_isolated[2];
    const int lost = xi[2] > 6.0 || isolated;
    expected += lost;
    assert_int_equal(release[i], lost ? 2 : 0);
  }
  assert_int_equal(count, expected);
  assert_int_equal(expected, 6 * 6 * 6 + 1);
  /* again: the released ones stay, nothing new */
  CUPID_ASSERT_OK(cupid_pd_operator_unsupported(w.op, anchored, release, &count));
  assert_int_equal(count, expected);
  for (cupid_int i = 0; i < w.n; i++)
    if (release[i]) release[i] = 1;
  CUPID_ASSERT_OK(cupid_pd_operator_unsupported(w.op, anchored, release, &count));
  assert_int_equal(count, 0);

  /* the slabs */
  int halo = 0;
  cupid_pd_operator_options oo = {.horizon = 2.0, .model = CUPID_PD_BOND};
  CUPID_ASSERT_OK(cupid_pd_operator_halo_layers(&oo, 1.0, &halo));
  body s[SUPPORT_PARTS];
  cupid_pd_grid_partition pt[SUPPORT_PARTS];
  unsigned char *rel[SUPPORT_PARTS], *seen[SUPPORT_PARTS];
  for (int p = 0; p < SUPPORT_PARTS; p++) {
    s[p] = support_body(SUPPORT_PARTS, p, halo);
    cupid_pd_grid_get_partition(s[p].grid, &pt[p]);
    rel[p] = calloc((size_t)s[p].n, 1);
    seen[p] = calloc((size_t)s[p].n, 1);
    cupid_int weak = 0;
    CUPID_ASSERT_OK(cupid_pd_operator_weakly_held(s[p].op, pt[p].owned_first, pt[p].owned_last,
                                                  rel[p], &weak));
  }
  support_share(s, pt, rel, 0);
  for (int p = 0; p < SUPPORT_PARTS; p++) {
    const double *xp = cupid_pd_grid_coords(s[p].grid);
    for (cupid_int i = 0; i < s[p].n; i++) seen[p][i] = xp[3 * i + 2] < 1.0 && !rel[p][i];
  }
  int rounds = 0;
  cupid_int changed;
  do {
    for (int p = 0; p < SUPPORT_PARTS; p++) {
      cupid_int added = 0;
      CUPID_ASSERT_OK(cupid_pd_operator_reach(s[p].op, rel[p], seen[p], &added));
    }
    changed = support_share(s, pt, seen, 1);
    rounds++;
  } while (changed > 0);
  assert_true(rounds >= 2); /* the upper slabs hold no anchored node */
  cupid_int total = 0;
  for (int p = 0; p < SUPPORT_PARTS; p++)
    for (cupid_int i = pt[p].owned_first; i < pt[p].owned_last; i++) {
      if (!rel[p][i] && !seen[p][i]) rel[p][i] = 2;
      const cupid_int g = pt[p].first_global + i;
      assert_int_equal(rel[p][i] != 0, release[g] != 0);
      total += rel[p][i] != 0;
    }
  assert_int_equal(total, expected);
  printf("support search: %lld of %lld nodes lost their support, found alike by the whole grid "
         "and by %d slabs in %d rounds\n", (long long)expected, (long long)w.n, SUPPORT_PARTS, rounds);
  for (int p = 0; p < SUPPORT_PARTS; p++) {
    free(rel[p]), free(seen[p]);
    destroy(&s[p]);
  }
  free(anchored), free(release);
  destroy(&w);
}

/* ---- Mechanisms of a few nodes (cupid_pd_operator_mechanisms) ----
 * A cube 6 x 6 x 6, spacing 1, horizon 1.5 (axis and face-diagonal bonds: a rigid lattice).
 * Nodes A (2.5, 2.5, 2.5) and B (3.5, 2.5, 2.5) keep only the bond A-B, A's bonds along +y and
 * +z and B's along -y and -z: each is held in every direction by its own bonds, its neighbours
 * fixed (cupid_pd_operator_weakly_held passes them), but together they translate along x
 * freely (6 DOFs, 5 bonds): cupid_pd_operator_mechanisms marks the one that moved least (|u|;
 * crack growth ties it), then the other is held by its bonds. C (2.5, 2.5, 4.5) keeps three
 * bonds along +x, +y and -z
 * to the body: rigid, not held. */
static void keep_only(body *w, const double *x, const double at[3], const double (*keep)[3], int nkeep,
                      double *words) {
  const int nw = cupid_pd_operator_broken_words(w->op);
  cupid_int i = 0;
  while (i < w->n && !(x[3 * i] == at[0] && x[3 * i + 1] == at[1] && x[3 * i + 2] == at[2])) i++;
  assert_true(i < w->n);
  const struct cupid_pd_operator_private *op = w->op;
  const int half = op->st.n / 2;
  const pd_family F = pd_family_of(op, i);
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    const cupid_int j = pd_family_node(op, &F, s);
    int kept = 0;
    for (int k = 0; k < nkeep; k++)
      kept |= x[3 * j] == keep[k][0] && x[3 * j + 1] == keep[k][1] && x[3 * j + 2] == keep[k][2];
    if (kept) continue;
    if (s >= half) { /* the packed words hold each bond at the end whose entry is in the upper half */
      const size_t at_w = (size_t)i * nw + ((s - half) >> 5);
      const uint32_t bit = (uint32_t)1 << ((s - half) & 31), have = (uint32_t)words[at_w];
      words[at_w] = (double)(have | bit); /* set once: another node's call may have set it */
      continue;
    }
    const pd_family G = pd_family_of(op, j);
    for (int r = 0; r < G.n; r++) {
      const int t = pd_family_entry(&G, r);
      if (t >= half && pd_family_node(op, &G, t) == i) {
        const size_t at_w = (size_t)j * nw + ((t - half) >> 5);
        const uint32_t bit = (uint32_t)1 << ((t - half) & 31), have = (uint32_t)words[at_w];
        if (!(have & bit)) words[at_w] = (double)(have | bit);
      }
    }
  }
}

/* A bond-based box [0, X] x [0, Y] x [0, Z], spacing 1, horizon 1.5 (18 neighbours), constant
 * influence, whole volumes: every bond of the same weight (the mechanism tests). */
static void bond_box(body *w, double X, double Y, double Z) {
  const cupid_box box = {.lo = {0, 0, 0}, .hi = {X, Y, Z}, .has = {1, 1, 1}};
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  int m = 0;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &box, &m, &w->grid));
  cupid_pd_operator_options oo = {.horizon = 1.5, .model = CUPID_PD_BOND,
                                  .influence = CUPID_INFLUENCE_CONSTANT,
                                  .partial_volume = CUPID_PARTIAL_NONE, .materials = mats,
                                  .n_materials = 1};
  CUPID_ASSERT_OK(cupid_pd_operator_create(w->grid, &oo, &w->op));
  w->n = cupid_pd_grid_num_nodes(w->grid);
}

static void test_mechanism(void **state) {
  (void)state;
  body w = {0};
  bond_box(&w, 6, 6, 6);
  const double *x = cupid_pd_grid_coords(w.grid);
  const int nw = cupid_pd_operator_broken_words(w.op);
  double *words = calloc((size_t)w.n * nw + 1, sizeof *words), *u = calloc(3 * (size_t)w.n, sizeof *u);
  unsigned char *release = calloc((size_t)w.n, 1);
  const double A[3] = {2.5, 2.5, 2.5}, B[3] = {3.5, 2.5, 2.5}, C[3] = {2.5, 2.5, 4.5};
  const double keepA[3][3] = {{3.5, 2.5, 2.5}, {2.5, 3.5, 2.5}, {2.5, 2.5, 3.5}};
  const double keepB[3][3] = {{2.5, 2.5, 2.5}, {3.5, 1.5, 2.5}, {3.5, 2.5, 1.5}};
  const double keepC[3][3] = {{3.5, 2.5, 4.5}, {2.5, 3.5, 4.5}, {2.5, 2.5, 3.5}};
  keep_only(&w, x, A, keepA, 3, words);
  keep_only(&w, x, B, keepB, 3, words);
  keep_only(&w, x, C, keepC, 3, words);
  cupid_pd_fracture_options fo = {.criterion = CUPID_PD_BREAK_STRETCH, .critical_stretch = 1.0};
  cupid_int added = 0;
  double dissipated = 0.0;
  CUPID_ASSERT_OK(cupid_pd_operator_unpack_broken(w.op, 0, w.n, words, u, &fo, &added, &dissipated));
  assert_int_equal(added, 3 * (18 - 3)); /* A-B kept by both */
  cupid_int count = -1;
  CUPID_ASSERT_OK(cupid_pd_operator_weakly_held(w.op, 0, w.n, release, &count));
  assert_int_equal(count, 0); /* each held by its own bonds */
  cupid_int iA = -1, iB = -1;
  for (cupid_int i = 0; i < w.n; i++) {
    if (x[3 * i] == A[0] && x[3 * i + 1] == A[1] && x[3 * i + 2] == A[2]) iA = i;
    if (x[3 * i] == B[0] && x[3 * i + 1] == B[1] && x[3 * i + 2] == B[2]) iB = i;
  }
  /* the node held is the one of the pair that moved least: B, then A */
  for (int round = 0; round < 2; round++) {
    memset(release, 0, (size_t)w.n);
    for (cupid_int k = 0; k < 3 * w.n; k++) u[k] = 0.0;
    u[3 * iA] = round ? 1.0 : 2.0, u[3 * iB] = round ? 2.0 : 1.0;
    CUPID_ASSERT_OK(cupid_pd_operator_mechanisms(w.op, 0, w.n, u, NULL, release, &count));
    assert_int_equal(count, 1);
    for (cupid_int i = 0; i < w.n; i++) assert_int_equal(release[i], i == (round ? iA : iB) ? 2 : 0);
    release[round ? iA : iB] = 1; /* the other is held by its bonds now */
    CUPID_ASSERT_OK(cupid_pd_operator_mechanisms(w.op, 0, w.n, u, NULL, release, &count));
    assert_int_equal(count, 0);
  }
  memset(release, 0, (size_t)w.n); /* without u: the node order (A before B), B held */
  CUPID_ASSERT_OK(cupid_pd_operator_mechanisms(w.op, 0, w.n, NULL, NULL, release, &count));
  assert_int_equal(count, 1);
  assert_int_equal(release[iA < iB ? iB : iA], 2);
  free(words), free(u), free(release);
  destroy(&w);
}

/* The node of a 3D grid at (x, y, z), or -1. */
static cupid_int node_at(const double *x, cupid_int n, double px, double py, double pz) {
  for (cupid_int i = 0; i < n; i++)
    if (x[3 * i] == px && x[3 * i + 1] == py && x[3 * i + 2] == pz) return i;
  return -1;
}

/* A mechanism of two nodes inside a band of damaged nodes (issue 37: the notched C-beam's
 * flange ligaments, src/pd/fracture.c "Mechanisms inside a band"): the top layer of a 10 x 10 x 4
 * grid (horizon 1.5) keeps of its 13 bonds the 4 in-plane edge bonds and the one straight down
 * (8/13 lost, P and Q below a diagonal one more: each node a candidate, held in x, y and z).
 * Its edge nodes are held (release 1, as crack growth holds nodes: fixed), which pins each row
 * and column of the layer against sliding along itself; the 64 inner nodes are one cluster over
 * their edge bonds, too large to be factorised whole. No mechanism there, the whole band searched
 * or only its nodes touched since @p seen. Then P = (4.5, 4.5, 3.5) and Q = (5.5, 4.5, 3.5) keep
 * only P-Q, P-(P + y), Q-(Q - y) and a diagonal bond down each, away from the other: each node
 * held in every direction by its own bonds (weakly_held sees nothing), the pair free to move as
 * ux_P = ux_Q = 1, uz_P = -1, uz_Q = 1 (K of that mode: zero, checked on the operator). The
 * balls around the nodes touched since the band's check find it: one of P and Q marked; the
 * call after that, with nothing touched, tests no ball; every node's ball finds it once. */
static void test_mechanism_in_band(void **state) {
  (void)state;
  body w = {0};
  bond_box(&w, 10, 10, 4);
  const double *x = cupid_pd_grid_coords(w.grid);
  const int nw = cupid_pd_operator_broken_words(w.op);
  double *words = calloc((size_t)w.n * nw + 1, sizeof *words), *u = calloc(3 * (size_t)w.n, sizeof *u);
  double *f = calloc(3 * (size_t)w.n, sizeof *f), *seen = calloc((size_t)w.n, sizeof *seen);
  unsigned char *release = calloc((size_t)w.n, 1), *held = calloc((size_t)w.n, 1);
  cupid_pd_fracture_options fo = {.criterion = CUPID_PD_BREAK_STRETCH, .critical_stretch = 1.0};
  cupid_int added = 0, count = -1, band = 0;
  double dissipated = 0.0;
  for (double px = 0.5; px < 10; px += 1.0)
    for (double py = 0.5; py < 10; py += 1.0) {
      const double c[3] = {px, py, 3.5}, dx = px == 4.5 && py == 4.5 ? -1 : 1; /* P's and Q's */
      const double keep[6][3] = {{px + 1, py, 3.5}, {px - 1, py, 3.5}, {px, py + 1, 3.5},
                                 {px, py - 1, 3.5}, {px, py, 2.5}, {px + dx, py, 2.5}};
      const int pq = py == 4.5 && (px == 4.5 || px == 5.5); /* their diagonals kept for later */
      keep_only(&w, x, c, keep, pq ? 6 : 5, words);
      if (px == 0.5 || px == 9.5 || py == 0.5 || py == 9.5) held[node_at(x, w.n, px, py, 3.5)] = 1;
    }
  CUPID_ASSERT_OK(cupid_pd_operator_unpack_broken(w.op, 0, w.n, words, u, &fo, &added, &dissipated));
  cupid_pd_operator_lost_shares(w.op, 0, w.n, f);
  for (cupid_int i = 0; i < w.n; i++) band += f[i] >= 0.5;
  assert_int_equal(band, 100); /* the layer, and no node below it */
  memcpy(release, held, (size_t)w.n);
  CUPID_ASSERT_OK(cupid_pd_operator_weakly_held(w.op, 0, w.n, release, &count));
  assert_int_equal(count, 0);
  CUPID_ASSERT_OK(cupid_pd_operator_mechanisms(w.op, 0, w.n, NULL, NULL, release, &count));
  assert_int_equal(count, 0); /* every node's ball */
  CUPID_ASSERT_OK(cupid_pd_operator_mechanisms(w.op, 0, w.n, NULL, seen, release, &count));
  assert_int_equal(count, 0);
  for (cupid_int i = 0; i < w.n; i++) assert_true(seen[i] == (held[i] ? 0.0 : f[i])); /* kept */
  const cupid_int iP = node_at(x, w.n, 4.5, 4.5, 3.5), iQ = node_at(x, w.n, 5.5, 4.5, 3.5);
  const double P[3] = {4.5, 4.5, 3.5}, Q[3] = {5.5, 4.5, 3.5};
  const double keepP[3][3] = {{5.5, 4.5, 3.5}, {4.5, 5.5, 3.5}, {3.5, 4.5, 2.5}};
  const double keepQ[3][3] = {{4.5, 4.5, 3.5}, {5.5, 3.5, 3.5}, {6.5, 4.5, 2.5}};
  memset(words, 0, (size_t)w.n * nw * sizeof *words);
  keep_only(&w, x, P, keepP, 3, words);
  keep_only(&w, x, Q, keepQ, 3, words);
  CUPID_ASSERT_OK(cupid_pd_operator_unpack_broken(w.op, 0, w.n, words, u, &fo, &added, &dissipated));
  assert_int_equal(added, 6); /* P: -x, -y, down; Q: +x, +y, down */
  CUPID_ASSERT_OK(cupid_pd_operator_weakly_held(w.op, 0, w.n, release, &count));
  assert_int_equal(count, 0); /* each held by its own bonds */
  u[3 * iP] = u[3 * iQ] = 1.0, u[3 * iP + 2] = -1.0, u[3 * iQ + 2] = 1.0; /* the pair's mode */
  CUPID_ASSERT_OK(cupid_pd_operator_apply(w.op, u, f));
  double fmax = 0.0, fref = 0.0;
  for (cupid_int k = 0; k < 3 * w.n; k++) fmax = fmax > fabs(f[k]) ? fmax : fabs(f[k]);
  u[3 * iP + 2] = 1.0; /* not the mode: the bonds resist */
  CUPID_ASSERT_OK(cupid_pd_operator_apply(w.op, u, f));
  for (cupid_int k = 0; k < 3 * w.n; k++) fref = fref > fabs(f[k]) ? fref : fabs(f[k]);
  assert_true(fref > 0.0 && fmax <= 1e-12 * fref);
  CUPID_ASSERT_OK(cupid_pd_operator_mechanisms(w.op, 0, w.n, NULL, seen, release, &count));
  assert_int_equal(count, 1);
  for (cupid_int i = 0; i < w.n; i++)
    assert_int_equal(release[i], held[i] ? 1 : i == iQ ? 2 : 0); /* the later of the pair */
  memcpy(release, held, (size_t)w.n); /* nothing lost a bond since: no ball, nothing found */
  CUPID_ASSERT_OK(cupid_pd_operator_mechanisms(w.op, 0, w.n, NULL, seen, release, &count));
  assert_int_equal(count, 0);
  CUPID_ASSERT_OK(cupid_pd_operator_mechanisms(w.op, 0, w.n, NULL, NULL, release, &count));
  assert_int_equal(count, 1); /* every node's ball: found once */
  assert_int_equal(release[iQ], 2);
  free(words), free(u), free(f), free(seen), free(release), free(held);
  destroy(&w);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_precrack_count),     cmocka_unit_test(test_cracked_operator),
      cmocka_unit_test(test_cracked_uniform),    cmocka_unit_test(test_corrected_lps_refused),
      cmocka_unit_test(test_patched_rows),        cmocka_unit_test(test_corrected_cut),
      cmocka_unit_test(test_stretch_threshold),  cmocka_unit_test(test_protect_damage_energy),
      cmocka_unit_test(test_threads),            cmocka_unit_test(test_isolated_node),
      cmocka_unit_test(test_copy_broken),        cmocka_unit_test(test_scan_paths),
      cmocka_unit_test(test_support),            cmocka_unit_test(test_mechanism),
      cmocka_unit_test(test_mechanism_in_band),  cmocka_unit_test(test_protected_ratios),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
