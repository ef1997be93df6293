/* Benchmark: the fictitious-node coupled model (paper 000 Eq. 38) solved matrix-free (issue 6):
 * GMRES on cupid_coupling_operator_apply() (the PD stiffness never formed), preconditioned by a
 * PETSc PC on the cheap matrix (Eq. 38 with a bond-based PD operator of horizon f h). Reads a
 * model file through the library (cupid_problem_setup: the stages of `cupid run` before the
 * solve, with the direct engine so that nothing is assembled), prints the time and peak memory of each phase, the iterations and the
 * displacements at the model's output points; with --check it also assembles the coupled
 * matrix, solves it with UMFPACK and requires max |u - u_direct| <= 1e-8 max |u_direct|.
 *
 * Usage: bench_coupled_mf MODEL [--threads N] [--pc lu|ilu|gamg|hypre|...] [--pkg umfpack|
 *        mumps|petsc] [--horizon F] [--rtol R] [--restart M] [--check] [--app] [PETSc options]
 * --app solves through cupid_problem_solve() with the PETSc engine (what `--solver petsc` does;
 * the PC then comes from PETSc options such as -pc_type).
 * Without PETSc (default build) it builds the operator and the preconditioner matrix, times
 * the products and stops before the solve. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cupid.h"
#include "cupid_config.h"
#if CUPID_HAVE_PETSC
#include <petscsys.h>
#endif

static void check(cupid_status st, const char *what) {
  if (st != CUPID_SUCCESS) {
    fprintf(stderr, "bench_coupled_mf: %s: %s: %s\n", what, cupid_status_name(st),
            cupid_error_message());
    exit(1);
  }
}

/* The bench takes fictitious-node static 3D models only. */
#define CUPID_CHECK_EXIT(cond)                                                                 \
  do {                                                                                         \
    if (!(cond)) {                                                                             \
      fprintf(stderr, "bench_coupled_mf: the model must be a static beam + 3D PD model with "  \
                      "coupling method fictitious\n");                                         \
      return 2;                                                                                \
    }                                                                                          \
  } while (0)

/* u at the model's output points, sampled as `cupid run` does. */
static void print_points(cupid_problem prob, const cupid_model_t *model) {
  for (int k = 0; k < model->output.n_points; k++) {
    const cupid_output_point *p = &model->output.points[k];
    double u[3];
    int where;
    check(cupid_problem_sample(prob, 1, p->at, u, NULL, &where), "sample");
    printf("point %s (%g, %g, %g) [%s]: u = (%.9e, %.9e, %.9e)\n", p->name, p->at[0], p->at[1],
           p->at[2], where == CUPID_REGION_PD ? "PD" : "FE", u[0], u[1], u[2]);
  }
}

static double t_last;
static void phase(const char *name) {
  double t = cupid_wtime();
  printf("| %-34s | %8.2f | %8.0f |\n", name, t - t_last, (double)cupid_peak_memory() / 1048576.0);
  fflush(stdout);
  t_last = cupid_wtime();
}

int main(int argc, char **argv) {
#if CUPID_HAVE_PETSC
  PetscInitialize(&argc, &argv, NULL, NULL);
#endif
  const char *path = NULL, *pc = "lu", *pkg = NULL;
  int threads = 0, do_check = 0, restart = 200, app = 0;
  double horizon = 1.5, rtol = 1e-10;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--pc") && i + 1 < argc) pc = argv[++i];
    else if (!strcmp(argv[i], "--pkg") && i + 1 < argc) pkg = argv[++i];
    else if (!strcmp(argv[i], "--horizon") && i + 1 < argc) horizon = atof(argv[++i]);
    else if (!strcmp(argv[i], "--rtol") && i + 1 < argc) rtol = atof(argv[++i]);
    else if (!strcmp(argv[i], "--restart") && i + 1 < argc) restart = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--check")) do_check = 1;
    else if (!strcmp(argv[i], "--app")) app = 1;
    else if (argv[i][0] != '-' && !path) path = argv[i];
    else if (argv[i][0] == '-' && argv[i][1] != '-' && i + 1 < argc && argv[i + 1][0] != '-') i++;
  }
  if (!path) {
    fprintf(stderr, "usage: bench_coupled_mf MODEL [--threads N] [--pc TYPE] [--pkg PKG] "
                    "[--horizon F] [--rtol R] [--restart M] [--check] [PETSc options]\n");
    return 2;
  }
  cupid_set_num_threads(threads);
  t_last = cupid_wtime();
  double t_start = t_last;
  cupid_run_options ro = cupid_run_options_default();
  ro.quiet = 1;
  ro.solver = app ? CUPID_SOLVER_PETSC : CUPID_SOLVER_DIRECT;
  cupid_problem prob = NULL;
  printf("model %s, %d threads\n\n", path, threads);
  printf("| %-34s | %8s | %8s |\n|---|---:|---:|\n", "phase", "seconds", "peak MiB");
  check(cupid_problem_create_from_file(path, &ro, &prob), "model");
  const cupid_model_t *model = cupid_problem_model(prob);
  CUPID_CHECK_EXIT(model->has_beam && model->has_peridynamics &&
                   model->coupling.method == CUPID_COUPLING_FICTITIOUS &&
                   model->analysis.type == CUPID_ANALYSIS_STATIC && model->pd.dimension == 3);
  check(cupid_problem_setup(prob), "setup");
  cupid_problem_system sys;
  cupid_coupling_options co;
  check(cupid_problem_get_system(prob, &sys), "system");
  check(cupid_problem_coupling_options(prob, &co), "coupling options");
  phase("grid, beam, conditions, loads");

#if CUPID_HAVE_PETSC
  if (app) { /* the one-call path of `--solver petsc` */
    check(cupid_problem_solve(prob), "cupid_problem_solve");
    phase("cupid_problem_solve");
    cupid_problem_info info;
    check(cupid_problem_get_info(prob, &info), "info");
    printf("\n%s: %lld equations, residual %.2e, %lld fictitious PD nodes, imbalance %.3e\n",
           info.method, (long long)(info.dofs - info.constrained_dofs), info.residual,
           (long long)info.fictitious_nodes, info.imbalance);
    print_points(prob, model);
    cupid_problem_destroy(&prob);
    PetscFinalize();
    return 0;
  }
#else
  (void)app;
#endif
  cupid_coupling_operator A = NULL;
  check(cupid_coupling_operator_create(sys.beam, sys.grid, &co, &A), "operator");
  phase("fictitious nodes + PD operator");
  cupid_csr P = NULL;
  check(cupid_coupling_preconditioner(A, horizon, &P), "preconditioner");
  phase("cheap matrix (Eq. 38, bond-based)");

  cupid_coupling_info ci;
  cupid_coupling_operator_get_info(A, &ci);
  cupid_int n = cupid_coupling_operator_size(A);
  double *y = NULL;
  check(cupid_calloc((size_t)n, sizeof *y, "y", &y), "alloc");
  double ta = cupid_wtime();
  for (int k = 0; k < 5; k++) check(cupid_coupling_operator_apply(A, sys.f_ext, y), "apply");
  double t_apply = (cupid_wtime() - ta) / 5;
  t_last = cupid_wtime();

  int rc = 0;
  cupid_solve_info ki;
  memset(&ki, 0, sizeof ki);
#if CUPID_HAVE_PETSC
  cupid_krylov_options ko = {.rtol = rtol, .restart = restart, .pc = pc,
                                      .factor_package = pkg};
  cupid_status st = cupid_coupling_krylov_solve(A, P, sys.bc, sys.f_ext, sys.u, &ko, &ki);
  double peak = (double)cupid_peak_memory() / 1048576.0;
  printf("| %-34s | %8.2f | %8s |\n", "PC set-up (PETSc matrix + factor)", ki.time_factor, "");
  printf("| %-34s | %8.2f | %8.0f |\n", "GMRES", ki.time_solve, peak);
  check(st, "krylov");
#else
  (void)pc, (void)pkg, (void)rtol, (void)restart;
  printf("\n(no PETSc in this build: configure with -DCUPID_WITH_PETSC=ON for the solve)\n");
#endif
  printf("| %-34s | %8.2f | %8.0f |\n\n", "total", cupid_wtime() - t_start,
         (double)cupid_peak_memory() / 1048576.0);
  printf("PD nodes %lld real + %lld fictitious, FE DOFs / 3 %lld, DOFs %lld (free %lld)\n",
         (long long)ci.n_real_pd, (long long)ci.n_fictitious_pd,
         (long long)(n - 3 * ci.n_real_pd - 3 * ci.n_fictitious_pd) / 3, (long long)n, (long long)sys.bc->n_free);
  printf("operator %.0f MiB, cheap matrix %.0f MiB (%.1f blocks a row), apply %.3f s\n",
         (double)cupid_coupling_operator_bytes(A) / 1048576.0,
         (double)cupid_csr_bytes(P) / 1048576.0,
         (double)P->rowptr[P->nrows] / (double)P->nrows, t_apply);
#if CUPID_HAVE_PETSC
  printf("%s + %s: %d iterations, relative residual %.2e (horizon %.2f h, rtol %.0e)\n",
         ki.ksp_type, ki.pc_type, ki.iterations, ki.residual, horizon, rtol);
  /* Equilibrium |R + P| / |P| (R: reactions A u - f on fixed DOFs), as `cupid run` prints it:
   * the fictitious-node method does not conserve momentum (docs/coupling.md). */
  double load[3], reac[3], pn = 0.0, rn = 0.0;
  check(cupid_coupling_operator_apply(A, sys.u, sys.f_int), "apply");
  check(cupid_problem_force_sums(prob, load, reac), "force sums");
  for (int k = 0; k < 3; k++) {
    pn += load[k] * load[k];
    rn += (load[k] + reac[k]) * (load[k] + reac[k]);
  }
  printf("equilibrium: load (%.6g, %.6g, %.6g), reaction (%.6g, %.6g, %.6g), |R + P| / |P| = "
         "%.3e\n", load[0], load[1], load[2], reac[0], reac[1], reac[2], sqrt(rn / pn));
  print_points(prob, model);
  if (do_check) {
    cupid_csr K = NULL;
    double *ud = NULL;
    double t0 = cupid_wtime();
    check(cupid_coupling_operator_assemble(A, NULL, &K), "assemble");
    check(cupid_calloc((size_t)n, sizeof *ud, "ud", &ud), "alloc");
    cupid_solve_info si;
    check(cupid_direct_solve(K, CUPID_MATRIX_GENERAL, sys.f_ext, sys.bc, ud, &si), "direct");
    double e = 0.0, m = 0.0;
    for (cupid_int d = 0; d < n; d++) {
      e = fmax(e, fabs(sys.u[d] - ud[d]));
      m = fmax(m, fabs(ud[d]));
    }
    printf("check: assembled + %s %.1f s (peak %.0f MiB): max |u - u_direct| / max |u_direct| = "
           "%.2e (%s, limit 1e-8)\n",
           si.method, cupid_wtime() - t0, (double)cupid_peak_memory() / 1048576.0, e / m,
           e <= 1e-8 * m ? "ok" : "FAILED");
    rc = e <= 1e-8 * m ? 0 : 1;
    cupid_csr_destroy(&K);
    cupid_free(&ud);
  }
#else
  (void)do_check;
#endif
  cupid_free(&y);
  cupid_csr_destroy(&P);
  cupid_coupling_operator_destroy(&A);
  cupid_problem_destroy(&prob);
#if CUPID_HAVE_PETSC
  PetscFinalize();
#endif
  return rc;
}
