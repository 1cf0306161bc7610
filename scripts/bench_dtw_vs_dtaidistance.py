#!/usr/bin/env python3
"""Banded DTW with the path: posecoach against dtaidistance's C implementation, same data, same run.

Usage: scripts/bench_dtw_vs_dtaidistance.py [--n 200] [--dims 51] [--band 20] [--seconds 2]
Needs `pip install dtaidistance numpy` and builds `posecoach` in release mode.
posecoach writes its random-walk sequences (little-endian f64); dtaidistance aligns the same
arrays with `dtw_ndim.warping_path(a, b, use_c=True, window=R+1, include_distance=True)`.
The band is the same: |i - j| <= R. Costs differ: posecoach takes the mean of per-joint
Euclidean distances (17 square roots per cell at D = 51), dtaidistance the squared Euclidean
distance over all D values; both are O(D) per cell.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from dtaidistance import dtw_ndim


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=200)
    p.add_argument("--dims", type=int, default=51)
    p.add_argument("--band", type=int, default=20)
    p.add_argument("--seconds", type=float, default=2.0)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args()

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "posecoach-cli"], cwd=root, check=True)
    exe = os.path.join(root, "target", "release", "posecoach")
    with tempfile.TemporaryDirectory() as tmp:
        data = os.path.join(tmp, "walk.f64")
        ours = json.loads(subprocess.run(
            [exe, "bench", "dtw", "--n", str(args.n), "--dims", str(args.dims), "--band", str(args.band),
             "--seconds", str(args.seconds), "--data-out", data, "--json"],
            check=True, capture_output=True, text=True).stdout)
        values = np.fromfile(data, dtype="<f8").reshape(2, args.n, args.dims)
    a, b = np.ascontiguousarray(values[0]), np.ascontiguousarray(values[1])

    dtw_ndim.warping_path(a, b, use_c=True, window=args.band + 1, include_distance=True)
    calls, start = 0, time.perf_counter()
    while time.perf_counter() - start < args.seconds or calls < 10:
        path, distance = dtw_ndim.warping_path(a, b, use_c=True, window=args.band + 1, include_distance=True)
        calls += 1
    theirs_us = (time.perf_counter() - start) / calls * 1e6

    report = {
        "n": args.n, "dims": args.dims, "band": args.band, "cells": ours["cells"],
        "posecoach_us_per_call": ours["us_per_call"], "posecoach_ns_per_cell": ours["ns_per_cell"],
        "dtaidistance_us_per_call": theirs_us, "dtaidistance_ns_per_cell": theirs_us * 1e3 / ours["cells"],
        "dtaidistance_path_len": len(path), "posecoach_path_len": ours["path_len"],
        "speedup": theirs_us / ours["us_per_call"],
    }
    if args.json:
        print(json.dumps(report))
    else:
        print(f"n={args.n} dims={args.dims} band={args.band} ({ours['cells']} banded cells), path included")
        print(f"  posecoach     {ours['us_per_call']:9.1f} us per call  {ours['ns_per_cell']:6.2f} ns per cell")
        print(f"  dtaidistance  {theirs_us:9.1f} us per call  {report['dtaidistance_ns_per_cell']:6.2f} ns per cell")
        print(f"  posecoach is {report['speedup']:.2f}x faster")


if __name__ == "__main__":
    main()
