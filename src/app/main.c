/* The cupid command-line tool: see src/app/cli.c for the commands. */
#define _GNU_SOURCE /* setenv, execv */
#include <stdlib.h>
#include <unistd.h>

#include "cupid/app.h"

/* OpenMP threads that wait at a barrier spin (libgomp's default, OMP_WAIT_POLICY unset) and on
 * a machine whose cores are busy with other work a spinning thread holds the core its peer
 * needs: the notched bar (examples/notched_bar, 2 threads on 2 busy cores) took 7.7 s against
 * 0.27 s with OMP_WAIT_POLICY=PASSIVE and 0.23 s on one thread (issue 33, bench/README.md,
 * "Threads on a busy machine"). libgomp reads the variable when it is loaded, before main, so
 * the tool sets PASSIVE and runs itself again, once, unless the user chose a policy
 * (OMP_WAIT_POLICY or GOMP_SPINCOUNT set, even empty). If the new image cannot start, the run
 * goes on as it is. */
static void passive_wait_policy(char **argv) {
  if (getenv("OMP_WAIT_POLICY") || getenv("GOMP_SPINCOUNT")) return;
  if (setenv("OMP_WAIT_POLICY", "PASSIVE", 1) != 0) return;
  execv("/proc/self/exe", argv);
}

int main(int argc, char **argv) {
  passive_wait_policy(argv);
  return cupid_cli_main(argc, argv);
}
