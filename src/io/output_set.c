/*
 * Output sets (include/cupid/io.h, cupid_output_set): the files of one run appear together or
 * not at all. A run writes into a staging folder beside the output folder (the same file
 * system, so that rename() moves files without copying); publishing moves them in, summary.json
 * last, after removing the files of the same kinds that the run did not write (an earlier,
 * longer run's numbered VTU files); aborting deletes the staging folder, and the previous
 * results stay as they were. A lock file beside the output folder (flock) refuses a second run
 * into the same folder while one is running; staging folders of runs that died (SIGKILL) are
 * removed by the next run into that folder.
 *
 * A resumable run (issue 36) stages into a folder of fixed name, parent/.base.cupid-partial,
 * that a signal leaves: it holds the files written so far and the run's checkpoints (dot
 * files, never published), and `--resume` continues in it. Any other run into the folder
 * removes it.
 */
#define _GNU_SOURCE
#include "cupid/io.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <fnmatch.h>
#include <stdlib.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "io/io_internal.h"

struct cupid_output_set_private {
  char *dir;     /* the output folder */
  char *parent;  /* its parent ("." for a relative name without a slash) */
  char *base;    /* its last component */
  char *staging; /* parent/.base.cupid-run-PID, or parent/.base.cupid-partial (resumable) */
  char *lock;    /* parent/.base.cupid-lock */
  int lock_fd;
  int slot;      /* cupid_io_set_register's, or -1 */
  int keep;      /* publish leaves the folder's other files alone (keep_others) */
  int suspend;   /* abort keeps the staging folder (an interrupted resumable run) */
};

/* The files a run writes, by pattern: the folder's other files are the user's and stay. */
static const char *const run_kinds[] = {
    "summary.json", "pd_nodes.csv", "pd.vtu", "beam.vtu", "model.pvd", "pd_[0-9]*.vtu",
    "beam_[0-9]*.vtu", "line_*.csv", "line_*.png", "line_*.gp", "history.csv", "history_*.png",
    "history_*.gp", "energies.csv", "energies.png", "energies.gp", "damage.csv", "damage.png",
    "damage.gp", "load_steps.csv", "load_displacement.png", "load_displacement.gp", "model.exo",
    NULL};

static int run_kind(const char *name) {
  for (int k = 0; run_kinds[k]; k++)
    if (fnmatch(run_kinds[k], name, 0) == 0) return 1;
  return 0;
}

static cupid_status join(const char *a, const char *b, char **out) {
  size_t n = strlen(a) + strlen(b) + 2;
  CUPID_CALL(cupid_malloc(n, 1, "path", out));
  snprintf(*out, n, "%s/%s", a, b);
  return CUPID_SUCCESS;
}

/* Remove a folder and the plain files in it (staging folders hold no subfolders). */
static void remove_flat(const char *dir) {
  DIR *d = opendir(dir);
  if (d) {
    struct dirent *e;
    while ((e = readdir(d)))
      if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
        char *p = NULL;
        if (join(dir, e->d_name, &p) == CUPID_SUCCESS) unlink(p);
        cupid_free(&p);
      }
    closedir(d);
  }
  rmdir(dir);
}

/* Staging folders of this output folder whose run is gone (its pid no longer exists). */
static void remove_dead_staging(const struct cupid_output_set_private *s) {
  DIR *d = opendir(s->parent);
  if (!d) return;
  char prefix[512];
  snprintf(prefix, sizeof prefix, ".%s.cupid-run-", s->base);
  size_t np = strlen(prefix);
  struct dirent *e;
  while ((e = readdir(d))) {
    if (strncmp(e->d_name, prefix, np)) continue;
    long pid = strtol(e->d_name + np, NULL, 10);
    if (pid > 0 && (kill((pid_t)pid, 0) == 0 || errno != ESRCH)) continue; /* alive */
    char *p = NULL;
    if (join(s->parent, e->d_name, &p) == CUPID_SUCCESS) remove_flat(p);
    cupid_free(&p);
  }
  closedir(d);
}

static void set_free(struct cupid_output_set_private *s) {
  cupid_io_set_unregister(s->slot);
  if (s->lock_fd >= 0) {
    unlink(s->lock);
    close(s->lock_fd); /* releases the flock */
  }
  cupid_free(&s->dir);
  cupid_free(&s->parent);
  cupid_free(&s->base);
  cupid_free(&s->staging);
  cupid_free(&s->lock);
  cupid_free(&s);
}

static cupid_status split_path(struct cupid_output_set_private *s, const char *dir) {
  CUPID_CALL(cupid_strdup(dir, &s->dir));
  size_t n = strlen(s->dir);
  while (n > 1 && s->dir[n - 1] == '/') s->dir[--n] = '\0'; /* "out/" is "out" */
  const char *slash = strrchr(s->dir, '/');
  if (!slash) {
    CUPID_CALL(cupid_strdup(".", &s->parent));
    return cupid_strdup(s->dir, &s->base);
  }
  CUPID_CALL(cupid_strdup(slash + 1, &s->base));
  CUPID_CALL(cupid_strdup(s->dir, &s->parent));
  s->parent[slash - s->dir > 0 ? slash - s->dir : 1] = '\0'; /* "/x": parent "/" */
  return CUPID_SUCCESS;
}

/* The fixed name of a resumable run's staging folder. */
static cupid_status partial_name(const struct cupid_output_set_private *s, char **out) {
  char name[600];
  snprintf(name, sizeof name, ".%s.cupid-partial", s->base);
  return join(s->parent, name, out);
}

/* The lock of @p dir, its parent made; CUPID_ERR_IO naming the other run's pid if held. */
static cupid_status take_lock(struct cupid_output_set_private *s, const char *dir) {
  CUPID_CALL(split_path(s, dir));
  CUPID_CHECK(strcmp(s->base, ".") && strcmp(s->base, ".."), CUPID_ERR_IO,
              "output folder '%s': name it by its own name (not '.' or '..')", dir);
  CUPID_CALL(cupid_mkdir_p(s->parent));
  char name[600];
  snprintf(name, sizeof name, ".%s.cupid-lock", s->base);
  CUPID_CALL(join(s->parent, name, &s->lock));
  s->lock_fd = open(s->lock, O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  CUPID_CHECK(s->lock_fd >= 0, CUPID_ERR_IO, "cannot create the lock file '%s': %s", s->lock,
              strerror(errno));
  if (flock(s->lock_fd, LOCK_EX | LOCK_NB) != 0) {
    char owner[32] = "?";
    ssize_t r = pread(s->lock_fd, owner, sizeof owner - 1, 0);
    owner[r > 0 ? r : 0] = '\0';
    owner[strcspn(owner, "\n")] = '\0';
    close(s->lock_fd); /* not ours to unlink */
    s->lock_fd = -1;
    return CUPID_ERROR(CUPID_ERR_IO,
                       "another cupid run (pid %s) is writing into '%s': wait for it, or write to "
                       "another folder (-o DIR)",
                       owner, dir);
  }
  char pid[32];
  int len = snprintf(pid, sizeof pid, "%ld\n", (long)getpid());
  if (ftruncate(s->lock_fd, 0) != 0 || pwrite(s->lock_fd, pid, (size_t)len, 0) != len) {
    /* the pid is for the message of a refused run only: not worth failing over */
  }
  return CUPID_SUCCESS;
}

/* mode 0: an ordinary run; 1: a resumable run from the start; 2: a resumption. */
static cupid_status begin(const char *dir, int mode, cupid_output_set *set) {
  CUPID_CHECK(dir && dir[0] && set, CUPID_ERR_ARGUMENT, "cupid_output_set_begin: empty folder name");
  *set = NULL;
  struct cupid_output_set_private *s = NULL;
  cupid_status st = CUPID_SUCCESS;
  char *partial = NULL;
  CUPID_CALL(cupid_calloc(1, sizeof *s, "output set", &s));
  s->lock_fd = -1;
  s->slot = -1;
  CUPID_TRY(take_lock(s, dir));
  remove_dead_staging(s);
  CUPID_TRY(partial_name(s, &partial));
  if (mode == 2) {
    struct stat sb;
    CUPID_TRY_CHECK(stat(partial, &sb) == 0 && S_ISDIR(sb.st_mode), CUPID_ERR_IO,
                    "nothing to resume: no interrupted run into '%s' (its folder '%s' is not "
                    "there); run without --resume to start",
                    dir, partial);
  } else {
    remove_flat(partial); /* an interrupted run's files: this run starts over */
  }
  if (mode) {
    s->staging = partial;
    partial = NULL;
  } else {
    char name[600];
    snprintf(name, sizeof name, ".%s.cupid-run-%ld", s->base, (long)getpid());
    CUPID_TRY(join(s->parent, name, &s->staging));
    remove_flat(s->staging); /* a leftover of this pid's earlier set */
  }
  if (mode != 2)
    CUPID_TRY_CHECK(mkdir(s->staging, 0777) == 0, CUPID_ERR_IO,
                    "cannot create the staging folder '%s': %s", s->staging, strerror(errno));
  /* a signal removes an ordinary run's staging folder and the lock; a resumable run's folder
   * stays for --resume */
  s->slot = cupid_io_set_register(mode ? "" : s->staging, s->lock);
  *set = s;
  s = NULL;
cleanup:
  cupid_free(&partial);
  if (s) set_free(s);
  return st;
}

cupid_status cupid_output_set_begin(const char *dir, cupid_output_set *set) {
  return begin(dir, 0, set);
}

cupid_status cupid_output_set_begin_resumable(const char *dir, int resume, cupid_output_set *set) {
  return begin(dir, resume ? 2 : 1, set);
}

cupid_status cupid_output_set_partial_dir(const char *dir, char **path) {
  CUPID_CHECK(dir && dir[0] && path, CUPID_ERR_ARGUMENT, "cupid_output_set_partial_dir: no folder");
  *path = NULL;
  struct cupid_output_set_private s = {0};
  cupid_status st = split_path(&s, dir);
  if (st == CUPID_SUCCESS) st = partial_name(&s, path);
  cupid_free(&s.dir);
  cupid_free(&s.parent);
  cupid_free(&s.base);
  return st;
}

const char *cupid_output_set_dir(const cupid_output_set set) { return set ? set->staging : NULL; }

/* Every staged file can replace its target: a target that is a folder would fail half-way
 * through the moves, so it is refused before any. */
static cupid_status check_targets(const struct cupid_output_set_private *s) {
  DIR *d = opendir(s->staging);
  CUPID_CHECK(d, CUPID_ERR_IO, "cannot read the staging folder '%s': %s", s->staging, strerror(errno));
  cupid_status st = CUPID_SUCCESS;
  struct dirent *e;
  while (st == CUPID_SUCCESS && (e = readdir(d))) {
    if (e->d_name[0] == '.') continue; /* ".", "..", a resumable run's checkpoints */
    char *target = NULL;
    st = join(s->dir, e->d_name, &target);
    struct stat sb;
    if (st == CUPID_SUCCESS && lstat(target, &sb) == 0 && S_ISDIR(sb.st_mode))
      st = CUPID_ERROR(CUPID_ERR_IO, "cannot write '%s': it is a folder", target);
    cupid_free(&target);
  }
  closedir(d);
  return st;
}

/* Files of the run's kinds in the output folder that this run did not write. */
static void remove_stale(const struct cupid_output_set_private *s) {
  DIR *d = opendir(s->dir);
  if (!d) return;
  struct dirent *e;
  while ((e = readdir(d))) {
    if (!run_kind(e->d_name)) continue;
    char *staged = NULL, *target = NULL;
    if (join(s->staging, e->d_name, &staged) == CUPID_SUCCESS &&
        join(s->dir, e->d_name, &target) == CUPID_SUCCESS && access(staged, F_OK) != 0)
      unlink(target);
    cupid_free(&staged);
    cupid_free(&target);
  }
  closedir(d);
}

/* A resumable run's checkpoints (its staging folder's dot files). */
static void remove_checkpoints(const struct cupid_output_set_private *s) {
  DIR *d = opendir(s->staging);
  if (!d) return;
  struct dirent *e;
  while ((e = readdir(d))) {
    if (e->d_name[0] != '.' || !strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    char *p = NULL;
    if (join(s->staging, e->d_name, &p) == CUPID_SUCCESS) unlink(p);
    cupid_free(&p);
  }
  closedir(d);
}

static cupid_status move_in(const struct cupid_output_set_private *s, const char *name) {
  char *from = NULL, *to = NULL;
  cupid_status st = join(s->staging, name, &from);
  if (st == CUPID_SUCCESS) st = join(s->dir, name, &to);
  if (st == CUPID_SUCCESS && rename(from, to) != 0)
    st = CUPID_ERROR(CUPID_ERR_IO, "cannot move '%s' to '%s': %s", from, to, strerror(errno));
  cupid_free(&from);
  cupid_free(&to);
  return st;
}

cupid_status cupid_output_set_publish(cupid_output_set *set) {
  CUPID_CHECK(set && *set, CUPID_ERR_ARGUMENT, "cupid_output_set_publish: no set");
  struct cupid_output_set_private *s = *set;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_mkdir_p(s->dir));
  CUPID_TRY(check_targets(s));
  remove_checkpoints(s); /* the run is whole: a stop while its files move in starts it over */
  if (!s->keep) remove_stale(s);
  DIR *d = opendir(s->staging);
  CUPID_TRY_CHECK(d, CUPID_ERR_IO, "cannot read the staging folder '%s': %s", s->staging,
                  strerror(errno));
  struct dirent *e;
  int has_summary = 0;
  while (st == CUPID_SUCCESS && (e = readdir(d))) {
    if (e->d_name[0] == '.') continue; /* ".", "..", a resumable run's checkpoints */
    if (!strcmp(e->d_name, "summary.json")) { /* last: it names the run the set is from */
      has_summary = 1;
      continue;
    }
    st = move_in(s, e->d_name);
  }
  closedir(d);
  if (st == CUPID_SUCCESS && has_summary) st = move_in(s, "summary.json");
cleanup:
  cupid_output_set_abort(set); /* the staging folder (now empty on success) and the lock */
  return st;
}

void cupid_output_set_keep_others(cupid_output_set set) {
  if (set) set->keep = 1;
}

void cupid_output_set_suspend(cupid_output_set *set) {
  if (set && *set) (*set)->suspend = 1;
  cupid_output_set_abort(set);
}

void cupid_output_set_abort(cupid_output_set *set) {
  if (!set || !*set) return;
  if (!(*set)->suspend) remove_flat((*set)->staging);
  set_free(*set);
  *set = NULL;
}
