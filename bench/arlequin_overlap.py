#!/usr/bin/python3
"""The stretch an Arlequin overlap adds to the bonds at its inner edge (issue 37).

    /usr/bin/python3 bench/arlequin_overlap.py [--cupid build/cupid]

The beam without a notch of examples/fracture/beam_adaptive.yaml (h = 1, delta = 3.015), linear
(one load step, nothing breaks), with PD fixed on y in [25, 65] and overlaps of 5 mm (two beam
elements of 2.5 mm) or 10 mm, each with the linear and the smooth weight; against the all-PD
beam on pins (senb_pd.yaml without its notch). For each lattice layer y near the lower overlap's
inner edge (y = 30 or 35) it reads the largest bond stretch of the layer's nodes (from
pd_nodes.csv, the linearised stretch e . xi / |xi|^2 over the bonds within delta) per 100 N of
load, and prints the coupled beam's over the all-PD beam's at the same layer, each normalised
by its own mid-span value (their supports differ: line supports against pins). A ratio above
1 is the overlap's own stretch: bonds there reach their limit before the all-PD beam's would,
which grows an adaptive zone or stops a fixed one. Reported figures, not a timed test.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EX = os.path.join(ROOT, "examples", "fracture")
LINEAR = ["--set", "analysis={type: static, steps: 1}", "--set", "output.plots=false",
          "--set", "output.vtu=false", "--set", "constraints[0].displacement.value=[-0.02, null, null]"]
BEAM = ["--set", "beam.axis={y: [0, 5, 25, 65, 85, 90], elements: [1, 4, 16, 4, 1], type: B4}",
        "--set", "peridynamics.regions=[{x: [0, 20], y: [25, 65], z: [0, 5]}]"]
PINS = ["--set", "peridynamics.precracks=[]",
        "--set", "constraints[1]={fix: {box: {x: [0, 0.9], y: [4, 5]}, components: [x, y, z]}}",
        "--set", "constraints[2]={fix: {box: {x: [0, 0.9], y: [85, 86]}, components: [x]}}"]
DELTA = 3.015
CASES = [  # label, overlap width, weight, the inner edge
    ("5 mm, linear", 5, "linear", 30.0),
    ("5 mm, smooth", 5, "smooth", 30.0),
    ("10 mm, linear", 10, "linear", 35.0),
    ("10 mm, smooth", 10, "smooth", 35.0),
]


def run(cupid, model, out, extra):
    subprocess.run([cupid, "run", model, "-o", out, "--quiet"] + extra, cwd=ROOT, check=True)
    rows = list(csv.DictReader(open(os.path.join(out, "pd_nodes.csv"))))
    s = json.load(open(os.path.join(out, "summary.json")))
    load = -s["fracture"]["peak_reactions"][0]["reaction"][0]
    return rows, load


def layer_stretch(rows, load):
    """The largest bond stretch of each layer y, per 100 N."""
    at = {}
    for r in rows:
        key = tuple(round(2 * float(r[k])) for k in "xyz")  # nodes at half-integers (h = 1)
        at[key] = (float(r["ux"]), float(r["uy"]), float(r["uz"]))
    reach = int(math.ceil(DELTA))
    offs = [(a, b, c) for a in range(-reach, reach + 1) for b in range(-reach, reach + 1)
            for c in range(-reach, reach + 1) if 0 < a * a + b * b + c * c <= DELTA * DELTA]
    top = {}
    for key, u in at.items():
        best = 0.0
        for o in offs:
            v = at.get((key[0] + 2 * o[0], key[1] + 2 * o[1], key[2] + 2 * o[2]))
            if v is None:
                continue
            e = sum(o[k] * (v[k] - u[k]) for k in range(3)) / sum(x * x for x in o)
            best = max(best, e)
        y = key[1] / 2
        top[y] = max(top.get(y, 0.0), best * 100.0 / load)
    return top


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cupid", default=os.path.join(ROOT, "build", "cupid"))
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as work:
        # beam_adaptive.yaml with a fixed zone: without its adaptive key (an `adaptive:` left
        # empty would read as the defaults)
        fixed = os.path.join(work, "fixed.yaml")
        with open(os.path.join(EX, "beam_adaptive.yaml")) as f, open(fixed, "w") as g:
            g.writelines(line for line in f if not line.startswith("  adaptive:"))
        pd = layer_stretch(*run(a.cupid, os.path.join(EX, "senb_pd.yaml"), os.path.join(work, "pd"),
                                PINS + LINEAR))
        pd_mid = pd[43.5]
        print("| overlap | layer y | stretch per 100 N, coupled | all-PD | coupled / all-PD "
              "(each over its y = 43.5) |")
        print("|---|---|---|---|---|")
        for label, width, weight, edge in CASES:
            lo = 25.0
            extra = BEAM + LINEAR + [
                "--set", "coupling.arlequin.weight=" + weight,
                "--set", "coupling.arlequin.overlap=[{y: [%g, %g]}, {y: [%g, %g]}]"
                % (lo, lo + width, 65 - width, 65)]
            c = layer_stretch(*run(a.cupid, fixed, os.path.join(work, label[:2]), extra))
            worst = max((c[y] / c[43.5]) / (pd[y] / pd_mid) for y in (edge - 0.5, edge + 0.5))
            for y in (edge - 1.5, edge - 0.5, edge + 0.5, edge + 1.5):
                print("| %s | %.1f | %.3e | %.3e | %.3f |" % (
                    label, y, c[y], pd[y], (c[y] / c[43.5]) / (pd[y] / pd_mid)))
            print("| %s | the edge's worst | | | **%.3f** |" % (label, worst))


if __name__ == "__main__":
    main()
