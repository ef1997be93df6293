#!/usr/bin/python3
"""The y-strain of a PD plate's middle layer, from a run's pd_nodes.csv, as a picture.

    /usr/bin/python3 examples/geometry/plate_strain.py RUN_DIR [--at 1.5] [-o PNG]

eps_yy at each node by the central difference of u_y over the nodes at y +- h (one-sided
where one is missing: the hole's edge and the plate's faces), on the layer z = AT, divided by
the far field's (the mean over the nodes with y in [45, 55]); gnuplot draws it
(scripts/install-deps.sh installs it). Prints the largest ratio and where it is.
"""
import argparse
import csv
import os
import subprocess
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run")
    ap.add_argument("--at", type=float, default=1.5)
    ap.add_argument("-o", "--output")
    a = ap.parse_args()
    path = os.path.join(a.run, "pd_nodes.csv")
    if not os.path.exists(path):
        sys.exit("%s: no pd_nodes.csv (run with output.pd_nodes: true)" % a.run)
    rows = list(csv.DictReader(open(path)))
    zs = sorted({float(r["z"]) for r in rows})
    z = min(zs, key=lambda c: abs(c - a.at))
    ys = sorted({float(r["y"]) for r in rows})
    h = ys[1] - ys[0]
    u = {(round(float(r["x"]), 9), round(float(r["y"]), 9)): float(r["uy"])
         for r in rows if abs(float(r["z"]) - z) < 1e-9}
    eps = {}
    for (x, y), uy in u.items():
        up, down = u.get((x, round(y + h, 9))), u.get((x, round(y - h, 9)))
        if up is not None and down is not None:
            eps[x, y] = (up - down) / (2 * h)
        elif up is not None:
            eps[x, y] = (up - uy) / h
        elif down is not None:
            eps[x, y] = (uy - down) / h
    far = [e for (x, y), e in eps.items() if 45 <= y <= 55]
    far = sum(far) / len(far)
    dat = os.path.join(a.run, "strain_yy.dat")
    with open(dat, "w") as f:
        for (x, y), e in sorted(eps.items()):
            f.write("%.9g %.9g %.9g\n" % (x, y, e / far))
    (xm, ym), em = max(eps.items(), key=lambda kv: kv[1])
    print("far-field strain %.4g; the largest %.3f times it at (%g, %g)" % (far, em / far, xm, ym))
    out = a.output or os.path.join(a.run, "strain_yy.png")
    subprocess.run(["gnuplot"], check=True, input=("""set terminal pngcairo size 760,700 font ",10"
set output "%s"
set title "y-strain over the far field's, layer z = %g"
set size ratio -1
set xlabel "x [mm]"
set ylabel "y [mm]"
set cbrange [0:3]
set cblabel "y-strain / far field" noenhanced
set palette rgbformulae 22,13,-31
plot "%s" u 1:2:3 w p pt 5 ps 0.7 lc palette notitle
""" % (out, z, dat)).encode())
    print("wrote", out)


if __name__ == "__main__":
    sys.exit(main())
