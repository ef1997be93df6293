#!/usr/bin/env bash
# libcupid from outside (issue 15): install the library (`cmake --install`), build
# examples/c/run_model.c against it with pkg-config, run the coupled bar through it and check
# that every count, resultant and point value equals the command line's summary.json (points
# to 1e-12 of the largest displacement: both runs take the same code path, so only the last
# printed digit may differ).
set -euo pipefail
SRC=${CUPID_SOURCE_DIR:?}
BUILD=$(dirname "${CUPID:?}")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

cmake --install "$BUILD" --prefix "$tmp/inst" >/dev/null
pc=$(dirname "$(find "$tmp/inst" -name cupid.pc | head -n1)")
test -n "$pc" || { echo "FAIL: no cupid.pc installed"; exit 1; }
flags=$(PKG_CONFIG_PATH=$pc pkg-config --cflags --libs cupid)
# A sanitized library (the CI's ASan stage) needs its runtime first: the program is built
# with the same sanitizers.
# (ldd's output is read whole first: under pipefail, `ldd | grep -q` fails whenever grep exits
# before ldd has written everything, and the program was then built without the runtime.)
san=""
libs=$(ldd "$(find "$tmp/inst" -name 'libcupid.so' | head -n1)")
if grep -q libasan <<<"$libs"; then
  san="-fsanitize=address,undefined"
fi
cc -std=c17 -Wall -Wextra -Werror $san "$SRC/examples/c/run_model.c" $flags -lm -o "$tmp/run_model"
echo "built examples/c/run_model.c with: pkg-config --cflags --libs cupid -> $flags"

model=$SRC/tests/models/mpi/coupled_bar.yaml
"$CUPID" run "$model" -o "$tmp/cli" --quiet
LD_LIBRARY_PATH=$(dirname "$(find "$tmp/inst" -name 'libcupid.so' | head -n1)") \
  "$tmp/run_model" "$model" "$tmp/lib" > "$tmp/lib.json"

/usr/bin/python3 - "$tmp/cli/summary.json" "$tmp/lib.json" "$tmp/lib/summary.json" <<'PY'
import json, sys
cli, lib, lib_summary = (json.load(open(p)) for p in sys.argv[1:4])
fails = []
for key in ("pd_nodes", "bonds", "fictitious_nodes", "fe_dofs", "dofs", "constrained_dofs"):
    if cli["counts"][key] != lib[key]:
        fails.append("%s: cli %s, library %s" % (key, cli["counts"][key], lib[key]))
umax = max(lib["max_pd_displacement"], lib["max_beam_displacement"])
for a, b in zip(cli["points"], lib["points"]):
    for c in ("ux", "uy", "uz"):
        if abs(a[c] - b[c]) > 1e-12 * umax:
            fails.append("point %s %s: cli %.17g, library %.17g" % (a["name"], c, a[c], b[c]))
for key in ("applied_load_sum", "reaction_sum"):
    scale = max(abs(v) for v in cli["applied_load_sum"])
    for k in range(3):
        if abs(cli[key][k] - lib[key][k]) > 1e-12 * scale:
            fails.append("%s[%d]: cli %.17g, library %.17g" % (key, k, cli[key][k], lib[key][k]))
if lib["pd_field_rows"] != cli["counts"]["pd_nodes"]:
    fails.append("PD field rows %d != PD nodes" % lib["pd_field_rows"])
if lib["beam_points"] <= 0 or not lib["max_beam_displacement"] > 0:
    fails.append("no beam field")
if lib_summary["points"] != cli["points"]:
    fails.append("the library's summary.json points differ from the CLI's")
print("library vs CLI: %d points, %d counts, max |u| %.6g" % (len(lib["points"]), 6, umax))
for f in fails:
    print("FAIL:", f)
sys.exit(1 if fails else 0)
PY
echo "1 passed, 0 failed"
