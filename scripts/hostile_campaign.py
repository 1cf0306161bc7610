#!/usr/bin/env python3
"""Hostile-input campaign: mutate the bundled files and run the release `posecoach` on each mutant.

Sources: the motion fixtures (BVH, C3D, CSV) through `inspect` and, for swings, `score` as the
student against the bundled driver; the coach references (.pcr) and int8 weights through
`inspect` (the int8 weights also through `replay --weights`, which uses every weight); the float
weights (PCTEACH3) through `inspect` and `score --weights`; a recorded session (.pclog) through
`replay`. Every (source, command) first runs on the unmutated file; one that is not accepted
there is skipped and listed (`score --weights` needs a binary built with `--features learn`).
Mutations, seeded and deterministic: single-bit flips in the first 128 bytes and anywhere,
truncations, 8-byte overwrites; for BVH and CSV also numeric-token replacements, line
duplication/deletion and header edits (BVH `Frames:`/`Frame Time:`, the CSV time column).
Large inputs, generated as scripts/reader_growth.py makes them (a swaying T-pose at 360 Hz): a
long keypoint CSV, a JSON array and JSON Lines of --large-mb MB each, a CSV header of 100 000
columns and a JSON of 50 000 landmark names, each through `inspect` unmutated and as
--large-count mutants (flips, truncations, overwrites, a line duplicated or deleted).

Outcome of each run, from its exit status and stderr:
  hang      ran past --timeout (its process group is killed)
  panic     stderr says `panicked`, or exit 101
  abort     killed by a signal (exit 128+N under /usr/bin/time), or stderr says `memory allocation of`
  accepted  exit 0;  refused: exit 1, 2 or 3 with an `error:` line;  other: any other exit
  memory bomb, counted on top: peak RSS over 1 GiB (/usr/bin/time -f %M, when present). Runs are
  capped at 4 GiB of address space (prlimit, when present), so a runaway allocation aborts
  instead of exhausting the machine.
  over memory, counted on top: peak RSS over F + 10 times the input's size, F being twice the
  command's own peak on the unmutated bundled file, or for the large inputs twice `inspect`'s
  on the one-row T-pose fixture (the process's own baseline, about 5 MB): a floor for small
  inputs, whose own cost is lost in the process's and in what an error message allocates.
Checksummed formats (.pcr, .pcw, .pclog), per bit flip: rejected, accepted with identical output,
or accepted with different output = a silent corruption. A .pclog frame carries its own CRC, so a
flip should lose only its frame: an accepted flip whose replay counts the damage (crc_errors,
malformed, overflows, refused) is "noticed", not silent; the swing count is compared too.
Text/motion formats carry no checksum, so acceptance is no corruption; "implausible" counts
accepted runs whose mutant `inspect --json` gives a height_m outside 0.5-2.75 m (or none).

Usage: scripts/hostile_campaign.py [--seed 1] [--count 2000] [--large-count 10] [--large-mb 16]
                                   [--jobs 2] [--timeout 10] [--json] [--keep DIR]
                                   [--bin target/release/posecoach]
The default, 2000 mutants per source and 10 per large input (30055 runs), took 2.5 minutes on
a busy two-core machine (2026-12-06). --keep DIR saves every mutant that hung, panicked, aborted,
bombed, went over its memory bound or was silently accepted, with a .txt beside it (mutation,
command, exit, stderr tail). Exit status 1 when any of those occurred.
"""
import argparse
import concurrent.futures
import glob
import json
import math
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import reader_growth

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DRIVER, IRON, LOG = "tests/fixtures/golf_driver_60hz.csv", "tests/fixtures/golf_iron_60hz.csv", "tests/logs/device_h36m_30hz.pclog"
INSPECT = ("inspect", ["inspect", "--json", "{file}"])
SCORE = ("score", ["score", "--coach", DRIVER, "--student", "{file}", "--json", "--report", "{out}/report.html"])
SCORE_WEIGHTS = ("score --weights", ["score", "--coach", DRIVER, "--student", IRON, "--weights", "{file}", "--json"])
REPLAY = ("replay", ["replay", "{file}", "--json"])
REPLAY_WEIGHTS = ("replay --weights", ["replay", LOG, "--weights", "{file}", "--json"])
SOURCES = ([(f, "bvh", [INSPECT]) for f in sorted(glob.glob("tests/fixtures/*.bvh", root_dir=ROOT))]
           + [(f, "c3d", [INSPECT, SCORE]) for f in sorted(glob.glob("tests/fixtures/*.c3d", root_dir=ROOT))]
           + [(DRIVER, "csv", [INSPECT, SCORE]), (IRON, "csv", [INSPECT, SCORE]),
              ("tests/fixtures/h36m17_tpose.csv", "csv", [INSPECT]),
              ("coaches/driver.pcr", "pcr", [INSPECT]), ("coaches/iron.pcr", "pcr", [INSPECT]),
              ("weights/distilled-int8.pcw", "pcw-int8", [INSPECT, REPLAY_WEIGHTS]),
              ("weights/distilled.pcw", "pcw-float", [INSPECT, SCORE_WEIGHTS]), (LOG, "pclog", [REPLAY])])
CHECKSUMMED = {"pcr", "pcw-int8", "pcw-float", "pclog"}
TPOSE = "tests/fixtures/h36m17_tpose.csv"
MB = 1 << 20
# Large inputs: (file name, kind, writer of the file at a path, given the size in MB).
LARGE = [("long.csv", "csv-long", lambda path, mb: reader_growth.write_sized(path, reader_growth.csv_frames, mb * MB)),
         ("wide.csv", "csv-wide", lambda path, mb: reader_growth.write_wide_csv(path)),
         ("names.json", "json-names", lambda path, mb: reader_growth.write_wide_json(path)),
         ("large.json", "json-large", lambda path, mb: reader_growth.write_sized(path, reader_growth.json_frames, mb * MB)),
         ("large.jsonl", "jsonl-large", lambda path, mb: reader_growth.write_sized(path, reader_growth.jsonl_frames, mb * MB))]
LARGE_KINDS = {kind for _, kind, _ in LARGE}
MOTION = {"bvh", "c3d", "csv"} | LARGE_KINDS
OUTCOMES = ["accepted", "refused", "panic", "abort", "hang", "other"]
FLIP_VERDICTS = ["flips", "rejected", "identical", "noticed", "silent"]
KEEP_WORTHY = {"hang", "panic", "abort"}
TOTALS = [("hangs", "hang"), ("panics", "panic"), ("aborts", "abort"), ("memory bombs", "memory bomb"),
          ("runs over their memory bound", "over memory"), ("silently accepted corruptions", "silent")]
MEMORY_FACTOR, FLOOR_FACTOR = 10, 2
BOMB_KB, AS_CAP = 1 << 20, 4 << 30
TIME, PRLIMIT = shutil.which("time", path="/usr/bin"), shutil.which("prlimit")
NUMBERS = ["0", "-0", "1e9", "1e-9", "1e300", "-1e300", "nan", "inf", "99999999999999999999", ""]
NUMBER = re.compile(rb"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


# Mutations: each takes the source bytes and a random.Random, and returns (mutant, description).
def flip(data, rng, limit):
    i, bit = rng.randrange(min(limit, len(data))), rng.randrange(8)
    out = bytearray(data)
    out[i] ^= 1 << bit
    return bytes(out), f"flip bit {bit} of byte {i}"


def flip_header(data, rng):
    return flip(data, rng, 128)


def flip_any(data, rng):
    return flip(data, rng, len(data))


def truncate(data, rng):
    n = rng.randrange(len(data))
    return data[:n], f"truncate to {n} bytes"


def overwrite(data, rng):
    i, junk = rng.randrange(len(data) - 7), rng.randbytes(8)
    return data[:i] + junk + data[i + 8:], f"overwrite 8 bytes at {i} with {junk.hex()}"


def number(data, rng):
    m, new = rng.choice(list(NUMBER.finditer(data))), rng.choice(NUMBERS)
    return data[:m.start()] + new.encode() + data[m.end():], f"number {m.group().decode()} at {m.start()} -> {new!r}"


def line(data, rng):
    lines = data.splitlines(keepends=True)
    i, dup = rng.randrange(len(lines)), rng.random() < 0.5
    lines[i:i + 1] = [lines[i]] * (2 if dup else 0)
    return b"".join(lines), f"{'duplicate' if dup else 'delete'} line {i + 1}"


def bvh_header(data, rng):
    field, values = rng.choice([(b"Frames:", ["0", "16777216", "-1"]), (b"Frame Time:", ["0", "1e9", "1e-9"])])
    new = rng.choice(values).encode()
    return re.sub(re.escape(field) + rb"[ \t]*\S+", field + b" " + new, data, count=1), f"{field.decode()} {new.decode()}"


def replaced(times, i, value):
    return times[:i] + [value] + times[i + 1:]


TIME_EDITS = {"constant": lambda t, i: [t[0]] * len(t), "scaled by 1e9": lambda t, i: [x * 1e9 for x in t],
              "scaled by 1e-9": lambda t, i: [x * 1e-9 for x in t], "reversed": lambda t, i: t[::-1],
              "repeated": lambda t, i: replaced(t, i, t[i - 1]), "jump to 1e9": lambda t, i: replaced(t, i, 1e9),
              "nan": lambda t, i: replaced(t, i, math.nan)}


def csv_time(data, rng):
    head, *rows = data.rstrip(b"\n").split(b"\n")
    name, i = rng.choice(sorted(TIME_EDITS)), rng.randrange(len(rows))
    times = TIME_EDITS[name]([float(r.split(b",", 1)[0]) for r in rows], i)
    body = [repr(t).encode() + b"," + r.split(b",", 1)[1] for t, r in zip(times, rows)]
    return b"\n".join([head] + body) + b"\n", f"time column {name} (row {i + 1})"


BINARY_OPS = [flip_header, flip_any, truncate, overwrite]
OPS = {"bvh": BINARY_OPS + [number, line, bvh_header], "csv": BINARY_OPS + [number, line, csv_time],
       **{kind: BINARY_OPS + [line] for kind in LARGE_KINDS}}


def classify(rc, err):
    if "panicked" in err or rc == 101:
        return "panic"
    if rc < 0 or rc >= 128 or "memory allocation of" in err:
        return "abort"
    if rc == 0:
        return "accepted"
    return "refused" if rc in (1, 2, 3) and re.search(r"^error:", err, re.M) else "other"


def run(argv, timeout, mem_path):
    """Runs argv (capped, timed) in the repository root; returns its outcome, output and peak KiB."""
    wrap = ([TIME, "-f", "%M", "-o", mem_path] if TIME else []) + ([PRLIMIT, f"--as={AS_CAP}", "--"] if PRLIMIT else [])
    p = subprocess.Popen(wrap + argv, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        return {"outcome": "hang", "rc": None, "stdout": "", "stderr": "", "peak_kb": None}
    err = err.decode(errors="replace")
    return {"outcome": classify(p.returncode, err), "rc": p.returncode, "stdout": out.decode(errors="replace"),
            "stderr": err, "peak_kb": peak_kb(mem_path) if TIME else None}


def peak_kb(mem_path):
    try:
        with open(mem_path) as f:
            return int(f.read().split()[-1])
    except (OSError, ValueError, IndexError):
        return None


def command(binary, cmd, path, out):
    return [binary] + [a.format(file=path, out=out) for a in cmd[1]]


def attack(binary, work, job, timeout):
    """Writes one mutant of a source into its own folder and runs the source's commands on it."""
    src, kind, cmds, index, seed = job
    rng = random.Random(seed)
    op = rng.choice(OPS.get(kind, BINARY_OPS))
    with open(os.path.join(ROOT, src), "rb") as f:
        data, desc = op(f.read(), rng)
    stem, ext = os.path.splitext(os.path.basename(src))
    folder = os.path.join(work, f"{stem}-{index:05d}")
    os.mkdir(folder)
    path = os.path.join(folder, stem + ext)
    with open(path, "wb") as f:
        f.write(data)
    runs = [run(command(binary, cmd, path, folder), timeout, os.path.join(folder, "peak")) for cmd in cmds]
    return {"src": src, "kind": kind, "cmds": cmds, "name": f"{stem}-{index:05d}{ext}", "path": path, "folder": folder,
            "mutation": desc, "flip": op in (flip_header, flip_any), "size": len(data), "runs": runs}


def parsed(stdout):
    try:
        return json.loads(stdout)
    except ValueError:
        return None


def implausible(inspect_run):
    """An accepted `inspect --json` whose height is missing or outside 0.5-2.75 m."""
    if inspect_run["outcome"] != "accepted":
        return False
    h = (parsed(inspect_run["stdout"]) or {}).get("height_m")
    return not (isinstance(h, (int, float)) and 0.5 <= h <= 2.75)


def damage(stdout):
    doc = parsed(stdout) or {}
    c = doc.get("counters", {})
    return sum(c.get(k, 0) for k in ("crc_errors", "malformed", "overflows")) + len(doc.get("refused", []))


def flip_verdict(kind, r, base, mutant):
    if r["outcome"] != "accepted":
        return "rejected"
    if r["stdout"].replace(mutant["path"], mutant["src"]) == base["stdout"]:
        return "identical"
    return "noticed" if kind == "pclog" and damage(r["stdout"]) > damage(base["stdout"]) else "silent"


def memory_bound_kb(mutant, cmd, baselines):
    """F + 10 times the input's size, F twice the command's peak on the unmutated bundled file (for
    a large input, `inspect`'s on the one-row T-pose fixture); None when a peak is unknown."""
    floor = baselines[(TPOSE, "inspect") if mutant["kind"] in LARGE_KINDS else (mutant["src"], cmd[0])]["peak_kb"]
    return None if floor is None else FLOOR_FACTOR * floor + MEMORY_FACTOR * mutant["size"] / 1024


def tally(rows, findings, mutant, baselines, keep, binary):
    kind, cmds = mutant["kind"], mutant["cmds"]
    for cmd, r in zip(cmds, mutant["runs"]):
        # A large input's own run is tallied whatever its outcome, and has no baseline but itself.
        row, base = rows[(kind, cmd[0])], baselines.get((mutant["src"], cmd[0]))
        row["runs"] += 1
        row[r["outcome"]] += 1
        bomb = (r["peak_kb"] or 0) > BOMB_KB
        row["memory bomb"] += bomb
        bound = memory_bound_kb(mutant, cmd, baselines)
        over = r["peak_kb"] is not None and bound is not None and r["peak_kb"] > bound
        row["over memory"] += over
        verdict = flip_verdict(kind, r, base, mutant) if kind in CHECKSUMMED and mutant["flip"] else None
        if verdict:
            row["flips"] += 1
            row[verdict] += 1
        if kind in MOTION and r["outcome"] == "accepted" and cmds[0] == INSPECT and implausible(mutant["runs"][0]):
            row["implausible"] += 1
        if kind == "pclog" and verdict in ("identical", "noticed", "silent"):
            row["swings changed"] += len((parsed(r["stdout"]) or {}).get("swings", [])) != len(parsed(base["stdout"])["swings"])
        what = (r["outcome"] if r["outcome"] in KEEP_WORTHY else "memory bomb" if bomb
                else "over memory" if over else "silent corruption")
        if r["outcome"] in KEEP_WORTHY or bomb or over or verdict == "silent":
            findings.append(finding(what, mutant, cmd, r, keep, binary))


def finding(what, mutant, cmd, r, keep, binary):
    """Describes one bad run; with --keep, saves its mutant and a .txt (command, stderr tail) beside it."""
    argv = command(binary, cmd, os.path.join(keep or "", mutant["name"]), "OUT")
    f = {"what": what, "kind": mutant["kind"], "mutant": mutant["name"], "mutation": mutant["mutation"],
         "command": " ".join(argv), "rc": r["rc"], "peak_kb": r["peak_kb"], "stderr": r["stderr"].strip()[:200]}
    if keep:
        shutil.copyfile(mutant["path"], os.path.join(keep, mutant["name"]))
        with open(os.path.join(keep, mutant["name"] + ".txt"), "a") as out:
            lines = [f"{k}: {f[k]}" for k in ("what", "mutation", "command", "rc", "peak_kb")]
            out.write("\n".join(lines + ["stderr (tail):"] + r["stderr"].splitlines()[-20:]) + "\n\n")
    return f


def baseline(binary, work, timeout):
    """Runs every (source, command) on the unmutated file; returns the accepted runs and the skipped."""
    runs, skipped = {}, []
    for src, kind, cmds in SOURCES:
        for cmd in cmds:
            r = run(command(binary, cmd, src, work), timeout, os.path.join(work, "peak"))
            if r["outcome"] == "accepted":
                runs[(src, cmd[0])] = r
            else:
                skipped.append({"source": src, "command": cmd[0], "outcome": r["outcome"], "stderr": r["stderr"].strip()[:200]})
    return runs, skipped


def large_sources(work, mb):
    """Writes the large inputs into work; returns them as sources."""
    sources = []
    for name, kind, write in LARGE:
        path = os.path.join(work, name)
        write(path, mb)
        sources.append((path, kind, [INSPECT]))
    return sources


def unmutated(src, kind, cmds, result):
    """A large input's own run, tallied as a mutant that changed nothing."""
    return {"src": src, "kind": kind, "cmds": cmds, "name": os.path.basename(src), "path": src, "folder": None,
            "mutation": "none", "flip": False, "size": os.path.getsize(src), "runs": [result]}


def report(rows, findings, skipped, totals, header):
    cols = OUTCOMES + ["memory bomb", "over memory", "implausible"]
    print(header)
    print(f"{'kind':10} {'command':17} {'runs':>6} " + " ".join(f"{c:>11}" for c in cols))
    for (kind, cmd), row in rows.items():
        print(f"{kind:10} {cmd:17} {row['runs']:6} " + " ".join(f"{row[c]:11}" for c in cols))
    print(f"\nbit flips in checksummed formats:\n{'kind':10} {'command':17} " + " ".join(f"{c:>9}" for c in FLIP_VERDICTS))
    for (kind, cmd), row in rows.items():
        if kind in CHECKSUMMED:
            print(f"{kind:10} {cmd:17} " + " ".join(f"{row[c]:9}" for c in FLIP_VERDICTS))
    for (kind, cmd), row in rows.items():
        if kind == "pclog":
            print(f"{kind} {cmd}: swing count changed by {row['swings changed']} of {row['flips'] - row['rejected']} accepted bit flips")
    for s in skipped:
        print(f"skipped {s['source']} {s['command']}: unmutated file {s['outcome']}: {s['stderr']}")
    for f in sorted(findings, key=lambda f: (f["what"], f["mutant"])):
        print(f"{f['what']}: {f['mutant']} ({f['mutation']}) rc {f['rc']} peak {f['peak_kb']} KiB: {f['command']}\n    {f['stderr']}")
    print(", ".join(f"{k} {v}" for k, v in totals.items()))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--count", type=int, default=2000, help="mutants per source")
    p.add_argument("--large-count", type=int, default=10, help="mutants per large input")
    p.add_argument("--large-mb", type=int, default=16, help="size of the long CSV, large JSON and JSON Lines")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--timeout", type=float, default=10.0, help="seconds per command; past it, a hang")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--keep", help="save every hanging, panicking, aborting, bombing, over-memory or silently accepted mutant here")
    p.add_argument("--bin", default=os.path.join(ROOT, "target/release/posecoach"))
    args = p.parse_args()
    if not os.access(args.bin, os.X_OK):
        sys.exit(f"no {args.bin}: build it with `cargo build --release -p posecoach-cli`")
    if args.keep:
        os.makedirs(args.keep, exist_ok=True)
    rng, start = random.Random(args.seed), time.monotonic()
    findings = []
    with tempfile.TemporaryDirectory(prefix="hostile-") as work:
        large = large_sources(work, args.large_mb)
        rows = {(kind, cmd[0]): dict.fromkeys(["runs"] + OUTCOMES + FLIP_VERDICTS
                                              + ["memory bomb", "over memory", "implausible", "swings changed"], 0)
                for _, kind, cmds in SOURCES + large for cmd in cmds}
        baselines, skipped = baseline(args.bin, work, args.timeout)
        for src, kind, cmds in large:
            r = run(command(args.bin, INSPECT, src, work), args.timeout, os.path.join(work, "peak"))
            tally(rows, findings, unmutated(src, kind, cmds, r), baselines, args.keep, args.bin)
            if r["outcome"] == "accepted":
                baselines[(src, INSPECT[0])] = r
        jobs = [(src, kind, [c for c in cmds if (src, c[0]) in baselines], i, rng.getrandbits(64))
                for sources, count in ((SOURCES, args.count), (large, args.large_count))
                for src, kind, cmds in sources for i in range(count)]
        with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
            for fut in concurrent.futures.as_completed([pool.submit(attack, args.bin, work, j, args.timeout) for j in jobs]):
                mutant = fut.result()
                tally(rows, findings, mutant, baselines, args.keep, args.bin)
                shutil.rmtree(mutant["folder"])
    rows = {k: v for k, v in rows.items() if v["runs"]}
    totals = {name: sum(r[key] for r in rows.values()) for name, key in TOTALS}
    elapsed = time.monotonic() - start
    if args.json:
        print(json.dumps({"seed": args.seed, "count": args.count, "jobs": args.jobs, "seconds": round(elapsed, 1),
                          "rows": [{"kind": k, "command": c, **v} for (k, c), v in rows.items()],
                          "skipped": skipped, "findings": findings, "totals": totals}, indent=1))
    else:
        runs = sum(r["runs"] for r in rows.values())
        report(rows, findings, skipped, totals,
               f"seed {args.seed}, {args.count} mutants per source, {runs} runs, {args.jobs} jobs, {elapsed:.0f} s")
    sys.exit(1 if any(totals.values()) else 0)


if __name__ == "__main__":
    main()
