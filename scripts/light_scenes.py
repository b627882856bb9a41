"""Writes the light-cluster scenes: scenes/bench/lights_64.scn (the clustered
forward pass's benchmark: 64 small point lights over a plane) and
scenes/lights.scn (a night square lit by 1,264 small coloured lights, 1,000 of
them fireflies circling).
Run from the repository root: python3 scripts/light_scenes.py"""

import colorsys
import math
import random


def light(f, origin, color, intensity, rng):
    f.write('{ "classname" "light_point"\n"origin" "%.3f %.3f %.3f"\n' % origin)
    f.write('"color" "%.3f %.3f %.3f"\n"intensity" "%.3f"\n"range" "%.3f" }\n' % (*color, intensity, rng))


def bench_grid(side):
    """side x side small point lights in a grid over a 20 m plane, each reaching
    2.5 grid steps."""
    n = side * side
    step = 20.0 / side
    with open("scenes/bench/lights_%d.scn" % n, "w") as f:
        f.write("// %d small point lights in a grid of %d x %d over a 20 m plane: the clustered\n" % (n, side, side))
        if n <= 64:
            f.write("// forward pass against the loop over every light (glint bench --clusters on|off).\n")
        else:
            f.write("// forward pass and the binning, on the CPU and the GPU (glint bench --cull cpu|gpu).\n")
        f.write("// Written by scripts/light_scenes.py.\n")
        f.write('{ "classname" "world"\n"background" "0 0 0"\n"ambient" "0.02 0.02 0.02" }\n')
        f.write('{ "classname" "camera"\n"origin" "0 9 13"\n"target" "0 0 0"\n"fov" "50" }\n')
        f.write('{ "classname" "material"\n"name" "floor"\n"base_color" "0.8 0.8 0.8"\n"specular" "0.4"\n"smoothness" "0.5" }\n')
        f.write('{ "classname" "entity"\n"mesh" "plane"\n"material" "floor"\n"scale" "20 1 20" }\n')
        for i in range(n):
            x, z = i % side, i // side
            r, g, b = colorsys.hsv_to_rgb(i / n, 0.8, 1.0)
            light(f, (-10 + step * (x + 0.5), 0.3, -10 + step * (z + 0.5)), (r, g, b), 2.0 * (8 / side) ** 2, 0.8 * step)


def night_square():
    rnd = random.Random(49)
    with open("scenes/lights.scn", "w") as f:
        f.write("// A night square lit by 1,264 small coloured lights: 1,000 fireflies circling\n")
        f.write("// over the paving, strings of lanterns between the pillars, glowing orbs on\n")
        f.write("// them, a ring of spot lights on the fountain. Every point and spot light is\n")
        f.write("// binned into the view's light clusters; without them (--clusters off) a\n")
        f.write("// frame takes at most 64.\n")
        f.write("// Written by scripts/light_scenes.py.\n")
        f.write("// Render: glint render scenes/lights.scn -o lights.png\n")
        f.write('{ "classname" "world"\n"background" "0.002 0.003 0.008"\n"ambient" "0.006 0.006 0.01" }\n')
        f.write('{ "classname" "camera"\n"origin" "0 7 19"\n"target" "0 0.5 0"\n"fov" "55"\n"near" "0.1"\n"far" "80" }\n')
        f.write('{ "classname" "light_directional"\n"direction" "0.3 -1 -0.4"\n"color" "0.5 0.6 1"\n"intensity" "0.04" }\n')
        f.write('{ "classname" "material"\n"name" "paving"\n"base_color" "0.55 0.52 0.5"\n"specular" "0.6"\n"smoothness" "0.7" }\n')
        f.write('{ "classname" "material"\n"name" "stone"\n"base_color" "0.7 0.68 0.64"\n"specular" "0.3"\n"smoothness" "0.4" }\n')
        f.write('{ "classname" "material"\n"name" "brass"\n"shading" "metallic_roughness"\n"base_color" "0.9 0.75 0.45"\n"metallic" "1"\n"roughness" "0.3" }\n')
        f.write('{ "classname" "entity"\n"mesh" "plane"\n"material" "paving"\n"scale" "60 1 60" }\n')
        f.write('{ "classname" "entity"\n"mesh" "cylinder"\n"material" "stone"\n"origin" "0 0.3 0"\n"scale" "4 0.6 4" }\n')
        f.write('{ "classname" "entity"\n"mesh" "sphere"\n"material" "brass"\n"origin" "0 1.3 0"\n"scale" "1.4 1.4 1.4" }\n')
        # Lanterns glow in one of eight colours: a material each.
        hues = [colorsys.hsv_to_rgb(h / 8, 0.75, 1.0) for h in range(8)]
        for h, (r, g, b) in enumerate(hues):
            f.write('{ "classname" "material"\n"name" "lantern%d"\n"base_color" "0 0 0"\n"emissive" "%.3f %.3f %.3f" }\n' % (h, 2 * r, 2 * g, 2 * b))
        count = 0
        # Pillars in a ring, an orb of light over each.
        for k in range(16):
            a = k / 16 * math.tau
            x, z = 9 * math.cos(a), 9 * math.sin(a)
            f.write('{ "classname" "entity"\n"mesh" "cylinder"\n"material" "stone"\n"origin" "%.3f 1 %.3f"\n"scale" "0.4 2 0.4" }\n' % (x, z))
            r, g, b = colorsys.hsv_to_rgb(0.08, 0.6, 1.0)
            light(f, (x, 2.4, z), (r, g, b), 0.8, 3.0)
            count += 1
        # A ring of spot lights on the fountain.
        for k in range(16):
            a = k / 16 * math.tau
            x, z = 2.6 * math.cos(a), 2.6 * math.sin(a)
            r, g, b = colorsys.hsv_to_rgb(k / 16, 0.7, 1.0)
            f.write('{ "classname" "light_spot"\n"origin" "%.3f 0.1 %.3f"\n"direction" "%.3f 1 %.3f"\n' % (x, z, -0.3 * math.cos(a), -0.3 * math.sin(a)))
            f.write('"color" "%.3f %.3f %.3f"\n"intensity" "3"\n"range" "4"\n"inner_angle" "10"\n"outer_angle" "25" }\n' % (r, g, b))
            count += 1
        # Fireflies, each circling a point of its own.
        for k in range(1000):
            a, d = rnd.random() * math.tau, 8.5 * math.sqrt(rnd.random())
            x, y, z = d * math.cos(a), 0.25 + 1.2 * rnd.random(), d * math.sin(a)
            h = rnd.randrange(8)
            f.write('{ "classname" "light_point"\n"origin" "%.3f %.3f %.3f"\n' % (x, y, z))
            f.write('"color" "%.3f %.3f %.3f"\n"intensity" "0.06"\n"range" "%.3f"\n' % (*hues[h], 0.8 + 0.4 * rnd.random()))
            f.write('"circle" "%.2f %.2f %.0f" }\n' % (0.3 + 1.2 * rnd.random(), 3 + 5 * rnd.random(), 360 * rnd.random() - 180))
            count += 1
        # Strings of lanterns between the pillars, sagging.
        while count < 1264:
            k = rnd.randrange(16)
            a0, a1 = k / 16 * math.tau, (k + rnd.choice([1, 5, 8])) / 16 * math.tau
            t = rnd.random()
            x = 9 * ((1 - t) * math.cos(a0) + t * math.cos(a1))
            z = 9 * ((1 - t) * math.sin(a0) + t * math.sin(a1))
            y = 2.3 - 1.2 * 4 * t * (1 - t) * (0.6 + 0.4 * rnd.random())
            h = rnd.randrange(8)
            y -= 0.6
            f.write('{ "classname" "entity"\n"mesh" "sphere"\n"material" "lantern%d"\n"origin" "%.3f %.3f %.3f"\n"scale" "0.07 0.07 0.07" }\n' % (h, x, y, z))
            light(f, (x, y - 0.1, z), hues[h], 0.1, 1.2 + 0.5 * rnd.random())
            count += 1
        # Mist drifting up from the fountain, lit by the lights around it
        # (from the view's light clusters).
        f.write('{ "classname" "emitter"\n"origin" "0 1.2 0"\n"rate" "80"\n"burst" "200"\n"lifetime" "5 7"\n')
        f.write('"shape" "sphere 2.5"\n"speed" "0.05 0.2"\n"spread" "80"\n"gravity" "0 0.08 0"\n"drag" "0.6"\n"noise" "0.2 0.6"\n')
        f.write('"color" "0.8 0.8 0.85 0.3"\n"color_end" "0.8 0.8 0.85 0"\n"size" "1"\n"size_end" "1.8"\n"blend" "alpha"\n"lit" "1"\n"seed" "3" }\n')


for side in (8, 32, 64):
    bench_grid(side)
night_square()
