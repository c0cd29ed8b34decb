#!/usr/bin/env python3
"""Cost of the thin lens's options (issue 61) against the plain thin lens on the demo.

Writes copies of a .glb with keys merged into its first camera's `extras`, renders each variant
in turn (alternated rounds: plain, option, plain, option, ...), and prints the median render time
(the EXR header's `aperture:renderTime`: no load or BVH build) and the ratio to the plain lens.

    python3 tools/bench/lens_options.py --binary target/release/aperture --rounds 7
    python3 tools/bench/lens_options.py --write-only out.glb '{"aperture_vignetting": 1}'
"""

import argparse
import json
import os
import statistics
import struct
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from many_lights import header_float  # noqa: E402

VARIANTS = {
    "plain (6 blades, f/1.4)": {},
    "vignetting 1 (6 blades)": {"aperture_vignetting": 1.0},
    "round, plain": {"aperture_blades": 0},
    "round, vignetting 1": {"aperture_blades": 0, "aperture_vignetting": 1.0},
    "distortion k1 -0.2, k2 0.05, p1 0.001": {
        "distortion_k1": -0.2, "distortion_k2": 0.05, "distortion_p1": 0.001},
    "round, vignetting 1 + distortion": {
        "aperture_blades": 0, "aperture_vignetting": 1.0, "distortion_k1": -0.2,
        "distortion_k2": 0.05, "distortion_p1": 0.001},
    # The bokeh image (a 128² star, `tools/lens/bokeh_image.py`, written beside the copies) and
    # chromatic aberration.
    "round, bokeh image (star)": {"aperture_blades": 0, "aperture_image": "lens_bench_star.png"},
    "bokeh image (star, 6 blades)": {"aperture_image": "lens_bench_star.png"},
    "chromatic lateral 0.003, longitudinal 0.02 (6 blades)": {
        "chromatic_lateral": 0.003, "chromatic_longitudinal": 0.02},
}


def with_extras(src, dst, keys):
    """Copy the .glb `src` to `dst` with `keys` merged into cameras[0].extras."""
    data = open(src, "rb").read()
    n = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + n])
    doc["cameras"][0].setdefault("extras", {}).update(keys)
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    rest = data[20 + n:]
    out = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + len(rest))
    out += struct.pack("<II", len(js), 0x4E4F534A) + js + rest
    open(dst, "wb").write(out)


def render_time(binary, path, args, out):
    cmd = ["nice", binary, "render", path, "-o", out, "--width", str(args.width), "--height",
           str(args.height), "--spp", str(args.spp), "--threads", "2", "--passes", "none",
           "--quiet"]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return header_float(out, "aperture:renderTime")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--binary", default="target/release/aperture")
    p.add_argument("--scene", default="assets/demo.glb")
    p.add_argument("--rounds", type=int, default=7)
    p.add_argument("--width", type=int, default=320)
    p.add_argument("--height", type=int, default=180)
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--write-only", nargs=2, metavar=("OUT", "JSON"))
    p.add_argument("--baseline", help="a binary without the options (e.g. main's), timed on the "
                   "plain lenses too")
    args = p.parse_args()
    if args.write_only:
        keys = json.loads(args.write_only[1])
        if keys.get("aperture_image") == "lens_bench_star.png":
            sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                            "lens"))
            import bokeh_image  # noqa: E402

            out_dir = os.path.dirname(os.path.abspath(args.write_only[0]))
            bokeh_image.png(os.path.join(out_dir, "lens_bench_star.png"), 128, bokeh_image.star)
        with_extras(args.scene, args.write_only[0], json.loads(args.write_only[1]))
        return
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "lens"))
    import bokeh_image  # noqa: E402

    bokeh_image.png("/tmp/lens_bench_star.png", 128, bokeh_image.star)
    paths = {}
    for i, (name, keys) in enumerate(VARIANTS.items()):
        paths[name] = f"/tmp/lens_bench_{i}.glb"
        with_extras(args.scene, paths[name], keys)
    runs = [(name, args.binary, paths[name]) for name in VARIANTS]
    if args.baseline:
        for name in ["plain (6 blades, f/1.4)", "round, plain"]:
            runs.append((f"{name}, baseline binary", args.baseline, paths[name]))
    times = {name: [] for name, _, _ in runs}
    for _ in range(args.rounds):
        for name, binary, path in runs:
            times[name].append(render_time(binary, path, args, "/tmp/lens_bench.exr"))
    med = {name: statistics.median(t) for name, t in times.items()}
    base = {name: med["round, plain" if name.startswith("round") else
                      "plain (6 blades, f/1.4)"] for name in times}
    print("| variant | median render time | ratio to its plain lens |")
    print("|---|---|---|")
    for name in times:
        print(f"| {name} | {med[name]:.3f} s | {med[name] / base[name]:.3f} |")


if __name__ == "__main__":
    main()
