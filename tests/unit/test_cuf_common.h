/* Helpers shared by the CUF tests: beam definitions built by hand (no model file), a direct
 * solve wrapper and rigid-body fields. Header only (static functions). */
#ifndef CUPID_TEST_CUF_COMMON_H
#define CUPID_TEST_CUF_COMMON_H

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cupid/cuf.h"
#include "testutil.h"

#define TB_MAXC 8
#define TB_MAXB 64

typedef struct {
  cupid_beam def;
  cupid_section_component comp[TB_MAXC];
  double xs[TB_MAXC][TB_MAXB], zs[TB_MAXC][TB_MAXB];
  double axis_y[TB_MAXB];
  int axis_el[TB_MAXB];
  cupid_material mat[4];
  int n_mat;
} tb_beam;

/* An empty definition with material 0 isotropic (E, nu). */
static inline void tb_init(tb_beam *t, double E, double nu) {
  memset(t, 0, sizeof *t);
  t->mat[0].E = E;
  t->mat[0].nu = nu;
  t->mat[0].name = (char *)"m0";
  t->n_mat = 1;
  t->def.material = 0;
  t->def.components = t->comp;
  t->def.axis_y = t->axis_y;
  t->def.axis_elements = t->axis_el;
}

static inline void tb_te(tb_beam *t, int N) {
  t->def.expansion = CUPID_EXPANSION_TE;
  t->def.te_order = N;
}

static inline void tb_le(tb_beam *t, int nodes) {
  t->def.expansion = CUPID_EXPANSION_LE;
  t->def.le_nodes = nodes;
}

/* Axis y0..y1 with ne elements of p nodes. */
static inline void tb_axis(tb_beam *t, double y0, double y1, int ne, int p) {
  t->axis_y[0] = y0;
  t->axis_y[1] = y1;
  t->axis_el[0] = ne;
  t->def.n_axis = 2;
  t->def.element_nodes = p;
}

/* Axis with breakpoints ys[0..n-1] and one element between each two (no element size set:
 * element_nodes stays as given by the caller or the default). */
static inline void tb_axis_spans(tb_beam *t, int n, const double *ys) {
  for (int k = 0; k < n; k++) t->axis_y[k] = ys[k];
  for (int k = 0; k + 1 < n; k++) t->axis_el[k] = 1;
  t->def.n_axis = n;
}

/* A rectangle component split into nx x nz equal cells (material -1: the beam's). */
static inline void tb_rect(tb_beam *t, double x0, double x1, int nx, double z0, double z1, int nz,
                           int material) {
  int c = t->def.n_components++;
  for (int i = 0; i <= nx; i++) t->xs[c][i] = x0 + (x1 - x0) * i / nx;
  for (int j = 0; j <= nz; j++) t->zs[c][j] = z0 + (z1 - z0) * j / nz;
  t->comp[c].x = t->xs[c];
  t->comp[c].z = t->zs[c];
  t->comp[c].nx = nx + 1;
  t->comp[c].nz = nz + 1;
  t->comp[c].material = material;
}

static inline cupid_cuf_beam tb_create(tb_beam *t) {
  cupid_cuf_beam b = NULL;
  CUPID_ASSERT_OK(cupid_cuf_beam_create_from(&t->def, t->mat, t->n_mat, &b));
  return b;
}

/* Solve K u = f with bc; returns the solution (caller frees with cupid_free). */
static inline double *tb_solve(cupid_cuf_beam b, const double *f, cupid_dirichlet bc,
                               double *assembly_time) {
  cupid_csr K = NULL;
  double t0 = cupid_wtime();
  CUPID_ASSERT_OK(cupid_cuf_assemble(b, &K));
  if (assembly_time) *assembly_time = cupid_wtime() - t0;
  double *u = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)cupid_cuf_num_dofs(b), sizeof *u, "u", &u));
  cupid_solve_info info;
  CUPID_ASSERT_OK(cupid_dirichlet_finalize(bc));
  CUPID_ASSERT_OK(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, &info));
  cupid_csr_destroy(&K);
  return u;
}

/* Rigid-body field: mode 0..2 translations, 3..5 rotations about x, y, z through (0,0,0). */
static inline void tb_rigid(void *ctx, const double p[3], double density, double out[3]) {
  int mode = *(const int *)ctx;
  (void)density;
  out[0] = out[1] = out[2] = 0;
  if (mode < 3) {
    out[mode] = 1.0;
    return;
  }
  double w[3] = {0, 0, 0};
  w[mode - 3] = 1.0;
  out[0] = w[1] * p[2] - w[2] * p[1];
  out[1] = w[2] * p[0] - w[0] * p[2];
  out[2] = w[0] * p[1] - w[1] * p[0];
}

/* Constant vector field (ctx: double[3]). */
static inline void tb_const(void *ctx, const double p[3], double density, double out[3]) {
  const double *v = ctx;
  (void)p;
  (void)density;
  out[0] = v[0], out[1] = v[1], out[2] = v[2];
}

#endif
