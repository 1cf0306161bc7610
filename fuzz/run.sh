#!/usr/bin/env bash
# Runs every fuzz target for a while, seeded with the committed fixtures.
# Usage: fuzz/run.sh [SECONDS_PER_TARGET]   (default 30). Needs nightly and cargo-fuzz.
set -euo pipefail
cd "$(dirname "$0")"
seconds="${1:-30}"
mkdir -p logs
# Seeds: the committed fixtures of each format; for the wire decoder, the pinned message stream;
# for the log reader and session, the committed recordings; for references, the bundled coaches;
# for weights, the committed int8 weights.
for target in bvh c3d csv wire log reference weights; do
    corpus="corpus/$target"
    mkdir -p "$corpus"
    case "$target" in
        wire) cp ../tests/fixtures/wire_messages.bin "$corpus/" ;;
        log) cp ../tests/logs/*.pclog "$corpus/" ;;
        reference) cp ../coaches/*.pcr "$corpus/" ;;
        weights) cp ../weights/distilled-int8.pcw "$corpus/" ;;
        *) find ../tests/fixtures -name "*.$target" -exec cp {} "$corpus/" \; ;;
    esac
    log="logs/$target.txt"
    # Whole recordings take milliseconds each; 48 KiB holds a pose session's set-up and first swing.
    limit=""
    [ "$target" = log ] && limit="-max_len=49152"
    if ! cargo +nightly fuzz run "$target" "$corpus" -- -max_total_time="$seconds" -rss_limit_mb=2048 $limit >"$log" 2>&1; then
        tail -40 "$log" >&2
        echo "fuzz $target failed: see fuzz/$log and fuzz/artifacts/$target" >&2
        exit 1
    fi
    echo "fuzz $target: $(grep -E '^Done [0-9]+ runs' "$log" || echo 'ran') in ${seconds}s"
done
