/* Output writers (io.h, "Output writers"; issue 35): the generic half of the table. A writer
 * owns copies of its spec's strings; its type owns w->data. */
#include <stdio.h>
#include <string.h>

#include "io_internal.h"

const char *cupid_writer_unavailable(const cupid_writer_type *type) {
  if (!type) return "no writer type";
  return type->missing ? type->missing() : NULL;
}

int cupid_writer_available(const cupid_writer_type *type) {
  return cupid_writer_unavailable(type) == NULL;
}

const char *cupid_writer_name(const cupid_writer_type *type) { return type ? type->name : ""; }

cupid_status cupid_writer_path(const cupid_writer w, const char *name, char *path, size_t size) {
  const char *leaf = name ? name : w->file;
  int n = snprintf(path, size, "%s/%s", w->dir, leaf ? leaf : "");
  CUPID_CHECK(n > 0 && (size_t)n < size, CUPID_ERR_IO, "output path too long: %s/%s", w->dir,
              leaf ? leaf : "");
  return CUPID_SUCCESS;
}

static void writer_free(cupid_writer w) {
  cupid_free(&w->dir);
  cupid_free(&w->file);
  cupid_free(&w->key);
  cupid_free(&w->title);
  cupid_free(&w);
}

static cupid_status copy(const char *s, char **out) { return cupid_strdup(s ? s : "", out); }

cupid_status cupid_writer_create(const cupid_writer_type *type, const cupid_writer_spec *spec,
                                 cupid_writer *writer) {
  CUPID_CHECK(type && spec && spec->dir && writer, CUPID_ERR_ARGUMENT,
              "cupid_writer_create: no type, spec, folder or handle");
  *writer = NULL;
  const char *missing = type->missing ? type->missing() : NULL;
  CUPID_CHECK(!missing, CUPID_ERR_UNSUPPORTED, "cupid cannot write %s files: %s", type->name,
              missing);
  cupid_writer w = NULL;
  CUPID_CALL(cupid_calloc(1, sizeof *w, "output writer", &w));
  w->type = type;
  cupid_status st = copy(spec->dir, &w->dir);
  if (st == CUPID_SUCCESS) st = copy(spec->file, &w->file);
  if (st == CUPID_SUCCESS) st = copy(spec->key, &w->key);
  if (st == CUPID_SUCCESS) st = copy(spec->title, &w->title);
  if (st == CUPID_SUCCESS) st = type->create(w, spec);
  if (st != CUPID_SUCCESS) {
    if (w->data) type->drop(w, 0);
    writer_free(w);
    return st;
  }
  *writer = w;
  return CUPID_SUCCESS;
}

cupid_status cupid_writer_step(cupid_writer writer, const cupid_frame *frame) {
  return writer ? writer->type->step(writer, frame) : CUPID_SUCCESS;
}

cupid_status cupid_writer_save(cupid_writer writer, cupid_checkpoint_writer ckw) {
  return writer ? writer->type->save(writer, ckw) : CUPID_SUCCESS;
}

cupid_status cupid_writer_end(cupid_writer *writer) {
  if (!writer || !*writer) return CUPID_SUCCESS;
  cupid_writer w = *writer;
  *writer = NULL;
  cupid_status st = w->type->end(w);
  w->type->drop(w, 0); /* after a commit: frees what is left */
  writer_free(w);
  return st;
}

void cupid_writer_drop(cupid_writer *writer, int keep) {
  if (!writer || !*writer) return;
  cupid_writer w = *writer;
  *writer = NULL;
  w->type->drop(w, keep);
  writer_free(w);
}
