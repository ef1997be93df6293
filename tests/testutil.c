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

/* Shared by the PD bar verification tests (test_pd_bar.c, test_pd_surface.c). */
int cupid_test_pd_pcg(cupid_pd_operator op, cupid_int n, const unsigned char *fixed,
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

