# SPDX-License-Identifier: MIT OR Apache-2.0
"""Acceptance test for the Blender add-on the `aperture_gltf_dof` add-on (issue 8).

Run it with Blender as a Python module (bpy 5.0.1, Python 3.11); `run_test.sh` beside this file
sets that up. It is never part of the Rust build.

    python test_export.py [--aperture target/release/aperture] [--out DIR] [--spp 512]

What it does:
  1. Installs the add-on as a user would (Preferences > Add-ons > Install from Disk, then enable),
     into a throw-away user-scripts folder.
  2. Builds a small scene: diffuse spheres at several depths on a ground plate, a sun, a small
     emissive "bulb" far behind the focal plane (its bokeh is the aperture's shape), and a camera
     with depth of field on (85 mm, f/1.4, 6 blades, focus object = the middle sphere).
  3. (a) Exports it with the official glTF exporter and checks the camera extras in the written
     JSON. A second export, with more cameras, checks the rules: custom properties win (with the
     exporter's "Custom Properties" option on and off), DOF off still writes use_dof false, an
     orthographic camera gets Cycles' radius, a bone subtarget warns, a focus object that is not
     exported becomes a focus distance, and the native values of a camera with DOF off are
     still written.
     (b) `aperture info --json` on the export resolves the lens radius lens/(2 fstop) (mm to m) and
     the focus object's depth along the view axis.
     (c) `aperture render --override-material diffuse` of the export matches a Cycles render of the
     same scene within noise: Cycles has no adaptive sampling, no denoising, no clamping, a 1-pixel
     box filter and plain diffuse BSDFs. The test compares RMSE and mean ratio, and checks that
     the bulb's bokeh is hexagonal and has the same orientation and size in both renders.

Units: a sun of S W/m² in Blender is exported as S * 683 lux (the exporter's default "Standard"
lighting mode). aperture reads that back as S W/m² (SPEC §4), and Cycles' sun strength is
irradiance in W/m². So the test uses a sun with angle 0 (a delta light, like glTF's). An emission
strength is a radiance in both renderers; the exporter writes it as emissiveFactor ×
KHR_materials_emissive_strength, with no 683.

`--cycles-as-aperture` checks (c)'s comparison itself, with a third Cycles seed in aperture's place.
(b) and (c) run when the `aperture` binary supports them. Otherwise they are reported as SKIP,
with the reason, or as FAIL when --require-all is given. The last line is "N passed, N failed, N
skipped". The exit status is non-zero when anything failed.
"""

import argparse
import json
import logging
import math
import os
import shutil
import subprocess
import sys
import tempfile

from addon_zip import addon_zip
import cycles_settings
from checks import check, record, summary

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
ADDON = "aperture_gltf_dof"

ARGS = None
WORK = None

# Scene constants (Blender: Z up, metres; the camera looks along +Y).
LENS, FSTOP, BLADES = 85.0, 1.4, 6
WIDTH, HEIGHT = 160, 90
CAM_Z = 0.05
SPHERE_R = 0.03
SPHERES = [  # name, depth along +Y, image x in [-1, 1], colour
    ("SphereNear", 0.35, 0.55, (0.8, 0.15, 0.1)),
    ("SphereMid", 0.5, 0.15, (0.75, 0.75, 0.7)),
    ("SphereFar", 0.7, 0.6, (0.1, 0.3, 0.8)),
    ("SphereBack", 0.9, 0.15, (0.2, 0.7, 0.2)),
]
FOCUS = "SphereMid"
BULB = ("Bulb", 6.0, -0.5, 0.4, 0.08, 20.0)  # name, depth, image x, image y, radius, emission


# --------------------------------------------------------------------------------------------
# Blender side


def import_bpy(user_scripts):
    # Blender reads BLENDER_USER_SCRIPTS when the module starts: set it before importing bpy so
    # the add-on is installed into a throw-away folder, not the user's own configuration.
    os.environ["BLENDER_USER_SCRIPTS"] = user_scripts
    os.environ["BLENDER_USER_CONFIG"] = os.path.join(user_scripts, "config")
    global bpy, Vector
    import bpy  # noqa: F401
    from mathutils import Vector  # noqa: F401


def install_addon():
    addon_file = addon_zip(tempfile.mkdtemp(prefix="aperture-addon-", dir=WORK))
    bpy.ops.preferences.addon_install(filepath=addon_file, overwrite=True)
    bpy.ops.preferences.addon_enable(module=ADDON)
    enabled = ADDON in bpy.context.preferences.addons.keys()
    check("install", enabled, f"add-on installed from {addon_file} and enabled")
    if not enabled:
        raise SystemExit(1)


def tan_half():
    """(tan of half the horizontal, vertical field of view) for LENS on a 36 mm AUTO sensor."""
    tx = 18.0 / LENS
    return tx, tx * HEIGHT / WIDTH


def at_image(nx, ny, depth):
    tx, ty = tan_half()
    return Vector((nx * tx * depth, depth, CAM_Z + ny * ty * depth))


def principled(name, colour, emission=0.0):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Roughness"].default_value = 1.0
    if emission > 0.0:
        bsdf.inputs["Base Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        bsdf.inputs["Emission Color"].default_value = (*colour, 1.0)
        bsdf.inputs["Emission Strength"].default_value = emission
    mat["test_colour"] = list(colour)
    mat["test_emission"] = emission
    return mat


def add_sphere(name, location, radius, mat):
    bpy.ops.mesh.primitive_uv_sphere_add(
        segments=48, ring_count=24, radius=radius, location=location
    )
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    bpy.ops.object.shade_smooth()
    obj.data.materials.append(mat)
    return obj


def add_camera(name, location, rotation=(math.pi / 2, 0.0, 0.0)):
    data = bpy.data.cameras.new(name)
    obj = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = location
    obj.rotation_euler = rotation
    return obj


def build_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.render.resolution_percentage = 100

    for name, depth, nx, colour in SPHERES:
        p = at_image(nx, 0.0, depth)
        add_sphere(name, (p.x, depth, 0.0), SPHERE_R, principled(name, colour))

    # The ground ends 1 m away: its blurred far edge stays clear of the bulb's bokeh.
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0.0, 0.45, -SPHERE_R))
    ground = bpy.context.active_object
    ground.name = ground.data.name = "Ground"
    ground.scale = (1.2, 1.1, 1.0)
    ground.data.materials.append(principled("Ground", (0.5, 0.5, 0.5)))

    name, depth, nx, ny, radius, strength = BULB
    add_sphere(name, at_image(nx, ny, depth), radius, principled(name, (1.0, 0.9, 0.8), strength))

    sun_data = bpy.data.lights.new("Sun", "SUN")
    sun_data.energy = 3.0  # W/m² (exported as 3 * 683 lux)
    sun_data.angle = 0.0  # a delta light, as glTF's directional light
    sun = bpy.data.objects.new("Sun", sun_data)
    scene.collection.objects.link(sun)
    sun.rotation_euler = (math.radians(40.0), 0.0, math.radians(-35.0))

    cam = add_camera("Camera", (0.0, 0.0, CAM_Z))
    cam.data.lens = LENS
    cam.data.sensor_width = 36.0
    cam.data.sensor_fit = "AUTO"
    cam.data.clip_start = 0.01
    cam.data.dof.use_dof = True
    cam.data.dof.aperture_fstop = FSTOP
    cam.data.dof.aperture_blades = BLADES
    cam.data.dof.aperture_rotation = 0.0
    cam.data.dof.focus_object = bpy.data.objects[FOCUS]
    cam.data.dof.focus_distance = 3.0  # ignored by Cycles while a focus object is set
    scene.camera = cam
    return cam


def add_rule_cameras():
    """Cameras for the rules of the add-on; only in the second export."""
    made = {}
    off = add_camera("CamOff", (0.3, -0.5, 0.1))
    off.data.dof.use_dof = False
    off.data.dof.aperture_blades = 5
    made["off"] = off

    custom = add_camera("CamCustom", (0.0, -0.5, 0.1))
    custom.data.dof.use_dof = True
    custom.data.dof.aperture_fstop = 2.0
    custom.data.lens = 35.0
    custom.data["aperture_fstop"] = 8.0  # set by hand: wins over the native 2.0
    custom.data["focus_distance"] = 1.25
    made["custom"] = custom

    ortho = add_camera("CamOrtho", (0.0, -1.0, 0.1))
    ortho.data.type = "ORTHO"
    ortho.data.ortho_scale = 1.5
    ortho.data.dof.use_dof = True
    ortho.data.dof.aperture_fstop = 2.0
    ortho.data.dof.focus_distance = 1.5
    made["ortho"] = ortho

    bpy.ops.object.armature_add(location=(0.4, 1.0, 0.0))
    rig = bpy.context.active_object
    rig.name = "Rig"
    bone = add_camera("CamBone", (-0.3, -0.5, 0.1))
    bone.data.dof.use_dof = True
    bone.data.dof.focus_object = rig
    bone.data.dof.focus_subtarget = "Bone"
    made["bone"] = bone

    lensed = add_camera("CamLens", (0.2, -0.25, 0.1))
    lensed.data.dof.use_dof = True
    lensed.data.aperture_lens.vignetting = 0.3
    lensed.data.aperture_lens.k1 = -0.1
    lensed.data.aperture_lens.p2 = 0.01
    lensed.data.aperture_lens.prescription = os.path.join(REPO, "assets", "lenses",
                                                          "dgauss-50mm.dat")
    lensed.data.aperture_lens.chromatic_lateral = 0.002
    bokeh_dir = os.path.join(WORK, "bokeh-source")
    os.makedirs(bokeh_dir, exist_ok=True)
    lensed.data.aperture_lens.aperture_image = write_grey_png(os.path.join(bokeh_dir, "bokeh.png"))
    made["lens"] = lensed

    hidden_target = bpy.data.objects.new("NotExported", None)
    bpy.context.scene.collection.objects.link(hidden_target)
    hidden_target.location = (0.0, 2.0, 0.1)
    hidden = add_camera("CamHiddenFocus", (0.0, -0.25, 0.1))
    hidden.data.dof.use_dof = True
    hidden.data.dof.focus_object = hidden_target
    made["hidden"] = hidden
    return made


def write_grey_png(path, size=8):
    """A small greyscale PNG (a bright disc on black), written without any imaging library."""
    import struct
    import zlib

    rows = b"".join(
        b"\x00" + bytes(255 if (x - 3.5) ** 2 + (y - 3.5) ** 2 < 9 else 0 for x in range(size))
        for y in range(size))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", size, size, 8, 0, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))
    with open(path, "wb") as f:
        f.write(png)
    return path


class LogCapture(logging.Handler):
    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages = []

    def emit(self, record):
        self.messages.append(record.getMessage())


def export(path, **options):
    capture = LogCapture()
    logging.getLogger("glTFImporter").addHandler(capture)
    try:
        settings = dict(
            filepath=path,
            export_format="GLTF_SEPARATE",
            export_cameras=True,
            export_lights=True,
            export_extras=True,
            export_yup=True,
            export_apply=True,
        )
        settings.update(options)
        bpy.ops.export_scene.gltf(**settings)
    finally:
        logging.getLogger("glTFImporter").removeHandler(capture)
    with open(path) as f:
        return json.load(f), capture.messages


def camera_extras(doc, name):
    for cam in doc.get("cameras", []):
        if cam.get("name") == name:
            return cam.get("extras") or {}
    return None


def view_depth(camera_obj, target_obj):
    m = camera_obj.matrix_world
    view = m.to_quaternion() @ Vector((0.0, 0.0, -1.0))
    return (target_obj.matrix_world.translation - m.translation).dot(view)


def close(a, b, tol=1e-5):
    return isinstance(a, (int, float)) and abs(a - b) <= tol * max(1.0, abs(b))


def test_extras_main(doc):
    ex = camera_extras(doc, "Camera")
    if not check("a.camera-extras-present", ex, f"cameras[Camera].extras = {ex}"):
        return
    expected = {
        "use_dof": True,
        "aperture_fstop": FSTOP,
        "aperture_blades": BLADES,
        "aperture_rotation": 0.0,
        "aperture_ratio": 1.0,
        "lens": LENS,
        "sensor_width": 36.0,
        "sensor_height": 24.0,
        "sensor_fit": "AUTO",
        "focus_object": FOCUS,
        "focus_distance": 3.0,
    }
    bad = {
        k: (ex.get(k), v)
        for k, v in expected.items()
        if not (ex.get(k) == v or (isinstance(v, float) and close(ex.get(k), v)))
    }
    check("a.camera-extras-values", not bad, "all 11 keys as set in Blender" if not bad else f"differ (got, want): {bad}")
    names = [n.get("name") for n in doc.get("nodes", [])]
    check("a.focus-object-is-a-node", FOCUS in names, f"node '{FOCUS}' exported: {FOCUS in names}")
    used = doc.get("extensionsUsed", [])
    lights = doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    lux = lights[0].get("intensity") if lights else None
    check("a.sun-units", lux is not None and close(lux, 3.0 * 683.0, 1e-4) and "KHR_lights_punctual" in used,
          f"sun exported as {lux} lux (3 W/m² × 683)")


def test_motion_extras(doc):
    """The scene's motion-blur settings in ``scenes[i].extras`` (SPEC section 7)."""
    scene = bpy.context.scene
    ex = doc.get("scenes", [{}])[doc.get("scene", 0)].get("extras") or {}
    fps = scene.render.fps / scene.render.fps_base
    expected = {
        "use_motion_blur": bool(scene.render.use_motion_blur),
        "motion_blur_shutter": float(scene.render.motion_blur_shutter),
        "motion_blur_position": scene.render.motion_blur_position,
        "rolling_shutter_type": scene.cycles.rolling_shutter_type,
        "fps": float(fps),
        "frame_current": int(scene.frame_current),
    }
    bad = {
        k: (ex.get(k), v)
        for k, v in expected.items()
        if not (ex.get(k) == v or (isinstance(v, float) and close(ex.get(k), v)))
    }
    check("a.scene-motion-extras", not bad,
          "motion blur settings as set in Blender" if not bad else f"differ (got, want): {bad}")


def test_extras_rules(cams, binary):
    # Export 2: every rule camera, "Custom Properties" on, the hidden focus target not selected.
    for obj in bpy.context.scene.objects:
        obj.select_set(obj.name != "NotExported")
    doc, warnings = export(os.path.join(WORK, "rules.gltf"), use_selection=True)
    ex = {c: camera_extras(doc, cams[c].data.name) or {} for c in cams}

    off = ex["off"]
    check("a.dof-off-exports-false", off.get("use_dof") is False and "lens" in off,
          f"use_dof = {off.get('use_dof')}, lens = {off.get('lens')}")
    check("a.dof-off-keeps-native-values", off.get("aperture_blades") == 5,
          f"aperture_blades = {off.get('aperture_blades')} (5 set)")

    cu = ex["custom"]
    check("a.custom-property-wins", cu.get("aperture_fstop") == 8.0 and cu.get("focus_distance") == 1.25
          and close(cu.get("lens"), 35.0),
          f"aperture_fstop = {cu.get('aperture_fstop')} (native 2.0, custom 8.0), "
          f"focus_distance = {cu.get('focus_distance')} (custom 1.25), lens = {cu.get('lens')}")

    lens = ex["lens"]
    lens_keys = {k: v for k, v in lens.items() if k.startswith(("aperture_vign", "distortion_"))}
    check("a.lens-keys", lens_keys == {"aperture_vignetting": 0.3, "distortion_k1": -0.1,
                                       "distortion_p2": 0.01}
          and not any(k.startswith(("aperture_vign", "distortion_")) for k in off),
          f"CamLens: {lens_keys} (vignetting 0.3, k1 -0.1, p2 0.01 set; the zeros left out); "
          f"CamOff (no lens settings): {[k for k in off if k.startswith('distortion_')]}")
    copied = os.path.join(WORK, "bokeh.png")
    check("a.bokeh-chromatic-keys", lens.get("chromatic_lateral") == 0.002
          and "chromatic_longitudinal" not in lens and lens.get("aperture_image") == "bokeh.png"
          and os.path.isfile(copied) and "aperture_image" not in off
          and not any(k.startswith("chromatic_") for k in off),
          f"CamLens: chromatic_lateral = {lens.get('chromatic_lateral')} (0.002 set), "
          f"aperture_image = {lens.get('aperture_image')!r} (copied beside the export: "
          f"{os.path.isfile(copied)}); CamOff: none of them")

    rows = lens.get("lens_prescription")
    check("a.lens-prescription", isinstance(rows, list) and len(rows) == 11
          and rows[0] == [29.475, 3.76, 1.67, 25.2] and rows[5][0] == 0.0
          and "lens_prescription" not in off,
          f"CamLens: lens_prescription {rows if not isinstance(rows, list) else f'{len(rows)} rows, first {rows[0]}'} "
          f"(the shipped double Gauss inline: 11 rows); CamOff has none")

    orth = ex["ortho"]
    check("a.orthographic", orth.get("use_dof") is True and close(orth.get("aperture_radius"), 0.25)
          and "orthographic" in next(c for c in doc["cameras"] if c["name"] == "CamOrtho"),
          f"orthographic camera: aperture_radius = {orth.get('aperture_radius')} (Cycles: 1/(2·2.0)), "
          f"focus_distance = {orth.get('focus_distance')}")

    bone = ex["bone"]
    warned = [w for w in warnings if "bone" in w.lower() and "CamBone" in w]
    check("a.bone-subtarget-warns", bone.get("focus_object") == "Rig" and warned,
          f"focus_object = {bone.get('focus_object')}, warning: {warned[:1]}")

    hid = ex["hidden"]
    depth = view_depth(cams["hidden"], bpy.data.objects["NotExported"])
    warned = [w for w in warnings if "NotExported" in w]
    check("a.unexported-focus-becomes-distance",
          "focus_object" not in hid and close(hid.get("focus_distance"), depth, 1e-4) and warned,
          f"focus_object dropped, focus_distance = {hid.get('focus_distance')} (depth {depth:.6g}), "
          f"warning: {warned[:1]}")

    test_info_rules(binary, os.path.join(WORK, "rules.gltf"), cams)

    # Export 3: "Custom Properties" off: the hand-set values still win, the rest is native.
    doc3, _ = export(os.path.join(WORK, "rules_noextras.gltf"), use_selection=True, export_extras=False)
    cu3 = camera_extras(doc3, "CamCustom") or {}
    check("a.custom-property-wins-without-custom-properties-export",
          cu3.get("aperture_fstop") == 8.0 and cu3.get("use_dof") is True,
          f"export_extras off: aperture_fstop = {cu3.get('aperture_fstop')}, use_dof = {cu3.get('use_dof')}")


# --------------------------------------------------------------------------------------------
# aperture side


def aperture_supports(binary, sub, flag):
    try:
        out = subprocess.run([binary, sub, "--help"], capture_output=True, text=True, timeout=60)
    except OSError as e:
        return False, str(e)
    text = out.stdout + out.stderr
    return flag in text, text


def info_json(binary, scene_path):
    """`aperture info --json` of a file, or None (with a FAIL recorded) when it fails."""
    out = subprocess.run([binary, "info", "--json", scene_path], capture_output=True, text=True, timeout=300)
    if out.returncode != 0:
        check(f"b.info-json-runs ({os.path.basename(scene_path)})", False,
              f"exit {out.returncode} {out.stderr.strip()[:300]}")
        return None
    return json.loads(out.stdout)


def info_camera(info, name):
    """The `dof` object of camera `name` in `aperture info --json` output ({} when absent)."""
    for camera in info.get("cameras", []):
        if camera.get("name") == name:
            return camera.get("dof") or {}
    return {}


def test_info(binary, scene_path, cam):
    ok, text = aperture_supports(binary, "info", "--json")
    if not ok:
        record("b.info-json", None if not ARGS.require_all else False,
               f"`aperture info --json` not supported by {binary}")
        return
    info = info_json(binary, scene_path)
    if info is None:
        return
    dof = info_camera(info, "Camera")
    want_r = LENS * 0.001 / (2.0 * FSTOP)
    want_f = view_depth(cam, bpy.data.objects[FOCUS])
    check("b.dof-enabled", dof.get("enabled") is True, f"cameras[Camera].dof.enabled = {dof.get('enabled')}")
    check("b.radius", close(dof.get("aperture_radius"), want_r, 1e-5),
          f"aperture_radius = {dof.get('aperture_radius')} m vs lens/(2·fstop) = {LENS} mm/(2·{FSTOP}) "
          f"= {want_r:.7g} m")
    check("b.focus-depth", close(dof.get("focus_distance"), want_f, 1e-5) and dof.get("focus_object") == FOCUS,
          f"focus_distance = {dof.get('focus_distance')} m on {dof.get('focus_object')!r} vs the depth of "
          f"'{FOCUS}' along the view axis in Blender = {want_f:.7g} m")
    check("b.blades", dof.get("blades") == BLADES, f"blades = {dof.get('blades')}")


def test_info_rules(binary, scene_path, cams):
    """`aperture info --json` on the rules export: what the add-on's special cases resolve to."""
    if not os.path.isfile(binary) or not aperture_supports(binary, "info", "--json")[0]:
        return
    info = info_json(binary, scene_path)
    if info is None:
        return
    ortho = info_camera(info, "CamOrtho")
    check("b.orthographic-radius", close(ortho.get("aperture_radius"), 0.25, 1e-5) and ortho.get("enabled"),
          f"CamOrtho: aperture_radius = {ortho.get('aperture_radius')} (Cycles: 1/(2·2.0) = 0.25)")
    custom = info_camera(info, "CamCustom")
    want = 35.0 * 0.001 / (2.0 * 8.0)
    check("b.custom-fstop", close(custom.get("aperture_radius"), want, 1e-5)
          and close(custom.get("focus_distance"), 1.25, 1e-5),
          f"CamCustom: aperture_radius = {custom.get('aperture_radius')} (35 mm/(2·8) = {want}), "
          f"focus_distance = {custom.get('focus_distance')}")
    lens = info_camera(info, "CamLens")
    k = lens.get("distortion") or {}
    check("b.lens-options", close(lens.get("vignetting"), 0.3, 1e-6) and close(k.get("k1"), -0.1, 1e-6)
          and close(k.get("p2"), 0.01, 1e-6) and k.get("k2") == 0.0,
          f"CamLens: vignetting = {lens.get('vignetting')}, distortion = {k}")
    pres = (lens.get("prescription") or {}).get("lens") or {}
    check("b.lens-prescription", close(pres.get("focal_length_mm"), 50.3582, 1e-3),
          f"CamLens: the inline double Gauss's focal length = {pres.get('focal_length_mm')} mm "
          f"(50.3582)")
    off = info_camera(info, "CamOff")
    check("b.dof-off", off.get("enabled") is False, f"CamOff: enabled = {off.get('enabled')}")
    hidden = info_camera(info, "CamHiddenFocus")
    depth = view_depth(cams["hidden"], bpy.data.objects["NotExported"])
    check("b.unexported-focus", close(hidden.get("focus_distance"), depth, 1e-4),
          f"CamHiddenFocus: focus_distance = {hidden.get('focus_distance')} (depth {depth:.6g})")


# --------------------------------------------------------------------------------------------
# renders and comparison


def setup_cycles(spp, seed):
    sc = bpy.context.scene
    cycles_settings.unbiased(sc, spp, seed)
    sc.world = None  # black, as glTF has no environment
    sc.render.use_persistent_data = False
    sc.render.threads_mode = "AUTO"
    sc.render.image_settings.exr_codec = "ZIP"


def diffuse_materials():
    """Plain Diffuse BSDFs (and plain Emission) for Cycles, the colours of the exported materials."""
    for mat in bpy.data.materials:
        if "test_colour" not in mat:
            continue
        colour = tuple(mat["test_colour"])
        nt = mat.node_tree
        nt.nodes.clear()
        out = nt.nodes.new("ShaderNodeOutputMaterial")
        if mat["test_emission"] > 0.0:
            node = nt.nodes.new("ShaderNodeEmission")
            node.inputs["Color"].default_value = (*colour, 1.0)
            node.inputs["Strength"].default_value = mat["test_emission"]
            nt.links.new(node.outputs["Emission"], out.inputs["Surface"])
        else:
            node = nt.nodes.new("ShaderNodeBsdfDiffuse")
            node.inputs["Color"].default_value = (*colour, 1.0)
            node.inputs["Roughness"].default_value = 0.0  # Lambert
            nt.links.new(node.outputs["BSDF"], out.inputs["Surface"])


def render_cycles(path, spp, seed):
    import time

    setup_cycles(spp, seed)
    bpy.context.scene.render.filepath = path
    t = time.time()
    bpy.ops.render.render(write_still=True)
    return time.time() - t


def load_exr(path):
    from exr_beauty import read_beauty

    return read_beauty(path, bottom_up=True)  # rows bottom to top, as Blender's pixels


def rmse(a, b):
    import numpy as np

    return float(np.sqrt(np.mean((a - b) ** 2)))


def bokeh_moments(img, centre, half):
    """Intensity centroid, RMS radius and normalised 6-fold moment of the blob within a circle of
    radius `half` around `centre` (a circle, so the window adds no shape of its own)."""
    import numpy as np

    lum = img.mean(axis=2)
    cx, cy = centre
    x0, x1 = max(0, int(cx - half)), min(lum.shape[1], int(cx + half) + 1)
    y0, y1 = max(0, int(cy - half)), min(lum.shape[0], int(cy + half) + 1)
    crop = lum[y0:y1, x0:x1]
    ys, xs = np.mgrid[y0:y1, x0:x1]
    inside = np.hypot(xs + 0.5 - cx, ys + 0.5 - cy) <= half
    w = np.where(inside, np.clip(crop, 0.0, None), 0.0)
    total = w.sum()
    mx, my = (w * (xs + 0.5)).sum() / total, (w * (ys + 0.5)).sum() / total
    dx, dy = xs + 0.5 - mx, ys + 0.5 - my
    r2 = dx * dx + dy * dy
    rms = math.sqrt((w * r2).sum() / total)
    theta = np.arctan2(dy, dx)
    r6 = r2 ** 3
    m6 = (w * r6 * np.exp(6j * theta)).sum() / (w * r6).sum()
    return (mx, my), rms, complex(m6), float(total)


def ideal_hexagon_m6(rotation=0.0, n=6, res=801):
    """The 6-fold moment of a uniform regular polygon with corners at rotation + π/n + 2πk/n."""
    import numpy as np

    ys, xs = np.mgrid[-1:1:res * 1j, -1:1:res * 1j]
    theta = np.arctan2(ys, xs)
    r = np.hypot(xs, ys)
    # Distance to the polygon's edge in direction theta (circumradius 0.95).
    apothem = 0.95 * math.cos(math.pi / n)
    rel = (theta - rotation) % (2 * math.pi / n) - math.pi / n  # 0 at the corners
    edge = apothem / np.cos(math.pi / n - np.abs(rel))
    inside = (r <= edge).astype(float)
    r6 = r ** 6
    return complex((inside * r6 * np.exp(6j * theta)).sum() / (inside * r6).sum())


def render_flags(help_text):
    """Maps our needs to the flags `aperture render --help` lists."""
    def first(*names):
        return next((n for n in names if n in help_text), None)

    return {
        "width": first("--width"),
        "height": first("--height"),
        "resolution": first("--resolution", "--size"),
        "spp": first("--spp", "--samples"),
        "seed": first("--seed"),
        "override": first("--override-material"),
        "filter": first("--filter"),
    }


def test_render(binary, scene_path, cam):
    import time

    ours = os.path.join(WORK, "aperture.exr")
    if ARGS.cycles_as_aperture:
        # Exercises the comparison itself: a third Cycles seed stands in for aperture's render.
        candidate = "Cycles seed 3"
        diffuse_materials()
        t_ours = render_cycles(ours, ARGS.spp, 3)
    else:
        ok, help_text = aperture_supports(binary, "render", "--override-material")
        if not ok:
            record("c.render", None if not ARGS.require_all else False,
                   f"`aperture render --override-material` not supported by {binary}")
            return
        candidate = "aperture"
        flags = render_flags(help_text)
        cmd = [binary, "render", scene_path, "-o", ours, flags["override"], "diffuse"]
        if flags["width"] and flags["height"]:
            cmd += [flags["width"], str(WIDTH), flags["height"], str(HEIGHT)]
        elif flags["resolution"]:
            cmd += [flags["resolution"], f"{WIDTH}x{HEIGHT}"]
        if flags["spp"]:
            cmd += [flags["spp"], str(ARGS.spp)]
        if flags["seed"]:
            cmd += [flags["seed"], "7"]
        if flags["filter"]:
            cmd += [flags["filter"], "box"]  # Cycles is set to a 1-pixel box too
        t = time.time()
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=1800)
        t_ours = time.time() - t
        if not check("c.aperture-render-runs", out.returncode == 0,
                     f"`{' '.join(cmd)}` exit {out.returncode} in {t_ours:.1f} s {out.stderr.strip()[-400:]}"):
            return
        diffuse_materials()
    compare(ours, candidate, t_ours, cam)


def compare(ours, candidate, t_ours, cam):
    """Compares `ours` (an EXR) with two Cycles renders of the scene (seeds 1 and 2)."""
    import numpy as np

    spp = ARGS.spp
    a_path, b_path = os.path.join(WORK, "cycles_seed1.exr"), os.path.join(WORK, "cycles_seed2.exr")
    t_a = render_cycles(a_path, spp, 1)
    t_b = render_cycles(b_path, spp, 2)
    print(f"Cycles: {t_a:.1f} s and {t_b:.1f} s at {WIDTH}x{HEIGHT}, {spp} spp; {candidate}: {t_ours:.1f} s")
    A, B, O = load_exr(a_path), load_exr(b_path), load_exr(ours)
    if not check("c.same-size", O.shape == A.shape,
                 f"{candidate} {O.shape[1]}x{O.shape[0]}, Cycles {A.shape[1]}x{A.shape[0]}"):
        return

    noise = rmse(A, B)
    err = rmse(O, A)
    check("c.rmse-within-noise", err <= 1.5 * noise,
          f"RMSE({candidate}, Cycles) = {err:.5f}, RMSE(Cycles seed 1, seed 2) = {noise:.5f}, limit ×1.5 = {1.5 * noise:.5f}")
    ratio = O.mean() / A.mean()
    check("c.mean-ratio", abs(ratio - 1.0) <= 0.03, f"mean({candidate}) / mean(Cycles) = {ratio:.4f} (±3 %)")

    # Mean ratio away from the bulb: the lit, diffuse part of the picture.
    name, depth, nx, ny, radius, strength = BULB
    cx, cy = (nx + 1.0) / 2.0 * WIDTH, (ny + 1.0) / 2.0 * HEIGHT  # rows go bottom to top
    tx, ty = tan_half()
    focus = view_depth(cam, bpy.data.objects[FOCUS])
    rad_m = LENS * 0.001 / (2.0 * FSTOP)
    coc = rad_m * abs(1.0 / focus - 1.0 / depth) * HEIGHT / ty
    half = 0.5 * coc + radius / depth / ty * HEIGHT / 2 + 3
    mask = np.ones(A.shape[:2], bool)
    mask[max(0, int(cy - half)):int(cy + half) + 1, max(0, int(cx - half)):int(cx + half) + 1] = False
    ratio_lit = O[mask].mean() / A[mask].mean()
    check("c.mean-ratio-lit", abs(ratio_lit - 1.0) <= 0.03,
          f"outside the bokeh: mean({candidate}) / mean(Cycles) = {ratio_lit:.4f} (±3 %)")

    # Bokeh: the blob's size, 6-fold shape and its orientation.
    ca, ra, ma, ea = bokeh_moments(A, (cx, cy), half)
    cb, rb, mb, eb = bokeh_moments(B, (cx, cy), half)
    co, ro, mo, eo = bokeh_moments(O, (cx, cy), half)
    ideal = ideal_hexagon_m6()
    print(f"bokeh: CoC {coc:.1f} px expected; centroid Cycles {ca[0]:.1f},{ca[1]:.1f} {candidate} {co[0]:.1f},{co[1]:.1f}; "
          f"RMS radius Cycles {ra:.2f}/{rb:.2f} {candidate} {ro:.2f}; M6 Cycles {ma:.3f}/{mb:.3f} {candidate} {mo:.3f} "
          f"(ideal sharp hexagon, corners up: {ideal:.3f}); energy ratio {eo / ea:.4f}")
    check("c.bokeh-position", math.hypot(co[0] - ca[0], co[1] - ca[1]) < 1.0,
          f"centroids {math.hypot(co[0] - ca[0], co[1] - ca[1]):.2f} px apart")
    check("c.bokeh-size", abs(ro / ra - 1.0) < 0.05, f"RMS radius ratio {ro / ra:.4f} (Cycles seeds: {rb / ra:.4f})")
    six_fold = abs(mo) > 0.25 * abs(ideal) and abs(ma) > 0.25 * abs(ideal)
    check("c.bokeh-hexagonal", six_fold,
          f"|M6| {candidate} {abs(mo):.3f}, Cycles {abs(ma):.3f}, seed noise {abs(ma - mb):.3f}; a disc gives ~0")
    dphase = abs((math.degrees(np.angle(mo) - np.angle(ma)) + 180.0) % 360.0 - 180.0) / 6.0
    check("c.bokeh-orientation", dphase < 5.0,
          f"hexagon orientations differ by {dphase:.2f}° (phase of M6 / 6)")


# --------------------------------------------------------------------------------------------


def main():
    global ARGS, WORK
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--aperture", default=os.path.join(HERE, "../../target/release/aperture"),
                        help="the aperture binary (default: target/release/aperture)")
    parser.add_argument("--out", help="keep the exports and renders in this folder")
    parser.add_argument("--spp", type=int, default=512, help="samples per pixel for both renderers")
    parser.add_argument("--cycles-as-aperture", action="store_true",
                        help="check part (c)'s comparison itself: a third Cycles seed plays aperture")
    parser.add_argument("--require-all", action="store_true",
                        help="fail (rather than skip) when the binary lacks `info --json` or `render`")
    ARGS = parser.parse_args()

    WORK = os.path.abspath(ARGS.out) if ARGS.out else tempfile.mkdtemp(prefix="aperture-blender-")
    os.makedirs(WORK, exist_ok=True)
    scripts = tempfile.mkdtemp(prefix="aperture-blender-scripts-")
    try:
        import_bpy(scripts)
        print(f"Blender {bpy.app.version_string}, working in {WORK}")
        cam = build_scene()  # reads factory settings, which resets the add-ons: install after
        install_addon()
        binary = os.path.abspath(ARGS.aperture)
        main_path = os.path.join(WORK, "scene.gltf")
        doc, _ = export(main_path)
        test_extras_main(doc)
        test_motion_extras(doc)

        if os.path.isfile(binary) and os.access(binary, os.X_OK):
            test_info(binary, main_path, cam)
            test_render(binary, main_path, cam)
        elif ARGS.cycles_as_aperture:
            test_render(binary, main_path, cam)
        else:
            for name in ("b.info-json", "c.render"):
                record(name, None if not ARGS.require_all else False, f"no aperture binary at {binary}")

        # The rule cameras change the scene: last.
        test_extras_rules(add_rule_cameras(), binary)
    finally:
        shutil.rmtree(scripts, ignore_errors=True)
        if not ARGS.out:
            shutil.rmtree(WORK, ignore_errors=True)

    return summary()


if __name__ == "__main__":
    sys.exit(main())
