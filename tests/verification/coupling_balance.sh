#!/usr/bin/env bash
# The balanced fictitious-node coupling, `coupling.balance: momentum` (issue 18 item 3;
# docs/coupling.md, "The balanced fictitious-node coupling"; the algebra in
# unit.coupling_balance):
#  1. The small bar tests/models/coupling/quality_bar.yaml in the form before issue 18 (h/2
#     fictitious element, one B2 per span, delta = 3): 32% imbalance with paper 000's operator;
#     balanced, the reactions equal the load to the solve's tolerance (direct: 1e-10; Krylov,
#     GMRES to 1e-10 relative: 1e-8), and the direct and the matrix-free paths give the same tip
#     displacement (1e-7 relative: two solves to 1e-10 on a system of condition ~1e3).
#  2. The C-beam of paper 000 (section 5.2) with PD around the web-flange corner
#     (examples/cbeam/cbeam_corner.yaml), over the web (cbeam_pd_l9.yaml) and over the web's
#     whole height with both corners (tests/models/coupling/cbeam_web_height.yaml), matrix-free,
#     against full L9 (cbeam_fe_l9.yaml) at A and B: balanced within 0.5% (measured 0.01%) with
#     an imbalance <= 1e-6 of the load; paper 000's operator misses the corner by > 2% with a
#     > 10% imbalance (the cause the balance removes). 0.5% is a quarter of the issue's 2%: room
#     for the solver's tolerance, and still far below the unbalanced 2.6%.
#  3. Load steps (one balanced solve scaled) and type evaluate (the internal forces of the
#     balanced operator sum to zero) balance too; type dynamic and an iterative engine's
#     assembled path are refused with a clear message.
#  4. Paper 000's operator on the small bar at fixed m = 1.5: the imbalance falls as h falls
#     (h = 1: 2.5e-3, h = 0.5: 5.2e-4, h = 0.25: 2.7e-4 measured; checked: at least halved from
#     h = 1 to 0.5), and the balanced operator keeps the patch test on that bar (ghost force
#     <= 1e-10 of the nodal force scale; measured 5e-14).
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, finish
Q="$SRC/tests/models/coupling/quality_bar.yaml"
OLD=(--set peridynamics.horizon=3 --set coupling.fictitious_fe=plane --set beam.axis.type=B2 --set 'beam.axis.elements=[1,1,1]')
check() { if "$@"; then ok; else bad "$*"; fi; }
run() { "$CUPID" run "$@" --quiet || bad "cupid run $*"; }

# 1. the small bar
run "$Q" -o "$work/none" "${OLD[@]}" --solver direct --set coupling.balance=none
run "$Q" -o "$work/direct" "${OLD[@]}" --solver direct --set coupling.balance=momentum
run "$Q" -o "$work/krylov" "${OLD[@]}" --solver krylov --set coupling.balance=momentum
check python3 - "$work" <<'PY'
import json, sys
w = sys.argv[1]
s = {k: json.load(open(f"{w}/{k}/summary.json")) for k in ("none", "direct", "krylov")}
imb = {k: s[k]["coupling_quality"]["imbalance"] for k in s}
tip = {k: [s[k]["points"][0][c] for c in ("ux", "uy", "uz")] for k in s}
scale = max(abs(v) for v in tip["direct"])
diff = max(abs(a - b) for a, b in zip(tip["direct"], tip["krylov"])) / scale
print(f"small bar: imbalance none {imb['none']:.3e}, direct {imb['direct']:.3e}, krylov {imb['krylov']:.3e}; "
      f"tip direct vs krylov {diff:.2e}")
ghost = max(s[k]["coupling_quality"]["patch_test"]["ghost_force"] for k in ("direct", "krylov"))
print(f"balanced patch test: ghost force {ghost:.2e}")
sys.exit(0 if imb["none"] > 0.1 and imb["direct"] <= 1e-10 and imb["krylov"] <= 1e-8 and diff <= 1e-7
         and ghost <= 1e-10 else 1)
PY

# 2. the C-beam against full L9
E="$SRC/examples/cbeam"
run "$E/cbeam_fe_l9.yaml" -o "$work/fe"
run "$E/cbeam_corner.yaml" -o "$work/corner" --solver krylov
run "$E/cbeam_corner.yaml" -o "$work/corner_none" --solver krylov --set coupling.balance=none
run "$E/cbeam_pd_l9.yaml" -o "$work/web" --solver krylov --set coupling.balance=momentum
run "$SRC/tests/models/coupling/cbeam_web_height.yaml" -o "$work/height" --solver krylov
check python3 - "$work" <<'PY'
import json, sys
w = sys.argv[1]
def pts(k):
    s = json.load(open(f"{w}/{k}/summary.json"))
    return {p["name"]: p["uz"] for p in s["points"]}, s.get("coupling_quality", {}).get("imbalance", 0.0)
fe, _ = pts("fe")
good = True
for k, tol, want_small in (("corner", 0.005, True), ("web", 0.005, True), ("height", 0.005, True),
                           ("corner_none", 0.02, False)):
    p, imb = pts(k)
    err = max(abs(p[n] / fe[n] - 1) for n in ("A", "B"))
    print(f"{k}: A {p['A']:.5f} ({(p['A'] / fe['A'] - 1) * 100:+.3f}%), B {p['B']:.5f} "
          f"({(p['B'] / fe['B'] - 1) * 100:+.3f}%), imbalance {imb:.2e}")
    if want_small:
        good &= err <= tol and imb <= 1e-6
    else:
        good &= err > tol and imb > 0.1
sys.exit(0 if good else 1)
PY

# 3. load steps and type evaluate balance too (issue 34: both were refused); an iterative
# engine's assembled path is still refused. Load steps without fracture are one balanced solve
# scaled: the tip as the one static solve's to 1e-11 (two factorisations' round-off), the
# reactions equal to the load. The balanced operator conserves momentum: an evaluation's
# internal forces sum to 0 (1e-10 of their magnitudes) where paper 000's operator leaves its
# imbalance.
run "$Q" -o "$work/steps" "${OLD[@]}" --solver direct --set coupling.balance=momentum --set analysis.steps=3
field=(--set analysis.type=evaluate --set 'analysis.field=["1e-3*x", "1e-3*y*y", "1e-4*z"]')
run "$Q" -o "$work/ev_none" "${OLD[@]}" "${field[@]}" --set coupling.balance=none
run "$Q" -o "$work/ev_bal" "${OLD[@]}" "${field[@]}" --set coupling.balance=momentum
check python3 - "$work" <<'PY'
import csv, json, sys
w = sys.argv[1]
d, st = (json.load(open(f"{w}/{k}/summary.json")) for k in ("direct", "steps"))
a = [d["points"][0][c] for c in ("ux", "uy", "uz")]
b = [st["points"][0][c] for c in ("ux", "uy", "uz")]
scale = max(abs(v) for v in a)
diff = max(abs(x - y) for x, y in zip(a, b)) / scale
rows = list(csv.DictReader(open(f"{w}/steps/load_steps.csv")))
imb = st["coupling_quality"]["imbalance"]
print(f"load steps, balanced: 3 rows, tip against the one solve {diff:.1e}, imbalance {imb:.1e}")
ev = {k: json.load(open(f"{w}/{k}/summary.json")) for k in ("ev_none", "ev_bal")}
rel = {k: max(abs(v) for v in s["internal_force_sum"]) / s["internal_force_magnitude"] for k, s in ev.items()}
print(f"evaluate: internal forces' resultant {rel['ev_none']:.2e} (paper 000's operator), "
      f"{rel['ev_bal']:.2e} (balanced) of their magnitudes")
# diff: the steps' one solve (CHOLMOD + the Schur block, growth_block.c) against the static one
# (UMFPACK's LU) of the same K: two factorisations, whose solutions differ by the system's
# round-off (the residuals are 1e-13): 1.2e-12 measured on an AMD EPYC with AVX-512, under
# 1e-12 elsewhere; 1e-11 is round-off still, and any real difference is far above it
sys.exit(0 if len(rows) == 3 and diff <= 1e-11 and imb <= 1e-10 and rel["ev_bal"] <= 1e-10
         and rel["ev_none"] > 1e-4 else 1)
PY
out=$("$CUPID" run "$Q" -o "$work/refused" --set coupling.balance=momentum --set analysis.type=dynamic --set materials.steel.density=7.8e-9 \
      --set 'analysis.dynamic={dt: 1e-7, duration: 1e-6}' 2>&1)
rc=$?
if [ "$rc" -eq 1 ] && grep -q "type dynamic is not supported with coupling method fictitious" <<<"$out"; then
  ok
else
  bad "type dynamic: rc $rc: $out"
fi
out=$("$CUPID" run "$Q" -o "$work/refused" --set coupling.balance=momentum --solver krylov --assembled 2>&1)
rc=$?
if [ "$rc" -ne 0 ] && grep -q "not on its assembled path (--assembled)" <<<"$out"; then ok; else bad "--assembled: rc $rc: $out"; fi

# 4. the paper's imbalance against h at fixed m
run "$Q" -o "$work/h1" --solver krylov --set coupling.balance=none
run "$Q" -o "$work/h05" --solver krylov --set peridynamics.spacing=0.5 --set peridynamics.horizon=0.75 --set coupling.balance=none
check python3 - "$work" <<'PY'
import json, sys
w = sys.argv[1]
i1, i05 = (json.load(open(f"{w}/{k}/summary.json"))["coupling_quality"]["imbalance"] for k in ("h1", "h05"))
print(f"paper 000's operator, m = 1.5: imbalance {i1:.2e} at h = 1, {i05:.2e} at h = 0.5")
sys.exit(0 if 0 < i05 <= 0.5 * i1 else 1)
PY
finish coupling_balance
