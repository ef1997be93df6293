/* Error recording: one thread-local message buffer (see include/cupid/error.h). */
#include "cupid/error.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static _Thread_local char error_message[2048];
static _Thread_local char error_origin[256];

cupid_status cupid_error_set(cupid_status code, const char *func, const char *file, int line,
                             const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(error_message, sizeof error_message, fmt, ap);
  va_end(ap);
  const char *base = strrchr(file, '/');
  snprintf(error_origin, sizeof error_origin, "%s (%s:%d)", func, base ? base + 1 : file, line);
  return code;
}

const char *cupid_error_message(void) { return error_message; }

const char *cupid_error_origin(void) { return error_origin; }

void cupid_error_clear(void) {
  error_message[0] = '\0';
  error_origin[0] = '\0';
}

const char *cupid_status_name(cupid_status code) {
  switch (code) {
  case CUPID_SUCCESS: return "success";
  case CUPID_ERR_MODEL: return "model error";
  case CUPID_ERR_NUMERIC: return "numerical error";
  case CUPID_ERR_IO: return "I/O error";
  case CUPID_ERR_MEMORY: return "out of memory";
  case CUPID_ERR_ARGUMENT: return "invalid argument";
  case CUPID_ERR_UNSUPPORTED: return "not supported";
  case CUPID_ERR_INTERNAL: return "internal error";
  case CUPID_ERR_INTERRUPTED: return "interrupted";
  }
  return "unknown error";
}

int cupid_status_exit_code(cupid_status code) {
  switch (code) {
  case CUPID_SUCCESS: return 0;
  case CUPID_ERR_MODEL:
  case CUPID_ERR_UNSUPPORTED: return 1;
  case CUPID_ERR_NUMERIC: return 2;
  case CUPID_ERR_IO: return 3;
  case CUPID_ERR_INTERRUPTED: return 5;
  default: return 4;
  }
}
