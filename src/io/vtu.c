/*
 * VTK XML output for ParaView (see include/cupid/io.h): UnstructuredGrid .vtu files with
 * appended raw binary data and .pvd collections.
 *
 * Layout of a .vtu: an XML header in which every DataArray has format="appended" and an
 * offset (in bytes, from the byte after the '_' marker) into <AppendedData encoding="raw">;
 * there each array is a UInt64 byte count followed by the raw values (header_type="UInt64").
 * The values are written straight from the caller's arrays with one fwrite each.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "cupid/io.h"
#include "io/io_internal.h"

void cupid_io_xml_escape(FILE *out, const char *s) {
  for (; *s; s++) {
    switch (*s) {
    case '&': fputs("&amp;", out); break;
    case '<': fputs("&lt;", out); break;
    case '>': fputs("&gt;", out); break;
    case '"': fputs("&quot;", out); break;
    case '\'': fputs("&apos;", out); break;
    default: fputc(*s, out);
    }
  }
}

/* The byte order of this machine, declared in the file instead of swapping bytes. */
static const char *host_byte_order(void) {
  const uint16_t probe = 1;
  unsigned char first;
  memcpy(&first, &probe, 1);
  return first ? "LittleEndian" : "BigEndian";
}

/* ---------------------------------------------------------------- checks */

static cupid_status vtu_check_arrays(const char *where, const cupid_vtu_array *a, int n,
                                     cupid_int count) {
  CUPID_CHECK(n >= 0 && (n == 0 || a), CUPID_ERR_ARGUMENT, "vtu: %d %s arrays but none given", n,
              where);
  for (int i = 0; i < n; i++) {
    CUPID_CHECK(a[i].name && a[i].name[0], CUPID_ERR_ARGUMENT, "vtu: %s array %d has no name",
                where, i);
    CUPID_CHECK(a[i].components >= 1, CUPID_ERR_ARGUMENT,
                "vtu: %s array '%s' has %d components", where, a[i].name, a[i].components);
    CUPID_CHECK(count <= INT64_MAX / 8 / a[i].components, CUPID_ERR_ARGUMENT,
                "vtu: %s array '%s' is too large", where, a[i].name);
    CUPID_CHECK(count == 0 || a[i].values, CUPID_ERR_ARGUMENT, "vtu: %s array '%s' has no values",
                where, a[i].name);
  }
  return CUPID_SUCCESS;
}

/* Reject meshes ParaView would misread: cheap (one pass) compared with writing them. */
static cupid_status vtu_check(const cupid_vtu_mesh *m) {
  CUPID_CHECK(m, CUPID_ERR_ARGUMENT, "vtu: NULL mesh");
  CUPID_CHECK(m->n_points >= 0 && m->n_cells >= 0, CUPID_ERR_ARGUMENT,
              "vtu: negative point or cell count");
  CUPID_CHECK(m->n_points <= INT64_MAX / 24, CUPID_ERR_ARGUMENT, "vtu: too many points");
  CUPID_CHECK(m->n_cells <= INT64_MAX / 8, CUPID_ERR_ARGUMENT, "vtu: too many cells");
  CUPID_CHECK(m->n_points == 0 || m->points, CUPID_ERR_ARGUMENT, "vtu: no point coordinates");
  CUPID_CHECK(m->n_cells == 0 || (m->connectivity && m->offsets && m->types), CUPID_ERR_ARGUMENT,
              "vtu: cells without connectivity, offsets or types");
  cupid_int previous = 0;
  for (cupid_int c = 0; c < m->n_cells; c++) {
    CUPID_CHECK(m->offsets[c] > previous, CUPID_ERR_ARGUMENT,
                "vtu: cell %lld: offset %lld does not increase (previous %lld)", (long long)c,
                (long long)m->offsets[c], (long long)previous);
    previous = m->offsets[c];
  }
  CUPID_CHECK(previous <= INT64_MAX / 8, CUPID_ERR_ARGUMENT, "vtu: connectivity too large");
  for (cupid_int k = 0; k < previous; k++)
    CUPID_CHECK(m->connectivity[k] >= 0 && m->connectivity[k] < m->n_points, CUPID_ERR_ARGUMENT,
                "vtu: connectivity entry %lld is point %lld, outside [0, %lld)", (long long)k,
                (long long)m->connectivity[k], (long long)m->n_points);
  CUPID_CALL(vtu_check_arrays("point", m->point_data, m->n_point_data, m->n_points));
  CUPID_CALL(vtu_check_arrays("cell", m->cell_data, m->n_cell_data, m->n_cells));
  return CUPID_SUCCESS;
}

/* ---------------------------------------------------------------- header */

/* One <DataArray> element; *offset advances past its block (UInt64 count + data). */
static void vtu_data_array(FILE *out, const char *indent, const char *type, const char *name,
                           int components, uint64_t nbytes, uint64_t *offset) {
  fprintf(out, "%s<DataArray type=\"%s\" Name=\"", indent, type);
  cupid_io_xml_escape(out, name);
  fputc('"', out);
  if (components > 1) fprintf(out, " NumberOfComponents=\"%d\"", components);
  fprintf(out, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)*offset);
  *offset += sizeof(uint64_t) + nbytes;
}

static void vtu_data_section(FILE *out, const char *tag, const cupid_vtu_array *a, int n,
                             cupid_int count, uint64_t *offset) {
  if (n == 0) {
    fprintf(out, "      <%s/>\n", tag);
    return;
  }
  fprintf(out, "      <%s>\n", tag);
  for (int i = 0; i < n; i++)
    vtu_data_array(out, "        ", "Float64", a[i].name, a[i].components,
                   (uint64_t)count * (uint64_t)a[i].components * sizeof(double), offset);
  fprintf(out, "      </%s>\n", tag);
}

static void vtu_header(FILE *out, const cupid_vtu_mesh *m) {
  uint64_t offset = 0;
  uint64_t n_conn = m->n_cells ? (uint64_t)m->offsets[m->n_cells - 1] : 0;
  fprintf(out,
          "<?xml version=\"1.0\"?>\n"
          "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"%s\" "
          "header_type=\"UInt64\">\n"
          "  <UnstructuredGrid>\n"
          "    <Piece NumberOfPoints=\"%lld\" NumberOfCells=\"%lld\">\n",
          host_byte_order(), (long long)m->n_points, (long long)m->n_cells);
  vtu_data_section(out, "PointData", m->point_data, m->n_point_data, m->n_points, &offset);
  vtu_data_section(out, "CellData", m->cell_data, m->n_cell_data, m->n_cells, &offset);
  fputs("      <Points>\n", out);
  vtu_data_array(out, "        ", "Float64", "Points", 3, (uint64_t)m->n_points * 24, &offset);
  fputs("      </Points>\n      <Cells>\n", out);
  vtu_data_array(out, "        ", "Int64", "connectivity", 1, n_conn * 8, &offset);
  vtu_data_array(out, "        ", "Int64", "offsets", 1, (uint64_t)m->n_cells * 8, &offset);
  vtu_data_array(out, "        ", "UInt8", "types", 1, (uint64_t)m->n_cells, &offset);
  fputs("      </Cells>\n"
        "    </Piece>\n"
        "  </UnstructuredGrid>\n"
        "  <AppendedData encoding=\"raw\">\n"
        "   _",
        out);
}

/* ---------------------------------------------------------------- data */

/* One appended block: its byte count, then the bytes in one fwrite. */
static cupid_status vtu_block(FILE *out, const char *path, const void *data, uint64_t nbytes) {
  size_t written = fwrite(&nbytes, sizeof nbytes, 1, out);
  if (written == 1 && nbytes > 0) written = fwrite(data, (size_t)nbytes, 1, out);
  CUPID_CHECK(written == 1, CUPID_ERR_IO, "cannot write '%s': write failed", path);
  return CUPID_SUCCESS;
}

static cupid_status vtu_blocks(FILE *out, const char *path, const cupid_vtu_array *a, int n,
                               cupid_int count) {
  for (int i = 0; i < n; i++)
    CUPID_CALL(vtu_block(out, path, a[i].values,
                         (uint64_t)count * (uint64_t)a[i].components * sizeof(double)));
  return CUPID_SUCCESS;
}

cupid_status cupid_vtu_write(const char *path, const cupid_vtu_mesh *mesh) {
  CUPID_CALL(vtu_check(mesh));
  const cupid_vtu_mesh *m = mesh;
  uint64_t n_conn = m->n_cells ? (uint64_t)m->offsets[m->n_cells - 1] : 0;
  cupid_status st = CUPID_SUCCESS;
  cupid_atomic_file file = NULL;
  CUPID_TRY(cupid_atomic_open(path, &file));
  FILE *out = cupid_atomic_stream(file);
  vtu_header(out, m); /* stdio errors are sticky: the commit's checks catch them */
  /* The same order as the offsets in the header. */
  CUPID_TRY(vtu_blocks(out, path, m->point_data, m->n_point_data, m->n_points));
  CUPID_TRY(vtu_blocks(out, path, m->cell_data, m->n_cell_data, m->n_cells));
  CUPID_TRY(vtu_block(out, path, m->points, (uint64_t)m->n_points * 24));
  CUPID_TRY(vtu_block(out, path, m->connectivity, n_conn * sizeof(cupid_int)));
  CUPID_TRY(vtu_block(out, path, m->offsets, (uint64_t)m->n_cells * sizeof(cupid_int)));
  CUPID_TRY(vtu_block(out, path, m->types, (uint64_t)m->n_cells));
  fputs("\n  </AppendedData>\n</VTKFile>\n", out);
  CUPID_TRY(cupid_atomic_commit(&file));
cleanup:
  cupid_atomic_abort(&file);
  return st;
}

cupid_status cupid_pvd_write(const char *path, int n, const char *const *files,
                             const double *times, const int *parts) {
  CUPID_CHECK(n >= 0 && (n == 0 || files), CUPID_ERR_ARGUMENT, "pvd: %d data sets but no files", n);
  for (int i = 0; i < n; i++) {
    CUPID_CHECK(files[i] && files[i][0], CUPID_ERR_ARGUMENT, "pvd: data set %d has no file", i);
    CUPID_CHECK(!times || isfinite(times[i]), CUPID_ERR_ARGUMENT,
                "pvd: data set %d ('%s') has a non-finite time", i, files[i]);
  }
  cupid_status st = CUPID_SUCCESS;
  cupid_atomic_file file = NULL;
  CUPID_TRY(cupid_atomic_open(path, &file));
  FILE *out = cupid_atomic_stream(file);
  fprintf(out,
          "<?xml version=\"1.0\"?>\n"
          "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"%s\">\n"
          "  <Collection>\n",
          host_byte_order());
  for (int i = 0; i < n; i++) {
    char time[40];
    cupid_io_format_double(times ? times[i] : 0.0, time, sizeof time);
    fprintf(out, "    <DataSet timestep=\"%s\" group=\"\" part=\"%d\" file=\"", time,
            parts ? parts[i] : 0);
    cupid_io_xml_escape(out, files[i]);
    fputs("\"/>\n", out);
  }
  fputs("  </Collection>\n</VTKFile>\n", out);
  CUPID_TRY(cupid_atomic_commit(&file));
cleanup:
  cupid_atomic_abort(&file);
  return st;
}
