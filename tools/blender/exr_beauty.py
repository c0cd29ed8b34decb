# SPDX-License-Identifier: MIT OR Apache-2.0
"""The beauty of an EXR file as a NumPy array, through OpenEXR's own Python reader.

aperture's EXR is always a multilayer file (its passes beside an unprefixed R,G,B,A), which
Blender's image loader does not expand outside a render; Cycles writes R,G,B,A or
`<layer>.Combined.R`. This reads either."""

import numpy as np


def read_beauty(path, bottom_up=False):
    """(height, width, 3) float64 RGB, rows top to bottom (or bottom to top, Blender's pixel
    order, with `bottom_up`)."""
    import OpenEXR

    channels = OpenEXR.File(path, separate_channels=True).channels()
    if "R" in channels:
        prefix = ""
    else:
        prefix = next(n[:-1] for n in sorted(channels) if n.endswith("Combined.R"))
    rgb = np.stack([np.array(channels[prefix + c].pixels, dtype=np.float64) for c in "RGB"], -1)
    return rgb[::-1] if bottom_up else rgb
