# SPDX-License-Identifier: MIT OR Apache-2.0
"""The lens prescription of a camera's *aperture Lens* panel (``aperture_lens.prescription``, a
pbrt-v4 lens file; issue 61) into the glTF export: the file's rows inline as the extras key
``lens_prescription`` (docs/lenses.md), so the exported scene needs no file beside it."""

import bpy

KEY = "lens_prescription"


def read_rows(path):
    """The rows of a lens file: four numbers a line (radius, thickness, IOR, aperture diameter,
    mm), ``#`` comments and blank lines skipped. Raises ValueError on a malformed line."""
    rows = []
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            tokens = line.split("#", 1)[0].replace(",", " ").split()
            if not tokens:
                continue
            if len(tokens) != 4:
                raise ValueError(f"line {n}: expected 4 numbers, found {len(tokens)}")
            rows.append([float(t) for t in tokens])
    return rows


def prescription_extras(lens):
    """``{"lens_prescription": rows}`` for a lens whose prescription path is set, the file read
    now; a file that cannot be read is exported as its path, for aperture to report; ``{}``
    when no path is set."""
    path = getattr(lens, "prescription", "")
    if not path:
        return {}
    absolute = bpy.path.abspath(path)
    try:
        return {KEY: read_rows(absolute)}
    except (OSError, ValueError) as e:
        print(f"WARNING: aperture_gltf_dof: lens prescription {absolute!r}: {e}")
        return {KEY: path}
