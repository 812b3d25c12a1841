#!/usr/bin/env bash
# The test command (README, CI): installs what the project needs, then
#   1. builds the product and the benchmarks (release) and runs the
#      benchmarks' own tests (label bench);
#   2. makes the Debian package and checks it (tests/package/check.sh: the
#      installed release program on the bundled CT);
#   3. builds with AddressSanitizer + UndefinedBehaviorSanitizer (and
#      assertions on) and runs every other CTest test there (labels cpu, gl,
#      mpi, gui): the test programs are built and run once, under the
#      sanitizers, not once in each build (docs/architecture.md, "What the
#      test command's time goes to");
#   4. runs the deterministic fuzz smoke over every parser (tests/fuzz/smoke.sh).
# At its end (and when a stage fails) it prints each stage's minutes.
#
#   tests/run.sh            everything
#   tests/run.sh quick      the release build of everything and every test
#                           there (no sanitizers, package or fuzzing)
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-all}
jobs=$(nproc)
log=$(mktemp /tmp/isoscope-tests-XXXXXX)

# ---- stage clock: each stage's minutes, printed at the end whatever happens
stages=()
stage_name=""
stage_start=0
begin() {
  end_stage
  stage_name=$1
  stage_start=$SECONDS
  # The free disk at each stage: the sanitizer build needs a few GB, and a
  # full disk shows up as a linker dying of SIGBUS, not as "no space".
  echo "== $1 ($(df -h --output=avail . | tail -1 | tr -d ' ') free on this disk)"
}
end_stage() {
  if [[ -n $stage_name ]]; then
    stages+=("$(awk -v s=$((SECONDS - stage_start)) -v n="$stage_name" 'BEGIN { printf "  %-46s %5.1f min", n, s / 60 }')")
    stage_name=""
  fi
}
report() {
  end_stage
  echo "== minutes per stage ($jobs cores)"
  printf '%s\n' "${stages[@]}"
  awk -v s=$SECONDS 'BEGIN { printf "  %-46s %5.1f min\n", "total", s / 60 }'
  rm -f "$log"
}
trap report EXIT

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

begin "packages (./setup.sh --tests)"
./setup.sh --tests

if [[ $mode == quick ]]; then
  begin "release build (everything)"
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DISOSCOPE_BUILD_TESTS=ON >/dev/null
  cmake --build build -j "$jobs"
  begin "release tests"
  run_ctest ctest --test-dir build --output-on-failure -j "$jobs" || { summary; exit 1; }
  summary
  exit 0
fi

# The release build makes what is shipped and what is measured: the
# product and the benchmarks. The test programs are built and run in the
# sanitizer stage only (they ran in both: here they were 946 of the release
# build's 2262 processor-seconds, then their run); the benchmarks' harness
# tests run here, where the benchmarks are.
# (cpack with Ninja builds nothing: the package takes what is built, so the
# target `installed` makes all it installs.)
begin "release build (the product and the benchmarks)"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DISOSCOPE_BUILD_TESTS=ON >/dev/null
cmake --build build -j "$jobs" --target installed benchmarks
begin "release: the benchmarks' tests"
run_ctest ctest --test-dir build --output-on-failure -j "$jobs" -L bench || { summary; exit 1; }

begin "Debian package (tests/package/check.sh)"
if tests/package/check.sh build; then passed=$((passed + 1)); else failed=$((failed + 1)); summary; exit 1; fi

begin "ASan+UBSan build"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DISOSCOPE_SANITIZE=ON -DISOSCOPE_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build build-asan -j "$jobs"
begin "ASan+UBSan tests"
# VTK and OpenVDB allocate globals that LeakSanitizer reports at exit; leaks
# are checked by the fuzzers on our own code paths instead.
run_ctest env ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-asan --output-on-failure -j "$jobs" || { summary; exit 1; }

begin "fuzz build"
CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DISOSCOPE_FUZZ=ON >/dev/null
cmake --build build-fuzz -j "$jobs" --target fuzzers
begin "fuzz smoke (deterministic)"
if tests/fuzz/smoke.sh build-fuzz; then
  passed=$((passed + 11)) # one per fuzz target (tests/fuzz/smoke.sh)
else
  failed=$((failed + 1))
  summary
  exit 1
fi
summary
