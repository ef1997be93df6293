/**
 * @file io.h
 * @brief Output files: atomic writes (temp + rename, never a half-written file),
 *        a streaming JSON writer, VTK XML unstructured grids (.vtu, appended base64 data,
 *        UInt64 headers) and .pvd collections for ParaView, and gnuplot PNG plots.
 */
#ifndef CUPID_IO_H
#define CUPID_IO_H

#include <stdio.h>

#include "cupid/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Create a directory and its parents (like `mkdir -p`); existing directories are fine.
 * CUPID_ERR_IO (naming the path and the system's reason) if a component cannot be made or
 * is an existing non-directory; CUPID_ERR_ARGUMENT for an empty path.
 */
cupid_status cupid_mkdir_p(const char *path);

/**
 * A file being written: data goes to a temporary sibling `.NAME.tmp.PID.COUNTER` (same
 * directory, created exclusively, mode 0666 & ~umask) that replaces @p path on commit, so
 * readers never see a half-written file and a failure leaves the old file (if any) intact.
 */
typedef struct cupid_atomic_file_private *cupid_atomic_file;

/** Create the temporary file for @p path. CUPID_ERR_IO if it cannot be created. */
cupid_status cupid_atomic_open(const char *path, cupid_atomic_file *file);
/** The stream to write to (fully buffered with a large buffer; do not fclose it). */
FILE *cupid_atomic_stream(cupid_atomic_file file);
/**
 * Flush, check every write succeeded (ferror, fflush, fclose), fsync-free, then rename()
 * over the target (atomic on POSIX). Always consumes the handle (*file becomes NULL); on any
 * failure the temporary file is removed and CUPID_ERR_IO names the final path.
 */
cupid_status cupid_atomic_commit(cupid_atomic_file *file);
/** Make the commit durable: the file is fsync'ed before the rename and its directory after it
 *  (checkpoints: a power cut leaves the old file or the new one, whole). */
void cupid_atomic_set_durable(cupid_atomic_file file);
/** Close and remove the temporary file, target untouched (NULL-safe; harmless after commit). */
void cupid_atomic_abort(cupid_atomic_file *file);
/** A resumable stream (issue 36): as cupid_atomic_open(), but its temporary file has a fixed
 *  name (".NAME.partial" beside @p path: a resumable run's staging folder) and is not removed
 *  by cupid_atomic_cleanup_all(), so that a resumed run continues it. @p keep < 0 starts it
 *  empty; keep >= 0 continues the one there (or @p path itself, when the stream was committed
 *  before the stop), cut to its first @p keep bytes (CUPID_ERR_IO if it is missing or shorter:
 *  the checkpoint that recorded the length is not this file's). */
cupid_status cupid_atomic_open_partial(const char *path, int64_t keep, cupid_atomic_file *file);
/** Write what @p file holds to disk (fflush, fdatasync) and give its length in bytes: what a
 *  checkpoint records of a stream. */
cupid_status cupid_atomic_sync(cupid_atomic_file file, int64_t *bytes);
/** Close @p file keeping its temporary file, target untouched (a run interrupted after a
 *  checkpoint: its resumption continues the file). NULL-safe; consumes the handle. */
void cupid_atomic_suspend(cupid_atomic_file *file);
/**
 * Unlink the temporary file of every atomic file still open in this process, after killing
 * and reaping a gnuplot still writing its PNG (which is unlinked too). It is
 * async-signal-safe (only kill(), waitpid() and unlink() on pids and paths stored
 * beforehand), so a SIGINT/SIGTERM handler can call it before re-raising the signal with the
 * default action:
 * `static void on_signal(int s) { cupid_atomic_cleanup_all(); signal(s, SIG_DFL); raise(s); }`.
 * The handles stay valid: abort them as usual; committing one fails with CUPID_ERR_IO.
 * Up to 64 simultaneously open files are tracked (more still work, but are not cleaned here).
 */
void cupid_atomic_cleanup_all(void);

/* ---- Checkpoints (src/io/checkpoint.c; issue 36) ----
 * A long run's state as named binary sections in one file, written durably (temporary file,
 * fsync, rename, directory fsync) with a CRC-32 (zlib) and the run's identity, the checkpoint it
 * replaces kept as PATH.prev. Reading takes PATH if intact, else PATH.prev. */
typedef struct cupid_checkpoint_writer_private *cupid_checkpoint_writer;
typedef struct cupid_checkpoint_private *cupid_checkpoint;
/** Start a checkpoint for @p path. @p identity: what the results depend on (the model file's
 *  contents, the result-changing options), in words: stored, and compared on opening. */
cupid_status cupid_checkpoint_write_begin(const char *path, const char *identity,
                                          cupid_checkpoint_writer *w);
/** Append section @p name (1 to 255 characters) of @p bytes bytes. */
cupid_status cupid_checkpoint_write(cupid_checkpoint_writer w, const char *name, const void *data,
                                    size_t bytes);
/** Finish: the trailer, fsync, the old checkpoint kept as PATH.prev, rename over PATH. Consumes
 *  the writer. On failure (CUPID_ERR_IO: a full disk, say) PATH and PATH.prev are as they were
 *  but for PATH.prev becoming a link to PATH. */
cupid_status cupid_checkpoint_write_commit(cupid_checkpoint_writer *w);
/** Drop a checkpoint being written; the files on disk are untouched (NULL-safe). */
void cupid_checkpoint_write_abort(cupid_checkpoint_writer *w);
/** Open the intact one of PATH and PATH.prev (PATH first). CUPID_ERR_IO: neither exists
 *  ("nothing to resume") or neither is intact (truncated, a flipped byte); CUPID_ERR_MODEL: it
 *  was written for another identity (the message quotes both). */
cupid_status cupid_checkpoint_open(const char *path, const char *identity, cupid_checkpoint *ck);
/** Open PATH.prev alone (the checkpoint PATH replaced): under mpirun, a rank whose latest is a
 *  step ahead of another's (the ranks were killed between their commits) resumes from it. The
 *  errors of cupid_checkpoint_open(); CUPID_ERR_IO when PATH.prev is missing or damaged. */
cupid_status cupid_checkpoint_open_previous(const char *path, const char *identity,
                                            cupid_checkpoint *ck);
/** 1 when the checkpoint opened is PATH.prev (PATH was missing or damaged, or asked for). */
int cupid_checkpoint_is_previous(const cupid_checkpoint ck);
/** Section @p name: a pointer into the checkpoint (valid until close) and its size;
 *  CUPID_ERR_IO when it has none. */
cupid_status cupid_checkpoint_section(const cupid_checkpoint ck, const char *name,
                                      const void **data, size_t *bytes);
/** Copy section @p name, which must hold exactly @p bytes bytes (else CUPID_ERR_IO). */
cupid_status cupid_checkpoint_read(const cupid_checkpoint ck, const char *name, void *data,
                                   size_t bytes);
void cupid_checkpoint_close(cupid_checkpoint *ck);

/**
 * The output files of one run as a set (src/io/output_set.c): begin stages a folder beside the
 * output folder @p dir (its parent is created) and locks @p dir against a second cupid run
 * (CUPID_ERR_IO naming the other run's pid); the run writes into cupid_output_set_dir();
 * publish moves the staged files into @p dir (created if missing), summary.json last, after
 * removing the files of the run's kinds (summary.json, pd_nodes.csv, VTU/PVD, line_*, history*,
 * energies*, damage*) that the run did not write; other files in @p dir are left alone. abort
 * (also after a failed publish) removes the staging folder: @p dir stays as it was. Staging
 * folders of runs that died are removed by the next begin on the same folder. publish and
 * abort release the lock and consume the handle (NULL-safe).
 */
typedef struct cupid_output_set_private *cupid_output_set;
cupid_status cupid_output_set_begin(const char *dir, cupid_output_set *set);
const char *cupid_output_set_dir(const cupid_output_set set);
cupid_status cupid_output_set_publish(cupid_output_set *set);
void cupid_output_set_abort(cupid_output_set *set);
/** As cupid_output_set_begin(), for a run that may be interrupted and resumed (issue 36): the
 *  staging folder has a fixed name (cupid_output_set_partial_dir()) that a signal leaves, and
 *  holds the run's checkpoints as dot files (never published; removed with the folder).
 *  @p resume 0 starts it empty (an interrupted run's folder is removed, as every other begin
 *  does); 1 keeps what it holds (CUPID_ERR_IO, "nothing to resume", when there is none). */
cupid_status cupid_output_set_begin_resumable(const char *dir, int resume, cupid_output_set *set);
/** The staging folder of a resumable run into @p dir (parent/.base.cupid-partial; every rank of
 *  an MPI run keeps its checkpoint there). Free with cupid_free(). */
cupid_status cupid_output_set_partial_dir(const char *dir, char **path);
/** Release the lock and keep the staging folder as it is (an interrupted resumable run, whose
 *  checkpoint is there). Consumes the handle (NULL-safe). */
void cupid_output_set_suspend(cupid_output_set *set);
/** publish leaves every file of @p dir that the set does not write alone (no stale files
 *  removed): a second publish of the same run's outputs, whose first one holds files (time
 *  series written as the run went) that this one does not. */
void cupid_output_set_keep_others(cupid_output_set set);

/**
 * Streaming JSON writer: pretty printed (2-space indent), keys and strings escaped per
 * RFC 8259 (invalid UTF-8 becomes U+FFFD), numbers round-trip exactly ("%.15g", else "%.17g"),
 * NaN/Inf become null, integers exact. Inside objects every value needs a key; inside arrays
 * and at the top level pass key = NULL. The writer functions never fail or crash: misuse
 * (unbalanced end, missing key, a second top-level value) is recorded and reported by
 * cupid_json_status(); write errors stay in the stream's error flag (cupid_atomic_commit()
 * checks it). A newline follows the top-level value.
 */
typedef struct cupid_json_private *cupid_json;
/** Start a writer on @p stream (not owned). */
cupid_status cupid_json_create(FILE *stream, cupid_json *json);
/** Free the writer (NULL-safe; does not close the stream). */
void cupid_json_destroy(cupid_json *json);
void cupid_json_begin_object(cupid_json json, const char *key); /* key NULL inside arrays */
void cupid_json_end_object(cupid_json json);
void cupid_json_begin_array(cupid_json json, const char *key);
void cupid_json_end_array(cupid_json json);
void cupid_json_string(cupid_json json, const char *key, const char *value); /**< NULL -> null */
void cupid_json_number(cupid_json json, const char *key, double value);
void cupid_json_integer(cupid_json json, const char *key, int64_t value);
void cupid_json_bool(cupid_json json, const char *key, int value);
void cupid_json_null(cupid_json json, const char *key);
/**
 * CUPID_SUCCESS if one complete, well-formed document was written: CUPID_ERR_INTERNAL
 * describing the first misuse or unclosed containers, CUPID_ERR_IO if the stream had an error.
 */
cupid_status cupid_json_status(cupid_json json);

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

/**
 * Write a .vtu file (VTK XML UnstructuredGrid version 1.0, host byte order declared in
 * byte_order): Points Float64, connectivity and offsets Int64, types UInt8, data arrays
 * Float64 with their NumberOfComponents, values as given (6-component symmetric tensors in
 * the caller's order). The arrays are appended data with encoding="base64", as VTK's own
 * writer makes them: each array one padded base64 run of its UInt64 byte count followed by
 * its bytes, offsets in characters after the '_' marker (4/3 the size of raw bytes, but
 * read by VTK/ParaView, meshio and every other reader; raw appended data is not). Written
 * atomically. The mesh is checked first (CUPID_ERR_ARGUMENT): offsets increasing and ending
 * at the connectivity length, connectivity within [0, n_points), arrays present. Zero
 * points/cells are allowed.
 */
cupid_status cupid_vtu_write(const char *path, const cupid_vtu_mesh *mesh);

/**
 * Write a .pvd collection (atomically): n datasets (file names relative to the .pvd), their
 * block names (NULL, or a NULL/empty entry: the file's base name without its extension and
 * without a trailing `_<digits>` step number, so "pd_000100.vtu" is "pd"), times (NULL: all
 * 0; must be finite) and parts (NULL: the distinct names numbered 0, 1, ... in order of
 * first appearance; else >= 0). ParaView shows the data sets of one time as blocks with these
 * names (the DataSet `name` attribute).
 */
cupid_status cupid_pvd_write_named(const char *path, int n, const char *const *files,
                                   const char *const *names, const double *times,
                                   const int *parts);

/** cupid_pvd_write_named() with the default names (from the file names). */
cupid_status cupid_pvd_write(const char *path, int n, const char *const *files,
                             const double *times, const int *parts);

/* ---- Output writers (src/io/writer*.c; issue 35) ----
 * The files of a run's output steps, written by writers chosen from a table, in the manner of
 * PETSc's viewers: a writer is made for a folder, takes a frame at each output step, records
 * what a checkpoint needs to continue it, and is ended (its files committed) or dropped (its
 * temporary files removed, or kept for a resumption). The runs (dynamics, load steps) build
 * frames; the writers alone write files.
 *   cupid_writer_csv:    a CSV file, its header and one row per frame (frame->row);
 *   cupid_writer_vtu:    PART_<step>.vtu per part and frame, and at the end a .pvd listing them
 *                        with their times (ParaView's blocks are the parts);
 *   cupid_writer_exodus: one Exodus II file: every part an element block (VTK vertices as
 *                        SPHERE elements with a volume attribute, hexahedra as HEX8), their
 *                        nodes one node set, the points written once, the nodal fields at every
 *                        frame as the time steps (where the build found exodusII.h and the
 *                        system has the library, loaded on first use:
 *                        cupid_writer_available()). */

/** A column of a CSV writer: printed as "%.10e", or as an integer ("%lld" of the value). */
typedef struct {
  const char *name;
  int integer;
} cupid_column;

/** One part of a frame: a mesh with its point data (and optionally each cell's volume). */
typedef struct {
  const char *name;            /**< "beam", "pd": file stems and Exodus block names */
  const cupid_vtu_mesh *mesh;  /**< points, cells of one type, point data */
  const double *cell_volume;   /**< Exodus: the SPHERE elements' volume attribute (or NULL) */
} cupid_frame_part;

/** What an output step hands to the writers. */
typedef struct {
  cupid_int step;      /**< the step's number (file names: PART_<step>.vtu) */
  double time;         /**< t, or a load step's load factor */
  const double *row;   /**< a CSV writer's values, one per column */
  int n_parts;
  const cupid_frame_part *parts;
} cupid_frame;

/** What a writer is made for. */
typedef struct {
  const char *dir;      /**< the folder its files go into */
  const char *file;     /**< CSV: the file; VTU: the collection (.pvd); Exodus: the .exo */
  const char *title;    /**< Exodus: the database's title */
  const cupid_column *columns; /**< CSV: the header's columns */
  int n_columns;
  /** A resumption: the checkpoint whose section @p key the writer saved (NULL: start anew). */
  cupid_checkpoint resume;
  const char *key;      /**< the writer's checkpoint section (cupid_writer_save) */
} cupid_writer_spec;

typedef struct cupid_writer_type cupid_writer_type;
typedef struct cupid_writer_private *cupid_writer;
extern const cupid_writer_type cupid_writer_csv, cupid_writer_vtu, cupid_writer_exodus;

/** 1 if writers of @p type can be made here (Exodus: exodusII.h at build time, its library
 *  loaded at run time). */
int cupid_writer_available(const cupid_writer_type *type);
/** NULL, or why writers of @p type cannot be made here (the package to install). */
const char *cupid_writer_unavailable(const cupid_writer_type *type);
/** The type's name: "csv", "vtu", "exodus". */
const char *cupid_writer_name(const cupid_writer_type *type);
/** Make a writer. CUPID_ERR_IO if its file cannot be made (or, resuming, found as the
 *  checkpoint left it); CUPID_ERR_ARGUMENT for a type this build lacks. */
cupid_status cupid_writer_create(const cupid_writer_type *type, const cupid_writer_spec *spec,
                                 cupid_writer *writer);
/** Write one frame (a NULL writer: nothing, success: a rank that writes no files). */
cupid_status cupid_writer_step(cupid_writer writer, const cupid_frame *frame);
/** Make what was written durable and record in section spec->key of @p ckw what a resumption
 *  needs to continue it (NULL writer: nothing). */
cupid_status cupid_writer_save(cupid_writer writer, cupid_checkpoint_writer ckw);
/** Finish the files (the .pvd, the Exodus file's close) and commit them; consumes the writer. */
cupid_status cupid_writer_end(cupid_writer *writer);
/** Drop a writer: its temporary files removed, or with @p keep left for a resumption (after a
 *  checkpoint). NULL-safe. */
void cupid_writer_drop(cupid_writer *writer, int keep);

/** A curve for a plot: columns of a CSV file (comma separated). */
typedef struct {
  const char *csv;    /**< file name relative to the plot's directory */
  int xcol, ycol;     /**< 1-based columns */
  const char *title;  /**< legend */
  const char *style;  /**< gnuplot style, e.g. "lines", "points pt 7 ps 0.5" (NULL: lines) */
  const char *xname;  /**< optional: x column by its header name (overrides xcol) */
  const char *yname;  /**< optional: y column by its header name (overrides ycol) */
} cupid_plot_curve;

/** Plot settings; start from cupid_plot_defaults(). */
typedef struct {
  int header_lines;  /**< lines skipped at the top of each CSV; default 1 (cupid's header) */
  int width, height; /**< PNG size in pixels; default 1000 x 650 */
  int logx, logy;    /**< logarithmic axes; default 0 */
  const char *key;   /**< gnuplot key placement ("top left", "off", ...); default "top right" */
} cupid_plot_options;

/** The default plot settings (one header line per CSV, 1000 x 650 px, linear axes). */
cupid_plot_options cupid_plot_defaults(void);

/**
 * Write `<stem>.gp` (a gnuplot script, kept so users can edit it; written atomically) into
 * @p dir and, if gnuplot is installed (found on PATH), run it in @p dir to produce
 * `<stem>.png`. *made is 1 if the PNG was made. A missing gnuplot is not an error (the script
 * is still there, *made = 0). Each CSV is assumed to start with one header line, which is
 * skipped. gnuplot's own output is captured and only shown (in the error message) if it fails:
 * CUPID_ERR_IO with its exit status. Titles and labels are printed literally (noenhanced).
 * A curve's xname/yname are looked up in the header line of its CSV (CUPID_ERR_IO if the
 * file cannot be read, CUPID_ERR_ARGUMENT if the column is missing).
 */
cupid_status cupid_plot(const char *dir, const char *stem, const char *title, const char *xlabel,
                        const char *ylabel, int n_curves, const cupid_plot_curve *curves,
                        int *made);

/** cupid_plot() with settings (@p options NULL: cupid_plot_defaults()). */
cupid_status cupid_plot_ex(const char *dir, const char *stem, const char *title,
                           const char *xlabel, const char *ylabel, int n_curves,
                           const cupid_plot_curve *curves, const cupid_plot_options *options,
                           int *made);

#ifdef __cplusplus
}
#endif
#endif
