# SPDX-License-Identifier: MIT OR Apache-2.0
"""The engine's settings (``scene.aperture``) and their panel in Render Properties."""

import bpy

FILTERS = [
    ("BLACKMAN_HARRIS", "Blackman-Harris", "1.5 px wide (Cycles' default)"),
    ("GAUSSIAN", "Gaussian", "1.5 px wide"),
    ("BOX", "Box", "1 px"),
]
TRANSMISSION = [
    ("AUTO", "Auto", "Blender's glass when the file was exported by Blender, else glTF's meaning"),
    ("GLTF", "glTF", "The Khronos meaning: transmission without volume is thin-walled"),
    ("BLENDER", "Blender", "Every transmissive closed mesh refracts, as Cycles shows it"),
]
# Cycles' Denoising Prefilter and Quality, with its defaults (`--denoise-prefilter`, `-quality`).
DENOISE_PREFILTERS = [
    ("NONE", "None", "Albedo and normal taken as noise-free (one filter)"),
    ("FAST", "Fast", "Albedo and normal cleaned with the image (one filter)"),
    ("ACCURATE", "Accurate", "Albedo and normal denoised first (three filters, the best image)"),
]
DENOISE_QUALITIES = [
    ("HIGH", "High", "The final-frame network"),
    ("BALANCED", "Balanced", "Half High's time with the Accurate prefilter, else the same"),
    ("FAST", "Fast", "A small network for the image, for previews"),
]


class ApertureSettings(bpy.types.PropertyGroup):
    """How aperture renders this scene."""

    binary: bpy.props.StringProperty(
        name="aperture binary",
        description="Path of the aperture program, or its folder (empty: `aperture`, "
        "`aperture.exe` on Windows, found on PATH or in ~/.cargo/bin; install it with "
        "`cargo install --path crates/cli`)",
        subtype="FILE_PATH",
        default="",
    )
    samples: bpy.props.IntProperty(name="Samples", default=64, min=1, max=65536)
    noise_threshold: bpy.props.FloatProperty(
        name="Noise Threshold",
        description="Adaptive sampling: a pixel stops once its relative error is below this "
        "(0: off, every pixel takes Samples)",
        default=0.0,
        min=0.0,
        max=1.0,
        precision=4,
    )
    max_bounces: bpy.props.IntProperty(name="Max Bounces", default=12, min=0, max=1024)
    clamp_direct: bpy.props.FloatProperty(name="Clamp Direct", default=0.0, min=0.0)
    clamp_indirect: bpy.props.FloatProperty(name="Clamp Indirect", default=0.0, min=0.0)
    filter: bpy.props.EnumProperty(name="Pixel Filter", items=FILTERS, default="BLACKMAN_HARRIS")
    seed: bpy.props.IntProperty(name="Seed", default=0, min=0)
    transmission: bpy.props.EnumProperty(name="Transmission", items=TRANSMISSION, default="AUTO")
    denoising_data: bpy.props.BoolProperty(
        name="Denoising Data",
        description="Denoising Albedo and Denoising Normal passes, for the Denoise node",
        default=True,
    )
    denoise: bpy.props.BoolProperty(
        name="Denoise",
        description="Denoise the image with Open Image Denoise (albedo and normal prefiltered, "
        "as Cycles; `aperture render --denoise`); the noisy image stays as the Noisy Image pass",
        default=True,
    )
    denoise_prefilter: bpy.props.EnumProperty(
        name="Prefilter",
        description="How the albedo and normal guide the denoiser, as Cycles' Prefilter",
        items=DENOISE_PREFILTERS,
        default="ACCURATE",
    )
    denoise_quality: bpy.props.EnumProperty(
        name="Quality",
        description="The denoising network's size (time against quality), as Cycles' Quality",
        items=DENOISE_QUALITIES,
        default="HIGH",
    )
    oidn: bpy.props.StringProperty(
        name="OIDN Library",
        description="Open Image Denoise library to denoise with: libOpenImageDenoise.so.2, "
        "OpenImageDenoise.dll on Windows (empty: APERTURE_OIDN if set, "
        "else the one that ships with this Blender, else aperture's own search)",
        subtype="FILE_PATH",
        default="",
    )
    viewport_denoise: bpy.props.BoolProperty(
        name="Viewport Denoise",
        description="Denoise the viewport with Open Image Denoise at Cycles' viewport settings "
        "(quality balanced, prefilter fast), from the Start Sample on; off when the library is "
        "not found (the viewport header says so)",
        default=False,
    )
    viewport_denoise_start: bpy.props.IntProperty(
        name="Start Sample",
        description="The viewport shows the noisy image until it has this many samples, as "
        "Cycles' viewport denoising Start Sample",
        default=1,
        min=1,
        soft_max=64,
    )
    f12_session: bpy.props.BoolProperty(
        name="Keep Scene Loaded",
        description="F12 renders the scene the viewport keeps loaded (with the aperture Python "
        "module): a second F12 exports only what changed. Off, or without the module, or with "
        "motion blur or a border: every F12 exports the scene and runs the aperture "
        "program",
        default=True,
    )
    keep_files: bpy.props.BoolProperty(
        name="Keep Files",
        description="Keep the exported glTF and aperture's EXR in the temporary folder (for "
        "debugging)",
        default=False,
    )


class RENDER_PT_aperture(bpy.types.Panel):
    """Render Properties › aperture."""

    bl_label = "aperture"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    COMPAT_ENGINES = {"APERTURE"}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        s = context.scene.aperture
        layout = self.layout
        layout.use_property_split = True
        for name in ("samples", "noise_threshold", "max_bounces", "clamp_direct",
                     "clamp_indirect", "filter", "seed", "transmission", "denoising_data",
                     "denoise", "denoise_prefilter", "denoise_quality", "oidn", "binary",
                     "viewport_denoise", "viewport_denoise_start",
                     "f12_session", "keep_files"):
            layout.prop(s, name)


CLASSES = (ApertureSettings, RENDER_PT_aperture)


def register():
    for c in CLASSES:
        bpy.utils.register_class(c)
    bpy.types.Scene.aperture = bpy.props.PointerProperty(type=ApertureSettings)


def unregister():
    del bpy.types.Scene.aperture
    for c in reversed(CLASSES):
        bpy.utils.unregister_class(c)
