#!/usr/bin/env python3
"""Writes a GLB of N nodes, each drawing the same one-triangle mesh at its own place:

    tools/hostile/make_nodes.py N OUT.glb [--chain]

Flat by default (N roots in the scene); --chain nests each node in the previous one (a
hierarchy N deep). Used to measure the loader's per-node cost (BENCHMARKS.md, "Memory budgets").
"""
import json
import struct
import sys


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    n = int(sys.argv[1])
    out = sys.argv[2]
    chain = "--chain" in sys.argv[3:]
    bin_ = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    side = max(1, int(round(n ** (1 / 3))))
    parts = []
    for i in range(n):
        if chain:
            kids = f',"children":[{i + 1}]' if i + 1 < n else ""
            parts.append('{"mesh":0,"translation":[0.001,0,0]%s}' % kids)
        else:
            x, y, z = i % side, (i // side) % side, i // (side * side)
            parts.append('{"mesh":0,"translation":[%d,%d,%d]}' % (2 * x, 2 * y, 2 * z))
    scene_nodes = "[0]" if chain else "[" + ",".join(str(i) for i in range(n)) + "]"
    head = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "bufferViews": [{"buffer": 0, "byteLength": len(bin_)}],
        "buffers": [{"byteLength": len(bin_)}],
    }
    text = json.dumps(head)[:-1] + ',"scenes":[{"nodes":%s}],"nodes":[%s]}' % (
        scene_nodes, ",".join(parts))
    j = text.encode()
    j += b" " * (-len(j) % 4)
    b = bin_ + b"\0" * (-len(bin_) % 4)
    total = 12 + 8 + len(j) + 8 + len(b)
    with open(out, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(j), b"JSON") + j)
        f.write(struct.pack("<I4s", len(b), b"BIN\0") + b)


if __name__ == "__main__":
    main()
