/* Private to src/solvers: what the direct solver (direct.c) and the kept factors (factor.c)
 * share. */
#ifndef CUPID_SOLVERS_INTERNAL_H
#define CUPID_SOLVERS_INTERNAL_H

#include "cupid/base.h"

/** The column (in the factored matrix's numbering) of the smallest pivot of a UMFPACK numeric
 *  factorisation of order @p n: where a singular or nearly singular matrix broke down. */
cupid_status cupid_umfpack_weakest_pivot(void *numeric, cupid_int n, cupid_int *col);

#endif
