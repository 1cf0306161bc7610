#!/usr/bin/env bash
# Runs every fuzz target for a while from its committed corpus (fuzz/corpus/TARGET), then
# minimizes the corpus (cargo fuzz cmin), so that a longer run leaves what it found for the next
# one; commit the corpus after a long run. Inputs are bounded per target (MAX_LEN below), so the
# corpus stays small enough to keep in the repository; docs/HOSTILE.md says where its first
# inputs came from and records the long runs.
# Usage: fuzz/run.sh [SECONDS_PER_TARGET [TARGET...]]   (default 30 s, every target).
# Needs nightly and cargo-fuzz. Prints, per target, libFuzzer's count of runs and the corpus.
set -euo pipefail
cd "$(dirname "$0")"
seconds="${1:-30}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(bvh c3d csv json wire log session reference weights teachfile)

# The longest input of each target, in bytes: room for a small file of its kind and its
# mutations. A recording needs 48 KiB for a pose session's set-up and first swing; the int8
# weights are one fixed 35 KB architecture; the session target builds its messages from a few
# bytes each.
max_len() {
    case "$1" in
        log) echo 49152 ;;
        weights) echo 36864 ;;
        wire | session) echo 4096 ;;
        *) echo 8192 ;;
    esac
}

mkdir -p logs
for target in "${targets[@]}"; do
    corpus="corpus/$target"
    log="logs/$target.txt"
    limit="-max_len=$(max_len "$target")"
    mkdir -p "$corpus"
    if ! cargo +nightly fuzz run "$target" "$corpus" -- -max_total_time="$seconds" -rss_limit_mb=2048 "$limit" >"$log" 2>&1; then
        tail -40 "$log" >&2
        echo "fuzz $target failed: see fuzz/$log and fuzz/artifacts/$target" >&2
        exit 1
    fi
    cargo +nightly fuzz cmin "$target" "$corpus" -- "$limit" >"logs/$target.cmin.txt" 2>&1
    echo "fuzz $target: $(grep -E '^Done [0-9]+ runs' "$log" || echo 'ran') (${seconds} s); corpus $(ls "$corpus" | wc -l) inputs, $(du -sk "$corpus" | cut -f1) KiB"
done
