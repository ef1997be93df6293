/* The output writers (io.h, "Output writers"; issue 35): the table behind the runs' files.
 * Each case can fail:
 *  - CSV: the header, reals as %.10e and counts as integers; interrupted after a checkpoint
 *    (a row written after it, the writer dropped and kept), resumed from the checkpoint and
 *    ended: the file of the uninterrupted writer, byte for byte;
 *  - VTU: PART_<step>.vtu per part and frame, and the .pvd listing them with their times; a
 *    resumption lists the files written before its checkpoint;
 *  - Exodus II (where built): three frames of two parts, and the same three with a checkpoint
 *    after the first, the second written, the writer dropped, resumed, the second and third
 *    written again: the same bytes; the refusals (mixed cell types, a cell type Exodus blocks
 *    are not written for, a frame whose points differ from the first's);
 *  - a writer of a type the build lacks: CUPID_ERR_UNSUPPORTED naming the package. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cupid/io.h"
#include "testutil.h"

static char dir[256];

static int setup(void **state) {
  (void)state;
  assert_int_equal(cupid_test_mkdtemp("writers", dir, sizeof dir), 0);
  return 0;
}

static int teardown(void **state) {
  (void)state;
  cupid_test_rmtree(dir);
  return 0;
}

static char *slurp(const char *name, size_t *len) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "rb");
  assert_non_null(f);
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *s = calloc((size_t)n + 1, 1);
  assert_non_null(s);
  assert_int_equal(fread(s, 1, (size_t)n, f), (size_t)n);
  fclose(f);
  *len = (size_t)n;
  return s;
}

static cupid_status save(cupid_writer w, const char *ck) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, ck);
  cupid_checkpoint_writer ckw = NULL;
  CUPID_CALL(cupid_checkpoint_write_begin(path, "writers", &ckw));
  cupid_status st = cupid_writer_save(w, ckw);
  if (st != CUPID_SUCCESS) {
    cupid_checkpoint_write_abort(&ckw);
    return st;
  }
  return cupid_checkpoint_write_commit(&ckw);
}

static cupid_checkpoint open_ck(const char *ck) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, ck);
  cupid_checkpoint c = NULL;
  CUPID_ASSERT_OK(cupid_checkpoint_open(path, "writers", &c));
  return c;
}

static const cupid_column columns[3] = {{"step", 1}, {"t", 0}, {"count", 1}};

static void csv_rows(cupid_writer w, int from, int to) {
  for (int k = from; k < to; k++) {
    const double row[3] = {k, 0.1 * k, 1000.0 * k};
    const cupid_frame f = {.step = k, .time = 0.1 * k, .row = row};
    CUPID_ASSERT_OK(cupid_writer_step(w, &f));
  }
}

static void csv_resumed(void **state) {
  (void)state;
  cupid_writer w = NULL;
  cupid_writer_spec spec = {.dir = dir, .file = "a.csv", .columns = columns, .n_columns = 3,
                            .key = "writer a.csv"};
  CUPID_ASSERT_OK(cupid_writer_create(&cupid_writer_csv, &spec, &w));
  csv_rows(w, 0, 4);
  CUPID_ASSERT_OK(cupid_writer_end(&w));
  size_t n_ref;
  char *ref = slurp("a.csv", &n_ref);
  assert_non_null(strstr(ref, "step,t,count\n0,0.0000000000e+00,0\n1,1.0000000000e-01,1000\n"));
  /* the same into b.csv: a checkpoint after two rows, a third written, the writer dropped */
  spec.file = "b.csv", spec.key = "writer b.csv";
  CUPID_ASSERT_OK(cupid_writer_create(&cupid_writer_csv, &spec, &w));
  csv_rows(w, 0, 2);
  CUPID_ASSERT_OK(save(w, "b.ck"));
  csv_rows(w, 2, 3);
  cupid_writer_drop(&w, 1);
  spec.resume = open_ck("b.ck");
  CUPID_ASSERT_OK(cupid_writer_create(&cupid_writer_csv, &spec, &w));
  cupid_checkpoint_close(&spec.resume);
  csv_rows(w, 2, 4);
  CUPID_ASSERT_OK(cupid_writer_end(&w));
  size_t n;
  char *got = slurp("b.csv", &n);
  assert_int_equal(n, n_ref);
  assert_memory_equal(got, ref, n);
  free(got);
  free(ref);
}

/* Two parts: a hexahedron (8 points) and three vertices. */
static double hex_points[24], vtx_points[9], hex_u[24], vtx_u[9], vtx_vol[3] = {1, 2, 3};
static cupid_int hex_conn[8] = {0, 1, 2, 3, 4, 5, 6, 7}, hex_offs[1] = {8};
static cupid_int vtx_conn[3] = {0, 1, 2}, vtx_offs[3] = {1, 2, 3};
static unsigned char hex_types[1] = {CUPID_VTK_HEXAHEDRON};
static unsigned char vtx_types[3] = {CUPID_VTK_VERTEX, CUPID_VTK_VERTEX, CUPID_VTK_VERTEX};

static void frame_at(int k, cupid_vtu_mesh *hex, cupid_vtu_mesh *vtx, cupid_vtu_array *hd,
                     cupid_vtu_array *vd, cupid_frame_part *parts, cupid_frame *f) {
  for (int p = 0; p < 8; p++)
    for (int c = 0; c < 3; c++) hex_points[3 * p + c] = (p >> c) & 1, hex_u[3 * p + c] = k * 0.5 + p;
  for (int p = 0; p < 3; p++)
    for (int c = 0; c < 3; c++) vtx_points[3 * p + c] = 2 + p + c, vtx_u[3 * p + c] = -k - 0.25 * p;
  hd[0] = (cupid_vtu_array){"displacement", 3, hex_u};
  vd[0] = (cupid_vtu_array){"displacement", 3, vtx_u};
  vd[1] = (cupid_vtu_array){"damage", 1, vtx_vol};
  *hex = (cupid_vtu_mesh){.n_points = 8, .points = hex_points, .n_cells = 1,
                          .connectivity = hex_conn, .offsets = hex_offs, .types = hex_types,
                          .point_data = hd, .n_point_data = 1};
  *vtx = (cupid_vtu_mesh){.n_points = 3, .points = vtx_points, .n_cells = 3,
                          .connectivity = vtx_conn, .offsets = vtx_offs, .types = vtx_types,
                          .point_data = vd, .n_point_data = 2};
  parts[0] = (cupid_frame_part){"beam", hex, NULL};
  parts[1] = (cupid_frame_part){"pd", vtx, vtx_vol};
  *f = (cupid_frame){.step = 10 * k, .time = 0.5 * k, .n_parts = 2, .parts = parts};
}

static void frames(cupid_writer w, int from, int to) {
  for (int k = from; k < to; k++) {
    cupid_vtu_mesh hex, vtx;
    cupid_vtu_array hd[1], vd[2];
    cupid_frame_part parts[2];
    cupid_frame f;
    frame_at(k, &hex, &vtx, hd, vd, parts, &f);
    CUPID_ASSERT_OK(cupid_writer_step(w, &f));
  }
}

static void vtu_series(void **state) {
  (void)state;
  cupid_writer w = NULL;
  cupid_writer_spec spec = {.dir = dir, .file = "model.pvd", .key = "writer model.pvd"};
  CUPID_ASSERT_OK(cupid_writer_create(&cupid_writer_vtu, &spec, &w));
  frames(w, 0, 1);
  CUPID_ASSERT_OK(save(w, "v.ck"));
  frames(w, 1, 2);
  cupid_writer_drop(&w, 1);
  spec.resume = open_ck("v.ck");
  CUPID_ASSERT_OK(cupid_writer_create(&cupid_writer_vtu, &spec, &w));
  cupid_checkpoint_close(&spec.resume);
  frames(w, 1, 3);
  CUPID_ASSERT_OK(cupid_writer_end(&w));
  size_t n;
  char *pvd = slurp("model.pvd", &n);
  const char *want[6] = {"beam_000000.vtu", "pd_000000.vtu", "beam_000010.vtu",
                         "pd_000010.vtu", "beam_000020.vtu", "pd_000020.vtu"};
  const char *at = pvd;
  for (int k = 0; k < 6; k++) { /* each once, in order */
    const char *hit = strstr(at, want[k]);
    assert_non_null(hit);
    assert_null(strstr(hit + 1, want[k]));
    at = hit;
  }
  assert_non_null(strstr(pvd, "timestep=\"1\""));
  free(pvd);
  free(slurp("pd_000020.vtu", &n));
}

static void exodus_resumed(void **state) {
  (void)state;
  cupid_writer w = NULL;
  cupid_writer_spec spec = {.dir = dir, .file = "a.exo", .title = "t", .key = "writer exo"};
  if (!cupid_writer_available(&cupid_writer_exodus)) {
    assert_int_equal(cupid_writer_create(&cupid_writer_exodus, &spec, &w), CUPID_ERR_UNSUPPORTED);
    assert_non_null(strstr(cupid_error_message(), "libexodusii"));
    cupid_error_clear();
    skip();
  }
  CUPID_ASSERT_OK(cupid_writer_create(&cupid_writer_exodus, &spec, &w));
  frames(w, 0, 3);
  CUPID_ASSERT_OK(cupid_writer_end(&w));
  size_t n_ref;
  char *ref = slurp("a.exo", &n_ref);
  spec.file = "b.exo";
  CUPID_ASSERT_OK(cupid_writer_create(&cupid_writer_exodus, &spec, &w));
  frames(w, 0, 1);
  CUPID_ASSERT_OK(save(w, "e.ck"));
  frames(w, 1, 2);
  cupid_writer_drop(&w, 1);
  char partial[512];
  snprintf(partial, sizeof partial, "%s/.b.exo.partial", dir);
  assert_int_equal(access(partial, F_OK), 0); /* kept for the resumption */
  spec.resume = open_ck("e.ck");
  CUPID_ASSERT_OK(cupid_writer_create(&cupid_writer_exodus, &spec, &w));
  cupid_checkpoint_close(&spec.resume);
  frames(w, 1, 3);
  CUPID_ASSERT_OK(cupid_writer_end(&w));
  assert_int_equal(access(partial, F_OK), -1);
  size_t n;
  char *got = slurp("b.exo", &n);
  assert_int_equal(n, n_ref);
  assert_memory_equal(got, ref, n);
  free(got);
  free(ref);
}

static void exodus_refusals(void **state) {
  (void)state;
  if (!cupid_writer_available(&cupid_writer_exodus)) skip();
  cupid_vtu_mesh hex, vtx;
  cupid_vtu_array hd[1], vd[2];
  cupid_frame_part parts[2];
  cupid_frame f;
  cupid_writer w = NULL;
  const cupid_writer_spec spec = {.dir = dir, .file = "r.exo", .key = "writer exo"};
  /* mixed cell types in a part */
  frame_at(0, &hex, &vtx, hd, vd, parts, &f);
  unsigned char mixed[3] = {CUPID_VTK_VERTEX, CUPID_VTK_LINE, CUPID_VTK_VERTEX};
  vtx.types = mixed;
  CUPID_ASSERT_OK(cupid_writer_create(&cupid_writer_exodus, &spec, &w));
  assert_int_equal(cupid_writer_step(w, &f), CUPID_ERR_ARGUMENT);
  assert_non_null(strstr(cupid_error_message(), "mixes cell types"));
  cupid_writer_drop(&w, 0);
  /* a cell type no block is written for */
  unsigned char quads[1] = {CUPID_VTK_QUAD};
  cupid_int quad_offs[1] = {4};
  frame_at(0, &hex, &vtx, hd, vd, parts, &f);
  hex.types = quads, hex.offsets = quad_offs;
  CUPID_ASSERT_OK(cupid_writer_create(&cupid_writer_exodus, &spec, &w));
  assert_int_equal(cupid_writer_step(w, &f), CUPID_ERR_ARGUMENT);
  assert_non_null(strstr(cupid_error_message(), "vertices and hexahedra"));
  cupid_writer_drop(&w, 0);
  /* a second frame with other points */
  CUPID_ASSERT_OK(cupid_writer_create(&cupid_writer_exodus, &spec, &w));
  frames(w, 0, 1);
  frame_at(1, &hex, &vtx, hd, vd, parts, &f);
  vtx.n_points = 2, vtx.n_cells = 2;
  assert_int_equal(cupid_writer_step(w, &f), CUPID_ERR_ARGUMENT);
  assert_non_null(strstr(cupid_error_message(), "the first had"));
  cupid_writer_drop(&w, 0);
  char partial[512];
  snprintf(partial, sizeof partial, "%s/.r.exo.partial", dir);
  assert_int_equal(access(partial, F_OK), -1); /* dropped: removed */
  cupid_error_clear();
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(csv_resumed, setup, teardown),
      cmocka_unit_test_setup_teardown(vtu_series, setup, teardown),
      cmocka_unit_test_setup_teardown(exodus_resumed, setup, teardown),
      cmocka_unit_test_setup_teardown(exodus_refusals, setup, teardown)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
