#!/usr/bin/python3
"""A picture of one layer of PD nodes coloured by damage, from a run's pd_nodes.csv.

    /usr/bin/python3 examples/fracture/layer_view.py RUN_DIR --normal x --at 4.5 [--warp 0]
        [--range 0 0.6] [-o PNG] [--title TEXT]

Takes the layer of nodes nearest to <normal> = AT (the nodes are on a grid, so a layer is the
nodes sharing that coordinate) and draws it seen along the normal: the two other axes in
x, y, z order (for --normal x: y across, z up), every node a square coloured by its damage,
displaced by WARP times its displacement (0: the reference grid). Writes PNG (default
RUN_DIR/damage_layer_<normal><at>.png) with gnuplot (scripts/install-deps.sh installs it).
Used for examples/fracture/README.md's notched C-beam web (output.pd_nodes: true).
"""
import argparse
import csv
import os
import subprocess
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run")
    ap.add_argument("--normal", choices="xyz", default="x")
    ap.add_argument("--at", type=float, default=0.0)
    ap.add_argument("--warp", type=float, default=0.0)
    ap.add_argument("--range", nargs=2, type=float, default=(0.0, 0.6))
    ap.add_argument("-o", "--output")
    ap.add_argument("--title")
    a = ap.parse_args()
    path = os.path.join(a.run, "pd_nodes.csv")
    if not os.path.exists(path):
        sys.exit("%s: no pd_nodes.csv (run with output.pd_nodes: true)" % a.run)
    rows = list(csv.DictReader(open(path)))
    u, v = [c for c in "xyz" if c != a.normal]
    layer = min({float(r[a.normal]) for r in rows}, key=lambda c: abs(c - a.at))
    dat = os.path.join(a.run, "layer_%s.dat" % a.normal)
    lo = [float("inf")] * 2
    hi = [-float("inf")] * 2
    with open(dat, "w") as f:
        for r in rows:
            if abs(float(r[a.normal]) - layer) > 1e-9:
                continue
            p = (float(r[u]) + a.warp * float(r["u" + u]), float(r[v]) + a.warp * float(r["u" + v]))
            for k in range(2):
                lo[k], hi[k] = min(lo[k], p[k]), max(hi[k], p[k])
            f.write("%.9g %.9g %s\n" % (p[0], p[1], r["damage"]))
    out = a.output or os.path.join(a.run, "damage_layer_%s%g.png" % (a.normal, layer))
    title = a.title or "damage on the layer %s = %g" % (a.normal, layer)
    if a.warp:
        title += ", displacements x %g" % a.warp
    span = [hi[k] - lo[k] for k in range(2)]
    pad = 0.04 * max(span)
    width = 900
    height = int(width * (span[1] + 2 * pad) / (span[0] + 2 * pad)) + 80
    subprocess.run(["gnuplot"], check=True, input=("""set terminal pngcairo size %d,%d font ",10"
set output "%s"
set title "%s"
set size ratio -1
set xlabel "%s [mm]"
set ylabel "%s [mm]"
set cbrange [%g:%g]
set cblabel "damage"
set palette rgbformulae 22,13,-31
set xrange [%g:%g]
set yrange [%g:%g]
plot "%s" u 1:2:3 w p pt 5 ps 0.55 lc palette notitle
""" % (width, max(300, min(height, 1600)), out, title.replace('"', "'"), u, v, a.range[0], a.range[1],
       lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad, dat)).encode())
    print("wrote", out)


if __name__ == "__main__":
    sys.exit(main())
