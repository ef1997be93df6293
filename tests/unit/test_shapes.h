/* Shapes for the unit tests of PD regions and holes (issue 35: test_pd_shapes.c,
 * test_pd_cut_volume.c): a sphere, a cylinder along an axis (through everything when
 * from > to) and a box, each with its bounding box as cupid_shape wants it. Header only. */
#ifndef CUPID_TEST_SHAPES_H
#define CUPID_TEST_SHAPES_H

#include <math.h>
#include <string.h>

#include "cupid/model.h"

static inline cupid_shape sphere(double x, double y, double z, double r) {
  cupid_shape s;
  memset(&s, 0, sizeof s);
  s.kind = CUPID_SHAPE_SPHERE;
  s.center[0] = x, s.center[1] = y, s.center[2] = z;
  s.radius = r;
  for (int a = 0; a < 3; a++) {
    s.box.has[a] = 1;
    s.box.lo[a] = s.center[a] - r;
    s.box.hi[a] = s.center[a] + r;
  }
  return s;
}

/* along axis, through [from, to] (through everything when from > to) */
static inline cupid_shape cylinder(int axis, double a, double b, double r, double from, double to) {
  cupid_shape s;
  memset(&s, 0, sizeof s);
  s.kind = CUPID_SHAPE_CYLINDER;
  s.axis = axis;
  for (int q = 0, t = 0; q < 3; q++)
    if (q != axis) s.center[q] = t++ ? b : a;
  s.radius = r;
  for (int q = 0; q < 3; q++) {
    s.box.has[q] = 1;
    s.box.lo[q] = s.center[q] - r;
    s.box.hi[q] = s.center[q] + r;
  }
  s.box.has[axis] = from < to;
  s.box.lo[axis] = from < to ? from : -INFINITY;
  s.box.hi[axis] = from < to ? to : INFINITY;
  return s;
}

static inline cupid_shape box(double x0, double x1, double y0, double y1, double z0, double z1) {
  cupid_shape s;
  memset(&s, 0, sizeof s);
  s.kind = CUPID_SHAPE_BOX;
  const double lo[3] = {x0, y0, z0}, hi[3] = {x1, y1, z1};
  for (int a = 0; a < 3; a++) s.box.has[a] = 1, s.box.lo[a] = lo[a], s.box.hi[a] = hi[a];
  return s;
}

#endif
