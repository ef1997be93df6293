/* Arithmetic expressions (include/cupid/expr.h): a recursive-descent parser that emits a flat
 * postfix program, folding constant sub-expressions as it goes. Evaluation walks the program
 * with a fixed-size stack on the C stack, so it never allocates and is thread safe.
 *
 * Grammar (precedence low to high; '^' binds tighter than unary minus, so -2^2 = -4):
 *   expr    := term    (('+' | '-') term)*
 *   term    := unary   (('*' | '/') unary)*
 *   unary   := ('+' | '-') unary | power
 *   power   := primary ('^' unary)?              right-associative: 2^3^2 = 2^9
 *   primary := number | name | function '(' expr ')' | '(' expr ')'
 */
#include "cupid/expr.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Limits that keep hostile input from exhausting the C stack (recursion and evaluation). */
#define EXPR_MAX_LENGTH 4096
#define EXPR_MAX_DEPTH 256
#define EXPR_MAX_STACK 512

const char *const cupid_expr_model_vars[CUPID_EXPR_NVARS] = {"x", "y", "z", "t", "density"};

typedef enum {
  OP_CONST, OP_VAR, OP_NEG, OP_ADD, OP_SUB, OP_MUL, OP_DIV, OP_POW, OP_FUNC
} expr_op;

typedef enum { FN_SIN, FN_COS, FN_TAN, FN_EXP, FN_LOG, FN_SQRT, FN_ABS, FN_COUNT } expr_function;
static const char *const function_names[FN_COUNT] = {"sin", "cos", "tan", "exp",
                                                     "log", "sqrt", "abs"};

typedef struct {
  int op;       /* expr_op */
  int arg;      /* variable index or expr_function */
  double value; /* OP_CONST */
} expr_instr;

struct cupid_expr_private {
  char *text;
  expr_instr *code;
  int n_code;
  int nvars;
};

typedef enum { TOK_END, TOK_NUMBER, TOK_NAME, TOK_OP, TOK_BAD } token_kind;

typedef struct {
  token_kind kind;
  int start, length; /* byte offset and length in the text */
  char op;           /* TOK_OP: one of + - * / ^ ( ) , */
  double value;      /* TOK_NUMBER */
} token;

typedef struct {
  const char *s;
  int len, pos;
  token tok;  /* current token */
  token prev; /* the token before it (for "missing operand after '+'") */
  int has_prev;
  const char *const *vars;
  int nvars;
  expr_instr *code;
  int n_code, cap;
  int depth, paren_depth;
  int failed, error_column;
  char message[512];
} expr_parser;

static void parse_expr(expr_parser *p);

/* Record the first error only: later ones are consequences. */
static void fail_at(expr_parser *p, int offset, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void fail_at(expr_parser *p, int offset, const char *fmt, ...) {
  if (p->failed) return;
  p->failed = 1;
  p->error_column = offset + 1;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(p->message, sizeof p->message, fmt, ap);
  va_end(ap);
}

/* Printable excerpt of a token for messages (at most 24 characters, bytes >= 0x7f escaped). */
static void token_text(const expr_parser *p, const token *t, char *buf, size_t size) {
  if (t->kind == TOK_END) {
    snprintf(buf, size, "end of expression");
    return;
  }
  size_t k = 0;
  int n = t->length > 24 ? 24 : t->length;
  for (int i = 0; i < n && k + 5 < size; i++) {
    unsigned char c = (unsigned char)p->s[t->start + i];
    if (isprint(c) && c < 0x7f) buf[k++] = (char)c;
    else k += (size_t)snprintf(buf + k, size - k, "\\x%02x", c);
  }
  if (n < t->length && k + 4 < size) {
    memcpy(buf + k, "...", 3);
    k += 3;
  }
  buf[k] = '\0';
}

static int is_name_start(int c) { return isalpha(c) || c == '_'; }
static int is_name_char(int c) { return isalnum(c) || c == '_'; }

/* Scan a number at p->pos: digits [. digits] [e [+-] digits], or . digits. */
static void scan_number(expr_parser *p, token *t) {
  const char *s = p->s;
  int i = p->pos, n = p->len;
  while (i < n && isdigit((unsigned char)s[i])) i++;
  if (i < n && s[i] == '.') {
    i++;
    while (i < n && isdigit((unsigned char)s[i])) i++;
  }
  int malformed = 0;
  if (i < n && (s[i] == 'e' || s[i] == 'E')) {
    int j = i + 1;
    if (j < n && (s[j] == '+' || s[j] == '-')) j++;
    if (j < n && isdigit((unsigned char)s[j])) {
      while (j < n && isdigit((unsigned char)s[j])) j++;
      i = j;
    } else if (!(j == i + 1 && j < n && is_name_char((unsigned char)s[j]))) {
      /* "1e", "1e+", "1e-x": an exponent without digits. (A letter after 'e', as in "2exp",
       * is left to the parser, which reports a missing operator.) */
      malformed = 1;
      i = j;
    }
  }
  /* "1.2.3" or "1.5_": glued characters that cannot follow a number. */
  if (i < n && (s[i] == '.' || s[i] == '_')) {
    malformed = 1;
    while (i < n && (is_name_char((unsigned char)s[i]) || s[i] == '.')) i++;
  }
  t->kind = TOK_NUMBER;
  t->start = p->pos;
  t->length = i - p->pos;
  p->pos = i;
  char buf[64];
  if (malformed || t->length >= (int)sizeof buf) {
    char text[64];
    token_text(p, t, text, sizeof text);
    fail_at(p, t->start, "malformed number '%s' at column %d", text, t->start + 1);
    t->value = 0;
    return;
  }
  memcpy(buf, s + t->start, (size_t)t->length);
  buf[t->length] = '\0';
  errno = 0;
  t->value = strtod(buf, NULL);
  if (!isfinite(t->value))
    fail_at(p, t->start, "number '%s' at column %d is out of range", buf, t->start + 1);
}

static void next_token(expr_parser *p) {
  p->prev = p->tok;
  p->has_prev = 1;
  const char *s = p->s;
  while (p->pos < p->len && (s[p->pos] == ' ' || s[p->pos] == '\t' || s[p->pos] == '\n' ||
                             s[p->pos] == '\r'))
    p->pos++;
  token *t = &p->tok;
  t->start = p->pos;
  t->length = 0;
  t->op = 0;
  if (p->pos >= p->len) {
    t->kind = TOK_END;
    return;
  }
  unsigned char c = (unsigned char)s[p->pos];
  if (isdigit(c) || (c == '.' && p->pos + 1 < p->len && isdigit((unsigned char)s[p->pos + 1]))) {
    scan_number(p, t);
  } else if (is_name_start(c)) {
    int i = p->pos;
    while (i < p->len && is_name_char((unsigned char)s[i])) i++;
    t->kind = TOK_NAME;
    t->length = i - p->pos;
    p->pos = i;
  } else if (strchr("+-*/^(),", (int)c) && c != '\0') {
    t->kind = TOK_OP;
    t->op = (char)c;
    t->length = 1;
    p->pos++;
  } else {
    t->kind = TOK_BAD;
    t->length = 1;
    p->pos++;
    char text[16];
    token_text(p, t, text, sizeof text);
    fail_at(p, t->start, "unexpected character '%s' at column %d", text, t->start + 1);
  }
}

static int is_op(const token *t, char op) { return t->kind == TOK_OP && t->op == op; }

static int name_is(const expr_parser *p, const token *t, const char *name) {
  return (int)strlen(name) == t->length && strncmp(p->s + t->start, name, (size_t)t->length) == 0;
}

static double apply_function(int f, double a) {
  switch (f) {
  case FN_SIN: return sin(a);
  case FN_COS: return cos(a);
  case FN_TAN: return tan(a);
  case FN_EXP: return exp(a);
  case FN_LOG: return log(a);
  case FN_SQRT: return sqrt(a);
  case FN_ABS: return fabs(a);
  default: return NAN;
  }
}

static double apply_binary(int op, double a, double b) {
  switch (op) {
  case OP_ADD: return a + b;
  case OP_SUB: return a - b;
  case OP_MUL: return a * b;
  case OP_DIV: return a / b;
  case OP_POW: return pow(a, b);
  default: return NAN;
  }
}

/* Append an instruction, folding it into the constants it consumes (see the file comment:
 * in a postfix program, constant operands are exactly the trailing OP_CONST entries). */
static void emit(expr_parser *p, int op, int arg, double value) {
  if (p->failed) return;
  expr_instr *c = p->code;
  int n = p->n_code;
  if ((op == OP_NEG || op == OP_FUNC) && n >= 1 && c[n - 1].op == OP_CONST) {
    c[n - 1].value = op == OP_NEG ? -c[n - 1].value : apply_function(arg, c[n - 1].value);
    return;
  }
  if (op >= OP_ADD && op <= OP_POW && n >= 2 && c[n - 1].op == OP_CONST &&
      c[n - 2].op == OP_CONST) {
    c[n - 2].value = apply_binary(op, c[n - 2].value, c[n - 1].value);
    p->n_code--;
    return;
  }
  if (n >= p->cap) { /* cannot happen: one instruction per token at most */
    fail_at(p, p->tok.start, "internal error: expression program overflow");
    return;
  }
  c[n].op = op;
  c[n].arg = arg;
  c[n].value = value;
  p->n_code++;
}

static void list_allowed(const expr_parser *p, char *buf, size_t size) {
  size_t k = 0;
  buf[0] = '\0';
  for (int i = 0; i < p->nvars && k < size; i++)
    k += (size_t)snprintf(buf + k, size - k, "%s, ", p->vars[i]);
  if (k < size) k += (size_t)snprintf(buf + k, size - k, "pi; functions");
  for (int i = 0; i < FN_COUNT && k < size; i++)
    k += (size_t)snprintf(buf + k, size - k, "%s %s", i ? "," : "", function_names[i]);
}

/* The operand is missing where a number, name or '(' was expected. */
static void fail_missing_operand(expr_parser *p) {
  const token *t = &p->tok;
  char text[64];
  if (p->has_prev && p->prev.kind == TOK_OP && p->prev.op != '(') {
    if (t->kind == TOK_END)
      fail_at(p, t->start, "missing operand after '%c' at column %d", p->prev.op, t->start + 1);
    else {
      token_text(p, t, text, sizeof text);
      fail_at(p, t->start, "missing operand after '%c': unexpected '%s' at column %d",
              p->prev.op, text, t->start + 1);
    }
  } else if (t->kind == TOK_END) {
    fail_at(p, t->start, "missing operand at column %d", t->start + 1);
  } else {
    token_text(p, t, text, sizeof text);
    fail_at(p, t->start, "missing operand: unexpected '%s' at column %d", text, t->start + 1);
  }
}

static void parse_name(expr_parser *p) {
  token name = p->tok;
  for (int i = 0; i < p->nvars; i++)
    if (name_is(p, &name, p->vars[i])) {
      emit(p, OP_VAR, i, 0);
      next_token(p);
      return;
    }
  if (name_is(p, &name, "pi")) {
    emit(p, OP_CONST, 0, 3.14159265358979323846);
    next_token(p);
    return;
  }
  char text[64];
  token_text(p, &name, text, sizeof text);
  for (int f = 0; f < FN_COUNT; f++)
    if (name_is(p, &name, function_names[f])) {
      next_token(p);
      if (!is_op(&p->tok, '(')) {
        fail_at(p, p->tok.start, "function '%s' must be followed by '(' at column %d", text,
                p->tok.start + 1);
        return;
      }
      token open = p->tok;
      next_token(p);
      p->paren_depth++;
      parse_expr(p);
      p->paren_depth--;
      if (p->failed) return;
      if (is_op(&p->tok, ',')) {
        fail_at(p, p->tok.start, "function '%s' takes one argument: unexpected ',' at column %d",
                text, p->tok.start + 1);
        return;
      }
      if (!is_op(&p->tok, ')')) {
        fail_at(p, open.start, "unbalanced parentheses: '(' at column %d is not closed",
                open.start + 1);
        return;
      }
      emit(p, OP_FUNC, f, 0);
      next_token(p);
      return;
    }
  char allowed[256];
  list_allowed(p, allowed, sizeof allowed);
  fail_at(p, name.start, "unknown name '%s' at column %d (allowed: %s)", text, name.start + 1,
          allowed);
}

static void parse_primary(expr_parser *p) {
  if (p->failed) return;
  token *t = &p->tok;
  if (t->kind == TOK_NUMBER) {
    emit(p, OP_CONST, 0, t->value);
    next_token(p);
  } else if (t->kind == TOK_NAME) {
    parse_name(p);
  } else if (is_op(t, '(')) {
    token open = *t;
    next_token(p);
    if (is_op(&p->tok, ')')) {
      fail_at(p, p->tok.start, "empty parentheses at column %d", open.start + 1);
      return;
    }
    p->paren_depth++;
    parse_expr(p);
    p->paren_depth--;
    if (p->failed) return;
    if (!is_op(&p->tok, ')')) {
      if (p->tok.kind == TOK_END)
        fail_at(p, open.start, "unbalanced parentheses: '(' at column %d is not closed",
                open.start + 1);
      else {
        char text[64];
        token_text(p, &p->tok, text, sizeof text);
        fail_at(p, p->tok.start, "expected an operator or ')' at column %d, got '%s'",
                p->tok.start + 1, text);
      }
      return;
    }
    next_token(p);
  } else if (is_op(t, ')') && p->paren_depth == 0) {
    fail_at(p, t->start, "unbalanced parentheses: unexpected ')' at column %d", t->start + 1);
  } else {
    fail_missing_operand(p);
  }
}

/* Depth guard shared by every recursive entry point (unary chains, '^' chains, parentheses). */
static int enter(expr_parser *p) {
  if (++p->depth > EXPR_MAX_DEPTH) {
    fail_at(p, p->tok.start, "expression nested too deeply (more than %d levels) at column %d",
            EXPR_MAX_DEPTH, p->tok.start + 1);
    return 0;
  }
  return 1;
}

static void parse_unary(expr_parser *p);

static void parse_power(expr_parser *p) {
  parse_primary(p);
  if (p->failed || !is_op(&p->tok, '^')) return;
  next_token(p);
  parse_unary(p); /* right-associative, and allows 2^-1 */
  emit(p, OP_POW, 0, 0);
}

static void parse_unary(expr_parser *p) {
  if (!enter(p)) return;
  if (is_op(&p->tok, '-') || is_op(&p->tok, '+')) {
    char sign = p->tok.op;
    next_token(p);
    parse_unary(p);
    if (sign == '-') emit(p, OP_NEG, 0, 0);
  } else {
    parse_power(p);
  }
  p->depth--;
}

static void parse_term(expr_parser *p) {
  parse_unary(p);
  while (!p->failed && (is_op(&p->tok, '*') || is_op(&p->tok, '/'))) {
    int op = p->tok.op == '*' ? OP_MUL : OP_DIV;
    next_token(p);
    parse_unary(p);
    emit(p, op, 0, 0);
  }
}

static void parse_expr(expr_parser *p) {
  if (!enter(p)) return;
  parse_term(p);
  while (!p->failed && (is_op(&p->tok, '+') || is_op(&p->tok, '-'))) {
    int op = p->tok.op == '+' ? OP_ADD : OP_SUB;
    next_token(p);
    parse_term(p);
    emit(p, op, 0, 0);
  }
  p->depth--;
}

/* Largest evaluation stack the program needs (checked against EXPR_MAX_STACK). */
static int program_stack_depth(const expr_instr *code, int n) {
  int depth = 0, max = 0;
  for (int i = 0; i < n; i++) {
    if (code[i].op == OP_CONST || code[i].op == OP_VAR) depth++;
    else if (code[i].op >= OP_ADD && code[i].op <= OP_POW) depth--;
    if (depth > max) max = depth;
  }
  return max;
}

static int is_blank(const char *s, size_t n) {
  for (size_t i = 0; i < n; i++)
    if (!isspace((unsigned char)s[i])) return 0;
  return 1;
}

cupid_status cupid_expr_create(const char *text, const char *const *vars, int nvars,
                               cupid_expr *expr, int *error_column) {
  if (error_column) *error_column = 0;
  CUPID_CHECK(expr != NULL, CUPID_ERR_ARGUMENT, "cupid_expr_create: expr is NULL");
  *expr = NULL;
  CUPID_CHECK(text != NULL, CUPID_ERR_ARGUMENT, "cupid_expr_create: text is NULL");
  CUPID_CHECK(nvars >= 0 && (nvars == 0 || vars != NULL), CUPID_ERR_ARGUMENT,
              "cupid_expr_create: bad variable list");
  size_t len = strlen(text);
  if (len > EXPR_MAX_LENGTH) {
    if (error_column) *error_column = 1;
    return CUPID_ERROR(CUPID_ERR_MODEL, "expression too long (%zu characters, at most %d)", len,
                       EXPR_MAX_LENGTH);
  }
  if (is_blank(text, len)) {
    if (error_column) *error_column = 1;
    return CUPID_ERROR(CUPID_ERR_MODEL, "empty expression");
  }

  cupid_status st = CUPID_SUCCESS;
  struct cupid_expr_private *e = NULL;
  expr_parser p;
  memset(&p, 0, sizeof p);
  CUPID_TRY(cupid_calloc(1, sizeof *e, "an expression", &e));
  CUPID_TRY(cupid_strdup(text, &e->text));
  p.cap = (int)len + 1;
  CUPID_TRY(cupid_calloc((size_t)p.cap, sizeof *p.code, "an expression program", &p.code));
  p.s = e->text;
  p.len = (int)len;
  p.vars = vars;
  p.nvars = nvars;
  next_token(&p);
  p.has_prev = 0;
  parse_expr(&p);
  if (!p.failed && p.tok.kind != TOK_END) {
    char tok[64];
    token_text(&p, &p.tok, tok, sizeof tok);
    if (is_op(&p.tok, ')'))
      fail_at(&p, p.tok.start, "unbalanced parentheses: unexpected ')' at column %d",
              p.tok.start + 1);
    else
      fail_at(&p, p.tok.start, "unexpected '%s' at column %d after a complete expression%s", tok,
              p.tok.start + 1,
              p.tok.kind == TOK_NUMBER || p.tok.kind == TOK_NAME || is_op(&p.tok, '(')
                  ? " (missing operator? write 2*x, not 2x)"
                  : "");
  }
  if (!p.failed && program_stack_depth(p.code, p.n_code) > EXPR_MAX_STACK)
    fail_at(&p, 0, "expression nested too deeply (needs more than %d stack entries) at column 1",
            EXPR_MAX_STACK);
  if (p.failed) {
    if (error_column) *error_column = p.error_column;
    st = CUPID_ERROR(CUPID_ERR_MODEL, "%s", p.message);
    goto cleanup;
  }
  e->code = p.code;
  e->n_code = p.n_code;
  e->nvars = nvars;
  p.code = NULL;
  *expr = e;
  e = NULL;
cleanup:
  cupid_free(&p.code);
  cupid_expr_destroy(&e);
  return st;
}

double cupid_expr_eval(const cupid_expr expr, const double *values) {
  if (!expr) return NAN;
  double stack[EXPR_MAX_STACK];
  int top = 0;
  const expr_instr *c = expr->code;
  for (int i = 0; i < expr->n_code; i++) {
    switch (c[i].op) {
    case OP_CONST: stack[top++] = c[i].value; break;
    case OP_VAR: stack[top++] = values ? values[c[i].arg] : NAN; break;
    case OP_NEG: stack[top - 1] = -stack[top - 1]; break;
    case OP_FUNC: stack[top - 1] = apply_function(c[i].arg, stack[top - 1]); break;
    default:
      top--;
      stack[top - 1] = apply_binary(c[i].op, stack[top - 1], stack[top]);
      break;
    }
  }
  return top == 1 ? stack[0] : NAN;
}

int cupid_expr_is_constant(const cupid_expr expr) {
  return expr && expr->n_code == 1 && expr->code[0].op == OP_CONST;
}

int cupid_expr_uses(const cupid_expr expr, int var) {
  for (int i = 0; expr && i < expr->n_code; i++)
    if (expr->code[i].op == OP_VAR && expr->code[i].arg == var) return 1;
  return 0;
}

const char *cupid_expr_text(const cupid_expr expr) { return expr ? expr->text : ""; }

void cupid_expr_destroy(cupid_expr *expr) {
  if (!expr || !*expr) return;
  cupid_free(&(*expr)->text);
  cupid_free(&(*expr)->code);
  cupid_free(expr);
}
