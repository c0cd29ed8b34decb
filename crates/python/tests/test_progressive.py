"""Progressive renders: steps that add up to N samples equal the one-shot N-sample render bit
for bit (beauty and every pass); cancel stops; an edit ends the render."""

import threading

import numpy as np
import pytest

import aperture
from conftest import bits

OPTS = dict(width=40, height=24, seed=7)


def same(a, b):
    ia, pa = a
    ib, pb = b
    assert np.array_equal(bits(ia), bits(ib))
    assert pa.keys() == pb.keys()
    for k in pa:
        assert np.array_equal(bits(pa[k]), bits(pb[k])), k


@pytest.mark.parametrize("steps", [[1, 3, 4], [8], [2, 2, 2, 2], [5, 100]])
def test_step_sums_equal_a_one_shot_render(demo, steps):
    scene = aperture.load(demo)
    r = scene.start(spp=8, **OPTS)
    assert r.samples == 0 and r.target == 8 and not r.done
    total = 0
    for n in steps:
        total = min(total + n, 8)
        assert r.step(n) == total
    assert r.done
    assert r.step(4) == 8, "no samples past the target"
    once = scene.render(spp=8, **OPTS)
    same(r.image(), once)
    assert r.image().samples == once.samples == 40 * 24 * 8


def test_doubling_schedule_and_partial_images(demo):
    scene = aperture.load(demo)
    r = scene.start(spp=8, passes=[], **OPTS)
    totals = []
    while not r.done:
        totals.append(r.step())
        image, passes = r.image()
        assert image.shape == (24, 40, 4)
        # A film read before its last sample says how many each pixel has, as a partial EXR.
        counts = passes.pop("Debug Sample Count", None)
        assert passes == {}
        if totals[-1] < 8:
            assert np.all(counts == totals[-1])
    assert totals == [1, 2, 4, 8]
    # Four samples in, the film equals the 4-sample render.
    r4 = scene.start(spp=8, passes=[], **OPTS)
    r4.step(4)
    same(r4.image(), scene.render(spp=4, passes=[], **OPTS))


def test_cancel_stops_the_render(demo):
    scene = aperture.load(demo)
    r = scene.start(spp=64, passes=[], **OPTS)
    r.step(2)
    r.cancel()
    assert r.done
    assert r.step(8) == 2
    # Cancelling from another thread during a long step returns early.
    big = scene.start(width=320, height=180, spp=4096, passes=[])
    timer = threading.Timer(0.5, big.cancel)
    timer.start()
    reached = big.step(4096)
    timer.join()
    assert reached == 0 and big.done
    image, _ = big.image()
    assert image.shape == (180, 320, 4)


def test_an_edit_ends_a_progressive_render(demo):
    scene = aperture.load(demo)
    r = scene.start(spp=4, passes=[], **OPTS)
    r.step(1)
    scene.set_camera(fstop=11.0)
    with pytest.raises(aperture.RenderError, match="edited"):
        r.step(1)
    with pytest.raises(aperture.RenderError):
        r.image()
    fresh = scene.start(spp=4, passes=[], **OPTS)
    fresh.step(4)
    same(fresh.image(), scene.render(spp=4, passes=[], **OPTS))


def _start_denoised(scene, **opts):
    """``scene.start(denoise=True, ...)``, or the missing-input rule when OIDN is absent."""
    try:
        return scene.start(denoise=True, **opts)
    except aperture.RenderError as e:
        if "Open Image Denoise" not in str(e):
            raise
        from conftest import missing
        missing("Open Image Denoise (tools/oidn/install.sh)")


@pytest.mark.parametrize("settings", [{}, dict(denoise_quality="balanced", denoise_prefilter="fast")])
def test_denoised_steps_equal_a_denoised_one_shot_render(demo, settings):
    """The viewport's denoising: a progressive render started with denoise=True gives, at N
    samples, the image of scene.render(spp=N, denoise=True) with the same settings, bit for
    bit; image(denoise=False) is the noisy film, which is the one-shot render's Noisy Image."""
    scene = aperture.load(demo)
    r = _start_denoised(scene, spp=4, passes="none", **settings, **OPTS)
    r.step(1)
    r.step(3)
    assert r.done
    once = scene.render(spp=4, passes="none", denoise=True, **settings, **OPTS)
    denoised = r.image()
    assert np.array_equal(bits(denoised.image), bits(once.image))
    noisy = r.image(denoise=False).image
    assert not np.array_equal(noisy[..., :3], denoised.image[..., :3]), "denoised"
    assert np.array_equal(bits(noisy[..., :3]), bits(once.passes["Noisy Image"][..., :3]))


def test_denoise_settings_differ_and_need_denoise(demo):
    scene = aperture.load(demo)
    _start_denoised(scene, spp=1, **OPTS)
    high = scene.render(spp=2, passes="none", denoise=True, **OPTS)
    fast = scene.render(spp=2, passes="none", denoise=True, denoise_quality="fast",
                        denoise_prefilter="none", **OPTS)
    assert not np.array_equal(bits(high.image), bits(fast.image)), "the settings reach OIDN"
    with pytest.raises(ValueError, match="need denoise=True"):
        scene.start(spp=2, denoise_quality="fast", **OPTS)
    with pytest.raises(ValueError, match="need denoise=True"):
        scene.render(spp=1, oidn="/nowhere/libOpenImageDenoise.so.2", **OPTS)
    with pytest.raises(aperture.RenderError, match="nowhere"):
        scene.render(spp=1, denoise=True, oidn="/nowhere/libOpenImageDenoise.so.2", **OPTS)
    with pytest.raises(ValueError, match="denoise_prefilter"):
        scene.render(spp=2, denoise=True, denoise_prefilter="slow", **OPTS)
    with pytest.raises(ValueError, match="started with denoise=True"):
        scene.start(spp=1, **OPTS).image(denoise=True)
