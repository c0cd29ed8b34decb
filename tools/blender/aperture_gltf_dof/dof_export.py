# SPDX-License-Identifier: MIT OR Apache-2.0
"""Depth of field into the glTF export: the exporter hook of the add-on (see the package's
documentation for the rules)."""
import math
import struct

import bpy

from .prescription_export import prescription_extras

# Camera data paths a focus pull keys, and the extras key each is exported to.
ANIMATED_KEYS = {"dof.focus_distance": "focus_distance", "dof.aperture_fstop": "aperture_fstop"}

# The keys this add-on writes, in SPEC section 3's order.
KEYS = (
    "use_dof",
    "focus_distance",
    "focus_object",
    "aperture_fstop",
    "aperture_blades",
    "aperture_rotation",
    "aperture_ratio",
    "lens",
    "sensor_width",
    "sensor_height",
    "sensor_fit",
    # Issue 61's lens keys (docs/lenses.md), written only when not 0.
    "aperture_vignetting",
    "distortion_k1",
    "distortion_k2",
    "distortion_k3",
    "distortion_p1",
    "distortion_p2",
    "chromatic_lateral",
    "chromatic_longitudinal",
)

# Written at export only, not sent by the viewport session's camera edits (``set_camera`` takes
# no arrays): the prescription's rows (issue 61).
EXPORT_ONLY_KEYS = ("lens_prescription",)

# The lens keys and the ``camera.aperture_lens`` property each comes from.
LENS_KEYS = {
    "aperture_vignetting": "vignetting",
    "distortion_k1": "k1",
    "distortion_k2": "k2",
    "distortion_k3": "k3",
    "distortion_p1": "p1",
    "distortion_p2": "p2",
    "chromatic_lateral": "chromatic_lateral",
    "chromatic_longitudinal": "chromatic_longitudinal",
}

# The bokeh image key: a file, copied beside the export (not a set_camera key: the image is
# loaded with the file, so the viewport re-exports when it changes).
IMAGE_KEY = "aperture_image"

# Written for orthographic cameras only (Cycles' radius for them).
ORTHO_RADIUS_KEY = "aperture_radius"

_PREFIX = "aperture_gltf_dof: "


def _json_value(value):
    """A custom property's value in a form the exporter can write (as its own extras code does)."""
    if isinstance(value, bpy.types.ID):
        return value  # the exporter writes an ID as {"name": ..., "type": ...}
    if isinstance(value, (bool, int, float, str)):
        return value
    if hasattr(value, "to_list"):
        return value.to_list()
    if hasattr(value, "to_dict"):
        return value.to_dict()
    if isinstance(value, (list, tuple)):
        return [_json_value(v) for v in value]
    return None


def _f32(value):
    """The shortest decimal that reads back as the same 32-bit float Blender stores (1.4, not
    1.399999976158142)."""
    value = float(value)
    packed = struct.pack("<f", value)
    for digits in range(6, 10):
        short = float(f"{value:.{digits}g}")
        if struct.pack("<f", short) == packed:
            return short
    return value


def native_extras(camera):
    """The camera data's native settings as SPEC section 3 extras: ``(extras, warnings)``.

    ``camera`` is a ``bpy.types.Camera`` (the object's data). Custom properties are not read here.
    """
    dof = camera.dof
    warnings = []
    blades = int(dof.aperture_blades)
    extras = {
        "use_dof": bool(dof.use_dof),
        "focus_distance": _f32(dof.focus_distance),
        "aperture_fstop": _f32(dof.aperture_fstop),
        "aperture_blades": blades if blades >= 3 else 0,
        "aperture_rotation": _f32(dof.aperture_rotation),
        "aperture_ratio": _f32(dof.aperture_ratio),
        "lens": _f32(camera.lens),
        "sensor_width": _f32(camera.sensor_width),
        "sensor_height": _f32(camera.sensor_height),
        "sensor_fit": str(camera.sensor_fit),
    }
    extras.update(lens_extras(camera))
    target = dof.focus_object
    if target is not None:
        extras["focus_object"] = target.name
        subtarget = getattr(dof, "focus_subtarget", "")
        if subtarget:
            warnings.append(
                f"camera '{camera.name}': focusing on bone '{subtarget}' of '{target.name}' is "
                f"not supported; the focus is on the origin of '{target.name}' instead"
            )
    return extras, warnings


def lens_extras(camera):
    """The camera's ``aperture_lens`` settings as extras, the keys that are not 0 (absent: the
    ideal thin lens, as aperture reads a missing key)."""
    lens = getattr(camera, "aperture_lens", None)
    if lens is None:
        return {}
    values = {key: _f32(getattr(lens, name)) for key, name in LENS_KEYS.items()}
    extras = {key: value for key, value in values.items() if value != 0.0}
    # The prescription (a file's rows, inline) when its path is set.
    extras.update(prescription_extras(lens))
    return extras


def aperture_image_extra(camera, export_settings):
    """The camera's bokeh image as ``(file name, warning)``: the file copied into the folder of
    the glTF file being written (aperture reads paths relative to it, never outside it), or
    ``(None, None)`` without an image."""
    import os
    import shutil

    lens = getattr(camera, "aperture_lens", None)
    path = getattr(lens, "aperture_image", "") if lens is not None else ""
    if not path:
        return None, None
    source = bpy.path.abspath(path)
    target = export_settings.get("gltf_filepath", "") if hasattr(export_settings, "get") else ""
    if not os.path.isfile(source):
        return None, f"camera '{camera.name}': bokeh image '{path}' not found; not exported"
    if not target:
        return None, f"camera '{camera.name}': no export folder known for the bokeh image"
    name = os.path.basename(source)
    folder = os.path.dirname(os.path.abspath(target))
    if os.path.abspath(os.path.join(folder, name)) != os.path.abspath(source):
        shutil.copyfile(source, os.path.join(folder, name))
    return name, None


def _warn(export_settings, message):
    log = export_settings.get("log") if hasattr(export_settings, "get") else None
    if log is not None and hasattr(log, "warning"):
        log.warning(_PREFIX + message)
    else:
        print("WARNING: " + _PREFIX + message)


def _view_depth(camera_object, target_object):
    """Distance of ``target_object``'s origin along ``camera_object``'s view axis (its local -Z)."""
    matrix = camera_object.matrix_world
    rotation = matrix.to_quaternion()  # scale removed, as SPEC section 1 says for cameras
    view = rotation @ bpy_vector((0.0, 0.0, -1.0))
    return (target_object.matrix_world.translation - matrix.translation).dot(view)


def bpy_vector(xyz):
    """A ``mathutils.Vector`` (imported lazily so the module loads without Blender's mathutils)."""
    from mathutils import Vector

    return Vector(xyz)


class glTF2ExportUserExtension:
    """Found by the glTF exporter among the enabled add-ons; one instance per export."""

    def __init__(self):
        # id(gltf camera) -> (camera data name, keys this add-on wrote from native values)
        self._written = {}
        # camera data name -> the glTF camera written for it
        self._gltf_cameras = {}
        # The frame shown when the export started: the exporter moves it while sampling.
        self._frame_current = bpy.context.scene.frame_current

    def gather_camera_hook(self, gltf2_camera, blender_camera, export_settings):
        """Adds the camera's depth of field to ``gltf2_camera.extras`` (custom properties win)."""
        if isinstance(blender_camera, bpy.types.Object):  # older exporters passed the object
            blender_camera = blender_camera.data
        if not isinstance(blender_camera, bpy.types.Camera):
            return
        native, warnings = native_extras(blender_camera)
        for message in warnings:
            _warn(export_settings, message)

        extras = gltf2_camera.extras if isinstance(gltf2_camera.extras, dict) else {}
        written = set()

        def put(key, value):
            if key in extras:
                return  # exported from a custom property already: it wins
            if key in blender_camera.keys():  # set by hand, "Custom Properties" export off
                custom = _json_value(blender_camera[key])
                if custom is not None:
                    extras[key] = custom
                    return
            extras[key] = value
            written.add(key)

        for key in KEYS + EXPORT_ONLY_KEYS:
            if key in native:
                put(key, native[key])
        image, problem = aperture_image_extra(blender_camera, export_settings)
        if problem:
            _warn(export_settings, problem)
        if image:
            put(IMAGE_KEY, image)

        if blender_camera.type == "ORTHO":
            fstop = extras.get("aperture_fstop")
            if isinstance(fstop, (int, float)) and not isinstance(fstop, bool) and fstop > 0:
                put(ORTHO_RADIUS_KEY, _f32(1.0 / (2.0 * float(fstop))))

        gltf2_camera.extras = extras
        self._written[id(gltf2_camera)] = (blender_camera.name, written)
        self._gltf_cameras[blender_camera.name] = gltf2_camera

    def gather_scene_hook(self, gltf2_scene, blender_scene, export_settings):
        """Adds the scene's motion-blur settings to ``gltf2_scene.extras`` (SPEC section 7)."""
        from . import motion_export

        motion_export.add_to(gltf2_scene, blender_scene, self._frame_current)

    def gather_gltf_hook(self, active_scene_idx, scenes, animations, export_settings):
        """Adds a ``KHR_animation_pointer`` animation for each camera with keyed DOF values."""
        for name, gltf_camera in self._gltf_cameras.items():
            data = bpy.data.cameras.get(name)
            curves = _dof_fcurves(data) if data is not None else {}
            if not curves:
                continue
            channels, samplers = [], []
            for key, curve in curves.items():
                frames = [k.co[0] for k in curve.keyframe_points]
                first, last = int(math.floor(min(frames))), int(math.ceil(max(frames)))
                scene = bpy.context.scene
                fps = scene.render.fps * scene.render.fps_base  # as the exporter's own keyframes
                times = [f / fps for f in range(first, last + 1)]
                values = [float(curve.evaluate(f)) for f in range(first, last + 1)]
                samplers.append(_sampler(times, values))
                channels.append(_pointer_channel(len(samplers) - 1, gltf_camera, key))
            animations.append(_animation(f"{name}_dof", channels, samplers))

    def gather_gltf_extensions_hook(self, gltf2_plan, export_settings):
        """Checks that each ``focus_object`` names an exported node, else falls back to a distance."""
        nodes = getattr(gltf2_plan, "nodes", None) or []
        cameras = getattr(gltf2_plan, "cameras", None) or []
        names = {getattr(n, "name", None) for n in nodes}
        for index, camera in enumerate(cameras):
            extras = getattr(camera, "extras", None)
            if not isinstance(extras, dict) or "focus_object" not in extras:
                continue
            target = extras["focus_object"]
            if not isinstance(target, str) or target in names:
                continue
            data_name, written = self._written.get(id(camera), (getattr(camera, "name", "?"), set()))
            if "focus_object" not in written:
                _warn(
                    export_settings,
                    f"camera '{data_name}': custom property focus_object = '{target}' names no "
                    "exported node",
                )
                continue
            del extras["focus_object"]
            camera_nodes = [
                n for n in nodes if getattr(n, "camera", None) in (index, camera)
            ]
            target_object = bpy.data.objects.get(target)
            camera_object = (
                bpy.data.objects.get(camera_nodes[0].name) if camera_nodes else None
            )
            if target_object is not None and camera_object is not None and "focus_distance" in written:
                depth = _view_depth(camera_object, target_object)
                if depth > 0.0:
                    extras["focus_distance"] = depth
                    _warn(
                        export_settings,
                        f"camera '{data_name}': focus object '{target}' is not exported; "
                        f"writing its depth, focus_distance = {depth:.6g}, instead",
                    )
                    continue
            _warn(
                export_settings,
                f"camera '{data_name}': focus object '{target}' is not exported; "
                f"focus_distance = {extras.get('focus_distance')} is used instead",
            )


def _dof_fcurves(camera):
    """``{extras key: fcurve}`` of the camera data's keyed depth of field (Blender 4.2 to 5.x)."""
    anim = camera.animation_data
    action = anim.action if anim is not None else None
    if action is None:
        return {}
    fcurves = None
    try:  # Blender 4.4+: slotted actions
        from bpy_extras import anim_utils

        bag = anim_utils.action_get_channelbag_for_slot(action, anim.action_slot)
        fcurves = bag.fcurves if bag is not None else None
    except (ImportError, AttributeError):
        pass
    if fcurves is None:
        fcurves = getattr(action, "fcurves", None) or []
    return {
        ANIMATED_KEYS[c.data_path]: c
        for c in fcurves
        if c.data_path in ANIMATED_KEYS and len(c.keyframe_points) > 0
    }


def _io():
    """The exporter's glTF object model (module names of Blender 4.2 to 5.x)."""
    from io_scene_gltf2.io.com import gltf2_io

    try:
        from io_scene_gltf2.io.com import constants
    except ImportError:
        from io_scene_gltf2.io.com import gltf2_io_constants as constants
    try:
        from io_scene_gltf2.io.exp.binary_data import BinaryData
    except ImportError:
        from io_scene_gltf2.io.exp.gltf2_io_binary_data import BinaryData
    return gltf2_io, constants, BinaryData


def _scalar_accessor(values):
    gltf2_io, constants, BinaryData = _io()
    return gltf2_io.Accessor(
        buffer_view=BinaryData.from_list(values, constants.ComponentType.Float),
        byte_offset=None,
        component_type=constants.ComponentType.Float,
        count=len(values),
        extensions=None,
        extras=None,
        max=[max(values)],
        min=[min(values)],
        name=None,
        normalized=None,
        sparse=None,
        type=constants.DataType.Scalar,
    )


def _sampler(times, values):
    gltf2_io, _, _ = _io()
    return gltf2_io.AnimationSampler(
        extensions=None,
        extras=None,
        input=_scalar_accessor(times),
        interpolation="LINEAR",
        output=_scalar_accessor(values),
    )


def _pointer_channel(sampler_index, gltf_camera, key):
    """A channel the exporter turns into ``/cameras/{index of gltf_camera}/extras/<key>``."""
    gltf2_io, _, _ = _io()
    target = gltf2_io.AnimationChannelTarget(
        extensions=None, extras=None, node=gltf_camera, path=f"/cameras/XXX/extras/{key}"
    )
    return gltf2_io.AnimationChannel(extensions=None, extras=None, sampler=sampler_index, target=target)


def _animation(name, channels, samplers):
    gltf2_io, _, _ = _io()
    return gltf2_io.Animation(channels=channels, extensions=None, extras=None, name=name, samplers=samplers)

