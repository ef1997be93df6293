/* Arlequin coupling of a CUF beam and a PD region (LPS or bond-based) with a penalty (paper
 * 004, section 3; coupling.md section 7). The two models overlap on [lo, hi] along the axis
 * (or on two such ranges, one at each end of a PD region inside the beam). The
 * coupled Hamiltonian is alpha H_FE + (1 - alpha) H_PD (Eq. 8) plus the penalty energy
 * kappa/2 sum_q |d_q - N(x_q) u|^2 over the PD nodes q of the overlap (Eqs. 16-17, node by
 * node), so the stiffness is K = K_FE(alpha) + K_PD(1 - alpha) + K_z (Eq. 18) and the mass
 * M = M_FE(alpha) + (1 - alpha) rho V (Eq. 14): symmetric, positive definite once the beam
 * is held (CHOLMOD). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "coupling/coupling_internal.h"

/* Lattice tolerance (relative to h) for "a PD node lies in the overlap". */
#define ARL_TOL 1e-9
/* Terms of the beam's weight: one for the regions without a section part, one per other. */
#define ARL_MAX_TERMS 64

double cupid_arlequin_alpha(const cupid_arlequin_weight *w, double y) {
  double len = w->hi - w->lo;
  /* s: 0 on the FE-only edge of the overlap, 1 on the PD-only edge */
  double s = w->fe_below ? (y - w->lo) / len : (w->hi - y) / len;
  if (s <= 0.0) return s < 0.0 || w->kind != CUPID_WEIGHT_CONSTANT ? 1.0 : 0.5;
  if (s >= 1.0) return s > 1.0 || w->kind != CUPID_WEIGHT_CONSTANT ? 0.0 : 0.5;
  switch (w->kind) {
  case CUPID_WEIGHT_CONSTANT: return 0.5;
  case CUPID_WEIGHT_SMOOTH: return 1.0 - s * s * (3.0 - 2.0 * s); /* C1 smoothstep */
  case CUPID_WEIGHT_LINEAR:
  default: return 1.0 - s; /* Eq. 9 */
  }
}

double cupid_arlequin_alpha_of(const cupid_arlequin_options *o, double y) {
  double a = cupid_arlequin_alpha(&o->weight, y);
  if (o->n_overlaps == 2) a = fmax(a, cupid_arlequin_alpha(&o->second, y));
  return a;
}

/* The regions of the options: the general list, or the y-only form as one unbounded region
 * with its one or two ramps along y. */
typedef struct {
  int n;
  const cupid_arlequin_region *r;
  cupid_arlequin_region one;
} layout_t;

static void layout_of(const cupid_arlequin_options *o, layout_t *L) {
  if (o->n_regions > 0) {
    L->n = o->n_regions;
    L->r = o->regions;
    return;
  }
  memset(&L->one, 0, sizeof L->one);
  L->one.ramps[L->one.n_ramps++] = (cupid_arlequin_ramp){.axis = 1, .weight = o->weight};
  if (o->n_overlaps == 2)
    L->one.ramps[L->one.n_ramps++] = (cupid_arlequin_ramp){.axis = 1, .weight = o->second};
  L->n = 1;
  L->r = &L->one;
}

/* Box tolerance: ARL_TOL of the box's largest extent (PD nodes lie on its faces). */
static double box_tol(const cupid_box *b) {
  double ext = 0.0;
  for (int k = 0; k < 3; k++)
    if (b->has[k]) ext = fmax(ext, b->hi[k] - b->lo[k]);
  return ARL_TOL * (ext > 0.0 ? ext : 1.0);
}

/* The region's PD weight at p restricted to the axes in mask (bit k: axis k): 0 outside the
 * box along those axes, else the product of 1 - alpha over the ramps along them. */
static double region_weight_axes(const cupid_arlequin_region *r, const double p[3], int mask) {
  double tol = box_tol(&r->box), w = 1.0;
  for (int k = 0; k < 3; k++)
    if ((mask >> k & 1) && r->box.has[k] && (p[k] < r->box.lo[k] - tol || p[k] > r->box.hi[k] + tol))
      return 0.0;
  for (int q = 0; q < r->n_ramps; q++)
    if (mask >> r->ramps[q].axis & 1) w *= 1.0 - cupid_arlequin_alpha(&r->ramps[q].weight, p[r->ramps[q].axis]);
  return w;
}

static double region_weight(const cupid_arlequin_region *r, const double p[3]) {
  return region_weight_axes(r, p, 7);
}

/* 1 if the region's weight depends on x or z (a box or ramps across the section). */
static int region_has_section(const cupid_arlequin_region *r) {
  if (r->box.has[0] || r->box.has[2]) return 1;
  for (int q = 0; q < r->n_ramps; q++)
    if (r->ramps[q].axis != 1) return 1;
  return 0;
}

/* PD weight at p: the sum over the regions (they do not overlap), at most 1. */
static double pd_weight_at(const layout_t *L, const double p[3]) {
  double w = 0.0;
  for (int r = 0; r < L->n; r++) w += region_weight(&L->r[r], p);
  return fmin(w, 1.0);
}

double cupid_arlequin_alpha_at(const cupid_arlequin_options *o, const double p[3]) {
  layout_t L;
  layout_of(o, &L);
  return 1.0 - pd_weight_at(&L, p);
}

/* The beam's weight as the separable sum of cupid_cuf_weight: one axis term
 * 1 - sum a_r(y) over the regions without a section part, and -a_r(y) s_r(x, z) for each
 * region with one (a_r: the y part of the PD weight, s_r: its x and z part). */
static double axis_term(void *ctx, double y) {
  const layout_t *L = ctx;
  double p[3] = {0.0, y, 0.0}, a = 1.0;
  for (int r = 0; r < L->n; r++)
    if (!region_has_section(&L->r[r])) a -= region_weight_axes(&L->r[r], p, 2);
  return a;
}

static double region_axis(void *ctx, double y) {
  double p[3] = {0.0, y, 0.0};
  return -region_weight_axes(ctx, p, 2);
}

static double region_section(void *ctx, double x, double z) {
  double p[3] = {x, 0.0, z};
  return region_weight_axes(ctx, p, 5);
}

/* The layout of o into *L and the beam's weight into *w (terms: ARL_MAX_TERMS; *w points
 * into terms and L, which must outlive its use). */
static cupid_status beam_weight(const cupid_arlequin_options *o, layout_t *L,
                                cupid_cuf_weight_term *terms, cupid_cuf_weight *w) {
  layout_of(o, L);
  CUPID_CHECK(L->n < ARL_MAX_TERMS, CUPID_ERR_ARGUMENT, "Arlequin: at most %d regions, not %d",
              ARL_MAX_TERMS - 1, L->n);
  int n = 0;
  terms[n++] = (cupid_cuf_weight_term){.axis = axis_term, .axis_ctx = (void *)L};
  for (int r = 0; r < L->n; r++)
    if (region_has_section(&L->r[r]))
      terms[n++] = (cupid_cuf_weight_term){.axis = region_axis,
                                           .axis_ctx = (void *)&L->r[r],
                                           .section = region_section,
                                           .section_ctx = (void *)&L->r[r]};
  *w = (cupid_cuf_weight){.constant = 0.0, .n_terms = n, .terms = terms};
  return CUPID_SUCCESS;
}

/* p lies in an overlap: inside a region and within one of its ramps' slabs (closed). */
static int in_overlap(const layout_t *L, const double p[3], double tol) {
  for (int r = 0; r < L->n; r++) {
    const cupid_arlequin_region *R = &L->r[r];
    if (!cupid_box_contains(&R->box, p, box_tol(&R->box))) continue;
    for (int q = 0; q < R->n_ramps; q++) {
      double c = p[R->ramps[q].axis];
      if (c >= R->ramps[q].weight.lo - tol && c <= R->ramps[q].weight.hi + tol) return 1;
    }
  }
  return 0;
}

/* The PD nodes of the overlap and their beam weights: CSR over tied nodes (tptr, tnode, tw). */
typedef struct {
  cupid_int n, *node, *ptr, *fe;
  double *w;
  int comps; /* tied components: 1 (y) in 1D, 3 in 3D */
} tied_t;

static void tied_free(tied_t *t) {
  cupid_free(&t->node);
  cupid_free(&t->ptr);
  cupid_free(&t->fe);
  cupid_free(&t->w);
}

static cupid_status tied_build(cupid_cuf_beam beam, cupid_pd_grid grid,
                               const cupid_arlequin_options *o, tied_t *t) {
  cupid_status st = CUPID_SUCCESS;
  cupid_cuf_info fi;
  cupid_cuf_get_info(beam, &fi);
  cupid_int n_pd = cupid_pd_grid_num_nodes(grid), per = (cupid_int)fi.M * fi.element_nodes;
  const double *x = cupid_pd_grid_coords(grid);
  double tol = ARL_TOL * cupid_pd_grid_spacing(grid);
  memset(t, 0, sizeof *t);
  t->comps = cupid_pd_grid_dimension(grid) == 1 ? 1 : 3;
  CUPID_TRY(cupid_malloc((size_t)n_pd, sizeof *t->node, "tied PD nodes", &t->node));
  layout_t L;
  layout_of(o, &L);
  /* a slab of a partitioned grid ties its owned nodes only: every tied node once over the
   * slabs (the halo's rows are not this slab's) */
  cupid_pd_grid_partition part;
  cupid_pd_grid_get_partition(grid, &part);
  for (cupid_int i = part.owned_first; i < part.owned_last; i++)
    if (in_overlap(&L, x + 3 * i, tol)) t->node[t->n++] = i;
  CUPID_TRY(cupid_calloc((size_t)t->n + 1, sizeof *t->ptr, "tied rows", &t->ptr));
  CUPID_TRY(cupid_malloc((size_t)(t->n * per + 1), sizeof *t->fe, "tied FE nodes", &t->fe));
  CUPID_TRY(cupid_malloc((size_t)(t->n * per + 1), sizeof *t->w, "tied weights", &t->w));
  for (cupid_int k = 0; k < t->n; k++) {
    const double *p = x + 3 * t->node[k];
    int count = 0;
    st = cupid_cuf_shape_at(beam, p[0], p[1], p[2], t->fe + t->ptr[k], t->w + t->ptr[k], &count);
    if (st != CUPID_SUCCESS) {
      st = CUPID_ERROR(CUPID_ERR_MODEL,
                       "Arlequin overlap: PD node %lld at (%g, %g, %g) lies in the overlap but "
                       "outside the beam; the beam must cover the overlap",
                       (long long)t->node[k], p[0], p[1], p[2]);
      goto cleanup;
    }
    t->ptr[k + 1] = t->ptr[k] + count;
  }
  return CUPID_SUCCESS;
cleanup:
  tied_free(t);
  return st;
}

static int cmp_col(const void *a, const void *b) {
  cupid_int x = *(const cupid_int *)a, y = *(const cupid_int *)b;
  return (x > y) - (x < y);
}

/* The entries (r, c) of the beam's and the ties' pattern, row by row: added once to count (col NULL: rows[r]
 * counts them), then again into each row's slot (rows[r] its next place). */
typedef struct {
  cupid_int *rows, *col;
} pattern_fill;

static void put(pattern_fill *f, cupid_int r, cupid_int c) {
  if (f->col) f->col[f->rows[r]] = c;
  f->rows[r]++;
}

static void put_all(pattern_fill *f, const cupid_int *frp, const cupid_int *fcol, const tied_t *t,
                    cupid_int n_pd, cupid_int n_fe) {
  for (cupid_int r = 0; r < n_fe; r++)
    for (cupid_int q = frp[r]; q < frp[r + 1]; q++) put(f, n_pd + r, n_pd + fcol[q]);
  for (cupid_int k = 0; k < t->n; k++) {
    put(f, t->node[k], t->node[k]); /* the penalty's own diagonal */
    for (cupid_int a = t->ptr[k]; a < t->ptr[k + 1]; a++) {
      put(f, t->node[k], n_pd + t->fe[a]);
      put(f, n_pd + t->fe[a], t->node[k]);
    }
  }
}

/* The pattern of the beam (shifted to block n_pd) and the penalty couplings; the PD block's
 * joins it at each assembly (union_pattern). The penalty's FE-FE blocks N^T N couple the FE
 * nodes of the one (beam element, section element) pair that holds the tied node
 * (cupid_cuf_shape_at()), which the beam's pattern already couples: only the PD-FE blocks and
 * the tied node's diagonal are added. Built row by row (a count, a fill, each row sorted and
 * its repeats dropped). */
static cupid_status build_pattern(cupid_cuf_beam beam, const tied_t *t, cupid_int n_pd,
                                  cupid_int n_fe, cupid_csr *K) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int *frp = NULL, *fcol = NULL, *start = NULL, *next = NULL, *col = NULL, nb = n_pd + n_fe;
  CUPID_TRY(cupid_cuf_pattern(beam, &frp, &fcol));
  CUPID_TRY(cupid_calloc((size_t)nb + 1, sizeof *start, "Arlequin rows", &start));
  CUPID_TRY(cupid_calloc((size_t)nb + 1, sizeof *next, "Arlequin rows", &next));
  pattern_fill f = {next, NULL};
  put_all(&f, frp, fcol, t, n_pd, n_fe);
  for (cupid_int r = 0; r < nb; r++) start[r + 1] = start[r] + next[r];
  CUPID_TRY(cupid_malloc((size_t)start[nb] + 1, sizeof *col, "Arlequin columns", &col));
  memcpy(next, start, (size_t)nb * sizeof *next);
  f = (pattern_fill){next, col};
  put_all(&f, frp, fcol, t, n_pd, n_fe);
  /* each row sorted, its repeats dropped, packed to the front: start[] becomes rowptr */
  cupid_int m = 0;
  for (cupid_int r = 0; r < nb; r++) {
    const cupid_int a = start[r], b = start[r + 1];
    qsort(col + a, (size_t)(b - a), sizeof *col, cmp_col);
    start[r] = m;
    for (cupid_int q = a; q < b; q++)
      if (q == a || col[q] != col[q - 1]) col[m++] = col[q];
  }
  start[nb] = m;
  CUPID_TRY(cupid_csr_create(nb, nb, 3, start, col, K));
cleanup:
  cupid_free(&frp);
  cupid_free(&fcol);
  cupid_free(&start);
  cupid_free(&next);
  cupid_free(&col);
  return st;
}

/* Add a part of the coupled matrix (the weighted PD block, or the beam's and the ties') into
 * K: row r of the part is a subset of row r of K, both sorted, walked together (a search per
 * block cost 14% of a coupled growth run). */
static cupid_status add_part(const cupid_csr_t *P, cupid_csr K) {
  for (cupid_int r = 0; r < P->nrows; r++) CUPID_CALL(cupid_csr_add_row(K, r, P, r));
  return CUPID_SUCCESS;
}

/* K_z = kappa [P, -N P; -N^T P, N^T N P] per tied node (P: the tied components). */
static cupid_status add_penalty(const tied_t *t, double kappa, cupid_int n_pd, cupid_csr K) {
  int c0 = t->comps == 1 ? 1 : 0, c1 = t->comps == 1 ? 2 : 3;
  for (cupid_int k = 0; k < t->n; k++) {
    cupid_int q = t->node[k];
    double *blk = cupid_csr_find(K, q, q);
    CUPID_CHECK(blk, CUPID_ERR_INTERNAL, "Arlequin pattern lacks a tied block");
    for (int c = c0; c < c1; c++) blk[4 * c] += kappa;
    for (cupid_int a = t->ptr[k]; a < t->ptr[k + 1]; a++) {
      cupid_int fa = n_pd + t->fe[a];
      double *qa = cupid_csr_find(K, q, fa), *aq = cupid_csr_find(K, fa, q);
      CUPID_CHECK(qa && aq, CUPID_ERR_INTERNAL, "Arlequin pattern lacks a penalty block");
      for (int c = c0; c < c1; c++) {
        qa[4 * c] -= kappa * t->w[a];
        aq[4 * c] -= kappa * t->w[a];
      }
      for (cupid_int b = t->ptr[k]; b < t->ptr[k + 1]; b++) {
        double *ab = cupid_csr_find(K, fa, n_pd + t->fe[b]);
        CUPID_CHECK(ab, CUPID_ERR_INTERNAL, "Arlequin pattern lacks a penalty block");
        for (int c = c0; c < c1; c++) ab[4 * c] += kappa * t->w[a] * t->w[b];
      }
    }
  }
  return CUPID_SUCCESS;
}

static cupid_status check_region(const cupid_arlequin_region *r, int k) {
  CUPID_CHECK(r->n_ramps >= 0 && r->n_ramps <= CUPID_ARLEQUIN_MAX_RAMPS, CUPID_ERR_ARGUMENT,
              "Arlequin: region %d has %d overlaps (0 to %d)", k, r->n_ramps, CUPID_ARLEQUIN_MAX_RAMPS);
  for (int q = 0; q < r->n_ramps; q++) {
    const cupid_arlequin_ramp *a = &r->ramps[q];
    CUPID_CHECK(a->axis >= 0 && a->axis <= 2 && a->weight.hi > a->weight.lo, CUPID_ERR_ARGUMENT,
                "Arlequin: region %d, overlap %d: axis %d, [%g, %g] (need an axis 0-2 and lo < hi)",
                k, q, a->axis, a->weight.lo, a->weight.hi);
  }
  return CUPID_SUCCESS;
}

static cupid_status check_options(cupid_cuf_beam beam, cupid_pd_grid grid,
                                  const cupid_arlequin_options *o) {
  CUPID_CHECK(beam && grid && o, CUPID_ERR_ARGUMENT, "Arlequin: NULL argument");
  CUPID_CHECK(o->penalty > 0, CUPID_ERR_ARGUMENT, "Arlequin: the penalty must be positive");
  if (o->n_regions > 0) {
    CUPID_CHECK(o->regions, CUPID_ERR_ARGUMENT, "Arlequin: %d regions without a region array",
                o->n_regions);
    for (int k = 0; k < o->n_regions; k++) CUPID_CALL(check_region(&o->regions[k], k));
  } else {
    CUPID_CHECK(o->weight.hi > o->weight.lo, CUPID_ERR_ARGUMENT,
                "Arlequin: empty overlap [%g, %g]", o->weight.lo, o->weight.hi);
    CUPID_CHECK(o->n_overlaps >= 0 && o->n_overlaps <= 2, CUPID_ERR_ARGUMENT,
                "Arlequin: one or two overlaps, not %d", o->n_overlaps);
    if (o->n_overlaps == 2)
      CUPID_CHECK(o->second.hi > o->second.lo && o->second.lo >= o->weight.hi &&
                      o->weight.fe_below && !o->second.fe_below,
                  CUPID_ERR_ARGUMENT,
                  "Arlequin: the second overlap [%g, %g] must lie above the first [%g, %g], with "
                  "the FE-only parts below the first and above the second",
                  o->second.lo, o->second.hi, o->weight.lo, o->weight.hi);
  }
  cupid_cuf_info fi;
  cupid_cuf_get_info(beam, &fi);
  CUPID_CHECK(fi.dof_offset == 3 * cupid_pd_grid_num_nodes(grid), CUPID_ERR_ARGUMENT,
              "Arlequin: the beam's DOF offset must be 3 x PD nodes");
  return CUPID_SUCCESS;
}

/* On a slab of a partitioned grid (issue 6) the FE rows are summed over the slabs: the last
 * slab, which owns the FE DOFs, adds the weighted beam; every slab adds the penalty of its
 * owned tied nodes. A whole grid does both. */
static int owns_beam(cupid_pd_grid grid) {
  cupid_pd_grid_partition part;
  cupid_pd_grid_get_partition(grid, &part);
  return part.parts <= 1 || part.part == part.parts - 1;
}

/* PD nodal weights 1 - alpha(x_i). */
cupid_status cpl_arlequin_pd_weights(cupid_pd_grid grid, const cupid_arlequin_options *o,
                                     double **wn, double *wmin) {
  cupid_int n = cupid_pd_grid_num_nodes(grid);
  const double *x = cupid_pd_grid_coords(grid);
  layout_t L;
  layout_of(o, &L);
  CUPID_CALL(cupid_malloc((size_t)n + 1, sizeof **wn, "PD weights", wn));
  *wmin = 1.0;
  for (cupid_int i = 0; i < n; i++) {
    (*wn)[i] = pd_weight_at(&L, x + 3 * i);
    if ((*wn)[i] < *wmin) *wmin = (*wn)[i];
  }
  return CUPID_SUCCESS;
}

/* What the coupled K keeps between assemblies: the weighted beam and the penalty (F, on the
 * union of their patterns) and the PD nodes' weights. Broken bonds change the PD block and
 * nothing else. Every K, the first included, is the union of F's pattern and the PD block's,
 * F added, then the PD block: K depends on the bonds intact now and not on those broken
 * before (a run resumed from a checkpoint assembles the K of a run never interrupted). */
struct cupid_arlequin_assembly_private {
  cupid_csr F;
  double *wn; /* the PD nodes' weights (Eq. 12) */
};

void cupid_arlequin_assembly_destroy(cupid_arlequin_assembly *A) {
  if (!A || !*A) return;
  cupid_csr_destroy(&(*A)->F);
  cupid_free(&(*A)->wn);
  cupid_free(A);
}

/* The union of the patterns of F and (rows below its own count) P, row by row: both rows are
 * sorted, so a merge (a count, then a fill). */
static cupid_status union_pattern(const cupid_csr_t *F, const cupid_csr_t *P, cupid_csr *K) {
  cupid_status st = CUPID_SUCCESS;
  const cupid_int nb = F->nrows;
  cupid_int *rowptr = NULL, *col = NULL;
  CUPID_TRY(cupid_calloc((size_t)nb + 1, sizeof *rowptr, "Arlequin rows", &rowptr));
  for (int pass = 0; pass < 2; pass++) {
    for (cupid_int r = 0; r < nb; r++) {
      cupid_int a = F->rowptr[r], b = P && r < P->nrows ? P->rowptr[r] : 0;
      cupid_int n = pass ? rowptr[r] : 0;
      const cupid_int ae = F->rowptr[r + 1], be = P && r < P->nrows ? P->rowptr[r + 1] : 0;
      while (a < ae || b < be) {
        const cupid_int c = b >= be || (a < ae && F->col[a] <= P->col[b]) ? F->col[a] : P->col[b];
        if (a < ae && F->col[a] == c) a++;
        if (b < be && P->col[b] == c) b++;
        if (pass) col[n] = c;
        n++;
      }
      if (!pass) rowptr[r + 1] = n; /* the row's count, summed below */
    }
    if (pass) break;
    for (cupid_int r = 0; r < nb; r++) rowptr[r + 1] += rowptr[r];
    CUPID_TRY(cupid_malloc((size_t)rowptr[nb] + 1, sizeof *col, "Arlequin columns", &col));
  }
  CUPID_TRY(cupid_csr_create(nb, nb, 3, rowptr, col, K));
cleanup:
  cupid_free(&rowptr);
  cupid_free(&col);
  return st;
}

/* K: F's pattern and the PD block's, F added, then the PD block of op. */
static cupid_status fill(const cupid_arlequin_assembly A, cupid_pd_operator op, cupid_csr *K) {
  cupid_status st = CUPID_SUCCESS;
  cupid_csr Kpd = NULL;
  *K = NULL;
  if (op) CUPID_TRY(cupid_pd_operator_assemble_weighted(op, A->wn, &Kpd)); /* Eq. 12 */
  CUPID_TRY(union_pattern(A->F, Kpd, K));
  cupid_csr_zero(*K);
  CUPID_TRY(add_part(A->F, *K));
  if (Kpd) CUPID_TRY(add_part(Kpd, *K));
cleanup:
  if (st != CUPID_SUCCESS) cupid_csr_destroy(K);
  cupid_csr_destroy(&Kpd);
  return st;
}

cupid_status cupid_arlequin_assembly_create(cupid_cuf_beam beam, cupid_pd_grid grid,
                                            cupid_pd_operator op, const cupid_arlequin_options *o,
                                            cupid_arlequin_assembly *out, cupid_csr *K,
                                            cupid_arlequin_info *info) {
  cupid_status st = CUPID_SUCCESS;
  cupid_arlequin_assembly A = NULL;
  tied_t t = {0};
  CUPID_CALL(check_options(beam, grid, o));
  *out = NULL, *K = NULL;
  cupid_int n_pd = cupid_pd_grid_num_nodes(grid), n_fe = cupid_cuf_num_dofs(beam) / 3;
  double wmin;
  CUPID_TRY(cupid_calloc(1, sizeof *A, "Arlequin assembly", &A));
  CUPID_TRY(cpl_arlequin_pd_weights(grid, o, &A->wn, &wmin));
  CUPID_TRY(tied_build(beam, grid, o, &t));
  CUPID_TRY(build_pattern(beam, &t, n_pd, n_fe, &A->F));
  layout_t L;
  cupid_cuf_weight_term terms[ARL_MAX_TERMS];
  cupid_cuf_weight wfe;
  CUPID_TRY(beam_weight(o, &L, terms, &wfe));
  if (owns_beam(grid)) CUPID_TRY(cupid_cuf_assemble_weight_add(beam, &wfe, A->F));
  CUPID_TRY(add_penalty(&t, o->penalty, n_pd, A->F));
  CUPID_TRY(fill(A, op, K));
  if (info) *info = (cupid_arlequin_info){.n_tied = t.n, .components = t.comps, .pd_weight_min = wmin};
  *out = A;
  A = NULL;
cleanup:
  cupid_arlequin_assembly_destroy(&A);
  tied_free(&t);
  return st;
}

cupid_status cupid_arlequin_assembly_matrix(const cupid_arlequin_assembly A, cupid_pd_operator op,
                                            cupid_csr *K) {
  CUPID_CHECK(A && K, CUPID_ERR_ARGUMENT, "cupid_arlequin_assembly_matrix needs its arguments");
  return fill(A, op, K);
}

/* Row by row as fill() does the whole K: zero, the kept part, the PD block (the same sums in
 * the same order, so the same values to the bit). */
cupid_status cupid_arlequin_assembly_update_rows(const cupid_arlequin_assembly A, cupid_pd_operator op,
                                                 const cupid_int *nodes, cupid_int n, cupid_csr K) {
  CUPID_CHECK(A && op && K && K->nrows == A->F->nrows && K->bs == 3, CUPID_ERR_ARGUMENT,
              "cupid_arlequin_assembly_update_rows needs the assembly, an operator and its K");
  cupid_csr R = NULL;
  CUPID_CALL(cupid_pd_operator_assemble_node_rows(op, A->wn, nodes, n, &R)); /* Eq. 12 */
  cupid_status st = CUPID_SUCCESS;
  for (cupid_int k = 0; k < n && st == CUPID_SUCCESS; k++) {
    const cupid_int r = nodes[k];
    cupid_csr_zero_row(K, r);
    st = cupid_csr_add_row(K, r, A->F, r);
    if (st == CUPID_SUCCESS) st = cupid_csr_add_row(K, r, R, k);
  }
  cupid_csr_destroy(&R);
  return st;
}

cupid_status cupid_arlequin_assemble(cupid_cuf_beam beam, cupid_pd_grid grid, cupid_pd_operator op,
                                     const cupid_arlequin_options *o, cupid_csr *K,
                                     cupid_arlequin_info *info) {
  cupid_arlequin_assembly A = NULL;
  cupid_status st = cupid_arlequin_assembly_create(beam, grid, op, o, &A, K, info);
  cupid_arlequin_assembly_destroy(&A);
  return st;
}

cupid_status cupid_arlequin_mass(cupid_cuf_beam beam, cupid_pd_grid grid,
                                 const cupid_arlequin_options *o, const double *pd_mass,
                                 cupid_csr M, double *lumped) {
  CUPID_CALL(check_options(beam, grid, o));
  CUPID_CHECK(pd_mass && (M != NULL) != (lumped != NULL), CUPID_ERR_ARGUMENT,
              "cupid_arlequin_mass: give the PD masses and exactly one of M, lumped");
  cupid_int n = cupid_pd_grid_num_nodes(grid);
  const double *x = cupid_pd_grid_coords(grid);
  layout_t L;
  cupid_cuf_weight_term terms[ARL_MAX_TERMS];
  cupid_cuf_weight wfe;
  CUPID_CALL(beam_weight(o, &L, terms, &wfe));
  for (cupid_int i = 0; i < n; i++) {
    double m = pd_weight_at(&L, x + 3 * i) * pd_mass[i]; /* Eq. 14 */
    if (lumped) {
      for (int c = 0; c < 3; c++) lumped[3 * i + c] += m;
      continue;
    }
    double *blk = cupid_csr_find(M, i, i);
    CUPID_CHECK(blk, CUPID_ERR_ARGUMENT, "the mass pattern lacks the block of PD node %lld",
                (long long)i);
    for (int c = 0; c < 3; c++) blk[4 * c] += m;
  }
  if (lumped) return cupid_cuf_mass_lumped_weight(beam, &wfe, lumped);
  return cupid_cuf_mass_weight_add(beam, &wfe, M);
}

cupid_status cupid_arlequin_tie_forces(cupid_cuf_beam beam, cupid_pd_grid grid,
                                      const cupid_arlequin_options *o, double *f) {
  CUPID_CALL(check_options(beam, grid, o));
  tied_t t;
  CUPID_CALL(tied_build(beam, grid, o, &t));
  cupid_int off = 3 * cupid_pd_grid_num_nodes(grid);
  int c0 = t.comps == 1 ? 1 : 0, c1 = t.comps == 1 ? 2 : 3;
  for (cupid_int k = 0; k < t.n; k++)
    for (int c = c0; c < c1; c++) {
      double *fq = &f[3 * t.node[k] + c];
      for (cupid_int a = t.ptr[k]; a < t.ptr[k + 1]; a++) f[off + 3 * t.fe[a] + c] += t.w[a] * *fq;
      *fq = 0.0;
    }
  tied_free(&t);
  return CUPID_SUCCESS;
}

cupid_status cupid_arlequin_gap(cupid_cuf_beam beam, cupid_pd_grid grid,
                                const cupid_arlequin_options *o, const double *u, double *gap) {
  CUPID_CALL(check_options(beam, grid, o));
  tied_t t;
  CUPID_CALL(tied_build(beam, grid, o, &t));
  cupid_int off = 3 * cupid_pd_grid_num_nodes(grid);
  int c0 = t.comps == 1 ? 1 : 0, c1 = t.comps == 1 ? 2 : 3;
  *gap = 0.0;
  for (cupid_int k = 0; k < t.n; k++)
    for (int c = c0; c < c1; c++) {
      double z = u[3 * t.node[k] + c];
      for (cupid_int a = t.ptr[k]; a < t.ptr[k + 1]; a++) z -= t.w[a] * u[off + 3 * t.fe[a] + c];
      if (fabs(z) > *gap) *gap = fabs(z);
    }
  tied_free(&t);
  return CUPID_SUCCESS;
}

cupid_status cupid_arlequin_node_stiffness(cupid_pd_operator op, cupid_pd_grid grid, double *k_node) {
  CUPID_CHECK(op && grid && k_node, CUPID_ERR_ARGUMENT, "cupid_arlequin_node_stiffness: NULL argument");
  cupid_int n = cupid_pd_grid_num_nodes(grid);
  cupid_pd_grid_partition part;
  cupid_pd_grid_get_partition(grid, &part);
  double *blk = NULL;
  CUPID_CALL(cupid_malloc(9 * (size_t)n + 1, sizeof *blk, "PD diagonal blocks", &blk));
  cupid_status st = cupid_pd_operator_diagonal(op, blk);
  const int one_d = cupid_pd_grid_dimension(grid) == 1;
  *k_node = 0.0;
  for (cupid_int i = part.owned_first; st == CUPID_SUCCESS && i < part.owned_last; i++) {
    const double *b = blk + 9 * i;
    double k = one_d ? b[4] : (b[0] + b[4] + b[8]) / 3.0;
    if (k > *k_node) *k_node = k;
  }
  cupid_free(&blk);
  return st;
}
