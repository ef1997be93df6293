/*
 * VTK XML output for ParaView (see include/cupid/io.h): UnstructuredGrid .vtu files with
 * appended base64 data and .pvd collections.
 *
 * Layout of a .vtu: an XML header in which every DataArray has format="appended" and an
 * offset (in characters, from the character after the '_' marker) into
 * <AppendedData encoding="base64">; there each array is one base64 run (padded with '='
 * to a multiple of 4 characters) encoding a UInt64 byte count followed by the raw values
 * (header_type="UInt64"), the count and the values encoded together as VTK's own writer
 * does. Base64 instead of raw bytes: meshio rewrites raw appended data into base64 itself
 * and mismatches the offsets of arrays whose raw offsets collide with rewritten ones (every
 * beam.vtu was rejected as corrupt), while every reader handles base64 appended data.
 * The values are encoded straight from the caller's arrays through a buffer, 3 bytes to
 * 4 characters with a table of character pairs.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "cupid/io.h"
#include "io/io_internal.h"

/* The first @p n characters of @p s, escaped. */
static void xml_escape_n(FILE *out, const char *s, size_t n) {
  for (size_t k = 0; k < n; k++) {
    switch (s[k]) {
    case '&': fputs("&amp;", out); break;
    case '<': fputs("&lt;", out); break;
    case '>': fputs("&gt;", out); break;
    case '"': fputs("&quot;", out); break;
    case '\'': fputs("&apos;", out); break;
    default: fputc(s[k], out);
    }
  }
}

void cupid_io_xml_escape(FILE *out, const char *s) { xml_escape_n(out, s, strlen(s)); }

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

/* Characters of the padded base64 encoding of @p nbytes bytes. */
static uint64_t base64_length(uint64_t nbytes) { return (nbytes + 2) / 3 * 4; }

/* One <DataArray> element; *offset advances past its block (UInt64 count + data, encoded). */
static void vtu_data_array(FILE *out, const char *indent, const char *type, const char *name,
                           int components, uint64_t nbytes, uint64_t *offset) {
  fprintf(out, "%s<DataArray type=\"%s\" Name=\"", indent, type);
  cupid_io_xml_escape(out, name);
  fputc('"', out);
  if (components > 1) fprintf(out, " NumberOfComponents=\"%d\"", components);
  fprintf(out, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)*offset);
  *offset += base64_length(sizeof(uint64_t) + nbytes);
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
        "  <AppendedData encoding=\"base64\">\n"
        "   _",
        out);
}

/* ---------------------------------------------------------------- base64 */

enum { BASE64_BUFFER = 1 << 18 }; /* characters encoded before one fwrite */

/* Encodes into a buffer written out when full; bytes short of a triple wait in carry. */
typedef struct {
  FILE *out;
  const char *path;
  char pairs[4096][2]; /* the two characters of every 12-bit value */
  unsigned char carry[3];
  int n_carry;
  size_t len;
  char *buffer; /* BASE64_BUFFER characters */
} base64_stream;

static void base64_init(base64_stream *s, FILE *out, const char *path, char *buffer) {
  static const char alphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  s->out = out;
  s->path = path;
  for (int v = 0; v < 4096; v++) {
    s->pairs[v][0] = alphabet[v >> 6];
    s->pairs[v][1] = alphabet[v & 63];
  }
  s->n_carry = 0;
  s->len = 0;
  s->buffer = buffer;
}

static cupid_status base64_flush(base64_stream *s) {
  size_t written = s->len ? fwrite(s->buffer, 1, s->len, s->out) : 0;
  CUPID_CHECK(written == s->len, CUPID_ERR_IO, "cannot write '%s': write failed", s->path);
  s->len = 0;
  return CUPID_SUCCESS;
}

/* Encode @p n complete triples of @p p into the buffer (room for 4 n characters). */
static void base64_triples(base64_stream *s, const unsigned char *p, size_t n) {
  char *dst = s->buffer + s->len;
  for (size_t k = 0; k < n; k++, p += 3, dst += 4) {
    const uint32_t v = (uint32_t)p[0] << 16 | (uint32_t)p[1] << 8 | p[2];
    memcpy(dst, s->pairs[v >> 12], 2);
    memcpy(dst + 2, s->pairs[v & 4095], 2);
  }
  s->len += 4 * n;
}

static cupid_status base64_put(base64_stream *s, const void *data, uint64_t nbytes) {
  const unsigned char *p = data;
  if (s->n_carry) { /* complete the waiting triple first */
    while (s->n_carry < 3 && nbytes) s->carry[s->n_carry++] = *p++, nbytes--;
    if (s->n_carry < 3) return CUPID_SUCCESS;
    if (s->len + 4 > BASE64_BUFFER) CUPID_CALL(base64_flush(s));
    base64_triples(s, s->carry, 1);
    s->n_carry = 0;
  }
  uint64_t triples = nbytes / 3;
  while (triples) {
    if (s->len + 4 > BASE64_BUFFER) CUPID_CALL(base64_flush(s));
    uint64_t room = (BASE64_BUFFER - s->len) / 4, k = triples < room ? triples : room;
    base64_triples(s, p, (size_t)k);
    p += 3 * k;
    triples -= k;
  }
  for (uint64_t r = 0; r < nbytes % 3; r++) s->carry[s->n_carry++] = p[r];
  return CUPID_SUCCESS;
}

/* End one base64 run: the last 1 or 2 bytes become 2 or 3 characters and '=' padding. */
static cupid_status base64_end(base64_stream *s) {
  if (!s->n_carry) return CUPID_SUCCESS;
  if (s->len + 4 > BASE64_BUFFER) CUPID_CALL(base64_flush(s));
  const int n = s->n_carry;
  s->carry[1] = n > 1 ? s->carry[1] : 0;
  s->carry[2] = 0;
  base64_triples(s, s->carry, 1);
  s->buffer[s->len - 1] = '=';
  if (n == 1) s->buffer[s->len - 2] = '=';
  s->n_carry = 0;
  return CUPID_SUCCESS;
}

/* ---------------------------------------------------------------- data */

/* One appended block: its byte count and its bytes, encoded as one base64 run. */
static cupid_status vtu_block(base64_stream *s, const void *data, uint64_t nbytes) {
  CUPID_CALL(base64_put(s, &nbytes, sizeof nbytes));
  if (nbytes > 0) CUPID_CALL(base64_put(s, data, nbytes));
  return base64_end(s);
}

static cupid_status vtu_blocks(base64_stream *s, const cupid_vtu_array *a, int n,
                               cupid_int count) {
  for (int i = 0; i < n; i++)
    CUPID_CALL(vtu_block(s, a[i].values,
                         (uint64_t)count * (uint64_t)a[i].components * sizeof(double)));
  return CUPID_SUCCESS;
}

cupid_status cupid_vtu_write(const char *path, const cupid_vtu_mesh *mesh) {
  CUPID_CALL(vtu_check(mesh));
  const cupid_vtu_mesh *m = mesh;
  uint64_t n_conn = m->n_cells ? (uint64_t)m->offsets[m->n_cells - 1] : 0;
  cupid_status st = CUPID_SUCCESS;
  cupid_atomic_file file = NULL;
  base64_stream *s = NULL;
  char *buffer = NULL;
  CUPID_TRY(cupid_malloc(1, sizeof *s, "VTU encoder", &s));
  CUPID_TRY(cupid_malloc(BASE64_BUFFER, 1, "VTU encoder buffer", &buffer));
  CUPID_TRY(cupid_atomic_open(path, &file));
  FILE *out = cupid_atomic_stream(file);
  base64_init(s, out, path, buffer);
  vtu_header(out, m); /* stdio errors are sticky: the commit's checks catch them */
  /* The same order as the offsets in the header. */
  CUPID_TRY(vtu_blocks(s, m->point_data, m->n_point_data, m->n_points));
  CUPID_TRY(vtu_blocks(s, m->cell_data, m->n_cell_data, m->n_cells));
  CUPID_TRY(vtu_block(s, m->points, (uint64_t)m->n_points * 24));
  CUPID_TRY(vtu_block(s, m->connectivity, n_conn * sizeof(cupid_int)));
  CUPID_TRY(vtu_block(s, m->offsets, (uint64_t)m->n_cells * sizeof(cupid_int)));
  CUPID_TRY(vtu_block(s, m->types, (uint64_t)m->n_cells));
  CUPID_TRY(base64_flush(s));
  fputs("\n  </AppendedData>\n</VTKFile>\n", out);
  CUPID_TRY(cupid_atomic_commit(&file));
cleanup:
  cupid_atomic_abort(&file);
  cupid_free(&s);
  cupid_free(&buffer);
  return st;
}

/* ---------------------------------------------------------------- pvd */

/* The default block name of @p file: its base name without the extension and without a
 * trailing `_<digits>` step number ("out/pd_000100.vtu" -> "pd"); sets *len. */
static const char *pvd_default_name(const char *file, size_t *len) {
  const char *base = strrchr(file, '/');
  base = base ? base + 1 : file;
  const char *dot = strrchr(base, '.');
  size_t n = dot && dot > base ? (size_t)(dot - base) : strlen(base);
  size_t k = n;
  while (k > 0 && base[k - 1] >= '0' && base[k - 1] <= '9') k--;
  if (k < n && k > 1 && base[k - 1] == '_') n = k - 1;
  *len = n;
  return base;
}

cupid_status cupid_pvd_write_named(const char *path, int n, const char *const *files,
                                   const char *const *names, const double *times,
                                   const int *parts) {
  CUPID_CHECK(n >= 0 && (n == 0 || files), CUPID_ERR_ARGUMENT, "pvd: %d data sets but no files", n);
  for (int i = 0; i < n; i++) {
    CUPID_CHECK(files[i] && files[i][0], CUPID_ERR_ARGUMENT, "pvd: data set %d has no file", i);
    CUPID_CHECK(!times || isfinite(times[i]), CUPID_ERR_ARGUMENT,
                "pvd: data set %d ('%s') has a non-finite time", i, files[i]);
    CUPID_CHECK(!parts || parts[i] >= 0, CUPID_ERR_ARGUMENT, "pvd: data set %d ('%s') has part %d",
                i, files[i], parts[i]);
  }
  cupid_status st = CUPID_SUCCESS;
  cupid_atomic_file file = NULL;
  const char **block = NULL; /* the name of each data set */
  size_t *block_len = NULL;
  int *part = NULL, n_distinct = 0, *first = NULL; /* first data set of each distinct name */
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *block, "PVD names", &block));
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *block_len, "PVD name lengths", &block_len));
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *part, "PVD parts", &part));
  CUPID_TRY(cupid_malloc((size_t)n, sizeof *first, "PVD distinct names", &first));
  for (int i = 0; i < n; i++) {
    if (names && names[i] && names[i][0]) {
      block[i] = names[i];
      block_len[i] = strlen(names[i]);
    } else {
      block[i] = pvd_default_name(files[i], &block_len[i]);
    }
    int d = 0; /* parts by default: the distinct names numbered in order of appearance */
    while (d < n_distinct && !(block_len[first[d]] == block_len[i] &&
                               memcmp(block[first[d]], block[i], block_len[i]) == 0))
      d++;
    if (d == n_distinct) first[n_distinct++] = i;
    part[i] = parts ? parts[i] : d;
  }
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
    fprintf(out, "    <DataSet timestep=\"%s\" group=\"\" part=\"%d\" name=\"", time, part[i]);
    xml_escape_n(out, block[i], block_len[i]);
    fputs("\" file=\"", out);
    cupid_io_xml_escape(out, files[i]);
    fputs("\"/>\n", out);
  }
  fputs("  </Collection>\n</VTKFile>\n", out);
  CUPID_TRY(cupid_atomic_commit(&file));
cleanup:
  cupid_atomic_abort(&file);
  cupid_free(&block);
  cupid_free(&block_len);
  cupid_free(&part);
  cupid_free(&first);
  return st;
}

cupid_status cupid_pvd_write(const char *path, int n, const char *const *files,
                             const double *times, const int *parts) {
  return cupid_pvd_write_named(path, n, files, NULL, times, parts);
}
