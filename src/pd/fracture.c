/* Fracture in the PD operator (docs/theory.md, section Fracture; shared/reference/fracture.md):
 * bonds removed by pre-cracks or broken by a criterion, the damage of a node, and the energy
 * a break dissipates.
 *
 * A removed bond is a bit in a per-node mask of stencil entries (pd_internal.h), set for both
 * of its ends; the families stay the geometric ones, so the storage and the stencil sweeps
 * of the intact body are untouched. Removing bonds recomputes the weighted volume m of the
 * two nodes over their intact bonds (broken bonds leave the family sums, fracture.md), takes
 * them and their families out of the stencil path's uniform-b stretches (uniform.c) and
 * bumps op->gen so that the stencil path refreshes its copies of mu/m. A node left without
 * any bond gets m = +inf: its dilatation, its a = kappa theta/m and b = mu/m are then 0, and
 * it carries no force (it flies free, as in every PD code). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "pd/pd_internal.h"

void pd_fracture_free(struct cupid_pd_operator_private *op) {
  cupid_free(&op->bslot);
  cupid_free(&op->bmask);
  cupid_free(&op->bgsum);
  cupid_free(&op->bcount);
  cupid_free(&op->bpre);
  op->nslots = op->slot_cap = 0;
  op->nbroken = 0;
  cupid_free(&op->changed);
  op->n_changed = op->changed_cap = 0;
  op->changed_all = 0;
}

static cupid_status fracture_init(struct cupid_pd_operator_private *op) {
  if (op->bslot) return CUPID_SUCCESS;
  /* Bond-based: a bond's pair coefficient carries its surface factor (G_ij + G_ji) / 2, and a
   * broken bond takes it out with its term. LPS: a broken bond's dilatation weight would leave
   * the corrected self-weight (gself, rebuilt with the D factors) by its raw wxn (bgsum), and
   * m is summed again over the intact family, against which the factors were not fitted. */
  CUPID_CHECK(op->surface == CUPID_SURFACE_NONE || op->model == CUPID_PD_BOND,
              CUPID_ERR_UNSUPPORTED, "pre-cracks and bond breaking with surface_correction: energy need model: bond (LPS: "
              "the corrected dilatation is not kept as bonds break)");
  CUPID_CALL(cupid_malloc((size_t)op->nnodes, sizeof *op->bslot, "PD broken-bond slots", &op->bslot));
  for (cupid_int i = 0; i < op->nnodes; i++) op->bslot[i] = -1;
  op->bwords = (op->st.n + 63) / 64;
  return CUPID_SUCCESS;
}

/* The slot of node i, made if it has none (grown by doubling). */
static cupid_status slot_of(struct cupid_pd_operator_private *op, cupid_int i, int32_t *slot) {
  if (op->bslot[i] >= 0) {
    *slot = op->bslot[i];
    return CUPID_SUCCESS;
  }
  if (op->nslots == op->slot_cap) {
    CUPID_CHECK(op->slot_cap < INT32_MAX / 2, CUPID_ERR_MEMORY, "too many damaged PD nodes");
    const int32_t cap = op->slot_cap ? 2 * op->slot_cap : 256;
    const size_t w = (size_t)op->bwords;
    uint64_t *mask = NULL;
    double *g = NULL;
    int *count = NULL, *pre = NULL;
    CUPID_CALL(cupid_calloc((size_t)cap * w, sizeof *mask, "PD broken-bond masks", &mask));
    if (cupid_calloc(3 * (size_t)cap, sizeof *g, "PD broken-bond weights", &g) != CUPID_SUCCESS ||
        cupid_calloc((size_t)cap, sizeof *count, "PD broken-bond counts", &count) != CUPID_SUCCESS ||
        cupid_calloc((size_t)cap, sizeof *pre, "PD broken-bond counts", &pre) != CUPID_SUCCESS) {
      cupid_free(&mask);
      cupid_free(&g);
      cupid_free(&count);
      return CUPID_ERR_MEMORY;
    }
    if (op->nslots) {
      memcpy(mask, op->bmask, (size_t)op->nslots * w * sizeof *mask);
      memcpy(g, op->bgsum, 3 * (size_t)op->nslots * sizeof *g);
      memcpy(count, op->bcount, (size_t)op->nslots * sizeof *count);
      memcpy(pre, op->bpre, (size_t)op->nslots * sizeof *pre);
    }
    cupid_free(&op->bmask);
    cupid_free(&op->bgsum);
    cupid_free(&op->bcount);
    cupid_free(&op->bpre);
    op->bmask = mask, op->bgsum = g, op->bcount = count, op->bpre = pre;
    op->slot_cap = cap;
  }
  *slot = op->bslot[i] = op->nslots++;
  return CUPID_SUCCESS;
}

/* Mark entry s of node i (neighbour j) broken (one direction; pre: by a pre-crack); 0 if it
 * already was. */
static cupid_status mark_broken(struct cupid_pd_operator_private *op, cupid_int i, cupid_int j, int s,
                                int pre, int *fresh) {
  int32_t k = -1;
  CUPID_CALL(slot_of(op, i, &k));
  uint64_t *word = op->bmask + (size_t)k * (size_t)op->bwords + (size_t)(s >> 6);
  const uint64_t bit = (uint64_t)1 << (s & 63);
  *fresh = !(*word & bit);
  if (!*fresh) return CUPID_SUCCESS;
  *word |= bit;
  op->bcount[k]++;
  op->bpre[k] += pre;
  for (int c = 0; c < 3; c++) op->bgsum[3 * (size_t)k + c] += op->st.wxn[3 * s + c] * pd_phi(op, j);
  return CUPID_SUCCESS;
}

/* m_i over the intact family, in stencil order as node_data sums it (operator.c), or +inf
 * for a node without any intact bond. */
static void weighted_volume(struct cupid_pd_operator_private *op, cupid_int i) {
  const pd_stencil *S = &op->st;
  const pd_family F = pd_family_of(op, i);
  double m = 0.0;
  int intact = 0;
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    if (pd_bond_broken(op, i, s)) continue;
    m += S->wb[s] * S->x[s] * S->x[s] * op->V * pd_phi(op, pd_family_node(op, &F, s));
    intact++;
  }
  op->m[i] = intact ? m : INFINITY;
}

static int cmp_int(const void *a, const void *b);

void pd_record_changed(struct cupid_pd_operator_private *op, cupid_int i, cupid_int j) {
  if (!op->changed_on || op->changed_all) return;
  if (op->n_changed + 2 > op->changed_cap) {
    const size_t cap = op->changed_cap ? 2 * op->changed_cap : 1024;
    if (cupid_realloc(cap, sizeof *op->changed, "changed rows", &op->changed) != CUPID_SUCCESS) {
      cupid_error_clear(); /* the record is lost, not the bond: every row counts as changed */
      op->changed_all = 1;
      return;
    }
    op->changed_cap = cap;
  }
  op->changed[op->n_changed++] = i;
  op->changed[op->n_changed++] = j;
}

cupid_status cupid_pd_operator_take_changed(cupid_pd_operator op, cupid_int **nodes, cupid_int *n,
                                            int *all) {
  CUPID_CHECK(op && nodes && n && all, CUPID_ERR_ARGUMENT,
              "take_changed needs an operator and three outputs");
  *nodes = NULL, *n = 0;
  /* LPS: a bond enters the dilatations of both its families, whose neighbours' rows change */
  *all = op->changed_all || !op->changed_on || op->model != CUPID_PD_BOND;
  cupid_status st = CUPID_SUCCESS;
  if (!*all && op->n_changed) {
    qsort(op->changed, op->n_changed, sizeof *op->changed, cmp_int);
    size_t m = 0;
    for (size_t k = 0; k < op->n_changed; k++)
      if (m == 0 || op->changed[m - 1] != op->changed[k]) op->changed[m++] = op->changed[k];
    st = cupid_malloc(m, sizeof **nodes, "changed rows", nodes);
    if (st == CUPID_SUCCESS) memcpy(*nodes, op->changed, m * sizeof **nodes), *n = (cupid_int)m;
  }
  op->n_changed = 0;
  op->changed_all = 0;
  op->changed_on = 1;
  return st;
}

/* Remove the bond of node i at stencil entry s (both directions). */
static cupid_status remove_bond(struct cupid_pd_operator_private *op, cupid_int i, int s, int pre,
                                int *removed) {
  const pd_family F = pd_family_of(op, i);
  const cupid_int j = pd_family_node(op, &F, s);
  int a, b;
  CUPID_CALL(mark_broken(op, i, j, s, pre, &a));
  CUPID_CALL(mark_broken(op, j, i, op->st.n - 1 - s, pre, &b));
  *removed = a;
  if (!a) return CUPID_SUCCESS;
  op->nbroken++;
  pd_record_changed(op, i, j);
  weighted_volume(op, i);
  weighted_volume(op, j);
  pd_uniform_exclude(op, i); /* b = mu/m of i and j changed: no longer uniform around them */
  pd_uniform_exclude(op, j);
  op->gen++;
  return CUPID_SUCCESS;
}

/* ---- Pre-cracks ---- */

/* 1 if the segment from p to q crosses the rectangle: its ends lie strictly on opposite
 * sides of the plane, or one lies on it and the other on the positive side (a plane through
 * a layer of nodes leaves the layer with the negative side, and every bond across is cut
 * once), and the crossing point lies within the bounds (inclusive). Nodes sit at cell
 * centres, so a plane between two layers, the usual case, meets none. */
static int segment_crosses(const cupid_pd_precrack *c, const double *p, const double *q) {
  const int a = c->normal;
  const double dp = p[a] - c->at, dq = q[a] - c->at;
  if ((dp < 0 && dq < 0) || (dp > 0 && dq > 0) || dp == dq) return 0;
  if ((dp == 0 && dq < 0) || (dq == 0 && dp < 0)) return 0;
  const double t = dp / (dp - dq);
  for (int b = 0; b < 3; b++) {
    if (b == a) continue;
    const double x = p[b] + t * (q[b] - p[b]);
    if (x < c->lo[b] || x > c->hi[b]) return 0;
  }
  return 1;
}

cupid_status cupid_pd_operator_precrack(cupid_pd_operator op, const cupid_pd_precrack *crack,
                                        cupid_int *removed) {
  CUPID_CHECK(op && crack && removed, CUPID_ERR_ARGUMENT, "precrack needs operator, crack, count");
  CUPID_CHECK(crack->normal >= 0 && crack->normal < 3 && isfinite(crack->at), CUPID_ERR_ARGUMENT,
              "a pre-crack needs a normal axis 0, 1 or 2 and a finite position");
  *removed = 0;
  CUPID_CALL(fracture_init(op));
  const double *x = op->grid->coords;
  const pd_stencil *S = &op->st;
  const int half = S->n / 2; /* entries s >= half reach higher node indices: each bond once */
  for (cupid_int i = 0; i < op->nnodes; i++) {
    const pd_family F = pd_family_of(op, i);
    for (int q = 0; q < F.n; q++) {
      const int s = pd_family_entry(&F, q);
      if (s < half) continue;
      const cupid_int j = pd_family_node(op, &F, s);
      if (!segment_crosses(crack, x + 3 * i, x + 3 * j)) continue;
      int fresh;
      CUPID_CALL(remove_bond(op, i, s, 1, &fresh));
      *removed += fresh;
    }
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_pd_operator_precrack_crossing(const cupid_pd_operator op,
                                                 const cupid_pd_precrack *crack, cupid_int *count) {
  CUPID_CHECK(op && crack && count, CUPID_ERR_ARGUMENT, "precrack_crossing needs its arguments");
  CUPID_CHECK(crack->normal >= 0 && crack->normal < 3 && isfinite(crack->at), CUPID_ERR_ARGUMENT,
              "a pre-crack needs a normal axis 0, 1 or 2 and a finite position");
  const double *x = op->grid->coords;
  const pd_stencil *S = &op->st;
  const int half = S->n / 2;
  cupid_int n = 0;
  for (cupid_int i = 0; i < op->nnodes; i++) {
    const pd_family F = pd_family_of(op, i);
    for (int q = 0; q < F.n; q++) {
      const int s = pd_family_entry(&F, q);
      if (s >= half && segment_crosses(crack, x + 3 * i, x + 3 * pd_family_node(op, &F, s))) n++;
    }
  }
  *count = n;
  return CUPID_SUCCESS;
}

/* ---- Breaking ---- */

/* 1 if node i's share is counted (cupid_pd_fracture_options.count_first/last). */
static int counted(const cupid_pd_fracture_options *o, cupid_int i) {
  return o->count_last <= o->count_first || (i >= o->count_first && i < o->count_last);
}

/* 1 if the bond i-j may break: neither end protected, and no no-fail box holds both. */
static int breakable(const cupid_pd_fracture_options *o, cupid_int i, cupid_int j) {
  if (o->protect && (o->protect[i] || o->protect[j])) return 0;
  if (o->no_fail && (o->no_fail[i] & o->no_fail[j])) return 0;
  return 1;
}

/* Node energy over its intact bonds (the summand of pd_lps_energy / pd_bond_energy), so
 * that the strain energy a set of breaks removes is the change of its nodes' energies. */
static double node_energy(const struct cupid_pd_operator_private *op, const double *u, cupid_int i) {
  const pd_stencil *S = &op->st;
  const pd_family F = pd_family_of(op, i);
  double q = 0.0, t = 0.0;
  for (int k = 0; k < F.n; k++) {
    const int s = pd_family_entry(&F, k);
    if (pd_bond_broken(op, i, s)) continue;
    const cupid_int j = pd_family_node(op, &F, s);
    const double e = pd_extension(S->nrm + 3 * s, u, i, j);
    if (op->model == CUPID_PD_BOND) {
      q += 0.25 * pd_pair_coefficient(op, i, j, s) * e * e;
    } else {
      q += S->wb[s] * pd_phi(op, j) * e * e;
      t += S->wb[s] * S->x[s] * pd_phi(op, j) * e;
    }
  }
  if (op->model == CUPID_PD_BOND) return q;
  if (isinf(op->m[i])) return 0.0;
  const double theta = 3.0 * op->V * t / op->m[i];
  return op->V * pd_phi(op, i) *
         (op->kappa[i] / 6.0 * theta * theta + 7.5 * op->mu[i] / op->m[i] * q * op->V);
}

/* The critical-energy test of the LPS bond i-j at entry s (fracture.md: w = 1/4 |t_ij +
 * t_ji| |e| against 4 G0 / (pi delta^4), t the scalar force states along n, linearised). */
static double bond_energy_density(const struct cupid_pd_operator_private *op, const double *theta,
                                  cupid_int i, cupid_int j, int s, double e) {
  const pd_stencil *S = &op->st;
  const double om = cupid_pd_influence(op->influence, S->x[s], op->delta);
  const double ai = op->kappa[i] * theta[i] / op->m[i], aj = op->kappa[j] * theta[j] / op->m[j];
  const double bi = op->mu[i] / op->m[i], bj = op->mu[j] / op->m[j];
  const double t = om * ((ai + aj) * S->x[s] + 15.0 * (bi + bj) * e);
  return 0.25 * fabs(t) * fabs(e);
}

static inline double stretch_limit(const cupid_pd_fracture_options *o, cupid_int i, cupid_int j) {
  return o->node_stretch ? fmin(o->node_stretch[i], o->node_stretch[j]) : o->critical_stretch;
}

typedef struct {
  cupid_int *i;
  int *s;
  size_t n, cap;
} bond_list;

static int list_push(bond_list *L, cupid_int i, int s) {
  if (L->n == L->cap) {
    size_t cap = L->cap ? 2 * L->cap : 64;
    cupid_int *a = realloc(L->i, cap * sizeof *a);
    if (!a) return 0;
    L->i = a;
    int *b = realloc(L->s, cap * sizeof *b);
    if (!b) return 0;
    L->s = b;
    L->cap = cap;
  }
  L->i[L->n] = i;
  L->s[L->n++] = s;
  return 1;
}

/* Tests compare the vectorised scan with the plain one (pd_fracture_force_plain_scan). */
static atomic_int plain_scan;

void pd_fracture_force_plain_scan(int on) { atomic_store(&plain_scan, on); }

/* The neighbour of node i at stencil entry s, or -1 when i's family lacks it. */
static cupid_int family_neighbour(const struct cupid_pd_operator_private *op, cupid_int i, int s) {
  const pd_family F = pd_family_of(op, i);
  if (F.s) {
    int a = 0, b = F.n; /* the stored entries ascend */
    while (a < b) {
      const int m = a + (b - a) / 2;
      if (F.s[m] < s) a = m + 1;
      else b = m;
    }
    if (a == F.n || F.s[a] != s) return -1;
  }
  return pd_family_node(op, &F, s);
}

/* The stretch criterion through the stencil path's vectorised scan (pd_stencil_stretch_scan):
 * its candidates, with a margin of 1e-8 below the smallest limit for the rounding of its
 * shifted copy of u, confirmed one by one on u as the plain scan tests them, so that both give
 * the same bonds in the same order. *done = 0 when the scan gave up. */
static cupid_status find_over_scan(const struct cupid_pd_operator_private *op, const double *u,
                                   const cupid_pd_fracture_options *o, bond_list *out, int *done) {
  double lim = o->critical_stretch;
  if (o->node_stretch) {
    lim = INFINITY;
    for (cupid_int i = 0; i < op->nnodes; i++) lim = fmin(lim, o->node_stretch[i]);
  }
  pd_hit *hits = NULL;
  cupid_int n = 0;
  CUPID_CALL(pd_stencil_stretch_scan(op, u, lim * (1.0 - 1e-8), &hits, &n));
  *done = n >= 0;
  cupid_status st = CUPID_SUCCESS;
  for (cupid_int k = 0; k < n && st == CUPID_SUCCESS; k++) {
    const cupid_int i = hits[k].i;
    const int s = hits[k].s;
    const cupid_int j = family_neighbour(op, i, s);
    if (j < 0 || pd_bond_broken(op, i, s)) continue;
    const double e = pd_extension(op->st.nrm + 3 * s, u, i, j);
    if (o->owned_only && !counted(o, i)) continue;
    if (e > stretch_limit(o, i, j) * op->st.x[s] && breakable(o, i, j) && !list_push(out, i, s))
      st = CUPID_ERROR(CUPID_ERR_MEMORY, "out of memory for broken bonds");
  }
  cupid_free(&hits);
  return st;
}

/* The bonds over their limit, each once (from its lower node), in ascending node order
 * whatever the thread count: each thread scans a contiguous block of nodes (static schedule)
 * into its own list and the lists are joined in thread order. The stretch criterion takes the
 * stencil path's vectorised scan when the operator has one. */
static cupid_status find_over(const struct cupid_pd_operator_private *op, const double *u,
                              const double *theta, const cupid_pd_fracture_options *o,
                              bond_list *out) {
  const pd_stencil *S = &op->st;
  const int half = S->n / 2;
  if (o->criterion == CUPID_PD_BREAK_STRETCH && !op->stencil_off && op->dim == 3 &&
      !atomic_load(&plain_scan)) {
    int done = 0;
    CUPID_CALL(find_over_scan(op, u, o, out, &done));
    if (done) return CUPID_SUCCESS;
  }
  int nt = 1;
#ifdef _OPENMP
  nt = op->nnodes > PD_OMP_MIN_NODES ? omp_get_max_threads() : 1;
#endif
  bond_list *per = calloc((size_t)nt, sizeof *per);
  CUPID_CHECK(per, CUPID_ERR_MEMORY, "out of memory for the bond check");
  int failed = 0;
#pragma omp parallel num_threads(nt)
  {
    int tid = 0;
#ifdef _OPENMP
    tid = omp_get_thread_num();
#endif
    bond_list *L = &per[tid];
#pragma omp for schedule(static)
    for (cupid_int i = 0; i < op->nnodes; i++) {
      if (o->owned_only && !counted(o, i)) continue;
      const pd_family F = pd_family_of(op, i);
      for (int q = 0; q < F.n; q++) {
        const int s = pd_family_entry(&F, q);
        if (s < half || pd_bond_broken(op, i, s)) continue;
        const cupid_int j = pd_family_node(op, &F, s);
        const double e = pd_extension(S->nrm + 3 * s, u, i, j);
        /* strictly over: a bond at exactly its limit holds */
        const int over = o->criterion == CUPID_PD_BREAK_STRETCH
                             ? e > stretch_limit(o, i, j) * S->x[s]
                             : bond_energy_density(op, theta, i, j, s, e) > o->critical_energy;
        if (over && breakable(o, i, j) && !list_push(L, i, s)) failed = 1;
      }
    }
  }
  cupid_status st = failed ? CUPID_ERROR(CUPID_ERR_MEMORY, "out of memory for broken bonds")
                           : CUPID_SUCCESS;
  for (int t = 0; t < nt; t++) {
    for (size_t k = 0; k < per[t].n && st == CUPID_SUCCESS; k++)
      if (!list_push(out, per[t].i[k], per[t].s[k]))
        st = CUPID_ERROR(CUPID_ERR_MEMORY, "out of memory for broken bonds");
    free(per[t].i);
    free(per[t].s);
  }
  free(per);
  return st;
}

static int cmp_int(const void *a, const void *b) {
  const cupid_int x = *(const cupid_int *)a, y = *(const cupid_int *)b;
  return (x > y) - (x < y);
}

/* K u without the bond i-j at entry s (bond-based): its energy C e^2 / 2 (node_energy) has
 * the gradient -C e n at u_i and +C e n at u_j. In list order, so the same in any thread
 * count. */
static void subtract_bond_force(const struct cupid_pd_operator_private *op, const double *u,
                                cupid_int i, int s, double *ku) {
  const pd_family F = pd_family_of(op, i);
  const cupid_int j = pd_family_node(op, &F, s);
  const double *n = op->st.nrm + 3 * s;
  const double ce = pd_pair_coefficient(op, i, j, s) * pd_extension(n, u, i, j);
  for (int a = 0; a < 3; a++) {
    ku[3 * i + a] += ce * n[a];
    ku[3 * j + a] -= ce * n[a];
  }
}

/* Break the listed bonds; *dissipated = the strain energy they held (the drop of their
 * counted nodes' energies, at u). */
static cupid_status break_list(struct cupid_pd_operator_private *op, const double *u,
                               const bond_list *L, const cupid_pd_fracture_options *o,
                               double *dissipated) {
  *dissipated = 0.0;
  if (L->n == 0) return CUPID_SUCCESS;
  cupid_int *nodes = malloc(2 * L->n * sizeof *nodes);
  CUPID_CHECK(nodes, CUPID_ERR_MEMORY, "out of memory for broken bonds");
  size_t nn = 0;
  for (size_t k = 0; k < L->n; k++) {
    const pd_family F = pd_family_of(op, L->i[k]);
    nodes[nn++] = L->i[k];
    nodes[nn++] = pd_family_node(op, &F, L->s[k]);
  }
  qsort(nodes, nn, sizeof *nodes, cmp_int);
  size_t u_n = 0;
  for (size_t k = 0; k < nn; k++)
    if ((u_n == 0 || nodes[u_n - 1] != nodes[k]) && counted(o, nodes[k])) nodes[u_n++] = nodes[k];
  if (o->ku && op->model == CUPID_PD_BOND)
    for (size_t k = 0; k < L->n; k++) subtract_bond_force(op, u, L->i[k], L->s[k], o->ku);
  double before = 0.0, after = 0.0;
  for (size_t k = 0; k < u_n; k++) before += node_energy(op, u, nodes[k]);
  cupid_status st = CUPID_SUCCESS;
  for (size_t k = 0; k < L->n && st == CUPID_SUCCESS; k++) {
    int fresh;
    st = remove_bond(op, L->i[k], L->s[k], 0, &fresh);
  }
  for (size_t k = 0; k < u_n; k++) after += node_energy(op, u, nodes[k]);
  free(nodes);
  *dissipated = before - after;
  return st;
}

static double bond_ratio(const struct cupid_pd_operator_private *op, const double *theta,
                         const cupid_pd_fracture_options *o, const double *u, cupid_int i,
                         cupid_int j, int s);

/* only_most: keep the most critical bond of the list (largest ratio to its limit), the first
 * in list order (ascending nodes) among those within CUPID_PD_TIE of the largest, which is
 * o->most_top when given (a slab's share of a whole grid). */
static cupid_status keep_most_critical(const struct cupid_pd_operator_private *op,
                                       const double *theta, const cupid_pd_fracture_options *o,
                                       const double *u, bond_list *L) {
  double *r = NULL, top = o->most_top;
  CUPID_CALL(cupid_malloc(L->n, sizeof *r, "bond ratios", &r));
  for (size_t k = 0; k < L->n; k++) {
    const pd_family F = pd_family_of(op, L->i[k]);
    r[k] = bond_ratio(op, theta, o, u, L->i[k], pd_family_node(op, &F, L->s[k]), L->s[k]);
    if (r[k] > top) top = r[k];
  }
  size_t best = 0;
  while (best + 1 < L->n && !(r[best] >= top * (1.0 - CUPID_PD_TIE))) best++;
  cupid_free(&r);
  L->i[0] = L->i[best], L->s[0] = L->s[best], L->n = 1;
  return CUPID_SUCCESS;
}

cupid_status cupid_pd_operator_break_bonds(cupid_pd_operator op, const double *u,
                                           const cupid_pd_fracture_options *o, int only_most,
                                           cupid_int *broken, double *dissipated) {
  CUPID_CHECK(op && u && o && broken && dissipated, CUPID_ERR_ARGUMENT,
              "break_bonds needs operator, displacement, options and outputs");
  CUPID_CHECK(o->criterion == CUPID_PD_BREAK_STRETCH ? o->critical_stretch > 0 || o->node_stretch
                                                     : o->critical_energy > 0,
              CUPID_ERR_ARGUMENT, "break_bonds needs a positive critical value");
  CUPID_CHECK(o->criterion == CUPID_PD_BREAK_STRETCH || op->model == CUPID_PD_LPS,
              CUPID_ERR_UNSUPPORTED, "the critical-energy criterion needs the LPS model");
  *broken = 0;
  *dissipated = 0.0;
  CUPID_CALL(fracture_init(op));
  double *theta = NULL;
  bond_list L = {0};
  cupid_status st = CUPID_SUCCESS;
  if (o->criterion == CUPID_PD_BREAK_ENERGY) {
    CUPID_TRY(cupid_malloc((size_t)op->nnodes, sizeof *theta, "PD dilatations", &theta));
    pd_lps_dilatation(op, 0, op->nnodes, u, theta);
  }
  CUPID_TRY(find_over(op, u, theta, o, &L));
  if (only_most && L.n > 0) CUPID_TRY(keep_most_critical(op, theta, o, u, &L));
  CUPID_TRY(break_list(op, u, &L, o, dissipated));
  for (size_t k = 0; k < L.n; k++) *broken += counted(o, L.i[k]);
cleanup:
  free(L.i);
  free(L.s);
  cupid_free(&theta);
  return st;
}

/* ---- The broken bonds of a slab's nodes, exchanged between MPI ranks ---- */

int cupid_pd_operator_broken_words(const cupid_pd_operator op) {
  return op ? (op->st.n - op->st.n / 2 + 31) / 32 : 0;
}

void cupid_pd_operator_pack_broken(const cupid_pd_operator op, cupid_int first, cupid_int last,
                                   double *words) {
  const int half = op->st.n / 2, nw = cupid_pd_operator_broken_words(op);
  for (cupid_int i = first; i < last; i++) {
    double *w = words + (size_t)(i - first) * (size_t)nw;
    for (int k = 0; k < nw; k++) w[k] = 0.0;
    if (!op->bslot || op->bslot[i] < 0) continue;
    uint32_t bits[8] = {0};
    for (int s = half; s < op->st.n; s++)
      if (pd_bond_broken(op, i, s)) bits[(s - half) >> 5] |= (uint32_t)1 << ((s - half) & 31);
    for (int k = 0; k < nw; k++) w[k] = (double)bits[k]; /* exact: 32-bit integers */
  }
}

cupid_status cupid_pd_operator_unpack_broken(cupid_pd_operator op, cupid_int first,
                                             cupid_int last, const double *words,
                                             const double *u, const cupid_pd_fracture_options *o,
                                             cupid_int *added, double *dissipated) {
  CUPID_CHECK(op && words && u && o && added && dissipated, CUPID_ERR_ARGUMENT,
              "unpack_broken needs operator, words, displacement, options and outputs");
  CUPID_CHECK(op->st.n - op->st.n / 2 <= 256, CUPID_ERR_UNSUPPORTED,
              "unpack_broken: more than 512 stencil entries");
  *added = 0, *dissipated = 0.0;
  CUPID_CALL(fracture_init(op));
  const int half = op->st.n / 2, nw = cupid_pd_operator_broken_words(op);
  bond_list L = {0};
  cupid_status st = CUPID_SUCCESS;
  for (cupid_int i = first; i < last && st == CUPID_SUCCESS; i++) {
    const double *w = words + (size_t)(i - first) * (size_t)nw;
    int any = 0;
    for (int k = 0; k < nw; k++) any |= w[k] != 0.0;
    if (!any) continue;
    const pd_family F = pd_family_of(op, i);
    for (int q = 0; q < F.n; q++) {
      const int s = pd_family_entry(&F, q);
      if (s < half || pd_bond_broken(op, i, s)) continue;
      const uint32_t bits = (uint32_t)w[(s - half) >> 5];
      if ((bits >> ((s - half) & 31)) & 1u)
        if (!list_push(&L, i, s)) st = CUPID_ERROR(CUPID_ERR_MEMORY, "out of memory for broken bonds");
    }
  }
  if (st == CUPID_SUCCESS) st = break_list(op, u, &L, o, dissipated);
  *added = (cupid_int)L.n;
  free(L.i);
  free(L.s);
  return st;
}

cupid_status cupid_pd_operator_copy_broken(cupid_pd_operator dst, const cupid_pd_operator src) {
  CUPID_CHECK(dst && src && dst->grid == src->grid && dst->st.n == src->st.n, CUPID_ERR_ARGUMENT,
              "copy_broken needs two operators on one grid with one stencil");
  return cupid_pd_operator_copy_broken_mapped(dst, src, NULL);
}

/* 1 if entry s of the stencil is in the family (a full family has them all). */
static int family_has(const pd_family *F, int s) {
  if (!F->s) return 1;
  for (int q = 0; q < F->n; q++)
    if (F->s[q] == s) return 1;
  return 0;
}

/* The stencils of two operators are one when their entries are the same lattice offsets in the
 * same order (the same horizon, spacing, dimension and partial-volume rule build them so). */
static int same_stencil(const struct cupid_pd_operator_private *a,
                        const struct cupid_pd_operator_private *b) {
  if (a->st.n != b->st.n || a->dim != b->dim || fabs(a->h - b->h) > 1e-12 * a->h) return 0;
  for (int s = 0; s < a->st.n; s++)
    for (int c = 0; c < 3; c++)
      if (a->st.off[3 * s + c] != b->st.off[3 * s + c]) return 0;
  return 1;
}

cupid_status cupid_pd_operator_copy_broken_mapped(cupid_pd_operator dst, const cupid_pd_operator src,
                                                  const cupid_int *map) {
  CUPID_CHECK(dst && src && same_stencil(dst, src), CUPID_ERR_ARGUMENT,
              "copy_broken: the two operators need one stencil (the same horizon, spacing and "
              "partial-volume rule)");
  CUPID_CHECK(map || dst->grid == src->grid, CUPID_ERR_ARGUMENT,
              "copy_broken: operators on two grids need the map of the nodes");
  if (!src->bslot || (!map && dst->nbroken == src->nbroken)) return CUPID_SUCCESS;
  CUPID_CALL(fracture_init(dst));
  const int half = src->st.n / 2;
  for (cupid_int i = 0; i < src->nnodes; i++) {
    const int32_t k = src->bslot[i];
    if (k < 0) continue;
    const cupid_int I = map ? map[i] : i;
    const uint64_t *mask = src->bmask + (size_t)k * (size_t)src->bwords;
    for (int w = 0; w < src->bwords; w++)
      for (uint64_t bits = mask[w]; bits; bits &= bits - 1) {
        const int s = 64 * w + __builtin_ctzll(bits);
        /* each bond from its lower node; through a map, from either (dst's order may differ) */
        if ((!map && s < half) || pd_bond_broken(dst, I, s)) continue;
        if (map) { /* the bond must join the images of its ends */
          const pd_family Fs = pd_family_of(src, i), Fd = pd_family_of(dst, I);
          const cupid_int j = pd_family_node(src, &Fs, s);
          const cupid_int J = family_has(&Fd, s) ? pd_family_node(dst, &Fd, s) : -1;
          CUPID_CHECK(j >= 0 && J >= 0 && map[j] == J, CUPID_ERR_ARGUMENT,
                      "copy_broken: the map does not carry bond (%lld, %lld) onto the other grid",
                      (long long)i, (long long)j);
        }
        int fresh; /* dst counts them as broken: the copy keeps no pre-crack tally */
        CUPID_CALL(remove_bond(dst, I, s, 0, &fresh));
      }
  }
  return CUPID_SUCCESS;
}

cupid_int cupid_pd_operator_num_broken(const cupid_pd_operator op) { return op ? op->nbroken : 0; }

/* The criterion's ratio to its limit of the intact bond (i, s) to j at u (theta: the
 * dilatations, energy criterion only): linear in u for both criteria (the energy's square root). */
static double bond_ratio(const struct cupid_pd_operator_private *op, const double *theta,
                         const cupid_pd_fracture_options *o, const double *u, cupid_int i,
                         cupid_int j, int s) {
  const pd_stencil *S = &op->st;
  const double e = pd_extension(S->nrm + 3 * s, u, i, j);
  return o->criterion == CUPID_PD_BREAK_STRETCH
             ? e / (stretch_limit(o, i, j) * S->x[s])
             : sqrt(bond_energy_density(op, theta, i, j, s, e) / o->critical_energy);
}

/* Over every intact bond (each once) that scanned() reads: the largest ratio, the count over
 * 1 and, for the blocked bonds, the protected end of the largest. */
typedef struct {
  double ratio;
  cupid_int over, node;
} ratio_scan;

/* The bonds a scan reads: the breakable ones, or (blocked) those that only the protection (a
 * coupling zone) keeps, not a no-fail box. */
static int scanned(const cupid_pd_fracture_options *o, int blocked, cupid_int i, cupid_int j) {
  if (!blocked) return breakable(o, i, j);
  if (!o->protect || !(o->protect[i] || o->protect[j])) return 0;
  return !(o->no_fail && (o->no_fail[i] & o->no_fail[j]));
}

static cupid_status scan_ratios(const cupid_pd_operator op, const double *u,
                                const cupid_pd_fracture_options *o, int want_blocked,
                                ratio_scan *out) {
  const pd_stencil *S = &op->st;
  double *theta = NULL;
  if (o->criterion == CUPID_PD_BREAK_ENERGY) {
    CUPID_CALL(cupid_malloc((size_t)op->nnodes, sizeof *theta, "PD dilatations", &theta));
    pd_lps_dilatation(op, 0, op->nnodes, u, theta);
  }
  double r = 0.0;
  cupid_int over = 0;
#pragma omp parallel for schedule(static) reduction(max : r) reduction(+ : over) if (op->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < op->nnodes; i++) {
    if (o->owned_only && !counted(o, i)) continue;
    const pd_family F = pd_family_of(op, i);
    for (int q = 0; q < F.n; q++) {
      const int s = pd_family_entry(&F, q);
      if (s < S->n / 2 || pd_bond_broken(op, i, s)) continue;
      const cupid_int j = pd_family_node(op, &F, s);
      if (!scanned(o, want_blocked, i, j)) continue;
      const double q_ = bond_ratio(op, theta, o, u, i, j, s);
      if (q_ > 1.0) over++;
      if (q_ > r) r = q_;
    }
  }
  /* the node of the largest (blocked bonds over their limit only, for the message): a second
   * pass, serial, so that ties resolve the same way on any thread count (the lowest index) */
  cupid_int node = -1;
  for (cupid_int i = 0; i < op->nnodes && want_blocked && over > 0 && node < 0; i++) {
    if (o->owned_only && !counted(o, i)) continue;
    const pd_family F = pd_family_of(op, i);
    for (int q = 0; q < F.n && node < 0; q++) {
      const int s = pd_family_entry(&F, q);
      if (s < S->n / 2 || pd_bond_broken(op, i, s)) continue;
      const cupid_int j = pd_family_node(op, &F, s);
      if (!scanned(o, want_blocked, i, j)) continue;
      if (bond_ratio(op, theta, o, u, i, j, s) == r) node = o->protect[i] ? i : j;
    }
  }
  cupid_free(&theta);
  *out = (ratio_scan){r, over, node};
  return CUPID_SUCCESS;
}

cupid_status cupid_pd_operator_max_ratio(const cupid_pd_operator op, const double *u,
                                         const cupid_pd_fracture_options *o, double *ratio) {
  CUPID_CHECK(op && u && o && ratio, CUPID_ERR_ARGUMENT, "max_ratio needs its arguments");
  ratio_scan sc;
  CUPID_CALL(scan_ratios(op, u, o, 0, &sc));
  *ratio = sc.ratio;
  return CUPID_SUCCESS;
}

cupid_status cupid_pd_operator_blocked(const cupid_pd_operator op, const double *u,
                                       const cupid_pd_fracture_options *o, cupid_int *count,
                                       cupid_int *node, double *ratio) {
  CUPID_CHECK(op && u && o && count && node && ratio, CUPID_ERR_ARGUMENT,
              "blocked needs its arguments");
  ratio_scan sc = {0.0, 0, -1};
  if (o->protect) CUPID_CALL(scan_ratios(op, u, o, 1, &sc));
  *count = sc.over;
  *node = sc.over > 0 ? sc.node : -1;
  *ratio = sc.ratio;
  return CUPID_SUCCESS;
}

cupid_status cupid_pd_operator_protected_ratios(const cupid_pd_operator op, const double *u,
                                                const cupid_pd_fracture_options *o, double *ratio) {
  CUPID_CHECK(op && u && o && ratio, CUPID_ERR_ARGUMENT, "protected_ratios needs its arguments");
  CUPID_CHECK(o->criterion == CUPID_PD_BREAK_STRETCH, CUPID_ERR_ARGUMENT,
              "protected_ratios reads the stretch criterion");
  /* each node over its whole family (both directions of a bond): no two threads write one
   * entry, and the result does not depend on the thread count */
#pragma omp parallel for schedule(static) if (op->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < op->nnodes; i++) {
    double r = 0.0;
    if (o->protect && o->protect[i]) {
      const pd_family F = pd_family_of(op, i);
      for (int q = 0; q < F.n; q++) {
        const int s = pd_family_entry(&F, q);
        if (pd_bond_broken(op, i, s)) continue;
        const cupid_int j = pd_family_node(op, &F, s);
        if (!scanned(o, 1, i, j)) continue;
        r = fmax(r, bond_ratio(op, NULL, o, u, i, j, s));
      }
    }
    ratio[i] = r;
  }
  return CUPID_SUCCESS;
}

/* The smallest eigenvalue of a symmetric 3x3 matrix (xx yy zz yz xz xy), closed form. */
static double min_eigenvalue(const double a[6]) {
  const double p1 = a[3] * a[3] + a[4] * a[4] + a[5] * a[5];
  const double q = (a[0] + a[1] + a[2]) / 3.0;
  const double p2 = (a[0] - q) * (a[0] - q) + (a[1] - q) * (a[1] - q) + (a[2] - q) * (a[2] - q) +
                    2.0 * p1;
  if (p2 <= 0.0) return q;
  const double p = sqrt(p2 / 6.0);
  const double b0 = (a[0] - q) / p, b1 = (a[1] - q) / p, b2 = (a[2] - q) / p;
  const double b3 = a[3] / p, b4 = a[4] / p, b5 = a[5] / p;
  const double det = b0 * (b1 * b2 - b3 * b3) - b5 * (b5 * b2 - b3 * b4) + b4 * (b5 * b3 - b1 * b4);
  double r = det / 2.0;
  r = r < -1.0 ? -1.0 : r > 1.0 ? 1.0 : r;
  const double phi = acos(r) / 3.0;
  return q + 2.0 * p * cos(phi + 2.0 * 3.14159265358979323846 / 3.0);
}

/* 1 when node i's intact bonds hold it weakly in some direction: the smallest eigenvalue of
 * sum omega beta n n^T over them below 1e-3 of the same sum's mean over its whole family (or
 * at most 2 bonds left). */
static int weakly_held(const struct cupid_pd_operator_private *op, cupid_int i) {
  const pd_stencil *S = &op->st;
  const pd_family F = pd_family_of(op, i);
  double a[6] = {0, 0, 0, 0, 0, 0}, all = 0.0;
  int intact = 0;
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    const double *n = S->nrm + 3 * s, w = S->wb[s];
    all += w;
    if (pd_bond_broken(op, i, s)) continue;
    intact++;
    a[0] += w * n[0] * n[0], a[1] += w * n[1] * n[1], a[2] += w * n[2] * n[2];
    a[3] += w * n[1] * n[2], a[4] += w * n[0] * n[2], a[5] += w * n[0] * n[1];
  }
  return intact <= 2 || min_eigenvalue(a) < 1e-3 * all / 3.0;
}

/* ---- Mechanisms of a few nodes ----
 * A node whose own bonds hold it in every direction can still move with a few neighbours as a
 * mechanism: two nodes bonded to each other, each with two more bonds to the body, have 6 DOFs
 * and 5 bonds. weakly_held() fixes the neighbours and does not see it; the factorisation of K
 * breaks down there (issue 37: the notched C-beam's flanges, whose last ligaments leave such
 * clusters by the hundred, each a factorisation of the grown zone, 15 s). So the nodes that lost
 * at least MECH_DAMAGE of their bonds (by weight) are grouped into clusters over their intact
 * bonds, and each cluster of at most MECH_CLUSTER_MAX nodes is tested as a body of its own,
 * everything outside it fixed: the block of sum w n n^T over its intact bonds (each bond's term
 * at both of its ends inside the cluster, at its inside end for a bond that leaves it; w and n
 * as weakly_held's) is factorised by Cholesky in the nodes' order, and a pivot under
 * MECH_PIVOT times the block's largest diagonal entry is a mechanism there: that node is
 * marked (crack growth ties it by a weak spring, src/problem/growth.c) and counts as fixed,
 * and the rest of the cluster is tested again. A mechanism that takes in less damaged nodes is
 * left to the factorisation, as before; a cluster larger than the bound (a crack face's band) is
 * tested in balls around its nodes that lost bonds since the last check (below). */
#define MECH_DAMAGE CUPID_PD_MECHANISM_DAMAGE
#define MECH_CLUSTER_MAX 48
/* A mechanism's pivot is round-off of the block's entries (1e-16 of them); a node held by a
 * bond a thousandth of the others' is no mechanism (weakly_held's bound for one node is 1e-3 of
 * the family's mean). */
#define MECH_PIVOT 1e-9

/* The share of node i's bond weight that is broken. */
static double lost_share(const struct cupid_pd_operator_private *op, cupid_int i) {
  const pd_stencil *S = &op->st;
  const pd_family F = pd_family_of(op, i);
  double all = 0.0, lost = 0.0;
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    all += S->wb[s];
    if (pd_bond_broken(op, i, s)) lost += S->wb[s];
  }
  return all > 0.0 ? lost / all : 0.0;
}

/* The block of the cluster nodes[0 .. m) (local[j]: j's place in it, or -1) into K (3m x 3m,
 * row-major). */
static void cluster_block(const struct cupid_pd_operator_private *op, const cupid_int *nodes, int m,
                          const int *local, double *K) {
  const pd_stencil *S = &op->st;
  const int N = 3 * m;
  memset(K, 0, (size_t)N * (size_t)N * sizeof *K);
  for (int a = 0; a < m; a++) {
    const pd_family F = pd_family_of(op, nodes[a]);
    for (int q = 0; q < F.n; q++) {
      const int s = pd_family_entry(&F, q);
      if (pd_bond_broken(op, nodes[a], s)) continue;
      const int b = local[pd_family_node(op, &F, s)];
      const double *n = S->nrm + 3 * s, w = S->wb[s];
      for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
          const double v = w * n[r] * n[c];
          K[(3 * a + r) * N + 3 * a + c] += v;
          if (b < 0) continue;
          K[(3 * b + r) * N + 3 * b + c] += v;
          K[(3 * a + r) * N + 3 * b + c] -= v;
          K[(3 * b + r) * N + 3 * a + c] -= v;
        }
    }
  }
}

/* Cholesky of K (N x N, row-major, lower triangle overwritten) over the rows not out[]: the
 * first row whose pivot falls under MECH_PIVOT times the largest diagonal entry, or -1. */
static int cluster_cholesky(double *K, int N, const unsigned char *out) {
  double top = 0.0;
  for (int k = 0; k < N; k++)
    if (!out[k]) top = fmax(top, K[k * N + k]);
  for (int k = 0; k < N; k++) {
    if (out[k]) continue;
    double d = K[k * N + k];
    for (int p = 0; p < k; p++)
      if (!out[p]) d -= K[k * N + p] * K[k * N + p];
    if (!(d > MECH_PIVOT * top)) return k;
    d = sqrt(d);
    K[k * N + k] = d;
    for (int r = k + 1; r < N; r++) {
      if (out[r]) continue;
      double v = K[r * N + k];
      for (int p = 0; p < k; p++)
        if (!out[p]) v -= K[r * N + p] * K[k * N + p];
      K[r * N + k] = v / d;
    }
  }
  return -1;
}

/* Mark (release = 2) the nodes of the cluster nodes[0 .. m) that complete a mechanism; *n
 * counts them. K: 9 MECH_CLUSTER_MAX^2 doubles of scratch. */
static void cluster_mechanisms(const struct cupid_pd_operator_private *op, const cupid_int *nodes,
                               int m, const int *local, unsigned char *release, double *K,
                               cupid_int *n) {
  const int N = 3 * m;
  unsigned char out[3 * MECH_CLUSTER_MAX];
  memset(out, 0, sizeof out);
  for (int held = 0; held < m; held++) {
    cluster_block(op, nodes, m, local, K);
    const int k = cluster_cholesky(K, N, out);
    if (k < 0) return;
    const int a = k / 3;
    release[nodes[a]] = 2, (*n)++;
    out[3 * a] = out[3 * a + 1] = out[3 * a + 2] = 1;
  }
}

/* The order of a cluster's nodes in its Cholesky factorisation: i before j when it moved more
 * (|u|, then the node index). A pivot vanishes at the node that completes a mechanism of the
 * nodes before it (the later ones fixed), so the node marked is the one of the mechanism that
 * moved least: the likeliest to sit on the part that stays (a notched plate cut through under
 * a grip: its last ligament is four nodes across the crack). Without u, the node index alone. */
static int cluster_first(const double *u, cupid_int i, cupid_int j) {
  if (u) {
    const double ui = u[3 * i] * u[3 * i] + u[3 * i + 1] * u[3 * i + 1] + u[3 * i + 2] * u[3 * i + 2];
    const double uj = u[3 * j] * u[3 * j] + u[3 * j + 1] * u[3 * j + 1] + u[3 * j + 2] * u[3 * j + 2];
    if (ui != uj) return ui > uj;
  }
  return i < j;
}

/* ---- Mechanisms inside a band of damaged nodes ----
 * A cluster larger than MECH_CLUSTER_MAX (a crack face's band) is not factorised whole, but a
 * mechanism of a few nodes can form inside one: the notched C-beam's flange ligaments leave
 * nodes that lost 78-80% of their bonds moving with a few neighbours inside damaged bands of
 * 400 nodes, each then found by a factorisation of the grown zone (examples/fracture/README.md).
 * A mechanism that forms takes in a node that lost a bond since the last check (the caller's
 * seen[]: each node's lost share then), so a ball of at most MECH_CLUSTER_MAX band nodes
 * around each such node is tested as a cluster, everything outside it fixed. The ball grows
 * over intact bonds, the most damaged neighbour first (ties: the lower index), so that the
 * loose nodes, which lost the most, come in before the band's ordinary crack-face nodes. A
 * mechanism of the ball with its outside fixed is one of the whole body (its mode, zero
 * outside, strains no bond there either), so what it marks is a mechanism; one that the ball
 * does not hold whole is left to the factorisation, as before. */

/* Scratch of one mechanisms() call. */
typedef struct {
  unsigned char *cand;  /* MECH_CAND, MECH_SEEN, MECH_TOUCHED, MECH_BAND bits per node */
  double *share;        /* lost share of each candidate */
  cupid_int *queue, *nodes, *front;
  int *local;           /* place in the cluster (>= 0), MECH_FRONT, or -1 */
  double *K;
} mech_scratch;
#define MECH_CAND 1u
#define MECH_SEEN 2u
#define MECH_TOUCHED 4u
#define MECH_BAND 8u
#define MECH_FRONT (-2)

/* Test the m nodes of s->nodes as a cluster in the order of cluster_first. */
static void test_cluster(const struct cupid_pd_operator_private *op, mech_scratch *s, int m,
                         const double *u, unsigned char *release, cupid_int *count) {
  cupid_int *nodes = s->nodes;
  for (int a = 1; a < m; a++)
    for (int b = a; b > 0 && cluster_first(u, nodes[b], nodes[b - 1]); b--) {
      const cupid_int x = nodes[b];
      nodes[b] = nodes[b - 1], nodes[b - 1] = x;
    }
  for (int a = 0; a < m; a++) s->local[nodes[a]] = a;
  cluster_mechanisms(op, nodes, m, s->local, release, s->K, count);
  for (int a = 0; a < m; a++) s->local[nodes[a]] = -1;
}

/* Put the band nodes bonded to v by intact bonds, not in the ball or its front yet, into the
 * front. */
static void ball_front(const struct cupid_pd_operator_private *op, mech_scratch *s, cupid_int v,
                       const unsigned char *release, int *nf) {
  const pd_family F = pd_family_of(op, v);
  for (int q = 0; q < F.n; q++) {
    const int e = pd_family_entry(&F, q);
    const cupid_int j = pd_family_node(op, &F, e);
    if ((s->cand[j] & MECH_BAND) && !release[j] && s->local[j] == -1 && !pd_bond_broken(op, v, e))
      s->local[j] = MECH_FRONT, s->front[(*nf)++] = j;
  }
}

/* The ball around centre c in the band (MECH_BAND), tested as a cluster. */
static void ball_mechanisms(const struct cupid_pd_operator_private *op, mech_scratch *s,
                            cupid_int c, const double *u, unsigned char *release,
                            cupid_int *count) {
  int m = 0, nf = 0;
  s->nodes[m++] = c, s->local[c] = 0;
  ball_front(op, s, c, release, &nf);
  while (m < MECH_CLUSTER_MAX && nf > 0) { /* the most damaged of the front next */
    int best = 0;
    for (int k = 1; k < nf; k++) {
      const cupid_int a = s->front[k], b = s->front[best];
      if (s->share[a] > s->share[b] || (s->share[a] == s->share[b] && a < b)) best = k;
    }
    const cupid_int j = s->front[best];
    s->front[best] = s->front[--nf];
    s->local[j] = m, s->nodes[m++] = j;
    ball_front(op, s, j, release, &nf);
  }
  for (int k = 0; k < nf; k++) s->local[s->front[k]] = -1;
  for (int a = 0; a < m; a++) s->local[s->nodes[a]] = -1;
  test_cluster(op, s, m, u, release, count);
}

/* The mechanisms of clusters of nodes in [first, last) that lost at least MECH_DAMAGE of their
 * bonds (above), and of balls in the larger ones around the nodes touched since seen[] (all of
 * their nodes without it): the nodes that complete them get release = 2, *count more of them. */
static cupid_status mechanisms(const struct cupid_pd_operator_private *op, cupid_int first,
                               cupid_int last, const double *u, double *seen,
                               unsigned char *release, cupid_int *count) {
  const cupid_int nn = op->nnodes;
  mech_scratch s = {0};
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_calloc((size_t)nn + 1, 1, "mechanism flags", &s.cand));
  CUPID_TRY(cupid_malloc((size_t)nn + 1, sizeof *s.share, "mechanism shares", &s.share));
  cupid_int nc = 0;
  for (cupid_int i = first; i < last; i++) {
    if (release[i] || op->bslot[i] < 0) continue;
    const double sh = lost_share(op, i);
    if (sh >= MECH_DAMAGE) s.cand[i] = MECH_CAND, s.share[i] = sh, nc++;
    if (seen && sh != seen[i]) s.cand[i] |= MECH_TOUCHED;
    if (seen) seen[i] = sh;
  }
  if (nc == 0) goto cleanup;
  CUPID_TRY(cupid_malloc((size_t)nn + 1, sizeof *s.queue, "mechanism queue", &s.queue));
  CUPID_TRY(cupid_malloc((size_t)nn + 1, sizeof *s.local, "mechanism map", &s.local));
  CUPID_TRY(cupid_malloc(MECH_CLUSTER_MAX, sizeof *s.nodes, "mechanism cluster", &s.nodes));
  CUPID_TRY(cupid_malloc((size_t)MECH_CLUSTER_MAX * (size_t)op->st.n + 1, sizeof *s.front,
                         "mechanism ball front", &s.front));
  CUPID_TRY(cupid_malloc(9 * MECH_CLUSTER_MAX * MECH_CLUSTER_MAX, sizeof *s.K, "mechanism block", &s.K));
  for (cupid_int i = 0; i < nn; i++) s.local[i] = -1;
  for (cupid_int i = first; i < last; i++) {
    if ((s.cand[i] & (MECH_CAND | MECH_SEEN)) != MECH_CAND) continue;
    cupid_int head = 0, tail = 0; /* the cluster over intact bonds between candidates */
    s.queue[tail++] = i, s.cand[i] |= MECH_SEEN;
    while (head < tail) {
      const cupid_int v = s.queue[head++];
      const pd_family F = pd_family_of(op, v);
      for (int q = 0; q < F.n; q++) {
        const int e = pd_family_entry(&F, q);
        const cupid_int j = pd_family_node(op, &F, e);
        if ((s.cand[j] & (MECH_CAND | MECH_SEEN)) == MECH_CAND && !pd_bond_broken(op, v, e))
          s.cand[j] |= MECH_SEEN, s.queue[tail++] = j;
      }
    }
    if (tail <= MECH_CLUSTER_MAX) { /* the whole cluster */
      for (cupid_int t = 0; t < tail; t++) s.nodes[t] = s.queue[t];
      test_cluster(op, &s, (int)tail, u, release, count);
      continue;
    }
    for (cupid_int t = 0; t < tail; t++) s.cand[s.queue[t]] |= MECH_BAND; /* a band: balls */
    for (cupid_int t = 0; t < tail; t++) {
      const cupid_int c = s.queue[t];
      if (!release[c] && (!seen || (s.cand[c] & MECH_TOUCHED))) ball_mechanisms(op, &s, c, u, release, count);
    }
    for (cupid_int t = 0; t < tail; t++) s.cand[s.queue[t]] &= (unsigned char)~MECH_BAND;
  }
cleanup:
  cupid_free(&s.cand);
  cupid_free(&s.share);
  cupid_free(&s.queue);
  cupid_free(&s.nodes);
  cupid_free(&s.front);
  cupid_free(&s.local);
  cupid_free(&s.K);
  return st;
}

cupid_status cupid_pd_operator_weakly_held(const cupid_pd_operator op, cupid_int first,
                                           cupid_int last, unsigned char *release,
                                           cupid_int *count) {
  CUPID_CHECK(op && release && count && first >= 0 && last <= op->nnodes, CUPID_ERR_ARGUMENT,
              "weakly_held needs its arguments and a range of nodes");
  /* nodes whose intact bonds no longer hold them in every direction: at most 2 left (a
   * mechanism: Peridigm's RANK_DEFICIENT_NODES), or all of them (nearly) in one plane */
  cupid_int n = 0;
  for (cupid_int i = first; i < last; i++)
    if (!release[i] && op->bslot && op->bslot[i] >= 0 && weakly_held(op, i)) release[i] = 2, n++;
  *count = n;
  return CUPID_SUCCESS;
}

cupid_status cupid_pd_operator_mechanisms(const cupid_pd_operator op, cupid_int first,
                                          cupid_int last, const double *u, double *seen,
                                          unsigned char *release, cupid_int *count) {
  CUPID_CHECK(op && release && count && first >= 0 && last <= op->nnodes, CUPID_ERR_ARGUMENT,
              "mechanisms needs its arguments and a range of nodes");
  *count = 0;
  if (!op->bslot) return CUPID_SUCCESS;
  return mechanisms(op, first, last, u, seen, release, count);
}

void cupid_pd_operator_lost_shares(const cupid_pd_operator op, cupid_int first, cupid_int last,
                                   double *share) {
  for (cupid_int i = first; i < last; i++)
    share[i] = op->bslot && op->bslot[i] >= 0 ? lost_share(op, i) : 0.0;
}

cupid_status cupid_pd_operator_reach(const cupid_pd_operator op, const unsigned char *release,
                                     unsigned char *seen, cupid_int *added) {
  CUPID_CHECK(op && release && seen && added, CUPID_ERR_ARGUMENT, "reach needs its arguments");
  const cupid_int nn = op->nnodes;
  cupid_int *queue = NULL, head = 0, tail = 0, n = 0;
  CUPID_CALL(cupid_malloc((size_t)nn + 1, sizeof *queue, "node queue", &queue));
  for (cupid_int i = 0; i < nn; i++)
    if (seen[i] && !release[i]) queue[tail++] = i;
  while (head < tail) {
    const cupid_int i = queue[head++];
    const pd_family F = pd_family_of(op, i);
    for (int q = 0; q < F.n; q++) {
      const int s = pd_family_entry(&F, q);
      if (pd_bond_broken(op, i, s)) continue;
      const cupid_int j = pd_family_node(op, &F, s);
      if (!seen[j] && !release[j]) seen[j] = 1, queue[tail++] = j, n++;
    }
  }
  *added = n;
  cupid_free(&queue);
  return CUPID_SUCCESS;
}

void cupid_pd_operator_mark_families(const cupid_pd_operator op, const unsigned char *mark,
                                     unsigned char *out) {
  for (cupid_int i = 0; i < op->nnodes; i++) {
    if (!mark[i]) continue;
    const pd_family F = pd_family_of(op, i);
    for (int q = 0; q < F.n; q++) out[pd_family_node(op, &F, pd_family_entry(&F, q))] = 1;
  }
}

cupid_status cupid_pd_operator_unsupported(const cupid_pd_operator op, const unsigned char *anchored,
                                           unsigned char *release, cupid_int *count) {
  CUPID_CHECK(op && anchored && release && count, CUPID_ERR_ARGUMENT,
              "unsupported needs its arguments");
  const cupid_int nn = op->nnodes;
  unsigned char *seen = NULL;
  cupid_int weak = 0, added = 0;
  CUPID_CALL(cupid_calloc((size_t)nn + 1, 1, "node flags", &seen));
  cupid_status st = cupid_pd_operator_weakly_held(op, 0, nn, release, &weak);
  /* what an anchored node reaches over intact bonds between kept nodes holds; the rest is a
   * fragment cut off from every support */
  for (cupid_int i = 0; i < nn; i++) seen[i] = anchored[i] && !release[i];
  if (st == CUPID_SUCCESS) st = cupid_pd_operator_reach(op, release, seen, &added);
  cupid_int n = 0;
  for (cupid_int i = 0; i < nn && st == CUPID_SUCCESS; i++) {
    if (!release[i] && !seen[i]) release[i] = 2;
    n += release[i] == 2;
  }
  *count = n;
  cupid_free(&seen);
  return st;
}

cupid_int cupid_pd_operator_nodes_broken(const cupid_pd_operator op, cupid_int *nodes) {
  cupid_int n = 0;
  if (!op || !op->bslot) return 0;
  if (!nodes) {
    for (int32_t k = 0; k < op->nslots; k++) n += op->bcount[k] > op->bpre[k];
    return n;
  }
  for (cupid_int i = 0; i < op->nnodes; i++) {
    const int32_t k = op->bslot[i];
    if (k >= 0 && op->bcount[k] > op->bpre[k]) nodes[n++] = i;
  }
  return n;
}

int cupid_pd_operator_bond_intact(const cupid_pd_operator op, cupid_int i, cupid_int j) {
  if (!op || i < 0 || j < 0 || i >= op->nnodes || j >= op->nnodes) return 0;
  const pd_family F = pd_family_of(op, i);
  for (int q = 0; q < F.n; q++) {
    const int s = pd_family_entry(&F, q);
    if (pd_family_node(op, &F, s) == j) return !pd_bond_broken(op, i, s);
  }
  return 0;
}

/* damage_i = 1 - sum over intact bonds of beta V / sum over all bonds of beta V (LAMMPS
 * compute damage/atom; the contract's definition): beta = (omega beta) / omega. */
cupid_status cupid_pd_operator_damage(const cupid_pd_operator op, double *damage,
                                      cupid_int *damaged, double *max_damage) {
  CUPID_CHECK(op && damage, CUPID_ERR_ARGUMENT, "damage needs operator and output");
  const pd_stencil *S = &op->st;
  cupid_int nd = 0;
  double mx = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : nd) reduction(max : mx) \
    if (op->nnodes > PD_OMP_MIN_NODES)
  for (cupid_int i = 0; i < op->nnodes; i++) {
    damage[i] = 0.0;
    if (!op->bslot || op->bslot[i] < 0) continue;
    const pd_family F = pd_family_of(op, i);
    double all = 0.0, lost = 0.0;
    for (int q = 0; q < F.n; q++) {
      const int s = pd_family_entry(&F, q);
      const double beta = S->wb[s] / cupid_pd_influence(op->influence, S->x[s], op->delta);
      all += beta;
      if (pd_bond_broken(op, i, s)) lost += beta;
    }
    damage[i] = all > 0 ? lost / all : 0.0;
    nd += lost > 0;
    if (damage[i] > mx) mx = damage[i];
  }
  if (damaged) *damaged = nd;
  if (max_damage) *max_damage = mx;
  return CUPID_SUCCESS;
}
