#!/usr/bin/env bash
# Runs one cargo-fuzz (libFuzzer) target at low priority:
#
#   tools/fuzz.sh TARGET SECONDS [--minimise]
#
# TARGET is one of: load exr env texture draco meshopt (fuzz/fuzz_targets/). The run stops
# after SECONDS or FUZZ_RUNS executions (default 1000000), whichever comes first. The committed,
# minimised corpus fuzz/corpus/TARGET seeds the run; what the run finds grows in
# fuzz/corpus-run/TARGET (not committed). A crash, a timeout (> 2 s for one input) or an
# allocation past libFuzzer's limits (one malloc over 96 MiB, above the targets' 64 MiB
# budget; RSS 2 GiB, AddressSanitizer's own memory included) stops the
# run with its input in fuzz/artifacts/TARGET/: make it a regression test in the crate's tests,
# then fix it. --minimise then merges the run's corpus into fuzz/corpus/TARGET (libFuzzer's
# -set_cover_merge=1 keeps a smallest set of inputs with the same coverage; inputs above
# 16 KiB are left out; the seed-* files stay).
#
# Needs the nightly toolchain and cargo-fuzz (`cargo install cargo-fuzz`). tools/fuzz-smoke.sh
# runs every target for 20 s; CI replays the committed corpus on stable
# (fuzz/harness/tests/corpus_replay.rs); run this before a change to a decoder lands.
set -euo pipefail
cd "$(dirname "$0")/.."

if [[ $# -lt 2 ]]; then
    sed -n 2,19p "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
target=$1
seconds=$2
minimise=${3:-}
case $target in
load | exr | env | texture | draco | meshopt) ;;
*)
    echo "unknown target $target (load exr env texture draco meshopt)" >&2
    exit 2
    ;;
esac

run_dir=fuzz/corpus-run/$target
mkdir -p "$run_dir" "fuzz/artifacts/$target"
cd fuzz
if [[ $seconds -gt 0 ]]; then
    # -timeout: an input taking over 2 s is a finding; -malloc_limit_mb: one allocation past
    # the budget (fuzz/harness MEMORY_BUDGET, 64 MiB) is one too, as is a process past 2 GiB.
    nice -n 19 cargo +nightly fuzz run "$target" "corpus-run/$target" "corpus/$target" -- \
        -max_total_time="$seconds" -runs="${FUZZ_RUNS:-1000000}" -timeout=2 -rss_limit_mb=2048 -malloc_limit_mb=96 \
        -max_len=16384 -print_final_stats=1 -artifact_prefix="artifacts/$target/"
fi
if [[ $minimise == --minimise ]]; then
    merged=$(mktemp -d)
    nice -n 19 cargo +nightly fuzz run "$target" "$merged" "corpus/$target" "corpus-run/$target" -- \
        -set_cover_merge=1 -max_len=16384 -timeout=2 -rss_limit_mb=2048
    find "corpus/$target" -name 'seed-*' -exec cp {} "$merged/" \;
    rm -rf "corpus/$target"
    mkdir -p "corpus/$target"
    find "$merged" -type f -size -16k -exec cp {} "corpus/$target/" \;
    rm -rf "$merged"
    echo "corpus/$target: $(ls "corpus/$target" | wc -l) files, $(du -sh "corpus/$target" | cut -f1)"
fi
