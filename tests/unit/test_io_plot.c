/* Unit tests of the gnuplot plots (src/io/plot.c). */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "testutil.h"

static char root[256];
static char dir[512];        /* the plot directory: has a space and a quote in its name */
static char saved_path[8192]; /* PATH before the test */

static int setup(void **state) {
  (void)state;
  if (cupid_test_mkdtemp("plot", root, sizeof root)) return -1;
  snprintf(dir, sizeof dir, "%s/plot dir 'q'", root);
  const char *path = getenv("PATH");
  snprintf(saved_path, sizeof saved_path, "%s", path ? path : "/usr/bin:/bin");
  return mkdir(dir, 0777);
}

static int teardown(void **state) {
  (void)state;
  setenv("PATH", saved_path, 1);
  return cupid_test_rmtree(root);
}

static const char *in_dir(const char *name) {
  static char buf[4][1024];
  static int next;
  char *b = buf[next++ % 4];
  snprintf(b, sizeof buf[0], "%s/%s", dir, name);
  return b;
}

static char *slurp(const char *path, size_t *size) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  char *buf = malloc(1 << 20);
  assert_non_null(buf);
  size_t n = fread(buf, 1, (1 << 20) - 1, f);
  buf[n] = '\0';
  fclose(f);
  if (size) *size = n;
  return buf;
}

static void write_csv(const char *name) {
  cupid_atomic_file f = NULL;
  CUPID_ASSERT_OK(cupid_atomic_open(in_dir(name), &f));
  FILE *out = cupid_atomic_stream(f);
  fputs("s,u_x,\"v\"\n", out);
  for (int i = 0; i <= 50; i++) fprintf(out, "%g,%g,%g\n", 0.02 * i, 0.02 * i * 0.02 * i, 1.0 - 0.01 * i);
  CUPID_ASSERT_OK(cupid_atomic_commit(&f));
}

static int have_gnuplot(void) { return system("command -v gnuplot > /dev/null 2>&1") == 0; }

static const cupid_plot_curve curves[] = {
    {.csv = "data.csv", .xcol = 1, .ycol = 2, .title = "u_x (it's)", .style = "lines lw 2"},
    {.csv = "data.csv", .xname = "s", .yname = "v", .title = "v", .style = "points pt 7 ps 0.5"}};

static void test_plot_png(void **state) {
  (void)state;
  if (!have_gnuplot()) skip();
  write_csv("data.csv");
  int made = -1;
  CUPID_ASSERT_OK(cupid_plot(dir, "disp", "Displacement of 'bar_1'", "s [m]", "u [m]", 2, curves,
                             &made));
  assert_int_equal(made, 1);
  size_t size;
  char *png = slurp(in_dir("disp.png"), &size);
  assert_non_null(png);
  assert_true(size > 1000);
  assert_memory_equal(png, "\x89PNG\r\n\x1a\n", 8);
  free(png);
  char *gp = slurp(in_dir("disp.gp"), NULL);
  assert_non_null(gp);
  assert_non_null(strstr(gp, "set terminal pngcairo size 1000,650 enhanced font 'sans,11'\n"));
  assert_non_null(strstr(gp, "set output 'disp.png'\n"));
  assert_non_null(strstr(gp, "set datafile separator ','\n"));
  assert_non_null(strstr(gp, "set title 'Displacement of ''bar_1''' noenhanced\n"));
  assert_non_null(strstr(gp, "set grid\n"));
  assert_non_null(strstr(gp, "plot 'data.csv' skip 1 using 1:2 with lines lw 2 title 'u_x (it''s)' noenhanced, \\\n"
                             "     'data.csv' skip 1 using 1:3 with points pt 7 ps 0.5 title 'v' noenhanced\n"));
  assert_non_null(strstr(gp, "# data.csv: x = column 1 (s), y = column 3 (v)\n"));
  free(gp);
  /* A second run replaces the plot. */
  CUPID_ASSERT_OK(cupid_plot(dir, "disp", NULL, NULL, NULL, 1, curves, &made));
  assert_int_equal(made, 1);
}

static void test_plot_options(void **state) {
  (void)state;
  write_csv("data.csv");
  setenv("PATH", root, 1); /* no gnuplot: only the script is checked here */
  cupid_plot_options o = cupid_plot_defaults();
  assert_int_equal(o.header_lines, 1);
  o.header_lines = 0;
  o.logy = 1;
  o.width = 640;
  o.height = 480;
  o.key = "off";
  cupid_plot_curve c = {.csv = "data.csv", .xcol = 1, .ycol = 3};
  int made = -1;
  CUPID_ASSERT_OK(cupid_plot_ex(dir, "opt", "t", "x", "y", 1, &c, &o, &made));
  assert_int_equal(made, 0);
  char *gp = slurp(in_dir("opt.gp"), NULL);
  assert_non_null(gp);
  assert_non_null(strstr(gp, "size 640,480"));
  assert_non_null(strstr(gp, "set key off\n"));
  assert_non_null(strstr(gp, "set logscale y\n"));
  assert_null(strstr(gp, "set logscale x"));
  assert_non_null(strstr(gp, "plot 'data.csv' using 1:3 with lines title '' noenhanced\n"));
  free(gp);
  /* Named columns need a header line; a missing name is reported with the file. */
  c.yname = "v";
  assert_int_equal(cupid_plot_ex(dir, "opt", "t", "x", "y", 1, &c, &o, &made), CUPID_ERR_ARGUMENT);
  c.yname = "w";
  assert_int_equal(cupid_plot(dir, "opt", "t", "x", "y", 1, &c, &made), CUPID_ERR_ARGUMENT);
  assert_non_null(strstr(cupid_error_message(), "no column 'w'"));
  c.csv = "missing.csv";
  assert_int_equal(cupid_plot(dir, "opt", "t", "x", "y", 1, &c, &made), CUPID_ERR_IO);
  assert_int_equal(cupid_plot(dir, "a/b", "t", "x", "y", 1, &c, &made), CUPID_ERR_ARGUMENT);
  assert_int_equal(cupid_plot(dir, "opt", "t", "x", "y", 0, &c, &made), CUPID_ERR_ARGUMENT);
}

static void test_plot_without_gnuplot(void **state) {
  (void)state;
  write_csv("data.csv");
  setenv("PATH", root, 1); /* a directory without gnuplot */
  int made = -1;
  CUPID_ASSERT_OK(cupid_plot(dir, "nogp", "t", "x", "y", 2, curves, &made));
  assert_int_equal(made, 0);
  char *gp = slurp(in_dir("nogp.gp"), NULL); /* the script is written all the same */
  assert_non_null(gp);
  assert_non_null(strstr(gp, "set output 'nogp.png'"));
  free(gp);
  struct stat sb;
  assert_int_not_equal(stat(in_dir("nogp.png"), &sb), 0);
}

/* A fake gnuplot that fails: its exit status and output are in the error, not on stdout. */
static void test_plot_gnuplot_fails(void **state) {
  (void)state;
  write_csv("data.csv");
  char fake[1024];
  snprintf(fake, sizeof fake, "%s/gnuplot", root);
  FILE *f = fopen(fake, "w");
  assert_non_null(f);
  fputs("#!/bin/sh\necho noise-on-stdout\necho \"boom in ${PWD##*/}: $1\" >&2\nexit 3\n", f);
  assert_int_equal(fclose(f), 0);
  assert_int_equal(chmod(fake, 0755), 0);
  setenv("PATH", root, 1);
  int made = -1;
  assert_int_equal(cupid_plot(dir, "fails", "t", "x", "y", 1, curves, &made), CUPID_ERR_IO);
  assert_int_equal(made, 0);
  const char *msg = cupid_error_message();
  if (!strstr(msg, "exit status 3") || !strstr(msg, "noise-on-stdout") ||
      !strstr(msg, "boom in plot dir 'q': ./fails.gp"))
    fail_msg("unexpected message: %s", msg);
}

/* A CSV with its header and no row (a run stopped at its first step): the script, no picture,
 * and no gnuplot run (the fake one here would fail; the real one fails on the empty range). */
static void test_plot_no_rows(void **state) {
  (void)state;
  FILE *f = fopen(in_dir("empty.csv"), "w");
  assert_non_null(f);
  fputs("t,u,v\n", f);
  assert_int_equal(fclose(f), 0);
  char fake[1024];
  snprintf(fake, sizeof fake, "%s/gnuplot", root);
  f = fopen(fake, "w");
  assert_non_null(f);
  fputs("#!/bin/sh\nexit 3\n", f);
  assert_int_equal(fclose(f), 0);
  assert_int_equal(chmod(fake, 0755), 0);
  setenv("PATH", root, 1);
  cupid_plot_curve c = {.csv = "empty.csv", .xname = "t", .yname = "u"};
  int made = -1;
  CUPID_ASSERT_OK(cupid_plot(dir, "norows", "t", "x", "y", 1, &c, &made));
  assert_int_equal(made, 0);
  struct stat sb;
  assert_int_equal(stat(in_dir("norows.gp"), &sb), 0);
  assert_int_not_equal(stat(in_dir("norows.png"), &sb), 0);
}

/* The real gnuplot on a missing CSV fails ("No data in plot"). */
static void test_plot_real_gnuplot_error(void **state) {
  (void)state;
  if (!have_gnuplot()) skip();
  cupid_plot_curve c = {.csv = "absent.csv", .xcol = 1, .ycol = 2, .title = "a"};
  int made = -1;
  assert_int_equal(cupid_plot(dir, "absent", "t", "x", "y", 1, &c, &made), CUPID_ERR_IO);
  assert_int_equal(made, 0);
  assert_non_null(strstr(cupid_error_message(), "gnuplot failed"));
  assert_non_null(strstr(cupid_error_message(), "absent.csv"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_plot_png, setup, teardown),
      cmocka_unit_test_setup_teardown(test_plot_options, setup, teardown),
      cmocka_unit_test_setup_teardown(test_plot_without_gnuplot, setup, teardown),
      cmocka_unit_test_setup_teardown(test_plot_gnuplot_fails, setup, teardown),
      cmocka_unit_test_setup_teardown(test_plot_real_gnuplot_error, setup, teardown),
      cmocka_unit_test_setup_teardown(test_plot_no_rows, setup, teardown),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
