/**
 * @file cupid.h
 * @brief The umbrella header: every public header of libcupid.
 *
 * A program that runs models needs only problem.h (the problem object); the subsystem headers
 * serve programs that build grids, beams, couplings or solves themselves. Link with
 * `pkg-config --cflags --libs cupid`.
 */
#ifndef CUPID_H
#define CUPID_H

#include "cupid/base.h"
#include "cupid/error.h"
#include "cupid/expr.h"
#include "cupid/io.h"
#include "cupid/model.h"
#include "cupid/solvers.h"
#include "cupid/pd.h"
#include "cupid/cuf.h"
#include "cupid/coupling.h"
#include "cupid/dynamics.h"
#include "cupid/problem.h"
#include "cupid/app.h"

#endif
