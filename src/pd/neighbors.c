/* Neighbour search on the uniform grid: a fixed integer stencil of offsets with beta > 0,
 * looked up for every node through the dense cell index (no spatial search needed). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pd/pd_internal.h"

void pd_stencil_free(pd_stencil *S) {
  cupid_free(&S->off);
  cupid_free(&S->x);
  cupid_free(&S->nrm);
  cupid_free(&S->wb);
  cupid_free(&S->wxn);
  S->n = 0;
}

static void sort3(int a[3]) {
  for (int p = 1; p < 3; p++)
    for (int q = p; q > 0 && a[q] < a[q - 1]; q--) {
      int t = a[q];
      a[q] = a[q - 1];
      a[q - 1] = t;
    }
}

cupid_status pd_stencil_build(int dim, double h, double delta, cupid_partial_volume rule,
                              cupid_influence influence, pd_stencil *S) {
  cupid_status st = CUPID_SUCCESS;
  double *memo = NULL;
  memset(S, 0, sizeof *S);
  CUPID_CHECK(isfinite(delta) && delta > 0 && isfinite(h) && h > 0, CUPID_ERR_MODEL,
              "horizon and spacing must be positive, got %g and %g", delta, h);
  CUPID_CHECK(delta / h <= 64, CUPID_ERR_MODEL,
              "horizon/spacing = %g is beyond the supported 64 (the stencil would hold ~%.3g "
              "offsets)", delta / h, 4.19 * pow(delta / h, 3));
  /* EXACT also takes cells whose centre lies beyond delta but which meet the ball. */
  const int R = (int)floor(delta / h + (rule == CUPID_PARTIAL_EXACT ? 0.5 : 0.0) + 1e-9) + 1;
  const int Rx = dim == 3 ? R : 0;
  const size_t side = 2 * (size_t)R + 1, sidex = 2 * (size_t)Rx + 1;
  const size_t total = side * sidex * sidex, nmemo = (size_t)(R + 1) * (R + 1) * (R + 1);
  CUPID_TRY(cupid_malloc(3 * total, sizeof *S->off, "the PD stencil", &S->off));
  CUPID_TRY(cupid_malloc(total, sizeof *S->x, "the PD stencil", &S->x));
  CUPID_TRY(cupid_malloc(3 * total, sizeof *S->nrm, "the PD stencil", &S->nrm));
  CUPID_TRY(cupid_malloc(total, sizeof *S->wb, "the PD stencil", &S->wb));
  CUPID_TRY(cupid_malloc(3 * total, sizeof *S->wxn, "the PD stencil", &S->wxn));
  CUPID_TRY(cupid_malloc(nmemo, sizeof *memo, "the PD stencil", &memo));
  for (size_t q = 0; q < nmemo; q++) memo[q] = -1.0;
  int n = 0;
  for (int dk = -Rx; dk <= Rx; dk++)
    for (int dj = -R; dj <= R; dj++)
      for (int di = -Rx; di <= Rx; di++) {
        if (di == 0 && dj == 0 && dk == 0) continue;
        double beta;
        if (dim == 1) {
          beta = cupid_pd_partial_volume_1d(rule, dj * h, h, delta);
        } else {
          /* beta depends on the sorted |offset| only: compute each class once. */
          int a[3] = {abs(di), abs(dj), abs(dk)};
          sort3(a);
          double *mm = memo + ((size_t)a[0] * (R + 1) + a[1]) * (R + 1) + a[2];
          if (*mm < 0) *mm = cupid_pd_partial_volume(rule, a[0] * h, a[1] * h, a[2] * h, h, delta);
          beta = *mm;
        }
        if (!(beta > 0)) continue;
        const double xi[3] = {di * h, dj * h, dk * h};
        const double r = sqrt(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]);
        const double wb = cupid_pd_influence(influence, r, delta) * beta;
        S->off[3 * n] = di;
        S->off[3 * n + 1] = dj;
        S->off[3 * n + 2] = dk;
        S->x[n] = r;
        S->wb[n] = wb;
        for (int c = 0; c < 3; c++) {
          S->nrm[3 * n + c] = xi[c] / r;
          S->wxn[3 * n + c] = wb * xi[c]; /* omega beta |xi| n = omega beta xi */
        }
        n++;
      }
  S->n = n;
  CUPID_TRY_CHECK(n > 0, CUPID_ERR_MODEL,
                  "the horizon %g holds no neighbour at spacing %g (it must exceed the spacing)",
                  delta, h);
cleanup:
  cupid_free(&memo);
  if (st != CUPID_SUCCESS) pd_stencil_free(S);
  return st;
}

cupid_status pd_stencil_sum(const pd_stencil *S, int only_first, int *n, int32_t **off) {
  cupid_status st = CUPID_SUCCESS;
  unsigned char *hit = NULL;
  *off = NULL;
  *n = 0;
  int R = 0;
  for (int s = 0; s < 3 * S->n; s++) R = abs(S->off[s]) > R ? abs(S->off[s]) : R;
  const int R2 = only_first ? R : 2 * R;
  const size_t side = 2 * (size_t)R2 + 1;
  CUPID_TRY(cupid_calloc(side * side * side, 1, "the PD stencil sum", &hit));
#define PD_HIT(a, b, c) hit[(((size_t)((c) + R2)) * side + (size_t)((b) + R2)) * side + (size_t)((a) + R2)]
  PD_HIT(0, 0, 0) = 1;
  for (int s = 0; s < S->n; s++) {
    const int32_t *o = S->off + 3 * s;
    PD_HIT(o[0], o[1], o[2]) = 1;
    if (only_first) continue;
    for (int t = 0; t < S->n; t++) {
      const int32_t *p = S->off + 3 * t;
      PD_HIT(o[0] + p[0], o[1] + p[1], o[2] + p[2]) = 1;
    }
  }
  int count = 0;
  for (size_t q = 0; q < side * side * side; q++) count += hit[q];
  CUPID_TRY(cupid_malloc(3 * (size_t)count, sizeof **off, "the PD stencil sum", off));
  /* Lexicographic (dk, dj, di): the order of node indices. */
  int m = 0;
  for (int c = -R2; c <= R2; c++)
    for (int b = -R2; b <= R2; b++)
      for (int a = -R2; a <= R2; a++)
        if (PD_HIT(a, b, c)) {
          (*off)[3 * m] = a;
          (*off)[3 * m + 1] = b;
          (*off)[3 * m + 2] = c;
          m++;
        }
#undef PD_HIT
  *n = m;
cleanup:
  cupid_free(&hit);
  return st;
}

cupid_status pd_neighbors_build(const struct cupid_pd_grid_private *g, const pd_stencil *S,
                                cupid_int **ptr, cupid_int **nbr, int32_t **sidx) {
  cupid_status st = CUPID_SUCCESS;
  const cupid_int nn = g->nnodes;
  *ptr = NULL;
  *nbr = NULL;
  *sidx = NULL;
  CUPID_TRY(cupid_malloc((size_t)nn + 1, sizeof **ptr, "PD bond offsets", ptr));
  cupid_int *p = *ptr;
  p[0] = 0;
#pragma omp parallel for schedule(static) if (nn > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < nn; i++) {
    const int32_t *q = g->ijk + 3 * i;
    cupid_int c = 0;
    for (int s = 0; s < S->n; s++)
      c += pd_grid_lookup(g, q[0] + S->off[3 * s], q[1] + S->off[3 * s + 1],
                          q[2] + S->off[3 * s + 2]) >= 0;
    p[i + 1] = c;
  }
  for (cupid_int i = 0; i < nn; i++) p[i + 1] += p[i];
  CUPID_TRY(cupid_malloc((size_t)p[nn], sizeof **nbr, "PD bonds", nbr));
  CUPID_TRY(cupid_malloc((size_t)p[nn], sizeof **sidx, "PD bond stencil entries", sidx));
  cupid_int *nb = *nbr;
  int32_t *sx = *sidx;
#pragma omp parallel for schedule(static) if (nn > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < nn; i++) {
    const int32_t *q = g->ijk + 3 * i;
    cupid_int b = p[i];
    for (int s = 0; s < S->n; s++) {
      cupid_int j = pd_grid_lookup(g, q[0] + S->off[3 * s], q[1] + S->off[3 * s + 1],
                                   q[2] + S->off[3 * s + 2]);
      if (j < 0) continue;
      nb[b] = j;
      sx[b] = s;
      b++;
    }
  }
cleanup:
  if (st != CUPID_SUCCESS) {
    cupid_free(ptr);
    cupid_free(nbr);
    cupid_free(sidx);
  }
  return st;
}

/* Nodes reachable from every node through a list of offsets, summed. */
static cupid_int count_present(const struct cupid_pd_grid_private *g, int n, const int32_t *off) {
  cupid_int total = 0;
#pragma omp parallel for schedule(static) reduction(+ : total) if (g->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < g->nnodes; i++) {
    const int32_t *q = g->ijk + 3 * i;
    for (int s = 0; s < n; s++)
      total += pd_grid_lookup(g, q[0] + off[3 * s], q[1] + off[3 * s + 1], q[2] + off[3 * s + 2]) >= 0;
  }
  return total;
}

cupid_status cupid_pd_operator_estimate(const cupid_pd_grid grid,
                                        const cupid_pd_operator_options *opts,
                                        cupid_pd_estimate *est) {
  cupid_status st = CUPID_SUCCESS;
  pd_stencil S;
  int32_t *sum = NULL;
  int nsum = 0;
  CUPID_CHECK(grid && opts && est, CUPID_ERR_ARGUMENT, "estimate needs grid, options and output");
  memset(est, 0, sizeof *est);
  CUPID_CALL(pd_stencil_build(grid->dim, grid->h, opts->horizon, opts->partial_volume,
                              opts->influence, &S));
  CUPID_TRY(pd_stencil_sum(&S, opts->model == CUPID_PD_BOND, &nsum, &sum));
  est->nodes = grid->nnodes;
  est->bonds = count_present(grid, S.n, S.off);
  est->blocks = count_present(grid, nsum, sum);
  /* Operator: neighbour + stencil index per bond, offsets, ~9 doubles per node. */
  est->bytes_operator = est->bonds * (int64_t)(sizeof(cupid_int) + sizeof(int32_t)) +
                        (est->nodes + 1) * (int64_t)sizeof(cupid_int) + est->nodes * 9 * 8 +
                        (opts->surface_correction != CUPID_SURFACE_NONE ? est->nodes * PD_SF * 8 : 0);
  est->bytes_matrix = (est->nodes + 1) * (int64_t)sizeof(cupid_int) +
                      est->blocks * (int64_t)(sizeof(cupid_int) + 9 * sizeof(double));
cleanup:
  cupid_free(&sum);
  pd_stencil_free(&S);
  return st;
}
