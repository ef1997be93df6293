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

/* A status agreed over the ranks: a slab's, or a replicated model's (PETSc is collective). */
static cupid_status agree(cupid_status st) {
  return cupid_petsc_size() > 1 ? cupid_problem_slab_agree(st) : st;
}

void cupid_growth_mf_free(cupid_growth_mf *gs) {
  cupid_petsc_nodes_solver_destroy(&gs->solver);
  cupid_krylov_solver_destroy(&gs->coupled);
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
  if (st == CUPID_SUCCESS) st = agree(cupid_krylov_solver_create(&gs->L, P, prob->bc, &ko, &gs->coupled));
  cupid_csr_destroy(&P); /* in PETSc's factor now */
  return st;
}

cupid_status cupid_growth_mf_prepare(cupid_problem_state *prob, cupid_growth_mf *gs) {
  CUPID_CALL(setup(prob, gs));
  if (!gs->solver && !gs->coupled) CUPID_CALL(create_solver(prob, gs));
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
  if (!gs->solver && !gs->coupled) CUPID_CALL(create_solver(prob, gs));
  const int guess = prob->growth.solves > 0;
  memcpy(gs->u_last, prob->u, (size_t)prob->ndof * sizeof *prob->u);
  cupid_status st = gs->solver ? cupid_petsc_nodes_solver_solve(gs->solver, prob->f_ext, guess, prob->u, &prob->solve)
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
  if (gs->coupled) /* u on every local DOF from the solve; the owned and the beam's rows */
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
