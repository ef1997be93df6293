/**
 * @file pd.h
 * @brief Peridynamics on uniform grids (paper 000, section 2; paper 004, section 2.2):
 *        the grid of nodes at cell centres, neighbour lists with partial volumes and
 *        influence, the linearised LPS and bond-based operators (matrix-free and
 *        assembled in 3x3-block CSR), nodal stress.
 *
 * Sign convention: the operator returns f = K u, the force the body resists with; at
 * static equilibrium K u = F_ext (paper 000 Eqs. 21-22, both sides multiplied by V_i).
 */
#ifndef CUPID_PD_H
#define CUPID_PD_H

#include "cupid/base.h"
#include "cupid/model.h"
#include "cupid/solvers.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cupid_pd_grid_private *cupid_pd_grid;
typedef struct cupid_pd_operator_private *cupid_pd_operator;

/** Parameters of a grid, usually taken from the model's `peridynamics:` section. */
typedef struct {
  double spacing;   /**< h */
  int dimension;    /**< 3 or 1 (a bar along y) */
  double area;      /**< dimension 1: cross-section area (cell volume = area * h) */
} cupid_pd_grid_options;

/**
 * Build the grid of a union of boxes: the lattice is anchored at the lowest corner of all
 * boxes, nodes sit at cell centres, a cell belongs to the union when its centre lies in
 * some box (first box wins for the material). Box bounds must lie on the lattice (error
 * names the box and bound otherwise). @p materials gives one material index per box.
 * Boxes with no node are an error. For dimension 1 only the y bounds are used.
 */
cupid_status cupid_pd_grid_create(const cupid_pd_grid_options *opts, int n_boxes,
                                  const cupid_box *boxes, const int *materials,
                                  cupid_pd_grid *grid);

/** The grid of the model's `peridynamics:` regions; errors are reported against the file. */
cupid_status cupid_pd_grid_create_from_model(const cupid_model_t *model, cupid_pd_grid *grid);

void cupid_pd_grid_destroy(cupid_pd_grid *grid);

cupid_int cupid_pd_grid_num_nodes(const cupid_pd_grid grid);
/** Node coordinates, 3 per node (x, y, z); for dimension 1, x = z = 0. */
const double *cupid_pd_grid_coords(const cupid_pd_grid grid);
/** Material index of each node. */
const int *cupid_pd_grid_materials(const cupid_pd_grid grid);
/** Cell volume (h^3, or area*h in 1D). */
double cupid_pd_grid_cell_volume(const cupid_pd_grid grid);
double cupid_pd_grid_spacing(const cupid_pd_grid grid);
int cupid_pd_grid_dimension(const cupid_pd_grid grid);
/** Node at integer lattice position (i, j, k), or -1 (in 1D pass i = k = 0). */
cupid_int cupid_pd_grid_node_at(const cupid_pd_grid grid, cupid_int i, cupid_int j, cupid_int k);
/** Lattice origin (the centre of cell (0,0,0) is origin + h/2 on each axis). */
void cupid_pd_grid_origin(const cupid_pd_grid grid, double origin[3]);
/** Bounding box of the union: lowest corner and number of cells per axis. */
void cupid_pd_grid_extent(const cupid_pd_grid grid, cupid_int ncells[3]);

/** Constitutive data per material, given by index. */
typedef struct {
  double E, nu;
} cupid_pd_material;

typedef struct {
  double horizon;                       /**< delta */
  cupid_pd_model_kind model;            /**< LPS or bond-based */
  cupid_influence influence;
  cupid_partial_volume partial_volume;
  const cupid_pd_material *materials;   /**< indexed by the grid's material indices */
  int n_materials;
} cupid_pd_operator_options;

/**
 * Neighbour lists (cell-list / integer-stencil search, OpenMP), quadrature coefficients
 * beta, influence omega, weighted volumes m_i (Eq. 18) and material constants.
 * LPS requires dimension 3; the 1D grid supports the bond-based model
 * (micromodulus 2E/(A delta^2) for constant influence).
 */
cupid_status cupid_pd_operator_create(const cupid_pd_grid grid,
                                      const cupid_pd_operator_options *opts,
                                      cupid_pd_operator *op);
void cupid_pd_operator_destroy(cupid_pd_operator *op);

/** Total bonds stored (each ordered pair i->j counted once per direction). */
cupid_int cupid_pd_operator_num_bonds(const cupid_pd_operator op);

/** Matrix-free f = K u (3 entries per node; in 1D too, with x and z decoupled and zero). */
cupid_status cupid_pd_operator_apply(const cupid_pd_operator op, const double *u, double *f);

/** Assemble K analytically in 3x3-block CSR (LPS couples nodes up to 2 delta apart). */
cupid_status cupid_pd_operator_assemble(const cupid_pd_operator op, cupid_csr *K);

/** Dilatation theta_i (Eq. 19) of a displacement field (LPS; 0 for bond-based). */
cupid_status cupid_pd_operator_dilatation(const cupid_pd_operator op, const double *u,
                                          double *theta);

/** Nodal stress (6 per node: xx yy zz yz xz xy) = sum_j T_ij (x) xi_ij beta V_j. */
cupid_status cupid_pd_operator_stress(const cupid_pd_operator op, const double *u, double *sigma);

/** Quadrature coefficient beta of the cell centred at offset (dx,dy,dz) from a node. */
double cupid_pd_partial_volume(cupid_partial_volume rule, double dx, double dy, double dz,
                               double h, double delta);

/** Influence omega(|xi|). */
double cupid_pd_influence(cupid_influence kind, double r, double delta);

#ifdef __cplusplus
}
#endif
#endif
