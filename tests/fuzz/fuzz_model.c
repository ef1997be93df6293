/* Fuzz target for the model reader and the validation that follows it (docs/hardening.md).
 *
 * Built two ways:
 *  - with clang and -DCUPID_FUZZ=ON as a libFuzzer binary (cupid_fuzz_model): the engine
 *    calls LLVMFuzzerTestOneInput with mutated inputs, seeded by every example and test model;
 *  - with any compiler as a replay driver (cupid_fuzz_replay, CUPID_FUZZ_REPLAY defined): its
 *    main() feeds every file named on the command line (directories are walked) through the
 *    same function. ctest runs it on the seed corpus and on tests/fuzz/regressions/, where
 *    every input that once crashed or hung is kept, so each finding stays a regression test
 *    in the normal (and the sanitizer) build.
 *
 * For each input: cupid_model_read_string(); on success the model's values are evaluated and,
 * when the PD grid is small enough to build in well under a millisecond, the grid, the operator
 * estimate and `cupid check`'s pipeline (cupid_run_model with check_only) run on it. Sizes are
 * bounded before anything is allocated so the fuzzer never spends its time (or memory) on
 * legitimately huge models: those are covered by tests/unit/limits.sh. */
#define _POSIX_C_SOURCE 200809L /* setenv */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cupid/problem.h"
#include "cupid/model.h"
#include "cupid/pd.h"

/* Bounds for the post-read stages (cells of the PD bounding box; nodes x stencil offsets). */
#define FUZZ_MAX_CELLS 4096.0
#define FUZZ_MAX_WORK 2.0e5

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv);

/* What the inputs reached (printed by the replay driver). */
static long n_accepted, n_grids, n_checks;

/* Evaluate every value of the model at a few points: constant folding and the evaluator
 * must cope with whatever expression the reader accepted (inf/nan are fine, crashes not). */
static double eval_values(const cupid_model_t *m) {
  static const double pts[3][4] = {{0, 0, 0, 0}, {1.5, -2.25, 1e3, 0.5}, {-1e-300, 1e300, 3, 1}};
  double acc = 0;
  for (int p = 0; p < 3; p++) {
    const double *x = pts[p];
    for (int c = 0; c < m->n_constraints; c++)
      for (int k = 0; k < 3; k++)
        acc += cupid_value_eval(&m->constraints[c].value[k], x[0], x[1], x[2], x[3], 1.0);
    for (int l = 0; l < m->n_loads; l++)
      for (int k = 0; k < 3; k++)
        acc += cupid_value_eval(&m->loads[l].value[k], x[0], x[1], x[2], x[3], 1.0);
    for (int k = 0; k < 3; k++) {
      acc += cupid_value_eval(&m->analysis.field[k], x[0], x[1], x[2], x[3], 2.0);
      acc += cupid_value_eval(&m->analysis.dynamic.initial_displacement[k], x[0], x[1], x[2],
                              x[3], 2.0);
      acc += cupid_value_eval(&m->analysis.dynamic.initial_velocity[k], x[0], x[1], x[2], x[3],
                              2.0);
    }
    for (int c = 0; c < m->n_constraints; c++)
      acc += cupid_box_contains(&m->constraints[c].box, x, 1e-9);
  }
  return acc;
}

/* Cells of the bounding box of the PD regions, computed from the model alone (no allocation);
 * +inf when a bound is missing or not finite (the grid builder reports those). */
static double pd_cells(const cupid_model_t *m) {
  const cupid_peridynamics *pd = &m->pd;
  if (!m->has_peridynamics || pd->n_regions <= 0 || !(pd->spacing > 0)) return INFINITY;
  double cells = 1;
  for (int a = 0; a < 3; a++) {
    if (pd->dimension == 1 && a != 1) continue;
    double lo = INFINITY, hi = -INFINITY;
    for (int r = 0; r < pd->n_regions; r++) {
      const cupid_box *b = &pd->regions[r].box;
      if (!b->has[a]) return INFINITY;
      lo = fmin(lo, b->lo[a]);
      hi = fmax(hi, b->hi[a]);
    }
    cells *= (hi - lo) / pd->spacing + 1;
  }
  return isfinite(cells) ? cells : INFINITY;
}

/* Point-in-region tests of the output lines and points (cupid_problem_check_points samples up to
 * every point of a line): the app refuses more than 2e8 (src/problem/estimate.c, guard_output), which
 * still take seconds under ASan; only the refusal and small counts are exercised here. */
static int sampling_ok(const cupid_model_t *m) {
  double points = m->output.n_points;
  for (int k = 0; k < m->output.n_lines; k++) points += m->output.lines[k].points;
  double work = points * (m->pd.n_regions > 0 ? m->pd.n_regions : 1);
  return work <= 1e6 || work > 2e8;
}

/* A beam small enough for `cupid check` to build in a few milliseconds (once CUF beams run:
 * elements along the axis times expansion functions of the section). */
static int beam_small(const cupid_model_t *m) {
  if (!m->has_beam) return 1;
  const cupid_beam *b = &m->beam;
  double elements = 0, terms = 0;
  for (int i = 0; i + 1 < b->n_axis; i++) elements += b->axis_elements[i];
  if (b->expansion == CUPID_EXPANSION_TE) {
    terms = (b->te_order + 1.0) * (b->te_order + 2.0) / 2;
  } else {
    terms = b->n_section_nodes;
    for (int c = 0; c < b->n_components; c++)
      terms += (double)b->components[c].nx * b->components[c].nz * b->le_nodes;
  }
  return elements * b->element_nodes <= 64 && terms <= 64;
}

static void exercise_pd(const cupid_model_t *m) {
  if (!sampling_ok(m) || !beam_small(m)) return;
  double cells = pd_cells(m);
  if (!(cells <= FUZZ_MAX_CELLS)) return;
  double ratio = m->pd.horizon / m->pd.spacing;
  if (!(ratio > 0 && ratio <= 6)) return;
  /* Stencil offsets: ~4.2 m^3 in 3D (x8 for the LPS two-hop sum), 2m in 1D. */
  double stencil = m->pd.dimension == 1 ? 2 * ratio + 1 : 4.2 * ratio * ratio * ratio + 1;
  if (m->pd.model == CUPID_PD_LPS) stencil *= 8;
  cupid_pd_grid grid = NULL;
  if (cupid_pd_grid_create_from_model(m, &grid) == CUPID_SUCCESS) {
    n_grids++;
    cupid_int n = cupid_pd_grid_num_nodes(grid);
    if ((double)n * stencil <= FUZZ_MAX_WORK) {
      cupid_pd_material *mats = calloc((size_t)m->n_materials + 1, sizeof *mats);
      if (mats) {
        for (int i = 0; i < m->n_materials; i++)
          mats[i] = (cupid_pd_material){.E = m->materials[i].E, .nu = m->materials[i].nu};
        cupid_pd_operator_options o = {.horizon = m->pd.horizon,
                                       .model = m->pd.model,
                                       .influence = m->pd.influence,
                                       .partial_volume = m->pd.partial_volume,
                                       .materials = mats,
                                       .n_materials = m->n_materials};
        cupid_pd_estimate est;
        (void)cupid_pd_operator_estimate(grid, &o, &est);
        free(mats);
        /* `cupid check`: supported features, grid, operator, output points, estimate. */
        cupid_run_options ro = {.solver = -1, .quiet = 1, .check_only = 1, .threads = 1};
        (void)cupid_run_model(m, &ro);
        n_checks++;
      }
    }
  }
  cupid_pd_grid_destroy(&grid);
}

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc;
  (void)argv;
  /* `cupid check` prints its counts on stdout: keep the fuzzer's output readable. */
  if (!freopen("/dev/null", "w", stdout)) return 0;
  cupid_set_num_threads(1);
  /* Gmsh's and Exodus II's libraries (beam.section.mesh, {geometry: FILE}, output.exodus)
   * stay out: loaded during an input (a fuzzed path that opens, ".", or exodus: true), what
   * they keep for the process's life would read as that input's leaks. The reader's side of
   * those keys (the path, the file check, the refusal) is still fuzzed. */
  setenv("CUPID_GMSH_LIBRARY", "/nonexistent/libgmsh-fuzzing.so", 1);
  setenv("CUPID_EXODUS_LIBRARY", "/nonexistent/libexodus-fuzzing.so", 1);
  return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  cupid_model m = NULL;
  cupid_status st = cupid_model_read_string((const char *)data, size, "fuzz.yaml", &m);
  if (st == CUPID_SUCCESS) {
    n_accepted++;
    volatile double sink = eval_values(m);
    (void)sink;
    exercise_pd(m);
  } else if (m != NULL || (st != CUPID_ERR_MODEL && st != CUPID_ERR_MEMORY)) {
    /* The reader's contract: a model error (or out of memory), and no model. */
    fprintf(stderr, "fuzz: status %d, model %p: %s\n", (int)st, (void *)m, cupid_error_message());
    abort();
  } else if (strncmp(cupid_error_message(), "fuzz.yaml:", 10) != 0) {
    fprintf(stderr, "fuzz: model error without a position: %s\n", cupid_error_message());
    abort();
  }
  cupid_model_destroy(&m);
  return 0;
}

#ifdef CUPID_FUZZ_REPLAY
#include <dirent.h>
#include <sys/stat.h>

static int replay_file(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "cannot open %s\n", path);
    return 1;
  }
  size_t cap = 1 << 16, n = 0;
  uint8_t *buf = malloc(cap);
  for (size_t k; buf && (k = fread(buf + n, 1, cap - n, f)) > 0;) {
    n += k;
    if (n == cap) {
      uint8_t *grown = realloc(buf, cap *= 2);
      if (!grown) free(buf);
      buf = grown;
    }
  }
  fclose(f);
  if (!buf) return 1;
  LLVMFuzzerTestOneInput(buf, n);
  free(buf);
  return 0;
}

static int replay(const char *path, int *count) {
  struct stat sb;
  if (stat(path, &sb) != 0) {
    fprintf(stderr, "cannot stat %s\n", path);
    return 1;
  }
  if (!S_ISDIR(sb.st_mode)) {
    (*count)++;
    return replay_file(path);
  }
  DIR *d = opendir(path);
  if (!d) return 1;
  int bad = 0;
  for (struct dirent *e; (e = readdir(d));) {
    if (e->d_name[0] == '.') continue;
    size_t len = strlen(path) + strlen(e->d_name) + 2;
    char *child = malloc(len);
    if (!child) {
      bad = 1;
      break;
    }
    snprintf(child, len, "%s/%s", path, e->d_name);
    bad |= replay(child, count);
    free(child);
  }
  closedir(d);
  return bad;
}

int main(int argc, char **argv) {
  LLVMFuzzerInitialize(&argc, &argv);
  int count = 0, bad = 0;
  for (int i = 1; i < argc; i++) bad |= replay(argv[i], &count);
  fprintf(stderr,
          "fuzz replay: %d inputs, no crash; %ld models accepted, %ld PD grids built, %ld checks "
          "run\n",
          count, n_accepted, n_grids, n_checks);
  return bad || count == 0;
}
#endif
