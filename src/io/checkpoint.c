/* Checkpoint files (issue 36): the state a long run needs to continue, as named binary
 * sections, written durably and read back only when intact.
 *
 * Layout (native byte order; a checkpoint is read back on the machine that wrote it):
 *   "CUPIDCK1"                         8 bytes
 *   u64 section count
 *   per section: u32 name length, the name, u64 byte count, the bytes
 *   u32 CRC-32 (zlib) of everything above, "CKEND001"
 * The first section is "identity": the caller's description of what the results depend on
 * (the model file's contents and the options that change results). Opening compares it and
 * refuses a checkpoint of another model or other options, naming both.
 *
 * Writing: a temporary sibling, fsync'ed, renamed over PATH, the directory fsync'ed
 * (cupid_atomic_set_durable); the checkpoint it replaces is kept as PATH.prev (a hard link made
 * before the rename). Reading: PATH if intact (magic, CRC, trailer, sizes), else PATH.prev,
 * else CUPID_ERR_IO. So a run killed at any moment, a flipped byte or a disk that fills while
 * writing leaves an intact checkpoint: the new one, or the previous. */
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#include "cupid/io.h"

#define CK_MAGIC "CUPIDCK1"
#define CK_END "CKEND001"
#define CK_NAME_MAX 256

struct cupid_checkpoint_writer_private {
  cupid_atomic_file file;
  char *path;
  uLong crc;        /* CRC-32 of the bytes after the section count */
  z_off_t length;   /* ... and their number */
  uint64_t count;   /* sections: written after the magic, in place, at the end */
};

struct cupid_checkpoint_private {
  unsigned char *data; /* the whole file */
  uint64_t count;
  int previous;       /* 1: read from PATH.prev */
};

static cupid_status put_raw(cupid_checkpoint_writer w, const void *p, size_t n) {
  FILE *f = cupid_atomic_stream(w->file);
  if (n && fwrite(p, 1, n, f) != n)
    return CUPID_ERROR(CUPID_ERR_IO, "cannot write checkpoint '%s': %s", w->path, strerror(errno));
  return CUPID_SUCCESS;
}

/* Bytes after the section count: written and added to the running CRC. */
static cupid_status put(cupid_checkpoint_writer w, const void *p, size_t n) {
  CUPID_CALL(put_raw(w, p, n));
  w->crc = crc32_z(w->crc, p, n);
  w->length += (z_off_t)n;
  return CUPID_SUCCESS;
}

cupid_status cupid_checkpoint_write_begin(const char *path, const char *identity,
                                          cupid_checkpoint_writer *out) {
  CUPID_CHECK(path && identity && out, CUPID_ERR_ARGUMENT, "checkpoint: NULL argument");
  *out = NULL;
  cupid_checkpoint_writer w = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_CALL(cupid_calloc(1, sizeof *w, "checkpoint writer", &w));
  CUPID_TRY(cupid_strdup(path, &w->path));
  CUPID_TRY(cupid_atomic_open(path, &w->file));
  cupid_atomic_set_durable(w->file);
  w->crc = crc32_z(0L, Z_NULL, 0);
  /* the count is not known yet: a placeholder, written in place at the end; the file's CRC is
   * then combined from its three parts (crc32_combine), nothing is read back */
  const uint64_t zero = 0;
  CUPID_TRY(put_raw(w, CK_MAGIC, 8));
  CUPID_TRY(put_raw(w, &zero, sizeof zero));
  CUPID_TRY(cupid_checkpoint_write(w, "identity", identity, strlen(identity)));
  *out = w;
  return CUPID_SUCCESS;
cleanup:
  cupid_checkpoint_write_abort(&w);
  return st;
}

cupid_status cupid_checkpoint_write(cupid_checkpoint_writer w, const char *name, const void *data,
                                    size_t bytes) {
  CUPID_CHECK(w && name && (data || !bytes), CUPID_ERR_ARGUMENT, "checkpoint: NULL argument");
  const size_t len = strlen(name);
  CUPID_CHECK(len > 0 && len < CK_NAME_MAX, CUPID_ERR_ARGUMENT,
              "checkpoint: a section name of 1 to %d characters", CK_NAME_MAX - 1);
  const uint32_t l = (uint32_t)len;
  const uint64_t b = (uint64_t)bytes;
  CUPID_CALL(put(w, &l, sizeof l));
  CUPID_CALL(put(w, name, len));
  CUPID_CALL(put(w, &b, sizeof b));
  CUPID_CALL(put(w, data, bytes));
  w->count++;
  return CUPID_SUCCESS;
}

cupid_status cupid_checkpoint_write_commit(cupid_checkpoint_writer *wp) {
  CUPID_CHECK(wp && *wp, CUPID_ERR_ARGUMENT, "checkpoint: NULL writer");
  cupid_checkpoint_writer w = *wp;
  cupid_status st = CUPID_SUCCESS;
  FILE *f = cupid_atomic_stream(w->file);
  CUPID_TRY_CHECK(!ferror(f), CUPID_ERR_IO, "cannot write checkpoint '%s'", w->path);
  CUPID_TRY_CHECK(fseek(f, 8, SEEK_SET) == 0 && fwrite(&w->count, sizeof w->count, 1, f) == 1 &&
                      fseek(f, 0, SEEK_END) == 0,
                  CUPID_ERR_IO, "cannot write checkpoint '%s': %s", w->path, strerror(errno));
  uLong head = crc32_z(crc32_z(0L, Z_NULL, 0), (const Bytef *)CK_MAGIC, 8);
  head = crc32_z(head, (const Bytef *)&w->count, sizeof w->count);
  const uLong crc = crc32_combine(head, w->crc, w->length);
  const uint32_t c = (uint32_t)crc;
  CUPID_TRY_CHECK(fwrite(&c, sizeof c, 1, f) == 1 && fwrite(CK_END, 8, 1, f) == 1, CUPID_ERR_IO,
                  "cannot write checkpoint '%s': %s", w->path, strerror(errno));
  { /* keep the checkpoint this one replaces as PATH.prev */
    char prev[4096];
    snprintf(prev, sizeof prev, "%s.prev", w->path);
    if (access(w->path, F_OK) == 0) {
      (void)unlink(prev);
      CUPID_TRY_CHECK(link(w->path, prev) == 0, CUPID_ERR_IO,
                      "cannot keep the previous checkpoint as '%s': %s", prev, strerror(errno));
    }
  }
  st = cupid_atomic_commit(&w->file);
cleanup:
  cupid_checkpoint_write_abort(wp);
  return st;
}

void cupid_checkpoint_write_abort(cupid_checkpoint_writer *wp) {
  if (!wp || !*wp) return;
  cupid_atomic_abort(&(*wp)->file);
  cupid_free(&(*wp)->path);
  cupid_free(wp);
}

/* ---- reading ---- */

/* The file at path, whole, into *data (NULL when it does not exist). */
static cupid_status slurp(const char *path, unsigned char **data, size_t *size) {
  *data = NULL, *size = 0;
  FILE *f = fopen(path, "rb");
  if (!f) {
    if (errno == ENOENT) return CUPID_SUCCESS;
    return CUPID_ERROR(CUPID_ERR_IO, "cannot read checkpoint '%s': %s", path, strerror(errno));
  }
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY_CHECK(fseek(f, 0, SEEK_END) == 0, CUPID_ERR_IO, "cannot read checkpoint '%s'", path);
  const long n = ftell(f);
  CUPID_TRY_CHECK(n >= 0 && fseek(f, 0, SEEK_SET) == 0, CUPID_ERR_IO, "cannot read checkpoint '%s'",
                  path);
  CUPID_TRY(cupid_malloc((size_t)n + 1, 1, "checkpoint", data));
  CUPID_TRY_CHECK(fread(*data, 1, (size_t)n, f) == (size_t)n, CUPID_ERR_IO,
                  "cannot read checkpoint '%s': short read", path);
  *size = (size_t)n;
cleanup:
  fclose(f);
  if (st != CUPID_SUCCESS) cupid_free(data);
  return st;
}

/* Walk the sections: 1 when the bytes are a whole, intact checkpoint (*count set). */
static int intact(const unsigned char *d, size_t n, uint64_t *count) {
  if (n < 8 + 8 + 4 + 8 || memcmp(d, CK_MAGIC, 8) != 0 || memcmp(d + n - 8, CK_END, 8) != 0)
    return 0;
  uint32_t c;
  memcpy(&c, d + n - 12, sizeof c);
  if ((uint32_t)crc32_z(crc32_z(0L, Z_NULL, 0), d, n - 12) != c) return 0;
  memcpy(count, d + 8, sizeof *count);
  size_t at = 16;
  for (uint64_t k = 0; k < *count; k++) {
    uint32_t l;
    uint64_t b;
    if (at + 4 > n - 12) return 0;
    memcpy(&l, d + at, 4);
    if (l == 0 || l >= CK_NAME_MAX || at + 4 + l + 8 > n - 12) return 0;
    memcpy(&b, d + at + 4 + l, 8);
    if (b > n - 12 - (at + 12 + l)) return 0;
    at += 12 + l + (size_t)b;
  }
  return at == n - 12;
}

/* Section `name` of an intact checkpoint: its bytes and size, or *p = NULL. */
static void find(const struct cupid_checkpoint_private *ck, const char *name, const unsigned char **p,
                 size_t *bytes) {
  size_t at = 16;
  const size_t len = strlen(name);
  *p = NULL, *bytes = 0;
  for (uint64_t k = 0; k < ck->count; k++) {
    uint32_t l;
    uint64_t b;
    memcpy(&l, ck->data + at, 4);
    memcpy(&b, ck->data + at + 4 + l, 8);
    if (l == len && memcmp(ck->data + at + 4, name, len) == 0) {
      *p = ck->data + at + 12 + l;
      *bytes = (size_t)b;
      return;
    }
    at += 12 + l + (size_t)b;
  }
}

/* The offset of the first line where identity a (na bytes) and b differ, and that line's
 * length in each. */
static size_t first_difference(const char *a, size_t na, const char *b, int *la, int *lb) {
  const size_t nb = strlen(b);
  size_t line = 0, k = 0;
  while (k < na && k < nb && a[k] == b[k]) {
    if (a[k] == '\n') line = k + 1;
    k++;
  }
  size_t ea = line, eb = line;
  while (ea < na && a[ea] != '\n') ea++;
  while (eb < nb && b[eb] != '\n') eb++;
  *la = (int)(ea - line);
  *lb = (int)(eb - line);
  return line;
}

/* The intact one of PATH and PATH.prev, from paths[first] on (first = 1: PATH.prev only). */
static cupid_status open_from(const char *path, const char *identity, int first,
                              cupid_checkpoint *out) {
  CUPID_CHECK(path && identity && out, CUPID_ERR_ARGUMENT, "checkpoint: NULL argument");
  *out = NULL;
  struct cupid_checkpoint_private *ck = NULL;
  cupid_status st = CUPID_SUCCESS;
  char prev[4096];
  snprintf(prev, sizeof prev, "%s.prev", path);
  const char *paths[2] = {path, prev};
  int found = 0;
  CUPID_CALL(cupid_calloc(1, sizeof *ck, "checkpoint", &ck));
  for (int k = first; k < 2 && !ck->data; k++) {
    unsigned char *d = NULL;
    size_t n = 0;
    CUPID_TRY(slurp(paths[k], &d, &n));
    found += d != NULL;
    if (d && intact(d, n, &ck->count)) ck->data = d, ck->previous = k;
    else cupid_free(&d);
  }
  CUPID_TRY_CHECK(found, CUPID_ERR_IO, "nothing to resume: no checkpoint '%s'", paths[first]);
  CUPID_TRY_CHECK(ck->data || first, CUPID_ERR_IO,
                  "no intact checkpoint: '%s' and '%s' are truncated or corrupt", path, prev);
  CUPID_TRY_CHECK(ck->data, CUPID_ERR_IO, "the previous checkpoint '%s' is truncated or corrupt",
                  prev);
  const unsigned char *id = NULL;
  size_t idn = 0;
  find(ck, "identity", &id, &idn);
  if (!(id && idn == strlen(identity) && memcmp(id, identity, idn) == 0)) {
    int was = 0, is = 0; /* the first line that differs (identities are a fact per line) */
    const size_t off = first_difference((const char *)id, id ? idn : 0, identity, &was, &is);
    st = CUPID_ERROR(CUPID_ERR_MODEL,
                     "the checkpoint '%s' belongs to another run: it was written for\n  %.*s\n"
                     "and this run has\n  %.*s\n(run without --resume to start again)",
                     paths[ck->previous], was, id ? (const char *)id + off : "", is, identity + off);
    goto cleanup;
  }
  *out = ck;
  return CUPID_SUCCESS;
cleanup:
  cupid_checkpoint_close(&ck);
  return st;
}

cupid_status cupid_checkpoint_open(const char *path, const char *identity, cupid_checkpoint *out) {
  return open_from(path, identity, 0, out);
}

cupid_status cupid_checkpoint_open_previous(const char *path, const char *identity,
                                            cupid_checkpoint *out) {
  return open_from(path, identity, 1, out);
}

int cupid_checkpoint_is_previous(const cupid_checkpoint ck) { return ck ? ck->previous : 0; }

cupid_status cupid_checkpoint_section(const cupid_checkpoint ck, const char *name,
                                      const void **data, size_t *bytes) {
  CUPID_CHECK(ck && name && data && bytes, CUPID_ERR_ARGUMENT, "checkpoint: NULL argument");
  const unsigned char *p = NULL;
  find(ck, name, &p, bytes);
  CUPID_CHECK(p, CUPID_ERR_IO, "the checkpoint has no section '%s'", name);
  *data = p;
  return CUPID_SUCCESS;
}

cupid_status cupid_checkpoint_read(const cupid_checkpoint ck, const char *name, void *data,
                                   size_t bytes) {
  const void *p = NULL;
  size_t n = 0;
  CUPID_CALL(cupid_checkpoint_section(ck, name, &p, &n));
  CUPID_CHECK(n == bytes, CUPID_ERR_IO, "the checkpoint's section '%s' holds %zu bytes, not %zu",
              name, n, bytes);
  memcpy(data, p, bytes);
  return CUPID_SUCCESS;
}

void cupid_checkpoint_close(cupid_checkpoint *ck) {
  if (!ck || !*ck) return;
  cupid_free(&(*ck)->data);
  cupid_free(ck);
}
