#!/usr/bin/env python3
"""Compares the rendered-street results of two or more scripts/evaluate.sh outputs.

Usage: scripts/compare-evaluations.py [--streets] BEFORE.txt AFTER.txt [MORE.txt ...]

Reads each output's per-street verdicts (the "bars (car within 30 m)" line after each
"--- street (...)" header) and prints one Markdown table: per set (tuning, held out) and path
(semantic image, stereo only), each file's streets meeting their bars, spurious cars, the
median of the streets' median centre errors and the streets over 0.3 m. With --streets, also
every street whose verdict, spurious count or centre error (by more than 0.03 m) differs
from the first file's. Streets missing from a file are left out of its cells.
"""
import re
import statistics
import sys

HEADER = re.compile(r"^--- (\S+) \(([^)]*)\)(, stereo only)?")
BARS = re.compile(r"bars \(car within 30 m\): recall ([\d.]+), spurious (\d+).*"
                  r"median centre error ([\d.]+) m.*: (PASS|FAIL)")


def parse(path):
    """{(street, path, set): (recall, spurious, centre error, verdict)}"""
    streets, key = {}, None
    with open(path, encoding="utf-8") as f:
        for line in f:
            m = HEADER.match(line)
            if m:
                key = (m.group(1), "stereo only" if m.group(3) else "semantic image",
                       "held out" if "held out" in m.group(2) else "tuning")
                continue
            m = BARS.search(line)
            if m and key:
                streets[key] = (float(m.group(1)), int(m.group(2)), float(m.group(3)),
                                m.group(4))
                key = None
    return streets


def cell(result, keys):
    keys = [k for k in keys if k in result]
    if not keys:
        return "-"
    passing = sum(result[k][3] == "PASS" for k in keys)
    spurious = sum(result[k][1] for k in keys)
    errors = [result[k][2] for k in keys]
    over = sum(e > 0.3 for e in errors)
    return (f"{passing}/{len(keys)} pass, {spurious} spurious, "
            f"{statistics.median(errors):.3f} m, {over} over 0.3 m")


def main(argv):
    show_streets = "--streets" in argv
    files = [a for a in argv if a != "--streets"]
    if len(files) < 2:
        sys.exit("compare-evaluations.py: error: usage: compare-evaluations.py [--streets] "
                 "BEFORE.txt AFTER.txt [MORE.txt ...]")
    results = []
    for path in files:
        try:
            results.append(parse(path))
        except OSError as e:
            sys.exit(f"compare-evaluations.py: error: {path}: {e.strerror}")
        if not results[-1]:
            sys.exit(f"compare-evaluations.py: error: {path}: no street verdicts "
                     "(not an evaluate.sh output?)")
    print("| set | path | " + " | ".join(files) + " |")
    print("|---|---|" + "---|" * len(files))
    for group in ("tuning", "held out"):
        for path in ("semantic image", "stereo only"):
            keys = sorted({k for r in results for k in r if k[1] == path and k[2] == group})
            if keys:
                print(f"| {group} | {path} | " +
                      " | ".join(cell(r, keys) for r in results) + " |")
    if not show_streets:
        return
    first = results[0]
    for path, result in zip(files[1:], results[1:]):
        print(f"\nstreets that differ, {files[0]} -> {path}:")
        for key in sorted(set(first) & set(result)):
            a, b = first[key], result[key]
            if a[3] != b[3] or a[1] != b[1] or abs(a[2] - b[2]) > 0.03:
                print(f"  {key[0]} ({key[2]}, {key[1]}): {a[3]} spurious {a[1]} "
                      f"{a[2]:.3f} m -> {b[3]} spurious {b[1]} {b[2]:.3f} m")


if __name__ == "__main__":
    main(sys.argv[1:])
