/* The PD grid of a model file: errors are reported against the file (cupid_model_error).
 * Kept in its own file so that programs using only cupid_pd_grid_create() do not pull in
 * the model reader. */
#include <math.h>
#include <stdio.h>

#include "pd/pd_internal.h"

cupid_status cupid_pd_grid_create_part_from_model(const cupid_model_t *model, int parts, int part,
                                                  int halo_layers, cupid_pd_grid *grid) {
  cupid_status st = CUPID_SUCCESS;
  cupid_box *boxes = NULL;
  cupid_shape *shapes = NULL, *holes = NULL;
  int *mats = NULL;
  *grid = NULL;
  CUPID_CHECK(model, CUPID_ERR_ARGUMENT, "no model");
  const cupid_peridynamics *pd = &model->pd;
  if (!model->has_peridynamics || pd->n_regions <= 0)
    return cupid_model_error(model, &pd->mark, "the peridynamics section needs at least one region");
  CUPID_TRY(cupid_calloc((size_t)pd->n_regions, sizeof *boxes, "PD regions", &boxes));
  CUPID_TRY(cupid_calloc((size_t)pd->n_regions, sizeof *mats, "PD region materials", &mats));
  CUPID_TRY(cupid_calloc((size_t)pd->n_regions, sizeof *shapes, "PD region shapes", &shapes));
  CUPID_TRY(cupid_calloc((size_t)pd->n_holes + 1, sizeof *holes, "PD holes", &holes));
  int any_shape = pd->n_holes > 0;
  for (int q = 0; q < pd->n_holes; q++) holes[q] = pd->holes[q].shape;
  for (int r = 0; r < pd->n_regions; r++) {
    boxes[r] = pd->regions[r].box;
    shapes[r] = pd->regions[r].shape;
    /* a geometry file's bounds are its facets' (or its CAD kernel's, with a tolerance): its
     * lattice planes lie at multiples of the spacing in the file's coordinates instead */
    if (shapes[r].kind == CUPID_SHAPE_GEOMETRY)
      for (int a = 0; a < 3; a++) boxes[r].lo[a] = pd->spacing * floor(boxes[r].lo[a] / pd->spacing + 1e-6);
    any_shape |= shapes[r].kind != CUPID_SHAPE_BOX;
    mats[r] = pd->regions[r].material >= 0 ? pd->regions[r].material : pd->material;
    if (mats[r] < 0 || mats[r] >= model->n_materials) {
      st = cupid_model_error(model, &pd->regions[r].mark,
                             "the region has no material (give material: here or in "
                             "peridynamics)");
      goto cleanup;
    }
  }
  cupid_pd_grid_options opts = {.spacing = pd->spacing, .dimension = pd->dimension,
                                .area = pd->area, .parts = parts, .part = part,
                                .halo_layers = halo_layers,
                                .shapes = any_shape ? shapes : NULL,
                                .n_holes = pd->n_holes,
                                .holes = holes,
                                .cut_volumes = pd->partial_volume == CUPID_PARTIAL_EXACT,
                                .has_anchor = pd->has_anchor,
                                .anchor = {pd->anchor[0], pd->anchor[1], pd->anchor[2]}};
  if (pd->has_slab_window && parts > 1)
    for (int e = 0; e < 2; e++) opts.own_z[e] = pd->slab_window[e];
  char msg[512];
  int bad = -1;
  st = pd_grid_build(&opts, pd->n_regions, boxes, mats, &bad, msg, sizeof msg, grid);
  if (st != CUPID_SUCCESS && bad >= 0) st = cupid_model_error(model, &pd->regions[bad].mark, "%s", msg);
  else if (st == CUPID_ERR_MODEL) { /* about the whole section: keep the text, add the place */
    snprintf(msg, sizeof msg, "%s", cupid_error_message());
    st = cupid_model_error(model, &pd->mark, "%s", msg);
  }
cleanup:
  cupid_free(&boxes);
  cupid_free(&shapes);
  cupid_free(&holes);
  cupid_free(&mats);
  return st;
}

cupid_status cupid_pd_grid_create_from_model(const cupid_model_t *model, cupid_pd_grid *grid) {
  return cupid_pd_grid_create_part_from_model(model, 1, 0, 0, grid);
}
