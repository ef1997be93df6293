#!/usr/bin/python3
"""The adaptive zone of the notched C-beam over its damage, on the section, at each conversion.

    build/cupid run examples/fracture/cbeam_adaptive.yaml
    /usr/bin/python3 examples/fracture/cbeam_zones.py [RUN_DIR] [-o PNG] [--at 499.5]

Reads RUN_DIR/adaptive.pvd (output.vtu: true; default RUN_DIR out/fracture/cbeam_adaptive): the
PD zone and its fields before each conversion and at the end. Each frame is drawn as the
lattice layer nearest y = AT (the crack's plane is y = 500: the layers either side of it hold
the broken bonds' ends), seen along y: x across, z up, every PD node a square coloured by its
damage, the C-section's outline in grey. Writes PNG (default
examples/fracture/cbeam_zones.png) with gnuplot; needs python3-meshio (Debian).
"""
import argparse
import os
import re
import subprocess

import meshio

HERE = os.path.dirname(os.path.abspath(__file__))
# the section of cbeam_adaptive.yaml: web x [0, 5], z [-50, 50]; flanges x [5, 50]
OUTLINE = [(0, -50), (50, -50), (50, -45), (5, -45), (5, 45), (50, 45), (50, 50), (0, 50), (0, -50)]


def frames(run):
    pvd = open(os.path.join(run, "adaptive.pvd")).read()
    out = []
    for t, f in re.findall(r'timestep="([^"]+)"[^>]*file="(adaptive_pd_\d+\.vtu)"', pvd):
        m = meshio.read(os.path.join(run, f))
        out.append((float(t), m.points, m.point_data["damage"]))
    return out


def write_outline(run, name, points):
    """A polyline (x, y pairs) as a gnuplot data file in run; its path."""
    path = os.path.join(run, name)
    with open(path, "w") as f:
        f.write("".join("%g %g\n" % p for p in points))
    return path


def draw(output, width, height, layout, title, axes, plots):
    """The frames' panels in one PNG: plots holds each panel's gnuplot commands, axes the ranges
    and labels they share, damage coloured from 0 to 0.6."""
    script = ('set terminal pngcairo size %d,%d font ",9" noenhanced\nset output "%s"\n'
              'set multiplot layout %s title "%s"\nset size ratio -1\n%s'
              'set cbrange [0:0.6]\nset palette rgbformulae 22,13,-31\n%s\nunset multiplot\n'
              % (width, height, output, layout, title, axes, "".join(plots)))
    subprocess.run(["gnuplot"], check=True, input=script.encode())
    print("wrote", output)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", nargs="?", default="out/fracture/cbeam_adaptive")
    ap.add_argument("-o", "--output", default=os.path.join(HERE, "cbeam_zones.png"))
    ap.add_argument("--at", type=float, default=499.5)
    a = ap.parse_args()
    fs = frames(a.run)
    if not fs:
        raise SystemExit("%s: no frames in adaptive.pvd (run with output.vtu: true)" % a.run)
    outline = write_outline(a.run, "cbeam_outline.dat", OUTLINE)
    plots = []
    for k, (t, pts, dmg) in enumerate(fs):
        layer = min({round(float(p[1]), 6) for p in pts}, key=lambda y: abs(y - a.at))
        dat = os.path.join(a.run, "cbeam_zone_%d.dat" % k)
        n = 0
        with open(dat, "w") as f:
            for p, d in zip(pts, dmg):
                if abs(p[1] - layer) < 1e-6:
                    f.write("%g %g %g\n" % (p[0], p[2], d))
                    n += 1
        last = k == len(fs) - 1
        when = ("at the end (the last solve)" if last
                else "before conversion %d (load factor %.4g)" % (k + 1, t))
        plots.append('set title "%s\\n%d PD nodes, %d on this layer"\n'
                     'plot "%s" w l lc rgb "gray" lw 1.5 notitle, "%s" u 1:2:3 w p pt 5 ps 0.35 lc palette notitle\n'
                     % (when, len(pts), n, outline, dat))
    cols = 4
    rows = (len(fs) + cols - 1) // cols
    draw(a.output, 300 * cols, 430 * rows + 40, "%d,%d" % (rows, cols),
         "Notched C-beam in tension (cbeam_adaptive.yaml): the adaptive PD zone on the layer "
         "y = %g, coloured by damage" % layer,
         'set xrange [-3:53]\nset yrange [-53:53]\nset xlabel "x [mm]"\nset ylabel "z [mm]"\n',
         plots)


if __name__ == "__main__":
    main()
