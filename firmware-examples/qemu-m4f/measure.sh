#!/usr/bin/env bash
# Builds the firmware, runs it under QEMU (it exits non-zero unless every reply equals the
# host's), and prints what the device pipeline costs: flash and static RAM from the ELF's
# sections, the stack's high-water mark, and instructions per stage. Then the same with the
# int8 network (`--features network`): its kernels, a window, and what it changes. The figures
# are a report, not a test: only the firmware's own checks decide the exit status.
# Usage: firmware-examples/qemu-m4f/measure.sh   (needs qemu-system-arm, defmt-print, size)
set -euo pipefail
cd "$(dirname "$0")"
elf=target/thumbv7em-none-eabihf/release/posecoach-qemu-m4f
out=$(mktemp)
net=$(mktemp)
trap 'rm -f "$out" "$net"' EXIT

section() { size -A "$elf" | awk -v s="$1" '$1 == s { print $2 }' | grep . || echo 0; }
field() { grep -m1 "^$2 " "$1" | sed -E "s/.* $3 ([0-9]+).*/\1/"; }
kib() { awk -v b="$1" 'BEGIN { printf "%.1f KiB", b / 1024 }'; }
minstr() { awk -v n="$1" 'BEGIN { printf "%.3f M", n / 1e6 }'; }
# Flash without the test's embedded logs, transcripts and test vectors, and static RAM, of the
# ELF just built whose output is in $1.
flash_of() {
    local code=$(( $(section .vector_table) + $(section .text) + $(section .rodata) + $(section .data) ))
    echo $((code - $(field "$1" EMBEDDED log) - $(field "$1" EMBEDDED transcript) - $(field "$1" EMBEDDED vectors) - $(field "$1" EMBEDDED hostile) - $(field "$1" EMBEDDED imu)))
}
static_of() { echo $(( $(section .data) + $(section .bss) + $(section .uninit) )); }

cargo build --release
./run.sh "$elf" | tee "$out"
flash=$(flash_of "$out")
static_ram=$(static_of)
cargo build --release --features network
./run.sh "$elf" | tee "$net"
net_flash=$(flash_of "$net")
net_ram=$(( $(static_of) + $(field "$net" RAM stack) ))

# Each figure against its target (docs/DEVICE.md): "met" or "MISS" in the last column; a
# figure with no target says "-".
verdict() { awk -v v="$1" -v t="$2" 'BEGIN { print (v + 0 <= t + 0) ? "met" : "MISS" }'; }
row() { # what, target text, measured text, measured value, target value (empty: none)
    if [ -n "${5:-}" ]; then echo "| $1 | $2 | $3 | $(verdict "$4" "$5") |"; else echo "| $1 | - | $3 | - |"; fi
}
iron=$(stat -c %s ../../coaches/iron.pcr)
stack=$(field "$out" RAM stack)
ram=$((static_ram + stack))
per_mac() { grep "^KERNEL int8 $1:" "$net" | sed -E 's/.*: ([0-9.]+) instructions per MAC/\1/'; }
per_cell=$(grep '^KERNEL DTW cell' "$out" | sed -E 's/.*: ([0-9.]+) instructions per cell/\1/')
window=$(grep '^NETWORK window' "$net" | sed -E 's/NETWORK window ([0-9]+).*/\1/')
stage() { field "$out" "STAGE $1" "$2"; }
hostile_stack=$(grep "^STACK hostile recording" "$out" | sed -E "s/.* ([0-9]+)$/\1/")
echo
echo "The product: the analytic retargeter and golf's contacts make the virtual coach."
echo
echo "| what | target | measured | |"
echo "| --- | --- | --- | --- |"
row "flash: code, constants, both coach references (without the test's logs, transcripts and test vectors)" "256 KiB" "$(kib "$flash")" "$flash" $((256 * 1024))
row "flash with one coach reference (without \`iron.pcr\`)" "" "$(kib $((flash - iron)))"
row "RAM: static (.data + .bss) and the stack's high-water mark" "64 KiB" "$(kib "$ram")" "$ram" $((64 * 1024))
row "of which static RAM" "" "$(kib "$static_ram")"
for b in ring coach floats bytes unsure; do
    row "of which session buffer \`$b\`" "" "$(kib "$(field "$out" RAM "$b")")"
done
row "of which the stack's high-water mark" "" "$(kib "$stack")"
for s in decode frame swing setup; do
    row "stack reached by a message: $s (the harness's frames included: $(kib "$(field "$out" BASE stack)"), the session's $(kib "$(field "$out" BASE session)") among them)" "" "$(kib "$(stage "$s" stack)")"
done
row "banded DTW with the path, a real 55-frame swing of 17 joints, radius 10, instructions per cell" "120" "$per_cell" "$per_cell" 120
row "decode one message (mean, $(stage decode calls) messages)" "" "$(minstr "$(stage decode mean)")"
row "one pose frame: stream, skeleton fit, detector (mean / max)" "" "$(minstr "$(stage frame mean)") / $(minstr "$(stage frame max)")"
row "the frame that ends a swing: events, DTW, report (mean of $(stage swing calls)); the budget counts a swing's report with its session update, 50 ms at 64 MHz" "3.2 M" "$(minstr "$(stage swing mean)")" "$(stage swing mean)" 3200000
row "a set-up (profile, settings or coach selection): coach retargeted, its contacts, its swing found (mean / max)" "" "$(minstr "$(stage setup mean)") / $(minstr "$(stage setup max)")"
row "hostile recording ($(field "$out" 'HOSTILE decode' calls) messages): costliest pose frame / IMU sample / set-up" "" "$(minstr "$(field "$out" 'HOSTILE frame' max)") / $(minstr "$(field "$out" 'HOSTILE imu' max)") / $(minstr "$(field "$out" 'HOSTILE setup' max)")"
row "costliest message of either recording" "$(minstr "$(field "$out" BUDGET budget)")" "$(minstr "$(field "$out" BUDGET message)")" "$(field "$out" BUDGET message)" "$(field "$out" BUDGET budget)"
row "stack high-water mark of the hostile recording" "" "$(kib "$hostile_stack")"
imu() { field "$out" "IMU $1" "$2"; }
row "wearing six IMUs at 200 Hz (\`imu_device_200hz\`, a 30 Hz model rate): instructions a second of the stream, every sample that does not end a swing (decoding, fusion, posing at the model rate, detection): the battery's load" "640 k (1 % of 64 MHz)" "$(minstr "$(field "$out" BATTERY "imu per_second")")" "$(field "$out" BATTERY "imu per_second")" 640000
row "of which decoding a sample (mean of $(imu decode calls) messages)" "" "$(minstr "$(imu decode mean)")"
row "of which an IMU sample: fusion, and posing and detecting the frames it completes (mean / max)" "" "$(minstr "$(imu imu mean)") / $(minstr "$(imu imu max)")"
row "the IMU sample that ends a swing (events, DTW, report, session)" "3.2 M" "$(minstr "$(imu swing mean)")" "$(imu swing mean)" 3200000
row "a phone's pose stream at 30 Hz (\`device_h36m_30hz\`): instructions a second, every frame that does not end a swing, decoding included" "" "$(minstr "$(field "$out" BATTERY "pose per_second")")"
echo
echo "With the int8 network (\`--features network\`) in the analytic retargeter's place."
echo
echo "| what | target | measured | |"
echo "| --- | --- | --- | --- |"
row "flash, int8 weights included" "256 KiB" "$(kib "$net_flash")" "$net_flash" $((256 * 1024))
row "of which int8 weights" "" "$(kib "$(field "$net" EMBEDDED weights)")"
row "RAM: static and the stack's high-water mark" "64 KiB" "$(kib "$net_ram")" "$net_ram" $((64 * 1024))
row "int8 linear layer: decoder.features, 16 x 16, requantization included, instructions per MAC" "2.5" "$(per_mac linear)" "$(per_mac linear)" 2.5
row "int8 grouped convolution: up_2, 96 channels in 6 groups, kernel 3, 64 frames, instructions per MAC" "2.5" "$(per_mac conv1d)" "$(per_mac conv1d)" 2.5
row "retarget one 64-frame coach window (int8 network, 22 joints onto 17)" "6 M" "$(minstr "$window")" "$window" 6000000
row "a set-up with the network (mean / max)" "" "$(minstr "$(field "$net" 'STAGE setup' mean)") / $(minstr "$(field "$net" 'STAGE setup' max)")"
row "the frame that ends a swing (mean of $(field "$net" 'STAGE swing' calls))" "3.2 M" "$(minstr "$(field "$net" 'STAGE swing' mean)")" "$(field "$net" 'STAGE swing' mean)" 3200000
row "costliest message of either recording" "$(minstr "$(field "$net" BUDGET budget)")" "$(minstr "$(field "$net" BUDGET message)")" "$(field "$net" BUDGET message)" "$(field "$net" BUDGET budget)"
