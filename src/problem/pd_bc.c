/* Constraints and loads on peridynamic nodes.
 *
 * PD has no boundary surface to put a condition on, so conditions act on volume layers:
 *  - clamp {y: Y, layer: L}: every component of the nodes with |y - Y| < L is zero
 *    (L defaults to the horizon: the usual fictitious-layer thickness in PD);
 *  - fix / displacement: nodes whose centre lies in the box;
 *  - traction on the plane y = Y: the nodes whose cell has a face on the plane that is a
 *    free surface of the grid, each loaded with t * (face area inside the patch); on a body
 *    with a cylinder or sphere region or holes, the areas scaled so that they sum to the true
 *    section's (issue 35: its cells are those whose centres lie in it);
 *  - point: the node whose cell contains the point;
 *  - body: force per unit volume times the cell volume, for the nodes in the box. */
#include <math.h>
#include <string.h>

#include "problem_internal.h"

/* Relative tolerance on lattice positions (box bounds on cell faces must include the nodes
 * that sit exactly on them after round-off). */
#define CUPID_LATTICE_TOL 1e-9

static void node_lattice(const cupid_problem_state *prob, cupid_int node, cupid_int ijk[3]) {
  const double *x = cupid_pd_grid_coords(prob->grid) + 3 * node;
  double o[3], h = cupid_pd_grid_spacing(prob->grid);
  cupid_pd_grid_origin(prob->grid, o);
  for (int a = 0; a < 3; a++) ijk[a] = (cupid_int)floor((x[a] - o[a]) / h);
  if (cupid_pd_grid_dimension(prob->grid) == 1) ijk[0] = ijk[2] = 0;
}

/* 1 if PD node i is one the constraint holds. */
static int in_constraint(const cupid_problem_state *prob, const cupid_constraint *c, cupid_int i) {
  const double *p = cupid_pd_grid_coords(prob->grid) + 3 * i;
  const double h = cupid_pd_grid_spacing(prob->grid);
  const double layer = c->layer > 0 ? c->layer : prob->model->pd.horizon;
  return c->kind == CUPID_CONSTRAINT_CLAMP ? fabs(p[1] - c->plane_y) < layer
                                           : cupid_box_contains(&c->box, p, CUPID_LATTICE_TOL * h);
}

/* The constraint's values on node i, at the problem's time. */
static void prescribe_node(cupid_problem_state *prob, const cupid_constraint *c, cupid_int i) {
  const cupid_model_t *m = prob->model;
  const double *p = cupid_pd_grid_coords(prob->grid) + 3 * i;
  const int *mat = cupid_pd_grid_materials(prob->grid);
  for (int a = 0; a < 3; a++) {
    cupid_int d = 3 * i + a;
    if (c->kind == CUPID_CONSTRAINT_DISPLACEMENT) {
      if (c->value[a].kind == CUPID_VALUE_NONE) continue;
      prob->bc->fixed[d] = 1;
      prob->bc->value[d] =
          cupid_value_eval(&c->value[a], p[0], p[1], p[2], prob->time, m->materials[mat[i]].density);
    } else if (c->kind == CUPID_CONSTRAINT_CLAMP || c->components[a]) {
      prob->bc->fixed[d] = 1;
      prob->bc->value[d] = 0.0;
    }
  }
}

static cupid_status constraint_on_nodes(cupid_problem_state *prob, const cupid_constraint *c,
                                        cupid_int *count) {
  *count = 0;
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    if (!in_constraint(prob, c, i)) continue;
    *count += cupid_problem_pd_owned(prob, i);
    prescribe_node(prob, c, i);
  }
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_pd_prescribe(cupid_problem_state *prob, const cupid_constraint *c) {
  cupid_int count;
  return constraint_on_nodes(prob, c, &count);
}

cupid_status cupid_problem_pd_constraint_nodes(const cupid_problem_state *prob,
                                               const cupid_constraint *c, cupid_int **nodes,
                                               cupid_int *n) {
  *nodes = NULL, *n = 0;
  cupid_int count = 0;
  for (cupid_int i = 0; i < prob->n_pd; i++) count += in_constraint(prob, c, i);
  CUPID_CALL(cupid_malloc((size_t)count + 1, sizeof **nodes, "constrained nodes", nodes));
  for (cupid_int i = 0; i < prob->n_pd; i++)
    if (in_constraint(prob, c, i)) (*nodes)[(*n)++] = i;
  return CUPID_SUCCESS;
}

void cupid_problem_pd_prescribe_nodes(cupid_problem_state *prob, const cupid_constraint *c,
                                      const cupid_int *nodes, cupid_int n) {
  /* distinct nodes, thread-safe expressions (a stack each): one node a thread at a time */
#pragma omp parallel for schedule(static) if (n > 4096)
  for (cupid_int k = 0; k < n; k++) prescribe_node(prob, c, nodes[k]);
}

/* A 1D grid is a bar along y: its x and z components carry no stiffness, so they are
 * eliminated (held at zero) rather than left singular. */
static void eliminate_transverse_1d(cupid_problem_state *prob) {
  if (cupid_pd_grid_dimension(prob->grid) != 1) return;
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    prob->bc->fixed[3 * i] = prob->bc->fixed[3 * i + 2] = 1;
    prob->bc->value[3 * i] = prob->bc->value[3 * i + 2] = 0.0;
  }
}

cupid_status cupid_problem_pd_constraints(cupid_problem_state *prob, const cupid_constraint *cons,
                                          int n) {
  const cupid_model_t *m = prob->model;
  eliminate_transverse_1d(prob);
  for (int k = 0; k < n; k++) {
    const cupid_constraint *c = &cons[k];
    cupid_int count;
    CUPID_CALL(constraint_on_nodes(prob, c, &count));
    CUPID_CALL(cupid_problem_check_finite(prob, prob->bc->value, &c->mark, "the prescribed displacement"));
    if (cupid_problem_global_count(prob, count) == 0) {
      if (c->kind == CUPID_CONSTRAINT_CLAMP)
        return cupid_model_error(m, &c->mark,
                                 "no PD node lies within %g of the plane y = %g (the clamp fixes "
                                 "a layer of PD nodes; set `layer:` or move the plane)",
                                 c->layer > 0 ? c->layer : m->pd.horizon, c->plane_y);
      return cupid_model_error(m, &c->mark,
                               "the box contains no PD node (PD nodes sit at cell centres, half "
                               "a spacing inside the region faces)");
    }
  }
  /* A clamp layer of zero nodes is caught above; report what was fixed for the log. */
  cupid_int nfixed = 0;
  for (cupid_int d = 0; d < prob->ndof; d++) nfixed += prob->bc->fixed[d] && cupid_problem_pd_owned(prob, d / 3);
  nfixed = cupid_problem_global_count(prob, nfixed);
  cupid_problem_progress(prob, "constraints: %lld DOFs prescribed", (long long)nfixed);
  return CUPID_SUCCESS;
}

/* Area of the cell face of node p (sides h) inside the traction patch (x/z ranges). */
static double face_area(const cupid_load *l, const double *p, double h, int dim, double area) {
  if (dim == 1) return area;
  double a = 1.0;
  const int axes[2] = {0, 2};
  for (int k = 0; k < 2; k++) {
    int ax = axes[k];
    double lo = p[ax] - 0.5 * h, hi = p[ax] + 0.5 * h;
    if (l->patch.has[ax]) {
      lo = fmax(lo, l->patch.lo[ax]);
      hi = fmin(hi, l->patch.hi[ax]);
    }
    a *= hi > lo ? hi - lo : 0.0;
  }
  return a;
}

/* A node lies on the traction plane if its cell has a face there that is a free surface. */
static int on_free_face(const cupid_problem_state *prob, cupid_int node, double plane_y) {
  const double *p = cupid_pd_grid_coords(prob->grid) + 3 * node;
  double h = cupid_pd_grid_spacing(prob->grid);
  double d = plane_y - p[1];
  if (fabs(fabs(d) - 0.5 * h) > CUPID_LATTICE_TOL * h * 10) return 0;
  cupid_int ijk[3];
  node_lattice(prob, node, ijk);
  cupid_int across = ijk[1] + (d > 0 ? 1 : -1);
  return cupid_pd_grid_node_at(prob->grid, ijk[0], across, ijk[2]) < 0;
}

/* A body with a cylinder or sphere region, or holes (issue 35): its cells are those whose
 * centres lie in it, so the cell faces on a plane cover its true section there only nearly. */
static int shaped_body(const cupid_model_t *m) {
  int shaped = m->pd.n_holes > 0;
  for (int r = 0; r < m->pd.n_regions; r++) shaped |= m->pd.regions[r].shape.kind != CUPID_SHAPE_BOX;
  return shaped;
}

/* 1 if p lies in some region's shape and in no hole. */
static int in_body(const cupid_model_t *m, const double p[3]) {
  int in = 0;
  for (int r = 0; r < m->pd.n_regions && !in; r++) in = cupid_shape_contains(&m->pd.regions[r].shape, p);
  for (int q = 0; q < m->pd.n_holes && in; q++) in = !cupid_shape_contains(&m->pd.holes[q].shape, p);
  return in;
}

/* Samples of the true section: at most about TRUE_AREA_SAMPLES, at most 64 per spacing and
 * direction (a curved edge's area to ~h / 128 of its length) */
#define TRUE_AREA_SAMPLES 4.0e6

/* The area of the body's true section on the plane y = Y within the patch, on the side of the
 * loaded faces (side: +1 the body below the plane, -1 above), over [lo, hi] in x and z (the
 * loaded faces and a spacing and a half around them, on the lattice's planes): the midpoints of
 * a grid of h / s. Its lines fall on the lattice's planes, so that a box's edges (on them)
 * are counted exactly. */
static double true_section_area(const cupid_model_t *m, const cupid_load *l, int side,
                                const double lo[2], const double hi[2], double h) {
  const double Y = l->plane_y - side * 1e-6 * h;
  const cupid_int c0 = (cupid_int)llround((hi[0] - lo[0]) / h), c1 = (cupid_int)llround((hi[1] - lo[1]) / h);
  cupid_int sub = (cupid_int)floor(sqrt(TRUE_AREA_SAMPLES / ((double)c0 * (double)c1)));
  sub = sub < 2 ? 2 : sub > 64 ? 64 : sub;
  const cupid_int n0 = c0 * sub, n1 = c1 * sub;
  const double d = h / (double)sub;
  cupid_int hits = 0; /* counted, so that the area has the same bits for any thread count */
#pragma omp parallel for reduction(+ : hits) schedule(static)
  for (cupid_int b = 0; b < n1; b++)
    for (cupid_int a = 0; a < n0; a++) {
      const double p[3] = {lo[0] + ((double)a + 0.5) * d, Y, lo[1] + ((double)b + 0.5) * d};
      if ((l->patch.has[0] && (p[0] < l->patch.lo[0] || p[0] > l->patch.hi[0])) ||
          (l->patch.has[2] && (p[2] < l->patch.lo[2] || p[2] > l->patch.hi[2])))
        continue;
      hits += in_body(m, p);
    }
  return (double)hits * d * d;
}

/* The scale of a traction's loaded faces on a shaped body, as made before for its plane and
 * patch (NULL: not yet). */
static const struct cupid_traction_scale *known_scale(const cupid_problem_state *prob,
                                                      const cupid_load *l) {
  for (int k = 0; k < prob->n_traction_scales; k++) {
    const struct cupid_traction_scale *t = &prob->traction_scales[k];
    if (t->plane_y == l->plane_y && !memcmp(&t->patch, &l->patch, sizeof t->patch)) return t;
  }
  return NULL;
}

/* The loaded faces' scale to the true section on a shaped body (the faces' area and extent
 * over the ranks: every rank makes the call), kept for the plane and patch. */
static cupid_status section_scale(cupid_problem_state *prob, const cupid_load *l,
                                  double lattice_area, double ext[6], double *scale) {
  const cupid_model_t *m = prob->model;
  if (prob->slab) {
    cupid_petsc_max_doubles(ext, 6);
    cupid_petsc_sum_doubles(&lattice_area, 1);
  }
  if (ext[4] > 0.0 && ext[5] > 0.0)
    return cupid_model_error(m, &l->mark,
                             "the plane y = %g is a free surface on both sides of the body (a "
                             "traction acts on one end face: give a patch x/z that selects it)",
                             l->plane_y);
  const double lo[2] = {-ext[0], -ext[1]}, hi[2] = {ext[2], ext[3]};
  *scale = true_section_area(m, l, ext[4] > 0.0 ? 1 : -1, lo, hi, cupid_pd_grid_spacing(prob->grid)) /
           lattice_area;
  struct cupid_traction_scale *t = NULL;
  CUPID_CALL(cupid_realloc((size_t)prob->n_traction_scales + 1, sizeof *t, "traction scales",
                           &prob->traction_scales));
  t = &prob->traction_scales[prob->n_traction_scales++];
  t->plane_y = l->plane_y, t->patch = l->patch, t->scale = *scale;
  return CUPID_SUCCESS;
}

static cupid_status traction_load(cupid_problem_state *prob, const cupid_load *l, double *f) {
  const cupid_model_t *m = prob->model;
  const double *x = cupid_pd_grid_coords(prob->grid);
  const int *mat = cupid_pd_grid_materials(prob->grid);
  double h = cupid_pd_grid_spacing(prob->grid);
  int dim = cupid_pd_grid_dimension(prob->grid);
  /* the loaded faces; on a shaped body their areas are scaled to the true section's (a
   * traction on a cylinder's end face sums to t pi r^2): their extent and the body's side */
  const int shaped = dim == 3 && shaped_body(m);
  cupid_int count = 0;
  double lattice_area = 0.0, ext[6] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY, 0.0, 0.0};
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    if (!on_free_face(prob, i, l->plane_y)) continue;
    const double *p = x + 3 * i;
    const double a = face_area(l, p, h, dim, m->pd.area);
    if (a <= 0 || !cupid_problem_pd_owned(prob, i)) continue;
    count++;
    lattice_area += a;
    ext[p[1] < l->plane_y ? 4 : 5] = 1.0; /* the body below the plane (+y faces), or above */
    for (int k = 0; k < 2; k++) { /* x, z: -lo and hi, a spacing and a half around */
      ext[k] = fmax(ext[k], -(p[2 * k] - 1.5 * h));
      ext[2 + k] = fmax(ext[2 + k], p[2 * k] + 1.5 * h);
    }
  }
  if (cupid_problem_global_count(prob, count) == 0)
    return cupid_model_error(m, &l->mark,
                             "no free PD surface lies on the plane y = %g%s (a traction acts on "
                             "an end face of a PD region)",
                             l->plane_y, l->patch.has[0] || l->patch.has[2] ? " inside the patch" : "");
  double scale = 1.0;
  if (shaped) {
    const struct cupid_traction_scale *known = known_scale(prob, l);
    if (known) scale = known->scale;
    else CUPID_CALL(section_scale(prob, l, lattice_area, ext, &scale));
  }
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    if (!on_free_face(prob, i, l->plane_y)) continue;
    const double *p = x + 3 * i;
    const double a = face_area(l, p, h, dim, m->pd.area) * scale;
    if (a <= 0) continue;
    for (int c = 0; c < 3; c++)
      f[3 * i + c] +=
          a * cupid_value_eval(&l->value[c], p[0], l->plane_y, p[2], prob->time,
                               m->materials[mat[i]].density);
  }
  return CUPID_SUCCESS;
}

static cupid_status point_load(cupid_problem_state *prob, const cupid_load *l, double *f) {
  const cupid_model_t *m = prob->model;
  double o[3], h = cupid_pd_grid_spacing(prob->grid);
  cupid_pd_grid_origin(prob->grid, o);
  int dim = cupid_pd_grid_dimension(prob->grid);
  cupid_int ijk[3];
  for (int a = 0; a < 3; a++) ijk[a] = (cupid_int)floor((l->at[a] - o[a]) / h);
  if (dim == 1) ijk[0] = ijk[2] = 0;
  cupid_int node = cupid_pd_grid_node_at(prob->grid, ijk[0], ijk[1], ijk[2]);
  /* A point on a cell face belongs to the cell below it when the one above is absent. */
  for (int a = 0; a < 3 && node < 0; a++) {
    if (dim == 1 && a != 1) continue;
    double s = (l->at[a] - o[a]) / h;
    if (fabs(s - round(s)) < 1e-9) {
      cupid_int q[3] = {ijk[0], ijk[1], ijk[2]};
      q[a] -= 1;
      node = cupid_pd_grid_node_at(prob->grid, q[0], q[1], q[2]);
    }
  }
  /* a slab: the rank that owns the node counts it (others may hold it in their halo) */
  if (cupid_problem_global_count(prob, node >= 0 && cupid_problem_pd_owned(prob, node)) == 0)
    return cupid_model_error(m, &l->mark, "the point (%g, %g, %g) lies outside every PD region",
                             l->at[0], l->at[1], l->at[2]);
  if (node < 0) return CUPID_SUCCESS; /* on another rank's slab */
  const int *mat = cupid_pd_grid_materials(prob->grid);
  for (int c = 0; c < 3; c++)
    f[3 * node + c] += cupid_value_eval(&l->value[c], l->at[0], l->at[1], l->at[2], prob->time,
                                                 m->materials[mat[node]].density);
  return CUPID_SUCCESS;
}

static cupid_status body_load(cupid_problem_state *prob, const cupid_load *l, double *f) {
  const cupid_model_t *m = prob->model;
  const double *x = cupid_pd_grid_coords(prob->grid);
  const int *mat = cupid_pd_grid_materials(prob->grid);
  double h = cupid_pd_grid_spacing(prob->grid), vol = cupid_pd_grid_cell_volume(prob->grid);
  const double *phi = cupid_pd_grid_volume_fractions(prob->grid); /* cut cells */
  cupid_int count = 0;
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    const double *p = x + 3 * i;
    if (!cupid_box_contains(&l->box, p, CUPID_LATTICE_TOL * h)) continue;
    count += cupid_problem_pd_owned(prob, i);
    double rho = m->materials[mat[i]].density;
    for (int c = 0; c < 3; c++)
      f[3 * i + c] += vol * (phi ? phi[i] : 1.0) *
                      cupid_value_eval(&l->value[c], p[0], p[1], p[2], prob->time, rho);
  }
  if (cupid_problem_global_count(prob, count) == 0)
    return cupid_model_error(m, &l->mark, "the box contains no PD node");
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_pd_loads(cupid_problem_state *prob, const cupid_load *loads, int n,
                                    double *f) {
  for (int k = 0; k < n; k++) {
    const cupid_load *l = &loads[k];
    switch (l->kind) {
    case CUPID_LOAD_TRACTION: CUPID_CALL(traction_load(prob, l, f)); break;
    case CUPID_LOAD_POINT: CUPID_CALL(point_load(prob, l, f)); break;
    case CUPID_LOAD_BODY: CUPID_CALL(body_load(prob, l, f)); break;
    }
    CUPID_CALL(cupid_problem_check_finite(prob, f, &l->mark, "the load"));
  }
  return CUPID_SUCCESS;
}
