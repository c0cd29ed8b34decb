#!/usr/bin/env python3
"""Reference scenes for aperture, rendered independently by Mitsuba 3.

Each scene is defined once, below, as plain data (boxes, quads, one light, a camera).
From that one definition the script writes

* ``assets/reference/<name>.gltf`` -- the scene for aperture (one embedded ``data:`` buffer),
* ``assets/reference/<name>.exr``  -- Mitsuba 3's render of the same scene (RGB float32),
* ``assets/reference/manifest.json`` -- what the Rust test needs to render the same image.

Mitsuba side: ``scalar_rgb`` variant, ``path`` integrator with ``max_depth = max_bounces + 2``
(Mitsuba counts path segments: 1 = emitters seen directly, 2 = direct light; aperture counts
bounces as Cycles does: 0 = direct light), ``hide_emitters`` false, ``independent`` sampler,
``hdrfilm`` with a 1-pixel ``box`` filter, ``thinlens`` (or ``perspective``) sensor with
``fov_axis`` 'y'. All surfaces are two-sided Lambertian (``twosided`` + ``diffuse``), which is
what aperture's ``--override-material diffuse`` renders.

The reference is rendered as two independent halves (seeds 0 and 1, ``spp/2`` each); their
average is written, and ``rmse(half0, half1) / 2`` -- the noise RMSE of that average -- is
recorded in the manifest as ``reference_noise_rmse`` so the test can account for it.

Usage: ``python make_reference.py [--spp N] [--only NAME ...] [--gltf-only]`` (see README.md).
"""

from __future__ import annotations

import argparse
import base64
import json
import math
import os
import struct
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
OUT = os.path.join(REPO, "assets", "reference")

# aperture's candela per W/sr (SPEC section 4: Blender's importer converts cd / 683).
LUMENS_PER_WATT = 683.0

WIDTH, HEIGHT = 160, 120
MAX_BOUNCES = 3
DEFAULT_SPP = 8192
# Seeds of the two Mitsuba halves whose average is the reference.
REFERENCE_SEEDS = [0, 1]

# --------------------------------------------------------------------------------------------
# Small linear algebra (row-major 4x4 lists; glTF wants column-major, converted on output).


def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def translate(x, y, z):
    return [[1, 0, 0, x], [0, 1, 0, y], [0, 0, 1, z], [0, 0, 0, 1]]


def scale(x, y, z):
    return [[x, 0, 0, 0], [0, y, 0, 0], [0, 0, z, 0], [0, 0, 0, 1]]


def rot_x(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return [[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]]


def rot_y(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return [[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1]]


def trs(t=(0, 0, 0), ry=0.0, rx=0.0, s=(1, 1, 1)):
    """translate * rot_y * rot_x * scale."""
    return mat_mul(mat_mul(mat_mul(translate(*t), rot_y(ry)), rot_x(rx)), scale(*s))


def normalize(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def gltf_camera_matrix(eye, target, up):
    """Camera-to-world of a glTF camera (looks down local -Z, +X right, +Y up)."""
    fwd = normalize([t - e for t, e in zip(target, eye)])
    right = normalize(cross(fwd, up))
    cup = cross(right, fwd)
    back = [-c for c in fwd]
    return [
        [right[0], cup[0], back[0], eye[0]],
        [right[1], cup[1], back[1], eye[1]],
        [right[2], cup[2], back[2], eye[2]],
        [0, 0, 0, 1],
    ]


def column_major(m):
    return [float(m[r][c]) for c in range(4) for r in range(4)]


# --------------------------------------------------------------------------------------------
# The two primitive shapes, exactly as Mitsuba's built-in `rectangle` and `cube` define them:
# the rectangle is [-1,1]^2 in z = 0 facing +Z, the cube is [-1,1]^3 with outward faces.

QUAD_POS = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
QUAD_NRM = [(0, 0, 1)] * 4
QUAD_IDX = [0, 1, 2, 0, 2, 3]


def cube_mesh():
    pos, nrm, idx = [], [], []
    for axis in range(3):
        for sign in (-1, 1):
            n = [0, 0, 0]
            n[axis] = sign
            # Two tangent axes, ordered so (u x v) = n (counter-clockwise seen from outside).
            u_ax, v_ax = (axis + 1) % 3, (axis + 2) % 3
            base = len(pos)
            for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0, 0, 0]
                p[axis] = sign
                p[u_ax] = su * sign
                p[v_ax] = sv
                pos.append(tuple(p))
                nrm.append(tuple(n))
            idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pos, nrm, idx


CUBE_POS, CUBE_NRM, CUBE_IDX = cube_mesh()


def check_winding(pos, idx, nrm):
    for t in range(0, len(idx), 3):
        a, b, c = (pos[i] for i in idx[t : t + 3])
        n = cross([b[k] - a[k] for k in range(3)], [c[k] - a[k] for k in range(3)])
        assert sum(n[k] * nrm[idx[t]][k] for k in range(3)) > 0, "winding disagrees with normal"


check_winding(QUAD_POS, QUAD_IDX, QUAD_NRM)
check_winding(CUBE_POS, CUBE_IDX, CUBE_NRM)

# --------------------------------------------------------------------------------------------
# The scenes.

EYE = (0.6, 1.6, 6.5)
TARGET = (0.0, 0.6, 0.0)
UP = (0.0, 1.0, 0.0)
YFOV_DEG = 40.0
FOCUS = math.dist(EYE, TARGET)  # distance to the target, a plane through the green box
APERTURE_RADIUS = 0.15
ENV = (0.6, 0.7, 0.9)


def base_objects():
    """Ground, and boxes at several depths; deliberately asymmetric (red near left, blue far
    right, a leaning tall box on the right) so a mirrored image cannot pass."""
    return [
        # name, shape, world matrix, diffuse albedo
        ("ground", "quad", trs(rx=-90, s=(10, 10, 1)), (0.7, 0.7, 0.7)),
        ("red_near", "cube", trs((-1.4, 0.4, 2.6), ry=25, s=(0.4, 0.4, 0.4)), (0.8, 0.15, 0.1)),
        ("green_mid", "cube", trs((0.0, 0.6, 0.0), ry=-15, s=(0.6, 0.6, 0.6)), (0.15, 0.7, 0.2)),
        ("blue_far", "cube", trs((2.2, 0.9, -4.5), ry=40, s=(0.9, 0.9, 0.9)), (0.1, 0.25, 0.8)),
        ("white_tall", "cube", trs((1.6, 1.2, 1.2), ry=10, rx=8, s=(0.25, 1.2, 0.25)), (0.8, 0.8, 0.75)),
        ("yellow_back_left", "cube", trs((-3.0, 0.5, -2.5), ry=-30, s=(0.5, 0.5, 1.0)), (0.8, 0.7, 0.1)),
    ]


def scene_defs():
    point = {"kind": "point", "position": (2.5, 4.0, 3.0), "intensity": (30.0, 27.0, 24.0)}
    area = {
        "kind": "area",
        # Faces down (-Y): the quad's +Z normal rotated by +90 deg about X.
        "matrix": trs((-0.5, 3.6, 1.0), rx=90, s=(0.8, 0.8, 1)),
        "radiance": (12.0, 11.0, 9.5),
    }
    dof = {"aperture_radius": APERTURE_RADIUS, "focus_distance": FOCUS}
    return {
        "dof_point": {"light": point, "dof": dof, "env": None},
        "pinhole_point": {"light": point, "dof": None, "env": None},
        "dof_area": {"light": area, "dof": dof, "env": None},
        "dof_env": {"light": None, "dof": dof, "env": ENV},
        # Glass (issue 14): a refractive sphere, smooth and rough, and an absorbing block, on a
        # textured ground under the area light, through a pinhole. Rendered with their own
        # materials, not the diffuse override.
        "glass_smooth": {"light": area, "dof": None, "env": None, "glass": GLASS_SPHERE},
        "glass_rough": {"light": area, "dof": None, "env": None,
                        "glass": {**GLASS_SPHERE, "roughness": 0.3}},
        "glass_absorbing": {"light": area, "dof": None, "env": None, "glass": GLASS_BLOCK},
    }


# The glass scenes' objects. The sphere is a UV sphere mesh (96 x 48, smooth normals) given to
# both renderers; the block is the cube, 2 cm above the ground (faces that coincide with the
# ground would be a tie each renderer breaks its own way). Attenuation:
# sigma_a = -ln(colour) / distance.
GLASS_SPHERE = {"shape": "sphere", "matrix": trs((0.0, 0.62, 0.0), s=(0.62, 0.62, 0.62)), "ior": 1.5,
                "roughness": 0.0, "attenuation": None}
GLASS_BLOCK = {"shape": "cube", "matrix": trs((0.0, 0.57, 0.0), ry=-25, s=(0.55, 0.55, 0.55)), "ior": 1.5,
               "roughness": 0.0, "attenuation": {"color": (0.35, 0.65, 0.9), "distance": 0.8}}
# Bounces for the glass scenes (refraction needs more than the diffuse scenes' 3).
GLASS_MAX_BOUNCES = 8
# The ground's checker texture: 2 x 2 texels (linear RGB), repeated 8 times over the ground.
CHECKER = [(0.8, 0.8, 0.8), (0.2, 0.3, 0.45)]
CHECKER_REPEAT = 8.0


def sigma_a(att):
    """KHR_materials_volume's absorption: -ln(attenuationColor) / attenuationDistance."""
    return [-math.log(c) / att["distance"] for c in att["color"]]


def max_bounces(sdef):
    return GLASS_MAX_BOUNCES if sdef.get("glass") else MAX_BOUNCES


def linear_to_srgb8(c):
    v = 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055
    return max(0, min(255, round(v * 255)))


def png_rgb8(width, height, rows):
    """An 8-bit RGB PNG file's bytes from `height` rows of `3 * width` bytes, top row first."""
    import zlib

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + bytes(r) for r in rows)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def checker_png():
    """The 2 x 2 checker as an sRGB PNG (texel (0,0) top-left: colours 0 1 / 1 0)."""
    rows = [b"".join(bytes(linear_to_srgb8(c) for c in CHECKER[(x + y) % 2]) for x in range(2))
            for y in range(2)]
    return png_rgb8(2, 2, rows)


def uv_sphere(segments=96, rings=48):
    """Unit UV sphere: smooth normals, counter-clockwise seen from outside, no degenerate
    triangles at the poles (bench_mitsuba.py's)."""
    pos, nrm, idx = [], [], []
    for j in range(rings + 1):
        theta = math.pi * j / rings
        for i in range(segments + 1):
            phi = 2.0 * math.pi * i / segments
            p = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
            pos.append(p)
            nrm.append(p)
    row = segments + 1
    for j in range(rings):
        for i in range(segments):
            a, b = j * row + i, j * row + i + 1
            c, d = (j + 1) * row + i, (j + 1) * row + i + 1
            if j != 0:
                idx += [a, c, b]
            if j != rings - 1:
                idx += [b, c, d]
    return pos, nrm, idx


SPHERE_POS, SPHERE_NRM, SPHERE_IDX = uv_sphere()
check_winding(SPHERE_POS, SPHERE_IDX, SPHERE_NRM)


def write_ply(path, pos, nrm, idx, uv=None):
    """Binary PLY with per-vertex normals, which Mitsuba's `ply` shape interpolates as the glTF
    NORMAL attribute is, and optionally texture coordinates `uv` (glTF's TEXCOORD_0, written
    unchanged as `u`, `v`). Sequences or NumPy arrays."""
    pos, nrm = np.asarray(pos, np.float32).reshape(-1, 3), np.asarray(nrm, np.float32).reshape(-1, 3)
    fields = [("p", "<f4", 3), ("n", "<f4", 3)] + ([("uv", "<f4", 2)] if uv is not None else [])
    verts = np.empty(len(pos), dtype=[(n, t, (k,)) for n, t, k in fields])
    verts["p"], verts["n"] = pos, nrm
    if uv is not None:
        verts["uv"] = np.asarray(uv, np.float32).reshape(-1, 2)
    faces = np.empty(len(idx) // 3, dtype=[("k", "u1"), ("i", "<i4", (3,))])
    faces["k"], faces["i"] = 3, np.asarray(idx, np.int64).reshape(-1, 3)
    with open(path, "wb") as f:
        f.write((
            "ply\nformat binary_little_endian 1.0\n"
            f"element vertex {len(pos)}\n"
            "property float x\nproperty float y\nproperty float z\n"
            "property float nx\nproperty float ny\nproperty float nz\n"
            + ("property float u\nproperty float v\n" if uv is not None else "")
            + f"element face {len(idx) // 3}\n"
            "property list uchar int vertex_indices\nend_header\n"
        ).encode())
        f.write(verts.tobytes())
        f.write(faces.tobytes())


def glass_objects():
    """The glass scenes' ground and boxes (base_objects without the green box the glass
    replaces)."""
    return [o for o in base_objects() if o[0] != "green_mid"]


# --------------------------------------------------------------------------------------------
# glTF writer.


def pack_f32(vals):
    return struct.pack("<%df" % len(vals), *vals)


def pack_u16(vals):
    return struct.pack("<%dH" % len(vals), *vals)


def gltf_buffers():
    """One glTF binary buffer with its views and accessors, and `add(data, target, comp, count,
    typ, minmax=None)` that appends 4-byte-aligned data and returns the new accessor's index
    (shared with bench_mitsuba.py)."""
    buf = bytearray()
    views, accessors = [], []

    def add(data, target, comp, count, typ, minmax=None):
        while len(buf) % 4:
            buf.append(0)
        views.append({"buffer": 0, "byteOffset": len(buf), "byteLength": len(data), "target": target})
        buf.extend(data)
        acc = {"bufferView": len(views) - 1, "componentType": comp, "count": count, "type": typ}
        if minmax:
            acc["min"], acc["max"] = minmax
        accessors.append(acc)
        return len(accessors) - 1

    return buf, views, accessors, add


def gltf_buffer_entries(buf, views, accessors):
    """The document's `accessors`, `bufferViews` and `buffers` (one embedded data: buffer)."""
    return {
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{
            "byteLength": len(buf),
            "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(buf)).decode(),
        }],
    }


def write_json(path, doc):
    """Writes a glTF document as the committed files are written (indent 1, final newline)."""
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def gltf_diffuse(name, rgb):
    """A glTF material that is Lambertian even without --override-material diffuse:
    metallicFactor 0 and KHR_materials_specular factor 0."""
    return {
        "name": name,
        "pbrMetallicRoughness": {"baseColorFactor": [*rgb, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
        "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}},
    }


def gltf_emissive(name, radiance):
    """A black emitter of `radiance` (emissiveFactor x KHR_materials_emissive_strength; no 683)."""
    strength = max(radiance)
    return {
        "name": name,
        "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0.0, "roughnessFactor": 1.0},
        "emissiveFactor": [c / strength for c in radiance],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": strength}},
    }


def gltf_point_light(name, intensity):
    """A KHR_lights_punctual point light of `intensity` W/sr: candela = 683 x W/sr (SPEC section 4)."""
    peak = max(intensity)
    return {"name": name, "type": "point", "color": [c / peak for c in intensity],
            "intensity": peak * LUMENS_PER_WATT}


def write_gltf(name, sdef, path):
    buf, views, accessors, add = gltf_buffers()

    def add_shape(pos, nrm, idx):
        flat_p = [c for p in pos for c in p]
        mins = [min(p[k] for p in pos) for k in range(3)]
        maxs = [max(p[k] for p in pos) for k in range(3)]
        p = add(pack_f32(flat_p), 34962, 5126, len(pos), "VEC3", (mins, maxs))
        n = add(pack_f32([c for v in nrm for c in v]), 34962, 5126, len(nrm), "VEC3")
        i = add(pack_u16(idx), 34963, 5123, len(idx), "SCALAR")
        return {"POSITION": p, "NORMAL": n}, i

    shapes = {"quad": add_shape(QUAD_POS, QUAD_NRM, QUAD_IDX), "cube": add_shape(CUBE_POS, CUBE_NRM, CUBE_IDX)}
    glass = sdef.get("glass")
    if glass and glass["shape"] == "sphere":
        shapes["sphere"] = add_shape(SPHERE_POS, SPHERE_NRM, SPHERE_IDX)
    if glass:
        # The ground's texture coordinates: Mitsuba's rectangle's (u along its local x, v
        # along its local y), repeated. Mitsuba's bitmap puts v = 0 at the image's first row,
        # as glTF does, so they carry over unchanged (checked: flipping v makes the test fail).
        uv = [(CHECKER_REPEAT * (p[0] + 1) / 2, CHECKER_REPEAT * (p[1] + 1) / 2) for p in QUAD_POS]
        t = add(pack_f32([c for q in uv for c in q]), 34962, 5126, 4, "VEC2")
        shapes["ground"] = ({**shapes["quad"][0], "TEXCOORD_0": t}, shapes["quad"][1])

    materials, meshes, nodes = [], [], []

    def add_object(oname, shape, matrix, material):
        materials.append(material)
        attrs, ind = shapes[shape]
        meshes.append({"name": oname, "primitives": [{"attributes": attrs, "indices": ind, "material": len(materials) - 1}]})
        nodes.append({"name": oname, "mesh": len(meshes) - 1, "matrix": column_major(matrix)})

    diffuse = gltf_diffuse

    ext_used = ["KHR_materials_specular"]
    extensions = {}
    extra = {}
    if glass:
        for oname, shape, matrix, albedo in glass_objects():
            if oname == "ground":
                mat = diffuse(oname, (1.0, 1.0, 1.0))
                mat["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
                add_object(oname, "ground", matrix, mat)
            else:
                add_object(oname, shape, matrix, diffuse(oname, albedo))
        png = checker_png()
        extra = {
            "images": [{"name": "checker", "uri": "data:image/png;base64," + base64.b64encode(png).decode()}],
            # NEAREST (9728) magnification, REPEAT wrap: exactly Mitsuba's nearest lookup.
            "samplers": [{"magFilter": 9728, "minFilter": 9728, "wrapS": 10497, "wrapT": 10497}],
            "textures": [{"sampler": 0, "source": 0}],
        }
        gmat = {
            "name": "glass",
            "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0.0,
                                      "roughnessFactor": glass["roughness"]},
            "extensions": {
                "KHR_materials_transmission": {"transmissionFactor": 1.0},
                "KHR_materials_ior": {"ior": glass["ior"]},
                "KHR_materials_volume": {"thicknessFactor": 1.0},
            },
        }
        if glass["attenuation"]:
            att = glass["attenuation"]
            gmat["extensions"]["KHR_materials_volume"].update(
                {"attenuationColor": list(att["color"]), "attenuationDistance": att["distance"]})
        add_object("glass", glass["shape"], glass["matrix"], gmat)
        ext_used += ["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"]
    else:
        for oname, shape, matrix, albedo in base_objects():
            add_object(oname, shape, matrix, diffuse(oname, albedo))
    light = sdef["light"]
    if light and light["kind"] == "area":
        add_object("area_light", "quad", light["matrix"], gltf_emissive("area_light", light["radiance"]))
        ext_used.append("KHR_materials_emissive_strength")
    elif light and light["kind"] == "point":
        extensions["KHR_lights_punctual"] = {"lights": [gltf_point_light("point", light["intensity"])]}
        nodes.append({
            "name": "point_light",
            "translation": list(light["position"]),
            "extensions": {"KHR_lights_punctual": {"light": 0}},
        })
        ext_used.append("KHR_lights_punctual")

    cam = {
        "name": "camera",
        "type": "perspective",
        "perspective": {"yfov": math.radians(YFOV_DEG), "aspectRatio": WIDTH / HEIGHT, "znear": 0.01},
    }
    if sdef["dof"]:
        cam["extras"] = dict(sdef["dof"])
    nodes.append({"name": "camera", "camera": 0, "matrix": column_major(gltf_camera_matrix(EYE, TARGET, UP))})

    doc = {
        "asset": {"version": "2.0", "generator": "aperture tools/reference/make_reference.py"},
        "extensionsUsed": ext_used,
        "scene": 0,
        "scenes": [{"name": name, "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [cam],
        **extra,
        **gltf_buffer_entries(buf, views, accessors),
    }
    if extensions:
        doc["extensions"] = extensions
    write_json(path, doc)


# --------------------------------------------------------------------------------------------
# Mitsuba scene and render.


def mitsuba_sensor(mi, look, yfov_deg, dof, size, spp, seed):
    """Mitsuba's camera for a glTF camera at `look` = (eye, target, up) with vertical field of
    view `yfov_deg`, thin lens `dof` ({aperture_radius, focus_distance}) or pinhole (None),
    `size` = (width, height), an `independent` sampler and a 1-pixel box filter.
    Mitsuba's camera frame looks down +Z with +X left; look_at with the same eye, target and up
    as the glTF camera therefore gives the same (unmirrored) image."""
    eye, target, up = look
    sensor = {
        "type": "thinlens" if dof else "perspective",
        "fov": yfov_deg,
        "fov_axis": "y",
        "to_world": mi.ScalarTransform4f().look_at(origin=list(eye), target=list(target), up=list(up)),
        "near_clip": 0.01,
        "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
        "film": {
            "type": "hdrfilm",
            "width": size[0],
            "height": size[1],
            "pixel_format": "rgb",
            "component_format": "float32",
            "rfilter": {"type": "box"},
        },
    }
    if dof:
        sensor["aperture_radius"] = dof["aperture_radius"]
        sensor["focus_distance"] = dof["focus_distance"]
    return sensor


def mitsuba_scene(mi, sdef, spp, seed, tmp=None):
    T = mi.ScalarTransform4f

    def twosided(rgb):
        return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(rgb)}}}

    sensor = mitsuba_sensor(mi, (EYE, TARGET, UP), YFOV_DEG, sdef["dof"], (WIDTH, HEIGHT), spp, seed)

    glass = sdef.get("glass")
    scene = {
        "type": "scene",
        # volpath for the absorbing medium (with no medium it is the path integrator).
        "integrator": {"type": "volpath" if glass else "path", "max_depth": max_bounces(sdef) + 2,
                       "hide_emitters": False},
        "sensor": sensor,
    }
    kinds = {"quad": "rectangle", "cube": "cube"}
    for oname, shape, matrix, albedo in (glass_objects() if glass else base_objects()):
        scene[oname] = {"type": kinds[shape], "to_world": T(matrix), "bsdf": twosided(albedo)}
    if glass:
        png = os.path.join(tmp, "checker.png")
        with open(png, "wb") as f:
            f.write(checker_png())
        scene["ground"]["bsdf"] = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
            "type": "bitmap", "filename": png, "filter_type": "nearest", "wrap_mode": "repeat",
            "to_uv": mi.ScalarTransform3f().scale([CHECKER_REPEAT, CHECKER_REPEAT])}}}
        if glass["roughness"] > 0:
            bsdf = {"type": "roughdielectric", "distribution": "ggx", "sample_visible": True,
                    "alpha": glass["roughness"] ** 2, "int_ior": glass["ior"], "ext_ior": 1.0}
        else:
            bsdf = {"type": "dielectric", "int_ior": glass["ior"], "ext_ior": 1.0}
        obj = {"bsdf": bsdf, "to_world": T(glass["matrix"])}
        if glass["shape"] == "sphere":
            ply = os.path.join(tmp, "sphere.ply")
            write_ply(ply, SPHERE_POS, SPHERE_NRM, SPHERE_IDX)
            obj.update({"type": "ply", "filename": ply})
        else:
            obj["type"] = "cube"
        if glass["attenuation"]:
            # sigma_t as an RGB in [0, 1] times `scale` (Mitsuba's RGB values are bounded).
            s = sigma_a(glass["attenuation"])
            peak = max(s)
            obj["interior"] = {"type": "homogeneous", "albedo": {"type": "rgb", "value": [0.0, 0.0, 0.0]},
                               "sigma_t": {"type": "rgb", "value": [c / peak for c in s]}, "scale": peak}
        scene["glass"] = obj
    light = sdef["light"]
    if light and light["kind"] == "point":
        scene["light"] = {
            "type": "point",
            "position": list(light["position"]),
            "intensity": {"type": "rgb", "value": list(light["intensity"])},
        }
    elif light and light["kind"] == "area":
        # Mitsuba's area light emits on the front (+Z) side only; aperture's emissive surfaces
        # emit on both. The quad faces down and nothing lies above it, so its back side lights
        # nothing and the camera (below it) never sees it.
        scene["light"] = {
            "type": "rectangle",
            "to_world": T(light["matrix"]),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}},
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": list(light["radiance"])}},
        }
    if sdef["env"]:
        scene["env"] = {"type": "constant", "radiance": {"type": "rgb", "value": list(sdef["env"])}}
    return scene


def render_mitsuba(mi, sdef, spp, seed):
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        scene = mi.load_dict(mitsuba_scene(mi, sdef, spp, seed, tmp))
        img = mi.render(scene, spp=spp, seed=seed)
        return np.array(img, dtype=np.float64)[:, :, :3]


# What aperture's test does with each scene: two renders at TEST_SPP, one per seed.
TEST_SPP = 64
TEST_SEEDS = [1, 2]


# Manifest fields that only a render gives (kept by --manifest-only).
MEASURED = ["reference_spp", "reference_noise_rmse", "reference_mean_rgb", "reference_seconds"]

GENERATOR = "tools/reference/make_reference.py"
COMMON = {
    "integrator": "path",
    "sampler": "independent",
    "filter": "box (1 pixel)",
}


def cli_args(name, sdef):
    """The `aperture` arguments that render the image the test compares (add `--seed S` and
    `--output FILE`)."""
    args = [
        "render", f"assets/reference/{name}.gltf",
        "--width", str(WIDTH), "--height", str(HEIGHT),
        "--spp", str(TEST_SPP),
        "--max-bounces", str(max_bounces(sdef)),
        "--filter", "box",
    ]
    glass = sdef.get("glass")
    if not glass:
        args += ["--override-material", "diffuse"]
    elif glass["roughness"] > 0:
        # Mitsuba's rough dielectric is single-scattering: compare the same model.
        args += ["--no-energy-compensation"]
    if sdef["env"]:
        args += ["--env", ",".join(repr(c) for c in sdef["env"])]
    return args


def static_entry(name, sdef):
    """The manifest fields that follow from the scene definition alone."""
    return {
        "name": name,
        "gltf": f"{name}.gltf",
        "exr": f"{name}.exr",
        "width": WIDTH,
        "height": HEIGHT,
        "max_bounces": max_bounces(sdef),
        "mitsuba_max_depth": max_bounces(sdef) + 2,
        # The diffuse override (two-sided Lambert of the base colour), or the scene's own
        # materials; whether aperture's energy compensation is on (off where Mitsuba's model
        # is single scattering).
        "material_override": None if sdef.get("glass") else "diffuse",
        "energy_compensation": not (sdef.get("glass") and sdef["glass"]["roughness"] > 0),
        "env": list(sdef["env"]) if sdef["env"] else None,
        "aperture_radius": sdef["dof"]["aperture_radius"] if sdef["dof"] else 0.0,
        "focus_distance": sdef["dof"]["focus_distance"] if sdef["dof"] else None,
        "reference_seeds": REFERENCE_SEEDS,
        "test_spp": TEST_SPP,
        "test_seeds": TEST_SEEDS,
        "cli_args": cli_args(name, sdef),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", type=int, default=DEFAULT_SPP, help="reference samples per pixel (two halves)")
    ap.add_argument("--only", nargs="*", help="scene names to (re)render; default all")
    ap.add_argument("--gltf-only", action="store_true", help="write the glTF files and stop")
    ap.add_argument("--manifest-only", action="store_true",
                    help="write the glTF files and refresh the manifest's scene-definition fields, keeping the measured ones; no render")
    ap.add_argument("--variant", default="scalar_rgb")
    ap.add_argument("--threads", type=int, default=1, help="Mitsuba worker threads (default 1)")
    args = ap.parse_args()
    if args.spp < 2 or args.spp % 2:
        sys.exit("--spp must be even (two halves)")

    os.makedirs(OUT, exist_ok=True)
    defs = scene_defs()
    names = args.only or list(defs)
    for name in names:
        write_gltf(name, defs[name], os.path.join(OUT, f"{name}.gltf"))
        print(f"wrote assets/reference/{name}.gltf")
    if args.gltf_only:
        return

    manifest_path = os.path.join(OUT, "manifest.json")
    manifest = {"scenes": []}
    if os.path.exists(manifest_path):
        with open(manifest_path) as f:
            manifest = json.load(f)
    entries = {e["name"]: e for e in manifest.get("scenes", [])}

    if args.manifest_only:
        for name in names:
            old = entries.get(name, {})
            kept = {k: old[k] for k in MEASURED if k in old}
            entries[name] = {**static_entry(name, defs[name]), **kept}
        manifest = {
            "generator": GENERATOR,
            "mitsuba": manifest.get("mitsuba"),
            **COMMON,
            "scenes": [entries[n] for n in defs if n in entries],
        }
        with open(manifest_path, "w") as f:
            json.dump(manifest, f, indent=2)
            f.write("\n")
        return

    import drjit as dr
    import mitsuba as mi

    mi.set_variant(args.variant)
    dr.set_thread_count(args.threads)

    for name in names:
        sdef = defs[name]
        t0 = time.time()
        half = args.spp // 2
        a = render_mitsuba(mi, sdef, half, REFERENCE_SEEDS[0])
        b = render_mitsuba(mi, sdef, half, REFERENCE_SEEDS[1])
        secs = time.time() - t0
        avg = 0.5 * (a + b)
        # Noise RMSE of the average of two independent halves: rmse(a, b) = sqrt(2) sigma_half
        # and sigma_avg = sigma_half / sqrt(2), so sigma_avg = rmse(a, b) / 2.
        ref_noise = float(np.sqrt(np.mean((a - b) ** 2)) / 2.0)
        # Mitsuba's EXR writer waits on its thread pool and deadlocks with one thread.
        dr.set_thread_count(max(2, args.threads))
        mi.Bitmap(avg.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB).write(
            os.path.join(OUT, f"{name}.exr")
        )
        dr.set_thread_count(args.threads)
        entries[name] = {
            **static_entry(name, sdef),
            "reference_spp": args.spp,
            "reference_noise_rmse": ref_noise,
            "reference_mean_rgb": [float(c) for c in avg.reshape(-1, 3).mean(axis=0)],
            "reference_seconds": round(secs, 1),
        }
        print(f"{name}: {args.spp} spp in {secs:.1f} s, reference noise rmse {ref_noise:.3g}, "
              f"mean {entries[name]['reference_mean_rgb']}", flush=True)

    manifest = {
        "generator": GENERATOR,
        "mitsuba": f"{mi.__version__} {args.variant}",
        **COMMON,
        "scenes": [entries[n] for n in defs if n in entries],
    }
    with open(manifest_path, "w") as f:
        json.dump(manifest, f, indent=2)
        f.write("\n")


if __name__ == "__main__":
    main()
