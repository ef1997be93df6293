/* The run kernels of the stencil path (stencil.c), instantiated once per instruction set.
 *
 * stencil.c includes this file several times, each time with
 *   PD_KLANES    nodes per vector (8 with AVX-512, 4 with AVX2, 2 with SSE2: as many as the
 *                accumulators, the node's own data and the loads of one pair keep in the
 *                registers of that set without spilling), and
 *   PD_KNAME(x)  the instance's name for x,
 * under `#pragma GCC target` for that set. The kernels see pd_work, pd_run, work_index,
 * pair_offsets and run_store of stencil.c. Not a public header: no include guard on purpose. */

#define PD_KVEC PD_KNAME(vec)
#define PD_KVEC_U PD_KNAME(vec_u)
#define PD_KIVEC PD_KNAME(ivec)
typedef double PD_KVEC __attribute__((vector_size(8 * PD_KLANES)));
typedef long long PD_KIVEC __attribute__((vector_size(8 * PD_KLANES)));
typedef double PD_KVEC_U __attribute__((vector_size(8 * PD_KLANES), aligned(8), may_alias));
#define PD_KLOAD(p) (*(const PD_KVEC_U *)(p))
#define PD_KSTORE(p, v) (*(PD_KVEC_U *)(p) = (v))

/* The ghost corrections of the nodes [i, i + len) of run R (pd_internal.h, gseg): each
 * segment of non-full nodes, clipped to them, over the kernels' own lane blocks (aligned
 * with their stores of the accumulators, so that these loads take the stored values
 * straight from the store queue: a block astride two stores waits for both to reach the
 * cache, which cost more than the corrections' arithmetic), from the components' streams.
 * The lanes outside the segment are masked to +0 (a bitwise and: whatever the neighbouring
 * records or cells hold, those lanes add exactly nothing). The accumulators (the kernels'
 * stack arrays) have a lane block of slack past the run, as the work arrays and records. */
#define PD_KGHOST_SEGMENTS(...)                                                                \
  do {                                                                                         \
    const cupid_int gr_ = R - op->runs;                                                        \
    PD_KIVEC iota_;                                                                            \
    for (int l = 0; l < PD_KLANES; l++) iota_[l] = l;                                          \
    for (cupid_int k_ = op->gptr[gr_]; k_ < op->gptr[gr_ + 1]; k_++) {                        \
      const pd_ghost_seg *g_ = op->gseg + k_;                                                  \
      const cupid_int a_ = g_->i0 > i ? g_->i0 - i : 0; /* in the call's nodes */              \
      const cupid_int b_ = g_->i0 + g_->n < i + len ? g_->i0 + g_->n - i : len;               \
      for (int t = (int)(a_ - a_ % PD_KLANES); t < b_; t += PD_KLANES) {                      \
        const cupid_int q = g_->rank + (i + t - g_->i0); /* the rank at lane 0 */             \
        const PD_KIVEC lane_ = iota_ + t;                                                      \
        const PD_KIVEC keep = (lane_ >= a_) & (lane_ < b_);                                    \
        __VA_ARGS__;                                                                           \
      }                                                                                        \
    }                                                                                          \
  } while (0)
#define PD_KMASKED(v, keep) ((PD_KVEC)((PD_KIVEC)(v) & (keep)))

/* b_i C_i u_i of a lane block at t, rank q (C_i: the sum over the node's absent entries of
 * w n n^T, pd_internal.h), into gx, gy, gz. */
#define PD_KGHOST_BCU(Bv)                                                                      \
  const PD_KVEC u0 = PD_KLOAD(X + t), u1 = PD_KLOAD(Y + t), u2 = PD_KLOAD(Z + t);              \
  const PD_KVEC bi = PD_KLOAD((Bv) + t);                                                       \
  const PD_KVEC cxx = PD_KLOAD(C + q), cyy = PD_KLOAD(C + gs + q),                             \
                czz = PD_KLOAD(C + 2 * gs + q), cyz = PD_KLOAD(C + 3 * gs + q),                \
                cxz = PD_KLOAD(C + 4 * gs + q), cxy = PD_KLOAD(C + 5 * gs + q);                \
  const PD_KVEC gx = bi * (cxx * u0 + cxy * u1 + cxz * u2);                                    \
  const PD_KVEC gy = bi * (cxy * u0 + cyy * u1 + cyz * u2);                                    \
  const PD_KVEC gz = bi * (cxz * u0 + cyz * u1 + czz * u2)

/* The first LPS pass's ghost bonds, while the nodes' u and b are in the cache (in the second
 * pass they came from memory: that cost twice the arithmetic):
 * - the dilatation: the pairs' g_s.(u+ - u-) hold sum_s g_s.u_j (absent cells read 0) but
 *   not the node's own term, -G_i.u_i with G_i the present entries' sum of g (gself), so
 *   acc -= G_i.u_i;
 * - with force, the b terms of the force, + b_i C_i u_i, into the kernel's w->gx..gz of the
 *   run's nodes (a block past the run's end lane by lane: those cells may be another
 *   thread's). */
static inline void PD_KNAME(ghost_first)(const struct cupid_pd_operator_private *op,
                                         const pd_work *w, const pd_run *R, cupid_int i, int len,
                                         double *restrict acc, int force) {
  if (R->full) return;
  const cupid_int li = work_index(w, R, i), gs = op->gstride;
  const double *restrict X = w->x + li, *restrict Y = w->y + li, *restrict Z = w->z + li;
  const double *restrict C = op->ncorr + PD_GHOST_SLACK;
  const double *restrict G0 = C + 6 * gs, *restrict G1 = G0 + gs, *restrict G2 = G1 + gs;
  double *restrict Fx = w->gx + li, *restrict Fy = w->gy + li, *restrict Fz = w->gz + li;
  PD_KGHOST_SEGMENTS({
    const PD_KVEC v = PD_KLOAD(G0 + q) * PD_KLOAD(X + t) + PD_KLOAD(G1 + q) * PD_KLOAD(Y + t) +
                      PD_KLOAD(G2 + q) * PD_KLOAD(Z + t);
    PD_KSTORE(acc + t, PD_KLOAD(acc + t) - PD_KMASKED(v, keep));
    if (force) {
      PD_KGHOST_BCU(w->b + li);
      const PD_KVEC hx = PD_KMASKED(gx, keep), hy = PD_KMASKED(gy, keep),
                    hz = PD_KMASKED(gz, keep);
      if (t + PD_KLANES <= len) {
        PD_KSTORE(Fx + t, PD_KLOAD(Fx + t) + hx);
        PD_KSTORE(Fy + t, PD_KLOAD(Fy + t) + hy);
        PD_KSTORE(Fz + t, PD_KLOAD(Fz + t) + hz);
      } else
        for (int l = 0; l < len - t; l++)
          Fx[t + l] += hx[l], Fy[t + l] += hy[l], Fz[t + l] += hz[l];
    }
  });
}

/* The second LPS pass's ghost bonds: + a_i G_i (pd_internal.h); the nodes' a are in the
 * cache (the pass reads them). */
static inline void PD_KNAME(ghost_second)(const struct cupid_pd_operator_private *op,
                                          const pd_work *w, const pd_run *R, cupid_int i,
                                          int len, double *restrict fx, double *restrict fy,
                                          double *restrict fz) {
  if (R->full) return;
  const cupid_int li = work_index(w, R, i), gs = op->gstride;
  const double *restrict A = w->a + li;
  const double *restrict G0 = op->ncorr + PD_GHOST_SLACK + 6 * gs, *restrict G1 = G0 + gs,
                         *restrict G2 = G1 + gs;
  PD_KGHOST_SEGMENTS({
    const PD_KVEC ai = PD_KMASKED(PD_KLOAD(A + t), keep);
    PD_KSTORE(fx + t, PD_KLOAD(fx + t) + ai * PD_KLOAD(G0 + q));
    PD_KSTORE(fy + t, PD_KLOAD(fy + t) + ai * PD_KLOAD(G1 + q));
    PD_KSTORE(fz + t, PD_KLOAD(fz + t) + ai * PD_KLOAD(G2 + q));
  });
}

/* The bond-based force's ghost bonds: + c_i C_i u_i (c_i in w->a). */
static inline void PD_KNAME(ghost_bond)(const struct cupid_pd_operator_private *op,
                                        const pd_work *w, const pd_run *R, cupid_int i, int len,
                                        double *restrict fx, double *restrict fy,
                                        double *restrict fz) {
  if (R->full) return;
  const cupid_int li = work_index(w, R, i), gs = op->gstride;
  const double *restrict X = w->x + li, *restrict Y = w->y + li, *restrict Z = w->z + li;
  const double *restrict C = op->ncorr + PD_GHOST_SLACK;
  PD_KGHOST_SEGMENTS({
    PD_KGHOST_BCU(w->a + li);
    PD_KSTORE(fx + t, PD_KLOAD(fx + t) + PD_KMASKED(gx, keep));
    PD_KSTORE(fy + t, PD_KLOAD(fy + t) + PD_KMASKED(gy, keep));
    PD_KSTORE(fz + t, PD_KLOAD(fz + t) + PD_KMASKED(gz, keep));
  });
}

/* a = kappa theta / m with theta = 3V/m sum_s omega beta xi_s . (u_j - u_i) (Eq. 19). */
static void PD_KNAME(run_dilatation)(const struct cupid_pd_operator_private *op,
                                     const pd_work *w, const pd_run *R, cupid_int i, int len,
                                     double *restrict theta) {
  const pd_stencil *S = &op->st;
  const cupid_int li = work_index(w, R, i);
  const double *restrict X = w->x + li, *restrict Y = w->y + li, *restrict Z = w->z + li;
  double acc[PD_RUN_MAX + PD_LANES_MAX];
  cupid_int bp[PD_PAIR_CHUNK], bm[PD_PAIR_CHUNK];
  const cupid_int *rp, *rm;
  const int half = S->n / 2;
  for (int s0 = 0; s0 < half; s0 += PD_PAIR_CHUNK) {
    const int s1 = s0 + PD_PAIR_CHUNK < half ? s0 + PD_PAIR_CHUNK : half;
    pair_offsets(op, w, R, i, s0, s1, 0, bp, bm, &rp, &rm);
    for (int t = 0; t < len; t += PD_KLANES) {
      /* Two accumulators (even and odd pairs): adds into one would chain every pair. */
      PD_KVEC g = {0}, h = {0};
      if (s0) g = PD_KLOAD(acc + t);
      for (int s = s0; s < s1; s++) {
        const cupid_int p = rp[s - s0] + t, m = rm[s - s0] + t;
        const double *gw = S->wxn + 3 * s;
        const PD_KVEC d = gw[0] * (PD_KLOAD(X + p) - PD_KLOAD(X + m)) +
                          gw[1] * (PD_KLOAD(Y + p) - PD_KLOAD(Y + m)) +
                          gw[2] * (PD_KLOAD(Z + p) - PD_KLOAD(Z + m));
        if ((s - s0) & 1) h += d;
        else g += d;
      }
      PD_KSTORE(acc + t, g + h);
    }
  }
  PD_KNAME(ghost_first)(op, w, R, i, len, acc, 0);
  run_theta(op, w, R, i, len, acc, theta);
}

/* n.d over the components that a pair class (pd_pair_plan) uses, HX, HY, HZ constants 0 or
 * 1: the unused components are neither loaded nor multiplied. On an axis n = +-1 is folded
 * into the plan's weights (w1 and nw = w15 n carry the sign: (s q) (w15 s) = w15 q), so the
 * plain difference. */
#define PD_KNDOT(HX, HY, HZ, n0, n1, n2, dx, dy, dz)                                           \
  ((HX) + (HY) + (HZ) == 1 ? ((HX) ? (dx) : (HY) ? (dy) : (dz))                                \
   : (HX) && (HY) && (HZ) ? (n0) * (dx) + (n1) * (dy) + (n2) * (dz)                            \
   : (HX) && (HY)         ? (n0) * (dx) + (n1) * (dy)                                          \
   : (HX)                 ? (n0) * (dx) + (n2) * (dz)                                          \
                          : (n1) * (dy) + (n2) * (dz))
/* The seven classes of a chunk, in the plan's order: PAIRS(NB, HX, HY, HZ, k0, k1). */
#define PD_KCLASSES(PAIRS, NB, sg)                                                             \
  do {                                                                                         \
    PAIRS(NB, 1, 1, 1, (sg)[0], (sg)[1]);                                                      \
    PAIRS(NB, 0, 1, 1, (sg)[1], (sg)[2]);                                                      \
    PAIRS(NB, 1, 0, 1, (sg)[2], (sg)[3]);                                                      \
    PAIRS(NB, 1, 1, 0, (sg)[3], (sg)[4]);                                                      \
    PAIRS(NB, 1, 0, 0, (sg)[4], (sg)[5]);                                                      \
    PAIRS(NB, 0, 1, 0, (sg)[5], (sg)[6]);                                                      \
    PAIRS(NB, 0, 0, 1, (sg)[6], (sg)[7]);                                                      \
  } while (0)

/* LPS, the first of the apply's two passes (pd_stencil_apply): the dilatation and the
 * force's terms without a, from one load of each neighbour's u and b. With d+ = n.(u+ - u_i)
 * and d- = n.(u- - u_i), the pair's dilatation term g_s.(u+ - u-) is wx (d+ - d-), and its
 * force term w15 ((b_i + b+) d+ + (b_i + b-) d-) n; the latter goes to w->gx..gz, and
 * run_lps_second adds wx (a+ - a-) n once every a is known. A dilatation pass and then a
 * whole force pass (the kernels before issue 20) loaded 16 neighbour vectors a pair, this
 * loads 8 here and 2 in the second pass (fewer for the pairs in a lattice plane or on an
 * axis: pd_pair_plan): the loops are bound by those loads and the products.
 * PD_KFB lane blocks share each pair's weights and offsets (as in run_lps_second): two with
 * AVX-512, whose 32 registers hold their 16 accumulators and node values; one where there
 * are 16 registers. */
#define PD_KFB (PD_KLANES == 8 ? 2 : 1)
#define PD_KFIRST_PAIRS_(NB, HX, HY, HZ, K0, K1, UNIFORM)                                       \
  for (int k = (K0); k < (K1); k++) {                                                          \
    const cupid_int op_ = t + rp[k - s0], om_ = t + rm[k - s0];                                \
    const double n0 = P->nrm[3 * k], n1 = P->nrm[3 * k + 1], n2 = P->nrm[3 * k + 2];           \
    const double v0 = P->nw[3 * k], v1 = P->nw[3 * k + 1], v2 = P->nw[3 * k + 2];              \
    const double w1 = P->w1[k];                                                                \
    _Pragma("GCC unroll 4") for (int b = 0; b < NB; b++) {                                     \
      const int o = b * PD_KLANES;                                                             \
      const PD_KVEC dp = PD_KNDOT(HX, HY, HZ, n0, n1, n2, PD_KLOAD(X + op_ + o) - xt[b],       \
                                  PD_KLOAD(Y + op_ + o) - yt[b], PD_KLOAD(Z + op_ + o) - zt[b]); \
      const PD_KVEC dm = PD_KNDOT(HX, HY, HZ, n0, n1, n2, PD_KLOAD(X + om_ + o) - xt[b],       \
                                  PD_KLOAD(Y + om_ + o) - yt[b], PD_KLOAD(Z + om_ + o) - zt[b]); \
      th[b] += w1 * (dp - dm);                                                                 \
      const PD_KVEC q = (UNIFORM) ? dp + dm                                                    \
                                  : (bt[b] + PD_KLOAD(B + op_ + o)) * dp +                     \
                                        (bt[b] + PD_KLOAD(B + om_ + o)) * dm;                  \
      if (HX) gx[b] += v0 * q;                                                                 \
      if (HY) gy[b] += v1 * q;                                                                 \
      if (HZ) gz[b] += v2 * q;                                                                 \
    }                                                                                          \
  }
#define PD_KFIRST_PAIRS(NB, HX, HY, HZ, K0, K1) PD_KFIRST_PAIRS_(NB, HX, HY, HZ, K0, K1, 0)
/* Where the node and its whole family share one b (pd_run's ub0, ub1): b_i + b_j = 2 b_i, so
 * the pair's term w15 ((b_i + b+) d+ + (b_i + b-) d-) n is w15 (d+ + d-) n times 2 b_i, taken
 * once per node after the pairs: neither b+ nor b- is loaded (6 neighbour loads a pair, not 8)
 * and 3 operations fewer a pair. */
#define PD_KFIRST_PAIRS_U(NB, HX, HY, HZ, K0, K1) PD_KFIRST_PAIRS_(NB, HX, HY, HZ, K0, K1, 1)
#define PD_KFIRST_GROUP(NB, PAIRS, UNIFORM)                                                     \
  do {                                                                                         \
    PD_KVEC gx[NB], gy[NB], gz[NB], th[NB], xt[NB], yt[NB], zt[NB], bt[NB];                    \
    for (int b = 0; b < NB; b++) {                                                             \
      const int u = t + b * PD_KLANES;                                                         \
      if (s0) {                                                                                \
        gx[b] = PD_KLOAD(fx + u), gy[b] = PD_KLOAD(fy + u), gz[b] = PD_KLOAD(fz + u);          \
        th[b] = PD_KLOAD(acc + u);                                                             \
      } else                                                                                   \
        gx[b] = gy[b] = gz[b] = th[b] = (PD_KVEC){0};                                          \
      xt[b] = PD_KLOAD(X + u), yt[b] = PD_KLOAD(Y + u), zt[b] = PD_KLOAD(Z + u);               \
      /* uniform: b_i only after the pairs (live across them, it cost AVX2 a register:        \
       * GCC kept an accumulator in memory) */                                                 \
      if (UNIFORM)                                                                             \
        bt[b] = (PD_KVEC){0};                                                                  \
      else                                                                                     \
        bt[b] = PD_KLOAD(B + u);                                                               \
    }                                                                                          \
    PD_KCLASSES(PAIRS, NB, sg);                                                      \
    for (int b = 0; b < NB; b++) {                                                             \
      const int u = t + b * PD_KLANES;                                                         \
      PD_KSTORE(acc + u, th[b]);                                                               \
      if ((UNIFORM) && s1 >= half) { /* the sums without b times b_i + b_j = 2 b_i */          \
        const PD_KVEC b2 = PD_KLOAD(B + u) + PD_KLOAD(B + u);                                  \
        gx[b] *= b2, gy[b] *= b2, gz[b] *= b2;                                                 \
      }                                                                                        \
      /* Between chunks on the stack; then into w->gx..gz, of this run's nodes only (the       \
       * cells past it may be another thread's). Not through memcpy: a call per run and        \
       * array cost 5% of an apply. */                                                         \
      if (s1 < half) {                                                                         \
        PD_KSTORE(fx + u, gx[b]);                                                              \
        PD_KSTORE(fy + u, gy[b]);                                                              \
        PD_KSTORE(fz + u, gz[b]);                                                              \
      } else if (u + PD_KLANES <= len) {                                                       \
        PD_KSTORE(w->gx + li + u, gx[b]);                                                      \
        PD_KSTORE(w->gy + li + u, gy[b]);                                                      \
        PD_KSTORE(w->gz + li + u, gz[b]);                                                      \
      } else                                                                                   \
        for (int l = 0; l < len - u; l++)                                                      \
          w->gx[li + u + l] = gx[b][l], w->gy[li + u + l] = gy[b][l],                          \
          w->gz[li + u + l] = gz[b][l];                                                        \
    }                                                                                          \
  } while (0)

static void PD_KNAME(run_lps_first)(const struct cupid_pd_operator_private *op,
                                    const pd_work *w, const pd_run *R, cupid_int i, int len,
                                    double *restrict theta) {
  const pd_pair_plan *P = &op->plan;
  const cupid_int li = work_index(w, R, i);
  const double *restrict X = w->x + li, *restrict Y = w->y + li, *restrict Z = w->z + li;
  const double *restrict B = w->b + li;
  double acc[PD_RUN_MAX + PD_LANES_MAX], fx[PD_RUN_MAX + PD_LANES_MAX],
      fy[PD_RUN_MAX + PD_LANES_MAX], fz[PD_RUN_MAX + PD_LANES_MAX];
  cupid_int bp[PD_PAIR_CHUNK], bm[PD_PAIR_CHUNK];
  const cupid_int *rp, *rm;
  const int half = P->n;
  /* The run's nodes of uniform b, [ua, ub) in this call's offsets (a call may start past
   * the run's first node). */
  const cupid_int ua = R->i0 + R->ub0 - i, ub = R->i0 + R->ub1 - i;
  for (int s0 = 0; s0 < half; s0 += PD_PAIR_CHUNK) {
    const int s1 = s0 + PD_PAIR_CHUNK < half ? s0 + PD_PAIR_CHUNK : half;
    const int *sg = P->seg + s0 / PD_PAIR_CHUNK * (PD_PAIR_CLASSES + 1);
    pair_offsets(op, w, R, i, s0, s1, 1, bp, bm, &rp, &rm);
    /* Lane blocks in pairs (PD_KFB) where both are of one kind: uniform (inside
     * [ub0, ub1)) or not. */
    for (int t = 0; t < len;) {
      const int u0 = t >= ua && t + PD_KLANES <= ub;
      const int u1 = t + PD_KLANES >= ua && t + 2 * PD_KLANES <= ub;
      if (PD_KFB == 2 && t + 2 * PD_KLANES <= len && u0 == u1) {
        if (u0) PD_KFIRST_GROUP(PD_KFB, PD_KFIRST_PAIRS_U, 1);
        else PD_KFIRST_GROUP(PD_KFB, PD_KFIRST_PAIRS, 0);
        t += PD_KFB * PD_KLANES;
        continue;
      }
      if (u0) PD_KFIRST_GROUP(1, PD_KFIRST_PAIRS_U, 1);
      else PD_KFIRST_GROUP(1, PD_KFIRST_PAIRS, 0);
      t += PD_KLANES;
    }
  }
  PD_KNAME(ghost_first)(op, w, R, i, len, acc, 1);
  run_theta(op, w, R, i, len, acc, theta);
}
#undef PD_KFIRST_GROUP
#undef PD_KFIRST_PAIRS_U
#undef PD_KFIRST_PAIRS
#undef PD_KFIRST_PAIRS_
#undef PD_KFB

/* LPS, the second pass: f = -V^2 (g + sum_s wx (a+ - a-) n_s) with g from run_lps_first:
 * -V^2 sum_s omega beta [ (a_i + a_j) x_s + 15 (b_i + b_j) e ] n_s (Eq. 21), the a_i terms
 * cancelling pair by pair. Its loop is light (two loads and four operations a pair and lane
 * block, fewer products in a lattice plane or on an axis), so a pair's weights and two
 * offsets would cost as much as that work: PD_KAB blocks share them, as many as the
 * registers hold at three accumulators a block. */
#define PD_KAB (PD_KLANES == 8 ? 4 : 2)
#define PD_KATERM_PAIRS(NB, HX, HY, HZ, K0, K1)                                                \
  for (int k = (K0); k < (K1); k++) {                                                          \
    const double *restrict A0 = A + t + rp[k - s0], *restrict A1 = A + t + rm[k - s0];         \
    const double g0 = P->wxn[3 * k], g1 = P->wxn[3 * k + 1], g2 = P->wxn[3 * k + 2];           \
    _Pragma("GCC unroll 8") for (int b = 0; b < NB; b++) {                                     \
      const PD_KVEC da = PD_KLOAD(A0 + b * PD_KLANES) - PD_KLOAD(A1 + b * PD_KLANES);          \
      if (HX) gx[b] += g0 * da;                                                                \
      if (HY) gy[b] += g1 * da;                                                                \
      if (HZ) gz[b] += g2 * da;                                                                \
    }                                                                                          \
  }
#define PD_KATERM_GROUP(NB)                                                                    \
  do {                                                                                         \
    PD_KVEC gx[NB], gy[NB], gz[NB];                                                            \
    const double *restrict Gx = s0 ? fx : w->gx + li, *restrict Gy = s0 ? fy : w->gy + li,     \
                           *restrict Gz = s0 ? fz : w->gz + li;                                \
    for (int b = 0; b < NB; b++) {                                                             \
      gx[b] = PD_KLOAD(Gx + t + b * PD_KLANES);                                                \
      gy[b] = PD_KLOAD(Gy + t + b * PD_KLANES);                                                \
      gz[b] = PD_KLOAD(Gz + t + b * PD_KLANES);                                                \
    }                                                                                          \
    PD_KCLASSES(PD_KATERM_PAIRS, NB, sg);                                                      \
    for (int b = 0; b < NB; b++) {                                                             \
      PD_KSTORE(fx + t + b * PD_KLANES, gx[b]);                                                \
      PD_KSTORE(fy + t + b * PD_KLANES, gy[b]);                                                \
      PD_KSTORE(fz + t + b * PD_KLANES, gz[b]);                                                \
    }                                                                                          \
  } while (0)

static void PD_KNAME(run_lps_second)(const struct cupid_pd_operator_private *op,
                                     const pd_work *w, const pd_run *R, cupid_int i, int len,
                                     double *restrict f) {
  const pd_pair_plan *P = &op->plan;
  const cupid_int li = work_index(w, R, i);
  const double *restrict A = w->a + li;
  double fx[PD_RUN_MAX + PD_LANES_MAX], fy[PD_RUN_MAX + PD_LANES_MAX],
      fz[PD_RUN_MAX + PD_LANES_MAX];
  cupid_int bp[PD_PAIR_CHUNK], bm[PD_PAIR_CHUNK];
  const cupid_int *rp, *rm;
  const int half = P->n;
  for (int s0 = 0; s0 < half; s0 += PD_PAIR_CHUNK) {
    const int s1 = s0 + PD_PAIR_CHUNK < half ? s0 + PD_PAIR_CHUNK : half;
    const int *sg = P->seg + s0 / PD_PAIR_CHUNK * (PD_PAIR_CLASSES + 1);
    pair_offsets(op, w, R, i, s0, s1, 1, bp, bm, &rp, &rm);
    int t = 0;
    for (; t + PD_KAB * PD_KLANES <= len; t += PD_KAB * PD_KLANES) PD_KATERM_GROUP(PD_KAB);
    for (; t < len; t += PD_KLANES) PD_KATERM_GROUP(1);
  }
  PD_KNAME(ghost_second)(op, w, R, i, len, fx, fy, fz);
  run_store(op, w, R, i, len, fx, fy, fz, f);
}
#undef PD_KATERM_GROUP
#undef PD_KATERM_PAIRS
#undef PD_KAB

/* f = -V^2 sum_s omega beta / x_s (c_i + c_j)/2 e n_s (bond-based). Per lane block,
 * (gx, gy, gz) += q n over the pairs of the chunk, q = wc ((c_i + c+) d+ + (c_i + c-) d-)
 * with wc tabled per chunk; the accumulators go through fx, fy, fz only between chunks. */
static void PD_KNAME(run_bond_force)(const struct cupid_pd_operator_private *op,
                                     const pd_work *w, const pd_run *R, cupid_int i, int len,
                                     double *restrict f) {
  const pd_stencil *S = &op->st;
  const cupid_int li = work_index(w, R, i);
  const double *restrict X = w->x + li, *restrict Y = w->y + li, *restrict Z = w->z + li;
  const double *restrict A = w->a + li;
  double fx[PD_RUN_MAX + PD_LANES_MAX], fy[PD_RUN_MAX + PD_LANES_MAX],
      fz[PD_RUN_MAX + PD_LANES_MAX];
  cupid_int bp[PD_PAIR_CHUNK], bm[PD_PAIR_CHUNK];
  const cupid_int *rp, *rm;
  double wc[PD_PAIR_CHUNK];
  const int half = S->n / 2;
  for (int s0 = 0; s0 < half; s0 += PD_PAIR_CHUNK) {
    const int s1 = s0 + PD_PAIR_CHUNK < half ? s0 + PD_PAIR_CHUNK : half;
    pair_offsets(op, w, R, i, s0, s1, 0, bp, bm, &rp, &rm);
    for (int s = s0; s < s1; s++) wc[s - s0] = 0.5 * S->wb[s] / S->x[s];
    for (int t = 0; t < len; t += PD_KLANES) {
      PD_KVEC gx = {0}, gy = {0}, gz = {0};
      if (s0) gx = PD_KLOAD(fx + t), gy = PD_KLOAD(fy + t), gz = PD_KLOAD(fz + t);
      const PD_KVEC xt = PD_KLOAD(X + t), yt = PD_KLOAD(Y + t), zt = PD_KLOAD(Z + t);
      const PD_KVEC ct = PD_KLOAD(A + t);
      for (int s = s0; s < s1; s++) {
        const cupid_int p = rp[s - s0] + t, m = rm[s - s0] + t;
        const double n0 = S->nrm[3 * s], n1 = S->nrm[3 * s + 1], n2 = S->nrm[3 * s + 2];
        const PD_KVEC dp = n0 * (PD_KLOAD(X + p) - xt) + n1 * (PD_KLOAD(Y + p) - yt) +
                           n2 * (PD_KLOAD(Z + p) - zt);
        const PD_KVEC dm = n0 * (PD_KLOAD(X + m) - xt) + n1 * (PD_KLOAD(Y + m) - yt) +
                           n2 * (PD_KLOAD(Z + m) - zt);
        const PD_KVEC q =
            wc[s - s0] * ((ct + PD_KLOAD(A + p)) * dp + (ct + PD_KLOAD(A + m)) * dm);
        gx += q * n0;
        gy += q * n1;
        gz += q * n2;
      }
      PD_KSTORE(fx + t, gx);
      PD_KSTORE(fy + t, gy);
      PD_KSTORE(fz + t, gz);
    }
  }
  PD_KNAME(ghost_bond)(op, w, R, i, len, fx, fy, fz);
  run_store(op, w, R, i, len, fx, fy, fz, f);
}

/* The bonds of the run's nodes to their neighbours at the entries s >= n/2 (each bond once,
 * from its lower node) whose extension e = n_s.(u_j - u_i) exceeds lim x_s: for pair s' < n/2
 * the entry is n-1-s' (offset -o_s', direction -n_s'), so e = n_s'.(u_i - u_-). Per lane
 * block the node's own displacement is loaded once and every pair of the chunk compared (as
 * the force kernels walk: three loads a pair, not six); a block with a lane over the limit
 * is walked again node by node, and only a value over the limit pays for scan_keeps (an
 * absent neighbour's padded cell reads 0; a broken bond stays over its limit as the crack
 * opens). Returns the count, or -1 if more than cap. */
static int PD_KNAME(run_stretch)(const struct cupid_pd_operator_private *op, const pd_work *w,
                                 const pd_run *R, cupid_int i, int len, double lim,
                                 pd_hit *restrict hits, int cap) {
  const pd_stencil *S = &op->st;
  const cupid_int li = work_index(w, R, i);
  const double *restrict X = w->x + li, *restrict Y = w->y + li, *restrict Z = w->z + li;
  cupid_int bp[PD_PAIR_CHUNK], bm[PD_PAIR_CHUNK];
  const cupid_int *rp, *rm;
  double thr[PD_PAIR_CHUNK];
  const int half = S->n / 2;
  int nh = 0;
  for (int s0 = 0; s0 < half; s0 += PD_PAIR_CHUNK) {
    const int s1 = s0 + PD_PAIR_CHUNK < half ? s0 + PD_PAIR_CHUNK : half;
    pair_offsets(op, w, R, i, s0, s1, 0, bp, bm, &rp, &rm);
    for (int s = s0; s < s1; s++) thr[s - s0] = lim * S->x[s];
    for (int t = 0; t < len; t += PD_KLANES) {
      const PD_KVEC xt = PD_KLOAD(X + t), yt = PD_KLOAD(Y + t), zt = PD_KLOAD(Z + t);
      PD_KIVEC over = {0};
      for (int s = s0; s < s1; s++) {
        const cupid_int m = rm[s - s0] + t;
        const double n0 = S->nrm[3 * s], n1 = S->nrm[3 * s + 1], n2 = S->nrm[3 * s + 2];
        const PD_KVEC v = n0 * (xt - PD_KLOAD(X + m)) + n1 * (yt - PD_KLOAD(Y + m)) +
                          n2 * (zt - PD_KLOAD(Z + m));
        PD_KVEC tv = {0};
        tv += thr[s - s0];
        over |= v > tv; /* lanes past the run read the slack: at worst a wasted look below */
      }
      int any = 0;
      for (int l = 0; l < PD_KLANES; l++) any |= over[l] != 0;
      if (!any) continue;
      const int end = t + PD_KLANES < len ? t + PD_KLANES : len;
      for (int s = s0; s < s1; s++) {
        const cupid_int m = rm[s - s0];
        const double n0 = S->nrm[3 * s], n1 = S->nrm[3 * s + 1], n2 = S->nrm[3 * s + 2];
        const int entry = S->n - 1 - s;
        for (int q = t; q < end; q++) {
          const double e =
              n0 * (X[q] - X[m + q]) + n1 * (Y[q] - Y[m + q]) + n2 * (Z[q] - Z[m + q]);
          if (e > thr[s - s0] && scan_keeps(op, i + q, entry)) {
            if (nh == cap) return -1;
            hits[nh++] = (pd_hit){i + q, entry};
          }
        }
      }
    }
  }
  return nh;
}

/* A run's u (by node, x y z interleaved) into the work arrays, less the reference r: with
 * the instance's instruction set the stride-3 loads become whole-vector loads and permutes
 * (the baseline build read them a pair at a time: 3% of an explicit LPS step). */
static void PD_KNAME(copy_run)(cupid_int len, const double *restrict u, double r0, double r1,
                               double r2, double *restrict x, double *restrict y,
                               double *restrict z) {
  for (cupid_int t = 0; t < len; t++) {
    x[t] = u[3 * t] - r0;
    y[t] = u[3 * t + 1] - r1;
    z[t] = u[3 * t + 2] - r2;
  }
}

static const pd_kernel_set PD_KNAME(kernels) = {
    PD_KNAME(run_dilatation), PD_KNAME(run_bond_force), PD_KNAME(run_lps_first),
    PD_KNAME(run_lps_second), PD_KNAME(run_stretch), PD_KNAME(copy_run), PD_KLANES};

#undef PD_KGHOST_BCU
#undef PD_KMASKED
#undef PD_KGHOST_SEGMENTS
#undef PD_KCLASSES
#undef PD_KNDOT
#undef PD_KSTORE
#undef PD_KLOAD
#undef PD_KVEC_U
#undef PD_KIVEC
#undef PD_KVEC
