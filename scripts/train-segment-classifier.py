#!/usr/bin/python3
"""Trains one of the stereo-only path's segment classifiers on rendered streets, and scores it.

The stereo-only path cuts the obstacles standing on the road into segments and measures each
(`cloud-analysis --semantics geometry --segments-out`: its height, width, depth, colour,
texture, how rough its surface is in disparity; docs/stereo-only.md). This script renders
streets it may learn from, gives every segment nearer than --max-depth the truth's answer (a
vehicle when most of its pixels are a car in the rendered instance image; with --target person, a
person when most are a person), and trains OpenCV's random trees (cv2.ml.RTrees, the depth
chosen by 4-fold cross-validation over the training streets) to answer vehicle (person) or not.
It writes the model (--out) and prints, beside the rules' answers, its errors on data it never
learnt from:

- held-out streets: the held-out seeds of scripts/street-seeds.sh (parking, kerbside and
  pedestrian streets as scripts/evaluate.sh renders them, cars in the class colour) and verge
  streets of their own seeds (scripts/make-verge-street.py, cars in the world's paints);
- real frames, when ../shared/data is there: the KITTI frames with instance images, and the real
  drive against the project's hand-drawn boxes (samples/labels-2d; a segment is a vehicle or a
  person when its image box overlaps a labelled one's by IoU > 0.3).

Training data is rendered streets only, never a real image: the tuning seeds of
scripts/street-seeds.sh and the extra tuning seeds 43-106 (parking and kerbside streets), each
rendered twice, its cars in the world's paints (--paints world) and in the class colour, so that
no colour tells a vehicle; and verge streets of seeds 1..--verge-streets in the world's paints.
The person model learns instead of the extra tuning seeds and the development body from the
pedestrian streets of --extra-pedestrian-seeds (50-89, seeds no evaluation renders), twice like
the others.
With --rigs, the tuning streets also through other rigs (scene-render sensors --preset), where
the same street comes out in other segments, and the held-out streets through them are scored
apart.

usage: scripts/train-segment-classifier.py [--target vehicle|person] [--out FILE] [--work DIR]
           [--no-write] [--rigs "..."]
           [--verge-streets N] [--max-depth M] [--build-dir DIR] [--parking-seeds "2 4 ..."]
           [--kerbside-seeds ...] [--pedestrian-seeds ...] [--held-out-seeds ...]
           [--extra-seeds "43 44 ..."] [--extra-pedestrian-seeds "50 51 ..."]
           [--held-out-verge-seeds "101 102 ..."]
"""
import argparse
import glob
import json
import os
import re
import subprocess
import sys

import cv2
import numpy as np

from stereoscene_assets import class_ids, write_body_table

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.path.join(ROOT, "..", "shared", "data")
# Per target: the instance image's class of the target, and the rules' class name for it.
TARGETS = {"vehicle": (class_ids("cityscapes")["car"], "car"),
           "person": (class_ids("cityscapes")["person"], "person")}
HELD_OUT_VERGE_SEEDS = range(101, 116)
# The rigs of scene-render sensors --preset besides KITTI's (docs/cli.md "Any stereo rig"): the
# same street seen at other resolutions, focal lengths and baselines is cut into other segments.
OTHER_RIGS = ("cityscapes", "argoverse", "zed", "realsense")
# A segment is a vehicle when more than this share of the trees call it one: a majority, the
# forest's own rule (Breiman 2001); no threshold is fitted.
VOTE_THRESHOLD = 0.5
# What the classifier reads, in order (cloud_analysis/geometry/segment_classifier.hpp, the
# segments table's "features").
FEATURES = ["top_m", "top_q25_m", "low_m", "width_m", "thickness_m", "depth_m", "near_m", "far_m",
            "green", "occluded", "tall", "horizontal_edges", "top_spread_m", "depth_range_m",
            "area_m2", "chroma_r", "chroma_g", "chroma_b", "fill", "luma", "luma_cv", "grad",
            "rough_h", "rough_v", "disparity_spread"]


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"train-segment-classifier: {' '.join(cmd[:2])}: {r.stderr.strip()}")


def street_seeds():
    seeds = {}
    with open(os.path.join(ROOT, "scripts", "street-seeds.sh")) as f:
        for line in f:
            m = re.fullmatch(r'(\w+)="([\d ]*)"', line.strip())
            if m:
                seeds[m.group(1)] = m.group(2).split()
    return seeds


def render(a, name, make, seed, paints, classes=None, preset=None):
    """Renders a street (make: the generator's arguments) once into the work folder, with
    another class table (classes) or through another rig (preset) when given."""
    root = os.path.join(a.work, name)
    if not os.path.isdir(root):
        scene = root + ".json"
        run(["python3", os.path.join(ROOT, "scripts", make[0])] + make[1:] +
            ["--seed", str(seed), "-o", scene])
        run([a.scene_render, "sensors", scene, "--out", root + ".tmp", "--frame", "000000",
             "--seed", str(seed), "--paints", paints] + (["--classes", classes] if classes else []) +
            (["--preset", preset] if preset else []))
        os.rename(root + ".tmp", root)
    return root


def body_table(a, body):
    """A class table drawing cars with a third-party body (and trucks with the kit's truck), or
    None when the kit is not there."""
    kit = os.path.join(ROOT, "..", "shared", "gltf-thirdparty", "kenney-car-kit")
    if not os.path.isfile(os.path.join(kit, body + ".glb")):
        return None
    path = os.path.join(a.work, f"classes-{body}.json")
    write_body_table(kit, body, path)
    return path


def segments(a, key, args):
    """The segments of one frame (rules only) and the image of their indices, cached."""
    out = os.path.join(a.work, "segments", key)
    if not os.path.exists(out + ".json"):
        os.makedirs(os.path.dirname(out), exist_ok=True)
        run([a.cloud_analysis] + args + ["--semantics", "geometry", "--vehicle-classifier", "none",
                                          "--person-classifier",
                                          "none", "--segments-out", out + ".tmp.json",
                                          "--segment-ids-out", out + ".png"])
        os.rename(out + ".tmp.json", out + ".json")
    ids = cv2.imread(out + ".png", cv2.IMREAD_UNCHANGED).astype(np.int64)
    return json.load(open(out + ".json"))["segments"], ids


def rows_with_instances(a, name, root, frame):
    """(name, features, the target in the truth, the target by the rules) of each near
    segment."""
    segs, ids = segments(a, name, ["--kitti-root", root, "--frame", frame])
    truth = cv2.imread(os.path.join(root, "instance", frame + ".png"), cv2.IMREAD_UNCHANGED)
    if truth.shape != ids.shape:
        # Analysed at a reduced resolution (a 5 MP frame is halved): the pixel each analysed
        # pixel starts at, as the analysis picks its labels.
        step = truth.shape[1] // ids.shape[1]
        truth = truth[::step, ::step][:ids.shape[0], :ids.shape[1]]
    label_id, rules_class = TARGETS[a.target]
    target = (truth.astype(np.int64) >> 8) == label_id
    pixels = np.bincount(ids.ravel(), minlength=len(segs) + 1)
    hits = np.bincount(ids.ravel(), weights=target.ravel(), minlength=len(segs) + 1)
    return [(name, s["features"], int(hits[s["index"] + 1] > 0.5 * pixels[s["index"] + 1]),
             int(s["rules_class"] == rules_class)) for s in segs if s["depth_m"] < a.max_depth]


def iou(p, q):
    w = min(p[2], q[2]) - max(p[0], q[0])
    h = min(p[3], q[3]) - max(p[1], q[1])
    if w <= 0 or h <= 0:
        return 0.0
    inter = w * h
    return inter / ((p[2] - p[0]) * (p[3] - p[1]) + (q[2] - q[0]) * (q[3] - q[1]) - inter)


def rows_of_real_drive(a, drive, labels_file):
    labels = json.load(open(labels_file))
    # The 2D evaluator's categories (cloud_analysis/src/evaluation/labels_2d.cpp).
    types = (("person", "pedestrian", "person_sitting") if a.target == "person" else
             ("car", "van", "truck", "bus", "tram", "train"))
    boxes = {f["frame"]: [o["box"] for o in f["objects"] if o["type"].lower() in types]
             for f in labels["frames"]}
    rules_class = TARGETS[a.target][1]
    rows = []
    for left in sorted(glob.glob(os.path.join(drive, "image_2", "*.png"))):
        frame = os.path.basename(left)[:-4]
        segs, _ = segments(a, "drive-" + frame,
                           ["--left", left, "--right", os.path.join(drive, "image_3", frame + ".png"),
                            "--calib", os.path.join(drive, "calib.txt")])
        for s in segs:
            if s["depth_m"] >= a.max_depth:
                continue
            u0, v0, u1, v1 = s["box_px"]
            box = [u0, v0, u1 + 1, v1 + 1]
            labelled = any(iou(box, b) > 0.3 for b in boxes.get(frame, []))
            rows.append(("drive-" + frame, s["features"], int(labelled),
                         int(s["rules_class"] == rules_class)))
    return rows


def train(rows, depth):
    x = np.array([r[1] for r in rows], np.float32)
    y = np.array([r[2] for r in rows], np.int32).reshape(-1, 1)
    trees = cv2.ml.RTrees_create()
    trees.setMaxDepth(depth)
    trees.setMinSampleCount(5)
    trees.setTermCriteria((cv2.TERM_CRITERIA_MAX_ITER, 100, 0))
    cv2.setRNGSeed(1)
    trees.train(cv2.ml.TrainData_create(x, cv2.ml.ROW_SAMPLE, y))
    return trees


def target_votes(trees, rows):
    """Share of the trees calling each row the target (a vehicle, a person)."""
    if not rows:
        return np.zeros(0)
    votes = trees.getVotes(np.array([r[1] for r in rows], np.float32), 0)
    vehicle = votes[1:, list(votes[0]).index(1)] if 1 in votes[0] else np.zeros(len(rows))
    return vehicle / votes[1:].sum(axis=1)


def errors(rows, guess):
    truth = np.array([r[2] for r in rows], int)
    guess = np.asarray(guess, int)
    return int(truth.sum()), int(((guess == 1) & (truth == 0)).sum()), \
        int(((guess == 0) & (truth == 1)).sum())


def street(name):
    """The street a render shows: every render of a street falls in one fold."""
    for suffix in ("-world", "-sedan") + tuple("-" + rig for rig in OTHER_RIGS):
        if name.endswith(suffix):
            return street(name[:-len(suffix)])
    return name


def cross_validate(rows):
    """The trees' depth with the fewest errors (false targets plus missed ones) over 4 folds by
    street, a vehicle (person) being what a majority of the trees call one; and the guesses it
    makes."""
    names = sorted({street(r[0]) for r in rows})
    folds = [set(names[k::4]) for k in range(4)]
    best = None
    for depth in (5, 8, 12):
        votes = np.zeros(len(rows))
        for fold in folds:
            fit = [r for r in rows if street(r[0]) not in fold]
            test = [k for k, r in enumerate(rows) if street(r[0]) in fold]
            votes[test] = target_votes(train(fit, depth), [rows[k] for k in test])
        n, fp, fn = errors(rows, votes > VOTE_THRESHOLD)
        print(f"  depth {depth}: {fp} false, {fn} missed of {n} segments")
        if best is None or fp + fn < best[1]:
            best = (depth, fp + fn, votes > VOTE_THRESHOLD)
    return best[0], best[2]


def write_model(a, trees, threshold, depth, rows, rigs):
    """The trees beside their manifest (what they read, where a vehicle or person begins), each
    file written whole."""
    manifest = a.out
    folder = os.path.dirname(os.path.abspath(manifest))
    os.makedirs(folder, exist_ok=True)
    model = os.path.splitext(os.path.basename(manifest))[0] + ".yml.gz"
    trees.save(os.path.join(folder, "." + model + ".tmp.yml.gz"))
    os.replace(os.path.join(folder, "." + model + ".tmp.yml.gz"), os.path.join(folder, model))
    names = sorted({street(r[0]) for r in rows})
    streets = ("the tuning streets and the extra pedestrian streets" if a.target == "person" else
               "the tuning and extra tuning parking and kerbside streets")
    doc = {"format": f"stereoscene-{a.target}-classifier", "version": 1, "model": model,
           "features": FEATURES, "vote_threshold": threshold,
           "trained_on": f"{len(names)} rendered streets ({len(rows)} segments): {streets} in "
                         f"the world's paints and the class colour, verge streets in the world's "
                         f"paints"
                         + (f"; the tuning streets through the {', '.join(rigs)} rigs"
                            if rigs else "") + f"; random trees of depth {depth}, 100 trees",
           "command": "scripts/train-segment-classifier.py"
                      + (" --target person" if a.target == "person" else "")}
    with open(manifest + ".tmp", "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
    os.replace(manifest + ".tmp", manifest)
    print(f"\nwrote {manifest} and {model}", file=sys.stderr)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--target", choices=sorted(TARGETS), default="vehicle",
                    help="what the trees answer: vehicle or not, person or not")
    ap.add_argument("--out", help="the manifest to write; the trees go beside it (<name>.yml.gz)"
                                  " (default: assets/classifiers/<target>-segments.json)")
    ap.add_argument("--no-write", action="store_true", help="score only; write no model")
    ap.add_argument("--work", default=os.path.join(ROOT, "build", "segment-classifier"),
                    help="renders and segment tables, kept for the next run")
    ap.add_argument("--build-dir", default=os.path.join(ROOT, "build"))
    ap.add_argument("--verge-streets", type=int, default=60,
                    help="verge streets of seeds 1..N to learn from")
    seeds = street_seeds()
    for kind in ("parking_seeds", "kerbside_seeds", "pedestrian_seeds", "held_out_seeds"):
        ap.add_argument("--" + kind.replace("_", "-"), default=" ".join(seeds[kind]),
                        help="(default: scripts/street-seeds.sh's)")
    ap.add_argument("--extra-seeds", default=" ".join(str(s) for s in range(43, 107)),
                    help="more parking and kerbside streets to learn from (docs/evaluation.md's "
                         "extra tuning streets)")
    ap.add_argument("--no-development-body", dest="development_body", action="store_false",
                    help="leave out the tuning streets drawn with the Kenney sedan (learnt from "
                         "when ../shared/gltf-thirdparty is there)")
    ap.add_argument("--extra-pedestrian-seeds", default=" ".join(str(s) for s in range(50, 90)),
                    help="more pedestrian streets the person model learns from")
    ap.add_argument("--held-out-verge-seeds",
                    default=" ".join(str(s) for s in HELD_OUT_VERGE_SEEDS))
    ap.add_argument("--rigs", default="",
                    help="other rigs (scene-render sensors --preset: "
                         f"{', '.join(OTHER_RIGS)}) the tuning streets are also rendered through "
                         "and learnt from, in the world's paints; the held-out streets are scored "
                         "through them apart (default: none, KITTI's rig only, as the shipped "
                         "model was trained)")
    ap.add_argument("--max-depth", type=float, default=45.0,
                    help="segments nearer than this (median depth) are learnt and scored, m")
    a = ap.parse_args()
    if a.out is None:
        a.out = os.path.join(ROOT, "assets", "classifiers", f"{a.target}-segments.json")
    a.cloud_analysis = os.path.join(a.build_dir, "cloud_analysis", "cloud-analysis")
    a.scene_render = os.path.join(a.build_dir, "scene_viewer", "scene-render")
    os.makedirs(a.work, exist_ok=True)
    seeds = {k: getattr(a, k).split() for k in ("parking_seeds", "kerbside_seeds",
                                                 "pedestrian_seeds", "held_out_seeds")}
    kinds = (("parking-street", ["make-parking-scene.py"]),
             ("kerbside", ["make-parking-scene.py", "--kerbside"]),
             ("pedestrians", ["make-parking-scene.py", "--kerbside", "--pedestrians"]))
    seed_lists = {"parking-street": "parking_seeds", "kerbside": "kerbside_seeds",
                  "pedestrians": "pedestrian_seeds"}
    fit = []
    # The person model learns from more pedestrian streets instead of the extra parking and
    # kerbside streets (cars seen over and over) and the development body (another car).
    person = a.target == "person"
    extra = [] if person else a.extra_seeds.split()
    extra_pedestrians = a.extra_pedestrian_seeds.split() if person else []
    for kind, make in kinds:
        street_seeds_of_kind = seeds[seed_lists[kind]] + (
            extra if kind != "pedestrians" else extra_pedestrians)
        for s in street_seeds_of_kind:
            # Each street twice: its cars in the world's paints and in the class colour, so
            # that no colour tells a vehicle.
            for paints, name in (("world", f"{kind}-{s}-world"), ("class", f"{kind}-{s}")):
                fit += rows_with_instances(a, name, render(a, name, make, s, paints), "000000")
    for s in range(1, a.verge_streets + 1):
        name = f"verge-street-{s}"
        fit += rows_with_instances(
            a, name, render(a, name, ["make-verge-street.py"], s, "world"), "000000")
    # The development body of scripts/evaluate-vehicle-models.sh (its test bodies, the SUV and
    # the van, are never learnt from): the tuning streets once more with its cars.
    table = body_table(a, "sedan") if a.development_body and not person else None
    if table:
        for kind, make in kinds:
            for s in seeds[seed_lists[kind]]:
                name = f"{kind}-{s}-sedan"
                fit += rows_with_instances(a, name, render(a, name, make, s, "class", table),
                                           "000000")
    rigs = a.rigs.split()
    if set(rigs) - set(OTHER_RIGS):
        ap.error(f"--rigs: unknown rig (one of {', '.join(OTHER_RIGS)})")
    for rig in rigs:
        for kind, make in kinds:
            for s in seeds[seed_lists[kind]]:
                name = f"{kind}-{s}-{rig}"
                fit += rows_with_instances(a, name, render(a, name, make, s, "world", None, rig),
                                           "000000")
    if len({r[2] for r in fit}) < 2:
        sys.exit(f"train-segment-classifier: the training streets need {a.target} and other "
                 "segments to learn from")
    print(f"cross-validation over the {len({street(r[0]) for r in fit})} training streets "
          f"({len({r[0] for r in fit})} renders; 4 folds by street):")
    depth, cv_guess = cross_validate(fit)
    threshold = VOTE_THRESHOLD
    trees = train(fit, depth)

    checks = [(f"training streets ({len({street(r[0]) for r in fit})}, cross-validated)", fit,
               cv_guess)]
    held = []
    for kind, make in kinds:
        for s in seeds["held_out_seeds"]:
            name = f"{kind}-{s}"
            held += rows_with_instances(a, name, render(a, name, make, s, "class"), "000000")
    checks.append((f"held-out streets ({len(seeds['held_out_seeds']) * 3})", held, None))
    if rigs:
        held = []
        for rig in rigs:
            for kind, make in kinds:
                for s in seeds["held_out_seeds"]:
                    name = f"{kind}-{s}-{rig}"
                    held += rows_with_instances(
                        a, name, render(a, name, make, s, "world", None, rig), "000000")
        checks.append((f"held-out streets through {len(rigs)} other rigs "
                       f"({len(seeds['held_out_seeds']) * 3 * len(rigs)} renders)", held, None))
    verge = []
    held_out_verge = [int(s) for s in a.held_out_verge_seeds.split()]
    if set(held_out_verge) & set(range(1, a.verge_streets + 1)):
        ap.error("--held-out-verge-seeds overlap the training verge streets 1..--verge-streets")
    for s in held_out_verge:
        name = f"verge-street-{s}"
        verge += rows_with_instances(
            a, name, render(a, name, ["make-verge-street.py"], s, "world"), "000000")
    checks.append((f"held-out verge streets ({len(held_out_verge)})", verge, None))
    kitti = os.path.join(SHARED, "kitti15")
    frames = sorted(os.path.basename(p)[:-4] for p in glob.glob(os.path.join(kitti, "instance",
                                                                             "*.png")))
    if frames:
        rows = sum((rows_with_instances(a, "kitti-" + f, kitti, f) for f in frames), [])
        checks.append((f"KITTI frames ({len(frames)}, instance images)", rows, None))
    drive = os.path.join(SHARED, "kitti_odometry_02")
    if os.path.isdir(os.path.join(drive, "image_2")):
        rows = rows_of_real_drive(a, drive, os.path.join(ROOT, "samples", "labels-2d",
                                                         "kitti_odometry_02.json"))
        checks.append(("real drive (20 frames, hand-drawn boxes)", rows, None))

    t = a.target
    print(f"\nsegments nearer than {a.max_depth:g} m, {t} or not; trees of depth {depth}, a "
          f"{t} above {threshold:.2f} of their votes:\n")
    print(f"| data | {t} segments | rules: false {t}s | rules: missed | "
          f"trees: false {t}s | trees: missed |")
    print("|---|---|---|---|---|---|")
    for label, rows, guess in checks:
        guess = target_votes(trees, rows) > threshold if guess is None else guess
        n, rfp, rfn = errors(rows, [r[3] for r in rows])
        _, tfp, tfn = errors(rows, guess)
        print(f"| {label} | {n} | {rfp} | {rfn} | {tfp} | {tfn} |")
    if not a.no_write:
        write_model(a, trees, threshold, depth, fit, rigs)


if __name__ == "__main__":
    main()
