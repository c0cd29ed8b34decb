"""Issue 60's benchmarks (BENCHMARKS.md, "Python module"):

1. `scene.intersect` from numpy against embreex (`rtcore_scene.run(..., output=1)`) on the same
   rays (bench-rays' thin-lens primary rays from `scene.camera_rays`, in tile order and
   shuffled) and the same world-space triangles (`scene.triangles()`), on 1 thread and on all;
   each timing is the whole call from numpy arrays to numpy answers. Runs alternate between the
   two; medians are reported.
2. The per-call overhead of `scene.render` for a 64×64 1-spp image: the call's wall time less
   the render's own time (the header's `aperture:renderTime`, measured around the library's
   `Frame::render`), median of alternated runs.

    pip install embreex && maturin build --release -m crates/python/Cargo.toml (install it)
    python tools/python/bench.py [--scene assets/demo.glb] [--rays 1000000] [--reps 5]
"""

import argparse
import concurrent.futures
import os
import platform
import statistics
import time

import numpy as np
from embreex import rtcore_scene as rtcs
from embreex.mesh_construction import TriangleMesh

import aperture


def rays_for(scene, n, seed):
    """At least n of bench-rays' primary rays (16 lens samples a pixel), cut to n."""
    width = 64
    while True:
        r = scene.camera_rays(width, lens_samples=16, seed=seed)
        if len(r["origins"]) >= n:
            return np.ascontiguousarray(r["origins"][:n]), np.ascontiguousarray(r["directions"][:n])
        width = int(width * 1.5)


def embree_scene(scene):
    tris = scene.triangles()
    s = rtcs.EmbreeScene()
    TriangleMesh(s, tris["vertices"], tris["indices"])
    return s, tris


def embree_all(s, o, d, workers):
    """embreex on `workers` Python threads, one chunk each (its run loop is Cython)."""
    chunks = np.array_split(np.arange(len(o)), workers)
    with concurrent.futures.ThreadPoolExecutor(workers) as pool:
        parts = list(pool.map(lambda c: s.run(o[c], d[c], output=1), chunks))
    return parts


def timed(f):
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


def agreement(hits, emb, tris):
    """Share of rays where both agree on hit/miss, and on the triangle hit."""
    e_hit = emb["geomID"] != -1
    same_hit = np.mean(hits["hit"] == e_hit)
    both = hits["hit"] & e_hit
    # embreex's primID indexes the soup: its triangle k is (instance[k], primitive[k]).
    k = emb["primID"][both]
    same_tri = np.mean((tris["instance"][k] == hits["instance"][both])
                       & (tris["primitive"][k] == hits["primitive"][both]))
    t_err = np.max(np.abs(emb["tfar"][both] - hits["t"][both]) / hits["t"][both])
    return same_hit, same_tri, t_err


def bench_rays(scene, n, reps, order):
    o, d = rays_for(scene, n, 0)
    if order == "shuffled":
        p = np.random.default_rng(0).permutation(n)
        o, d = np.ascontiguousarray(o[p]), np.ascontiguousarray(d[p])
    emb, tris = embree_scene(scene)
    workers = os.cpu_count() or 1
    hits = scene.intersect(o, d, threads=1)
    ans = emb.run(o, d, output=1)
    same_hit, same_tri, t_err = agreement(hits, ans, tris)
    runs = {k: [] for k in ("ap1", "em1", "apN", "emN")}
    for _ in range(reps):
        runs["ap1"].append(timed(lambda: scene.intersect(o, d, threads=1)))
        runs["em1"].append(timed(lambda: emb.run(o, d, output=1)))
        runs["apN"].append(timed(lambda: scene.intersect(o, d)))
        runs["emN"].append(timed(lambda: embree_all(emb, o, d, workers)))
    mrays = {k: n / statistics.median(v) / 1e6 for k, v in runs.items()}
    print(f"| {order} | {n:,} | {len(tris['indices']):,} | 1 | {mrays['ap1']:.2f} | "
          f"{mrays['em1']:.2f} | {mrays['ap1'] / mrays['em1']:.2f}× |")
    print(f"| {order} | {n:,} | {len(tris['indices']):,} | {workers} | {mrays['apN']:.2f} | "
          f"{mrays['emN']:.2f} | {mrays['apN'] / mrays['emN']:.2f}× |")
    print(f"  (agreement: hit/miss {100 * same_hit:.3f} %, same triangle {100 * same_tri:.3f} %, "
          f"largest relative t difference {t_err:.2e}; hits {hits['hit'].mean():.3f})")


def bench_render(scene, reps):
    for passes in ([], "default"):
        walls, renders = [], []
        for _ in range(reps):
            t0 = time.perf_counter()
            r = scene.render(width=64, height=64, spp=1, passes=passes)
            walls.append(time.perf_counter() - t0)
            renders.append(r.header["aperture:renderTime"])
        over = [w - r for w, r in zip(walls, renders)]
        name = "none" if passes == [] else passes
        print(f"| 64×64, 1 spp, passes {name} | {1e3 * statistics.median(walls):.2f} ms | "
              f"{1e3 * statistics.median(renders):.2f} ms | "
              f"{1e3 * statistics.median(over):.2f} ms |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default="assets/demo.glb")
    ap.add_argument("--rays", type=int, default=1_000_000)
    ap.add_argument("--reps", type=int, default=5)
    args = ap.parse_args()
    scene = aperture.load(args.scene)
    print(f"{time.strftime('%Y-%m-%d')}, {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} threads, Python {platform.python_version()}, "
          f"aperture {aperture.__version__}, scene {args.scene}")
    print("| rays | N | triangles | threads | aperture Mrays/s | embreex Mrays/s | ratio |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for order in ("tile order", "shuffled"):
        bench_rays(scene, args.rays, args.reps, order)
    print("| render call | wall (median) | render (header) | overhead |")
    print("| --- | --- | --- | --- |")
    scene.render(width=64, height=64, spp=1)  # first render builds the energy tables
    bench_render(scene, max(args.reps, 51))


if __name__ == "__main__":
    main()
