#!/usr/bin/env python3
"""Where the glass sphere's caustic folds cross the floor (README, "The glass sphere at its own
height has no finite variance; raised, it is a test").

Traces, in closed form, rays from a point of the light through both refractions of the sphere
(IOR 1.5, radius 0.5, centre (0, h, 0)) to the floor y = 0, over a grid of directions across
the sphere's disc as the light point sees it, and differentiates the map direction -> floor
point by finite differences. A determinant that changes sign is a fold, where the generalized
geometric term of a manifold estimator is unbounded; the smallest |det| against the median
says how heavy the term's tail is.

    python3 passes/partitioned_sms/tests/sphere_caustic_folds.py [h ...]   (default 0.6 1.0 1.5 1.7)
"""
import math
import sys

IOR, RADIUS = 1.5, 0.5
LIGHT = (0.6, 3.0, -0.3)  # the light's centre in glass_sphere.json


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def mul(a, s):
    return tuple(x * s for x in a)


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def normalize(a):
    return mul(a, 1.0 / math.sqrt(dot(a, a)))


def refract(d, n, eta):
    """Snell's law; n faces against d, eta = n1 / n2. None on total internal reflection."""
    c = -dot(d, n)
    k = 1.0 - eta * eta * (1.0 - c * c)
    return None if k < 0 else normalize(add(mul(d, eta), mul(n, eta * c - math.sqrt(k))))


def hit_sphere(o, d, centre, far):
    oc = sub(o, centre)
    b = dot(oc, d)
    disc = b * b - (dot(oc, oc) - RADIUS * RADIUS)
    if disc < 0:
        return None
    t = -b + math.sqrt(disc) if far else -b - math.sqrt(disc)
    return add(o, mul(d, t)) if t > 1e-6 else None


def floor_point(light, centre, u, v):
    """The floor point of the ray aimed at disc point (u, v), |(u, v)| < 1; None if it misses."""
    axis = normalize(sub(centre, light))
    t1 = normalize((axis[1], -axis[0], 0.0))
    t2 = (axis[1] * t1[2] - axis[2] * t1[1], axis[2] * t1[0] - axis[0] * t1[2],
          axis[0] * t1[1] - axis[1] * t1[0])
    d = normalize(sub(add(centre, add(mul(t1, u * RADIUS), mul(t2, v * RADIUS))), light))
    p1 = hit_sphere(light, d, centre, far=False)
    if p1 is None:
        return None
    d1 = refract(d, normalize(sub(p1, centre)), 1.0 / IOR)
    p2 = hit_sphere(p1, d1, centre, far=True) if d1 else None
    if p2 is None:
        return None
    d2 = refract(d1, mul(normalize(sub(p2, centre)), -1.0), IOR)
    if d2 is None or d2[1] >= 0:
        return None
    t = -p2[1] / d2[1]
    return (p2[0] + t * d2[0], p2[2] + t * d2[2])


def determinants(h, n=200, eps=1e-5):
    centre = (0.0, h, 0.0)
    out = []
    for i in range(n):
        for j in range(n):
            u, v = -1 + 2 * (i + 0.5) / n, -1 + 2 * (j + 0.5) / n
            if u * u + v * v >= 1:
                continue
            a = floor_point(LIGHT, centre, u, v)
            b = floor_point(LIGHT, centre, u + eps, v)
            c = floor_point(LIGHT, centre, u, v + eps)
            if a and b and c:
                out.append(((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) /
                           (eps * eps))
    return out


def main():
    heights = [float(x) for x in sys.argv[1:]] or [0.6, 1.0, 1.5, 1.7]
    print(f"{'centre h':>8} {'directions':>10} {'det > 0':>8} {'det < 0':>8} "
          f"{'median / min |det|':>18}")
    for h in heights:
        dets = determinants(h)
        negative = sum(1 for d in dets if d < 0)
        mags = sorted(abs(d) for d in dets)
        print(f"{h:8.2f} {len(dets):10d} {len(dets) - negative:8d} {negative:8d} "
              f"{mags[len(mags) // 2] / mags[0]:18.0f}")


if __name__ == "__main__":
    main()
