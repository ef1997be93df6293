/**
 * @file expr.h
 * @brief Small, safe arithmetic expressions for loads, constraints and fields.
 *
 * Grammar (model-format.md): numbers, named variables, + - * / ^ (right-assoc),
 * unary minus, parentheses, functions sin cos tan exp log sqrt abs, constant pi.
 * Expressions are compiled once into a flat program and evaluated without allocation,
 * so they are safe to evaluate from OpenMP threads.
 */
#ifndef CUPID_EXPR_H
#define CUPID_EXPR_H

#include "cupid/base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cupid_expr_private *cupid_expr;

/** The variables every model expression may use, in this order: x y z t density. */
#define CUPID_EXPR_NVARS 5
extern const char *const cupid_expr_model_vars[CUPID_EXPR_NVARS];

/**
 * Compile @p text. @p vars names the variables (their order is the order of values given
 * to cupid_expr_eval()). On a syntax error returns CUPID_ERR_MODEL with a message such as
 * "unexpected ')' at column 7" and stores the 1-based column in @p error_column (if given).
 */
cupid_status cupid_expr_create(const char *text, const char *const *vars, int nvars,
                               cupid_expr *expr, int *error_column);

/** Evaluate with the variable values @p values (in the order given at creation). */
double cupid_expr_eval(const cupid_expr expr, const double *values);

/** 1 if the expression does not depend on any variable (it folds to a constant). */
int cupid_expr_is_constant(const cupid_expr expr);

/** 1 if the expression names variable @p var (its index in the create call's list), whatever
 *  its value does with it ("0*t" uses t). */
int cupid_expr_uses(const cupid_expr expr, int var);

/** The source text the expression was compiled from. */
const char *cupid_expr_text(const cupid_expr expr);

/** Destroy and set *expr to NULL (NULL-safe). */
void cupid_expr_destroy(cupid_expr *expr);

#ifdef __cplusplus
}
#endif
#endif
