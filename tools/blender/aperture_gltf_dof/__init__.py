# SPDX-License-Identifier: MIT OR Apache-2.0
"""aperture for Blender: a render engine, and Blender's camera depth of field in glTF exports.

One add-on (a folder; install its zip), two features:

**The render engine "aperture"** (Render Properties › Render Engine). F12 exports the evaluated
scene at the current frame to a temporary GLB through Blender's own glTF exporter (cameras,
lights, custom properties and this add-on's depth of field on, modifiers applied), runs
`aperture render` on it with the scene's resolution (percentage included), active camera, world
(a colour × strength, or an equirectangular Environment Texture with its Z rotation and
strength: anything else is reported, not dropped) and the engine's settings, and loads the EXR
into the render result: Combined and the passes enabled in View Layer Properties (Depth,
Position, Normal, the light passes, Cryptomatte) plus Denoising Albedo/Normal. Progress comes
from `aperture render --progress json`; Esc stops the process within a second and removes the
temporary files; aperture's own error messages appear in the report area.

**Depth of field in glTF exports.** It hooks the official glTF 2.0 exporter (io_scene_gltf2) through its
user-extension interface (``glTF2ExportUserExtension``) and writes each camera's native settings to
``cameras[i].extras`` under Blender's own property names. The aperture renderer reads them there
(its SPEC, section 3):

    use_dof, focus_distance, focus_object, aperture_fstop, aperture_blades, aperture_rotation,
    aperture_ratio, lens, sensor_width, sensor_height, sensor_fit

The rules:

- Custom properties win. If you set a custom property with one of these names on the camera data
  by hand, its value is exported, whether or not the exporter's "Custom Properties" option is on.
- A camera with depth of field off still exports ``use_dof: false``, together with the other keys.
- ``focus_object`` is the name of the focused object's glTF node. The exporter names nodes after
  their objects. Focusing on a bone (``focus_subtarget``) is not supported: the exporter warns, and
  the focus goes to the armature object's origin. If the focus object is not exported (for example
  "Selected Objects" is on and the object is not selected), ``focus_object`` is replaced by
  ``focus_distance``, the object's depth along the camera's view axis as it is in Blender, and the
  exporter warns.
- Orthographic cameras: Cycles uses a lens radius of ``1 / (2 * fstop)`` scene units for these
  (no focal length); the test measured this with Blender 5.0.1. The add-on writes that radius as
  ``aperture_radius``, which wins over ``aperture_fstop``, so the renderer gets the same aperture
  as Cycles. A hand-set ``aperture_fstop`` is used for it, and a hand-set ``aperture_radius`` is
  kept.
- Blade counts of 1 and 2 (Blender's own settings cannot hold them) are written as 0, a round
  aperture, which is what Cycles renders.
- Keyframed ``dof.focus_distance`` and ``dof.aperture_fstop`` (a focus pull) are exported as
  ``KHR_animation_pointer`` channels at ``/cameras/{i}/extras/focus_distance`` and
  ``/cameras/{i}/extras/aperture_fstop``, sampled at every frame of their keys' range (time = frame
  / fps, as the exporter writes object animation), in one animation named ``<camera data>_dof``.

Install: zip this folder (`python3 -m zipfile -c aperture_gltf_dof.zip aperture_gltf_dof/`
in tools/blender), then Edit > Preferences > Add-ons > Install from Disk (the zip) and enable
"aperture". After that, File > Export > glTF 2.0 writes the extras, and "aperture" is a render
engine.
"""


bl_info = {
    "name": "aperture",
    "author": "the aperture authors",
    "version": (0, 2, 0),
    "blender": (4, 2, 0),
    "location": "Render Properties > Render Engine; File > Export > glTF 2.0 (cameras' extras)",
    "description": "Renders with aperture (physically based depth of field from glTF), and writes "
    "each camera's depth of field, lens and sensor to cameras[i].extras of glTF exports",
    "doc_url": "",
    "category": "Render",
}

import bpy

from . import engine, lens_settings, settings
# The glTF exporter looks for this name in every enabled add-on's module.
from .dof_export import glTF2ExportUserExtension  # noqa: F401

# Blender's panels a custom engine must opt into: those of these modules that Eevee shows.
_PANEL_MODULES = ("properties_output", "properties_render", "properties_view_layer",
                  "properties_world", "properties_data_camera", "properties_data_light",
                  "properties_material")


def _panels():
    import bl_ui

    for name in _PANEL_MODULES:
        module = getattr(bl_ui, name, None)
        for value in vars(module).values() if module else ():
            engines = getattr(value, "COMPAT_ENGINES", None)
            if isinstance(value, type) and isinstance(engines, set) and (
                engines & {"BLENDER_EEVEE", "BLENDER_EEVEE_NEXT", "BLENDER_WORKBENCH"}
            ):
                yield value


def register():
    settings.register()
    lens_settings.register()
    engine.register()
    for panel in _panels():
        panel.COMPAT_ENGINES.add(engine.ApertureRenderEngine.bl_idname)


def unregister():
    for panel in _panels():
        panel.COMPAT_ENGINES.discard(engine.ApertureRenderEngine.bl_idname)
    engine.unregister()
    lens_settings.unregister()
    settings.unregister()
