#!/usr/bin/env bash
# Fuzz smoke pass over every parser.
#
#   tests/fuzz/smoke.sh BUILD_DIR            deterministic: fixed seed and a fixed
#                                            number of inputs per target (CI)
#   tests/fuzz/smoke.sh BUILD_DIR SECONDS    explore: SECONDS per target, random seed
#
# Each target starts from seeds written by fuzz_seeds plus every input that
# once crashed a reader (tests/fuzz/regressions/TARGET/, replayed first as
# part of the corpus). Fails on any crash, leak or sanitizer error, timeout
# or out-of-memory. libFuzzer writes the failing inputs (crash-*, oom-*,
# leak-*, timeout-* after the prefix) to BUILD_DIR/artifacts/, never to the
# working directory: crash-TARGET-KIND-SHA1, the name a regression keeps
# when it is moved to tests/fuzz/regressions/TARGET/. The folder holds the
# last run's findings only: a target's files are removed before it runs and
# again when it passes (the VDB reader's forked child crashes by design on
# some inputs, the parent reports iso::Error, and libFuzzer's handler in the
# child still writes the input).
set -uo pipefail
build=${1:?usage: smoke.sh BUILD_DIR [SECONDS]}
seconds=${2:-}
here=$(cd "$(dirname "$0")" && pwd)
artifacts=$(mkdir -p "$build/artifacts" && cd "$build/artifacts" && pwd)
work=$(mktemp -d /tmp/isoscope-fuzz-smoke-XXXXXX)
trap 'rm -rf "$work"' EXIT
"$build/tests/fuzz/fuzz_seeds" "$work/seeds" >/dev/null || { echo "fuzz smoke: seed writer failed"; exit 1; }
# Inputs per target in deterministic mode (about 10 s each on a 2-core
# machine; the VDB target forks a reader process per input).
declare -A runs=([nrrd]=20000 [nifti]=20000 [metaimage]=20000 [vti]=10000 [vdb]=60 [dicom]=600
                 [stl]=20000 [ply]=20000 [obj]=20000 [vtp]=10000 [markups]=8000)
targets=(nrrd nifti metaimage vti vdb dicom stl ply obj vtp markups)
failed=()
for target in "${targets[@]}"; do
  exe="$build/tests/fuzz/fuzz_$target"
  corpus="$work/corpus-$target"
  mkdir -p "$corpus"
  cp -r "$work/seeds/$target/." "$corpus/" 2>/dev/null || true
  cp -r "$here/regressions/$target/." "$corpus/" 2>/dev/null || true
  if [[ -n $seconds ]]; then budget=(-max_total_time="$seconds"); else budget=(-seed=1 -runs="${runs[$target]}"); fi
  rm -f "$artifacts/crash-$target-"*
  # -malloc_limit_mb above 4 GiB: a DICOM element may claim up to 4 GiB, which
  # vtk-dicom reserves without touching (harmless); RSS stays capped at 2 GiB.
  # ASan's leak checker runs at exit, where VTK keeps singletons alive on
  # purpose; the harness replaces operator new (see fuzz_target.cpp), which
  # makes ASan's new/free pairing check meaningless.
  if ASAN_OPTIONS=detect_leaks=0:alloc_dealloc_mismatch=0 \
     "$exe" "${budget[@]}" -rss_limit_mb=2048 -malloc_limit_mb=8192 -timeout=10 -print_final_stats=0 \
       -artifact_prefix="$artifacts/crash-$target-" "$corpus" >"$work/$target.log" 2>&1; then
    done_runs=$(grep -o 'Done [0-9]* runs' "$work/$target.log" | tail -1)
    echo "fuzz_$target: ok (${done_runs:-no run count})"
    rm -f "$artifacts/crash-$target-"*
  else
    echo "fuzz_$target: FAILED"
    tail -n 40 "$work/$target.log"
    failed+=("$target")
  fi
done
if ((${#failed[@]})); then
  echo "fuzz smoke: findings in ${failed[*]} (inputs saved under $artifacts/)"
  exit 1
fi
echo "fuzz smoke: all ${#targets[@]} targets ran clean"
