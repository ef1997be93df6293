/* Unit tests of directories and atomic files (src/io/files.c). */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "testutil.h"

static char root[256]; /* a fresh directory per test */

static int setup(void **state) {
  (void)state;
  return cupid_test_mkdtemp("files", root, sizeof root);
}

static int teardown(void **state) {
  (void)state;
  return cupid_test_rmtree(root);
}

static const char *in_root(const char *name) {
  static char buf[1024];
  snprintf(buf, sizeof buf, "%s/%s", root, name);
  return buf;
}

/* Number of entries of @p dir whose name contains ".tmp." (cupid's temporary files). */
static int count_temp_files(const char *dir) {
  DIR *d = opendir(dir);
  assert_non_null(d);
  int n = 0;
  struct dirent *e;
  while ((e = readdir(d)))
    if (strstr(e->d_name, ".tmp.")) n++;
  closedir(d);
  return n;
}

static void write_plain(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  assert_int_equal(fputs(text, f) >= 0, 1);
  assert_int_equal(fclose(f), 0);
}

/* The whole content of a file (static buffer), or NULL if it cannot be read. */
static const char *slurp(const char *path) {
  static char buf[4096];
  FILE *f = fopen(path, "r");
  if (!f) return NULL;
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  buf[n] = '\0';
  fclose(f);
  return buf;
}

static int is_dir(const char *path) {
  struct stat sb;
  return stat(path, &sb) == 0 && S_ISDIR(sb.st_mode);
}

static void test_mkdir_p(void **state) {
  (void)state;
  CUPID_ASSERT_OK(cupid_mkdir_p(in_root("a/b/c")));
  assert_true(is_dir(in_root("a/b/c")));
  CUPID_ASSERT_OK(cupid_mkdir_p(in_root("a/b/c")));       /* existing: fine */
  CUPID_ASSERT_OK(cupid_mkdir_p(in_root("a//b/./d/")));   /* repeated slash, ".", trailing / */
  assert_true(is_dir(in_root("a/b/d")));
  CUPID_ASSERT_OK(cupid_mkdir_p(root));
  assert_int_equal(cupid_mkdir_p(""), CUPID_ERR_ARGUMENT);
  assert_int_equal(cupid_mkdir_p(NULL), CUPID_ERR_ARGUMENT);
}

static void test_mkdir_p_blocked_by_file(void **state) {
  (void)state;
  write_plain(in_root("f"), "x");
  char path[1024];
  snprintf(path, sizeof path, "%s/f/x/y", root);
  assert_int_equal(cupid_mkdir_p(path), CUPID_ERR_IO);
  assert_non_null(strstr(cupid_error_message(), path));
  assert_non_null(strstr(cupid_error_message(), "not a directory"));
  assert_int_equal(cupid_mkdir_p(in_root("f")), CUPID_ERR_IO); /* the leaf itself is a file */
  assert_string_equal(slurp(in_root("f")), "x");
}

static void test_atomic_commit_replaces(void **state) {
  (void)state;
  const char *target = in_root("out.txt");
  write_plain(target, "old\n");
  cupid_atomic_file f = NULL;
  CUPID_ASSERT_OK(cupid_atomic_open(target, &f));
  assert_non_null(cupid_atomic_stream(f));
  assert_true(fprintf(cupid_atomic_stream(f), "new %d\n", 42) > 0);
  assert_int_equal(fflush(cupid_atomic_stream(f)), 0);
  assert_string_equal(slurp(target), "old\n"); /* readers see the old file until commit */
  assert_int_equal(count_temp_files(root), 1);
  CUPID_ASSERT_OK(cupid_atomic_commit(&f));
  assert_null(f);
  assert_string_equal(slurp(target), "new 42\n");
  assert_int_equal(count_temp_files(root), 0);
  /* A new file in the current directory (a path without '/'). */
  char cwd[512];
  assert_non_null(getcwd(cwd, sizeof cwd));
  assert_int_equal(chdir(root), 0);
  CUPID_ASSERT_OK(cupid_atomic_open("plain", &f));
  fputs("p", cupid_atomic_stream(f));
  CUPID_ASSERT_OK(cupid_atomic_commit(&f));
  assert_int_equal(chdir(cwd), 0);
  assert_string_equal(slurp(in_root("plain")), "p");
  /* Permissions follow the umask like an ordinary new file (not mkstemp's 0600). */
  struct stat sb;
  mode_t mask = umask(022);
  umask(mask);
  assert_int_equal(stat(in_root("plain"), &sb), 0);
  assert_int_equal(sb.st_mode & 0777, 0666 & ~mask);
}

static void test_atomic_abort(void **state) {
  (void)state;
  const char *target = in_root("keep.txt");
  write_plain(target, "keep\n");
  cupid_atomic_file f = NULL;
  CUPID_ASSERT_OK(cupid_atomic_open(target, &f));
  fputs("discarded", cupid_atomic_stream(f));
  cupid_atomic_abort(&f);
  assert_null(f);
  cupid_atomic_abort(&f); /* NULL-safe */
  cupid_atomic_abort(NULL);
  assert_string_equal(slurp(target), "keep\n");
  assert_int_equal(count_temp_files(root), 0);
  /* Abort of a never-existing target leaves nothing at all. */
  CUPID_ASSERT_OK(cupid_atomic_open(in_root("never"), &f));
  cupid_atomic_abort(&f);
  assert_null(slurp(in_root("never")));
  assert_int_equal(count_temp_files(root), 0);
}

static void test_atomic_open_failure(void **state) {
  (void)state;
  cupid_atomic_file f = (cupid_atomic_file)1;
  const char *target = in_root("missing/dir/x.txt");
  assert_int_equal(cupid_atomic_open(target, &f), CUPID_ERR_IO);
  assert_null(f);
  assert_non_null(strstr(cupid_error_message(), target));
  assert_non_null(strstr(cupid_error_message(), "No such file or directory"));
  assert_int_equal(cupid_atomic_open(in_root("dir/"), &f), CUPID_ERR_IO);
  assert_int_equal(cupid_atomic_open("", &f), CUPID_ERR_ARGUMENT);
  assert_int_equal(cupid_atomic_commit(&f), CUPID_ERR_ARGUMENT); /* f is NULL */
}

static void test_atomic_commit_rename_fails(void **state) {
  (void)state;
  /* The target is a non-empty directory: writing works, the final rename cannot. */
  CUPID_ASSERT_OK(cupid_mkdir_p(in_root("target/sub")));
  const char *target = in_root("target");
  cupid_atomic_file f = NULL;
  CUPID_ASSERT_OK(cupid_atomic_open(target, &f));
  fputs("data", cupid_atomic_stream(f));
  assert_int_equal(cupid_atomic_commit(&f), CUPID_ERR_IO);
  assert_null(f);
  assert_non_null(strstr(cupid_error_message(), target));
  assert_int_equal(count_temp_files(root), 0);
  assert_true(is_dir(in_root("target/sub")));
}

static void test_atomic_commit_write_error(void **state) {
  (void)state;
  const char *target = in_root("w.txt");
  write_plain(target, "old\n");
  cupid_atomic_file f = NULL;
  CUPID_ASSERT_OK(cupid_atomic_open(target, &f));
  FILE *s = cupid_atomic_stream(f);
  fputs("partial", s);
  /* Reading a write-only stream sets its error flag, as a failed write would. */
  assert_int_equal(fgetc(s), EOF);
  assert_true(ferror(s));
  assert_int_equal(cupid_atomic_commit(&f), CUPID_ERR_IO);
  assert_non_null(strstr(cupid_error_message(), target));
  assert_string_equal(slurp(target), "old\n");
  assert_int_equal(count_temp_files(root), 0);
}

static void test_atomic_cleanup_all(void **state) {
  (void)state;
  /* More files than the registry tracks (64): the first 64 are cleaned, all can be aborted. */
  enum { N = 70 };
  cupid_atomic_file f[N];
  for (int i = 0; i < N; i++) {
    char name[32];
    snprintf(name, sizeof name, "f%d", i);
    CUPID_ASSERT_OK(cupid_atomic_open(in_root(name), &f[i]));
    fputs("x", cupid_atomic_stream(f[i]));
  }
  assert_int_equal(count_temp_files(root), N);
  cupid_atomic_cleanup_all();
  assert_int_equal(count_temp_files(root), N - 64);
  assert_int_equal(cupid_atomic_commit(&f[0]), CUPID_ERR_IO); /* its temporary file is gone */
  assert_null(slurp(in_root("f0")));
  for (int i = 1; i < N; i++) cupid_atomic_abort(&f[i]);
  assert_int_equal(count_temp_files(root), 0);
  /* Slots are reused after close. */
  CUPID_ASSERT_OK(cupid_atomic_open(in_root("again"), &f[0]));
  cupid_atomic_cleanup_all();
  assert_int_equal(count_temp_files(root), 0);
  cupid_atomic_abort(&f[0]);
}

static void on_signal(int sig) {
  cupid_atomic_cleanup_all();
  signal(sig, SIG_DFL);
  raise(sig);
}

static void test_atomic_cleanup_in_signal_handler(void **state) {
  (void)state;
  pid_t pid = fork();
  assert_true(pid >= 0);
  if (pid == 0) {
    signal(SIGTERM, on_signal);
    cupid_atomic_file a = NULL, b = NULL;
    if (cupid_atomic_open(in_root("s1"), &a) || cupid_atomic_open(in_root("s2"), &b)) _exit(10);
    fputs("half-written", cupid_atomic_stream(a));
    raise(SIGTERM);
    _exit(11); /* not reached */
  }
  int status = 0;
  assert_int_equal(waitpid(pid, &status, 0), pid);
  assert_true(WIFSIGNALED(status));
  assert_int_equal(WTERMSIG(status), SIGTERM);
  assert_int_equal(count_temp_files(root), 0);
  assert_null(slurp(in_root("s1")));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_mkdir_p, setup, teardown),
      cmocka_unit_test_setup_teardown(test_mkdir_p_blocked_by_file, setup, teardown),
      cmocka_unit_test_setup_teardown(test_atomic_commit_replaces, setup, teardown),
      cmocka_unit_test_setup_teardown(test_atomic_abort, setup, teardown),
      cmocka_unit_test_setup_teardown(test_atomic_open_failure, setup, teardown),
      cmocka_unit_test_setup_teardown(test_atomic_commit_rename_fails, setup, teardown),
      cmocka_unit_test_setup_teardown(test_atomic_commit_write_error, setup, teardown),
      cmocka_unit_test_setup_teardown(test_atomic_cleanup_all, setup, teardown),
      cmocka_unit_test_setup_teardown(test_atomic_cleanup_in_signal_handler, setup, teardown),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
