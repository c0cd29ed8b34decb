"""Motion blur against Cycles (SPEC section 7, issue 47). A scene of our own, made here in bpy:
an emissive cube translating 6 m and turning 1.5 rad between frames 1 and 5, an emissive ball
falling under gravity (keyed at every frame, z = 4 - g t^2 / 2), a camera with depth of field
(f/1.4, focused on the cube's path, so the ball, nearer, is out of focus while it falls). Frame
3 is rendered with a one-frame centred shutter by Cycles (CPU, box filter, 256 spp) and by
aperture from the glTF export (`--motion-blur --shutter 1`), each twice with other seeds, so
each renderer's noise is measured. Checks, with motion blur and again without it (both renderers
showing the instant of frame 3):

* the image means agree within 1 %;
* the RMSE between the renderers is within 1.5x their combined noise (sqrt(sa^2 + sc^2), each
  the RMSE of one image, half the RMSE between its two seeds times sqrt(2));
* with and without motion blur differ (the blur is there);
* and the same with a rolling shutter (Cycles' TOP, 0.3 of the shutter), which differs from
  the global shutter's image.

    ~/.cache/aperture/bpy-5.0.1/bin/python tools/blender/test_motion_blur.py [aperture binary]
"""

import math
import os
import subprocess
import sys
import tempfile

import bpy
import numpy as np
import OpenEXR

HERE = os.path.dirname(os.path.abspath(__file__))
W, H, SPP = 96, 64, 256
FSTOP, FOCUS = 1.4, 12.0
G = 9.81


def emitter(name, colour, strength):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (*colour, 1.0)
    em.inputs["Strength"].default_value = strength
    nt.links.new(em.outputs[0], out.inputs[0])
    return mat


def linear_keys(obj):
    """Linear keys: Cycles evaluates the curves between frames (Bezier by default), the glTF
    export samples them at frames and interpolates linearly; with linear curves both are the
    same motion (with Bezier keys the ball's fall differed by 0.1 m at shutter close)."""
    from bpy_extras import anim_utils

    anim = obj.animation_data
    for fc in anim_utils.action_get_channelbag_for_slot(anim.action, anim.action_slot).fcurves:
        for k in fc.keyframe_points:
            k.interpolation = "LINEAR"


def build():
    bpy.ops.wm.read_factory_settings(use_empty=False)
    s = bpy.context.scene
    s.render.engine = "CYCLES"
    s.cycles.samples = SPP
    s.cycles.device = "CPU"
    s.cycles.use_adaptive_sampling = False
    s.cycles.use_denoising = False
    s.cycles.pixel_filter_type = "BOX"
    s.render.resolution_x, s.render.resolution_y, s.render.resolution_percentage = W, H, 100
    s.render.fps = 24
    s.world = None
    for o in list(bpy.data.objects):
        if o.type == "LIGHT":
            bpy.data.objects.remove(o)
    cube, cam = bpy.data.objects["Cube"], bpy.data.objects["Camera"]
    # The camera looks along +Y from 12 m, level: the cube's path is 12 m away, the ball's 8 m.
    cam.location, cam.rotation_euler = (0.0, -FOCUS, 1.0), (math.radians(90), 0.0, 0.0)
    cam.data.lens = 35.0
    cam.data.dof.use_dof = True
    cam.data.dof.aperture_fstop = FSTOP
    cam.data.dof.focus_distance = FOCUS
    # The same lens for the glTF (SPEC section 3: custom properties of the camera data).
    cam.data["aperture_fstop"] = FSTOP
    cam.data["focus_distance"] = FOCUS
    cube.data.materials.clear()
    cube.data.materials.append(emitter("glow", (1.0, 1.0, 1.0), 1.0))
    cube.location, cube.rotation_euler = (-3.0, 0.0, 1.0), (0.0, 0.0, 0.0)
    cube.keyframe_insert("location", frame=1)
    cube.keyframe_insert("rotation_euler", frame=1)
    cube.location, cube.rotation_euler = (3.0, 0.0, 1.0), (0.0, 0.0, 1.5)
    cube.keyframe_insert("location", frame=5)
    cube.keyframe_insert("rotation_euler", frame=5)
    bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=0.5, location=(1.5, -4.0, 4.0))
    ball = bpy.context.active_object
    ball.name = "Ball"
    ball.data.materials.append(emitter("ball", (1.0, 0.4, 0.1), 2.0))
    for frame in range(1, 6):
        t = (frame - 1) / s.render.fps
        ball.location = (1.5, -4.0, 4.0 - 0.5 * G * t * t * 20.0)  # a 20x gravity: a visible fall
        ball.keyframe_insert("location", frame=frame)
    for obj in (cube, ball):
        linear_keys(obj)
    s.frame_set(3)
    s.render.motion_blur_shutter = 1.0
    s.render.motion_blur_position = "CENTER"
    s.render.image_settings.file_format = "OPEN_EXR"
    s.render.image_settings.color_depth = "32"
    s.view_settings.view_transform = "Standard"
    return s


def rgb(path):
    f = OpenEXR.File(path, separate_channels=True)
    ch = {n: np.array(c.pixels, dtype=np.float64) for n, c in f.channels().items()}
    return np.stack([ch[[n for n in ch if n.endswith(c)][0]] for c in "RGB"], -1)


def cycles(s, work, blur, seed):
    s.render.use_motion_blur = blur
    s.cycles.seed = seed
    s.render.filepath = f"{work}/cyc_{int(blur)}_{seed}.exr"
    bpy.ops.render.render(write_still=True)
    return rgb(s.render.filepath)


def aperture(binary, glb, work, blur, seed):
    out = f"{work}/ap_{int(blur)}_{seed}.exr"
    args = ["--motion-blur", "--shutter", "1"] if blur else ["--no-motion-blur"]
    subprocess.run([binary, "render", glb, "-o", out, "--width", str(W), "--height", str(H),
                    "--spp", str(SPP), "--seed", str(seed), "--frame", "3", "--filter", "box",
                    "--passes", "none", "--quiet"] + args, check=True)
    return rgb(out)


def rmse(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)))


def compare(label, c, a):
    """c, a: two seeds of each renderer. True when they agree (see the module documentation)."""
    noise_c, noise_a = rmse(*c) / math.sqrt(2), rmse(*a) / math.sqrt(2)
    combined = math.hypot(noise_c, noise_a)
    diff = rmse(c[0], a[0])
    mc, ma = float(c[0].mean()), float(a[0].mean())
    ok = abs(ma / mc - 1.0) < 0.01 and diff <= 1.5 * combined
    print(f"{'PASS' if ok else 'FAIL'} motion-blur.{label}: means {mc:.6f} (Cycles) {ma:.6f} "
          f"(aperture, {100 * (ma / mc - 1):+.2f} %); RMSE between them {diff:.4f}, combined "
          f"noise {combined:.4f} (Cycles {noise_c:.4f}, aperture {noise_a:.4f}): "
          f"{diff / combined:.2f}x")
    return ok


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "../../target/release/aperture")
    work = tempfile.mkdtemp(prefix="aperture-motion-")
    s = build()
    glb = f"{work}/mb_scene.glb"
    bpy.ops.export_scene.gltf(filepath=glb, export_format="GLB", export_cameras=True, export_yup=True,
                              export_animations=True, export_extras=True)
    ok = True
    images = {}
    for blur in (True, False):
        c = [cycles(s, work, blur, seed) for seed in (1, 2)]
        a = [aperture(binary, glb, work, blur, seed) for seed in (1, 2)]
        images[blur] = a[0]
        ok &= compare("on" if blur else "off", c, a)
    # A rolling shutter (Cycles' TOP, 0.3 of the shutter): the settings travel in the scene's
    # extras (SPEC section 7), as the add-on writes them.
    s.cycles.rolling_shutter_type, s.cycles.rolling_shutter_duration = "TOP", 0.3
    s["rolling_shutter_type"], s["rolling_shutter_duration"] = "TOP", 0.3
    rolling = f"{work}/mb_rolling.glb"
    bpy.ops.export_scene.gltf(filepath=rolling, export_format="GLB", export_cameras=True, export_yup=True,
                              export_animations=True, export_extras=True)
    c = [cycles(s, work, True, seed) for seed in (3, 4)]
    a = [aperture(binary, rolling, work, True, seed) for seed in (3, 4)]
    ok &= compare("rolling", c, a)
    ok &= float(np.abs(a[0] - images[True]).max()) > 0.1
    moved = float(np.abs(images[True] - images[False]).max())
    print(f"{'PASS' if moved > 0.1 else 'FAIL'} motion-blur.differs: largest difference between "
          f"aperture with and without motion blur {moved:.3f}")
    ok &= moved > 0.1
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
