#!/usr/bin/env bash
# Fuzz the model reader and validator with libFuzzer (docs/hardening.md).
#
#   tests/fuzz/run.sh [SECONDS] [CORPUS_DIR]
#
# Builds build-fuzz/ with clang-14 (-DCUPID_FUZZ=ON: ASan + UBSan + coverage) if needed, seeds a
# corpus with every example and test model, tests/fuzz/regressions/ and the minimised corpus of
# earlier runs (tests/fuzz/corpus/), and fuzzes for
# SECONDS (default 60) with the model-format dictionary. CORPUS_DIR (default: a temporary
# directory) keeps the inputs that found new coverage, so long runs can be resumed.
# FUZZ_JOBS=N runs N fuzzing processes in parallel (default 1).
# A crash, leak, timeout (10 s per input) or out-of-memory (2 GB) stops the run with exit
# status 1 and leaves the input in build-fuzz/artifacts/; add it to tests/fuzz/regressions/ (a
# test replays every file there) once fixed.
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-60}
corpus=${2:-}
jobs=${FUZZ_JOBS:-1}
build=${CUPID_FUZZ_BUILD_DIR:-build-fuzz}

if [ ! -x "$build/cupid_fuzz_model" ] || [ -n "$(find src include tests/fuzz -newer "$build/cupid_fuzz_model" -name '*.[ch]' | head -1)" ]; then
  CC=${CC_FUZZ:-clang-14} cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" -DCUPID_FUZZ=ON -DCUPID_BUILD_TESTS=OFF >/dev/null
  cmake --build "$build" -j"$(nproc)" --target cupid_fuzz_model
fi

seeds=$(mktemp -d)
cleanup() { rm -rf "$seeds"; [ -n "${tmp_corpus:-}" ] && rm -rf "$tmp_corpus"; return 0; }
trap cleanup EXIT
n=0
while IFS= read -r -d '' f; do
  cp "$f" "$seeds/seed_$n.yaml"
  n=$((n + 1))
done < <(find examples tests/models -type f -name '*.yaml' -print0
         find tests/fuzz/regressions tests/fuzz/corpus -type f -print0)
echo "fuzz: $n seeds, $seconds s, $jobs job(s)"
if [ -z "$corpus" ]; then tmp_corpus=$(mktemp -d); corpus=$tmp_corpus; fi
mkdir -p "$corpus" "$build/artifacts"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
args=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536
      -dict=tests/fuzz/model.dict -artifact_prefix="$build/artifacts/" -print_final_stats=1)
if [ "$jobs" -gt 1 ]; then args+=(-fork="$jobs" -ignore_crashes=0); fi
log=$build/fuzz.log
if "$build/cupid_fuzz_model" "${args[@]}" "$corpus" "$seeds" >"$log" 2>&1; then
  grep -E '^stat::|^Done' "$log" || true
  echo "fuzz: no crash in $seconds s; corpus $(ls "$corpus" | wc -l) inputs (log: $log)"
else
  tail -n 80 "$log" >&2
  echo "fuzz: FAILED; reproduce with $build/cupid_fuzz_model $build/artifacts/<file>" >&2
  ls -la "$build/artifacts" >&2
  exit 1
fi
