/* The runs' stretches of uniform b (pd_run ub0, ub1), for the LPS first pass.
 *
 * The first pass sums w15 ((b_i + b+) d+ + (b_i + b-) d-) n over the pairs, loading b+ and
 * b- for every pair (stencil_kernels.h). Where node i and every node of its family have the
 * same b = mu / m (bit for bit: one material, full families all round, so one m), the sum is
 * 2 b_i sum w15 (d+ + d-) n, and the kernel skips those loads. That holds at least a horizon
 * inside the surface: a third of the nodes of a 40^3 cube, two thirds of a 100^3 one. */
#include <math.h>

#include "pd/pd_internal.h"

/* The longest stretch of nonzero ok[0 .. len). */
static void longest(const unsigned char *ok, int len, int *a, int *b) {
  *a = *b = 0;
  for (int t = 0; t < len;) {
    if (!ok[t]) {
      t++;
      continue;
    }
    int e = t;
    while (e < len && ok[e]) e++;
    if (e - t > *b - *a) *a = t, *b = e;
    t = e;
  }
}

cupid_status pd_uniform_build(struct cupid_pd_operator_private *op) {
  if (!op->padded || op->model != CUPID_PD_LPS) return CUPID_SUCCESS;
  const cupid_int cells = op->pn[0] * op->pn[1] * op->pn[2];
  double *bc = NULL;
  /* b by padded cell, NaN where no node is: a comparison with an absent neighbour fails. */
  CUPID_CALL(cupid_malloc((size_t)cells, sizeof *bc, "PD uniform stretches", &bc));
#pragma omp parallel for schedule(static) if (cells > PD_OMP_MIN_NODES)
  for (cupid_int c = 0; c < cells; c++) bc[c] = NAN;
#pragma omp parallel for schedule(static) if (op->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < op->nnodes; i++) bc[pd_node_pcell(op, i)] = op->mu[i] / op->m[i];
  const pd_stencil *S = &op->st;
#pragma omp parallel for schedule(dynamic, 16) if (op->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int r = 0; r < op->nruns; r++) {
    pd_run *R = &op->runs[r];
    const double *restrict b = bc + R->cp0;
    unsigned char ok[PD_RUN_MAX];
    for (int t = 0; t < R->len; t++) ok[t] = op->full[R->i0 + t];
    for (int s = 0; s < S->n; s++) {
      const double *restrict bj = b + op->pclin[s];
      for (int t = 0; t < R->len; t++) ok[t] &= bj[t] == b[t];
    }
    longest(ok, R->len, &R->ub0, &R->ub1);
  }
  cupid_free(&bc);
  return CUPID_SUCCESS;
}
