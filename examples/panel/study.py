#!/usr/bin/env python3
"""FE-mesh and horizon study of the coupled stiffened panel (examples/panel/README.md).

usage: examples/panel/study.py [VARIANT ...] [--cupid build/cupid] [--solver petsc]
                               [--against fine] [--list]

Each variant is panel_pd_l9.yaml with another beam mesh (axis breakpoints / elements / type),
section mesh (skin x, stringer z breakpoints) or PD horizon / surface correction, run with its
full-FE twin (the same beam and section mesh, no PD), so that A, B, C are compared with the FE
model they discretise. Prints a markdown table (error of u_z at A, B and sigma_yy at C against
the twin, the equilibrium imbalance, time and peak memory) and writes it to
out/panel/study/study.md. Every coupled run takes ~5-10 s and up to 1.4 GB on 2 cores; all
variants about 3 minutes. With no VARIANT, all of them at h = 1 (the h0.5_* variants, which
need the matrix-free path: `--cupid build-petsc/cupid --solver petsc`, ~10-15 s each, are run
only when named). `--against fine` also compares every row with the full FE of a section- and
beam-converged L9 mesh (REFERENCES; FE only).
"""
import argparse
import json
import os
import subprocess
import sys

SKIN = "0,12,24,36,48,52,64,76,88,100,112,124,136,148,152,164,176,190,200"
SKIN44 = "0,12,24,36,44,48,52,56,64,76,88,100,112,124,136,144,148,152,156,164,176,190,200"
ADJ = dict(axis_y="0,280,290,310,320,600", axis_el="4,1,1,1,3")
STRIP = dict(axis_y="0,250,290,290.5,309.5,310,350,600", axis_el="4,1,1,1,1,1,3")
SC = "energy"
# Skin split beside the stringers (x 42, 46 | 54, 58) and at the stringers' mid-planes (50):
# conforming with stringers of 2 or 4 elements across their thickness.
def breaks(s):
    """Breakpoints in ascending order (lists built by joining pieces)."""
    return ",".join(sorted(s.split(","), key=float))


SKIN_B = "0,12,24,36,42,46,48,52,54,58,64,76,88,100,112,124,136,142,146,148,152,154,158,164,176,190,200"
SKIN_X2 = SKIN_B.replace("48,52", "48,50,52").replace("148,152", "148,150,152")
SKIN_X4 = SKIN_B.replace("48,52", "48,49,50,51,52").replace("148,152", "148,149,150,151,152")
H05 = dict(h="0.5")

# name: (description, overrides of the example's parameters)
VARIANTS = {
    "example": ("the example: y [0,290,310,600], elements [4,1,3] B4; stringer z [2,7,12,17,22]", {}),
    "region2": ("2 B4 across each region ([4,2,3])", dict(axis_el="4,2,3")),
    "region4": ("4 B4 across each region ([4,4,3])", dict(axis_el="4,4,3")),
    "b3": ("B3 instead of B4", dict(type="B3")),
    "adj40": ("40 mm elements next to the regions (y ..250,290,310,350..)",
              dict(axis_y="0,250,290,310,350,600", axis_el="4,1,1,1,3")),
    "adj40_region2": ("same, 2 B4 across the regions and their neighbours",
                      dict(axis_y="0,250,290,310,350,600", axis_el="4,2,2,2,3")),
    "adj20": ("20 mm elements next to the regions (y ..270,290,310,330..)",
              dict(axis_y="0,270,290,310,330,600", axis_el="4,1,1,1,3")),
    "adj10": ("10 mm elements next to the regions (y ..280,290,310,320..)", ADJ),
    "adj_graded": ("graded 10-50 mm elements on both sides (11 B4)",
                   dict(axis_y="0,200,250,270,280,290,310,320,330,350,400,600",
                        axis_el="3,1,1,1,1,1,1,1,1,1,2")),
    "strip_y": ("h/2 beam elements at the normal interfaces (y ..290,290.5,309.5,310..)", STRIP),
    "strip_z": ("h/2 stringer element at the foot (z [2,2.5,7,..])", dict(str_z="2,2.5,7,12,17,22")),
    "strip_yz": ("both h/2 strips (paper-like fictitious FEs)", dict(STRIP, str_z="2,2.5,7,12,17,22")),
    "z1mm": ("1 mm stringer element at the foot (z [2,3,7,..])", dict(str_z="2,3,7,12,17,22")),
    "z2el": ("2 stringer elements (z [2,12,22])", dict(str_z="2,12,22")),
    "z1el": ("1 stringer element (z [2,22])", dict(str_z="2,22")),
    "adj10_z5el": ("adj10 + 5 stringer elements (z [2,6,..,22])", dict(ADJ, str_z="2,6,10,14,18,22")),
    "adj10_z3el": ("adj10 + 3 stringer elements (z [2,9,15.5,22])", dict(ADJ, str_z="2,9,15.5,22")),
    "adj10_zgraded": ("adj10 + z [2,8,13,17.5,22]", dict(ADJ, str_z="2,8,13,17.5,22")),
    "skin4": ("4 mm skin elements beside the stringers (x ..44,48,52,56..)", dict(skin_x=SKIN44)),
    "m2": ("the example, m = 2", dict(delta="2.0")),
    "m1.5": ("the example, m = 1.5", dict(delta="1.5")),
    "adj10_m2.5": ("adj10, m = 2.5", dict(ADJ, delta="2.5")),
    "adj10_m2": ("adj10, m = 2", dict(ADJ, delta="2.0")),
    "adj10_energy": ("adj10, surface correction", dict(ADJ, sc=SC)),
    "adj10_m2_energy": ("adj10, m = 2, surface correction", dict(ADJ, delta="2.0", sc=SC)),
    "adj10_m1.5_energy": ("adj10, m = 1.5, surface correction", dict(ADJ, delta="1.5", sc=SC)),
    "h0.5": ("the example, h = 0.5 (8 x 40 x 40 PD nodes per stringer)", H05),
    "h0.5_skin": ("h = 0.5, skin split beside the stringers and in 2 through its thickness",
                  dict(H05, skin_x=SKIN_B, skin_z="0,1,2")),
    "h0.5_x2": ("h0.5_skin + stringers in 2 elements across their thickness",
                dict(H05, skin_x=SKIN_X2, skin_z="0,1,2", str_x="0,2,4")),
    "h0.5_x4": ("h = 0.5, skin in 4 through its thickness, stringers in 4 across theirs",
                dict(H05, skin_x=SKIN_X4, skin_z="0,0.5,1,1.5,2", str_x="0,1,2,3,4")),
}
OPT_IN = {k for k in VARIANTS if k.startswith("h0.5")}

# Full-FE references (FE only): the section and beam mesh refined until A, B, C move by less
# than 0.2% (README.md: from the example's mesh, B moves by +3.9%).
REFERENCES = {
    "fine": dict(skin_x=breaks(SKIN_X4 + ",30,44,56,70,130,144,156,170"), skin_z="0,0.5,1,1.5,2",
                 str_x="0,1,2,3,4", str_z="2,2.5,3,4,5,6,7.5,9,11,13,15,17,19.5,22",
                 axis_el="12,2,9"),
}

DEFAULTS = dict(axis_y="0,290,310,600", axis_el="4,1,3", type="B4", skin_x=SKIN,
                skin_z="0,2", str_x="0,4", str_z="2,7,12,17,22", delta="3.0", h="1.0", sc=None)


def lst(s):
    return "[" + ", ".join(s.split(",")) + "]"



def stringer_x(p, x0):
    return ",".join(f"{x0 + float(o):g}" for o in p["str_x"].split(","))


def models(p, d):
    beam = f"""materials:
  resin: {{E: 10000, nu: 0.2}}
beam:
  material: resin
  axis: {{y: {lst(p['axis_y'])}, elements: {lst(p['axis_el'])}, type: {p['type']}}}
  section:
    expansion: LE
    element: L9
    components:
      - {{x: {lst(p['skin_x'])}, z: {lst(p['skin_z'])}}}
      - {{x: {lst(stringer_x(p, 48))}, z: {lst(p['str_z'])}}}
      - {{x: {lst(stringer_x(p, 148))}, z: {lst(p['str_z'])}}}
"""
    sc = f"  surface_correction: {p['sc']}\n" if p["sc"] else ""
    pd = f"""peridynamics:
  spacing: {p['h']}
  horizon: {float(p['delta']) * float(p['h']):g}
  model: lps
  influence: gaussian
  partial_volume: pdlammps
{sc}  material: resin
  regions:
    - {{x: [48, 52], y: [290, 310], z: [2, 22]}}
    - {{x: [148, 152], y: [290, 310], z: [2, 22]}}
coupling: {{method: fictitious}}
analysis: {{type: static, solver: direct}}
"""
    rest = """constraints:
  - clamp: {y: 0}
loads:
  - traction: {y: 600, x: [190, 200], z: [0, 2], value: [0, 0, -1]}
output:
  directory: DIR
  points:
    - {name: A, at: [195, 600, 1]}
    - {name: B, at: [5, 600, 1]}
    - {name: C, at: [50, 100, 22], stress: true}
"""
    return ("title: panel study, full FE\n" + beam + rest.replace("DIR", d + "/fe"),
            "title: panel study, coupled\n" + beam + pd + rest.replace("DIR", d + "/pd"))


def run(cupid, path, outdir, extra=()):
    timer = ["/usr/bin/time", "-f", "%M"] if os.path.exists("/usr/bin/time") else []
    r = subprocess.run(timer + [cupid, "run", path, "--quiet", *extra], capture_output=True,
                       text=True)
    if r.returncode:
        sys.exit(f"{path}: cupid failed\n{r.stdout}{r.stderr}")
    s = json.load(open(os.path.join(outdir, "summary.json")))
    try:
        rss = int(r.stderr.strip().split()[-1]) * 1024
    except (ValueError, IndexError):
        rss = s["peak_memory_bytes"]
    return s, rss


def value(s, name, comp):
    return next(p for p in s["points"] if p["name"] == name)[comp]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("variants", nargs="*")
    ap.add_argument("--cupid", default="build/cupid")
    ap.add_argument("--solver", help="solver of the coupled runs (e.g. petsc)")
    ap.add_argument("--against", choices=sorted(REFERENCES),
                    help="also compare with this converged full-FE reference")
    ap.add_argument("--list", action="store_true")
    a = ap.parse_args()
    if a.list:
        for k, (desc, _) in VARIANTS.items():
            print(f"{k:20s} {desc}")
        return
    for n in a.variants:
        if n not in VARIANTS:
            sys.exit(f"unknown variant '{n}' (--list names them)")
    names = a.variants or [k for k in VARIANTS if k not in OPT_IN]
    base = os.path.join("out", "panel", "study")
    extra = ("--solver", a.solver) if a.solver else ()
    ref = None
    if a.against:
        d = os.path.abspath(os.path.join(base, "ref_" + a.against))
        os.makedirs(d, exist_ok=True)
        fe_y, _ = models(dict(DEFAULTS, **REFERENCES[a.against]), d)
        with open(os.path.join(d, "fe.yaml"), "w") as f:
            f.write(fe_y)
        ref, _ = run(a.cupid, os.path.join(d, "fe.yaml"), os.path.join(d, "fe"))
        print(f"reference '{a.against}' (full FE, {ref['counts']['fe_dofs']} DOFs): A "
              f"{value(ref, 'A', 'uz'):.4f}, B {value(ref, 'B', 'uz'):.4f}, "
              f"C {value(ref, 'C', 'syy'):.4f}\n")
    vs = " | coupled vs reference A, B, C" if ref else ""
    rows = ["| variant | configuration | FE DOFs | u_z A | u_z B | sigma_yy C | imbalance x, y, z [N] "
            "| time, peak memory" + vs + " |", "|---|---|---|---|---|---|---|---|" + ("---|" if ref else "")]
    print("\n".join(rows), flush=True)
    for n in names:
        desc, over = VARIANTS[n]
        p = dict(DEFAULTS, **over)
        d = os.path.abspath(os.path.join(base, n))
        os.makedirs(d, exist_ok=True)
        fe_y, pd_y = models(p, d)
        for name, text in (("fe.yaml", fe_y), ("pd.yaml", pd_y)):
            with open(os.path.join(d, name), "w") as f:
                f.write(text)
        fe, _ = run(a.cupid, os.path.join(d, "fe.yaml"), os.path.join(d, "fe"))
        pd, rss = run(a.cupid, os.path.join(d, "pd.yaml"), os.path.join(d, "pd"), extra)
        cells = []
        for pt, c in (("A", "uz"), ("B", "uz"), ("C", "syy")):
            f, q = value(fe, pt, c), value(pd, pt, c)
            cells.append(f"{q:.4f} / {f:.4f} ({100 * (q / f - 1):+.2f}%)")
        imb = ", ".join(f"{v:.2f}" for v in pd["equilibrium_imbalance"])
        row = (f"| {n} | {desc} | {fe['counts']['fe_dofs']} | " + " | ".join(cells) +
               f" | {imb} | {pd['total_time_s']:.1f} s, {rss / 1e9:.2f} GB |")
        if ref:
            row += " " + ", ".join(
                f"{100 * (value(pd, pt, c) / value(ref, pt, c) - 1):+.2f}%"
                for pt, c in (("A", "uz"), ("B", "uz"), ("C", "syy"))) + " |"
        rows.append(row)
        print(row, flush=True)
    with open(os.path.join(base, "study.md"), "w") as f:
        f.write("\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
