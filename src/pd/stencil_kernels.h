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

/* a = kappa theta / m with theta = 3V/m sum_s omega beta xi_s . (u_j - u_i) (Eq. 19). */
static void PD_KNAME(run_dilatation)(const struct cupid_pd_operator_private *op,
                                     const pd_work *w, const pd_run *R, cupid_int i, int len,
                                     double *restrict theta) {
  const pd_stencil *S = &op->st;
  const cupid_int li = work_index(w, R, i);
  const double *restrict X = w->x + li, *restrict Y = w->y + li, *restrict Z = w->z + li;
  double acc[PD_RUN_MAX + PD_LANES_MAX];
  cupid_int rp[PD_PAIR_CHUNK], rm[PD_PAIR_CHUNK];
  const int half = S->n / 2;
  for (int s0 = 0; s0 < half; s0 += PD_PAIR_CHUNK) {
    const int s1 = s0 + PD_PAIR_CHUNK < half ? s0 + PD_PAIR_CHUNK : half;
    pair_offsets(op, w, R, i, s0, s1, rp, rm);
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
  if (!R->full)
    for (int t = 0; t < len; t++) {
      const cupid_int n = i + t;
      if (op->full[n]) continue;
      const double *G = op->gself + 3 * n; /* ghost bonds: -(sum over them of g).(0 - u_i) */
      acc[t] -= G[0] * X[t] + G[1] * Y[t] + G[2] * Z[t];
    }
  if (op->bslot)
    for (int t = 0; t < len; t++)
      if (op->bslot[i + t] >= 0) acc[t] -= broken_dilatation(op, w, R, i + t);
  double *restrict a = w->a + li;
  const double *restrict mi = op->m + i, *restrict ki = op->kappa + i;
  const double V3 = 3.0 * op->V;
  for (int t = 0; t < len; t++) {
    const double th = V3 * acc[t] / mi[t];
    a[t] = ki[t] * th / mi[t];
    acc[t] = th;
  }
  if (theta) memcpy(theta + i, acc, (size_t)len * sizeof(double));
}

/* The pair loop of the force kernels: per lane block, (gx, gy, gz) += q n over the pairs
 * of the chunk, q = PAIR (with d+ = n.(u+ - u_i) = dp, d- = n.(u- - u_i) = dm, and the
 * pair's weights w1, w2 that CONSTS tables per chunk in c1, c2); the accumulators go
 * through fx, fy, fz only between chunks. */
#define PD_KFORCE_PAIRS(NODE_LOAD, CONSTS, PAIR)                                               \
  double fx[PD_RUN_MAX + PD_LANES_MAX], fy[PD_RUN_MAX + PD_LANES_MAX],                       \
      fz[PD_RUN_MAX + PD_LANES_MAX];                                                         \
  cupid_int rp[PD_PAIR_CHUNK], rm[PD_PAIR_CHUNK];                                            \
  double c1[PD_PAIR_CHUNK], c2[PD_PAIR_CHUNK];                                               \
  const int half = S->n / 2;                                                                 \
  for (int s0 = 0; s0 < half; s0 += PD_PAIR_CHUNK) {                                         \
    const int s1 = s0 + PD_PAIR_CHUNK < half ? s0 + PD_PAIR_CHUNK : half;                    \
    pair_offsets(op, w, R, i, s0, s1, rp, rm);                                               \
    for (int s = s0; s < s1; s++) CONSTS                                                     \
    for (int t = 0; t < len; t += PD_KLANES) {                                               \
      PD_KVEC gx = {0}, gy = {0}, gz = {0};                                                  \
      if (s0) gx = PD_KLOAD(fx + t), gy = PD_KLOAD(fy + t), gz = PD_KLOAD(fz + t);          \
      const PD_KVEC xt = PD_KLOAD(X + t), yt = PD_KLOAD(Y + t), zt = PD_KLOAD(Z + t);        \
      NODE_LOAD                                                                              \
      for (int s = s0; s < s1; s++) {                                                        \
        const cupid_int p = rp[s - s0] + t, m = rm[s - s0] + t;                              \
        const double n0 = S->nrm[3 * s], n1 = S->nrm[3 * s + 1], n2 = S->nrm[3 * s + 2];     \
        const double w1 = c1[s - s0], w2 = c2[s - s0];                                       \
        (void)w2;                                                                            \
        const PD_KVEC dp = n0 * (PD_KLOAD(X + p) - xt) + n1 * (PD_KLOAD(Y + p) - yt) +       \
                           n2 * (PD_KLOAD(Z + p) - zt);                                      \
        const PD_KVEC dm = n0 * (PD_KLOAD(X + m) - xt) + n1 * (PD_KLOAD(Y + m) - yt) +       \
                           n2 * (PD_KLOAD(Z + m) - zt);                                      \
        const PD_KVEC q = PAIR;                                                              \
        gx += q * n0;                                                                        \
        gy += q * n1;                                                                        \
        gz += q * n2;                                                                        \
      }                                                                                      \
      PD_KSTORE(fx + t, gx);                                                                 \
      PD_KSTORE(fy + t, gy);                                                                 \
      PD_KSTORE(fz + t, gz);                                                                 \
    }                                                                                        \
  }

/* f = -V^2 sum_s omega beta [ (a_i + a_j) x_s + 15 (b_i + b_j) e ] n_s (LPS, Eq. 21). */
static void PD_KNAME(run_lps_force)(const struct cupid_pd_operator_private *op,
                                    const pd_work *w, const pd_run *R, cupid_int i, int len,
                                    double *restrict f) {
  const pd_stencil *S = &op->st;
  const cupid_int li = work_index(w, R, i);
  const double *restrict X = w->x + li, *restrict Y = w->y + li, *restrict Z = w->z + li;
  const double *restrict A = w->a + li, *restrict B = w->b + li;
  PD_KFORCE_PAIRS(const PD_KVEC bt = PD_KLOAD(B + t);,
                  (c1[s - s0] = S->wb[s] * S->x[s], c2[s - s0] = 15.0 * S->wb[s]);,
                  w1 * (PD_KLOAD(A + p) - PD_KLOAD(A + m)) +
                      w2 * ((bt + PD_KLOAD(B + p)) * dp + (bt + PD_KLOAD(B + m)) * dm))
  run_store(op, w, R, i, len, fx, fy, fz, f);
}

/* f = -V^2 sum_s omega beta / x_s (c_i + c_j)/2 e n_s (bond-based). */
static void PD_KNAME(run_bond_force)(const struct cupid_pd_operator_private *op,
                                     const pd_work *w, const pd_run *R, cupid_int i, int len,
                                     double *restrict f) {
  const pd_stencil *S = &op->st;
  const cupid_int li = work_index(w, R, i);
  const double *restrict X = w->x + li, *restrict Y = w->y + li, *restrict Z = w->z + li;
  const double *restrict A = w->a + li;
  PD_KFORCE_PAIRS(const PD_KVEC ct = PD_KLOAD(A + t);,
                  (c1[s - s0] = 0.5 * S->wb[s] / S->x[s], c2[s - s0] = 0.0);,
                  w1 * ((ct + PD_KLOAD(A + p)) * dp + (ct + PD_KLOAD(A + m)) * dm))
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
  cupid_int rp[PD_PAIR_CHUNK], rm[PD_PAIR_CHUNK];
  double thr[PD_PAIR_CHUNK];
  const int half = S->n / 2;
  int nh = 0;
  for (int s0 = 0; s0 < half; s0 += PD_PAIR_CHUNK) {
    const int s1 = s0 + PD_PAIR_CHUNK < half ? s0 + PD_PAIR_CHUNK : half;
    pair_offsets(op, w, R, i, s0, s1, rp, rm);
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

static const pd_kernel_set PD_KNAME(kernels) = {
    PD_KNAME(run_dilatation), PD_KNAME(run_lps_force), PD_KNAME(run_bond_force),
    PD_KNAME(run_stretch), PD_KLANES};

#undef PD_KFORCE_PAIRS
#undef PD_KSTORE
#undef PD_KLOAD
#undef PD_KVEC_U
#undef PD_KIVEC
#undef PD_KVEC
