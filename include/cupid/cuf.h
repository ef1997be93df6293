/**
 * @file cuf.h
 * @brief 1D Carrera Unified Formulation (CUF) beams: Taylor (TE) and Lagrange (LE)
 *        cross-section expansions, B2/B3/B4 beam elements, separable fundamental-nucleus
 *        assembly into 3x3-block CSR, loads, constraints and 3D post-processing.
 *
 * Kinematics (paper 000, Eqs. 23-24): u(x,y,z) = F_tau(x,z) N_i(y) u_tau_i, beam axis y,
 * cross-section in the x-z plane. Every (expansion function tau, beam node i) pair is one
 * "FE node" carrying 3 DOFs (u_x, u_y, u_z), so every matrix is block CSR with bs = 3.
 *
 * Conventions
 * - FE node numbering: node = i * M + tau (beam node major), M = expansion functions per beam
 *   node. Scalar DOF = dof_offset + 3 * node + component. The stiffness built by
 *   cupid_cuf_assemble() uses local numbering (offset 0); loads, constraints and
 *   post-processing read and write global vectors at dof_offset (see cupid_cuf_set_dof_offset()).
 * - TE: F_tau = xh^a zh^b, a + b <= N, ordered by total degree then increasing power of z
 *   (cuf.md section 2), in the centred and scaled coordinates xh = (x - xc)/h, zh = (z - zc)/h
 *   where (xc, zc) is the area centroid of the section and h its largest half-extent about it.
 *   This spans exactly the same space as plain x^a z^b (so results are those of TE N) but keeps
 *   the matrix well conditioned in any unit system. TE0 (F = 1) is allowed (a rod).
 * - LE: section elements L4, L9, L16, isoparametric; node order inside an element is the
 *   MUL2_new/CUF one (cuf.md section 3.1): L4 (-1,-1) (1,-1) (1,1) (-1,1); L9 corners and
 *   mid-sides counter-clockwise from (-1,-1), centre last; L16 the 12 boundary nodes
 *   counter-clockwise from (-1,-1), then (-1/3,-1/3) (1/3,-1/3) (1/3,1/3) (-1/3,1/3).
 *   Explicit section elements (beam.section_elements) use the same order.
 * - Components: each cell between consecutive breakpoints is one section element (LE) or one
 *   integration cell (TE). Coincident nodes of different components are merged (tolerance
 *   1e-9 of the section size); for LE a node of one component lying inside an edge of another
 *   (a non-matching interface) is a model error, and overlapping components always are.
 * - Beam elements: Lagrange B2/B3/B4 with equally spaced nodes; axis Gauss rule 2/3/4 points.
 * - Integration (beam.integration): 0 full (default), 1 selective reduced integration of the
 *   transverse-shear strains gamma_yz, gamma_xy (rule with one point fewer), 2 MITC (those two
 *   strains interpolated from the tying points {0} / {+-1/sqrt3} / {0, +-sqrt(3/5)}, cuf.md 4).
 *   Full is the default because it reproduces the published B4 results (cuf.md 1.4) and
 *   B4 locks only weakly; use MITC with B2/B3 (see bench/README_cuf.md for the study). With
 *   these tying points MITC equals selective reduced integration unless C couples the shear
 *   rows to the others.
 * - Materials: isotropic or orthotropic with material axes = x y z; nu_ij is the Poisson ratio
 *   for a stress along i (S_ij = -nu_ij / E_i).
 * - Poisson locking (beam.poisson_correction, default auto = on for TE0 and TE1): a TE0 section
 *   cannot contract and a TE1 section only uniformly, so with nu != 0 the 3D law makes the rod
 *   stiffer (TE0: E(1-nu)/((1+nu)(1-2nu)) instead of E) and the TE1 beam stiffer in bending
 *   (tip deflection -26 % at nu = 0.3, cuf.md 1.4). The correction (the CUF literature's
 *   reduced coefficients for N <= 1, Carrera & Giunta 2010, Carrera, Giunta & Petrolo 2011;
 *   cupid's form is derived in docs/theory.md) imposes sigma_xx = sigma_zz = 0: C~ = the
 *   compliance restricted to the other four stresses, inverted (sigma_yy = E_y eps_yy, shears
 *   unchanged). TE0 uses C~. TE1 uses C~ plus the rest of the 3D law, R = C - C~, on eps_xx,
 *   eps_zz and the constant-term part of eps_yy only: uniform tension keeps its exact 3D
 *   solution (contraction included), bending gets E I, and no zero-energy mode appears.
 *   Stiffness and stress output use the same law.
 * - Stresses are returned in the order xx yy zz yz xz xy, computed as C eps(x,y,z) from the
 *   3D strain of the expansion (for reduced/MITC the untied strain is used). The VTU array
 *   uses VTK's symmetric-tensor order xx yy zz xy yz xz instead, so ParaView names them right.
 *
 * Coupling hooks: a mask per (beam element, section element) pair marks parts of the beam as
 * inactive (removed: no stiffness, no loads, not found by point queries); FE nodes that touch
 * no active pair have an empty row apart from a zero diagonal block and must be fixed by the
 * caller (cupid_cuf_node_used()).
 */
#ifndef CUPID_CUF_H
#define CUPID_CUF_H

#include "cupid/base.h"
#include "cupid/io.h"
#include "cupid/model.h"
#include "cupid/solvers.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A discretised CUF beam (opaque). */
typedef struct cupid_cuf_beam_private *cupid_cuf_beam;

/** Integration rules along the axis (values of cupid_beam.integration). */
enum { CUPID_CUF_FULL = 0, CUPID_CUF_REDUCED = 1, CUPID_CUF_MITC = 2 };

/** Poisson-locking correction (values of cupid_beam.poisson_correction): AUTO applies it to
 *  TE0 and TE1 and not otherwise; ON is refused (CUPID_ERR_MODEL) for TE2 and up and LE. */
enum { CUPID_CUF_POISSON_AUTO = 0, CUPID_CUF_POISSON_ON = 1, CUPID_CUF_POISSON_OFF = 2 };

/** Counts and settings of a beam (for summaries). */
typedef struct {
  cupid_expansion expansion;
  int te_order;              /**< TE order N (TE only) */
  int le_nodes;              /**< 4, 9, 16 (LE only; 0 for TE) */
  int integration;           /**< CUPID_CUF_FULL / REDUCED / MITC */
  int poisson_corrected;     /**< 1: the reduced (sigma_xx = sigma_zz = 0) law is in use */
  int M;                     /**< expansion functions per beam node (TE terms or LE nodes) */
  int element_nodes;         /**< 2, 3, 4 (B2, B3, B4) */
  cupid_int n_beam_nodes, n_beam_elements;
  cupid_int n_section_nodes;    /**< geometric section nodes (= M for LE) */
  cupid_int n_section_elements; /**< LE elements or TE integration cells */
  cupid_int n_fe_nodes;      /**< n_beam_nodes * M */
  cupid_int n_dofs;          /**< 3 * n_fe_nodes */
  cupid_int dof_offset;
  double section_area;
  double y_min, y_max;
} cupid_cuf_info;

/** Build the beam of model->beam (model->has_beam must be set). Errors are CUPID_ERR_MODEL
 *  reported against the model file marks. */
cupid_status cupid_cuf_beam_create(const cupid_model_t *model, cupid_cuf_beam *beam);

/** Build a beam from a beam definition and a material table (no model file needed). */
cupid_status cupid_cuf_beam_create_from(const cupid_beam *def, const cupid_material *materials,
                                        int n_materials, cupid_cuf_beam *beam);

/** Destroy and set *beam to NULL (NULL-safe). */
void cupid_cuf_beam_destroy(cupid_cuf_beam *beam);

/** Counts and settings. */
void cupid_cuf_get_info(const cupid_cuf_beam beam, cupid_cuf_info *info);

/** Scalar DOFs of the beam (3 * beam nodes * M). */
cupid_int cupid_cuf_num_dofs(const cupid_cuf_beam beam);

/** Place the beam DOFs at @p offset (a multiple of 3) of a larger system. Default 0. */
cupid_status cupid_cuf_set_dof_offset(cupid_cuf_beam beam, cupid_int offset);
/** The time t at which cupid_cuf_load_add() and cupid_cuf_constraint_apply() evaluate the
 *  model's expressions (0 until set: a dynamic run sets it at every step). */
void cupid_cuf_set_time(cupid_cuf_beam beam, double t);

/** Global scalar DOF (offset included) of expansion function tau, beam node i, component k. */
cupid_int cupid_cuf_dof(const cupid_cuf_beam beam, int tau, cupid_int node, int k);

/** y coordinate of beam node i. */
double cupid_cuf_beam_node_y(const cupid_cuf_beam beam, cupid_int node);

/** Beam node at y (tolerance 1e-9 of the length), or -1. */
cupid_int cupid_cuf_beam_node_at(const cupid_cuf_beam beam, double y);

/** Beam element e: its first node (nodes first .. first + element_nodes - 1) and y range. */
void cupid_cuf_beam_element(const cupid_cuf_beam beam, cupid_int e, cupid_int *first_node,
                            double *y0, double *y1);

/** LE: coordinates (x, z) of section node tau. TE: the centre (xc, zc) and scale h of the
 *  monomials in xz[0], xz[1] and *h (tau ignored). */
void cupid_cuf_section_node(const cupid_cuf_beam beam, int tau, double xz[2], double *h);

/** Section element e: nodes per element (*npe), its geometric node indices (conn, may be
 *  NULL), its material index, its bounding box [xmin, xmax, zmin, zmax] (box may be NULL). */
void cupid_cuf_section_element(const cupid_cuf_beam beam, cupid_int e, int *npe,
                               cupid_int *conn, int *material, double box[4]);

/** Mark the pair (beam element be, section element se) active (1) or inactive (0). */
cupid_status cupid_cuf_set_active(cupid_cuf_beam beam, cupid_int be, cupid_int se, int active);

/** 1 if the pair is active. */
int cupid_cuf_is_active(const cupid_cuf_beam beam, cupid_int be, cupid_int se);

/** 1 if FE node (tau, beam node i) belongs to at least one active pair. */
int cupid_cuf_node_used(const cupid_cuf_beam beam, int tau, cupid_int node);

/** Block-CSR (bs = 3) sparsity pattern of the stiffness in local numbering: rowptr has
 *  n_fe_nodes + 1 entries, columns sorted. Caller frees both with cupid_free(). Pairs
 *  (tau,i)-(s,j) are present iff tau and s share an active section element of a beam element
 *  holding i and j (TE: every tau, s); diagonal blocks are always present. */
cupid_status cupid_cuf_pattern(const cupid_cuf_beam beam, cupid_int **rowptr, cupid_int **col);

/** Assemble the stiffness matrix (local numbering, bs = 3) into a new matrix *K. */
cupid_status cupid_cuf_assemble(const cupid_cuf_beam beam, cupid_csr *K);

/** Add the beam stiffness into an existing bs = 3 matrix whose pattern contains the beam's
 *  pattern shifted by dof_offset / 3 blocks (for coupled systems). */
cupid_status cupid_cuf_assemble_add(const cupid_cuf_beam beam, cupid_csr K);

/** A vector field f(p) -> out[3] for loads and prescribed displacements; @p density is the
 *  density of the material at p (0 where unknown). */
typedef void (*cupid_cuf_field_fn)(void *ctx, const double p[3], double density, double out[3]);

/** Add the consistent forces of a point load P at @p at: f_{tau i k} += F_tau N_i P_k.
 *  CUPID_ERR_MODEL if the point is not inside an active part of the beam. */
cupid_status cupid_cuf_point_load_add(const cupid_cuf_beam beam, const double at[3],
                                      const double P[3], double *f);

/** Add a traction (force per area, fn evaluated on the plane) on the section plane y over the
 *  patch box (x/z bounds; has[] = 0: unbounded; NULL: whole section), clipped to the section
 *  elements. *area receives the loaded area (may be NULL); CUPID_ERR_MODEL if it is zero. */
cupid_status cupid_cuf_traction_add(const cupid_cuf_beam beam, double y, const cupid_box *patch,
                                    cupid_cuf_field_fn fn, void *ctx, double *f, double *area);

/** Add a body force (per volume) over box (NULL: everywhere) ∩ beam. *volume receives the
 *  loaded volume (may be NULL). */
cupid_status cupid_cuf_body_force_add(const cupid_cuf_beam beam, const cupid_box *box,
                                      cupid_cuf_field_fn fn, void *ctx, double *f, double *volume);

/** Add every load of model->loads to f (global vector, dof_offset applied). */
cupid_status cupid_cuf_load_vector(const cupid_cuf_beam beam, const cupid_model_t *model, double *f);

/** Add one load of a model. */
cupid_status cupid_cuf_load_add(const cupid_cuf_beam beam, const cupid_model_t *model,
                                const cupid_load *load, double *f);

/** Fix all DOFs of beam node i (u = 0 on the whole section there). */
cupid_status cupid_cuf_clamp_node(const cupid_cuf_beam beam, cupid_int node, cupid_dirichlet bc);

/**
 * Prescribe components (mask[k] != 0) of the displacement to fn (NULL: zero) at beam nodes in
 * box (y bounds) and, for LE, at section nodes in box (x/z bounds). TE: the box must contain the
 * whole section; the prescribed field is the L2 projection of fn on the expansion (exact for
 * polynomials of degree <= N). *count receives the number of scalar DOFs fixed (may be NULL).
 */
cupid_status cupid_cuf_prescribe(const cupid_cuf_beam beam, const cupid_box *box,
                                 const int mask[3], cupid_cuf_field_fn fn, void *ctx,
                                 cupid_dirichlet bc, cupid_int *count);

/** Apply every constraint of model->constraints (clamp, fix, displacement) to bc. */
cupid_status cupid_cuf_apply_constraints(const cupid_cuf_beam beam, const cupid_model_t *model,
                                         cupid_dirichlet bc);

/** Apply one constraint of a model. */
cupid_status cupid_cuf_constraint_apply(const cupid_cuf_beam beam, const cupid_model_t *model,
                                        const cupid_constraint *c, cupid_dirichlet bc);

/** The generalised DOFs (into u at dof_offset) that represent the field fn: LE nodal values,
 *  TE section-wise L2 projection at every beam node. */
cupid_status cupid_cuf_interpolate(const cupid_cuf_beam beam, cupid_cuf_field_fn fn, void *ctx,
                                   double *u);

/**
 * The largest principal strain of the solution @p u at the quadrature points of every (beam
 * element, section element) pair: peak[be * n_section_elements + se] (-inf for an inactive
 * pair). The points are the stiffness's Gauss rules: the beam element's p points along the
 * axis, the section's rule on the element. The trigger of adaptive PD zones (issue 37: an
 * element turns to PD when its peak reaches a fraction of the critical stretch).
 */
cupid_status cupid_cuf_strain_peaks(const cupid_cuf_beam beam, const double *u, double *peak);

/** 1 if (x, y, z) lies inside an active part of the beam (tolerance 1e-9 of the size). */
int cupid_cuf_contains(const cupid_cuf_beam beam, double x, double y, double z);

/** Expansion weights at a point: w[n] for the FE nodes node[n] (n < *count <= M * element
 *  nodes), so that u(p) = sum_n w[n] u_{node[n]}. Arrays must hold M * element_nodes entries.
 *  CUPID_ERR_MODEL if outside. (For coupling constraints.) */
cupid_status cupid_cuf_shape_at(const cupid_cuf_beam beam, double x, double y, double z,
                                cupid_int *node, double *w, int *count);

/** Displacement at (x, y, z) from the global solution u. CUPID_ERR_MODEL if outside. */
cupid_status cupid_cuf_displacement_at(const cupid_cuf_beam beam, const double *u, double x,
                                       double y, double z, double out[3]);

/** Stress (xx yy zz yz xz xy) at (x, y, z). CUPID_ERR_MODEL if outside. */
cupid_status cupid_cuf_stress_at(const cupid_cuf_beam beam, const double *u, double x, double y,
                                 double z, double out[6]);

/** The 3D reconstruction as hexahedra, ready for cupid_vtu_write(&vtu->mesh). */
typedef struct {
  cupid_int n_points;
  double *points;        /**< 3 per point */
  double *displacement;  /**< 3 per point */
  double *stress;        /**< 6 per point in VTK's tensor order: xx yy zz xy yz xz */
  cupid_int n_cells;
  cupid_int *connectivity, *offsets;
  unsigned char *types;
  cupid_vtu_array point_data[2]; /**< "displacement", "stress" */
  cupid_vtu_mesh mesh;           /**< points at the arrays above */
} cupid_cuf_vtu;

/**
 * Build the reconstruction for solution u (NULL: zero): every active pair (beam element,
 * section element) becomes hexahedra: along y one per beam-node interval; across the section
 * LE elements are split by their node grid, TE cells into @p subdivisions^2 quads (<= 0: N+1).
 * Points are not shared between pairs, so stresses of different materials stay apart.
 */
cupid_status cupid_cuf_vtu_build(const cupid_cuf_beam beam, const double *u, int subdivisions,
                                 cupid_cuf_vtu **vtu);

/** Destroy and set *vtu to NULL (NULL-safe). */
void cupid_cuf_vtu_destroy(cupid_cuf_vtu **vtu);


/* ---- Mass matrix (src/cuf/mass.c; dynamics, issue 5) ----
 * Nucleus (paper 004 Eq. 3 in CUF form): M_ij^{tau s} = delta_kl int rho F_tau F_s N_i N_j dV,
 * rho the density of each section element's material (0 if not given). */

/** Assemble the consistent mass matrix (local numbering, bs = 3, the stiffness pattern of
 *  cupid_cuf_pattern()) into a new matrix *M. */
cupid_status cupid_cuf_mass_assemble(const cupid_cuf_beam beam, cupid_csr *M);

/** Add the consistent mass into an existing bs = 3 matrix at the beam's dof_offset (coupled
 *  systems; the pattern must contain the beam's). */
cupid_status cupid_cuf_mass_add(const cupid_cuf_beam beam, cupid_csr M);

/**
 * Add the lumped (diagonal) mass into d (global vector, dof_offset applied): HRZ lumping per
 * (beam element, section element) pair: the diagonal of the pair's consistent mass scaled so
 * that the translational functions (every LE node; the constant TE term) carry the pair's mass
 * rho V in each direction. Higher TE terms keep their diagonal in the same proportion.
 */
cupid_status cupid_cuf_mass_lumped(const cupid_cuf_beam beam, double *d);

/** Total mass sum rho V over the active pairs. */
cupid_status cupid_cuf_mass_total(const cupid_cuf_beam beam, double *total);
/* ---- end of the mass block ---- */

/* ---- Weighted stiffness and mass (src/cuf/weighted.c; Arlequin coupling, paper 004 Eqs.
 * 12 and 14) ----
 * The beam's energies multiplied by a weight alpha(x, y, z): K_alpha = int alpha B^T C B dV,
 * M_alpha = int alpha rho N^T N dV. The weight is a separable sum (cupid_cuf_weight)
 * alpha = c + sum_t a_t(y) s_t(x, z), which keeps the nucleus separable: axis integrals
 * weighted by a_t, section integrals weighted by s_t. The axis rule has p + 2 points (p = nodes
 * per beam element), the weighted section rule 2 points more per direction than the
 * stiffness rule: exact when a_t and s_t are polynomials of degree <= 3 on every element (put
 * the kinks of a piecewise weight on element boundaries). Full and selective reduced
 * integration are supported; MITC is CUPID_ERR_UNSUPPORTED (its tied axis functions are not
 * weighted). */

/** An axis weight a(y). */
typedef double (*cupid_cuf_weight_fn)(void *ctx, double y);

/** A section weight s(x, z). */
typedef double (*cupid_cuf_section_weight_fn)(void *ctx, double x, double z);

/** One separable term a(y) s(x, z) of a weight; a NULL function is 1. */
typedef struct {
  cupid_cuf_weight_fn axis;
  void *axis_ctx;
  cupid_cuf_section_weight_fn section;
  void *section_ctx;
} cupid_cuf_weight_term;

/** alpha(x, y, z) = constant + sum of the n_terms terms. */
typedef struct {
  double constant;
  int n_terms;
  const cupid_cuf_weight_term *terms;
} cupid_cuf_weight;

/** Add the weighted stiffness into an existing bs = 3 matrix at the beam's dof_offset (the
 *  pattern must contain the beam's). */
cupid_status cupid_cuf_assemble_weight_add(const cupid_cuf_beam beam, const cupid_cuf_weight *w,
                                           cupid_csr K);

/** Add the weighted consistent mass into an existing bs = 3 matrix at dof_offset. */
cupid_status cupid_cuf_mass_weight_add(const cupid_cuf_beam beam, const cupid_cuf_weight *w,
                                       cupid_csr M);

/** Add the weighted HRZ-lumped mass into d (global vector, dof_offset applied): the lumping of
 *  cupid_cuf_mass_lumped() applied to the weighted pair matrices. */
cupid_status cupid_cuf_mass_lumped_weight(const cupid_cuf_beam beam, const cupid_cuf_weight *w,
                                          double *d);

/* The axis-only forms alpha(y) = fn(ctx, y) (one term, no constant). */

/** Add the alpha(y)-weighted stiffness into an existing bs = 3 matrix at dof_offset. */
cupid_status cupid_cuf_assemble_weighted_add(const cupid_cuf_beam beam, cupid_cuf_weight_fn fn,
                                             void *ctx, cupid_csr K);

/** The alpha(y)-weighted stiffness in a new matrix (local numbering, cupid_cuf_pattern()). */
cupid_status cupid_cuf_assemble_weighted(const cupid_cuf_beam beam, cupid_cuf_weight_fn fn,
                                         void *ctx, cupid_csr *K);

/** Add the alpha(y)-weighted consistent mass into an existing bs = 3 matrix at dof_offset. */
cupid_status cupid_cuf_mass_weighted_add(const cupid_cuf_beam beam, cupid_cuf_weight_fn fn,
                                         void *ctx, cupid_csr M);

/** Add the alpha(y)-weighted HRZ-lumped mass into d. */
cupid_status cupid_cuf_mass_lumped_weighted(const cupid_cuf_beam beam, cupid_cuf_weight_fn fn,
                                            void *ctx, double *d);
/* ---- end of the weighted block ---- */

#ifdef __cplusplus
}
#endif
#endif
