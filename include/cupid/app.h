/**
 * @file app.h
 * @brief The application layer: the `cupid` command line and the run pipeline that turns a
 *        model into results (grid, assembly, coupling, factorisation, solve, output).
 */
#ifndef CUPID_APP_H
#define CUPID_APP_H

#include "cupid/base.h"
#include "cupid/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Options of `cupid run` beyond the model file. */
typedef struct {
  const char *output_dir;   /**< -o DIR, overrides output.directory (NULL: keep) */
  int solver;               /**< -1 keep the model's; else a cupid_solver_kind */
  int threads;              /**< --threads N (0 = default) */
  double max_memory_gb;     /**< --max-memory (0 = default limit) */
  int quiet;                /**< --quiet */
  int check_only;           /**< `cupid check`: validate, count, estimate; solve nothing */
} cupid_run_options;

/** Run a model as `cupid run` does. Messages go to stderr unless quiet. */
cupid_status cupid_run_model(const cupid_model_t *model, const cupid_run_options *opts);

/** The command-line tool (returns the exit status). */
int cupid_cli_main(int argc, char **argv);

#ifdef __cplusplus
}
#endif
#endif
