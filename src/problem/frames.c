/* The frames a run hands its output writers (io.h, "Output writers"; issue 35): the PD nodes
 * as VTK vertices with their volumes and fields, and the beam's 3D reconstruction (hexahedra)
 * at a solution. The runs build frames; the writers (VTU series, Exodus II, CSV) write them. */
#include <string.h>

#include "problem_internal.h"

cupid_status cupid_problem_vertices_build(cupid_pd_grid grid, cupid_problem_vertices *v) {
  memset(v, 0, sizeof *v);
  const cupid_int n = cupid_pd_grid_num_nodes(grid);
  v->grid = grid;
  CUPID_CALL(cupid_malloc((size_t)n + 1, sizeof *v->conn, "VTU connectivity", &v->conn));
  CUPID_CALL(cupid_malloc((size_t)n + 1, sizeof *v->offs, "VTU offsets", &v->offs));
  CUPID_CALL(cupid_malloc((size_t)n + 1, sizeof *v->types, "VTU cell types", &v->types));
  CUPID_CALL(cupid_malloc((size_t)n + 1, sizeof *v->volume, "node volumes", &v->volume));
  for (cupid_int i = 0; i < n; i++)
    v->conn[i] = i, v->offs[i] = i + 1, v->types[i] = CUPID_VTK_VERTEX,
    v->volume[i] = cupid_pd_grid_node_volume(grid, i);
  return CUPID_SUCCESS;
}

void cupid_problem_vertices_free(cupid_problem_vertices *v) {
  cupid_free(&v->conn);
  cupid_free(&v->offs);
  cupid_free(&v->types);
  cupid_free(&v->volume);
}

cupid_vtu_mesh cupid_problem_vertices_mesh(const cupid_problem_vertices *v,
                                           const cupid_vtu_array *data, int n_data) {
  const cupid_int n = cupid_pd_grid_num_nodes(v->grid);
  return (cupid_vtu_mesh){.n_points = n, .points = cupid_pd_grid_coords(v->grid), .n_cells = n,
                          .connectivity = v->conn, .offsets = v->offs, .types = v->types,
                          .point_data = data, .n_point_data = n_data};
}

cupid_status cupid_problem_frame_write(cupid_problem_state *prob, const cupid_problem_vertices *verts,
                                       cupid_int step, double t, const double *u,
                                       const cupid_vtu_array *fields, int n_fields,
                                       cupid_writer *writers, int n_writers) {
  cupid_frame_part parts[2];
  cupid_vtu_array data[CUPID_FRAME_FIELDS];
  cupid_vtu_mesh pd;
  cupid_cuf_vtu *beam = NULL;
  double *gathered[CUPID_FRAME_FIELDS] = {NULL};
  cupid_status st = CUPID_SUCCESS;
  int np = 0, nd = 0;
  CUPID_CHECK(n_fields <= CUPID_FRAME_FIELDS, CUPID_ERR_INTERNAL, "a frame of %d fields", n_fields);
  if (prob->beam && prob->writedir) {
    CUPID_TRY(cupid_cuf_vtu_build(prob->beam, u, 0, &beam));
    parts[np++] = (cupid_frame_part){"beam", &beam->mesh, NULL};
  }
  for (int k = 0; k < n_fields && prob->grid; k++) {
    if (!fields[k].values) continue; /* a field the run has not (damage without fracture) */
    const double *values = fields[k].values;
    if (prob->slab) {
      CUPID_TRY(cupid_problem_slab_gather(prob, values, fields[k].components, &gathered[k]));
      values = gathered[k];
    }
    data[nd++] = (cupid_vtu_array){fields[k].name, fields[k].components, values};
  }
  if (prob->grid && verts->grid) { /* the rank that writes */
    pd = cupid_problem_vertices_mesh(verts, data, nd);
    parts[np++] = (cupid_frame_part){"pd", &pd, verts->volume};
  }
  const cupid_frame f = {.step = step, .time = t, .n_parts = np, .parts = parts};
  for (int k = 0; k < n_writers && st == CUPID_SUCCESS; k++) st = cupid_writer_step(writers[k], &f);
  if (prob->slab) st = cupid_problem_slab_agree(st);
cleanup:
  cupid_cuf_vtu_destroy(&beam);
  for (int k = 0; k < CUPID_FRAME_FIELDS; k++) cupid_free(&gathered[k]);
  return st;
}
