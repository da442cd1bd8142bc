#!/usr/bin/env python3
"""Writes scenes/creature_mane_regions.png, the region map of scenes/creature_mane.toml.

The built-in creature's UVs (`Mesh::creature` in crates/pelage-scene/src/mesh.rs) are its
side view over its bounding box: u from the tail (-z) to the nose (+z), v from the feet
to the ear tips. This script paints, in the creature's own coordinates (z, y) before it
is centred, region 1 (the mane) on the crown, down the neck and along the back ridge;
everything else is region 0 (the short fur of [hair.growth]). It needs only Python's
standard library: the bounding box is computed from the same parts, subdivided
icospheres scaled, turned and moved as the Rust code does.

    python3 scripts/creature_mane_map.py        # rewrites the PNG (8-bit grey, 128 x 96)
"""

import math
import struct
import zlib
from pathlib import Path

WIDTH, HEIGHT = 128, 96

# (radii, rotation about (axis, angle), centre, subdivisions) of each part, as in
# Mesh::creature.
PARTS = [
    ((0.5, 0.42, 0.7), None, (0.0, -0.1, -0.15), 3),
    ((0.36, 0.36, 0.36), None, (0.0, 0.32, 0.5), 2),
    ((0.15, 0.12, 0.14), None, (0.0, 0.24, 0.82), 1),
    ((0.1, 0.22, 0.05), ("z", -0.35), (0.2, 0.66, 0.45), 2),
    ((0.1, 0.22, 0.05), ("z", 0.35), (-0.2, 0.66, 0.45), 2),
    ((0.12, 0.12, 0.3), ("x", 0.6), (0.0, 0.12, -0.88), 1),
    ((0.12, 0.22, 0.12), None, (0.28, -0.5, 0.25), 1),
    ((0.12, 0.22, 0.12), None, (-0.28, -0.5, 0.25), 1),
    ((0.12, 0.22, 0.12), None, (0.28, -0.5, -0.5), 1),
    ((0.12, 0.22, 0.12), None, (-0.28, -0.5, -0.5), 1),
]


def rotate(p, rotation):
    if rotation is None:
        return p
    axis, a = rotation
    c, s = math.cos(a), math.sin(a)
    x, y, z = p
    if axis == "z":
        return (c * x - s * y, s * x + c * y, z)
    return (x, c * y - s * z, s * y + c * z)


def icosphere(level):
    """The unit directions of Mesh::icosphere(1, level): the icosahedron's 12, then each
    edge's normalised midpoint, `level` times (the set of vertices Rust makes)."""
    t = (1 + 5 ** 0.5) / 2
    raw = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
           (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    dirs = [normalise(v) for v in raw]
    tris = [0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2,
            10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11,
            6, 2, 10, 8, 6, 7, 9, 8, 1]
    for _ in range(level):
        cache, out = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                cache[key] = len(dirs)
                dirs.append(normalise(tuple(p + q for p, q in zip(dirs[a], dirs[b]))))
            return cache[key]

        for i in range(0, len(tris), 3):
            a, b, c = tris[i:i + 3]
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            out += [a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca]
        tris = out
    return dirs


def normalise(v):
    n = math.sqrt(sum(c * c for c in v))
    return tuple(c / n for c in v)


def bounds():
    """The (y, z) bounds of the creature's vertices before it is centred."""
    lo, hi = [math.inf, math.inf], [-math.inf, -math.inf]
    for radii, rotation, centre, level in PARTS:
        for d in icosphere(level):
            p = rotate(tuple(r * c for r, c in zip(radii, d)), rotation)
            y, z = p[1] + centre[1], p[2] + centre[2]
            lo = [min(lo[0], y), min(lo[1], z)]
            hi = [max(hi[0], y), max(hi[1], z)]
    return lo, hi


def is_mane(z, y):
    """The mane, in the creature's coordinates: from the crown behind the ears, down the
    neck and along the back ridge to the rump, above a line that rises toward the head."""
    if not -0.62 <= z <= 0.4:
        return False
    rise = min(max((z + 0.05) / 0.45, 0.0), 1.0)
    return y > 0.17 + 0.23 * rise


def png_grey(width, height, rows):
    raw = b"".join(b"\x00" + bytes(row) for row in rows)

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")


def main():
    (ylo, zlo), (yhi, zhi) = bounds()
    rows = []
    for row in range(HEIGHT):
        v = 1.0 - (row + 0.5) / HEIGHT  # row 0 is the top of the image: v = 1
        y = ylo + v * (yhi - ylo)
        rows.append([1 if is_mane(zlo + (col + 0.5) / WIDTH * (zhi - zlo), y) else 0 for col in range(WIDTH)])
    out = Path(__file__).resolve().parent.parent / "scenes" / "creature_mane_regions.png"
    out.write_bytes(png_grey(WIDTH, HEIGHT, rows))
    mane = sum(map(sum, rows))
    print(f"{out}: {WIDTH} x {HEIGHT}, {mane} mane texels ({mane / (WIDTH * HEIGHT):.1%}); "
          f"bounds y [{ylo:.3f}, {yhi:.3f}], z [{zlo:.3f}, {zhi:.3f}]")


if __name__ == "__main__":
    main()
