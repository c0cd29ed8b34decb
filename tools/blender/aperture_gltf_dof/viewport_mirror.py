# SPDX-License-Identifier: MIT OR Apache-2.0
"""What Blender's glTF exporter (io_scene_gltf2, Blender 4.2–5.0, +Y up) would write for one
object, light, material or camera, computed without exporting: the values the viewport session
sends as edits. Each function follows the exporter's own code (named in its docstring) so that
an edit leaves the session as a fresh export would, bit for bit where the pipeline allows.

Also: signatures of what the mirror does not cover, so that a change of those is seen and
answered with a re-export instead of being dropped."""

import hashlib
import math

import numpy as np

from . import mesh_arrays
from .dof_export import KEYS, _json_value, native_extras

# io_scene_gltf2/blender/exp/tree.py: cameras and lights get a -90° turn about X with +Y up.
_CORRECTED = ("CAMERA", "LIGHT")
PBR_WATTS_TO_LUMENS = 683.0  # io_scene_gltf2/blender/com/conversion.py


def gltf_world(obj):
    """The exporter's ``vnode.matrix_world`` (Blender axes; tree.py): the object's world
    matrix, with the camera/light correction."""
    from mathutils import Quaternion

    m = obj.matrix_world.copy()
    if obj.type in _CORRECTED:
        m @= Quaternion((2**0.5 / 2, -(2**0.5) / 2, 0.0, 0.0)).to_matrix().to_4x4()
    return m


def _near(v, target):
    return v if abs(v - target) > 2.0e-6 else target  # gltf2_blender_math.round_if_near


def node_trs(obj, parent=None):
    """``(translation, rotation xyzw, scale)`` of the object's glTF node as floats
    (nodes.py ``__gather_trans_rot_scale``: local to ``parent``'s node, decomposed, the
    rotation normalised, axes swizzled to +Y up, values near the defaults rounded to them)."""
    m = gltf_world(obj)
    if parent is not None:
        m = gltf_world(parent).inverted_safe() @ m
    t, r, s = m.decompose()
    r.normalize()
    t = [_near(v, 0.0) for v in (t[0], t[2], -t[1])]
    r = [_near(r[0], 1.0)] + [_near(v, 0.0) for v in (r[1], r[3], -r[2])]
    s = [_near(v, 1.0) for v in (s[0], s[2], s[1])]
    return t, [r[1], r[2], r[3], r[0]], s


def _f32(values):
    return [float(np.float32(v)) for v in values]


def trs_matrix(t, r, s):
    """The 4×4 matrix (rows as math writes them) aperture builds from a stored TRS: f32 values
    widened to f64, the quaternion normalised and turned into a matrix in glam's order of
    operations (``DAffine3::from_scale_rotation_translation``). Rounded to f32 by the library,
    it equals what a fresh export places for a node without a parent."""
    t, (x, y, z, w), s = _f32(t), _f32(r), _f32(s)
    inv = 1.0 / math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x * inv, y * inv, z * inv, w * inv
    x2, y2, z2 = x + x, y + y, z + z
    xx, xy, xz, yy, yz, zz = x * x2, x * y2, x * z2, y * y2, y * z2, z * z2
    wx, wy, wz = w * x2, w * y2, w * z2
    cols = [(1.0 - (yy + zz), xy + wz, xz - wy), (xy - wz, 1.0 - (xx + zz), yz + wx),
            (xz + wy, yz - wx, 1.0 - (xx + yy))]
    m = np.eye(4)
    for c in range(3):
        m[:3, c] = [v * s[c] for v in cols[c]]
    m[:3, 3] = t
    return m


def node_matrix(obj, parent=None):
    """The object's glTF node's local matrix, as a fresh export would store it."""
    return trs_matrix(*node_trs(obj, parent))


def camera_keys(camera):
    """``set_camera`` keys of the camera data: SPEC §3's extras as the add-on's exporter hook
    writes them (custom properties win), every key named (None removes it)."""
    native, _ = native_extras(camera)
    keys = {}
    for key in KEYS:
        value = native.get(key)
        if key in camera.keys():
            custom = _json_value(camera[key])
            value = custom if custom is not None else value
        keys[key] = value
    return keys


def light_values(light, world_matrix):
    """``set_light`` values (lights.py ``__gather_color``/``__gather_intensity``, lighting
    mode "Standard", no node tree), or None when the light uses nodes (re-export)."""
    if getattr(light, "use_nodes", False) and light.node_tree is not None:
        return None
    color = list(light.color)
    if getattr(light, "use_temperature", False):
        color = [c * light.temperature_color for c in color]
    strength = light.energy
    if not getattr(light, "normalize", True):
        strength *= light.area(world_matrix=world_matrix)
    if light.type != "SUN":
        strength = strength / (4 * math.pi)
    strength *= PBR_WATTS_TO_LUMENS
    return {"color": color, "intensity": strength * 2 ** getattr(light, "exposure", 0.0)}


# Principled BSDF inputs the session edits (glTF factor names); anything else is a signature.
_FACTORS = {"Base Color": "base_color", "Metallic": "metallic", "Roughness": "roughness",
            "Alpha": None}


def _principled(material):
    tree = material.node_tree if material.use_nodes else None
    nodes = [n for n in tree.nodes if n.type == "BSDF_PRINCIPLED"] if tree else []
    return nodes[0] if len(nodes) == 1 else None


def material_factors(material):
    """``set_material`` factors of a material whose Principled BSDF's Base Color, Alpha,
    Metallic and Roughness are plain values (material pbr export); None otherwise."""
    bsdf = _principled(material)
    if bsdf is None or any(bsdf.inputs[k].is_linked for k in _FACTORS):
        return None
    rgb = list(bsdf.inputs["Base Color"].default_value)[:3]
    return {"base_color": rgb + [bsdf.inputs["Alpha"].default_value],
            "metallic": bsdf.inputs["Metallic"].default_value,
            "roughness": bsdf.inputs["Roughness"].default_value}


def _value(v):
    if isinstance(v, (str, bool, int, type(None))):
        return v
    try:
        return tuple(round(float(x), 7) for x in v)
    except TypeError:
        return round(float(v), 7) if isinstance(v, float) else repr(v)


def material_signature(material):
    """Everything of a material's node tree the factors above leave out: links and the other
    inputs' values (a change of these needs a re-export)."""
    tree = material.node_tree if material.use_nodes else None
    if tree is None:
        return (tuple(material.diffuse_color), material.blend_method)
    skip = {n.name for n in tree.nodes if n.type == "BSDF_PRINCIPLED"}
    items = [(l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
             for l in tree.links]
    for node in tree.nodes:
        for i in node.inputs:
            if hasattr(i, "default_value") and not (node.name in skip and i.name in _FACTORS):
                items.append((node.name, i.identifier, _value(i.default_value)))
    return tuple(items)


def rna_signature(data, skip):
    """A datablock's plain properties except ``skip`` (lights' and cameras' other settings)."""
    out = []
    for p in data.bl_rna.properties:
        if p.identifier in skip or p.type in ("POINTER", "COLLECTION") or p.identifier == "rna_type":
            continue
        out.append((p.identifier, _value(getattr(data, p.identifier))))
    return tuple(out)


LIGHT_EDITED = {"color", "energy", "exposure", "temperature", "use_temperature", "name"}
CAMERA_EDITED = {"lens", "sensor_width", "sensor_height", "sensor_fit", "name", "lens_unit",
                 "angle", "angle_x", "angle_y"}


def geometry_signature(obj):
    """A hash of the evaluated mesh (vertex positions, faces, materials): what a geometry edit
    changes and a material or transform edit does not."""
    mesh = obj.data
    h = hashlib.sha1(mesh_arrays.positions(mesh).tobytes())
    h.update(mesh_arrays.corner_vertices(mesh).tobytes())
    h.update(repr([m.name if m else None for m in mesh.materials]).encode())
    return h.hexdigest()
