"""The viewport's session timed through the code the viewport runs (issue 63): bpy as a module,
the add-on's ``viewport_sync`` on a real depsgraph, a 1920 x 1080 viewport.

    python viewport_blender.py [--scene demo|big] [--triangles 1000000] [--moves 7]
        [--denoise off|schedule|every]

``demo`` imports assets/demo.glb into Blender; ``big`` is f12_blender.py's generated tiles.
Printed: start (export + load + first image), then the medians over ``--moves`` of: a camera
move to its first image and to 16 samples a pixel, and an object's move to its first image
(each after Blender's own depsgraph update, which is not counted). The first image comes at the
pixel size the last update's full pass asks for (viewport_sync.pixel_size_for).

``--denoise schedule`` turns *Viewport Denoise* on (Start Sample 1, the panel's default): the
worker denoises when ``viewport_sync.denoise_now`` says so. ``--denoise every`` puts the rule
it replaced in its place (every film from the Start Sample denoised), to time the difference;
each prints how many films were denoised per move.
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
sys.path.insert(0, HERE)
from addon_zip import ADDON, addon_zip  # noqa: E402

W, H, SPP = 1920, 1080, 16


def first_image(worker):
    """Seconds until the worker has an image, then the worker (polled every 0.5 ms)."""
    t = time.perf_counter()
    while worker.latest()[0] is None and worker.error is None:
        time.sleep(0.0005)
    return time.perf_counter() - t


class timed_parts:
    """The session's export and its meshes read as arrays, timed (``--no-arrays``: the
    exporter writes every mesh)."""

    def __init__(self, vs, arrays, off):
        self.seconds = {"export": 0.0, "arrays": 0.0}
        given, stubbed = arrays.given, arrays.stubbed
        if off:
            arrays.stubbed = lambda on=True: stubbed(False)

        def timed_given(*args):
            t = time.perf_counter()
            try:
                return given(*args)
            finally:
                self.seconds["arrays"] += time.perf_counter() - t

        arrays.given = timed_given
        self._export = vs.export_scene

    def export(self, path):
        t = time.perf_counter()
        self._export(path)
        self.seconds["export"] += time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default="demo", choices=["demo", "big"])
    ap.add_argument("--triangles", type=int, default=1_000_000)
    ap.add_argument("--moves", type=int, default=7)
    ap.add_argument("--denoise", default="off", choices=["off", "schedule", "every"])
    ap.add_argument("--no-arrays", action="store_true",
                    help="export every mesh through the glTF exporter (no mesh_arrays stand-ins)")
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="aperture-viewport-bench-")
    os.environ["BLENDER_USER_SCRIPTS"] = os.path.join(work, "s")
    import bpy

    if a.scene == "big":
        import f12_blender

        f12_blender.build(bpy, a.triangles)
    else:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        bpy.ops.import_scene.gltf(filepath=os.path.join(HERE, "..", "..", "assets", "demo.glb"))
        sc = bpy.context.scene
        sc.camera = next(o for o in sc.objects if o.type == "CAMERA")
    bpy.ops.preferences.addon_install(filepath=addon_zip(work), overwrite=True)
    bpy.ops.preferences.addon_enable(module=ADDON)
    vs = sys.modules[ADDON + ".viewport_sync"]
    sc = bpy.context.scene
    sc.render.engine = "APERTURE"
    sc.aperture.samples, sc.aperture.denoise = SPP, False
    sc.aperture.viewport_denoise = a.denoise != "off"
    denoise, denoise_start = vs.viewport_denoise(sc)
    if a.denoise == "every":
        # The rule before the schedule: every film from the Start Sample on.
        vs.denoise_now = lambda samples, start, *rest: start is not None and samples >= start
    tris = sum(len(o.data.polygons) for o in sc.objects if o.type == "MESH")
    dg = bpy.context.evaluated_depsgraph_get()
    parts = timed_parts(vs, sys.modules[ADDON + ".mesh_arrays"], a.no_arrays)
    t = time.perf_counter()
    s = vs.Session(dg, export=parts.export)
    loaded = time.perf_counter() - t
    print(f"start parts: export {parts.seconds['export']:.3f} s, meshes read as arrays "
          f"{parts.seconds['arrays']:.3f} s ({len(s.stood_in)} meshes), load (aperture.load + "
          f"info) {loaded - sum(parts.seconds.values()):.3f} s", flush=True)
    w = s.start(width=W, height=H, denoise_start=denoise_start, **denoise)
    start = loaded + first_image(w)
    w.wait()
    print(f"{a.scene}: {tris} polygons; start: export + load {loaded:.3f} s, to the first image "
          f"{start:.3f} s", flush=True)
    bpy.app.handlers.depsgraph_update_post.append(lambda scene, depsgraph: s.sync(depsgraph))
    cam = sc.camera
    mover = next(o for o in sc.objects if o.type == "MESH")
    rows = {"camera": [], "camera16": [], "transform": [], "pixel": [], "denoised": []}
    for k in range(a.moves):
        cam.location.x += 0.05 if k % 2 == 0 else -0.05
        bpy.context.view_layer.update()  # the handler syncs (not counted: Blender's own work)
        t = time.perf_counter()
        w = s.start(width=W, height=H, denoise_start=denoise_start, **denoise)
        rows["camera"].append(first_image(w) + 0.0)
        rows["pixel"].append(w.pixel_size)
        w.wait()
        rows["camera16"].append(time.perf_counter() - t)
        rows["denoised"].append(w.denoised)
        mover.location.z += 0.01 if k % 2 == 0 else -0.01
        bpy.context.view_layer.update()
        t = time.perf_counter()
        w = s.start(width=W, height=H, denoise_start=denoise_start, **denoise)
        rows["transform"].append(first_image(w))
        w.wait()
    med = {k: statistics.median(v) for k, v in rows.items()}
    print(f"camera move -> first image {med['camera'] * 1e3:.1f} ms (pixel sizes {rows['pixel']}), "
          f"-> {SPP} spp {med['camera16']:.2f} s; transform -> first image "
          f"{med['transform'] * 1e3:.1f} ms (medians of {a.moves}); denoise {a.denoise}, "
          f"films denoised per move {rows['denoised']}", flush=True)
    s.free()


if __name__ == "__main__":
    main()
