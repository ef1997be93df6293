/* The `cupid` command line (model-format.md, "Command line"): parse, then create, set up,
 * solve and write the problem (include/cupid/problem.h), and turn the status into the exit code.
 *   cupid run MODEL.yaml [-o DIR] [--solver auto|direct|krylov|petsc] [--threads N]
 *                        [--max-memory GB] [--quiet] [--replicate] [--assembled]
 *                        [--resume] [-PETSC_OPTION [VALUE]]...
 *   mpirun -n N cupid run MODEL.yaml --solver petsc [...]   (every rank runs, rank 0 writes)
 *   cupid check MODEL.yaml
 *   cupid --version | --help
 * Exit status: 0 success, 1 model error, 2 numerical failure, 3 I/O failure, 4 internal,
 * 5 interrupted after a checkpoint (resume with --resume). */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cupid/app.h"
#include "cupid/io.h"
#include "cupid/problem.h"
#include "cupid/solvers.h"

static const char usage_text[] =
    "usage: cupid run MODEL.yaml [-o DIR] [--solver auto|direct|krylov|petsc] [--threads N]\n"
    "                            [--max-memory GB] [--quiet] [--replicate] [--assembled]\n"
    "                            [--allow-large] [--set key.path=value]... [--resume]\n"
    "                            [-petsc_option [value]]...\n"
    "       mpirun -n N cupid run MODEL.yaml --solver petsc [...]\n"
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
    "  --solver NAME      auto (default: the engine of the smallest estimated time\n"
    "                     that fits), direct (SuiteSparse), krylov (matrix-free\n"
    "                     CG/GMRES + a SuiteSparse-factored twin) or petsc (MPI)\n"
    "  --threads N        number of OpenMP threads (default: OMP_NUM_THREADS or all cores)\n"
    "  --max-memory GB    refuse models whose estimated memory exceeds GB\n"
    "                     (default: 90% of the physical memory)\n"
    "  -q, --quiet        no progress messages on stderr\n"
    "  --replicate        under mpirun, keep the whole model on every rank instead of\n"
    "                     splitting the PD grid into z slabs (for comparisons)\n"
    "  --assembled        PETSc solves of coupled models, and of PD-only load steps on\n"
    "                     one process or --replicate, on the assembled matrix instead\n"
    "                     of the matrix-free operator\n"
    "  --set K=V          override a value of the model file (repeatable), validated\n"
    "                     as the file's: --set analysis.solver=direct,\n"
    "                     --set loads[0].traction.value=[0,50,0]\n"
    "  --allow-large      run a dynamic analysis estimated to take more than a day\n"
    "                     or write more than 50 GB or 10^5 files (refused otherwise)\n"
    "  --resume           continue an interrupted run (dynamics, crack growth) from\n"
    "                     its last checkpoint, kept beside the output folder: the\n"
    "                     same files, byte for byte, as a run never interrupted\n"
    "  -ksp_*, -pc_*, -log_view, ... (one dash) go to PETSc (--solver petsc; builds\n"
    "                     with PETSc only), e.g. -ksp_monitor -pc_type hypre\n"
    "\n"
    "Exit status: 0 success, 1 model error, 2 numerical failure (singular or\n"
    "unconstrained system), 3 I/O failure, 4 internal error or out of memory,\n"
    "5 interrupted by SIGINT or SIGTERM after writing a checkpoint (dynamics, crack\n"
    "growth: continue with --resume; a second signal stops at once).\n"
    "The model file format is described in docs/model-format.md.\n";

/* A resumable run (issue 36) asked to stop: it writes a checkpoint at its next safe point (an
 * output step, a load step's end) and
 * ends with status 5. Any other run, or a second signal: interrupted runs leave no half-written
 * files (temporary outputs are removed; a resumable run's staging folder and its last
 * checkpoint stay). */
static void on_signal(int sig) {
  if (cupid_interrupt_request()) {
    static const char msg[] = "\ncupid: interrupt: a checkpoint is written at the next output "
                              "step (dynamics) or step's end (load steps), then the run stops "
                              "(a second signal stops it at once)\n";
    if (write(STDERR_FILENO, msg, sizeof msg - 1) < 0) {
      /* nothing to do in a signal handler */
    }
    return;
  }
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

/* An engine's name (the solver table) or auto. */
static int parse_solver(const char *s) {
  if (!strcmp(s, "auto")) return CUPID_SOLVER_AUTO;
  const cupid_solver_type *e = cupid_solver_type_find(s);
  return e ? e->kind : -1;
}

static int parse_positive(const char *s, double *out) {
  char *end = NULL;
  double v = strtod(s, &end);
  if (!end || *end || end == s || !(v > 0) || v > 1e12) return 0;
  *out = v;
  return 1;
}

static int ends_with(const char *s, const char *tail) {
  size_t n = strlen(s), m = strlen(tail);
  return n >= m && !strcmp(s + n - m, tail);
}

/* A PETSc run-time option: one dash and a letter (cupid's own short options are -o, -q). */
static int is_petsc_option(const char *a) {
  return a[0] == '-' && ((a[1] >= 'a' && a[1] <= 'z') || (a[1] >= 'A' && a[1] <= 'Z')) &&
         strcmp(a, "-o") && strcmp(a, "-q") && strcmp(a, "-h");
}

/* Parse the options that follow `run MODEL` / `check MODEL`. PETSc options (and their values:
 * the next argument unless it is an option or, before the model, a .yaml/.yml file) are
 * appended to petsc_argv / *petsc_argc. Returns 0 or an exit code. */
static int parse_options(int argc, char **argv, int first, cupid_run_options *opts,
                         const char **model_path, char **petsc_argv, int *petsc_argc) {
  for (int i = first; i < argc; i++) {
    const char *a = argv[i];
    int has_value = i + 1 < argc;
    if (is_petsc_option(a)) {
      if (!cupid_petsc_available())
        return usage_error("%s: a PETSc option, but cupid was built without PETSc: rebuild "
                           "with scripts/build.sh --with-petsc", a);
      petsc_argv[(*petsc_argc)++] = argv[i];
      const char *v = has_value ? argv[i + 1] : NULL;
      if (v && v[0] != '-' && !(!*model_path && (ends_with(v, ".yaml") || ends_with(v, ".yml"))))
        petsc_argv[(*petsc_argc)++] = argv[++i];
      continue;
    }
    if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
      if (!has_value || !argv[i + 1][0]) return usage_error("option %s needs a directory", a);
      opts->output_dir = argv[++i];
    } else if (!strcmp(a, "--solver")) {
      if (!has_value) return usage_error("option %s needs a value", a);
      opts->solver = parse_solver(argv[++i]);
      if (opts->solver < 0)
        return usage_error("--solver: unknown solver '%s' (allowed: auto, direct, krylov, petsc)", argv[i]);
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
    } else if (!strcmp(a, "--replicate")) {
      opts->replicate = 1;
    } else if (!strcmp(a, "--assembled")) {
      opts->assembled = 1;
    } else if (!strcmp(a, "--allow-large")) {
      opts->allow_large = 1;
    } else if (!strcmp(a, "--resume")) {
      opts->resume = 1;
    } else if (!strcmp(a, "--set")) {
      static const char *sets[256];
      if (!has_value) return usage_error("option %s needs key.path=value", a);
      if (opts->n_sets == (int)(sizeof sets / sizeof *sets))
        return usage_error("%s", "too many --set options (at most 256)");
      sets[opts->n_sets++] = argv[++i];
      opts->sets = sets;
    } else if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
      fputs(usage_text, stdout);
      fputs("\n", stdout);
      fputs(help_text, stdout);
      return -1; /* done: exit 0 */
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

/* The largest |u| of a 3-component field and where. */
static double max_displacement(const double *u, const double *x, cupid_int n, const double **at) {
  double m = -1.0;
  *at = NULL;
  for (cupid_int i = 0; i < n; i++) {
    const double v = sqrt(u[3 * i] * u[3 * i] + u[3 * i + 1] * u[3 * i + 1] + u[3 * i + 2] * u[3 * i + 2]);
    if (v > m) m = v, *at = x + 3 * i;
  }
  return m;
}

/* The final block of a run on stderr (batch logs as well as terminals): what was solved, the
 * output points, the largest displacements, the equilibrium, where the files are, time and
 * memory. Read back through the library, as any program would. */
static void print_results(cupid_problem p) {
  cupid_problem_info info;
  if (cupid_problem_get_info(p, &info) != CUPID_SUCCESS) return;
  fprintf(stderr, "cupid: %s analysis done in %.2f s, peak memory %.3g GB; solver %s (%s)",
          info.analysis, info.total_seconds, (double)info.peak_memory_bytes / 1e9, info.solver,
          info.method);
  if (info.iterations > 0) fprintf(stderr, ", %d iterations", info.iterations);
  fprintf(stderr, ", residual %.2e\n", info.residual);
  const int np = cupid_problem_output_point_count(p);
  for (int k = 0; k < np; k++) {
    const char *name;
    double xyz[3], u[3];
    int stress, region;
    if (cupid_problem_output_point(p, k, &name, xyz, &stress) != CUPID_SUCCESS ||
        cupid_problem_sample(p, 1, xyz, u, NULL, &region) != CUPID_SUCCESS)
      continue;
    fprintf(stderr, "  point %s (%g, %g, %g) [%s]: u = (%.6g, %.6g, %.6g)\n", name, xyz[0], xyz[1],
            xyz[2], region == CUPID_REGION_PD ? "PD" : region == CUPID_REGION_FE ? "FE" : "none",
            u[0], u[1], u[2]);
  }
  const double *u, *x, *at;
  cupid_int n;
  int nc;
  if (cupid_problem_get_field(p, CUPID_FIELD_PD_DISPLACEMENT, &u, &n, &nc) == CUPID_SUCCESS && n > 0 &&
      cupid_problem_get_field(p, CUPID_FIELD_PD_COORDINATES, &x, &n, &nc) == CUPID_SUCCESS) {
    const double m = max_displacement(u, x, n, &at);
    fprintf(stderr, "  max |u| on the PD nodes: %.6g at (%g, %g, %g)\n", m, at[0], at[1], at[2]);
  }
  if (cupid_problem_get_field(p, CUPID_FIELD_BEAM_DISPLACEMENT, &u, &n, &nc) == CUPID_SUCCESS && n > 0 &&
      cupid_problem_get_field(p, CUPID_FIELD_BEAM_POINTS, &x, &n, &nc) == CUPID_SUCCESS) {
    const double m = max_displacement(u, x, n, &at);
    fprintf(stderr, "  max |u| on the beam: %.6g at (%g, %g, %g)\n", m, at[0], at[1], at[2]);
  }
  if (strcmp(info.analysis, "static") == 0)
    fprintf(stderr, "  equilibrium: load (%.6g, %.6g, %.6g), |R + P| / |P| = %.3e\n",
            info.load_sum[0], info.load_sum[1], info.load_sum[2], info.imbalance);
  fprintf(stderr, "  results in %s (summary.json)\n", cupid_problem_output_directory(p));
}

static int report_error(cupid_status st) {
  const char *msg = cupid_error_message();
  char where[32] = "";
  if (cupid_petsc_size() > 1) snprintf(where, sizeof where, "rank %d: ", cupid_petsc_rank());
  fprintf(stderr, "cupid: %s%s: %s\n", where, cupid_status_name(st), msg[0] ? msg : "(no message)");
  if (getenv("CUPID_DEBUG")) fprintf(stderr, "cupid: raised in %s\n", cupid_error_origin());
  return cupid_status_exit_code(st);
}

/* Under MPI every rank ran the same replicated pipeline: the lowest failing rank prints its
 * message once (rank 0 when all failed alike), every rank exits with the worst status. */
static int finish_parallel(cupid_status st) {
  int size = cupid_petsc_size(), rank = cupid_petsc_rank();
  int code = st == CUPID_SUCCESS ? 0 : cupid_status_exit_code(st);
  int worst = cupid_petsc_max_int(code);
  int lowest = size - cupid_petsc_max_int(code ? size - rank : 0);
  if (code && rank == lowest) report_error(st);
  cupid_petsc_finalize();
  return worst;
}

int cupid_cli_main(int argc, char **argv) {
  if (argc < 2) {
    fputs(usage_text, stderr);
    return 1;
  }
  const char *cmd = argv[1];
  if (!strcmp(cmd, "--version") || !strcmp(cmd, "-V") || !strcmp(cmd, "version")) {
    /* The optional engine is named so that scripts (and the tests) can tell the builds apart. */
    printf("cupid %s (%s)\n", cupid_version(),
           cupid_petsc_available() ? "solvers: direct, petsc" : "solvers: direct");
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

  cupid_run_options opts = cupid_run_options_default();
  const char *path = NULL;
  /* argv[0] and the PETSc options: kept until PetscFinalize (PETSc holds the pointers). */
  static char *petsc_argv[4096];
  int petsc_argc = 1;
  petsc_argv[0] = argv[0];
  if (argc >= (int)(sizeof petsc_argv / sizeof *petsc_argv) - 1)
    return usage_error("%s", "too many arguments");
  int rc = parse_options(argc, argv, 2, &opts, &path, petsc_argv, &petsc_argc);
  if (rc) return rc < 0 ? 0 : rc; /* -1: help printed */
  opts.check_only = is_check;
  petsc_argv[petsc_argc] = NULL;
  cupid_petsc_set_args(petsc_argc, petsc_argv);

  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);

  /* PETSc (and MPI) start here when launched by mpirun or asked for explicitly; `auto` starts it
   * later, only if it picks PETSc (src/problem/problem.c). */
  cupid_status st = CUPID_SUCCESS;
  const cupid_solver_type *requested = cupid_solver_type_get(opts.solver);
  if (cupid_petsc_available() && (cupid_petsc_launched_parallel() || (requested && requested->distributed)))
    st = cupid_petsc_initialize(petsc_argc, petsc_argv);
  cupid_problem problem = NULL;
  if (st == CUPID_SUCCESS) st = cupid_problem_create_from_file(path, &opts, &problem);
  if (st == CUPID_SUCCESS) st = cupid_problem_setup(problem);
  if (st == CUPID_SUCCESS && is_check) st = cupid_problem_print_estimate(problem);
  if (st == CUPID_SUCCESS && is_run) st = cupid_problem_solve(problem);
  /* a crack growth that stopped before its last step (a coupling zone, a collapse): its
   * message, as an error's, even with --quiet; its results written; a run that did not
   * finish, status 2 */
  int stopped = 0;
  cupid_problem_info info;
  if (st == CUPID_SUCCESS && is_run && cupid_problem_get_info(problem, &info) == CUPID_SUCCESS)
    stopped = info.stopped != NULL;
  if (stopped && cupid_petsc_rank() == 0) fprintf(stderr, "cupid: %s\n", info.stopped);
  if (st == CUPID_SUCCESS && is_run) st = cupid_problem_write_outputs(problem);
  if (st == CUPID_SUCCESS && is_run && !opts.quiet && cupid_petsc_rank() == 0)
    print_results(problem);
  cupid_problem_destroy(&problem);
  if (cupid_petsc_initialized()) {
    const int code = finish_parallel(st);
    return code ? code : stopped ? 2 : 0;
  }
  if (st != CUPID_SUCCESS) return report_error(st); /* writing the outputs failed */
  return stopped ? 2 : 0;
}
