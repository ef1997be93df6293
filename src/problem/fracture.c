/* Pre-cracks and bond breaking of a model (model-format.md: peridynamics.precracks,
 * peridynamics.fracture; docs/theory.md, section Fracture): what this version runs, the
 * pre-cracks removed from prob->op, the breaking rule (critical stretch, given or derived from
 * G0; critical bond energy), the nodes whose bonds never break (no-fail boxes; the coupling
 * zone of a coupled model, from its method), the break step of a dynamic run, and the damage
 * the outputs show. The bonds themselves live in the PD operator (src/pd/fracture.c). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "method.h"
#include "problem_internal.h"

int cupid_problem_has_damage(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  return m->has_peridynamics && (m->pd.fracture.has_fracture || m->pd.n_precracks > 0);
}

cupid_status cupid_problem_fracture_check(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  if (!cupid_problem_has_damage(prob)) return CUPID_SUCCESS;
  const cupid_fracture *fr = &m->pd.fracture;
  const cupid_mark *mk = fr->has_fracture ? &fr->mark : &m->pd.precracks[0].mark;
  if (m->pd.surface_correction != CUPID_SURFACE_NONE && m->pd.model != CUPID_PD_BOND)
    return cupid_model_error(m, mk,
                             "pre-cracks and fracture with peridynamics.surface_correction: energy "
                             "need model: bond (LPS: the corrected dilatation is not kept as bonds "
                             "break); or surface_correction: none");
  if (!(prob->method->caps & CUPID_METHOD_FRACTURE))
    return cupid_model_error(m, mk,
                             "pre-cracks and fracture are not supported with coupling method %s "
                             "in cupid %s",
                             prob->method->name, cupid_version());
  if (!fr->has_fracture) return CUPID_SUCCESS;
  const cupid_analysis *a = &m->analysis;
  if (a->type == CUPID_ANALYSIS_EVALUATE)
    return cupid_model_error(m, &fr->mark,
                             "bond breaking needs type: static (crack growth over load steps) or "
                             "dynamic (integrator: central); type evaluate breaks nothing");
  if (a->type == CUPID_ANALYSIS_DYNAMIC && a->dynamic.integrator != CUPID_INTEGRATOR_CENTRAL)
    return cupid_model_error(m, &fr->mark,
                             "bond breaking needs analysis.dynamic.integrator: central (Newmark "
                             "factors K once, and every broken bond changes K)");
  if (a->type == CUPID_ANALYSIS_DYNAMIC && !prob->method->explicit_operator)
    return cupid_model_error(m, &fr->mark,
                             "bond breaking in dynamics needs the method's matrix-free explicit "
                             "operator, which coupling method %s has not (its K is assembled "
                             "once); quasi-static growth (type: static with steps) breaks bonds "
                             "with it, or use `coupling: {method: arlequin}` for dynamics",
                             prob->method->name);
  return CUPID_SUCCESS;
}

/* The bonds the pre-cracks cut; each must cut one. */
static cupid_status apply_precracks(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  for (int k = 0; k < m->pd.n_precracks; k++) {
    const cupid_precrack *pc = &m->pd.precracks[k];
    cupid_pd_precrack c = {.normal = pc->normal, .at = pc->at};
    for (int b = 0; b < 3; b++) c.lo[b] = pc->rect.lo[b], c.hi[b] = pc->rect.hi[b];
    cupid_int removed = 0, crossing = 0;
    CUPID_CALL(cupid_pd_operator_precrack(prob->op, &c, &removed));
    prob->precrack_bonds += removed;
    if (cupid_problem_global_count(prob, removed) > 0) continue;
    /* nothing left to cut: pre-cracks that overlap are one crack (issue 33: "cuts no bond"
     * was said of a rectangle inside an earlier one) */
    CUPID_CALL(cupid_pd_operator_precrack_crossing(prob->op, &c, &crossing));
    if (cupid_problem_global_count(prob, crossing) > 0) {
      cupid_problem_progress(prob, "precracks[%d]: its bonds were cut by the pre-cracks before "
                             "it (it lies over them)", k);
      continue;
    }
    return cupid_model_error(m, &pc->mark,
                             "the pre-crack cuts no bond: no two PD nodes within the horizon "
                             "lie on opposite sides of its rectangle (nodes sit at cell "
                             "centres, half a spacing inside the region faces)");
  }
  return CUPID_SUCCESS;
}

/* A pre-crack must not reach a node whose bonds never break (the coupling zone). An adaptive
 * zone grows away from its pre-cracks first (adaptive.c), then checks. */
cupid_status cupid_problem_fracture_check_protected(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  if (!prob->protect || m->pd.n_precracks == 0) return CUPID_SUCCESS;
  CUPID_CALL(cupid_problem_fracture_damage(prob));
  const double *x = cupid_pd_grid_coords(prob->grid);
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    if (!prob->protect[i] || prob->damage[i] <= 0) continue;
    char zone[512] = "";
    if (prob->method->protected_zone) {
      char z[480];
      prob->method->protected_zone(prob, x + 3 * i, z, sizeof z);
      snprintf(zone, sizeof zone, ": %s", z);
    }
    return cupid_model_error(m, &m->pd.precracks[0].mark,
                             "a pre-crack reaches the coupling zone at the PD node (%g, %g, %g) "
                             "(coupling method %s%s; its bonds never break); keep pre-cracks "
                             "more than a horizon away from it",
                             x[3 * i], x[3 * i + 1], x[3 * i + 2], prob->method->name, zone);
  }
  return CUPID_SUCCESS;
}

/* s0 from G0 per node (fracture.md, docs/theory.md): bond-based sqrt(5 G0 / (9 K delta))
 * (Silling & Askari 2005), LPS sqrt(G0 / ((3 mu + (3/4)^4 (K - 5 mu / 3)) delta)). */
/* The critical stretch of node i's material from G0.
 * continuum (Silling & Askari 2005; fracture.md): bond-based s0 = sqrt(5 G0 / (9 K delta)),
 *   LPS s0 = sqrt(G0 / ((3 mu + (3/4)^4 (K - 5 mu / 3)) delta));
 * grid (bond-based, issue 38): the energy that cutting a plane releases, summed over the
 *   lattice's own bonds. A pair's energy at stretch s is c omega beta s^2 |xi| V^2 / 2, and per
 *   unit area of a plane with normal n, averaged over its positions, |xi . n| / V pairs of
 *   offset xi cross it; averaged over orientations, |xi . n| -> |xi| / 2. So
 *   G = c s^2 / 8 sum omega beta |xi|^2 V = (9/4) K s^2 R, R = m_full / S_full with
 *   c = 18 K / S_full: s0 = sqrt(G0 / ((9/4) K R)). In the continuum R = 4 delta / 5 and this
 *   is the formula above; on a lattice R is the operator's (influence, partial volumes). */
static double stretch_from_g0(const cupid_problem_state *prob, const cupid_material *mt, double G0,
                              int grid) {
  const double delta = prob->model->pd.horizon;
  const double K = mt->E / (3.0 * (1.0 - 2.0 * mt->nu)), mu = mt->E / (2.0 * (1.0 + mt->nu));
  if (prob->model->pd.model != CUPID_PD_BOND) {
    const double q = 0.75 * 0.75 * 0.75 * 0.75;
    return sqrt(G0 / ((3.0 * mu + q * (K - 5.0 * mu / 3.0)) * delta));
  }
  if (!grid) return sqrt(5.0 * G0 / (9.0 * K * delta));
  return sqrt(G0 / (2.25 * K * prob->lattice_ratio));
}

double cupid_problem_fracture_s0_of(const cupid_problem_state *prob, int material) {
  const cupid_fracture *fr = &prob->model->pd.fracture;
  if (fr->has_critical_stretch) return fr->critical_stretch;
  return stretch_from_g0(prob, &prob->model->materials[material], fr->energy_release_rate, 0);
}

/* The lattice's cut energy at the continuum s0 over G0 (bond-based): 5 R / (4 delta). */
static double lattice_energy_fraction(const cupid_problem_state *prob) {
  return 5.0 * prob->lattice_ratio / (4.0 * prob->model->pd.horizon);
}

static cupid_status node_stretch(cupid_problem_state *prob, double G0) {
  const cupid_model_t *m = prob->model;
  const int *mat = cupid_pd_grid_materials(prob->grid);
  if (m->pd.model == CUPID_PD_BOND) { /* R = m / S, read now: the reports come after the
                                        solve, when a slab run may hold no operator */
    double m_full = 0.0, S_full = 0.0;
    cupid_pd_operator_full_family(prob->op, &m_full, &S_full);
    prob->lattice_ratio = m_full / S_full;
  }
  CUPID_CALL(cupid_malloc((size_t)prob->n_pd, sizeof *prob->node_stretch, "critical stretches",
                          &prob->node_stretch));
  for (cupid_int i = 0; i < prob->n_pd; i++)
    prob->node_stretch[i] =
        stretch_from_g0(prob, &m->materials[mat[i]], G0, m->pd.fracture.calibration_grid);
  if (m->pd.model == CUPID_PD_BOND && prob->n_pd > 0)
    for (int g = 0; g < 2; g++)
      prob->s0_calibrations[g] = stretch_from_g0(prob, &m->materials[mat[0]], G0, g);
  return CUPID_SUCCESS;
}

/* Bit b of no_fail[i]: node i lies in no-fail box b. */
static cupid_status no_fail_masks(cupid_problem_state *prob) {
  const cupid_fracture *fr = &prob->model->pd.fracture;
  if (fr->n_no_fail == 0) return CUPID_SUCCESS;
  CUPID_CALL(cupid_calloc((size_t)prob->n_pd, sizeof *prob->no_fail, "no-fail flags", &prob->no_fail));
  const double *x = cupid_pd_grid_coords(prob->grid), h = cupid_pd_grid_spacing(prob->grid);
  for (cupid_int i = 0; i < prob->n_pd; i++)
    for (int b = 0; b < fr->n_no_fail; b++)
      if (cupid_box_contains(&fr->no_fail[b], x + 3 * i, 1e-9 * h)) prob->no_fail[i] |= 1u << b;
  return CUPID_SUCCESS;
}

/* The critical-energy test reads the dilatations of both ends, and a slab's outer halo has
 * them wrong (its families are cut), as it then has the bonds decided there, and so on
 * inwards step by step. So on a slab each bond is decided by the rank that owns its lower
 * node (where both ends' dilatations are right: halo of two horizons), and its bit goes to
 * every rank that holds the node (one exchange a step). The stretch test reads u alone,
 * which every rank has right: each rank decides its slab's bonds itself, as the whole grid
 * would, and nothing is exchanged. */
static cupid_status break_exchange_setup(cupid_problem_state *prob) {
  const cupid_pd_grid_partition *p = &prob->part;
  const cupid_int nw = cupid_pd_operator_broken_words(prob->op);
  prob->fracture.owned_only = 1;
  CUPID_CALL(cupid_calloc((size_t)(nw * prob->n_pd) + 1, sizeof *prob->break_words,
                          "broken-bond bits", &prob->break_words));
  return cupid_petsc_halo_create(nw * prob->n_pd, nw * p->owned_first, nw * p->owned_last,
                                 nw * p->first_global, &prob->break_halo);
}

/* After this rank's decisions: the other ranks' decisions on the nodes it holds as halo,
 * their energies on its owned nodes added to *dissipated (collective). */
static cupid_status break_exchange(cupid_problem_state *prob, const double *u, double *dissipated) {
  const cupid_pd_grid_partition *p = &prob->part;
  const cupid_int nw = cupid_pd_operator_broken_words(prob->op);
  double *w = prob->break_words, more = 0.0, extra = 0.0;
  cupid_int added = 0;
  cupid_pd_operator_pack_broken(prob->op, p->owned_first, p->owned_last, w + nw * p->owned_first);
  CUPID_CALL(cupid_petsc_halo_update(prob->break_halo, w));
  CUPID_CALL(cupid_pd_operator_unpack_broken(prob->op, 0, p->owned_first, w, u, &prob->fracture,
                                             &added, &more));
  CUPID_CALL(cupid_pd_operator_unpack_broken(prob->op, p->owned_last, prob->n_pd,
                                             w + nw * p->owned_last, u, &prob->fracture, &added,
                                             &extra));
  *dissipated += more + extra;
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_fracture_setup(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  prob->first_break_step = -1;
  /* an adaptive zone that starts empty has no grid until its first conversion */
  if (!cupid_problem_has_damage(prob) || !prob->grid) return CUPID_SUCCESS;
  CUPID_CALL(cupid_calloc((size_t)prob->n_pd, sizeof *prob->damage, "damage", &prob->damage));
  if (prob->method->fracture_protect) {
    CUPID_CALL(cupid_calloc((size_t)prob->n_pd, 1, "protected nodes", &prob->protect));
    CUPID_CALL(prob->method->fracture_protect(prob, prob->protect));
  }
  CUPID_CALL(apply_precracks(prob));
  if (!prob->adaptive) CUPID_CALL(cupid_problem_fracture_check_protected(prob));
  const cupid_fracture *fr = &m->pd.fracture;
  if (!fr->has_fracture) return CUPID_SUCCESS;
  cupid_pd_fracture_options *o = &prob->fracture;
  o->criterion = fr->criterion == CUPID_FRACTURE_ENERGY ? CUPID_PD_BREAK_ENERGY : CUPID_PD_BREAK_STRETCH;
  if (fr->criterion == CUPID_FRACTURE_ENERGY) {
    /* critical bond energy density 4 G0 / (pi delta^4) (3D; fracture.md, after Foster 2011) */
    const double d = m->pd.horizon;
    o->critical_energy = 4.0 * fr->energy_release_rate / (3.14159265358979323846 * d * d * d * d);
  } else if (fr->has_critical_stretch) {
    o->critical_stretch = fr->critical_stretch;
  } else {
    CUPID_CALL(node_stretch(prob, fr->energy_release_rate));
    o->node_stretch = prob->node_stretch;
  }
  CUPID_CALL(no_fail_masks(prob));
  o->no_fail = prob->no_fail;
  o->protect = prob->protect;
  if (prob->slab) { /* each bond and energy counted by one rank: its lower node's owner */
    o->count_first = prob->part.owned_first;
    o->count_last = prob->part.owned_last;
  }
  /* the energy test, and static growth (whose `per_iteration: one` breaks one bond of the
   * whole grid): each bond decided by one rank, its bit sent to the others */
  if (prob->slab && (o->criterion == CUPID_PD_BREAK_ENERGY || m->analysis.type == CUPID_ANALYSIS_STATIC))
    CUPID_CALL(break_exchange_setup(prob));
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_max_ratio(const cupid_problem_state *prob, const double *u, double *r) {
  *r = 0.0;
  if (!prob->op) return CUPID_SUCCESS; /* an adaptive zone not grown yet: no bond */
  CUPID_CALL(cupid_pd_operator_max_ratio(prob->op, u, &prob->fracture, r));
  if (prob->slab) cupid_petsc_max_doubles(r, 1); /* each rank its owned bonds (owned_only) */
  return CUPID_SUCCESS;
}

/* `per_iteration: one` on a slab run: 1 on the rank that breaks the bond, the most critical of
 * the whole grid (the lowest rank among near-equals, CUPID_PD_TIE: it holds the lower nodes,
 * as the whole grid's scan takes the first of them); *top the whole grid's largest ratio. */
static cupid_status breaks_most_here(const cupid_problem_state *prob, const double *u, int *here,
                                     double *top) {
  double r = 0.0;
  CUPID_CALL(cupid_pd_operator_max_ratio(prob->op, u, &prob->fracture, &r));
  *top = r;
  cupid_petsc_max_doubles(top, 1);
  const int near = *top > 1.0 && r >= *top * (1.0 - CUPID_PD_TIE);
  *here = cupid_problem_lowest_rank(near) == cupid_petsc_rank();
  return CUPID_SUCCESS;
}

/* Where the crack started: the centroid of the nodes of the first broken bonds (over the
 * ranks of a slab run: each its owned nodes). */
static cupid_status first_break_place(cupid_problem_state *prob) {
  cupid_int *nodes = NULL;
  CUPID_CALL(cupid_malloc((size_t)prob->n_pd + 1, sizeof *nodes, "broken nodes", &nodes));
  const cupid_int n = cupid_pd_operator_nodes_broken(prob->op, nodes);
  const double *x = cupid_pd_grid_coords(prob->grid);
  double sum[4] = {0, 0, 0, 0};
  for (cupid_int k = 0; k < n; k++) {
    if (!cupid_problem_pd_owned(prob, nodes[k])) continue;
    for (int a = 0; a < 3; a++) sum[a] += x[3 * nodes[k] + a];
    sum[3] += 1.0;
  }
  cupid_free(&nodes);
  if (prob->slab) cupid_petsc_sum_doubles(sum, 4);
  for (int a = 0; a < 3; a++) prob->first_break_at[a] = sum[3] > 0 ? sum[a] / sum[3] : 0.0;
  return CUPID_SUCCESS;
}

cupid_int cupid_problem_fracture_nodes_broken(const cupid_problem_state *prob) {
  if (!prob->op) return 0;
  if (!prob->slab) return cupid_pd_operator_nodes_broken(prob->op, NULL);
  cupid_int *nodes = NULL, owned = 0;
  cupid_status st = cupid_malloc((size_t)prob->n_pd + 1, sizeof *nodes, "broken nodes", &nodes);
  const cupid_int n = st == CUPID_SUCCESS ? cupid_pd_operator_nodes_broken(prob->op, nodes) : 0;
  for (cupid_int k = 0; k < n; k++) owned += cupid_problem_pd_owned(prob, nodes[k]);
  cupid_free(&nodes);
  return cupid_problem_global_count(prob, owned);
}

cupid_status cupid_problem_fracture_step(cupid_problem_state *prob, cupid_int step, double t,
                                         const double *u, int only_most, cupid_int *n_broken,
                                         double *dissipated) {
  *dissipated = 0.0;
  cupid_int broken = 0;
  if (n_broken) *n_broken = 0;
  if (!prob->model->pd.fracture.has_fracture || !prob->op) return CUPID_SUCCESS;
  int here = 1;
  cupid_pd_fracture_options o = prob->fracture;
  if (prob->slab && only_most)
    CUPID_CALL(cupid_problem_slab_agree(breaks_most_here(prob, u, &here, &o.most_top)));
  cupid_status st = here ? cupid_pd_operator_break_bonds(prob->op, u, &o, only_most, &broken,
                                                         dissipated)
                         : CUPID_SUCCESS;
  CUPID_CALL(prob->slab ? cupid_problem_slab_agree(st) : st);
  if (prob->break_halo) CUPID_CALL(cupid_problem_slab_agree(break_exchange(prob, u, dissipated)));
  double total[2] = {(double)broken, *dissipated}; /* a slab's shares: summed over the ranks */
  if (prob->slab) cupid_petsc_sum_doubles(total, 2);
  broken = (cupid_int)total[0];
  if (n_broken) *n_broken = broken;
  if (broken == 0) return CUPID_SUCCESS;
  if (prob->first_break_step < 0) {
    prob->first_break_step = step;
    prob->first_break_t = t;
    CUPID_CALL(first_break_place(prob));
    const double *c = prob->first_break_at;
    cupid_problem_progress(prob, "fracture: the first bonds broke at step %lld (%s = %.4g): %lld, "
                           "at (%.4g, %.4g, %.4g)",
                           (long long)step,
                           prob->model->analysis.type == CUPID_ANALYSIS_STATIC ? "load factor" : "t",
                           t, (long long)broken, c[0], c[1], c[2]);
  }
  prob->broken_bonds += broken;
  prob->fracture_energy += total[1];
  if (prob->crack_copy)
    CUPID_CALL(cupid_pd_operator_copy_broken_mapped(prob->crack_copy, prob->op, prob->crack_map));
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_fracture_damage(cupid_problem_state *prob) {
  if (!prob->damage) return CUPID_SUCCESS;
  if (prob->op)
    CUPID_CALL(cupid_pd_operator_damage(prob->op, prob->damage, &prob->damaged_nodes,
                                        &prob->max_damage));
  if (prob->op && !prob->slab) return CUPID_SUCCESS;
  /* a slab (its owned nodes, over the ranks), or rank 0's gathered field after a slab run */
  double count = 0.0, top = 0.0;
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    if (!cupid_problem_pd_owned(prob, i)) continue;
    count += prob->damage[i] > 0.0;
    top = fmax(top, prob->damage[i]);
  }
  if (prob->slab) {
    cupid_petsc_sum_doubles(&count, 1);
    cupid_petsc_max_doubles(&top, 1);
  }
  prob->damaged_nodes = (cupid_int)count;
  prob->max_damage = top;
  return CUPID_SUCCESS;
}

void cupid_problem_fracture_print(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  printf("pre-cracks: %d, %lld bonds removed\n", m->pd.n_precracks, (long long)prob->precrack_bonds);
  if (!m->pd.fracture.has_fracture) return;
  const cupid_pd_fracture_options *o = &prob->fracture;
  if (o->criterion == CUPID_PD_BREAK_ENERGY)
    printf("fracture: critical bond energy %.6g (from G0 = %g)\n", o->critical_energy,
           m->pd.fracture.energy_release_rate);
  else if (prob->node_stretch) {
    printf("fracture: critical stretch %.6g (from G0 = %g, calibration %s; the first node's "
           "material)\n",
           prob->n_pd ? prob->node_stretch[0] : 0.0, m->pd.fracture.energy_release_rate,
           m->pd.fracture.calibration_grid ? "grid" : "continuum");
    if (prob->lattice_ratio > 0.0)
      printf("fracture: s0 continuum %.6g (the lattice's cut energy G_eff / G0 = %.4f), grid "
             "%.6g (G_eff / G0 = 1)%s\n",
             prob->s0_calibrations[0], lattice_energy_fraction(prob), prob->s0_calibrations[1],
             m->pd.surface_correction != CUPID_SURFACE_NONE
                 ? "; the bulk lattice's, before the surface correction's factors (which restore "
                   "the faces' share)"
                 : "");
  }
  else
    printf("fracture: critical stretch %.6g\n", o->critical_stretch);
}

void cupid_problem_fracture_json(cupid_json js, const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  if (!cupid_problem_has_damage(prob)) return;
  const cupid_fracture *fr = &m->pd.fracture;
  cupid_json_begin_object(js, "fracture");
  cupid_json_integer(js, "precracks", m->pd.n_precracks);
  cupid_json_integer(js, "precrack_bonds_removed", prob->precrack_bonds);
  if (fr->has_fracture) {
    cupid_json_string(js, "criterion", fr->criterion == CUPID_FRACTURE_ENERGY ? "energy" : "stretch");
    if (prob->fracture.criterion == CUPID_PD_BREAK_ENERGY)
      cupid_json_number(js, "critical_bond_energy", prob->fracture.critical_energy);
    else if (!prob->node_stretch)
      cupid_json_number(js, "critical_stretch", prob->fracture.critical_stretch);
    if (fr->has_energy_release_rate) cupid_json_number(js, "energy_release_rate", fr->energy_release_rate);
    if (prob->node_stretch && prob->n_pd > 0) { /* the first node's: one material is the usual */
      cupid_json_number(js, "critical_stretch_from_G0", prob->node_stretch[0]);
      cupid_json_string(js, "calibration", fr->calibration_grid ? "grid" : "continuum");
      if (prob->lattice_ratio > 0.0) { /* bond-based: both calibrations and the cut energy */
        cupid_json_number(js, "critical_stretch_continuum", prob->s0_calibrations[0]);
        cupid_json_number(js, "critical_stretch_grid", prob->s0_calibrations[1]);
        cupid_json_number(js, "g_eff_over_g0_continuum", lattice_energy_fraction(prob));
      }
    }
    cupid_json_integer(js, "broken_bonds", prob->broken_bonds);
    if (prob->first_break_load > 0) cupid_json_number(js, "first_break_load_factor", prob->first_break_load);
    if (prob->first_break_step >= 0) {
      cupid_json_integer(js, "first_break_step", prob->first_break_step);
      if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC)
        cupid_json_number(js, "first_break_t", prob->first_break_t);
      cupid_json_begin_array(js, "first_break_at");
      for (int a = 0; a < 3; a++) cupid_json_number(js, NULL, prob->first_break_at[a]);
      cupid_json_end_array(js);
    }
    cupid_json_number(js, "dissipated_energy", prob->fracture_energy);
    if (prob->growth.peak) { /* static growth: the envelope's peak of each constraint */
      cupid_json_begin_array(js, "peak_reactions");
      for (int k = 0; k < m->n_constraints; k++) {
        const double *p = prob->growth.peak + 6 * k;
        cupid_json_begin_object(js, NULL);
        cupid_json_integer(js, "constraint", k);
        cupid_json_number(js, "load_factor", p[1]);
        cupid_json_integer(js, "step", (cupid_int)p[2]);
        cupid_json_begin_array(js, "reaction");
        for (int a = 0; a < 3; a++) cupid_json_number(js, NULL, p[3 + a]);
        cupid_json_end_array(js);
        cupid_json_end_object(js);
      }
      cupid_json_end_array(js);
    }
    if (prob->growth.held) { /* growth.c, held_forces */
      cupid_json_integer(js, "held_nodes", prob->growth.held_count);
      cupid_json_number(js, "held_share", prob->growth.held_share);
    }
    if (prob->growth.tied_nodes) { /* growth.c, tie_mechanisms */
      cupid_json_integer(js, "tied_nodes", prob->growth.tied_nodes);
      cupid_json_integer(js, "tied_singular", prob->growth.tied_singular);
      cupid_json_number(js, "tie_stiffness", prob->growth.tie_stiffness);
      cupid_json_number(js, "tie_share", prob->growth.tie_share);
    }
    if (prob->growth.collapse_step) { /* growth.c, check_collapse */
      cupid_json_begin_object(js, "collapse");
      cupid_json_integer(js, "step", prob->growth.collapse_step);
      cupid_json_number(js, "load_factor", prob->growth.collapse_load);
      cupid_json_number(js, "held_share", prob->growth.collapse_share);
      cupid_json_integer(js, "held_nodes", prob->growth.collapse_held);
      cupid_json_string(js, "cause", prob->growth.collapse_cause);
      cupid_json_end_object(js);
    }
    if (prob->growth.stopped_step) {
      cupid_json_integer(js, "stopped_step", prob->growth.stopped_step);
      cupid_json_string(js, "stopped", prob->growth.stopped);
    }
    if (prob->growth.resolve) { /* static growth: how the re-solves went (growth.c) */
      cupid_json_begin_object(js, "solves");
      cupid_json_string(js, "resolve", prob->growth.resolve);
      cupid_json_integer(js, "solves", prob->growth.solves);
      cupid_json_integer(js, "factorisations", prob->growth.factorisations);
      cupid_json_integer(js, "failed_factorisations", prob->growth.failed_factorisations);
      cupid_json_integer(js, "cg_solves", prob->growth.cg_solves);
      cupid_json_integer(js, "cg_iterations", prob->growth.cg_iterations);
      cupid_json_number(js, "factorisation_s", prob->growth.factor_s);
      cupid_json_number(js, "cg_s", prob->growth.cg_s);
      cupid_json_integer(js, "downdates", prob->growth.downdates);
      cupid_json_integer(js, "downdate_columns", prob->growth.downdate_columns);
      cupid_json_number(js, "downdate_s", prob->growth.downdate_s);
      cupid_json_integer(js, "held_rows", prob->growth.held_rows);
      cupid_json_end_object(js);
    }
  }
  cupid_json_integer(js, "damaged_nodes", prob->damaged_nodes);
  cupid_json_number(js, "max_damage", prob->max_damage);
  cupid_json_end_object(js);
}
