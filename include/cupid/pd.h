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
  /* A slab of a distributed grid (issue 6; dimension 3 only). parts <= 1: the whole union. */
  int parts;        /**< number of slabs (MPI ranks) the z layers are split into */
  int part;         /**< the slab this grid holds, 0 <= part < parts */
  int halo_layers;  /**< z layers kept on each side of the owned ones (see
                         cupid_pd_operator_halo_layers) */
  /** With parts > 1 and own_z[1] > own_z[0]: own the z layers between the planes own_z[0]
   *  and own_z[1] (cell faces, as cupid_pd_grid_partition reports them) instead of the
   *  balanced split: a second grid cut like another grid's slab (the extended grid of the
   *  fictitious-node coupling). */
  double own_z[2];
  /** Shapes (issue 35): NULL, or one per box, the box then its bounding box (a cylinder's or a
   *  sphere's cells are those whose centres lie in it; its bounds need not be on the lattice,
   *  which is anchored at the boxes' lowest corner when some region is a box); and holes,
   *  whose cells (centres) are removed from every box. */
  const cupid_shape *shapes;
  int n_holes;
  const cupid_shape *holes;
  /** 1: with shapes or holes (3D), each node's volume is the body's nearest it rather than
   *  the whole cell (`partial_volume: exact`; cupid_pd_grid_volume_fractions). */
  int cut_volumes;
  /** 1: the lattice's planes lie at anchor + k spacing (3D; the origin is the highest such
   *  plane at or below the lowest region bound), and a box's bounds need not lie on them: its
   *  cells are those whose centres lie in it. A grid that grows (issue 37: an adaptive zone)
   *  keeps its lattice, so that its nodes map onto the grown grid's
   *  (cupid_pd_grid_map_nodes). */
  int has_anchor;
  double anchor[3];
} cupid_pd_grid_options;

/* cupid_pd_grid_partition, where a grid sits in the whole union, is in solvers.h (the
 * Krylov solves over slabs read it too). */

/**
 * Build the grid of a union of boxes (or, with opts->parts > 1, one slab of it plus its halo:
 * cupid_pd_grid_partition; more parts than z layers is CUPID_ERR_MODEL): the lattice is anchored at the lowest corner of all
 * boxes, nodes sit at cell centres, a cell belongs to the union when its centre lies in
 * some box (first box wins for the material). Box bounds must lie on the lattice (error
 * names the box and bound otherwise), unless opts->has_anchor sets the lattice (then a box's
 * cells are those whose centres lie in it); with opts->shapes, a cylinder's or a sphere's cells are
 * those whose centres lie in it, and opts->holes remove theirs. @p materials gives one
 * material index per box.
 * Boxes with no node are an error. For dimension 1 only the y bounds are used.
 * Bound check tolerance 1e-9 h. Nodes are numbered lexicographically by cell (i, j, k)
 * with x fastest and z slowest. The bounding box may hold at most 2^31 cells (a dense
 * cell -> node index of 8 bytes per cell is kept for O(1) lookups).
 */
cupid_status cupid_pd_grid_create(const cupid_pd_grid_options *opts, int n_boxes,
                                  const cupid_box *boxes, const int *materials,
                                  cupid_pd_grid *grid);

/**
 * The grid of the model's `peridynamics:` regions (spacing, dimension, area; each region's
 * material, else the section's `material:`); errors name the region's file:line:col
 * through cupid_model_error(). Lives in its own object file (src/pd/grid_model.c).
 */
cupid_status cupid_pd_grid_create_from_model(const cupid_model_t *model, cupid_pd_grid *grid);

void cupid_pd_grid_destroy(cupid_pd_grid *grid);

cupid_int cupid_pd_grid_num_nodes(const cupid_pd_grid grid);
/** The grid's place in the whole union (a whole grid: itself). */
void cupid_pd_grid_get_partition(const cupid_pd_grid grid, cupid_pd_grid_partition *part);
/**
 * The slab of the model's grid for one MPI rank (see cupid_pd_grid_create and
 * cupid_pd_grid_partition); parts <= 1 gives the whole grid.
 */
cupid_status cupid_pd_grid_create_part_from_model(const cupid_model_t *model, int parts, int part,
                                                  int halo_layers, cupid_pd_grid *grid);
/** Node coordinates, 3 per node (x, y, z); for dimension 1, x = z = 0. */
const double *cupid_pd_grid_coords(const cupid_pd_grid grid);
/** Material index of each node. */
const int *cupid_pd_grid_materials(const cupid_pd_grid grid);
/**
 * map[i] = the node of @p to at the place of node i of @p from, or -1 where @p to has none;
 * both grids on one lattice (the same spacing, origins a whole number of spacings apart, to
 * 1e-9 of a spacing: else CUPID_ERR_ARGUMENT). With cupid_pd_operator_copy_broken_mapped(), a
 * grown grid's operator takes the bonds the old one lost.
 */
cupid_status cupid_pd_grid_map_nodes(const cupid_pd_grid from, const cupid_pd_grid to,
                                     cupid_int *map);
/** Cell volume (h^3, or area*h in 1D). */
double cupid_pd_grid_cell_volume(const cupid_pd_grid grid);
/**
 * The nodes' volumes over the cell volume, one per node, or NULL when every node has the
 * whole cell. With opts->cut_volumes on a shaped body (issue 35): a node has the body's volume
 * in its cell plus a share of the body's volume in the neighbouring cells that hold no node
 * (their centres outside), so that the volumes sum to the body's (src/pd/cut_volume.c). The
 * PD operator, masses, body loads and outputs take them.
 */
const double *cupid_pd_grid_volume_fractions(const cupid_pd_grid grid);
/** Volume of one node: the cell volume times its fraction. */
double cupid_pd_grid_node_volume(const cupid_pd_grid grid, cupid_int node);
/** The body's volume in cut cells with no node among their neighbours (given to none). */
double cupid_pd_grid_unassigned_volume(const cupid_pd_grid grid);
double cupid_pd_grid_spacing(const cupid_pd_grid grid);
int cupid_pd_grid_dimension(const cupid_pd_grid grid);
/** Node at integer lattice position (i, j, k), or -1 (in 1D pass i = k = 0). */
cupid_int cupid_pd_grid_node_at(const cupid_pd_grid grid, cupid_int i, cupid_int j, cupid_int k);
/** Lattice origin (the centre of cell (0,0,0) is origin + h/2 on each axis; in 1D the
 *  x and z origins are -h/2 so that x = z = 0). */
void cupid_pd_grid_origin(const cupid_pd_grid grid, double origin[3]);
/** Bounding box of the union: lowest corner and number of cells per axis. */
void cupid_pd_grid_extent(const cupid_pd_grid grid, cupid_int ncells[3]);
/** Lattice position (i, j, k) of a node (in 1D i = k = 0). */
void cupid_pd_grid_node_lattice(const cupid_pd_grid grid, cupid_int node, cupid_int ijk[3]);
/**
 * Interior flags: flags[i] = 1 when every lattice point within @p radius of node i
 * (|offset| h <= radius) is a node of the grid, i.e. node i is farther than @p radius
 * from the surface of the union; else 0. Useful to pick nodes with complete families
 * (radius delta for bond-based, 2 delta for LPS forces; with EXACT partial volumes the
 * family reaches delta + sqrt(3)/2 h).
 */
cupid_status cupid_pd_grid_interior(const cupid_pd_grid grid, double radius, unsigned char *flags);

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
  cupid_surface_correction surface_correction; /**< 0 = none (see create) */
} cupid_pd_operator_options;

/**
 * Families on the integer stencil (OpenMP), quadrature coefficients beta, influence omega,
 * weighted volumes m_i (Eq. 18) and material constants. No per-bond storage for nodes with a
 * full family (the bulk): their bonds are the stencil's; near-surface nodes store their
 * stencil entries (4 bytes a bond). About 60 bytes a node plus 4 per near-surface bond
 * (100^3 nodes at delta = 3.015 h: ~125 bytes a node).
 * LPS requires dimension 3 (CUPID_ERR_UNSUPPORTED otherwise); the 1D grid supports the
 * bond-based model (micromodulus below). A node without neighbours (horizon below the
 * spacing) or a material with E <= 0 or nu outside (-1, 0.5) is CUPID_ERR_MODEL.
 *
 * The grid is borrowed and must outlive the operator. Constants per node from its
 * material: K = E/(3(1-2nu)), mu = E/(2(1+nu)).
 *
 * LPS (paper 000 Eqs. 16-21, generalised to per-node constants, V the cell volume):
 *   m_i = sum_j omega x^2 beta V,  theta_i = 3/m_i sum_j omega x e_ij beta V,
 *   e_ij = n_ij.(u_j - u_i),
 *   (K u)_i = -sum_j beta V^2 omega [ (3K_i-5mu_i) x theta_i/m_i + (3K_j-5mu_j) x theta_j/m_j
 *                                     + 15 (mu_i/m_i + mu_j/m_j) e_ij ] n_ij,
 * the gradient of E = sum_i V [ (3K_i-5mu_i)/6 theta_i^2 + 15mu_i/(2m_i) sum_j omega e^2 beta V ].
 *
 * Bond-based micro-elastic (paper 004 section 2.2, linearised):
 *   (K u)_i = -sum_j c_ij omega beta V^2 (e_ij/x_ij) n_ij,  c_ij = (c_i + c_j)/2,
 * with the micromodulus calibrated on the discrete full family so that a uniform
 * dilatation (3D) or a uniform strain (1D) gives exactly the continuum energy in the
 * bulk: 3D c = 18 K / S, 1D c = 2 E / S, S = sum over the full stencil of omega x beta V
 * (continuum limit, constant omega: 18K/(pi delta^4) and 2E/(A delta^2), paper 004).
 * Bond-based PD has nu = 1/4 in 3D; other nu are accepted, K is taken from E and nu as
 * given (the shear response is then 3K/5, not mu). Energy: E = sum_i V/4 sum_j c_ij omega
 * beta V e_ij^2 / x_ij.
 *
 * Surface correction (surface_correction = CUPID_SURFACE_ENERGY, src/pd/surface.c): per-bond
 * factors D_ij = sum_k d_ik n_k^2 in theta_i and G_ij = sum_k (g_ik n_k^2 + q_ik n_k^4) on bond
 * j of node i's deviatoric sum (LPS: E = sum_i V [kappa_i/6 theta_i^2 + 15 mu_i/(2 m_i)
 * sum_j omega G_ij e^2 beta V], theta_i = 3/m_i sum_j omega D_ij x e beta V) or on the pair
 * energy (bond-based: c_ij times (G_ij + G_ji)/2), with each node's d, g, q fitted so that
 * theta_i and the node's energy are the continuum ones under every normal strain. Every operation
 * (apply, ranges, energy, stress, assembly, diagonal) uses the corrected energy: K stays
 * symmetric with the rigid modes in its null space. A factor that is not positive (a family
 * too truncated to fit) is CUPID_ERR_MODEL.
 */
cupid_status cupid_pd_operator_create(const cupid_pd_grid grid,
                                      const cupid_pd_operator_options *opts,
                                      cupid_pd_operator *op);
void cupid_pd_operator_destroy(cupid_pd_operator *op);

/** Total bonds (each ordered pair i->j counted once per direction), stored or not. */
cupid_int cupid_pd_operator_num_bonds(const cupid_pd_operator op);
/** Bonds of the nodes [first, last) (e.g. the owned nodes of a slab grid). */
cupid_int cupid_pd_operator_num_bonds_range(const cupid_pd_operator op, cupid_int first,
                                            cupid_int last);
/**
 * The z layers a slab of rows depends on beyond its own (issue 6): twice the stencil's reach
 * in z (LPS reads theta and m of every neighbour, each from the neighbour's family; the
 * surface factors likewise), for both models. A slab grid built with this halo
 * (cupid_pd_grid_options.halo_layers) gives, on its owned rows, exactly the operator of the
 * whole grid: apply_range, stress and diagonal of the owned nodes agree to round-off.
 */
cupid_status cupid_pd_operator_halo_layers(const cupid_pd_operator_options *opts, double h,
                                           int *layers);

/**
 * Matrix-free f = K u (3 entries per node; in 1D too, with x and z decoupled and zero). On the
 * stencil: runs of consecutive nodes sweep each stencil offset with contiguous SIMD loops
 * (src/pd/stencil.c; LPS two passes, dilatation then force). Keeps work arrays of 40 bytes
 * per cell of the padded bounding box between calls (one call at a time uses them; a
 * concurrent call allocates its own).
 */
cupid_status cupid_pd_operator_apply(const cupid_pd_operator op, const double *u, double *f);

/**
 * Rows [first, last) of K u: f has 3 (last - first) entries, u is indexed by global node but
 * only the nodes [lo, hi) of cupid_pd_operator_dependency_range() are read. The building block
 * of a distributed (MPI) or blocked matrix-free product; first = 0, last = nodes equals
 * cupid_pd_operator_apply().
 */
cupid_status cupid_pd_operator_apply_range(const cupid_pd_operator op, cupid_int first,
                                           cupid_int last, const double *u, double *f);

/**
 * The node range [*lo, *hi) that rows [first, last) of K u depend on (bond-based: the
 * families of the rows; LPS: two hops, since theta_j of every neighbour j is needed). Nodes
 * are numbered z slowest, so a slab of z layers depends on a slab widened by the reach.
 */
cupid_status cupid_pd_operator_dependency_range(const cupid_pd_operator op, cupid_int first,
                                                cupid_int last, cupid_int *lo, cupid_int *hi);

/**
 * Assemble K analytically in 3x3-block CSR (LPS couples nodes up to 2 delta apart):
 * K = K_pair + sum_p c_p g_p g_p^T, c_p = V (3K_p - 5mu_p)/3, g_p = d theta_p/dU.
 * OpenMP row-wise gather, O(nodes). *K is a new matrix (struct and arrays from
 * cupid_calloc/cupid_malloc, freed by cupid_csr_destroy).
 */
cupid_status cupid_pd_operator_assemble(const cupid_pd_operator op, cupid_csr *K);

/**
 * K of the node-weighted energy E_w = sum_p w_p E_p (E_p node p's share of the energy in
 * cupid_pd_operator_create: LPS its dilatation and deviatoric terms; bond-based half of each
 * of its bonds), i.e. the operator with node p's moduli scaled by w_p: the Arlequin weighting
 * of the PD energy (paper 004 Eq. 12) for state-based PD, where a bond-by-bond weighting does
 * not apply. Bond-based with one material: bond ij weighted by (w_i + w_j)/2. Symmetric, with
 * the rigid modes in its null space, for any w >= 0. The operator is modified during the call
 * and restored bit-exactly (not concurrently with other uses of @p op).
 */
cupid_status cupid_pd_operator_assemble_weighted(cupid_pd_operator op, const double *w,
                                                 cupid_csr *K);

/**
 * The rows of K of the given nodes only (row k of *K is node nodes[k]'s; ncols = nodes),
 * weighted by @p w as cupid_pd_operator_assemble_weighted(), or not (w = NULL). Each row is
 * the whole assembly's to the bit, so a caller that keeps K assembles again only the rows
 * that broken bonds changed (cupid_pd_operator_take_changed()).
 */
cupid_status cupid_pd_operator_assemble_node_rows(cupid_pd_operator op, const double *w,
                                                  const cupid_int *nodes, cupid_int n, cupid_csr *K);

/**
 * The nodes whose rows of K changed since the last call (bond-based: both ends of each bond
 * removed since), sorted and without repeats, into a new *nodes (cupid_free; NULL when none);
 * the record then starts again (the first call starts it: nothing is recorded before, so it
 * says *all = 1). *all = 1 when any row may have changed (LPS, whose broken bond
 * changes the rows of both its families' neighbours; moduli scaled; the record lost to a lack
 * of memory): assemble K whole.
 */
cupid_status cupid_pd_operator_take_changed(cupid_pd_operator op, cupid_int **nodes, cupid_int *n,
                                            int *all);

/**
 * Weight node p's energy by w_p from now on (w >= 0, one per node): the operator's per-node
 * moduli are scaled in place, so every later apply, apply_range and assembly is that of the
 * node-weighted energy of cupid_pd_operator_assemble_weighted() (the matrix-free Arlequin
 * operator, paper 004 Eq. 12). Calls multiply.
 */
cupid_status cupid_pd_operator_scale_energy(cupid_pd_operator op, const double *w);

/** Dilatation theta_i (Eq. 19) of a displacement field (LPS; 0 for bond-based). */
cupid_status cupid_pd_operator_dilatation(const cupid_pd_operator op, const double *u,
                                          double *theta);

/**
 * Nodal stress (6 per node: xx yy zz yz xz xy): LPS sum_j T_ij (x) xi_ij beta V_j (T from
 * Eq. 20); bond-based 1/2 sum_j f_ij (x) xi_ij beta V_j (f_ij the pair force density).
 * Exact (the continuum stress) for an affine field at nodes with a full family when the
 * stencil quadrature is isotropic (always for a dilatation).
 */
cupid_status cupid_pd_operator_stress(const cupid_pd_operator op, const double *u, double *sigma);

/** A full (uncut) family's sums over its bonds: *m = sum omega beta |xi|^2 V (its weighted
 *  volume) and *S = sum omega beta |xi| V (the bond-based micromodulus is c = 18 K / S), with
 *  the operator's influence function and partial volumes. */
void cupid_pd_operator_full_family(const cupid_pd_operator op, double *m, double *S);
/** Weighted volume m_i of each node (Eq. 18; also for bond-based). */
const double *cupid_pd_operator_weighted_volume(const cupid_pd_operator op);

/** Strain energy E(u) = u.K u / 2, evaluated from its own formula (see create). */
cupid_status cupid_pd_operator_energy(const cupid_pd_operator op, const double *u, double *energy);

/** The 3x3 diagonal blocks of K (9 per node, row-major), e.g. for block Jacobi. */
cupid_status cupid_pd_operator_diagonal(const cupid_pd_operator op, double *blocks);

/**
 * A guaranteed bound of K's rows for the stable step of explicit dynamics, without K: r (3 per
 * node, each of node i's DOFs the same value) >= sum_j |K_ij|_2 over the 3x3 blocks of row
 * block i (block Gershgorin: with a mass equal on a node's three DOFs, every eigenvalue of
 * M^-1 K is at most max_i r_i / m_i). From the intact bonds, in O(nodes x stencil), no
 * product of K. LPS: the pair term and the dilatation term bounded apart (|kappa| for
 * nu < 1/4, where 3K - 5mu < 0).
 */
cupid_status cupid_pd_operator_row_bound(const cupid_pd_operator op, double *r);

/** Predicted sizes of an operator and its assembled matrix (for `cupid check`). */
typedef struct {
  cupid_int nodes;
  cupid_int bonds;        /**< exact: stored bonds (both directions) */
  cupid_int blocks;       /**< 3x3 blocks of the assembled K: exact for bond-based, an
                               upper bound for LPS (lattice points within two stencil hops;
                               equal on boxes) */
  int64_t bytes_operator; /**< near-surface bonds + per-node data of the operator */
  int64_t bytes_matrix;   /**< rowptr + col + val of the assembled K */
} cupid_pd_estimate;

/** Count bonds and matrix blocks without building the operator (O(nodes x stencil)). */
cupid_status cupid_pd_operator_estimate(const cupid_pd_grid grid,
                                        const cupid_pd_operator_options *opts,
                                        cupid_pd_estimate *est);

/**
 * Quadrature coefficient beta of the cell (cube of side h) centred at offset (dx,dy,dz)
 * from a node, with r = |offset|:
 *  - NONE: 1 if r <= delta (+1e-12 h), else 0;
 *  - PDLAMMPS (Parks et al.): 1 for r <= delta - h/2, (delta + h/2 - r)/h up to delta,
 *    0 beyond delta (bonds beyond delta are dropped);
 *  - EXACT: the fraction of the cell inside the ball of radius delta about the node
 *    (analytic over the disk-rectangle section, tanh-sinh quadrature along the third
 *    axis, ~1e-13 absolute); includes cells whose centre lies beyond delta.
 * The result is exactly invariant under sign changes and permutations of the offset.
 */
double cupid_pd_partial_volume(cupid_partial_volume rule, double dx, double dy, double dz,
                               double h, double delta);

/** The same in 1D: for EXACT the fraction of [d - h/2, d + h/2] inside [-delta, delta]. */
double cupid_pd_partial_volume_1d(cupid_partial_volume rule, double d, double h, double delta);

/** Influence omega(|xi|). */
double cupid_pd_influence(cupid_influence kind, double r, double delta);


/* ---- Fracture (src/pd/fracture.c; docs/theory.md, section Fracture) ----
 * Bonds removed before a run (pre-cracks) or broken by a criterion during one leave every
 * operation of the operator: apply (both paths), ranges, assembly, diagonal, energy, stress;
 * the weighted volumes m are those of the intact families. Irreversible. Not with a surface
 * correction (CUPID_ERR_UNSUPPORTED). Not thread-safe against a concurrent apply. */

/** A pre-crack: the rectangle lo[b] <= x_b <= hi[b] (b != normal) on the plane
 *  x_normal = at. */
typedef struct {
  int normal;          /**< 0 x, 1 y, 2 z */
  double at;
  double lo[3], hi[3]; /**< bounds of the two other axes (the normal's entries are unused) */
} cupid_pd_precrack;

/**
 * Remove every bond whose segment crosses the rectangle (its ends strictly on opposite sides
 * of the plane, or one on the plane and the other on the positive side; the crossing point
 * within the bounds, inclusive). *removed = bonds (unordered pairs) removed by this call.
 */
cupid_status cupid_pd_operator_precrack(cupid_pd_operator op, const cupid_pd_precrack *crack,
                                        cupid_int *removed);
/** The bonds of the stencil (unordered pairs, removed or not) that cross the rectangle as
 *  cupid_pd_operator_precrack() counts crossing: > 0 where a pre-crack that removed nothing
 *  lies over bonds an earlier one removed. */
cupid_status cupid_pd_operator_precrack_crossing(const cupid_pd_operator op,
                                                 const cupid_pd_precrack *crack, cupid_int *count);

typedef enum {
  CUPID_PD_BREAK_STRETCH = 0, /**< e / |xi| > critical_stretch (linearised stretch) */
  CUPID_PD_BREAK_ENERGY = 1   /**< LPS: 1/4 |t_ij + t_ji| |e| > critical_energy */
} cupid_pd_break_criterion;

/** What breaks and what may not. */
typedef struct {
  cupid_pd_break_criterion criterion;
  double critical_stretch;       /**< s0 > 0 (stretch), unless node_stretch is given */
  const double *node_stretch;    /**< per node s0 (e.g. from G0 and each node's material), or
                                      NULL; a bond's limit is the smaller of its ends' (LAMMPS) */
  double critical_energy;        /**< w_c > 0 (energy): 4 G0 / (pi delta^4) in 3D */
  const unsigned char *protect;  /**< per node: 1 = no bond of this node breaks; or NULL */
  const uint32_t *no_fail;       /**< per node: bit b = inside no-fail box b; a bond whose ends
                                      share a bit never breaks; or NULL */
  double *ku;                    /**< optional: K u at the u of break_bonds (3 per node). For
                                      the bond-based model break_bonds subtracts the forces of
                                      the bonds it breaks (an explicit step then needs no new
                                      product); LPS leaves it (a break changes the dilatations
                                      of both families: recompute). */
  cupid_int count_first, count_last; /**< a slab of a distributed grid: *broken counts the
                                      bonds whose lower node is in [count_first, count_last),
                                      *dissipated the energies of those nodes; 0, 0: all */
  int owned_only;                /**< decide only the bonds whose lower node is counted: their
                                      owner decides, and cupid_pd_operator_unpack_broken()
                                      brings the others (a criterion that reads dilatations,
                                      which a slab's outer halo does not have right) */
  double most_top;               /**< only_most on a slab: the largest ratio (max_ratio's) over
                                      every rank, so that near-ties are judged against the
                                      whole grid's; 0: this operator's own */
} cupid_pd_fracture_options;

/** only_most's near-ties: bonds whose ratios are within this fraction of the largest are
 *  equal, and the first (lowest lower node, then stencil entry) breaks. A symmetric model has
 *  mirror bonds whose ratios differ by round-off alone, and different solvers' round-off would
 *  otherwise pick different mirrors (the direct and PETSc paths differ by ~1e-10). */
#define CUPID_PD_TIE 1e-8

/**
 * Break every intact bond over its limit at u (only_most: only the one furthest over it,
 * relative to its limit), a bond at exactly its limit holding. The set depends on u alone,
 * not on the thread count. *broken = bonds broken, *dissipated = the strain energy they
 * held (the drop of E(u) the breaks cause).
 */
cupid_status cupid_pd_operator_break_bonds(cupid_pd_operator op, const double *u,
                                           const cupid_pd_fracture_options *opts, int only_most,
                                           cupid_int *broken, double *dissipated);

/** Words per node (32-bit integers held in doubles, exact) of the broken-bond bits a node
 *  owns: its stencil entries towards higher node indices (each bond once). */
int cupid_pd_operator_broken_words(const cupid_pd_operator op);
/** The bits of the nodes [first, last) into words (broken_words per node). */
void cupid_pd_operator_pack_broken(const cupid_pd_operator op, cupid_int first, cupid_int last,
                                   double *words);
/** Break the bonds of the nodes [first, last) that @p words (as packed) mark and this
 *  operator still has: *added of them, *dissipated the energy they held at u on the counted
 *  nodes of @p opts (a slab receiving the decisions of the ranks that own those nodes). */
cupid_status cupid_pd_operator_unpack_broken(cupid_pd_operator op, cupid_int first,
                                             cupid_int last, const double *words,
                                             const double *u, const cupid_pd_fracture_options *opts,
                                             cupid_int *added, double *dissipated);

/** Remove from @p dst every bond removed from @p src that it still has (both operators on one
 *  grid with the same stencil: e.g. a weighted copy of the operator). */
cupid_status cupid_pd_operator_copy_broken(cupid_pd_operator dst, const cupid_pd_operator src);
/** As cupid_pd_operator_copy_broken() onto an operator on another grid of the same lattice
 *  spacing and stencil: the bond of @p src's node i at stencil entry s is the bond of node
 *  map[i] of @p dst at the same entry (e.g. a fictitious-node coupling's extended grid, whose
 *  real nodes are the model grid's: cupid_coupling_operator_pd). A bond whose other end does
 *  not map onto dst's neighbour is an ARGUMENT error. @p map NULL: one grid, as copy_broken. */
cupid_status cupid_pd_operator_copy_broken_mapped(cupid_pd_operator dst, const cupid_pd_operator src,
                                                  const cupid_int *map);

/** The largest ratio of an intact, breakable bond's criterion to its limit at u (stretch:
 *  e / (s0 |xi|); energy: sqrt(w / w_c), both linear in u): a linear solution scaled by
 *  1 / ratio brings the first bond exactly to its limit. 0 when no bond is stretched. With
 *  opts->owned_only, the bonds whose lower node is counted (a slab's share). */
cupid_status cupid_pd_operator_max_ratio(const cupid_pd_operator op, const double *u,
                                         const cupid_pd_fracture_options *opts, double *ratio);

/** The bonds over their limit at u that only the protection (opts->protect: a coupling zone)
 *  keeps from breaking (no-fail boxes excluded): *count of them, *node the protected end of the
 *  one most over (-1: none), *ratio its ratio (the largest among such bonds, over 1 or not). */
cupid_status cupid_pd_operator_blocked(const cupid_pd_operator op, const double *u,
                                       const cupid_pd_fracture_options *opts, cupid_int *count,
                                       cupid_int *node, double *ratio);

/** Per node, the largest ratio (stretch criterion) over its intact bonds that only the
 *  protection keeps from breaking (as cupid_pd_operator_blocked() reads them): 0 for a node
 *  that opts->protect does not protect or that has no such bond. One entry per node of op. */
cupid_status cupid_pd_operator_protected_ratios(const cupid_pd_operator op, const double *u,
                                                const cupid_pd_fracture_options *opts,
                                                double *ratio);

/**
 * Nodes that lost their support: those with at most 2 intact bonds (a mechanism; Peridigm's
 * rule) and those that no @p anchored node (a node with a constrained DOF, or tied to a beam)
 * reaches over intact bonds (a fragment cut off). @p release: one flag per node, nonzero on
 * entry for nodes released before (left alone); newly released ones are set to 2 and counted
 * in *count. A static solve holds released nodes instead of going singular.
 */
cupid_status cupid_pd_operator_unsupported(const cupid_pd_operator op, const unsigned char *anchored,
                                           unsigned char *release, cupid_int *count);

/** The first check of cupid_pd_operator_unsupported() on nodes [first, last) alone: those
 *  whose intact bonds no longer hold them in every direction get release = 2 (*count: how
 *  many). A slab of a distributed grid decides its owned nodes (their families are whole). */
cupid_status cupid_pd_operator_weakly_held(const cupid_pd_operator op, cupid_int first,
                                           cupid_int last, unsigned char *release,
                                           cupid_int *count);

/** The second: from every node with seen = 1 and release = 0, mark seen = 1 on each node
 *  with release = 0 that it reaches over intact bonds (*added: how many were new). On a slab,
 *  rounds of this and an exchange of the flags between ranks find what the whole grid would. */
cupid_status cupid_pd_operator_reach(const cupid_pd_operator op, const unsigned char *release,
                                     unsigned char *seen, cupid_int *added);

/** The share of a node's bond weight lost from which it counts as damaged in the search for
 *  mechanisms (cupid_pd_operator_mechanisms(); crack growth's damaged nodes' block too). */
#define CUPID_PD_MECHANISM_DAMAGE 0.5

/**
 * Mechanisms of a few nodes that cupid_pd_operator_weakly_held() does not see (each node held in
 * every direction by its own bonds, the cluster free to move): the nodes in [first, last) that
 * lost at least half of their bonds (by weight), grouped over intact bonds into clusters; each
 * cluster of at most 48 nodes is tested with everything outside it fixed (Cholesky of its bond
 * block), and in a larger one (a crack face's band) a ball of 48 of its nodes around each node
 * whose lost share differs from @p seen (every node of the band where @p seen is NULL), grown
 * over intact bonds the most damaged first. Where a cluster is a mechanism, the node that
 * completes it in the order of largest |u| first (@p u: the displacements, or NULL for the
 * node order) gets release = 2 (*count: how many), and the rest is tested again. Released
 * nodes count as fixed. @p seen (optional, one per node): each node's lost share at the last
 * call, updated to the present ones (cupid_pd_operator_lost_shares fills it anew). Crack growth
 * ties the nodes marked by weak springs before a downdate or a factorisation breaks down on
 * them (src/pd/fracture.c, "Mechanisms"; src/problem/growth.c, "Ties").
 */
cupid_status cupid_pd_operator_mechanisms(const cupid_pd_operator op, cupid_int first,
                                          cupid_int last, const double *u, double *seen,
                                          unsigned char *release, cupid_int *count);

/** share[i] for i in [first, last): the share of node i's bond weight that is broken (0 where
 *  no bond of it broke), as cupid_pd_operator_mechanisms() compares them. */
void cupid_pd_operator_lost_shares(const cupid_pd_operator op, cupid_int first, cupid_int last,
                                   double *share);

/** out[j] = 1 for every node j in the family (the stencil's neighbours present, bonds intact
 *  or not) of a node i with mark[i] != 0; other entries of @p out are left as they are. The
 *  family is symmetric, so j is flagged exactly when a marked node is in j's family. */
void cupid_pd_operator_mark_families(const cupid_pd_operator op, const unsigned char *mark,
                                     unsigned char *out);

/** Bonds (unordered pairs) removed so far: pre-cracks and breaks. */
cupid_int cupid_pd_operator_num_broken(const cupid_pd_operator op);

/** Nodes that lost a bond to breaking (cupid_pd_operator_break_bonds; pre-cracks aside);
 *  with @p nodes (room for every node), their indices, ascending. */
cupid_int cupid_pd_operator_nodes_broken(const cupid_pd_operator op, cupid_int *nodes);

/** 1 if nodes i and j are bonded and the bond is intact; 0 otherwise. */
int cupid_pd_operator_bond_intact(const cupid_pd_operator op, cupid_int i, cupid_int j);

/**
 * Damage per node: 1 - sum over intact bonds of beta V / sum over all its bonds of beta V;
 * *damaged = nodes with at least one bond removed, *max_damage the largest (both optional).
 */
cupid_status cupid_pd_operator_damage(const cupid_pd_operator op, double *damage,
                                      cupid_int *damaged, double *max_damage);

/* ---- Distributed solves (issue 6): owned-row assembly of a preconditioner, matrix-free PETSc
 * solve. Appended by the PETSc engine (src/pd/assemble_rows.c, src/solvers/petsc.c). ---- */

/**
 * Rows [first, last) (nodes) of a short-range bond-based stiffness on the grid's lattice: bonds
 * to every node at lattice offset |o| h <= radius (radius in length units, e.g. 1.5 h: faces and
 * edges), K_ij = -c_ij (V^2 / |xi|) n n^T, K_ii = -sum_j K_ij, c_ij = (E_i + E_j)/2. Not the
 * model's operator: an SPD (once constrained) spectrally close approximation of it, cheap to
 * assemble (19 blocks per row at 1.5 h), used as the matrix GAMG coarsens for the matrix-free
 * solve. *K: nrows = last - first, ncols = nodes, bs = 3; materials gives E per material index.
 * Dimension 3 only (CUPID_ERR_UNSUPPORTED otherwise).
 */
cupid_status cupid_pd_assemble_rows_bond(const cupid_pd_grid grid, const cupid_pd_material *materials,
                                         double radius, cupid_int first, cupid_int last,
                                         cupid_csr *K);

/** The PD operator as a node operator for the matrix-free PETSc solve (solvers.h,
 *  cupid_petsc_solve_nodes): its products and diagonal, and the bond-based rows of radius r of
 *  @p materials as the preconditioner's. The three objects are borrowed. */
void cupid_pd_node_operator(const cupid_pd_operator op, const cupid_pd_grid grid,
                            const cupid_pd_material *materials, cupid_node_operator *A);
/* ---- end of the distributed-solve block ---- */

#ifdef __cplusplus
}
#endif
#endif
