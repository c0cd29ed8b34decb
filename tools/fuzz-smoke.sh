#!/usr/bin/env bash
# CI's fuzz smoke step: builds every cargo-fuzz target on nightly and runs each for a short,
# fixed budget, seeded from its committed corpus:
#
#   tools/fuzz-smoke.sh [SECONDS_PER_TARGET]   (default 20)
#
# A crash, a panic outside the decoders whose panics the readers catch, a timeout (> 10 s for
# one input) or a process past 2 GiB fails the step and prints the input as hex. The committed
# corpora are read, never written (what a run finds goes to a temporary folder).
#
# Fast enough for CI on a fresh clone (2 cores: under 6 minutes with the build): no sanitizer
# (`--sanitizer none`; panics and overflows are what the smoke run looks for, and a full
# AddressSanitizer build of the std library took 37 minutes), optimised, with debug assertions
# and overflow checks (cargo-fuzz's default without -O), in a target folder kept between runs
# ($FUZZ_TARGET_DIR, default ~/.cache/aperture/fuzz-target). The longer campaign with
# AddressSanitizer is tools/fuzz.sh.
#
# Needs rustup's nightly toolchain; installs cargo-fuzz if it is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-20}
targets=(load exr env texture draco meshopt)
target_dir=${FUZZ_TARGET_DIR:-$HOME/.cache/aperture/fuzz-target}

if ! cargo +nightly --version >/dev/null 2>&1; then
    echo "fuzz smoke: the nightly toolchain is missing (cargo-fuzz needs it):" >&2
    echo "  rustup toolchain install nightly --profile minimal" >&2
    exit 1
fi
if ! cargo +nightly fuzz --version >/dev/null 2>&1; then
    echo "fuzz smoke: installing cargo-fuzz"
    cargo install cargo-fuzz --locked
fi

build_start=$(date +%s)
(cd fuzz && cargo +nightly fuzz build --sanitizer none --target-dir "$target_dir")
echo "fuzz smoke: built ${#targets[@]} targets in $(($(date +%s) - build_start)) s"
bin_dir=$target_dir/$(rustc +nightly -vV | sed -n 's/^host: //p')/release

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
