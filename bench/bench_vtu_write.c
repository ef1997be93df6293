/* Benchmark of the VTU writer (src/io/vtu.c): 10^6 PD-like nodes as vertex cells with a
 * displacement (3 components) and a damage (1) array, base64-encoded appended data, as
 * pd.vtu of a large grid. Prints the file size, the best and median wall time of several
 * writes and the write rate. The target of the VTU issue was "well under a second" for this
 * size; per-value text writes take ~10 s.
 * Then the output writers (io.h) on a series of FRAMES frames of the same nodes: the VTU series
 * (a pd_<step>.vtu per frame and the .pvd) against the Exodus II file (a time step per frame;
 * issue 35 asks at most 2x the VTU files' time), best and median of the repeats.
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
  double vol = 1.0;
  double *volume = malloc(sizeof(double) * (size_t)n);
  for (cupid_int i = 0; volume && i < n; i++) volume[i] = vol;
  const cupid_writer_type *types_w[2] = {&cupid_writer_vtu, &cupid_writer_exodus};
  const char *files[2] = {"bench_series.pvd", "bench_series.exo"};
  enum { FRAMES = 5 };
  double best[2] = {0, 0}, median[2] = {0, 0};
  for (int w = 0; w < 2 && volume; w++) {
    if (!cupid_writer_available(types_w[w])) continue;
    for (int r = 0; r < reps; r++) {
      cupid_writer wr = NULL;
      const cupid_writer_spec spec = {.dir = dir, .file = files[w], .title = "bench"};
      double t0 = cupid_wtime();
      cupid_status st = cupid_writer_create(types_w[w], &spec, &wr);
      for (int f = 0; f < FRAMES && st == CUPID_SUCCESS; f++) {
        const cupid_frame_part part = {"pd", &mesh, volume};
        const cupid_frame frame = {.step = f, .time = f, .n_parts = 1, .parts = &part};
        st = cupid_writer_step(wr, &frame);
      }
      if (st == CUPID_SUCCESS) st = cupid_writer_end(&wr);
      times[r] = cupid_wtime() - t0;
      if (st != CUPID_SUCCESS) {
        fprintf(stderr, "bench_vtu_write: %s\n", cupid_error_message());
        return 3;
      }
    }
    qsort(times, (size_t)reps, sizeof *times, cmp);
    best[w] = times[0], median[w] = times[reps / 2];
  }
  char cmd[4200];
  snprintf(cmd, sizeof cmd, "rm -f '%s'/pd_0000*.vtu '%s'/bench_series.pvd '%s'/bench_series.exo",
           dir, dir, dir);
  if (system(cmd) != 0) fprintf(stderr, "bench_vtu_write: could not remove the series\n");
  printf("\n| writer, %d frames of %lld nodes | best s | median s |\n|---|---|---|\n", FRAMES,
         (long long)n);
  printf("| vtu (pd_<step>.vtu + .pvd) | %.3f | %.3f |\n", best[0], median[0]);
  if (best[1] > 0)
    printf("| exodus (model.exo) | %.3f | %.3f |\n| exodus / vtu | %.2f | %.2f |\n", best[1],
           median[1], best[1] / best[0], median[1] / median[0]);
  else
    printf("| exodus | not in this build | |\n");
  free(volume);
  free(points), free(u), free(damage), free(conn), free(offs), free(types);
  return 0;
}
