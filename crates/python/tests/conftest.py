"""Shared fixtures of the `aperture` module's tests (tools/python/test.sh runs them).

Under CI=true anything the tests need and cannot find (the aperture binary, OpenEXR's Python
reader) fails the test instead of skipping it.
"""

import json
import os
import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[3]
DEMO = ROOT / "assets" / "demo.glb"
CI = os.environ.get("CI") == "true"


def missing(what):
    """Fail under CI, skip elsewhere."""
    if CI:
        pytest.fail(f"{what} is missing (CI=true: a missing input fails)")
    pytest.skip(f"{what} is missing")


@pytest.fixture(scope="session")
def demo():
    if not DEMO.exists():
        missing(str(DEMO))
    return DEMO


@pytest.fixture(scope="session")
def aperture_bin():
    """The command line's binary (APERTURE_BIN, else target/debug/aperture)."""
    path = Path(os.environ.get("APERTURE_BIN", ROOT / "target" / "debug" / "aperture"))
    if not path.exists():
        missing(f"the aperture binary {path} (cargo build -p aperture-cli)")
    return path


def run_cli(binary, *args):
    """Runs the command line; its output on failure."""
    out = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
    assert out.returncode == 0, f"aperture {' '.join(map(str, args))}:\n{out.stderr}"
    return out.stdout


@pytest.fixture(scope="session")
def exr_reader():
    """OpenEXR's own Python reader: `read(path)` -> (header, {channel: HxW float32})."""
    try:
        import OpenEXR
    except ImportError:
        missing("OpenEXR (pip install OpenEXR)")

    def read(path):
        with OpenEXR.File(str(path), separate_channels=True) as f:
            header = dict(f.header())
            channels = {name: np.asarray(c.pixels, dtype=np.float32)
                        for name, c in f.channels().items()}
        return header, channels

    return read


def read_glb(path):
    """A .glb as (json dict, bin chunk bytes)."""
    data = Path(path).read_bytes()
    assert data[:4] == b"glTF"
    (json_len,) = struct.unpack_from("<I", data, 12)
    doc = json.loads(data[20:20 + json_len])
    rest = data[20 + json_len:]
    binary = b""
    if rest:
        (bin_len,) = struct.unpack_from("<I", rest, 0)
        binary = rest[8:8 + bin_len]
    return doc, binary


def write_glb(path, doc, binary):
    """A .glb of `doc` and its binary chunk (both padded to 4 bytes)."""
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(text) + (8 + len(binary) if binary else 0)
    out = struct.pack("<4sII", b"glTF", 2, total)
    out += struct.pack("<I4s", len(text), b"JSON") + text
    if binary:
        out += struct.pack("<I4s", len(binary), b"BIN\0") + binary
    Path(path).write_bytes(out)


def bits(a):
    """A float32 array's bits, so comparisons are bit for bit (NaN, -0.0 included)."""
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)
