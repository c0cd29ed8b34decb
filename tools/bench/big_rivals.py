#!/usr/bin/env python3
"""What the renderers users would pick instead of aperture pay on big scenes (issue 59): time
from command to first sample and peak memory of Blender Cycles and Mitsuba 3, on the GLB files
of tools/bench/big_scene.py, the median of ROUNDS fresh child processes each:

    python3 tools/bench/big_rivals.py [--rounds 3] [--renderers cycles,mitsuba]
        [--work /tmp/big_rivals] [--keep-work] [--mem-limit-gb G] [--threads 2]
        [--bpy-python ~/.cache/aperture/bpy-5.0.1/bin/python]
        [--mitsuba-python /tmp/mitsuba-venv/bin/python] FILE.glb...

Preparation, untimed and cached in --work (redone when the GLB is newer; about 3× the GLBs'
size, so a file's inputs are removed once it is measured unless --keep-work):
  cycles   Blender's glTF importer (bpy.ops.import_scene.gltf, default options, so no vertex
           merging) into an empty scene, saved as an uncompressed .blend.
  mitsuba  every mesh written as a binary PLY (float32 positions and normals, uint32 faces,
           world space of its node passed as to_world) plus a JSON of camera, sun and
           materials, parsed from the GLB here with struct and json.
Its time, peak RSS and output size are printed per file, to plan bigger scenes.

Timed, each in a fresh child, on CPU, 320x240, 1 spp, box filter, no denoiser, THREADS threads:
  cycles   `import bpy`, bpy.ops.wm.open_mainfile (the "open/load" column), then one
           bpy.ops.render.render() (F12; persistent data off, so it is scene sync + BVH build
           (Embree, Cycles' CPU BVH) + the one sample: the "first render" column; at 1 spp and
           320x240 the sampling itself is well under a second).
  mitsuba  `import mitsuba`, mi.set_variant('scalar_rgb') (the CPU variant that needs no LLVM
           JIT), dr.set_thread_count(THREADS), then mi.load_dict in two steps, together the
           "open/load" column: one `ply` shape per file (PLY parsing), then the scene of those
           shapes, whose construction builds the accel ("BVH" column: Embree 3, Mitsuba's
           default for scalar variants when built with it, as the pip wheels are, on a device
           of the pool's THREADS threads); then mi.render(scene, spp=1) ("first render"), then
           a second render ("again", sampling alone).
"start" is from the launch of the child to the renderer's module imported; "total" from the
launch to the end of the first render (command to first sample). Peak RSS is the child's
ru_maxrss (os.wait4); "B/tri" is peak RSS per triangle and "B/tri net" the same less the peak
RSS of a child that only imports the module (printed as the "import only" rows).

--mem-limit-gb G: a watcher thread reads the child's VmRSS in /proc/PID/status every 50 ms and
kills it past G GB (1 GB = 1e9 bytes); the table says "killed at G GB". (RLIMIT_AS would count
virtual reservations, which Embree and LLVM make far beyond what they touch.)

Standard library only; the children run under the renderers' own Pythons. Run it niced.
"""

import argparse
import json
import math
import os
import resource
import signal
import shutil
import statistics
import struct
import subprocess
import sys
import threading
import time
from array import array

HERE = os.path.abspath(__file__)
MARK = "BIG_RIVALS_JSON "
WIDTH, HEIGHT = 320, 240


# ---------------------------------------------------------------------------------------------
# Parent side: children, watcher, GLB to PLY.

def run_child(argv, limit_gb=None):
    """Runs `argv` with stdout and stderr merged; returns (result dict or None, peak RSS bytes,
    launch epoch, wall seconds, killed flag, output tail). The result is the child's last
    MARK line."""
    launch = time.time()
    t0 = time.perf_counter()
    p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                         errors="replace")
    done = threading.Event()
    killed = []

    def watch():
        limit_kb = limit_gb * 1e6
        path = f"/proc/{p.pid}/status"
        while not done.wait(0.05):
            try:
                with open(path) as f:
                    for line in f:
                        if line.startswith("VmRSS:"):
                            rss_kb = int(line.split()[1])
                            break
                    else:
                        continue
            except OSError:
                return
            if rss_kb > limit_kb and not done.is_set():
                killed.append(rss_kb)
                os.kill(p.pid, signal.SIGKILL)
                return

    watcher = None
    if limit_gb:
        watcher = threading.Thread(target=watch, daemon=True)
        watcher.start()
    out = p.stdout.read()
    _, status, usage = os.wait4(p.pid, 0)
    done.set()
    p.returncode = status
    wall = time.perf_counter() - t0
    if watcher:
        watcher.join()
    result = None
    for line in out.splitlines():
        if line.startswith(MARK):
            result = json.loads(line[len(MARK):])
    if status != 0 and not killed:
        sys.exit(f"{' '.join(argv)} failed ({status}):\n{out[-2000:]}")
    return result, usage.ru_maxrss * 1024, launch, wall, bool(killed), out[-2000:]


def quat_matrix(q):
    x, y, z, w = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def node_matrix(node):
    """The 4x4 row-major local matrix of a glTF node."""
    if "matrix" in node:
        m = node["matrix"]  # column-major
        return [[m[c * 4 + r] for c in range(4)] for r in range(4)]
    t = node.get("translation", [0.0, 0.0, 0.0])
    r = quat_matrix(node.get("rotation", [0.0, 0.0, 0.0, 1.0]))
    s = node.get("scale", [1.0, 1.0, 1.0])
    return [[r[i][0] * s[0], r[i][1] * s[1], r[i][2] * s[2], t[i]] for i in range(3)] + \
        [[0.0, 0.0, 0.0, 1.0]]


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


IDENTITY = [[float(i == j) for j in range(4)] for i in range(4)]


def read_glb(path):
    """The JSON of a GLB and the file offset of its BIN chunk's data."""
    with open(path, "rb") as f:
        magic, _, _ = struct.unpack("<4sII", f.read(12))
        if magic != b"glTF":
            sys.exit(f"{path}: not a GLB")
        length, kind = struct.unpack("<I4s", f.read(8))
        doc = json.loads(f.read(length))
        _, kind = struct.unpack("<I4s", f.read(8))
        if kind != b"BIN\0":
            sys.exit(f"{path}: no BIN chunk")
        return doc, f.tell()


def world_nodes(doc):
    """(node, world matrix) of every node reachable from the default scene."""
    nodes = doc["nodes"]
    out = []
    stack = [(n, IDENTITY) for n in doc["scenes"][doc.get("scene", 0)]["nodes"]]
    while stack:
        n, parent = stack.pop()
        world = matmul(parent, node_matrix(nodes[n]))
        out.append((nodes[n], world))
        stack.extend((c, world) for c in nodes[n].get("children", []))
    return out


def accessor_bytes(f, doc, bin_at, index, want):
    """Raw little-endian bytes of accessor `index`, which must be tightly packed."""
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    ctype, kind = acc["componentType"], acc["type"]
    size = {5121: 1, 5123: 2, 5125: 4, 5126: 4}[ctype] * {"SCALAR": 1, "VEC3": 3}[kind]
    if (ctype, kind) not in want or view.get("byteStride", size) != size:
        sys.exit(f"accessor {index}: {ctype} {kind} stride {view.get('byteStride')} unsupported")
    f.seek(bin_at + view.get("byteOffset", 0) + acc.get("byteOffset", 0))
    return f.read(acc["count"] * size), acc["count"], ctype


def triangle_count(path):
    doc, _ = read_glb(path)
    tris = 0
    for node, _ in world_nodes(doc):
        for prim in doc["meshes"][node["mesh"]]["primitives"] if "mesh" in node else []:
            acc = prim.get("indices", prim["attributes"]["POSITION"])
            tris += doc["accessors"][acc]["count"] // 3
    return tris


def write_ply(out, pos, nrm, idx):
    """A binary PLY of float32 positions (and normals) and uint32 triangles; idx None means
    every three vertices make a triangle."""
    n = len(pos) // 3
    stride = 6 if nrm is not None else 3
    verts = array("f", [0.0]) * (n * stride)
    for k in range(3):
        verts[k::stride] = pos[k::3]
        if nrm is not None:
            verts[3 + k::stride] = nrm[k::3]
    if idx is None:
        idx = array("I", range(n))
    faces = len(idx) // 3
    raw = idx.tobytes()
    data = bytearray(13 * faces)
    data[0::13] = b"\x03" * faces
    for j in range(12):
        data[1 + j::13] = raw[j::12]
    head = ["ply", "format binary_little_endian 1.0", f"element vertex {n}",
            "property float x", "property float y", "property float z"]
    if nrm is not None:
        head += ["property float nx", "property float ny", "property float nz"]
    head += [f"element face {faces}", "property list uchar uint vertex_indices", "end_header"]
    with open(out, "wb") as f:
        f.write(("\n".join(head) + "\n").encode())
        f.write(verts.tobytes())
        f.write(data)


def prepare_mitsuba(glb, work):
    """PLY files and a scene JSON for the Mitsuba child, in its own directory of `work`."""
    stem = os.path.splitext(os.path.basename(glb))[0]
    folder = os.path.join(work, stem + "-mitsuba")
    scene_json = os.path.join(folder, "scene.json")
    if os.path.exists(scene_json) and os.path.getmtime(scene_json) > os.path.getmtime(glb):
        return scene_json, None
    os.makedirs(folder, exist_ok=True)
    t0 = time.perf_counter()
    doc, bin_at = read_glb(glb)
    shapes, camera, sun = [], None, None
    materials = doc.get("materials", [])
    with open(glb, "rb") as f:
        for node, world in world_nodes(doc):
            if "mesh" in node:
                for p, prim in enumerate(doc["meshes"][node["mesh"]]["primitives"]):
                    if prim.get("mode", 4) != 4:
                        continue
                    attrs = prim["attributes"]
                    raw, _, _ = accessor_bytes(f, doc, bin_at, attrs["POSITION"], {(5126, "VEC3")})
                    pos = array("f", raw)
                    nrm = None
                    if "NORMAL" in attrs:
                        nrm = array("f", accessor_bytes(f, doc, bin_at, attrs["NORMAL"],
                                                        {(5126, "VEC3")})[0])
                    idx = None
                    if "indices" in prim:
                        raw, _, ctype = accessor_bytes(f, doc, bin_at, prim["indices"],
                                                       {(5121, "SCALAR"), (5123, "SCALAR"),
                                                        (5125, "SCALAR")})
                        idx = array({5121: "B", 5123: "H", 5125: "I"}[ctype], raw)
                        if ctype != 5125:
                            idx = array("I", idx)
                    if sys.byteorder != "little":
                        for a in (pos, nrm, idx):
                            if a is not None:
                                a.byteswap()
                    name = f"shape{len(shapes)}.ply"
                    write_ply(os.path.join(folder, name), pos, nrm, idx)
                    mat = materials[prim["material"]] if "material" in prim else {}
                    color = mat.get("pbrMetallicRoughness", {}).get("baseColorFactor",
                                                                    [0.8, 0.8, 0.8, 1.0])
                    shapes.append({"file": name, "color": color[:3],
                                   "to_world": None if world == IDENTITY else world})
            if "camera" in node and camera is None:
                cam = doc["cameras"][node["camera"]]
                yfov = cam.get("perspective", {}).get("yfov", 0.7)
                # glTF cameras look down -Z with +X right, Mitsuba's down +Z with +X left.
                m = [[-row[0], row[1], -row[2], row[3]] for row in world]
                camera = {"fov": math.degrees(yfov), "to_world": m}
            light = node.get("extensions", {}).get("KHR_lights_punctual")
            if light is not None and sun is None:
                spec = doc["extensions"]["KHR_lights_punctual"]["lights"][light["light"]]
                if spec["type"] == "directional":
                    d = [-world[i][2] for i in range(3)]
                    scale = spec.get("intensity", 1.0) / 683.0  # lux to W/m^2, as Blender does
                    sun = {"direction": d,
                           "irradiance": [c * scale for c in spec.get("color", [1, 1, 1])]}
    if camera is None:
        sys.exit(f"{glb}: no camera")
    with open(scene_json, "w") as f:
        json.dump({"shapes": shapes, "camera": camera, "sun": sun}, f)
    secs = time.perf_counter() - t0
    size = sum(os.path.getsize(os.path.join(folder, s["file"])) for s in shapes)
    # This process's peak: an upper bound of the preparation's, GLB parsing included.
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    return scene_json, {"secs": secs, "bytes": size, "rss": rss}


def prepare_cycles(glb, work, python, threads, limit_gb):
    """A .blend of the GLB imported into an empty scene, set up for the timed render."""
    stem = os.path.splitext(os.path.basename(glb))[0]
    blend = os.path.join(work, stem + ".blend")
    if os.path.exists(blend) and os.path.getmtime(blend) > os.path.getmtime(glb):
        return blend, None
    res, rss, _, wall, killed, tail = run_child(
        [python, HERE, "--child", "cycles-prepare", glb, blend, str(threads)], limit_gb)
    if killed:
        sys.exit(f"cycles preparation of {glb} killed at {limit_gb} GB")
    return blend, {"secs": res["import_s"], "save_s": res["save_s"], "wall": wall,
                   "bytes": os.path.getsize(blend), "rss": rss}


# ---------------------------------------------------------------------------------------------
# Child side: runs under the renderer's Python.

def emit(result):
    sys.stdout.flush()
    print(MARK + json.dumps(result), flush=True)


def cycles_settings(bpy, threads):
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.samples = 1
    sc.cycles.use_adaptive_sampling = False
    sc.cycles.use_denoising = False
    sc.cycles.pixel_filter_type = "BOX"
    sc.render.resolution_x, sc.render.resolution_y = WIDTH, HEIGHT
    sc.render.resolution_percentage = 100
    sc.render.threads_mode = "FIXED"
    sc.render.threads = threads
    sc.render.use_persistent_data = False


def child_cycles_prepare(glb, blend, threads):
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    t0 = time.perf_counter()
    bpy.ops.import_scene.gltf(filepath=glb)
    import_s = time.perf_counter() - t0
    sc = bpy.context.scene
    if sc.camera is None:
        sc.camera = next(o for o in sc.objects if o.type == "CAMERA")
    cycles_settings(bpy, threads)
    t0 = time.perf_counter()
    bpy.ops.wm.save_as_mainfile(filepath=blend, compress=False)
    emit({"import_s": import_s, "save_s": time.perf_counter() - t0})


def child_cycles(blend, threads):
    import bpy
    imported = time.time()
    result = {"version": bpy.app.version_string, "imported": imported}
    if blend:
        t0 = time.perf_counter()
        bpy.ops.wm.open_mainfile(filepath=blend)
        result["open_s"] = time.perf_counter() - t0
        cycles_settings(bpy, threads)
        t0 = time.perf_counter()
        bpy.ops.render.render()
        result["render_s"] = time.perf_counter() - t0
        result["rendered"] = time.time()
    emit(result)


def child_mitsuba(scene_json, threads):
    import drjit as dr
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    dr.set_thread_count(threads)
    imported = time.time()
    result = {"version": f"Mitsuba {mi.__version__}, Dr.Jit {dr.__version__}, scalar_rgb, "
                         f"Embree {'on' if mi.MI_ENABLE_EMBREE else 'off'}",
              "imported": imported}
    if scene_json:
        with open(scene_json) as f:
            desc = json.load(f)
        folder = os.path.dirname(scene_json)
        cam = desc["camera"]
        scene = {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 6},
            "sensor": {"type": "perspective", "fov": cam["fov"], "fov_axis": "y",
                       "to_world": mi.ScalarTransform4f(cam["to_world"]),
                       "sampler": {"type": "independent", "sample_count": 1},
                       "film": {"type": "hdrfilm", "width": WIDTH, "height": HEIGHT,
                                "rfilter": {"type": "box"}}},
        }
        if desc["sun"]:
            scene["sun"] = {"type": "directional", "direction": desc["sun"]["direction"],
                            "irradiance": {"type": "rgb", "value": desc["sun"]["irradiance"]}}
        t0 = time.perf_counter()
        for i, s in enumerate(desc["shapes"]):
            shape = {"type": "ply", "filename": os.path.join(folder, s["file"]),
                     "bsdf": {"type": "diffuse",
                              "reflectance": {"type": "rgb", "value": s["color"]}}}
            if s["to_world"]:
                shape["to_world"] = mi.ScalarTransform4f(s["to_world"])
            scene[f"shape{i}"] = mi.load_dict(shape)
        parsed = time.perf_counter()
        loaded = mi.load_dict(scene)
        result["open_s"] = time.perf_counter() - t0
        result["bvh_s"] = time.perf_counter() - parsed
        t0 = time.perf_counter()
        mi.render(loaded, spp=1)
        result["render_s"] = time.perf_counter() - t0
        result["rendered"] = time.time()
        t0 = time.perf_counter()
        mi.render(loaded, spp=1, seed=1)
        result["again_s"] = time.perf_counter() - t0
    emit(result)


def child(argv):
    kind = argv[0]
    if kind == "cycles-prepare":
        child_cycles_prepare(argv[1], argv[2], int(argv[3]))
    elif kind == "cycles":
        child_cycles(argv[1] or None, int(argv[2]))
    elif kind == "mitsuba":
        child_mitsuba(argv[1] or None, int(argv[2]))
    else:
        sys.exit(f"unknown child {kind}")


# ---------------------------------------------------------------------------------------------

def fmt(x, digits=2):
    if x is None:
        return "–"
    return f"{x:.{digits}f}" if abs(x) < 100 else f"{x:.0f}"


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        return child(sys.argv[2:])
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--renderers", default="cycles,mitsuba")
    ap.add_argument("--work", default="/tmp/big_rivals")
    ap.add_argument("--keep-work", action="store_true",
                    help="keep the prepared inputs in --work for the next run")
    ap.add_argument("--mem-limit-gb", type=float, default=None)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--bpy-python",
                    default=os.path.expanduser("~/.cache/aperture/bpy-5.0.1/bin/python"))
    ap.add_argument("--mitsuba-python", default="/tmp/mitsuba-venv/bin/python")
    a = ap.parse_args()
    renderers = [r for r in a.renderers.split(",") if r]
    for r in renderers:
        if r not in ("cycles", "mitsuba"):
            sys.exit(f"unknown renderer {r}")
    python = {"cycles": a.bpy_python, "mitsuba": a.mitsuba_python}
    os.makedirs(a.work, exist_ok=True)
    limit = a.mem_limit_gb

    versions, base_rss = {}, {}
    for r in renderers:
        res, rss, launch, _, _, _ = run_child([python[r], HERE, "--child", r, "", str(a.threads)])
        versions[r], base_rss[r] = res["version"], rss
        print(f"{r}: {res['version']}; import only: {res['imported'] - launch:.2f} s, "
              f"peak RSS {rss / 1e9:.3f} GB", flush=True)

    rows = []
    for glb in a.files:
        tris = triangle_count(glb)
        inputs = {}
        for r in renderers:
            if r == "cycles":
                inputs[r], prep = prepare_cycles(glb, a.work, python[r], a.threads, limit)
            else:
                inputs[r], prep = prepare_mitsuba(glb, a.work)
            if prep:
                extra = f", peak RSS {prep['rss'] / 1e9:.2f} GB" if prep["rss"] else ""
                if "save_s" in prep:
                    extra += f", save {prep['save_s']:.1f} s, child wall {prep['wall']:.1f} s"
                print(f"prepared {r} input of {os.path.basename(glb)} ({tris} triangles): "
                      f"{prep['secs']:.1f} s ({prep['secs'] / tris * 1e6:.1f} s per M "
                      f"triangles){extra}, {prep['bytes'] / 1e6:.0f} MB", flush=True)
            else:
                print(f"cached {r} input of {os.path.basename(glb)}: {inputs[r]}", flush=True)
        runs = {r: [] for r in renderers}
        for _ in range(a.rounds):
            for r in renderers:
                res, rss, launch, wall, killed, _ = run_child(
                    [python[r], HERE, "--child", r, inputs[r], str(a.threads)], limit)
                if killed:
                    runs[r].append({"killed": True})
                    continue
                runs[r].append({"start": res["imported"] - launch, "open": res["open_s"],
                                "bvh": res.get("bvh_s"),
                                "render": res["render_s"], "again": res.get("again_s"),
                                "total": res["rendered"] - launch, "rss": rss, "wall": wall})
        if not a.keep_work:
            for r, path in inputs.items():
                # Mitsuba's: scene.json in a folder of PLY files; Cycles': one .blend.
                if r == "mitsuba":
                    shutil.rmtree(os.path.dirname(path))
                else:
                    os.remove(path)
        for r in renderers:
            done = [x for x in runs[r] if not x.get("killed")]
            if not done:
                rows.append(f"| {os.path.basename(glb)} | {tris} | {r} | killed at {limit:g} GB"
                            + " | –" * 8 + " |")
                continue

            def med(key):
                values = [x[key] for x in done if x[key] is not None]
                return statistics.median(values) if values else None
            rss = med("rss")
            note = f" ({len(runs[r]) - len(done)} of {len(runs[r])} killed at {limit:g} GB)" \
                if len(done) < len(runs[r]) else ""
            rows.append(f"| {os.path.basename(glb)} | {tris} | {r}{note} | {fmt(med('start'))} | "
                        f"{fmt(med('open'))} | {fmt(med('bvh'))} | {fmt(med('render'))} | {fmt(med('again'))} | "
                        f"{fmt(med('total'))} | {rss / 1e9:.2f} | {rss / tris:.0f} | "
                        f"{(rss - base_rss[r]) / tris:.0f} |")

    print(f"\nmedian of {a.rounds} round(s); {a.threads} threads, {WIDTH}x{HEIGHT}, 1 spp")
    print("| scene | triangles | renderer | start s | open/load s | of which BVH s"
          " | sync+BVH+1spp / first render s | again s | total s | peak RSS GB | B/tri"
          " | B/tri net |")
    print("|---" * 12 + "|")
    for r in renderers:
        print(f"| (import only) | 0 | {r} | | | | | | | {base_rss[r] / 1e9:.2f} | | |")
    for row in rows:
        print(row)
    print()
    for r in renderers:
        print(f"{r}: {versions[r]}")


if __name__ == "__main__":
    main()
