"""Each edit kind equals a cold load of the edited file (SPEC §9): the glTF is edited in Python
(the demo's JSON chunk), written as a new .glb and loaded cold; both render bit for bit alike."""

import copy

import numpy as np
import pytest

import aperture
from conftest import bits, read_glb, write_glb

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
