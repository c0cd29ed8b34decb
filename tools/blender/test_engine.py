# SPDX-License-Identifier: MIT OR Apache-2.0
"""Acceptance test of the "aperture" render engine of the add-on (issue 20).

Run with Blender as a Python module (bpy 5.0.1, Python 3.11, with OpenEXR); `run_test.sh`
sets it up:

    python test_engine.py --aperture target/debug/aperture [--require-all]

With the engine selected, `bpy.ops.render.render()` must fill the render result with exactly
the pixels of `aperture render` on the same exported file (the engine keeps its files for the
test); the resolution percentage, the active camera, the frame, and the world's colour and
strength must change the render as they should; a cancelled render must leave no process and
no temporary files; the Depth and Normal passes must equal the EXR's and feed a Defocus node;
and aperture's own error message must reach the report area.
"""

import argparse
import math
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

from addon_zip import ADDON, addon_zip
from checks import check, record, summary

W, H = 96, 64
ARGS = None
WORK = None


def import_bpy(user_scripts):
    os.environ["BLENDER_USER_SCRIPTS"] = user_scripts
    os.environ["BLENDER_USER_CONFIG"] = os.path.join(user_scripts, "config")
    global bpy
    import bpy  # noqa: F401


def build_scene():
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = W, H
    sc.render.resolution_percentage = 100
    sc.frame_start, sc.frame_end = 1, 20

    def material(name, colour):
        mat = bpy.data.materials.new(name)
        mat.use_nodes = True
        bsdf = mat.node_tree.nodes["Principled BSDF"]
        bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
        bsdf.inputs["Roughness"].default_value = 1.0
        return mat

    bpy.ops.mesh.primitive_plane_add(size=20.0)
    bpy.context.active_object.data.materials.append(material("Ground", (0.5, 0.5, 0.5)))
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.5, location=(-1.0, 4.0, 0.5))
    ball = bpy.context.active_object
    ball.name = "Ball"
    ball.data.materials.append(material("Red", (0.8, 0.05, 0.05)))
    ball.keyframe_insert("location", frame=1)
    ball.location = (1.0, 4.0, 0.5)
    ball.keyframe_insert("location", frame=20)
    for name, loc, rot in (("CamA", (0.0, -2.0, 1.0), (84.0, 0.0, 0.0)),
                           ("CamB", (3.0, 1.0, 1.5), (75.0, 0.0, 60.0))):
        data = bpy.data.cameras.new(name)
        data.dof.use_dof = True
        data.dof.focus_object = ball
        data.dof.aperture_fstop = 2.8
        obj = bpy.data.objects.new(name, data)
        obj.location = loc
        obj.rotation_euler = tuple(math.radians(a) for a in rot)
        sc.collection.objects.link(obj)
    sc.camera = bpy.data.objects["CamA"]
    sc.world = bpy.data.worlds.new("World")
    sc.world.use_nodes = True
    background = sc.world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.2, 0.3, 0.5, 1.0)
    background.inputs["Strength"].default_value = 1.0
    sc.render.engine = "APERTURE"
    s = sc.aperture
    s.binary = os.path.abspath(ARGS.aperture)
    s.samples = 8
    s.seed = 3
    s.keep_files = True
    # The exactness checks below (bit-identical to the CLI, a border equal to the whole
    # render's pixels, strength 2 doubling the mean) hold for the raw render; denoising is
    # not linear. test_denoise turns it on (as a new scene has it).
    s.denoise = False
    # This test is of the command-line path (test_viewport.py tests F12 in the session).
    s.f12_session = False
    vl = sc.view_layers[0]
    vl.use_pass_z = True
    vl.use_pass_normal = True
    sc.frame_set(1)  # the keyframes were set by hand: evaluate the animation at frame 1
    return sc


def engine_module():
    return sys.modules[ADDON + ".engine"]


def read_exr(path):
    import OpenEXR

    return {k: np.array(v.pixels, dtype=np.float32)
            for k, v in OpenEXR.File(path, separate_channels=True).channels().items()}


def render(socket="Image", connect=None, name="out"):
    """Renders with the engine and returns the compositor's output of the Render Layers
    socket (or of `connect(tree, render_layers)`), RGBA rows top to bottom."""
    sc = bpy.context.scene
    tree = bpy.data.node_groups.new("Comp", "CompositorNodeTree")
    sc.compositing_node_group = tree
    rl = tree.nodes.new("CompositorNodeRLayers")
    out = tree.nodes.new("NodeGroupOutput")
    tree.interface.new_socket(name="Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    tree.links.new(connect(tree, rl) if connect else rl.outputs[socket], out.inputs[0])
    sc.render.use_compositing = True
    sc.render.image_settings.file_format = "OPEN_EXR"
    sc.render.image_settings.color_depth = "32"
    sc.view_settings.view_transform = "Standard"
    path = os.path.join(WORK, name + ".exr")
    sc.render.filepath = path
    bpy.ops.render.render(write_still=True)
    sc.compositing_node_group = None
    bpy.data.node_groups.remove(tree)
    ch = read_exr(path)
    prefix = next(n[:-1] for n in ch if n.endswith("R"))
    return np.stack([ch[prefix + c] for c in "RGBA"], axis=-1)


def cli_render(extra_out):
    """The engine's last command, run again by hand to another file: its EXR's channels."""
    cmd = list(engine_module().LAST_RUN["command"])
    cmd[cmd.index("-o") + 1] = extra_out
    cmd = [c for c in cmd if c not in ("--progress", "json")]
    subprocess.run(cmd, check=True, capture_output=True)
    return read_exr(extra_out)


def test_combined_bits():
    ours = render(name="combined")
    run = engine_module().LAST_RUN
    cli = cli_render(os.path.join(WORK, "cli.exr"))
    rgb = np.stack([cli[c] for c in "RGB"], axis=-1)
    # Film › Transparent is off: Combined is opaque, as Cycles makes it.
    same = ours.shape[:2] == rgb.shape[:2] and np.array_equal(
        ours[..., :3].view(np.uint32), rgb.view(np.uint32)) and (ours[..., 3] == 1.0).all()
    check("engine.combined-bit-identical", same,
          f"render result {ours.shape} vs `{os.path.basename(run['command'][0])} "
          f"render …` of the same export: RGB {'identical' if same else 'different'}, alpha 1; "
          f"mean {ours[..., :3].mean():.4f}")
    return ours, cli


def test_passes(cli):
    depth = render(socket="Depth", name="depth")[..., 0]
    normal = render(socket="Normal", name="normal")[..., :3]
    want_n = np.stack([cli[f"Normal.{c}"] for c in "XYZ"], axis=-1)
    dz = float(np.abs(depth - cli["Depth.Z"]).max())
    dn = float(np.abs(normal - want_n).max())
    check("engine.passes", dz == 0.0 and dn == 0.0,
          f"Depth and Normal equal the EXR's (largest differences {dz:.2e}, {dn:.2e}); depth "
          f"from {depth.min():.3f}, median {np.median(depth):.3f}")

    def defocus(tree, rl):
        d = tree.nodes.new("CompositorNodeDefocus")
        tree.links.new(rl.outputs["Image"], d.inputs["Image"])
        tree.links.new(rl.outputs["Depth"], d.inputs["Z"])
        return d.outputs["Image"]

    blurred = render(connect=defocus, name="defocus")
    sharp = np.stack([cli[c] for c in "RGBA"], axis=-1)
    changed = float(np.abs(blurred[..., :3] - sharp[..., :3]).mean())
    check("engine.defocus-node", np.isfinite(blurred).all() and changed > 1e-4,
          f"a Defocus node fed with Combined and Depth runs (mean change {changed:.4f})")


def test_resolution():
    sc = bpy.context.scene
    sc.render.resolution_percentage = 50
    half = render(name="half")
    sc.render.resolution_percentage = 100
    check("engine.resolution-percentage", half.shape[:2] == (H // 2, W // 2),
          f"50%: {half.shape[1]}x{half.shape[0]} from {W}x{H}")


def test_border(base):
    sc = bpy.context.scene
    r = sc.render
    r.use_border, r.use_crop_to_border = True, False
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = 0.25, 0.75, 0.5, 1.0
    part = render(name="border")
    cmd = engine_module().LAST_RUN["command"]
    r.use_border = False
    region = cmd[cmd.index("--region") + 1] if "--region" in cmd else None
    inside = (slice(0, H // 2), slice(W // 4, 3 * W // 4))  # the top half, middle half
    same = np.array_equal(part[inside][..., :3].view(np.uint32), base[inside][..., :3].view(np.uint32))
    outside = part.copy()
    outside[inside] = 0.0
    check("engine.border", region == f"{W // 4},0,{3 * W // 4},{H // 2}" and same
          and not outside[..., :3].any(),
          f"a border render passes --region {region}: inside bit-identical to the whole "
          f"render, nothing outside")


def test_camera(base):
    sc = bpy.context.scene
    sc.camera = bpy.data.objects["CamB"]
    other = render(name="camb")
    cmd = engine_module().LAST_RUN["command"]
    sc.camera = bpy.data.objects["CamA"]
    diff = float(np.abs(other - base).mean())
    check("engine.active-camera", cmd[cmd.index("--camera") + 1] == "CamB" and diff > 0.01,
          f"CamB renders another view (mean difference {diff:.3f})")


def red_centroid(img):
    red = (img[..., 0] > 2.0 * img[..., 1] + 0.02)
    ys, xs = np.nonzero(red)
    return xs.mean() if xs.size else float("nan"), xs.size


def test_frame():
    sc = bpy.context.scene
    sc.frame_set(1)
    a = render(name="frame1")
    sc.frame_set(20)
    b = render(name="frame20")
    sc.frame_set(1)
    (xa, na), (xb, nb) = red_centroid(a), red_centroid(b)
    check("engine.frame", na > 20 and nb > 20 and xb - xa > 10,
          f"the ball's image moves from x = {xa:.1f} (frame 1) to {xb:.1f} (frame 20)")


def footprint(img, empty):
    """Centre and spread (standard deviation, px) along x of where `img` differs from the same
    view without the ball (`empty`): the ball's image with its shadow."""
    w = np.abs(img[..., :3] - empty[..., :3]).sum(axis=(0, 2))
    x = np.arange(w.size)
    centre = float((w * x).sum() / w.sum())
    return centre, float(np.sqrt((w * (x - centre) ** 2).sum() / w.sum()))


def test_motion_blur():
    """F12 with Blender's motion blur on (shutter 6 frames, centred at frame 10): the engine asks
    for frame 10, and the ball's footprint is its still one spread by its path over the shutter
    (from where it stands at frames 7 and 13): a box of length L adds L²/12 to the variance."""
    sc = bpy.context.scene
    ball = bpy.data.objects["Ball"]
    try:
        sc.frame_set(10)
        ball.hide_render = True
        empty = render(name="empty10")
        ball.hide_render = False
        ends = []
        for f in (7, 13):
            sc.frame_set(f)
            ends.append(footprint(render(name=f"still{f}"), empty)[0])
        sc.frame_set(10)
        still = footprint(render(name="still10"), empty)
        sc.render.use_motion_blur = True
        sc.render.motion_blur_shutter = 6.0
        blurred = footprint(render(name="blur10"), empty)
        cmd = list(engine_module().LAST_RUN["command"])
    finally:
        ball.hide_render = False
        sc.render.use_motion_blur = False
        sc.frame_set(1)
    length = ends[1] - ends[0]
    added = math.sqrt(max(blurred[1] ** 2 - still[1] ** 2, 0.0))
    asked = "--frame" in cmd and cmd[cmd.index("--frame") + 1] == "10"
    check("engine.motion-blur",
          asked and length > 10 and abs(added - length / math.sqrt(12)) < 0.3 * length / math.sqrt(12)
          and abs(blurred[0] - still[0]) < 1.5,
          f"shutter 6 frames: the footprint spreads {blurred[1]:.2f} px against {still[1]:.2f} still, "
          f"adding {added:.2f} where a {length:.1f} px path adds {length / math.sqrt(12):.2f}; "
          f"centred at {blurred[0]:.1f} against {still[0]:.1f}; the command asks for frame 10: {asked}")


def test_world():
    sc = bpy.context.scene
    bg = sc.world.node_tree.nodes["Background"]
    one = render(name="world1")
    bg.inputs["Strength"].default_value = 2.0
    two = render(name="world2")
    bg.inputs["Strength"].default_value = 1.0
    bg.inputs["Color"].default_value = (0.5, 0.3, 0.2, 1.0)
    warm = render(name="world-warm")
    bg.inputs["Color"].default_value = (0.2, 0.3, 0.5, 1.0)
    ratio = float(two[..., :3].mean() / one[..., :3].mean())
    check("engine.world-strength", abs(ratio - 2.0) < 1e-3,
          f"world strength 2 doubles the mean brightness: ratio {ratio:.5f}")
    sky = (slice(0, 4), slice(None))  # the top rows see the sky
    cold = one[sky][..., :3].reshape(-1, 3).mean(0)
    hot = warm[sky][..., :3].reshape(-1, 3).mean(0)
    check("engine.world-colour", np.allclose(cold, (0.2, 0.3, 0.5), atol=2e-3)
          and np.allclose(hot, (0.5, 0.3, 0.2), atol=2e-3),
          f"sky pixels show the world colour: {np.round(cold, 4)} then {np.round(hot, 4)}")


def test_cancel():
    base = engine_module().ApertureRenderEngine

    class Cancelling(base):
        bl_idname = "APERTURE_CANCEL_TEST"
        bl_label = "aperture (cancel test)"
        calls = 0

        def cancelled(self):
            # Esc a moment after aperture has started (Blender's test_break cannot be
            # overridden from Python: the engine asks it through this method).
            Cancelling.calls += 1
            return Cancelling.calls > 10

    bpy.utils.register_class(Cancelling)
    sc = bpy.context.scene
    sc.render.engine = Cancelling.bl_idname
    sc.aperture.keep_files = False
    sc.aperture.samples = 4096
    import time

    t0 = time.time()
    bpy.ops.render.render(write_still=False)
    took = time.time() - t0
    run = engine_module().LAST_RUN
    try:
        os.kill(run["pid"], 0)
        alive = True
    except (ProcessLookupError, KeyError):
        alive = False
    gone = not os.path.exists(run["dir"])
    sc.aperture.samples = 8
    sc.aperture.keep_files = True
    sc.render.engine = "APERTURE"
    bpy.utils.unregister_class(Cancelling)
    check("engine.cancel", not alive and gone and took < 5,
          f"a 4096-spp render (about 20 s) stopped after {took:.1f} s; process left: {alive}; temporary "
          f"folder removed: {gone}")


def test_denoise():
    """The Denoise checkbox (on by default, as in Cycles) runs `--denoise` with the OIDN that
    ships inside Blender; Combined is the denoised image, Noisy Image the raw one."""
    s = bpy.context.scene.aperture
    default = type(s).bl_rna.properties["denoise"].default
    s.denoise = True
    denoised = render(name="denoised")
    cmd = engine_module().LAST_RUN["command"]
    noisy = render(socket="Noisy Image", name="noisy")
    props = type(s).bl_rna.properties
    cycles_defaults = (props["denoise_prefilter"].default, props["denoise_quality"].default)
    s.denoise_prefilter, s.denoise_quality = "FAST", "BALANCED"
    quick = render(name="quick")
    quick_cmd = " ".join(engine_module().LAST_RUN["command"])
    s.denoise_prefilter, s.denoise_quality = cycles_defaults
    s.denoise = False
    raw = render(name="raw")
    lib = cmd[cmd.index("--oidn") + 1] if "--oidn" in cmd else None
    ships = lib is not None and os.path.dirname(lib) == os.path.join(
        os.path.dirname(bpy.utils.resource_path("LOCAL")), "lib")
    check("engine.denoise-command", default and "--denoise" in cmd
          and (ships or bool(os.environ.get("APERTURE_OIDN"))),
          f"Denoise on by default: {default}; the command has --denoise and --oidn {lib}")
    same_noisy = np.array_equal(noisy[..., :3].view(np.uint32), raw[..., :3].view(np.uint32))
    changed = float(np.abs(denoised[..., :3] - raw[..., :3]).mean())
    ratio = float(denoised[..., :3].mean() / raw[..., :3].mean())
    check("engine.denoise", same_noisy and changed > 1e-4 and abs(ratio - 1.0) < 0.02,
          f"Noisy Image equals the undenoised render: {same_noisy}; Combined denoised (mean "
          f"change {changed:.4f}, brightness ratio {ratio:.4f})")
    differs = float(np.abs(quick[..., :3] - denoised[..., :3]).mean())
    quick_ratio = float(quick[..., :3].mean() / raw[..., :3].mean())
    check("engine.denoise-settings", cycles_defaults == ("ACCURATE", "HIGH")
          and "--denoise-prefilter accurate --denoise-quality high" in " ".join(cmd)
          and "--denoise-prefilter fast --denoise-quality balanced" in quick_cmd
          and differs > 1e-5 and abs(quick_ratio - 1.0) < 0.02,
          f"defaults {cycles_defaults}, as Cycles'; Prefilter Fast and Quality Balanced reach "
          f"the command and change the image (mean change {differs:.5f}, brightness ratio "
          f"{quick_ratio:.4f})")


def test_error():
    cam = bpy.data.objects["CamA"].data
    cam["aperture_fstop"] = -1.0
    log = os.path.join(WORK, "report.txt")
    # Blender prints reports from C: capture the process's own stdout and stderr.
    saved = [os.dup(1), os.dup(2)]
    with open(log, "w") as f:
        os.dup2(f.fileno(), 1)
        os.dup2(f.fileno(), 2)
        try:
            bpy.ops.render.render(write_still=False)
        except RuntimeError as e:
            print(e)
        finally:
            sys.stdout.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
    del cam["aperture_fstop"]
    text = open(log).read()
    line = next((l for l in text.splitlines() if "aperture_fstop" in l), "")
    check("engine.error-report", "aperture" in line and "-1" in line,
          f"the report area shows aperture's message: {line.strip()!r}")


def main():
    global ARGS, WORK
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--aperture", default="target/release/aperture")
    parser.add_argument("--require-all", action="store_true")
    ARGS, _ = parser.parse_known_args()
    WORK = tempfile.mkdtemp(prefix="aperture-engine-")
    # Every temporary folder of the run (the engine's own, kept by `keep_files`, included) is
    # made inside WORK and goes with it: CI runs leave nothing behind in the system's.
    tempfile.tempdir = WORK
    try:
        return run()
    finally:
        tempfile.tempdir = None
        shutil.rmtree(WORK, ignore_errors=True)


def run():
    if not os.path.isfile(ARGS.aperture):
        record("engine", False if ARGS.require_all else None, f"no aperture binary at {ARGS.aperture}")
        return summary()
    import_bpy(tempfile.mkdtemp(prefix="aperture-engine-scripts-"))
    print(f"Blender {bpy.app.version_string}, working in {WORK}")
    bpy.ops.wm.read_factory_settings(use_empty=True)  # resets the add-ons: install after
    bpy.ops.preferences.addon_install(filepath=addon_zip(WORK), overwrite=True)
    bpy.ops.preferences.addon_enable(module=ADDON)
    build_scene()
    base, cli = test_combined_bits()
    test_passes(cli)
    test_resolution()
    test_border(base)
    test_camera(base)
    test_frame()
    test_motion_blur()
    test_world()
    test_denoise()
    test_error()
    test_cancel()
    return summary()


if __name__ == "__main__":
    sys.exit(main())
