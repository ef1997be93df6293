/* The Exodus II writer (io.h, cupid_writer_exodus; issue 35), through the ExodusII C library
 * (Debian's libexodusii-dev, the 6.x API) over netCDF's classic 64-bit-offset format, which
 * ParaView, meshio (with python3-netcdf4) and netCDF4 read.
 *
 * Layout: the parts' points one after another as the nodes (3D coordinates), each part an
 * element block of its own id (1, 2, ...) named after it: VTK vertices as SPHERE elements with
 * a `volume` attribute (Peridigm's and PeriLab's PD nodes), hexahedra as HEX8 (VTK and Exodus
 * number a hexahedron's corners alike). The nodal variables are the parts' point-data arrays,
 * split into components (displacement_x ..., stress_xx yy zz xy yz xz); a part without an
 * array has 0 there. Every frame is a time step (its time: t, or the load factor).
 *
 * The file is written as `.NAME.partial` beside its name and renamed at the end, so that no
 * half-written database is ever seen; a checkpoint records the time steps written, and a
 * resumption opens the partial file again and writes from the next step on (netCDF's classic
 * format places each time step at a fixed offset: the file ends byte for byte as an
 * uninterrupted run's). */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cupid_config.h"
#include "io_internal.h"

#if CUPID_HAVE_EXODUS
#include <exodusII.h>

/* The library is loaded when a model asks for model.exo (dlopen of Debian's libexodusii5), not
 * linked: through netCDF it brings HDF5 and OpenMPI, some 10 ms at every start of cupid. The
 * functions' types are exodusII.h's (the build's header). */
#define EXO_FN(name) __typeof__(name) *name
static struct {
  EXO_FN(ex_create_int);
  EXO_FN(ex_open_int);
  EXO_FN(ex_close);
  EXO_FN(ex_get_err);
  EXO_FN(ex_inquire_int);
  EXO_FN(ex_opts);
  EXO_FN(ex_put_coord);
  EXO_FN(ex_put_coord_names);
  EXO_FN(ex_put_elem_attr);
  EXO_FN(ex_put_elem_attr_names);
  EXO_FN(ex_put_elem_block);
  EXO_FN(ex_put_elem_conn);
  EXO_FN(ex_put_init);
  EXO_FN(ex_put_name);
  EXO_FN(ex_put_time);
  EXO_FN(ex_put_var);
  EXO_FN(ex_put_variable_names);
  EXO_FN(ex_put_variable_param);
  EXO_FN(ex_update);
  EXO_FN(nc_strerror);
} exo;
#undef EXO_FN
static int exo_state; /* 0: not tried, 1: loaded, -1: failed */
static char exo_why[512];

/* NULL when the library is loaded (once, kept for the process's life), else why not. */
static const char *exo_missing(void) {
  if (exo_state) return exo_state > 0 ? NULL : exo_why;
  exo_state = -1;
  const cupid_io_symbol syms[] = {
      {"ex_create_int", (void **)&exo.ex_create_int},
      {"ex_open_int", (void **)&exo.ex_open_int},
      {"ex_close", (void **)&exo.ex_close},
      {"ex_get_err", (void **)&exo.ex_get_err},
      {"ex_inquire_int", (void **)&exo.ex_inquire_int},
      {"ex_opts", (void **)&exo.ex_opts},
      {"ex_put_coord", (void **)&exo.ex_put_coord},
      {"ex_put_coord_names", (void **)&exo.ex_put_coord_names},
      {"ex_put_elem_attr", (void **)&exo.ex_put_elem_attr},
      {"ex_put_elem_attr_names", (void **)&exo.ex_put_elem_attr_names},
      {"ex_put_elem_block", (void **)&exo.ex_put_elem_block},
      {"ex_put_elem_conn", (void **)&exo.ex_put_elem_conn},
      {"ex_put_init", (void **)&exo.ex_put_init},
      {"ex_put_name", (void **)&exo.ex_put_name},
      {"ex_put_time", (void **)&exo.ex_put_time},
      {"ex_put_var", (void **)&exo.ex_put_var},
      {"ex_put_variable_names", (void **)&exo.ex_put_variable_names},
      {"ex_put_variable_param", (void **)&exo.ex_put_variable_param},
      {"ex_update", (void **)&exo.ex_update},
      {"nc_strerror", (void **)&exo.nc_strerror}}; /* netCDF's, through the library */
  if (!cupid_io_load_library("CUPID_EXODUS_LIBRARY", "libexoIIv2c.so.5", "libexoIIv2c.so", syms,
                             sizeof syms / sizeof *syms, "the Exodus II library", "libexodusii5",
                             exo_why, sizeof exo_why))
    return exo_why;
  exo_state = 1;
  return NULL;
}

enum { MAX_VARS = 64 };

typedef struct {
  int id;             /* the database (-1: not open) */
  char temp[4096], path[4096];
  int64_t frames;     /* time steps written */
  int n_vars;
  char names[MAX_VARS][MAX_STR_LENGTH + 1];
  const char *array[MAX_VARS]; /* the point-data array of each variable ... */
  int component[MAX_VARS];     /* ... and its component */
  int n_parts;
  cupid_int n_nodes;
  double *values;     /* one variable over every node */
} exo_writer;

/* The library's last message, for ours. */
static const char *exo_reason(int code) {
  const char *msg = NULL, *func = NULL;
  int err = 0;
  exo.ex_get_err(&msg, &func, &err);
  if (msg && msg[0]) return msg;
  return code < 0 ? exo.nc_strerror(code) : "the Exodus II library failed";
}

#define EXO(call, what)                                                                        \
  do {                                                                                         \
    int rc_ = (call);                                                                          \
    CUPID_CHECK(rc_ >= 0, CUPID_ERR_IO, "Exodus II: %s in %s failed: %s", what, x->temp,        \
                exo_reason(rc_));                                                              \
  } while (0)

static const char *const SUFFIX3[3] = {"_x", "_y", "_z"};
/* VTK's symmetric-tensor order (io.h: the VTU writer takes the caller's) */
static const char *const SUFFIX6[6] = {"_xx", "_yy", "_zz", "_xy", "_yz", "_xz"};

/* The variables: every array of every part, by name, in the order first seen. */
static cupid_status list_variables(exo_writer *x, const cupid_frame *f) {
  x->n_vars = 0;
  for (int p = 0; p < f->n_parts; p++) {
    const cupid_vtu_mesh *m = f->parts[p].mesh;
    for (int a = 0; a < m->n_point_data; a++) {
      const cupid_vtu_array *arr = &m->point_data[a];
      int seen = 0;
      for (int v = 0; v < x->n_vars && !seen; v++) seen = !strcmp(x->array[v], arr->name);
      if (seen) continue;
      const int nc = arr->components;
      CUPID_CHECK(nc == 1 || nc == 3 || nc == 6, CUPID_ERR_ARGUMENT,
                  "Exodus II: point data '%s' has %d components (1, 3 or 6 are written)",
                  arr->name, nc);
      CUPID_CHECK(x->n_vars + nc <= MAX_VARS, CUPID_ERR_ARGUMENT,
                  "Exodus II: more than %d nodal variables", MAX_VARS);
      for (int c = 0; c < nc; c++) {
        const char *sfx = nc == 1 ? "" : nc == 3 ? SUFFIX3[c] : SUFFIX6[c];
        int len = snprintf(x->names[x->n_vars], sizeof x->names[0], "%s%s", arr->name, sfx);
        CUPID_CHECK(len > 0 && len <= MAX_STR_LENGTH, CUPID_ERR_ARGUMENT,
                    "Exodus II: variable name '%s%s' too long", arr->name, sfx);
        x->array[x->n_vars] = arr->name;
        x->component[x->n_vars++] = c;
      }
    }
  }
  return CUPID_SUCCESS;
}

/* A part's cells: all of one type (a block has one element type). */
static cupid_status block_type(const exo_writer *x, const cupid_frame_part *part, const char **type,
                               int *per) {
  const cupid_vtu_mesh *m = part->mesh;
  const unsigned char t = m->n_cells ? m->types[0] : CUPID_VTK_VERTEX;
  for (cupid_int e = 0; e < m->n_cells; e++)
    CUPID_CHECK(m->types[e] == t, CUPID_ERR_ARGUMENT,
                "Exodus II: part '%s' of %s mixes cell types", part->name, x->path);
  if (t == CUPID_VTK_VERTEX) *type = "SPHERE", *per = 1;
  else if (t == CUPID_VTK_HEXAHEDRON) *type = "HEX8", *per = 8;
  else
    return CUPID_ERROR(CUPID_ERR_ARGUMENT, "Exodus II: part '%s' has VTK cells of type %d "
                       "(vertices and hexahedra are written)", part->name, (int)t);
  for (cupid_int e = 0; e < m->n_cells; e++)
    CUPID_CHECK(m->offsets[e] == (e + 1) * (cupid_int)*per, CUPID_ERR_ARGUMENT,
                "Exodus II: part '%s': cell %lld does not have %d points", part->name,
                (long long)e, *per);
  return CUPID_SUCCESS;
}

static cupid_status put_block(exo_writer *x, int id, const cupid_frame_part *part, int64_t first) {
  const cupid_vtu_mesh *m = part->mesh;
  const char *type = "";
  int per = 0;
  CUPID_CALL(block_type(x, part, &type, &per));
  const int sphere = per == 1;
  EXO(exo.ex_put_elem_block(x->id, id, type, m->n_cells, per, sphere ? 1 : 0), "the element block");
  EXO(exo.ex_put_name(x->id, EX_ELEM_BLOCK, id, part->name), "the block's name");
  if (m->n_cells == 0) return CUPID_SUCCESS;
  int64_t *conn = NULL;
  const size_t nc = (size_t)m->n_cells * (size_t)per;
  CUPID_CALL(cupid_malloc(nc, sizeof *conn, "Exodus connectivity", &conn));
  for (size_t k = 0; k < nc; k++) conn[k] = first + m->connectivity[k] + 1; /* 1-based */
  int rc = exo.ex_put_elem_conn(x->id, id, conn);
  cupid_free(&conn);
  EXO(rc, "the connectivity");
  if (!sphere) return CUPID_SUCCESS;
  char *names[1] = {"volume"};
  EXO(exo.ex_put_elem_attr_names(x->id, id, names), "the attribute's name");
  double *vol = NULL;
  CUPID_CALL(cupid_malloc((size_t)m->n_cells, sizeof *vol, "Exodus volumes", &vol));
  for (cupid_int e = 0; e < m->n_cells; e++) vol[e] = part->cell_volume ? part->cell_volume[e] : 0.0;
  rc = exo.ex_put_elem_attr(x->id, id, vol);
  cupid_free(&vol);
  EXO(rc, "the volumes");
  return CUPID_SUCCESS;
}

/* The database, from the first frame: nodes, blocks, variable names. */
static cupid_status define(cupid_writer w, exo_writer *x, const cupid_frame *f) {
  x->n_parts = f->n_parts;
  cupid_int n = 0, ne = 0;
  for (int p = 0; p < f->n_parts; p++) n += f->parts[p].mesh->n_points, ne += f->parts[p].mesh->n_cells;
  CUPID_CHECK(n < 2147483647 && ne < 2147483647, CUPID_ERR_ARGUMENT,
              "Exodus II: %lld nodes, %lld elements: the classic format holds 32-bit ids",
              (long long)n, (long long)ne);
  x->n_nodes = n;
  CUPID_CALL(list_variables(x, f));
  int cpu = 8, io = 8;
  x->id = exo.ex_create_int(x->temp, EX_CLOBBER | EX_LARGE_MODEL | EX_ALL_INT64_API, &cpu, &io,
                           EX_API_VERS_NODOT);
  CUPID_CHECK(x->id >= 0, CUPID_ERR_IO, "Exodus II: cannot create %s: %s", x->temp,
              exo_reason(x->id));
  char title[MAX_LINE_LENGTH + 1];
  snprintf(title, sizeof title, "%s", w->title[0] ? w->title : "cupid");
  EXO(exo.ex_put_init(x->id, title, 3, n, ne, f->n_parts, 0, 0), "the header");
  double *xyz = NULL;
  CUPID_CALL(cupid_calloc(3 * (size_t)n + 1, sizeof *xyz, "Exodus coordinates", &xyz));
  cupid_int at = 0;
  for (int p = 0; p < f->n_parts; p++) {
    const cupid_vtu_mesh *m = f->parts[p].mesh;
    for (cupid_int i = 0; i < m->n_points; i++, at++)
      for (int c = 0; c < 3; c++) xyz[(size_t)c * (size_t)n + (size_t)at] = m->points[3 * i + c];
  }
  int rc = exo.ex_put_coord(x->id, xyz, xyz + n, xyz + 2 * (size_t)n);
  cupid_free(&xyz);
  EXO(rc, "the coordinates");
  char *coord[3] = {"x", "y", "z"};
  EXO(exo.ex_put_coord_names(x->id, coord), "the coordinates' names");
  int64_t first = 0;
  for (int p = 0; p < f->n_parts; p++) {
    CUPID_CALL(put_block(x, p + 1, &f->parts[p], first));
    first += f->parts[p].mesh->n_points;
  }
  if (x->n_vars) {
    char *names[MAX_VARS];
    for (int v = 0; v < x->n_vars; v++) names[v] = x->names[v];
    EXO(exo.ex_put_variable_param(x->id, EX_NODAL, x->n_vars), "the variables");
    EXO(exo.ex_put_variable_names(x->id, EX_NODAL, x->n_vars, names), "the variables' names");
  }
  return CUPID_SUCCESS;
}

/* The values of variable v over every node (0 on a part without its array). */
static void gather(exo_writer *x, const cupid_frame *f, int v) {
  cupid_int at = 0;
  for (int p = 0; p < f->n_parts; p++) {
    const cupid_vtu_mesh *m = f->parts[p].mesh;
    const cupid_vtu_array *arr = NULL;
    for (int a = 0; a < m->n_point_data && !arr; a++)
      if (!strcmp(m->point_data[a].name, x->array[v])) arr = &m->point_data[a];
    const int nc = arr ? arr->components : 0, c = x->component[v];
    for (cupid_int i = 0; i < m->n_points; i++, at++)
      x->values[at] = arr && arr->values ? arr->values[(size_t)nc * (size_t)i + (size_t)c] : 0.0;
  }
}

/* A frame must have the first one's parts and points (the nodes are written once). */
static cupid_status same_layout(const exo_writer *x, const cupid_frame *f) {
  cupid_int n = 0;
  for (int p = 0; p < f->n_parts; p++) n += f->parts[p].mesh->n_points;
  CUPID_CHECK(f->n_parts == x->n_parts && n == x->n_nodes, CUPID_ERR_ARGUMENT,
              "Exodus II: frame %lld of %s has %d parts and %lld points, the first had %d and %lld",
              (long long)f->step, x->path, f->n_parts, (long long)n, x->n_parts,
              (long long)x->n_nodes);
  return CUPID_SUCCESS;
}

static cupid_status exo_step(cupid_writer w, const cupid_frame *f) {
  exo_writer *x = w->data;
  if (x->id < 0) CUPID_CALL(define(w, x, f));
  else if (!x->n_vars && x->frames > 0) CUPID_CALL(list_variables(x, f)); /* a resumption's */
  CUPID_CALL(same_layout(x, f));
  if (!x->values)
    CUPID_CALL(cupid_malloc((size_t)x->n_nodes + 1, sizeof *x->values, "Exodus values", &x->values));
  const int step = (int)(x->frames + 1);
  EXO(exo.ex_put_time(x->id, step, &f->time), "the time");
  for (int v = 0; v < x->n_vars; v++) {
    gather(x, f, v);
    EXO(exo.ex_put_var(x->id, step, EX_NODAL, v + 1, 1, x->n_nodes, x->values), "a nodal variable");
  }
  x->frames++;
  return CUPID_SUCCESS;
}

/* What is written reaches the disk (netCDF's sync, then the file's data), then the count. */
static cupid_status exo_save(cupid_writer w, cupid_checkpoint_writer ckw) {
  exo_writer *x = w->data;
  if (x->id >= 0) {
    EXO(exo.ex_update(x->id), "the sync");
    int fd = open(x->temp, O_RDONLY);
    const int synced = fd >= 0 && fdatasync(fd) == 0;
    const int err = errno;
    if (fd >= 0) close(fd);
    CUPID_CHECK(synced, CUPID_ERR_IO, "cannot sync %s: %s", x->temp, strerror(err));
  }
  return cupid_checkpoint_write(ckw, w->key, &x->frames, sizeof x->frames);
}

static cupid_status exo_end(cupid_writer w) {
  exo_writer *x = w->data;
  if (x->id < 0) return CUPID_SUCCESS; /* no frame: no database */
  int rc = exo.ex_close(x->id);
  x->id = -1;
  CUPID_CHECK(rc >= 0, CUPID_ERR_IO, "Exodus II: closing %s failed: %s", x->temp, exo_reason(rc));
  CUPID_CHECK(rename(x->temp, x->path) == 0, CUPID_ERR_IO, "cannot rename %s to %s: %s", x->temp,
              x->path, strerror(errno));
  return CUPID_SUCCESS;
}

static void exo_drop(cupid_writer w, int keep) {
  exo_writer *x = w->data;
  if (!x) return;
  if (x->id >= 0) exo.ex_close(x->id);
  if (!keep && x->temp[0]) unlink(x->temp);
  cupid_free(&x->values);
  cupid_free(&x);
  w->data = NULL;
}

/* A resumption: the partial database as the checkpoint left it, reopened for writing; the
 * variables are listed again from the next frame (the same arrays, in the same order). */
static cupid_status exo_reopen(cupid_writer w, exo_writer *x, cupid_checkpoint ck) {
  CUPID_CALL(cupid_checkpoint_read(ck, w->key, &x->frames, sizeof x->frames));
  if (x->frames == 0) return CUPID_SUCCESS;
  int cpu = 8, io = 0;
  float version = 0;
  x->id = exo.ex_open_int(x->temp, EX_WRITE | EX_ALL_INT64_API, &cpu, &io, &version,
                         EX_API_VERS_NODOT);
  CUPID_CHECK(x->id >= 0, CUPID_ERR_IO, "Exodus II: cannot reopen %s to resume: %s", x->temp,
              exo_reason(x->id));
  int64_t nodes = exo.ex_inquire_int(x->id, EX_INQ_NODES), blocks = exo.ex_inquire_int(x->id, EX_INQ_ELEM_BLK);
  x->n_nodes = (cupid_int)nodes;
  x->n_parts = (int)blocks;
  return CUPID_SUCCESS;
}

static cupid_status exo_create(cupid_writer w, const cupid_writer_spec *spec) {
  exo_writer *x = NULL;
  CUPID_CALL(cupid_calloc(1, sizeof *x, "Exodus writer", &x));
  w->data = x;
  x->id = -1;
  CUPID_CALL(cupid_writer_path(w, NULL, x->path, sizeof x->path));
  char name[4096];
  int len = snprintf(name, sizeof name, ".%s.partial", w->file);
  CUPID_CHECK(len > 0 && (size_t)len < sizeof name, CUPID_ERR_IO, "output name too long");
  CUPID_CALL(cupid_writer_path(w, name, x->temp, sizeof x->temp));
  exo.ex_opts(EX_DEFAULT); /* quiet: the messages are ours */
  return spec->resume ? exo_reopen(w, x, spec->resume) : CUPID_SUCCESS;
}

const cupid_writer_type cupid_writer_exodus = {"exodus", exo_missing, exo_create, exo_step,
                                               exo_save, exo_end, exo_drop};

#else /* no exodusII.h at build time: the type is listed, and refused by cupid_writer_create */

static const char *exo_missing(void) {
  return "this cupid was built without Exodus II (Debian's libexodusii-dev: "
         "scripts/install-deps.sh installs it; then build again)";
}

const cupid_writer_type cupid_writer_exodus = {"exodus", exo_missing, NULL, NULL, NULL, NULL, NULL};

#endif
