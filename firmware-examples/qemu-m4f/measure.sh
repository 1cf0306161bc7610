#!/usr/bin/env bash
# Builds the firmware, runs it under QEMU (it exits non-zero unless every reply equals the
# host's), and prints what the device pipeline costs: flash and static RAM from the ELF's
# sections, the stack's high-water mark, and instructions per stage. The figures are a report,
# not a test: only the firmware's own check decides the exit status.
# Usage: firmware-examples/qemu-m4f/measure.sh   (needs qemu-system-arm, defmt-print, size)
set -euo pipefail
cd "$(dirname "$0")"
cargo build --release
elf=target/thumbv7em-none-eabihf/release/posecoach-qemu-m4f
out=$(mktemp)
trap 'rm -f "$out"' EXIT
./run.sh "$elf" | tee "$out"

section() { size -A "$elf" | awk -v s="$1" '$1 == s { print $2 }' | grep . || echo 0; }
field() { grep "^$1 " "$out" | sed -E "s/.* $2 ([0-9]+).*/\1/"; }
kib() { awk -v b="$1" 'BEGIN { printf "%.1f KiB", b / 1024 }'; }
minstr() { awk -v n="$1" 'BEGIN { printf "%.3f M", n / 1e6 }'; }

code=$(( $(section .vector_table) + $(section .text) + $(section .rodata) + $(section .data) ))
log=$(field EMBEDDED log)
transcript=$(field EMBEDDED transcript)
golden=$(field EMBEDDED golden)
weights=$(field EMBEDDED weights)
hostile=$(field EMBEDDED hostile)
static_ram=$(( $(section .data) + $(section .bss) + $(section .uninit) ))
stack=$(field RAM stack)
# Each figure against its target (docs/DEVICE.md): "met" or "MISS" in the last column; a
# figure with no target says "-".
verdict() { awk -v v="$1" -v t="$2" 'BEGIN { print (v + 0 <= t + 0) ? "met" : "MISS" }'; }
row() { # what, target text, measured text, measured value, target value (empty: none)
    if [ -n "${5:-}" ]; then echo "| $1 | $2 | $3 | $(verdict "$4" "$5") |"; else echo "| $1 | - | $3 | - |"; fi
}
flash=$((code - log - transcript - golden - hostile))
iron=$(stat -c %s ../../coaches/iron.pcr)
ram=$((static_ram + stack))
per_mac() { grep "^KERNEL int8 $1:" "$out" | sed -E 's/.*: ([0-9.]+) instructions per MAC/\1/'; }
per_cell=$(grep '^KERNEL DTW cell' "$out" | sed -E 's/.*: ([0-9.]+) instructions per cell/\1/')
window=$(grep '^NETWORK window' "$out" | sed -E 's/NETWORK window ([0-9]+).*/\1/')
stage_stack() { field "STAGE $1" stack; }
hostile_stack=$(grep "^STACK hostile recording" "$out" | sed -E "s/.* ([0-9]+)$/\1/")
echo
echo "| what | target | measured | |"
echo "| --- | --- | --- | --- |"
row "flash: code, constants, int8 weights, both coach references (without the test's logs, transcripts and golden vectors)" "256 KiB" "$(kib "$flash")" "$flash" $((256 * 1024))
row "of which int8 weights" "" "$(kib "$weights")"
row "flash with one coach reference (without \`iron.pcr\`)" "" "$(kib $((flash - iron)))"
row "RAM: static (.data + .bss) and the stack's high-water mark" "64 KiB" "$(kib "$ram")" "$ram" $((64 * 1024))
row "of which static RAM" "" "$(kib "$static_ram")"
for b in ring coach floats bytes unsure; do
    row "of which session buffer \`$b\`" "" "$(kib "$(field RAM "$b")")"
done
row "of which the stack's high-water mark" "" "$(kib "$stack")"
for s in decode frame swing setup; do
    row "stack reached by a message: $s (the harness's frames included: $(kib "$(field BASE stack)"), the session's $(kib "$(field BASE session)") among them)" "" "$(kib "$(stage_stack "$s")")"
done
row "int8 linear layer: decoder.features, 16 x 16, requantization included, instructions per MAC" "2.5" "$(per_mac linear)" "$(per_mac linear)" 2.5
row "int8 grouped convolution: up_2, 96 channels in 6 groups, kernel 3, 64 frames, instructions per MAC" "2.5" "$(per_mac conv1d)" "$(per_mac conv1d)" 2.5
row "banded DTW with the path, a real 55-frame swing of 17 joints, radius 10, instructions per cell" "120" "$per_cell" "$per_cell" 120
row "retarget one 64-frame coach window (int8 network, 22 joints onto 17)" "6 M" "$(minstr "$window")" "$window" 6000000
row "decode one message (mean, $(field 'STAGE decode' calls) messages)" "" "$(minstr "$(field 'STAGE decode' mean)")"
row "one pose frame: stream, skeleton fit, detector (mean / max)" "" "$(minstr "$(field 'STAGE frame' mean)") / $(minstr "$(field 'STAGE frame' max)")"
row "the frame that ends a swing: events, DTW, report (mean of $(field 'STAGE swing' calls))" "0.5 M" "$(minstr "$(field 'STAGE swing' mean)")" "$(field 'STAGE swing' mean)" 500000
row "a set-up (profile, settings or coach selection): coach retargeted (int8 network), its swing found (mean / max)" "" "$(minstr "$(field 'STAGE setup' mean)") / $(minstr "$(field 'STAGE setup' max)")"
row "hostile recording ($(field 'HOSTILE decode' calls) messages): costliest pose frame / IMU sample / set-up" "" "$(minstr "$(field 'HOSTILE frame' max)") / $(minstr "$(field 'HOSTILE imu' max)") / $(minstr "$(field 'HOSTILE setup' max)")"
row "costliest message of either recording" "$(minstr "$(field BUDGET budget)")" "$(minstr "$(field BUDGET message)")" "$(field BUDGET message)" "$(field BUDGET budget)"
row "stack high-water mark of the hostile recording" "" "$(kib "$hostile_stack")"
