/* Unit tests of the model reader on valid models (tests/models/good/): every parsed field,
 * the defaults, the marks, and the helpers declared in model.h. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"

/* Parsed numbers are exact decimal conversions; 0 tolerance unless computed. */
static cupid_model read_good(const char *name) {
  char rel[256];
  snprintf(rel, sizeof rel, "tests/models/good/%s", name);
  cupid_model m = NULL;
  CUPID_ASSERT_OK(cupid_model_read(cupid_test_source_path(rel), &m));
  assert_non_null(m);
  return m;
}

static void assert_mark(const cupid_mark *mark, int line, int column, const char *key) {
  if (mark->line != line || mark->column != column || strcmp(mark->key, key))
    fail_msg("mark %d:%d '%s', expected %d:%d '%s'", mark->line, mark->column, mark->key, line,
             column, key);
}

static double value_at(const cupid_value *v, double x, double y, double z) {
  return cupid_value_eval(v, x, y, z, 0, 0);
}

static void test_bar(void **state) {
  (void)state;
  cupid_model m = read_good("bar.yaml");
  assert_string_equal(m->title, "Bar in uniaxial traction with a PD middle");
  assert_non_null(strstr(m->file, "tests/models/good/bar.yaml"));
  assert_int_equal(m->n_materials, 1);
  assert_string_equal(m->materials[0].name, "resin");
  assert_false(m->materials[0].orthotropic);
  assert_true(m->materials[0].E == 10000 && m->materials[0].nu == 0.2);
  assert_true(m->materials[0].has_density && m->materials[0].density == 1.2e-9);
  assert_mark(&m->materials[0].mark, 5, 3, "materials.resin");

  assert_true(m->has_beam && m->has_peridynamics && m->has_coupling);
  const cupid_beam *b = &m->beam;
  assert_int_equal(b->material, 0);
  assert_int_equal(b->n_axis, 4);
  const double y[4] = {0, 30, 70, 100};
  for (int i = 0; i < 4; i++) assert_true(b->axis_y[i] == y[i]);
  for (int i = 0; i < 3; i++) assert_int_equal(b->axis_elements[i], 1);
  assert_int_equal(b->element_nodes, 2);
  assert_int_equal(b->integration, 0);
  assert_int_equal(b->poisson_correction, 0); /* auto */
  assert_int_equal(b->expansion, CUPID_EXPANSION_TE);
  assert_int_equal(b->te_order, 2);
  assert_int_equal(b->n_components, 1);
  assert_int_equal(b->components[0].nx, 2);
  assert_int_equal(b->components[0].nz, 2);
  assert_true(b->components[0].x[1] == 10 && b->components[0].z[1] == 10);
  assert_int_equal(b->components[0].material, -1);
  assert_int_equal(b->n_section_nodes, 0);

  const cupid_peridynamics *pd = &m->pd;
  assert_true(pd->spacing == 1.0 && pd->horizon == 3.0);
  assert_int_equal(pd->model, CUPID_PD_LPS);
  assert_int_equal(pd->influence, CUPID_INFLUENCE_GAUSSIAN);
  assert_int_equal(pd->partial_volume, CUPID_PARTIAL_PDLAMMPS);
  assert_int_equal(pd->dimension, 3);
  assert_int_equal(pd->material, 0);
  assert_int_equal(pd->n_regions, 1);
  const cupid_pd_region *r = &pd->regions[0];
  assert_true(r->box.lo[0] == 0 && r->box.hi[0] == 10 && r->box.lo[1] == 30 &&
              r->box.hi[1] == 70 && r->box.lo[2] == 0 && r->box.hi[2] == 10);
  assert_true(r->box.has[0] && r->box.has[1] && r->box.has[2]);
  assert_int_equal(r->material, 0);
  assert_mark(&r->mark, 23, 7, "peridynamics.regions[0]");
  assert_mark(&pd->mark, 16, 3, "peridynamics"); /* a block mapping starts at its first key */

  assert_int_equal(m->coupling.method, CUPID_COUPLING_FICTITIOUS);
  assert_false(m->coupling.has_arlequin);

  assert_int_equal(m->n_constraints, 3);
  assert_int_equal(m->constraints[0].kind, CUPID_CONSTRAINT_CLAMP);
  assert_true(m->constraints[0].plane_y == 0 && m->constraints[0].layer == 0);
  assert_mark(&m->constraints[0].mark, 29, 5, "constraints[0]");
  const cupid_constraint *fix = &m->constraints[1];
  assert_int_equal(fix->kind, CUPID_CONSTRAINT_FIX);
  assert_true(fix->components[0] && !fix->components[1] && !fix->components[2]);
  assert_true(fix->box.has[0] && fix->box.hi[0] == 1 && fix->box.hi[1] == 100);
  const cupid_constraint *disp = &m->constraints[2];
  assert_int_equal(disp->kind, CUPID_CONSTRAINT_DISPLACEMENT);
  assert_true(!disp->box.has[0] && disp->box.has[1] && !disp->box.has[2]);
  assert_true(isinf(disp->box.lo[0]) && disp->box.lo[0] < 0 && isinf(disp->box.hi[2]));
  assert_int_equal(disp->value[0].kind, CUPID_VALUE_EXPR);
  assert_int_equal(disp->value[1].kind, CUPID_VALUE_NONE);
  assert_int_equal(disp->value[2].kind, CUPID_VALUE_CONSTANT);
  ASSERT_NEAR(value_at(&disp->value[0], 0, 100, 0), 0.1, 1e-15);
  assert_true(value_at(&disp->value[1], 1, 2, 3) == 0);

  assert_int_equal(m->n_loads, 5);
  const cupid_load *l = m->loads;
  assert_int_equal(l[0].kind, CUPID_LOAD_TRACTION);
  assert_true(l[0].plane_y == 100 && !l[0].patch.has[0] && !l[0].patch.has[2]);
  assert_true(l[0].value[1].kind == CUPID_VALUE_CONSTANT && l[0].value[1].constant == 100);
  assert_true(l[1].patch.has[0] && l[1].patch.lo[0] == 4 && l[1].patch.hi[0] == 6);
  assert_true(l[1].patch.has[2] && l[1].patch.lo[2] == 5 && l[1].patch.hi[2] == 10);
  assert_false(l[1].patch.has[1]);
  assert_true(l[1].value[2].constant == -20);
  assert_int_equal(l[2].kind, CUPID_LOAD_POINT);
  assert_true(l[2].at[0] == 5 && l[2].at[1] == 100 && l[2].at[2] == 5);
  assert_int_equal(l[3].kind, CUPID_LOAD_BODY);
  assert_true(l[3].box.has[2] && !l[3].box.has[0]);
  ASSERT_NEAR(cupid_value_eval(&l[3].value[2], 0, 0, 0, 0, 1.2e-9), -9.81e-9 * 1.2e-9, 1e-30);
  assert_true(!l[4].box.has[0] && !l[4].box.has[1] && !l[4].box.has[2]); /* whole body */
  ASSERT_NEAR(value_at(&l[4].value[1], 0, 50, 0), 2, 1e-14);
  assert_mark(&l[4].mark, 38, 5, "loads[4]");

  assert_int_equal(m->analysis.type, CUPID_ANALYSIS_STATIC);
  assert_int_equal(m->analysis.solver, CUPID_SOLVER_DIRECT);
  assert_false(m->analysis.dynamic.has_dynamic);

  const cupid_output *o = &m->output;
  assert_string_equal(o->directory, "out/bar");
  assert_true(o->vtu && !o->pd_nodes && o->plots);
  assert_int_equal(o->n_lines, 1);
  assert_string_equal(o->lines[0].name, "axis");
  assert_true(o->lines[0].from[1] == 0 && o->lines[0].to[1] == 100 && o->lines[0].points == 101);
  assert_int_equal(o->n_points, 1);
  assert_string_equal(o->points[0].name, "tip");
  assert_true(o->points[0].stress && o->points[0].at[1] == 100);
  cupid_model_destroy(&m);
  assert_null(m);
}

static void test_pd_only_defaults(void **state) {
  (void)state;
  cupid_model m = read_good("pd_only.yaml");
  assert_string_equal(m->title, "");
  assert_false(m->has_beam);
  assert_false(m->has_coupling);
  assert_true(m->has_peridynamics);
  assert_false(m->materials[0].has_density);
  assert_int_equal(m->pd.model, CUPID_PD_LPS);
  assert_int_equal(m->pd.influence, CUPID_INFLUENCE_GAUSSIAN);
  assert_int_equal(m->pd.partial_volume, CUPID_PARTIAL_PDLAMMPS);
  assert_int_equal(m->pd.dimension, 3);
  assert_int_equal(m->pd.material, -1);     /* not given ... */
  assert_int_equal(m->pd.regions[1].material, 0); /* ... so the only material is used */
  assert_int_equal(m->pd.n_regions, 2);
  const cupid_constraint *c = &m->constraints[0];
  assert_true(c->components[0] && c->components[1] && c->components[2]); /* default: all */
  assert_int_equal(m->analysis.type, CUPID_ANALYSIS_STATIC);
  assert_int_equal(m->analysis.solver, CUPID_SOLVER_AUTO);
  const cupid_dynamic *d = &m->analysis.dynamic;
  assert_int_equal(d->integrator, CUPID_INTEGRATOR_NEWMARK);
  assert_true(d->newmark_beta == 0.25 && d->newmark_gamma == 0.5 && d->every == 1);
  assert_false(d->lumped_mass);
  assert_string_equal(m->output.directory, "out/pd_only");
  assert_true(m->output.vtu && !m->output.pd_nodes && m->output.plots);
  assert_int_equal(m->output.n_lines, 0);
  assert_int_equal(m->output.n_points, 0);
  cupid_model_destroy(&m);
}

static void test_truss_1d_dynamic(void **state) {
  (void)state;
  cupid_model m = read_good("truss_1d.yaml");
  assert_string_equal(m->title, "Truss, Arlequin");
  assert_int_equal(m->beam.material, 0); /* the only material */
  assert_int_equal(m->beam.te_order, 0);
  assert_int_equal(m->beam.axis_elements[0], 30);
  const cupid_peridynamics *pd = &m->pd;
  assert_int_equal(pd->dimension, 1);
  assert_int_equal(pd->model, CUPID_PD_BOND); /* the 1D default */
  assert_true(pd->area == 1.0);
  assert_int_equal(pd->influence, CUPID_INFLUENCE_CONSTANT);
  assert_int_equal(pd->partial_volume, CUPID_PARTIAL_NONE);
  assert_true(pd->regions[0].box.has[1] && !pd->regions[0].box.has[0] && !pd->regions[0].box.has[2]);
  assert_true(pd->regions[0].box.lo[1] == 0.4 && pd->regions[0].box.hi[1] == 1.0);
  const cupid_coupling *c = &m->coupling;
  assert_int_equal(c->method, CUPID_COUPLING_ARLEQUIN);
  assert_true(c->has_arlequin && c->penalty == 1e9 && !c->penalty_auto);
  assert_int_equal(c->weight, CUPID_WEIGHT_LINEAR);
  assert_true(c->n_overlaps == 1 && c->overlaps[0].has[1] && c->overlaps[0].lo[1] == 0.4 && c->overlaps[0].hi[1] == 0.6);
  assert_true(m->constraints[0].layer == 0.0375);
  const cupid_analysis *a = &m->analysis;
  assert_int_equal(a->type, CUPID_ANALYSIS_DYNAMIC);
  const cupid_dynamic *d = &a->dynamic;
  assert_true(d->has_dynamic);
  assert_int_equal(d->integrator, CUPID_INTEGRATOR_NEWMARK);
  assert_true(d->dt == 1e-6 && d->duration == 0.056 && d->every == 10);
  assert_true(d->rayleigh_mass == 0.1 && d->rayleigh_stiffness == 3.2e-6);
  assert_true(d->newmark_beta == 0.3 && d->newmark_gamma == 0.6 && d->lumped_mass);
  ASSERT_NEAR(value_at(&d->initial_displacement[1], 0, 0.5, 0), 5e-4, 1e-18);
  assert_int_equal(d->initial_velocity[0].kind, CUPID_VALUE_CONSTANT);
  assert_mark(&d->mark, 27, 5, "analysis.dynamic");
  assert_int_equal(m->output.n_points, 2);
  assert_string_equal(m->output.points[1].name, "mid");
  assert_false(m->output.points[1].stress);
  cupid_model_destroy(&m);
}

static void test_le_explicit(void **state) {
  (void)state;
  cupid_model m = read_good("le_explicit.yaml");
  assert_int_equal(m->n_materials, 2);
  const cupid_material *ply = &m->materials[1];
  assert_true(ply->orthotropic);
  assert_true(ply->Ex == 140000 && ply->Ey == 10000 && ply->Ez == 10000);
  assert_true(ply->nu_xy == 0.3 && ply->nu_xz == 0.3 && ply->nu_yz == 0.45);
  assert_true(ply->Gxy == 5000 && ply->Gxz == 5000 && ply->Gyz == 3500);
  const cupid_beam *b = &m->beam;
  assert_int_equal(b->element_nodes, 4);
  assert_int_equal(b->integration, 1);
  assert_int_equal(b->poisson_correction, 2); /* off */
  assert_int_equal(b->axis_elements[0], 4);
  assert_int_equal(b->axis_elements[1], 2);
  assert_int_equal(b->expansion, CUPID_EXPANSION_LE);
  assert_int_equal(b->le_nodes, 4);
  assert_int_equal(b->n_components, 0);
  assert_int_equal(b->n_section_nodes, 6);
  assert_true(b->section_nodes[2 * 5] == 2 && b->section_nodes[2 * 5 + 1] == 1);
  assert_int_equal(b->n_section_elements, 2);
  const int e[8] = {0, 1, 4, 3, 1, 2, 5, 4};
  for (int i = 0; i < 8; i++) assert_int_equal(b->section_elements[i], e[i]);
  assert_int_equal(b->section_element_material[0], -1);
  assert_int_equal(b->section_element_material[1], 1);
  assert_false(m->has_peridynamics);
  assert_int_equal(m->analysis.type, CUPID_ANALYSIS_EVALUATE);
  assert_int_equal(m->analysis.field[0].kind, CUPID_VALUE_EXPR);
  assert_int_equal(m->analysis.field[1].kind, CUPID_VALUE_CONSTANT);
  assert_int_equal(m->analysis.field[2].kind, CUPID_VALUE_CONSTANT); /* "0" folds */
  ASSERT_NEAR(value_at(&m->analysis.field[0], 2, 0, 0), 2e-6, 1e-20);
  assert_true(m->loads[0].value[2].constant == -1);
  assert_string_equal(m->output.directory, "out/le_explicit");
  cupid_model_destroy(&m);
}

static void test_components(void **state) {
  (void)state;
  cupid_model m = read_good("components.yaml");
  assert_string_equal(m->title, "C-section: bending and torsion");
  const cupid_beam *b = &m->beam;
  assert_int_equal(b->element_nodes, 4);
  assert_int_equal(b->integration, 2);
  assert_int_equal(b->le_nodes, 9);
  assert_int_equal(b->n_components, 3);
  assert_int_equal(b->components[0].nz, 6);
  assert_true(b->components[0].z[2] == -30);
  assert_int_equal(b->components[0].material, -1);
  assert_int_equal(b->components[2].material, 1);
  assert_mark(&b->components[2].mark, 16, 9, "beam.section.components[2]");
  assert_int_equal(m->pd.model, CUPID_PD_BOND);
  assert_int_equal(m->pd.influence, CUPID_INFLUENCE_INVERSE);
  assert_int_equal(m->pd.partial_volume, CUPID_PARTIAL_EXACT);
  assert_int_equal(m->coupling.method, CUPID_COUPLING_LAGRANGE);
  assert_string_equal(m->output.directory, "results/csec");
  assert_true(!m->output.vtu && m->output.pd_nodes && !m->output.plots);
  assert_string_equal(m->output.lines[0].name, "uz_line");
  assert_int_equal(m->output.lines[0].points, 201);
  assert_string_equal(m->output.points[0].name, "A");
  cupid_model_destroy(&m);
}

/* precracks and fracture, given before the keys they are checked against (model, regions). */
static void test_fracture(void **state) {
  (void)state;
  cupid_model m = read_good("fracture.yaml");
  const cupid_peridynamics *pd = &m->pd;
  assert_int_equal(pd->model, CUPID_PD_LPS);
  assert_int_equal(pd->n_regions, 2);
  assert_int_equal(pd->n_precracks, 2);
  const cupid_precrack *c = &pd->precracks[0];
  assert_int_equal(c->normal, 1);
  assert_true(c->at == 20);
  assert_true(!c->rect.has[1] && c->rect.lo[1] == -INFINITY && c->rect.hi[1] == INFINITY);
  assert_true(c->rect.has[0] && c->rect.lo[0] == 0 && c->rect.hi[0] == 4);
  assert_true(c->rect.has[2] && c->rect.lo[2] == 0 && c->rect.hi[2] == 2);
  assert_mark(&c->mark, 16, 7, "peridynamics.precracks[0]");
  c = &pd->precracks[1]; /* keys in any order */
  assert_int_equal(c->normal, 0);
  assert_true(c->at == 5);
  assert_true(!c->rect.has[0] && c->rect.has[1] && c->rect.has[2]);
  assert_true(c->rect.lo[1] == 10 && c->rect.hi[1] == 30 && c->rect.hi[2] == 2);
  assert_mark(&c->mark, 17, 7, "peridynamics.precracks[1]");
  const cupid_fracture *f = &pd->fracture;
  assert_true(f->has_fracture);
  assert_int_equal(f->criterion, CUPID_FRACTURE_ENERGY);
  assert_true(f->has_energy_release_rate && f->energy_release_rate == 0.35);
  assert_false(f->has_critical_stretch);
  assert_int_equal(f->per_iteration_all, 0);
  assert_mark(&f->mark, 9, 5, "peridynamics.fracture");
  assert_int_equal(f->n_no_fail, 2);
  const cupid_box *b = &f->no_fail[0]; /* axes left out are unbounded */
  assert_true(b->has[1] && b->lo[1] == 0 && b->hi[1] == 3);
  assert_true(!b->has[0] && b->lo[0] == -INFINITY && !b->has[2] && b->hi[2] == INFINITY);
  b = &f->no_fail[1];
  assert_true(b->has[0] && b->has[1] && b->has[2] && b->lo[1] == 37 && b->hi[0] == 2);
  assert_mark(&f->no_fail_marks[0], 13, 9, "peridynamics.fracture.no_fail[0]");
  assert_mark(&f->no_fail_marks[1], 14, 9, "peridynamics.fracture.no_fail[1]");
  cupid_model_destroy(&m);
}

/* The defaults of fracture, and a model without it. */
static void test_fracture_defaults(void **state) {
  (void)state;
  const char *text = "materials: {m: {E: 1, nu: 0}}\n"
                     "peridynamics:\n"
                     "  fracture: {critical_stretch: 5.0e-4}\n"
                     "  model: bond\n"
                     "  precracks:\n"
                     "  spacing: 1\n  horizon: 3\n"
                     "  regions: [{x: [0, 4], y: [0, 4], z: [0, 4]}]\n";
  cupid_model m = NULL;
  CUPID_ASSERT_OK(cupid_model_read_string(text, strlen(text), "f.yaml", &m));
  const cupid_fracture *f = &m->pd.fracture;
  assert_true(f->has_fracture);
  assert_int_equal(f->criterion, CUPID_FRACTURE_STRETCH);
  assert_true(f->has_critical_stretch && f->critical_stretch == 5.0e-4);
  assert_false(f->has_energy_release_rate);
  assert_int_equal(f->per_iteration_all, 1);
  assert_int_equal(f->n_no_fail, 0);
  assert_int_equal(m->pd.n_precracks, 0); /* "precracks:" alone is an empty list */
  cupid_model_destroy(&m);
  /* stretch from G0 (bond-based too); per_iteration: all spelt out */
  text = "materials: {m: {E: 1, nu: 0}}\n"
         "peridynamics: {spacing: 1, horizon: 3, model: bond, regions: [{x: [0, 4], y: [0, 4], "
         "z: [0, 4]}], fracture: {energy_release_rate: 2, per_iteration: all}}\n";
  CUPID_ASSERT_OK(cupid_model_read_string(text, strlen(text), "f.yaml", &m));
  f = &m->pd.fracture;
  assert_int_equal(f->criterion, CUPID_FRACTURE_STRETCH);
  assert_true(f->has_energy_release_rate && f->energy_release_rate == 2);
  assert_false(f->has_critical_stretch);
  assert_int_equal(f->per_iteration_all, 1);
  cupid_model_destroy(&m);
  m = read_good("pd_only.yaml");
  assert_false(m->pd.fracture.has_fracture);
  assert_int_equal(m->pd.n_precracks, 0);
  assert_null(m->pd.precracks);
  cupid_model_destroy(&m);
}

/* coupling.arlequin.penalty: auto (kappa chosen at run time, method_arlequin.c) and two PD
 * regions that touch (one body for Arlequin) are read as given. */
static void test_arlequin_penalty_auto(void **state) {
  (void)state;
  const char *text = "materials: {m: {E: 1, nu: 0.25}}\n"
                     "beam: {material: m, axis: {y: [0, 8], elements: [8]},\n"
                     "       section: {expansion: TE1, components: [{x: [0, 2], z: [0, 2]}]}}\n"
                     "peridynamics: {spacing: 1, horizon: 1.5, model: bond, material: m,\n"
                     "  regions: [{x: [0, 2], y: [4, 6], z: [0, 2]}, {x: [0, 2], y: [6, 9], z: [0, 2]}]}\n"
                     "coupling: {method: arlequin, arlequin: {penalty: auto, overlap: {y: [4, 5]}}}\n";
  cupid_model m = NULL;
  CUPID_ASSERT_OK(cupid_model_read_string(text, strlen(text), "f.yaml", &m));
  assert_true(m->coupling.has_arlequin && m->coupling.penalty_auto && m->coupling.penalty == 0.0);
  assert_int_equal(m->pd.n_regions, 2);
  cupid_model_destroy(&m);
}

static void test_read_string_and_defaults(void **state) {
  (void)state;
  const char *text = "materials: {m: {E: 1, nu: 0}}\n"
                     "peridynamics: {spacing: 1, horizon: 2.5, regions: [{x: [0, 1], y: [0, 1], "
                     "z: [0, 1]}]}\n"
                     "analysis:\noutput:\n";
  cupid_model m = NULL;
  CUPID_ASSERT_OK(cupid_model_read_string(text, strlen(text), "dir.d/my.model.yaml", &m));
  assert_string_equal(m->file, "dir.d/my.model.yaml");
  assert_string_equal(m->output.directory, "out/my.model");
  assert_int_equal(m->n_constraints, 0);
  assert_int_equal(m->n_loads, 0);
  assert_int_equal(m->analysis.type, CUPID_ANALYSIS_STATIC);
  cupid_model_destroy(&m);
  /* Anchors and aliases are ordinary YAML and work. */
  const char *aliased = "materials: {m: &mat {E: 1, nu: 0}, n: *mat}\n"
                        "peridynamics:\n  spacing: 1\n  horizon: 3\n  material: n\n"
                        "  regions: [&r {x: [0, 1], y: [0, 1], z: [0, 1]}, *r]\n";
  CUPID_ASSERT_OK(cupid_model_read_string(aliased, strlen(aliased), NULL, &m));
  assert_int_equal(m->pd.n_regions, 2);
  assert_int_equal(m->pd.regions[1].material, 1);
  assert_true(m->materials[1].E == 1);
  /* a model that is no file ("<model>", "<dict>"): out/model, not a folder named "<model>" */
  assert_string_equal(m->output.directory, "out/model");
  cupid_model_destroy(&m);
  cupid_model_destroy(&m); /* NULL-safe */
  cupid_model_destroy(NULL);
}

static void test_model_error_and_helpers(void **state) {
  (void)state;
  cupid_model m = read_good("bar.yaml");
  cupid_status st = cupid_model_error(m, &m->pd.regions[0].mark, "region %d is empty", 0);
  assert_int_equal(st, CUPID_ERR_MODEL);
  char want[512];
  snprintf(want, sizeof want, "%s:23:7: peridynamics.regions[0]: region 0 is empty", m->file);
  assert_string_equal(cupid_error_message(), want);
  cupid_mark unknown = {0, 0, ""};
  assert_int_equal(cupid_model_error(m, &unknown, "no place"), CUPID_ERR_MODEL);
  snprintf(want, sizeof want, "%s: no place", m->file);
  assert_string_equal(cupid_error_message(), want);
  cupid_model_destroy(&m);

  cupid_box box = {{0, -INFINITY, 1}, {1, INFINITY, 2}, {1, 0, 1}};
  assert_true(cupid_box_contains(&box, (double[3]){0.5, 1e30, 1.5}, 0));
  assert_true(cupid_box_contains(&box, (double[3]){1.0, 0, 2.0}, 0));     /* bounds included */
  assert_false(cupid_box_contains(&box, (double[3]){1.1, 0, 1.5}, 0));
  assert_true(cupid_box_contains(&box, (double[3]){1.1, 0, 1.5}, 0.2));  /* within tolerance */
  assert_false(cupid_box_contains(&box, (double[3]){0.5, 0, 0.5}, 0.1));

  cupid_value none = {CUPID_VALUE_NONE, 0, NULL}, constant = {CUPID_VALUE_CONSTANT, 2.5, NULL};
  assert_true(cupid_value_eval(&none, 1, 2, 3, 4, 5) == 0);
  assert_true(cupid_value_eval(&constant, 1, 2, 3, 4, 5) == 2.5);
  assert_true(cupid_value_eval(NULL, 1, 2, 3, 4, 5) == 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_bar),
      cmocka_unit_test(test_pd_only_defaults),
      cmocka_unit_test(test_truss_1d_dynamic),
      cmocka_unit_test(test_le_explicit),
      cmocka_unit_test(test_components),
      cmocka_unit_test(test_fracture),
      cmocka_unit_test(test_fracture_defaults),
      cmocka_unit_test(test_arlequin_penalty_auto),
      cmocka_unit_test(test_read_string_and_defaults),
      cmocka_unit_test(test_model_error_and_helpers),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
