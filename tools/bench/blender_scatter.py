"""Builds a large scene in Blender the way an artist would and writes it with Blender's own glTF
exporter: the "real large export" of the big-scenes benchmark (issue 59), indexed meshes whose
vertices, normals and UVs are shared as Blender writes them (tools/bench/big_scene.py writes
the opposite, a vertex per triangle corner).

    python blender_scatter.py TRIANGLES OUT.glb [OBJECTS] [--no-addon] [--live-modifiers]

Run with the bpy venv (~/.cache/aperture/bpy-5.0.1/bin/python; `import bpy` headless).

The scene: a ground plane (a grid holding ~2% of the triangles) under OBJECTS (default 400)
separate objects scattered over it like a forest or a crowd: Suzannes with a Subdivision
Surface modifier (~60%), UV spheres (~25%) and cylinders with creased rims and a Subdivision
Surface modifier (~15%), all shaded smooth, each with mesh data of its own (Shift+D copies, not
linked duplicates: every triangle is unique), each bent by a smooth random warp (a few % of its
size) so that no two hold the same vertex data (they keep their kind's topology, and the
exporter, which merges identical data, writes one index accessor per kind that all its meshes
use). Positions, rotations (a free yaw, a small tilt) and scales (0.5-2x) come from
random.Random(1); a sixth of the objects are put against one already placed, touching or
overlapping it a little, and the objects sink a little into the ground, as a scatter does. The
Suzannes' and cylinders' levels are those whose triangle count is nearest to the objects' share
of TRIANGLES; the spheres' segments take up the rest, and the ground what is then left, so the
total lands near TRIANGLES. A sun, and a perspective camera (35 mm) looking over the scatter
with depth of field on (f/2.8, focused on the middle).

The modifiers are applied once, to the three template meshes, before the copies are made
(Blender's exporter keeps every subdivided object's evaluation alive through an export: with
--live-modifiers, every object keeps its Subdivision Surface modifier and the exporter applies
them, which took 3.5 GB and 23 s for 2 M triangles against 0.46 GB and 2.6 s, Blender 5.0.1).

The export: bpy.ops.export_scene.gltf as GLB with the exporter's defaults except Apply
Modifiers, Cameras and Punctual Lights on. Blender's exporter does not write depth of field;
this repository's add-on (tools/blender/aperture_gltf_dof) does, into the camera's extras, so
it is installed and enabled first (in a temporary user-scripts folder) unless --no-addon.

Prints the build and export seconds (with --live-modifiers the export includes them), the
triangles written (from the GLB's index accessors, checked against the evaluated meshes), the
file's size and the process's peak memory. Deterministic: the same arguments build the same
scene.
"""

import json
import math
import os
import random
import resource
import shutil
import struct
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blender"))

# Per kind: share of the objects, radius of its footprint on the ground at scale 1.
KINDS = (("suzanne", 0.60, 1.2), ("sphere", 0.25, 1.0), ("cylinder", 0.15, 0.5))
GROUND_SHARE = 0.02
CYLINDER_VERTICES = 32


def peak_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def triangles_of(mesh):
    """Triangles of a mesh's faces (a face of n corners is n - 2 of them)."""
    return len(mesh.loops) - 2 * len(mesh.polygons)


def material(bpy, name, color, roughness):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes.get("Principled BSDF")
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    m.diffuse_color = (*color, 1.0)
    return m


def take_mesh(bpy, smooth=True):
    """The active object's mesh, its object deleted (the mesh stays, as a template)."""
    obj = bpy.context.active_object
    mesh = obj.data
    if smooth:
        mesh.shade_smooth()
    bpy.data.objects.remove(obj)
    return mesh


def subdivided_triangles(bpy, mesh, level):
    """Triangles `mesh` carries under a Subdivision Surface modifier at `level`."""
    if level == 0:
        return triangles_of(mesh)
    obj = bpy.data.objects.new("probe", mesh)
    bpy.context.scene.collection.objects.link(obj)
    mod = obj.modifiers.new("Subdivision", "SUBSURF")
    mod.levels = mod.render_levels = level
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    tri = triangles_of(ev.to_mesh())
    ev.to_mesh_clear()
    bpy.data.objects.remove(obj)
    return tri


def applied(bpy, mesh, level):
    """A new mesh: `mesh` with a Subdivision Surface modifier at `level` applied (shading, UVs,
    materials kept, as Ctrl+A > Apply does)."""
    obj = bpy.data.objects.new("probe", mesh)
    bpy.context.scene.collection.objects.link(obj)
    mod = obj.modifiers.new("Subdivision", "SUBSURF")
    mod.levels = mod.render_levels = level
    out = bpy.data.meshes.new_from_object(obj.evaluated_get(bpy.context.evaluated_depsgraph_get()))
    bpy.data.objects.remove(obj)
    return out


def nearest_level(bpy, mesh, target):
    """The Subdivision Surface level (0-6) whose triangle count is nearest `target` by ratio,
    and that count; counts are measured, not guessed (level 6 only when level 5 is below)."""
    best, level = None, 0
    while level <= 6:
        tri = subdivided_triangles(bpy, mesh, level)
        score = abs(math.log(tri / target))
        if best is None or score < best[0]:
            best = (score, level, tri)
        if tri >= target:
            break
        level += 1
    return best[1], best[2]


def sphere_segments(target):
    """Even segment count s (rings s / 2) whose UV sphere, 2 s (s / 2 - 1) triangles, is nearest
    `target`."""
    s = max(4, 2 * round(math.sqrt(target) / 2))
    return min((c for c in (s - 2, s, s + 2) if c >= 4), key=lambda c: abs(c * (c - 2) - target))


def uv_sphere(bpy, segments, rings):
    """A UV sphere of radius 1 as Add > Mesh > UV Sphere makes it (a quad grid with triangle fans
    at the poles, UVs cut along one meridian), built here because that operator's corner order
    changes from run to run (Blender 5.0.1) and with it the exported triangle order."""
    def ring(r, k):
        return 1 + (r - 1) * segments + k % segments

    verts = [(0.0, 0.0, 1.0)]
    for r in range(1, rings):
        t = math.pi * r / rings
        verts += [(math.sin(t) * math.cos(2 * math.pi * k / segments),
                   math.sin(t) * math.sin(2 * math.pi * k / segments), math.cos(t)) for k in range(segments)]
    verts.append((0.0, 0.0, -1.0))
    bottom = len(verts) - 1
    faces, uvs = [], []
    for k in range(segments):
        u0, u1, um = k / segments, (k + 1) / segments, (k + 0.5) / segments
        faces.append((0, ring(1, k), ring(1, k + 1)))
        uvs += [(um, 1.0), (u0, 1 - 1 / rings), (u1, 1 - 1 / rings)]
        for r in range(1, rings - 1):
            faces.append((ring(r, k), ring(r + 1, k), ring(r + 1, k + 1), ring(r, k + 1)))
            va, vb = 1 - r / rings, 1 - (r + 1) / rings
            uvs += [(u0, va), (u0, vb), (u1, vb), (u1, va)]
        faces.append((ring(rings - 1, k), bottom, ring(rings - 1, k + 1)))
        uvs += [(u0, 1 / rings), (um, 0.0), (u1, 1 / rings)]
    mesh = bpy.data.meshes.new("Sphere")
    mesh.from_pydata(verts, [], faces)
    layer = mesh.uv_layers.new(name="UVMap")
    layer.data.foreach_set("uv", [c for uv in uvs for c in uv])
    mesh.shade_smooth()
    return mesh


def vary(mesh, rng, amount=0.04):
    """Makes a copied mesh its own shape, as a Warp or Displace modifier would: every vertex moved
    by a smooth random field of up to `amount` (scene units at scale 1), so no two objects hold
    the same vertex data. The field's slope stays below 0.12, so it folds no triangle and
    shortens no edge by more than 12% (moving along the normals would, at creased rims)."""
    import numpy as np
    n = len(mesh.vertices)
    co = np.empty(3 * n, np.float32)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(n, 3)
    moved = co.copy()
    for _ in range(2):
        k, d = (np.array([rng.gauss(0, 1) for _ in range(3)], np.float32) for _ in range(2))
        k *= rng.uniform(1.5, 3.0) / max(1e-6, float(np.linalg.norm(k)))
        d *= 0.5 * amount / max(1e-6, float(np.linalg.norm(d)))
        moved += np.sin(co @ k + rng.uniform(0, 2 * math.pi)).astype(np.float32)[:, None] * d
    mesh.vertices.foreach_set("co", moved.ravel())
    mesh.update()


def crease_rims(mesh, value=0.9):
    """Creases a cylinder's rim edges (those whose two ends are at one height), so the
    Subdivision Surface rounds the rims only a little."""
    attr = mesh.attributes.get("crease_edge") or mesh.attributes.new("crease_edge", "FLOAT", "EDGE")
    vs = mesh.vertices
    for e, d in zip(mesh.edges, attr.data):
        a, b = e.vertices
        d.value = value if abs(vs[a].co.z - vs[b].co.z) < 1e-6 else 0.0


def place(rng, footprints, half):
    """Scatter positions: mostly uniform over the square [-half, half]^2 with little overlap
    (centres no closer than 0.85 of the sum of footprints, best of 40 tries), a sixth of them
    against an already placed object, touching or overlapping it a little."""
    cell = 2 * max(footprints) + 1e-6
    grid = {}
    placed = []

    def neighbours(x, y):
        cx, cy = int(math.floor(x / cell)), int(math.floor(y / cell))
        for i in range(cx - 1, cx + 2):
            for j in range(cy - 1, cy + 2):
                yield from grid.get((i, j), ())

    def clearance(x, y, r):
        worst = math.inf
        for k in neighbours(x, y):
            px, py, pr = placed[k]
            worst = min(worst, math.hypot(x - px, y - py) / (r + pr))
        return worst

    for r in footprints:
        m = half - r
        if placed and rng.random() < 1 / 6:
            px, py, pr = placed[rng.randrange(len(placed))]
            a = rng.uniform(0, 2 * math.pi)
            d = (r + pr) * rng.uniform(0.85, 1.0)
            x = min(m, max(-m, px + d * math.cos(a)))
            y = min(m, max(-m, py + d * math.sin(a)))
        else:
            best = None
            for _ in range(40):
                x, y = rng.uniform(-m, m), rng.uniform(-m, m)
                c = clearance(x, y, r)
                if best is None or c > best[0]:
                    best = (c, x, y)
                if c >= 0.85:
                    break
            _, x, y = best
        grid.setdefault((int(math.floor(x / cell)), int(math.floor(y / cell))), []).append(len(placed))
        placed.append((x, y, r))
    return [(x, y) for x, y, _ in placed]


def glb_triangles(path):
    """Triangles the GLB's node-referenced triangle-list primitives hold (index counts / 3)."""
    with open(path, "rb") as f:
        magic, _, _ = struct.unpack("<4sII", f.read(12))
        length, kind = struct.unpack("<I4s", f.read(8))
        assert magic == b"glTF" and kind == b"JSON"
        doc = json.loads(f.read(length))
    acc = doc["accessors"]
    tri = 0
    for node in doc.get("nodes", []):
        if "mesh" not in node:
            continue
        for p in doc["meshes"][node["mesh"]]["primitives"]:
            if p.get("mode", 4) != 4:
                continue
            n = acc[p["indices"]]["count"] if "indices" in p else acc[p["attributes"]["POSITION"]]["count"]
            tri += n // 3
    return tri, doc


def install_addon(bpy, work):
    from addon_zip import ADDON, addon_zip
    bpy.ops.preferences.addon_install(filepath=addon_zip(work), overwrite=True)
    bpy.ops.preferences.addon_enable(module=ADDON)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if len(args) < 2:
        sys.exit(__doc__)
    use_addon = "--no-addon" not in sys.argv
    live = "--live-modifiers" in sys.argv
    triangles, out = int(args[0]), os.path.abspath(args[1])
    count = int(args[2]) if len(args) > 2 else 400
    work = tempfile.mkdtemp(prefix="aperture-scatter-")
    if use_addon:
        os.environ["BLENDER_USER_SCRIPTS"] = os.path.join(work, "scripts")
    import bpy
    from mathutils import Euler, Vector

    t0 = time.perf_counter()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if use_addon:
        install_addon(bpy, work)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 1920, 1080
    rng = random.Random(1)

    # What each object is, then the level or segments that spend the triangle budget.
    kinds = []
    for _ in range(count):
        u, acc = rng.random(), 0.0
        for name, share, _ in KINDS:
            acc += share
            if u < acc:
                break
        kinds.append(name)
    n_of = {name: kinds.count(name) for name, _, _ in KINDS}
    share = triangles * (1 - GROUND_SHARE) / max(1, count)

    bpy.ops.mesh.primitive_monkey_add(size=2.0)
    suzanne = take_mesh(bpy)
    bpy.ops.mesh.primitive_cylinder_add(vertices=CYLINDER_VERTICES, radius=0.5, depth=3.0,
                                        end_fill_type="NGON")
    cylinder = take_mesh(bpy)
    crease_rims(cylinder)
    suz_level, suz_tri = nearest_level(bpy, suzanne, share)
    cyl_level, cyl_tri = nearest_level(bpy, cylinder, share)
    rest = triangles * (1 - GROUND_SHARE) - n_of["suzanne"] * suz_tri - n_of["cylinder"] * cyl_tri
    seg = sphere_segments(max(16, rest / n_of["sphere"]) if n_of["sphere"] else share)
    sphere = uv_sphere(bpy, seg, seg // 2)
    sph_tri = triangles_of(sphere)
    objects_tri = n_of["suzanne"] * suz_tri + n_of["cylinder"] * cyl_tri + n_of["sphere"] * sph_tri
    cells = max(1, round(math.sqrt(max(2, triangles - objects_tri) / 2)))
    print(f"objects: {n_of['suzanne']} Suzannes (level {suz_level}, {suz_tri} triangles), "
          f"{n_of['sphere']} UV spheres ({seg} x {seg // 2}, {sph_tri}), {n_of['cylinder']} "
          f"cylinders (level {cyl_level}, {cyl_tri}); ground {cells} x {cells} cells", flush=True)

    mats = {
        "suzanne": [material(bpy, "Skin", (0.75, 0.45, 0.3), 0.5), material(bpy, "Leaf", (0.2, 0.5, 0.15), 0.6)],
        "sphere": [material(bpy, "Stone", (0.5, 0.5, 0.48), 0.8)],
        "cylinder": [material(bpy, "Bark", (0.35, 0.22, 0.12), 0.9)],
    }
    template = {"suzanne": (suzanne, suz_level), "sphere": (sphere, 0), "cylinder": (cylinder, cyl_level)}
    if not live:
        # Apply the modifiers once; the objects get copies of the subdivided meshes.
        for kind, (mesh, level) in list(template.items()):
            if level:
                template[kind] = (applied(bpy, mesh, level), 0)
                bpy.data.meshes.remove(mesh)
    footprint = {name: r for name, _, r in KINDS}
    boxes = {kind: _box(mesh) for kind, (mesh, _) in template.items()}

    scales = [rng.uniform(0.5, 2.0) for _ in range(count)]
    radii = [footprint[k] * s for k, s in zip(kinds, scales)]
    # A square where the footprints cover ~30% of the ground.
    half = 0.5 * math.sqrt(sum(math.pi * r * r for r in radii) / 0.30) if count else 5.0
    spots = place(rng, radii, half)

    coll = scene.collection
    for i, (kind, s, (x, y)) in enumerate(zip(kinds, scales, spots)):
        base, level = template[kind]
        mesh = base.copy()
        mesh.name = f"{kind}.{i:04d}"
        mesh.materials.clear()
        vary(mesh, rng)
        mesh.materials.append(rng.choice(mats[kind]))
        obj = bpy.data.objects.new(mesh.name, mesh)
        tilt = math.radians(12 if kind != "sphere" else 180)
        rot = Euler((rng.uniform(-tilt, tilt), rng.uniform(-tilt, tilt), rng.uniform(0, 2 * math.pi)))
        obj.rotation_euler, obj.scale = rot, (s, s, s)
        # Rest on the ground (the template's box, rotated and scaled), sunk in by 3% of the size.
        m = rot.to_matrix() * s
        low = min((m @ Vector(c)).z for c in boxes[kind])
        obj.location = (x, y, -low - 0.03 * s * 2 * footprint[kind])
        if level:
            mod = obj.modifiers.new("Subdivision", "SUBSURF")
            mod.levels = mod.render_levels = level
        coll.objects.link(obj)
    for base, _ in template.values():
        bpy.data.meshes.remove(base)

    bpy.ops.mesh.primitive_grid_add(x_subdivisions=cells, y_subdivisions=cells, size=2 * half * 1.15)
    ground = bpy.context.active_object
    ground.name = ground.data.name = "Ground"
    ground.data.materials.append(material(bpy, "Ground", (0.3, 0.27, 0.2), 0.95))

    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 4.0
    sun.rotation_euler = (math.radians(40), math.radians(10), math.radians(35))
    coll.objects.link(sun)

    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location = (0.0, -1.6 * half, 0.85 * half)
    target = Vector((0.0, 0.1 * half, 0.0))
    cam.rotation_euler = (target - cam.location).to_track_quat("-Z", "Y").to_euler()
    cam.data.lens = 35.0
    cam.data.clip_start, cam.data.clip_end = 0.1, 10 * half
    cam.data.dof.use_dof = True
    cam.data.dof.aperture_fstop = 2.8
    cam.data.dof.focus_distance = (target - cam.location).length
    coll.objects.link(cam)
    scene.camera = cam
    build = time.perf_counter() - t0
    print(f"built in {build:.1f} s (square {2 * half:.1f} units, {len(coll.objects)} objects), "
          f"peak {peak_mb():.0f} MB", flush=True)

    t0 = time.perf_counter()
    bpy.ops.export_scene.gltf(filepath=out, export_format="GLB", export_apply=True,
                              export_cameras=True, export_lights=True)
    export = time.perf_counter() - t0
    size = os.path.getsize(out)
    print(f"exported in {export:.1f} s, peak {peak_mb():.0f} MB", flush=True)

    written, doc = glb_triangles(out)
    dg = bpy.context.evaluated_depsgraph_get()
    evaluated = 0
    for obj in coll.objects:
        if obj.type == "MESH":
            ev = obj.evaluated_get(dg)
            evaluated += triangles_of(ev.to_mesh())
            ev.to_mesh_clear()
    vertices = sum(doc["accessors"][p["attributes"]["POSITION"]]["count"]
                   for m in doc["meshes"] for p in m["primitives"])
    dof = (doc.get("cameras") or [{}])[0].get("extras", {})
    print(f"{out}: {written} triangles ({evaluated} in the evaluated meshes), {vertices} vertices, "
          f"{len(doc['meshes'])} meshes, {size} bytes ({size / 1e6:.1f} MB); export {export:.1f} s, "
          f"build {build:.1f} s; camera extras: use_dof {dof.get('use_dof')}, "
          f"f/{dof.get('aperture_fstop')}, focus {dof.get('focus_distance')}; "
          f"Blender peak {peak_mb():.0f} MB", flush=True)
    shutil.rmtree(work, ignore_errors=True)


def _box(mesh):
    """The 8 corners of a mesh's axis-aligned bounding box."""
    xs, ys, zs = (sorted(v.co[k] for v in mesh.vertices) for k in range(3))
    return [(x, y, z) for x in (xs[0], xs[-1]) for y in (ys[0], ys[-1]) for z in (zs[0], zs[-1])]


if __name__ == "__main__":
    main()
