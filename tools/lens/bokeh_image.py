#!/usr/bin/env python3
"""Writes a greyscale bokeh image (`aperture_image`, docs/lenses.md) without any imaging library:
a five-pointed star or a heart, white on black, anti-aliased by 4×4 supersampling.

    python3 tools/lens/bokeh_image.py star /tmp/star.png --size 128
    python3 tools/lens/bokeh_image.py heart /tmp/heart.png

The shape fills the image's inscribed circle (the aperture's round stop), point up.
"""

import argparse
import math
import struct
import zlib


def star(x, y, points=5, inner=0.45):
    """Inside a star of `points` points (outer radius 0.95, inner `inner` × it), point up."""
    r = math.hypot(x, y)
    if r == 0:
        return True
    a = (math.atan2(y, x) - math.pi / 2) % (2 * math.pi / points)
    half = math.pi / points
    # The edge between an outer point (angle 0) and an inner corner (angle half), in polar form.
    p0 = (0.95, 0.0)
    p1 = (0.95 * inner * math.cos(half), 0.95 * inner * math.sin(half))
    t = a if a <= half else 2 * half - a
    d = (math.cos(t), math.sin(t))
    # Ray from the centre along d meets the segment p0-p1 at distance s.
    ex, ey = p1[0] - p0[0], p1[1] - p0[1]
    den = d[0] * ey - d[1] * ex
    s = (p0[0] * ey - p0[1] * ex) / den
    return r <= s


def heart(x, y):
    """Inside a heart, point down, filling the unit circle."""
    x, y = x * 1.25, y * 1.25 - 0.15
    return (x * x + y * y - 1) ** 3 - x * x * y ** 3 <= 0


def png(path, size, inside):
    """A `size`² greyscale PNG, 255 inside the shape (x right, y up, both in [-1, 1])."""
    rows = bytearray()
    n = 4
    for j in range(size):
        rows.append(0)
        for i in range(size):
            hits = sum(
                inside(2 * (i + (a + 0.5) / n) / size - 1, 1 - 2 * (j + (b + 0.5) / n) / size)
                for a in range(n) for b in range(n))
            rows.append(round(255 * hits / (n * n)))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    head = struct.pack(">IIBBBBB", size, size, 8, 0, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", head) + chunk(b"IDAT", zlib.compress(bytes(rows)))
                + chunk(b"IEND", b""))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("shape", choices=["star", "heart"])
    p.add_argument("out")
    p.add_argument("--size", type=int, default=128)
    a = p.parse_args()
    png(a.out, a.size, star if a.shape == "star" else heart)


if __name__ == "__main__":
    main()
