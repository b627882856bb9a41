#!/usr/bin/env python3
"""Write the underwater scene's OBJ models (scenes/underwater.scn) into
assets/underwater/: a fish and a shark, each facing +z with its nose at
z = +0.5 and its tail fin reaching z = -0.6 (a unit long), textured by
assets/underwater/fish.png (examples/gen_textures.rs) (u from nose to tail, v from back to belly). The
scene's materials swing the tails (`motion` `swim`). Run from the repository
root; the files it writes are committed, so the scene needs nothing but glint."""

import math
import os

OUT = "assets/underwater"


class Obj:
    def __init__(self, name):
        self.name, self.v, self.vt, self.n, self.f = name, [], [], [], []

    def vertex(self, p, uv, n):
        self.v.append(p)
        self.vt.append(uv)
        l = math.sqrt(sum(c * c for c in n)) or 1.0
        self.n.append(tuple(c / l for c in n))
        return len(self.v)

    def tri(self, a, b, c):
        self.f.append((a, b, c))

    def write(self, material, texture, kd):
        with open(os.path.join(OUT, self.name + ".obj"), "w") as out:
            out.write(f"# {self.name}: written by scripts/underwater_models.py\n")
            out.write(f"mtllib {self.name}.mtl\nusemtl {material}\n")
            for x, y, z in self.v:
                out.write(f"v {x:.4f} {y:.4f} {z:.4f}\n")
            for u, v in self.vt:
                out.write(f"vt {u:.4f} {v:.4f}\n")
            for x, y, z in self.n:
                out.write(f"vn {x:.4f} {y:.4f} {z:.4f}\n")
            for a, b, c in self.f:
                out.write(f"f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}\n")
        with open(os.path.join(OUT, self.name + ".mtl"), "w") as out:
            out.write(f"newmtl {material}\nKd {kd[0]} {kd[1]} {kd[2]}\nKs 0.3 0.3 0.3\nNs 40\n")
            if texture:
                out.write(f"map_Kd {texture}\n")


def body(obj, half_width, half_height, rings=14, sides=12, nose=0.5, tail=-0.35):
    """A lofted body from the nose to the tail root: ellipses whose size
    follows a fish's profile, widest a third of the way back."""
    rows = []
    for i in range(rings + 1):
        t = i / rings
        z = nose + (tail - nose) * t
        shape = math.sin(math.pi * min(1.0, t ** 0.8)) ** 0.7
        shape = max(shape, 0.12 * t)  # the tail root keeps some thickness
        row = []
        for k in range(sides):
            a = 2.0 * math.pi * k / sides
            x, y = half_width * shape * math.cos(a), half_height * shape * math.sin(a)
            n = (math.cos(a) / max(half_width, 1e-3), math.sin(a) / max(half_height, 1e-3), 0.3 * (1 - 2 * t))
            u = (nose - z) / 1.1
            v = 0.5 - 0.5 * math.sin(a)
            row.append(obj.vertex((x, y, z), (u, 1.0 - v), n))
        rows.append(row)
    for lo, hi in zip(rows, rows[1:]):
        for k in range(sides):
            a, b, c, d = lo[k], lo[(k + 1) % sides], hi[(k + 1) % sides], hi[k]
            obj.tri(a, c, b)
            obj.tri(a, d, c)
    tip = obj.vertex((0.0, 0.0, nose + 0.02), (0.0, 0.5), (0.0, 0.0, 1.0))
    for k in range(sides):
        obj.tri(tip, rows[0][k], rows[0][(k + 1) % sides])


def fin(obj, points, uv, normal_x=1.0):
    """A flat fin, both sides (points in the model's YZ plane, x = 0)."""
    for side in (1.0, -1.0):
        ids = [obj.vertex((0.0, y, z), uv, (side * normal_x, 0.0, 0.0)) for (y, z) in points]
        for k in range(1, len(ids) - 1):
            if side > 0:
                obj.tri(ids[0], ids[k], ids[k + 1])
            else:
                obj.tri(ids[0], ids[k + 1], ids[k])


def fish():
    obj = Obj("fish")
    body(obj, 0.09, 0.2)
    fin(obj, [(0.0, -0.33), (0.2, -0.6), (0.02, -0.5), (-0.2, -0.6)], (0.95, 0.5))
    fin(obj, [(0.16, 0.1), (0.3, -0.15), (0.14, -0.2)], (0.5, 0.05))
    obj.write("fish", "fish.png", (1.0, 1.0, 1.0))


def shark():
    obj = Obj("shark")
    body(obj, 0.1, 0.11, rings=18, sides=14)
    fin(obj, [(0.02, -0.33), (0.26, -0.62), (0.04, -0.45), (-0.14, -0.55)], (0.95, 0.2))
    fin(obj, [(0.09, 0.12), (0.3, -0.02), (0.09, -0.06)], (0.5, 0.05))
    # Pectoral fins, out to the sides and down.
    for side in (1.0, -1.0):
        ids = [
            obj.vertex((side * 0.08, -0.06, 0.18), (0.3, 0.9), (0.0, 1.0, 0.0)),
            obj.vertex((side * 0.3, -0.14, 0.02), (0.4, 0.9), (0.0, 1.0, 0.0)),
            obj.vertex((side * 0.08, -0.06, 0.05), (0.4, 0.9), (0.0, 1.0, 0.0)),
        ]
        obj.tri(*ids) if side > 0 else obj.tri(ids[0], ids[2], ids[1])
        ids = [obj.vertex(obj.v[i - 1], (0.3, 0.9), (0.0, -1.0, 0.0)) for i in ids]
        obj.tri(ids[0], ids[2], ids[1]) if side > 0 else obj.tri(*ids)
    obj.write("shark", None, (0.36, 0.4, 0.46))


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    fish()
    shark()
    print(f"wrote fish and shark to {OUT}")
