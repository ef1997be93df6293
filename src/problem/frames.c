/* The frames a run hands its output writers (io.h, "Output writers"; issue 35): the PD nodes
 * as VTK vertices with their volumes and fields, and the beam's 3D reconstruction (hexahedra)
 * at a solution. The runs build frames; the writers (VTU series, Exodus II, CSV) write them. */
#include <string.h>

#include "problem_internal.h"

cupid_status cupid_problem_vertices_build(cupid_pd_grid grid, cupid_problem_vertices *v) {
  memset(v, 0, sizeof *v);
  const cupid_int n = cupid_pd_grid_num_nodes(grid);
  const double vol = cupid_pd_grid_cell_volume(grid);
  v->grid = grid;
  CUPID_CALL(cupid_malloc((size_t)n + 1, sizeof *v->conn, "VTU connectivity", &v->conn));
  CUPID_CALL(cupid_malloc((size_t)n + 1, sizeof *v->offs, "VTU offsets", &v->offs));
  CUPID_CALL(cupid_malloc((size_t)n + 1, sizeof *v->types, "VTU cell types", &v->types));
  CUPID_CALL(cupid_malloc((size_t)n + 1, sizeof *v->volume, "node volumes", &v->volume));
  for (cupid_int i = 0; i < n; i++)
    v->conn[i] = i, v->offs[i] = i + 1, v->types[i] = CUPID_VTK_VERTEX, v->volume[i] = vol;
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

cupid_status cupid_problem_frame_write(cupid_writer *writers, int n_writers, const cupid_frame *f) {
  for (int k = 0; k < n_writers; k++) CUPID_CALL(cupid_writer_step(writers[k], f));
  return CUPID_SUCCESS;
}
