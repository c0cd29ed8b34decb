"""Property tests: random arrays and random option dicts through the bindings. Each call either
answers (and the answer keeps its promises) or raises ValueError/TypeError; the interpreter
never crashes (a crash would end the test run)."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import aperture

ALLOWED = (ValueError, TypeError)


@pytest.fixture(scope="module")
def scene(demo):
    return aperture.load(demo)


dtypes = st.sampled_from([np.float32, np.float64, np.float16, np.int32, np.uint8, np.bool_])
shapes = st.one_of(
    st.tuples(st.integers(0, 40), st.just(3)),
    hnp.array_shapes(min_dims=1, max_dims=3, max_side=5),
)
floats = st.floats(allow_nan=True, allow_infinity=True, width=32)


@st.composite
def arrays(draw):
    dtype, shape = draw(dtypes), draw(shapes)
    a = draw(hnp.arrays(dtype, shape, elements=hnp.from_dtype(np.dtype(dtype))
                        if dtype not in (np.float32, np.float64) else floats))
    if draw(st.booleans()):
        a = np.asfortranarray(a)
    return a


bounds = st.one_of(st.none(), floats.map(float), st.integers(-3, 3))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(o=arrays(), d=arrays(), tmin=bounds, tmax=bounds)
def test_random_arrays(scene, o, d, tmin, tmax):
    kw = {k: v for k, v in (("tmin", tmin), ("tmax", tmax)) if v is not None}
    try:
        hits = scene.intersect(o, d, **kw)
    except ALLOWED:
        with pytest.raises(ALLOWED):
            scene.occluded(o, d, **kw)
        return
    # Accepted: finite (N, 3) origins, finite non-zero directions, 0 <= tmin <= tmax.
    n = len(o)
    assert o.shape == (n, 3) and d.shape == (n, 3)
    assert np.all(np.isfinite(np.asarray(o, np.float64)))
    assert hits["t"].shape == (n,) and hits["normal"].shape == (n, 3)
    lo, hi = kw.get("tmin", 0.0), kw.get("tmax", np.inf)
    t = hits["t"][hits["hit"]]
    assert np.all((t >= np.float32(lo)) & (t <= np.float32(hi)))
    assert np.array_equal(scene.occluded(o, d, **kw), hits["hit"])


values = st.one_of(st.none(), st.booleans(), st.integers(-5, 70000),
                   st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=8),
                   st.lists(st.floats(-2, 2), max_size=4))
render_keys = st.sampled_from([
    "spp", "width", "height", "seed", "camera", "passes", "filter", "sampler", "env",
    "env_strength", "max_bounces", "clamp_direct", "noise_threshold", "min_spp",
    "sample_offset", "transmission", "single_sided", "override_material", "bvh_quality",
    "no_energy_compensation", "motion_blur", "shutter", "time", "frame", "fps", "threads",
    "env_rotation", "nonsense",
])


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(options=st.dictionaries(render_keys, values, max_size=4))
def test_random_render_options(scene, options):
    opts = dict(options)
    # Keep accepted renders tiny.
    for k in ("width", "height"):
        if isinstance(opts.get(k), int) and not isinstance(opts[k], bool) and opts[k] > 16:
            opts[k] = 16
    for k, default in (("width", 8), ("height", 6)):
        if opts.get(k) is None:
            opts[k] = default
    if isinstance(opts.get("spp"), int) and not isinstance(opts["spp"], bool) and opts["spp"] > 4:
        opts["spp"] = 4
    opts.setdefault("spp", 1)
    if isinstance(opts.get("max_bounces"), int) and opts["max_bounces"] > 4:
        opts["max_bounces"] = 4
    try:
        result = scene.render(**opts)
    except ALLOWED:
        return
    image, passes = result
    assert image.dtype == np.float32 and image.shape[2] == 4
    assert image.shape[:2] == (opts["height"], opts["width"])
    for name, array in passes.items():
        assert array.shape[:2] == image.shape[:2], name


load_keys = st.sampled_from(["scene", "variant", "time", "frame", "fps", "animation",
                             "aperture_radius", "fstop", "focus_distance", "focus_object",
                             "no_dof", "max_memory", "transmission", "single_sided", "bogus"])


@settings(max_examples=60, deadline=None)
@given(options=st.dictionaries(load_keys, values, max_size=3))
def test_random_load_options(demo, options):
    try:
        scene = aperture.load(demo, **options)
    except ALLOWED + (aperture.LoadError,):
        return
    assert scene.info()["meshes"] > 0
