/* Helpers shared by the files of src/io (not part of the public API). */
#ifndef CUPID_IO_INTERNAL_H
#define CUPID_IO_INTERNAL_H

#include <stdio.h>
#include <sys/types.h>

/** Shortest of "%.15g" / "%.17g" that reads back to exactly @p v (finite v); buf >= 32 bytes. */
void cupid_io_format_double(double v, char *buf, size_t size);

/** Write @p s to @p out with the five XML special characters escaped (attribute-safe). */
void cupid_io_xml_escape(FILE *out, const char *s);

/**
 * A file written by a helper process (gnuplot's PNG, written straight to its final name): while
 * @p child runs, a signal handler calling cupid_atomic_cleanup_all() kills and reaps the child,
 * then unlinks @p path, so an interrupted run leaves no half-written file. Returns a slot for
 * cupid_io_helper_end() (-1 if none is free: the file is then not protected).
 */
int cupid_io_helper_begin(const char *path, pid_t child);
/** The helper of @p slot (registered with child 0 before it was started, so that a signal in
 *  between already removes its file) is now running as @p child. */
void cupid_io_helper_set_child(int slot, pid_t child);
/** The helper has exited: forget it (the file is complete or already removed). */
void cupid_io_helper_end(int slot);

/**
 * An output set being written (output_set.c): cupid_atomic_cleanup_all() removes its staging
 * folder with the files in it and its lock file, so that an interrupted run leaves neither.
 * Returns a slot for cupid_io_set_unregister() (-1 if none is free: then the next run into the
 * folder removes what is left, as for a run that was killed).
 */
int cupid_io_set_register(const char *staging, const char *lock);
void cupid_io_set_unregister(int slot);

/* ---- Output writers (writer.c): the table behind cupid_writer_type (io.h) ---- */
#include "cupid/io.h"

struct cupid_writer_type {
  const char *name;
  /* NULL: always available; else why the type cannot write now (its library missing from the
   * build or the system), or NULL when it can */
  const char *(*missing)(void);
  cupid_status (*create)(cupid_writer w, const cupid_writer_spec *spec);
  cupid_status (*step)(cupid_writer w, const cupid_frame *frame);
  cupid_status (*save)(cupid_writer w, cupid_checkpoint_writer ckw);
  cupid_status (*end)(cupid_writer w);
  void (*drop)(cupid_writer w, int keep); /* frees w->data */
};

struct cupid_writer_private {
  const cupid_writer_type *type;
  char *dir, *file, *key, *title;
  void *data; /* the type's own */
};

/** dir/file of a writer (or dir/name) into @p path; CUPID_ERR_IO if too long. */
cupid_status cupid_writer_path(const cupid_writer w, const char *name, char *path, size_t size);

/* ---- Gmsh (gmsh.c; issue 35): a section mesh through Gmsh's C API, loaded on first use ---- */
/** A section's quadrilaterals in cupid's LE node order (model.h, cupid_le_node_grid). */
typedef struct {
  double *xz;        /* 2 per node: Gmsh's x and y */
  cupid_int n_nodes;
  int *conn;         /* npe per element, 0-based node indices */
  int *group;        /* per element: its physical group (index into groups), -1 none */
  cupid_int n_elements;
  int npe;
  char **groups;     /* the 2D physical groups' names (an unnamed one: its number) */
  int n_groups;
} cupid_gmsh_section;
/** 1 if Gmsh's library loads (libgmsh.so.4.8, or $CUPID_GMSH_LIBRARY). */
int cupid_gmsh_available(void);
/** Read (or mesh) @p path into @p s with elements of @p npe nodes (4, 9, 16: Gmsh makes the
 *  order). On failure, *why says what, in words for a model error (the caller adds the key's
 *  file:line:col); CUPID_ERR_UNSUPPORTED without Gmsh, CUPID_ERR_IO for a file that cannot be
 *  read, CUPID_ERR_MODEL for a mesh that is no section mesh (triangles, not planar). */
cupid_status cupid_gmsh_read_section(const char *path, int npe, cupid_gmsh_section *s, char *why,
                                     size_t size);
void cupid_gmsh_section_free(cupid_gmsh_section *s);

/* ---- Closed surfaces (surface.c): geometry shapes ---- */
#include "cupid/model.h"
/** A surface of @p n_tri triangles (3 node indices each) over @p n_nodes nodes (xyz), copied.
 *  *open_edges (if given): the edges not shared by an even number of triangles (0: closed). */
cupid_status cupid_surface_create(const double *xyz, int64_t n_nodes, const int64_t *tri,
                                  int64_t n_tri, cupid_surface *surface, int64_t *open_edges);
void cupid_surface_destroy(cupid_surface *surface);
void cupid_surface_bounds(const cupid_surface surface, double lo[3], double hi[3]);
/** The boundary of the volumes of a Gmsh file (.step, .brep, .geo, .msh) as triangles: its
 *  surface mesh, made by Gmsh where the file has none (elements of 10 @p size at most, 256 a
 *  turn where the surface curves), quadrilaterals split. *why as for cupid_gmsh_read_section. */
cupid_status cupid_gmsh_read_surface(const char *path, double size, cupid_surface *surface,
                                     char *why, size_t why_size);

/* ---- Libraries loaded on first use (dynload.c) ---- */
typedef struct {
  const char *name;
  void **fn;
} cupid_io_symbol;
/** Load @p soname (else @p devname; or $@p env alone where set: another build, or none in the
 *  fuzzer) and resolve @p syms. 1 on success; else 0 and *why says what is missing in words
 *  (@p what, the library's name; @p package, the Debian package that has it). */
int cupid_io_load_library(const char *env, const char *soname, const char *devname,
                          const cupid_io_symbol *syms, size_t n_syms, const char *what,
                          const char *package, char *why, size_t size);

#endif
