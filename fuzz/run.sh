#!/usr/bin/env bash
# Runs every fuzz target for a while, from its corpus (fuzz/corpus/TARGET, kept between runs)
# and the committed fixtures, then minimizes the corpus (cargo fuzz cmin), so that a longer run
# leaves what it found for the next one. (A 20 s run leaves 23 MB, mostly mutated C3D files and
# recordings: the corpus is not committed until its inputs are bounded.)
# Usage: fuzz/run.sh [SECONDS_PER_TARGET]   (default 30). Needs nightly and cargo-fuzz.
set -euo pipefail
cd "$(dirname "$0")"
seconds="${1:-30}"
mkdir -p logs
# Seeds (read, never copied into the corpus): the committed fixtures of each format; for the
# wire decoder, the pinned message stream; for the log reader and session, the committed
# recordings; for references, the bundled coaches; for weights, the committed int8 weights;
# for the float weights (teachfile), the committed distilled network.
# The session target builds its messages from the bytes and needs no seed.
seeds="$(mktemp -d)"
trap 'rm -rf "$seeds"' EXIT
for target in bvh c3d csv wire log session reference weights teachfile; do
    corpus="corpus/$target"
    seed="$seeds/$target"
    mkdir -p "$corpus" "$seed"
    case "$target" in
        wire) cp ../tests/fixtures/wire_messages.bin "$seed/" ;;
        log) cp ../tests/logs/*.pclog "$seed/" ;;
        reference) cp ../coaches/*.pcr "$seed/" ;;
        weights) cp ../weights/distilled-int8.pcw "$seed/" ;;
        teachfile) cp ../weights/distilled.pcw "$seed/" ;;
        session) ;;
        *) find ../tests/fixtures -name "*.$target" -exec cp {} "$seed/" \; ;;
    esac
    log="logs/$target.txt"
    # Whole recordings take milliseconds each; 48 KiB holds a pose session's set-up and first swing.
    limit=""
    [ "$target" = log ] && limit="-max_len=49152"
    if ! cargo +nightly fuzz run "$target" "$corpus" "$seed" -- -max_total_time="$seconds" -rss_limit_mb=2048 $limit >"$log" 2>&1; then
        tail -40 "$log" >&2
        echo "fuzz $target failed: see fuzz/$log and fuzz/artifacts/$target" >&2
        exit 1
    fi
    cargo +nightly fuzz cmin "$target" "$corpus" -- $limit >"logs/$target.cmin.txt" 2>&1
    echo "fuzz $target: $(grep -E '^Done [0-9]+ runs' "$log" || echo 'ran') in ${seconds}s; corpus $(ls "$corpus" | wc -l) inputs"
done
