# SPDX-License-Identifier: MIT OR Apache-2.0
"""The thin lens's imperfections on a camera (``camera.aperture_lens``, issue 61) and their panel
in Camera Properties: exported as the extras keys ``aperture_vignetting``, ``distortion_*``,
``chromatic_*`` and ``aperture_image`` (docs/lenses.md) by the exporter hook
(``dof_export.lens_extras``, ``dof_export.aperture_image_extra``), and a lens prescription file
whose rows are exported inline as ``lens_prescription`` (``prescription_export``)."""

import bpy


class ApertureLens(bpy.types.PropertyGroup):
    """Optical vignetting and Brown–Conrady distortion (OpenCV's coefficients)."""

    vignetting: bpy.props.FloatProperty(
        name="Vignetting",
        description="How far the lens barrel clips the aperture at the image's corners, in "
        "lens radii (0: none; cat's-eye bokeh off axis)",
        default=0.0, min=0.0, max=1.0,
    )
    k1: bpy.props.FloatProperty(name="K1", description="Radial distortion, r² term "
                                "(negative: barrel)", default=0.0, precision=4)
    k2: bpy.props.FloatProperty(name="K2", description="Radial distortion, r⁴ term",
                                default=0.0, precision=4)
    k3: bpy.props.FloatProperty(name="K3", description="Radial distortion, r⁶ term",
                                default=0.0, precision=4)
    p1: bpy.props.FloatProperty(name="P1", description="Tangential distortion",
                                default=0.0, precision=4)
    p2: bpy.props.FloatProperty(name="P2", description="Tangential distortion",
                                default=0.0, precision=4)
    prescription: bpy.props.StringProperty(
        name="Prescription",
        description="A real lens traced surface by surface: a lens file in pbrt-v4's format "
        "(radius, thickness, IOR, aperture diameter in mm per surface); its rows are exported "
        "inline as lens_prescription. Empty: the thin lens",
        default="", subtype="FILE_PATH",
    )
    chromatic_lateral: bpy.props.FloatProperty(
        name="Lateral",
        description="Lateral chromatic aberration: red's image is 1 + this times green's size, "
        "blue's 1 - this (typical 0.001-0.005)",
        default=0.0, min=-0.5, max=0.5, precision=4, step=0.01,
    )
    chromatic_longitudinal: bpy.props.FloatProperty(
        name="Longitudinal",
        description="Longitudinal chromatic aberration: red focuses at 1 + this times the focus "
        "distance, blue at 1 - this (typical 0.005-0.03)",
        default=0.0, min=-0.5, max=0.5, precision=4, step=0.01,
    )
    aperture_image: bpy.props.StringProperty(
        name="Bokeh Image",
        description="Greyscale image of the aperture's shape and transmission (bokeh image); "
        "copied beside the exported glTF file. Empty: the plain aperture",
        default="", subtype="FILE_PATH",
    )


class DATA_PT_aperture_lens(bpy.types.Panel):
    """Camera Properties › aperture Lens."""

    bl_label = "aperture Lens"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "data"
    COMPAT_ENGINES = {"APERTURE"}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES and context.camera is not None

    def draw(self, context):
        lens = context.camera.aperture_lens
        layout = self.layout
        layout.use_property_split = True
        layout.prop(lens, "vignetting")
        column = layout.column(heading="Distortion")
        for name in ("k1", "k2", "k3", "p1", "p2"):
            column.prop(lens, name)
        layout.prop(lens, "prescription")
        column = layout.column(heading="Chromatic Aberration")
        column.prop(lens, "chromatic_lateral")
        column.prop(lens, "chromatic_longitudinal")
        layout.prop(lens, "aperture_image")


CLASSES = (ApertureLens, DATA_PT_aperture_lens)


def register():
    for c in CLASSES:
        bpy.utils.register_class(c)
    bpy.types.Camera.aperture_lens = bpy.props.PointerProperty(type=ApertureLens)


def unregister():
    del bpy.types.Camera.aperture_lens
    for c in reversed(CLASSES):
        bpy.utils.unregister_class(c)
