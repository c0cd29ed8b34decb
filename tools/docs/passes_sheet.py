# SPDX-License-Identifier: MIT OR Apache-2.0
"""Draws docs/passes.png, the README's picture of the EXR passes, from an aperture EXR.

    target/release/aperture render assets/demo.glb -o /tmp/passes.exr --width 480 --height 270 \\
        --spp 64 --passes all
    python tools/docs/passes_sheet.py /tmp/passes.exr docs/passes.png

Needs NumPy and the OpenEXR package (the Blender test's venv has both). Six panels, left to
right, top to bottom: the beauty (sRGB), Depth (log scale, near bright), Normal (0.5 + 0.5 n),
Denoising Albedo, CryptoObject (each object's coverage in a colour of its ID) and Glossy
Direct × Glossy Color.
"""

import struct
import sys
import zlib

import numpy as np
import OpenEXR


def srgb(x):
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def write_png(path, rgb):
    h, w, _ = rgb.shape
    data = (np.clip(rgb, 0, 1) * 255 + 0.5).astype(np.uint8)
    raw = b"".join(b"\0" + data[y].tobytes() for y in range(h))

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def main(src, dst):
    ch = {k: np.array(v.pixels, dtype=np.float64)
          for k, v in OpenEXR.File(src, separate_channels=True).channels().items()}
    layer = lambda name, cs: np.stack([ch[f"{name}.{c}" if name else c] for c in cs], -1)
    beauty = srgb(layer("", "RGB"))
    z = ch["Depth.Z"]
    near = z[z < 1e9].min()
    depth = np.where(z < 1e9, 1.0 - np.log(z / near) / np.log(z[z < 1e9].max() / near), 0.0)
    depth = np.repeat(depth[..., None], 3, -1)
    normal = 0.5 + 0.5 * layer("Normal", "XYZ")
    albedo = srgb(layer("Denoising Albedo", "RGB"))
    crypto = np.zeros_like(beauty)
    for i in range(3):
        l = layer(f"CryptoObject{i:02d}", "RGBA").astype(np.float32)
        for rank in (0, 2):
            ids = l[..., rank].view(np.uint32).astype(np.uint64)
            colour = np.stack([((ids * k) >> 16) % 256 / 255.0 for k in (2654435761, 40503, 69069)], -1)
            crypto += colour * l[..., rank + 1, None]
    glossy = srgb(layer("Glossy Direct", "RGB") * layer("Glossy Color", "RGB"))
    gap = np.ones((beauty.shape[0], 4, 3))
    rows = [np.concatenate([beauty, gap, depth, gap, normal], 1),
            np.concatenate([albedo, gap, crypto, gap, glossy], 1)]
    sheet = np.concatenate([rows[0], np.ones((4, rows[0].shape[1], 3)), rows[1]], 0)
    write_png(dst, sheet)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
