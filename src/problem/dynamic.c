/* `type: dynamic` (model-format.md analysis.dynamic; issue 5): mass, initial conditions, time
 * integration by src/dynamics, and the time-series outputs, made into frames for the output
 * writers (io.h): history.csv (the output points at every step), energies.csv and
 * pd_<step>.vtu / beam_<step>.vtu at every `every` steps, model.pvd with their times,
 * model.exo (output.exodus: the same frames as Exodus II time steps), PNG plots, and a
 * "dynamic" block in summary.json.
 *
 * FE-only and PD-only models. The global system uses the [3 per PD node | FE DOFs] layout of
 * the prob, so a coupled model only needs its coupling terms in K (and, for Arlequin, the
 * weighted masses: coupled_arlequin.c; for Lagrange, the tied PD nodes' mass moved onto the
 * beam through the tie, and outputs that see the tied nodes recovered) before
 * cupid_dynamics_run(). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "problem_internal.h"
#include "method.h"
#include "cupid/dynamics.h"
#include "cupid/io.h"

/* The state of the output during a run. */
typedef struct {
  cupid_problem_state *prob;
  /* the writers (io.h), on the rank that writes files: the series, then the frames' */
  cupid_writer history, energies, damage, vtu, exodus;
  cupid_problem_vertices verts; /* the PD nodes of the frames (a slab run: the whole grid) */
  int timed_constraints, timed_loads; /* some value changes with t */
  cupid_int broken_reported;          /* broken bonds at the last progress line */
  cupid_int out_count;
  double *u_view;   /* Lagrange: u with the tied PD nodes recovered from the beam (outputs) */
  cupid_int **cnodes, *n_cnodes; /* timed constraints: the PD nodes of each constraint */
  /* a slab run (slab.c): rank 0's whole grid (coordinates only) for the frames */
  cupid_pd_grid whole;
  const double *u_out; /* the displacements the outputs of this step show (u or u_view) */
  /* a resumption (--resume): the integrator's state; its checkpoint, open until the writers
   * have read what they saved */
  cupid_dynamics_restart restart;
  double *restart_vectors;  /* a, react, load, and two scratch vectors (n each) */
  cupid_checkpoint resume;
  /* an adaptive zone (issue 37): the trigger's steps, the state where it fired, and
   * adaptive.pvd (the zone before each conversion and at the end) */
  int adapt_every;
  cupid_dynamics_restart paused;
  cupid_writer zones;
  cupid_int zone_frames;
  cupid_int converted_at; /* the last conversion's step */
  int energy_pending;     /* its energy is read at the next output step (monitor_outputs) */
  double conversion_before; /* the conversions' energy before it */
} dyn_output;

/* Every material used by the model needs a density. */
static cupid_status check_density(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  const cupid_dynamic *d = &m->analysis.dynamic;
  for (int k = 0; k < m->n_materials; k++) {
    int used = 0;
    if (m->has_beam) {
      used |= m->beam.material == k;
      for (int c = 0; c < m->beam.n_components; c++) used |= m->beam.components[c].material == k;
    }
    for (int r = 0; r < m->pd.n_regions && m->has_peridynamics; r++)
      used |= m->pd.regions[r].material == k;
    if (used && !(m->materials[k].has_density && m->materials[k].density > 0))
      return cupid_model_error(m, &m->materials[k].mark,
                               "material '%s' needs a positive density for type: dynamic",
                               m->materials[k].name);
  }
  if (d->integrator == CUPID_INTEGRATOR_NEWMARK && !(d->newmark_beta > 0))
    return cupid_model_error(m, &d->mark,
                             "newmark beta = 0 is the explicit method: use integrator: central");
  if (d->integrator == CUPID_INTEGRATOR_CENTRAL && m->has_beam && !d->lumped_mass)
    return cupid_model_error(m, &d->mark,
                             "integrator: central needs a diagonal mass: set lumped: true (the "
                             "consistent CUF mass would need a solve per step)");
  return CUPID_SUCCESS;
}

/* 1 if a value's expression names t (cupid_expr_model_vars: x y z t density): it is then
 * evaluated at every step. */
static int depends_on_time(const cupid_value *v) {
  return v->kind == CUPID_VALUE_EXPR && cupid_expr_uses(v->expr, 3);
}

static int load_depends_on_time(const cupid_load *l) {
  return depends_on_time(&l->value[0]) || depends_on_time(&l->value[1]) ||
         depends_on_time(&l->value[2]);
}

static int constraint_depends_on_time(const cupid_constraint *c) {
  return c->kind == CUPID_CONSTRAINT_DISPLACEMENT &&
         (depends_on_time(&c->value[0]) || depends_on_time(&c->value[1]) ||
          depends_on_time(&c->value[2]));
}

cupid_status cupid_problem_dynamic_check(const cupid_problem_state *prob) {
  return check_density(prob);
}

static void field_of_values(void *ctx, const double p[3], double density, double out[3]) {
  const cupid_value *v = ctx;
  for (int c = 0; c < 3; c++) out[c] = cupid_value_eval(&v[c], p[0], p[1], p[2], 0.0, density);
}

/* u0, v0 from the model's expressions (PD: nodal values; FE: cupid_cuf_interpolate). */
static cupid_status initial_state(cupid_problem_state *prob, double *v) {
  const cupid_model_t *m = prob->model;
  const cupid_dynamic *d = &m->analysis.dynamic;
  if (prob->grid) {
    const double *x = cupid_pd_grid_coords(prob->grid);
    const int *mat = cupid_pd_grid_materials(prob->grid);
    for (cupid_int i = 0; i < prob->n_pd; i++) {
      const double *p = x + 3 * i;
      double rho = m->materials[mat[i]].density;
      for (int c = 0; c < 3; c++) {
        prob->u[3 * i + c] = cupid_value_eval(&d->initial_displacement[c], p[0], p[1], p[2], 0, rho);
        v[3 * i + c] = cupid_value_eval(&d->initial_velocity[c], p[0], p[1], p[2], 0, rho);
      }
    }
  }
  if (prob->beam) {
    CUPID_CALL(cupid_cuf_interpolate(prob->beam, field_of_values, (void *)d->initial_displacement,
                                     prob->u));
    CUPID_CALL(cupid_cuf_interpolate(prob->beam, field_of_values, (void *)d->initial_velocity, v));
  }
  return CUPID_SUCCESS;
}

/* The step's frame for the VTU series and the Exodus file: the beam's reconstruction and the PD
 * nodes with displacement, velocity and (with fracture) damage (collective on a slab run). */
static cupid_status write_frame(dyn_output *o, cupid_int step, double t, const double *v) {
  cupid_problem_state *prob = o->prob;
  const cupid_vtu_array fields[3] = {{"displacement", 3, o->u_out}, {"velocity", 3, v},
                                     {"damage", 1, prob->damage}};
  cupid_writer writers[2] = {o->vtu, o->exodus};
  return cupid_problem_frame_write(prob, &o->verts, step, t, o->u_out, fields, 3, writers, 2);
}

/* A row of the history (t, then u at every output point) kept in the problem
 * (cupid_problem_get_history), grown by doubling. */
static cupid_status history_grow(cupid_problem_state *prob, double **row) {
  const int cols = 1 + 3 * prob->model->output.n_points;
  if (prob->history_rows == prob->history_cap) {
    cupid_int cap = prob->history_cap ? 2 * prob->history_cap : 1024;
    double *h = NULL;
    CUPID_CALL(cupid_malloc((size_t)cap * (size_t)cols, sizeof *h, "history", &h));
    if (prob->history_rows)
      memcpy(h, prob->history, sizeof *h * (size_t)prob->history_rows * (size_t)cols);
    cupid_free(&prob->history);
    prob->history = h;
    prob->history_cap = cap;
  }
  prob->history_cols = cols;
  *row = prob->history + (size_t)prob->history_rows++ * (size_t)cols;
  return CUPID_SUCCESS;
}

/* The output points at time t: in the problem's history and, on the rank that writes the
 * files, in history.csv. */
static cupid_status history_row(dyn_output *o, double t) {
  const cupid_output *out = &o->prob->model->output;
  double *row;
  CUPID_CALL(history_grow(o->prob, &row));
  row[0] = t;
  for (int k = 0; k < out->n_points; k++) {
    double *u = row + 1 + 3 * k;
    cupid_region_kind region;
    CUPID_CALL(cupid_problem_sample_point(o->prob, o->u_out, out->points[k].at, u, NULL, &region));
  }
  if (o->prob->slab) CUPID_CALL(cupid_problem_slab_points(o->prob, row + 1));
  const cupid_frame f = {.time = t, .row = row}; /* the row's columns: t, then the points' u */
  return cupid_writer_step(o->history, &f);
}

static cupid_status monitor_outputs(dyn_output *o, cupid_int step, double t, int output,
                                    const double *v, const cupid_dynamics_energy *e);

/* How central differences knew dt is stable (the integrator's check ran before step 0). */
static void stable_step_progress(cupid_problem_state *prob) {
  const cupid_dynamics_info *in = &prob->dyn.info;
  if (prob->model->analysis.dynamic.integrator != CUPID_INTEGRATOR_CENTRAL) return;
  if (in->omega_max != in->omega_max) { /* NaN: the bound sufficed */
    if (isinf(in->dt_bound)) /* K = 0 on the free DOFs */
      cupid_problem_progress(prob, "dynamics: dt is stable: K vanishes on the free DOFs");
    else
      cupid_problem_progress(prob, "dynamics: dt is stable: a bound of K guarantees steps up to "
                             "%.4g (no Lanczos estimate needed)", in->dt_bound);
    return;
  }
  char products[48] = ""; /* the matrix-free estimate counts its products */
  if (in->lanczos_steps > 0) snprintf(products, sizeof products, ", %d products", in->lanczos_steps);
  if (in->dt_bound > 0.0)
    cupid_problem_progress(prob, "dynamics: critical step %.4g (Lanczos estimate%s); guaranteed "
                           "stable up to %.4g", in->dt_critical, products, in->dt_bound);
  else
    cupid_problem_progress(prob, "dynamics: critical step %.4g (Lanczos estimate%s)",
                           in->dt_critical, products);
}

static cupid_status monitor(void *ctx, cupid_int step, double t, int output, const double *u,
                            const double *v, const double *a, const cupid_dynamics_energy *e) {
  (void)a;
  dyn_output *o = ctx;
  o->u_out = u;
  if (o->u_view) { /* outputs see the tied nodes following the beam (they are fixed in u) */
    memcpy(o->u_view, u, sizeof *u * (size_t)o->prob->ndof);
    o->prob->method->recover(o->prob, o->u_view);
    o->u_out = o->u_view;
  }
  cupid_status st = monitor_outputs(o, step, t, output, v, e);
  if (step == 0) stable_step_progress(o->prob);
  /* every tenth of the run, whatever `every` is (the monitor sees every step) */
  const cupid_int tenth = o->prob->dyn.steps / 10 > 0 ? o->prob->dyn.steps / 10 : 1;
  if (st == CUPID_SUCCESS && step > 0 && step % tenth == 0) {
    if (o->prob->model->pd.fracture.has_fracture && o->prob->model->has_peridynamics)
      cupid_problem_progress(o->prob, "dynamics: step %lld / %lld, t = %.4g, %lld broken bonds "
                             "(+%lld), energy balance %.2e",
                             (long long)step, (long long)o->prob->dyn.steps, t,
                             (long long)o->prob->broken_bonds,
                             (long long)(o->prob->broken_bonds - o->broken_reported), e->balance);
    else
      cupid_problem_progress(o->prob, "dynamics: step %lld / %lld, t = %.4g, energy balance %.2e",
                             (long long)step, (long long)o->prob->dyn.steps, t, e->balance);
    o->broken_reported = o->prob->broken_bonds;
  }
  return st;
}

/* The last conversion's energy, once the integrator has booked it (its sum of conversions'
 * energies now @p booked: at the next output step, or at the next conversion's step). */
static void conversion_energy(dyn_output *o, double booked) {
  if (!o->energy_pending) return;
  const double added = booked - o->conversion_before;
  cupid_problem_adaptive_energy(o->prob, added);
  cupid_problem_progress(o->prob, "adaptive: the conversion at step %lld changed the kinetic + "
                         "strain energy by %.4g (conversion_added in energies.csv)",
                         (long long)o->converted_at, added);
  o->energy_pending = 0;
}

static cupid_status monitor_outputs(dyn_output *o, cupid_int step, double t, int output,
                                    const double *v, const cupid_dynamics_energy *e) {
  if (o->prob->model->output.n_points) CUPID_CALL(history_row(o, t));
  if (!output) return CUPID_SUCCESS;
  o->out_count++;
  cupid_problem_state *prob = o->prob;
  /* energies.csv's columns (open_outputs): fracture with it, conversion with an adaptive zone */
  const double total =
      e->kinetic + e->strain + e->damping + e->fracture - e->external - e->conversion;
  double erow[10];
  int k = 0;
  erow[k++] = t, erow[k++] = (double)step, erow[k++] = e->kinetic, erow[k++] = e->strain;
  erow[k++] = e->damping;
  if (prob->damage || prob->adaptive) erow[k++] = e->fracture;
  if (prob->adaptive) erow[k++] = e->conversion;
  erow[k++] = e->external, erow[k++] = total, erow[k++] = e->balance;
  const cupid_frame ef = {.step = step, .time = t, .row = erow};
  CUPID_CALL(cupid_writer_step(o->energies, &ef));
  conversion_energy(o, e->conversion); /* the first output after a conversion */
  if (prob->damage || prob->adaptive) { /* collective on a slab run: every rank counts, rank 0
                                           writes (a zone that starts empty: no PD node yet) */
    if (prob->damage) CUPID_CALL(cupid_problem_fracture_damage(prob));
    const double drow[7] = {(double)step, t, (double)prob->broken_bonds,
                            (double)prob->damaged_nodes, prob->max_damage,
                            (double)cupid_problem_fracture_nodes_broken(prob), (double)prob->n_pd};
    const cupid_frame df = {.step = step, .time = t, .row = drow};
    CUPID_CALL(cupid_writer_step(o->damage, &df));
  }
  const cupid_output *out = &prob->model->output;
  if ((out->vtu || out->exodus) && (prob->writedir || prob->slab))
    CUPID_CALL(write_frame(o, step, t, v));
  o->prob->dyn.energy = *e;
  return CUPID_SUCCESS;
}

/* A writer of the run's outputs: a resumption continues it from the checkpoint (io.h). */
static cupid_status open_writer(dyn_output *o, const cupid_writer_type *type, const char *file,
                                const cupid_column *columns, int n_columns, cupid_writer *w) {
  const cupid_model_t *m = o->prob->model;
  char key[64];
  snprintf(key, sizeof key, "writer %s", file);
  const cupid_writer_spec spec = {.dir = o->prob->writedir, .file = file, .title = m->title,
                                  .columns = columns, .n_columns = n_columns,
                                  .resume = o->resume, .key = key};
  return cupid_writer_create(type, &spec, w);
}

/* The writers of rank 0 (a slab run's others write nothing): damage.csv with fracture,
 * energies.csv, history.csv with output points, the VTU series and model.exo. */
static cupid_status open_outputs(dyn_output *o) {
  cupid_problem_state *prob = o->prob;
  const cupid_output *out = &prob->model->output;
  if (!prob->writedir) return CUPID_SUCCESS; /* an MPI rank other than 0: no files */
  if (prob->damage || prob->adaptive) { /* damage.csv (model-format.md, fracture outputs);
                                           pd_nodes: adaptive */
    static const cupid_column dc[7] = {{"step", 1}, {"t", 0}, {"broken_bonds", 1},
                                       {"damaged_nodes", 1}, {"max_damage", 0},
                                       {"nodes_broken", 1}, {"pd_nodes", 1}};
    CUPID_CALL(open_writer(o, &cupid_writer_csv, "damage.csv", dc, prob->adaptive ? 7 : 6,
                           &o->damage));
  }
  /* fracture_dissipated with fracture, conversion_added with an adaptive zone (monitor_outputs) */
  cupid_column ec[10];
  int ne = 0;
  ec[ne++] = (cupid_column){"t", 0}, ec[ne++] = (cupid_column){"step", 1};
  ec[ne++] = (cupid_column){"kinetic", 0}, ec[ne++] = (cupid_column){"strain", 0};
  ec[ne++] = (cupid_column){"damping_dissipated", 0};
  if (prob->damage || prob->adaptive) ec[ne++] = (cupid_column){"fracture_dissipated", 0};
  if (prob->adaptive) ec[ne++] = (cupid_column){"conversion_added", 0};
  ec[ne++] = (cupid_column){"external_work", 0}, ec[ne++] = (cupid_column){"total", 0};
  ec[ne++] = (cupid_column){"balance", 0};
  CUPID_CALL(open_writer(o, &cupid_writer_csv, "energies.csv", ec, ne, &o->energies));
  if (prob->adaptive && out->vtu) /* the zone before each conversion and at the end */
    CUPID_CALL(open_writer(o, &cupid_writer_vtu, "adaptive.pvd", NULL, 0, &o->zones));
  if (out->vtu) CUPID_CALL(open_writer(o, &cupid_writer_vtu, "model.pvd", NULL, 0, &o->vtu));
  if (out->exodus)
    CUPID_CALL(open_writer(o, &cupid_writer_exodus, "model.exo", NULL, 0, &o->exodus));
  if (out->n_points == 0) return CUPID_SUCCESS;
  const int nc = 1 + 3 * out->n_points;
  cupid_column *hc = NULL;
  char (*names)[200] = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_calloc((size_t)nc, sizeof *hc, "history columns", &hc));
  CUPID_TRY(cupid_calloc((size_t)nc, sizeof *names, "history columns", &names));
  hc[0] = (cupid_column){"t", 0};
  for (int k = 0; k < out->n_points; k++)
    for (int c = 0; c < 3; c++) {
      snprintf(names[1 + 3 * k + c], sizeof names[0], "%s_u%c", out->points[k].name, "xyz"[c]);
      hc[1 + 3 * k + c] = (cupid_column){names[1 + 3 * k + c], 0};
    }
  st = open_writer(o, &cupid_writer_csv, "history.csv", hc, nc, &o->history);
cleanup:
  cupid_free(&hc);
  cupid_free(&names);
  return st;
}

static cupid_status plots(const cupid_problem_state *prob, int damage) {
  const cupid_output *out = &prob->model->output;
  const char *title = prob->model->title[0] ? prob->model->title : "cupid";
  char t[600];
  int made = 0;
  cupid_plot_curve ec[5];
  static const char *enames[5] = {"kinetic", "strain", "damping_dissipated", "external_work", "total"};
  /* the total (the balance check) drawn thick and dashed, so it stays visible on top of the
   * kinetic and strain curves it sums */
  for (int k = 0; k < 5; k++)
    ec[k] = (cupid_plot_curve){.csv = "energies.csv", .xname = "t", .yname = enames[k],
                               .title = enames[k],
                               .style = k == 4 ? "lines lw 3 dt 2 lc rgb 'black'" : "lines lw 1.5"};
  snprintf(t, sizeof t, "%s: energies", title);
  CUPID_CALL(cupid_plot(prob->writedir, "energies", t, "t", "energy", 5, ec, &made));
  if (damage) { /* damage.png: how the crack grows */
    cupid_plot_curve dc[2] = {
        {.csv = "damage.csv", .xname = "t", .yname = "broken_bonds", .title = "broken bonds"},
        {.csv = "damage.csv", .xname = "t", .yname = "damaged_nodes", .title = "damaged nodes"}};
    snprintf(t, sizeof t, "%s: fracture", title);
    CUPID_CALL(cupid_plot(prob->writedir, "damage", t, "t", "count", 2, dc, &made));
  }
  for (int k = 0; k < out->n_points; k++) {
    char stem[512], cols[3][200];
    cupid_plot_curve hc[3];
    for (int c = 0; c < 3; c++) {
      snprintf(cols[c], sizeof cols[c], "%s_u%c", out->points[k].name, "xyz"[c]);
      hc[c] = (cupid_plot_curve){.csv = "history.csv", .xname = "t", .yname = cols[c],
                                 .title = cols[c]};
    }
    snprintf(stem, sizeof stem, "history_%s", out->points[k].name);
    snprintf(t, sizeof t, "%s: displacement history at '%s'", title, out->points[k].name);
    /* the y label names the components that move (the plot leaves out the others) */
    double umax[3] = {0, 0, 0};
    for (cupid_int r = 0; r < prob->history_rows; r++)
      for (int c = 0; c < 3; c++) {
        const double v = prob->history[(size_t)r * (size_t)prob->history_cols + 1 + 3 * k + c];
        if (v == v && fabs(v) > umax[c]) umax[c] = fabs(v);
      }
    char ylabel[64];
    cupid_plot_component_label(umax, ylabel, sizeof ylabel);
    CUPID_CALL(cupid_plot(prob->writedir, stem, t, "t", ylabel, 3, hc, &made));
  }
  return CUPID_SUCCESS;
}

static cupid_status finish_outputs(dyn_output *o) {
  cupid_problem_state *prob = o->prob;
  if (!prob->writedir) return CUPID_SUCCESS;
  /* ending consumes the handle (sets it NULL): remember whether damage.csv was written */
  const int damage = o->damage != NULL;
  CUPID_CALL(cupid_writer_end(&o->history));
  CUPID_CALL(cupid_writer_end(&o->damage));
  CUPID_CALL(cupid_writer_end(&o->energies));
  CUPID_CALL(cupid_writer_end(&o->vtu)); /* model.pvd */
  CUPID_CALL(cupid_writer_end(&o->zones)); /* adaptive.pvd */
  CUPID_CALL(cupid_writer_end(&o->exodus));
  if (prob->model->output.plots) CUPID_CALL(plots(prob, damage));
  return CUPID_SUCCESS;
}

/* A prescribed value that turned non-finite at t (an expression undefined there): a model
 * error at the constraint's line, the node and t, as the load's (cupid_problem_pd_loads). Only
 * this constraint's nodes are scanned each step; the message's scan runs once. */
static cupid_status check_prescribed(const cupid_problem_state *prob, const cupid_constraint *c,
                                     const cupid_int *nodes, cupid_int n, double t) {
  const double *v = prob->bc->value;
  int bad = 0;
  for (cupid_int k = 0; k < n && !bad; k++)
    for (int a = 0; a < 3; a++) bad |= !isfinite(v[3 * nodes[k] + a]);
  if (!bad) return CUPID_SUCCESS;
  char what[96];
  snprintf(what, sizeof what, "at t = %g the prescribed displacement", t);
  return cupid_problem_check_finite(prob, v, &c->mark, what);
}

/* A prescribed displacement that changes with t on beam DOFs needs a lumped mass: with the
 * consistent CUF mass the support's acceleration reaches the free DOFs through M's coupling
 * (M_fs a_s), which the integrators do not carry (they hold a fixed DOF's velocity and
 * acceleration at 0): the energy balance of a ramped grip on the truss missed by 6-8% with
 * the consistent mass, 2e-14 lumped. A PD node's mass is diagonal: its grips are exact. */
static cupid_status check_beam_motion(const cupid_problem_state *prob, int lumped) {
  const cupid_model_t *m = prob->model;
  if (!prob->beam || lumped) return CUPID_SUCCESS;
  for (int k = 0; k < m->n_constraints; k++) {
    const cupid_constraint *c = &m->constraints[k];
    if (constraint_depends_on_time(c) && cupid_problem_fe_node_in_box(prob, &c->box))
      return cupid_model_error(m, &c->mark,
                               "a prescribed displacement that changes with t on the beam needs "
                               "analysis.dynamic.lumped: true (the consistent mass would carry "
                               "the support's acceleration into the free DOFs, which the "
                               "integrators hold at rest on a fixed DOF)");
  }
  return CUPID_SUCCESS;
}

/* hooks->conditions: the values of the model's expressions at t on the PD nodes and the beam
 * (issue 34: a beam's were refused). Every constraint is applied
 * again in the file's order, so that where two overlap the later one wins as at t = 0. */
static cupid_status conditions_now(void *ctx, double t, double *u_fixed, double *f) {
  dyn_output *o = ctx;
  cupid_problem_state *prob = o->prob;
  const cupid_model_t *m = prob->model;
  prob->time = t;
  if (o->timed_constraints && !o->cnodes) { /* the nodes of every constraint, once */
    CUPID_CALL(cupid_calloc((size_t)m->n_constraints + 1, sizeof *o->cnodes, "constraint nodes",
                            &o->cnodes));
    CUPID_CALL(cupid_calloc((size_t)m->n_constraints + 1, sizeof *o->n_cnodes,
                            "constraint nodes", &o->n_cnodes));
    for (int k = 0; k < m->n_constraints; k++)
      CUPID_CALL(cupid_problem_pd_constraint_nodes(prob, &m->constraints[k], &o->cnodes[k],
                                                   &o->n_cnodes[k]));
  }
  cupid_cuf_set_time(prob->beam, t); /* the beam's expressions too */
  if (o->timed_constraints)
    for (int k = 0; k < m->n_constraints; k++) {
      const cupid_constraint *c = &m->constraints[k];
      cupid_problem_pd_prescribe_nodes(prob, c, o->cnodes[k], o->n_cnodes[k]);
      CUPID_CALL(check_prescribed(prob, c, o->cnodes[k], o->n_cnodes[k], t));
      if (prob->beam && constraint_depends_on_time(c) && cupid_problem_fe_node_in_box(prob, &c->box)) {
        CUPID_CALL(cupid_cuf_constraint_apply(prob->beam, m, c, prob->bc)); /* the same DOFs */
        int bad = 0; /* the beam's DOFs only each step; the message's scan once */
        for (cupid_int d = prob->fe_offset; d < prob->ndof && !bad; d++)
          bad = !isfinite(prob->bc->value[d]);
        if (bad)
          CUPID_CALL(cupid_problem_check_finite(prob, prob->bc->value, &c->mark,
                                                "the prescribed displacement"));
      }
    }
  if (o->timed_loads && prob->beam) { /* every load again, through the method (its split
                                         between the beam and the grid, a tie's transfer) */
    memset(prob->f_ext, 0, sizeof *prob->f_ext * (size_t)prob->ndof);
    CUPID_CALL(prob->method->loads(prob));
  } else if (o->timed_loads) {
    memset(prob->f_ext, 0, sizeof *prob->f_ext * (size_t)prob->ndof);
    CUPID_CALL(cupid_problem_pd_loads(prob, m->loads, m->n_loads, prob->f_ext));
  }
  const double *value = prob->bc->value, *f_ext = prob->f_ext;
#pragma omp parallel for schedule(static) if (prob->ndof > 100000)
  for (cupid_int d = 0; d < prob->ndof; d++) u_fixed[d] = value[d], f[d] = f_ext[d];
  return CUPID_SUCCESS;
}

/* hooks->after_forces: bond breaking at u_{n+1} (fracture.c); the bond-based model takes the
 * broken bonds' forces out of ku itself, LPS asks for a new product. */
static cupid_status break_bonds(void *ctx, cupid_int step, double t, const double *u, double *ku,
                                double *dissipated, int *changed) {
  dyn_output *o = ctx;
  cupid_problem_state *prob = o->prob;
  *changed = 0;
  if (!prob->op) return CUPID_SUCCESS; /* an adaptive zone that has not grown yet */
  const cupid_int before = cupid_pd_operator_num_broken(prob->op); /* this rank's bonds */
  prob->fracture.ku = prob->model->pd.model == CUPID_PD_BOND ? ku : NULL;
  cupid_status st = cupid_problem_fracture_step(prob, step, t, u, 0, NULL, dissipated);
  prob->fracture.ku = NULL;
  const int broke = cupid_pd_operator_num_broken(prob->op) != before;
  *changed = broke ? (prob->model->pd.model == CUPID_PD_BOND ? 1 : 2) : 0;
  return st;
}

/* ---- Checkpoints (resume.c; issue 36): the integrator's state, the outputs so far ---- */

/* The scalars of a safe point and of the outputs. */
typedef struct {
  cupid_dynamics_energy shares, whole, last;
  double e0, scale, max_balance, omega_max, dt_critical, dt_bound;
  int lanczos_steps;
  cupid_int out_count, broken_reported;
  cupid_int zone_frames, converted_at; /* an adaptive zone's */
  int energy_pending;
  double conversion_before;
} dyn_scalars;

/* A safe point's state, for cupid_problem_checkpoint_save. */
typedef struct {
  dyn_output *o;
  const cupid_dynamics_restart *r;
} dyn_point;

static cupid_status write_state(void *ctx, cupid_checkpoint_writer w) {
  const dyn_point *p = ctx;
  dyn_output *o = p->o;
  const cupid_dynamics_restart *r = p->r;
  cupid_problem_state *prob = o->prob;
  dyn_scalars c = {.shares = r->shares, .whole = r->whole, .last = prob->dyn.energy, .e0 = r->e0,
                   .scale = r->scale, .max_balance = r->max_balance, .omega_max = r->omega_max,
                   .dt_critical = r->dt_critical, .dt_bound = r->dt_bound,
                   .lanczos_steps = r->lanczos_steps,
                   .out_count = o->out_count, .broken_reported = o->broken_reported,
                   .zone_frames = o->zone_frames, .converted_at = o->converted_at,
                   .energy_pending = o->energy_pending, .conversion_before = o->conversion_before};
  cupid_writer writers[6] = {o->history, o->energies, o->damage, o->vtu, o->exodus, o->zones};
  for (int k = 0; k < 6; k++) CUPID_CALL(cupid_writer_save(writers[k], w));
  CUPID_CALL(cupid_problem_adaptive_save(prob, w)); /* the zone (nothing without one) */
  /* the patch test of the run's first layout (a resumed adaptive run starts on a grown one) */
  CUPID_CALL(cupid_checkpoint_write(w, "quality", &prob->quality, sizeof prob->quality));
  const size_t bytes = sizeof(double) * (size_t)r->n;
  CUPID_CALL(cupid_checkpoint_write(w, "step", &r->step, sizeof r->step));
  CUPID_CALL(cupid_checkpoint_write(w, "dynamics", &c, sizeof c));
  CUPID_CALL(cupid_checkpoint_write(w, "u", r->u, bytes));
  CUPID_CALL(cupid_checkpoint_write(w, "v", r->v, bytes));
  CUPID_CALL(cupid_checkpoint_write(w, "a", r->a, bytes));
  if (r->react) CUPID_CALL(cupid_checkpoint_write(w, "reactions", r->react, bytes));
  if (r->load) CUPID_CALL(cupid_checkpoint_write(w, "load", r->load, bytes));
  return CUPID_SUCCESS;
}

/* hooks->safe_point: a checkpoint when one is due; after a signal's, the run stops. */
static cupid_status save_point(void *ctx, const cupid_dynamics_restart *r) {
  dyn_output *o = ctx;
  const cupid_problem_state *prob = o->prob;
  dyn_point p = {o, r};
  char where[160];
  snprintf(where, sizeof where, "at step %lld of %lld (t = %g)", (long long)r->step,
           (long long)prob->dyn.steps, (double)r->step * prob->model->analysis.dynamic.dt);
  return cupid_problem_checkpoint_save(o->prob, r->step, write_state, &p, where);
}

/* --resume: the checkpoint's state into o->restart (u and v into prob->u and v), the outputs'
 * bookkeeping, and (resume.c) the fracture state and history. */
static cupid_status read_state(dyn_output *o, const cupid_checkpoint ck, double *v) {
  cupid_problem_state *prob = o->prob;
  const cupid_int n = prob->ndof;
  const size_t bytes = sizeof(double) * (size_t)n;
  dyn_scalars c;
  cupid_dynamics_restart *r = &o->restart;
  CUPID_CALL(cupid_checkpoint_read(ck, "step", &r->step, sizeof r->step));
  CUPID_CALL(cupid_checkpoint_read(ck, "dynamics", &c, sizeof c));
  CUPID_CALL(cupid_calloc(5 * (size_t)n + 1, sizeof(double), "resumed state", &o->restart_vectors));
  double *a = o->restart_vectors, *react = a + n, *load = react + n;
  CUPID_CALL(cupid_checkpoint_read(ck, "u", prob->u, bytes));
  CUPID_CALL(cupid_checkpoint_read(ck, "v", v, bytes));
  CUPID_CALL(cupid_checkpoint_read(ck, "a", a, bytes));
  const void *data = NULL;
  size_t got = 0;
  const int timed = cupid_checkpoint_section(ck, "load", &data, &got) == CUPID_SUCCESS;
  cupid_error_clear();
  if (timed) {
    CUPID_CALL(cupid_checkpoint_read(ck, "reactions", react, bytes));
    CUPID_CALL(cupid_checkpoint_read(ck, "load", load, bytes));
  }
  *r = (cupid_dynamics_restart){.step = r->step, .n = n, .u = prob->u, .v = v, .a = a,
                                .react = timed ? react : NULL, .load = timed ? load : NULL,
                                .shares = c.shares, .whole = c.whole, .e0 = c.e0,
                                .scale = c.scale, .max_balance = c.max_balance,
                                .omega_max = c.omega_max, .dt_critical = c.dt_critical,
                                .dt_bound = c.dt_bound, .lanczos_steps = c.lanczos_steps};
  const char *patch_skipped = prob->quality.patch_skipped; /* this process's pointer */
  CUPID_CALL(cupid_checkpoint_read(ck, "quality", &prob->quality, sizeof prob->quality));
  prob->quality.patch_skipped = patch_skipped;
  prob->dyn.energy = c.last;
  o->out_count = c.out_count;
  o->broken_reported = c.broken_reported;
  o->zone_frames = c.zone_frames, o->converted_at = c.converted_at;
  o->energy_pending = c.energy_pending, o->conversion_before = c.conversion_before;
  cupid_problem_progress(prob, "resume: from step %lld of %lld (t = %g), %lld broken bonds",
                         (long long)r->step, (long long)prob->dyn.steps,
                         (double)r->step * prob->model->analysis.dynamic.dt,
                         (long long)prob->broken_bonds);
  return CUPID_SUCCESS;
}

/* The checkpoint stays open in o->resume until the writers have read theirs (open_outputs). */
static cupid_status resume_from_checkpoint(dyn_output *o, double *v) {
  CUPID_CALL(cupid_problem_checkpoint_open(o->prob, "step", &o->resume));
  CUPID_CALL(cupid_problem_checkpoint_fracture(o->prob, o->resume));
  return read_state(o, o->resume, v);
}

/* ---- Adaptive zones (issue 37; adaptive.c): the run pauses where the trigger fires, the zone
 * grows, and the run goes on from that step on the new layout ---- */

/* hooks->pause: every adapt_every steps (not the last), the trigger on u (prob->u: the
 * integrator's) and the damage now; the run stops at the step when it marked something. */
static cupid_status adaptive_pause(void *ctx, cupid_int step, const double *u, const double *v,
                                   int *stop) {
  (void)u, (void)v;
  dyn_output *o = ctx;
  *stop = 0;
  if (step % o->adapt_every != 0 || step == o->prob->dyn.steps) return CUPID_SUCCESS;
  cupid_int marked = 0;
  CUPID_CALL(cupid_problem_fracture_damage(o->prob));
  CUPID_CALL(cupid_problem_adaptive_trigger(o->prob, &marked));
  *stop = marked > 0;
  return CUPID_SUCCESS;
}

/* hooks->stopped: the state where the trigger fired. Its u and v are the run's own vectors
 * (prob->u and v), which outlive the call; the integrator's acceleration, reactions and load
 * are not kept: the changed system makes them again. */
static cupid_status adaptive_stopped(void *ctx, const cupid_dynamics_restart *r) {
  dyn_output *o = ctx;
  o->paused = *r;
  o->paused.a = o->paused.react = o->paused.load = NULL;
  return CUPID_SUCCESS;
}

/* adaptive.pvd: the zone and its fields (displacement, velocity, damage) at time t. */
static cupid_status zone_frame(dyn_output *o, double t, const double *v) {
  if (!o->zones) return CUPID_SUCCESS;
  cupid_problem_state *prob = o->prob;
  CUPID_CALL(cupid_problem_fracture_damage(prob));
  const cupid_vtu_array fields[3] = {{"displacement", 3, prob->u}, {"velocity", 3, v},
                                     {"damage", 1, prob->damage}};
  return cupid_problem_frame_write(prob, &o->verts, ++o->zone_frames, t, prob->u, fields, 3,
                                   &o->zones, 1);
}

static void free_constraint_nodes(dyn_output *o) {
  for (int k = 0; o->cnodes && k < o->prob->model->n_constraints; k++) cupid_free(&o->cnodes[k]);
  cupid_free(&o->cnodes);
  cupid_free(&o->n_cnodes);
}

/* What a run needs of a layout: the mass and, for central differences on an operator with
 * one, the rows' bound of K (the guaranteed stable step). */
typedef struct {
  cupid_csr M;
  double *m_lumped, *row_bound;
} dyn_layout;

static void layout_free(dyn_layout *l) {
  cupid_csr_destroy(&l->M);
  cupid_free(&l->m_lumped);
  cupid_free(&l->row_bound);
}

static cupid_status row_bounds(const cupid_problem_state *prob, const cupid_method_operator *op,
                               dyn_layout *l) {
  if (!op || !op->row_bound || prob->model->analysis.dynamic.integrator != CUPID_INTEGRATOR_CENTRAL)
    return CUPID_SUCCESS;
  /* a slab's operator gives its owned rows exactly (cupid_pd_operator_halo_layers) */
  CUPID_CALL(cupid_malloc((size_t)prob->ndof + 1, sizeof *l->row_bound, "row bounds of K",
                          &l->row_bound));
  return op->row_bound(op->ctx, l->row_bound);
}

/* The trigger fired at o->paused.step: the zone grows (adaptive.c: the new nodes take u and
 * v from the beam's field there), and the operator, mass, row bounds and frames' nodes are
 * made again for the new layout; o->paused becomes the changed system's state to go on
 * from. *capped: the zone would pass max_nodes (the layout as it was; the run stops). */
static cupid_status convert_zone(dyn_output *o, cupid_method_operator *op, double **v,
                                 dyn_layout *l, int *capped) {
  cupid_problem_state *prob = o->prob;
  const cupid_int step = o->paused.step;
  const double t = (double)step * prob->model->analysis.dynamic.dt;
  conversion_energy(o, o->paused.whole.conversion); /* one since the last output step */
  CUPID_CALL(zone_frame(o, t, *v));
  /* what borrows the old layout */
  if (op->destroy) op->destroy(&op->ctx);
  *op = (cupid_method_operator){0};
  prob->crack_copy = NULL, prob->crack_map = NULL;
  layout_free(l);
  free_constraint_nodes(o);
  cupid_problem_vertices_free(&o->verts);
  CUPID_CALL(cupid_problem_adaptive_convert(prob, (int)step, t, v, 1, capped));
  /* (capped: the old layout still, its operator again for the run's end) */
  CUPID_CALL(prob->method->explicit_operator(prob, op));
  CUPID_CALL(prob->method->mass(prob, &l->M, &l->m_lumped));
  CUPID_CALL(row_bounds(prob, op, l));
  if (prob->model->output.vtu && prob->grid)
    CUPID_CALL(cupid_problem_vertices_build(prob->grid, &o->verts));
  if (*capped) return CUPID_SUCCESS; /* nothing converted: the run ends here */
  o->converted_at = step;
  o->energy_pending = 1;
  o->conversion_before = o->paused.whole.conversion;
  o->paused.n = prob->ndof;
  o->paused.u = prob->u;
  o->paused.v = *v;
  o->paused.changed = 1;
  return CUPID_SUCCESS;
}

/* --resume of an adaptive run: the checkpoint was written at its step before the trigger's
 * test there (the safe point comes first), so the test runs now, as the run that went on ran
 * it; a conversion makes the changed system the run resumes from (opt->resume), a cap ends
 * the run there (no step left). */
static cupid_status trigger_at_resume(dyn_output *o, cupid_method_operator *op, double **v,
                                      dyn_layout *l, cupid_dynamics_options *opt) {
  int stop = 0, capped = 0;
  CUPID_CALL(adaptive_pause(o, o->restart.step, o->prob->u, *v, &stop));
  if (!stop) return CUPID_SUCCESS;
  o->paused = o->restart;
  o->paused.a = o->paused.react = o->paused.load = NULL;
  CUPID_CALL(convert_zone(o, op, v, l, &capped));
  if (capped) opt->steps = o->restart.step;
  else opt->resume = &o->paused;
  return CUPID_SUCCESS;
}

/* A slab's stiffness product: its owned rows (the halo's rows are not needed, and not
 * right: their families reach beyond the slab). */
static cupid_status slab_apply(void *ctx, const double *x, double *y) {
  const cupid_problem_state *prob = ctx;
  const cupid_int a = prob->part.owned_first, b = prob->part.owned_last;
  return cupid_pd_operator_apply_range(prob->op, a, b, x, y + 3 * a);
}

/* A status that one rank of a slab run found, agreed by all. */
static cupid_status agreed(const cupid_problem_state *prob, cupid_status st) {
  return prob->slab ? cupid_problem_slab_agree(st) : st;
}

cupid_status cupid_problem_run_dynamic(cupid_problem_state *prob, cupid_method_operator *op) {
  const cupid_model_t *m = prob->model;
  const cupid_dynamic *d = &m->analysis.dynamic;
  cupid_status st = CUPID_SUCCESS;
  dyn_layout l = {0};
  double *v = NULL, t0 = cupid_wtime();
  dyn_output o = {.prob = prob};
  int mf = op && op->apply; /* (an adaptive zone that starts empty: not until it grows) */
  cupid_petsc_halo halo = NULL;
  cupid_dynamics_partition part;
  CUPID_TRY(agreed(prob, prob->method->mass(prob, &l.M, &l.m_lumped)));
  cupid_problem_phase_end(prob, CUPID_PHASE_ASSEMBLY, t0);
  CUPID_TRY(agreed(prob, cupid_calloc((size_t)prob->ndof + 1, sizeof *v, "velocities", &v)));
  CUPID_TRY(agreed(prob, initial_state(prob, v)));
  CUPID_TRY(agreed(prob, cupid_problem_check_finite(prob, prob->u, &d->mark,
                                                    "the initial displacement")));
  CUPID_TRY(agreed(prob, cupid_problem_check_finite(prob, v, &d->mark, "the initial velocity")));
  const int frames = m->output.vtu || m->output.exodus;
  if (prob->slab) { /* the halo exchange, and rank 0's whole grid for the frames */
    CUPID_TRY(cupid_problem_slab_partition(prob, &halo, &part));
    if (prob->writedir && frames) st = cupid_pd_grid_create_from_model(m, &o.whole);
    if (st == CUPID_SUCCESS && o.whole) st = cupid_problem_vertices_build(o.whole, &o.verts);
    CUPID_TRY(cupid_problem_slab_agree(st));
  } else if (prob->grid && frames) {
    CUPID_TRY(cupid_problem_vertices_build(prob->grid, &o.verts));
  }

  cupid_dynamics_options opt = cupid_dynamics_defaults();
  opt.integrator = d->integrator;
  opt.dt = d->dt;
  opt.steps = (cupid_int)llround(d->duration / d->dt);
  if (opt.steps < 1) opt.steps = 1;
  opt.every = d->every;
  opt.beta = d->newmark_beta;
  opt.gamma = d->newmark_gamma;
  opt.rayleigh_mass = d->rayleigh_mass;
  opt.rayleigh_stiffness = d->rayleigh_stiffness;
  opt.velocity_at_outputs = 1; /* monitor(): v only for the output steps' files */
  if (prob->opts->check_only) opt.steps = 0; /* `cupid check`: the checks before step 1 only */
  cupid_dynamics_hooks hooks = {.ctx = &o};
  for (int k = 0; k < m->n_constraints; k++) o.timed_constraints |= constraint_depends_on_time(&m->constraints[k]);
  CUPID_TRY(agreed(prob, check_beam_motion(prob, l.m_lumped != NULL)));
  for (int k = 0; k < m->n_loads; k++) o.timed_loads |= load_depends_on_time(&m->loads[k]);
  if (o.timed_constraints || o.timed_loads) hooks.conditions = conditions_now;
  if (m->has_peridynamics && m->pd.fracture.has_fracture) hooks.after_forces = break_bonds;
  if (prob->adaptive) { /* the zone grows where the trigger fires (issue 37) */
    o.adapt_every = cupid_problem_adaptive_every(prob);
    hooks.pause = adaptive_pause, hooks.stopped = adaptive_stopped;
  }
  if (hooks.conditions || hooks.after_forces || hooks.pause) opt.hooks = &hooks;
  prob->dyn.steps = opt.steps;
  prob->dyn.lumped = l.m_lumped != NULL;
  prob->dyn.matrix_free = mf;
  if (prob->method->recover)
    CUPID_TRY(cupid_malloc((size_t)prob->ndof, sizeof *o.u_view, "recovered displacements",
                           &o.u_view));
  if (!prob->opts->check_only) { /* checkpoints, and a resumption's state */
    double cost_s = 0, bytes = 0, files = 0;
    cupid_problem_run_cost(prob, &cost_s, &bytes, &files);
    CUPID_TRY(agreed(prob, cupid_problem_checkpoint_begin(prob, cost_s)));
    hooks.safe_point = save_point;
    opt.hooks = &hooks;
    if (prob->opts->resume) {
      CUPID_TRY(agreed(prob, resume_from_checkpoint(&o, v)));
      opt.resume = &o.restart;
      /* the conditions as the checkpoint's step left them (the load, the grips' values, the
       * clock of the expressions): the steps after it make their own, but a run resumed at its
       * last step makes none, and its report reads them (the applied load, the reactions) */
      if (hooks.conditions) {
        double *scratch = o.restart_vectors + 3 * (size_t)prob->ndof;
        CUPID_TRY(agreed(prob, hooks.conditions(hooks.ctx, (double)o.restart.step * opt.dt,
                                                scratch, scratch + prob->ndof)));
      }
    }
  }
  CUPID_TRY(agreed(prob, open_outputs(&o)));
  cupid_checkpoint_close(&o.resume);
  if (prob->opts->check_only)
    cupid_problem_progress(prob, "dynamics: the step %g of central differences checked as a "
                           "run checks it", opt.dt);
  else
    cupid_problem_progress(prob, "dynamics: %s, %lld steps of %g, %s mass",
                           d->integrator == CUPID_INTEGRATOR_NEWMARK ? "newmark" : "central",
                           (long long)opt.steps, opt.dt, l.m_lumped ? "lumped" : "consistent");
  t0 = cupid_wtime();
  CUPID_TRY(agreed(prob, row_bounds(prob, op, &l)));
  double stepping = 0.0; /* the time loops' seconds, over the segments of an adaptive run */
  if (prob->adaptive && opt.resume && !prob->opts->check_only)
    CUPID_TRY(trigger_at_resume(&o, op, &v, &l, &opt));
  for (;;) { /* one segment, unless an adaptive zone grows (then a segment per zone) */
    cupid_dynamics_system sys = {.K = prob->K, .M = l.M, .m_lumped = l.m_lumped, .bc = prob->bc,
                                 .f = prob->f_ext};
    mf = op && op->apply;
    prob->dyn.matrix_free = mf;
    cupid_dynamics_explicit_system esys = {.n = prob->ndof, .apply = mf ? op->apply : NULL,
                                           .ctx = mf ? op->ctx : NULL, .m_lumped = l.m_lumped,
                                           .bc = prob->bc, .f = prob->f_ext, .row_bound = l.row_bound};
    if (prob->slab) esys.apply = slab_apply, esys.ctx = prob, esys.part = &part;
    st = mf ? cupid_dynamics_run_explicit(&esys, &opt, prob->u, v, monitor, &o, &prob->dyn.info)
            : cupid_dynamics_run(&sys, &opt, prob->u, v, monitor, &o, &prob->dyn.info);
    stepping += prob->dyn.info.time_step_s;
    if (st == CUPID_ERR_ARGUMENT && d->integrator == CUPID_INTEGRATOR_CENTRAL &&
        prob->dyn.info.dt_critical > 0 && d->dt > prob->dyn.info.dt_critical)
      st = cupid_model_error(m, &d->mark, "%s%s", opt.resume == &o.paused ?
                             "after the adaptive zone grew: " : "", cupid_error_message());
    CUPID_TRY(st);
    if (!prob->dyn.info.stopped_at) break;
    int capped = 0;
    CUPID_TRY(convert_zone(&o, op, &v, &l, &capped));
    if (capped) break;
    opt.resume = &o.paused;
  }
  prob->dyn.info.time_step_s = stepping;
  if (prob->opts->check_only) goto cleanup; /* no step was taken, nothing to write */
  prob->phases[CUPID_PHASE_FACTORISATION] =
      (cupid_phase_record){prob->dyn.info.factor.time_factor, cupid_peak_memory(), 1};
  prob->phases[CUPID_PHASE_SOLVE] = (cupid_phase_record){cupid_wtime() - t0, cupid_peak_memory(), 1};
  if (d->integrator == CUPID_INTEGRATOR_NEWMARK) {
    prob->solve = prob->dyn.info.factor;
    prob->solved = 1;
  }
  if (mf) CUPID_TRY(agreed(prob, prob->slab ? slab_apply(prob, prob->u, prob->f_int)
                                            : op->apply(op->ctx, prob->u, prob->f_int)));
  else cupid_csr_matvec(prob->K, prob->u, prob->f_int);
  if (prob->slab) CUPID_TRY(cupid_problem_slab_collect(prob)); /* rank 0: the whole model */
  t0 = cupid_wtime();
  CUPID_TRY(zone_frame(&o, (double)prob->dyn.steps * d->dt, v)); /* the zone at the end */
  CUPID_TRY(finish_outputs(&o));
  cupid_problem_phase_end(prob, CUPID_PHASE_OUTPUT, t0);
  prob->dyn.done = 1;
  if (prob->ckpt.written)
    cupid_problem_progress(prob, "checkpoints: %lld written, %.3g s in all",
                           (long long)prob->ckpt.written, prob->ckpt.seconds);
  cupid_problem_progress(prob, "dynamics: done, %lld output steps, energy balance %.2e (relative)",
                     (long long)o.out_count, prob->dyn.info.max_balance);
  if (prob->dyn.info.max_balance > CUPID_ENERGY_BALANCE_BOUND && !prob->quiet &&
      (!prob->slab || cupid_petsc_rank() == 0))
    fprintf(stderr, "cupid: warning: the energy balance misses by %.2e of the run's largest "
            "energy (bound %.0e): the energies' bookkeeping or the time step is off; compare "
            "energies.csv's columns (docs/dynamics.md, \"Energies\")\n",
            prob->dyn.info.max_balance, CUPID_ENERGY_BALANCE_BOUND);
cleanup:
  /* the checkpoint recorded their lengths: --resume goes on (after an interrupt, or again
   * after a resumption that failed) */
  {
    const int keep = prob->ckpt.interrupted || prob->opts->resume;
    cupid_writer *writers[6] = {&o.history, &o.damage, &o.energies, &o.vtu, &o.exodus, &o.zones};
    for (int k = 0; k < 6; k++) cupid_writer_drop(writers[k], keep);
  }
  cupid_checkpoint_close(&o.resume);
  cupid_problem_vertices_free(&o.verts);
  cupid_problem_checkpoint_end(prob);
  cupid_free(&o.restart_vectors);
  free_constraint_nodes(&o);
  cupid_free(&o.u_view);
  layout_free(&l);
  cupid_free(&v);
  cupid_petsc_halo_destroy(&halo);
  cupid_pd_grid_destroy(&o.whole);
  return st;
}

void cupid_problem_dynamic_json(cupid_json js, const cupid_problem_state *prob) {
  const cupid_dynamic *d = &prob->model->analysis.dynamic;
  const cupid_dynamics_info *in = &prob->dyn.info;
  cupid_json_begin_object(js, "dynamic");
  int nm = d->integrator == CUPID_INTEGRATOR_NEWMARK;
  cupid_json_string(js, "integrator", nm ? "newmark" : "central");
  cupid_json_number(js, "dt", d->dt);
  cupid_json_integer(js, "steps", prob->dyn.steps);
  cupid_json_number(js, "duration", d->dt * (double)prob->dyn.steps);
  cupid_json_integer(js, "every", d->every);
  cupid_json_string(js, "mass", prob->dyn.lumped ? "lumped" : "consistent");
  cupid_json_string(js, "operator", prob->dyn.matrix_free ? "matrix-free" : "assembled");
  if (nm) {
    cupid_json_number(js, "newmark_beta", d->newmark_beta);
    cupid_json_number(js, "newmark_gamma", d->newmark_gamma);
  } else {
    cupid_json_number(js, "omega_max", in->omega_max);
    cupid_json_number(js, "dt_critical", in->dt_critical);
    cupid_json_number(js, "dt_guaranteed_stable", in->dt_bound);
    if (prob->dyn.matrix_free) cupid_json_integer(js, "lanczos_steps", in->lanczos_steps);
    cupid_json_string(js, "stable_step_check", in->omega_max == in->omega_max ? "lanczos" : "bound");
  }
  cupid_json_number(js, "rayleigh_mass", d->rayleigh_mass);
  cupid_json_number(js, "rayleigh_stiffness", d->rayleigh_stiffness);
  cupid_json_number(js, "time_stepping_s", in->time_step_s);
  cupid_json_begin_object(js, "final_energy");
  cupid_json_number(js, "kinetic", prob->dyn.energy.kinetic);
  cupid_json_number(js, "strain", prob->dyn.energy.strain);
  cupid_json_number(js, "damping_dissipated", prob->dyn.energy.damping);
  if (prob->damage) cupid_json_number(js, "fracture_dissipated", prob->dyn.energy.fracture);
  if (prob->adaptive) cupid_json_number(js, "conversion_added", prob->dyn.energy.conversion);
  cupid_json_number(js, "external_work", prob->dyn.energy.external);
  cupid_json_end_object(js);
  cupid_json_number(js, "max_energy_balance_relative", in->max_balance);
  cupid_json_number(js, "energy_balance_bound", CUPID_ENERGY_BALANCE_BOUND);
  if (prob->slab_ranks > 1) { /* the PD grid was stepped in z slabs, one per rank */
    cupid_json_begin_object(js, "pd_slabs");
    cupid_json_integer(js, "ranks", prob->slab_ranks);
    cupid_json_integer(js, "largest_slab_nodes", prob->slab_nodes_max);
    cupid_json_end_object(js);
  }
  cupid_json_end_object(js);
}
