#!/usr/bin/env python3
"""Peak memory and times of `aperture info` and `aperture render` on big scenes (issue 59),
for binaries A and B run in turn (A, B, A, B, ...), the median of ROUNDS each (A = B: one binary):

    python3 tools/bench/big_load.py A B ROUNDS FILE.glb...

Per binary and file: `info` wall time and peak RSS; `render` (320x240, 1 spp, no passes, 2
threads, BVH fast) wall time, peak RSS and the load / BVH / first-samples times of its summary
line (first samples only from binaries that print them). Peak RSS is the child's `ru_maxrss`
(os.wait4), so it needs no /proc reading by the binary. Make the files with
tools/bench/big_scene.py. Standard library only."""

import os
import re
import statistics
import subprocess
import sys
import tempfile
import time


def run(argv):
    """Wall seconds, peak RSS bytes and stderr of one run of `argv`."""
    t0 = time.perf_counter()
    p = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    err = p.stderr.read()
    _, status, usage = os.wait4(p.pid, 0)
    secs = time.perf_counter() - t0
    if status != 0:
        sys.exit(f"{' '.join(argv)}: {err[-400:]}")
    return secs, usage.ru_maxrss * 1024, err


def summary_times(err):
    """load, BVH and first-samples seconds of a render summary line (None when absent)."""
    def num(pattern):
        m = re.search(pattern, err)
        return float(m.group(1)) if m else None
    return num(r"\(load ([0-9.]+) s"), num(r"BVH \w+ ([0-9.]+) s"), num(r"first samples at ([0-9.]+) s")


def measure(binary, scene, out):
    """One round of `info` and `render` of `scene` by `binary`."""
    info_s, info_rss, _ = run([binary, "info", scene])
    argv = [binary, "render", scene, "-o", out, "--width", "320", "--height", "240", "--spp", "1",
            "--passes", "none", "--threads", "2", "--bvh-quality", "fast"]
    render_s, render_rss, err = run(argv)
    load, bvh, first = summary_times(err)
    return {"info s": info_s, "info MB": info_rss / 1e6, "render s": render_s,
            "render MB": render_rss / 1e6, "load s": load, "BVH s": bvh, "first samples s": first}


def median(rows, key):
    values = [r[key] for r in rows if r[key] is not None]
    return statistics.median(values) if values else None


def main():
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    a, b, rounds, scenes = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4:]
    keys = ["info s", "info MB", "render s", "render MB", "load s", "BVH s", "first samples s"]
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.exr")
        for scene in scenes:
            binaries = list(dict.fromkeys((a, b)))  # A = B: one binary, measured once a round
            rows = {x: [] for x in binaries}
            for _ in range(rounds):
                for binary in binaries:
                    rows[binary].append(measure(binary, scene, out))
            print(f"\n{os.path.basename(scene)}, median of {rounds}")
            print("| binary | " + " | ".join(keys) + " |")
            print("|---" * (len(keys) + 1) + "|")
            for binary in binaries:
                cells = [median(rows[binary], k) for k in keys]
                text = ["–" if c is None else f"{c:.2f}" if c < 100 else f"{c:.0f}" for c in cells]
                print(f"| {binary} | " + " | ".join(text) + " |")


if __name__ == "__main__":
    main()
