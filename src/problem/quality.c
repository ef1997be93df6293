/* The coupling's quality, measured on the model itself (issue 18 item 4; docs/coupling.md,
 * "The quality report of a coupled run"):
 *  - the patch test: the coupled operator applied to the field of uniaxial stress along the
 *    beam axis (u_y = eps y, u_x = -nu eps x, u_z = -nu eps z), an exact solution of
 *    elasticity with free lateral faces that every expansion from TE1 up and every LE section
 *    holds exactly. Its internal forces must vanish everywhere but on the beam's end sections
 *    (the traction there) and on PD nodes whose interactions reach a free surface (the PD
 *    surface effect, a property of PD, not of the coupling). What is left on the other DOFs
 *    is the coupling's ghost force: 0 to round-off for paper 000's fictitious nodes (Eq. 38
 *    reads the exact field), the truncated families at the tied layer for Lagrange, the
 *    weight's gradient in the overlaps for Arlequin.
 *  - the equilibrium imbalance |P + R| / |P| after a static solve (the fictitious-node method
 *    does not conserve momentum).
 * Each figure has a stated bound; a run above it prints a warning and lists it in
 * summary.json. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "method.h"

/* The strain of the test field: the figures are ratios, so its size only keeps the products
 * far from overflow and underflow. */
#define PATCH_STRAIN 1e-3

typedef struct {
  double eps, nu;
} uniaxial_field;

static void uniaxial_fn(void *ctx, const double p[3], double density, double u[3]) {
  const uniaxial_field *f = ctx;
  (void)density;
  u[0] = -f->nu * f->eps * p[0];
  u[1] = f->eps * p[1];
  u[2] = -f->nu * f->eps * p[2];
}

/* The one isotropic material of the model (the beam's and every PD region's), or NULL: the
 * uniaxial field is a solution only where E and nu are the same everywhere. */
static const cupid_material *one_isotropic_material(const cupid_model_t *m) {
  if (m->n_materials < 1) return NULL;
  const cupid_material *a = &m->materials[0];
  for (int k = 0; k < m->n_materials; k++) {
    const cupid_material *b = &m->materials[k];
    if (b->orthotropic || b->E != a->E || b->nu != a->nu) return NULL;
  }
  return a;
}

/* The reach of a PD node's force: 2 delta for LPS (its neighbours' dilatations), delta for
 * bond-based; EXACT partial volumes reach half a cell diagonal further. */
static double pd_reach(const cupid_problem_state *prob, double h) {
  const cupid_pd_operator_options *o = &prob->pd_options;
  double r = o->model == CUPID_PD_LPS ? 2.0 * o->horizon : o->horizon;
  if (o->partial_volume == CUPID_PARTIAL_EXACT) r += 0.5 * sqrt(3.0) * h;
  return r;
}

typedef struct {
  int di, dj, dk;
  double r2;
} offset;

static int farthest_first(const void *a, const void *b) {
  double ra = ((const offset *)a)->r2, rb = ((const offset *)b)->r2;
  return ra < rb ? 1 : ra > rb ? -1 : 0;
}

/* The lattice offsets within @p radius, farthest first (a node near a free surface is told
 * so by its first few). */
static cupid_status reach_offsets(int dim, double radius, double h, offset **off, int *n) {
  const double rr = radius / h * (1.0 + 1e-12);
  const int R = (int)floor(rr), Rx = dim == 3 ? R : 0;
  size_t side = 2 * (size_t)R + 1, sidex = 2 * (size_t)Rx + 1;
  CUPID_CALL(cupid_malloc(side * sidex * sidex, sizeof **off, "patch-test offsets", off));
  *n = 0;
  for (int dk = -Rx; dk <= Rx; dk++)
    for (int dj = -R; dj <= R; dj++)
      for (int di = -Rx; di <= Rx; di++) {
        double r2 = (double)(di * di + dj * dj + dk * dk);
        if (r2 <= rr * rr) (*off)[(*n)++] = (offset){di, dj, dk, r2};
      }
  qsort(*off, (size_t)*n, sizeof **off, farthest_first);
  return CUPID_SUCCESS;
}

/* flags[i] = 1 when every lattice point within the reach of PD node i is undamaged material
 * (a node of the grid with no broken bond, or a point inside an active part of the beam):
 * its force under an affine field owes nothing to a free surface or a crack. */
static cupid_status interior_nodes(const cupid_problem_state *prob, unsigned char *flags,
                                   cupid_int *count) {
  const cupid_pd_grid g = prob->grid;
  const int dim = cupid_pd_grid_dimension(g);
  const double h = cupid_pd_grid_spacing(g), *x = cupid_pd_grid_coords(g);
  double *damage = NULL;
  offset *off = NULL;
  int n_off = 0;
  cupid_status st = CUPID_SUCCESS;
  CUPID_TRY(reach_offsets(dim, pd_reach(prob, h), h, &off, &n_off));
  if (cupid_pd_operator_num_broken(prob->op) > 0) {
    CUPID_TRY(cupid_calloc((size_t)prob->n_pd, sizeof *damage, "node damage", &damage));
    CUPID_TRY(cupid_pd_operator_damage(prob->op, damage, NULL, NULL));
  }
  const double y_lo = prob->fe_info.y_min, y_hi = prob->fe_info.y_max;
  cupid_int n_in = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : n_in)
  for (cupid_int i = 0; i < prob->n_pd; i++) {
    unsigned char in = cupid_problem_pd_owned(prob, i) && !(damage && damage[i] > 0.0);
    cupid_int q[3];
    cupid_pd_grid_node_lattice(g, i, q);
    for (int s = 0; s < n_off && in; s++) {
      const offset *o = &off[s];
      cupid_int j = cupid_pd_grid_node_at(g, q[0] + o->di, q[1] + o->dj, q[2] + o->dk);
      if (j >= 0) {
        in = !(damage && damage[j] > 0.0);
        continue;
      }
      double p[3] = {x[3 * i] + o->di * h, x[3 * i + 1] + o->dj * h, x[3 * i + 2] + o->dk * h};
      /* a 1D grid is a bar along the axis: its material is the beam's length */
      in = dim == 3 ? cupid_cuf_contains(prob->beam, p[0], p[1], p[2])
                    : p[1] >= y_lo - 1e-9 * h && p[1] <= y_hi + 1e-9 * h;
    }
    flags[i] = in;
    n_in += in;
  }
  *count = n_in;
cleanup:
  cupid_free(&damage);
  cupid_free(&off);
  return st;
}

/* max |r| over the FE DOFs of used nodes of interior beam nodes (*interior) and of the end
 * sections (*ends). */
static void fe_maxima(const cupid_problem_state *prob, const double *r, double *interior,
                      double *ends, cupid_int *checked) {
  const cupid_cuf_info *fi = &prob->fe_info;
  const double tol = 1e-9 * (fi->y_max - fi->y_min);
  *interior = *ends = 0.0;
  *checked = 0;
  for (cupid_int n = 0; n < fi->n_fe_nodes; n++) {
    cupid_int bn = n / fi->M;
    if (!cupid_cuf_node_used(prob->beam, (int)(n % fi->M), bn)) continue;
    double y = cupid_cuf_beam_node_y(prob->beam, bn), m = 0.0;
    for (int c = 0; c < 3; c++) m = fmax(m, fabs(r[prob->fe_offset + 3 * n + c]));
    if (y <= fi->y_min + tol || y >= fi->y_max - tol) {
      *ends = fmax(*ends, m);
    } else {
      *interior = fmax(*interior, m);
      (*checked)++;
    }
  }
}

/* The method's tie on r. On a slab each rank ties its owned PD nodes, so the FE rows get one
 * share per rank: the shares are summed (the FE rows of r are the whole model's on every rank
 * before and after). */
static cupid_status tie(const cupid_problem_state *prob, double *r) {
  const cupid_int nfe = prob->ndof - prob->fe_offset;
  double *before = NULL;
  cupid_status st = CUPID_SUCCESS;
  if (prob->slab) {
    CUPID_TRY(cupid_malloc((size_t)nfe + 1, sizeof *before, "FE rows", &before));
    memcpy(before, r + prob->fe_offset, (size_t)nfe * sizeof *before);
  }
  CUPID_TRY(prob->method->patch_tie(prob, r));
  if (prob->slab) {
    double *fe = r + prob->fe_offset;
    for (cupid_int d = 0; d < nfe; d++) fe[d] -= before[d];
    cupid_petsc_sum_doubles(fe, (int)nfe);
    for (cupid_int d = 0; d < nfe; d++) fe[d] += before[d];
  }
cleanup:
  cupid_free(&before);
  return st;
}

int cupid_problem_is_coupled(const cupid_problem_state *prob) {
  return prob->beam && prob->grid;
}

cupid_status cupid_problem_patch_test(cupid_problem_state *prob, cupid_system_apply apply,
                                      void *ctx) {
  cupid_problem_quality *q = &prob->quality;
  if (!cupid_problem_is_coupled(prob) || q->patch_done) return CUPID_SUCCESS;
  const cupid_material *mat = one_isotropic_material(prob->model);
  if (!mat) {
    q->patch_skipped = "the beam and the PD regions need one isotropic material";
    return CUPID_SUCCESS;
  }
  double t0 = cupid_wtime();
  double *x = NULL, *r = NULL;
  unsigned char *interior = NULL;
  cupid_status st = CUPID_SUCCESS;
  uniaxial_field f = {PATCH_STRAIN, mat->nu};
  CUPID_TRY(cupid_calloc((size_t)prob->ndof, sizeof *x, "patch-test field", &x));
  CUPID_TRY(cupid_calloc((size_t)prob->ndof, sizeof *r, "patch-test forces", &r));
  CUPID_TRY(cupid_calloc((size_t)prob->n_pd + 1, 1, "interior PD nodes", &interior));
  CUPID_TRY(cupid_problem_system_field(prob, uniaxial_fn, &f, x));
  CUPID_TRY(apply(ctx, x, r));
  if (prob->method->patch_tie) CUPID_TRY(tie(prob, r));
  cupid_int pd_in = 0;
  CUPID_TRY(interior_nodes(prob, interior, &pd_in));
  double pd_max = 0.0;
  for (cupid_int i = 0; i < prob->n_pd; i++)
    if (interior[i])
      for (int c = 0; c < 3; c++) pd_max = fmax(pd_max, fabs(r[3 * i + c]));
  double fe_max, fe_ends;
  fe_maxima(prob, r, &fe_max, &fe_ends, &q->fe_checked);
  /* a slab: its owned PD rows; the FE rows are the whole model's on every rank */
  double maxima[3] = {pd_max, fe_max, fe_ends};
  if (prob->slab) cupid_petsc_max_doubles(maxima, 3);
  q->pd_checked = cupid_problem_global_count(prob, pd_in);
  /* Scales: a PD node's share of the stress, E eps times its cross-section (h^2; the bar's
   * area on a 1D grid); an FE DOF's, the largest force on an end section (the traction's
   * nodal forces), else E eps A when both ends lie in PD regions. */
  const double h = cupid_pd_grid_spacing(prob->grid);
  const double sigma = mat->E * PATCH_STRAIN;
  const double pd_scale = sigma * cupid_pd_grid_cell_volume(prob->grid) / h;
  const double fe_scale = maxima[2] > 0.0 ? maxima[2] : sigma * prob->fe_info.section_area;
  q->ghost_pd = maxima[0] / pd_scale;
  q->ghost_fe = maxima[1] / fe_scale;
  q->ghost = fmax(q->ghost_pd, q->ghost_fe);
  q->strain = PATCH_STRAIN;
  q->patch_done = 1;
  q->patch_seconds = cupid_wtime() - t0;
cleanup:
  cupid_free(&x);
  cupid_free(&r);
  cupid_free(&interior);
  return st;
}

static cupid_status csr_apply(void *ctx, const double *x, double *y) {
  cupid_csr_matvec(ctx, x, y);
  return CUPID_SUCCESS;
}

cupid_status cupid_problem_patch_test_assembled(cupid_problem_state *prob) {
  if (!prob->K) return CUPID_SUCCESS;
  return cupid_problem_patch_test(prob, csr_apply, prob->K);
}

static void warn(const cupid_problem_state *prob, const char *fmt, double value, double bound) {
  if (prob->quiet || prob->slab) return;
  fprintf(stderr, "cupid: warning: ");
  fprintf(stderr, fmt, value, bound);
  fputc('\n', stderr);
}

void cupid_problem_quality_report(cupid_problem_state *prob) {
  cupid_problem_quality *q = &prob->quality;
  if (!cupid_problem_is_coupled(prob) || prob->slab) return;
  const int stat = prob->model->analysis.type == CUPID_ANALYSIS_STATIC && prob->solved;
  if (stat) {
    double pn = 0.0, in = 0.0;
    for (int c = 0; c < 3; c++) {
      pn += prob->load_sum[c] * prob->load_sum[c];
      in += (prob->load_sum[c] + prob->reaction_sum[c]) * (prob->load_sum[c] + prob->reaction_sum[c]);
    }
    q->has_imbalance = pn > 0.0;
    q->imbalance = pn > 0.0 ? sqrt(in / pn) : 0.0;
    q->imbalance_warning = q->has_imbalance && q->imbalance > CUPID_QUALITY_IMBALANCE_BOUND;
  }
  q->ghost_warning = q->patch_done && q->ghost > CUPID_QUALITY_GHOST_BOUND;
  if (q->patch_done)
    cupid_problem_progress(prob, "coupling quality: patch test (uniaxial stress along the axis): "
                           "ghost force %.2e of the end-section force on %lld FE nodes, %.2e of E "
                           "eps h^2 on %lld interior PD nodes (bound %.0e, %.2f s)",
                           q->ghost_fe, (long long)q->fe_checked, q->ghost_pd,
                           (long long)q->pd_checked, CUPID_QUALITY_GHOST_BOUND, q->patch_seconds);
  else if (q->patch_skipped)
    cupid_problem_progress(prob, "coupling quality: patch test skipped (%s)", q->patch_skipped);
  /* the imbalance itself is on the method's equilibrium line and the run's summary line */
  if (q->ghost_warning)
    warn(prob, "the coupled operator fails the patch test: a uniform axial stress leaves "
         "ghost forces of %.2e of the nodal force scale (bound %.0e) away from the beam ends "
         "and the free surfaces (docs/coupling.md, \"The quality report of a coupled run\")",
         q->ghost, CUPID_QUALITY_GHOST_BOUND);
  if (q->imbalance_warning)
    warn(prob, "the reactions miss the load by %.2e of it (bound %.0e): the coupling is not "
         "in equilibrium (docs/coupling.md, \"The quality report of a coupled run\")",
         q->imbalance, CUPID_QUALITY_IMBALANCE_BOUND);
}

void cupid_problem_quality_json(cupid_json js, const cupid_problem_state *prob) {
  const cupid_problem_quality *q = &prob->quality;
  if (!cupid_problem_is_coupled(prob)) return;
  cupid_json_begin_object(js, "coupling_quality");
  cupid_json_begin_object(js, "patch_test");
  if (q->patch_done) {
    cupid_json_string(js, "field", "uniaxial stress along the axis");
    cupid_json_number(js, "strain", q->strain);
    cupid_json_number(js, "ghost_force", q->ghost);
    cupid_json_number(js, "ghost_force_fe", q->ghost_fe);
    cupid_json_number(js, "ghost_force_pd", q->ghost_pd);
    cupid_json_integer(js, "fe_nodes_checked", q->fe_checked);
    cupid_json_integer(js, "pd_nodes_checked", q->pd_checked);
    cupid_json_number(js, "bound", CUPID_QUALITY_GHOST_BOUND);
  } else {
    cupid_json_string(js, "skipped", q->patch_skipped ? q->patch_skipped : "not run");
  }
  cupid_json_end_object(js);
  if (q->has_imbalance) {
    cupid_json_number(js, "imbalance", q->imbalance);
    cupid_json_number(js, "imbalance_bound", CUPID_QUALITY_IMBALANCE_BOUND);
  }
  cupid_json_begin_array(js, "warnings");
  if (q->ghost_warning) cupid_json_string(js, NULL, "ghost_force");
  if (q->imbalance_warning) cupid_json_string(js, NULL, "imbalance");
  cupid_json_end_array(js);
  cupid_json_end_object(js);
}

/* The applied load and the constraints' reactions summed along x, y, z (summary.json,
 * the imbalance above). */
cupid_status cupid_problem_force_sums(cupid_problem_state *prob, double load[3],
                                      double reaction[3]) {
  double *t = NULL;
  /* The unit translation along k: 1 at every PD DOF of component k, the beam's own
   * interpolation elsewhere (cupid_problem_translations); without a beam the PD DOFs are all
   * there is, and their sums need no vector (three of the DOF count were written and read). */
  if (prob->beam)
    CUPID_CALL(cupid_calloc((size_t)(3 * prob->ndof), sizeof *t, "translation vectors", &t));
  cupid_status st = t ? cupid_problem_translations(prob, t) : CUPID_SUCCESS;
  for (int k = 0; k < 3 && st == CUPID_SUCCESS; k++) {
    const double *tk = t ? t + (size_t)k * (size_t)prob->ndof : NULL;
    const cupid_int first = tk ? 0 : k, step = tk ? 1 : 3;
    const cupid_int end = tk ? prob->ndof : 3 * prob->n_pd;
    load[k] = reaction[k] = 0.0;
    for (cupid_int d = first; d < end; d += step) {
      const double w = tk ? tk[d] : 1.0;
      load[k] += prob->f_ext[d] * w;
      /* a node that growth held is no support of the model's: its force is apart
       * (growth.held_reaction, summary.json's held_reaction_sum) */
      const int held = prob->growth.held && d < 3 * prob->n_pd && prob->growth.held[d / 3];
      if (prob->bc->fixed[d] && !held) reaction[k] += (prob->f_int[d] - prob->f_ext[d]) * w;
    }
  }
  cupid_free(&t);
  return st;
}

/* The resultant of the internal forces, sum over DOFs of f_int T_k (the unit translations), and
 * the sum of |f_int| for its scale: 0 for an operator that conserves momentum (every PD model,
 * the balanced coupling: R^T K' = 0), the coupling's imbalance otherwise (summary.json of an
 * evaluation, `internal_force_sum`). */
cupid_status cupid_problem_internal_force_sum(const cupid_problem_state *prob, double sum[3],
                                              double *scale) {
  double *t = NULL;
  CUPID_CALL(cupid_calloc((size_t)(3 * prob->ndof) + 1, sizeof *t, "translation vectors", &t));
  cupid_status st = cupid_problem_translations(prob, t);
  *scale = 0.0;
  for (int k = 0; k < 3; k++) {
    sum[k] = 0.0;
    for (cupid_int d = 0; d < prob->ndof && st == CUPID_SUCCESS; d++) {
      const double f = prob->f_int[d] * t[(size_t)k * (size_t)prob->ndof + d];
      sum[k] += f;
      *scale += fabs(f);
    }
  }
  cupid_free(&t);
  return st;
}
