/* Private data and kernels of the CUF beam (src/cuf). See include/cupid/cuf.h for conventions. */
#ifndef CUPID_CUF_INTERNAL_H
#define CUPID_CUF_INTERNAL_H

#include "cupid/cuf.h"

#define CUF_MAX_N 4  /* nodes per direction of a section element (L16) */
#define CUF_MAX_P 4  /* nodes per beam element (B4) */
#define CUF_MAX_GAUSS 32
/* Below this many scalar DOFs the loops run serially: a parallel region costs more than the
 * work (and much more on oversubscribed cores). */
#define CUF_PARALLEL_DOFS 30000
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Voigt order used everywhere in src/cuf (and for stress output): xx yy zz yz xz xy. */
enum { CUF_XX = 0, CUF_YY, CUF_ZZ, CUF_YZ, CUF_XZ, CUF_XY };

/* Voigt index of the strain that displacement component k produces through the derivative
 * d/dd (d = 0: x, 1: y, 2: z): e.g. u_x,y -> gamma_xy. (cuf.md 1.1, rows of B(g).) */
extern const int cuf_vidx[3][3];

/* A tensor-product isoparametric quadrilateral with n nodes per direction. */
typedef struct {
  int n, npe;
  int ia[16], ib[16]; /* grid index (r, s) of each node */
  double grid[CUF_MAX_N];
} cuf_quad;

typedef struct {
  double C[36];  /* 6x6, Voigt order above (the corrected law when poisson_corrected) */
  double R[36];  /* Poisson correction: C_3D - C, the contraction part (docs/theory.md) */
  double density;
} cuf_material;

/* One axis integration "part" (cuf_axis_parts): which C entries it takes and how the axis
 * functions of the test and trial side are evaluated. */
typedef struct {
  unsigned char cmask[36]; /* 1 where C[r][c] belongs to this part */
  int tilde_test, tilde_trial; /* MITC: tied (interpolated) axis functions */
  int reduced;                 /* selective reduced: reduced Gauss rule */
} cuf_part;

struct cupid_cuf_beam_private {
  /* materials */
  int n_mat;
  cuf_material *mat;
  /* expansion */
  cupid_expansion expansion;
  int te_order;
  int M;            /* expansion functions per beam node */
  int *te_a, *te_b; /* TE exponents of x and z */
  double xc, zc, h; /* TE centring and scale */
  /* section mesh (LE elements or TE integration cells) */
  cuf_quad quad;
  cupid_int n_snodes;
  double *sxz;        /* 2 per node */
  cupid_int n_selem;
  cupid_int *sconn;   /* npe per element */
  int *smat;          /* material per element */
  double *sbox;       /* 4 per element: xmin xmax zmin zmax */
  unsigned char *srect; /* 1: affine axis-aligned rectangle (exact clipping/inversion) */
  cupid_int *n2e_ptr, *n2e; /* section node -> elements */
  int sec_ng;         /* section Gauss points per direction for the stiffness */
  double *te_E;       /* TE: section integrals per cell, 9 * M * M each */
  double area, bbox[4], size;
  /* axis */
  int p;              /* nodes per beam element */
  cupid_int n_bnodes, n_belem;
  double *by;         /* y of each beam node */
  double ymin, ymax;
  double time; /* t of the model's expressions (cupid_cuf_set_time; 0 by default) */
  int integration;
  int poisson_corrected; /* 1: every C is the corrected law (cuf_poisson_correct) */
  int poisson_split;     /* TE1: R acts on the constant-term axial strain (docs/theory.md) */
  int n_parts;
  cuf_part parts[4];
  /* coupling hooks */
  cupid_int dof_offset;
  unsigned char *active; /* n_belem * n_selem */
  double tol_xz, tol_y;
};

/* ---- shape.c ---- */
/* Gauss-Legendre rule with n points on [-1, 1] (n <= CUF_MAX_GAUSS). */
void cuf_gauss(int n, double *x, double *w);
/* 1D Lagrange polynomials through nodes[0..n-1] and their derivatives at xi. */
void cuf_lagrange(int n, const double *nodes, double xi, double *N, double *dN);
/* Quadrilateral type with n = 2, 3, 4 nodes per direction (L4, L9, L16). */
void cuf_quad_init(cuf_quad *q, int n);
/* Shape functions and parametric derivatives at (r, s). */
void cuf_quad_shape(const cuf_quad *q, double r, double s, double *F, double *Fr, double *Fs);
/* Equally spaced beam-element nodes on [-1, 1]. */
void cuf_beam_nodes(int p, double *xi);

/* ---- section.c ---- */
/* Needs b->mat / b->n_mat; model may be NULL (messages without a file position). */
cupid_status cuf_section_build(struct cupid_cuf_beam_private *b, const cupid_beam *def,
                               const cupid_model_t *model);
/* Geometry at (r, s) of section element e: x, z, det J, and inverse Jacobian
 * [dr/dx, ds/dx, dr/dz, ds/dz]; returns the shape values of the geometric nodes in F. */
double cuf_section_map(const struct cupid_cuf_beam_private *b, cupid_int e, double r, double s,
                       double *x, double *z, double inv[4]);
/* Expansion functions of section element e at (r, s): m local functions (LE: npe, TE: M),
 * F, F_x, F_z; returns det J and the physical point. */
int cuf_section_functions(const struct cupid_cuf_beam_private *b, cupid_int e, double r,
                          double s, double *F, double *Fx, double *Fz, double *x, double *z,
                          double *detJ);
/* Global expansion index of local function a of element e (LE: node, TE: a). */
static inline int cuf_tau(const struct cupid_cuf_beam_private *b, cupid_int e, int a) {
  return b->expansion == CUPID_EXPANSION_LE ? (int)b->sconn[e * b->quad.npe + a] : a;
}
/* Number of local expansion functions of a section element. */
static inline int cuf_local_m(const struct cupid_cuf_beam_private *b) {
  return b->expansion == CUPID_EXPANSION_LE ? b->quad.npe : b->M;
}
/* Parametric coordinates of (x, z) in element e; 1 if inside (tolerance). */
int cuf_section_invert(const struct cupid_cuf_beam_private *b, cupid_int e, double x, double z,
                       double *r, double *s);
/* Section integrals E[(3 d + d') m m + s m + tau] = int G_d(F_s) G_d'(F_tau), G_0 = d/dx,
 * G_1 = identity, G_2 = d/dz, over element e (m = cuf_local_m), with ng points per direction. */
void cuf_section_integrals(const struct cupid_cuf_beam_private *b, cupid_int e, int ng,
                           double *E);
/* The same with the integrand times fn(ctx, x, z) (fn NULL: 1); the Arlequin weights. */
void cuf_section_integrals_weighted(const struct cupid_cuf_beam_private *b, cupid_int e, int ng,
                                    cupid_cuf_section_weight_fn fn, void *ctx, double *E);

/* ---- beam_mesh.c ---- */
cupid_status cuf_axis_build(struct cupid_cuf_beam_private *b, const cupid_beam *def,
                            const cupid_model_t *model);
/* Beam element containing y (-1 if outside; at a shared node the lower element). */
cupid_int cuf_axis_locate(const struct cupid_cuf_beam_private *b, double y, double *xi);
/* Axis shape functions of element e at xi: N and dN/dy. */
void cuf_axis_shape(const struct cupid_cuf_beam_private *b, cupid_int e, double xi, double *N,
                    double *dNdy);

/* ---- nucleus.c ---- */
cupid_status cuf_material_stiffness(const cupid_material *m, double C[36]);
/* Replace C by the Poisson-locking-corrected law (sigma_xx = sigma_zz = 0 imposed) and
 * return the remainder R = C_3D - C_corrected (symmetric positive semi-definite, zero on the
 * strains with sigma_xx = sigma_zz = 0). */
cupid_status cuf_poisson_correct(double C[36], double R[36]);
void cuf_parts_init(struct cupid_cuf_beam_private *b);
/* Axis integrals of beam element e for every part: I[((P * 4) + 2 dt + dr) p p + j p + i]
 * = int H_dt(N_j) H_dr(N_i) dy, H_0 = N, H_1 = dN/dy (tilde functions for MITC parts). */
void cuf_axis_integrals(const struct cupid_cuf_beam_private *b, cupid_int e, double *I);
/* Dense nucleus block of a (beam element, section group): Ke is (3 m p)^2, row (s, j, k),
 * column (tau, i, h), index ((a * p + j) * 3 + k). E: section integrals of the group (9 m^2),
 * material mat, I from cuf_axis_integrals. Ke is overwritten. */
void cuf_pair_matrix(const struct cupid_cuf_beam_private *b, int m, const double *E, int mat,
                     const double *I, double *Ke);

/* ---- loads.c ---- */
/* Quadrature points of section element e clipped to rect = [xlo, xhi, zlo, zhi] (see loads.c);
 * r, s, w must hold 64 ng^2 entries. Returns the number of points. */
int cuf_clip_rule(const struct cupid_cuf_beam_private *b, cupid_int e, const double rect[4], int ng,
                  double *r, double *s, double *w);

/* ---- post.c ---- */
/* Find an active pair containing (x, y, z): beam element, section element and local coords. */
int cuf_locate(const struct cupid_cuf_beam_private *b, double x, double y, double z, cupid_int *be,
               cupid_int *se, double *xi, double *r, double *s);

/* ---- constraints.c ---- */
/* TE: coefficients c[3 tau + k] of the L2 projection of fn(., y, .) on the expansion. */
cupid_status cuf_te_project(const struct cupid_cuf_beam_private *b, double y, cupid_cuf_field_fn fn,
                            void *ctx, double *c);

/* ---- misc ---- */
/* Evaluate a model value; NONE -> 0. */
/** A model value at p and time t (cupid_cuf_set_time: a dynamic run's conditions). */
double cuf_value(const cupid_value *v, const double p[3], double density, double t);
/** What value_field callbacks read: the values and the time to evaluate them at. */
typedef struct {
  const cupid_value *v;
  double t;
} cuf_values_at;

#endif
