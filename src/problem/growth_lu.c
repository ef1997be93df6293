/* Crack growth with a non-symmetric coupling on the direct engine (fictitious nodes, paper 000
 * Eq. 38, with `balance: none` or `momentum`; issue 34): each solve after bonds broke is GMRES
 * on the current K from the last solution, right-preconditioned by the UMFPACK LU of the last
 * factorised K (growth.c's CG on the last CHOLMOD factor, for a matrix CG cannot take).
 *
 * Why GMRES on the last LU: a break changes K by the terms of a few bonds (bond-based: rank one
 * each), so K_last^-1 K_now is the identity plus a change of that rank, and GMRES converges in
 * about as many iterations; an LU of the SENB's coupled K costs about 50 of them. The balanced
 * K' = K - W C^T (balance.c: six terms per balanced group) is preconditioned by the factorised
 * K' exactly, by Sherman-Morrison-Woodbury on the LU (cupid_coupling_balance_smw): breaks change
 * neither W nor C (docs/theory.md), so K'_last^-1 K'_now differs from the identity by the broken
 * bonds alone, as unbalanced (101 -> 75 s on the SENB at h = 1 against the LU of K alone). The
 * factor is renewed by the rent rule of growth.c (the GMRES iterations since the factorisation
 * cost as much as it did, by operation counts, so that the choice does not depend on the
 * machine's load), when a re-solve needs more than LU_RESOLVE_MAX iterations, and at the first
 * solve of a load step after breaks (growth.c: a mechanism the support search misses shows as
 * a singular factorisation, which names its node). Every scalar product is cupid_dot's, so the
 * iterates, hence the bonds that break, are the same for any thread count. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "method.h"
#include "problem_internal.h"

#define LU_RTOL 1e-12        /* growth.c's CG_RTOL */
#define LU_RESOLVE_MAX 60    /* growth.c's CG_REFACTOR */
#define LU_FLOP_WEIGHT 5.0   /* growth.c's CG_FLOP_WEIGHT: a triangular solve's operation is
                                memory-bound, ~5 times one of the factorisation's */

int cupid_growth_lu_applies(const cupid_problem_state *prob) {
  return prob->method->matrix == CUPID_MATRIX_GENERAL && !prob->engine->iterative && prob->K;
}

void cupid_growth_lu_renew(cupid_growth_lu *s) {
  cupid_coupling_balance_smw_destroy(&s->smw);
  cupid_direct_factor_destroy(&s->F);
}

void cupid_growth_lu_free(cupid_growth_lu *s) {
  cupid_growth_lu_renew(s);
  cupid_coupling_balance_destroy(&s->B);
  cupid_free(&s->t);
  cupid_free(&s->z);
}

/* The system's operator: K, or K' = K - W C^T with C = K^T R of this K. */
typedef struct {
  const cupid_csr_t *K;
  cupid_coupling_balance B; /* NULL: K itself */
} system_op;

static cupid_status system_apply(void *ctx, const double *x, double *y) {
  const system_op *o = ctx;
  cupid_csr_matvec(o->K, x, y);
  if (o->B) cupid_coupling_balance_correct(o->B, x, y);
  return CUPID_SUCCESS;
}

typedef struct {
  cupid_direct_factor F;
  cupid_coupling_balance_smw smw; /* balanced: the factor's K' exactly */
  const cupid_dirichlet_t *bc;
  double *t;
} lu_pc;

/* z = P M^-1 P^T r, M the factorised K (balanced: K - W C^T by SMW, whose C and W breaks do not
 * change): the factor keeps the free DOFs it was made with; nodes held since then are fixed now
 * (r and z zero there), so this is M restricted to the current free DOFs. */
static cupid_status lu_apply(void *ctx, const double *r, double *z) {
  const lu_pc *p = ctx;
  const cupid_int n = p->bc->n;
  for (cupid_int d = 0; d < n; d++) p->t[d] = p->bc->fixed[d] ? 0.0 : r[d];
  if (p->smw) CUPID_CALL(cupid_coupling_balance_smw_apply(p->smw, p->t, z));
  else CUPID_CALL(cupid_direct_factor_solve(p->F, p->t, z));
  for (cupid_int d = 0; d < n; d++)
    if (p->bc->fixed[d]) z[d] = 0.0;
  return CUPID_SUCCESS;
}

static cupid_status factorise(cupid_problem_state *prob, cupid_growth_lu *s,
                              const cupid_coupling_balance B) {
  cupid_solve_info info;
  const double t0 = cupid_wtime();
  cupid_growth_lu_renew(s);
  cupid_status st = cupid_direct_factor_create_kind(prob->K, CUPID_MATRIX_GENERAL, prob->bc, &s->F, &info);
  prob->solve = info; /* a breakdown names its DOF (growth.c holds its node) */
  CUPID_CALL(st);
  s->factor_info = info;
  s->factorisations++;
  s->bonds_at_factor = prob->broken_bonds;
  s->factor_flops = info.flops_factor;
  const double nnz_k = (double)prob->K->rowptr[prob->K->nrows] * prob->K->bs * prob->K->bs;
  s->iteration_flops = 4.0 * info.nnz_factor + 2.0 * nnz_k;
  s->since_factor = 0;
  if (B) CUPID_CALL(cupid_coupling_balance_smw_create(B, s->F, prob->bc, &s->smw));
  s->t_factor += cupid_wtime() - t0;
  return CUPID_SUCCESS;
}

/* GMRES from prob->u; *done = 1 when it converged within LU_RESOLVE_MAX (u then the solution,
 * else as it was). */
static cupid_status resolve(cupid_problem_state *prob, cupid_growth_lu *s,
                            const cupid_linear_operator *L, int *done) {
  const size_t n = (size_t)prob->ndof;
  const double t0 = cupid_wtime();
  lu_pc pc = {s->F, s->smw, prob->bc, s->t};
  cupid_solve_info info;
  memcpy(s->z, prob->u, n * sizeof *s->z);
  CUPID_CALL(cupid_gmres_resolve(L, prob->bc, lu_apply, &pc, prob->f_ext, s->z, LU_RTOL,
                                 LU_RESOLVE_MAX, &info));
  s->t_resolve += cupid_wtime() - t0;
  *done = strncmp(info.converged_reason, "CONVERGED", 9) == 0;
  if (!*done) return CUPID_SUCCESS;
  memcpy(prob->u, s->z, n * sizeof *s->z);
  s->resolves += info.iterations > 0;
  s->iterations += info.iterations;
  s->since_factor += info.iterations;
  prob->solve = s->factor_info; /* the factor's figures, the re-solve's outcome */
  prob->solve.method = "umfpack + gmres";
  prob->solve.iterations = info.iterations;
  prob->solve.residual = info.residual;
  prob->solve.time_solve = info.time_solve;
  snprintf(prob->solve.ksp_type, sizeof prob->solve.ksp_type, "gmres");
  snprintf(prob->solve.pc_type, sizeof prob->solve.pc_type, "lu of the last K");
  snprintf(prob->solve.converged_reason, sizeof prob->solve.converged_reason, "%s",
           info.converged_reason);
  return CUPID_SUCCESS;
}

cupid_status cupid_growth_lu_solve(cupid_problem_state *prob, cupid_growth_lu *s) {
  const size_t n = (size_t)prob->ndof;
  cupid_status st = CUPID_SUCCESS;
  if (!s->t) CUPID_CALL(cupid_calloc(n + 1, sizeof *s->t, "growth work vector", &s->t));
  if (!s->z) CUPID_CALL(cupid_calloc(n + 1, sizeof *s->z, "growth work vector", &s->z));
  /* W and C = K^T R of the first K, kept for the run: a break away from the interfaces leaves
   * both as they were (docs/theory.md; unit.coupling_fracture) */
  if (cupid_problem_balanced(prob) && !s->B)
    CUPID_CALL(cupid_problem_balance_assembled(prob, prob->K, &s->B));
  system_op op = {prob->K, s->B};
  if (!s->patch_tested) { /* the first K, as the one-shot solves test theirs (Eq. 38 itself:
                             balance.c says why) */
    CUPID_TRY(cupid_problem_patch_test_assembled(prob));
    s->patch_tested = 1;
  }
  const cupid_linear_operator L = {.n = prob->ndof, .apply = system_apply, .ctx = &op};
  int done = 0;
  if (s->F) CUPID_TRY(resolve(prob, s, &L, &done));
  if (!done) {
    CUPID_TRY(factorise(prob, s, op.B));
    for (cupid_int d = 0; d < prob->ndof; d++) /* the factor's own solution as the guess */
      s->t[d] = prob->bc->fixed[d] ? prob->bc->value[d] : 0.0;
    CUPID_TRY(system_apply(&op, s->t, s->z));
    for (cupid_int d = 0; d < prob->ndof; d++) s->z[d] = prob->bc->fixed[d] ? 0.0 : prob->f_ext[d] - s->z[d];
    lu_pc pc = {s->F, s->smw, prob->bc, s->t};
    CUPID_TRY(lu_apply(&pc, s->z, prob->u));
    for (cupid_int d = 0; d < prob->ndof; d++)
      if (prob->bc->fixed[d]) prob->u[d] = prob->bc->value[d];
    CUPID_TRY(resolve(prob, s, &L, &done)); /* checked, refined if need be */
    if (!done) { /* the fresh factor of this K cannot solve it: K is singular but for round-off
                    (a mechanism breaking left, that passed the pivot bound); its weakest pivot
                    names the node growth.c holds, as for a factorisation that broke down */
      cupid_int dof = -1;
      CUPID_TRY(cupid_direct_factor_weakest_dof(s->F, &dof));
      prob->solve.failed_dof = dof;
      cupid_growth_lu_renew(s);
      st = CUPID_ERROR(CUPID_ERR_NUMERIC,
                       "growth: GMRES on the fresh LU of K did not reach a relative residual of "
                       "%.0e in %d iterations: K is singular to round-off at DOF %lld (a part "
                       "that breaking left loose)",
                       LU_RTOL, LU_RESOLVE_MAX, (long long)dof);
      goto cleanup;
    }
  }
  prob->solved = 1;
  cupid_problem_record_solve(prob);
  /* rent: renew once the iterations since the factorisation cost as much as it did */
  if ((double)s->since_factor * LU_FLOP_WEIGHT * s->iteration_flops > s->factor_flops)
    cupid_growth_lu_renew(s);
  CUPID_TRY(system_apply(&op, prob->u, prob->f_int));
cleanup:
  return st;
}
