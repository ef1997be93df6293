/* Unit tests of the .vtu/.pvd writers (src/io/vtu.c): appended base64 data, read back in C and by
 * tests/tools/read_vtu.py (an independent reader that checks the file's structure). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

static char root[256];

static int setup(void **state) {
  (void)state;
  return cupid_test_mkdtemp("vtu", root, sizeof root);
}

static int teardown(void **state) {
  (void)state;
  return cupid_test_rmtree(root);
}

static const char *in_root(const char *name) {
  static char buf[4][1024];
  static int next;
  char *b = buf[next++ % 4];
  snprintf(b, sizeof buf[0], "%s/%s", root, name);
  return b;
}

static char *slurp(const char *path, size_t *size) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  assert_int_equal(fseek(f, 0, SEEK_END), 0);
  long n = ftell(f);
  assert_true(n >= 0);
  rewind(f);
  char *buf = malloc((size_t)n + 1);
  assert_non_null(buf);
  assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
  buf[n] = '\0';
  fclose(f);
  if (size) *size = (size_t)n;
  return buf;
}

/* ---------------------------------------------------------------- a test mesh */

enum { NX = 3, NY = 2, NZ = 2, NVERT = 5 };
#define NPTS ((NX + 1) * (NY + 1) * (NZ + 1))
#define NHEX (NX * NY * NZ)
#define NCELLS (NHEX + NVERT + 1)
#define NCONN (8 * NHEX + NVERT + 2)

typedef struct {
  double points[3 * NPTS];
  cupid_int conn[NCONN], offsets[NCELLS];
  unsigned char types[NCELLS];
  double T[NPTS], u[3 * NPTS], sigma[6 * NPTS];
  double damage[NCELLS], stress[6 * NCELLS];
  cupid_vtu_array pd[3], cd[2];
  cupid_vtu_mesh mesh;
} test_mesh;

static cupid_int node(int i, int j, int k) { return i + (NX + 1) * (j + (NY + 1) * k); }

/* Hexahedra of a 3 x 2 x 2 grid, 5 vertex cells, one line; random data with edge cases. */
static void make_mesh(test_mesh *m) {
  uint64_t seed = 42;
  for (int k = 0; k <= NZ; k++)
    for (int j = 0; j <= NY; j++)
      for (int i = 0; i <= NX; i++) {
        double *p = &m->points[3 * node(i, j, k)];
        p[0] = 0.5 * i;
        p[1] = 0.25 * j + 1e-3 * cupid_test_random(&seed);
        p[2] = -0.1 * k;
      }
  cupid_int c = 0, n = 0;
  for (int k = 0; k < NZ; k++)
    for (int j = 0; j < NY; j++)
      for (int i = 0; i < NX; i++) {
        cupid_int v[8] = {node(i, j, k),         node(i + 1, j, k),     node(i + 1, j + 1, k),
                          node(i, j + 1, k),     node(i, j, k + 1),     node(i + 1, j, k + 1),
                          node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)};
        for (int a = 0; a < 8; a++) m->conn[n++] = v[a];
        m->offsets[c] = n;
        m->types[c++] = CUPID_VTK_HEXAHEDRON;
      }
  for (int v = 0; v < NVERT; v++) {
    m->conn[n++] = 7 * v;
    m->offsets[c] = n;
    m->types[c++] = CUPID_VTK_VERTEX;
  }
  m->conn[n++] = 0;
  m->conn[n++] = NPTS - 1;
  m->offsets[c] = n;
  m->types[c++] = CUPID_VTK_LINE;
  assert_int_equal(c, NCELLS);
  assert_int_equal(n, NCONN);
  for (int i = 0; i < NPTS; i++) m->T[i] = 300.0 + cupid_test_random(&seed);
  for (int i = 0; i < 3 * NPTS; i++) m->u[i] = 1e-3 * cupid_test_random(&seed);
  for (int i = 0; i < 6 * NPTS; i++) m->sigma[i] = 1e8 * cupid_test_random(&seed);
  for (int i = 0; i < NCELLS; i++) m->damage[i] = 0.5 + 0.5 * cupid_test_random(&seed);
  for (int i = 0; i < 6 * NCELLS; i++) m->stress[i] = 1e6 * cupid_test_random(&seed);
  m->u[0] = -0.0;   /* the sign of zero must survive */
  m->u[1] = 1e-310; /* a subnormal */
  m->T[1] = 0.1;
  m->pd[0] = (cupid_vtu_array){"T", 1, m->T};
  m->pd[1] = (cupid_vtu_array){"u", 3, m->u};
  m->pd[2] = (cupid_vtu_array){"sigma", 6, m->sigma};
  m->cd[0] = (cupid_vtu_array){"damage", 1, m->damage};
  m->cd[1] = (cupid_vtu_array){"stress<&\"'>", 6, m->stress}; /* XML special characters */
  m->mesh = (cupid_vtu_mesh){.n_points = NPTS, .points = m->points, .n_cells = NCELLS,
                             .connectivity = m->conn, .offsets = m->offsets, .types = m->types,
                             .point_data = m->pd, .n_point_data = 3, .cell_data = m->cd,
                             .n_cell_data = 2};
}

/* ---------------------------------------------------------------- reading back in C */

/* The value of one base64 character, -1 for '=' and -2 for anything else. */
static int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return c == '=' ? -1 : -2;
}

/* Decode @p nchars characters (a multiple of 4, '=' only in the last group) into @p out;
 * returns the number of bytes. */
static size_t base64_decode(const char *text, size_t nchars, unsigned char *out) {
  assert_int_equal(nchars % 4, 0);
  size_t n = 0;
  for (size_t g = 0; g < nchars; g += 4) {
    int v[4];
    for (int k = 0; k < 4; k++) v[k] = base64_value(text[g + k]);
    const int last = g + 4 == nchars;
    assert_true(v[0] >= 0 && v[1] >= 0);
    assert_true(v[2] >= 0 || (last && v[2] == -1 && v[3] == -1));
    assert_true(v[3] >= 0 || (last && v[3] == -1));
    out[n++] = (unsigned char)(v[0] << 2 | v[1] >> 4);
    if (v[2] >= 0) out[n++] = (unsigned char)((v[1] & 15) << 4 | v[2] >> 2);
    if (v[3] >= 0) out[n++] = (unsigned char)((v[2] & 3) << 6 | v[3]);
  }
  return n;
}

/*
 * The appended array whose Name attribute is @p xml_name (as written in the XML, i.e.
 * escaped): offset (in characters) from the header, then one padded base64 run that decodes
 * to a UInt64 byte count and exactly that many bytes, followed by the next run or the end of
 * the appended data. Returns the data (caller frees) and its byte count.
 */
static unsigned char *appended_array(const char *file, size_t size, const char *xml_name,
                                     uint64_t *nbytes) {
  const char *data_tag = strstr(file, "<AppendedData encoding=\"base64\">");
  assert_non_null(data_tag);
  const char *marker = strchr(data_tag, '_');
  assert_non_null(marker);
  char attr[256];
  snprintf(attr, sizeof attr, "Name=\"%s\"", xml_name);
  const char *el = strstr(file, attr);
  if (!el || el > data_tag) fail_msg("no DataArray %s", attr);
  const char *off = strstr(el, "offset=\"");
  assert_non_null(off);
  assert_true(off < strchr(el, '>'));
  uint64_t offset = strtoull(off + 8, NULL, 10);
  const char *run = marker + 1 + offset;
  assert_true(run + 12 <= file + size);
  unsigned char head[9];
  assert_true(base64_decode(run, 12, head) >= 8); /* the count: bytes 0-7 of the run */
  memcpy(nbytes, head, 8);
  const size_t nchars = (size_t)(8 + *nbytes + 2) / 3 * 4;
  assert_true(run + nchars <= file + size);
  assert_true(run[nchars] == '\n' || base64_value(run[nchars]) >= 0); /* the run ends here */
  unsigned char *bytes = malloc(nchars / 4 * 3);
  assert_non_null(bytes);
  assert_int_equal(base64_decode(run, nchars, bytes), 8 + *nbytes);
  memmove(bytes, bytes + 8, (size_t)*nbytes);
  return bytes;
}

static void expect_array(const char *file, size_t size, const char *xml_name, const void *values,
                         size_t nbytes) {
  uint64_t got = 0;
  unsigned char *data = appended_array(file, size, xml_name, &got);
  if (got != nbytes) fail_msg("%s: %llu bytes, expected %zu", xml_name, (unsigned long long)got, nbytes);
  if (nbytes && memcmp(data, values, nbytes) != 0) fail_msg("%s: values differ", xml_name);
  free(data);
}

static void check_with_c_reader(const char *path, const test_mesh *m) {
  size_t size;
  char *file = slurp(path, &size);
  assert_non_null(file);
  assert_non_null(strstr(file, "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                               "byte_order=\"LittleEndian\" header_type=\"UInt64\">"));
  char piece[128];
  snprintf(piece, sizeof piece, "<Piece NumberOfPoints=\"%d\" NumberOfCells=\"%d\">", NPTS, NCELLS);
  assert_non_null(strstr(file, piece));
  assert_non_null(strstr(file, "Name=\"sigma\" NumberOfComponents=\"6\""));
  assert_non_null(strstr(file, "Name=\"stress&lt;&amp;&quot;&apos;&gt;\" NumberOfComponents=\"6\""));
  expect_array(file, size, "Points", m->points, sizeof m->points);
  expect_array(file, size, "connectivity", m->conn, sizeof m->conn);
  expect_array(file, size, "offsets", m->offsets, sizeof m->offsets);
  expect_array(file, size, "types", m->types, sizeof m->types);
  expect_array(file, size, "T", m->T, sizeof m->T);
  expect_array(file, size, "u", m->u, sizeof m->u);
  expect_array(file, size, "sigma", m->sigma, sizeof m->sigma);
  expect_array(file, size, "damage", m->damage, sizeof m->damage);
  expect_array(file, size, "stress&lt;&amp;&quot;&apos;&gt;", m->stress, sizeof m->stress);
  assert_non_null(strstr(file + size - 40, "\n  </AppendedData>\n</VTKFile>\n"));
  free(file);
}

/* ---------------------------------------------------------------- reading back in Python */

/* Run read_vtu.py on @p path; returns its dump (caller frees) or fails the test. */
static char *python_dump(const char *path) {
  const char *dump = in_root("dump.txt");
  char cmd[4096];
  snprintf(cmd, sizeof cmd, "python3 '%s' '%s' '%s'",
           cupid_test_source_path("tests/tools/read_vtu.py"), path, dump);
  assert_int_equal(system(cmd), 0);
  char *text = slurp(dump, NULL);
  assert_non_null(text);
  return text;
}

/* Compare one dumped array with the expected values bit for bit. */
static void compare_dumped(char **cursor, const char *type, const void *expected, size_t count) {
  for (size_t i = 0; i < count; i++) {
    char *end;
    if (strcmp(type, "Float64") == 0) {
      double v = strtod(*cursor, &end); /* repr() is exact: bitwise equality is required */
      if (memcmp(&v, (const double *)expected + i, 8) != 0)
        fail_msg("value %zu: %.17g != %.17g", i, v, ((const double *)expected)[i]);
    } else {
      long long v = strtoll(*cursor, &end, 10);
      long long e = strcmp(type, "UInt8") == 0 ? ((const unsigned char *)expected)[i]
                                               : ((const int64_t *)expected)[i];
      if (v != e) fail_msg("value %zu: %lld != %lld", i, v, e);
    }
    assert_true(end != *cursor);
    *cursor = end;
  }
}

static void check_with_python(const char *path, const test_mesh *m) {
  char *text = python_dump(path);
  char *cursor = text;
  int npts, ncells, consumed;
  assert_int_equal(sscanf(cursor, "points %d cells %d%n", &npts, &ncells, &consumed), 2);
  assert_int_equal(npts, NPTS);
  assert_int_equal(ncells, NCELLS);
  cursor += consumed;
  struct {
    const char *section, *name, *type;
    int comps;
    const void *values;
    size_t count;
  } expect[] = {{"PointData", "T", "Float64", 1, m->T, NPTS},
                {"PointData", "u", "Float64", 3, m->u, 3 * NPTS},
                {"PointData", "sigma", "Float64", 6, m->sigma, 6 * NPTS},
                {"CellData", "damage", "Float64", 1, m->damage, NCELLS},
                {"CellData", "stress<&\"'>", "Float64", 6, m->stress, 6 * NCELLS},
                {"Points", "Points", "Float64", 3, m->points, 3 * NPTS},
                {"Cells", "connectivity", "Int64", 1, m->conn, NCONN},
                {"Cells", "offsets", "Int64", 1, m->offsets, NCELLS},
                {"Cells", "types", "UInt8", 1, m->types, NCELLS}};
  for (size_t a = 0; a < sizeof expect / sizeof expect[0]; a++) {
    char section[64], name[64], type[64];
    int comps;
    size_t count;
    assert_int_equal(sscanf(cursor, " array %63s %63s %63s %d %zu%n", section, name, type, &comps,
                            &count, &consumed), 5);
    cursor += consumed;
    assert_string_equal(section, expect[a].section);
    assert_string_equal(name, expect[a].name);
    assert_string_equal(type, expect[a].type);
    assert_int_equal(comps, expect[a].comps);
    assert_int_equal(count, expect[a].count);
    compare_dumped(&cursor, type, expect[a].values, count);
  }
  free(text);
}

/* ---------------------------------------------------------------- tests */

static void test_vtu_round_trip(void **state) {
  (void)state;
  test_mesh *m = calloc(1, sizeof *m);
  assert_non_null(m);
  make_mesh(m);
  const char *path = in_root("mesh.vtu");
  CUPID_ASSERT_OK(cupid_vtu_write(path, &m->mesh));
  check_with_c_reader(path, m);
  check_with_python(path, m);
  /* Overwriting works (atomic replace) and leaves exactly one file. */
  m->T[0] = 1234.5;
  CUPID_ASSERT_OK(cupid_vtu_write(path, &m->mesh));
  check_with_c_reader(path, m);
  free(m);
}

static void test_vtu_empty(void **state) {
  (void)state;
  /* No cells (points only) and nothing at all are both valid grids. */
  double p[6] = {0, 0, 0, 1, 2, 3};
  cupid_vtu_mesh mesh = {.n_points = 2, .points = p};
  CUPID_ASSERT_OK(cupid_vtu_write(in_root("points.vtu"), &mesh));
  char *text = python_dump(in_root("points.vtu"));
  assert_non_null(strstr(text, "points 2\ncells 0\n"));
  assert_non_null(strstr(text, "array Points Points Float64 3 6\n0.0\n0.0\n0.0\n1.0\n2.0\n3.0\n"));
  assert_non_null(strstr(text, "array Cells connectivity Int64 1 0\n"));
  free(text);
  cupid_vtu_mesh none = {0};
  CUPID_ASSERT_OK(cupid_vtu_write(in_root("none.vtu"), &none));
  text = python_dump(in_root("none.vtu"));
  assert_non_null(strstr(text, "points 0\ncells 0\n"));
  free(text);
}

/* Every length of the last base64 group (byte counts 8 + n = 0, 1, 2 mod 3 for both the
 * 1-byte types and the 8-byte values), read back by both readers. */
static void test_vtu_padding(void **state) {
  (void)state;
  double p[3 * 6], a[6];
  cupid_int conn[6], offs[6];
  unsigned char types[6];
  for (int i = 0; i < 6; i++) {
    for (int d = 0; d < 3; d++) p[3 * i + d] = 0.1 * i - 0.7 * d;
    a[i] = -1.0 / (i + 3);
    conn[i] = i;
    offs[i] = i + 1;
    types[i] = CUPID_VTK_VERTEX;
  }
  for (int n = 1; n <= 6; n++) {
    cupid_vtu_array pd[] = {{"a", 1, a}};
    cupid_vtu_mesh mesh = {.n_points = n, .points = p, .n_cells = n, .connectivity = conn,
                           .offsets = offs, .types = types, .point_data = pd, .n_point_data = 1};
    const char *path = in_root("pad.vtu");
    CUPID_ASSERT_OK(cupid_vtu_write(path, &mesh));
    size_t size;
    char *file = slurp(path, &size);
    assert_non_null(file);
    expect_array(file, size, "a", a, (size_t)n * 8);
    expect_array(file, size, "Points", p, (size_t)n * 24);
    expect_array(file, size, "connectivity", conn, (size_t)n * 8);
    expect_array(file, size, "offsets", offs, (size_t)n * 8);
    expect_array(file, size, "types", types, (size_t)n);
    free(file);
    char *text = python_dump(path);
    char expect[64];
    snprintf(expect, sizeof expect, "points %d\ncells %d\n", n, n);
    assert_non_null(strstr(text, expect));
    snprintf(expect, sizeof expect, "array Cells types UInt8 1 %d\n", n);
    assert_non_null(strstr(text, expect));
    free(text);
  }
}

static void test_vtu_rejects_bad_meshes(void **state) {
  (void)state;
  test_mesh *m = calloc(1, sizeof *m);
  assert_non_null(m);
  make_mesh(m);
  const char *path = in_root("bad.vtu");
  m->conn[3] = NPTS; /* a point that does not exist */
  assert_int_equal(cupid_vtu_write(path, &m->mesh), CUPID_ERR_ARGUMENT);
  assert_non_null(strstr(cupid_error_message(), "outside"));
  m->conn[3] = 0;
  m->offsets[2] = m->offsets[1]; /* an empty cell */
  assert_int_equal(cupid_vtu_write(path, &m->mesh), CUPID_ERR_ARGUMENT);
  make_mesh(m);
  m->pd[1].components = 0;
  assert_int_equal(cupid_vtu_write(path, &m->mesh), CUPID_ERR_ARGUMENT);
  make_mesh(m);
  m->cd[0].values = NULL;
  assert_int_equal(cupid_vtu_write(path, &m->mesh), CUPID_ERR_ARGUMENT);
  assert_int_equal(cupid_vtu_write(path, NULL), CUPID_ERR_ARGUMENT);
  assert_null(slurp(path, NULL)); /* nothing was created */
  make_mesh(m);
  assert_int_equal(cupid_vtu_write(in_root("no/such/dir/x.vtu"), &m->mesh), CUPID_ERR_IO);
  assert_non_null(strstr(cupid_error_message(), "no/such/dir/x.vtu"));
  free(m);
}

static void test_pvd(void **state) {
  (void)state;
  const char *files[] = {"beam.vtu", "pd.vtu", "step_1&2.vtu"};
  const double times[] = {0.0, 0.0, 2.5e-3};
  const int parts[] = {0, 1, 0};
  const char *path = in_root("model.pvd");
  CUPID_ASSERT_OK(cupid_pvd_write(path, 3, files, times, parts));
  char *text = slurp(path, NULL);
  assert_non_null(text);
  assert_string_equal(text,
                      "<?xml version=\"1.0\"?>\n"
                      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
                      "  <Collection>\n"
                      "    <DataSet timestep=\"0\" group=\"\" part=\"0\" name=\"beam\" "
                      "file=\"beam.vtu\"/>\n"
                      "    <DataSet timestep=\"0\" group=\"\" part=\"1\" name=\"pd\" "
                      "file=\"pd.vtu\"/>\n"
                      "    <DataSet timestep=\"0.0025\" group=\"\" part=\"0\" "
                      "name=\"step_1&amp;2\" file=\"step_1&amp;2.vtu\"/>\n"
                      "  </Collection>\n"
                      "</VTKFile>\n");
  free(text);
  /* Well-formed XML for an independent parser. */
  char cmd[2048];
  snprintf(cmd, sizeof cmd,
           "python3 -c 'import sys, xml.etree.ElementTree as E; r = E.parse(sys.argv[1]).getroot(); "
           "assert [d.get(\"file\") for d in r.iter(\"DataSet\")] == [\"beam.vtu\", \"pd.vtu\", "
           "\"step_1&2.vtu\"]' '%s'",
           path);
  assert_int_equal(system(cmd), 0);
  CUPID_ASSERT_OK(cupid_pvd_write(in_root("empty.pvd"), 0, NULL, NULL, NULL));
  const double bad[] = {NAN};
  assert_int_equal(cupid_pvd_write(in_root("bad.pvd"), 1, files, bad, NULL), CUPID_ERR_ARGUMENT);
  assert_int_equal(cupid_pvd_write(in_root("bad.pvd"), 2, NULL, NULL, NULL), CUPID_ERR_ARGUMENT);
  const int negative[] = {0, -1};
  assert_int_equal(cupid_pvd_write(in_root("bad.pvd"), 2, files, NULL, negative),
                   CUPID_ERR_ARGUMENT);
  assert_null(slurp(in_root("bad.pvd"), NULL));
}

/* Block names: given, or from the file names without a step number; default parts number the
 * distinct names (a time series of two blocks: pd and beam at every time). */
static void test_pvd_names(void **state) {
  (void)state;
  const char *files[] = {"pd_000000.vtu", "beam_000000.vtu", "pd_000100.vtu", "beam_000100.vtu",
                         "dir/x_1.vtu",   "_7.vtu",          "run_2b.vtu"};
  const double times[] = {0.0, 0.0, 1e-3, 1e-3, 0.0, 0.0, 0.0};
  const char *path = in_root("series.pvd");
  CUPID_ASSERT_OK(cupid_pvd_write(path, 7, files, times, NULL));
  char *text = slurp(path, NULL);
  assert_non_null(text);
  assert_string_equal(text,
                      "<?xml version=\"1.0\"?>\n"
                      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
                      "  <Collection>\n"
                      "    <DataSet timestep=\"0\" group=\"\" part=\"0\" name=\"pd\" "
                      "file=\"pd_000000.vtu\"/>\n"
                      "    <DataSet timestep=\"0\" group=\"\" part=\"1\" name=\"beam\" "
                      "file=\"beam_000000.vtu\"/>\n"
                      "    <DataSet timestep=\"0.001\" group=\"\" part=\"0\" name=\"pd\" "
                      "file=\"pd_000100.vtu\"/>\n"
                      "    <DataSet timestep=\"0.001\" group=\"\" part=\"1\" name=\"beam\" "
                      "file=\"beam_000100.vtu\"/>\n"
                      "    <DataSet timestep=\"0\" group=\"\" part=\"2\" name=\"x\" "
                      "file=\"dir/x_1.vtu\"/>\n"
                      "    <DataSet timestep=\"0\" group=\"\" part=\"3\" name=\"_7\" "
                      "file=\"_7.vtu\"/>\n"
                      "    <DataSet timestep=\"0\" group=\"\" part=\"4\" name=\"run_2b\" "
                      "file=\"run_2b.vtu\"/>\n"
                      "  </Collection>\n"
                      "</VTKFile>\n");
  free(text);
  /* Given names (escaped; a NULL or empty entry falls back to the file) and parts. */
  const char *names[] = {"PD <nodes>", NULL, ""};
  const int parts[] = {3, 0, 7};
  CUPID_ASSERT_OK(cupid_pvd_write_named(path, 3, files, names, NULL, parts));
  text = slurp(path, NULL);
  assert_non_null(text);
  assert_non_null(strstr(text, "\n    <DataSet timestep=\"0\" group=\"\" part=\"3\" "
                               "name=\"PD &lt;nodes&gt;\" file=\"pd_000000.vtu\"/>\n"
                               "    <DataSet timestep=\"0\" group=\"\" part=\"0\" name=\"beam\" "
                               "file=\"beam_000000.vtu\"/>\n"
                               "    <DataSet timestep=\"0\" group=\"\" part=\"7\" name=\"pd\" "
                               "file=\"pd_000100.vtu\"/>\n  </Collection>"));
  free(text);
}

/* 10^6 PD-like nodes as vertex cells with displacement and damage: every array comes back
 * bit for bit at the size of a large grid (97 MB). Its write time is a figure
 * of bench/bench_vtu_write.c, not an assertion here (a timed test fails on a loaded machine
 * or under valgrind). */
static void test_vtu_large(void **state) {
  (void)state;
  const cupid_int n = 1000000;
  double *points, *u, *damage;
  cupid_int *conn, *offsets;
  unsigned char *types;
  CUPID_ASSERT_OK(cupid_malloc((size_t)n * 3, sizeof *points, "points", &points));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n * 3, sizeof *u, "u", &u));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n, sizeof *damage, "damage", &damage));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n, sizeof *conn, "conn", &conn));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n, sizeof *offsets, "offsets", &offsets));
  CUPID_ASSERT_OK(cupid_malloc((size_t)n, sizeof *types, "types", &types));
  for (cupid_int i = 0; i < n; i++) {
    for (int d = 0; d < 3; d++) {
      points[3 * i + d] = (double)(i % 100 + d);
      u[3 * i + d] = 1e-6 * (double)i;
    }
    damage[i] = (double)(i % 7) / 7.0;
    conn[i] = i;
    offsets[i] = i + 1;
    types[i] = CUPID_VTK_VERTEX;
  }
  cupid_vtu_array pd[] = {{"u", 3, u}, {"damage", 1, damage}};
  cupid_vtu_mesh mesh = {.n_points = n, .points = points, .n_cells = n, .connectivity = conn,
                         .offsets = offsets, .types = types, .point_data = pd, .n_point_data = 2};
  const char *path = in_root("big.vtu");
  CUPID_ASSERT_OK(cupid_vtu_write(path, &mesh));
  size_t size;
  char *file = slurp(path, &size);
  assert_non_null(file);
  expect_array(file, size, "Points", points, (size_t)n * 24);
  expect_array(file, size, "u", u, (size_t)n * 24);
  expect_array(file, size, "damage", damage, (size_t)n * 8);
  expect_array(file, size, "types", types, (size_t)n);
  free(file);
  cupid_free(&points);
  cupid_free(&u);
  cupid_free(&damage);
  cupid_free(&conn);
  cupid_free(&offsets);
  cupid_free(&types);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_vtu_round_trip, setup, teardown),
      cmocka_unit_test_setup_teardown(test_vtu_empty, setup, teardown),
      cmocka_unit_test_setup_teardown(test_vtu_padding, setup, teardown),
      cmocka_unit_test_setup_teardown(test_vtu_rejects_bad_meshes, setup, teardown),
      cmocka_unit_test_setup_teardown(test_pvd, setup, teardown),
      cmocka_unit_test_setup_teardown(test_pvd_names, setup, teardown),
      cmocka_unit_test_setup_teardown(test_vtu_large, setup, teardown),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
