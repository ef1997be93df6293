/* Private to src/problem: the coupling methods as tables of functions.
 *
 * A model is a PD grid, a beam, or both joined by a coupling method. Each method fills one
 * cupid_method_ops; the stages of problem.c and dynamic.c call through it and never ask which
 * method it is. The tables:
 *   cupid_method_none        PD only or beam only (method_none.c)
 *   cupid_method_fictitious  paper 000 section 4, fictitious nodes (method_fictitious.c)
 *   cupid_method_lagrange    Lagrange multipliers, eliminated (method_lagrange.c)
 *   cupid_method_arlequin    paper 004 section 3, energy weights + penalty (method_arlequin.c)
 * Adding a method is filling a table and naming it in cupid_problem_method_of(); a NULL entry
 * means the method has no such stage (the capability bits say what it can run). */
#ifndef CUPID_PROBLEM_METHOD_H
#define CUPID_PROBLEM_METHOD_H

#include "problem_internal.h"

/** What a method can run (cupid_method_ops.caps). */
enum {
  CUPID_METHOD_DYNAMIC = 1 << 0,    /**< type dynamic */
  CUPID_METHOD_GRID_1D = 1 << 1,    /**< 1D PD grids (a bar along the axis) */
  CUPID_METHOD_SLABS = 1 << 2,      /**< the PD grid split into z slabs under mpirun (its
                                         matrix-free static solve runs on slabs) */
  CUPID_METHOD_GUARD_MATRIX_FREE = 1 << 3, /**< its matrix-free static solve has a calibrated
                                               memory estimate, checked before it runs */
  CUPID_METHOD_CONDITIONS_ASSEMBLE = 1 << 4, /**< its constraints need the assembled system
                                                 (Lagrange's tie): `cupid check` skips them */
  CUPID_METHOD_FRACTURE = 1 << 5,   /**< pre-cracks and bond breaking on prob->op (the PD
                                         operator its explicit operator applies) */
  CUPID_METHOD_ADAPTIVE = 1 << 6,   /**< adaptive PD zones (adaptive.c): its layout follows the
                                         model's regions and overlaps, built again as they grow */
  CUPID_METHOD_OVERLAPS = 1 << 7,   /**< its PD regions carry overlaps with the beam
                                         (coupling.arlequin.overlap) that an adaptive zone lays
                                         out with them; without: a zone's region is its core */
};

/** A matrix-free operator of a whole system for explicit dynamics: y = K x. */
typedef struct {
  cupid_status (*apply)(void *ctx, const double *x, double *y);
  void *ctx;
  void (*destroy)(void **ctx); /**< NULL: borrowed */
  /** Optional: a guaranteed bound of K's rows (cupid_dynamics_explicit_system.row_bound),
   *  ndof entries (on a slab: right on the owned rows), so that a stable dt needs no Lanczos
   *  estimate. */
  cupid_status (*row_bound)(void *ctx, double *r);
} cupid_method_operator;

struct cupid_method_ops {
  const char *name;           /**< as in the model file: none, fictitious, lagrange, arlequin */
  unsigned caps;              /**< CUPID_METHOD_* */
  cupid_matrix_kind matrix;   /**< the assembled system: SPD (CHOLMOD) or GENERAL (UMFPACK) */

  /** What this version cannot run with the method: model errors, before anything is built. */
  cupid_status (*check)(const cupid_problem_state *prob);
  /** After the grid and the beam are built: the coupling layout (the beam gives way inside
   *  the regions, overlaps). NULL: nothing to do. */
  cupid_status (*prepare)(cupid_problem_state *prob);
  /** Constraints into prob->bc (not finalized), split between the beam and the PD grid. */
  cupid_status (*constraints)(cupid_problem_state *prob);
  /** Loads into prob->f_ext (after bc is finalized). */
  cupid_status (*loads)(cupid_problem_state *prob);
  /** prob->K: the whole system's stiffness with the coupling terms (unless already built). */
  cupid_status (*assemble)(cupid_problem_state *prob);
  /** After bonds broke: the rows of prob->K of the PD nodes @p nodes (sorted; the nodes whose
   *  bonds changed, cupid_pd_operator_take_changed()) assembled again in place, each as a new K
   *  would have it to the bit (K keeps its pattern: a broken bond's blocks are zero). NULL: K
   *  is assembled whole again (growth.c). */
  cupid_status (*update_rows)(cupid_problem_state *prob, const cupid_int *nodes, cupid_int n);
  /** The static solve of the assembled K (prob->u, f_int, solve, solved). NULL: the engine's
   *  solve (cupid_problem_assembled_solve). */
  cupid_status (*solve_assembled)(cupid_problem_state *prob);
  /** 1 when the static solve with @p engine takes the matrix-free path. */
  int (*matrix_free)(const cupid_problem_state *prob, const cupid_solver_type *engine);
  /** The matrix-free static solve: prob->u, f_int, solve, phases, solved. */
  cupid_status (*solve_matrix_free)(cupid_problem_state *prob);
  /** Central differences with a lumped mass without K: the operator (NULL: assemble K). */
  cupid_status (*explicit_operator)(cupid_problem_state *prob, cupid_method_operator *op);
  /** The mass for type dynamic: *M in K's pattern (consistent) or *m_lumped (lumped). */
  cupid_status (*mass)(cupid_problem_state *prob, cupid_csr *M, double **m_lumped);
  /** Eliminated unknowns back into a solution vector (NULL: none eliminated). */
  void (*recover)(const cupid_problem_state *prob, double *u);
  /** After a solve: figures of merit on stderr (equilibrium, constraint gap). NULL: none. */
  cupid_status (*report)(const cupid_problem_state *prob);
  /** The matrix-free path's estimate (issue 6 calibrations): bytes on one rank, seconds and
   *  what it is; 0 when the method has none for this model. */
  int (*estimate_matrix_free)(const cupid_problem_state *prob, double *bytes, double *seconds,
                              const char **what);
  /** The patch test (quality.c): move the forces @p r of DOFs the method ties to others onto
   *  those (a penalty tie held exactly), so that what is left is what the tied problem
   *  leaves. NULL: every DOF is independent (fictitious; Lagrange's K is already the tied
   *  system). */
  cupid_status (*patch_tie)(const cupid_problem_state *prob, double *r);
  /** Fracture: flag the PD nodes whose bonds must never break (the coupling zone: overlaps,
   *  tied or fictitious-node layers), @p protect zeroed, one per PD node. NULL: none. */
  cupid_status (*fracture_protect)(const cupid_problem_state *prob, unsigned char *protect);
  /** Fracture: name the protected zone holding the PD node at @p x for a message (e.g. "the
   *  Arlequin overlap {y: [29, 34]} (coupling.arlequin.overlap[0], line 40)"); by position, so
   *  that any rank of a slab run can name another's node. NULL: the method's name. */
  void (*protected_zone)(const cupid_problem_state *prob, const double x[3], char *buf, size_t len);
  /** Load steps and crack growth on the matrix-free path (growth_matrix_free.c): the static
   *  operator in *L (on a slab: its rows), the preconditioner matrix in *P and the operator's
   *  owner, kept for the whole run; with pre-cracks or fracture prob->crack_copy is set to
   *  the operator's own PD bonds, so that they break with prob->op's. On failure nothing is
   *  left to free. NULL: the method's growth assembles K. */
  cupid_status (*growth_operator)(cupid_problem_state *prob, cupid_linear_operator *L, cupid_csr *P,
                                  cupid_method_operator *owner);
  /** Free prob->method_state (what the method kept between its stages). NULL: it keeps none. */
  void (*free_state)(cupid_problem_state *prob);
};

/** dynamic.c: the method's mass, integrate (central differences on @p op when it has an apply,
 *  else on prob->K; an adaptive zone that grows replaces @p op), write history.csv,
 *  energies.csv, the VTU series and plots. */
cupid_status cupid_problem_run_dynamic(cupid_problem_state *prob, cupid_method_operator *op);

extern const cupid_method_ops cupid_method_none, cupid_method_fictitious, cupid_method_lagrange,
    cupid_method_arlequin;

/** The table of a model's method: none unless it has both a beam and a PD grid. */
const cupid_method_ops *cupid_problem_method_of(const cupid_model_t *model);

/* ---- shared by the coupled methods (method_coupled.c) ---- */

/** The beam gives way inside each of the given boxes (region by region, so that an error names
 *  the region's line in the model file). */
cupid_status cupid_method_deactivate_regions(cupid_problem_state *prob);
/** Which part a constraint or load touches; the default rules of fictitious and Lagrange: a
 *  clamp or traction plane on a beam node goes to the beam, else to the grid; boxes to both. */
typedef struct {
  /** 1 if a clamp plane (y) has PD nodes to hold (NULL: when no beam node is there). */
  int (*clamp_on_pd)(const cupid_problem_state *prob, const cupid_constraint *c);
} cupid_split_rules;
/** Split the model's constraints between the beam (applied here) and the grid (through
 *  cupid_problem_pd_constraints), then hold the FE nodes where the beam gave way at zero. */
cupid_status cupid_method_split_constraints(cupid_problem_state *prob, const cupid_split_rules *r);
/** Split the model's loads between the beam and the grid (no overlaps: fictitious, Lagrange). */
cupid_status cupid_method_split_loads(cupid_problem_state *prob);
/** The coupling's options from the model; *boxes and *mats (one per region) are the caller's
 *  to free, also after a failure. */
cupid_status cupid_method_coupling_options(const cupid_problem_state *prob,
                                           cupid_coupling_options *co, cupid_box **boxes,
                                           int **mats);
/** |R + P| / |P| on stderr (the figure of merit of a coupled run). */
cupid_status cupid_method_print_equilibrium(const cupid_problem_state *prob);
/** Solve prob's system by the engine's matrix-free solve of @p L preconditioned by *P and
 *  record it (prob->u, f_int, solve, phases, solved). On a slab the operator (@p owner) and *P
 *  are then freed (both set to NULL) and rank 0 gathers the whole model (slab.c). */
cupid_status cupid_method_krylov_solve(cupid_problem_state *prob, const cupid_linear_operator *L,
                                       cupid_csr *P, cupid_method_operator *owner);
/** The coupling object and its assembled K by @p create (cupid_coupling_create or
 *  cupid_coupling_lagrange_create), timed as the coupling phase; *info is the coupling's. */
cupid_status cupid_method_build_coupling(cupid_problem_state *prob,
                                         cupid_status (*create)(const cupid_cuf_beam,
                                                                const cupid_pd_grid,
                                                                const cupid_coupling_options *,
                                                                cupid_coupling_h *, cupid_csr *),
                                         cupid_coupling_info *info);
/** The PD and beam masses of a layout without coupling terms in the mass (none, Lagrange):
 *  rho V on the PD nodes, the beam's consistent or HRZ mass; with @p move_tied (Lagrange) the
 *  tied PD nodes' mass goes onto the beam through the tie. */
cupid_status cupid_method_plain_mass(cupid_problem_state *prob, int move_tied, cupid_csr *M,
                                     double **m_lumped);

#endif
