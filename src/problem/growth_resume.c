/* Checkpoints of crack growth over load steps (issue 36; docs/hardening.md, "Checkpoints").
 *
 * A checkpoint is written after a load step's row, when one is due (resume.c): the solution,
 * the conditions with the held nodes, the envelope, the counts, and how the re-solves stand.
 * The re-solves after breaks use the factor of an earlier K, downdated by the bonds broken since
 * (growth.c): its bits are those of that history, not of a factorisation of the K now, and the
 * iterates that decide the next breaks depend on them. So the factor is not saved (hundreds of
 * MB) but its journal: the broken bonds and the fixed DOFs when it was factorised, and the words
 * of the broken-bond bits each downdate added. A resumption puts the operator back in that state,
 * factorises the same K with the same conditions, and downdates it round by round as the run did:
 * the same factor to the bit, then the current bonds and conditions. The matrix-free path builds
 * its kept solver on the intact grid, as the run did at its first solve, before the bonds are
 * restored. A non-symmetric coupling's LU (fictitious nodes, growth_lu.c) is journaled the same
 * way: its Sherman-Morrison-Woodbury columns are solves under the conditions of their round, so
 * the journal has the DOFs each round held too, and the balance's W and C are made on the
 * intact K first, as at the run's first solve. */
#include <stdio.h>
#include <string.h>

#include "growth_run.h"
#include "method.h"

/* ---- the journal ---- */

void growth_journal_free(growth_journal *j) {
  cupid_free(&j->bits);
  cupid_free(&j->now);
  cupid_free(&j->fresh);
  cupid_free(&j->fixed);
  cupid_free(&j->fixed_now);
  cupid_free(&j->pairs);
  cupid_free(&j->held);
  cupid_free(&j->ends);
  memset(j, 0, sizeof *j);
}

static int journaled(const growth_run *g) { return g->prob->ckpt.path && g->prob->op; }

/* The buffers of the journal (once). */
static cupid_status journal_alloc(growth_run *g) {
  const cupid_problem_state *prob = g->prob;
  growth_journal *j = &g->journal;
  if (j->bits) return CUPID_SUCCESS;
  j->words = (cupid_int)cupid_pd_operator_broken_words(prob->op) * prob->n_pd;
  CUPID_CALL(cupid_malloc((size_t)j->words + 1, sizeof *j->bits, "factor journal", &j->bits));
  CUPID_CALL(cupid_malloc((size_t)j->words + 1, sizeof *j->now, "factor journal", &j->now));
  CUPID_CALL(cupid_malloc((size_t)j->words + 1, sizeof *j->fresh, "factor journal", &j->fresh));
  CUPID_CALL(cupid_malloc((size_t)prob->ndof + 1, 1, "factor journal", &j->fixed));
  return cupid_malloc((size_t)prob->ndof + 1, 1, "factor journal", &j->fixed_now);
}

cupid_status growth_journal_factored(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  growth_journal *j = &g->journal;
  if (!journaled(g)) return CUPID_SUCCESS;
  CUPID_CALL(journal_alloc(g));
  cupid_pd_operator_pack_broken(prob->op, 0, prob->n_pd, j->bits);
  memcpy(j->now, j->bits, sizeof *j->now * (size_t)j->words);
  memcpy(j->fixed, prob->bc->fixed, (size_t)prob->ndof);
  for (cupid_int i = 0; g->tie && i < prob->n_pd; i++) /* K's springs, in the factor */
    for (int c = 0; c < 3 && g->tie[i]; c++) j->fixed[3 * i + c] |= 2;
  memcpy(j->fixed_now, j->fixed, (size_t)prob->ndof);
  j->n_pairs = j->n_held = j->n_rounds = 0;
  return CUPID_SUCCESS;
}

/* Room for @p more items of @p size in *a (capacity *cap, *n used). */
static cupid_status grow(void *a, cupid_int *cap, cupid_int n, cupid_int more, size_t size) {
  if (n + more <= *cap) return CUPID_SUCCESS;
  cupid_int c = *cap ? *cap : 256;
  while (c < n + more) c *= 2;
  CUPID_CALL(cupid_realloc((size_t)c, size, "factor journal", a));
  *cap = c;
  return CUPID_SUCCESS;
}

cupid_status growth_journal_downdated(growth_run *g) {
  const cupid_problem_state *prob = g->prob;
  growth_journal *j = &g->journal;
  if (!journaled(g) || !j->bits) return CUPID_SUCCESS;
  double *fresh = j->fresh; /* kept: a round is a downdate's milliseconds, not an allocation's */
  cupid_pd_operator_pack_broken(prob->op, 0, prob->n_pd, fresh);
  cupid_int changed = 0, held = 0;
  for (cupid_int k = 0; k < j->words; k++) changed += fresh[k] != j->now[k];
  for (cupid_int d = 0; d < prob->ndof; d++) held += prob->bc->fixed[d] && !(j->fixed_now[d] & 1);
  for (cupid_int i = 0; g->tie && i < prob->n_pd; i++) /* the factor's new ties (state 1) */
    held += 3 * (g->tie[i] == 1 && !(j->fixed_now[3 * i] & 2));
  cupid_status st = grow(&j->pairs, &j->cap_pairs, 2 * j->n_pairs, 2 * changed, sizeof *j->pairs);
  if (st == CUPID_SUCCESS) st = grow(&j->held, &j->cap_held, j->n_held, held, sizeof *j->held);
  if (st == CUPID_SUCCESS) st = grow(&j->ends, &j->cap_rounds, 2 * j->n_rounds, 2, sizeof *j->ends);
  if (st == CUPID_SUCCESS) {
    for (cupid_int k = 0; k < j->words; k++)
      if (fresh[k] != j->now[k]) {
        j->pairs[2 * j->n_pairs] = (double)k;
        j->pairs[2 * j->n_pairs + 1] = fresh[k];
        j->n_pairs++;
        j->now[k] = fresh[k];
      }
    for (cupid_int d = 0; d < prob->ndof; d++)
      if (prob->bc->fixed[d] && !(j->fixed_now[d] & 1)) j->held[j->n_held++] = d, j->fixed_now[d] |= 1;
    for (cupid_int d = 0; g->tie && d < 3 * prob->n_pd; d++)
      if (g->tie[d / 3] == 1 && !(j->fixed_now[d] & 2)) j->held[j->n_held++] = -1 - d, j->fixed_now[d] |= 2;
    j->ends[2 * j->n_rounds] = j->n_pairs;
    j->ends[2 * j->n_rounds + 1] = j->n_held;
    j->n_rounds++;
  }
  return st;
}

/* ---- what a checkpoint holds ---- */

/* The scalars of the run and of prob's growth block. */
typedef struct {
  cupid_int step, released, bonds_at_factor, cg_since_factor, downdates, downdate_columns;
  cupid_int factorisations, cg_solves, cg_iterations, solves, held_count, mf_iterations;
  double next_ratio, ratio_per_load, u0[3], factor_flops, cg_iteration_flops;
  double t_downdate, t_factor, t_cg, held_share, weak_share, force_scale;
  double first_break_load, held_reaction[3], mf_setup_s, mf_solve_s;
  int cut_through, downdate, has_factor, mf_limit, n_rounds, lu_no_update;
  cupid_int n_pairs, n_held, words;
  /* the LU of a non-symmetric coupling (growth_lu.c) */
  cupid_int lu_bonds_at_factor, lu_updates, lu_update_columns, lu_factorisations, lu_resolves;
  cupid_int lu_iterations, held_rows, tied, tied_singular, failed_factorisations;
  double tie_k, tie_share;
  double lu_factor_flops, lu_iteration_flops, lu_since_factor, lu_t_update, lu_t_factor;
  double lu_t_resolve;
  cupid_solve_info lu_factor_info;
  char solve_method[24], lu_method[24];
  int zone_frames;  /* adaptive.pvd's frames so far (an adaptive zone) */
  double last_load; /* the last row's load factor (the end's zone frame is at it) */
} growth_scalars;

/* The non-symmetric path (growth_lu.c), known before K is assembled (cupid_growth_lu_applies
 * asks for K too). */
static int lu_path(const cupid_problem_state *prob) {
  return prob->method->matrix == CUPID_MATRIX_GENERAL && !prob->engine->iterative;
}

/* The factor a resumption rebuilds: the LU's on the non-symmetric path, else the CHOLMOD one. */
static int has_factor(const growth_run *g) {
  return lu_path(g->prob) ? cupid_growth_lu_has_factor(&g->lu) : g->F != NULL;
}

/* A solve's method name (a string of this process) from its text in a checkpoint. */
static const char *method_named(const char *text, const char *otherwise) {
  static const char *const methods[] = {"cholmod", "umfpack", "petsc", "krylov", "gmres",
                                        "umfpack, updated", "umfpack + gmres", "cholmod + schur",
                                        "cholmod + schur, updated", "cholmod + schur + gmres"};
  for (size_t k = 0; k < sizeof methods / sizeof *methods; k++)
    if (!strcmp(text, methods[k])) return methods[k];
  return otherwise;
}

static void fill_scalars(const growth_run *g, int k, growth_scalars *c) {
  const cupid_problem_state *prob = g->prob;
  memset(c, 0, sizeof *c);
  *c = (growth_scalars){
      .step = k, .released = g->released, .bonds_at_factor = g->bonds_at_factor,
      .cg_since_factor = g->cg_since_factor, .downdates = g->downdates,
      .downdate_columns = g->downdate_columns, .held_rows = g->held_rows, .tied = g->tied,
      .tied_singular = g->tied_singular, .failed_factorisations = g->failed_factorisations,
      .tie_k = g->tie_k, .tie_share = g->tie_share,
      .factorisations = g->factorisations,
      .cg_solves = g->cg_solves, .cg_iterations = g->cg_iterations,
      .solves = prob->growth.solves, .held_count = prob->growth.held_count,
      .mf_iterations = g->mf.iterations, .next_ratio = g->next_ratio,
      .ratio_per_load = g->ratio_per_load, .u0 = {g->u0[0], g->u0[1], g->u0[2]},
      .factor_flops = g->factor_flops, .cg_iteration_flops = g->cg_iteration_flops,
      .t_downdate = g->t_downdate, .t_factor = g->t_factor, .t_cg = g->t_cg,
      .held_share = g->held_share, .weak_share = g->weak_share, .force_scale = g->force_scale,
      .first_break_load = prob->first_break_load,
      .held_reaction = {prob->growth.held_reaction[0], prob->growth.held_reaction[1],
                        prob->growth.held_reaction[2]},
      .mf_setup_s = g->mf.setup_s, .mf_solve_s = g->mf.solve_s,
      .cut_through = g->cut_through, .downdate = g->downdate, .has_factor = has_factor(g),
      .mf_limit = g->mf.limit, .n_rounds = (int)g->journal.n_rounds,
      .lu_no_update = g->lu.no_update, .n_pairs = g->journal.n_pairs,
      .n_held = g->journal.n_held, .words = g->journal.words,
      .lu_bonds_at_factor = g->lu.bonds_at_factor, .lu_updates = g->lu.updates,
      .lu_update_columns = g->lu.update_columns, .lu_factorisations = g->lu.factorisations,
      .lu_resolves = g->lu.resolves, .lu_iterations = g->lu.iterations,
      .lu_factor_flops = g->lu.factor_flops, .lu_iteration_flops = g->lu.iteration_flops,
      .lu_since_factor = g->lu.since_factor, .lu_t_update = g->lu.t_update,
      .lu_t_factor = g->lu.t_factor, .lu_t_resolve = g->lu.t_resolve,
      .lu_factor_info = g->lu.factor_info};
  c->zone_frames = g->zone_frames, c->last_load = g->last_load;
  if (prob->solve.method) snprintf(c->solve_method, sizeof c->solve_method, "%s", prob->solve.method);
  if (g->lu.factor_info.method)
    snprintf(c->lu_method, sizeof c->lu_method, "%s", g->lu.factor_info.method);
}

/* A load step's end, for cupid_problem_checkpoint_save. */
typedef struct {
  growth_run *g;
  int k;
} growth_point;

static cupid_status write_growth(void *ctx, cupid_checkpoint_writer w) {
  const growth_point *p = ctx;
  growth_run *g = p->g;
  const int k = p->k;
  cupid_problem_state *prob = g->prob;
  const size_t n = (size_t)prob->ndof, np = (size_t)prob->n_pd;
  const size_t nk = (size_t)prob->model->n_constraints;
  growth_scalars c;
  fill_scalars(g, k, &c);
  CUPID_CALL(cupid_writer_save(g->csv, w)); /* NULL writers (the ranks that write no files): nothing */
  CUPID_CALL(cupid_writer_save(g->exodus, w));
  CUPID_CALL(cupid_writer_save(g->zones, w));
  CUPID_CALL(cupid_problem_adaptive_save(prob, w)); /* the zone (nothing without one) */
  const cupid_int step = k;
  CUPID_CALL(cupid_checkpoint_write(w, "step", &step, sizeof step));
  CUPID_CALL(cupid_checkpoint_write(w, "growth", &c, sizeof c));
  CUPID_CALL(cupid_checkpoint_write(w, "solve", &prob->solve, sizeof prob->solve));
  CUPID_CALL(cupid_checkpoint_write(w, "quality", &prob->quality, sizeof prob->quality));
  CUPID_CALL(cupid_checkpoint_write(w, "u", prob->u, n * sizeof(double)));
  CUPID_CALL(cupid_checkpoint_write(w, "f_int", prob->f_int, n * sizeof(double)));
  CUPID_CALL(cupid_checkpoint_write(w, "fixed", prob->bc->fixed, n));
  CUPID_CALL(cupid_checkpoint_write(w, "values", prob->bc->value, n * sizeof(double)));
  CUPID_CALL(cupid_checkpoint_write(w, "reactions", g->react, 3 * nk * sizeof(double)));
  if (prob->growth.peak)
    CUPID_CALL(cupid_checkpoint_write(w, "peaks", prob->growth.peak, 6 * nk * sizeof(double)));
  if (g->release) {
    CUPID_CALL(cupid_checkpoint_write(w, "released", g->release, np));
    CUPID_CALL(cupid_checkpoint_write(w, "weak", g->weak, np));
  }
  if (g->tie) CUPID_CALL(cupid_checkpoint_write(w, "tied", g->tie, np));
  const growth_journal *j = &g->journal;
  if (c.has_factor) {
    CUPID_CHECK(j->bits, CUPID_ERR_INTERNAL, "growth: a factor without its journal");
    CUPID_CALL(cupid_checkpoint_write(w, "journal bits", j->bits, (size_t)j->words * sizeof(double)));
    CUPID_CALL(cupid_checkpoint_write(w, "journal fixed", j->fixed, n));
    if (j->n_pairs)
      CUPID_CALL(cupid_checkpoint_write(w, "journal pairs", j->pairs,
                                        2 * (size_t)j->n_pairs * sizeof(double)));
    if (j->n_held)
      CUPID_CALL(cupid_checkpoint_write(w, "journal held", j->held,
                                        (size_t)j->n_held * sizeof(cupid_int)));
    if (j->n_rounds)
      CUPID_CALL(cupid_checkpoint_write(w, "journal ends", j->ends,
                                        2 * (size_t)j->n_rounds * sizeof(cupid_int)));
  }
  return CUPID_SUCCESS;
}

cupid_status growth_safe_point(growth_run *g, int k) {
  const cupid_problem_state *prob = g->prob;
  growth_point p = {g, k};
  char where[96];
  snprintf(where, sizeof where, "after load step %d of %d", k,
           prob->model->analysis.steps > 0 ? prob->model->analysis.steps : 1);
  return cupid_problem_checkpoint_save(g->prob, k, write_growth, &p, where);
}

/* ---- the resumption ---- */

/* The operator's bonds as words (every node's) say: the bonds they mark broken (a method's copy
 * too). */
static cupid_status break_as(cupid_problem_state *prob, double *words) {
  cupid_int added = 0;
  double dissipated = 0.0;
  cupid_pd_fracture_options o = prob->fracture;
  o.ku = NULL;
  CUPID_CALL(cupid_pd_operator_unpack_broken(prob->op, 0, prob->n_pd, words, prob->u, &o, &added,
                                             &dissipated));
  if (prob->crack_copy)
    CUPID_CALL(cupid_pd_operator_copy_broken_mapped(prob->crack_copy, prob->op, prob->crack_map));
  return CUPID_SUCCESS;
}

/* The journal of the checkpoint into g->journal. */
static cupid_status read_journal(growth_run *g, const cupid_checkpoint ck, const growth_scalars *c) {
  growth_journal *j = &g->journal;
  const size_t n = (size_t)g->prob->ndof;
  CUPID_CALL(journal_alloc(g));
  CUPID_CHECK(c->words == j->words, CUPID_ERR_IO, "the checkpoint's journal is of another operator");
  CUPID_CALL(cupid_checkpoint_read(ck, "journal bits", j->bits, (size_t)j->words * sizeof(double)));
  CUPID_CALL(cupid_checkpoint_read(ck, "journal fixed", j->fixed, n));
  CUPID_CALL(grow(&j->pairs, &j->cap_pairs, 0, 2 * c->n_pairs, sizeof *j->pairs));
  CUPID_CALL(grow(&j->held, &j->cap_held, 0, c->n_held, sizeof *j->held));
  CUPID_CALL(grow(&j->ends, &j->cap_rounds, 0, 2 * (cupid_int)c->n_rounds, sizeof *j->ends));
  if (c->n_pairs)
    CUPID_CALL(cupid_checkpoint_read(ck, "journal pairs", j->pairs,
                                     2 * (size_t)c->n_pairs * sizeof(double)));
  if (c->n_held)
    CUPID_CALL(cupid_checkpoint_read(ck, "journal held", j->held,
                                     (size_t)c->n_held * sizeof(cupid_int)));
  if (c->n_rounds)
    CUPID_CALL(cupid_checkpoint_read(ck, "journal ends", j->ends,
                                     2 * (size_t)c->n_rounds * sizeof(cupid_int)));
  j->n_pairs = c->n_pairs;
  j->n_held = c->n_held;
  j->n_rounds = c->n_rounds;
  memcpy(j->now, j->bits, sizeof *j->now * (size_t)j->words);
  memcpy(j->fixed_now, j->fixed, n);
  return CUPID_SUCCESS;
}

/* The conditions of the replay: the journal's fixed DOFs (the factor's free DOFs are what
 * counts; the values are not read). */
static cupid_status replay_conditions(const growth_run *g, cupid_dirichlet *bc) {
  const growth_journal *j = &g->journal;
  CUPID_CALL(cupid_dirichlet_create(g->prob->ndof, bc));
  for (cupid_int d = 0; d < g->prob->ndof; d++)
    if (j->fixed_now[d] & 1) CUPID_CALL(cupid_dirichlet_fix(*bc, d, 0.0));
  return cupid_dirichlet_finalize(*bc);
}

/* Round r of the journal into j->now and j->fixed_now. */
static void replay_round(growth_journal *j, cupid_int r) {
  for (cupid_int at = r ? j->ends[2 * r - 2] : 0; at < j->ends[2 * r]; at++)
    j->now[(cupid_int)j->pairs[2 * at]] = j->pairs[2 * at + 1];
  for (cupid_int at = r ? j->ends[2 * r - 1] : 0; at < j->ends[2 * r + 1]; at++) {
    const cupid_int d = j->held[at];
    if (d >= 0) j->fixed_now[d] |= 1;
    else j->fixed_now[-1 - d] |= 2 | 4; /* tied in this round */
  }
}

/* The DOFs whose journal flags have @p bit: their springs (growth.c, tie_mechanisms) into K,
 * and into F too where F is not NULL. */
static cupid_status replay_ties(growth_run *g, unsigned char bit, cupid_csr_t *K, cupid_direct_factor F) {
  const growth_journal *j = &g->journal;
  cupid_int n = 0, *dofs = NULL;
  for (cupid_int d = 0; d < g->prob->ndof; d++) n += (j->fixed_now[d] & bit) != 0;
  if (n == 0) return CUPID_SUCCESS;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *dofs, "tied DOFs", &dofs));
  n = 0;
  for (cupid_int d = 0; d < g->prob->ndof; d++)
    if (j->fixed_now[d] & bit) dofs[n++] = d;
  if (K) CUPID_TRY(growth_tie_matrix(K, n, dofs, g->tie_k));
  if (F) CUPID_TRY(growth_tie_factor(F, n, dofs, g->tie_k));
cleanup:
  cupid_free(&dofs);
  return st;
}

/* The factor as the run had it: the K of the journal's bonds factorised under its fixed DOFs,
 * then downdated (CHOLMOD) or updated (the LU's SMW) round by round under each round's
 * conditions, by growth.c's and growth_lu.c's own calls (their solves and counts left out:
 * the checkpoint holds those). */
static cupid_status replay_factor(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  growth_journal *j = &g->journal;
  const int lu = lu_path(prob);
  cupid_dirichlet bc = NULL, saved = prob->bc;
  cupid_csr Kold = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(break_as(prob, j->now));
  CUPID_TRY(replay_conditions(g, &bc));
  prob->bc = bc;
  cupid_csr_destroy(&prob->K);
  CUPID_TRY(prob->method->assemble(prob));
  CUPID_TRY(replay_ties(g, 2, prob->K, NULL));
  if (lu) {
    CUPID_TRY(cupid_growth_lu_factorise(prob, &g->lu));
  } else {
    cupid_solve_info info;
    memset(&info, 0, sizeof info);
    CUPID_TRY(cupid_direct_factor_create(prob->K, bc, &g->F, &info));
  }
  for (cupid_int r = 0; r < j->n_rounds; r++) {
    replay_round(j, r);
    prob->bc = saved;
    cupid_dirichlet_destroy(&bc);
    CUPID_TRY(replay_conditions(g, &bc));
    prob->bc = bc;
    Kold = prob->K, prob->K = NULL;
    CUPID_TRY(break_as(prob, j->now));
    CUPID_TRY(prob->method->assemble(prob));
    CUPID_TRY(replay_ties(g, 2, prob->K, NULL)); /* every tie so far, this round's too */
    const cupid_int updates = g->lu.updates;
    int ok = 1;
    if (lu) {
      CUPID_TRY(cupid_growth_lu_update(prob, &g->lu, Kold));
      ok = g->lu.updates == updates + 1 && cupid_growth_lu_has_factor(&g->lu);
    } else {
      /* as growth.c's downdate_factor: the round's new ties into Kold; the held nodes, the
       * ties, the bonds */
      CUPID_TRY(replay_ties(g, 4, Kold, NULL));
      CUPID_TRY(cupid_growth_downdate_terms(Kold, prob->K, &g->dd, &ok));
      cupid_int held = 0;
      if (ok) CUPID_TRY(cupid_direct_factor_hold(g->F, bc, &held));
      if (ok) CUPID_TRY(replay_ties(g, 4, NULL, g->F));
      if (ok)
        CUPID_TRY(cupid_direct_factor_downdate(g->F, g->dd.r, g->dd.colptr, g->dd.rows, g->dd.vals));
    }
    CUPID_TRY_CHECK(ok, CUPID_ERR_INTERNAL, "resume: round %lld of the factor's journal did not "
                    "replay as it ran", (long long)r);
    for (cupid_int d = 0; d < prob->ndof; d++) j->fixed_now[d] &= (unsigned char)~4u;
    cupid_csr_destroy(&Kold);
  }
cleanup:
  prob->bc = saved;
  cupid_csr_destroy(&Kold);
  cupid_dirichlet_destroy(&bc);
  return st;
}

/* The run's arrays and counts from the checkpoint. */
static cupid_status read_growth(growth_run *g, const cupid_checkpoint ck, const growth_scalars *c) {
  cupid_problem_state *prob = g->prob;
  const size_t n = (size_t)prob->ndof, np = (size_t)prob->n_pd;
  const size_t nk = (size_t)prob->model->n_constraints;
  const char *patch_skipped = prob->quality.patch_skipped; /* this process's pointers */
  const char *method = prob->solve.method;
  CUPID_CALL(cupid_checkpoint_read(ck, "solve", &prob->solve, sizeof prob->solve));
  CUPID_CALL(cupid_checkpoint_read(ck, "quality", &prob->quality, sizeof prob->quality));
  prob->quality.patch_skipped = patch_skipped;
  prob->solve.method = method_named(c->solve_method, method);
  CUPID_CALL(cupid_checkpoint_read(ck, "u", prob->u, n * sizeof(double)));
  CUPID_CALL(cupid_checkpoint_read(ck, "f_int", prob->f_int, n * sizeof(double)));
  unsigned char *fixed = NULL;
  CUPID_CALL(cupid_malloc(n + 1, 1, "fixed DOFs", &fixed));
  cupid_status st = cupid_checkpoint_read(ck, "fixed", fixed, n);
  if (st == CUPID_SUCCESS)
    st = cupid_checkpoint_read(ck, "values", prob->bc->value, n * sizeof(double));
  for (size_t d = 0; d < n && st == CUPID_SUCCESS; d++)
    if (fixed[d] && !prob->bc->fixed[d]) st = cupid_dirichlet_fix(prob->bc, (cupid_int)d, prob->bc->value[d]);
  cupid_free(&fixed);
  CUPID_CALL(st);
  CUPID_CALL(cupid_dirichlet_finalize(prob->bc));
  CUPID_CALL(cupid_checkpoint_read(ck, "reactions", g->react, 3 * nk * sizeof(double)));
  if (prob->growth.peak)
    CUPID_CALL(cupid_checkpoint_read(ck, "peaks", prob->growth.peak, 6 * nk * sizeof(double)));
  if (g->release) {
    CUPID_CALL(cupid_checkpoint_read(ck, "released", g->release, np));
    CUPID_CALL(cupid_checkpoint_read(ck, "weak", g->weak, np));
  }
  if (g->tie) CUPID_CALL(cupid_checkpoint_read(ck, "tied", g->tie, np));
  g->released = c->released, g->bonds_at_factor = c->bonds_at_factor;
  g->cg_since_factor = c->cg_since_factor, g->downdates = c->downdates;
  g->downdate_columns = c->downdate_columns, g->factorisations = c->factorisations;
  g->held_rows = c->held_rows, g->tied = c->tied, g->tie_share = c->tie_share;
  g->tied_singular = c->tied_singular, g->failed_factorisations = c->failed_factorisations;
  g->cg_solves = c->cg_solves, g->cg_iterations = c->cg_iterations;
  prob->growth.solves = c->solves, prob->growth.held_count = c->held_count;
  g->mf.iterations = c->mf_iterations, g->next_ratio = c->next_ratio;
  g->ratio_per_load = c->ratio_per_load;
  for (int a = 0; a < 3; a++) g->u0[a] = c->u0[a], prob->growth.held_reaction[a] = c->held_reaction[a];
  g->factor_flops = c->factor_flops, g->cg_iteration_flops = c->cg_iteration_flops;
  g->t_downdate = c->t_downdate, g->t_factor = c->t_factor, g->t_cg = c->t_cg;
  g->held_share = c->held_share, g->weak_share = c->weak_share, g->force_scale = c->force_scale;
  prob->first_break_load = c->first_break_load;
  g->mf.setup_s = c->mf_setup_s, g->mf.solve_s = c->mf_solve_s;
  g->cut_through = c->cut_through, g->downdate = c->downdate;
  cupid_growth_lu *lu = &g->lu; /* the non-symmetric path's (growth_lu.c) */
  lu->bonds_at_factor = c->lu_bonds_at_factor, lu->updates = c->lu_updates;
  lu->update_columns = c->lu_update_columns, lu->factorisations = c->lu_factorisations;
  lu->resolves = c->lu_resolves, lu->iterations = c->lu_iterations;
  lu->factor_flops = c->lu_factor_flops, lu->iteration_flops = c->lu_iteration_flops;
  lu->since_factor = c->lu_since_factor, lu->t_update = c->lu_t_update;
  lu->t_factor = c->lu_t_factor, lu->t_resolve = c->lu_t_resolve;
  lu->no_update = c->lu_no_update;
  lu->factor_info = c->lu_factor_info;
  lu->factor_info.method = method_named(c->lu_method, NULL);
  lu->patch_tested = 1; /* the first K's, whose report the checkpoint's quality holds */
  g->zone_frames = c->zone_frames, g->last_load = c->last_load;
  return CUPID_SUCCESS;
}

cupid_status growth_resume(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  cupid_checkpoint ck = NULL;
  growth_scalars c;
  cupid_status st = CUPID_SUCCESS;
  /* what the run's first solve made on the intact grid: the matrix-free path's kept solver,
   * the balance's W and C of the LU path (its work vectors too) */
  if (g->matrix_free) CUPID_CALL(cupid_growth_mf_prepare(prob, &g->mf));
  if (lu_path(prob)) {
    CUPID_CALL(prob->method->assemble(prob));
    CUPID_CALL(cupid_growth_lu_prepare(prob, &g->lu));
  }
  CUPID_CALL(cupid_problem_checkpoint_open(prob, "step", &ck)); /* restores no bonds yet ... */
  CUPID_TRY(cupid_checkpoint_read(ck, "growth", &c, sizeof c));
  g->tie_k = c.tie_k; /* the replay's springs */
  if (c.has_factor) {
    CUPID_TRY(read_journal(g, ck, &c));
    CUPID_TRY(replay_factor(g));
  }
  CUPID_TRY(cupid_problem_checkpoint_fracture(prob, ck)); /* ... the bonds now */
  CUPID_TRY(read_growth(g, ck, &c));
  if (g->matrix_free && c.mf_limit > 0) CUPID_TRY(cupid_growth_mf_set_limit(&g->mf, c.mf_limit));
  g->first_step = (int)c.step + 1;
  cupid_problem_progress(prob, "resume: after load step %d of %d, %lld broken bonds, %lld nodes "
                         "held%s", (int)c.step, prob->model->analysis.steps,
                         (long long)prob->broken_bonds, (long long)g->released,
                         c.has_factor ? ", the factor rebuilt from its journal" : "");
  g->resume = ck, ck = NULL; /* the writers read theirs (growth.c, open_writers) */
cleanup:
  cupid_checkpoint_close(&ck);
  return st;
}
