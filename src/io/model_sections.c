/* Model reader, part 2: one parser per section of shared/reference/model-format.md. Each one
 * opens its mapping against the allowed keys (unknown and duplicate keys are errors there),
 * fills defaults, then reads and range-checks every value at its own file position. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cupid/io.h"
#include "io/io_internal.h"
#include "io/model_internal.h"

#define PATH_SIZE sizeof(((cupid_mark *)0)->key)
#define COUNT(a) ((int)(sizeof(a) / sizeof((a)[0])))

/* Largest counts accepted where a later stage allocates per item (beam elements, TE terms). */
#define MAX_ELEMENTS_PER_SPAN 100000
#define MAX_TE_ORDER 20
#define MAX_LINE_POINTS 10000000L

static const char *text_of(const yaml_node_t *node) {
  return (const char *)node->data.scalar.value;
}

/* ---------------------------------------------------------------------------------- title */

static cupid_status read_title(model_reader *rd, yaml_node_t *node) {
  if (!node || mr_is_null(node)) return cupid_strdup("", &rd->model->title);
  return mr_string(rd, node, "title", MODEL_MAX_STRING, &rd->model->title);
}

/* ------------------------------------------------------------------------------ materials */

/* Orthotropic constants are admissible when the normal-stress block of the compliance matrix
 * is positive definite (the shear terms only need G > 0); test its leading minors. */
static int orthotropic_admissible(const cupid_material *m) {
  double s11 = 1 / m->Ex, s22 = 1 / m->Ey, s33 = 1 / m->Ez;
  double s12 = -m->nu_xy / m->Ex, s13 = -m->nu_xz / m->Ex, s23 = -m->nu_yz / m->Ey;
  double d2 = s11 * s22 - s12 * s12;
  double d3 = s11 * (s22 * s33 - s23 * s23) - s12 * (s12 * s33 - s23 * s13) +
              s13 * (s12 * s23 - s22 * s13);
  return d2 > 0 && d3 > 0;
}

static cupid_status read_positive3(model_reader *rd, yaml_node_t *node, const char *path,
                                   const char *what, double out[3]) {
  CUPID_CALL(mr_numbers(rd, node, path, 3, what, out));
  for (int i = 0; i < 3; i++)
    if (!(out[i] > 0)) {
      char item_path[PATH_SIZE];
      mr_path_index(item_path, path, i);
      return mr_error(rd, mr_item(rd, node, i), item_path, "must be > 0, got %g", out[i]);
    }
  return CUPID_SUCCESS;
}

static cupid_status read_material(model_reader *rd, yaml_node_t *node, const char *path,
                                  cupid_material *mat) {
  static const char *const keys[] = {"E", "nu", "G", "density"};
  mr_map map;
  char p[PATH_SIZE];
  CUPID_CALL(mr_map_open(rd, node, path, keys, COUNT(keys), &map));
  yaml_node_t *E, *nu, *G = mr_get(&map, "G"), *density = mr_get(&map, "density");
  CUPID_CALL(mr_require(rd, &map, "E", &E));
  CUPID_CALL(mr_require(rd, &map, "nu", &nu));
  if (E->type == YAML_SEQUENCE_NODE) {
    double v[3];
    mat->orthotropic = 1;
    mr_path(p, path, "E");
    CUPID_CALL(read_positive3(rd, E, p, "[Ex, Ey, Ez]", v));
    mat->Ex = v[0], mat->Ey = v[1], mat->Ez = v[2];
    mr_path(p, path, "nu");
    CUPID_CALL(mr_numbers(rd, nu, p, 3, "[nu_xy, nu_xz, nu_yz]", v));
    mat->nu_xy = v[0], mat->nu_xz = v[1], mat->nu_yz = v[2];
    if (!G)
      return mr_error(rd, map.node, path,
                      "missing required key 'G' (an orthotropic material needs G: [Gxy, Gxz, "
                      "Gyz])");
    mr_path(p, path, "G");
    CUPID_CALL(read_positive3(rd, G, p, "[Gxy, Gxz, Gyz]", v));
    mat->Gxy = v[0], mat->Gxz = v[1], mat->Gyz = v[2];
    if (!orthotropic_admissible(mat)) {
      mr_path(p, path, "nu");
      return mr_error(rd, nu, p,
                      "these Poisson ratios with E = [%g, %g, %g] give a compliance matrix that "
                      "is not positive definite (need |nu_xy| < sqrt(Ex/Ey) and so on)",
                      mat->Ex, mat->Ey, mat->Ez);
    }
  } else {
    mr_path(p, path, "E");
    CUPID_CALL(mr_positive(rd, E, p, &mat->E));
    mr_path(p, path, "nu");
    CUPID_CALL(mr_number(rd, nu, p, &mat->nu));
    if (!(mat->nu > -1 && mat->nu < 0.5))
      return mr_error(rd, nu, p, "must satisfy -1 < nu < 0.5, got %s", text_of(nu));
    if (G) {
      mr_path(p, path, "G");
      return mr_error(rd, G, p,
                      "G is only used by orthotropic materials (E: [Ex, Ey, Ez]); an isotropic "
                      "material has G = E / (2 (1 + nu))");
    }
  }
  if (density) {
    mr_path(p, path, "density");
    CUPID_CALL(mr_nonnegative(rd, density, p, &mat->density));
    mat->has_density = 1;
  }
  return CUPID_SUCCESS;
}

static cupid_status read_materials(model_reader *rd, yaml_node_t *node) {
  cupid_model_t *m = rd->model;
  char got[64];
  if (!node || node->type != YAML_MAPPING_NODE)
    return mr_error(rd, node, "materials",
                    "must be a mapping of material names to {E: ..., nu: ...}, got %s",
                    mr_describe(node, got, sizeof got));
  int n = (int)(node->data.mapping.pairs.top - node->data.mapping.pairs.start);
  if (n == 0) return mr_error(rd, node, "materials", "must define at least one material");
  if (n > MODEL_MAX_MATERIALS)
    return mr_error(rd, node, "materials", "defines %d materials, at most %d are allowed", n,
                    MODEL_MAX_MATERIALS);
  CUPID_CALL(cupid_calloc((size_t)n, sizeof *m->materials, "materials", &m->materials));
  m->n_materials = n;
  for (int i = 0; i < n; i++) {
    yaml_node_pair_t *pair = &node->data.mapping.pairs.start[i];
    yaml_node_t *key = mr_node(rd, pair->key);
    if (!mr_is_scalar(key) || mr_is_null(key))
      return mr_error(rd, key, "materials", "material names must be plain names, got %s",
                      mr_describe(key, got, sizeof got));
    char path[PATH_SIZE];
    mr_path(path, "materials", text_of(key));
    mr_mark(key, path, &m->materials[i].mark);
    CUPID_CALL(mr_string(rd, key, path, MODEL_MAX_NAME, &m->materials[i].name));
    CUPID_CALL(read_material(rd, mr_node(rd, pair->value), path, &m->materials[i]));
  }
  char **names = NULL;
  CUPID_CALL(cupid_malloc((size_t)n, sizeof *names, "material names", &names));
  for (int i = 0; i < n; i++) names[i] = m->materials[i].name;
  int first = -1, dup = mr_find_duplicate(names, n, &first);
  cupid_free(&names);
  if (dup >= 0)
    return cupid_model_error(m, &m->materials[dup].mark,
                             "duplicate material name (first defined at line %d)",
                             m->materials[first].mark.line);
  return CUPID_SUCCESS;
}

/* A material reference, or the only material when the key is absent and there is just one. */
static cupid_status material_or_sole(model_reader *rd, const mr_map *map, const char *path,
                                     int *index) {
  yaml_node_t *node = mr_get(map, "material");
  if (node) {
    char p[PATH_SIZE];
    mr_path(p, path, "material");
    return mr_material(rd, node, p, index);
  }
  if (rd->model->n_materials == 1) {
    *index = 0;
    return CUPID_SUCCESS;
  }
  return mr_error(rd, map->node, path,
                  "missing required key 'material' (needed when more than one material is "
                  "defined)");
}

/* ----------------------------------------------------------------------------------- beam */

static cupid_status read_axis(model_reader *rd, yaml_node_t *node, cupid_beam *b) {
  static const char *const keys[] = {"y", "elements", "type"};
  static const char *const types[] = {"B2", "B3", "B4"};
  mr_map map;
  yaml_node_t *y, *elements, *type;
  CUPID_CALL(mr_map_open(rd, node, "beam.axis", keys, COUNT(keys), &map));
  CUPID_CALL(mr_require(rd, &map, "y", &y));
  CUPID_CALL(mr_require(rd, &map, "elements", &elements));
  CUPID_CALL(mr_breakpoints(rd, y, "beam.axis.y", 2, &b->axis_y, &b->n_axis));
  int count;
  CUPID_CALL(mr_list(rd, elements, "beam.axis.elements", 0, "element counts, one per span",
                     &count));
  if (count != b->n_axis - 1)
    return mr_error(rd, elements, "beam.axis.elements",
                    "needs one element count per span: %d breakpoints in y give %d span%s, got "
                    "%d count%s",
                    b->n_axis, b->n_axis - 1, b->n_axis == 2 ? "" : "s", count,
                    count == 1 ? "" : "s");
  CUPID_CALL(cupid_calloc((size_t)count, sizeof *b->axis_elements, "beam elements",
                          &b->axis_elements));
  for (int i = 0; i < count; i++) {
    char p[PATH_SIZE];
    mr_path_index(p, "beam.axis.elements", i);
    CUPID_CALL(mr_integer(rd, mr_item(rd, elements, i), p, 1, MAX_ELEMENTS_PER_SPAN,
                          &b->axis_elements[i]));
  }
  b->element_nodes = 2;
  if ((type = mr_get(&map, "type"))) {
    int t;
    CUPID_CALL(mr_enum(rd, type, "beam.axis.type", types, COUNT(types), &t));
    b->element_nodes = t + 2;
  }
  return CUPID_SUCCESS;
}

/* "TE<N>" or "LE". */
static cupid_status read_expansion(model_reader *rd, yaml_node_t *node, cupid_beam *b) {
  const char *path = "beam.section.expansion";
  char got[64];
  if (mr_is_scalar(node) && !mr_is_null(node)) {
    const char *s = text_of(node);
    if (!strcmp(s, "LE")) {
      b->expansion = CUPID_EXPANSION_LE;
      return CUPID_SUCCESS;
    }
    if (!strncmp(s, "TE", 2)) {
      size_t n = strlen(s + 2);
      int digits = n > 0 && n <= 4;
      for (size_t i = 0; digits && i < n; i++) digits = isdigit((unsigned char)s[2 + i]) != 0;
      if (!digits)
        return mr_error(rd, node, path,
                        "TE needs its order as a whole number N >= 0, e.g. TE2; got %s",
                        mr_describe(node, got, sizeof got));
      int order = (int)strtol(s + 2, NULL, 10);
      if (order > MAX_TE_ORDER)
        return mr_error(rd, node, path, "TE order must be at most %d, got %d", MAX_TE_ORDER,
                        order);
      b->expansion = CUPID_EXPANSION_TE;
      b->te_order = order;
      return CUPID_SUCCESS;
    }
  }
  return mr_error(rd, node, path,
                  "must be TE<N> (Taylor expansion of order N >= 0, e.g. TE2) or LE (Lagrange "
                  "elements), got %s",
                  mr_describe(node, got, sizeof got));
}

static cupid_status read_component(model_reader *rd, yaml_node_t *node, const char *path,
                                   cupid_section_component *c) {
  static const char *const keys[] = {"x", "z", "material"};
  mr_map map;
  yaml_node_t *x, *z, *material;
  char p[PATH_SIZE];
  mr_mark(node, path, &c->mark);
  c->material = -1;
  CUPID_CALL(mr_map_open(rd, node, path, keys, COUNT(keys), &map));
  CUPID_CALL(mr_require(rd, &map, "x", &x));
  CUPID_CALL(mr_require(rd, &map, "z", &z));
  mr_path(p, path, "x");
  CUPID_CALL(mr_breakpoints(rd, x, p, 2, &c->x, &c->nx));
  mr_path(p, path, "z");
  CUPID_CALL(mr_breakpoints(rd, z, p, 2, &c->z, &c->nz));
  if ((material = mr_get(&map, "material"))) {
    mr_path(p, path, "material");
    CUPID_CALL(mr_material(rd, material, p, &c->material));
  }
  return CUPID_SUCCESS;
}

static cupid_status read_components(model_reader *rd, yaml_node_t *node, cupid_beam *b) {
  const char *path = "beam.section.components";
  int n;
  CUPID_CALL(mr_list(rd, node, path, 0, "rectangles {x: [...], z: [...]}", &n));
  if (n == 0) return mr_error(rd, node, path, "must list at least one rectangle");
  CUPID_CALL(cupid_calloc((size_t)n, sizeof *b->components, "section components", &b->components));
  b->n_components = n;
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    mr_path_index(p, path, i);
    CUPID_CALL(read_component(rd, mr_item(rd, node, i), p, &b->components[i]));
  }
  return CUPID_SUCCESS;
}

static cupid_status read_section_nodes(model_reader *rd, yaml_node_t *node, cupid_beam *b) {
  const char *path = "beam.section.nodes";
  int n;
  CUPID_CALL(mr_list(rd, node, path, 0, "points [x, z]", &n));
  if (n == 0) return mr_error(rd, node, path, "must list at least one node [x, z]");
  CUPID_CALL(cupid_calloc((size_t)n * 2, sizeof *b->section_nodes, "section nodes",
                          &b->section_nodes));
  b->n_section_nodes = n;
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    mr_path_index(p, path, i);
    CUPID_CALL(mr_numbers(rd, mr_item(rd, node, i), p, 2, "[x, z]", &b->section_nodes[2 * i]));
  }
  return CUPID_SUCCESS;
}

/* One explicit element: [n1, ...] or {nodes: [n1, ...], material: name}. */
static cupid_status read_section_element(model_reader *rd, yaml_node_t *node, const char *path,
                                         cupid_beam *b, int e) {
  static const char *const keys[] = {"nodes", "material"};
  yaml_node_t *list = node;
  char p[PATH_SIZE], got[64];
  const char *list_path = path;
  b->section_element_material[e] = -1;
  if (node && node->type == YAML_MAPPING_NODE) {
    mr_map map;
    yaml_node_t *material;
    CUPID_CALL(mr_map_open(rd, node, path, keys, COUNT(keys), &map));
    CUPID_CALL(mr_require(rd, &map, "nodes", &list));
    if ((material = mr_get(&map, "material"))) {
      mr_path(p, path, "material");
      CUPID_CALL(mr_material(rd, material, p, &b->section_element_material[e]));
    }
    mr_path(p, path, "nodes");
    list_path = p;
  }
  int k = b->le_nodes;
  if (!list || list->type != YAML_SEQUENCE_NODE)
    return mr_error(rd, list, list_path,
                    "must be a list of %d node indices (or {nodes: [...], material: name}), got "
                    "%s",
                    k, mr_describe(list, got, sizeof got));
  int count = (int)(list->data.sequence.items.top - list->data.sequence.items.start);
  if (count != k)
    return mr_error(rd, list, list_path, "an L%d element needs %d node indices, got %d", k, k,
                    count);
  int *nodes = &b->section_elements[(size_t)e * (size_t)k];
  for (int i = 0; i < k; i++) {
    char item_path[PATH_SIZE];
    mr_path_index(item_path, list_path, i);
    yaml_node_t *item = mr_item(rd, list, i);
    CUPID_CALL(mr_integer(rd, item, item_path, -2147483647L, 2147483647L, &nodes[i]));
    if (nodes[i] < 0 || nodes[i] >= b->n_section_nodes)
      return mr_error(rd, item, item_path,
                      "node index must be from 0 to %d (indices into section.nodes, 0-based), "
                      "got %d",
                      b->n_section_nodes - 1, nodes[i]);
    for (int j = 0; j < i; j++)
      if (nodes[j] == nodes[i])
        return mr_error(rd, item, item_path, "node %d appears twice in this element", nodes[i]);
  }
  return CUPID_SUCCESS;
}

static cupid_status read_section_elements(model_reader *rd, yaml_node_t *node, cupid_beam *b) {
  const char *path = "beam.section.elements";
  int n;
  CUPID_CALL(mr_list(rd, node, path, 0, "elements [n1, ...]", &n));
  if (n == 0) return mr_error(rd, node, path, "must list at least one element");
  CUPID_CALL(cupid_calloc((size_t)n * (size_t)b->le_nodes, sizeof *b->section_elements,
                          "section elements", &b->section_elements));
  CUPID_CALL(cupid_calloc((size_t)n, sizeof *b->section_element_material,
                          "section element materials", &b->section_element_material));
  b->n_section_elements = n;
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    mr_path_index(p, path, i);
    CUPID_CALL(read_section_element(rd, mr_item(rd, node, i), p, b, i));
  }
  return CUPID_SUCCESS;
}

/* A file named in the model, relative to the model file's folder (as given, for a model that
 * is no file or an absolute path). */
static cupid_status model_relative(const model_reader *rd, const char *name, char **out) {
  const char *file = rd->model->file, *slash = file ? strrchr(file, '/') : NULL;
  if (name[0] == '/' || !slash) return cupid_strdup(name, out);
  const size_t dir = (size_t)(slash - file + 1), n = dir + strlen(name) + 1;
  CUPID_CALL(cupid_malloc(n, 1, "file path", out));
  memcpy(*out, file, dir);
  memcpy(*out + dir, name, strlen(name) + 1);
  return CUPID_SUCCESS;
}

/* beam.section.groups: {Gmsh physical group: material}: each element's material. */
static cupid_status read_section_groups(model_reader *rd, yaml_node_t *node,
                                        const cupid_gmsh_section *mesh, const char *file,
                                        int *group_material) {
  const char *path = "beam.section.groups";
  char got[64];
  for (int g = 0; g < mesh->n_groups; g++) group_material[g] = -1;
  if (!node) return CUPID_SUCCESS;
  if (node->type != YAML_MAPPING_NODE)
    return mr_error(rd, node, path, "must be a mapping {physical group: material}, got %s",
                    mr_describe(node, got, sizeof got));
  const int n = (int)(node->data.mapping.pairs.top - node->data.mapping.pairs.start);
  for (int i = 0; i < n; i++) {
    yaml_node_pair_t *pair = &node->data.mapping.pairs.start[i];
    yaml_node_t *key = mr_node(rd, pair->key);
    if (!mr_is_scalar(key) || mr_is_null(key))
      return mr_error(rd, key, path, "group names must be plain names, got %s",
                      mr_describe(key, got, sizeof got));
    const char *name = text_of(key);
    int g = -1;
    for (int k = 0; k < mesh->n_groups && g < 0; k++)
      if (!strcmp(mesh->groups[k], name)) g = k;
    if (g < 0) {
      char have[400] = "";
      for (int k = 0; k < mesh->n_groups; k++)
        snprintf(have + strlen(have), sizeof have - strlen(have), "%s'%s'", k ? ", " : "",
                 mesh->groups[k]);
      return mr_error(rd, key, path, "%s has no 2D physical group '%s' (%s%s)", file, name,
                      mesh->n_groups ? "it has " : "it has none", have);
    }
    char p[PATH_SIZE];
    mr_path(p, path, name);
    CUPID_CALL(mr_material(rd, mr_node(rd, pair->value), p, &group_material[g]));
  }
  return CUPID_SUCCESS;
}

/* beam.section.mesh: the section's quadrilaterals from a Gmsh file (.msh, or .geo / CAD that
 * Gmsh meshes) become the explicit mesh (nodes + elements, their materials by `groups`). */
static cupid_status read_section_mesh(model_reader *rd, yaml_node_t *node, yaml_node_t *groups,
                                      cupid_beam *b) {
  const char *path = "beam.section.mesh";
  char *name = NULL, *file = NULL, why[1024];
  int *group_material = NULL;
  cupid_gmsh_section mesh = {0};
  cupid_status st = mr_string(rd, node, path, MODEL_MAX_STRING, &name);
  if (st == CUPID_SUCCESS && !name[0]) st = mr_error(rd, node, path, "must name a file");
  if (st == CUPID_SUCCESS) st = model_relative(rd, name, &file);
  if (st == CUPID_SUCCESS && cupid_gmsh_read_section(file, b->le_nodes, &mesh, why, sizeof why))
    st = mr_error(rd, node, path, "%s: %s", file, why);
  if (st == CUPID_SUCCESS && mesh.n_nodes > 2147483647 / 2)
    st = mr_error(rd, node, path, "%s: %lld nodes: too many for a section", file,
                  (long long)mesh.n_nodes);
  if (st == CUPID_SUCCESS)
    st = cupid_calloc((size_t)mesh.n_groups + 1, sizeof *group_material, "group materials",
                      &group_material);
  if (st == CUPID_SUCCESS) st = read_section_groups(rd, groups, &mesh, file, group_material);
  if (st == CUPID_SUCCESS) {
    b->section_mesh = file, file = NULL; /* summary.json names it */
    b->section_nodes = mesh.xz, mesh.xz = NULL;
    b->n_section_nodes = (int)mesh.n_nodes;
    b->section_elements = mesh.conn, mesh.conn = NULL;
    b->n_section_elements = (int)mesh.n_elements;
    st = cupid_calloc((size_t)mesh.n_elements, sizeof *b->section_element_material,
                      "section element materials", &b->section_element_material);
  }
  for (cupid_int e = 0; st == CUPID_SUCCESS && e < mesh.n_elements; e++)
    b->section_element_material[e] = mesh.group[e] >= 0 ? group_material[mesh.group[e]] : -1;
  cupid_gmsh_section_free(&mesh);
  cupid_free(&group_material);
  cupid_free(&name);
  cupid_free(&file);
  return st;
}

static cupid_status read_section(model_reader *rd, yaml_node_t *node, cupid_beam *b) {
  static const char *const keys[] = {"expansion", "element", "components", "nodes", "elements",
                                     "mesh", "groups"};
  static const char *const elements[] = {"L4", "L9", "L16"};
  static const int element_nodes[] = {4, 9, 16};
  const char *path = "beam.section";
  mr_map map;
  yaml_node_t *expansion, *element, *components, *nodes, *elems, *mesh, *groups;
  CUPID_CALL(mr_map_open(rd, node, path, keys, COUNT(keys), &map));
  CUPID_CALL(mr_require(rd, &map, "expansion", &expansion));
  CUPID_CALL(read_expansion(rd, expansion, b));
  element = mr_get(&map, "element");
  components = mr_get(&map, "components");
  nodes = mr_get(&map, "nodes");
  elems = mr_get(&map, "elements");
  mesh = mr_get(&map, "mesh");
  groups = mr_get(&map, "groups");
  if (element) {
    int e;
    CUPID_CALL(mr_enum(rd, element, "beam.section.element", elements, COUNT(elements), &e));
    b->le_nodes = element_nodes[e];
  } else if (b->expansion == CUPID_EXPANSION_LE) {
    return mr_error(rd, map.node, path,
                    "missing required key 'element': expansion LE needs element: L4 | L9 | L16");
  }
  if (groups && !mesh)
    return mr_error(rd, groups, "beam.section.groups", "names the physical groups of a section "
                    "mesh: give beam.section.mesh");
  if (mesh && (components || nodes || elems))
    return mr_error(rd, mesh, "beam.section.mesh", "give one of components, nodes + elements or "
                    "mesh");
  if (mesh && !element)
    return mr_error(rd, map.node, path, "missing required key 'element': a section mesh needs "
                    "element: L4 | L9 | L16 (Gmsh makes the elements' order)");
  if (mesh) return read_section_mesh(rd, mesh, groups, b);
  if (components && (nodes || elems))
    return mr_error(rd, nodes ? nodes : elems, nodes ? "beam.section.nodes" : "beam.section.elements",
                    "give either components or nodes + elements, not both");
  if (components) return read_components(rd, components, b);
  if (!nodes && !elems)
    return mr_error(rd, map.node, path, "missing required key 'components' (or an explicit mesh: "
                    "nodes + elements, or a Gmsh file: mesh)");
  if (!nodes || !elems)
    return mr_error(rd, map.node, path, "missing required key '%s' (an explicit mesh needs both "
                    "nodes and elements)", nodes ? "elements" : "nodes");
  if (!element)
    return mr_error(rd, map.node, path,
                    "missing required key 'element': an explicit section mesh needs element: L4 "
                    "| L9 | L16");
  CUPID_CALL(read_section_nodes(rd, nodes, b));
  return read_section_elements(rd, elems, b);
}

static cupid_status read_beam(model_reader *rd, yaml_node_t *node) {
  static const char *const keys[] = {"material", "axis", "section", "integration",
                                     "poisson_correction"};
  static const char *const integrations[] = {"full", "reduced", "mitc"};
  static const char *const corrections[] = {"auto", "on", "off"}; /* CUPID_CUF_POISSON_* */
  cupid_beam *b = &rd->model->beam;
  mr_map map;
  yaml_node_t *axis, *section, *integration, *poisson;
  mr_mark(node, "beam", &b->mark);
  rd->model->has_beam = 1;
  CUPID_CALL(mr_map_open(rd, node, "beam", keys, COUNT(keys), &map));
  CUPID_CALL(material_or_sole(rd, &map, "beam", &b->material));
  CUPID_CALL(mr_require(rd, &map, "axis", &axis));
  CUPID_CALL(read_axis(rd, axis, b));
  CUPID_CALL(mr_require(rd, &map, "section", &section));
  CUPID_CALL(read_section(rd, section, b));
  if ((integration = mr_get(&map, "integration")))
    CUPID_CALL(mr_enum(rd, integration, "beam.integration", integrations, COUNT(integrations),
                       &b->integration));
  if ((poisson = mr_get(&map, "poisson_correction"))) {
    CUPID_CALL(mr_enum(rd, poisson, "beam.poisson_correction", corrections, COUNT(corrections),
                       &b->poisson_correction));
    /* TE2 and up and LE sections contract freely: nothing to correct (docs/theory.md) */
    if (b->poisson_correction == 1 && !(b->expansion == CUPID_EXPANSION_TE && b->te_order <= 1))
      return mr_error(rd, poisson, "beam.poisson_correction",
                      "'on' applies to TE0 and TE1 only: %s sections contract freely and have no "
                      "Poisson locking (use auto or off)",
                      b->expansion == CUPID_EXPANSION_LE ? "LE" : "TE2 and higher");
  }
  return CUPID_SUCCESS;
}

/* --------------------------------------------------------------------------- peridynamics */

/* A cylinder {axis, center: [a, b], radius, from, to} (center in the plane normal to the axis,
 * in the order x, y, z less the axis) or a sphere {center: [x, y, z], radius} into s, with its
 * bounding box. A cylinder without from/to runs through the body along its axis (allowed for
 * holes only: @p need_ends). */
static cupid_status read_round(model_reader *rd, yaml_node_t *node, const char *path, int cylinder,
                               int need_ends, cupid_shape *s) {
  static const char *const ckeys[] = {"axis", "center", "radius", "from", "to"};
  static const char *const skeys[] = {"center", "radius"};
  static const char *const axes[] = {"x", "y", "z"};
  mr_map map;
  char p[PATH_SIZE];
  CUPID_CALL(mr_map_open(rd, node, path, cylinder ? ckeys : skeys, cylinder ? 5 : 2, &map));
  memset(s, 0, sizeof *s);
  s->kind = cylinder ? CUPID_SHAPE_CYLINDER : CUPID_SHAPE_SPHERE;
  yaml_node_t *v;
  if (cylinder) {
    CUPID_CALL(mr_require(rd, &map, "axis", &v));
    mr_path(p, path, "axis");
    CUPID_CALL(mr_enum(rd, v, p, axes, 3, &s->axis));
  }
  CUPID_CALL(mr_require(rd, &map, "center", &v));
  mr_path(p, path, "center");
  double c[3] = {0.0, 0.0, 0.0};
  CUPID_CALL(mr_numbers(rd, v, p, cylinder ? 2 : 3, cylinder ? "[a, b] (the axis point, x y z less the axis)" : "[x, y, z]", c));
  for (int a = 0, t = 0; a < 3; a++)
    if (!cylinder || a != s->axis) s->center[a] = c[t++];
  CUPID_CALL(mr_require(rd, &map, "radius", &v));
  mr_path(p, path, "radius");
  CUPID_CALL(mr_positive(rd, v, p, &s->radius));
  for (int a = 0; a < 3; a++) {
    s->box.has[a] = 1;
    s->box.lo[a] = s->center[a] - s->radius;
    s->box.hi[a] = s->center[a] + s->radius;
  }
  if (!cylinder) return CUPID_SUCCESS;
  yaml_node_t *from = mr_get(&map, "from"), *to = mr_get(&map, "to");
  const int ax = s->axis;
  s->box.has[ax] = 0;
  s->box.lo[ax] = -INFINITY;
  s->box.hi[ax] = INFINITY;
  if (!from && !to && !need_ends) return CUPID_SUCCESS; /* through the body */
  if (!from || !to)
    return mr_error(rd, map.node, path, "a cylinder %s needs both from and to (its ends along %s)",
                    need_ends ? "region" : "hole with either end", axes[ax]);
  mr_path(p, path, "from");
  CUPID_CALL(mr_number(rd, from, p, &s->box.lo[ax]));
  mr_path(p, path, "to");
  CUPID_CALL(mr_number(rd, to, p, &s->box.hi[ax]));
  if (!(s->box.lo[ax] < s->box.hi[ax]))
    return mr_error(rd, to, p, "must be above from (%.15g), got %.15g", s->box.lo[ax], s->box.hi[ax]);
  s->box.has[ax] = 1;
  return CUPID_SUCCESS;
}

/* {geometry: FILE}: the volume a Gmsh file bounds (.step, .brep, .geo, .msh, relative to the
 * model file), its surface meshed by Gmsh where it has none (elements of a spacing at most). */
static cupid_status read_geometry(model_reader *rd, yaml_node_t *node, const char *path,
                                  cupid_shape *s) {
  char *name = NULL, *file = NULL, why[1024];
  cupid_status st = mr_string(rd, node, path, MODEL_MAX_STRING, &name);
  if (st == CUPID_SUCCESS && !name[0]) st = mr_error(rd, node, path, "must name a file");
  if (st == CUPID_SUCCESS) st = model_relative(rd, name, &file);
  if (st == CUPID_SUCCESS &&
      cupid_gmsh_read_surface(file, rd->model->pd.spacing, &s->surface, why, sizeof why))
    st = mr_error(rd, node, path, "%s: %s", file, why);
  if (st == CUPID_SUCCESS) {
    s->kind = CUPID_SHAPE_GEOMETRY;
    cupid_surface_bounds(s->surface, s->box.lo, s->box.hi);
    for (int a = 0; a < 3; a++) s->box.has[a] = 1;
    s->file = file, file = NULL; /* summary.json names it */
  }
  cupid_free(&name);
  cupid_free(&file);
  return st;
}

/* A region or hole's shape: a box {x, y, z} (a region: all three; a hole: at least one, the
 * others unbounded), or one of {cylinder: {..}}, {sphere: {..}}, {geometry: FILE}. */
static cupid_status read_shape(model_reader *rd, const mr_map *map, const char *path, int hole,
                               cupid_pd_region *r) {
  static const char *const axes[] = {"x", "y", "z"};
  const cupid_peridynamics *pd = &rd->model->pd;
  yaml_node_t *cyl = mr_get(map, "cylinder"), *sph = mr_get(map, "sphere");
  yaml_node_t *geo = mr_get(map, "geometry");
  int any_axis = 0;
  for (int a = 0; a < 3; a++) any_axis |= mr_get(map, axes[a]) != NULL;
  if (geo) {
    if (cyl || sph || any_axis)
      return mr_error(rd, map->node, path, "a %s is one shape: a box {x, y, z}, or {cylinder: "
                      "{..}}, or {sphere: {..}}, or {geometry: FILE}", hole ? "hole" : "region");
    if (pd->dimension == 1)
      return mr_error(rd, map->node, path, "geometry files need dimension 3");
    char p[PATH_SIZE];
    mr_path(p, path, "geometry");
    CUPID_CALL(read_geometry(rd, geo, p, &r->shape));
    r->box = r->shape.box;
    return CUPID_SUCCESS;
  }
  if (cyl || sph) {
    if ((cyl && sph) || any_axis)
      return mr_error(rd, map->node, path, "a %s is one shape: a box {x, y, z}, or {cylinder: "
                      "{..}}, or {sphere: {..}}", hole ? "hole" : "region");
    if (pd->dimension == 1)
      return mr_error(rd, map->node, path, "cylinders and spheres need dimension 3");
    char p[PATH_SIZE];
    mr_path(p, path, cyl ? "cylinder" : "sphere");
    CUPID_CALL(read_round(rd, cyl ? cyl : sph, p, cyl != NULL, !hole, &r->shape));
    r->box = r->shape.box;
    return CUPID_SUCCESS;
  }
  for (int a = 0; a < 3; a++) {
    char p[PATH_SIZE];
    mr_path(p, path, axes[a]);
    yaml_node_t *v = mr_get(map, axes[a]);
    r->box.lo[a] = -INFINITY;
    r->box.hi[a] = INFINITY;
    r->box.has[a] = 0;
    if (pd->dimension == 1 && a != 1) {
      if (v)
        return mr_error(rd, v, p, "dimension 1 regions take only y: [y0, y1] (a bar along y)");
      continue;
    }
    if (!v && hole) continue;
    if (!v)
      return mr_error(rd, map->node, path, "missing required key '%s' (%s)", axes[a],
                      pd->dimension == 1 ? "a dimension 1 region is {y: [y0, y1]}"
                                         : "a region needs x, y and z, each [min, max], or is "
                                           "{cylinder: {..}} or {sphere: {..}}");
    double range[2];
    CUPID_CALL(mr_range(rd, v, p, 1, range));
    r->box.lo[a] = range[0];
    r->box.hi[a] = range[1];
    r->box.has[a] = 1;
  }
  if (hole && !any_axis)
    return mr_error(rd, map->node, path, "a hole is a box {x, y, z} (at least one axis), "
                    "{cylinder: {..}} or {sphere: {..}}");
  r->shape.kind = CUPID_SHAPE_BOX;
  r->shape.box = r->box;
  return CUPID_SUCCESS;
}

static cupid_status read_region(model_reader *rd, yaml_node_t *node, const char *path,
                                cupid_pd_region *r) {
  static const char *const keys[] = {"x", "y", "z", "material", "cylinder", "sphere", "geometry"};
  const cupid_peridynamics *pd = &rd->model->pd;
  mr_map map;
  mr_mark(node, path, &r->mark);
  CUPID_CALL(mr_map_open(rd, node, path, keys, COUNT(keys), &map));
  CUPID_CALL(read_shape(rd, &map, path, 0, r));
  yaml_node_t *material = mr_get(&map, "material");
  if (material) {
    char p[PATH_SIZE];
    mr_path(p, path, "material");
    return mr_material(rd, material, p, &r->material);
  }
  if (pd->material >= 0) {
    r->material = pd->material;
    return CUPID_SUCCESS;
  }
  if (rd->model->n_materials == 1) {
    r->material = 0;
    return CUPID_SUCCESS;
  }
  return mr_error(rd, map.node, path,
                  "no material: give peridynamics.material or material: in this region");
}

/* peridynamics.holes: shapes removed from every region. */
static cupid_status read_holes(model_reader *rd, yaml_node_t *holes, cupid_peridynamics *pd) {
  static const char *const keys[] = {"x", "y", "z", "cylinder", "sphere", "geometry"};
  int n;
  CUPID_CALL(mr_list(rd, holes, "peridynamics.holes", 1, "shapes {x: [..], ..}, {cylinder: {..}}, "
                     "{sphere: {..}}", &n));
  if (n == 0) return CUPID_SUCCESS;
  if (pd->dimension == 1)
    return mr_error(rd, holes, "peridynamics.holes", "holes need dimension 3");
  CUPID_CALL(cupid_calloc((size_t)n, sizeof *pd->holes, "PD holes", &pd->holes));
  pd->n_holes = n;
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    mr_path_index(p, "peridynamics.holes", i);
    yaml_node_t *node = mr_item(rd, holes, i);
    cupid_pd_region *h = &pd->holes[i];
    mr_map map;
    mr_mark(node, p, &h->mark);
    h->material = -1;
    CUPID_CALL(mr_map_open(rd, node, p, keys, COUNT(keys), &map));
    CUPID_CALL(read_shape(rd, &map, p, 1, h));
  }
  return CUPID_SUCCESS;
}

static cupid_status read_pd_options(model_reader *rd, const mr_map *map, cupid_peridynamics *pd) {
  static const char *const models[] = {"lps", "bond"};
  static const char *const influences[] = {"gaussian", "inverse", "constant"};
  static const char *const partials[] = {"none", "pdlammps", "exact"};
  static const char *const corrections[] = {"none", "energy"};
  yaml_node_t *v;
  pd->dimension = 3;
  if ((v = mr_get(map, "dimension"))) {
    CUPID_CALL(mr_integer(rd, v, "peridynamics.dimension", 1, 3, &pd->dimension));
    if (pd->dimension == 2)
      return mr_error(rd, v, "peridynamics.dimension",
                      "must be 3 or 1 (dimension 2 is not supported), got 2");
  }
  /* The 1D grid is bond-based only: default to it there, and refuse an explicit LPS. */
  pd->model = pd->dimension == 1 ? CUPID_PD_BOND : CUPID_PD_LPS;
  if ((v = mr_get(map, "model"))) {
    int k;
    CUPID_CALL(mr_enum(rd, v, "peridynamics.model", models, COUNT(models), &k));
    pd->model = (cupid_pd_model_kind)k;
    if (pd->model == CUPID_PD_LPS && pd->dimension == 1)
      return mr_error(rd, v, "peridynamics.model",
                      "LPS needs dimension 3; use model: bond with dimension: 1");
  }
  pd->influence = CUPID_INFLUENCE_GAUSSIAN;
  if ((v = mr_get(map, "influence"))) {
    int k;
    CUPID_CALL(mr_enum(rd, v, "peridynamics.influence", influences, COUNT(influences), &k));
    pd->influence = (cupid_influence)k;
  }
  pd->partial_volume = CUPID_PARTIAL_PDLAMMPS;
  if ((v = mr_get(map, "partial_volume"))) {
    int k;
    CUPID_CALL(mr_enum(rd, v, "peridynamics.partial_volume", partials, COUNT(partials), &k));
    pd->partial_volume = (cupid_partial_volume)k;
  }
  pd->surface_correction = CUPID_SURFACE_NONE;
  if ((v = mr_get(map, "surface_correction"))) {
    int k;
    CUPID_CALL(mr_enum(rd, v, "peridynamics.surface_correction", corrections, COUNT(corrections),
                       &k));
    pd->surface_correction = (cupid_surface_correction)k;
  }
  v = mr_get(map, "area");
  if (pd->dimension == 1) {
    if (!v)
      return mr_error(rd, map->node, "peridynamics",
                      "missing required key 'area' (dimension 1 needs the bar's cross-section "
                      "area)");
    CUPID_CALL(mr_positive(rd, v, "peridynamics.area", &pd->area));
  } else if (v) {
    return mr_error(rd, v, "peridynamics.area", "is only used with dimension: 1");
  }
  return CUPID_SUCCESS;
}

static cupid_status read_regions(model_reader *rd, yaml_node_t *regions, cupid_peridynamics *pd) {
  int n;
  CUPID_CALL(mr_list(rd, regions, "peridynamics.regions", 0, "boxes {x: [..], y: [..], z: [..]}, "
                     "{cylinder: {..}} or {sphere: {..}}",
                     &n));
  /* an adaptive zone may start empty: the lattice is then laid on the beam (adaptive.c) */
  if (n == 0 && !pd->adaptive.has_adaptive)
    return mr_error(rd, regions, "peridynamics.regions", "must list at least one region (an "
                    "empty list needs peridynamics.adaptive: the zone then starts empty)");
  if (n == 0) return CUPID_SUCCESS;
  CUPID_CALL(cupid_calloc((size_t)n, sizeof *pd->regions, "PD regions", &pd->regions));
  pd->n_regions = n;
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    mr_path_index(p, "peridynamics.regions", i);
    CUPID_CALL(read_region(rd, mr_item(rd, regions, i), p, &pd->regions[i]));
  }
  return CUPID_SUCCESS;
}

/* ------------------------------------------------------------- precracks and fracture */

static const char *const axis_names[] = {"x", "y", "z"};

/* The two axes other than the normal n, in the order x, y, z. */
static void other_axes(int n, int *u, int *w) {
  *u = n == 0 ? 1 : 0;
  *w = n == 2 ? 1 : 2;
}

/* One side of a precrack's rectangle: [min, max] with min < max (a zero-size rectangle would
 * cut no bond, so it is surely a typo). */
static cupid_status read_precrack_side(model_reader *rd, yaml_node_t *node, const char *path,
                                       int axis, cupid_box *rect) {
  double r[2];
  CUPID_CALL(mr_numbers(rd, node, path, 2, "[min, max]", r));
  if (!(r[0] < r[1]))
    return mr_error(rd, node, path, "must be [min, max] with min < max, got [%g, %g]%s", r[0],
                    r[1], r[0] == r[1] ? " (the rectangle has zero size)" : "");
  rect->lo[axis] = r[0];
  rect->hi[axis] = r[1];
  rect->has[axis] = 1;
  return CUPID_SUCCESS;
}

/* The rectangle's two sides: the axes other than the normal, which itself takes no bounds. */
static cupid_status read_precrack_rect(model_reader *rd, const mr_map *map, const char *path,
                                       cupid_precrack *c) {
  int u, w;
  other_axes(c->normal, &u, &w);
  for (int a = 0; a < 3; a++) {
    char p[PATH_SIZE];
    mr_path(p, path, axis_names[a]);
    yaml_node_t *v = mr_get(map, axis_names[a]);
    c->rect.lo[a] = -INFINITY;
    c->rect.hi[a] = INFINITY;
    c->rect.has[a] = 0;
    if (a == c->normal) {
      if (v)
        return mr_error(rd, v, p,
                        "is the crack's normal axis: the crack lies on the plane %s = at and "
                        "takes bounds on %s and %s only",
                        axis_names[c->normal], axis_names[u], axis_names[w]);
      continue;
    }
    if (!v)
      return mr_error(rd, map->node, path,
                      "missing required key '%s' (a precrack with normal %s needs %s: [min, max] "
                      "and %s: [min, max])",
                      axis_names[a], axis_names[c->normal], axis_names[u], axis_names[w]);
    CUPID_CALL(read_precrack_side(rd, v, p, a, &c->rect));
  }
  return CUPID_SUCCESS;
}

/* The crack plane crosses the region and the rectangle overlaps its face by a positive area. */
static int precrack_touches(const cupid_precrack *c, const cupid_box *region) {
  if (!(c->at >= region->lo[c->normal] && c->at <= region->hi[c->normal])) return 0;
  for (int a = 0; a < 3; a++)
    if (a != c->normal && !(c->rect.lo[a] < region->hi[a] && c->rect.hi[a] > region->lo[a]))
      return 0;
  return 1;
}

/* A precrack that meets no region cuts no bond: say whether the plane or the rectangle misses. */
static cupid_status check_precrack_inside(model_reader *rd, const yaml_node_t *node,
                                          const char *path, const cupid_precrack *c) {
  const cupid_peridynamics *pd = &rd->model->pd;
  int n = c->normal, u, w, plane = 0;
  other_axes(n, &u, &w);
  if (pd->n_regions == 0) return CUPID_SUCCESS; /* an adaptive zone grows to it (adaptive.c) */
  for (int r = 0; r < pd->n_regions; r++) {
    const cupid_box *b = &pd->regions[r].box;
    if (precrack_touches(c, b)) return CUPID_SUCCESS;
    plane |= c->at >= b->lo[n] && c->at <= b->hi[n];
  }
  if (!plane)
    return mr_error(rd, node, path, "lies outside every PD region (none of them reaches %s = %g)",
                    axis_names[n], c->at);
  return mr_error(rd, node, path,
                  "lies outside every PD region (on the plane %s = %g, the rectangle %s [%g, %g], "
                  "%s [%g, %g] overlaps none of them)",
                  axis_names[n], c->at, axis_names[u], c->rect.lo[u], c->rect.hi[u],
                  axis_names[w], c->rect.lo[w], c->rect.hi[w]);
}

static cupid_status read_precrack(model_reader *rd, yaml_node_t *node, const char *path,
                                  cupid_precrack *c) {
  static const char *const keys[] = {"normal", "at", "x", "y", "z"};
  mr_map map;
  yaml_node_t *normal, *at;
  char p[PATH_SIZE];
  mr_mark(node, path, &c->mark);
  CUPID_CALL(mr_map_open(rd, node, path, keys, COUNT(keys), &map));
  if (!(normal = mr_get(&map, "normal")))
    return mr_error(rd, map.node, path,
                    "missing required key 'normal' (x, y or z: the axis normal to the crack)");
  mr_path(p, path, "normal");
  CUPID_CALL(mr_enum(rd, normal, p, axis_names, 3, &c->normal));
  if (!(at = mr_get(&map, "at")))
    return mr_error(rd, map.node, path,
                    "missing required key 'at' (the position of the crack plane along %s)",
                    axis_names[c->normal]);
  mr_path(p, path, "at");
  CUPID_CALL(mr_number(rd, at, p, &c->at));
  CUPID_CALL(read_precrack_rect(rd, &map, path, c));
  return check_precrack_inside(rd, node, path, c);
}

static cupid_status read_precracks(model_reader *rd, yaml_node_t *node, cupid_peridynamics *pd) {
  const char *path = "peridynamics.precracks";
  int n;
  CUPID_CALL(mr_list(rd, node, path, 1, "rectangles {normal: y, at: 50, x: [..], z: [..]}",
                     &n));
  /* Every precrack is tested against every region here and every bond later. */
  if (n > MODEL_MAX_PRECRACKS)
    return mr_error(rd, node, path, "lists %d precracks, at most %d are allowed", n,
                    MODEL_MAX_PRECRACKS);
  CUPID_CALL(cupid_calloc((size_t)n, sizeof *pd->precracks, "precracks", &pd->precracks));
  pd->n_precracks = n;
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    mr_path_index(p, path, i);
    CUPID_CALL(read_precrack(rd, mr_item(rd, node, i), p, &pd->precracks[i]));
  }
  return CUPID_SUCCESS;
}

/* Positive volume in common with a region (an axis the box leaves out is unbounded); a box
 * that only touches a face holds no node, since nodes sit at cell centres. */
static int box_overlaps(const cupid_box *box, const cupid_box *region) {
  for (int a = 0; a < 3; a++)
    if (!(box->lo[a] < region->hi[a] && box->hi[a] > region->lo[a])) return 0;
  return 1;
}

static cupid_status read_no_fail(model_reader *rd, yaml_node_t *node, cupid_fracture *f) {
  const char *path = "peridynamics.fracture.no_fail";
  const cupid_peridynamics *pd = &rd->model->pd;
  int n;
  CUPID_CALL(mr_list(rd, node, path, 1, "boxes {x: [..], y: [..], z: [..]}", &n));
  if (n > CUPID_MAX_NO_FAIL)
    return mr_error(rd, node, path, "lists %d boxes, at most %d are allowed", n,
                    CUPID_MAX_NO_FAIL);
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    yaml_node_t *item = mr_item(rd, node, i);
    mr_path_index(p, path, i);
    mr_mark(item, p, &f->no_fail_marks[i]);
    CUPID_CALL(mr_box(rd, item, p, &f->no_fail[i]));
    for (int a = 0; a < 3; a++) /* a box of no volume holds no node's centre but by chance */
      if (f->no_fail[i].has[a] && !(f->no_fail[i].lo[a] < f->no_fail[i].hi[a]))
        return mr_error(rd, item, p, "the box has no volume along %c ([%g, %g]): a no_fail box "
                        "needs min < max on every axis it gives", "xyz"[a], f->no_fail[i].lo[a],
                        f->no_fail[i].hi[a]);
    int inside = 0;
    for (int r = 0; r < pd->n_regions && !inside; r++)
      inside = box_overlaps(&f->no_fail[i], &pd->regions[r].box);
    if (!inside && !pd->adaptive.has_adaptive)
      return mr_error(rd, item, p, "no_fail box lies outside the body (it overlaps no PD region)");
  }
  f->n_no_fail = n;
  return CUPID_SUCCESS;
}

/* The limit of a bond: s0 directly or G0 (s0 derived later from G0, the bulk modulus and the
 * horizon); `stretch` takes exactly one of them, `energy` needs G0. */
static cupid_status read_fracture_limit(model_reader *rd, const mr_map *map, cupid_fracture *f) {
  const char *path = "peridynamics.fracture";
  yaml_node_t *s0 = mr_get(map, "critical_stretch"), *g0 = mr_get(map, "energy_release_rate");
  if (f->criterion == CUPID_FRACTURE_ENERGY) {
    if (s0)
      return mr_error(rd, s0, "peridynamics.fracture.critical_stretch",
                      "is not used with criterion: energy (the critical bond energy comes from "
                      "energy_release_rate, G0)");
    if (!g0)
      return mr_error(rd, map->node, path,
                      "missing required key 'energy_release_rate' (criterion energy needs G0)");
  } else if (s0 && g0) {
    int g0_later = g0->start_mark.index > s0->start_mark.index;
    return mr_error(rd, g0_later ? g0 : s0,
                    g0_later ? "peridynamics.fracture.energy_release_rate"
                             : "peridynamics.fracture.critical_stretch",
                    "give critical_stretch (s0) or energy_release_rate (G0), not both");
  } else if (!s0 && !g0) {
    return mr_error(rd, map->node, path,
                    "missing required key: give critical_stretch (s0) or energy_release_rate (G0)");
  }
  if (s0) {
    CUPID_CALL(mr_positive(rd, s0, "peridynamics.fracture.critical_stretch",
                           &f->critical_stretch));
    f->has_critical_stretch = 1;
  }
  if (g0) {
    CUPID_CALL(mr_positive(rd, g0, "peridynamics.fracture.energy_release_rate",
                           &f->energy_release_rate));
    f->has_energy_release_rate = 1;
  }
  return CUPID_SUCCESS;
}

static cupid_status read_fracture(model_reader *rd, yaml_node_t *node, cupid_peridynamics *pd) {
  static const char *const keys[] = {"criterion", "critical_stretch", "energy_release_rate",
                                     "calibration", "per_iteration", "no_fail"};
  static const char *const criteria[] = {"stretch", "energy"};
  static const char *const calibrations[] = {"continuum", "grid"};
  static const char *const per_iteration[] = {"all", "one"};
  cupid_fracture *f = &pd->fracture;
  mr_map map;
  yaml_node_t *v;
  int k;
  mr_mark(node, "peridynamics.fracture", &f->mark);
  f->has_fracture = 1;
  f->criterion = CUPID_FRACTURE_STRETCH;
  f->per_iteration_all = 1;
  CUPID_CALL(mr_map_open(rd, node, "peridynamics.fracture", keys, COUNT(keys), &map));
  if ((v = mr_get(&map, "criterion"))) {
    CUPID_CALL(mr_enum(rd, v, "peridynamics.fracture.criterion", criteria, COUNT(criteria), &k));
    f->criterion = (cupid_fracture_criterion)k;
    /* The bond energy needs the LPS split into dilatation and deviatoric parts. */
    if (f->criterion == CUPID_FRACTURE_ENERGY && pd->model == CUPID_PD_BOND)
      return mr_error(rd, v, "peridynamics.fracture.criterion",
                      "the energy criterion needs model: lps; use criterion: stretch for "
                      "bond-based");
  }
  CUPID_CALL(read_fracture_limit(rd, &map, f));
  if ((v = mr_get(&map, "calibration"))) {
    CUPID_CALL(mr_enum(rd, v, "peridynamics.fracture.calibration", calibrations,
                       COUNT(calibrations), &k));
    f->calibration_grid = k == 1;
    if (!f->has_energy_release_rate || f->criterion != CUPID_FRACTURE_STRETCH)
      return mr_error(rd, v, "peridynamics.fracture.calibration",
                      "calibrates the critical stretch from energy_release_rate (G0): it needs "
                      "criterion: stretch with energy_release_rate, not critical_stretch");
    /* LPS: a cut releases the dilatation energy of whole families, not a sum of bond
     * energies, so "the bonds across the plane at s0" does not define it */
    if (f->calibration_grid && pd->model == CUPID_PD_LPS)
      return mr_error(rd, v, "peridynamics.fracture.calibration",
                      "grid is defined for model: bond (the energy a cut releases is the sum of "
                      "the energies of the bonds it cuts); with lps a cut also releases the "
                      "dilatation energy of whole families: use calibration: continuum");
  }
  if ((v = mr_get(&map, "per_iteration"))) {
    CUPID_CALL(mr_enum(rd, v, "peridynamics.fracture.per_iteration", per_iteration,
                       COUNT(per_iteration), &k));
    f->per_iteration_all = k == 0;
    mr_mark(v, "peridynamics.fracture.per_iteration", &f->per_iteration_mark);
  }
  if ((v = mr_get(&map, "no_fail"))) CUPID_CALL(read_no_fail(rd, v, f));
  return CUPID_SUCCESS;
}

/* peridynamics.adaptive (issue 37): after fracture, which it needs (the trigger is a fraction
 * of the critical stretch, and the zone follows cracks). */
static cupid_status read_adaptive(model_reader *rd, yaml_node_t *node, cupid_peridynamics *pd) {
  static const char *const keys[] = {"threshold", "margin", "within", "max_nodes", "overlap",
                                     "every"};
  cupid_adaptive *a = &pd->adaptive;
  mr_map map;
  yaml_node_t *v;
  mr_mark(node, "peridynamics.adaptive", &a->mark);
  if (!pd->fracture.has_fracture)
    return mr_error(rd, node, "peridynamics.adaptive",
                    "needs peridynamics.fracture: the zone grows where the beam nears the "
                    "critical stretch and follows the cracks");
  a->has_adaptive = 1;
  a->threshold = 0.5;
  a->margin = 2.0;
  a->overlap = 1.0;
  CUPID_CALL(mr_map_open(rd, node, "peridynamics.adaptive", keys, COUNT(keys), &map));
  if ((v = mr_get(&map, "threshold"))) {
    CUPID_CALL(mr_number(rd, v, "peridynamics.adaptive.threshold", &a->threshold));
    if (!(a->threshold > 0.0 && a->threshold <= 1.0))
      return mr_error(rd, v, "peridynamics.adaptive.threshold",
                      "must lie in (0, 1] (a fraction of the critical stretch s0: an element "
                      "turns to PD when its largest principal strain reaches threshold * s0), "
                      "got %g", a->threshold);
  }
  if ((v = mr_get(&map, "margin")))
    CUPID_CALL(mr_nonnegative(rd, v, "peridynamics.adaptive.margin", &a->margin));
  if ((v = mr_get(&map, "overlap"))) {
    CUPID_CALL(mr_number(rd, v, "peridynamics.adaptive.overlap", &a->overlap));
    mr_mark(v, "peridynamics.adaptive.overlap", &a->overlap_mark);
    a->has_overlap = 1;
    if (!(a->overlap > 0.0))
      return mr_error(rd, v, "peridynamics.adaptive.overlap",
                      "must be positive (horizons: the overlaps of a zone that starts empty "
                      "span at least this), got %g", a->overlap);
  }
  if ((v = mr_get(&map, "within"))) {
    CUPID_CALL(mr_box(rd, v, "peridynamics.adaptive.within", &a->within));
    mr_mark(v, "peridynamics.adaptive.within", &a->within_mark);
    a->has_within = 1;
    for (int k = 0; k < 3; k++)
      if (a->within.has[k] && !(a->within.lo[k] < a->within.hi[k]))
        return mr_error(rd, v, "peridynamics.adaptive.within",
                        "the box has no volume along %c ([%g, %g]): give min < max",
                        "xyz"[k], a->within.lo[k], a->within.hi[k]);
  }
  if ((v = mr_get(&map, "max_nodes"))) {
    int n = 0;
    CUPID_CALL(mr_integer(rd, v, "peridynamics.adaptive.max_nodes", 1, 2147483647L, &n));
    a->max_nodes = n;
  }
  if ((v = mr_get(&map, "every"))) { /* dynamics: the trigger's steps (adaptive.c checks the type) */
    CUPID_CALL(mr_integer(rd, v, "peridynamics.adaptive.every", 1, 2147483647L, &a->every));
    mr_mark(v, "peridynamics.adaptive.every", &a->every_mark);
  }
  return CUPID_SUCCESS;
}

/* After the regions and options, so that the order of the keys does not matter. */
static cupid_status read_pd_fracture(model_reader *rd, const mr_map *map, cupid_peridynamics *pd) {
  yaml_node_t *precracks = mr_get(map, "precracks"), *fracture = mr_get(map, "fracture");
  if (pd->dimension == 1 && (precracks || fracture))
    return mr_error(rd, precracks ? precracks : fracture,
                    precracks ? "peridynamics.precracks" : "peridynamics.fracture",
                    "precracks and fracture need dimension: 3");
  if (precracks) CUPID_CALL(read_precracks(rd, precracks, pd));
  if (fracture) CUPID_CALL(read_fracture(rd, fracture, pd));
  yaml_node_t *adaptive = mr_get(map, "adaptive");
  if (adaptive) CUPID_CALL(read_adaptive(rd, adaptive, pd));
  return CUPID_SUCCESS;
}

static cupid_status read_peridynamics(model_reader *rd, yaml_node_t *node) {
  static const char *const keys[] = {"spacing",   "horizon",   "model",    "influence",
                                     "partial_volume", "surface_correction", "dimension",
                                     "area", "material", "regions", "holes", "precracks",
                                     "fracture", "adaptive"};
  cupid_peridynamics *pd = &rd->model->pd;
  mr_map map;
  yaml_node_t *spacing, *horizon, *regions, *material;
  mr_mark(node, "peridynamics", &pd->mark);
  rd->model->has_peridynamics = 1;
  pd->material = -1;
  CUPID_CALL(mr_map_open(rd, node, "peridynamics", keys, COUNT(keys), &map));
  CUPID_CALL(mr_require(rd, &map, "spacing", &spacing));
  CUPID_CALL(mr_positive(rd, spacing, "peridynamics.spacing", &pd->spacing));
  CUPID_CALL(mr_require(rd, &map, "horizon", &horizon));
  CUPID_CALL(mr_number(rd, horizon, "peridynamics.horizon", &pd->horizon));
  if (!(pd->horizon > pd->spacing))
    return mr_error(rd, horizon, "peridynamics.horizon", "must be larger than spacing (%g), got %g",
                    pd->spacing, pd->horizon);
  /* The same bound as pd_stencil_build, reported here with the file position. */
  if (pd->horizon / pd->spacing > 64)
    return mr_error(rd, horizon, "peridynamics.horizon",
                    "horizon/spacing = %g is beyond the supported 64 (m = 3 to 4 is usual; the "
                    "stencil would hold ~%.3g offsets a node)",
                    pd->horizon / pd->spacing, 4.19 * pow(pd->horizon / pd->spacing, 3));
  CUPID_CALL(read_pd_options(rd, &map, pd));
  if ((material = mr_get(&map, "material")))
    CUPID_CALL(mr_material(rd, material, "peridynamics.material", &pd->material));
  CUPID_CALL(mr_require(rd, &map, "regions", &regions));
  /* set again by read_adaptive: an adaptive zone may start empty, and its no_fail boxes and
   * pre-cracks may lie where it has not grown yet */
  pd->adaptive.has_adaptive = mr_get(&map, "adaptive") != NULL;
  CUPID_CALL(read_regions(rd, regions, pd));
  yaml_node_t *holes = mr_get(&map, "holes");
  if (holes) CUPID_CALL(read_holes(rd, holes, pd));
  return read_pd_fracture(rd, &map, pd);
}

/* ------------------------------------------------------------------------------- coupling */

/* coupling.arlequin.overlap[i]: a slab along one axis ({y: [30, 35]}), or one bounded on
 * more axes with `along` naming the axis its weight ramps along (it serves only the regions
 * inside its other bounds: an adaptive zone's overlap next to one section element). */
static cupid_status read_overlap(model_reader *rd, yaml_node_t *item, const char *p,
                                 cupid_coupling *c, int i) {
  static const char *const axes[] = {"x", "y", "z"};
  yaml_node_t *along = NULL;
  CUPID_CALL(mr_box_extra(rd, item, p, "along", &c->overlaps[i], &along));
  mr_mark(item, p, &c->overlap_marks[i]);
  const cupid_box *bx = &c->overlaps[i];
  const int n = bx->has[0] + bx->has[1] + bx->has[2];
  if (!along) {
    if (n != 1)
      return mr_error(rd, item, p,
                      "an overlap is a slab along one axis next to a PD region's face: give "
                      "exactly one of x, y, z (e.g. {y: [30, 35]}), or name the axis its "
                      "weight ramps along with `along` (e.g. {x: [5, 20], z: [45, 50], along: x})");
    c->overlap_along[i] = bx->has[0] ? 0 : bx->has[1] ? 1 : 2;
    return CUPID_SUCCESS;
  }
  char ap[PATH_SIZE];
  mr_path(ap, p, "along");
  int k;
  CUPID_CALL(mr_enum(rd, along, ap, axes, 3, &k));
  if (!bx->has[k])
    return mr_error(rd, along, ap, "the overlap ramps along %s, and gives no %s range: give "
                    "%s: [min, max]", axes[k], axes[k], axes[k]);
  c->overlap_along[i] = k;
  return CUPID_SUCCESS;
}

static cupid_status read_arlequin(model_reader *rd, yaml_node_t *node, cupid_coupling *c) {
  static const char *const keys[] = {"penalty", "overlap", "weight"};
  static const char *const weights[] = {"linear", "constant", "smooth"};
  mr_map map;
  yaml_node_t *penalty, *overlap, *weight;
  CUPID_CALL(mr_map_open(rd, node, "coupling.arlequin", keys, COUNT(keys), &map));
  CUPID_CALL(mr_require(rd, &map, "penalty", &penalty));
  /* a number (N/m per tied node and component) or `auto` (chosen from the PD stiffness) */
  CUPID_CALL(mr_positive_or_auto(rd, penalty, "coupling.arlequin.penalty", &c->penalty_auto,
                                 &c->penalty));
  CUPID_CALL(mr_require(rd, &map, "overlap", &overlap));
  int n = 1;
  if (overlap->type == YAML_SEQUENCE_NODE) {
    CUPID_CALL(mr_list(rd, overlap, "coupling.arlequin.overlap", 0, "slabs {y: [..]}", &n));
    mr_mark(overlap, "coupling.arlequin.overlap", &c->overlap_list_mark);
    /* [] only for an adaptive zone that starts empty (checked with the PD section) */
    if (n < 0 || n > CUPID_MAX_OVERLAPS)
      return mr_error(rd, overlap, "coupling.arlequin.overlap",
                      "lists %d slabs; give 1 to %d (one per interface face of the PD regions)",
                      n, CUPID_MAX_OVERLAPS);
  }
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    yaml_node_t *item = overlap->type == YAML_SEQUENCE_NODE ? mr_item(rd, overlap, i) : overlap;
    if (overlap->type == YAML_SEQUENCE_NODE) mr_path_index(p, "coupling.arlequin.overlap", i);
    else snprintf(p, sizeof p, "coupling.arlequin.overlap");
    CUPID_CALL(read_overlap(rd, item, p, c, i));
  }
  c->n_overlaps = n;
  c->weight = CUPID_WEIGHT_LINEAR;
  if ((weight = mr_get(&map, "weight"))) {
    int k;
    CUPID_CALL(mr_enum(rd, weight, "coupling.arlequin.weight", weights, COUNT(weights), &k));
    c->weight = (cupid_weight)k;
  }
  c->has_arlequin = 1;
  return CUPID_SUCCESS;
}

/* coupling.fictitious_fe: removed | adjacent | plane | a length > 0 (model.h). */
static cupid_status read_fictitious_fe(model_reader *rd, yaml_node_t *node, cupid_coupling *c) {
  static const char *const kinds[] = {"removed", "adjacent", "plane"};
  const char *path = "coupling.fictitious_fe";
  if (mr_is_scalar(node) && node->data.scalar.style == YAML_PLAIN_SCALAR_STYLE) {
    char *end = NULL;
    const char *text = (const char *)node->data.scalar.value;
    double v = strtod(text, &end);
    if (end != text && *end == '\0') {
      if (!(v > 0 && isfinite(v)))
        return mr_error(rd, node, path, "a length must be > 0, got %s", text);
      c->fictitious_fe = 3;
      c->fictitious_length = v;
      return CUPID_SUCCESS;
    }
  }
  int k;
  CUPID_CALL(mr_enum(rd, node, path, kinds, COUNT(kinds), &k));
  c->fictitious_fe = k;
  return CUPID_SUCCESS;
}

static cupid_status read_coupling(model_reader *rd, yaml_node_t *node) {
  static const char *const keys[] = {"method", "arlequin", "fictitious_fe", "balance"};
  static const char *const balances[] = {"none", "momentum", "global"};
  static const char *const methods[] = {"fictitious", "lagrange", "arlequin"};
  cupid_coupling *c = &rd->model->coupling;
  mr_map map;
  yaml_node_t *method, *arlequin;
  int k;
  mr_mark(node, "coupling", &c->mark);
  rd->model->has_coupling = 1;
  CUPID_CALL(mr_map_open(rd, node, "coupling", keys, COUNT(keys), &map));
  CUPID_CALL(mr_require(rd, &map, "method", &method));
  CUPID_CALL(mr_enum(rd, method, "coupling.method", methods, COUNT(methods), &k));
  c->method = (cupid_coupling_method)k;
  arlequin = mr_get(&map, "arlequin");
  yaml_node_t *ffe = mr_get(&map, "fictitious_fe");
  if (ffe && c->method != CUPID_COUPLING_FICTITIOUS)
    return mr_error(rd, ffe, "coupling.fictitious_fe", "is only used with method: fictitious");
  if (ffe) CUPID_CALL(read_fictitious_fe(rd, ffe, c));
  yaml_node_t *balance = mr_get(&map, "balance");
  if (balance && c->method != CUPID_COUPLING_FICTITIOUS)
    return mr_error(rd, balance, "coupling.balance",
                    "is only used with method: fictitious (lagrange and arlequin conserve "
                    "momentum already)");
  c->balance = c->method == CUPID_COUPLING_FICTITIOUS; /* the default (set_defaults) */
  if (balance) CUPID_CALL(mr_enum(rd, balance, "coupling.balance", balances, COUNT(balances), &c->balance));
  if (c->method == CUPID_COUPLING_ARLEQUIN) {
    if (!arlequin)
      return mr_error(rd, map.node, "coupling",
                      "missing required key 'arlequin' (method arlequin needs {penalty: ..., "
                      "overlap: {y: [..]}})");
    return read_arlequin(rd, arlequin, c);
  }
  if (arlequin)
    return mr_error(rd, arlequin, "coupling.arlequin", "is only used with method: arlequin");
  return CUPID_SUCCESS;
}

/* ---------------------------------------------------------------- constraints and loads */

/* Each list entry holds exactly one of the given kinds: its index, and the kind's value. */
static cupid_status one_kind(model_reader *rd, yaml_node_t *node, const char *path,
                             const char *const *kinds, int n, int *kind, yaml_node_t **value) {
  mr_map map;
  char list[128];
  CUPID_CALL(mr_map_open(rd, node, path, kinds, n, &map));
  mr_join(kinds, n, ", ", list, sizeof list);
  *kind = -1;
  for (int i = 0; i < n; i++) {
    if (!map.value[i]) continue;
    if (*kind >= 0)
      return mr_error(rd, node, path, "has both '%s' and '%s'; give one of %s per list entry",
                      kinds[*kind], kinds[i], list);
    *kind = i;
    *value = map.value[i];
  }
  if (*kind < 0) return mr_error(rd, node, path, "must be one of %s", list);
  return CUPID_SUCCESS;
}

static cupid_status read_fix_components(model_reader *rd, yaml_node_t *node, const char *path,
                                        int components[3]) {
  static const char *const axes[] = {"x", "y", "z"};
  int n;
  CUPID_CALL(mr_list(rd, node, path, 0, "components (x, y, z)", &n));
  if (n == 0) return mr_error(rd, node, path, "must list at least one of x, y, z");
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    int a;
    mr_path_index(p, path, i);
    yaml_node_t *item = mr_item(rd, node, i);
    CUPID_CALL(mr_enum(rd, item, p, axes, 3, &a));
    if (components[a]) return mr_error(rd, item, p, "component '%s' is listed twice", axes[a]);
    components[a] = 1;
  }
  return CUPID_SUCCESS;
}

static cupid_status read_constraint(model_reader *rd, yaml_node_t *node, const char *path,
                                    cupid_constraint *c) {
  static const char *const kinds[] = {"clamp", "fix", "displacement"};
  static const char *const clamp_keys[] = {"y", "layer"};
  static const char *const fix_keys[] = {"box", "components"};
  static const char *const displacement_keys[] = {"box", "value"};
  int kind;
  yaml_node_t *body, *v;
  char sub[PATH_SIZE], p[PATH_SIZE];
  mr_map map;
  mr_mark(node, path, &c->mark);
  CUPID_CALL(one_kind(rd, node, path, kinds, COUNT(kinds), &kind, &body));
  c->kind = (cupid_constraint_kind)kind;
  mr_path(sub, path, kinds[kind]);
  if (c->kind == CUPID_CONSTRAINT_CLAMP) {
    CUPID_CALL(mr_map_open(rd, body, sub, clamp_keys, COUNT(clamp_keys), &map));
    CUPID_CALL(mr_require(rd, &map, "y", &v));
    mr_path(p, sub, "y");
    CUPID_CALL(mr_number(rd, v, p, &c->plane_y));
    if ((v = mr_get(&map, "layer"))) {
      mr_path(p, sub, "layer");
      CUPID_CALL(mr_nonnegative(rd, v, p, &c->layer));
    }
  } else if (c->kind == CUPID_CONSTRAINT_FIX) {
    CUPID_CALL(mr_map_open(rd, body, sub, fix_keys, COUNT(fix_keys), &map));
    CUPID_CALL(mr_require(rd, &map, "box", &v));
    mr_path(p, sub, "box");
    CUPID_CALL(mr_box(rd, v, p, &c->box));
    if ((v = mr_get(&map, "components"))) {
      mr_path(p, sub, "components");
      CUPID_CALL(read_fix_components(rd, v, p, c->components));
    } else {
      c->components[0] = c->components[1] = c->components[2] = 1;
    }
  } else {
    CUPID_CALL(mr_map_open(rd, body, sub, displacement_keys, COUNT(displacement_keys), &map));
    CUPID_CALL(mr_require(rd, &map, "box", &v));
    mr_path(p, sub, "box");
    CUPID_CALL(mr_box(rd, v, p, &c->box));
    CUPID_CALL(mr_require(rd, &map, "value", &v));
    mr_path(p, sub, "value");
    CUPID_CALL(mr_values3(rd, v, p, 1, c->value));
    if (!c->value[0].kind && !c->value[1].kind && !c->value[2].kind)
      return mr_error(rd, v, p, "all three components are null (free): nothing is imposed");
  }
  return CUPID_SUCCESS;
}

static cupid_status read_constraints(model_reader *rd, yaml_node_t *node) {
  cupid_model_t *m = rd->model;
  int n;
  CUPID_CALL(mr_list(rd, node, "constraints", 1, "constraints (clamp, fix, displacement)", &n));
  CUPID_CALL(cupid_calloc((size_t)n, sizeof *m->constraints, "constraints", &m->constraints));
  m->n_constraints = n;
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    mr_path_index(p, "constraints", i);
    CUPID_CALL(read_constraint(rd, mr_item(rd, node, i), p, &m->constraints[i]));
  }
  return CUPID_SUCCESS;
}

static cupid_status read_traction(model_reader *rd, yaml_node_t *body, const char *sub,
                                  cupid_load *l) {
  static const char *const keys[] = {"y", "x", "z", "value"};
  mr_map map;
  yaml_node_t *v;
  char p[PATH_SIZE];
  CUPID_CALL(mr_map_open(rd, body, sub, keys, COUNT(keys), &map));
  CUPID_CALL(mr_require(rd, &map, "y", &v));
  mr_path(p, sub, "y");
  CUPID_CALL(mr_number(rd, v, p, &l->plane_y));
  for (int a = 0; a < 3; a++) {
    l->patch.lo[a] = -INFINITY;
    l->patch.hi[a] = INFINITY;
  }
  for (int a = 0; a < 3; a += 2) {
    const char *axis = a == 0 ? "x" : "z";
    if (!(v = mr_get(&map, axis))) continue;
    double range[2];
    mr_path(p, sub, axis);
    CUPID_CALL(mr_range(rd, v, p, 1, range));
    l->patch.lo[a] = range[0];
    l->patch.hi[a] = range[1];
    l->patch.has[a] = 1;
  }
  CUPID_CALL(mr_require(rd, &map, "value", &v));
  mr_path(p, sub, "value");
  return mr_values3(rd, v, p, 0, l->value);
}

static cupid_status read_load(model_reader *rd, yaml_node_t *node, const char *path,
                              cupid_load *l) {
  static const char *const kinds[] = {"traction", "point", "body"};
  static const char *const point_keys[] = {"at", "value"};
  static const char *const body_keys[] = {"box", "value"};
  int kind;
  yaml_node_t *body, *v;
  char sub[PATH_SIZE], p[PATH_SIZE];
  mr_map map;
  mr_mark(node, path, &l->mark);
  CUPID_CALL(one_kind(rd, node, path, kinds, COUNT(kinds), &kind, &body));
  l->kind = (cupid_load_kind)kind;
  mr_path(sub, path, kinds[kind]);
  if (l->kind == CUPID_LOAD_TRACTION) return read_traction(rd, body, sub, l);
  if (l->kind == CUPID_LOAD_POINT) {
    CUPID_CALL(mr_map_open(rd, body, sub, point_keys, COUNT(point_keys), &map));
    CUPID_CALL(mr_require(rd, &map, "at", &v));
    mr_path(p, sub, "at");
    CUPID_CALL(mr_numbers(rd, v, p, 3, "[x, y, z]", l->at));
  } else {
    CUPID_CALL(mr_map_open(rd, body, sub, body_keys, COUNT(body_keys), &map));
    for (int a = 0; a < 3; a++) {
      l->box.lo[a] = -INFINITY;
      l->box.hi[a] = INFINITY;
    }
    if ((v = mr_get(&map, "box"))) {
      mr_path(p, sub, "box");
      CUPID_CALL(mr_box(rd, v, p, &l->box));
    }
  }
  CUPID_CALL(mr_require(rd, &map, "value", &v));
  mr_path(p, sub, "value");
  return mr_values3(rd, v, p, 0, l->value);
}

static cupid_status read_loads(model_reader *rd, yaml_node_t *node) {
  cupid_model_t *m = rd->model;
  int n;
  CUPID_CALL(mr_list(rd, node, "loads", 1, "loads (traction, point, body)", &n));
  CUPID_CALL(cupid_calloc((size_t)n, sizeof *m->loads, "loads", &m->loads));
  m->n_loads = n;
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    mr_path_index(p, "loads", i);
    CUPID_CALL(read_load(rd, mr_item(rd, node, i), p, &m->loads[i]));
  }
  return CUPID_SUCCESS;
}

/* ------------------------------------------------------------------------------- analysis */

static cupid_status read_newmark(model_reader *rd, yaml_node_t *node, cupid_dynamic *d) {
  static const char *const keys[] = {"beta", "gamma"};
  mr_map map;
  yaml_node_t *v;
  CUPID_CALL(mr_map_open(rd, node, "analysis.dynamic.newmark", keys, COUNT(keys), &map));
  if ((v = mr_get(&map, "beta"))) {
    CUPID_CALL(mr_number(rd, v, "analysis.dynamic.newmark.beta", &d->newmark_beta));
    if (!(d->newmark_beta >= 0 && d->newmark_beta <= 0.5))
      return mr_error(rd, v, "analysis.dynamic.newmark.beta", "must be from 0 to 0.5, got %s",
                      text_of(v));
  }
  if ((v = mr_get(&map, "gamma"))) {
    CUPID_CALL(mr_number(rd, v, "analysis.dynamic.newmark.gamma", &d->newmark_gamma));
    /* gamma < 1/2 adds negative numerical damping: the response grows without bound. */
    if (!(d->newmark_gamma >= 0.5 && d->newmark_gamma <= 1))
      return mr_error(rd, v, "analysis.dynamic.newmark.gamma",
                      "must be from 0.5 to 1 (below 0.5 the scheme is unstable), got %s",
                      text_of(v));
  }
  return CUPID_SUCCESS;
}

static cupid_status read_rayleigh(model_reader *rd, yaml_node_t *node, cupid_dynamic *d) {
  static const char *const keys[] = {"mass", "stiffness"};
  mr_map map;
  yaml_node_t *v;
  CUPID_CALL(mr_map_open(rd, node, "analysis.dynamic.rayleigh", keys, COUNT(keys), &map));
  if ((v = mr_get(&map, "mass")))
    CUPID_CALL(mr_nonnegative(rd, v, "analysis.dynamic.rayleigh.mass", &d->rayleigh_mass));
  if ((v = mr_get(&map, "stiffness")))
    CUPID_CALL(
        mr_nonnegative(rd, v, "analysis.dynamic.rayleigh.stiffness", &d->rayleigh_stiffness));
  return CUPID_SUCCESS;
}

static cupid_status read_initial(model_reader *rd, yaml_node_t *node, cupid_dynamic *d) {
  static const char *const keys[] = {"displacement", "velocity"};
  mr_map map;
  yaml_node_t *v;
  CUPID_CALL(mr_map_open(rd, node, "analysis.dynamic.initial", keys, COUNT(keys), &map));
  if ((v = mr_get(&map, "displacement")))
    CUPID_CALL(mr_values3(rd, v, "analysis.dynamic.initial.displacement", 0,
                          d->initial_displacement));
  if ((v = mr_get(&map, "velocity")))
    CUPID_CALL(mr_values3(rd, v, "analysis.dynamic.initial.velocity", 0, d->initial_velocity));
  return CUPID_SUCCESS;
}

static cupid_status read_dynamic(model_reader *rd, yaml_node_t *node, cupid_dynamic *d) {
  static const char *const keys[] = {"integrator", "dt",      "duration", "every",
                                     "rayleigh",   "newmark", "lumped",   "initial"};
  static const char *const integrators[] = {"newmark", "central"};
  mr_map map;
  yaml_node_t *v, *dt, *duration;
  mr_mark(node, "analysis.dynamic", &d->mark);
  d->has_dynamic = 1;
  CUPID_CALL(mr_map_open(rd, node, "analysis.dynamic", keys, COUNT(keys), &map));
  if ((v = mr_get(&map, "integrator"))) {
    int k;
    CUPID_CALL(mr_enum(rd, v, "analysis.dynamic.integrator", integrators, COUNT(integrators), &k));
    d->integrator = (cupid_integrator)k;
  }
  CUPID_CALL(mr_require(rd, &map, "dt", &dt));
  CUPID_CALL(mr_positive(rd, dt, "analysis.dynamic.dt", &d->dt));
  CUPID_CALL(mr_require(rd, &map, "duration", &duration));
  CUPID_CALL(mr_positive(rd, duration, "analysis.dynamic.duration", &d->duration));
  if (d->duration < d->dt)
    return mr_error(rd, duration, "analysis.dynamic.duration", "must be at least dt (%g), got %g",
                    d->dt, d->duration);
  if (d->duration / d->dt > 1e9)
    return mr_error(rd, dt, "analysis.dynamic.dt",
                    "gives %.3g time steps over the duration (at most 1e9)", d->duration / d->dt);
  if ((v = mr_get(&map, "every")))
    CUPID_CALL(mr_integer(rd, v, "analysis.dynamic.every", 1, 2147483647L, &d->every));
  if ((v = mr_get(&map, "rayleigh"))) CUPID_CALL(read_rayleigh(rd, v, d));
  if ((v = mr_get(&map, "newmark"))) {
    if (d->integrator != CUPID_INTEGRATOR_NEWMARK)
      return mr_error(rd, v, "analysis.dynamic.newmark", "is only used with integrator: newmark");
    CUPID_CALL(read_newmark(rd, v, d));
  }
  if ((v = mr_get(&map, "lumped")))
    CUPID_CALL(mr_bool(rd, v, "analysis.dynamic.lumped", &d->lumped_mass));
  if ((v = mr_get(&map, "initial"))) CUPID_CALL(read_initial(rd, v, d));
  return CUPID_SUCCESS;
}

static cupid_status read_analysis(model_reader *rd, yaml_node_t *node) {
  static const char *const keys[] = {"type", "solver", "steps", "field", "dynamic"};
  static const char *const types[] = {"static", "dynamic", "evaluate"};
  static const char *const solvers[] = {"auto", "direct", "petsc", "krylov"};
  cupid_analysis *a = &rd->model->analysis;
  mr_map map;
  yaml_node_t *v;
  int k;
  if (node) mr_mark(node, "analysis", &a->mark);
  CUPID_CALL(mr_map_open(rd, node, "analysis", keys, COUNT(keys), &map));
  if ((v = mr_get(&map, "type"))) {
    CUPID_CALL(mr_enum(rd, v, "analysis.type", types, COUNT(types), &k));
    a->type = (cupid_analysis_type)k;
  }
  if ((v = mr_get(&map, "solver"))) {
    CUPID_CALL(mr_enum(rd, v, "analysis.solver", solvers, COUNT(solvers), &k));
    a->solver = (cupid_solver_kind)k;
  }
  if ((v = mr_get(&map, "steps"))) {
    if (a->type != CUPID_ANALYSIS_STATIC)
      return mr_error(rd, v, "analysis.steps", "is only used with type: static (load steps)");
    CUPID_CALL(mr_integer(rd, v, "analysis.steps", 1, 1000000L, &a->steps));
    mr_mark(v, "analysis.steps", &a->steps_mark);
  }
  v = mr_get(&map, "field");
  if (a->type == CUPID_ANALYSIS_EVALUATE) {
    if (!v)
      return mr_error(rd, node, "analysis",
                      "missing required key 'field' (type evaluate imposes field: [ux, uy, uz])");
    CUPID_CALL(mr_values3(rd, v, "analysis.field", 0, a->field));
  } else if (v) {
    return mr_error(rd, v, "analysis.field", "is only used with type: evaluate");
  }
  v = mr_get(&map, "dynamic");
  if (a->type == CUPID_ANALYSIS_DYNAMIC) {
    if (!v)
      return mr_error(rd, node, "analysis",
                      "missing required key 'dynamic' (type dynamic needs dynamic: {dt: ..., "
                      "duration: ...})");
    CUPID_CALL(read_dynamic(rd, v, &a->dynamic));
  } else if (v) {
    return mr_error(rd, v, "analysis.dynamic", "is only used with type: dynamic");
  }
  return CUPID_SUCCESS;
}

/* --------------------------------------------------------------------------------- output */

/* Names end up in file names (line_<name>.csv) and CSV headers: letters, digits, _ and -. */
static cupid_status read_output_name(model_reader *rd, yaml_node_t *node, const char *path,
                                     char **out) {
  CUPID_CALL(mr_string(rd, node, path, MODEL_MAX_NAME, out));
  int ok = (*out)[0] != '\0';
  for (const char *s = *out; ok && *s; s++)
    ok = isalnum((unsigned char)*s) || *s == '_' || *s == '-';
  if (!ok)
    return mr_error(rd, node, path,
                    "must be a name of letters, digits, _ and - (it is used in file names), got "
                    "'%s'",
                    *out);
  return CUPID_SUCCESS;
}

static cupid_status read_line(model_reader *rd, yaml_node_t *node, const char *path,
                              cupid_output_line *l) {
  static const char *const keys[] = {"name", "from", "to", "points"};
  mr_map map;
  yaml_node_t *v, *to;
  char p[PATH_SIZE];
  mr_mark(node, path, &l->mark);
  CUPID_CALL(mr_map_open(rd, node, path, keys, COUNT(keys), &map));
  CUPID_CALL(mr_require(rd, &map, "name", &v));
  mr_path(p, path, "name");
  CUPID_CALL(read_output_name(rd, v, p, &l->name));
  CUPID_CALL(mr_require(rd, &map, "from", &v));
  mr_path(p, path, "from");
  CUPID_CALL(mr_numbers(rd, v, p, 3, "[x, y, z]", l->from));
  CUPID_CALL(mr_require(rd, &map, "to", &to));
  mr_path(p, path, "to");
  CUPID_CALL(mr_numbers(rd, to, p, 3, "[x, y, z]", l->to));
  if (l->from[0] == l->to[0] && l->from[1] == l->to[1] && l->from[2] == l->to[2])
    return mr_error(rd, to, p, "must differ from 'from' (a line needs two distinct ends)");
  CUPID_CALL(mr_require(rd, &map, "points", &v));
  mr_path(p, path, "points");
  return mr_integer(rd, v, p, 2, MAX_LINE_POINTS, &l->points);
}

static cupid_status read_point(model_reader *rd, yaml_node_t *node, const char *path,
                               cupid_output_point *pt) {
  static const char *const keys[] = {"name", "at", "stress"};
  mr_map map;
  yaml_node_t *v;
  char p[PATH_SIZE];
  mr_mark(node, path, &pt->mark);
  CUPID_CALL(mr_map_open(rd, node, path, keys, COUNT(keys), &map));
  CUPID_CALL(mr_require(rd, &map, "name", &v));
  mr_path(p, path, "name");
  CUPID_CALL(read_output_name(rd, v, p, &pt->name));
  CUPID_CALL(mr_require(rd, &map, "at", &v));
  mr_path(p, path, "at");
  CUPID_CALL(mr_numbers(rd, v, p, 3, "[x, y, z]", pt->at));
  if ((v = mr_get(&map, "stress"))) {
    mr_path(p, path, "stress");
    CUPID_CALL(mr_bool(rd, v, p, &pt->stress));
  }
  return CUPID_SUCCESS;
}

/* Names must be unique within a list; report the later one against the earlier one. */
static cupid_status unique_names(model_reader *rd, char **names, const cupid_mark *const *marks,
                                 int n, const char *what) {
  int first = -1, dup = mr_find_duplicate(names, n, &first);
  if (dup < 0) return CUPID_SUCCESS;
  char path[PATH_SIZE];
  cupid_mark mark = *marks[dup];
  mr_path(path, marks[dup]->key, "name");
  memcpy(mark.key, path, sizeof mark.key);
  return cupid_model_error(rd->model, &mark, "duplicate %s name '%s' (also %s)", what, names[dup],
                           marks[first]->key);
}

static cupid_status read_output_lists(model_reader *rd, const mr_map *map, cupid_output *o) {
  yaml_node_t *lines = mr_get(map, "lines"), *points = mr_get(map, "points");
  cupid_status st = CUPID_SUCCESS;
  char **names = NULL;
  const cupid_mark **marks = NULL;
  int n;
  CUPID_TRY(mr_list(rd, lines, "output.lines", 1, "lines {name, from, to, points}", &n));
  CUPID_TRY(cupid_calloc((size_t)n, sizeof *o->lines, "output lines", &o->lines));
  o->n_lines = n;
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    mr_path_index(p, "output.lines", i);
    CUPID_TRY(read_line(rd, mr_item(rd, lines, i), p, &o->lines[i]));
  }
  CUPID_TRY(mr_list(rd, points, "output.points", 1, "points {name, at}", &n));
  CUPID_TRY(cupid_calloc((size_t)n, sizeof *o->points, "output points", &o->points));
  o->n_points = n;
  for (int i = 0; i < n; i++) {
    char p[PATH_SIZE];
    mr_path_index(p, "output.points", i);
    CUPID_TRY(read_point(rd, mr_item(rd, points, i), p, &o->points[i]));
  }
  int most = o->n_lines > o->n_points ? o->n_lines : o->n_points;
  CUPID_TRY(cupid_calloc((size_t)most, sizeof *names, "output names", &names));
  CUPID_TRY(cupid_calloc((size_t)most, sizeof *marks, "output marks", &marks));
  for (int i = 0; i < o->n_lines; i++) names[i] = o->lines[i].name, marks[i] = &o->lines[i].mark;
  CUPID_TRY(unique_names(rd, names, marks, o->n_lines, "line"));
  for (int i = 0; i < o->n_points; i++)
    names[i] = o->points[i].name, marks[i] = &o->points[i].mark;
  CUPID_TRY(unique_names(rd, names, marks, o->n_points, "point"));
cleanup:
  cupid_free(&names);
  cupid_free(&marks);
  return st;
}

/* "out/<stem>": the model file's name without directories and extension; "out/model" for a
 * model that is no file ("<dict>", "<text>": the Python API's names, issue 33: a folder named
 * "<dict>" was made). */
static cupid_status default_directory(const char *file, char **out) {
  if (file[0] == '<') return cupid_strdup("out/model", out);
  const char *base = strrchr(file, '/');
  base = base ? base + 1 : file;
  size_t n = strlen(base);
  const char *dot = strrchr(base, '.');
  if (dot && dot != base) n = (size_t)(dot - base);
  if (n == 0) return cupid_strdup("out/model", out);
  CUPID_CALL(cupid_malloc(n + 5, 1, "the output directory", out));
  memcpy(*out, "out/", 4);
  memcpy(*out + 4, base, n);
  (*out)[n + 4] = '\0';
  return CUPID_SUCCESS;
}

static cupid_status read_output(model_reader *rd, yaml_node_t *node) {
  static const char *const keys[] = {"directory", "vtu", "pd_nodes", "plots", "lines", "points",
                                     "checkpoint", "exodus"};
  cupid_output *o = &rd->model->output;
  mr_map map;
  yaml_node_t *v;
  o->vtu = 1;
  o->plots = 1;
  o->pd_nodes = 0;
  if (node) mr_mark(node, "output", &o->mark);
  CUPID_CALL(mr_map_open(rd, node, "output", keys, COUNT(keys), &map));
  if ((v = mr_get(&map, "directory"))) {
    CUPID_CALL(mr_string(rd, v, "output.directory", MODEL_MAX_STRING, &o->directory));
    if (!o->directory[0]) return mr_error(rd, v, "output.directory", "must not be empty");
  } else {
    CUPID_CALL(default_directory(rd->model->file, &o->directory));
  }
  if ((v = mr_get(&map, "vtu"))) CUPID_CALL(mr_bool(rd, v, "output.vtu", &o->vtu));
  if ((v = mr_get(&map, "pd_nodes"))) CUPID_CALL(mr_bool(rd, v, "output.pd_nodes", &o->pd_nodes));
  if ((v = mr_get(&map, "plots"))) CUPID_CALL(mr_bool(rd, v, "output.plots", &o->plots));
  if ((v = mr_get(&map, "exodus"))) {
    CUPID_CALL(mr_bool(rd, v, "output.exodus", &o->exodus));
    const char *missing = o->exodus ? cupid_writer_unavailable(&cupid_writer_exodus) : NULL;
    if (missing) return mr_error(rd, v, "output.exodus", "%s", missing);
  }
  if ((v = mr_get(&map, "checkpoint"))) {
    CUPID_CALL(mr_number(rd, v, "output.checkpoint", &o->checkpoint));
    if (!(o->checkpoint >= 0 && o->checkpoint <= 1e9))
      return mr_error(rd, v, "output.checkpoint", "must be seconds between checkpoints, from 0 "
                      "(none) to 1e9");
  }
  return read_output_lists(rd, &map, o);
}

/* ------------------------------------------------------------------------------ the model */

static void set_defaults(cupid_model_t *m) {
  m->analysis.type = CUPID_ANALYSIS_STATIC;
  m->analysis.solver = CUPID_SOLVER_AUTO;
  cupid_dynamic *d = &m->analysis.dynamic;
  d->integrator = CUPID_INTEGRATOR_NEWMARK;
  d->every = 1;
  d->newmark_beta = 0.25;
  d->newmark_gamma = 0.5;
  m->beam.material = -1;
  m->beam.element_nodes = 2;
  m->pd.material = -1;
  m->pd.dimension = 3;
  m->coupling.weight = CUPID_WEIGHT_LINEAR;
  m->coupling.balance = 1; /* method fictitious, the default: each interface balanced (issue 34;
                              `balance: none` is paper 000's Eq. 38 as printed) */
  m->output.vtu = 1;
  m->output.plots = 1;
  m->output.checkpoint = -1; /* auto: cupid_problem_checkpoint_period() */
}

cupid_status mr_read_model(model_reader *rd, yaml_node_t *root) {
  static const char *const keys[] = {"title",       "materials", "beam",     "peridynamics",
                                     "coupling",    "constraints", "loads", "analysis",
                                     "output"};
  char got[64];
  if (!root || root->type != YAML_MAPPING_NODE)
    return mr_error(rd, root, "",
                    "the top level of a model must be a mapping of sections (title:, materials:, "
                    "beam:, ...), got %s",
                    mr_describe(root, got, sizeof got));
  set_defaults(rd->model);
  mr_map top;
  yaml_node_t *v;
  CUPID_CALL(mr_map_open(rd, root, "", keys, COUNT(keys), &top));
  CUPID_CALL(read_title(rd, mr_get(&top, "title")));
  CUPID_CALL(mr_require(rd, &top, "materials", &v));
  CUPID_CALL(read_materials(rd, v));
  if ((v = mr_get(&top, "beam"))) CUPID_CALL(read_beam(rd, v));
  if ((v = mr_get(&top, "peridynamics"))) CUPID_CALL(read_peridynamics(rd, v));
  if ((v = mr_get(&top, "coupling"))) CUPID_CALL(read_coupling(rd, v));
  CUPID_CALL(read_constraints(rd, mr_get(&top, "constraints")));
  CUPID_CALL(read_loads(rd, mr_get(&top, "loads")));
  CUPID_CALL(read_analysis(rd, mr_get(&top, "analysis")));
  CUPID_CALL(read_output(rd, mr_get(&top, "output")));
  return mr_validate(rd, &top);
}
