"""Times Intel Embree (embreex) on ray files `aperture bench-rays --save-rays DIR` wrote, so
Embree and aperture trace the identical rays.

    python embree_time_rays.py SCENE.gltf DIR/primary_tile.rays [DIR/other.rays ...] [--repeats 5]

Triangles come from the Embree anchor's own loader (`../shared/tools/embree-anchor/gltf_io.py`,
found beside this repository, or at EMBREE_ANCHOR). A `.tmax` file beside a `.rays` file (the
shadow rays' finite tmax, which the raw format cannot carry) is passed as Embree's `tfar`, so the
shadow rays are the same queries on both sides. Embree runs `rtcIntersect1` / `rtcOccluded1` once
per ray on one thread (embreex's `run`). Prints one line per file and query: rays, hits, median,
min and max Mrays/s over the repeats.
"""
import argparse, os, sys, time
import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
anchor = os.environ.get("EMBREE_ANCHOR", os.path.join(here, "../../../shared/tools/embree-anchor"))
sys.path.insert(0, anchor)
import gltf_io  # noqa: E402
from embreex import rtcore_scene as rs  # noqa: E402
from embreex.mesh_construction import TriangleMesh  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("scene")
ap.add_argument("rays", nargs="+")
ap.add_argument("--repeats", type=int, default=5)
a = ap.parse_args()

sc = gltf_io.GltfScene(a.scene)
tris = np.concatenate([m["positions"][m["indices"]] for m in sc.meshes], 0)
tris = np.asarray(tris, dtype=np.float32).reshape(-1, 3, 3)
t0 = time.perf_counter()
scene = rs.EmbreeScene()
TriangleMesh(scene, tris)
scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))  # commit (builds the BVH)
print(f"{a.scene}: {len(tris)} triangles, build {time.perf_counter() - t0:.3f} s")

for path in a.rays:
    raw = np.fromfile(path, dtype="<f4")
    if raw.size % 6:
        sys.exit(f"{path}: {raw.size * 4} bytes is not a whole number of 24-byte rays")
    raw = raw.reshape(-1, 6)
    o, d = np.ascontiguousarray(raw[:, :3]), np.ascontiguousarray(raw[:, 3:])
    tmax_path = os.path.splitext(path)[0] + ".tmax"
    dists = np.fromfile(tmax_path, dtype="<f4") if os.path.exists(tmax_path) else None
    n = len(o)
    for label, query in (("closest", "INTERSECT"), ("occluded", "OCCLUDED")):
        rates = []
        for _ in range(a.repeats):
            t0 = time.perf_counter()
            if query == "INTERSECT":
                res = scene.run(o, d, dists=dists, output=1)
            else:
                res = scene.run(o, d, dists=dists, query="OCCLUDED")
            rates.append(n / (time.perf_counter() - t0) / 1e6)
        if query == "INTERSECT":
            hits = int(np.sum(res["geomID"] >= 0))
        else:
            hits = int(np.sum(np.asarray(res) != -1))  # -1: not occluded
        rates.sort()
        print(f"{os.path.basename(path)} {label}: {n} rays, {hits} hits, "
              f"median {np.median(rates):.3f} [{rates[0]:.3f} {rates[-1]:.3f}] Mrays/s"
              f"{' (tmax from ' + os.path.basename(tmax_path) + ')' if dists is not None else ''}")
