/* The solver engines as a table (solvers.h, cupid_solver_type): the direct engine
 * (SuiteSparse: CHOLMOD for SPD systems, UMFPACK otherwise; src/solvers/direct.c), the built-in
 * iterative engine `krylov` (matrix-free CG/GMRES preconditioned by a SuiteSparse factor of
 * the cheap twin, iterative.c; one process) and the PETSc engine (Krylov on assembled
 * matrices, petsc.c; matrix-free Krylov, krylov.c; MPI). The only place that maps an engine's
 * name or kind to its functions. */
#include <string.h>

#include "cupid/model.h"
#include "cupid/solvers.h"

static int always(void) { return 1; }
static cupid_status nothing_to_start(void) { return CUPID_SUCCESS; }

/* The direct engine ignores the hints (they serve PETSc's multigrid). */
static cupid_status direct_solve_matrix(const cupid_csr_t *K, cupid_matrix_kind kind,
                                        const double *f, const cupid_dirichlet_t *bc, double *u,
                                        const cupid_petsc_options *hints, cupid_solve_info *info) {
  (void)hints;
  return cupid_direct_solve(K, kind, f, bc, u, info);
}

static cupid_status petsc_start(void) {
  return cupid_petsc_initialize(0, NULL); /* no-op when the CLI did it (mpirun) */
}

static const cupid_solver_type engines[] = {
    {.name = "direct",
     .kind = CUPID_SOLVER_DIRECT,
     .iterative = 0,
     .distributed = 0,
     .available = always,
     .start = nothing_to_start,
     .solve_matrix = direct_solve_matrix,
     .solve_nodes = NULL,
     .solve_operator = NULL},
    {.name = "krylov",
     .kind = CUPID_SOLVER_KRYLOV,
     .iterative = 1,
     .distributed = 0,
     .available = always,
     .start = nothing_to_start,
     .solve_matrix = direct_solve_matrix, /* an assembled system: the factorisation */
     .solve_nodes = NULL,
     .solve_operator = cupid_iterative_solve},
    {.name = "petsc",
     .kind = CUPID_SOLVER_PETSC,
     .iterative = 1,
     .distributed = 1,
     .available = cupid_petsc_available,
     .start = petsc_start,
     .solve_matrix = cupid_petsc_solve,
     .solve_nodes = cupid_petsc_solve_nodes,
     .solve_operator = cupid_krylov_solve},
};

const cupid_solver_type *cupid_solver_type_get(int kind) {
  for (size_t k = 0; k < sizeof engines / sizeof *engines; k++)
    if (engines[k].kind == kind) return &engines[k];
  return NULL;
}

const cupid_solver_type *cupid_solver_type_at(int k) {
  return k >= 0 && (size_t)k < sizeof engines / sizeof *engines ? &engines[k] : NULL;
}

const cupid_solver_type *cupid_solver_type_find(const char *name) {
  for (size_t k = 0; name && k < sizeof engines / sizeof *engines; k++)
    if (!strcmp(engines[k].name, name)) return &engines[k];
  return NULL;
}
