#!/usr/bin/env bash
# The stiffened panel of paper 000 (section 5.3) with the balanced fictitious-node coupling
# (issue 18 item 3; docs/coupling.md, "The balanced fictitious-node coupling"):
# examples/panel/study.py runs the coupled panel on the example's FE mesh and on a refined one
# (skin split beside the stringers and in 2 through its thickness, stringers in 2 elements
# across theirs: "x2"), each with its same-mesh full L9 twin, and the converged full-L9 panel
# ("fine", study.py REFERENCES).
#  - balanced, each coupled model is within 1% of its same-mesh L9 at A, B and C (measured
#    0.05-0.70%: the PD stringer at h = 1 against an L9 stringer; the issue's 2% with room for
#    the solver's tolerance);
#  - balanced, refining the FE mesh brings the coupled panel within 1% of the converged L9
#    (measured 0.32%, 0.42%, 0.21%), and its error falls at each point;
#  - paper 000's operator (balance: none) on the refined mesh misses the converged L9 by more
#    than 2% (the issue's finding: it gets worse as the FE mesh near the regions is refined).
# ~1 minute on 2 cores (the converged reference has 251,370 FE DOFs).
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd)
export CUPID_LIBRARY="${CUPID_LIBRARY:-$(dirname "$CUPID")/libcupid.so}"
# A sanitizer build's library needs its runtime loaded first in Python (as unit.python has it),
# and Python's own allocations are no leak of cupid's. ldd's output is read whole first (an
# early grep exit under pipefail once failed a run: tests/regression/library.sh).
libs=$(ldd "$CUPID_LIBRARY" 2>/dev/null || true)
asan=$(awk '/libasan/ {print $3; exit}' <<<"$libs")
if [ -n "$asan" ]; then
  export LD_PRELOAD="$asan" ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
fi
PY=/usr/bin/python3
"$PY" "$SRC/examples/panel/study.py" example x2 --solver krylov --against fine --balance momentum \
  > balanced.md || { echo "FAIL: study.py (balanced)"; exit 1; }
"$PY" "$SRC/examples/panel/study.py" x2 --solver krylov --against fine > paper.md ||
  { echo "FAIL: study.py (balance: none)"; exit 1; }
cat balanced.md paper.md | cut -c1-300
"$PY" - balanced.md paper.md <<'PY'
import re, sys
def rows(path):
    out = {}
    for line in open(path):
        if not line.startswith("| ") or line.startswith("| variant"):
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        same = [float(x) for x in re.findall(r"\(([+-][0-9.]+)%\)", " ".join(cells[3:6]))]
        ref = [float(x) for x in re.findall(r"([+-][0-9.]+)%", cells[-1])]
        out[cells[0]] = (same, ref)
    return out
b, p = rows(sys.argv[1]), rows(sys.argv[2])
ok = True
for v in ("example", "x2"):
    same, ref = b[v]
    print(f"balanced {v}: vs its same-mesh L9 {same}, vs the converged L9 {ref}")
    ok &= len(same) == 3 and max(abs(x) for x in same) <= 1.0
ok &= max(abs(x) for x in b["x2"][1]) <= 1.0
ok &= all(abs(r) < abs(e) for r, e in zip(b["x2"][1], b["example"][1]))
print(f"paper 000's operator, x2: vs the converged L9 {p['x2'][1]}")
ok &= max(abs(x) for x in p["x2"][1]) > 2.0
print("coupling_panel_balance:", "passed" if ok else "FAILED")
sys.exit(0 if ok else 1)
PY
