#!/usr/bin/env python3
"""`tinsmith tin` as a whole command against a plain CGAL program.

The input: N random points as XYZ text (UTM-sized coordinates, a 10 km square)
and L random break lines of 11 vertices each as GeoJSON LineStrings, long
enough that about 17 500 pairs of them cross. Both programs read the same two
files, triangulate, and write their result; each run is a child process timed
from outside (wall clock) with its peak resident memory (wait4). The runs
take turns — CGAL, tinsmith with 1 thread, tinsmith with 2 — within every
repetition, so that load on a shared machine hits all of them alike; the
fastest of R repetitions is reported for the whole command, and each stage's
fastest time for the stages (a stage's time varies apart from its run's: the
fsync at the end of a write, most of all).

The reference is cgal_tin (cgal_tin.cpp beside this file). Between the
repetitions the disk's sequential write speed is measured on a file the size
of the .tin with the same write, fsync and rename over the old file that the
writer does. From tinsmith's
build report (--report) come the stage times: reading each file (the XYZ's MB/s),
triangulating, the structural check (as a share of triangulating) and the
.tin write (against the disk).

    python3 tests/bench/tin/run.py [--points N] [--lines L] [--reps R]
                                   [--build DIR] [--keep DIR] [--check]
                                   [--tinsmith BINARY] [--cgal BINARY]

--check (the ctest smoke): small sizes, one repetition, exits non-zero when a
program fails or the two triangulations disagree on their vertex count.
"""
import argparse
import json
import math
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))


def make_input(folder, points, lines, seed=14):
    """The points (XYZ text) and break lines (GeoJSON); returns their paths."""
    rng = random.Random(seed)
    side, x0, y0 = 10000.0, 430000.0, 4510000.0
    xyz = os.path.join(folder, "points.xyz")
    with open(xyz, "w") as f:
        f.writelines(
            "%.3f %.3f %.3f\n"
            % (x0 + rng.random() * side, y0 + rng.random() * side, 1500 + rng.random() * 300)
            for _ in range(points))
    # Random walks of 10 steps whose length (0.234 of the side) makes about
    # 17 500 crossings among 1000 of them.
    step = 0.234 * side / 10
    features = []
    for k in range(lines):
        x = side * (0.1 + 0.8 * rng.random())
        y = side * (0.1 + 0.8 * rng.random())
        heading = rng.random() * 2 * math.pi
        coordinates = []
        for _ in range(11):
            heading += rng.uniform(-0.3, 0.3)
            coordinates.append([round(x0 + x, 3), round(y0 + y, 3), round(1500 + rng.random() * 300, 3)])
            x = min(max(x + math.cos(heading) * step, 0.0), side)
            y = min(max(y + math.sin(heading) * step, 0.0), side)
        features.append({"type": "Feature", "properties": {"id": k},
                         "geometry": {"type": "LineString", "coordinates": coordinates}})
    geojson = os.path.join(folder, "lines.geojson")
    with open(geojson, "w") as f:
        json.dump({"type": "FeatureCollection", "features": features}, f)
    return xyz, geojson


def run(command, stdout_path):
    """Runs a child; returns (wall seconds, peak RSS in MB)."""
    with open(stdout_path, "w") as out:
        start = time.perf_counter()
        child = subprocess.Popen(command, stdout=out, stderr=subprocess.PIPE)
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.perf_counter() - start
        child.returncode = os.waitstatus_to_exitcode(status)
        err = child.stderr.read().decode()
    if child.returncode != 0:
        sys.exit("%s failed (%d):\n%s" % (" ".join(command), child.returncode, err))
    return wall, usage.ru_maxrss / 1024.0


def disk_write_seconds(path, size):
    """Writes `size` bytes in 1 MiB blocks to a temp file, fsyncs it and renames
    it over `path` (a file of that size already), as the .tin writer does."""
    block = b"\x01" * (1 << 20)

    def write(target):
        fd = os.open(target, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        try:
            left = size
            while left > 0:
                left -= os.write(fd, block[:min(left, len(block))])
            os.fsync(fd)
        finally:
            os.close(fd)

    if not os.path.exists(path):
        write(path)
    start = time.perf_counter()
    write(path + ".part")
    os.rename(path + ".part", path)
    return time.perf_counter() - start




def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--points", type=int, default=1_000_000)
    parser.add_argument("--lines", type=int, default=1000)
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    parser.add_argument("--tinsmith", help="the tinsmith binary (default: BUILD/bin/tinsmith)")
    parser.add_argument("--cgal", help="the cgal_tin binary (default: BUILD/tests/bench/tin/cgal_tin)")
    parser.add_argument("--keep", help="write the inputs and outputs here and keep them")
    parser.add_argument("--check", action="store_true", help="a small smoke run (ctest)")
    args = parser.parse_args()
    if args.check:
        args.points, args.lines, args.reps = 20000, 40, 1

    tinsmith = args.tinsmith or os.path.join(args.build, "bin", "tinsmith")
    cgal = args.cgal or os.path.join(args.build, "tests", "bench", "tin", "cgal_tin")
    for program in (tinsmith, cgal):
        if not os.access(program, os.X_OK):
            sys.exit("%s is missing: build the 'tinsmith' and 'cgal_tin' targets (needs libcgal-dev)"
                     % program)

    work = args.keep or tempfile.mkdtemp(prefix="tin-bench-")
    os.makedirs(work, exist_ok=True)
    try:
        xyz, geojson = make_input(work, args.points, args.lines)
        xyz_mb = os.path.getsize(xyz) / 1e6
        runs = {
            "cgal": [cgal, xyz, geojson, os.path.join(work, "cgal.bin")],
            "1T": [tinsmith, "tin", "--points", xyz, "--breaklines", geojson, "-q", "--threads", "1",
                   "-o", os.path.join(work, "1T.tin"), "--report", os.path.join(work, "1T.json")],
            "2T": [tinsmith, "tin", "--points", xyz, "--breaklines", geojson, "-q", "--threads", "2",
                   "-o", os.path.join(work, "2T.tin"), "--report", os.path.join(work, "2T.json")],
        }
        best = {}     # name -> (wall, peak MB, details) of its fastest run
        stages = {}   # name -> stage -> seconds of every run (their minimum is reported)
        disk = []     # seconds to write the .tin's size
        for rep in range(args.reps):
            for name, command in runs.items():
                wall, peak = run(command, os.path.join(work, name + ".out"))
                if name == "cgal":
                    words = open(os.path.join(work, "cgal.out")).read().split()
                    details = dict(zip(words[0::2], map(float, words[1::2])))
                else:
                    details = json.load(open(os.path.join(work, name + ".json")))
                if name not in best or wall < best[name][0]:
                    best[name] = (wall, peak, details)
                times = details if name == "cgal" else {t["stage"]: t["seconds"] for t in details["times"]}
                for stage, seconds in times.items():
                    stages.setdefault(name, {}).setdefault(stage, []).append(seconds)
            tin_bytes = os.path.getsize(os.path.join(work, "1T.tin"))
            disk.append(disk_write_seconds(os.path.join(work, "disk.bin"), tin_bytes))
            print("repetition %d: CGAL %.2f s, tinsmith 1T %.2f s, 2T %.2f s"
                  % (rep + 1, *(best[n][0] for n in ("cgal", "1T", "2T"))), file=sys.stderr)

        cgal_wall, cgal_peak, cgal_details = best["cgal"]
        print("`tinsmith tin` and a plain CGAL program, %d points + %d break lines "
              "(%.1f MB of XYZ), best of %d, load average %.1f\n"
              % (args.points, args.lines, xyz_mb, args.reps, os.getloadavg()[0]))
        print("| program | wall s | ratio to CGAL | peak MB | vertices | triangles |")
        print("|---|---|---|---|---|---|")
        print("| CGAL 5 (cgal_tin, 1 thread) | %.2f | 1.00 | %.0f | %d | %d |"
              % (cgal_wall, cgal_peak, cgal_details["vertices"], cgal_details["triangles"]))
        for name in ("1T", "2T"):
            wall, peak, report = best[name]
            print("| tinsmith tin --threads %s | %.2f | %.2f | %.0f | %d | %d |"
                  % (name[0], wall, wall / cgal_wall, peak, report["result"]["vertices"],
                     report["result"]["triangles"]))

        def fastest(name, stage):
            """The stage's shortest time over the repetitions."""
            return min(stages[name][stage])

        disk_mbs = tin_bytes / 1e6 / min(disk)
        print("\n| stage (s, fastest of the repetitions) | CGAL | tinsmith 1T | tinsmith 2T |")
        print("|---|---|---|---|")
        rows = [("read both files", "read", ("read points.xyz", "read lines.geojson")),
                ("read points.xyz", None, ("read points.xyz",)),
                ("read lines.geojson", None, ("read lines.geojson",)),
                ("triangulate", "triangulate", ("triangulate",)),
                ("structural check", None, ("validate",)),
                ("write", "write", ("write",))]
        for label, cgal_key, names in rows:
            cells = ["%.3f" % fastest("cgal", cgal_key) if cgal_key else "—"]
            cells += ["%.3f" % sum(fastest(n, st) for st in names) for n in ("1T", "2T")]
            print("| %s | %s |" % (label, " | ".join(cells)))

        print("\n| goal | 1 thread | 2 threads |")
        print("|---|---|---|")
        ratio = {n: best[n][0] / cgal_wall for n in ("1T", "2T")}
        print("| whole command ≤ 1.0× CGAL (1T), ≤ 0.7× (2T) | %.2f× %s | %.2f× %s |"
              % (ratio["1T"], "met" if ratio["1T"] <= 1.0 else "missed",
                 ratio["2T"], "met" if ratio["2T"] <= 0.7 else "missed"))
        cells = []
        for n in ("1T", "2T"):
            share = fastest(n, "validate") / fastest(n, "triangulate")
            cells.append("%.0f %% %s" % (100 * share, "met" if share <= 0.15 else "missed"))
        print("| structural check ≤ 15 %% of triangulating | %s |" % " | ".join(cells))
        cells = []
        for n in ("1T", "2T"):
            write_mbs = tin_bytes / 1e6 / fastest(n, "write")
            cells.append("%.0f MB/s: %.2f× the time of the disk's %.0f MB/s %s"
                         % (write_mbs, disk_mbs / write_mbs, disk_mbs,
                            "met" if disk_mbs / write_mbs <= 2.0 else "missed"))
        print("| .tin write within 2× of the disk | %s |" % " | ".join(cells))
        cells = []
        for n in ("1T", "2T"):
            read_mbs = xyz_mb / fastest(n, "read points.xyz")
            cells.append("%.0f MB/s %s" % (read_mbs, "met" if read_mbs >= 200 else "missed"))
        print("| XYZ read ≥ 200 MB/s | %s |" % " | ".join(cells))

        if args.check:
            ours = best["1T"][2]["result"]["vertices"]
            if ours != best["2T"][2]["result"]["vertices"] or ours != cgal_details["vertices"]:
                sys.exit("the triangulations disagree on their vertex count")
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
