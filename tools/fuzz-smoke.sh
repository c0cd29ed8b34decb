#!/usr/bin/env bash
# CI's fuzz smoke step: builds every cargo-fuzz target and runs each for a short, fixed budget,
# seeded from its committed corpus:
#
#   tools/fuzz-smoke.sh [SECONDS_PER_TARGET]   (default 12)
#
# A crash, a panic outside the decoders whose panics the readers catch, a timeout (> 10 s for
# one input) or a process past 2 GiB fails the step and prints the input as hex. The committed
# corpora are read, never written (what a run finds goes to a temporary folder).
#
# The build is cargo-fuzz's own (the same libFuzzer, the same coverage instrumentation:
# FUZZ_FLAGS below are what `cargo fuzz build --sanitizer none` passes to rustc) made by plain
# cargo, so it needs neither cargo-fuzz nor nightly: with no sanitizer, none of those flags is
# unstable, and a fresh CI machine has only the stable toolchain. It uses the fuzz workspace's
# `smoke` profile (opt-level 1, no debug info: 400 CPU-s to build from nothing instead of 574 s,
# and as many executions a second as the release build here), with debug assertions and
# overflow checks, in a target folder of its own ($FUZZ_TARGET_DIR, default
# ~/.cache/aperture/fuzz-smoke). Panics and overflows are what the smoke run looks for; the
# longer campaign with AddressSanitizer is tools/fuzz.sh (nightly and cargo-fuzz).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-12}
targets=(load exr env texture draco meshopt)
target_dir=${FUZZ_TARGET_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/aperture/fuzz-smoke}
host=$(rustc -vV | sed -n 's/^host: //p')
FUZZ_FLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4
 -Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table
 -Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing
 -Cllvm-args=-simplifycfg-branch-fold-threshold=0 -Cllvm-args=-sanitizer-coverage-stack-depth
 -Cdebug-assertions"

build_start=$(date +%s)
# --target keeps the flags off build scripts and proc macros, as cargo-fuzz does.
(cd fuzz && RUSTFLAGS=$(echo $FUZZ_FLAGS) cargo build --quiet --profile smoke --target "$host" \
    --target-dir "$target_dir")
echo "fuzz smoke: built ${#targets[@]} targets in $(($(date +%s) - build_start)) s"
bin_dir=$target_dir/$host/smoke

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failed=()
for t in "${targets[@]}"; do
    mkdir -p "$work/$t/corpus" "$work/$t/artifacts"
    log=$work/$t/log
    status=0
    "$bin_dir/$t" "$work/$t/corpus" "fuzz/corpus/$t" -max_total_time="$seconds" \
        -timeout=10 -rss_limit_mb=2048 -max_len=16384 -print_final_stats=1 \
        -artifact_prefix="$work/$t/artifacts/" >"$log" 2>&1 || status=$?
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    if [[ $status -eq 0 ]]; then
        echo "fuzz smoke: $t: ${runs:-?} executions in ${seconds} s, no crash"
        continue
    fi
    failed+=("$t")
    echo "fuzz smoke: $t FAILED (exit $status) after ${runs:-?} executions; the log's end:"
    grep -v '^#[0-9]' "$log" | tail -40
    for input in "$work/$t/artifacts"/*; do
        [[ -f $input ]] || continue
        echo "fuzz smoke: $t: input $(basename "$input") ($(wc -c <"$input") bytes), hex:"
        od -An -v -tx1 "$input" | tr -s ' ' | sed 's/^ //'
    done
done
if [[ ${#failed[@]} -gt 0 ]]; then
    echo "fuzz smoke: crashes in: ${failed[*]} (make each a regression test, then fix it)" >&2
    exit 1
fi
echo "fuzz smoke: ${#targets[@]} targets, ${seconds} s each, no crash"
