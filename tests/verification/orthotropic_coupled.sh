#!/usr/bin/env bash
# An orthotropic beam with an isotropic PD region (issue 19 item 2: refused before with "PD
# material 1: Young's modulus must be positive, got 0"): tests/models/coupling/
# orthotropic_beam_pd.yaml runs with each coupling method that takes it (Lagrange, fictitious
# nodes), with Lagrange multipliers its reactions balance the load (to 1e-9 of it: a direct
# solve, residual ~1e-13; the fictitious-node imbalance on this coarse layout is issue 18's), and
# an orthotropic material with isotropic constants (E, nu, G = E / (2 (1 + nu)) on every axis)
# gives the isotropic material's displacements (to 1e-9 of the largest: the same stiffness).
set -euo pipefail
SRC=${CUPID_SOURCE_DIR:?}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
model=$SRC/tests/models/coupling/orthotropic_beam_pd.yaml
fail=0
for method in lagrange fictitious; do
  sed "s/method: lagrange/method: $method/" "$model" > "$tmp/$method.yaml"
  "$CUPID" run "$tmp/$method.yaml" -o "$tmp/$method" --quiet
  # the ply as an isotropic material, and as an orthotropic one with isotropic constants
  /usr/bin/python3 - "$tmp/$method.yaml" "$tmp/${method}_iso.yaml" "$tmp/${method}_oiso.yaml" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
ply = re.compile(r"  ply:\n(    .*\n)+")
open(sys.argv[2], "w").write(ply.sub("  ply: {E: 10000, nu: 0.3}\n", text))
open(sys.argv[3], "w").write(ply.sub("  ply:\n    E: [10000, 10000, 10000]\n    nu: [0.3, 0.3, 0.3]\n"
                                     "    G: [3846.153846153846, 3846.153846153846, 3846.153846153846]\n", text))
PY
  "$CUPID" run "$tmp/${method}_iso.yaml" -o "$tmp/${method}_iso" --quiet
  "$CUPID" run "$tmp/${method}_oiso.yaml" -o "$tmp/${method}_oiso" --quiet
  /usr/bin/python3 - "$tmp/$method" "$tmp/${method}_iso" "$tmp/${method}_oiso" "$method" <<'PY' || fail=1
import json, sys
s, iso, oiso = (json.load(open(d + "/summary.json")) for d in sys.argv[1:4])
load, reac = s["applied_load_sum"], s["reaction_sum"]
imb = max(abs(a + b) for a, b in zip(load, reac)) / max(abs(a) for a in load)
ui = [p[c] for p in iso["points"] for c in ("ux", "uy", "uz")]
uo = [p[c] for p in oiso["points"] for c in ("ux", "uy", "uz")]
diff = max(abs(a - b) for a, b in zip(ui, uo)) / max(abs(a) for a in ui)
tip = s["points"][0]["uy"]
# the fictitious-node method does not conserve momentum (docs/coupling.md, issue 18): its
# imbalance is reported, not bounded; Lagrange multipliers balance to round-off
balanced = imb < 1e-9 or sys.argv[4] != "lagrange"
ok = balanced and diff < 1e-9 and tip > 0
print("%s: tip u_y %.6g, |R + P| / |P| %.2e, orthotropic-as-isotropic vs isotropic %.2e: %s"
      % (sys.argv[4], tip, imb, diff, "ok" if ok else "FAIL"))
sys.exit(0 if ok else 1)
PY
done
[ $fail -eq 0 ] && echo "2 passed, 0 failed" || exit 1
