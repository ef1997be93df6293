/* Model reader, public entry points: read from a file or a string, destroy, report errors
 * against the file, evaluate values, test boxes (include/cupid/model.h). */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "io/io_internal.h"
#include "io/model_internal.h"

cupid_status cupid_model_read(const char *path, cupid_model *model) {
  return cupid_model_read_with(path, NULL, 0, model);
}

cupid_status cupid_model_read_with(const char *path, const char *const *sets, int n_sets,
                                   cupid_model *model) {
  CUPID_CHECK(model != NULL, CUPID_ERR_ARGUMENT, "cupid_model_read: model is NULL");
  *model = NULL;
  CUPID_CHECK(path != NULL, CUPID_ERR_ARGUMENT, "cupid_model_read: path is NULL");
  FILE *f = fopen(path, "rb");
  if (!f) return CUPID_ERROR(CUPID_ERR_IO, "cannot open model file '%s': %s", path, strerror(errno));
  cupid_status st = CUPID_SUCCESS;
  char *text = NULL;
  size_t length = 0, capacity = 0;
  /* Read in chunks (works for pipes too), refusing anything beyond the size limit. */
  for (;;) {
    if (length == capacity) {
      if (capacity > MODEL_MAX_FILE_BYTES) break;
      capacity = capacity ? 2 * capacity : 65536;
      CUPID_TRY(cupid_realloc(capacity + 1, 1, "the model file", &text));
    }
    size_t got = fread(text + length, 1, capacity - length, f);
    length += got;
    if (got == 0) break;
  }
  if (ferror(f)) {
    st = CUPID_ERROR(CUPID_ERR_IO, "cannot read model file '%s': %s", path, strerror(errno));
    goto cleanup;
  }
  if (length > MODEL_MAX_FILE_BYTES) {
    st = CUPID_ERROR(CUPID_ERR_MODEL, "%s:1:1: the model file is too large (more than %zu MiB)",
                     path, MODEL_MAX_FILE_BYTES >> 20);
    goto cleanup;
  }
  CUPID_TRY(cupid_model_read_string_with(text ? text : "", length, path, sets, n_sets, model));
cleanup:
  fclose(f);
  cupid_free(&text);
  return st;
}

cupid_status cupid_model_read_string(const char *text, size_t length, const char *name,
                                     cupid_model *model) {
  return cupid_model_read_string_with(text, length, name, NULL, 0, model);
}

cupid_status cupid_model_read_string_with(const char *text, size_t length, const char *name,
                                          const char *const *sets, int n_sets,
                                          cupid_model *model) {
  CUPID_CHECK(model != NULL, CUPID_ERR_ARGUMENT, "cupid_model_read_string: model is NULL");
  CUPID_CHECK(n_sets >= 0 && (n_sets == 0 || sets), CUPID_ERR_ARGUMENT,
              "cupid_model_read_string: %d overrides but none given", n_sets);
  *model = NULL;
  CUPID_CHECK(text != NULL || length == 0, CUPID_ERR_ARGUMENT,
              "cupid_model_read_string: text is NULL");
  if (!name) name = "<model>";
  if (length > MODEL_MAX_FILE_BYTES)
    return CUPID_ERROR(CUPID_ERR_MODEL, "%s:1:1: the model file is too large (more than %zu MiB)",
                       name, MODEL_MAX_FILE_BYTES >> 20);
  yaml_document_t doc;
  CUPID_CALL(mr_load(text ? text : "", length, name, &doc));
  cupid_status st = CUPID_SUCCESS;
  cupid_model_t *m = NULL;
  CUPID_TRY(cupid_calloc(1, sizeof *m, "the model", &m));
  CUPID_TRY(cupid_strdup(name, &m->file));
  m->source_bytes = length; /* what a checkpoint's run was read from (issue 36) */
  m->source_crc = (uint32_t)crc32(0L, Z_NULL, 0);
  for (size_t at = 0; at < length;) { /* crc32 takes at most UINT_MAX bytes a call */
    const size_t chunk = length - at < (1u << 30) ? length - at : (1u << 30);
    m->source_crc = (uint32_t)crc32(m->source_crc, (const Bytef *)text + at, (uInt)chunk);
    at += chunk;
  }
  /* the overrides, kept for the messages about their values (cupid_model_error) */
  CUPID_TRY(cupid_calloc((size_t)n_sets + 1, sizeof *m->sets, "overrides", &m->sets));
  for (int k = 0; k < n_sets; k++) CUPID_TRY(cupid_strdup(sets[k], &m->sets[k]));
  m->n_sets = n_sets;
  CUPID_TRY(mr_apply_overrides(&doc, m->file, sets, n_sets));
  model_reader rd = {&doc, m->file, m, sets, n_sets};
  CUPID_TRY(mr_read_model(&rd, yaml_document_get_root_node(&doc)));
  *model = m;
  m = NULL;
cleanup:
  yaml_document_delete(&doc);
  cupid_model_destroy(&m);
  return st;
}

static void value_clear(cupid_value *v) {
  cupid_expr_destroy(&v->expr);
  v->kind = CUPID_VALUE_NONE;
}

static void values_clear(cupid_value *v, int n) {
  for (int i = 0; i < n; i++) value_clear(&v[i]);
}

void cupid_model_destroy(cupid_model *model) {
  if (!model || !*model) return;
  cupid_model_t *m = *model;
  for (int i = 0; i < m->n_materials; i++) cupid_free(&m->materials[i].name);
  cupid_free(&m->materials);
  cupid_beam *b = &m->beam;
  cupid_free(&b->axis_y);
  cupid_free(&b->axis_elements);
  for (int i = 0; i < b->n_components; i++) {
    cupid_free(&b->components[i].x);
    cupid_free(&b->components[i].z);
  }
  cupid_free(&b->components);
  cupid_free(&b->section_nodes);
  cupid_free(&b->section_elements);
  cupid_free(&b->section_element_material);
  cupid_free(&b->section_mesh);
  for (int i = 0; i < m->pd.n_regions; i++) {
    cupid_surface_destroy(&m->pd.regions[i].shape.surface);
    cupid_free(&m->pd.regions[i].shape.file);
  }
  for (int i = 0; i < m->pd.n_holes; i++) {
    cupid_surface_destroy(&m->pd.holes[i].shape.surface);
    cupid_free(&m->pd.holes[i].shape.file);
  }
  cupid_free(&m->pd.regions);
  cupid_free(&m->pd.holes);
  cupid_free(&m->pd.precracks);
  for (int i = 0; i < m->n_constraints; i++) values_clear(m->constraints[i].value, 3);
  cupid_free(&m->constraints);
  for (int i = 0; i < m->n_loads; i++) values_clear(m->loads[i].value, 3);
  cupid_free(&m->loads);
  values_clear(m->analysis.field, 3);
  values_clear(m->analysis.dynamic.initial_displacement, 3);
  values_clear(m->analysis.dynamic.initial_velocity, 3);
  for (int i = 0; i < m->output.n_lines; i++) cupid_free(&m->output.lines[i].name);
  cupid_free(&m->output.lines);
  for (int i = 0; i < m->output.n_points; i++) cupid_free(&m->output.points[i].name);
  cupid_free(&m->output.points);
  cupid_free(&m->output.directory);
  cupid_free(&m->title);
  cupid_free(&m->file);
  for (int k = 0; k < m->n_sets; k++) cupid_free(&m->sets[k]);
  cupid_free(&m->sets);
  cupid_free(model);
}

/* The last --set whose path lies within the item at key ("peridynamics.precracks[0].at=50"
 * within "peridynamics.precracks[0]"), or NULL: an error about an item whose mark is in the
 * file may be about the value an override gave it. */
const char *mr_override_within(const char *const *sets, int n_sets, const char *key) {
  const size_t n = key ? strlen(key) : 0;
  const char *found = NULL;
  for (int k = 0; n > 0 && k < n_sets; k++) {
    const char *s = sets[k];
    if (strncmp(s, key, n) == 0 && (s[n] == '.' || s[n] == '[' || s[n] == '=')) found = s;
  }
  return found;
}

cupid_status cupid_model_error(const cupid_model_t *model, const cupid_mark *mark, const char *fmt,
                               ...) {
  char message[1536];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(message, sizeof message, fmt, ap);
  va_end(ap);
  const char *file = model && model->file ? model->file : "<model>";
  if (mark && model && mark->line > MR_SET_LINE && mark->line - 1 - MR_SET_LINE < model->n_sets)
    return CUPID_ERROR(CUPID_ERR_MODEL, "%s: --set %s: %s%s%s", file,
                       model->sets[mark->line - 1 - MR_SET_LINE], mark->key,
                       mark->key[0] ? ": " : "", message);
  if (!mark || mark->line <= 0) {
    if (mark && mark->key[0])
      return CUPID_ERROR(CUPID_ERR_MODEL, "%s: %s: %s", file, mark->key, message);
    return CUPID_ERROR(CUPID_ERR_MODEL, "%s: %s", file, message);
  }
  const char *set = mr_override_within((const char *const *)model->sets, model->n_sets, mark->key);
  if (set) /* the item is the file's, a value in it the override's: cite the override */
    return CUPID_ERROR(CUPID_ERR_MODEL, "%s: --set %s: %s (%s:%d:%d): %s", file, set, mark->key,
                       file, mark->line, mark->column, message);
  if (mark->key[0])
    return CUPID_ERROR(CUPID_ERR_MODEL, "%s:%d:%d: %s: %s", file, mark->line, mark->column,
                       mark->key, message);
  return CUPID_ERROR(CUPID_ERR_MODEL, "%s:%d:%d: %s", file, mark->line, mark->column, message);
}

double cupid_value_eval(const cupid_value *v, double x, double y, double z, double t,
                        double density) {
  if (!v) return 0.0;
  switch (v->kind) {
  case CUPID_VALUE_CONSTANT: return v->constant;
  case CUPID_VALUE_EXPR: {
    const double values[CUPID_EXPR_NVARS] = {x, y, z, t, density};
    return cupid_expr_eval(v->expr, values);
  }
  default: return 0.0;
  }
}

int cupid_box_contains(const cupid_box *box, const double p[3], double tol) {
  for (int a = 0; a < 3; a++)
    if (box->has[a] && (p[a] < box->lo[a] - tol || p[a] > box->hi[a] + tol)) return 0;
  return 1;
}

int cupid_shape_contains(const cupid_shape *shape, const double p[3]) {
  if (!cupid_box_contains(&shape->box, p, 0.0)) return 0;
  if (shape->kind == CUPID_SHAPE_GEOMETRY) return cupid_surface_contains(shape->surface, p);
  double r2 = 0.0;
  for (int a = 0; a < 3; a++) {
    if (shape->kind == CUPID_SHAPE_CYLINDER && a == shape->axis) continue;
    const double d = p[a] - shape->center[a];
    r2 += d * d;
  }
  return shape->kind == CUPID_SHAPE_BOX || r2 <= shape->radius * shape->radius;
}

int cupid_shape_chords(const cupid_shape *shape, double y, double z, double *x, int cap) {
  const cupid_box *b = &shape->box;
  if ((b->has[1] && (y < b->lo[1] || y > b->hi[1])) || (b->has[2] && (z < b->lo[2] || z > b->hi[2])))
    return 0;
  if (cap < 1) return -1;
  const double lo = b->has[0] ? b->lo[0] : -INFINITY, hi = b->has[0] ? b->hi[0] : INFINITY;
  const double *c = shape->center, r2 = shape->radius * shape->radius;
  int n = 1;
  x[0] = -INFINITY, x[1] = INFINITY;
  switch (shape->kind) {
  case CUPID_SHAPE_BOX: break;
  case CUPID_SHAPE_SPHERE:
  case CUPID_SHAPE_CYLINDER: {
    const double dy = y - c[1], dz = z - c[2];
    /* the half chord across the circle or sphere; along the cylinder's own axis x, the whole
     * line when (y, z) lies in the disc */
    double q = r2;
    if (shape->kind == CUPID_SHAPE_SPHERE || shape->axis == 0) q -= dy * dy + dz * dz;
    else q -= shape->axis == 1 ? dz * dz : dy * dy;
    if (q < 0) return 0;
    if (shape->kind == CUPID_SHAPE_SPHERE || shape->axis != 0)
      x[0] = c[0] - sqrt(q), x[1] = c[0] + sqrt(q);
    break;
  }
  case CUPID_SHAPE_GEOMETRY: n = cupid_surface_chords(shape->surface, y, z, x, cap); break;
  }
  int m = 0;
  for (int k = 0; k < n; k++) { /* clipped to the box; empty ones dropped */
    const double a = fmax(x[2 * k], lo), e = fmin(x[2 * k + 1], hi);
    if (e > a) x[2 * m] = a, x[2 * m + 1] = e, m++;
  }
  return n < 0 ? n : m;
}

/* Distance from t to [lo, hi] along an axis (0 inside; an axis without bounds: 0). */
static double axis_gap(const cupid_box *b, int a, double t) {
  if (!b->has[a]) return 0.0;
  return t < b->lo[a] ? b->lo[a] - t : t > b->hi[a] ? t - b->hi[a] : 0.0;
}

int cupid_shape_cuts_cell(const cupid_shape *shape, const double lo[3], double h) {
  if (shape->kind == CUPID_SHAPE_GEOMETRY) return 1;
  const double p[3] = {lo[0] + 0.5 * h, lo[1] + 0.5 * h, lo[2] + 0.5 * h}, r = 0.8661 * h;
  const cupid_box *b = &shape->box;
  for (int a = 0; a < 3; a++)
    if (axis_gap(b, a, p[a]) > r) return 0; /* outside the box grown by r */
  switch (shape->kind) {
  case CUPID_SHAPE_BOX: { /* near a face: not deeper inside than r on every bounded axis */
    int deep = 1;
    for (int a = 0; a < 3; a++)
      if (b->has[a]) deep &= p[a] - b->lo[a] > r && b->hi[a] - p[a] > r;
    return !deep;
  }
  case CUPID_SHAPE_SPHERE: {
    double d2 = 0.0;
    for (int a = 0; a < 3; a++) d2 += (p[a] - shape->center[a]) * (p[a] - shape->center[a]);
    return fabs(sqrt(d2) - shape->radius) <= r;
  }
  case CUPID_SHAPE_CYLINDER: {
    const int ax = shape->axis;
    double d2 = 0.0;
    for (int a = 0; a < 3; a++)
      if (a != ax) d2 += (p[a] - shape->center[a]) * (p[a] - shape->center[a]);
    const double rho = sqrt(d2);
    if (fabs(rho - shape->radius) <= r) return 1; /* the side (within the grown ends: above) */
    return b->has[ax] && rho <= shape->radius + r &&
           (fabs(p[ax] - b->lo[ax]) <= r || fabs(p[ax] - b->hi[ax]) <= r); /* an end */
  }
  case CUPID_SHAPE_GEOMETRY: break; /* above */
  }
  return 1;
}

void cupid_le_node_grid(int npe, int k, int *a, int *b) {
  static const int l4a[4] = {0, 1, 1, 0}, l4b[4] = {0, 0, 1, 1};
  static const int l9a[9] = {0, 1, 2, 2, 2, 1, 0, 0, 1}, l9b[9] = {0, 0, 0, 1, 2, 2, 2, 1, 1};
  static const int l16a[16] = {0, 1, 2, 3, 3, 3, 3, 2, 1, 0, 0, 0, 1, 2, 2, 1};
  static const int l16b[16] = {0, 0, 0, 0, 1, 2, 3, 3, 3, 3, 2, 1, 1, 1, 2, 2};
  const int *A = npe == 4 ? l4a : npe == 9 ? l9a : l16a, *B = npe == 4 ? l4b : npe == 9 ? l9b : l16b;
  *a = A[k];
  *b = B[k];
}
