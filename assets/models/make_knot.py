#!/usr/bin/env python3
"""Writes knot.gltf (standard library only): a (2, 3) torus knot tube, 3,072
triangles, positions and normals, in one copper metallic-roughness material;
its buffer as a data: URI. For scenes/materials.scn.

    python3 assets/models/make_knot.py
"""

import base64
import json
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
SEGMENTS, SIDES, TUBE = 192, 8, 0.11


def knot(t):
    """A point of the (2, 3) torus knot, about 1.3 units across."""
    r = 0.42 + 0.18 * math.cos(3 * t)
    return (r * math.cos(2 * t), 0.18 * math.sin(3 * t), r * math.sin(2 * t))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def unit(a):
    n = math.sqrt(sum(x * x for x in a))
    return tuple(x / n for x in a)


def main():
    positions, normals, indices = [], [], []
    for i in range(SEGMENTS):
        t = 2 * math.pi * i / SEGMENTS
        p = knot(t)
        tangent = unit(sub(knot(t + 1e-3), knot(t - 1e-3)))
        side = unit(cross(tangent, (0.0, 1.0, 0.0)))
        up = cross(side, tangent)
        for j in range(SIDES):
            a = 2 * math.pi * j / SIDES
            n = tuple(math.cos(a) * s + math.sin(a) * u for s, u in zip(side, up))
            positions.append(tuple(c + TUBE * k for c, k in zip(p, n)))
            normals.append(n)
    for i in range(SEGMENTS):
        for j in range(SIDES):
            a = i * SIDES + j
            b = ((i + 1) % SEGMENTS) * SIDES + j
            c = ((i + 1) % SEGMENTS) * SIDES + (j + 1) % SIDES
            d = i * SIDES + (j + 1) % SIDES
            indices += [a, b, c, a, c, d]
    data = b"".join(struct.pack("<3f", *p) for p in positions)
    data += b"".join(struct.pack("<3f", *n) for n in normals)
    data += struct.pack(f"<{len(indices)}H", *indices)
    count = len(positions)
    lo = [min(p[k] for p in positions) for k in range(3)]
    hi = [max(p[k] for p in positions) for k in range(3)]
    gltf = {
        "asset": {"version": "2.0", "generator": "glint assets/models/make_knot.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "knot"}],
        "meshes": [{"name": "knot", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]}],
        "materials": [{
            "name": "copper",
            "pbrMetallicRoughness": {"baseColorFactor": [0.95, 0.64, 0.54, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.3},
        }],
        "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 12 * count, "target": 34962},
            {"buffer": 0, "byteOffset": 12 * count, "byteLength": 12 * count, "target": 34962},
            {"buffer": 0, "byteOffset": 24 * count, "byteLength": 2 * len(indices), "target": 34963},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5126, "count": count, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": len(indices), "type": "SCALAR"},
        ],
    }
    with open(os.path.join(HERE, "knot.gltf"), "w") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
