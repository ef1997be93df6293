/* Helpers shared by cupid's C tests (cmocka is the runner). */
#ifndef CUPID_TESTUTIL_H
#define CUPID_TESTUTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "cupid.h"

/** Fail the test with the recorded cupid error message unless the call succeeded. */
#define CUPID_ASSERT_OK(expr)                                                                  \
  do {                                                                                         \
    cupid_status s_ = (expr);                                                                  \
    if (s_ != CUPID_SUCCESS)                                                                   \
      fail_msg("%s failed: %s: %s [%s]", #expr, cupid_status_name(s_), cupid_error_message(), \
               cupid_error_origin());                                                          \
  } while (0)

/** Assert |a - b| <= tol, printing both values. */
#define ASSERT_NEAR(a, b, tol)                                                                 \
  do {                                                                                         \
    double a_ = (a), b_ = (b), t_ = (tol);                                                     \
    if (!(fabs(a_ - b_) <= t_))                                                                \
      fail_msg("%s = %.15g, %s = %.15g, |diff| = %.3g > %.3g", #a, a_, #b, b_, fabs(a_ - b_), t_); \
  } while (0)

/** Deterministic uniform random numbers in [-1, 1) (splitmix64), for reproducible tests. */
double cupid_test_random(uint64_t *state);

/** Create a fresh directory /tmp/cupid_test_<tag>_XXXXXX into buf (len >= 64); 0 on success. */
int cupid_test_mkdtemp(const char *tag, char *buf, size_t len);

/** Remove a directory tree (rm -rf); 0 on success. */
int cupid_test_rmtree(const char *path);

/** An affine displacement field u(p) = c + B p (patch tests). */
typedef struct {
  double c[3], B[3][3];
} cupid_test_affine;

/** Evaluate an affine field at p. */
void cupid_test_affine_eval(const cupid_test_affine *a, const double p[3], double out[3]);

/** The same as a field callback (ctx: a cupid_test_affine); density is unused. */
void cupid_test_affine_fn(void *ctx, const double p[3], double density, double out[3]);

/** A deterministic random affine field with entries of size 1e-3. */
cupid_test_affine cupid_test_random_affine(uint64_t seed);

/** A PD-only bar in uniaxial traction (cupid_test_pd_bar). */
typedef struct {
  double strain; /**< interior axial strain / (sigma/E) */
  double nu;     /**< measured -eps_xx/eps_yy at the middle section */
  int iterations;
} cupid_test_bar_result;

/**
 * The W x NY x W bar (h = 1, delta = 3, Gaussian influence, E = 1e4, sigma = 1 on y = NY; u_y
 * held on the first layer, rigid modes removed), solved by Jacobi CG to relative residual
 * @p rtol (true residual asserted). Shared by the PD bar verification tests.
 */
cupid_test_bar_result cupid_test_pd_bar(int W, int NY, cupid_pd_model_kind model,
                                        cupid_partial_volume pvr, double nu,
                                        cupid_surface_correction sc, double rtol);

/** Absolute path of a file in the source tree (tests run from the build tree). */
const char *cupid_test_source_path(const char *relative);

#endif
