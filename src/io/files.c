/*
 * Directories and atomic files (see include/cupid/io.h).
 *
 * An atomic file is written to a temporary sibling and renamed over the target on commit:
 * rename() within one directory is atomic on POSIX, so a reader (ParaView, a script, the
 * next run) sees either the old file or the complete new one, never a truncated one.
 * Temporary files still open are listed in a lock-free registry so a signal handler can
 * unlink them (cupid_atomic_cleanup_all) and an interrupted run leaves no debris behind.
 */
#define _GNU_SOURCE /* syscall(), SYS_getdents64: a folder listing safe in a signal handler */
#include "cupid/io.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/syscall.h>

#include "io/io_internal.h"

/* ---------------------------------------------------------------- directories */

/* Make one directory of a mkdir -p chain; an existing directory is fine. */
static cupid_status make_one_dir(const char *dir, const char *full) {
  if (mkdir(dir, 0777) == 0) return CUPID_SUCCESS;
  int err = errno;
  struct stat sb;
  /* stat after the failure (not before the mkdir) also copes with a concurrent mkdir. */
  if (stat(dir, &sb) == 0) {
    if (S_ISDIR(sb.st_mode)) return CUPID_SUCCESS;
    return CUPID_ERROR(CUPID_ERR_IO, "cannot create directory '%s': '%s' exists and is not a directory",
                       full, dir);
  }
  return CUPID_ERROR(CUPID_ERR_IO, "cannot create directory '%s': '%s': %s", full, dir,
                     strerror(err));
}

cupid_status cupid_mkdir_p(const char *path) {
  CUPID_CHECK(path && path[0], CUPID_ERR_ARGUMENT, "cupid_mkdir_p: empty directory name");
  char *buf = NULL;
  CUPID_CALL(cupid_strdup(path, &buf));
  cupid_status st = CUPID_SUCCESS;
  size_t len = strlen(buf);
  for (size_t i = 1; i <= len && st == CUPID_SUCCESS; i++) {
    if (buf[i] != '/' && buf[i] != '\0') continue;
    if (buf[i - 1] == '/') continue; /* "a//b" or the root "/" */
    char saved = buf[i];
    buf[i] = '\0';
    st = make_one_dir(buf, path);
    buf[i] = saved;
  }
  cupid_free(&buf);
  return st;
}

/* ---------------------------------------------------------------- temp-file registry */

/*
 * Fixed slots so the signal handler needs no allocation or locks. A slot is FREE, CLAIMED
 * (path being written, not to be touched by the handler) or ACTIVE (path complete, file exists).
 * After a commit renamed the file, an ACTIVE path no longer exists: unlinking it is harmless.
 */
#define REGISTRY_SLOTS 64
#define REGISTRY_PATH 4096
enum { SLOT_FREE = 0, SLOT_CLAIMED = 1, SLOT_ACTIVE = 2 };
_Static_assert(ATOMIC_INT_LOCK_FREE == 2, "the signal-safe registry needs lock-free atomic int");

static struct {
  atomic_int state;
  char path[REGISTRY_PATH];
} registry[REGISTRY_SLOTS];

/* Register @p path; returns the slot or -1 if the registry is full or the path too long. */
static int registry_add(const char *path) {
  size_t len = strlen(path);
  if (len >= REGISTRY_PATH) return -1;
  for (int i = 0; i < REGISTRY_SLOTS; i++) {
    int expected = SLOT_FREE;
    if (atomic_compare_exchange_strong(&registry[i].state, &expected, SLOT_CLAIMED)) {
      memcpy(registry[i].path, path, len + 1);
      atomic_store(&registry[i].state, SLOT_ACTIVE);
      return i;
    }
  }
  return -1;
}

static void registry_remove(int slot) {
  if (slot >= 0) atomic_store(&registry[slot].state, SLOT_FREE);
}

/* Helper processes writing a registered file, by slot (0: none). Killed and reaped before the
 * files are unlinked, so that they cannot (re)create a file after the cleanup. */
static atomic_int registry_child[REGISTRY_SLOTS];
_Static_assert(sizeof(pid_t) <= sizeof(int), "a pid must fit an atomic int");

int cupid_io_helper_begin(const char *path, pid_t child) {
  int slot = registry_add(path);
  if (slot >= 0) atomic_store(&registry_child[slot], (int)child);
  return slot;
}

void cupid_io_helper_set_child(int slot, pid_t child) {
  if (slot >= 0) atomic_store(&registry_child[slot], (int)child);
}

void cupid_io_helper_end(int slot) {
  if (slot < 0) return;
  atomic_store(&registry_child[slot], 0);
  registry_remove(slot);
}

/* Output sets being written (output_set.c): the staging folder and the lock file of each, so
 * that an interrupted run removes both (issue 33: SIGINT left the lock and an empty staging
 * folder). A few sets at once at most (the Python API may hold several problems). */
#define SET_SLOTS 8
static struct {
  atomic_int state;
  char staging[REGISTRY_PATH], lock[REGISTRY_PATH];
} set_registry[SET_SLOTS];

int cupid_io_set_register(const char *staging, const char *lock) {
  const size_t ls = strlen(staging), ll = strlen(lock);
  if (ls >= REGISTRY_PATH || ll >= REGISTRY_PATH) return -1;
  for (int i = 0; i < SET_SLOTS; i++) {
    int expected = SLOT_FREE;
    if (atomic_compare_exchange_strong(&set_registry[i].state, &expected, SLOT_CLAIMED)) {
      memcpy(set_registry[i].staging, staging, ls + 1);
      memcpy(set_registry[i].lock, lock, ll + 1);
      atomic_store(&set_registry[i].state, SLOT_ACTIVE);
      return i;
    }
  }
  return -1;
}

void cupid_io_set_unregister(int slot) {
  if (slot >= 0 && slot < SET_SLOTS) atomic_store(&set_registry[slot].state, SLOT_FREE);
}

/* The files of a flat folder and the folder, from a signal handler: open, getdents64 (the
 * system call: readdir allocates), unlinkat and rmdir are async-signal-safe. Two passes, as
 * unlinking while reading may skip an entry. */
static void remove_folder_signal_safe(const char *dir) {
  for (int pass = 0; pass < 2; pass++) {
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return;
    _Alignas(8) char buf[4096];
    long n;
    while ((n = syscall(SYS_getdents64, fd, buf, sizeof buf)) > 0)
      for (long off = 0; off < n;) {
        const struct {
          uint64_t ino;
          int64_t off;
          unsigned short reclen;
          unsigned char type;
          char name[];
        } *e = (const void *)(buf + off);
        const char *name = e->name;
        if (!(name[0] == '.' && (name[1] == '\0' || (name[1] == '.' && name[2] == '\0'))))
          unlinkat(fd, name, 0);
        off += e->reclen;
      }
    close(fd);
    if (rmdir(dir) == 0) return;
  }
}

void cupid_atomic_cleanup_all(void) {
  int saved = errno; /* a signal handler must not change errno under the interrupted code */
  for (int i = 0; i < REGISTRY_SLOTS; i++) {
    pid_t child = (pid_t)atomic_load(&registry_child[i]);
    if (child > 0 && kill(child, SIGKILL) == 0)
      while (waitpid(child, NULL, 0) < 0 && errno == EINTR) continue;
  }
  for (int i = 0; i < REGISTRY_SLOTS; i++)
    if (atomic_load(&registry[i].state) == SLOT_ACTIVE) unlink(registry[i].path);
  for (int i = 0; i < SET_SLOTS; i++) /* the staged files, their folder, then the lock */
    if (atomic_load(&set_registry[i].state) == SLOT_ACTIVE) {
      if (set_registry[i].staging[0]) /* "": a resumable run's, kept for --resume */
        remove_folder_signal_safe(set_registry[i].staging);
      unlink(set_registry[i].lock);
    }
  errno = saved;
}

/* ---------------------------------------------------------------- atomic files */

#define ATOMIC_BUFFER_SIZE (1u << 20) /* 1 MiB: few write() calls for text-heavy files */

struct cupid_atomic_file_private {
  FILE *stream;
  char *path;   /* the target */
  char *temp;   /* the temporary sibling */
  char *buffer; /* stdio buffer of stream */
  int slot;     /* registry slot or -1 */
  int durable;  /* fsync the file before the rename and the directory after it */
};

static atomic_ulong temp_counter;

/* fsync the directory that holds path (best effort: some file systems refuse it). */
static void sync_directory(const char *path) {
  const char *slash = strrchr(path, '/');
  char dir[4096];
  if (!slash) snprintf(dir, sizeof dir, ".");
  else if (slash == path) snprintf(dir, sizeof dir, "/");
  else snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
  const int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  (void)fsync(fd);
  close(fd);
}

static void atomic_free(struct cupid_atomic_file_private *f) {
  cupid_free(&f->path);
  cupid_free(&f->temp);
  cupid_free(&f->buffer);
  cupid_free(&f);
}

/* Create the temporary sibling exclusively (retrying on a name clash) and return its fd. The
 * name is registered before the file is created: a signal between the two would otherwise
 * leave the new file behind (seen in tests/unit/signals.sh: SIGTERM during the VTU output);
 * unlinking a name that does not exist yet is harmless. */
static cupid_status create_temp(struct cupid_atomic_file_private *f, int *fd_out) {
  const char *slash = strrchr(f->path, '/');
  const char *base = slash ? slash + 1 : f->path;
  int dirlen = slash ? (int)(slash - f->path + 1) : 0;
  size_t size = strlen(f->path) + 64;
  CUPID_CALL(cupid_malloc(size, 1, "temporary file name", &f->temp));
  for (int attempt = 0; attempt < 1000; attempt++) {
    unsigned long counter = atomic_fetch_add(&temp_counter, 1);
    snprintf(f->temp, size, "%.*s.%s.tmp.%ld.%lu", dirlen, f->path, base, (long)getpid(),
             counter);
    f->slot = registry_add(f->temp);
    int fd = open(f->temp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      *fd_out = fd;
      return CUPID_SUCCESS;
    }
    int err = errno;
    registry_remove(f->slot); /* not ours (a clash) or not created */
    f->slot = -1;
    errno = err;
    if (errno != EEXIST)
      return CUPID_ERROR(CUPID_ERR_IO, "cannot write '%s': cannot create temporary file '%s': %s",
                         f->path, f->temp, strerror(errno));
  }
  return CUPID_ERROR(CUPID_ERR_IO, "cannot write '%s': no free temporary file name", f->path);
}

/* The buffered stream of f on its temporary file's descriptor *fd (the stream owns it then:
 * *fd becomes -1). */
static cupid_status attach_stream(struct cupid_atomic_file_private *f, int *fd) {
  f->stream = fdopen(*fd, "wb");
  CUPID_CHECK(f->stream, CUPID_ERR_IO, "cannot write '%s': fdopen: %s", f->path, strerror(errno));
  *fd = -1;
  CUPID_CHECK(setvbuf(f->stream, f->buffer, _IOFBF, ATOMIC_BUFFER_SIZE) == 0, CUPID_ERR_IO,
              "cannot write '%s': setvbuf failed", f->path);
  return CUPID_SUCCESS;
}

cupid_status cupid_atomic_open(const char *path, cupid_atomic_file *file) {
  CUPID_CHECK(file, CUPID_ERR_ARGUMENT, "cupid_atomic_open: NULL handle");
  *file = NULL;
  CUPID_CHECK(path && path[0], CUPID_ERR_ARGUMENT, "cupid_atomic_open: empty file name");
  size_t len = strlen(path);
  CUPID_CHECK(path[len - 1] != '/', CUPID_ERR_IO, "cannot write '%s': it names a directory",
              path);
  cupid_status st = CUPID_SUCCESS;
  struct cupid_atomic_file_private *f = NULL;
  int fd = -1;
  CUPID_CALL(cupid_calloc(1, sizeof *f, "atomic file", &f));
  f->slot = -1;
  CUPID_TRY(cupid_strdup(path, &f->path));
  CUPID_TRY(cupid_malloc(ATOMIC_BUFFER_SIZE, 1, "file buffer", &f->buffer));
  CUPID_TRY(create_temp(f, &fd)); /* registers the temporary name (f->slot) */
  CUPID_TRY(attach_stream(f, &fd));
  *file = f;
  return CUPID_SUCCESS;
cleanup:
  if (f->stream) fclose(f->stream);
  if (fd >= 0) close(fd);
  if (f->temp && (f->stream || fd >= 0 || f->slot >= 0)) unlink(f->temp);
  registry_remove(f->slot);
  atomic_free(f);
  return st;
}

FILE *cupid_atomic_stream(cupid_atomic_file file) { return file ? file->stream : NULL; }

void cupid_atomic_set_durable(cupid_atomic_file file) {
  if (file) file->durable = 1;
}

cupid_status cupid_atomic_commit(cupid_atomic_file *file) {
  CUPID_CHECK(file && *file, CUPID_ERR_ARGUMENT, "cupid_atomic_commit: NULL handle");
  struct cupid_atomic_file_private *f = *file;
  *file = NULL;
  const char *what = NULL; /* the first step that failed */
  int err = 0;
  /* fflush first: if an earlier write failed (e.g. ENOSPC) it usually fails again with errno. */
  if (fflush(f->stream) != 0) {
    what = "write failed";
    err = errno;
  }
  if (!what && ferror(f->stream)) what = "write failed";
  if (!what && f->durable && fsync(fileno(f->stream)) != 0) {
    what = "fsync failed";
    err = errno;
  }
  if (fclose(f->stream) != 0 && !what) {
    what = "close failed";
    err = errno;
  }
  f->stream = NULL;
  if (!what && rename(f->temp, f->path) != 0) {
    what = "cannot rename the temporary file over it";
    err = errno;
  }
  cupid_status st = CUPID_SUCCESS;
  if (what) {
    unlink(f->temp);
    st = CUPID_ERROR(CUPID_ERR_IO, "cannot write '%s': %s%s%s", f->path, what, err ? ": " : "",
                     err ? strerror(err) : "");
  } else if (f->durable) {
    sync_directory(f->path); /* the rename itself on disk */
  }
  registry_remove(f->slot);
  atomic_free(f);
  return st;
}

void cupid_atomic_abort(cupid_atomic_file *file) {
  if (!file || !*file) return;
  struct cupid_atomic_file_private *f = *file;
  *file = NULL;
  if (f->stream) fclose(f->stream); /* its result is irrelevant: the file is discarded */
  unlink(f->temp);
  registry_remove(f->slot);
  atomic_free(f);
}

/* ---------------------------------------------------------------- resumable streams */

cupid_status cupid_atomic_open_partial(const char *path, int64_t keep, cupid_atomic_file *file) {
  CUPID_CHECK(file && path && path[0], CUPID_ERR_ARGUMENT, "cupid_atomic_open_partial: no file");
  *file = NULL;
  cupid_status st = CUPID_SUCCESS;
  struct cupid_atomic_file_private *f = NULL;
  int fd = -1;
  CUPID_CALL(cupid_calloc(1, sizeof *f, "atomic file", &f));
  f->slot = -1; /* not registered: a signal keeps it for the resumption */
  CUPID_TRY(cupid_strdup(path, &f->path));
  CUPID_TRY(cupid_malloc(ATOMIC_BUFFER_SIZE, 1, "file buffer", &f->buffer));
  const char *slash = strrchr(path, '/');
  const size_t size = strlen(path) + 16;
  CUPID_TRY(cupid_malloc(size, 1, "temporary file name", &f->temp));
  snprintf(f->temp, size, "%.*s.%s.partial", slash ? (int)(slash - path + 1) : 0, path,
           slash ? slash + 1 : path);
  /* a run stopped after it committed the stream (its last steps done, its outputs being
   * finished) left it under its own name: it continues from there */
  if (keep >= 0 && access(f->temp, F_OK) != 0 && access(path, F_OK) == 0)
    (void)rename(path, f->temp);
  fd = open(f->temp, keep < 0 ? O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC : O_WRONLY | O_CLOEXEC,
            0666);
  CUPID_TRY_CHECK(fd >= 0, CUPID_ERR_IO, "cannot %s '%s': %s", keep < 0 ? "write" : "continue",
                  f->temp, strerror(errno));
  if (keep >= 0) {
    struct stat sb;
    CUPID_TRY_CHECK(fstat(fd, &sb) == 0 && sb.st_size >= keep, CUPID_ERR_IO,
                    "cannot continue '%s': it holds %lld bytes, the checkpoint recorded %lld",
                    f->temp, (long long)sb.st_size, (long long)keep);
    CUPID_TRY_CHECK(ftruncate(fd, (off_t)keep) == 0 && lseek(fd, 0, SEEK_END) == (off_t)keep,
                    CUPID_ERR_IO, "cannot continue '%s': %s", f->temp, strerror(errno));
  }
  CUPID_TRY(attach_stream(f, &fd));
  *file = f;
  return CUPID_SUCCESS;
cleanup:
  if (f->stream) fclose(f->stream);
  if (fd >= 0) close(fd);
  atomic_free(f);
  return st;
}

cupid_status cupid_atomic_sync(cupid_atomic_file file, int64_t *bytes) {
  CUPID_CHECK(file && bytes, CUPID_ERR_ARGUMENT, "cupid_atomic_sync: NULL argument");
  const int fd = fileno(file->stream);
  CUPID_CHECK(fflush(file->stream) == 0 && !ferror(file->stream) && fdatasync(fd) == 0,
              CUPID_ERR_IO, "cannot write '%s': %s", file->path, strerror(errno));
  const off_t at = lseek(fd, 0, SEEK_CUR);
  CUPID_CHECK(at >= 0, CUPID_ERR_IO, "cannot write '%s': %s", file->path, strerror(errno));
  *bytes = (int64_t)at;
  return CUPID_SUCCESS;
}

void cupid_atomic_suspend(cupid_atomic_file *file) {
  if (!file || !*file) return;
  struct cupid_atomic_file_private *f = *file;
  *file = NULL;
  if (f->stream) fclose(f->stream);
  registry_remove(f->slot);
  atomic_free(f);
}
