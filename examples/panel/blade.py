#!/usr/bin/env python3
"""Stiffness of one panel stringer as a PD block against the L9 beam (examples/panel/README.md).

usage: examples/panel/blade.py [--cupid build/cupid]

The blade x [48, 52], z [2, 22] (4 PD nodes thick at h = 1) as a 40 mm cantilever along y,
clamped at y = 0 (FE: clamp; PD: a fixed layer y in [-3, 0]), loaded on its end y = 40 by
(ax) axial, (strong) in-plane bending along z, (weak) out-of-plane bending along x (the
blade's t^3 term) and (torsion) a torque. Prints the end displacement of each PD variant
relative to the L9 beam (4 B4, 4 L9 across z): the PD blade's own stiffness error, which the
coupled panel inherits. Each PD run ~2.5 s, 0.3 GB.
"""
import argparse
import json
import os
import subprocess
import sys

LOADS = {  # name: (traction on y = 40, output point, component)
    "axial": ('[0, 1, 0]', "[50, 40, 12]", "uy"),
    "strong bending (z)": ('[0, 0, 0.1]', "[50, 40, 12]", "uz"),
    "weak bending (x, t^3)": ('[0.01, 0, 0]', "[50, 40, 12]", "ux"),
    "torsion": ('["-0.01*(z-12)", "0", "0.01*(x-50)"]', "[50, 40, 22]", "ux"),
}
PD = {"LPS m = 3": ("3.0", ""), "LPS m = 3, energy correction": ("3.0", "  surface_correction: energy\n"),
      "LPS m = 2": ("2.0", "")}


def fe_model(load, point, d):
    return f"""title: blade FE
materials:
  resin: {{E: 10000, nu: 0.2}}
beam:
  material: resin
  axis: {{y: [0, 40], elements: [4], type: B4}}
  section:
    expansion: LE
    element: L9
    components:
      - {{x: [48, 52], z: [2, 7, 12, 17, 22]}}
constraints:
  - clamp: {{y: 0}}
loads:
  - traction: {{y: 40, value: {load}}}
output:
  directory: {d}
  points:
    - {{name: T, at: {point}}}
"""


def pd_model(load, point, d, delta, sc):
    return f"""title: blade PD
materials:
  resin: {{E: 10000, nu: 0.2}}
peridynamics:
  spacing: 1.0
  horizon: {delta}
  model: lps
  influence: gaussian
  partial_volume: pdlammps
{sc}  material: resin
  regions:
    - {{x: [48, 52], y: [-3, 40], z: [2, 22]}}
constraints:
  - fix: {{box: {{y: [-3, 0]}}}}
loads:
  - traction: {{y: 40, value: {load}}}
analysis: {{type: static, solver: direct}}
output:
  directory: {d}
  points:
    - {{name: T, at: {point}}}
"""


def run(cupid, text, d):
    os.makedirs(d, exist_ok=True)
    path = d + ".yaml"
    with open(path, "w") as f:
        f.write(text)
    r = subprocess.run([cupid, "run", path, "--quiet"], capture_output=True, text=True)
    if r.returncode:
        sys.exit(f"{path}: cupid failed\n{r.stdout}{r.stderr}")
    return json.load(open(os.path.join(d, "summary.json")))["points"][0]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cupid", default="build/cupid")
    a = ap.parse_args()
    base = os.path.abspath(os.path.join("out", "panel", "blade"))
    print("| load | L9 beam | " + " | ".join(PD) + " |")
    print("|---|---|" + "---|" * len(PD))
    for i, (name, (load, point, c)) in enumerate(LOADS.items()):
        fe = run(a.cupid, fe_model(load, point, f"{base}/fe{i}"), f"{base}/fe{i}")[c]
        cells = []
        for j, (delta, sc) in enumerate(PD.values()):
            d = f"{base}/pd{i}_{j}"
            q = run(a.cupid, pd_model(load, point, d, delta, sc), d)[c]
            cells.append(f"{q:.6f} ({100 * (q / fe - 1):+.1f}%)")
        print(f"| {name} | {fe:.6f} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
