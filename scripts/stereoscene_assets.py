"""What the scene generators share: class ids by name from a palette (assets/palettes/<name>.json,
the same files cloud-analysis and scene-render read) and writing an entity file."""
import json
import os
import sys

ASSETS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "assets")


def class_ids(palette="cityscapes"):
    """{class name: id} of a bundled palette."""
    with open(os.path.join(ASSETS, "palettes", f"{palette}.json")) as f:
        return {c["name"]: c["id"] for c in json.load(f)["classes"]}


def write_entity_file(doc, out):
    """Writes doc as sorted, indented JSON to out ('-' = stdout), whole or not at all."""
    text = json.dumps(doc, indent=2, sort_keys=True) + "\n"
    if out == "-":
        sys.stdout.write(text)
        return
    with open(out + ".tmp", "w") as f:
        f.write(text)
    os.replace(out + ".tmp", out)
