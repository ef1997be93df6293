#!/usr/bin/env python3
"""Coupling error against the horizon (the coupled bar, TE2, fictitious nodes).

usage: examples/bar/convergence.py [--cupid build/cupid] [--method fictitious|lagrange|arlequin]
                                   [--solver petsc] [--clamp-elements 3]
                                   [--surface-correction energy] [H:DELTA ...]

Default cases: fixed m = 3 with delta = 3, 2, 1.5 (h = 1, 2/3, 1/2; the last has 32,000 PD
nodes: ~50 GB for the direct factorisation, seconds with `--cupid build-petsc/cupid --solver
petsc`, the matrix-free path). Each case is bar_coupled_te2.yaml with its spacing and horizon
replaced; the reference is bar_fe_te2.yaml. `--clamp-elements 3` cuts the clamped span into 3
B2 elements in both (bar_fe_te2_c3.yaml, the README's bar.yaml), `--surface-correction
energy` adds the PD surface correction (both as compare_coupled.py). `--method arlequin` puts
the overlaps [30, 35] and [65, 70] inside the PD region (beam-element ends there, the
penalty 10 E h, as bar_coupled_arlequin_l9.yaml) and the FE reference gets the same element
ends. Prints a table of the
largest error of u_y along the axis relative to the tip displacement, the largest pointwise
relative error, and the equilibrium imbalance.
"""
import argparse, csv, json, os, re, subprocess

ap = argparse.ArgumentParser()
ap.add_argument("--cupid", default="build/cupid")
ap.add_argument("--method", default="fictitious")
ap.add_argument("--expansion", default="te2")
ap.add_argument("--solver", help="analysis solver of the coupled runs (e.g. petsc)")
ap.add_argument("--clamp-elements", type=int, default=1)
ap.add_argument("--surface-correction", default="none", choices=["none", "energy"])
ap.add_argument("cases", nargs="*", default=["1:3", "0.6666666666666666:2", "0.5:1.5"])
a = ap.parse_args()
here = os.path.dirname(os.path.abspath(__file__))
out = os.path.join("out", "bar", "convergence")
os.makedirs(out, exist_ok=True)

def axis(d):
    return [(float(r["y"]), float(r["uy"])) for r in csv.DictReader(open(os.path.join(d, "line_axis.csv")))]

def clamped(txt):
    """The clamped span [0, 30] in a.clamp_elements B2 elements (compare_coupled.py); for
    Arlequin, element ends at the overlap bounds 35 and 65 too."""
    if a.method == "arlequin":
        txt = txt.replace("axis: {y: [0, 30, 70, 100], elements: [1, 1, 1]",
                          "axis: {y: [0, 30, 35, 65, 70, 100], elements: [1, 1, 1, 1, 1]")
    if a.clamp_elements == 1:
        return txt
    return re.sub(r"elements: \[1, ", f"elements: [{a.clamp_elements}, ", txt, count=1)

def coupling(h):
    if a.method != "arlequin":
        return f"coupling: {{method: {a.method}}}"
    return ("coupling: {method: arlequin, arlequin: {penalty: %g, overlap: [{y: [30, 35]}, "
            "{y: [65, 70]}]}}" % (10 * 10000 * h))  # kappa = 10 E h, E = 10 GPa

fe_dir = os.path.join(out, f"fe_c{a.clamp_elements}")
fe_model = os.path.join(out, f"fe_c{a.clamp_elements}.yaml")
open(fe_model, "w").write(clamped(open(os.path.join(here, f"bar_fe_{a.expansion}.yaml")).read()))
subprocess.run([a.cupid, "run", fe_model, "-o", fe_dir, "--quiet"], check=True)
fe = axis(fe_dir)
tip = abs(fe[-1][1])
src = clamped(open(os.path.join(here, f"bar_coupled_{a.expansion}.yaml")).read())
if a.surface_correction != "none":
    src = src.replace("  partial_volume: pdlammps", f"  partial_volume: pdlammps\n  surface_correction: {a.surface_correction}")
extra = ["--solver", a.solver] if a.solver else []
print(f"| h | delta | m | PD nodes | max error / tip u | max relative error | equilibrium imbalance | wall s |")
print("|---|---|---|---|---|---|---|---|")
for case in a.cases:
    h, d = (float(v) for v in case.split(":"))
    txt = re.sub(r"spacing: [0-9.]+", f"spacing: {h!r}", src)
    txt = re.sub(r"horizon: [0-9.]+", f"horizon: {d!r}", txt)
    txt = txt.replace("coupling: {method: fictitious}", coupling(h))
    name = f"h{h:.3f}_d{d:g}_{a.method}_c{a.clamp_elements}_{a.surface_correction}"
    model = os.path.join(out, name + ".yaml")
    open(model, "w").write(txt)
    dd = os.path.join(out, name)
    subprocess.run([a.cupid, "run", model, "-o", dd, "--quiet", *extra], check=True)
    c = axis(dd)
    s = json.load(open(os.path.join(dd, "summary.json")))
    err = max(abs(u - v) for (_, u), (_, v) in zip(c, fe)) / tip
    rel = max(abs(u - v) / abs(v) for (y, u), (_, v) in zip(c, fe) if y > 0)
    imb = abs(s["applied_load_sum"][1] + s["reaction_sum"][1]) / abs(s["applied_load_sum"][1])
    wall = sum(p["time_s"] for p in s["phases"].values())
    print(f"| {h:.4g} | {d:g} | {d/h:.3g} | {s['counts']['pd_nodes']} | {100*err:.2f}% | {100*rel:.2f}% | {100*imb:.2f}% | {wall:.0f} |", flush=True)
