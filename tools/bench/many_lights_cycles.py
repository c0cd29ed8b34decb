#!/usr/bin/env python3
# SPDX-License-Identifier: MIT OR Apache-2.0
"""aperture against Blender Cycles (light tree on, its default) on the street scenes of
``many_lights.py``: image means, variance and time per sample, and the efficiency ratio.

Run with the bpy venv's Python (``tools/blender/run_test.sh`` installs it):

    ~/.cache/aperture/bpy-5.0.1/bin/python tools/bench/many_lights_cycles.py \
        --aperture target/release/aperture [--spp 16] [--width 160] [--height 120] \
        [--threads 2] DIR/street_*.gltf

Both renderers see the same file: Cycles imports it with Blender's glTF importer (point lights
of radius 0; materials replaced by Lambert of their base colour plus their emission, as
``tools/reference/bench_renderers.py``'s ``cycles_material``), aperture renders it with ``--override-material
diffuse``. Both: 1-pixel box filter, 6 bounces, no clamp, no adaptive sampling, no denoiser.
For each seed (1 and 2) Cycles and aperture render in turn, so the machine's drift hits both.
Times: Cycles' ``bpy.ops.render.render`` with persistent data after a warm-up render (no scene
sync or BVH build), aperture's ``aperture:renderTime`` (no load or BVH build). The variance
of a pixel is half the mean squared difference of the two seeds' images; efficiency is
variance × time per sample, aperture over Cycles (below 1: aperture is more efficient).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blender"))
sys.path.insert(0, os.path.join(HERE, "..", "reference"))
sys.path.insert(0, HERE)

BOUNCES = 6


def cycles_scene(path, args):
    """The file imported into an empty Blender scene, set to render as aperture does."""
    import bench_renderers
    import bpy
    import cycles_settings

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = args.width, args.height
    sc.render.resolution_percentage = 100
    cycles_settings.unbiased(sc, args.spp, 1)
    cy = sc.cycles
    cy.max_bounces = cy.diffuse_bounces = cy.glossy_bounces = cy.transmission_bounces = BOUNCES
    cy.use_light_tree = True
    sc.render.threads_mode = "FIXED"
    sc.render.threads = args.threads
    sc.render.use_persistent_data = True
    sc.view_settings.view_transform = "Standard"
    for mat in bpy.data.materials:
        if mat.use_nodes:
            bench_renderers.cycles_material(bpy, mat)
    for light in bpy.data.lights:
        light.shadow_soft_size = 0.0
    sc.camera = next(o for o in sc.objects if o.type == "CAMERA")
    world = bpy.data.worlds.new("World")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    sc.world = world
    return sc


def cycles_render(sc, tmp, spp, seed):
    """(image, seconds) of one Cycles render."""
    import bpy
    from exr_beauty import read_beauty

    sc.cycles.samples, sc.cycles.seed = spp, seed
    # A new path each time: a persistent session would otherwise keep the old samples and seed.
    sc.render.filepath = os.path.join(tmp, f"cycles_{spp}_{seed}.exr")
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    secs = time.perf_counter() - t0
    return read_beauty(sc.render.filepath), secs


def aperture_render(path, tmp, spp, seed, args):
    """(image, seconds) of one aperture render."""
    from exr_beauty import read_beauty
    from many_lights import header_float

    out = os.path.join(tmp, f"aperture_{spp}_{seed}.exr")
    subprocess.run([args.aperture, "render", path, "-o", out, "--width", str(args.width),
                    "--height", str(args.height), "--spp", str(spp), "--seed", str(seed),
                    "--threads", str(args.threads), "--max-bounces", str(BOUNCES),
                    "--filter", "box", "--override-material", "diffuse", "--passes", "none",
                    # Cycles draws the files' single-sided faces from both sides (Blender's
                    # meaning); aperture's automatic choice gives these non-Blender files glTF's.
                    "--single-sided", "blender", "--quiet"], check=True, stdout=subprocess.DEVNULL)
    return read_beauty(out), header_float(out, "aperture:renderTime")


def compare(path, args, tmp):
    sc = cycles_scene(path, args)
    cycles_render(sc, tmp, 1, 0)  # warm-up: scene sync and BVH
    imgs = {"cycles": [], "aperture": []}
    secs = {"cycles": [], "aperture": []}
    for seed in (1, 2):
        for name in ("cycles", "aperture"):
            if name == "cycles":
                img, s = cycles_render(sc, tmp, args.spp, seed)
            else:
                img, s = aperture_render(path, tmp, args.spp, seed, args)
            imgs[name].append(img)
            secs[name].append(s)
    res = {}
    for name, (a, b) in imgs.items():
        var = float(np.mean((a - b) ** 2) / 2)
        # Standard error of the two seeds' mean image mean: one image's is std(a - b) / √2 / √n.
        err = float(np.std((a - b).mean(axis=-1)) / 2 / np.sqrt(a[..., 0].size))
        res[name] = (float(np.mean((a + b) / 2)), err, var, sum(secs[name]) / 2 / args.spp)
    (mc, ec, vc, tc), (ma, ea, va, ta) = res["cycles"], res["aperture"]
    print(f"{os.path.basename(path)}\tmean cycles {mc:.4f}±{ec:.4f} aperture {ma:.4f}±{ea:.4f}"
          f"\tvariance {vc:.3g} / {va:.3g}\tms/spp {tc * 1e3:.1f} / {ta * 1e3:.1f}"
          f"\tefficiency aperture/cycles {va * ta / (vc * tc):.3f}", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--aperture", required=True, help="the aperture binary")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("files", nargs="+")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for path in args.files:
            compare(os.path.abspath(path), args, tmp)


if __name__ == "__main__":
    sys.exit(main())
