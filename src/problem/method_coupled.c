/* What the coupling methods share (method.h): which table a model gets, the beam giving way
 * inside the PD regions, the split of constraints and loads between the beam and the grid,
 * the coupling's options, the equilibrium figure, the matrix-free Krylov solve and the plain
 * (uncoupled) mass. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "method.h"

/* The one place that maps a model's coupling method to its table. */
const cupid_method_ops *cupid_problem_method_of(const cupid_model_t *model) {
  if (!(model->has_beam && model->has_peridynamics)) return &cupid_method_none;
  switch (model->coupling.method) {
  case CUPID_COUPLING_LAGRANGE: return &cupid_method_lagrange;
  case CUPID_COUPLING_ARLEQUIN: return &cupid_method_arlequin;
  default: return &cupid_method_fictitious;
  }
}

cupid_status cupid_method_deactivate_regions(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  for (int r = 0; r < m->pd.n_regions; r++) {
    if (cupid_coupling_deactivate(prob->beam, 1, &m->pd.regions[r].box) == CUPID_SUCCESS) continue;
    /* The library names the region "PD region 0" (it saw one box); the mark names it here. */
    char msg[1024];
    const char *e = cupid_error_message(), *tail = strstr(e, "PD region 0");
    if (tail) {
      tail += strlen("PD region 0");
      if (*tail == ':') tail++;
      while (*tail == ' ') tail++;
    }
    snprintf(msg, sizeof msg, "%s", tail ? tail : e);
    return cupid_model_error(m, &m->pd.regions[r].mark, "%s", msg);
  }
  return CUPID_SUCCESS;
}

/* FE nodes where the beam gave way carry no stiffness: hold them at zero. */
static cupid_status fix_inactive_fe_nodes(cupid_problem_state *prob) {
  for (cupid_int n = 0; n < prob->fe_info.n_fe_nodes; n++) {
    if (cupid_cuf_node_used(prob->beam, (int)(n % prob->fe_info.M), n / prob->fe_info.M)) continue;
    for (int c = 0; c < 3; c++)
      CUPID_CALL(cupid_dirichlet_fix(prob->bc, prob->fe_offset + 3 * n + c, 0.0));
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_method_split_constraints(cupid_problem_state *prob, const cupid_split_rules *r) {
  const cupid_model_t *m = prob->model;
  cupid_status st = CUPID_SUCCESS;
  cupid_constraint *pd = NULL;
  int npd = 0;
  CUPID_CALL(cupid_calloc((size_t)m->n_constraints + 1, sizeof *pd, "PD constraints", &pd));
  for (int k = 0; k < m->n_constraints; k++) {
    const cupid_constraint *c = &m->constraints[k];
    int on_fe, on_pd;
    if (c->kind == CUPID_CONSTRAINT_CLAMP) {
      on_fe = cupid_problem_fe_node_at(prob, c->plane_y);
      on_pd = r && r->clamp_on_pd ? r->clamp_on_pd(prob, c) : !on_fe;
    } else {
      on_fe = cupid_problem_fe_node_in_box(prob, &c->box);
      on_pd = cupid_problem_pd_node_in_box(prob, &c->box);
    }
    if (!on_fe && !on_pd) {
      st = cupid_model_error(m, &c->mark,
                             "the constraint touches neither the beam (outside the PD regions) "
                             "nor a PD node");
      goto cleanup;
    }
    if (on_fe) CUPID_TRY(cupid_cuf_constraint_apply(prob->beam, m, c, prob->bc));
    if (on_fe)
      CUPID_TRY(cupid_problem_check_finite(prob, prob->bc->value, &c->mark, "the prescribed displacement"));
    if (on_pd) pd[npd++] = *c;
  }
  CUPID_TRY(cupid_problem_pd_constraints(prob, pd, npd)); /* also x, z of a 1D grid */
  CUPID_TRY(fix_inactive_fe_nodes(prob));
cleanup:
  cupid_free(&pd);
  return st;
}

cupid_status cupid_method_split_loads(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  cupid_status st = CUPID_SUCCESS;
  cupid_load *pd = NULL;
  int npd = 0;
  CUPID_CALL(cupid_calloc((size_t)m->n_loads + 1, sizeof *pd, "PD loads", &pd));
  for (int k = 0; k < m->n_loads; k++) {
    const cupid_load *l = &m->loads[k];
    int on_fe = 0, on_pd = 0;
    switch (l->kind) {
    case CUPID_LOAD_TRACTION: on_fe = cupid_problem_fe_node_at(prob, l->plane_y); on_pd = !on_fe; break;
    case CUPID_LOAD_POINT:
      on_fe = cupid_cuf_contains(prob->beam, l->at[0], l->at[1], l->at[2]);
      on_pd = !on_fe;
      break;
    case CUPID_LOAD_BODY:
      on_fe = cupid_problem_fe_node_in_box(prob, &l->box);
      on_pd = cupid_problem_pd_node_in_box(prob, &l->box);
      break;
    }
    if (on_fe) CUPID_TRY(cupid_cuf_load_add(prob->beam, m, l, prob->f_ext));
    if (on_fe) CUPID_TRY(cupid_problem_check_finite(prob, prob->f_ext, &l->mark, "the load"));
    if (on_pd) pd[npd++] = *l;
  }
  CUPID_TRY(cupid_problem_pd_loads(prob, pd, npd, prob->f_ext));
cleanup:
  cupid_free(&pd);
  return st;
}

cupid_status cupid_method_coupling_options(const cupid_problem_state *prob,
                                           cupid_coupling_options *co, cupid_box **boxes,
                                           int **mats) {
  const cupid_model_t *m = prob->model;
  const int nr = m->pd.n_regions;
  CUPID_CALL(cupid_calloc((size_t)nr, sizeof **boxes, "region boxes", boxes));
  CUPID_CALL(cupid_calloc((size_t)nr, sizeof **mats, "region materials", mats));
  for (int r = 0; r < nr; r++) {
    (*boxes)[r] = m->pd.regions[r].box;
    (*mats)[r] = m->pd.regions[r].material;
  }
  *co = (cupid_coupling_options){.beam_def = &m->beam,
                                 .materials = m->materials,
                                 .n_materials = m->n_materials,
                                 .n_regions = nr,
                                 .regions = *boxes,
                                 .region_materials = *mats,
                                 .spacing = m->pd.spacing,
                                 .pd = prob->pd_options,
                                 .fictitious_fe = (cupid_fictitious_fe)m->coupling.fictitious_fe,
                                 .fictitious_length = m->coupling.fictitious_length,
                                 .pd_operator = prob->op}; /* its pre-cracks and breaks */
  return CUPID_SUCCESS;
}

/* |R + P| / |P| along y (the axis; x, z printed too): the fictitious-node method does not
 * conserve momentum (docs/coupling.md), so the imbalance is a figure of merit of the run. */
cupid_status cupid_method_print_equilibrium(const cupid_problem_state *prob) {
  if (prob->quiet) return CUPID_SUCCESS;
  double load[3], reac[3];
  CUPID_CALL(cupid_problem_force_sums((cupid_problem_state *)prob, load, reac)); /* reads only */
  double pn = sqrt(load[0] * load[0] + load[1] * load[1] + load[2] * load[2]);
  double in = sqrt((load[0] + reac[0]) * (load[0] + reac[0]) + (load[1] + reac[1]) * (load[1] + reac[1]) +
                   (load[2] + reac[2]) * (load[2] + reac[2]));
  cupid_problem_progress(prob, "equilibrium: load (%.6g, %.6g, %.6g), reaction (%.6g, %.6g, %.6g), "
                         "|R + P| / |P| = %.3e", load[0], load[1], load[2], reac[0], reac[1],
                         reac[2], pn > 0 ? in / pn : in);
  return CUPID_SUCCESS;
}

/* Record a matrix-free Krylov solve: prob->solve and the factorisation / solve phases. */
static void record_krylov(cupid_problem_state *prob, const cupid_solve_info *si) {
  prob->solve = *si;
  if (prob->slab) { /* the owned free DOFs of every slab, and the FE ones once */
    cupid_int own = 0;
    for (cupid_int d = 0; d < prob->ndof; d++)
      own += !prob->bc->fixed[d] && (d >= prob->fe_offset ? cupid_petsc_rank() == 0
                                                          : cupid_problem_pd_owned(prob, d / 3));
    prob->solve.n = cupid_problem_global_count(prob, own);
  }
  cupid_problem_record_solve(prob);
}

static cupid_status linear_apply(void *ctx, const double *x, double *y) {
  return cupid_krylov_apply(ctx, x, y);
}

cupid_status cupid_method_krylov_solve(cupid_problem_state *prob, const cupid_linear_operator *L,
                                       cupid_csr *P, cupid_method_operator *owner) {
  /* MUMPS: PETSc's UMFPACK interface has 32-bit indices and ran out of them at 10^5 PD
   * nodes (bench/README_coupled.md); -pc_factor_mat_solver_type overrides it. */
  cupid_krylov_options ko = {.factor_package = "mumps"};
  cupid_solve_info ki = {0};
  CUPID_CALL(cupid_problem_patch_test(prob, linear_apply, (void *)L)); /* collective */
  CUPID_CHECK(prob->engine->solve_operator, CUPID_ERR_UNSUPPORTED,
              "solver %s has no matrix-free solve", prob->engine->name);
  cupid_status st = prob->engine->solve_operator(L, *P, prob->bc, prob->f_ext, prob->u, &ko, &ki);
  record_krylov(prob, &ki);
  CUPID_CALL(st);
  prob->solved = 1;
  CUPID_CALL(cupid_krylov_apply(L, prob->u, prob->f_int)); /* a slab: owned and FE rows */
  cupid_problem_progress(prob, "solve: %s + %s, %lld equations, %d iterations, residual %.2e",
                         ki.ksp_type, ki.pc_type, (long long)prob->solve.n, ki.iterations,
                         ki.residual);
  if (!prob->slab) return CUPID_SUCCESS;
  cupid_csr_destroy(P); /* rank 0 gathers the slabs into the whole model; the others stop */
  if (owner->destroy) owner->destroy(&owner->ctx);
  return cupid_problem_slab_collect(prob);
}

cupid_status cupid_method_build_coupling(cupid_problem_state *prob,
                                         cupid_status (*create)(const cupid_cuf_beam,
                                                                const cupid_pd_grid,
                                                                const cupid_coupling_options *,
                                                                cupid_coupling_h *, cupid_csr *),
                                         cupid_coupling_info *info) {
  double t0 = cupid_wtime();
  cupid_status st = CUPID_SUCCESS;
  cupid_box *boxes = NULL;
  int *mats = NULL;
  cupid_coupling_options co;
  CUPID_TRY(cupid_method_coupling_options(prob, &co, &boxes, &mats));
  CUPID_TRY(create(prob->beam, prob->grid, &co, &prob->coupling, &prob->K));
  cupid_coupling_get_info(prob->coupling, info);
  cupid_problem_phase_end(prob, CUPID_PHASE_COUPLING, t0);
cleanup:
  cupid_free(&boxes);
  cupid_free(&mats);
  return st;
}

/* ---------------------------------------------------------------------------- the mass */

/* Lagrange: the tied PD nodes' rho V leaves the PD diagonal and goes to the beam DOFs through
 * the tie (T^T M T, cupid_coupling_lagrange_mass()), so that the eliminated system's mass is
 * consistent with its stiffness T^T K T. */
static cupid_status move_tied_mass(cupid_problem_state *prob, cupid_csr M, double *m_lumped) {
  cupid_status st = CUPID_SUCCESS;
  double *pd_mass = NULL;
  const cupid_int *tied;
  cupid_int nt;
  CUPID_TRY(cupid_malloc((size_t)prob->n_pd + 1, sizeof *pd_mass, "PD masses", &pd_mass));
  for (cupid_int i = 0; i < prob->n_pd; i++) pd_mass[i] = m_lumped[3 * i];
  cupid_coupling_tied(prob->coupling, &tied, &nt);
  for (cupid_int t = 0; t < nt; t++)
    for (int c = 0; c < 3; c++) m_lumped[3 * tied[t] + c] = 0.0;
  CUPID_TRY(cupid_coupling_lagrange_mass(prob->coupling, pd_mass, M, M ? NULL : m_lumped));
cleanup:
  cupid_free(&pd_mass);
  return st;
}

/* The PD diagonal (rho V per component) into M's diagonal blocks. */
static cupid_status add_pd_diagonal(const cupid_problem_state *prob, cupid_csr M, const double *m_pd) {
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    double *blk = cupid_csr_find(M, i, i);
    CUPID_CHECK(blk, CUPID_ERR_INTERNAL, "the stiffness lacks the diagonal block of PD node %lld",
                (long long)i);
    for (int c = 0; c < 3; c++) blk[4 * c] += m_pd[3 * i + c];
  }
  return CUPID_SUCCESS;
}

/* PD nodal mass rho V (every component), FE consistent matrix or HRZ diagonal. With both PD
 * and FE (a coupled layout) and a consistent FE mass, M takes K's global pattern: the beam's
 * mass at its DOF offset and rho V on the PD diagonal. */
cupid_status cupid_method_plain_mass(cupid_problem_state *prob, int move_tied, cupid_csr *M,
                                     double **m_lumped) {
  const cupid_model_t *m = prob->model;
  int lumped = m->analysis.dynamic.lumped_mass || !prob->beam;
  CUPID_CALL(cupid_calloc((size_t)prob->ndof, sizeof(double), "lumped mass", m_lumped));
  if (prob->grid) {
    const int *mat = cupid_pd_grid_materials(prob->grid);
    for (cupid_int i = 0; i < prob->n_pd; i++) {
      const double vol = cupid_pd_grid_node_volume(prob->grid, i); /* cut cells: its part */
      for (int c = 0; c < 3; c++) (*m_lumped)[3 * i + c] = m->materials[mat[i]].density * vol;
    }
  }
  if (lumped) {
    if (prob->beam) CUPID_CALL(cupid_cuf_mass_lumped(prob->beam, *m_lumped));
    if (move_tied) CUPID_CALL(move_tied_mass(prob, NULL, *m_lumped));
    return CUPID_SUCCESS;
  }
  if (!prob->grid) {
    CUPID_CALL(cupid_cuf_mass_assemble(prob->beam, M));
  } else {
    CUPID_CALL(cupid_csr_duplicate(prob->K, M));
    cupid_csr_zero(*M);
    CUPID_CALL(cupid_cuf_mass_add(prob->beam, *M));
    /* before the PD diagonal goes in: the tied entries are zeroed */
    if (move_tied) CUPID_CALL(move_tied_mass(prob, *M, *m_lumped));
    CUPID_CALL(add_pd_diagonal(prob, *M, *m_lumped));
  }
  cupid_free(m_lumped);
  return CUPID_SUCCESS;
}
