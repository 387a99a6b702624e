#!/usr/bin/env python3
"""Writes the bad-input corpus's large or special files into a folder at test time (a FIFO, a
PNG header promising 20000x20000, a 16-bit PNG, a sparse 200 MB file, JSON nested 10^5 deep, glTF models with wrapping offsets,
unchecked image views, 200k-node chains and shared huge accessors), so none is committed.

usage: make_hostile.py OUT_DIR
"""
import json
import os
import struct
import sys
import zlib


def png_header_only(path, width, height):
    """A PNG whose IHDR promises width x height RGB pixels, followed by a tiny IDAT."""
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    body = chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 64)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + body)


def png_grey16(path, width, height):
    """A valid 16-bit greyscale PNG (a ramp), as a 12- or 16-bit camera writes."""
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    ihdr = struct.pack(">IIBBBBB", width, height, 16, 0, 0, 0, 0)
    rows = b"".join(b"\0" + b"".join(struct.pack(">H", (x * 997) & 0xFFFF) for x in range(width))
                    for _ in range(height))
    body = chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + body)


def nested(depth):
    return "[" * depth + "]" * depth


def entity_document(extra=""):
    doc = ('{"schema_version": "1.0", "frame": {"id": "x", "coordinate_system": "kitti_camera"},'
           ' "entities": []' + extra + "}")
    return doc


def gltf(path, doc, binary=b""):
    """A .gltf with its one buffer as a data: URI when `binary` is given."""
    if binary or "buffers" in doc:
        import base64
        doc.setdefault("buffers", [{"byteLength": len(binary)}])
        doc["buffers"][0]["uri"] = ("data:application/octet-stream;base64," +
                                    base64.b64encode(binary).decode())
    doc.setdefault("asset", {"version": "2.0"})
    with open(path, "w") as f:
        json.dump(doc, f)


def triangle_buffer():
    return struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)


def write_models(out):
    tri = triangle_buffer()
    mesh = {"primitives": [{"attributes": {"POSITION": 0}}]}
    accessor = {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}
    # A bufferView offset near 2^64: 64-bit end offsets wrap.
    gltf(f"{out}/wrap.gltf", {
        "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}], "meshes": [mesh],
        "accessors": [accessor],
        "bufferViews": [{"buffer": 0, "byteOffset": 18446744073709551600, "byteLength": 36}],
    }, tri)
    # An image stored in a buffer view past the end of its buffer.
    gltf(f"{out}/image_view.gltf", {
        "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}], "meshes": [mesh],
        "accessors": [accessor],
        "bufferViews": [{"buffer": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 30, "byteLength": 1000000}],
        "images": [{"bufferView": 1, "mimeType": "image/png"}],
    }, tri)
    # A chain of 200k nodes, each the only child of the one before.
    n = 200_000
    nodes = [{"children": [i + 1]} for i in range(n - 1)] + [{"mesh": 0}]
    gltf(f"{out}/chain.gltf", {
        "scenes": [{"nodes": [0]}], "nodes": nodes, "meshes": [mesh],
        "accessors": [accessor], "bufferViews": [{"buffer": 0, "byteLength": 36}],
    }, tri)
    # 64 primitives sharing one 3M-vertex accessor without a buffer view (reads as zeros).
    big = {"componentType": 5126, "count": 3_000_000, "type": "VEC3"}
    gltf(f"{out}/shared.gltf", {
        "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}] * 64}],
        "accessors": [big],
    })
    # JSON nested 10^5 deep inside the glTF (tinygltf's parser recurses).
    with open(f"{out}/deep.gltf", "w") as f:
        f.write('{"asset": {"version": "2.0"}, "extras": ' + nested(100_000) + "}")
    for name in ("wrap", "image_view", "chain", "shared", "deep"):
        table = {"format": "stereoscene-render-classes", "version": 1, "classes": [
            {"name": "car", "class_id": 26, "colour": [0, 0, 142], "kind": "object",
             "model": f"{name}.gltf"}]}
        with open(f"{out}/classes_{name}.json", "w") as f:
            json.dump(table, f)


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    fifo = os.path.join(out, "fifo")
    if not os.path.exists(fifo):
        os.mkfifo(fifo)
    png_header_only(f"{out}/huge.png", 20000, 20000)
    png_grey16(f"{out}/left16.png", 64, 32)
    # 200 MB of holes (no disk used): within the text limit, more than a run under a 100 MB
    # data limit can allocate.
    with open(f"{out}/sparse_200mb.json", "wb") as f:
        f.truncate(200 << 20)
    deep = nested(100_000)
    with open(f"{out}/deep_member.json", "w") as f:
        f.write(entity_document(', "extra": ' + deep))
    with open(f"{out}/deep_top.json", "w") as f:
        f.write(deep)
    with open(f"{out}/deep_calib.json", "w") as f:
        f.write('{"fx": ' + deep + "}")
    with open(f"{out}/deep_palette.json", "w") as f:
        f.write('{"name": "x", "classes": ' + deep + "}")
    with open(f"{out}/deep_visibility.json", "w") as f:
        f.write('{"entities": ' + deep + "}")
    write_models(out)


if __name__ == "__main__":
    main()
