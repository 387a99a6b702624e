#!/usr/bin/env python3
"""Writes a long street for a drive with a moving camera, as an entity file for
`scene-render sensors --frames N --ego-speed V --ego-yaw-rate W`, from a seed.

The street follows the path the camera drives: straight, or a circle of radius V / W (a positive
yaw rate turns right) starting at the camera, 1.65 m above the road's centre line. Both sides are
parked with cars of mixed lengths (small cars to vans) with 0.4-1.2 m gaps and now and then a
driveway, street trees and poles at the kerb, sidewalks and buildings behind. On a straight street
two cars drive as well: one ahead in the camera's lane, one oncoming in the other. The scene is
the world of the drive (the camera at the first frame); give scene-render the same speed and yaw
rate:

    scripts/make-drive-street.py --seed 1 --speed 8 --yaw-rate 0 --length 100 -o street.json
    scene-render sensors street.json --out drive --frames 100 --ego-speed 8 --ego-yaw-rate 0

The same arguments give the same file byte for byte.
"""
import argparse
import math
import random

from stereoscene_assets import class_ids, kitti_frame, write_entity_file

ROAD_TOP_Y = 1.60  # the road's top surface in the camera frame (y down), metres
KERB = 6.0  # the road's half width, metres
SIDEWALK = 3.0  # sidewalk width, metres
SEGMENT = 4.0  # length of the road and sidewalk pieces on a curve, metres
FAMILIES = [  # (family, subclass, length, width, height in metres, weight)
    ("small", "car", 3.6, 1.65, 1.45, 2),
    ("sedan", "car", 4.5, 1.80, 1.45, 4),
    ("estate", "car", 4.8, 1.82, 1.50, 2),
    ("suv", "car", 4.7, 1.90, 1.72, 2),
    ("van", "van", 5.2, 2.00, 2.00, 1),
]
CLASS_IDS = class_ids("cityscapes")


class Path:
    """The camera's path: arc length s -> point and heading (a unicycle at speed v, yaw rate w)."""

    def __init__(self, speed, yaw_rate_dps):
        self.curvature = math.radians(yaw_rate_dps) / speed if speed else 0.0

    def heading(self, s):
        return self.curvature * s

    def point(self, s, d=0.0):
        """(x, z) of arc length s, d metres to the right of the path."""
        psi = self.heading(s)
        if abs(self.curvature) < 1e-12:
            x, z = 0.0, s
        else:
            r = 1.0 / self.curvature
            x, z = r * (1.0 - math.cos(psi)), r * math.sin(psi)
        return x + d * math.cos(psi), z - d * math.sin(psi)


def box(eid, cls, path, s, d, y, L, W, H, along=True, turn=0.0):
    """An upright box centred d metres right of the path at arc length s; L along the path."""
    x, z = path.point(s, d)
    theta = path.heading(s) - math.pi / 2 + turn if along else 0.0
    theta = math.atan2(math.sin(theta), math.cos(theta))
    return {"id": eid, "class": cls, "class_id": CLASS_IDS[cls], "x": round(x, 3),
            "y": round(y, 3), "z": round(z, 3), "L": round(L, 3), "W": round(W, 3),
            "H": round(H, 3), "theta": round(theta, 4), "confidence": 1.0, "method": "hand",
            "point_count": 0}


def parked_row(rng, s_from, s_to):
    """(kind, family, s_centre) along one kerb: vehicles with gaps, driveways, trees, poles."""
    items = []
    s = s_from
    while s < s_to:
        r = rng.random()
        if r < 0.08:  # a driveway: nobody parks
            s += rng.uniform(4.0, 8.0)
            continue
        if r < 0.16:
            items.append(("tree", None, s + 0.8))
            s += 1.6 + rng.uniform(0.3, 0.6)
            continue
        fam = rng.choices(FAMILIES, weights=[f[5] for f in FAMILIES])[0]
        items.append(("vehicle", fam, s + fam[2] / 2))
        gap = rng.uniform(0.4, 1.2)
        if rng.random() < 0.15:
            items.append(("pole", None, s + fam[2] + gap / 2))
        s += fam[2] + gap
    return items


def build_scene(seed, speed, yaw_rate_dps, length):
    rng = random.Random(seed)
    path = Path(speed, yaw_rate_dps)
    ents, counts = [], {}

    def add(cls, *args, **kw):
        counts[cls] = counts.get(cls, 0) + 1
        e = box(f"{cls}-{counts[cls]}", cls, *args, **kw)
        ents.append(e)
        return e

    s_end = length + 40.0
    straight = abs(path.curvature) < 1e-12
    pieces = [(-10.0 + 0.5 * (s_end + 10.0), s_end + 10.0)] if straight else [
        (s + SEGMENT / 2, SEGMENT + 0.05) for s in
        [-10.0 + SEGMENT * k for k in range(int((s_end + 10.0) / SEGMENT) + 1)]]
    for s, L in pieces:
        add("road", path, s, 0.0, ROAD_TOP_Y + 0.025, L, 2 * KERB, 0.05)
        for side in (-1, 1):
            add("sidewalk", path, s, side * (KERB + SIDEWALK / 2), ROAD_TOP_Y - 0.025, L,
                SIDEWALK, 0.15)
    for side in (-1, 1):
        s = -8.0
        while s < s_end:
            L, H = rng.uniform(10.0, 24.0), rng.uniform(8.0, 14.0)
            add("building", path, s + L / 2, side * (KERB + SIDEWALK + 5.0 + rng.uniform(0, 2)),
                ROAD_TOP_Y - 0.15 - H / 2, L, 10.0, H)
            s += L + rng.uniform(0.5, 3.0)
        for kind, fam, sc in parked_row(rng, rng.uniform(3.0, 5.0), s_end - 5.0):
            if kind == "tree":
                add("vegetation", path, sc, side * (KERB - 0.2), -1.2, 2.6, 2.6, 5.6)
            elif kind == "pole":
                add("pole", path, sc, side * (KERB - 0.35), -0.4, 0.25, 0.25, 4.0)
            else:
                name, sub, L, W, H = fam[:5]
                e = add("car", path, sc, side * (KERB - 0.2 - W / 2 + rng.uniform(-0.1, 0.15)),
                        ROAD_TOP_Y - H / 2, L, W, H,
                        turn=(0.0 if side > 0 else math.pi) + rng.uniform(-0.04, 0.04))
                e["subclass"] = sub
    if straight:
        # One car ahead in the camera's lane, a little faster; one oncoming in the other lane.
        for s0, d, v, turn in ((12.0, 0.0, speed + 1.0, 0.0),
                               (length * 0.6, -3.0, -rng.uniform(6.0, 10.0), math.pi)):
            e = add("car", path, s0, d, ROAD_TOP_Y - 0.725, 4.5, 1.8, 1.45, turn=turn)
            e["subclass"] = "car"
            e["velocity"] = {"vx": 0.0, "vz": round(v, 3)}
    return {
        "schema_version": "1.1.0",
        "frame": kitti_frame(f"drive-street-{seed}"),
        "source": {"tool": "scripts/make-drive-street.py",
                   "description": f"A {length:g} m street for a drive at {speed:g} m/s turning "
                                  f"{yaw_rate_dps:g} deg/s, seed {seed}: parked cars both sides, "
                                  "trees, poles, sidewalks, buildings"
                                  + (", a car ahead and one oncoming" if straight else "")
                                  + ". Render with scene-render sensors --frames N "
                                  f"--ego-speed {speed:g} --ego-yaw-rate {yaw_rate_dps:g}."},
        "entities": ents,
    }


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--seed", type=int, required=True, help="seed of the street (>= 0)")
    p.add_argument("--speed", type=float, default=8.0, help="the camera's speed, m/s (> 0)")
    p.add_argument("--yaw-rate", type=float, default=0.0,
                   help="the camera's yaw rate, degrees a second (+ turns right)")
    p.add_argument("--length", type=float, default=100.0, help="metres the camera drives")
    p.add_argument("-o", "--out", default="-", help="output entity file ('-' = stdout)")
    a = p.parse_args()
    if a.seed < 0:
        p.error("--seed must be >= 0")
    if not a.speed > 0:
        p.error("--speed must be > 0")
    if not 0 < a.length <= 1000:
        p.error("--length must be in (0, 1000]")
    if a.yaw_rate and abs(a.speed / math.radians(a.yaw_rate)) < 2 * (KERB + SIDEWALK + 15):
        p.error("--yaw-rate too large for --speed: the street's radius must be at least "
                f"{2 * (KERB + SIDEWALK + 15):g} m")
    write_entity_file(build_scene(a.seed, a.speed, a.yaw_rate, a.length), a.out)


if __name__ == "__main__":
    main()
