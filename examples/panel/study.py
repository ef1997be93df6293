#!/usr/bin/env python3
"""FE-mesh and horizon study of the coupled stiffened panel (examples/panel/README.md).

usage: examples/panel/study.py [VARIANT ...] [--library build/libcupid.so] [--solver petsc]
                               [--against fine] [--balance momentum] [--list]

Each variant is panel_pd_l9.yaml with another beam mesh (axis breakpoints / elements / type),
section mesh (skin x, stringer z breakpoints) or PD horizon / surface correction, run with its
full-FE twin (the same beam and section mesh, no PD), so that A, B, C are compared with the FE
model they discretise. The models are built as dicts and solved through the cupid Python
package (python/cupid); each variant's two models are written to out/panel/study/<variant>/
(fe.yaml, pd.yaml: JSON, which `cupid run` reads) for rerunning by hand. Prints a markdown table (error of u_z at A, B and sigma_yy at C against
the twin, the equilibrium imbalance, time and peak memory) and writes it to
out/panel/study/study.md. Every coupled run takes ~5-10 s and up to 1.4 GB on 2 cores; all
variants about 3 minutes. With no VARIANT, all of them at h = 1 (the h0.5_* variants, which
need the matrix-free path: `--library build-petsc/libcupid.so --solver petsc`, ~10-15 s each,
are run only when named). `--against fine` also compares every row with the full FE of a section- and
beam-converged L9 mesh (REFERENCES; FE only).
"""
import argparse
import ctypes
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
import cupid  # noqa: E402

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
BALANCE = ["none"]  # coupling.balance of the coupled models (--balance)

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
    "x2": ("skin split beside the stringers and in 2 through its thickness, stringers in 2 "
           "elements across their thickness (h0.5_x2's FE mesh at h = 1)",
           dict(skin_x=SKIN_X2, skin_z="0,1,2", str_x="0,2,4")),
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


def nums(s):
    """A breakpoint list "0,12,24" as numbers."""
    return [float(v) for v in s.split(",")]


def stringer_x(p, x0):
    return [x0 + float(o) for o in p["str_x"].split(",")]


POINTS = [{"name": "A", "at": [195, 600, 1]}, {"name": "B", "at": [5, 600, 1]},
          {"name": "C", "at": [50, 100, 22], "stress": True}]


def models(p, d):
    """The full-FE and the coupled model of parameters p (dicts with the model file's keys),
    their outputs (if written) in d/fe and d/pd."""
    beam = {"material": "resin",
            "axis": {"y": nums(p["axis_y"]), "elements": [int(v) for v in p["axis_el"].split(",")],
                     "type": p["type"]},
            "section": {"expansion": "LE", "element": "L9", "components": [
                {"x": nums(p["skin_x"]), "z": nums(p["skin_z"])},
                {"x": stringer_x(p, 48), "z": nums(p["str_z"])},
                {"x": stringer_x(p, 148), "z": nums(p["str_z"])}]}}
    pd = {"spacing": float(p["h"]), "horizon": float(p["delta"]) * float(p["h"]), "model": "lps",
          "influence": "gaussian", "partial_volume": "pdlammps"}
    if p["sc"]:
        pd["surface_correction"] = p["sc"]
    pd["material"] = "resin"
    pd["regions"] = [{"x": [48, 52], "y": [290, 310], "z": [2, 22]},
                     {"x": [148, 152], "y": [290, 310], "z": [2, 22]}]

    def model(title, d_out, extra):
        m = {"title": title, "materials": {"resin": {"E": 10000, "nu": 0.2}}, "beam": beam}
        m.update(extra)
        m["constraints"] = [{"clamp": {"y": 0}}]
        m["loads"] = [{"traction": {"y": 600, "x": [190, 200], "z": [0, 2], "value": [0, 0, -1]}}]
        m["output"] = {"directory": d_out, "points": POINTS}
        return m

    return (model("panel study, full FE", d + "/fe", {}),
            model("panel study, coupled", d + "/pd",
                  {"peridynamics": pd, "coupling": {"method": "fictitious", "balance": BALANCE[0]},
                   "analysis": {"type": "static", "solver": "direct"}}))


def reset_peak_memory():
    """Restart the process's peak-RSS count (Linux >= 4.0), so that p.info's
    peak_memory_bytes (getrusage, the process's high-water mark) is this problem's, as
    /usr/bin/time measured a `cupid run` (the freed heap of the runs before handed back first)."""
    try:
        ctypes.CDLL(None).malloc_trim(0)
    except (OSError, AttributeError):
        pass
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass  # the peak of the whole script so far


def run(model, path, solver=None):
    """The model (dict) written to path (for `cupid run`) and solved: its output points as
    summary.json lists them, its counts and resultants (p.info) and its peak memory."""
    with open(path, "w") as f:
        json.dump(model, f, indent=1)
    reset_peak_memory()
    try:
        with cupid.Problem(model, solver=solver) as p:
            p.solve()
            info = p.info
            s = {"points": p.sample_output_points(), "counts": info,
                 "equilibrium_imbalance": [a + b for a, b in zip(info["load_sum"],
                                                                 info["reaction_sum"])],
                 "total_time_s": info["total_seconds"]}
    except cupid.Error as e:
        sys.exit(f"{path}: cupid failed ({e.status}): {e}")
    return s, info["peak_memory_bytes"]


def value(s, name, comp):
    return next(p for p in s["points"] if p["name"] == name)[comp]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("variants", nargs="*")
    ap.add_argument("--library", help="libcupid to load (default: $CUPID_LIBRARY, else "
                    "build/libcupid.so); build-petsc/libcupid.so for --solver petsc")
    ap.add_argument("--cupid", help=argparse.SUPPRESS)  # old form: the library beside this binary
    ap.add_argument("--solver", help="solver of the coupled runs (e.g. petsc)")
    ap.add_argument("--against", choices=sorted(REFERENCES),
                    help="also compare with this converged full-FE reference")
    ap.add_argument("--balance", choices=("none", "momentum"), default="none",
                    help="coupling.balance of the coupled models (docs/coupling.md)")
    ap.add_argument("--list", action="store_true")
    a = ap.parse_args()
    BALANCE[0] = a.balance
    if a.list:
        for k, (desc, _) in VARIANTS.items():
            print(f"{k:20s} {desc}")
        return
    for n in a.variants:
        if n not in VARIANTS:
            sys.exit(f"unknown variant '{n}' (--list names them)")
    names = a.variants or [k for k in VARIANTS if k not in OPT_IN]
    lib = a.library or (a.cupid and os.path.join(os.path.dirname(os.path.abspath(a.cupid)),
                                                 "libcupid.so"))
    if lib:  # read when the first problem is made
        os.environ["CUPID_LIBRARY"] = os.path.abspath(lib)
    base = os.path.join("out", "panel", "study" + ("_" + a.balance if a.balance != "none" else ""))
    ref = None
    if a.against:
        d = os.path.abspath(os.path.join(base, "ref_" + a.against))
        os.makedirs(d, exist_ok=True)
        fe_m, _ = models(dict(DEFAULTS, **REFERENCES[a.against]), d)
        ref, _ = run(fe_m, os.path.join(d, "fe.yaml"))
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
        fe_m, pd_m = models(p, d)
        fe, _ = run(fe_m, os.path.join(d, "fe.yaml"))
        pd, rss = run(pd_m, os.path.join(d, "pd.yaml"), a.solver)
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
