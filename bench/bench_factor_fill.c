/* Benchmark: how large a Cholesky factor of a model's PD stiffness is, by CHOLMOD's symbolic
 * analysis alone (no numeric factor: it runs where the factor itself would not fit). For
 * issue 38, item 2: whether a factor of the coupled SENB at h = 1/4 can fit 8 GB under any
 * ordering CHOLMOD offers. Reads a model through the library (cupid_problem_setup on the
 * direct engine: nothing is factorised), assembles the PD block K (the coupled K adds the
 * beam's few thousand DOFs and the overlap's penalty on nodes K already couples), and analyses
 * its lower triangle (3 DOFs a node, every DOF free) with each ordering: CHOLMOD's default
 * (AMD, then METIS where AMD's fill is high, the better kept), AMD, METIS, NESDIS (CHOLMOD's
 * nested dissection with constrained minimum degree), and METIS on the node graph (a node's
 * 3 DOFs kept together), given to CHOLMOD as a permutation. Prints, per ordering, the
 * factor's entries (the simplicial count lnz), the flops, and the bytes of its values (8 an
 * entry: the supernodal factor's floor, its supernodes padded), of its simplicial form (a value
 * and a 64-bit row index an entry: the form CHOLMOD downdates) and of crack growth's peak on the
 * direct path (both: 24 bytes an entry; measured 22 at h = 1/3, session 35).
 *
 * Usage: bench_factor_fill MODEL [--set key=value ...] [--threads N] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cholmod.h>

#include "cupid.h"

static void check(cupid_status st, const char *what) {
  if (st != CUPID_SUCCESS) {
    fprintf(stderr, "bench_factor_fill: %s: %s: %s\n", what, cupid_status_name(st),
            cupid_error_message());
    exit(1);
  }
}

/* The scalar lower triangle's pattern of a 3x3-block CSR K (rows = columns: K is symmetric,
 * so block row i's columns j <= i are column i's rows of the upper triangle, i.e. the lower
 * triangle's column i in CHOLMOD's column-major storage, read as rows >= i). */
static cholmod_sparse *lower_pattern(const cupid_csr_t *K, cholmod_common *c) {
  const SuiteSparse_long nb = K->nrows, n = 3 * nb;
  size_t nz = 0;
  for (SuiteSparse_long i = 0; i < nb; i++)
    for (cupid_int k = K->rowptr[i]; k < K->rowptr[i + 1]; k++)
      if (K->col[k] >= i) nz += K->col[k] == i ? 6 : 9;
  cholmod_sparse *A = cholmod_l_allocate_sparse((size_t)n, (size_t)n, nz, 1, 1, -1,
                                                CHOLMOD_PATTERN, c);
  if (!A) return NULL;
  SuiteSparse_long *p = A->p, *ri = A->i, at = 0;
  for (SuiteSparse_long i = 0; i < nb; i++)
    for (int a = 0; a < 3; a++) { /* column 3i + a: rows 3j + b >= 3i + a over blocks j >= i */
      p[3 * i + a] = at;
      for (cupid_int k = K->rowptr[i]; k < K->rowptr[i + 1]; k++) {
        const SuiteSparse_long j = K->col[k];
        if (j < i) continue;
        for (int b = j == i ? a : 0; b < 3; b++) ri[at++] = 3 * j + b;
      }
    }
  p[n] = at;
  return A;
}

/* The node graph's lower triangle (one entry a 3x3 block). */
static cholmod_sparse *node_pattern(const cupid_csr_t *K, cholmod_common *c) {
  const SuiteSparse_long nb = K->nrows;
  size_t nz = 0;
  for (SuiteSparse_long i = 0; i < nb; i++)
    for (cupid_int k = K->rowptr[i]; k < K->rowptr[i + 1]; k++) nz += K->col[k] >= i;
  cholmod_sparse *A = cholmod_l_allocate_sparse((size_t)nb, (size_t)nb, nz, 1, 1, -1,
                                                CHOLMOD_PATTERN, c);
  if (!A) return NULL;
  SuiteSparse_long *p = A->p, *ri = A->i, at = 0;
  for (SuiteSparse_long i = 0; i < nb; i++) {
    p[i] = at;
    for (cupid_int k = K->rowptr[i]; k < K->rowptr[i + 1]; k++)
      if (K->col[k] >= i) ri[at++] = K->col[k];
  }
  p[nb] = at;
  return A;
}

/* METIS's nested dissection of the node graph, each node's 3 DOFs kept together (CHOLMOD
 * orders the scalar graph, 3 times larger, whose nodes' DOFs METIS may separate). */
static SuiteSparse_long *node_metis_perm(const cupid_csr_t *K) {
  cholmod_common c;
  cholmod_l_start(&c);
  cholmod_sparse *G = node_pattern(K, &c);
  const size_t nb = (size_t)K->nrows;
  SuiteSparse_long *pn = malloc(nb * sizeof *pn), *perm = malloc(3 * nb * sizeof *perm);
  int ok = G && pn && perm && cholmod_l_metis(G, NULL, 0, 1, pn, &c);
  if (ok)
    for (size_t k = 0; k < nb; k++)
      for (int a = 0; a < 3; a++) perm[3 * k + (size_t)a] = 3 * pn[k] + a;
  cholmod_l_free_sparse(&G, &c);
  cholmod_l_finish(&c);
  free(pn);
  if (!ok) {
    free(perm);
    return NULL;
  }
  return perm;
}

static void analyse(cholmod_sparse *A, const char *name, int ordering, SuiteSparse_long *perm) {
  cholmod_common c;
  cholmod_l_start(&c);
  c.print = 0;
  c.supernodal = CHOLMOD_SUPERNODAL;
  if (ordering >= 0) {
    c.nmethods = 1;
    c.method[0].ordering = ordering;
    c.postorder = 1;
  }
  const double t0 = cupid_wtime();
  cholmod_factor *L = perm ? cholmod_l_analyze_p(A, perm, NULL, 0, &c) : cholmod_l_analyze(A, &c);
  const double t = cupid_wtime() - t0;
  if (!L) {
    printf("| %-18s | analysis failed (status %d) | | | | | |\n", name, c.status);
  } else {
    const double lnz = c.lnz, gb = 1e-9;
    printf("| %-18s | %10.3e | %10.3e | %6.2f | %6.2f | %6.2f | %6.1f |\n", name, lnz, c.fl,
           8 * lnz * gb, 16 * lnz * gb, 24 * lnz * gb, t);
    cholmod_l_free_factor(&L, &c);
  }
  cholmod_l_finish(&c);
}

int main(int argc, char **argv) {
  const char *path = NULL;
  const char **sets = calloc((size_t)argc, sizeof *sets);
  int n_sets = 0, threads = 0;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--set") && i + 1 < argc) sets[n_sets++] = argv[++i];
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
    else if (argv[i][0] != '-' && !path) path = argv[i];
  }
  if (!path) {
    fprintf(stderr, "usage: bench_factor_fill MODEL [--set key=value ...] [--threads N]\n");
    return 2;
  }
  cupid_set_num_threads(threads);
  cupid_run_options ro = cupid_run_options_default();
  ro.quiet = 1;
  ro.solver = CUPID_SOLVER_DIRECT;
  ro.max_memory_gb = 1e6; /* the analysis needs none of what the limit guards */
  ro.sets = sets;
  ro.n_sets = n_sets;
  cupid_problem prob = NULL;
  check(cupid_problem_create_from_file(path, &ro, &prob), "model");
  check(cupid_problem_setup(prob), "setup");
  cupid_problem_system sys;
  check(cupid_problem_get_system(prob, &sys), "system");
  if (!sys.op) {
    fprintf(stderr, "bench_factor_fill: the model has no peridynamics\n");
    return 2;
  }
  cupid_csr K = NULL;
  check(cupid_pd_operator_assemble(sys.op, &K), "assemble");
  const double blocks = (double)K->rowptr[K->nrows];
  printf("model %s: %lld PD nodes, K %.4g 3x3 blocks (%.3e entries in its lower triangle), "
         "peak %.2f GB so far\n\n",
         path, (long long)K->nrows, blocks, 4.5 * blocks + 1.5 * (double)K->nrows,
         (double)cupid_peak_memory() * 1e-9);
  const double t0 = cupid_wtime();
  SuiteSparse_long *perm = node_metis_perm(K);
  const double t_perm = cupid_wtime() - t0;
  cholmod_common c;
  cholmod_l_start(&c);
  cholmod_sparse *A = lower_pattern(K, &c);
  cupid_csr_destroy(&K);
  cupid_problem_destroy(&prob);
  if (!A) {
    fprintf(stderr, "bench_factor_fill: out of memory for the pattern\n");
    return 1;
  }
  printf("| ordering | factor entries | flops | values GB | simplicial GB | growth GB | "
         "analysis s |\n|---|---:|---:|---:|---:|---:|---:|\n");
  analyse(A, "default", -1, NULL);
  analyse(A, "AMD", CHOLMOD_AMD, NULL);
  analyse(A, "METIS", CHOLMOD_METIS, NULL);
  analyse(A, "NESDIS", CHOLMOD_NESDIS, NULL);
  if (perm) {
    analyse(A, "METIS on the nodes", CHOLMOD_GIVEN, perm);
    printf("\n(METIS on the node graph: %.1f s before the analysis)\n", t_perm);
  }
  free(perm);
  cholmod_l_free_sparse(&A, &c);
  cholmod_l_finish(&c);
  free(sets);
  return 0;
}
