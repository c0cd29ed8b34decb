"""Blender's motion-blur settings as SPEC section 7 scene extras: the keys aperture reads from
``scenes[i].extras`` (``use_motion_blur``, ``motion_blur_shutter``, ``motion_blur_position``,
``rolling_shutter_type``, ``rolling_shutter_duration``, ``fps``, ``frame_current``)."""


def motion_extras(scene, frame_current=None):
    """The scene's motion-blur settings, under Blender's own property names.

    ``motion_blur_position`` is on the render settings in Blender 4.2 and later, on Cycles'
    before; the rolling shutter is Cycles'. A setting Blender does not have is left out.
    """
    render = scene.render
    cycles = getattr(scene, "cycles", None)
    extras = {
        "use_motion_blur": bool(render.use_motion_blur),
        "motion_blur_shutter": float(render.motion_blur_shutter),
        "fps": float(render.fps) / float(render.fps_base),
        "frame_current": int(scene.frame_current if frame_current is None else frame_current),
    }
    position = getattr(render, "motion_blur_position", None)
    if position is None and cycles is not None:
        position = getattr(cycles, "motion_blur_position", None)
    if position in ("START", "CENTER", "END"):
        extras["motion_blur_position"] = position
    rolling = getattr(cycles, "rolling_shutter_type", None) if cycles is not None else None
    if rolling in ("NONE", "TOP"):
        extras["rolling_shutter_type"] = rolling
        extras["rolling_shutter_duration"] = float(cycles.rolling_shutter_duration)
    return extras


def add_to(gltf2_scene, blender_scene, frame_current=None):
    """Writes the settings into ``gltf2_scene.extras``; keys already there (custom properties)
    win. ``frame_current``: the frame shown when the export started (the exporter moves the
    scene's while it samples animations)."""
    extras = gltf2_scene.extras if isinstance(gltf2_scene.extras, dict) else {}
    for key, value in motion_extras(blender_scene, frame_current).items():
        extras.setdefault(key, value)
    gltf2_scene.extras = extras
