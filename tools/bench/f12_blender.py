"""F12 in Blender (bpy as a module) with aperture, through the shared session and through the
command line, against Cycles, on a generated scene of displaced tiles (issue 63's benchmark).

    python f12_blender.py --aperture BIN [--triangles 1000000] [--repeats 3]

Run with the bpy venv that tools/python/test.sh fills (the add-on's wheel installed). Prints
per engine and path the median seconds of the first F12 (export or sync + build) and of a
repeated F12 with nothing changed (320 x 180, 4 spp, 2 threads, no denoising).
"""

import argparse
import math
import os
import statistics
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blender"))
from addon_zip import ADDON, addon_zip  # noqa: E402


def build(bpy, triangles):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 320, 180, 100
    tiles = 16
    cuts = max(1, int(math.sqrt(triangles / tiles / 2)) - 1)
    for i in range(tiles):
        bpy.ops.mesh.primitive_grid_add(x_subdivisions=cuts, y_subdivisions=cuts, size=2.0,
                                        location=((i % 4) * 2.1 - 3.15, (i // 4) * 2.1 - 3.15, 0))
        obj = bpy.context.active_object
        for v in obj.data.vertices:
            v.co.z = 0.15 * math.sin(5 * v.co.x + i) * math.cos(4 * v.co.y)
    cam = bpy.data.objects.new("Cam", bpy.data.cameras.new("Cam"))
    cam.location, cam.rotation_euler = (0, -9, 6), (math.radians(55), 0, 0)
    sc.collection.objects.link(cam)
    sc.camera = cam
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sc.collection.objects.link(sun)
    tris = sum(len(o.data.polygons) * 2 for o in sc.objects if o.type == "MESH")
    return tris


def timed(bpy):
    t = time.perf_counter()
    bpy.ops.render.render()
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--aperture", required=True)
    ap.add_argument("--triangles", type=int, default=1_000_000)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="aperture-f12-")
    os.environ["BLENDER_USER_SCRIPTS"] = os.path.join(work, "scripts")
    import bpy

    rows = {}
    for r in range(a.repeats):
        tris = build(bpy, a.triangles)
        bpy.ops.preferences.addon_install(filepath=addon_zip(work), overwrite=True)
        bpy.ops.preferences.addon_enable(module=ADDON)
        vs = sys.modules[ADDON + ".viewport_sync"]
        sc = bpy.context.scene
        runs = (("APERTURE", True), ("APERTURE", False), ("CYCLES", None), ("CYCLES", "sync"))
        for engine, session in runs:
            sc.render.engine = engine
            sc.render.resolution_percentage = 100
            if engine == "APERTURE":
                s = sc.aperture
                s.samples, s.denoise, s.binary, s.f12_session = 4, False, a.aperture, session
                label = "aperture, session" if session else "aperture, command line"
            else:
                sc.cycles.samples, sc.cycles.use_denoising = 4, False
                sc.render.threads_mode, sc.render.threads = "FIXED", 2
                label = "Cycles"
                if session == "sync":  # 1 sample at 32 x 18: about Cycles' sync + BVH alone
                    sc.cycles.samples, sc.render.resolution_percentage = 1, 10
                    label = "Cycles, 1 spp at 32 x 18 (sync + BVH)"
            first, again = timed(bpy), timed(bpy)
            rows.setdefault(label, []).append((first, again))
            vs.free_shared()
        print(f"round {r + 1}: {tris} triangles: " + ", ".join(
            f"{k} {v[-1][0]:.2f} / {v[-1][1]:.2f} s" for k, v in rows.items()), flush=True)
    for k, v in rows.items():
        f = statistics.median(x[0] for x in v)
        g = statistics.median(x[1] for x in v)
        print(f"{k}: first F12 {f:.2f} s, repeated F12 {g:.2f} s ({g / f:.2f}x)")


if __name__ == "__main__":
    main()
