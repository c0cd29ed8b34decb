# SPDX-License-Identifier: MIT OR Apache-2.0
"""Blender's world as aperture's `--env`: glTF has no environment, so the engine passes it on
the command line. What it cannot express is reported, never silently dropped."""

import math


def _linked(socket):
    return socket.links[0].from_node if socket.is_linked and socket.links else None


def env_arguments(world):
    """``(arguments, problems)``: the `--env` arguments for ``world`` (a constant colour × strength,
    or an Environment Texture's image with its rotation and strength), and what could not be
    expressed, one line each."""
    if world is None:
        return [], []
    tree = world.node_tree if getattr(world, "use_nodes", True) else None
    if tree is None:
        c = world.color
        return ["--env", f"{c[0]:.9g},{c[1]:.9g},{c[2]:.9g}"], []
    output = next(
        (n for n in tree.nodes if n.type == "OUTPUT_WORLD" and n.is_active_output),
        next((n for n in tree.nodes if n.type == "OUTPUT_WORLD"), None),
    )
    source = _linked(output.inputs["Surface"]) if output is not None else None
    if source is None:
        return [], []
    if source.type != "BACKGROUND":
        return [], [f"world: a {source.bl_label} node is not supported; the background is black"]
    strength = source.inputs["Strength"].default_value
    if source.inputs["Strength"].is_linked:
        return [], ["world: a linked Strength is not supported; the background is black"]
    colour = source.inputs["Color"]
    texture = _linked(colour)
    if texture is None:
        c = colour.default_value
        return ["--env", ",".join(f"{v * strength:.9g}" for v in c[:3])], []
    if texture.type != "TEX_ENVIRONMENT" or texture.image is None:
        return [], [f"world: a {texture.bl_label} node feeding the Background is not supported; "
                    "the background is black"]
    problems = []
    if texture.projection != "EQUIRECTANGULAR":
        problems.append("world: only equirectangular environment textures are supported")
    rotation = 0.0
    mapping = _linked(texture.inputs["Vector"])
    if mapping is not None:
        if mapping.type != "MAPPING":
            problems.append(f"world: a {mapping.bl_label} node on the texture's vector is ignored")
        else:
            r = mapping.inputs["Rotation"].default_value
            if abs(r[0]) > 1e-6 or abs(r[1]) > 1e-6:
                problems.append("world: only a rotation about Z of the environment is supported")
            # Blender rotates the lookup vector (Point mapping): the sky turns the other way.
            rotation = -math.degrees(r[2])
    path = texture.image.filepath_from_user() if texture.image.filepath else ""
    if not path.lower().endswith((".hdr", ".exr")):
        problems.append(f"world: environment image {path!r} is not .hdr or .exr; the background is black")
        return [], problems
    args = ["--env", path, "--env-strength", f"{strength:.9g}"]
    if rotation:
        args += ["--env-rotation", f"{rotation:.9g}"]
    return args, problems
