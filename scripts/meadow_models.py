#!/usr/bin/env python3
"""Write the meadow's small OBJ models (scenes/meadow.scn) into assets/meadow/:
a grass blade, a clump of small round grass, a flower (stem, leaves, petals),
a butterfly and an ant. Each model stands on y = 0 and is about a unit tall
(the scene scales its instances). Run from the repository root; the files it
writes are committed, so the scene needs nothing but glint."""

import math
import os

OUT = "assets/meadow"


class Obj:
    def __init__(self, name):
        self.name, self.v, self.n, self.f, self.groups = name, [], [], [], []

    def vertex(self, p, n):
        self.v.append(p)
        self.n.append(n)
        return len(self.v)

    def group(self, material):
        self.groups.append((len(self.f), material))

    def tri(self, a, b, c):
        self.f.append((a, b, c))

    def quad(self, a, b, c, d):
        self.tri(a, b, c)
        self.tri(a, c, d)

    def write(self, mtl=None):
        path = os.path.join(OUT, self.name + ".obj")
        with open(path, "w") as out:
            out.write(f"# {self.name}: written by scripts/meadow_models.py\n")
            if mtl:
                out.write(f"mtllib {self.name}.mtl\n")
            for x, y, z in self.v:
                out.write(f"v {x:.4f} {y:.4f} {z:.4f}\n")
            for x, y, z in self.n:
                out.write(f"vn {x:.4f} {y:.4f} {z:.4f}\n")
            starts = dict(self.groups)
            for k, (a, b, c) in enumerate(self.f):
                if k in starts:
                    out.write(f"usemtl {starts[k]}\n")
                out.write(f"f {a}//{a} {b}//{b} {c}//{c}\n")
        if mtl:
            with open(os.path.join(OUT, self.name + ".mtl"), "w") as out:
                for name, rgb in mtl:
                    out.write(f"newmtl {name}\nKd {rgb[0]} {rgb[1]} {rgb[2]}\nKs 0.1 0.1 0.1\nNs 20\n")


def rot_y(p, a):
    x, y, z = p
    c, s = math.cos(a), math.sin(a)
    return (c * x + s * z, y, -s * x + c * z)


def blade(obj, height, width, lean, turn, at=(0.0, 0.0)):
    """A tapered, curved blade in its own plane, turned `turn` about y."""
    levels = [0.0, 0.3, 0.6, 0.85, 1.0]
    rows = []
    for t in levels:
        half = width * (1.0 - t) * 0.5 + 0.002
        z = lean * t * t
        row = []
        for side in (-half, half) if t < 1.0 else (0.0,):
            p = rot_y((side, height * t, z), turn)
            n = rot_y((0.0, -2.0 * lean * t / height * 0.3, 1.0), turn)
            row.append(obj.vertex((p[0] + at[0], p[1], p[2] + at[1]), n))
        rows.append(row)
    for lo, hi in zip(rows, rows[1:]):
        if len(hi) == 2:
            obj.quad(lo[0], lo[1], hi[1], hi[0])
        else:
            obj.tri(lo[0], lo[1], hi[0])


def main():
    os.makedirs(OUT, exist_ok=True)
    tall = Obj("blade")
    tall.group("blade")
    blade(tall, 1.0, 0.07, 0.18, 0.0)
    tall.write([("blade", (0.32, 0.6, 0.14))])

    clump = Obj("small_grass")
    clump.group("grass")
    for k in range(7):
        a = k * 2.0 * math.pi / 7
        blade(clump, 0.35 + 0.06 * (k % 3), 0.06, 0.12, a, at=(0.04 * math.cos(a), 0.04 * math.sin(a)))
    clump.write([("grass", (0.22, 0.5, 0.12))])

    flower = Obj("flower")
    flower.group("stem")
    blade(flower, 0.55, 0.025, 0.05, 0.0)
    blade(flower, 0.55, 0.025, 0.05, math.pi / 2)
    flower.group("leaf")
    blade(flower, 0.28, 0.12, 0.12, 0.8)
    blade(flower, 0.22, 0.12, 0.12, 3.6)
    flower.group("petal")
    top = (0.0, 0.55, 0.05 * 0.55)
    centre = flower.vertex(top, (0.0, 1.0, 0.0))
    ring = []
    for k in range(10):
        a = k * 2.0 * math.pi / 10
        r = 0.13 if k % 2 == 0 else 0.05
        ring.append(flower.vertex((top[0] + r * math.cos(a), top[1] + 0.02, top[2] + r * math.sin(a)), (0.0, 1.0, 0.0)))
    for k in range(10):
        flower.tri(centre, ring[(k + 1) % 10], ring[k])
    flower.write([("stem", (0.25, 0.5, 0.12)), ("leaf", (0.2, 0.55, 0.15)), ("petal", (0.95, 0.9, 0.35))])

    fly = Obj("butterfly")
    fly.group("wing")
    for s in (-1.0, 1.0):
        pts = [(0.05 * s, 0.0, -0.35), (0.05 * s, 0.0, 0.45), (1.0 * s, 0.0, 0.7), (0.9 * s, 0.0, -0.6)]
        ids = [fly.vertex(p, (0.0, 1.0, 0.0)) for p in pts]
        fly.quad(*(ids if s > 0 else ids[::-1]))
    fly.group("body")
    body = [fly.vertex((x, 0.02, z), (0.0, 1.0, 0.0)) for x, z in ((-0.05, -0.5), (0.05, -0.5), (0.05, 0.55), (-0.05, 0.55))]
    fly.quad(body[3], body[2], body[1], body[0])
    fly.write([("wing", (0.95, 0.55, 0.1)), ("body", (0.1, 0.08, 0.05))])

    ant = Obj("ant")
    ant.group("ant")
    for z0, z1, w, h in ((-0.6, -0.15, 0.18, 0.2), (-0.12, 0.12, 0.1, 0.14), (0.15, 0.45, 0.14, 0.16)):
        corners = [(x, y, z) for z in (z0, z1) for y in (0.05, 0.05 + h) for x in (-w / 2, w / 2)]
        ids = [ant.vertex(c, (0.0, 1.0, 0.0)) for c in corners]
        # Six faces of the box (x fastest, then y, then z), counter-clockwise outside.
        for a, b, c, d in ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)):
            ant.quad(ids[a], ids[b], ids[c], ids[d])
    ant.write([("ant", (0.06, 0.04, 0.03))])


if __name__ == "__main__":
    main()
