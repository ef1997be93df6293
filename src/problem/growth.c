/* Load steps and quasi-static crack growth (`analysis: {type: static, steps: N}`,
 * model-format.md; shared/reference/fracture.md, "Quasi-static crack growth"; issue 17).
 *
 * Every load and prescribed value ramps as k/N over N steps. Without fracture each step is one
 * linear solve. With fracture the scheme is sequentially linear (Ni, Zaccariotto, Zhu,
 * Galvanetto 2019): solve, break the bonds over their limit (all of them, or the most critical
 * one: `fracture.per_iteration`), solve again at the same load, until none is over; the
 * stiffness is secant (intact bonds only). Each solve is linear, so a crack is broken at the
 * load it first fails at (the sub-steps of load_step: the crack's path and the peak do not
 * hang on N), and the load factor of the first break is exact. Nodes that lose their support
 * (at most 2 intact bonds, or a fragment cut off from every support) are released: held where
 * they are, counted and reported, so that a run does not end in a singular matrix because of
 * fracture; held nodes that carry load are a collapse, which stops the run (check_collapse).
 * Outputs: damage.csv one row per step (load factor, iterations, counts, the reaction of every
 * constraint), its plot, and the fracture block of summary.json. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "growth_run.h"
#include "method.h"


/* What the run keeps per DOF and per PD node of the problem's layout (setup_layout makes it;
 * an adaptive zone's conversion frees it for the new layout: growth_release). */
static void free_layout(growth_run *g) {
  cupid_free(&g->f_full);
  cupid_free(&g->g_full);
  cupid_free(&g->fixed0);
  cupid_free(&g->anchored);
  cupid_free(&g->weak_scan);
  cupid_free(&g->mech_seen);
  cupid_free(&g->masks);
  cupid_free(&g->T);
  for (int k = 0; k < 4; k++) cupid_free(&g->w[k]);
  cupid_free(&g->near_fixed);
  cupid_free(&g->u_before);
  cupid_direct_factor_destroy(&g->F);
  cupid_growth_downdate_free(&g->dd);
  growth_journal_free(&g->journal);
  cupid_problem_vertices_free(&g->verts);
}

static void growth_free(growth_run *g) {
  free_layout(g);
  cupid_free(&g->release);
  cupid_free(&g->weak);
  cupid_free(&g->tie);
  cupid_free(&g->u1);
  cupid_writer_drop(&g->csv, 0);
  cupid_writer_drop(&g->exodus, 0);
  cupid_writer_drop(&g->zones, 0);
  cupid_pd_grid_destroy(&g->whole);
  cupid_checkpoint_close(&g->resume);
  cupid_free(&g->react);
  cupid_free(&g->points);
  cupid_free(&g->row);
  cupid_growth_mf_free(&g->mf);
  cupid_growth_lu_free(&g->lu);
}

/* The DOFs each constraint fixes (one byte a DOF and constraint), and the unit translations:
 * the reaction of constraint k along c is sum over its DOFs d of (f_int - f_ext)[d] T_c[d]. The
 * constraint is applied alone to a scratch copy of the conditions (its PD part; a beam's through
 * the beam). */
static cupid_status constraint_masks(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  const cupid_model_t *m = prob->model;
  const size_t n = (size_t)prob->ndof, nk = (size_t)m->n_constraints;
  cupid_dirichlet scratch = NULL, saved = prob->bc;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_calloc(n * (nk ? nk : 1), 1, "constraint masks", &g->masks));
  CUPID_TRY(cupid_calloc(3 * n, sizeof *g->T, "translation vectors", &g->T));
  CUPID_TRY(cupid_problem_translations(prob, g->T));
  for (size_t k = 0; k < nk; k++) {
    CUPID_TRY(cupid_dirichlet_create(prob->ndof, &scratch));
    prob->bc = scratch;
    if (prob->grid) st = cupid_problem_pd_prescribe(prob, &m->constraints[k]);
    if (st == CUPID_SUCCESS && prob->beam &&
        cupid_cuf_constraint_apply(prob->beam, m, &m->constraints[k], scratch) != CUPID_SUCCESS)
      cupid_error_clear(); /* a constraint on PD nodes only: nothing of the beam */
    prob->bc = saved;
    CUPID_TRY(st);
    memcpy(g->masks + k * n, scratch->fixed, n);
    cupid_dirichlet_destroy(&scratch);
  }
cleanup:
  prob->bc = saved;
  cupid_dirichlet_destroy(&scratch);
  return st;
}

/* The file of the steps: damage.csv with pre-cracks or fracture (model-format.md), else
 * load_steps.csv; the output points' displacements make the load-displacement curves. */
static const char *csv_name(const cupid_problem_state *prob) {
  return cupid_problem_has_damage(prob) ? "damage.csv" : "load_steps.csv";
}

/* The steps' file's columns (write_row fills a row in this order): step, t, load_factor,
 * iterations, the damage counts, the next break's load factor, every constraint's reaction and
 * every output point's displacement. *names: the names made here (freed by the caller). */
static cupid_status csv_columns(const cupid_problem_state *prob, cupid_column **cols, int *n,
                                char (**names)[200]) {
  const cupid_model_t *m = prob->model;
  static const cupid_column head[4] = {{"step", 1}, {"t", 0}, {"load_factor", 0},
                                       {"iterations", 1}};
  static const cupid_column damage[5] = {{"broken_bonds", 1}, {"damaged_nodes", 1},
                                         {"max_damage", 0}, {"nodes_broken", 1},
                                         {"released_nodes", 1}};
  const int most = 4 + 5 + 2 + 3 * (m->n_constraints + m->output.n_points);
  CUPID_CALL(cupid_calloc((size_t)most, sizeof **cols, "CSV columns", cols));
  CUPID_CALL(cupid_calloc((size_t)most, sizeof **names, "CSV columns", names));
  cupid_column *c = *cols;
  int k = 0;
  for (int j = 0; j < 4; j++) c[k++] = head[j];
  if (cupid_problem_has_damage(prob))
    for (int j = 0; j < 5; j++) c[k++] = damage[j];
  if (m->has_peridynamics && m->pd.fracture.has_fracture)
    c[k++] = (cupid_column){"next_break_load_factor", 0};
  if (prob->adaptive) c[k++] = (cupid_column){"pd_nodes", 1};
  for (int j = 0; j < m->n_constraints; j++)
    for (int a = 0; a < 3; a++) {
      snprintf((*names)[k], sizeof **names, "reaction_%d_%c", j, "xyz"[a]);
      c[k] = (cupid_column){(*names)[k], 0}, k++;
    }
  for (int j = 0; j < m->output.n_points; j++)
    for (int a = 0; a < 3; a++) {
      snprintf((*names)[k], sizeof **names, "%s_u%c", m->output.points[j].name, "xyz"[a]);
      c[k] = (cupid_column){(*names)[k], 0}, k++;
    }
  *n = k;
  return CUPID_SUCCESS;
}

/* The PD nodes of model.exo's frames (output.exodus), on the rank that writes (a slab run:
 * rank 0's whole grid; collective there). */
static cupid_status frame_vertices(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  const cupid_model_t *m = prob->model;
  cupid_status st = CUPID_SUCCESS;
  if (!(m->output.exodus || (prob->adaptive && m->output.vtu)) || !prob->grid) return CUPID_SUCCESS;
  if (prob->slab && prob->writedir) st = cupid_pd_grid_create_from_model(m, &g->whole);
  if (st == CUPID_SUCCESS && (g->whole || !prob->slab))
    st = cupid_problem_vertices_build(g->whole ? g->whole : prob->grid, &g->verts);
  return prob->slab ? cupid_problem_slab_agree(st) : st;
}

/* The writers, on the rank that writes files (io.h): the steps' file and, with
 * output.exodus, model.exo; a resumption continues them from its checkpoint (issue 36). */
static cupid_status open_writers(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  const cupid_model_t *m = prob->model;
  cupid_status st = CUPID_SUCCESS;
  if (!prob->writedir) return CUPID_SUCCESS;
  cupid_column *cols = NULL;
  char(*names)[200] = NULL;
  int n = 0;
  char key[64];
  snprintf(key, sizeof key, "writer %s", csv_name(prob));
  CUPID_TRY(csv_columns(prob, &cols, &n, &names));
  cupid_writer_spec spec = {.dir = prob->writedir, .file = csv_name(prob), .columns = cols,
                            .n_columns = n, .resume = g->resume, .key = key};
  CUPID_TRY(cupid_writer_create(&cupid_writer_csv, &spec, &g->csv));
  if (m->output.exodus) {
    spec = (cupid_writer_spec){.dir = prob->writedir, .file = "model.exo", .title = m->title,
                               .resume = g->resume, .key = "writer model.exo"};
    CUPID_TRY(cupid_writer_create(&cupid_writer_exodus, &spec, &g->exodus));
  }
  if (prob->adaptive && m->output.vtu) { /* the zone at each conversion (zone_frame) */
    spec = (cupid_writer_spec){.dir = prob->writedir, .file = "adaptive.pvd", .title = m->title,
                               .resume = g->resume, .key = "writer adaptive.pvd"};
    CUPID_TRY(cupid_writer_create(&cupid_writer_vtu, &spec, &g->zones));
  }
cleanup:
  cupid_free(&cols);
  cupid_free(&names);
  cupid_checkpoint_close(&g->resume);
  return st;
}

/* A load step's frame for model.exo: the beam's reconstruction and the PD nodes with their
 * displacement, internal force and damage (collective on a slab run). */
static cupid_status write_frame(growth_run *g, int step, double lambda) {
  cupid_problem_state *prob = g->prob;
  if (!prob->model->output.exodus) return CUPID_SUCCESS;
  const cupid_vtu_array fields[3] = {{"displacement", 3, prob->u}, {"force", 3, prob->f_int},
                                     {"damage", 1, prob->damage}};
  return cupid_problem_frame_write(prob, &g->verts, step, lambda, prob->u, fields, 3, &g->exodus, 1);
}

/* adaptive.pvd (adaptive zones with output.vtu): the zone and its fields at the settled
 * solution before each conversion, and at the end of the run; frame k (its files'
 * number) has the load factor as its time (two conversions of one step: two frames at one
 * time, the later the zone it grew to first). */
static cupid_status zone_frame(growth_run *g, double lambda) {
  cupid_problem_state *prob = g->prob;
  /* collective on slabs: every rank gathers, rank 0 (which holds the writer) writes */
  if (!(prob->adaptive && prob->model->output.vtu)) return CUPID_SUCCESS;
  const cupid_vtu_array fields[3] = {{"displacement", 3, prob->u}, {"force", 3, prob->f_int},
                                     {"damage", 1, prob->damage}};
  return cupid_problem_frame_write(prob, &g->verts, ++g->zone_frames, lambda, prob->u, fields, 3,
                                   &g->zones, 1);
}

/* The reaction of each constraint k into g->react[3 k ..]: the work of (f_int - f_ext) on its
 * DOFs against the unit translations (a slab: on its owned DOFs and, on rank 0, the beam's,
 * which every rank holds whole, summed over the ranks). */
static void add_reaction(const growth_run *g, const unsigned char *fixed, size_t d0, size_t d1,
                         double r[3]) {
  const cupid_problem_state *prob = g->prob;
  const size_t n = (size_t)prob->ndof;
  for (size_t d = d0; d < d1; d++)
    if (fixed[d])
      for (int c = 0; c < 3; c++) r[c] += (prob->f_int[d] - prob->f_ext[d]) * g->T[(size_t)c * n + d];
}

/* The held nodes carry more than COLLAPSE_SHARE of the forces on the body (held_forces): the
 * crack has cut the load path of a load the supports can no longer take (a traction on a part
 * cut loose, an Arlequin beam end whose PD piece broke through), and what the held nodes hold
 * is a support the model never had. 1e-6: a fragment without load, or a body cut through under
 * a grip, leaves its held nodes round-off (1e-20 of the run's forces on the growth test's
 * plate); a collapse puts nearly all of the load on them (0.997 on a plate pulled apart). */
#define COLLAPSE_SHARE 1e-6
/* A weakly held node's pull is a force of the holding (held_forces): 3% of the forces on a plate
 * pulled apart, mid-step. Weakly held nodes that carry a tenth of them at a settled step are a
 * support all the same: the beam without a notch whose adaptive zone `within` kept small (issue
 * 37) went on after its crack cut the section, reloaded through its weakly held nodes to 0.35
 * of the forces, and its peak envelope read 141.7 N against the 124.2 N it carried. */
#define WEAK_COLLAPSE_SHARE 0.1
/* A tied node's spring (tie_mechanisms) pulls it to its reference position with k |u|, k 1e-8
 * of K's largest diagonal entry: following the body, a tie carries 1e-8 of a stiff node's force
 * at that displacement (4e-17 of the forces on the plate of verification.fracture_growth; an
 * estimate for the notched C-beam, whose beam DOFs are stiffer than its PD nodes: some 4e-8 of
 * the forces on the body a tie); a mechanism that takes load along its mode puts
 * that load on its spring. Ties whose springs carry more than 1e-4 of the forces on the body are
 * a collapse: thousands of ties that only follow it stay below. */
#define TIE_COLLAPSE_SHARE 1e-4

/* The share of the forces on the body that the held nodes carry: H / (H + S), H the sum over
 * held nodes of |f_int - f_ext| at the node, S the applied load's magnitude |P| plus the
 * magnitudes of the constraints' reactions |R_k| (g->react, just computed), the largest of the
 * run (so that a body cut through under a grip compares round-off with the load it had). A
 * node of a fragment cut off from every support, or one a factorisation found singular, is
 * held to remove a rigid mode of what breaking left loose: it carries nothing but round-off
 * and the load applied to the loose part, so a share above COLLAPSE_SHARE is load carried by
 * supports the model never had: the body has collapsed (check_collapse). The magnitudes are
 * summed node by node so that a fragment held under a moment, whose forces cancel, still
 * counts. A weakly held node (at most 2 intact bonds, or all in one plane) is apart: held
 * where it is, its few bonds to the body pull on it as the body moves on (24 N of the 800 N
 * of a plate pulled apart, mid-step), a force of the holding, not of a lost load path; its
 * share is g->weak_share, reported at the end. Every held node's force is in the vector sum
 * for summary.json (held_reaction_sum), apart from the constraints' reactions. */
static void held_forces(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  const size_t n = (size_t)prob->ndof;
  double sums[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0}; /* the held vector sum, H (held, weak, tied) */
  double load[3] = {0.0, 0.0, 0.0};
  cupid_int a = 0, b = prob->n_pd;
  if (prob->slab) a = prob->part.owned_first, b = prob->part.owned_last;
  for (cupid_int i = a; g->release && i < b; i++) {
    if (!g->release[i]) continue;
    double r[3];
    for (int c = 0; c < 3; c++) r[c] = prob->f_int[3 * i + c] - prob->f_ext[3 * i + c];
    for (int c = 0; c < 3 && g->tie && g->tie[i]; c++) /* tied, then held (hold_loaded_ties):
                                                           its spring is a support of its own,
                                                           no force of the body's */
      r[c] -= g->tie_k * prob->u[3 * i + c];
    for (int c = 0; c < 3; c++) sums[c] += r[c];
    sums[g->weak[i] ? 4 : 3] += sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  }
  for (cupid_int i = a; g->tie && i < b; i++) { /* a tie's spring (tie_mechanisms) */
    if (!g->tie[i] || g->release[i]) continue;
    const double *u = prob->u + 3 * i;
    for (int c = 0; c < 3; c++) sums[c] += g->tie_k * u[c];
    sums[5] += g->tie_k * sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  }
  for (size_t d = prob->slab ? 3 * (size_t)a : 0; d < (prob->slab ? 3 * (size_t)b : n); d++)
    for (int c = 0; c < 3; c++) load[c] += prob->f_ext[d] * g->T[(size_t)c * n + d];
  if (prob->slab && cupid_petsc_rank() == 0) /* the beam, which every rank holds whole */
    for (size_t d = (size_t)prob->fe_offset; d < n; d++)
      for (int c = 0; c < 3; c++) load[c] += prob->f_ext[d] * g->T[(size_t)c * n + d];
  if (prob->slab) {
    double all[8] = {sums[0], sums[1], sums[2], sums[3], sums[4], load[0], load[1], load[2]};
    cupid_petsc_sum_doubles(all, 8);
    memcpy(sums, all, 5 * sizeof *all);
    memcpy(load, all + 5, 3 * sizeof *all);
  }
  double S = sqrt(load[0] * load[0] + load[1] * load[1] + load[2] * load[2]);
  for (int k = 0; k < prob->model->n_constraints; k++) {
    const double *r = g->react + 3 * k;
    S += sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  }
  if (S > g->force_scale) g->force_scale = S;
  S = g->force_scale; /* a body cut through under a grip: round-off against round-off */
  memcpy(prob->growth.held_reaction, sums, 3 * sizeof *sums);
  g->held_share = sums[3] > 0.0 ? sums[3] / (sums[3] + S) : 0.0;
  g->weak_share = sums[4] > 0.0 ? sums[4] / (sums[4] + S) : 0.0;
  g->tie_share = sums[5] > 0.0 ? sums[5] / (sums[5] + S) : 0.0;
}

static void reactions(growth_run *g) {
  const cupid_problem_state *prob = g->prob;
  const size_t n = (size_t)prob->ndof;
  const int nk = prob->model->n_constraints;
  for (int k = 0; k < nk; k++) {
    const unsigned char *fixed = g->masks + (size_t)k * n;
    double *r = g->react + 3 * k;
    r[0] = r[1] = r[2] = 0.0;
    if (!prob->slab) {
      add_reaction(g, fixed, 0, n, r);
      continue;
    }
    add_reaction(g, fixed, 3 * (size_t)prob->part.owned_first, 3 * (size_t)prob->part.owned_last, r);
    if (cupid_petsc_rank() == 0) add_reaction(g, fixed, (size_t)prob->fe_offset, n, r);
  }
  if (prob->slab) cupid_petsc_sum_doubles(g->react, 3 * nk);
  held_forces(g);
}

/* The load factor at which the next bond breaks, the crack as it is: each solve is linear, so
 * the settled solution at lambda scaled by 1 / ratio brings the most critical bond exactly to
 * its limit, and the reactions scale with it. These are the tops of the sawtooth of
 * sequentially linear analysis (Rots et al.), so the peak load does not hang on the step size.
 * Exact while no node is held (a held node keeps its displacement as the load scales).
 * 0 when no breakable bond is stretched. */
static double next_break(const growth_run *g, double lambda) {
  const double lc = g->next_ratio > 0.0 ? lambda / g->next_ratio : 0.0;
  return isfinite(lc) ? lc : 0.0; /* a limit no stretch comes near (s0 = 1e307) */
}

/* A settled largest ratio per unit load factor below CUT_THROUGH times the first solve's:
 * the crack has cut the load path. What is left of the stretches is the solve's round-off
 * (1e-11 of the first one's on a SENB cut through by a grip's displacement), which the
 * scaling by 1 / ratio of next_break would blow up into a "next break" at 10^10 times the
 * load and a peak reaction of round-off times 10^11 (measured: 60 N against the true 16 N).
 * A crack that still leaves a load path lowers the stretches at a given grip displacement by
 * far less (the SENB before its cut: to 0.13 of the first). */
#define CUT_THROUGH 1e-6

static int carries_load(const growth_run *g, double lambda, double ratio) {
  return !(g->ratio_per_load > 0.0 && lambda > 0.0 && ratio / lambda < CUT_THROUGH * g->ratio_per_load);
}

/* Each solve's point of the envelope, kept where it is a constraint's largest reaction (by
 * magnitude). Each solve is linear in the load at its crack, so the crack as this solve has it
 * takes the load factor mu = lambda min(1, 1 / ratio) with the reactions R mu / lambda: with
 * ratio > 1 (bonds over their limit: the first solve of the step where the first bond breaks,
 * or a re-solve after breaks) the load at which its most critical bond reaches its limit,
 * the top of a tooth of the sawtooth of sequentially linear analysis (Rots et al.); with
 * ratio <= 1 (settled) the load applied. So every break is on the envelope, whichever step it
 * falls in, and nothing is extrapolated past the loading applied (a model whose bonds never
 * come near their limit peaks at load factor 1). Exact while no node is held (a held node
 * keeps its displacement as the load scales). */
static void track_peaks(growth_run *g, int step, double lambda, double ratio) {
  cupid_problem_state *prob = g->prob;
  /* held nodes that carry load (check_collapse's stop): the reactions are the holding's, not
   * the body's (a solve on the way to the collapse read 200 N on the beam without a notch of
   * examples/fracture, whose peak is 126 N) */
  if (!prob->growth.peak || lambda <= 0.0 || g->held_share > COLLAPSE_SHARE) return;
  const double mu = ratio > 1.0 ? lambda / ratio : lambda;
  for (int k = 0; k < prob->model->n_constraints; k++) {
    double r[3];
    for (int c = 0; c < 3; c++) r[c] = g->react[3 * k + c] * (mu / lambda);
    double *p = prob->growth.peak + 6 * k;
    const double mag = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (!(mag > p[0])) continue;
    p[0] = mag, p[1] = mu, p[2] = step;
    for (int c = 0; c < 3; c++) p[3 + c] = r[c];
  }
}

/* The step's row: every rank of a slab run takes part in the sums, rank 0 writes. */
static cupid_status write_row(growth_run *g, int step, double lambda, int iterations) {
  cupid_problem_state *prob = g->prob;
  const cupid_model_t *m = prob->model;
  reactions(g);
  if (!g->csv && !prob->slab) return CUPID_SUCCESS;
  CUPID_CALL(cupid_problem_fracture_damage(prob));
  const int damage = cupid_problem_has_damage(prob);
  const cupid_int nodes_broken = damage ? cupid_problem_fracture_nodes_broken(prob) : 0;
  for (int k = 0; k < m->output.n_points; k++) {
    cupid_region_kind region;
    CUPID_CALL(cupid_problem_sample_point(prob, prob->u, m->output.points[k].at, g->points + 3 * k,
                                          NULL, &region));
  }
  if (prob->slab) CUPID_CALL(cupid_problem_slab_points(prob, g->points));
  for (int c = 0; c < 3 && m->output.n_points > 0; c++) g->u0[c] = g->points[c];
  if (!g->csv) return CUPID_SUCCESS;
  /* the columns of csv_columns; t is the load factor: the contract's columns step,t,... read
   * as a pseudo-time */
  double *row = g->row;
  int k = 0;
  row[k++] = step, row[k++] = lambda, row[k++] = lambda, row[k++] = iterations;
  if (damage) {
    row[k++] = (double)prob->broken_bonds, row[k++] = (double)prob->damaged_nodes;
    row[k++] = prob->max_damage, row[k++] = (double)nodes_broken, row[k++] = (double)g->released;
  }
  if (m->has_peridynamics && m->pd.fracture.has_fracture) row[k++] = next_break(g, lambda);
  if (prob->adaptive) row[k++] = (double)prob->n_pd;
  for (int j = 0; j < 3 * m->n_constraints; j++) row[k++] = g->react[j];
  for (int j = 0; j < 3 * m->output.n_points; j++) row[k++] = g->points[j];
  const cupid_frame frame = {.step = step, .time = lambda, .row = row};
  return cupid_writer_step(g->csv, &frame);
}

/* damage.png (broken bonds and damaged nodes against the load factor) and, with an output
 * point, load_displacement.png: the reactions of the first constraint against the point's
 * displacement along the axis it moves most. */
static cupid_status plots(const growth_run *g) {
  const cupid_problem_state *prob = g->prob;
  const cupid_model_t *m = prob->model;
  if (!prob->writedir || !m->output.plots) return CUPID_SUCCESS;
  const char *title = m->title[0] ? m->title : "cupid", *csv = csv_name(prob);
  char t[600];
  int made = 0;
  if (cupid_problem_has_damage(prob)) {
    cupid_plot_curve dc[2] = {
        {.csv = csv, .xname = "load_factor", .yname = "broken_bonds", .title = "broken bonds"},
        {.csv = csv, .xname = "load_factor", .yname = "damaged_nodes", .title = "damaged nodes"}};
    snprintf(t, sizeof t, "%s: fracture", title);
    CUPID_CALL(cupid_plot(prob->writedir, "damage", t, "load factor", "count", 2, dc, &made));
  }
  if (m->output.n_points == 0 || m->n_constraints == 0) return CUPID_SUCCESS;
  int c = 0;
  for (int a = 1; a < 3; a++)
    if (fabs(g->u0[a]) > fabs(g->u0[c])) c = a;
  char xname[200], xlabel[240], ynames[3][40], ytitles[3][60];
  snprintf(xname, sizeof xname, "%s_u%c", m->output.points[0].name, "xyz"[c]);
  snprintf(xlabel, sizeof xlabel, "u_%c at '%s'", "xyz"[c], m->output.points[0].name);
  cupid_plot_curve rc[3];
  for (int a = 0; a < 3; a++) {
    snprintf(ynames[a], sizeof ynames[a], "reaction_0_%c", "xyz"[a]);
    snprintf(ytitles[a], sizeof ytitles[a], "reaction of constraint 0, %c", "xyz"[a]);
    rc[a] = (cupid_plot_curve){.csv = csv, .xname = xname, .yname = ynames[a],
                               .title = ytitles[a], .style = "linespoints pt 7 ps 0.6"};
  }
  snprintf(t, sizeof t, "%s: load-displacement", title);
  return cupid_plot(prob->writedir, "load_displacement", t, xlabel, "force", 3, rc, &made);
}

/* Anchored PD nodes: a constrained DOF, or the coupling zone (tied to the beam). */
static void anchor(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  for (cupid_int i = 0; i < prob->n_pd; i++)
    g->anchored[i] = (unsigned char)(g->fixed0[3 * i] || g->fixed0[3 * i + 1] ||
                                     g->fixed0[3 * i + 2] || (prob->protect && prob->protect[i]));
}

/* ---- Ties (issue 37) ----
 * A few nodes that lost most of their bonds can move together as a mechanism although each is
 * held in every direction by its own bonds (the notched C-beam's flanges leave such clusters by
 * the hundred in their last ligaments): K is singular there, and the factorisation or downdate
 * that finds it costs a factorisation of the zone per node (15-19 s on the C-beam's grown
 * zone). cupid_pd_operator_mechanisms() finds them before the solve, cluster by cluster; the
 * node that completes each mechanism is tied to its reference position by a weak spring of
 * TIE_STIFFNESS times K's largest diagonal entry on each of its DOFs (added to K after every
 * assembly, and to a live factor as a rank-three update), not held at its displacement: a held
 * node stays where the last solve left it while the body relaxes or moves on, and pulls on its
 * bonds (on the plate of verification.fracture_growth, held one round before its cut: 1% of
 * the grip's peak afterwards), where a tied node follows the body (the mechanism's mode costs
 * no bond energy: the spring alone fixes it) and carries k |u|. Its forces count with the held
 * nodes' (held_forces), so that a tie that took load (a loaded cluster, not a mechanism) is a
 * collapse. 1e-8: far above round-off
 * in the factor (its pivot ratio must stay above CUPID_DIRECT_PIVOT_TOL times the order: 1e-8
 * is that bound at 5 million equations) and far below the 1e-6 share of the forces that makes
 * held nodes a collapse. The run's own factor only (SPD on a direct engine): elsewhere the
 * engine's breakdown still names the node to hold. */
#define TIE_STIFFNESS 1e-8

cupid_status growth_tie_matrix(cupid_csr_t *K, cupid_int n, const cupid_int *dofs, double k) {
  for (cupid_int t = 0; t < n; t++) {
    const cupid_int d = dofs[t], b = K->bs;
    double *a = cupid_csr_find(K, d / b, d / b);
    CUPID_CHECK(a, CUPID_ERR_INTERNAL, "growth: no diagonal entry of K at DOF %lld", (long long)d);
    a[(d % b) * b + d % b] += k;
  }
  return CUPID_SUCCESS;
}

cupid_status growth_tie_factor(cupid_direct_factor F, cupid_int n, const cupid_int *dofs, double k) {
  cupid_int *colptr = NULL;
  double *vals = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_malloc((size_t)n + 1, sizeof *colptr, "tie columns", &colptr));
  CUPID_TRY(cupid_malloc((size_t)n + 1, sizeof *vals, "tie columns", &vals));
  for (cupid_int t = 0; t <= n; t++) colptr[t] = t;
  for (cupid_int t = 0; t < n; t++) vals[t] = sqrt(k);
  CUPID_TRY(cupid_direct_factor_update(F, n, colptr, dofs, vals));
cleanup:
  cupid_free(&colptr);
  cupid_free(&vals);
  return st;
}

/* The DOFs of the nodes whose tie is in state @p state, into a new *dofs (*n of them). */
static cupid_status tie_dofs(growth_run *g, unsigned char state, cupid_int **dofs, cupid_int *n) {
  const cupid_problem_state *prob = g->prob;
  *n = 0;
  for (cupid_int i = 0; i < prob->n_pd; i++) *n += 3 * (g->tie[i] == state);
  if (*n == 0) return CUPID_SUCCESS;
  CUPID_CALL(cupid_malloc((size_t)*n, sizeof **dofs, "tied DOFs", dofs));
  cupid_int t = 0;
  for (cupid_int i = 0; i < prob->n_pd; i++)
    for (int c = 0; c < 3 && g->tie[i] == state; c++) (*dofs)[t++] = 3 * i + c;
  return CUPID_SUCCESS;
}

/* The springs of the ties in state @p state into K; their state becomes @p next. */
static cupid_status tie_into(growth_run *g, cupid_csr_t *K, unsigned char state, unsigned char next) {
  cupid_int *dofs = NULL, n = 0;
  CUPID_CALL(tie_dofs(g, state, &dofs, &n));
  cupid_status st = n ? growth_tie_matrix(K, n, dofs, g->tie_k) : CUPID_SUCCESS;
  cupid_free(&dofs);
  for (cupid_int i = 0; i < g->prob->n_pd && st == CUPID_SUCCESS; i++)
    if (g->tie[i] == state) g->tie[i] = next;
  return st;
}

/* A K just assembled (fresh: every tie's spring; otherwise K has them but the new ones). */
static cupid_status tie_assembled(growth_run *g, int fresh) {
  cupid_problem_state *prob = g->prob;
  if (!g->tie || !g->tied) return CUPID_SUCCESS;
  if (g->tie_k == 0.0) { /* the first tie: its stiffness from K's largest diagonal entry */
    double top = 0.0, *d = g->w[3];
    CUPID_CALL(cupid_csr_diagonal(prob->K, d));
    for (cupid_int k = 0; k < prob->ndof; k++) top = fmax(top, fabs(d[k]));
    g->tie_k = TIE_STIFFNESS * top;
  }
  if (fresh) {
    CUPID_CALL(tie_into(g, prob->K, 1, 1));
    CUPID_CALL(tie_into(g, prob->K, 3, 3));
  }
  return tie_into(g, prob->K, 2, 3);
}

/* The lost shares the next mechanism check compares with (g->mech_seen): the present ones, at
 * the run's start, after a conversion (a new layout) and after a resumption. The bands of
 * damaged nodes are searched around the nodes that lost bonds since (src/pd/fracture.c), and at
 * a step's end, where checkpoints are written, no bond has broken since the last check: a
 * resumed run compares with what the uninterrupted one did. */
static void mechanisms_seen(growth_run *g) {
  if (g->mech_seen) cupid_pd_operator_lost_shares(g->prob->op, 0, g->prob->n_pd, g->mech_seen);
}

/* The nodes that complete a mechanism of a few (cupid_pd_operator_mechanisms), tied: state 2
 * (in neither K nor the factor yet). Held and tied nodes count as fixed. */
static cupid_status tie_mechanisms(growth_run *g, int step) {
  cupid_problem_state *prob = g->prob;
  unsigned char *scan = g->weak_scan;
  cupid_int count = 0;
  for (cupid_int i = 0; i < prob->n_pd; i++) scan[i] = g->release[i] || g->tie[i];
  if (!g->band_check) mechanisms_seen(g); /* no node touched: no band searched */
  CUPID_CALL(cupid_pd_operator_mechanisms(prob->op, 0, prob->n_pd, prob->u, g->mech_seen, scan,
                                          &count));
  if (count == 0) return CUPID_SUCCESS;
  const double *x = cupid_pd_grid_coords(prob->grid);
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    if (scan[i] != 2 || g->release[i] || g->tie[i]) continue;
    g->tie[i] = 2;
    if (count <= 3)
      cupid_problem_progress(prob, "growth: step %d: node (%g, %g, %g) completes a mechanism of a "
                             "few nodes: tied by a weak spring", step, x[3 * i], x[3 * i + 1],
                             x[3 * i + 2]);
  }
  g->tied += count;
  if (count > 3)
    cupid_problem_progress(prob, "growth: step %d: %lld nodes complete mechanisms of a few nodes: "
                           "tied by weak springs", step, (long long)count);
  return CUPID_SUCCESS;
}

/* Release the nodes that lost their support: held at their displacement now. */
static cupid_status release_unsupported(growth_run *g, int step) {
  cupid_problem_state *prob = g->prob;
  cupid_int fresh = 0, weak = 0;
  /* which of the nodes released now are weakly held (held_forces tells them apart): the owned
   * ones, on a copy of the flags, the first check of the searches below */
  const cupid_int a = prob->slab ? prob->part.owned_first : 0;
  const cupid_int b = prob->slab ? prob->part.owned_last : prob->n_pd;
  memcpy(g->weak_scan, g->release, (size_t)prob->n_pd);
  CUPID_CALL(cupid_pd_operator_weakly_held(prob->op, a, b, g->weak_scan, &weak));
  for (cupid_int i = a; i < b && weak > 0; i++)
    if (g->weak_scan[i] == 2) g->weak[i] = 1;
  if (prob->slab)
    CUPID_CALL(cupid_growth_mf_unsupported(prob, &g->mf, g->anchored, g->release, &fresh));
  else
    CUPID_CALL(cupid_pd_operator_unsupported(prob->op, g->anchored, g->release, &fresh));
  if (g->tie) CUPID_CALL(tie_mechanisms(g, step));
  if (fresh == 0) return CUPID_SUCCESS;
  const double *x = cupid_pd_grid_coords(prob->grid);
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    if (g->release[i] != 2) continue;
    g->release[i] = 1;
    for (int c = 0; c < 3; c++) CUPID_CALL(cupid_dirichlet_fix(prob->bc, 3 * i + c, prob->u[3 * i + c]));
    if (fresh <= 3 && !prob->slab) /* a slab run: the count below */
      cupid_problem_progress(prob, "growth: step %d: node (%g, %g, %g) lost its support: held",
                             step, x[3 * i], x[3 * i + 1], x[3 * i + 2]);
  }
  g->released += fresh;
  if (fresh > 3 || prob->slab)
    cupid_problem_progress(prob, "growth: step %d: %lld node%s lost their support: held", step,
                           (long long)fresh, fresh == 1 ? "" : "s");
  return cupid_dirichlet_finalize(prob->bc);
}

/* A PD DOF whose node is not held yet: what hold_singular_node can hold. */
static int loose_node(const growth_run *g, cupid_int dof) {
  const cupid_problem_state *prob = g->prob;
  return prob->grid && dof >= 0 && dof < 3 * prob->n_pd && !g->release[dof / 3];
}

/* The mechanisms that no ball of a band holds whole (the notched C-beam's flanges: nodes that
 * lost 74-87% of their bonds inside damaged bands of more than 400 nodes, 2 of 48 found by a
 * search of every ball; docs/theory.md), found as the factorisation of the grown zone finds
 * them, one node a factorisation, but on the block of the damaged nodes alone (those that
 * lost CUPID_PD_MECHANISM_DAMAGE of their bond weight, as the bands'; everything else fixed,
 * held and tied nodes too): a mechanism of that block with its outside fixed is one of the
 * whole body (its mode, zero outside, strains no bond there either), and its factorisation
 * costs a fraction of the grown zone's. Each node it names is tied (state 2) and the block
 * factorised again without it, until the block factorises; at most BAND_FACTOR_MAX nodes (the
 * grown zone's factorisation names any left). *count: the nodes tied. */
#define BAND_FACTOR_MAX 1000
static cupid_status tie_band_factorised(growth_run *g, cupid_int *count) {
  cupid_problem_state *prob = g->prob;
  const cupid_int n_pd = prob->n_pd, n = prob->K->nrows * prob->K->bs;
  cupid_dirichlet bc = NULL;
  cupid_direct_factor F = NULL;
  cupid_status st = CUPID_SUCCESS;
  *count = 0;
  double *share = NULL;
  CUPID_TRY(cupid_malloc((size_t)n_pd + 1, sizeof *share, "lost shares", &share));
  cupid_pd_operator_lost_shares(prob->op, 0, n_pd, share);
  CUPID_TRY(cupid_dirichlet_create(n, &bc));
  cupid_int band = 0;
  for (cupid_int d = 0; d < n; d++) {
    const cupid_int i = d / 3;
    const int free = d < 3 * n_pd && share[i] >= CUPID_PD_MECHANISM_DAMAGE && !g->release[i] &&
                     !g->tie[i];
    if (!free) bc->fixed[d] = 1, bc->value[d] = 0.0;
    band += free;
  }
  if (band == 0) goto cleanup;
  while (*count < BAND_FACTOR_MAX) {
    CUPID_TRY(cupid_dirichlet_finalize(bc));
    cupid_solve_info info = {0};
    info.failed_dof = -1;
    st = cupid_direct_factor_create(prob->K, bc, &F, &info);
    cupid_direct_factor_destroy(&F);
    if (st != CUPID_ERR_NUMERIC) break; /* the block factorises: no mechanism left in it */
    const cupid_int d = info.failed_dof;
    st = CUPID_SUCCESS;
    cupid_error_clear();
    if (d < 0 || d >= 3 * n_pd || g->tie[d / 3]) break; /* not a band node: left as it was */
    const cupid_int i = d / 3;
    g->tie[i] = 2;
    (*count)++;
    for (int c = 0; c < 3; c++) bc->fixed[3 * i + c] = 1;
  }
  CUPID_TRY(st);
cleanup:
  cupid_direct_factor_destroy(&F);
  cupid_dirichlet_destroy(&bc);
  cupid_free(&share);
  return st;
}

/* A DOF that a failed downdate or factorisation of the run's own factor names (its pivot
 * vanished): its node completes a mechanism that the cluster check did not test (the notched
 * C-beam's flanges leave such nodes in damaged bands of hundreds of nodes, beyond the cluster
 * check's 48, MECH_CLUSTER_MAX in src/pd/fracture.c), tied as tie_mechanisms ties (state 2: K
 * takes its spring at once, tie_assembled; the factor at its next factorisation). The
 * downdate that names it saves the engine's factorisation that would have broken down to name
 * it again: one factorisation a node instead of two. *tied = 0 where it is no PD node of such a
 * run, or one held or tied already (the engine's breakdown then names a node to hold,
 * hold_singular_node). The others of its kind that the breaks left are then found on the
 * damaged nodes' block alone (tie_band_factorised) and tied with it. */
static cupid_status tie_singular(growth_run *g, cupid_int dof, int *tied) {
  cupid_problem_state *prob = g->prob;
  *tied = g->tie && loose_node(g, dof) && !g->tie[dof / 3];
  if (!*tied) return CUPID_SUCCESS;
  const cupid_int i = dof / 3;
  g->tie[i] = 2;
  g->tied++;
  g->tied_singular++;
  cupid_error_clear();
  const double *x = cupid_pd_grid_coords(prob->grid) + 3 * i;
  const int quiet = prob->quiet; /* a re-solve is quiet (load_step); this is news */
  prob->quiet = g->quiet;
  cupid_problem_progress(prob, "growth: step %d: node (%g, %g, %g) left singular: tied by a weak "
                         "spring", g->step, x[0], x[1], x[2]);
  cupid_int more = 0;
  if (g->band_factor) CUPID_CALL(tie_band_factorised(g, &more));
  if (more > 0) {
    g->tied += more;
    g->tied_singular += more;
    cupid_problem_progress(prob, "growth: step %d: the damaged nodes' block factorised alone: %lld "
                           "more node%s left singular: tied", g->step, (long long)more,
                           more == 1 ? "" : "s");
  }
  prob->quiet = quiet;
  return tie_assembled(g, 0);
}

/* The solve just made put load on ties (g->tie_share above TIE_COLLAPSE_SHARE): the mode a
 * spring fixes is loaded, and the solve moved it by that load over 1e-8 of K. A tie whose spring
 * carries more than its part of that bound (TIE_COLLAPSE_SHARE of the forces over the ties) is
 * held where the last solve before this one left it, as a node left singular was held before
 * ties (hold_singular_node), and the solve is dropped (u as it was): a held node that carries
 * load is a collapse at the settled step (check_collapse), as it was. *held = 0 where none is
 * (the ties' share is then spread over many: check_collapse stops at this solve). */
static cupid_status hold_loaded_ties(growth_run *g, int step, int *held) {
  cupid_problem_state *prob = g->prob;
  const double bound = TIE_COLLAPSE_SHARE * g->force_scale / (double)(g->tied > 0 ? g->tied : 1);
  *held = 0;
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    if (!g->tie[i] || g->release[i]) continue;
    const double *u = prob->u + 3 * i;
    if (g->tie_k * sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) <= bound) continue;
    g->release[i] = 1;
    g->released++;
    (*held)++;
    for (int c = 0; c < 3; c++)
      CUPID_CALL(cupid_dirichlet_fix(prob->bc, 3 * i + c, g->u_before[3 * i + c]));
  }
  if (*held == 0) return CUPID_SUCCESS;
  memcpy(prob->u, g->u_before, (size_t)prob->ndof * sizeof *prob->u);
  cupid_problem_progress(prob, "growth: step %d: %d tied node%s took load (a loaded mechanism): "
                         "held", step, *held, *held == 1 ? "" : "s");
  return cupid_dirichlet_finalize(prob->bc);
}

/* A factorisation that broke down at a PD node after bonds broke: that node lost its support
 * in a way the checks of cupid_pd_operator_unsupported() miss (a mechanism of several nodes):
 * it is held too. The matrix-free path has no factorisation: CG on a mechanism diverges or
 * stalls, and the node its iterate moved furthest is held (growth_matrix_free.c). *held = 0
 * when the failure names no such node (the solve's error then stands). */
static cupid_status hold_singular_node(growth_run *g, int step, int *held) {
  cupid_problem_state *prob = g->prob;
  const cupid_int dof = prob->solve.failed_dof;
  *held = 0;
  if (g->matrix_free) { /* no factorisation to name it: where CG's iterate ran away */
    double x[3];
    CUPID_CALL(cupid_growth_mf_hold_runaway(prob, &g->mf, g->release, x, held));
    if (!*held) return CUPID_SUCCESS;
    cupid_error_clear();
    g->released++;
    cupid_problem_progress(prob, "growth: step %d: node (%g, %g, %g) ran away in the PETSc solve "
                           "(a mechanism): held", step, x[0], x[1], x[2]);
    return CUPID_SUCCESS;
  }
  if (!loose_node(g, dof)) return CUPID_SUCCESS;
  const cupid_int i = dof / 3;
  cupid_error_clear();
  g->release[i] = 1;
  g->released++;
  for (int c = 0; c < 3; c++) CUPID_CALL(cupid_dirichlet_fix(prob->bc, 3 * i + c, prob->u[3 * i + c]));
  CUPID_CALL(cupid_dirichlet_finalize(prob->bc));
  const double *x = cupid_pd_grid_coords(prob->grid) + 3 * i;
  cupid_problem_progress(prob, "growth: step %d: node (%g, %g, %g) left singular: held", step,
                         x[0], x[1], x[2]);
  *held = 1;
  return CUPID_SUCCESS;
}

/* ---- K after breaks: assembled whole, or patched in the rows the breaks changed ----
 * A round of breaks changes the rows of the broken bonds' nodes alone (bond-based), a few
 * hundred of the grid's; assembling K whole again and comparing it with the last to find the
 * bonds' terms cost a third of a coupled SENB's growth (h = 1: 7.9 s of 28.7 in the assembly,
 * 3.3 s in the comparison). The method's update_rows assembles those rows again in place, to
 * the bit as a whole assembly would, and the downdate's terms are read off those rows alone.
 * K keeps its pattern, with zero blocks where bonds broke: a product or a downdate reads the
 * same values, but a factorisation orders by the pattern, so K is assembled whole again
 * before one (whole_k), and every solve is what it was (CUPID_GROWTH_WHOLE_K=1 assembles it
 * whole every time, as before; verification.fracture_growth compares the two). */
static int cmp_node(const void *a, const void *b) {
  const cupid_int x = *(const cupid_int *)a, y = *(const cupid_int *)b;
  return (x > y) - (x < y);
}

/* K assembled (whole, where it was NULL: the operator's record of changed rows starts again
 * from it), and the ties' springs that it lacks. */
static cupid_status assemble_k(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  const int fresh = prob->K == NULL;
  CUPID_CALL(prob->method->assemble(prob));
  if (fresh && prob->op) {
    cupid_int *rows = NULL, n = 0;
    int all = 0;
    CUPID_CALL(cupid_pd_operator_take_changed(prob->op, &rows, &n, &all)); /* all in K now */
    cupid_free(&rows);
    g->tracked_k = prob->K, g->tracked_op = prob->op, g->patched = 0;
  }
  return tie_assembled(g, fresh);
}

/* A patched K assembled whole again (before a factorisation reads its pattern). */
static cupid_status whole_k(growth_run *g) {
  if (!g->patched) return CUPID_SUCCESS;
  cupid_csr_destroy(&g->prob->K);
  return assemble_k(g);
}

/* The rows of @p rows (the nodes whose bonds broke) assembled again in place; *Kold (when
 * asked): a copy of those rows as they were. The tied nodes among them take their springs
 * again; then the new ties' (tie_assembled). */
static cupid_status patch_rows(growth_run *g, const cupid_int *rows, cupid_int n, cupid_csr *Kold) {
  cupid_problem_state *prob = g->prob;
  if (Kold) CUPID_CALL(cupid_growth_rows_copy(prob->K, rows, n, Kold));
  CUPID_CALL(prob->method->update_rows(prob, rows, n));
  for (cupid_int t = 0; t < n && g->tie && g->tied; t++) {
    const cupid_int i = rows[t];
    if (i >= prob->n_pd || (g->tie[i] != 1 && g->tie[i] != 3)) continue;
    const cupid_int dofs[3] = {3 * i, 3 * i + 1, 3 * i + 2};
    CUPID_CALL(growth_tie_matrix(prob->K, 3, dofs, g->tie_k));
  }
  g->patched |= n > 0;
  return tie_assembled(g, 0);
}

/* The rows that changed since K was assembled, when K can be patched there: *all = 1 when it
 * is to be assembled whole (no update_rows, LPS, a K the record does not follow). */
static cupid_status changed_rows(growth_run *g, cupid_int **rows, cupid_int *n, int *all) {
  cupid_problem_state *prob = g->prob;
  *rows = NULL, *n = 0, *all = 1;
  if (!g->patch || !prob->method->update_rows || !prob->K || !prob->op || g->tracked_k != prob->K ||
      g->tracked_op != prob->op)
    return CUPID_SUCCESS;
  return cupid_pd_operator_take_changed(prob->op, rows, n, all);
}

/* ---- Re-solves after bonds break (issue 17, item 3) ----
 * A break changes K by a few bonds (bond-based: a rank-one term each; LPS: the dilatation
 * terms of both families), so the factor of the K of the last factorisation stays a close
 * preconditioner: CG on the current K (assembled again, cheap next to a factorisation)
 * preconditioned by that factor converges in about as many iterations as the rank of the
 * change, and the factor is renewed once the CG iterations since it cost as much as it did
 * (CHOLMOD's operation count against two triangular solves and a product per iteration,
 * weighted) or a solve needs more than CG_REFACTOR iterations: at worst about twice the cost
 * of the best sequence of factorisations (bench/growth.sh measures both ways).
 * Nodes held since the factorisation are fixed in the current system: the preconditioner is
 * the factor restricted to the current free DOFs (P F^-1 P^T, still symmetric positive
 * definite). Each load step after a break starts with a new factor: a mechanism of several
 * nodes that cupid_pd_operator_unsupported() does not see takes no load, and CG would leave
 * it where the preconditioner puts it, where the factorisation finds it singular and the
 * node is held (hold_singular_node). A solve by a new factor is checked the same way as a CG
 * solve (its residual to CG_RTOL, refined by CG if not), and one that fails goes to the
 * engine's solve, with its refinement and messages. The scalar products are summed in one
 * thread, so the iterates, hence the bonds that break, do not depend on the thread count. */
#define CG_RTOL 1e-12
#define CG_REFACTOR 60
#define CG_FLOP_WEIGHT 5.0
#define DOWNDATE_MAX_SHARE 50 /* a round of more than n / 50 broken bonds refactorises */

static double dot_free(const cupid_dirichlet_t *bc, cupid_int n, const double *a, const double *b) {
  double s = 0.0;
  for (cupid_int d = 0; d < n; d++)
    if (!bc->fixed[d]) s += a[d] * b[d];
  return s;
}

/* z = P F^-1 P^T r: r's free entries through the factor, z zero on the fixed DOFs. */
static cupid_status precondition(growth_run *g, const double *r, double *z) {
  return cupid_direct_factor_solve_masked(g->F, g->prob->bc, r, z);
}

/* b = f - K u_c on the free DOFs (u_c: the prescribed values), 0 on the fixed ones, into b
 * (t: scratch); returns |b|. */
static double lifted_rhs(growth_run *g, double *t, double *b) {
  const cupid_problem_state *prob = g->prob;
  const cupid_dirichlet_t *bc = prob->bc;
  const cupid_int n = prob->ndof;
  const cupid_csr_t *K = prob->K;
  for (cupid_int d = 0; d < n; d++) t[d] = bc->fixed[d] ? bc->value[d] : 0.0;
  /* K t is zero but in the rows next to the fixed DOFs (K's pattern is symmetric: SPD): only
   * those computed, a product of a few rows where a whole one was a quarter of a round */
  unsigned char *near = g->near_fixed;
  memset(near, 0, (size_t)K->nrows);
  for (cupid_int r = 0; r < K->nrows; r++) {
    const int bs = K->bs;
    int any = 0;
    for (int c = 0; c < bs; c++) any |= bc->fixed[bs * r + c];
    for (cupid_int p = K->rowptr[r]; any && p < K->rowptr[r + 1]; p++) near[K->col[p]] = 1;
  }
  cupid_csr_matvec_marked(K, t, near, b);
  for (cupid_int d = 0; d < n; d++) b[d] = bc->fixed[d] ? 0.0 : prob->f_ext[d] - b[d];
  return sqrt(dot_free(bc, n, b, b));
}

/* Factorise the current K and solve (u: the prescribed values on the fixed DOFs). */
static cupid_status factor_solve(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  const cupid_dirichlet_t *bc = prob->bc;
  const cupid_int n = prob->ndof;
  CUPID_CALL(whole_k(g)); /* the whole assembly's pattern, which orders the factor */
  double t0 = cupid_wtime(), *t = g->w[0], *r = g->w[1];
  cupid_direct_factor_destroy(&g->F);
  cupid_solve_info info;
  memset(&info, 0, sizeof info);
  cupid_status st = cupid_direct_factor_create(prob->K, bc, &g->F, &info);
  prob->solve = info;
  if (st == CUPID_ERR_NUMERIC) g->failed_factorisations++, g->t_factor += cupid_wtime() - t0;
  if (st != CUPID_SUCCESS) return st;
  g->factorisations++;
  g->bonds_at_factor = prob->broken_bonds;
  for (cupid_int i = 0; g->tie && i < prob->n_pd; i++)
    if (g->tie[i] == 3) g->tie[i] = 1; /* K's springs, now in F */
  CUPID_CALL(growth_journal_factored(g)); /* what a resumption replays (growth_resume.c) */
  g->factor_flops = info.flops_factor;
  const double nnz_k = (double)prob->K->rowptr[prob->K->nrows] * prob->K->bs * prob->K->bs;
  g->cg_iteration_flops = 4.0 * info.nnz_factor + 2.0 * nnz_k;
  g->cg_since_factor = 0;
  g->t_factor += cupid_wtime() - t0;
  lifted_rhs(g, t, r);
  CUPID_CALL(cupid_direct_factor_solve(g->F, r, prob->u));
  for (cupid_int d = 0; d < n; d++)
    if (bc->fixed[d]) prob->u[d] = bc->value[d];
  return CUPID_SUCCESS;
}

/* CG on the current K from the last u, preconditioned by the factor, to a residual of CG_RTOL
 * |f_f - K_fc u_c|; *done = 0 when it did not get there within CG_REFACTOR iterations (u then
 * as it was). A u already there costs one product and counts as no CG solve. */
static cupid_status cg_solve(growth_run *g, int *done) {
  cupid_problem_state *prob = g->prob;
  const cupid_dirichlet_t *bc = prob->bc;
  const cupid_int n = prob->ndof;
  double t0 = cupid_wtime(), *x = g->w[0], *r = g->w[1], *z = g->w[2], *p = prob->f_int;
  double *q = g->w[3];
  *done = 0;
  const double scale = lifted_rhs(g, x, r);
  for (cupid_int d = 0; d < n; d++) x[d] = bc->fixed[d] ? bc->value[d] : prob->u[d];
  cupid_csr_matvec(prob->K, x, r);
  for (cupid_int d = 0; d < n; d++) r[d] = bc->fixed[d] ? 0.0 : prob->f_ext[d] - r[d];
  const double r0 = sqrt(dot_free(bc, n, r, r));
  int it = 0;
  if (r0 > CG_RTOL * scale) {
    CUPID_CALL(precondition(g, r, z));
    memcpy(p, z, (size_t)n * sizeof *p);
    double rz = dot_free(bc, n, r, z);
    for (it = 1; it <= CG_REFACTOR; it++) {
      cupid_csr_matvec(prob->K, p, q);
      const double pq = dot_free(bc, n, p, q);
      if (!(pq > 0.0)) break; /* not positive definite on the free DOFs: refactorise */
      const double alpha = rz / pq;
      for (cupid_int d = 0; d < n; d++)
        if (!bc->fixed[d]) x[d] += alpha * p[d], r[d] -= alpha * q[d];
      if (sqrt(dot_free(bc, n, r, r)) <= CG_RTOL * scale) break;
      CUPID_CALL(precondition(g, r, z));
      const double rz1 = dot_free(bc, n, r, z), beta = rz1 / rz;
      rz = rz1;
      for (cupid_int d = 0; d < n; d++) p[d] = bc->fixed[d] ? 0.0 : z[d] + beta * p[d];
    }
    if (it > CG_REFACTOR || sqrt(dot_free(bc, n, r, r)) > CG_RTOL * scale) return CUPID_SUCCESS;
  }
  memcpy(prob->u, x, (size_t)n * sizeof *x);
  prob->solve.residual = scale > 0.0 ? sqrt(dot_free(bc, n, r, r)) / scale : 0.0;
  *done = 1;
  if (it == 0) return CUPID_SUCCESS;
  g->cg_solves++;
  g->cg_iterations += it;
  g->t_cg += cupid_wtime() - t0;
  prob->solve.iterations = it;
  /* Renew the factor once the CG iterations since it cost as much as it did (the rule of
   * renting until the rent paid equals the price: never more than twice the best choice in
   * hindsight). By operation counts, not clocks: the choice changes the iterates (to
   * round-off), so it must not depend on the machine's load, or the bonds that break would
   * not be the same in every run. A triangular solve's operation is memory-bound, about
   * CG_FLOP_WEIGHT times the time of one in the factorisation's dense blocks (measured on the
   * plate of bench/growth.sh: 1.35 against 6.6 Gflop/s). */
  /* a downdated factor is the current K's: its one iteration is the check, not rent */
  g->cg_since_factor += g->downdate ? it - 1 : it;
  if ((double)g->cg_since_factor * CG_FLOP_WEIGHT * g->cg_iteration_flops > g->factor_flops)
    cupid_direct_factor_destroy(&g->F);
  return CUPID_SUCCESS;
}

/* Bring the factor to the K that broken bonds left (Kold: the K it factors): downdated by the
 * bonds' rank-one terms, it is that K's factor again, and CG on it converges at once. A change
 * that is no sum of bond terms (LPS) turns downdating off for the run (CG on the stale factor
 * as before). The nodes held since the last round (release_unsupported) leave the factor first
 * (cupid_direct_factor_hold: a few rank-two modifications, where the run used to factorise
 * the notched C-beam's grown zone again for each node its flanges' last ligaments left loose);
 * the nodes tied since (tie_mechanisms) go in next, as an update by their springs; a downdate
 * that leaves it indefinite all the same (a mechanism larger than tie_mechanisms tests) drops
 * the factor, and the next solve is the engine's at once, whose breakdown names the node to
 * hold (solve, hold_singular_node). */
static cupid_status downdate_tied(growth_run *g, cupid_csr_t *Kold, const cupid_int *tied,
                                  cupid_int n_tied, int partial, const cupid_int *rows,
                                  cupid_int n_rows, double t0) {
  cupid_problem_state *prob = g->prob;
  int ok = 0;
  for (cupid_int t = 0; t < n_tied; t++) /* K - Kold: bonds (Kold of rows: those rows') */
    if (!partial || (n_rows && bsearch(&(cupid_int){tied[t] / 3}, rows, (size_t)n_rows, sizeof *rows, cmp_node)))
      CUPID_CALL(growth_tie_matrix(Kold, 1, tied + t, g->tie_k));
  if (partial) CUPID_CALL(cupid_growth_downdate_rows(Kold, prob->K, rows, n_rows, &g->dd, &ok));
  else CUPID_CALL(cupid_growth_downdate_terms(Kold, prob->K, &g->dd, &ok));
  if (!ok) {
    g->downdate = 0;
    cupid_problem_progress(prob, "growth: the broken bonds changed K by more than a rank-one term "
                           "each (LPS): re-solves by CG on the last factor, no downdates");
    return CUPID_SUCCESS;
  }
  /* A round that broke very many bonds (a crack running through) is cheaper to factorise
   * afresh: a downdate costs 8-10 ms a bond on the examples' factors, a factorisation 3.5 s
   * (9,000-node SENB, 27,000 equations) to 10 s (the notched C-beam, 45,000): break-even at
   * about n / 50 bonds in both. Counted, not timed, so that the choice is the same in every
   * run. */
  if (g->refactor_share && g->dd.r > cupid_direct_factor_size(g->F) / g->refactor_share) {
    cupid_direct_factor_destroy(&g->F);
    g->t_downdate += cupid_wtime() - t0;
    return CUPID_SUCCESS;
  }
  /* the nodes held since (release_unsupported: a node the breaks left loose) first, their rows
   * deleted from the factor, so that the downdate leaves it definite */
  cupid_int held = 0;
  cupid_status st = cupid_direct_factor_hold(g->F, prob->bc, &held);
  g->held_rows += held;
  /* then the new ties' springs (a mechanism the broken bonds complete: the downdate would leave
   * it singular), then the bonds */
  if (st == CUPID_SUCCESS && n_tied) st = growth_tie_factor(g->F, n_tied, tied, g->tie_k);
  if (st == CUPID_SUCCESS)
    for (cupid_int i = 0; i < prob->n_pd && n_tied; i++)
      if (g->tie[i] == 3) g->tie[i] = 1;
  if (st == CUPID_SUCCESS)
    st = cupid_direct_factor_downdate(g->F, g->dd.r, g->dd.colptr, g->dd.rows, g->dd.vals);
  if (st == CUPID_ERR_NUMERIC) { /* the node it names tied, and a new factor (solve); else the
                                    engine's breakdown names one to hold */
    const cupid_int dof = cupid_direct_factor_failed_dof(g->F);
    int named = 0;
    cupid_error_clear();
    cupid_direct_factor_destroy(&g->F);
    if (g->name_by_downdate) CUPID_CALL(tie_singular(g, dof, &named));
    else named = g->tie != NULL; /* the factorisation names it (solve) */
    g->singular = !named;
  } else {
    CUPID_CALL(st);
    g->bonds_at_factor = prob->broken_bonds;
    CUPID_CALL(growth_journal_downdated(g));
  }
  g->downdates++;
  g->downdate_columns += g->dd.r;
  g->t_downdate += cupid_wtime() - t0;
  return CUPID_SUCCESS;
}

/* Kold: the last K, or (partial) its rows @p rows alone, none or some (K patched there:
 * patch_rows). */
static cupid_status downdate_factor(growth_run *g, cupid_csr_t *Kold, int partial,
                                    const cupid_int *rows, cupid_int n_rows) {
  cupid_int *tied = NULL, n_tied = 0; /* the ties since: in K, neither in Kold nor in F */
  const double t0 = cupid_wtime();
  if (g->tie) CUPID_CALL(tie_dofs(g, 3, &tied, &n_tied));
  cupid_status st = downdate_tied(g, Kold, tied, n_tied, partial, rows, n_rows, t0);
  cupid_free(&tied);
  return st;
}

/* The growth solves with its own CHOLMOD factor (downdates, CG): an SPD method whose K is
 * assembled on one process (the direct engine, or the built-in krylov one where the model is
 * not solved matrix-free: its assembled solve is the same factorisation, which every re-solve
 * repeated before); otherwise every solve is the engine's. */
static int own_factor(const cupid_problem_state *prob) {
  return prob->method->matrix == CUPID_MATRIX_SPD && !prob->engine->distributed;
}

/* The kept matrix-free solve (growth_matrix_free.c): PD slabs, or a PD-only 3D or coupled
 * model whose method solves it matrix-free on this engine (--solver petsc, or the built-in
 * krylov: a coupled model), unless --assembled asks for the engine's solves of the assembled
 * K. A coupled model needs the method's kept operator and a kept solve on one process
 * (PETSc's, or the twin's factor on the built-in engine; a model replicated on several ranks
 * assembles K). */
static int matrix_free(const cupid_problem_state *prob) {
  if (prob->slab) return 1;
  if (!prob->grid || prob->opts->assembled || !prob->method->matrix_free(prob, prob->engine)) return 0;
  return !prob->beam || (prob->method->growth_operator && cupid_petsc_size() == 1 &&
                         (prob->engine->distributed || prob->engine->iterative));
}

/* Solve at the current load (K assembled again when bonds broke): CG preconditioned by the
 * last factor when there is one (downdated to the current K where it can be: growth by
 * downdates, else by Krylov re-solves), else a factorisation. A non-symmetric method or an
 * iterative engine takes the engine's solve every time. */
static cupid_status solve(growth_run *g, int reassemble) {
  cupid_problem_state *prob = g->prob;
  if (g->matrix_free) { /* no K: the kept matrix-free solve (growth_matrix_free.c) */
    CUPID_CALL(cupid_growth_mf_solve(prob, &g->mf));
    prob->growth.solves++;
    return CUPID_SUCCESS;
  }
  cupid_csr Kold = NULL;
  const int lu = cupid_growth_lu_applies(prob);
  const int keep_old = (g->F && g->downdate) || (lu && cupid_growth_lu_has_factor(&g->lu) && !g->lu.no_update);
  cupid_int *rows = NULL, n_rows = 0;
  int all = 1;
  if (reassemble && !lu) CUPID_CALL(changed_rows(g, &rows, &n_rows, &all));
  cupid_status st0 = CUPID_SUCCESS;
  if (!all) st0 = patch_rows(g, rows, n_rows, keep_old ? &Kold : NULL);
  else {
    if (reassemble && keep_old) Kold = prob->K, prob->K = NULL;
    if (reassemble) cupid_csr_destroy(&prob->K);
    st0 = assemble_k(g);
  }
  const cupid_int updates = g->lu.updates, factorisations = g->lu.factorisations;
  if (st0 == CUPID_SUCCESS && Kold)
    st0 = lu ? cupid_growth_lu_update(prob, &g->lu, Kold)
             : downdate_factor(g, Kold, !all, rows, n_rows);
  cupid_free(&rows);
  cupid_csr_destroy(&Kold);
  CUPID_CALL(st0);
  if (lu && g->lu.updates > updates) CUPID_CALL(growth_journal_downdated(g)); /* issue 36 */
  if (lu) { /* non-symmetric (fictitious nodes, either balance): the last LU, updated by the
               broken bonds, and GMRES (growth_lu.c) */
    CUPID_CALL(cupid_growth_lu_solve(prob, &g->lu));
    if (g->lu.factorisations > factorisations) CUPID_CALL(growth_journal_factored(g));
    prob->growth.solves++;
    return CUPID_SUCCESS;
  }
  if (cupid_problem_balanced(prob)) { /* K' = K - W C^T: the balanced solve and f_int = K' u
                                         (balance.c; load steps without fracture: one solve) */
    CUPID_CALL(prob->method->solve_assembled(prob));
    prob->growth.solves++;
    return CUPID_SUCCESS;
  }
  CUPID_CALL(cupid_problem_patch_test_assembled(prob)); /* the first K: once */
  const int own = own_factor(prob);
  int done = 0;
  if (own && g->F && g->krylov) CUPID_CALL(cg_solve(g, &done));
  /* After a downdate that left the factor indefinite, K is singular but for round-off: a
   * factorisation here would break down as the engine's does, which then names the node to
   * hold (hold_singular_node): a factorisation of the grown zone saved for each node the
   * notched C-beam's flanges leave loose in a way release_unsupported does not see. Where the
   * engine's solve does not break down, its solve stands. */
  const int singular = g->singular;
  g->singular = 0;
  if (own && !done && !singular) {
    cupid_status st = factor_solve(g);
    /* a singular K: the node it names tied and K factorised again (one factorisation a node
     * of a mechanism); else the engine's solve again, for its message naming a node to hold */
    for (int tied = 1; st == CUPID_ERR_NUMERIC && tied;) {
      CUPID_CALL(tie_singular(g, prob->solve.failed_dof, &tied));
      if (tied) st = factor_solve(g);
    }
    if (st == CUPID_ERR_NUMERIC) cupid_error_clear();
    else CUPID_CALL(st);
    if (st == CUPID_SUCCESS) CUPID_CALL(cg_solve(g, &done)); /* checked, refined if need be */
  }
  if (!done) CUPID_CALL(whole_k(g)); /* the engine's factorisation */
  if (!done) CUPID_CALL(cupid_problem_linear_solve(prob, prob->method->matrix));
  prob->growth.solves++;
  if (prob->method->recover) prob->method->recover(prob, prob->u);
  cupid_csr_matvec(prob->K, prob->u, prob->f_int);
  return CUPID_SUCCESS;
}

/* On slabs: the blocked bonds counted over the ranks, the largest ratio and the place of its
 * node from the lowest rank that has it (collective). */
static cupid_status blocked_over_ranks(const cupid_problem_state *prob, cupid_int *count,
                                       double *ratio, double x[3]) {
  const cupid_int mine = *count;
  double top = mine > 0 ? *ratio : -1.0;
  cupid_petsc_max_doubles(&top, 1);
  *count = cupid_problem_global_count(prob, mine);
  const int winner = cupid_problem_lowest_rank(mine > 0 && *ratio == top);
  double where[3] = {0.0, 0.0, 0.0};
  if (winner == cupid_petsc_rank()) memcpy(where, x, sizeof where);
  cupid_petsc_sum_doubles(where, 3);
  memcpy(x, where, sizeof where);
  *ratio = top;
  return CUPID_SUCCESS;
}

/* A crack that reached the coupling zone (whose bonds never break: the PD nodes there share
 * the load with the beam): bonds over their limit there stop the growth, named and placed;
 * *stop = 1. The steps before it stand (written), this one is not. */
/* The largest ratio of a coupling zone's bonds (over their limit or not; 0 without a zone),
 * over the ranks of a slab run: the sub-step stops at the load where it reaches 1. */
static cupid_status blocked_ratio(growth_run *g, double *ratio) {
  cupid_problem_state *prob = g->prob;
  cupid_int count = 0, node = -1;
  *ratio = 0.0;
  if (!prob->protect) return CUPID_SUCCESS;
  CUPID_CALL(cupid_pd_operator_blocked(prob->op, prob->u, &prob->fracture, &count, &node, ratio));
  if (prob->slab) cupid_petsc_max_doubles(ratio, 1);
  return CUPID_SUCCESS;
}

static cupid_status check_blocked(growth_run *g, int k, double lambda, int *stop) {
  cupid_problem_state *prob = g->prob;
  cupid_int count = 0, node = -1;
  double ratio = 0.0, x[3] = {0.0, 0.0, 0.0};
  *stop = 0;
  if (!prob->protect) return CUPID_SUCCESS;
  CUPID_CALL(cupid_pd_operator_blocked(prob->op, prob->u, &prob->fracture, &count, &node, &ratio));
  if (count > 0)
    memcpy(x, cupid_pd_grid_coords(prob->grid) + 3 * node, sizeof x);
  if (prob->slab) /* the owned bonds of every rank: the count summed, the worst one's place */
    CUPID_CALL(blocked_over_ranks(prob, &count, &ratio, x));
  if (count == 0) return CUPID_SUCCESS;
  if (prob->adaptive) { /* the zone grows there instead, where `within` lets it */
    cupid_int marked = 0;
    CUPID_CALL(cupid_problem_adaptive_blocked(prob, x, &marked));
    if (marked > 0) {
      g->convert = 1;
      return CUPID_SUCCESS;
    }
  }
  char zone[480];
  snprintf(zone, sizeof zone, "the coupling zone of method %s", prob->method->name);
  if (prob->method->protected_zone) prob->method->protected_zone(prob, x, zone, sizeof zone);
  snprintf(prob->growth.stopped, sizeof prob->growth.stopped,
           "crack growth stopped at load step %d (load factor %.6g): %lld bond%s of %s reached "
           "the breaking limit (up to %.3g times) near (%g, %g, %g), where a crack cannot go: "
           "the bonds of a coupling zone never break (its PD nodes share their load with the "
           "beam). %s; the steps before are in the steps' file, the fields written are this solve's",
           k, lambda, (long long)count, count == 1 ? "" : "s", zone, ratio, x[0], x[1], x[2],
           prob->adaptive ? "The adaptive zone may not grow there: widen "
                            "peridynamics.adaptive.within (and refine the beam there)"
                          : "Extend the PD region, or move the coupling zone, away from where "
                            "the crack runs");
  prob->growth.stopped_step = k;
  *stop = 1;
  return CUPID_SUCCESS;
}

/* A collapse stops the run at this step (*stop = 1), reported as such: the message, the
 * fracture block's `collapse`, exit status 2; the step's row is not written (no equilibrium),
 * the fields written are this solve's, for the crack that cut the body. Checked on a settled
 * solve, by the nodes held for a fragment or a singular factorisation (a weakly held node's
 * bonds pull on it at every step: held_forces); with_weak: by every held node, where a
 * coupling zone stopped the step (check_blocked) in the middle of its re-solves. */
static cupid_status check_collapse(growth_run *g, int k, double lambda, int with_weak, int *stop) {
  cupid_problem_state *prob = g->prob;
  const int weak = g->weak_share > g->held_share &&
                   (with_weak || g->weak_share > WEAK_COLLAPSE_SHARE);
  double share = weak ? g->weak_share : g->held_share;
  const int tied = g->tie_share > TIE_COLLAPSE_SHARE && g->tie_share > share;
  *stop = 0;
  if (tied) share = g->tie_share;
  else if (share <= COLLAPSE_SHARE) return CUPID_SUCCESS;
  prob->growth.collapse_step = k;
  prob->growth.collapse_load = lambda;
  prob->growth.collapse_share = share;
  prob->growth.collapse_cause = tied ? "tied nodes carry load" : "held nodes carry load";
  const cupid_int n = tied ? g->tied : g->released; /* the nodes that carry it */
  prob->growth.collapse_held = n;
  const double *h = prob->growth.held_reaction;
  /* Driven by prescribed displacements alone, a body cut through has an equilibrium: no
   * reaction. Its held nodes carry the grips' pull where a node left singular is still bonded
   * to a part the grips move (0.08 of the forces on examples/geometry/plate_hole_crack.yaml
   * at spacing 1.5): past here the reactions would be the holding's, not the body's. */
  const int grips = !g->loaded;
  if (grips)
    prob->growth.collapse_cause =
        tied ? "tied nodes carry the grips' pull" : "held nodes carry the grips' pull";
  snprintf(prob->growth.stopped, sizeof prob->growth.stopped,
           "%s at load step %d (load factor %.6g)%s, and the %lld node%s %s where breaking "
           "left %s loose%s carr%s %.3g of the forces on the body (a sum of (%.4g, %.4g, %.4g); "
           "more than %.0e is a support the model does not have)%s",
           grips ? "the crack cut the body" : "the body collapsed", k, lambda,
           grips ? "" : ": the crack cut the load path", (long long)n, n == 1 ? "" : "s",
           tied ? "tied by weak springs" : "held", n == 1 ? "it" : "them",
           tied ? "" : grips ? " or singular" : "", n == 1 ? "ies" : "y", share, h[0], h[1], h[2],
           tied ? TIE_COLLAPSE_SHARE : COLLAPSE_SHARE,
           grips ? ": past this step the reactions would be the holding's, not the body's. "
                   "Results up to the last step written; the fields written are this solve's"
                 : ". The load is more than what is left of the body can carry: results past "
                   "the last step written are no equilibrium; the fields written are this "
                   "solve's");
  prob->growth.stopped_step = k;
  *stop = 1;
  return CUPID_SUCCESS;
}

/* The load and the prescribed values of the model at load factor mu (held nodes keep theirs). */
static void set_load(growth_run *g, double mu) {
  cupid_problem_state *prob = g->prob;
  for (cupid_int d = 0; d < prob->ndof; d++) {
    prob->f_ext[d] = mu * g->f_full[d];
    if (g->fixed0[d]) prob->bc->value[d] = mu * g->g_full[d];
  }
}

/* The solve at load factor mu scaled to mu2: exact, each solve being linear, while no node is
 * held (a held node keeps its displacement). */
static void scale_solution(growth_run *g, double mu, double mu2) {
  cupid_problem_state *prob = g->prob;
  const double s = mu2 / mu;
  for (cupid_int d = 0; d < prob->ndof; d++) prob->u[d] *= s, prob->f_int[d] *= s;
  for (int c = 0; c < 3 * prob->model->n_constraints; c++) g->react[c] *= s;
  set_load(g, mu2);
}

/* How far past its limit a sub-step puts the most critical bond, so that it breaks: far above
 * the round-off of the ratio (1e-15), far below any physical difference (the growth test finds
 * the first break between 1e-9 below and above the predicted load). */
#define SUBSTEP_OVER 1e-9

/* A matrix-free solve that runs away again and again in one load step, each time after the
 * node its iterate moved furthest was held (growth_matrix_free.c): a mechanism that holding
 * nodes one by one does not steady, under load (CG converges on a mechanism the load does not
 * push). The Arlequin bar cut through under its end traction on the petsc engine held 17
 * crack-face nodes at 3 s each, and went on for 13 minutes, where the direct path's factor
 * names the loose part at once and the held share calls it a collapse (check_collapse). A
 * step whose solve ran away more than RUNAWAY_HOLDS_MAX times stops as a collapse. 8: the
 * runaways of a growth that goes on are the odd node at a time (the force-loaded plate of
 * verification.mpi_fracture_growth: one). */
#define RUNAWAY_HOLDS_MAX 8

static cupid_status runaway_collapse(growth_run *g, int k, double mu, int runaways, int *stop) {
  cupid_problem_state *prob = g->prob;
  prob->growth.collapse_step = k;
  prob->growth.collapse_load = mu;
  prob->growth.collapse_share = g->held_share;
  prob->growth.collapse_held = g->released;
  prob->growth.collapse_cause = "runaway";
  snprintf(prob->growth.stopped, sizeof prob->growth.stopped,
           "the body collapsed at load step %d (load factor %.6g): the crack cut the load path: "
           "the PETSc solve ran away %d times in this step, each time after the node it moved "
           "furthest was held (a mechanism under load, that holding nodes does not steady: a "
           "part that came loose carries load). Results past the last step written are no "
           "equilibrium; the fields written are the last steady solve's",
           k, mu, runaways);
  prob->growth.stopped_step = k;
  *stop = 1;
  return CUPID_SUCCESS;
}

/* One load step to load factor lambda: solve, break, solve again until nothing is over its
 * limit; *stop = 1 when a coupling zone stopped it (check_blocked) or the body collapsed
 * (check_collapse).
 * Sub-steps make the crack's path independent of the step count: a solve of a crack that
 * broke nothing at its load yet, with bonds over their limit (ratio r > 1), is scaled back to
 * the load factor mu / r (1 + SUBSTEP_OVER) at which its most critical bond reaches its limit
 * (exact: each solve is linear), the bonds break there, and the re-solves run at that load
 * until nothing more breaks (a crack that runs at constant load); then the load goes on to
 * lambda, by scaling the settled solve again (no solve: the next sub-step, if any, is found
 * on it). A coupling zone's bond that would reach its limit first stops the sub-step there:
 * the run stops at the load where the crack first asks to enter the zone, whatever the
 * steps (check_blocked). So every crack is broken at the load it first fails at, as in sequentially linear
 * analysis (Rots et al. 2008), and the steps only choose where the rows are written: a
 * coarse step no longer breaks at once the bonds a finer one would have broken one event at
 * a time, at lower loads (the plate of issue 33: peaks of 1134 to 1284 N over 1 to 50 steps
 * before). Once a node is held the scaling is no longer exact, and the bonds over their limit
 * break at the step's load as they did (CUPID_GROWTH_SUBSTEP=0: always so, bench/growth.sh). */
/* A line every STEP_HEARTBEAT_S within a load step whose crack runs: the notched C-beam's step
 * 18 re-solves for minutes at one load (issue 37), and a user who sees nothing for that long
 * cannot tell a running crack from a hung run. */
#define STEP_HEARTBEAT_S 10.0

static void heartbeat(growth_run *g, int k, double mu, int solves) {
  const cupid_problem_state *prob = g->prob;
  const double now = cupid_wtime();
  if (now - g->t_line < STEP_HEARTBEAT_S) return;
  g->t_line = now;
  cupid_problem_progress(prob, "growth: step %d, load factor %.4g: %d solve%s so far, %lld bonds "
                         "broken, %lld nodes held", k, mu, solves, solves == 1 ? "" : "s",
                         (long long)prob->broken_bonds, (long long)g->released);
}

static cupid_status load_step(growth_run *g, int k, double lambda, int *iterations, int *stop) {
  cupid_problem_state *prob = g->prob;
  const cupid_model_t *m = prob->model;
  const int fracture = m->has_peridynamics && m->pd.fracture.has_fracture;
  const int only_most = fracture && !m->pd.fracture.per_iteration_all;
  int reassemble = 0; /* K holds the intact bonds of the last solve */
  double mu = lambda; /* the load factor of the solve */
  int broke_here = 0; /* bonds broke at load factor mu */
  int scaled = 0;     /* the solution is the last solve's scaled to mu: no solve needed */
  int runaways = 0;   /* nodes held where the matrix-free solve ran away, this step */
  *iterations = 0;
  g->step = k, g->quiet = prob->quiet;
  if (g->F && g->bonds_at_factor != prob->broken_bonds) cupid_direct_factor_destroy(&g->F);
  if (cupid_growth_lu_has_factor(&g->lu) && g->lu.bonds_at_factor != prob->broken_bonds) cupid_growth_lu_renew(&g->lu);
  for (;;) {
    const int quiet = prob->quiet; /* the first solve reports its assembly; the others would
                                      repeat it per broken bond */
    if (k > 1 || *iterations > 0) prob->quiet = 1;
    if (g->u_before && !scaled) /* where a tie that takes load is held (hold_loaded_ties) */
      memcpy(g->u_before, prob->u, (size_t)prob->ndof * sizeof *prob->u);
    cupid_status st = scaled ? CUPID_SUCCESS : solve(g, reassemble);
    prob->quiet = quiet;
    if (st == CUPID_ERR_NUMERIC && prob->broken_bonds > 0) { /* what breaking left loose */
      int held = 0;
      CUPID_CALL(hold_singular_node(g, k, &held));
      if (held && g->matrix_free && ++runaways > RUNAWAY_HOLDS_MAX)
        return runaway_collapse(g, k, mu, runaways, stop);
      if (held) {
        reassemble = 1;
        continue;
      }
    }
    CUPID_CALL(st);
    if (!scaled) (*iterations)++;
    scaled = 0;
    if (!fracture) return CUPID_SUCCESS;
    reactions(g);
    if (g->tie_share > TIE_COLLAPSE_SHARE) { /* a tie took load: held, and solved again; or a
                                                collapse at this solve, before any bond breaks
                                                on it */
      int held = 0;
      CUPID_CALL(hold_loaded_ties(g, k, &held));
      if (held) {
        reassemble = 1;
        continue;
      }
      CUPID_CALL(check_collapse(g, k, mu, 0, stop));
      if (*stop) return CUPID_SUCCESS;
    }
    double r = 0.0; /* the largest ratio of this solution's breakable bonds */
    CUPID_CALL(cupid_problem_max_ratio(prob, prob->u, &r));
    if (prob->first_break_step < 0) { /* the exact load of the first break, by scaling */
      if (r > 1.0) prob->first_break_load = mu / r;
      if (g->ratio_per_load == 0.0 && r > 0.0 && mu > 0.0) g->ratio_per_load = r / mu;
    }
    if (!broke_here && g->substep && g->released == 0) { /* the sub-step, to the first limit
                                                            reached: a bond's, or a coupling
                                                            zone's (check_blocked stops there) */
      double rb = 0.0;
      CUPID_CALL(blocked_ratio(g, &rb));
      const double top = r > rb ? r : rb;
      if (top > 1.0) {
        const double mc = mu / top * (1.0 + SUBSTEP_OVER);
        scale_solution(g, mu, mc);
        r *= mc / mu, mu = mc;
      }
    }
    CUPID_CALL(check_blocked(g, k, mu, stop));
    if (g->convert) { /* an adaptive zone grows first (convert_zone), unless the crack has cut
                         the load path: a loose part whose held nodes carry load swung into the
                         overlap, and the zone would grow after it, as a fixed zone's stop there
                         is a collapse (below) */
      CUPID_CALL(check_collapse(g, k, mu, 0, stop));
      if (*stop) g->convert = 0;
      return CUPID_SUCCESS;
    }
    if (*stop) { /* a loose part swung round into a coupling zone: a collapse, if held nodes
                    carry it (an Arlequin bar cut through under an end traction: weakly held
                    nodes among them, the pivots it swung round) */
      int collapsed = 0;
      return check_collapse(g, k, mu, 1, &collapsed);
    }
    track_peaks(g, k, mu, carries_load(g, mu, r) ? r : 0.0);
    cupid_int broken = 0;
    double diss = 0.0;
    CUPID_CALL(cupid_problem_fracture_step(prob, k, mu, prob->u, only_most, &broken, &diss));
    if (broken == 0 && mu < lambda) { /* settled below the step's load: on to it, by scaling
                                         (no node held) or a solve */
      if (g->released == 0) scale_solution(g, mu, lambda), scaled = 1;
      else set_load(g, lambda), reassemble = 0;
      mu = lambda, broke_here = 0;
      continue;
    }
    if (broken == 0) { /* settled: the next break's load factor from this solution (nothing
                          broke, so the ratio scanned above still holds) */
      CUPID_CALL(check_collapse(g, k, lambda, 0, stop));
      if (*stop) return CUPID_SUCCESS;
      g->next_ratio = carries_load(g, lambda, r) ? r : 0.0; /* none after a cut */
      if (g->next_ratio == 0.0 && r > 0.0 && !g->cut_through) {
        g->cut_through = 1;
        cupid_problem_progress(prob, "growth: step %d: the crack has cut the load path (the bonds' "
                               "largest stretch per unit load is %.1e of the first solve's): no "
                               "next break, no peak from here", k, r / lambda / g->ratio_per_load);
      }
      return CUPID_SUCCESS;
    }
    broke_here = 1;
    heartbeat(g, k, mu, *iterations);
    CUPID_CALL(release_unsupported(g, k));
    reassemble = 1;
    CUPID_CHECK(*iterations < 1000000, CUPID_ERR_NUMERIC,
                "growth: load step %d did not settle in 10^6 re-solves", k);
  }
}

/* The progress line of step k of N: the first, the last, every tenth, and the others at most
 * one a second, so that a run of 10^5 steps does not fill a batch log (issue 33: 11 MB) while
 * a slow run still shows it moves (docs/model-format.md, "Progress"). */
#define STEP_LINE_INTERVAL_S 1.0

static int step_line_due(growth_run *g, int k, int N) {
  const int tenth = N / 10 > 0 ? N / 10 : 1;
  const double now = cupid_wtime();
  if (k == 1 || k == N || k % tenth == 0 || now - g->t_line >= STEP_LINE_INTERVAL_S) {
    g->t_line = now;
    return 1;
  }
  return 0;
}

/* What the run keeps per DOF and per PD node of the problem's layout (free_layout). */
static cupid_status setup_layout(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  const size_t n = (size_t)prob->ndof;
  CUPID_CALL(cupid_malloc(n, sizeof *g->f_full, "full load", &g->f_full));
  CUPID_CALL(cupid_malloc(n, sizeof *g->g_full, "full prescribed values", &g->g_full));
  CUPID_CALL(cupid_malloc(n, 1, "constrained flags", &g->fixed0));
  memcpy(g->f_full, prob->f_ext, n * sizeof *g->f_full);
  double any = 0.0; /* a slab's rows are its own: summed over the ranks */
  for (size_t d = 0; d < n; d++) any += fabs(g->f_full[d]);
  if (prob->slab) cupid_petsc_sum_doubles(&any, 1);
  g->loaded = any > 0.0;
  memcpy(g->g_full, prob->bc->value, n * sizeof *g->g_full);
  memcpy(g->fixed0, prob->bc->fixed, n);
  if (prob->grid) {
    CUPID_CALL(cupid_calloc((size_t)prob->n_pd + 1, 1, "anchored nodes", &g->anchored));
    CUPID_CALL(cupid_calloc((size_t)prob->n_pd + 1, 1, "released nodes", &g->release));
    CUPID_CALL(cupid_calloc((size_t)prob->n_pd + 1, 1, "weakly held nodes", &g->weak));
    CUPID_CALL(cupid_calloc((size_t)prob->n_pd + 1, 1, "weakly held scan", &g->weak_scan));
    if (own_factor(prob) && !matrix_free(prob) && !prob->slab) {
      CUPID_CALL(cupid_calloc((size_t)prob->n_pd + 1, 1, "tied nodes", &g->tie));
      CUPID_CALL(cupid_malloc((size_t)prob->n_pd + 1, sizeof *g->mech_seen, "lost shares",
                              &g->mech_seen));
      mechanisms_seen(g);
    }
    anchor(g);
  }
  CUPID_CALL(constraint_masks(g));
  for (int k = 0; k < 4; k++)
    CUPID_CALL(cupid_calloc(n + 1, sizeof(double), "growth work vectors", &g->w[k]));
  if (g->tie) CUPID_CALL(cupid_calloc(n + 1, sizeof(double), "growth work vectors", &g->u_before));
  CUPID_CALL(cupid_calloc(n + 1, 1, "rows next to fixed DOFs", &g->near_fixed));
  return CUPID_SUCCESS;
}

/* An adaptive zone grows (adaptive.c): before the conversion, what the run keeps of the
 * layout is freed (the factor, the kept solvers, whose operators borrow the old problem's
 * objects), the held nodes' flags kept for the map; the counters stay. */
static void growth_release(growth_run *g, unsigned char **held, unsigned char **weak,
                           unsigned char **tie) {
  *held = g->release, *weak = g->weak, *tie = g->tie;
  g->release = g->weak = g->tie = NULL;
  free_layout(g);
  const cupid_growth_lu lu = g->lu;
  cupid_growth_lu_free(&g->lu);
  g->lu = (cupid_growth_lu){.factorisations = lu.factorisations, .resolves = lu.resolves,
                            .iterations = lu.iterations, .t_factor = lu.t_factor,
                            .t_resolve = lu.t_resolve, .updates = lu.updates,
                            .update_columns = lu.update_columns, .t_update = lu.t_update,
                            .whole = lu.whole};
  const cupid_growth_mf mf = g->mf;
  cupid_growth_mf_free(&g->mf);
  g->mf = (cupid_growth_mf){.iterations = mf.iterations, .setup_s = mf.setup_s,
                            .solve_s = mf.solve_s};
  g->prob->crack_copy = NULL, g->prob->crack_map = NULL;
}

static cupid_status frame_vertices(growth_run *g);

/* After a conversion: the layout's state again, the nodes held before held again where they
 * are now (at their displacement, carried over), and the load of factor lambda. */
static cupid_status growth_rezone(growth_run *g, double lambda, unsigned char *held,
                                  unsigned char *weak, const unsigned char *tie) {
  cupid_problem_state *prob = g->prob;
  CUPID_CALL(setup_layout(g));
  cupid_int n_old = 0;
  const cupid_int *map = cupid_problem_adaptive_map(prob, &n_old);
  for (cupid_int i = 0; i < n_old && tie && g->tie; i++) /* in the new K at its assembly */
    if (tie[i]) g->tie[map[i]] = 2;
  for (cupid_int i = 0; i < n_old && held; i++) {
    if (!held[i]) continue;
    const cupid_int j = map[i];
    g->release[j] = 1, g->weak[j] = weak[i];
    for (int c = 0; c < 3; c++) CUPID_CALL(cupid_dirichlet_fix(prob->bc, 3 * j + c, prob->u[3 * j + c]));
  }
  CUPID_CALL(cupid_dirichlet_finalize(prob->bc));
  for (size_t d = 0; d < (size_t)prob->ndof; d++) {
    prob->f_ext[d] = lambda * g->f_full[d];
    if (g->fixed0[d]) prob->bc->value[d] = lambda * g->g_full[d];
  }
  g->bonds_at_factor = -1;
  g->tracked_k = g->tracked_op = NULL, g->patched = 0; /* a new K, a new operator */
  g->matrix_free = matrix_free(prob); /* a zone that started empty: the beam's path until now */
  return frame_vertices(g);
}

/* After load step k settled: the zone grows while the trigger fires (or a crack asked into an
 * overlap: g->convert), the step solved again at its load each time (*stop: max_nodes). */
static cupid_status convert_zone(growth_run *g, int k, double lambda, int *again, int *stop) {
  cupid_problem_state *prob = g->prob;
  cupid_int n = 0;
  *again = 0;
  /* the damage now: the step's breaks (the margin test and the frame read it; write_row made
   * it last at the step before) */
  CUPID_CALL(cupid_problem_fracture_damage(prob));
  /* (after a crack blocked at an overlap too: the overlaps' other bonds near their limit
   * turn with it, one conversion instead of one per side) */
  CUPID_CALL(cupid_problem_adaptive_trigger(prob, &n));
  if (!g->convert && n == 0) return CUPID_SUCCESS;
  g->convert = 0;
  CUPID_CALL(zone_frame(g, lambda));
  unsigned char *held = NULL, *weak = NULL, *tie = NULL;
  growth_release(g, &held, &weak, &tie);
  cupid_status st = cupid_problem_adaptive_convert(prob, k, lambda, NULL, 0, stop);
  if (st == CUPID_SUCCESS) st = growth_rezone(g, lambda, held, weak, tie);
  cupid_free(&held);
  cupid_free(&weak);
  cupid_free(&tie);
  CUPID_CALL(st);
  *again = !*stop;
  return CUPID_SUCCESS;
}

static cupid_status setup_run(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  CUPID_CALL(setup_layout(g));
  CUPID_CALL(cupid_calloc(3 * (size_t)prob->model->n_constraints + 1, sizeof(double), "reactions",
                          &g->react));
  CUPID_CALL(cupid_calloc(3 * (size_t)prob->model->output.n_points + 1, sizeof(double),
                          "output points", &g->points));
  CUPID_CALL(cupid_calloc(12 + 3 * (size_t)(prob->model->n_constraints + prob->model->output.n_points),
                          sizeof(double), "a row of the steps' file", &g->row));
  /* bench/growth.sh: factor | krylov | downdate (the default) */
  const char *how = getenv("CUPID_GROWTH_RESOLVE");
  g->krylov = !(how && strcmp(how, "factor") == 0);
  g->downdate = g->krylov && !(how && strcmp(how, "krylov") == 0);
  g->matrix_free = matrix_free(prob);
  /* tests: CUPID_GROWTH_DOWNDATE_ALL=1 downdates rounds of any size (verification.fracture_growth
   * compares it with the default on a plate pulled apart, whose rounds hold nodes) */
  const char *all = getenv("CUPID_GROWTH_DOWNDATE_ALL");
  g->refactor_share = all && strcmp(all, "1") == 0 ? 0 : DOWNDATE_MAX_SHARE;
  /* ... and CUPID_GROWTH_NAME_BY_FACTOR=1 has the factorisation after a failed downdate name
   * the node to tie, as a run that refactorised that round would (the same nodes in both) */
  const char *by_factor = getenv("CUPID_GROWTH_NAME_BY_FACTOR");
  g->name_by_downdate = !(by_factor && strcmp(by_factor, "1") == 0);
  /* ... and CUPID_GROWTH_WHOLE_K=1 assembles K whole after every round (patch_rows' twin) */
  const char *whole = getenv("CUPID_GROWTH_WHOLE_K");
  g->patch = !(whole && strcmp(whole, "1") == 0);
  const char *sub = getenv("CUPID_GROWTH_SUBSTEP");
  g->substep = !(sub && strcmp(sub, "0") == 0);
  /* ... and CUPID_GROWTH_BANDS=0 leaves the mechanisms inside bands of damaged nodes to the
   * factorisation, as before they were searched (the failed downdates that name them) */
  const char *bands = getenv("CUPID_GROWTH_BANDS");
  g->band_check = !(bands && strcmp(bands, "0") == 0);
  /* ... and CUPID_GROWTH_BAND_FACTOR=0 leaves the nodes left singular after the first to the
   * grown zone's factorisations, one each (tie_band_factorised) */
  const char *band_factor = getenv("CUPID_GROWTH_BAND_FACTOR");
  g->band_factor = !(band_factor && strcmp(band_factor, "0") == 0);
  return CUPID_SUCCESS;
}

/* Crack growth (growth_resume.c; issue 36): checkpoints, periodic and on a signal, and with
 * --resume the checkpoint's state; the peaks' array first (a checkpoint holds them). Then the
 * steps' file, new or continued. */
static cupid_status begin_growth(growth_run *g) {
  cupid_problem_state *prob = g->prob;
  const cupid_model_t *m = prob->model;
  const int N = m->analysis.steps > 0 ? m->analysis.steps : 1;
  CUPID_CALL(cupid_calloc(6 * (size_t)(m->n_constraints ? m->n_constraints : 1), sizeof(double),
                          "peak reactions", &prob->growth.peak));
  /* the estimate: a solve of the chosen engine per load step, at least */
  CUPID_CALL(cupid_problem_checkpoint_begin(prob, prob->estimate.seconds * N));
  if (prob->opts->resume) {
    CUPID_CALL(growth_resume(g));
    mechanisms_seen(g); /* the checkpoint's broken bonds */
  }
  return open_writers(g);
}

/* A status agreed over the ranks of an MPI run (a slab's, or a replicated model's). */
static cupid_status agreed_growth(const cupid_problem_state *prob, cupid_status st) {
  return cupid_petsc_size() > 1 ? cupid_problem_slab_agree(st) : st;
}

cupid_status cupid_problem_run_growth(cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  const int N = m->analysis.steps > 0 ? m->analysis.steps : 1;
  growth_run g = {.prob = prob, .first_step = 1};
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(setup_run(&g));
  const int fracture = cupid_problem_growth_resumable(prob); /* crack growth: resumable */
  CUPID_TRY(agreed_growth(prob, fracture ? begin_growth(&g) : open_writers(&g)));
  CUPID_TRY(frame_vertices(&g));
  const size_t n = (size_t)prob->ndof;
  double t0 = cupid_wtime();
  g.t_line = t0; /* the heartbeat (heartbeat()) counts from the start */
  if (!fracture) { /* linear: one solve at load factor 1 (one factorisation), each step its
                      multiple: the last step's is the solution */
    CUPID_TRY(solve(&g, 0));
    CUPID_TRY(cupid_malloc(2 * n, sizeof *g.u1, "the unit solution", &g.u1));
    memcpy(g.u1, prob->u, n * sizeof *g.u1);
    memcpy(g.u1 + n, prob->f_int, n * sizeof *g.u1);
  }
  for (int k = 1; k <= N && !fracture; k++) {
    const double lambda = (double)k / N;
    for (size_t d = 0; d < n; d++) {
      prob->u[d] = lambda * g.u1[d];
      prob->f_int[d] = lambda * g.u1[n + d];
      prob->f_ext[d] = lambda * g.f_full[d];
    }
    CUPID_TRY(write_row(&g, k, lambda, k == 1));
    CUPID_TRY(write_frame(&g, k, lambda));
  }
  for (int k = g.first_step; k <= N && fracture && !prob->growth.stopped_step; k++) {
    const double lambda = (double)k / N;
    /* every DOF of the layout now (an adaptive zone adds DOFs: issue 37) */
    for (size_t d = 0; d < (size_t)prob->ndof; d++) {
      prob->f_ext[d] = lambda * g.f_full[d];
      if (g.fixed0[d]) prob->bc->value[d] = lambda * g.g_full[d];
      /* CG's first guess on the matrix-free path: the last step's solution scaled to this
       * load, exact when no bond breaks (each solve is linear); held nodes stay */
      else if (g.matrix_free && k > 1 && !prob->bc->fixed[d]) prob->u[d] *= (double)k / (k - 1);
    }
    const cupid_int before = prob->broken_bonds;
    int it = 0, stop = 0;
    for (int again = 1, conversions = 0; again; conversions++) { /* adaptive: the step again
                                                                    after each conversion */
      int solves = 0;
      CUPID_TRY(load_step(&g, k, lambda, &solves, &stop));
      it += solves;
      if (stop || !prob->adaptive) break;
      CUPID_TRY_CHECK(conversions < 10000, CUPID_ERR_NUMERIC,
                      "adaptive: load step %d converted 10^4 times without settling", k);
      CUPID_TRY(convert_zone(&g, k, lambda, &again, &stop));
    }
    if (stop) break; /* the message: cupid_problem_get_info's stopped (the CLI prints it) */
    g.last_load = lambda;
    CUPID_TRY(write_row(&g, k, lambda, it));
    CUPID_TRY(write_frame(&g, k, lambda));
    if (step_line_due(&g, k, N))
      cupid_problem_progress(prob, "growth: step %d / %d, load factor %.4g: %d solve%s, %lld bonds "
                           "broken (+%lld), %lld nodes held",
                           k, N, lambda, it, it == 1 ? "" : "s", (long long)prob->broken_bonds,
                           (long long)(prob->broken_bonds - before), (long long)g.released);
    CUPID_TRY(growth_safe_point(&g, k)); /* a checkpoint when one is due */
  }
  CUPID_TRY(whole_k(&g)); /* K as assembled whole: what the summary and later stages read */
  if (prob->ckpt.written)
    cupid_problem_progress(prob, "checkpoints: %lld written, %.3g s in all",
                           (long long)prob->ckpt.written, prob->ckpt.seconds);
  prob->solved = 1;
  prob->phases[CUPID_PHASE_SOLVE] = (cupid_phase_record){cupid_wtime() - t0, cupid_peak_memory(), 1};
  const int lu = g.lu.factorisations > 0;
  prob->growth.resolve = g.matrix_free       ? "matrix-free"
                         : lu                ? (!g.lu.updates ? "gmres" : g.lu.whole ? "lu update" : "block downdate")
                         : !own_factor(prob) ? "engine"
                         : g.downdates       ? "downdate"
                         : g.krylov          ? "krylov"
                                             : "factor";
  prob->growth.downdates = g.downdates;
  prob->growth.downdate_columns = g.downdate_columns;
  prob->growth.held_rows = g.held_rows;
  prob->growth.tied_nodes = g.tied, prob->growth.tie_stiffness = g.tie_k;
  prob->growth.tied_singular = g.tied_singular;
  prob->growth.failed_factorisations = g.failed_factorisations;
  prob->growth.tie_share = g.tie_share;
  prob->growth.downdate_s = g.t_downdate;
  prob->growth.factorisations = g.factorisations;
  prob->growth.cg_solves = g.cg_solves;
  prob->growth.cg_iterations = g.cg_iterations;
  prob->growth.factor_s = g.t_factor;
  prob->phases[CUPID_PHASE_FACTORISATION] =
      (cupid_phase_record){g.t_factor, cupid_peak_memory(), g.factorisations > 0};
  prob->growth.cg_s = g.t_cg;
  if (lu) { /* GMRES on the last LU: its re-solves in the CG fields */
    prob->growth.factorisations = g.lu.factorisations;
    prob->growth.cg_solves = g.lu.resolves;
    prob->growth.cg_iterations = g.lu.iterations;
    prob->growth.factor_s = g.lu.t_factor;
    prob->growth.cg_s = g.lu.t_resolve;
    prob->growth.downdates = g.lu.updates; /* the LU's Sherman-Morrison-Woodbury updates */
    prob->growth.downdate_columns = g.lu.update_columns;
    prob->growth.downdate_s = g.lu.t_update;
    prob->phases[CUPID_PHASE_FACTORISATION] = (cupid_phase_record){g.lu.t_factor, cupid_peak_memory(), 1};
  }
  if (g.matrix_free) { /* the CG + GAMG solves */
    prob->growth.cg_solves = prob->growth.solves;
    prob->growth.cg_iterations = g.mf.iterations;
    prob->growth.cg_s = g.mf.solve_s;
    prob->growth.factor_s = g.mf.setup_s;
    /* the preconditioner's one set-up stands for the factorisations */
    prob->phases[CUPID_PHASE_FACTORISATION] = (cupid_phase_record){g.mf.setup_s, cupid_peak_memory(), 1};
  }
  if (g.released > 0) { /* the held nodes, whose forces the summary shows apart (force_sums;
                          a slab's gathered with the fields) */
    prob->growth.held = g.release, g.release = NULL;
    prob->growth.held_count = g.released;
    prob->growth.held_share = g.held_share > g.weak_share ? g.held_share : g.weak_share;
    if (!prob->growth.collapse_step && g.weak_share > COLLAPSE_SHARE && !prob->quiet &&
        (!prob->slab || cupid_petsc_rank() == 0))
      fprintf(stderr, "cupid: warning: the %lld nodes held where breaking left them weakly held "
              "(at most 2 bonds, or all in one plane) carry %.3g of the forces on the body: a "
              "support of that size that the model does not have (summary.json's "
              "held_reaction_sum)\n", (long long)g.released, g.weak_share);
  }
  if (prob->slab) { /* rank 0 gathers the whole model */
    CUPID_TRY(cupid_problem_slab_collect(prob));
    if (prob->slab) goto cleanup; /* a rank other than 0 */
  }
  CUPID_TRY(cupid_writer_end(&g.csv));
  CUPID_TRY(cupid_writer_end(&g.exodus));
  if (g.zones) { /* the zone at the end */
    CUPID_TRY(cupid_problem_fracture_damage(prob));
    CUPID_TRY(zone_frame(&g, g.last_load));
    CUPID_TRY(cupid_writer_end(&g.zones));
  }
  CUPID_TRY(plots(&g));
  if (prob->method->report) CUPID_TRY(prob->method->report(prob));
cleanup:
  /* --resume continues it (after an interrupt, or again after a resumption that failed) */
  if (prob->ckpt.interrupted || prob->opts->resume) {
    cupid_writer_drop(&g.csv, 1);
    cupid_writer_drop(&g.exodus, 1);
  }
  cupid_problem_checkpoint_end(prob);
  growth_free(&g);
  return st;
}
