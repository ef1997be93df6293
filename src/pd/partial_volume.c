/* Influence functions and quadrature coefficients (partial volumes) on a uniform grid
 * (paper 000 section 2.2, Eq. 9 and the beta of Eqs. 18-21; coupling.md section 5). */
#include <math.h>

#include "pd/pd_internal.h"

double cupid_pd_influence(cupid_influence kind, double r, double delta) {
  switch (kind) {
  case CUPID_INFLUENCE_GAUSSIAN: return exp(-(r * r) / (delta * delta)); /* paper 000 Eq. 9 */
  case CUPID_INFLUENCE_INVERSE: return 1.0 / r;
  case CUPID_INFLUENCE_CONSTANT: return 1.0;
  }
  return 0.0;
}

/* Bonds exactly at the horizon (common for delta = integer * h) are kept in spite of
 * rounding in |xi|. */
#define PD_TOL 1e-12

/* Parks et al. linear rule (PDLAMMPS): 1 up to delta - h/2, linear to 1/2 at delta. */
static double pdlammps(double r, double h, double delta) {
  if (r > delta + PD_TOL * h) return 0.0;
  if (r <= delta - 0.5 * h) return 1.0;
  double b = (delta + 0.5 * h - r) / h;
  return b > 1.0 ? 1.0 : b;
}

/* ---- exact volume of cube ∩ ball ----------------------------------------------------- */

/* Antiderivative of sqrt(R^2 - y^2). */
static double arc_primitive(double y, double R) {
  double t = y / R;
  if (t > 1.0) t = 1.0;
  if (t < -1.0) t = -1.0;
  double s = R * R - y * y;
  return 0.5 * (y * sqrt(s > 0 ? s : 0.0) + R * R * asin(t));
}

static void sort_small(double *v, int n) {
  for (int i = 1; i < n; i++)
    for (int j = i; j > 0 && v[j] < v[j - 1]; j--) {
      double t = v[j];
      v[j] = v[j - 1];
      v[j - 1] = t;
    }
}

/* Area of the disk y^2 + z^2 <= R^2 inside [y0,y1] x [z0,z1], exactly: the z-extent at
 * each y is min(z1, s) - max(z0, -s) with s = sqrt(R^2 - y^2); between the y where s
 * meets |z0| or |z1| each bound is either constant or +-s, integrated analytically. */
static double disk_rect_area(double R, double y0, double y1, double z0, double z1) {
  if (R <= 0) return 0.0;
  double ya = y0 > -R ? y0 : -R, yb = y1 < R ? y1 : R;
  if (ya >= yb) return 0.0;
  double pts[6];
  int n = 0;
  pts[n++] = ya;
  const double zc[2] = {z0, z1};
  for (int c = 0; c < 2; c++)
    if (fabs(zc[c]) < R) {
      double y = sqrt(R * R - zc[c] * zc[c]);
      if (y > ya && y < yb) pts[n++] = y;
      if (-y > ya && -y < yb) pts[n++] = -y;
    }
  pts[n++] = yb;
  sort_small(pts, n);
  double area = 0.0;
  for (int p = 0; p + 1 < n; p++) {
    double a = pts[p], b = pts[p + 1];
    if (b <= a) continue;
    double mid = 0.5 * (a + b), sm = sqrt(R * R - mid * mid);
    int up_arc = sm < z1, lo_arc = -sm > z0;
    double up = up_arc ? sm : z1, lo = lo_arc ? -sm : z0;
    if (up <= lo) continue;
    double arc = arc_primitive(b, R) - arc_primitive(a, R);
    area += (up_arc ? arc : z1 * (b - a)) - (lo_arc ? -arc : z0 * (b - a));
  }
  return area;
}

typedef struct {
  double delta, y0, y1, z0, z1;
} slab;

static double slab_area(const slab *s, double x) {
  double r2 = s->delta * s->delta - x * x;
  return r2 > 0 ? disk_rect_area(sqrt(r2), s->y0, s->y1, s->z0, s->z1) : 0.0;
}

/* Tanh-sinh (double-exponential) quadrature of the slab area over [a, b]: it converges
 * exponentially even with the (x - a)^(3/2) end-point behaviour of the pieces. The step is
 * halved (reusing the points) until two levels agree to ~1e-15 of the slab scale. */
static double tanh_sinh(const slab *s, double a, double b, double scale) {
  const double c = 0.5 * (a + b), hw = 0.5 * (b - a), half_pi = 1.5707963267948966;
  const double tmax = 3.6; /* beyond, 1 - tanh(pi/2 sinh t) < 1e-24 */
  double step = 0.5;
  double sum = half_pi * slab_area(s, c); /* t = 0: weight pi/2 */
  double prev = 0.0, est = 0.0;
  for (int level = 0; level < 10; level++) {
    /* New points: all k*step at level 0, the odd multiples afterwards. */
    const int stride = level == 0 ? 1 : 2;
    for (int k = 1;; k += stride) {
      const double t = k * step;
      if (t > tmax) break;
      const double u = half_pi * sinh(t);
      const double eu = exp(-2.0 * u);
      const double gap = 2.0 * eu / (1.0 + eu);                 /* 1 - tanh(u) */
      const double w = half_pi * cosh(t) * 4.0 * eu / ((1.0 + eu) * (1.0 + eu)); /* pi/2 cosh t / cosh^2 u */
      sum += w * (slab_area(s, a + hw * gap) + slab_area(s, b - hw * gap));
    }
    est = hw * step * sum;
    if (level > 0 && fabs(est - prev) <= 1e-15 * scale) break;
    prev = est;
    step *= 0.5;
  }
  return est;
}

/* Fraction of the cube of side h centred at (cx, cy, cz) inside the ball of radius delta
 * about the origin: integral over x of the disk-rectangle area, split where the disk's
 * radius crosses the distance to an edge line or a corner of the rectangle (the area is
 * analytic between those points, with (x - x_b)^(3/2) behaviour at them). */
static double exact_fraction(double cx, double cy, double cz, double h, double delta) {
  /* Canonical order |cx| >= |cy| >= |cz| makes beta exactly symmetric. */
  double c[3] = {fabs(cx), fabs(cy), fabs(cz)};
  sort_small(c, 3);
  const double X = c[2], Y = c[1], Z = c[0];
  const double hh = 0.5 * h;
  /* Nearest and farthest points of the cube. */
  double dmin2 = 0.0, dmax2 = 0.0;
  for (int a = 0; a < 3; a++) {
    double lo = c[a] - hh, hi = c[a] + hh;
    double near = lo > 0 ? lo : 0.0;
    dmin2 += near * near;
    dmax2 += hi * hi;
  }
  if (dmin2 >= delta * delta) return 0.0;
  if (dmax2 <= delta * delta) return 1.0;
  slab s = {delta, Y - hh, Y + hh, Z - hh, Z + hh};
  double xa = X - hh > -delta ? X - hh : -delta, xb = X + hh < delta ? X + hh : delta;
  if (xa >= xb) return 0.0;
  double pts[24];
  int n = 0;
  pts[n++] = xa;
  const double ed[4] = {s.y0, s.y1, s.z0, s.z1};
  double rs[8];
  for (int e = 0; e < 4; e++) rs[e] = fabs(ed[e]);
  for (int e = 0; e < 4; e++) rs[4 + e] = sqrt(ed[e / 2] * ed[e / 2] + ed[2 + e % 2] * ed[2 + e % 2]);
  for (int e = 0; e < 8; e++)
    if (rs[e] < delta) {
      double x = sqrt(delta * delta - rs[e] * rs[e]);
      if (x > xa && x < xb) pts[n++] = x;
      if (-x > xa && -x < xb) pts[n++] = -x;
    }
  pts[n++] = xb;
  sort_small(pts, n);
  double vol = 0.0;
  for (int p = 0; p + 1 < n; p++)
    if (pts[p + 1] > pts[p]) vol += tanh_sinh(&s, pts[p], pts[p + 1], h * h * h);
  double beta = vol / (h * h * h);
  return beta < 0 ? 0.0 : (beta > 1 ? 1.0 : beta);
}

double cupid_pd_partial_volume(cupid_partial_volume rule, double dx, double dy, double dz,
                               double h, double delta) {
  double r = sqrt(dx * dx + dy * dy + dz * dz);
  switch (rule) {
  case CUPID_PARTIAL_NONE: return r <= delta + PD_TOL * h ? 1.0 : 0.0;
  case CUPID_PARTIAL_PDLAMMPS: return pdlammps(r, h, delta);
  case CUPID_PARTIAL_EXACT: return exact_fraction(dx, dy, dz, h, delta);
  }
  return 0.0;
}

double cupid_pd_partial_volume_1d(cupid_partial_volume rule, double d, double h, double delta) {
  double r = fabs(d);
  switch (rule) {
  case CUPID_PARTIAL_NONE: return r <= delta + PD_TOL * h ? 1.0 : 0.0;
  case CUPID_PARTIAL_PDLAMMPS: return pdlammps(r, h, delta);
  case CUPID_PARTIAL_EXACT: {
    double lo = r - 0.5 * h, hi = r + 0.5 * h;
    if (lo < -delta) lo = -delta;
    if (hi > delta) hi = delta;
    return hi > lo ? (hi - lo) / h : 0.0;
  }
  }
  return 0.0;
}
