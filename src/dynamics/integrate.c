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
#pragma omp parallel for schedule(static) if (n > DYN_OMP_MIN)
  for (cupid_int d = 0; d < n; d++) y[d] = sys->m_lumped[d] * x[d];
}

double dyn_dot(cupid_int n, const double *x, const double *y) {
  double s = 0.0;
#pragma omp parallel for reduction(+ : s) schedule(static) if (n > DYN_OMP_MIN)
  for (cupid_int d = 0; d < n; d++) s += x[d] * y[d];
  return s;
}

/* Work vectors of a run. */
typedef struct {
  cupid_int n;
  const cupid_dynamics_system *sys;
  cupid_dynamics_stiffness_fn kfn; /* matrix-free K (sys->K is NULL), else NULL */
  void *kctx;
  const double *row_bound;         /* matrix-free: a Gershgorin bound of K's rows (owned DOFs) */
  cupid_status kst;                /* first failure of kfn (checked after each step) */
  const cupid_dynamics_options *opt;
  const cupid_dynamics_hooks *hooks; /* opt->hooks, or NULL */
  const cupid_dynamics_partition *part; /* a distributed run, or NULL */
  cupid_int lo, hi;                  /* the DOFs whose energies this process counts */
  double *a, *un, *vn, *an, *w1, *w2, *t1, *t2, *g;
  double *minv; /* central differences: 1 / the lumped mass (0 on fixed DOFs) */
  /* Time-dependent conditions (hooks->conditions): the load now (f points here, else at
   * sys->f), the prescribed values, the support reactions of the last step, the fixed DOFs'
   * increment. */
  const double *f;
  double *fcur, *fprev, *ufix, *react, *du;
  cupid_dynamics_energy e;  /* this process's damping, external and fracture shares */
  cupid_dynamics_energy eg; /* the whole system's energies (monitor, balance) */
  double e0, scale, max_balance;
  int ku_ok;                /* g holds K u for the u the monitor sees (central differences) */
} dyn_state;

static void state_free(dyn_state *s) {
  double **arrays[] = {&s->a,  &s->un, &s->vn, &s->an,   &s->w1,   &s->w2,    &s->t1,
                       &s->t2, &s->g,  &s->fcur, &s->fprev, &s->ufix, &s->react, &s->du, &s->minv};
  for (size_t k = 0; k < sizeof arrays / sizeof *arrays; k++) cupid_free(arrays[k]);
}

static cupid_status state_alloc(dyn_state *s) {
  double **arrays[] = {&s->a, &s->un, &s->vn, &s->an, &s->w1, &s->w2, &s->t1, &s->t2, &s->g};
  for (size_t k = 0; k < sizeof arrays / sizeof *arrays; k++)
    CUPID_CALL(cupid_calloc((size_t)s->n, sizeof(double), "dynamics work vector", arrays[k]));
  s->f = s->sys->f;
  if (!(s->hooks && s->hooks->conditions)) {
    /* A constant load of zeros (a free vibration) is no load: the explicit step then takes
     * its two-stream paths (central_drift, central_kick) and the external work stays 0. */
    int zero = s->f != NULL;
    for (cupid_int d = 0; zero && d < s->n; d++) zero = s->f[d] == 0.0;
    if (zero) s->f = NULL;
    return CUPID_SUCCESS;
  }
  double **more[] = {&s->fcur, &s->fprev, &s->ufix, &s->react, &s->du};
  for (size_t k = 0; k < sizeof more / sizeof *more; k++)
    CUPID_CALL(cupid_calloc((size_t)s->n, sizeof(double), "dynamics work vector", more[k]));
  s->f = s->fcur;
  return CUPID_SUCCESS;
}

/* Sum over the processes of a distributed run (nothing on one process). */
static void reduce(const dyn_state *s, double *v, int n) {
  if (s->part) s->part->sum(s->part->ctx, v, n);
}

/* A failure that one process found stops every process: 1 if any found one. */
static int any_process(const dyn_state *s, int bad) {
  double b = bad ? 1.0 : 0.0;
  reduce(s, &b, 1);
  return b > 0.0;
}

/* x's copies from their owners (a distributed run). */
static cupid_status refresh(const dyn_state *s, double *x) {
  return s->part ? s->part->exchange(s->part->ctx, x) : CUPID_SUCCESS;
}

/* The conditions at time t: the load into fcur (the previous one kept in fprev) and the
 * prescribed values into ufix. */
static cupid_status conditions_at(dyn_state *s, double t) {
  double *keep = s->fprev; /* the current load becomes the previous one: swap, not copy */
  s->fprev = s->fcur;
  s->fcur = keep;
  s->f = s->fcur;
  CUPID_CALL(s->hooks->conditions(s->hooks->ctx, t, s->ufix, s->fcur));
  cupid_int bad = s->n; /* the first DOF whose value is not finite */
#pragma omp parallel for reduction(min : bad) schedule(static) if (s->n > DYN_OMP_MIN)
  for (cupid_int d = 0; d < s->n; d++)
    if (!(isfinite(s->fcur[d]) && (!dyn_fixed(s->sys->bc, d) || isfinite(s->ufix[d])))) bad = d;
  if (bad == s->n) bad = -1;
  if (!any_process(s, bad >= 0)) return CUPID_SUCCESS;
  CUPID_CHECK(bad < 0, CUPID_ERR_NUMERIC, "the %s of DOF %lld is not finite at t = %g",
              isfinite(s->fcur[bad]) ? "prescribed displacement" : "load", (long long)bad, t);
  return CUPID_ERROR(CUPID_ERR_NUMERIC, "another process found a value that is not finite at "
                     "t = %g", t);
}

/* Work of the moving supports over a step: the trapezoidal rule on R = K u + C v + M a - f
 * at the fixed DOFs (r_new holds it at the step's end; react the start's). */
static void support_work(dyn_state *s, const double *r_new) {
  const cupid_dirichlet_t *bc = s->sys->bc;
  double w = 0.0;
  const cupid_int lo = s->lo, hi = s->hi;
#pragma omp parallel for reduction(+ : w) schedule(static) if (hi - lo > DYN_OMP_MIN)
  for (cupid_int d = lo; d < hi; d++)
    if (dyn_fixed(bc, d)) {
      w += 0.5 * (s->react[d] + r_new[d]) * s->du[d];
      s->react[d] = r_new[d];
    }
  s->e.external += w;
}

/* hooks->after_forces at u (K u of the old K in ku): *changed as the hook says (0: K is as
 * it was; 1: ku is the new K's product; 2: recompute it). */
static cupid_status after_forces(dyn_state *s, cupid_int step, const double *u, double *ku,
                                 int *changed) {
  *changed = 0;
  if (!s->hooks || !s->hooks->after_forces) return CUPID_SUCCESS;
  double diss = 0.0;
  CUPID_CALL(s->hooks->after_forces(s->hooks->ctx, step, (double)step * s->opt->dt, u, ku, &diss,
                                    changed));
  s->e.fracture += diss;
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

/* The energies of (u, v) (kinetic and strain over the DOFs this process counts; damping,
 * external and fracture from its shares), summed over the processes into eg. */
static void energies(dyn_state *s, const double *u, const double *v) {
  const cupid_int lo = s->lo, len = s->hi - s->lo;
  dyn_mass_apply(s->sys, s->n, v, s->t1);
  double sums[6] = {0.5 * dyn_dot(len, v + lo, s->t1 + lo), 0.0, s->e.damping, s->e.external,
                    s->e.fracture, s->e.conversion};
  const double *ku = s->g; /* the step's own product when it holds (an apply saved) */
  if (!s->ku_ok) {
    dyn_stiffness(s, u, s->t1);
    ku = s->t1;
  }
  sums[1] = 0.5 * dyn_dot(len, u + lo, ku + lo);
  reduce(s, sums, 6);
  cupid_dynamics_energy *g = &s->eg;
  g->kinetic = sums[0], g->strain = sums[1], g->damping = sums[2], g->external = sums[3];
  g->fracture = sums[4], g->conversion = sums[5];
  g->balance = g->kinetic + g->strain + g->damping + g->fracture - g->external - g->conversion -
               s->e0;
  double level = fmax(g->kinetic + g->strain, fmax(fmax(g->damping, g->fracture), fabs(g->external)));
  if (level > s->scale) s->scale = level;
  if (fabs(g->balance) > s->max_balance) s->max_balance = fabs(g->balance);
}

/* Midpoint-rule increments of the dissipated energy and of the external work (a load that
 * changes over the step: its mean; the supports' share: support_work). */
static void accumulate(dyn_state *s, const double *u0, const double *u1, const double *vm) {
  const double *f = s->f;
  if (f && s->fprev)
    for (cupid_int d = s->lo; d < s->hi; d++) {
      s->e.external += 0.5 * (f[d] + s->fprev[d]) * (u1[d] - u0[d]);
      s->du[d] = u1[d] - u0[d];
    }
  else if (f)
    for (cupid_int d = s->lo; d < s->hi; d++) s->e.external += f[d] * (u1[d] - u0[d]);
  if (s->opt->rayleigh_mass != 0.0 || s->opt->rayleigh_stiffness != 0.0) {
    damping_apply(s, vm, s->t1, s->t2);
    s->e.damping += s->opt->dt * dyn_dot(s->hi - s->lo, vm + s->lo, s->t1 + s->lo);
  }
}

static void residual_of(dyn_state *s, const double *ku, const double *v, double *r);

/* r = f - K u - C v on free DOFs, 0 on fixed ones; with moving supports their reactions
 * K u + C v - f go to w2 (a lumped mass has no M a term on a fixed DOF). */
static void residual_force(dyn_state *s, const double *u, const double *v, double *r) {
  dyn_stiffness(s, u, r);
  residual_of(s, r, v, r);
}

/* r = f - ku - C v on free DOFs, 0 on fixed ones, from ku = K u (r may be ku); with moving
 * supports their reactions go to w2. */
static void residual_of(dyn_state *s, const double *ku, const double *v, double *r) {
  const cupid_dirichlet_t *bc = s->sys->bc;
  const int damped = s->opt->rayleigh_mass != 0.0 || s->opt->rayleigh_stiffness != 0.0;
  if (damped) damping_apply(s, v, s->w1, s->t2);
  const double *f = s->f;
  for (cupid_int d = 0; d < s->n; d++) {
    const double rd = (f ? f[d] : 0.0) - ku[d] - (damped ? s->w1[d] : 0.0);
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

/* Initial acceleration M a = f - K u - C v on the free DOFs (K u left in g). */
static cupid_status initial_acceleration(dyn_state *s, const double *u, const double *v) {
  dyn_stiffness(s, u, s->g);
  residual_of(s, s->g, v, s->t1);
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

static int output_step(const dyn_state *s, cupid_int step) {
  return step % s->opt->every == 0 || step == s->opt->steps;
}

/* Kinetic and strain energy cost two products per call, so they are evaluated at output
 * steps only (the balance check samples those); the monitor sees them there, and v and a
 * only there if the run was asked velocity_at_outputs. */
static cupid_status notify(dyn_state *s, cupid_dynamics_monitor fn, void *ctx, cupid_int step,
                           const double *u, const double *v) {
  int out = output_step(s, step);
  if (out) energies(s, u, v);
  if (!fn) return CUPID_SUCCESS;
  const int hide = !out && s->opt->velocity_at_outputs;
  return fn(ctx, step, (double)step * s->opt->dt, out, u, hide ? NULL : v, hide ? NULL : s->a,
            &s->eg);
}

/* hooks->safe_point at the end of an output step (after the monitor): the state a resumption
 * continues from. K u, the work vectors and the previous load are not in it: every step makes
 * them before it reads them. */
static cupid_dynamics_restart state_at(const dyn_state *s, const cupid_dynamics_info *info,
                                       cupid_int step, const double *u, const double *v) {
  return (cupid_dynamics_restart){
      .step = step, .n = s->n, .u = u, .v = v, .a = s->a, .react = s->react,
      .load = s->react ? s->fcur : NULL, .shares = s->e, .whole = s->eg, .e0 = s->e0,
      .scale = s->scale, .max_balance = s->max_balance, .omega_max = info->omega_max,
      .dt_critical = info->dt_critical, .dt_bound = info->dt_bound,
      .lanczos_steps = info->lanczos_steps};
}

static cupid_status safe_point(dyn_state *s, const cupid_dynamics_info *info, cupid_int step,
                               const double *u, const double *v) {
  if (!s->hooks || !s->hooks->safe_point || !output_step(s, step)) return CUPID_SUCCESS;
  const cupid_dynamics_restart r = state_at(s, info, step, u, v);
  return s->hooks->safe_point(s->hooks->ctx, &r);
}

/* A resumption of a changed system (restart.changed): the conditions at the state's time on
 * the new DOFs (the load into fcur, the fixed DOFs at their values, at rest). The acceleration,
 * reactions, stable step and the change's energy follow in run_central (book_change). */
static cupid_status changed_conditions(dyn_state *s, const cupid_dynamics_restart *r, double *u,
                                       double *v) {
  CUPID_CHECK(s->opt->integrator == CUPID_INTEGRATOR_CENTRAL, CUPID_ERR_ARGUMENT,
              "cupid_dynamics_run: a changed system resumes with central differences only "
              "(Newmark's factor is of the old one)");
  if (s->react) CUPID_CALL(conditions_at(s, (double)r->step * s->opt->dt));
  const cupid_dirichlet_t *bc = s->sys->bc;
  for (cupid_int d = 0; d < s->n; d++)
    if (dyn_fixed(bc, d)) u[d] = s->react ? s->ufix[d] : bc->value[d], v[d] = 0.0;
  CUPID_CALL(refresh(s, u));
  return refresh(s, v);
}

/* A resumption (opts->resume): the state of its safe point copied in, in place of the start
 * at t = 0 (E0, the conditions at 0, the fixed DOFs' values: all in it). */
static cupid_status resume_state(dyn_state *s, const cupid_dynamics_restart *r, double *u,
                                 double *v, cupid_dynamics_info *info) {
  CUPID_CHECK(r->n == s->n && r->step >= 0 && r->step <= s->opt->steps && r->u && r->v &&
                  (r->changed || (r->a && !r->react == !s->react && !r->load == !s->react)),
              CUPID_ERR_ARGUMENT, "cupid_dynamics_run: the state to resume (step %lld of %lld "
              "DOFs) is not one of this run's (%lld steps of %lld DOFs)",
              (long long)r->step, (long long)r->n, (long long)s->opt->steps, (long long)s->n);
  const size_t bytes = sizeof(double) * (size_t)s->n;
  memcpy(u, r->u, bytes);
  memcpy(v, r->v, bytes);
  s->e = r->shares;
  s->eg = r->whole;
  s->e0 = r->e0;
  s->scale = r->scale;
  s->max_balance = r->max_balance;
  info->omega_max = r->omega_max;
  info->dt_critical = r->dt_critical;
  info->dt_bound = r->dt_bound;
  info->lanczos_steps = r->lanczos_steps;
  if (r->changed) return changed_conditions(s, r, u, v);
  memcpy(s->a, r->a, bytes);
  if (s->react) {
    memcpy(s->react, r->react, bytes);
    memcpy(s->fcur, r->load, bytes);
  }
  return CUPID_SUCCESS;
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
  const cupid_int first = o->resume ? o->resume->step + 1 : 1;
  if (!o->resume) {
    CUPID_TRY(initial_acceleration(s, u, v));
    if (s->react) initial_reactions(s);
  }
  CUPID_TRY(effective_matrix(s, a0 + a1 * ra, 1.0 + a1 * rb, &Keff));
  CUPID_TRY(cupid_direct_factor_create(Keff, bc, &F, &info->factor));
  /* g = K_eff u_c: the prescribed values moved to the right-hand side (constant). */
  for (cupid_int d = 0; d < s->n; d++) s->t1[d] = dyn_fixed(bc, d) ? u[d] : 0.0;
  cupid_csr_matvec(Keff, s->t1, s->g);
  if (!o->resume) CUPID_TRY(notify(s, fn, ctx, 0, u, v));
  double t0 = cupid_wtime();
  for (cupid_int step = first; step <= o->steps; step++) {
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
    CUPID_TRY(safe_point(s, info, step, u, v));
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

/* The Gershgorin bound of M^-1 K from the rows' bound: the max over the free owned DOFs (of
 * every process) of row_bound / m; +inf (no bound) if one is not a number. */
static double row_bound_lambda(const dyn_state *s) {
  double b = 0.0;
  for (cupid_int d = s->lo; d < s->hi; d++) {
    const double q = s->row_bound[d] * s->minv[d]; /* minv is 0 on the fixed DOFs */
    if (!(q <= b)) b = q == q ? q : INFINITY;
  }
  if (s->part) s->part->max(s->part->ctx, &b, 1);
  return b;
}

static cupid_status check_stable(dyn_state *s, cupid_dynamics_info *info) {
  const cupid_dynamics_options *o = s->opt;
  double est = 0.0, bound = 0.0;
  int steps = 0;
  if (s->row_bound) { /* matrix-free with a guaranteed bound: when dt is below its step, the
                         Lanczos estimate (tens of products of K) has nothing to check */
    bound = row_bound_lambda(s);
    info->dt_bound = bound < INFINITY ? critical_step(bound, o->rayleigh_mass, o->rayleigh_stiffness) : 0.0;
    if (o->dt <= info->dt_bound) {
      info->omega_max = info->dt_critical = NAN;
      info->lanczos_steps = 0;
      return CUPID_SUCCESS;
    }
  }
  if (s->kfn) /* matrix-free: Lanczos (dt_bound from the row bound if there is one, else 0) */
    CUPID_CALL(dyn_lambda_max_fn(s->kfn, s->kctx, s->n, s->sys->m_lumped, s->sys->bc, s->part,
                                 200, &est, &steps));
  else
    CUPID_CALL(cupid_dynamics_lambda_max(s->sys->K, s->sys->m_lumped, s->sys->bc, 200, &est, &bound));
  info->omega_max = sqrt(est);
  info->lanczos_steps = steps;
  info->dt_critical = critical_step(est, o->rayleigh_mass, o->rayleigh_stiffness);
  if (!s->kfn) info->dt_bound = critical_step(bound, o->rayleigh_mass, o->rayleigh_stiffness);
  else if (!s->row_bound) info->dt_bound = 0.0;
  CUPID_CHECK(o->dt <= info->dt_critical, CUPID_ERR_ARGUMENT,
              "central differences are unstable with dt = %g: the critical step is about %g "
              "(omega_max = %g by a Lanczos estimate; guaranteed stable below %g); use a "
              "smaller dt or the newmark integrator",
              o->dt, info->dt_critical, info->omega_max, info->dt_bound);
  return CUPID_SUCCESS;
}

/* The drift and the kick where no DOF is fixed and there is no load: the streams as
 * restrict-qualified arguments (through s the compiler must assume they alias, and leaves the
 * loops scalar), so they vectorise. */
static void drift_free(cupid_int n, double dt, const double *restrict v,
                       const double *restrict a, double *restrict vh, double *restrict u) {
#pragma omp parallel for schedule(static) if (n > DYN_OMP_MIN)
  for (cupid_int d = 0; d < n; d++) {
    const double h = v[d] + 0.5 * dt * a[d];
    vh[d] = h;
    u[d] += dt * h;
  }
}

static void kick_free(cupid_int n, double hdt, const double *restrict g,
                      const double *restrict minv, const double *restrict vh, double *restrict a,
                      double *restrict v) {
#pragma omp parallel for schedule(static) if (n > DYN_OMP_MIN)
  for (cupid_int d = 0; d < n; d++) {
    a[d] = (0.0 - g[d]) * minv[d];
    v[d] = vh[d] + hdt * a[d];
  }
}

/* A step's closing half-kick merged with the next step's drift, between outputs where no
 * one reads v_{n+1} (merge_kicks): a_{n+1} = -M^-1 K u_{n+1}, v_{n+3/2} = v_{n+1/2} + dt
 * a_{n+1}, u_{n+2} = u_{n+1} + dt v_{n+3/2}, in place (vh holds v_{n+1/2}); one pass over
 * g, minv, vh and u instead of the kick's and the drift's five streams each. A uniform mass
 * (every node of one material) is one number: a stream fewer, the same values. */
static void kick_drift_free(cupid_int n, double dt, const double *restrict g,
                            const double *restrict minv, double *restrict vh,
                            double *restrict u) {
#pragma omp parallel for schedule(static) if (n > DYN_OMP_MIN)
  for (cupid_int d = 0; d < n; d++) {
    const double h = vh[d] + dt * ((0.0 - g[d]) * minv[d]);
    vh[d] = h;
    u[d] += dt * h;
  }
}

static void kick_drift_uniform(cupid_int n, double dt, const double *restrict g, double minv,
                               double *restrict vh, double *restrict u) {
#pragma omp parallel for schedule(static) if (n > DYN_OMP_MIN)
  for (cupid_int d = 0; d < n; d++) {
    const double h = vh[d] + dt * ((0.0 - g[d]) * minv);
    vh[d] = h;
    u[d] += dt * h;
  }
}

/* minv's value if every entry has it, else NaN. */
static double uniform_value(cupid_int n, const double *x) {
  for (cupid_int d = 1; d < n; d++)
    if (x[d] != x[0]) return NAN;
  return n > 0 ? x[0] : NAN;
}

/* Whether the closing half-kick of a step may merge with the next step's drift: no one
 * reads v_{n+1} between outputs (the monitor asked velocity_at_outputs; no hook, load,
 * fixed DOF or damping needs it or changes the update). */
static int merge_kicks(const dyn_state *s) {
  const cupid_dynamics_options *o = s->opt;
  /* a safe point (checkpoints) is at output steps, where the kick is whole: it does not stop
   * the merge */
  const int hooked = s->hooks && (s->hooks->conditions || s->hooks->after_forces || s->hooks->pause);
  return o->velocity_at_outputs && !hooked && !s->f && !s->du && !s->react &&
         !dyn_any_fixed(s->sys->bc) && o->rayleigh_mass == 0.0 && o->rayleigh_stiffness == 0.0;
}

/* The drift of a step: v_{n+1/2} = v_n + dt/2 a_n into vh, u_{n+1} = u_n + dt v_{n+1/2} (the
 * fixed DOFs at their values at the step's end, moved), in place, with the external work of
 * the step (the load's mean over the step when it changes) and the fixed DOFs' increments. */
static void central_drift(dyn_state *s, double *u, const double *v, const double *moved,
                          double *vh) {
  const cupid_dirichlet_t *bc = s->sys->bc;
  const double dt = s->opt->dt, *f = s->f, *fp = s->fprev;
  double w = 0.0;
  const cupid_int n = s->n, lo = s->lo, hi = s->hi;
  double *du = s->du;
  if (!f && !du && !dyn_any_fixed(bc)) { /* the common explicit step */
    drift_free(n, dt, v, s->a, vh, u);
    return;
  }
#pragma omp parallel for reduction(+ : w) schedule(static) if (n > DYN_OMP_MIN)
  for (cupid_int d = 0; d < n; d++) {
    vh[d] = v[d] + 0.5 * dt * s->a[d];
    const double un = dyn_fixed(bc, d) ? moved[d] : u[d] + dt * vh[d], step = un - u[d];
    if (f && d >= lo && d < hi) w += (fp ? 0.5 * (f[d] + fp[d]) : f[d]) * step;
    if (du) du[d] = step;
    u[d] = un;
  }
  s->e.external += w;
}

/* a = M^-1 r on the free DOFs, 0 on the fixed ones. */
static void accelerations(dyn_state *s, const double *r) {
#pragma omp parallel for schedule(static) if (s->n > DYN_OMP_MIN)
  for (cupid_int d = 0; d < s->n; d++) s->a[d] = r[d] * s->minv[d];
}

/* The kick that ends a step: a_{n+1} = M^-1 (f - K u_{n+1} - C v_{n+1/2}) and v_{n+1} =
 * v_{n+1/2} + dt/2 a_{n+1} (zero on the fixed DOFs; the supports' reactions in w2); K u_{n+1}
 * stays in g for the after-forces hook. */
static void central_kick(dyn_state *s, const double *u, const double *vh, double *v) {
  const cupid_dirichlet_t *bc = s->sys->bc;
  const double hdt = 0.5 * s->opt->dt;
  dyn_stiffness(s, u, s->g);
  if (s->opt->rayleigh_mass != 0.0 || s->opt->rayleigh_stiffness != 0.0) {
    residual_of(s, s->g, vh, s->t1);
    for (cupid_int d = 0; d < s->n; d++) {
      s->a[d] = s->t1[d] * s->minv[d];
      v[d] = dyn_fixed(bc, d) ? 0.0 : vh[d] + hdt * s->a[d];
    }
    return;
  }
  /* undamped: residual, reactions, acceleration and velocity in one pass */
  const double *f = s->f;
  if (!f && !dyn_any_fixed(bc)) { /* no load, no fixed DOF: no reactions */
    kick_free(s->n, hdt, s->g, s->minv, vh, s->a, v);
    return;
  }
  if (!dyn_any_fixed(bc)) { /* no fixed DOF: no reactions, and branch-free */
    double *restrict a = s->a;
    const double *restrict g = s->g, *restrict minv = s->minv;
#pragma omp parallel for schedule(static) if (s->n > DYN_OMP_MIN)
    for (cupid_int d = 0; d < s->n; d++) {
      a[d] = ((f ? f[d] : 0.0) - g[d]) * minv[d];
      v[d] = vh[d] + hdt * a[d];
    }
    return;
  }
#pragma omp parallel for schedule(static) if (s->n > DYN_OMP_MIN)
  for (cupid_int d = 0; d < s->n; d++) {
    const int fixed = dyn_fixed(bc, d);
    const double rd = (f ? f[d] : 0.0) - s->g[d];
    if (s->react && fixed) s->w2[d] = -rd;
    s->a[d] = fixed ? 0.0 : rd * s->minv[d];
    v[d] = fixed ? 0.0 : vh[d] + hdt * s->a[d];
  }
}

/* The after-forces hook at t_{n+1} (K u_{n+1} in g): if K changed, v_{n+1} stands and the
 * next half-kick uses the new K's acceleration (from the hook's updated K u when it gave
 * one and there is no stiffness damping, else from a new product). */
static cupid_status after_break(dyn_state *s, cupid_int step, const double *u, const double *v) {
  int changed = 0;
  if (!s->hooks || !s->hooks->after_forces) return CUPID_SUCCESS;
  CUPID_CALL(after_forces(s, step, u, s->g, &changed));
  if (!changed) return CUPID_SUCCESS;
  if (changed != 1) s->ku_ok = 0; /* g is the old K's product */
  if (changed == 1 && s->opt->rayleigh_stiffness == 0.0) residual_of(s, s->g, v, s->t1);
  else residual_force(s, u, v, s->t1);
  accelerations(s, s->t1);
  /* The supports' reactions at the start of the next step are the new K's (w2, just made):
   * support_work had kept the old K's, and the next step's trapezoid then counted the broken
   * bonds' pull on the grips again, work that their breaking had already booked as fracture
   * (issue 33: a balance of 0.497 when every bond breaks at the first step). */
  if (s->react)
    for (cupid_int d = s->lo; d < s->hi; d++)
      if (dyn_fixed(s->sys->bc, d)) s->react[d] = s->w2[d];
  return s->kst;
}

/* A resumption of a changed system, its acceleration made (K u in g): the energy the change
 * added, the new kinetic + strain energy at (u, v) less the state's, booked as conversion
 * (one process's share holds it) before the balance is sampled with it. */
static void book_change(dyn_state *s, const cupid_dynamics_restart *r, const double *u,
                        const double *v, cupid_dynamics_info *info) {
  const double scale = s->scale, worst = s->max_balance;
  energies(s, u, v);
  const double added = s->eg.kinetic + s->eg.strain - (r->whole.kinetic + r->whole.strain);
  if (!s->part || s->part->global_first == 0) s->e.conversion += added;
  s->scale = scale, s->max_balance = worst;
  energies(s, u, v); /* the balance with it (g still holds K u: no new product) */
  info->changed_energy = added;
}

/* hooks->pause asked the run to stop at this step: the energies at it, and the whole state to
 * hooks->stopped, as a safe point's. */
static cupid_status stopped(dyn_state *s, cupid_dynamics_info *info, cupid_int step,
                            const double *u, const double *v) {
  CUPID_CHECK(s->hooks->stopped, CUPID_ERR_ARGUMENT,
              "cupid_dynamics_run: hooks->pause needs hooks->stopped to take the state");
  if (!output_step(s, step)) energies(s, u, v);
  CUPID_CALL(s->kst);
  const cupid_dynamics_restart r = state_at(s, info, step, u, v);
  info->stopped_at = step;
  return s->hooks->stopped(s->hooks->ctx, &r);
}

static cupid_status run_central(dyn_state *s, double *u, double *v, cupid_dynamics_monitor fn,
                                void *ctx, cupid_dynamics_info *info) {
  const cupid_dynamics_options *o = s->opt;
  const cupid_dirichlet_t *bc = s->sys->bc;
  double dt = o->dt;
  CUPID_CHECK(s->sys->m_lumped && !s->sys->M, CUPID_ERR_ARGUMENT,
              "central differences need a lumped (diagonal) mass");
  cupid_int massless = -1;
  for (cupid_int d = 0; d < s->n && massless < 0; d++)
    if (!(dyn_fixed(bc, d) || s->sys->m_lumped[d] > 0.0)) massless = d;
  if (any_process(s, massless >= 0)) {
    CUPID_CHECK(massless < 0, CUPID_ERR_ARGUMENT,
                "free DOF %lld has no mass (central differences need a positive lumped mass)",
                (long long)massless);
    return CUPID_ERROR(CUPID_ERR_ARGUMENT, "another process found a free DOF without mass");
  }
  CUPID_CALL(cupid_calloc((size_t)s->n + 1, sizeof *s->minv, "inverse masses", &s->minv));
  for (cupid_int d = 0; d < s->n; d++) s->minv[d] = dyn_fixed(bc, d) ? 0.0 : 1.0 / s->sys->m_lumped[d];
  if (!o->resume || o->resume->changed) { /* a resumption has all of this in its state (of
                                             the system it was written on) */
    CUPID_CALL(check_stable(s, info));
    CUPID_CALL(initial_acceleration(s, u, v));
    s->ku_ok = 1;
    if (s->react) initial_reactions(s);
    CUPID_CALL(s->kst);
    if (o->resume) {
      book_change(s, o->resume, u, v, info);
      CUPID_CALL(s->kst);
    } else {
      CUPID_CALL(after_break(s, 0, u, v));
      CUPID_CALL(notify(s, fn, ctx, 0, u, v));
    }
  }
  double t0 = cupid_wtime();
  const int stiff_damping = o->rayleigh_stiffness != 0.0;
  const int merge = merge_kicks(s);
  const double mu = merge ? uniform_value(s->n, s->minv) : NAN;
  int drifted = 0; /* u holds u_{n+1} and vn v_{n+1/2} already (a merged kick and drift) */
  for (cupid_int step = o->resume ? o->resume->step + 1 : 1; step <= o->steps; step++) {
    if (s->react) CUPID_CALL(conditions_at(s, (double)step * dt));
    double *vh = s->vn; /* v_{n+1/2} */
    if (!drifted) central_drift(s, u, v, s->react ? s->ufix : u, vh);
    drifted = 0;
    s->ku_ok = 0;
    CUPID_CALL(refresh(s, u));
    if (stiff_damping) CUPID_CALL(refresh(s, vh)); /* b K v_{n+1/2} reads its copies */
    if (o->rayleigh_mass != 0.0 || stiff_damping) { /* the damping's work over the step */
      damping_apply(s, vh, s->t1, s->t2);
      s->e.damping += dt * dyn_dot(s->hi - s->lo, vh + s->lo, s->t1 + s->lo);
    }
    if (merge && !output_step(s, step)) { /* v_{n+1} unread: the kick joins the next drift */
      dyn_stiffness(s, u, s->g);
      s->ku_ok = 1;
      CUPID_CALL(s->kst);
      CUPID_CALL(notify(s, fn, ctx, step, u, NULL));
      if (mu == mu) kick_drift_uniform(s->n, dt, s->g, mu, vh, u);
      else kick_drift_free(s->n, dt, s->g, s->minv, vh, u);
      drifted = 1;
      continue;
    }
    central_kick(s, u, vh, v);
    s->ku_ok = 1;
    if (s->react) support_work(s, s->w2);
    CUPID_CALL(s->kst);
    CUPID_CALL(after_break(s, step, u, v));
    CUPID_CALL(notify(s, fn, ctx, step, u, v));
    CUPID_CALL(s->kst);
    CUPID_CALL(safe_point(s, info, step, u, v));
    int stop = 0;
    if (s->hooks && s->hooks->pause) CUPID_CALL(s->hooks->pause(s->hooks->ctx, step, u, v, &stop));
    if (stop) {
      info->time_step_s = cupid_wtime() - t0;
      return stopped(s, info, step, u, v);
    }
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
  CUPID_CHECK(!(s->hooks && s->hooks->pause) || opts->integrator == CUPID_INTEGRATOR_CENTRAL,
              CUPID_ERR_ARGUMENT, "a pause hook (a system that changes) needs central differences");
  CUPID_TRY(state_alloc(s));
  const cupid_dirichlet_t *bc = sys->bc;
  if (opts->resume) {
    CUPID_TRY(resume_state(s, opts->resume, u, v, info));
  } else {
    if (s->react) CUPID_TRY(conditions_at(s, 0.0));
    for (cupid_int d = 0; d < s->n; d++)
      if (dyn_fixed(bc, d)) u[d] = s->react ? s->ufix[d] : bc->value[d], v[d] = 0.0;
    /* E0: the energy at t = 0, the reference of the balance. */
    CUPID_TRY(refresh(s, u));
    CUPID_TRY(refresh(s, v));
    energies(s, u, v);
    CUPID_TRY(s->kst);
    s->e0 = s->eg.kinetic + s->eg.strain;
    s->scale = s->max_balance = 0.0;
  }
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
  s.hi = s.n;
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
  const cupid_dynamics_partition *p = sys->part;
  CUPID_CHECK(!p || (p->exchange && p->sum && p->owned_first >= 0 &&
                     p->owned_first <= p->owned_last && p->owned_last <= sys->n),
              CUPID_ERR_ARGUMENT, "cupid_dynamics_run_explicit: a partition needs exchange, sum "
              "and owned DOFs within [0, n)");
  CUPID_CHECK(!p || !sys->row_bound || p->max, CUPID_ERR_ARGUMENT,
              "cupid_dynamics_run_explicit: a row_bound in a distributed run needs the "
              "partition's max");
  dyn_state s = {.n = sys->n, .sys = &full, .opt = opts, .kfn = sys->apply, .kctx = sys->ctx,
                 .row_bound = sys->row_bound, .part = p, .lo = p ? p->owned_first : 0,
                 .hi = p ? p->owned_last : sys->n};
  return run(&s, u, v, monitor, ctx, info);
}
