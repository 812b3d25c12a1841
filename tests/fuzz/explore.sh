#!/usr/bin/env bash
# Randomized fuzzing of one parser for as long as asked: by hand, never in CI
# (the test command runs the deterministic tests/fuzz/smoke.sh instead).
#
#   tests/fuzz/explore.sh BUILD_DIR TARGET SECONDS [JOBS]
#
# BUILD_DIR is the fuzz build (CC=clang CXX=clang++ cmake -S . -B build-fuzz
# -G Ninja -DISOSCOPE_FUZZ=ON && cmake --build build-fuzz --target fuzzers).
# Starts from the committed corpus (tests/fuzz/corpus/TARGET/), the
# regressions (tests/fuzz/regressions/TARGET/) and whatever earlier runs
# found (BUILD_DIR/explore/TARGET/, kept between runs), with a random seed.
# It runs libFuzzer's fork mode with JOBS workers (default 1), which goes on
# after a finding (each one is saved). Findings go to BUILD_DIR/artifacts/
# as explore-TARGET-KIND-SHA1; once the reader is fixed, move each to
# tests/fuzz/regressions/TARGET/ (renamed crash-TARGET-KIND-SHA1), where the
# smoke and the fuzz_regressions test replay it on every run.
# Prints the number of executions and the findings at the end.
set -uo pipefail
build=${1:?usage: explore.sh BUILD_DIR TARGET SECONDS [JOBS]}
target=${2:?usage: explore.sh BUILD_DIR TARGET SECONDS [JOBS]}
seconds=${3:?usage: explore.sh BUILD_DIR TARGET SECONDS [JOBS]}
jobs=${4:-1}
here=$(cd "$(dirname "$0")" && pwd)
exe="$build/tests/fuzz/fuzz_$target"
[[ -x $exe ]] || { echo "explore: no $exe (build the fuzz targets first)"; exit 2; }
found=$(mkdir -p "$build/explore/$target" && cd "$build/explore/$target" && pwd)
artifacts=$(mkdir -p "$build/artifacts" && cd "$build/artifacts" && pwd)
log="$build/explore/$target.log"
mode=(-fork="$jobs" -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1)
echo "explore: fuzz_$target for $seconds s, $jobs job(s); log $log"
ASAN_OPTIONS=detect_leaks=0:alloc_dealloc_mismatch=0 \
  "$exe" "${mode[@]}" -max_total_time="$seconds" -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=30 \
  -artifact_prefix="$artifacts/explore-$target-" "$found" "$here/corpus/$target" "$here/regressions/$target" \
  >"$log" 2>&1
rc=$?
runs=$(grep -aoE '^#[0-9]+' "$log" | tail -1 | tr -d '#')
echo "explore: fuzz_$target exit $rc after ${runs:-?} executions; corpus now $(ls "$found" | wc -l) files"
ls "$artifacts" | grep "^explore-$target-" || echo "explore: no findings"
