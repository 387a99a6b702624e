#!/usr/bin/python3
"""Generates the project's own low-poly glTF 2.0 models (assets/models/*.glb).

Every model is built from a few parametric parts (boxes, beams, cylinders, spheres, frusta),
flat-shaded (one normal per face), one glTF primitive per material. Convention (glTF 2.0):
+Y up, the model's front faces +Z, right-handed, metres, standing on y = 0, centred on x = z = 0.
The renderer scales each model's bounding box to the entity's W (x), H (y), L (z).

The output is deterministic: running the script again rewrites identical bytes, so the
committed .glb files can be checked against it (`--check`).

Usage: scripts/make-models.py [--out assets/models] [--check]
Licence of the generated models: CC0 1.0 (see assets/LICENSE-models.md).
"""

import argparse
import json
import math
import struct
import sys
from pathlib import Path

import numpy as np

TRIANGLE_BUDGET = 1500
# The hedge is its leaves: fewer would leave it a smooth blob to stereo, which a real one is not.
TRIANGLE_BUDGETS = {"hedge.glb": 2600}


def srgb_to_linear(c):
    """sRGB 8-bit channel -> linear float (glTF baseColorFactor is linear)."""
    c = c / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def colour(r, g, b, a=1.0):
    return [round(srgb_to_linear(r), 6), round(srgb_to_linear(g), 6), round(srgb_to_linear(b), 6), a]


# Cityscapes palette (sRGB) for the class-coloured parts, and the shared part colours.
PALETTE = {
    "car": (0, 0, 142), "truck": (0, 0, 70), "bus": (0, 60, 100), "person": (220, 20, 60),
    "rider": (255, 0, 0), "bicycle": (119, 11, 32), "motorcycle": (0, 0, 230),
    "vegetation": (107, 142, 35), "building": (70, 70, 70), "pole": (153, 153, 153),
    "traffic sign": (220, 220, 0), "traffic light": (250, 170, 30),
}
TYRE = colour(25, 25, 25)
GLASS = colour(140, 170, 190)
METAL = colour(170, 170, 175)
SKIN = colour(224, 172, 105)
TROUSERS = colour(40, 40, 60)
LIGHT_FRONT = colour(255, 250, 210)
LIGHT_REAR = colour(200, 20, 20)
BARK = colour(90, 60, 35)
ROOF = colour(50, 50, 50)
DARK = colour(35, 35, 35)


class Mesh:
    """Triangles grouped by material; flat-shaded (vertices are not shared between faces)."""

    def __init__(self, name):
        self.name = name
        self.materials = {}  # material name -> (rgba, roughness, list of triangles (3x3 arrays))
        self.order = []

    def material(self, name, rgba, roughness=0.8):
        if name not in self.materials:
            self.materials[name] = (rgba, roughness, [])
            self.order.append(name)
        return name

    def tri(self, mat, a, b, c):
        self.materials[mat][2].append(np.array([a, b, c], dtype=np.float64))

    def quad(self, mat, a, b, c, d):
        """Counter-clockwise quad a, b, c, d seen from its front."""
        self.tri(mat, a, b, c)
        self.tri(mat, a, c, d)

    def hexahedron(self, mat, corners):
        """8 corners: bottom (y-) 0..3 then top 4..7, each ring counter-clockwise seen from +Y:
        (-x,-z), (-x,+z), (+x,+z), (+x,-z)."""
        c = [np.asarray(p, dtype=np.float64) for p in corners]
        self.quad(mat, c[4], c[5], c[6], c[7])  # top
        self.quad(mat, c[0], c[3], c[2], c[1])  # bottom
        for i in range(4):
            j = (i + 1) % 4
            self.quad(mat, c[i], c[j], c[j + 4], c[i + 4])

    def box(self, mat, center, size):
        cx, cy, cz = center
        hx, hy, hz = (s / 2.0 for s in size)
        ring = [(-hx, -hz), (-hx, hz), (hx, hz), (hx, -hz)]
        self.hexahedron(mat, [(cx + x, cy - hy, cz + z) for x, z in ring] +
                        [(cx + x, cy + hy, cz + z) for x, z in ring])

    def frustum_box(self, mat, center_bottom, bottom_size, top_size, height, top_shift_z=0.0):
        """A box whose top rectangle differs from its bottom one (car cabins, roofs)."""
        cx, cy, cz = center_bottom
        bx, bz = bottom_size[0] / 2.0, bottom_size[1] / 2.0
        tx, tz = top_size[0] / 2.0, top_size[1] / 2.0
        ring_b = [(-bx, -bz), (-bx, bz), (bx, bz), (bx, -bz)]
        ring_t = [(-tx, -tz), (-tx, tz), (tx, tz), (tx, -tz)]
        self.hexahedron(mat, [(cx + x, cy, cz + z) for x, z in ring_b] +
                        [(cx + x, cy + height, cz + z + top_shift_z) for x, z in ring_t])

    def beam(self, mat, p0, p1, thickness):
        """A square-section bar from p0 to p1 (bicycle frames, arms, legs)."""
        p0 = np.asarray(p0, dtype=np.float64)
        p1 = np.asarray(p1, dtype=np.float64)
        axis = p1 - p0
        axis /= np.linalg.norm(axis)
        helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        u = np.cross(axis, helper)
        u /= np.linalg.norm(u)
        v = np.cross(axis, u)
        h = thickness / 2.0
        ring = [(-h, -h), (-h, h), (h, h), (h, -h)]
        corners = [p0 + a * u + b * v for a, b in ring] + [p1 + a * u + b * v for a, b in ring]
        # The ring runs clockwise around `axis` (u x v = axis reversed order); fix orientation.
        self.hexahedron(mat, corners if np.dot(np.cross(u, v), axis) < 0 else
                        [corners[i] for i in (0, 3, 2, 1, 4, 7, 6, 5)])

    def cylinder(self, mat, center, radius, length, axis="y", segments=12, radius_top=None):
        """A closed cylinder (or frustum when radius_top differs) centred on `center`."""
        radius_top = radius if radius_top is None else radius_top
        k = {"x": 0, "y": 1, "z": 2}[axis]
        # (u, v, w) is a right-handed frame with w along the axis.
        frames = {0: (1, 2, 0), 1: (2, 0, 1), 2: (0, 1, 2)}
        iu, iv, iw = frames[k]

        def point(r, angle, w):
            p = [0.0, 0.0, 0.0]
            p[iu] = r * math.cos(angle)
            p[iv] = r * math.sin(angle)
            p[iw] = w
            return np.asarray(center, dtype=np.float64) + np.array(p)

        h = length / 2.0
        bottom_c = point(0.0, 0.0, -h)
        top_c = point(0.0, 0.0, h)
        for s in range(segments):
            a0 = 2.0 * math.pi * s / segments
            a1 = 2.0 * math.pi * (s + 1) / segments
            b0, b1 = point(radius, a0, -h), point(radius, a1, -h)
            t0, t1 = point(radius_top, a0, h), point(radius_top, a1, h)
            self.quad(mat, b0, b1, t1, t0)
            if radius_top > 0.0:
                self.tri(mat, top_c, t0, t1)
            self.tri(mat, bottom_c, b1, b0)

    def sphere(self, mat, center, radii, segments=10, rings=6):
        c = np.asarray(center, dtype=np.float64)
        r = np.asarray(radii, dtype=np.float64)

        def point(i, j):
            theta = math.pi * i / rings
            phi = 2.0 * math.pi * j / segments
            return c + r * np.array([math.sin(theta) * math.sin(phi), math.cos(theta),
                                     math.sin(theta) * math.cos(phi)])

        for i in range(rings):
            for j in range(segments):
                a, b = point(i, j), point(i + 1, j)
                cc, d = point(i + 1, j + 1), point(i, j + 1)
                if i == 0:
                    self.tri(mat, a, b, cc)
                elif i == rings - 1:
                    self.tri(mat, a, b, d)
                else:
                    self.quad(mat, a, b, cc, d)

    def triangle_count(self):
        return sum(len(m[2]) for m in self.materials.values())


def pad4(data, fill=b"\x00"):
    return data + fill * ((4 - len(data) % 4) % 4)


def to_glb(mesh, generator="stereoscene scripts/make-models.py"):
    """Serialises one mesh as a binary glTF 2.0 container (one node, one mesh)."""
    bin_data = b""
    buffer_views, accessors, primitives, materials = [], [], [], []

    def add_view(data, target):
        nonlocal bin_data
        bin_data = pad4(bin_data)
        buffer_views.append({"buffer": 0, "byteOffset": len(bin_data), "byteLength": len(data),
                             "target": target})
        bin_data += data
        return len(buffer_views) - 1

    for name in mesh.order:
        rgba, roughness, tris = mesh.materials[name]
        if not tris:
            continue
        positions = np.concatenate(tris).astype(np.float32)
        normals = []
        for t in tris:
            n = np.cross(t[1] - t[0], t[2] - t[0])
            length = np.linalg.norm(n)
            n = n / length if length > 0 else np.array([0.0, 1.0, 0.0])
            normals.extend([n, n, n])
        normals = np.asarray(normals, dtype=np.float32)
        indices = np.arange(len(positions), dtype=np.uint16)
        pos_view = add_view(positions.tobytes(), 34962)
        accessors.append({"bufferView": pos_view, "componentType": 5126, "count": len(positions),
                          "type": "VEC3", "min": [float(v) for v in positions.min(axis=0)],
                          "max": [float(v) for v in positions.max(axis=0)]})
        pos_acc = len(accessors) - 1
        nrm_view = add_view(normals.tobytes(), 34962)
        accessors.append({"bufferView": nrm_view, "componentType": 5126, "count": len(normals),
                          "type": "VEC3"})
        nrm_acc = len(accessors) - 1
        idx_view = add_view(indices.tobytes(), 34963)
        accessors.append({"bufferView": idx_view, "componentType": 5123, "count": len(indices),
                          "type": "SCALAR"})
        idx_acc = len(accessors) - 1
        materials.append({"name": name, "pbrMetallicRoughness": {
            "baseColorFactor": rgba, "metallicFactor": 0.0, "roughnessFactor": roughness}})
        primitives.append({"attributes": {"POSITION": pos_acc, "NORMAL": nrm_acc},
                           "indices": idx_acc, "material": len(materials) - 1, "mode": 4})

    bin_data = pad4(bin_data)
    doc = {
        "asset": {"version": "2.0", "generator": generator, "copyright": "CC0 1.0, stereoscene"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": mesh.name, "mesh": 0}],
        "meshes": [{"name": mesh.name, "primitives": primitives}],
        "materials": materials,
        "accessors": accessors,
        "bufferViews": buffer_views,
        "buffers": [{"byteLength": len(bin_data)}],
    }
    json_bytes = pad4(json.dumps(doc, separators=(",", ":")).encode("utf-8"), b" ")
    total = 12 + 8 + len(json_bytes) + 8 + len(bin_data)
    return (struct.pack("<4sII", b"glTF", 2, total) +
            struct.pack("<I4s", len(json_bytes), b"JSON") + json_bytes +
            struct.pack("<I4s", len(bin_data), b"BIN\x00") + bin_data)


def wheels(m, mat, xs, zs, radius, width, hub=None):
    for x in xs:
        for z in zs:
            m.cylinder(mat, (x, radius, z), radius, width, axis="x", segments=12)
            if hub is not None:
                side = 1.0 if x > 0 else -1.0
                m.cylinder(hub, (x + side * (width / 2.0 + 0.005), radius, z), radius * 0.5, 0.01,
                           axis="x", segments=8)


def make_car():
    m = Mesh("car")
    body = m.material("paint", colour(*PALETTE["car"]), 0.4)
    glass = m.material("glass", GLASS, 0.1)
    tyre = m.material("tyre", TYRE)
    hub = m.material("hub", METAL, 0.3)
    front = m.material("headlight", LIGHT_FRONT, 0.2)
    rear = m.material("taillight", LIGHT_REAR, 0.2)
    m.frustum_box(body, (0, 0.25, 0), (1.8, 4.3), (1.78, 4.2), 0.55)  # lower body 0.25..0.8
    m.frustum_box(glass, (0, 0.8, -0.15), (1.7, 2.5), (1.4, 1.6), 0.5, top_shift_z=-0.1)
    m.box(body, (0, 1.33, -0.25), (1.38, 0.06, 1.55))  # roof
    m.box(front, (0.6, 0.65, 2.16), (0.35, 0.12, 0.04))
    m.box(front, (-0.6, 0.65, 2.16), (0.35, 0.12, 0.04))
    m.box(rear, (0.65, 0.68, -2.16), (0.3, 0.12, 0.04))
    m.box(rear, (-0.65, 0.68, -2.16), (0.3, 0.12, 0.04))
    wheels(m, tyre, (-0.8, 0.8), (-1.35, 1.4), 0.33, 0.24, hub)
    return m


def make_truck():
    m = Mesh("truck")
    body = m.material("paint", colour(*PALETTE["truck"]), 0.5)
    cargo = m.material("cargo", colour(200, 200, 205), 0.7)
    glass = m.material("glass", GLASS, 0.1)
    tyre = m.material("tyre", TYRE)
    hub = m.material("hub", METAL, 0.3)
    front = m.material("headlight", LIGHT_FRONT, 0.2)
    m.box(body, (0, 1.45, 2.6), (2.4, 1.9, 1.8))  # cab
    m.box(glass, (0, 1.9, 3.46), (2.1, 0.8, 0.1))  # windscreen
    m.box(body, (0, 0.75, 0), (2.3, 0.3, 7.0))  # chassis
    m.box(cargo, (0, 2.05, -1.0), (2.5, 2.3, 5.0))  # cargo box
    m.box(front, (0.85, 0.85, 3.51), (0.35, 0.15, 0.04))
    m.box(front, (-0.85, 0.85, 3.51), (0.35, 0.15, 0.04))
    wheels(m, tyre, (-1.0, 1.0), (2.5, -1.8, -2.9), 0.5, 0.35, hub)
    return m


def make_bus():
    m = Mesh("bus")
    body = m.material("paint", colour(*PALETTE["bus"]), 0.5)
    glass = m.material("glass", GLASS, 0.1)
    tyre = m.material("tyre", TYRE)
    hub = m.material("hub", METAL, 0.3)
    front = m.material("headlight", LIGHT_FRONT, 0.2)
    roof = m.material("roof", colour(220, 220, 220), 0.6)
    m.box(body, (0, 1.05, 0), (2.5, 1.5, 12.0))  # lower body 0.3..1.8
    m.box(glass, (0, 2.25, 0), (2.46, 0.9, 11.96))  # window band
    m.box(body, (0, 2.85, 0), (2.5, 0.3, 12.0))  # upper band
    m.box(roof, (0, 3.05, -0.5), (1.6, 0.1, 4.0))  # roof equipment
    m.box(glass, (0, 1.5, 6.0), (2.2, 1.6, 0.06))  # windscreen
    m.box(front, (0.9, 0.6, 6.01), (0.35, 0.15, 0.04))
    m.box(front, (-0.9, 0.6, 6.01), (0.35, 0.15, 0.04))
    wheels(m, tyre, (-1.05, 1.05), (4.0, -3.3), 0.5, 0.35, hub)
    return m


def person_parts(m, skin, shirt, trousers, shoes, riding=False, base=(0.0, 0.0, 0.0)):
    """A standing or (riding=True) cycling person; base is the point between the feet."""
    bx, by, bz = base
    if not riding:
        for side in (-0.11, 0.11):
            m.beam(trousers, (bx + side, by + 0.9, bz), (bx + side, by + 0.08, bz), 0.15)
            m.box(shoes, (bx + side, by + 0.04, bz + 0.04), (0.12, 0.08, 0.26))
        m.frustum_box(shirt, (bx, by + 0.88, bz), (0.36, 0.22), (0.46, 0.26), 0.6)
        for side in (-0.27, 0.27):
            m.beam(shirt, (bx + side, by + 1.44, bz), (bx + side * 1.1, by + 0.8, bz + 0.03), 0.1)
            m.sphere(skin, (bx + side * 1.1, by + 0.76, bz + 0.03), (0.05, 0.06, 0.05), 6, 4)
        m.cylinder(skin, (bx, by + 1.52, bz), 0.05, 0.1, axis="y", segments=6)
        m.sphere(skin, (bx, by + 1.65, bz), (0.1, 0.12, 0.11), 10, 6)
        return
    hip = np.array([bx, by + 0.95, bz - 0.25])
    shoulder = np.array([bx, by + 1.45, bz + 0.15])
    for side in (-0.11, 0.11):
        knee = np.array([bx + side, by + 0.75, bz + 0.15])
        foot = np.array([bx + side, by + 0.35, bz + 0.05 + (0.1 if side > 0 else -0.1)])
        m.beam(trousers, hip + [side, 0, 0], knee, 0.14)
        m.beam(trousers, knee, foot, 0.12)
        m.box(shoes, foot + [0, -0.03, 0.05], (0.1, 0.07, 0.22))
        hand = np.array([bx + side * 2.2, by + 1.12, bz + 0.55])
        m.beam(shirt, shoulder + [side * 2.2, 0, 0], hand, 0.09)
        m.sphere(skin, hand, (0.045, 0.045, 0.045), 6, 4)
    m.beam(shirt, hip, shoulder, 0.3)
    m.sphere(skin, shoulder + [0, 0.22, 0.08], (0.1, 0.12, 0.11), 10, 6)


def make_person():
    m = Mesh("person")
    shirt = m.material("clothes", colour(*PALETTE["person"]), 0.9)
    skin = m.material("skin", SKIN, 0.9)
    trousers = m.material("trousers", TROUSERS, 0.9)
    shoes = m.material("shoes", DARK, 0.9)
    person_parts(m, skin, shirt, trousers, shoes)
    return m


def bicycle_parts(m, frame, tyre, metal, z0=0.0):
    r = 0.34
    for z in (z0 - 0.53, z0 + 0.53):
        m.cylinder(tyre, (0, r, z), r, 0.05, axis="x", segments=16)
        m.cylinder(metal, (0, r, z), 0.05, 0.07, axis="x", segments=6)
    rear_hub = (0, r, z0 - 0.53)
    front_hub = (0, r, z0 + 0.53)
    crank = (0, 0.32, z0 - 0.02)
    seat = (0, 0.86, z0 - 0.2)
    head = (0, 0.86, z0 + 0.38)
    m.beam(frame, crank, seat, 0.045)
    m.beam(frame, seat, head, 0.045)
    m.beam(frame, crank, head, 0.05)
    m.beam(frame, rear_hub, crank, 0.035)
    m.beam(frame, rear_hub, seat, 0.035)
    m.beam(frame, front_hub, (0, 0.95, z0 + 0.42), 0.04)  # fork
    m.beam(metal, (-0.25, 1.0, z0 + 0.4), (0.25, 1.0, z0 + 0.4), 0.035)  # handlebar
    m.box(metal, (0, 0.92, z0 - 0.22), (0.12, 0.05, 0.24))  # saddle
    m.cylinder(metal, crank, 0.09, 0.03, axis="x", segments=8)  # chainring


def make_bicycle():
    m = Mesh("bicycle")
    frame = m.material("frame", colour(*PALETTE["bicycle"]), 0.4)
    tyre = m.material("tyre", TYRE)
    metal = m.material("metal", METAL, 0.3)
    bicycle_parts(m, frame, tyre, metal)
    return m


def make_cyclist():
    m = Mesh("cyclist")
    shirt = m.material("rider", colour(*PALETTE["rider"]), 0.9)
    frame = m.material("frame", colour(*PALETTE["bicycle"]), 0.4)
    tyre = m.material("tyre", TYRE)
    metal = m.material("metal", METAL, 0.3)
    skin = m.material("skin", SKIN, 0.9)
    trousers = m.material("trousers", TROUSERS, 0.9)
    bicycle_parts(m, frame, tyre, metal)
    person_parts(m, skin, shirt, trousers, trousers, riding=True, base=(0.0, 0.0, 0.0))
    return m


def make_motorcycle():
    m = Mesh("motorcycle")
    body = m.material("paint", colour(*PALETTE["motorcycle"]), 0.4)
    tyre = m.material("tyre", TYRE)
    metal = m.material("metal", METAL, 0.3)
    seat = m.material("seat", DARK, 0.9)
    front = m.material("headlight", LIGHT_FRONT, 0.2)
    r = 0.32
    for z in (-0.7, 0.72):
        m.cylinder(tyre, (0, r, z), r, 0.14, axis="x", segments=14)
        m.cylinder(metal, (0, r, z), 0.12, 0.16, axis="x", segments=8)
    m.box(metal, (0, 0.45, -0.05), (0.3, 0.3, 0.55))  # engine
    m.frustum_box(body, (0, 0.6, 0.2), (0.34, 0.5), (0.26, 0.4), 0.28)  # tank
    m.box(seat, (0, 0.84, -0.35), (0.28, 0.1, 0.6))
    m.box(body, (0, 0.75, -0.72), (0.26, 0.12, 0.4))  # tail
    m.beam(metal, (0, r, -0.7), (0, 0.55, -0.1), 0.06)  # swing arm
    m.beam(metal, (0, r, 0.72), (0, 1.0, 0.5), 0.06)  # fork
    m.beam(metal, (-0.35, 1.02, 0.48), (0.35, 1.02, 0.48), 0.04)  # handlebar
    m.box(front, (0, 0.9, 0.62), (0.14, 0.14, 0.08))
    m.box(body, (0, 0.66, 0.72), (0.16, 0.05, 0.4))  # front mudguard
    return m


def make_tree():
    m = Mesh("tree")
    bark = m.material("trunk", BARK, 0.9)
    leaves = m.material("crown", colour(*PALETTE["vegetation"]), 0.9)
    m.cylinder(bark, (0, 1.3, 0), 0.16, 2.6, axis="y", segments=8, radius_top=0.1)
    m.sphere(leaves, (0, 3.6, 0), (1.6, 1.9, 1.6), 12, 8)
    m.sphere(leaves, (0.5, 4.7, 0.3), (0.9, 0.8, 0.9), 8, 5)
    return m


HEDGE_SIZE = (0.9, 1.2, 3.0)  # W (x), H (y), L (z), metres: the model's own box
HEDGE_LEAVES = 1250
# Leaf colours around the X-Rite ColorChecker's "foliage" patch (sRGB 87, 108, 67): real leaves
# are an olive, not the saturated green of the palette's vegetation class; some darker, some
# yellower, some dry.
HEDGE_GREENS = [(87, 108, 67), (70, 88, 52), (104, 112, 66), (58, 72, 44), (118, 118, 78)]


def hedge_surface_point(rng):
    """A point on the hedge's rounded box (sides, ends and top; not the bottom) and its outward
    normal, drawn uniformly over the area."""
    w, h, l = HEDGE_SIZE
    faces = [("x", l * h), ("x", l * h), ("z", w * h), ("z", w * h), ("y", w * l)]
    areas = np.array([a for _, a in faces])
    face = rng.choice(len(faces), p=areas / areas.sum())
    u, v = rng.random(), rng.random()
    if face < 2:
        sign = 1.0 if face == 0 else -1.0
        p, n = np.array([sign * w / 2, v * h, (u - 0.5) * l]), np.array([sign, 0.0, 0.0])
    elif face < 4:
        sign = 1.0 if face == 2 else -1.0
        p, n = np.array([(u - 0.5) * w, v * h, sign * l / 2]), np.array([0.0, 0.0, sign])
    else:
        p, n = np.array([(u - 0.5) * w, h, (v - 0.5) * l]), np.array([0.0, 1.0, 0.0])
    # Rounded edges: a point near an edge leans both ways and sinks in (a clipped hedge's
    # corners are round, not square).
    edge = np.array([abs(p[0]) / (w / 2), p[1] / h, abs(p[2]) / (l / 2)])
    lean = np.clip((edge - 0.85) / 0.15, 0.0, 1.0) * np.sign([p[0], 1.0, p[2]])
    lean[1] = max(lean[1], 0.0)
    n = n + lean * (1.0 - np.abs(n))
    n /= np.linalg.norm(n)
    return p - 0.12 * lean * (1.0 - np.abs(n)), n


def make_hedge():
    """A clipped hedge: many small leaves scattered over and just under the surface of a
    rounded box, each tilted at random and in one of a few greens, around a dark core. Stereo
    sees it as a real hedge is seen: a rough, porous surface, not a smooth blob."""
    m = Mesh("hedge")
    rng = np.random.default_rng(7)
    greens = [m.material(f"leaves {i}", colour(*c), 0.9) for i, c in enumerate(HEDGE_GREENS)]
    core = m.material("core", colour(30, 36, 22), 1.0)
    w, h, l = HEDGE_SIZE
    m.box(core, (0, (h - 0.25) / 2, 0), (w - 0.4, h - 0.25, l - 0.4))
    for _ in range(HEDGE_LEAVES):
        p, n = hedge_surface_point(rng)
        p = p - n * rng.exponential(0.07)  # leaves stand at different depths
        n = n + rng.normal(0.0, 0.6, 3)  # and face every way but inwards
        n /= np.linalg.norm(n)
        a = np.cross(n, rng.normal(size=3))
        a /= np.linalg.norm(a)
        b = np.cross(n, a)
        half_a, half_b = rng.uniform(0.05, 0.09), rng.uniform(0.03, 0.06)
        corners = [p - half_a * a - half_b * b, p + half_a * a - half_b * b,
                   p + half_a * a + half_b * b, p - half_a * a + half_b * b]
        corners = [np.array([c[0], max(c[1], 0.0), c[2]]) for c in corners]
        m.quad(greens[rng.integers(len(greens))], *corners)
    return m


def make_building():
    m = Mesh("building")
    wall = m.material("walls", colour(*PALETTE["building"]), 0.9)
    glass = m.material("windows", GLASS, 0.1)
    roof = m.material("roof", ROOF, 0.9)
    door = m.material("door", colour(60, 40, 30), 0.9)
    w, d, h = 10.0, 8.0, 9.0
    m.box(wall, (0, h / 2.0, 0), (w, h, d))
    m.box(roof, (0, h + 0.15, 0), (w + 0.3, 0.3, d + 0.3))
    floors = 3
    for f in range(floors):
        y = 1.6 + f * 3.0
        for i in range(4):
            x = -w / 2.0 + w * (i + 0.5) / 4.0
            if f == 0 and i == 1:
                m.box(door, (x, 1.1, d / 2.0 + 0.03), (1.2, 2.2, 0.06))
                continue
            m.box(glass, (x, y, d / 2.0 + 0.03), (1.3, 1.5, 0.06))
            m.box(glass, (x, y, -d / 2.0 - 0.03), (1.3, 1.5, 0.06))
        for i in range(3):
            z = -d / 2.0 + d * (i + 0.5) / 3.0
            m.box(glass, (w / 2.0 + 0.03, y, z), (0.06, 1.5, 1.3))
            m.box(glass, (-w / 2.0 - 0.03, y, z), (0.06, 1.5, 1.3))
    return m


def make_pole():
    m = Mesh("pole")
    metal = m.material("pole", colour(*PALETTE["pole"]), 0.5)
    lamp = m.material("lamp", LIGHT_FRONT, 0.2)
    m.cylinder(metal, (0, 0.2, 0), 0.14, 0.4, axis="y", segments=8)  # foot
    m.cylinder(metal, (0, 3.0, 0), 0.08, 6.0, axis="y", segments=8, radius_top=0.06)
    m.beam(metal, (0, 5.9, 0), (0, 6.1, 1.2), 0.06)  # arm towards the road (+z)
    m.box(metal, (0, 6.1, 1.35), (0.25, 0.12, 0.55))
    m.box(lamp, (0, 6.03, 1.35), (0.2, 0.03, 0.45))
    return m


def make_traffic_sign():
    m = Mesh("traffic sign")
    metal = m.material("post", colour(*PALETTE["pole"]), 0.5)
    face = m.material("sign", colour(*PALETTE["traffic sign"]), 0.6)
    border = m.material("border", colour(200, 30, 30), 0.6)
    m.cylinder(metal, (0, 1.25, 0), 0.04, 2.5, axis="y", segments=8)
    # A triangular warning sign facing +z: red border triangle with a yellow face in front.
    top, left, right = (0, 2.95, 0.05), (-0.45, 2.17, 0.05), (0.45, 2.17, 0.05)
    m.tri(border, left, right, top)
    m.tri(metal, (0.45, 2.17, 0.03), (-0.45, 2.17, 0.03), (0, 2.95, 0.03))  # grey back
    m.tri(face, (-0.33, 2.24, 0.06), (0.33, 2.24, 0.06), (0, 2.8, 0.06))
    m.box(metal, (0, 2.45, 0.02), (0.9, 0.05, 0.02))  # backing strut
    return m


def make_traffic_light():
    m = Mesh("traffic light")
    metal = m.material("pole", colour(*PALETTE["pole"]), 0.5)
    housing = m.material("housing", colour(*PALETTE["traffic light"]), 0.6)
    red = m.material("red", colour(230, 30, 30), 0.2)
    amber = m.material("amber", colour(250, 170, 30), 0.2)
    green = m.material("green", colour(40, 200, 80), 0.2)
    m.cylinder(metal, (0, 1.4, 0), 0.06, 2.8, axis="y", segments=8)
    m.box(housing, (0, 3.25, 0), (0.35, 0.95, 0.3))
    for y, lamp in ((3.55, red), (3.25, amber), (2.95, green)):
        m.cylinder(lamp, (0, y, 0.16), 0.1, 0.03, axis="z", segments=10)
    return m


MODELS = {
    "car.glb": make_car, "truck.glb": make_truck, "bus.glb": make_bus,
    "person.glb": make_person, "cyclist.glb": make_cyclist, "bicycle.glb": make_bicycle,
    "motorcycle.glb": make_motorcycle, "tree.glb": make_tree, "hedge.glb": make_hedge, "building.glb": make_building,
    "pole.glb": make_pole, "traffic_sign.glb": make_traffic_sign,
    "traffic_light.glb": make_traffic_light,
}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path,
                        default=Path(__file__).resolve().parent.parent / "assets" / "models")
    parser.add_argument("--check", action="store_true",
                        help="compare with the files in --out instead of writing them")
    args = parser.parse_args()
    failed = False
    for file_name, make in MODELS.items():
        mesh = make()
        triangles = mesh.triangle_count()
        budget = TRIANGLE_BUDGETS.get(file_name, TRIANGLE_BUDGET)
        if triangles > budget:
            print(f"make-models: error: {file_name}: {triangles} triangles > {budget}",
                  file=sys.stderr)
            return 1
        data = to_glb(mesh)
        target = args.out / file_name
        if args.check:
            if not target.exists() or target.read_bytes() != data:
                print(f"make-models: {target} differs from the generator's output",
                      file=sys.stderr)
                failed = True
            continue
        args.out.mkdir(parents=True, exist_ok=True)
        tmp = target.with_name("." + file_name + ".tmp")
        tmp.write_bytes(data)
        tmp.replace(target)
        print(f"{target}: {triangles} triangles, {len(data)} bytes", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
