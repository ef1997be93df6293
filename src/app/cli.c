/* Placeholder replaced by the lead's command-line implementation. */
#include <stdio.h>

#include "cupid/app.h"

int cupid_cli_main(int argc, char **argv) {
  (void)argc;
  (void)argv;
  printf("cupid %s\n", cupid_version());
  return 0;
}
