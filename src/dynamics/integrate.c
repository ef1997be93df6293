/* Time integration of M a + C v + K u = f (include/cupid/dynamics.h): Newmark with one
 * factorisation of the effective matrix, and explicit central differences (velocity-Verlet
 * form) with a lumped mass, on an assembled K or a matrix-free one (a callback: every K
 * product goes through dyn_stiffness). Energies by the midpoint rule, for which the Newmark
 * average-acceleration balance is exact (it is the trapezoidal rule). */
#include <math.h>
#include <string.h>

#include "dynamics/dynamics_internal.h"

cupid_dynamics_options cupid_dynamics_defaults(void) {
  return (cupid_dynamics_options){.integrator = CUPID_INTEGRATOR_NEWMARK, .every = 1,
                                  .beta = 0.25, .gamma = 0.5};
}

double cupid_dynamics_rayleigh_zeta(double a, double b, double omega) {
  return a / (2.0 * omega) + 0.5 * b * omega;
}

void dyn_mass_apply(const cupid_dynamics_system *sys, cupid_int n, const double *x, double *y) {
  if (sys->M) {
    cupid_csr_matvec(sys->M, x, y);
    return;
  }
#pragma omp parallel for schedule(static) if (n > 100000)
  for (cupid_int d = 0; d < n; d++) y[d] = sys->m_lumped[d] * x[d];
}

double dyn_dot(cupid_int n, const double *x, const double *y) {
  double s = 0.0;
#pragma omp parallel for reduction(+ : s) schedule(static) if (n > 100000)
  for (cupid_int d = 0; d < n; d++) s += x[d] * y[d];
  return s;
}

/* Work vectors of a run. */
typedef struct {
  cupid_int n;
  const cupid_dynamics_system *sys;
  cupid_dynamics_stiffness_fn kfn; /* matrix-free K (sys->K is NULL), else NULL */
  void *kctx;
  cupid_status kst;                /* first failure of kfn (checked after each step) */
  const cupid_dynamics_options *opt;
  const cupid_dynamics_hooks *hooks; /* opt->hooks, or NULL */
  double *a, *un, *vn, *an, *w1, *w2, *t1, *t2, *g;
  /* Time-dependent conditions (hooks->conditions): the load now (f points here, else at
   * sys->f), the prescribed values, the support reactions of the last step, the fixed DOFs'
   * increment. */
  const double *f;
  double *fcur, *fprev, *ufix, *react, *du;
  cupid_dynamics_energy e;
  double e0, scale, max_balance;
} dyn_state;

static void state_free(dyn_state *s) {
  double **arrays[] = {&s->a,  &s->un, &s->vn, &s->an,   &s->w1,   &s->w2,    &s->t1,
                       &s->t2, &s->g,  &s->fcur, &s->fprev, &s->ufix, &s->react, &s->du};
  for (size_t k = 0; k < sizeof arrays / sizeof *arrays; k++) cupid_free(arrays[k]);
}

static cupid_status state_alloc(dyn_state *s) {
  double **arrays[] = {&s->a, &s->un, &s->vn, &s->an, &s->w1, &s->w2, &s->t1, &s->t2, &s->g};
  for (size_t k = 0; k < sizeof arrays / sizeof *arrays; k++)
    CUPID_CALL(cupid_calloc((size_t)s->n, sizeof(double), "dynamics work vector", arrays[k]));
  s->f = s->sys->f;
  if (!(s->hooks && s->hooks->conditions)) return CUPID_SUCCESS;
  double **more[] = {&s->fcur, &s->fprev, &s->ufix, &s->react, &s->du};
  for (size_t k = 0; k < sizeof more / sizeof *more; k++)
    CUPID_CALL(cupid_calloc((size_t)s->n, sizeof(double), "dynamics work vector", more[k]));
  s->f = s->fcur;
  return CUPID_SUCCESS;
}

/* The conditions at time t: the load into fcur (the previous one kept in fprev) and the
 * prescribed values into ufix. */
static cupid_status conditions_at(dyn_state *s, double t) {
  memcpy(s->fprev, s->fcur, sizeof *s->fcur * (size_t)s->n);
  CUPID_CALL(s->hooks->conditions(s->hooks->ctx, t, s->ufix, s->fcur));
  for (cupid_int d = 0; d < s->n; d++)
    CUPID_CHECK(isfinite(s->fcur[d]) && (!dyn_fixed(s->sys->bc, d) || isfinite(s->ufix[d])),
                CUPID_ERR_NUMERIC, "the %s of DOF %lld is not finite at t = %g",
                isfinite(s->fcur[d]) ? "prescribed displacement" : "load", (long long)d, t);
  return CUPID_SUCCESS;
}

/* Work of the moving supports over a step: the trapezoidal rule on R = K u + C v + M a - f
 * at the fixed DOFs (r_new holds it at the step's end; react the start's). */
static void support_work(dyn_state *s, const double *r_new) {
  const cupid_dirichlet_t *bc = s->sys->bc;
  double w = 0.0;
  for (cupid_int d = 0; d < s->n; d++)
    if (dyn_fixed(bc, d)) {
      w += 0.5 * (s->react[d] + r_new[d]) * s->du[d];
      s->react[d] = r_new[d];
    }
  s->e.external += w;
}

/* *changed = 1 when the hook removed energy (K changed: the caller recomputes the forces,
 * so that what broke exerts none after the step it broke in). */
static cupid_status after_forces(dyn_state *s, cupid_int step, const double *u, int *changed) {
  *changed = 0;
  if (!s->hooks || !s->hooks->after_forces) return CUPID_SUCCESS;
  double diss = 0.0;
  CUPID_CALL(s->hooks->after_forces(s->hooks->ctx, step, (double)step * s->opt->dt, u, &diss));
  s->e.fracture += diss;
  *changed = diss != 0.0;
  return CUPID_SUCCESS;
}

/* y = K x, assembled or matrix-free. */
static void dyn_stiffness(dyn_state *s, const double *x, double *y) {
  if (!s->kfn) {
    cupid_csr_matvec(s->sys->K, x, y);
    return;
  }
  cupid_status st = s->kfn(s->kctx, x, y);
  if (st != CUPID_SUCCESS && s->kst == CUPID_SUCCESS) s->kst = st;
}

/* y = C x = a M x + b K x (t is scratch). */
static void damping_apply(dyn_state *s, const double *x, double *y, double *t) {
  double a = s->opt->rayleigh_mass, b = s->opt->rayleigh_stiffness;
  memset(y, 0, sizeof *y * (size_t)s->n);
  if (a != 0.0) {
    dyn_mass_apply(s->sys, s->n, x, t);
    for (cupid_int d = 0; d < s->n; d++) y[d] += a * t[d];
  }
  if (b != 0.0) {
    dyn_stiffness(s, x, t);
    for (cupid_int d = 0; d < s->n; d++) y[d] += b * t[d];
  }
}

/* Kinetic and strain energy of (u, v); damping and external are accumulated by the steppers. */
static void energies(dyn_state *s, const double *u, const double *v) {
  dyn_mass_apply(s->sys, s->n, v, s->t1);
  s->e.kinetic = 0.5 * dyn_dot(s->n, v, s->t1);
  dyn_stiffness(s, u, s->t1);
  s->e.strain = 0.5 * dyn_dot(s->n, u, s->t1);
  s->e.balance = s->e.kinetic + s->e.strain + s->e.damping + s->e.fracture - s->e.external - s->e0;
  double level = fmax(s->e.kinetic + s->e.strain,
                      fmax(fmax(s->e.damping, s->e.fracture), fabs(s->e.external)));
  if (level > s->scale) s->scale = level;
  if (fabs(s->e.balance) > s->max_balance) s->max_balance = fabs(s->e.balance);
}

/* Midpoint-rule increments of the dissipated energy and of the external work (a load that
 * changes over the step: its mean; the supports' share: support_work). */
static void accumulate(dyn_state *s, const double *u0, const double *u1, const double *vm) {
  const double *f = s->f;
  if (f && s->fprev)
    for (cupid_int d = 0; d < s->n; d++) {
      s->e.external += 0.5 * (f[d] + s->fprev[d]) * (u1[d] - u0[d]);
      s->du[d] = u1[d] - u0[d];
    }
  else if (f)
    for (cupid_int d = 0; d < s->n; d++) s->e.external += f[d] * (u1[d] - u0[d]);
  if (s->opt->rayleigh_mass != 0.0 || s->opt->rayleigh_stiffness != 0.0) {
    damping_apply(s, vm, s->t1, s->t2);
    s->e.damping += s->opt->dt * dyn_dot(s->n, vm, s->t1);
  }
}

/* r = f - K u - C v on free DOFs, 0 on fixed ones; with moving supports their reactions
 * K u + C v - f go to w2 (a lumped mass has no M a term on a fixed DOF). */
static void residual_force(dyn_state *s, const double *u, const double *v, double *r) {
  const cupid_dirichlet_t *bc = s->sys->bc;
  dyn_stiffness(s, u, r);
  damping_apply(s, v, s->w1, s->t2);
  const double *f = s->f;
  for (cupid_int d = 0; d < s->n; d++) {
    const double rd = (f ? f[d] : 0.0) - r[d] - s->w1[d];
    if (s->react && dyn_fixed(bc, d)) s->w2[d] = -rd;
    r[d] = dyn_fixed(bc, d) ? 0.0 : rd;
  }
}

/* The supports' reactions at t = 0 (after initial_acceleration: w2 holds K u + C v - f on
 * the fixed DOFs), with M a. */
static void initial_reactions(dyn_state *s) {
  dyn_mass_apply(s->sys, s->n, s->a, s->t1);
  for (cupid_int d = 0; d < s->n; d++)
    s->react[d] = dyn_fixed(s->sys->bc, d) ? s->w2[d] + s->t1[d] : 0.0;
}

/* Initial acceleration M a = f - K u - C v on the free DOFs. */
static cupid_status initial_acceleration(dyn_state *s, const double *u, const double *v) {
  residual_force(s, u, v, s->t1);
  const cupid_dirichlet_t *bc = s->sys->bc;
  if (!s->sys->M) {
    for (cupid_int d = 0; d < s->n; d++)
      s->a[d] = dyn_fixed(bc, d) ? 0.0 : s->t1[d] / s->sys->m_lumped[d];
    return CUPID_SUCCESS;
  }
  cupid_direct_factor F = NULL;
  CUPID_CALL(cupid_direct_factor_create(s->sys->M, bc, &F, NULL));
  cupid_status st = cupid_direct_factor_solve(F, s->t1, s->a);
  cupid_direct_factor_destroy(&F);
  for (cupid_int d = 0; d < s->n; d++)
    if (dyn_fixed(bc, d)) s->a[d] = 0.0;
  return st;
}

/* Kinetic and strain energy cost two products per call, so they are evaluated at output
 * steps only (the balance check samples those); the monitor sees them there. */
static cupid_status notify(dyn_state *s, cupid_dynamics_monitor fn, void *ctx, cupid_int step,
                           const double *u, const double *v) {
  int out = step % s->opt->every == 0 || step == s->opt->steps;
  if (out) energies(s, u, v);
  if (!fn) return CUPID_SUCCESS;
  return fn(ctx, step, (double)step * s->opt->dt, out, u, v, s->a, &s->e);
}

/* K_eff = (1 + a1 b) K + (a0 + a1 a) M. */
static cupid_status effective_matrix(const dyn_state *s, double cm, double ck, cupid_csr *Keff) {
  const cupid_dynamics_system *sys = s->sys;
  CUPID_CALL(cupid_csr_duplicate(sys->K, Keff));
  cupid_csr_scale(*Keff, ck);
  if (sys->M) return cupid_csr_axpy(cm, sys->M, *Keff);
  int bs = sys->K->bs;
  for (cupid_int row = 0; row < sys->K->nrows; row++) {
    double *blk = cupid_csr_find(*Keff, row, row);
    CUPID_CHECK(blk, CUPID_ERR_ARGUMENT, "the stiffness lacks the diagonal block of row %lld",
                (long long)row);
    for (int k = 0; k < bs; k++) blk[k * bs + k] += cm * sys->m_lumped[row * bs + k];
  }
  return CUPID_SUCCESS;
}

static cupid_status run_newmark(dyn_state *s, double *u, double *v, cupid_dynamics_monitor fn,
                                void *ctx, cupid_dynamics_info *info) {
  cupid_status st = CUPID_SUCCESS;
  const cupid_dynamics_options *o = s->opt;
  const cupid_dirichlet_t *bc = s->sys->bc;
  double dt = o->dt, beta = o->beta, gamma = o->gamma;
  double a0 = 1.0 / (beta * dt * dt), a1 = gamma / (beta * dt), a2 = 1.0 / (beta * dt);
  double a3 = 1.0 / (2.0 * beta) - 1.0, a4 = gamma / beta - 1.0, a5 = 0.5 * dt * (gamma / beta - 2.0);
  double ra = o->rayleigh_mass, rb = o->rayleigh_stiffness;
  cupid_csr Keff = NULL;
  cupid_direct_factor F = NULL;
  CUPID_TRY(initial_acceleration(s, u, v));
  if (s->react) initial_reactions(s);
  CUPID_TRY(effective_matrix(s, a0 + a1 * ra, 1.0 + a1 * rb, &Keff));
  CUPID_TRY(cupid_direct_factor_create(Keff, bc, &F, &info->factor));
  /* g = K_eff u_c: the prescribed values moved to the right-hand side (constant). */
  for (cupid_int d = 0; d < s->n; d++) s->t1[d] = dyn_fixed(bc, d) ? u[d] : 0.0;
  cupid_csr_matvec(Keff, s->t1, s->g);
  CUPID_TRY(notify(s, fn, ctx, 0, u, v));
  double t0 = cupid_wtime();
  for (cupid_int step = 1; step <= o->steps; step++) {
    if (s->react) { /* moving supports: g = K_eff u_c at the step's end */
      CUPID_TRY(conditions_at(s, (double)step * dt));
      for (cupid_int d = 0; d < s->n; d++) s->t1[d] = dyn_fixed(bc, d) ? s->ufix[d] : 0.0;
      cupid_csr_matvec(Keff, s->t1, s->g);
    }
    /* rhs = f + M (w1 + a w2) + b K w2, w1 = a0 u + a2 v + a3 a, w2 = a1 u + a4 v + a5 a */
    for (cupid_int d = 0; d < s->n; d++) {
      s->w2[d] = a1 * u[d] + a4 * v[d] + a5 * s->a[d];
      s->w1[d] = a0 * u[d] + a2 * v[d] + a3 * s->a[d] + ra * s->w2[d];
    }
    dyn_mass_apply(s->sys, s->n, s->w1, s->t1);
    if (rb != 0.0) {
      cupid_csr_matvec(s->sys->K, s->w2, s->t2);
      for (cupid_int d = 0; d < s->n; d++) s->t1[d] += rb * s->t2[d];
    }
    for (cupid_int d = 0; d < s->n; d++) s->t1[d] += (s->f ? s->f[d] : 0.0) - s->g[d];
    memcpy(s->un, u, sizeof *u * (size_t)s->n);
    if (s->react)
      for (cupid_int d = 0; d < s->n; d++)
        if (dyn_fixed(bc, d)) s->un[d] = s->ufix[d];
    CUPID_TRY(cupid_direct_factor_solve(F, s->t1, s->un));
    for (cupid_int d = 0; d < s->n; d++) {
      if (dyn_fixed(bc, d)) {
        s->an[d] = s->vn[d] = 0.0;
        continue;
      }
      s->an[d] = a0 * (s->un[d] - u[d]) - a2 * v[d] - a3 * s->a[d];
      s->vn[d] = v[d] + dt * ((1.0 - gamma) * s->a[d] + gamma * s->an[d]);
    }
    for (cupid_int d = 0; d < s->n; d++) s->w1[d] = 0.5 * (v[d] + s->vn[d]);
    accumulate(s, u, s->un, s->w1);
    memcpy(u, s->un, sizeof *u * (size_t)s->n);
    memcpy(v, s->vn, sizeof *v * (size_t)s->n);
    memcpy(s->a, s->an, sizeof *v * (size_t)s->n);
    if (s->react) { /* R = K u + C v + M a - f at the step's end */
      cupid_csr_matvec(s->sys->K, u, s->t1);
      damping_apply(s, v, s->t2, s->w1);
      dyn_mass_apply(s->sys, s->n, s->a, s->w1);
      for (cupid_int d = 0; d < s->n; d++)
        s->w2[d] = s->t1[d] + s->t2[d] + s->w1[d] - (s->f ? s->f[d] : 0.0);
      support_work(s, s->w2);
    }
    CUPID_TRY(notify(s, fn, ctx, step, u, v));
  }
  info->time_step_s = cupid_wtime() - t0;
cleanup:
  cupid_direct_factor_destroy(&F);
  cupid_csr_destroy(&Keff);
  return st;
}

/* The critical step of central differences for the highest mode, with its damping ratio. */
static double critical_step(double lambda, double a, double b) {
  if (!(lambda > 0.0)) return INFINITY;
  double w = sqrt(lambda), xi = cupid_dynamics_rayleigh_zeta(a, b, w);
  return 2.0 / w * (sqrt(1.0 + xi * xi) - xi);
}

static cupid_status check_stable(dyn_state *s, cupid_dynamics_info *info) {
  const cupid_dynamics_options *o = s->opt;
  double est = 0.0, bound = 0.0;
  if (s->kfn) /* matrix-free: power iteration only, no Gershgorin bound (dt_bound = 0) */
    CUPID_CALL(dyn_lambda_max_fn(s->kfn, s->kctx, s->n, s->sys->m_lumped, s->sys->bc, 200, &est));
  else
    CUPID_CALL(cupid_dynamics_lambda_max(s->sys->K, s->sys->m_lumped, s->sys->bc, 200, &est, &bound));
  info->omega_max = sqrt(est);
  info->dt_critical = critical_step(est, o->rayleigh_mass, o->rayleigh_stiffness);
  info->dt_bound = s->kfn ? 0.0 : critical_step(bound, o->rayleigh_mass, o->rayleigh_stiffness);
  CUPID_CHECK(o->dt <= info->dt_critical, CUPID_ERR_ARGUMENT,
              "central differences are unstable with dt = %g: the critical step is about %g "
              "(omega_max = %g by power iteration; guaranteed stable below %g); use a smaller "
              "dt or the newmark integrator",
              o->dt, info->dt_critical, info->omega_max, info->dt_bound);
  return CUPID_SUCCESS;
}

static cupid_status run_central(dyn_state *s, double *u, double *v, cupid_dynamics_monitor fn,
                                void *ctx, cupid_dynamics_info *info) {
  const cupid_dynamics_options *o = s->opt;
  const cupid_dirichlet_t *bc = s->sys->bc;
  double dt = o->dt;
  CUPID_CHECK(s->sys->m_lumped && !s->sys->M, CUPID_ERR_ARGUMENT,
              "central differences need a lumped (diagonal) mass");
  for (cupid_int d = 0; d < s->n; d++)
    CUPID_CHECK(dyn_fixed(bc, d) || s->sys->m_lumped[d] > 0.0, CUPID_ERR_ARGUMENT,
                "free DOF %lld has no mass (central differences need a positive lumped mass)",
                (long long)d);
  CUPID_CALL(check_stable(s, info));
  CUPID_CALL(initial_acceleration(s, u, v));
  if (s->react) initial_reactions(s);
  CUPID_CALL(s->kst);
  int changed = 0;
  CUPID_CALL(after_forces(s, 0, u, &changed));
  if (changed) CUPID_CALL(initial_acceleration(s, u, v));
  CUPID_CALL(notify(s, fn, ctx, 0, u, v));
  double t0 = cupid_wtime();
  for (cupid_int step = 1; step <= o->steps; step++) {
    if (s->react) CUPID_CALL(conditions_at(s, (double)step * dt));
    const double *moved = s->react ? s->ufix : u; /* the fixed DOFs' values at the step's end */
    double *vh = s->vn; /* v_{n+1/2} */
    for (cupid_int d = 0; d < s->n; d++) {
      vh[d] = v[d] + 0.5 * dt * s->a[d];
      s->un[d] = dyn_fixed(bc, d) ? moved[d] : u[d] + dt * vh[d];
    }
    accumulate(s, u, s->un, vh);
    memcpy(u, s->un, sizeof *u * (size_t)s->n);
    residual_force(s, u, vh, s->t1);
    if (s->react) support_work(s, s->w2);
    for (cupid_int d = 0; d < s->n; d++) {
      s->a[d] = dyn_fixed(bc, d) ? 0.0 : s->t1[d] / s->sys->m_lumped[d];
      v[d] = dyn_fixed(bc, d) ? 0.0 : vh[d] + 0.5 * dt * s->a[d];
    }
    CUPID_CALL(s->kst);
    int broke = 0;
    CUPID_CALL(after_forces(s, step, u, &broke));
    if (broke) { /* it broke at t_{n+1}: v_{n+1} stands, the next half-kick uses the new K */
      residual_force(s, u, v, s->t1);
      for (cupid_int d = 0; d < s->n; d++)
        s->a[d] = dyn_fixed(bc, d) ? 0.0 : s->t1[d] / s->sys->m_lumped[d];
      CUPID_CALL(s->kst);
    }
    CUPID_CALL(notify(s, fn, ctx, step, u, v));
    CUPID_CALL(s->kst);
  }
  info->time_step_s = cupid_wtime() - t0;
  return CUPID_SUCCESS;
}

/* The common part of both entries: options, fixed DOFs, E0, the integrator. */
static cupid_status run(dyn_state *s, double *u, double *v, cupid_dynamics_monitor monitor,
                        void *ctx, cupid_dynamics_info *info) {
  const cupid_dynamics_options *opts = s->opt;
  const cupid_dynamics_system *sys = s->sys;
  CUPID_CHECK(opts->dt > 0.0 && isfinite(opts->dt) && opts->steps >= 0 && opts->every >= 1,
              CUPID_ERR_ARGUMENT, "cupid_dynamics_run: need dt > 0, steps >= 0, every >= 1");
  CUPID_CHECK(opts->integrator != CUPID_INTEGRATOR_NEWMARK ||
                  (opts->beta > 0.0 && opts->gamma >= 0.5),
              CUPID_ERR_ARGUMENT, "Newmark needs beta > 0 and gamma >= 1/2 (got %g, %g)",
              opts->beta, opts->gamma);
  cupid_dynamics_info local;
  if (!info) info = &local;
  memset(info, 0, sizeof *info);
  info->dt = opts->dt;
  info->steps = opts->steps;
  cupid_status st = CUPID_SUCCESS;
  s->hooks = opts->hooks;
  CUPID_CHECK(!(s->hooks && s->hooks->after_forces) || opts->integrator == CUPID_INTEGRATOR_CENTRAL,
              CUPID_ERR_ARGUMENT, "an after-forces hook (bond breaking) needs central differences "
              "(Newmark factors K once)");
  CUPID_TRY(state_alloc(s));
  const cupid_dirichlet_t *bc = sys->bc;
  if (s->react) CUPID_TRY(conditions_at(s, 0.0));
  for (cupid_int d = 0; d < s->n; d++)
    if (dyn_fixed(bc, d)) u[d] = s->react ? s->ufix[d] : bc->value[d], v[d] = 0.0;
  /* E0: the energy at t = 0, the reference of the balance. */
  dyn_mass_apply(sys, s->n, v, s->t1);
  s->e0 = 0.5 * dyn_dot(s->n, v, s->t1);
  dyn_stiffness(s, u, s->t1);
  CUPID_TRY(s->kst);
  s->e0 += 0.5 * dyn_dot(s->n, u, s->t1);
  if (opts->integrator == CUPID_INTEGRATOR_NEWMARK)
    CUPID_TRY(run_newmark(s, u, v, monitor, ctx, info));
  else
    CUPID_TRY(run_central(s, u, v, monitor, ctx, info));
  info->max_balance = s->scale > 0.0 ? s->max_balance / s->scale : 0.0;
cleanup:
  state_free(s);
  return st;
}

cupid_status cupid_dynamics_run(const cupid_dynamics_system *sys, const cupid_dynamics_options *opts,
                                double *u, double *v, cupid_dynamics_monitor monitor, void *ctx,
                                cupid_dynamics_info *info) {
  CUPID_CHECK(sys && sys->K && opts && u && v, CUPID_ERR_ARGUMENT,
              "cupid_dynamics_run: NULL argument");
  CUPID_CHECK(!sys->M != !sys->m_lumped, CUPID_ERR_ARGUMENT,
              "cupid_dynamics_run: give exactly one of a consistent and a lumped mass");
  dyn_state s = {.n = sys->K->nrows * sys->K->bs, .sys = sys, .opt = opts};
  return run(&s, u, v, monitor, ctx, info);
}

cupid_status cupid_dynamics_run_explicit(const cupid_dynamics_explicit_system *sys,
                                         const cupid_dynamics_options *opts, double *u, double *v,
                                         cupid_dynamics_monitor monitor, void *ctx,
                                         cupid_dynamics_info *info) {
  CUPID_CHECK(sys && sys->apply && sys->m_lumped && sys->n > 0 && opts && u && v,
              CUPID_ERR_ARGUMENT, "cupid_dynamics_run_explicit: NULL argument or no DOF");
  CUPID_CHECK(opts->integrator == CUPID_INTEGRATOR_CENTRAL, CUPID_ERR_ARGUMENT,
              "a matrix-free stiffness needs the central-difference integrator (Newmark "
              "factors K)");
  const cupid_dynamics_system full = {.m_lumped = sys->m_lumped, .bc = sys->bc, .f = sys->f};
  dyn_state s = {.n = sys->n, .sys = &full, .opt = opts, .kfn = sys->apply, .kctx = sys->ctx};
  return run(&s, u, v, monitor, ctx, info);
}
