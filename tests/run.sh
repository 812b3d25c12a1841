#!/usr/bin/env bash
# The test command (README, CI): installs what the project needs, builds, runs
# every CTest test (labels cpu and gl), the same tests under ASan+UBSan, and a
# short libFuzzer smoke pass over every parser.
#
#   tests/run.sh            everything
#   tests/run.sh quick      the main build and its tests only
#
# Environment: ISOSCOPE_FUZZ_SECONDS=N fuzzes N seconds per target with a
# random seed instead of the deterministic pass.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-all}
jobs=$(nproc)
log=$(mktemp /tmp/isoscope-tests-XXXXXX)
trap 'rm -f "$log"' EXIT

# Runs ctest, showing its output, and adds its counts to the totals.
passed=0
failed=0
run_ctest() {
  local rc=0
  "$@" 2>&1 | tee "$log" || rc=$?
  local line
  line=$(grep -E 'tests passed, [0-9]+ tests failed out of [0-9]+' "$log" | tail -1)
  if [[ -n $line ]]; then
    local f t
    f=$(sed -E 's/.*, ([0-9]+) tests failed out of ([0-9]+).*/\1/' <<<"$line")
    t=$(sed -E 's/.*, ([0-9]+) tests failed out of ([0-9]+).*/\2/' <<<"$line")
    passed=$((passed + t - f))
    failed=$((failed + f))
  fi
  return $rc
}
summary() { echo "tests: $passed passed, $failed failed"; }

./setup.sh

echo "== build (RelWithDebInfo)"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j "$jobs"
echo "== tests"
run_ctest ctest --test-dir build --output-on-failure -j "$jobs" || { summary; exit 1; }

if [[ $mode == quick ]]; then summary; exit 0; fi

echo "== tests under AddressSanitizer + UndefinedBehaviorSanitizer"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DISOSCOPE_SANITIZE=ON -DISOSCOPE_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build build-asan -j "$jobs"
# VTK and OpenVDB allocate globals that LeakSanitizer reports at exit; leaks
# are checked by the fuzzers on our own code paths instead.
run_ctest env ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-asan --output-on-failure -j "$jobs" || { summary; exit 1; }

if [[ -f tests/fuzz/smoke.sh ]]; then
  echo "== fuzz smoke"
  CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DISOSCOPE_FUZZ=ON >/dev/null
  cmake --build build-fuzz -j "$jobs" --target fuzzers
  if tests/fuzz/smoke.sh build-fuzz ${ISOSCOPE_FUZZ_SECONDS:-}; then
    passed=$((passed + 11)) # one per fuzz target (tests/fuzz/smoke.sh)
  else
    failed=$((failed + 1))
    summary
    exit 1
  fi
fi
summary
