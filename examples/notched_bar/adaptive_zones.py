#!/usr/bin/python3
"""The adaptive PD zone of the notched bar over its damage, before each conversion and at the end.

    build/cupid run examples/notched_bar/notched_bar_adaptive.yaml
    /usr/bin/python3 examples/notched_bar/adaptive_zones.py [RUN_DIR] [-o PNG]

Reads RUN_DIR/adaptive.pvd (output.vtu: true; default RUN_DIR out/notched_bar_adaptive): the PD
zone and its fields before each conversion and at the end of the run. Each frame is the
lattice layer nearest z = 5 (mid-thickness), seen along z: y along the bar, x across, every PD
node a square coloured by its damage, the bar's outline in grey. Writes PNG (default
examples/notched_bar/adaptive_zones.png) with gnuplot; needs python3-meshio (Debian).
"""
import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "fracture"))
# adaptive.pvd's frames (time, points, damage), the outline's file and the panels' picture
from cbeam_zones import draw, frames, write_outline  # noqa: E402

OUTLINE = [(0, 0), (100, 0), (100, 10), (0, 10), (0, 0)]  # the bar: y [0, 100], x [0, 10]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", nargs="?", default="out/notched_bar_adaptive")
    ap.add_argument("-o", "--output", default=os.path.join(HERE, "adaptive_zones.png"))
    a = ap.parse_args()
    fs = frames(a.run)
    if not fs:
        raise SystemExit("%s: no frames in adaptive.pvd (run with output.vtu: true)" % a.run)
    outline = write_outline(a.run, "bar_outline.dat", OUTLINE)
    plots = []
    for k, (t, pts, dmg) in enumerate(fs):
        layer = min({round(float(p[2]), 6) for p in pts}, key=lambda z: abs(z - 5.0))
        dat = os.path.join(a.run, "bar_zone_%d.dat" % k)
        ys = [float(p[1]) for p in pts]
        with open(dat, "w") as f:
            for p, d in zip(pts, dmg):
                if abs(p[2] - layer) < 1e-6:
                    f.write("%g %g %g\n" % (p[1], p[0], d))
        when = ("at the end, t = %.3g us" % (t * 1e6) if k == len(fs) - 1
                else "before conversion %d, t = %.3g us" % (k + 1, t * 1e6))
        plots.append('set title "%s: %d PD nodes on y in [%g, %g]"\n'
                     'plot "%s" w l lc rgb "gray" lw 1.5 notitle, "%s" u 1:2:3 w p pt 5 ps 0.6 lc palette notitle\n'
                     % (when, len(pts), min(ys) - 0.5, max(ys) + 0.5, outline, dat))
    draw(a.output, 1000, 170 * len(fs) + 50, "%d,1" % len(fs),
         "Notched bar under a 30 MPa step (notched_bar_adaptive.yaml): the PD zone on the layer "
         "z = %g, coloured by damage; the rest is CUF beam" % layer,
         'set xrange [-1:101]\nset yrange [-1:11]\nset ylabel "x [mm]"\n', plots)


if __name__ == "__main__":
    main()
