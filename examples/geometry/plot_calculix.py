#!/usr/bin/env python3
"""The picture of examples/geometry/README.md, "Against CalculiX": the PD plate with a hole
(plate_hole_calculix.yaml, cut cells) beside CalculiX's C3D20R model of it
(tests/tools/plate_hole_ccx.py) on the node layer z = 2.5: u_y along the load's axis x = 20.5,
and s_yy / t along the line y = 20.5 through the hole's sides.

usage: /usr/bin/python3 examples/geometry/plot_calculix.py OUT PNG
  (OUT: the output folder of plate_hole_calculix.yaml, with pd.vtu; needs ccx, python3-meshio
  and gnuplot)"""
import json
import os
import subprocess
import sys
import tempfile

import meshio
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
CCX = os.path.join(HERE, "..", "..", "tests", "tools", "plate_hole_ccx.py")


def main():
    out, png = sys.argv[1], sys.argv[2]
    m = meshio.read(os.path.join(out, "pd.vtu"))
    p, u = m.points, m.point_data["displacement"]
    sig = m.point_data["stress"]
    axis = np.nonzero((abs(p[:, 0] - 20.5) < 1e-9) & (abs(p[:, 2] - 2.5) < 1e-9))[0]
    axis = axis[np.argsort(p[axis, 1])]
    line = np.nonzero((abs(p[:, 1] - 20.5) < 1e-9) & (abs(p[:, 2] - 2.5) < 1e-9))[0]
    line = line[np.argsort(p[line, 0])]
    pts = ["%g,%g,%g" % tuple(p[i]) for i in np.concatenate([axis, line])]
    with tempfile.TemporaryDirectory() as tmp:
        fe = json.loads(subprocess.run([sys.executable, CCX, os.path.join(tmp, "ccx"), "40", "6",
                                        "5.5", "16", "16", "4"] + pts, check=True,
                                       capture_output=True, text=True).stdout)["points"]
        # u_y relative to the node layer y = 0.5 (PD holds it; the FE model holds y = 0)
        ref_pd, ref_fe = u[axis[0], 1], fe[0]["u"][1]
        with open(os.path.join(tmp, "axis.dat"), "w") as f:
            for k, i in enumerate(axis):
                if k and p[i, 1] - p[axis[k - 1], 1] > 1.5:
                    f.write("\n")  # the hole: a gap in both curves
                f.write("%g %g %g\n" % (p[i, 1], u[i, 1] - ref_pd, fe[k]["u"][1] - ref_fe))
        with open(os.path.join(tmp, "line.dat"), "w") as f:
            for k, i in enumerate(line):
                x = p[i, 0]
                if k and x - p[line[k - 1], 0] > 1.5:
                    f.write("\n")  # the hole: a gap in both curves
                f.write("%g %g %g\n" % (x, sig[i, 1] / 100, fe[len(axis) + k]["stress"][1] / 100))
        gp = """set terminal pngcairo size 1200,480 font ',11'
set output '%s'
set multiplot layout 1,2 title 'Plate with a hole (40 x 40 x 6 mm, r = 5.5 mm, 100 MPa): PD with cut cells and CalculiX C3D20R, node layer z = 2.5'
set key bottom right
set grid
set xlabel 'y (mm), on x = 20.5'
set ylabel 'u_y - u_y(y = 0.5) (mm)'
set object 1 rect from 14.5, graph 0 to 25.5, graph 1 fc rgb '#eeeeee' fs solid noborder behind
plot '%s/axis.dat' u 1:2 w p pt 7 ps 0.8 lc rgb '#1f77b4' t 'PD (LPS, h = 1)', '' u 1:3 w l lw 2 lc rgb '#d62728' t 'CalculiX'
unset object 1
set key bottom center
set xlabel 'x (mm), on y = 20.5'
set ylabel 's_{yy} / t'
set yrange [0:4]
set object 2 rect from 14.5, graph 0 to 25.5, graph 1 fc rgb '#eeeeee' fs solid noborder behind
plot '%s/line.dat' u 1:2 w p pt 7 ps 0.8 lc rgb '#1f77b4' t 'PD nodal stress', '' u 1:3 w l lw 2 lc rgb '#d62728' t 'CalculiX'
unset multiplot
""" % (png, tmp, tmp)
        subprocess.run(["gnuplot"], input=gp, text=True, check=True)


if __name__ == "__main__":
    main()
