#!/usr/bin/python3
"""Constants and the pre-crack of the LAMMPS peri/pmb notched-plate deck (README.md here).

Writes generated.lmp (included by in.notched_plate): the micromodulus cupid uses, the atom
types of the notch columns and the neighbour exclusions that remove the pre-cracked bonds.
Prints the derived numbers (micromodulus, stable time step, wave speeds, bond counts) and, with
--json FILE, stores them. Everything is in mm, tonne, s, N, MPa (cupid's units); the deck is in
SI, converted here.

Pre-crack rule (the one cupid must follow): a bond (p, q) with |xi| <= delta is removed when its
segment crosses the plane y = 20 (y_p and y_q strictly on either side; nodes never lie on it)
at a point with 0 <= x <= 10 and 0 <= z <= 3 (closed rectangle, 1e-9 mm tolerance). Bonds whose
crossing point is exactly x = 10 (the notch tip: e.g. (9.5, 20.5) - (10.5, 19.5)) are removed.
"""
import argparse
import itertools
import json
import math

import numpy as np

# ---- the setup (mm, tonne, s, N, MPa) ----
H = 1.0                        # lattice spacing
NX, NY, NZ = 40, 40, 3         # cells; nodes at cell centres
DELTA = 3.015                  # horizon
E, NU, RHO = 72000.0, 0.25, 2.44e-9
K = E / (3.0 * (1.0 - 2.0 * NU))
MU = E / (2.0 * (1.0 + NU))
V = H ** 3
CRACK_Y, CRACK_X, CRACK_Z = 20.0, (0.0, 10.0), (0.0, 3.0)
TOL = 1e-9 * H

# Notch columns that get their own atom type: x = 0.5 .. 13.5, y = 17.5 .. 22.5.
NCOL_X, NCOL_Y, COL_Y0 = 14, 6, 17


def beta_pdlammps(r):
    """cupid's PARTIAL_PDLAMMPS (src/pd/partial_volume.c) = LAMMPS's vfrac_scale."""
    if r > DELTA + 1e-12 * H:
        return 0.0
    if r <= DELTA - 0.5 * H:
        return 1.0
    return min(1.0, (DELTA + 0.5 * H - r) / H)


def stencil():
    R = int(math.ceil(DELTA / H))
    offs = []
    for d in itertools.product(range(-R, R + 1), repeat=3):
        if d == (0, 0, 0):
            continue
        r = H * math.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)
        b = beta_pdlammps(r)
        if b > 0:
            offs.append((d, r, b))
    return offs


def crossing(p, q):
    """True when the segment p-q crosses the pre-crack rectangle (closed)."""
    yp, yq = p[1] - CRACK_Y, q[1] - CRACK_Y
    if yp * yq >= 0:
        return False
    t = yp / (yp - yq)
    xc = p[0] + t * (q[0] - p[0])
    zc = p[2] + t * (q[2] - p[2])
    return (CRACK_X[0] - TOL <= xc <= CRACK_X[1] + TOL) and (CRACK_Z[0] - TOL <= zc <= CRACK_Z[1] + TOL)


def crossing_open(p, q):
    """The same with the open rectangle (crossing point strictly inside): for the record."""
    yp, yq = p[1] - CRACK_Y, q[1] - CRACK_Y
    if yp * yq >= 0:
        return False
    t = yp / (yp - yq)
    xc = p[0] + t * (q[0] - p[0])
    zc = p[2] + t * (q[2] - p[2])
    return (CRACK_X[0] + TOL < xc < CRACK_X[1] - TOL) and (CRACK_Z[0] + TOL < zc < CRACK_Z[1] - TOL)


def brute_force_bonds(offs):
    """Every node pair of the plate within the horizon (undirected), counted directly."""
    nodes = np.array([(i + 0.5, j + 0.5, k + 0.5) for k in range(NZ) for j in range(NY) for i in range(NX)]) * H
    total = removed = removed_open = 0
    per_node = np.zeros(len(nodes), dtype=int)   # initial family size after the pre-crack
    for a in range(len(nodes)):
        d = nodes - nodes[a]
        r = np.sqrt((d * d).sum(axis=1))
        for b in np.nonzero((r <= DELTA + 1e-12 * H) & (r > 0))[0]:
            if b <= a:
                continue
            total += 1
            if crossing(nodes[a], nodes[b]):
                removed += 1
            else:
                per_node[a] += 1
                per_node[b] += 1
            if crossing_open(nodes[a], nodes[b]):
                removed_open += 1
    return nodes, total, removed, removed_open, per_node


def column_type(ix, iy):
    return 2 + ix + NCOL_X * iy


def exclusions():
    """Type pairs (notch columns on either side of y = 20) whose bonds cross the pre-crack."""
    pairs = []
    # the columns reach every bond that can cross: |dy| <= delta < 3.5 h, x_c <= 10 => x <= 10 + delta
    assert NCOL_Y * H / 2 >= math.floor(DELTA / H) * H and NCOL_X * H >= CRACK_X[1] + DELTA
    for ixa, iya, ixb, iyb in itertools.product(range(NCOL_X), range(3, NCOL_Y), range(NCOL_X), range(0, 3)):
        pa = ((ixa + 0.5) * H, (COL_Y0 + iya + 0.5) * H)
        pb = ((ixb + 0.5) * H, (COL_Y0 + iyb + 0.5) * H)
        d2 = (pa[0] - pb[0]) ** 2 + (pa[1] - pb[1]) ** 2
        if d2 > (DELTA + 1e-12) ** 2:
            continue
        # the crossing point's x and z do not depend on the z offset (z stays inside [0, 3])
        if crossing((pa[0], pa[1], 1.5), (pb[0], pb[1], 1.5)):
            pairs.append((column_type(ixa, iya), column_type(ixb, iyb)))
    return pairs


def rayleigh_ratio(nu):
    """c_R / c_s from the Rayleigh equation, xi^6 - 8 xi^4 + (24 - 16 k) xi^2 - 16 (1 - k) = 0,
    k = c_s^2 / c_p^2 = (1 - 2 nu) / (2 (1 - nu)); the root in (0, 1)."""
    k = (1.0 - 2.0 * nu) / (2.0 * (1.0 - nu))
    roots = np.roots([1.0, -8.0, 24.0 - 16.0 * k, -16.0 * (1.0 - k)])
    x2 = [r.real for r in roots if abs(r.imag) < 1e-12 and 0 < r.real < 1]
    return math.sqrt(min(x2))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--json", help="write the derived numbers here")
    ap.add_argument("--out", default="generated.lmp")
    args = ap.parse_args()

    offs = stencil()
    # cupid (src/pd/operator.c, node_data): c = 18 K / S, S = sum over the full stencil of
    # omega |xi| beta V (omega = 1 for influence: constant).
    S = sum(r * b * V for _, r, b in offs)
    c_cupid = 18.0 * K / S
    c_cont = 18.0 * K / (math.pi * DELTA ** 4)
    # Stable step of the linearised bond-based PD (Silling & Askari 2005, Eq. 28 with the
    # lattice's partial volumes): dt < sqrt(2 rho / sum_j V beta c / |xi|).
    dt_crit = math.sqrt(2.0 * RHO / sum(V * b * c_cupid / r for _, r, b in offs))
    cs = math.sqrt(MU / RHO)                       # mm/s
    cp = math.sqrt((K + 4.0 * MU / 3.0) / RHO)
    cR = rayleigh_ratio(NU) * cs
    nu_ps = NU / (1.0 + NU)                        # plane stress: the 2D Poisson ratio
    cR_ps = rayleigh_ratio(nu_ps) * cs

    nodes, total, removed, removed_open, per_node = brute_force_bonds(offs)
    pairs = exclusions()

    with open(args.out, "w") as f:
        f.write("# Generated by make_deck.py: do not edit. SI units (m, kg, s, N, Pa).\n")
        f.write("# cupid's micromodulus c = 18 K / S, S = sum_stencil |xi| beta V = %.12g mm^4\n" % S)
        f.write("variable c_pmb equal %.12e    # N/m^6 (= %.10g N/mm^6)\n" % (c_cupid * 1e18, c_cupid))
        f.write("variable delta equal %.6e\n" % (DELTA * 1e-3))
        f.write("variable rho equal %.6e\n" % (RHO * 1e12))
        f.write("variable vol equal %.6e\n" % (V * 1e-9))
        f.write("variable ntypes equal %d\n" % (1 + NCOL_X * NCOL_Y))
        f.write("# notch columns x = 0.5..%.1f, y = %.1f..%.1f mm get type 2 + ix + %d iy\n"
                % (NCOL_X - 0.5, COL_Y0 + 0.5, COL_Y0 + NCOL_Y - 0.5, NCOL_X))
        f.write("variable ctype atom \"1 + (x<%.6e)*(y>%.6e)*(y<%.6e)*(1 + floor(x/%.6e) + %d*floor((y-%.6e)/%.6e))\"\n"
                % (NCOL_X * 1e-3, COL_Y0 * 1e-3, (COL_Y0 + NCOL_Y) * 1e-3, H * 1e-3, NCOL_X, COL_Y0 * 1e-3, H * 1e-3))
        f.write("# pre-crack: %d undirected bonds cross y = 20, x in [0, 10] (brute force)\n" % removed)
        for a, b in pairs:
            f.write("neigh_modify exclude type %d %d\n" % (a, b))

    out = {
        "S_mm4": S, "c_cupid_N_per_mm6": c_cupid, "c_continuum_N_per_mm6": c_cont,
        "c_ratio_cupid_over_continuum": c_cupid / c_cont,
        "stencil_bonds": len(offs),
        "dt_crit_s": dt_crit, "cs_mm_per_s": cs, "cp_mm_per_s": cp,
        "cR_mm_per_s": cR, "cR_plane_stress_mm_per_s": cR_ps,
        "bonds_total_undirected": total, "bonds_removed_closed": removed,
        "bonds_removed_open": removed_open,
        "bonds_after_precrack_directed": 2 * (total - removed),
        "exclusion_type_pairs": len(pairs),
    }
    for k, v in out.items():
        print("%-32s %s" % (k, v))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)
            f.write("\n")


if __name__ == "__main__":
    main()
