# SPDX-License-Identifier: MIT OR Apache-2.0
"""The add-on as users install it: its folder (`aperture_gltf_dof/`) zipped."""

import os
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
ADDON = "aperture_gltf_dof"


def addon_zip(folder):
    """Zips the add-on into `folder` and returns the zip's path."""
    path = os.path.join(folder, ADDON + ".zip")
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for root, _, files in os.walk(os.path.join(HERE, ADDON)):
            for name in sorted(files):
                if name.endswith(".py"):
                    full = os.path.join(root, name)
                    z.write(full, os.path.relpath(full, HERE))
    return path
