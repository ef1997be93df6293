#define _GNU_SOURCE /* mkdtemp, truncate */
/* Checkpoint files (issue 36; src/io/checkpoint.c): what a long run keeps to continue, and the
 * refusals of item 4. Each case can fail:
 *  - round trip: two checkpoints written in turn; the second reads back bit for bit, the first
 *    is kept as PATH.prev;
 *  - a flipped byte in PATH (anywhere: header, a section, the CRC): PATH.prev is used;
 *  - PATH.prev asked for (a rank a checkpoint ahead of the others under mpirun): its data
 *    though PATH is intact; another identity refused; damaged: CUPID_ERR_IO naming it;
 *  - PATH truncated and PATH.prev flipped: CUPID_ERR_IO, "no intact checkpoint";
 *  - no checkpoint: CUPID_ERR_IO, "nothing to resume";
 *  - another identity (the model or a result-changing option changed): CUPID_ERR_MODEL quoting
 *    both;
 *  - a disk that fills while writing (RLIMIT_FSIZE, SIGXFSZ ignored: the write fails with
 *    EFBIG as with ENOSPC): the commit fails with CUPID_ERR_IO and the last checkpoint still
 *    opens, whole, with its data;
 *  - a missing section, or one of another size: CUPID_ERR_IO. */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "cupid/io.h"
#include "testutil.h"

#define N 20000

static char dir[256], path[300], prev[320];
static double a[N], b[N];

static void fill(double *x, double s) {
  for (int k = 0; k < N; k++) x[k] = s + 1e-3 * k;
}

static cupid_status write_one(const char *identity, const double *x, long step) {
  cupid_checkpoint_writer w = NULL;
  CUPID_CALL(cupid_checkpoint_write_begin(path, identity, &w));
  cupid_status st = cupid_checkpoint_write(w, "step", &step, sizeof step);
  if (st == CUPID_SUCCESS) st = cupid_checkpoint_write(w, "u", x, N * sizeof *x);
  if (st != CUPID_SUCCESS) {
    cupid_checkpoint_write_abort(&w);
    return st;
  }
  return cupid_checkpoint_write_commit(&w);
}

/* Open with identity "model A" and check it holds x at step. */
static void expect_data(const double *x, long step, int previous) {
  cupid_checkpoint ck = NULL;
  CUPID_ASSERT_OK(cupid_checkpoint_open(path, "model A", &ck));
  assert_int_equal(cupid_checkpoint_is_previous(ck), previous);
  long s = 0;
  static double y[N];
  CUPID_ASSERT_OK(cupid_checkpoint_read(ck, "step", &s, sizeof s));
  CUPID_ASSERT_OK(cupid_checkpoint_read(ck, "u", y, sizeof y));
  assert_int_equal(s, step);
  assert_memory_equal(x, y, sizeof y);
  cupid_checkpoint_close(&ck);
}

static void flip(const char *p, long at) {
  FILE *f = fopen(p, "r+b");
  assert_non_null(f);
  fseek(f, at, SEEK_SET);
  int c = fgetc(f);
  fseek(f, at, SEEK_SET);
  fputc(c ^ 0x10, f);
  fclose(f);
}

static long size_of(const char *p) {
  FILE *f = fopen(p, "rb");
  assert_non_null(f);
  fseek(f, 0, SEEK_END);
  const long n = ftell(f);
  fclose(f);
  return n;
}

static void expect_error(cupid_status want, const char *identity, const char *text) {
  cupid_checkpoint ck = NULL;
  const cupid_status st = cupid_checkpoint_open(path, identity, &ck);
  assert_int_equal(st, want);
  assert_null(ck);
  printf("  %s\n", cupid_error_message());
  assert_non_null(strstr(cupid_error_message(), text));
  cupid_error_clear();
}

static int setup(void **state) {
  (void)state;
  snprintf(dir, sizeof dir, "/tmp/cupid_ck_XXXXXX");
  assert_non_null(mkdtemp(dir));
  snprintf(path, sizeof path, "%s/run.ck", dir);
  snprintf(prev, sizeof prev, "%s/run.ck.prev", dir);
  fill(a, 1.0);
  fill(b, 2.0);
  return 0;
}

static int teardown(void **state) {
  (void)state;
  unlink(path);
  unlink(prev);
  rmdir(dir);
  return 0;
}

static void refusals(void **state) {
  (void)state;
  expect_error(CUPID_ERR_IO, "model A", "nothing to resume");
  CUPID_ASSERT_OK(write_one("model A", a, 10));
  expect_data(a, 10, 0);
  CUPID_ASSERT_OK(write_one("model A", b, 20));
  expect_data(b, 20, 0);
  /* another identity */
  expect_error(CUPID_ERR_MODEL, "model B", "model B");
  /* a missing section, a section of another size */
  cupid_checkpoint ck = NULL;
  CUPID_ASSERT_OK(cupid_checkpoint_open(path, "model A", &ck));
  double v[3];
  assert_int_equal(cupid_checkpoint_read(ck, "v", v, sizeof v), CUPID_ERR_IO);
  cupid_error_clear();
  assert_int_equal(cupid_checkpoint_read(ck, "u", v, sizeof v), CUPID_ERR_IO);
  cupid_error_clear();
  cupid_checkpoint_close(&ck);
  /* PATH.prev asked for: the previous one though PATH is intact */
  static double y[N];
  long s = 0;
  CUPID_ASSERT_OK(cupid_checkpoint_open_previous(path, "model A", &ck));
  assert_int_equal(cupid_checkpoint_is_previous(ck), 1);
  CUPID_ASSERT_OK(cupid_checkpoint_read(ck, "step", &s, sizeof s));
  CUPID_ASSERT_OK(cupid_checkpoint_read(ck, "u", y, sizeof y));
  assert_int_equal(s, 10);
  assert_memory_equal(a, y, sizeof y);
  cupid_checkpoint_close(&ck);
  assert_int_equal(cupid_checkpoint_open_previous(path, "model B", &ck), CUPID_ERR_MODEL);
  assert_null(ck);
  cupid_error_clear();
  flip(prev, 100);
  assert_int_equal(cupid_checkpoint_open_previous(path, "model A", &ck), CUPID_ERR_IO);
  assert_null(ck);
  assert_non_null(strstr(cupid_error_message(), "previous checkpoint"));
  cupid_error_clear();
  flip(prev, 100);
  /* a flipped byte anywhere in PATH: the previous one */
  const long n = size_of(path), spots[4] = {3, 40, n / 2, n - 10};
  for (int k = 0; k < 4; k++) {
    flip(path, spots[k]);
    expect_data(a, 10, 1);
    flip(path, spots[k]);
    expect_data(b, 20, 0);
  }
  /* PATH truncated, PATH.prev damaged: nothing intact */
  assert_int_equal(truncate(path, n - 100), 0);
  flip(prev, 100);
  expect_error(CUPID_ERR_IO, "model A", "no intact checkpoint");
}

static void full_disk(void **state) {
  (void)state;
  CUPID_ASSERT_OK(write_one("model A", a, 10));
  CUPID_ASSERT_OK(write_one("model A", a, 11));
  /* files may not grow past 64 KiB (the checkpoint is 160 KB): the write fails as on a full
   * disk */
  struct rlimit old, lim;
  getrlimit(RLIMIT_FSIZE, &old);
  lim = old;
  lim.rlim_cur = 65536;
  signal(SIGXFSZ, SIG_IGN);
  assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
  const cupid_status st = write_one("model A", b, 12);
  setrlimit(RLIMIT_FSIZE, &old);
  signal(SIGXFSZ, SIG_DFL);
  assert_int_equal(st, CUPID_ERR_IO);
  printf("  %s\n", cupid_error_message());
  cupid_error_clear();
  expect_data(a, 11, 0); /* the last checkpoint, whole */
  /* no temporary file left behind */
  char cmd[400];
  snprintf(cmd, sizeof cmd, "test $(ls -A %s | wc -l) -le 2", dir);
  assert_int_equal(system(cmd), 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test_setup_teardown(refusals, setup, teardown),
                                     cmocka_unit_test_setup_teardown(full_disk, setup, teardown)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
