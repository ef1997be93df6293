"""The stiffened panel's reported figures (u_z at A and B, sigma_yy at C) of a coupled run
against two full-FE runs: a table, and the points outside the bound against the first one.

usage: python3 panel_points.py COUPLED_DIR BOUNDED_REF_DIR OTHER_REF_DIR LABEL BOUND_PERCENT
       [B_BOUND_PERCENT]
Each DIR holds a cupid summary.json; LABEL names the three columns ("coupled,ref,other").
Exit status 1 if a point is off the bounded reference by more than its bound (B may have its
own). Shared by the panel tests (verification.mpi_panel_fine, verification.mpi_panel_arlequin).
"""
import json
import sys


def load(d):
    return {p["name"]: p for p in json.load(open(f"{d}/summary.json"))["points"]}


def main():
    run, ref, other, label, bound = sys.argv[1:6]
    b_bound = float(sys.argv[6]) if len(sys.argv) > 6 else float(bound)
    names = label.split(",")
    c, r, o = load(run), load(ref), load(other)
    print(f"point  {names[0]:>14s}  {names[1]:>14s}  (error)  {names[2]:>14s}  (error)")
    good = True
    for name, comp in (("A", "uz"), ("B", "uz"), ("C", "syy")):
        a, b, e = c[name][comp], r[name][comp], o[name][comp]
        err = 100 * (a / b - 1)
        print(f"{name} {comp:4s} {a:14.5f}  {b:14.5f} ({err:+.2f}%)  {e:14.5f} ({100 * (a / e - 1):+.2f}%)")
        lim = b_bound if name == "B" else float(bound)
        if abs(err) > lim:
            print(f"FAIL: {name}: {err:+.2f}% from {names[1]} (bound {lim:g}%)")
            good = False
    return 0 if good else 1


if __name__ == "__main__":
    sys.exit(main())
