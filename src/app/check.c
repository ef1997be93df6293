/* Size, memory and time estimates: printed by `cupid check`, and the guard that makes
 * `cupid run` refuse a model that cannot fit before it allocates the big arrays.
 *
 * Stored matrix: one 3x3 block (72 B of values + 8 B of column index) per coupled node pair,
 * counted by cupid_pd_operator_estimate (exact for bond-based; for LPS, which couples nodes up
 * to 2 delta apart, the grid nodes within two stencil hops: an upper bound).
 * Direct factor: nested dissection on a 3D grid gives nnz(L) ~ c n^(4/3) and flops ~ n^2;
 * c and the time scale are fitted to the CHOLMOD measurements on this class of machine in
 * shared/reference/dependencies.md (bond-based, delta = 3h: 20^3 -> 5.3e7 nnz(L), 3.7 s;
 * 40^3 -> 1.23e9, 232 s). LPS couples nodes 2 delta apart: bench/bench_pd_cube measured
 * 15^3 -> 2.38e7 nnz(L), 3.3 s and 20^3 -> 1.08e8, 19 s, i.e. about 3x the fill and 7.5x the
 * time of the bond-based fit. An estimate to decide what fits, not a promise. */
#include <math.h>
#include <stdio.h>
#include <unistd.h>

#include "app_internal.h"

typedef struct {
  double matrix_blocks, matrix_bytes;
  double factor_nnz, factor_bytes, factor_seconds;
  double total_bytes;
} cupid_estimate;

static cupid_status estimate(const cupid_job *job, cupid_estimate *e) {
  const cupid_model_t *m = job->model;
  double n = (double)job->n_pd, ndof = 3.0 * n;
  double ratio = m->pd.horizon / m->pd.spacing;
  cupid_pd_estimate pe;
  CUPID_CALL(cupid_pd_operator_estimate(job->grid, &job->pd_options, &pe));
  e->matrix_blocks = (double)pe.blocks;
  e->matrix_bytes = e->matrix_blocks * 80.0 + 8.0 * n;
  double fill = m->pd.model == CUPID_PD_LPS ? 3.0 : 1.0;
  if (m->pd.dimension == 1) {
    e->factor_nnz = ndof * 3.0 * (2 * ratio + 1); /* banded */
    e->factor_seconds = 1e-7 * e->factor_nnz;
  } else {
    e->factor_nnz = fill * 77.0 * pow(ndof, 4.0 / 3.0);
    double slow = m->pd.model == CUPID_PD_LPS ? 7.5 : 1.0;
    e->factor_seconds = slow * 3.7 * (ndof / 24000.0) * (ndof / 24000.0);
  }
  double dense = 0.5 * ndof * ndof;
  if (e->factor_nnz > dense) e->factor_nnz = dense;
  e->factor_bytes = 12.0 * e->factor_nnz;
  /* K, its reduced one-triangle copy for CHOLMOD (about half of K at 12 B/entry), factor. */
  e->total_bytes = e->matrix_bytes + 0.5 * 9.0 * e->matrix_blocks * 12.0 + e->factor_bytes +
                   10.0 * ndof * 8.0;
  return CUPID_SUCCESS;
}

static double physical_memory(void) {
  long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
  return pages > 0 && size > 0 ? (double)pages * (double)size : 0.0;
}

/* The beam's matrix: its exact pattern (cheap to build) and a banded-profile bound for the
 * factor, since the beam axis orders the DOFs into a band of a few elements' width. */
static cupid_status estimate_fe(const cupid_job *job, cupid_estimate *e) {
  cupid_int *rowptr = NULL, *col = NULL;
  CUPID_CALL(cupid_cuf_pattern(job->beam, &rowptr, &col));
  cupid_int nb = job->fe_info.n_fe_nodes;
  double blocks = (double)rowptr[nb];
  cupid_free(&rowptr);
  cupid_free(&col);
  double ndof = (double)job->n_fe_dofs, bw = 9.0 * blocks / ndof;
  e->matrix_blocks += blocks;
  e->matrix_bytes += blocks * 80.0 + 8.0 * (double)nb;
  e->factor_nnz += 2.0 * ndof * bw;
  e->factor_bytes += 24.0 * ndof * bw;
  e->factor_seconds += 4e-10 * ndof * bw * bw;
  e->total_bytes += 1.5 * blocks * 80.0 + 24.0 * ndof * bw + 10.0 * ndof * 8.0;
  return CUPID_SUCCESS;
}

cupid_status cupid_app_estimate(const cupid_job *job, int print) {
  cupid_estimate e = {0};
  if (job->grid) CUPID_CALL(estimate(job, &e));
  if (job->beam) CUPID_CALL(estimate_fe(job, &e));
  double limit = job->opts->max_memory_gb > 0 ? job->opts->max_memory_gb * 1e9 : 0.9 * physical_memory();
  if (print) {
    const cupid_model_t *m = job->model;
    printf("model: %s%s%s\n", m->file, m->title[0] ? " - " : "", m->title);
    if (job->beam)
      printf("beam: %lld nodes, %lld FE nodes, %lld FE DOFs\n",
             (long long)job->fe_info.n_beam_nodes, (long long)job->fe_info.n_fe_nodes,
             (long long)job->n_fe_dofs);
    if (job->grid)
      printf("PD nodes: %lld\nbonds: %lld\n", (long long)job->n_pd, (long long)job->n_bonds);
    printf("DOFs: %lld\n", (long long)job->ndof);
    printf("stiffness matrix: about %.3g stored 3x3 blocks, %.3g GB\n", e.matrix_blocks,
           e.matrix_bytes / 1e9);
    printf("direct solver (CHOLMOD): about %.3g factor entries, %.3g GB, %.3g s\n", e.factor_nnz,
           e.factor_bytes / 1e9, e.factor_seconds);
    printf("estimated peak memory: %.3g GB (limit %.3g GB)\n", e.total_bytes / 1e9, limit / 1e9);
    printf("the model is valid%s\n", limit > 0 && e.total_bytes > limit
                                          ? ", but too large for the direct solver on this machine"
                                          : "");
  }
  if (!print && limit > 0 && e.total_bytes > limit)
    return CUPID_ERROR(CUPID_ERR_MODEL,
                       "%s: the model needs about %.3g GB (%lld PD nodes; stiffness %.3g GB, "
                       "factor %.3g GB), more than the limit of %.3g GB; use --max-memory GB to "
                       "raise the limit, or a coarser grid",
                       job->model->file, e.total_bytes / 1e9, (long long)job->n_pd,
                       e.matrix_bytes / 1e9, e.factor_bytes / 1e9, limit / 1e9);
  return CUPID_SUCCESS;
}
