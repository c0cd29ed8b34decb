#!/usr/bin/env python3
"""Street-grid scenes with many lights, for the light tree's benchmark (issue 46).

A 40 m ground, a 9 x 9 grid of boxes (one mesh, instanced), N coloured point lights between
them and optionally P small emissive panels (one quad mesh, instanced), seen from above at an
angle. Written as self-contained .gltf (buffer inline), deterministic for a seed.

    many_lights.py -o DIR [--lights 10,100,1000,10000] [--panels 0] [--seed 1]
    many_lights.py time --before BIN --after BIN DIR/*.gltf [--spp 16] [--rounds 3]

``time`` renders each file with both binaries alternately (``nice``, 2 threads), ``--rounds``
times, and prints the median time per sample from the EXR header's ``aperture:renderTime``
(the traced image only: no loading, no BVH build).

    many_lights.py efficiency --before BIN --after BIN DIR/*.gltf [--spp 16]

``efficiency`` renders each file with both binaries at seeds 1 and 2: the variance of a pixel
is half the mean squared difference of the two images; it prints image means (equal within
noise for unbiased samplers), variances, times per sample and variance × time after/before
(below 1: the after binary is more efficient). Needs NumPy (reads the EXRs with
``tools/blender/aperture_gltf_dof/exr.py``).
"""

from __future__ import annotations

import argparse
import base64
import json
import os
import random
import statistics
import struct
import subprocess
import sys

GROUND = 20.0  # half size, metres
GRID = 9


def box_mesh():
    """A unit cube centred on the origin, flat normals: positions, normals, indices."""
    pos, nrm, idx = [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = [0.0, 0.0, 0.0]
            n[axis] = sign
            u, v = [(axis + 1) % 3, (axis + 2) % 3]
            base = len(pos)
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0.0, 0.0, 0.0]
                p[axis] = 0.5 * sign
                p[u] = 0.5 * a
                p[v] = 0.5 * b
                pos.append(p)
                nrm.append(n)
            quad = [base, base + 1, base + 2, base, base + 2, base + 3]
            if sign < 0:
                quad = [base, base + 2, base + 1, base, base + 3, base + 2]
            idx += quad
    return pos, nrm, idx


def quad_mesh(h):
    """A square of half-size h in the XY plane facing +Z."""
    pos = [[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]]
    return pos, [[0.0, 0.0, 1.0]] * 4, [0, 1, 2, 0, 2, 3]


class Buffer:
    """One binary buffer with its views and accessors."""

    def __init__(self):
        self.data = bytearray()
        self.views, self.accessors = [], []

    def add(self, values, fmt, count, kind, ctype, target, minmax=None):
        while len(self.data) % 4:
            self.data.append(0)
        off = len(self.data)
        self.data += struct.pack("<" + fmt * len(values), *values)
        self.views.append({"buffer": 0, "byteOffset": off, "byteLength": len(self.data) - off,
                           "target": target})
        acc = {"bufferView": len(self.views) - 1, "componentType": ctype, "count": count,
               "type": kind}
        if minmax:
            acc["min"], acc["max"] = minmax
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def mesh(self, pos, nrm, idx, material):
        flat = [c for p in pos for c in p]
        lo = [min(p[i] for p in pos) for i in range(3)]
        hi = [max(p[i] for p in pos) for i in range(3)]
        a_pos = self.add(flat, "f", len(pos), "VEC3", 5126, 34962, (lo, hi))
        a_nrm = self.add([c for n in nrm for c in n], "f", len(nrm), "VEC3", 5126, 34962)
        a_idx = self.add(idx, "I", len(idx), "SCALAR", 5125, 34963)
        return {"primitives": [{"attributes": {"POSITION": a_pos, "NORMAL": a_nrm},
                                "indices": a_idx, "material": material}]}


def scene(n_lights, n_panels, seed):
    """The glTF document of the street grid with these many lights and panels."""
    rng = random.Random(seed)
    buf = Buffer()
    materials = [
        {"name": "ground", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1],
                                                    "metallicFactor": 0, "roughnessFactor": 0.8}},
        {"name": "box", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.65, 0.6, 1],
                                                 "metallicFactor": 0, "roughnessFactor": 0.5}},
        {"name": "panel", "emissiveFactor": [1.0, 0.8, 0.5],
         "extensions": {"KHR_materials_emissive_strength": {
             "emissiveStrength": 400.0 / max(n_panels, 1) ** 0.5}},
         "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0}},
    ]
    g = GROUND
    ground = ([[-g, 0, -g], [-g, 0, g], [g, 0, g], [g, 0, -g]], [[0, 1, 0]] * 4,
              [0, 1, 2, 0, 2, 3])
    meshes = [buf.mesh(*ground, 0), buf.mesh(*box_mesh(), 1), buf.mesh(*quad_mesh(0.15), 2)]
    nodes = [{"mesh": 0}]
    spacing = 2 * g / GRID
    boxes = []
    for i in range(GRID):
        for j in range(GRID):
            x, z = -g + spacing * (i + 0.5), -g + spacing * (j + 0.5)
            h = rng.uniform(1.0, 6.0)
            w = spacing * 0.45
            boxes.append((x, z, w, h))
            nodes.append({"mesh": 1, "translation": [x, h / 2, z], "scale": [w, h, w]})
    lights = []
    # Total intensity stays the same whatever N, so that the images stay comparable.
    intensity = 40000.0 / max(n_lights, 1)
    for k in range(n_lights):
        colour = [rng.uniform(0.2, 1.0) for _ in range(3)]
        lights.append({"type": "point", "color": colour, "intensity": intensity})
        # In the streets between the boxes (the grid lines), at lamp heights.
        if rng.random() < 0.5:
            x = -g + spacing * rng.randint(0, GRID) + rng.uniform(-0.3, 0.3)
            z = rng.uniform(-g, g)
        else:
            x = rng.uniform(-g, g)
            z = -g + spacing * rng.randint(0, GRID) + rng.uniform(-0.3, 0.3)
        nodes.append({"translation": [x, rng.uniform(0.3, 4.0), z],
                      "extensions": {"KHR_lights_punctual": {"light": k}}})
    on_box = [0] * len(boxes)
    for _ in range(n_panels):
        # On a box's street-facing side (+Z), at some height; each panel of a box 2 mm in
        # front of the one before. Overlapping panels closer than a shadow ray's offset (0.1 mm
        # was) are all seen by light sampling but one at a time by rays: the two strategies
        # then disagree, and an image's brightness depends on which one MIS favours.
        b = rng.randrange(len(boxes))
        x, z, w, h = boxes[b]
        gap = 0.01 + 2e-3 * on_box[b]
        on_box[b] += 1
        nodes.append({"mesh": 2, "translation": [x + rng.uniform(-w, w) * 0.4,
                                                 rng.uniform(0.3, h - 0.2), z + w / 2 + gap]})
    nodes.append({"camera": 0, "translation": [0, 14, 30],
                  "rotation": [-0.2588190, 0, 0, 0.9659258]})  # 30 degrees down
    doc = {
        "asset": {"version": "2.0", "generator": "aperture tools/bench/many_lights.py"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{"type": "perspective",
                     "perspective": {"yfov": 0.9, "znear": 0.1, "aspectRatio": 4 / 3}}],
        "buffers": [{"byteLength": len(buf.data), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(bytes(buf.data)).decode()}],
        "bufferViews": buf.views,
        "accessors": buf.accessors,
    }
    if not lights:
        del doc["extensions"]
    return doc


def write(args):
    os.makedirs(args.out, exist_ok=True)
    for n in [int(x) for x in args.lights.split(",")]:
        name = f"street_{n}" + (f"_panels{args.panels}" if args.panels else "") + ".gltf"
        with open(os.path.join(args.out, name), "w") as f:
            json.dump(scene(n, args.panels, args.seed), f)
        print(os.path.join(args.out, name))


def header_float(path, name):
    """A float attribute of an EXR header (scalar part of OpenEXR's header, no library)."""
    with open(path, "rb") as f:
        data = f.read(1 << 16)
    at = 8  # magic and version
    while data[at] != 0:
        end = data.index(b"\0", at)
        key = data[at:end].decode()
        tend = data.index(b"\0", end + 1)
        size = struct.unpack_from("<i", data, tend + 1)[0]
        value = tend + 5
        if key == name:
            return struct.unpack_from("<f", data, value)[0]
        at = value + size
    raise ValueError(f"{path}: no {name}")


def render_time(binary, path, spp, width, height, out="/tmp/many_lights_out.exr", seed=0):
    cmd = ["nice", binary, "render", path, "-o", out, "--width", str(width), "--height",
           str(height), "--spp", str(spp), "--threads", "2", "--passes", "none", "--seed",
           str(seed), "--quiet"]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return header_float(out, "aperture:renderTime")


def timing(args):
    bins = {"before": args.before, "after": args.after}
    for path in args.files:
        per = {k: [] for k in bins}
        for _ in range(args.rounds):
            for k, b in bins.items():  # alternated, so drift of the machine hits both
                if k == "before" and args.skip_before and args.skip_before in path:
                    continue
                per[k].append(render_time(b, path, args.spp, args.width, args.height) / args.spp)
        med = {k: statistics.median(v) * 1e3 if v else float("nan") for k, v in per.items()}
        print(f"{os.path.basename(path)}\tbefore {med['before']:.1f} ms/spp"
              f"\tafter {med['after']:.1f} ms/spp\t({args.rounds} rounds)", flush=True)


def beauty(path):
    """The beauty's R, G, B of an aperture EXR, as one (h, w, 3) array."""
    import importlib.util
    import numpy as np
    here = os.path.dirname(os.path.abspath(__file__))
    spec = importlib.util.spec_from_file_location(
        "aperture_exr", os.path.join(here, "..", "blender", "aperture_gltf_dof", "exr.py"))
    exr = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(exr)
    channels, _ = exr.read(path)
    pick = [next(k for k in channels if k == c or k.endswith("Combined." + c)) for c in "RGB"]
    return np.stack([channels[k] for k in pick], axis=-1).astype(np.float64)


def efficiency(args):
    import numpy as np
    bins = {"before": args.before, "after": args.after}
    for path in args.files:
        res = {}
        for k, b in bins.items():
            imgs, secs = [], []
            for seed in (1, 2):
                out = f"/tmp/many_lights_{k}_{seed}.exr"
                secs.append(render_time(b, path, args.spp, args.width, args.height, out, seed))
                imgs.append(beauty(out))
            var = float(np.mean((imgs[0] - imgs[1]) ** 2) / 2)
            mean = float(np.mean((imgs[0] + imgs[1]) / 2))
            res[k] = (mean, var, statistics.mean(secs) / args.spp)
        (mb, vb, tb), (ma, va, ta) = res["before"], res["after"]
        print(f"{os.path.basename(path)}\tmean {mb:.4f} -> {ma:.4f}\tvariance {vb:.3g} -> "
              f"{va:.3g}\tms/spp {tb * 1e3:.1f} -> {ta * 1e3:.1f}\tvariance x time after/before "
              f"{va * ta / (vb * tb):.3f}", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd")
    t = sub.add_parser("time")
    t.add_argument("--before", required=True)
    t.add_argument("--after", required=True)
    t.add_argument("--spp", type=int, default=16)
    t.add_argument("--skip-before", help="files whose name holds this: after only")
    t.add_argument("--rounds", type=int, default=3)
    t.add_argument("--width", type=int, default=320)
    t.add_argument("--height", type=int, default=240)
    t.add_argument("files", nargs="+")
    e = sub.add_parser("efficiency")
    e.add_argument("--before", required=True)
    e.add_argument("--after", required=True)
    e.add_argument("--spp", type=int, default=16)
    e.add_argument("--width", type=int, default=160)
    e.add_argument("--height", type=int, default=120)
    e.add_argument("files", nargs="+")
    ap.add_argument("-o", "--out")
    ap.add_argument("--lights", default="10,100,1000,10000")
    ap.add_argument("--panels", type=int, default=0)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    if args.cmd == "time":
        timing(args)
    elif args.cmd == "efficiency":
        efficiency(args)
    elif args.out:
        write(args)
    else:
        ap.error("-o DIR or the time command")


if __name__ == "__main__":
    sys.exit(main())
