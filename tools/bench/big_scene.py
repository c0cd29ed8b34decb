#!/usr/bin/env python3
"""Writes a large glTF scene for load and session benchmarks: MESHES meshes of a displaced grid
in a square, every triangle with vertices of its own (positions and normals, no indices
shared: the worst case for memory), under a sun, seen by a thin-lens camera (f/2.8, focused
on the middle) whose depth-of-field keys sit in its extras as Blender writes them.

    python3 tools/bench/big_scene.py TRIANGLES OUT.glb [MESHES] [--interleaved]

--interleaved: the same square and triangles, but mesh m holds every MESHES-th row of one
big grid (rows m, m + MESHES, ...), so every mesh's box spans the whole square: the worst case
for a tree over the meshes' boxes (issue 59's joined builds).

Standard library only; deterministic bytes for a given argument list."""

import json
import math
import struct
import sys
from array import array


def grid(cells, x0, z0, size, seed, rows=None, width=None):
    """Positions and normals of a displaced grid of cells x cells quads, 6 vertices a quad
    (only rows `rows` of a grid `width` cells wide, when given)."""
    def height(i, j):
        x, z = i / cells, j / cells
        return 0.08 * size * (math.sin(7.0 * x + seed) * math.cos(5.0 * z + 0.7 * seed)
                              + 0.3 * math.sin(23.0 * (x + z) + seed))

    pos, nrm = array("f"), array("f")
    step = size / cells
    for j in (range(cells) if rows is None else rows):
        for i in range(cells if width is None else width):
            corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
            p = [(x0 + a * step, height(a, b), z0 + b * step) for a, b in corners]
            for tri in ((0, 2, 1), (0, 3, 2)):
                a, b, c = (p[k] for k in tri)
                u = [b[k] - a[k] for k in range(3)]
                v = [c[k] - a[k] for k in range(3)]
                n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
                length = math.sqrt(sum(x * x for x in n)) or 1.0
                n = [x / length for x in n]
                for q in (a, b, c):
                    pos.extend(q)
                    nrm.extend(n)
    return pos, nrm


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    interleaved = "--interleaved" in sys.argv
    args = [a for a in sys.argv[1:] if a != "--interleaved"]
    triangles, out = int(args[0]), args[1]
    meshes = int(args[2]) if len(args) > 2 else 64
    side = math.ceil(math.sqrt(meshes))
    cells = max(1, round(math.sqrt(triangles / meshes / 2)))
    size = 2.0
    bin_data = bytearray()
    views, accessors, gl_meshes, nodes = [], [], [], []
    for m in range(meshes):
        gx, gz = m % side, m // side
        x0, z0 = (gx - side / 2) * size, -(gz + 1) * size
        if interleaved:
            # One grid of side x side tiles' cells; this mesh's rows of it.
            n = side * cells
            pos, nrm = grid(n, -side / 2 * size, -side * size, side * size, 0.0, range(m, n, meshes), n)
        else:
            pos, nrm = grid(cells, x0, z0, size, m * 0.37)
        count = len(pos) // 3
        lo = [min(pos[k::3]) for k in range(3)]
        hi = [max(pos[k::3]) for k in range(3)]
        for data, extra in ((pos, {"min": lo, "max": hi}), (nrm, {})):
            views.append({"buffer": 0, "byteOffset": len(bin_data), "byteLength": len(data) * 4})
            bin_data += data.tobytes()
            accessors.append({"bufferView": len(views) - 1, "componentType": 5126,
                              "count": count, "type": "VEC3", **extra})
        gl_meshes.append({"primitives": [{"attributes": {"POSITION": len(accessors) - 2,
                                                         "NORMAL": len(accessors) - 1},
                                          "material": m % 3}]})
        nodes.append({"name": f"tile_{m}", "mesh": m})
    depth = side * size
    nodes.append({"name": "Sun", "rotation": [-0.3535534, 0.3535534, 0.1464466, 0.8535534],
                  "extensions": {"KHR_lights_punctual": {"light": 0}}})
    nodes.append({"name": "Camera", "camera": 0, "translation": [0.0, 0.35 * depth, 0.3 * depth],
                  "rotation": [-0.2588190, 0.0, 0.0, 0.9659258]})
    doc = {
        "asset": {"version": "2.0", "generator": "aperture tools/bench/big_scene.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "intensity": 2000.0, "color": [1.0, 0.95, 0.9]}]}},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": gl_meshes,
        "materials": [
            {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.7, 0.6, 1.0], "roughnessFactor": 0.6,
                                      "metallicFactor": 0.0}},
            {"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.8, 0.4, 1.0], "roughnessFactor": 0.3,
                                      "metallicFactor": 1.0}},
            {"pbrMetallicRoughness": {"baseColorFactor": [0.3, 0.5, 0.7, 1.0], "roughnessFactor": 0.8,
                                      "metallicFactor": 0.0}},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.05},
                     "extras": {"use_dof": True, "aperture_fstop": 2.8, "lens": 50.0,
                                "focus_distance": 0.7 * depth}}],
        "buffers": [{"byteLength": len(bin_data)}],
        "bufferViews": views,
        "accessors": accessors,
    }
    text = json.dumps(doc, separators=(",", ":"), sort_keys=True).encode()
    text += b" " * (-len(text) % 4)
    bin_data += b"\0" * (-len(bin_data) % 4)
    total = 12 + 8 + len(text) + 8 + len(bin_data)
    with open(out, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(text), b"JSON") + text)
        f.write(struct.pack("<I4s", len(bin_data), b"BIN\0") + bin_data)
    print(f"{out}: {meshes} meshes, {meshes * cells * cells * 2} triangles, {total / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
