/* The CUF beam of a model inside a run: the beam's DOFs sit after the PD DOFs in the global
 * system (offset fe_offset), so the same vectors serve PD-only, FE-only and coupled models. */
#include <string.h>

#include "app_internal.h"
#include "cupid/io.h"

cupid_status cupid_app_fe_build(cupid_job *job) {
  double t0 = cupid_wtime();
  CUPID_CALL(cupid_cuf_beam_create(job->model, &job->beam));
  job->fe_offset = 3 * job->n_pd;
  CUPID_CALL(cupid_cuf_set_dof_offset(job->beam, job->fe_offset));
  cupid_cuf_get_info(job->beam, &job->fe_info);
  job->n_fe_dofs = job->fe_info.n_dofs;
  cupid_job_phase_end(job, CUPID_PHASE_GRID, t0);
  cupid_job_progress(job, "beam: %lld FE nodes, %lld DOFs", (long long)job->fe_info.n_fe_nodes,
                     (long long)job->n_fe_dofs);
  return CUPID_SUCCESS;
}

cupid_status cupid_app_fe_constraints(cupid_job *job) {
  return cupid_cuf_apply_constraints(job->beam, job->model, job->bc);
}

cupid_status cupid_app_fe_loads(cupid_job *job) {
  return cupid_cuf_load_vector(job->beam, job->model, job->f_ext);
}

static void field_of_model(void *ctx, const double p[3], double density, double out[3]) {
  const cupid_value *v = ctx;
  for (int c = 0; c < 3; c++) out[c] = cupid_value_eval(&v[c], p[0], p[1], p[2], 0.0, density);
}

/* `evaluate`: the generalised DOFs that represent the imposed field (LE: nodal values; TE:
 * the section-wise L2 projection, exact for polynomials up to the expansion order). */
cupid_status cupid_app_fe_impose_field(cupid_job *job) {
  return cupid_cuf_interpolate(job->beam, field_of_model, (void *)job->model->analysis.field,
                               job->u);
}

static void unit_field(void *ctx, const double p[3], double density, double out[3]) {
  const int *k = ctx;
  for (int c = 0; c < 3; c++) out[c] = c == *k ? 1.0 : 0.0;
}

cupid_status cupid_app_translations(const cupid_job *job, double *t) {
  for (int k = 0; k < 3; k++) {
    double *tk = t + (size_t)k * (size_t)job->ndof;
    for (cupid_int i = 0; i < job->n_pd; i++) tk[3 * i + k] = 1.0;
    if (job->beam) CUPID_CALL(cupid_cuf_interpolate(job->beam, unit_field, &k, tk));
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_app_fe_write_vtu(cupid_job *job, const char *path) {
  cupid_cuf_vtu *vtu = NULL;
  CUPID_CALL(cupid_cuf_vtu_build(job->beam, job->u, 0, &vtu));
  cupid_status st = cupid_vtu_write(path, &vtu->mesh);
  cupid_cuf_vtu_destroy(&vtu);
  return st;
}
