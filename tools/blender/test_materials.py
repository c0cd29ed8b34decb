# SPDX-License-Identifier: MIT OR Apache-2.0
"""Acceptance test for materials Blender exports (issue 14): glass and Principled spheres, as
Cycles renders them after re-importing Blender's glTF export, against aperture's render of the
same export.

Run it with Blender as a Python module (bpy 5.0.1, Python 3.11); `run_test.sh` beside this file
sets that up.

    python test_materials.py [--aperture target/release/aperture] [--out DIR] [--spp 128]

1. Glass: a smooth glass sphere (Principled BSDF, Transmission 1, roughness 0, IOR 1.5; no
   volume, as Blender writes an ordinary glass object) on a matte ground, in a uniform world.
   Blender's exporter writes KHR_materials_transmission without KHR_materials_volume; aperture's
   default `--transmission auto` must read Blender's exporter in `asset.generator`, make the
   closed sphere refract and match Cycles within noise: RMSE of the two renderers' averages at
   most 1.25 × the noise both carry (each measured from two seeds: `rmse(a, b) / 2` is the noise
   of their average), and the mean within 1 %. `--transmission gltf` (thin-walled) must not.
2. Principled spheres: metal at roughness 0.3 and 0.7, a plastic and a glossy white dielectric,
   in a uniform world: each sphere's mean (its inner 80 %: the rims depend on Fresnel, where
   glTF's Schlick and Cycles' differ) within 3 % of Cycles'. This is what energy compensation is
   for: without it the rough metal is darker by about 10 %.

The ground and everything matte use Specular IOR Level 0 (exported as KHR_materials_specular
factor 0): a Lambertian in both renderers. The last line is "N passed, N failed, N skipped"; the
exit status is non-zero when anything failed.
"""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import cycles_settings  # noqa: E402
from checks import check, record, summary  # noqa: E402

ARGS = None
WORK = None
WIDTH, HEIGHT = 160, 120
WORLD = (0.6, 0.7, 0.9)

# name, location (Blender: Z up), radius, base colour, metallic, roughness
SPHERES = [
    ("Metal03", (-1.65, 0.0, 0.5), 0.5, (0.9, 0.7, 0.4), 1.0, 0.3),
    ("Metal07", (-0.55, 0.0, 0.5), 0.5, (0.9, 0.7, 0.4), 1.0, 0.7),
    ("Plastic", (0.55, 0.0, 0.5), 0.5, (0.1, 0.3, 0.7), 0.0, 0.4),
    ("GlossyWhite", (1.65, 0.0, 0.5), 0.5, (0.9, 0.9, 0.9), 0.0, 0.1),
]


def principled(name, colour, metallic=0.0, roughness=1.0, transmission=0.0, matte=False):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Transmission Weight"].default_value = transmission
    bsdf.inputs["IOR"].default_value = 1.5
    if matte:
        bsdf.inputs["Specular IOR Level"].default_value = 0.0
    return mat


def sphere(name, location, radius, mat):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=radius, location=location)
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    bpy.ops.object.shade_smooth()
    obj.data.materials.append(mat)
    return obj


def ground(size, colour):
    bpy.ops.mesh.primitive_plane_add(size=size, location=(0.0, 0.0, 0.0))
    g = bpy.context.active_object
    g.name = g.data.name = "Ground"
    g.data.materials.append(principled("Ground", colour, matte=True))


def camera(location, target):
    from mathutils import Vector

    data = bpy.data.cameras.new("Camera")
    cam = bpy.data.objects.new("Camera", data)
    bpy.context.scene.collection.objects.link(cam)
    cam.location = location
    direction = Vector(target) - Vector(location)
    cam.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    data.lens = 40.0
    data.clip_start = 0.05
    bpy.context.scene.camera = cam
    bpy.context.view_layer.update()  # matrix_world, for the projections below
    return cam


def new_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = WIDTH, HEIGHT
    sc.render.resolution_percentage = 100


def build_glass():
    new_scene()
    ground(8.0, (0.5, 0.45, 0.4))
    # A box beside and behind the sphere, so refraction has something to show.
    bpy.ops.mesh.primitive_cube_add(size=0.6, location=(0.5, 0.9, 0.3))
    box = bpy.context.active_object
    box.data.materials.append(principled("Box", (0.8, 0.2, 0.1), matte=True))
    sphere("Glass", (0.0, 0.0, 0.5), 0.5, principled("Glass", (1.0, 1.0, 1.0), roughness=0.0, transmission=1.0))
    camera((0.3, -3.2, 1.4), (0.1, 0.2, 0.35))


def build_spheres():
    new_scene()
    ground(12.0, (0.4, 0.4, 0.4))
    for name, loc, r, colour, metallic, rough in SPHERES:
        sphere(name, loc, r, principled(name, colour, metallic, rough))
    camera((0.0, -5.0, 1.3), (0.0, 0.0, 0.5))


def export(path):
    bpy.ops.export_scene.gltf(filepath=path, export_format="GLTF_SEPARATE", export_cameras=True,
                              export_yup=True, export_apply=True)
    with open(path) as f:
        return json.load(f)


def setup_cycles(spp, seed):
    sc = bpy.context.scene
    cycles_settings.unbiased(sc, spp, seed)
    world = bpy.data.worlds.new("World")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (*WORLD, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0
    sc.world = world


def cycles_of_export(gltf_path, out_path, spp, seed):
    """Cycles' render of the export, re-imported into an empty scene."""
    new_scene()
    bpy.ops.import_scene.gltf(filepath=gltf_path)
    sc = bpy.context.scene
    cams = [o for o in sc.objects if o.type == "CAMERA"]
    sc.camera = cams[0]
    setup_cycles(spp, seed)
    sc.render.filepath = out_path
    t = time.time()
    bpy.ops.render.render(write_still=True)
    return time.time() - t


def aperture(binary, gltf_path, out_path, spp, seed, *extra):
    cmd = [binary, "render", gltf_path, "-o", out_path, "--width", str(WIDTH), "--height", str(HEIGHT),
           "--spp", str(spp), "--seed", str(seed), "--filter", "box", "--max-bounces", "12",
           "--env", ",".join(str(c) for c in WORLD), *extra]
    t = time.time()
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=3600)
    if out.returncode != 0:
        raise RuntimeError(f"`{' '.join(cmd)}` exit {out.returncode}: {out.stderr[-400:]}")
    return time.time() - t


def load(path):
    from exr_beauty import read_beauty

    return read_beauty(path)


def rmse(a, b):
    import numpy as np

    return float(np.sqrt(np.mean((a - b) ** 2)))


def pair(render, prefix):
    """Two renders (seeds 1, 2) through `render(path, seed)`: their average and the noise RMSE
    of that average, rmse(a, b) / 2."""
    paths = [os.path.join(WORK, f"{prefix}_{s}.exr") for s in (1, 2)]
    secs = sum(render(p, s) for p, s in zip(paths, (1, 2)))
    a, b = load(paths[0]), load(paths[1])
    return 0.5 * (a + b), rmse(a, b) / 2.0, secs


def write_png(img, path, scale=1.0):
    """A quick look at a linear image (sRGB-encoded, clipped)."""
    import numpy as np

    h, w, _ = img.shape
    v = np.clip(img * scale, 0.0, 1.0)
    v = np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)
    im = bpy.data.images.new(os.path.basename(path), w, h, alpha=True)
    px = np.ones((h, w, 4), np.float32)
    px[..., :3] = v[::-1]
    im.pixels[:] = px.ravel()
    im.filepath_raw = path
    im.file_format = "PNG"
    im.save()


def test_glass(binary):
    build_glass()
    path = os.path.join(WORK, "glass.gltf")
    doc = export(path)
    used = doc.get("extensionsUsed", [])
    check("glass.export", "KHR_materials_transmission" in used and "KHR_materials_volume" not in used
          and "Blender I/O" in doc.get("asset", {}).get("generator", ""),
          f"Blender wrote transmission without a volume ({used}), generator {doc['asset'].get('generator')!r}")
    info = subprocess.run([binary, "info", "--json", path], capture_output=True, text=True, timeout=300)
    tr = json.loads(info.stdout).get("transmission", {}) if info.returncode == 0 else {}
    check("glass.auto-is-blender", tr.get("applies") == "blender" and tr.get("refractive_meshes") == 1,
          f"aperture info: transmission {tr}")
    spp = ARGS.spp
    cyc, n_cyc, t_cyc = pair(lambda p, s: cycles_of_export(path, p, spp, s), "glass_cycles")
    ours, n_ours, t_ours = pair(lambda p, s: aperture(binary, path, p, spp, s), "glass_aperture")
    thin, _, _ = pair(lambda p, s: aperture(binary, path, p, spp, s, "--transmission", "gltf"), "glass_thin")
    expected = math.hypot(n_cyc, n_ours)
    err, err_thin = rmse(ours, cyc), rmse(thin, cyc)
    print(f"glass: Cycles {t_cyc:.1f} s, aperture {t_ours:.1f} s for two {spp}-spp renders each")
    check("glass.within-noise", err <= 1.25 * expected,
          f"RMSE(aperture, Cycles) = {err:.5f}, noise: aperture {n_ours:.5f}, Cycles {n_cyc:.5f}, "
          f"limit 1.25 × {expected:.5f} = {1.25 * expected:.5f} (ratio {err / expected:.3f})")
    ratio = ours.mean() / cyc.mean()
    check("glass.mean", abs(ratio - 1.0) <= 0.01, f"mean(aperture) / mean(Cycles) = {ratio:.4f} (±1 %)")
    check("glass.thin-walled-differs", err_thin > 2.0 * 1.25 * expected,
          f"--transmission gltf (thin-walled) is {err_thin / expected:.2f} × the noise away: the test can fail")
    write_png(cyc, os.path.join(WORK, "glass_cycles.png"))
    write_png(ours, os.path.join(WORK, "glass_aperture.png"))
    write_png(abs(ours - cyc), os.path.join(WORK, "glass_difference_x4.png"), 4.0)


def sphere_masks(cam):
    """Per sphere, the pixels inside 80 % of its projected radius (rows top to bottom)."""
    import numpy as np
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    sc = bpy.context.scene
    ys, xs = np.mgrid[0:HEIGHT, 0:WIDTH]
    masks = {}
    for name, loc, r, *_ in SPHERES:
        c = world_to_camera_view(sc, cam, Vector(loc))
        edge = world_to_camera_view(sc, cam, Vector(loc) + cam.matrix_world.to_quaternion() @ Vector((r, 0, 0)))
        cx, cy = c.x * WIDTH, (1.0 - c.y) * HEIGHT
        rad = abs(edge.x - c.x) * WIDTH * 0.8
        masks[name] = (xs + 0.5 - cx) ** 2 + (ys + 0.5 - cy) ** 2 <= rad * rad
    return masks


def test_spheres(binary):
    build_spheres()
    cam = bpy.context.scene.camera
    masks = sphere_masks(cam)
    path = os.path.join(WORK, "spheres.gltf")
    export(path)
    spp = ARGS.spp
    cyc, _, t_cyc = pair(lambda p, s: cycles_of_export(path, p, spp, s), "spheres_cycles")
    ours, _, t_ours = pair(lambda p, s: aperture(binary, path, p, spp, s), "spheres_aperture")
    flat, _, _ = pair(lambda p, s: aperture(binary, path, p, spp, s, "--no-energy-compensation"),
                      "spheres_uncompensated")
    print(f"spheres: Cycles {t_cyc:.1f} s, aperture {t_ours:.1f} s for two {spp}-spp renders each")
    for name, *_ in SPHERES:
        m = masks[name]
        ratio = ours[m].mean() / cyc[m].mean()
        ratio_flat = flat[m].mean() / cyc[m].mean()
        check(f"spheres.{name}", abs(ratio - 1.0) <= 0.03,
              f"mean over {int(m.sum())} px: aperture / Cycles = {ratio:.4f} (±3 %); "
              f"without energy compensation {ratio_flat:.4f}")
    write_png(cyc, os.path.join(WORK, "spheres_cycles.png"))
    write_png(ours, os.path.join(WORK, "spheres_aperture.png"))
    write_png(abs(ours - cyc), os.path.join(WORK, "spheres_difference_x4.png"), 4.0)


def main():
    global ARGS, WORK, bpy
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--aperture", default=os.path.join(HERE, "../../target/release/aperture"))
    parser.add_argument("--out", help="keep the exports, renders and difference images in this folder")
    parser.add_argument("--spp", type=int, default=128, help="samples per pixel for both renderers")
    parser.add_argument("--require-all", action="store_true", help="fail (rather than skip) without a binary")
    ARGS = parser.parse_args()
    WORK = os.path.abspath(ARGS.out) if ARGS.out else tempfile.mkdtemp(prefix="aperture-materials-")
    os.makedirs(WORK, exist_ok=True)
    import bpy  # noqa: F401

    binary = os.path.abspath(ARGS.aperture)
    try:
        if not (os.path.isfile(binary) and os.access(binary, os.X_OK)):
            record("materials", None if not ARGS.require_all else False, f"no aperture binary at {binary}")
        else:
            print(f"Blender {bpy.app.version_string}, working in {WORK}")
            test_glass(binary)
            test_spheres(binary)
    finally:
        if not ARGS.out:
            shutil.rmtree(WORK, ignore_errors=True)
    return summary()


if __name__ == "__main__":
    sys.exit(main())
