/* Benchmark of the CUF beam solver on the C-section beam of shared/reference/examples.md
 * section 2 (FE only): web x [0,5] z [-50,50], flanges x [5,50] z [45,50] and [-50,-45],
 * y [0,1000], E = 200000, nu = 0.2, clamp y = 0, -20 MPa on x [40,50] z [45,50] of y = 1000;
 * 12 B4 elements (5 on [0,490], 2 on [490,510], 5 on [510,1000]).
 * Models: TE1, TE4, TE8 and L9 sections of growing refinement. Prints a markdown table:
 * DOFs, stiffness non-zeros, assembly / factorisation / solve time, memory, u_z at A and B.
 *
 * usage: bench_cuf [max_L9_level (default 4)] [integration 0|1|2 (default 0)] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cupid.h"
#include "cupid/cuf.h"

typedef struct {
  cupid_beam def;
  cupid_section_component comp[3];
  double x[3][64], z[3][160];
  double axis_y[4];
  int axis_el[3];
  cupid_material mat;
} c_beam;

static void breakpoints(double *out, int *count, double a, double b, int n) {
  for (int i = 0; i <= n; i++) out[(*count)++] = a + (b - a) * i / n;
  (*count)--; /* the next segment starts at b */
}

/* Level r: web r cells across, r / 6r / r along z; flanges 3r x r cells. */
static void c_section(c_beam *c, int te_order, int level, int integration) {
  memset(c, 0, sizeof *c);
  c->mat.name = (char *)"steel";
  c->mat.E = 200000;
  c->mat.nu = 0.2;
  c->def.material = 0;
  c->def.expansion = te_order >= 0 ? CUPID_EXPANSION_TE : CUPID_EXPANSION_LE;
  c->def.te_order = te_order;
  c->def.le_nodes = 9;
  c->def.element_nodes = 4;
  c->def.integration = integration;
  double ay[4] = {0, 490, 510, 1000};
  int ae[3] = {5, 2, 5};
  memcpy(c->axis_y, ay, sizeof ay);
  memcpy(c->axis_el, ae, sizeof ae);
  c->def.axis_y = c->axis_y;
  c->def.axis_elements = c->axis_el;
  c->def.n_axis = 4;
  int r = level < 1 ? 1 : level, n;
  /* web */
  n = 0;
  breakpoints(c->x[0], &n, 0, 5, r);
  c->comp[0].nx = n + 1;
  n = 0;
  breakpoints(c->z[0], &n, -50, -45, r);
  breakpoints(c->z[0], &n, -45, 45, 6 * r);
  breakpoints(c->z[0], &n, 45, 50, r);
  c->comp[0].nz = n + 1;
  /* flanges */
  for (int f = 1; f <= 2; f++) {
    n = 0;
    breakpoints(c->x[f], &n, 5, 50, 3 * r);
    c->comp[f].nx = n + 1;
    n = 0;
    breakpoints(c->z[f], &n, f == 1 ? 45 : -50, f == 1 ? 50 : -45, r);
    c->comp[f].nz = n + 1;
  }
  for (int k = 0; k < 3; k++) {
    c->comp[k].x = c->x[k];
    c->comp[k].z = c->z[k];
    c->comp[k].material = -1;
  }
  c->def.components = c->comp;
  c->def.n_components = 3;
}

static void traction(void *ctx, const double p[3], double density, double out[3]) {
  (void)ctx;
  (void)p;
  (void)density;
  out[0] = out[1] = 0;
  out[2] = -20.0;
}

static int run(const char *name, int te_order, int level, int integration) {
  c_beam c;
  c_section(&c, te_order, level, integration);
  cupid_cuf_beam b = NULL;
  cupid_csr K = NULL;
  cupid_dirichlet bc = NULL;
  double *f = NULL, *u = NULL;
  cupid_status st = CUPID_SUCCESS;
  double t0 = cupid_wtime();
  CUPID_TRY(cupid_cuf_beam_create_from(&c.def, &c.mat, 1, &b));
  double t1 = cupid_wtime();
  CUPID_TRY(cupid_cuf_assemble(b, &K));
  double t2 = cupid_wtime();
  cupid_int n = cupid_cuf_num_dofs(b);
  CUPID_TRY(cupid_calloc((size_t)n, sizeof *f, "f", &f));
  CUPID_TRY(cupid_calloc((size_t)n, sizeof *u, "u", &u));
  cupid_box patch = {{40, 0, 45}, {50, 0, 50}, {1, 0, 1}};
  CUPID_TRY(cupid_cuf_traction_add(b, 1000, &patch, traction, NULL, f, NULL));
  CUPID_TRY(cupid_dirichlet_create(n, &bc));
  CUPID_TRY(cupid_cuf_clamp_node(b, 0, bc));
  CUPID_TRY(cupid_dirichlet_finalize(bc));
  cupid_solve_info info;
  double t3 = cupid_wtime();
  CUPID_TRY(cupid_direct_solve(K, CUPID_MATRIX_SPD, f, bc, u, &info));
  double t4 = cupid_wtime();
  double A[3], B[3];
  CUPID_TRY(cupid_cuf_displacement_at(b, u, 2.5, 1000, 0, A));
  CUPID_TRY(cupid_cuf_displacement_at(b, u, 45, 1000, 47.5, B));
  cupid_cuf_info bi;
  cupid_cuf_get_info(b, &bi);
  printf("| %-8s | %4lld | %7lld | %7.2f | %6.3f | %6.3f | %6.3f | %6.3f | %6.3f | %7.1f | %7.1f | %7.1f | %8.5f | %8.5f |\n",
         name, (long long)bi.M, (long long)n, (double)cupid_csr_nnz(K) / 1e6, t1 - t0, t2 - t1,
         info.time_factor, info.time_solve, t4 - t0 - (t3 - t2),
         (double)cupid_csr_bytes(K) / 1048576.0, (double)info.memory_factor / 1048576.0,
         (double)cupid_peak_memory() / 1048576.0, A[2], B[2]);
  fflush(stdout);
cleanup:
  if (st != CUPID_SUCCESS) fprintf(stderr, "%s: %s\n", name, cupid_error_message());
  cupid_free(&f);
  cupid_free(&u);
  cupid_dirichlet_destroy(&bc);
  cupid_csr_destroy(&K);
  cupid_cuf_beam_destroy(&b);
  return st != CUPID_SUCCESS;
}

int main(int argc, char **argv) {
  int max_level = argc > 1 ? atoi(argv[1]) : 4, integration = argc > 2 ? atoi(argv[2]) : 0, fail = 0;
  printf("C-section beam (examples.md 2), 12 B4 elements, integration %d, %d threads\n\n", integration,
         cupid_num_threads());
  printf("| model    | M    | DOFs    | nnz [M] | create | assem. | factor | solve  | total  | K [MB]  | L [MB]  | peak MB | u_z(A) [mm] | u_z(B) [mm] |\n");
  printf("|----------|------|---------|---------|--------|--------|--------|--------|--------|---------|---------|---------|----------|----------|\n");
  fail |= run("TE1", 1, 1, integration);
  fail |= run("TE4", 4, 1, integration);
  fail |= run("TE8", 8, 1, integration);
  for (int level = 1; level <= max_level; level++) {
    char name[32];
    snprintf(name, sizeof name, "L9 r=%d", level);
    fail |= run(name, -1, level, integration);
  }
  return fail;
}
