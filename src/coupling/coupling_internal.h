/* Private to src/coupling: a row-by-row builder of bs = 3 block-CSR matrices (each row's
 * blocks are gathered through a column -> slot marker, then sorted and appended). */
#ifndef CUPID_COUPLING_INTERNAL_H
#define CUPID_COUPLING_INTERNAL_H

#include "cupid/base.h"
#include "cupid/coupling.h"
#include "cupid/solvers.h"

typedef struct {
  cupid_int ncols;
  cupid_int *slot;    /* ncols: slot of a column in the current row, or -1 */
  cupid_int *cols;    /* current row's columns */
  double *vals;       /* current row's blocks, 9 each */
  cupid_int n, cap;
  cupid_int nrows_done, nrows;
  cupid_int *rowptr;  /* nrows + 1 */
  cupid_int *col;     /* all rows */
  double *val;
  cupid_int nnz, cap_out;
} cpl_rowbuild;

cupid_status cpl_rowbuild_init(cpl_rowbuild *rb, cupid_int nrows, cupid_int ncols);
/** Add s * blk (3x3 row-major) at column c of the current row. */
cupid_status cpl_rowbuild_add(cpl_rowbuild *rb, cupid_int c, double s, const double *blk);
/** Close the current row (a zero diagonal block is added when @p diag >= 0 and absent). */
cupid_status cpl_rowbuild_end_row(cpl_rowbuild *rb, cupid_int diag);
/** Hand the matrix over as *K (the builder's arrays move into it). */
cupid_status cpl_rowbuild_finish(cpl_rowbuild *rb, cupid_csr *K);
void cpl_rowbuild_free(cpl_rowbuild *rb);

/* A node of a fictitious FE element inside the PD region: the section fit of Eqs. 33-35 of
 * the PD nodes around its section, U^{f-FE} = G U^PD per component (Eq. 36). */
typedef struct {
  cupid_int n_q;        /* real PD nodes that feed it (one plane, or two around its section) */
  cupid_int *q;         /* their indices */
  double *G;            /* M x n_q */
} cpl_fnode;

/* One interface plane normal to the axis: the fictitious element and the fits of its nodes. */
typedef struct {
  double y_i;           /* interface plane */
  int side;             /* 0: the region lies above y_i (its lower bound), 1: below */
  int region;
  cupid_int beam_node;  /* real beam node on the interface */
  cupid_cuf_beam aux;   /* the fictitious element (a one-element beam from y_i into the region) */
  int n_nodes;          /* its nodes (2 for B2, 3, 4) */
  int end_i;            /* node of aux on y_i; the others lie in the region */
  cpl_fnode *fn;        /* per node of aux; fn[end_i] is empty */
} interface_t;

struct cupid_coupling_private {
  cupid_coupling_info info;
  interface_t *iface;
  int n_iface;
  /* Lagrange coupling: tied PD nodes and their CUF weights (CSR over tied nodes). */
  cupid_int n_tied, *tied, *tptr, *tnode;
  double *tw;
  cupid_int fe_block; /* first FE block (= real PD nodes) */
  int tie_M, tie_te;  /* expansion functions per beam node; 1 for a TE expansion (lumping) */
  /* kept for cupid_coupling_lagrange_update (a cracked PD operator, the rest unchanged): the
   * tie by FE node (fptr over FE nodes, flist the tied PD nodes, fw their weights), each PD
   * node's tied index or -1, and the beam's K */
  cupid_int *tied_of, *fptr, *flist;
  double *fw;
  cupid_csr Kb;
  cupid_int n_fe;
};

/** The interfaces: region y bounds whose beam node is still used by an active pair
 *  (fills c->iface, c->n_iface: y_i, side, region, beam node). */
cupid_status cpl_find_interfaces(cupid_cuf_beam beam, const cupid_coupling_options *o,
                                 cupid_coupling_h c);

/* For every node of an extended grid (real + fictitious PD nodes): its real node, or -1 and
 * its interpolation from the FE field (Eqs. 29-30). */
typedef struct {
  cupid_int *real;                 /* ext node -> real node or -1 */
  cupid_int *fptr;                 /* ext node -> first weight (n_ext + 1) */
  cupid_int *fnode;                /* FE node (local) */
  double *fw;                      /* weight N_i F_tau (Eq. 29) */
} ext_map;

void cpl_ext_map_free(ext_map *m);
/** Map the nodes of @p ext onto the real grid or, through cupid_cuf_shape_at(), onto the FE
 *  nodes of the beam's active part (*n_fict: fictitious nodes). */
cupid_status cpl_map_extended(cupid_pd_grid ext, cupid_pd_grid grid, cupid_cuf_beam beam, int M,
                              int p, ext_map *m, cupid_int *n_fict);
/** Rows of real PD nodes: K^PD on real columns, K^{f-PD} I^{f-PD} on FE columns (Eq. 38). */
cupid_status cpl_pd_rows(cpl_rowbuild *rb, const cupid_csr_t *Ke, const ext_map *m,
                         cupid_int n_ext, cupid_int n_pd);
/** The fictitious FE element the options ask for (the model's coupling.fictitious_fe),
 *  checked. */
cupid_status cpl_fictitious_fe_choice(const cupid_coupling_options *o, cupid_fictitious_fe *kind,
                                      double *length);
/** 1 if region @p b spans the beam's whole cross-section (missing x/z bounds count as spanning). */
int cpl_region_full(const cupid_cuf_beam beam, const cupid_box *b);
/* The pieces of Eq. 38 that do not depend on the PD operator: the extended grid (real +
 * fictitious PD nodes) with its map, and the rows of the real FE nodes, assembled (n_fe_nodes
 * block rows over all n_pd + n_fe_nodes block columns). The coupled matrix is the PD rows of
 * any PD operator on ext (cpl_pd_rows) stacked on Kfe; the matrix-free operator
 * (src/coupling/operator.c) applies the PD operator instead. */
typedef struct {
  cupid_pd_grid ext;
  ext_map map;
  cupid_int n_ext, n_fict, n_pd;
  cupid_csr Kfe;
} cpl_parts;

/** Build the parts (either kind of region; fills c's interfaces and info). */
cupid_status cpl_parts_build(cupid_cuf_beam beam, cupid_pd_grid grid,
                             const cupid_coupling_options *o, cupid_coupling_h c, cpl_parts *p);
/** The coupled matrix of Eq. 38 with the PD operator of @p pd on the extended grid. */
cupid_status cpl_parts_assemble(const cpl_parts *p, const cupid_pd_operator_options *pd,
                                cupid_csr *K);
/** The coupled matrix of Eq. 38 with the PD operator @p op on the extended grid (its broken
 *  bonds included). */
cupid_status cpl_parts_assemble_op(const cpl_parts *p, const cupid_pd_operator op, cupid_csr *K);
void cpl_parts_free(cpl_parts *p);
/** The options of an extended grid: the whole one (@p cut NULL or a whole grid's partition),
 *  or the slab cut like the real grid's slab @p cut (same z window and halo). */
cupid_pd_grid_options cpl_ext_grid_options(double h, const cupid_pd_grid_partition *cut);
/** The extended grid of a coupling with some region over part of the section (partial.c). */
cupid_status cpl_partial_extended_grid(cupid_cuf_beam beam, const cupid_coupling_options *o,
                                       const cupid_pd_grid_partition *cut, cupid_pd_grid *ext);
/** The parts when some region covers part of the section (src/coupling/partial.c). */
cupid_status cpl_partial_parts(cupid_cuf_beam beam, cupid_pd_grid grid,
                               const cupid_coupling_options *o, cupid_coupling_h c, cpl_parts *p);

/** The real grid's partition of a fictitious-node operator, and its real PD nodes (the
 *  slab's, on a slab). */
const cupid_pd_grid_partition *cpl_operator_partition(const cupid_coupling_operator A,
                                                      cupid_int *n_pd);

/** The Arlequin PD weights 1 - alpha(x_i) of the grid's nodes (*wn allocated; *wmin their
 *  smallest) (src/coupling/arlequin.c). */
cupid_status cpl_arlequin_pd_weights(cupid_pd_grid grid, const cupid_arlequin_options *o,
                                     double **wn, double *wmin);

#endif
