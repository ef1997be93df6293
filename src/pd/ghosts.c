/* The ghost-bond corrections of the padded stencil kernels (pd_internal.h: gseg, ncorr).
 *
 * In the padded lattice absent cells read u = a = b = 0, so the kernels sum the bonds of a
 * non-full node to its absent entries too; those ghost bonds are removed per node from
 * records of its absent entries (C_i = sum w n n^T) and present ones (G_i = gself). The
 * non-full nodes of a run come in segments; segments with the same records share one copy:
 * on a box every row of a kind (which faces it is near) has the same segments, so the
 * records the kernels stream shrink from 72 bytes a near-surface node (1.8 MB at 40^3,
 * streamed from memory on every apply) to a few kilobytes that stay in the cache. */
#include <stdint.h>
#include <string.h>

#include "pd/pd_internal.h"

/* The segments of consecutive non-full nodes of each run, with their ranks among the
 * non-full nodes (rank[i], -1 for full nodes). */
static cupid_status ghost_segments(struct cupid_pd_operator_private *op, const int32_t *rank) {
  cupid_int nseg = 0;
  for (int pass = 0; pass < 2; pass++) {
    nseg = 0;
    for (cupid_int r = 0; r < op->nruns; r++) {
      const pd_run *R = &op->runs[r];
      if (pass) op->gptr[r] = nseg;
      for (cupid_int i = R->i0; i < R->i0 + R->len; i++) {
        if (op->full[i]) continue;
        if (i > R->i0 && !op->full[i - 1]) {
          if (pass) op->gseg[nseg - 1].n++;
          continue;
        }
        if (pass) op->gseg[nseg] = (pd_ghost_seg){.i0 = i, .rank = rank[i], .n = 1};
        nseg++;
      }
    }
    if (!pass) {
      CUPID_CALL(cupid_malloc((size_t)op->nruns + 1, sizeof *op->gptr, "PD ghost segments", &op->gptr));
      CUPID_CALL(cupid_malloc((size_t)nseg + 1, sizeof *op->gseg, "PD ghost segments", &op->gseg));
    }
  }
  op->gptr[op->nruns] = nseg;
  op->nseg = nseg;
  return CUPID_SUCCESS;
}

/* The records of every non-full node by rank, stored by component (c gs + rank): C_i, the
 * sum over the absent entries of w n n^T, and G_i = gself (node_data's sum over the present
 * entries of g = omega beta xi; LPS only, 0 bond-based, whose kernels do not read it). */
static void ghost_records(const struct cupid_pd_operator_private *op, const int32_t *rank,
                          cupid_int gs, double *restrict rec) {
  const pd_stencil *S = &op->st;
  const cupid_int nn = op->nnodes;
#pragma omp parallel for schedule(dynamic, 64) if (nn > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < nn; i++) {
    if (op->full[i]) continue;
    const pd_family F = pd_family_of(op, i);
    double c[PD_GHOST_STRIDE] = {0};
    int q = 0; /* present entries come in stencil order: walk them alongside */
    for (int s = 0; s < S->n; s++) {
      if (q < F.n && F.s[q] == s) {
        q++;
        continue;
      }
      const double *n = S->nrm + 3 * s;
      const double w = op->model == CUPID_PD_LPS ? 15.0 * S->wb[s] : 0.5 * S->wb[s] / S->x[s];
      c[0] += w * n[0] * n[0];
      c[1] += w * n[1] * n[1];
      c[2] += w * n[2] * n[2];
      c[3] += w * n[1] * n[2];
      c[4] += w * n[0] * n[2];
      c[5] += w * n[0] * n[1];
    }
    if (op->gself)
      for (int k = 0; k < 3; k++) c[6 + k] = op->gself[3 * i + k];
    for (int k = 0; k < PD_GHOST_STRIDE; k++) rec[k * gs + rank[i]] = c[k];
  }
}

/* FNV-1a over a segment's records, component by component. */
static uint64_t segment_hash(const double *rec, cupid_int gs, const pd_ghost_seg *g) {
  uint64_t h = 1469598103934665603ull ^ (uint64_t)g->n;
  for (int k = 0; k < PD_GHOST_STRIDE; k++) {
    const unsigned char *b = (const unsigned char *)(rec + k * gs + g->rank);
    for (size_t j = 0; j < (size_t)g->n * sizeof(double); j++) h = (h ^ b[j]) * 1099511628211ull;
  }
  return h;
}

static int segments_equal(const double *rec, cupid_int gs, const pd_ghost_seg *a,
                          const pd_ghost_seg *b) {
  if (a->n != b->n) return 0;
  for (int k = 0; k < PD_GHOST_STRIDE; k++)
    if (memcmp(rec + k * gs + a->rank, rec + k * gs + b->rank, (size_t)a->n * sizeof(double)))
      return 0;
  return 1;
}

/* Each segment's records once per distinct content (bit for bit) into op->ncorr; the
 * segments' ranks then index it. An open-addressed table of the first segment with each
 * content. */
static cupid_status ghost_share(struct cupid_pd_operator_private *op, const double *rec,
                                cupid_int gs) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int cap = 16, *slot = NULL, *canon = NULL, used = 0;
  while (cap < 2 * op->nseg) cap *= 2;
  CUPID_TRY(cupid_malloc((size_t)cap, sizeof *slot, "PD ghost segments", &slot));
  CUPID_TRY(cupid_malloc((size_t)op->nseg + 1, sizeof *canon, "PD ghost segments", &canon));
  for (cupid_int k = 0; k < cap; k++) slot[k] = -1;
  /* canon[k]: the first segment with k's content; the distinct ones' records count `used` */
  for (cupid_int k = 0; k < op->nseg; k++) {
    cupid_int h = (cupid_int)(segment_hash(rec, gs, &op->gseg[k]) & (uint64_t)(cap - 1));
    while (slot[h] >= 0 && !segments_equal(rec, gs, &op->gseg[slot[h]], &op->gseg[k]))
      h = (h + 1) & (cap - 1);
    if (slot[h] < 0) {
      slot[h] = k;
      used += op->gseg[k].n;
    }
    canon[k] = slot[h];
  }
  op->gstride = used + PD_GHOST_SLACK;
  CUPID_TRY(cupid_calloc(PD_GHOST_STRIDE * (size_t)op->gstride + PD_GHOST_SLACK, sizeof *op->ncorr,
                         "PD ghost corrections", &op->ncorr));
  double *C = op->ncorr + PD_GHOST_SLACK;
  cupid_int at = 0;
  for (cupid_int k = 0; k < op->nseg; k++) { /* canon[k] <= k: a first one is placed first */
    pd_ghost_seg *g = &op->gseg[k];
    if (canon[k] == k) {
      for (int c = 0; c < PD_GHOST_STRIDE; c++)
        memcpy(C + c * op->gstride + at, rec + c * gs + g->rank, (size_t)g->n * sizeof(double));
      g->rank = (int32_t)at;
      at += g->n;
    } else
      g->rank = op->gseg[canon[k]].rank;
  }
cleanup:
  cupid_free(&slot);
  cupid_free(&canon);
  return st;
}

cupid_status pd_ghosts_build(struct cupid_pd_operator_private *op) {
  const pd_stencil *S = &op->st;
  const cupid_int nn = op->nnodes;
  cupid_status st = CUPID_SUCCESS;
  int32_t *rank = NULL;
  double *rec = NULL;
  for (int s = 0; s < S->n; s++)
    for (int k = 0; k < 3; k++)
      CUPID_CHECK(S->off[3 * (S->n - 1 - s) + k] == -S->off[3 * s + k], CUPID_ERR_INTERNAL,
                  "the PD stencil is not symmetric at entry %d", s);
  CUPID_TRY(cupid_malloc((size_t)nn + 1, sizeof *rank, "PD ghost corrections", &rank));
  int32_t ne = 0;
  for (cupid_int i = 0; i < nn; i++) rank[i] = op->full[i] ? -1 : ne++;
  CUPID_TRY(ghost_segments(op, rank));
  CUPID_TRY(cupid_malloc(PD_GHOST_STRIDE * (size_t)ne + 1, sizeof *rec, "PD ghost corrections", &rec));
  ghost_records(op, rank, ne, rec);
  CUPID_TRY(ghost_share(op, rec, ne));
cleanup:
  cupid_free(&rank);
  cupid_free(&rec);
  return st;
}
