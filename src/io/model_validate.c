/* Model reader, part 3: checks across sections, run once every section has been read. */
#include <string.h>

#include "io/model_internal.h"

/* A dynamic analysis builds mass matrices: every material in use needs a density. */
static cupid_status check_density(const model_reader *rd, int material, const char *user) {
  const cupid_model_t *m = rd->model;
  if (material < 0 || m->materials[material].has_density) return CUPID_SUCCESS;
  return cupid_model_error(m, &m->materials[material].mark,
                           "needs a density for a dynamic analysis (it is used by %s)", user);
}

static cupid_status check_dynamic_densities(const model_reader *rd) {
  const cupid_model_t *m = rd->model;
  if (m->has_beam) {
    const cupid_beam *b = &m->beam;
    CUPID_CALL(check_density(rd, b->material, "beam"));
    for (int i = 0; i < b->n_components; i++)
      CUPID_CALL(check_density(rd, b->components[i].material, b->components[i].mark.key));
    for (int i = 0; i < b->n_section_elements; i++)
      CUPID_CALL(check_density(rd, b->section_element_material[i], "beam.section.elements"));
  }
  if (m->has_peridynamics)
    for (int i = 0; i < m->pd.n_regions; i++)
      CUPID_CALL(check_density(rd, m->pd.regions[i].material, m->pd.regions[i].mark.key));
  return CUPID_SUCCESS;
}

/* t is the time of a dynamic analysis. A static one (load steps or not) and an evaluation have
 * no time: they ramp every load and prescribed value by the load factor themselves, and a
 * value in t was silently evaluated at t = 0 (issue 33): refused, with the value and the way. */
static cupid_status check_no_time(const cupid_model_t *m, const cupid_mark *mark,
                                  const cupid_value v[3]) {
  static const char *const type[] = {"static", "dynamic", "evaluate"};
  for (int c = 0; c < 3; c++) {
    if (v[c].kind != CUPID_VALUE_EXPR || !cupid_expr_uses(v[c].expr, 3)) continue;
    const int a = m->analysis.type;
    return cupid_model_error(
        m, mark,
        "value[%d] \"%s\" uses t, the time of a dynamic analysis; analysis type: %s has no time "
        "(%s), or use type: dynamic",
        c, cupid_expr_text(v[c].expr), a >= 0 && a < 3 ? type[a] : "?",
        a == CUPID_ANALYSIS_EVALUATE ? "it evaluates one field: give it without t"
                                     : "its load steps scale every load and prescribed value "
                                       "by the load factor, k / steps at step k: give the value "
                                       "at load factor 1 without t");
  }
  return CUPID_SUCCESS;
}

/* peridynamics.adaptive grows the PD zone into the beam: it needs one, and `within` must
 * share a length of the beam's axis (else the zone could never grow). */
static cupid_status check_adaptive(const cupid_model_t *m) {
  const cupid_adaptive *a = &m->pd.adaptive;
  if (!m->has_peridynamics || !a->has_adaptive) return CUPID_SUCCESS;
  if (!m->has_beam)
    return cupid_model_error(m, &a->mark,
                             "needs a beam: the PD zone grows by turning beam elements into "
                             "PD (a PD-only model is PD everywhere already)");
  const cupid_coupling *c = &m->coupling;
  if (c->has_arlequin && m->pd.n_regions == 0 && c->n_overlaps > 0)
    return cupid_model_error(m, &c->overlap_marks[0],
                             "with peridynamics.regions: [] the zone starts empty and its "
                             "overlaps span peridynamics.adaptive.overlap horizons each: give "
                             "overlap: []");
  if (a->has_overlap && m->pd.n_regions > 0)
    return cupid_model_error(m, &a->overlap_mark,
                             "is the overlap width of a zone that starts empty (regions: []); "
                             "a zone that starts with regions keeps the widths of "
                             "coupling.arlequin.overlap");
  const double y0 = m->beam.axis_y[0], y1 = m->beam.axis_y[m->beam.n_axis - 1];
  if (a->has_within && a->within.has[1] && (a->within.hi[1] <= y0 || a->within.lo[1] >= y1))
    return cupid_model_error(m, &a->within_mark,
                             "the box y in [%g, %g] lies outside the beam (y in [%g, %g]): the "
                             "zone could never grow",
                             a->within.lo[1], a->within.hi[1], y0, y1);
  return CUPID_SUCCESS;
}

cupid_status mr_validate(model_reader *rd, const mr_map *top) {
  const cupid_model_t *m = rd->model;
  if (!m->has_beam && !m->has_peridynamics)
    return mr_error(rd, top->node, "",
                    "a model needs a beam: section, a peridynamics: section, or both");
  if (m->has_beam && m->has_peridynamics && !m->has_coupling)
    return mr_error(rd, mr_get(top, "peridynamics"), "coupling",
                    "required when the model has both beam and peridynamics; add coupling: "
                    "{method: fictitious | lagrange | arlequin}");
  if (m->has_coupling && !(m->has_beam && m->has_peridynamics))
    return mr_error(rd, mr_get(top, "coupling"), "coupling",
                    "only meaningful when the model has both beam and peridynamics");
  if (m->has_coupling && m->coupling.method != CUPID_COUPLING_ARLEQUIN) {
    /* fictitious nodes and Lagrange multipliers build their interfaces on box regions; the
     * Arlequin method ties node by node and takes a shape's bounding box as its region */
    const cupid_peridynamics *pd = &m->pd;
    for (int r = 0; r < pd->n_regions; r++)
      if (pd->regions[r].shape.kind != CUPID_SHAPE_BOX)
        return cupid_model_error(m, &pd->regions[r].mark,
                                 "cylinder, sphere and geometry regions need coupling.method: "
                                 "arlequin with a beam: the fictitious-node and Lagrange couplings "
                                 "build their interfaces on box regions");
    if (pd->n_holes > 0)
      return cupid_model_error(m, &pd->holes[0].mark,
                               "holes need coupling.method: arlequin with a beam: the "
                               "fictitious-node and Lagrange couplings build their interfaces on "
                               "whole box regions");
  }
  CUPID_CALL(check_adaptive(m));
  if (m->has_coupling && m->coupling.has_arlequin && m->coupling.n_overlaps == 0 &&
      !(m->pd.adaptive.has_adaptive && m->pd.n_regions == 0))
    return cupid_model_error(m, &m->coupling.overlap_list_mark,
                             "lists no slab; give 1 to %d (one per interface face of the PD "
                             "regions; an empty list is for an adaptive zone that starts empty, "
                             "peridynamics.regions: [])",
                             CUPID_MAX_OVERLAPS);
  const cupid_fracture *f = &m->pd.fracture;
  if (m->analysis.type != CUPID_ANALYSIS_STATIC && f->per_iteration_mark.line > 0)
    return cupid_model_error(m, &f->per_iteration_mark,
                             "is only used with type: static (the re-solves of a load step); "
                             "explicit dynamics breaks every bond over its limit at each time "
                             "step");
  if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC) return check_dynamic_densities(rd);
  for (int k = 0; k < m->n_loads; k++)
    CUPID_CALL(check_no_time(m, &m->loads[k].mark, m->loads[k].value));
  if (m->analysis.type == CUPID_ANALYSIS_EVALUATE) /* the imposed field too */
    CUPID_CALL(check_no_time(m, &m->analysis.mark, m->analysis.field));
  for (int k = 0; k < m->n_constraints; k++)
    if (m->constraints[k].kind == CUPID_CONSTRAINT_DISPLACEMENT)
      CUPID_CALL(check_no_time(m, &m->constraints[k].mark, m->constraints[k].value));
  return CUPID_SUCCESS;
}
