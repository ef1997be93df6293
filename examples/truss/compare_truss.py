#!/usr/bin/env python3
"""Run the truss models (paper 004, section 4) and compare FE, PD and the exact solution.

usage: examples/truss/compare_truss.py [--out out/truss]

Runs every examples/truss/truss_*.yaml (FE, PD and the Arlequin-coupled trusses) through the
cupid Python package (python/cupid), each model's outputs written into OUT/<name> as
`cupid run -o OUT/<name>` writes them, then writes into OUT:
  comparison.md             RMS differences of the tip and mid-point histories against the
                            exact solution (mode sum, with the Rayleigh damping of each mode),
                            the energy balance and timings;
  exact.csv                 the exact histories (t, tip, mid; undamped and damped);
  history_<name>.csv        each model's computed histories (t, tip_uy, mid_uy);
  compare_<point>[_damped].png   FE, PD, Arlequin and exact histories (gnuplot).
The penalty and overlap-size sweeps of the Arlequin truss: examples/truss/arlequin_sweep.py.
Exact solution of the released uniform stretch eps0 = 1e-3 of a fixed-free bar:
  u(y, t) = sum_k 8 eps0 L (-1)^(k+1) / (pi^2 (2k-1)^2) sin(w_k y / c) q_k(t),
  w_k = (2k-1) pi c / (2L), q_k the free response of a mode with zeta_k = a/(2w_k) + b w_k/2
(the tip is a triangle wave of period T1 = 4L/c and amplitude eps0 L when undamped).
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
import cupid  # noqa: E402

E, RHO, L, EPS0 = 1e9, 7800.0, 1.0, 1e-3
C = math.sqrt(E / RHO)
MODES = 400


def exact(y, t, a=0.0, b=0.0):
    u = 0.0
    for k in range(1, MODES + 1):
        w = (2 * k - 1) * math.pi * C / (2 * L)
        amp = 8 * EPS0 * L * (-1) ** (k + 1) / (math.pi ** 2 * (2 * k - 1) ** 2)
        z = a / (2 * w) + b * w / 2
        if z < 1:
            wd = w * math.sqrt(1 - z * z)
            q = math.exp(-z * w * t) * (math.cos(wd * t) + z / math.sqrt(1 - z * z) * math.sin(wd * t))
        else:  # overdamped high modes: they carry ~nothing; critically damped form
            q = math.exp(-w * t) * (1 + w * t)
        u += amp * math.sin(w * y / C) * q
    return u


def run(model, d):
    """The model solved with its outputs in d: its history ({"t", "tip", "mid"}: arrays) and
    the "dynamic" block of its summary (steps, energy balance, time-stepping time)."""
    with cupid.Problem(model, output_dir=d) as p:
        p.solve().write_outputs()
        h = p.history
        # p.info has no dynamic block (steps, max_energy_balance_relative, time_stepping_s):
        # read it from the summary.json that write_outputs() wrote.
        with open(os.path.join(p.output_dir, "summary.json")) as f:
            dyn = json.load(f)["dynamic"]
    return {"t": h["t"], "tip": h["tip"][:, 1], "mid": h["mid"][:, 1]}, dyn


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="out/truss")
    a = ap.parse_args()
    here = os.path.dirname(os.path.abspath(__file__))
    models = sorted(f for f in os.listdir(here) if f.startswith("truss_") and f.endswith(".yaml"))
    os.makedirs(a.out, exist_ok=True)
    results = {}
    for m in models:
        name = m[len("truss_"):-len(".yaml")]
        d = os.path.join(a.out, name)
        hist, dyn = run(os.path.join(here, m), d)
        results[name] = (hist, dyn)
        with open(os.path.join(a.out, "history_%s.csv" % name), "w") as f:  # for the plots
            f.write("t,tip_uy,mid_uy\n")
            for row in zip(hist["t"], hist["tip"], hist["mid"]):
                f.write("%.10e,%.10e,%.10e\n" % row)
    # exact histories on the FE time grid
    ts = results["fe"][0]["t"]
    with open(os.path.join(a.out, "exact.csv"), "w") as f:
        f.write("t,tip,mid,tip_damped,mid_damped\n")
        for t in ts[::5]:
            vals = (exact(1.0, t), exact(0.5, t), exact(1.0, t, 0.1, 3.2e-6), exact(0.5, t, 0.1, 3.2e-6))
            f.write("%.8e,%.8e,%.8e,%.8e,%.8e\n" % ((t,) + vals))
    lines = ["| model | tip RMS err / 1e-3 | mid RMS err / 1e-3 | max energy balance | steps | time-stepping s |",
             "|---|---|---|---|---|---|"]
    for name, (hist, dyn) in results.items():
        ab = (0.1, 3.2e-6) if "damped" in name else (0.0, 0.0)
        err = {"tip": 0.0, "mid": 0.0}
        n = 0
        # every 5th step: 1100+ samples over 5 periods
        for t, tip, mid in zip(hist["t"][::5], hist["tip"][::5], hist["mid"][::5]):
            t = float(t)
            err["tip"] += (tip - exact(1.0, t, *ab)) ** 2
            err["mid"] += (mid - exact(0.5, t, *ab)) ** 2
            n += 1
        lines.append("| %s | %.4f | %.4f | %.1e | %d | %.3f |" % (
            name, math.sqrt(err["tip"] / n) / EPS0, math.sqrt(err["mid"] / n) / EPS0,
            dyn["max_energy_balance_relative"], dyn["steps"], dyn["time_stepping_s"]))
    with open(os.path.join(a.out, "comparison.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    if shutil.which("gnuplot"):
        for point in ("tip", "mid"):
            for suffix, col in (("", point), ("_damped", point + "_damped")):
                gp = os.path.join(a.out, "compare_%s%s.gp" % (point, suffix))
                with open(gp, "w") as f:
                    f.write('set terminal pngcairo size 1100,600\nset output "compare_%s%s.png"\n' % (point, suffix))
                    f.write('set datafile separator ","\nset key outside\nset xlabel "t (s)"\n')
                    f.write('set ylabel "u_y at %s (m)"\nset title "Truss (paper 004): %s%s"\n' % (point, point, suffix.replace("_", ", ")))
                    f.write('plot "exact.csv" u 1:"%s" w l lw 3 lc rgb "gray" t "exact (mode sum)", ' % col)
                    f.write('"history_fe%s.csv" u 1:"%s_uy" w l t "FE (CUF TE0, 80 nodes)", ' % (suffix, point))
                    f.write('"history_pd%s.csv" u 1:"%s_uy" w l t "PD (bond, 80 nodes)"' % (suffix, point))
                    # the Arlequin trusses (FE [0, 0.6] + PD [0.4, 1], 80 nodes), where present
                    for arl, label in (("arlequin" + suffix, "Arlequin, kappa 1e9"),
                                       ("arlequin_k1e11" + suffix, "Arlequin, kappa 1e11")):
                        if arl in results:
                            f.write(', "history_%s.csv" u 1:"%s_uy" w l t "%s"' % (arl, point, label))
                    f.write("\n")
                subprocess.run(["gnuplot", os.path.basename(gp)], cwd=a.out, check=True)


if __name__ == "__main__":
    main()
