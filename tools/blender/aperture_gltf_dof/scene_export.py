# SPDX-License-Identifier: MIT OR Apache-2.0
"""The scene as F12 and the viewport export it: the GLB and the image size."""

import bpy


def resolution(scene):
    r = scene.render
    return (max(1, round(r.resolution_x * r.resolution_percentage / 100)),
            max(1, round(r.resolution_y * r.resolution_percentage / 100)))


def export_scene(path, motion_blur=False):
    """The evaluated scene at the current frame, as a GLB: cameras, lights, custom properties
    and this add-on's depth of field on, modifiers applied, render-visible objects only. With
    motion blur, the animation too (aperture poses the shutter's motion steps from it, and the
    scene's extras carry the shutter)."""
    bpy.ops.export_scene.gltf(
        filepath=path,
        export_format="GLB",
        use_renderable=True,
        export_cameras=True,
        export_lights=True,
        export_extras=True,
        export_apply=True,
        export_animations=motion_blur,
        export_current_frame=not motion_blur,
        export_yup=True,
    )
