/**
 * @file model.h
 * @brief The model file (shared/reference/model-format.md) as read and validated.
 *
 * cupid_model_read() parses the YAML file with libyaml, checks every key, type and range
 * and returns a ::cupid_model_t whose fields are plain data. Every item keeps a
 * ::cupid_mark (line, column, key path) so that later stages can report semantic errors
 * against the file with cupid_model_error(). Unknown keys are errors with a
 * "did you mean" hint. All lengths are in the user's consistent units.
 */
#ifndef CUPID_MODEL_H
#define CUPID_MODEL_H

#include "cupid/base.h"
#include "cupid/expr.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Where an item stands in the model file. line/column are 1-based (0 = unknown). */
typedef struct {
  int line, column;
  char key[128]; /**< key path, e.g. "peridynamics.regions[1]" */
} cupid_mark;

/** A scalar that is absent (null), a constant, or an expression in x y z t density. */
typedef enum { CUPID_VALUE_NONE = 0, CUPID_VALUE_CONSTANT, CUPID_VALUE_EXPR } cupid_value_kind;
typedef struct {
  cupid_value_kind kind;
  double constant;
  cupid_expr expr; /**< owned; variables cupid_expr_model_vars */
} cupid_value;

/** Evaluate a value at (x, y, z, t) with @p density; NONE evaluates to 0. */
double cupid_value_eval(const cupid_value *v, double x, double y, double z, double t,
                        double density);

/** Axis-aligned box; an axis with has[a] == 0 is unbounded (lo = -inf, hi = +inf). */
typedef struct {
  double lo[3], hi[3];
  int has[3];
} cupid_box;

/** 1 if point p lies in the box, with tolerance @p tol on every bound. */
int cupid_box_contains(const cupid_box *box, const double p[3], double tol);

/** The shape of a PD region or hole (peridynamics.regions[k], peridynamics.holes[k]; issue 35). */
typedef enum {
  CUPID_SHAPE_BOX = 0,
  CUPID_SHAPE_CYLINDER = 1,
  CUPID_SHAPE_SPHERE = 2,
  CUPID_SHAPE_GEOMETRY = 3 /**< {geometry: FILE}: the volume a closed surface bounds */
} cupid_shape_kind;
/** A closed triangulated surface (src/io/surface.c): a geometry shape's boundary. */
typedef struct cupid_surface_private *cupid_surface;
typedef struct {
  cupid_shape_kind kind;
  int axis;         /**< cylinder: 0 x, 1 y, 2 z */
  double center[3]; /**< sphere: the centre; cylinder: a point of the axis (its axis entry 0) */
  double radius;    /**< cylinder, sphere */
  cupid_box box;    /**< box: the box; cylinder, sphere: the bounding box (a cylinder's ends
                         from/to along the axis, unbounded there when not given); geometry:
                         the surface's bounding box */
  cupid_surface surface; /**< geometry: its surface (owned by the model) */
  char *file;       /**< geometry: the file read (relative to the model's folder resolved) */
} cupid_shape;

/** 1 if p lies inside the closed surface (on it counts as inside): a ray's crossings. */
int cupid_surface_contains(const cupid_surface surface, const double p[3]);
/** The chords of the line through (y, z) along x inside the closed surface: *n* intervals
 *  [x[2k], x[2k+1]], sorted and disjoint, at most @p cap of them (-1: more). */
int cupid_surface_chords(const cupid_surface surface, double y, double z, double *x, int cap);
/** Calls mark(ctx, i, j, k) for every cell (i, j, k), c0 <= (i, j, k) < c1, of the lattice of
 *  spacing h from origin that a triangle passes through (its open cell: a triangle lying in a
 *  cell's face does not cut it); from several
 *  threads at once, maybe twice for a cell. */
void cupid_surface_cut_cells(const cupid_surface surface, const double origin[3], double h,
                             const int64_t c0[3], const int64_t c1[3],
                             void (*mark)(void *ctx, int64_t i, int64_t j, int64_t k), void *ctx);
/** The surface's triangles (summary.json reports them). */
int64_t cupid_surface_num_triangles(const cupid_surface surface);

/** The node order of LE section elements (L4, L9, L16; cuf.md section 3.1, MUL2_new's): node
 *  @p k (0-based) of an element with @p npe = n^2 nodes sits at grid point (a, b) of the n x n
 *  grid of natural coordinates r, s = -1 + 2 a / (n - 1), -1 + 2 b / (n - 1). Explicit section
 *  elements and meshed sections (beam.section.mesh) list their nodes in this order. */
void cupid_le_node_grid(int npe, int k, int *a, int *b);

/** 1 if point p lies in the shape (on its surface counts as inside). */
int cupid_shape_contains(const cupid_shape *shape, const double p[3]);
/** The chords of the line through (y, z) along x inside the shape (its bounding box clips
 *  them): n intervals [x[2k], x[2k+1]], sorted and disjoint, at most @p cap (-1: more). The
 *  cut-cell volumes of the PD lattice integrate them (src/pd/cut_volume.c). */
int cupid_shape_chords(const cupid_shape *shape, double y, double z, double *x, int cap);
/** 0 when a solid's surface surely misses the cube of side h at lo (1: it may cut it): within
 *  half the cube's diagonal of its centre. A geometry gives 1 (its cut cells are found
 *  triangle by triangle: cupid_surface_cut_cells). */
int cupid_shape_cuts_cell(const cupid_shape *shape, const double lo[3], double h);

typedef struct {
  char *name;
  int orthotropic;  /**< 0: isotropic (E, nu); 1: orthotropic (Ex.., nu_xy.., Gxy..) */
  double E, nu;     /**< isotropic constants */
  double Ex, Ey, Ez, nu_xy, nu_xz, nu_yz, Gxy, Gxz, Gyz; /**< orthotropic, material axes x y z */
  double density;   /**< 0 when not given */
  int has_density;
  cupid_mark mark;
} cupid_material;

typedef enum { CUPID_EXPANSION_TE = 0, CUPID_EXPANSION_LE = 1 } cupid_expansion;

/** A rectangular component of a beam section given by breakpoints (model-format beam.section). */
typedef struct {
  double *x, *z; /**< breakpoints, increasing */
  int nx, nz;
  int material; /**< index into materials, -1 = the beam's material */
  cupid_mark mark;
} cupid_section_component;

typedef struct {
  int material;                  /**< index into materials (the only one when not given) */
  double *axis_y;                /**< breakpoints along y, increasing, n_axis of them */
  int *axis_elements;            /**< elements per span, n_axis - 1 of them */
  int n_axis;
  int element_nodes;             /**< 2, 3 or 4 (B2, B3, B4) */
  int integration;               /**< 0 full (default), 1 reduced, 2 mitc; see cuf.h */
  int poisson_correction;        /**< 0 auto (default: on for TE0/TE1), 1 on, 2 off; see cuf.h */
  cupid_expansion expansion;
  int te_order;                  /**< TE order N (0 allowed: a rod; at most 20) */
  int le_nodes;                  /**< 4, 9 or 16 (L4, L9, L16); 0 when `element:` is absent (TE) */
  cupid_section_component *components;
  int n_components;
  double *section_nodes;         /**< explicit LE section: [x0, z0, x1, z1, ...] */
  int n_section_nodes;
  int *section_elements;         /**< explicit LE elements: le_nodes node indices each, 0-based
                                      (as in the file), all in [0, n_section_nodes) */
  int *section_element_material; /**< per explicit element, -1 = beam material */
  char *section_mesh;            /**< beam.section.mesh: the Gmsh file read (resolved), or NULL */
  int n_section_elements;
  cupid_mark mark;
} cupid_beam;

typedef enum { CUPID_PD_LPS = 0, CUPID_PD_BOND = 1 } cupid_pd_model_kind;
typedef enum {
  CUPID_INFLUENCE_GAUSSIAN = 0, /**< exp(-|xi|^2/delta^2), paper 000 Eq. 9 */
  CUPID_INFLUENCE_INVERSE = 1,  /**< 1/|xi| */
  CUPID_INFLUENCE_CONSTANT = 2  /**< 1 */
} cupid_influence;
typedef enum {
  CUPID_PARTIAL_NONE = 0,     /**< beta = 1 for |xi| <= delta */
  CUPID_PARTIAL_PDLAMMPS = 1, /**< Parks et al. linear rule */
  CUPID_PARTIAL_EXACT = 2     /**< volume of cell inside the sphere */
} cupid_partial_volume;
/** Correction of the PD surface effect (peridynamics.surface_correction; src/pd/surface.c). */
typedef enum {
  CUPID_SURFACE_NONE = 0,  /**< none (paper 000) */
  CUPID_SURFACE_ENERGY = 1 /**< energy method: per-node directional factors (Le & Bobaru 2018) */
} cupid_surface_correction;

typedef struct {
  cupid_box box; /**< lo < hi on every axis given; for dimension 1 only y is set; a cylinder's
                      or sphere's bounding box */
  cupid_shape shape; /**< CUPID_SHAPE_BOX (box the same), or a cylinder or sphere */
  int material;  /**< index into materials: the region's, else peridynamics.material, else the
                      only material (unused for holes) */
  cupid_mark mark;
} cupid_pd_region;

/** A pre-crack (peridynamics.precracks[k]): a rectangle on the plane x_normal = at, bounded
 *  on the two other axes; every bond whose segment crosses it is removed before the run. */
typedef struct {
  int normal;     /**< 0 x, 1 y, 2 z */
  double at;      /**< position of the plane along the normal */
  cupid_box rect; /**< bounds on the two other axes (has[] = 1, lo < hi); the normal axis has
                       has[normal] = 0 */
  cupid_mark mark;
} cupid_precrack;

typedef enum {
  CUPID_FRACTURE_STRETCH = 0, /**< critical stretch s0 (bond-based and LPS) */
  CUPID_FRACTURE_ENERGY = 1   /**< critical bond energy from G0 (LPS) */
} cupid_fracture_criterion;

#define CUPID_MAX_NO_FAIL 32 /**< no_fail boxes per model */

/** Bond breaking (peridynamics.fracture; docs/theory.md, section Fracture). */
typedef struct {
  int has_fracture;                  /**< 0: a linear elastic PD body (no key) */
  cupid_fracture_criterion criterion;
  double critical_stretch;           /**< s0 > 0 when has_critical_stretch */
  int has_critical_stretch;
  double energy_release_rate;        /**< G0 > 0 when has_energy_release_rate */
  int has_energy_release_rate;       /**< exactly one of the two is given for `stretch`;
                                          `energy` needs G0 */
  int calibration_grid;              /**< s0 from G0: 0 the continuum formula (default), 1 the
                                          lattice's own cut energy (`calibration: grid`,
                                          bond-based; docs/theory.md "Fracture") */
  int per_iteration_all;             /**< static growth: 1 all bonds over their limit per
                                          re-solve (default), 0 only the most critical one */
  cupid_mark per_iteration_mark;     /**< line > 0 when the key is given (static only) */
  cupid_box no_fail[CUPID_MAX_NO_FAIL];
  cupid_mark no_fail_marks[CUPID_MAX_NO_FAIL];
  int n_no_fail;
  cupid_mark mark;
} cupid_fracture;

/** Adaptive PD zones (peridynamics.adaptive; issue 37): the zone grows where the beam nears
 *  failure, by whole beam elements, and never shrinks. */
typedef struct {
  int has_adaptive;
  double threshold;   /**< (0, 1]: an element turns to PD when its largest principal strain
                           reaches threshold * s0 */
  double margin;      /**< horizons: a crack this close to a coupling zone grows the zone
                           (default 2) */
  double overlap;     /**< horizons: a zone that starts empty (regions: []) has overlaps of
                           the fewest beam elements that span this (default 1) */
  int has_overlap;
  cupid_mark overlap_mark;
  cupid_box within;   /**< the zone never grows outside it (has[] 0: no bound on that axis) */
  int has_within;
  int64_t max_nodes;  /**< the zone's largest node count (0: no cap) */
  int every;          /**< dynamics: time steps between two tests of the trigger (0: given
                           none, analysis.dynamic.every) */
  cupid_mark every_mark;
  cupid_mark within_mark;
  cupid_mark mark;
} cupid_adaptive;

typedef struct {
  double spacing, horizon;
  cupid_pd_model_kind model;
  cupid_influence influence;
  cupid_partial_volume partial_volume;
  cupid_surface_correction surface_correction; /**< default none */
  int dimension;   /**< 3 or 1 */
  double area;     /**< cross-section area, dimension 1 only */
  int material;    /**< default region material, -1 if not given */
  cupid_pd_region *regions;
  int n_regions;
  cupid_pd_region *holes; /**< removed from every region (peridynamics.holes) */
  int n_holes;
  cupid_precrack *precracks;
  int n_precracks;
  cupid_fracture fracture;
  cupid_adaptive adaptive;
  /** Set by a run, never read from a file: the lattice's planes at anchor + k spacing (an
   *  adaptive run's grown zone keeps its initial lattice: cupid_pd_grid_options.anchor). */
  int has_anchor;
  double anchor[3];
  /** Set by a run, never read from a file: on PD slabs under mpirun, this process owns the z
   *  layers between these planes (an adaptive run's grown zone keeps each rank's first slab:
   *  cupid_pd_grid_options.own_z). */
  int has_slab_window;
  double slab_window[2];
  cupid_mark mark;
} cupid_peridynamics;

typedef enum {
  CUPID_COUPLING_FICTITIOUS = 0,
  CUPID_COUPLING_LAGRANGE = 1,
  CUPID_COUPLING_ARLEQUIN = 2
} cupid_coupling_method;
typedef enum { CUPID_WEIGHT_LINEAR = 0, CUPID_WEIGHT_CONSTANT = 1, CUPID_WEIGHT_SMOOTH = 2 } cupid_weight;

#define CUPID_MAX_OVERLAPS 32 /**< Arlequin overlaps per model */

typedef struct {
  cupid_coupling_method method;
  double penalty;        /**< arlequin: kappa, N/m per tied node and component; 0 with penalty_auto */
  int penalty_auto;      /**< arlequin `penalty: auto`: kappa from the PD stiffness (method_arlequin.c) */
  /** arlequin: the overlaps, each a slab along one axis ({y: [..]}, {x: [..]} or {z: [..]})
   *  inside a PD region next to one of its faces (`overlap:` a box or a list of them) */
  cupid_box overlaps[CUPID_MAX_OVERLAPS];
  cupid_mark overlap_marks[CUPID_MAX_OVERLAPS];
  /** the axis each overlap's weight ramps along (0 x, 1 y, 2 z): its one axis, or `along:`
   *  for a slab bounded on more axes, which serves only the regions inside those bounds */
  int overlap_along[CUPID_MAX_OVERLAPS];
  int n_overlaps;        /**< 0 (`overlap: []`) only with an adaptive zone that starts empty */
  cupid_mark overlap_list_mark; /**< the `overlap:` list (messages about it as a whole) */
  cupid_weight weight;   /**< arlequin */
  int has_arlequin;
  /** fictitious: the fictitious FE element at a normal interface (`fictitious_fe:`): 0 removed
   *  (default, the beam element the region removed), 1 adjacent (a copy of the real element
   *  next to the interface), 2 plane (h/2 to the nearest PD plane: cupid before issue 18),
   *  3 a given length (a number); coupling.h cupid_fictitious_fe */
  int fictitious_fe;
  double fictitious_length;
  /** fictitious: `balance:` 0 none (paper 000's Eq. 38), 1 momentum (the balanced operator
   *  K - sum W_g C_g^T: momentum conserved across each interface plane, or over the whole model
   *  when a region covers part of the section), 2 global (one K - W C^T for the whole model,
   *  issue 18's form); coupling.h, docs/coupling.md */
  int balance;
  cupid_mark mark;
} cupid_coupling;

typedef enum {
  CUPID_CONSTRAINT_CLAMP = 0,        /**< all components zero on a section plane y = value */
  CUPID_CONSTRAINT_FIX = 1,          /**< listed components zero in a box */
  CUPID_CONSTRAINT_DISPLACEMENT = 2  /**< prescribed values (expressions) in a box */
} cupid_constraint_kind;

typedef struct {
  cupid_constraint_kind kind;
  double plane_y;         /**< clamp */
  double layer;           /**< clamp on PD nodes: thickness of the fixed layer (0 = default) */
  cupid_box box;          /**< fix, displacement */
  int components[3];      /**< fix: 1 for each constrained component (default all) */
  cupid_value value[3];   /**< displacement: NONE = free component */
  cupid_mark mark;
} cupid_constraint;

typedef enum { CUPID_LOAD_TRACTION = 0, CUPID_LOAD_POINT = 1, CUPID_LOAD_BODY = 2 } cupid_load_kind;

typedef struct {
  cupid_load_kind kind;
  double plane_y;         /**< traction: the end-section plane */
  cupid_box patch;        /**< traction: x/z patch (has[] = 0: whole section; has[1] is 0) */
  double at[3];           /**< point */
  cupid_box box;          /**< body (has[] all 0: the whole body) */
  cupid_value value[3];   /**< force per area (traction), force (point), per volume (body) */
  cupid_mark mark;
} cupid_load;

typedef enum { CUPID_ANALYSIS_STATIC = 0, CUPID_ANALYSIS_DYNAMIC = 1, CUPID_ANALYSIS_EVALUATE = 2 } cupid_analysis_type;
/** The solver engines (the table of solvers.h): auto picks one by its estimate. */
typedef enum {
  CUPID_SOLVER_AUTO = 0,
  CUPID_SOLVER_DIRECT = 1, /**< SuiteSparse: CHOLMOD, UMFPACK */
  CUPID_SOLVER_PETSC = 2,  /**< PETSc/MPI: Krylov, matrix-free, slabs (builds with PETSc) */
  CUPID_SOLVER_KRYLOV = 3  /**< built in: matrix-free CG/GMRES + a SuiteSparse-factored twin */
} cupid_solver_kind;
typedef enum { CUPID_INTEGRATOR_NEWMARK = 0, CUPID_INTEGRATOR_CENTRAL = 1 } cupid_integrator;

typedef struct {
  cupid_integrator integrator;
  double dt, duration;
  int every;
  double rayleigh_mass, rayleigh_stiffness;
  double newmark_beta, newmark_gamma;
  int lumped_mass;
  cupid_value initial_displacement[3];
  cupid_value initial_velocity[3];
  int has_dynamic;
  cupid_mark mark;
} cupid_dynamic;

typedef struct {
  cupid_analysis_type type;
  cupid_solver_kind solver;
  int steps;            /**< static: load steps (loads and prescribed values ramp as k/steps);
                             0 when not given (one step) */
  cupid_mark steps_mark;
  cupid_value field[3]; /**< evaluate */
  cupid_dynamic dynamic;
  cupid_mark mark;
} cupid_analysis;

typedef struct {
  char *name;
  double from[3], to[3];
  int points;
  cupid_mark mark;
} cupid_output_line;

typedef struct {
  char *name;
  double at[3];
  int stress;
  cupid_mark mark;
} cupid_output_point;

typedef struct {
  char *directory;        /**< default "out/<model file stem>" */
  int vtu, pd_nodes, plots;
  int exodus;             /**< model.exo (Exodus II) beside the VTU files (issue 35) */
  double checkpoint;      /**< seconds of run time between checkpoints (issue 36); 0: none;
                               -1 (default): every 600 s for a run estimated over 10 minutes */
  cupid_output_line *lines;
  int n_lines;
  cupid_output_point *points;
  int n_points;
  cupid_mark mark;
} cupid_output;

/** A whole model. Sections absent from the file have has_* == 0. */
typedef struct cupid_model {
  char *file;  /**< path as given */
  uint32_t source_crc;   /**< CRC-32 of the model text (a checkpoint's identity, issue 36) */
  uint64_t source_bytes; /**< its length */
  char **sets; /**< the --set overrides applied (key.path=value), for messages */
  int n_sets;
  char *title; /**< "" if absent */
  cupid_material *materials;
  int n_materials;
  int has_beam, has_peridynamics, has_coupling;
  cupid_beam beam;
  cupid_peridynamics pd;
  cupid_coupling coupling;
  cupid_constraint *constraints;
  int n_constraints;
  cupid_load *loads;
  int n_loads;
  cupid_analysis analysis;
  cupid_output output;
} cupid_model_t;
typedef cupid_model_t *cupid_model;

/** Read and validate a model file. Errors are CUPID_ERR_MODEL ("file:line:col: key: ...")
 *  or CUPID_ERR_IO (file cannot be read). Files over 16 MiB, nesting deeper than 64 levels,
 *  more than 10^6 values or alias expansions, or more than 1000 anchors are refused, so that
 *  no input can make the reader run away in time or memory. */
cupid_status cupid_model_read(const char *path, cupid_model *model);

/** Same, from a string in memory; @p name stands for the file name in messages. */
cupid_status cupid_model_read_string(const char *text, size_t length, const char *name,
                                     cupid_model *model);

/** Read with overrides: each of @p sets is "key.path=value" (keys separated by dots, list
 *  items as key[i]; the value is YAML: a number, string, [flow, list] or {flow: map}),
 *  applied to the document before it is read, so it is validated as a value of the file;
 *  messages about an override name it ("FILE: --set K=V: key: what is wrong"). */
cupid_status cupid_model_read_with(const char *path, const char *const *sets, int n_sets,
                                   cupid_model *model);
cupid_status cupid_model_read_string_with(const char *text, size_t length, const char *name,
                                          const char *const *sets, int n_sets,
                                          cupid_model *model);

/** Destroy and set *model to NULL (NULL-safe). */
void cupid_model_destroy(cupid_model *model);

/** Record a model error at @p mark: "file:line:col: key: <message>"; returns CUPID_ERR_MODEL. */
cupid_status cupid_model_error(const cupid_model_t *model, const cupid_mark *mark, const char *fmt,
                               ...) __attribute__((format(printf, 3, 4)));

#ifdef __cplusplus
}
#endif
#endif
