/* Checkpoints and the resumption of long runs (issue 36; docs/hardening.md, "Checkpoints").
 *
 * A resumable run (dynamics, crack growth) stages its files in a folder of fixed name beside the output
 * folder (io.h, cupid_output_set_begin_resumable) and keeps its checkpoints there: one file per
 * rank (.checkpoint, .checkpoint-rank-R), written by src/io/checkpoint.c (temporary file, CRC,
 * fsync, rename; the one before kept as .prev). The stage writes its own state; this file
 * holds what every resumable run shares: when a checkpoint is due (the period, or a signal
 * through cupid_interrupt_request), the run's identity (the model text, the overrides, the
 * result-changing options, the ranks), and the fracture state and history rows of prob. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "problem_internal.h"

/* The default period: a run estimated over 10 minutes is checkpointed every 10 minutes. */
#define CHECKPOINT_AUTO_OVER_S 600.0
#define CHECKPOINT_AUTO_PERIOD_S 600.0

/* The identity: what the results depend on, one fact per line, so that a refused resumption
 * can name the line that differs. --threads is not in it: results do not depend on it. */
static cupid_status identity(const cupid_problem_state *prob, char *buf, size_t len) {
  const cupid_model_t *m = prob->model;
  size_t at = 0;
#define ADD(...)                                                                            \
  do {                                                                                      \
    int k_ = snprintf(buf + at, len - at, __VA_ARGS__);                                     \
    CUPID_CHECK(k_ >= 0 && (size_t)k_ < len - at, CUPID_ERR_ARGUMENT,                       \
                "checkpoint identity: too long (the overrides?)");                          \
    at += (size_t)k_;                                                                       \
  } while (0)
  ADD("cupid %s\n", cupid_version());
  /* the text, not the path: the same file reached from another folder is the same model */
  ADD("model text: %llu bytes, CRC-32 %08x\n", (unsigned long long)m->source_bytes,
      (unsigned)m->source_crc);
  for (int k = 0; k < m->n_sets; k++) /* the checkpoints' period changes no result */
    if (strncmp(m->sets[k], "output.checkpoint=", 18)) ADD("--set %s\n", m->sets[k]);
  ADD("processes %d, this one %d\n", cupid_petsc_size(), cupid_petsc_rank());
  ADD("solver %s%s%s\n", prob->engine ? prob->engine->name : "auto",
      prob->opts->assembled ? ", --assembled" : "", prob->opts->replicate ? ", --replicate" : "");
#undef ADD
  return CUPID_SUCCESS;
}

int cupid_problem_growth_resumable(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  return m->has_peridynamics && m->pd.fracture.has_fracture;
}

double cupid_problem_checkpoint_period(const cupid_problem_state *prob, double estimated_seconds) {
  const double given = prob->model->output.checkpoint;
  return given >= 0 ? given
         : estimated_seconds > CHECKPOINT_AUTO_OVER_S ? CHECKPOINT_AUTO_PERIOD_S
                                                      : 0.0;
}

/* This rank's checkpoint file in the resumable staging folder (*path allocated). */
static cupid_status checkpoint_path(const cupid_problem_state *prob, char **path) {
  char *dir = NULL;
  CUPID_CALL(cupid_output_set_partial_dir(prob->outdir, &dir));
  const size_t n = strlen(dir) + 40;
  cupid_status st = cupid_malloc(n, 1, "checkpoint path", path);
  if (st == CUPID_SUCCESS) {
    const int rank = cupid_petsc_rank();
    if (rank == 0) snprintf(*path, n, "%s/.checkpoint", dir);
    else snprintf(*path, n, "%s/.checkpoint-rank-%d", dir, rank);
  }
  cupid_free(&dir);
  return st;
}

/* The checkpoint at path, if it is this run's (another run's: a model error naming the model
 * file this run read). */
static cupid_status open_identified(const cupid_problem_state *prob, const char *path,
                                    int previous, cupid_checkpoint *ck) {
  char id[8192];
  CUPID_CALL(identity(prob, id, sizeof id));
  cupid_status st = previous ? cupid_checkpoint_open_previous(path, id, ck)
                             : cupid_checkpoint_open(path, id, ck);
  if (st == CUPID_ERR_MODEL) {
    char why[2048];
    snprintf(why, sizeof why, "%s", cupid_error_message());
    st = CUPID_ERROR(CUPID_ERR_MODEL, "%s: --resume: %s", prob->model->file, why);
  }
  return st;
}

cupid_status cupid_problem_checkpoint_begin(cupid_problem_state *prob, double estimated_seconds) {
  prob->ckpt.period = cupid_problem_checkpoint_period(prob, estimated_seconds);
  prob->ckpt.last = cupid_wtime();
  CUPID_CALL(checkpoint_path(prob, &prob->ckpt.path));
  cupid_interrupt_arm(1);
  prob->ckpt.armed = 1;
  if (prob->ckpt.period > 0)
    cupid_problem_progress(prob, "checkpoints: every %g s (output.checkpoint), and on SIGINT or "
                           "SIGTERM", prob->ckpt.period);
  return CUPID_SUCCESS;
}

void cupid_problem_checkpoint_end(cupid_problem_state *prob) {
  if (prob->ckpt.armed) cupid_interrupt_arm(0);
  prob->ckpt.armed = 0;
  cupid_free(&prob->ckpt.path);
}

/* Whether to write a checkpoint now (collective on several ranks: every rank agrees): 0 no, 1
 * the period is up, 2 a signal asked for one (the run then stops after it). */
static int checkpoint_due(cupid_problem_state *prob) {
  if (!prob->ckpt.path) return 0;
  int due = cupid_interrupt_pending() ? 2
            : prob->ckpt.period > 0 && cupid_wtime() - prob->ckpt.last >= prob->ckpt.period ? 1
                                                                                          : 0;
  if (cupid_petsc_size() > 1) due = cupid_petsc_max_int(due); /* one rank's signal stops all */
  return due;
}

/* A writer on this rank's file, its identity written. */
static cupid_status checkpoint_start(cupid_problem_state *prob, cupid_checkpoint_writer *w) {
  char id[8192];
  CUPID_CALL(identity(prob, id, sizeof id));
  return cupid_checkpoint_write_begin(prob->ckpt.path, id, w);
}

/* The scalars of the fracture state and of the run's clock. */
typedef struct {
  cupid_int broken_bonds, first_break_step, damaged_nodes, history_rows, history_cols;
  double first_break_t, fracture_energy, first_break_at[3], max_damage, time;
} common_scalars;

/* The sections every resumable run has: the fracture state (the operator's broken bonds, the
 * counts, the first break, damage) and the history rows. */
static cupid_status checkpoint_common(cupid_problem_state *prob, cupid_checkpoint_writer w) {
  const common_scalars c = {.broken_bonds = prob->broken_bonds,
                            .first_break_step = prob->first_break_step,
                            .damaged_nodes = prob->damaged_nodes,
                            .history_rows = prob->history_rows,
                            .history_cols = prob->history_cols,
                            .first_break_t = prob->first_break_t,
                            .fracture_energy = prob->fracture_energy,
                            .first_break_at = {prob->first_break_at[0], prob->first_break_at[1],
                                               prob->first_break_at[2]},
                            .max_damage = prob->max_damage,
                            .time = prob->time};
  CUPID_CALL(cupid_checkpoint_write(w, "problem", &c, sizeof c));
  if (prob->history_rows)
    CUPID_CALL(cupid_checkpoint_write(w, "history", prob->history,
                                      sizeof(double) * (size_t)prob->history_rows *
                                          (size_t)prob->history_cols));
  if (!prob->op || !prob->damage) return CUPID_SUCCESS;
  CUPID_CALL(cupid_checkpoint_write(w, "damage", prob->damage, sizeof(double) * (size_t)prob->n_pd));
  const size_t words = (size_t)cupid_pd_operator_broken_words(prob->op) * (size_t)prob->n_pd;
  double *bits = NULL;
  CUPID_CALL(cupid_malloc(words + 1, sizeof *bits, "broken-bond bits", &bits));
  cupid_pd_operator_pack_broken(prob->op, 0, prob->n_pd, bits);
  cupid_status st = cupid_checkpoint_write(w, "broken bonds", bits, sizeof *bits * words);
  cupid_free(&bits);
  return st;
}

/* Commit @p w when @p filled (the status of writing its sections) is a success, else drop it
 * (collective on several ranks: every rank's or none). A failure (a full disk) is a warning:
 * the previous checkpoint stays and the run goes on. */
static void checkpoint_commit(cupid_problem_state *prob, cupid_checkpoint_writer *w,
                              cupid_status filled, cupid_int step) {
  cupid_status st = filled;
  if (st == CUPID_SUCCESS) st = cupid_checkpoint_write_commit(w);
  cupid_checkpoint_write_abort(w); /* NULL after a commit */
  int failed = st != CUPID_SUCCESS;
  if (cupid_petsc_size() > 1) failed = cupid_petsc_max_int(failed); /* all ranks' or none */
  prob->ckpt.last = cupid_wtime();
  if (!failed) {
    prob->ckpt.written++;
    return;
  }
  /* The previous checkpoint is intact (checkpoint.c): a periodic one's failure costs the run
   * nothing but the protection it gave; after a signal the run stops all the same. */
  if (!prob->quiet)
    fprintf(stderr, "cupid: warning: the checkpoint of step %lld could not be written (%s); the "
            "previous one stays\n", (long long)step,
            st != CUPID_SUCCESS ? cupid_error_message() : "on another rank");
  cupid_error_clear();
}

/* The fracture state of the checkpoint: the broken bonds into the operator (and a method's copy
 * of it), the damage and the counts. */
static cupid_status restore_fracture(cupid_problem_state *prob, const cupid_checkpoint ck) {
  if (!prob->op || !prob->damage) return CUPID_SUCCESS;
  CUPID_CALL(cupid_checkpoint_read(ck, "damage", prob->damage, sizeof(double) * (size_t)prob->n_pd));
  const size_t words = (size_t)cupid_pd_operator_broken_words(prob->op) * (size_t)prob->n_pd;
  const void *bits = NULL;
  size_t bytes = 0;
  CUPID_CALL(cupid_checkpoint_section(ck, "broken bonds", &bits, &bytes));
  CUPID_CHECK(bytes == words * sizeof(double), CUPID_ERR_IO,
              "the checkpoint's broken bonds are not of this model's operator");
  cupid_int added = 0;
  double dissipated = 0.0;
  double *copy = NULL; /* the section may not be aligned for doubles */
  CUPID_CALL(cupid_malloc(words + 1, sizeof *copy, "broken-bond bits", &copy));
  memcpy(copy, bits, bytes);
  cupid_pd_fracture_options o = prob->fracture;
  o.ku = NULL;
  cupid_status st = cupid_pd_operator_unpack_broken(prob->op, 0, prob->n_pd, copy, prob->u, &o,
                                                    &added, &dissipated);
  cupid_free(&copy);
  CUPID_CALL(st);
  if (prob->crack_copy)
    CUPID_CALL(cupid_pd_operator_copy_broken_mapped(prob->crack_copy, prob->op, prob->crack_map));
  return CUPID_SUCCESS;
}

static cupid_status restore_common(cupid_problem_state *prob, const cupid_checkpoint ck) {
  common_scalars c;
  CUPID_CALL(cupid_checkpoint_read(ck, "problem", &c, sizeof c));
  prob->broken_bonds = c.broken_bonds;
  prob->first_break_step = c.first_break_step;
  prob->damaged_nodes = c.damaged_nodes;
  prob->first_break_t = c.first_break_t;
  prob->fracture_energy = c.fracture_energy;
  for (int a = 0; a < 3; a++) prob->first_break_at[a] = c.first_break_at[a];
  prob->max_damage = c.max_damage;
  prob->time = c.time;
  cupid_free(&prob->history);
  prob->history_rows = prob->history_cap = 0;
  if (c.history_rows > 0) {
    const size_t n = (size_t)c.history_rows * (size_t)c.history_cols;
    CUPID_CALL(cupid_malloc(n, sizeof *prob->history, "history", &prob->history));
    CUPID_CALL(cupid_checkpoint_read(ck, "history", prob->history, n * sizeof *prob->history));
    prob->history_rows = prob->history_cap = c.history_rows;
    prob->history_cols = (int)c.history_cols;
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_checkpoint_fracture(cupid_problem_state *prob, const cupid_checkpoint ck) {
  return restore_fracture(prob, ck);
}

/* The ranks' agreement on the step to resume from (a collective of every rank, whatever its
 * own status): the largest failure's exit code, the lowest and highest step. */
static void ranks_agree(cupid_status st, cupid_int step, int *worst, int *lo, int *hi) {
  *worst = cupid_petsc_max_int(st == CUPID_SUCCESS ? 0 : cupid_status_exit_code(st));
  *lo = -cupid_petsc_max_int(-(int)step);
  *hi = cupid_petsc_max_int((int)step);
}

/* This rank's checkpoint at path (its "step" section in *step), the one every rank resumes
 * from. The ranks commit their checkpoints each in its own time, so a SIGKILL between two
 * commits leaves some ranks a checkpoint ahead; those go back to the one their latest replaced
 * (PATH.prev), which is of the others' step. Collective under mpirun. */
static cupid_status open_agreed(cupid_problem_state *prob, const char *path,
                                const char *step_section, int say, cupid_checkpoint *ck) {
  *ck = NULL;
  cupid_int step = -1;
  cupid_status st = open_identified(prob, path, 0, ck);
  if (st == CUPID_SUCCESS && say && cupid_checkpoint_is_previous(*ck))
    cupid_problem_progress(prob, "resume: '%s' was damaged or missing; its previous one is used",
                           path);
  if (st == CUPID_SUCCESS) st = cupid_checkpoint_read(*ck, step_section, &step, sizeof step);
  int worst = 0, lo = 0, hi = 0;
  if (cupid_petsc_size() == 1) goto done;
  ranks_agree(st, step, &worst, &lo, &hi);
  if (!worst && lo != hi) {
    if (step > lo) {
      cupid_checkpoint_close(ck);
      step = -1;
      st = open_identified(prob, path, 1, ck);
      if (st == CUPID_SUCCESS) st = cupid_checkpoint_read(*ck, step_section, &step, sizeof step);
      if (st == CUPID_SUCCESS && step != lo)
        st = CUPID_ERROR(CUPID_ERR_IO, "the ranks' checkpoints are of different steps (%d to %d) "
                         "and this rank's previous one is of step %lld: run again without "
                         "--resume", lo, hi, (long long)step);
    }
    const int was_hi = hi;
    ranks_agree(st, step, &worst, &lo, &hi);
    if (!worst && lo == hi && say)
      cupid_problem_progress(prob, "resume: the ranks' latest checkpoints are of steps %d to %d "
                             "(a rank stopped between their commits): those ahead go back to "
                             "their previous one, step %d", lo, was_hi, lo);
  }
  if (st == CUPID_SUCCESS && worst)
    st = CUPID_ERROR(worst == 1 ? CUPID_ERR_MODEL : CUPID_ERR_IO,
                     "another rank cannot resume from its checkpoint");
  if (st == CUPID_SUCCESS && lo != hi)
    st = CUPID_ERROR(CUPID_ERR_IO, "the ranks' checkpoints are of different steps (%d to %d): "
                     "run again without --resume", lo, hi);
done:
  if (st != CUPID_SUCCESS) cupid_checkpoint_close(ck);
  return st;
}

cupid_status cupid_problem_checkpoint_peek(cupid_problem_state *prob, const char *section,
                                           void **data, size_t *bytes) {
  char *path = NULL;
  cupid_checkpoint ck = NULL;
  const void *at = NULL;
  *data = NULL, *bytes = 0;
  cupid_status st = checkpoint_path(prob, &path);
  if (st == CUPID_SUCCESS) st = open_agreed(prob, path, "step", 0, &ck);
  if (st == CUPID_SUCCESS) st = cupid_checkpoint_section(ck, section, &at, bytes);
  if (st == CUPID_SUCCESS) st = cupid_malloc(*bytes + 1, 1, "a checkpoint's section", data);
  if (st == CUPID_SUCCESS) memcpy(*data, at, *bytes);
  cupid_checkpoint_close(&ck);
  cupid_free(&path);
  return st;
}

cupid_status cupid_problem_checkpoint_open(cupid_problem_state *prob, const char *step_section,
                                           cupid_checkpoint *ck) {
  cupid_status st = open_agreed(prob, prob->ckpt.path, step_section, 1, ck);
  if (st == CUPID_SUCCESS) st = restore_common(prob, *ck);
  if (st != CUPID_SUCCESS) cupid_checkpoint_close(ck);
  return st;
}

cupid_status cupid_problem_checkpoint_save(cupid_problem_state *prob, cupid_int step,
                                           cupid_status (*fill)(void *ctx, cupid_checkpoint_writer w),
                                           void *ctx, const char *where) {
  /* the tests' deterministic signal: CUPID_TEST_INTERRUPT_STEP=N acts as a SIGTERM that came
   * during step N (or before: the first safe point from N on stops) */
  const char *test_step = getenv("CUPID_TEST_INTERRUPT_STEP");
  if (test_step && step >= strtoll(test_step, NULL, 10)) (void)cupid_interrupt_request();
  const int due = checkpoint_due(prob);
  if (!due) return CUPID_SUCCESS;
  const double t0 = cupid_wtime();
  cupid_checkpoint_writer w = NULL;
  cupid_status st = checkpoint_start(prob, &w);
  if (st == CUPID_SUCCESS) st = fill(ctx, w);
  if (st == CUPID_SUCCESS) st = checkpoint_common(prob, w);
  checkpoint_commit(prob, &w, st, step);
  prob->ckpt.seconds += cupid_wtime() - t0;
  if (due < 2) return CUPID_SUCCESS;
  prob->ckpt.interrupted = 1;
  return CUPID_ERROR(CUPID_ERR_INTERRUPTED, "interrupted %s: continue with `cupid run %s "
                     "--resume` (the same options)", where, prob->model->file);
}
