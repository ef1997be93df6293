#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cupid_config.h"

double cupid_test_random(uint64_t *state) {
  uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return 2.0 * ((double)(z >> 11) / 9007199254740992.0) - 1.0;
}

const char *cupid_test_source_path(const char *relative) {
  static _Thread_local char buf[4096];
  const char *root = getenv("CUPID_SOURCE_DIR");
  snprintf(buf, sizeof buf, "%s/%s", root ? root : CUPID_SOURCE_DIR, relative);
  return buf;
}

int cupid_test_mkdtemp(const char *tag, char *buf, size_t len) {
  int n = snprintf(buf, len, "/tmp/cupid_test_%s_XXXXXX", tag);
  if (n < 0 || (size_t)n >= len) return -1;
  return mkdtemp(buf) ? 0 : -1;
}

int cupid_test_rmtree(const char *path) {
  if (!path || !path[0] || strchr(path, '\'')) return -1; /* quoted below */
  char cmd[4200];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", path);
  return system(cmd);
}

void cupid_test_affine_eval(const cupid_test_affine *a, const double p[3], double out[3]) {
  for (int k = 0; k < 3; k++) {
    out[k] = a->c[k];
    for (int d = 0; d < 3; d++) out[k] += a->B[k][d] * p[d];
  }
}

void cupid_test_affine_fn(void *ctx, const double p[3], double density, double out[3]) {
  (void)density;
  cupid_test_affine_eval(ctx, p, out);
}

cupid_test_affine cupid_test_random_affine(uint64_t seed) {
  cupid_test_affine a;
  uint64_t s = seed;
  for (int k = 0; k < 3; k++) {
    a.c[k] = 1e-3 * cupid_test_random(&s);
    for (int d = 0; d < 3; d++) a.B[k][d] = 1e-3 * cupid_test_random(&s);
  }
  return a;
}

/* Jacobi-preconditioned CG on the free DOFs (fixed DOFs held at zero); the true residual is
 * asserted (10 rtol). Returns the iterations. */
static int pd_pcg(cupid_pd_operator op, cupid_int n, const unsigned char *fixed,
                  const double *diag, const double *b, double *x, double rtol, int maxit) {
  double *r = calloc((size_t)n, sizeof *r), *z = calloc((size_t)n, sizeof *z);
  double *p = calloc((size_t)n, sizeof *p), *q = calloc((size_t)n, sizeof *q);
  memset(x, 0, (size_t)n * sizeof *x);
  double bn = 0, rz = 0;
  for (cupid_int i = 0; i < n; i++) {
    r[i] = fixed[i] ? 0.0 : b[i];
    z[i] = fixed[i] ? 0.0 : r[i] / diag[i];
    p[i] = z[i];
    bn += r[i] * r[i];
    rz += r[i] * z[i];
  }
  bn = sqrt(bn);
  int it = 0;
  for (; it < maxit; it++) {
    CUPID_ASSERT_OK(cupid_pd_operator_apply(op, p, q));
    double pq = 0;
    for (cupid_int i = 0; i < n; i++) {
      if (fixed[i]) q[i] = 0.0;
      pq += p[i] * q[i];
    }
    assert_true(pq > 0); /* K_ff is SPD once the rigid modes are removed */
    const double alpha = rz / pq;
    double rn = 0, rz1 = 0;
    for (cupid_int i = 0; i < n; i++) {
      x[i] += alpha * p[i];
      r[i] -= alpha * q[i];
      z[i] = fixed[i] ? 0.0 : r[i] / diag[i];
      rn += r[i] * r[i];
      rz1 += r[i] * z[i];
    }
    if (sqrt(rn) <= rtol * bn) break;
    const double beta = rz1 / rz;
    rz = rz1;
    for (cupid_int i = 0; i < n; i++) p[i] = z[i] + beta * p[i];
  }
  /* True residual check. */
  CUPID_ASSERT_OK(cupid_pd_operator_apply(op, x, q));
  double res = 0;
  for (cupid_int i = 0; i < n; i++)
    if (!fixed[i]) res += (q[i] - b[i]) * (q[i] - b[i]);
  assert_true(sqrt(res) <= 10 * rtol * bn);
  free(r);
  free(z);
  free(p);
  free(q);
  return it;
}

cupid_test_bar_result cupid_test_pd_bar(int W, int NY, cupid_pd_model_kind model,
                                        cupid_partial_volume pvr, double nu,
                                        cupid_surface_correction sc, double rtol) {
  const int NX = W, NZ = W;
  cupid_box box = {.lo = {0, 0, 0}, .hi = {NX, NY, NZ}, .has = {1, 1, 1}};
  int mzero = 0;
  cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
  cupid_pd_grid g = NULL;
  CUPID_ASSERT_OK(cupid_pd_grid_create(&go, 1, &box, &mzero, &g));
  const double E = 1.0e4, sigma = 1.0, delta = 3.0;
  cupid_pd_material mat = {E, nu};
  cupid_pd_operator_options o = {.horizon = delta, .model = model, .influence = CUPID_INFLUENCE_GAUSSIAN,
                                 .partial_volume = pvr, .materials = &mat, .n_materials = 1,
                                 .surface_correction = sc};
  cupid_pd_operator op = NULL;
  CUPID_ASSERT_OK(cupid_pd_operator_create(g, &o, &op));
  const cupid_int nn = cupid_pd_grid_num_nodes(g), n = 3 * nn;
  unsigned char *fixed = calloc((size_t)n, 1);
  double *b = calloc((size_t)n, sizeof *b), *u = calloc((size_t)n, sizeof *u);
  double *diag = malloc((size_t)n * sizeof *diag), *blk = malloc(9 * (size_t)nn * sizeof *blk);
  assert_true(fixed && b && u && diag && blk);
  CUPID_ASSERT_OK(cupid_pd_operator_diagonal(op, blk));
  for (cupid_int p = 0; p < nn; p++)
    for (int c = 0; c < 3; c++) diag[3 * p + c] = blk[9 * p + 4 * c];
  for (int k = 0; k < NZ; k++)
    for (int i = 0; i < NX; i++) {
      fixed[3 * cupid_pd_grid_node_at(g, i, 0, k) + 1] = 1;              /* u_y = 0 at y = 0 */
      b[3 * cupid_pd_grid_node_at(g, i, NY - 1, k) + 1] = sigma * 1.0;    /* sigma h^2 */
    }
  const cupid_int a = cupid_pd_grid_node_at(g, NX / 2, 0, NZ / 2), c2 = cupid_pd_grid_node_at(g, NX / 2, 0, 0);
  fixed[3 * a] = fixed[3 * a + 2] = 1; /* translations x, z */
  fixed[3 * c2] = 1;                   /* rotation about y */
  cupid_test_bar_result res;
  res.iterations = pd_pcg(op, n, fixed, diag, b, u, rtol, 20000);
  /* Axial strain between sections j1 and j2 (15 h from either end), section-averaged. */
  const int j1 = 12, j2 = 27;
  double s = 0;
  for (int k = 0; k < NZ; k++)
    for (int i = 0; i < NX; i++)
      s += u[3 * cupid_pd_grid_node_at(g, i, j2, k) + 1] - u[3 * cupid_pd_grid_node_at(g, i, j1, k) + 1];
  const double eyy = s / (NX * NZ) / (j2 - j1);
  res.strain = eyy / (sigma / E);
  /* Lateral strain at the middle section: least-squares slope of u_x in x. */
  const int jm = (j1 + j2) / 2;
  double sxx = 0, sxu = 0, xm = (NX - 1) / 2.0;
  for (int k = 0; k < NZ; k++)
    for (int i = 0; i < NX; i++) {
      sxx += (i - xm) * (i - xm);
      sxu += (i - xm) * u[3 * cupid_pd_grid_node_at(g, i, jm, k)];
    }
  res.nu = -(sxu / sxx) / eyy;
  free(fixed);
  free(b);
  free(u);
  free(diag);
  free(blk);
  cupid_pd_operator_destroy(&op);
  cupid_pd_grid_destroy(&g);
  return res;
}
