#!/usr/bin/env python3
"""Stiffness of one panel stringer as a PD block against the L9 beam (examples/panel/README.md).

usage: examples/panel/blade.py

The blade x [48, 52], z [2, 22] (4 PD nodes thick at h = 1) as a 40 mm cantilever along y,
clamped at y = 0 (FE: clamp; PD: a fixed layer y in [-3, 0]), loaded on its end y = 40 by
(ax) axial, (strong) in-plane bending along z, (weak) out-of-plane bending along x (the
blade's t^3 term) and (torsion) a torque. Prints the end displacement of each PD variant
relative to the L9 beam (4 B4, 4 L9 across z): the PD blade's own stiffness error, which the
coupled panel inherits. The models are built as dicts and solved through the cupid Python
package (python/cupid); nothing is written. Each PD run ~2.5 s, 0.3 GB.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
import cupid  # noqa: E402

LOADS = {  # name: (traction on y = 40, sampled point, component)
    "axial": ([0, 1, 0], [50, 40, 12], 1),
    "strong bending (z)": ([0, 0, 0.1], [50, 40, 12], 2),
    "weak bending (x, t^3)": ([0.01, 0, 0], [50, 40, 12], 0),
    "torsion": (["-0.01*(z-12)", "0", "0.01*(x-50)"], [50, 40, 22], 0),
}
PD = {"LPS m = 3": (3.0, None), "LPS m = 3, energy correction": (3.0, "energy"),
      "LPS m = 2": (2.0, None)}
MATERIALS = {"resin": {"E": 10000, "nu": 0.2}}


def fe_model(load):
    return {
        "title": "blade FE",
        "materials": MATERIALS,
        "beam": {"material": "resin", "axis": {"y": [0, 40], "elements": [4], "type": "B4"},
                 "section": {"expansion": "LE", "element": "L9",
                             "components": [{"x": [48, 52], "z": [2, 7, 12, 17, 22]}]}},
        "constraints": [{"clamp": {"y": 0}}],
        "loads": [{"traction": {"y": 40, "value": load}}],
    }


def pd_model(load, delta, sc):
    pd = {"spacing": 1.0, "horizon": delta, "model": "lps", "influence": "gaussian",
          "partial_volume": "pdlammps", "material": "resin",
          "regions": [{"x": [48, 52], "y": [-3, 40], "z": [2, 22]}]}
    if sc:
        pd["surface_correction"] = sc
    return {
        "title": "blade PD",
        "materials": MATERIALS,
        "peridynamics": pd,
        "constraints": [{"fix": {"box": {"y": [-3, 0]}}}],
        "loads": [{"traction": {"y": 40, "value": load}}],
        "analysis": {"type": "static", "solver": "direct"},
    }


def end_displacement(model, point, c):
    """Component c of the displacement at point, the model solved."""
    with cupid.Problem(model) as p:
        u, _ = p.solve().sample([point])
    return u[0, c]


def main():
    argparse.ArgumentParser(description=__doc__.split("\n")[0]).parse_args()
    print("| load | L9 beam | " + " | ".join(PD) + " |")
    print("|---|---|" + "---|" * len(PD))
    for name, (load, point, c) in LOADS.items():
        fe = end_displacement(fe_model(load), point, c)
        cells = []
        for delta, sc in PD.values():
            q = end_displacement(pd_model(load, delta, sc), point, c)
            cells.append(f"{q:.6f} ({100 * (q / fe - 1):+.1f}%)")
        print(f"| {name} | {fe:.6f} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
