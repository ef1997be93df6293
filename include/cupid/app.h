/**
 * @file app.h
 * @brief The `cupid` command line (src/app/cli.c): parse, then the problem's stages
 *        (problem.h), and the exit status.
 */
#ifndef CUPID_APP_H
#define CUPID_APP_H

#include "cupid/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The command-line tool (returns the exit status). */
int cupid_cli_main(int argc, char **argv);

#ifdef __cplusplus
}
#endif
#endif
