# SPDX-License-Identifier: MIT OR Apache-2.0
"""The viewport's session (issue 63): one ``aperture`` scene loaded from one export of the
Blender scene, kept in step with Blender by edits made from the depsgraph's updates, and a
worker thread that renders it progressively.

What takes which path (``Session.sync`` returns ``[(path, name)]``):

- ``camera``: the active camera's move, lens, sensor or depth of field: ``set_camera``;
- ``transform``: an object's move (``is_updated_transform``): ``set_transform`` of its node;
- ``light``: a light's colour, power, exposure or temperature: ``set_light``;
- ``material``: a Principled BSDF's Base Color, Alpha, Metallic, Roughness: ``set_material``;
- ``visible``: an exported object's Disable in Renders: ``set_visible``;
- ``geometry``: a mesh's new triangles (edit mode, modifiers): ``set_geometry`` of that mesh
  alone, read from the evaluated object (``mesh_arrays``), no export;
- ``options``: world and render settings: the next render's options (no edit);
- ``reexport``: a new object, a mesh whose material slots changed or that the arrays cannot
  carry (shape keys, skins, ...), or a change the edits cannot express (a light's type, a
  material's links, ...): the whole scene is exported again and reloaded.

The export writes stand-ins for the meshes and the load takes their triangles as arrays
(``mesh_arrays``: the exporter's vertex deduplication was most of a big scene's start). A
geometry flag is confirmed against a hash of the evaluated mesh, so a material or modifier
update that leaves the mesh as it was sends nothing.

F12 and the viewport share one session per Blender scene (``shared``): F12's depsgraph is a
fresh evaluation, so F12 brings the session to it with ``Session.refresh``, which compares every
exported object's edit values with the ones sent (the same edits, no updates needed): a second
F12 with nothing changed exports nothing and sends nothing.
"""

import json
import os
import shutil
import struct
import tempfile
import threading
import time

import bpy
import numpy as np

from . import mesh_arrays, viewport_mirror as mirror, world
from .scene_export import export_scene, resolution


def available():
    """True when the ``aperture`` Python module imports (else the engine keeps the CLI)."""
    try:
        import aperture  # noqa: F401
    except ImportError:
        return False
    return True


def glb_json(path):
    """The JSON chunk of a .glb."""
    with open(path, "rb") as f:
        head = f.read(20)
        length, kind = struct.unpack_from("<II", head, 12)
        if kind != 0x4E4F534A:
            raise ValueError(f"{path}: the first chunk is not JSON")
        return json.loads(f.read(length))


def env_options(scene):
    """The world as ``render`` options (the engine's `--env` arguments, parsed)."""
    args, _ = world.env_arguments(scene.world)
    opts = {}
    for flag, value in zip(args[::2], args[1::2]):
        if flag == "--env":
            parts = value.split(",")
            opts["env"] = [float(v) for v in parts] if len(parts) == 3 else value
        else:
            opts[flag[2:].replace("-", "_")] = float(value)
    return opts


def render_options(scene, size=None):
    """``scene.render`` options equal to the F12 command's (no passes, no denoising)."""
    s = scene.aperture
    w, h = size or resolution(scene)
    opts = dict(width=w, height=h, spp=s.samples, seed=s.seed, max_bounces=s.max_bounces,
                clamp_direct=s.clamp_direct, clamp_indirect=s.clamp_indirect,
                filter=s.filter.lower().replace("_", "-"), passes="none")
    if s.noise_threshold > 0.0:
        opts["noise_threshold"] = s.noise_threshold
    if s.transmission != "AUTO":
        opts["transmission"] = s.transmission.lower()
    if scene.camera is not None:
        opts["camera"] = scene.camera.data.name
    opts.update(env_options(scene))
    return opts


# Cycles' viewport denoising settings (faster than F12's high/accurate).
VIEWPORT_DENOISE = dict(denoise=True, denoise_quality="balanced", denoise_prefilter="fast")
DENOISE_KEYS = tuple(VIEWPORT_DENOISE)


def viewport_denoise(scene):
    """The worker's options for the *Viewport Denoise* setting: ``({options}, start sample)``,
    ``({}, None)`` when it is off."""
    s = scene.aperture
    if not s.viewport_denoise:
        return {}, None
    return dict(VIEWPORT_DENOISE), s.viewport_denoise_start


# Object types the export writes a node for that a new object of would need a re-export.
EXPORTED = {"MESH", "CURVE", "SURFACE", "META", "FONT", "LIGHT", "CAMERA", "EMPTY"}


def _same(a, b):
    """Equal edit values (numpy matrices, dicts, lists, numbers)."""
    if isinstance(a, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b)
    return a == b


# The first image after an update should come within this (Cycles' viewport aims at 1/30 s).
FIRST_IMAGE_SECONDS = 1.0 / 30.0
# The coarsest preview: one pixel of it covers PIXEL_SIZE_MAX² of the viewport's.
PIXEL_SIZE_MAX = 16


def pixel_size_for(full_pass_seconds, target=FIRST_IMAGE_SECONDS):
    """The preview's pixel size (a power of two) for a viewport whose full-resolution
    one-sample pass took ``full_pass_seconds``: the smallest whose pass (a quarter of the
    pixels at each doubling) fits ``target``, as Cycles halves the resolution until an update
    fits. 1 (no preview) when the full pass fits already."""
    size = 1
    while size < PIXEL_SIZE_MAX and full_pass_seconds / (size * size) > target:
        size *= 2
    return size


def pass_estimate(full_pass_seconds, preview_seconds, pixel_size):
    """What a full-resolution one-sample pass is taken to cost for choosing the next preview:
    the last worker's measured full pass, or its preview's time times the pixels it left out
    (``pixel_size``²) when that is more. A small preview costs more per pixel than the full
    pass (its rays part sooner; the render's own set-up): on 980 k triangles the full pass
    chose pixel size 8, whose preview took 38 ms, not the 16 ms the pass predicted. So the
    next preview is chosen from what the last one took, as Cycles adapts its resolution
    divider to the last update's time. None when neither was measured."""
    scaled = None if preview_seconds is None else preview_seconds * pixel_size * pixel_size
    if full_pass_seconds is None or scaled is None:
        return scaled if full_pass_seconds is None else full_pass_seconds
    return max(full_pass_seconds, scaled)


# While samples still come, denoising may take at most this share of the worker's time (Cycles'
# render scheduler limits its viewport denoiser likewise); the last film is always denoised.
DENOISE_SHARE = 0.25


def denoise_now(samples, start, done, denoised_before, rendered, last_cost):
    """Whether the worker denoises the film it has now: never below ``start`` samples (or with
    ``start`` None); always the last film (``done``) and the first from ``start`` on; between
    them once the render time since the last denoised film (``rendered``, seconds) is at least
    (1 / DENOISE_SHARE - 1) times that denoise's cost (``last_cost``), so the denoiser takes
    at most DENOISE_SHARE of the time. On a 2-core machine a denoised 1080p film costs three
    one-sample passes: denoising every pass made the film refine four times slower."""
    if start is None or samples < start:
        return False
    if done or not denoised_before:
        return True
    return rendered * DENOISE_SHARE >= last_cost * (1.0 - DENOISE_SHARE)


class Worker:
    """Renders one progressive render on a thread until it is done or stopped: first, when
    ``pixel_size`` > 1, one sample at 1/pixel_size of the resolution (shown with each of its
    pixels covering pixel_size² of the film's: the quick first image while the view changes),
    then the doubling schedule at full resolution. ``film`` is the latest image (always the
    full size), ``samples`` its samples per pixel (0 for the preview); ``first_shape`` the
    resolution of the first image and ``full_pass_seconds`` the first full-resolution pass's
    time (what the next update's pixel size is chosen from). With ``denoise_start`` (options
    with ``denoise``), films from that many samples on are denoised when :func:`denoise_now`
    says so, the last one always; the film shown stays the last denoised one in between
    (``denoised`` counts them). ``clock`` is the time source (tests pass their own)."""

    def __init__(self, scene, options, pixel_size=1, denoise_start=None, clock=time.perf_counter):
        self._clock = clock
        self.render = scene.start(**options)
        self.denoise_start = denoise_start if options.get("denoise") else None
        self.denoised = 0
        self.film, self.samples, self.error = None, 0, None
        self.first_shape, self.full_pass_seconds, self.preview_seconds = None, None, None
        self._scene, self._options, self.pixel_size = scene, options, pixel_size
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _preview(self):
        """The quick first image: one sample at 1/pixel_size of the resolution, scaled up;
        ``preview_seconds`` its time (what the next update's pixel size is chosen from too)."""
        t = self._clock()
        w, h, ps = self._options["width"], self._options["height"], self.pixel_size
        drop = ("noise_threshold", "min_spp") + DENOISE_KEYS
        opts = {k: v for k, v in self._options.items() if k not in drop}
        opts.update(width=-(-w // ps), height=-(-h // ps), spp=1, passes="none")
        small = self._scene.render(**opts).image
        self.first_shape = small.shape[:2]
        big = np.repeat(np.repeat(small, ps, axis=0), ps, axis=1)[:h, :w]
        self.preview_seconds = self._clock() - t
        with self._lock:
            self.film, self.samples = big, 0

    def _run(self):
        try:
            if self.pixel_size > 1 and "width" in self._options and "height" in self._options:
                self._preview()
            rendered, last_cost = 0.0, 0.0
            while not self.render.done:
                t = self._clock()
                self.render.step()
                rendered += self._clock() - t
                samples, start = self.render.samples, self.denoise_start
                denoise = denoise_now(samples, start, self.render.done, self.denoised > 0,
                                      rendered, last_cost)
                if start is not None and samples >= start and not denoise:
                    continue  # the last denoised film stays up: no noisy film in between
                d = self._clock()
                image = self.render.image(denoise=denoise).image
                if denoise:
                    last_cost = self._clock() - d
                    self.denoised, rendered = self.denoised + 1, 0.0
                if self.full_pass_seconds is None:
                    # The pass and its film, not the denoiser: the preview is never denoised.
                    self.full_pass_seconds = self._clock() - t - (last_cost if denoise else 0.0)
                    self.first_shape = self.first_shape or image.shape[:2]
                with self._lock:
                    self.film, self.samples = image, samples
        except Exception as e:  # reported by the engine, never raised into Blender
            self.error = e

    def latest(self):
        with self._lock:
            return self.film, self.samples

    def stop(self):
        """Cancels within a batch of samples and waits for the thread."""
        self.render.cancel()
        self._thread.join()

    def wait(self, timeout=None):
        self._thread.join(timeout)
        return not self._thread.is_alive()


_SHARED = {}


def shared(depsgraph, export=export_scene):
    """The session F12 and the viewport share for this Blender scene: created (one export) on
    first use, else brought to ``depsgraph``'s state by ``Session.refresh``. Its ``last_sync``
    says what that took (``[("export", scene)]`` for a new one). Hold ``lock`` while using it."""
    key = (bpy.data.filepath, depsgraph.scene.name)
    s = _SHARED.get(key)
    if s is None:
        s = _SHARED[key] = Session(depsgraph, export=export)
        s.last_sync = [("export", depsgraph.scene.name)]
    else:
        s.last_sync = s.refresh(depsgraph)
    return s


def existing(depsgraph):
    """The shared session of ``depsgraph``'s scene, or None (nothing is created)."""
    return _SHARED.get((bpy.data.filepath, depsgraph.scene.name))


def synced(depsgraph, export=export_scene):
    """The shared session for the viewport: created as ``shared`` does, else synced from
    ``depsgraph.updates`` (cheaper than a refresh: only what changed is looked at)."""
    key = (bpy.data.filepath, depsgraph.scene.name)
    s = _SHARED.get(key)
    if s is None:
        return shared(depsgraph, export)
    s.last_sync = s.sync(depsgraph)
    return s


@bpy.app.handlers.persistent
def free_shared(*_):
    """Frees every shared session (a file is loaded, the add-on is disabled)."""
    for s in _SHARED.values():
        s.free()
    _SHARED.clear()


class Session:
    """One loaded export of the scene, its name maps, the last synced state, and a worker."""

    def __init__(self, depsgraph, size=None, export=export_scene):
        import aperture

        self._aperture, self._export, self._size = aperture, export, size
        # F12 (a render thread) and the viewport (the main thread) take turns.
        self.lock = threading.RLock()
        self.last_sync = []
        self.folder = tempfile.mkdtemp(prefix="aperture-viewport-")
        self.exports = 0
        self.edits = []  # every (path, name) synced, for tests and the header's report
        self.worker = None
        self.notice = None  # a warning for the viewport's header (denoising unavailable)
        self._busy = False  # an export's own depsgraph updates are not synced
        self._reload(depsgraph)

    # -- the export and its maps ------------------------------------------------------------
    def _reload(self, depsgraph):
        self.exports += 1
        path = os.path.join(self.folder, f"scene{self.exports}.glb")
        doc, geometry = self._export_arrays(path, depsgraph)
        self.scene = self._aperture.load(path, geometry=geometry)
        self.triangles = mesh_arrays.drawn_triangles(doc, geometry)
        self.path = path
        self.nodes = {n.get("name"): i for i, n in enumerate(doc.get("nodes", []))}
        self.parents = {c: p for p, n in enumerate(doc.get("nodes", [])) for c in n.get("children", [])}
        lights = doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
        self.lights = {l.get("name"): i for i, l in enumerate(lights)}
        self.materials = {m.get("name"): i for i, m in enumerate(doc.get("materials", []))}
        self.scene_options = render_options(depsgraph.scene, self._size)
        self._snapshot(depsgraph)

    def _export_arrays(self, path, depsgraph, stand_ins=True):
        """Exports to ``path`` with stand-in meshes; returns the JSON and the stood-in meshes'
        arrays. A stood-in mesh that cannot be read back exports again without stand-ins."""
        self._busy = True
        try:
            with mesh_arrays.stubbed(stand_ins) as stubs:
                self._export(path)
        finally:
            self._busy = False
        doc = glb_json(path)
        self.stood_in, self.drawn_by = {}, {}
        if not stubs:
            return doc, {}
        try:
            geometry, self.drawn_by = mesh_arrays.given(doc, lambda n: bpy.data.objects[n].evaluated_get(
                depsgraph) if n in bpy.data.objects else None)
        except LookupError:
            return self._export_arrays(path, depsgraph, stand_ins=False)
        self.stood_in = mesh_arrays.stood_in(doc)
        return doc, geometry

    def _geometry(self, obj, depsgraph):
        """A stood-in mesh's new triangles as ``set_geometry`` (the objects drawing it take the
        new hash), or ``reexport`` when its slots changed or it is not stood in."""
        m = self.drawn_by.get(obj.name)
        prims = None if m is None else mesh_arrays.primitives(
            obj.evaluated_get(depsgraph).data, self.stood_in[m][0])
        if prims is None:
            return "reexport"
        self.scene.set_geometry(m, prims)
        for name in (n for n, k in self.drawn_by.items() if k == m and n in bpy.data.objects):
            o = bpy.data.objects[name].evaluated_get(depsgraph)
            self.geometry[name] = mirror.geometry_signature(o)
        return "geometry"

    def _snapshot(self, depsgraph):
        """What the export holds now: visibility, geometry hashes and the signatures of what
        the edits do not cover."""
        self.visible, self.geometry, self.signatures, self.sent = {}, {}, {}, {}
        for light in bpy.data.lights:
            self.signatures[("light", light.name)] = mirror.rna_signature(light, mirror.LIGHT_EDITED)
        for cam in bpy.data.cameras:
            self.signatures[("camera", cam.name)] = mirror.rna_signature(cam, mirror.CAMERA_EDITED)
        for mat in bpy.data.materials:
            self.signatures[("material", mat.name)] = mirror.material_signature(mat)
        for obj in self._objects():
            self.visible[obj.name] = not obj.hide_render
            if obj.type == "MESH":
                self.geometry[obj.name] = mirror.geometry_signature(obj.evaluated_get(depsgraph))
            self._edits(obj, send=False)

    def _objects(self):
        return [bpy.data.objects[n] for n in self.nodes if n in bpy.data.objects]

    def _parent(self, obj):
        p = self.parents.get(self.nodes[obj.name])
        names = {i: n for n, i in self.nodes.items()}
        return bpy.data.objects.get(names.get(p)) if p is not None else None

    # -- the edits --------------------------------------------------------------------------
    def _changed(self, key, value):
        old = self.signatures.get(key)
        self.signatures[key] = value
        return old != value

    def _send(self, key, value, apply, send=True):
        """Applies an edit unless the session has its value already; the path, or None."""
        if self.sent.get(key) is not None and _same(self.sent[key], value):
            return None
        self.sent[key] = value
        if send:
            apply(value)
        return key[0]

    def _edits(self, obj, send=True):
        """Sends (or, at a reload, records) every edit value of an exported object."""
        if obj.type == "CAMERA":
            self._camera(obj, send)
        else:
            self._transform(obj, send)
        if obj.type == "LIGHT":
            self._light(obj, send)
        for slot in getattr(obj, "material_slots", []):
            if slot.material is not None:
                self._material(slot.material, send)

    def _transform(self, obj, send=True):
        # The node's TRS as the exporter stores it: the session builds the matrix as a load
        # of that file does (exact for parented nodes too).
        trs = mirror.node_trs(obj, self._parent(obj))
        return self._send(("transform", obj.name), trs, lambda v: self.scene.set_transform(
            self.nodes[obj.name], translation=v[0], rotation=v[1], scale=v[2]), send)

    def _camera(self, obj, send=True):
        if self._changed(("camera", obj.data.name), mirror.rna_signature(obj.data, mirror.CAMERA_EDITED)):
            return "reexport"
        value = (mirror.node_matrix(obj, self._parent(obj)), mirror.camera_keys(obj.data))
        return self._send(("camera", obj.name), value, lambda v: self.scene.set_camera(
            obj.data.name, v[0], **v[1]), send)

    def _light(self, obj, send=True):
        values = mirror.light_values(obj.data, obj.matrix_world)
        if values is None or obj.data.name not in self.lights or self._changed(
                ("light", obj.data.name), mirror.rna_signature(obj.data, mirror.LIGHT_EDITED)):
            return "reexport"
        index = self.lights[obj.data.name]
        return self._send(("light", obj.data.name), values,
                          lambda v: self.scene.set_light(index, **v), send)

    def _material(self, mat, send=True):
        factors = mirror.material_factors(mat)
        if mat.name not in self.materials:
            return "ignored"  # not used by an exported mesh (a new use is a geometry edit)
        if factors is None or self._changed(("material", mat.name), mirror.material_signature(mat)):
            return "reexport"
        index = self.materials[mat.name]
        return self._send(("material", mat.name), factors,
                          lambda f: self.scene.set_material(index, **f), send)

    def _object(self, update, obj, depsgraph):
        """The paths an object's update takes."""
        if obj.name not in self.nodes:
            return ["reexport"] if not obj.hide_render else []
        paths = []
        if update.is_updated_geometry and obj.type == "MESH":
            sig = mirror.geometry_signature(obj.evaluated_get(depsgraph))
            if sig != self.geometry.get(obj.name):
                paths.append(self._geometry(obj, depsgraph))
        if obj.type == "CAMERA":
            return [self._camera(obj)] if update.is_updated_transform else []
        if update.is_updated_transform:
            paths.append(self._transform(obj))
        if obj.type == "LIGHT" and (update.is_updated_shading or update.is_updated_geometry):
            paths.append(self._light(obj))
        return paths

    def _update(self, update, depsgraph):
        """``[(path, name)]`` for one of ``depsgraph.updates``."""
        data = update.id.original if update.id.is_evaluated else update.id
        users = lambda: [o for o in self._objects() if o.data == data]
        if isinstance(data, bpy.types.Object):
            paths = self._object(update, data, depsgraph)
        elif isinstance(data, bpy.types.Camera):
            paths = [self._camera(o) for o in users()]
        elif isinstance(data, bpy.types.Light):
            paths = [self._light(o) for o in users()]
        elif isinstance(data, bpy.types.Material):
            paths = [self._material(data)]
        else:
            paths = []  # meshes' own updates come with their object's; world: options
        return [(p, data.name) for p in paths if p is not None]

    def _visibility(self):
        out = []
        for obj in self._objects():
            shown = not obj.hide_render
            if shown != self.visible.get(obj.name, shown):
                self.scene.set_visible(self.nodes[obj.name], shown)
                out.append(("visible", obj.name))
            self.visible[obj.name] = shown
        return out

    def sync(self, depsgraph):
        """Applies ``depsgraph.updates``; returns ``[(path, name)]`` (a re-export reloads the
        scene once however many updates ask for it). The worker restarts if anything
        changed."""
        if self._busy:
            return []
        self.stop()
        done = []
        for update in depsgraph.updates:
            done += self._update(update, depsgraph)
        return self._finish(depsgraph, done)

    def _finish(self, depsgraph, done):
        """The end of ``sync`` and ``refresh``: visibility, at most one re-export, options."""
        done += self._visibility()
        if any(p == "reexport" for p, _ in done):
            self._reload(depsgraph)
        options = render_options(depsgraph.scene, self._size)
        if options != self.scene_options:
            self.scene_options = options
            done.append(("options", depsgraph.scene.name))
        self.edits += done
        return done

    def refresh(self, depsgraph):
        """Brings the session to ``depsgraph``'s state without its updates (F12's depsgraph is
        a fresh evaluation): each exported object's edit values are sent where they differ
        from the ones sent; a changed mesh, a new or deleted object, or a change the edits
        cannot express re-exports. Returns ``[(path, name)]`` as ``sync`` does."""
        if self._busy:
            return []
        self.stop()
        done = []
        for obj in depsgraph.scene.objects:
            if obj.name not in self.nodes and not obj.hide_render and obj.type in EXPORTED:
                done.append(("reexport", obj.name))
        done += [("reexport", n) for n in self.visible if n not in bpy.data.objects]
        for obj in self._objects():
            if obj.type == "MESH" and self.geometry.get(obj.name) != mirror.geometry_signature(
                    obj.evaluated_get(depsgraph)):
                done.append((self._geometry(obj, depsgraph), obj.name))
            paths = [self._camera(obj)] if obj.type == "CAMERA" else [self._transform(obj)]
            if obj.type == "LIGHT":
                paths.append(self._light(obj))
            for slot in getattr(obj, "material_slots", []):
                if slot.material is not None:
                    paths.append(self._material(slot.material))
            done += [(p, obj.name) for p in paths if p not in (None, "ignored")]
        return self._finish(depsgraph, done)

    def forget_camera(self, obj):
        """The session's camera was moved outside the sync (the viewport's own view): the next
        sync or refresh sends ``obj``'s camera again."""
        self.sent.pop(("camera", obj.name), None)

    # -- rendering --------------------------------------------------------------------------
    def start(self, pixel_size=None, denoise_start=None, **overrides):
        """Starts the worker on the synced scene (stopping the last one). The first image
        comes at a reduced resolution when the last full-resolution pass, or the last preview
        scaled up (:func:`pass_estimate`), did not fit ``FIRST_IMAGE_SECONDS`` (``pixel_size``
        forces one; the very first start, with nothing measured, previews at 4). With the
        denoise options (``viewport_denoise``) the film is denoised from ``denoise_start``
        samples on; without Open Image Denoise the viewport renders undenoised and ``notice``
        says why."""
        self.stop()
        last = self.worker
        if pixel_size is None:
            estimate = None if last is None else pass_estimate(
                last.full_pass_seconds, last.preview_seconds, last.pixel_size)
            if estimate is None:
                pixel_size = last.pixel_size if last is not None else 4
            else:
                pixel_size = pixel_size_for(estimate)
        opts = {**self.scene_options, **overrides}
        opts.setdefault("bvh_quality", self.bvh_quality(opts))
        self.notice = None
        try:
            self.worker = Worker(self.scene, opts, pixel_size, denoise_start)
        except self._aperture.RenderError as e:
            if not opts.get("denoise") or "Open Image Denoise" not in str(e):
                raise
            self.notice = f"viewport denoising is off: {str(e).splitlines()[0]}"
            opts = {k: v for k, v in opts.items() if k not in DENOISE_KEYS}
            self.worker = Worker(self.scene, opts, pixel_size)
        return self.worker

    def bvh_quality(self, opts):
        """The BVH preset ``auto`` would choose for the whole progressive render (``fast``
        when it takes fewer samples than half the triangles), named explicitly so that the
        preview, which takes far fewer, uses the same BVH instead of building another."""
        samples = opts.get("width", 1) * opts.get("height", 1) * opts.get("spp", 64)
        return "fast" if 2 * samples < self.triangles else "medium"

    def stop(self):
        if self.worker is not None:
            self.worker.stop()

    def film(self):
        """The latest image (H×W×4 float32, rows from the top) or None."""
        return self.worker.latest()[0] if self.worker is not None else None

    def free(self):
        self.stop()
        self.worker = None
        shutil.rmtree(self.folder, ignore_errors=True)
