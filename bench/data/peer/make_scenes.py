#!/usr/bin/env python3
# Writes the peer-benchmark scenes (bench/peer_cycles.sh) as world-space OBJ parts, so that
# Loom and Blender read the same triangles: no transform conventions to match. Run once; the
# outputs are committed.
import math, os

def rot(axis, deg, p):
    # Rodrigues, right-handed, degrees.
    ax = [a / math.sqrt(sum(c * c for c in axis)) for a in axis]
    t = math.radians(deg); c, s = math.cos(t), math.sin(t)
    d = sum(ax[i] * p[i] for i in range(3))
    cr = [ax[1] * p[2] - ax[2] * p[1], ax[2] * p[0] - ax[0] * p[2], ax[0] * p[1] - ax[1] * p[0]]
    return [p[i] * c + cr[i] * s + ax[i] * d * (1 - c) for i in range(3)]

def xf(p, scale=(1, 1, 1), rotate=None, translate=(0, 0, 0)):
    p = [p[i] * scale[i] for i in range(3)]
    if rotate: p = rot(rotate[0], rotate[1], p)
    return [p[i] + translate[i] for i in range(3)]

RECT = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]  # normal +z (counter-clockwise)

def rect(**k):
    return [[xf(v, **k) for v in RECT]]

def cube(**k):
    faces = []
    for axis in range(3):
        for sign in (-1, 1):
            quad = []
            for (a, b) in [(-1, -1), (1, -1), (1, 1), (-1, 1)]:
                p = [0, 0, 0]
                p[axis] = sign
                p[(axis + 1) % 3] = a
                p[(axis + 2) % 3] = b
                quad.append(p)
            if sign < 0: quad.reverse()  # outward normals
            faces.append([xf(v, **k) for v in quad])
    return faces

def sphere(center, radius, rings=24, segments=48):
    faces = []
    def pt(i, j):
        th, ph = math.pi * i / rings, 2 * math.pi * j / segments
        return [center[0] + radius * math.sin(th) * math.cos(ph), center[1] + radius * math.cos(th),
                center[2] - radius * math.sin(th) * math.sin(ph)]
    for i in range(rings):
        for j in range(segments):
            a, b, c, d = pt(i, j), pt(i + 1, j), pt(i + 1, j + 1), pt(i, j + 1)
            if i == 0: faces.append([a, b, c])
            elif i == rings - 1: faces.append([a, b, d])
            else: faces.append([a, b, c, d])
    return faces

def write(path, faces):
    with open(path, "w") as f:
        f.write("# world-space part of a peer-benchmark scene (make_scenes.py)\n")
        n = 0
        for face in faces:
            for v in face: f.write("v %.7g %.7g %.7g\n" % tuple(v))
            f.write("f " + " ".join(str(n + i + 1) for i in range(len(face))) + "\n")
            n += len(face)

os.makedirs("cornell_grey", exist_ok=True)
write("cornell_grey/floor.obj", rect(rotate=((1, 0, 0), -90)))
write("cornell_grey/ceiling.obj", rect(rotate=((1, 0, 0), 90), translate=(0, 2, 0)))
write("cornell_grey/back.obj", rect(translate=(0, 1, -1)))
write("cornell_grey/left.obj", rect(rotate=((0, 1, 0), 90), translate=(-1, 1, 0)))
write("cornell_grey/right.obj", rect(rotate=((0, 1, 0), -90), translate=(1, 1, 0)))
write("cornell_grey/short_box.obj", cube(scale=(0.3, 0.3, 0.3), rotate=((0, 1, 0), -17), translate=(0.33, 0.3, 0.37)))
write("cornell_grey/tall_box.obj", cube(scale=(0.3, 0.6, 0.3), rotate=((0, 1, 0), 18), translate=(-0.33, 0.6, -0.29)))
write("cornell_grey/light.obj", rect(scale=(0.235, 0.19, 1), rotate=((1, 0, 0), 90), translate=(-0.005, 1.98, -0.03)))

os.makedirs("glossy_env", exist_ok=True)
write("glossy_env/floor.obj", rect(scale=(4, 4, 1), rotate=((1, 0, 0), -90)))
write("glossy_env/sphere_smooth_metal.obj", sphere((-1.1, 0.5, 0), 0.5))
write("glossy_env/sphere_diffuse.obj", sphere((0, 0.5, 0), 0.5))
write("glossy_env/sphere_rough_gold.obj", sphere((1.1, 0.5, 0), 0.5))
write("glossy_env/light.obj", rect(scale=(0.5, 0.5, 1), rotate=((1, 0, 0), 90), translate=(0.5, 3, 1)))
