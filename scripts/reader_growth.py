#!/usr/bin/env python3
"""Time and peak memory of `posecoach inspect` against the size of a keypoint file.

Generates, in a temporary folder, a swaying T-pose (the 17 joints of
tests/fixtures/h36m17_tpose.csv, at 360 Hz so that even the largest file is within the motion
limits) as:

- csv:   a keypoint CSV, `time,pelvis_x,...`;
- json:  a JSON array of frames, `{"time": t, "keypoints": {"pelvis": {"x", "y", "z",
         "visibility"}, ...}}`;
- jsonl: JSON Lines, one frame a line, the landmarks as the frame's keys (`"pelvis": [x, y, z]`);

each of 1, 2, 4, ... 64 MB (--sizes), and two wide files: a CSV header of 100 000 columns (the
17 joints and 33 316 landmarks no vocabulary knows, three rows) and a JSON of 50 000 landmark
names (three frames). Each file goes through `posecoach inspect --json` once; the table gives the
wall time, the peak resident memory (GNU time's %M: getrusage of its child, which a process
forked from Python would overstate by the interpreter's own resident memory), the ratio of
peak to file size, and the ratio of the peak over the floor to file size. A run past --timeout
is killed and shown as `>T`; runs are capped at --cap GiB of address space. `floor` is the
process's own peak on the one-row T-pose fixture.

Usage: scripts/reader_growth.py [--bin target/release/posecoach] [--sizes 1,2,4,8,16,32,64]
                                [--timeout 300] [--cap 8] [--only csv,json,...] [--json]
Needs /usr/bin/time (GNU time).
"""
import argparse
import json
import math
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TPOSE = os.path.join(ROOT, "tests", "fixtures", "h36m17_tpose.csv")
RATE_HZ = 360
MB = 1 << 20
WIDE_COLUMNS, WIDE_NAMES = 100_000, 50_000
TIME = shutil.which("time", path="/usr/bin")


def tpose():
    """The T-pose's joints: [(name, (x, y, z))]."""
    with open(TPOSE) as f:
        header, row = f.read().split("\n")[:2]
    names, values = header.split(",")[1:], [float(v) for v in row.split(",")[1:]]
    return [(names[i][:-2], tuple(values[i:i + 3])) for i in range(0, len(names), 3)]


def pose(joints, f):
    """Frame f: the T-pose swaying 5 cm left and right every 2 s."""
    dx = 0.05 * math.sin(2 * math.pi * f / (2 * RATE_HZ))
    return [(name, (x + dx, y, z)) for name, (x, y, z) in joints]


def xyz(p):
    return ", ".join(f"{v:.5f}" for v in p)


def csv_frames(joints, frame):
    yield "time," + ",".join(f"{n}_{a}" for n, _ in joints for a in "xyz") + "\n"
    for f in frame():
        yield f"{f / RATE_HZ:.6f}," + ",".join(f"{v:.5f}" for _, p in pose(joints, f) for v in p) + "\n"


def json_frames(joints, frame):
    yield "["
    for f in frame():
        points = ", ".join(f'"{n}": {{"x": {p[0]:.5f}, "y": {p[1]:.5f}, "z": {p[2]:.5f}, "visibility": 0.9}}'
                           for n, p in pose(joints, f))
        yield ("" if f == 0 else ",\n") + f'{{"time": {f / RATE_HZ:.6f}, "keypoints": {{{points}}}}}'
    yield "]\n"


def jsonl_frames(joints, frame):
    for f in frame():
        points = ", ".join(f'"{n}": [{xyz(p)}]' for n, p in pose(joints, f))
        yield f'{{"time": {f / RATE_HZ:.6f}, {points}}}\n'


SHAPES = {"csv": (".csv", csv_frames), "json": (".json", json_frames), "jsonl": (".jsonl", jsonl_frames)}


def write_sized(path, shape, size):
    """Writes frames of `shape` until the file holds at least `size` bytes, then closes it."""
    written = [0]

    def frames():
        f = 0
        while written[0] < size:
            yield f
            f += 1

    with open(path, "w") as out:
        for chunk in shape(tpose(), frames):
            out.write(chunk)
            written[0] += len(chunk)


def write_wide_csv(path):
    joints = tpose()
    extra = (WIDE_COLUMNS - 1 - 3 * len(joints)) // 3
    names = [n for n, _ in joints] + [f"extra{k}" for k in range(extra)]
    with open(path, "w") as out:
        out.write("time," + ",".join(f"{n}_{a}" for n in names for a in "xyz") + "\n")
        for f in range(3):
            cells = [f"{v:.5f}" for _, p in pose(joints, f) for v in p] + ["0"] * (3 * extra)
            out.write(f"{f / 60:.6f}," + ",".join(cells) + "\n")


def write_wide_json(path):
    joints = tpose()
    extra = WIDE_NAMES - len(joints)
    with open(path, "w") as out:
        frames = []
        for f in range(3):
            points = [f'"{n}": [{xyz(p)}]' for n, p in pose(joints, f)]
            points += [f'"extra{k}": [0, 0, 0]' for k in range(extra)]
            frames.append(f'{{"time": {f / 60:.6f}, "landmarks": {{{", ".join(points)}}}}}')
        out.write("[" + ",\n".join(frames) + "]\n")


def measure(binary, path, timeout, cap_gib):
    """Runs `inspect --json` on path; returns (seconds or None past the timeout, peak KiB, exit status)."""
    def limit():
        cap = cap_gib << 30
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))

    with tempfile.NamedTemporaryFile("r") as peak:
        start = time.monotonic()
        p = subprocess.Popen([TIME, "-f", "%M", "-o", peak.name, binary, "inspect", "--json", path],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, preexec_fn=limit,
                             start_new_session=True)
        try:
            rc = p.wait(timeout=timeout)
            seconds = time.monotonic() - start
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
            rc, seconds = None, None
        words = peak.read().split()
        return seconds, int(words[-1]) if words and words[-1].isdigit() else None, rc


def cases(sizes):
    for kind in SHAPES:
        for mb in sizes:
            yield kind, f"{mb} MB", lambda path, k=kind, s=mb * MB: write_sized(path, SHAPES[k][1], s), SHAPES[kind][0]
    yield "csv-wide", f"{WIDE_COLUMNS} columns", write_wide_csv, ".csv"
    yield "json-names", f"{WIDE_NAMES} names", write_wide_json, ".json"


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--bin", default=os.path.join(ROOT, "target/release/posecoach"))
    p.add_argument("--sizes", default="1,2,4,8,16,32,64", help="MB, comma-separated")
    p.add_argument("--timeout", type=float, default=300.0, help="seconds per run; past it the run is killed")
    p.add_argument("--cap", type=int, default=8, help="GiB of address space per run")
    p.add_argument("--only", help="kinds to run, comma-separated (csv, json, jsonl, csv-wide, json-names)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args()
    if not os.access(args.bin, os.X_OK):
        sys.exit(f"no {args.bin}: build it with `cargo build --release -p posecoach-cli`")
    if not TIME:
        sys.exit("no /usr/bin/time: install GNU time")
    sizes = [int(s) for s in args.sizes.split(",")]
    only = set(args.only.split(",")) if args.only else None
    _, floor_kib, _ = measure(args.bin, TPOSE, args.timeout, args.cap)
    rows = []
    with tempfile.TemporaryDirectory(prefix="reader-growth-") as work:
        for kind, label, write, ext in cases(sizes):
            if only and kind not in only:
                continue
            path = os.path.join(work, "input" + ext)
            write(path)
            size = os.path.getsize(path)
            seconds, peak_kib, rc = measure(args.bin, path, args.timeout, args.cap)
            os.remove(path)
            over = None if peak_kib is None else round((peak_kib - floor_kib) * 1024 / size, 2)
            rows.append({"kind": kind, "input": label, "bytes": size, "seconds": seconds and round(seconds, 3),
                         "peak_kib": peak_kib, "peak_per_byte": peak_kib and round(peak_kib * 1024 / size, 2),
                         "over_floor_per_byte": over, "exit": rc})
            if not args.json:
                t = f"{seconds:8.2f}" if seconds is not None else f"{'>' + str(int(args.timeout)):>8}"
                peak = f"{peak_kib / 1024:9.1f} MB {peak_kib * 1024 / size:6.2f} x {over:6.2f} x" if peak_kib else "?"
                print(f"{kind:10} {label:16} {size / MB:8.2f} MB {t} s {peak}  exit {rc}", flush=True)
    if args.json:
        print(json.dumps({"bin": args.bin, "timeout_s": args.timeout, "floor_kib": floor_kib, "rows": rows}, indent=1))
    else:
        print(f"floor (the one-row T-pose fixture): {floor_kib / 1024:.1f} MB")


if __name__ == "__main__":
    main()
