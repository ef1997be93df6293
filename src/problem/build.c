/* The set-up's building stages (problem.c runs them in order; cupid_problem_setup): the PD
 * grid and its operator, the fields, the constraints and loads through the method; and their
 * rebuild when an adaptive zone grows (adaptive.c). Below the stages that call them, so that
 * problem.c and adaptive.c share them without calling each other (docs/architecture.md). */
#include <string.h>

#include "method.h"

/* PD regions need isotropic materials (the LPS and bond-based models take E and nu). */
static cupid_status check_isotropic(const cupid_model_t *m) {
  for (int r = 0; r < m->pd.n_regions; r++) {
    const cupid_material *mat = &m->materials[m->pd.regions[r].material];
    if (mat->orthotropic)
      return cupid_model_error(m, &m->pd.regions[r].mark,
                               "material '%s' is orthotropic; peridynamics needs an isotropic "
                               "material {E, nu}",
                               mat->name);
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_pd_options(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  CUPID_CALL(check_isotropic(m));
  CUPID_CALL(cupid_calloc((size_t)m->n_materials, sizeof *prob->pd_materials, "PD materials",
                          &prob->pd_materials));
  for (int i = 0; i < m->n_materials; i++)
    prob->pd_materials[i] = (cupid_pd_material){.E = m->materials[i].E, .nu = m->materials[i].nu};
  prob->pd_options = (cupid_pd_operator_options){.horizon = m->pd.horizon,
                                                 .model = m->pd.model,
                                                 .influence = m->pd.influence,
                                                 .partial_volume = m->pd.partial_volume,
                                                 .surface_correction = m->pd.surface_correction,
                                                 .materials = prob->pd_materials,
                                                 .n_materials = m->n_materials};
  return CUPID_SUCCESS;
}

/* The body's volume as the nodes carry it (cut cells: their parts), over the owned nodes of
 * every rank (collective on slabs). */
static void pd_body_volume(cupid_problem_state *prob) {
  const double *phi = cupid_pd_grid_volume_fractions(prob->grid);
  double v[2] = {0.0, 0.0};
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    if (!cupid_problem_pd_owned(prob, i)) continue;
    v[0] += cupid_pd_grid_node_volume(prob->grid, i);
    v[1] += phi && phi[i] != 1.0;
  }
  if (prob->slab) cupid_petsc_sum_doubles(v, 2);
  prob->pd_volume = v[0];
  prob->n_cut_nodes = (cupid_int)v[1];
}

cupid_status cupid_problem_build_pd(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  double t0 = cupid_wtime();
  CUPID_CALL(cupid_problem_pd_options(prob));
  if (prob->slab) { /* this rank's z layers and the halo its rows read (slab.c) */
    int halo = 0;
    CUPID_CALL(cupid_pd_operator_halo_layers(&prob->pd_options, m->pd.spacing, &halo));
    CUPID_CALL(cupid_pd_grid_create_part_from_model(m, cupid_petsc_size(), cupid_petsc_rank(),
                                                    halo, &prob->grid));
  } else {
    CUPID_CALL(cupid_pd_grid_create_from_model(m, &prob->grid));
  }
  cupid_pd_grid_get_partition(prob->grid, &prob->part);
  prob->n_pd = cupid_pd_grid_num_nodes(prob->grid);
  CUPID_CALL(cupid_pd_operator_create(prob->grid, &prob->pd_options, &prob->op));
  prob->n_bonds = cupid_pd_operator_num_bonds(prob->op);
  pd_body_volume(prob);
  cupid_problem_phase_end(prob, CUPID_PHASE_GRID, t0);
  if (prob->slab)
    cupid_problem_progress(prob, "grid: %lld PD nodes in %d z slabs; rank 0 holds %lld (%lld owned)",
                           (long long)prob->part.global_nodes, prob->part.parts,
                           (long long)prob->n_pd,
                           (long long)(prob->part.owned_last - prob->part.owned_first));
  else
    cupid_problem_progress(prob, "grid: %lld PD nodes, %lld bonds", (long long)prob->n_pd,
                           (long long)prob->n_bonds);
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_allocate_fields(cupid_problem_state *prob) {
  size_t n = (size_t)prob->ndof;
  CUPID_CALL(cupid_calloc(n, sizeof(double), "displacements", &prob->u));
  CUPID_CALL(cupid_calloc(n, sizeof(double), "applied loads", &prob->f_ext));
  CUPID_CALL(cupid_calloc(n, sizeof(double), "internal forces", &prob->f_int));
  CUPID_CALL(cupid_dirichlet_create(prob->ndof, &prob->bc));
  return CUPID_SUCCESS;
}

/* A slab run agrees on every rank's status before the next collective call (slab.c). */
static cupid_status agreed(const cupid_problem_state *prob, cupid_status st) {
  return prob->slab ? cupid_problem_slab_agree(st) : st;
}

/* Constraints (finalized) and loads of a static or dynamic analysis, through the method. */
cupid_status cupid_problem_apply_conditions(cupid_problem_state *prob) {
  CUPID_CALL(prob->method->constraints(prob));
  CUPID_CALL(cupid_dirichlet_finalize(prob->bc));
  return agreed(prob, prob->method->loads(prob));
}

/* An adaptive zone changed (adaptive.c): what was built from the model's PD regions is built
 * again, by the stages of this file (grid and operator, beam, the method's layout, pre-cracks and the
 * breaking rule, fields, constraints and loads at load factor 1). The caller took what it
 * keeps of the old (grid, operator, beam, u: set to NULL here). The run's counters, outputs
 * and checkpoints stay. */
void cupid_problem_free_layout(cupid_problem_state *prob) {
  if (prob->method->free_state) prob->method->free_state(prob);
  cupid_coupling_destroy(&prob->coupling);
  cupid_pd_operator_destroy(&prob->op);
  cupid_pd_grid_destroy(&prob->grid);
  cupid_cuf_beam_destroy(&prob->beam);
  cupid_csr_destroy(&prob->K);
  cupid_dirichlet_destroy(&prob->bc);
  double **vectors[] = {&prob->u, &prob->f_ext, &prob->f_int, &prob->pd_stress, &prob->beam_points,
                       &prob->beam_u, &prob->node_stretch, &prob->damage};
  for (size_t k = 0; k < sizeof vectors / sizeof *vectors; k++) cupid_free(vectors[k]);
  cupid_free(&prob->pd_materials);
  cupid_free(&prob->arlequin_regions);
  cupid_free(&prob->region_boxes);
  cupid_free(&prob->traction_scales);
  cupid_free(&prob->region_materials);
  cupid_free(&prob->protect);
  cupid_free(&prob->no_fail);
}

cupid_status cupid_problem_rebuild(cupid_problem_state *prob, int fields) {
  cupid_problem_free_layout(prob);
  /* a zone that started empty ran as the beam alone (cupid_method_none) until now */
  prob->method = cupid_problem_method_of(prob->model);
  CUPID_CALL(prob->method->check(prob));
  prob->n_arlequin_regions = prob->n_traction_scales = 0;
  prob->n_beam_points = 0;
  prob->precrack_bonds = 0;
  prob->fracture = (cupid_pd_fracture_options){0};
  const cupid_int first_break = prob->first_break_step;
  const int quiet = prob->quiet;
  prob->quiet = 1; /* the conversion says what changed */
  cupid_status st = cupid_problem_build_pd(prob);
  if (st == CUPID_SUCCESS) st = cupid_problem_fe_build(prob);
  if (st == CUPID_SUCCESS && prob->method->prepare) st = prob->method->prepare(prob);
  if (st == CUPID_SUCCESS) st = cupid_problem_fracture_setup(prob);
  prob->first_break_step = first_break;
  if (st == CUPID_SUCCESS && fields) {
    prob->fe_offset = 3 * prob->n_pd;
    prob->ndof = prob->fe_offset + prob->n_fe_dofs;
    st = cupid_problem_check_points(prob);
    if (st == CUPID_SUCCESS) st = cupid_problem_allocate_fields(prob);
    if (st == CUPID_SUCCESS) st = cupid_problem_apply_conditions(prob);
  }
  prob->quiet = quiet;
  return st;
}
