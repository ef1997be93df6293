/* Coupled models with `coupling: {method: arlequin}` inside a run (paper 004 section 3;
 * src/coupling/arlequin.c for the method). Any number of PD regions (LPS or bond-based, 1D or
 * 3D), each a box inside or at the end of the beam, over the whole section (the coupled bar,
 * the truss) or part of it (LE: a C-beam web, a panel's stringers). Every face of a region
 * where the beam continues beyond it is an interface and needs an overlap: a slab along one
 * axis inside the region, starting on that face (`overlap: [{y: [30, 35]}, {z: [15, 30]},
 * ..]`; one slab serves every region with a face on one of its edges). Regions may touch (an
 * L-shaped PD zone of two boxes is one body: a face meeting another region is no interface)
 * but not share a volume. `penalty: auto` takes kappa from the PD node stiffness
 * (choose_penalty()). Both models live in the
 * overlaps, with the energy weights of paper 004 Eqs. 8-9 ramping across them; inside the
 * rest of the region (its core) the beam gives way (cupid_coupling_deactivate(): those pairs
 * are inactive, their FE nodes held at zero). The weights' kinks must fall on element
 * boundaries (beam nodes along y, section-element edges along x and z), so that the
 * quadrature is exact. Constraints and loads go to the part they touch; body and point loads
 * reaching into an overlap are shared, alpha to the beam and 1 - alpha to the PD nodes (a
 * traction on a plane inside an overlap acts on no free surface: refused). Static runs
 * (CHOLMOD; with --solver petsc matrix-free, CG + Cholesky of a cheap twin, or assembled with
 * -cupid_coupled_assembled: the system is symmetric), evaluate, and dynamic runs (through
 * cupid_problem_run_dynamic() with the weighted masses of cupid_problem_arlequin_mass(); central
 * differences with a lumped mass on the matrix-free operator). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "method.h"

#define ARL_TOL 1e-9

static const char AXIS[3] = {'x', 'y', 'z'};

static cupid_status check(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  const cupid_coupling *c = &m->coupling;
  if (m->beam.integration == CUPID_CUF_MITC)
    return cupid_model_error(m, &c->mark,
                             "method arlequin: MITC beam integration is not yet supported (use "
                             "full or reduced)");
  if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC) return cupid_problem_dynamic_check(prob);
  return CUPID_SUCCESS;
}

/* The options of the run: the layout built by cupid_problem_arlequin_prepare(). */
static cupid_arlequin_options options(const cupid_problem_state *prob) {
  return (cupid_arlequin_options){.penalty = prob->arlequin_penalty,
                                  .n_regions = prob->n_arlequin_regions,
                                  .regions = prob->arlequin_regions};
}

/* ----------------------------------------------------------------------------- geometry */

/* Extent of the model along each axis: the section's box in x and z, the beam in y. */
static void model_extent(const cupid_problem_state *prob, double lo[3], double hi[3]) {
  lo[1] = prob->fe_info.y_min, hi[1] = prob->fe_info.y_max;
  lo[0] = lo[2] = INFINITY, hi[0] = hi[2] = -INFINITY;
  for (cupid_int e = 0; e < prob->fe_info.n_section_elements; e++) {
    double bx[4];
    int npe, mat;
    cupid_cuf_section_element(prob->beam, e, &npe, NULL, &mat, bx);
    lo[0] = fmin(lo[0], bx[0]), hi[0] = fmax(hi[0], bx[1]);
    lo[2] = fmin(lo[2], bx[2]), hi[2] = fmax(hi[2], bx[3]);
  }
}

static double model_scale(const cupid_problem_state *prob) {
  double lo[3], hi[3], s = 0.0;
  model_extent(prob, lo, hi);
  for (int k = 0; k < 3; k++) s = fmax(s, hi[k] - lo[k]);
  return s;
}

/* What lies just beyond face (axis k, side: 0 lo, 1 hi) of region r, on a 9 x 9 sample of the
 * face moved just outside it: *beam, some point in the beam and in no other PD region (an
 * interface); *pd, some point in another PD region (the regions touch there: one PD body,
 * the lattice and its bonds run on through the face). Axes the box leaves open are sampled
 * over the model's extent. */
static void face_meets(const cupid_problem_state *prob, int r, int k, int side, int *beam, int *pd) {
  const cupid_pd_region *regions = prob->model->pd.regions;
  const cupid_box *b = &regions[r].box;
  double lo[3], hi[3], eps = 1e-6 * model_scale(prob);
  model_extent(prob, lo, hi);
  for (int a = 0; a < 3; a++)
    if (b->has[a]) lo[a] = fmax(lo[a], b->lo[a]), hi[a] = fmin(hi[a], b->hi[a]);
  int a1 = (k + 1) % 3, a2 = (k + 2) % 3;
  *beam = *pd = 0;
  for (int i = 0; i < 9; i++)
    for (int j = 0; j < 9; j++) {
      double p[3];
      p[k] = side ? b->hi[k] + eps : b->lo[k] - eps;
      p[a1] = lo[a1] + (i + 0.5) / 9.0 * (hi[a1] - lo[a1]);
      p[a2] = lo[a2] + (j + 0.5) / 9.0 * (hi[a2] - lo[a2]);
      int other = 0;
      for (int q = 0; q < prob->model->pd.n_regions && !other; q++)
        other = q != r && cupid_box_contains(&regions[q].box, p, 0.0);
      if (other) *pd = 1;
      else if (cupid_cuf_contains(prob->beam, p[0], p[1], p[2])) *beam = 1;
    }
}

/* v along x or z (axis k) must not cut a section element that reaches into [olo, ohi] along
 * the other section axis: the weight's kinks must fall on element edges. */
static int section_edge_ok(const cupid_problem_state *prob, int k, double v, double olo, double ohi, double tol) {
  for (cupid_int e = 0; e < prob->fe_info.n_section_elements; e++) {
    double bx[4];
    int npe, mat;
    cupid_cuf_section_element(prob->beam, e, &npe, NULL, &mat, bx);
    const double *own = k == 0 ? bx : bx + 2, *oth = k == 0 ? bx + 2 : bx;
    if (oth[1] <= olo + tol || oth[0] >= ohi - tol) continue;
    if (own[0] < v - tol && own[1] > v + tol) return 0;
  }
  return 1;
}

/* Overlap slab s (its axis k: coupling.overlap_along) attached to a face of region box b: 0
 * (lo face), 1 (hi face), 2 (it spans b along k: either face; the one the beam meets) or -1.
 * The slab starts on the face and ends inside the region; a slab bounded on other axes too
 * serves only the boxes inside those bounds. */
static int slab_face(const cupid_coupling *c, int s, const cupid_box *b, double tol, int *axis) {
  const cupid_box *slab = &c->overlaps[s];
  int k = c->overlap_along[s];
  *axis = k;
  if (!b->has[k]) return -1;
  for (int a = 0; a < 3; a++)
    if (a != k && slab->has[a] &&
        (!b->has[a] || b->lo[a] < slab->lo[a] - tol || b->hi[a] > slab->hi[a] + tol))
      return -1;
  double lo = slab->lo[k], hi = slab->hi[k];
  const int at_lo = fabs(b->lo[k] - lo) <= tol && hi <= b->hi[k] + tol;
  const int at_hi = fabs(b->hi[k] - hi) <= tol && lo >= b->lo[k] - tol;
  return at_lo && at_hi ? 2 : at_lo ? 0 : at_hi ? 1 : -1;
}

/* 1 if y is the end of a beam element. */
static int element_end(const cupid_problem_state *prob, double y, double tol) {
  for (cupid_int e = 0; e < prob->fe_info.n_beam_elements; e++) {
    cupid_int first;
    double y0, y1;
    cupid_cuf_beam_element(prob->beam, e, &first, &y0, &y1);
    if (fabs(y - y0) <= tol || fabs(y - y1) <= tol) return 1;
  }
  return 0;
}

/* Where a slab's bound must lie: y on a beam-element end; x, z on section-element edges. */
static cupid_status slab_bounds_ok(const cupid_problem_state *prob, const cupid_box *b, int k, int s) {
  const cupid_model_t *m = prob->model;
  const cupid_mark *mk = &m->coupling.overlap_marks[s];
  const cupid_box *slab = &m->coupling.overlaps[s];
  double tol = ARL_TOL * model_scale(prob);
  for (int e = 0; e < 2; e++) {
    double v = e ? slab->hi[k] : slab->lo[k];
    if (k == 1) {
      if (v > prob->fe_info.y_min + tol && v < prob->fe_info.y_max - tol && !element_end(prob, v, tol))
        return cupid_model_error(m, mk,
                                 "the overlap bound y = %g is not a beam-element end: move it "
                                 "(or the beam's axis breakpoints) so that they coincide (the "
                                 "weight's kinks must fall between elements)",
                                 v);
      continue;
    }
    int o = 2 - k; /* the other section axis */
    double olo = b->has[o] ? b->lo[o] : -INFINITY, ohi = b->has[o] ? b->hi[o] : INFINITY;
    if (!section_edge_ok(prob, k, v, olo, ohi, tol))
      return cupid_model_error(m, mk,
                               "the overlap bound %c = %g cuts a section element: move it (or "
                               "the section's breakpoints) to an element edge (the weight's "
                               "kinks must fall between elements)",
                               AXIS[k], v);
  }
  return CUPID_SUCCESS;
}

/* 1 if region R has a ramp along k already (a slab spanning a region serves one face). */
static int slab_used(const cupid_arlequin_region *R, int k) {
  for (int q = 0; q < R->n_ramps; q++)
    if (R->ramps[q].axis == k) return 1;
  return 0;
}

/* The layout of region r: a ramp on every interface face, from the slab that starts there. */
static cupid_status build_region(cupid_problem_state *prob, int r, cupid_arlequin_region *out) {
  const cupid_model_t *m = prob->model;
  const cupid_coupling *c = &m->coupling;
  const cupid_box *b = &m->pd.regions[r].box;
  double tol = ARL_TOL * model_scale(prob);
  memset(out, 0, sizeof *out);
  out->box = *b;
  for (int k = 0; k < 3; k++)
    for (int side = 0; side < 2; side++) {
      if (!b->has[k]) continue;
      int slab = -1, interface, touches;
      face_meets(prob, r, k, side, &interface, &touches);
      double f = side ? b->hi[k] : b->lo[k];
      if (interface && touches)
        return cupid_model_error(m, &m->pd.regions[r].mark,
                                 "the face %c = %g of this PD region meets another PD region on "
                                 "part of it and the beam on the rest: an overlap cannot start "
                                 "on part of a face; split the regions so that each face meets "
                                 "either the beam or other PD regions (a re-entrant corner of "
                                 "the PD zone must not face the beam)",
                                 AXIS[k], f);
      for (int s = 0; s < c->n_overlaps; s++) {
        int axis, on = slab_face(c, s, b, tol, &axis);
        if (axis != k || (on == 2 ? !interface || (side == 1 && slab_used(out, k)) : on != side))
          continue;
        if (slab >= 0)
          return cupid_model_error(m, &c->overlap_marks[s],
                                   "two overlaps on the face %c = %g of the PD region %d",
                                   AXIS[k], side ? b->hi[k] : b->lo[k], r);
        slab = s;
      }
      if (slab < 0 && interface)
        return cupid_model_error(m, &m->pd.regions[r].mark,
                                 "the face %c = %g of this PD region meets the beam: give it an "
                                 "overlap (coupling.arlequin.overlap, e.g. {%c: [%g, %g]}: a "
                                 "slab inside the region starting on that face)",
                                 AXIS[k], f, AXIS[k], side ? f - 1 : f, side ? f : f + 1);
      if (slab < 0) continue;
      if (!interface)
        return cupid_model_error(m, &c->overlap_marks[slab],
                                 "the overlap %c in [%g, %g] lies on the face %c = %g of PD region "
                                 "%d, where the beam does not continue (%s): an overlap belongs "
                                 "on a face the beam meets",
                                 AXIS[k], c->overlaps[slab].lo[k], c->overlaps[slab].hi[k], AXIS[k],
                                 f, r, touches ? "another PD region touches it there" : "a free surface");
      CUPID_CALL(slab_bounds_ok(prob, b, k, slab));
      out->ramps[out->n_ramps++] = (cupid_arlequin_ramp){
          .axis = k,
          .weight = {.lo = c->overlaps[slab].lo[k], .hi = c->overlaps[slab].hi[k],
                     .fe_below = side == 0, .kind = c->weight}};
    }
  return CUPID_SUCCESS;
}

/* The region's core (the box less its overlaps, clipped to the beam's y range): where the
 * beam gives way. 0 if empty. */
static int region_core(const cupid_problem_state *prob, const cupid_arlequin_region *R, cupid_box *core) {
  double tol = ARL_TOL * model_scale(prob);
  *core = R->box;
  for (int q = 0; q < R->n_ramps; q++) {
    const cupid_arlequin_ramp *a = &R->ramps[q];
    if (a->weight.fe_below) core->lo[a->axis] = a->weight.hi;
    else core->hi[a->axis] = a->weight.lo;
  }
  core->lo[1] = fmax(core->lo[1], prob->fe_info.y_min);
  core->hi[1] = fmin(core->hi[1], prob->fe_info.y_max);
  for (int k = 0; k < 3; k++)
    if (core->has[k] && core->hi[k] - core->lo[k] <= tol) return 0;
  return 1;
}

/* 1 if boxes a and b share a volume (open axes overlap everything): touching on a face is no
 * overlap. */
static int boxes_share_volume(const cupid_box *a, const cupid_box *b, double tol) {
  for (int k = 0; k < 3; k++)
    if (a->has[k] && b->has[k] && (a->hi[k] <= b->lo[k] + tol || b->hi[k] <= a->lo[k] + tol)) return 0;
  return 1;
}

/* Regions may touch (an L-shaped PD zone of two boxes: the grid is their union, one lattice
 * with its bonds across the shared face, and each PD node lies in one box), but not share a
 * volume: the energies are weighted region by region (alpha = 1 - sum_r w_r), and a node in
 * two boxes would count twice. */
static cupid_status regions_disjoint(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  double tol = ARL_TOL * model_scale(prob);
  for (int r = 0; r < m->pd.n_regions; r++)
    for (int q = 0; q < r; q++)
      if (boxes_share_volume(&m->pd.regions[q].box, &m->pd.regions[r].box, tol))
        return cupid_model_error(m, &m->pd.regions[r].mark,
                                 "this PD region shares a volume with PD region %d: with method "
                                 "arlequin the regions may touch (share a face) but not overlap "
                                 "(their energies are weighted region by region); split them "
                                 "into boxes that only touch",
                                 q);
  return CUPID_SUCCESS;
}

/* 1 if the union of boxes a and b is a box stacked along y: the same extent along x and z,
 * touching or overlapping along y. Then *a becomes the union. Only along y: cores side by side
 * across the section stay apart, so that cupid_coupling_deactivate() checks their shared x or
 * z bound against the section-element edges (the beam's weight is integrated on either side
 * of it, and a section Gauss point on it would count in both regions). */
static int merge_boxes(cupid_box *a, const cupid_box *b, double tol) {
  int differ = -1;
  for (int k = 0; k < 3; k++) {
    if (a->has[k] != b->has[k]) return 0;
    if (!a->has[k] || (fabs(a->lo[k] - b->lo[k]) <= tol && fabs(a->hi[k] - b->hi[k]) <= tol)) continue;
    if (differ >= 0) return 0;
    differ = k;
  }
  if (differ < 0) return 1;
  if (differ != 1) return 0;
  if (a->hi[differ] < b->lo[differ] - tol || b->hi[differ] < a->lo[differ] - tol) return 0;
  a->lo[differ] = fmin(a->lo[differ], b->lo[differ]);
  a->hi[differ] = fmax(a->hi[differ], b->hi[differ]);
  return 1;
}

/* The cores, touching ones merged where their union is a box (two boxes stacked along y: the
 * beam gives way across the shared face, which need not be an element end). n: the cores;
 * who[i]: the first region of core i. */
static int merge_cores(cupid_box *core, int *who, int n, double tol) {
  for (int again = 1; again;) {
    again = 0;
    for (int i = 0; i < n && !again; i++)
      for (int j = i + 1; j < n && !again; j++)
        if (merge_boxes(&core[i], &core[j], tol)) {
          core[j] = core[n - 1], who[j] = who[n - 1];
          n--;
          again = 1;
        }
  }
  return n;
}

/* The penalty: the model's kappa, or with `penalty: auto` CUPID_ARLEQUIN_AUTO_PENALTY times
 * k_node, the stiffest PD node's diagonal stiffness (its family's springs; the largest over
 * the slabs of a partitioned grid). A tie softer than k_node adds its compliance to every
 * tied node's (paper 004's kappa = 1e9 N/m on its truss is 0.025 k_node: the wave arrives 5 %
 * of a period late by the second period, 1 k_node keeps it within 0.7 % over five); one much
 * stiffer shortens the explicit stable step as 1/sqrt(kappa), that of the lightest tied node
 * on its spring, 2 sqrt(w_min rho V / kappa) (docs/coupling.md, "The penalty"). Both are
 * printed, and recorded in summary.json. */
static cupid_status choose_penalty(cupid_problem_state *prob) {
  const cupid_coupling *c = &prob->model->coupling;
  double k = 0.0;
  CUPID_CALL(cupid_arlequin_node_stiffness(prob->op, prob->grid, &k));
  if (prob->slab) { /* the max over the slabs: each adds its own in its slot */
    int parts = prob->part.parts, me = prob->part.part;
    double *all = NULL;
    CUPID_CALL(cupid_calloc((size_t)parts, sizeof *all, "slab stiffnesses", &all));
    all[me] = k;
    cupid_petsc_sum_doubles(all, parts);
    for (int i = 0; i < parts; i++) k = fmax(k, all[i]);
    cupid_free(&all);
  }
  if (!(k > 0.0))
    return cupid_model_error(prob->model, &c->mark,
                             "method arlequin: the PD nodes have no stiffness (k_node = %g): "
                             "no penalty can be scaled to it",
                             k);
  prob->arlequin_node_stiffness = k;
  prob->arlequin_penalty = c->penalty_auto ? CUPID_ARLEQUIN_AUTO_PENALTY * k : c->penalty;
  cupid_problem_progress(prob,
                         "Arlequin penalty: kappa = %g N/m%s, %.3g x the PD node stiffness "
                         "k_node = %g N/m",
                         prob->arlequin_penalty, c->penalty_auto ? " (auto)" : "",
                         prob->arlequin_penalty / k, k);
  return CUPID_SUCCESS;
}

/* The regions, their overlaps against the built beam, and the cores where the beam gives
 * way. Stored in prob->arlequin_regions. */
static cupid_status prepare(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  const cupid_coupling *c = &m->coupling;
  cupid_status st = CUPID_SUCCESS;
  cupid_box *core = NULL;
  int *who = NULL, n = 0;
  for (int s = 0; s < c->n_overlaps; s++)
    if (!c->overlaps[s].has[1] && m->pd.dimension != 3)
      return cupid_model_error(m, &c->overlap_marks[s],
                               "a 1D peridynamic grid overlaps the beam along y only");
  CUPID_CALL(regions_disjoint(prob));
  double tol = ARL_TOL * model_scale(prob);
  for (int s = 0; s < c->n_overlaps; s++) { /* every slab starts on a face of some region */
    int axis = c->overlap_along[s], on_face = 0;
    for (int r = 0; r < m->pd.n_regions && !on_face; r++)
      on_face = slab_face(c, s, &m->pd.regions[r].box, tol, &axis) >= 0;
    if (!on_face) {
      const cupid_box *o = &c->overlaps[s];
      return cupid_model_error(m, &c->overlap_marks[s],
                               "the overlap %c in [%g, %g] starts on no face of a PD region: an "
                               "overlap is a slab inside a region, from one of its faces inward",
                               AXIS[axis], o->lo[axis], o->hi[axis]);
    }
  }
  CUPID_CALL(cupid_calloc((size_t)m->pd.n_regions, sizeof *prob->arlequin_regions,
                          "Arlequin regions", &prob->arlequin_regions));
  prob->n_arlequin_regions = m->pd.n_regions;
  for (int r = 0; r < m->pd.n_regions; r++)
    CUPID_CALL(build_region(prob, r, &prob->arlequin_regions[r]));
  CUPID_CALL(choose_penalty(prob));
  CUPID_TRY(cupid_calloc((size_t)m->pd.n_regions, sizeof *core, "Arlequin cores", &core));
  CUPID_TRY(cupid_calloc((size_t)m->pd.n_regions, sizeof *who, "Arlequin cores", &who));
  for (int r = 0; r < m->pd.n_regions; r++) {
    if (!region_core(prob, &prob->arlequin_regions[r], &core[n])) continue;
    cupid_problem_progress(prob, "Arlequin: region %d: %d overlaps", r,
                           prob->arlequin_regions[r].n_ramps);
    who[n++] = r;
  }
  n = merge_cores(core, who, n, tol);
  for (int i = 0; i < n; i++) {
    const cupid_box *b = &core[i];
    st = cupid_coupling_deactivate(prob->beam, 1, b);
    if (st != CUPID_SUCCESS) {
      st = cupid_model_error(m, &m->pd.regions[who[i]].mark,
                             "the beam cannot give way inside this region, off its overlaps "
                             "(x [%g, %g], y [%g, %g], z [%g, %g]): %s",
                             b->lo[0], b->hi[0], b->lo[1], b->hi[1], b->lo[2], b->hi[2],
                             cupid_error_message());
      goto cleanup;
    }
    cupid_problem_progress(prob, "Arlequin: the beam gives way on y in [%g, %g]%s", b->lo[1], b->hi[1],
                           cupid_coupling_region_spans_section(prob->beam, b) ? " over the whole section"
                                                                              : " over part of the section");
  }
cleanup:
  cupid_free(&core);
  cupid_free(&who);
  return st;
}

/* --------------------------------------------------------------- constraints and loads */

static int pd_node_near(const cupid_problem_state *prob, double y, double layer) {
  const double *x = cupid_pd_grid_coords(prob->grid);
  int found = 0;
  for (cupid_int i = 0; i < prob->n_pd && !found; i++) found = fabs(x[3 * i + 1] - y) < layer;
  return cupid_problem_global_count(prob, found) > 0; /* a slab: some rank's slab (collective) */
}

/* A clamp plane holds the beam where a used beam node lies on it and, independently, the PD
 * nodes within its layer (an overlap has both). */
static int clamp_on_pd(const cupid_problem_state *prob, const cupid_constraint *c) {
  return pd_node_near(prob, c->plane_y, c->layer > 0 ? c->layer : prob->model->pd.horizon);
}

static cupid_status constraints(cupid_problem_state *prob) {
  const cupid_split_rules rules = {.clamp_on_pd = clamp_on_pd};
  return cupid_method_split_constraints(prob, &rules);
}

/* The slab of ramp a of region R as a box (the region's extent on the other axes). */
static cupid_box ramp_slab(const cupid_arlequin_region *R, const cupid_arlequin_ramp *a) {
  cupid_box s = R->box;
  s.lo[a->axis] = a->weight.lo, s.hi[a->axis] = a->weight.hi, s.has[a->axis] = 1;
  return s;
}

/* 1 if boxes a and b overlap with positive volume (open axes overlap everything). */
static int boxes_meet(const cupid_box *a, const cupid_box *b, double tol) {
  for (int k = 0; k < 3; k++)
    if (a->has[k] && b->has[k] && (a->hi[k] <= b->lo[k] + tol || b->hi[k] <= a->lo[k] - tol)) return 0;
  return 1;
}

/* 1 if the load acts inside an overlap (both models there): a traction plane strictly inside a
 * slab's y range whose patch meets it; a point in a slab; a body load meeting a slab. */
static int load_in_overlap(const cupid_problem_state *prob, const cupid_load *l, double tol) {
  for (int r = 0; r < prob->n_arlequin_regions; r++) {
    const cupid_arlequin_region *R = &prob->arlequin_regions[r];
    for (int q = 0; q < R->n_ramps; q++) {
      cupid_box s = ramp_slab(R, &R->ramps[q]);
      switch (l->kind) {
      case CUPID_LOAD_TRACTION: {
        if (!s.has[1] || l->plane_y <= s.lo[1] + tol || l->plane_y >= s.hi[1] - tol) break;
        cupid_box patch = l->patch;
        patch.has[1] = 0;
        if (boxes_meet(&patch, &s, tol)) return 1;
        break;
      }
      case CUPID_LOAD_POINT:
        if (cupid_box_contains(&s, l->at, tol)) return 1;
        break;
      case CUPID_LOAD_BODY:
      default:
        if (boxes_meet(&l->box, &s, tol)) return 1;
      }
    }
  }
  return 0;
}

/* The external work is shared like the energy (paper 004 Eq. 8: alpha W_FE + (1 - alpha)
 * W_PD): a body or point load that reaches into an overlap goes to the beam times alpha and
 * to the PD nodes times 1 - alpha (alpha = 1 on the FE-only side, 0 on the PD-only side, so
 * outside the overlaps this is the plain split). */
typedef struct {
  const cupid_value *value;
  const cupid_arlequin_options *o;
} alpha_load;

static void alpha_field(void *ctx, const double p[3], double density, double out[3]) {
  const alpha_load *w = ctx;
  double a = cupid_arlequin_alpha_at(w->o, p);
  for (int k = 0; k < 3; k++)
    out[k] = a * cupid_value_eval(&w->value[k], p[0], p[1], p[2], 0.0, density);
}

/* The PD share: the load applied to the PD nodes as in a PD-only model (into a scratch vector,
 * with its checks), then scaled by 1 - alpha: at each node for a body load (the integrand),
 * at the load's point for a point load (so that the two shares sum to the load). */
static cupid_status add_pd_share(cupid_problem_state *prob, const cupid_load *l, const cupid_arlequin_options *o) {
  cupid_status st = CUPID_SUCCESS;
  double *scratch = NULL, *keep = prob->f_ext;
  CUPID_CALL(cupid_calloc((size_t)prob->ndof, sizeof *scratch, "PD load share", &scratch));
  st = cupid_problem_pd_loads(prob, l, 1, scratch);
  if (st == CUPID_SUCCESS) {
    const double *x = cupid_pd_grid_coords(prob->grid);
    for (cupid_int i = 0; i < prob->n_pd; i++) {
      const double *p = l->kind == CUPID_LOAD_POINT ? l->at : x + 3 * i;
      double w = 1.0 - cupid_arlequin_alpha_at(o, p);
      for (int c = 0; c < 3; c++) keep[3 * i + c] += w * scratch[3 * i + c];
    }
  }
  cupid_free(&scratch);
  return st;
}

/* A body or point load reaching into an overlap: the two shares. */
static cupid_status add_shared_load(cupid_problem_state *prob, const cupid_load *l, const cupid_arlequin_options *o) {
  const cupid_model_t *m = prob->model;
  alpha_load ctx = {.value = l->value, .o = o};
  int on_fe = l->kind == CUPID_LOAD_BODY ? cupid_problem_fe_node_in_box(prob, &l->box)
                                         : cupid_cuf_contains(prob->beam, l->at[0], l->at[1], l->at[2]);
  int on_pd = l->kind == CUPID_LOAD_BODY ? cupid_problem_pd_node_in_box(prob, &l->box) : 1;
  if (!on_fe && !on_pd) return cupid_model_error(m, &l->mark, "the load touches neither the beam nor a PD node");
  if (on_fe && l->kind == CUPID_LOAD_BODY) {
    cupid_status st = cupid_cuf_body_force_add(prob->beam, &l->box, alpha_field, &ctx, prob->f_ext, NULL);
    if (st != CUPID_SUCCESS) return cupid_model_error(m, &l->mark, "%s", cupid_error_message());
  } else if (on_fe) {
    double P[3];
    alpha_field(&ctx, l->at, 0.0, P);
    CUPID_CALL(cupid_cuf_point_load_add(prob->beam, l->at, P, prob->f_ext));
  }
  return on_pd ? add_pd_share(prob, l, o) : CUPID_SUCCESS;
}

static cupid_status loads(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  cupid_status st = CUPID_SUCCESS;
  cupid_load *pd = NULL;
  int npd = 0;
  const cupid_arlequin_options o = options(prob);
  double tol = ARL_TOL * model_scale(prob);
  CUPID_CALL(cupid_calloc((size_t)m->n_loads + 1, sizeof *pd, "PD loads", &pd));
  for (int k = 0; k < m->n_loads; k++) {
    const cupid_load *l = &m->loads[k];
    if (load_in_overlap(prob, l, tol)) {
      if (l->kind == CUPID_LOAD_TRACTION) {
        st = cupid_model_error(m, &l->mark,
                               "a traction on the plane y = %g inside an Arlequin overlap acts on "
                               "no free surface (move it to an end face)",
                               l->plane_y);
        goto cleanup;
      }
      CUPID_TRY(add_shared_load(prob, l, &o));
      CUPID_TRY(cupid_problem_check_finite(prob, prob->f_ext, &l->mark, "the load"));
      continue;
    }
    int on_fe = 0;
    switch (l->kind) {
    case CUPID_LOAD_TRACTION: on_fe = cupid_problem_fe_node_at(prob, l->plane_y); break;
    case CUPID_LOAD_POINT: on_fe = cupid_cuf_contains(prob->beam, l->at[0], l->at[1], l->at[2]); break;
    case CUPID_LOAD_BODY: on_fe = cupid_problem_fe_node_in_box(prob, &l->box); break;
    }
    if (on_fe) CUPID_TRY(cupid_cuf_load_add(prob->beam, m, l, prob->f_ext));
    if (on_fe) CUPID_TRY(cupid_problem_check_finite(prob, prob->f_ext, &l->mark, "the load"));
    if (!on_fe || (l->kind == CUPID_LOAD_BODY && cupid_problem_pd_node_in_box(prob, &l->box))) pd[npd++] = *l;
  }
  CUPID_TRY(cupid_problem_pd_loads(prob, pd, npd, prob->f_ext));
cleanup:
  cupid_free(&pd);
  return st;
}

/* ------------------------------------------------------------------------ the runs */

/* The method's state (prob->method_state): what the coupled K keeps between assemblies (crack
 * growth assembles K again after every round of broken bonds, and only its PD block changes). */
static void free_state(cupid_problem_state *prob) {
  cupid_arlequin_assembly A = prob->method_state;
  cupid_arlequin_assembly_destroy(&A);
  prob->method_state = NULL;
}

static cupid_status assemble(cupid_problem_state *prob) {
  if (prob->K) return CUPID_SUCCESS;
  double t0 = cupid_wtime();
  if (prob->method_state) { /* bonds broke: the kept blocks and the PD block now */
    CUPID_CALL(cupid_arlequin_assembly_matrix(prob->method_state, prob->op, &prob->K));
    cupid_problem_phase_end(prob, CUPID_PHASE_COUPLING, t0);
    return CUPID_SUCCESS;
  }
  cupid_arlequin_options o = options(prob);
  cupid_arlequin_info info;
  cupid_arlequin_assembly A = NULL;
  CUPID_CALL(cupid_arlequin_assembly_create(prob->beam, prob->grid, prob->op, &o, &A, &prob->K, &info));
  prob->method_state = A;
  cupid_problem_phase_end(prob, CUPID_PHASE_COUPLING, t0);
  static const char *wn[] = {"linear", "constant", "smooth"};
  char slabs[512] = "";
  size_t len = 0;
  const cupid_coupling *c = &prob->model->coupling;
  for (int s = 0; s < c->n_overlaps && len + 48 < sizeof slabs; s++) {
    const cupid_box *b = &c->overlaps[s];
    int k = c->overlap_along[s];
    len += (size_t)snprintf(slabs + len, sizeof slabs - len, "%s%c in [%g, %g]%s", s ? ", " : "",
                            AXIS[k], b->lo[k], b->hi[k],
                            b->has[0] + b->has[1] + b->has[2] > 1 ? " (bounded)" : "");
  }
  cupid_problem_progress(prob,
                     "coupling (Arlequin, penalty): %d region(s), overlaps %s, %s weight, kappa "
                     "= %g N/m, %lld tied PD nodes (%d components), min PD weight %.3g; %lld "
                     "non-zeros",
                     prob->n_arlequin_regions, slabs, wn[c->weight], o.penalty,
                     (long long)info.n_tied, info.components, info.pd_weight_min,
                     (long long)cupid_csr_nnz(prob->K));
  return CUPID_SUCCESS;
}

/* After bonds broke: only the changed PD rows, from the kept blocks (growth.c). */
static cupid_status update_rows(cupid_problem_state *prob, const cupid_int *nodes, cupid_int n) {
  CUPID_CHECK(prob->K && prob->method_state, CUPID_ERR_INTERNAL, "update_rows: no Arlequin K to update");
  const double t0 = cupid_wtime();
  CUPID_CALL(cupid_arlequin_assembly_update_rows(prob->method_state, prob->op, nodes, n, prob->K));
  cupid_problem_phase_end(prob, CUPID_PHASE_COUPLING, t0);
  return CUPID_SUCCESS;
}

static cupid_status report_gap(const cupid_problem_state *prob) {
  cupid_arlequin_options o = options(prob);
  double gap, umax = 0.0;
  CUPID_CALL(cupid_arlequin_gap(prob->beam, prob->grid, &o, prob->u, &gap));
  for (cupid_int d = 0; d < prob->ndof; d++)
    if (fabs(prob->u[d]) > umax) umax = fabs(prob->u[d]);
  cupid_problem_progress(prob, "Arlequin constraint gap max |d - N u| = %.3e (%.3e of max |u|)", gap,
                     umax > 0 ? gap / umax : 0.0);
  return CUPID_SUCCESS;
}

/* An iterative engine (krylov, petsc), static: the PD block matrix-free (src/coupling/arlequin_operator.c), CG
 * preconditioned by the Cholesky factor of the cheap twin (MUMPS, parallel on several ranks);
 * --assembled keeps the assembled path (CG + GAMG on K's rows). */
static int matrix_free(const cupid_problem_state *prob, const cupid_solver_type *engine) {
  return engine->solve_operator && !prob->opts->assembled;
}

/* The matrix-free operator and, when P is given, the cheap preconditioner matrix (the
 * coupling phase). */
static cupid_status create_operator(cupid_problem_state *prob, cupid_arlequin_operator *A, cupid_csr *P) {
  cupid_arlequin_options o = options(prob);
  cupid_arlequin_info info;
  double t0 = cupid_wtime();
  /* a slab: every rank's failure stops all of them before the next collective call */
  cupid_status st = cupid_arlequin_operator_create(prob->beam, prob->grid, &prob->pd_options, &o, A, &info);
  /* its own (weighted) PD operator loses the pre-cracks' bonds as prob->op did */
  if (st == CUPID_SUCCESS && prob->damage)
    st = cupid_pd_operator_copy_broken(cupid_arlequin_operator_pd(*A), prob->op);
  if (st == CUPID_SUCCESS && P) st = cupid_arlequin_preconditioner(*A, 1.5, P);
  CUPID_CALL(prob->slab ? cupid_problem_slab_agree(st) : st);
  info.n_tied = cupid_problem_global_count(prob, info.n_tied); /* a slab ties its owned nodes */
  cupid_problem_phase_end(prob, CUPID_PHASE_COUPLING, t0);
  cupid_problem_progress(prob,
                     "coupling (Arlequin, matrix-free): %d region(s), %lld tied PD nodes, min PD "
                     "weight %.3g; operator %.1f MB, preconditioner matrix %.1f MB%s",
                     prob->n_arlequin_regions, (long long)info.n_tied, info.pd_weight_min,
                     (double)cupid_arlequin_operator_bytes(*A) / 1e6,
                     P ? (double)cupid_csr_bytes(*P) / 1e6 : 0.0,
                     prob->slab ? " (rank 0's slab)" : "");
  return CUPID_SUCCESS;
}

static cupid_status k_apply(void *ctx, const double *x, double *y) {
  return cupid_arlequin_operator_apply(ctx, x, y);
}

static void destroy_operator(void **ctx) {
  cupid_arlequin_operator A = *ctx;
  cupid_arlequin_operator_destroy(&A);
  *ctx = NULL;
}

static cupid_status solve_matrix_free(cupid_problem_state *prob) {
  cupid_status st = CUPID_SUCCESS;
  cupid_arlequin_operator A = NULL;
  cupid_csr P = NULL;
  CUPID_TRY(create_operator(prob, &A, &P));
  cupid_linear_operator L;
  cupid_arlequin_operator_linear(A, &L); /* on a slab: its rows (cupid_krylov_solve) */
  cupid_method_operator owner = {.ctx = A, .destroy = destroy_operator};
  st = cupid_method_krylov_solve(prob, &L, &P, &owner);
  A = owner.ctx; /* NULL once a slab freed it */
cleanup:
  cupid_csr_destroy(&P);
  cupid_arlequin_operator_destroy(&A);
  return st;
}

/* Growth on the matrix-free path: the operator of the one-shot solve, kept (its own PD bonds
 * break with prob->op's). */
static cupid_status growth_operator(cupid_problem_state *prob, cupid_linear_operator *L, cupid_csr *P,
                                    cupid_method_operator *owner) {
  cupid_arlequin_operator A = NULL;
  cupid_status st = create_operator(prob, &A, P);
  if (st != CUPID_SUCCESS) {
    cupid_arlequin_operator_destroy(&A);
    cupid_csr_destroy(P);
    return st;
  }
  cupid_arlequin_operator_linear(A, L);
  *owner = (cupid_method_operator){.ctx = A, .destroy = destroy_operator};
  if (prob->damage) prob->crack_copy = cupid_arlequin_operator_pd(A);
  return CUPID_SUCCESS;
}

/* Central differences (lumped mass, checked) need K only through products: the matrix-free
 * operator, no assembled K, no preconditioner. */
static cupid_status explicit_operator(cupid_problem_state *prob, cupid_method_operator *op) {
  cupid_arlequin_operator A = NULL;
  CUPID_CALL(create_operator(prob, &A, NULL));
  *op = (cupid_method_operator){.apply = k_apply, .ctx = A, .destroy = destroy_operator};
  if (prob->damage) prob->crack_copy = cupid_arlequin_operator_pd(A); /* bonds break on both */
  return CUPID_SUCCESS;
}

/* The patch test with the tie held exactly: the overlap's PD forces act on the beam. */
static cupid_status patch_tie(const cupid_problem_state *prob, double *r) {
  cupid_arlequin_options o = options(prob);
  return cupid_arlequin_tie_forces(prob->beam, prob->grid, &o, r);
}

/* The overlaps: their PD nodes are tied to the beam by the penalty and share their energy with
 * it, so their bonds never break (a crack must stay in the PD-only part of a region). */
static cupid_status fracture_protect(const cupid_problem_state *prob, unsigned char *protect) {
  const cupid_coupling *c = &prob->model->coupling;
  const double *x = cupid_pd_grid_coords(prob->grid), h = cupid_pd_grid_spacing(prob->grid);
  for (cupid_int i = 0; i < prob->n_pd; i++)
    for (int s = 0; s < c->n_overlaps && !protect[i]; s++)
      protect[i] = (unsigned char)cupid_box_contains(&c->overlaps[s], x + 3 * i, 1e-9 * h);
  return CUPID_SUCCESS;
}

/* The overlap holding the PD node at x, for the message of a crack that reached it. */
static void protected_zone(const cupid_problem_state *prob, const double x[3], char *buf, size_t len) {
  const cupid_coupling *c = &prob->model->coupling;
  const double h = cupid_pd_grid_spacing(prob->grid);
  snprintf(buf, len, "an Arlequin overlap");
  for (int s = 0; s < c->n_overlaps; s++) {
    if (!cupid_box_contains(&c->overlaps[s], x, 1e-9 * h)) continue;
    const cupid_box *b = &c->overlaps[s];
    const int a = c->overlap_along[s];
    snprintf(buf, len, "the Arlequin overlap {%c: [%g, %g]} (%s, line %d)", "xyz"[a], b->lo[a],
             b->hi[a], c->overlap_marks[s].key, c->overlap_marks[s].line);
    return;
  }
}

/* The weighted mass (paper 004 Eq. 14): *M in K's pattern (consistent) or *m_lumped. */
static cupid_status mass(cupid_problem_state *prob, cupid_csr *M, double **m_lumped) {
  const cupid_model_t *m = prob->model;
  cupid_status st = CUPID_SUCCESS;
  double *pd_mass = NULL;
  cupid_arlequin_options o = options(prob);
  const int *mat = cupid_pd_grid_materials(prob->grid);
  CUPID_TRY(cupid_malloc((size_t)prob->n_pd + 1, sizeof *pd_mass, "PD masses", &pd_mass));
  for (cupid_int i = 0; i < prob->n_pd; i++) /* cut cells: the node's part of the body */
    pd_mass[i] = m->materials[mat[i]].density * cupid_pd_grid_node_volume(prob->grid, i);
  if (m->analysis.dynamic.lumped_mass) {
    CUPID_TRY(cupid_calloc((size_t)prob->ndof, sizeof **m_lumped, "lumped mass", m_lumped));
    CUPID_TRY(cupid_arlequin_mass(prob->beam, prob->grid, &o, pd_mass, NULL, *m_lumped));
  } else {
    CUPID_TRY(cupid_csr_duplicate(prob->K, M));
    cupid_csr_zero(*M);
    CUPID_TRY(cupid_arlequin_mass(prob->beam, prob->grid, &o, pd_mass, *M, NULL));
  }
cleanup:
  cupid_free(&pd_mass);
  return st;
}

/* Matrix-free Arlequin + MUMPS Cholesky of the cheap twin, measured on the Arlequin C-beam and
 * panel (12,000 / 6,400 / 51,200 PD nodes: 0.68 / 0.42 / 2.6 GB, 3.0 / 1.9 / 15 s): ~55 kB a
 * PD node, most of it the twin's factor. */
static int estimate_matrix_free(const cupid_problem_state *prob, double *bytes, double *seconds,
                                const char **what) {
  if (prob->model->analysis.type != CUPID_ANALYSIS_STATIC) return 0;
  *bytes = 55e3 * (double)prob->n_pd + 30.0 * (double)prob->ndof * 8.0;
  *seconds = 1.0 + 2.8e-4 * (double)prob->n_pd;
  *what = "matrix-free CG + Cholesky of a bond-based twin";
  return 1;
}

const cupid_method_ops cupid_method_arlequin = {
    .name = "arlequin",
    .caps = CUPID_METHOD_DYNAMIC | CUPID_METHOD_GRID_1D | CUPID_METHOD_SLABS |
            CUPID_METHOD_GUARD_MATRIX_FREE | CUPID_METHOD_FRACTURE | CUPID_METHOD_ADAPTIVE |
            CUPID_METHOD_OVERLAPS,
    .matrix = CUPID_MATRIX_SPD, /* symmetric positive definite once held: CHOLMOD, CG */
    .check = check,
    .prepare = prepare,
    .constraints = constraints,
    .loads = loads,
    .assemble = assemble,
    .update_rows = update_rows,
    .matrix_free = matrix_free,
    .solve_matrix_free = solve_matrix_free,
    .explicit_operator = explicit_operator,
    .mass = mass,
    .report = report_gap,
    .estimate_matrix_free = estimate_matrix_free,
    .fracture_protect = fracture_protect,
    .protected_zone = protected_zone,
    .growth_operator = growth_operator,
    .patch_tie = patch_tie,
    .free_state = free_state,
};
