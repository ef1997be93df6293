/* Owned-row assembly of a short-range bond-based stiffness on the PD lattice: the matrix that
 * algebraic multigrid coarsens when the model's own operator (LPS, coupling nodes 2 delta apart)
 * is only applied matrix-free (issue 6, src/solvers/petsc.c). Uses the public grid API only. */
#include <math.h>
#include <stdlib.h>

#include "cupid/pd.h"

typedef struct {
  int o[3];      /* lattice offset */
  double nn[9];  /* n n^T / |xi| * V^2 (without the modulus) */
} stencil_bond;

/* Lattice offsets with 0 < |o| h <= radius, and their geometric factors. */
static cupid_status make_stencil(double h, double V, double radius, stencil_bond **out, int *count) {
  int R = (int)floor(radius / h + 1e-9);
  int n = 0;
  CUPID_CHECK(R >= 1, CUPID_ERR_ARGUMENT,
              "preconditioner radius %g is below the grid spacing %g: no bonds", radius, h);
  stencil_bond *s = NULL;
  size_t cap = (size_t)(2 * R + 1) * (size_t)(2 * R + 1) * (size_t)(2 * R + 1);
  CUPID_CALL(cupid_calloc(cap, sizeof *s, "preconditioner stencil", &s));
  for (int k = -R; k <= R; k++)
    for (int j = -R; j <= R; j++)
      for (int i = -R; i <= R; i++) {
        double x[3] = {i * h, j * h, k * h};
        double r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        if (r == 0.0 || r > radius * (1.0 + 1e-12)) continue;
        stencil_bond *b = &s[n++];
        b->o[0] = i, b->o[1] = j, b->o[2] = k;
        for (int a = 0; a < 3; a++)
          for (int c = 0; c < 3; c++) b->nn[3 * a + c] = V * V * x[a] * x[c] / (r * r * r);
      }
  *out = s;
  *count = n;
  return CUPID_SUCCESS;
}

cupid_status cupid_pd_assemble_rows_bond(const cupid_pd_grid grid, const cupid_pd_material *materials,
                                         double radius, cupid_int first, cupid_int last,
                                         cupid_csr *K) {
  cupid_int nodes = cupid_pd_grid_num_nodes(grid);
  CUPID_CHECK(cupid_pd_grid_dimension(grid) == 3, CUPID_ERR_UNSUPPORTED,
              "the bond-based preconditioner matrix needs a 3D grid");
  CUPID_CHECK(first >= 0 && first <= last && last <= nodes, CUPID_ERR_ARGUMENT,
              "row range [%lld, %lld) outside [0, %lld)", (long long)first, (long long)last,
              (long long)nodes);
  cupid_status st = CUPID_SUCCESS;
  stencil_bond *s = NULL;
  cupid_int *rowptr = NULL, *col = NULL, *nbr = NULL;
  int ns = 0;
  cupid_int nrows = last - first;
  const int *mat = cupid_pd_grid_materials(grid);
  CUPID_TRY(make_stencil(cupid_pd_grid_spacing(grid), cupid_pd_grid_cell_volume(grid), radius, &s, &ns));
  /* Neighbour table: nbr[r * ns + b] = node at offset b of row r, or -1 (the stencil is ordered
   * z, y, x slowest to fastest, so with the diagonal inserted in place columns come sorted). */
  CUPID_TRY(cupid_malloc((size_t)(nrows * ns + 1), sizeof *nbr, "preconditioner neighbours", &nbr));
  CUPID_TRY(cupid_calloc((size_t)nrows + 1, sizeof *rowptr, "preconditioner rows", &rowptr));
#pragma omp parallel for schedule(static)
  for (cupid_int r = 0; r < nrows; r++) {
    cupid_int ijk[3], count = 1;
    cupid_pd_grid_node_lattice(grid, first + r, ijk);
    for (int b = 0; b < ns; b++) {
      cupid_int j = cupid_pd_grid_node_at(grid, ijk[0] + s[b].o[0], ijk[1] + s[b].o[1],
                                          ijk[2] + s[b].o[2]);
      nbr[r * ns + b] = j;
      count += j >= 0;
    }
    rowptr[r + 1] = count;
  }
  for (cupid_int r = 0; r < nrows; r++) rowptr[r + 1] += rowptr[r];
  CUPID_TRY(cupid_malloc((size_t)rowptr[nrows] + 1, sizeof *col, "preconditioner columns", &col));
#pragma omp parallel for schedule(static)
  for (cupid_int r = 0; r < nrows; r++) {
    cupid_int p = rowptr[r], i = first + r;
    int diag_done = 0;
    for (int b = 0; b < ns; b++) {
      cupid_int j = nbr[r * ns + b];
      if (j < 0) continue;
      if (!diag_done && j > i) col[p++] = i, diag_done = 1;
      col[p++] = j;
    }
    if (!diag_done) col[p++] = i;
  }
  CUPID_TRY(cupid_csr_create(nrows, nodes, 3, rowptr, col, K));
  cupid_csr_t *A = *K;
#pragma omp parallel for schedule(static)
  for (cupid_int r = 0; r < nrows; r++) {
    cupid_int i = first + r;
    double *d = cupid_csr_find(A, r, i);
    for (int b = 0; b < ns; b++) {
      cupid_int j = nbr[r * ns + b];
      if (j < 0) continue;
      double c = 0.5 * (materials[mat[i]].E + materials[mat[j]].E);
      double *o = cupid_csr_find(A, r, j);
      for (int q = 0; q < 9; q++) {
        o[q] -= c * s[b].nn[q];
        d[q] += c * s[b].nn[q];
      }
    }
  }
cleanup:
  cupid_free(&s);
  cupid_free(&nbr);
  cupid_free(&rowptr);
  cupid_free(&col);
  return st;
}
