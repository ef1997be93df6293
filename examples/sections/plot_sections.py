#!/usr/bin/env python3
"""The picture of examples/sections/README.md: the beam's 3D reconstruction (beam.vtu) cut at
its clamped end (the section mesh as cupid built it from the Gmsh file) and, for the C-beam, at
its free end displaced (magnified); for the tube in torsion, the in-plane displacement of the
end section's outer points as arrows (a rigid rotation of the section: Saint-Venant's torsion).

usage: /usr/bin/python3 examples/sections/plot_sections.py OUT_TUBE OUT_CBEAM PNG
  (OUT_*: the output folders of tube_torsion.yaml and cbeam_mesh_l9.yaml; needs python3-meshio
  and gnuplot)"""
import os
import subprocess
import sys
import tempfile

import meshio
import numpy as np


def faces(out, scale):
    """The hexahedra's faces on the first and last section plane: (x, z) loops, the last ones
    displaced by scale * u."""
    m = meshio.read(os.path.join(out, "beam.vtu"))
    p, u = m.points, m.point_data["displacement"]
    y0, y1 = p[:, 1].min(), p[:, 1].max()
    hexes = np.concatenate([c.data for c in m.cells if c.type == "hexahedron"])
    first, last = [], []
    for h in hexes:
        for quad in (h[:4], h[4:]):
            y = p[quad, 1]
            if np.all(abs(y - y0) < 1e-9):
                first.append(p[quad][:, [0, 2]])
            elif np.all(abs(y - y1) < 1e-9):
                last.append(p[quad][:, [0, 2]] + scale * u[quad][:, [0, 2]])
    return first, last


def arrows(out, scale, path):
    """The end section's outer points and their in-plane displacement (x, z) * scale."""
    m = meshio.read(os.path.join(out, "beam.vtu"))
    p, u = m.points, m.point_data["displacement"]
    y1 = p[:, 1].max()
    r = np.hypot(p[:, 0], p[:, 2])
    pick = (abs(p[:, 1] - y1) < 1e-9) & (r > r.max() - 1e-6)
    seen = set()
    with open(path, "w") as f:
        for k in np.flatnonzero(pick):
            key = (round(p[k, 0], 6), round(p[k, 2], 6))
            if key in seen:
                continue
            seen.add(key)
            f.write("%.9g %.9g %.9g %.9g\n" % (p[k, 0], p[k, 2], scale * u[k, 0], scale * u[k, 2]))


def write(loops, path):
    with open(path, "w") as f:
        for q in loops:
            for k in range(5):
                f.write("%.9g %.9g\n" % tuple(q[k % 4]))
            f.write("\n")


def main():
    tube, cbeam, png = sys.argv[1:4]
    with tempfile.TemporaryDirectory() as tmp:
        t0, _ = faces(tube, 0.0)
        arrows(tube, 1e5, os.path.join(tmp, "ta.dat"))
        c0, c1 = faces(cbeam, 3.0)
        for name, loops in (("t0", t0), ("c0", c0), ("c1", c1)):
            write(loops, os.path.join(tmp, name + ".dat"))
        gp = """set terminal pngcairo size 1200,560 font ',11'
set output '%s'
set multiplot layout 1,2
set size ratio -1
set xlabel 'x (mm)'; set ylabel 'z (mm)'
set key top right box opaque
set title 'Tube (tube\\_section.geo, 64 L9): the section, and u at the end (x 1e5)'
set xrange [-14:14]; set yrange [-14:14]
plot '%s/t0.dat' w l lc rgb '#1f77b4' lw 1 t 'section mesh (y = 0)', '%s/ta.dat' w vectors head filled size 0.3,20 lc rgb '#d62728' lw 1.5 t 'y = 200: u (x 1e5)'
set autoscale y
set title 'C-beam (cbeam\\_section.msh, 14 L9): y = 0, and the tip (u x 3)'
set xrange [-20:80]
plot '%s/c0.dat' w l lc rgb '#1f77b4' lw 1.5 t 'y = 0', '%s/c1.dat' w l lc rgb '#d62728' lw 1 t 'y = 1000, u x 3'
unset multiplot
""" % (png, tmp, tmp, tmp, tmp)
        subprocess.run(["gnuplot"], input=gp, text=True, check=True)


if __name__ == "__main__":
    main()
