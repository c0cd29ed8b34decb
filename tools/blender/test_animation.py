# SPDX-License-Identifier: MIT OR Apache-2.0
"""Acceptance test for SPEC §7 with Blender (issue 15): bpy 5.0.1 on Python 3.11, run by run_test.sh.

    python test_animation.py --aperture target/release/aperture [--out DIR] [--require-all]

(a) `--frame N` is Blender's frame N: an animated scene (keyed location/rotation/scale, a child of a
    rotating empty) exported with the exporter's default settings; at frames 1, 12 and 37 the
    world-space bounds of every object in Blender (evaluated mesh x matrix_world, Z-up turned to
    glTF's Y-up) equal `aperture info --frame N --json`'s node_bounds within 1e-5.
(b) A focus pull: one camera focuses on an empty that moves, another has keyed
    dof.focus_distance (exported by the add-on as KHR_animation_pointer channels). A small emitter
    on the optical axis is rendered at several frames; the diameter of its blur disc, from the
    blob's second moment, follows SPEC §2's c = R·|1/f − 1/z|·H/tan(yfov/2) at each frame's focus
    distance (Blender's own value at that frame) within 5 %.

The last line is "N passed, N failed, N skipped"; the exit status is non-zero when anything failed.
"""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

from addon_zip import addon_zip  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ADDON = "aperture_gltf_dof"
RESULTS = []
FRAMES = (1, 12, 37)
W, H, SPP = 240, 135, 128
LENS, FSTOP = 50.0, 0.25  # R = 50 mm / (2 · 0.25) = 0.1 m
EMITTER_DEPTH, EMITTER_RADIUS = 4.0, 0.01


def record(name, ok, detail):
    status = {True: "PASS", False: "FAIL", None: "SKIP"}[ok]
    RESULTS.append(status)
    print(f"{status} {name}: {detail}", flush=True)


def yup(v):
    """Blender Z-up to glTF Y-up (the exporter's default +Y Up)."""
    return (v[0], v[2], -v[1])


def info(binary, path, frame):
    out = subprocess.run([binary, "info", "--json", "--frame", str(frame), path],
                         capture_output=True, text=True, timeout=600)
    if out.returncode != 0:
        raise RuntimeError(out.stderr)
    return json.loads(out.stdout)


def keyed_scene():
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 40
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0, 0, 0))
    mover = bpy.context.active_object
    mover.name = "Mover"
    for frame, loc, rot, scale in [(1, (0, 0, 0), (0, 0, 0), (1, 1, 1)),
                                   (20, (2, 1, 0.5), (0.3, 0.5, 1.0), (1.5, 1, 0.5)),
                                   (40, (-1, 3, 2), (1.0, -0.5, 2.0), (0.5, 2, 1))]:
        mover.location, mover.rotation_euler, mover.scale = loc, rot, scale
        for path in ("location", "rotation_euler", "scale"):
            mover.keyframe_insert(path, frame=frame)
    parent = bpy.data.objects.new("Spinner", None)
    scene.collection.objects.link(parent)
    parent.location = (0, -2, 0)
    for frame, angle in [(1, 0.0), (40, math.pi / 2)]:
        parent.rotation_euler = (0, 0, angle)
        parent.keyframe_insert("rotation_euler", frame=frame)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.25, location=(0, 0, 0))
    child = bpy.context.active_object
    child.name = "Child"
    child.parent = parent
    child.location = (1.5, 0, 0.3)
    return [mover, child]


def world_bounds(obj):
    import bpy

    deps = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(deps)
    mesh = ev.to_mesh()
    pts = [yup(ev.matrix_world @ v.co) for v in mesh.vertices]
    ev.to_mesh_clear()
    return [min(p[i] for p in pts) for i in range(3)], [max(p[i] for p in pts) for i in range(3)]


def test_frames(binary, work):
    import bpy

    objects = keyed_scene()
    path = os.path.join(work, "keyed.gltf")
    bpy.ops.export_scene.gltf(filepath=path, export_format="GLTF_SEPARATE")
    doc = json.load(open(path))
    node_of = {n.get("name"): i for i, n in enumerate(doc["nodes"])}
    for frame in FRAMES:
        bpy.context.scene.frame_set(frame)
        r = info(binary, path, frame)
        got = {b["node"]: b for b in r["node_bounds"]}
        worst, detail = 0.0, []
        for obj in objects:
            lo, hi = world_bounds(obj)
            b = got.get(node_of.get(obj.name))
            if b is None:
                worst = math.inf
                detail.append(f"{obj.name}: no bounds from aperture")
                continue
            err = max(abs(a - w) / max(1.0, abs(w)) for a, w in zip(b["min"] + b["max"], lo + hi))
            worst = max(worst, err)
            detail.append(f"{obj.name} max {[round(x, 5) for x in b['max']]} vs Blender {[round(x, 5) for x in hi]}")
        record(f"a.frame-{frame}", worst <= 1e-5, f"worst relative difference {worst:.2e}; " + "; ".join(detail))


def focus_scene():
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 30
    scene.render.resolution_x, scene.render.resolution_y = W, H
    bpy.ops.mesh.primitive_uv_sphere_add(radius=EMITTER_RADIUS, location=(0, EMITTER_DEPTH, 0))
    bulb = bpy.context.active_object
    bulb.name = "Bulb"
    mat = bpy.data.materials.new("Glow")
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0, 0, 0, 1)
    bsdf.inputs["Emission Color"].default_value = (1, 1, 1, 1)
    bsdf.inputs["Emission Strength"].default_value = 1000.0
    bulb.data.materials.append(mat)
    target = bpy.data.objects.new("Target", None)
    scene.collection.objects.link(target)
    for frame, y in [(1, 1.2), (30, 2.6)]:
        target.location = (0.3, y, 0.2)
        target.keyframe_insert("location", frame=frame)
    cams = {}
    for name in ("CamPull", "CamKeyed"):
        data = bpy.data.cameras.new(name)
        cam = bpy.data.objects.new(name, data)
        scene.collection.objects.link(cam)
        cam.rotation_euler = (math.pi / 2, 0, 0)
        data.lens, data.sensor_width, data.sensor_fit = LENS, 36.0, "AUTO"
        data.dof.use_dof = True
        data.dof.aperture_fstop = FSTOP
        cams[name] = cam
    cams["CamPull"].data.dof.focus_object = target
    keyed = cams["CamKeyed"].data
    for frame, dist in [(1, 1.0), (30, 3.0)]:
        keyed.dof.focus_distance = dist
        keyed.dof.keyframe_insert("focus_distance", frame=frame)
    scene.camera = cams["CamPull"]
    return cams


def blob_diameter(path, expected):
    """Disc diameter from the blob's second moment: mean r² = a²/2 for a uniform disc of radius a,
    plus the emitter's own image (b²/2) and the 1-pixel box filter (1/6)."""
    import numpy as np
    from exr_beauty import read_beauty

    lum = read_beauty(path, bottom_up=True).mean(axis=2)
    h, w = lum.shape
    ys, xs = np.mgrid[0:h, 0:w]
    cx, cy = w / 2.0, h / 2.0
    r2 = (xs + 0.5 - cx) ** 2 + (ys + 0.5 - cy) ** 2
    weight = np.where(r2 <= (0.5 * expected + 4.0) ** 2, lum, 0.0)
    m = (weight * r2).sum() / weight.sum()
    tan_half_y = 18.0 / LENS * H / W
    b = EMITTER_RADIUS / EMITTER_DEPTH * (H / 2.0) / tan_half_y
    return 2.0 * math.sqrt(max(0.0, 2.0 * (m - 1.0 / 6.0 - b * b / 2.0)))


def test_focus_pull(binary, work):
    import bpy
    from mathutils import Vector

    cams = focus_scene()
    addon_file = addon_zip(tempfile.mkdtemp(prefix="aperture-addon-", dir=work))
    bpy.ops.preferences.addon_install(filepath=addon_file, overwrite=True)
    bpy.ops.preferences.addon_enable(module=ADDON)
    path = os.path.join(work, "focus.gltf")
    bpy.ops.export_scene.gltf(filepath=path, export_format="GLTF_SEPARATE", export_cameras=True,
                              export_extras=True)
    doc = json.load(open(path))
    pointers = [c["target"].get("extensions", {}).get("KHR_animation_pointer", {}).get("pointer")
                for a in doc.get("animations", []) for c in a["channels"]]
    record("b.addon-pointer-channel", any(p and p.endswith("/extras/focus_distance") for p in pointers),
           f"pointer channels {[p for p in pointers if p]}")
    radius = LENS * 0.001 / (2.0 * FSTOP)
    tan_half_y = 18.0 / LENS * H / W
    for name, cam in cams.items():
        for frame in (1, 15, 30):
            bpy.context.scene.frame_set(frame)
            m = cam.matrix_world
            view = m.to_quaternion() @ Vector((0, 0, -1))
            if name == "CamPull":
                f = (bpy.data.objects["Target"].matrix_world.translation - m.translation).dot(view)
            else:
                f = cam.data.dof.focus_distance
            z = (Vector((0, EMITTER_DEPTH, 0)) - m.translation).dot(view)
            want = radius * abs(1.0 / f - 1.0 / z) * H / tan_half_y
            out = os.path.join(work, f"{name}_{frame}.exr")
            cmd = [binary, "render", path, "-o", out, "--camera", name, "--frame", str(frame),
                   "--width", str(W), "--height", str(H), "--spp", str(SPP), "--filter", "box"]
            run = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
            if run.returncode != 0:
                record(f"b.{name}-frame-{frame}", False, f"`{' '.join(cmd)}`: {run.stderr.strip()[-300:]}")
                continue
            got = blob_diameter(out, want)
            r = info(binary, path, frame)
            dof = next(c["dof"] for c in r["cameras"] if c["name"] == name)
            record(f"b.{name}-frame-{frame}", abs(got / want - 1.0) <= 0.05,
                   f"focus {f:.4f} m in Blender, {dof['focus_distance']} in aperture info; blur "
                   f"diameter {got:.2f} px measured vs {want:.2f} px from SPEC §2 ({got / want - 1.0:+.2%})")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--aperture", default=os.path.join(HERE, "../../target/release/aperture"))
    parser.add_argument("--out")
    parser.add_argument("--require-all", action="store_true")
    args = parser.parse_args()
    work = os.path.abspath(args.out) if args.out else tempfile.mkdtemp(prefix="aperture-anim-")
    os.makedirs(work, exist_ok=True)
    scripts = tempfile.mkdtemp(prefix="aperture-blender-scripts-")
    os.environ["BLENDER_USER_SCRIPTS"] = scripts
    os.environ["BLENDER_USER_CONFIG"] = os.path.join(scripts, "config")
    binary = os.path.abspath(args.aperture)
    try:
        import bpy

        print(f"Blender {bpy.app.version_string}, working in {work}")
        help_text = subprocess.run([binary, "info", "--help"], capture_output=True, text=True).stdout \
            if os.path.isfile(binary) else ""
        if "--frame" not in help_text:
            record("animation", None if not args.require_all else False, f"{binary} has no --frame")
        else:
            test_frames(binary, work)
            test_focus_pull(binary, work)
    finally:
        shutil.rmtree(scripts, ignore_errors=True)
        if not args.out:
            shutil.rmtree(work, ignore_errors=True)
    passed, failed, skipped = (RESULTS.count(s) for s in ("PASS", "FAIL", "SKIP"))
    print(f"{passed} passed, {failed} failed, {skipped} skipped")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
