/* The runs' stretches of uniform b (pd_run ub0, ub1), for the LPS first pass.
 *
 * The first pass sums w15 ((b_i + b+) d+ + (b_i + b-) d-) n over the pairs, loading b+ and
 * b- for every pair (stencil_kernels.h). Where node i and every node of its family have the
 * same b = mu / m (to the bit: one material, full families all round, so one m), the sum is
 * 2 b_i sum w15 (d+ + d-) n, and the kernel skips those loads. That holds two horizons
 * inside the surface: a third of the nodes of a 40^3 cube, two thirds of a 100^3 one. A
 * removed bond changes the m, so the b, of its two nodes (fracture.c): pd_uniform_exclude
 * then cuts them and their families out of the stretches. */
#include <stdint.h>

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
  uint16_t *key = NULL;
  /* By padded cell: the material + 1 of a node with a full family, else 0. Full nodes of one
   * material have one b = mu / m to the bit (m of a full family is summed once, node_data),
   * so a node whose family all has its own key has uniform b. */
  for (cupid_int i = 0; i < op->nnodes; i++)
    if (op->grid->material[i] >= UINT16_MAX - 1) return CUPID_SUCCESS; /* no key: no stretch */
  CUPID_CALL(cupid_calloc((size_t)cells, sizeof *key, "PD uniform stretches", &key));
#pragma omp parallel for schedule(static) if (op->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < op->nnodes; i++)
    if (op->full[i]) key[pd_node_pcell(op, i)] = (uint16_t)(op->grid->material[i] + 1);
  const pd_stencil *S = &op->st;
#pragma omp parallel for schedule(dynamic, 16) if (op->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int r = 0; r < op->nruns; r++) {
    pd_run *R = &op->runs[r];
    const uint16_t *restrict k = key + R->cp0;
    unsigned char ok[PD_RUN_MAX];
    for (int t = 0; t < R->len; t++) ok[t] = k[t] != 0;
    for (int s = 0; s < S->n; s++) {
      const uint16_t *restrict kj = k + op->pclin[s];
      for (int t = 0; t < R->len; t++) ok[t] &= kj[t] == k[t];
    }
    longest(ok, R->len, &R->ub0, &R->ub1);
  }
  cupid_free(&key);
  return CUPID_SUCCESS;
}

/* Node k out of its run's stretch: the longer side of it stays. */
static void cut(struct cupid_pd_operator_private *op, cupid_int k) {
  pd_run *R = &op->runs[pd_first_run(op, k)];
  const int t = (int)(k - R->i0);
  if (t < R->ub0 || t >= R->ub1) return;
  if (t - R->ub0 >= R->ub1 - t - 1) R->ub1 = t;
  else R->ub0 = t + 1;
}

void pd_uniform_exclude(struct cupid_pd_operator_private *op, cupid_int i) {
  if (!op->padded || op->model != CUPID_PD_LPS) return;
  const pd_family F = pd_family_of(op, i);
  cut(op, i);
  for (int q = 0; q < F.n; q++) cut(op, pd_family_node(op, &F, pd_family_entry(&F, q)));
}
