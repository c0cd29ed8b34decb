# SPDX-License-Identifier: MIT OR Apache-2.0
"""Meshes handed to the session as numpy arrays instead of through the glTF exporter (issue 63):
the exporter spends about 1.5 s of Python a million triangles deduplicating vertices and
packing buffers. While the session exports, ``stubbed`` has the exporter write, for each mesh
it can stand in for, one marked triangle per material slot instead of the mesh's triangles
(its nodes, materials, cameras and lights are exported as before, the mesh not validated:
``Mesh.validate()`` took most of the export); ``given`` then reads those
meshes' triangles from the evaluated objects with ``foreach_get`` and the session loads the
file with them (``aperture.load(path, geometry=...)``). A geometry edit of such a mesh is one
``Scene.set_geometry``, no export.

A mesh is stood in for when the arrays carry everything the exporter would write of it: no
shape keys, no skin, at most one UV map, no colour attributes. Vertices are the mesh's
vertices when its normals are smooth and its UVs have no seam, else its corners (each with its
position, corner normal and UV): the same surface the exporter's deduplicated vertices
describe, +Y up as the exporter turns it.
"""

import concurrent.futures
import contextlib
import os

import numpy as np

# The stand-in triangle's z: no mesh the exporter writes has a triangle there by chance.
MARK = -12345.0


def _exporter():
    """The exporter's primitive extraction module and its constants (Blender 4.3–5.0 names,
    then 4.2's), or ``(None, None)``."""
    try:
        from io_scene_gltf2.blender.exp import primitive_extract as extract
        from io_scene_gltf2.io.com import constants
    except ImportError:
        try:
            from io_scene_gltf2.blender.exp import gltf2_blender_gather_primitives_extract as extract
            from io_scene_gltf2.io.com import gltf2_io_constants as constants
        except ImportError:
            return None, None
    return extract, constants


def eligible(mesh):
    """True when the arrays carry all the exporter would write of ``mesh``."""
    return (mesh.shape_keys is None and len(mesh.uv_layers) <= 1
            and len(mesh.color_attributes) == 0 and len(mesh.polygons) > 0)


def _read(collection, name, n, width, dtype):
    """``foreach_get`` into a new array (a dtype matching the property's is a plain copy;
    another converts item by item, 70× slower on a million triangles)."""
    a = np.empty(n * width, dtype)
    collection.foreach_get(name, a)
    return a.reshape(n, width) if width > 1 else a


def _triangle_slots(mesh):
    """Each loop triangle's material slot (``None``: all 0, the mesh has no such attribute)."""
    attr = mesh.attributes.get("material_index")
    if attr is None or attr.domain != "FACE":
        return None
    face = _read(attr.data, "value", len(mesh.polygons), 1, np.int32)
    tri_face = _read(mesh.loop_triangle_polygons, "value", len(mesh.loop_triangles), 1, np.int32)
    return face[tri_face]


def slots(mesh):
    """The material slots the mesh's triangles use, sorted: one primitive each, in this
    order (the exporter's ``primitive_split`` buckets them the same way)."""
    tri = _triangle_slots(mesh)
    return np.zeros(1, np.int32) if tri is None else np.unique(tri)


def corner_vertices(mesh):
    """Each corner's vertex (Blender 4.x's attribute, a plain copy; else the loops')."""
    corners = mesh.attributes.get(".corner_vert")
    return _read(corners.data if corners else mesh.loops, "value" if corners else "vertex_index",
                 len(mesh.loops), 1, np.int32)


def positions(mesh):
    """The vertices' positions (the ``position`` attribute: a plain copy)."""
    return _read(mesh.attributes["position"].data, "vector", len(mesh.vertices), 3, np.float32)


def _stand_ins(mesh, constants):
    """What ``extract_primitives`` returns for ``mesh`` stood in for: a triangle per slot at
    ``MARK``, its slot in x (``given`` checks both)."""
    prims = []
    for slot in slots(mesh):
        p = np.array([[slot, 0, MARK], [slot, 1, MARK], [slot, 0, MARK + 1]], np.float32)
        prims.append({
            "attributes": {"POSITION": {
                "data": p,
                "component_type": constants.ComponentType.Float,
                "data_type": constants.DataType.Vec3,
            }},
            "indices": np.array([0, 1, 2], np.uint32),
            "material": int(slot),
            "uvmap_attributes_index": {},
        })
    return prims, [None] * len(prims), None


def _nodes():
    """The exporter's node module when it has the mesh gathering ``_unvalidated`` wraps
    (Blender 4.3–5.0), else None."""
    try:
        from io_scene_gltf2.blender.exp import nodes
    except ImportError:
        return None
    names = ("__gather_mesh", "__keep_material_info", "gltf2_blender_gather_mesh", "VExportNode")
    return nodes if all(n in vars(nodes) for n in names) else None


def _unvalidated(nodes, original):
    """The node module's ``__gather_mesh`` without its ``Mesh.validate()`` for a mesh object
    the arrays stand in for (no modifiers, ``eligible``): the exporter validates every mesh
    it writes (0.67 s of the 0.73 s export on 4.9 M triangles) and may change the user's
    mesh doing so, although it reads nothing of a stood-in one. The rest is the original's
    path for such an object; ``primitives`` checks what it reads instead."""
    keep = vars(nodes)["__keep_material_info"]

    def gather_mesh(vnode, obj, export_settings):
        if (obj is None or vnode.blender_type == nodes.VExportNode.COLLECTION
                or obj.type != "MESH" or vnode.force_as_empty or len(obj.modifiers)
                or export_settings.get("gltf_shared_accessors") or not eligible(obj.data)):
            return original(vnode, obj, export_settings)
        materials = tuple(ms.material for ms in obj.material_slots)
        keep(materials, True, export_settings)
        return nodes.gltf2_blender_gather_mesh.gather_mesh(
            obj.data, None, obj.vertex_groups, None, materials, None, export_settings)

    return gather_mesh


@contextlib.contextmanager
def stubbed(on=True):
    """Within it, the exporter writes stand-ins for the meshes ``eligible`` accepts (without
    validating them, where this exporter's node module is known). Yields False (and changes
    nothing) when not ``on`` or this Blender's exporter is not the one known here."""
    extract, constants = _exporter() if on else (None, None)
    original = getattr(extract, "extract_primitives", None)
    if original is None:
        yield False
        return

    def extract_primitives(materials, mesh, skinned, *rest):
        export_settings = rest[-1]
        if skinned is not None or export_settings.get("gltf_shared_accessors") or not eligible(mesh):
            return original(materials, mesh, skinned, *rest)
        return _stand_ins(mesh, constants)

    nodes = _nodes()
    gather = vars(nodes)["__gather_mesh"] if nodes else None
    extract.extract_primitives = extract_primitives
    if nodes:
        vars(nodes)["__gather_mesh"] = _unvalidated(nodes, gather)
    try:
        yield True
    finally:
        extract.extract_primitives = original
        if nodes:
            vars(nodes)["__gather_mesh"] = gather


def stood_in(doc):
    """``{mesh index: (slots, [node names])}`` of the export's stood-in meshes."""
    accessors = doc.get("accessors", [])
    out = {}
    for m, mesh in enumerate(doc.get("meshes", [])):
        lows = [accessors[p["attributes"]["POSITION"]].get("min", [0, 0, 0])
                for p in mesh.get("primitives", [])]
        if lows and all(low[2] == MARK for low in lows):
            out[m] = ([int(low[0]) for low in lows], [])
    for n in doc.get("nodes", []):
        if n.get("mesh") in out:
            out[n["mesh"]][1].append(n.get("name"))
    return out


def _yup(v):
    """Blender's +Z up as the exporter writes +Y up: (x, z, -y)."""
    out = np.empty_like(v)
    out[:, 0], out[:, 1], out[:, 2] = v[:, 0], v[:, 2], -v[:, 1]
    return out


def _normals(n):
    """Normals as the exporter writes them (``__get_normals``: rounded to 4 digits,
    normalised, a zero one made +Z, then +Y up), so that a render matches a full export's
    bit for bit."""
    n = np.round(n, 4)
    norms = np.linalg.norm(n, axis=1, keepdims=True)
    np.divide(n, norms, out=n, where=norms != 0)
    n[~n.any(axis=1), 2] = 1
    return _yup(n)


def _read_mesh(mesh, want):
    """What ``mesh``'s arrays are made of, read from Blender (on the calling thread: bpy's
    data is read there only): ``by`` says whose normals the vertices take (``vertex``,
    ``face`` or ``corner``); ``None`` when the arrays cannot carry the mesh (``primitives``)."""
    if not eligible(mesh) or list(slots(mesh)) != list(want):
        return None
    nv, nc = len(mesh.vertices), len(mesh.loops)
    r = {"loops": _read(mesh.loop_triangles, "loops", len(mesh.loop_triangles), 3, np.uint32),
         "corner_vertex": corner_vertices(mesh), "co": positions(mesh), "uv": None,
         "slots": _triangle_slots(mesh) if len(want) > 1 else None}
    if not _valid(r["co"], r["corner_vertex"]):
        return None
    if len(mesh.uv_layers):
        r["uv"] = _read(mesh.attributes[mesh.uv_layers[0].name].data, "vector", nc, 2, np.float32)
        r["uv"][:, 1] = 1.0 - r["uv"][:, 1]  # glTF's v runs down the image (the exporter's flip)
    if mesh.normals_domain == "POINT":
        if r["uv"] is not None:
            r["uv_vertex"] = np.zeros((nv, 2), np.float32)
            r["uv_vertex"][r["corner_vertex"]] = r["uv"]
        if r["uv"] is None or np.array_equal(r["uv_vertex"][r["corner_vertex"]], r["uv"]):
            # Smooth, without UV seams: by vertex.
            r["by"], r["normals"] = "vertex", _read(mesh.vertex_normals, "vector", nv, 3,
                                                    np.float32)
            return r
    if mesh.normals_domain == "FACE":  # each corner its face's: normalised once a face
        # Each triangle's face (an attribute, a plain copy; the faces' loop_start is read
        # item by item, 0.1 s on 2.4 M faces).
        r["triangle_faces"] = _read(mesh.loop_triangle_polygons, "value", len(r["loops"]), 1,
                                    np.int32)
        r["by"], r["normals"] = "face", _read(mesh.polygon_normals, "vector",
                                              len(mesh.polygons), 3, np.float32)
    else:
        r["by"], r["normals"] = "corner", _read(mesh.corner_normals, "vector", nc, 3, np.float32)
    return r


def _arrays(r):
    """The vertex arrays of what ``_read_mesh`` read, and each triangle's three vertices: by
    vertex when it chose so, else by corner (numpy only: any thread)."""
    loops = r["loops"]  # uint32, as Blender holds them: the library reads them as they are
    normals = _normals(r["normals"])
    if r["by"] == "vertex":
        arrays = {"positions": _yup(r["co"]), "normals": normals}
        if r["uv"] is not None:
            arrays["uvs"] = r["uv_vertex"]
        return arrays, r["corner_vertex"][loops]
    if r["by"] == "face":
        # Every corner is a corner of one of its face's triangles.
        corner_face = np.zeros(len(r["corner_vertex"]), np.int32)
        corner_face[loops] = r["triangle_faces"][:, None]
        normals = np.take(normals, corner_face, axis=0)
    # np.take: the same gather as indexing, in half the time.
    arrays = {"positions": np.take(_yup(r["co"]), r["corner_vertex"], axis=0), "normals": normals}
    if r["uv"] is not None:
        arrays["uvs"] = r["uv"]
    return arrays, loops


def _valid(co, corner_vertex):
    """False when the exporter's ``Mesh.validate()``, which stood-in meshes skip, would have
    had to mend what the arrays read: a position ``co`` that is not finite, a corner naming
    no vertex (the exporter's path then takes the mesh)."""
    inside = len(corner_vertex) == 0 or (corner_vertex.min() >= 0 and corner_vertex.max() < len(co))
    return bool(inside and np.isfinite(co).all())


def _primitives_of(r, want):
    """The primitive dicts of what ``_read_mesh`` read, one per slot of ``want`` in that
    order (numpy only: any thread)."""
    arrays, tri_vertices = _arrays(r)
    if len(want) == 1:
        return [dict(arrays, triangles=tri_vertices)]
    out = []
    for slot in want:
        used, local = np.unique(tri_vertices[r["slots"] == slot], return_inverse=True)
        prim = {k: v[used] for k, v in arrays.items()}
        prim["triangles"] = local.reshape(-1, 3)
        out.append(prim)
    return out


def primitives(mesh, want):
    """The primitive dicts of ``mesh`` (an evaluated mesh), one per slot of ``want`` in that
    order; ``None`` when its slots are no longer those (a re-export is needed) or it needs
    mending (``_valid``)."""
    r = _read_mesh(mesh, want)
    return None if r is None else _primitives_of(r, want)


def given(doc, objects):
    """``({mesh index: primitive dicts}, {object name: mesh index})`` of the export's stood-in
    meshes, read from ``objects(name)`` (the evaluated object of a node's name, or None).
    Raises ``LookupError`` when a stood-in mesh cannot be read back (the caller exports
    without stand-ins)."""
    futures, drawn_by = {}, {}
    # Blender's data is read here; each mesh's numpy work (which lets go of the GIL) runs in
    # the pool meanwhile (with np.take and loop_triangle_polygons: 0.97 -> 0.65 s on 4.9 M).
    with concurrent.futures.ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        for m, (want, names) in stood_in(doc).items():
            obj = next((o for o in map(objects, names) if o is not None), None)
            r = _read_mesh(obj.data, want) if obj is not None and obj.type == "MESH" else None
            if r is None:
                raise LookupError(f"mesh {m} (nodes {names}) cannot be read back")
            futures[m] = pool.submit(_primitives_of, r, want)
            drawn_by.update((n, m) for n in names)
        return {m: f.result() for m, f in futures.items()}, drawn_by


def drawn_triangles(doc, geometry):
    """The triangles the export draws, each mesh once per node drawing it (``info()``'s
    ``drawn``), from its JSON and the stood-in meshes' ``geometry``: ``info()`` also
    classifies every triangle and bounds every node (0.13 s on 4.9 M triangles)."""
    accessors = doc.get("accessors", [])

    def triangles(m, k, prim):
        if m in geometry:
            return len(geometry[m][k]["triangles"])
        at = prim.get("indices", prim.get("attributes", {}).get("POSITION"))
        n = accessors[at].get("count", 0) if at is not None and at < len(accessors) else 0
        mode = prim.get("mode", 4)
        return n // 3 if mode == 4 else max(n - 2, 0) if mode in (5, 6) else 0

    meshes = [sum(triangles(m, k, p) for k, p in enumerate(mesh.get("primitives", [])))
              for m, mesh in enumerate(doc.get("meshes", []))]
    return sum(meshes[n["mesh"]] for n in doc.get("nodes", [])
               if isinstance(n.get("mesh"), int) and n["mesh"] < len(meshes))
