/* Unit tests of the expression compiler (src/io/expr.c): values, precedence, folding, every
 * error kind with its column, and random inputs that must never crash. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

/* Results are exact up to libm rounding: 1e-12 relative is far below any real mistake. */
#define TOL 1e-12
#define PI 3.14159265358979323846
#define EULER 2.71828182845904523536

static double eval_model(const char *text, double x, double y, double z, double t, double rho) {
  cupid_expr e = NULL;
  CUPID_ASSERT_OK(cupid_expr_create(text, cupid_expr_model_vars, CUPID_EXPR_NVARS, &e, NULL));
  const double v[CUPID_EXPR_NVARS] = {x, y, z, t, rho};
  double r = cupid_expr_eval(e, v);
  assert_string_equal(cupid_expr_text(e), text);
  cupid_expr_destroy(&e);
  assert_null(e);
  return r;
}

static double eval_const(const char *text) { return eval_model(text, 0, 0, 0, 0, 0); }

static void test_arithmetic(void **state) {
  (void)state;
  ASSERT_NEAR(eval_const("1+2*3"), 7, TOL);
  ASSERT_NEAR(eval_const("(1+2)*3"), 9, TOL);
  ASSERT_NEAR(eval_const("1-2-3"), -4, TOL);       /* left-associative */
  ASSERT_NEAR(eval_const("10/4/5"), 0.5, TOL);     /* left-associative */
  ASSERT_NEAR(eval_const("2^3^2"), 512, TOL);      /* right-associative: 2^9 */
  ASSERT_NEAR(eval_const("-2^2"), -4, TOL);        /* ^ binds tighter than unary minus */
  ASSERT_NEAR(eval_const("2^-1"), 0.5, TOL);       /* unary minus in an exponent */
  ASSERT_NEAR(eval_const("(-2)^2"), 4, TOL);
  ASSERT_NEAR(eval_const("--3"), 3, TOL);
  ASSERT_NEAR(eval_const("+3 - -2"), 5, TOL);
  ASSERT_NEAR(eval_const("2*-3"), -6, TOL);
  ASSERT_NEAR(eval_const("1 + 2 * 3 ^ 2 / 6"), 4, TOL);
  ASSERT_NEAR(eval_const(" \t( 1 )\n"), 1, TOL);
}

static void test_numbers(void **state) {
  (void)state;
  ASSERT_NEAR(eval_const("1e-3"), 1e-3, 1e-18);
  ASSERT_NEAR(eval_const("1E+2"), 100, TOL);
  ASSERT_NEAR(eval_const(".5"), 0.5, TOL);
  ASSERT_NEAR(eval_const("2."), 2, TOL);
  ASSERT_NEAR(eval_const("2.5e1"), 25, TOL);
  ASSERT_NEAR(eval_const("007"), 7, TOL);
  ASSERT_NEAR(eval_const("1e-400"), 0, 0); /* underflow to zero is not an error */
}

static void test_functions(void **state) {
  (void)state;
  ASSERT_NEAR(eval_const("pi"), PI, TOL);
  ASSERT_NEAR(eval_const("sin(pi/2)"), 1, TOL);
  ASSERT_NEAR(eval_const("cos(0)"), 1, TOL);
  ASSERT_NEAR(eval_const("tan(pi/4)"), 1, TOL);
  ASSERT_NEAR(eval_const("exp(1)"), EULER, TOL);
  ASSERT_NEAR(eval_const("log(exp(2))"), 2, TOL);
  ASSERT_NEAR(eval_const("sqrt(16)"), 4, TOL);
  ASSERT_NEAR(eval_const("abs(-3)"), 3, TOL);
  ASSERT_NEAR(eval_const("sqrt(abs(-2)*8)^2"), 16, TOL);
  ASSERT_NEAR(eval_const("-sin(0)+cos(0)"), 1, TOL);
}

static void test_variables(void **state) {
  (void)state;
  ASSERT_NEAR(eval_model("1e-3*y", 0, 100, 0, 0, 0), 0.1, TOL);
  ASSERT_NEAR(eval_model("x+2*y+3*z+4*t+5*density", 1, 2, 3, 4, 5), 1 + 4 + 9 + 16 + 25, TOL);
  ASSERT_NEAR(eval_model("-9.81e-9*density", 0, 0, 0, 0, 7800), -9.81e-9 * 7800, 1e-18);
  ASSERT_NEAR(eval_model("sin(pi*x/10)*t^2", 5, 0, 0, 3, 0), 9, TOL);
  /* Any variable list works; names are matched whole ("ab" is not "a"). */
  const char *vars[] = {"a", "ab", "c_1"};
  cupid_expr e = NULL;
  CUPID_ASSERT_OK(cupid_expr_create("a*100 + ab*10 + c_1", vars, 3, &e, NULL));
  const double v[3] = {1, 2, 3};
  ASSERT_NEAR(cupid_expr_eval(e, v), 123, TOL);
  assert_false(cupid_expr_is_constant(e));
  cupid_expr_destroy(&e);
  /* With no variables, x is unknown. */
  assert_int_equal(cupid_expr_create("x", NULL, 0, &e, NULL), CUPID_ERR_MODEL);
  assert_null(e);
}

static void test_constant_folding(void **state) {
  (void)state;
  const char *constant[] = {"1+2*3", "2*pi+sin(0)", "-(3)", "sqrt(2)^2", "((((1))))", "2^3^2"};
  for (size_t i = 0; i < sizeof constant / sizeof *constant; i++) {
    cupid_expr e = NULL;
    CUPID_ASSERT_OK(cupid_expr_create(constant[i], cupid_expr_model_vars, 5, &e, NULL));
    if (!cupid_expr_is_constant(e)) fail_msg("'%s' should fold to a constant", constant[i]);
    /* A folded expression needs no variable values. */
    assert_true(isfinite(cupid_expr_eval(e, NULL)));
    cupid_expr_destroy(&e);
  }
  const char *variable[] = {"x", "0*x", "1+2*y", "sin(t)", "density^0"};
  for (size_t i = 0; i < sizeof variable / sizeof *variable; i++) {
    cupid_expr e = NULL;
    CUPID_ASSERT_OK(cupid_expr_create(variable[i], cupid_expr_model_vars, 5, &e, NULL));
    if (cupid_expr_is_constant(e)) fail_msg("'%s' depends on a variable", variable[i]);
    cupid_expr_destroy(&e);
  }
  /* Folding must keep the value: (2+3)*x at x = 4 with the constant part folded. */
  ASSERT_NEAR(eval_model("(2+3)*x - 2^2", 4, 0, 0, 0, 0), 16, TOL);
  assert_false(cupid_expr_is_constant(NULL));
}

typedef struct {
  const char *text;
  int column;
  const char *fragment;
} expr_error_case;

static void check_error(const char *text, int column, const char *fragment) {
  cupid_expr e = (cupid_expr)1;
  int col = -1;
  cupid_status st = cupid_expr_create(text, cupid_expr_model_vars, CUPID_EXPR_NVARS, &e, &col);
  if (st != CUPID_ERR_MODEL) fail_msg("'%.40s' should fail, got status %d", text, st);
  assert_null(e);
  if (col != column)
    fail_msg("'%.40s': column %d, expected %d (%s)", text, col, column, cupid_error_message());
  if (!strstr(cupid_error_message(), fragment))
    fail_msg("'%.40s': message '%s' lacks '%s'", text, cupid_error_message(), fragment);
}

/* Which variables an expression names (dynamic runs evaluate the ones naming t every step). */
static void test_uses(void **state) {
  (void)state;
  const char *texts[5] = {"100*t", "x*(x-0.3)*(x-1.7)*t", "0*t + y", "sin(z) + density", "3"};
  const int uses_t[5] = {1, 1, 1, 0, 0}, uses_x[5] = {0, 1, 0, 0, 0};
  for (int k = 0; k < 5; k++) {
    cupid_expr e = NULL;
    CUPID_ASSERT_OK(cupid_expr_create(texts[k], cupid_expr_model_vars, CUPID_EXPR_NVARS, &e, NULL));
    assert_int_equal(cupid_expr_uses(e, 3), uses_t[k]);
    assert_int_equal(cupid_expr_uses(e, 0), uses_x[k]);
    cupid_expr_destroy(&e);
  }
  assert_int_equal(cupid_expr_uses(NULL, 3), 0);
}

static void test_errors(void **state) {
  (void)state;
  static const expr_error_case cases[] = {
      {"", 1, "empty expression"},
      {"   ", 1, "empty expression"},
      {"1+", 3, "missing operand after '+' at column 3"},
      {"1+*2", 3, "missing operand after '+'"},
      {"*2", 1, "missing operand"},
      {"2*(3-)", 6, "missing operand after '-'"},
      {"foo+1", 1, "unknown name 'foo' at column 1"},
      {"x+densty", 3, "allowed: x, y, z, t, density, pi; functions sin, cos"},
      {"(1+2", 1, "unbalanced parentheses: '(' at column 1 is not closed"},
      {"sin(x", 4, "unbalanced parentheses: '(' at column 4 is not closed"},
      {"1+2)", 4, "unbalanced parentheses: unexpected ')' at column 4"},
      {")", 1, "unbalanced parentheses"},
      {"()", 2, "empty parentheses"},
      {"(1 2)", 4, "expected an operator or ')' at column 4"},
      {"2 3", 3, "unexpected '3' at column 3 after a complete expression"},
      {"2x", 2, "missing operator"},
      {"x(2)", 2, "after a complete expression"},
      {"sin x", 5, "function 'sin' must be followed by '('"},
      {"sqrt", 5, "function 'sqrt' must be followed by '('"},
      {"sin(1,2)", 6, "takes one argument"},
      {"1e", 1, "malformed number '1e'"},
      {"1e+", 1, "malformed number"},
      {"1.2.3", 1, "malformed number '1.2.3'"},
      {"3*1e999", 3, "out of range"},
      {"2#3", 2, "unexpected character '#' at column 2"},
      {"x\xff", 2, "unexpected character '\\xff'"},
      {"x,y", 2, "unexpected ','"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof *cases; i++)
    check_error(cases[i].text, cases[i].column, cases[i].fragment);

  /* Nesting limits: parentheses, unary chains and '^' chains all recurse. */
  char buf[8192];
  int n = 0;
  for (int i = 0; i < 300; i++) buf[n++] = '(';
  buf[n++] = '1';
  for (int i = 0; i < 300; i++) buf[n++] = ')';
  buf[n] = '\0';
  check_error(buf, 129, "nested too deeply");
  n = 0;
  for (int i = 0; i < 300; i++) buf[n++] = '-';
  strcpy(buf + n, "1");
  check_error(buf, 256, "nested too deeply");
  n = 0;
  for (int i = 0; i < 300; i++) n += sprintf(buf + n, "2^");
  strcpy(buf + n, "1");
  check_error(buf, 511, "nested too deeply");
  /* A deep but legal expression still works (128 parentheses = 256 levels is the limit). */
  n = 0;
  for (int i = 0; i < 100; i++) buf[n++] = '(';
  buf[n++] = 'x';
  for (int i = 0; i < 100; i++) buf[n++] = ')';
  buf[n] = '\0';
  ASSERT_NEAR(eval_model(buf, 7, 0, 0, 0, 0), 7, 0);
  /* Over-long input. */
  n = 0;
  while (n < 5000) n += sprintf(buf + n, "1+");
  buf[n - 1] = '\0';
  check_error(buf, 1, "expression too long");
  /* A long flat expression just under the limit compiles (stack depth stays 2). */
  n = 0;
  while (n < 4000) n += sprintf(buf + n, "x+");
  strcpy(buf + n, "1");
  ASSERT_NEAR(eval_model(buf, 1, 0, 0, 0, 0), 2001, 0);

  /* Bad arguments. */
  cupid_expr e = NULL;
  assert_int_equal(cupid_expr_create(NULL, NULL, 0, &e, NULL), CUPID_ERR_ARGUMENT);
  assert_int_equal(cupid_expr_create("1", NULL, 0, NULL, NULL), CUPID_ERR_ARGUMENT);
  cupid_expr_destroy(&e);
  cupid_expr_destroy(NULL);
}

/* Compile, and on success evaluate: no input may crash, and failures carry a sane column. */
static void try_text(const char *text) {
  cupid_expr e = NULL;
  int col = 0;
  cupid_status st = cupid_expr_create(text, cupid_expr_model_vars, CUPID_EXPR_NVARS, &e, &col);
  if (st == CUPID_SUCCESS) {
    const double v[5] = {0.5, -1.5, 2.0, 0.25, 3.0};
    (void)cupid_expr_eval(e, v);
    if (cupid_expr_is_constant(e)) (void)cupid_expr_eval(e, NULL);
    cupid_expr_destroy(&e);
    return;
  }
  if (st != CUPID_ERR_MODEL) fail_msg("'%s': unexpected status %d", text, st);
  assert_null(e);
  if (col < 1 || col > (int)strlen(text) + 1)
    fail_msg("'%s': error column %d out of range", text, col);
  assert_true(cupid_error_message()[0] != '\0');
}

static void test_random_bytes(void **state) {
  (void)state;
  uint64_t seed = 12345;
  char buf[64];
  for (int iter = 0; iter < 100000; iter++) {
    int n = (int)((cupid_test_random(&seed) + 1) * 20);
    for (int i = 0; i < n; i++) {
      double r = cupid_test_random(&seed);
      /* Mostly expression characters, some arbitrary bytes (no NUL: the text is a C string). */
      if (r < 0.6) buf[i] = "xyzt0123456789.e+-*/^() ,pisnqrtcolgabd"[(int)((r + 1) / 1.6 * 38)];
      else buf[i] = (char)(1 + (int)((r - 0.6) / 0.4 * 254));
    }
    buf[n] = '\0';
    try_text(buf);
  }
}

static void test_random_tokens(void **state) {
  (void)state;
  static const char *const tokens[] = {"x",  "y",    "density", "1",   "2.5", ".5",  "1e-3",
                                       "+",  "-",    "*",       "/",   "^",   "(",   ")",
                                       "(",  ")",    "sin",     "sqrt", "pi", " ",   ",",
                                       "t",  "abs(", "log(",    "e",   "2.",  "1e"};
  const int n_tokens = (int)(sizeof tokens / sizeof *tokens);
  uint64_t seed = 777;
  char buf[512];
  int ok = 0;
  for (int iter = 0; iter < 100000; iter++) {
    int n = (int)((cupid_test_random(&seed) + 1) * 12), k = 0;
    buf[0] = '\0';
    for (int i = 0; i < n; i++) {
      int t = (int)((cupid_test_random(&seed) + 1) / 2 * n_tokens);
      if (t >= n_tokens) t = n_tokens - 1;
      k += snprintf(buf + k, sizeof buf - (size_t)k, "%s", tokens[t]);
    }
    cupid_expr e = NULL;
    if (cupid_expr_create(buf, cupid_expr_model_vars, 5, &e, NULL) == CUPID_SUCCESS) ok++;
    cupid_expr_destroy(&e);
    try_text(buf);
  }
  /* The generator must also reach valid expressions, or the loop tests only the error paths. */
  assert_true(ok > 1000);
}

/* The compiled program is read-only at evaluation: many threads can share one expression. */
static void test_threads(void **state) {
  (void)state;
  cupid_expr e = NULL;
  CUPID_ASSERT_OK(cupid_expr_create("sin(x)*y^2 - t/(1+z^2)", cupid_expr_model_vars, 5, &e, NULL));
  enum { N = 20000 };
  static double serial[N], parallel[N];
  for (int i = 0; i < N; i++) {
    double v[5] = {0.001 * i, 1 + 1e-4 * i, -0.5, 2, 0};
    serial[i] = cupid_expr_eval(e, v);
  }
#pragma omp parallel for
  for (int i = 0; i < N; i++) {
    double v[5] = {0.001 * i, 1 + 1e-4 * i, -0.5, 2, 0};
    parallel[i] = cupid_expr_eval(e, v);
  }
  for (int i = 0; i < N; i++) assert_true(serial[i] == parallel[i]);
  cupid_expr_destroy(&e);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_arithmetic),       cmocka_unit_test(test_numbers),
      cmocka_unit_test(test_uses),
      cmocka_unit_test(test_functions),        cmocka_unit_test(test_variables),
      cmocka_unit_test(test_constant_folding), cmocka_unit_test(test_errors),
      cmocka_unit_test(test_random_bytes),     cmocka_unit_test(test_random_tokens),
      cmocka_unit_test(test_threads),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
