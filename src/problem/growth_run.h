/* Private to growth.c and growth_resume.c: the state of a run of load steps (issue 17) and the
 * journal that lets a resumption rebuild its factor to the bit (issue 36). */
#ifndef CUPID_GROWTH_RUN_H
#define CUPID_GROWTH_RUN_H

#include "problem_internal.h"

/* The factor's journal: the broken bonds (as cupid_pd_operator_pack_broken packs them) and the
 * fixed DOFs when the factor (g->F, or the LU's g->lu.F) was made, and what each downdate or
 * update since changed (the words of the bits, the DOFs held), so that a resumption factorises
 * the same K and brings it up to date by the same rounds (growth_resume.c). */
typedef struct {
  double *bits;         /* every node's words at the factorisation */
  double *now;          /* the words after the last round */
  double *fresh;        /* scratch: the words now, packed at each round */
  unsigned char *fixed; /* per DOF at the factorisation: 1 fixed (bc->fixed), 2 tied (g->tie) */
  unsigned char *fixed_now; /* ... after the last round (4: tied in the round replayed) */
  double *pairs;        /* (word index, word) of each round's changed words, in order */
  cupid_int n_pairs, cap_pairs;
  cupid_int *held;      /* the DOFs each round found newly fixed (held nodes) or, as -1 - d,
                           tied, in order */
  cupid_int n_held, cap_held;
  cupid_int *ends;      /* 2 per round: pairs and held DOFs at its end */
  cupid_int n_rounds, cap_rounds;
  cupid_int words;      /* words of every node */
} growth_journal;

/* The run's state. */
typedef struct {
  cupid_problem_state *prob;
  double *f_full, *g_full;      /* the load and the prescribed values at load factor 1 */
  unsigned char *fixed0;        /* the model's constrained DOFs */
  unsigned char *anchored, *release;
  unsigned char *weak_scan;     /* a copy of release, scratch */
  double *mech_seen;            /* with ties: each PD node's lost share at the last mechanism
                                   check (tie_mechanisms), its start or the layout's */
  int band_check;               /* search the bands of damaged nodes for mechanisms (default) */
  int band_factor;              /* after a node left singular, factorise the damaged nodes'
                                   block alone for the others (tie_band_factorised; default) */
  unsigned char *weak;          /* per node: released as weakly held (at most 2 bonds, or all
                                   in one plane; held_forces) */
  unsigned char *tie;           /* per node: tied by a weak spring (tie_mechanisms): 0 no, 1 in
                                   K and in F, 2 in neither yet, 3 in K, not yet in F; NULL where
                                   the run has no own factor (the engine finds mechanisms) */
  double tie_k;                 /* the ties' spring stiffness (TIE_STIFFNESS of K's diagonal) */
  cupid_int tied;               /* nodes tied */
  cupid_int tied_singular;      /* of them, named by a failed downdate or factorisation
                                   (tie_singular) */
  int step;                     /* the load step being solved (its messages) ... */
  int quiet;                    /* ... and the run's quiet flag (a re-solve is quiet) */
  double *u_before;             /* u before the last solve (ndof; with ties): where a tie that
                                   took load is held (hold_loaded_ties) */
  unsigned char *masks;         /* per constraint k: ndof flags, the DOFs it fixes */
  double *T;                    /* the unit translations, 3 ndof (cupid_problem_translations) */
  double *u1;                   /* without fracture: u and K u at load factor 1 */
  double u0[3];                 /* the first output point's displacement, last step */
  double next_ratio;            /* fracture: the settled step's largest ratio (next_break) */
  double ratio_per_load;        /* the first scanned solve's largest ratio per load factor */
  int cut_through;              /* the crack has cut the load path (carries_load) */
  int loaded;                   /* the model applies a load (not prescribed values alone) */
  int substep;                  /* sub-steps to each break's load (load_step) */
  int name_by_downdate;         /* a failed downdate names the node to tie (tie_singular); 0:
                                   the factorisation after it does (CUPID_GROWTH_NAME_BY_FACTOR,
                                   tests) */
  int refactor_share;           /* a round of more than n / this broken bonds refactorises
                                   (DOWNDATE_MAX_SHARE; 0: never, CUPID_GROWTH_DOWNDATE_ALL) */
  double t_line;                /* when the last step's progress line was printed */
  cupid_writer csv;             /* damage.csv or load_steps.csv (io.h's CSV writer) */
  cupid_writer exodus;          /* model.exo: a time step per load step (output.exodus) */
  cupid_problem_vertices verts; /* the PD nodes of its frames (a slab run: rank 0's whole grid) */
  cupid_pd_grid whole;          /* a slab run's whole grid, on rank 0 */
  cupid_int released;
  /* Re-solves after breaks (below): the factor of the last factorised K, reused as the
   * preconditioner of CG on the current K. */
  cupid_direct_factor F;
  int krylov;                   /* 0: refactorise after every break (CUPID_GROWTH_RESOLVE) */
  int downdate;                 /* 1: downdate F by the broken bonds (bond-based), so that it
                                   stays the factor of the current K; 0 after a K change that
                                   is no sum of bond terms (LPS), or CUPID_GROWTH_RESOLVE */
  int singular;                 /* the last downdate left F indefinite: the next solve goes to
                                   the engine at once (solve) */
  cupid_growth_downdate dd;
  /* K patched row by row after breaks (the method's update_rows) since it was assembled
   * whole: tracked_k / tracked_op are the K and operator whose changed rows the operator
   * records (cupid_pd_operator_take_changed); patched: K holds the zero blocks of broken
   * bonds, which a factorisation must not see (its ordering follows the pattern) */
  const void *tracked_k, *tracked_op;
  int patch;                    /* 1: patch K where it can (0: CUPID_GROWTH_WHOLE_K=1) */
  int patched;
  cupid_int downdates, downdate_columns;
  cupid_int held_rows;           /* factor rows deleted for nodes held (cupid_direct_factor_hold) */
  double t_downdate;
  double *w[4];                 /* CG work vectors */
  unsigned char *near_fixed;    /* per block row of K: next to a fixed DOF (lifted_rhs) */
  cupid_int factorisations, cg_solves, cg_iterations;
  cupid_int failed_factorisations; /* that broke down (a mechanism): each costs one, their time
                                     in t_factor */
  cupid_int bonds_at_factor;    /* broken bonds when F was made */
  double factor_flops;          /* the last factorisation's operations, and those of one */
  double cg_iteration_flops;    /* CG iteration with its factor (two triangular solves, K x) */
  cupid_int cg_since_factor;    /* CG iterations since the last factorisation */
  double t_factor, t_cg;
  double *react;                /* 3 per constraint: the reactions of the last solution */
  double held_share;            /* the held nodes' share of the forces on the body (collapse) */
  double weak_share;            /* the weakly held nodes' share (held_forces) */
  double tie_share;             /* the tied nodes' springs' share (held_forces) */
  double force_scale;           /* the largest |P| + sum |R_k| of the run (held_forces) */
  double *points;               /* 3 per output point */
  double *row;                  /* a row of the steps' file (write_row) */
  cupid_growth_lu lu;           /* a non-symmetric method on the direct engine (growth_lu.c) */
  int matrix_free;              /* solves by the kept matrix-free PETSc solve ... */
  cupid_growth_mf mf;           /* ... (growth_matrix_free.c) */
  growth_journal journal;       /* how g->F came to be (growth_resume.c) */
  int first_step;               /* 1, or a resumption's step after its checkpoint */
  int convert;                  /* adaptive: a crack asked into an overlap; the zone grows
                                   before the step goes on (convert_zone) */
  cupid_writer zones;           /* adaptive.pvd: the zone at each conversion (output.vtu) */
  int zone_frames;              /* its frames so far */
  double last_load;             /* the load factor of the last step written */
  cupid_checkpoint resume;      /* a resumption's checkpoint, open until the writers read it */
} growth_run;

/* growth.c: a weak spring of stiffness k on each DOF dofs[0 .. n) of K (its diagonal), and on
 * the factor F (cupid_direct_factor_update; growth_resume.c replays ties with them) */
cupid_status growth_tie_matrix(cupid_csr_t *K, cupid_int n, const cupid_int *dofs, double k);
cupid_status growth_tie_factor(cupid_direct_factor F, cupid_int n, const cupid_int *dofs, double k);

/* growth_resume.c */
/** g->F was just factorised: the journal starts again from the operator and the conditions. */
cupid_status growth_journal_factored(growth_run *g);
/** g->F was just downdated by a round of broken bonds: the words they changed, appended. */
cupid_status growth_journal_downdated(growth_run *g);
void growth_journal_free(growth_journal *j);
/** After load step @p k (its row written): a checkpoint when one is due; after a signal's,
 *  CUPID_ERR_INTERRUPTED (the run stops). */
cupid_status growth_safe_point(growth_run *g, int k);
/** --resume (after setup_run): the checkpoint's state into g and prob, the factor rebuilt from
 *  its journal, g->first_step the step after it. */
cupid_status growth_resume(growth_run *g);

#endif
