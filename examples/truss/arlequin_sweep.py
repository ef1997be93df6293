#!/usr/bin/env python3
"""Penalty and overlap-size sweeps of the Arlequin truss (paper 004, section 4; Fig. 3).

usage: examples/truss/arlequin_sweep.py [--out out/truss/sweep]

Runs examples/truss/truss_fe.yaml (the reference) and variants of truss_arlequin.yaml through
the cupid Python package (python/cupid; each variant's model text in OUT/<name>.yaml, its
outputs in OUT/<name>), and writes OUT/sweep.md with, per period k = 1..5 of the first mode:
  amp   (max |u_tip| over period k) / (FE's) - 1, in %;
  phase the lag of the k-th downward zero crossing of u_tip behind FE's, in % of T1
        (positive: the coupled truss is late; cumulative, its growth is the drift per period);
The tip is sampled at y = 1, half a PD spacing beyond the last PD node (constant
extrapolation), hence the -0.6 / -0.75 % amplitude of period 1 for every PD and coupled run.
and the RMS of u_tip - u_tip,FE over the first period (in % of the 1e-3 amplitude).
Penalty sweep: kappa = 1e5 .. 1e13 N/m on truss_arlequin.yaml (FE 40 + PD 40 nodes, overlap
[0.4, 0.6]); beta = kappa h / (E A) is the penalty relative to one PD bond-spacing stiffness.
Overlap sweep: one spacing dx = 0.0125 m for both models, overlap [0.5 - w/2, 0.5 + w/2] with
w = 2, 4, 8, 16 dx (FE on [0, 0.5 + w/2], PD on [0.5 - w/2, 1]; 81 + w/dx nodes), kappa 1e9
and 1e11.
Penalty against k_node (the PD node stiffness that `penalty: auto` takes, read from the auto
run's summary.json): kappa = 1e-3 .. 100 k_node (and the paper's 1e9), the phase lag and tip
RMS as above and the central-difference critical step (lumped masses, one step of 1e-8 s:
the Lanczos estimate on the coupled operator) against the FE-only truss's.
"""
import argparse
import json
import math
import os
import re
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
import cupid  # noqa: E402

T1 = 4.0 / math.sqrt(1e9 / 7800.0)
HERE = os.path.dirname(os.path.abspath(__file__))


def down_crossings(h):
    out = []
    for a, b in zip(h, h[1:]):
        if a["tip_uy"] > 0 >= b["tip_uy"]:
            out.append(a["t"] + (b["t"] - a["t"]) * a["tip_uy"] / (a["tip_uy"] - b["tip_uy"]))
    return out


def metrics(h, fe):
    amp, ph = [], []
    cc, cf = down_crossings(h), down_crossings(fe)
    for k in range(5):
        a = max(abs(r["tip_uy"]) for r in h if k * T1 <= r["t"] < (k + 1) * T1)
        b = max(abs(r["tip_uy"]) for r in fe if k * T1 <= r["t"] < (k + 1) * T1)
        amp.append(100 * (a / b - 1))
        ph.append(100 * (cc[k] - cf[k]) / T1 if k < len(cc) and k < len(cf) else float("nan"))
    n = sum(1 for r in h if r["t"] <= T1)
    rms = math.sqrt(sum((a["tip_uy"] - b["tip_uy"]) ** 2 for a, b in zip(h[:n], fe[:n])) / n) / 1e-3
    return amp, ph, 100 * rms


def run(text, out, name):
    """The model text solved (written to OUT/<name>.yaml, outputs in OUT/<name>): the tip
    history as rows {"t", "tip_uy"}, the counts (p.info) and the summary's dynamic block."""
    path = os.path.join(out, name + ".yaml")
    with open(path, "w") as f:
        f.write(text)
    with cupid.Problem(path, output_dir=os.path.join(out, name)) as p:
        p.solve().write_outputs()
        h, info = p.history, p.info
        # p.info has no dynamic block (max_energy_balance_relative): read it from the
        # summary.json that write_outputs() wrote.
        with open(os.path.join(p.output_dir, "summary.json")) as f:
            dyn = json.load(f)["dynamic"]
    hist = [{"t": float(t), "tip_uy": float(u)} for t, u in zip(h["t"], h["tip"][:, 1])]
    return hist, info, dyn


def run_coupling(text, out, name):
    """The model text run through the CLI-equivalent Problem; the summary's coupling and
    dynamic blocks (empty dicts when absent)."""
    path = os.path.join(out, name + ".yaml")
    with open(path, "w") as f:
        f.write(text)
    with cupid.Problem(path, output_dir=os.path.join(out, name)) as p:
        p.solve().write_outputs()
        with open(os.path.join(p.output_dir, "summary.json")) as f:
            s = json.load(f)
    return None, s.get("dynamic", {}), s.get("coupling", {})


def central(text):
    """The model by central differences with lumped masses, one step of 1e-8 s."""
    t = text.replace("integrator: newmark", "integrator: central\n    lumped: true")
    t = re.sub(r"dt: [0-9.e-]+", "dt: 1.0e-8", t)
    return re.sub(r"duration: [0-9.e-]+", "duration: 1.0e-8", t)


def fmt(v):
    return " ".join("%+.2f" % x for x in v)


def overlap_model(base, w_dx, kappa):
    dx = 0.0125
    lo, hi = 0.5 - w_dx * dx / 2, 0.5 + w_dx * dx / 2
    t = base.replace("penalty: 1.0e9", "penalty: %g" % kappa)
    t = re.sub(r"axis: \{y: \[0, 0.6\], elements: \[39\]", "axis: {y: [0, %g], elements: [%d]" % (hi, round(hi / dx)), t)
    t = t.replace("spacing: 0.015", "spacing: %g" % dx).replace("horizon: 0.045", "horizon: %g" % (3 * dx))
    t = t.replace("{y: [0.4, 1]}", "{y: [%g, 1]}" % lo).replace("overlap: {y: [0.4, 0.6]}", "overlap: {y: [%g, %g]}" % (lo, hi))
    return t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="out/truss/sweep")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    fe, _, _ = run(open(os.path.join(HERE, "truss_fe.yaml")).read(), a.out, "fe")
    base = open(os.path.join(HERE, "truss_arlequin.yaml")).read()
    out = ["## Penalty sweep (FE 40 + PD 40 nodes, overlap [0.4, 0.6], linear weight, undamped)", "",
           "| kappa (N/m) | beta = kappa h/(EA) | tip RMS vs FE, 1st period (%) | amp err per period (%) | phase lag at crossing k (% T1, cumulative) | energy balance |",
           "|---|---|---|---|---|---|"]
    for kappa in (1e5, 1e7, 1e9, 1e10, 1e11, 1e13):
        h, _, dyn = run(base.replace("penalty: 1.0e9", "penalty: %g" % kappa), a.out, "k%g" % kappa)
        amp, ph, rms = metrics(h, fe)
        out.append("| %.0e | %.3g | %.2f | %s | %s | %.1e |" % (
            kappa, kappa * 0.015 / 1e9, rms, fmt(amp), fmt(ph), dyn["max_energy_balance_relative"]))
    out += ["", "## Overlap-size sweep (dx = 0.0125 for both, overlap centred at y = 0.5, linear weight)", "",
            "| overlap width | nodes | kappa (N/m) | tip RMS vs FE, 1st period (%) | amp err per period (%) | phase lag at crossing k (% T1, cumulative) |",
            "|---|---|---|---|---|---|"]
    for kappa in (1e9, 1e11):
        for w in (2, 4, 8, 16):
            h, info, _ = run(overlap_model(base, w, kappa), a.out, "w%d_k%g" % (w, kappa))
            amp, ph, rms = metrics(h, fe)
            out.append("| %d dx = %g m | %d | %.0e | %.2f | %s | %s |" % (
                w, w * 0.0125, info["pd_nodes"] + info["fe_nodes"], kappa, rms, fmt(amp), fmt(ph)))
    # penalty relative to the PD node stiffness (`penalty: auto` is CUPID_ARLEQUIN_AUTO_PENALTY
    # k_node): Newmark accuracy and the central-difference critical step (lumped masses; one
    # step at dt = 1e-8 reads dt_critical from the Lanczos estimate on the coupled operator)
    _, _, kn = run_coupling(base.replace("penalty: 1.0e9", "penalty: auto"), a.out, "auto")
    k_node = kn["pd_node_stiffness"]
    crit = lambda text, name: run_coupling(central(text), a.out, name)[1]["dt_critical"]
    dt_fe = crit(open(os.path.join(HERE, "truss_fe.yaml")).read(), "fe_central")
    dt_pd = crit(open(os.path.join(HERE, "truss_pd.yaml")).read(), "pd_central")
    out += ["", "## Penalty against the PD node stiffness k_node = %.4g N/m (`penalty: auto` = %g k_node)"
            % (k_node, kn["penalty_over_node_stiffness"]), "",
            "Critical step of central differences (lumped): FE-only truss %.3e s, PD-only truss %.3e s." % (dt_fe, dt_pd), "",
            "| kappa / k_node | kappa (N/m) | tip RMS vs FE, 1st period (%) | phase lag at crossing k (% T1, cumulative) | dt_critical (s) | dt_critical / FE-only's |",
            "|---|---|---|---|---|---|"]
    for c in (1e-3, 1e9 / k_node, 0.1, 0.3, 1, 3, 10, 100):
        text = base.replace("penalty: 1.0e9", "penalty: %.6g" % (c * k_node))
        h, _, _ = run(text, a.out, "c%.3g" % c)
        amp, ph, rms = metrics(h, fe)
        dt = crit(text, "c%.3g_central" % c)
        out.append("| %.3g | %.3g | %.2f | %s | %.3e | %.2f |" % (c, c * k_node, rms, fmt(ph), dt, dt / dt_fe))
    # PD-only for reference
    h, _, _ = run(open(os.path.join(HERE, "truss_pd.yaml")).read(), a.out, "pd")
    amp, ph, rms = metrics(h, fe)
    out += ["", "PD-only truss (80 nodes) against FE: tip RMS %.2f %%, amp %s %%, phase %s %% T1" % (rms, fmt(amp), fmt(ph))]
    with open(os.path.join(a.out, "sweep.md"), "w") as f:
        f.write("\n".join(out) + "\n")
    print("\n".join(out))


if __name__ == "__main__":
    main()
