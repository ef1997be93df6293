/* The slab check shared by the coupled operators' tests (issue 6): the real grid of some
 * boxes is split into z slabs (cupid_pd_grid_partition), the operator and its preconditioner
 * matrix are built on each slab, and each slab's owned PD rows and its share of the FE rows of
 * A x and P x are gathered into the whole model's numbering (the FE rows summed over the
 * slabs, as cupid_krylov_solve() does over the MPI ranks). They must equal the whole model's
 * to 1e-13 of max |y|: the same terms, summed in another order. Header only. */
#ifndef CUPID_TEST_SLABS_H
#define CUPID_TEST_SLABS_H

#include <math.h>
#include <stdio.h>

#include "cupid/coupling.h"
#include "testutil.h"

/* One kind of coupled operator: build it and its preconditioner matrix on a grid (whole or a
 * slab; the beam's DOF offset is set to the grid's nodes), the rows [d0, d1) of its product,
 * destroy it. */
typedef struct {
  cupid_status (*create)(void *ctx, cupid_pd_grid grid, void **op, cupid_csr *P);
  cupid_status (*apply_rows)(void *op, const double *x, cupid_int d0, cupid_int d1, double *y);
  void (*destroy)(void *op);
  void *ctx;
} slab_operator;

/* A (rows [0, n)) and P times x on the grid g, into y and py (n = 3 nodes + the FE DOFs). */
static inline cupid_int slab_products(const slab_operator *so, cupid_cuf_beam beam,
                                      cupid_pd_grid g, const double *x, double *y, double *py) {
  cupid_int nl = cupid_pd_grid_num_nodes(g), n = 3 * nl + cupid_cuf_num_dofs(beam);
  void *op = NULL;
  cupid_csr P = NULL;
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(beam, 3 * nl));
  CUPID_ASSERT_OK(so->create(so->ctx, g, &op, &P));
  cupid_pd_grid_partition pt;
  cupid_pd_grid_get_partition(g, &pt);
  CUPID_ASSERT_OK(so->apply_rows(op, x, 3 * pt.owned_first, 3 * pt.owned_last, y));
  CUPID_ASSERT_OK(so->apply_rows(op, x, 3 * nl, n, y));
  cupid_csr_matvec(P, x, py);
  cupid_csr_destroy(&P);
  so->destroy(op);
  return n;
}

static inline void slab_check(const char *what, const slab_operator *so, cupid_cuf_beam beam,
                              int n_boxes, const cupid_box *boxes, const int *mats, int halo,
                              int parts) {
  cupid_pd_grid whole = NULL;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, n_boxes, boxes, mats, &whole));
  const cupid_int G = cupid_pd_grid_num_nodes(whole), n_fe = cupid_cuf_num_dofs(beam),
                  N = 3 * G + n_fe;
  double *x = NULL, *y = NULL, *py = NULL, *ys = NULL, *pys = NULL, *xl = NULL, *yl = NULL,
         *pl = NULL;
  CUPID_ASSERT_OK(cupid_malloc((size_t)N, sizeof *x, "x", &x));
  CUPID_ASSERT_OK(cupid_calloc((size_t)N, sizeof *y, "y", &y));
  CUPID_ASSERT_OK(cupid_calloc((size_t)N, sizeof *py, "Px", &py));
  CUPID_ASSERT_OK(cupid_calloc((size_t)N, sizeof *ys, "y slabs", &ys));
  CUPID_ASSERT_OK(cupid_calloc((size_t)N, sizeof *pys, "Px slabs", &pys));
  CUPID_ASSERT_OK(cupid_malloc((size_t)N, sizeof *xl, "x local", &xl)); /* a slab's n <= N */
  CUPID_ASSERT_OK(cupid_malloc((size_t)N, sizeof *yl, "y local", &yl));
  CUPID_ASSERT_OK(cupid_malloc((size_t)N, sizeof *pl, "Px local", &pl));
  uint64_t seed = 5;
  for (cupid_int d = 0; d < N; d++) x[d] = 2.0 * cupid_test_random(&seed) - 1.0;
  slab_products(so, beam, whole, x, y, py);
  cupid_int owned_total = 0;
  for (int part = 0; part < parts; part++) {
    cupid_pd_grid g = NULL;
    cupid_pd_grid_options gs = {.spacing = 1.0, .dimension = 3, .parts = parts, .part = part,
                                .halo_layers = halo};
    CUPID_ASSERT_OK(cupid_pd_grid_create(&gs, n_boxes, boxes, mats, &g));
    cupid_pd_grid_partition pt;
    cupid_pd_grid_get_partition(g, &pt);
    const cupid_int nl = cupid_pd_grid_num_nodes(g), g0 = 3 * pt.first_global;
    for (cupid_int d = 0; d < 3 * nl; d++) xl[d] = x[g0 + d];
    for (cupid_int d = 0; d < n_fe; d++) xl[3 * nl + d] = x[3 * G + d];
    slab_products(so, beam, g, xl, yl, pl);
    for (cupid_int d = 3 * pt.owned_first; d < 3 * pt.owned_last; d++)
      ys[g0 + d] = yl[d], pys[g0 + d] = pl[d];
    for (cupid_int d = 0; d < n_fe; d++) ys[3 * G + d] += yl[3 * nl + d], pys[3 * G + d] += pl[3 * nl + d];
    owned_total += pt.owned_last - pt.owned_first;
    cupid_pd_grid_destroy(&g);
  }
  CUPID_ASSERT_OK(cupid_cuf_set_dof_offset(beam, 3 * G));
  assert_int_equal(owned_total, G);
  double e = 0.0, ep = 0.0, ym = 0.0, pm = 0.0;
  for (cupid_int d = 0; d < N; d++) {
    e = fmax(e, fabs(ys[d] - y[d])), ep = fmax(ep, fabs(pys[d] - py[d]));
    ym = fmax(ym, fabs(y[d])), pm = fmax(pm, fabs(py[d]));
  }
  printf("%s on %d z slabs (halo %d layers): owned + summed FE rows against the whole model: "
         "operator %.1e, preconditioner %.1e of max |y|\n", what, parts, halo, e / ym, ep / pm);
  assert_true(e <= 1e-13 * ym);
  assert_true(ep <= 1e-13 * pm);
  cupid_free(&x);
  cupid_free(&y);
  cupid_free(&py);
  cupid_free(&ys);
  cupid_free(&pys);
  cupid_free(&xl);
  cupid_free(&yl);
  cupid_free(&pl);
  cupid_pd_grid_destroy(&whole);
}

#endif
