#!/usr/bin/env python3
"""Side-by-side disparity scores of cloud-analysis settings on KITTI 2015 frames.

Usage: scripts/compare-disparity.py BUILD/cloud_analysis/cloud-analysis [KITTI15_DIR]
Prints the Markdown table of docs/evaluation.md (section Disparity): D1-all, D1-valid, EPE,
density from the tool's --gt-disparity line, and the median disparity time of 3 runs.
Reads the data in place; copies nothing.
"""
import re
import statistics
import subprocess
import sys

tool = sys.argv[1]
root = sys.argv[2] if len(sys.argv) > 2 else "/work/shared/data/kitti15"
LINE = re.compile(r"D1-all ([\d.]+) %, D1-valid ([\d.]+) %, EPE ([\d.]+) px, density ([\d.]+) %")
SETTINGS = [
    ("OpenCV sample (`--preset opencv-sample`)", ["--preset", "opencv-sample"]),
    ("**tuned defaults**", []),
    ("tuned + `--lr-check`", ["--lr-check"]),
    ("tuned + `--wls`", ["--wls"]),
    ("tuned + `--lr-check --wls`", ["--lr-check", "--wls"]),
    ("tuned but `--sgbm-mode sgbm`", ["--sgbm-mode", "sgbm"]),
    ("tuned but `--no-pad-left`", ["--no-pad-left"]),
]
print("| settings | frame | D1-all % | D1-valid % | EPE px | density % | ms |")
print("|---|---|---|---|---|---|---|")
for name, flags in SETTINGS:
    for frame in ["000000_10", "000001_10"]:
        times, score = [], None
        for _ in range(3):
            cmd = [tool, "--kitti-root", root, "--frame", frame, "--gt-disparity",
                   f"{root}/disp_occ_0/{frame}.png", "--timings"] + flags
            err = subprocess.run(cmd, capture_output=True, text=True, check=True).stderr
            score = LINE.search(err).groups()
            times.append(float(re.search(r"timing: disparity\s+([\d.]+) ms", err).group(1)))
        print(f"| {name} | {frame} | " + " | ".join(score) + f" | {statistics.median(times):.0f} |")
