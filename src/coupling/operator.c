/* The coupled operator of the fictitious-node method (paper 000 Eq. 38) without the PD
 * stiffness: y = A x over [3 DOFs per real PD node | FE DOFs], the ordering of the assembled
 * coupled matrix (cupid_coupling_create()).
 *
 * PD rows: the extended PD grid (real + fictitious nodes) carries u_ext = [x_PD ; I^{f-PD} x_FE]
 * (Eqs. 29-30: a fictitious node takes the CUF field at its point); the PD operator is applied
 * matrix-free on it and the rows of the real nodes are kept. This is the assembled matrix's PD
 * rows re-associated: K^PD x_PD + K^{f-PD} (I^{f-PD} x_FE). FE rows: the real and fictitious FE
 * elements with their I^{f-FE} columns, assembled (they are few: the beam's DOFs).
 *
 * The preconditioner matrix is the same Eq. 38 with a cheap PD operator on the same extended
 * grid: bond-based, horizon delta' = f h (f ~ 1.5: the 18 face and edge neighbours), constant
 * influence, whole cells (partial volume NONE), each node's micromodulus calibrated to its bulk
 * modulus (pd.h: c = 18 K / S on the discrete stencil). About 19 blocks a PD row instead of the
 * ~900 of LPS at delta = 3 h, and no 2 delta coupling. */
#include <math.h>
#include <string.h>

#include "coupling_internal.h"
#include "cupid/coupling.h"

struct cupid_coupling_operator_private {
  cupid_coupling_h c;              /* interfaces and info */
  cpl_parts parts;                 /* extended grid, its map, the FE rows */
  cupid_pd_operator_options pd;    /* the PD operator of the model */
  cupid_pd_operator op;            /* ... on the extended grid */
  cupid_int *ext_of;               /* real PD node -> extended node */
  int ext_ascending;               /* ext_of increases (row ranges map to extended ranges) */
  cupid_pd_grid_partition part;    /* the real grid's: a slab holds its owned rows (issue 6) */
  double *ue, *fe;                 /* 3 per extended node: work vectors of apply */
};

cupid_status cupid_coupling_operator_create(cupid_cuf_beam beam, cupid_pd_grid grid,
                                            const cupid_coupling_options *opts,
                                            cupid_coupling_operator *out) {
  cupid_status st = CUPID_SUCCESS;
  cupid_coupling_operator A = NULL;
  CUPID_CALL(cupid_calloc(1, sizeof *A, "coupled operator", &A));
  CUPID_TRY(cupid_calloc(1, sizeof *A->c, "coupling", &A->c));
  CUPID_TRY(cpl_parts_build(beam, grid, opts, A->c, &A->parts));
  A->pd = opts->pd;
  cupid_pd_grid_get_partition(grid, &A->part);
  CUPID_TRY(cupid_pd_operator_create(A->parts.ext, &A->pd, &A->op));
  cupid_int n_ext = A->parts.n_ext, n_pd = A->parts.n_pd;
  CUPID_TRY(cupid_malloc((size_t)(n_pd > 0 ? n_pd : 1), sizeof *A->ext_of, "real -> extended",
                         &A->ext_of));
  for (cupid_int i = 0; i < n_ext; i++)
    if (A->parts.map.real[i] >= 0) A->ext_of[A->parts.map.real[i]] = i;
  A->ext_ascending = 1;
  for (cupid_int r = 1; r < n_pd; r++) A->ext_ascending &= A->ext_of[r] > A->ext_of[r - 1];
  CUPID_TRY(cupid_malloc((size_t)(3 * n_ext), sizeof *A->ue, "extended displacements", &A->ue));
  CUPID_TRY(cupid_malloc((size_t)(3 * n_ext), sizeof *A->fe, "extended forces", &A->fe));
  *out = A;
  A = NULL;
cleanup:
  cupid_coupling_operator_destroy(&A);
  return st;
}

void cupid_coupling_operator_destroy(cupid_coupling_operator *A) {
  if (!A || !*A) return;
  cupid_coupling_destroy(&(*A)->c);
  cpl_parts_free(&(*A)->parts);
  cupid_pd_operator_destroy(&(*A)->op);
  cupid_free(&(*A)->ext_of);
  cupid_free(&(*A)->ue);
  cupid_free(&(*A)->fe);
  cupid_free(A);
}

cupid_int cupid_coupling_operator_size(const cupid_coupling_operator A) {
  return 3 * (A->parts.n_pd + A->parts.Kfe->nrows);
}

void cupid_coupling_operator_get_info(const cupid_coupling_operator A, cupid_coupling_info *info) {
  *info = A->c->info;
}

const cupid_pd_grid_partition *cpl_operator_partition(const cupid_coupling_operator A,
                                                      cupid_int *n_pd) {
  *n_pd = A->parts.n_pd;
  return &A->part;
}

int64_t cupid_coupling_operator_bytes(const cupid_coupling_operator A) {
  cupid_int n_ext = A->parts.n_ext;
  int64_t b = (int64_t)cupid_pd_operator_num_bonds(A->op) * 12 /* neighbour + stencil index */
              + n_ext * (int64_t)(8 * 6 + 8 * 8) /* ue, fe, coords, per-node data, map */
              + cupid_csr_bytes(A->parts.Kfe);
  b += (int64_t)A->parts.map.fptr[n_ext] * 16;
  return b;
}

/* u_ext = [x_PD ; I^{f-PD} x_FE] (Eq. 29) on the extended nodes [lo, hi). */
static void extended_field(const cupid_coupling_operator A, const double *x, cupid_int lo,
                           cupid_int hi) {
  const ext_map *m = &A->parts.map;
  const double *xfe = x + 3 * A->parts.n_pd;
  double *ue = A->ue;
#pragma omp parallel for schedule(static) if (hi - lo > 4096)
  for (cupid_int i = lo; i < hi; i++) {
    cupid_int r = m->real[i];
    double *u = ue + 3 * i;
    if (r >= 0) {
      u[0] = x[3 * r];
      u[1] = x[3 * r + 1];
      u[2] = x[3 * r + 2];
      continue;
    }
    u[0] = u[1] = u[2] = 0.0;
    for (cupid_int k = m->fptr[i]; k < m->fptr[i + 1]; k++) {
      const double *v = xfe + 3 * m->fnode[k];
      double w = m->fw[k];
      u[0] += w * v[0];
      u[1] += w * v[1];
      u[2] += w * v[2];
    }
  }
}

cupid_status cupid_coupling_operator_apply(const cupid_coupling_operator A, const double *x,
                                           double *y) {
  cupid_int n_ext = A->parts.n_ext, n_pd = A->parts.n_pd;
  extended_field(A, x, 0, n_ext);
  CUPID_CALL(cupid_pd_operator_apply(A->op, A->ue, A->fe));
  const double *fe = A->fe;
#pragma omp parallel for schedule(static) if (n_pd > 4096)
  for (cupid_int r = 0; r < n_pd; r++) {
    const double *f = fe + 3 * A->ext_of[r];
    y[3 * r] = f[0];
    y[3 * r + 1] = f[1];
    y[3 * r + 2] = f[2];
  }
  /* FE rows: real and fictitious FE elements (Eq. 38), assembled. */
  cupid_csr_matvec(A->parts.Kfe, x, y + 3 * n_pd);
  return CUPID_SUCCESS;
}

/* z = A^T w: the PD operator is symmetric, so the PD rows' transpose is the operator applied to
 * w_PD on the real nodes (0 on the fictitious ones), its real rows kept and its fictitious
 * rows sent to the FE DOFs by the transpose of Eq. 29's interpolation; the FE rows' by Kfe^T. */
cupid_status cupid_coupling_operator_apply_transpose(const cupid_coupling_operator A,
                                                     const double *w, double *z) {
  const cupid_int n_ext = A->parts.n_ext, n_pd = A->parts.n_pd;
  CUPID_CHECK(A->part.parts <= 1,
              CUPID_ERR_UNSUPPORTED, "the transpose of the coupled operator needs the whole grid");
  const ext_map *m = &A->parts.map;
  memset(A->ue, 0, (size_t)(3 * n_ext) * sizeof *A->ue);
  for (cupid_int r = 0; r < n_pd; r++)
    for (int c = 0; c < 3; c++) A->ue[3 * A->ext_of[r] + c] = w[3 * r + c];
  CUPID_CALL(cupid_pd_operator_apply(A->op, A->ue, A->fe));
  cupid_csr_matvec_transpose(A->parts.Kfe, w + 3 * n_pd, z);
  for (cupid_int i = 0; i < n_ext; i++) {
    const double *g = A->fe + 3 * i;
    cupid_int r = m->real[i];
    if (r >= 0) {
      for (int c = 0; c < 3; c++) z[3 * r + c] += g[c];
      continue;
    }
    for (cupid_int k = m->fptr[i]; k < m->fptr[i + 1]; k++)
      for (int c = 0; c < 3; c++) z[3 * (n_pd + m->fnode[k]) + c] += m->fw[k] * g[c];
  }
  return CUPID_SUCCESS;
}

const cupid_csr_t *cupid_coupling_operator_fe_rows(const cupid_coupling_operator A) {
  return A->parts.Kfe;
}

cupid_status cupid_coupling_operator_apply_rows(const cupid_coupling_operator A, const double *x,
                                                cupid_int d0, cupid_int d1, double *y) {
  cupid_int n_pd = A->parts.n_pd, n = cupid_coupling_operator_size(A);
  CUPID_CHECK(d0 >= 0 && d0 <= d1 && d1 <= n, CUPID_ERR_ARGUMENT,
              "rows [%lld, %lld) outside the operator's %lld", (long long)d0, (long long)d1,
              (long long)n);
  if (!A->ext_ascending) /* no range of extended nodes holds the rows: the whole product */
    return cupid_coupling_operator_apply(A, x, y);
  const cupid_int r0 = d0 / 3, r1 = (d1 < 3 * n_pd ? d1 + 2 : 3 * n_pd) / 3;
  if (r0 < r1) {
    /* The real nodes [r0, r1) lie in the extended nodes [e0, e1), which read [lo, hi). */
    const cupid_int e0 = A->ext_of[r0], e1 = A->ext_of[r1 - 1] + 1;
    cupid_int lo, hi;
    CUPID_CALL(cupid_pd_operator_dependency_range(A->op, e0, e1, &lo, &hi));
    extended_field(A, x, lo, hi);
    CUPID_CALL(cupid_pd_operator_apply_range(A->op, e0, e1, A->ue, A->fe));
    for (cupid_int r = r0; r < r1; r++) {
      const double *f = A->fe + 3 * (A->ext_of[r] - e0);
      for (int c = 0; c < 3; c++)
        if (3 * r + c >= d0 && 3 * r + c < d1) y[3 * r + c] = f[c];
    }
  }
  /* FE rows: block rows of Kfe, columns over [PD | FE] */
  cupid_csr_matvec_rows(A->parts.Kfe, x, 3 * n_pd, d0, d1, y);
  return CUPID_SUCCESS;
}

cupid_status cupid_coupling_operator_assemble(const cupid_coupling_operator A,
                                              const cupid_pd_operator_options *pd, cupid_csr *K) {
  return pd ? cpl_parts_assemble(&A->parts, pd, K) : cpl_parts_assemble_op(&A->parts, A->op, K);
}

cupid_pd_operator cupid_coupling_operator_pd(const cupid_coupling_operator A) { return A->op; }

const cupid_int *cupid_coupling_operator_extended_nodes(const cupid_coupling_operator A) {
  return A->ext_of;
}

cupid_status cupid_coupling_operator_fit_boxes(const cupid_coupling_operator A,
                                               const cupid_cuf_beam beam, double *boxes) {
  const cupid_csr_t *F = A->parts.Kfe;
  const double *xe = cupid_pd_grid_coords(A->parts.ext);
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  CUPID_CHECK(F->nrows == info.n_fe_nodes, CUPID_ERR_ARGUMENT,
              "fit boxes: the operator has %lld FE nodes, the beam %lld", (long long)F->nrows,
              (long long)info.n_fe_nodes);
  const cupid_int n_pd = A->parts.n_pd;
  for (cupid_int a = 0; a < F->nrows; a++) {
    double *b = boxes + 6 * a;
    for (int c = 0; c < 3; c++) b[c] = INFINITY, b[3 + c] = -INFINITY;
    int reads_pd = 0;
    for (cupid_int k = F->rowptr[a]; k < F->rowptr[a + 1]; k++) {
      const cupid_int col = F->col[k];
      if (col >= n_pd) continue;
      const double *v = F->val + 9 * k;
      int nonzero = 0;
      for (int e = 0; e < 9; e++) nonzero |= v[e] != 0.0;
      if (!nonzero) continue;
      reads_pd = 1;
      const double *x = xe + 3 * A->ext_of[col];
      for (int c = 0; c < 3; c++) b[c] = fmin(b[c], x[c]), b[3 + c] = fmax(b[3 + c], x[c]);
    }
    if (!reads_pd) continue;
    /* the FE node itself: its beam node's y, and its section point (LE; a TE term spans the
     * section, which the fits over whole planes already do) */
    double xz[2], hs;
    const double y = cupid_cuf_beam_node_y(beam, a / info.M);
    b[1] = fmin(b[1], y), b[4] = fmax(b[4], y);
    if (info.expansion == CUPID_EXPANSION_LE) {
      cupid_cuf_section_node(beam, (int)(a % info.M), xz, &hs);
      b[0] = fmin(b[0], xz[0]), b[3] = fmax(b[3], xz[0]);
      b[2] = fmin(b[2], xz[1]), b[5] = fmax(b[5], xz[1]);
    }
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_coupling_operator_zone(const cupid_coupling_operator A,
                                          const unsigned char *core, unsigned char *zone) {
  const cupid_int n_ext = A->parts.n_ext, n_pd = A->parts.n_pd;
  unsigned char *mark = NULL, *near = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_calloc((size_t)n_ext + 1, 1, "fictitious nodes", &mark));
  CUPID_TRY(cupid_calloc((size_t)n_ext + 1, 1, "coupling zone", &near));
  for (cupid_int i = 0; i < n_ext; i++) mark[i] = A->parts.map.real[i] < 0;
  cupid_pd_operator_mark_families(A->op, mark, near);
  for (cupid_int r = 0; r < n_pd; r++) zone[r] = near[A->ext_of[r]] || (core && core[r]);
cleanup:
  cupid_free(&mark);
  cupid_free(&near);
  return st;
}

void cupid_coupling_cheap_options(const cupid_pd_operator_options *fine, double spacing,
                                  double horizon_factor, cupid_pd_operator_options *cheap) {
  *cheap = *fine;
  cheap->model = CUPID_PD_BOND;
  cheap->horizon = (horizon_factor > 0.0 ? horizon_factor : 1.5) * spacing;
  cheap->influence = CUPID_INFLUENCE_CONSTANT;
  cheap->partial_volume = CUPID_PARTIAL_NONE;
}

cupid_status cupid_coupling_preconditioner(const cupid_coupling_operator A, double horizon_factor,
                                           cupid_csr *P) {
  cupid_pd_operator_options cheap;
  double h = cupid_pd_grid_spacing(A->parts.ext);
  cupid_coupling_cheap_options(&A->pd, h, horizon_factor, &cheap);
  return cpl_parts_assemble(&A->parts, &cheap, P);
}

/* The fictitious-node operator as a cupid_linear_operator. */
static cupid_status fict_apply(void *ctx, const double *x, double *y) {
  return cupid_coupling_operator_apply(ctx, x, y);
}

static cupid_status fict_apply_rows(void *ctx, const double *x, cupid_int d0, cupid_int d1, double *y) {
  return cupid_coupling_operator_apply_rows(ctx, x, d0, d1, y);
}

void cupid_coupling_operator_linear(const cupid_coupling_operator A, cupid_linear_operator *L) {
  cupid_int n_pd = 0; /* the slab's on a slab (the info counts the whole model) */
  const cupid_pd_grid_partition *part = cpl_operator_partition(A, &n_pd);
  *L = (cupid_linear_operator){.n = cupid_coupling_operator_size(A),
                               .apply = fict_apply,
                               .apply_rows = fict_apply_rows,
                               .ctx = A,
                               .symmetric = 0,
                               .n_pd_dofs = 3 * n_pd,
                               .part = part};
}

cupid_status cupid_coupling_krylov_solve(const cupid_coupling_operator A, const cupid_csr_t *P,
                                         const cupid_dirichlet_t *bc, const double *f, double *u,
                                         const cupid_krylov_options *opts,
                                         cupid_solve_info *info) {
  CUPID_CHECK(A, CUPID_ERR_ARGUMENT, "Krylov solve: NULL operator");
  cupid_linear_operator L;
  cupid_coupling_operator_linear(A, &L);
  return cupid_krylov_solve(&L, P, bc, f, u, opts, info);
}
