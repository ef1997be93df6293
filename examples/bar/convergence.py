#!/usr/bin/env python3
"""Coupling error against the horizon (the coupled bar, TE2, fictitious nodes).

usage: examples/bar/convergence.py [--library build/libcupid.so]
                                   [--method fictitious|lagrange|arlequin]
                                   [--solver petsc] [--clamp-elements 3]
                                   [--surface-correction energy] [H:DELTA ...]

Default cases: fixed m = 3 with delta = 3, 2, 1.5 (h = 1, 2/3, 1/2; the last has 32,000 PD
nodes: ~50 GB for the direct factorisation, seconds with `--library build-petsc/libcupid.so
--solver petsc`, the matrix-free path of the PETSc build). Each case is bar_coupled_te2.yaml
with its spacing and horizon replaced (the text written to out/bar/convergence/<case>.yaml and
solved through the cupid Python package, python/cupid); the reference is bar_fe_te2.yaml.
`--clamp-elements 3` cuts the clamped span into 3 B2 elements in both (bar_fe_te2_c3.yaml, the
README's bar.yaml), `--surface-correction energy` adds the PD surface correction (both as
compare_coupled.py). `--method arlequin` puts the overlaps [30, 35] and [65, 70] inside the PD
region (beam-element ends there, the penalty 10 E h, as bar_coupled_arlequin_l9.yaml) and the
FE reference gets the same element ends. Prints a table of the largest error of u_y along the
axis relative to the tip displacement, the largest pointwise relative error, and the
equilibrium imbalance.
"""
import argparse, os, re, sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
import cupid  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--library", help="libcupid to load (default: $CUPID_LIBRARY, else "
                "build/libcupid.so); build-petsc/libcupid.so for --solver petsc")
ap.add_argument("--cupid", help=argparse.SUPPRESS)  # old form: the library beside this binary
ap.add_argument("--method", default="fictitious")
ap.add_argument("--balance", default="none", choices=["none", "momentum", "global"],
                help="coupling.balance of the fictitious-node runs (default none: paper 000's "
                     "Eq. 38 as printed, the figures of docs/coupling.md)")
ap.add_argument("--expansion", default="te2")
ap.add_argument("--solver", help="analysis solver of the coupled runs (e.g. petsc)")
ap.add_argument("--clamp-elements", type=int, default=1)
ap.add_argument("--surface-correction", default="none", choices=["none", "energy"])
ap.add_argument("cases", nargs="*", default=["1:3", "0.6666666666666666:2", "0.5:1.5"])
a = ap.parse_args()
lib = a.library or (a.cupid and os.path.join(os.path.dirname(os.path.abspath(a.cupid)), "libcupid.so"))
if lib:  # read when the first problem is made
    os.environ["CUPID_LIBRARY"] = os.path.abspath(lib)
here = os.path.dirname(os.path.abspath(__file__))
out = os.path.join("out", "bar", "convergence")
os.makedirs(out, exist_ok=True)

def line(frm, to, n):
    """The n points of an output line from frm to to, placed as line_<name>.csv places them."""
    return [[f + k / (n - 1) * (t - f) for f, t in zip(frm, to)] for k in range(n)]

AXIS = line([5, 0, 5], [5, 100, 5], 101)  # the models' output line "axis"

def solve(model, solver=None):
    """The model file solved: (y, u_y) along the axis and the problem's info."""
    with cupid.Problem(model, solver=solver) as p:
        u, _ = p.solve().sample(AXIS)
        return [(q[1], v[1]) for q, v in zip(AXIS, u)], p.info

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
    if a.method == "fictitious":
        return f"coupling: {{method: fictitious, balance: {a.balance}}}"
    if a.method != "arlequin":
        return f"coupling: {{method: {a.method}}}"
    return ("coupling: {method: arlequin, arlequin: {penalty: %g, overlap: [{y: [30, 35]}, "
            "{y: [65, 70]}]}}" % (10 * 10000 * h))  # kappa = 10 E h, E = 10 GPa

fe_model = os.path.join(out, f"fe_c{a.clamp_elements}.yaml")
open(fe_model, "w").write(clamped(open(os.path.join(here, f"bar_fe_{a.expansion}.yaml")).read()))
fe, _ = solve(fe_model)
tip = abs(fe[-1][1])
src = clamped(open(os.path.join(here, f"bar_coupled_{a.expansion}.yaml")).read())
if a.surface_correction != "none":
    src = src.replace("  partial_volume: pdlammps", f"  partial_volume: pdlammps\n  surface_correction: {a.surface_correction}")
print("| h | delta | m | PD nodes | max error / tip u | max relative error | equilibrium imbalance | wall s |")
print("|---|---|---|---|---|---|---|---|")
for case in a.cases:
    h, d = (float(v) for v in case.split(":"))
    txt = re.sub(r"spacing: [0-9.]+", f"spacing: {h!r}", src)
    txt = re.sub(r"horizon: [0-9.]+", f"horizon: {d!r}", txt)
    txt = re.sub(r"coupling: \{method: fictitious[^}]*\}", coupling(h), txt)
    name = f"h{h:.3f}_d{d:g}_{a.method}_c{a.clamp_elements}_{a.surface_correction}"
    model = os.path.join(out, name + ".yaml")
    open(model, "w").write(txt)
    c, s = solve(model, a.solver)
    err = max(abs(u - v) for (_, u), (_, v) in zip(c, fe)) / tip
    rel = max(abs(u - v) / abs(v) for (y, u), (_, v) in zip(c, fe) if y > 0)
    imb = abs(s["load_sum"][1] + s["reaction_sum"][1]) / abs(s["load_sum"][1])
    wall = sum(s["phase_seconds"].values())
    print(f"| {h:.4g} | {d:g} | {d/h:.3g} | {s['pd_nodes']} | {100*err:.2f}% | {100*rel:.2f}% | {100*imb:.2f}% | {wall:.0f} |", flush=True)
