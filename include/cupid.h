/** @file cupid.h  Umbrella header: the whole public API of libcupid. */
#ifndef CUPID_H
#define CUPID_H
#include "cupid/base.h"
#include "cupid/cuf.h"
#include "cupid/error.h"
#include "cupid/expr.h"
#include "cupid/io.h"
#include "cupid/model.h"
#include "cupid/pd.h"
#include "cupid/solvers.h"
#endif
