#!/usr/bin/env bash
# Makes the recorded sessions in this folder and their expected swings. The golden replay
# reports beside them are rewritten by `POSECOACH_BLESS=1 cargo test -p posecoach-tests --test replay`.
#
# The committed sessions were made by an earlier synth-log, whose noise draws have since
# changed, and re-framed for wire versions 2, 3 and 4 (every message kept byte for byte, the
# version byte and CRC rewritten, by scripts/reframe.py since version 4; for version 2 the short
# session's CoachSelect dropped, so its swings get the coaches of their clubs). This script
# makes sessions of the same description with other draws: on some draws of the short session
# the driver's backswing comes out 8 to 10 % short (docs/COACHING.md, "What misses and why").
set -euo pipefail
cd "$(dirname "$0")/../.."
pc() { cargo run -q --release -p posecoach-cli -- "$@"; }
fx=tests/fixtures
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# A 1.75 m golfer (H3.6M keypoints at 30 Hz, 7 mm noise, 4 ms jitter, 3 % lost): walks up,
# waggles, hits the driver, a practice half swing, walks, the iron.
pc synth-log --swing $fx/golf_driver_60hz.csv --swing $fx/golf_iron_60hz.csv \
    --walk $fx/bandai_walk_excerpt.bvh --coach 0 --seed 1 --out tests/logs/range_h36m_30hz.pclog

# The same golfer and swings with the device's own model rate, 30 Hz (the network's rate): the
# session the QEMU firmware replays.
pc synth-log --swing $fx/golf_driver_60hz.csv --swing $fx/golf_iron_60hz.csv \
    --walk $fx/bandai_walk_excerpt.bvh --model-rate 30 --coach 0 --seed 1 \
    --out tests/logs/device_h36m_30hz.pclog

# A 1.60 m amateur (CMU-31 keypoints at 30 Hz, 10 mm noise, 6 ms jitter, 5 % lost) whose
# backswings take 1.5 times as long as the tour player's: the iron, then the driver; no coach
# selected.
pc tpose --format cmu31 --height 1.6 --out "$tmp/cmu_160.bvh"
pc synth-log --swing $fx/golf_iron_60hz.csv --swing $fx/golf_driver_60hz.csv \
    --student-tpose "$tmp/cmu_160.bvh" --format cmu31 --noise-mm 10 --jitter-ms 6 --drop 0.05 \
    --backswing-tempo 1.5 --seed 2 --out tests/logs/short_cmu_30hz.pclog

# The 1.75 m golfer with six IMUs (pelvis, chest, upper arms, wrists; magnetometers) at 200 Hz,
# 3 % of samples lost: a still T-pose to calibrate, then the driver and the iron.
pc synth-log --swing $fx/golf_driver_60hz.csv --swing $fx/golf_iron_60hz.csv --imu-rate 200 \
    --coach 0 --seed 4 --out tests/logs/imu_200hz.pclog

# The same golfer with the six IMUs at the device's own model rate, 30 Hz: a still T-pose, then
# the driver. The session the QEMU firmware replays to measure what wearing the sensors costs
# a second.
pc synth-log --swing $fx/golf_driver_60hz.csv --imu-rate 200 --model-rate 30 --coach 0 --seed 5 \
    --out tests/logs/imu_device_200hz.pclog

# The hostile session (hostile_h36m_30hz: the firmware's session with bursts of what a broken or
# hostile phone sends) is made from device_h36m_30hz.pclog by its test:
# POSECOACH_BLESS=1 cargo test -p posecoach-tests --test hostile
