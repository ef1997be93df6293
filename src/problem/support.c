/* The layer below the stages of a problem (problem.c drives them: set-up, the analyses,
 * the outputs): what every stage and method uses, and nothing of theirs: progress lines, the
 * phases' times, the check that a vector is finite. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>

#include "problem_internal.h"

void cupid_problem_progress(const cupid_problem_state *prob, const char *fmt, ...) {
  if (prob->quiet) return;
  va_list ap;
  va_start(ap, fmt);
  fprintf(stderr, "cupid [%7.2f s] ", cupid_wtime() - prob->t_start);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
}

void cupid_problem_phase_end(cupid_problem_state *prob, cupid_phase phase, double t0) {
  prob->phases[phase].seconds += cupid_wtime() - t0;
  prob->phases[phase].peak_memory = cupid_peak_memory();
  prob->phases[phase].used = 1;
}

void cupid_problem_record_solve(cupid_problem_state *prob) {
  prob->phases[CUPID_PHASE_FACTORISATION] =
      (cupid_phase_record){prob->solve.time_factor, cupid_peak_memory(), 1};
  prob->phases[CUPID_PHASE_SOLVE] = (cupid_phase_record){prob->solve.time_solve, cupid_peak_memory(), 1};
}

cupid_status cupid_problem_check_finite(const cupid_problem_state *prob, const double *v,
                                        const cupid_mark *mark, const char *what) {
  cupid_int d = 0;
  while (d < prob->ndof && isfinite(v[d])) d++;
  if (d == prob->ndof) return CUPID_SUCCESS;
  char where[160];
  const char comp = "xyz"[d % 3];
  if (d < prob->fe_offset) {
    const double *x = cupid_pd_grid_coords(prob->grid) + 3 * (d / 3);
    snprintf(where, sizeof where, "PD node (%g, %g, %g), component %c", x[0], x[1], x[2], comp);
  } else {
    cupid_int node = (d - prob->fe_offset) / 3 / prob->fe_info.M;
    snprintf(where, sizeof where, "beam node %lld (y = %g), component %c", (long long)node,
             cupid_cuf_beam_node_y(prob->beam, node), comp);
  }
  if (!mark)
    return CUPID_ERROR(CUPID_ERR_NUMERIC, "%s is not finite (%g) at %s", what, v[d], where);
  return cupid_model_error(prob->model, mark,
                           "%s is not finite (%g) at %s: an expression is undefined or overflows "
                           "there",
                           what, v[d], where);
}

/* ---- over the ranks of a slab run (slab.c); one process: the value itself */

int cupid_problem_pd_owned(const cupid_problem_state *prob, cupid_int node) {
  return !prob->slab || (node >= prob->part.owned_first && node < prob->part.owned_last);
}

int cupid_problem_lowest_rank(int mine) {
  const int size = cupid_petsc_size();
  return size - cupid_petsc_max_int(mine ? size - cupid_petsc_rank() : 0);
}

cupid_int cupid_problem_global_count(const cupid_problem_state *prob, cupid_int count) {
  if (!prob->slab) return count;
  double c = (double)count;
  cupid_petsc_sum_doubles(&c, 1);
  return (cupid_int)c;
}

cupid_status cupid_problem_slab_agree(cupid_status st) {
  if (!cupid_petsc_max_int(st != CUPID_SUCCESS)) return CUPID_SUCCESS;
  if (st != CUPID_SUCCESS) return st;
  return CUPID_ERROR(CUPID_ERR_MODEL, "another MPI rank reported an error");
}

/* ---- what the outputs need */

int cupid_problem_needs_stress(const cupid_problem_state *prob) {
  const cupid_output *o = &prob->model->output;
  if (o->vtu) return 1;
  for (int k = 0; k < o->n_points; k++)
    if (o->points[k].stress) return 1;
  return 0;
}

void cupid_plot_component_label(const double umax[3], char *label, size_t len) {
  double top = fmax(umax[0], fmax(umax[1], umax[2]));
  label[0] = '\0';
  for (int c = 0, n = 0; c < 3; c++)
    if (umax[c] > 1e-12 * top || top == 0.0)
      n += snprintf(label + n, len - (size_t)n, "%su_%c", n ? ", " : "", "xyz"[c]);
}

int cupid_problem_runs_steps(const cupid_problem_state *prob) {
  const cupid_model_t *m = prob->model;
  return m->analysis.steps > 0 || (m->has_peridynamics && m->pd.fracture.has_fracture);
}

int cupid_problem_writes_frames(const cupid_problem_state *prob) {
  const cupid_analysis_type type = prob->model->analysis.type;
  return type == CUPID_ANALYSIS_DYNAMIC ||
         (type == CUPID_ANALYSIS_STATIC && cupid_problem_runs_steps(prob));
}
