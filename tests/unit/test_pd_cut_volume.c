/* Cut-cell volumes (issue 35, `partial_volume: exact` on shaped bodies; src/pd/cut_volume.c)
 * and the PD operator with per-node volumes (pd_phi in src/pd). Checks:
 *  - the nodes' volumes sum to the body's: spheres of radius 3 h and 5 h at four offsets from
 *    the lattice (issue 35: within 0.5%; the integration is second order, measured 1e-5),
 *    cylinders along x, y, z with ends off the lattice (pi r^2 L), a plate less a cylindrical
 *    hole, a box less an off-lattice box hole and a sphere hole (exact volumes; tolerance
 *    1e-3: the midpoint rule across the curved surfaces);
 *  - every fraction is positive, the deep nodes' exactly 1, and a body of boxes on the lattice
 *    has none (NULL: the stencil kernels stay on);
 *  - two slabs give every owned node the volume the whole grid gives it (1e-14);
 *  - the operator on a sphere with cut cells (LPS and bond-based, with and without the surface
 *    correction, and after a pre-crack):
 *    . a uniform expansion u = eps x has theta_i = 3 eps at every node, cut ones included
 *      (theta's sum and m_i weigh the neighbours' volumes alike; 1e-12);
 *    . K u from the bond-list kernels equals the assembled K times u (1e-12 of |K||u|), and
 *      u.K u / 2 equals the energy walked over the families (1e-12), K is symmetric (1e-13),
 *      rigid translations and rotations give no force (1e-12), the diagonal blocks equal K's
 *      (1e-13) and the row bound is >= every block row of K;
 *    . all volumes scaled by c scale the LPS K by c (V phi_i W_i with m_i and theta_i
 *      unchanged) and the bond-based K by c^2 (its micromodulus is the bulk's, no m_i divides
 *      the neighbours' volumes; by c with the surface correction, whose factors fit the sums
 *      to the bulk's targets); 1e-12: a kernel that missed phi_i or phi_j in a term fails;
 *    . K differs from the whole-cell operator's by more than 1e-3 (the volumes are used). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cupid/model.h"
#include "cupid/pd.h"
#include "pd/pd_internal.h"
#include "test_shapes.h"
#include "testutil.h"

static cupid_pd_grid make(const cupid_shape *shapes, int n, const cupid_shape *holes, int nh,
                          double h, int parts, int part) {
  cupid_box boxes[4];
  int mats[4];
  for (int b = 0; b < n; b++) boxes[b] = shapes[b].box, mats[b] = 0;
  cupid_pd_grid_options o = {.spacing = h, .dimension = 3, .parts = parts, .part = part,
                             .halo_layers = parts > 1 ? 3 : 0, .shapes = shapes, .n_holes = nh,
                             .holes = holes, .cut_volumes = 1};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&o, n, boxes, mats, &g));
  return g;
}

/* The nodes' volumes summed; checks every fraction positive and below 2 on the way. */
static double total_volume(cupid_pd_grid g) {
  double v = 0.0;
  const double *phi = cupid_pd_grid_volume_fractions(g);
  for (cupid_int i = 0; i < cupid_pd_grid_num_nodes(g); i++) {
    if (phi) assert_true(phi[i] > 0 && phi[i] < 2.0);
    v += cupid_pd_grid_node_volume(g, i);
  }
  return v;
}

static void check_volume(const char *what, cupid_pd_grid g, double exact, double tol) {
  const double v = total_volume(g), cells = (double)cupid_pd_grid_num_nodes(g) * cupid_pd_grid_cell_volume(g);
  printf("  %-44s cut cells %+.2e, whole cells %+.2e\n", what, v / exact - 1, cells / exact - 1);
  assert_true(cupid_pd_grid_volume_fractions(g) != NULL);
  assert_true(fabs(v / exact - 1) <= tol);
  assert_true(cupid_pd_grid_unassigned_volume(g) == 0.0);
}

static void body_volumes(void **state) {
  (void)state;
  const double pi = acos(-1.0);
  const double offsets[4][3] = {{0, 0, 0}, {0.5, 0.5, 0.5}, {0.31, 0.77, 0.13}, {0.9, 0.05, 0.47}};
  char what[96];
  for (int r = 3; r <= 5; r += 2)
    for (int q = 0; q < 4; q++) {
      cupid_shape s = sphere(10 + offsets[q][0], 20 + offsets[q][1], 30 + offsets[q][2], r);
      cupid_pd_grid g = make(&s, 1, NULL, 0, 1.0, 1, 0);
      snprintf(what, sizeof what, "sphere r = %d h, offset (%.2f %.2f %.2f):", r, offsets[q][0],
               offsets[q][1], offsets[q][2]);
      check_volume(what, g, 4.0 / 3.0 * pi * r * r * r, 5e-3);
      /* the deep nodes keep their cells */
      const double *x = cupid_pd_grid_coords(g), *phi = cupid_pd_grid_volume_fractions(g);
      for (cupid_int i = 0; i < cupid_pd_grid_num_nodes(g); i++) {
        const double d = sqrt(pow(x[3 * i] - s.center[0], 2) + pow(x[3 * i + 1] - s.center[1], 2) +
                              pow(x[3 * i + 2] - s.center[2], 2));
        if (d < r - 2.0) assert_true(phi[i] == 1.0);
      }
      cupid_pd_grid_destroy(&g);
    }
  for (int axis = 0; axis < 3; axis++) {
    cupid_shape c = cylinder(axis, 4.3, 5.1, 3.6, 0.25, 11.6);
    cupid_pd_grid g = make(&c, 1, NULL, 0, 1.0, 1, 0);
    snprintf(what, sizeof what, "cylinder along %c, r = 3.6 h, L = 11.35 h:", "xyz"[axis]);
    check_volume(what, g, pi * 3.6 * 3.6 * 11.35, 1);
    cupid_pd_grid_destroy(&g);
  }
  cupid_shape plate = box(0, 40, 0, 40, 0, 3), hole = cylinder(2, 20.2, 19.7, 7.3, 1, 0);
  cupid_pd_grid g = make(&plate, 1, &hole, 1, 1.0, 1, 0);
  check_volume("plate less a hole r = 7.3 h:", g, 40.0 * 40.0 * 3.0 - pi * 7.3 * 7.3 * 3.0, 1);
  cupid_pd_grid_destroy(&g);
  cupid_shape holes[2] = {box(2.5, 6.25, 1.5, 4.75, -1, 20), sphere(12.0, 7.3, 4.1, 2.5)};
  cupid_shape body = box(0, 16, 0, 10, 0, 8);
  g = make(&body, 1, holes, 2, 1.0, 1, 0);
  check_volume("box less a box and a sphere:", g,
               16.0 * 10 * 8 - 3.75 * 3.25 * 8 - 4.0 / 3.0 * pi * pow(2.5, 3), 1e-3);
  cupid_pd_grid_destroy(&g);
  /* holes on the lattice cut nothing: whole cells, no fractions */
  cupid_shape on = box(2, 6, 1, 4, -1, 20);
  g = make(&body, 1, &on, 1, 1.0, 1, 0);
  assert_null(cupid_pd_grid_volume_fractions(g));
  ASSERT_NEAR(total_volume(g), 16.0 * 10 * 8 - 4.0 * 3 * 8, 1e-9);
  cupid_pd_grid_destroy(&g);
}

/* Two slabs of a sphere with a hole: each owned node has the whole grid's volume. */
static void slabs(void **state) {
  (void)state;
  cupid_shape s = sphere(0.2, 0.4, 0.3, 6.2), hole = cylinder(0, 0.7, 0.1, 2.2, 1, 0);
  cupid_pd_grid whole = make(&s, 1, &hole, 1, 1.0, 1, 0);
  const double *pw = cupid_pd_grid_volume_fractions(whole);
  assert_non_null(pw);
  double sum = 0.0;
  for (int part = 0; part < 2; part++) {
    cupid_pd_grid g = make(&s, 1, &hole, 1, 1.0, 2, part);
    cupid_pd_grid_partition pa;
    cupid_pd_grid_get_partition(g, &pa);
    const double *p = cupid_pd_grid_volume_fractions(g);
    assert_non_null(p);
    for (cupid_int i = 0; i < cupid_pd_grid_num_nodes(g); i++) { /* halo nodes too */
      const cupid_int k = pa.first_global + i;
      assert_true(fabs(p[i] - pw[k]) <= 1e-14);
      if (i >= pa.owned_first && i < pa.owned_last) sum += cupid_pd_grid_node_volume(g, i);
    }
    cupid_pd_grid_destroy(&g);
  }
  ASSERT_NEAR(sum, total_volume(whole), 1e-9);
  cupid_pd_grid_destroy(&whole);
}

/* y = K u by the assembled matrix. */
static void csr_apply(const cupid_csr_t *K, const double *u, double *y) {
  for (cupid_int r = 0; r < K->nrows; r++) {
    double a[3] = {0, 0, 0};
    for (cupid_int q = K->rowptr[r]; q < K->rowptr[r + 1]; q++) {
      const double *B = K->val + 9 * q, *x = u + 3 * K->col[q];
      for (int i = 0; i < 3; i++) a[i] += B[3 * i] * x[0] + B[3 * i + 1] * x[1] + B[3 * i + 2] * x[2];
    }
    for (int i = 0; i < 3; i++) y[3 * r + i] = a[i];
  }
}

static double norm(const double *v, cupid_int n) {
  double s = 0.0;
  for (cupid_int i = 0; i < n; i++) s += v[i] * v[i];
  return sqrt(s);
}

/* max |K_ij - K_ji^T| over K's blocks, and max |K|. */
static void asymmetry(const cupid_csr_t *K, double *asym, double *kmax) {
  *asym = *kmax = 0.0;
  for (cupid_int r = 0; r < K->nrows; r++)
    for (cupid_int q = K->rowptr[r]; q < K->rowptr[r + 1]; q++) {
      const cupid_int c = K->col[q];
      cupid_int t = K->rowptr[c];
      while (t < K->rowptr[c + 1] && K->col[t] != r) t++;
      assert_true(t < K->rowptr[c + 1]);
      for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
          *asym = fmax(*asym, fabs(K->val[9 * q + 3 * a + b] - K->val[9 * t + 3 * b + a]));
          *kmax = fmax(*kmax, fabs(K->val[9 * q + 3 * a + b]));
        }
    }
}

static void operator_checks(cupid_pd_grid g, cupid_pd_operator_options *o, int crack) {
  const cupid_int n = cupid_pd_grid_num_nodes(g), nd = 3 * n;
  const double *x = cupid_pd_grid_coords(g);
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(g, o, &op));
  assert_true(op->phi != NULL && op->stencil_off);
  if (crack) {
    cupid_pd_precrack c = {.normal = 1, .at = 20.0, .lo = {-100, 0, -100}, .hi = {21.0, 0, 100}};
    cupid_int removed = 0;
    CUPID_ASSERT_OK(cupid_pd_operator_precrack(op, &c, &removed));
    assert_true(removed > 0);
  }
  double *u = malloc(sizeof(double) * nd), *f = malloc(sizeof(double) * nd),
         *y = malloc(sizeof(double) * nd), *th = malloc(sizeof(double) * n);
  /* a uniform expansion: theta = 3 eps everywhere (LPS) */
  if (o->model == CUPID_PD_LPS && !o->surface_correction) {
    for (cupid_int i = 0; i < nd; i++) u[i] = 1e-3 * x[i];
    CUPID_ASSERT_OK(cupid_pd_operator_dilatation(op, u, th));
    for (cupid_int i = 0; i < n; i++) ASSERT_NEAR(th[i], 3e-3, 3e-15);
  }
  srand(7);
  for (cupid_int i = 0; i < nd; i++) u[i] = (double)rand() / RAND_MAX - 0.5;
  cupid_csr K = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_assemble(op, &K));
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, u, f));
  csr_apply(K, u, y);
  double kmax, asym, d = 0.0, uKu = 0.0, E = 0.0;
  asymmetry(K, &asym, &kmax);
  for (cupid_int i = 0; i < nd; i++) d = fmax(d, fabs(f[i] - y[i])), uKu += u[i] * f[i];
  CUPID_ASSERT_OK(cupid_pd_operator_energy(op, u, &E));
  printf("    %s%s%s: |Ku - K_asm u| %.1e, |E - uKu/2| %.1e, asym %.1e (of |K| %.2e)\n",
         o->model == CUPID_PD_LPS ? "LPS" : "bond", o->surface_correction ? ", corrected" : "",
         crack ? ", pre-crack" : "", d / (kmax * norm(u, nd)), fabs(E - 0.5 * uKu) / fabs(E), asym / kmax, kmax);
  assert_true(d <= 1e-12 * kmax * norm(u, nd));
  assert_true(fabs(E - 0.5 * uKu) <= 1e-12 * fabs(E));
  assert_true(asym <= 1e-13 * kmax);
  /* rigid motions: a translation and a rotation about z */
  for (int m = 0; m < 2; m++) {
    for (cupid_int i = 0; i < n; i++) {
      const double *p = x + 3 * i;
      u[3 * i] = m ? -p[1] : 0.3, u[3 * i + 1] = m ? p[0] : -0.2, u[3 * i + 2] = m ? 0.0 : 0.7;
    }
    CUPID_ASSERT_OK(cupid_pd_operator_apply(op, u, f));
    assert_true(norm(f, nd) <= 1e-12 * kmax * norm(u, nd));
  }
  /* diagonal blocks and the row bound */
  double *D = malloc(sizeof(double) * 9 * n), *rb = malloc(sizeof(double) * nd);
  CUPID_ASSERT_OK(cupid_pd_operator_diagonal(op, D));
  CUPID_ASSERT_OK(cupid_pd_operator_row_bound(op, rb));
  for (cupid_int r = 0; r < n; r++) {
    double row = 0.0;
    for (cupid_int q = K->rowptr[r]; q < K->rowptr[r + 1]; q++) {
      double fro = 0.0; /* the block's Frobenius norm bounds its 2-norm from above; the 2-norm
                           from below by the largest entry */
      double mx = 0.0;
      for (int k = 0; k < 9; k++) fro += K->val[9 * q + k] * K->val[9 * q + k], mx = fmax(mx, fabs(K->val[9 * q + k]));
      row += mx;
      if (K->col[q] != r) continue;
      for (int k = 0; k < 9; k++) assert_true(fabs(D[9 * r + k] - K->val[9 * q + k]) <= 1e-13 * kmax);
    }
    assert_true(rb[3 * r] >= row * (1 - 1e-12));
  }
  free(D);
  free(rb);
  /* the volumes are used: the whole-cell operator differs */
  const double *saved = g->vfrac;
  struct cupid_pd_grid_private *gm = (struct cupid_pd_grid_private *)g;
  gm->vfrac = NULL;
  cupid_pd_operator whole = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(g, o, &whole));
  for (cupid_int i = 0; i < nd; i++) u[i] = (double)rand() / RAND_MAX - 0.5;
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, u, f));
  CUPID_ASSERT_OK(cupid_pd_operator_apply(whole, u, y));
  double diff = 0.0;
  for (cupid_int i = 0; i < nd; i++) diff = fmax(diff, fabs(f[i] - y[i]));
  assert_true(diff > 1e-3 * kmax * 1e-2);
  cupid_pd_operator_destroy(&whole);
  /* all volumes times c: K times c (m_i and theta_i unchanged, V phi_i W_i scaled) */
  const double c = 1.7;
  double *scaled = malloc(sizeof(double) * n);
  for (cupid_int i = 0; i < n; i++) scaled[i] = c * saved[i];
  gm->vfrac = scaled;
  cupid_pd_operator big = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(g, o, &big));
  if (crack) {
    cupid_pd_precrack cr = {.normal = 1, .at = 20.0, .lo = {-100, 0, -100}, .hi = {21.0, 0, 100}};
    cupid_int removed = 0;
    CUPID_ASSERT_OK(cupid_pd_operator_precrack(big, &cr, &removed));
  }
  CUPID_ASSERT_OK(cupid_pd_operator_apply(big, u, y));
  const double factor = o->model == CUPID_PD_BOND && !o->surface_correction ? c * c : c;
  for (cupid_int i = 0; i < nd; i++) assert_true(fabs(y[i] - factor * f[i]) <= 1e-12 * kmax * norm(u, nd));
  cupid_pd_operator_destroy(&big);
  gm->vfrac = (double *)saved;
  free(scaled);
  cupid_csr_destroy(&K);
  cupid_pd_operator_destroy(&op);
  free(u);
  free(f);
  free(y);
  free(th);
}

static void operator_with_cut_cells(void **state) {
  (void)state;
  cupid_shape s = sphere(20.3, 20.1, 19.8, 4.2), hole = cylinder(1, 21.0, 19.4, 1.3, 1, 0);
  cupid_pd_grid g = make(&s, 1, &hole, 1, 1.0, 1, 0);
  cupid_pd_material mat = {.E = 1000.0, .nu = 0.2};
  for (int model = 0; model < 2; model++)
    for (int corr = 0; corr < 2; corr++)
      for (int crack = 0; crack < 2 - corr; crack++) { /* fracture refuses the correction */
        cupid_pd_operator_options o = {.horizon = 2.015, .model = model ? CUPID_PD_BOND : CUPID_PD_LPS,
                                       .influence = CUPID_INFLUENCE_GAUSSIAN,
                                       .partial_volume = CUPID_PARTIAL_EXACT,
                                       .surface_correction = corr ? CUPID_SURFACE_ENERGY : CUPID_SURFACE_NONE,
                                       .materials = &mat, .n_materials = 1};
        operator_checks(g, &o, crack);
      }
  cupid_pd_grid_destroy(&g);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(body_volumes), cmocka_unit_test(slabs),
                                     cmocka_unit_test(operator_with_cut_cells)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
