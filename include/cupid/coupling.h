/**
 * @file coupling.h
 * @brief PD-CUF coupling: a CUF beam with embedded peridynamic regions, joined by the
 *        improved coupling with fictitious nodes of paper 000, section 4 (Eqs. 29-38).
 *
 * Geometry. One CUF beam (axis y) and PD regions (boxes). Where a region lies inside the beam,
 * the beam gives way: the (beam element, section element) pairs inside the region's box are
 * made inactive (cupid_coupling_deactivate()). Region y bounds must be beam-element ends.
 * A region may span the whole cross-section (interfaces normal to the axis only, e.g. the
 * coupled bar) or part of it (LE only; interfaces parallel to the axis too, e.g. a C-beam web
 * or a panel stringer: paper 000 section 4.4, see "Partial-section regions" below).
 *
 * Fictitious PD nodes (section 4.2). One PD grid holds the real nodes and, inside the beam,
 * fictitious nodes up to 2 delta (rounded up to whole spacings) beyond every interface: LPS
 * couples nodes 2 delta apart. Its stiffness is assembled once; the rows of real nodes are
 * kept and the fictitious columns are replaced by u_f = I^{f-PD} u_FE (Eqs. 29-30, the CUF
 * expansion at the node, cupid_cuf_shape_at()).
 *
 * Fictitious FE elements (sections 4.1, 4.3). At every interface plane y_I a fictitious beam
 * element (the same cross-section) reaches into the region: by default the beam element the
 * region removed next to y_I (its type and length Delta l: section 4.1 puts the fictitious FE
 * node one element length from the interface); cupid_fictitious_fe lists the others (the h/2
 * B2 element to the nearest PD plane, cupid's form before issue 18, among them). Each of its
 * nodes in the region takes U^{fs-FE} = [A I^{fs-PD}]^{-1} A U^PD (Eqs. 31-35) over the real
 * PD nodes of a PD plane: I^{fs-PD}_{q,tau} = F_tau(x_q, z_q), A the weighted average of Eq. 33
 * (weights |N_i F_tau|); between two planes the two fits interpolated linearly, within h/2 of
 * a region face extrapolated from the two outermost planes. Its element stiffness adds the
 * real-real block to the interface FE rows and the fictitious columns, through I^{f-FE}, to PD
 * columns (Eq. 38); the rows of the fictitious DOFs are dropped (they would be FE forces in
 * the PD region). Every form is exact for the affine fields of the patch test.
 *
 * Partial-section regions (section 4.4, Remarks 1-2, Eq. 37). The region's x/z bounds must be
 * section-element edges (no element cut); the section elements inside its x/z box give way over
 * its y range, the others stay active. A TE expansion spans the whole section and cannot lose
 * a part: a partial region on a TE beam is CUPID_ERR_MODEL. When any region is partial, every
 * region is coupled as follows (src/coupling/partial.c):
 * - fictitious PD nodes at every lattice position within 2 delta of the region's box, on any
 *   side, that lies in an active part of the beam (Eq. 29; positions outside the section are
 *   free surface and get no node). The layer is built from the section elements' bounding
 *   boxes, so section elements are assumed rectangular (axis-aligned); a lattice position in
 *   a box but outside a skewed element is reported as outside the beam's active part;
 * - the fictitious FE elements are the removed (beam element, section element) pairs
 *   themselves: their nodes still used by an active pair are the real FE nodes (Eq. 37: nodes
 *   on the surface of real elements take the real FE field; a node shared by several sections
 *   has one value, Remark 1), their other nodes lie in the PD region and take the trilinear
 *   interpolation of the 8 real PD nodes around the node's point (for LE the node value is the
 *   displacement at that point: Eq. 31 solved node by node; a PD node feeds every fictitious
 *   node around it, Remark 2). The rows of real FE nodes get the removed pairs' stiffness, real
 *   columns on FE DOFs and fictitious ones through the interpolation (Eq. 38).
 *   Deviation from the paper: the fictitious elements are the removed section elements (their
 *   size) instead of h/2-thick elements ending on the nearest PD plane, and the section fit of
 *   Eqs. 33-35 is replaced by the nodal interpolation, which is exact for affine fields (patch
 *   test) and needs no [A I] inverse. A removed pair whose nodes are all real (B2 with one
 *   beam element across the region and no section node inside) is plain FE: the FE side then
 *   does not feel the PD region; use B3/B4 or several elements across the region.
 *
 * The coupled matrix (Eq. 38) is not symmetric; it is bs = 3 block CSR over
 * [3 DOFs per real PD node | FE DOFs], the FE DOFs starting at block n_pd (the beam's DOF
 * offset must be 3 n_pd). FE nodes used by no active pair keep an empty row but for a zero
 * diagonal block and must be fixed by the caller (cupid_cuf_node_used()).
 */
#ifndef CUPID_COUPLING_H
#define CUPID_COUPLING_H

#include "cupid/base.h"
#include "cupid/cuf.h"
#include "cupid/model.h"
#include "cupid/pd.h"
#include "cupid/solvers.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A built coupling (opaque). */
typedef struct cupid_coupling_private *cupid_coupling_h;

/**
 * The fictitious FE element at an interface normal to the axis (regions spanning the section;
 * paper 000 sections 4.1 and 4.3, docs/coupling.md "The fictitious FE element"). Its node on the
 * interface is the real FE node; its other nodes lie in the PD region and take the section fit
 * of Eqs. 33-35 of the PD field at their sections (the fits of the two PD planes around a
 * section interpolated linearly, extrapolated within h/2 of a region face). Every kind is
 * exact for affine fields (the patch test).
 */
typedef enum {
  /** Default. The beam element the region removed next to the interface, i.e. the full-FE
   *  mesh continued into the region: section 4.1, "the fictitious FEM node is positioned at a
   *  distance Delta l (the FE length) from the interface". Its nodes inside the region are
   *  fictitious, the far one too when it lies on the region's other face (one element across
   *  the region: the PD field extrapolated there, not the real FE node of the other
   *  interface). The removed pairs are also the fictitious elements of partial regions. */
  CUPID_FICTITIOUS_FE_REMOVED = 0,
  /** A copy of the real beam element next to the interface on the beam's side (its type and
   *  length Delta l) laid into the region, capped at the region's far face: section 4.1 with
   *  Delta l the length of the coupled model's own FEs. */
  CUPID_FICTITIOUS_FE_ADJACENT = 1,
  /** A B2 element from the interface to the nearest plane of real PD nodes, h/2 away
   *  (section 4.3 and Fig. 6 read literally; cupid's only form before issue 18). */
  CUPID_FICTITIOUS_FE_PLANE = 2,
  /** A B2 element of length cupid_coupling_options.fictitious_length, capped at the region's
   *  far face (studies). */
  CUPID_FICTITIOUS_FE_LENGTH = 3
} cupid_fictitious_fe;

/** What the coupling needs besides the beam and the real PD grid. */
typedef struct {
  const cupid_beam *beam_def;          /**< the beam's definition (for fictitious elements) */
  const cupid_material *materials;     /**< the model's material table */
  int n_materials;
  int n_regions;
  const cupid_box *regions;            /**< PD region boxes */
  const int *region_materials;         /**< material index per region */
  double spacing;                      /**< PD grid spacing h */
  cupid_pd_operator_options pd;        /**< the PD operator of the real grid */
  /** The fictitious FE element at interfaces normal to the axis (0: the default, REMOVED;
   *  the model's coupling.fictitious_fe: removed | adjacent | plane | a length). Regions over
   *  part of the section (partial.c) always use the removed pairs. */
  cupid_fictitious_fe fictitious_fe;
  double fictitious_length;            /**< CUPID_FICTITIOUS_FE_LENGTH only */
  /** The real grid's PD operator to assemble from, its removed bonds (pre-cracks, breaks)
   *  included (borrowed; NULL: the coupling builds its own from @p pd). Read by the Lagrange
   *  coupling; the fictitious-node one builds its operator on the extended grid. */
  cupid_pd_operator pd_operator;
} cupid_coupling_options;

/** Counts, for summaries. */
typedef struct {
  cupid_int n_real_pd;         /**< real PD nodes */
  cupid_int n_fictitious_pd;   /**< fictitious PD nodes (inside the beam) */
  int n_interfaces;            /**< interface planes (one fictitious FE element each); with
                                    partial regions: region faces with fictitious PD nodes */
  cupid_int n_fictitious_fe;   /**< fictitious FE nodes (section DOF groups of those elements;
                                    with partial regions: removed-pair nodes inside PD) */
  cupid_fictitious_fe fictitious_fe; /**< the fictitious FE element used (full-section regions) */
} cupid_coupling_info;

/**
 * Make inactive every (beam element, section element) pair inside a PD region. Errors
 * (CUPID_ERR_MODEL, message naming region index and the boundary to move): a y bound that is
 * not a beam-element end, a region outside the beam's y range; for a region over part of the
 * section: a TE beam, an x/z bound that is not a section-element edge, a box cutting a section
 * element, a box holding no section element.
 */
cupid_status cupid_coupling_deactivate(cupid_cuf_beam beam, int n_regions,
                                       const cupid_box *regions);

/**
 * Build the fictitious nodes and elements and the coupled matrix *K (Eq. 38). The beam must
 * have been deactivated and its DOF offset set to 3 * (real PD nodes). @p grid is the grid of
 * the real PD nodes (borrowed).
 */
cupid_status cupid_coupling_create(cupid_cuf_beam beam, cupid_pd_grid grid,
                                   const cupid_coupling_options *opts, cupid_coupling_h *c,
                                   cupid_csr *K);

/**
 * The Lagrange-multiplier coupling (Pagani & Carrera 2020, the baseline of paper 000 section
 * 5.1; cuf.md section 7), solved by elimination. Every real PD node q of the layer nearest a
 * face of its region (h/2 inside) whose mirror image across the face lies in an active part of
 * the beam is tied to the CUF field at its interface point p_q (q's coordinate normal to that
 * face moved onto the face; a node in an edge or corner layer of two or three such faces lands
 * on the edge or corner): u_q = sum_n w_n(p_q) u_n (cupid_cuf_shape_at()). Faces normal to the
 * axis (y bounds: the full-section bar, p_q = (x_q, y_I, z_q)) and parallel to it (x/z bounds of
 * a region over part of an LE section: the C-beam web, the panel's stringers) are treated
 * alike; a face on the beam's outer surface or against another PD region ties nothing.
 * Eliminating the constraints (u = T [u_m; u_FE]) gives the symmetric positive definite
 * K = T^T diag(K_PD, K_FE) T, identical to the saddle-point solution; the multipliers are the
 * reactions of the tied nodes. The PD grid holds the real nodes only (no fictitious nodes):
 * the truncated families at the interfaces and the h/2 offset of the tied layer cause the
 * distortions paper 000 reports. *K has the layout of cupid_coupling_create(); the rows and
 * columns of tied PD nodes are empty but for a zero diagonal block: fix their DOFs
 * (cupid_coupling_tied()) and fill them after the solve with cupid_coupling_recover(); loads on
 * them go to the beam with cupid_coupling_lagrange_load(). info.n_interfaces counts the region
 * faces with tied nodes. A region over part of the section of a TE beam: CUPID_ERR_MODEL.
 */
cupid_status cupid_coupling_lagrange_create(cupid_cuf_beam beam, cupid_pd_grid grid,
                                            const cupid_coupling_options *opts,
                                            cupid_coupling_h *c, cupid_csr *K);

/** The eliminated K of the Lagrange coupling @p c again, with K_PD from @p op (the operator
 *  of the real grid, its removed bonds included: crack growth); the tie and the beam's K are
 *  c's. Equal to what cupid_coupling_lagrange_create() builds with that operator. */
cupid_status cupid_coupling_lagrange_update(const cupid_coupling_h c, const cupid_pd_operator op,
                                            cupid_csr *K);

/** Tied PD nodes of the Lagrange coupling (NULL, 0 for the fictitious-node method). */
void cupid_coupling_tied(const cupid_coupling_h c, const cupid_int **nodes, cupid_int *n);

/** Set the displacements of the tied PD nodes from the FE DOFs of u (Lagrange coupling). */
void cupid_coupling_recover(const cupid_coupling_h c, double *u);

/**
 * Lagrange coupling: move the forces on tied PD DOFs of f to the beam, f_FE += T^T f_tied, and
 * zero them (the load vector of the eliminated system; a load on a tied node acts on the beam).
 */
void cupid_coupling_lagrange_load(const cupid_coupling_h c, double *f);

/**
 * Lagrange coupling in dynamics: the tied PD nodes' masses carried by the beam through the
 * tie, the mass of the eliminated system T^T diag(M_PD, M_FE) T restricted to the tied part:
 * consistent (into @p M, a matrix with the pattern of the coupled K; adds m_q w_a w_b I3 to
 * the FE blocks (a, b) of every tied node q) or HRZ-lumped (into the diagonal @p lumped:
 * m_q w_a^2 / sum w_t^2 over the translational functions t, every LE node or the constant TE
 * term, so that a translation carries m_q). Exactly one of M and lumped is non-NULL;
 * @p pd_mass holds rho V per real PD node (the entries of tied nodes are read only here: the
 * caller leaves them out of its own PD mass). The rest of the system's mass (FE, untied PD
 * nodes) is the caller's.
 */
cupid_status cupid_coupling_lagrange_mass(const cupid_coupling_h c, const double *pd_mass,
                                          cupid_csr M, double *lumped);

/** Destroy and set *c to NULL (NULL-safe). */
void cupid_coupling_destroy(cupid_coupling_h *c);

/** Counts. */
void cupid_coupling_get_info(const cupid_coupling_h c, cupid_coupling_info *info);


/* ---- Arlequin coupling (paper 004 section 3; src/coupling/arlequin.c) ----
 * The beam and a PD region overlap on [lo, hi] along the axis y; both models live there.
 * The Hamiltonian is H = alpha H_FE + (1 - alpha) H_PD (Eq. 8): alpha = 1 on the FE-only side,
 * 0 on the PD-only side, a ramp across the overlap (Eq. 9: linear; also constant 0.5 and the
 * C1 cubic 1 - 3s^2 + 2s^3). The FE stiffness and mass are integrated with alpha at the axis
 * Gauss points (cupid_cuf_assemble_weighted_add(), Eqs. 12, 14); every PD bond is weighted by
 * the mean of its end weights (1 - alpha_i + 1 - alpha_j)/2 and every PD mass by 1 - alpha_i
 * (Eqs. 12, 14; for LPS node p's whole energy by 1 - alpha_p, see below). Every PD node q in
 * an overlap is tied to the beam by a penalty (Eqs. 15-19):
 * energy kappa/2 |d_q - N(x_q) u_FE|^2, one spring of stiffness kappa (N/m) per tied node and
 * component (the node-by-node form of Eq. 16-17; the volumetric penalty of Eq. 16 is
 * kappa_v = kappa / V_q). The coupled K is symmetric (CHOLMOD), layout [3 per PD node | FE].
 * 1D grids tie the axial component only; 3D grids all three. The PD energy is weighted node
 * by node (cupid_pd_operator_assemble_weighted: node p's energy times 1 - alpha(y_p)), which
 * for bond-based PD with one material is the bond weight (w_i + w_j)/2 and for LPS weights each
 * node's dilatation and deviatoric energy. A PD region between two beam parts has two overlaps
 * (n_overlaps = 2): FE-only below the first and above the second, PD-only between them.
 * General layouts (cupid_arlequin_region): several regions, each a box with overlaps along
 * any of its faces (normal or parallel to the axis); the beam's weight is then the separable
 * sum 1 - sum_r a_r(y) s_r(x, z), integrated by cupid_cuf_assemble_weight_add(). */

/** The Arlequin weight alpha(y) of the FE model. */
typedef struct {
  double lo, hi;        /**< the overlap along y */
  int fe_below;         /**< 1: the FE-only side is y < lo (alpha = 1 there); 0: y > hi */
  cupid_weight kind;    /**< linear (Eq. 9), constant (0.5 inside), smooth (C1 cubic) */
} cupid_arlequin_weight;

/** alpha(y): 1 on the FE-only side, 0 on the PD-only side, the ramp of @p w in [lo, hi]. */
double cupid_arlequin_alpha(const cupid_arlequin_weight *w, double y);

/** One overlap of a PD region: the slab [lo, hi] along @p axis next to one of its faces,
 *  with the weight's ramp across it (fe_below: the face is at lo). */
typedef struct {
  int axis;             /**< 0: x, 1: y, 2: z */
  cupid_arlequin_weight weight;
} cupid_arlequin_ramp;

#define CUPID_ARLEQUIN_MAX_RAMPS 6 /**< one per face of a box */

/** A PD region of a general layout: its box and the overlaps along its interfaces. Inside the
 *  box the PD weight is w = prod_k (1 - alpha_k(x_k)) over its ramps (1 where no ramp
 *  reaches; 0 outside the box), alpha = 1 - sum over regions of w. The product keeps the
 *  beam's weight separable (cupid_cuf_weight): where two ramps cross (a corner of a region
 *  inside the section), the PD weight is the product of the two. */
typedef struct {
  cupid_box box;        /**< the region (axes with has[k] = 0 are unbounded) */
  int n_ramps;
  cupid_arlequin_ramp ramps[CUPID_ARLEQUIN_MAX_RAMPS];
} cupid_arlequin_region;

typedef struct {
  cupid_arlequin_weight weight; /**< the overlap (the lower one when there are two) */
  double penalty;       /**< kappa, N/m per tied node and component */
  int n_overlaps;       /**< 0 or 1: one overlap; 2: also @p second */
  cupid_arlequin_weight second; /**< the upper overlap (above weight; FE-only above it) */
  /** General layouts (several regions, regions over part of the section, overlaps along x or
   *  z): when n_regions > 0 these replace weight / n_overlaps / second, which describe one
   *  unbounded region with ramps along y. */
  int n_regions;
  const cupid_arlequin_region *regions;
} cupid_arlequin_options;

/** alpha(y) of the y-only form: the one ramp, or with two overlaps the larger of the two ramps
 *  (1 below the first and above the second, 0 between them). */
double cupid_arlequin_alpha_of(const cupid_arlequin_options *o, double y);

/** alpha at the point p: 1 - the sum of the regions' PD weights (1 outside every region). */
double cupid_arlequin_alpha_at(const cupid_arlequin_options *o, const double p[3]);

typedef struct {
  cupid_int n_tied;     /**< PD nodes tied to the beam (those in the overlap) */
  int components;       /**< tied components per node (1 in 1D, 3 in 3D) */
  double pd_weight_min; /**< smallest PD nodal weight 1 - alpha_i */
} cupid_arlequin_info;

/** `penalty: auto` (issue 18): kappa = CUPID_ARLEQUIN_AUTO_PENALTY x k_node, k_node the
 *  stiffness of a PD node's family (cupid_arlequin_node_stiffness()). The factor is measured on
 *  paper 004's truss (docs/coupling.md, "The penalty"). */
#define CUPID_ARLEQUIN_AUTO_PENALTY 1.0

/** k_node: the largest diagonal stiffness of a PD node of @p op (N/m), over the grid's owned
 *  nodes: the yy entry of its 3x3 diagonal block on a 1D grid (the tied component), the mean
 *  of the three diagonal entries on a 3D one: the springs of its family, which a tie must
 *  match. 1D bond-based, constant influence, no partial volumes (micromodulus calibrated on
 *  the lattice sums): 4 H_m / (m (m + 1)) x E A / h, m = delta / h, H_m the harmonic number
 *  (11/18 E A / h at m = 3, E A / h at m = 2); 3D bond-based at delta = 1.5 h: 2.52 E h. On
 *  a slab of a partitioned grid the caller takes the maximum over the slabs. */
cupid_status cupid_arlequin_node_stiffness(cupid_pd_operator op, cupid_pd_grid grid, double *k_node);

/**
 * The coupled stiffness: weighted PD (@p op on @p grid, LPS or bond-based) + weighted beam + the
 * penalty K_z = kappa [I, -N; -N^T, N^T N] (Eq. 18, sign as coupling.md 7.2). The beam's DOF
 * offset must be 3 * nodes of the grid. CUPID_ERR_MODEL if a PD node of an overlap lies
 * outside the beam. @p op NULL: the same matrix without the PD block (the assembled part of
 * the matrix-free operator below). On a slab of a partitioned grid (issue 6,
 * cupid_pd_grid_partition) this is the slab's share: only its owned tied nodes add their
 * penalty, and only the last slab (the owner of the FE DOFs) adds the weighted beam, so the
 * owned PD rows are the whole matrix's and the FE rows sum over the slabs to the whole FE rows.
 */
cupid_status cupid_arlequin_assemble(cupid_cuf_beam beam, cupid_pd_grid grid,
                                     cupid_pd_operator op, const cupid_arlequin_options *o,
                                     cupid_csr *K, cupid_arlequin_info *info);

/** What the coupled K keeps for assembling again (crack growth): the weighted beam and the
 *  penalty (the part that breaks do not change), built once; each K is the union of its
 *  pattern and the PD block's, that part added, then the PD block of the operator then. A K
 *  depends on the bonds intact when it is made alone: it equals cupid_arlequin_assemble()'s
 *  on the same bonds to the bit (a run resumed from a checkpoint meets the same K). */
typedef struct cupid_arlequin_assembly_private *cupid_arlequin_assembly;
/** As cupid_arlequin_assemble(), keeping what does not change when bonds break in @p out. */
cupid_status cupid_arlequin_assembly_create(cupid_cuf_beam beam, cupid_pd_grid grid,
                                            cupid_pd_operator op, const cupid_arlequin_options *o,
                                            cupid_arlequin_assembly *out, cupid_csr *K,
                                            cupid_arlequin_info *info);
/** A new K (the caller's): the kept part and the PD block of @p op (an operator on the grid of
 *  create, e.g. the same one after breaks; NULL: no PD block). */
cupid_status cupid_arlequin_assembly_matrix(const cupid_arlequin_assembly A, cupid_pd_operator op,
                                            cupid_csr *K);
/** The rows of the PD nodes @p nodes (sorted) of a K from cupid_arlequin_assembly_matrix(),
 *  assembled again in place from the kept part and the PD block of @p op, as a new K would
 *  have them to the bit (the bonds of the other nodes unchanged; K keeps its pattern, where a
 *  broken bond's blocks are now zero). */
cupid_status cupid_arlequin_assembly_update_rows(const cupid_arlequin_assembly A, cupid_pd_operator op,
                                                 const cupid_int *nodes, cupid_int n, cupid_csr K);
void cupid_arlequin_assembly_destroy(cupid_arlequin_assembly *A);

/**
 * The weighted mass (Eq. 14): into @p M (consistent FE mass; K's pattern, zeroed by the
 * caller) or into the diagonal @p lumped (HRZ FE mass); exactly one is non-NULL. @p pd_mass
 * holds the unweighted PD nodal mass rho V per node.
 */
cupid_status cupid_arlequin_mass(cupid_cuf_beam beam, cupid_pd_grid grid,
                                 const cupid_arlequin_options *o, const double *pd_mass,
                                 cupid_csr M, double *lumped);

/** Largest constraint gap max_q |d_q - N(x_q) u_FE| over the tied nodes and components. */
/** The forces @p f (system layout) under a tie held exactly (kappa -> infinity): the tied PD
 *  nodes' components go to the beam through the tie, f_FE += N^T f_tied, and are zeroed (the
 *  patch test of the tied problem; issue 18). */
cupid_status cupid_arlequin_tie_forces(cupid_cuf_beam beam, cupid_pd_grid grid,
                                      const cupid_arlequin_options *o, double *f);
cupid_status cupid_arlequin_gap(cupid_cuf_beam beam, cupid_pd_grid grid,
                                const cupid_arlequin_options *o, const double *u, double *gap);

/* Matrix-free Arlequin (issue 6; src/coupling/arlequin_operator.c): K x without the PD matrix.
 * The PD block is the PD operator of @p pd with node p's energy weighted by 1 - alpha(x_p)
 * (cupid_pd_operator_scale_energy()), applied matrix-free; the weighted beam and the penalty
 * ties are assembled (cupid_arlequin_assemble() with op NULL). Symmetric positive definite
 * once held, like the assembled K: CG, preconditioned by the same K with the cheap bond-based
 * PD operator of cupid_coupling_cheap_options() (cupid_arlequin_preconditioner()). */

/** The matrix-free Arlequin operator (opaque). */
typedef struct cupid_arlequin_operator_private *cupid_arlequin_operator;

/** Build it (@p beam, @p grid and the region array of @p o are borrowed: they must outlive
 *  it; the beam's DOF offset must be 3 * nodes of the grid). */
cupid_status cupid_arlequin_operator_create(cupid_cuf_beam beam, cupid_pd_grid grid,
                                            const cupid_pd_operator_options *pd,
                                            const cupid_arlequin_options *o,
                                            cupid_arlequin_operator *A, cupid_arlequin_info *info);
/** Destroy and set *A to NULL (NULL-safe). */
void cupid_arlequin_operator_destroy(cupid_arlequin_operator *A);
/** The operator's weighted PD operator (borrowed): pre-cracks and broken bonds are copied
 *  onto it with cupid_pd_operator_copy_broken(). */
cupid_pd_operator cupid_arlequin_operator_pd(const cupid_arlequin_operator A);
/** Scalar DOFs (3 * PD nodes + the beam's). */
cupid_int cupid_arlequin_operator_size(const cupid_arlequin_operator A);
/** Approximate bytes held (the PD operator's bonds and per-node data, the assembled rest). */
int64_t cupid_arlequin_operator_bytes(const cupid_arlequin_operator A);
/** y = K x; equals cupid_csr_matvec() with the matrix of cupid_arlequin_assemble() up to
 *  round-off. Not thread-safe (work vectors). */
cupid_status cupid_arlequin_operator_apply(const cupid_arlequin_operator A, const double *x,
                                           double *y);
/** The rows [d0, d1) of y = K x (the others left undefined): what each MPI rank computes. */
cupid_status cupid_arlequin_operator_apply_rows(const cupid_arlequin_operator A, const double *x,
                                                cupid_int d0, cupid_int d1, double *y);
/** The preconditioner matrix: K with the cheap PD operator (horizon_factor <= 0: 1.5). */
cupid_status cupid_arlequin_preconditioner(const cupid_arlequin_operator A, double horizon_factor,
                                           cupid_csr *P);
/* ---- end of the Arlequin block ---- */

/* ---- Matrix-free fictitious-node coupling (issue 6; src/coupling/operator.c, krylov.c) ----
 * y = A x for the coupled matrix of Eq. 38 (layout of cupid_coupling_create(): [3 DOFs per real
 * PD node | FE DOFs]) without forming the PD stiffness: the PD operator of opts->pd is applied
 * matrix-free on the extended grid (real + fictitious PD nodes) to [x_PD ; I^{f-PD} x_FE] and
 * the rows of the real nodes are kept; the FE rows (real and fictitious FE elements, with their
 * I^{f-FE} columns) are assembled. Full-section and partial regions alike. Memory: the PD
 * operator's bonds (~12 bytes each) instead of the ~2,700 scalar non-zeros a row of the
 * assembled LPS matrix. For Krylov solves, preconditioned by the same Eq. 38 with a cheap
 * bond-based PD operator (cupid_coupling_preconditioner()). */

/** The matrix-free coupled operator (opaque). */
typedef struct cupid_coupling_operator_private *cupid_coupling_operator;

/**
 * Build the fictitious nodes and elements as cupid_coupling_create() does, and the PD operator
 * of opts->pd on the extended grid, but no PD matrix. The beam must have been deactivated and
 * its DOF offset set to 3 * (real PD nodes); @p grid is borrowed for the call only.
 */
cupid_status cupid_coupling_operator_create(cupid_cuf_beam beam, cupid_pd_grid grid,
                                            const cupid_coupling_options *opts,
                                            cupid_coupling_operator *A);
/** Destroy and set *A to NULL (NULL-safe). */
void cupid_coupling_operator_destroy(cupid_coupling_operator *A);
/** Scalar DOFs of the operator (3 * (real PD nodes + FE nodes)). */
cupid_int cupid_coupling_operator_size(const cupid_coupling_operator A);
/** Counts, as cupid_coupling_get_info(). */
void cupid_coupling_operator_get_info(const cupid_coupling_operator A, cupid_coupling_info *info);
/** Approximate bytes held by the operator (bonds, per-node data, FE rows). */
int64_t cupid_coupling_operator_bytes(const cupid_coupling_operator A);
/**
 * y = A x (x, y of cupid_coupling_operator_size() entries; not thread-safe: A holds work
 * vectors). Equals cupid_csr_matvec() with the matrix of cupid_coupling_create() up to
 * round-off (the fictitious columns are summed in another order).
 */
cupid_status cupid_coupling_operator_apply(const cupid_coupling_operator A, const double *x,
                                           double *y);

/**
 * The rows [d0, d1) of y = A x (global DOF numbering; x whole, y of
 * cupid_coupling_operator_size() entries, those outside [d0, d1) left undefined): the PD rows
 * through cupid_pd_operator_apply_range() on the extended nodes they need, the FE rows of
 * the assembled block. What each MPI rank computes for its own rows of a Krylov product.
 */
cupid_status cupid_coupling_operator_apply_rows(const cupid_coupling_operator A, const double *x,
                                                cupid_int d0, cupid_int d1, double *y);
/**
 * The assembled coupled matrix of Eq. 38 with the PD operator @p pd on the same extended grid
 * (NULL: the operator's own, with its broken bonds; intact, the matrix of
 * cupid_coupling_create()).
 */
cupid_status cupid_coupling_operator_assemble(const cupid_coupling_operator A,
                                              const cupid_pd_operator_options *pd, cupid_csr *K);
/**
 * The operator's own PD operator on the extended grid (real + fictitious nodes), which fracture
 * keeps in step with the model grid's: cupid_pd_operator_copy_broken_mapped() with the map of
 * cupid_coupling_operator_extended_nodes(). Borrowed: it lives as long as A.
 */
cupid_pd_operator cupid_coupling_operator_pd(const cupid_coupling_operator A);
/** Each real PD node's node on the extended grid (the grid's nodes: a slab's local ones). */
const cupid_int *cupid_coupling_operator_extended_nodes(const cupid_coupling_operator A);
/**
 * For every FE node a whose row of Eq. 38 reads PD columns (through the fits of a fictitious FE
 * element, Eqs. 31-36): boxes[6 a ..] = the bounding box (lo x y z, hi x y z) of those PD nodes
 * and of the FE node's own point (LE: its section node at its beam node's y; TE: the beam
 * node's y), which is the part of the region its fictitious elements span; other rows: an empty
 * box (lo = +inf, hi = -inf). On a slab, the PD columns of this slab's owned nodes only: the
 * boxes of the ranks are joined by min / max. @p beam: the beam the operator was built on.
 */
cupid_status cupid_coupling_operator_fit_boxes(const cupid_coupling_operator A,
                                               const cupid_cuf_beam beam, double *boxes);
/**
 * The coupling zone of fracture: zone[r] = 1 for every real PD node r (one entry per real node
 * of the grid: a slab's local nodes) whose family on the extended grid holds a fictitious node,
 * or that is in @p core (NULL: none; one flag per real node, e.g. those inside
 * cupid_coupling_operator_fit_boxes); else 0.
 * Any bond (i, j) with neither end in the zone changes the PD rows of Eq. 38 in real columns
 * only, by the same symmetric, rigid-mode-free terms as on the model grid: the fits of
 * Eqs. 33-36 and the balance's C = K^T R stay as they were (docs/theory.md, "Fracture with
 * fictitious nodes"); the fit boxes keep a crack from passing between an interface and the
 * planes its fictitious FE element reads, which would bridge the crack with beam stiffness.
 */
cupid_status cupid_coupling_operator_zone(const cupid_coupling_operator A,
                                          const unsigned char *core, unsigned char *zone);
/**
 * The cheap PD operator of the preconditioner: @p fine (materials kept) turned bond-based with
 * horizon horizon_factor * spacing (<= 0: 1.5, the 18 face and edge neighbours), constant
 * influence, whole cells (partial volume NONE); its micromodulus matches each material's bulk
 * modulus (pd.h). It couples nodes one short horizon apart only.
 */
void cupid_coupling_cheap_options(const cupid_pd_operator_options *fine, double spacing,
                                  double horizon_factor, cupid_pd_operator_options *cheap);
/** The preconditioner matrix: Eq. 38 with cupid_coupling_cheap_options() (never the LPS matrix). */
cupid_status cupid_coupling_preconditioner(const cupid_coupling_operator A, double horizon_factor,
                                           cupid_csr *P);

/** z = A^T w (a whole grid; the PD operator is symmetric): for the balanced coupling. */
cupid_status cupid_coupling_operator_apply_transpose(const cupid_coupling_operator A,
                                                     const double *w, double *z);
/** The FE rows of Eq. 38 (real and fictitious FE elements; block columns over [PD | FE]). */
const cupid_csr_t *cupid_coupling_operator_fe_rows(const cupid_coupling_operator A);

/* ---- The balanced fictitious-node coupling (issue 18; src/coupling/balance.c) ----
 * Eq. 38's K conserves neither linear nor angular momentum (R^T K != 0 for the six rigid
 * modes R). `coupling.balance: momentum` solves with K' = K - W C^T, C = K^T R,
 * W = D R (R^T D R)^-1, D = diag(K) on the interface FE DOFs (the real FE nodes of the
 * fictitious elements): R^T K' = 0 (reactions balance the load), K' R = 0, and K' x = K x for
 * every x whose K x has no resultant or moment (the patch test's fields). Never assembled. */
#define CUPID_BALANCE_MODES 6
typedef struct cupid_coupling_balance_private *cupid_coupling_balance;
/** From the rigid modes R and C = K^T R (CUPID_BALANCE_MODES columns of n each, mode k at
 *  offset k n) and the weights d (n; > 0 on the DOFs that take the correction). CUPID_ERR_MODEL
 *  when those DOFs do not span the rigid modes. */
cupid_status cupid_coupling_balance_create(cupid_int n, const double *R, const double *C,
                                           const double *d, cupid_coupling_balance *B);
/** 1 when PD region @p region spans the beam's whole cross-section (x/z bounds missing or
 *  covering it): its interfaces are planes normal to the axis at its y bounds. */
int cupid_coupling_region_spans_section(const cupid_cuf_beam beam, const cupid_box *region);
/** Interfaces balanced apart at most (cupid_coupling_balance_create_grouped). */
#define CUPID_BALANCE_GROUPS_MAX 64
/** The balance of each interface on its own: the DOFs in @p n_groups groups (group[j], one per
 *  DOF; every DOF whose column of C is nonzero must lie in the group of its interface), and
 *  K' = K - sum_g W_g C_g^T with C_g the group's entries of C and W_g = D_g R (R^T D_g R)^-1
 *  from its weights. Then R^T K' = 0 as before, and the forces across each interface balance
 *  (every free body cut between interfaces is in equilibrium: docs/coupling.md). A group with
 *  no entry of C and no weight is left out; one with entries of C but weights that do not span
 *  the rigid modes: CUPID_ERR_MODEL. n_groups = 1 (group NULL): cupid_coupling_balance_create.
 *  At most CUPID_BALANCE_GROUPS_MAX groups. */
cupid_status cupid_coupling_balance_create_grouped(cupid_int n, const double *R, const double *C,
                                                   const double *d, int n_groups, const int *group,
                                                   cupid_coupling_balance *B);
void cupid_coupling_balance_destroy(cupid_coupling_balance *B);
/** y -= W (C^T x): turns y = K x into K' x. */
void cupid_coupling_balance_correct(const cupid_coupling_balance B, const double *x, double *y);
/** The terms of K' = K - W C^T as they are kept: *k columns of n entries each, column after
 *  column (W zero on the PD rows), for solvers that fold them into their own elimination
 *  (src/problem/growth_block.c). The arrays are B's. */
void cupid_coupling_balance_terms(const cupid_coupling_balance B, int *k, const double **C,
                                  const double **W);
/** u with K'_ff u_f = f_f - K'_fc u_c (u_c = bc's values) from the factor F of K_ff
 *  (Sherman-Morrison-Woodbury: CUPID_BALANCE_MODES more solves per group). */
cupid_status cupid_coupling_balance_solve(const cupid_coupling_balance B, const cupid_csr_t *K,
                                          cupid_direct_factor F, const cupid_dirichlet_t *bc,
                                          const double *f, double *u);
/** The Sherman-Morrison-Woodbury form of cupid_coupling_balance_solve() kept with its factor:
 *  _create solves for (K_ff)^-1 W once (F: the factor of K_ff with the free DOFs of @p bc,
 *  borrowed), _apply gives z = (K'_ff)^-1 r for full-length r (free entries read; z zero on
 *  the fixed DOFs of bc) by one solve with F: the exact inverse of the balanced K whose K F
 *  factors, e.g. the preconditioner of re-solves after bonds broke (C and W do not change
 *  then: docs/theory.md). */
typedef struct cupid_coupling_balance_smw_private *cupid_coupling_balance_smw;
cupid_status cupid_coupling_balance_smw_create(const cupid_coupling_balance B, cupid_direct_factor F,
                                               const cupid_dirichlet_t *bc,
                                               cupid_coupling_balance_smw *M);
cupid_status cupid_coupling_balance_smw_apply(const cupid_coupling_balance_smw M, const double *r,
                                              double *z);
void cupid_coupling_balance_smw_destroy(cupid_coupling_balance_smw *M);
/** On a PD slab under mpirun: B holds this slab's share of C (its owned PD DOFs and, on one
 *  rank, the FE DOFs; R, W and the weights on every local DOF), @p sum adds a few doubles over
 *  the ranks (collective), and the FE rows' correction is added where @p apply_here is 1 (the
 *  rank whose share of the FE rows holds their FE columns). */
void cupid_coupling_balance_set_slab(cupid_coupling_balance B, void (*sum)(double *v, int n),
                                     int apply_here);
/** *out: the operator K' around the matrix-free K of @p L (kept by B), with apply_rows when L
 *  has it (the FE rows' call collective on a slab, which needs cupid_coupling_balance_set_slab:
 *  else CUPID_ERR_ARGUMENT). */
cupid_status cupid_coupling_balance_linear(cupid_coupling_balance B, const cupid_linear_operator *L,
                                           cupid_linear_operator *out);
/** The weights d of the FE rows @p Kfe (block rows of FE nodes, block columns [PD | FE], n_pd
 *  PD nodes first): diag(K) on the rows that read PD columns, 0 elsewhere (3 (n_pd + rows)). */
cupid_status cupid_coupling_balance_weights(const cupid_csr_t *Kfe, cupid_int n_pd, double *d);

/**
 * Solve A u = f with the Dirichlet conditions @p bc (finalized; fixed DOFs take bc->value) by
 * GMRES on the free DOFs, A matrix-free (a PETSc MATSHELL), preconditioned by @p P (the
 * cheap matrix, e.g. from cupid_coupling_preconditioner(); its free-free block is given to
 * the PC). PETSc is initialised here when needed (PETSC_COMM_SELF; one rank). Builds without
 * PETSc: CUPID_ERR_UNSUPPORTED. Not converged in max_it: CUPID_ERR_NUMERIC (u holds the last
 * iterate).
 */
cupid_status cupid_coupling_krylov_solve(const cupid_coupling_operator A, const cupid_csr_t *P,
                                         const cupid_dirichlet_t *bc, const double *f, double *u,
                                         const cupid_krylov_options *opts,
                                         cupid_solve_info *info);
/** The fictitious-node operator as a cupid_linear_operator (GMRES; A borrowed). */
void cupid_coupling_operator_linear(const cupid_coupling_operator A, cupid_linear_operator *L);
/** The Arlequin operator as a cupid_linear_operator (symmetric: CG; A borrowed). */
void cupid_arlequin_operator_linear(const cupid_arlequin_operator A, cupid_linear_operator *L);
/* ---- end of the matrix-free coupling block ---- */

#ifdef __cplusplus
}
#endif
#endif
