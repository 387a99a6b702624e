#!/usr/bin/python3
"""Depth error of the matcher against KITTI Stereo 2015's LiDAR disparities, by range, with the
disparity offsets given (docs/clouds.md "Disparity offset"): for each offset o, the median of
(fB / (d + o) - fB / d_true) / (fB / d_true) over the pixels both maps hold, per range bin.
The offset's depth is the analysis' own (cloud-analysis --disparity-offset o): the matcher's
disparity d plus o. Pixels more than 30 % off (occlusions, mismatches) are left out.

usage: scripts/depth-bias.py [--build-dir DIR] [--kitti-root DIR] [--frames F ...]
                             [--offsets O ...]
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile

import cv2
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
BINS = [(0, 10), (10, 20), (20, 30), (30, 50), (50, 80)]


def disparity(path):
    """A KITTI 16-bit disparity PNG in px, 0 where none."""
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if image is None:
        sys.exit(f"depth-bias.py: error: cannot read {path}")
    return image.astype(np.float64) / 256.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build-dir", default=str(ROOT / "build"))
    parser.add_argument("--kitti-root", default=str(ROOT.parent / "shared/data/kitti15"))
    parser.add_argument("--frames", nargs="+", default=["000000_10", "000001_10", "000046_10"])
    parser.add_argument("--offsets", nargs="+", type=float, default=[0.0, 0.3, 0.5])
    args = parser.parse_args()
    tool = pathlib.Path(args.build_dir) / "cloud_analysis" / "cloud-analysis"
    root = pathlib.Path(args.kitti_root)
    if not (root / "disp_occ_0").is_dir():
        print(f"depth-bias.py: no KITTI disparities under {root}; skipped", file=sys.stderr)
        return 0
    est, true, depth = [], [], []  # per pixel both maps hold: disparities, true depth (m)
    with tempfile.TemporaryDirectory() as work:
        for frame in args.frames:
            out, entities = (os.path.join(work, frame + ext) for ext in (".png", ".json"))
            subprocess.run([str(tool), "--kitti-root", str(root), "--frame", frame,
                            "--semantics", "geometry", "--disparity-kitti", out, "-o", entities],
                           check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            rig = json.load(open(entities))["source"]["calibration"]
            d, t = disparity(out), disparity(root / "disp_occ_0" / (frame + ".png"))
            both = (d > 0) & (t > 0)
            est.append(d[both])
            true.append(t[both])
            depth.append(rig["fx"] * rig["baseline_m"] / t[both])
    est, true, depth = (np.concatenate(a) for a in (est, true, depth))
    print(f"frames {' '.join(args.frames)}: {est.size} pixels with a LiDAR disparity")
    print("| offset px | " + " | ".join(f"{lo}-{hi} m" for lo, hi in BINS) + " |")
    print("|---|" + "---|" * len(BINS))
    for offset in args.offsets:
        # fB cancels in the relative error: z / z_true - 1 = d_true / (d + o) - 1.
        relative = true / (est + offset) - 1.0
        cells = []
        for lo, hi in BINS:
            inside = (depth >= lo) & (depth < hi) & (np.abs(relative) < 0.3)
            cells.append(f"{100 * np.median(relative[inside]):+.1f} %" if inside.any() else "-")
        print(f"| {offset:+.2f} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
