# SPDX-License-Identifier: MIT OR Apache-2.0
"""The "aperture" render engine: F12 exports the evaluated scene at the current frame to a
temporary GLB through Blender's own glTF exporter, runs `aperture render` on it, and loads its
EXR into the render result, passes included. With the `aperture` Python module, F12 renders the
scene the viewport keeps loaded instead (f12_session: nothing exported when nothing changed)."""

import json
import os
import queue
import shutil
import subprocess
import tempfile
import threading
import time

import bpy

from . import exr, f12_session, platforms, viewport_sync, world
from .scene_export import export_scene, resolution  # noqa: F401 (the engine's names)
from .viewport import ViewportMixin

# Blender pass name -> (channels, channel ids, type, aperture pass, view layer flag or None).
PASSES = [
    ("Depth", 1, "Z", "VALUE", "Depth", "use_pass_z"),
    ("Position", 3, "XYZ", "VECTOR", "Position", "use_pass_position"),
    ("Normal", 3, "XYZ", "VECTOR", "Normal", "use_pass_normal"),
    ("Diffuse Direct", 3, "RGB", "COLOR", "Diffuse Direct", "use_pass_diffuse_direct"),
    ("Diffuse Indirect", 3, "RGB", "COLOR", "Diffuse Indirect", "use_pass_diffuse_indirect"),
    ("Diffuse Color", 3, "RGB", "COLOR", "Diffuse Color", "use_pass_diffuse_color"),
    ("Glossy Direct", 3, "RGB", "COLOR", "Glossy Direct", "use_pass_glossy_direct"),
    ("Glossy Indirect", 3, "RGB", "COLOR", "Glossy Indirect", "use_pass_glossy_indirect"),
    ("Glossy Color", 3, "RGB", "COLOR", "Glossy Color", "use_pass_glossy_color"),
    ("Transmission Direct", 3, "RGB", "COLOR", "Transmission Direct", "use_pass_transmission_direct"),
    ("Transmission Indirect", 3, "RGB", "COLOR", "Transmission Indirect",
     "use_pass_transmission_indirect"),
    ("Transmission Color", 3, "RGB", "COLOR", "Transmission Color", "use_pass_transmission_color"),
    ("Emission", 3, "RGB", "COLOR", "Emission", "use_pass_emit"),
    ("Environment", 3, "RGB", "COLOR", "Environment", "use_pass_environment"),
    ("Denoising Albedo", 3, "RGB", "COLOR", "Denoising Albedo", None),
    ("Denoising Normal", 3, "XYZ", "VECTOR", "Denoising Normal", None),
]
CRYPTO = [("CryptoObject", "use_pass_cryptomatte_object"),
          ("CryptoMaterial", "use_pass_cryptomatte_material")]

# What the last render did, for tests and debugging: command, folder, process id.
LAST_RUN = {}


def enabled_passes(scene, view_layer):
    """The Blender passes this render produces, as PASSES rows and Cryptomatte layer names."""
    rows = [p for p in PASSES if (getattr(view_layer, p[5]) if p[5] else scene.aperture.denoising_data)]
    crypto = [name for name, flag in CRYPTO if getattr(view_layer, flag)]
    return rows, crypto


def find_binary(settings):
    setting = bpy.path.abspath(settings.binary) if settings.binary else ""
    path_dirs = os.environ.get("PATH", "").split(os.pathsep)
    home = os.path.expanduser("~")
    path = platforms.find_aperture(setting, path_dirs, home)
    if path is None:
        raise RuntimeError(
            f"the aperture binary ({platforms.exe('aperture')}) was not found: set it in Render "
            "Properties › aperture, or install it on PATH with `cargo install --path crates/cli`"
        )
    return path


def border(scene):
    """The border region as (x0, y0, x1, y1) in image pixels, rows from the top (aperture's
    `--region`), or None for the whole image."""
    r = scene.render
    if not r.use_border:
        return None
    w, h = resolution(scene)
    x0, x1 = int(r.border_min_x * w), int(r.border_max_x * w)
    bottom, top = int(r.border_min_y * h), int(r.border_max_y * h)
    if x1 <= x0 or top <= bottom:
        return None
    return x0, h - top, x1, h - bottom


def motion_arguments(scene):
    """The frame to render and its fps when motion blur is on (the shutter comes from the
    exported scene extras); nothing otherwise."""
    if not scene.render.use_motion_blur:
        return []
    fps = scene.render.fps / scene.render.fps_base
    return ["--frame", str(scene.frame_current), "--fps", f"{fps:.9g}"]


def blender_oidn():
    """The Open Image Denoise library that ships with this Blender (the `bpy` module's `lib/`,
    or the `lib/` beside the Blender executable, also `blender.shared/` on Windows), or None."""
    # Blender's <version>/ folder sits beside its lib/, in an installation and in the bpy module.
    bases = [os.path.dirname(bpy.utils.resource_path("LOCAL"))]
    if bpy.app.binary_path:
        bases.append(os.path.dirname(bpy.app.binary_path))
    folders = [os.path.join(b, d) for b in bases for d in platforms.blender_lib_dirs()]
    for folder in folders:
        lib = os.path.join(folder, platforms.oidn_library())
        if os.path.isfile(lib):
            return lib
    return None


def oidn_library(s):
    """The library to denoise with: the panel's, else None when APERTURE_OIDN is set (aperture
    reads it), else Blender's own, else None (aperture's search)."""
    lib = bpy.path.abspath(s.oidn) if s.oidn else None
    if lib is None and not os.environ.get("APERTURE_OIDN"):
        lib = blender_oidn()
    return lib


def denoise_arguments(s):
    """`--denoise`, its settings and the library (``oidn_library``)."""
    if not s.denoise:
        return []
    lib = oidn_library(s)
    settings = ["--denoise-prefilter", s.denoise_prefilter.lower(),
                "--denoise-quality", s.denoise_quality.lower()]
    return ["--denoise"] + settings + (["--oidn", lib] if lib else [])


def command(binary, glb, out, scene, view_layer):
    """The `aperture render` command line for this scene's settings; and what of the world it
    could not express."""
    s = scene.aperture
    w, h = resolution(scene)
    rows, crypto = enabled_passes(scene, view_layer)
    passes = ",".join([r[4] for r in rows] + crypto) or "none"
    cmd = [binary, "render", glb, "-o", out, "--width", str(w), "--height", str(h),
           "--spp", str(s.samples), "--seed", str(s.seed), "--max-bounces", str(s.max_bounces),
           "--clamp-direct", f"{s.clamp_direct:.9g}", "--clamp-indirect", f"{s.clamp_indirect:.9g}",
           "--filter", s.filter.lower().replace("_", "-"), "--passes", passes,
           "--progress", "json"]
    if s.noise_threshold > 0.0:
        cmd += ["--noise-threshold", f"{s.noise_threshold:.9g}"]
    cmd += denoise_arguments(s)
    cmd += motion_arguments(scene)
    if s.transmission != "AUTO":
        cmd += ["--transmission", s.transmission.lower()]
    if scene.camera is not None:
        cmd += ["--camera", scene.camera.data.name]
    region = border(scene)
    if region is not None:
        cmd += ["--region", ",".join(map(str, region))]
    env, problems = world.env_arguments(scene.world)
    return cmd + env, problems


class ApertureRenderEngine(ViewportMixin, bpy.types.RenderEngine):
    """aperture: physically based depth of field from glTF, as a Blender render engine."""

    bl_idname = "APERTURE"
    bl_label = "aperture"
    bl_use_postprocess = True
    bl_use_preview = False

    def update_render_passes(self, scene=None, renderlayer=None):
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")
        if scene.aperture.denoise:
            # As Cycles with denoising: the image before denoising, for the compositor.
            self.register_pass(scene, renderlayer, "Noisy Image", 4, "RGBA", "COLOR")
        rows, crypto = enabled_passes(scene, renderlayer)
        for name, n, chan, kind, _, _ in rows:
            self.register_pass(scene, renderlayer, name, n, chan, kind)
        for layer in crypto:
            for i in range(3):
                self.register_pass(scene, renderlayer, f"{layer}{i:02d}", 4, "RGBA", "COLOR")

    def render(self, depsgraph):
        scene = depsgraph.scene
        view_layer = depsgraph.view_layer
        if f12_session.usable(scene):
            self.render_in_session(depsgraph)
            return
        folder = tempfile.mkdtemp(prefix="aperture-blender-")
        LAST_RUN.clear()
        LAST_RUN["dir"] = folder
        try:
            binary = find_binary(scene.aperture)
            glb = os.path.join(folder, "scene.glb")
            out = os.path.join(folder, "render.exr")
            export_scene(glb, scene.render.use_motion_blur)
            cmd, problems = command(binary, glb, out, scene, view_layer)
            for p in problems:
                self.report({"WARNING"}, p)
            LAST_RUN["command"] = cmd
            if not self.run(cmd):
                return
            self.load(out, scene, view_layer)
        except Exception as e:  # every failure reaches the report area with its message
            self.report({"ERROR"}, f"aperture: {e}")
        finally:
            if not scene.aperture.keep_files:
                shutil.rmtree(folder, ignore_errors=True)

    def render_in_session(self, depsgraph):
        """F12 through the session the viewport shares (f12_session): no export when nothing
        changed."""
        scene, view_layer = depsgraph.scene, depsgraph.view_layer
        LAST_RUN.clear()
        LAST_RUN["path"] = "session"
        try:
            rows, crypto = enabled_passes(scene, view_layer)
            names = [r[4] for r in rows] + crypto
            lib = oidn_library(scene.aperture) if scene.aperture.denoise else None
            chans, synced = f12_session.render(depsgraph, names, self.cancelled,
                                               self.update_progress, lib)
            LAST_RUN["sync"] = synced
            s = viewport_sync.existing(depsgraph)
            LAST_RUN["exports"] = s.exports if s is not None else 0
            if chans is not None:
                self.load_channels(chans, scene, view_layer)
        except Exception as e:  # every failure reaches the report area with its message
            self.report({"ERROR"}, f"aperture: {e}")

    def run(self, cmd):
        """Runs aperture, forwarding its JSON progress; False when cancelled (Esc). Raises with
        aperture's own message when it fails."""
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        LAST_RUN["pid"] = proc.pid
        lines = queue.Queue()
        errors = []

        def pump(stream, sink):
            for line in stream:
                sink(line)

        threads = [threading.Thread(target=pump, args=(proc.stdout, lines.put), daemon=True),
                   threading.Thread(target=pump, args=(proc.stderr, errors.append), daemon=True)]
        for t in threads:
            t.start()
        while proc.poll() is None:
            if self.cancelled():
                proc.terminate()
                try:
                    proc.wait(timeout=1.0)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
                return False
            self.forward(lines)
            time.sleep(0.05)
        for t in threads:
            t.join(timeout=1.0)
        self.forward(lines)
        if proc.returncode != 0:
            lines = "".join(errors).strip().splitlines()
            # aperture's own message: its `error:` line (a usage error adds a help hint after).
            message = next((l for l in lines if l.startswith("error")), lines[-1] if lines else "")
            raise RuntimeError(message or f"exit status {proc.returncode}")
        return True

    def cancelled(self):
        """True once the user pressed Esc (Blender's ``test_break``)."""
        return self.test_break()

    def forward(self, lines):
        while True:
            try:
                line = lines.get_nowait()
            except queue.Empty:
                return
            try:
                event = json.loads(line)
            except ValueError:
                continue
            if event.get("event") == "progress":
                self.update_progress(float(event.get("fraction", 0.0)))
                self.update_stats("", f"aperture: {event.get('samples_done', 0)}/"
                                      f"{event.get('samples_total', 0)} samples, "
                                      f"{event.get('elapsed', 0.0):.1f} s")

    def load(self, path, scene, view_layer):
        """aperture's EXR into the render result: the beauty as Combined, each pass by name
        (rows flipped: Blender's are bottom to top)."""
        channels, _ = exr.read(path)
        self.load_channels(channels, scene, view_layer)

    def load_channels(self, channels, scene, view_layer):
        """EXR-style channels (``{"R": …, "Depth.Z": …}``, rows from the top) into the render
        result."""
        w, h = resolution(scene)
        x0, y0, x1, y1 = border(scene) or (0, 0, w, h)
        # With a border, Blender's render result is the border itself (placed in the image by
        # Blender, cropped or not as the scene says): the region's pixels fill it.
        result = self.begin_result(0, 0, x1 - x0, y1 - y0, layer=view_layer.name)
        layer = result.layers[0]

        def put(name, names):
            if name not in layer.passes or not all(n in channels for n in names):
                return
            data = [channels[n][::-1].reshape(-1) for n in names]
            import numpy as np

            pixels = np.stack(data, axis=-1).astype(np.float32)
            rect = layer.passes[name].rect
            try:  # a plain copy (Blender 4.x): a list of 230 k pixels took 0.1 s
                rect.foreach_set(pixels.reshape(-1))
            except (AttributeError, TypeError, RuntimeError):
                layer.passes[name].rect = pixels.tolist()

        if not scene.render.film_transparent:
            # As Cycles without Film › Transparent: the background is opaque (RGB is already
            # the radiance over it).
            channels["A"] = channels["A"] * 0.0 + 1.0
        put("Combined", ["R", "G", "B", "A"])
        put("Noisy Image", [f"Noisy Image.{c}" for c in "RGBA"])
        rows, crypto = enabled_passes(scene, view_layer)
        for name, _, chan, _, ap, _ in rows:
            put(name, [f"{ap}.{c}" for c in chan])
        for layer_name in crypto:
            for i in range(3):
                put(f"{layer_name}{i:02d}", [f"{layer_name}{i:02d}.{c}" for c in "RGBA"])
        self.end_result(result)


def register():
    bpy.utils.register_class(ApertureRenderEngine)
    # A new file frees the sessions F12 and the viewport share.
    bpy.app.handlers.load_pre.append(viewport_sync.free_shared)


def unregister():
    if viewport_sync.free_shared in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(viewport_sync.free_shared)
    viewport_sync.free_shared()
    bpy.utils.unregister_class(ApertureRenderEngine)
