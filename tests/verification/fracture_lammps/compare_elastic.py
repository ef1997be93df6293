#!/usr/bin/env python3
"""cupid's history.csv of elastic_check.yaml against the stored LAMMPS run (elastic_lammps.csv).

  python3 compare_elastic.py out/elastic_check/history.csv

Standard library only. Each displacement history (p_ux, p_uy, q_ux, q_uy, q_uz) must agree to
TOL of its largest LAMMPS magnitude at every step. Measured: 1.5e-4 (LAMMPS's PMB uses the
nonlinear stretch and the current bond direction, cupid the linearised ones; strains here reach
~1e-3). Exit status 0 when all agree.
"""
import csv
import os
import sys

TOL = 1e-3
HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    lam = list(csv.DictReader(open(os.path.join(HERE, "elastic_lammps.csv"))))
    cup = list(csv.DictReader(open(sys.argv[1])))
    if len(cup) < len(lam):
        print("compare_elastic.py: %d cupid rows, %d LAMMPS steps" % (len(cup), len(lam)))
        return 1
    worst = 0.0
    for col in ("p_ux", "p_uy", "q_ux", "q_uy", "q_uz"):
        ref = [float(r[col]) * 1e3 for r in lam]          # m -> mm
        got = [float(cup[k][col]) for k in range(len(lam))]
        scale = max(abs(v) for v in ref)
        err = max(abs(a - b) for a, b in zip(ref, got)) / scale
        worst = max(worst, err)
        print("%-5s max |LAMMPS| %.4e mm, max |cupid - LAMMPS| / max |LAMMPS| = %.2e" % (col, scale, err))
    print("worst %.2e, tolerance %.0e: %s" % (worst, TOL, "ok" if worst <= TOL else "FAIL"))
    return 0 if worst <= TOL else 1


if __name__ == "__main__":
    sys.exit(main())
