/* Benchmark: the fictitious-node coupled model (paper 000 Eq. 38) solved matrix-free (issue 6):
 * GMRES on cupid_coupling_operator_apply() (the PD stiffness never formed), preconditioned by a
 * PETSc PC on the cheap matrix (Eq. 38 with a bond-based PD operator of horizon f h). Reads a
 * model file through the library (src/app/coupled_setup.c: the stages of `cupid run` that do
 * not assemble), prints the time and peak memory of each phase, the iterations and the
 * displacements at the model's output points; with --check it also assembles the coupled
 * matrix, solves it with UMFPACK and requires max |u - u_direct| <= 1e-8 max |u_direct|.
 *
 * Usage: bench_coupled_mf MODEL [--threads N] [--pc lu|ilu|gamg|hypre|...] [--pkg umfpack|
 *        mumps|petsc] [--horizon F] [--rtol R] [--restart M] [--check] [--app] [PETSc options]
 * --app solves through cupid_app_coupled_solve_mf() (the call `--solver petsc` is to make).
 * Without PETSc (default build) it builds the operator and the preconditioner matrix, times
 * the products and stops before the solve. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/coupled_setup.h"
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
  cupid_model model = NULL;
  check(cupid_model_read(path, &model), "model");
  cupid_run_options ro = {.solver = -1, .quiet = 1};
  cupid_coupled_setup s;
  printf("model %s, %d threads\n\n", path, threads);
  printf("| %-34s | %8s | %8s |\n|---|---:|---:|\n", "phase", "seconds", "peak MiB");
  check(cupid_app_coupled_setup(model, &ro, &s), "setup");
  cupid_job *job = &s.job;
  phase("grid, beam, conditions, loads");

#if CUPID_HAVE_PETSC
  if (app) { /* the one-call path for `--solver petsc` (coupled_setup.c) */
    cupid_coupling_krylov_options ko0 = {.rtol = rtol, .restart = restart, .pc = pc,
                                         .factor_package = pkg};
    check(cupid_app_coupled_solve_mf(job, &s.co, &ko0), "cupid_app_coupled_solve_mf");
    phase("cupid_app_coupled_solve_mf");
    printf("\n%s: %lld equations, residual %.2e, %lld fictitious PD nodes\n", job->solve.method,
           (long long)job->solve.n, job->solve.residual, (long long)job->n_fictitious);
    for (int k = 0; k < model->output.n_points; k++) {
      double u[3];
      cupid_region_kind where;
      check(cupid_app_sample(job, model->output.points[k].at, u, NULL, &where), "sample");
      printf("point %s: u = (%.9e, %.9e, %.9e)\n", model->output.points[k].name, u[0], u[1], u[2]);
    }
    cupid_app_coupled_setup_free(&s);
    cupid_model_destroy(&model);
    PetscFinalize();
    return 0;
  }
#else
  (void)app;
#endif
  cupid_coupling_operator A = NULL;
  check(cupid_coupling_operator_create(job->beam, job->grid, &s.co, &A), "operator");
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
  for (int k = 0; k < 5; k++) check(cupid_coupling_operator_apply(A, job->f_ext, y), "apply");
  double t_apply = (cupid_wtime() - ta) / 5;
  t_last = cupid_wtime();

  int rc = 0;
  cupid_coupling_krylov_info ki;
  memset(&ki, 0, sizeof ki);
#if CUPID_HAVE_PETSC
  cupid_coupling_krylov_options ko = {.rtol = rtol, .restart = restart, .pc = pc,
                                      .factor_package = pkg};
  cupid_status st = cupid_coupling_krylov_solve(A, P, job->bc, job->f_ext, job->u, &ko, &ki);
  double peak = (double)cupid_peak_memory() / 1048576.0;
  printf("| %-34s | %8.2f | %8s |\n", "PC set-up (PETSc matrix + factor)", ki.time_setup, "");
  printf("| %-34s | %8.2f | %8.0f |\n", "GMRES", ki.time_solve, peak);
  check(st, "krylov");
#else
  (void)pc, (void)pkg, (void)rtol, (void)restart;
  printf("\n(no PETSc in this build: configure with -DCUPID_WITH_PETSC=ON for the solve)\n");
#endif
  printf("| %-34s | %8.2f | %8.0f |\n\n", "total", cupid_wtime() - t_start,
         (double)cupid_peak_memory() / 1048576.0);
  printf("PD nodes %lld real + %lld fictitious, FE nodes %lld, DOFs %lld (free %lld)\n",
         (long long)ci.n_real_pd, (long long)ci.n_fictitious_pd,
         (long long)job->fe_info.n_fe_nodes, (long long)n, (long long)job->bc->n_free);
  printf("operator %.0f MiB, cheap matrix %.0f MiB (%.1f blocks a row), apply %.3f s\n",
         (double)cupid_coupling_operator_bytes(A) / 1048576.0,
         (double)cupid_csr_bytes(P) / 1048576.0,
         (double)P->rowptr[P->nrows] / (double)P->nrows, t_apply);
#if CUPID_HAVE_PETSC
  printf("%s: %d iterations, relative residual %.2e (horizon %.2f h, rtol %.0e)\n", ki.method,
         ki.iterations, ki.residual, horizon, rtol);
  /* Equilibrium |R + P| / |P| (R: reactions A u - f on fixed DOFs), as `cupid run` prints it:
   * the fictitious-node method does not conserve momentum (docs/coupling.md). */
  double *t = NULL, load[3], reac[3];
  check(cupid_coupling_operator_apply(A, job->u, job->f_int), "apply");
  check(cupid_calloc((size_t)(3 * n), sizeof *t, "translations", &t), "alloc");
  check(cupid_app_translations(job, t), "translations");
  double pn = 0.0, rn = 0.0;
  for (int k = 0; k < 3; k++) {
    load[k] = reac[k] = 0.0;
    for (cupid_int d = 0; d < n; d++) {
      load[k] += job->f_ext[d] * t[(size_t)k * (size_t)n + (size_t)d];
      if (job->bc->fixed[d])
        reac[k] += (job->f_int[d] - job->f_ext[d]) * t[(size_t)k * (size_t)n + (size_t)d];
    }
    pn += load[k] * load[k];
    rn += (load[k] + reac[k]) * (load[k] + reac[k]);
  }
  printf("equilibrium: load (%.6g, %.6g, %.6g), reaction (%.6g, %.6g, %.6g), |R + P| / |P| = "
         "%.3e\n", load[0], load[1], load[2], reac[0], reac[1], reac[2], sqrt(rn / pn));
  cupid_free(&t);
  for (int k = 0; k < model->output.n_points; k++) {
    const cupid_output_point *p = &model->output.points[k];
    double u[3];
    cupid_region_kind where;
    check(cupid_app_sample(job, p->at, u, NULL, &where), "sample");
    printf("point %s (%g, %g, %g) [%s]: u = (%.9e, %.9e, %.9e)\n", p->name, p->at[0], p->at[1],
           p->at[2], where == CUPID_REGION_PD ? "PD" : "FE", u[0], u[1], u[2]);
  }
  if (do_check) {
    cupid_csr K = NULL;
    double *ud = NULL;
    double t0 = cupid_wtime();
    check(cupid_coupling_operator_assemble(A, NULL, &K), "assemble");
    check(cupid_calloc((size_t)n, sizeof *ud, "ud", &ud), "alloc");
    cupid_solve_info si;
    check(cupid_direct_solve(K, CUPID_MATRIX_GENERAL, job->f_ext, job->bc, ud, &si), "direct");
    double e = 0.0, m = 0.0;
    for (cupid_int d = 0; d < n; d++) {
      e = fmax(e, fabs(job->u[d] - ud[d]));
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
  cupid_app_coupled_setup_free(&s);
  cupid_model_destroy(&model);
#if CUPID_HAVE_PETSC
  PetscFinalize();
#endif
  return rc;
}
