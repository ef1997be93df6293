/* Sparse assembly of the CUF stiffness (paper 000 Eqs. 27-28): block CSR (bs = 3) whose pattern
 * follows the element connectivity, so LE nodes that share no section element get no block
 * (cuf.md section 3.2), and a separable nucleus per (beam element, section group). */
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "cuf/cuf_internal.h"

typedef struct cupid_cuf_beam_private beam_t;

/* Beam elements holding beam node i: [*lo, *hi]. */
static void node_elements(const beam_t *b, cupid_int i, cupid_int *lo, cupid_int *hi) {
  cupid_int e = i / (b->p - 1);
  *lo = (i % (b->p - 1) == 0 && e > 0) ? e - 1 : e;
  *hi = e < b->n_belem ? e : b->n_belem - 1;
}

/* Sorted columns of block row r = (beam node i, function tau): beam neighbours j in increasing
 * order, and for each j the section neighbours of tau (sorted adjacency, LE) that share an
 * active section element with tau in a beam element holding i and j. mark[] (size M) holds
 * the stamp of the last (row, j) that marked a function. */
static cupid_int row_columns(const beam_t *b, const unsigned char *be_any, const cupid_int *adj_ptr,
                             const cupid_int *adj, cupid_int r, cupid_int *mark, cupid_int *stamp,
                             cupid_int *out) {
  cupid_int M = b->M, i = r / M, n = 0;
  int tau = (int)(r % M), p = b->p;
  cupid_int lo, hi;
  node_elements(b, i, &lo, &hi);
  for (cupid_int j = lo * (p - 1); j <= hi * (p - 1) + p - 1; j++) {
    cupid_int st = ++*stamp;
    int any = 0;
    if (j == i) mark[tau] = st, any = 1; /* the diagonal block is always there */
    for (cupid_int e = lo; e <= hi; e++) {
      if (j < e * (p - 1) || j > e * (p - 1) + p - 1) continue;
      if (b->expansion == CUPID_EXPANSION_TE) {
        any |= be_any[e];
        continue;
      }
      for (cupid_int k = b->n2e_ptr[tau]; k < b->n2e_ptr[tau + 1]; k++) {
        cupid_int se = b->n2e[k];
        if (!b->active[e * b->n_selem + se]) continue;
        const cupid_int *conn = b->sconn + se * b->quad.npe;
        for (int q = 0; q < b->quad.npe; q++) mark[conn[q]] = st;
        any = 1;
      }
    }
    if (!any) continue;
    if (b->expansion == CUPID_EXPANSION_TE) {
      if (j != i || be_any[lo] || be_any[hi])
        for (cupid_int s2 = 0; s2 < M; s2++) out[n++] = j * M + s2;
      else
        out[n++] = r;
      continue;
    }
    for (cupid_int k = adj_ptr[tau]; k < adj_ptr[tau + 1]; k++)
      if (mark[adj[k]] == st) out[n++] = j * M + adj[k];
  }
  return n;
}

static int cmp_int(const void *a, const void *b) {
  cupid_int x = *(const cupid_int *)a, y = *(const cupid_int *)b;
  return (x > y) - (x < y);
}

/* LE: sorted section-node adjacency (nodes sharing an element, the node itself included). */
static cupid_status section_adjacency(const beam_t *b, cupid_int **adj_ptr, cupid_int **adj) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int nn = b->n_snodes, *mark = NULL, *ptr = NULL, *a = NULL;
  int npe = b->quad.npe;
  CUPID_TRY(cupid_calloc((size_t)nn + 1, sizeof *ptr, "section adjacency", &ptr));
  CUPID_TRY(cupid_malloc((size_t)nn, sizeof *mark, "section adjacency marks", &mark));
  for (cupid_int v = 0; v < nn; v++) mark[v] = -1;
  for (int pass = 0; pass < 2; pass++) {
    for (cupid_int v = 0; v < nn; v++) {
      cupid_int c = 0;
      for (cupid_int k = b->n2e_ptr[v]; k < b->n2e_ptr[v + 1]; k++)
        for (int q = 0; q < npe; q++) {
          cupid_int w = b->sconn[b->n2e[k] * npe + q];
          if (mark[w] == v + pass * nn) continue;
          mark[w] = v + pass * nn;
          if (pass) a[ptr[v] + c] = w;
          c++;
        }
      if (pass == 0) ptr[v + 1] = c;
      else qsort(a + ptr[v], (size_t)c, sizeof *a, cmp_int);
    }
    if (pass == 0) {
      for (cupid_int v = 0; v < nn; v++) ptr[v + 1] += ptr[v];
      CUPID_TRY(cupid_malloc((size_t)ptr[nn], sizeof *a, "section adjacency", &a));
    }
  }
  *adj_ptr = ptr;
  *adj = a;
  ptr = a = NULL;
cleanup:
  cupid_free(&mark);
  cupid_free(&ptr);
  cupid_free(&a);
  return st;
}

cupid_status cupid_cuf_pattern(const cupid_cuf_beam b, cupid_int **rowptr_out, cupid_int **col_out) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int n = b->n_bnodes * b->M, *rowptr = NULL, *col = NULL, *adj_ptr = NULL, *adj = NULL;
  unsigned char *be_any = NULL;
  int fail = 0;
  /* widest possible row: 2 beam elements x p nodes x (M or the LE neighbourhood) */
  cupid_int width = 2 * b->p * (cupid_int)b->M;
  if (b->expansion == CUPID_EXPANSION_LE) {
    cupid_int deg = 0;
    for (cupid_int v = 0; v < b->n_snodes; v++)
      if (b->n2e_ptr[v + 1] - b->n2e_ptr[v] > deg) deg = b->n2e_ptr[v + 1] - b->n2e_ptr[v];
    if (deg * b->quad.npe < b->M) width = 2 * b->p * deg * b->quad.npe;
  }
  width += 1;
  if (b->expansion == CUPID_EXPANSION_LE) CUPID_TRY(section_adjacency(b, &adj_ptr, &adj));
  CUPID_TRY(cupid_calloc((size_t)n + 1, sizeof *rowptr, "CUF pattern rows", &rowptr));
  CUPID_TRY(cupid_calloc((size_t)b->n_belem, 1, "CUF element flags", &be_any));
  for (cupid_int e = 0; e < b->n_belem; e++)
    for (cupid_int s = 0; s < b->n_selem && !be_any[e]; s++) be_any[e] = b->active[e * b->n_selem + s];
  for (int pass = 0; pass < 2; pass++) {
#pragma omp parallel reduction(| : fail) if (3 * n > CUF_PARALLEL_DOFS)
    {
      cupid_int *marker = NULL, *buf = NULL, stamp = 0;
      if (cupid_malloc((size_t)b->M, sizeof *marker, "CUF pattern marker", &marker) != CUPID_SUCCESS ||
          cupid_malloc((size_t)width, sizeof *buf, "CUF pattern row", &buf) != CUPID_SUCCESS) {
        fail = 1;
      } else {
        for (cupid_int k = 0; k < b->M; k++) marker[k] = -1;
#pragma omp for schedule(dynamic, 64)
        for (cupid_int r = 0; r < n; r++) {
          cupid_int *dst = pass == 0 ? buf : col + rowptr[r];
          cupid_int c = row_columns(b, be_any, adj_ptr, adj, r, marker, &stamp, dst);
          if (pass == 0) rowptr[r + 1] = c;
        }
      }
      cupid_free(&marker);
      cupid_free(&buf);
    }
    CUPID_TRY_CHECK(!fail, CUPID_ERR_MEMORY, "out of memory building the CUF pattern");
    if (pass == 0) {
      for (cupid_int r = 0; r < n; r++) rowptr[r + 1] += rowptr[r];
      CUPID_TRY(cupid_malloc((size_t)rowptr[n], sizeof *col, "CUF pattern columns", &col));
    }
  }
  *rowptr_out = rowptr;
  *col_out = col;
  rowptr = col = NULL;
cleanup:
  cupid_free(&rowptr);
  cupid_free(&col);
  cupid_free(&be_any);
  cupid_free(&adj_ptr);
  cupid_free(&adj);
  return st;
}

/* First position in block row `row` of K with column >= col (K->rowptr[row + 1] if none). */
static cupid_int lower_bound(const cupid_csr_t *K, cupid_int row, cupid_int col) {
  cupid_int lo = K->rowptr[row], hi = K->rowptr[row + 1];
  while (lo < hi) {
    cupid_int mid = (lo + hi) / 2;
    if (K->col[mid] < col) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

/* Add a dense pair matrix (layout of cuf_pair_matrix) into K at block offset boff. The local
 * functions are visited in increasing global index (order[]), so each block row is walked
 * forward once per beam node instead of one binary search per block. */
static int scatter(const beam_t *b, cupid_csr K, cupid_int boff, cupid_int be, cupid_int se,
                   int m, const double *Ke, int *order) {
  int p = b->p, n = 3 * m * p;
  cupid_int j0 = be * (p - 1), M = b->M;
  for (int a = 0; a < m; a++) order[a] = a;
  if (se >= 0) /* insertion sort of the (few) local LE nodes by global index */
    for (int a = 1; a < m; a++)
      for (int c = a; c > 0 && cuf_tau(b, se, order[c - 1]) > cuf_tau(b, se, order[c]); c--) {
        int tmp = order[c];
        order[c] = order[c - 1];
        order[c - 1] = tmp;
      }
  for (int s = 0; s < m; s++)
    for (int j = 0; j < p; j++) {
      cupid_int row = boff + (j0 + j) * M + cuf_tau(b, se, s), end = K->rowptr[row + 1];
      for (int i = 0; i < p; i++) {
        cupid_int base = boff + (j0 + i) * M;
        cupid_int pos = lower_bound(K, row, base + cuf_tau(b, se, order[0]));
        for (int q = 0; q < m; q++) {
          int t = order[q];
          cupid_int col = base + cuf_tau(b, se, t);
          while (pos < end && K->col[pos] < col) pos++;
          if (pos == end || K->col[pos] != col) return 1;
          double *blk = K->val + 9 * pos;
          const double *src = Ke + (size_t)((s * p + j) * 3) * n + (t * p + i) * 3;
          for (int k = 0; k < 3; k++)
            for (int h = 0; h < 3; h++) blk[3 * k + h] += src[(size_t)k * n + h];
        }
      }
    }
  return 0;
}

/* One beam element: every active section element (LE) or the active cells of each
 * material summed into one group (TE), times the axis integrals. */
static int add_beam_element(const beam_t *b, cupid_csr K, cupid_int boff, cupid_int be, double *I,
                            double *E, double *Ke, unsigned char *used, int *order) {
  cuf_axis_integrals(b, be, I);
  int m = cuf_local_m(b);
  size_t per = 9 * (size_t)m * m;
  if (b->expansion == CUPID_EXPANSION_LE) {
    for (cupid_int se = 0; se < b->n_selem; se++) {
      if (!b->active[be * b->n_selem + se]) continue;
      cuf_section_integrals(b, se, b->sec_ng, E);
      cuf_pair_matrix(b, m, E, b->smat[se], I, Ke);
      if (scatter(b, K, boff, be, se, m, Ke, order)) return 1;
    }
    return 0;
  }
  memset(E, 0, sizeof *E * per * (size_t)b->n_mat);
  memset(used, 0, (size_t)b->n_mat);
  for (cupid_int se = 0; se < b->n_selem; se++) {
    if (!b->active[be * b->n_selem + se]) continue;
    int mat = b->smat[se];
    used[mat] = 1;
    const double *src = b->te_E + per * se;
    double *dst = E + per * mat;
    for (size_t q = 0; q < per; q++) dst[q] += src[q];
  }
  for (int mat = 0; mat < b->n_mat; mat++) {
    if (!used[mat]) continue;
    cuf_pair_matrix(b, m, E + per * mat, mat, I, Ke);
    if (scatter(b, K, boff, be, -1, m, Ke, order)) return 1;
  }
  return 0;
}

static cupid_status add_impl(const beam_t *b, cupid_csr K, cupid_int boff) {
  int m = cuf_local_m(b), p = b->p, fail = 0, nomem = 0;
  size_t nI = (size_t)b->n_parts * 4 * p * p, nE = 9 * (size_t)m * m * (b->expansion == CUPID_EXPANSION_TE ? (size_t)b->n_mat : 1);
  size_t nK = (size_t)(3 * m * p) * (3 * m * p);
  /* two colours: beam elements of one parity share no node, so their rows are disjoint */
  for (int colour = 0; colour < 2; colour++) {
    cupid_int count = (b->n_belem - colour + 1) / 2;
#pragma omp parallel reduction(| : fail, nomem) if (3 * b->n_bnodes * b->M > CUF_PARALLEL_DOFS)
    {
      double *I = NULL, *E = NULL, *Ke = NULL;
      unsigned char *used = NULL;
      int *order = NULL;
      if (cupid_malloc(nI, sizeof *I, "axis integrals", &I) || cupid_malloc(nE, sizeof *E, "section integrals", &E) ||
          cupid_malloc(nK, sizeof *Ke, "element matrix", &Ke) ||
          cupid_malloc((size_t)b->n_mat, 1, "material flags", &used) ||
          cupid_malloc((size_t)m, sizeof *order, "local order", &order)) {
        nomem = 1;
      } else {
#pragma omp for schedule(dynamic)
        for (cupid_int k = 0; k < count; k++)
          fail |= add_beam_element(b, K, boff, 2 * k + colour, I, E, Ke, used, order);
      }
      cupid_free(&I);
      cupid_free(&E);
      cupid_free(&Ke);
      cupid_free(&used);
      cupid_free(&order);
    }
    CUPID_CHECK(!nomem, CUPID_ERR_MEMORY, "out of memory in CUF assembly");
    CUPID_CHECK(!fail, CUPID_ERR_ARGUMENT, "the matrix pattern lacks blocks of the CUF beam");
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_cuf_assemble(const cupid_cuf_beam b, cupid_csr *K) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int *rowptr = NULL, *col = NULL, n = b->n_bnodes * b->M;
  CUPID_CHECK(K, CUPID_ERR_ARGUMENT, "cupid_cuf_assemble: NULL argument");
  *K = NULL;
  CUPID_TRY(cupid_cuf_pattern(b, &rowptr, &col));
  CUPID_TRY(cupid_csr_create(n, n, 3, rowptr, col, K));
  st = add_impl(b, *K, 0);
  if (st != CUPID_SUCCESS) cupid_csr_destroy(K);
cleanup:
  cupid_free(&rowptr);
  cupid_free(&col);
  return st;
}

cupid_status cupid_cuf_assemble_add(const cupid_cuf_beam b, cupid_csr K) {
  CUPID_CHECK(K && K->bs == 3, CUPID_ERR_ARGUMENT, "cupid_cuf_assemble_add: need a bs = 3 matrix");
  cupid_int boff = b->dof_offset / 3;
  CUPID_CHECK(K->nrows >= boff + b->n_bnodes * b->M && K->ncols >= boff + b->n_bnodes * b->M,
              CUPID_ERR_ARGUMENT, "matrix too small for the beam at DOF offset %lld",
              (long long)b->dof_offset);
  return add_impl(b, K, boff);
}
