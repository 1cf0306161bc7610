#!/usr/bin/env python3
"""Banded DTW with the path: posecoach against dtaidistance's C implementation, same data, same run.

Usage: scripts/bench_dtw_vs_dtaidistance.py [--n 200] [--dims 51] [--band 20] [--seconds 2] [--json]
       scripts/bench_dtw_vs_dtaidistance.py --sweep [--seconds 0.5] [--svg docs/dtw_speed.svg] [--json]
Needs `pip install dtaidistance numpy` and builds `posecoach` in release mode.
posecoach writes its random-walk sequences (little-endian f64); dtaidistance aligns the same
arrays with `dtw_ndim.warping_path(a, b, use_c=True, window=R+1, include_distance=True)`.
The band is the same: |i - j| <= R. Costs differ: posecoach takes the mean of per-joint
Euclidean distances (17 square roots per cell at D = 51), dtaidistance the squared Euclidean
distance over all D values; both are O(D) per cell.

--sweep measures the points of `posecoach bench dtw --sweep` (N from 100 to 5 000 frames at
D = 51, R = 20; D from 3 to 99 at N = 200; R from 5 to 50 at N = 200, D = 51), both tools on
each point's data in turn, prints the table and draws ns per cell against each axis as an SVG.
"""
import argparse
import json
import os
import subprocess
import tempfile
import time

import numpy as np
from dtaidistance import dtw_ndim

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def measure(exe, n, dims, band, seconds):
    """One point: both tools on the same random walks, each timed for `seconds`."""
    with tempfile.TemporaryDirectory() as tmp:
        data = os.path.join(tmp, "walk.f64")
        ours = json.loads(subprocess.run(
            [exe, "bench", "dtw", "--n", str(n), "--dims", str(dims), "--band", str(band),
             "--seconds", str(seconds), "--data-out", data, "--json"],
            check=True, capture_output=True, text=True).stdout)
        values = np.fromfile(data, dtype="<f8").reshape(2, n, dims)
    a, b = np.ascontiguousarray(values[0]), np.ascontiguousarray(values[1])

    path, _ = dtw_ndim.warping_path(a, b, use_c=True, window=band + 1, include_distance=True)
    calls, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds or calls < 10:
        path, _ = dtw_ndim.warping_path(a, b, use_c=True, window=band + 1, include_distance=True)
        calls += 1
    theirs_us = (time.perf_counter() - start) / calls * 1e6
    return {
        "n": n, "dims": dims, "band": band, "cells": ours["cells"],
        "posecoach_us_per_call": ours["us_per_call"], "posecoach_ns_per_cell": ours["ns_per_cell"],
        "dtaidistance_us_per_call": theirs_us, "dtaidistance_ns_per_cell": theirs_us * 1e3 / ours["cells"],
        "dtaidistance_path_len": len(path), "posecoach_path_len": ours["path_len"],
        "speedup": theirs_us / ours["us_per_call"],
    }


def sweep_points(exe):
    """The points `posecoach bench dtw --sweep` measures, in its order."""
    out = subprocess.run([exe, "bench", "dtw", "--sweep", "--seconds", "0", "--json"],
                         check=True, capture_output=True, text=True).stdout
    return [(p["n"], p["dims"], p["band"]) for p in json.loads(out)["points"]]


def svg(points, path):
    """ns per cell against N (log scale), D and R, one panel each, both tools."""
    panels = [("frames N (D = 51, R = 20)", "n", lambda p: p["dims"] == 51 and p["band"] == 20, True),
              ("values per frame D (N = 200, R = 20)", "dims", lambda p: p["n"] == 200 and p["band"] == 20, False),
              ("band radius R (N = 200, D = 51)", "band", lambda p: p["n"] == 200 and p["dims"] == 51, False)]
    width, height, pad = 260, 220, 44
    tools = [("posecoach", "posecoach_ns_per_cell", "#0072B2"), ("dtaidistance", "dtaidistance_ns_per_cell", "#D55E00")]
    top = max(p[key] for p in points for _, key, _ in tools) * 1.1
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{3 * width}" height="{height + 40}" '
             f'font-family="sans-serif" font-size="11">',
             f'<rect width="100%" height="100%" fill="white"/>']
    for k, (title, axis, keep, log) in enumerate(panels):
        chosen = sorted((p for p in points if keep(p)), key=lambda p: p[axis])
        xs = [p[axis] for p in chosen]
        lo, hi = (np.log10(min(xs)), np.log10(max(xs))) if log else (0, max(xs))
        x0, y0, w, h = k * width + pad, 12, width - pad - 10, height - 50

        def x(v):
            return x0 + w * ((np.log10(v) if log else v) - lo) / (hi - lo)

        def y(v):
            return y0 + h * (1 - v / top)

        parts.append(f'<rect x="{x0}" y="{y0}" width="{w}" height="{h}" fill="none" stroke="#888"/>')
        step = 10 ** np.floor(np.log10(top / 2))
        step *= 5 if top / step > 20 else 2 if top / step > 8 else 1
        for t in np.arange(step, top, step):
            parts.append(f'<line x1="{x0}" x2="{x0 + w}" y1="{y(t):.1f}" y2="{y(t):.1f}" stroke="#eee"/>')
            parts.append(f'<text x="{x0 - 4}" y="{y(t) + 4:.1f}" text-anchor="end">{t:g}</text>')
        for v in xs:
            parts.append(f'<text x="{x(v):.1f}" y="{y0 + h + 14}" text-anchor="middle">{v}</text>')
        parts.append(f'<text x="{x0 + w / 2}" y="{y0 + h + 30}" text-anchor="middle">{title}</text>')
        for name, key, colour in tools:
            line = " ".join(f"{x(p[axis]):.1f},{y(p[key]):.1f}" for p in chosen)
            parts.append(f'<polyline points="{line}" fill="none" stroke="{colour}" stroke-width="2"/>')
            parts += [f'<circle cx="{x(p[axis]):.1f}" cy="{y(p[key]):.1f}" r="3" fill="{colour}"/>' for p in chosen]
    parts.append(f'<text x="{pad}" y="{height + 30}">ns per banded cell, path included, lower is faster:</text>')
    for i, (name, _, colour) in enumerate(tools):
        parts.append(f'<text x="{pad + 270 + 120 * i}" y="{height + 30}" fill="{colour}">■ {name}</text>')
    parts.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(parts) + "\n")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=200)
    p.add_argument("--dims", type=int, default=51)
    p.add_argument("--band", type=int, default=20)
    p.add_argument("--seconds", type=float, default=None,
                   help="measuring time per tool and point (default 2, or 0.5 with --sweep)")
    p.add_argument("--sweep", action="store_true", help="every point of `posecoach bench dtw --sweep`")
    p.add_argument("--svg", default=None, help="with --sweep, also draw ns per cell to this SVG file")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args()

    subprocess.run(["cargo", "build", "--release", "-q", "-p", "posecoach-cli"], cwd=ROOT, check=True)
    exe = os.path.join(ROOT, "target", "release", "posecoach")
    if not args.sweep:
        report = measure(exe, args.n, args.dims, args.band, args.seconds or 2.0)
        if args.json:
            print(json.dumps(report))
            return
        print(f"n={args.n} dims={args.dims} band={args.band} ({report['cells']} banded cells), path included")
        print(f"  posecoach     {report['posecoach_us_per_call']:9.1f} us per call  {report['posecoach_ns_per_cell']:6.2f} ns per cell")
        print(f"  dtaidistance  {report['dtaidistance_us_per_call']:9.1f} us per call  {report['dtaidistance_ns_per_cell']:6.2f} ns per cell")
        print(f"  posecoach is {report['speedup']:.2f}x faster")
        return

    points = []
    todo = sweep_points(exe)
    for k, (n, dims, band) in enumerate(todo):
        print(f"point {k + 1} of {len(todo)}: n={n} dims={dims} band={band}", file=os.sys.stderr)
        points.append(measure(exe, n, dims, band, args.seconds or 0.5))
    if args.svg:
        svg(points, args.svg)
    if args.json:
        print(json.dumps({"points": points}))
        return
    print("| N | D | R | cells | posecoach ns per cell | dtaidistance ns per cell | speed-up |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for r in points:
        print(f"| {r['n']} | {r['dims']} | {r['band']} | {r['cells']} | {r['posecoach_ns_per_cell']:.2f} | "
              f"{r['dtaidistance_ns_per_cell']:.2f} | {r['speedup']:.2f}x |")


if __name__ == "__main__":
    main()
