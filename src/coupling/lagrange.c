/* The Lagrange-multiplier PD-CUF coupling (the baseline of paper 000, section 5.1; cuf.md
 * section 7), by elimination of the constraints u_q = sum_n w_n(p_q) u_n for the real PD nodes
 * q of the layer nearest every interface face (normal and parallel to the axis), p_q their
 * point on the face (see coupling.h); the tie also carries loads and, in dynamics, masses. */
#include <math.h>
#include <string.h>

#include "coupling_internal.h"

#define TOL 1e-9

/* The region of node x (the first box holding it), or -1. */
static int region_of(const cupid_coupling_options *o, const double *x, double tol) {
  for (int r = 0; r < o->n_regions; r++)
    if (cupid_box_contains(&o->regions[r], x, tol)) return r;
  return -1;
}

/* The interface point of node x of region r: every coordinate whose node layer is the one
 * nearest a face of the box (h/2 inside) and whose mirror image across that face lies in an
 * active part of the beam is moved onto the face (normal faces: y; parallel faces: x, z; a node
 * in an edge or corner layer lands on the edge or corner). Returns the faces crossed as bits
 * 2 * axis + side (0: not tied). */
static int interface_point(cupid_cuf_beam beam, const cupid_box *b, const double *x, double h,
                           double pt[3]) {
  int faces = 0;
  for (int a = 0; a < 3; a++) pt[a] = x[a];
  for (int a = 0; a < 3; a++) {
    if (!b->has[a]) continue;
    for (int side = 0; side < 2; side++) {
      double bound = side ? b->hi[a] : b->lo[a];
      double layer = side ? bound - 0.5 * h : bound + 0.5 * h;
      if (fabs(x[a] - layer) > TOL * h) continue;
      double mirror[3] = {x[0], x[1], x[2]};
      mirror[a] = 2.0 * bound - x[a];
      if (!cupid_cuf_contains(beam, mirror[0], mirror[1], mirror[2])) continue;
      pt[a] = bound;
      faces |= 1 << (2 * a + side);
    }
  }
  return faces;
}

/* The tied nodes and their weights (the CUF expansion at the interface point); counts the
 * interfaces (region faces with tied nodes) into c->info.n_interfaces. */
static cupid_status tie_nodes(cupid_coupling_h c, cupid_cuf_beam beam, cupid_pd_grid grid,
                              const cupid_coupling_options *o, int M, int p) {
  cupid_int n = cupid_pd_grid_num_nodes(grid);
  const double *x = cupid_pd_grid_coords(grid);
  double h = o->spacing;
  cupid_int cap = 1024, nw = 0;
  cupid_int *node = NULL;
  double *w = NULL;
  int *faces_seen = NULL;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cupid_malloc((size_t)n + 1, sizeof *c->tied, "tied nodes", &c->tied));
  CUPID_TRY(cupid_calloc((size_t)n + 1, sizeof *c->tptr, "tied pointers", &c->tptr));
  CUPID_TRY(cupid_malloc((size_t)cap, sizeof *c->tnode, "tied weights", &c->tnode));
  CUPID_TRY(cupid_malloc((size_t)cap, sizeof *c->tw, "tied weights", &c->tw));
  CUPID_TRY(cupid_malloc((size_t)(M * p), sizeof *node, "shape nodes", &node));
  CUPID_TRY(cupid_malloc((size_t)(M * p), sizeof *w, "shape weights", &w));
  CUPID_TRY(cupid_calloc((size_t)o->n_regions + 1, sizeof *faces_seen, "interface faces",
                         &faces_seen));
  for (cupid_int i = 0; i < n; i++) {
    const double *xi = x + 3 * i;
    int r = region_of(o, xi, TOL * h);
    if (r < 0) continue;
    double pt[3];
    int faces = interface_point(beam, &o->regions[r], xi, h, pt);
    if (!faces) continue;
    faces_seen[r] |= faces;
    int count;
    CUPID_TRY(cupid_cuf_shape_at(beam, pt[0], pt[1], pt[2], node, w, &count));
    for (int k = 0; k < count; k++) {
      if (w[k] == 0.0) continue;
      if (nw == cap) {
        cap *= 2;
        CUPID_TRY(cupid_realloc((size_t)cap, sizeof *c->tnode, "tied weights", &c->tnode));
        CUPID_TRY(cupid_realloc((size_t)cap, sizeof *c->tw, "tied weights", &c->tw));
      }
      c->tnode[nw] = node[k];
      c->tw[nw++] = w[k];
    }
    c->tied[c->n_tied++] = i;
    c->tptr[c->n_tied] = nw;
  }
  c->info.n_interfaces = 0;
  for (int r = 0; r < o->n_regions; r++)
    for (int f = 0; f < 6; f++) c->info.n_interfaces += (faces_seen[r] >> f) & 1;
cleanup:
  cupid_free(&node);
  cupid_free(&w);
  cupid_free(&faces_seen);
  return st;
}

/* Row i of K_PD through T: master columns stay, tied columns go to FE columns. */
static cupid_status pd_row_through_t(cpl_rowbuild *rb, const cupid_csr_t *Kp, cupid_int i,
                                     double s, const cupid_int *tied_of,
                                     const struct cupid_coupling_private *c) {
  for (cupid_int k = Kp->rowptr[i]; k < Kp->rowptr[i + 1]; k++) {
    cupid_int j = Kp->col[k];
    const double *blk = Kp->val + 9 * k;
    cupid_int t = tied_of[j];
    if (t < 0) {
      CUPID_CALL(cpl_rowbuild_add(rb, j, s, blk));
    } else {
      for (cupid_int n = c->tptr[t]; n < c->tptr[t + 1]; n++)
        CUPID_CALL(cpl_rowbuild_add(rb, c->fe_block + c->tnode[n], s * c->tw[n], blk));
    }
  }
  return CUPID_SUCCESS;
}

/* K = T^T diag(K_PD, K_FE) T, row by row, from the PD matrix @p Kp and what @p c keeps. */
static cupid_status eliminated_matrix(const struct cupid_coupling_private *c, const cupid_csr_t *Kp,
                                      cupid_csr *K) {
  const cupid_int n_pd = c->fe_block, nfe = c->n_fe;
  const cupid_csr_t *Kb = c->Kb;
  cpl_rowbuild rb = {0};
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(cpl_rowbuild_init(&rb, n_pd + nfe, n_pd + nfe));
  for (cupid_int i = 0; i < n_pd; i++) {
    if (c->tied_of[i] < 0) CUPID_TRY(pd_row_through_t(&rb, Kp, i, 1.0, c->tied_of, c));
    CUPID_TRY(cpl_rowbuild_end_row(&rb, i));
  }
  for (cupid_int a = 0; a < nfe; a++) {
    for (cupid_int k = Kb->rowptr[a]; k < Kb->rowptr[a + 1]; k++)
      CUPID_TRY(cpl_rowbuild_add(&rb, n_pd + Kb->col[k], 1.0, Kb->val + 9 * k));
    for (cupid_int k = c->fptr[a]; k < c->fptr[a + 1]; k++)
      CUPID_TRY(pd_row_through_t(&rb, Kp, c->flist[k], c->fw[k], c->tied_of, c));
    CUPID_TRY(cpl_rowbuild_end_row(&rb, n_pd + a));
  }
  CUPID_TRY(cpl_rowbuild_finish(&rb, K));
cleanup:
  cpl_rowbuild_free(&rb);
  return st;
}

cupid_status cupid_coupling_lagrange_create(cupid_cuf_beam beam, cupid_pd_grid grid,
                                            const cupid_coupling_options *o, cupid_coupling_h *out,
                                            cupid_csr *K) {
  cupid_status st = CUPID_SUCCESS;
  cupid_coupling_h c = NULL;
  cupid_pd_operator op = NULL;
  cupid_csr Kp = NULL;
  cupid_cuf_info info;
  cupid_cuf_get_info(beam, &info);
  int M = info.M, p = info.element_nodes;
  cupid_int n_pd = cupid_pd_grid_num_nodes(grid), nfe = info.n_fe_nodes;
  for (int r = 0; r < o->n_regions; r++)
    CUPID_CHECK(info.expansion != CUPID_EXPANSION_TE || cpl_region_full(beam, &o->regions[r]),
                CUPID_ERR_MODEL,
                "PD region %d covers part of the cross-section: a TE expansion spans the whole "
                "section and cannot be tied in part (use an LE section or a full-section region)",
                r);
  CUPID_CHECK(info.dof_offset == 3 * n_pd, CUPID_ERR_ARGUMENT,
              "the beam's DOF offset (%lld) must be 3 x the real PD nodes (%lld)",
              (long long)info.dof_offset, (long long)(3 * n_pd));
  CUPID_CALL(cupid_calloc(1, sizeof *c, "coupling", &c));
  c->fe_block = n_pd;
  c->n_fe = nfe;
  c->tie_M = M;
  c->tie_te = info.expansion == CUPID_EXPANSION_TE;
  CUPID_TRY(tie_nodes(c, beam, grid, o, M, p));

  /* Transpose of the tie map: for each FE node, the tied nodes and weights. */
  CUPID_TRY(cupid_malloc((size_t)n_pd + 1, sizeof *c->tied_of, "tied index", &c->tied_of));
  for (cupid_int i = 0; i < n_pd; i++) c->tied_of[i] = -1;
  for (cupid_int t = 0; t < c->n_tied; t++) c->tied_of[c->tied[t]] = t;
  cupid_int nw = c->n_tied ? c->tptr[c->n_tied] : 0;
  CUPID_TRY(cupid_calloc((size_t)nfe + 1, sizeof *c->fptr, "FE tie pointers", &c->fptr));
  CUPID_TRY(cupid_malloc((size_t)nw + 1, sizeof *c->flist, "FE tie list", &c->flist));
  CUPID_TRY(cupid_malloc((size_t)nw + 1, sizeof *c->fw, "FE tie weights", &c->fw));
  cupid_int *fptr = c->fptr;
  for (cupid_int k = 0; k < nw; k++) fptr[c->tnode[k] + 1]++;
  for (cupid_int a = 0; a < nfe; a++) fptr[a + 1] += fptr[a];
  for (cupid_int t = 0; t < c->n_tied; t++)
    for (cupid_int k = c->tptr[t]; k < c->tptr[t + 1]; k++) {
      cupid_int a = c->tnode[k], pos = fptr[a]++;
      c->flist[pos] = c->tied[t];
      c->fw[pos] = c->tw[k];
    }
  for (cupid_int a = nfe; a > 0; a--) fptr[a] = fptr[a - 1];
  fptr[0] = 0;

  if (o->pd_operator) { /* the caller's, with its removed bonds (fracture) */
    CUPID_TRY(cupid_pd_operator_assemble(o->pd_operator, &Kp));
  } else {
    CUPID_TRY(cupid_pd_operator_create(grid, &o->pd, &op));
    CUPID_TRY(cupid_pd_operator_assemble(op, &Kp));
    cupid_pd_operator_destroy(&op);
  }
  CUPID_TRY(cupid_cuf_assemble(beam, &c->Kb));
  CUPID_TRY(eliminated_matrix(c, Kp, K));
  c->info.n_real_pd = n_pd;
  *out = c;
  c = NULL;
cleanup:
  cupid_csr_destroy(&Kp);
  cupid_pd_operator_destroy(&op);
  cupid_coupling_destroy(&c);
  return st;
}

cupid_status cupid_coupling_lagrange_update(const cupid_coupling_h c, const cupid_pd_operator op,
                                            cupid_csr *K) {
  CUPID_CHECK(c && c->Kb && op && K, CUPID_ERR_ARGUMENT,
              "cupid_coupling_lagrange_update needs a Lagrange coupling and a PD operator");
  cupid_csr Kp = NULL;
  CUPID_CALL(cupid_pd_operator_assemble(op, &Kp));
  cupid_status st = eliminated_matrix(c, Kp, K);
  cupid_csr_destroy(&Kp);
  return st;
}

void cupid_coupling_tied(const cupid_coupling_h c, const cupid_int **nodes, cupid_int *n) {
  *nodes = c->tied;
  *n = c->n_tied;
}

void cupid_coupling_recover(const cupid_coupling_h c, double *u) {
  for (cupid_int t = 0; t < c->n_tied; t++) {
    double *ui = u + 3 * c->tied[t];
    ui[0] = ui[1] = ui[2] = 0.0;
    for (cupid_int k = c->tptr[t]; k < c->tptr[t + 1]; k++) {
      const double *v = u + 3 * (c->fe_block + c->tnode[k]);
      for (int a = 0; a < 3; a++) ui[a] += c->tw[k] * v[a];
    }
  }
}

void cupid_coupling_lagrange_load(const cupid_coupling_h c, double *f) {
  for (cupid_int t = 0; t < c->n_tied; t++) {
    double *ft = f + 3 * c->tied[t];
    for (cupid_int k = c->tptr[t]; k < c->tptr[t + 1]; k++) {
      double *fa = f + 3 * (c->fe_block + c->tnode[k]);
      for (int a = 0; a < 3; a++) fa[a] += c->tw[k] * ft[a];
    }
    ft[0] = ft[1] = ft[2] = 0.0;
  }
}

/* HRZ factor of one tied node: 1 / sum of w^2 over its translational functions (every LE node;
 * the constant TE term, tau = 0), so that those carry its mass in each direction. */
static double hrz_scale(const cupid_coupling_h c, cupid_int t) {
  double s = 0.0;
  for (cupid_int k = c->tptr[t]; k < c->tptr[t + 1]; k++)
    if (!c->tie_te || c->tnode[k] % c->tie_M == 0) s += c->tw[k] * c->tw[k];
  return s > 0.0 ? 1.0 / s : 0.0;
}

cupid_status cupid_coupling_lagrange_mass(const cupid_coupling_h c, const double *pd_mass,
                                          cupid_csr M, double *lumped) {
  CUPID_CHECK((M == NULL) != (lumped == NULL), CUPID_ERR_ARGUMENT,
              "the Lagrange tied mass goes into exactly one of M and lumped");
  for (cupid_int t = 0; t < c->n_tied; t++) {
    double m = pd_mass[c->tied[t]];
    if (lumped) {
      double s = m * hrz_scale(c, t);
      for (cupid_int k = c->tptr[t]; k < c->tptr[t + 1]; k++)
        for (int a = 0; a < 3; a++)
          lumped[3 * (c->fe_block + c->tnode[k]) + a] += s * c->tw[k] * c->tw[k];
      continue;
    }
    for (cupid_int k = c->tptr[t]; k < c->tptr[t + 1]; k++)
      for (cupid_int l = c->tptr[t]; l < c->tptr[t + 1]; l++) {
        double *blk = cupid_csr_find(M, c->fe_block + c->tnode[k], c->fe_block + c->tnode[l]);
        CUPID_CHECK(blk, CUPID_ERR_INTERNAL,
                    "the mass pattern lacks the block of FE nodes %lld, %lld (tied PD node %lld)",
                    (long long)c->tnode[k], (long long)c->tnode[l], (long long)c->tied[t]);
        double v = m * c->tw[k] * c->tw[l];
        for (int a = 0; a < 3; a++) blk[4 * a] += v;
      }
  }
  return CUPID_SUCCESS;
}
