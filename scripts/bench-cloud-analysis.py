#!/usr/bin/env python3
"""Median per-stage milliseconds of cloud-analysis on KITTI frames (a benchmark, not a test).

Usage: scripts/bench-cloud-analysis.py BUILD/cloud_analysis/cloud-analysis [KITTI15_DIR] [RUNS]
Each run writes the three cloud formats into a temporary folder (formatting and the atomic
write, not fsync'ed unless --fsync-clouds, are timed separately per file), so the cost of a
cloud can be set against the disparity that produced it. Reads the data in place; copies nothing.
"""
import collections
import re
import statistics
import subprocess
import sys
import tempfile

tool = sys.argv[1]
root = sys.argv[2] if len(sys.argv) > 2 else "/work/shared/data/kitti15"
runs = int(sys.argv[3]) if len(sys.argv) > 3 else 5
LINE = re.compile(r"timing: (.+?)\s+([\d.]+) ms")

for frame in ["000000_10", "000001_10"]:
    stages = collections.defaultdict(list)
    with tempfile.TemporaryDirectory() as out:
        for _ in range(runs):
            cmd = [tool, "--kitti-root", root, "--frame", frame, "--timings",
                   "--xyz", f"{out}/c.xyz", "--pcd", f"{out}/c.pcd", "--ply", f"{out}/c.ply"]
            err = subprocess.run(cmd, capture_output=True, text=True, check=True).stderr
            for name, ms in LINE.findall(err):
                stages[name.strip()].append(float(ms))
    print(f"{frame} (median of {runs} runs)")
    for name, values in stages.items():
        print(f"  {name:24s} {statistics.median(values):8.1f} ms")
    for fmt in ["xyz", "pcd", "ply"]:
        cost = statistics.median(
            [a + b for a, b in zip(stages[f"format --{fmt}"], stages[f"write --{fmt}"])])
        print(f"  .{fmt} format+write {cost:6.1f} ms vs disparity "
              f"{statistics.median(stages['disparity']):6.1f} ms")
