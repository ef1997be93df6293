#!/usr/bin/python3
"""The single-edge-notched beam's horizon study: peak load against ASTM E399, PD-only and coupled.

    /usr/bin/python3 examples/fracture/senb_study.py [--h 5/3 1.25 1 5/6]
        [--models pd coupled fictitious corrected] [--fine 1/2 5/12 1/3] [--cupid build/cupid]
        [--out out/fracture/study] [--threads N] [--reuse]

Runs examples/fracture/senb_pd.yaml (all PD) and senb_coupled.yaml (CUF beam + PD around the
notch, Arlequin; `fictitious`: the same beam coupled by fictitious nodes, paper 000, with the
default balance; `corrected`: the Arlequin beam with peridynamics.surface_correction: energy,
issue 38) at each grid spacing h with m = 3 (horizon 3.015 h). --fine adds finer spacings for
the corrected beam only, with PD on y in [35, 55] (overlaps [35, 40] and [50, 55], the beam
axis refined to match: bench/fracture_senb_scale.sh's model; 16,000, 27,648 and 54,000 PD
nodes at h = 1/2, 5/12, 1/3, about 10, 20 and 70 minutes and 2.6, 5.7 and 14.3 GB on 2
cores). It writes into OUT:
  study.csv, study.md       per run: h, delta, nodes, the peak load P (constraint 0's reaction on
                            the sawtooth envelope, summary.json fracture.peak_reactions), the
                            load of the first break, P against E399, bonds broken, seconds;
  load_displacement.png     P against the load point's deflection, every run;
  peak_vs_horizon.png       P against delta with E399's plane-stress to plane-strain band
                            and, with three or more corrected runs, the quadratic in delta
                            through the three finest, extrapolated to delta = 0;
  damage_<model>_h<h>.png   the side face (z = h/2) of the finest run of each model, nodes
                            coloured by damage, displaced 30x.
--reuse skips runs whose summary.json is there. Needs gnuplot (scripts/install-deps.sh).

E399 (shared/reference/fracture.md): K_I = P S / (B W^1.5) f(a/W),
f(a) = 3 sqrt(a) [1.99 - a (1 - a)(2.15 - 3.93 a + 2.7 a^2)] / (2 (1 + 2a)(1 - a)^1.5), and
K_Ic = sqrt(E G0) (plane stress) or sqrt(E G0 / (1 - nu^2)) (plane strain).
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
from fractions import Fraction

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
MODELS = {"pd": "senb_pd.yaml", "coupled": "senb_coupled.yaml", "fictitious": "senb_coupled.yaml",
          "corrected": "senb_coupled.yaml"}
EXTRA = {"fictitious": ["--set", "coupling={method: fictitious}"],
         "corrected": ["--set", "peridynamics.surface_correction=energy"]}
LABEL = {"pd": "PD only", "coupled": "CUF + PD (Arlequin)", "fictitious": "CUF + PD (fictitious nodes)",
         "corrected": "CUF + PD (Arlequin), surface-corrected"}
STYLE = {"pd": (7, 1), "coupled": (5, 2), "fictitious": (9, 4), "corrected": (11, 1)}  # point, dash
W, S, B, A, E, NU, G0 = 20.0, 80.0, 5.0, 10.0, 22350.0, 0.25, 0.01006
M_RATIO = 3.015
# The fine runs' zone: PD on y in [35, 55] instead of the model's [30, 60], the beam's elements
# ending at the overlaps' edges (the 2.5 mm elements of the coarse model are too long for 1 mm
# overlaps' quadrature; bench/fracture_senb_scale.sh runs the same model).
FINE_ZONE = ["--set", "beam.axis={y: [0, 5, 35, 40, 50, 55, 85, 90], elements: [1, 6, 1, 2, 1, 6, 1], type: B4}",
             "--set", "peridynamics.regions=[{x: [0, 20], y: [35, 55], z: [0, 5]}]",
             "--set", "coupling.arlequin.overlap=[{y: [35, 40]}, {y: [50, 55]}]"]
OVERLAPS = {False: ((30, 35), (55, 60)), True: ((35, 40), (50, 55))}  # the side views' grey bands
WARP = 30  # the side views' displacement scale


def e399_loads():
    """P_c (plane stress, plane strain) of the E399 formula for this beam."""
    a = A / W
    f = 3 * math.sqrt(a) * (1.99 - a * (1 - a) * (2.15 - 3.93 * a + 2.7 * a * a)) / (
        2 * (1 + 2 * a) * (1 - a) ** 1.5)
    p = lambda k: k * B * W ** 1.5 / (S * f)
    return p(math.sqrt(E * G0)), p(math.sqrt(E * G0 / (1 - NU * NU)))


def surface_fraction(h, B=B):
    """G_eff / G0 of the PD slab: the bond-based energy to break every bond across a plane
    normal to y through a plate B thick (nodes at cell centres, constant influence, the
    families cut by the faces z = 0 and z = B), against an unbounded body's. With s0 from G0
    (Silling & Askari) the latter is G0; the thin beam's truncated families hold less."""
    d, r = M_RATIO * h, int(math.ceil(M_RATIO)) + 1
    offs = [(a, b, c) for a in range(-r, r + 1) for b in range(1, r + 1) for c in range(-r, r + 1)
            if math.sqrt(a * a + b * b + c * c) * h <= d]
    nz = int(round(B / h))
    w = lambda a, b, c: b * math.sqrt(a * a + b * b + c * c)  # b rows of bonds cross the plane
    bulk = nz * sum(w(*o) for o in offs)
    slab = sum(w(a, b, c) for k in range(nz) for a, b, c in offs if 0 <= k + c < nz)
    return slab / bulk


def cupid_run(cupid, model, d, sets, threads, reuse):
    """cupid run MODEL -o D with the --set arguments SETS (skipped where reuse finds D's
    summary.json); its summary.json and damage.csv rows. dcb_study.py runs its models so too."""
    if not (reuse and os.path.exists(os.path.join(d, "summary.json"))):
        cmd = [cupid, "run", model, "-o", d, "--quiet"] + list(sets)
        if threads:
            cmd += ["--threads", str(threads)]
        subprocess.run(cmd, check=True, cwd=ROOT)
    return (json.load(open(os.path.join(d, "summary.json"))),
            list(csv.DictReader(open(os.path.join(d, "damage.csv")))))


def run(cupid, model, h, out, threads, reuse, fine=False):
    """One run (fine: in FINE_ZONE); returns its row (dict) and the load-displacement curve [(d, P)]."""
    d = os.path.join(out, "%s_h%s%s" % (model, str(h).replace("/", "_"), "_fine" if fine else ""))
    hf = float(h)
    s, rows = cupid_run(cupid, os.path.join(HERE, MODELS[model]), d,
                        ["--set", "peridynamics.spacing=%.17g" % hf,
                         "--set", "peridynamics.horizon=%.17g" % (M_RATIO * hf)] + EXTRA.get(model, []) +
                        (FINE_ZONE if fine else []), threads, reuse)
    fr = s["fracture"]
    curve = [(-float(r["load_ux"]), -float(r["reaction_0_x"])) for r in rows]
    # the first break's load: the reaction of step 1 scaled to its load factor
    r1 = rows[0]
    first = -float(r1["reaction_0_x"]) * fr["first_break_load_factor"] / float(r1["load_factor"])
    peak = fr["peak_reactions"][0]
    info = {
        "model": model, "h": str(h), "delta": M_RATIO * hf, "pd_nodes": s["counts"]["pd_nodes"],
        "peak_N": -peak["reaction"][0], "peak_step": peak["step"], "first_break_N": first,
        "broken_bonds": fr["broken_bonds"], "seconds": s["total_time_s"],
        "memory_MB": s["peak_memory_bytes"] / 2 ** 20, "g_fraction": surface_fraction(hf),
        "dir": d, "fine": fine, "pd_zone_y": "[35, 55]" if fine else "all" if model == "pd" else "[30, 60]",
    }
    return info, curve


def extrapolation(infos):
    """The corrected runs' peak at delta -> 0: the quadratic in delta through the three finest
    (Lagrange's form), and the line through the two finest; None with fewer than three runs."""
    pts = sorted((i["delta"], i["peak_N"]) for i in infos if i["model"] == "corrected")[:3]
    if len(pts) < 3:
        return None
    def quad(x):
        return sum(pj * math.prod((x - pk[0]) / (pj_d - pk[0]) for pk in pts if pk[0] != pj_d)
                   for pj_d, pj in pts)
    (d0, p0), (d1, p1) = pts[0], pts[1]
    return {"quadratic": quad, "quadratic_0": quad(0.0), "line_0": p0 - d0 * (p1 - p0) / (d1 - d0),
            "span": pts[2][0]}


def gnuplot(script):
    subprocess.run(["gnuplot"], input=script.encode(), check=True)


def side_view(info, out):
    """The front face (the layer nearest z = 0) coloured by damage, displaced 100x."""
    rows = list(csv.DictReader(open(os.path.join(info["dir"], "pd_nodes.csv"))))
    zmin = min(float(r["z"]) for r in rows)
    dat = os.path.join(out, "side_%s_h%s.dat" % (info["model"], info["h"].replace("/", "_")))
    with open(dat, "w") as f:
        for r in rows:
            if abs(float(r["z"]) - zmin) < 1e-9:
                f.write("%s %s %s\n" % (float(r["y"]) + WARP * float(r["uy"]),
                                        float(r["x"]) + WARP * float(r["ux"]), r["damage"]))
    png = os.path.join(out, "damage_%s_h%s.png" % (info["model"], info["h"].replace("/", "_")))
    ps = 0.95 * float(Fraction(info["h"]))
    beam = ""
    if info["model"] != "pd":  # the beam's outline and the overlaps, where PD is not alone
        (a0, a1), (b0, b1) = OVERLAPS[info["fine"]]
        beam = ("set object 1 rect from 0, 0 to 90, 20 fs empty border lc rgb 'gray' dt 2\n"
                "set object 2 rect from %g, 0 to %g, 20 fc rgb '#e0e0e0' fs solid noborder behind\n"
                "set object 3 rect from %g, 0 to %g, 20 fc rgb '#e0e0e0' fs solid noborder behind\n"
                "set label 1 'CUF beam' at 10, 10 tc rgb 'gray'\n"
                "set label 2 'CUF beam' at 72, 10 tc rgb 'gray'\n" % (a0, a1, b0, b1))
    gnuplot("""set terminal pngcairo size 1000,330 font ",10"
set output "%s"
set title "SENB, %s, h = %s (delta = %.3g): damage on the side face, displacements x %d"
set size ratio -1
set xlabel "y [mm]"
set ylabel "x [mm]"
set cbrange [0:0.6]
set cblabel "damage"
set palette rgbformulae 22,13,-31
set xrange [-2:92]
set yrange [-3:22]
%s
plot "%s" u 1:2:3 w p pt 5 ps %.2f lc palette notitle
""" % (png, {"pd": "peridynamics only", "coupled": "CUF beam + PD (Arlequin)",
              "fictitious": "CUF beam + PD (fictitious nodes)",
              "corrected": "CUF beam + PD (Arlequin), surface-corrected"}[info["model"]],
       info["h"], info["delta"], WARP, beam, dat, ps))
    return png


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--h", nargs="+", default=["5/3", "1.25", "1", "5/6"])
    ap.add_argument("--models", nargs="+", choices=sorted(MODELS), default=["pd", "coupled", "fictitious", "corrected"])
    ap.add_argument("--fine", nargs="*", default=[],
                    help="finer spacings for the corrected model, PD on y in [35, 55]")
    ap.add_argument("--cupid", default=os.path.join(ROOT, "build", "cupid"))
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "fracture", "study"))
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--reuse", action="store_true")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    p_stress, p_strain = e399_loads()
    infos, curves = [], {}
    todo = [(m, h, False) for m in args.models for h in args.h]
    if "corrected" in args.models:
        todo += [("corrected", h, True) for h in args.fine]
    for model, h, fine in todo:
        info, curve = run(args.cupid, model, Fraction(h), args.out, args.threads, args.reuse, fine)
        info["h"] = h
        info["error_stress_%"] = 100 * (info["peak_N"] / p_stress - 1)
        infos.append(info)
        curves[(model, h)] = curve
        print("%-8s h = %-5s delta = %.3f: peak %.2f N (E399 %.1f-%.1f N: %+.1f%%), first "
              "break %.2f N, %d bonds, %.0f s" % (model, h, info["delta"], info["peak_N"],
                                                  p_stress, p_strain, info["error_stress_%"],
                                                  info["first_break_N"], info["broken_bonds"],
                                                  info["seconds"]), flush=True)
    keys = ["model", "h", "delta", "pd_zone_y", "pd_nodes", "peak_N", "peak_step", "first_break_N",
            "error_stress_%", "g_fraction", "broken_bonds", "seconds", "memory_MB"]
    with open(os.path.join(args.out, "study.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(infos)
    with open(os.path.join(args.out, "study.md"), "w") as f:
        f.write("E399: P_c = %.2f N (plane stress) to %.2f N (plane strain)\n\n" % (p_stress, p_strain))
        f.write("| model | h | delta | PD on y | PD nodes | peak P (N) | P / P_c | G_eff / G0 | first "
                "break (N) | bonds broken | time (s) | memory (MB) |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|\n")
        for i in infos:
            f.write("| %s | %s | %.3f | %s | %d | %.2f | %.3f | %.3f | %.2f | %d | %.0f | %.0f |\n" % (
                i["model"], i["h"], i["delta"], i["pd_zone_y"], i["pd_nodes"], i["peak_N"],
                i["peak_N"] / p_stress, i["g_fraction"], i["first_break_N"], i["broken_bonds"],
                i["seconds"], i["memory_MB"]))
        ext = extrapolation(infos)
        if ext:
            f.write("\nThe corrected runs' peak at delta -> 0: %.2f N = %.3f P_c (the quadratic in delta "
                    "through the three finest), %.2f N = %.3f P_c (the line through the two finest)\n" % (
                        ext["quadratic_0"], ext["quadratic_0"] / p_stress, ext["line_0"],
                        ext["line_0"] / p_stress))
    # the curves and the peak against delta
    plots = []
    for (model, h), c in curves.items():
        dat = os.path.join(args.out, "curve_%s_h%s.dat" % (model, h.replace("/", "_")))
        with open(dat, "w") as f:
            f.write("0 0\n" + "".join("%g %g\n" % p for p in c))
        plots.append('"%s" u 1:2 w lp pt %d ps 0.5 lw 2 dt %d t "%s, h = %s"' % (
            dat, STYLE[model][0], STYLE[model][1], LABEL[model], h))
    gnuplot("""set terminal pngcairo size 900,550 font ",11"
set output "%s/load_displacement.png"
set title "SENB in three-point bending: load against load-point deflection"
set xlabel "deflection of the load point [mm]"
set ylabel "load P [N]"
set grid
set key top right
set arrow from graph 0, first %g to graph 1, first %g nohead dt 3 lc rgb "gray"
set arrow from graph 0, first %g to graph 1, first %g nohead dt 3 lc rgb "gray"
set label "E399 plane stress / strain" at graph 0.02, first %g offset 0,0.7 tc rgb "gray"
plot %s
""" % (args.out, p_stress, p_stress, p_strain, p_strain, p_strain, ", \\\n     ".join(plots)))
    pk = os.path.join(args.out, "peaks.dat")
    with open(pk, "w") as f:
        for model in args.models:
            for i in infos:
                if i["model"] == model:
                    f.write("%g %g\n" % (i["delta"], i["peak_N"]))
            f.write("\n\n")
    series = ['"%s" index %d u 1:2 w lp pt %d ps 1 lw 2 t "%s"' % (pk, k, STYLE[m][0], LABEL[m])
              for k, m in enumerate(args.models)]
    # E399 with the slab's own fracture energy and stiffness (both a fraction G_eff / G0 of the
    # bulk's near the faces): P ~ sqrt(E G) ~ P_c G_eff / G0
    est = os.path.join(args.out, "surface.dat")
    with open(est, "w") as f:
        for hh in sorted({float(Fraction(i["h"])) for i in infos}):
            f.write("%g %g\n" % (M_RATIO * hh, p_stress * surface_fraction(hh)))
    series.append('"%s" u 1:2 w l dt 3 lw 2 lc rgb "gray40" t "E399 x G_eff / G0 (plane stress)"' % est)
    if ext:
        xq = os.path.join(args.out, "extrapolation.dat")
        with open(xq, "w") as f:
            for k in range(41):
                x = ext["span"] * k / 40
                f.write("%g %g\n" % (x, ext["quadratic"](x)))
        series.append('"%s" u 1:2 w l dt 2 lw 1.5 lc rgb "black" t "quadratic through the three finest: '
                      '%.2f N (%.3f P_c) at delta = 0"' % (xq, ext["quadratic_0"], ext["quadratic_0"] / p_stress))
    gnuplot("""set terminal pngcairo size 800,500 font ",11"
set output "%s/peak_vs_horizon.png"
set title "SENB peak load against the horizon (m = 3)"
set xlabel "horizon delta [mm]"
set ylabel "peak load P [N]"
set grid
set key bottom left
set xrange [0:*]
set yrange [0:35]
set object 1 rect from graph 0, first %g to graph 1, first %g fc rgb "#dddddd" fs solid 0.5 noborder behind
set label "ASTM E399 (plane stress to plane strain)" at graph 0.4, first %g offset 0,0.8
plot %s
""" % (args.out, p_stress, p_strain, p_strain, ", ".join(series)))
    finest = {}
    for i in infos:
        if i["model"] not in finest or float(Fraction(i["h"])) < float(Fraction(finest[i["model"]]["h"])):
            finest[i["model"]] = i
    for i in finest.values():
        print("wrote", side_view(i, args.out))
    print("wrote %s/study.md, load_displacement.png, peak_vs_horizon.png" % args.out)


if __name__ == "__main__":
    sys.exit(main())
