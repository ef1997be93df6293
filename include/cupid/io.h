/**
 * @file io.h
 * @brief Output files: atomic writes (temp + rename, never a half-written file),
 *        a streaming JSON writer, VTK XML unstructured grids (.vtu, appended raw binary,
 *        UInt64 headers) and .pvd collections for ParaView, and gnuplot PNG plots.
 */
#ifndef CUPID_IO_H
#define CUPID_IO_H

#include <stdio.h>

#include "cupid/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Create a directory and its parents (like mkdir -p). CUPID_ERR_IO on failure. */
cupid_status cupid_mkdir_p(const char *path);

/** A file being written: data goes to a temporary sibling that replaces @p path on commit. */
typedef struct cupid_atomic_file_private *cupid_atomic_file;

cupid_status cupid_atomic_open(const char *path, cupid_atomic_file *file);
/** The stream to write to. */
FILE *cupid_atomic_stream(cupid_atomic_file file);
/** Flush, check every write succeeded, fsync-free close, rename over the target. */
cupid_status cupid_atomic_commit(cupid_atomic_file *file);
/** Remove the temporary file (NULL-safe; harmless after commit). */
void cupid_atomic_abort(cupid_atomic_file *file);

/** Streaming JSON writer with indentation and correct escaping; NaN/Inf become null. */
typedef struct cupid_json_private *cupid_json;
cupid_status cupid_json_create(FILE *stream, cupid_json *json);
void cupid_json_destroy(cupid_json *json);
void cupid_json_begin_object(cupid_json json, const char *key); /* key NULL inside arrays */
void cupid_json_end_object(cupid_json json);
void cupid_json_begin_array(cupid_json json, const char *key);
void cupid_json_end_array(cupid_json json);
void cupid_json_string(cupid_json json, const char *key, const char *value);
void cupid_json_number(cupid_json json, const char *key, double value);
void cupid_json_integer(cupid_json json, const char *key, int64_t value);
void cupid_json_bool(cupid_json json, const char *key, int value);
void cupid_json_null(cupid_json json, const char *key);

/** VTK cell types used by cupid. */
enum { CUPID_VTK_VERTEX = 1, CUPID_VTK_LINE = 3, CUPID_VTK_QUAD = 9, CUPID_VTK_HEXAHEDRON = 12 };

/** A data array attached to points or cells. */
typedef struct {
  const char *name;
  int components;       /**< 1 (scalar), 3 (vector), 6 (symmetric tensor) ... */
  const double *values; /**< n * components */
} cupid_vtu_array;

/** An unstructured grid to write. */
typedef struct {
  cupid_int n_points;
  const double *points;        /**< 3 per point */
  cupid_int n_cells;
  const cupid_int *connectivity;
  const cupid_int *offsets;    /**< end offset of each cell in connectivity (VTK convention) */
  const unsigned char *types;  /**< VTK cell type per cell */
  const cupid_vtu_array *point_data;
  int n_point_data;
  const cupid_vtu_array *cell_data;
  int n_cell_data;
} cupid_vtu_mesh;

/** Write a .vtu file (VTK XML UnstructuredGrid, appended raw binary, UInt64 headers). */
cupid_status cupid_vtu_write(const char *path, const cupid_vtu_mesh *mesh);

/** Write a .pvd collection: n datasets (file names relative to the .pvd), times, parts. */
cupid_status cupid_pvd_write(const char *path, int n, const char *const *files,
                             const double *times, const int *parts);

/** A curve for a plot: columns of a CSV file. */
typedef struct {
  const char *csv;    /**< file name relative to the plot's directory */
  int xcol, ycol;     /**< 1-based columns */
  const char *title;  /**< legend */
  const char *style;  /**< gnuplot style, e.g. "lines", "points pt 7 ps 0.5" */
} cupid_plot_curve;

/**
 * Write `<stem>.gp` (a gnuplot script, kept so users can edit it) into @p dir and, if
 * gnuplot is installed, run it to produce `<stem>.png`. *made is 1 if the PNG was made.
 * A missing gnuplot is not an error (the script is still there).
 */
cupid_status cupid_plot(const char *dir, const char *stem, const char *title, const char *xlabel,
                        const char *ylabel, int n_curves, const cupid_plot_curve *curves,
                        int *made);

#ifdef __cplusplus
}
#endif
#endif
