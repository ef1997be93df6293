/*
 * Streaming JSON writer (see include/cupid/io.h): RFC 8259 output, pretty printed.
 * The writer keeps a stack of open containers and how many members each has so far, which
 * is all that is needed to place commas, newlines and indentation.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cupid/io.h"
#include "io/io_internal.h"

#define JSON_MAX_DEPTH 64

enum { JSON_OBJECT = 1, JSON_ARRAY = 2 };

struct cupid_json_private {
  FILE *out;
  int depth;                   /* open containers */
  int ignored;                 /* containers opened beyond JSON_MAX_DEPTH (not written) */
  int done;                    /* the top-level value is complete */
  char kind[JSON_MAX_DEPTH];   /* JSON_OBJECT or JSON_ARRAY */
  int64_t count[JSON_MAX_DEPTH];
  char misuse[256];            /* the first misuse, "" if none */
};

void cupid_io_format_double(double v, char *buf, size_t size) {
  /* %.15g reads nicer (0.1 not 0.10000000000000001); %.17g always round-trips. */
  if (v == 0.0 && signbit(v)) { /* "-0" would read back as the integer 0 in many parsers */
    snprintf(buf, size, "-0.0");
    return;
  }
  snprintf(buf, size, "%.15g", v);
  if (strtod(buf, NULL) != v) snprintf(buf, size, "%.17g", v);
  /* Under a decimal-comma LC_NUMERIC (set by some host program) printf writes "0,5". */
  for (char *c = buf; *c; c++)
    if (*c == ',') *c = '.';
}

static void json_misuse(cupid_json j, const char *what) {
  if (!j->misuse[0]) snprintf(j->misuse, sizeof j->misuse, "%s", what);
}

cupid_status cupid_json_create(FILE *stream, cupid_json *json) {
  CUPID_CHECK(json, CUPID_ERR_ARGUMENT, "cupid_json_create: NULL handle");
  *json = NULL;
  CUPID_CHECK(stream, CUPID_ERR_ARGUMENT, "cupid_json_create: NULL stream");
  CUPID_CALL(cupid_calloc(1, sizeof **json, "JSON writer", json));
  (*json)->out = stream;
  return CUPID_SUCCESS;
}

void cupid_json_destroy(cupid_json *json) { cupid_free(json); }

/* Length of the valid UTF-8 sequence starting at s (s[0] >= 0x80), 0 if invalid (RFC 3629). */
static int utf8_sequence_length(const unsigned char *s) {
  unsigned c = s[0];
  unsigned lo = 0x80, hi = 0xBF;
  if (c >= 0xC2 && c <= 0xDF) return (s[1] & 0xC0) == 0x80 ? 2 : 0;
  if (c >= 0xE0 && c <= 0xEF) {
    if (c == 0xE0) lo = 0xA0; /* overlong */
    if (c == 0xED) hi = 0x9F; /* UTF-16 surrogates */
    return s[1] >= lo && s[1] <= hi && (s[2] & 0xC0) == 0x80 ? 3 : 0;
  }
  if (c >= 0xF0 && c <= 0xF4) {
    if (c == 0xF0) lo = 0x90; /* overlong */
    if (c == 0xF4) hi = 0x8F; /* beyond U+10FFFF */
    return s[1] >= lo && s[1] <= hi && (s[2] & 0xC0) == 0x80 && (s[3] & 0xC0) == 0x80 ? 4 : 0;
  }
  return 0;
}

/* Write a quoted, escaped string. Runs of plain bytes go out with one fwrite. */
static void json_write_string(FILE *out, const char *str) {
  const unsigned char *s = (const unsigned char *)str;
  fputc('"', out);
  const unsigned char *run = s;
  while (*s) {
    unsigned c = *s;
    int len = 1;
    const char *esc = NULL;
    char ubuf[8];
    if (c == '"') esc = "\\\"";
    else if (c == '\\') esc = "\\\\";
    else if (c == '\n') esc = "\\n";
    else if (c == '\t') esc = "\\t";
    else if (c == '\r') esc = "\\r";
    else if (c == '\b') esc = "\\b";
    else if (c == '\f') esc = "\\f";
    else if (c < 0x20) {
      snprintf(ubuf, sizeof ubuf, "\\u%04x", c);
      esc = ubuf;
    } else if (c >= 0x80) {
      len = utf8_sequence_length(s);
      if (len == 0) {
        esc = "\\ufffd"; /* keep the document valid UTF-8 whatever the input */
        len = 1;
      }
    }
    if (esc) {
      fwrite(run, 1, (size_t)(s - run), out);
      fputs(esc, out);
      s += len;
      run = s;
    } else {
      s += len;
    }
  }
  fwrite(run, 1, (size_t)(s - run), out);
  fputc('"', out);
}

/* Place a new value: comma, newline, indentation, key. Returns 0 if it must not be written. */
static int json_prefix(cupid_json j, const char *key) {
  if (j->ignored) return 0;
  if (j->depth == 0) {
    if (j->done) {
      json_misuse(j, "a second top-level value");
      return 0;
    }
    if (key) json_misuse(j, "a key on the top-level value (ignored)");
    return 1;
  }
  int top = j->depth - 1;
  if (j->count[top] > 0) fputc(',', j->out);
  fputc('\n', j->out);
  for (int i = 0; i < j->depth; i++) fputs("  ", j->out);
  if (j->kind[top] == JSON_OBJECT) {
    if (!key) {
      json_misuse(j, "a value without a key inside an object");
      key = "";
    }
    json_write_string(j->out, key);
    fputs(": ", j->out);
  } else if (key) {
    json_misuse(j, "a key inside an array (ignored)");
  }
  j->count[top]++;
  return 1;
}

/* After a complete value: the document ends with the top-level value. */
static void json_value_done(cupid_json j) {
  if (j->depth == 0) {
    fputc('\n', j->out);
    j->done = 1;
  }
}

static void json_begin(cupid_json j, const char *key, int kind) {
  if (!j) return;
  if (j->ignored || j->depth == JSON_MAX_DEPTH) {
    if (!j->ignored) json_misuse(j, "nesting deeper than 64 levels (ignored)");
    j->ignored++;
    return;
  }
  if (!json_prefix(j, key)) {
    j->ignored++; /* swallow the contents of a container that cannot be written */
    return;
  }
  fputc(kind == JSON_OBJECT ? '{' : '[', j->out);
  j->kind[j->depth] = (char)kind;
  j->count[j->depth] = 0;
  j->depth++;
}

static void json_end(cupid_json j, int kind) {
  if (!j) return;
  if (j->ignored) {
    j->ignored--;
    return;
  }
  if (j->depth == 0 || j->kind[j->depth - 1] != kind) {
    json_misuse(j, kind == JSON_OBJECT ? "end_object without a matching begin_object"
                                       : "end_array without a matching begin_array");
    return;
  }
  if (j->count[j->depth - 1] > 0) {
    fputc('\n', j->out);
    for (int i = 0; i < j->depth - 1; i++) fputs("  ", j->out);
  }
  fputc(kind == JSON_OBJECT ? '}' : ']', j->out);
  j->depth--;
  json_value_done(j);
}

void cupid_json_begin_object(cupid_json json, const char *key) { json_begin(json, key, JSON_OBJECT); }
void cupid_json_end_object(cupid_json json) { json_end(json, JSON_OBJECT); }
void cupid_json_begin_array(cupid_json json, const char *key) { json_begin(json, key, JSON_ARRAY); }
void cupid_json_end_array(cupid_json json) { json_end(json, JSON_ARRAY); }

/* Write a scalar given as literal text. */
static void json_scalar(cupid_json j, const char *key, const char *text) {
  if (!j || !json_prefix(j, key)) return;
  fputs(text, j->out);
  json_value_done(j);
}

void cupid_json_string(cupid_json json, const char *key, const char *value) {
  if (!value) {
    json_scalar(json, key, "null");
    return;
  }
  if (!json || !json_prefix(json, key)) return;
  json_write_string(json->out, value);
  json_value_done(json);
}

void cupid_json_number(cupid_json json, const char *key, double value) {
  char buf[40];
  if (!isfinite(value)) { /* JSON has no NaN or Infinity */
    json_scalar(json, key, "null");
    return;
  }
  cupid_io_format_double(value, buf, sizeof buf);
  json_scalar(json, key, buf);
}

void cupid_json_integer(cupid_json json, const char *key, int64_t value) {
  char buf[32];
  snprintf(buf, sizeof buf, "%lld", (long long)value);
  json_scalar(json, key, buf);
}

void cupid_json_bool(cupid_json json, const char *key, int value) {
  json_scalar(json, key, value ? "true" : "false");
}

void cupid_json_null(cupid_json json, const char *key) { json_scalar(json, key, "null"); }

cupid_status cupid_json_status(cupid_json json) {
  CUPID_CHECK(json, CUPID_ERR_ARGUMENT, "cupid_json_status: NULL handle");
  CUPID_CHECK(!json->misuse[0], CUPID_ERR_INTERNAL, "JSON writer misused: %s", json->misuse);
  CUPID_CHECK(json->depth == 0 && !json->ignored, CUPID_ERR_INTERNAL,
              "JSON writer misused: %d container(s) left open", json->depth + json->ignored);
  CUPID_CHECK(json->done, CUPID_ERR_INTERNAL, "JSON writer misused: nothing written");
  CUPID_CHECK(!ferror(json->out), CUPID_ERR_IO, "writing JSON failed");
  return CUPID_SUCCESS;
}
