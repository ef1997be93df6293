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

/* Nodes reachable from every node through a list of offsets, summed; with partial, also
 * the sum over the nodes that miss some offset (near-surface families) and their count. */
static cupid_int count_present(const struct cupid_pd_grid_private *g, int n, const int32_t *off,
                               cupid_int *partial, cupid_int *npartial) {
  cupid_int total = 0, part = 0, np = 0;
#pragma omp parallel for schedule(static) reduction(+ : total, part, np) if (g->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < g->nnodes; i++) {
    const int32_t *q = g->ijk + 3 * i;
    cupid_int c = 0;
    for (int s = 0; s < n; s++)
      c += pd_grid_lookup(g, q[0] + off[3 * s], q[1] + off[3 * s + 1], q[2] + off[3 * s + 2]) >= 0;
    total += c;
    if (c < n) part += c, np++;
  }
  if (partial) *partial = part, *npartial = np;
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
  cupid_int edge_bonds = 0, edge_nodes = 0;
  est->bonds = count_present(grid, S.n, S.off, &edge_bonds, &edge_nodes);
  est->blocks = count_present(grid, nsum, sum, NULL, NULL);
  /* Operator (pd_families_build): a stencil entry per bond of the near-surface nodes and
   * their list, a flag and a family offset per node, ~6 doubles per node (m, constants,
   * dilatation self-weights); bulk bonds cost nothing. A surface correction keeps explicit
   * bond lists (neighbour + stencil index per bond) and PD_SF factors per node. */
  est->bytes_operator = edge_bonds * (int64_t)sizeof(int32_t) + edge_nodes * (int64_t)sizeof(cupid_int) +
                        (est->nodes + 1) * (int64_t)(sizeof(cupid_int) + 1) + est->nodes * 6 * 8;
  if (opts->surface_correction != CUPID_SURFACE_NONE)
    est->bytes_operator += est->bonds * (int64_t)(sizeof(cupid_int) + sizeof(int32_t)) +
                           (est->nodes + 1) * (int64_t)sizeof(cupid_int) + est->nodes * PD_SF * 8;
  est->bytes_matrix = (est->nodes + 1) * (int64_t)sizeof(cupid_int) +
                      est->blocks * (int64_t)(sizeof(cupid_int) + 9 * sizeof(double));
cleanup:
  cupid_free(&sum);
  pd_stencil_free(&S);
  return st;
}

static inline int neighbour_exists(const struct cupid_pd_grid_private *g, cupid_int i,
                                   const int32_t *o) {
  const int32_t *q = g->ijk + 3 * i;
  return pd_grid_lookup(g, q[0] + o[0], q[1] + o[1], q[2] + o[2]) >= 0;
}

/* Neighbour counts on the padded lattice, from a byte per cell: full flags, fptr[i + 1] =
 * the count of a non-full node (0 for full ones), the total returned. Nodes at consecutive
 * cells are counted together, the stencil outermost and the nodes innermost (vectorised:
 * node by node, the count was a chain of byte loads at scattered offsets). */
static cupid_int count_families(struct cupid_pd_operator_private *op, const unsigned char *present) {
  const pd_stencil *S = &op->st;
  const cupid_int nn = op->grid->nnodes;
  cupid_int total = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : total) if (nn > PD_OMP_MIN_NODES)
  for (cupid_int i0 = 0; i0 < nn; i0 += PD_RUN_MAX) {
    const cupid_int i1 = i0 + PD_RUN_MAX < nn ? i0 + PD_RUN_MAX : nn;
    int32_t cnt[PD_RUN_MAX];
    for (cupid_int i = i0; i < i1;) {
      const cupid_int c0 = pd_node_pcell(op, i);
      cupid_int e = i + 1; /* [i, e): consecutive cells */
      while (e < i1 && pd_node_pcell(op, e) == c0 + (e - i)) e++;
      const int len = (int)(e - i);
      for (int t = 0; t < len; t++) cnt[t] = 0;
      for (int s = 0; s < S->n; s++) {
        const unsigned char *restrict pc = present + c0 + op->pclin[s];
        for (int t = 0; t < len; t++) cnt[t] += pc[t];
      }
      for (int t = 0; t < len; t++) {
        op->full[i + t] = cnt[t] == S->n;
        op->fptr[i + t + 1] = op->full[i + t] ? 0 : cnt[t];
        total += cnt[t];
      }
      i = e;
    }
  }
  return total;
}

/* Families without per-bond storage for the bulk (pd_internal.h): cell offsets of the
 * stencil, full flags, the stencil entries of near-surface nodes, the padded lattice and
 * the runs. Two passes over nodes x stencil, O(nodes). */
cupid_status pd_families_build(struct cupid_pd_operator_private *op) {
  const struct cupid_pd_grid_private *g = op->grid;
  const pd_stencil *S = &op->st;
  const cupid_int nn = g->nnodes;
  CUPID_CALL(cupid_malloc((size_t)S->n, sizeof *op->clin, "PD stencil cell offsets", &op->clin));
  for (int s = 0; s < S->n; s++) {
    const int32_t *o = S->off + 3 * s;
    op->clin[s] = o[0] + g->n[0] * (o[1] + g->n[1] * (cupid_int)o[2]);
  }
  /* Padded lattice: reach per axis, padded sizes, padded cell offsets. */
  int32_t r[3] = {0, 0, 0};
  for (int s = 0; s < S->n; s++)
    for (int k = 0; k < 3; k++) {
      const int32_t o = S->off[3 * s + k] < 0 ? -S->off[3 * s + k] : S->off[3 * s + k];
      if (o > r[k]) r[k] = o;
    }
  double pcells = 1.0;
  for (int k = 0; k < 3; k++) {
    op->pr[k] = r[k];
    op->pn[k] = g->n[k] + 2 * (cupid_int)r[k];
    if (k == 0) op->pn[k] = (op->pn[k] + PD_ROW_ALIGN - 1) / PD_ROW_ALIGN * PD_ROW_ALIGN;
    pcells *= (double)op->pn[k];
  }
  op->padded = pcells <= PD_PAD_RATIO * (double)nn + 4096.0;
  CUPID_CALL(cupid_malloc((size_t)S->n, sizeof *op->pclin, "PD stencil cell offsets", &op->pclin));
  CUPID_CALL(cupid_malloc((size_t)S->n, sizeof *op->pclin_opp, "PD stencil cell offsets",
                          &op->pclin_opp));
  for (int s = 0; s < S->n; s++) {
    const int32_t *o = S->off + 3 * s;
    op->pclin[s] = o[0] + op->pn[0] * (o[1] + op->pn[1] * (cupid_int)o[2]);
  }
  for (int s = 0; s < S->n; s++) op->pclin_opp[s] = op->pclin[S->n - 1 - s];
  CUPID_CALL(pd_pair_plan_build(op));
  /* Which stencil neighbours exist: on the padded lattice from a byte per cell (a load a
   * neighbour, no bounds tests: a tenth of the grid lookups' time), else by lookups. */
  unsigned char *present = NULL;
  if (op->padded) {
    CUPID_CALL(cupid_calloc((size_t)pcells + 1, 1, "PD padded cells", &present));
#pragma omp parallel for schedule(static) if (nn > PD_OMP_MIN_NODES)
    for (cupid_int i = 0; i < nn; i++) present[pd_node_pcell(op, i)] = 1;
  }
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_malloc((size_t)nn, sizeof *op->full, "PD full-family flags", &op->full));
  CUPID_TRY(cupid_malloc((size_t)nn + 1, sizeof *op->fptr, "PD family offsets", &op->fptr));
  cupid_int *p = op->fptr, total = 0;
  p[0] = 0;
  if (present) total = count_families(op, present);
  else {
#pragma omp parallel for schedule(static) reduction(+ : total) if (nn > PD_OMP_MIN_NODES)
    for (cupid_int i = 0; i < nn; i++) {
      cupid_int c = 0;
      for (int s = 0; s < S->n; s++) c += neighbour_exists(g, i, S->off + 3 * s);
      op->full[i] = c == S->n;
      p[i + 1] = op->full[i] ? 0 : c;
      total += c;
    }
  }
  op->nbonds = total;
  for (cupid_int i = 0; i < nn; i++) p[i + 1] += p[i];
  CUPID_TRY(cupid_malloc((size_t)p[nn] + 1, sizeof *op->fidx, "PD near-surface families",
                         &op->fidx));
#pragma omp parallel for schedule(static) if (nn > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < nn; i++) {
    if (op->full[i]) continue;
    cupid_int b = p[i];
    if (present) { /* branch-free: every entry written at b, which only a present one
                      advances; past the node's last slot, into a scratch */
      const unsigned char *pc = present + pd_node_pcell(op, i);
      const cupid_int end = p[i + 1];
      int32_t scratch;
      for (int s = 0; s < S->n; s++) {
        *(b < end ? op->fidx + b : &scratch) = s;
        b += pc[op->pclin[s]];
      }
      continue;
    }
    for (int s = 0; s < S->n; s++)
      if (neighbour_exists(g, i, S->off + 3 * s)) op->fidx[b++] = s;
  }
cleanup:
  cupid_free(&present);
  CUPID_CALL(st);
  /* Runs: consecutive nodes at consecutive cells of one row, at most PD_RUN_MAX long (a new
   * run wherever the padded cell index jumps); full = every node of the run is full. */
  cupid_int nruns = 0;
  for (int pass = 0; pass < 2; pass++) {
    nruns = 0;
    cupid_int prev = -2;
    for (cupid_int i = 0; i < nn; i++) {
      const cupid_int cp = pd_node_pcell(op, i);
      pd_run *R = pass && nruns ? &op->runs[nruns - 1] : NULL;
      /* Padded, a row is one run (ghost bonds corrected per node: fewer, longer vector loops beat
       * splitting off the few near-surface nodes); else full and partial nodes split. */
      const int joins = i > 0 && cp == prev + 1 && (op->padded || op->full[i] == op->full[i - 1]);
      prev = cp;
      if (joins && (!pass || R->len < PD_RUN_MAX)) {
        if (pass) {
          R->len++;
          R->full &= op->full[i];
        }
        continue;
      }
      if (pass)
        op->runs[nruns] = (pd_run){.i0 = i, .c0 = pd_node_cell(g, i), .cp0 = cp, .len = 1,
                                   .full = op->full[i]};
      nruns++;
    }
    /* Runs split at PD_RUN_MAX add at most nn / PD_RUN_MAX. */
    if (!pass)
      CUPID_CALL(cupid_malloc((size_t)(nruns + nn / PD_RUN_MAX + 1), sizeof *op->runs, "PD runs", &op->runs));
  }
  op->nruns = nruns;
  return CUPID_SUCCESS;
}

/* Full nodes: every neighbour exists and node order follows cell order, so the extremes
 * are at the stencil entries of smallest and largest cell offset. */
void pd_neighbour_span(const struct cupid_pd_operator_private *op, cupid_int first, cupid_int last,
                       cupid_int *lo, cupid_int *hi) {
  const pd_stencil *S = &op->st;
  int smin = 0, smax = 0;
  for (int s = 1; s < S->n; s++) {
    if (op->clin[s] < op->clin[smin]) smin = s;
    if (op->clin[s] > op->clin[smax]) smax = s;
  }
  cupid_int a = first, b = last;
  for (cupid_int i = first; i < last; i++) {
    const pd_family F = pd_family_of(op, i);
    if (F.n == 0) continue;
    cupid_int jmin, jmax;
    if (!F.s) {
      jmin = pd_family_node(op, &F, smin);
      jmax = pd_family_node(op, &F, smax);
    } else { /* entries in stencil order = neighbours ascending */
      jmin = pd_family_node(op, &F, F.s[0]);
      jmax = pd_family_node(op, &F, F.s[F.n - 1]);
    }
    if (jmin < a) a = jmin;
    if (jmax + 1 > b) b = jmax + 1;
  }
  *lo = a;
  *hi = b;
}
