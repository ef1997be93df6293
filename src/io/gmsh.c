/* Gmsh's C API (Debian's libgmsh4.8; issue 35): a beam section's 2D mesh from a .msh file, or
 * from a .geo (or CAD) file that Gmsh meshes. The library is loaded when a model names such a
 * file (dlopen), not linked: it brings some 90 shared libraries (OpenCASCADE, FLTK, ...) that
 * would add ~50 ms to every start of cupid, and a build without it still builds and runs.
 * The functions' types are those of gmshc.h in Gmsh 4.8 (the version Debian 12 ships). */
#include <errno.h>
#include <stdlib.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "cupid/model.h"
#include "io_internal.h"

typedef struct {
  void (*initialize)(int, char **, const int, int *);
  void (*clear)(int *);
  void (*open)(const char *, int *);
  void (*option_set_number)(const char *, const double, int *);
  void (*logger_start)(int *);
  void (*logger_get_last_error)(char **, int *);
  void (*mesh_generate)(const int, int *);
  void (*mesh_set_order)(const int, int *);
  void (*get_entities)(int **, size_t *, const int, int *);
  void (*get_physical_groups)(int **, size_t *, const int, int *);
  void (*get_physical_name)(const int, const int, char **, int *);
  void (*get_entities_for_physical_group)(const int, const int, int **, size_t *, int *);
  void (*get_nodes)(size_t **, size_t *, double **, size_t *, double **, size_t *, const int,
                    const int, const int, const int, int *);
  void (*get_elements)(int **, size_t *, size_t ***, size_t **, size_t *, size_t ***, size_t **,
                       size_t *, const int, const int, int *);
  void (*get_element_properties)(const int, char **, int *, int *, int *, double **, size_t *,
                                 int *, int *);
  void (*free)(void *);
  void (*get_boundary)(const int *, size_t, int **, size_t *, const int, const int, const int,
                       int *);
} gmsh_api;

static gmsh_api api;
static int api_state; /* 0: not tried, 1: loaded and initialised, -1: failed */
static char api_why[512];

/* Loaded once and kept for the process's life. Gmsh's state is global: models are read by one
 * thread at a time (the model reader's callers: the command line, a Problem). */
static int load_api(void) {
  if (api_state) return api_state > 0;
  api_state = -1;
  const cupid_io_symbol syms[] = {
      {"gmshInitialize", (void **)&api.initialize},
      {"gmshClear", (void **)&api.clear},
      {"gmshOpen", (void **)&api.open},
      {"gmshOptionSetNumber", (void **)&api.option_set_number},
      {"gmshLoggerStart", (void **)&api.logger_start},
      {"gmshLoggerGetLastError", (void **)&api.logger_get_last_error},
      {"gmshModelMeshGenerate", (void **)&api.mesh_generate},
      {"gmshModelMeshSetOrder", (void **)&api.mesh_set_order},
      {"gmshModelGetEntities", (void **)&api.get_entities},
      {"gmshModelGetPhysicalGroups", (void **)&api.get_physical_groups},
      {"gmshModelGetPhysicalName", (void **)&api.get_physical_name},
      {"gmshModelGetEntitiesForPhysicalGroup", (void **)&api.get_entities_for_physical_group},
      {"gmshModelMeshGetNodes", (void **)&api.get_nodes},
      {"gmshModelMeshGetElements", (void **)&api.get_elements},
      {"gmshModelMeshGetElementProperties", (void **)&api.get_element_properties},
      {"gmshFree", (void **)&api.free},
      {"gmshModelGetBoundary", (void **)&api.get_boundary}};
  if (!cupid_io_load_library("CUPID_GMSH_LIBRARY", "libgmsh.so.4.8", "libgmsh.so", syms,
                             sizeof syms / sizeof *syms, "Gmsh's library", "libgmsh4.8", api_why,
                             sizeof api_why))
    return 0;
  int ierr = 0;
  api.initialize(0, NULL, 0, &ierr);
  if (!ierr) api.option_set_number("General.Terminal", 0, &ierr); /* quiet: messages are ours */
  if (!ierr) api.option_set_number("General.Verbosity", 1, &ierr);
  if (!ierr) api.option_set_number("Mesh.SecondOrderIncomplete", 0, &ierr); /* 9-node quads */
  if (!ierr) api.logger_start(&ierr);
  if (ierr) {
    snprintf(api_why, sizeof api_why, "Gmsh did not start (error %d)", ierr);
    return 0;
  }
  api_state = 1;
  return 1;
}

int cupid_gmsh_available(void) { return load_api(); }

/* Gmsh's last error message, or a generic one. */
static void gmsh_reason(char *why, size_t size, const char *what) {
  char *msg = NULL;
  int ierr = 0;
  api.logger_get_last_error(&msg, &ierr);
  snprintf(why, size, "%s%s%s", what, msg && msg[0] ? ": " : "", msg && msg[0] ? msg : "");
  if (msg) api.free(msg);
}

static cupid_status fail(char *why, size_t size, cupid_status code, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static cupid_status fail(char *why, size_t size, cupid_status code, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(why, size, fmt, ap);
  va_end(ap);
  return code;
}

void cupid_gmsh_section_free(cupid_gmsh_section *s) {
  cupid_free(&s->xz);
  cupid_free(&s->conn);
  cupid_free(&s->group);
  for (int k = 0; k < s->n_groups; k++) cupid_free(&s->groups[k]);
  cupid_free(&s->groups);
  memset(s, 0, sizeof *s);
}

/* The local node of a Gmsh element type at each of cupid's node positions (model.h's
 * cupid_le_node_grid), and the same for the element's mirror image (u and v swapped), which
 * turns a clockwise element counter-clockwise. */
static cupid_status node_maps(int type, int npe, int map[16], int mirror[16], char *why,
                              size_t size) {
  char *name = NULL;
  double *local = NULL;
  size_t n_local = 0;
  int dim = 0, order = 0, nodes = 0, primary = 0, ierr = 0;
  api.get_element_properties(type, &name, &dim, &order, &nodes, &local, &n_local, &primary, &ierr);
  cupid_status st = CUPID_SUCCESS;
  if (ierr) st = fail(why, size, CUPID_ERR_MODEL, "Gmsh knows no element type %d", type);
  else if (strncmp(name, "Quadrilateral", 13) != 0)
    st = fail(why, size, CUPID_ERR_MODEL, "the mesh has %s elements: a section mesh must be "
              "quadrilaterals (in Gmsh: Recombine Surface{...}; or Mesh.RecombineAll = 1)", name);
  else if (nodes != npe)
    st = fail(why, size, CUPID_ERR_MODEL, "the mesh's quadrilaterals have %d nodes, element: L%d "
              "needs %d", nodes, npe, npe);
  const int n = npe == 4 ? 2 : npe == 9 ? 3 : 4;
  for (int k = 0; k < npe && st == CUPID_SUCCESS; k++) {
    int a, b;
    cupid_le_node_grid(npe, k, &a, &b);
    const double r = -1.0 + 2.0 * a / (n - 1), s = -1.0 + 2.0 * b / (n - 1);
    map[k] = mirror[k] = -1;
    for (int j = 0; j < nodes; j++) {
      const double *uv = local + (size_t)j * n_local / (size_t)nodes; /* u, v (, w) */
      const double u = uv[0], v = uv[1];
      if (fabs(u - r) < 1e-9 && fabs(v - s) < 1e-9) map[k] = j;
      if (fabs(v - r) < 1e-9 && fabs(u - s) < 1e-9) mirror[k] = j;
    }
    if (map[k] < 0 || mirror[k] < 0)
      st = fail(why, size, CUPID_ERR_INTERNAL, "Gmsh's %s has no node at (%g, %g)", name, r, s);
  }
  api.free(name);
  api.free(local);
  return st;
}

/* The mesh's nodes, each once (Gmsh gives a node on a curve shared by two surfaces with each),
 * in increasing order of Gmsh's tags (which are not contiguous): node k is sorted[k]. */
typedef struct {
  size_t n;
  size_t *sorted; /* the tags */
  double *xyz;    /* 3 per node */
} node_table;

static void node_table_free(node_table *t) {
  cupid_free(&t->sorted);
  cupid_free(&t->xyz);
  memset(t, 0, sizeof *t);
}

static _Thread_local const size_t *sort_tags;
static int by_tag(const void *a, const void *b) {
  size_t x = sort_tags[*(const size_t *)a], y = sort_tags[*(const size_t *)b];
  return (x > y) - (x < y);
}

/* The nodes of the entities of dimension @p dim (-1: all) with their boundaries'. */
static cupid_status node_table_read(int dim, node_table *t) {
  size_t *tags = NULL, n = 0, n_coord = 0, n_param = 0, *order = NULL;
  double *coord = NULL, *param = NULL;
  int ierr = 0;
  memset(t, 0, sizeof *t);
  api.get_nodes(&tags, &n, &coord, &n_coord, &param, &n_param, dim, -1, 1, 0, &ierr);
  if (param) api.free(param);
  cupid_status st = ierr ? CUPID_ERROR(CUPID_ERR_IO, "Gmsh could not list the mesh's nodes")
                         : CUPID_SUCCESS;
  if (st == CUPID_SUCCESS) st = cupid_malloc(n + 1, sizeof *order, "node order", &order);
  if (st == CUPID_SUCCESS) st = cupid_malloc(n + 1, sizeof *t->sorted, "node tags", &t->sorted);
  if (st == CUPID_SUCCESS)
    st = cupid_malloc(3 * n + 1, sizeof *t->xyz, "node coordinates", &t->xyz);
  if (st == CUPID_SUCCESS) {
    for (size_t i = 0; i < n; i++) order[i] = i;
    sort_tags = tags;
    qsort(order, n, sizeof *order, by_tag);
    sort_tags = NULL;
    for (size_t i = 0; i < n; i++) {
      const size_t tag = tags[order[i]];
      if (t->n > 0 && t->sorted[t->n - 1] == tag) continue; /* the same node again */
      t->sorted[t->n] = tag;
      memcpy(t->xyz + 3 * t->n, coord + 3 * order[i], 3 * sizeof *coord);
      t->n++;
    }
  }
  if (tags) api.free(tags);
  if (coord) api.free(coord);
  cupid_free(&order);
  return st;
}

/* The node of tag @p tag, or -1. */
static cupid_int node_table_find(const node_table *t, size_t tag) {
  size_t lo = 0, hi = t->n;
  while (lo < hi) {
    size_t mid = lo + (hi - lo) / 2;
    if (t->sorted[mid] == tag) return (cupid_int)mid;
    if (t->sorted[mid] < tag) lo = mid + 1;
    else hi = mid;
  }
  return -1;
}

/* Open @p path in Gmsh (the system's reason first where it cannot be opened: Gmsh's is vaguer;
 * Gmsh is not loaded then) and mesh its surfaces where it has no mesh (a .geo, a CAD file):
 * elements of at most @p max_size (0: Gmsh's default), @p per_turn where a surface curves (0:
 * not from the curvature). */
static cupid_status open_meshed(const char *path, double max_size, double per_turn, char *why,
                                size_t size) {
  FILE *probe = fopen(path, "rb");
  if (!probe) return fail(why, size, CUPID_ERR_IO, "cannot open it: %s", strerror(errno));
  fclose(probe);
  if (!load_api()) return fail(why, size, CUPID_ERR_UNSUPPORTED, "%s", api_why);
  int ierr = 0;
  api.clear(&ierr);
  api.option_set_number("Mesh.MeshSizeMax", max_size > 0 ? max_size : 1e22, &ierr);
  api.option_set_number("Mesh.MeshSizeFromCurvature", per_turn, &ierr);
  api.open(path, &ierr);
  if (ierr) {
    gmsh_reason(why, size, "Gmsh cannot read the file");
    return CUPID_ERR_IO;
  }
  size_t *tags = NULL, n = 0, n_coord = 0, n_param = 0;
  double *coord = NULL, *param = NULL;
  api.get_nodes(&tags, &n, &coord, &n_coord, &param, &n_param, 2, -1, 1, 0, &ierr);
  if (tags) api.free(tags);
  if (coord) api.free(coord);
  if (param) api.free(param);
  if (!ierr && n > 0) return CUPID_SUCCESS;
  api.mesh_generate(2, &ierr);
  if (!ierr) return CUPID_SUCCESS;
  gmsh_reason(why, size, "Gmsh could not mesh the surfaces");
  return CUPID_ERR_MODEL;
}

/* The physical group (2D) of each surface entity: group[k] for entity tag ents[k], -1 none. */
static cupid_status entity_groups(cupid_gmsh_section *s, const int *ents, size_t n_ents,
                                  int *group, char *why, size_t size) {
  int *pg = NULL, ierr = 0;
  size_t n_pg = 0;
  for (size_t k = 0; k < n_ents; k++) group[k] = -1;
  api.get_physical_groups(&pg, &n_pg, 2, &ierr);
  if (ierr) return fail(why, size, CUPID_ERR_IO, "Gmsh could not list the physical groups");
  cupid_status st = CUPID_SUCCESS;
  s->n_groups = (int)(n_pg / 2);
  if (s->n_groups)
    st = cupid_calloc((size_t)s->n_groups, sizeof *s->groups, "group names", &s->groups);
  for (int g = 0; g < s->n_groups && st == CUPID_SUCCESS; g++) {
    char *name = NULL;
    api.get_physical_name(2, pg[2 * g + 1], &name, &ierr);
    char number[32];
    snprintf(number, sizeof number, "%d", pg[2 * g + 1]); /* an unnamed group: its number */
    st = cupid_strdup(name && name[0] ? name : number, &s->groups[g]);
    if (name) api.free(name);
    int *tags = NULL;
    size_t n_tags = 0;
    api.get_entities_for_physical_group(2, pg[2 * g + 1], &tags, &n_tags, &ierr);
    for (size_t t = 0; t < n_tags; t++)
      for (size_t k = 0; k < n_ents; k++)
        if (ents[k] == tags[t] && group[k] < 0) group[k] = g;
    if (tags) api.free(tags);
  }
  if (pg) api.free(pg);
  return st;
}

/* The elements of one surface entity, by type (gmshModelMeshGetElements). */
typedef struct {
  int *types;
  size_t n_types, **etags, *etags_n, etags_nn, **ntags, *ntags_n, ntags_nn;
} entity_elements;

static void entity_elements_free(entity_elements *el) {
  for (size_t t = 0; t < el->n_types; t++) {
    if (el->etags) api.free(el->etags[t]);
    if (el->ntags) api.free(el->ntags[t]);
  }
  if (el->types) api.free(el->types);
  if (el->etags) api.free(el->etags);
  if (el->etags_n) api.free(el->etags_n);
  if (el->ntags) api.free(el->ntags);
  if (el->ntags_n) api.free(el->ntags_n);
}

static cupid_status entity_elements_read(int entity, entity_elements *el, char *why, size_t size) {
  int ierr = 0;
  memset(el, 0, sizeof *el);
  api.get_elements(&el->types, &el->n_types, &el->etags, &el->etags_n, &el->etags_nn, &el->ntags,
                   &el->ntags_n, &el->ntags_nn, 2, entity, &ierr);
  return ierr ? fail(why, size, CUPID_ERR_IO, "Gmsh could not list the elements of surface %d",
                     entity) : CUPID_SUCCESS;
}

/* The elements of one surface entity, appended (their nodes in cupid's order). */
static cupid_status add_elements(cupid_gmsh_section *s, int entity, int group, int npe,
                                 const node_table *nodes, char *why, size_t size) {
  entity_elements el;
  cupid_status st = entity_elements_read(entity, &el, why, size);
  int *types = el.types;
  size_t n_types = el.n_types, **etags = el.etags, *etags_n = el.etags_n, **ntags = el.ntags;
  for (size_t t = 0; t < n_types && st == CUPID_SUCCESS; t++) {
    int map[16], mirror[16];
    st = node_maps(types[t], npe, map, mirror, why, size);
    const size_t ne = etags_n[t];
    const size_t total = (size_t)s->n_elements + ne;
    if (st == CUPID_SUCCESS)
      st = cupid_realloc(total * (size_t)npe, sizeof *s->conn, "section elements", &s->conn);
    if (st == CUPID_SUCCESS)
      st = cupid_realloc(total + 1, sizeof *s->group, "section element groups", &s->group);
    for (size_t e = 0; e < ne && st == CUPID_SUCCESS; e++) {
      const size_t *nt = ntags[t] + e * (size_t)npe;
      int *c = s->conn + (size_t)s->n_elements * (size_t)npe;
      for (int k = 0; k < npe && st == CUPID_SUCCESS; k++) {
        cupid_int i = node_table_find(nodes, nt[map[k]]);
        if (i < 0)
          st = fail(why, size, CUPID_ERR_IO, "element %zu refers to node %zu, which the mesh "
                    "does not have", etags[t][e], nt[map[k]]);
        c[k] = (int)i;
      }
      /* a clockwise element (its corners' signed area < 0 in x, z): its mirror image's order */
      double area = 0.0;
      int corner[4] = {0, 0, 0, 0}, nc = 0;
      for (int k = 0; k < npe && nc < 4; k++) {
        int a, b;
        cupid_le_node_grid(npe, k, &a, &b);
        const int last = npe == 4 ? 1 : npe == 9 ? 2 : 3;
        if ((a == 0 || a == last) && (b == 0 || b == last)) corner[nc++] = c[k];
      }
      for (int k = 0; k < 4; k++) {
        const double *p = s->xz + 2 * corner[k], *q = s->xz + 2 * corner[(k + 1) % 4];
        area += p[0] * q[1] - q[0] * p[1];
      }
      if (area < 0)
        for (int k = 0; k < npe && st == CUPID_SUCCESS; k++)
          c[k] = (int)node_table_find(nodes, nt[mirror[k]]);
      s->group[s->n_elements++] = group;
    }
  }
  entity_elements_free(&el);
  return st;
}

cupid_status cupid_gmsh_read_section(const char *path, int npe, cupid_gmsh_section *s, char *why,
                                     size_t size) {
  memset(s, 0, sizeof *s);
  why[0] = '\0';
  int *ents = NULL, *group = NULL, ierr = 0;
  size_t n_ents = 0;
  node_table nodes = {0};
  cupid_status st = open_meshed(path, 0.0, 0.0, why, size);
  if (st != CUPID_SUCCESS) return st;
  /* the elements' order of `element:`, their new nodes on the geometry */
  api.mesh_set_order(npe == 4 ? 1 : npe == 9 ? 2 : 3, &ierr);
  if (ierr) {
    gmsh_reason(why, size, "Gmsh could not make the elements' order");
    st = CUPID_ERR_MODEL;
    goto cleanup;
  }
  CUPID_TRY(node_table_read(2, &nodes)); /* the surfaces' nodes alone: no stray points */
  const cupid_int n = (cupid_int)nodes.n;
  if (n == 0) {
    st = fail(why, size, CUPID_ERR_MODEL, "the file has no surface mesh");
    goto cleanup;
  }
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *s->xz * 2, "section nodes", &s->xz));
  double zmax = 0.0, span = 0.0;
  const double *xyz = nodes.xyz;
  for (cupid_int i = 0; i < n; i++) {
    s->xz[2 * i] = xyz[3 * i], s->xz[2 * i + 1] = xyz[3 * i + 1]; /* Gmsh x, y: section x, z */
    zmax = fmax(zmax, fabs(xyz[3 * i + 2]));
    span = fmax(span, fmax(fabs(xyz[3 * i] - xyz[0]), fabs(xyz[3 * i + 1] - xyz[1])));
  }
  if (zmax > 1e-9 * (span > 0 ? span : 1.0)) {
    st = fail(why, size, CUPID_ERR_MODEL, "the mesh is not in Gmsh's xy plane (z up to %g): a "
              "section's x and z are Gmsh's x and y", zmax);
    goto cleanup;
  }
  s->n_nodes = n;
  s->npe = npe;
  api.get_entities(&ents, &n_ents, 2, &ierr);
  if (ierr) {
    st = fail(why, size, CUPID_ERR_IO, "Gmsh could not list the surfaces");
    goto cleanup;
  }
  n_ents /= 2; /* (dim, tag) pairs */
  for (size_t k = 0; k < n_ents; k++) ents[k] = ents[2 * k + 1];
  CUPID_TRY(cupid_malloc(n_ents + 1, sizeof *group, "surface groups", &group));
  CUPID_TRY(entity_groups(s, ents, n_ents, group, why, size));
  for (size_t k = 0; k < n_ents; k++)
    CUPID_TRY(add_elements(s, ents[k], group[k], npe, &nodes, why, size));
  if (s->n_elements == 0) st = fail(why, size, CUPID_ERR_MODEL, "the file has no quadrilaterals");
cleanup:
  if (st != CUPID_SUCCESS && why[0] == '\0') snprintf(why, size, "%s", cupid_error_message());
  if (ents) api.free(ents);
  node_table_free(&nodes);
  cupid_free(&group);
  if (st != CUPID_SUCCESS) cupid_gmsh_section_free(s);
  int e2 = 0;
  api.clear(&e2);
  return st;
}

/* The triangles of surface entity `entity` (quadrilaterals split in two) appended to *tri, node
 * tags mapped to indices. */
static cupid_status add_triangles(int entity, const node_table *nodes, int64_t **tri,
                                  int64_t *n_tri, int64_t *cap, char *why, size_t size) {
  entity_elements el;
  int ierr = 0;
  cupid_status st = entity_elements_read(entity, &el, why, size);
  int *types = el.types;
  size_t n_types = el.n_types, *etags_n = el.etags_n, **ntags = el.ntags;
  for (size_t t = 0; t < n_types && st == CUPID_SUCCESS; t++) {
    char *name = NULL;
    double *local = NULL;
    size_t n_local = 0;
    int dim = 0, order = 0, per = 0, primary = 0;
    api.get_element_properties(types[t], &name, &dim, &order, &per, &local, &n_local, &primary,
                               &ierr);
    const int quad = primary == 4;
    if (ierr || !(primary == 3 || primary == 4))
      st = fail(why, size, CUPID_ERR_MODEL, "the surface mesh has %s elements (triangles and "
                "quadrilaterals bound a volume)", name ? name : "unknown");
    if (name) api.free(name);
    if (local) api.free(local);
    const size_t ne = etags_n[t];
    for (size_t e = 0; e < ne && st == CUPID_SUCCESS; e++) {
      const size_t *nt = ntags[t] + e * (size_t)per; /* the corners come first */
      int64_t c[4];
      for (int k = 0; k < primary; k++) {
        c[k] = node_table_find(nodes, nt[k]);
        if (c[k] < 0)
          st = fail(why, size, CUPID_ERR_IO, "an element refers to node %zu, which the mesh "
                    "does not have", nt[k]);
      }
      for (int h = 0; h < (quad ? 2 : 1) && st == CUPID_SUCCESS; h++) {
        if (*n_tri == *cap) {
          *cap = *cap ? 2 * *cap : 1024;
          st = cupid_realloc(3 * (size_t)*cap, sizeof **tri, "surface triangles", tri);
          if (st != CUPID_SUCCESS) break;
        }
        int64_t *o = *tri + 3 * *n_tri;
        o[0] = c[0], o[1] = c[h ? 2 : 1], o[2] = c[h ? 3 : 2];
        (*n_tri)++;
      }
    }
  }
  entity_elements_free(&el);
  return st;
}

cupid_status cupid_gmsh_read_surface(const char *path, double size, cupid_surface *surface,
                                     char *why, size_t why_size) {
  *surface = NULL;
  why[0] = '\0';
  int ierr = 0, *vols = NULL, *bnd = NULL;
  size_t n_vols = 0, n_bnd = 0;
  node_table nodes = {0};
  int64_t *tri = NULL, n_tri = 0, cap = 0, open_edges = 0;
  cupid_status st = CUPID_SUCCESS;
  /* The facets' distance to a curved surface decides which cells near it are in: at most about
   * 1% of a spacing. Flat faces need no small elements: ten spacings at most; a face curving
   * with radius R takes elements of 2 pi R / 256 (a chord 7.5e-5 R from the arc) */
  CUPID_TRY(open_meshed(path, 10 * size, 256, why, why_size));
  /* the surfaces that bound the volumes (a file of surfaces alone: all of them) */
  api.get_entities(&vols, &n_vols, 3, &ierr);
  if (n_vols) api.get_boundary(vols, n_vols, &bnd, &n_bnd, 1, 0, 0, &ierr); /* of their union */
  else api.get_entities(&bnd, &n_bnd, 2, &ierr);
  if (ierr || n_bnd == 0) {
    st = fail(why, why_size, CUPID_ERR_MODEL, "the file has no volume or surface");
    goto cleanup;
  }
  CUPID_TRY(node_table_read(-1, &nodes));
  for (size_t k = 0; k < n_bnd / 2; k++) /* (dim, tag) pairs; a tag's sign is its orientation */
    CUPID_TRY(add_triangles(abs(bnd[2 * k + 1]), &nodes, &tri, &n_tri, &cap, why, why_size));
  if (n_tri == 0) {
    st = fail(why, why_size, CUPID_ERR_MODEL, "the file's surfaces have no mesh");
    goto cleanup;
  }
  CUPID_TRY(cupid_surface_create(nodes.xyz, (int64_t)nodes.n, tri, n_tri, surface, &open_edges));
  if (open_edges) {
    cupid_surface_destroy(surface);
    st = fail(why, why_size, CUPID_ERR_MODEL, "the surface is not closed (%lld edges of its "
              "%lld triangles are not shared by two): no volume to fill",
              (long long)open_edges, (long long)n_tri);
  }
cleanup:
  if (st != CUPID_SUCCESS && why[0] == '\0') snprintf(why, why_size, "%s", cupid_error_message());
  if (vols) api.free(vols);
  if (bnd) api.free(bnd);
  node_table_free(&nodes);
  cupid_free(&tri);
  if (api_state > 0) {
    int e2 = 0;
    api.clear(&e2);
  }
  return st;
}
