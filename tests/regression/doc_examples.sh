#!/usr/bin/env bash
# The documented examples run as written (issue 19 item 10): every ```yaml block of docs/*.md
# preceded by the line `<!-- test: run ... -->` is a whole model; `cupid check` and `cupid run`
# must accept it (exit 0) and write its summary.json with finite point values.
. "$(dirname "$0")/../tools/checks.sh"  # CUPID, SRC, $work (cwd), ok, bad, finish
n=0
for doc in "$SRC"/docs/*.md; do
  /usr/bin/python3 - "$doc" "$work" <<'PY' || { bad "cannot extract the blocks of $doc"; continue; }
import os, sys
doc, out = sys.argv[1], sys.argv[2]
lines, k = open(doc).read().split("\n"), 0
for i, line in enumerate(lines):
    if line.startswith("<!-- test: run") and i + 1 < len(lines) and lines[i + 1].startswith("```yaml"):
        j = i + 2
        while j < len(lines) and not lines[j].startswith("```"):
            j += 1
        name = "%s.%d.yaml" % (os.path.basename(doc)[:-3], k)
        open(os.path.join(out, name), "w").write("\n".join(lines[i + 2:j]) + "\n")
        k += 1
PY
done
for model in "$work"/*.yaml; do
  [ -e "$model" ] || continue
  n=$((n+1))
  name=$(basename "$model")
  out=$("$CUPID" check "$model" 2>&1) && ok || bad "check $name: $out"
  out=$("$CUPID" run "$model" -o "run_$name" --quiet 2>&1) && ok || { bad "run $name: $out"; continue; }
  /usr/bin/python3 -c "
import json, math, sys
s = json.load(open(sys.argv[1]))
assert s['points'] and all(math.isfinite(p[c]) for p in s['points'] for c in ('ux', 'uy', 'uz')), s['points']
" "run_$name/summary.json" && ok || bad "$name: no finite point values"
done
[ "$n" -ge 1 ] && ok || bad "no documented example found (<!-- test: run --> blocks)"
finish doc_examples
