/**
 * @file dynamics.h
 * @brief Linear structural dynamics M a + C v + K u = f (paper 004 Eq. 3 with Rayleigh damping,
 *        paper 004 section 4): implicit Newmark with one factorisation for a constant step,
 *        explicit central differences with a lumped mass and a stable-step check, energies,
 *        and a small dense generalised eigen solver for verification.
 *
 * The system is given as global matrices on any DOF layout: PD-only, FE-only, or a coupled
 * [3 per PD node | FE DOFs] system (K then includes the coupling terms). Fixed DOFs of the
 * Dirichlet conditions are held at their prescribed values with zero velocity and
 * acceleration (massless supports); values and load are constant in time unless
 * cupid_dynamics_hooks.conditions gives them at each step.
 *
 * Damping: C = a M + b K (Rayleigh), modal damping ratio zeta = a / (2 omega) + b omega / 2.
 */
#ifndef CUPID_DYNAMICS_H
#define CUPID_DYNAMICS_H

#include "cupid/base.h"
#include "cupid/model.h"
#include "cupid/solvers.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The semi-discrete system. Exactly one of M (consistent, same shape as K) and m_lumped
 *  (one mass per scalar DOF) is given; central differences need m_lumped. */
typedef struct {
  const cupid_csr_t *K;          /**< stiffness, SPD on the free DOFs */
  const cupid_csr_t *M;          /**< consistent mass, or NULL */
  const double *m_lumped;        /**< diagonal mass (n entries), or NULL */
  const cupid_dirichlet_t *bc;   /**< finalized conditions, or NULL (nothing fixed) */
  const double *f;               /**< constant external force (n entries), or NULL */
} cupid_dynamics_system;

/** Energies at one instant. With E0 the initial kinetic + strain energy, the balance is
 *  kinetic + strain + damping + fracture - external - conversion = E0 (drift reported as its
 *  residual). */
typedef struct {
  double kinetic;   /**< v.M v / 2 */
  double strain;    /**< u.K u / 2 */
  double damping;   /**< energy dissipated by C since t = 0 (midpoint rule) */
  double external;  /**< work of f (and of moving supports) since t = 0 */
  double fracture;  /**< strain energy removed by hooks->after_forces (broken bonds) */
  double conversion; /**< energy the system's changes added (a resumption of a changed
                          system, cupid_dynamics_restart.changed: its kinetic + strain energy
                          after the change less before; issue 37's adaptive zones) */
  double balance;   /**< kinetic + strain + damping + fracture - external - conversion - E0 */
} cupid_dynamics_energy;

/**
 * The integrator's whole state at the end of a step (issue 36): what a run needs to continue
 * from there exactly, to the bit, as if it had never stopped. hooks->safe_point gets it at
 * every output step (pointers into the integrator, valid during the call); a run given it in
 * cupid_dynamics_options.resume continues from its step (the vectors copied in). Vectors have
 * n entries; those a run does not use are NULL (react, load: no time-dependent conditions).
 * In a distributed run each process has its own.
 */
typedef struct {
  cupid_int step;            /**< the last step done */
  cupid_int n;
  const double *u, *v, *a;   /**< displacement, velocity, acceleration */
  const double *react;       /**< the supports' reactions at the step's end, or NULL */
  const double *load;        /**< the load of the step's end, or NULL */
  cupid_dynamics_energy shares; /**< this process's damping, external and fracture sums */
  cupid_dynamics_energy whole;  /**< the energies of the last output step, whole system */
  double e0, scale, max_balance; /**< E0, the largest energy, the largest |balance| so far */
  double omega_max, dt_critical, dt_bound; /**< the stable-step check of step 0 */
  int lanczos_steps;
  /** 1: the system changed after this state (issue 37: an adaptive zone grew; central
   *  differences only). u and v are given on the new system's DOFs (n its size); a, react and
   *  load are not read (may be NULL): the run makes them again from the new K, mass and
   *  conditions at the state's time, holds the fixed DOFs at their values (zero velocity),
   *  checks the stable step again, and books the energy the change added (the new system's
   *  kinetic + strain energy at u, v less whole's, which must be this step's: hooks->stopped
   *  gives it so) in cupid_dynamics_energy.conversion and info->changed_energy. */
  int changed;
} cupid_dynamics_restart;

/** Optional hooks of a run (cupid_dynamics_options.hooks). */
typedef struct {
  /** Time-dependent conditions: at time t, the prescribed values of the fixed DOFs (into
   *  @p u_fixed: its fixed entries are read) and the whole load (into @p f, n entries). Called
   *  at t = 0 and at every step's end time. NULL: the constant bc values and f. The support
   *  reactions R = K u + C v + M a - f on the fixed DOFs then do work as they move (the
   *  trapezoidal rule), counted in the external work; fixed DOFs carry no kinetic energy. */
  cupid_status (*conditions)(void *ctx, double t, double *u_fixed, double *f);
  /** After the forces of every step and at t = 0 (central differences only): e.g. break
   *  bonds. The strain energy it removes from the system at u goes to *dissipated (added to
   *  cupid_dynamics_energy.fracture). When it changes K it sets *changed: K changed at
   *  t_{n+1}, v_{n+1} stands and the acceleration is recomputed with the new K, so that what
   *  broke does no work after it broke and the energy balance stays second order. @p ku holds
   *  K u at u (the old K): *changed = 1 says the hook updated it to the new K's product
   *  (e.g. subtracted the broken bonds' forces: no new product of K), 2 that the integrator
   *  must recompute it. In a distributed run (cupid_dynamics_partition) u's copies are
   *  current, ku is meaningful on the owned DOFs and *dissipated is this process's share.
   *  NULL: none. */
  cupid_status (*after_forces)(void *ctx, cupid_int step, double t, const double *u, double *ku,
                               double *dissipated, int *changed);
  /** At the end of every output step after the monitor (issue 36): the state to keep for a
   *  resumption (e.g. write a checkpoint). A non-success return stops the run with it. NULL:
   *  none. */
  cupid_status (*safe_point)(void *ctx, const cupid_dynamics_restart *state);
  /** After every step of central differences (after the monitor and the safe point): *stop =
   *  1 ends the run at this step (issue 37: an adaptive zone's trigger fired). The run then
   *  evaluates the energies at this step, gives its whole state to `stopped` (needed with
   *  pause; pointers valid during the call) and returns CUPID_SUCCESS with info->stopped_at =
   *  the step; the caller continues it through cupid_dynamics_options.resume, on the same
   *  system or (restart.changed) a changed one. NULL: none. */
  cupid_status (*pause)(void *ctx, cupid_int step, const double *u, const double *v, int *stop);
  cupid_status (*stopped)(void *ctx, const cupid_dynamics_restart *state);
  void *ctx;
} cupid_dynamics_hooks;

/** Integration settings (cupid_dynamics_defaults() gives average-acceleration Newmark). */
typedef struct {
  cupid_integrator integrator;   /**< CUPID_INTEGRATOR_NEWMARK or _CENTRAL */
  double dt;                     /**< time step */
  cupid_int steps;               /**< number of steps */
  int every;                     /**< output every this many steps (>= 1) */
  double beta, gamma;            /**< Newmark parameters (default 1/4, 1/2) */
  double rayleigh_mass;          /**< a in C = a M + b K */
  double rayleigh_stiffness;     /**< b */
  const cupid_dynamics_hooks *hooks; /**< NULL: constant conditions, nothing after the forces */
  /** 1: the monitor reads v and a at step 0 and at output steps only (it gets NULL for both
   *  at the other steps). Central differences may then merge a step's closing half-kick
   *  with the next step's opening one between outputs (v_{n+3/2} = v_{n+1/2} + dt a_{n+1}:
   *  one pass over the vectors a step instead of two; the same scheme, other rounding), where
   *  nothing else needs v_{n+1}: no load, fixed DOF, damping or hook. 0 (default): v and a
   *  at every step. */
  int velocity_at_outputs;
  /** Continue from this state (a safe point's, of the same system and options) instead of
   *  starting at t = 0: no initial acceleration, stable-step check or step-0 call; the run's
   *  results are bit for bit those of the run that reached it. NULL: start at t = 0. */
  const cupid_dynamics_restart *resume;
} cupid_dynamics_options;

/** What a run did. */
typedef struct {
  cupid_int steps;
  double dt;
  double omega_max;      /**< estimate of the largest free frequency (Lanczos on
                              M^-1/2 K M^-1/2; central differences only, else 0; NaN
                              when a guaranteed bound made it unnecessary) */
  int lanczos_steps;     /**< products of K the estimate took */
  double dt_critical;    /**< stable step 2/omega_max, reduced for damping (central only) */
  double dt_bound;       /**< guaranteed-stable step from a Gershgorin bound (central only) */
  cupid_solve_info factor; /**< the factorisation of K + a0 M + a1 C (Newmark) */
  double time_step_s;    /**< wall time in the time loop */
  double max_balance;    /**< max |balance| / max(E0, max energy) over the output steps */
  cupid_int stopped_at;  /**< the step hooks->pause stopped the run at, or 0: it ran to the end */
  double changed_energy; /**< a resumption of a changed system: the energy the change added */
} cupid_dynamics_info;

/**
 * Called at step 0 (t = 0, before any step) and after every step; @p output is 1 at steps
 * that are multiples of `every` and at the last step. u, v, a are full vectors (n entries);
 * v and a are NULL at the steps that are not output steps if the run was asked
 * velocity_at_outputs.
 * The kinetic and strain energies (and the balance) are evaluated at output steps only (the
 * other steps see the last output's values; damping and external work are accumulated at
 * every step). A non-success return stops the run with that status.
 */
typedef cupid_status (*cupid_dynamics_monitor)(void *ctx, cupid_int step, double t, int output,
                                               const double *u, const double *v, const double *a,
                                               const cupid_dynamics_energy *energy);

/** Defaults: Newmark beta = 1/4, gamma = 1/2, every = 1, no damping (dt and steps to set). */
cupid_dynamics_options cupid_dynamics_defaults(void);

/**
 * Integrate from u (initial displacement, overwritten by the final one) and v (initial
 * velocity, overwritten), both with n = K->nrows * K->bs entries; fixed DOFs are reset to
 * their prescribed value and zero velocity. Newmark: K_eff = K + a0 M + a1 C is factored once
 * (CUPID_ERR_NUMERIC if singular); the initial acceleration solves M a = f - K u - C v
 * (a second factorisation for a consistent M). Central differences (needs m_lumped, every
 * free DOF with positive mass): v_{n+1/2} = v_n + dt/2 a_n, u_{n+1} = u_n + dt v_{n+1/2},
 * a_{n+1} = M^-1 (f - K u_{n+1} - C v_{n+1/2}) (damping lagged half a step),
 * v_{n+1} = v_{n+1/2} + dt/2 a_{n+1}; refused (CUPID_ERR_ARGUMENT, stating both steps) when
 * dt exceeds the critical step 2/omega_max (sqrt(1 + xi^2) - xi), xi the damping ratio of the
 * highest mode; info->dt_bound is the guaranteed (Gershgorin) bound.
 * monitor and info may be NULL.
 */
cupid_status cupid_dynamics_run(const cupid_dynamics_system *sys, const cupid_dynamics_options *opts,
                                double *u, double *v, cupid_dynamics_monitor monitor, void *ctx,
                                cupid_dynamics_info *info);

/** A matrix-free stiffness: y = K x (n entries each), e.g. cupid_pd_operator_apply. */
typedef cupid_status (*cupid_dynamics_stiffness_fn)(void *ctx, const double *x, double *y);

/** A distributed explicit run: this process holds the DOFs [0, n) of its share of a grid
 *  split over MPI ranks, of which it owns [owned_first, owned_last); the others are copies of
 *  DOFs other processes own (a halo that apply reads). The integrator updates every DOF it
 *  holds, refreshes the copies of u (and of the vectors it applies K to) through exchange,
 *  and sums energies and scalar products over the processes through sum, so that every
 *  process sees the same energies, stable step and monitor values. */
typedef struct {
  cupid_int owned_first, owned_last; /**< owned DOFs */
  cupid_int global_first;            /**< global index of DOF 0 (a start vector that does
                                          not depend on the split) */
  /** Overwrite x's copies with their owners' values (collective). */
  cupid_status (*exchange)(void *ctx, double *x);
  /** Sum values[0..count) over the processes, in place (collective). */
  void (*sum)(void *ctx, double *values, int count);
  void *ctx;
  /** Optional: the maximum of values[0..count) over the processes, in place (collective);
   *  a row_bound (cupid_dynamics_explicit_system) needs it in a distributed run. */
  void (*max)(void *ctx, double *values, int count);
} cupid_dynamics_partition;

/** The system of an explicit run with a matrix-free K and a lumped mass. */
typedef struct {
  cupid_int n;                        /**< scalar DOFs */
  cupid_dynamics_stiffness_fn apply;  /**< y = K x, symmetric positive semi-definite (in a
                                           distributed run: correct on the owned rows) */
  void *ctx;                          /**< passed to apply */
  const double *m_lumped;             /**< diagonal mass (n entries) */
  const cupid_dirichlet_t *bc;        /**< finalized conditions, or NULL */
  const double *f;                    /**< constant external force (n entries), or NULL */
  const cupid_dynamics_partition *part; /**< NULL: one process holds every DOF */
  /** Optional: a guaranteed bound of K's rows, n entries, such that every eigenvalue of
   *  M^-1 K on the free DOFs is at most max over them of row_bound[d] / m_lumped[d] (e.g.
   *  cupid_pd_operator_row_bound()). When dt is stable by this bound the Lanczos estimate is
   *  skipped. In a distributed run only the owned DOFs' entries are read, and part->max must
   *  be given. */
  const double *row_bound;
} cupid_dynamics_explicit_system;

/**
 * Central differences (opts->integrator must be CUPID_INTEGRATOR_CENTRAL) as in
 * cupid_dynamics_run(), with K only through products: no assembly, memory O(n) besides what
 * apply needs. Same steps, energies, damping (b K v through apply), monitor and stable-step
 * check, with two differences: the critical step comes from the Lanczos estimate, and
 * info->dt_bound is 0 (the Gershgorin bound needs the entries of K) unless sys->row_bound
 * gives one; then a dt within that bound is stable without the estimate (info->omega_max and
 * dt_critical NaN, lanczos_steps 0), and only a larger dt runs Lanczos. With apply the product
 * of an assembled K, the results equal cupid_dynamics_run()'s to round-off. An apply failure
 * stops the run with its status.
 */
cupid_status cupid_dynamics_run_explicit(const cupid_dynamics_explicit_system *sys,
                                         const cupid_dynamics_options *opts, double *u, double *v,
                                         cupid_dynamics_monitor monitor, void *ctx,
                                         cupid_dynamics_info *info);

/**
 * Largest eigenvalue lambda of M^-1 K on the free DOFs, for a lumped mass: Lanczos on
 * M^-1/2 K M^-1/2 (*estimate, the largest Ritz value, a lower bound converging from below;
 * at most @p iterations products, fewer once it is stable to 1e-7) and the Gershgorin
 * bound of M^-1/2 K M^-1/2 (*bound, an upper bound). Either pointer may be NULL.
 */
cupid_status cupid_dynamics_lambda_max(const cupid_csr_t *K, const double *m_lumped,
                                       const cupid_dirichlet_t *bc, int iterations,
                                       double *estimate, double *bound);

/**
 * The @p nev lowest eigenpairs of K x = lambda M x on the free DOFs, by a dense Cholesky
 * reduction and cyclic Jacobi rotations: for verification on small models (free DOFs <= 3000;
 * O(n^3)). omega[k] = sqrt(lambda_k) ascending; modes (may be NULL) receives nev full-length
 * vectors (n each, zero on fixed DOFs), M-normalised. M or m_lumped as in the system.
 */
cupid_status cupid_dynamics_eigen_dense(const cupid_csr_t *K, const cupid_csr_t *M,
                                        const double *m_lumped, const cupid_dirichlet_t *bc,
                                        int nev, double *omega, double *modes);

/** Modal damping ratio of Rayleigh damping at frequency omega: a/(2 omega) + b omega/2. */
double cupid_dynamics_rayleigh_zeta(double a, double b, double omega);

#ifdef __cplusplus
}
#endif
#endif
