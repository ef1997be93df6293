/* Life cycle, counts, DOF map and the (beam element, section element) activity mask of a CUF
 * beam; small shared helpers (model errors, model values). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "cuf/cuf_internal.h"

typedef struct cupid_cuf_beam_private beam_t;

double cuf_value(const cupid_value *v, const double p[3], double density, double t) {
  switch (v->kind) {
    case CUPID_VALUE_NONE: return 0.0;
    case CUPID_VALUE_CONSTANT: return v->constant;
    default: return cupid_value_eval(v, p[0], p[1], p[2], t, density);
  }
}

void cupid_cuf_set_time(cupid_cuf_beam beam, double t) {
  if (beam) beam->time = t;
}

/* ---------------------------------------------------------------- create / destroy */

static cupid_status te_setup(beam_t *b) {
  int N = b->te_order;
  b->M = (N + 1) * (N + 2) / 2;
  CUPID_CALL(cupid_malloc((size_t)b->M, sizeof *b->te_a, "TE exponents", &b->te_a));
  CUPID_CALL(cupid_malloc((size_t)b->M, sizeof *b->te_b, "TE exponents", &b->te_b));
  /* increasing total degree, inside a degree increasing power of z (cuf.md section 2) */
  int t = 0;
  for (int deg = 0; deg <= N; deg++)
    for (int c = 0; c <= deg; c++) b->te_a[t] = deg - c, b->te_b[t++] = c;
  int any_curved = 0;
  for (cupid_int e = 0; e < b->n_selem; e++) any_curved |= !b->srect[e];
  /* N + 1 points integrate products of degree 2N exactly on affine cells (cuf.md 2) */
  b->sec_ng = (N + 1 > b->quad.n ? N + 1 : b->quad.n) + (any_curved ? 2 : 0);
  size_t per = 9 * (size_t)b->M * b->M;
  CUPID_CALL(cupid_malloc(per * (size_t)b->n_selem, sizeof *b->te_E, "TE section integrals", &b->te_E));
#pragma omp parallel for schedule(dynamic) if (b->n_selem * per > 1000000)
  for (cupid_int e = 0; e < b->n_selem; e++) cuf_section_integrals(b, e, b->sec_ng, b->te_E + per * e);
  return CUPID_SUCCESS;
}

static cupid_status beam_create(const cupid_beam *def, const cupid_material *materials,
                                int n_materials, const cupid_model_t *model, cupid_cuf_beam *out) {
  cupid_status st = CUPID_SUCCESS;
  beam_t *b = NULL;
  CUPID_CHECK(def && out && (materials || n_materials == 0), CUPID_ERR_ARGUMENT,
              "cupid_cuf_beam_create: NULL argument");
  *out = NULL;
  CUPID_TRY(cupid_calloc(1, sizeof *b, "CUF beam", &b));
  if (def->material < 0 || def->material >= n_materials) {
    st = cupid_model_error(model, &def->mark, "beam material index %d out of range (%d materials)",
                         def->material, n_materials);
    goto cleanup;
  }
  b->n_mat = n_materials;
  CUPID_TRY(cupid_calloc((size_t)n_materials, sizeof *b->mat, "CUF materials", &b->mat));
  for (int k = 0; k < n_materials; k++) {
    st = cuf_material_stiffness(&materials[k], b->mat[k].C);
    if (st != CUPID_SUCCESS) {
      st = cupid_model_error(model, &materials[k].mark, "%s", cupid_error_message());
      goto cleanup;
    }
    b->mat[k].density = materials[k].has_density ? materials[k].density : 0.0;
  }
  b->expansion = def->expansion;
  if (b->expansion == CUPID_EXPANSION_TE && (def->te_order < 0 || def->te_order > 20)) {
    st = cupid_model_error(model, &def->mark, "TE order must be in 0..20, got %d", def->te_order);
    goto cleanup;
  }
  b->te_order = b->expansion == CUPID_EXPANSION_TE ? def->te_order : 0;
  if (def->integration < 0 || def->integration > 2) {
    st = cupid_model_error(model, &def->mark, "integration must be 0 (full), 1 (reduced) or 2 (mitc)");
    goto cleanup;
  }
  b->integration = def->integration;
  /* Poisson locking: TE0/TE1 sections cannot follow the lateral contraction (cuf.h) */
  int low_order = b->expansion == CUPID_EXPANSION_TE && b->te_order <= 1;
  if (def->poisson_correction < CUPID_CUF_POISSON_AUTO ||
      def->poisson_correction > CUPID_CUF_POISSON_OFF) {
    st = cupid_model_error(model, &def->mark, "poisson_correction must be 0 (auto), 1 (on) or 2 (off)");
    goto cleanup;
  }
  if (def->poisson_correction == CUPID_CUF_POISSON_ON && !low_order) {
    st = cupid_model_error(model, &def->mark,
                           "poisson_correction: on applies to TE0 and TE1 only (TE2 and up and LE "
                           "sections contract freely and need no correction)");
    goto cleanup;
  }
  b->poisson_corrected = def->poisson_correction == CUPID_CUF_POISSON_ON ||
                         (def->poisson_correction == CUPID_CUF_POISSON_AUTO && low_order);
  /* TE0 drops the contraction part R of the law; TE1 keeps it on the section-constant
   * strains, which it can contract with (docs/theory.md, "Poisson locking") */
  b->poisson_split = b->poisson_corrected && b->te_order == 1;
  for (int k = 0; k < n_materials && b->poisson_corrected; k++) {
    st = cuf_poisson_correct(b->mat[k].C, b->mat[k].R);
    if (st != CUPID_SUCCESS) {
      st = cupid_model_error(model, &materials[k].mark, "%s", cupid_error_message());
      goto cleanup;
    }
  }
  CUPID_TRY(cuf_axis_build(b, def, model));
  CUPID_TRY(cuf_section_build(b, def, model));
  if (b->expansion == CUPID_EXPANSION_TE) {
    CUPID_TRY(te_setup(b));
  } else {
    b->M = (int)b->n_snodes;
    CUPID_TRY_CHECK(b->n_snodes < (cupid_int)1 << 30, CUPID_ERR_MODEL, "section too large");
    b->sec_ng = b->quad.n;
  }
  cuf_parts_init(b);
  CUPID_TRY(cupid_malloc((size_t)(b->n_belem * b->n_selem), 1, "CUF activity mask", &b->active));
  memset(b->active, 1, (size_t)(b->n_belem * b->n_selem));
  *out = b;
  b = NULL;
cleanup:
  cupid_cuf_beam_destroy(&b);
  return st;
}

cupid_status cupid_cuf_beam_create(const cupid_model_t *model, cupid_cuf_beam *beam) {
  CUPID_CHECK(model && beam, CUPID_ERR_ARGUMENT, "cupid_cuf_beam_create: NULL argument");
  CUPID_CHECK(model->has_beam, CUPID_ERR_MODEL, "the model has no beam");
  return beam_create(&model->beam, model->materials, model->n_materials, model, beam);
}

cupid_status cupid_cuf_beam_create_from(const cupid_beam *def, const cupid_material *materials,
                                        int n_materials, cupid_cuf_beam *beam) {
  return beam_create(def, materials, n_materials, NULL, beam);
}

void cupid_cuf_beam_destroy(cupid_cuf_beam *beam) {
  if (!beam || !*beam) return;
  beam_t *b = *beam;
  cupid_free(&b->mat);
  cupid_free(&b->te_a);
  cupid_free(&b->te_b);
  cupid_free(&b->sxz);
  cupid_free(&b->sconn);
  cupid_free(&b->smat);
  cupid_free(&b->sbox);
  cupid_free(&b->srect);
  cupid_free(&b->n2e_ptr);
  cupid_free(&b->n2e);
  cupid_free(&b->te_E);
  cupid_free(&b->by);
  cupid_free(&b->active);
  cupid_free(beam);
}

/* ---------------------------------------------------------------- queries */

void cupid_cuf_get_info(const cupid_cuf_beam b, cupid_cuf_info *info) {
  memset(info, 0, sizeof *info);
  info->expansion = b->expansion;
  info->te_order = b->te_order;
  info->le_nodes = b->expansion == CUPID_EXPANSION_LE ? b->quad.npe : 0;
  info->integration = b->integration;
  info->poisson_corrected = b->poisson_corrected;
  info->M = b->M;
  info->element_nodes = b->p;
  info->n_beam_nodes = b->n_bnodes;
  info->n_beam_elements = b->n_belem;
  info->n_section_nodes = b->n_snodes;
  info->n_section_elements = b->n_selem;
  info->n_fe_nodes = b->n_bnodes * b->M;
  info->n_dofs = 3 * info->n_fe_nodes;
  info->dof_offset = b->dof_offset;
  info->section_area = b->area;
  info->y_min = b->ymin;
  info->y_max = b->ymax;
}

cupid_int cupid_cuf_num_dofs(const cupid_cuf_beam b) { return 3 * b->n_bnodes * b->M; }

cupid_status cupid_cuf_set_dof_offset(cupid_cuf_beam b, cupid_int offset) {
  CUPID_CHECK(offset >= 0 && offset % 3 == 0, CUPID_ERR_ARGUMENT,
              "DOF offset must be a non-negative multiple of 3, got %lld", (long long)offset);
  b->dof_offset = offset;
  return CUPID_SUCCESS;
}

cupid_int cupid_cuf_dof(const cupid_cuf_beam b, int tau, cupid_int node, int k) {
  return b->dof_offset + 3 * (node * b->M + tau) + k;
}

double cupid_cuf_beam_node_y(const cupid_cuf_beam b, cupid_int node) { return b->by[node]; }

cupid_int cupid_cuf_beam_node_at(const cupid_cuf_beam b, double y) {
  double xi;
  cupid_int e = cuf_axis_locate(b, y, &xi);
  if (e < 0) return -1;
  for (int a = 0; a < b->p; a++) {
    cupid_int n = e * (b->p - 1) + a;
    if (fabs(b->by[n] - y) <= b->tol_y) return n;
  }
  if (e + 1 < b->n_belem && fabs(b->by[(e + 1) * (b->p - 1)] - y) <= b->tol_y)
    return (e + 1) * (b->p - 1);
  return -1;
}

void cupid_cuf_beam_element(const cupid_cuf_beam b, cupid_int e, cupid_int *first_node, double *y0,
                            double *y1) {
  if (first_node) *first_node = e * (b->p - 1);
  if (y0) *y0 = b->by[e * (b->p - 1)];
  if (y1) *y1 = b->by[(e + 1) * (b->p - 1)];
}

void cupid_cuf_section_node(const cupid_cuf_beam b, int tau, double xz[2], double *h) {
  if (b->expansion == CUPID_EXPANSION_LE) {
    xz[0] = b->sxz[2 * tau];
    xz[1] = b->sxz[2 * tau + 1];
    if (h) *h = 0.0;
  } else {
    xz[0] = b->xc;
    xz[1] = b->zc;
    if (h) *h = b->h;
  }
}

void cupid_cuf_section_element(const cupid_cuf_beam b, cupid_int e, int *npe, cupid_int *conn,
                               int *material, double box[4]) {
  if (npe) *npe = b->quad.npe;
  if (conn) memcpy(conn, b->sconn + e * b->quad.npe, sizeof *conn * (size_t)b->quad.npe);
  if (material) *material = b->smat[e];
  if (box) memcpy(box, b->sbox + 4 * e, 4 * sizeof *box);
}

cupid_status cupid_cuf_set_active(cupid_cuf_beam b, cupid_int be, cupid_int se, int active) {
  CUPID_CHECK(be >= 0 && be < b->n_belem && se >= 0 && se < b->n_selem, CUPID_ERR_ARGUMENT,
              "pair (%lld, %lld) out of range", (long long)be, (long long)se);
  b->active[be * b->n_selem + se] = (unsigned char)(active != 0);
  return CUPID_SUCCESS;
}

int cupid_cuf_is_active(const cupid_cuf_beam b, cupid_int be, cupid_int se) {
  return b->active[be * b->n_selem + se];
}

int cupid_cuf_node_used(const cupid_cuf_beam b, int tau, cupid_int node) {
  /* beam elements holding the node: one, or two at a shared end */
  cupid_int e_hi = node / (b->p - 1), e_lo = node % (b->p - 1) == 0 ? e_hi - 1 : e_hi;
  if (e_hi >= b->n_belem) e_hi = b->n_belem - 1;
  for (cupid_int e = e_lo < 0 ? 0 : e_lo; e <= e_hi; e++) {
    if (b->expansion == CUPID_EXPANSION_TE) {
      for (cupid_int s = 0; s < b->n_selem; s++)
        if (b->active[e * b->n_selem + s]) return 1;
    } else {
      for (cupid_int k = b->n2e_ptr[tau]; k < b->n2e_ptr[tau + 1]; k++)
        if (b->active[e * b->n_selem + b->n2e[k]]) return 1;
    }
  }
  return 0;
}
