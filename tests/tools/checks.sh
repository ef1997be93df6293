# Shared preamble of the bash tests that count checks (sourced, not a test itself): the cupid
# binary and source tree from ctest's environment, a scratch directory removed on exit (and
# made the working directory), and the pass/fail counters with their reporters.
#   . "$(dirname "$0")/../tools/checks.sh"
#   ... ok / bad "what failed" ...
#   finish NAME   # prints "NAME: P passed, F failed"; exit status 0 only without failures
#   expect CODE PATTERN -- CMD...   # one check: CMD's exit status and a pattern in its output
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
pass=0; fail=0
ok() { pass=$((pass+1)); }
bad() { echo "FAIL: $*"; fail=$((fail+1)); }
finish() {
  echo "$1: $pass passed, $fail failed"
  [ "$fail" -eq 0 ]
}
# expect CODE PATTERN -- CMD...: CMD exits with CODE and prints PATTERN (grep -E)
expect() {
  local code=$1 pattern=$2; shift 3
  local out rc
  out=$("$@" 2>&1); rc=$?
  if [ "$rc" -ne "$code" ]; then bad "$* -> exit $rc, expected $code"; echo "$out" | head -5; return; fi
  if ! grep -qE -- "$pattern" <<<"$out"; then bad "$* -> output does not match '$pattern'"; echo "$out" | head -5; return; fi
  ok
}
