#!/usr/bin/python3
"""The double cantilever beam against corrected beam theory: load against crack length.

    /usr/bin/python3 examples/fracture/dcb_study.py [--h 1 0.5] [--cupid build/cupid]
        [--out out/fracture/dcb] [--threads N] [--reuse]

Runs examples/fracture/dcb_pd.yaml (all PD, bond-based, surface-corrected; the arms never
break, so the crack runs along the plane x = 5) at each grid spacing h with m = 3 (horizon
3.015 h), and once at the coarsest without the surface correction, and writes into OUT:
  dcb.md              per run: h, nodes, the peak load against the theory at a0, the worst
                      step of the growth against the theory at its crack length, seconds, MB;
  dcb_load.png        each step's load against its crack length a = a0 + (bonds broken) /
                      (the pre-crack's bonds per unit length), with the theory's curve.
Corrected beam theory (shared/reference/fracture.md; Kanninen 1973):
G = 12 P^2 (a + chi H)^2 / (E B^2 H^3), chi = 0.64, so P(a) = sqrt(G0 E B^2 H^3 / 12) / (a + chi H).
Needs gnuplot (scripts/install-deps.sh).
"""
import argparse
import math
import os
import subprocess
import sys

from senb_study import cupid_run  # this folder's

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
G0, E, B, H, CHI, A0 = 0.01006, 22350.0, 3.0, 5.0, 0.64, 25.0
M_RATIO = 3.015


def theory(a):
    """The load at which an arm pair with crack length a grows (corrected beam theory)."""
    return math.sqrt(G0 * E * B * B * H ** 3 / 12) / (a + CHI * H)


def run(cupid, h, corrected, out, threads, reuse):
    """One run at spacing h; returns its row (dict) and its (a, P) points."""
    d = os.path.join(out, "h%g%s" % (h, "" if corrected else "_uncorrected"))
    # the pin lines (one node line at each arm's mid-height) and the clamp, a spacing wide
    sets = ["--set", "peridynamics.spacing=%g" % h,
            "--set", "peridynamics.horizon=%.17g" % (M_RATIO * h),
            "--set", "constraints[0].displacement.box={x: [7, %g], y: [0, %g]}" % (7 + h, h),
            "--set", "constraints[1].displacement.box={x: [%g, 3], y: [0, %g]}" % (3 - h, h),
            "--set", "constraints[2].fix.box={y: [%g, 60]}" % (60 - h),
            "--set", "output.vtu=false", "--set", "output.plots=false"]
    if not corrected:
        sets += ["--set", "peridynamics.surface_correction=none"]
    s, rows = cupid_run(cupid, os.path.join(HERE, "dcb_pd.yaml"), d, sets, threads, reuse)
    fr = s["fracture"]
    per_length = fr["precrack_bonds_removed"] / A0
    points = [(A0 + float(r["broken_bonds"]) / per_length, float(r["reaction_0_x"])) for r in rows]
    growing = [(a, p) for (a, p), r in zip(points, rows)
               if float(r["broken_bonds"]) > 0.01 * fr["precrack_bonds_removed"]]
    worst = max((p / theory(a) - 1 for a, p in growing), key=abs) if growing else float("nan")
    peak = fr["peak_reactions"][0]["reaction"][0]
    info = {"h": h, "corrected": corrected, "pd_nodes": s["counts"]["pd_nodes"], "peak_N": peak,
            "peak_error_%": 100 * (peak / theory(A0) - 1), "growth_error_%": 100 * worst,
            "a_end": points[-1][0], "seconds": s["total_time_s"],
            "memory_MB": s["peak_memory_bytes"] / 2 ** 20}
    return info, points


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--h", nargs="+", type=float, default=[1.0, 0.5])
    ap.add_argument("--cupid", default=os.path.join(ROOT, "build", "cupid"))
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "fracture", "dcb"))
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--reuse", action="store_true")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    cases = [(h, True) for h in args.h] + [(max(args.h), False)]
    infos, series = [], []
    for h, corrected in cases:
        info, points = run(args.cupid, h, corrected, args.out, args.threads, args.reuse)
        infos.append(info)
        print("h = %g%s: peak %.3f N (theory %.3f N at a0: %+.1f%%), growth within %+.1f%%, "
              "a at the end %.2f, %.0f s" % (h, "" if corrected else " uncorrected", info["peak_N"],
                                             theory(A0), info["peak_error_%"],
                                             info["growth_error_%"], info["a_end"],
                                             info["seconds"]), flush=True)
        dat = os.path.join(args.out, "points_h%g%s.dat" % (h, "" if corrected else "_uncorrected"))
        with open(dat, "w") as f:
            f.write("".join("%g %g\n" % p for p in points))
        series.append('"%s" u 1:2 w lp pt %d ps 1 lw 2 t "PD, h = %g%s"' % (
            dat, 7 if corrected else 6, h, "" if corrected else ", uncorrected"))
    with open(os.path.join(args.out, "dcb.md"), "w") as f:
        f.write("| h | surface correction | PD nodes | peak P (N) | against theory at a0 | "
                "growth: worst step against theory | a at the end (mm) | time (s) | memory (MB) |\n"
                "|---|---|---|---|---|---|---|---|---|\n")
        for i in infos:
            f.write("| %g | %s | %d | %.3f | %+.1f%% | %+.1f%% | %.1f | %.0f | %.0f |\n" % (
                i["h"], "energy" if i["corrected"] else "none", i["pd_nodes"], i["peak_N"],
                i["peak_error_%"], i["growth_error_%"], i["a_end"], i["seconds"], i["memory_MB"]))
    th = os.path.join(args.out, "theory.dat")
    with open(th, "w") as f:
        for k in range(101):
            a = 22.0 + 12.0 * k / 100
            f.write("%g %g\n" % (a, theory(a)))
    series.insert(0, '"%s" u 1:2 w l lw 2 dt 2 lc rgb "black" t "corrected beam theory, chi = %g"'
                  % (th, CHI))
    subprocess.run(["gnuplot"], input=("""set terminal pngcairo size 800,500 font ",11"
set output "%s/dcb_load.png"
set title "DCB: load against crack length (each load step)"
set xlabel "crack length a [mm] (a0 + bonds broken / the pre-crack's bonds per mm)"
set ylabel "load P [N]"
set grid
set key top right
set xrange [24:34]
set yrange [0:6]
plot %s
""" % (args.out, ", \\\n     ".join(series))).encode(), check=True)
    print("wrote %s/dcb.md, dcb_load.png" % args.out)


if __name__ == "__main__":
    sys.exit(main())
