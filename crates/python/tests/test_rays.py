"""Ray queries against `aperture bench-rays`: its generated ray sets (saved with --save-rays)
get from scene.intersect / scene.occluded the hit counts bench-rays reports, camera_rays
gives its primary rays bit for bit, and the answers agree with each other."""

import csv

import numpy as np
import pytest

import aperture
from conftest import run_cli

WIDTH, LENS = 40, 2


@pytest.fixture(scope="module")
def bench(demo, aperture_bin, tmp_path_factory):
    """bench-rays' saved sets and its CSV rows {(set, query, mode, threads): hits}."""
    out = tmp_path_factory.mktemp("bench-rays")
    run_cli(aperture_bin, "bench-rays", demo, "--width", WIDTH, "--lens-samples", LENS,
            "--bvh-quality", "medium", "--repeats", "1", "--threads", "1",
            "--save-rays", out, "-o", out)
    with open(out / "bench-rays.csv") as f:
        rows = {(r["set"], r["query"], r["mode"], r["threads"]): int(r["hits"])
                for r in csv.DictReader(f)}
    return out, rows


def load_set(folder, name):
    """A .rays file (origins, directions) and its .tmax sidecar when there is one."""
    raw = np.fromfile(folder / f"{name}.rays", dtype="<f4").reshape(-1, 6)
    tmax_path = folder / f"{name}.tmax"
    tmax = np.fromfile(tmax_path, dtype="<f4") if tmax_path.exists() else np.inf
    return raw[:, :3], raw[:, 3:], tmax


@pytest.mark.parametrize("name", ["primary_tile", "primary_random", "diffuse", "shadow"])
def test_hits_equal_bench_rays(demo, bench, name):
    folder, rows = bench
    origins, directions, tmax = load_set(folder, name)
    assert len(origins) > 0
    scene = aperture.load(demo)
    hits = scene.intersect(origins, directions, tmax=tmax)
    blocked = scene.occluded(origins, directions, tmax=tmax)
    for mode in ("one-ray", "batch", "packet"):
        assert int(hits["hit"].sum()) == rows[(name, "closest", mode, "1")], mode
        assert int(blocked.sum()) == rows[(name, "occluded", mode, "1")], mode
    # A closest hit exists exactly where the segment is blocked.
    assert np.array_equal(hits["hit"], blocked)


def test_camera_rays_are_bench_rays_primary_rays(demo, bench):
    folder, _ = bench
    origins, directions, _ = load_set(folder, "primary_tile")
    rays = aperture.load(demo).camera_rays(WIDTH, lens_samples=LENS, seed=0)
    assert rays["origins"].dtype == np.float32
    assert np.array_equal(rays["origins"].view(np.uint32), origins.view(np.uint32))
    assert np.array_equal(rays["directions"].view(np.uint32), directions.view(np.uint32))
    assert rays["pixels"].shape == (len(origins), 2)
    assert set(np.unique(rays["samples"])) == set(range(LENS))


def test_hits_are_consistent(demo):
    scene = aperture.load(demo)
    rays = scene.camera_rays(32, lens_samples=2, seed=5)
    o, d = rays["origins"], rays["directions"]
    h = scene.intersect(o, d)
    hit = h["hit"]
    assert 0 < hit.sum() < len(hit)
    assert np.all(np.isinf(h["t"][~hit])) and np.all(h["primitive"][~hit] == -1)
    t = h["t"][hit]
    assert np.all(np.isfinite(t)) and np.all(t >= 0)
    u, v = h["u"][hit], h["v"][hit]
    assert np.all(u >= -1e-6) and np.all(v >= -1e-6) and np.all(u + v <= 1 + 1e-5)
    n = h["normal"][hit]
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5)
    info = scene.info()
    assert np.all(h["instance"][hit] < info["instances"]) and np.all(h["mesh"][hit] < info["meshes"])
    # Nothing is closer than the closest hit: the segment up to just before it is clear.
    short = scene.occluded(o[hit], d[hit], tmax=t * 0.999)
    assert short.mean() < 0.01
    # And limiting tmax below the hit loses it; starting past it finds a farther one or none.
    capped = scene.intersect(o[hit], d[hit], tmax=t * 0.5)
    assert not capped["hit"].any() or np.all(capped["t"][capped["hit"]] <= t[capped["hit"]] * 0.5)
    beyond = scene.intersect(o[hit], d[hit], tmin=t * 1.001 + 1e-4)
    assert np.all(beyond["t"][beyond["hit"]] > t[beyond["hit"]])


def test_layouts_dtypes_and_threads_agree(demo):
    scene = aperture.load(demo)
    rays = scene.camera_rays(24, lens_samples=2, seed=1)
    o, d = rays["origins"], rays["directions"]
    base = scene.intersect(o, d)
    variants = [
        (np.asfortranarray(o), np.asfortranarray(d), {}),
        (o.astype(np.float64), d.astype(np.float64), {}),
        (np.asfortranarray(o.astype(np.float64)), d, {"threads": 1}),
        (o[::1], d, {"threads": 2}),
        (o.tolist(), d.tolist(), {}),
    ]
    for vo, vd, kw in variants:
        other = scene.intersect(vo, vd, **kw)
        for key in base:
            assert np.array_equal(base[key], other[key]), key
    # A strided view (every other ray) answers as those rays do.
    half = scene.intersect(o[::2], d[::2])
    assert np.array_equal(half["t"], base["t"][::2])


def test_outputs_own_their_data(demo):
    scene = aperture.load(demo)
    rays = scene.camera_rays(8, lens_samples=1)
    h = scene.intersect(rays["origins"], rays["directions"])
    for key, a in h.items():
        assert a.flags["C_CONTIGUOUS"] and a.flags["WRITEABLE"], key
        assert len(a) == len(rays["origins"])
    assert h["hit"].dtype == np.bool_ and h["t"].dtype == np.float32
    assert h["primitive"].dtype == np.int32 and h["normal"].shape == (len(h["t"]), 3)


def test_many_tasks_agree_and_bad_rays_are_named_exactly(demo):
    """More rays than one worker's task (2048): every layout, thread count and bound form
    answers as the contiguous float32 call, and a bad ray deep in the array is the one named."""
    scene = aperture.load(demo)
    rays = scene.camera_rays(64, lens_samples=4, seed=2)
    o, d = rays["origins"], rays["directions"]
    assert len(o) > 3 * 2048
    base = scene.intersect(o, d, threads=1)
    t = np.where(base["hit"], base["t"], 1.0).astype(np.float32)
    for vo, vd, kw in [
        (o, d, {}),
        (np.asfortranarray(o.astype(np.float64)), d, {"threads": 2}),
        (o, d, {"tmin": np.zeros(len(o), np.float32), "tmax": np.full(len(o), np.inf)}),
    ]:
        other = scene.intersect(vo, vd, **kw)
        for key in base:
            assert np.array_equal(base[key], other[key]), key
    assert np.array_equal(scene.occluded(o, d, threads=1), base["hit"])
    assert np.array_equal(scene.occluded(o, d, tmax=t * 0.5), scene.occluded(o, d, tmax=t * 0.5, threads=1))
    bad_o, bad_d = o.copy(), d.copy()
    bad_o[5000, 1] = np.nan
    bad_d[100] = 0.0
    bad_d[6000, 2] = np.inf
    for threads in (1, None):
        with pytest.raises(ValueError, match=r"origins\[5000\]"):
            scene.intersect(bad_o, bad_d, threads=threads)
        with pytest.raises(ValueError, match=r"directions\[100\]"):
            scene.occluded(o, bad_d, threads=threads)
