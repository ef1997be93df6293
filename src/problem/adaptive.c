/* Adaptive PD zones (issue 37; model-format.md peridynamics.adaptive; docs/theory.md
 * "Adaptive PD zones"). The zone is a set of beam elements whose beam gave way to PD (the
 * cores); each run of them is one PD region over the whole section with the model's Arlequin
 * overlaps, as many beam elements wide as the initial ones, on its faces that meet the beam. A
 * conversion adds elements to the cores, lays the regions out again on the initial lattice
 * (cupid_pd_grid_options.anchor) and rebuilds the problem around them (cupid_problem_rebuild):
 * the nodes already there keep their place, their displacement and their broken bonds
 * (cupid_pd_grid_map_nodes, cupid_pd_operator_copy_broken_mapped); a new node starts from the
 * beam's displacement at its place. The run works on its own copy of the model (prob->model),
 * whose regions and overlaps change; everything else is the model read. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "adaptive_section.h"
#include "method.h"
#include "problem_internal.h"

#define ADAPTIVE_TOL 1e-9 /* of the beam's length: element ends, boxes */

struct cupid_problem_adaptive_private {
  cupid_model_t work;              /* prob->model: the model read, with this run's zone */
  cupid_pd_region *regions;        /* work.pd.regions once the zone changed (owned) */
  cupid_int ne;                    /* beam elements, in order along y */
  double *ends;                    /* ne + 1 element ends */
  unsigned char *core;             /* per element: the beam gave way to PD */
  unsigned char *mark;             /* per element: to convert */
  int ov_lo, ov_hi;                /* overlap widths in elements: below and above a core (the
                                      model's overlaps) */
  double ov_width;                 /* > 0: each overlap the fewest elements that span it (a zone
                                      that starts empty), instead of ov_lo / ov_hi */
  cupid_box across;                /* the zone's extent over the section (x, z) */
  int material;
  double s0;                       /* the trigger's critical stretch */
  double tol;
  cupid_problem_conversion *conv;  /* the conversions so far */
  int n_conv, cap_conv;
  cupid_int *map;                  /* the last conversion: old node -> new node */
  cupid_int map_n;
  cupid_int initial_nodes;
  cupid_int layer_nodes;           /* PD nodes in one lattice layer across the section */
  const char *why;                 /* what marked the elements */
  int blocked;                     /* the marks began with a crack blocked at an overlap */
  int overlaps;                    /* the method's regions carry overlaps (Arlequin); without
                                      (fictitious nodes) a zone's region is its core, and
                                      ov_lo / ov_hi only keep zones apart (settle_zone) */
  /* zones over part of the section (initial regions over part of it): the unit of conversion
   * is a beam element times a section element; each run of beam elements has one footprint
   * on the section (adaptive_section.c) */
  int partial;
  int nse;                         /* section elements */
  cupid_section_map sec;           /* partial: the section's elements and their faces */
  unsigned char *foot;             /* partial: ne x nse, the cores' section elements */
  unsigned char *mark_s;           /* partial: ne x nse, the units to convert */
  unsigned char *next;             /* partial: ne x nse, the footprints a conversion plans */
};

const cupid_model_t *cupid_problem_adaptive_model(const cupid_model_t *model,
                                                  cupid_problem_adaptive **out) {
  *out = NULL;
  if (!model->has_peridynamics || !model->pd.adaptive.has_adaptive || !model->has_beam) return model;
  cupid_problem_adaptive *a = NULL;
  if (cupid_calloc(1, sizeof *a, "adaptive zone", &a) != CUPID_SUCCESS) return NULL;
  a->work = *model; /* its arrays are the model's, but for the regions once the zone grows */
  *out = a;
  return &a->work;
}

void cupid_problem_adaptive_free(cupid_problem_adaptive **a) {
  if (!*a) return;
  cupid_free(&(*a)->regions);
  cupid_free(&(*a)->ends);
  cupid_free(&(*a)->core);
  cupid_free(&(*a)->mark);
  cupid_free(&(*a)->conv);
  cupid_free(&(*a)->map);
  cupid_free(&(*a)->foot);
  cupid_free(&(*a)->mark_s);
  cupid_free(&(*a)->next);
  cupid_section_map_free(&(*a)->sec);
  cupid_free(a);
}

/* ------------------------------------------------------------------ what this version runs */

cupid_status cupid_problem_adaptive_check(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  if (!prob->adaptive) return CUPID_SUCCESS;
  const cupid_adaptive *ad = &m->pd.adaptive;
  const cupid_method_ops *method = cupid_problem_method_of(m); /* prob's: none if it starts empty */
  if (!(method->caps & CUPID_METHOD_ADAPTIVE))
    return cupid_model_error(m, &ad->mark,
                             "adaptive zones grow with the coupling methods arlequin and "
                             "fictitious in cupid %s (the coupling is built again around the "
                             "zone); method %s is not supported yet",
                             cupid_version(), method->name);
  if (m->analysis.type == CUPID_ANALYSIS_EVALUATE)
    return cupid_model_error(m, &ad->mark,
                             "adaptive zones grow in quasi-static crack growth (type: static "
                             "with steps) and in explicit dynamics (type: dynamic); type "
                             "evaluate breaks nothing");
  if (m->analysis.type == CUPID_ANALYSIS_STATIC && ad->every > 0)
    return cupid_model_error(m, &ad->every_mark,
                             "`every` is the time steps between two tests of the trigger in "
                             "dynamics; quasi-static growth tests it after every load step: "
                             "remove it");
  if (m->pd.fracture.criterion != CUPID_FRACTURE_STRETCH)
    return cupid_model_error(m, &ad->mark,
                             "the trigger compares the beam's strain with the critical stretch: "
                             "it needs fracture.criterion: stretch");
  if (cupid_petsc_size() > 1 && !prob->opts->check_only &&
      (m->pd.n_regions == 0 || !cupid_problem_slab_wanted(prob)))
    return cupid_model_error(m, &ad->mark,
                             "under mpirun an adaptive zone grows on PD slabs: quasi-static "
                             "growth from initial regions on the PETSc engine's matrix-free path "
                             "(`--solver petsc`, not --assembled or --replicate); this model "
                             "would keep the whole model on every rank: run it on one process");
  if (m->output.exodus)
    return cupid_model_error(m, &ad->mark,
                             "model.exo (output.exodus) keeps one node set for the whole run, and "
                             "an adaptive zone adds nodes: use the VTU output (adaptive.pvd "
                             "holds the zone at each conversion)");
  for (int r = 0; r < m->pd.n_regions; r++)
    if (m->pd.regions[r].shape.kind != CUPID_SHAPE_BOX)
      return cupid_model_error(m, &m->pd.regions[r].mark,
                               "adaptive zones grow from box regions (a grown zone is made of "
                               "boxes of beam elements and section elements)");
  if (m->pd.n_holes > 0)
    return cupid_model_error(m, &m->pd.holes[0].mark,
                             "adaptive zones are boxes of beam elements and section elements: "
                             "holes are not supported with adaptive yet");
  return CUPID_SUCCESS;
}

/* ---- On PD slabs under mpirun (issue 37: "grow inside the slabs"): each rank holds the z
 * layers of its first slab, with the beam whole; a full-section zone grows along y, so the
 * grown grid keeps every rank's layers (cupid_model_t pd.slab_window) and each old node,
 * its halo's too, is on the same rank in the new grid: the carry-over stays on the rank. What
 * the trigger reads of the PD nodes (their bonds, their damage) each rank reads on the nodes
 * it owns, and the ranks agree on the marks. ---- */

/* The zone's PD nodes: a slab run's over every rank. */
static cupid_int zone_nodes(const cupid_problem_state *prob) {
  return prob->slab ? prob->part.global_nodes : prob->n_pd;
}

/* Whether this rank decides for PD node i (a slab run: the nodes it owns, not its halo). */
static int decides(const cupid_problem_state *prob, cupid_int i) {
  return !prob->slab || cupid_problem_pd_owned(prob, i);
}

/* The largest of v[0..n) over the ranks of a slab run. */
static void max_over_ranks(const cupid_problem_state *prob, double *v, cupid_int n) {
  if (prob->slab) cupid_petsc_max_doubles(v, (int)n);
}

/* The marks of every rank on every rank (a slab run): an element marked on one is marked. */
static cupid_status agree_marks(const cupid_problem_state *prob, cupid_problem_adaptive *a) {
  if (!prob->slab) return CUPID_SUCCESS;
  double *m = NULL;
  CUPID_CALL(cupid_malloc((size_t)a->ne + 1, sizeof *m, "marks over the ranks", &m));
  for (cupid_int e = 0; e < a->ne; e++) m[e] = a->mark[e];
  max_over_ranks(prob, m, a->ne);
  for (cupid_int e = 0; e < a->ne; e++) a->mark[e] = m[e] > 0.0;
  cupid_free(&m);
  return CUPID_SUCCESS;
}

/* --------------------------------------------------------------------------- the layout */

static int elements_in(const cupid_problem_adaptive *a, double lo, double hi, cupid_int *e0,
                       cupid_int *e1) {
  *e0 = -1, *e1 = -2;
  for (cupid_int e = 0; e < a->ne; e++)
    if (a->ends[e] >= lo - a->tol && a->ends[e + 1] <= hi + a->tol) {
      if (*e0 < 0) *e0 = e;
      *e1 = e;
    }
  return *e0 >= 0;
}

/* The elements of the overlap below a core that starts at element e0 (> e0: it does not fit
 * on the beam) and above one that ends at e1 (> ne - 1 - e1: it does not fit). */
static cupid_int ov_below(const cupid_problem_adaptive *a, cupid_int e0) {
  if (a->ov_width <= 0.0) return a->ov_lo;
  cupid_int k = 1;
  while (k <= e0 && a->ends[e0] - a->ends[e0 - k] < a->ov_width - a->tol) k++;
  return k;
}

static cupid_int ov_above(const cupid_problem_adaptive *a, cupid_int e1) {
  if (a->ov_width <= 0.0) return a->ov_hi;
  cupid_int k = 1;
  while (e1 + k <= a->ne - 1 && a->ends[e1 + 1 + k] - a->ends[e1 + 1] < a->ov_width - a->tol) k++;
  return k;
}

/* Element e may turn to PD: its region (the element and the overlaps it would bring; with
 * fictitious nodes the element) lies in `within`. */
static int convertible(const cupid_problem_adaptive *a, const cupid_adaptive *ad, cupid_int e) {
  if (!ad->has_within || !ad->within.has[1]) return 1;
  const cupid_int below = a->overlaps ? ov_below(a, e) : 0, above = a->overlaps ? ov_above(a, e) : 0;
  const cupid_int lo = e - below > 0 ? e - below : 0;
  const cupid_int hi = e + above < a->ne - 1 ? e + above : a->ne - 1;
  return a->ends[lo] >= ad->within.lo[1] - a->tol && a->ends[hi + 1] <= ad->within.hi[1] + a->tol;
}

/* Zones over part of the section: unit (e, s) may turn (its element may, and its section
 * element lies in `within`'s x and z bounds). */
static int unit_convertible(const cupid_problem_adaptive *a, const cupid_adaptive *ad, cupid_int e,
                            int s) {
  if (!convertible(a, ad, e)) return 0;
  const double *b = a->sec.box + 4 * s;
  for (int k = 0; k < 3 && ad->has_within; k += 2)
    if (ad->within.has[k] && (b[k] < ad->within.lo[k] - a->tol || b[k + 1] > ad->within.hi[k] + a->tol))
      return 0;
  return 1;
}

/* The trigger's s0: the critical stretch, or the smallest of the nodes' (from G0). */
static double trigger_stretch(const cupid_problem_state *prob) {
  const cupid_pd_fracture_options *o = &prob->fracture;
  if (!o->node_stretch) return o->critical_stretch;
  double s = INFINITY;
  for (cupid_int i = 0; i < prob->n_pd; i++) s = fmin(s, o->node_stretch[i]);
  double neg = -s;
  max_over_ranks(prob, &neg, 1);
  return -neg;
}

/* The elements of the beam in order along y (each starts where the one before ends). */
static cupid_status element_ends(cupid_problem_adaptive *a, const cupid_problem_state *prob) {
  a->ne = prob->fe_info.n_beam_elements;
  CUPID_CALL(cupid_malloc((size_t)a->ne + 1, sizeof *a->ends, "element ends", &a->ends));
  CUPID_CALL(cupid_calloc((size_t)a->ne + 1, 1, "zone elements", &a->core));
  CUPID_CALL(cupid_calloc((size_t)a->ne + 1, 1, "elements to convert", &a->mark));
  for (cupid_int e = 0; e < a->ne; e++) {
    cupid_int first;
    double y0, y1;
    cupid_cuf_beam_element(prob->beam, e, &first, &y0, &y1);
    CUPID_CHECK(e == 0 || fabs(y0 - a->ends[e]) <= a->tol, CUPID_ERR_INTERNAL,
                "adaptive: beam element %lld does not start where the one before ends",
                (long long)e);
    a->ends[e] = y0, a->ends[e + 1] = y1;
  }
  return CUPID_SUCCESS;
}

/* An empty start (regions: []): the lattice on the beam's bounding box (nodes at cell centres
 * from its lowest corner), the zone over the whole section, which must be the box its
 * components fill; each overlap the fewest beam elements that span `overlap` horizons. */
static cupid_status empty_zone(cupid_problem_adaptive *a, cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  const cupid_adaptive *ad = &m->pd.adaptive;
  const cupid_beam *b = &m->beam;
  if (b->n_components == 0)
    return cupid_model_error(m, &ad->mark,
                             "with peridynamics.regions: [] the zone is a box over the section: "
                             "give the section by components (rectangles) in cupid %s",
                             cupid_version());
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY}, area = 0.0;
  for (int k = 0; k < b->n_components; k++) {
    const cupid_section_component *c = &b->components[k];
    lo[0] = fmin(lo[0], c->x[0]), hi[0] = fmax(hi[0], c->x[c->nx - 1]);
    lo[1] = fmin(lo[1], c->z[0]), hi[1] = fmax(hi[1], c->z[c->nz - 1]);
    area += (c->x[c->nx - 1] - c->x[0]) * (c->z[c->nz - 1] - c->z[0]);
  }
  const double box = (hi[0] - lo[0]) * (hi[1] - lo[1]);
  if (fabs(area - box) > 1e-9 * box)
    return cupid_model_error(m, &ad->mark,
                             "with peridynamics.regions: [] the zone is one box over the section, "
                             "and this section fills %.4g of its bounding box x [%g, %g], z [%g, "
                             "%g] (a C, I or hollow section): give the initial zone as regions "
                             "in cupid %s",
                             area / box, lo[0], hi[0], lo[1], hi[1], cupid_version());
  const int mat = m->pd.material >= 0 ? m->pd.material : m->n_materials == 1 ? 0 : -1;
  if (mat < 0)
    return cupid_model_error(m, &m->pd.mark,
                             "with regions: [] the zone's material is peridynamics.material: "
                             "give it (the model has %d materials)",
                             m->n_materials);
  if (m->pd.fracture.calibration_grid)
    return cupid_model_error(m, &m->pd.fracture.mark,
                             "calibration: grid needs the lattice's families, and a zone that "
                             "starts empty has none before the trigger (the strain against s0) "
                             "first runs: use calibration: continuum with regions: []");
  memset(&a->across, 0, sizeof a->across);
  a->across.lo[0] = lo[0], a->across.hi[0] = hi[0], a->across.has[0] = 1;
  a->across.lo[2] = lo[1], a->across.hi[2] = hi[1], a->across.has[2] = 1;
  a->material = mat;
  a->ov_width = ad->overlap * m->pd.horizon;
  a->work.pd.anchor[0] = lo[0], a->work.pd.anchor[1] = a->ends[0], a->work.pd.anchor[2] = lo[1];
  a->work.pd.has_anchor = 1;
  a->s0 = cupid_problem_fracture_s0_of(prob, mat);
  /* the nodes of one lattice layer: the cells whose centres lie in the section's box */
  const double h = m->pd.spacing;
  a->layer_nodes = (cupid_int)(floor((hi[0] - lo[0]) / h - 0.5 + 1e-9) + 1) *
                   (cupid_int)(floor((hi[1] - lo[1]) / h - 0.5 + 1e-9) + 1);
  return CUPID_SUCCESS;
}

/* A region over part of the section: its core's section elements in the footprint of its
 * core's beam elements [e0, e1]; each of its overlaps across the section one section element
 * wide (as every overlap of a grown zone: adaptive_section.c). */
static cupid_status partial_region(cupid_problem_adaptive *a, const cupid_problem_state *prob,
                                   int r, cupid_int e0, cupid_int e1) {
  const cupid_model_t *m = prob->model;
  const cupid_arlequin_region *R = &prob->arlequin_regions[r];
  cupid_box core = R->box;
  for (int q = 0; q < R->n_ramps; q++) {
    const cupid_arlequin_ramp *w = &R->ramps[q];
    if (w->weight.fe_below) core.lo[w->axis] = w->weight.hi;
    else core.hi[w->axis] = w->weight.lo;
    if (w->axis == 1) continue;
    for (int s = 0; s < a->nse; s++) { /* the section elements across the overlap */
      const double *b = a->sec.box + 4 * s, *o = b + 2 * (1 - w->axis / 2);
      const double *own = b + w->axis; /* x: b[0..1], z: b[2..3] */
      const int ko = w->axis == 0 ? 2 : 0;
      if (own[1] <= w->weight.lo + a->tol || own[0] >= w->weight.hi - a->tol) continue;
      if (R->box.has[ko] && (o[1] <= R->box.lo[ko] + a->tol || o[0] >= R->box.hi[ko] - a->tol)) continue;
      if (fabs(own[0] - w->weight.lo) > a->tol || fabs(own[1] - w->weight.hi) > a->tol)
        return cupid_model_error(m, &m->pd.regions[r].mark,
                                 "with adaptive an overlap across the section is one section "
                                 "element wide (as each overlap of the grown zone): the overlap "
                                 "%c in [%g, %g] of this region covers the section element %c in "
                                 "[%g, %g]",
                                 "xyz"[w->axis], w->weight.lo, w->weight.hi, "xyz"[w->axis],
                                 own[0], own[1]);
    }
  }
  int any = 0;
  for (int s = 0; s < a->nse; s++) {
    const double *b = a->sec.box + 4 * s;
    if (b[0] < core.lo[0] - a->tol || b[1] > core.hi[0] + a->tol || b[2] < core.lo[2] - a->tol ||
        b[3] > core.hi[2] + a->tol)
      continue;
    any = 1;
    for (cupid_int e = e0; e <= e1; e++) a->foot[e * a->nse + s] = 1;
  }
  if (!any)
    return cupid_model_error(m, &m->pd.regions[r].mark,
                             "with adaptive the PD zone is made of whole section elements: this "
                             "region, less its overlaps (x in [%g, %g], z in [%g, %g]), holds "
                             "none",
                             core.lo[0], core.hi[0], core.lo[2], core.hi[2]);
  return CUPID_SUCCESS;
}

/* Zones over part of the section: the section's map and the footprints. */
static cupid_status partial_begin(cupid_problem_adaptive *a, const cupid_problem_state *prob) {
  a->partial = 1;
  CUPID_CALL(cupid_section_map_create(prob->beam, a->nse, &a->sec));
  CUPID_CALL(cupid_calloc((size_t)a->ne * (size_t)a->nse, 1, "zone units", &a->foot));
  CUPID_CALL(cupid_calloc((size_t)a->ne * (size_t)a->nse, 1, "units to convert", &a->mark_s));
  CUPID_CALL(cupid_calloc((size_t)a->ne * (size_t)a->nse, 1, "the planned zone", &a->next));
  return CUPID_SUCCESS;
}

/* The initial zone from the Arlequin layout: each region's core (less its overlaps) is a run
 * of elements (over part of the section: of units); the overlaps' widths along y in elements
 * are kept for every zone to come. */
static cupid_status initial_zone(cupid_problem_adaptive *a, cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  const cupid_adaptive *ad = &m->pd.adaptive;
  a->ov_lo = a->ov_hi = -1;
  /* Arlequin: its regions with their ramps; fictitious nodes: the model's boxes, no ramps */
  const int nr = a->overlaps ? prob->n_arlequin_regions : m->pd.n_regions;
  for (int r = 0; r < nr && !a->partial; r++) {
    const cupid_box *b = a->overlaps ? &prob->arlequin_regions[r].box : &m->pd.regions[r].box;
    if (cupid_coupling_region_spans_section(prob->beam, b)) continue;
    if (!a->overlaps)
      return cupid_model_error(m, &m->pd.regions[r].mark,
                               "adaptive zones over part of the section grow with Arlequin's "
                               "overlaps around them (the coupling method arlequin) in cupid %s; "
                               "with fictitious nodes a zone is whole beam elements over the "
                               "whole section",
                               cupid_version());
    CUPID_CALL(partial_begin(a, prob));
  }
  for (int r = 0; r < nr; r++) {
    cupid_arlequin_region none;
    memset(&none, 0, sizeof none);
    none.box = m->pd.regions[r].box;
    const cupid_arlequin_region *R = a->overlaps ? &prob->arlequin_regions[r] : &none;
    double lo = fmax(R->box.lo[1], a->ends[0]), hi = fmin(R->box.hi[1], a->ends[a->ne]);
    for (int q = 0; q < R->n_ramps; q++) {
      const cupid_arlequin_weight *w = &R->ramps[q].weight;
      if (R->ramps[q].axis != 1) continue;
      cupid_int e0, e1;
      const int n = elements_in(a, w->lo, w->hi, &e0, &e1) ? (int)(e1 - e0 + 1) : 0;
      if (w->fe_below) lo = w->hi, a->ov_lo = a->ov_lo < 0 ? n : a->ov_lo;
      else hi = w->lo, a->ov_hi = a->ov_hi < 0 ? n : a->ov_hi;
    }
    cupid_int e0, e1;
    if (!elements_in(a, lo, hi, &e0, &e1))
      return cupid_model_error(m, &m->pd.regions[r].mark,
                               "with adaptive the PD zone is made of whole beam elements: this "
                               "region, less its overlaps (y in [%g, %g]), holds none",
                               lo, hi);
    for (cupid_int e = e0; e <= e1; e++) a->core[e] = 1;
    if (a->partial) CUPID_CALL(partial_region(a, prob, r, e0, e1));
    if (r == 0) {
      a->across = R->box;
      a->material = m->pd.regions[r].material;
    }
  }
  if (!a->overlaps) a->ov_lo = a->ov_hi = 1; /* zones a beam element apart at least */
  if (a->ov_lo < 0) a->ov_lo = a->ov_hi;
  if (a->ov_hi < 0) a->ov_hi = a->ov_lo;
  if (a->ov_lo <= 0)
    return cupid_model_error(m, &ad->mark,
                             "the PD zone has no overlap with the beam: there is no beam left "
                             "for it to grow into");
  cupid_int can = 0;
  for (cupid_int e = 0; e < a->ne; e++) can += !a->core[e] && convertible(a, ad, e);
  for (cupid_int u = 0; a->partial && u < a->ne * a->nse; u++) /* units of the core's rows too */
    can += !a->foot[u] && unit_convertible(a, ad, u / a->nse, (int)(u % a->nse));
  if (can == 0)
    return cupid_model_error(m, ad->has_within ? &ad->within_mark : &ad->mark,
                             "no beam element can turn to PD: each lies outside `within` or its "
                             "overlaps would (%d element%s below a zone, %d above): the zone "
                             "could never grow",
                             a->ov_lo, a->ov_lo == 1 ? "" : "s", a->ov_hi);
  return CUPID_SUCCESS;
}

/* Lattice cells along axis k whose centres lie in [lo, hi] (the grid's rule with an anchor:
 * cupid_pd_grid_options.has_anchor). */
static cupid_int cells(const cupid_model_t *m, int k, double lo, double hi) {
  const double h = m->pd.spacing, o = m->pd.anchor[k];
  const double j0 = ceil((lo - o) / h - 0.5 - 1e-9), j1 = floor((hi - o) / h - 0.5 + 1e-9);
  return j1 >= j0 ? (cupid_int)(j1 - j0 + 1) : 0;
}

/* Lattice layers along y in [lo, hi]. */
static cupid_int layers(const cupid_model_t *m, double lo, double hi) { return cells(m, 1, lo, hi); }

/* *n: the PD nodes of one lattice layer over footprint F and its ring (zones over part of the
 * section). */
static cupid_status footprint_nodes(const cupid_problem_adaptive *a, const unsigned char *F,
                                    cupid_int *n) {
  cupid_section_ring *ring = NULL;
  CUPID_CALL(cupid_malloc((size_t)a->nse + 1, sizeof *ring, "footprint ring", &ring));
  const int nr = cupid_section_ring_of(&a->sec, F, ring);
  *n = 0;
  for (int s = 0; s < a->nse + nr; s++) {
    const int e = s < a->nse ? s : ring[s - a->nse].element;
    if (s < a->nse && !F[s]) continue;
    const double *b = a->sec.box + 4 * e;
    *n += cells(&a->work, 0, b[0], b[1]) * cells(&a->work, 2, b[2], b[3]);
  }
  cupid_free(&ring);
  return CUPID_SUCCESS;
}

static cupid_int layer_nodes_of(const cupid_problem_state *prob) {
  const double *x = cupid_pd_grid_coords(prob->grid), h = cupid_pd_grid_spacing(prob->grid);
  double y = INFINITY;
  for (cupid_int i = 0; i < prob->n_pd; i++) y = fmin(y, x[3 * i + 1]);
  double low = -y; /* (every rank's lowest layer) */
  max_over_ranks(prob, &low, 1);
  y = -low;
  cupid_int n = 0;
  for (cupid_int i = 0; i < prob->n_pd; i++) n += decides(prob, i) && fabs(x[3 * i + 1] - y) < 0.5 * h;
  return cupid_problem_global_count(prob, n);
}

/* ------------------------------------------------------------------------- the triggers */

/* Mark the elements that meet (y - r, y + r) (r = 0: the one holding y) and may turn. */
static cupid_int mark_around(cupid_problem_adaptive *a, const cupid_adaptive *ad, double y,
                             double r) {
  cupid_int n = 0;
  for (cupid_int e = 0; e < a->ne; e++) {
    const int meets = r > 0.0 ? a->ends[e] < y + r && a->ends[e + 1] > y - r
                              : a->ends[e] <= y && y <= a->ends[e + 1];
    if (!meets || a->core[e] || a->mark[e] || !convertible(a, ad, e)) continue;
    a->mark[e] = 1;
    n++;
  }
  return n;
}

static cupid_int mark_unit(cupid_problem_adaptive *a, const cupid_adaptive *ad, cupid_int e, int s) {
  const cupid_int u = e * a->nse + s;
  if (a->foot[u] || a->mark_s[u] || !unit_convertible(a, ad, e, s)) return 0;
  a->mark_s[u] = 1, a->mark[e] = 1;
  return 1;
}

/* Zones over part of the section: mark the units that hold p or whose box lies within r of
 * it, in one pass. */
static cupid_int mark_units_around(cupid_problem_adaptive *a, const cupid_adaptive *ad,
                                   const double p[3], double r) {
  cupid_int n = 0;
  for (cupid_int e = 0; e < a->ne; e++) {
    const double dy = fmax(fmax(a->ends[e] - p[1], p[1] - a->ends[e + 1]), 0.0);
    if (dy > a->tol && dy >= r) continue;
    for (int s = 0; s < a->nse; s++) {
      const double *b = a->sec.box + 4 * s;
      const double dx = fmax(fmax(b[0] - p[0], p[0] - b[1]), 0.0);
      const double dz = fmax(fmax(b[2] - p[2], p[2] - b[3]), 0.0);
      const double d = sqrt(dx * dx + dy * dy + dz * dz);
      if (d <= a->tol || d < r) n += mark_unit(a, ad, e, s);
    }
  }
  return n;
}

/* Mark what lies within r of p (and holds it): units over part of the section, elements over
 * the whole of it. */
static cupid_int mark_near(cupid_problem_adaptive *a, const cupid_adaptive *ad, const double p[3],
                           double r) {
  if (a->partial) return mark_units_around(a, ad, p, r);
  return mark_around(a, ad, p[1], 0.0) + mark_around(a, ad, p[1], r);
}

/* A crack near an overlap: the elements that hold a damaged node (a broken bond's end) or lie
 * within margin horizons of one. */
static cupid_int mark_damage(cupid_problem_adaptive *a, const cupid_problem_state *prob) {
  const cupid_adaptive *ad = &prob->model->pd.adaptive;
  if (!prob->grid || !prob->damage) return 0;
  const double *x = cupid_pd_grid_coords(prob->grid), r = ad->margin * prob->model->pd.horizon;
  cupid_int n = 0;
  for (cupid_int i = 0; i < prob->n_pd && prob->damage; i++)
    if (prob->damage[i] > 0.0 && decides(prob, i)) n += mark_near(a, ad, x + 3 * i, r);
  return n;
}

/* The element holding y (the first of two when y is an end): binary search of the ends. */
static cupid_int element_at(const cupid_problem_adaptive *a, double y) {
  cupid_int lo = 0, hi = a->ne - 1;
  while (lo < hi) {
    const cupid_int mid = lo + (hi - lo) / 2;
    if (y <= a->ends[mid + 1]) hi = mid;
    else lo = mid + 1;
  }
  return lo;
}

/* Each PD node's largest protected bond stretch over its limit (*ratio allocated; NULL when
 * the zone has no PD node yet). */
static cupid_status node_ratios(const cupid_problem_state *prob, double **ratio) {
  *ratio = NULL;
  if (!prob->op || prob->n_pd == 0) return CUPID_SUCCESS;
  CUPID_CALL(cupid_malloc((size_t)prob->n_pd, sizeof **ratio, "bond ratios", ratio));
  cupid_status st = cupid_pd_operator_protected_ratios(prob->op, prob->u, &prob->fracture, *ratio);
  if (st != CUPID_SUCCESS) cupid_free(ratio);
  return st;
}

/* Fictitious nodes: the beam element beyond the end of e's run nearest to y (-1: a beam end). */
static cupid_int element_beyond(const cupid_problem_adaptive *a, cupid_int e, double y) {
  cupid_int r0 = e, r1 = e;
  while (r0 > 0 && a->core[r0 - 1]) r0--;
  while (r1 < a->ne - 1 && a->core[r1 + 1]) r1++;
  const cupid_int next = y - a->ends[r0] <= a->ends[r1 + 1] - y ? r0 - 1 : r1 + 1;
  return next >= 0 && next < a->ne ? next : -1;
}

/* An overlap's elements: the largest stretch of their PD nodes' protected bonds over its limit
 * (peak[e], -1 where no PD node lies; with fictitious nodes, whose coupling zone lies inside
 * the core, the element beyond the nearest interface takes it). The beam under an overlap
 * follows the PD nodes it is tied to, whose lattice (its free surfaces) the beam's expansion
 * cannot follow: its strain there is no measure of the material's (1.5 times the beam's alone
 * next to the core of beam_adaptive.yaml), and the bonds' stretch is. */
static cupid_status overlap_stretch(const cupid_problem_state *prob, const cupid_problem_adaptive *a,
                                    double *peak) {
  for (cupid_int e = 0; e < a->ne; e++) peak[e] = -1.0;
  double *ratio = NULL;
  cupid_status st = node_ratios(prob, &ratio);
  const double *x = ratio ? cupid_pd_grid_coords(prob->grid) : NULL;
  for (cupid_int i = 0; ratio && i < prob->n_pd && st == CUPID_SUCCESS; i++) {
    if (!decides(prob, i)) continue;
    /* a node on an element's end belongs to both elements (a mirror image of the zone has
     * its mirror node on the mirror end: the marks stay symmetric) */
    const double y = x[3 * i + 1];
    const cupid_int e = element_at(a, y);
    if (a->core[e] && !a->overlaps) { /* fictitious nodes: the coupling zone lies in the core */
      const cupid_int next = element_beyond(a, e, y);
      if (next >= 0) peak[next] = fmax(peak[next], ratio[i]);
      continue;
    }
    if (!a->core[e]) peak[e] = fmax(peak[e], ratio[i]);
    if (e + 1 < a->ne && fabs(y - a->ends[e + 1]) <= a->tol && !a->core[e + 1])
      peak[e + 1] = fmax(peak[e + 1], ratio[i]);
  }
  cupid_free(&ratio);
  max_over_ranks(prob, peak, a->ne);
  return st;
}

/* The beam's largest principal strain over each element's quadrature points, over s0. */
static cupid_status beam_strain(const cupid_problem_state *prob, const cupid_problem_adaptive *a,
                                double *top) {
  const int nse = prob->fe_info.n_section_elements;
  double *peak = NULL;
  CUPID_CALL(cupid_malloc((size_t)a->ne * (size_t)nse, sizeof *peak, "strain peaks", &peak));
  cupid_status st = cupid_cuf_strain_peaks(prob->beam, prob->u, peak);
  for (cupid_int e = 0; e < a->ne; e++) {
    top[e] = -INFINITY;
    for (int s = 0; s < nse; s++) top[e] = fmax(top[e], peak[e * nse + s] / a->s0);
  }
  cupid_free(&peak);
  return st;
}

/* Zones over part of the section: overlap_stretch per unit (peak[e * nse + s]); a node on an
 * element's end or a section element's edge belongs to each element there. */
static cupid_status overlap_stretch_units(const cupid_problem_state *prob,
                                          const cupid_problem_adaptive *a, double *peak) {
  const cupid_int nu = a->ne * a->nse;
  for (cupid_int u = 0; u < nu; u++) peak[u] = -1.0;
  double *ratio = NULL;
  cupid_status st = node_ratios(prob, &ratio);
  const double *x = ratio ? cupid_pd_grid_coords(prob->grid) : NULL;
  for (cupid_int i = 0; ratio && i < prob->n_pd && st == CUPID_SUCCESS; i++) {
    const double *p = x + 3 * i;
    const cupid_int e = element_at(a, p[1]);
    const int two_e = e + 1 < a->ne && fabs(p[1] - a->ends[e + 1]) <= a->tol;
    int se[2];
    const int ns = cupid_section_elements_at(&a->sec, p[0], p[2], se);
    for (int q = 0; q <= two_e; q++)
      for (int k = 0; k < ns; k++) {
        const cupid_int u = (e + q) * a->nse + se[k];
        if (!a->foot[u]) peak[u] = fmax(peak[u], ratio[i]);
      }
  }
  cupid_free(&ratio);
  return st;
}

/* Zones over part of the section: each unit off the cores by its PD bonds (where it holds PD
 * nodes) or the beam's strain. */
static cupid_status trigger_units(cupid_problem_state *prob, cupid_problem_adaptive *a,
                                  cupid_int *count, cupid_int *in_overlap) {
  const cupid_adaptive *ad = &prob->model->pd.adaptive;
  const cupid_int nu = a->ne * a->nse;
  double *bonds = NULL, *strain = NULL;
  CUPID_CALL(cupid_malloc((size_t)nu, sizeof *bonds, "overlap stretch", &bonds));
  cupid_status st = cupid_malloc((size_t)nu, sizeof *strain, "beam strain", &strain);
  if (st == CUPID_SUCCESS) st = overlap_stretch_units(prob, a, bonds);
  if (st == CUPID_SUCCESS) st = cupid_cuf_strain_peaks(prob->beam, prob->u, strain);
  for (cupid_int u = 0; u < nu && st == CUPID_SUCCESS; u++) {
    const double r = bonds[u] >= 0.0 ? bonds[u] : strain[u] / a->s0;
    if (r >= ad->threshold && mark_unit(a, ad, u / a->nse, (int)(u % a->nse)))
      (*count)++, *in_overlap += bonds[u] >= 0.0;
  }
  cupid_free(&bonds);
  cupid_free(&strain);
  return st;
}

/* After the strain and stretch marks (*count, in_overlap of them by bonds): what marked them
 * (a crack blocked at an overlap keeps its name), then the crack's margin test. */
static cupid_status trigger_done(cupid_problem_state *prob, cupid_problem_adaptive *a,
                                 cupid_int *count, cupid_int in_overlap) {
  if (*count && !a->blocked)
    a->why = in_overlap < *count ? "strain"
             : a->overlaps       ? "stretch in an overlap"
                                 : "stretch in the coupling zone";
  /* the strain and stretch marks agree over the ranks of a slab run already (the beam is
   * whole, the stretch taken over the ranks); the cracks' are each rank's */
  const cupid_int near = cupid_problem_global_count(prob, mark_damage(a, prob));
  CUPID_CALL(agree_marks(prob, a));
  if (near && !*count && !a->blocked) a->why = "crack near an overlap";
  *count += near;
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_adaptive_trigger(cupid_problem_state *prob, cupid_int *count) {
  cupid_problem_adaptive *a = prob->adaptive;
  const cupid_adaptive *ad = &prob->model->pd.adaptive;
  if (a->partial) {
    cupid_int in_overlap = 0;
    *count = 0;
    CUPID_CALL(trigger_units(prob, a, count, &in_overlap));
    return trigger_done(prob, a, count, in_overlap);
  }
  double *bonds = NULL, *strain = NULL;
  *count = 0;
  cupid_int in_overlap = 0;
  CUPID_CALL(cupid_malloc((size_t)a->ne, sizeof *bonds, "overlap stretch", &bonds));
  cupid_status st = cupid_malloc((size_t)a->ne, sizeof *strain, "beam strain", &strain);
  if (st == CUPID_SUCCESS) st = overlap_stretch(prob, a, bonds);
  if (st == CUPID_SUCCESS) st = beam_strain(prob, a, strain);
  for (cupid_int e = 0; e < a->ne && st == CUPID_SUCCESS; e++) {
    if (a->core[e] || a->mark[e] || !convertible(a, ad, e)) continue;
    /* an overlap's element by its bonds, the beam's own by its strain; with fictitious nodes
     * the beam next to a zone also by the coupling zone's bonds across its interface */
    const double r = !a->overlaps ? fmax(bonds[e], strain[e]) : bonds[e] >= 0.0 ? bonds[e] : strain[e];
    if (r >= ad->threshold)
      a->mark[e] = 1, (*count)++, in_overlap += bonds[e] >= 0.0 && (a->overlaps || bonds[e] >= strain[e]);
  }
  cupid_free(&bonds);
  cupid_free(&strain);
  CUPID_CALL(st);
  return trigger_done(prob, a, count, in_overlap);
}

cupid_status cupid_problem_adaptive_blocked(cupid_problem_state *prob, const double x[3],
                                            cupid_int *count) {
  cupid_problem_adaptive *a = prob->adaptive;
  const cupid_adaptive *ad = &prob->model->pd.adaptive;
  *count = mark_near(a, ad, x, ad->margin * prob->model->pd.horizon);
  if (!a->overlaps) { /* fictitious nodes: the coupling zone lies in the core; the beam beyond */
    const cupid_int e = element_beyond(a, element_at(a, x[1]), x[1]);
    if (e >= 0 && !a->core[e] && !a->mark[e] && convertible(a, ad, e)) a->mark[e] = 1, (*count)++;
  }
  a->why = a->overlaps ? "an overlap's bond reached its limit" : "a coupling zone's bond reached its limit";
  a->blocked = *count > 0;
  return CUPID_SUCCESS;
}

/* ------------------------------------------------------------------------ the conversion */

/* The zone after the marks: the cores and the marked elements, with the gaps between two
 * zones that their overlaps would fill (Arlequin's regions may not share a volume, nor an
 * overlap end on another region) and the ends of the beam that an overlap would not fit
 * before (an overlap needs the beam beyond it) turned to PD too. */
static void settle_zone(const cupid_problem_adaptive *a, unsigned char *z) {
  for (int changed = 1; changed;) {
    changed = 0;
    cupid_int last_end = -1; /* the last element of the run before */
    for (cupid_int e = 0; e < a->ne; e++) {
      if (!z[e] || (e > 0 && z[e - 1])) continue;
      cupid_int f = e;
      while (f + 1 < a->ne && z[f + 1]) f++;
      cupid_int fill_lo = -1, fill_hi = -2;
      if (e > 0 && e <= ov_below(a, e)) fill_lo = 0, fill_hi = e - 1;
      else if (last_end >= 0 && e - last_end - 1 <= ov_above(a, last_end) + ov_below(a, e))
        fill_lo = last_end + 1, fill_hi = e - 1;
      if (f < a->ne - 1 && f + ov_above(a, f) >= a->ne - 1) {
        for (cupid_int q = f + 1; q < a->ne; q++) z[q] = 1;
        changed = 1;
      }
      for (cupid_int q = fill_lo; q <= fill_hi; q++) z[q] = 1, changed = 1;
      last_end = f;
      e = f;
    }
  }
}

/* The runs of z: first and last element of each, at most cap. */
static int zone_runs(const cupid_problem_adaptive *a, const unsigned char *z, cupid_int *runs, int cap) {
  int n = 0;
  for (cupid_int e = 0; e < a->ne; e++) {
    if (!z[e] || (e > 0 && z[e - 1])) continue;
    cupid_int f = e;
    while (f + 1 < a->ne && z[f + 1]) f++;
    if (n < cap) runs[2 * n] = e, runs[2 * n + 1] = f;
    n++;
    e = f;
  }
  return n;
}

/* The region of run [e0, e1]: the core and its overlaps along y. */
static void run_region(const cupid_problem_adaptive *a, cupid_int e0, cupid_int e1, double *lo,
                       double *hi) {
  const int ov = a->overlaps; /* (fictitious nodes: the region is the core) */
  *lo = e0 > 0 ? a->ends[e0 - ov * ov_below(a, e0)] : a->ends[0];
  *hi = e1 < a->ne - 1 ? a->ends[e1 + 1 + ov * ov_above(a, e1)] : a->ends[a->ne];
}

#define MAX_ZONES (CUPID_MAX_OVERLAPS / 2)

/* Append overlap slab o (its weight ramping along axis `along`) to the working model. */
static cupid_status push_overlap(cupid_problem_adaptive *a, const cupid_box *o, int along) {
  cupid_coupling *c = &a->work.coupling;
  CUPID_CHECK(c->n_overlaps < CUPID_MAX_OVERLAPS, CUPID_ERR_UNSUPPORTED,
              "adaptive: the zone would need more than %d Arlequin overlaps; bound it with "
              "`within`",
              CUPID_MAX_OVERLAPS);
  c->overlaps[c->n_overlaps] = *o;
  c->overlap_along[c->n_overlaps] = along;
  c->overlap_marks[c->n_overlaps++] = a->work.pd.adaptive.mark;
  return CUPID_SUCCESS;
}

/* The overlaps along y of run [e0, e1], below and above it where the beam goes on (none with
 * fictitious nodes: the interfaces are the region's faces). */
static cupid_status run_overlaps(cupid_problem_adaptive *a, cupid_int e0, cupid_int e1) {
  cupid_box o;
  memset(&o, 0, sizeof o);
  o.has[1] = 1;
  if (!a->overlaps) return CUPID_SUCCESS;
  if (e0 > 0) {
    o.lo[1] = a->ends[e0 - ov_below(a, e0)], o.hi[1] = a->ends[e0];
    CUPID_CALL(push_overlap(a, &o, 1));
  }
  if (e1 < a->ne - 1) {
    o.lo[1] = a->ends[e1 + 1], o.hi[1] = a->ends[e1 + 1 + ov_above(a, e1)];
    CUPID_CALL(push_overlap(a, &o, 1));
  }
  return CUPID_SUCCESS;
}

/* A region of the zone: box b, the zone's material. */
static cupid_pd_region zone_region(const cupid_problem_adaptive *a, const cupid_box *b) {
  cupid_pd_region r = {.box = *b, .material = a->material, .mark = a->work.pd.adaptive.mark};
  r.shape.kind = CUPID_SHAPE_BOX;
  r.shape.box = *b;
  return r;
}

/* The working model's regions (taking over *regions, n of them) and the overlaps laid out. */
static void set_regions(cupid_problem_adaptive *a, cupid_pd_region **regions, int n) {
  cupid_free(&a->regions);
  a->regions = *regions, *regions = NULL;
  a->work.pd.regions = a->regions;
  a->work.pd.n_regions = n;
}

/* The working model's regions and overlaps: one region and up to two overlaps per run. */
static cupid_status lay_out(cupid_problem_adaptive *a, const cupid_int *runs, int n) {
  cupid_pd_region *regions = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_CALL(cupid_calloc((size_t)n, sizeof *regions, "PD regions", &regions));
  a->work.coupling.n_overlaps = 0;
  for (int r = 0; r < n; r++) {
    cupid_box b = a->across;
    run_region(a, runs[2 * r], runs[2 * r + 1], &b.lo[1], &b.hi[1]);
    b.has[1] = 1;
    regions[r] = zone_region(a, &b);
    CUPID_TRY(run_overlaps(a, runs[2 * r], runs[2 * r + 1]));
  }
  set_regions(a, &regions, n);
cleanup:
  cupid_free(&regions);
  return st;
}

/* ------------------------------------------------- zones over part of the section: layout */

typedef struct {
  double r[4]; /* x lo, x hi, z lo, z hi */
  int tag;     /* 0: core; f + 1: a ring element meeting the core on its face f */
} section_rect;

/* Merge rectangles with the same tag whose union is a rectangle (one shared whole face). */
static int merge_rects(section_rect *q, int n, double tol) {
  for (int again = 1; again;) {
    again = 0;
    for (int i = 0; i < n && !again; i++)
      for (int j = i + 1; j < n && !again; j++) {
        double *a = q[i].r, *b = q[j].r;
        if (q[i].tag != q[j].tag) continue;
        for (int k = 0; k < 2 && !again; k++) { /* k: the axis they touch along (0 x, 1 z) */
          const int o = 1 - k;
          if (fabs(a[2 * o] - b[2 * o]) > tol || fabs(a[2 * o + 1] - b[2 * o + 1]) > tol) continue;
          if (fabs(a[2 * k + 1] - b[2 * k]) > tol && fabs(b[2 * k + 1] - a[2 * k]) > tol) continue;
          a[2 * k] = fmin(a[2 * k], b[2 * k]), a[2 * k + 1] = fmax(a[2 * k + 1], b[2 * k + 1]);
          q[j] = q[n - 1];
          n--;
          again = 1;
        }
      }
  }
  return n;
}

/* The rectangles of footprint F (its core merged, its ring elements merged by face): n at most
 * 2 * nse. */
static int footprint_rects(const cupid_problem_adaptive *a, const unsigned char *F, section_rect *q,
                           cupid_section_ring *ring) {
  int n = 0;
  for (int s = 0; s < a->nse; s++)
    if (F[s]) memcpy(q[n].r, a->sec.box + 4 * s, sizeof q[n].r), q[n++].tag = 0;
  const int nr = cupid_section_ring_of(&a->sec, F, ring);
  for (int i = 0; i < nr; i++) {
    memcpy(q[n].r, a->sec.box + 4 * ring[i].element, sizeof q[n].r);
    q[n++].tag = ring[i].face + 1;
  }
  return merge_rects(q, n, a->tol);
}

/* The working model's regions and overlaps of zones over part of the section: per run, a box
 * per rectangle of its footprint, the y overlaps at its ends and an overlap along x or z
 * (bounded to it: `along`) over each ring rectangle. */
static cupid_status lay_out_partial(cupid_problem_adaptive *a, const cupid_int *runs, int n) {
  cupid_pd_region *regions = NULL;
  section_rect *q = NULL;
  cupid_section_ring *ring = NULL;
  cupid_status st = CUPID_SUCCESS;
  int nreg = 0;
  CUPID_TRY(cupid_malloc(2 * (size_t)a->nse + 1, sizeof *q, "footprint boxes", &q));
  CUPID_TRY(cupid_malloc((size_t)a->nse + 1, sizeof *ring, "footprint ring", &ring));
  CUPID_TRY(cupid_calloc((size_t)n * (2 * (size_t)a->nse + 1), sizeof *regions, "PD regions", &regions));
  a->work.coupling.n_overlaps = 0;
  for (int r = 0; r < n; r++) {
    const cupid_int e0 = runs[2 * r], e1 = runs[2 * r + 1];
    const int nq = footprint_rects(a, a->next + e0 * a->nse, q, ring);
    cupid_box b;
    memset(&b, 0, sizeof b);
    run_region(a, e0, e1, &b.lo[1], &b.hi[1]);
    b.has[0] = b.has[1] = b.has[2] = 1;
    for (int i = 0; i < nq; i++) {
      b.lo[0] = q[i].r[0], b.hi[0] = q[i].r[1], b.lo[2] = q[i].r[2], b.hi[2] = q[i].r[3];
      regions[nreg++] = zone_region(a, &b);
      if (q[i].tag > 0) CUPID_TRY(push_overlap(a, &b, (q[i].tag - 1) / 2 == 0 ? 0 : 2));
    }
    CUPID_TRY(run_overlaps(a, e0, e1));
  }
  set_regions(a, &regions, nreg);
cleanup:
  cupid_free(&regions);
  cupid_free(&q);
  cupid_free(&ring);
  return st;
}

/* Zones over part of the section: the footprints the marks ask for (a->next), run by run of
 * the settled rows z: the union of the run's cores and marks, settled on the section. */
static void plan_footprints(cupid_problem_adaptive *a, const cupid_int *runs, int n) {
  const int nse = a->nse;
  memset(a->next, 0, (size_t)a->ne * (size_t)nse);
  for (int r = 0; r < n; r++) {
    unsigned char *F = a->next + runs[2 * r] * nse;
    for (cupid_int e = runs[2 * r]; e <= runs[2 * r + 1]; e++)
      for (int s = 0; s < nse; s++) F[s] |= a->foot[e * nse + s] | a->mark_s[e * nse + s];
    cupid_section_settle(&a->sec, F);
    for (cupid_int e = runs[2 * r] + 1; e <= runs[2 * r + 1]; e++) memcpy(a->next + e * nse, F, (size_t)nse);
  }
}

/* What the old problem leaves the new one: the nodes' places, displacements, broken bonds. */
typedef struct {
  cupid_pd_grid grid;
  cupid_pd_operator op;
  cupid_cuf_beam beam;
  double *u;
  cupid_int n_pd, fe_offset, n_fe_dofs;
} old_zone;

static void old_free(old_zone *o) {
  cupid_pd_grid_destroy(&o->grid);
  cupid_pd_operator_destroy(&o->op);
  cupid_cuf_beam_destroy(&o->beam);
  cupid_free(&o->u);
}

/* A field of the old problem (old, its DOFs) on the new one's DOFs (out): the old nodes'
 * values where they were; a new node's the old beam's field at its place (issue 37: "the new
 * nodes start from the beam's CUF displacement field", and in dynamics its velocity: the
 * beam's interpolation is linear in its DOFs); the beam's DOFs as they were (one mesh). */
static cupid_status carry_over(const cupid_problem_state *prob, const cupid_problem_adaptive *a,
                               const old_zone *o, const double *old, double *out) {
  const double *x = cupid_pd_grid_coords(prob->grid);
  unsigned char *seen = NULL;
  CUPID_CALL(cupid_calloc((size_t)prob->n_pd + 1, 1, "mapped nodes", &seen));
  for (cupid_int i = 0; i < o->n_pd; i++) {
    const cupid_int j = a->map[i];
    if (j < 0) continue;
    seen[j] = 1;
    memcpy(out + 3 * j, old + 3 * i, 3 * sizeof *out);
  }
  cupid_status st = CUPID_SUCCESS;
  for (cupid_int j = 0; j < prob->n_pd && st == CUPID_SUCCESS; j++) {
    if (seen[j]) continue;
    st = cupid_cuf_displacement_at(o->beam, old, x[3 * j], x[3 * j + 1], x[3 * j + 2], out + 3 * j);
  }
  cupid_free(&seen);
  CUPID_CALL(st);
  memcpy(out + prob->fe_offset, old + o->fe_offset, (size_t)o->n_fe_dofs * sizeof *out);
  return CUPID_SUCCESS;
}

/* The caller's fields of the old layout (carry[k], old ndof each), each replaced by its
 * carried copy on the new one. */
static cupid_status carry_fields(const cupid_problem_state *prob, const cupid_problem_adaptive *a,
                                 const old_zone *o, double **carry, int n_carry) {
  for (int k = 0; k < n_carry; k++) {
    double *out = NULL;
    CUPID_CALL(cupid_calloc((size_t)prob->ndof + 1, sizeof *out, "a carried field", &out));
    const cupid_status st = carry_over(prob, a, o, carry[k], out);
    if (st != CUPID_SUCCESS) {
      cupid_free(&out);
      return st;
    }
    cupid_free(&carry[k]);
    carry[k] = out;
  }
  return CUPID_SUCCESS;
}

static cupid_status record(cupid_problem_adaptive *a, const cupid_problem_conversion *c) {
  if (a->n_conv == a->cap_conv) {
    const int cap = a->cap_conv ? 2 * a->cap_conv : 8;
    CUPID_CALL(cupid_realloc((size_t)cap, sizeof *a->conv, "conversions", &a->conv));
    a->cap_conv = cap;
  }
  a->conv[a->n_conv++] = *c;
  return CUPID_SUCCESS;
}

/* Where a run stopped: "crack growth stopped at load step k (load factor x)", in dynamics
 * "the dynamic run stopped at step k (t = x)". */
static void stopped_at(const cupid_problem_state *prob, int step, double load, char *buf, size_t n) {
  if (prob->model->analysis.type == CUPID_ANALYSIS_DYNAMIC)
    snprintf(buf, n, "the dynamic run stopped at step %d (t = %.6g)", step, load);
  else
    snprintf(buf, n, "crack growth stopped at load step %d (load factor %.6g)", step, load);
}

/* The zone would pass max_nodes: the run stops there (exit 2) with its results so far. */
static void stop_at_cap(cupid_problem_state *prob, int step, double load, cupid_int nodes) {
  char where[96];
  stopped_at(prob, step, load, where, sizeof where);
  snprintf(prob->growth.stopped, sizeof prob->growth.stopped,
           "%s: the adaptive zone would grow to %lld PD nodes, over "
           "peridynamics.adaptive.max_nodes = %lld; raise it (cupid check prints what `within` "
           "allows) or bound the zone; the steps before are in the %s",
           where, (long long)nodes, (long long)prob->model->pd.adaptive.max_nodes,
           prob->model->analysis.type == CUPID_ANALYSIS_DYNAMIC ? "time series" : "steps' file");
  prob->growth.stopped_step = step;
}

/* The zone of the cores and the marks, settled, as the working model's regions: *runs of them
 * (at most MAX_ZONES), *nodes its PD nodes, *first / *last / *count the elements it adds.
 * *capped when it would pass max_nodes (then nothing changed). */
static cupid_status plan_zone(cupid_problem_state *prob, cupid_problem_adaptive *a, unsigned char *z,
                              int step, double load_factor, int *capped, cupid_problem_conversion *c) {
  const cupid_adaptive *ad = &prob->model->pd.adaptive;
  cupid_int runs[2 * MAX_ZONES];
  *capped = 0;
  for (cupid_int e = 0; e < a->ne; e++) z[e] = a->core[e] | a->mark[e];
  settle_zone(a, z);
  const int n = zone_runs(a, z, runs, MAX_ZONES);
  CUPID_CHECK(n <= MAX_ZONES, CUPID_ERR_UNSUPPORTED,
              "adaptive: the zone would split into %d parts along the beam, over the %d that "
              "Arlequin's %d overlaps allow; bound it with `within`",
              n, MAX_ZONES, CUPID_MAX_OVERLAPS);
  if (a->partial) plan_footprints(a, runs, n);
  cupid_int nodes = 0, first = -1, last = -1, count = 0;
  for (int r = 0; r < n; r++) {
    double lo, hi;
    cupid_int layer = a->layer_nodes;
    run_region(a, runs[2 * r], runs[2 * r + 1], &lo, &hi);
    if (a->partial) CUPID_CALL(footprint_nodes(a, a->next + runs[2 * r] * a->nse, &layer));
    nodes += layers(&a->work, lo, hi) * layer;
  }
  double box[4] = {INFINITY, -INFINITY, INFINITY, -INFINITY}; /* the units added, x and z */
  for (cupid_int e = 0; e < a->ne; e++) { /* elements, or over part of the section units */
    cupid_int added = !a->partial && z[e] && !a->core[e];
    for (int s = 0; s < a->nse && a->partial; s++) {
      const cupid_int u = e * a->nse + s;
      if (!a->next[u] || a->foot[u]) continue;
      added++;
      const double *b = a->sec.box + 4 * s;
      box[0] = fmin(box[0], b[0]), box[1] = fmax(box[1], b[1]);
      box[2] = fmin(box[2], b[2]), box[3] = fmax(box[3], b[3]);
    }
    if (!added) continue;
    if (first < 0) first = e;
    last = e, count += added;
  }
  if (ad->max_nodes > 0 && nodes > ad->max_nodes) {
    stop_at_cap(prob, step, load_factor, nodes);
    *capped = 1;
    return CUPID_SUCCESS;
  }
  CUPID_CALL(a->partial ? lay_out_partial(a, runs, n) : lay_out(a, runs, n));
  *c = (cupid_problem_conversion){.step = step, .load_factor = load_factor,
                                  .y_lo = a->ends[first], .y_hi = a->ends[last + 1],
                                  .elements = (int)count, .why = a->why, .partial = a->partial,
                                  .x_lo = box[0], .x_hi = box[1], .z_lo = box[2], .z_hi = box[3]};
  return CUPID_SUCCESS;
}

/* After a conversion: the zone's new cores, the marks cleared, the conversion recorded and
 * told. */
static cupid_status converted(cupid_problem_state *prob, cupid_problem_adaptive *a,
                              const unsigned char *z, cupid_problem_conversion *c, cupid_int before) {
  memcpy(a->core, z, (size_t)a->ne);
  memset(a->mark, 0, (size_t)a->ne);
  a->blocked = 0;
  if (a->partial) {
    memcpy(a->foot, a->next, (size_t)a->ne * (size_t)a->nse);
    memset(a->mark_s, 0, (size_t)a->ne * (size_t)a->nse);
  }
  c->added_nodes = zone_nodes(prob) - before, c->pd_nodes = zone_nodes(prob);
  CUPID_CALL(record(a, c));
  cupid_int zones = 0;
  for (cupid_int e = 0; e < a->ne; e++) zones += z[e] && (e == 0 || !z[e - 1]);
  char part[128] = "";
  if (c->partial)
    snprintf(part, sizeof part, ", x in [%g, %g], z in [%g, %g]", c->x_lo, c->x_hi, c->z_lo, c->z_hi);
  const int timed = prob->model->analysis.type == CUPID_ANALYSIS_DYNAMIC;
  cupid_problem_progress(prob, "adaptive: step %d, %s %.4g: %d %s%s on y in [%g, %g]%s "
                         "turned to PD (%s): +%lld nodes, %lld in all, %lld zone%s",
                         c->step, timed ? "t =" : "load factor", c->load_factor, c->elements,
                         c->partial ? "unit" : "beam element", c->elements == 1 ? "" : "s",
                         c->y_lo, c->y_hi, part, c->why ? c->why : "", (long long)c->added_nodes,
                         (long long)c->pd_nodes, (long long)zones, zones == 1 ? "" : "s");
  return CUPID_SUCCESS;
}

/* A crack that reached a node whose bonds never break after all (margin below a horizon: a
 * broken bond's far end in a new overlap): the run stops there, as a fixed zone's does. */
static int stop_if_protected_damaged(cupid_problem_state *prob, int step, double load) {
  const double *x = cupid_pd_grid_coords(prob->grid);
  cupid_int found = -1;
  for (cupid_int i = 0; i < prob->n_pd && prob->protect && prob->damage && found < 0; i++)
    if (prob->protect[i] && prob->damage[i] > 0.0 && decides(prob, i)) found = i;
  double p[3] = {0.0, 0.0, 0.0};
  if (found >= 0) memcpy(p, x + 3 * found, sizeof p);
  if (prob->slab) { /* the place the lowest rank that found one found */
    double who = found >= 0 ? -(double)cupid_petsc_rank() : -INFINITY;
    cupid_petsc_max_doubles(&who, 1);
    if (who == -INFINITY) return 0;
    if (-who != (double)cupid_petsc_rank()) p[0] = p[1] = p[2] = 0.0;
    cupid_petsc_sum_doubles(p, 3);
    found = 0;
  }
  if (found >= 0) {
    char where[96];
    stopped_at(prob, step, load, where, sizeof where);
    snprintf(prob->growth.stopped, sizeof prob->growth.stopped,
             "%s: the grown adaptive zone has a broken bond at its overlap's PD node (%g, %g, "
             "%g), whose bonds never break; give peridynamics.adaptive.margin of a horizon or "
             "more", where, p[0], p[1], p[2]);
    prob->growth.stopped_step = step;
    return 1;
  }
  return 0;
}

cupid_status cupid_problem_adaptive_convert(cupid_problem_state *prob, int step, double load_factor,
                                            double **carry, int n_carry, int *stopped) {
  cupid_problem_adaptive *a = prob->adaptive;
  unsigned char *z = NULL;
  old_zone o = {0};
  cupid_problem_conversion c = {0};
  cupid_status st = CUPID_SUCCESS;
  *stopped = 0;
  CUPID_TRY(cupid_malloc((size_t)a->ne + 1, 1, "the new zone", &z));
  CUPID_TRY(plan_zone(prob, a, z, step, load_factor, stopped, &c));
  if (*stopped) goto cleanup;
  /* the old problem's grid, operator, beam and u stay for the carry-over */
  const cupid_int before = zone_nodes(prob);
  o = (old_zone){prob->grid, prob->op, prob->beam, prob->u, prob->n_pd, prob->fe_offset,
                 prob->n_fe_dofs};
  prob->grid = NULL, prob->op = NULL, prob->beam = NULL, prob->u = NULL;
  st = cupid_problem_rebuild(prob, 1);
  if (st != CUPID_SUCCESS) { /* e.g. a support's box that holds no PD node of the zone now */
    char msg[768];
    snprintf(msg, sizeof msg, "%s", cupid_error_message());
    st = CUPID_ERROR(st, "adaptive: at load step %d the PD zone grew over y in [%g, %g] (%s): %s; "
                     "keep it away from there with peridynamics.adaptive.within",
                     step, c.y_lo, c.y_hi, c.why ? c.why : "", msg);
    goto cleanup;
  }
  cupid_free(&a->map);
  CUPID_TRY(cupid_malloc((size_t)o.n_pd + 1, sizeof *a->map, "node map", &a->map));
  a->map_n = o.n_pd;
  if (o.grid) { /* (a zone that started empty had none) */
    CUPID_TRY(cupid_pd_grid_map_nodes(o.grid, prob->grid, a->map));
    for (cupid_int i = 0; i < o.n_pd; i++)
      CUPID_TRY_CHECK(a->map[i] >= 0, CUPID_ERR_INTERNAL,
                      "adaptive: PD node %lld of the old zone is not in the new one", (long long)i);
    CUPID_TRY(cupid_pd_operator_copy_broken_mapped(prob->op, o.op, a->map));
  }
  CUPID_TRY(cupid_problem_fracture_damage(prob));
  CUPID_TRY(carry_over(prob, a, &o, o.u, prob->u));
  CUPID_TRY(carry_fields(prob, a, &o, carry, n_carry));
  CUPID_TRY(converted(prob, a, z, &c, before));
  *stopped = stop_if_protected_damaged(prob, step, load_factor);
cleanup:
  old_free(&o);
  cupid_free(&z);
  return st;
}

/* During the set-up: the zone grows away from the pre-cracks first (the elements within
 * margin horizons of their cut bonds), as it would from any broken bond: "step 0". Then no
 * pre-crack may reach an overlap. */
static cupid_status grow_from_precracks(cupid_problem_state *prob, cupid_problem_adaptive *a) {
  const cupid_model_t *m = prob->model;
  const cupid_adaptive *ad = &m->pd.adaptive;
  CUPID_CALL(cupid_problem_fracture_damage(prob));
  cupid_int n = mark_damage(a, prob);
  /* a zone that starts empty: the elements a pre-crack spans, and those within margin
   * horizons and a horizon (its cut bonds' reach) of it (else the pre-cracks lie in the
   * regions, and their cut bonds are the damage above) */
  const double r = (ad->margin + 1.0) * m->pd.horizon;
  for (int k = 0; k < m->pd.n_precracks && !prob->grid; k++) {
    const cupid_precrack *pc = &m->pd.precracks[k];
    const double y0 = pc->normal == 1 ? pc->at : pc->rect.lo[1];
    const double y1 = pc->normal == 1 ? pc->at : pc->rect.hi[1];
    for (cupid_int e = 0; e < a->ne; e++)
      if (a->ends[e] < y1 + r && a->ends[e + 1] > y0 - r && !a->core[e] && !a->mark[e] &&
          convertible(a, ad, e))
        a->mark[e] = 1, n++;
  }
  n = cupid_problem_global_count(prob, n); /* the cut bonds of every rank */
  CUPID_CALL(agree_marks(prob, a));
  if (n > 0) {
    a->why = "pre-crack near an overlap";
    unsigned char *z = NULL;
    cupid_problem_conversion c = {0};
    int capped = 0;
    const cupid_int before = zone_nodes(prob);
    CUPID_CALL(cupid_malloc((size_t)a->ne + 1, 1, "the new zone", &z));
    cupid_status st = plan_zone(prob, a, z, 0, 0.0, &capped, &c);
    if (st == CUPID_SUCCESS && capped)
      st = cupid_model_error(prob->model, &prob->model->pd.adaptive.mark, "%s",
                             prob->growth.stopped);
    if (st == CUPID_SUCCESS) st = cupid_problem_rebuild(prob, 0);
    if (st == CUPID_SUCCESS) st = cupid_problem_fracture_damage(prob);
    if (st == CUPID_SUCCESS) st = converted(prob, a, z, &c, before);
    cupid_free(&z);
    CUPID_CALL(st);
  }
  return cupid_problem_fracture_check_protected(prob);
}

/* The overlaps' widths in words: the fewest elements over a length, or element counts. */
static void overlap_words(const cupid_problem_adaptive *a, const cupid_model_t *m, char *buf,
                          size_t n) {
  if (a->ov_width > 0.0)
    snprintf(buf, n, "each the fewest beam elements that span %g horizon%s = %g",
             m->pd.adaptive.overlap, m->pd.adaptive.overlap == 1.0 ? "" : "s", a->ov_width);
  else
    snprintf(buf, n, "%d / %d beam elements below / above a zone%s", a->ov_lo, a->ov_hi,
             a->partial ? ", one section element across the section" : "");
}

#define ADAPTIVE_MAX_ELEMENT 10.0 /* horizons: the longest beam element a zone may take */

/* A zone grows by whole beam elements: one much longer than the horizon would turn a slab of
 * beam far from the crack to PD at once (the C-beam's 121 mm elements next to its zone: 40
 * horizons, 10^5 PD nodes) and put its next overlap as far away. Each element that may turn
 * must be at most ADAPTIVE_MAX_ELEMENT horizons long. */
static cupid_status long_elements(const cupid_problem_adaptive *a, const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  const cupid_adaptive *ad = &m->pd.adaptive;
  const double limit = ADAPTIVE_MAX_ELEMENT * m->pd.horizon;
  for (cupid_int e = 0; e < a->ne; e++) {
    const double len = a->ends[e + 1] - a->ends[e];
    if (a->core[e] || !convertible(a, ad, e) || len <= limit + a->tol) continue;
    return cupid_model_error(m, ad->has_within ? &ad->within_mark : &ad->mark,
                             "the beam element on y in [%g, %g] may turn to PD and is %g long, "
                             "%.3g horizons: a zone grows by whole beam elements and could not "
                             "follow a crack by one this long (at most %g horizons = %g): refine "
                             "beam.axis where the zone may grow, or keep the zone off it with "
                             "peridynamics.adaptive.within",
                             a->ends[e], a->ends[e + 1], len, len / m->pd.horizon,
                             ADAPTIVE_MAX_ELEMENT, limit);
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_adaptive_begin(cupid_problem_state *prob) {
  cupid_problem_adaptive *a = prob->adaptive;
  a->tol = ADAPTIVE_TOL * (prob->fe_info.y_max - prob->fe_info.y_min);
  a->nse = (int)prob->fe_info.n_section_elements;
  a->overlaps = (cupid_problem_method_of(prob->model)->caps & CUPID_METHOD_OVERLAPS) != 0;
  CUPID_CALL(element_ends(a, prob));
  if (!prob->grid) {
    CUPID_CALL(empty_zone(a, prob));
  } else {
    /* the lattice of the first grid, kept by every grid to come */
    cupid_pd_grid_origin(prob->grid, a->work.pd.anchor);
    a->work.pd.has_anchor = 1;
    CUPID_CALL(initial_zone(a, prob));
    a->s0 = trigger_stretch(prob);
    a->layer_nodes = layer_nodes_of(prob);
    if (prob->slab && a->partial)
      return cupid_model_error(prob->model, &prob->model->pd.adaptive.mark,
                               "under mpirun an adaptive zone grows over the whole section "
                               "(its z slabs keep their layers); a zone over part of the "
                               "section changes its z extent: run it on one process");
    if (prob->slab) { /* each rank keeps its layers (zone_nodes, above) */
      a->work.pd.has_slab_window = 1;
      a->work.pd.slab_window[0] = prob->part.own_z[0];
      a->work.pd.slab_window[1] = prob->part.own_z[1];
    }
  }
  CUPID_CALL(long_elements(a, prob));
  a->initial_nodes = zone_nodes(prob);
  const cupid_adaptive *ad = &prob->model->pd.adaptive;
  if (ad->max_nodes > 0 && a->initial_nodes > ad->max_nodes)
    return cupid_model_error(prob->model, &ad->mark,
                             "the initial PD zone has %lld nodes, over max_nodes = %lld",
                             (long long)a->initial_nodes, (long long)ad->max_nodes);
  CUPID_CALL(grow_from_precracks(prob, a));
  char ov[96];
  overlap_words(a, prob->model, ov, sizeof ov);
  cupid_problem_progress(prob, "adaptive: the zone grows by %s where the strain (under an "
                         "overlap: the bonds' stretch) reaches %g x s0 = %.4g, or a crack comes "
                         "within %g horizons of an overlap (%s)",
                         a->partial ? "beam element x section element" : "beam elements",
                         ad->threshold, ad->threshold * a->s0, ad->margin, ov);
  return CUPID_SUCCESS;
}

/* ---- Checkpoints (resume.c; issue 36): the zone is part of the run's state ---- */

/* The triggers' names, by number in a checkpoint (a conversion's `why` points at one). */
static const char *const WHY[] = {"strain", "stretch in an overlap", "stretch in the coupling zone",
                                  "crack near an overlap", "an overlap's bond reached its limit",
                                  "a coupling zone's bond reached its limit",
                                  "pre-crack near an overlap"};
#define N_WHY ((int)(sizeof WHY / sizeof *WHY))

/* The section's head; then core (ne bytes), foot (ne x nse bytes, partial), the conversions
 * (why: its number in WHY), the regions' boxes, the overlaps' boxes and their `along`. */
typedef struct {
  cupid_int ne;
  int nse, partial, n_conv, n_regions, n_overlaps;
} zone_head;

typedef struct {
  cupid_problem_conversion c;
  int why;
} zone_conversion;

static size_t zone_bytes(const zone_head *h) {
  return sizeof *h + (size_t)h->ne + (h->partial ? (size_t)h->ne * (size_t)h->nse : 0) +
         (size_t)h->n_conv * sizeof(zone_conversion) +
         (size_t)(h->n_regions + h->n_overlaps) * sizeof(cupid_box) +
         (size_t)h->n_overlaps * sizeof(int);
}

cupid_status cupid_problem_adaptive_save(const cupid_problem_state *prob, cupid_checkpoint_writer w) {
  const cupid_problem_adaptive *a = prob->adaptive;
  if (!a) return CUPID_SUCCESS;
  const cupid_model_t *m = &a->work;
  const zone_head h = {.ne = a->ne, .nse = a->nse, .partial = a->partial, .n_conv = a->n_conv,
                       .n_regions = m->pd.n_regions, .n_overlaps = m->coupling.n_overlaps};
  unsigned char *buf = NULL;
  CUPID_CALL(cupid_malloc(zone_bytes(&h), 1, "the zone's checkpoint", &buf));
  unsigned char *at = buf;
#define PUT(src, n) (memcpy(at, (src), (n)), at += (n))
  PUT(&h, sizeof h);
  PUT(a->core, (size_t)a->ne);
  if (a->partial) PUT(a->foot, (size_t)a->ne * (size_t)a->nse);
  for (int k = 0; k < a->n_conv; k++) {
    zone_conversion z = {.c = a->conv[k], .why = -1};
    for (int q = 0; q < N_WHY; q++)
      if (a->conv[k].why && !strcmp(a->conv[k].why, WHY[q])) z.why = q;
    z.c.why = NULL;
    PUT(&z, sizeof z);
  }
  for (int r = 0; r < h.n_regions; r++) PUT(&m->pd.regions[r].box, sizeof(cupid_box));
  for (int q = 0; q < h.n_overlaps; q++) PUT(&m->coupling.overlaps[q], sizeof(cupid_box));
  for (int q = 0; q < h.n_overlaps; q++) PUT(&m->coupling.overlap_along[q], sizeof(int));
#undef PUT
  const cupid_status st = cupid_checkpoint_write(w, "adaptive", buf, zone_bytes(&h));
  cupid_free(&buf);
  return st;
}

/* The zone of a checkpoint's section (data, bytes) into a (regions, overlaps, cores,
 * conversions); *grew: it differs from the zone the set-up laid (conversions since). */
static cupid_status zone_restore(cupid_problem_adaptive *a, const unsigned char *data, size_t bytes,
                                 int *grew) {
  zone_head h;
  *grew = 0;
  CUPID_CHECK(bytes >= sizeof h, CUPID_ERR_IO, "the checkpoint's adaptive zone is cut short");
  memcpy(&h, data, sizeof h);
  CUPID_CHECK(h.ne == a->ne && h.nse == a->nse && h.partial == a->partial && h.n_conv >= 0 &&
                  h.n_regions >= 0 && h.n_overlaps >= 0 && h.n_overlaps <= CUPID_MAX_OVERLAPS &&
                  bytes == zone_bytes(&h),
              CUPID_ERR_IO, "the checkpoint's adaptive zone is not of this model's beam");
  if (h.n_conv == a->n_conv) return CUPID_SUCCESS; /* no conversion after the set-up's */
  const unsigned char *at = data + sizeof h;
  memcpy(a->core, at, (size_t)a->ne), at += a->ne;
  if (a->partial) {
    memcpy(a->foot, at, (size_t)a->ne * (size_t)a->nse);
    at += (size_t)a->ne * (size_t)a->nse;
  }
  a->n_conv = 0;
  for (int k = 0; k < h.n_conv; k++, at += sizeof(zone_conversion)) {
    zone_conversion z;
    memcpy(&z, at, sizeof z);
    z.c.why = z.why >= 0 && z.why < N_WHY ? WHY[z.why] : NULL;
    CUPID_CALL(record(a, &z.c));
  }
  cupid_pd_region *regions = NULL;
  CUPID_CALL(cupid_calloc((size_t)h.n_regions, sizeof *regions, "PD regions", &regions));
  for (int r = 0; r < h.n_regions; r++, at += sizeof(cupid_box)) {
    cupid_box b;
    memcpy(&b, at, sizeof b);
    regions[r] = zone_region(a, &b);
  }
  set_regions(a, &regions, h.n_regions);
  a->work.coupling.n_overlaps = 0;
  const unsigned char *along = at + (size_t)h.n_overlaps * sizeof(cupid_box);
  for (int q = 0; q < h.n_overlaps; q++) {
    cupid_box b;
    int ax;
    memcpy(&b, at + (size_t)q * sizeof b, sizeof b);
    memcpy(&ax, along + (size_t)q * sizeof ax, sizeof ax);
    CUPID_CALL(push_overlap(a, &b, ax));
  }
  memset(a->mark, 0, (size_t)a->ne);
  if (a->partial) memset(a->mark_s, 0, (size_t)a->ne * (size_t)a->nse);
  *grew = 1;
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_adaptive_resume(cupid_problem_state *prob) {
  cupid_problem_adaptive *a = prob->adaptive;
  if (!a || !prob->opts->resume) return CUPID_SUCCESS;
  void *data = NULL;
  size_t bytes = 0;
  int grew = 0;
  CUPID_CALL(cupid_problem_checkpoint_peek(prob, "adaptive", &data, &bytes));
  const cupid_status st = zone_restore(a, data, bytes, &grew);
  cupid_free(&data);
  CUPID_CALL(st);
  if (!grew) return CUPID_SUCCESS;
  CUPID_CALL(cupid_problem_rebuild(prob, 1));
  cupid_problem_progress(prob, "resume: the adaptive zone of the checkpoint: %lld PD nodes after "
                         "%d conversions", (long long)zone_nodes(prob), a->n_conv);
  return CUPID_SUCCESS;
}

void cupid_problem_adaptive_energy(cupid_problem_state *prob, double energy) {
  cupid_problem_adaptive *a = prob->adaptive;
  if (!a || a->n_conv == 0) return;
  a->conv[a->n_conv - 1].energy = energy;
  a->conv[a->n_conv - 1].has_energy = 1;
}

int cupid_problem_adaptive_every(const cupid_problem_state *prob) {
  const int every = prob->model->pd.adaptive.every;
  return every > 0 ? every : prob->model->analysis.dynamic.every;
}

const cupid_int *cupid_problem_adaptive_map(const cupid_problem_state *prob, cupid_int *n) {
  *n = prob->adaptive ? prob->adaptive->map_n : 0;
  return prob->adaptive ? prob->adaptive->map : NULL;
}

/* ------------------------------------------------------------------------------ reports */

/* The largest zone `within` allows: every element that may turn, with the zone now. */
static cupid_int largest_zone(const cupid_problem_adaptive *a, const cupid_adaptive *ad) {
  unsigned char *z = NULL;
  cupid_int runs[2 * MAX_ZONES], nodes = 0;
  if (cupid_malloc((size_t)a->ne + 1, 1, "the largest zone", &z) != CUPID_SUCCESS) {
    cupid_error_clear();
    return -1;
  }
  for (cupid_int e = 0; e < a->ne; e++) z[e] = a->core[e] || convertible(a, ad, e);
  settle_zone(a, z);
  const int n = zone_runs(a, z, runs, MAX_ZONES);
  unsigned char *all = NULL; /* over part of the section: the largest footprint, all of it */
  if (a->partial && cupid_malloc((size_t)a->nse, 1, "the largest footprint", &all) != CUPID_SUCCESS) {
    cupid_error_clear();
    cupid_free(&z);
    return -1;
  }
  if (all) memset(all, 1, (size_t)a->nse);
  cupid_int layer = a->layer_nodes;
  if (all && footprint_nodes(a, all, &layer) != CUPID_SUCCESS) cupid_error_clear(), layer = -1;
  for (int r = 0; r < n && r < MAX_ZONES && layer >= 0; r++) {
    double lo, hi;
    run_region(a, runs[2 * r], runs[2 * r + 1], &lo, &hi);
    nodes += layers(&a->work, lo, hi) * layer;
  }
  if (layer < 0) nodes = -1;
  cupid_free(&all);
  cupid_free(&z);
  return nodes;
}

void cupid_problem_adaptive_print(const cupid_problem_state *prob, double bytes) {
  const cupid_problem_adaptive *a = prob->adaptive;
  if (!a || !a->ends) return;
  const cupid_adaptive *ad = &prob->model->pd.adaptive;
  char ov[96];
  overlap_words(a, prob->model, ov, sizeof ov);
  printf("adaptive: threshold %g x s0 = %.6g (strain), margin %g horizons = %g; overlaps: %s\n",
         ad->threshold, ad->threshold * a->s0, ad->margin, ad->margin * prob->model->pd.horizon,
         ov);
  if (ad->has_within && ad->within.has[1])
    printf("adaptive: within y in [%g, %g]\n", ad->within.lo[1], ad->within.hi[1]);
  if (prob->model->analysis.type == CUPID_ANALYSIS_DYNAMIC)
    printf("adaptive: the trigger is tested every %d time steps\n", cupid_problem_adaptive_every(prob));
  const cupid_int big = largest_zone(a, ad);
  /* the memory of a zone that size: this model's estimate per PD node */
  const double per_node = prob->n_pd > 0 && bytes > 0 ? bytes / (double)prob->n_pd : 0.0;
  printf("adaptive: zone now %lld PD nodes; the largest `within` allows: %lld PD nodes",
         (long long)prob->n_pd, (long long)big);
  if (per_node > 0.0) printf(" (about %.3g GB at this model's %.3g kB a node)", big * per_node / 1e9,
                             per_node / 1e3);
  printf("%s\n", ad->max_nodes > 0 && big > ad->max_nodes ? ", over max_nodes: a run may stop there"
                                                          : "");
}

/* A box as a model's keys ({x: [..], y: [..], z: [..]}, with `along` when along >= 0). */
static void json_box(cupid_json js, const cupid_box *b, int along) {
  cupid_json_begin_object(js, NULL);
  for (int k = 0; k < 3; k++) {
    if (!b->has[k]) continue;
    const char key[2] = {"xyz"[k], 0};
    cupid_json_begin_array(js, key);
    cupid_json_number(js, NULL, b->lo[k]);
    cupid_json_number(js, NULL, b->hi[k]);
    cupid_json_end_array(js);
  }
  if (along >= 0) {
    const char axis[2] = {"xyz"[along], 0};
    cupid_json_string(js, "along", axis);
  }
  cupid_json_end_object(js);
}

void cupid_problem_adaptive_json(cupid_json js, const cupid_problem_state *prob) {
  const cupid_problem_adaptive *a = prob->adaptive;
  if (!a) return;
  const cupid_adaptive *ad = &prob->model->pd.adaptive;
  cupid_json_begin_object(js, "adaptive");
  cupid_json_number(js, "threshold", ad->threshold);
  cupid_json_number(js, "trigger_strain", ad->threshold * a->s0);
  cupid_json_number(js, "margin", ad->margin);
  if (a->ov_width > 0.0) cupid_json_number(js, "overlap", ad->overlap);
  if (ad->max_nodes > 0) cupid_json_integer(js, "max_nodes", ad->max_nodes);
  cupid_json_integer(js, "initial_pd_nodes", a->initial_nodes);
  cupid_json_integer(js, "pd_nodes", zone_nodes(prob));
  /* the zone at the end: the boxes and overlaps of a model that has it from the start */
  const cupid_model_t *w = &a->work;
  cupid_json_begin_array(js, "regions");
  for (int r = 0; r < w->pd.n_regions; r++) json_box(js, &w->pd.regions[r].box, -1);
  cupid_json_end_array(js);
  cupid_json_begin_array(js, "overlaps");
  for (int q = 0; q < w->coupling.n_overlaps; q++) {
    const cupid_box *b = &w->coupling.overlaps[q];
    json_box(js, b, b->has[0] + b->has[1] + b->has[2] > 1 ? w->coupling.overlap_along[q] : -1);
  }
  cupid_json_end_array(js);
  cupid_json_begin_array(js, "conversions");
  for (int k = 0; k < a->n_conv; k++) {
    const cupid_problem_conversion *c = &a->conv[k];
    cupid_json_begin_object(js, NULL);
    cupid_json_integer(js, "step", c->step);
    cupid_json_number(js, prob->model->analysis.type == CUPID_ANALYSIS_DYNAMIC ? "t" : "load_factor",
                      c->load_factor);
    if (c->has_energy) cupid_json_number(js, "energy", c->energy);
    cupid_json_integer(js, "added_nodes", c->added_nodes);
    cupid_json_integer(js, "pd_nodes", c->pd_nodes);
    cupid_json_integer(js, "elements", c->elements);
    cupid_json_number(js, "y_from", c->y_lo);
    cupid_json_number(js, "y_to", c->y_hi);
    if (c->partial) {
      cupid_json_number(js, "x_from", c->x_lo);
      cupid_json_number(js, "x_to", c->x_hi);
      cupid_json_number(js, "z_from", c->z_lo);
      cupid_json_number(js, "z_to", c->z_hi);
    }
    cupid_json_string(js, "trigger", c->why);
    cupid_json_end_object(js);
  }
  cupid_json_end_array(js);
  cupid_json_end_object(js);
}
