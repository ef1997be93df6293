/* Unit tests of the error convention and checked allocation (src/core). */
#include <math.h>
#include <string.h>

#include "testutil.h"

static cupid_status fails_with_model_error(int x) {
  CUPID_CHECK(x > 0, CUPID_ERR_MODEL, "x must be positive, got %d", x);
  return CUPID_SUCCESS;
}

static cupid_status propagates(int x) {
  CUPID_CALL(fails_with_model_error(x));
  return CUPID_SUCCESS;
}

static void test_error_propagation(void **state) {
  (void)state;
  assert_int_equal(propagates(1), CUPID_SUCCESS);
  assert_int_equal(propagates(-3), CUPID_ERR_MODEL);
  assert_string_equal(cupid_error_message(), "x must be positive, got -3");
  assert_non_null(strstr(cupid_error_origin(), "fails_with_model_error"));
  assert_int_equal(cupid_status_exit_code(CUPID_ERR_MODEL), 1);
  assert_int_equal(cupid_status_exit_code(CUPID_ERR_NUMERIC), 2);
  assert_int_equal(cupid_status_exit_code(CUPID_ERR_IO), 3);
  assert_int_equal(cupid_status_exit_code(CUPID_ERR_MEMORY), 4);
}

static void test_alloc_overflow(void **state) {
  (void)state;
  double *x = (double *)1;
  assert_int_equal(cupid_calloc(SIZE_MAX / 4, 8, "huge", &x), CUPID_ERR_MEMORY);
  assert_null(x);
  assert_non_null(strstr(cupid_error_message(), "huge"));
  CUPID_ASSERT_OK(cupid_calloc(10, sizeof *x, "x", &x));
  for (int i = 0; i < 10; i++) assert_true(x[i] == 0.0);
  cupid_free(&x);
  assert_null(x);
  cupid_free(&x); /* double free is harmless */
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_error_propagation),
                                     cmocka_unit_test(test_alloc_overflow)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
