"""The Vector pass against Cycles (SPEC section 6): a cube keyed to move +2 m in x and +1 m in y
between frames 1 and 3, seen from above by Blender's default camera, rendered at frame 2 by
Cycles (motion blur off, Vector pass on) and by aperture from the glTF export. Both passes'
means over the pixels that move must agree (channel order X, Y, Z, W and signs included).

    ~/.cache/aperture/bpy-5.0.1/bin/python tools/blender/test_vector.py [aperture binary]

Measured 2026-11-29 with bpy 5.0.1: Cycles (X, Y, Z, W) = (-9.877, -4.938, -9.877, -4.938) px,
aperture the same to 1e-6 (418 and 400 moving pixels: Cycles averages the pass over its
samples, aperture takes the pixel centre's ray).
"""

import os
import subprocess
import sys
import tempfile

import bpy
import numpy as np
import OpenEXR

HERE = os.path.dirname(os.path.abspath(__file__))


def moving_means(path, prefix):
    """Mean (X, Y, Z, W) of the Vector pass over the pixels where it is not zero."""
    f = OpenEXR.File(path, separate_channels=True)
    for part in f.parts:
        ch = {n: np.array(c.pixels, dtype=np.float64) for n, c in part.channels.items()}
        names = [f"{prefix}Vector.{c}" for c in "XYZW"]
        if all(n in ch for n in names):
            stack = np.stack([ch[n] for n in names], axis=-1)
            mask = np.abs(stack).sum(axis=-1) > 1e-6
            return stack[mask].mean(axis=0), int(mask.sum())
    raise ValueError(f"{path}: no Vector pass")


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "../../target/release/aperture")
    work = tempfile.mkdtemp(prefix="aperture-vector-")
    bpy.ops.wm.read_factory_settings(use_empty=False)
    s = bpy.context.scene
    s.render.engine = "CYCLES"
    s.cycles.samples = 4
    s.cycles.device = "CPU"
    s.render.resolution_x = s.render.resolution_y = 64
    s.render.resolution_percentage = 100
    s.render.use_motion_blur = False
    cube, cam = bpy.data.objects["Cube"], bpy.data.objects["Camera"]
    cam.location, cam.rotation_euler = (0, 0, 10), (0, 0, 0)
    cube.location = (0, 0, 0)
    cube.keyframe_insert("location", frame=1)
    cube.location = (2, 1, 0)
    cube.keyframe_insert("location", frame=3)
    s.frame_set(2)
    s.view_layers[0].use_pass_vector = True
    s.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
    s.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    s.render.filepath = os.path.join(work, "cycles.exr")
    bpy.ops.render.render(write_still=True)
    cycles, n_cycles = moving_means(s.render.filepath, "ViewLayer.")

    glb = os.path.join(work, "scene.glb")
    bpy.ops.export_scene.gltf(filepath=glb, export_format="GLB", export_cameras=True,
                              export_yup=True, export_animations=True)
    out = os.path.join(work, "aperture.exr")
    subprocess.run([binary, "render", glb, "-o", out, "--width", "64", "--height", "64",
                    "--spp", "4", "--frame", "2", "--passes", "vector", "--env", "1,1,1",
                    "--quiet"], check=True)
    ours, n_ours = moving_means(out, "")
    print(f"Cycles  X Y Z W = {cycles} over {n_cycles} pixels")
    print(f"aperture X Y Z W = {ours} over {n_ours} pixels")
    ok = np.allclose(cycles, ours, rtol=1e-3, atol=1e-3)
    print("PASS" if ok else "FAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
