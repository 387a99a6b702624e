"""What the scene generators share: class ids by name from a palette (assets/palettes/<name>.json,
the same files cloud-analysis and scene-render read), KITTI's camera as an entity file's frame,
a class table with another vehicle body, and writing an entity file."""
import json
import os
import sys

ASSETS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "assets")


def class_ids(palette="cityscapes"):
    """{class name: id} of a bundled palette."""
    with open(os.path.join(ASSETS, "palettes", f"{palette}.json")) as f:
        return {c["name"]: c["id"] for c in json.load(f)["classes"]}


def kitti_frame(frame_id):
    """An entity file's frame seen by KITTI's left colour camera (1242x375, baseline 0.54 m)."""
    return {"id": frame_id, "convention": "kitti_camera",
            "camera": {"width": 1242, "height": 375, "fx": 721.5377, "fy": 721.5377,
                       "cx": 609.5593, "cy": 172.854, "baseline_m": 0.54}}


def write_body_table(kit, body, out):
    """Writes to `out` the shipped class table (assets/classes/render_classes.json) with the car
    class drawn by `kit`/`body`.glb and the truck class by the kit's truck.glb; every model path
    absolute, so the table may live in any folder."""
    source = os.path.join(ASSETS, "classes", "render_classes.json")
    with open(source) as f:
        table = json.load(f)
    for c in table["classes"]:
        for member in ("model", "low_model"):
            if member in c:
                c[member] = os.path.normpath(os.path.join(os.path.dirname(source), c[member]))
        if c["name"] == "car":
            c["model"] = os.path.join(kit, body + ".glb")
        if c["name"] == "truck":
            c["model"] = os.path.join(kit, "truck.glb")
    with open(out + ".tmp", "w") as f:
        json.dump(table, f, indent=1)
    os.replace(out + ".tmp", out)


def write_entity_file(doc, out):
    """Writes doc as sorted, indented JSON to out ('-' = stdout), whole or not at all."""
    text = json.dumps(doc, indent=2, sort_keys=True) + "\n"
    if out == "-":
        sys.stdout.write(text)
        return
    with open(out + ".tmp", "w") as f:
        f.write(text)
    os.replace(out + ".tmp", out)
