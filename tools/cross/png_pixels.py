# SPDX-License-Identifier: MIT OR Apache-2.0
"""Prints the SHA-256 of a PNG's decoded pixels (width, height, colour type, bit depth, then the
unfiltered rows), so two renders compare bit for bit whatever their text chunks say. Standard
library only; 8- and 16-bit non-interlaced PNGs, as aperture writes.

    python3 tools/cross/png_pixels.py a.png [b.png ...]"""

import hashlib
import struct
import sys
import zlib

CHANNELS = {0: 1, 2: 3, 4: 2, 6: 4}


def chunks(data):
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    pos = 8
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        yield data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        pos += 12 + length


def paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    return a if pa <= pb and pa <= pc else (b if pb <= pc else c)


def unfilter(raw, width, height, bpp):
    stride = width * bpp
    prev = bytearray(stride)
    out = bytearray()
    for y in range(height):
        kind, row = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = row[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            row[i] = (row[i] + (0, a, b, (a + b) // 2, paeth(a, b, c))[kind]) & 0xFF
        out += row
        prev = row
    return bytes(out)


def pixels_sha256(path):
    with open(path, "rb") as f:
        data = f.read()
    ihdr, idat = None, b""
    for kind, body in chunks(data):
        if kind == b"IHDR":
            ihdr = body
        elif kind == b"IDAT":
            idat += body
    width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", ihdr)
    if interlace or colour not in CHANNELS or depth not in (8, 16):
        raise ValueError(f"{path}: unsupported PNG (colour {colour}, depth {depth})")
    bpp = CHANNELS[colour] * depth // 8
    rows = unfilter(zlib.decompress(idat), width, height, bpp)
    return hashlib.sha256(ihdr[:10] + rows).hexdigest(), width, height


def main():
    for path in sys.argv[1:]:
        digest, w, h = pixels_sha256(path)
        print(f"{digest}  {w}x{h}  {path}")


if __name__ == "__main__":
    main()
