#!/usr/bin/env python3
"""Checks that a drive scene is physically possible: no two vehicles' bird's-eye boxes overlap
(within a margin) in any frame, each moving at its constant velocity, as scene-render sensors
--frames renders them. A truth with two cars in one place cannot be met by any detector, so a
drive evaluated against it measures nothing there.

usage: scripts/check-drive-scene.py SCENE.json [--frames 100] [--fps 10] [--margin 0.1]
Prints every overlapping pair with its frames; exits 1 when there is one, 2 on bad input.
"""
import argparse
import json
import math
import sys

VEHICLES = {"car", "truck", "bus", "van", "motorcycle", "bicycle"}


def corners(e, t, margin):
    """Footprint corners (x, z) at time t, grown by margin on every side."""
    v = e.get("velocity") or {"vx": 0.0, "vz": 0.0}
    x, z = e["x"] + v["vx"] * t, e["z"] + v["vz"] * t
    c, s = math.cos(e["theta"]), math.sin(e["theta"])
    half_l, half_w = e["L"] / 2 + margin, e["W"] / 2 + margin
    # Heading (cos t, -sin t) in camera x-z; across it (sin t, cos t).
    return [(x + c * dl * half_l + s * dw * half_w, z - s * dl * half_l + c * dw * half_w)
            for dl, dw in ((1, 1), (1, -1), (-1, -1), (-1, 1))]


def separated(a, b):
    """Whether two convex quadrilaterals have a separating axis (they do not overlap)."""
    for poly in (a, b):
        for i in range(4):
            (px, pz), (qx, qz) = poly[i], poly[(i + 1) % 4]
            nx, nz = qz - pz, px - qx
            pa = [nx * x + nz * z for x, z in a]
            pb = [nx * x + nz * z for x, z in b]
            if max(pa) <= min(pb) or max(pb) <= min(pa):
                return True
    return False


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene")
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument("--fps", type=float, default=10.0)
    parser.add_argument("--margin", type=float, default=0.1)
    args = parser.parse_args()
    if args.frames < 1 or not args.fps > 0 or args.margin < 0:
        print("check-drive-scene: error: --frames >= 1, --fps > 0, --margin >= 0", file=sys.stderr)
        return 2
    try:
        with open(args.scene) as f:
            entities = json.load(f)["entities"]
        vehicles = [e for e in entities if e.get("class") in VEHICLES]
        for e in vehicles:
            for key in ("x", "z", "theta", "L", "W"):
                float(e[key])
    except (OSError, ValueError, KeyError, TypeError) as error:
        print(f"check-drive-scene: error: {args.scene}: {error}", file=sys.stderr)
        return 2
    overlaps = {}
    for k in range(args.frames):
        t = k / args.fps
        boxes = [corners(e, t, args.margin) for e in vehicles]
        for i in range(len(vehicles)):
            for j in range(i + 1, len(vehicles)):
                if not separated(boxes[i], boxes[j]):
                    overlaps.setdefault((vehicles[i]["id"], vehicles[j]["id"]), []).append(k)
    for (a, b), frames in overlaps.items():
        print(f"{args.scene}: {a} and {b} overlap in frames {frames[0]}-{frames[-1]} "
              f"({len(frames)} frames)")
    if not overlaps:
        print(f"{args.scene}: no two of {len(vehicles)} vehicles overlap in {args.frames} frames")
    return 1 if overlaps else 0


if __name__ == "__main__":
    sys.exit(main())
