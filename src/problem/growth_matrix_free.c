/* Load steps and crack growth of a PD-only 3D or an Arlequin-coupled model on the PETSc
 * engine, matrix-free: on PD slabs under mpirun, or on the whole model with --solver petsc
 * (one process; a PD-only grid also with --replicate) (issue 17, item 5; growth.c runs the
 * steps and calls these where such a run differs from the assembled one).
 *
 * A coupled model keeps the method's static operator instead (growth_operator: Arlequin's
 * weighted PD operator, the beam and the tie, whose own PD copy loses every bond prob->op
 * loses) on cupid_krylov_solver: CG with the MUMPS Cholesky factor of its bond-based twin,
 * factored once; on slabs every rank holds the whole beam, whose rows are summed over the
 * ranks at every product.
 *
 * The solve: cupid_petsc_nodes_solver, the matrix-free CG of the one-shot slab solve (a
 * MATSHELL over each rank's owned rows, GAMG on the short-range bond-based matrix of the
 * intact grid) kept for the whole run. Bonds that break and nodes that are held change the
 * operator, which the shell reads at every product; the preconditioner stays the intact
 * grid's (still symmetric positive definite, so CG converges; only its iteration count feels
 * the crack), and each re-solve starts from the last solution, which after a round of breaks
 * is already close: no set-up is repeated per broken bond (issue 17, item 3's Krylov re-solve
 * "preconditioned by the last factor", with GAMG for the factor). The target is absolute,
 * |b - K u| <= rtol |b|, as from a zero guess, so the guess does not change what "solved"
 * means.
 *
 * Support: a node whose own intact bonds no longer hold it is decided by its owner (its family
 * is whole there). A fragment cut off from every support is a connectivity question over the
 * whole grid: each rank searches its slab from the anchored nodes and those its neighbours
 * found (cupid_pd_operator_reach), the flags of the owned nodes go to the other ranks' halo
 * copies, and the rounds repeat until no copy changes anywhere. A path that crosses between
 * slabs k times takes about k + 1 rounds; an intact bond lies in the slabs of both its ends'
 * owners (the halo is at least a horizon), so each round carries every mark one crossing
 * further, and the fixed point is what one search of the whole grid finds. */
#include <string.h>

#include "method.h"
#include "problem_internal.h"

#define RUNAWAY_FACTOR 10
#define RUNAWAY_MIN 300
/* The built-in engine's re-solves: the one-shot krylov solve's tolerance (iterative.c) and
 * iteration bound before the first solve sets the runaway limit. */
#define TWIN_RTOL 1e-10
#define TWIN_MAX_IT 2000

/* A status agreed over the ranks: a slab's, or a replicated model's (PETSc is collective). */
static cupid_status agree(cupid_status st) {
  return cupid_petsc_size() > 1 ? cupid_problem_slab_agree(st) : st;
}

void cupid_growth_mf_free(cupid_growth_mf *gs) {
  cupid_petsc_nodes_solver_destroy(&gs->solver);
  cupid_krylov_solver_destroy(&gs->coupled);
  cupid_direct_factor_destroy(&gs->twin);
  if (gs->owner_destroy) gs->owner_destroy(&gs->owner);
  gs->owner_destroy = NULL;
  cupid_petsc_halo_destroy(&gs->halo);
  cupid_free(&gs->flags);
  cupid_free(&gs->u_last);
}

/* The buffers and, on a slab, the halo exchange, at the first use. */
static cupid_status setup(cupid_problem_state *prob, cupid_growth_mf *gs) {
  if (gs->u_last) return CUPID_SUCCESS;
  cupid_status st = cupid_calloc((size_t)prob->ndof + 1, sizeof *gs->u_last, "last solution", &gs->u_last);
  if (st == CUPID_SUCCESS && prob->slab) /* the support search's exchange */
    st = cupid_calloc((size_t)prob->ndof + 1, sizeof *gs->flags, "node flags", &gs->flags);
  CUPID_CALL(agree(st));
  if (!prob->slab) return CUPID_SUCCESS;
  cupid_dynamics_partition part;
  return cupid_problem_slab_partition(prob, &gs->halo, &part);
}

static cupid_status linear_apply(void *ctx, const double *x, double *y) {
  return cupid_krylov_apply(ctx, x, y);
}

/* The built-in krylov engine (one process, no PETSc): the twin's factor on the free DOFs of
 * the first solve (CHOLMOD, or UMFPACK for a non-symmetric method), kept for the run as the
 * PETSc path keeps MUMPS's. Nodes held later are fixed in bc but not in the factor: the
 * preconditioner drops their rows and columns (precondition_twin), the principal part of the
 * factor's inverse on the DOFs still free, as symmetric positive definite as the whole. */
static cupid_status twin_factor(cupid_problem_state *prob, cupid_growth_mf *gs, const cupid_csr_t *P) {
  cupid_solve_info info;
  memset(&info, 0, sizeof info);
  const cupid_matrix_kind kind = gs->L.symmetric ? CUPID_MATRIX_SPD : CUPID_MATRIX_GENERAL;
  const double t0 = cupid_wtime();
  CUPID_CALL(cupid_direct_factor_create_kind(P, kind, prob->bc, &gs->twin, &info));
  gs->twin_setup_s = cupid_wtime() - t0;
  gs->bc = prob->bc;
  return CUPID_SUCCESS;
}

/* z = M^-1 r for cupid_krylov_resolve: r's free entries through the twin's factor, z zero on
 * the fixed DOFs (those fixed since the factorisation too). */
static cupid_status precondition_twin(void *ctx, const double *r, double *z) {
  const cupid_growth_mf *gs = ctx;
  return cupid_direct_factor_solve_masked(gs->twin, gs->bc, r, z);
}

/* The krylov engine's re-solve from prob->u (zero at the first): CUPID_ERR_NUMERIC when it
 * breaks down or does not converge within the limit, u then its last iterate (where a
 * mechanism ran away: cupid_growth_mf_hold_runaway), as the PETSc solve's. */
static cupid_status twin_solve(cupid_problem_state *prob, cupid_growth_mf *gs, int guess) {
  if (!guess) memset(prob->u, 0, (size_t)prob->ndof * sizeof *prob->u);
  const int limit = gs->limit > 0 ? gs->limit : TWIN_MAX_IT;
  cupid_status st = cupid_krylov_resolve(&gs->L, prob->bc, precondition_twin, gs, prob->f_ext,
                                         prob->u, TWIN_RTOL, limit, &prob->solve);
  prob->solve.method = "krylov";
  prob->solve.matrix_free = 1;
  snprintf(prob->solve.pc_type, sizeof prob->solve.pc_type, "%s",
           gs->L.symmetric ? "cholmod" : "umfpack");
  prob->solve.time_factor = gs->twin_setup_s; /* the factorisation: charged to the first solve */
  gs->twin_setup_s = 0.0;
  CUPID_CALL(st);
  CUPID_CHECK(!strncmp(prob->solve.converged_reason, "CONVERGED", 9), CUPID_ERR_NUMERIC,
              "the Krylov re-solve (%s + the twin's factor) did not converge in %d iterations "
              "(%s): relative residual %.2e (rtol %.0e)", prob->solve.ksp_type,
              prob->solve.iterations, prob->solve.converged_reason, prob->solve.residual, TWIN_RTOL);
  return CUPID_SUCCESS;
}

/* The kept solver at the first solve: CG + GAMG on the PD grid's node operator, or a coupled
 * model's operator (the method's growth_operator, patch-tested as the one-shot solve is) with
 * the Cholesky factor of its twin by MUMPS (method_coupled.c's choice). */
static cupid_status create_solver(cupid_problem_state *prob, cupid_growth_mf *gs) {
  if (!prob->beam) {
    cupid_pd_node_operator(prob->op, prob->grid, prob->pd_materials, &gs->op);
    return agree(cupid_petsc_nodes_solver_create(&gs->op, prob->bc, &gs->solver));
  }
  CUPID_CHECK(prob->method->growth_operator, CUPID_ERR_UNSUPPORTED,
              "coupling method %s has no kept matrix-free solve for load steps", prob->method->name);
  cupid_csr P = NULL;
  cupid_method_operator owner = {0};
  CUPID_CALL(prob->method->growth_operator(prob, &gs->L, &P, &owner)); /* agreed */
  gs->owner = owner.ctx, gs->owner_destroy = owner.destroy;
  cupid_status st = cupid_problem_patch_test(prob, linear_apply, &gs->L); /* collective */
  const cupid_krylov_options ko = {.factor_package = "mumps"};
  if (st == CUPID_SUCCESS && !prob->engine->distributed) st = twin_factor(prob, gs, P);
  else if (st == CUPID_SUCCESS) st = agree(cupid_krylov_solver_create(&gs->L, P, prob->bc, &ko, &gs->coupled));
  cupid_csr_destroy(&P); /* in the factor now */
  return st;
}

cupid_status cupid_growth_mf_prepare(cupid_problem_state *prob, cupid_growth_mf *gs) {
  CUPID_CALL(setup(prob, gs));
  if (!gs->solver && !gs->coupled && !gs->twin) CUPID_CALL(create_solver(prob, gs));
  return CUPID_SUCCESS;
}

cupid_status cupid_growth_mf_set_limit(cupid_growth_mf *gs, int limit) {
  gs->limit = limit;
  if (gs->solver) cupid_petsc_nodes_solver_limit(gs->solver, limit);
  if (gs->coupled) cupid_krylov_solver_limit(gs->coupled, limit);
  return CUPID_SUCCESS;
}

cupid_status cupid_growth_mf_solve(cupid_problem_state *prob, cupid_growth_mf *gs) {
  CUPID_CALL(setup(prob, gs));
  const double t0 = cupid_wtime();
  if (!gs->solver && !gs->coupled && !gs->twin) CUPID_CALL(create_solver(prob, gs));
  const int guess = prob->growth.solves > 0;
  memcpy(gs->u_last, prob->u, (size_t)prob->ndof * sizeof *prob->u);
  cupid_status st = gs->solver  ? cupid_petsc_nodes_solver_solve(gs->solver, prob->f_ext, guess, prob->u, &prob->solve)
                    : gs->twin ? twin_solve(prob, gs, guess)
                               : cupid_krylov_solver_solve(gs->coupled, prob->f_ext, guess, prob->u, &prob->solve);
  cupid_problem_record_solve(prob);
  CUPID_CALL(agree(st));
  gs->iterations += prob->solve.iterations;
  /* A re-solve starts from the last solution, so it needs fewer iterations than the first;
   * CG on a mechanism (a part that lost its support in a way the search does not see) never
   * converges, and is told by needing RUNAWAY_FACTOR times the first solve's count (bounded
   * below by RUNAWAY_MIN), not the default 10^4 (cupid_growth_mf_hold_runaway then). */
  const int limit = RUNAWAY_FACTOR * prob->solve.iterations > RUNAWAY_MIN
                        ? RUNAWAY_FACTOR * prob->solve.iterations
                        : RUNAWAY_MIN;
  if (!guess) CUPID_CALL(cupid_growth_mf_set_limit(gs, limit));
  gs->setup_s += prob->solve.time_factor;
  gs->solve_s += cupid_wtime() - t0 - prob->solve.time_factor;
  if (gs->coupled || gs->twin) /* u on every local DOF from the solve; the owned and the beam's rows */
    return agree(cupid_krylov_apply(&gs->L, prob->u, prob->f_int));
  /* the whole slab's u: owned from the solve, the halo from its owners (a whole grid: every
   * node from the solve) */
  if (prob->slab) CUPID_CALL(cupid_problem_slab_agree(cupid_petsc_halo_update(gs->halo, prob->u)));
  for (cupid_int d = 0; d < prob->ndof; d++)
    if (prob->bc->fixed[d]) prob->u[d] = prob->bc->value[d];
  const cupid_int a = prob->part.owned_first, b = prob->part.owned_last;
  return agree(cupid_pd_operator_apply_range(prob->op, a, b, prob->u, prob->f_int + 3 * a));
}

/* Node flags of the owned nodes to every halo copy: copy[i] = owner's (overwrite), or
 * copy[i] |= owner's (*changed: how many copies that raised). */
static cupid_status share_flags(cupid_problem_state *prob, cupid_growth_mf *gs,
                                unsigned char *flag, int or, cupid_int *changed) {
  const cupid_int first = prob->part.owned_first, last = prob->part.owned_last;
  cupid_int n = 0;
  for (cupid_int i = first; i < last; i++) gs->flags[3 * i] = flag[i];
  CUPID_CALL(cupid_problem_slab_agree(cupid_petsc_halo_update(gs->halo, gs->flags)));
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    if (i >= first && i < last) continue;
    const unsigned char v = (unsigned char)gs->flags[3 * i];
    if (!or) flag[i] = v;
    else if (v && !flag[i]) flag[i] = v, n++;
  }
  if (changed) *changed = n;
  return CUPID_SUCCESS;
}

cupid_status cupid_growth_mf_unsupported(cupid_problem_state *prob, cupid_growth_mf *gs,
                                           const unsigned char *anchored, unsigned char *release,
                                           cupid_int *fresh) {
  const cupid_int first = prob->part.owned_first, last = prob->part.owned_last, nn = prob->n_pd;
  unsigned char *seen = NULL;
  cupid_int weak = 0, added = 0, changed = 0;
  CUPID_CALL(setup(prob, gs));
  CUPID_CALL(cupid_problem_slab_agree(cupid_calloc((size_t)nn + 1, 1, "node flags", &seen)));
  cupid_status st = cupid_pd_operator_weakly_held(prob->op, first, last, release, &weak);
  CUPID_TRY(cupid_problem_slab_agree(st));
  CUPID_TRY(share_flags(prob, gs, release, 0, NULL));
  for (cupid_int i = 0; i < nn; i++) seen[i] = anchored[i] && !release[i];
  do { /* rounds of a search on each slab and an exchange, to the fixed point */
    CUPID_TRY(cupid_problem_slab_agree(cupid_pd_operator_reach(prob->op, release, seen, &added)));
    CUPID_TRY(share_flags(prob, gs, seen, 1, &changed));
  } while (cupid_petsc_max_int(changed > 0));
  cupid_int n = 0;
  for (cupid_int i = first; i < last; i++) {
    if (!release[i] && !seen[i]) release[i] = 2;
    n += release[i] == 2;
  }
  CUPID_TRY(share_flags(prob, gs, release, 0, NULL));
  *fresh = cupid_problem_global_count(prob, n);
cleanup:
  cupid_free(&seen);
  return st;
}

cupid_status cupid_growth_mf_hold_runaway(cupid_problem_state *prob, cupid_growth_mf *gs,
                                            unsigned char *release, double x[3], int *held) {
  const cupid_int first = prob->part.owned_first, last = prob->part.owned_last;
  const cupid_dirichlet_t *bc = prob->bc;
  *held = 0;
  if (prob->slab) CUPID_CALL(cupid_problem_slab_agree(cupid_petsc_halo_update(gs->halo, prob->u)));
  /* this rank's owned node that moved furthest, then the largest over the ranks */
  double top = 0.0;
  cupid_int node = -1;
  for (cupid_int i = first; i < last; i++) {
    if (release[i]) continue;
    double d2 = 0.0;
    for (int c = 0; c < 3; c++) {
      const double d = bc->fixed[3 * i + c] ? 0.0 : prob->u[3 * i + c] - gs->u_last[3 * i + c];
      d2 += d * d;
    }
    if (!(d2 >= 0.0)) continue; /* a NaN never wins */
    if (node < 0 || d2 > top) top = d2, node = i;
  }
  double best = node >= 0 ? top : -1.0;
  cupid_petsc_max_doubles(&best, 1);
  const int size = cupid_petsc_size(), rank = cupid_petsc_rank();
  const int winner = cupid_problem_lowest_rank(node >= 0 && top == best && best > 0.0);
  double where[4] = {0, 0, 0, 0}; /* the global index and position, from the winner */
  if (winner == rank) {
    const double *xi = cupid_pd_grid_coords(prob->grid) + 3 * node;
    where[0] = (double)(prob->part.first_global + node);
    for (int c = 0; c < 3; c++) where[1 + c] = xi[c];
  }
  cupid_petsc_sum_doubles(where, 4);
  memcpy(prob->u, gs->u_last, (size_t)prob->ndof * sizeof *prob->u);
  if (winner >= size) return CUPID_SUCCESS; /* nothing moved */
  const cupid_int i = (cupid_int)where[0] - prob->part.first_global;
  cupid_status st = CUPID_SUCCESS;
  if (i >= 0 && i < prob->n_pd) { /* this rank holds it, owned or as halo */
    release[i] = 1;
    for (int c = 0; c < 3 && st == CUPID_SUCCESS; c++)
      st = cupid_dirichlet_fix(prob->bc, 3 * i + c, prob->u[3 * i + c]);
    if (st == CUPID_SUCCESS) st = cupid_dirichlet_finalize(prob->bc);
  }
  CUPID_CALL(agree(st));
  for (int c = 0; c < 3; c++) x[c] = where[1 + c];
  *held = 1;
  return CUPID_SUCCESS;
}
