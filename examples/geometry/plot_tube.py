#!/usr/bin/env python3
"""The picture of examples/geometry/README.md, "A tube with PD around a notch": the axial strain
on the PD zone's outer cell layer (central differences of u_y between the nodes above and below
each node, times E: the stress of uniaxial bending; a difference across the notch is its
opening), unrolled (the angle from the top against y), and the deflection along the top line
z = 9 (beam and PD) against Euler-Bernoulli's cantilever.

usage: /usr/bin/python3 examples/geometry/plot_tube.py OUT PNG
  (OUT: the output folder of tube_notch.yaml; needs python3-meshio and gnuplot)"""
import csv
import math
import os
import subprocess
import sys
import tempfile

import meshio
import numpy as np

E, RO, RI, L, T = 200000.0, 10.0, 8.0, 200.0, 10.0  # the model's steel, tube, span, traction


def main():
    out, png = sys.argv[1], sys.argv[2]
    m = meshio.read(os.path.join(out, "pd.vtu"))
    p, u = m.points, m.point_data["displacement"]
    h = 2.0 / 3.0
    r = np.hypot(p[:, 0], p[:, 2])
    outer = r > RO - 0.7  # the outer cell layer (spacing 2/3)
    at = {tuple(np.round(q / h * 2).astype(int)): i for i, q in enumerate(p)}
    F = T * math.pi * (RO ** 2 - RI ** 2)
    I = math.pi / 4 * (RO ** 4 - RI ** 4)
    with tempfile.TemporaryDirectory() as tmp:
        with open(os.path.join(tmp, "surface.dat"), "w") as f:
            for i in np.nonzero(outer)[0]:
                key = np.round(p[i] / h * 2).astype(int)
                up, down = at.get((key[0], key[1] + 2, key[2])), at.get((key[0], key[1] - 2, key[2]))
                if up is None or down is None:
                    continue
                theta = math.degrees(math.atan2(p[i, 0], p[i, 2]))
                f.write("%g %g %g\n" % (p[i, 1], theta, E * (u[up, 1] - u[down, 1]) / (2 * h)))
        rows = list(csv.DictReader(open(os.path.join(out, "line_top.csv"))))
        with open(os.path.join(tmp, "fe.dat"), "w") as fe, open(os.path.join(tmp, "pd.dat"), "w") as pd:
            for row in rows:
                (fe if row["region"] == "FE" else pd).write("%s %s\n" % (row["y"], row["uz"]))
        gp = """set terminal pngcairo size 1200,500 font ',11'
set output '%s'
set multiplot layout 1,2 title 'Notched tube (r = 10 mm, wall 2 mm), CUF beam with PD on y in [88, 112], Arlequin; 10 MPa down on the end'
set xlabel 'y (mm)'
set ylabel 'angle from the top (degrees)'
set cblabel 'E du_y/dy (MPa), PD outer cell layer'
set palette defined (0 '#313695', 1 '#74add1', 2 '#ffffbf', 3 '#f46d43', 4 '#a50026')
set cbrange [-300:600]
set xrange [88:112]
set yrange [-180:180]
set ytics 45
plot '%s/surface.dat' u 1:2:3 w p pt 5 ps 0.45 palette notitle
unset cbrange
set autoscale
set xrange [0:200]
set ytics auto
set key bottom left
set xlabel 'y (mm), on the top line z = 9'
set ylabel 'u_z (mm)'
set grid
w(y) = -%g * y**2 * (3 * %g - y) / (6 * %g * %g)
plot w(x) w l lw 2 lc rgb '#999999' t 'Euler-Bernoulli cantilever', '%s/fe.dat' w p pt 7 ps 0.6 lc rgb '#1f77b4' t 'beam (CUF)', '%s/pd.dat' w p pt 5 ps 0.6 lc rgb '#d62728' t 'PD'
unset multiplot
""" % (png, tmp, F, L, E, I, tmp, tmp)
        subprocess.run(["gnuplot"], input=gp, text=True, check=True)


if __name__ == "__main__":
    main()
