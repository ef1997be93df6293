/* The fictitious-node coupling for PD regions over part of the cross-section (paper 000,
 * section 4.4: interfaces parallel to the beam axis as well as normal to it; see coupling.h).
 *
 * PD side (Eqs. 29-30): fictitious PD nodes at every lattice position within 2 delta of a
 * region's box that lies inside an active part of the beam (any side: normal and parallel
 * interfaces alike), interpolated from the FE field.
 *
 * FE side (Eqs. 31-38, Remarks 1-2, Eq. 37): the fictitious FE elements are the removed
 * (beam element, section element) pairs themselves. Their nodes that are still used by an
 * active pair are real FE nodes (Eq. 37: nodes on the surface of real elements take the real
 * FE field); the others lie in the PD region and are interpolated from the real PD nodes. An
 * LE node value is the displacement at the node's point, so the interpolation is the
 * trilinear interpolation of the 8 real PD nodes around that point (Eq. 31 solved for the
 * node value; exact for affine fields). A node shared by several removed pairs gets one
 * interpolation (the average of Remark 1 of equal rows), a PD node feeds every fictitious node
 * near it (Remark 2). Only rows of real FE nodes are kept (Eq. 38). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "coupling_internal.h"
#include "cupid/coupling.h"

#define TOL 1e-9

static double snap_lo(double v, double a, double h) {
  return a + h * ceil((v - a) / h - 0.5 - TOL);
}
static double snap_hi(double v, double a, double h) {
  return a + h * (floor((v - a) / h - 0.5 + TOL) + 1.0);
}

/* Extended grid: the real regions, then, for every region and section element, the part of
 * the element within 2 delta (whole spacings) of the region's box over the beam's y range. */
cupid_status cpl_partial_extended_grid(cupid_cuf_beam beam, const cupid_coupling_options *o,
                                       const cupid_pd_grid_partition *cut, cupid_pd_grid *ext) {
  cupid_status st = CUPID_SUCCESS;
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  cupid_int nse = info.n_section_elements;
  int cap = o->n_regions * (int)(nse + 1);
  cupid_box *boxes = NULL;
  int *mats = NULL;
  double h = o->spacing;
  double radius = o->pd.horizon +
                  (o->pd.partial_volume == CUPID_PARTIAL_EXACT ? 0.5 * sqrt(3.0) * h : 0.0);
  double L = h * ceil(2.0 * radius / h - TOL);
  CUPID_TRY(cupid_calloc((size_t)cap, sizeof *boxes, "extended boxes", &boxes));
  CUPID_TRY(cupid_calloc((size_t)cap, sizeof *mats, "extended materials", &mats));
  double anchor[3];
  for (int a = 0; a < 3; a++) anchor[a] = o->regions[0].lo[a];
  int k = 0;
  for (int r = 0; r < o->n_regions; r++) {
    boxes[k] = o->regions[r];
    mats[k++] = o->region_materials[r];
  }
  for (int r = 0; r < o->n_regions; r++) {
    const cupid_box *rb = &o->regions[r];
    for (cupid_int se = 0; se < nse; se++) {
      int npe, mat;
      double sb[4];
      cupid_cuf_section_element(beam, se, &npe, NULL, &mat, sb);
      double lo[3] = {fmax(rb->lo[0] - L, sb[0]), fmax(rb->lo[1] - L, info.y_min),
                      fmax(rb->lo[2] - L, sb[2])};
      double hi[3] = {fmin(rb->hi[0] + L, sb[1]), fmin(rb->hi[1] + L, info.y_max),
                      fmin(rb->hi[2] + L, sb[3])};
      cupid_box b = {.has = {1, 1, 1}};
      int empty = 0;
      for (int a = 0; a < 3; a++) {
        b.lo[a] = snap_lo(lo[a], anchor[a], h);
        b.hi[a] = snap_hi(hi[a], anchor[a], h);
        empty |= b.hi[a] - b.lo[a] < 0.5 * h;
      }
      if (empty) continue;
      boxes[k] = b;
      mats[k++] = o->region_materials[r];
    }
  }
  cupid_pd_grid_options go = cpl_ext_grid_options(h, cut);
  CUPID_TRY(cupid_pd_grid_create(&go, k, boxes, mats, ext));
cleanup:
  cupid_free(&boxes);
  cupid_free(&mats);
  return st;
}

/* Trilinear weights of the 8 real PD nodes of the lattice cell around p (shifted by one cell
 * where p lies in the outer half cell of a region: then it extrapolates, still exact for
 * affine fields). */
static cupid_status pd_trilinear(cupid_pd_grid grid, const double p[3], cupid_int node[8],
                                 double w[8]) {
  double o[3], h = cupid_pd_grid_spacing(grid), t[3];
  cupid_pd_grid_origin(grid, o);
  cupid_int i0[3];
  for (int a = 0; a < 3; a++) {
    t[a] = (p[a] - o[a]) / h - 0.5;
    i0[a] = (cupid_int)floor(t[a] + TOL);
  }
  static const int order[3] = {0, -1, 1};
  for (int s = 0; s < 27; s++) {
    cupid_int j[3] = {i0[0] + order[s % 3], i0[1] + order[(s / 3) % 3], i0[2] + order[s / 9]};
    int ok = 1;
    for (int c = 0; c < 8 && ok; c++) {
      node[c] = cupid_pd_grid_node_at(grid, j[0] + (c & 1), j[1] + ((c >> 1) & 1),
                                      j[2] + ((c >> 2) & 1));
      ok = node[c] >= 0;
    }
    if (!ok) continue;
    for (int c = 0; c < 8; c++) {
      w[c] = 1.0;
      for (int a = 0; a < 3; a++) {
        double f = t[a] - (double)j[a];
        w[c] *= ((c >> a) & 1) ? f : 1.0 - f;
      }
    }
    return CUPID_SUCCESS;
  }
  return CUPID_ERROR(CUPID_ERR_MODEL,
                     "fictitious FE node (%g, %g, %g) has no 2 x 2 x 2 block of real PD nodes "
                     "around it (a PD region over part of the section must be at least two "
                     "spacings thick in x, y and z)",
                     p[0], p[1], p[2]);
}

/* The removed pairs' stiffness (same FE numbering): a twin beam with only those pairs active. */
static cupid_status removed_stiffness(cupid_cuf_beam beam, const cupid_coupling_options *o,
                                      cupid_cuf_beam *twin_out, cupid_csr *Kr) {
  cupid_status st = CUPID_SUCCESS;
  cupid_cuf_beam twin = NULL;
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  CUPID_TRY(cupid_cuf_beam_create_from(o->beam_def, o->materials, o->n_materials, &twin));
  for (cupid_int e = 0; e < info.n_beam_elements; e++)
    for (cupid_int se = 0; se < info.n_section_elements; se++)
      CUPID_TRY(cupid_cuf_set_active(twin, e, se, !cupid_cuf_is_active(beam, e, se)));
  CUPID_TRY(cupid_cuf_assemble(twin, Kr));
  *twin_out = twin;
  twin = NULL;
cleanup:
  cupid_cuf_beam_destroy(&twin);
  return st;
}

/* Interpolation of every fictitious FE node (a node of a removed pair used by no active
 * pair) from the real PD nodes: fptr/fnode/fw over FE nodes (empty for real ones). */
typedef struct {
  cupid_int *ptr, *pd;
  double *w;
  cupid_int n_fict;
} fe_interp;

static cupid_status fictitious_fe(cupid_cuf_beam beam, cupid_cuf_beam twin, cupid_pd_grid grid,
                                  fe_interp *fi) {
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  cupid_int n = info.n_fe_nodes, M = info.M;
  CUPID_CALL(cupid_calloc((size_t)n + 1, sizeof *fi->ptr, "fictitious FE pointers", &fi->ptr));
  CUPID_CALL(cupid_malloc((size_t)(8 * n), sizeof *fi->pd, "fictitious FE nodes", &fi->pd));
  CUPID_CALL(cupid_malloc((size_t)(8 * n), sizeof *fi->w, "fictitious FE weights", &fi->w));
  cupid_int nw = 0;
  fi->n_fict = 0;
  for (cupid_int a = 0; a < n; a++) {
    int tau = (int)(a % M);
    cupid_int bn = a / M;
    if (cupid_cuf_node_used(twin, tau, bn) && !cupid_cuf_node_used(beam, tau, bn)) {
      double xz[2], hh;
      cupid_cuf_section_node(beam, tau, xz, &hh);
      double p[3] = {xz[0], cupid_cuf_beam_node_y(beam, bn), xz[1]};
      CUPID_CALL(pd_trilinear(grid, p, fi->pd + nw, fi->w + nw));
      nw += 8;
      fi->n_fict++;
    }
    fi->ptr[a + 1] = nw;
  }
  return CUPID_SUCCESS;
}

static void fe_interp_free(fe_interp *fi) {
  cupid_free(&fi->ptr);
  cupid_free(&fi->pd);
  cupid_free(&fi->w);
}

/* Rows of real FE nodes: K^FE of the active pairs, plus the removed pairs' blocks, real
 * columns to FE columns and fictitious ones through their PD interpolation (Eq. 38). */
static cupid_status partial_fe_rows(cpl_rowbuild *rb, cupid_cuf_beam beam, const cupid_csr_t *Kb,
                                    const cupid_csr_t *Kr, const fe_interp *fi, cupid_int n_pd) {
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  int M = info.M;
  for (cupid_int a = 0; a < info.n_fe_nodes; a++) {
    for (cupid_int k = Kb->rowptr[a]; k < Kb->rowptr[a + 1]; k++)
      CUPID_CALL(cpl_rowbuild_add(rb, n_pd + Kb->col[k], 1.0, Kb->val + 9 * k));
    if (cupid_cuf_node_used(beam, (int)(a % M), a / M)) {
      for (cupid_int k = Kr->rowptr[a]; k < Kr->rowptr[a + 1]; k++) {
        cupid_int c = Kr->col[k];
        const double *blk = Kr->val + 9 * k;
        if (fi->ptr[c + 1] == fi->ptr[c]) {
          CUPID_CALL(cpl_rowbuild_add(rb, n_pd + c, 1.0, blk));
        } else {
          for (cupid_int q = fi->ptr[c]; q < fi->ptr[c + 1]; q++)
            if (fi->w[q] != 0.0) CUPID_CALL(cpl_rowbuild_add(rb, fi->pd[q], fi->w[q], blk));
        }
      }
    }
    CUPID_CALL(cpl_rowbuild_end_row(rb, n_pd + a));
  }
  return CUPID_SUCCESS;
}

/* Region faces with fictitious PD nodes beyond them (the interfaces, for the summary). */
static int count_interfaces(cupid_pd_grid ext, const ext_map *m, const cupid_coupling_options *o) {
  cupid_int n_ext = cupid_pd_grid_num_nodes(ext);
  const double *x = cupid_pd_grid_coords(ext);
  int count = 0;
  for (int r = 0; r < o->n_regions; r++) {
    const cupid_box *b = &o->regions[r];
    for (int f = 0; f < 6; f++) {
      int a = f / 2, hi = f % 2, found = 0;
      for (cupid_int i = 0; i < n_ext && !found; i++) {
        if (m->real[i] >= 0) continue;
        const double *p = x + 3 * i;
        int in = hi ? p[a] > b->hi[a] : p[a] < b->lo[a];
        for (int d = 0; d < 3 && in; d++)
          if (d != a) in = p[d] > b->lo[d] && p[d] < b->hi[d];
        found = in;
      }
      count += found;
    }
  }
  return count;
}

cupid_status cpl_partial_parts(cupid_cuf_beam beam, cupid_pd_grid grid,
                               const cupid_coupling_options *o, cupid_coupling_h c, cpl_parts *p) {
  cupid_status st = CUPID_SUCCESS;
  cupid_csr Kb = NULL, Kr = NULL;
  cupid_cuf_beam twin = NULL;
  fe_interp fi = {0};
  cpl_rowbuild rb = {0};
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  CUPID_CHECK(info.expansion == CUPID_EXPANSION_LE, CUPID_ERR_MODEL,
              "a PD region over part of the section needs an LE section expansion");
  cupid_int n_pd = p->n_pd;

  CUPID_TRY(cpl_partial_extended_grid(beam, o, NULL, &p->ext));
  p->n_ext = cupid_pd_grid_num_nodes(p->ext);
  CUPID_TRY(cpl_map_extended(p->ext, grid, beam, info.M, info.element_nodes, &p->map, &p->n_fict));
  CUPID_TRY_CHECK(p->n_ext - p->n_fict == n_pd, CUPID_ERR_ARGUMENT,
                  "extended grid holds %lld real nodes, expected %lld",
                  (long long)(p->n_ext - p->n_fict), (long long)n_pd);

  CUPID_TRY(cupid_cuf_assemble(beam, &Kb));
  CUPID_TRY(removed_stiffness(beam, o, &twin, &Kr));
  CUPID_TRY(fictitious_fe(beam, twin, grid, &fi));

  cupid_int N = n_pd + info.n_fe_nodes;
  CUPID_TRY(cpl_rowbuild_init(&rb, info.n_fe_nodes, N));
  CUPID_TRY(partial_fe_rows(&rb, beam, Kb, Kr, &fi, n_pd));
  CUPID_TRY(cpl_rowbuild_finish(&rb, &p->Kfe));
  c->info = (cupid_coupling_info){.n_real_pd = n_pd,
                                  .n_fictitious_pd = p->n_fict,
                                  .n_interfaces = count_interfaces(p->ext, &p->map, o),
                                  .n_fictitious_fe = fi.n_fict};
cleanup:
  cupid_csr_destroy(&Kb);
  cupid_csr_destroy(&Kr);
  cupid_cuf_beam_destroy(&twin);
  fe_interp_free(&fi);
  cpl_rowbuild_free(&rb);
  return st;
}
