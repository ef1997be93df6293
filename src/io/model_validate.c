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
  if (m->analysis.type == CUPID_ANALYSIS_DYNAMIC) CUPID_CALL(check_dynamic_densities(rd));
  return CUPID_SUCCESS;
}
