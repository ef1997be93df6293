#!/usr/bin/env python3
"""The plate with a circular hole in tension by CalculiX (C3D20R), the independent reference of
verification.pd_plate_calculix (issue 35).

The plate [0, W] x [0, W] x [0, T] with a hole of radius R about (W/2, W/2), fixed as the PD
model is (u_y = 0 on y = 0; u_x = u_z = 0 on the edge x = y = 0), pulled by a traction t on
y = W. The mesh is an O-grid of four blocks, one per side of the square: n elements along each
side, m from the hole out (graded towards the hole), k through the thickness; 20-node
hexahedra whose mid-side nodes lie on the map, so the hole's edges are curved (quadratic).
C3D20R: reduced integration, as the element the issue names.

  plate_hole_ccx.py OUT W T R n m k x,y,z [x,y,z ...]

runs ccx in OUT and prints JSON: the displacements at the points (interpolated with the
elements' own shape functions) and the stresses there (Hooke's law on the elements' gradient;
order xx yy zz yz xz xy), the node and element counts. Needs ccx (Debian's calculix-ccx)
and numpy.
"""
import json
import os
import subprocess
import sys

import numpy as np

W, T, R, TRACTION = 60.0, 3.0, 8.0, 100.0  # set from the command line
E, NU = 70000.0, 0.33
C = np.array([W / 2, W / 2])

# C3D20 nodes in natural coordinates (Abaqus/CalculiX order): corners, bottom then top edges,
# then the vertical edges.
XI = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
               [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1],
               [0, -1, -1], [1, 0, -1], [0, 1, -1], [-1, 0, -1],
               [0, -1, 1], [1, 0, 1], [0, 1, 1], [-1, 0, 1],
               [-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=float)


def block_point(b, s, t):
    """Block b's map: s along the side (0..1, counter-clockwise), t from the hole (0) out (1)."""
    th = np.radians(-45.0 + 90.0 * b + 90.0 * s)
    inner = C + R * np.array([np.cos(th), np.sin(th)])
    outer = [np.array([W, W * s]), np.array([W - W * s, W]), np.array([0.0, W - W * s]),
             np.array([W * s, 0.0])][b]
    g = t ** 1.6  # graded towards the hole
    return inner + g * (outer - inner)


def mesh(n, m, k):
    nodes, index, elems = [], {}, []

    def node(p):
        key = tuple(int(round(v * 1e7)) for v in p)
        if key not in index:
            index[key] = len(nodes)
            nodes.append(p)
        return index[key]

    for b in range(4):
        for i in range(n):
            for j in range(m):
                for q in range(k):
                    ids = []
                    for xi, eta, zeta in XI:
                        # xi radial (t), eta along the side (s), zeta through the thickness:
                        # right-handed (s runs counter-clockwise, t outwards)
                        t = (j + (xi + 1) / 2) / m
                        s = (i + (eta + 1) / 2) / n
                        z = T * (q + (zeta + 1) / 2) / k
                        xy = block_point(b, s, t)
                        ids.append(node((xy[0], xy[1], z)))
                    elems.append(ids)
    return np.array(nodes), np.array(elems)


def shape(xi):
    """The 20 shape functions and their derivatives at natural point xi."""
    N = np.zeros(20)
    dN = np.zeros((20, 3))
    for a, (p, q, r) in enumerate(XI):
        x, y, z = xi
        if a < 8:
            N[a] = (1 + p * x) * (1 + q * y) * (1 + r * z) * (p * x + q * y + r * z - 2) / 8
            dN[a, 0] = p * (1 + q * y) * (1 + r * z) * (2 * p * x + q * y + r * z - 1) / 8
            dN[a, 1] = q * (1 + p * x) * (1 + r * z) * (p * x + 2 * q * y + r * z - 1) / 8
            dN[a, 2] = r * (1 + p * x) * (1 + q * y) * (p * x + q * y + 2 * r * z - 1) / 8
        elif p == 0:
            N[a] = (1 - x * x) * (1 + q * y) * (1 + r * z) / 4
            dN[a] = [-2 * x * (1 + q * y) * (1 + r * z) / 4, q * (1 - x * x) * (1 + r * z) / 4,
                     r * (1 - x * x) * (1 + q * y) / 4]
        elif q == 0:
            N[a] = (1 - y * y) * (1 + p * x) * (1 + r * z) / 4
            dN[a] = [p * (1 - y * y) * (1 + r * z) / 4, -2 * y * (1 + p * x) * (1 + r * z) / 4,
                     r * (1 - y * y) * (1 + p * x) / 4]
        else:
            N[a] = (1 - z * z) * (1 + p * x) * (1 + q * y) / 4
            dN[a] = [p * (1 - z * z) * (1 + q * y) / 4, q * (1 - z * z) * (1 + p * x) / 4,
                     -2 * z * (1 + p * x) * (1 + q * y) / 4]
    return N, dN


def locate(X, elems, p):
    """(element, natural coordinates) of point p: Newton on the element map."""
    lo, hi = X[elems].min(axis=1), X[elems].max(axis=1)
    for e in np.nonzero(np.all((lo <= p + 1e-9) & (hi >= p - 1e-9), axis=1))[0]:
        xe, xi = X[elems[e]], np.zeros(3)
        for _ in range(30):
            N, dN = shape(xi)
            r = N @ xe - p
            if np.linalg.norm(r) < 1e-12 * W:
                break
            xi = xi - np.linalg.solve(xe.T @ dN, r)
        if np.all(np.abs(xi) <= 1 + 1e-9) and np.linalg.norm(shape(xi)[0] @ xe - p) < 1e-9 * W:
            return e, xi
    raise SystemExit("point %s is in no element" % (p,))


def write_input(path, X, elems):
    with open(path, "w") as f:
        f.write("*HEADING\nplate with a hole in tension (cupid verification.pd_plate_calculix)\n*NODE, NSET=NALL\n")
        for i, p in enumerate(X):
            f.write("%d, %.12g, %.12g, %.12g\n" % (i + 1, p[0], p[1], p[2]))
        f.write("*ELEMENT, TYPE=C3D20R, ELSET=EALL\n")
        for e, ids in enumerate(elems):
            v = [str(e + 1)] + [str(i + 1) for i in ids]
            f.write(", ".join(v[:16]) + ",\n" + ", ".join(v[16:]) + "\n")
        tol = 1e-9 * W
        f.write("*NSET, NSET=BOTTOM\n")
        f.write("".join("%d,\n" % (i + 1) for i, p in enumerate(X) if abs(p[1]) < tol))
        f.write("*NSET, NSET=EDGE\n")
        f.write("".join("%d,\n" % (i + 1) for i, p in enumerate(X) if abs(p[0]) < tol and abs(p[1]) < tol))
        f.write("*MATERIAL, NAME=ALU\n*ELASTIC\n%.12g, %.12g\n" % (E, NU))
        f.write("*SOLID SECTION, ELSET=EALL, MATERIAL=ALU\n")
        f.write("*STEP\n*STATIC\n*BOUNDARY\nBOTTOM, 2, 2\nEDGE, 1, 1\nEDGE, 3, 3\n*DLOAD\n")
        # the faces on y = W: xi = +1 of the +y block's outer elements is face S4 (2-6-7-3)
        for e, ids in enumerate(elems):
            if all(abs(X[i][1] - W) < tol for i in (ids[1], ids[5], ids[6], ids[2])):
                f.write("%d, P4, %.12g\n" % (e + 1, -TRACTION))
        f.write("*NODE PRINT, NSET=NALL\nU\n*END STEP\n")


def read_displacements(path, n):
    U = np.full((n, 3), np.nan)
    with open(path) as f:
        lines = f.read().splitlines()
    start = next(i for i, l in enumerate(lines) if "displacements" in l) + 1
    for l in lines[start:]:
        v = l.split()
        if len(v) == 4:
            U[int(v[0]) - 1] = [float(x) for x in v[1:]]
        elif U[~np.isnan(U[:, 0])].shape[0] and l.strip() and not v[0].isdigit():
            break
    if np.isnan(U).any():
        raise SystemExit("ccx's output misses displacements")
    return U


def main():
    global W, T, R, C
    out = sys.argv[1]
    W, T, R = (float(v) for v in sys.argv[2:5])
    C = np.array([W / 2, W / 2])
    n, m, k = (int(v) for v in sys.argv[5:8])
    points = [np.array([float(v) for v in a.split(",")]) for a in sys.argv[8:]]
    os.makedirs(out, exist_ok=True)
    X, elems = mesh(n, m, k)
    for e in elems:  # every element right-handed
        assert np.linalg.det(X[e].T @ shape(np.zeros(3))[1]) > 0
    write_input(os.path.join(out, "plate.inp"), X, elems)
    subprocess.run(["ccx", "-i", "plate"], cwd=out, check=True, stdout=subprocess.DEVNULL,
                   env=dict(os.environ, OMP_NUM_THREADS="1"))
    U = read_displacements(os.path.join(out, "plate.dat"), len(X))
    res = []
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    for p in points:
        e, xi = locate(X, elems, p)
        N, dN = shape(xi)
        u = N @ U[elems[e]]
        # the strain from the element's own gradient, the stress by Hooke's law
        G = U[elems[e]].T @ dN @ np.linalg.inv(X[elems[e]].T @ dN)  # du_i / dx_j
        eps = 0.5 * (G + G.T)
        sig = lam * np.trace(eps) * np.eye(3) + 2 * mu * eps
        res.append({"at": list(p), "u": list(u),
                    "stress": [sig[0, 0], sig[1, 1], sig[2, 2], sig[1, 2], sig[0, 2], sig[0, 1]]})
    json.dump({"nodes": len(X), "elements": len(elems), "points": res}, sys.stdout)
    print()


if __name__ == "__main__":
    main()
