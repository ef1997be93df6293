/* Model reader, overrides: `--set key.path=value` (cupid run, issue 19 item 11) changes one
 * value of the loaded YAML document before it is read, so an override is validated exactly as
 * the file's own value would be. A path is keys separated by dots, each optionally followed
 * by [i] list indices (loads[0].traction.value); a missing key is added (a missing mapping on
 * the way too), an index must exist. The value is YAML itself (a number, a string, a flow list
 * [0, "50*t", 0] or a flow mapping {x: [0, 1]}). The new nodes carry the line MR_SET_LINE + k
 * (k: the override's index), so that every error about them names the override instead of a
 * line of the file (error_va, cupid_model_error). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/model_internal.h"

/* Copy node @p i of @p src into @p dst; returns the new node's index (0 on failure). */
static int copy_node(yaml_document_t *dst, yaml_document_t *src, int i, int line, int depth) {
  yaml_node_t *n = yaml_document_get_node(src, i);
  if (!n || depth > MODEL_MAX_DEPTH) return 0;
  int out = 0;
  switch (n->type) {
  case YAML_SCALAR_NODE:
    out = yaml_document_add_scalar(dst, n->tag, n->data.scalar.value, (int)n->data.scalar.length,
                                   n->data.scalar.style);
    break;
  case YAML_SEQUENCE_NODE: {
    out = yaml_document_add_sequence(dst, n->tag, YAML_FLOW_SEQUENCE_STYLE);
    int count = (int)(n->data.sequence.items.top - n->data.sequence.items.start);
    for (int k = 0; out && k < count; k++) {
      n = yaml_document_get_node(src, i); /* the source does not move; re-read for clarity */
      int item = copy_node(dst, src, n->data.sequence.items.start[k], line, depth + 1);
      if (!item || !yaml_document_append_sequence_item(dst, out, item)) out = 0;
    }
    break;
  }
  case YAML_MAPPING_NODE: {
    out = yaml_document_add_mapping(dst, n->tag, YAML_FLOW_MAPPING_STYLE);
    int count = (int)(n->data.mapping.pairs.top - n->data.mapping.pairs.start);
    for (int k = 0; out && k < count; k++) {
      n = yaml_document_get_node(src, i);
      yaml_node_pair_t pair = n->data.mapping.pairs.start[k];
      int key = copy_node(dst, src, pair.key, line, depth + 1);
      int value = key ? copy_node(dst, src, pair.value, line, depth + 1) : 0;
      if (!value || !yaml_document_append_mapping_pair(dst, out, key, value)) out = 0;
    }
    break;
  }
  default: break;
  }
  if (out) {
    yaml_node_t *c = yaml_document_get_node(dst, out);
    c->start_mark.line = c->end_mark.line = (size_t)line;
    c->start_mark.column = c->end_mark.column = 0;
  }
  return out;
}

/* One path segment: the key and its list indices ("loads[0]" -> "loads", {0}). */
typedef struct {
  char key[128];
  int index[4], n_index;
} segment;

static int parse_segment(const char *s, size_t len, segment *seg) {
  size_t k = 0;
  while (k < len && s[k] != '[') k++;
  if (k == 0 || k >= sizeof seg->key) return 0;
  memcpy(seg->key, s, k);
  seg->key[k] = '\0';
  seg->n_index = 0;
  while (k < len) {
    if (s[k] != '[' || seg->n_index == 4) return 0;
    char *end = NULL;
    long v = strtol(s + k + 1, &end, 10);
    if (end == s + k + 1 || *end != ']' || v < 0 || v > 1000000) return 0;
    seg->index[seg->n_index++] = (int)v;
    k = (size_t)(end - s) + 1;
  }
  return 1;
}

/* The value slot of @p key in mapping @p map (a new null pair when absent and create). */
static int *mapping_slot(yaml_document_t *doc, int map, const char *key, int line) {
  yaml_node_t *m = yaml_document_get_node(doc, map);
  for (yaml_node_pair_t *p = m->data.mapping.pairs.start; p < m->data.mapping.pairs.top; p++) {
    yaml_node_t *k = yaml_document_get_node(doc, p->key);
    if (k && k->type == YAML_SCALAR_NODE && !strcmp((const char *)k->data.scalar.value, key))
      return &p->value;
  }
  int kn = yaml_document_add_scalar(doc, NULL, (const yaml_char_t *)key, (int)strlen(key),
                                    YAML_PLAIN_SCALAR_STYLE);
  int vn = yaml_document_add_mapping(doc, NULL, YAML_BLOCK_MAPPING_STYLE);
  if (!kn || !vn || !yaml_document_append_mapping_pair(doc, map, kn, vn)) return NULL;
  yaml_document_get_node(doc, kn)->start_mark.line = (size_t)line;
  yaml_document_get_node(doc, vn)->start_mark.line = (size_t)line;
  m = yaml_document_get_node(doc, map);
  return &(m->data.mapping.pairs.top - 1)->value;
}

static cupid_status set_error(const char *name, const char *set, const char *fmt, const char *arg) {
  char what[512];
  snprintf(what, sizeof what, fmt, arg);
  return CUPID_ERROR(CUPID_ERR_MODEL, "%s: --set %s: %s", name, set, what);
}

/* Apply override k, "path=value", to the document. */
static cupid_status apply_one(yaml_document_t *doc, const char *name, const char *set, int k) {
  const char *eq = strchr(set, '=');
  if (!eq || eq == set)
    return set_error(name, set, "expected key.path=value (e.g. %s)", "analysis.solver=direct");
  const int line = MR_SET_LINE + k;
  /* the value, parsed as YAML (an empty value is null) */
  yaml_parser_t parser;
  yaml_document_t value;
  if (!yaml_parser_initialize(&parser))
    return CUPID_ERROR(CUPID_ERR_MEMORY, "cannot initialise the YAML parser");
  const char *text = eq[1] ? eq + 1 : "null";
  yaml_parser_set_input_string(&parser, (const unsigned char *)text, strlen(text));
  int ok = yaml_parser_load(&parser, &value);
  yaml_parser_delete(&parser);
  if (!ok || !yaml_document_get_root_node(&value)) {
    if (ok) yaml_document_delete(&value);
    return set_error(name, set, "the value '%s' is not valid YAML", eq + 1);
  }
  cupid_status st = CUPID_SUCCESS;
  int copied = copy_node(doc, &value, 1, line, 0);
  yaml_document_delete(&value);
  if (!copied) return CUPID_ERROR(CUPID_ERR_MEMORY, "--set %s: out of memory", set);
  /* walk the path: mappings by key, sequences by index */
  int node = 1; /* the root */
  int *slot = NULL;
  for (const char *s = set; s < eq && st == CUPID_SUCCESS;) {
    const char *dot = memchr(s, '.', (size_t)(eq - s));
    size_t len = (size_t)((dot ? dot : eq) - s);
    segment seg;
    if (!parse_segment(s, len, &seg))
      return set_error(name, set, "'%s' is not a key path (keys separated by dots, list items as key[i])",
                       "");
    yaml_node_t *n = yaml_document_get_node(doc, node);
    if (!n || n->type != YAML_MAPPING_NODE)
      return set_error(name, set, "'%s' is not inside a mapping", seg.key);
    slot = mapping_slot(doc, node, seg.key, line);
    if (!slot) return CUPID_ERROR(CUPID_ERR_MEMORY, "--set %s: out of memory", set);
    for (int q = 0; q < seg.n_index; q++) {
      yaml_node_t *list = yaml_document_get_node(doc, *slot);
      int count = list && list->type == YAML_SEQUENCE_NODE
                      ? (int)(list->data.sequence.items.top - list->data.sequence.items.start)
                      : -1;
      if (seg.index[q] >= count) {
        char what[320];
        snprintf(what, sizeof what, "%s[%d] does not exist (%d items)", seg.key, seg.index[q],
                 count < 0 ? 0 : count);
        return set_error(name, set, "%s", what);
      }
      slot = &list->data.sequence.items.start[seg.index[q]];
    }
    node = *slot;
    s = dot ? dot + 1 : eq;
  }
  *slot = copied;
  return st;
}

cupid_status mr_apply_overrides(yaml_document_t *doc, const char *name, const char *const *sets,
                                int n_sets) {
  CUPID_CHECK(n_sets <= MR_MAX_SETS, CUPID_ERR_MODEL, "%s: more than %d --set overrides", name,
              MR_MAX_SETS);
  for (int k = 0; k < n_sets; k++) CUPID_CALL(apply_one(doc, name, sets[k], k));
  return CUPID_SUCCESS;
}
