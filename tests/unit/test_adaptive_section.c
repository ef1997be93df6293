/* Zones over part of the section (issue 37; src/problem/adaptive_section.c): which section
 * elements next to a zone's core can be its overlaps, and which must join it.
 *  - paper 000's C-section (tests below: cbeam()): a web of 8 elements along z and two flanges
 *    of 3 along x meeting the web's corner elements at x = 5. A core in the middle of the web
 *    is kept, with a ring of one element either side (faces z lo / z hi); a core up to the
 *    web's corner element pulls the corner in (its far face is free: no beam to ramp to) and
 *    the flange's first element becomes the ring (face x lo); a core over the web and both
 *    flanges' first elements has their second elements as its ring,
 *    and once the flanges' last elements are in reach (their far faces are free), the whole
 *    section;
 *  - a 3 x 5 grid: a core in the centre cannot have a ring (each edge neighbour's sides meet
 *    the diagonal elements, which are beam): the core takes the whole section; a core on a
 *    corner the same; a core over a full row keeps it, with the rows either side as rings;
 *  - a core on the web whose ring would sit between it and another core element (the ring
 *    meets the core on two faces) joins them. */
#include <string.h>

#include "problem/adaptive_section.h"
#include "testutil.h"

/* the C-section: web x [0, 5], z [-50, -45, -30, -15, 0, 15, 30, 45, 50] (elements 0-7), top
 * flange x [5, 20, 35, 50] z [45, 50] (8-10), bottom flange (11-13) */
static int cbeam(double *b) {
  const double zw[] = {-50, -45, -30, -15, 0, 15, 30, 45, 50}, xf[] = {5, 20, 35, 50};
  int n = 0;
  for (int i = 0; i < 8; i++, n++) b[4 * n] = 0, b[4 * n + 1] = 5, b[4 * n + 2] = zw[i], b[4 * n + 3] = zw[i + 1];
  for (int f = 0; f < 2; f++)
    for (int i = 0; i < 3; i++, n++) {
      b[4 * n] = xf[i], b[4 * n + 1] = xf[i + 1];
      b[4 * n + 2] = f == 0 ? 45 : -50, b[4 * n + 3] = f == 0 ? 50 : -45;
    }
  return n;
}

static void set(unsigned char *F, int n, const int *in, int k) {
  memset(F, 0, (size_t)n);
  for (int i = 0; i < k; i++) F[in[i]] = 1;
}

static int count(const unsigned char *F, int n) {
  int c = 0;
  for (int i = 0; i < n; i++) c += F[i];
  return c;
}

static void c_section(void **state) {
  (void)state;
  double b[4 * 14];
  const int n = cbeam(b);
  cupid_section_map m;
  CUPID_ASSERT_OK(cupid_section_map_from_boxes(n, b, &m));
  unsigned char F[14];
  cupid_section_ring ring[14];

  /* the example's initial core: web z [-15, 15] */
  const int mid[] = {3, 4};
  set(F, n, mid, 2);
  assert_int_equal(cupid_section_settle(&m, F), 0);
  assert_int_equal(cupid_section_ring_of(&m, F, ring), 2);
  assert_int_equal(ring[0].element, 2), assert_int_equal(ring[0].face, 3); /* z hi */
  assert_int_equal(ring[1].element, 5), assert_int_equal(ring[1].face, 2); /* z lo */

  /* the core up to z = 45: the corner element joins, the flange's first element is the ring */
  const int upper[] = {3, 4, 5, 6};
  set(F, n, upper, 4);
  assert_int_equal(cupid_section_settle(&m, F), 1);
  assert_true(F[7] && count(F, n) == 5);
  assert_int_equal(cupid_section_ring_of(&m, F, ring), 2);
  assert_int_equal(ring[0].element, 2), assert_int_equal(ring[0].face, 3);
  assert_int_equal(ring[1].element, 8), assert_int_equal(ring[1].face, 0); /* x lo */

  /* the whole web and the flanges' first elements: their second ones are the ring */
  const int web[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 11};
  set(F, n, web, 10);
  assert_int_equal(cupid_section_settle(&m, F), 0);
  assert_int_equal(cupid_section_ring_of(&m, F, ring), 2);
  assert_int_equal(ring[0].element, 9), assert_int_equal(ring[0].face, 0);
  assert_int_equal(ring[1].element, 12), assert_int_equal(ring[1].face, 0);

  /* and their second elements: the last ones' far faces are free, so they join (no ring) */
  const int most[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12};
  set(F, n, most, 12);
  assert_int_equal(cupid_section_settle(&m, F), 2);
  assert_int_equal(count(F, n), 14);
  assert_int_equal(cupid_section_ring_of(&m, F, ring), 0);

  /* a ring element between two parts of the core (web 2 and 4, ring 3 meets both) joins */
  const int split[] = {2, 4};
  set(F, n, split, 2);
  assert_int_equal(cupid_section_settle(&m, F), 1);
  assert_true(F[3] && count(F, n) == 3);

  /* every element found where it is: a point on the shared edge z = 0 lies in two */
  int at[2];
  assert_int_equal(cupid_section_elements_at(&m, 2.5, 7.0, at), 1);
  assert_int_equal(at[0], 4);
  assert_int_equal(cupid_section_elements_at(&m, 2.5, 0.0, at), 2);
  cupid_section_map_free(&m);
}

static void grid(void **state) {
  (void)state;
  double b[4 * 15]; /* 3 along x, 5 along z: element 3 j + i */
  for (int j = 0; j < 5; j++)
    for (int i = 0; i < 3; i++) {
      double *e = b + 4 * (3 * j + i);
      e[0] = i, e[1] = i + 1, e[2] = j, e[3] = j + 1;
    }
  cupid_section_map m;
  CUPID_ASSERT_OK(cupid_section_map_from_boxes(15, b, &m));
  unsigned char F[15];
  cupid_section_ring ring[15];
  const int centre[] = {7}, corner[] = {0}, row[] = {6, 7, 8}, edge_row[] = {0, 1, 2};
  set(F, 15, centre, 1);
  assert_int_equal(cupid_section_settle(&m, F), 14);
  set(F, 15, corner, 1);
  assert_int_equal(cupid_section_settle(&m, F), 14);
  set(F, 15, row, 3);
  assert_int_equal(cupid_section_settle(&m, F), 0);
  assert_int_equal(cupid_section_ring_of(&m, F, ring), 6);
  for (int i = 0; i < 6; i++) /* below the core: its z hi face meets it; above: z lo */
    assert_int_equal(ring[i].face, ring[i].element < 6 ? 3 : 2);
  set(F, 15, edge_row, 3); /* a row on the edge: the next row is its ring */
  assert_int_equal(cupid_section_settle(&m, F), 0);
  assert_int_equal(cupid_section_ring_of(&m, F, ring), 3);
  cupid_section_map_free(&m);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(c_section), cmocka_unit_test(grid)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
