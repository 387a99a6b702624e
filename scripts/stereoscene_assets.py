"""What the project's scripts read from assets/ instead of writing it again: class ids by name
from a palette (assets/palettes/<name>.json, the same files cloud-analysis and scene-render
read)."""
import json
import os

ASSETS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "assets")


def class_ids(palette="cityscapes"):
    """{class name: id} of a bundled palette."""
    with open(os.path.join(ASSETS, "palettes", f"{palette}.json")) as f:
        return {c["name"]: c["id"] for c in json.load(f)["classes"]}
