#!/usr/bin/env python3
"""Writes a hard parking street as an entity file for `scene-render sensors`, from a seed.

A 12 m street, the camera 1.65 m above its centre line, both sides parked bumper to bumper
with 0.3-1.0 m gaps from about 4 m to 40 m ahead (grazing angles at 30-35 m), a mix of
lengths (3.6 m small cars, sedans, estates, SUVs, 5.2 m vans: all class car; one truck, one
bus), a van 15-20 m ahead on the right seen from behind-left, a street tree standing in each
parked row and poles at the kerb between cars, sidewalks and buildings behind. The same seed
gives the same file byte for byte. Render it with label bleed in the semantic image:

    scripts/make-parking-scene.py --seed 1 -o parking.json
    scene-render sensors parking.json --out out --label-bleed 3 --seed 1

With --kerbside nobody parks on the right from 12 m to 32 m: garden walls with pillars (some
with a pierced coping) before front gardens, hedges, a post box among bollards, bins and a
bicycle stand on the sidewalk there (docs/evaluation.md "Kerbside streets").

With --pedestrians as well (kerbside streets only), groups of one to three people stand
together on that sidewalk, some beside a pole, some under a street tree's crown: people side by side are as wide and as tall as
a car's back, which stereo alone must tell apart. The rest of the street is the same as with
--kerbside alone.

Every car carries its size family in `subclass` (car, van); the truck and the bus are their
own classes. docs/evaluation.md "Hard parking streets" describes how they are scored.
"""
import argparse
import math
import random

from stereoscene_assets import class_ids, kitti_frame, write_entity_file

ROAD_TOP_Y = 1.60  # the road's top surface in the camera frame (y down), metres
ROW_X = 4.9  # parked cars' centre line from the street's centre, metres
KERB_X = 6.0  # kerb: edge of the road, metres

# Size families (length, width, height in metres) and how often each appears in a row.
FAMILIES = [
    ("small", "car", 3.6, 1.65, 1.45, 2),
    ("sedan", "car", 4.5, 1.80, 1.45, 4),
    ("estate", "car", 4.8, 1.82, 1.50, 2),
    ("suv", "car", 4.7, 1.90, 1.72, 2),
    ("van", "van", 5.2, 2.00, 2.00, 1),
]
VAN = FAMILIES[4]
TRUCK = ("truck", "truck", 7.5, 2.40, 3.20)
BUS = ("bus", "bus", 11.0, 2.55, 3.20)
CLASS_IDS = class_ids("cityscapes")
SIDEWALK_BACK_X = 9.0  # the sidewalk's far edge (the buildings' side), metres


def stuff(eid, cls, x, y, z, L, W, H, theta=-math.pi / 2):
    return {"id": eid, "class": cls, "class_id": CLASS_IDS[cls], "x": x, "y": y, "z": z,
            "L": L, "W": W, "H": H, "theta": theta, "confidence": 1.0, "method": "hand",
            "point_count": 0}


def pick_family(rng):
    weights = [f[5] for f in FAMILIES]
    return rng.choices(FAMILIES, weights=weights)[0]


def row(rng, side, z_start, z_end, specials):
    """One parked row: a list of (kind, family, z_centre). specials: {index: family or kind}.

    Vehicles follow each other from z_start with gaps of 0.3-1.0 m; a 'tree' slot is 1.6 m of
    kerb with a tree, a 'pole' stands in the gap before the vehicle that follows it."""
    items = []
    z = z_start
    i = 0
    while z < z_end:
        spec = specials.get(i)
        if spec == "tree":
            items.append(("tree", None, z + 0.8))
            z += 1.6 + rng.uniform(0.3, 0.6)
            i += 1
            continue
        fam = spec if isinstance(spec, tuple) else pick_family(rng)
        length = fam[2]
        items.append(("vehicle", fam, z + length / 2))
        gap = rng.uniform(0.3, 1.0)
        if rng.random() < 0.2:
            items.append(("pole", None, z + length + gap / 2))
        z += length + gap
        i += 1
    return items


def place_van(rng, items, z_lo, z_hi):
    """Makes the vehicle whose centre is nearest a random z in [z_lo, z_hi] a van, shifting the
    vehicles behind it to keep their gaps."""
    target = rng.uniform(z_lo, z_hi)
    vehicles = [k for k, it in enumerate(items) if it[0] == "vehicle" and it[1][1] != "truck"
                and it[1][1] != "bus"]
    k = min(vehicles, key=lambda k: abs(items[k][2] - target))
    kind, fam, zc = items[k]
    grow = VAN[2] - fam[2]
    items[k] = (kind, VAN, zc + grow / 2)
    for j in range(k + 1, len(items)):
        items[j] = (items[j][0], items[j][1], items[j][2] + grow)


def kerbside(rng, z_start, z_end):
    """Kerbside clutter on the right sidewalk from z_start to z_end, where nobody parks: garden
    walls with pillars (some with a pierced coping of short blocks) before front gardens,
    hedges, a post box among bollards, bins, a parked bicycle. Returns (class, x, y, z, L, W, H)
    boxes, L along the street."""
    items = []
    z = z_start
    while z < z_end:
        kind = rng.choice(["wall", "wall", "hedge", "postbox", "bins", "bicycle"])
        if kind == "wall":
            length = rng.uniform(3.0, 7.0)
            height = rng.uniform(0.8, 1.4)
            x = SIDEWALK_BACK_X - 0.4
            items.append(("wall", x, height / 2, z + length / 2, length, 0.3, height))
            pillars = max(2, int(length / 2.5) + 1)
            for k in range(pillars):
                zp = z + 0.2 + k * (length - 0.4) / (pillars - 1)
                items.append(("wall", x, (height + 0.3) / 2, zp, 0.45, 0.45, height + 0.3))
            if rng.random() < 0.5:  # a pierced coping: short blocks with gaps on top
                zc = z + 0.5
                while zc < z + length - 0.5:
                    items.append(("wall", x, height + 0.125, zc + 0.15, 0.3, 0.25, 0.25))
                    zc += 0.45
            z += length
        elif kind == "hedge":
            length = rng.uniform(2.0, 5.0)
            height = rng.uniform(1.0, 1.5)
            items.append(("vegetation", SIDEWALK_BACK_X - 0.6, height / 2, z + length / 2, length,
                          1.0, height))
            z += length
        elif kind == "postbox":
            items.append(("static", KERB_X + 0.6, 0.575, z + 1.5, 0.5, 0.5, 1.15))
            for k in range(rng.randint(2, 4)):
                items.append(("pole", KERB_X + 0.25, 0.45, z + 0.3 + 1.2 * k, 0.12, 0.12, 0.9))
            z += 1.2 * 4
        elif kind == "bins":
            for k in range(2):
                items.append(("static", KERB_X + 0.7, 0.6, z + 0.4 + 0.75 * k, 0.7, 0.6, 1.2))
            z += 2.0
        else:
            items.append(("bicycle", KERB_X + 0.8, 0.525, z + 0.9, 1.75, 0.6, 1.05))
            z += 2.0
        z += rng.uniform(0.5, 2.5)
    # Each item's third value is its centre's height above the sidewalk, whose top is 0.15 m
    # above the road's; y is the box centre's (camera frame, y down).
    return [(c, round(x, 3), round(ROAD_TOP_Y - 0.15 - h, 3), round(zc, 3), round(L, 3), W,
             round(H, 3)) for c, x, h, zc, L, W, H in items]


def pedestrians(rng, z_start, z_end):
    """Groups of one to three people standing together on the right sidewalk between the
    kerbside clutter and the walls, side by side along the street, a pole beside some groups and
    a street tree behind some, its crown over their heads. Returns (class, x, y, z, L, W, H)
    boxes like kerbside()."""
    items = []
    z = z_start + rng.uniform(0.0, 3.0)
    while z < z_end:
        x = KERB_X + 1.45 + rng.uniform(-0.1, 0.1)
        for k in range(rng.randint(1, 3)):
            height = rng.uniform(1.6, 1.85)
            items.append(("person", x + rng.uniform(-0.1, 0.1), ROAD_TOP_Y - 0.15 - height / 2,
                          z + 0.6 * k, 0.3, 0.55, height))
        if rng.random() < 0.5:
            items.append(("pole", KERB_X + 0.3, ROAD_TOP_Y - 0.15 - 2.0, z - 0.6, 0.2, 0.2, 4.0))
        if rng.random() < 0.5:  # a street tree behind them, its crown over their heads
            items.append(("vegetation", KERB_X + 2.1, ROAD_TOP_Y - 0.15 - 2.8, z + 0.6, 2.6, 2.6,
                          5.6))
        z += rng.uniform(4.0, 8.0)
    return [(c, round(x, 3), round(y, 3), round(zc, 3), L, W, round(H, 3))
            for c, x, y, zc, L, W, H in items]


def build_scene(seed, with_kerbside=False, with_pedestrians=False):
    rng = random.Random(seed)
    ents = [
        stuff("road-1", "road", 0.0, 1.625, 30.0, 80.0, 12.0, 0.05),
        stuff("sidewalk-1", "sidewalk", -7.5, 1.575, 30.0, 80.0, 3.0, 0.15),
        stuff("sidewalk-2", "sidewalk", 7.5, 1.575, 30.0, 80.0, 3.0, 0.15),
        stuff("building-1", "building", -14.0, -3.5, 20.0, 30.0, 10.0, 10.0),
        stuff("building-2", "building", -14.0, -4.5, 50.0, 28.0, 10.0, 12.0),
        stuff("building-3", "building", 14.0, -4.0, 18.0, 26.0, 10.0, 11.0),
        stuff("building-4", "building", 14.0, -5.5, 46.0, 28.0, 10.0, 14.0),
    ]
    things = []
    occluders = []
    # Right row: parked along the traffic (heading +z, seen from behind-left); the van
    # 15-20 m ahead, the truck after 24 m. Left row: facing the camera; the bus last.
    right = row(rng, +1, rng.uniform(2.5, 4.5), 38.0,
                {rng.randint(1, 2): "tree"})
    place_van(rng, right, 15.0, 20.0)
    clutter = []
    if with_kerbside:
        # Nobody parks on the right from about 12 m to 32 m: the kerbside shows.
        right = [it for it in right if it[2] + (it[1][2] / 2 if it[1] else 0.8) < 12.0]
        clutter = kerbside(rng, 12.5, 32.0)
        # Front gardens behind the walls: the right-hand buildings stand 2-5 m farther back.
        setback = rng.uniform(2.0, 5.0)
        for e in ents:
            if e["id"] in ("building-3", "building-4"):
                e["x"] = round(e["x"] + setback, 3)
    for k, it in enumerate(right):
        if it[0] == "vehicle" and it[2] > 25.0 and it[1][1] != "van":
            grow = TRUCK[2] - it[1][2]
            right[k] = ("vehicle", TRUCK, it[2] + grow / 2)
            right = right[:k + 1]
            break
    left = row(rng, -1, rng.uniform(3.0, 5.0), 30.0, {rng.randint(3, 4): "tree"})
    last_end = max(it[2] + (it[1][2] / 2 if it[1] else 0.8) for it in left)
    bus_gap = rng.uniform(0.5, 1.0)
    left.append(("vehicle", BUS, last_end + bus_gap + BUS[2] / 2))
    for side, items, heading in ((+1, right, -math.pi / 2), (-1, left, math.pi / 2)):
        for kind, fam, zc in items:
            if kind == "tree":
                occluders.append(("vegetation", side * (ROW_X - 0.2), -1.2, zc, 2.6, 2.6, 5.6))
            elif kind == "pole":
                occluders.append(("pole", side * (KERB_X - 0.35), -0.4, zc, 0.25, 0.25, 4.0))
            else:
                name, cls, L, W, H = fam[0], fam[1], fam[2], fam[3], fam[4]
                things.append({
                    "class": "car" if cls in ("car", "van") else cls,
                    "subclass": cls, "family": name,
                    "x": round(side * (KERB_X - 0.2 - W / 2 + rng.uniform(-0.1, 0.15)), 3),
                    "y": round(ROAD_TOP_Y - H / 2, 3), "z": round(zc, 3),
                    "L": L, "W": W, "H": H,
                    "theta": round(heading + rng.uniform(-0.04, 0.04), 4)})
    counts = {}
    for t in sorted(things, key=lambda t: (t["class"], t["z"], t["x"])):
        cls = t["class"]
        counts[cls] = counts.get(cls, 0) + 1
        e = stuff(f"{cls}-{counts[cls]}", cls, t["x"], t["y"], t["z"], t["L"], t["W"], t["H"],
                  t["theta"])
        if cls == "car":
            e["subclass"] = t["subclass"]
        ents.append(e)
    for cls, x, y, z, L, W, H in sorted(occluders, key=lambda o: (o[0], o[3])):
        counts[cls] = counts.get(cls, 0) + 1
        ents.append(stuff(f"{cls}-{counts[cls]}", cls, round(x, 3), y, round(z, 3), L, W, H,
                          0.0))
    for cls, x, y, z, L, W, H in clutter:
        counts[cls] = counts.get(cls, 0) + 1
        ents.append(stuff(f"{cls}-{counts[cls]}", cls, x, y, z, L, W, H))
    if with_pedestrians:
        # A generator of their own: the street around them stays the kerbside street's.
        for cls, x, y, z, L, W, H in pedestrians(random.Random(f"pedestrians-{seed}"), 12.5,
                                                 30.0):
            counts[cls] = counts.get(cls, 0) + 1
            ents.append(stuff(f"{cls}-{counts[cls]}", cls, x, y, z, L, W, H, 0.0))
    name = f"kerbside-{seed}" if with_kerbside else f"parking-street-{seed}"
    if with_pedestrians:
        name = f"pedestrians-{seed}"
    return {
        "schema_version": "1.0.0",
        "frame": kitti_frame(name),
        "source": {"tool": "scripts/make-parking-scene.py",
                   "description": f"Parking street, seed {seed}: both sides parked bumper to "
                                  "bumper (gaps 0.3-1.0 m) 3-40 m ahead, small cars to vans, "
                                  "a truck on the right and a bus on the left, a van 15-20 m "
                                  "ahead on the right seen from behind-left, street trees and "
                                  "poles between the cars. Camera 1.65 m above the road."
                                  + (" Kerbside: nobody parks on the right from 12 m to 32 m; "
                                     "walls, hedges, a post box, bollards, bins and a bicycle "
                                     "stand on the sidewalk." if with_kerbside else "")
                                  + (" Groups of one to three people stand on that sidewalk, "
                                     "some beside a pole, some under a tree."
                                     if with_pedestrians else "")},
        "entities": ents,
    }


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--seed", type=int, required=True, help="seed of the street (>= 0)")
    p.add_argument("--kerbside", action="store_true",
                   help="nobody parks on the right from 12 m to 32 m: garden walls (with "
                        "pillars, some with a pierced coping), hedges, a post box among "
                        "bollards, bins and a bicycle stand on the sidewalk instead, the "
                        "buildings behind them 2-5 m back")
    p.add_argument("--pedestrians", action="store_true",
                   help="with --kerbside: groups of one to three people stand on that "
                        "sidewalk, some beside a pole, some under a tree")
    p.add_argument("-o", "--out", default="-", help="output entity file ('-' = stdout)")
    a = p.parse_args()
    if a.seed < 0:
        p.error("--seed must be >= 0")
    if a.pedestrians and not a.kerbside:
        p.error("--pedestrians needs --kerbside (the people stand where nobody parks)")
    write_entity_file(build_scene(a.seed, a.kerbside, a.pedestrians), a.out)


if __name__ == "__main__":
    main()
