#!/usr/bin/env python3
"""Coupled bar against the full-FE bar (paper 000, section 5.1, Figs. 13-14).

usage: examples/bar/compare_coupled.py [--surface-correction energy] [--clamp-elements N]
                                      [EXPANSION ...]

Runs bar_fe_<e>.yaml and bar_coupled_<e>.yaml for each expansion (default te1 te2 te3 l4 l9,
lagrange_l9: the Lagrange-multiplier coupling, and arlequin_l9: the Arlequin penalty coupling
with two overlaps, both against the L9 full-FE bar: the three methods of paper 000 Fig. 14 side
by side with l9)
through the cupid Python package (python/cupid), samples u_y along the models' axis line
(y from 0 to 100, 101 points) and prints, per expansion: the largest relative error of u_y along the axis
(|u_c - u_fe| / |u_fe| over y > 0), the largest error relative to the tip displacement, the
tip values, and the equilibrium imbalance |reaction + load| / |load| of the coupled run.
Writes out/bar/coupled_comparison.md, out/bar/coupled_axis_<e>.csv (y, u_y FE, u_y coupled),
out/bar/coupled_error_<e>.csv (y, relative error in %), and from them out/bar/coupled_uy.png
and coupled_error.png (gnuplot).
With --surface-correction energy the coupled models run with peridynamics.surface_correction
set (temporary copies; files with the suffix _energy, e.g. the table
out/bar/coupled_comparison_energy.md).
With --clamp-elements N (N > 1) both the full-FE and the coupled models run (temporary copies)
with N B2 elements on the clamped span y in [0, 30] instead of one (suffix _cN): one element
clamped at y = 0 interpolates the Poisson contraction linearly from zero, so its interface
node contracts more than the uniaxial value; the PD block cannot follow that FE artefact and
the non-conservative fictitious-node coupling passes ~0.996 P into the span (1.04 P with the
h/2 fictitious element of cupid before issue 18; docs/coupling.md).
The fictitious FE element of the coupled runs is the models' coupling.fictitious_fe (removed,
the default | adjacent | plane | a length; docs/coupling.md).
"""
import argparse, os, subprocess, sys, tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
import cupid  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--surface-correction", default="none", choices=["none", "energy"])
ap.add_argument("--clamp-elements", type=int, default=1)
ap.add_argument("expansions", nargs="*",
                default=["te1", "te2", "te3", "l4", "l9", "lagrange_l9", "arlequin_l9"])
a = ap.parse_args()
here = os.path.dirname(os.path.abspath(__file__))

def line(frm, to, n):
    """The n points of an output line from frm to to, placed as line_<name>.csv places them."""
    return [[f + k / (n - 1) * (t - f) for f, t in zip(frm, to)] for k in range(n)]

AXIS = line([5, 0, 5], [5, 100, 5], 101)  # the models' output line "axis"

def model_text(model, correction):
    """The model's text with the surface correction and the clamped span of the options."""
    text = open(model).read()
    if correction != "none":
        # the key after partial_volume
        text = text.replace("  partial_volume: pdlammps\n",
                            f"  partial_volume: pdlammps\n  surface_correction: {correction}\n")
        assert "surface_correction" in text, model
    if a.clamp_elements != 1:
        # the clamped span is the first entry (Arlequin models have five spans)
        n = a.clamp_elements
        if "elements: [1, 1, 1, 1, 1]" in text:
            text = text.replace("elements: [1, 1, 1, 1, 1]", f"elements: [{n}, 1, 1, 1, 1]")
        else:
            assert "elements: [1, 1, 1]" in text, model
            text = text.replace("elements: [1, 1, 1]", f"elements: [{n}, 1, 1]")
    return text

def run(model, correction="none"):
    """The model solved (a temporary copy when the options change it): [(y, u_y, region)]
    along the axis, and p.info."""
    path = model
    if correction != "none" or a.clamp_elements != 1:
        with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as fh:
            fh.write(model_text(model, correction))
        path = fh.name
    try:
        with cupid.Problem(path) as p:
            u, regions = p.solve().sample(AXIS)
            return [(q[1], v[1], r) for q, v, r in zip(AXIS, u, regions)], p.info
    finally:
        if path != model:
            os.unlink(path)

def csv_y(y):
    """y as line_axis.csv printed it (%.10g) and the script read it back."""
    return float("%.10g" % y)

sfx = ("" if a.surface_correction == "none" else "_" + a.surface_correction) + \
      ("" if a.clamp_elements == 1 else f"_c{a.clamp_elements}")
rows = []
curves = []
for e in a.expansions:
    # "lagrange_l9": the Lagrange-multiplier model against the L9 full-FE bar.
    fe, _ = run(os.path.join(here, f"bar_fe_{e.split('_')[-1]}.yaml"))
    c, s = run(os.path.join(here, f"bar_coupled_{e}.yaml"), a.surface_correction)
    tip = abs(fe[-1][1])
    rel = max(abs(u - v) / abs(v) for (y, u, _), (_, v, _) in zip(c, fe) if y > 0)
    relpd = max((abs(u - v) / abs(v) for (y, u, r), (_, v, _) in zip(c, fe) if r == "PD"), default=0)
    reltip = max(abs(u - v) for (_, u, _), (_, v, _) in zip(c, fe)) / tip
    load, reac = s["load_sum"][1], s["reaction_sum"][1]
    rows.append((e, fe[-1][1], c[-1][1], rel, relpd, reltip, abs(load + reac) / abs(load),
                 s["phase_seconds"]["factorisation"]))
    curves.append(e)
    os.makedirs("out/bar", exist_ok=True)
    with open(f"out/bar/coupled_axis_{e}{sfx}.csv", "w") as fh:   # the u_y plot
        fh.write("y,uy_fe,uy_coupled\n")
        for (y, u, _), (_, v, _) in zip(c, fe):
            fh.write(f"{csv_y(y)},{v:.10e},{u:.10e}\n")
    with open(f"out/bar/coupled_error_{e}{sfx}.csv", "w") as fh:   # paper Fig. 14C
        fh.write("y,rel_error_percent\n")
        for (y, u, _), (_, v, _) in zip(c, fe):
            if y > 0:
                fh.write(f"{csv_y(y)},{100 * (u - v) / v}\n")

os.makedirs("out/bar", exist_ok=True)
hdr = "| model | u_y tip FE | u_y tip coupled | max rel. error | max rel. error in PD | max error / tip u | equilibrium imbalance | factorisation s |"
lines = [hdr, "|" + "---|" * 8]
for r in rows:
    lines.append(f"| {r[0]} | {r[1]:.6f} | {r[2]:.6f} | {100*r[3]:.2f}% | {100*r[4]:.2f}% | {100*r[5]:.2f}% | {100*r[6]:.2f}% | {r[7]:.1f} |")
txt = "\n".join(lines)
print(txt)
open(f"out/bar/coupled_comparison{sfx}.md", "w").write(txt + "\n")
try:
    plot = ["set terminal pngcairo noenhanced size 1000,600", f"set output 'coupled_uy{sfx}.png'", "set datafile separator ','",
            "set key left top", "set xlabel 'y [mm]'", "set ylabel 'u_y [mm]'", "set grid"]
    parts = []
    for e in curves:
        parts.append(f"'coupled_axis_{e}{sfx}.csv' every ::1 using 1:3 with points pt 7 ps 0.5 title 'coupled {e}'")
        parts.append(f"'coupled_axis_{e}{sfx}.csv' every ::1 using 1:2 with lines title 'FE {e}'")
    plot.append("plot " + ", ".join(parts))
    plot += [f"set output 'coupled_error{sfx}.png'", "set ylabel 'relative error of u_y [%]'",
             "plot " + ", ".join(f"'coupled_error_{e}{sfx}.csv' every ::1 using 1:2 with linespoints pt 7 ps 0.4 title '{e}'" for e in curves)]
    subprocess.run(["gnuplot"], input="\n".join(plot), text=True, cwd="out/bar", check=True)
except Exception as ex:
    print("plot skipped:", ex, file=sys.stderr)
