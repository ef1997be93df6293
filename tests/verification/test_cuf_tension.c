/* Verification: uniform tension of a bar is reproduced to round-off by every expansion (TE0
 * with nu = 0, TE1..TE8, L4/L9/L16) and every beam element (B2..B4, full/reduced/MITC):
 * u_y = sigma y / E, u_x = -nu sigma (x - xc) / E, u_z = -nu sigma (z - zc) / E, sigma_yy = sigma.
 * The model path is used for the load (traction on the end face) and for the LE constraints
 * (fix boxes), so the lateral faces stay free and the Poisson contraction is not restrained. */
#include "unit/test_cuf_common.h"

/* Bar of examples.md section 1: x, z in [0, 10], y in [0, 100]; axis with uneven spans. */
static const double SIG = 100.0, XC = 5.0, ZC = 5.0;

typedef struct {
  tb_beam t;
  cupid_model_t model;
  cupid_load load;
  cupid_constraint cons[3];
} bar_case;

static void bar_init(bar_case *c, double nu, int p, int integration) {
  memset(c, 0, sizeof *c);
  tb_init(&c->t, 1e4, nu);
  c->t.axis_y[0] = 0, c->t.axis_y[1] = 30, c->t.axis_y[2] = 70, c->t.axis_y[3] = 100;
  c->t.axis_el[0] = 1, c->t.axis_el[1] = 2, c->t.axis_el[2] = 1;
  c->t.def.n_axis = 4;
  c->t.def.element_nodes = p;
  c->t.def.integration = integration;
  c->model.materials = c->t.mat;
  c->model.n_materials = 1;
  c->model.has_beam = 1;
  c->load.kind = CUPID_LOAD_TRACTION;
  c->load.plane_y = 100.0;
  c->load.value[1].kind = CUPID_VALUE_CONSTANT;
  c->load.value[1].constant = SIG;
  c->model.loads = &c->load;
  c->model.n_loads = 1;
}

static cupid_box box3(double x0, double x1, double y0, double y1, double z0, double z1) {
  cupid_box b = {{x0, y0, z0}, {x1, y1, z1}, {1, 1, 1}};
  return b;
}

static double solve_and_check(bar_case *c, const char *what) {
  c->model.beam = c->t.def;
  cupid_cuf_beam b = NULL;
  CUPID_ASSERT_OK(cupid_cuf_beam_create(&c->model, &b));
  cupid_int n = cupid_cuf_num_dofs(b);
  double *f = NULL;
  CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f, "f", &f));
  CUPID_ASSERT_OK(cupid_cuf_load_vector(b, &c->model, f));
  cupid_dirichlet bc = NULL;
  CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
  CUPID_ASSERT_OK(cupid_cuf_apply_constraints(b, &c->model, bc));
  cupid_cuf_info info;
  cupid_cuf_get_info(b, &info);
  if (info.expansion == CUPID_EXPANSION_TE) {
    /* centre translation in x, z and the rotation about y (u_x ~ z) at y = 0; the TE
     * monomials are centred at the centroid, so the exact solution has these terms zero */
    bc->fixed[cupid_cuf_dof(b, 0, 0, 0)] = 1;
    bc->fixed[cupid_cuf_dof(b, 0, 0, 2)] = 1;
    if (info.te_order >= 1) bc->fixed[cupid_cuf_dof(b, 2, 0, 0)] = 1;
  }
  double *u = tb_solve(b, f, bc, NULL);
  double E = 1e4, nu = c->t.mat[0].nu, eps = SIG / E, umax = eps * 100, err = 0, serr = 0;
  const double pts[][3] = {{0, 100, 0}, {10, 100, 10}, {5, 50, 5}, {2.5, 30, 7.5}, {10, 0, 0},
                           {0.3, 77.7, 9.1}, {9.99, 12.3, 0.01}};
  for (size_t k = 0; k < sizeof pts / sizeof pts[0]; k++) {
    const double *p = pts[k];
    double d[3], s[6];
    CUPID_ASSERT_OK(cupid_cuf_displacement_at(b, u, p[0], p[1], p[2], d));
    CUPID_ASSERT_OK(cupid_cuf_stress_at(b, u, p[0], p[1], p[2], s));
    double ex[3] = {-nu * eps * (p[0] - XC), eps * p[1], -nu * eps * (p[2] - ZC)};
    for (int q = 0; q < 3; q++) err = fmax(err, fabs(d[q] - ex[q]));
    for (int q = 0; q < 6; q++) serr = fmax(serr, fabs(s[q] - (q == 1 ? SIG : 0.0)));
  }
  /* round-off: 1e-9 of the largest displacement and of the stress; the solve residual is
   * checked to 1e-8 by the solver, and TE8 monomials cost a few digits of conditioning */
  if (!(err <= 1e-9 * umax && serr <= 1e-9 * SIG))
    fail_msg("%s: displacement error %.3g (of %.3g), stress error %.3g", what, err, umax, serr);
  printf("  %-22s dofs %5lld  |u - u_exact| / u_max = %.1e  |s - s_exact| / s = %.1e\n", what,
         (long long)info.n_dofs, err / umax, serr / SIG);
  cupid_free(&u);
  cupid_free(&f);
  cupid_dirichlet_destroy(&bc);
  cupid_cuf_beam_destroy(&b);
  return err / umax;
}

static void test_tension_te(void **state) {
  (void)state;
  char what[64];
  for (int integ = 0; integ < 3; integ++)
    for (int p = 2; p <= 4; p++)
      for (int N = 0; N <= 8; N += (N < 4 ? 1 : 4)) {
        bar_case c;
        bar_init(&c, N == 0 ? 0.0 : 0.2, p, integ); /* TE0 has no contraction: nu = 0 */
        tb_te(&c.t, N);
        tb_rect(&c.t, 0, 10, 1, 0, 10, 2, -1);
        /* u_y = 0 on the whole section at y = 0 (a TE "fix" must hold the whole section) */
        c.cons[0].kind = CUPID_CONSTRAINT_FIX;
        c.cons[0].box = box3(-1, 11, 0, 0, -1, 11);
        c.cons[0].components[1] = 1;
        c.model.constraints = c.cons;
        c.model.n_constraints = 1;
        snprintf(what, sizeof what, "TE%d B%d int %d", N, p, integ);
        solve_and_check(&c, what);
      }
}

/* Poisson locking of a TE0 rod (nu = 0.25, paper 004's truss material): the tip of the bar
 * under the end traction SIG moves SIG L / E with the correction (the default) and
 * SIG L (1 + nu)(1 - 2 nu) / ((1 - nu) E) without; stresses: sigma_yy = SIG in both,
 * sigma_xx = sigma_zz = 0 with the correction, nu / (1 - nu) SIG (the lateral stress of the
 * restrained contraction) without. Exact for a linear field: round-off, 1e-12. */
static void test_rod_poisson(void **state) {
  (void)state;
  const double nu = 0.25, E = 1e4, eps = SIG / E;
  for (int off = 0; off < 2; off++)
    for (int p = 2; p <= 4; p++) {
      bar_case c;
      bar_init(&c, nu, p, 0);
      c.t.def.poisson_correction = off ? CUPID_CUF_POISSON_OFF : CUPID_CUF_POISSON_AUTO;
      tb_te(&c.t, 0);
      tb_rect(&c.t, 0, 10, 1, 0, 10, 2, -1);
      c.model.beam = c.t.def;
      cupid_cuf_beam b = NULL;
      CUPID_ASSERT_OK(cupid_cuf_beam_create(&c.model, &b));
      cupid_int n = cupid_cuf_num_dofs(b);
      double *f = NULL;
      CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f, "f", &f));
      CUPID_ASSERT_OK(cupid_cuf_load_vector(b, &c.model, f));
      cupid_dirichlet bc = NULL;
      CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
      CUPID_ASSERT_OK(cupid_cuf_clamp_node(b, 0, bc));
      double *u = tb_solve(b, f, bc, NULL);
      double d[3], s[6]; /* stresses xx yy zz yz xz xy */
      CUPID_ASSERT_OK(cupid_cuf_displacement_at(b, u, 3, 100, 7, d));
      CUPID_ASSERT_OK(cupid_cuf_stress_at(b, u, 3, 55, 7, s));
      double ref = off ? eps * 100 * (1 + nu) * (1 - 2 * nu) / (1 - nu) : eps * 100;
      double lat = off ? nu / (1 - nu) * SIG : 0.0;
      printf("  TE0 B%d nu %.2f correction %-4s tip u_y %.12e (expected %.12e), sxx %.6g szz %.6g syy %.6g\n",
             p, nu, off ? "off" : "on", d[1], ref, s[0], s[2], s[1]);
      ASSERT_NEAR(d[1], ref, 1e-12 * ref);
      ASSERT_NEAR(s[1], SIG, 1e-12 * SIG);
      ASSERT_NEAR(s[0], lat, 1e-12 * SIG);
      ASSERT_NEAR(s[2], lat, 1e-12 * SIG);
      cupid_free(&u);
      cupid_free(&f);
      cupid_dirichlet_destroy(&bc);
      cupid_cuf_beam_destroy(&b);
    }
  /* orthotropic (axes x y z): the corrected rod stretches SIG L / E_y, sigma_xx = sigma_zz = 0 */
  for (int N = 0; N <= 1; N++) {
    bar_case c;
    bar_init(&c, nu, 3, 0);
    cupid_material *m = &c.t.mat[0];
    m->orthotropic = 1;
    m->Ex = 3e4, m->Ey = 1e4, m->Ez = 2e4;
    m->nu_xy = 0.35, m->nu_xz = 0.3, m->nu_yz = 0.2;
    m->Gxy = 5e3, m->Gxz = 8e3, m->Gyz = 4e3;
    tb_te(&c.t, N);
    tb_rect(&c.t, 0, 10, 1, 0, 10, 2, -1);
    c.model.beam = c.t.def;
    cupid_cuf_beam b = NULL;
    CUPID_ASSERT_OK(cupid_cuf_beam_create(&c.model, &b));
    cupid_int n = cupid_cuf_num_dofs(b);
    double *f = NULL;
    CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f, "f", &f));
    CUPID_ASSERT_OK(cupid_cuf_load_vector(b, &c.model, f));
    /* u_y = 0 over the section at y = 0 and the rigid motions, the lateral faces free (as
     * test_tension_te): the exact solution, contraction included for TE1 */
    cupid_dirichlet bc = NULL;
    CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
    c.cons[0].kind = CUPID_CONSTRAINT_FIX;
    c.cons[0].box = box3(-1, 11, 0, 0, -1, 11);
    c.cons[0].components[1] = 1;
    c.model.constraints = c.cons;
    c.model.n_constraints = 1;
    CUPID_ASSERT_OK(cupid_cuf_apply_constraints(b, &c.model, bc));
    bc->fixed[cupid_cuf_dof(b, 0, 0, 0)] = 1;
    bc->fixed[cupid_cuf_dof(b, 0, 0, 2)] = 1;
    if (N == 1) bc->fixed[cupid_cuf_dof(b, 2, 0, 0)] = 1;
    double *u = tb_solve(b, f, bc, NULL);
    double d[3], s[6];
    CUPID_ASSERT_OK(cupid_cuf_displacement_at(b, u, 5, 100, 5, d));
    CUPID_ASSERT_OK(cupid_cuf_stress_at(b, u, 3, 85, 7, s));
    double ref = SIG / 1e4 * 100;
    printf("  orthotropic TE%d: tip u_y %.12e (SIG L / E_y %.12e), sxx %.3g szz %.3g syy %.12g\n", N,
           d[1], ref, s[0], s[2], s[1]);
    ASSERT_NEAR(d[1], ref, 1e-12 * ref);
    ASSERT_NEAR(s[1], SIG, 1e-12 * SIG);
    ASSERT_NEAR(s[0], 0.0, 1e-12 * SIG);
    ASSERT_NEAR(s[2], 0.0, 1e-12 * SIG);
    cupid_free(&u);
    cupid_free(&f);
    cupid_dirichlet_destroy(&bc);
    cupid_cuf_beam_destroy(&b);
  }
}

static void test_tension_le(void **state) {
  (void)state;
  char what[64];
  for (int integ = 0; integ < 3; integ++)
    for (int p = 2; p <= 4; p++)
      for (int ln = 4; ln <= 16; ln += ln == 4 ? 5 : 7) {
        bar_case c;
        bar_init(&c, 0.2, p, integ);
        tb_le(&c.t, ln);
        /* two components sharing the edge x = 5 (component-wise section, one material) */
        tb_rect(&c.t, 0, 5, 1, 0, 10, 2, -1);
        tb_rect(&c.t, 5, 10, 2, 0, 10, 2, -1);
        /* u_y = 0 at y = 0; u_x = u_z = 0 at the node (5, 0, 5); u_x = 0 at (5, 0, 10) */
        c.cons[0].kind = CUPID_CONSTRAINT_FIX;
        c.cons[0].box = box3(-1, 11, 0, 0, -1, 11);
        c.cons[0].components[1] = 1;
        c.cons[1].kind = CUPID_CONSTRAINT_FIX;
        c.cons[1].box = box3(4.9, 5.1, 0, 0, 4.9, 5.1);
        c.cons[1].components[0] = c.cons[1].components[2] = 1;
        c.cons[2].kind = CUPID_CONSTRAINT_FIX;
        c.cons[2].box = box3(4.9, 5.1, 0, 0, 9.9, 10.1);
        c.cons[2].components[0] = 1;
        c.model.constraints = c.cons;
        c.model.n_constraints = 3;
        snprintf(what, sizeof what, "L%d B%d int %d", ln, p, integ);
        solve_and_check(&c, what);
      }
}

/* A body force rho g along y: the consistent load sums to the weight, and the TE/LE solutions
 * agree with each other at the tip (u_y(L) = rho g L^2 / (2 E) for nu = 0). */
static void field_g(void *ctx, const double p[3], double density, double out[3]) {
  (void)ctx;
  (void)p;
  out[0] = out[2] = 0;
  out[1] = density * 9.81;
}

static void test_body_force(void **state) {
  (void)state;
  for (int le = 0; le < 2; le++) {
    tb_beam t;
    tb_init(&t, 1e4, 0.0);
    t.mat[0].density = 2.0;
    t.mat[0].has_density = 1;
    tb_axis(&t, 0, 100, 4, 3);
    if (le) tb_le(&t, 9);
    else tb_te(&t, 1);
    tb_rect(&t, 0, 10, 1, 0, 10, 1, -1);
    cupid_cuf_beam b = tb_create(&t);
    cupid_int n = cupid_cuf_num_dofs(b);
    double *f = NULL, vol = 0;
    CUPID_ASSERT_OK(cupid_calloc((size_t)n, sizeof *f, "f", &f));
    CUPID_ASSERT_OK(cupid_cuf_body_force_add(b, NULL, field_g, NULL, f, &vol));
    ASSERT_NEAR(vol, 1e4, 1e-9);
    /* the y forces sum to the weight: with a partition of unity (LE) exactly; for TE the
     * constant term alone carries the resultant */
    cupid_cuf_info info;
    cupid_cuf_get_info(b, &info);
    double sum = 0;
    for (cupid_int i = 0; i < n / 3; i++)
      if (le || i % info.M == 0) sum += f[3 * i + 1];
    ASSERT_NEAR(sum, 2.0 * 9.81 * 1e4, 1e-9 * 2e5);
    /* clamp y = 0 (fixes all DOFs there; nu = 0 so no lateral restraint) */
    cupid_dirichlet bc = NULL;
    CUPID_ASSERT_OK(cupid_dirichlet_create(n, &bc));
    CUPID_ASSERT_OK(cupid_cuf_clamp_node(b, 0, bc));
    double *u = tb_solve(b, f, bc, NULL);
    double d[3];
    CUPID_ASSERT_OK(cupid_cuf_displacement_at(b, u, 5, 100, 5, d));
    /* quadratic u_y is exact for B3 elements: 1e-9 relative (round-off) */
    ASSERT_NEAR(d[1], 2.0 * 9.81 * 100 * 100 / (2 * 1e4), 1e-9 * 1.0);
    cupid_free(&u);
    cupid_free(&f);
    cupid_dirichlet_destroy(&bc);
    cupid_cuf_beam_destroy(&b);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_tension_te),
                                     cmocka_unit_test(test_rod_poisson),
                                     cmocka_unit_test(test_tension_le),
                                     cmocka_unit_test(test_body_force)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
