#!/usr/bin/env python3
"""Coordinate-descent tuning of cloud-analysis's SGBM flags on KITTI 2015 frames.

Usage: scripts/tune-disparity.py BUILD/cloud_analysis/cloud-analysis [KITTI15_DIR]
Scores each setting with the tool's own --gt-disparity line (D1-all, missing pixels count as
outliers) averaged over the frames, starting from the current defaults, and prints the table.
Reads the data in place; copies nothing.
"""
import re
import subprocess
import sys
import time

tool = sys.argv[1]
root = sys.argv[2] if len(sys.argv) > 2 else "/work/shared/data/kitti15"
frames = ["000000_10", "000001_10"]
LINE = re.compile(r"D1-all ([\d.]+) %, D1-valid ([\d.]+) %, EPE ([\d.]+) px, density ([\d.]+) %")


def score(flags):
    total = [0.0] * 4
    ms = 0.0
    for f in frames:
        cmd = [tool, "--kitti-root", root, "--frame", f, "--gt-disparity",
               f"{root}/disp_occ_0/{f}.png", "--timings"] + flags
        out = subprocess.run(cmd, capture_output=True, text=True)
        m = LINE.search(out.stderr)
        if not m:
            raise SystemExit(f"no score from {' '.join(cmd)}:\n{out.stderr}")
        t = re.search(r"timing: disparity\s+([\d.]+) ms", out.stderr)
        ms += float(t.group(1))
        total = [a + float(b) for a, b in zip(total, m.groups())]
    n = len(frames)
    return [v / n for v in total] + [ms / n]


def show(name, s):
    print(f"{name:60s} D1-all {s[0]:6.2f} %  D1-valid {s[1]:5.2f} %  EPE {s[2]:.3f} px  "
          f"density {s[3]:5.1f} %  {s[4]:6.1f} ms", flush=True)


show("opencv-sample", score(["--preset", "opencv-sample"]))
base = {}
best = score([])
show("defaults", best)
grid = {
    "--block-size": ["3", "5", "7", "9"],
    "--sgbm-mode": ["sgbm", "hh", "sgbm_3way"],
    "--uniqueness-ratio": ["0", "5", "10", "15"],
    "--speckle-range": ["1", "2", "4", "32"],
    "--speckle-window-size": ["0", "50", "100", "200"],
    "--disp12-max-diff": ["-1", "1", "2"],
    "--pre-filter-cap": ["15", "31", "63"],
    "--p2": ["0", "1600", "2400", "3200"],
    "--colour-matching": [None, ""],
    "--wls": [None, ""],
}
for flag, values in grid.items():
    for v in values:
        trial = dict(base)
        if v is None:
            trial.pop(flag, None)
        else:
            trial[flag] = v
        flags = [x for k, val in trial.items() for x in ([k] if val == "" else [k, val])]
        s = score(flags)
        show(" ".join(flags) or "(defaults)", s)
        if s[0] < best[0] - 0.05:
            best, base = s, trial
print("best:", " ".join(f"{k} {v}" for k, v in base.items()))
show("best", best)
