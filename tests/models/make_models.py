#!/usr/bin/env python3
"""Writes the small glTF test models in this folder (standard library only).

    python3 tests/models/make_models.py

- skinned.gltf + skinned.bin, and skinned.glb (the same model in one binary
  file): a tube of two joints; the upper joint bends 90 degrees about Z over
  one second. JOINTS_0 are u8, WEIGHTS_0 floats, indices u16.
- morph.gltf: a 9x9 grid with one morph target (a bump stored as a sparse
  accessor, with its normal offsets); its weight goes 0 -> 1 over one second.
  Buffers as data: URIs.
- uv1.gltf: a quad whose base colour map reads TEXCOORD_1 (TEXCOORD_0 is the
  mirror image of it, so reading the wrong set shows) through a KHR_texture_transform of rotation 90 degrees, offset (1, 0),
  lit by a KHR_lights_punctual spot light. Buffers and image as data: URIs.
- cutout.obj + cutout.mtl + cutout_mask.png: an OBJ quad whose material has a
  map_d (left half opaque, right half cut away) and no map_Kd.
- smoothing.obj: two octagonal prisms without normals. The left one has its
  sides in smoothing group 1 and flat caps (s off); the right one is flat all
  over (s off); faces before any s statement would smooth with each other.
"""

import base64
import json
import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
FLOAT, U8, U16 = 5126, 5121, 5123


class Builder:
    """Packs accessors into one buffer, each view 4-byte aligned."""

    def __init__(self):
        self.data = bytearray()
        self.views = []
        self.accessors = []

    def add(self, fmt, rows, kind, component, minmax=False, target=None):
        while len(self.data) % 4:
            self.data.append(0)
        offset = len(self.data)
        for row in rows:
            self.data += struct.pack("<" + fmt, *(row if isinstance(row, (list, tuple)) else [row]))
        view = {"buffer": 0, "byteOffset": offset, "byteLength": len(self.data) - offset}
        if target:
            view["target"] = target
        self.views.append(view)
        accessor = {"bufferView": len(self.views) - 1, "componentType": component, "count": len(rows), "type": kind}
        if minmax:
            columns = list(zip(*[r if isinstance(r, (list, tuple)) else [r] for r in rows]))
            accessor["min"] = [min(c) for c in columns]
            accessor["max"] = [max(c) for c in columns]
        self.accessors.append(accessor)
        return len(self.accessors) - 1

    def sparse(self, count, entries):
        """A VEC3 float accessor of `count` zeros except `entries` {index: xyz},
        stored sparse (no base buffer view)."""
        keys = sorted(entries)
        indices = self.add("H", keys, "SCALAR", U16)
        values = self.add("3f", [entries[k] for k in keys], "VEC3", FLOAT)
        self.accessors.pop()
        self.accessors.pop()
        columns = list(zip(*[entries[k] for k in keys]))
        self.accessors.append({
            "componentType": FLOAT, "count": count, "type": "VEC3",
            "min": [min(0.0, min(c)) for c in columns], "max": [max(0.0, max(c)) for c in columns],
            "sparse": {"count": len(keys), "indices": {"bufferView": len(self.views) - 2, "componentType": U16},
                       "values": {"bufferView": len(self.views) - 1}},
        })
        return len(self.accessors) - 1

    def document(self, uri, rest):
        doc = {"asset": {"version": "2.0", "generator": "glint tests/models/make_models.py"}}
        doc.update(rest)
        doc["buffers"] = [{"byteLength": len(self.data)}]
        if uri is not None:
            doc["buffers"][0]["uri"] = uri
        doc["bufferViews"] = self.views
        doc["accessors"] = self.accessors
        return doc


def data_uri(mime, payload):
    return "data:%s;base64,%s" % (mime, base64.b64encode(payload).decode())


def write_json(name, doc):
    with open(os.path.join(HERE, name), "w") as f:
        json.dump(doc, f, separators=(",", ":"))
        f.write("\n")


def skinned():
    b = Builder()
    rings, segments, radius = 9, 12, 0.25
    positions, normals, joints, weights, indices = [], [], [], [], []
    for r in range(rings):
        y = 2.0 * r / (rings - 1)
        upper = min(max((y - 0.75) / 0.5, 0.0), 1.0)
        for s in range(segments):
            a = 2.0 * math.pi * s / segments
            positions.append((radius * math.cos(a), y, radius * math.sin(a)))
            normals.append((math.cos(a), 0.0, math.sin(a)))
            joints.append((0, 1, 0, 0))
            weights.append((1.0 - upper, upper, 0.0, 0.0))
    for r in range(rings - 1):
        for s in range(segments):
            a, c = r * segments + s, r * segments + (s + 1) % segments
            indices += [a, a + segments, c, c, a + segments, c + segments]
    half = math.sqrt(0.5)
    attributes = {
        "POSITION": b.add("3f", positions, "VEC3", FLOAT, minmax=True, target=34962),
        "NORMAL": b.add("3f", normals, "VEC3", FLOAT, target=34962),
        "JOINTS_0": b.add("4B", joints, "VEC4", U8, target=34962),
        "WEIGHTS_0": b.add("4f", weights, "VEC4", FLOAT, target=34962),
    }
    index = b.add("H", indices, "SCALAR", U16, target=34963)
    ibm = [[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1], [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1]]
    inverse_bind = b.add("16f", ibm, "MAT4", FLOAT)
    times = b.add("f", [0.0, 1.0], "SCALAR", FLOAT, minmax=True)
    bend = b.add("4f", [(0, 0, 0, 1), (0, 0, half, half)], "VEC4", FLOAT)
    rest = {
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "tube", "mesh": 0, "skin": 0},
            {"name": "root", "children": [2]},
            {"name": "elbow", "translation": [0, 1, 0]},
        ],
        "meshes": [{"name": "tube", "primitives": [{"attributes": attributes, "indices": index, "material": 0}]}],
        "materials": [{"name": "skin", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.45, 0.2, 1], "metallicFactor": 0, "roughnessFactor": 0.6}}],
        "skins": [{"name": "arm", "joints": [1, 2], "inverseBindMatrices": inverse_bind}],
        "animations": [{"name": "bend", "samplers": [{"input": times, "output": bend, "interpolation": "LINEAR"}],
                        "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}}]}],
    }
    write_json("skinned.gltf", b.document("skinned.bin", rest))
    with open(os.path.join(HERE, "skinned.bin"), "wb") as f:
        f.write(b.data)
    # The same model as GLB: a JSON chunk and a BIN chunk, each padded to 4 bytes.
    text = json.dumps(b.document(None, rest), separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    blob = bytes(b.data) + b"\0" * (-len(b.data) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(blob), 0x004E4942) + blob
    with open(os.path.join(HERE, "skinned.glb"), "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)


def morph():
    b = Builder()
    n = 9
    positions, normals, bump, bump_normals, indices = [], [], [], [], []
    for j in range(n):
        for i in range(n):
            x, z = 2.0 * i / (n - 1) - 1.0, 2.0 * j / (n - 1) - 1.0
            h = 0.8 * math.exp(-3.0 * (x * x + z * z))
            # Normal of y = h(x, z): (-dh/dx, 1, -dh/dz), normalised.
            dx, dz = -6.0 * x * h, -6.0 * z * h
            length = math.sqrt(dx * dx + 1.0 + dz * dz)
            positions.append((x, 0.0, z))
            normals.append((0.0, 1.0, 0.0))
            bump.append((0.0, h, 0.0))
            bump_normals.append((-dx / length, 1.0 / length - 1.0, -dz / length))
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            indices += [a, a + n, a + 1, a + 1, a + n, a + n + 1]
    primitive = {
        "attributes": {"POSITION": b.add("3f", positions, "VEC3", FLOAT, minmax=True),
                       "NORMAL": b.add("3f", normals, "VEC3", FLOAT)},
        "indices": b.add("H", indices, "SCALAR", U16),
        # The bump's position offsets are sparse: only vertices that move are stored.
        "targets": [{"POSITION": b.sparse(len(bump), {i: d for i, d in enumerate(bump) if d[1] > 0.01}),
                     "NORMAL": b.add("3f", bump_normals, "VEC3", FLOAT)}],
        "material": 0,
    }
    times = b.add("f", [0.0, 1.0], "SCALAR", FLOAT, minmax=True)
    weights = b.add("f", [0.0, 1.0], "SCALAR", FLOAT)
    rest = {
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "grid", "mesh": 0}],
        "meshes": [{"name": "grid", "primitives": [primitive], "weights": [0.0]}],
        "materials": [{"name": "clay", "pbrMetallicRoughness": {"baseColorFactor": [0.3, 0.6, 0.9, 1], "metallicFactor": 0, "roughnessFactor": 0.5}}],
        "animations": [{"name": "rise", "samplers": [{"input": times, "output": weights, "interpolation": "LINEAR"}],
                        "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]}],
    }
    b_doc = b.document(None, rest)
    b_doc["buffers"][0]["uri"] = data_uri("application/octet-stream", bytes(b.data))
    write_json("morph.gltf", b_doc)


def png(width, height, pixel):
    rows = b"".join(b"\0" + b"".join(bytes(pixel(x, y)) for x in range(width)) for y in range(height))

    def chunk(tag, payload):
        return struct.pack(">I", len(payload)) + tag + payload + struct.pack(">I", zlib.crc32(tag + payload))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b"")


def uv1():
    b = Builder()
    # Quadrants: red top-left, green top-right, blue bottom-left, white bottom-right.
    colors = [[(220, 40, 40), (40, 200, 40)], [(40, 60, 220), (240, 240, 240)]]
    image = png(16, 16, lambda x, y: colors[y // 8][x // 8])
    corners = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
    primitive = {
        "attributes": {
            "POSITION": b.add("3f", corners, "VEC3", FLOAT, minmax=True),
            "NORMAL": b.add("3f", [(0, 0, 1)] * 4, "VEC3", FLOAT),
            "TEXCOORD_0": b.add("2f", [(1, 1), (0, 1), (0, 0), (1, 0)], "VEC2", FLOAT),
            "TEXCOORD_1": b.add("2f", [(0, 1), (1, 1), (1, 0), (0, 0)], "VEC2", FLOAT),
        },
        "indices": b.add("H", [0, 1, 2, 0, 2, 3], "SCALAR", U16),
        "material": 0,
    }
    transform = {"KHR_texture_transform": {"rotation": math.pi / 2, "offset": [1, 0]}}
    rest = {
        "extensionsUsed": ["KHR_texture_transform", "KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "spot", "color": [1, 1, 1], "intensity": 6, "range": 20,
             "spot": {"innerConeAngle": 0.35, "outerConeAngle": 0.5}}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": "quad", "mesh": 0},
                  {"name": "spot", "translation": [0, 0, 2.5], "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "meshes": [{"name": "quad", "primitives": [primitive]}],
        "materials": [{"name": "quadrants", "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0, "texCoord": 1, "extensions": transform},
            "metallicFactor": 0, "roughnessFactor": 1}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728}],
        "images": [{"uri": data_uri("image/png", image)}],
    }
    doc = b.document(None, rest)
    doc["buffers"][0]["uri"] = data_uri("application/octet-stream", bytes(b.data))
    write_json("uv1.gltf", doc)


def cutout():
    with open(os.path.join(HERE, "cutout_mask.png"), "wb") as f:
        f.write(png(8, 8, lambda x, y: (255, 255, 255) if x < 4 else (0, 0, 0)))
    with open(os.path.join(HERE, "cutout.mtl"), "w") as f:
        f.write("# Written by make_models.py: map_d masks the right half away.\n")
        f.write("newmtl leaf\nKd 0.2 0.7 0.2\nmap_d -bm 1 cutout_mask.png\n")
    with open(os.path.join(HERE, "cutout.obj"), "w") as f:
        f.write("# Written by make_models.py: a unit quad with uvs, one material.\nmtllib cutout.mtl\n")
        f.write("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n")
        f.write("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl leaf\nf 1/1/1 2/2/1 3/3/1 4/4/1\n")


def smoothing():
    lines = ["# Written by make_models.py: two octagonal prisms, no normals."]
    count = 0
    for name, x, sides in (("rounded", -1.1, "s 1"), ("faceted", 1.1, "s off")):
        lines.append("o " + name)
        for y in (-0.8, 0.8):
            for k in range(8):
                a = 2 * math.pi * (k + 0.5) / 8
                lines.append("v %.6f %.6f %.6f" % (x + math.cos(a), y, -math.sin(a)))
        bottom = [count + 1 + k for k in range(8)]
        top = [count + 9 + k for k in range(8)]
        lines.append(sides)
        for k in range(8):
            j = (k + 1) % 8
            lines.append("f %d %d %d %d" % (bottom[k], bottom[j], top[j], top[k]))
        lines.append("s off")
        lines.append("f " + " ".join(str(i) for i in reversed(bottom)))
        lines.append("f " + " ".join(str(i) for i in top))
        count += 16
    with open(os.path.join(HERE, "smoothing.obj"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    skinned()
    morph()
    uv1()
    cutout()
    smoothing()
