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
echo
echo "| what | measured |"
echo "| --- | --- |"
echo "| flash: code, constants, int8 weights, both coach references (without the test's logs, transcripts and golden vectors) | $(kib $((code - log - transcript - golden - hostile))) |"
echo "| of which int8 weights | $(kib "$weights") |"
iron=$(stat -c %s ../../coaches/iron.pcr)
echo "| flash with one coach reference (the budget's measure: without \`iron.pcr\`) | $(kib $((code - log - transcript - golden - hostile - iron))) |"
echo "| static RAM (.data + .bss) | $(kib "$static_ram") |"
for b in ring coach floats bytes unsure; do
    echo "| of which session buffer \`$b\` | $(kib "$(field RAM "$b")") |"
done
echo "| stack high-water mark | $(kib "$stack") |"
per_mac() { grep "^KERNEL int8 $1:" "$out" | sed -E 's/.*: ([0-9.]+) instructions per MAC/\1/'; }
echo "| int8 linear layer: decoder.features, 16 x 16, requantization included | $(per_mac linear) instructions per MAC |"
echo "| int8 grouped convolution: up_2, 96 channels in 6 groups, kernel 3, 64 frames | $(per_mac conv1d) instructions per MAC |"
echo "| retarget one 64-frame coach window (int8 network, 22 joints onto 17) | $(minstr "$(grep '^NETWORK window' "$out" | sed -E 's/NETWORK window ([0-9]+).*/\1/')") |"
echo "| decode one message (mean, $(field 'STAGE decode' calls) messages) | $(minstr "$(field 'STAGE decode' mean)") |"
echo "| one pose frame: stream, skeleton fit, detector (mean / max) | $(minstr "$(field 'STAGE frame' mean)") / $(minstr "$(field 'STAGE frame' max)") |"
echo "| the frame that ends a swing: events, DTW, report (mean of $(field 'STAGE swing' calls)) | $(minstr "$(field 'STAGE swing' mean)") |"
echo "| a set-up (profile, settings or coach selection): coach retargeted (int8 network), its swing found (mean / max) | $(minstr "$(field 'STAGE setup' mean)") / $(minstr "$(field 'STAGE setup' max)") |"
hostile_stack=$(grep '^STACK after the hostile recording' "$out" | sed -E 's/.* ([0-9]+)$/\1/')
echo "| hostile recording ($(field 'HOSTILE decode' calls) messages): costliest pose frame / IMU sample / set-up | $(minstr "$(field 'HOSTILE frame' max)") / $(minstr "$(field 'HOSTILE imu' max)") / $(minstr "$(field 'HOSTILE setup' max)") |"
echo "| costliest message of either recording, against the budget | $(minstr "$(field BUDGET message)") of $(minstr "$(field BUDGET budget)") |"
echo "| stack high-water mark after the hostile recording | $(kib "$hostile_stack") |"
