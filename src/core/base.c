/* Checked allocation, clocks, memory statistics, threads (see include/cupid/base.h). */
#define _POSIX_C_SOURCE 200809L /* clock_gettime; gcc -fopenmp only gets it via -D_REENTRANT */
#include "cupid/base.h"

#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "cupid_config.h"

const char *cupid_version(void) { return CUPID_VERSION; }

static cupid_status alloc_impl(size_t count, size_t size, const char *what, int zero, void *out) {
  void **p = (void **)out;
  *p = NULL;
  if (count == 0 || size == 0) return CUPID_SUCCESS;
  if (count > SIZE_MAX / size)
    return CUPID_ERROR(CUPID_ERR_MEMORY, "allocation of %zu x %zu bytes for %s overflows", count,
                       size, what ? what : "an array");
  *p = zero ? calloc(count, size) : malloc(count * size);
  if (!*p)
    return CUPID_ERROR(CUPID_ERR_MEMORY, "out of memory allocating %.3g MB for %s",
                       (double)count * (double)size / 1e6, what ? what : "an array");
  return CUPID_SUCCESS;
}

cupid_status cupid_calloc(size_t count, size_t size, const char *what, void *out) {
  return alloc_impl(count, size, what, 1, out);
}

cupid_status cupid_malloc(size_t count, size_t size, const char *what, void *out) {
  return alloc_impl(count, size, what, 0, out);
}

cupid_status cupid_realloc(size_t count, size_t size, const char *what, void *inout) {
  void **p = (void **)inout;
  if (count == 0 || size == 0) {
    free(*p);
    *p = NULL;
    return CUPID_SUCCESS;
  }
  if (count > SIZE_MAX / size)
    return CUPID_ERROR(CUPID_ERR_MEMORY, "allocation of %zu x %zu bytes for %s overflows", count,
                       size, what ? what : "an array");
  void *q = realloc(*p, count * size);
  if (!q)
    return CUPID_ERROR(CUPID_ERR_MEMORY, "out of memory growing %s to %.3g MB",
                       what ? what : "an array", (double)count * (double)size / 1e6);
  *p = q;
  return CUPID_SUCCESS;
}

void cupid_free(void *ptr) {
  void **p = (void **)ptr;
  if (!p) return;
  free(*p);
  *p = NULL;
}

cupid_status cupid_strdup(const char *s, char **out) {
  size_t n = strlen(s) + 1;
  CUPID_CALL(cupid_malloc(n, 1, "a string", out));
  memcpy(*out, s, n);
  return CUPID_SUCCESS;
}

#define DOT_CHUNK 4096
#define DOT_STACK 512

static double dot_chunk(cupid_int n, const double *a, const double *b) {
  double s = 0.0;
  for (cupid_int k = 0; k < n; k++) s += a[k] * b[k];
  return s;
}

void cupid_pseudo_random(double *x, cupid_int n, uint64_t seed) {
  uint64_t s = seed;
  for (cupid_int k = 0; k < n; k++) {
    s ^= s << 13, s ^= s >> 7, s ^= s << 17;
    x[k] = (double)(s >> 11) / 9007199254740992.0 - 0.5;
  }
}

double cupid_dot(cupid_int n, const double *a, const double *b) {
  const cupid_int nc = (n + DOT_CHUNK - 1) / DOT_CHUNK;
  if (nc <= 4) return dot_chunk(n, a, b);
  double stack[DOT_STACK], *part = nc <= DOT_STACK ? stack : malloc((size_t)nc * sizeof *part);
  if (!part) return dot_chunk(n, a, b); /* the same sum, in one thread */
#pragma omp parallel for schedule(static)
  for (cupid_int c = 0; c < nc; c++) {
    const cupid_int k0 = c * DOT_CHUNK, len = k0 + DOT_CHUNK <= n ? DOT_CHUNK : n - k0;
    part[c] = dot_chunk(len, a + k0, b + k0);
  }
  double s = 0.0;
  for (cupid_int c = 0; c < nc; c++) s += part[c];
  if (part != stack) free(part);
  return s;
}

double cupid_wtime(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int64_t cupid_peak_memory(void) {
  struct rusage ru;
  if (getrusage(RUSAGE_SELF, &ru) != 0) return 0;
  return (int64_t)ru.ru_maxrss * 1024; /* Linux reports kilobytes */
}

int64_t cupid_current_memory(void) {
  FILE *f = fopen("/proc/self/statm", "r");
  if (!f) return 0;
  long pages = 0, resident = 0;
  int n = fscanf(f, "%ld %ld", &pages, &resident);
  fclose(f);
  if (n != 2) return 0;
  return (int64_t)resident * (int64_t)sysconf(_SC_PAGESIZE);
}

int cupid_num_threads(void) {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

void cupid_set_num_threads(int n) {
#ifdef _OPENMP
  if (n > 0) omp_set_num_threads(n);
#else
  (void)n;
#endif
}

/* ---------------------------------------------------------------- interrupts (issue 36) */

static atomic_int interrupt_armed, interrupt_pending;

void cupid_interrupt_arm(int armed) {
  atomic_store(&interrupt_pending, 0);
  atomic_store(&interrupt_armed, armed ? 1 : 0);
}

int cupid_interrupt_request(void) {
  if (!atomic_load(&interrupt_armed)) return 0;
  return atomic_exchange(&interrupt_pending, 1) == 0; /* a second request: stop at once */
}

int cupid_interrupt_pending(void) { return atomic_load(&interrupt_pending); }

/* The handlers of cupid_interrupt_install: the previous ones, kept to hand signals back. */
static struct sigaction previous[2];
static const int handled[2] = {SIGINT, SIGTERM};
static atomic_int installed;

static void on_interrupt(int sig) {
  if (cupid_interrupt_request()) return; /* the run stops at its next safe point */
  const int k = sig == SIGINT ? 0 : 1;   /* not armed, or a second signal: as before */
  sigaction(sig, &previous[k], NULL);
  raise(sig);
}

int cupid_interrupt_install(void) {
  if (atomic_exchange(&installed, 1)) return 0;
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  for (int k = 0; k < 2; k++)
    if (sigaction(handled[k], &sa, &previous[k]) != 0) {
      for (int j = 0; j < k; j++) sigaction(handled[j], &previous[j], NULL);
      atomic_store(&installed, 0);
      return -1;
    }
  return 0;
}

void cupid_interrupt_uninstall(void) {
  if (!atomic_exchange(&installed, 0)) return;
  for (int k = 0; k < 2; k++) sigaction(handled[k], &previous[k], NULL);
}
