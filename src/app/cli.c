/* The `cupid` command line (model-format.md, "Command line"):
 *   cupid run MODEL.yaml [-o DIR] [--solver auto|direct|petsc] [--threads N]
 *                        [--max-memory GB] [--quiet]
 *   cupid check MODEL.yaml
 *   cupid --version | --help
 * Exit status: 0 success, 1 model error, 2 numerical failure, 3 I/O failure, 4 internal. */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cupid/app.h"
#include "cupid/io.h"
#include "cupid/model.h"

static const char usage_text[] =
    "usage: cupid run MODEL.yaml [-o DIR] [--solver auto|direct|petsc] [--threads N]\n"
    "                            [--max-memory GB] [--quiet]\n"
    "       cupid check MODEL.yaml\n"
    "       cupid --version | --help\n";

static const char help_text[] =
    "cupid couples 3D peridynamics with high-order 1D (CUF) beam finite elements.\n"
    "\n"
    "Commands:\n"
    "  run MODEL.yaml     read the model, solve it and write the outputs\n"
    "  check MODEL.yaml   validate the model, print counts and a memory estimate;\n"
    "                     solve nothing\n"
    "\n"
    "Options of run:\n"
    "  -o, --output DIR   write the outputs to DIR (overrides output.directory)\n"
    "  --solver NAME      auto (default), direct (SuiteSparse) or petsc\n"
    "  --threads N        number of OpenMP threads (default: OMP_NUM_THREADS or all cores)\n"
    "  --max-memory GB    refuse models whose estimated memory exceeds GB\n"
    "                     (default: 90% of the physical memory)\n"
    "  -q, --quiet        no progress messages on stderr\n"
    "\n"
    "Exit status: 0 success, 1 model error, 2 numerical failure (singular or\n"
    "unconstrained system), 3 I/O failure, 4 internal error or out of memory.\n"
    "The model file format is described in docs/model-format.md.\n";

/* Interrupted runs leave no half-written files: temporary outputs are removed. */
static void on_signal(int sig) {
  cupid_atomic_cleanup_all();
  signal(sig, SIG_DFL);
  raise(sig);
}

static int usage_error(const char *fmt, const char *arg) {
  fprintf(stderr, "cupid: ");
  fprintf(stderr, fmt, arg);
  fprintf(stderr, "\n%s", usage_text);
  return 1;
}

static int parse_solver(const char *s) {
  if (!strcmp(s, "auto")) return CUPID_SOLVER_AUTO;
  if (!strcmp(s, "direct")) return CUPID_SOLVER_DIRECT;
  if (!strcmp(s, "petsc")) return CUPID_SOLVER_PETSC;
  return -1;
}

static int parse_positive(const char *s, double *out) {
  char *end = NULL;
  double v = strtod(s, &end);
  if (!end || *end || end == s || !(v > 0) || v > 1e12) return 0;
  *out = v;
  return 1;
}

/* Parse the options that follow `run MODEL` / `check MODEL`. Returns 0 or an exit code. */
static int parse_options(int argc, char **argv, int first, cupid_run_options *opts,
                         const char **model_path) {
  for (int i = first; i < argc; i++) {
    const char *a = argv[i];
    int has_value = i + 1 < argc;
    if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
      if (!has_value) return usage_error("option %s needs a directory", a);
      opts->output_dir = argv[++i];
    } else if (!strcmp(a, "--solver")) {
      if (!has_value) return usage_error("option %s needs a value", a);
      opts->solver = parse_solver(argv[++i]);
      if (opts->solver < 0)
        return usage_error("--solver: unknown solver '%s' (allowed: auto, direct, petsc)", argv[i]);
    } else if (!strcmp(a, "--threads")) {
      double v;
      if (!has_value) return usage_error("option %s needs a value", a);
      if (!parse_positive(argv[++i], &v) || v != (int)v || v > 4096)
        return usage_error("--threads: expected a positive integer, got '%s'", argv[i]);
      opts->threads = (int)v;
    } else if (!strcmp(a, "--max-memory")) {
      if (!has_value) return usage_error("option %s needs a value in GB", a);
      if (!parse_positive(argv[++i], &opts->max_memory_gb))
        return usage_error("--max-memory: expected a positive number of GB, got '%s'", argv[i]);
    } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
      opts->quiet = 1;
    } else if (a[0] == '-' && a[1] != '\0') {
      return usage_error("unknown option '%s'", a);
    } else if (!*model_path) {
      *model_path = a;
    } else {
      return usage_error("unexpected argument '%s' (one model file per run)", a);
    }
  }
  if (!*model_path) return usage_error("%s", "missing the model file");
  return 0;
}

static int report_error(cupid_status st) {
  const char *msg = cupid_error_message();
  fprintf(stderr, "cupid: %s: %s\n", cupid_status_name(st), msg[0] ? msg : "(no message)");
  if (getenv("CUPID_DEBUG")) fprintf(stderr, "cupid: raised in %s\n", cupid_error_origin());
  return cupid_status_exit_code(st);
}

int cupid_cli_main(int argc, char **argv) {
  if (argc < 2) {
    fputs(usage_text, stderr);
    return 1;
  }
  const char *cmd = argv[1];
  if (!strcmp(cmd, "--version") || !strcmp(cmd, "-V") || !strcmp(cmd, "version")) {
    printf("cupid %s\n", cupid_version());
    return 0;
  }
  if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
    fputs(usage_text, stdout);
    fputs("\n", stdout);
    fputs(help_text, stdout);
    return 0;
  }
  int is_run = !strcmp(cmd, "run"), is_check = !strcmp(cmd, "check");
  if (!is_run && !is_check) return usage_error("unknown command '%s'", cmd);

  cupid_run_options opts = {.solver = -1};
  const char *path = NULL;
  int rc = parse_options(argc, argv, 2, &opts, &path);
  if (rc) return rc;
  opts.check_only = is_check;

  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);

  cupid_model model = NULL;
  cupid_status st = cupid_model_read(path, &model);
  if (st == CUPID_SUCCESS) st = cupid_run_model(model, &opts);
  cupid_model_destroy(&model);
  if (st != CUPID_SUCCESS) return report_error(st);
  return 0;
}
