/**
 * @file error.h
 * @brief One error convention for all of cupid: status codes, messages, and the
 *        call/check macros (patterned on PetscCall/PetscCheck and CeedCall/CeedCheck).
 *
 * Every fallible function returns a ::cupid_status. On failure the function that
 * detected the problem records a message with CUPID_ERROR() (thread-local buffer);
 * callers propagate the code unchanged with CUPID_CALL() or, in functions that own
 * resources, with CUPID_TRY() + a `cleanup:` label. The command-line tool maps the
 * code to its exit status (model-format.md: 1 model error, 2 numerical, 3 I/O).
 */
#ifndef CUPID_ERROR_H
#define CUPID_ERROR_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Status codes. The first four double as the command-line exit status. */
typedef enum cupid_status {
  CUPID_SUCCESS = 0,         /**< no error */
  CUPID_ERR_MODEL = 1,       /**< the model file or user input is wrong (exit 1) */
  CUPID_ERR_NUMERIC = 2,     /**< singular/unconstrained system, solver failure (exit 2) */
  CUPID_ERR_IO = 3,          /**< a file could not be read or written (exit 3) */
  CUPID_ERR_MEMORY = 4,      /**< an allocation failed or a size overflowed (exit 4) */
  CUPID_ERR_ARGUMENT = 5,    /**< a library function got an invalid argument (exit 4) */
  CUPID_ERR_UNSUPPORTED = 6, /**< a valid request that this build cannot serve (exit 1) */
  CUPID_ERR_INTERNAL = 7,    /**< a bug: an invariant was violated (exit 4) */
  CUPID_ERR_INTERRUPTED = 8  /**< stopped by a signal after writing a checkpoint: resume it
                                  (`cupid run --resume`; exit 5) */
} cupid_status;

/** Record an error message (printf-style) and return @p code. Use via CUPID_ERROR(). */
cupid_status cupid_error_set(cupid_status code, const char *func, const char *file, int line,
                             const char *fmt, ...) __attribute__((format(printf, 5, 6)));

/** The last message recorded on this thread ("" if none). */
const char *cupid_error_message(void);

/** Where the last message was recorded: "function (file:line)". */
const char *cupid_error_origin(void);

/** Forget the last message. */
void cupid_error_clear(void);

/** Short name of a status code, e.g. "model error". */
const char *cupid_status_name(cupid_status code);

/** The command-line exit status for a status code (0..4). */
int cupid_status_exit_code(cupid_status code);

/** Record a message and evaluate to @p code. */
#define CUPID_ERROR(code, ...) cupid_error_set((code), __func__, __FILE__, __LINE__, __VA_ARGS__)

/** Call a cupid function and return its status from the caller if it failed. */
#define CUPID_CALL(expr)                                                                       \
  do {                                                                                         \
    cupid_status cupid_call_status_ = (expr);                                                  \
    if (cupid_call_status_ != CUPID_SUCCESS) return cupid_call_status_;                        \
  } while (0)

/** Return CUPID_ERROR(code, ...) from the caller unless @p cond holds. */
#define CUPID_CHECK(cond, code, ...)                                                           \
  do {                                                                                         \
    if (!(cond)) return CUPID_ERROR((code), __VA_ARGS__);                                      \
  } while (0)

/** In a function with `cupid_status st` and a `cleanup:` label: call, on failure jump. */
#define CUPID_TRY(expr)                                                                        \
  do {                                                                                         \
    st = (expr);                                                                               \
    if (st != CUPID_SUCCESS) goto cleanup;                                                     \
  } while (0)

/** In a function with `cupid_status st` and a `cleanup:` label: check, on failure jump. */
#define CUPID_TRY_CHECK(cond, code, ...)                                                       \
  do {                                                                                         \
    if (!(cond)) {                                                                             \
      st = CUPID_ERROR((code), __VA_ARGS__);                                                   \
      goto cleanup;                                                                            \
    }                                                                                          \
  } while (0)

#ifdef __cplusplus
}
#endif
#endif
