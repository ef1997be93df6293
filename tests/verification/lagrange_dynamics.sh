#!/usr/bin/env bash
# The Lagrange-multiplier coupling in dynamics (issue 5: "all three coupling methods in
# dynamics") and a PD load on a tied node (issue 4), with `cupid run` on a coarse 3D bar:
# y in [0, 1] m, section 0.1 x 0.1 m (L4), E = 1e9 Pa, nu = 0, rho = 7800 kg/m^3, clamped at
# y = 0; FE on [0, 0.4] and [0.6, 1] (B2, 16 + 16 elements), 3D LPS peridynamics on
# [0.4, 0.6] (h = 0.025: 4 x 8 x 4 nodes, delta = 3 h, Gaussian influence) tied to the beam by
# Lagrange multipliers (eliminated; the tied layers' mass carried by the beam through the tie).
# Released from the uniform stretch u_y = 1e-3 y (nu = 0: the 3D bar is a rod; the exact tip
# history is a triangle wave of period T1 = 4 L / sqrt(E / rho) = 11.17 ms, amplitude 1e-3).
# The reference is the FE-only model (the same beam without the PD region).
#
# Checks (python3, standard library):
#  - Newmark average acceleration, undamped: the energy balance holds to 1e-9 relative (the
#    trapezoidal rule conserves the discrete energy of any symmetric K, M; measured 3e-12);
#  - tip history against the FE-only model over the first period: RMS <= 10% and max <= 20%
#    of the amplitude (measured 6.9% and 15.6%). The deviation is the Lagrange coupling's
#    stiffness error, not the integration: the static tip displacement under an end traction
#    is 5.7% short of the FE one in the same model (printed; checked within 3..9%: the tied
#    layers sit h/2 inside the region but take the interface field, so the 0.2 m PD part acts
#    as 0.175 m of lattice (12.5% stiffer), plus the LPS surface effect of a 4-node section),
#    which shortens the period by ~3% and shifts the triangle wave by up to 4 x 3% = 12% of its
#    amplitude within one period; halving h (8 x 8 sections, 44 s, not run here) brings the
#    RMS to 2.9% and the max to 6.7%;
#  - central differences (lumped mass: HRZ of the beam and of the tied nodes) on the same
#    model agree with Newmark: RMS <= 2%, max <= 6% (measured 0.9%, 3.9%: the lumped mass and
#    Newmark's period elongation differ at O(dt^2) and in dispersion); bounded energy error
#    (<= 1e-4, measured 9e-6);
#  - Rayleigh damping (a = 20 1/s, b = 1e-6 s): the balance with the dissipated energy holds
#    (1e-9), the dissipated energy is positive and the final total below the initial;
#  - static, a point load on a tied PD node (the layer nearest y = 0.4): it reaches the beam
#    through the tie (T^T f): the tip moves by P 0.4 / (E A) to 1e-9 relative (the load acts at
#    the interface point y = 0.4), where a dropped load would leave the bar at rest;
#  - the fictitious-node method is still refused in dynamics, with the reason;
#  - the 1D truss of paper 004 (examples/truss/truss_lagrange.yaml: TE0 rod on [0, 0.4], 1D
#    bond PD on [0.4, 1]), first period, against truss_fe.yaml: tip RMS <= 5% and no worse
#    than the PD-only truss (truss_pd.yaml) over the same period (measured 2.4% against 3.0%:
#    60% of the bar is PD, whose free-end surface layer lowers its frequency, the tie adds the
#    h/2 offset); energy balance 1e-9.
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, finish

# model NAME PD(0/1) ANALYSIS-BLOCK [METHOD]
model() {
  local name=$1 pd=$2 analysis=$3 method=${4:-lagrange}
  {
    cat <<EOF
title: 3D bar $name
materials:
  steel: {E: 1.0e9, nu: 0.0, density: 7800}
beam:
  material: steel
  axis: {y: [0, 0.4, 0.6, 1], elements: [16, 8, 16], type: B2}
  section:
    expansion: LE
    element: L4
    components:
      - {x: [0, 0.1], z: [0, 0.1]}
EOF
    if [ "$pd" = 1 ]; then
      cat <<EOF
peridynamics:
  spacing: 0.025
  horizon: 0.075
  model: lps
  influence: gaussian
  partial_volume: pdlammps
  material: steel
  regions:
    - {x: [0, 0.1], y: [0.4, 0.6], z: [0, 0.1]}
coupling: {method: $method}
EOF
    fi
    cat <<EOF
constraints:
  - clamp: {y: 0}
$analysis
output:
  directory: out
  vtu: false
  plots: false
  points:
    - {name: tip, at: [0.05, 1, 0.05]}
EOF
  } > "$name.yaml"
}

dyn() { # integrator dt every extra-lines
  cat <<EOF
analysis:
  type: dynamic
  dynamic:
    integrator: $1
    dt: $2
    duration: 0.01117
    every: $3
$4
    initial: {displacement: ["0", "1e-3*y", "0"], velocity: ["0", "0", "0"]}
EOF
}
static_load() { # load line
  cat <<EOF
loads:
  - $1
analysis:
  type: static
  solver: direct
EOF
}

model fe 0 "$(dyn newmark 1.0e-5 10 '')"
model lag 1 "$(dyn newmark 1.0e-5 10 '')"
model lagc 1 "$(dyn central 2.0e-6 50 '    lumped: true')"
model lagd 1 "$(dyn newmark 1.0e-5 10 '    rayleigh: {mass: 20, stiffness: 1.0e-6}')"
model st_fe 0 "$(static_load 'traction: {y: 1, value: [0, 1.0e6, 0]}')"
model st_lag 1 "$(static_load 'traction: {y: 1, value: [0, 1.0e6, 0]}')"
model pt_lag 1 "$(static_load 'point: {at: [0.0375, 0.4125, 0.0375], value: [0, 1.0e4, 0]}')"
model fict 1 "$(dyn newmark 1.0e-5 10 '')" fictitious

for m in fe lag lagc lagd st_fe st_lag pt_lag; do
  if "$CUPID" run "$m.yaml" -o "$m" --quiet >"$m.log" 2>&1; then ok; else bad "$m failed"; head -5 "$m.log"; fi
done
for m in fe pd lagrange; do # the trusses, first period only
  sed 's/duration: .*/duration: 0.01117/' "$SRC/examples/truss/truss_$m.yaml" > "truss_$m.yaml"
  if "$CUPID" run "truss_$m.yaml" -o "truss_$m" --quiet >"truss_$m.log" 2>&1; then ok; else bad "truss_$m failed"; head -5 "truss_$m.log"; fi
done
out=$("$CUPID" run fict.yaml -o fict --quiet 2>&1); rc=$?
if [ "$rc" -ne 0 ] && grep -q "fictitious" <<<"$out"; then ok; else bad "fictitious dynamic not refused: $rc $out"; fi

python3 - "$work" <<'PY' && ok || bad "history/energy/load checks"
import bisect, csv, json, math, sys
w = sys.argv[1]
def summ(m): return json.load(open("%s/%s/summary.json" % (w, m)))
def hist(m):
    r = list(csv.DictReader(open("%s/%s/history.csv" % (w, m))))
    return [float(x["t"]) for x in r], [float(x["tip_uy"]) for x in r]
def at(t, ts, us):
    i = min(max(bisect.bisect_left(ts, t), 1), len(ts) - 1)
    s = (t - ts[i - 1]) / (ts[i] - ts[i - 1])
    return us[i - 1] * (1 - s) + us[i] * s
T = 4 / math.sqrt(1e9 / 7800)
def compare(a, b):
    ta, ua = hist(a); tb, ub = hist(b)
    d = [ua[i] - at(ta[i], tb, ub) for i in range(len(ta)) if ta[i] <= T + 1e-12]
    return max(map(abs, d)) / 1e-3, math.sqrt(sum(x * x for x in d) / len(d)) / 1e-3
okay = True
def check(cond, what):
    global okay
    print(("ok   " if cond else "FAIL ") + what)
    okay &= bool(cond)
lag = summ("lag")["dynamic"]
check(lag["max_energy_balance_relative"] < 1e-9,
      "Newmark energy balance %.2e (<= 1e-9)" % lag["max_energy_balance_relative"])
mx, rms = compare("fe", "lag")
check(rms <= 0.10 and mx <= 0.20, "Lagrange vs FE tip, first period: RMS %.4f (<= 0.10), max %.4f (<= 0.20)" % (rms, mx))
us_fe = summ("st_fe")["points"][0]["uy"]; us_lag = summ("st_lag")["points"][0]["uy"]
es = us_lag / us_fe - 1
check(-0.09 <= es <= -0.03, "static tip error of the Lagrange model %+.4f (stiffer: -0.09..-0.03)" % es)
mx, rms = compare("lag", "lagc")
c = summ("lagc")["dynamic"]
check(rms <= 0.02 and mx <= 0.06, "central (lumped) vs Newmark, Lagrange: RMS %.4f (<= 0.02), max %.4f (<= 0.06)" % (rms, mx))
check(c["max_energy_balance_relative"] < 1e-4, "central energy error %.2e (<= 1e-4)" % c["max_energy_balance_relative"])
d = summ("lagd")["dynamic"]; e = d["final_energy"]
e0 = [float(r["kinetic"]) + float(r["strain"]) for r in csv.DictReader(open(w + "/lagd/energies.csv"))][0]
check(d["max_energy_balance_relative"] < 1e-9 and e["damping_dissipated"] > 0 and
      e["kinetic"] + e["strain"] < e0,
      "damped: balance %.2e, dissipated %.4g J, final %.4g J < initial %.4g J" %
      (d["max_energy_balance_relative"], e["damping_dissipated"], e["kinetic"] + e["strain"], e0))
u = summ("pt_lag")["points"][0]["uy"]; exact = 1.0e4 * 0.4 / (1e9 * 0.01)
check(abs(u - exact) <= 1e-9 * exact, "point load on a tied PD node: tip u_y %.10g vs P 0.4 / (E A) = %.10g" % (u, exact))
tl = summ("truss_lagrange")["dynamic"]["max_energy_balance_relative"]
_, rms_l = compare("truss_fe", "truss_lagrange"); _, rms_p = compare("truss_fe", "truss_pd")
check(rms_l <= 0.05 and rms_l <= rms_p and tl < 1e-9,
      "truss, Lagrange vs FE tip RMS %.4f (<= 0.05 and <= PD-only %.4f), energy balance %.2e" %
      (rms_l, rms_p, tl))
sys.exit(0 if okay else 1)
PY

finish lagrange_dynamics
