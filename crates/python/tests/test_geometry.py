"""Geometry given from numpy (`Scene.set_geometry`, `aperture.load(geometry=)`) equals a cold load
of a file that stores those arrays as the primitives' accessors (SPEC §9), and bad arrays raise."""

import copy

import numpy as np
import pytest

import aperture
from conftest import bits, read_glb, write_glb

OPTS = dict(width=40, height=24, spp=2, seed=1, passes=["Depth", "Normal", "CryptoObject"])


def bumpy(n, radius, seed):
    """A closed, bumpy UV sphere: positions, normals (of the unbumped sphere: shading differs
    from the flat facets), texture coordinates and triangles, as numpy arrays."""
    rng = np.random.default_rng(seed)
    th, ph = np.meshgrid(np.linspace(0, np.pi, n), np.linspace(0, 2 * np.pi, 2 * n), indexing="ij")
    d = np.stack([np.sin(th) * np.cos(ph), np.cos(th), np.sin(th) * np.sin(ph)], -1).reshape(-1, 3)
    r = radius * (1 + 0.15 * rng.random(len(d)))
    tris = []
    for i in range(n - 1):
        for j in range(2 * n - 1):
            a, b, c, e = i * 2 * n + j, i * 2 * n + j + 1, (i + 1) * 2 * n + j, (i + 1) * 2 * n + j + 1
            tris += [(a, c, b), (b, c, e)]
    uv = np.stack([ph.reshape(-1) / (2 * np.pi), th.reshape(-1) / np.pi], -1)
    return dict(positions=(d * r[:, None]).astype(np.float32), normals=d.astype(np.float32),
                uvs=uv.astype(np.float32), triangles=np.array(tris, dtype=np.uint32))


def slab(size, height):
    """A box without normals (flat: each triangle its own), indices as int64."""
    x, z = size, size
    p = np.array([[sx * x, sy * height, sz * z] for sx in (-1, 1) for sy in (0, 1) for sz in (-1, 1)],
                 np.float64)
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = [t for a, b, c, d in faces for t in ((a, b, c), (a, c, d))]
    return dict(positions=p, triangles=np.array(tris, dtype=np.int64))


GIVEN = {
    4: [bumpy(12, 0.35, 1)],                 # Row3_Sphere: shares its accessors with meshes 1, 7
    0: [slab(3.0, 0.05), slab(0.5, 0.4)],    # Ground: two primitives, two materials
}


def store(doc, binary, mesh, prims):
    """`doc` with mesh `mesh`'s primitives reading `prims` from new accessors after `binary`."""
    binary = bytearray(binary)

    def accessor(a, type_, component):
        a = np.ascontiguousarray(a)
        binary.extend(b"\0" * (-len(binary) % 4))
        doc["bufferViews"].append(dict(buffer=0, byteOffset=len(binary), byteLength=a.nbytes))
        binary.extend(a.tobytes())
        acc = dict(bufferView=len(doc["bufferViews"]) - 1, componentType=component,
                   count=len(a), type=type_)
        if type_ == "VEC3":
            acc.update(min=a.min(0).tolist(), max=a.max(0).tolist())
        doc["accessors"].append(acc)
        return len(doc["accessors"]) - 1

    for prim, g in zip(doc["meshes"][mesh]["primitives"], prims):
        attributes = {"POSITION": accessor(g["positions"].astype(np.float32), "VEC3", 5126)}
        if "normals" in g:
            attributes["NORMAL"] = accessor(g["normals"], "VEC3", 5126)
        if "uvs" in g:
            attributes["TEXCOORD_0"] = accessor(g["uvs"], "VEC2", 5126)
        prim["attributes"] = attributes
        prim["indices"] = accessor(g["triangles"].astype(np.uint32).reshape(-1), "SCALAR", 5125)
    doc["buffers"][0]["byteLength"] = len(binary)
    return bytes(binary)


def cold(demo, tmp_path):
    doc, binary = read_glb(demo)
    doc = copy.deepcopy(doc)
    for mesh, prims in GIVEN.items():
        binary = store(doc, binary, mesh, prims)
    path = tmp_path / "stored.glb"
    write_glb(path, doc, binary)
    return aperture.load(path).render(**OPTS)


def same(a, b):
    assert np.array_equal(bits(a[0]), bits(b[0]))
    for k in b[1]:
        assert np.array_equal(bits(a[1][k]), bits(b[1][k])), k


def test_set_geometry_equals_a_cold_load(demo, tmp_path):
    scene = aperture.load(demo)
    before = scene.render(**OPTS)
    for mesh, prims in GIVEN.items():
        scene.set_geometry(mesh, prims)
    warm = scene.render(**OPTS)
    same(warm, cold(demo, tmp_path))
    assert not np.array_equal(bits(before[0]), bits(warm[0]))
    # Edits after it replay it: a reload (visibility) keeps the given geometry.
    scene.set_visible(2, True)
    same(scene.render(**OPTS), warm)


def test_load_with_geometry_equals_a_cold_load(demo, tmp_path):
    same(aperture.load(demo, geometry=GIVEN).render(**OPTS), cold(demo, tmp_path))


def test_the_last_geometry_given_counts(demo):
    scene = aperture.load(demo)
    scene.set_geometry(4, [bumpy(6, 0.2, 3)])
    scene.set_geometry(4, GIVEN[4])
    same(scene.render(**OPTS), aperture.load(demo, geometry={4: GIVEN[4]}).render(**OPTS))


def _bad(**change):
    g = dict(bumpy(4, 0.3, 0))
    g.update(change)
    return [{k: v for k, v in g.items() if v is not None}]


@pytest.mark.parametrize("mesh, prims, error, says", [
    (4, _bad(triangles=np.array([[0, 1, 99]])), ValueError, "triangles[0]"),
    (4, _bad(positions=np.full((32, 3), np.nan)), ValueError, "positions[0]"),
    (4, _bad(normals=np.zeros((3, 3))), ValueError, "normals"),
    (4, _bad(uvs=np.zeros((32, 3))), ValueError, "2 columns"),
    (4, _bad(triangles=np.array([[0.0, 1.0, 2.0]])), ValueError, "integers"),
    (4, _bad(triangles=np.array([[0, -1, 2]])), ValueError, "index -1"),
    (4, _bad(triangles=np.array([[0, -1, 2]], np.int32)), ValueError, "index -1"),
    (4, _bad(positions=None), ValueError, "positions is missing"),
    (4, [dict(bumpy(4, 0.3, 0), colour=np.zeros((32, 4)))], ValueError, "unknown key"),
    (0, _bad(), ValueError, "the mesh has 2"),
    (99, _bad(), ValueError, "meshes[99]"),
    (-1, _bad(), ValueError, "≥ 0"),
    ("Ground", _bad(), TypeError, "index"),
    (4, _bad()[0], TypeError, "list"),
    (4, ["not a dict"], TypeError, "dict"),
])
def test_bad_geometry_raises_and_changes_nothing(demo, mesh, prims, error, says):
    scene = aperture.load(demo)
    before = scene.render(**OPTS)
    with pytest.raises(error) as e:
        scene.set_geometry(mesh, prims)
    assert says in str(e.value)
    same(scene.render(**OPTS), before)
