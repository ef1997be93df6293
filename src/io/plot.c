/*
 * Plots through gnuplot (see include/cupid/io.h). cupid writes a readable script next to the
 * CSV files it plots, so a user can restyle a figure without cupid, and runs gnuplot on it
 * when gnuplot is installed. gnuplot is spawned directly (no shell, so no quoting of the
 * directory is needed) with its working directory set to the plot's directory.
 */
#define _GNU_SOURCE /* posix_spawn_file_actions_addchdir_np, pipe2 */
#include <errno.h>
#include <math.h>
#include <fcntl.h>
#include <spawn.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cupid/io.h"
#include "io/io_internal.h"

#define PLOT_MAX_STEM 255 /* a file name component (NAME_MAX) */

cupid_plot_options cupid_plot_defaults(void) {
  cupid_plot_options o = {.header_lines = 1, .width = 1000, .height = 650, .key = "top right"};
  return o;
}

/* ---------------------------------------------------------------- the script */

/* A gnuplot single-quoted string s + suffix: '' stands for ', a newline would end the command. */
static void gp_quote_suffix(FILE *out, const char *s, const char *suffix) {
  fputc('\'', out);
  for (; s && *s; s++) {
    if (*s == '\'') fputs("''", out);
    else if (*s == '\n' || *s == '\r') fputc(' ', out);
    else fputc(*s, out);
  }
  fputs(suffix, out);
  fputc('\'', out);
}

static void gp_quote(FILE *out, const char *s) { gp_quote_suffix(out, s, ""); }

/* Raw gnuplot text (a style) on one line. */
static void gp_raw(FILE *out, const char *s) {
  for (; *s; s++) fputc(*s == '\n' || *s == '\r' ? ' ' : *s, out);
}

/* Split off the next comma-separated field of a CSV header line, trimmed of blanks and quotes. */
static char *csv_next_field(char **cursor) {
  char *s = *cursor;
  if (!s) return NULL;
  char *comma = strchr(s, ',');
  if (comma) {
    *comma = '\0';
    *cursor = comma + 1;
  } else {
    *cursor = NULL;
  }
  while (*s == ' ' || *s == '\t' || *s == '"') s++;
  char *end = s + strlen(s);
  while (end > s && strchr(" \t\r\n\"", end[-1])) *--end = '\0';
  return s;
}

/* Open @p dir/@p csv for reading: *path is the caller's to free; *in NULL if it cannot be read. */
static cupid_status csv_open(const char *dir, const char *csv, char **path, FILE **in) {
  size_t size = strlen(dir) + strlen(csv) + 2;
  CUPID_CALL(cupid_malloc(size, 1, "file name", path));
  snprintf(*path, size, "%s/%s", dir, csv);
  *in = fopen(*path, "r");
  return CUPID_SUCCESS;
}

/* The 1-based column called @p name in the header line of @p dir/@p csv. */
static cupid_status csv_column(const char *dir, const char *csv, const char *name, int *col) {
  char *path = NULL, *line = NULL;
  size_t cap = 0;
  FILE *in = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(csv_open(dir, csv, &path, &in));
  CUPID_TRY_CHECK(in, CUPID_ERR_IO, "cannot read '%s': %s", path, strerror(errno));
  CUPID_TRY_CHECK(getline(&line, &cap, in) >= 0, CUPID_ERR_IO, "cannot read '%s': %s", path,
                  ferror(in) ? strerror(errno) : "no header line");
  char *cursor = line, *field;
  *col = 0;
  for (int i = 1; (field = csv_next_field(&cursor)); i++)
    if (strcmp(field, name) == 0) {
      *col = i;
      break;
    }
  CUPID_TRY_CHECK(*col > 0, CUPID_ERR_ARGUMENT, "plot: '%s' has no column '%s'", path, name);
cleanup:
  if (in) fclose(in); /* read only: nothing to lose */
  free(line);         /* getline allocates with malloc */
  cupid_free(&path);
  return st;
}

static cupid_status plot_check(const char *dir, const char *stem, int n_curves,
                               const cupid_plot_curve *curves, const cupid_plot_options *o) {
  CUPID_CHECK(dir && dir[0] && stem && stem[0], CUPID_ERR_ARGUMENT, "plot: no directory or name");
  CUPID_CHECK(!strpbrk(stem, "/\n\r") && strlen(stem) <= PLOT_MAX_STEM, CUPID_ERR_ARGUMENT,
              "plot: name '%s' must be a plain file name", stem);
  CUPID_CHECK(n_curves > 0 && curves, CUPID_ERR_ARGUMENT, "plot '%s': no curves", stem);
  CUPID_CHECK(o->header_lines >= 0 && o->width > 0 && o->height > 0, CUPID_ERR_ARGUMENT,
              "plot '%s': bad options (header lines %d, size %d x %d)", stem, o->header_lines,
              o->width, o->height);
  for (int i = 0; i < n_curves; i++) {
    const cupid_plot_curve *c = &curves[i];
    CUPID_CHECK(c->csv && c->csv[0] && !strpbrk(c->csv, "\n\r"), CUPID_ERR_ARGUMENT,
                "plot '%s': curve %d has no CSV file", stem, i);
    CUPID_CHECK((c->xname || c->xcol >= 1) && (c->yname || c->ycol >= 1), CUPID_ERR_ARGUMENT,
                "plot '%s': curve %d: columns must be named or >= 1 (got %d:%d)", stem, i,
                c->xcol, c->ycol);
    CUPID_CHECK(!(c->xname || c->yname) || o->header_lines >= 1, CUPID_ERR_ARGUMENT,
                "plot '%s': curve %d names columns but the CSV has no header line", stem, i);
  }
  return CUPID_SUCCESS;
}

static cupid_status plot_curve_columns(const char *dir, const cupid_plot_curve *c, int *x, int *y) {
  *x = c->xcol;
  *y = c->ycol;
  if (c->xname) CUPID_CALL(csv_column(dir, c->csv, c->xname, x));
  if (c->yname) CUPID_CALL(csv_column(dir, c->csv, c->yname, y));
  return CUPID_SUCCESS;
}

/* The largest |value| of column @p col of @p dir/@p csv after @p skip header lines (NaN and
 * unreadable fields count as 0; an unreadable file as infinite). */
static cupid_status column_max_abs(const char *dir, const char *csv, int col, int skip, double *max) {
  char *path = NULL, *line = NULL;
  size_t cap = 0;
  FILE *in = NULL;
  cupid_status st = CUPID_SUCCESS;
  *max = 0.0;
  CUPID_TRY(csv_open(dir, csv, &path, &in));
  if (!in) { /* unknown: the curve is kept, and gnuplot says what is wrong with the file */
    *max = INFINITY;
    goto cleanup;
  }
  for (int row = 0; getline(&line, &cap, in) >= 0; row++) {
    if (row < skip) continue;
    char *cursor = line, *field = NULL;
    for (int i = 1; i <= col && (field = csv_next_field(&cursor)); i++) continue;
    double v = field ? strtod(field, NULL) : 0.0;
    if (v == v && fabs(v) > *max) *max = fabs(v);
  }
cleanup:
  if (in) fclose(in);
  free(line);
  cupid_free(&path);
  return st;
}

/* 1 when some curve's CSV has a data row after its header lines (a run that stopped at its
 * first step has none: gnuplot would fail on the empty range, and the run with it). */
static int plot_has_rows(const char *dir, int n_curves, const cupid_plot_curve *curves,
                         const cupid_plot_options *o) {
  int found = 0;
  for (int i = 0; i < n_curves && !found; i++) {
    char *path = NULL, *line = NULL;
    size_t cap = 0;
    FILE *in = NULL;
    if (csv_open(dir, curves[i].csv, &path, &in) != CUPID_SUCCESS) {
      cupid_error_clear();
      return 1; /* unknown: gnuplot says what is wrong with the file */
    }
    if (!in) found = 1;
    for (int row = 0; in && !found && getline(&line, &cap, in) >= 0; row++)
      found = row >= o->header_lines && strspn(line, " \t\r\n") < strlen(line);
    if (in) fclose(in);
    free(line);
    cupid_free(&path);
  }
  return found;
}

/* Curves that are zero everywhere (to 1e-12 of the largest curve: round-off of a symmetric
 * model) say nothing and crowd the key: they are left out (all kept if every one is). */
static cupid_status plot_keep(const char *dir, int n_curves, const cupid_plot_curve *curves,
                              const cupid_plot_options *o, unsigned char *keep) {
  double top = 0.0, m[64];
  for (int i = 0; i < n_curves; i++) {
    int x, y;
    CUPID_CALL(plot_curve_columns(dir, &curves[i], &x, &y));
    m[i < 64 ? i : 63] = 0.0;
    if (i < 64) CUPID_CALL(column_max_abs(dir, curves[i].csv, y, o->header_lines, &m[i]));
    if (i < 64 && m[i] > top) top = m[i];
  }
  int kept = 0;
  for (int i = 0; i < n_curves; i++) kept += keep[i] = i >= 64 || m[i] > 1e-12 * top;
  if (!kept)
    for (int i = 0; i < n_curves; i++) keep[i] = 1;
  return CUPID_SUCCESS;
}

static cupid_status plot_script(const char *dir, const char *script, const char *stem,
                                const char *title, const char *xlabel, const char *ylabel,
                                int n_curves, const cupid_plot_curve *curves,
                                const cupid_plot_options *o) {
  cupid_status st = CUPID_SUCCESS;
  cupid_atomic_file file = NULL;
  CUPID_TRY(cupid_atomic_open(script, &file));
  FILE *out = cupid_atomic_stream(file);
  fprintf(out, "# Written by cupid %s. Remake the plot with: gnuplot %s.gp (from any folder)\n",
          cupid_version(), stem);
  /* run from another folder (gnuplot path/to/x.gp): read and write beside the script */
  fputs("if (exists(\"ARG0\") && strstrt(ARG0, \"/\") > 0) "
        "{ cd system(sprintf(\"dirname '%s'\", ARG0)) }\n", out);
  fprintf(out, "set terminal pngcairo size %d,%d enhanced font 'sans,11'\nset output ", o->width,
          o->height);
  gp_quote_suffix(out, stem, ".png");
  fputs("\nset datafile separator ','\n", out);
  /* noenhanced: names like u_x are printed as written, not with subscripts. */
  const char *labels[3][2] = {{"title", title}, {"xlabel", xlabel}, {"ylabel", ylabel}};
  for (int i = 0; i < 3; i++) {
    if (!labels[i][1]) continue;
    fprintf(out, "set %s ", labels[i][0]);
    gp_quote(out, labels[i][1]);
    fputs(" noenhanced\n", out);
  }
  fputs("set key ", out);
  gp_raw(out, o->key ? o->key : "top right");
  fputs("\nset grid\n", out);
  if (o->logx) fputs("set logscale x\n", out);
  if (o->logy) fputs("set logscale y\n", out);
  fputs("set offsets 0, 0, graph 0.05, graph 0.05 # keep curves off the frame\n", out);
  for (int i = 0; i < n_curves; i++) {
    int x, y;
    CUPID_TRY(plot_curve_columns(dir, &curves[i], &x, &y));
    if (curves[i].xname || curves[i].yname)
      fprintf(out, "# %s: x = column %d (%s), y = column %d (%s)\n", curves[i].csv, x,
              curves[i].xname ? curves[i].xname : "-", y,
              curves[i].yname ? curves[i].yname : "-");
  }
  unsigned char keep[256];
  CUPID_TRY_CHECK(n_curves <= 256, CUPID_ERR_ARGUMENT, "plot '%s': more than 256 curves", stem);
  CUPID_TRY(plot_keep(dir, n_curves, curves, o, keep));
  for (int i = 0; i < n_curves; i++)
    if (!keep[i])
      fprintf(out, "# left out, zero everywhere: %s\n", curves[i].title ? curves[i].title : curves[i].csv);
  for (int i = 0, first = 1; i < n_curves; i++) {
    const cupid_plot_curve *c = &curves[i];
    int x, y;
    if (!keep[i]) continue;
    CUPID_TRY(plot_curve_columns(dir, c, &x, &y));
    fputs(first ? "plot " : ", \\\n     ", out);
    first = 0;
    gp_quote(out, c->csv);
    if (o->header_lines > 0) fprintf(out, " skip %d", o->header_lines);
    fprintf(out, " using %d:%d with ", x, y);
    gp_raw(out, c->style ? c->style : "lines");
    fputs(" title ", out);
    gp_quote(out, c->title ? c->title : "");
    fputs(" noenhanced", out);
  }
  fputc('\n', out);
  CUPID_TRY(cupid_atomic_commit(&file));
cleanup:
  cupid_atomic_abort(&file);
  return st;
}

/* ---------------------------------------------------------------- running gnuplot */

/* Find an executable gnuplot on PATH (as execvp would). *found = NULL if there is none. */
static cupid_status find_gnuplot(char **found) {
  *found = NULL;
  const char *path = getenv("PATH");
  if (!path) path = "/usr/bin:/bin";
  size_t size = strlen(path) + sizeof "/gnuplot" + 2;
  char *candidate = NULL;
  CUPID_CALL(cupid_malloc(size, 1, "gnuplot path", &candidate));
  for (const char *p = path;; p++) {
    const char *end = strchr(p, ':');
    size_t len = end ? (size_t)(end - p) : strlen(p);
    if (len == 0) snprintf(candidate, size, "./gnuplot"); /* an empty entry means "." */
    else snprintf(candidate, size, "%.*s/gnuplot", (int)len, p);
    struct stat sb;
    if (stat(candidate, &sb) == 0 && S_ISREG(sb.st_mode) && access(candidate, X_OK) == 0) {
      *found = candidate;
      return CUPID_SUCCESS;
    }
    if (!end) break;
    p = end;
  }
  cupid_free(&candidate);
  return CUPID_SUCCESS;
}

/* Keep the last part of gnuplot's output (its error comes last). */
static void log_append(char *log, size_t cap, size_t *len, const char *data, size_t n) {
  if (n >= cap) {
    data += n - (cap - 1);
    n = cap - 1;
    *len = 0;
  }
  if (*len + n >= cap) {
    size_t drop = *len + n - (cap - 1);
    memmove(log, log + drop, *len - drop);
    *len -= drop;
  }
  memcpy(log + *len, data, n);
  *len += n;
  log[*len] = '\0';
}

/* Run `gnuplot ./<script>` in @p dir, its output captured into @p log; *status as from waitpid.
 * While it runs, @p png (which gnuplot writes in place) is registered with the signal cleanup:
 * an interrupted run kills gnuplot and removes the half-made PNG. */
static cupid_status spawn_gnuplot(const char *gnuplot, const char *dir, const char *script,
                                  const char *png, int *status, char *log, size_t cap) {
  int fds[2] = {-1, -1};
  size_t len = 0;
  log[0] = '\0';
  CUPID_CHECK(pipe2(fds, O_CLOEXEC) == 0, CUPID_ERR_IO, "cannot run gnuplot: pipe: %s",
              strerror(errno));
  posix_spawn_file_actions_t actions;
  int rc = posix_spawn_file_actions_init(&actions);
  if (rc == 0) {
    /* Every action is checked; the first failure is kept in rc. */
    rc = posix_spawn_file_actions_addchdir_np(&actions, dir);
    if (rc == 0) rc = posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    if (rc == 0) rc = posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
    if (rc == 0) rc = posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
    pid_t pid = -1;
    char *argv[] = {"gnuplot", (char *)script, NULL};
    /* The PNG's name is registered before gnuplot starts: a signal from here on removes it
     * (and, once the pid is known, stops gnuplot first). */
    int slot = rc == 0 ? cupid_io_helper_begin(png, 0) : -1;
    if (rc == 0) rc = posix_spawn(&pid, gnuplot, &actions, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    close(fds[1]);
    fds[1] = -1;
    if (rc != 0) cupid_io_helper_end(slot);
    if (rc == 0) {
      cupid_io_helper_set_child(slot, pid);
      char chunk[4096];
      for (;;) {
        ssize_t n = read(fds[0], chunk, sizeof chunk);
        if (n > 0) log_append(log, cap, &len, chunk, (size_t)n);
        else if (n == 0 || errno != EINTR) break;
      }
      pid_t w;
      while ((w = waitpid(pid, status, 0)) < 0 && errno == EINTR) continue;
      if (w < 0) rc = errno;
      cupid_io_helper_end(slot);
    }
  }
  close(fds[0]);
  if (fds[1] >= 0) close(fds[1]);
  CUPID_CHECK(rc == 0, CUPID_ERR_IO, "cannot run %s in '%s': %s", gnuplot, dir, strerror(rc));
  return CUPID_SUCCESS;
}

static cupid_status run_gnuplot(const char *gnuplot, const char *dir, const char *stem,
                                const char *png, int *made) {
  char log[2048];
  int status = 0;
  char script[PLOT_MAX_STEM + 8];
  snprintf(script, sizeof script, "./%s.gp", stem); /* "./" so a name starting with '-' is no option */
  /* A stale PNG must not pass for a new one. */
  CUPID_CHECK(unlink(png) == 0 || errno == ENOENT, CUPID_ERR_IO, "cannot replace '%s': %s", png,
              strerror(errno));
  CUPID_CALL(spawn_gnuplot(gnuplot, dir, script, png, &status, log, sizeof log));
  for (size_t n = strlen(log); n > 0 && strchr(" \t\r\n", log[n - 1]); n--) log[n - 1] = '\0';
  if (WIFSIGNALED(status))
    return CUPID_ERROR(CUPID_ERR_IO, "gnuplot was killed by signal %d making '%s': %s",
                       WTERMSIG(status), png, log);
  CUPID_CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0, CUPID_ERR_IO,
              "gnuplot failed (exit status %d) making '%s': %s", WEXITSTATUS(status), png, log);
  struct stat sb;
  CUPID_CHECK(stat(png, &sb) == 0 && sb.st_size > 0, CUPID_ERR_IO,
              "gnuplot succeeded but made no '%s'%s%s", png, log[0] ? ": " : "", log);
  *made = 1;
  return CUPID_SUCCESS;
}

cupid_status cupid_plot_ex(const char *dir, const char *stem, const char *title,
                           const char *xlabel, const char *ylabel, int n_curves,
                           const cupid_plot_curve *curves, const cupid_plot_options *options,
                           int *made) {
  CUPID_CHECK(made, CUPID_ERR_ARGUMENT, "plot: NULL result flag");
  *made = 0;
  cupid_plot_options o = options ? *options : cupid_plot_defaults();
  CUPID_CALL(plot_check(dir, stem, n_curves, curves, &o));
  cupid_status st = CUPID_SUCCESS;
  char *script = NULL, *png = NULL, *gnuplot = NULL;
  size_t size = strlen(dir) + strlen(stem) + 6;
  CUPID_TRY(cupid_malloc(size, 1, "file name", &script));
  CUPID_TRY(cupid_malloc(size, 1, "file name", &png));
  snprintf(script, size, "%s/%s.gp", dir, stem);
  snprintf(png, size, "%s/%s.png", dir, stem);
  CUPID_TRY(plot_script(dir, script, stem, title, xlabel, ylabel, n_curves, curves, &o));
  if (!plot_has_rows(dir, n_curves, curves, &o)) goto cleanup; /* the script, no picture */
  CUPID_TRY(find_gnuplot(&gnuplot));
  if (gnuplot) CUPID_TRY(run_gnuplot(gnuplot, dir, stem, png, made));
cleanup:
  cupid_free(&script);
  cupid_free(&png);
  cupid_free(&gnuplot);
  return st;
}

cupid_status cupid_plot(const char *dir, const char *stem, const char *title, const char *xlabel,
                        const char *ylabel, int n_curves, const cupid_plot_curve *curves,
                        int *made) {
  return cupid_plot_ex(dir, stem, title, xlabel, ylabel, n_curves, curves, NULL, made);
}
