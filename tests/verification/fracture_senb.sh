#!/usr/bin/env bash
# The single-edge-notched beam in three-point bending (examples/fracture; issue 17): quasi-static
# crack growth against LEFM, and the coupled model against the PD-only one.
#  1. LEFM: the PD-only beam's peak load (the sawtooth envelope's, summary.json) at three
#     horizons, delta = 5.03, 3.77, 3.02 (h = 5/3, 1.25, 1 at m = 3), against ASTM E399's
#     P_c = 31.5 N (plane stress, fracture.md). The error must fall as delta shrinks, and each
#     peak must lie between 0.5 and 1 of P_c: the thickness B = 5 is within a horizon or two of
#     both faces, whose truncated families hold a fraction of G0 and of the stiffness (the
#     discrete fraction of G0 is 0.63, 0.72, 0.78 at these horizons: examples/fracture/README.md),
#     so a peak at or above P_c, or below half of it (a wrong s0 of G0, say), is a fault.
#  2. Coupled (CUF beam + PD around the notch, Arlequin; Lagrange multipliers, within 3%;
#     fictitious nodes with the default balance, within 1% of the all-PD beam on pins, see 2b)
#     against PD-only at h = 1.25 and 1: the
#     peak loads within the PD-only model's own discretisation change between its two finest
#     horizons (|P(1) - P(1.25)| / P(1)); the crack path the same: the highest damaged node
#     above the notch and the widest damaged node off the notch plane within one spacing.
#  3. The envelope: every step's next-break load factor is at or above its own load factor
#     (a settled step has no bond over its limit), and the peak is at or above every step's
#     reaction.
#  4. A crack that reaches an Arlequin overlap stops the run: exit status 2, the message names
#     the overlap with its line and the step, the steps before it are written, summary.json
#     says where it stopped.
#  5. The surface correction (issue 38): the coupled peak raised by about 1 / g (g the faces'
#     share of G0), between 0.8 and 1 of P_c, its error falling with delta.
# About 4.5 minutes on 2 cores.
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, finish
PY=${CUPID_SYSTEM_PYTHON:-/usr/bin/python3}
EX=$SRC/examples/fracture
short=(--set analysis.steps=20 --set "constraints[0].displacement.value=[-0.03, null, null]")

# A sanitizer build (CUPID_TEST_SANITIZED=1, the CI's ASan stage) runs every model kind once, at
# h = 1.25, and leaves the numbers to the plain build: the finer horizons take the same code paths
# (12 minutes of the ASan stage's 20 otherwise).
sanitized=${CUPID_TEST_SANITIZED:-0}
horizons="5/3 1.25 1"
[ "$sanitized" = 1 ] && horizons=1.25
for h in $horizons; do
  hv=$("$PY" -c "from fractions import Fraction as F; print(repr(float(F('$h'))))")
  dv=$("$PY" -c "print(repr(3.015 * $hv))")
  tag=${h//\//_}
  "$CUPID" run "$EX/senb_pd.yaml" -o "pd_$tag" --quiet "${short[@]}" \
    --set peridynamics.spacing="$hv" --set peridynamics.horizon="$dv" && ok || bad "PD-only run, h = $h"
  if [ "$h" != 5/3 ]; then
    "$CUPID" run "$EX/senb_coupled.yaml" -o "cp_$tag" --quiet "${short[@]}" \
      --set peridynamics.spacing="$hv" --set peridynamics.horizon="$dv" && ok || bad "coupled run, h = $h"
    "$CUPID" run "$EX/senb_coupled.yaml" -o "lg_$tag" --quiet "${short[@]}" --set 'coupling={method: lagrange}' \
      --set peridynamics.spacing="$hv" --set peridynamics.horizon="$dv" && ok || bad "Lagrange run, h = $h"
    "$CUPID" run "$EX/senb_coupled.yaml" -o "fi_$tag" --quiet "${short[@]}" --set 'coupling={method: fictitious}' \
      --set peridynamics.spacing="$hv" --set peridynamics.horizon="$dv" && ok || bad "fictitious run, h = $h"
    "$CUPID" run "$EX/senb_coupled.yaml" -o "sc_$tag" --quiet "${short[@]}" --set peridynamics.surface_correction=energy \
      --set peridynamics.spacing="$hv" --set peridynamics.horizon="$dv" && ok || bad "surface-corrected run, h = $h"
    # the all-PD beam on pins: one node column at each support (x held on one column cannot
    # resist a rotation, as the beam's line supports; the example's two columns can)
    "$CUPID" run "$EX/senb_pd.yaml" -o "pin_$tag" --quiet "${short[@]}" \
      --set peridynamics.spacing="$hv" --set peridynamics.horizon="$dv" \
      --set 'constraints[1]={fix: {box: {x: [0, 0.9], y: [4, 5]}, components: [x, y, z]}}' \
      --set 'constraints[2]={fix: {box: {x: [0, 0.9], y: [85, 86]}, components: [x]}}' && ok || bad "pinned PD-only run, h = $h"
  fi
done
# paper 000's operator as printed, h = 1.25: the cause the default balance removes
"$CUPID" run "$EX/senb_coupled.yaml" -o fn_1.25 --quiet "${short[@]}" --set 'coupling={method: fictitious, balance: none}' \
  --set peridynamics.spacing=1.25 --set peridynamics.horizon=3.76875 && ok || bad "fictitious run, balance: none"

if [ "$sanitized" = 1 ]; then
  echo "sanitizer build: the peaks, paths and envelopes are checked in the plain build"
else
"$PY" - <<'PY' && ok || bad "SENB: LEFM trend, coupled against PD-only, the envelope"
import csv, json, math

W, S, B, A, E, G0 = 20.0, 80.0, 5.0, 10.0, 22350.0, 0.01006
a = A / W
f = 3 * math.sqrt(a) * (1.99 - a * (1 - a) * (2.15 - 3.93 * a + 2.7 * a * a)) / (2 * (1 + 2 * a) * (1 - a) ** 1.5)
Pc = math.sqrt(E * G0) * B * W ** 1.5 / (S * f)
assert abs(Pc - 31.5) < 0.05, Pc  # fracture.md's figure

def load(d):
    s = json.load(open(d + "/summary.json"))["fracture"]
    rows = list(csv.DictReader(open(d + "/damage.csv")))
    nodes = list(csv.DictReader(open(d + "/pd_nodes.csv")))
    return s, rows, nodes

def peak(s):
    return -s["peak_reactions"][0]["reaction"][0]

def path(nodes, h):
    """the highest damaged node above the notch, the widest off the plane y = 45"""
    hit = [(float(n["x"]), abs(float(n["y"]) - 45)) for n in nodes
           if float(n["damage"]) > 0.3 and float(n["x"]) > 10]
    return max(x for x, _ in hit), max(dy for _, dy in hit)

runs = {}
for tag, h in (("5_3", 5 / 3), ("1.25", 1.25), ("1", 1.0)):
    runs["pd", tag] = load("pd_" + tag) + (h,)
    if tag != "5_3":
        for key in ("cp", "lg", "fi", "pin", "sc"):
            runs[key, tag] = load(key + "_" + tag) + (h,)

# 3. the envelope
for key, (s, rows, nodes, h) in runs.items():
    for r in rows:
        lf, nb = float(r["load_factor"]), float(r["next_break_load_factor"])
        assert nb >= lf * (1 - 1e-12), (key, r["step"], lf, nb)
    top = max(-float(r["reaction_0_x"]) for r in rows)
    assert peak(s) >= top * (1 - 1e-12), (key, peak(s), top)

# 1. LEFM: the error falls with delta
errs = []
for tag in ("5_3", "1.25", "1"):
    s, rows, nodes, h = runs["pd", tag]
    P = peak(s)
    errs.append(P / Pc - 1)
    print("PD only, h = %-5s delta = %.3f: peak %.2f N, E399 %.2f N: %+.1f%%" % (tag, 3.015 * h, P, Pc, 100 * errs[-1]))
    assert 0.5 * Pc < P < Pc, (tag, P)
assert errs[0] < errs[1] < errs[2], errs

# 2. coupled against PD-only
tol = abs(peak(runs["pd", "1"][0]) - peak(runs["pd", "1.25"][0])) / peak(runs["pd", "1"][0])
print("tolerance from the PD-only horizon study: %.1f%%" % (100 * tol))
def against_pd(key, name, bound):
    """the coupled model's peak within bound of the PD-only one, the same crack to a spacing"""
    for tag in ("1.25", "1"):
        sp, _, np_, h = runs["pd", tag]
        sc, _, nc, _ = runs[key, tag]
        d = peak(sc) / peak(sp) - 1
        xp, yp = path(np_, h)
        xc, yc = path(nc, h)
        print("h = %s: %s peak %.2f N against PD-only %.2f N (%+.2f%%); crack top %.2f / %.2f, "
              "width %.2f / %.2f" % (tag, name, peak(sc), peak(sp), 100 * d, xc, xp, yc, yp))
        assert abs(d) <= bound, (tag, d, bound)
        assert abs(xc - xp) <= h + 1e-9 and abs(yc - yp) <= h + 1e-9, (tag, xc, xp, yc, yp)

against_pd("cp", "coupled", tol)
# 2a. Lagrange multipliers (issue 34: the method refused cracks) against PD-only: within 3%
# (the issue's bound: the tie's truncated families and the h/2 offset of the tied layer, paper
# 000 section 5.1), the same crack
against_pd("lg", "Lagrange", 0.03)
# 2b. fictitious nodes (issue 34, the default balance: each interface balanced), the same crack
# as PD-only, and the peak within 1% of the all-PD beam on pins (the issue's bound; measured
# +0.09% and +0.07%), with the span the statics read: M = P S / 4 at the notch, S = 80 for the
# beam's line supports, from pin to pin for the PD one (its node columns at h/2 off y = 5 and
# 85). Against the example's PD-only beam the coupled models are 4.0% and 2.35% low: its two
# node columns at each support hold a moment, which raises its peak. Fictitious nodes and
# Arlequin, both conserving momentum, within 0.1% of each other (measured 0.005%).
against_pd("fi", "fictitious", tol)
for tag, h in (("1.25", 1.25), ("1", 1.0)):
    span = 80 + h  # the columns at y = 5 - h/2 and 85 + h/2 (5 and 85 are lattice planes)
    pin = peak(runs["pin", tag][0]) * span / 80
    fi, cp = peak(runs["fi", tag][0]), peak(runs["cp", tag][0])
    print("h = %s: fictitious %.3f N, Arlequin %.3f N, all-PD on pins %.3f N (span %.2f, as at 80: "
          "%.3f N): %+.2f%%, Arlequin %+.3f%%" % (tag, fi, cp, peak(runs["pin", tag][0]), span, pin,
                                              100 * (fi / pin - 1), 100 * (fi / cp - 1)))
    assert abs(fi / pin - 1) <= 0.01 and abs(fi / cp - 1) <= 0.001, (tag, fi, pin, cp)
    # the re-solves: the block factor (CHOLMOD of the PD block, growth_block.c) downdated by
    # the broken bonds, one step each; a factorisation per round of breaks or per load step
    # (GMRES on the last LU made 30-40 here) would mean the downdates were lost
    sv = runs["fi", tag][0]["solves"]
    print("  %d solves, %d factorisations, %d downdate columns, %d steps" %
          (sv["solves"], sv["factorisations"], sv["downdate_columns"], sv["cg_iterations"]))
    assert sv["resolve"] == "block downdate" and sv["factorisations"] <= 5, sv
    assert sv["cg_iterations"] == sv["cg_solves"], sv  # one step per re-solve
    # ... and its memory, Arlequin's within 1.5x (issue 34; measured 1.15x at h = 1: the
    # Cholesky factor of the PD block is Arlequin's, the whole K's LU was 1.9x)
    mem = [json.load(open(k + "_" + tag + "/summary.json"))["peak_memory_bytes"] for k in ("fi", "cp")]
    print("  peak memory: fictitious %.0f MB, Arlequin %.0f MB (%.2fx)" %
          (mem[0] / 2**20, mem[1] / 2**20, mem[0] / mem[1]))
    assert mem[0] <= 1.5 * mem[1], mem
# ... and the cause the balance removes: paper 000's operator as printed over 5% above (11%)
fn = peak(json.load(open("fn_1.25/summary.json"))["fracture"])
print("h = 1.25: paper 000's operator as printed %.3f N (%+.1f%% against Arlequin)" %
      (fn, 100 * (fn / peak(runs["cp", "1.25"][0]) - 1)))
assert fn > 1.05 * peak(runs["cp", "1.25"][0]), fn

# 5. the surface correction (issue 38): the faces z = 0 and 5 truncate the families, which hold
# the fraction g of G0 across the crack plane (g = 0.721, 0.777 at h = 1.25, 1: surface_fraction
# below, as examples/fracture/senb_study.py) and of the stiffness about as much; P_c goes with
# sqrt(E G). The energy method restores both near the faces, each bond's energy at its limit
# scaled by its factor, so it raises the coupled peak by about 1 / g: within 10% of it (measured
# -5% and -2%; a correction of the stiffness alone would raise it by about 1 / sqrt(g), 20%
# short, and one lost on the bonds as they break, by less). The corrected peaks lie between 0.8
# and 1 of P_c and their error falls with delta.
def surface_fraction(h, B=5.0, m=3.015):
    d, r = m * h, int(math.ceil(m)) + 1
    offs = [(a, b, c) for a in range(-r, r + 1) for b in range(1, r + 1) for c in range(-r, r + 1)
            if math.sqrt(a * a + b * b + c * c) * h <= d]
    nz = int(round(B / h))
    w = lambda a, b, c: b * math.sqrt(a * a + b * b + c * c)
    return sum(w(a, b, c) for k in range(nz) for a, b, c in offs if 0 <= k + c < nz) / (nz * sum(w(*o) for o in offs))

errs = []
for tag, h in (("1.25", 1.25), ("1", 1.0)):
    g = surface_fraction(h)
    sc, cp = peak(runs["sc", tag][0]), peak(runs["cp", tag][0])
    errs.append(sc / Pc - 1)
    print("h = %s: surface-corrected %.2f N (%.3f P_c) against %.2f N: x %.3f, 1 / g = %.3f (g = %.3f)"
          % (tag, sc, sc / Pc, cp, sc / cp, 1 / g, g))
    assert 0.8 * Pc < sc <= Pc, (tag, sc)
    assert abs(sc / cp * g - 1) <= 0.10, (tag, sc / cp, 1 / g)
assert abs(errs[1]) < abs(errs[0]), errs
PY
fi

# 4. a crack into an Arlequin overlap
out=$("$CUPID" run "$SRC/tests/models/growth/senb_interface.yaml" -o stop --quiet 2>&1); rc=$?
[ $rc -eq 2 ] && ok || bad "a crack into the overlap: exit $rc (want 2)"
grep -q "crack growth stopped at load step [0-9]* (load factor [0-9.e-]*): [0-9]* bonds\? of the Arlequin overlap {x: \[8, 12\]} (coupling.arlequin.overlap\[2\], line 35) reached the breaking limit" <<<"$out" \
  && ok || bad "the stop message: $out"
"$PY" - stop <<'PY' && ok || bad "the stopped run's files"
import csv, json, sys
s = json.load(open(sys.argv[1] + "/summary.json"))["fracture"]
rows = list(csv.DictReader(open(sys.argv[1] + "/damage.csv")))
k = s["stopped_step"]
assert k > 1 and "Arlequin overlap" in s["stopped"], s
assert [int(r["step"]) for r in rows] == list(range(1, k)), (k, len(rows))
assert int(rows[-1]["broken_bonds"]) > 0  # the crack grew before it got there
PY

finish fracture_senb
