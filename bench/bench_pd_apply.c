/* Benchmark: the matrix-free PD operator f = K u on cubes of n^3 nodes, stencil path (the
 * default, src/pd/stencil.c) against the bond-list path (explicit bonds, lps.c / bond.c).
 * Lattice as the LAMMPS comparison (bench/run_lammps.sh): h = 1, delta = 3.015 h, influence
 * 1/|xi|, PDLAMMPS partial volumes, E = 1e4, nu = 0.25 (LPS; --bond for bond-based).
 * For each n: operator creation, operator bytes per node (stencil storage; bond lists; the
 * apply's kept work arrays), peak memory before and after building the bond lists,
 * best-of-reps apply time of each path, force evaluations per second, and the time of
 * `--steps` explicit central-difference steps (velocity Verlet, lumped mass rho V,
 * cupid_pd_operator_apply per step), peak resident memory. Prints a markdown table.
 * `--uniform-ab R`: R rounds in one process, alternating the LPS stencil apply with and
 * without the runs' stretches of uniform b (pd_run ub0, ub1; src/pd/uniform.c), best of 5
 * applies each: the medians and the median of the rounds' ratios (to stderr). One process
 * sees one memory layout, so a few percent are resolved that separate processes blur.
 * Usage: bench_pd_apply [n ...] [--bond] [--steps S] [--reps R] [--no-bond-lists]
 * [--uniform-ab R]; threads from OMP_NUM_THREADS. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "cupid.h"
#include "pd/pd_internal.h" /* storage sizes and the bond-list switch */

static void check(cupid_status st) {
  if (st != CUPID_SUCCESS) {
    fprintf(stderr, "bench_pd_apply: %s: %s\n", cupid_status_name(st), cupid_error_message());
    exit(1);
  }
}

/* Bytes held by the operator's stencil storage (families, runs, per-node data, the ghost
 * records of near-surface nodes' segments). */
static double stencil_bytes(const struct cupid_pd_operator_private *op) {
  const double nn = (double)op->nnodes;
  double b = nn * (1 + 8) + 8; /* full flags, family offsets */
  b += (double)op->fptr[op->nnodes] * 4 + (double)op->nruns * sizeof(pd_run);
  b += (double)op->st.n * (3 * 4 + 8 + 24 + 8 + 24 + 8 + 8 + 8 + 8);
  b += nn * 8 * (op->model == CUPID_PD_LPS ? 6 : 4); /* m kappa mu + gself(3) | c */
  if (op->gseg) /* segments, their shared records */
    b += (double)op->nruns * 8 + (double)op->nseg * sizeof(pd_ghost_seg) +
         ((double)op->gstride * PD_GHOST_STRIDE + PD_GHOST_SLACK) * 8;
  return b;
}

static double bond_list_bytes(const struct cupid_pd_operator_private *op) {
  return ((double)op->nnodes + 1) * 8 + (double)op->bptr[op->nnodes] * 12;
}

/* CPU time of the process, all threads (user + system): robust against other load. */
static double cpu_time(void) {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
         (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
}

/* Best wall time of one apply over reps; *cpu = mean CPU time of one apply. */
static double best_apply(cupid_pd_operator op, const double *u, double *f, int reps, double *cpu) {
  double best = INFINITY, c0 = cpu_time();
  for (int r = 0; r < reps; r++) {
    double t0 = cupid_wtime();
    check(cupid_pd_operator_apply(op, u, f));
    double t = cupid_wtime() - t0;
    if (t < best) best = t;
  }
  *cpu = (cpu_time() - c0) / reps;
  return best;
}

static int by_value(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

static double median(double *x, int n) {
  qsort(x, (size_t)n, sizeof *x, by_value);
  return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

/* The apply with the uniform-b stretches and without (see the header), rounds alternated. */
static void uniform_ab(struct cupid_pd_operator_private *op, int n, int rounds, const double *u,
                       double *f) {
  int *keep = malloc(2 * (size_t)op->nruns * sizeof *keep);
  double *on = malloc(3 * (size_t)rounds * sizeof *on), *off = on + rounds, *ratio = off + rounds;
  if (!keep || !on) exit(1);
  cupid_int nodes = 0;
  for (cupid_int r = 0; r < op->nruns; r++) {
    keep[2 * r] = op->runs[r].ub0, keep[2 * r + 1] = op->runs[r].ub1;
    nodes += op->runs[r].ub1 - op->runs[r].ub0;
  }
  for (int k = 0; k < rounds; k++) {
    for (int with = 1; with >= 0; with--) {
      for (cupid_int r = 0; r < op->nruns; r++) {
        op->runs[r].ub0 = with ? keep[2 * r] : 0;
        op->runs[r].ub1 = with ? keep[2 * r + 1] : 0;
      }
      double cpu;
      (with ? on : off)[k] = best_apply(op, u, f, 5, &cpu);
    }
    ratio[k] = on[k] / off[k];
  }
  fprintf(stderr, "n = %d: uniform-b stretches (%lld nodes of %lld), %d alternated rounds of "
          "best-of-5 applies: on %.3f ms, off %.3f ms (medians), on/off median %.3f\n",
          n, (long long)nodes, (long long)op->nnodes, rounds, 1e3 * median(on, rounds),
          1e3 * median(off, rounds), median(ratio, rounds));
  free(keep);
  free(on);
}

/* steps of velocity Verlet, m a = -K u, from a smooth initial velocity; returns wall
 * seconds, *cpu the CPU seconds. */
static double explicit_steps(cupid_pd_operator op, cupid_int nn, int steps, double *u, double *v,
                             double *f, double *checksum, double *cpu) {
  const double rho = 1.0, V = 1.0, dt = 1e-3, m = rho * V;
  const double *x = cupid_pd_grid_coords((cupid_pd_grid)op->grid);
  for (cupid_int i = 0; i < 3 * nn; i++) u[i] = 0.0;
  for (cupid_int i = 0; i < nn; i++)
    for (int c = 0; c < 3; c++) v[3 * i + c] = 1e-3 * sin(0.1 * x[3 * i + c] + c);
  check(cupid_pd_operator_apply(op, u, f));
  double t0 = cupid_wtime(), c0 = cpu_time();
  for (int s = 0; s < steps; s++) {
#pragma omp parallel for schedule(static)
    for (cupid_int d = 0; d < 3 * nn; d++) {
      v[d] -= 0.5 * dt * f[d] / m;
      u[d] += dt * v[d];
    }
    check(cupid_pd_operator_apply(op, u, f));
#pragma omp parallel for schedule(static)
    for (cupid_int d = 0; d < 3 * nn; d++) v[d] -= 0.5 * dt * f[d] / m;
  }
  double t = cupid_wtime() - t0;
  *cpu = cpu_time() - c0;
  double cs = 0.0;
  for (cupid_int d = 0; d < 3 * nn; d++) cs += fabs(u[d]);
  *checksum = cs;
  return t;
}

int main(int argc, char **argv) {
  int sizes[64], ns = 0, steps = 110, reps = 10, bond_lists = 1, ab = 0;
  cupid_pd_model_kind model = CUPID_PD_LPS;
  for (int a = 1; a < argc && ns < 64; a++) {
    if (!strcmp(argv[a], "--bond")) model = CUPID_PD_BOND;
    else if (!strcmp(argv[a], "--steps") && a + 1 < argc) steps = atoi(argv[++a]);
    else if (!strcmp(argv[a], "--reps") && a + 1 < argc) reps = atoi(argv[++a]);
    else if (!strcmp(argv[a], "--no-bond-lists")) bond_lists = 0;
    else if (!strcmp(argv[a], "--uniform-ab") && a + 1 < argc) ab = atoi(argv[++a]);
    else sizes[ns++] = atoi(argv[a]);
  }
  if (ns == 0) {
    const int def[] = {20, 40, 60};
    for (int i = 0; i < 3; i++) sizes[ns++] = def[i];
  }
  const char *th = getenv("OMP_NUM_THREADS");
  printf("PD apply benchmark: %s, influence 1/|xi|, pdlammps, delta = 3.015 h, %s threads, "
         "%d explicit steps, cupid %s\n\n",
         model == CUPID_PD_LPS ? "LPS" : "bond-based", th ? th : "default", steps, cupid_version());
  printf("Apply: best wall time of %d (CPU: mean CPU seconds of all threads per apply). Steps: "
         "wall and CPU seconds of the %d-step loop; evals/s = steps / loop wall time.\n\n",
         reps, steps);
  printf("| n | nodes | bonds/node | full nodes | create s | stencil B/node | bond-list B/node "
         "| apply stencil ms (CPU) | apply bond-list ms (CPU) | %d steps stencil s (CPU) "
         "| %d steps bond-list s (CPU) | evals/s stencil | evals/s bond-list | work B/node "
         "| peak MB stencil | peak MB |\n",
         steps, steps);
  printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (int k = 0; k < ns; k++) {
    const int n = sizes[k];
    cupid_box box = {{0, 0, 0}, {n, n, n}, {1, 1, 1}};
    int mat = 0;
    cupid_pd_grid_options go = {.spacing = 1.0, .dimension = 3};
    cupid_pd_grid grid = NULL;
    check(cupid_pd_grid_create(&go, 1, &box, &mat, &grid));
    cupid_pd_material pm = {.E = 1e4, .nu = 0.25};
    cupid_pd_operator_options oo = {.horizon = 3.015, .model = model,
                                    .influence = CUPID_INFLUENCE_INVERSE,
                                    .partial_volume = CUPID_PARTIAL_PDLAMMPS, .materials = &pm,
                                    .n_materials = 1};
    cupid_pd_operator op = NULL;
    double t0 = cupid_wtime();
    check(cupid_pd_operator_create(grid, &oo, &op));
    const double t_create = cupid_wtime() - t0;
    const cupid_int nn = cupid_pd_grid_num_nodes(grid);
    double *u = malloc(3 * (size_t)nn * sizeof *u), *v = malloc(3 * (size_t)nn * sizeof *v);
    double *f = malloc(3 * (size_t)nn * sizeof *f), *g = malloc(3 * (size_t)nn * sizeof *g);
    if (!u || !v || !f || !g) return 1;
    uint64_t seed = 88172645463325252ULL;
    for (cupid_int i = 0; i < 3 * nn; i++) {
      seed ^= seed << 13, seed ^= seed >> 7, seed ^= seed << 17;
      u[i] = (double)(seed >> 11) / 9007199254740992.0 - 0.5;
    }
    const double sb = stencil_bytes(op);
    double c_st = 0, c_st_steps = 0, c_bl = NAN, c_bl_steps = NAN;
    const double t_st = best_apply(op, u, f, reps, &c_st);
    double cs_st = 0, cs_bl = 0;
    const double t_st_steps = explicit_steps(op, nn, steps, u, v, f, &cs_st, &c_st_steps);
    if (ab > 0) uniform_ab(op, n, ab, u, f);
    const double peak_stencil = (double)cupid_peak_memory() / 1e6;
    /* The kept work arrays: 5 doubles a cell of the padded window (8 for LPS). */
    const double wb = (op->model == CUPID_PD_LPS ? 64.0 : 40.0) *
                      (op->padded ? (double)(op->pn[0] * op->pn[1] * op->pn[2]) : (double)nn);
    double t_bl = NAN, t_bl_steps = NAN, bb = NAN, diff = NAN;
    if (bond_lists) {
      for (cupid_int i = 0; i < 3 * nn; i++) {
        seed ^= seed << 13, seed ^= seed >> 7, seed ^= seed << 17;
        u[i] = (double)(seed >> 11) / 9007199254740992.0 - 0.5;
      }
      check(cupid_pd_operator_apply(op, u, f));
      check(pd_operator_use_bond_lists(op));
      bb = bond_list_bytes(op);
      t_bl = best_apply(op, u, g, reps, &c_bl);
      double fm = 0;
      diff = 0;
      for (cupid_int i = 0; i < 3 * nn; i++) {
        fm = fmax(fm, fabs(g[i]));
        diff = fmax(diff, fabs(f[i] - g[i]));
      }
      diff /= fm;
      t_bl_steps = explicit_steps(op, nn, steps, u, v, f, &cs_bl, &c_bl_steps);
    }
    cupid_int full = 0;
    for (cupid_int i = 0; i < nn; i++) full += op->full[i];
    printf("| %d | %lld | %.1f | %lld | %.3f | %.0f | %.0f | %.2f (%.2f) | %.2f (%.2f) | %.3f (%.3f) "
           "| %.3f (%.3f) | %.1f | %.1f | %.0f | %.0f | %.0f |\n",
           n, (long long)nn, (double)cupid_pd_operator_num_bonds(op) / (double)nn, (long long)full,
           t_create, sb / (double)nn, bb / (double)nn, 1e3 * t_st, 1e3 * c_st, 1e3 * t_bl,
           1e3 * c_bl, t_st_steps, c_st_steps, t_bl_steps, c_bl_steps, steps / t_st_steps,
           steps / t_bl_steps, wb / (double)nn, peak_stencil, (double)cupid_peak_memory() / 1e6);
    fprintf(stderr, "n = %d: max |f_stencil - f_bondlist| / max|f| = %.2e, explicit checksums %.12e %.12e\n",
            n, diff, cs_st, cs_bl);
    fflush(stdout);
    free(u);
    free(v);
    free(f);
    free(g);
    cupid_pd_operator_destroy(&op);
    cupid_pd_grid_destroy(&grid);
  }
  return 0;
}
