#!/usr/bin/python3
"""Writes the tiny hand-made glTF files the loader tests read (stdlib only, deterministic).

Each file has one feature and a known answer (bounds, triangle count, colour); see
tests/scene_viewer/test_gltf.cpp. Run from anywhere: files are written beside this script.
"""

import base64
import json
import struct
import zlib
from pathlib import Path

HERE = Path(__file__).resolve().parent

TRIANGLE = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)]
QUAD = [(-1.0, -1.0, 0.0), (1.0, -1.0, 0.0), (1.0, 1.0, 0.0), (-1.0, 1.0, 0.0)]
QUAD_INDICES = [0, 1, 2, 0, 2, 3]
QUAD_UV = [(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)]


def floats(values):
    return b"".join(struct.pack("<" + "f" * len(v), *v) for v in values)


def pad4(data, fill=b"\x00"):
    return data + fill * ((4 - len(data) % 4) % 4)


class Doc:
    """A minimal glTF document with one buffer assembled from views."""

    def __init__(self):
        self.bin = b""
        self.doc = {"asset": {"version": "2.0", "generator": "make_test_files.py"},
                    "accessors": [], "bufferViews": [], "meshes": [], "nodes": [],
                    "scenes": [{"nodes": []}], "scene": 0}

    def view(self, data):
        self.bin = pad4(self.bin)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": len(self.bin),
                                        "byteLength": len(data)})
        self.bin += data
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, data, count, type_, component, extra=None):
        acc = {"bufferView": self.view(data), "count": count, "type": type_,
               "componentType": component}
        acc.update(extra or {})
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def positions(self, pts):
        lo = [min(p[i] for p in pts) for i in range(3)]
        hi = [max(p[i] for p in pts) for i in range(3)]
        return self.accessor(floats(pts), len(pts), "VEC3", 5126, {"min": lo, "max": hi})

    def material(self, rgba, texture=None):
        pbr = {"baseColorFactor": rgba}
        if texture is not None:
            pbr["baseColorTexture"] = {"index": texture}
        self.doc.setdefault("materials", []).append({"pbrMetallicRoughness": pbr})
        return len(self.doc["materials"]) - 1

    def mesh(self, primitives):
        self.doc["meshes"].append({"primitives": primitives})
        return len(self.doc["meshes"]) - 1

    def node(self, node, root=True):
        self.doc["nodes"].append(node)
        index = len(self.doc["nodes"]) - 1
        if root:
            self.doc["scenes"][0]["nodes"].append(index)
        return index

    def finish(self, uri):
        self.bin = pad4(self.bin)
        buf = {"byteLength": len(self.bin)}
        if uri is not None:
            buf["uri"] = uri
        self.doc["buffers"] = [buf]
        return self.doc


def data_uri(data):
    return "data:application/octet-stream;base64," + base64.b64encode(data).decode("ascii")


def write_json(name, doc):
    (HERE / name).write_text(json.dumps(doc, indent=1) + "\n")


def glb(doc, bin_data):
    j = pad4(json.dumps(doc, separators=(",", ":")).encode(), b" ")
    total = 12 + 8 + len(j) + 8 + len(bin_data)
    return (struct.pack("<4sII", b"glTF", 2, total) + struct.pack("<I4s", len(j), b"JSON") + j +
            struct.pack("<I4s", len(bin_data), b"BIN\x00") + bin_data)


def png_rgba(width, height, pixels):
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    raw = b"".join(b"\x00" + bytes(pixels[y * width * 4:(y + 1) * width * 4])
                   for y in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6,
                                                             0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def triangle_glb():
    """triangle.glb: one indexed red triangle with normals, BIN chunk."""
    d = Doc()
    pos = d.positions(TRIANGLE)
    nrm = d.accessor(floats([(0, 0, 1)] * 3), 3, "VEC3", 5126)
    idx = d.accessor(pad4(struct.pack("<3H", 0, 1, 2)), 3, "SCALAR", 5123)
    mat = d.material([1.0, 0.0, 0.0, 1.0])
    d.node({"mesh": d.mesh([{"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx,
                            "material": mat}])})
    doc = d.finish(None)
    data = glb(doc, d.bin)
    (HERE / "triangle.glb").write_bytes(data)
    (HERE / "truncated.glb").write_bytes(data[: len(data) // 2])


def quad_external():
    """quad_external.gltf + quad_external.bin: uint32 indices, no normals (computed)."""
    d = Doc()
    pos = d.positions(QUAD)
    idx = d.accessor(struct.pack("<6I", *QUAD_INDICES), 6, "SCALAR", 5125)
    d.node({"mesh": d.mesh([{"attributes": {"POSITION": pos}, "indices": idx}])})
    doc = d.finish("quad_external.bin")
    (HERE / "quad_external.bin").write_bytes(d.bin)
    write_json("quad_external.gltf", doc)


def quad_datauri():
    """quad_datauri.gltf: the quad non-indexed (6 vertices), buffer in a data: URI."""
    d = Doc()
    pos = d.positions([QUAD[i] for i in QUAD_INDICES])
    d.node({"mesh": d.mesh([{"attributes": {"POSITION": pos}, "mode": 4}])})
    doc = d.finish(data_uri(d.bin))
    write_json("quad_datauri.gltf", doc)


def hierarchy():
    """hierarchy.gltf: parent translated by (10,0,0), child by (0,5,0) and scaled by 2."""
    d = Doc()
    pos = d.positions(TRIANGLE)
    mesh = d.mesh([{"attributes": {"POSITION": pos}}])
    d.node({"name": "parent", "translation": [10, 0, 0], "children": [1]})
    d.node({"name": "child", "translation": [0, 5, 0], "scale": [2, 2, 2], "mesh": mesh},
           root=False)
    write_json("hierarchy.gltf", d.finish(data_uri(d.bin)))


def mirrored():
    """mirrored.gltf: the triangle under a node scaled by -1 in x (a mirroring transform)."""
    d = Doc()
    pos = d.positions(TRIANGLE)
    d.node({"scale": [-1, 1, 1], "mesh": d.mesh([{"attributes": {"POSITION": pos}}])})
    write_json("mirrored.gltf", d.finish(data_uri(d.bin)))


def two_primitives():
    """two_primitives.gltf: one mesh, a red triangle and a blue quad at z = 1."""
    d = Doc()
    tri = d.positions(TRIANGLE)
    quad = d.positions([(x, y, 1.0) for x, y, _ in QUAD])
    idx = d.accessor(pad4(bytes(QUAD_INDICES)), 6, "SCALAR", 5121)
    red = d.material([1.0, 0.0, 0.0, 1.0])
    blue = d.material([0.0, 0.0, 1.0, 1.0])
    d.node({"mesh": d.mesh([{"attributes": {"POSITION": tri}, "material": red},
                            {"attributes": {"POSITION": quad}, "indices": idx,
                             "material": blue}])})
    write_json("two_primitives.gltf", d.finish(data_uri(d.bin)))


def textured():
    """textured.gltf + checker.png: a quad with a 2x2 texture (red, green / blue, white)."""
    pixels = [255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255]
    (HERE / "checker.png").write_bytes(png_rgba(2, 2, pixels))
    d = Doc()
    pos = d.positions(QUAD)
    uv = d.accessor(floats(QUAD_UV), 4, "VEC2", 5126)
    idx = d.accessor(pad4(struct.pack("<6H", *QUAD_INDICES)), 6, "SCALAR", 5123)
    d.doc["images"] = [{"uri": "checker.png"}]
    d.doc["textures"] = [{"source": 0}]
    mat = d.material([1.0, 1.0, 1.0, 1.0], texture=0)
    d.node({"mesh": d.mesh([{"attributes": {"POSITION": pos, "TEXCOORD_0": uv},
                             "indices": idx, "material": mat}])})
    write_json("textured.gltf", d.finish(data_uri(d.bin)))


def textured_transform():
    """textured_transform.gltf: textured.gltf with KHR_texture_transform (offset, rotation 90
    degrees, scale) on the base colour texture."""
    textured()
    doc = json.loads((HERE / "textured.gltf").read_text())
    doc["extensionsUsed"] = ["KHR_texture_transform"]
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = {
        "KHR_texture_transform": {"offset": [0.5, 0.25], "rotation": 1.5707963267948966,
                                  "scale": [0.5, 2.0]}}
    write_json("textured_transform.gltf", doc)


def textured_material():
    """textured_material.gltf: textured.gltf as a third-party kit writes it: a double-sided,
    alpha-masked, half-metallic material with roughness 0.3 and an emissive tint, and a
    NEAREST / CLAMP_TO_EDGE sampler (pixel-art textures). The .glb export keeps them."""
    textured()
    doc = json.loads((HERE / "textured.gltf").read_text())
    doc["samplers"] = [{"magFilter": 9728, "minFilter": 9728, "wrapS": 33071, "wrapT": 33071}]
    doc["textures"][0]["sampler"] = 0
    material = doc["materials"][0]
    material["name"] = "kit"
    material["doubleSided"] = True
    material["alphaMode"] = "MASK"
    material["alphaCutoff"] = 0.4
    material["emissiveFactor"] = [0.25, 0.0, 0.0]
    material["pbrMetallicRoughness"]["metallicFactor"] = 0.5
    material["pbrMetallicRoughness"]["roughnessFactor"] = 0.3
    write_json("textured_material.gltf", doc)


def lines_and_triangles():
    """lines_and_triangles.gltf: a LINES primitive (skipped with a warning) and a triangle."""
    d = Doc()
    tri = d.positions(TRIANGLE)
    line = d.positions([(0.0, 0.0, 0.0), (5.0, 5.0, 5.0)])
    d.node({"mesh": d.mesh([{"attributes": {"POSITION": line}, "mode": 1},
                            {"attributes": {"POSITION": tri}, "mode": 4}])})
    write_json("lines_and_triangles.gltf", d.finish(data_uri(d.bin)))


def escapes():
    """Buffers whose URIs leave the folder; the loader must refuse them before reading."""
    for name, uri in (("escape_parent.gltf", "../quad_external.bin"),
                      ("escape_encoded.gltf", "sub/%2e%2e/%2E%2E/quad_external.bin"),
                      ("escape_absolute.gltf", "/etc/hostname"),
                      ("escape_file_uri.gltf", "file:///etc/hostname")):
        d = Doc()
        pos = d.positions(TRIANGLE)
        d.node({"mesh": d.mesh([{"attributes": {"POSITION": pos}}])})
        write_json(name, d.finish(uri))


if __name__ == "__main__":
    triangle_glb()
    quad_external()
    quad_datauri()
    hierarchy()
    mirrored()
    two_primitives()
    textured()
    textured_transform()
    textured_material()
    lines_and_triangles()
    escapes()
