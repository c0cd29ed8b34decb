"""Each edit kind equals a cold load of the edited file (SPEC §9): the glTF is edited in Python
(the demo's JSON chunk), written as a new .glb and loaded cold; both render bit for bit alike."""

import copy
import shutil
import struct
import zlib

import numpy as np
import pytest

import aperture
from conftest import ROOT, bits, read_glb, write_glb

OPTS = dict(width=40, height=24, spp=2, seed=1, passes=["Depth", "Normal", "CryptoObject"])

MATRIX = np.array([[0.0, 0.0, 0.2, 0.1],
                   [0.0, 0.2, 0.0, 0.15],
                   [-0.2, 0.0, 0.0, -1.1],
                   [0.0, 0.0, 0.0, 1.0]])


def camera_node(doc):
    return next(i for i, n in enumerate(doc["nodes"]) if "camera" in n)


def look_at(eye, target):
    """A camera's 4x4 world matrix at `eye` looking at `target` (+Y up, looking down -Z)."""
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    f = (target - eye) / np.linalg.norm(target - eye)
    r = np.cross(f, [0, 1, 0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = r, u, -f, eye
    return m


def set_matrix(node, m):
    for k in ("translation", "rotation", "scale"):
        node.pop(k, None)
    node["matrix"] = [float(np.float32(x)) for x in np.asarray(m).T.reshape(-1)]


def edit_transform(scene, doc):
    scene.set_transform(4, MATRIX)
    set_matrix(doc["nodes"][4], MATRIX)


def edit_transform_by_name(scene, doc):
    scene.set_transform("Row1_Box", MATRIX)
    set_matrix(doc["nodes"][2], MATRIX)


def edit_translation_and_rotation(scene, doc):
    # The components given replace the node's stored ones; the others (scale) stay.
    t, r = [0.5, 1.25, -2.0], [0.0, 0.38268343, 0.0, 0.92387953]
    scene.set_transform(4, translation=t, rotation=r)
    node = doc["nodes"][4]
    node.pop("matrix", None)
    node["translation"], node["rotation"] = t, r


def edit_visible(scene, doc):
    scene.set_visible(2, False)
    doc["nodes"][2].setdefault("extensions", {})["KHR_node_visibility"] = {"visible": False}
    doc.setdefault("extensionsUsed", []).append("KHR_node_visibility")


def edit_material(scene, doc):
    scene.set_material(3, base_color=[0.2, 0.9, 0.3, 1.0], roughness=0.7, metallic=0.0)
    pbr = doc["materials"][3]["pbrMetallicRoughness"]
    pbr.update(baseColorFactor=[0.2, 0.9, 0.3, 1.0], roughnessFactor=0.7, metallicFactor=0.0)


def edit_material_by_name(scene, doc):
    scene.set_material("WarmLight", emissive=[0.2, 0.5, 1.0], emissive_strength=20.0)
    m = next(m for m in doc["materials"] if m["name"] == "WarmLight")
    m["emissiveFactor"] = [0.2, 0.5, 1.0]
    m["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] = 20.0


def edit_light(scene, doc):
    scene.set_light(0, color=[0.5, 0.7, 1.0], intensity=900.0)
    light = doc["extensions"]["KHR_lights_punctual"]["lights"][0]
    light.update(color=[0.5, 0.7, 1.0], intensity=900.0)


def edit_camera_keys(scene, doc):
    scene.set_camera(fstop=4.0, blades=5, focus_object="Row4_Box")
    doc["cameras"][0]["extras"].update(aperture_fstop=4.0, aperture_blades=5,
                                       focus_object="Row4_Box")


def edit_lens_options(scene, doc):
    scene.set_camera(aperture_vignetting=0.5, distortion_k1=-0.2, distortion_p2=0.01)
    doc["cameras"][0]["extras"].update(aperture_vignetting=0.5, distortion_k1=-0.2,
                                       distortion_p2=0.01)


def edit_chromatic(scene, doc):
    scene.set_camera(chromatic_lateral=0.01, chromatic_longitudinal=-0.05)
    doc["cameras"][0]["extras"].update(chromatic_lateral=0.01, chromatic_longitudinal=-0.05)


def edit_camera_matrix(scene, doc):
    m = look_at([0.6, 0.5, 0.4], [0.0, 0.1, -1.8])
    scene.set_camera(matrix=m, focus_distance=2.0)
    set_matrix(doc["nodes"][camera_node(doc)], m)
    extras = doc["cameras"][0]["extras"]
    extras.pop("focus_object")
    extras["focus_distance"] = 2.0
    # focus_distance with focus_object present: the session keeps both, as the file would.
    scene.set_camera(focus_object=None)


EDITS = [edit_transform, edit_transform_by_name, edit_translation_and_rotation, edit_visible,
         edit_material,
         edit_material_by_name, edit_light, edit_camera_keys, edit_lens_options, edit_chromatic,
         edit_camera_matrix]


@pytest.mark.parametrize("edit", EDITS, ids=lambda f: f.__name__)
def test_edit_equals_a_cold_load(demo, tmp_path, edit):
    doc, binary = read_glb(demo)
    scene = aperture.load(demo)
    before = scene.render(**OPTS)  # a frame to edit in place
    edited = copy.deepcopy(doc)
    edit(scene, edited)
    path = tmp_path / "edited.glb"
    write_glb(path, edited, binary)
    warm = scene.render(**OPTS)
    cold = aperture.load(path).render(**OPTS)
    assert np.array_equal(bits(warm[0]), bits(cold[0]))
    assert warm[1].keys() == cold[1].keys()
    for k in cold[1]:
        assert np.array_equal(bits(warm[1][k]), bits(cold[1][k])), k
    # The edit changed the image (a test that cannot fail would prove nothing).
    assert not np.array_equal(bits(before[0]), bits(warm[0]))


def test_edits_in_sequence_equal_a_cold_load(demo, tmp_path):
    doc, binary = read_glb(demo)
    scene = aperture.load(demo)
    edited = copy.deepcopy(doc)
    for edit in (edit_light, edit_visible, edit_camera_keys, edit_transform):
        edit(scene, edited)
    write_glb(tmp_path / "all.glb", edited, binary)
    warm = scene.render(**OPTS)
    cold = aperture.load(tmp_path / "all.glb").render(**OPTS)
    assert np.array_equal(bits(warm[0]), bits(cold[0]))


# Issue 61: the bokeh image and the lens prescription as edits. The scene is the demo copied
# into tmp_path with a texture (a ring) added, beside a bokeh image (a triangle), a black image
# and the shipped double Gauss, so that the session and the cold load of the edited file (also
# in tmp_path) read the same relative paths.
LENS = ROOT / "assets" / "lenses" / "dgauss-50mm.dat"


def write_png(path, grey):
    """An 8-bit greyscale PNG of the H×W uint8 array `grey` (no imaging library)."""
    grey = np.asarray(grey, np.uint8)
    h, w = grey.shape
    raw = b"".join(b"\0" + row.tobytes() for row in grey)

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data)))

    header = struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                     + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def lens_rows():
    """The double Gauss's rows, as a list of [radius, thickness, IOR, aperture] lists."""
    lines = (line.split("#")[0].split() for line in LENS.read_text().splitlines())
    return [[float(x) for x in row] for row in lines if row]


@pytest.fixture
def lens_scene(demo, tmp_path):
    """(folder, document, binary chunk, base .glb) of the demo with a texture, and its images."""
    y, x = np.mgrid[0:32, 0:32]
    write_png(tmp_path / "triangle.png", np.where(abs(x - 15.5) * 2 < y, 255, 0))
    ring = abs(np.hypot(x - 15.5, y - 15.5) - 11) < 4
    write_png(tmp_path / "ring.png", np.where(ring, 230, 0))
    write_png(tmp_path / "black.png", np.zeros((4, 4)))
    (tmp_path / "lenses").mkdir()
    shutil.copy(LENS, tmp_path / "lenses" / LENS.name)
    doc, binary = read_glb(demo)
    doc["images"] = [{"uri": "ring.png"}]
    doc["textures"] = [{"source": 0}]
    base = tmp_path / "base.glb"
    write_glb(base, doc, binary)
    return tmp_path, doc, binary, base


LENS_EDITS = [
    ("aperture_image", "triangle.png"),
    ("aperture_image", 0),  # a texture no camera named: the session loads the file again
    ("lens_prescription", "lenses/dgauss-50mm.dat"),
    ("lens_prescription", lens_rows()),
]


def same_render(a, b):
    assert np.array_equal(bits(a[0]), bits(b[0]))
    assert a[1].keys() == b[1].keys()
    for k in b[1]:
        assert np.array_equal(bits(a[1][k]), bits(b[1][k])), k


@pytest.mark.parametrize("key,value", LENS_EDITS, ids=lambda v: str(v)[:24])
def test_lens_edit_equals_a_cold_load(lens_scene, key, value):
    folder, doc, binary, base = lens_scene
    scene = aperture.load(base)
    before = scene.render(**OPTS)
    scene.set_camera(**{key: value})
    edited = copy.deepcopy(doc)
    edited["cameras"][0]["extras"][key] = value
    write_glb(folder / "edited.glb", edited, binary)
    warm = scene.render(**OPTS)
    cold = aperture.load(folder / "edited.glb").render(**OPTS)
    same_render(warm, cold)
    assert not np.array_equal(bits(before[0]), bits(warm[0]))
    # None removes the key: the image as loaded again.
    scene.set_camera(**{key: None})
    same_render(scene.render(**OPTS), before)


def test_bad_lens_edits_raise_and_change_nothing(lens_scene):
    _, _, _, base = lens_scene
    scene = aperture.load(base)
    before = scene.render(**OPTS)
    image = 'camera "Camera": cameras.extras.aperture_image'
    lens = 'camera "Camera": cameras.extras.lens_prescription'
    for value, match in [("missing.png", "missing.png"), ("black.png", "black"),
                         ("../triangle.png", "triangle.png"), (7, r"textures\[7\]"),
                         (-1, "texture index"), ("", "expected an image path")]:
        with pytest.raises(ValueError, match=f"{image}.*{match}"):
            scene.set_camera(aperture_image=value)
    for value, match in [("nowhere.dat", "nowhere.dat"), ([[30, 4, 1.6]], "row 0"),
                         ([[0, 4, 0, 12], [0, 4, 0, 12]], "stop")]:
        with pytest.raises(ValueError, match=f"{lens}.*{match}"):
            scene.set_camera(lens_prescription=value)
    # Shapes Python cannot pass as JSON name the key.
    for value in ([30, 4, 1.6, 20], [[30, 4, float("nan"), 20]], [["a", 4, 1.6, 20]], {"r": 1}):
        with pytest.raises(ValueError, match="lens_prescription"):
            scene.set_camera(lens_prescription=value)
    same_render(scene.render(**OPTS), before)


def test_a_material_only_hidden_nodes_use_can_be_edited(demo, tmp_path):
    # FillPanel (node 21) alone uses material 11: hidden, its mesh is not even decoded, but the
    # file has the material and the edit holds once the node is shown again.
    doc, binary = read_glb(demo)
    scene = aperture.load(demo)
    scene.set_visible(21, False)
    scene.set_material(11, base_color=[0.9, 0.1, 0.6, 1.0], emissive=[0.0, 1.0, 0.0])
    scene.set_visible(21, True)
    edited = copy.deepcopy(doc)
    edited["materials"][11].setdefault("pbrMetallicRoughness", {})["baseColorFactor"] = [0.9, 0.1, 0.6, 1.0]
    edited["materials"][11]["emissiveFactor"] = [0.0, 1.0, 0.0]
    write_glb(tmp_path / "m.glb", edited, binary)
    warm = scene.render(**OPTS)
    assert np.array_equal(bits(warm[0]), bits(aperture.load(tmp_path / "m.glb").render(**OPTS)[0]))
    assert not np.array_equal(bits(warm[0]), bits(aperture.load(demo).render(**OPTS)[0]))
