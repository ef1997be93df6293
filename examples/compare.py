#!/usr/bin/env python3
"""Run every model of an example directory and compare them.

usage: examples/compare.py EXAMPLE_DIR [--line NAME] [--component uz] [--max-memory GB]

Runs each *.yaml of EXAMPLE_DIR (in name order) through the cupid Python package (python/cupid,
the library the command line uses), writes each model's outputs as `cupid run` does, then writes
into out/<example>/: comparison.md (a table of DOFs, time and every output point) and
comparison_<line>.png (the chosen component along the line for every model, by gnuplot). A
model that needs more memory than the limit (or fails) gets a line saying so and the table goes
on without it.
"""
import argparse
import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import cupid  # noqa: E402


def run(model, max_memory_gb):
    """The model solved and its outputs written; its summary as the command line's fields."""
    with cupid.Problem(model, max_memory_gb=max_memory_gb) as p:
        p.solve().write_outputs()
        info = p.info
        m_points = p.sample_output_points()
        return p.output_dir, info, m_points


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("example")
    ap.add_argument("--max-memory", type=float, default=0.0,
                    help="GB; default: 90%% of the physical memory, as cupid run")
    ap.add_argument("--line", default=None)
    ap.add_argument("--component", default=None)
    a = ap.parse_args()
    models = sorted(f for f in os.listdir(a.example) if f.endswith(".yaml"))
    name = os.path.basename(os.path.normpath(a.example))
    out = os.path.join("out", name)
    os.makedirs(out, exist_ok=True)
    rows, curves = [], []
    for m in models:
        path = os.path.join(a.example, m)
        try:
            d, info, points = run(path, a.max_memory)
        except cupid.Error as e:
            print(f"{m}: skipped ({e.status}): {e}", file=sys.stderr)
            continue
        s = {"counts": info, "total_time_s": info["total_seconds"], "points": points,
             "cupid_version": cupid.version()}
        rows.append((m, s))
        lines = [f for f in os.listdir(d) if f.startswith("line_") and f.endswith(".csv")]
        line = f"line_{a.line}.csv" if a.line else (sorted(lines)[0] if lines else None)
        if line and os.path.exists(os.path.join(d, line)):
            curves.append((m, os.path.relpath(os.path.join(d, line), out), line))
    if not rows:
        print("no model of %s ran" % a.example, file=sys.stderr)
        return 1
    pts = [p["name"] for p in rows[0][1]["points"]]
    comp = {}
    for p in rows[0][1]["points"]:
        comp[p["name"]] = ["uy", "uz"] + (["syy"] if "syy" in p else [])
    header = "| model | FE DOFs | PD nodes | time [s] | " + " | ".join(
        f"{c} at {p}" for p in pts for c in comp[p]) + " |"
    md = [f"# {name}: comparison (cupid {rows[0][1]['cupid_version']})", "", header,
          "|" + "---|" * (header.count("|") - 1)]
    for m, s in rows:
        vals = {p["name"]: p for p in s["points"]}
        cells = [m, str(s["counts"]["fe_dofs"]), str(s["counts"]["pd_nodes"]),
                 f"{s['total_time_s']:.2f}"]
        cells += [f"{vals[p][c]:.5g}" for p in pts for c in comp[p]]
        md.append("| " + " | ".join(cells) + " |")
    open(os.path.join(out, "comparison.md"), "w").write("\n".join(md) + "\n")
    print("\n".join(md))
    if curves and shutil.which("gnuplot"):
        col = {"ux": 5, "uy": 6, "uz": 7}[a.component or ("uz" if name != "bar" else "uy")]
        stem = "comparison_" + curves[0][2][5:-4]
        gp = [
            "set terminal pngcairo size 1000,650 enhanced font 'sans,11'",
            f"set output '{stem}.png'", "set datafile separator ','",
            "set key below", "set grid", "set xlabel 's (distance along the line) [mm]'",
            f"set ylabel '{['u_x', 'u_y', 'u_z'][col - 5]} [mm]' noenhanced",
            f"set title '{name}: {['u_x', 'u_y', 'u_z'][col - 5]} along the line, every model' noenhanced",
            "plot " + ", ".join(
                f"'{c}' skip 1 using 1:{col} with linespoints pt 7 ps 0.3 title '{m[:-5]}' noenhanced"
                for m, c, _ in curves),
        ]
        open(os.path.join(out, stem + ".gp"), "w").write("\n".join(gp) + "\n")
        subprocess.run(["gnuplot", stem + ".gp"], cwd=out, check=True)
        print(f"plot: {os.path.join(out, stem + '.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
