#!/usr/bin/python3
"""Writes a suburban road with grass verges as an entity file for `scene-render sensors`.

What a real road out of town shows the stereo pair, where most of what stands by the road is
not a vehicle: on each side a grass verge 1-6 m wide between the kerb and a back line of hedges
(the leafy hedge model), garden walls, fences and garages, with bushes and street trees (trunk
and crown) on the verge, parked bicycles against the hedges, poles and signs, and a few cars:
parked at the kerb, nose-in on a driveway, or driving in either lane. Houses stand behind. The
camera drives in the right-hand lane, 1.65 m above the road.

Everything is drawn from the seed. Vehicles are cars of four size families and vans; render with
`scene-render sensors --paints world` so that they are not all the class colour. Garages are
buildings 2.2-2.8 m tall (a garage door seen end-on is a van's back to stereo); bushes and
hedges are vegetation lower than they are long, drawn with the hedge model.

usage: scripts/make-verge-street.py --seed N [-o FILE]
"""
import argparse
import math
import random

from stereoscene_assets import class_ids, kitti_frame, write_entity_file

ROAD_TOP_Y = 1.60  # the road's top surface in the camera frame (y down), metres
VERGE_TOP_Y = ROAD_TOP_Y - 0.1  # the verge stands on a 0.1 m kerb
LANE_M = 3.5
CLASS_IDS = class_ids("cityscapes")
# (length, width, height) in metres and weight: small, sedan, estate, SUV, van.
VEHICLES = [((3.6, 1.65, 1.45), 2), ((4.5, 1.80, 1.45), 4), ((4.8, 1.82, 1.50), 2),
            ((4.7, 1.90, 1.72), 2), ((5.2, 2.00, 2.00), 1)]


def box(cls, x, y_bottom, z, L, W, H, theta=-math.pi / 2):
    """A box standing on y_bottom (camera frame, y down), L along the heading theta."""
    return {"class": cls, "class_id": CLASS_IDS[cls], "x": round(x, 3),
            "y": round(y_bottom - H / 2, 3), "z": round(z, 3), "L": round(L, 3),
            "W": round(W, 3), "H": round(H, 3), "theta": round(theta, 4), "confidence": 1.0,
            "method": "hand", "point_count": 0}


def vehicle(rng):
    sizes = [v[0] for v in VEHICLES]
    return rng.choices(sizes, weights=[v[1] for v in VEHICLES])[0]


def back_line(rng, side, x, z0, z1):
    """Hedges, walls, fences and garages along x from z0 to z1, with gaps (gates, drives)."""
    items = []
    z = z0
    while z < z1:
        kind = rng.choices(["hedge", "wall", "fence", "garage", "gap"], [5, 2, 2, 1, 2])[0]
        length = rng.uniform(3.0, 12.0)
        if kind == "hedge":
            height, thick = rng.uniform(0.8, 2.2), rng.uniform(0.6, 1.3)
            # Pieces of about 3 m: the hedge model keeps the size of its leaves.
            pieces = max(1, round(length / 3.0))
            for k in range(pieces):
                zc = z + (k + 0.5) * length / pieces
                h = height * rng.uniform(0.92, 1.08)
                items.append(box("vegetation", x + side * thick / 2, VERGE_TOP_Y, zc,
                                 length / pieces + 0.1, thick, h))
        elif kind == "wall":
            items.append(box("wall", x + side * 0.15, VERGE_TOP_Y, z + length / 2, length, 0.3,
                             rng.uniform(0.6, 1.8)))
        elif kind == "fence":
            items.append(box("fence", x + side * 0.05, VERGE_TOP_Y, z + length / 2, length, 0.1,
                             rng.uniform(1.0, 1.9)))
        elif kind == "garage":
            length = rng.uniform(3.0, 6.5)
            depth = rng.uniform(5.5, 7.0)
            items.append(box("building", x + side * (depth / 2 + 0.5), VERGE_TOP_Y,
                             z + length / 2, length, depth, rng.uniform(2.2, 2.8)))
        else:
            length = rng.uniform(2.5, 5.0)
        z += length + rng.uniform(0.0, 1.0)
    return items


def verge(rng, side, kerb_x, back_x, z0, z1, taken):
    """Bushes, street trees, poles, signs and parked bicycles on the verge, clear of the z
    ranges in `taken` (cars on driveways)."""
    items = []
    z = z0 + rng.uniform(0.0, 4.0)
    while z < z1:
        if any(a - 1.5 < z < b + 1.5 for a, b in taken):
            z += 1.0
            continue
        kind = rng.choices(["bush", "tree", "pole", "sign", "bicycle", "none"],
                           [4, 3, 1, 1, 1, 2])[0]
        room = abs(back_x - kerb_x)
        if kind == "bush" and room > 1.2:
            L, W, H = rng.uniform(0.8, 2.5), rng.uniform(0.7, 1.6), rng.uniform(0.5, 1.6)
            W = min(W, room - 0.3)
            H = min(H, 0.95 * max(L, W))  # a bush is lower than it is wide
            x = kerb_x + side * rng.uniform(0.2 + W / 2, room - W / 2)
            items.append(box("vegetation", x, VERGE_TOP_Y, z, L, W, H))
        elif kind == "tree":
            crown = rng.uniform(2.2, 4.5)
            x = kerb_x + side * min(room / 2, rng.uniform(0.8, 2.5))
            items.append(box("vegetation", x, VERGE_TOP_Y, z, crown, crown,
                             rng.uniform(4.5, 9.0), 0.0))
        elif kind == "pole":
            items.append(box("pole", kerb_x + side * 0.4, VERGE_TOP_Y, z, 0.25, 0.25,
                             rng.uniform(4.0, 7.0), 0.0))
        elif kind == "sign":
            items.append(box("traffic sign", kerb_x + side * 0.5, VERGE_TOP_Y, z, 0.1, 0.9,
                             rng.uniform(2.2, 3.0), 0.0 if side > 0 else math.pi))
        elif kind == "bicycle" and room > 1.0:
            x = back_x - side * 0.4
            items.append(box("bicycle", x, VERGE_TOP_Y, z, 1.75, 0.6, 1.05,
                             -math.pi / 2 + rng.uniform(-0.3, 0.3)))
        z += rng.uniform(3.0, 9.0)
    return items


def cars(rng, side, kerb_x, back_x, z0, z1):
    """A few cars: parked at the kerb (along the road), nose-in on a driveway across the verge,
    or driving in the lane nearest this side. Returns them and the z ranges the driveways take
    on the verge."""
    items, taken = [], []
    z = z0 + rng.uniform(2.0, 10.0)
    while z < z1:
        L, W, H = vehicle(rng)
        kind = rng.choices(["kerb", "driveway", "lane"], [5, 2, 2])[0]
        heading = -math.pi / 2 if side > 0 else math.pi / 2
        if kind == "kerb":
            x = kerb_x - side * (W / 2 + 0.2)
            items.append(box("car", x, ROAD_TOP_Y, z, L, W, H,
                             heading + rng.uniform(-0.05, 0.05)))
        elif kind == "driveway" and abs(back_x - kerb_x) > L + 0.3:
            x = kerb_x + side * (L / 2 + 0.3)
            turn = 0.0 if rng.random() < 0.5 else math.pi
            items.append(box("car", x, VERGE_TOP_Y, z, L, W, H, turn + rng.uniform(-0.1, 0.1)))
            taken.append((z - W / 2, z + W / 2))
        elif kind == "lane":  # ahead in the camera's lane, or oncoming in the other
            x = rng.uniform(-0.3, 0.3) - (LANE_M if side < 0 else 0.0)
            items.append(box("car", x, ROAD_TOP_Y, max(z, 12.0), L, W, H,
                             heading + rng.uniform(-0.03, 0.03)))
        z += L + rng.uniform(6.0, 25.0)
    return items, taken


def build_scene(seed):
    rng = random.Random(seed)
    right_kerb = LANE_M / 2 + rng.uniform(0.0, 0.5)
    left_kerb = -(1.5 * LANE_M + rng.uniform(0.0, 0.5))
    ents = [box("road", (right_kerb + left_kerb) / 2, ROAD_TOP_Y + 0.05, 30.0, 90.0,
                right_kerb - left_kerb, 0.05)]
    for side, kerb in ((+1, right_kerb), (-1, left_kerb)):
        width = rng.uniform(1.0, 6.0)
        back = kerb + side * width
        ents.append(box("terrain", kerb + side * (width / 2 + 4.0), VERGE_TOP_Y + 0.05, 30.0,
                        90.0, width + 8.0, 0.05))
        ents += back_line(rng, side, back, -5.0, 70.0)
        parked, taken = cars(rng, side, kerb, back, 0.0, 45.0)
        ents += parked + verge(rng, side, kerb, back, 0.0, 60.0, taken)
        z = rng.uniform(0.0, 10.0)
        while z < 80.0:  # houses behind the gardens
            length = rng.uniform(8.0, 14.0)
            setback = rng.uniform(8.0, 20.0)
            depth = rng.uniform(8.0, 11.0)
            ents.append(box("building", back + side * (setback + depth / 2), VERGE_TOP_Y,
                            z + length / 2, length, depth, rng.uniform(6.0, 10.0)))
            z += length + rng.uniform(4.0, 12.0)
    counts = {}
    for e in ents:
        counts[e["class"]] = counts.get(e["class"], 0) + 1
        e["id"] = f"{e['class'].replace(' ', '-')}-{counts[e['class']]}"
    return {
        "schema_version": "1.0.0",
        "frame": kitti_frame(f"verge-street-{seed}"),
        "source": {"tool": "scripts/make-verge-street.py",
                   "description": f"Verge street, seed {seed}: a two-lane road with grass "
                                  "verges, hedges, walls, fences and garages behind them, "
                                  "bushes, trees, poles, signs and bicycles on them, a few "
                                  "cars parked, on driveways or driving. Camera 1.65 m above "
                                  "the road, in the right-hand lane."},
        "entities": ents,
    }


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--seed", type=int, required=True, help="seed of the street (>= 0)")
    p.add_argument("-o", "--out", default="-", help="output entity file ('-' = stdout)")
    a = p.parse_args()
    if a.seed < 0:
        p.error("--seed must be >= 0")
    write_entity_file(build_scene(a.seed), a.out)


if __name__ == "__main__":
    main()
