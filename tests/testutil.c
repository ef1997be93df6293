#include "testutil.h"

#include <stdio.h>
#include <stdlib.h>

#include "cupid_config.h"

double cupid_test_random(uint64_t *state) {
  uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return 2.0 * ((double)(z >> 11) / 9007199254740992.0) - 1.0;
}

const char *cupid_test_source_path(const char *relative) {
  static _Thread_local char buf[4096];
  const char *root = getenv("CUPID_SOURCE_DIR");
  snprintf(buf, sizeof buf, "%s/%s", root ? root : CUPID_SOURCE_DIR, relative);
  return buf;
}
