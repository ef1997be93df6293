/* The balanced fictitious-node coupling (issue 18; docs/coupling.md, "The balanced
 * fictitious-node coupling"). Paper 000's Eq. 38 operator K conserves neither linear nor
 * angular momentum: R^T K != 0 for the six rigid modes R, so the reactions miss the load (7.7%
 * on the C-beam example, 12% with PD around its web-flange corner, 26% on the panel). The
 * balanced operator is
 *     K' = K - W C^T,   C = K^T R,   W = D R (R^T D R)^-1,
 * D = diag(K) on the FE DOFs of the interfaces (the real FE nodes of the fictitious elements).
 *   - R^T K' = R^T K - (R^T W) C^T = 0: every force system K' u is self-equilibrated, so the
 *     reactions balance the load (linear and angular momentum).
 *   - K' R = K R - W (R^T K R) = 0: rigid motions stay force-free.
 *   - K' x = K x when K x has no resultant and no moment (the affine fields of the patch test,
 *     whose forces are the end tractions: the patch test is kept).
 * The correction is the net force and moment of K u, put back on the interface FE nodes with
 * the distribution of a rigid motion weighted by their stiffness. K' is dense in six rank-one
 * terms, so it is never assembled: products add W (C^T x), the direct solve uses the factor of
 * K_ff and the Sherman-Morrison-Woodbury formula (six more solves). */
#include <math.h>
#include <string.h>

#include "coupling_internal.h"
#include "cupid/coupling.h"

#define NR CUPID_BALANCE_MODES

struct cupid_coupling_balance_private {
  cupid_int n;
  int k;         /* columns: NR per group that takes a correction */
  double *C, *W; /* k columns of n each: group g's C_g = its DOFs' entries of K^T R, W_g */
  cupid_linear_operator inner; /* the wrapped operator (cupid_coupling_balance_linear) */
  /* on a slab (cupid_coupling_balance_set_slab): C holds this slab's share, the partial C^T x
   * are summed over the ranks by sum, and the FE rows' correction is added on one rank */
  void (*sum)(double *v, int n);
  int apply_here;
};

/* A Z = B in place (A: n x n, B: n x nrhs, row-major); 0 if singular to working precision (a
 * pivot below 1e-12 of the largest entry: the rank a dense 6 x 6 system can be trusted with). */
static int dense_solve(double *A, double *B, int n, int nrhs) {
  return cupid_dense_solve(n, A, B, nrhs, 1e-12 * cupid_dense_max_abs(n, A));
}

/* the same to the bit for any thread count (a growth's iterates decide which bonds break) */
static double dot(cupid_int n, const double *a, const double *b) { return cupid_dot(n, a, b); }

cupid_status cupid_coupling_balance_create(cupid_int n, const double *R, const double *C,
                                           const double *d, cupid_coupling_balance *out) {
  return cupid_coupling_balance_create_grouped(n, R, C, d, 1, NULL, out);
}

/* Group g's W_g = D_g R (R^T D_g R)^-1 into W (NR columns), dr scratch (NR n). 0: D_g does not
 * span the rigid modes. */
static int group_weights(cupid_int n, const double *R, const double *d, const int *group, int g,
                         double *dr, double *W) {
  for (int a = 0; a < NR; a++)
    for (cupid_int j = 0; j < n; j++)
      dr[(size_t)a * n + j] = (!group || group[j] == g) ? d[j] * R[(size_t)a * n + j] : 0.0;
  double G[NR * NR];
  for (int a = 0; a < NR; a++)
    for (int b = 0; b < NR; b++) G[a * NR + b] = dot(n, R + (size_t)a * n, dr + (size_t)b * n);
  double Gi[NR * NR] = {0}; /* G^-1: one elimination for the NR columns */
  for (int b = 0; b < NR; b++) Gi[b * NR + b] = 1.0;
  if (!dense_solve(G, Gi, NR, NR)) return 0;
  for (int b = 0; b < NR; b++) { /* column b of W = D R G^-1 e_b */
    double *w = W + (size_t)b * n;
    for (cupid_int j = 0; j < n; j++) {
      double v = 0.0;
      for (int a = 0; a < NR; a++) v += dr[(size_t)a * n + j] * Gi[a * NR + b];
      w[j] = v;
    }
  }
  return 1;
}

cupid_status cupid_coupling_balance_create_grouped(cupid_int n, const double *R, const double *C,
                                                   const double *d, int n_groups, const int *group,
                                                   cupid_coupling_balance *out) {
  cupid_status st = CUPID_SUCCESS;
  cupid_coupling_balance B = NULL;
  double *dr = NULL;
  *out = NULL;
  CUPID_CHECK(n_groups >= 1 && n_groups <= CUPID_BALANCE_GROUPS_MAX && (n_groups == 1 || group),
              CUPID_ERR_ARGUMENT, "balance: 1 to %d groups, with the group of every DOF (got %d)",
              CUPID_BALANCE_GROUPS_MAX, n_groups);
  CUPID_CALL(cupid_calloc(1, sizeof *B, "balanced coupling", &B));
  B->n = n;
  B->apply_here = 1;
  const size_t cap = (size_t)NR * (size_t)n_groups * (size_t)n;
  CUPID_TRY(cupid_calloc(cap + 1, sizeof *B->C, "K^T R", &B->C));
  CUPID_TRY(cupid_calloc(cap + 1, sizeof *B->W, "balance distribution", &B->W));
  CUPID_TRY(cupid_malloc((size_t)NR * (size_t)n, sizeof *dr, "D R", &dr));
  for (int g = 0; g < n_groups; g++) {
    /* C_g: the group's entries of K^T R; a group whose DOFs neither take a correction nor
     * make an imbalance is left out */
    double *Cg = B->C + (size_t)B->k * (size_t)n, *Wg = B->W + (size_t)B->k * (size_t)n;
    int any_c = 0, any_d = 0;
    for (cupid_int j = 0; j < n; j++) {
      const int in = n_groups == 1 || group[j] == g;
      any_d |= in && d[j] != 0.0;
      for (int a = 0; a < NR; a++) {
        const double c = in ? C[(size_t)a * n + j] : 0.0;
        Cg[(size_t)a * n + j] = c;
        any_c |= c != 0.0;
      }
    }
    if (!any_c && !any_d) continue;
    CUPID_TRY_CHECK(any_d && group_weights(n, R, d, n_groups == 1 ? NULL : group, g, dr, Wg),
                    CUPID_ERR_MODEL,
                    "coupling.balance: the interface FE nodes%s do not span the six rigid-body "
                    "modes (a region whose interfaces hold too few FE nodes)",
                    n_groups > 1 ? " of an interface" : "");
    B->k += NR;
  }
  *out = B;
  B = NULL;
cleanup:
  cupid_free(&dr);
  cupid_coupling_balance_destroy(&B);
  return st;
}

void cupid_coupling_balance_destroy(cupid_coupling_balance *B) {
  if (!B || !*B) return;
  cupid_free(&(*B)->C);
  cupid_free(&(*B)->W);
  cupid_free(B);
}

void cupid_coupling_balance_correct(const cupid_coupling_balance B, const double *x, double *y) {
  const cupid_int n = B->n;
  double c[NR * CUPID_BALANCE_GROUPS_MAX];
  for (int k = 0; k < B->k; k++) c[k] = dot(n, B->C + (size_t)k * n, x);
#pragma omp parallel for schedule(static) if (n > 100000)
  for (cupid_int j = 0; j < n; j++) {
    double v = 0.0;
    for (int k = 0; k < B->k; k++) v += B->W[(size_t)k * n + j] * c[k];
    y[j] -= v;
  }
}

void cupid_coupling_balance_terms(const cupid_coupling_balance B, int *k, const double **C,
                                  const double **W) {
  *k = B ? B->k : 0;
  *C = B ? B->C : NULL;
  *W = B ? B->W : NULL;
}

cupid_status cupid_coupling_balance_solve(const cupid_coupling_balance B, const cupid_csr_t *K,
                                          cupid_direct_factor F, const cupid_dirichlet_t *bc,
                                          const double *f, double *u) {
  const cupid_int n = B->n;
  double *b = NULL, *y = NULL;
  cupid_coupling_balance_smw M = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_calloc((size_t)n, sizeof *b, "balanced right-hand side", &b));
  CUPID_TRY(cupid_calloc((size_t)n, sizeof *y, "balanced solve", &y));
  /* b = f - K' u_c (u_c: the prescribed values, 0 on the free DOFs) */
  for (cupid_int j = 0; j < n; j++) y[j] = bc->fixed[j] ? bc->value[j] : 0.0;
  cupid_csr_matvec(K, y, b);
  cupid_coupling_balance_correct(B, y, b);
  for (cupid_int j = 0; j < n; j++) b[j] = bc->fixed[j] ? 0.0 : f[j] - b[j];
  /* K'_ff = K_ff - W_f C_f^T by Sherman-Morrison-Woodbury on F */
  CUPID_TRY(cupid_coupling_balance_smw_create(B, F, bc, &M));
  CUPID_TRY(cupid_coupling_balance_smw_apply(M, b, y));
  for (cupid_int j = 0; j < n; j++) u[j] = bc->fixed[j] ? bc->value[j] : y[j];
cleanup:
  cupid_coupling_balance_smw_destroy(&M);
  cupid_free(&b);
  cupid_free(&y);
  return st;
}

/* The SMW form kept with its factor (cupid_coupling_balance_smw). */
struct cupid_coupling_balance_smw_private {
  cupid_int n;
  int k;
  cupid_direct_factor F; /* borrowed */
  double *Cf;            /* k columns: C on the factor's free DOFs, 0 on its fixed ones */
  double *Z;             /* k columns: (K_ff)^-1 W_f, 0 on the fixed DOFs */
  double *Si;            /* k x k: (I - C_f^T Z)^-1, made once (row-major) */
};

cupid_status cupid_coupling_balance_smw_create(const cupid_coupling_balance B, cupid_direct_factor F,
                                               const cupid_dirichlet_t *bc,
                                               cupid_coupling_balance_smw *out) {
  const cupid_int n = B->n;
  const int k = B->k;
  cupid_coupling_balance_smw M = NULL;
  double *S = NULL;
  cupid_status st = CUPID_SUCCESS;
  *out = NULL;
  CUPID_CHECK(bc->n == n, CUPID_ERR_ARGUMENT, "balance SMW: %lld conditions for %lld DOFs",
              (long long)bc->n, (long long)n);
  CUPID_CALL(cupid_calloc(1, sizeof *M, "balance SMW", &M));
  M->n = n, M->k = k, M->F = F;
  CUPID_TRY(cupid_calloc((size_t)k * (size_t)n + 1, sizeof *M->Cf, "balance SMW", &M->Cf));
  CUPID_TRY(cupid_calloc((size_t)k * (size_t)n + 1, sizeof *M->Z, "balance SMW", &M->Z));
  CUPID_TRY(cupid_calloc((size_t)(k * k) + 1, sizeof *M->Si, "balance SMW", &M->Si));
  CUPID_TRY(cupid_calloc((size_t)(k * k) + 1, sizeof *S, "capacitance", &S));
  for (int c = 0; c < k; c++) {
    double *Cc = M->Cf + (size_t)c * n, *Zc = M->Z + (size_t)c * n;
    const double *Wc = B->W + (size_t)c * n;
    for (cupid_int j = 0; j < n; j++) Cc[j] = bc->fixed[j] ? 0.0 : B->C[(size_t)c * n + j];
    CUPID_TRY(cupid_direct_factor_solve(F, Wc, Zc));
    for (cupid_int j = 0; j < n; j++)
      if (bc->fixed[j]) Zc[j] = 0.0;
  }
  for (int a = 0; a < k; a++)
    for (int c = 0; c < k; c++)
      S[a * k + c] = (a == c) - dot(n, M->Cf + (size_t)a * n, M->Z + (size_t)c * n);
  for (int c = 0; c < k; c++) M->Si[c * k + c] = 1.0; /* the inverse: one elimination */
  CUPID_TRY_CHECK(dense_solve(S, M->Si, k, k), CUPID_ERR_NUMERIC,
                  "coupling.balance: the balanced operator is singular on the free DOFs");
  *out = M;
  M = NULL;
cleanup:
  cupid_free(&S);
  cupid_coupling_balance_smw_destroy(&M);
  return st;
}

cupid_status cupid_coupling_balance_smw_apply(const cupid_coupling_balance_smw M, const double *r,
                                              double *z) {
  const cupid_int n = M->n;
  const int k = M->k;
  for (cupid_int j = 0; j < n; j++) z[j] = 0.0;
  CUPID_CALL(cupid_direct_factor_solve(M->F, r, z));
  if (k == 0) return CUPID_SUCCESS;
  double t[NR * CUPID_BALANCE_GROUPS_MAX], g[NR * CUPID_BALANCE_GROUPS_MAX];
  for (int a = 0; a < k; a++) t[a] = dot(n, M->Cf + (size_t)a * n, z);
  for (int a = 0; a < k; a++) { /* g = (I - C_f^T Z)^-1 C_f^T y */
    g[a] = 0.0;
    for (int c = 0; c < k; c++) g[a] += M->Si[a * k + c] * t[c];
  }
#pragma omp parallel for schedule(static) if (n > 100000)
  for (cupid_int j = 0; j < n; j++) {
    double v = 0.0;
    for (int c = 0; c < k; c++) v += M->Z[(size_t)c * n + j] * g[c];
    z[j] += v;
  }
  return CUPID_SUCCESS;
}

void cupid_coupling_balance_smw_destroy(cupid_coupling_balance_smw *M) {
  if (!M || !*M) return;
  cupid_free(&(*M)->Cf);
  cupid_free(&(*M)->Z);
  cupid_free(&(*M)->Si);
  cupid_free(M);
}

static cupid_status balanced_apply(void *ctx, const double *x, double *y) {
  const cupid_coupling_balance B = ctx;
  /* a slab's share of C gives a slab's share of C^T x: its products go by rows */
  CUPID_CHECK(!B->sum, CUPID_ERR_ARGUMENT, "a balanced operator on a slab applies by rows "
              "(cupid_krylov_apply)");
  CUPID_CALL(B->inner.apply(B->inner.ctx, x, y));
  cupid_coupling_balance_correct(B, x, y);
  return CUPID_SUCCESS;
}

/* The rows [d0, d1) of K' x: W is zero on the PD rows, so a call for PD rows only is K's; the
 * FE rows' call sums C^T x over the ranks (collective on a slab: every rank makes it). */
static cupid_status balanced_apply_rows(void *ctx, const double *x, cupid_int d0, cupid_int d1,
                                        double *y) {
  const cupid_coupling_balance B = ctx;
  CUPID_CALL(B->inner.apply_rows(B->inner.ctx, x, d0, d1, y));
  const cupid_int fe0 = B->inner.n_pd_dofs, n = B->n;
  if (d1 <= fe0 || B->k == 0) return CUPID_SUCCESS;
  double c[NR * CUPID_BALANCE_GROUPS_MAX];
  for (int a = 0; a < B->k; a++) c[a] = dot(n, B->C + (size_t)a * n, x);
  if (B->sum) B->sum(c, B->k);
  if (!B->apply_here) return CUPID_SUCCESS;
  for (cupid_int j = d0 > fe0 ? d0 : fe0; j < d1; j++) {
    double v = 0.0;
    for (int a = 0; a < B->k; a++) v += B->W[(size_t)a * n + j] * c[a];
    y[j] -= v;
  }
  return CUPID_SUCCESS;
}

void cupid_coupling_balance_set_slab(cupid_coupling_balance B, void (*sum)(double *v, int n),
                                     int apply_here) {
  B->sum = sum;
  B->apply_here = apply_here;
}

cupid_status cupid_coupling_balance_linear(cupid_coupling_balance B, const cupid_linear_operator *L,
                                           cupid_linear_operator *out) {
  const int slab = L->part && L->part->parts > 1;
  CUPID_CHECK(!slab || (B->sum && L->apply_rows), CUPID_ERR_ARGUMENT,
              "balanced operator on a slab: the balance needs its slab share "
              "(cupid_coupling_balance_set_slab) and the operator its rows");
  CUPID_CHECK(L->n == B->n, CUPID_ERR_ARGUMENT, "balanced operator: %lld DOFs, balance %lld",
              (long long)L->n, (long long)B->n);
  B->inner = *L;
  *out = *L;
  out->apply = balanced_apply;
  out->apply_rows = L->apply_rows ? balanced_apply_rows : NULL;
  out->ctx = B;
  return CUPID_SUCCESS;
}

cupid_status cupid_coupling_balance_weights(const cupid_csr_t *Kfe, cupid_int n_pd, double *d) {
  CUPID_CHECK(Kfe->bs == 3, CUPID_ERR_ARGUMENT, "balance weights: FE rows in 3 x 3 blocks, got %d",
              Kfe->bs);
  memset(d, 0, (size_t)(3 * (n_pd + Kfe->nrows)) * sizeof *d);
  for (cupid_int i = 0; i < Kfe->nrows; i++) {
    int reads_pd = 0;
    const double *diag = NULL;
    for (cupid_int a = Kfe->rowptr[i]; a < Kfe->rowptr[i + 1]; a++) {
      if (Kfe->col[a] < n_pd) reads_pd = 1;
      if (Kfe->col[a] == n_pd + i) diag = Kfe->val + (size_t)a * 9;
    }
    if (!reads_pd || !diag) continue;
    for (int c = 0; c < 3; c++) d[3 * (n_pd + i) + c] = fabs(diag[4 * c]);
  }
  return CUPID_SUCCESS;
}
