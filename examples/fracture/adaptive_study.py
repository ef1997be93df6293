#!/usr/bin/python3
"""Adaptive PD zones against fixed zones and all-PD beams (issue 37): table and pictures.

    /usr/bin/python3 examples/fracture/adaptive_study.py [--cupid build/cupid] [--out DIR]
        [--reuse] [--threads N]

Runs, at h = 1 (delta = 3.015), the notched beam (SENB, a/W = 0.5) and the beam without a notch,
each three ways: all peridynamics on pins (senb_pd.yaml with one node column at each support:
the statics of the beam's line supports, its peak scaled from its span, 80 + h, to 80), the
CUF beam with a fixed PD zone on [30, 60] (senb_coupled.yaml), and the CUF beam with an adaptive
zone (senb_adaptive.yaml: PD on [40, 50] at the start; beam_adaptive.yaml: no PD at the start).
Prints a markdown table (peak load, PD nodes at the end, damaged nodes shared with the all-PD
beam, time, memory) and writes adaptive_zones.png (the zone of beam_adaptive.yaml over its
damage at each conversion, from adaptive.pvd) and adaptive_senb.png (the damage of the notched
beams, all-PD against adaptive) next to this script. --reuse skips runs whose summary.json is
there. Needs gnuplot and python3-meshio (scripts/install-deps.sh).
"""
import argparse
import csv
import json
import os
import re
import subprocess

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
H = 1.0
PINS = ["--set", "constraints[1]={fix: {box: {x: [0, 0.9], y: [4, 5]}, components: [x, y, z]}}",
        "--set", "constraints[2]={fix: {box: {x: [0, 0.9], y: [85, 86]}, components: [x]}}"]
UNNOTCHED = ["--set", "peridynamics.precracks=[]",
             "--set", "constraints[0].displacement.value=[-0.09, null, null]"]
# name: (model file, extra arguments, label, notched)
RUNS = {
    "senb_pd": ("senb_pd.yaml", PINS, "all PD (pins)", True),
    "senb_fixed": ("senb_coupled.yaml", [], "CUF + PD on [30, 60]", True),
    "senb_adaptive": ("senb_adaptive.yaml", [], "CUF + adaptive PD, [40, 50] at the start", True),
    "beam_pd": ("senb_pd.yaml", PINS + UNNOTCHED, "all PD (pins)", False),
    "beam_fixed": ("senb_coupled.yaml", UNNOTCHED, "CUF + PD on [30, 60]", False),
    "beam_adaptive": ("beam_adaptive.yaml", [], "CUF + adaptive PD, none at the start", False),
}


def run(cupid, name, out, threads, reuse):
    model, extra, label, notched = RUNS[name]
    d = os.path.join(out, name)
    if not (reuse and os.path.exists(os.path.join(d, "summary.json"))):
        cmd = [cupid, "run", os.path.join(HERE, model), "-o", d, "--quiet"] + extra
        if threads:
            cmd += ["--threads", str(threads)]
        # a run that stops (a crack that cut the body: exit 2) has its results up to the stop
        subprocess.run(cmd, cwd=ROOT, check=False)
    s = json.load(open(os.path.join(d, "summary.json")))
    fr = s["fracture"]
    peak = -fr["peak_reactions"][0]["reaction"][0]
    if name.endswith("_pd"):
        peak *= (80 + H) / 80  # from pin to pin, as at the beam's span
    damaged = set()
    for r in csv.DictReader(open(os.path.join(d, "pd_nodes.csv"))):
        if float(r["damage"]) > 0:
            damaged.add((round(float(r["x"]), 3), round(float(r["y"]), 3), round(float(r["z"]), 3)))
    return {"name": name, "label": label, "notched": notched, "dir": d, "peak": peak,
            "pd_nodes": s["counts"]["pd_nodes"], "damaged": damaged,
            "bonds": fr["broken_bonds"], "seconds": s["total_time_s"],
            "memory_MB": s["peak_memory_bytes"] / 2 ** 20,
            "conversions": len(s.get("adaptive", {}).get("conversions", []))}


def gnuplot(script):
    subprocess.run(["gnuplot"], input=script.encode(), check=True)


# the side view of the beam, y across and x up, damage coloured (both pictures)
SIDE = """set size ratio -1
set xrange [-2:92]
set yrange [-3:22]
set xlabel "y [mm]"
set ylabel "x [mm]"
set cbrange [0:0.6]
set palette rgbformulae 22,13,-31
set object 2 rect from 0, 0 to 90, 20 fs empty border lc rgb 'gray'
"""


def side(points, path):
    """The side face (z nearest 0) of (x, y, z, damage) points into a gnuplot data file."""
    zmin = min(p[2] for p in points)
    with open(path, "w") as f:
        for x, y, z, dmg in points:
            if abs(z - zmin) < 1e-9:
                f.write("%g %g %g\n" % (y, x, dmg))


def zone_frames(d):
    """adaptive.pvd's PD frames: (load factor, [(x, y, z, damage)])."""
    import meshio
    pvd = open(os.path.join(d, "adaptive.pvd")).read()
    frames = []
    for t, f in re.findall(r'timestep="([^"]+)"[^>]*file="(adaptive_pd_\d+\.vtu)"', pvd):
        m = meshio.read(os.path.join(d, f))
        dmg = m.point_data["damage"]
        frames.append((float(t), [(p[0], p[1], p[2], dmg[i]) for i, p in enumerate(m.points)]))
    return frames


def picture_zones(info, out):
    frames = zone_frames(info["dir"])
    rows = len(frames)
    plots = []
    for k, (t, pts) in enumerate(frames):
        dat = os.path.join(out, "zone_%d.dat" % k)
        side(pts, dat)
        ys = [p[1] for p in pts]
        lo, hi = min(ys) - H / 2, max(ys) + H / 2  # the outline: the nodes' cells
        plots.append("""set title "load factor %.3f: %d PD nodes, on y in [%g, %g]"
set object 1 rect from %g, 0 to %g, 20 fs empty border lc rgb 'black' dt 2 lw 1.5
plot "%s" u 1:2:3 w p pt 5 ps 0.55 lc palette notitle
unset object 1
""" % (t, len(pts), min(ys), max(ys), lo, hi, dat))
    gnuplot("""set terminal pngcairo size 1000,%d font ",10" noenhanced
set output "%s"
set multiplot layout %d,1 title "Beam without a notch (beam_adaptive.yaml, h = 1): the PD zone (dashed) over the damage (side face), at each conversion and at the end"
%s%s
unset multiplot
""" % (190 * rows + 40, os.path.join(HERE, "adaptive_zones.png"), rows, SIDE, "".join(plots)))


def picture_senb(infos, out):
    plots = []
    for info in infos:
        pts = [(float(r["x"]), float(r["y"]), float(r["z"]), float(r["damage"]))
               for r in csv.DictReader(open(os.path.join(info["dir"], "pd_nodes.csv")))]
        dat = os.path.join(out, "senb_%s.dat" % info["name"])
        side(pts, dat)
        plots.append('set title "%s: %d PD nodes, peak %.2f N"\nplot "%s" u 1:2:3 w p pt 5 ps 0.55 '
                     'lc palette notitle\n' % (info["label"], info["pd_nodes"], info["peak"], dat))
    gnuplot("""set terminal pngcairo size 1000,430 font ",10" noenhanced
set output "%s"
set multiplot layout 2,1 title "SENB (h = 1): damage on the side face at the end"
%s%s
unset multiplot
""" % (os.path.join(HERE, "adaptive_senb.png"), SIDE, "".join(plots)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cupid", default=os.path.join(ROOT, "build", "cupid"))
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "fracture", "adaptive_study"))
    ap.add_argument("--reuse", action="store_true")
    ap.add_argument("--threads", type=int, default=0)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    info = {n: run(a.cupid, n, a.out, a.threads, a.reuse) for n in RUNS}
    print("| beam | model | PD nodes at the end | peak P (N) | against all-PD | damaged nodes "
          "shared with all-PD | bonds broken | conversions | time (s) | memory (MB) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for n, r in info.items():
        ref = info[("senb" if r["notched"] else "beam") + "_pd"]
        # the beam is symmetric about the load line y = 45, and a crack may start on either
        # side of it (round-off): the damaged nodes shared, as they are or mirrored
        mirror = {(x, round(90 - y, 3), z) for x, y, z in ref["damaged"]}
        shared = max(len(r["damaged"] & d) / len(r["damaged"] | d) if r["damaged"] | d else 1.0
                     for d in (ref["damaged"], mirror))
        print("| %s | %s | %d | %.2f | %+.2f%% | %.0f%% (%d / %d) | %d | %d | %.1f | %.0f |" % (
            "notched" if r["notched"] else "no notch", r["label"], r["pd_nodes"], r["peak"],
            100 * (r["peak"] / ref["peak"] - 1), 100 * shared, len(r["damaged"]),
            len(ref["damaged"]), r["bonds"], r["conversions"], r["seconds"], r["memory_MB"]))
    picture_zones(info["beam_adaptive"], a.out)
    picture_senb([info["senb_pd"], info["senb_adaptive"]], a.out)


if __name__ == "__main__":
    main()
