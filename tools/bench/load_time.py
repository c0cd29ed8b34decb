#!/usr/bin/env python3
"""Whole-process time of `aperture render FILE` at 8x8, 1 spp (loading dominates) for two
binaries A and B, alternated, the median of ROUNDS each (issue 49: the cost of overflow checks
in the parsing crates):

    python3 tools/bench/load_time.py A B [ROUNDS]

Samples from APERTURE_SAMPLES (default ../shared/gltf-samples)."""

import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SAMPLES = os.environ.get("APERTURE_SAMPLES", os.path.join(HERE, "..", "..", "..", "shared", "gltf-samples"))
# The largest files and every decoder: PNG/JPEG, KTX2/Basis, Draco.
FILES = ["benchmark/StainedGlassLamp/StainedGlassLamp.gltf",
         "unsupported/StainedGlassLamp-KTX-BasisU/StainedGlassLamp.gltf",
         "compression/Avocado-Draco/Avocado.gltf",
         "benchmark/FlightHelmet/FlightHelmet.gltf",
         "benchmark/ToyCar/ToyCar.gltf",
         "materials/SheenCloth/SheenCloth.gltf",
         "compression/AnisotropyBarnLamp-KTX2-Basisu/AnisotropyBarnLamp.gltf"]


def seconds(binary, scene, out):
    """Wall time of one render of `scene` by `binary`."""
    t0 = time.perf_counter()
    run = subprocess.run([binary, "render", scene, "-o", out, "--width", "8", "--height", "8",
                          "--spp", "1", "--passes", "none", "--threads", "2", "--bvh-quality", "fast"],
                         capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"{binary} {scene}: {run.stderr[-400:]}")
    return time.perf_counter() - t0


def main():
    a, b = sys.argv[1:3]
    rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 5
    total = {a: 0.0, b: 0.0}
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "x.exr")
        for f in FILES:
            times = {a: [], b: []}
            for r in range(rounds):
                for binary in ((a, b) if r % 2 == 0 else (b, a)):
                    times[binary].append(seconds(binary, os.path.join(SAMPLES, f), out))
            med = {k: statistics.median(v) for k, v in times.items()}
            for k in total:
                total[k] += med[k]
            print(f"{f.split('/')[-2]:40} {med[a]:.3f}  {med[b]:.3f}  B/A {med[b] / med[a]:.3f}", flush=True)
    print(f"{'total':40} {total[a]:.3f}  {total[b]:.3f}  B/A {total[b] / total[a]:.3f}")


if __name__ == "__main__":
    main()
