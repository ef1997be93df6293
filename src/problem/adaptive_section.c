/* Adaptive PD zones over part of the section (issue 37; docs/theory.md "Zones over part of the
 * section"). A zone's footprint on the section is a set of section elements (the core, where
 * the beam gives way) and a ring of overlap elements around it, one element each. Arlequin's
 * weight in a ring element ramps from 1 on the face it meets the core to 0 on the opposite
 * face, where the beam must continue; its other faces may meet only free surface or ring
 * elements with the same ramp, so that the PD weight is continuous wherever there is material
 * (method_arlequin.c refuses a face that meets the beam without an overlap, or the beam on
 * part of it and PD on the rest). An element next to the core that cannot be such an overlap
 * joins the core (cupid_section_settle): on a thin wall (a C-beam's web, one element thick)
 * the zone runs along the wall, and at the end of the wall (the web's corner element, whose
 * far face is free) it takes the corner and reaches into the flange beyond. */
#include "adaptive_section.h"

#include <math.h>
#include <string.h>

#define S CUPID_SECTION_SAMPLES

void cupid_section_map_free(cupid_section_map *m) {
  cupid_free(&m->box);
  cupid_free(&m->beyond);
  m->n = 0;
}

static int contains(const double *b, double x, double z, double tol) {
  return x >= b[0] - tol && x <= b[1] + tol && z >= b[2] - tol && z <= b[3] + tol;
}

static int element_holding(const cupid_section_map *m, double x, double z) {
  for (int e = 0; e < m->n; e++)
    if (contains(m->box + 4 * e, x, z, 0.0)) return e;
  return -1;
}

cupid_status cupid_section_map_create(const cupid_cuf_beam beam, cupid_int n, cupid_section_map *m) {
  double *box = NULL;
  CUPID_CALL(cupid_malloc(4 * (size_t)n + 1, sizeof *box, "section element boxes", &box));
  for (cupid_int e = 0; e < n; e++) {
    int npe, mat;
    cupid_cuf_section_element(beam, e, &npe, NULL, &mat, box + 4 * e);
  }
  cupid_status st = cupid_section_map_from_boxes((int)n, box, m);
  cupid_free(&box);
  return st;
}

cupid_status cupid_section_map_from_boxes(int n, const double *boxes, cupid_section_map *m) {
  memset(m, 0, sizeof *m);
  m->n = n;
  CUPID_CALL(cupid_malloc(4 * (size_t)n + 1, sizeof *m->box, "section element boxes", &m->box));
  CUPID_CALL(cupid_malloc(4 * (size_t)n * S + 1, sizeof *m->beyond, "section faces", &m->beyond));
  memcpy(m->box, boxes, 4 * (size_t)n * sizeof *boxes);
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (int e = 0; e < n; e++) {
    const double *b = m->box + 4 * e;
    lo[0] = fmin(lo[0], b[0]), hi[0] = fmax(hi[0], b[1]);
    lo[1] = fmin(lo[1], b[2]), hi[1] = fmax(hi[1], b[3]);
  }
  const double size = fmax(hi[0] - lo[0], hi[1] - lo[1]);
  m->tol = 1e-9 * size;
  const double eps = 1e-6 * size; /* a sample's step out of its face */
  for (int e = 0; e < n; e++) {
    const double *b = m->box + 4 * e;
    for (int f = 0; f < 4; f++) {
      const int k = f / 2, side = f % 2; /* k 0: x, 1: z */
      const double v = side ? b[2 * k + 1] + eps : b[2 * k] - eps;
      const double *o = b + 2 * (1 - k); /* the face's extent along the other axis */
      for (int i = 0; i < S; i++) {
        const double w = o[0] + (i + 0.5) / S * (o[1] - o[0]);
        m->beyond[(4 * e + f) * S + i] = k == 0 ? element_holding(m, v, w) : element_holding(m, w, v);
      }
    }
  }
  return CUPID_SUCCESS;
}

int cupid_section_elements_at(const cupid_section_map *m, double x, double z, int out[2]) {
  int k = 0;
  for (int e = 0; e < m->n && k < 2; e++)
    if (contains(m->box + 4 * e, x, z, m->tol)) out[k++] = e;
  return k;
}

/* Element e (not in F): the faces where it meets the core (bit f), and 1 in *whole when it
 * meets the core on the whole of each. */
static int core_faces(const cupid_section_map *m, const unsigned char *F, int e, int *whole) {
  int faces = 0;
  *whole = 1;
  for (int f = 0; f < 4; f++) {
    int in = 0;
    for (int i = 0; i < S; i++) {
      const int b = m->beyond[(4 * e + f) * S + i];
      in += b >= 0 && F[b];
    }
    if (in) faces |= 1 << f, *whole &= in == S;
  }
  return faces;
}

/* The face bit of a ring candidate that meets the core on one face only, or 0. */
static int one_face(int faces) { return faces && !(faces & (faces - 1)) ? faces : 0; }

/* Ring candidate e, meeting the core on face bit `face` alone: 1 if it can be an overlap. */
static int ring_ok(const cupid_section_map *m, const unsigned char *F, const int *faces, int e,
                   int face) {
  int f = 0;
  while (!(face >> f & 1)) f++;
  const int k = f / 2, opposite = f ^ 1;
  const double *b = m->box + 4 * e;
  for (int i = 0; i < S; i++) { /* beyond the opposite face: the beam alone */
    const int o = m->beyond[(4 * e + opposite) * S + i];
    if (o < 0 || F[o] || faces[o]) return 0;
  }
  for (int g = 0; g < 4; g++) { /* the sides: free, or a ring element with the same ramp */
    if (g / 2 == k) continue;
    for (int i = 0; i < S; i++) {
      const int o = m->beyond[(4 * e + g) * S + i];
      if (o < 0) continue;
      if (F[o] || one_face(faces[o]) != face) return 0;
      const double *c = m->box + 4 * o;
      if (fabs(c[2 * k] - b[2 * k]) > m->tol || fabs(c[2 * k + 1] - b[2 * k + 1]) > m->tol) return 0;
    }
  }
  return 1;
}

int cupid_section_settle(const cupid_section_map *m, unsigned char *F) {
  int *faces = NULL, added = 0;
  unsigned char *join = NULL;
  if (cupid_calloc((size_t)m->n, sizeof *faces, "ring faces", &faces) != CUPID_SUCCESS ||
      cupid_calloc((size_t)m->n, 1, "elements to join", &join) != CUPID_SUCCESS) {
    cupid_free(&faces); /* out of memory: the whole section (always a valid footprint) */
    cupid_error_clear();
    for (int e = 0; e < m->n; e++) added += !F[e], F[e] = 1;
    return added;
  }
  for (int changed = 1; changed;) {
    changed = 0;
    for (int e = 0; e < m->n; e++) {
      int whole;
      faces[e] = F[e] ? 0 : core_faces(m, F, e, &whole);
      join[e] = faces[e] && (!one_face(faces[e]) || !whole);
    }
    for (int e = 0; e < m->n; e++)
      if (faces[e] && !join[e]) join[e] = !ring_ok(m, F, faces, e, faces[e]);
    for (int e = 0; e < m->n; e++)
      if (join[e]) F[e] = 1, added++, changed = 1;
  }
  cupid_free(&faces);
  cupid_free(&join);
  return added;
}

int cupid_section_ring_of(const cupid_section_map *m, const unsigned char *F,
                          cupid_section_ring *ring) {
  int n = 0;
  for (int e = 0; e < m->n; e++) {
    int whole;
    const int faces = F[e] ? 0 : core_faces(m, F, e, &whole);
    if (!faces) continue;
    int f = 0;
    while (!(faces >> f & 1)) f++;
    ring[n++] = (cupid_section_ring){.element = e, .face = f};
  }
  return n;
}
