/* The cupid command-line tool: see src/app/cli.c for the commands. */
#include "cupid/app.h"

int main(int argc, char **argv) { return cupid_cli_main(argc, argv); }
