#!/usr/bin/env python3
"""Coupled bar against the full-FE bar (paper 000, section 5.1, Figs. 13-14).

usage: examples/bar/compare_coupled.py [--cupid build/cupid] [--surface-correction energy]
                                      [--clamp-elements N] [EXPANSION ...]

Runs bar_fe_<e>.yaml and bar_coupled_<e>.yaml for each expansion (default te1 te2 te3 l4 l9,
lagrange_l9: the Lagrange-multiplier coupling, and arlequin_l9: the Arlequin penalty coupling
with two overlaps, both against the L9 full-FE bar: the three methods of paper 000 Fig. 14 side
by side with l9),
then prints, per expansion: the largest relative error of u_y along the axis
(|u_c - u_fe| / |u_fe| over y > 0), the largest error relative to the tip displacement, the
tip values, and the equilibrium imbalance |reaction + load| / |load| of the coupled run.
Writes out/bar/coupled_comparison.md, out/bar/coupled_uy.png and coupled_error.png (gnuplot).
With --surface-correction energy the coupled models run with peridynamics.surface_correction
set (temporary copies; results in out/bar/coupled_<e>_energy, table
out/bar/coupled_comparison_energy.md).
With --clamp-elements N (N > 1) both the full-FE and the coupled models run (temporary copies)
with N B2 elements on the clamped span y in [0, 30] instead of one (suffix _cN): one element
clamped at y = 0 interpolates the Poisson contraction linearly from zero, so its interface
node contracts more than the uniaxial value; the PD block cannot follow that FE artefact and
the non-conservative fictitious-node coupling passes ~0.996 P into the span (1.04 P with the
h/2 fictitious element of cupid before issue 18; docs/coupling.md).
The environment's CUPID_FICTITIOUS_FE (removed | adjacent | plane | a length) reaches every
coupled run: the fictitious FE element's study switch (include/cupid/coupling.h).
"""
import argparse, csv, json, os, subprocess, sys, tempfile

ap = argparse.ArgumentParser()
ap.add_argument("--cupid", default="build/cupid")
ap.add_argument("--surface-correction", default="none", choices=["none", "energy"])
ap.add_argument("--clamp-elements", type=int, default=1)
ap.add_argument("expansions", nargs="*",
                default=["te1", "te2", "te3", "l4", "l9", "lagrange_l9", "arlequin_l9"])
a = ap.parse_args()
here = os.path.dirname(os.path.abspath(__file__))

def run(model, correction="none"):
    d = None
    for line in open(model):
        s = line.strip()
        if s.startswith("directory:"):
            d = s.split(":", 1)[1].split("#")[0].strip()
    if correction == "none" and a.clamp_elements == 1:
        subprocess.run([a.cupid, "run", model, "--quiet"], check=True)
        return d
    text = open(model).read()
    if correction != "none":
        # A copy with the key after partial_volume, in its own output directory.
        text = text.replace("  partial_volume: pdlammps\n",
                            f"  partial_volume: pdlammps\n  surface_correction: {correction}\n")
        assert "surface_correction" in text, model
        d = f"{d}_{correction}"
    if a.clamp_elements != 1:
        # the clamped span is the first entry (Arlequin models have five spans)
        n = a.clamp_elements
        if "elements: [1, 1, 1, 1, 1]" in text:
            text = text.replace("elements: [1, 1, 1, 1, 1]", f"elements: [{n}, 1, 1, 1, 1]")
        else:
            assert "elements: [1, 1, 1]" in text, model
            text = text.replace("elements: [1, 1, 1]", f"elements: [{n}, 1, 1]")
        d = f"{d}_c{a.clamp_elements}"
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as fh:
        fh.write(text)
    try:
        subprocess.run([a.cupid, "run", fh.name, "-o", d, "--quiet"], check=True)
    finally:
        os.unlink(fh.name)
    return d

def axis(d):
    return [(float(r["y"]), float(r["uy"]), r["region"]) for r in csv.DictReader(open(os.path.join(d, "line_axis.csv")))]

sfx = ("" if a.surface_correction == "none" else "_" + a.surface_correction) + \
      ("" if a.clamp_elements == 1 else f"_c{a.clamp_elements}")
rows = []
curves = []
for e in a.expansions:
    # "lagrange_l9": the Lagrange-multiplier model against the L9 full-FE bar.
    dfe = run(os.path.join(here, f"bar_fe_{e.split('_')[-1]}.yaml"))
    dc = run(os.path.join(here, f"bar_coupled_{e}.yaml"), a.surface_correction)
    fe, c = axis(dfe), axis(dc)
    tip = abs(fe[-1][1])
    rel = max(abs(u - v) / abs(v) for (y, u, _), (_, v, _) in zip(c, fe) if y > 0)
    relpd = max((abs(u - v) / abs(v) for (y, u, r), (_, v, _) in zip(c, fe) if r == "PD"), default=0)
    reltip = max(abs(u - v) for (_, u, _), (_, v, _) in zip(c, fe)) / tip
    s = json.load(open(os.path.join(dc, "summary.json")))
    load, reac = s["applied_load_sum"][1], s["reaction_sum"][1]
    rows.append((e, fe[-1][1], c[-1][1], rel, relpd, reltip, abs(load + reac) / abs(load),
                 s["phases"]["factorisation"]["time_s"]))
    curves.append((e, os.path.relpath(os.path.join(dc, "line_axis.csv"), "out/bar"),
                   os.path.relpath(os.path.join(dfe, "line_axis.csv"), "out/bar")))
    os.makedirs("out/bar", exist_ok=True)
    with open(f"out/bar/coupled_error_{e}{sfx}.csv", "w") as fh:   # paper Fig. 14C
        fh.write("y,rel_error_percent\n")
        for (y, u, _), (_, v, _) in zip(c, fe):
            if y > 0:
                fh.write(f"{y},{100 * (u - v) / v}\n")

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
    for e, c, f in curves:
        parts.append(f"'{c}' every ::1 using 3:6 with points pt 7 ps 0.5 title 'coupled {e}'")
        parts.append(f"'{f}' every ::1 using 3:6 with lines title 'FE {e}'")
    plot.append("plot " + ", ".join(parts))
    plot += [f"set output 'coupled_error{sfx}.png'", "set ylabel 'relative error of u_y [%]'",
             "plot " + ", ".join(f"'coupled_error_{e}{sfx}.csv' every ::1 using 1:2 with linespoints pt 7 ps 0.4 title '{e}'" for e, _, _ in curves)]
    subprocess.run(["gnuplot"], input="\n".join(plot), text=True, cwd="out/bar", check=True)
except Exception as ex:
    print("plot skipped:", ex, file=sys.stderr)
