"""scene.render against `aperture render`: the same options give the same EXR bit for bit,
and aperture.write writes the file the command line writes; scene.info against
`aperture info --json`."""

import json

import numpy as np
import pytest

import aperture
from conftest import bits, run_cli

# (the command line's flags, load(**options), render(**options)): the same render.
CASES = [
    (["--width", "48", "--height", "27", "--spp", "4", "--seed", "3"],
     {}, dict(width=48, height=27, spp=4, seed=3)),
    (["--width", "40", "--spp", "3", "--fstop", "2.8", "--passes", "all", "--filter", "box",
      "--max-bounces", "3", "--env", "0.2,0.3,0.4", "--single-sided", "gltf"],
     dict(fstop=2.8), dict(width=40, spp=3, passes="all", filter="box", max_bounces=3,
                           env=(0.2, 0.3, 0.4), single_sided="gltf")),
    (["--height", "20", "--spp", "2", "--passes", "Depth,Emission", "--camera", "0",
      "--sampler", "random", "--clamp-indirect", "2", "--no-dof"],
     dict(no_dof=True), dict(height=20, spp=2, passes=["Depth", "Emission"], camera=0,
                             sampler="random", clamp_indirect=2)),
]


def cli_exr(binary, scene, flags, tmp_path, reader, name="cli.exr"):
    out = tmp_path / name
    run_cli(binary, "render", scene, "-o", out, "--quiet", *flags)
    return reader(out)


@pytest.mark.parametrize("flags,load,render", CASES)
def test_numpy_image_equals_the_cli_exr(demo, aperture_bin, exr_reader, tmp_path, flags, load,
                                        render):
    header, channels = cli_exr(aperture_bin, demo, flags, tmp_path, exr_reader)
    scene = aperture.load(demo, **load)
    result = scene.render(**render)
    image, passes = result
    assert image.dtype == np.float32 and image.ndim == 3 and image.shape[2] == 4
    assert image.shape[:2] == channels["R"].shape
    for k, c in enumerate("RGBA"):
        assert np.array_equal(bits(image[..., k]), bits(channels[c])), c
    # Every pass, every channel, by the EXR's names; nothing more, nothing less.
    seen = {"R", "G", "B", "A"}
    for layer, array in passes.items():
        for k, c in enumerate(result.channels[layer]):
            name = f"{layer}.{c}"
            assert name in channels, name
            assert np.array_equal(bits(array[..., k]), bits(channels[name])), name
            seen.add(name)
    assert seen == set(channels)
    assert image[..., 3].max() > 0.0, "something is drawn"
    assert int(header["aperture:spp"]) == result.header["aperture:spp"] == render["spp"]


def test_write_gives_the_cli_file(demo, aperture_bin, exr_reader, tmp_path):
    flags, load, render = CASES[0]
    cli_header, cli = cli_exr(aperture_bin, demo, flags, tmp_path, exr_reader)
    result = aperture.load(demo, **load).render(**render)
    aperture.write(tmp_path / "py.exr", result)
    header, ours = exr_reader(tmp_path / "py.exr")
    assert set(ours) == set(cli)
    for name in cli:
        assert np.array_equal(bits(ours[name]), bits(cli[name])), name
    # The same header but for the clock.
    varying = {"capDate", "utcOffset", "aperture:renderTime"}
    assert set(header) == set(cli_header)
    for key in set(cli_header) - varying:
        assert repr(header[key]) == repr(cli_header[key]), key
    # PNG: through the library's PNG writer (8-bit sRGB, opaque).
    aperture.write(tmp_path / "py.png", result)
    png = (tmp_path / "py.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"


def test_write_plain_arrays(tmp_path, exr_reader):
    rng = np.random.default_rng(1)
    image = rng.random((5, 7, 4), dtype=np.float32)
    depth = rng.random((5, 7), dtype=np.float32)
    aperture.write(tmp_path / "plain.exr", np.asfortranarray(image), {"Depth": depth})
    _, ch = exr_reader(tmp_path / "plain.exr")
    for k, c in enumerate("RGBA"):
        assert np.array_equal(ch[c], image[..., k])
    assert np.array_equal(ch["Depth.Z"], depth)


def test_info_matches_the_cli_json(demo, aperture_bin):
    cli = json.loads(run_cli(aperture_bin, "info", demo, "--json"))
    ours = aperture.load(demo).info()
    assert ours, "info is a dict with keys"
    # Every key info() has is the CLI's, with its value (the CLI adds a few it computes itself:
    # extensions, motion, degenerate and emissive triangle counts).
    def subset(a, b, at):
        if isinstance(a, dict):
            assert isinstance(b, dict), at
            for k in a:
                assert k in b, f"{at}/{k}"
                subset(a[k], b[k], f"{at}/{k}")
        elif isinstance(a, list):
            assert isinstance(b, list) and len(a) == len(b), at
            for i, (x, y) in enumerate(zip(a, b)):
                subset(x, y, f"{at}/{i}")
        else:
            assert a == b, at
    subset(ours, cli, "")
    assert len(ours) >= 15 and ours["triangles"]["unique"] == cli["triangles"]["unique"] > 0
    assert ours["cameras"][0]["dof"]["blades"] == cli["cameras"][0]["dof"]["blades"]


def test_time_and_frame_pose_the_scene(demo):
    scene = aperture.load(demo, frame=12, fps=24)
    assert scene.info()["time"] == 0.5


def test_gil_is_released_during_a_render(demo):
    import threading
    import time

    scene = aperture.load(demo)
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    t0 = time.perf_counter()
    scene.render(width=160, height=90, spp=16, passes=[])
    elapsed = time.perf_counter() - t0
    stop.set()
    t.join()
    during = [x for x in ticks if t0 <= x <= t0 + elapsed]
    # A thread that held the GIL for the render would have let the counter tick ~never.
    assert elapsed > 0.05 and len(during) > elapsed / 0.01, (elapsed, len(during))


INTERRUPT_SCRIPT = """
import sys, time, aperture
scene = aperture.load(sys.argv[1])
print("ready", flush=True)
t0 = time.perf_counter()
try:
    scene.render(width=640, height=360, spp=4096, passes=[])
    print("finished", flush=True)
except KeyboardInterrupt:
    print(f"interrupted {time.perf_counter() - t0:.2f}", flush=True)
"""


def test_ctrl_c_cancels_a_render(demo, tmp_path):
    import signal
    import subprocess
    import sys
    import time

    script = tmp_path / "interrupt.py"
    script.write_text(INTERRUPT_SCRIPT)
    p = subprocess.Popen([sys.executable, str(script), str(demo)], stdout=subprocess.PIPE,
                         text=True)
    assert p.stdout.readline().strip() == "ready"
    time.sleep(1.0)
    sent = time.perf_counter()
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=60)
    stopped = time.perf_counter() - sent
    assert out.startswith("interrupted"), out
    # A 4096-spp render takes minutes; the interrupt stops it within a batch of samples.
    assert stopped < 10.0, stopped


def test_denoise_equals_the_cli(demo, aperture_bin, exr_reader, tmp_path):
    """--denoise through Open Image Denoise (tools/oidn/install.sh puts it in the cache)."""
    out = tmp_path / "dn.exr"
    import subprocess
    flags = ["--width", "48", "--height", "27", "--spp", "4", "--denoise", "--quiet"]
    done = subprocess.run([str(aperture_bin), "render", str(demo), "-o", str(out), *flags],
                          capture_output=True, text=True)
    if done.returncode != 0 and "Open Image Denoise" in done.stderr:
        from conftest import missing
        missing("Open Image Denoise (tools/oidn/install.sh)")
    assert done.returncode == 0, done.stderr
    _, cli = exr_reader(out)
    result = aperture.load(demo).render(width=48, height=27, spp=4, denoise=True)
    image, passes = result
    for k, c in enumerate("RGBA"):
        assert np.array_equal(bits(image[..., k]), bits(cli[c])), c
    noisy = passes["Noisy Image"]
    assert not np.array_equal(noisy[..., :3], image[..., :3]), "the beauty is denoised"
    assert np.array_equal(bits(noisy[..., 0]), bits(cli["Noisy Image.R"]))
