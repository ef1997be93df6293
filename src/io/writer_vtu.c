/* The VTU series writer (io.h, cupid_writer_vtu): PART_<step>.vtu for each part of a frame
 * (model.pvd's; another series, e.g. adaptive.pvd, names them STEM_PART_<step>.vtu)
 * (each written atomically, in the frame's part order) and, at the end, the .pvd collection
 * that lists them with their times (ParaView shows the parts of one time as blocks). A
 * checkpoint records the files written; a resumption lists them again. */
#include <stdio.h>
#include <string.h>

#include "io_internal.h"

enum { NAME = 64 };

typedef struct {
  char (*files)[NAME];
  double *times;
  int n, cap;
  char prefix[24]; /* "" for model.pvd, else the .pvd's stem and "_" */
} vtu_writer;

static cupid_status record(vtu_writer *v, const char *name, double t) {
  if (v->n == v->cap) {
    int cap = v->cap ? 2 * v->cap : 64;
    CUPID_CALL(cupid_realloc((size_t)cap, sizeof *v->files, "VTU file names", &v->files));
    CUPID_CALL(cupid_realloc((size_t)cap, sizeof *v->times, "VTU times", &v->times));
    v->cap = cap;
  }
  memset(v->files[v->n], 0, NAME); /* whole: a checkpoint stores the slot */
  snprintf(v->files[v->n], NAME, "%s", name);
  v->times[v->n++] = t;
  return CUPID_SUCCESS;
}

/* A checkpoint's section: the count, then the names, then the times. */
static cupid_status vtu_resume(cupid_writer w, vtu_writer *v, cupid_checkpoint ck) {
  const void *data = NULL;
  size_t bytes = 0;
  int n = 0;
  CUPID_CALL(cupid_checkpoint_section(ck, w->key, &data, &bytes));
  CUPID_CHECK(bytes >= sizeof n, CUPID_ERR_IO, "checkpoint section %s is cut short", w->key);
  memcpy(&n, data, sizeof n);
  CUPID_CHECK(n >= 0 && bytes == sizeof n + (size_t)n * (NAME + sizeof(double)), CUPID_ERR_IO,
              "checkpoint section %s does not hold a list of VTU files", w->key);
  const char *p = (const char *)data + sizeof n;
  for (int k = 0; k < n; k++) {
    double t;
    memcpy(&t, p + (size_t)n * NAME + (size_t)k * sizeof t, sizeof t);
    char name[NAME];
    memcpy(name, p + (size_t)k * NAME, NAME);
    name[NAME - 1] = '\0';
    CUPID_CALL(record(v, name, t));
  }
  return CUPID_SUCCESS;
}

static cupid_status vtu_create(cupid_writer w, const cupid_writer_spec *spec) {
  vtu_writer *v = NULL;
  CUPID_CALL(cupid_calloc(1, sizeof *v, "VTU writer", &v));
  w->data = v;
  const char *dot = spec->file ? strrchr(spec->file, '.') : NULL;
  const size_t stem = dot ? (size_t)(dot - spec->file) : 0;
  CUPID_CHECK(stem < sizeof v->prefix - 1, CUPID_ERR_ARGUMENT, "VTU series name too long: %s",
              spec->file);
  if (stem > 0 && strncmp(spec->file, "model", stem) != 0)
    snprintf(v->prefix, sizeof v->prefix, "%.*s_", (int)stem, spec->file);
  return spec->resume ? vtu_resume(w, v, spec->resume) : CUPID_SUCCESS;
}

static cupid_status vtu_step(cupid_writer w, const cupid_frame *frame) {
  vtu_writer *v = w->data;
  for (int k = 0; k < frame->n_parts; k++) {
    const cupid_frame_part *part = &frame->parts[k];
    char name[NAME], path[4096];
    int len = snprintf(name, sizeof name, "%s%s_%06lld.vtu", v->prefix, part->name,
                       (long long)frame->step);
    CUPID_CHECK(len > 0 && len < NAME, CUPID_ERR_ARGUMENT, "VTU part name too long: %s", part->name);
    CUPID_CALL(cupid_writer_path(w, name, path, sizeof path));
    CUPID_CALL(cupid_vtu_write(path, part->mesh));
    CUPID_CALL(record(v, name, frame->time));
  }
  return CUPID_SUCCESS;
}

static cupid_status vtu_save(cupid_writer w, cupid_checkpoint_writer ckw) {
  vtu_writer *v = w->data;
  const size_t bytes = sizeof v->n + (size_t)v->n * (NAME + sizeof(double));
  char *blob = NULL;
  CUPID_CALL(cupid_malloc(bytes, 1, "VTU list", &blob));
  memcpy(blob, &v->n, sizeof v->n);
  if (v->n) {
    memcpy(blob + sizeof v->n, v->files, (size_t)v->n * NAME);
    memcpy(blob + sizeof v->n + (size_t)v->n * NAME, v->times, (size_t)v->n * sizeof(double));
  }
  cupid_status st = cupid_checkpoint_write(ckw, w->key, blob, bytes);
  cupid_free(&blob);
  return st;
}

static cupid_status vtu_end(cupid_writer w) {
  vtu_writer *v = w->data;
  if (!v->n) return CUPID_SUCCESS;
  const char **names = NULL;
  char path[4096];
  CUPID_CALL(cupid_calloc((size_t)v->n, sizeof *names, "PVD names", &names));
  for (int k = 0; k < v->n; k++) names[k] = v->files[k];
  cupid_status st = cupid_writer_path(w, NULL, path, sizeof path);
  if (st == CUPID_SUCCESS) st = cupid_pvd_write(path, v->n, names, v->times, NULL);
  cupid_free(&names);
  return st;
}

/* The step files are whole files already: a dropped series leaves them to the staging folder
 * (removed with it, or kept for a resumption). */
static void vtu_drop(cupid_writer w, int keep) {
  (void)keep;
  vtu_writer *v = w->data;
  if (!v) return;
  cupid_free(&v->files);
  cupid_free(&v->times);
  cupid_free(&v);
  w->data = NULL;
}

const cupid_writer_type cupid_writer_vtu = {"vtu", NULL, vtu_create, vtu_step, vtu_save, vtu_end,
                                            vtu_drop};
