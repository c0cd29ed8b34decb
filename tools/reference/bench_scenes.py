#!/usr/bin/env python3
"""Time to an RMSE target on three scenes we did not tune for: aperture, Mitsuba 3 and Cycles.

Issue 18. Each scene is defined once, below, as plain data (meshes, objects with a diffuse
albedo or a base-colour texture, emissive quads, point lights, a constant environment, a
thin-lens camera). From that one definition the script writes

* the glTF for aperture (``assets/bench/outdoor_dof.gltf``, small, committed; the others into
  ``OUT/scenes/``: the 560 k-triangle interior is generated, the helmet is a derived file with
  copies of its base-colour textures),
* the Mitsuba 3 scene (PLY meshes in ``OUT/scenes/ply/``, built with ``make_reference``'s
  sensor and conventions),
* the Cycles scene: Blender imports the same glTF, then the materials become Diffuse BSDFs (of
  the base colour or its image texture, plus Emission), lights radius 0, camera and thin lens
  set from the definition, world = the environment, ``cycles_settings.unbiased`` with 6 bounces.

For each renderer a series: a reference of two independent halves (``rmse(a, b) / 2`` is its
noise RMSE), then per spp budget the median *render-only* time of ``--repeats`` renders, with
RMSE / rel. MSE / MAE against that renderer's own reference. ``all`` keeps one process per
renderer loaded and alternates them, round by round within each budget, the rounds spread over
``--sweeps`` passes through the budgets, so that a machine whose speed drifts during the run
(this one's moved by 15-40 % within an hour) moves all three alike, and all budgets
(``series`` times one renderer alone); each timed render waits ``--settle`` seconds first, so
that no other renderer's worker threads still spin. Written as
``OUT/<scene>/<renderer>.csv`` in the columns of ``aperture bench``'s results.csv (usable with
``aperture bench --series``). ``summary`` prints time to each RMSE target, the ratios and the
per-sample costs. See README.md ("Three more scenes").

    bench_scenes.py all -o OUT [--scenes a,b,c] [--spp 1,2,...] [--reference-spp N] ...
    bench_scenes.py write -o OUT          # scene files only
    bench_scenes.py summary -o OUT        # the table, from the CSVs
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench_mitsuba as bm  # noqa: E402  (render in passes, metrics, the CSV writer)
import make_reference as mr  # noqa: E402  (glTF writer, meshes, matrices, Mitsuba sensor)
from bench_renderers import (DENOISE_DEFAULT, aperture_renderer, cycles_renderer,  # noqa: E402
                             mitsuba_renderer)

REPO = mr.REPO
WIDTH, HEIGHT = 320, 240
SCENES = ["outdoor_dof", "interior_500k", "flight_helmet"]
RENDERERS = ["aperture", "mitsuba", "cycles"]
HELMET = os.path.normpath(os.path.join(REPO, "..", "shared", "gltf-samples", "benchmark",
                                       "FlightHelmet", "FlightHelmet.gltf"))
MITSUBA_PY = os.path.expanduser("~/.cache/aperture/mitsuba-venv/bin/python")
BPY_PY = os.path.expanduser("~/.cache/aperture/bpy-5.0.1/bin/python")
REFERENCE_SEEDS = (1000, 1001)
EMBED_LIMIT = 2_000_000  # bytes of geometry above which the glTF is not committed

# --------------------------------------------------------------------------------------------
# Meshes: dicts of NumPy arrays pos (N,3), nrm (N,3), idx (3M,), optional uv (N,2).


def mesh(pos, nrm, idx, uv=None):
    m = {"pos": np.asarray(pos, np.float32).reshape(-1, 3), "nrm": np.asarray(nrm, np.float32).reshape(-1, 3),
         "idx": np.asarray(idx, np.uint32).reshape(-1)}
    if uv is not None:
        m["uv"] = np.asarray(uv, np.float32).reshape(-1, 2)
    return m


def sphere_mesh(segments, rings):
    return mesh(*mr.uv_sphere(segments, rings))


def torus_mesh(major, minor, nu, nv):
    """Torus around +Y: nu segments around the ring, nv around the tube; ccw from outside."""
    u = np.linspace(0, 2 * np.pi, nu + 1)[:, None]
    v = np.linspace(0, 2 * np.pi, nv + 1)[None, :]
    cx, cz = np.cos(u), -np.sin(u)
    n = np.stack(np.broadcast_arrays(np.cos(v) * cx, np.sin(v), np.cos(v) * cz), -1).reshape(-1, 3)
    ring = np.stack(np.broadcast_arrays(major * cx, 0 * v, major * cz), -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a, b = i * (nv + 1) + j, (i + 1) * (nv + 1) + j
    idx = np.stack([a, b, a + 1, a + 1, b, b + 1], -1).reshape(-1)
    return mesh(ring + minor * n, n, idx)


def triangles(scene):
    return sum(len(scene["meshes"][o["mesh"]]["idx"]) // 3 for o in scene["objects"])


def obj(name, mesh_key, matrix, albedo=(0.7, 0.7, 0.7), texture=None, emission=None):
    return {"name": name, "mesh": mesh_key, "matrix": matrix, "albedo": albedo, "texture": texture,
            "emission": emission}


def camera(eye, target, yfov_deg, radius, focus_point):
    """Thin lens focused on the plane through `focus_point` (distance along the view axis)."""
    fwd = mr.normalize([t - e for t, e in zip(target, eye)])
    focus = sum(f * (p - e) for f, p, e in zip(fwd, focus_point, eye))
    return {"eye": eye, "target": target, "up": (0.0, 1.0, 0.0), "yfov_deg": yfov_deg,
            "dof": {"aperture_radius": radius, "focus_distance": focus}}


def basic_meshes():
    return {"quad": mesh(mr.QUAD_POS, mr.QUAD_NRM, mr.QUAD_IDX), "cube": mesh(mr.CUBE_POS, mr.CUBE_NRM, mr.CUBE_IDX)}


# --------------------------------------------------------------------------------------------
# The three scenes.


def outdoor_dof():
    """(a) Open scene: ground, three spheres (one shared 128 x 64 mesh), two boxes and a torus at
    depths from 2 to 12 m, one point light, black environment; the lens is focused on the torus."""
    meshes = {**basic_meshes(), "sphere": sphere_mesh(128, 64), "torus": torus_mesh(1.0, 0.3, 96, 48)}
    t = mr.trs
    objects = [
        obj("ground", "quad", t(rx=-90, s=(14, 14, 1)), (0.6, 0.6, 0.55)),
        obj("sphere_near", "sphere", t((-1.3, 0.45, 3.4), s=(0.45,) * 3), (0.8, 0.25, 0.15)),
        obj("sphere_mid", "sphere", t((1.7, 0.7, -0.8), s=(0.7,) * 3), (0.2, 0.45, 0.8)),
        obj("sphere_far", "sphere", t((-2.4, 1.1, -5.0), s=(1.1,) * 3), (0.85, 0.8, 0.3)),
        obj("box_left", "cube", t((-2.6, 0.5, 1.0), ry=30, s=(0.5, 0.5, 0.5)), (0.3, 0.7, 0.3)),
        obj("box_tall_far", "cube", t((2.8, 1.5, -4.0), ry=-20, s=(0.4, 1.5, 0.4)), (0.8, 0.8, 0.8)),
        obj("torus_focus", "torus", t((0.0, 0.75, 1.0), ry=35, rx=70, s=(0.6,) * 3), (0.75, 0.55, 0.7)),
    ]
    return {"name": "outdoor_dof", "meshes": meshes, "objects": objects, "env": None,
            "points": [{"position": (3.0, 5.0, 4.0), "intensity": (60.0, 56.0, 50.0)}],
            "camera": camera((0.6, 1.5, 7.5), (0.0, 0.8, 0.0), 40.0, 0.12, (0.0, 0.75, 1.0)),
            "gltf": os.path.join(REPO, "assets", "bench", "outdoor_dof.gltf")}


def room_objects():
    """The interior's shell: 8 x 3 x 8 m, the ceiling framing a 1.2 x 0.8 m hole that the
    emissive panel fills (so its back side, emitting upwards in aperture and Cycles, lights
    nothing in any renderer), and furniture boxes."""
    t, q = mr.trs, "quad"
    px, pz, hx, hz = 0.0, -1.5, 0.6, 0.4  # panel centre and half sizes
    ceiling = [((-4 + px - hx) / 2, -1.0, (px - hx + 4) / 2, 4.0),    # left strip: x centre, z, x half, z half
               ((4 + px + hx) / 2, -1.0, (4 - px - hx) / 2, 4.0),
               (px, (pz - hz - 5) / 2, hx, (pz - hz + 5) / 2),
               (px, (pz + hz + 3) / 2, hx, (3 - pz - hz) / 2)]
    shell = [obj("floor", q, t((0, 0, -1), rx=-90, s=(4, 4, 1)), (0.55, 0.5, 0.45)),
             obj("wall_back", q, t((0, 1.5, -5), s=(4, 1.5, 1)), (0.7, 0.7, 0.7)),
             obj("wall_front", q, t((0, 1.5, 3), ry=180, s=(4, 1.5, 1)), (0.6, 0.65, 0.7)),
             obj("wall_left", q, t((-4, 1.5, -1), ry=90, s=(4, 1.5, 1)), (0.75, 0.35, 0.3)),
             obj("wall_right", q, t((4, 1.5, -1), ry=-90, s=(4, 1.5, 1)), (0.3, 0.5, 0.7))]
    shell += [obj(f"ceiling_{k}", q, t((x, 3.0, z), rx=90, s=(sx, sz, 1)), (0.8, 0.8, 0.8))
              for k, (x, z, sx, sz) in enumerate(ceiling)]
    shell.append(obj("panel", q, t((px, 3.0, pz), rx=90, s=(hx, hz, 1)), (0, 0, 0), emission=(9.0, 8.5, 7.5)))
    boxes = [("table_top", (0.0, 0.75, -2.2), (1.2, 0.04, 0.6)), ("shelf", (-3.6, 1.0, -3.5), (0.35, 1.0, 1.0)),
             ("cabinet", (3.4, 0.45, -4.2), (0.5, 0.45, 0.6)), ("stool", (-1.6, 0.25, -0.6), (0.25, 0.25, 0.25))]
    boxes += [(f"table_leg_{i}", (sx * 1.1, 0.355, -2.2 + sz * 0.5), (0.04, 0.355, 0.04))
              for i, (sx, sz) in enumerate([(-1, -1), (1, -1), (-1, 1), (1, 1)])]
    shell += [obj(n, "cube", t(c, s=s), (0.6, 0.45, 0.3)) for n, c, s in boxes]
    return shell


def interior_500k():
    """(b) Closed room, camera inside: five UV spheres and five tori, each its own mesh of about
    55 k triangles (562 k in the scene), on and around furniture; lit by the ceiling panel and
    one point light; thin lens focused on the sphere on the table."""
    meshes = basic_meshes()
    objects = room_objects()
    places = [((0.0, 1.04, -2.2), 0.25), ((-2.2, 0.45, -3.6), 0.45), ((2.3, 0.6, -2.4), 0.6),
              ((-0.9, 0.3, 0.4), 0.3), ((1.2, 0.35, -0.2), 0.35)]
    colours = [(0.8, 0.3, 0.2), (0.3, 0.7, 0.35), (0.25, 0.4, 0.8), (0.85, 0.8, 0.3), (0.7, 0.7, 0.75),
               (0.6, 0.3, 0.7), (0.3, 0.75, 0.75), (0.9, 0.55, 0.3), (0.5, 0.5, 0.5), (0.8, 0.45, 0.6)]
    for k, (c, r) in enumerate(places):
        meshes[f"sphere{k}"] = sphere_mesh(236 + 2 * k, 118)
        objects.append(obj(f"sphere{k}", f"sphere{k}", mr.trs(c, s=(r,) * 3), colours[k]))
    for k, (c, ry, rx) in enumerate([((-1.0, 0.84, -2.3), 20, 90), ((0.8, 1.0, -2.1), -30, 60),
                                      ((-2.8, 1.6, -1.0), 60, 20), ((2.6, 1.9, -4.4), 10, 80),
                                      ((0.3, 0.2, -4.2), 0, 0)]):
        meshes[f"torus{k}"] = torus_mesh(1.0, 0.3, 240 + 2 * k, 115)
        objects.append(obj(f"torus{k}", f"torus{k}", mr.trs(c, ry=ry, rx=rx, s=(0.2 + 0.05 * k,) * 3),
                           colours[5 + k]))
    return {"name": "interior_500k", "meshes": meshes, "objects": objects, "env": None,
            "points": [{"position": (2.6, 2.5, -0.5), "intensity": (6.0, 5.5, 5.0)}],
            "camera": camera((1.2, 1.7, 2.6), (-0.2, 0.9, -2.6), 55.0, 0.04, (0.0, 1.04, -2.2)),
            "gltf": None}


def gltf_accessor(doc, blob, index):
    """Accessor `index` of a glTF with one binary buffer, as a NumPy array (tightly packed)."""
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    dtype = {5126: np.float32, 5125: np.uint32, 5123: np.uint16, 5121: np.uint8}[acc["componentType"]]
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[acc["type"]]
    assert view.get("byteStride", width * np.dtype(dtype).itemsize) == width * np.dtype(dtype).itemsize
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    return np.frombuffer(blob, dtype, acc["count"] * width, start).reshape(-1, width)


def flight_helmet():
    """(c) The FlightHelmet sample (94 k triangles, five 512 x 512 base-colour textures) under a
    uniform sky, no ground. Only what all three renderers can do the same way is kept: positions,
    normals, TEXCOORD_0 and the base-colour texture (sRGB, bilinear) of each material, as a
    two-sided Lambertian; normal maps (Mitsuba's `normalmap` builds its own tangent frame),
    occlusion/metal-rough maps and the lenses' alpha blending are dropped. The derived glTF
    is written to OUT/scenes/ with copies of the five base-colour PNGs; nothing goes into the
    repository."""
    with open(HELMET) as f:
        doc = json.load(f)
    with open(os.path.join(os.path.dirname(HELMET), doc["buffers"][0]["uri"]), "rb") as f:
        blob = f.read()
    meshes, objects = {}, []
    for node in doc["nodes"]:
        assert not any(k in node for k in ("matrix", "translation", "rotation", "scale", "children"))
        for k, prim in enumerate(doc["meshes"][node["mesh"]]["primitives"]):
            a = prim["attributes"]
            key = f"{node['name']}_{k}"
            meshes[key] = mesh(*(gltf_accessor(doc, blob, a[n]) for n in ("POSITION", "NORMAL")),
                               gltf_accessor(doc, blob, prim["indices"]), gltf_accessor(doc, blob, a["TEXCOORD_0"]))
            pbr = doc["materials"][prim["material"]]["pbrMetallicRoughness"]
            image = doc["images"][doc["textures"][pbr["baseColorTexture"]["index"]]["source"]]["uri"]
            objects.append(obj(key, key, mr.trs(), tuple(pbr.get("baseColorFactor", [1, 1, 1])[:3]),
                               texture=os.path.join(os.path.dirname(HELMET), image)))
    return {"name": "flight_helmet", "meshes": meshes, "objects": objects, "env": (0.9, 0.95, 1.0),
            "points": [], "camera": camera((0.45, 0.55, 1.15), (0.0, 0.37, 0.0), 36.0, 0.012, (0.0, 0.4, 0.12)),
            "gltf": None}


def scene_def(name):
    return {"outdoor_dof": outdoor_dof, "interior_500k": interior_500k, "flight_helmet": flight_helmet}[name]()


# --------------------------------------------------------------------------------------------
# glTF for aperture (and for Blender's importer).


def local_texture(path, gltf_dir):
    """A copy of a texture in `gltf_dir`/textures/ (aperture refuses URIs that leave the scene's
    folder), as the URI to write."""
    import shutil
    dst = os.path.join(gltf_dir, "textures", os.path.basename(path))
    os.makedirs(os.path.dirname(dst), exist_ok=True)
    if not os.path.exists(dst):
        shutil.copyfile(path, dst)
    return "textures/" + os.path.basename(path)


def gltf_materials(scene, gltf_dir):
    """One material per object; images copied beside the glTF file."""
    materials, images = [], []
    for o in scene["objects"]:
        if o["emission"]:
            mat = mr.gltf_emissive(o["name"], o["emission"])
            mat["extensions"]["KHR_materials_specular"] = {"specularFactor": 0.0}
        else:
            mat = mr.gltf_diffuse(o["name"], o["albedo"])
        if o["texture"]:
            uri = local_texture(o["texture"], gltf_dir)
            if uri not in images:
                images.append(uri)
            mat["pbrMetallicRoughness"]["baseColorTexture"] = {"index": images.index(uri)}
        mat["doubleSided"] = True
        materials.append(mat)
    textures = {
        "images": [{"uri": u} for u in images],
        # Bilinear both ways, no mipmaps (what every renderer here does), repeat.
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497, "wrapT": 10497}],
        "textures": [{"sampler": 0, "source": i} for i in range(len(images))],
    } if images else {}
    return materials, textures


def gltf_geometry(scene):
    """Buffer contents and the primitive attributes of each mesh (uint32 indices)."""
    buf, views, accessors, add = mr.gltf_buffers()
    prims = {}
    for key, m in scene["meshes"].items():
        p = add(m["pos"].astype("<f4").tobytes(), 34962, 5126, len(m["pos"]), "VEC3",
                (m["pos"].min(0).tolist(), m["pos"].max(0).tolist()))
        attrs = {"POSITION": p, "NORMAL": add(m["nrm"].astype("<f4").tobytes(), 34962, 5126, len(m["nrm"]), "VEC3")}
        if "uv" in m:
            attrs["TEXCOORD_0"] = add(m["uv"].astype("<f4").tobytes(), 34962, 5126, len(m["uv"]), "VEC2")
        prims[key] = (attrs, add(m["idx"].astype("<u4").tobytes(), 34963, 5125, len(m["idx"]), "SCALAR"))
    return buf, views, accessors, prims


def write_gltf(scene, path):
    """The scene as glTF: geometry embedded when small, else in `<stem>.bin` beside it."""
    buf, views, accessors, prims = gltf_geometry(scene)
    materials, textures = gltf_materials(scene, os.path.dirname(os.path.abspath(path)))
    meshes = [{"name": o["name"], "primitives": [{"attributes": prims[o["mesh"]][0], "indices": prims[o["mesh"]][1],
                                                  "material": i}]} for i, o in enumerate(scene["objects"])]
    nodes = [{"name": o["name"], "mesh": i, "matrix": mr.column_major(o["matrix"])} for i, o in enumerate(scene["objects"])]
    lights = [mr.gltf_point_light(f"point{i}", p["intensity"]) for i, p in enumerate(scene["points"])]
    nodes += [{"name": f"point{i}", "translation": list(p["position"]), "extensions": {"KHR_lights_punctual": {"light": i}}}
              for i, p in enumerate(scene["points"])]
    cam = scene["camera"]
    nodes.append({"name": "camera", "camera": 0,
                  "matrix": mr.column_major(mr.gltf_camera_matrix(cam["eye"], cam["target"], cam["up"]))})
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    if len(buf) <= EMBED_LIMIT:
        geometry = mr.gltf_buffer_entries(buf, views, accessors)
    else:
        stem = os.path.splitext(os.path.basename(path))[0]
        with open(os.path.splitext(path)[0] + ".bin", "wb") as f:
            f.write(buf)
        geometry = {"accessors": accessors, "bufferViews": views, "buffers": [{"byteLength": len(buf), "uri": stem + ".bin"}]}
    doc = {
        "asset": {"version": "2.0", "generator": "aperture tools/reference/bench_scenes.py"},
        "extensionsUsed": ["KHR_materials_specular", "KHR_materials_emissive_strength", "KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"name": scene["name"], "nodes": list(range(len(nodes)))}],
        "nodes": nodes, "meshes": meshes, "materials": materials,
        "cameras": [{"name": "camera", "type": "perspective", "extras": dict(cam["dof"]),
                     "perspective": {"yfov": math.radians(cam["yfov_deg"]), "aspectRatio": WIDTH / HEIGHT, "znear": 0.01}}],
        **textures, **geometry,
    }
    mr.write_json(path, doc)
    return len(buf)


def gltf_path(scene, out):
    """Where the scene's glTF lives: assets/bench/ for the small committed one, else OUT/scenes/."""
    return scene["gltf"] or os.path.join(out, "scenes", scene["name"] + ".gltf")


# --------------------------------------------------------------------------------------------
# A series: reference, then per budget a first call and `repeats` timed renders.


def reference(render, spp, path):
    """Average of two independent halves; its noise RMSE is rmse(a, b) / 2. Saved as .npy + .json."""
    t0 = time.perf_counter()
    a, _ = render(spp // 2, REFERENCE_SEEDS[0], raw=True)
    b, _ = render(spp // 2, REFERENCE_SEEDS[1], raw=True)
    ref = 0.5 * (a + b)
    meta = {"spp": spp, "noise_rmse": float(np.sqrt(np.mean((a - b) ** 2)) / 2.0),
            "mean_rgb": ref.reshape(-1, 3).mean(0).tolist(), "seconds": time.perf_counter() - t0}
    np.save(path + ".npy", ref.astype(np.float32))
    with open(path + ".json", "w") as f:
        json.dump(meta, f, indent=1)
    print(f"  reference {spp} spp: {meta['seconds']:.1f} s, noise RMSE {meta['noise_rmse']:.3e}, "
          f"mean {[round(c, 5) for c in meta['mean_rgb']]}", flush=True)
    return ref


def series(render, label, args, size):
    out_dir = os.path.join(args.output, args.scene)
    os.makedirs(out_dir, exist_ok=True)
    ref = reference(render, args.reference_spp, os.path.join(out_dir, f"{label}_reference"))
    rows = []
    for spp in [int(s) for s in args.spp.split(",")]:
        _, first = render(spp, 1)
        times = []
        for r in range(args.repeats):
            img, secs = render(spp, 2 + r)
            times.append(secs)
            if sum(times) > args.repeat_seconds:
                break
        rows.append(series_row(label, spp, size, args.threads, times, first, bm.metrics(img, ref)))
    bm.write_series_csv(os.path.join(out_dir, f"{label}.csv"), rows)


def series_row(label, spp, size, threads, times, first, metrics):
    """One budget's CSV row (the median of `times`, the metrics of its last image), printed."""
    row = {"config": label, "spp": spp, "width": size[0], "height": size[1], "threads": threads,
           "seconds": statistics.median(times), "samples": spp * size[0] * size[1], "mean_spp": float(spp),
           **{m: metrics[m] for m in ("rmse", "rel_mse", "mae")}, "first_call_seconds": first}
    print(f"  {label:9} {spp:>5} spp: {row['seconds']:8.3f} s (median of {len(times)}; first {first:.3f} s), "
          f"RMSE {row['rmse']:.3e}", flush=True)
    return row


# --------------------------------------------------------------------------------------------
# Summary.


def read_rows(path):
    import csv
    with open(path) as f:
        return [{k: (v if k == "config" else float(v)) for k, v in r.items()} for r in csv.DictReader(f)]


def time_to_rmse(rows, target):
    """Seconds to reach `target`, log-log interpolated between the budgets that bracket it
    (as `aperture bench` does for rel. MSE); None when no two budgets bracket it."""
    pts = sorted((r["spp"], r["rmse"], r["seconds"]) for r in rows)
    for (_, e0, t0), (_, e1, t1) in zip(pts, pts[1:]):
        if e0 >= target >= e1 and e0 > e1:
            f = (math.log(e0) - math.log(target)) / (math.log(e0) - math.log(e1))
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0)))
    return None


def write_png(path, img, scale):
    """sRGB 8-bit PNG of a linear image times `scale`."""
    v = np.clip(img * scale, 0, 1)
    v = np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)
    rows = (v * 255 + 0.5).astype(np.uint8)
    with open(path, "wb") as f:
        f.write(mr.png_rgb8(rows.shape[1], rows.shape[0], [r.tobytes() for r in rows]))


def reference_check(name, d, refs):
    """Prints the references' means and agreement; writes them side by side as a PNG."""
    base = refs[RENDERERS[0]]["mean_rgb"] if RENDERERS[0] in refs else None
    for r, m in refs.items():
        diff = "" if base is None else "  vs aperture " + " ".join(f"{100 * (c / b - 1):+.2f}%" for c, b in zip(m["mean_rgb"], base))
        print(f"  {r:9} reference {m['spp']} spp: mean RGB {' '.join(f'{c:.5f}' for c in m['mean_rgb'])}, "
              f"noise RMSE {m['noise_rmse']:.3e}{diff}")
    imgs = [np.load(os.path.join(d, f"{r}_reference.npy")) for r in refs]
    scale = 0.35 / max(float(np.mean(imgs[0])), 1e-6)
    write_png(os.path.join(d, "references.png"), np.concatenate(imgs, 1), scale)
    print(f"  {os.path.join(d, 'references.png')}: {', '.join(refs)}, left to right (x{scale:.2f})")


def ceil2(x):
    """`x` rounded up to two significant digits (a target never below k x the noise)."""
    e = 10.0 ** (math.floor(math.log10(x)) - 1)
    return math.ceil(x / e - 1e-9) * e


def summarize_scene(name, out, multiples, explicit):
    d = os.path.join(out, name)
    rows = {r: read_rows(os.path.join(d, f"{r}.csv")) for r in RENDERERS if os.path.exists(os.path.join(d, f"{r}.csv"))}
    refs = {r: json.load(open(os.path.join(d, f"{r}_reference.json"))) for r in rows}
    if not rows:
        return
    w, h = int(next(iter(rows.values()))[0]["width"]), int(next(iter(rows.values()))[0]["height"])
    print(f"\n== {name} ({w}x{h})")
    reference_check(name, d, refs)
    worst = max(m["noise_rmse"] for m in refs.values())
    targets = explicit or [ceil2(k * worst) for k in multiples]
    head = "".join(f" {r + ' s':>11}" for r in rows) + "".join(f" {'ap/' + r[:3]:>7}" for r in rows if r != "aperture")
    print(f"  {'RMSE target':>11} {'worst ref/target':>16}{head}")
    for t in targets:
        secs = {r: time_to_rmse(v, t) for r, v in rows.items()}
        cells = "".join(f" {secs[r]:11.3f}" if secs[r] else f" {'-':>11}" for r in rows)
        ap = secs.get("aperture")
        ratios = "".join(f" {ap / secs[r]:7.2f}" if ap and secs[r] else f" {'-':>7}" for r in rows if r != "aperture")
        flag = "ok" if worst <= t / 4 else "REFERENCE TOO NOISY"
        print(f"  {t:11.3e} {worst / t:9.3f} {flag:>6}{cells}{ratios}")
    print("  cost per sample (ns per path at the largest budget): " + ", ".join(
        f"{r} {1e9 * v[-1]['seconds'] / v[-1]['samples']:.0f}" for r, v in rows.items())
        + "; RMSE^2 x spp there (noise per sample): " + ", ".join(
        f"{r} {v[-1]['rmse'] ** 2 * v[-1]['spp']:.3e}" for r, v in rows.items()))


def summary(args):
    explicit = {}
    for t in args.target or []:
        scene, values = t.split("=")
        explicit[scene] = [float(v) for v in values.split(",")]
    multiples = [float(k) for k in args.target_multiples.split(",")]
    for name in args.scenes.split(","):
        summarize_scene(name, args.output, multiples, explicit.get(name))


# --------------------------------------------------------------------------------------------
# Command line.


def write(args):
    for name in args.scenes.split(","):
        scene = scene_def(name)
        path = gltf_path(scene, args.output)
        size = write_gltf(scene, path)
        print(f"wrote {os.path.relpath(path)} ({triangles(scene)} triangles, {size / 1e6:.1f} MB of geometry)", flush=True)


def make_renderer(args, tmp):
    """The render(spp, seed) of `args.renderer` on `args.scene`, and the image size."""
    scene = scene_def(args.scene)
    gltf = os.path.abspath(gltf_path(scene, args.output))
    size = tuple(int(v) for v in args.size.split("x"))
    if args.renderer == "mitsuba":
        return mitsuba_renderer(scene, args.output, size, args.threads, args.variant), size
    if args.renderer == "cycles":
        return cycles_renderer(scene, gltf, size, args.threads, tmp,
                               denoise_settings(args, args.cycles_denoise_settings)), size
    return aperture_renderer(scene, gltf, args.aperture, size, args.threads, tmp, args.bvh_quality,
                             denoise_settings(args, args.denoise_settings)), size


def denoise_settings(args, text):
    """(prefilter, quality) from "PREFILTER,QUALITY" when --denoise, else None."""
    if not args.denoise:
        return None
    prefilter, quality = text.lower().split(",")
    return prefilter, quality


def run_series(args):
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        render, size = make_renderer(args, tmp)
        series(render, args.renderer, args, size)


def run_worker(args):
    """One renderer kept loaded for `all`: its reference first, then a render per line "SPP SEED"
    on stdin, answered on file descriptor `--result-fd` (the renderers print on stdout) with a
    JSON line: seconds and the metrics against the reference."""
    import tempfile
    answer = os.fdopen(args.result_fd, "w")
    with tempfile.TemporaryDirectory() as tmp:
        render, size = make_renderer(args, tmp)
        out_dir = os.path.join(args.output, args.scene)
        os.makedirs(out_dir, exist_ok=True)
        ref = reference(render, args.reference_spp, os.path.join(out_dir, f"{args.renderer}_reference"))
        answer.write(json.dumps({"size": size}) + "\n")
        answer.flush()
        for line in sys.stdin:
            spp, seed = (int(v) for v in line.split())
            img, secs = render(spp, seed)
            answer.write(json.dumps({"seconds": secs, **bm.metrics(img, ref)}) + "\n")
            answer.flush()


class Worker:
    """A `worker` process of one renderer on one scene."""

    def __init__(self, renderer, name, args, python):
        read, write_end = os.pipe()
        cmd = [python, os.path.abspath(__file__), "worker", "--renderer", renderer, "--scene", name,
               "-o", args.output, "--reference-spp", str(args.reference_spp), "--threads", str(args.threads),
               "--size", args.size, "--aperture", args.aperture, "--variant", args.variant,
               "--bvh-quality", args.bvh_quality, "--result-fd", str(write_end),
               "--denoise-settings", args.denoise_settings,
               "--cycles-denoise-settings", args.cycles_denoise_settings,
               *(["--denoise"] if args.denoise else [])]
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, text=True, pass_fds=(write_end,))
        os.close(write_end)
        self.answers = os.fdopen(read)
        self.size = self._answer()["size"]

    def _answer(self):
        line = self.answers.readline()
        if not line:
            raise SystemExit(f"worker {self.proc.args[4]} ended (exit {self.proc.wait()})")
        return json.loads(line)

    def render(self, spp, seed):
        self.proc.stdin.write(f"{spp} {seed}\n")
        self.proc.stdin.flush()
        return self._answer()

    def close(self):
        self.proc.stdin.close()
        self.proc.wait()


def alternated_series(workers, name, args):
    """Per budget a first call of each renderer, then `repeats` rounds per budget in which every
    renderer renders once, in an order that rotates from round to round: a machine that speeds
    up or slows down during the run moves every renderer's times alike. The rounds are spread
    over `--sweeps` passes through all the budgets, so that a slow spell of the host falls on
    several budgets rather than all of one budget's renders (a renderer's time to a target
    weighs the budgets around it unequally: aperture's loosest target on outdoor_dof leans on
    2 spp, Mitsuba's on 4). Writes each renderer's CSV."""
    budgets = [int(s) for s in args.spp.split(",")]
    order = list(workers)

    def render(r, spp, seed):
        # The other renderers' thread pools must be asleep: Dr.Jit's workers spin on after a
        # render, and a render started at once shares the two cores with them (outdoor_dof,
        # 2 spp: aperture took 33.3 ms right after Mitsuba, 28.0 ms after a 0.3 s pause).
        time.sleep(args.settle)
        return workers[r].render(spp, seed)

    first = {spp: {r: render(r, spp, 1)["seconds"] for r in workers} for spp in budgets}
    times = {spp: {r: [] for r in workers} for spp in budgets}
    last = {spp: {} for spp in budgets}
    sweeps = max(1, min(args.sweeps, args.repeats))
    for sweep in range(sweeps):
        for spp in budgets:
            done = len(times[spp][order[0]])
            # Rounds up to this sweep's share of `repeats`; none once a budget's renders add up
            # to `repeat_seconds` for every renderer.
            for k in range(done, args.repeats * (sweep + 1) // sweeps):
                if k and min(sum(t) for t in times[spp].values()) > args.repeat_seconds:
                    break
                for r in order[k % len(order):] + order[:k % len(order)]:
                    last[spp][r] = render(r, spp, 2 + k)
                    times[spp][r].append(last[spp][r]["seconds"])
    rows = {r: [] for r in workers}
    for spp in budgets:
        for r, w in workers.items():
            rows[r].append(series_row(r, spp, w.size, args.threads, times[spp][r], first[spp][r], last[spp][r]))
    for r, v in rows.items():
        bm.write_series_csv(os.path.join(args.output, name, f"{r}.csv"), v)


def run_all(args):
    """Scene files, then per scene one worker per renderer (each computes its reference, then
    waits), the alternated series, then the summary."""
    write(args)
    python = {"aperture": args.mitsuba_python, "mitsuba": args.mitsuba_python, "cycles": args.blender_python}
    t0 = time.time()
    for name in args.scenes.split(","):
        workers = {}
        try:
            for renderer in [r for r in RENDERERS if r in args.renderers.split(",")]:
                print(f"== {name}: {renderer} reference ({time.time() - t0:.0f} s so far)", flush=True)
                workers[renderer] = Worker(renderer, name, args, python[renderer])
            print(f"== {name}: alternated series ({time.time() - t0:.0f} s so far)", flush=True)
            alternated_series(workers, name, args)
        finally:
            for w in workers.values():
                w.close()
    print(f"== all series in {time.time() - t0:.0f} s")
    summary(args)


def parser():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("command", choices=["all", "write", "series", "worker", "summary"])
    ap.add_argument("-o", "--output", default="bench-out/scenes")
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--renderers", default=",".join(RENDERERS))
    ap.add_argument("--spp", default="1,2,4,8,16,32,64,128", help="budgets, comma separated")
    ap.add_argument("--reference-spp", type=int, default=1024, help="per renderer, two halves")
    ap.add_argument("--repeats", type=int, default=3, help="timed renders per budget (median), after a first call")
    ap.add_argument("--repeat-seconds", type=float, default=10.0,
                    help="stop repeating a budget once its timed renders add up to this")
    ap.add_argument("--sweeps", type=int, default=3,
                    help="all: passes through the budgets that the repeats are spread over")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--settle", type=float, default=0.3,
                    help="seconds of pause before each timed render, so that no renderer's workers still spin")
    ap.add_argument("--size", default=f"{WIDTH}x{HEIGHT}", help="WxH (smaller for smoke runs)")
    ap.add_argument("--aperture", default=os.path.join(REPO, "target", "release", "aperture"))
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant")
    ap.add_argument("--bvh-quality", default="medium", help="aperture's --bvh-quality (bench's default)")
    ap.add_argument("--mitsuba-python", default=MITSUBA_PY)
    ap.add_argument("--blender-python", default=BPY_PY)
    ap.add_argument("--target-multiples", default="4,8,16",
                    help="RMSE targets as multiples of the noisiest reference's noise RMSE")
    ap.add_argument("--target", action="append", help="SCENE=RMSE,RMSE...: explicit targets (repeatable)")
    ap.add_argument("--denoise", action="store_true",
                    help="budgets denoised (aperture --denoise; Cycles' OIDN, albedo+normal), "
                         "references not: the error of a denoised image against the truth")
    default = ",".join(DENOISE_DEFAULT)
    ap.add_argument("--denoise-settings", default=default,
                    help="with --denoise: aperture's PREFILTER,QUALITY (accurate|fast|none, "
                         "high|balanced|fast; default Cycles' own)")
    ap.add_argument("--cycles-denoise-settings", default=default,
                    help="with --denoise: Cycles' PREFILTER,QUALITY (default: F12's)")
    ap.add_argument("--scene", help="series: the scene")
    ap.add_argument("--renderer", choices=RENDERERS, help="series: the renderer")
    ap.add_argument("--result-fd", type=int, help="worker: where its answers go")
    return ap


def main():
    args = parser().parse_args()
    if args.reference_spp % 2:
        sys.exit("--reference-spp must be even (two halves)")
    commands = {"all": run_all, "write": write, "series": run_series, "worker": run_worker, "summary": summary}
    commands[args.command](args)


if __name__ == "__main__":
    main()
