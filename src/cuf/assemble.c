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

/* Unsorted columns of block row r; marker[] holds the last row that marked each column. */
static cupid_int row_columns(const beam_t *b, const unsigned char *be_any, cupid_int r,
                             cupid_int *marker, cupid_int *out) {
  cupid_int M = b->M, i = r / M, n = 0;
  int tau = (int)(r % M);
  cupid_int lo, hi;
  node_elements(b, i, &lo, &hi);
  marker[r] = r;
  out[n++] = r; /* the diagonal block is always there */
  for (cupid_int e = lo; e <= hi; e++) {
    cupid_int j0 = e * (b->p - 1);
    if (b->expansion == CUPID_EXPANSION_TE) {
      if (!be_any[e]) continue;
      for (int a = 0; a < b->p; a++)
        for (cupid_int s = 0; s < M; s++) {
          cupid_int c = (j0 + a) * M + s;
          if (marker[c] != r) marker[c] = r, out[n++] = c;
        }
    } else {
      for (cupid_int k = b->n2e_ptr[tau]; k < b->n2e_ptr[tau + 1]; k++) {
        cupid_int se = b->n2e[k];
        if (!b->active[e * b->n_selem + se]) continue;
        const cupid_int *conn = b->sconn + se * b->quad.npe;
        for (int a = 0; a < b->p; a++)
          for (int q = 0; q < b->quad.npe; q++) {
            cupid_int c = (j0 + a) * M + conn[q];
            if (marker[c] != r) marker[c] = r, out[n++] = c;
          }
      }
    }
  }
  return n;
}

static int cmp_int(const void *a, const void *b) {
  cupid_int x = *(const cupid_int *)a, y = *(const cupid_int *)b;
  return (x > y) - (x < y);
}

cupid_status cupid_cuf_pattern(const cupid_cuf_beam b, cupid_int **rowptr_out, cupid_int **col_out) {
  cupid_status st = CUPID_SUCCESS;
  cupid_int n = b->n_bnodes * b->M, *rowptr = NULL, *col = NULL;
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
  CUPID_TRY(cupid_calloc((size_t)n + 1, sizeof *rowptr, "CUF pattern rows", &rowptr));
  CUPID_TRY(cupid_calloc((size_t)b->n_belem, 1, "CUF element flags", &be_any));
  for (cupid_int e = 0; e < b->n_belem; e++)
    for (cupid_int s = 0; s < b->n_selem && !be_any[e]; s++) be_any[e] = b->active[e * b->n_selem + s];
  for (int pass = 0; pass < 2; pass++) {
#pragma omp parallel reduction(| : fail)
    {
      cupid_int *marker = NULL, *buf = NULL;
      if (cupid_malloc((size_t)n, sizeof *marker, "CUF pattern marker", &marker) != CUPID_SUCCESS ||
          cupid_malloc((size_t)width, sizeof *buf, "CUF pattern row", &buf) != CUPID_SUCCESS) {
        fail = 1;
      } else {
        for (cupid_int k = 0; k < n; k++) marker[k] = -1;
#pragma omp for schedule(dynamic, 64)
        for (cupid_int r = 0; r < n; r++) {
          cupid_int c = row_columns(b, be_any, r, marker, buf);
          if (pass == 0) {
            rowptr[r + 1] = c;
          } else {
            qsort(buf, (size_t)c, sizeof *buf, cmp_int);
            memcpy(col + rowptr[r], buf, sizeof *buf * (size_t)c);
          }
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
  return st;
}

static double *find_block(const cupid_csr_t *K, cupid_int row, cupid_int col) {
  cupid_int lo = K->rowptr[row], hi = K->rowptr[row + 1] - 1;
  while (lo <= hi) {
    cupid_int mid = (lo + hi) / 2;
    if (K->col[mid] == col) return K->val + 9 * mid;
    if (K->col[mid] < col) lo = mid + 1;
    else hi = mid - 1;
  }
  return NULL;
}

/* Add a dense pair matrix (layout of cuf_pair_matrix) into K at block offset boff. */
static int scatter(const beam_t *b, cupid_csr K, cupid_int boff, cupid_int be, cupid_int se,
                   int m, const double *Ke) {
  int p = b->p, n = 3 * m * p;
  cupid_int j0 = be * (p - 1), M = b->M;
  for (int s = 0; s < m; s++)
    for (int j = 0; j < p; j++) {
      cupid_int row = boff + (j0 + j) * M + (se >= 0 ? cuf_tau(b, se, s) : s);
      for (int t = 0; t < m; t++)
        for (int i = 0; i < p; i++) {
          cupid_int col = boff + (j0 + i) * M + (se >= 0 ? cuf_tau(b, se, t) : t);
          double *blk = find_block(K, row, col);
          if (!blk) return 1;
          const double *src = Ke + (size_t)((s * p + j) * 3) * n + (t * p + i) * 3;
          for (int k = 0; k < 3; k++)
            for (int h = 0; h < 3; h++) blk[3 * k + h] += src[(size_t)k * n + h];
        }
    }
  return 0;
}

/* One beam element: every active section element (LE) or the active cells of each
 * material summed into one group (TE), times the axis integrals. */
static int add_beam_element(const beam_t *b, cupid_csr K, cupid_int boff, cupid_int be, double *I,
                            double *E, double *Ke, unsigned char *used) {
  cuf_axis_integrals(b, be, I);
  int m = cuf_local_m(b);
  size_t per = 9 * (size_t)m * m;
  if (b->expansion == CUPID_EXPANSION_LE) {
    for (cupid_int se = 0; se < b->n_selem; se++) {
      if (!b->active[be * b->n_selem + se]) continue;
      cuf_section_integrals(b, se, b->sec_ng, E);
      cuf_pair_matrix(b, m, E, b->smat[se], I, Ke);
      if (scatter(b, K, boff, be, se, m, Ke)) return 1;
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
    if (scatter(b, K, boff, be, -1, m, Ke)) return 1;
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
#pragma omp parallel reduction(| : fail, nomem)
    {
      double *I = NULL, *E = NULL, *Ke = NULL;
      unsigned char *used = NULL;
      if (cupid_malloc(nI, sizeof *I, "axis integrals", &I) || cupid_malloc(nE, sizeof *E, "section integrals", &E) ||
          cupid_malloc(nK, sizeof *Ke, "element matrix", &Ke) ||
          cupid_malloc((size_t)b->n_mat, 1, "material flags", &used)) {
        nomem = 1;
      } else {
#pragma omp for schedule(dynamic)
        for (cupid_int k = 0; k < count; k++)
          fail |= add_beam_element(b, K, boff, 2 * k + colour, I, E, Ke, used);
      }
      cupid_free(&I);
      cupid_free(&E);
      cupid_free(&Ke);
      cupid_free(&used);
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
