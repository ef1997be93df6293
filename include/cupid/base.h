/**
 * @file base.h
 * @brief Basic types and services shared by every subsystem: 64-bit index type,
 *        checked allocation, wall clock, peak memory, version.
 */
#ifndef CUPID_BASE_H
#define CUPID_BASE_H

#include <stddef.h>
#include <stdint.h>

#include "cupid/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Index type for everything that scales with the model (nodes, DOFs, bonds, non-zeros). */
typedef int64_t cupid_int;

/** Version string, e.g. "0.1.0". */
const char *cupid_version(void);

/**
 * Allocate @p count items of @p size bytes, zero-filled, into `*(void **)out`.
 * Fails with CUPID_ERR_MEMORY (and a message naming @p what and the byte count) on
 * overflow or exhaustion. count == 0 stores NULL and succeeds.
 * Usage: `double *x; CUPID_CALL(cupid_calloc(n, sizeof *x, "displacements", &x));`
 */
cupid_status cupid_calloc(size_t count, size_t size, const char *what, void *out);

/** Like cupid_calloc() without zero-filling (for arrays that are written in full). */
cupid_status cupid_malloc(size_t count, size_t size, const char *what, void *out);

/** Resize `*(void **)inout` to @p count items of @p size bytes (realloc semantics). */
cupid_status cupid_realloc(size_t count, size_t size, const char *what, void *inout);

/** Free `*(void **)ptr` and set it to NULL (NULL-safe). */
void cupid_free(void *ptr);

/** Duplicate a string with a checked allocation. */
cupid_status cupid_strdup(const char *s, char **out);

/** Monotonic wall-clock time in seconds. */
double cupid_wtime(void);
/** sum_k a[k] b[k], the same to the bit for any thread count: partial sums over fixed chunks
 *  of 4096 entries (in parallel), added in order. Solvers whose iterates decide which bonds
 *  break use it, so that a crack does not depend on OMP_NUM_THREADS. */
double cupid_dot(cupid_int n, const double *a, const double *b);
/** x[k] in [-0.5, 0.5) from a xorshift64 sequence started at @p seed (non-zero): a fixed probe
 *  vector for the checks of a factor or a matrix (the same numbers on every run). */
void cupid_pseudo_random(double *x, cupid_int n, uint64_t seed);

/** Solve A X = B for a small dense system (src/core/dense.c): A n x n row-major (overwritten by
 *  its elimination), B n x nrhs row-major (overwritten by X); Gaussian elimination with partial
 *  pivoting, one elimination for all right-hand sides, the same bits for any thread count.
 *  Returns 0 (B undefined) when a pivot is not above @p pivot_min in magnitude. */
int cupid_dense_solve(int n, double *A, double *B, int nrhs, double pivot_min);
/** A = A^-1 in place (n x n row-major; work: n x n) by cupid_dense_solve() on the identity: one
 *  elimination; 0 (A undefined) when a pivot is not above @p pivot_min. */
int cupid_dense_invert(int n, double *A, double *work, double pivot_min);
/** The LU factorisation P A = L U of a small dense matrix in place (A n x n row-major; L unit
 *  lower below the diagonal, U on and above; piv[c]: the row swapped with c at step c), kept
 *  for many solves; 0 when a pivot is not above @p pivot_min in magnitude. */
int cupid_dense_lu(int n, double *A, int *piv, double pivot_min);
/** b = A^-1 b with the factorisation of cupid_dense_lu(). */
void cupid_dense_lu_solve(int n, const double *A, const int *piv, double *b);
/** max |A_ij| of an n x n matrix (a relative pivot bound's scale). */
double cupid_dense_max_abs(int n, const double *A);

/* ---- Interrupts (issue 36): a run that can stop at a safe point with a checkpoint arms them
 * while it runs; the command line's SIGINT/SIGTERM handler then records a request instead of
 * ending the process, and the run writes a checkpoint at its next safe point and returns
 * CUPID_ERR_INTERRUPTED. All three are async-signal-safe (lock-free atomics). */
/** Arm (1) or disarm (0) interrupts for the run now going (disarming clears a request). */
void cupid_interrupt_arm(int armed);
/** From a signal handler: record a request. Returns 1 if an armed run will act on it, 0 if none
 *  is armed or a request was already pending (the handler then stops the process at once). */
int cupid_interrupt_request(void);
/** 1 while a request is pending. */
int cupid_interrupt_pending(void);
/** For a program without handlers of its own (the Python package during solve()): SIGINT and
 *  SIGTERM handlers that request an interrupt of an armed run; with none armed, or at a second
 *  signal, the handlers that were there before take it (re-raised). Returns 0, or -1 (errno)
 *  when sigaction failed. cupid_interrupt_uninstall() puts the previous handlers back. */
int cupid_interrupt_install(void);
void cupid_interrupt_uninstall(void);

/** Peak resident memory of this process so far, in bytes (0 if unknown). */
int64_t cupid_peak_memory(void);

/** Current resident memory of this process, in bytes (0 if unknown). */
int64_t cupid_current_memory(void);

/** Number of OpenMP threads in use (1 without OpenMP). */
int cupid_num_threads(void);

/** Set the number of OpenMP threads (n <= 0 leaves the default). */
void cupid_set_num_threads(int n);

#ifdef __cplusplus
}
#endif
#endif
