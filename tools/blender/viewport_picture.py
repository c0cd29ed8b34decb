"""The README's picture of the viewport (issue 63): bpy as a module has no window, so the
picture is the session's own film, the one ``view_draw`` uploads, at three moments after a
camera move: the quick first image (pixel size 8), the first full pass (1 sample a pixel) and
16 samples, side by side. The scene is assets/demo.glb imported into Blender.

    python viewport_picture.py OUT.png    (the bpy venv with the aperture wheel)
"""

import os
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
W, H = 480, 270


def main():
    out = os.path.abspath(sys.argv[1])
    work = tempfile.mkdtemp(prefix="aperture-viewport-picture-")
    os.environ["BLENDER_USER_SCRIPTS"] = os.path.join(work, "s")
    sys.path.insert(0, HERE)
    from addon_zip import ADDON, addon_zip
    import aperture
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=os.path.join(HERE, "..", "..", "assets", "demo.glb"))
    sc = bpy.context.scene
    sc.camera = next(o for o in sc.objects if o.type == "CAMERA")
    bpy.ops.preferences.addon_install(filepath=addon_zip(work), overwrite=True)
    bpy.ops.preferences.addon_enable(module=ADDON)
    vs = sys.modules[ADDON + ".viewport_sync"]
    sc.render.engine = "APERTURE"
    s = vs.Session(bpy.context.evaluated_depsgraph_get())
    panels = []
    # The preview as view_draw shows it: each of its pixels covers 8 × 8 of the viewport's.
    w = s.start(pixel_size=8, width=W, height=H, spp=1)
    w.wait()
    opts = {k: v for k, v in w._options.items() if k not in ("noise_threshold", "min_spp")}
    opts.update(width=-(-W // 8), height=-(-H // 8), spp=1, passes="none")
    small = s.scene.render(**opts).image
    panels.append(np.repeat(np.repeat(small, 8, axis=0), 8, axis=1)[:H, :W])
    for spp in (1, 16):
        w = s.start(pixel_size=1, width=W, height=H, spp=spp)
        w.wait()
        panels.append(s.film())
    gap = np.ones((H, 6, 4), np.float32)
    image = np.concatenate([panels[0], gap, panels[1], gap, panels[2]], axis=1)
    aperture.write(out, np.ascontiguousarray(image), view="agx")
    s.free()
    print(out)


if __name__ == "__main__":
    main()
