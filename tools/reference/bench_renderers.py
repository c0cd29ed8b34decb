#!/usr/bin/env python3
"""The three renderers of ``bench_scenes.py``, each as ``render(spp, seed) -> (linear RGB float64
image, seconds)`` over one scene definition of that script: Mitsuba 3 (its scene dict built from
the definition), Blender Cycles (the same glTF aperture renders, imported and matched to the
definition) and aperture (one ``aperture render`` process per render)."""

from __future__ import annotations

import importlib.util
import math
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench_mitsuba as bm  # noqa: E402  (render in passes)
import make_reference as mr  # noqa: E402  (Mitsuba sensor and conventions)

REPO = mr.REPO
MAX_BOUNCES = 6  # aperture/Cycles bounces; Mitsuba max_depth = MAX_BOUNCES + 2 (make_reference.py)

# --------------------------------------------------------------------------------------------
# Mitsuba 3.


def mitsuba_bsdf(o):
    if o["texture"]:
        refl = {"type": "bitmap", "filename": o["texture"], "filter_type": "bilinear", "wrap_mode": "repeat"}
    else:
        refl = {"type": "rgb", "value": list(o["albedo"])}
    return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": refl}}


def mitsuba_dict(mi, scene, ply_dir, size, spp=1, seed=0):
    """The Mitsuba scene: every mesh a PLY file (written once into `ply_dir`), make_reference's
    sensor, `path` with max_depth = MAX_BOUNCES + 2, constant environment if any."""
    os.makedirs(ply_dir, exist_ok=True)
    cam = scene["camera"]
    out = {"type": "scene",
           "integrator": {"type": "path", "max_depth": MAX_BOUNCES + 2, "hide_emitters": False},
           "sensor": mr.mitsuba_sensor(mi, (cam["eye"], cam["target"], cam["up"]), cam["yfov_deg"], cam["dof"],
                                       size, spp, seed)}
    for key, m in scene["meshes"].items():
        ply = os.path.join(ply_dir, f"{scene['name']}_{key}.ply")
        if not os.path.exists(ply):
            mr.write_ply(ply, m["pos"], m["nrm"], m["idx"], m.get("uv"))
    for o in scene["objects"]:
        shape = {"type": "ply", "filename": os.path.join(ply_dir, f"{scene['name']}_{o['mesh']}.ply"),
                 "to_world": mi.ScalarTransform4f(o["matrix"]), "bsdf": mitsuba_bsdf(o)}
        if o["emission"]:
            # Front (normal) side only; the panels face into the scene and their backs see nothing.
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": list(o["emission"])}}
        out[o["name"]] = shape
    for i, p in enumerate(scene["points"]):
        out[f"point{i}"] = {"type": "point", "position": list(p["position"]),
                            "intensity": {"type": "rgb", "value": list(p["intensity"])}}
    if scene["env"]:
        out["env"] = {"type": "constant", "radiance": {"type": "rgb", "value": list(scene["env"])}}
    return out


# --------------------------------------------------------------------------------------------
# Cycles (Blender as a Python module): the same glTF, imported, then matched to the definition.


def cycles_material(bpy, mat):
    """Replaces an imported material by Diffuse BSDF (roughness 0: Lambert) of the Principled
    node's base colour -- its value or whatever feeds it (the image texture, sRGB) -- plus an
    Emission of the Principled node's emission colour and strength."""
    nt = mat.node_tree
    pbsdf = next(n for n in nt.nodes if n.type == "BSDF_PRINCIPLED")
    out = next(n for n in nt.nodes if n.type == "OUTPUT_MATERIAL")
    diff = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diff.inputs["Roughness"].default_value = 0.0
    base = pbsdf.inputs["Base Color"]
    if base.is_linked:
        nt.links.new(base.links[0].from_socket, diff.inputs["Color"])
    else:
        diff.inputs["Color"].default_value = base.default_value
    strength = pbsdf.inputs["Emission Strength"].default_value
    colour = list(pbsdf.inputs["Emission Color"].default_value)
    shader = diff.outputs["BSDF"]
    if strength > 0 and max(colour[:3]) > 0:
        em = nt.nodes.new("ShaderNodeEmission")
        em.inputs["Color"].default_value = colour
        em.inputs["Strength"].default_value = strength
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(shader, add.inputs[0])
        nt.links.new(em.outputs["Emission"], add.inputs[1])
        shader = add.outputs["Shader"]
    nt.links.new(shader, out.inputs["Surface"])


def cycles_camera(bpy, sc, cam_def):
    """The imported camera, with the definition's vertical field of view and thin lens: Cycles'
    lens radius is focal length / (2 f-number), so f-number = lens / (2 R)."""
    cam = next(o for o in sc.objects if o.type == "CAMERA")
    sc.camera = cam
    data = cam.data
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.radians(cam_def["yfov_deg"])
    data.clip_start = 0.01
    data.dof.use_dof = True
    data.dof.focus_object = None
    data.dof.focus_distance = cam_def["dof"]["focus_distance"]
    data.dof.aperture_blades = 0
    data.dof.aperture_ratio = 1.0
    data.dof.aperture_fstop = data.lens * 1e-3 / (2.0 * cam_def["dof"]["aperture_radius"])


def cycles_load(scene, gltf, size, threads):
    """Blender scene ready to render: import, materials, lights (radius 0: the importer's W =
    cd / 683 x 4 pi, which Cycles turns back into W / 4 pi per steradian), camera, world,
    cycles_settings.unbiased with MAX_BOUNCES, persistent data (so repeated renders reuse the
    synced scene and BVH)."""
    import bpy
    import cycles_settings

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=gltf)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = size
    sc.render.resolution_percentage = 100
    cycles_settings.unbiased(sc, 1, 0)
    cy = sc.cycles
    cy.max_bounces = cy.diffuse_bounces = cy.glossy_bounces = cy.transmission_bounces = MAX_BOUNCES
    sc.render.threads_mode = "FIXED"
    sc.render.threads = threads
    sc.render.use_persistent_data = True
    sc.view_settings.view_transform = "Standard"
    for mat in bpy.data.materials:
        if mat.use_nodes:
            cycles_material(bpy, mat)
    for light in bpy.data.lights:
        light.shadow_soft_size = 0.0
    cycles_camera(bpy, sc, scene["camera"])
    world = bpy.data.worlds.new("World")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (*(scene["env"] or (0, 0, 0)), 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0
    sc.world = world
    return sc


# A denoiser's settings as (prefilter, quality); Cycles' defaults for F12.
DENOISE_DEFAULT = ("accurate", "high")


def cycles_denoising(sc, settings):
    """Cycles' own denoiser, on with `settings` (prefilter, quality; DENOISE_DEFAULT is what a
    Blender user has by default for F12) or off with None, set explicitly: Open Image Denoise
    on the CPU with albedo and normal."""
    cy = sc.cycles
    cy.use_denoising = settings is not None
    if settings is not None:
        cy.denoiser = "OPENIMAGEDENOISE"
        cy.denoising_input_passes = "RGB_ALBEDO_NORMAL"
        cy.denoising_prefilter = settings[0].upper()
        cy.denoising_quality = settings[1].upper()
        cy.denoising_use_gpu = False


def cycles_renderer(scene, gltf, size, threads, tmp, denoise=None):
    """render(spp, seed) -> (image, seconds): the seconds are `bpy.ops.render.render(write_still=
    True)` (with persistent data: session start, render, film read-back, the EXR write -- the
    render_post and render_write handlers fire within 1 ms of the call's end; no scene sync or
    BVH build after the first call). (`Render Result.save_render` after a plain render returns
    the first render's pixels again under persistent data, hence write_still.)"""
    import bpy
    sys.path.insert(0, os.path.join(REPO, "tools", "blender"))
    from exr_beauty import read_beauty

    sc = cycles_load(scene, gltf, size, threads)

    def render(spp, seed, raw=False):
        # raw: the reference, never denoised (its error is what a denoised image is judged by)
        cycles_denoising(sc, None if raw else denoise)
        sc.cycles.samples, sc.cycles.seed = spp, seed
        # A new output path each time: else a persistent session renders with the old samples
        # and seed (sc.update_tag() also works, but re-syncs more: +0.15 s on the interior).
        sc.render.filepath = os.path.join(tmp, f"cycles_{spp}_{seed}.exr")
        t0 = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        secs = time.perf_counter() - t0
        img = read_beauty(sc.render.filepath)
        os.remove(sc.render.filepath)
        return img, secs

    return render


# --------------------------------------------------------------------------------------------
# Mitsuba and aperture renderers: render(spp, seed) -> (linear RGB float64 image, seconds).


def mitsuba_renderer(scene, out, size, threads, variant):
    """Mitsuba: the scene is loaded once; the seconds are bench_mitsuba.render's (mi.render in
    passes of at most 256 spp, dr.eval + sync included, loading and kernel compilation not:
    the series' first call at each budget compiles)."""
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(variant)
    dr.set_thread_count(threads)
    loaded = mi.load_dict(mitsuba_dict(mi, scene, os.path.join(out, "scenes", "ply"), size))
    return lambda spp, seed, raw=False: bm.render(dr, mi, loaded, spp, seed)


def exr_render_time(path):
    """aperture's `aperture:renderTime` header attribute (render only: no loading, no BVH), read
    with the Blender add-on's EXR module (NumPy only; loaded by path, since its package imports
    bpy)."""
    spec = importlib.util.spec_from_file_location(
        "aperture_exr", os.path.join(REPO, "tools", "blender", "aperture_gltf_dof", "exr.py"))
    exr = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(exr)
    with open(path, "rb") as f:
        attrs, _ = exr.attributes(f.read())
    if "aperture:renderTime" not in attrs:
        raise ValueError(f"{path}: no aperture:renderTime")
    # A denoised render's wait is the render and the denoiser (Cycles' time holds both).
    return sum(float(np.frombuffer(attrs[k][1], "<f4")[0])
               for k in ("aperture:renderTime", "aperture:denoiseTime") if k in attrs)


def read_exr_rgb(path):
    """R, G, B of an EXR as float64 (Mitsuba's reader in the Mitsuba venv, OpenEXR's in Blender's)."""
    try:
        import mitsuba as mi
        if mi.variant() is None:
            mi.set_variant("scalar_rgb")
        bmp = mi.Bitmap(path)
        names = [bmp.struct_()[i].name for i in range(bmp.channel_count())]
        arr = np.array(bmp, dtype=np.float64)
        return np.stack([arr[:, :, names.index(c)] for c in "RGB"], -1)
    except ImportError:
        sys.path.insert(0, os.path.join(REPO, "tools", "blender"))
        from exr_beauty import read_beauty
        return read_beauty(path)


# Budgets up to which aperture renders twice per call and times the second (see aperture_renderer).
WARM_MAX_SPP = 256


def aperture_renderer(scene, gltf, binary, size, threads, tmp, bvh="medium", denoise=None):
    """aperture: one `aperture render` process per render; the seconds are the render time the
    EXR header records (the traced image only: scene loading and BVH build excluded), beauty
    only (`--passes none`: Mitsuba and Cycles render no Depth, Normal or Cryptomatte either). The BVH
    quality is fixed (`aperture bench`'s default, medium) rather than `render`'s automatic
    choice, which picks a faster build, slower traversal for small budgets.

    The process renders the image twice (`--frames 1..2` of a still scene: the same pixels, bit
    for bit) and the second render is the one timed, so that aperture is timed as Mitsuba and
    Cycles are, after a first call in the same process (a fresh process's render pays its film's
    page faults, its thread pool's start and its tables' first use: 0.2-3.9 % of the time
    measured, BENCHMARKS.md, "Frame sequences"). Renders above `WARM_MAX_SPP` (the references,
    whose time is not used) render once."""
    env = ["--env", ",".join(repr(float(c)) for c in scene["env"])] if scene["env"] else []
    # Whether frames 1 and 2 were seen to be the same render: the scene does not change between
    # calls, so one comparison (one more EXR read) settles it for all of them.
    still = []

    def render(spp, seed, raw=False):
        last = 2 if spp <= WARM_MAX_SPP else 1
        dn = [] if raw or denoise is None else [
            "--denoise", "--denoise-prefilter", denoise[0], "--denoise-quality", denoise[1]]
        pattern = os.path.join(tmp, "aperture_####.exr")
        cmd = [binary, "render", gltf, "-o", pattern, "--frames", f"1..{last}",
               "--width", str(size[0]), "--height", str(size[1]),
               "--spp", str(spp), "--seed", str(seed), "--threads", str(threads),
               "--max-bounces", str(MAX_BOUNCES), "--filter", "box", "--override-material", "diffuse",
               "--bvh-quality", bvh, "--passes", "none", "--quiet", *dn, *env]
        subprocess.run(cmd, check=True)
        exr = pattern.replace("####", f"{last:04d}")
        img = read_exr_rgb(exr)
        # Frames are posed at frame N: a scene that moves would time another image than a plain
        # render gives, so frames 1 and 2 must be the same render.
        if last == 2 and not still:
            if not np.array_equal(img, read_exr_rgb(pattern.replace("####", "0001"))):
                raise ValueError(f"{gltf}: frames 1 and 2 differ (an animated scene); time it cold")
            still.append(True)
        return img, exr_render_time(exr)

    return render


