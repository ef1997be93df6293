/* Model reader, part 1: libyaml loading, the bounded pre-pass, and the typed accessors every
 * section parser uses. Each accessor reports its own errors as "FILE:LINE:COL: PATH: what is
 * wrong, and what is allowed" at the offending node (libyaml marks are 0-based; we print 1-based).
 */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/model_internal.h"

/* ------------------------------------------------------------------------------------------ */
/* Errors, marks and messages                                                                 */
/* ------------------------------------------------------------------------------------------ */

static cupid_status error_va(const model_reader *rd, int line0, int column0, const char *path,
                             const char *fmt, va_list ap) {
  char message[1536];
  const char *name = rd->name;
  vsnprintf(message, sizeof message, fmt, ap);
  if (line0 >= MR_SET_LINE && line0 - MR_SET_LINE < rd->n_sets) /* a --set value's node */
    return CUPID_ERROR(CUPID_ERR_MODEL, "%s: --set %s: %s%s%s", name,
                       rd->sets[line0 - MR_SET_LINE], path && path[0] ? path : "",
                       path && path[0] ? ": " : "", message);
  const char *set = path ? mr_override_within(rd->sets, rd->n_sets, path) : NULL;
  if (set) /* the item is the file's, a value in it the override's: cite the override */
    return CUPID_ERROR(CUPID_ERR_MODEL, "%s: --set %s: %s (%s:%d:%d): %s", name, set, path, name,
                       line0 + 1, column0 + 1, message);
  if (path && path[0])
    return CUPID_ERROR(CUPID_ERR_MODEL, "%s:%d:%d: %s: %s", name, line0 + 1, column0 + 1, path,
                       message);
  return CUPID_ERROR(CUPID_ERR_MODEL, "%s:%d:%d: %s", name, line0 + 1, column0 + 1, message);
}

cupid_status mr_error(const model_reader *rd, const yaml_node_t *node, const char *path,
                      const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int line = node ? (int)node->start_mark.line : 0;
  int column = node ? (int)node->start_mark.column : 0;
  cupid_status st = error_va(rd, line, column, path, fmt, ap);
  va_end(ap);
  return st;
}

cupid_status mr_error_at(const model_reader *rd, int line0, int column0, const char *path,
                         const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  cupid_status st = error_va(rd, line0, column0, path, fmt, ap);
  va_end(ap);
  return st;
}

/* Copy at most max bytes of s into buf, escaping anything that is not printable ASCII. */
static void printable(const char *s, size_t length, size_t max, char *buf, size_t size) {
  size_t k = 0;
  size_t n = length < max ? length : max;
  for (size_t i = 0; i < n && k + 5 < size; i++) {
    unsigned char c = (unsigned char)s[i];
    if (c >= 0x20 && c < 0x7f) buf[k++] = (char)c;
    else k += (size_t)snprintf(buf + k, size - k, "\\x%02x", c);
  }
  if (n < length && k + 4 < size) {
    memcpy(buf + k, "...", 3);
    k += 3;
  }
  buf[k] = '\0';
}

static void copy_truncated(char *dst, size_t size, const char *a, const char *b, const char *c) {
  size_t k = 0;
  const char *parts[3] = {a, b, c};
  for (int p = 0; p < 3; p++)
    for (const char *s = parts[p]; s && *s && k + 1 < size; s++) dst[k++] = *s;
  dst[k] = '\0';
}

void mr_path(char *buf, const char *parent, const char *key) {
  char safe[48];
  printable(key, strlen(key), 40, safe, sizeof safe);
  if (parent && parent[0]) copy_truncated(buf, sizeof(((cupid_mark *)0)->key), parent, ".", safe);
  else copy_truncated(buf, sizeof(((cupid_mark *)0)->key), safe, NULL, NULL);
}

void mr_path_index(char *buf, const char *parent, int index) {
  char suffix[24];
  snprintf(suffix, sizeof suffix, "[%d]", index);
  copy_truncated(buf, sizeof(((cupid_mark *)0)->key), parent, suffix, NULL);
}

void mr_mark(const yaml_node_t *node, const char *path, cupid_mark *mark) {
  mark->line = node ? (int)node->start_mark.line + 1 : 0;
  mark->column = node ? (int)node->start_mark.column + 1 : 0;
  copy_truncated(mark->key, sizeof mark->key, path, NULL, NULL);
}

static const char *scalar(const yaml_node_t *node) { return (const char *)node->data.scalar.value; }

int mr_is_scalar(const yaml_node_t *node) { return node && node->type == YAML_SCALAR_NODE; }

int mr_is_null(const yaml_node_t *node) {
  if (!mr_is_scalar(node) || node->data.scalar.style != YAML_PLAIN_SCALAR_STYLE) return 0;
  const char *s = scalar(node);
  return !strcmp(s, "") || !strcmp(s, "~") || !strcmp(s, "null") || !strcmp(s, "Null") ||
         !strcmp(s, "NULL");
}

const char *mr_describe(const yaml_node_t *node, char *buf, size_t size) {
  if (!node) snprintf(buf, size, "nothing");
  else if (node->type == YAML_SEQUENCE_NODE) snprintf(buf, size, "a list");
  else if (node->type == YAML_MAPPING_NODE) snprintf(buf, size, "a mapping");
  else if (mr_is_null(node)) snprintf(buf, size, "null");
  else {
    char text[160];
    printable(scalar(node), node->data.scalar.length, 40, text, sizeof text);
    snprintf(buf, size, "'%s'", text);
  }
  return buf;
}

/* Levenshtein distance, for "did you mean" (names are short: at most 64 characters). */
static int edit_distance(const char *a, const char *b) {
  size_t n = strlen(a), m = strlen(b);
  if (n > 64 || m > 64) return 99;
  int row[65];
  for (size_t j = 0; j <= m; j++) row[j] = (int)j;
  for (size_t i = 1; i <= n; i++) {
    int diag = row[0];
    row[0] = (int)i;
    for (size_t j = 1; j <= m; j++) {
      int up = row[j];
      int cost = a[i - 1] == b[j - 1] ? 0 : 1;
      int best = diag + cost;
      if (up + 1 < best) best = up + 1;
      if (row[j - 1] + 1 < best) best = row[j - 1] + 1;
      row[j] = best;
      diag = up;
    }
  }
  return row[m];
}

static int equal_ignoring_case(const char *a, const char *b) {
  for (; *a && *b; a++, b++)
    if (tolower((unsigned char)*a) != tolower((unsigned char)*b)) return 0;
  return *a == *b;
}

const char *mr_closest(const char *word, const char *const *names, int n) {
  for (int i = 0; i < n; i++)
    if (equal_ignoring_case(word, names[i])) return names[i];
  const char *best = NULL;
  int best_distance = 3;
  for (int i = 0; i < n; i++) {
    int d = edit_distance(word, names[i]);
    /* A one-letter name is never "close" to a different one-letter word. */
    if (d < best_distance && d < (int)strlen(names[i])) {
      best = names[i];
      best_distance = d;
    }
  }
  return best;
}

void mr_join(const char *const *names, int n, const char *sep, char *buf, size_t size) {
  size_t k = 0;
  buf[0] = '\0';
  for (int i = 0; i < n; i++) {
    size_t need = strlen(names[i]) + strlen(sep) + 8;
    if (k + need >= size) {
      snprintf(buf + k, size - k, "%s...", i ? sep : "");
      return;
    }
    k += (size_t)snprintf(buf + k, size - k, "%s%s", i ? sep : "", names[i]);
  }
}

/* ------------------------------------------------------------------------------------------ */
/* Structure                                                                                  */
/* ------------------------------------------------------------------------------------------ */

yaml_node_t *mr_node(const model_reader *rd, int index) {
  return yaml_document_get_node(rd->doc, index);
}

cupid_status mr_map_open(const model_reader *rd, yaml_node_t *node, const char *path,
                         const char *const *keys, int n_keys, mr_map *map) {
  memset(map, 0, sizeof *map);
  map->node = node;
  map->path = path;
  map->keys = keys;
  map->n_keys = n_keys;
  /* An absent section, or "section:" with nothing after it, reads as an empty mapping. */
  if (!node || mr_is_null(node)) return CUPID_SUCCESS;
  char got[64];
  if (!node || node->type != YAML_MAPPING_NODE)
    return mr_error(rd, node, path, "must be a mapping (key: value), got %s",
                    mr_describe(node, got, sizeof got));
  const yaml_node_t *key_node[MODEL_MAX_KEYS] = {0};
  for (yaml_node_pair_t *p = node->data.mapping.pairs.start; p < node->data.mapping.pairs.top;
       p++) {
    yaml_node_t *key = mr_node(rd, p->key);
    if (!mr_is_scalar(key) || mr_is_null(key))
      return mr_error(rd, key, path, "keys must be plain names, got %s",
                      mr_describe(key, got, sizeof got));
    const char *name = scalar(key);
    char key_path[sizeof(((cupid_mark *)0)->key)];
    mr_path(key_path, path, name);
    int found = -1;
    if (strlen(name) == key->data.scalar.length)
      for (int i = 0; i < n_keys; i++)
        if (!strcmp(name, keys[i])) found = i;
    if (found < 0) {
      const char *hint = mr_closest(name, keys, n_keys);
      if (hint) return mr_error(rd, key, key_path, "unknown key; did you mean '%s'?", hint);
      char allowed[512];
      mr_join(keys, n_keys, ", ", allowed, sizeof allowed);
      return mr_error(rd, key, key_path, "unknown key; allowed keys here: %s", allowed);
    }
    if (key_node[found])
      return mr_error(rd, key, key_path, "duplicate key (first given at line %d)",
                      (int)key_node[found]->start_mark.line + 1);
    key_node[found] = key;
    map->value[found] = mr_node(rd, p->value);
  }
  return CUPID_SUCCESS;
}

yaml_node_t *mr_get(const mr_map *map, const char *key) {
  for (int i = 0; i < map->n_keys; i++)
    if (!strcmp(map->keys[i], key)) return map->value[i];
  return NULL;
}

cupid_status mr_require(const model_reader *rd, const mr_map *map, const char *key,
                        yaml_node_t **value) {
  *value = mr_get(map, key);
  if (*value) return CUPID_SUCCESS;
  return mr_error(rd, map->node, map->path, "missing required key '%s'", key);
}

cupid_status mr_list(const model_reader *rd, yaml_node_t *node, const char *path, int allow_null,
                     const char *what, int *count) {
  *count = 0;
  if (allow_null && (!node || mr_is_null(node))) return CUPID_SUCCESS;
  char got[64];
  if (!node || node->type != YAML_SEQUENCE_NODE)
    return mr_error(rd, node, path, "must be a list of %s, got %s", what,
                    mr_describe(node, got, sizeof got));
  *count = (int)(node->data.sequence.items.top - node->data.sequence.items.start);
  return CUPID_SUCCESS;
}

yaml_node_t *mr_item(const model_reader *rd, const yaml_node_t *list, int index) {
  return mr_node(rd, list->data.sequence.items.start[index]);
}

/* ------------------------------------------------------------------------------------------ */
/* Typed scalars                                                                              */
/* ------------------------------------------------------------------------------------------ */

/* A decimal number: [+-] digits [. digits] [e [+-] digits] (or . digits); YAML's .inf, .nan,
 * hexadecimal and 1_000 forms are refused. Returns 1 and the value on success. */
static int parse_number(const char *s, size_t length, double *out) {
  if (length == 0 || length >= 64) return 0;
  size_t i = 0, digits = 0;
  if (s[i] == '+' || s[i] == '-') i++;
  while (i < length && isdigit((unsigned char)s[i])) i++, digits++;
  if (i < length && s[i] == '.') {
    i++;
    while (i < length && isdigit((unsigned char)s[i])) i++, digits++;
  }
  if (digits == 0) return 0;
  if (i < length && (s[i] == 'e' || s[i] == 'E')) {
    i++;
    if (i < length && (s[i] == '+' || s[i] == '-')) i++;
    size_t exponent_digits = 0;
    while (i < length && isdigit((unsigned char)s[i])) i++, exponent_digits++;
    if (exponent_digits == 0) return 0;
  }
  if (i != length) return 0;
  char buf[64];
  memcpy(buf, s, length);
  buf[length] = '\0';
  *out = strtod(buf, NULL);
  return 1;
}

cupid_status mr_number(const model_reader *rd, const yaml_node_t *node, const char *path,
                       double *out) {
  char got[64];
  if (!mr_is_scalar(node) || mr_is_null(node) ||
      !parse_number(scalar(node), node->data.scalar.length, out))
    return mr_error(rd, node, path, "must be a number, got %s", mr_describe(node, got, sizeof got));
  if (!isfinite(*out))
    return mr_error(rd, node, path, "must be a finite number, got %s",
                    mr_describe(node, got, sizeof got));
  return CUPID_SUCCESS;
}

cupid_status mr_positive(const model_reader *rd, const yaml_node_t *node, const char *path,
                         double *out) {
  CUPID_CALL(mr_number(rd, node, path, out));
  if (!(*out > 0)) return mr_error(rd, node, path, "must be > 0, got %s", scalar(node));
  return CUPID_SUCCESS;
}

cupid_status mr_positive_or_auto(const model_reader *rd, const yaml_node_t *node,
                                const char *path, int *is_auto, double *out) {
  char got[64];
  *is_auto = mr_is_scalar(node) && !mr_is_null(node) && !strcmp(scalar(node), "auto");
  *out = 0.0;
  if (*is_auto) return CUPID_SUCCESS;
  if (!mr_is_scalar(node) || mr_is_null(node) ||
      !parse_number(scalar(node), node->data.scalar.length, out) || !isfinite(*out) || !(*out > 0))
    return mr_error(rd, node, path, "must be a positive number or auto, got %s",
                    mr_describe(node, got, sizeof got));
  return CUPID_SUCCESS;
}

cupid_status mr_nonnegative(const model_reader *rd, const yaml_node_t *node, const char *path,
                            double *out) {
  CUPID_CALL(mr_number(rd, node, path, out));
  if (!(*out >= 0)) return mr_error(rd, node, path, "must be >= 0, got %s", scalar(node));
  return CUPID_SUCCESS;
}

cupid_status mr_integer(const model_reader *rd, const yaml_node_t *node, const char *path,
                        long min, long max, int *out) {
  char got[64];
  int ok = mr_is_scalar(node) && !mr_is_null(node);
  const char *s = ok ? scalar(node) : "";
  size_t length = ok ? node->data.scalar.length : 0;
  size_t i = (length > 0 && (s[0] == '+' || s[0] == '-')) ? 1 : 0;
  ok = ok && length > i && length - i <= 12;
  for (size_t k = i; ok && k < length; k++) ok = isdigit((unsigned char)s[k]) != 0;
  if (!ok)
    return mr_error(rd, node, path, "must be an integer, got %s",
                    mr_describe(node, got, sizeof got));
  long long v = strtoll(s, NULL, 10);
  if (v < min || v > max) {
    if (max >= 1000000000L)
      return mr_error(rd, node, path, "must be an integer >= %ld, got %s", min, s);
    return mr_error(rd, node, path, "must be an integer from %ld to %ld, got %s", min, max, s);
  }
  *out = (int)v;
  return CUPID_SUCCESS;
}

cupid_status mr_bool(const model_reader *rd, const yaml_node_t *node, const char *path, int *out) {
  char got[64];
  if (mr_is_scalar(node) && node->data.scalar.style == YAML_PLAIN_SCALAR_STYLE) {
    const char *s = scalar(node);
    if (!strcmp(s, "true") || !strcmp(s, "True") || !strcmp(s, "TRUE")) {
      *out = 1;
      return CUPID_SUCCESS;
    }
    if (!strcmp(s, "false") || !strcmp(s, "False") || !strcmp(s, "FALSE")) {
      *out = 0;
      return CUPID_SUCCESS;
    }
  }
  return mr_error(rd, node, path, "must be true or false, got %s",
                  mr_describe(node, got, sizeof got));
}

cupid_status mr_string(const model_reader *rd, const yaml_node_t *node, const char *path,
                       size_t max_length, char **out) {
  char got[64];
  if (!mr_is_scalar(node) || mr_is_null(node))
    return mr_error(rd, node, path, "must be a string, got %s", mr_describe(node, got, sizeof got));
  if (node->data.scalar.length > max_length)
    return mr_error(rd, node, path, "is too long (%zu bytes, at most %zu)",
                    node->data.scalar.length, max_length);
  if (strlen(scalar(node)) != node->data.scalar.length)
    return mr_error(rd, node, path, "must not contain NUL characters");
  return cupid_strdup(scalar(node), out);
}

cupid_status mr_enum(const model_reader *rd, const yaml_node_t *node, const char *path,
                     const char *const *names, int n, int *out) {
  char allowed[256], got[64];
  mr_join(names, n, " | ", allowed, sizeof allowed);
  if (mr_is_scalar(node) && !mr_is_null(node)) {
    const char *s = scalar(node);
    for (int i = 0; i < n; i++)
      if (!strcmp(s, names[i])) {
        *out = i;
        return CUPID_SUCCESS;
      }
    const char *hint = mr_closest(s, names, n);
    if (hint)
      return mr_error(rd, node, path, "must be one of %s, got %s; did you mean '%s'?", allowed,
                      mr_describe(node, got, sizeof got), hint);
  }
  return mr_error(rd, node, path, "must be one of %s, got %s", allowed,
                  mr_describe(node, got, sizeof got));
}

cupid_status mr_numbers(const model_reader *rd, yaml_node_t *node, const char *path, int n,
                        const char *what, double *out) {
  char got[64];
  if (!node || node->type != YAML_SEQUENCE_NODE)
    return mr_error(rd, node, path, "must be a list of %d numbers %s, got %s", n, what,
                    mr_describe(node, got, sizeof got));
  int count = (int)(node->data.sequence.items.top - node->data.sequence.items.start);
  if (count != n)
    return mr_error(rd, node, path, "must be a list of %d numbers %s, got %d item%s", n, what,
                    count, count == 1 ? "" : "s");
  for (int i = 0; i < n; i++) {
    char item_path[sizeof(((cupid_mark *)0)->key)];
    mr_path_index(item_path, path, i);
    CUPID_CALL(mr_number(rd, mr_item(rd, node, i), item_path, &out[i]));
  }
  return CUPID_SUCCESS;
}

cupid_status mr_breakpoints(const model_reader *rd, yaml_node_t *node, const char *path,
                            int min_count, double **out, int *count) {
  char got[64];
  *out = NULL;
  *count = 0;
  int n = 0;
  if (node && node->type == YAML_SEQUENCE_NODE)
    n = (int)(node->data.sequence.items.top - node->data.sequence.items.start);
  if (!node || node->type != YAML_SEQUENCE_NODE || n < min_count)
    return mr_error(rd, node, path, "must be a list of at least %d increasing numbers, got %s",
                    min_count,
                    node && node->type == YAML_SEQUENCE_NODE
                        ? (snprintf(got, sizeof got, "%d item%s", n, n == 1 ? "" : "s"), got)
                        : mr_describe(node, got, sizeof got));
  cupid_status st = CUPID_SUCCESS;
  double *v = NULL;
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *v, "breakpoints", &v));
  for (int i = 0; i < n; i++) {
    char item_path[sizeof(((cupid_mark *)0)->key)];
    mr_path_index(item_path, path, i);
    yaml_node_t *item = mr_item(rd, node, i);
    CUPID_TRY(mr_number(rd, item, item_path, &v[i]));
    if (i > 0 && !(v[i] > v[i - 1])) {
      st = mr_error(rd, item, item_path, "breakpoints must increase, got %g after %g", v[i],
                    v[i - 1]);
      goto cleanup;
    }
  }
  *out = v;
  *count = n;
  v = NULL;
cleanup:
  cupid_free(&v);
  return st;
}

cupid_status mr_range(const model_reader *rd, yaml_node_t *node, const char *path, int strict,
                      double out[2]) {
  CUPID_CALL(mr_numbers(rd, node, path, 2, "[min, max]", out));
  if (strict ? !(out[0] < out[1]) : !(out[0] <= out[1]))
    return mr_error(rd, node, path, "must be [min, max] with min %s max, got [%g, %g]",
                    strict ? "<" : "<=", out[0], out[1]);
  return CUPID_SUCCESS;
}

cupid_status mr_box(const model_reader *rd, yaml_node_t *node, const char *path, cupid_box *box) {
  return mr_box_extra(rd, node, path, NULL, box, NULL);
}

cupid_status mr_box_extra(const model_reader *rd, yaml_node_t *node, const char *path,
                          const char *extra, cupid_box *box, yaml_node_t **extra_value) {
  const char *const axes[] = {"x", "y", "z", extra};
  mr_map map;
  CUPID_CALL(mr_map_open(rd, node, path, axes, extra ? 4 : 3, &map));
  if (extra_value) *extra_value = mr_get(&map, extra);
  int any = 0;
  for (int a = 0; a < 3; a++) {
    box->lo[a] = -INFINITY;
    box->hi[a] = INFINITY;
    box->has[a] = 0;
    if (!map.value[a]) continue;
    char axis_path[sizeof(((cupid_mark *)0)->key)];
    mr_path(axis_path, path, axes[a]);
    double r[2];
    CUPID_CALL(mr_range(rd, map.value[a], axis_path, 0, r));
    box->lo[a] = r[0];
    box->hi[a] = r[1];
    box->has[a] = 1;
    any = 1;
  }
  if (!any)
    return mr_error(rd, node, path, "a box needs at least one of x, y, z, each [min, max]");
  return CUPID_SUCCESS;
}

/* Column in the file of 1-based column @p column of a scalar's text (quotes shift it by one). */
static int scalar_text_column0(const yaml_node_t *node, int column) {
  int shift = node->data.scalar.style == YAML_SINGLE_QUOTED_SCALAR_STYLE ||
                      node->data.scalar.style == YAML_DOUBLE_QUOTED_SCALAR_STYLE
                  ? 1
                  : 0;
  return (int)node->start_mark.column + shift + (column > 0 ? column - 1 : 0);
}

cupid_status mr_value(const model_reader *rd, const yaml_node_t *node, const char *path,
                      int allow_null, cupid_value *out) {
  char got[64];
  memset(out, 0, sizeof *out);
  if (mr_is_null(node)) {
    if (allow_null) return CUPID_SUCCESS; /* CUPID_VALUE_NONE: a free component */
    return mr_error(rd, node, path,
                    "must be a number or an expression, got null (null, a free component, is "
                    "allowed only in displacement constraints)");
  }
  if (!mr_is_scalar(node))
    return mr_error(rd, node, path, "must be a number or an expression string, got %s",
                    mr_describe(node, got, sizeof got));
  const char *s = scalar(node);
  size_t length = node->data.scalar.length;
  if (parse_number(s, length, &out->constant)) {
    if (!isfinite(out->constant))
      return mr_error(rd, node, path, "must be a finite number, got %s",
                      mr_describe(node, got, sizeof got));
    out->kind = CUPID_VALUE_CONSTANT;
    return CUPID_SUCCESS;
  }
  if (strlen(s) != length) return mr_error(rd, node, path, "must not contain NUL characters");
  int column = 0;
  cupid_expr e = NULL;
  cupid_status st = cupid_expr_create(s, cupid_expr_model_vars, CUPID_EXPR_NVARS, &e, &column);
  if (st == CUPID_ERR_MODEL) {
    char why[600], text[160];
    snprintf(why, sizeof why, "%s", cupid_error_message());
    printable(s, length, 60, text, sizeof text);
    return mr_error_at(rd, (int)node->start_mark.line, scalar_text_column0(node, column), path,
                       "bad expression \"%s\": %s", text, why);
  }
  CUPID_CALL(st);
  if (cupid_expr_is_constant(e)) {
    out->constant = cupid_expr_eval(e, NULL);
    cupid_expr_destroy(&e);
    if (!isfinite(out->constant))
      return mr_error(rd, node, path, "expression %s evaluates to %g",
                      mr_describe(node, got, sizeof got), out->constant);
    out->kind = CUPID_VALUE_CONSTANT;
    return CUPID_SUCCESS;
  }
  out->kind = CUPID_VALUE_EXPR;
  out->expr = e;
  return CUPID_SUCCESS;
}

cupid_status mr_values3(const model_reader *rd, yaml_node_t *node, const char *path,
                        int allow_null, cupid_value out[3]) {
  char got[64];
  const char *what = allow_null ? "values [vx, vy, vz] (numbers, expressions or null)"
                                : "values [vx, vy, vz] (numbers or expressions)";
  if (!node || node->type != YAML_SEQUENCE_NODE)
    return mr_error(rd, node, path, "must be a list of 3 %s, got %s", what,
                    mr_describe(node, got, sizeof got));
  int count = (int)(node->data.sequence.items.top - node->data.sequence.items.start);
  if (count != 3)
    return mr_error(rd, node, path, "must be a list of 3 %s, got %d item%s", what, count,
                    count == 1 ? "" : "s");
  for (int i = 0; i < 3; i++) {
    char item_path[sizeof(((cupid_mark *)0)->key)];
    mr_path_index(item_path, path, i);
    CUPID_CALL(mr_value(rd, mr_item(rd, node, i), item_path, allow_null, &out[i]));
  }
  return CUPID_SUCCESS;
}

cupid_status mr_material(const model_reader *rd, const yaml_node_t *node, const char *path,
                         int *index) {
  char got[64];
  const cupid_model_t *m = rd->model;
  if (!mr_is_scalar(node) || mr_is_null(node))
    return mr_error(rd, node, path, "must be a material name, got %s",
                    mr_describe(node, got, sizeof got));
  const char *s = scalar(node);
  for (int i = 0; i < m->n_materials; i++)
    if (!strcmp(s, m->materials[i].name)) {
      *index = i;
      return CUPID_SUCCESS;
    }
  /* The names live in the materials; gather pointers for the hint and the list. */
  const char *names[16];
  int n = m->n_materials < 16 ? m->n_materials : 16;
  for (int i = 0; i < n; i++) names[i] = m->materials[i].name;
  const char *hint = mr_closest(s, names, n);
  if (hint)
    return mr_error(rd, node, path, "unknown material %s; did you mean '%s'?",
                    mr_describe(node, got, sizeof got), hint);
  char known[512];
  mr_join(names, n, ", ", known, sizeof known);
  return mr_error(rd, node, path, "unknown material %s; known materials: %s%s",
                  mr_describe(node, got, sizeof got), known, m->n_materials > n ? ", ..." : "");
}

typedef struct {
  const char *name;
  int index;
} named_index;

static int compare_named(const void *a, const void *b) {
  const named_index *x = a, *y = b;
  int c = strcmp(x->name, y->name);
  return c ? c : (x->index > y->index) - (x->index < y->index);
}

int mr_find_duplicate(char *const *names, int n, int *first) {
  if (n < 2) return -1;
  named_index *v = malloc((size_t)n * sizeof *v);
  int found = -1;
  if (!v) { /* fall back to the quadratic search rather than fail */
    for (int j = 1; j < n && found < 0; j++)
      for (int i = 0; i < j; i++)
        if (!strcmp(names[i], names[j])) {
          found = j;
          *first = i;
          break;
        }
    return found;
  }
  for (int i = 0; i < n; i++) v[i] = (named_index){names[i], i};
  qsort(v, (size_t)n, sizeof *v, compare_named);
  /* Sorted by (name, index): in each run of equal names the first entry is the earliest. The
   * duplicate to report is the earliest second occurrence in file order. */
  for (int i = 1; i < n; i++)
    if (!strcmp(v[i].name, v[i - 1].name) && (found < 0 || v[i].index < found)) {
      int run_start = i - 1;
      while (run_start > 0 && !strcmp(v[run_start - 1].name, v[i].name)) run_start--;
      found = v[i].index;
      *first = v[run_start].index;
    }
  free(v);
  return found;
}

/* ------------------------------------------------------------------------------------------ */
/* Loading the document                                                                       */
/* ------------------------------------------------------------------------------------------ */

/* Line and column (0-based, in characters) of a byte offset; libyaml gives reader errors (bad
 * UTF-8, control characters) only as an offset. */
static void offset_position(const char *text, size_t length, size_t offset, int *line0,
                            int *column0) {
  int line = 0, column = 0;
  for (size_t i = 0; i < offset && i < length; i++) {
    unsigned char c = (unsigned char)text[i];
    if (c == '\n') {
      line++;
      column = 0;
    } else if ((c & 0xC0) != 0x80) {
      column++;
    }
  }
  *line0 = line;
  *column0 = column;
}

/* The byte at a 0-based (line, column-in-characters) position, or -1. */
static int byte_at(const char *text, size_t length, size_t line0, size_t column0) {
  size_t i = 0;
  for (size_t line = 0; line < line0 && i < length; i++)
    if (text[i] == '\n') line++;
  for (size_t column = 0; i < length && text[i] != '\n'; i++) {
    if (((unsigned char)text[i] & 0xC0) == 0x80) continue;
    if (column++ == column0) return (unsigned char)text[i];
  }
  return -1;
}

static cupid_status parser_error(const yaml_parser_t *parser, const char *text, size_t length,
                                 const char *name) {
  if (parser->error == YAML_MEMORY_ERROR)
    return CUPID_ERROR(CUPID_ERR_MEMORY, "%s: out of memory while reading the YAML", name);
  const char *problem = parser->problem ? parser->problem : "unknown problem";
  if (parser->error == YAML_READER_ERROR) {
    int line, column;
    size_t offset = parser->problem_offset;
    /* libyaml points at the bad continuation byte; the user wants the broken character. */
    if (strstr(problem, "trailing"))
      for (int back = 0; back < 3 && offset > 0 && offset <= length; back++)
        if (((unsigned char)text[--offset] & 0xC0) == 0xC0) break;
    offset_position(text, length, offset, &line, &column);
    int encoding = strstr(problem, "UTF") || strstr(problem, "Unicode");
    char value[32] = "";
    if (parser->problem_value >= 0 && !strstr(problem, "trailing"))
      snprintf(value, sizeof value, " (byte 0x%02x)", (unsigned)parser->problem_value);
    return CUPID_ERROR(CUPID_ERR_MODEL, "%s:%d:%d: %s: %s%s", name, line + 1, column + 1,
                       encoding ? "not valid UTF-8 text" : "invalid character", problem, value);
  }
  const yaml_mark_t *mark = &parser->problem_mark;
  const char *hint = "";
  if (byte_at(text, length, mark->line, mark->column) == '\t')
    hint = "; YAML does not allow tabs for indentation, use spaces";
  if (parser->context)
    return CUPID_ERROR(CUPID_ERR_MODEL, "%s:%d:%d: YAML syntax error: %s (%s)%s", name,
                       (int)mark->line + 1, (int)mark->column + 1, problem, parser->context,
                       hint);
  return CUPID_ERROR(CUPID_ERR_MODEL, "%s:%d:%d: YAML syntax error: %s%s", name,
                     (int)mark->line + 1, (int)mark->column + 1, problem, hint);
}

/* Visit every node with aliases expanded, bounding the count and the depth, so that later
 * passes (which never descend further than this one) cannot be made to run away. */
static cupid_status bounded_walk(const model_reader *rd, yaml_node_t *node, int depth,
                                 long *visits) {
  if (!node) return CUPID_SUCCESS;
  if (++*visits > MODEL_MAX_VISITS)
    return mr_error(rd, node, "",
                    "model too large or alias expansion too deep (more than %ld nodes visited)",
                    MODEL_MAX_VISITS);
  if (depth > MODEL_MAX_DEPTH)
    return mr_error(rd, node, "", "nested more than %d levels deep (or an alias refers to itself)",
                    MODEL_MAX_DEPTH);
  if (node->type == YAML_SEQUENCE_NODE) {
    for (yaml_node_item_t *it = node->data.sequence.items.start; it < node->data.sequence.items.top;
         it++)
      CUPID_CALL(bounded_walk(rd, mr_node(rd, *it), depth + 1, visits));
  } else if (node->type == YAML_MAPPING_NODE) {
    for (yaml_node_pair_t *p = node->data.mapping.pairs.start; p < node->data.mapping.pairs.top;
         p++) {
      CUPID_CALL(bounded_walk(rd, mr_node(rd, p->key), depth + 1, visits));
      CUPID_CALL(bounded_walk(rd, mr_node(rd, p->value), depth + 1, visits));
    }
  }
  return CUPID_SUCCESS;
}

/* libyaml's scanner re-checks every open flow level ('[' or '{') at every token, and its composer
 * looks anchors up by linear search, so deep flow nesting or many anchors take quadratic time
 * (100000 '[' take about a minute). Scan the tokens first with its own scanner, which is linear
 * while the nesting is bounded, and refuse such input before composing the document. */
static cupid_status token_guard(const char *text, size_t length, const char *name) {
  yaml_parser_t parser;
  if (!yaml_parser_initialize(&parser))
    return CUPID_ERROR(CUPID_ERR_MEMORY, "%s: cannot initialise the YAML parser", name);
  yaml_parser_set_input_string(&parser, (const unsigned char *)text, length);
  cupid_status st = CUPID_SUCCESS;
  int depth = 0;
  long anchors = 0, aliases = 0, scalars = 0;
  for (;;) {
    yaml_token_t token;
    if (!yaml_parser_scan(&parser, &token)) {
      st = parser_error(&parser, text, length, name);
      break;
    }
    yaml_token_type_t type = token.type;
    yaml_mark_t mark = token.start_mark;
    yaml_token_delete(&token);
    if (type == YAML_STREAM_END_TOKEN || type == YAML_NO_TOKEN) break;
    char what[96] = "";
    if (type == YAML_FLOW_SEQUENCE_START_TOKEN || type == YAML_FLOW_MAPPING_START_TOKEN) {
      if (++depth > MODEL_MAX_DEPTH)
        snprintf(what, sizeof what, "nested more than %d levels deep", MODEL_MAX_DEPTH);
    } else if (type == YAML_FLOW_SEQUENCE_END_TOKEN || type == YAML_FLOW_MAPPING_END_TOKEN) {
      depth--;
    } else if (type == YAML_ANCHOR_TOKEN) {
      if (++anchors > MODEL_MAX_ANCHORS)
        snprintf(what, sizeof what, "more than %ld anchors (&name)", MODEL_MAX_ANCHORS);
    } else if (type == YAML_SCALAR_TOKEN) {
      /* Bounds the document's memory: the composer keeps every node. */
      if (++scalars > MODEL_MAX_VISITS)
        snprintf(what, sizeof what, "model too large (more than %ld values)", MODEL_MAX_VISITS);
    } else if (type == YAML_ALIAS_TOKEN) {
      if (++aliases > MODEL_MAX_ALIASES)
        snprintf(what, sizeof what, "more than %ld aliases (*name)", MODEL_MAX_ALIASES);
    }
    if (what[0]) {
      st = CUPID_ERROR(CUPID_ERR_MODEL, "%s:%d:%d: %s", name, (int)mark.line + 1,
                       (int)mark.column + 1, what);
      break;
    }
  }
  yaml_parser_delete(&parser);
  return st;
}

cupid_status mr_load(const char *text, size_t length, const char *name, yaml_document_t *doc) {
  memset(doc, 0, sizeof *doc);
  CUPID_CALL(token_guard(text, length, name));
  yaml_parser_t parser;
  if (!yaml_parser_initialize(&parser))
    return CUPID_ERROR(CUPID_ERR_MEMORY, "%s: cannot initialise the YAML parser", name);
  yaml_parser_set_input_string(&parser, (const unsigned char *)text, length);
  cupid_status st = CUPID_SUCCESS;
  int loaded = 0;
  yaml_document_t second;
  if (!yaml_parser_load(&parser, doc)) {
    st = parser_error(&parser, text, length, name);
    goto cleanup;
  }
  loaded = 1;
  yaml_node_t *root = yaml_document_get_root_node(doc);
  if (!root || (mr_is_null(root) && root->data.scalar.length == 0)) {
    st = CUPID_ERROR(CUPID_ERR_MODEL, "%s:1:1: the model file is empty", name);
    goto cleanup;
  }
  /* One model, one document: a second one is refused rather than silently dropped. */
  if (!yaml_parser_load(&parser, &second)) {
    st = parser_error(&parser, text, length, name);
    goto cleanup;
  }
  int has_second = yaml_document_get_root_node(&second) != NULL;
  yaml_mark_t second_mark = second.start_mark;
  yaml_document_delete(&second);
  if (has_second) {
    st = CUPID_ERROR(CUPID_ERR_MODEL,
                     "%s:%d:%d: the file holds more than one YAML document ('---'); a model "
                     "file holds exactly one",
                     name, (int)second_mark.line + 1, (int)second_mark.column + 1);
    goto cleanup;
  }
  model_reader rd = {doc, name, NULL, NULL, 0};
  long visits = 0;
  CUPID_TRY(bounded_walk(&rd, root, 0, &visits));
cleanup:
  if (st != CUPID_SUCCESS && loaded) yaml_document_delete(doc);
  yaml_parser_delete(&parser);
  return st;
}
