#!/usr/bin/env python3
"""Whole-process time of `aperture render FILE` at 8x8, 1 spp (loading dominates) for two
binaries A and B, alternated: python3 tools/bench/load_time.py A B [ROUNDS]. Samples from
APERTURE_SAMPLES (default ../shared/gltf-samples)."""
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
S = os.environ.get("APERTURE_SAMPLES", os.path.join(HERE, "..", "..", "..", "shared", "gltf-samples")) + "/"
FILES = ["benchmark/StainedGlassLamp/StainedGlassLamp.gltf",
         "unsupported/StainedGlassLamp-KTX-BasisU/StainedGlassLamp.gltf",
         "compression/Avocado-Draco/Avocado.gltf",
         "benchmark/FlightHelmet/FlightHelmet.gltf",
         "benchmark/ToyCar/ToyCar.gltf",
         "materials/SheenCloth/SheenCloth.gltf",
         "compression/AnisotropyBarnLamp-KTX2-Basisu/AnisotropyBarnLamp.gltf"]
bins = sys.argv[1:3]
rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 5
def load_secs(b, f):
    t0 = time.perf_counter()
    o = subprocess.run([b, "render", S + f, "-o", os.path.join(os.environ.get("TMPDIR", "/tmp"), "aperture-load-time.exr"), "--width", "8", "--height", "8",
                        "--spp", "1", "--passes", "none", "--threads", "2", "--bvh-quality", "fast"],
                       capture_output=True, text=True)
    if o.returncode != 0:
        sys.exit(f"{b} {f}: {o.stderr[-400:]}")
    return time.perf_counter() - t0
tot = {b: 0.0 for b in bins}
for f in FILES:
    t = {b: [] for b in bins}
    for r in range(rounds):
        for b in (bins if r % 2 == 0 else bins[::-1]):
            t[b].append(load_secs(b, f))
    med = {b: statistics.median(v) for b, v in t.items()}
    for b in bins: tot[b] += med[b]
    print(f"{f.split('/')[-2]:40} " + "  ".join(f"{med[b]:.3f}" for b in bins) + f"  B/A {med[bins[1]]/med[bins[0]]:.3f}", flush=True)
print("total " + "  ".join(f"{tot[b]:.3f}" for b in bins) + f"  B/A {tot[bins[1]]/tot[bins[0]]:.3f}")
