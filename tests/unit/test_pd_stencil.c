/* The stencil kernels of the matrix-free PD operator (src/pd/stencil.c, the default path)
 * against the bond-list kernels (lps.c, bond.c on explicit bond lists, the former path) on
 * random fields: boxes, a union of boxes with a re-entrant corner and a hole, two
 * materials, a row longer than one run, a grid too thin for any full family, a horizon of
 * two pair chunks, a 1D bar;
 * LPS and bond-based, three influence / partial-volume combinations; whole products and
 * row ranges; every instruction-set instance of the kernels. Also the storage: no bond
 * stored for full families; the pair plan; the ghost-bond records and their sharing. */
#include <math.h>
#include <string.h>

#include "pd/pd_internal.h"
#include "testutil.h"

typedef struct {
  const char *name;
  int n_boxes;
  cupid_box boxes[3];
  int mats[3];
  int dim;
  double horizon;
} grid_case;

static double max_abs(cupid_int n, const double *x) {
  double m = 0.0;
  for (cupid_int i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
  return m;
}

/* The runs' stretches of uniform b (pd_run ub0, ub1; uniform.c): every node in one has its
 * whole family, each neighbour with the node's own b to the bit (as the work arrays hold it:
 * mu / m); with `some`, the grid has such nodes. */
static void check_uniform(const struct cupid_pd_operator_private *op, int some) {
  cupid_int total = 0;
  for (cupid_int r = 0; r < op->nruns; r++) {
    const pd_run *R = &op->runs[r];
    assert_true(R->ub0 >= 0 && R->ub0 <= R->ub1 && R->ub1 <= R->len);
    for (cupid_int i = R->i0 + R->ub0; i < R->i0 + R->ub1; i++) {
      assert_true(op->full[i]);
      const double bi = op->mu[i] / op->m[i];
      const pd_family F = pd_family_of(op, i);
      for (int s = 0; s < op->st.n; s++) {
        const cupid_int j = pd_family_node(op, &F, s);
        assert_true(j >= 0);
        assert_true(op->mu[j] / op->m[j] == bi);
      }
    }
    total += R->ub1 - R->ub0;
  }
  if (some) assert_true(total > 0);
}

/* Stencil f against bond-list f of the same operator, whole and by ranges. */
static void compare(const grid_case *gc, cupid_pd_model_kind model, cupid_influence infl,
                    cupid_partial_volume pv) {
  cupid_pd_grid_options go = {.spacing = 0.5, .dimension = gc->dim, .area = 0.3};
  cupid_pd_grid grid = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, gc->n_boxes, gc->boxes, gc->mats, &grid));
  const cupid_pd_material pm[2] = {{.E = 1000.0, .nu = 0.3}, {.E = 270.0, .nu = 0.22}};
  cupid_pd_operator_options oo = {.horizon = gc->horizon * go.spacing, .model = model,
                                  .influence = infl, .partial_volume = pv, .materials = pm,
                                  .n_materials = 2};
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(grid, &oo, &op));
  const cupid_int n = cupid_pd_grid_num_nodes(grid);
  /* No per-bond storage for full families: only the near-surface ones are listed. */
  cupid_int listed = op->fptr[n], full_bonds = 0;
  for (cupid_int i = 0; i < n; i++) full_bonds += op->full[i] ? op->st.n : 0;
  assert_int_equal(listed + full_bonds, cupid_pd_operator_num_bonds(op));
  double *u = NULL, *f = NULL, *g = NULL;
  CUPID_ASSERT_OK(cupid_malloc(3 * (size_t)n, sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_malloc(3 * (size_t)n, sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_malloc(3 * (size_t)n, sizeof *g, "g", &g));
  uint64_t seed = 11 + (uint64_t)model;
  for (cupid_int i = 0; i < 3 * n; i++) u[i] = cupid_test_random(&seed) - 0.5;
  check_uniform(op, strncmp(gc->name, "deep", 4) == 0 && model == CUPID_PD_LPS);
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, u, f)); /* stencil (default) */
  assert_int_equal(op->stencil_off, 0);
  CUPID_ASSERT_OK(pd_operator_use_bond_lists(op));
  assert_int_equal(op->bptr[n], cupid_pd_operator_num_bonds(op));
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, u, g)); /* bond lists */
  /* Same sums in the same bond order, other rounding (precomputed omega beta xi, FMA):
   * round-off, 1e-13 of max |f| (the terms are O(max |f| / family)). */
  const double fmax = max_abs(3 * n, g);
  assert_true(fmax > 0);
  for (cupid_int i = 0; i < 3 * n; i++) ASSERT_NEAR(f[i], g[i], 1e-13 * fmax);
  /* Row ranges on the stencil path, u poisoned outside the dependency range. */
  op->stencil_off = 0;
  const cupid_int ranges[3][2] = {{0, n / 3}, {n / 3 + 1, n}, {n / 5, n / 5 + n / 4 + 3}};
  double *v = NULL;
  CUPID_ASSERT_OK(cupid_malloc(3 * (size_t)n, sizeof *v, "v", &v));
  for (int r = 0; r < 3; r++) {
    const cupid_int a = ranges[r][0], b = ranges[r][1];
    cupid_int lo, hi;
    CUPID_ASSERT_OK(cupid_pd_operator_dependency_range(op, a, b, &lo, &hi));
    for (cupid_int i = 0; i < 3 * n; i++) v[i] = (i >= 3 * lo && i < 3 * hi) ? u[i] : NAN;
    CUPID_ASSERT_OK(cupid_pd_operator_apply_range(op, a, b, v, g));
    /* The same arithmetic as the whole product: 1e-14 of max |f|. */
    for (cupid_int i = 0; i < 3 * (b - a); i++) ASSERT_NEAR(g[i], f[3 * a + i], 1e-14 * fmax);
  }
  /* A large rigid translation plus a small strain: K ignores the translation, and both
   * paths must too (the stencil path corrects its ghost bonds with terms of size |u|;
   * it shifts u first, so the result stays within round-off of the small forces). */
  const double *x = cupid_pd_grid_coords(grid);
  for (cupid_int i = 0; i < n; i++)
    for (int c = 0; c < 3; c++)
      v[3 * i + c] = 1e4 * (c + 1) + 1e-3 * (1 + c) * x[3 * i + c] + 1e-4 * sin(x[3 * i] + 2 * c);
  op->stencil_off = 1;
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, v, g));
  op->stencil_off = 0;
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, v, f));
  const double gmax = max_abs(3 * n, g);
  for (cupid_int i = 0; i < 3 * n; i++) ASSERT_NEAR(f[i], g[i], 1e-13 * gmax);
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, u, f));
  /* The kept work arrays after the poisoned ranges: the whole product again, twice (the
   * second reuses the zeroed window). */
  for (int rep = 0; rep < 2; rep++) {
    CUPID_ASSERT_OK(cupid_pd_operator_apply(op, u, g));
    for (cupid_int i = 0; i < 3 * n; i++) ASSERT_NEAR(g[i], f[i], 1e-14 * fmax);
  }
  cupid_free(&u);
  cupid_free(&f);
  cupid_free(&g);
  cupid_free(&v);
  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&grid);
}

#define BOX(x0, y0, z0, x1, y1, z1) {{x0, y0, z0}, {x1, y1, z1}, {1, 1, 1}}

static const grid_case cases[] = {
    /* 14 x 12 x 16 nodes: a bulk of 8 x 6 x 10 full nodes at m = 3. */
    {"box", 1, {BOX(0, 0, 0, 7, 6, 8)}, {0}, 3, 3.015},
    /* L-shaped union with a second material, plus a detached block (its own runs). */
    {"union", 3, {BOX(0, 0, 0, 8, 4, 4), BOX(0, 4, 0, 4, 8, 4), BOX(5.5, 5, 0, 8, 8, 3)},
     {0, 1, 0}, 3, 2.5},
    /* 300-node rows: interior rows longer than PD_RUN_MAX are split. */
    {"long", 1, {BOX(0, 0, 0, 150, 3.5, 3.5)}, {0}, 3, 3.015},
    /* Too thin for a full family anywhere: everything on the near-surface path. */
    {"thin", 1, {BOX(0, 0, 0, 5, 5, 1.5)}, {0}, 3, 3.015},
    /* Sparse union (two blocks far apart): no padded lattice, families walked instead. */
    {"sparse", 2, {BOX(0, 0, 0, 5, 4, 4), BOX(40, 30, 20, 44, 34, 24)}, {0, 1}, 3, 3.015},
    /* m = 4: 128 pairs, two chunks of the pair plan. */
    {"wide", 1, {BOX(0, 0, 0, 6, 5.5, 5)}, {0}, 3, 4.015},
    /* 30 x 13 x 13 nodes: lane blocks of uniform b (pd_run ub0, ub1) in the middle rows. */
    {"deep", 1, {BOX(0, 0, 0, 15, 6.5, 6.5)}, {0}, 3, 3.015},
    /* 34 x 17 x 17 nodes at m = 4: uniform blocks over two pair chunks. */
    {"deep wide", 1, {BOX(0, 0, 0, 17, 8.5, 8.5)}, {0}, 3, 4.015},
};

static void test_lps(void **state) {
  (void)state;
  for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
    compare(&cases[c], CUPID_PD_LPS, CUPID_INFLUENCE_INVERSE, CUPID_PARTIAL_PDLAMMPS);
    compare(&cases[c], CUPID_PD_LPS, CUPID_INFLUENCE_GAUSSIAN, CUPID_PARTIAL_EXACT);
  }
}

static void test_bond(void **state) {
  (void)state;
  for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
    compare(&cases[c], CUPID_PD_BOND, CUPID_INFLUENCE_CONSTANT, CUPID_PARTIAL_NONE);
    compare(&cases[c], CUPID_PD_BOND, CUPID_INFLUENCE_GAUSSIAN, CUPID_PARTIAL_PDLAMMPS);
  }
}

static void test_bar(void **state) {
  (void)state;
  const grid_case bar = {"bar", 2, {BOX(0, 0, 0, 0, 40, 0), BOX(0, 40, 0, 0, 90, 0)}, {0, 1}, 1, 3.015};
  compare(&bar, CUPID_PD_BOND, CUPID_INFLUENCE_CONSTANT, CUPID_PARTIAL_EXACT);
}

/* Every instruction-set instance of the kernels the CPU can run (AVX-512: 8 lanes, AVX2: 4,
 * baseline: 2), each against the bond lists: the lane blocks that overhang a run's end,
 * the runs shorter than a block ("thin", the union's short rows) and the tabled pair
 * offsets are the instance's own code. */
static void test_instances(void **state) {
  (void)state;
  const int levels[3] = {1, 3, 4};
  int seen = 0; /* lanes already checked: a level the CPU lacks falls back to one of them */
  for (int l = 0; l < 3; l++) {
    const int lanes = pd_stencil_force_isa(levels[l]);
    print_message("kernel instance %d: %d lanes%s\n", levels[l], lanes,
                  seen & lanes ? " (checked above)" : "");
    assert_true(lanes == 2 || lanes == 4 || lanes == 8);
    if (seen & lanes) continue;
    seen |= lanes;
    for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
      compare(&cases[c], CUPID_PD_LPS, CUPID_INFLUENCE_INVERSE, CUPID_PARTIAL_PDLAMMPS);
      compare(&cases[c], CUPID_PD_BOND, CUPID_INFLUENCE_GAUSSIAN, CUPID_PARTIAL_PDLAMMPS);
    }
  }
  pd_stencil_force_isa(0);
}

/* The pair plan (pd_pair_plan): every pair s < n/2 once, in its own chunk, grouped by class
 * (the components the class skips are zero, the others not), the padded offsets and
 * weights of its stencil entry, the sign of n folded into w1 on an axis. */
static void check_plan(const struct cupid_pd_operator_private *op) {
  const pd_stencil *S = &op->st;
  const pd_pair_plan *P = &op->plan;
  static const int uses[PD_PAIR_CLASSES][3] = {{1, 1, 1}, {0, 1, 1}, {1, 0, 1}, {1, 1, 0},
                                               {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  assert_int_equal(P->n, S->n / 2);
  int seen[1024] = {0};
  assert_true(P->n <= 1024);
  for (int c = 0; c * PD_PAIR_CHUNK < P->n; c++) {
    const int *sg = P->seg + c * (PD_PAIR_CLASSES + 1);
    assert_int_equal(sg[0], c * PD_PAIR_CHUNK);
    assert_int_equal(sg[PD_PAIR_CLASSES], c * PD_PAIR_CHUNK + PD_PAIR_CHUNK < P->n
                                              ? c * PD_PAIR_CHUNK + PD_PAIR_CHUNK : P->n);
    for (int q = 0; q < PD_PAIR_CLASSES; q++)
      for (int k = sg[q]; k < sg[q + 1]; k++) {
        const int s = P->s[k];
        assert_true(s >= c * PD_PAIR_CHUNK && s < c * PD_PAIR_CHUNK + PD_PAIR_CHUNK && s < P->n);
        seen[s]++;
        int axis_sign = 0;
        for (int a = 0; a < 3; a++) {
          assert_int_equal(S->off[3 * s + a] != 0, uses[q][a]);
          assert_true(P->nrm[3 * k + a] == S->nrm[3 * s + a]);
          assert_true(P->wxn[3 * k + a] == S->wxn[3 * s + a]);
          if (uses[q][a]) axis_sign = S->off[3 * s + a] > 0 ? 1 : -1;
        }
        const double w1 = S->wb[s] * S->x[s];
        assert_true(P->w1[k] == (q >= 4 ? axis_sign * w1 : w1));
        for (int a = 0; a < 3; a++)
          assert_true(P->nw[3 * k + a] == 15.0 * S->wb[s] * S->nrm[3 * s + a] * (q >= 4 ? axis_sign : 1));
        assert_int_equal(P->pp[k], op->pclin[s]);
        assert_int_equal(P->pm[k], op->pclin[S->n - 1 - s]);
      }
  }
  for (int s = 0; s < P->n; s++) assert_int_equal(seen[s], 1);
}

/* fn on the LPS operator (influence 1/|xi|, PDLAMMPS volumes) of every case. */
static void each_case(void (*fn)(const struct cupid_pd_operator_private *op, size_t c)) {
  for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
    cupid_pd_grid_options go = {.spacing = 0.5, .dimension = cases[c].dim, .area = 0.3};
    cupid_pd_grid grid = NULL;
    CUPID_ASSERT_OK(cupid_pd_grid_create(&go, cases[c].n_boxes, cases[c].boxes, cases[c].mats, &grid));
    const cupid_pd_material pm[2] = {{.E = 1.0, .nu = 0.25}, {.E = 2.0, .nu = 0.25}};
    cupid_pd_operator_options oo = {.horizon = cases[c].horizon * go.spacing, .model = CUPID_PD_LPS,
                                    .influence = CUPID_INFLUENCE_INVERSE,
                                    .partial_volume = CUPID_PARTIAL_PDLAMMPS, .materials = pm,
                                    .n_materials = 2};
    cupid_pd_operator op = NULL;
    CUPID_ASSERT_OK(cupid_pd_operator_create(grid, &oo, &op));
    fn(op, c);
    cupid_pd_operator_destroy(&op);
    cupid_pd_grid_destroy(&grid);
  }
}

static void plan_case(const struct cupid_pd_operator_private *op, size_t c) {
  (void)c;
  check_plan(op);
}

static void test_pair_plan(void **state) {
  (void)state;
  each_case(plan_case);
}

/* The ghost-bond records (ghosts.c): each run's segments are exactly its runs of non-full
 * nodes, in order; every node's record, read where the kernels read it (the segment's
 * shared records), is the sum over its own family (C_i over the absent entries, G_i =
 * gself over the present ones); and on the box, whose rows of a kind share their
 * segments, the shared records are a small fraction of the near-surface nodes. */
static void check_ghosts(const struct cupid_pd_operator_private *op, int box) {
  const pd_stencil *S = &op->st;
  const double *C = op->ncorr + PD_GHOST_SLACK;
  cupid_int nonfull = 0;
  for (cupid_int r = 0; r < op->nruns; r++) {
    const pd_run *R = &op->runs[r];
    cupid_int k = op->gptr[r];
    for (cupid_int i = R->i0; i < R->i0 + R->len; i++) {
      if (op->full[i]) continue;
      nonfull++;
      while (k < op->gptr[r + 1] && op->gseg[k].i0 + op->gseg[k].n <= i) k++;
      assert_true(k < op->gptr[r + 1]);
      const pd_ghost_seg *g = &op->gseg[k];
      assert_true(g->i0 <= i && (i == g->i0 || !op->full[i - 1]));
      const cupid_int q = g->rank + (i - g->i0);
      assert_true(q >= 0 && q + PD_GHOST_SLACK <= op->gstride);
      const pd_family F = pd_family_of(op, i);
      double want[PD_GHOST_STRIDE] = {0}, scale = 0.0;
      for (int s = 0, p = 0; s < S->n; s++) {
        const double *n = S->nrm + 3 * s, w = 15.0 * S->wb[s];
        if (p < F.n && F.s[p] == s) {
          p++;
          for (int c = 0; c < 3; c++) want[6 + c] += S->wxn[3 * s + c];
          continue;
        }
        const int ab[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};
        for (int c = 0; c < 6; c++) want[c] += w * n[ab[c][0]] * n[ab[c][1]];
      }
      for (int c = 0; c < PD_GHOST_STRIDE; c++) scale = fmax(scale, fabs(want[c]));
      for (int c = 0; c < 3; c++) ASSERT_NEAR(want[6 + c], op->gself[3 * i + c], 1e-14 * scale);
      for (int c = 0; c < PD_GHOST_STRIDE; c++)
        ASSERT_NEAR(C[c * op->gstride + q], want[c], 1e-14 * scale);
    }
    for (cupid_int j = op->gptr[r]; j < op->gptr[r + 1]; j++) { /* maximal, inside the run */
      const pd_ghost_seg *g = &op->gseg[j];
      assert_true(g->n >= 1 && g->i0 >= R->i0 && g->i0 + g->n <= R->i0 + R->len);
      assert_true(g->i0 == R->i0 || op->full[g->i0 - 1]);
      assert_true(g->i0 + g->n == R->i0 + R->len || op->full[g->i0 + g->n]);
      for (cupid_int i = g->i0; i < g->i0 + g->n; i++) assert_false(op->full[i]);
    }
  }
  assert_int_equal(op->gptr[op->nruns], op->nseg);
  const cupid_int shared = op->gstride - PD_GHOST_SLACK;
  print_message("ghost records: %lld near-surface nodes, %lld segments, %lld records\n",
                (long long)nonfull, (long long)op->nseg, (long long)shared);
  assert_true(shared <= nonfull);
  if (box) assert_true(3 * shared < nonfull); /* 678 of 2208 */
}

static void ghosts_case(const struct cupid_pd_operator_private *op, size_t c) {
  check_ghosts(op, c == 0);
}

static void test_ghosts(void **state) {
  (void)state;
  each_case(ghosts_case);
}

/* The runs cover every node once, in order, at consecutive (padded) cells with one full
 * flag each; the union is dense enough for the padded lattice, a sparse one is not. */
static void test_partition(void **state) {
  (void)state;
  cupid_pd_grid_options go = {.spacing = 0.5, .dimension = 3};
  const cupid_pd_material pm[2] = {{.E = 1.0, .nu = 0.25}, {.E = 2.0, .nu = 0.25}};
  cupid_pd_operator_options oo = {.horizon = 1.5, .model = CUPID_PD_LPS,
                                  .influence = CUPID_INFLUENCE_INVERSE,
                                  .partial_volume = CUPID_PARTIAL_PDLAMMPS, .materials = pm,
                                  .n_materials = 2};
  for (int c = 1; c < 5; c += 3) {
    cupid_pd_grid grid = NULL;
    CUPID_ASSERT_OK(cupid_pd_grid_create(&go, cases[c].n_boxes, cases[c].boxes, cases[c].mats, &grid));
    cupid_pd_operator op = NULL;
    CUPID_ASSERT_OK(cupid_pd_operator_create(grid, &oo, &op));
    assert_int_equal(op->padded, c == 1);
    const cupid_int n = cupid_pd_grid_num_nodes(grid);
    cupid_int next = 0, nfull = 0;
    for (cupid_int r = 0; r < op->nruns; r++) {
      const pd_run *R = &op->runs[r];
      assert_true(R->len >= 1 && R->len <= PD_RUN_MAX);
      assert_int_equal(R->i0, next);
      int all = 1;
      for (int t = 0; t < R->len; t++) {
        all &= op->full[R->i0 + t];
        if (!op->padded) assert_int_equal(op->full[R->i0 + t], R->full);
        assert_int_equal(pd_node_cell(op->grid, R->i0 + t), R->c0 + t);
        assert_int_equal(pd_node_pcell(op, R->i0 + t), R->cp0 + t);
      }
      assert_int_equal(all, R->full);
      next += R->len;
      nfull += R->full ? R->len : 0;
    }
    assert_int_equal(next, n);
    assert_true(nfull < n);
    /* The families: a full node has every stencil neighbour, a listed one exactly the
     * entries whose cell holds a node, ascending. */
    for (cupid_int i = 0; i < n; i++) {
      const int32_t *q = op->grid->ijk + 3 * i;
      cupid_int k = op->fptr[i];
      for (int s = 0; s < op->st.n; s++) {
        const int32_t *o = op->st.off + 3 * s;
        const int exists = pd_grid_lookup(op->grid, q[0] + o[0], q[1] + o[1], q[2] + o[2]) >= 0;
        if (op->full[i]) {
          assert_true(exists);
          continue;
        }
        if (!exists) continue;
        assert_true(k < op->fptr[i + 1]);
        assert_int_equal(op->fidx[k++], s);
      }
      assert_int_equal(k, op->fptr[i + 1]);
    }
    cupid_pd_operator_destroy(&op);
    cupid_pd_grid_destroy(&grid);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_lps), cmocka_unit_test(test_bond),
                                     cmocka_unit_test(test_bar), cmocka_unit_test(test_instances),
                                     cmocka_unit_test(test_partition),
                                     cmocka_unit_test(test_pair_plan),
                                     cmocka_unit_test(test_ghosts)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
