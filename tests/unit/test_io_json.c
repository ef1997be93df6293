/* Unit tests of the JSON writer (src/io/json.c). */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

/* A writer on a memory stream; finish() returns the text (caller frees). */
typedef struct {
  FILE *stream;
  char *text;
  size_t size;
  cupid_json json;
} memdoc;

static void start(memdoc *d) {
  d->text = NULL;
  d->size = 0;
  d->stream = open_memstream(&d->text, &d->size);
  assert_non_null(d->stream);
  CUPID_ASSERT_OK(cupid_json_create(d->stream, &d->json));
}

static cupid_status finish(memdoc *d) {
  cupid_status st = cupid_json_status(d->json);
  cupid_json_destroy(&d->json);
  assert_null(d->json);
  assert_int_equal(fclose(d->stream), 0);
  return st;
}

static void test_exact_text(void **state) {
  (void)state;
  memdoc d;
  start(&d);
  cupid_json j = d.json;
  cupid_json_begin_object(j, NULL);
  cupid_json_string(j, "name", "bar \"1\"");
  cupid_json_integer(j, "n", 3);
  cupid_json_number(j, "x", 0.1);
  cupid_json_number(j, "third", 1.0 / 3.0);
  cupid_json_begin_object(j, "empty");
  cupid_json_end_object(j);
  cupid_json_begin_array(j, "list");
  cupid_json_integer(j, NULL, 1);
  cupid_json_null(j, NULL);
  cupid_json_bool(j, NULL, 1);
  cupid_json_begin_object(j, NULL);
  cupid_json_number(j, "nan", NAN);
  cupid_json_end_object(j);
  cupid_json_begin_array(j, NULL);
  cupid_json_end_array(j);
  cupid_json_end_array(j);
  cupid_json_bool(j, "off", 0);
  cupid_json_string(j, "none", NULL);
  cupid_json_end_object(j);
  CUPID_ASSERT_OK(finish(&d));
  const char *expected = "{\n"
                         "  \"name\": \"bar \\\"1\\\"\",\n"
                         "  \"n\": 3,\n"
                         "  \"x\": 0.1,\n"
                         "  \"third\": 0.33333333333333331,\n"
                         "  \"empty\": {},\n"
                         "  \"list\": [\n"
                         "    1,\n"
                         "    null,\n"
                         "    true,\n"
                         "    {\n"
                         "      \"nan\": null\n"
                         "    },\n"
                         "    []\n"
                         "  ],\n"
                         "  \"off\": false,\n"
                         "  \"none\": null\n"
                         "}\n";
  assert_string_equal(d.text, expected);
  free(d.text);
}

static void test_escapes(void **state) {
  (void)state;
  memdoc d;
  start(&d);
  /* quote, backslash, newline, tab, 0x01, 0x1f, DEL (no escape), UTF-8 (2, 3, 4 bytes),
   * then invalid UTF-8: a lone continuation byte, a truncated sequence, an overlong '/'. */
  cupid_json_string(d.json, NULL,
                    "q\"b\\n\n\t\x01\x1f\x7f \xc2\xb5\xe2\x82\xac\xf0\x9d\x84\x9e \x80|\xe2\x82|\xc0\xaf");
  CUPID_ASSERT_OK(finish(&d));
  assert_string_equal(d.text, "\"q\\\"b\\\\n\\n\\t\\u0001\\u001f\x7f \xc2\xb5\xe2\x82\xac"
                              "\xf0\x9d\x84\x9e \\ufffd|\\ufffd\\ufffd|\\ufffd\\ufffd\"\n");
  free(d.text);
}

/* Write @p text to @p path (plain stdio; the file is test input). */
static void write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  assert_int_equal(fclose(f), 0);
}

/* Python's json module checks the document and writes back the values it read (float(v):
 * an integral double such as 12345678901234568 is written without exponent, read as int). */
static const char *checker =
    "import json, sys\n"
    "d = json.load(open(sys.argv[1], encoding='utf-8'))\n"
    "assert d['s'] == 'q\"b\\\\n\\n\\x01\\u00b5\\u20ac\\U0001d11e\\ufffd', repr(d['s'])\n"
    "assert d['nested']['a'][1]['deep'] == [None, None, None], d['nested']\n"
    "assert d['nested']['a'][0] == 'x' and d['nested']['b'] == {}\n"
    "assert d['imin'] == -9223372036854775808 and d['imax'] == 9223372036854775807\n"
    "assert d['t'] is True and d['f'] is False and d['z'] is None\n"
    "assert d['x'] == 0.1 and d['big'] == 1e300 and d['tiny'] == 5e-324\n"
    "assert d['negzero'] == 0.0 and str(d['negzero']) == '-0.0'\n"
    "assert d['\\u00b5 key \"q\"'] == 1\n"
    "with open(sys.argv[2], 'w') as out:\n"
    "    for v in d['random']: out.write(float.hex(float(v)) + '\\n')\n";

static char dir[64]; /* a fresh directory for test_python_parses */

static int setup(void **state) {
  (void)state;
  return cupid_test_mkdtemp("json", dir, sizeof dir);
}

static int teardown(void **state) { /* runs after a failure too */
  (void)state;
  return cupid_test_rmtree(dir);
}

static void test_python_parses(void **state) {
  (void)state;
  char json_path[512], py_path[512], hex_path[512], cmd[2048];
  snprintf(json_path, sizeof json_path, "%s/doc.json", dir);
  snprintf(py_path, sizeof py_path, "%s/check.py", dir);
  snprintf(hex_path, sizeof hex_path, "%s/values.txt", dir);
  write_text(py_path, checker);

  enum { N = 2000 };
  double values[N];
  uint64_t seed = 7;
  for (int i = 0; i < N; i++) /* spread over many decades to exercise %.15g vs %.17g */
    values[i] = cupid_test_random(&seed) * pow(10.0, 300.0 * cupid_test_random(&seed));
  values[0] = DBL_MAX;
  values[1] = -DBL_MIN;
  values[2] = 4.9406564584124654e-324;

  cupid_atomic_file file = NULL;
  CUPID_ASSERT_OK(cupid_atomic_open(json_path, &file));
  cupid_json j = NULL;
  CUPID_ASSERT_OK(cupid_json_create(cupid_atomic_stream(file), &j));
  cupid_json_begin_object(j, NULL);
  cupid_json_string(j, "s", "q\"b\\n\n\x01\xc2\xb5\xe2\x82\xac\xf0\x9d\x84\x9e\xff");
  cupid_json_begin_object(j, "nested");
  cupid_json_begin_array(j, "a");
  cupid_json_string(j, NULL, "x");
  cupid_json_begin_object(j, NULL);
  cupid_json_begin_array(j, "deep");
  cupid_json_number(j, NULL, NAN);
  cupid_json_number(j, NULL, INFINITY);
  cupid_json_number(j, NULL, -INFINITY);
  cupid_json_end_array(j);
  cupid_json_end_object(j);
  cupid_json_end_array(j);
  cupid_json_begin_object(j, "b");
  cupid_json_end_object(j);
  cupid_json_end_object(j);
  cupid_json_integer(j, "imin", INT64_MIN);
  cupid_json_integer(j, "imax", INT64_MAX);
  cupid_json_bool(j, "t", 5);
  cupid_json_bool(j, "f", 0);
  cupid_json_null(j, "z");
  cupid_json_number(j, "x", 0.1);
  cupid_json_number(j, "big", 1e300);
  cupid_json_number(j, "tiny", 5e-324);
  cupid_json_number(j, "negzero", -0.0);
  cupid_json_integer(j, "\xc2\xb5 key \"q\"", 1);
  cupid_json_begin_array(j, "random");
  for (int i = 0; i < N; i++) cupid_json_number(j, NULL, values[i]);
  cupid_json_end_array(j);
  cupid_json_end_object(j);
  CUPID_ASSERT_OK(cupid_json_status(j));
  cupid_json_destroy(&j);
  CUPID_ASSERT_OK(cupid_atomic_commit(&file));

  snprintf(cmd, sizeof cmd, "python3 '%s' '%s' '%s'", py_path, json_path, hex_path);
  assert_int_equal(system(cmd), 0);
  /* Every number must read back bit for bit (exact round trip, no tolerance). */
  FILE *in = fopen(hex_path, "r");
  assert_non_null(in);
  char line[128];
  int n = 0;
  while (fgets(line, sizeof line, in)) {
    assert_true(n < N);
    double v = strtod(line, NULL); /* C99 reads Python's float.hex exactly */
    if (memcmp(&v, &values[n], sizeof v) != 0)
      fail_msg("value %d: wrote %.17g, read back %.17g", n, values[n], v);
    n++;
  }
  fclose(in);
  assert_int_equal(n, N);
}

static void expect_misuse(memdoc *d, const char *fragment) {
  cupid_status st = finish(d);
  assert_int_equal(st, CUPID_ERR_INTERNAL);
  if (!strstr(cupid_error_message(), fragment))
    fail_msg("message '%s' lacks '%s'", cupid_error_message(), fragment);
  free(d->text);
}

static void test_misuse_does_not_crash(void **state) {
  (void)state;
  memdoc d;
  /* Unbalanced ends. */
  start(&d);
  cupid_json_end_object(d.json);
  cupid_json_end_array(d.json);
  cupid_json_begin_array(d.json, NULL);
  cupid_json_end_object(d.json); /* wrong kind: ignored */
  cupid_json_end_array(d.json);
  assert_string_equal(d.text ? d.text : "", ""); /* not flushed yet: check after finish */
  expect_misuse(&d, "end_object without a matching begin_object");

  start(&d);
  cupid_json_begin_object(d.json, NULL);
  cupid_json_integer(d.json, NULL, 1); /* no key in an object: written with key "" */
  cupid_json_end_object(d.json);
  expect_misuse(&d, "without a key");

  start(&d);
  cupid_json_integer(d.json, NULL, 1);
  cupid_json_integer(d.json, NULL, 2);
  expect_misuse(&d, "second top-level value");

  start(&d);
  cupid_json_begin_object(d.json, NULL);
  cupid_json_begin_array(d.json, "a");
  expect_misuse(&d, "2 container(s) left open");

  start(&d);
  expect_misuse(&d, "nothing written");

  /* Nesting beyond 64 levels: the deep part is dropped, the document stays balanced. */
  start(&d);
  for (int i = 0; i < 100; i++) cupid_json_begin_array(d.json, NULL);
  cupid_json_integer(d.json, NULL, 1);
  for (int i = 0; i < 100; i++) cupid_json_end_array(d.json);
  cupid_json_end_array(d.json); /* one too many */
  expect_misuse(&d, "deeper than 64");

  /* A NULL writer is ignored by every function. */
  cupid_json_begin_object(NULL, "a");
  cupid_json_number(NULL, "a", 1.0);
  cupid_json_string(NULL, "a", "b");
  cupid_json_end_object(NULL);
  cupid_json_destroy(NULL);
  assert_int_equal(cupid_json_status(NULL), CUPID_ERR_ARGUMENT);
  cupid_json j = (cupid_json)1;
  assert_int_equal(cupid_json_create(NULL, &j), CUPID_ERR_ARGUMENT);
  assert_null(j);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_exact_text), cmocka_unit_test(test_escapes),
                                     cmocka_unit_test_setup_teardown(test_python_parses, setup, teardown),
                                     cmocka_unit_test(test_misuse_does_not_crash)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
