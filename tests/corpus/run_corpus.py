#!/usr/bin/env python3
"""Runs every bad-input case of the corpus through cloud-analysis or scene-render and checks the
promise for bad input: the expected exit code, exactly one line on stderr that starts with the
tool's name and names the file or flag at fault, nothing left behind in the output folder
(compared before and after, hidden temp files included, an earlier file unchanged), and time
and peak memory under bounds.

usage: run_corpus.py --cloud-analysis EXE --scene-render EXE --samples DIR --work DIR
                     [--sanitize] [-k SUBSTRING]
"""
import argparse
import hashlib
import os
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
CASES = os.path.join(HERE, "cases")

# (name, tool, arguments, exit code, text the error line must contain[, options]). Options:
# data_mib runs the case under that RLIMIT_DATA (skipped under the sanitizers). In arguments,
# {c} is tests/corpus/cases, {g} the generated files, {s} the samples folder, {o} the output
# folder (which holds keep.json and keep.png, earlier files no failure may touch, and a
# directory dir).
CA, SR = "cloud-analysis", "scene-render"
MAX_LINE = 400  # characters of an error line: a pointer or a path, not a dump
STEREO = "--left {s}/synthetic/left.png --right {s}/synthetic/right.png"
CALIB = "--calib {s}/synthetic/calib.yaml"
SCENE = "{s}/synthetic/expected_entities.json"
CASES_TABLE = [
    # Files that are not files.
    ("calibration is a FIFO", CA, f"{STEREO} --calib {{g}}/fifo -o {{o}}/e.json", 1, "fifo"),
    ("left image is a FIFO", CA, f"--left {{g}}/fifo --right {{s}}/synthetic/right.png {CALIB} -o {{o}}/e.json", 1, "fifo"),
    ("left image is /dev/zero", CA, f"--left /dev/zero --right {{s}}/synthetic/right.png {CALIB} -o {{o}}/e.json", 1, "/dev/zero"),
    ("calibration is a directory", CA, f"{STEREO} --calib {{c}} -o {{o}}/e.json", 1, "cases"),
    ("entity file is a FIFO", SR, "{g}/fifo --view bev -o {o}/r.png", 1, "fifo"),
    ("entity file is /dev/zero", SR, "/dev/zero --view bev -o {o}/r.png", 1, "/dev/zero"),
    ("background is a FIFO", SR, f"{SCENE} --view camera --background {{g}}/fifo -o {{o}}/r.png", 1, "background"),
    ("rig is a FIFO", SR, f"sensors {SCENE} --rig {{g}}/fifo --out {{o}}/rig --frame 000000", 1, "fifo"),
    ("cloud is a FIFO", SR, f"{SCENE} --view bev --cloud {{g}}/fifo -o {{o}}/r.png", 1, "fifo"),
    ("class table is a FIFO", SR, f"{SCENE} --view bev --classes {{g}}/fifo -o {{o}}/r.png", 1, "fifo"),
    ("evaluate: entity file is a FIFO", CA, f"evaluate --entities {{g}}/fifo --reference {SCENE}", 1, "fifo"),
    # Sizes promised by headers.
    ("left image promises 20000x20000", CA, f"--left {{g}}/huge.png --right {{s}}/synthetic/right.png {CALIB} -o {{o}}/e.json", 1, "huge.png"),
    ("left image is a truncated PNG", CA, f"--left {{c}}/truncated.png --right {{s}}/synthetic/right.png {CALIB} -o {{o}}/e.json", 1, "truncated.png"),
    ("background promises 20000x20000", SR, f"{SCENE} --view camera --background {{g}}/huge.png -o {{o}}/r.png", 1, "too large"),
    ("left image is 16-bit", CA, f"--left {{g}}/left16.png --right {{s}}/synthetic/right.png {CALIB} -o {{o}}/e.json", 1, "left16.png"),
    ("semantic image is 16-bit", CA, f"{STEREO} {CALIB} --semantic {{g}}/left16.png -o {{o}}/e.json", 1, "left16.png"),
    # Calibrations no rig has.
    ("calibration fx 1e300", CA, f"{STEREO} --calib {{c}}/calib_fx_1e300.yaml -o {{o}}/e.json", 1, "calib_fx_1e300.yaml"),
    ("calibration S_rect 1e30", CA, f"{STEREO} --calib {{c}}/calib_s_rect_1e30.txt -o {{o}}/e.json", 1, "calib_s_rect_1e30.txt"),
    ("calibration width 1e30", CA, f"{STEREO} --calib {{c}}/calib_width_1e30.json -o {{o}}/e.json", 1, "calib_width_1e30.json"),
    ("calibration baseline 0", CA, f"{STEREO} --calib {{c}}/calib_baseline_0.yaml -o {{o}}/e.json", 1, "calib_baseline_0.yaml"),
    ("calibration baseline negative", CA, f"{STEREO} --calib {{c}}/calib_baseline_negative.yaml -o {{o}}/e.json", 1, "calib_baseline_negative.yaml"),
    ("calibration fy NaN", CA, f"{STEREO} --calib {{c}}/calib_fy_nan.yaml -o {{o}}/e.json", 1, "calib_fy_nan.yaml"),
    # Memory the system refuses (a 100 MB data limit; not under the sanitizers' shadow memory).
    ("evaluate: entity file larger than the memory given", CA, f"evaluate --entities {{g}}/sparse_200mb.json --reference {SCENE}", 1, "sparse_200mb.json", {"data_mib": 100}),
    ("render: entity file larger than the memory given", SR, "{g}/sparse_200mb.json --view bev -o {o}/r.png", 1, "sparse_200mb.json", {"data_mib": 100}),
    # Limits raised or lowered by flags.
    ("--max-pixels below the left image", CA, f"{STEREO} {CALIB} --max-pixels 1000 -o {{o}}/e.json", 1, "--max-pixels"),
    ("--max-pixels 0", CA, f"{STEREO} {CALIB} --max-pixels 0 -o {{o}}/e.json", 2, "--max-pixels"),
    ("--max-model-vertices below the car model", SR, f"{SCENE} --view bev --max-model-vertices 10 -o {{o}}/r.png", 1, "--max-model-vertices"),
    ("--max-entities below the entity file", SR, f"{SCENE} --view bev --max-entities 1 -o {{o}}/r.png", 1, "--max-entities"),
    ("--max-text-mib below a 200 MB entity file", CA, f"evaluate --entities {{g}}/sparse_200mb.json --reference {SCENE} --max-text-mib 100", 1, "--max-text-mib"),
    ("render --max-pixels below --size", SR, f"{SCENE} --view bev --size 800x800 --max-pixels 1000 -o {{o}}/r.png", 2, "--size"),
    # An entity file whose camera the renderer cannot draw: the file is at fault, not the flags.
    ("entity file camera 10^6 x 10^6", SR, "{c}/camera_1e6.json --view camera -o {o}/r.png", 1, "camera_1e6.json"),
    # JSON nested 10^5 deep.
    ("entity member nested 10^5 deep", SR, "{g}/deep_member.json --view bev -o {o}/r.png", 1, "deep_member.json"),
    ("entity file nested 10^5 deep", SR, "{g}/deep_top.json --view bev -o {o}/r.png", 1, "deep_top.json"),
    ("evaluate: entity file nested 10^5 deep", CA, f"evaluate --entities {{g}}/deep_member.json --reference {SCENE}", 1, "deep_member.json"),
    ("calibration nested 10^5 deep", CA, f"{STEREO} --calib {{g}}/deep_calib.json -o {{o}}/e.json", 1, "deep_calib.json"),
    ("palette nested 10^5 deep", CA, f"{STEREO} --semantic {{s}}/synthetic/semantic.png {CALIB} --palette {{g}}/deep_palette.json -o {{o}}/e.json", 1, "deep_palette.json"),
    # glTF models from strangers.
    ("glTF buffer view offset near 2^64", SR, f"{SCENE} --view bev --classes {{g}}/classes_wrap.json -o {{o}}/r.png", 1, "wrap.gltf"),
    ("glTF image view past its buffer", SR, f"{SCENE} --view bev --classes {{g}}/classes_image_view.json -o {{o}}/r.png", 1, "image_view.gltf"),
    ("glTF 64 primitives share a 3M-vertex accessor", SR, f"{SCENE} --view bev --classes {{g}}/classes_shared.json -o {{o}}/r.png", 1, "shared.gltf"),
    ("glTF nested 10^5 deep", SR, f"{SCENE} --view bev --classes {{g}}/classes_deep.json -o {{o}}/r.png", 1, "deep.gltf"),
    # Values that pass a type check but not a range.
    ("class_id 1e30", SR, "{c}/class_id_1e30.json --view bev -o {o}/r.png", 1, "class_id"),
    ("point_count 1e30", SR, "{c}/point_count_1e30.json --view bev -o {o}/r.png", 1, "point_count"),
    ("entity at x = 1e30", SR, "{c}/x_1e30.json --view bev -o {o}/r.png", 1, "/x"),
    ("--min-disparity 2^31-1", CA, f"{STEREO} {CALIB} --min-disparity 2147483647 -o {{o}}/e.json", 2, "--min-disparity"),
    ("--min-disparity -2^31", CA, f"{STEREO} {CALIB} --min-disparity -2147483648 -o {{o}}/e.json", 2, "--min-disparity"),
    ("PCD with a 1-byte float field", SR, f"{SCENE} --view bev --cloud {{c}}/float_size_1.pcd -o {{o}}/r.png", 1, "float_size_1.pcd"),
    ("PCD with a huge COUNT", SR, f"{SCENE} --view bev --cloud {{c}}/huge_count.pcd -o {{o}}/r.png", 1, "huge_count.pcd"),
    ("palette colour 2^40", CA, f"{STEREO} --semantic {{s}}/synthetic/semantic.png {CALIB} --palette {{c}}/palette_colour_2p40.json -o {{o}}/e.json", 1, "palette_colour_2p40.json"),
    # Output paths.
    ("render output is a directory", SR, f"{SCENE} --view bev -o {{o}}/dir", 1, "dir"),
    ("render output and --glb are the same file", SR, f"{SCENE} --view bev -o {{o}}/same.png --glb {{o}}/same.png", 1, "same.png"),
    ("render --glb is a directory after a good PNG", SR, f"{SCENE} --view bev -o {{o}}/r.png --glb {{o}}/dir", 1, "dir"),
    ("analyse -o is a directory", CA, f"{STEREO} {CALIB} -o {{o}}/dir", 1, "dir"),
    ("analyse writes one file for two flags", CA, f"{STEREO} {CALIB} -o {{o}}/e.json --disparity-png {{o}}/same.png --disparity-kitti {{o}}/same.png", 1, "same.png"),
    ("analyse keeps an earlier entity file when a later output is refused", CA, f"{STEREO} {CALIB} -o {{o}}/keep.json --disparity-png {{o}}/dir", 1, "dir"),
    ("batch frame id climbs out of --out-dir", CA, "batch --kitti-root {c} --frames ../escape --out-dir {o}", 2, "--frames"),
    ("batch frame id is an absolute path", CA, "batch --kitti-root {c} --frames /tmp/escape --out-dir {o}", 2, "--frames"),
    ("batch list names a frame outside --out-dir", CA, "batch --kitti-root {c} --list {c}/list_dotdot.txt --out-dir {o}", 1, "list_dotdot.txt"),
    ("batch list is a FIFO", CA, "batch --kitti-root {c} --list {g}/fifo --out-dir {o}", 1, "fifo"),
    ("batch --report is a directory", CA, "batch --kitti-root {c} --frames x --out-dir {o} --report {o}/dir", 1, "--report"),
    ("make-sample at 100000x100000", CA, "make-sample --width 100000 --height 100000 --out {o}/sample", 2, "--width"),
    ("grid --columns -1", SR, f"grid --inputs {SCENE} --columns -1 -o {{o}}/g.png", 2, "--columns"),
    ("sensors --size 16384x16384", SR, f"sensors {SCENE} --size 16384x16384 --out {{o}}/rig --frame 000000", 2, "--size"),
    ("html --out is a file", SR, f"html {SCENE} --out {{o}}/keep.json", 1, "keep.json"),
    ("html --out is inside a file", SR, f"html {SCENE} --out {{o}}/keep.json/viewer", 1, "keep.json"),
    # An earlier file at an output path survives every kind of failure, in every command that
    # writes: a bad input, an output refused up front, a failure after the work is done.
    ("analyse keeps an earlier -o file when the calibration is bad", CA, f"{STEREO} --calib {{c}}/calib_fx_1e300.yaml -o {{o}}/keep.json", 1, "calib_fx_1e300.yaml"),
    ("batch keeps the earlier output of a frame that fails", CA, "batch --kitti-root {c} --frames keep --out-dir {o} --quiet", 1, "frame keep"),
    ("evaluate keeps an earlier --json file when the entity file is bad", CA, f"evaluate --entities {{c}}/x_1e30.json --reference {SCENE} --json {{o}}/keep.json", 1, "x_1e30.json"),
    ("export-kitti keeps an earlier -o file when the entity file is bad", CA, "export-kitti {c}/x_1e30.json -o {o}/keep.json", 1, "x_1e30.json"),
    ("make-sample --out is a file", CA, "make-sample --out {o}/keep.json", 1, "keep.json"),
    ("render keeps an earlier -o file when the entity file is bad", SR, "{c}/x_1e30.json --view bev -o {o}/keep.png", 1, "x_1e30.json"),
    ("render keeps an earlier -o file when --glb is refused", SR, f"{SCENE} --view bev -o {{o}}/keep.png --glb {{o}}/dir", 1, "dir"),
    ("grid keeps an earlier -o file when an input is bad", SR, f"grid --inputs {SCENE} {{c}}/x_1e30.json -o {{o}}/keep.png", 1, "x_1e30.json"),
    ("sensors fails after rendering: --out is a file", SR, f"sensors {SCENE} --out {{o}}/keep.json --frame 000000", 1, "keep.json"),
    ("play keeps an earlier frame PNG when a later frame is broken", SR, "play {c}/drive_broken --out-dir {o} --view bev", 1, "broken.json"),
    ("play keeps an earlier --strip and makes no folder when a frame is broken", SR, "play {c}/drive_broken --out-dir {o}/new/frames --strip {o}/keep.png --view bev", 1, "broken.json"),
    ("play --strip is a directory", SR, "play {c}/drive_broken --out-dir {o}/frames --strip {o}/dir --view bev", 1, "dir"),
    ("play --video is a file's folder", SR, "play {c}/drive_broken --out-dir {o} --video {o}/keep.json/v.mp4 --view bev", 1, "keep.json"),
]


def snapshot(folder):
    """Every entry under folder (hidden ones too) with its type and content hash."""
    out = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            path = os.path.join(root, name)
            rel = os.path.relpath(path, folder)
            if os.path.isdir(path):
                out[rel] = "dir"
            else:
                with open(path, "rb") as f:
                    out[rel] = hashlib.sha256(f.read()).hexdigest()
    return out


def run_case(case, exes, dirs, bounds):
    name, tool, args, code, names = case[:5]
    options = case[5] if len(case) > 5 else {}
    limit = None
    if "data_mib" in options:
        import resource
        data = options["data_mib"] << 20
        limit = lambda: resource.setrlimit(resource.RLIMIT_DATA, (data, data))
    out = os.path.join(dirs["work"], "out")
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(os.path.join(out, "dir"))
    with open(os.path.join(out, "keep.json"), "w") as f:
        f.write('{"earlier": "file"}\n')
    with open(os.path.join(out, "keep.png"), "wb") as f:
        f.write(b"earlier image\n")
    with open(os.path.join(out, "dir", "inside"), "w") as f:
        f.write("x")
    before = snapshot(out)
    argv = [exes[tool]] + args.format(c=CASES, g=dirs["gen"], s=dirs["samples"], o=out).split()
    start = time.monotonic()
    proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, preexec_fn=limit)
    try:
        _, err = proc.communicate(timeout=bounds["seconds"])
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        return [f"still running after {bounds['seconds']} s (killed)"]
    seconds = time.monotonic() - start
    problems = []
    lines = err.decode(errors="replace").splitlines()
    if proc.returncode != code:
        problems.append(f"exit {proc.returncode}, expected {code}")
    errors = [l for l in lines if ": warning: " not in l]
    if len(errors) != 1:
        problems.append(f"{len(errors)} error lines, expected 1")
    elif not errors[0].startswith(tool + ": ") or names not in errors[0]:
        problems.append(f"error line does not start with '{tool}: ' and name '{names}'")
    elif len(errors[0]) > MAX_LINE:
        problems.append(f"error line of {len(errors[0])} characters, more than {MAX_LINE}")
    after = snapshot(out)
    if after != before:
        added = sorted(set(after) - set(before))
        changed = sorted(k for k in before if after.get(k) != before[k])
        problems.append(f"output folder changed: added {added}, changed or lost {changed}")
    if seconds > bounds["seconds"]:
        problems.append(f"took {seconds:.1f} s")
    if problems:
        problems.append("stderr: " + " | ".join(lines[:5]))
    return problems


def peak_rss_mib():
    import resource
    return resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--cloud-analysis", required=True)
    p.add_argument("--scene-render", required=True)
    p.add_argument("--samples", required=True)
    p.add_argument("--work", required=True)
    p.add_argument("--sanitize", action="store_true", help="looser time bound (ASan is slow)")
    p.add_argument("-k", default="", help="run only cases whose name contains this")
    a = p.parse_args()
    exes = {CA: a.cloud_analysis, SR: a.scene_render}
    shutil.rmtree(a.work, ignore_errors=True)
    gen = os.path.join(a.work, "gen")
    subprocess.run([sys.executable, os.path.join(HERE, "make_hostile.py"), gen], check=True)
    dirs = {"work": a.work, "gen": gen, "samples": a.samples}
    bounds = {"seconds": 60.0 if a.sanitize else 15.0, "mib": 1024.0}
    failed = 0
    ran = 0
    for case in CASES_TABLE:
        if a.k not in case[0]:
            continue
        if a.sanitize and len(case) > 5 and "data_mib" in case[5]:
            print(f"skip {case[0]} (a data limit and the sanitizers' shadow memory do not mix)")
            continue
        ran += 1
        problems = run_case(case, exes, dirs, bounds)
        status = "ok  " if not problems else "FAIL"
        print(f"{status} {case[0]}")
        for problem in problems:
            print(f"       {problem}")
        failed += bool(problems)
    # ru_maxrss of RUSAGE_CHILDREN is the largest peak of any one child.
    rss = peak_rss_mib()
    print(f"{ran} cases, {failed} failed, largest peak memory of a run {rss:.0f} MiB")
    if not a.sanitize and rss > bounds["mib"]:
        print(f"FAIL peak memory above {bounds['mib']:.0f} MiB")
        failed += 1
    shutil.rmtree(a.work, ignore_errors=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
