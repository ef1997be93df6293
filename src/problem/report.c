/* Every output file of a run (model-format.md, `output:`): lines, pd_nodes.csv, pd.vtu +
 * model.pvd, plots and summary.json. Each file is written atomically (temp + rename). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "problem_internal.h"
#include "cupid/io.h"

static const char *phase_names[CUPID_PHASE_COUNT] = {"grid",          "assembly", "coupling",
                                                     "factorisation", "solve",    "output"};

static const char *region_name(cupid_region_kind r) {
  return r == CUPID_REGION_PD ? "PD" : r == CUPID_REGION_FE ? "FE" : "none";
}

static cupid_status join_path(const char *dir, const char *name, char *out, size_t len) {
  int n = snprintf(out, len, "%s/%s", dir, name);
  CUPID_CHECK(n > 0 && (size_t)n < len, CUPID_ERR_IO, "output path too long: %s/%s", dir, name);
  return CUPID_SUCCESS;
}


/* Write `line_<name>.csv`: s,x,y,z,ux,uy,uz,region, and its plot. */
static cupid_status write_line(cupid_problem_state *prob, const cupid_output_line *line) {
  char name[512], path[4096];
  snprintf(name, sizeof name, "line_%s.csv", line->name);
  CUPID_CALL(join_path(prob->writedir, name, path, sizeof path));
  cupid_atomic_file file = NULL;
  CUPID_CALL(cupid_atomic_open(path, &file));
  FILE *out = cupid_atomic_stream(file);
  double len = 0.0;
  for (int a = 0; a < 3; a++) len += (line->to[a] - line->from[a]) * (line->to[a] - line->from[a]);
  len = sqrt(len);
  fprintf(out, "s,x,y,z,ux,uy,uz,region\n");
  double umax[3] = {0, 0, 0};
  for (int k = 0; k < line->points; k++) {
    double t = line->points > 1 ? (double)k / (line->points - 1) : 0.0, p[3], u[3];
    for (int a = 0; a < 3; a++) p[a] = line->from[a] + t * (line->to[a] - line->from[a]);
    cupid_region_kind region;
    cupid_status st = cupid_problem_sample_point(prob, prob->u, p, u, NULL, &region);
    if (st != CUPID_SUCCESS) {
      cupid_atomic_abort(&file);
      return st;
    }
    fprintf(out, "%.10g,%.10g,%.10g,%.10g,%.10e,%.10e,%.10e,%s\n", t * len, p[0], p[1], p[2], u[0],
            u[1], u[2], region_name(region));
    for (int c = 0; c < 3; c++)
      if (u[c] == u[c] && fabs(u[c]) > umax[c]) umax[c] = fabs(u[c]);
  }
  CUPID_CALL(cupid_atomic_commit(&file));
  if (!prob->model->output.plots) return CUPID_SUCCESS;
  char stem[512], title[600];
  snprintf(stem, sizeof stem, "line_%s", line->name);
  snprintf(title, sizeof title, "%s: displacement along line '%s'",
           prob->model->title[0] ? prob->model->title : "cupid", line->name);
  cupid_plot_curve curves[3];
  for (int c = 0; c < 3; c++)
    curves[c] = (cupid_plot_curve){.csv = name, .xcol = 1, .ycol = 5 + c,
                                   .title = c == 0 ? "u_x" : c == 1 ? "u_y" : "u_z",
                                   .style = "linespoints pt 7 ps 0.4"};
  /* The axes say what is plotted, in the model's own quantities (the contract leaves units to
   * the user): the coordinate a line runs along, and the components that are not zero (the
   * plot leaves those out, cupid_plot). */
  char xlabel[64], ylabel[64];
  int axis = -1, moving = 0;
  for (int a = 0; a < 3; a++)
    if (line->to[a] != line->from[a]) axis = a, moving++;
  if (moving == 1) snprintf(xlabel, sizeof xlabel, "%c", "xyz"[axis]);
  else snprintf(xlabel, sizeof xlabel, "s (distance along the line)");
  cupid_plot_component_label(umax, ylabel, sizeof ylabel);
  int made = 0;
  return cupid_plot(prob->writedir, stem, title, xlabel, ylabel, 3, curves, &made);
}

/* `pd_nodes.csv`: x,y,z,ux,uy,uz,fx,fy,fz per real PD node; f = K u, the internal force,
 * which equals the applied load plus the reaction at every node. */
static cupid_status write_pd_nodes(cupid_problem_state *prob) {
  char path[4096];
  CUPID_CALL(join_path(prob->writedir, "pd_nodes.csv", path, sizeof path));
  cupid_atomic_file file = NULL;
  CUPID_CALL(cupid_atomic_open(path, &file));
  FILE *out = cupid_atomic_stream(file);
  const double *x = cupid_pd_grid_coords(prob->grid);
  const double *dmg = prob->damage; /* a damage column with pre-cracks or fracture */
  fprintf(out, "x,y,z,ux,uy,uz,fx,fy,fz%s\n", dmg ? ",damage" : "");
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    const double *p = x + 3 * i, *u = prob->u + 3 * i, *f = prob->f_int + 3 * i;
    fprintf(out, "%.10g,%.10g,%.10g,%.12e,%.12e,%.12e,%.12e,%.12e,%.12e", p[0], p[1], p[2], u[0],
            u[1], u[2], f[0], f[1], f[2]);
    if (dmg) fprintf(out, ",%.10g", dmg[i]);
    fputc('\n', out);
  }
  return cupid_atomic_commit(&file);
}

/* The PD nodes of the results (pd.vtu, model.exo): vertices with displacement, force,
 * material, the constrained components, damage, stress and (cut cells) the nodes' volumes. */
typedef struct {
  cupid_problem_vertices verts;
  double *mat, *fixed, *stress;
  cupid_vtu_array data[7];
  cupid_vtu_mesh mesh;
} pd_part;

static void pd_part_free(pd_part *p) {
  cupid_problem_vertices_free(&p->verts);
  cupid_free(&p->mat);
  cupid_free(&p->fixed);
  cupid_free(&p->stress);
}

static cupid_status pd_part_build(const cupid_problem_state *prob, pd_part *p) {
  const cupid_int n = prob->n_pd;
  memset(p, 0, sizeof *p);
  CUPID_CALL(cupid_problem_vertices_build(prob->grid, &p->verts));
  CUPID_CALL(cupid_malloc((size_t)n + 1, sizeof *p->mat, "VTU materials", &p->mat));
  CUPID_CALL(cupid_malloc((size_t)n + 1, sizeof *p->fixed, "VTU constraint flags", &p->fixed));
  if (prob->pd_stress) {
    /* VTK's symmetric-tensor order is xx yy zz xy yz xz; cupid's is xx yy zz yz xz xy. */
    static const int vtk_order[6] = {0, 1, 2, 5, 3, 4};
    CUPID_CALL(cupid_malloc((size_t)(6 * n), sizeof *p->stress, "VTU stresses", &p->stress));
    for (cupid_int i = 0; i < n; i++)
      for (int c = 0; c < 6; c++) p->stress[6 * i + c] = prob->pd_stress[6 * i + vtk_order[c]];
  }
  const int *m = cupid_pd_grid_materials(prob->grid);
  for (cupid_int i = 0; i < n; i++) {
    p->mat[i] = m[i];
    p->fixed[i] = prob->bc ? (double)(prob->bc->fixed[3 * i] + prob->bc->fixed[3 * i + 1] +
                                     prob->bc->fixed[3 * i + 2])
                          : 0.0;
  }
  int np = 0;
  p->data[np++] = (cupid_vtu_array){"displacement", 3, prob->u};
  p->data[np++] = (cupid_vtu_array){"force", 3, prob->f_int};
  p->data[np++] = (cupid_vtu_array){"material", 1, p->mat};
  p->data[np++] = (cupid_vtu_array){"constrained_components", 1, p->fixed};
  if (prob->damage) p->data[np++] = (cupid_vtu_array){"damage", 1, prob->damage};
  if (prob->pd_stress) p->data[np++] = (cupid_vtu_array){"stress", 6, p->stress};
  if (cupid_pd_grid_volume_fractions(prob->grid)) /* cut cells: each node's own volume */
    p->data[np++] = (cupid_vtu_array){"volume", 1, p->verts.volume};
  p->mesh = cupid_problem_vertices_mesh(&p->verts, p->data, np);
  return CUPID_SUCCESS;
}

/* The result files of the parts (`vtu`: beam.vtu, the 3D reconstruction of the beam as
 * hexahedra, pd.vtu, the PD nodes as vertices, and model.pvd, the collection ParaView opens
 * with both; `exodus`: model.exo, their one time step), each part built once for both. */
static cupid_status write_parts(cupid_problem_state *prob, int vtu, int exodus) {
  cupid_frame_part parts[2];
  const char *files[2];
  const double times[2] = {0.0, 0.0};
  const int ids[2] = {0, 1};
  cupid_cuf_vtu *beam = NULL;
  cupid_writer w = NULL;
  pd_part pd;
  char path[4096];
  int np = 0, have_pd = 0;
  cupid_status st = CUPID_SUCCESS;
  if (prob->beam) {
    CUPID_TRY(cupid_cuf_vtu_build(prob->beam, prob->u, 0, &beam));
    parts[np] = (cupid_frame_part){"beam", &beam->mesh, NULL};
    files[np++] = "beam.vtu";
  }
  if (prob->grid) {
    have_pd = 1;
    CUPID_TRY(pd_part_build(prob, &pd));
    parts[np] = (cupid_frame_part){"pd", &pd.mesh, pd.verts.volume};
    files[np++] = "pd.vtu";
  }
  for (int k = 0; k < np && vtu; k++) {
    CUPID_TRY(join_path(prob->writedir, files[k], path, sizeof path));
    CUPID_TRY(cupid_vtu_write(path, parts[k].mesh));
  }
  if (vtu) {
    CUPID_TRY(join_path(prob->writedir, "model.pvd", path, sizeof path));
    CUPID_TRY(cupid_pvd_write(path, np, files, times, ids));
  }
  if (exodus) {
    const cupid_writer_spec spec = {.dir = prob->writedir, .file = "model.exo",
                                    .title = prob->model->title};
    const cupid_frame f = {.step = 0, .time = 0.0, .n_parts = np, .parts = parts};
    CUPID_TRY(cupid_writer_create(&cupid_writer_exodus, &spec, &w));
    CUPID_TRY(cupid_writer_step(w, &f));
    CUPID_TRY(cupid_writer_end(&w));
  }
cleanup:
  cupid_writer_drop(&w, 0);
  cupid_cuf_vtu_destroy(&beam);
  if (have_pd) pd_part_free(&pd);
  return st;
}

static void json_vec3(cupid_json js, const char *key, const double v[3]) {
  cupid_json_begin_array(js, key);
  for (int c = 0; c < 3; c++) cupid_json_number(js, NULL, v[c]);
  cupid_json_end_array(js);
}

static void json_counts(cupid_json js, const cupid_problem_state *prob) {
  cupid_int nfixed = 0;
  for (cupid_int d = 0; d < prob->ndof && prob->bc; d++) nfixed += prob->bc->fixed[d];
  cupid_json_begin_object(js, "counts");
  cupid_json_integer(js, "fe_nodes", prob->beam ? prob->fe_info.n_fe_nodes : 0);
  cupid_json_integer(js, "fe_dofs", prob->n_fe_dofs);
  cupid_json_integer(js, "pd_nodes", prob->n_pd);
  cupid_json_integer(js, "pd_cut_cell_nodes", prob->n_cut_nodes);
  cupid_json_integer(js, "bonds", prob->n_bonds);
  cupid_json_integer(js, "pd_dofs", 3 * prob->n_pd);
  cupid_json_integer(js, "fictitious_nodes", prob->n_fictitious);
  cupid_json_integer(js, "dofs", prob->ndof);
  cupid_json_integer(js, "constrained_dofs", nfixed);
  cupid_json_integer(js, "matrix_nonzeros", prob->K ? cupid_csr_nnz(prob->K) : 0);
  cupid_json_end_object(js);
}

/* The beam's model (only with a beam): expansion, integration and whether the Poisson-locking
 * correction is on (docs/theory.md; auto turns it on for TE0 and TE1). */
static void json_beam(cupid_json js, const cupid_problem_state *prob) {
  static const char *integrations[3] = {"full", "reduced", "mitc"};
  const cupid_cuf_info *fi = &prob->fe_info;
  char expansion[32];
  if (fi->expansion == CUPID_EXPANSION_TE) snprintf(expansion, sizeof expansion, "TE%d", fi->te_order);
  else snprintf(expansion, sizeof expansion, "LE (L%d)", fi->le_nodes);
  cupid_json_begin_object(js, "beam");
  cupid_json_string(js, "expansion", expansion);
  cupid_json_string(js, "integration", integrations[fi->integration]);
  cupid_json_bool(js, "poisson_correction", fi->poisson_corrected);
  const cupid_beam *b = &prob->model->beam;
  if (b->section_mesh) { /* beam.section.mesh: the Gmsh file and what it gave */
    cupid_json_begin_object(js, "section_mesh");
    cupid_json_string(js, "file", b->section_mesh);
    cupid_json_integer(js, "elements", b->n_section_elements);
    cupid_json_integer(js, "nodes", b->n_section_nodes);
    cupid_json_end_object(js);
  }
  cupid_json_end_object(js);
}

/* The PD bodies' geometry files ({geometry: FILE} regions and holes): the file and the
 * triangles of its surface. */
static void json_geometry(cupid_json js, const cupid_problem_state *prob) {
  const cupid_peridynamics *pd = &prob->model->pd;
  int any = 0;
  for (int k = 0; k < pd->n_regions + pd->n_holes; k++) {
    const cupid_shape *s = k < pd->n_regions ? &pd->regions[k].shape : &pd->holes[k - pd->n_regions].shape;
    if (s->kind != CUPID_SHAPE_GEOMETRY) continue;
    if (!any++) cupid_json_begin_array(js, "geometry");
    cupid_json_begin_object(js, NULL);
    cupid_json_string(js, "of", k < pd->n_regions ? "region" : "hole");
    cupid_json_integer(js, "index", k < pd->n_regions ? k : k - pd->n_regions);
    cupid_json_string(js, "file", s->file ? s->file : "");
    cupid_json_integer(js, "triangles", cupid_surface_num_triangles(s->surface));
    cupid_json_end_object(js);
  }
  if (any) cupid_json_end_array(js);
}

static void json_phases(cupid_json js, const cupid_problem_state *prob) {
  cupid_json_begin_object(js, "phases");
  for (int p = 0; p < CUPID_PHASE_COUNT; p++) {
    cupid_json_begin_object(js, phase_names[p]);
    cupid_json_number(js, "time_s", prob->phases[p].used ? prob->phases[p].seconds : 0.0);
    cupid_json_integer(js, "peak_memory_bytes", prob->phases[p].used ? prob->phases[p].peak_memory : 0);
    cupid_json_end_object(js);
  }
  cupid_json_end_object(js);
}

static void json_solver(cupid_json js, const cupid_problem_state *prob) {
  cupid_json_begin_object(js, "solver");
  if (prob->solved) {
    cupid_json_string(js, "method", prob->solve.method);
    cupid_json_integer(js, "equations", prob->solve.n);
    cupid_json_integer(js, "matrix_nonzeros", prob->solve.nnz_matrix);
    cupid_json_number(js, "factor_nonzeros", prob->solve.nnz_factor);
    cupid_json_number(js, "residual", prob->solve.residual);
    cupid_json_number(js, "backward_error", prob->solve.backward_error);
    if (prob->solver_reason[0]) cupid_json_string(js, "choice", prob->solver_reason);
    cupid_json_string(js, "engine", prob->engine->name);
    if (prob->estimate.seconds > 0) { /* what the choice rested on (bench/estimates.sh) */
      cupid_json_begin_object(js, "estimate");
      cupid_json_string(js, "path", prob->estimate.what);
      cupid_json_number(js, "seconds", prob->estimate.seconds);
      cupid_json_number(js, "bytes", prob->estimate.bytes);
      cupid_json_end_object(js);
    }
    if (prob->engine && prob->engine->iterative) { /* issue 6: what the Krylov solve did */
      cupid_json_integer(js, "ranks", prob->solve.ranks);
      cupid_json_integer(js, "iterations", prob->solve.iterations);
      cupid_json_string(js, "ksp_type", prob->solve.ksp_type);
      cupid_json_string(js, "pc_type", prob->solve.pc_type);
      cupid_json_string(js, "converged_reason", prob->solve.converged_reason);
      cupid_json_string(js, "operator", prob->solve.matrix_free ? "matrix-free" : "assembled");
      if (prob->slab_ranks > 1) { /* the PD grid was split into z slabs, one per rank */
        cupid_json_begin_object(js, "pd_slabs");
        cupid_json_integer(js, "ranks", prob->slab_ranks);
        cupid_json_integer(js, "largest_slab_nodes", prob->slab_nodes_max);
        cupid_json_end_object(js);
      }
    }
  } else {
    cupid_json_string(js, "method", "none");
    cupid_json_null(js, "residual");
  }
  cupid_json_end_object(js);
}

static cupid_status json_points(cupid_json js, const cupid_problem_state *prob) {
  const cupid_output *o = &prob->model->output;
  cupid_json_begin_array(js, "points");
  for (int k = 0; k < o->n_points; k++) {
    const cupid_output_point *pt = &o->points[k];
    double u[3], s[6];
    cupid_region_kind region;
    CUPID_CALL(cupid_problem_sample_point(prob, prob->u, pt->at, u, s, &region));
    cupid_json_begin_object(js, NULL);
    cupid_json_string(js, "name", pt->name);
    cupid_json_number(js, "x", pt->at[0]);
    cupid_json_number(js, "y", pt->at[1]);
    cupid_json_number(js, "z", pt->at[2]);
    cupid_json_number(js, "ux", u[0]);
    cupid_json_number(js, "uy", u[1]);
    cupid_json_number(js, "uz", u[2]);
    cupid_json_string(js, "region", region_name(region));
    if (pt->stress) {
      static const char *names[6] = {"sxx", "syy", "szz", "syz", "sxz", "sxy"};
      for (int c = 0; c < 6; c++) cupid_json_number(js, names[c], s[c]);
    }
    cupid_json_end_object(js);
  }
  cupid_json_end_array(js);
  return CUPID_SUCCESS;
}

static cupid_status write_summary(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  char path[4096];
  CUPID_CALL(join_path(prob->writedir, "summary.json", path, sizeof path));
  cupid_atomic_file file = NULL;
  cupid_json js = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_atomic_open(path, &file));
  CUPID_TRY(cupid_json_create(cupid_atomic_stream(file), &js));
  static const char *types[3] = {"static", "dynamic", "evaluate"};
  cupid_json_begin_object(js, NULL);
  cupid_json_string(js, "cupid_version", cupid_version());
  cupid_json_string(js, "title", m->title);
  cupid_json_string(js, "model_file", m->file);
  cupid_json_string(js, "analysis", types[m->analysis.type]);
  cupid_json_integer(js, "threads", cupid_num_threads());
  /* how the threads waited (the CLI and the Python package set PASSIVE unless told: main.c) */
  const char *wait = getenv("OMP_WAIT_POLICY");
  cupid_json_string(js, "omp_wait_policy", wait ? wait : "");
  json_counts(js, prob);
  if (prob->beam) json_beam(js, prob);
  json_geometry(js, prob);
  if (prob->grid) cupid_json_number(js, "pd_volume", prob->pd_volume); /* the nodes' volumes */
  json_phases(js, prob);
  json_solver(js, prob);
  if (prob->arlequin_penalty > 0) { /* method arlequin: the penalty in use and its scale */
    cupid_json_begin_object(js, "coupling");
    cupid_json_string(js, "method", "arlequin");
    cupid_json_number(js, "penalty", prob->arlequin_penalty);
    cupid_json_string(js, "penalty_choice", m->coupling.penalty_auto ? "auto" : "given");
    cupid_json_number(js, "pd_node_stiffness", prob->arlequin_node_stiffness);
    cupid_json_number(js, "penalty_over_node_stiffness",
                      prob->arlequin_penalty / prob->arlequin_node_stiffness);
    cupid_json_end_object(js);
  }
  json_vec3(js, "applied_load_sum", prob->load_sum);
  json_vec3(js, "reaction_sum", prob->reaction_sum); /* the model's constraints */
  if (prob->growth.held) json_vec3(js, "held_reaction_sum", prob->growth.held_reaction);
  if (m->analysis.type == CUPID_ANALYSIS_EVALUATE) { /* the internal forces' resultant */
    double sum[3], scale;
    CUPID_TRY(cupid_problem_internal_force_sum(prob, sum, &scale));
    json_vec3(js, "internal_force_sum", sum);
    cupid_json_number(js, "internal_force_magnitude", scale);
  }
  if (m->analysis.type != CUPID_ANALYSIS_DYNAMIC) { /* a static balance; dynamics: the energy's */
    double imbalance[3];
    for (int c = 0; c < 3; c++) imbalance[c] = prob->load_sum[c] + prob->reaction_sum[c];
    json_vec3(js, "equilibrium_imbalance", imbalance);
  } else {
    cupid_json_number(js, "energy_balance", prob->dyn.info.max_balance);
  }
  cupid_problem_quality_json(js, prob);
  if (prob->dyn.done) cupid_problem_dynamic_json(js, prob);
  cupid_problem_fracture_json(js, prob);
  cupid_problem_adaptive_json(js, prob);
  cupid_json_number(js, "total_time_s", cupid_wtime() - prob->t_start);
  cupid_json_integer(js, "peak_memory_bytes", cupid_peak_memory());
  CUPID_TRY(json_points(js, prob));
  cupid_json_end_object(js);
  CUPID_TRY(cupid_json_status(js));
  cupid_json_destroy(&js);
  CUPID_TRY(cupid_atomic_commit(&file));
cleanup:
  cupid_json_destroy(&js);
  cupid_atomic_abort(&file);
  return st;
}


cupid_status cupid_problem_pd_stress(cupid_problem_state *prob) {
  if (!prob->grid || prob->pd_stress || !prob->u) return CUPID_SUCCESS;
  CUPID_CALL(cupid_calloc((size_t)(6 * prob->n_pd), sizeof(double), "PD stresses", &prob->pd_stress));
  return cupid_pd_operator_stress(prob->op, prob->u, prob->pd_stress);
}

cupid_status cupid_problem_report(cupid_problem_state *prob) {
  const cupid_output *o = &prob->model->output;
  double t0 = cupid_wtime();
  CUPID_CALL(cupid_problem_fracture_damage(prob));
  if (cupid_problem_needs_stress(prob)) CUPID_CALL(cupid_problem_pd_stress(prob));
  for (int k = 0; k < o->n_lines; k++) CUPID_CALL(write_line(prob, &o->lines[k]));
  if (o->pd_nodes && prob->grid) CUPID_CALL(write_pd_nodes(prob));
  /* dynamic runs wrote their VTU series, and runs of steps their model.exo, as they went */
  const int vtu = o->vtu && prob->model->analysis.type != CUPID_ANALYSIS_DYNAMIC;
  const int exodus = o->exodus && !cupid_problem_writes_frames(prob);
  if (vtu || exodus) CUPID_CALL(write_parts(prob, vtu, exodus));
  /* The output phase is recorded before summary.json so that the file reports it. */
  cupid_problem_phase_end(prob, CUPID_PHASE_OUTPUT, t0);
  return write_summary(prob);
}

