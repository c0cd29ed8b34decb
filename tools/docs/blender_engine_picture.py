# SPDX-License-Identifier: MIT OR Apache-2.0
"""Draws docs/blender-engine.png: a Blender scene rendered by the add-on's "aperture" engine
(F12 in Blender; here bpy.ops.render.render in bpy 5.0.1, with the add-on installed from its zip).

    python tools/docs/blender_engine_picture.py target/release/aperture docs/blender-engine.png
"""

import math
import os
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blender"))

from addon_zip import ADDON, addon_zip  # noqa: E402


def main(binary, out):
    os.environ["BLENDER_USER_SCRIPTS"] = tempfile.mkdtemp()
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.preferences.addon_install(filepath=addon_zip(tempfile.mkdtemp()), overwrite=True)
    bpy.ops.preferences.addon_enable(module=ADDON)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 640, 360

    def material(colour, metallic=0.0, roughness=0.4):
        m = bpy.data.materials.new("m")
        m.use_nodes = True
        b = m.node_tree.nodes["Principled BSDF"]
        b.inputs["Base Color"].default_value = (*colour, 1.0)
        b.inputs["Metallic"].default_value = metallic
        b.inputs["Roughness"].default_value = roughness
        return m

    bpy.ops.mesh.primitive_plane_add(size=40.0)
    bpy.context.active_object.data.materials.append(material((0.35, 0.35, 0.38), roughness=0.8))
    balls = [((-1.6, 2.0, 0.4), (0.8, 0.1, 0.08), 0.0), ((-0.3, 4.0, 0.5), (1.0, 0.78, 0.35), 1.0),
             ((1.2, 6.5, 0.6), (0.1, 0.3, 0.8), 0.0), ((2.8, 10.0, 0.7), (0.9, 0.9, 0.9), 1.0)]
    for i, (loc, colour, metal) in enumerate(balls):
        bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=loc[2],
                                             location=loc)
        bpy.ops.object.shade_smooth()
        o = bpy.context.active_object
        o.name = f"Ball{i}"
        o.data.materials.append(material(colour, metal, 0.25))
    cam = bpy.data.cameras.new("Cam")
    cam.lens = 50
    cam.dof.use_dof = True
    cam.dof.focus_object = bpy.data.objects["Ball1"]
    cam.dof.aperture_fstop = 1.4
    cam.dof.aperture_blades = 6
    o = bpy.data.objects.new("Cam", cam)
    o.location = (0.0, -2.5, 1.0)
    o.rotation_euler = (math.radians(84), 0.0, math.radians(-8))
    sc.collection.objects.link(o)
    sc.camera = o
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 2.5
    sun.rotation_euler = (math.radians(50), 0.0, math.radians(-30))
    sc.collection.objects.link(sun)
    sc.world = bpy.data.worlds.new("World")
    sc.world.use_nodes = True
    sc.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.25, 0.35, 0.55, 1)
    sc.render.engine = "APERTURE"
    sc.aperture.binary = os.path.abspath(binary)
    sc.aperture.samples = 256
    sc.render.image_settings.file_format = "PNG"
    sc.view_settings.view_transform = "AgX"
    sc.render.filepath = os.path.abspath(out)
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
