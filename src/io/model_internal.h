/* Private interface of the model reader (src/io/model_*.c).
 *
 * model_read.c      libyaml loading, the bounded pre-pass, typed accessors and error helpers
 * model_sections.c  one parser per top-level section of model-format.md
 * model_validate.c  cross-section checks that need the whole model
 * model.c           the public entry points, destroy, cupid_model_error, values and boxes
 */
#ifndef CUPID_MODEL_INTERNAL_H
#define CUPID_MODEL_INTERNAL_H

#include <yaml.h>

#include "cupid/model.h"

/* Robustness limits: a hostile file must fail fast instead of exhausting time or memory. */
#define MODEL_MAX_FILE_BYTES ((size_t)16 << 20) /* 16 MiB of YAML is far beyond any model */
#define MODEL_MAX_VISITS 1000000L /* nodes visited with aliases expanded ("billion laughs") */
#define MODEL_MAX_DEPTH 64        /* nesting depth (also stops recursive aliases) */
#define MODEL_MAX_STRING 4096     /* title, directory, expressions */
#define MODEL_MAX_NAME 64         /* material, line and point names */
#define MODEL_MAX_KEYS 24         /* keys of one schema mapping */
#define MODEL_MAX_ANCHORS 1000L   /* libyaml registers and resolves anchors by linear search */
#define MODEL_MAX_ALIASES 100000L
#define MODEL_MAX_MATERIALS 1000  /* material references are resolved by linear search */
#define MODEL_MAX_PRECRACKS 1000  /* each is tested against every region, then every bond */

typedef struct {
  yaml_document_t *doc;
  const char *name; /* the file name used in messages */
  cupid_model_t *model;
  const char *const *sets; /* the --set overrides, for messages about their nodes */
  int n_sets;
} model_reader;

/* Nodes made by an override k (--set) carry the line MR_SET_LINE + k (model_override.c). */
#define MR_SET_LINE 1000000000
/* The last of sets ("key.path=value") whose path lies within the item at key, or NULL. */
const char *mr_override_within(const char *const *sets, int n_sets, const char *key);
#define MR_MAX_SETS 256
/* Apply the overrides "key.path=value" to the loaded document (model_override.c). */
cupid_status mr_apply_overrides(yaml_document_t *doc, const char *name, const char *const *sets,
                                int n_sets);

/* A schema mapping: the value of each allowed key (NULL when absent). */
typedef struct {
  yaml_node_t *node; /* the mapping itself */
  const char *path;
  const char *const *keys;
  int n_keys;
  yaml_node_t *value[MODEL_MAX_KEYS];
} mr_map;

/* ---- errors and marks ---- */

/** Record "FILE:LINE:COL: PATH: message" at @p node (path may be "") and return CUPID_ERR_MODEL. */
cupid_status mr_error(const model_reader *rd, const yaml_node_t *node, const char *path,
                      const char *fmt, ...) __attribute__((format(printf, 4, 5)));
/** Same at an explicit 0-based (line, column). */
cupid_status mr_error_at(const model_reader *rd, int line0, int column0, const char *path,
                         const char *fmt, ...) __attribute__((format(printf, 5, 6)));
/** Fill a cupid_mark from a node's start mark. */
void mr_mark(const yaml_node_t *node, const char *path, cupid_mark *mark);
/** Short description of a node for "got ...": 'text', null, a list, a mapping. */
const char *mr_describe(const yaml_node_t *node, char *buf, size_t size);
/** The closest name within edit distance 2 (or equal ignoring case), or NULL. */
const char *mr_closest(const char *word, const char *const *names, int n);
/** Join names as "a, b, c" into buf (truncated with ", ..."). */
void mr_join(const char *const *names, int n, const char *sep, char *buf, size_t size);

/* ---- structure ---- */

yaml_node_t *mr_node(const model_reader *rd, int index);
int mr_is_null(const yaml_node_t *node);
int mr_is_scalar(const yaml_node_t *node);
/** "parent.key" (or "key" when parent is empty) into buf[128]. */
void mr_path(char *buf, const char *parent, const char *key);
/** "parent[i]" into buf[128]. */
void mr_path_index(char *buf, const char *parent, int index);
/** Check a mapping against its allowed keys (unknown, duplicate, non-scalar keys are errors). */
cupid_status mr_map_open(const model_reader *rd, yaml_node_t *node, const char *path,
                         const char *const *keys, int n_keys, mr_map *map);
yaml_node_t *mr_get(const mr_map *map, const char *key);
/** The value of a required key, or "missing required key" at the mapping. */
cupid_status mr_require(const model_reader *rd, const mr_map *map, const char *key,
                        yaml_node_t **value);
/** A list node: its length (null counts as an empty list when allow_null). */
cupid_status mr_list(const model_reader *rd, yaml_node_t *node, const char *path, int allow_null,
                     const char *what, int *count);
yaml_node_t *mr_item(const model_reader *rd, const yaml_node_t *list, int index);

/* ---- typed scalars ---- */

cupid_status mr_number(const model_reader *rd, const yaml_node_t *node, const char *path,
                       double *out);
/** A number > 0. */
cupid_status mr_positive(const model_reader *rd, const yaml_node_t *node, const char *path,
                         double *out);
/** A number > 0 or the word auto (*is_auto 1, *out 0). */
cupid_status mr_positive_or_auto(const model_reader *rd, const yaml_node_t *node,
                                const char *path, int *is_auto, double *out);
/** A number >= 0. */
cupid_status mr_nonnegative(const model_reader *rd, const yaml_node_t *node, const char *path,
                            double *out);
cupid_status mr_integer(const model_reader *rd, const yaml_node_t *node, const char *path,
                        long min, long max, int *out);
cupid_status mr_bool(const model_reader *rd, const yaml_node_t *node, const char *path, int *out);
/** A string of at most @p max_length bytes (no NUL); allocated into *out. */
cupid_status mr_string(const model_reader *rd, const yaml_node_t *node, const char *path,
                       size_t max_length, char **out);
/** One of names[]: its index. */
cupid_status mr_enum(const model_reader *rd, const yaml_node_t *node, const char *path,
                     const char *const *names, int n, int *out);
/** A list of exactly n numbers; @p what describes it for messages ("[x, y, z]"). */
cupid_status mr_numbers(const model_reader *rd, yaml_node_t *node, const char *path, int n,
                        const char *what, double *out);
/** A list of >= min_count strictly increasing numbers, allocated. */
cupid_status mr_breakpoints(const model_reader *rd, yaml_node_t *node, const char *path,
                            int min_count, double **out, int *count);
/** [min, max] with min <= max (strict: min < max). */
cupid_status mr_range(const model_reader *rd, yaml_node_t *node, const char *path, int strict,
                      double out[2]);
/** A box {x: [..], y: [..], z: [..]} with at least one axis. */
cupid_status mr_box(const model_reader *rd, yaml_node_t *node, const char *path, cupid_box *box);
/** mr_box with one more key allowed (@p extra): its value in *extra_value (NULL if absent). */
cupid_status mr_box_extra(const model_reader *rd, yaml_node_t *node, const char *path,
                          const char *extra, cupid_box *box, yaml_node_t **extra_value);
/** A number, an expression string (x y z t density) or, when allow_null, null (free). */
cupid_status mr_value(const model_reader *rd, const yaml_node_t *node, const char *path,
                      int allow_null, cupid_value *out);
/** A list of 3 values. */
cupid_status mr_values3(const model_reader *rd, yaml_node_t *node, const char *path,
                        int allow_null, cupid_value out[3]);
/** A material name: its index in model->materials. */
cupid_status mr_material(const model_reader *rd, const yaml_node_t *node, const char *path,
                         int *index);
/** Index of the first name equal to an earlier one (and that earlier one), or -1. */
int mr_find_duplicate(char *const *names, int n, int *first);

/* ---- document ---- */

/** Parse text into a document (syntax, UTF-8, empty, multi-document errors), then run the
 *  bounded pre-pass over it. On success the caller must yaml_document_delete(doc). */
cupid_status mr_load(const char *text, size_t length, const char *name, yaml_document_t *doc);

/* ---- sections (model_sections.c) and checks (model_validate.c) ---- */

cupid_status mr_read_model(model_reader *rd, yaml_node_t *root);
cupid_status mr_validate(model_reader *rd, const mr_map *top);

#endif
