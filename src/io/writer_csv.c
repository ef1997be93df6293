/* The CSV writer (io.h, cupid_writer_csv): a header line of the columns' names, then a row per
 * frame, reals as "%.10e" and counts as integers. A resumable stream (cupid_atomic_open_partial):
 * a checkpoint records its length, and a resumption continues it from there. */
#include <stdio.h>
#include <string.h>

#include "io_internal.h"

typedef struct {
  cupid_atomic_file file;
  int n;
  unsigned char *integer; /* per column */
} csv_writer;

static cupid_status csv_create(cupid_writer w, const cupid_writer_spec *spec) {
  csv_writer *c = NULL;
  CUPID_CHECK(spec->n_columns > 0 && spec->columns, CUPID_ERR_ARGUMENT, "a CSV writer needs columns");
  CUPID_CALL(cupid_calloc(1, sizeof *c, "CSV writer", &c));
  w->data = c;
  c->n = spec->n_columns;
  CUPID_CALL(cupid_calloc((size_t)c->n, 1, "CSV columns", &c->integer));
  for (int k = 0; k < c->n; k++) c->integer[k] = (unsigned char)(spec->columns[k].integer != 0);
  int64_t keep = -1;
  if (spec->resume) CUPID_CALL(cupid_checkpoint_read(spec->resume, w->key, &keep, sizeof keep));
  char path[4096];
  CUPID_CALL(cupid_writer_path(w, NULL, path, sizeof path));
  CUPID_CALL(cupid_atomic_open_partial(path, keep, &c->file));
  if (keep >= 0) return CUPID_SUCCESS;
  FILE *f = cupid_atomic_stream(c->file);
  for (int k = 0; k < c->n; k++) fprintf(f, "%s%s", k ? "," : "", spec->columns[k].name);
  fputc('\n', f);
  return CUPID_SUCCESS;
}

static cupid_status csv_step(cupid_writer w, const cupid_frame *frame) {
  csv_writer *c = w->data;
  FILE *f = cupid_atomic_stream(c->file);
  for (int k = 0; k < c->n; k++) {
    if (k) fputc(',', f);
    if (c->integer[k]) fprintf(f, "%lld", (long long)frame->row[k]);
    else fprintf(f, "%.10e", frame->row[k]);
  }
  fputc('\n', f);
  return CUPID_SUCCESS;
}

static cupid_status csv_save(cupid_writer w, cupid_checkpoint_writer ckw) {
  csv_writer *c = w->data;
  int64_t bytes = -1;
  CUPID_CALL(cupid_atomic_sync(c->file, &bytes));
  return cupid_checkpoint_write(ckw, w->key, &bytes, sizeof bytes);
}

static cupid_status csv_end(cupid_writer w) {
  csv_writer *c = w->data;
  return cupid_atomic_commit(&c->file);
}

static void csv_drop(cupid_writer w, int keep) {
  csv_writer *c = w->data;
  if (!c) return;
  if (keep) cupid_atomic_suspend(&c->file);
  cupid_atomic_abort(&c->file);
  cupid_free(&c->integer);
  cupid_free(&c);
  w->data = NULL;
}

const cupid_writer_type cupid_writer_csv = {"csv", NULL, csv_create, csv_step, csv_save, csv_end,
                                            csv_drop};
