"""The `aperture` wheel inside Blender's Python (issue 60): bpy 5.0.x imports next to aperture,
the demo is rendered from a bpy script, the image goes into a Blender image, is saved by Blender
as an EXR and read back by Blender unchanged; meanwhile Blender's Python keeps running (the
render releases the GIL).

    <bpy venv>/bin/python tools/python/blender_render.py assets/demo.glb

tools/python/test.sh runs it with the wheel it built installed into Blender's venv.
"""

import sys
import tempfile
import threading
import time
from pathlib import Path

import bpy
import numpy as np

import aperture


def main(scene_path):
    assert bpy.app.version >= (5, 0, 0), bpy.app.version_string
    scene = aperture.load(scene_path)
    ticks = []
    done = threading.Event()
    result = {}

    def render():
        result["r"] = scene.render(width=96, height=54, spp=8, passes=["Depth"])
        done.set()

    worker = threading.Thread(target=render)
    t0 = time.perf_counter()
    worker.start()
    while not done.is_set():  # Blender's side keeps working while aperture renders.
        ticks.append(len(bpy.data.objects))
        time.sleep(0.002)
    worker.join()
    secs = time.perf_counter() - t0
    image, passes = result["r"]
    assert image.shape == (54, 96, 4) and image.dtype == np.float32
    assert passes["Depth"].shape == (54, 96, 1)
    assert image[..., 3].max() > 0.0, "the demo is drawn"
    assert len(ticks) > 3, f"Blender's thread ran {len(ticks)} times during a {secs:.2f} s render"

    # Into Blender: an image datablock (rows bottom-up), saved as a float EXR and read back.
    bl = bpy.data.images.new("aperture", 96, 54, alpha=True, float_buffer=True)
    bl.pixels.foreach_set(np.ascontiguousarray(image[::-1]).reshape(-1))
    out = Path(tempfile.mkdtemp()) / "aperture_in_blender.exr"
    bl.filepath_raw = str(out)
    bl.file_format = "OPEN_EXR"
    bl.save()
    back = bpy.data.images.load(str(out))
    pixels = np.empty(96 * 54 * 4, np.float32)
    back.pixels.foreach_get(pixels)
    pixels = pixels.reshape(54, 96, 4)[::-1]
    # Blender's EXR writer stores half floats by default: equal to half precision where the
    # pixel is covered (Blender reads partly covered pixels back with its own alpha handling),
    # coverage equal everywhere.
    opaque = image[..., 3] == 1.0
    assert opaque.mean() > 0.5, opaque.mean()
    assert np.allclose(pixels[opaque], image[opaque], rtol=2e-3, atol=1e-4), \
        np.abs(pixels[opaque] - image[opaque]).max()
    assert np.allclose(pixels[..., 3], image[..., 3], atol=1e-3)
    print(f"blender {bpy.app.version_string}: aperture {aperture.__version__} rendered "
          f"{Path(scene_path).name} 96x54 8 spp in {secs:.2f} s (Blender's thread ran "
          f"{len(ticks)} times meanwhile); mean RGB {image[..., :3].mean():.4f}; "
          f"saved and re-read by Blender: {out}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "assets/demo.glb")
