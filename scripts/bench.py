#!/usr/bin/python3
"""Benchmarks of cloud-analysis and scene-render (docs/performance.md); a benchmark, never a test.

usage: scripts/bench.py --build BUILD_DIR [--out out/bench] [--runs 5] [--batch-frames 100]
                        [--parts table,batch,presets,scaling,matchers,odometry,profile]
                        [--plots docs/images]

table    per-stage medians of `cloud-analysis bench` (entities; entities + three clouds), for
         frames from memory (as from a camera: the stages after decoding) and from PNG files
         (including decode), beside the OpenCV matcher alone on the same input in the same
         process, the ratio, fps, peak RSS; for a KITTI-size synthetic pair made on the fly and
         ../shared/data/kitti15 frames; plus `scene-render bench` rows (50 entities, 1280x720).
batch    `cloud-analysis batch` over BATCH_FRAMES frames (the available frames repeated): fps,
         resident memory per frame and its mean per block of 10 frames.
presets  tuned / fast / quality: D1-all on kitti15 (--gt-disparity) and the car numbers of
         `cloud-analysis evaluate`, beside the matcher and pipeline time.
scaling  time vs pixels (1/4, 1/2, 1, 2 x KITTI) and vs disparities (64..256); scene-render vs
         entities (10..10000); PNG plots into --plots.
matchers the project's census SGM (--matcher sgm) beside cv::StereoSGBM: both timed interleaved
         in one `cloud-analysis bench` process (wall and CPU ms), and their D1-all and car
         recall/precision from `evaluate`, on kitti15 and the rendered samples, per preset.
odometry the real drive's batch with and without --odometry, and the odometry alone.
profile  `perf record` over a batch of the real drive (stereo only) and of the KITTI frames
         (semantic images): each stage's share of the CPU time and the top symbols (self time).
         Only when asked (--parts profile) and perf is installed.
Everything goes to OUT/bench.json and a Markdown table on stdout. Reads shared data in place.
"""
import argparse
import json
import os
import pathlib
import re
import statistics
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
KITTI = ROOT.parent / "shared" / "data" / "kitti15"
KITTI_FRAMES = ["000000_10", "000001_10"]  # frames with semantic_rgb and disp_occ_0
RENDERED = ROOT / "samples" / "rendered"
RENDERED_SCENES = ["street", "parking-row", "thesis-one-car"]


def log(*a):
    print(*a, file=sys.stderr, flush=True)


def run(cmd, **kw):
    log("$", " ".join(str(c) for c in cmd))
    return subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)


def make_sample(tool, folder, width, height):
    """Synthetic pair of the given size (fx scaled from KITTI's 721.5 at 1242 px)."""
    folder = pathlib.Path(folder)
    if not (folder / "left.png").exists():
        fx = 721.5 * width / 1242.0
        r = run([tool, "make-sample", "--out", folder, "--width", width, "--height", height,
                 "--fx", f"{fx:.3f}"])
        if r.returncode != 0:
            sys.exit(r.stderr)
    return ["--left", folder / "left.png", "--right", folder / "right.png",
            "--semantic", folder / "semantic.png", "--calib", folder / "calib.yaml"]


def kitti_layout_of(sample, folder, frame="synthetic_10"):
    """A KITTI-layout folder holding the synthetic pair (for `batch`)."""
    folder = pathlib.Path(folder)
    for sub, name in [("image_2", "left.png"), ("image_3", "right.png"),
                      ("semantic_rgb", "semantic.png"), ("calib", "calib.yaml")]:
        (folder / sub).mkdir(parents=True, exist_ok=True)
        ext = ".txt" if sub == "calib" else ".png"
        target = folder / sub / (frame + ext)
        if not target.exists():
            target.symlink_to(pathlib.Path(sample).resolve() / name)
    return folder


def bench(tool, inputs, work, runs, extra=()):
    work.mkdir(parents=True, exist_ok=True)
    r = run([tool, "bench", *inputs, *extra, "--work-dir", work, "--runs", runs, "--json", "-"])
    if r.returncode != 0:
        sys.exit(f"cloud-analysis bench failed: {r.stderr}")
    return json.loads(r.stdout)


ROW = re.compile(r"^(lit fxaa|lit msaa \d+|lit none|semantic)\s+(\d+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)")


def render_bench(render, entities=50, frames=30, extra=()):
    r = run([render, "bench", "--entities", entities, "--frames", frames, *extra])
    if r.returncode != 0:
        log(f"scene-render bench failed: {r.stderr.strip()}")
        return []
    rows = []
    for line in (r.stdout + r.stderr).splitlines():
        m = ROW.match(line.strip())
        if m:
            rows.append({"shading": m[1], "triangles": int(m[2]), "ms_per_frame": float(m[3]),
                         "min_ms": float(m[4]), "fps": float(m[5]), "png_ms": float(m[6]),
                         "png_kib": float(m[7])})
    return rows


def stage(row, name):
    return sum(s["ms"] for s in row["stages"] if s["stage"] == name)


def part_table(a, tool, render, result):
    inputs = {"synthetic 1242x375": make_sample(tool, a.out / "kitti-size", 1242, 375)}
    if (KITTI / "image_2").is_dir():
        for f in KITTI_FRAMES:
            inputs[f"kitti15 {f}"] = ["--kitti-root", KITTI, "--frame", f]
        # The same real frames through the stereo-only path (classes from the geometry).
        for f in KITTI_FRAMES:
            inputs[f"kitti15 {f}, stereo only"] = ["--kitti-root", KITTI, "--frame", f,
                                                   "--semantics", "geometry"]
    table = []
    for name, args in inputs.items():
        b = bench(tool, args, a.out / "work", a.runs)
        b["input"] = name
        table.append(b)
    result["cloud_analysis"] = table
    print("\n### cloud-analysis, one frame (median of %d runs after a warm-up)\n" % a.runs)
    print("memory = frames from memory (as from a camera): stages after decoding; "
          "files = frames from PNG files (including decode). Same process, same matcher floor.\n")
    print("| input | frames from | output | load | matcher alone | disparity stage | "
          "classes (semantic or geometry) + reproject | entities | entity write | clouds (format+write) | total ms | "
          "CPU ms | fps | pipeline / matcher | peak RSS MB |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for b in table:
        for row in b["rows"]:
            clouds = sum(s["ms"] for s in row["stages"]
                         if s["stage"].startswith(("format --", "write --x", "write --p")))
            load = f"{stage(row, 'load'):.1f}" if row["input"] == "files" else "-"
            print(f"| {b['input']} | {row['input']} | {row['row']} | {load} | "
                  f"{b['matcher_ms']:.1f} | {stage(row, 'disparity'):.1f} | "
                  f"{stage(row, 'semantic') + stage(row, 'geometry') + stage(row, 'reproject'):.1f} | "
                  f"{stage(row, 'entities'):.1f} | {stage(row, 'write --entities'):.1f} | "
                  f"{clouds:.1f} | {row['total_ms']:.1f} | {row['cpu_ms']:.1f} | "
                  f"{row['fps']:.1f} | {row['ratio_to_matcher']:.2f} | {b['peak_rss_mb']:.0f} |")
    if render:
        rows = render_bench(render, 50, a.render_frames)
        result["scene_render"] = rows
        print("\n### scene-render bench (50 entities, 1280x720, readback)\n")
        print("| shading | triangles | ms/frame | fps | PNG ms | PNG KiB |")
        print("|---|---|---|---|---|---|")
        for r in rows:
            print(f"| {r['shading']} | {r['triangles']} | {r['ms_per_frame']:.1f} | "
                  f"{r['fps']:.1f} | {r['png_ms']:.1f} | {r['png_kib']:.1f} |")


def part_batch(a, tool, result):
    sample = a.out / "kitti-size"
    make_sample(tool, sample, 1242, 375)
    roots = [(kitti_layout_of(sample, a.out / "synthetic-kitti"), ["synthetic_10"])]
    if (KITTI / "image_2").is_dir():
        roots.append((KITTI, KITTI_FRAMES))
    result["batch"] = []
    print(f"\n### cloud-analysis batch, {a.batch_frames} frames\n")
    print("| frames from | preset | method | fps | CPU ms per frame | cores busy % | "
          "load average | main thread waited ms per frame (loader / finisher) | "
          "RSS first / median / last frame MB | peak RSS MB |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for root, frames in roots:
        for preset, method, extra in [("tuned", "instances", []), ("tuned", "centroid", []),
                                      ("fast", "instances", []),
                                      ("tuned", "instances", ["--track"]),
                                      ("tuned", "instances", ["--matcher", "sgm"]),
                                      ("fast", "instances", ["--matcher", "sgm"])]:
            out = a.out / "batch"
            out.mkdir(parents=True, exist_ok=True)
            listing = out / "frames.txt"
            listing.write_text("\n".join(frames[i % len(frames)]
                                         for i in range(a.batch_frames)) + "\n")
            report = out / "report.json"
            load = os.getloadavg()[0]
            r = run([tool, "batch", "--kitti-root", root, "--list", listing, "--out-dir", out,
                     "--preset", preset, "--method", method, "--report", report, *extra])
            if r.returncode != 0:
                sys.exit(f"batch failed: {r.stderr}")
            rep = json.loads(report.read_text())
            rss = [f["rss_mb"] for f in rep["per_frame"]]
            rep_short = {k: v for k, v in rep.items() if k != "per_frame"}
            waits = [sum(f.get(k, 0.0) for f in rep["per_frame"]) / len(rep["per_frame"])
                     for k in ("wait_load_ms", "wait_finish_ms")]
            rep_short.update(root=str(root), method=method, rss_mb=rss, load_average=load,
                             wait_load_ms=waits[0], wait_finish_ms=waits[1])
            result["batch"].append(rep_short)
            src = "synthetic 1242x375" if "synthetic" in str(root) else "kitti15 " + "+".join(frames)
            name = preset + (" + sgm" if "sgm" in extra else "") + (" + track" if "--track" in extra else "")
            rep_short["label"] = f"{src}, {name}, {method}"
            print(f"| {src} | {name} | {method} | {rep['fps']:.2f} | "
                  f"{rep['cpu_ms_per_frame']:.0f} | {100 * rep['cores_busy']:.0f} | {load:.1f} | "
                  f"{waits[0]:.1f} / {waits[1]:.1f} | "
                  f"{rss[0]:.0f} / "
                  f"{statistics.median(rss):.0f} / {rss[-1]:.0f} | {rep['peak_rss_mb']:.0f} |")
    blocks = (a.batch_frames + 9) // 10
    print("\nMean RSS per block of 10 frames, MB\n")
    print("| row | " + " | ".join(f"{10 * k + 1}-{min(10 * k + 10, a.batch_frames)}"
                                  for k in range(blocks)) + " |")
    print("|---|" + "---|" * blocks)
    for rep in result["batch"]:
        rss = rep["rss_mb"]
        means = [statistics.mean(rss[10 * k:10 * k + 10]) for k in range(blocks)]
        print(f"| {rep['label']} | " + " | ".join(f"{m:.0f}" for m in means) + " |")


def part_presets(a, tool, result):
    if not (KITTI / "image_2").is_dir():
        log("presets: ../shared/data/kitti15 missing, skipped")
        return
    result["presets"] = []
    print("\n### presets on kitti15 (accuracy from --gt-disparity and `evaluate`)\n")
    print("| preset | frame | matcher ms | pipeline ms (entities, from memory) | D1-all % | "
          "density % | car recall | car precision (scorable) | centre dist m |")
    print("|---|---|---|---|---|---|---|---|---|")
    out = a.out / "presets"
    out.mkdir(parents=True, exist_ok=True)
    for preset in ["tuned", "fast", "quality"]:
        for f in KITTI_FRAMES:
            b = bench(tool, ["--kitti-root", KITTI, "--frame", f], a.out / "work", 3,
                      ["--preset", preset])
            ent, disp = out / f"{preset}-{f}.json", out / f"{preset}-{f}.png"
            r = run([tool, "--kitti-root", KITTI, "--frame", f, "--preset", preset, "-o", ent,
                     "--disparity-kitti", disp])
            if r.returncode != 0:
                sys.exit(r.stderr)
            ev = out / f"{preset}-{f}-eval.json"
            r = run([tool, "evaluate", "--entities", ent, "--disparity", disp,
                     "--kitti-root", KITTI, "--frame", f, "--json", ev])
            if r.returncode not in (0, 3):
                sys.exit(r.stderr)
            e = json.loads(ev.read_text())
            d, c = e["disparity"], e["cars"]
            row = {"preset": preset, "frame": f, "matcher_ms": b["matcher_ms"],
                   "pipeline_ms": b["rows"][0]["total_ms"], "d1_all": d["d1_all"],
                   "density": d["density"], "recall": c["recall"], "precision": c["precision"],
                   "precision_scorable": c["precision_scorable"],
                   "centre_m": c["mean_centre_distance_m"]}
            result["presets"].append(row)
            print(f"| {preset} | {f} | {row['matcher_ms']:.1f} | {row['pipeline_ms']:.1f} | "
                  f"{100 * row['d1_all']:.2f} | {100 * row['density']:.1f} | "
                  f"{c['gt_owed_matched']}/{c['gt_owed']} | {100 * c['precision']:.0f} % "
                  f"({100 * c['precision_scorable']:.0f} %) | {row['centre_m']:.2f} |")


def matcher_accuracy(tool, root, frame, reference, flags, out):
    """D1-all and car recall/precision of one run (`evaluate`; rendered scenes by their truth)."""
    tag = "-".join([root.name, frame] + [f.strip("-") for f in flags])
    ent, disp, ev = out / f"{tag}.json", out / f"{tag}.png", out / f"{tag}-eval.json"
    r = run([tool, "--kitti-root", root, "--frame", frame, *flags, "-o", ent,
             "--disparity-kitti", disp])
    if r.returncode != 0:
        sys.exit(r.stderr)
    cmd = [tool, "evaluate", "--entities", ent, "--disparity", disp, "--kitti-root", root,
           "--frame", frame, "--json", ev]
    if reference:
        cmd += ["--reference", reference, "--min-visible-fraction", "0.25"]
    r = run(cmd)
    if r.returncode not in (0, 3):
        sys.exit(r.stderr)
    e = json.loads(ev.read_text())
    if reference:
        car = e["entities"]["classes"]["car"]["bins"]["all"]
        recall, precision = car["recall"], car["precision"]
    else:
        recall, precision = e["cars"]["recall"], e["cars"]["precision"]
    return {"d1_all": e["disparity"]["d1_all"], "density": e["disparity"]["density"],
            "car_recall": recall, "car_precision": precision}


def part_matchers(a, tool, result):
    inputs = [(RENDERED / s, "000000", RENDERED / "scenes" / f"{s}.json")
              for s in RENDERED_SCENES]
    if (KITTI / "image_2").is_dir():
        inputs += [(KITTI, f, None) for f in KITTI_FRAMES]
    result["matchers"] = []
    print("\n### census SGM (--matcher sgm) beside cv::StereoSGBM, timed in one process\n")
    print("| input | preset | SGBM ms | SGM ms | speed-up | SGBM CPU ms | SGM CPU ms | "
          "D1-all % SGBM / SGM | car recall SGBM / SGM | car precision SGBM / SGM |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    out = a.out / "matchers"
    out.mkdir(parents=True, exist_ok=True)
    for preset in ["tuned", "fast"]:
        for root, frame, reference in inputs:
            b = bench(tool, ["--kitti-root", root, "--frame", frame], a.out / "work", a.runs,
                      ["--preset", preset, "--matcher", "sgm"])
            acc = [matcher_accuracy(tool, root, frame, reference,
                                    ["--preset", preset, "--matcher", m], out)
                   for m in ("sgbm", "sgm")]
            row = {"input": f"{root.name} {frame}", "preset": preset,
                   "sgbm_ms": b["reference_matcher_ms"], "sgm_ms": b["matcher_ms"],
                   "sgbm_cpu_ms": b["reference_matcher_cpu_ms"], "sgm_cpu_ms": b["matcher_cpu_ms"],
                   "sgbm": acc[0], "sgm": acc[1]}
            result["matchers"].append(row)
            pair = lambda k, scale=1.0, fmt=".2f": (f"{scale * acc[0][k]:{fmt}} / "
                                                    f"{scale * acc[1][k]:{fmt}}")
            print(f"| {row['input']} | {preset} | {row['sgbm_ms']:.1f} | {row['sgm_ms']:.1f} | "
                  f"{row['sgbm_ms'] / row['sgm_ms']:.2f} | {row['sgbm_cpu_ms']:.1f} | "
                  f"{row['sgm_cpu_ms']:.1f} | {pair('d1_all', 100.0)} | "
                  f"{pair('car_recall')} | {pair('car_precision')} |")


def part_scaling(a, tool, render, result):
    sizes = [(621, 188, "1/4"), (878, 265, "1/2"), (1242, 375, "1"), (1756, 530, "2")]
    scaling = {"size": [], "disparities": [], "entities": []}
    for w, h, label in sizes:
        args = make_sample(tool, a.out / f"sample-{w}x{h}", w, h)
        # Pixels alone: the range fitted to each size's focal length would change it too.
        b = bench(tool, args, a.out / "work", 3, ["--num-disparities", 128])
        row = b["rows"][0]
        scaling["size"].append({"pixels": w * h, "label": f"{label} ({w}x{h})",
                                "matcher_ms": b["matcher_ms"], "total_ms": row["total_ms"],
                                "disparity_ms": stage(row, "disparity"),
                                "entities_ms": stage(row, "entities")})
    args = make_sample(tool, a.out / "kitti-size", 1242, 375)
    for n in [64, 128, 192, 256]:
        b = bench(tool, args, a.out / "work", 3, ["--num-disparities", n])
        row = b["rows"][0]
        scaling["disparities"].append({"num_disparities": n, "matcher_ms": b["matcher_ms"],
                                       "total_ms": row["total_ms"],
                                       "disparity_ms": stage(row, "disparity")})
    if render:
        for n in [10, 100, 1000, 10000]:
            rows = render_bench(render, n, 3 if n >= 1000 else 10)
            lit = [r for r in rows if r["shading"] == "lit none"] or rows[:1]
            if lit:
                scaling["entities"].append({"entities": n, **lit[0]})
    result["scaling"] = scaling
    print("\n### scaling\n")
    print("| image | pixels | matcher ms | pipeline ms (entities, from memory) |")
    print("|---|---|---|---|")
    for s in scaling["size"]:
        print(f"| {s['label']} | {s['pixels']} | {s['matcher_ms']:.1f} | {s['total_ms']:.1f} |")
    print("\n| disparities | matcher ms | pipeline ms (entities, from memory) |")
    print("|---|---|---|")
    for s in scaling["disparities"]:
        print(f"| {s['num_disparities']} | {s['matcher_ms']:.1f} | {s['total_ms']:.1f} |")
    if scaling["entities"]:
        print("\n| entities | triangles | ms/frame (lit, no MSAA) | PNG ms |")
        print("|---|---|---|---|")
        for s in scaling["entities"]:
            print(f"| {s['entities']} | {s['triangles']} | {s['ms_per_frame']:.1f} | "
                  f"{s['png_ms']:.1f} |")
    if a.plots:
        plot(scaling, pathlib.Path(a.plots))


def plot(scaling, folder):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    folder.mkdir(parents=True, exist_ok=True)

    fig, ax = plt.subplots(figsize=(5, 3.5))
    px = [s["pixels"] / 1e3 for s in scaling["size"]]
    ax.plot(px, [s["matcher_ms"] for s in scaling["size"]], "o-", label="matcher alone")
    ax.plot(px, [s["total_ms"] for s in scaling["size"]], "s-",
            label="pipeline (entities, from memory)")
    ax.set_xlabel("image size, kilopixels (1/4, 1/2, 1, 2 x KITTI)")
    ax.set_ylabel("ms per frame")
    ax.set_title("cloud-analysis vs image size (128 disparities)")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(folder / "perf_size.png", dpi=100)

    fig, ax = plt.subplots(figsize=(5, 3.5))
    nd = [s["num_disparities"] for s in scaling["disparities"]]
    ax.plot(nd, [s["matcher_ms"] for s in scaling["disparities"]], "o-", label="matcher alone")
    ax.plot(nd, [s["total_ms"] for s in scaling["disparities"]], "s-",
            label="pipeline (entities, from memory)")
    ax.set_xlabel("number of disparities")
    ax.set_ylabel("ms per frame")
    ax.set_title("cloud-analysis vs disparities (1242x375)")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(folder / "perf_disparities.png", dpi=100)

    if scaling["entities"]:
        fig, ax = plt.subplots(figsize=(5, 3.5))
        ne = [s["entities"] for s in scaling["entities"]]
        ax.loglog(ne, [s["ms_per_frame"] for s in scaling["entities"]], "o-",
                  label="render + readback")
        ax.loglog(ne, [s["png_ms"] for s in scaling["entities"]], "s-", label="PNG encode")
        ax.set_xlabel("entities (glTF cars)")
        ax.set_ylabel("ms per frame")
        ax.set_title("scene-render vs entities (1280x720, llvmpipe)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(folder / "perf_entities.png", dpi=100)


def part_odometry(a, tool, result):
    """The real drive with and without --odometry: what the odometry costs beside the rest of
    the frame (CPU time per frame, same process) and how far it drifts (evaluate-odometry)."""
    drive = KITTI.parent / "kitti_odometry_02"
    if not (drive / "image_2").is_dir():
        log(f"no real drive at {drive}: odometry rows skipped")
        return
    out = a.out / "odometry"
    out.mkdir(parents=True, exist_ok=True)
    pairs = out / "pairs.txt"
    pairs.write_text("".join(f"{p} {drive / 'image_3' / p.name}\n"
                             for p in sorted((drive / "image_2").glob("*.png"))))
    rows = {}
    for name, extra in [("without", []), ("with --odometry", ["--odometry"])]:
        cpu, fps = [], []
        for _ in range(a.runs):
            report = out / "report.json"
            r = run([tool, "batch", "--pairs", pairs, "--calib", drive / "calib.txt",
                     "--out-dir", out, "-q", "--report", report, *extra])
            if r.returncode != 0:
                sys.exit(f"batch failed: {r.stderr}")
            rep = json.loads(report.read_text())
            cpu.append(rep["cpu_ms_per_frame"])
            fps.append(rep["fps"])
        rows[name] = (statistics.median(cpu), statistics.median(fps))
    score = run([tool, "evaluate-odometry", "--poses", out / "poses.txt", "--truth",
                 drive / "poses.txt", "--json", "-"])
    errors = json.loads(score.stdout)
    # The odometry alone, in the process that ran the matcher (bench --next-left): every
    # fifth frame pair of the drive, a median of --runs each, the odometry moved from the frame
    # before first (--prev-left), as in the batch after its first frame.
    lefts = sorted((drive / "image_2").glob("*.png"))
    alone = []
    for prev, left, next_left in list(zip(lefts, lefts[1:], lefts[2:]))[::5]:
        r = run([tool, "bench", "--left", left, "--right", drive / "image_3" / left.name,
                 "--calib", drive / "calib.txt", "--next-left", next_left,
                 "--prev-left", prev, "--prev-right", drive / "image_3" / prev.name,
                 "--work-dir", out, "--runs", str(a.runs), "--json", "-"])
        if r.returncode != 0:
            sys.exit(f"bench failed: {r.stderr}")
        b = json.loads(r.stdout)
        alone.append((left.stem, b["odometry_cpu_ms"], b["odometry_ms"], b["matcher_cpu_ms"]))
    result["odometry"] = {"cpu_ms_per_frame": {k: v[0] for k, v in rows.items()},
                          "fps": {k: v[1] for k, v in rows.items()}, "errors": errors,
                          "alone": [dict(zip(("frame", "cpu_ms", "wall_ms", "matcher_cpu_ms"), x))
                                    for x in alone]}
    print(f"\n### Odometry on the real drive ({drive.name}, 20 frames, medians of {a.runs} runs)\n")
    print("| batch | CPU ms per frame | fps |")
    print("|---|---|---|")
    for name, (c, f) in rows.items():
        print(f"| {name} | {c:.1f} | {f:.1f} |")
    print("\n| frame pair from | odometry CPU ms | odometry wall ms | matcher CPU ms |")
    print("|---|---|---|---|")
    for frame, cpu, wall, matcher in alone:
        print(f"| {frame} | {cpu:.1f} | {wall:.1f} | {matcher:.1f} |")
    extra = rows["with --odometry"][0] - rows["without"][0]
    print(f"\nThe odometry's own cost: {extra:.1f} ms of CPU a frame in the batch, "
          f"{statistics.median(x[1] for x in alone):.1f} ms alone (bench --next-left, median of "
          f"the pairs). Drift: translation "
          f"{errors['translation_pct']:.2f} % and rotation {errors['rotation_deg_per_m']:.4f} deg/m "
          f"over the segments, end point {errors['end_point_m']:.2f} m = "
          f"{errors['end_point_pct']:.2f} % of {errors['path_m']:.1f} m.")


# Where a symbol's CPU time goes: the first stage whose pattern its shared object or name holds
# (self time; std:: templates inlined into a stage count as that stage, the others as "other").
PROFILE_STAGES = [
    ("matcher (StereoSGBM, census SGM)", ("libopencv_calib3d", "DisparityMatcher", "stereo::",
                                          "census", "sgm")),
    ("PNG decoding", ("libdeflate", "libpng", "libz.so", "decode_png", "read_image", "imgcodecs")),
    ("stereo-only classes (geometry, trees)", ("geometry::", "libopencv_ml")),
    ("reprojection", ("reproject", "RowReprojector", "take_points", "depth_edge_band",
                      "scan_chunks", "write_points", "points_by_class", "copy_to_classes")),
    ("entities (clusters, boxes, rows)", ("instances::", "euclidean_clusters", "voxelize",
                                          "CellTable", "fit_", "lshape", "weighted_", "quantile",
                                          "select_two", "far_end", "closeness", "extract",
                                          "suppress", "footprint", "dominant_face", "ground",
                                          "count_near_plane", "classify_pixels", "row_")),
    ("odometry and tracking", ("odometry::", "tracking::")),
    ("entity file and clouds (format, write)", ("put_fixed", "xyz_lines", "format_", "json",
                                                "entity_", "write_")),
    ("kernel (I/O, page faults, threads)", ("[kernel]",)),
    ("memory (memset, memmove, malloc)", ("memset", "memmove", "memcpy", "malloc", "free",
                                          "_int_", "unlink_chunk", "_M_fill")),
    ("loading the program and the trees", ("ld-linux", "FileStorage", "RTrees")),
    ("thread pools (TBB, OpenCV parallel_for)", ("libtbb", "parallel_for", "ThreadPool",
                                                 "TaskQueue")),
]


def profile_stage(dso, symbol):
    text = dso + " " + symbol
    for stage_name, patterns in PROFILE_STAGES:
        if any(pat in text for pat in patterns):
            return stage_name
    return "other"


def readable_symbol(symbol):
    """A symbol short enough for a table: a lambda run by a thread pool (std::function) named
    by the function it is written in, anonymous namespaces and template arguments left out."""
    if symbol.startswith("std::_Function_handler"):
        names = [n for n in re.findall(r"(\w+)\(", symbol)
                 if n not in ("void", "for_each_chunk", "for_stripes", "parallel_for_")]
        if names:
            return f"(a thread's share of) {names[0]}"
    symbol = symbol.replace("(anonymous namespace)::", "")
    while True:
        shorter = re.sub(r"<[^<>]*>", "", symbol)
        if shorter == symbol:
            break
        symbol = shorter
    return symbol if len(symbol) <= 70 else symbol[:67] + "..."


def perf_profile(cmd, data):
    """Self-time shares (percent) of `cmd` by stage and its top symbols, from `perf record`
    (2999 samples a second per thread, all threads); None when it fails."""
    r = run(["perf", "record", "-F", "2999", "-o", data, "--", *cmd])
    if r.returncode != 0:
        log(f"perf record failed: {r.stderr.strip()[-300:]}")
        return None
    rep = run(["perf", "report", "-i", data, "--no-children", "--sort", "dso,symbol",
               "--stdio", "-g", "none"])
    line = re.compile(r"^\s*([\d.]+)%\s+(\S+)\s+\[(.)\]\s+(.+?)\s*$")
    stages, symbols = {}, {}
    for text in rep.stdout.splitlines():
        m = line.match(text)
        if not m:
            continue
        share, dso, kind = float(m[1]), m[2], m[3]
        symbol = re.split(r"\s{2,}", m[4].strip())[0]
        dso = "[kernel]" if kind == "k" else dso
        name = profile_stage(dso, symbol)
        stages[name] = stages.get(name, 0.0) + share
        symbol = "(no symbols: all of it)" if symbol.startswith("0x") else readable_symbol(symbol)
        key = (dso, symbol, name)
        symbols[key] = symbols.get(key, 0.0) + share
    top = sorted(((v,) + k for k, v in symbols.items()), reverse=True)[:15]
    return stages, top


def part_profile(a, tool, result):
    """Where a frame's CPU time goes, by `perf record` over whole batches (all threads): the
    real drive from its stereo pairs alone and the KITTI frames with their semantic images."""
    if run(["perf", "--version"]).returncode != 0:
        log("perf not installed (Debian: linux-perf): profile rows skipped")
        return
    jobs = []
    drive = KITTI.parent / "kitti_odometry_02"
    out = a.out / "profile"
    out.mkdir(parents=True, exist_ok=True)
    if (drive / "image_2").is_dir():
        lefts = sorted((drive / "image_2").glob("*.png"))
        pairs = out / "pairs.txt"
        pairs.write_text("".join(f"{p} {drive / 'image_3' / p.name}\n" for p in lefts))
        jobs.append((f"real drive, stereo only, batch of its {len(lefts)} frames",
                     [tool, "batch", "--pairs", pairs, "--calib", drive / "calib.txt",
                      "--out-dir", out / "drive", "-q"]))
    if (KITTI / "image_2").is_dir():
        listing = out / "frames.txt"
        listing.write_text("\n".join(KITTI_FRAMES[i % 2] for i in range(50)) + "\n")
        jobs.append(("KITTI frames with semantic images, batch of 50 frames",
                     [tool, "batch", "--kitti-root", KITTI, "--list", listing,
                      "--out-dir", out / "kitti", "-q"]))
    result["profile"] = []
    for label, cmd in jobs:
        got = perf_profile(cmd, out / "perf.data")
        if got is None:
            return
        stages, symbols = got
        result["profile"].append({"label": label, "stages": stages,
                                  "top_symbols": [dict(zip(("percent", "dso", "symbol", "stage"),
                                                           s)) for s in symbols]})
        print(f"\n### CPU profile: {label}\n")
        print("| stage | share of CPU time % |")
        print("|---|---|")
        for name, share in sorted(stages.items(), key=lambda kv: -kv[1]):
            print(f"| {name} | {share:.1f} |")
        print("\n| symbol (self time) | shared object | stage | % |")
        print("|---|---|---|---|")
        for share, dso, symbol, name in symbols:
            print(f"| `{symbol}` | {dso} | {name} | {share:.1f} |")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--build", type=pathlib.Path, required=True)
    p.add_argument("--out", type=pathlib.Path, default=ROOT / "out" / "bench")
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--batch-frames", type=int, default=100)
    p.add_argument("--render-frames", type=int, default=30)
    p.add_argument("--parts", default="table,batch,presets,scaling,matchers,odometry")
    p.add_argument("--plots", default="")
    p.add_argument("--render", type=pathlib.Path, help="scene-render binary (default: BUILD's)")
    a = p.parse_args()
    a.out = a.out.resolve()
    a.out.mkdir(parents=True, exist_ok=True)
    tool = a.build / "cloud_analysis" / "cloud-analysis"
    render = a.render or a.build / "scene_viewer" / "scene-render"
    if not render.exists():
        log("scene-render not built: its rows are skipped")
        render = None
    parts = a.parts.split(",")
    machine = {"nproc": os.cpu_count(), "cpu": "", "gl_renderer": ""}
    for line in open("/proc/cpuinfo"):
        if line.startswith("model name"):
            machine["cpu"] = line.split(":", 1)[1].strip()
            break
    if render:
        info = run([render, "--info"])
        m = re.search(r"GL renderer:\s*(.+)", info.stdout + info.stderr)
        machine["gl_renderer"] = m[1].strip() if m else ""
    machine["load_average_1_5_15"] = os.getloadavg()  # other jobs on the machine skew times
    result = {"machine": machine}
    print(f"machine: {machine['nproc']} cores, {machine['cpu']}, GL {machine['gl_renderer']}, "
          f"load average at start {machine['load_average_1_5_15'][0]:.2f}")
    if "table" in parts:
        part_table(a, tool, render, result)
    if "batch" in parts:
        part_batch(a, tool, result)
    if "presets" in parts:
        part_presets(a, tool, result)
    if "scaling" in parts:
        part_scaling(a, tool, render, result)
    if "matchers" in parts:
        part_matchers(a, tool, result)
    if "odometry" in parts:
        part_odometry(a, tool, result)
    if "profile" in parts:
        part_profile(a, tool, result)
    result["load_average_at_end"] = os.getloadavg()
    (a.out / "bench.json").write_text(json.dumps(result, indent=1) + "\n")
    log(f"wrote {a.out / 'bench.json'}")


if __name__ == "__main__":
    main()
