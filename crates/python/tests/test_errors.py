"""Every bad input raises the named exception with the library's message; none crashes."""

import numpy as np
import pytest

import aperture


@pytest.fixture(scope="module")
def scene(demo):
    return aperture.load(demo)


def test_load_errors(tmp_path, demo):
    with pytest.raises(aperture.LoadError, match="No such file"):
        aperture.load(tmp_path / "missing.glb")
    junk = tmp_path / "junk.glb"
    junk.write_bytes(b"glTF\x02\x00\x00\x00garbage")
    with pytest.raises(aperture.LoadError):
        aperture.load(junk)
    (tmp_path / "bad.gltf").write_text('{"asset": {"version": "2.0"}, "nodes": [{"mesh": 5}]}')
    with pytest.raises(aperture.LoadError):
        aperture.load(tmp_path / "bad.gltf")
    with pytest.raises(aperture.LoadError):
        aperture.load(demo, scene=9)
    with pytest.raises(aperture.LoadError):
        aperture.load(demo, variant="nope")
    assert issubclass(aperture.LoadError, Exception)


@pytest.mark.parametrize("options,match", [
    (dict(fstop=2, aperture_radius=0.1), "both"),
    (dict(fstop=0), "fstop"),
    (dict(fstop=float("nan")), "fstop"),
    (dict(aperture_radius=-1), "aperture_radius"),
    (dict(time=1, frame=2), "time and frame"),
    (dict(transmission="cycles"), "transmission"),
    (dict(max_memory="lots"), "max_memory"),
    (dict(no_dof=True, fstop=2), "no_dof"),
])
def test_bad_load_options(demo, options, match):
    with pytest.raises(ValueError, match=match):
        aperture.load(demo, **options)


def test_unknown_options_are_type_errors(demo, scene):
    with pytest.raises(TypeError, match="spp"):
        aperture.load(demo, spp=4)
    with pytest.raises(TypeError, match="sample"):
        scene.render(sample=4)
    with pytest.raises(TypeError):
        scene.render(spp="many")
    with pytest.raises(TypeError):
        scene.set_material(0, colour=[1, 0, 0, 1])
    with pytest.raises(TypeError):
        scene.set_camera(f_stop=2)


@pytest.mark.parametrize("options,match", [
    (dict(spp=0), "spp"),
    (dict(spp=-1), "spp"),
    (dict(spp=70000), "spp"),
    (dict(width=0), "width"),
    (dict(height=-5), "height"),
    (dict(passes=["Albedo"]), "Albedo"),
    (dict(passes="Depth,Nope"), "Nope"),
    (dict(camera="nope"), "camera"),
    (dict(camera=3), "camera"),
    (dict(camera=-1), "camera"),
    (dict(filter="mitchell"), "filter"),
    (dict(sampler="halton"), "sampler"),
    (dict(env=(1, 2)), "env"),
    (dict(env=(1, float("nan"), 2)), "env"),
    (dict(env="missing-sky.hdr"), "environment"),
    (dict(noise_threshold=0), "noise_threshold"),
    (dict(noise_threshold=0.1, min_spp=100, spp=8), "min_spp"),
    (dict(min_spp=4), "min_spp"),
    (dict(sample_offset=65535, spp=8), "sample_offset"),
    (dict(clamp_direct=-1), "clamp_direct"),
    (dict(seed=-3), "seed"),
    (dict(threads=0), "threads"),
    (dict(bvh_quality="best"), "bvh_quality"),
])
def test_bad_render_options(scene, options, match):
    base = dict(width=8, height=8, spp=1)
    base.update(options)
    with pytest.raises(ValueError, match=match):
        scene.render(**base)
    with pytest.raises(ValueError, match=match):
        scene.start(**base)


def rays(n=4):
    o = np.zeros((n, 3), np.float32)
    d = np.tile(np.float32([0, 0, -1]), (n, 1))
    return o, d


@pytest.mark.parametrize("make,match", [
    (lambda o, d: (o[:, :2], d), "shape"),
    (lambda o, d: (o.reshape(-1), d), "shape"),
    (lambda o, d: (o.astype(np.int64), d), "float32 or float64"),
    (lambda o, d: (o.astype(np.float16), d), "float32 or float64"),
    (lambda o, d: (o, d[:3]), "origins for"),
    (lambda o, d: (np.where(np.eye(4, 3, dtype=bool), np.nan, o).astype(np.float32), d),
     "origins"),
    (lambda o, d: (o, np.zeros_like(d)), "directions"),
    (lambda o, d: (o, np.full_like(d, np.inf)), "directions"),
    (lambda o, d: ([["a", "b", "c"]] * 4, d), "origins"),
])
def test_bad_rays(scene, make, match):
    o, d = make(*rays())
    with pytest.raises(ValueError, match=match):
        scene.intersect(o, d)
    with pytest.raises(ValueError, match=match):
        scene.occluded(o, d)


def test_bad_ray_bounds(scene):
    o, d = rays()
    for kw, match in [(dict(tmin=-1), "tmin"), (dict(tmax=float("nan")), "tmax"),
                      (dict(tmin=2, tmax=1), "tmin"), (dict(tmax=np.ones(3)), "tmax"),
                      (dict(tmin=float("inf")), "tmin")]:
        with pytest.raises(ValueError, match=match):
            scene.intersect(o, d, **kw)
    with pytest.raises(ValueError):
        scene.camera_rays(0)
    with pytest.raises(ValueError):
        scene.camera_rays(8, lens_samples=0)
    with pytest.raises(ValueError):
        scene.camera_rays(8, camera="nope")
    with pytest.raises(ValueError):
        scene.camera_rays(-1)
    with pytest.raises(ValueError, match="threads"):
        scene.intersect(o, d, threads=0)
    with pytest.raises(ValueError, match="threads"):
        scene.occluded(o, d, threads=-2)


def test_bad_edits(demo):
    scene = aperture.load(demo)
    with pytest.raises(ValueError, match="node"):
        scene.set_transform(999, np.eye(4))
    with pytest.raises(ValueError, match="named"):
        scene.set_transform("NoSuchNode", np.eye(4))
    with pytest.raises(ValueError, match="4×4"):
        scene.set_transform(1, np.eye(3))
    with pytest.raises(ValueError, match="finite"):
        scene.set_transform(1, np.full((4, 4), np.nan))
    with pytest.raises(ValueError, match="not both"):
        scene.set_transform(1, np.eye(4), translation=[0, 0, 0])
    with pytest.raises(ValueError, match="give a matrix"):
        scene.set_transform(1)
    with pytest.raises(ValueError, match="rotation must be 4"):
        scene.set_transform(1, rotation=[0, 0, 1])
    with pytest.raises(ValueError, match="finite"):
        scene.set_transform(1, scale=[1, float("inf"), 1])
    with pytest.raises(ValueError):
        scene.set_visible(999, False)
    with pytest.raises(ValueError):
        scene.set_material(99, roughness=0.5)
    with pytest.raises(ValueError, match="named"):
        scene.set_material("NoSuchMaterial", roughness=0.5)
    with pytest.raises(ValueError):
        scene.set_material(0, base_color=[1, 0])
    with pytest.raises(ValueError):
        scene.set_material(0, roughness=float("inf"))
    with pytest.raises(ValueError):
        scene.set_light(7, intensity=3)
    with pytest.raises(ValueError):
        scene.set_camera(fstop=float("nan"))
    with pytest.raises(ValueError):
        scene.set_camera(camera="nope", fstop=2)
    with pytest.raises(ValueError, match="Camera.*aperture_image.*no-such-star.png"):
        scene.set_camera(aperture_image="no-such-star.png")
    with pytest.raises(ValueError, match="lens_prescription"):
        scene.set_camera(lens_prescription=[[1.0, 2.0], 3.0])
    with pytest.raises(TypeError):
        scene.set_transform(1.5, np.eye(4))
    # After all that the scene still renders as loaded.
    fresh = aperture.load(demo).render(width=8, height=8, spp=1)[0]
    assert np.array_equal(scene.render(width=8, height=8, spp=1)[0], fresh)


def test_bad_writes(scene, tmp_path):
    result = scene.render(width=8, height=8, spp=1)
    with pytest.raises(ValueError, match="jpg|extension|format"):
        aperture.write(tmp_path / "out.jpg", result)
    with pytest.raises(ValueError):
        aperture.write(tmp_path / "out.exr", np.zeros((4, 4, 2), np.float32))
    with pytest.raises(ValueError):
        aperture.write(tmp_path / "out.exr", result, {"Depth": np.zeros((4, 4))})
    with pytest.raises(ValueError):
        aperture.write(tmp_path / "out.png", result, view="filmic")
    with pytest.raises(OSError):
        aperture.write(tmp_path / "no" / "such" / "dir.exr", result)
    with pytest.raises(ValueError):
        scene.start(width=8, height=8, spp=2).step(0)
