#!/usr/bin/env python3
"""Period of the FE truss (truss_fe.yaml, CUF TE0 rod) with paper 004's Poisson ratio.

usage: examples/truss/poisson_period.py [--cupid build/cupid] [--out out/truss/poisson]

Runs truss_fe.yaml with nu = 0 (the file's value), and with nu = 0.25 (paper 004, section 4)
with the Poisson-locking correction (beam.poisson_correction: auto, on for TE0) and without it
(off), and measures the period of the tip history (the mean spacing of its zero crossings,
linearly interpolated, over the 5 periods of the run) against the rod's T1 = 4 L / c,
c = sqrt(E / rho); without the correction the rod's modulus is C_yyyy = E (1 - nu) /
((1 + nu)(1 - 2 nu)) = 1.2 E and its period T1 / sqrt(1.2) = 0.913 T1.
"""
import argparse
import csv
import math
import os
import subprocess

E, RHO, L = 1e9, 7800.0, 1.0
T1 = 4 * L / math.sqrt(E / RHO)


def period(history):
    t, u = [], []
    with open(history) as f:
        for row in csv.DictReader(f):
            t.append(float(row["t"]))
            u.append(float(row["tip_uy"]))
    cross = [t[i] - u[i] * (t[i + 1] - t[i]) / (u[i + 1] - u[i])
             for i in range(len(u) - 1) if u[i] * u[i + 1] < 0]
    return 2 * (cross[-1] - cross[0]) / (len(cross) - 1), len(cross)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser()
    ap.add_argument("--cupid", default=os.path.join(here, "..", "..", "build", "cupid"))
    ap.add_argument("--out", default="out/truss/poisson")
    a = ap.parse_args()
    nu = 0.25
    locked = (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    cases = [("nu = 0 (file)", []),
             ("nu = 0.25, correction auto (on)", ["materials.steel.nu=0.25"]),
             ("nu = 0.25, correction off", ["materials.steel.nu=0.25", "beam.poisson_correction=off"])]
    print(f"T1 = 4 L / c = {T1 * 1e3:.5f} ms; locked rod T1 / sqrt({locked:.3f}) = "
          f"{T1 / math.sqrt(locked) * 1e3:.5f} ms\n")
    print("| model | period (ms) | period / T1 - 1 | zero crossings |")
    print("|---|---|---|---|")
    for k, (name, sets) in enumerate(cases):
        d = os.path.join(a.out, f"case{k}")
        cmd = [a.cupid, "run", os.path.join(here, "truss_fe.yaml"), "-o", d, "--quiet"]
        for s in sets:
            cmd += ["--set", s]
        subprocess.run(cmd + ["--set", "output.vtu=false", "--set", "output.plots=false"], check=True)
        p, n = period(os.path.join(d, "history.csv"))
        print(f"| {name} | {p * 1e3:.5f} | {p / T1 - 1:+.2e} | {n} |")


if __name__ == "__main__":
    main()
