#!/usr/bin/env bash
# `pip install ./python` (issue 35, item 5): the package installs with Debian's python3-pip and
# python3-setuptools, nothing downloaded (--no-index, --no-build-isolation), into a virtual
# environment, with its own libcupid; `import cupid` then works from any folder without
# PYTHONPATH or CUPID_LIBRARY, and gives the command line's answer. Checked both ways of getting
# the library (python/setup.py):
#   1. CUPID_LIBRARY=build/libcupid.so bundles that file (byte for byte);
#   2. without it, setup.py builds libcupid with CMake (the library target alone).
# And a CUPID_LIBRARY that is no file fails the install with a message naming it. The
# repository is a copy of python/ beside links to the rest, so the source tree gets no build
# files.
set -u
CUPID=$(realpath "${CUPID:-build/cupid}")
SRC=$(realpath "${CUPID_SOURCE_DIR:-.}")
LIB=$(realpath "$(dirname "$CUPID")/libcupid.so")
PY=/usr/bin/python3
# A sanitized build (CUPID_SANITIZE) needs the ASan runtime loaded first into the plain
# interpreter that imports it (as unit.python); the interpreter's allocations are not ours.
asan=$(ldd "$LIB" 2>/dev/null | awk '/libasan/ {print $3}')
pyenv=()
[ -n "$asan" ] && pyenv=(LD_PRELOAD="$asan" ASAN_OPTIONS=detect_leaks=0)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
die() { echo "FAIL: $*"; fail=$((fail + 1)); }

mkdir -p "$work/repo" "$work/elsewhere"
for e in "$SRC"/*; do
  name=$(basename "$e")
  case $name in
    python) mkdir "$work/repo/python"
            cp -r "$SRC/python/cupid" "$SRC/python/setup.py" "$SRC/python/pyproject.toml" \
                  "$SRC/python/README.md" "$work/repo/python/"
            rm -f "$work/repo/python/cupid/libcupid.so" ;;
    build*|out) ;;
    *) ln -s "$e" "$work/repo/$name" ;;
  esac
done

# the command line's answer for the bar
"$CUPID" run "$SRC/examples/bar/bar.yaml" -o "$work/cli" --quiet || die "cupid run bar.yaml"
check_import() { # venv, what
  (cd "$work/elsewhere" && env -u CUPID_LIBRARY -u PYTHONPATH "${pyenv[@]}" "$1/bin/python" - "$1" "$SRC" \
     "$work/cli/summary.json" "$("$CUPID" --version)" "$work/py_$2" <<'EOF'
import json, os, sys
import cupid
venv, src, summary, cli_version, out = sys.argv[1:]
lib = cupid.library_path()
assert lib.startswith(os.path.realpath(venv)) or lib.startswith(venv), lib
assert cli_version.split()[1] == cupid.version(), (cli_version, cupid.version())
p = cupid.Problem(os.path.join(src, "examples/bar/bar.yaml"), output_dir=out)
p.solve()
want = json.load(open(summary))["reaction_sum"]
got = p.info["reaction_sum"]
scale = max(abs(v) for v in want)
assert all(abs(a - b) <= 1e-12 * scale for a, b in zip(got, want)), (got, want)
print("  import cupid from %s: %s, the bar's reactions as the command line's" % (os.getcwd(), lib))
EOF
  ) || die "$2: import cupid from the installed package"
}

# 1. an existing build, bundled
"$PY" -m venv --system-site-packages --without-pip "$work/venv1" || die "venv"
if CUPID_LIBRARY=$LIB "$work/venv1/bin/python" -m pip install -q --no-index --no-build-isolation \
     "$work/repo/python" > "$work/pip1.log" 2>&1; then
  bundled=$(ls "$work"/venv1/lib/python3*/site-packages/cupid/libcupid.so)
  cmp -s "$bundled" "$LIB" || die "the bundled library differs from CUPID_LIBRARY's"
  check_import "$work/venv1" bundled
else
  die "pip install with CUPID_LIBRARY"; tail -5 "$work/pip1.log"
fi

# 2. built by the same command (CMake)
"$PY" -m venv --system-site-packages --without-pip "$work/venv2" || die "venv"
if CMAKE_BUILD_PARALLEL_LEVEL=2 "$work/venv2/bin/python" -m pip install -q --no-index \
     --no-build-isolation "$work/repo/python" > "$work/pip2.log" 2>&1; then
  [ -f "$work/repo/python/build/cmake/libcupid.so" ] || die "setup.py did not build libcupid"
  check_import "$work/venv2" built
else
  die "pip install building libcupid"; tail -5 "$work/pip2.log"
fi

# 3. a CUPID_LIBRARY that is no file
"$PY" -m venv --system-site-packages --without-pip "$work/venv3" || die "venv"
out=$(CUPID_LIBRARY=$work/no/libcupid.so "$work/venv3/bin/python" -m pip install --no-index \
        --no-build-isolation "$work/repo/python" 2>&1) && die "a missing CUPID_LIBRARY installed"
grep -q "CUPID_LIBRARY=$work/no/libcupid.so is not a file" <<<"$out" ||
  die "the message does not name the missing CUPID_LIBRARY: $(tail -3 <<<"$out")"

[ "$fail" -eq 0 ] && echo "python_install: all checks passed"
exit $((fail > 0))
