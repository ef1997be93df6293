/* Adaptive PD zones over part of the section (issue 37; adaptive_section.c): the section's
 * elements, which face of each meets which, and the zone's footprint on them: the section
 * elements whose beam gave way to PD (the core) and the ring of overlap elements around it. */
#ifndef CUPID_PROBLEM_ADAPTIVE_SECTION_H
#define CUPID_PROBLEM_ADAPTIVE_SECTION_H

#include "cupid/cuf.h"

#define CUPID_SECTION_SAMPLES 9 /* points along a face where its far side is looked up */

/** The section's elements and their faces. Face f of an element: 0 x lo, 1 x hi, 2 z lo,
 *  3 z hi; beyond[(4 e + f) * CUPID_SECTION_SAMPLES + i]: the element just beyond sample
 *  point i of the face, -1 where it is free (no material). */
typedef struct {
  int n;          /**< section elements */
  double *box;    /**< 4 per element: x lo, x hi, z lo, z hi */
  int *beyond;
  double tol;     /**< of the section's size */
} cupid_section_map;

/** The ring element's overlap: the face it meets the core on (its weight is 1 there and
 *  ramps to 0 at the opposite face, where the beam continues). */
typedef struct {
  int element;
  int face;       /**< 0..3 as above */
} cupid_section_ring;

cupid_status cupid_section_map_create(const cupid_cuf_beam beam, cupid_int n, cupid_section_map *m);
/** The map of n elements given by their boxes (4 each: x lo, x hi, z lo, z hi). */
cupid_status cupid_section_map_from_boxes(int n, const double *boxes, cupid_section_map *m);
void cupid_section_map_free(cupid_section_map *m);

/** The elements holding (x, z): up to two (a point on a shared edge). Returns how many. */
int cupid_section_elements_at(const cupid_section_map *m, double x, double z, int out[2]);

/** Settle footprint F (n flags: the core): an element next to the core that could not be an
 *  overlap (it meets the core on more than one face or on part of one; the face opposite the
 *  core does not lead to the beam alone; a side meets the beam or the core) joins the core,
 *  until every element next to it can. Returns the elements added. */
int cupid_section_settle(const cupid_section_map *m, unsigned char *F);

/** The ring of a settled footprint: its elements and their faces into *ring (n entries at
 *  most). Returns how many. */
int cupid_section_ring_of(const cupid_section_map *m, const unsigned char *F,
                          cupid_section_ring *ring);

#endif
