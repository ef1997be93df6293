/* The Arlequin coupled operator (paper 004 Eq. 18) without the PD matrix: y = K x with
 * K = K_PD(1 - alpha) + K_FE(alpha) + K_z over [3 DOFs per PD node | FE DOFs], the ordering of
 * cupid_arlequin_assemble(). The PD block is the model's PD operator with every node's energy
 * weighted by w_p = 1 - alpha(x_p) (cupid_pd_operator_scale_energy(): its per-node moduli
 * scaled once) and applied matrix-free; the rest, the weighted beam and the penalty ties, is
 * assembled (cupid_arlequin_assemble() with no PD operator: the beam's DOFs and the tied
 * nodes' couplings, few next to the LPS block's ~900 blocks a PD row at delta = 3 h).
 *
 * The preconditioner matrix is the same K with the cheap PD operator of the fictitious-node
 * path (cupid_coupling_cheap_options(): bond-based, horizon 1.5 h, micromodulus calibrated to
 * the bulk modulus), weighted node by node the same way: symmetric positive definite like K,
 * with ~19 blocks a PD row.
 *
 * On a slab of a partitioned grid (issue 6) the operator is the slab's: its owned PD rows are
 * the whole operator's (the halo holds what they read) and its FE rows are the slab's share
 * (cupid_arlequin_assemble() on a slab), summed over the ranks by cupid_krylov_solve(). */
#include <string.h>

#include "coupling_internal.h"
#include "cupid/coupling.h"

struct cupid_arlequin_operator_private {
  cupid_pd_operator op;          /* the weighted PD operator (owned) */
  cupid_pd_operator_options pd;  /* its options (for the cheap twin) */
  cupid_cuf_beam beam;           /* borrowed */
  cupid_pd_grid grid;            /* borrowed */
  cupid_arlequin_options o;      /* borrowed region array */
  cupid_csr R;                   /* K_FE(alpha) + K_z, assembled */
  cupid_int n_pd, n;
  cupid_pd_grid_partition part;  /* the grid's: a slab holds its owned rows (issue 6) */
  double *fpd;                   /* work: 3 per PD node */
};

cupid_pd_operator cupid_arlequin_operator_pd(const cupid_arlequin_operator A) {
  return A ? A->op : NULL;
}

cupid_status cupid_arlequin_operator_create(cupid_cuf_beam beam, cupid_pd_grid grid,
                                            const cupid_pd_operator_options *pd,
                                            const cupid_arlequin_options *o,
                                            cupid_arlequin_operator *out,
                                            cupid_arlequin_info *info) {
  cupid_status st = CUPID_SUCCESS;
  cupid_arlequin_operator A = NULL;
  double *w = NULL, wmin;
  CUPID_CHECK(beam && grid && pd && o && out, CUPID_ERR_ARGUMENT,
              "cupid_arlequin_operator_create: NULL argument");
  *out = NULL;
  CUPID_CALL(cupid_calloc(1, sizeof *A, "Arlequin operator", &A));
  A->beam = beam;
  A->grid = grid;
  A->pd = *pd;
  A->o = *o;
  A->n_pd = cupid_pd_grid_num_nodes(grid);
  A->n = 3 * A->n_pd + cupid_cuf_num_dofs(beam);
  cupid_pd_grid_get_partition(grid, &A->part);
  CUPID_TRY(cupid_arlequin_assemble(beam, grid, NULL, o, &A->R, info));
  CUPID_TRY(cupid_pd_operator_create(grid, pd, &A->op));
  CUPID_TRY(cpl_arlequin_pd_weights(grid, o, &w, &wmin));
  CUPID_TRY(cupid_pd_operator_scale_energy(A->op, w)); /* Eq. 12, node by node */
  CUPID_TRY(cupid_malloc((size_t)(3 * A->n_pd) + 1, sizeof *A->fpd, "PD forces", &A->fpd));
  *out = A;
  A = NULL;
cleanup:
  cupid_free(&w);
  cupid_arlequin_operator_destroy(&A);
  return st;
}

void cupid_arlequin_operator_destroy(cupid_arlequin_operator *A) {
  if (!A || !*A) return;
  cupid_pd_operator_destroy(&(*A)->op);
  cupid_csr_destroy(&(*A)->R);
  cupid_free(&(*A)->fpd);
  cupid_free(A);
}

cupid_int cupid_arlequin_operator_size(const cupid_arlequin_operator A) { return A->n; }

int64_t cupid_arlequin_operator_bytes(const cupid_arlequin_operator A) {
  return (int64_t)cupid_pd_operator_num_bonds(A->op) * 12 + A->n_pd * (int64_t)(8 * 6 + 8 * 8) +
         cupid_csr_bytes(A->R);
}

cupid_status cupid_arlequin_operator_apply_rows(const cupid_arlequin_operator A, const double *x,
                                                cupid_int d0, cupid_int d1, double *y) {
  CUPID_CHECK(A && x && y && d0 >= 0 && d0 <= d1 && d1 <= A->n, CUPID_ERR_ARGUMENT,
              "Arlequin operator: rows [%lld, %lld) outside its %lld", (long long)d0,
              (long long)d1, (long long)(A ? A->n : 0));
  cupid_csr_matvec_rows(A->R, x, 0, d0, d1, y);
  const cupid_int r0 = d0 / 3, r1 = (d1 < 3 * A->n_pd ? d1 + 2 : 3 * A->n_pd) / 3;
  if (r0 >= r1) return CUPID_SUCCESS;
  /* the PD rows [r0, r1): the weighted PD operator on the nodes they depend on */
  CUPID_CALL(cupid_pd_operator_apply_range(A->op, r0, r1, x, A->fpd));
  for (cupid_int r = r0; r < r1; r++)
    for (int c = 0; c < 3; c++)
      if (3 * r + c >= d0 && 3 * r + c < d1) y[3 * r + c] += A->fpd[3 * (r - r0) + c];
  return CUPID_SUCCESS;
}

cupid_status cupid_arlequin_operator_apply(const cupid_arlequin_operator A, const double *x,
                                           double *y) {
  return cupid_arlequin_operator_apply_rows(A, x, 0, A ? A->n : 0, y);
}

cupid_status cupid_arlequin_preconditioner(const cupid_arlequin_operator A, double horizon_factor,
                                           cupid_csr *P) {
  CUPID_CHECK(A && P, CUPID_ERR_ARGUMENT, "cupid_arlequin_preconditioner: NULL argument");
  cupid_pd_operator_options cheap;
  cupid_pd_operator op = NULL;
  cupid_coupling_cheap_options(&A->pd, cupid_pd_grid_spacing(A->grid), horizon_factor, &cheap);
  CUPID_CALL(cupid_pd_operator_create(A->grid, &cheap, &op));
  cupid_status st = cupid_arlequin_assemble(A->beam, A->grid, op, &A->o, P, NULL);
  cupid_pd_operator_destroy(&op);
  return st;
}

static cupid_status lin_apply(void *ctx, const double *x, double *y) {
  return cupid_arlequin_operator_apply(ctx, x, y);
}

static cupid_status lin_apply_rows(void *ctx, const double *x, cupid_int d0, cupid_int d1,
                                   double *y) {
  return cupid_arlequin_operator_apply_rows(ctx, x, d0, d1, y);
}

void cupid_arlequin_operator_linear(const cupid_arlequin_operator A, cupid_linear_operator *L) {
  *L = (cupid_linear_operator){.n = A->n,
                               .apply = lin_apply,
                               .apply_rows = lin_apply_rows,
                               .ctx = A,
                               .symmetric = 1,
                               .n_pd_dofs = 3 * A->n_pd,
                               .part = &A->part};
}
