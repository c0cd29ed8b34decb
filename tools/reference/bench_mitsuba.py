#!/usr/bin/env python3
"""Error against time of Mitsuba 3 on aperture's DOF benchmark scene, as an `aperture bench` series.

The scene is make_reference.py's ground and five boxes plus five finely tessellated UV spheres
(45 184 triangles in all), lit by both the area light of ``dof_area`` and the point light of
``dof_point``, seen through the same thin lens, at 320 x 240. From that one definition the
script writes

* ``assets/bench/dof_spheres.gltf`` -- the scene for aperture (``--write-gltf``; the spheres
  share one mesh, so the file stays small),
* ``OUT/mitsuba_reference.exr`` -- Mitsuba's high-spp reference (rendered in passes),
* ``OUT/mitsuba.csv`` -- one row per sample budget, in the columns of ``aperture bench``'s
  ``results.csv`` (``config,spp,width,height,threads,seconds,samples,mean_spp,rmse,rel_mse,mae``)
  plus ``first_call_seconds``; pass it to ``aperture bench --series OUT/mitsuba.csv``.

``seconds`` is the *warm* time: the median of ``--repeats`` renders after a first call at the
same budget, whose time (Dr.Jit tracing and LLVM compilation included) is ``first_call_seconds``.
Errors are those of the last warm render against the reference, with the metric definitions of
``crates/imageio/src/metrics.rs`` (relative MSE: mean over pixels and RGB of
``(x - y)^2 / (y^2 + 0.01)``).

Usage: ``python bench_mitsuba.py [--spp 1,2,4,...] [--reference-spp N] [--threads 2] [-o DIR]``
(see README.md).
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import statistics
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import make_reference as mr  # noqa: E402  (the shared scene definitions and helpers)

REPO = mr.REPO
GLTF_PATH = os.path.join(REPO, "assets", "bench", "dof_spheres.gltf")
WIDTH, HEIGHT = 320, 240
MAX_BOUNCES = mr.MAX_BOUNCES
# Largest budget rendered in one Mitsuba call: the llvm variant traces every sample of a call
# at once, so memory grows with spp x pixels; bigger budgets are summed over passes.
PASS_SPP = 256
# Must equal aperture's metrics::RELATIVE_MSE_EPSILON.
RELATIVE_MSE_EPSILON = 1e-2

# The same 96 x 48 UV sphere as the reference scenes.
SPHERE_POS, SPHERE_NRM, SPHERE_IDX = mr.SPHERE_POS, mr.SPHERE_NRM, mr.SPHERE_IDX
mr.check_winding(SPHERE_POS, SPHERE_IDX, SPHERE_NRM)


def spheres():
    """name, centre, radius, albedo: at several depths, so some are sharp and some blurred."""
    return [
        ("sphere_near", (-0.35, 0.35, 3.7), 0.35, (0.75, 0.75, 0.2)),
        ("sphere_focus", (0.95, 0.45, 0.9), 0.45, (0.7, 0.3, 0.6)),
        ("sphere_left", (-1.6, 0.7, -0.6), 0.7, (0.3, 0.6, 0.7)),
        ("sphere_far", (0.4, 0.8, -3.2), 0.8, (0.8, 0.5, 0.3)),
        ("sphere_small", (-0.9, 0.22, 1.4), 0.22, (0.9, 0.9, 0.9)),
    ]


def scene_def():
    defs = mr.scene_defs()
    return {
        "area": defs["dof_area"]["light"],
        "point": defs["dof_point"]["light"],
        "dof": defs["dof_area"]["dof"],
    }


def triangle_count():
    per_shape = {"quad": len(mr.QUAD_IDX) // 3, "cube": len(mr.CUBE_IDX) // 3}
    boxes = sum(per_shape[shape] for _, shape, _, _ in mr.base_objects())
    return boxes + len(spheres()) * len(SPHERE_IDX) // 3 + per_shape["quad"]  # + the area light


# --------------------------------------------------------------------------------------------
# glTF for aperture.


def write_gltf(path):
    sdef = scene_def()
    buf, views, accessors, add = mr.gltf_buffers()

    def add_shape(pos, nrm, idx):
        mins = [min(p[k] for p in pos) for k in range(3)]
        maxs = [max(p[k] for p in pos) for k in range(3)]
        p = add(mr.pack_f32([c for v in pos for c in v]), 34962, 5126, len(pos), "VEC3", (mins, maxs))
        n = add(mr.pack_f32([c for v in nrm for c in v]), 34962, 5126, len(nrm), "VEC3")
        i = add(mr.pack_u16(idx), 34963, 5123, len(idx), "SCALAR")
        return {"POSITION": p, "NORMAL": n}, i

    shapes = {
        "quad": add_shape(mr.QUAD_POS, mr.QUAD_NRM, mr.QUAD_IDX),
        "cube": add_shape(mr.CUBE_POS, mr.CUBE_NRM, mr.CUBE_IDX),
        "sphere": add_shape(SPHERE_POS, SPHERE_NRM, SPHERE_IDX),
    }
    materials, meshes, nodes = [], [], []

    def add_object(oname, shape, matrix, material):
        materials.append(material)
        attrs, ind = shapes[shape]
        meshes.append({"name": oname, "primitives": [{"attributes": attrs, "indices": ind, "material": len(materials) - 1}]})
        nodes.append({"name": oname, "mesh": len(meshes) - 1, "matrix": mr.column_major(matrix)})

    diffuse = mr.gltf_diffuse

    for oname, shape, matrix, albedo in mr.base_objects():
        add_object(oname, shape, matrix, diffuse(oname, albedo))
    for oname, centre, radius, albedo in spheres():
        add_object(oname, "sphere", mr.trs(centre, s=(radius, radius, radius)), diffuse(oname, albedo))

    area = sdef["area"]
    add_object("area_light", "quad", area["matrix"], mr.gltf_emissive("area_light", area["radiance"]))
    point = sdef["point"]
    nodes.append({
        "name": "point_light",
        "translation": list(point["position"]),
        "extensions": {"KHR_lights_punctual": {"light": 0}},
    })
    cam = {
        "name": "camera",
        "type": "perspective",
        "perspective": {"yfov": math.radians(mr.YFOV_DEG), "aspectRatio": WIDTH / HEIGHT, "znear": 0.01},
        "extras": dict(sdef["dof"]),
    }
    nodes.append({"name": "camera", "camera": 0, "matrix": mr.column_major(mr.gltf_camera_matrix(mr.EYE, mr.TARGET, mr.UP))})
    doc = {
        "asset": {"version": "2.0", "generator": "aperture tools/reference/bench_mitsuba.py"},
        "extensionsUsed": ["KHR_materials_specular", "KHR_materials_emissive_strength", "KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [mr.gltf_point_light("point", point["intensity"])]}},
        "scene": 0,
        "scenes": [{"name": "dof_spheres", "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [cam],
        **mr.gltf_buffer_entries(buf, views, accessors),
    }
    mr.write_json(path, doc)


# --------------------------------------------------------------------------------------------
# Mitsuba.


def mitsuba_scene(mi, ply, spp, seed):
    sdef = scene_def()
    # make_reference's dof_area scene (ground, boxes, area light, thin lens), resized, plus the
    # point light and the spheres.
    scene = mr.mitsuba_scene(mi, {"light": sdef["area"], "dof": sdef["dof"], "env": None}, spp, seed)
    scene["sensor"]["film"]["width"] = WIDTH
    scene["sensor"]["film"]["height"] = HEIGHT
    scene["point_light"] = {
        "type": "point",
        "position": list(sdef["point"]["position"]),
        "intensity": {"type": "rgb", "value": list(sdef["point"]["intensity"])},
    }
    T = mi.ScalarTransform4f
    for oname, centre, radius, albedo in spheres():
        scene[oname] = {
            "type": "ply",
            "filename": ply,
            "to_world": T(mr.trs(centre, s=(radius, radius, radius))),
            "bsdf": {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(albedo)}}},
        }
    return scene


def render(dr, mi, scene, spp, seed):
    """Renders `spp` samples per pixel (in passes of at most PASS_SPP) and returns the image
    as float64 RGB and the wall time, evaluation of the result included."""
    t0 = time.perf_counter()
    acc, done, k = None, 0, 0
    while done < spp:
        n = min(PASS_SPP, spp - done)
        img = mi.render(scene, spp=n, seed=seed * 4096 + k)
        dr.eval(img)
        dr.sync_thread()
        part = np.array(img, dtype=np.float64)[:, :, :3] * n
        acc = part if acc is None else acc + part
        done += n
        k += 1
    secs = time.perf_counter() - t0
    return acc / spp, secs


def metrics(img, ref):
    d = img - ref
    mse = float(np.mean(d * d))
    return {
        "rmse": math.sqrt(mse),
        "rel_mse": float(np.mean(d * d / (ref * ref + RELATIVE_MSE_EPSILON))),
        "mae": float(np.mean(np.abs(d))),
    }


def write_series_csv(path, rows):
    """Rows (dicts) in the columns of `aperture bench`'s results.csv, plus first_call_seconds."""
    cols = ["config", "spp", "width", "height", "threads", "seconds", "samples", "mean_spp",
            "rmse", "rel_mse", "mae", "first_call_seconds"]
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(cols)
        for r in rows:
            w.writerow([r["config"], r["spp"], r["width"], r["height"], r["threads"],
                        f"{r['seconds']:.6f}", r["samples"], f"{r['mean_spp']:.3f}",
                        f"{r['rmse']:.6e}", f"{r['rel_mse']:.6e}", f"{r['mae']:.6e}",
                        f"{r['first_call_seconds']:.6f}"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", default="1,2,4,8,16,32,64,128", help="sample budgets, comma separated")
    ap.add_argument("--reference-spp", type=int, default=4096)
    ap.add_argument("--threads", type=int, default=2, help="Dr.Jit worker threads (default 2)")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--repeats", type=int, default=3, help="warm renders per budget (median time)")
    ap.add_argument("-o", "--output", default="bench-out", help="folder of the CSV and the reference EXR")
    ap.add_argument("--reference", help="reuse this Mitsuba reference EXR instead of rendering one")
    ap.add_argument("--write-gltf", action="store_true", help="(re)write assets/bench/dof_spheres.gltf and stop")
    ap.add_argument("--label", default="mitsuba", help="the series' `config` column")
    args = ap.parse_args()
    budgets = [int(s) for s in args.spp.split(",")]

    if args.write_gltf:
        write_gltf(GLTF_PATH)
        print(f"wrote {os.path.relpath(GLTF_PATH, REPO)} ({os.path.getsize(GLTF_PATH)} bytes, "
              f"{triangle_count()} triangles)")
        return

    import drjit as dr
    import mitsuba as mi

    mi.set_variant(args.variant)
    dr.set_thread_count(args.threads)
    os.makedirs(args.output, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        ply = os.path.join(tmp, "sphere.ply")
        mr.write_ply(ply, SPHERE_POS, SPHERE_NRM, SPHERE_IDX)
        scene = mi.load_dict(mitsuba_scene(mi, ply, 1, 0))

        ref_path = os.path.join(args.output, "mitsuba_reference.exr")
        if args.reference:
            ref = np.array(mi.Bitmap(args.reference), dtype=np.float64)[:, :, :3]
        else:
            ref, secs = render(dr, mi, scene, args.reference_spp, seed=100_000)
            mi.Bitmap(ref.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB).write(ref_path)
            print(f"reference: {args.reference_spp} spp in {secs:.1f} s -> {ref_path}, mean RGB "
                  f"{[round(float(c), 5) for c in ref.reshape(-1, 3).mean(axis=0)]}", flush=True)

        rows = []
        for spp in budgets:
            _, first = render(dr, mi, scene, spp, seed=1)
            times = []
            for r in range(args.repeats):
                img, secs = render(dr, mi, scene, spp, seed=2 + r)
                times.append(secs)
            m = metrics(img, ref)
            row = {
                "config": args.label, "spp": spp, "width": WIDTH, "height": HEIGHT,
                "threads": args.threads, "seconds": statistics.median(times),
                "samples": spp * WIDTH * HEIGHT, "mean_spp": float(spp), **m,
                "first_call_seconds": first,
            }
            rows.append(row)
            print(f"{args.label} {spp:>6} spp: first {first:8.3f} s, warm {row['seconds']:8.3f} s "
                  f"(of {['%.3f' % t for t in times]}), relMSE {m['rel_mse']:.3e}", flush=True)

    out = os.path.join(args.output, f"{args.label}.csv")
    write_series_csv(out, rows)
    print(f"wrote {out} (Mitsuba {mi.__version__} {args.variant}, {args.threads} threads)")


if __name__ == "__main__":
    main()
