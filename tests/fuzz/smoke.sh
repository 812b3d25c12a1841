#!/usr/bin/env bash
# Deterministic fuzz smoke over every parser (the test command runs it).
#
#   tests/fuzz/smoke.sh BUILD_DIR [TARGET ...]
#
# Each target first replays its corpus: tests/fuzz/corpus/TARGET/ (committed
# seeds) and tests/fuzz/regressions/TARGET/ (every input that once crashed,
# aborted or exhausted a reader); then it mutates that corpus for a fixed
# number of runs from a fixed seed. The same commit makes the same inputs and
# so gives the same verdict on every machine. What that rests on: committed
# seeds (none written at run time), -seed=1 and -runs=N, no corpus reload
# (-reload=0, which re-runs files on a timer), the input file at the same path
# everywhere (ISOSCOPE_FUZZ_INPUT_DIR), the seeds in a fixed order
# (-seed_inputs), no mutations from the values compared (-use_cmp=0: pointer
# comparisons make them depend on where allocations land, which VTK's threads
# vary) and no address randomization (setarch -R), the child processes' input
# and messages through files, their plumbing left out of coverage (see
# io/child_process.cpp), memory limits checked at each allocation
# (-malloc_limit_mb) rather than only by the sampled RSS. Each
# target's final statistics (cov, ft, corp) are printed, so two runs can be
# compared line by line.
#
# Fails on any crash, abort, leak or sanitizer error, timeout or out-of-memory.
# libFuzzer writes the failing input to BUILD_DIR/artifacts/ as
# crash-TARGET-KIND-SHA1, the name it keeps when moved to
# tests/fuzz/regressions/TARGET/. The folder holds the last run's findings
# only: a target's files are removed before it runs and again when it passes
# (the VDB reader's forked child crashes by design on some inputs, the parent
# reports iso::Error, and libFuzzer's handler in the child still writes one).
#
# Longer, randomized fuzzing is tests/fuzz/explore.sh (by hand, not in CI).
set -uo pipefail
build=${1:?usage: smoke.sh BUILD_DIR [TARGET ...]}
shift
here=$(cd "$(dirname "$0")" && pwd)
artifacts=$(mkdir -p "$build/artifacts" && cd "$build/artifacts" && pwd)
work=$(mktemp -d /tmp/isoscope-fuzz-smoke-XXXXXX)
trap 'rm -rf "$work" /tmp/isoscope-fuzz-smoke-input' EXIT
# Runs per target, the replay included (about 5-50 s each on a 2-core
# machine; the VDB and VTP targets start a reader process per input, the
# DICOM target one for each compressed input).
declare -A runs=([nrrd]=20000 [nifti]=20000 [metaimage]=20000 [vti]=10000 [vdb]=60 [dicom]=3000
                 [stl]=20000 [ply]=20000 [obj]=20000 [vtp]=300 [markups]=8000)
targets=(nrrd nifti metaimage vti vdb dicom stl ply obj vtp markups)
(($#)) && targets=("$@")
# The same addresses in every run, where the system allows it.
fixed=()
if setarch "$(uname -m)" -R true 2>/dev/null; then fixed=(setarch "$(uname -m)" -R); fi
shopt -s nullglob
# One target: replay, then mutate. Writes its one-line verdict (and the log's
# tail on a failure) to $work/TARGET.verdict.
run_target() {
  local target=$1
  local exe="$build/tests/fuzz/fuzz_$target"
  # The seeds in a fixed order (the globs sort): as a directory, libFuzzer
  # would take them in readdir order, which differs between filesystems, and
  # run equally long ones in that order.
  local seeds=("$here/corpus/$target/"* "$here/regressions/$target/"*)
  (IFS=,; printf "%s" "${seeds[*]}") >"$work/seeds-$target"
  local corpus="$work/corpus-$target" # what the run adds
  mkdir -p "$corpus"
  rm -f "$artifacts/crash-$target-"*
  # ASan's leak checker runs at exit, where VTK keeps singletons alive on
  # purpose; the harness replaces operator new (see fuzz_target.cpp), which
  # makes ASan's new/free pairing check meaningless.
  local start=$SECONDS
  if ASAN_OPTIONS=detect_leaks=0:alloc_dealloc_mismatch=0 ISOSCOPE_FUZZ_INPUT_DIR=/tmp/isoscope-fuzz-smoke-input/$target \
     "${fixed[@]}" "$exe" -seed=1 -runs="${runs[$target]}" -reload=0 -use_cmp=0 -use_memmem=0 -rss_limit_mb=2048 \
       -malloc_limit_mb=2048 -timeout=30 -print_final_stats=0 -artifact_prefix="$artifacts/crash-$target-" \
       -seed_inputs=@"$work/seeds-$target" "$corpus" >"$work/$target.log" 2>&1; then
    local stats
    stats=$(grep -aoE '#[0-9]+[[:space:]]+DONE[[:space:]]+cov: [0-9]+ ft: [0-9]+ corp: [0-9]+' "$work/$target.log" | tail -1 | tr -s ' \t' ' ')
    echo "fuzz_$target: ok (${#seeds[@]} seeds replayed, ${runs[$target]} runs: ${stats:-no statistics}; $((SECONDS - start)) s)" >"$work/$target.verdict"
    rm -f "$artifacts/crash-$target-"*
  else
    { echo "fuzz_$target: FAILED"; tail -n 40 "$work/$target.log"; } >"$work/$target.verdict"
  fi
}
# The targets are independent (each has its own input folder, corpus, log and
# artifact prefix; libFuzzer runs one thread), so as many run at once as there
# are processors: on 2 cores the smoke took 4.9 min one after another. Each
# target's inputs and verdict are the same either way; the verdicts are
# printed in the targets' order.
parallel=${ISOSCOPE_FUZZ_JOBS:-$(nproc)}
for target in "${targets[@]}"; do
  while (($(jobs -rp | wc -l) >= parallel)); do wait -n || true; done
  run_target "$target" &
done
wait
# A target passed when its verdict says so (its job's exit status may have
# been taken by `wait -n` above, so the verdict file is the record).
failed=()
for target in "${targets[@]}"; do
  if [[ -f $work/$target.verdict ]]; then cat "$work/$target.verdict"; else echo "fuzz_$target: FAILED (no verdict)"; fi
  grep -q "^fuzz_$target: ok " "$work/$target.verdict" 2>/dev/null || failed+=("$target")
done
if ((${#failed[@]})); then
  echo "fuzz smoke: findings in ${failed[*]} (inputs saved under $artifacts/)"
  exit 1
fi
echo "fuzz smoke: all ${#targets[@]} targets ran clean"
