/* Benchmark of the VTU writer (src/io/vtu.c): 10^6 PD-like nodes as vertex cells with a
 * displacement (3 components) and a damage (1) array, base64-encoded appended data, as
 * pd.vtu of a large grid. Prints the file size, the best and median wall time of several
 * writes and the write rate. The target of the VTU issue was "well under a second" for this
 * size; per-value text writes take ~10 s.
 *
 * usage: bench_vtu_write [nodes (default 1000000)] [repeats (default 5)] [directory (default .)] */
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>

#include "cupid.h"
#include "cupid/io.h"

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

int main(int argc, char **argv) {
  cupid_int n = argc > 1 ? atoll(argv[1]) : 1000000;
  int reps = argc > 2 ? atoi(argv[2]) : 5;
  const char *dir = argc > 3 ? argv[3] : ".";
  if (n < 1 || reps < 1 || reps > 100) {
    fprintf(stderr, "usage: bench_vtu_write [nodes >= 1] [repeats 1..100] [directory]\n");
    return 1;
  }
  double *points = malloc(sizeof(double) * 3 * (size_t)n), *u = malloc(sizeof(double) * 3 * (size_t)n);
  double *damage = malloc(sizeof(double) * (size_t)n), times[100];
  cupid_int *conn = malloc(sizeof(cupid_int) * (size_t)n), *offs = malloc(sizeof(cupid_int) * (size_t)n);
  unsigned char *types = malloc((size_t)n);
  if (!points || !u || !damage || !conn || !offs || !types) {
    fprintf(stderr, "bench_vtu_write: out of memory\n");
    return 2;
  }
  for (cupid_int i = 0; i < n; i++) {
    for (int d = 0; d < 3; d++) points[3 * i + d] = (double)(i % 100 + d), u[3 * i + d] = 1e-6 * (double)i;
    damage[i] = (double)(i % 7) / 7.0;
    conn[i] = i, offs[i] = i + 1, types[i] = CUPID_VTK_VERTEX;
  }
  cupid_vtu_array pd[] = {{"u", 3, u}, {"damage", 1, damage}};
  cupid_vtu_mesh mesh = {.n_points = n, .points = points, .n_cells = n, .connectivity = conn,
                         .offsets = offs, .types = types, .point_data = pd, .n_point_data = 2};
  char path[4096];
  snprintf(path, sizeof path, "%s/bench_vtu_write.vtu", dir);
  for (int r = 0; r < reps; r++) {
    double t0 = cupid_wtime();
    if (cupid_vtu_write(path, &mesh) != CUPID_SUCCESS) {
      fprintf(stderr, "bench_vtu_write: %s\n", cupid_error_message());
      return 3;
    }
    times[r] = cupid_wtime() - t0;
  }
  struct stat sb;
  double mb = stat(path, &sb) == 0 ? (double)sb.st_size / 1e6 : 0.0;
  remove(path);
  qsort(times, (size_t)reps, sizeof *times, cmp);
  printf("| nodes | MB | best s | median s | MB/s (best) |\n|---|---|---|---|---|\n");
  printf("| %lld | %.1f | %.3f | %.3f | %.0f |\n", (long long)n, mb, times[0], times[reps / 2],
         mb / times[0]);
  free(points), free(u), free(damage), free(conn), free(offs), free(types);
  return 0;
}
