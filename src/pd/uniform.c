/* The runs' stretches of uniform b (pd_run ub0, ub1), for the LPS first pass.
 *
 * The first pass sums w15 ((b_i + b+) d+ + (b_i + b-) d-) n over the pairs, loading b+ and
 * b- for every pair (stencil_kernels.h). Where node i and every node of its family have the
 * same b = mu / m to the bit, the sum is 2 b_i sum w15 (d+ + d-) n, and the kernel skips
 * those loads. That holds two horizons inside the surface of a body of one material: a
 * third of the nodes of a 40^3 cube, two thirds of a 100^3 one.
 *
 * The decision compares b itself, as the work arrays hold it (mu / m, stencil.c work_fill),
 * never a proxy of it: every factor of b changes it. The material (mu); m, which differs near
 * the surface (ghost corrections: non-full nodes are never in a stretch) and where a bond is
 * removed; and the energy weights of an Arlequin overlap (cupid_pd_operator_scale_energy()
 * scales mu node by node after the operator is built, and rebuilds the stretches). Keying by
 * the material alone, as first done, took 2 b_i for b_i + b_j across an overlap's ramp: the
 * matrix-free Arlequin solves were 4-7% off (issue 32). A removed bond changes m, so b, of
 * its two nodes (fracture.c): pd_uniform_exclude then cuts them and their families out. */
#include <stdint.h>
#include <string.h>

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

/* Keys of b: equal keys are equal b = mu / m to the bit, 0 no key (a node whose family is
 * not full, or one of more distinct b values than 16 bits number: left out, never wrong).
 * 16-bit keys, not the doubles, in the stretch compares below: a quarter of the bytes
 * streamed (st.n compares a node). The distinct values are few (one a material in the bulk,
 * one a weight of an overlap's ramp): an open-addressed table of their bits. */
#define KEY_TABLE (1u << 17) /* twice the keys it can give: probes stay short */
typedef struct {
  uint64_t bits[KEY_TABLE];
  uint16_t key[KEY_TABLE]; /* 0: empty slot */
  uint16_t next;           /* the next key to give */
} b_keys;

static uint16_t b_key(b_keys *T, uint64_t bits) {
  uint32_t h = (uint32_t)((bits * 0x9E3779B97F4A7C15ull) >> 47) & (KEY_TABLE - 1);
  while (T->key[h] && T->bits[h] != bits) h = (h + 1) & (KEY_TABLE - 1);
  if (T->key[h]) return T->key[h];
  if (T->next == UINT16_MAX) return 0; /* out of keys */
  T->bits[h] = bits;
  return T->key[h] = T->next++;
}

cupid_status pd_uniform_build(struct cupid_pd_operator_private *op) {
  for (cupid_int r = 0; r < op->nruns; r++) op->runs[r].ub0 = op->runs[r].ub1 = 0;
  if (!op->padded || op->model != CUPID_PD_LPS) return CUPID_SUCCESS;
  const cupid_int cells = op->pn[0] * op->pn[1] * op->pn[2];
  uint16_t *key = NULL;
  b_keys *T = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_calloc((size_t)cells, sizeof *key, "PD uniform stretches", &key));
  CUPID_TRY(cupid_calloc(1, sizeof *T, "PD uniform stretches' keys", &T));
  T->next = 1;
  /* By padded cell: the key of b of a node with a full family, else 0. Serial (the table is
   * shared); runs of equal b skip the table. */
  uint64_t last = 0;
  uint16_t last_key = 0;
  for (cupid_int i = 0; i < op->nnodes; i++) {
    if (!op->full[i]) continue;
    const double b = op->mu[i] / op->m[i]; /* as work_fill computes it */
    uint64_t bits;
    memcpy(&bits, &b, sizeof bits);
    if (!last_key || bits != last) last = bits, last_key = b_key(T, bits);
    key[pd_node_pcell(op, i)] = last_key;
  }
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
cleanup:
  cupid_free(&T);
  cupid_free(&key);
  return st;
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
