#!/usr/bin/env python3
"""Two `aperture` binaries (say a commit and its parent) on one scene of each kind, alternated:
the check to run before calling a speed-related issue resolved (issue 64).

    compare_binaries.py --before BIN --after BIN [--rounds 3] [--threads 2] [--cases a,b] [-o DIR]

Cases (each a scene kind whose cost must not creep in unnoticed):

* ``demo``       the README's command (480 x 270, defaults): still, one sun, single-sided faces
* ``outdoor``    ``assets/bench/outdoor_dof.gltf``, 64 spp, as issue 64 measured it
* ``interior``   bench_scenes.py's 567 k-triangle interior (written into DIR when missing), 16 spp
* ``lights``     many_lights.py's street grid with 1000 point lights, 16 spp
* ``motion``     the shared CesiumMan (skinned) at frame 12 with motion blur, 16 spp

Each round renders every case with ``before`` then ``after`` (the order flips every round, so a
drifting machine hits both alike). Printed per case: the median render-only time (the EXR
header's ``aperture:renderTime``: tracing, no load or BVH build), the median whole-command wall
time, and after / before for both. The images of the two binaries are compared too (``same``
when every beauty value is bitwise equal).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
from many_lights import header_float  # noqa: E402  (an EXR header's float, no library)

SAMPLES = os.environ.get("APERTURE_SAMPLES", os.path.join(REPO, "..", "shared", "gltf-samples"))
DIFFUSE = ["--override-material", "diffuse", "--passes", "none", "--filter", "box",
           "--max-bounces", "6", "--width", "320", "--height", "240"]


def cases(out):
    """name -> (scene path, arguments, how to write the scene when it is missing)."""
    interior = os.path.join(out, "scenes", "interior_500k.gltf")
    lights = os.path.join(out, "lights", "many_lights_1000.gltf")
    return {
        "demo": (os.path.join(REPO, "assets", "demo.glb"),
                 ["--width", "480", "--height", "270"], None),
        "outdoor": (os.path.join(REPO, "assets", "bench", "outdoor_dof.gltf"),
                    DIFFUSE + ["--spp", "64"], None),
        "interior": (interior, DIFFUSE + ["--spp", "16"],
                     [sys.executable, os.path.join(REPO, "tools", "reference", "bench_scenes.py"),
                      "write", "-o", out, "--scenes", "interior_500k"]),
        "lights": (lights, ["--width", "320", "--height", "240", "--spp", "16", "--passes", "none"],
                   [sys.executable, os.path.join(HERE, "many_lights.py"), "-o",
                    os.path.join(out, "lights"), "--lights", "1000"]),
        "motion": (os.path.join(SAMPLES, "animation", "CesiumMan", "CesiumMan.glb"),
                   ["--width", "320", "--height", "240", "--spp", "16", "--frame", "12",
                    "--motion-blur", "--passes", "none"], None),
    }


def ensure(path, writer):
    if os.path.exists(path):
        return
    if writer is None:
        sys.exit(f"missing scene: {path}")
    subprocess.run(writer, check=True, stdout=subprocess.DEVNULL)
    if not os.path.exists(path):
        sys.exit(f"{' '.join(writer)} did not write {path}")


def header_end(data):
    """The offset just past a single-part EXR header: attributes (name, type, size, value)
    until an empty name."""
    at = 8  # magic and version
    while data[at] != 0:
        name_end = data.index(b"\0", at)
        type_end = data.index(b"\0", name_end + 1)
        size = int.from_bytes(data[type_end + 1:type_end + 5], "little")
        at = type_end + 5 + size
    return at + 1


def render(binary, scene, args, threads, out):
    """(render-only seconds, wall seconds, sha256 of the EXR's pixel bytes)."""
    cmd = [binary, "render", scene, "-o", out, "--threads", str(threads), "--quiet",
           *args]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    with open(out, "rb") as f:
        data = f.read()
    # The header carries times, which differ run to run: hash what follows it (offsets, pixels).
    digest = hashlib.sha256(data[header_end(data):]).hexdigest()[:12]
    return header_float(out, "aperture:renderTime"), wall, digest


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--before", required=True)
    ap.add_argument("--after", required=True)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--cases", default="demo,outdoor,interior,lights,motion")
    ap.add_argument("-o", "--out", default="/tmp/aperture-compare")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    table = cases(a.out)
    bins = {"before": a.before, "after": a.after}
    print(f"case\tbefore render s\tafter render s\tratio\tbefore wall s\tafter wall s\tratio\timages")
    for name in a.cases.split(","):
        scene, args, writer = table[name]
        ensure(scene, writer)
        got = {k: [] for k in bins}
        for r in range(a.rounds):
            order = list(bins) if r % 2 == 0 else list(reversed(bins))
            for k in order:
                out = os.path.join(a.out, f"{name}-{k}.exr")
                got[k].append(render(bins[k], scene, args, a.threads, out))
        med = {k: (statistics.median(x[0] for x in v), statistics.median(x[1] for x in v))
               for k, v in got.items()}
        same = "same" if got["before"][0][2] == got["after"][0][2] else "DIFFER"
        b, f = med["before"], med["after"]
        print(f"{name}\t{b[0]:.3f}\t{f[0]:.3f}\t{f[0] / b[0]:.3f}\t{b[1]:.3f}\t{f[1]:.3f}"
              f"\t{f[1] / b[1]:.3f}\t{same}", flush=True)


if __name__ == "__main__":
    main()
