#!/usr/bin/env python3
"""Would a learned classifier class the stereo-only path's segments better than its rules?

Runs `cloud-analysis --semantics geometry --segments-out --segment-ids-out` on rendered scenes
(with their ground-truth instance images) and on KITTI frames, gives every segment the class
most of its pixels have in the truth, and compares, for the question that makes entities (car
or not, segments nearer than --max-depth), the rules' classes with OpenCV's random trees
(cv2.ml.RTrees) trained on the segments' measurements:

- tuning scenes: the trees' depth chosen by 4-fold cross-validation over scenes, and their
  errors in that cross-validation;
- held-out scenes and check frames: trees trained on every tuning scene, never on these.

Rendered scenes come from a `scripts/evaluate.sh --out DIR` run (DIR/rendered/<name>/) with the
same seeds as evaluate.sh, plus the committed samples; KITTI frames from --kitti. Nothing is
written but the table on stdout. Needs python3-opencv and numpy (scripts/install-deps.sh).

usage: scripts/segment-classifier.py --evaluate-dir DIR [--kitti DIR] [--frames F ...]
           [--cloud-analysis EXE] [--max-depth M] [--parking-seeds "2 4 ..."]
           [--kerbside-seeds "2 3 ..."] [--pedestrian-seeds "2 3 ..."]
           [--held-out-seeds "13 14 ..."]
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

import cv2
import numpy as np

from stereoscene_assets import class_ids

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Cityscapes labelIds (instance PNG: labelId << 8 | n) counted as a car: the entities' class.
CAR_LABEL_ID = class_ids("cityscapes")["car"]
FEATURES = ["top_m", "top_q25_m", "low_m", "width_m", "thickness_m", "depth_m", "near_m",
            "far_m", "green", "occluded", "tall", "cells", "horizontal_edges"]


def features(s):
    f = [float(s[k]) for k in FEATURES]
    # Scale-free forms: the top's spread, the depth range, the surface seen (pixels * z^2 / f^2
    # up to the focal length, the same for every rig here).
    f += [s["top_m"] - s["top_q25_m"], s["far_m"] - s["near_m"], s["pixels"] * s["depth_m"] ** 2]
    return f


def segments_of(exe, root, frame, work):
    """The segments of one frame, each with its measurements and the truth's share of car."""
    table = os.path.join(work, "segments.json")
    ids_png = os.path.join(work, "ids.png")
    run = subprocess.run([exe, "--kitti-root", root, "--frame", frame, "--semantics", "geometry",
                          "--segments-out", table, "--segment-ids-out", ids_png],
                         capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"segment-classifier: {root} {frame}: {run.stderr.strip()}")
    segments = json.load(open(table))["segments"]
    ids = cv2.imread(ids_png, cv2.IMREAD_UNCHANGED).astype(np.int64)
    instance = cv2.imread(os.path.join(root, "instance", frame + ".png"), cv2.IMREAD_UNCHANGED)
    if instance is None:
        sys.exit(f"segment-classifier: {root}: no instance/{frame}.png (the truth)")
    car = (instance.astype(np.int64) >> 8) == CAR_LABEL_ID
    pixels = np.bincount(ids.ravel(), minlength=len(segments) + 1)
    car_pixels = np.bincount(ids.ravel(), weights=car.ravel(), minlength=len(segments) + 1)
    for s in segments:
        n = pixels[s["index"] + 1]
        s["car_share"] = car_pixels[s["index"] + 1] / n if n else 0.0
    return segments


def dataset(exe, scenes, max_depth):
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for name, root, frame in scenes:
            for s in segments_of(exe, root, frame, work):
                if s["depth_m"] < max_depth:
                    rows.append((name, features(s), 1 if s["car_share"] > 0.5 else 0,
                                 1 if s["class"] == "car" else 0))
    return rows


def arrays(rows):
    x = np.array([r[1] for r in rows], np.float32)
    y = np.array([r[2] for r in rows], np.int32)
    return x, y


def train(rows, depth):
    x, y = arrays(rows)
    trees = cv2.ml.RTrees_create()
    trees.setMaxDepth(depth)
    trees.setMinSampleCount(5)
    trees.setTermCriteria((cv2.TERM_CRITERIA_MAX_ITER, 200, 0))
    cv2.setRNGSeed(1)
    trees.train(cv2.ml.TrainData_create(x, cv2.ml.ROW_SAMPLE, y.reshape(-1, 1)))
    return trees


def predict(trees, rows):
    return trees.predict(arrays(rows)[0])[1].ravel().astype(int)


def counts(truth, guess):
    truth, guess = np.asarray(truth), np.asarray(guess)
    return (int(truth.sum()), int(((guess == 1) & (truth == 1)).sum()),
            int(((guess == 1) & (truth == 0)).sum()), int(((guess == 0) & (truth == 1)).sum()))


def street_seeds():
    """The default seed lists, shared with evaluate.sh (scripts/street-seeds.sh)."""
    seeds = {}
    with open(os.path.join(ROOT, "scripts", "street-seeds.sh")) as f:
        for line in f:
            m = re.fullmatch(r'(\w+)="([\d ]*)"', line.strip())
            if m:
                seeds[m.group(1)] = m.group(2)
    return seeds


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--evaluate-dir",
                    help="the --out folder of a scripts/evaluate.sh run (its rendered/ streets); "
                         "needed unless every seed list is empty")
    ap.add_argument("--kitti", default=os.path.join(ROOT, "..", "shared", "data", "kitti15"))
    ap.add_argument("--frames", nargs="*", default=["000000_10", "000001_10"])
    ap.add_argument("--cloud-analysis",
                    default=os.path.join(ROOT, "build", "cloud_analysis", "cloud-analysis"))
    ap.add_argument("--max-depth", type=float, default=30.0,
                    help="segments nearer than this (median depth), metres")
    seeds = street_seeds()
    ap.add_argument("--parking-seeds", default=seeds["parking_seeds"])
    ap.add_argument("--kerbside-seeds", default=seeds["kerbside_seeds"])
    ap.add_argument("--pedestrian-seeds", default=seeds["pedestrian_seeds"])
    ap.add_argument("--held-out-seeds", default=seeds["held_out_seeds"])
    a = ap.parse_args()
    seeds = (a.parking_seeds.split() + a.kerbside_seeds.split() + a.pedestrian_seeds.split() +
             a.held_out_seeds.split())
    if seeds and not a.evaluate_dir:
        ap.error("--evaluate-dir is needed for the seeds' streets (or give empty seed lists)")
    rendered = os.path.join(a.evaluate_dir or ".", "rendered")
    committed = os.path.join(ROOT, "samples", "rendered")
    tuning = [(n, os.path.join(committed, n), "000000") for n in sorted(os.listdir(committed))
              if os.path.isdir(os.path.join(committed, n, "instance"))]
    tuning += [(f"parking-street-{s}", os.path.join(rendered, f"parking-street-{s}"), "000000")
               for s in a.parking_seeds.split()]
    tuning += [(f"kerbside-{s}", os.path.join(rendered, f"kerbside-{s}"), "000000")
               for s in a.kerbside_seeds.split()]
    tuning += [(f"pedestrians-{s}", os.path.join(rendered, f"pedestrians-{s}"), "000000")
               for s in a.pedestrian_seeds.split()]
    held = [(f"{k}-{s}", os.path.join(rendered, f"{k}-{s}"), "000000")
            for s in a.held_out_seeds.split() for k in ("parking-street", "kerbside", "pedestrians")]
    checks = [(f"KITTI {f}", a.kitti, f) for f in a.frames
              if os.path.exists(os.path.join(a.kitti, "instance", f + ".png"))]
    for name, root, _ in tuning + held:
        if not os.path.isdir(root):
            sys.exit(f"segment-classifier: {root} missing: run scripts/evaluate.sh --out "
                     f"{a.evaluate_dir} first (same seeds)")

    tune_rows = dataset(a.cloud_analysis, tuning, a.max_depth)
    if not any(r[2] for r in tune_rows):
        sys.exit("segment-classifier: the tuning scenes hold no car segment to learn from")
    names = sorted({r[0] for r in tune_rows})
    folds = [names[k::4] for k in range(4)]
    best = None
    print(f"cross-validation over the {len(names)} tuning scenes (4 folds by scene):")
    for depth in (3, 5, 8):
        guess = np.zeros(len(tune_rows), int)
        for fold in folds:
            fit = [r for r in tune_rows if r[0] not in fold]
            test = [k for k, r in enumerate(tune_rows) if r[0] in fold]
            guess[test] = predict(train(fit, depth), [tune_rows[k] for k in test])
        n, tp, fp, fn = counts([r[2] for r in tune_rows], guess)
        print(f"  depth {depth}: {fp} false cars, {fn} missed of {n} car segments")
        if best is None or fp + fn < best[1]:
            best = (depth, fp + fn, guess)
    depth, _, cv_guess = best
    trees = train(tune_rows, depth)

    print(f"\nsegments nearer than {a.max_depth:g} m, car (most pixels car in the truth) or not;"
          f" trees of depth {depth}:\n")
    print("| data | car segments | rules: false cars | rules: missed | trees: false cars | "
          "trees: missed |")
    print("|---|---|---|---|---|---|")
    for label, rows, guess in (
            (f"tuning ({len(tuning)} rendered, cross-validated)", tune_rows, cv_guess),
            (f"held out ({len(held)} rendered)", None, None),
            (f"KITTI checks ({len(checks)} frames)", None, None)):
        if rows is None:
            rows = dataset(a.cloud_analysis, held if label.startswith("held") else checks,
                           a.max_depth)
            guess = predict(trees, rows) if rows else []
        truth = [r[2] for r in rows]
        n, _, rfp, rfn = counts(truth, [r[3] for r in rows])
        _, _, tfp, tfn = counts(truth, guess)
        print(f"| {label} | {n} | {rfp} | {rfn} | {tfp} | {tfn} |")


if __name__ == "__main__":
    main()
