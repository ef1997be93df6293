/* Benchmark: PD operator set-up on cubes of n^3 nodes (h = 1, delta = 3 h, LPS, gaussian
 * influence, PDLAMMPS partial volumes): grid, neighbour search, analytic assembly of K,
 * one matrix-free apply and the assembled mat-vec; sizes and peak memory. "CPU ns/pair" is
 * the assembly CPU time (all threads) per (p, k) term of the dilatation part, the
 * O(nodes x family^2) work; CPU time is less disturbed than wall time by other load. Prints a markdown
 * table. Usage: bench_pd_cube [n ...] (default 10 15 20 25 30 40); threads from
 * OMP_NUM_THREADS. Options: --bond (bond-based), --exact (exact partial volumes). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "cupid.h"
#include "pd/pd_internal.h" /* bond counts for the work measure */

static void check(cupid_status st) {
  if (st != CUPID_SUCCESS) {
    fprintf(stderr, "bench_pd_cube: %s: %s\n", cupid_status_name(st), cupid_error_message());
    exit(1);
  }
}

static double cpu_time(void) {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
         1e-6 * (double)ru.ru_stime.tv_usec;
}

/* Work of the LPS assembly: (p, k) pairs summed over rows, sum_r sum_{p in H_r + r} |H_p + p|. */
static double assembly_pairs(const struct cupid_pd_operator_private *op) {
  double w = 0;
  for (cupid_int r = 0; r < op->nnodes; r++) {
    const pd_family F = pd_family_of(op, r);
    w += (double)(F.n + 1);
    for (int q = 0; q < F.n; q++)
      w += (double)(pd_family_of(op, pd_family_node(op, &F, pd_family_entry(&F, q))).n + 1);
  }
  return w;
}

/* y = K u for the 3x3-block matrix (OpenMP over block rows). */
/* A static solve on the assembled K with CHOLMOD: the layer z < 3 (one horizon) is held,
 * the rest carries a uniform body force along z. Returns 0 on success. */
static int solve(const cupid_csr_t *K, const double *coords, cupid_int nn, cupid_solve_info *info) {
  cupid_dirichlet bc = NULL;
  double *f = calloc(3 * (size_t)nn, sizeof *f), *u = calloc(3 * (size_t)nn, sizeof *u);
  if (!f || !u) return 1;
  check(cupid_dirichlet_create(3 * nn, &bc));
  for (cupid_int i = 0; i < nn; i++) {
    if (coords[3 * i + 2] < 3.0)
      for (int c = 0; c < 3; c++) bc->fixed[3 * i + c] = 1;
    f[3 * i + 2] = -1.0;
  }
  check(cupid_dirichlet_finalize(bc));
  check(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, info));
  cupid_dirichlet_destroy(&bc);
  free(f);
  free(u);
  return 0;
}

int main(int argc, char **argv) {
  int sizes[64], ns = 0;
  cupid_pd_model_kind model = CUPID_PD_LPS;
  cupid_partial_volume pv = CUPID_PARTIAL_PDLAMMPS;
  int solve_max = 20; /* CHOLMOD solve for n <= solve_max (20^3 LPS: ~5 GB, minutes) */
  for (int a = 1; a < argc && ns < 64; a++) {
    if (!strcmp(argv[a], "--bond")) model = CUPID_PD_BOND;
    else if (!strcmp(argv[a], "--exact")) pv = CUPID_PARTIAL_EXACT;
    else if (!strcmp(argv[a], "--solve-max") && a + 1 < argc) solve_max = atoi(argv[++a]);
    else sizes[ns++] = atoi(argv[a]);
  }
  if (ns == 0) {
    const int def[] = {10, 15, 20, 25, 30, 40};
    for (int i = 0; i < 6; i++) sizes[ns++] = def[i];
  }
  printf("PD cube benchmark: %s, gaussian, %s, delta = 3h, %d OpenMP threads, cupid %s\n\n",
         model == CUPID_PD_LPS ? "LPS" : "bond-based", pv == CUPID_PARTIAL_EXACT ? "exact" : "pdlammps",
         cupid_num_threads(), cupid_version());
  printf("| n | nodes | bonds | K blocks | K MB | grid s | neighbours s | assembly s | assembly CPU s "
         "| assembly us/node | assembly CPU ns/pair | apply ms | K matvec ms | factor s | solve s "
         "| nnz(L) | peak MB |\n");
  printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  fflush(stdout);
  for (int s = 0; s < ns; s++) {
    const int n = sizes[s];
    cupid_box box = {.lo = {0, 0, 0}, .hi = {n, n, n}, .has = {1, 1, 1}};
    int mat = 0;
    cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
    cupid_pd_material m = {1.0e4, model == CUPID_PD_LPS ? 0.3 : 0.25};
    cupid_pd_operator_options oo = {.horizon = 3.0, .model = model,
                                    .influence = CUPID_INFLUENCE_GAUSSIAN, .partial_volume = pv,
                                    .materials = &m, .n_materials = 1};
    cupid_pd_grid g = NULL;
    cupid_pd_operator op = NULL;
    cupid_csr K = NULL;
    double t0 = cupid_wtime();
    check(cupid_pd_grid_create(&go, 1, &box, &mat, &g));
    double t1 = cupid_wtime();
    check(cupid_pd_operator_create(g, &oo, &op));
    double t2 = cupid_wtime();
    const double c2 = cpu_time();
    check(cupid_pd_operator_assemble(op, &K));
    double t3 = cupid_wtime();
    const double cpu = cpu_time() - c2;
    const cupid_int nn = cupid_pd_grid_num_nodes(g);
    double *u = malloc(3 * (size_t)nn * sizeof *u), *f = malloc(3 * (size_t)nn * sizeof *f);
    if (!u || !f) return 1;
    for (cupid_int i = 0; i < 3 * nn; i++) u[i] = 1e-3 * (double)((i * 7919) % 1000);
    double t4 = cupid_wtime();
    check(cupid_pd_operator_apply(op, u, f));
    double t5 = cupid_wtime();
    cupid_csr_matvec(K, u, f);
    double t6 = cupid_wtime();
    cupid_solve_info info = {0};
    int solved = n <= solve_max && !solve(K, cupid_pd_grid_coords(g), nn, &info);
    const cupid_int blocks = K->rowptr[nn];
    const double kmb = (double)((nn + 1) * 8 + blocks * (8 + 72)) / 1e6;
    const double pairs = model == CUPID_PD_LPS ? assembly_pairs(op) : (double)cupid_pd_operator_num_bonds(op);
    char fs[32] = "-", ss[32] = "-", ls[32] = "-";
    if (solved) {
      snprintf(fs, sizeof fs, "%.2f", info.time_factor);
      snprintf(ss, sizeof ss, "%.3f", info.time_solve);
      snprintf(ls, sizeof ls, "%.3g", info.nnz_factor);
    }
    printf("| %d | %lld | %lld | %lld | %.0f | %.3f | %.3f | %.2f | %.2f | %.1f | %.2f | %.1f | %.1f | %s | %s | %s | %.0f |\n", n,
           (long long)nn, (long long)cupid_pd_operator_num_bonds(op), (long long)blocks, kmb, t1 - t0,
           t2 - t1, t3 - t2, cpu, 1e6 * (t3 - t2) / (double)nn, 1e9 * cpu / pairs, 1e3 * (t5 - t4),
           1e3 * (t6 - t5), fs, ss, ls, (double)cupid_peak_memory() / 1e6);
    fflush(stdout);
    free(u);
    free(f);
    cupid_csr_destroy(&K);
    cupid_pd_operator_destroy(&op);
    cupid_pd_grid_destroy(&g);
  }
  return 0;
}
