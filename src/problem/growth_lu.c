/* Crack growth with a non-symmetric coupling on the direct engine (fictitious nodes, paper 000
 * Eq. 38, with `balance: none` or `momentum`; issue 34): the factor of the last factorised K,
 * brought to the current K exactly as bonds break, and a re-solve from the last solution.
 *
 * The factor is the block elimination of growth_block.c: CHOLMOD of the symmetric PD block,
 * downdated by the broken bonds as growth.c downdates Arlequin's factor, the beam block's LU and
 * a small capacitance on the interface (the balance's W C^T folded in). A round costs its
 * downdate and one solve with the round's columns; every re-solve is one step
 * x += M^-1 (f - K x) on the current K, checked by its residual (GMRES from there if a node
 * held since the factorisation made it inexact). On the SENB at h = 1, 20 steps: 28.3 s and
 * 0.37 GB against Arlequin's 20.2 s and 0.31 GB (bench/README.md).
 *
 * Where K is not two such blocks (a PD block that is not symmetric, a singular beam block) the
 * factor is UMFPACK's LU of the whole K. SuiteSparse cannot downdate an LU, but a bond broken
 * outside the coupling zone changes K by its symmetric rank-one pair term alone
 * (growth_downdate.c checks both triangles; docs/theory.md), so that LU is updated by
 * Sherman-Morrison-Woodbury (growth_smw.c): one solve with it per broken bond, when it breaks.
 * The balanced K' = K - W C^T (balance.c: six terms per balanced group) is that LU's exactly by
 * its own SMW (cupid_coupling_balance_smw): breaks change neither W nor C. That path took 37 s
 * and 593 MB on the same SENB (1,610 update columns of 12 ms).
 *
 * The factor is renewed when a round breaks more bonds than a factorisation is worth (a crack
 * running through: 1/BLOCK_MAX_SHARE of the PD equations for the block factor, as growth.c's
 * downdates; for the LU, more columns than a factorisation is worth in solves, or more than
 * the LU holds), by the rent rule of growth.c for what is left (GMRES iterations past the
 * check, the products with the LU's update columns), when a re-solve needs more than
 * LU_RESOLVE_MAX iterations, when the update finds K singular (the factorisation then names
 * the node), and at the first solve of a load step after breaks that were not brought in.
 * Counted, not timed, so that the choice is the same in every run. A change that is no sum of
 * bond terms (LPS) turns the updates off for the run: each re-solve is then GMRES on the last
 * factor, right-preconditioned by it (K_last^-1 K_now is the identity plus a change of the
 * broken bonds' rank). Every scalar product is cupid_dot's or in a fixed order, so the
 * iterates, hence the bonds that break, are the same for any thread count. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "method.h"
#include "problem_internal.h"

#define LU_RTOL 1e-12        /* growth.c's CG_RTOL */
#define LU_RESOLVE_MAX 60    /* growth.c's CG_REFACTOR */
#define BLOCK_MAX_SHARE 50  /* growth.c's DOWNDATE_MAX_SHARE */
#define LU_FLOP_WEIGHT 5.0   /* growth.c's CG_FLOP_WEIGHT: a triangular solve's operation is
                                memory-bound, ~5 times one of the factorisation's */

int cupid_growth_lu_applies(const cupid_problem_state *prob) {
  return prob->method->matrix == CUPID_MATRIX_GENERAL && !prob->engine->iterative;
}

void cupid_growth_lu_renew(cupid_growth_lu *s) {
  cupid_growth_block_destroy(&s->M);
  cupid_growth_smw_reset(&s->upd);
  cupid_coupling_balance_smw_destroy(&s->smw);
  cupid_direct_factor_destroy(&s->F);
}

void cupid_growth_lu_free(cupid_growth_lu *s) {
  cupid_growth_lu_renew(s);
  cupid_coupling_balance_destroy(&s->B);
  cupid_growth_smw_free(&s->upd);
  cupid_growth_downdate_free(&s->dd);
  cupid_free(&s->t);
  cupid_free(&s->z);
  cupid_free(&s->w);
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
  cupid_growth_block M;           /* the block factor (balanced within), or NULL and: */
  cupid_direct_factor F;
  cupid_coupling_balance_smw smw; /* balanced: the factor's K' exactly */
  const cupid_growth_smw *upd;    /* the bonds broken since (NULL: the factor's K) */
  const cupid_dirichlet_t *bc;
  double *t;
} lu_pc;

/* z = P M^-1 P^T r, M the factorised K (balanced: K - W C^T by SMW, whose C and W breaks do not
 * change) less the bonds broken since (growth_smw.c): the factor keeps the free DOFs it was made
 * with; nodes held since then are fixed now (r and z zero there), so this is M restricted to the
 * current free DOFs, exact while no node was held since the factorisation. */
static cupid_status lu_apply(void *ctx, const double *r, double *z) {
  const lu_pc *p = ctx;
  const cupid_int n = p->bc->n;
  for (cupid_int d = 0; d < n; d++) p->t[d] = p->bc->fixed[d] ? 0.0 : r[d];
  if (p->M) CUPID_CALL(cupid_growth_block_solve(p->M, p->t, z));
  else if (p->smw) CUPID_CALL(cupid_coupling_balance_smw_apply(p->smw, p->t, z));
  else CUPID_CALL(cupid_direct_factor_solve(p->F, p->t, z));
  if (p->upd) cupid_growth_smw_correct(p->upd, z);
  for (cupid_int d = 0; d < n; d++)
    if (p->bc->fixed[d]) z[d] = 0.0;
  return CUPID_SUCCESS;
}

static cupid_status factorise(cupid_problem_state *prob, cupid_growth_lu *s,
                              const cupid_coupling_balance B) {
  cupid_solve_info info;
  const double t0 = cupid_wtime();
  cupid_growth_lu_renew(s);
  cupid_status st = CUPID_SUCCESS;
  if (!s->whole) { /* block elimination: the symmetric PD block's CHOLMOD factor */
    st = cupid_growth_block_create(prob->K, prob->fe_offset, prob->bc, B, &s->M, &info);
    if (st == CUPID_SUCCESS && !s->M) {
      s->whole = 1;
      cupid_problem_progress(prob, "growth: K is not two blocks the elimination takes (a PD block "
                             "that is not symmetric, or a singular FE block): the LU of the "
                             "whole K, updated by Sherman-Morrison-Woodbury");
    } else if (st == CUPID_SUCCESS && s->factorisations == 0) {
      cupid_int nic = 0, nib = 0;
      const cupid_int ns = cupid_growth_block_interface(s->M, &nic, &nib);
      cupid_problem_progress(prob, "growth: block elimination: CHOLMOD of the PD block (%lld "
                             "equations), the LU of the %lld free FE DOFs' block and an "
                             "interface of %lld x %lld; factors %.3g M entries",
                             (long long)(info.n - ns), (long long)ns, (long long)nic,
                             (long long)nib, info.nnz_factor / 1e6);
    }
  }
  if (st == CUPID_SUCCESS && !s->M)
    st = cupid_direct_factor_create_kind(prob->K, CUPID_MATRIX_GENERAL, prob->bc, &s->F, &info);
  prob->solve = info; /* a breakdown names its DOF (growth.c holds its node) */
  CUPID_CALL(st);
  s->factor_info = info;
  s->factorisations++;
  s->bonds_at_factor = prob->broken_bonds;
  s->factor_flops = info.flops_factor;
  const double nnz_k = (double)prob->K->rowptr[prob->K->nrows] * prob->K->bs * prob->K->bs;
  /* a solve reads the factor twice (forward, back; the block factor's Cholesky factor once
   * each, with the beam block's small LU) and K once */
  s->iteration_flops = 4.0 * info.nnz_factor + 2.0 * nnz_k;
  s->since_factor = 0;
  s->updates_since = 0;
  if (B && s->F) CUPID_CALL(cupid_coupling_balance_smw_create(B, s->F, prob->bc, &s->smw));
  s->t_factor += cupid_wtime() - t0;
  return CUPID_SUCCESS;
}

/* |f_f - K_f x| over the free DOFs into r (0 on the fixed ones), x holding the prescribed
 * values on the fixed DOFs. */
static double free_residual(const cupid_problem_state *prob, const cupid_linear_operator *L,
                            const double *x, double *r) {
  const cupid_dirichlet_t *bc = prob->bc;
  L->apply(L->ctx, x, r);
  for (cupid_int d = 0; d < prob->ndof; d++) r[d] = bc->fixed[d] ? 0.0 : prob->f_ext[d] - r[d];
  return sqrt(cupid_dot(prob->ndof, r, r));
}

/* One step x += M^-1 (f - K x) from x = s->z: with the factor brought to the current K by the
 * updates it is the solution but for round-off, in two products and a solve where a GMRES cycle
 * of one iteration takes three and two. info->converged_reason says CONVERGED when the residual
 * meets GMRES's own test (LU_RTOL |f_f - K_fc u_c|); else GMRES goes on from x. */
static cupid_status one_step(cupid_problem_state *prob, cupid_growth_lu *s,
                             const cupid_linear_operator *L, lu_pc *pc, cupid_solve_info *info) {
  const cupid_dirichlet_t *bc = prob->bc;
  const cupid_int n = prob->ndof;
  double *x = s->z, *r = s->w, *dz = s->w + n;
  for (cupid_int d = 0; d < n; d++) dz[d] = bc->fixed[d] ? bc->value[d] : 0.0;
  const double bnorm = free_residual(prob, L, dz, r);
  for (cupid_int d = 0; d < n; d++)
    if (bc->fixed[d]) x[d] = bc->value[d];
  double rnorm = free_residual(prob, L, x, r);
  memset(info, 0, sizeof *info);
  if (rnorm > LU_RTOL * bnorm) {
    CUPID_CALL(lu_apply(pc, r, dz));
    for (cupid_int d = 0; d < n; d++)
      if (!bc->fixed[d]) x[d] += dz[d];
    rnorm = free_residual(prob, L, x, r);
    info->iterations = 1;
  }
  CUPID_CHECK(isfinite(rnorm), CUPID_ERR_NUMERIC, "growth: a non-finite residual in the re-solve");
  info->residual = bnorm > 0.0 ? rnorm / bnorm : 0.0;
  snprintf(info->converged_reason, sizeof info->converged_reason, "%s",
           rnorm <= LU_RTOL * bnorm ? "CONVERGED_RTOL" : "NOT_YET");
  return CUPID_SUCCESS;
}

/* From prob->u: one step on the updated factor, then GMRES if need be; *done = 1 when it
 * converged within LU_RESOLVE_MAX iterations (u then the solution, else as it was). */
static cupid_status resolve(cupid_problem_state *prob, cupid_growth_lu *s,
                            const cupid_linear_operator *L, int *done) {
  const size_t n = (size_t)prob->ndof;
  const double t0 = cupid_wtime();
  lu_pc pc = {s->M, s->F, s->smw, &s->upd, prob->bc, s->t};
  cupid_solve_info info;
  memcpy(s->z, prob->u, n * sizeof *s->z);
  int stepped = 0;
  if (!s->no_update) {
    CUPID_CALL(one_step(prob, s, L, &pc, &info));
    stepped = strncmp(info.converged_reason, "CONVERGED", 9) == 0;
  }
  if (!stepped) {
    const int before = s->no_update ? 0 : info.iterations; /* the step's */
    CUPID_CALL(cupid_gmres_resolve(L, prob->bc, lu_apply, &pc, prob->f_ext, s->z, LU_RTOL,
                                   LU_RESOLVE_MAX, &info));
    info.iterations += before;
  }
  s->t_resolve += cupid_wtime() - t0;
  *done = strncmp(info.converged_reason, "CONVERGED", 9) == 0;
  if (!*done) return CUPID_SUCCESS;
  memcpy(prob->u, s->z, n * sizeof *s->z);
  s->resolves += info.iterations > 0;
  s->iterations += info.iterations;
  /* an updated factor is the current K's: its one iteration is the check, not rent */
  s->since_factor += info.iterations - ((s->M || s->upd.r > 0) && info.iterations > 0);
  s->since_factor += info.iterations * 2.0 * (double)s->upd.r * (double)prob->ndof / s->iteration_flops;
  prob->solve = s->factor_info; /* the factor's figures, the re-solve's outcome */
  prob->solve.method = s->M ? (stepped ? "cholmod + schur, updated" : "cholmod + schur + gmres")
                            : (stepped ? "umfpack, updated" : "umfpack + gmres");
  prob->solve.iterations = info.iterations;
  prob->solve.residual = info.residual;
  prob->solve.time_solve = info.time_solve;
  snprintf(prob->solve.ksp_type, sizeof prob->solve.ksp_type, stepped ? "richardson" : "gmres");
  snprintf(prob->solve.pc_type, sizeof prob->solve.pc_type, "%s",
           s->M       ? (s->updates_since ? "block factor, downdated" : "block lu of the last K")
           : s->upd.r ? "lu of the last K, updated"
                      : "lu of the last K");
  snprintf(prob->solve.converged_reason, sizeof prob->solve.converged_reason, "%s",
           info.converged_reason);
  return CUPID_SUCCESS;
}

/* The block factor downdated by the round's bonds (growth_block.c), as growth.c downdates
 * Arlequin's CHOLMOD factor, and renewed on the same count: a round that broke more than
 * 1/BLOCK_MAX_SHARE of its PD equations' worth of bonds (a crack running through) is cheaper
 * to factorise afresh. */
static cupid_status block_downdate(cupid_problem_state *prob, cupid_growth_lu *s, double t0) {
  int ok = 0;
  cupid_int nic = 0, nib = 0;
  const cupid_int na = s->factor_info.n - cupid_growth_block_interface(s->M, &nic, &nib);
  if (s->dd.r > na / BLOCK_MAX_SHARE) ok = 0;
  else CUPID_CALL(cupid_growth_block_downdate(s->M, &s->dd, &ok));
  if (!ok) cupid_growth_lu_renew(s); /* or K singular: the factorisation names the node */
  else {
    s->bonds_at_factor = prob->broken_bonds;
    s->updates++;
    s->updates_since++;
    s->update_columns += s->dd.r;
  }
  s->t_update += cupid_wtime() - t0;
  return CUPID_SUCCESS;
}

/* Bring the last LU to the K that broken bonds left (Kold: the K of the last solve): their
 * rank-one terms (growth_downdate.c, both triangles checked) join the Sherman-Morrison-Woodbury
 * update of the factor (growth_smw.c), so that it inverts the current K and a re-solve is one
 * step, as it is one CG iteration on a downdated CHOLMOD factor for Arlequin. A change that is no sum of
 * bond terms (LPS) turns updates off for the run (GMRES on the last LU as before); a round that
 * leaves K singular drops the factor, and the factorisation names the node. */
cupid_status cupid_growth_lu_update(cupid_problem_state *prob, cupid_growth_lu *s,
                                    const cupid_csr_t *Kold) {
  if (!cupid_growth_lu_has_factor(s) || s->no_update) return CUPID_SUCCESS;
  const double t0 = cupid_wtime();
  int ok = 0;
  CUPID_CALL(cupid_growth_downdate_terms(Kold, prob->K, &s->dd, &ok));
  if (!ok) {
    s->no_update = 1;
    cupid_problem_progress(prob, "growth: the broken bonds changed K by more than a rank-one term "
                           "each (LPS): re-solves by GMRES on the last LU, no updates");
    return CUPID_SUCCESS;
  }
  if (s->dd.r == 0) return CUPID_SUCCESS;
  if (s->M) return block_downdate(prob, s, t0);
  /* A column costs a solve, paid whether or not the factor is renewed later (the bond is
   * broken in every later K): renewing saves only the round's own columns, and then only when
   * they cost more than a factorisation (a crack running through); and Z is kept no larger
   * than the LU itself. The products with Z are rent (cupid_growth_lu_solve). */
  const double columns_per_factor = s->factor_flops / (LU_FLOP_WEIGHT * s->iteration_flops);
  if ((double)s->dd.r > columns_per_factor ||
      (double)(s->upd.r + s->dd.r) * (double)prob->ndof > s->factor_info.nnz_factor) {
    cupid_growth_lu_renew(s);
    s->t_update += cupid_wtime() - t0;
    return CUPID_SUCCESS;
  }
  lu_pc pc = {NULL, s->F, s->smw, NULL, prob->bc, s->t};
  CUPID_CALL(cupid_growth_smw_add(&s->upd, prob->ndof, &s->dd, lu_apply, &pc, &ok));
  if (!ok) cupid_growth_lu_renew(s); /* K singular: the factorisation names the node */
  else {
    s->bonds_at_factor = prob->broken_bonds;
    s->updates++;
    s->update_columns += s->dd.r;
  }
  s->t_update += cupid_wtime() - t0;
  return CUPID_SUCCESS;
}

cupid_status cupid_growth_lu_prepare(cupid_problem_state *prob, cupid_growth_lu *s) {
  const size_t n = (size_t)prob->ndof;
  if (!s->t) CUPID_CALL(cupid_calloc(n + 1, sizeof *s->t, "growth work vector", &s->t));
  if (!s->z) CUPID_CALL(cupid_calloc(n + 1, sizeof *s->z, "growth work vector", &s->z));
  if (!s->w) CUPID_CALL(cupid_calloc(2 * n + 1, sizeof *s->w, "growth work vector", &s->w));
  /* W and C = K^T R of the first K, kept for the run: a break away from the interfaces leaves
   * both as they were (docs/theory.md; unit.coupling_fracture) */
  if (cupid_problem_balanced(prob) && !s->B)
    CUPID_CALL(cupid_problem_balance_assembled(prob, prob->K, &s->B));
  return CUPID_SUCCESS;
}

cupid_status cupid_growth_lu_factorise(cupid_problem_state *prob, cupid_growth_lu *s) {
  return factorise(prob, s, s->B);
}

cupid_status cupid_growth_lu_solve(cupid_problem_state *prob, cupid_growth_lu *s) {
  cupid_status st = CUPID_SUCCESS;
  CUPID_CALL(cupid_growth_lu_prepare(prob, s));
  system_op op = {prob->K, s->B};
  if (!s->patch_tested) { /* the first K, as the one-shot solves test theirs (Eq. 38 itself:
                             balance.c says why) */
    CUPID_TRY(cupid_problem_patch_test_assembled(prob));
    s->patch_tested = 1;
  }
  const cupid_linear_operator L = {.n = prob->ndof, .apply = system_apply, .ctx = &op};
  int done = 0;
  if (cupid_growth_lu_has_factor(s)) CUPID_TRY(resolve(prob, s, &L, &done));
  if (!done) {
    CUPID_TRY(factorise(prob, s, op.B));
    for (cupid_int d = 0; d < prob->ndof; d++) /* the factor's own solution as the guess */
      s->t[d] = prob->bc->fixed[d] ? prob->bc->value[d] : 0.0;
    CUPID_TRY(system_apply(&op, s->t, s->z));
    for (cupid_int d = 0; d < prob->ndof; d++) s->z[d] = prob->bc->fixed[d] ? 0.0 : prob->f_ext[d] - s->z[d];
    lu_pc pc = {s->M, s->F, s->smw, NULL, prob->bc, s->t};
    CUPID_TRY(lu_apply(&pc, s->z, prob->u));
    for (cupid_int d = 0; d < prob->ndof; d++)
      if (prob->bc->fixed[d]) prob->u[d] = prob->bc->value[d];
    CUPID_TRY(resolve(prob, s, &L, &done)); /* checked, refined if need be */
    if (!done) { /* the fresh factor of this K cannot solve it: K is singular but for round-off
                    (a mechanism breaking left, that passed the pivot bound); its weakest pivot
                    names the node growth.c holds, as for a factorisation that broke down */
      cupid_int dof = -1;
      CUPID_TRY(s->M ? cupid_growth_block_weakest_dof(s->M, &dof)
                     : cupid_direct_factor_weakest_dof(s->F, &dof));
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
  if (s->since_factor * LU_FLOP_WEIGHT * s->iteration_flops > s->factor_flops)
    cupid_growth_lu_renew(s);
  CUPID_TRY(system_apply(&op, prob->u, prob->f_int));
cleanup:
  return st;
}
