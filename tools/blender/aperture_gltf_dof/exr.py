# SPDX-License-Identifier: MIT OR Apache-2.0
"""Reads the EXR files aperture writes, with NumPy and zlib only (Blender's Python has both but
no OpenEXR binding, and Blender's own loader does not expand a multilayer file outside a render).

Covers what aperture writes: one scan-line part, uncompressed, ZIPS or ZIP (16 lines),
float32 and half channels, any data window. Anything else raises ``ValueError``.
"""

import struct
import zlib

import numpy as np

_SAMPLE = {1: (np.float16, 2), 2: (np.float32, 4)}  # 0 (uint) is not written by aperture
_LINES = {0: 1, 2: 1, 3: 16}  # compression -> scan lines per block


def attributes(data):
    """The header attributes of an EXR file's bytes, `{name: (type, value bytes)}`, and where the
    header ends."""
    if data[:4] != b"\x76\x2f\x31\x01":
        raise ValueError("not an OpenEXR file")
    if struct.unpack_from("<I", data, 4)[0] & 0x1E00:
        raise ValueError("tiled, deep or multi-part EXR")
    at, attrs = 8, {}
    while data[at] != 0:
        name_end = data.index(b"\0", at)
        type_end = data.index(b"\0", name_end + 1)
        size = struct.unpack_from("<i", data, type_end + 1)[0]
        value = data[type_end + 5 : type_end + 5 + size]
        attrs[data[at:name_end].decode()] = (data[name_end + 1 : type_end].decode(), value)
        at = type_end + 5 + size
    return attrs, at + 1


def _channels(value):
    out, at = [], 0
    while value[at] != 0:
        end = value.index(b"\0", at)
        # Pixel type, pLinear and three reserved bytes, x and y sampling.
        kind, xs, ys = struct.unpack_from("<i4xii", value, end + 1)
        if (xs, ys) != (1, 1) or kind not in _SAMPLE:
            raise ValueError(f"channel {value[at:end].decode()}: unsupported type or sampling")
        out.append((value[at:end].decode(), kind))
        at = end + 17
    return out


def _unzip(block, size):
    """ZIP's inverse: inflate, undo the byte predictor, interleave the two halves again."""
    t = np.frombuffer(zlib.decompress(block), dtype=np.uint8)
    if t.size != size:
        raise ValueError("damaged ZIP block")
    t = _undo_predictor(t)
    half = (size + 1) // 2
    out = np.empty(size, dtype=np.uint8)
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return out


def _undo_predictor(t):
    # t[i] = t[i-1] + t[i] - 128 (mod 256), cumulative.
    d = t.astype(np.int64)
    d[1:] -= 128
    return (np.cumsum(d) & 0xFF).astype(np.uint8)


def read(path):
    """``(channels, header)``: each channel's samples as a float32 array of the data window's
    shape (rows top to bottom), and ``header`` with ``data_window`` and ``display_window``
    as (x0, y0, x1, y1) inclusive, and the text and float attributes."""
    with open(path, "rb") as f:
        data = f.read()
    attrs, at = attributes(data)
    compression = attrs["compression"][1][0]
    if compression not in _LINES:
        raise ValueError(f"compression {compression} is not one aperture writes")
    channels = _channels(attrs["channels"][1])
    x0, y0, x1, y1 = struct.unpack("<iiii", attrs["dataWindow"][1])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    lines = _LINES[compression]
    blocks = (h + lines - 1) // lines
    offsets = struct.unpack_from(f"<{blocks}Q", data, at)
    row_bytes = sum(_SAMPLE[k][1] for _, k in channels) * w
    out = {name: np.empty((h, w), dtype=np.float32) for name, _ in channels}
    for b, offset in enumerate(offsets):
        y, size = struct.unpack_from("<ii", data, offset)
        rows = min(lines, y1 - y + 1)
        raw = data[offset + 8 : offset + 8 + size]
        expected = rows * row_bytes
        pixels = np.frombuffer(raw, dtype=np.uint8) if size == expected else _unzip(raw, expected)
        at_row = 0
        for r in range(rows):
            for name, kind in channels:
                dtype, n = _SAMPLE[kind]
                chunk = pixels[at_row : at_row + w * n]
                out[name][y - y0 + r] = np.frombuffer(chunk.tobytes(), dtype=dtype)
                at_row += w * n
    header = {"data_window": (x0, y0, x1, y1)}
    header["display_window"] = struct.unpack("<iiii", attrs["displayWindow"][1])
    for key, (kind, value) in attrs.items():
        if kind == "string":
            header[key] = value.decode("utf-8", "replace")
        elif kind == "float":
            header[key] = struct.unpack("<f", value)[0]
    return out, header
