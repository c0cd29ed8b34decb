#!/usr/bin/env python3
"""Self-test of check_layout.py on tiny fake workspaces built in a temp dir: a circle closed
through a `pub use` re-export is reported (it used to be hidden by following the re-export to the
defining file), and the same tree without the back import reports none.

    python3 tools/layout/test_check_layout.py     # plain asserts; exit 1 on a failure
    python3 -m pytest tools/layout/test_check_layout.py   # the same tests under pytest
"""

import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def write_tree(root, files):
    for rel, text in files.items():
        path = os.path.join(root, rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w") as f:
            f.write(text)


def cargo(name):
    return f'[package]\nname = "{name}"\nversion = "0.1.0"\n'


# bands.rs takes TILE through render.rs's re-export; render.rs imports bands.rs back.
RENDER_LIKE = {
    "crates/fake/Cargo.toml": cargo("aperture-fake"),
    "crates/fake/src/lib.rs": "mod bands;\nmod render;\n",
    "crates/fake/src/render.rs": (
        "mod tiles;\n"
        "pub use tiles::TILE;\n"
        "use crate::bands::progress;\n"
        "pub fn run() -> u32 { progress() }\n"
    ),
    "crates/fake/src/render/tiles.rs": "pub const TILE: u32 = 16;\n",
    "crates/fake/src/bands.rs": "use crate::render::TILE;\npub fn progress() -> u32 { TILE }\n",
}


def run_checker(root):
    """Runs a copy of the checker placed in `root`'s tools/layout (it checks the tree it sits in)
    with `--graph`: (exit code, its output, {file: imported files}, [circle lines])."""
    dst = os.path.join(root, "tools", "layout")
    os.makedirs(dst, exist_ok=True)
    shutil.copy(os.path.join(HERE, "check_layout.py"), dst)
    run = subprocess.run(
        [sys.executable, os.path.join(dst, "check_layout.py"), "--graph"],
        capture_output=True,
        text=True,
    )
    edges, circles = {}, []
    for line in run.stdout.splitlines():
        if " -> " in line and not line.startswith(" "):
            f, ts = line.split(" -> ", 1)
            edges[f] = set(ts.split(", "))
        elif line.startswith("  circle: "):
            circles.append(line[len("  circle: "):])
    return run.returncode, run.stdout, edges, circles


def test_circle_through_reexport_is_reported():
    with tempfile.TemporaryDirectory() as root:
        write_tree(root, RENDER_LIKE)
        _, out, _, circles = run_checker(root)
        assert circles == ["crates/fake/src/bands.rs <-> crates/fake/src/render.rs"], out


def test_reexport_imports_the_reexporting_file():
    with tempfile.TemporaryDirectory() as root:
        write_tree(root, RENDER_LIKE)
        _, _, edges, _ = run_checker(root)
        # The user of the re-export imports the file that makes it, not the defining file...
        assert edges["crates/fake/src/bands.rs"] == {"crates/fake/src/render.rs"}, edges
        # ...and the re-exporting file imports the defining one.
        assert "crates/fake/src/render/tiles.rs" in edges["crates/fake/src/render.rs"], edges


def test_no_back_import_no_circle():
    tree = dict(RENDER_LIKE)
    tree["crates/fake/src/render.rs"] = "mod tiles;\npub use tiles::TILE;\npub fn run() {}\n"
    with tempfile.TemporaryDirectory() as root:
        write_tree(root, tree)
        code, out, _, circles = run_checker(root)
        assert circles == [] and code == 0, out


def test_reexport_across_crates_imports_the_crate_root():
    tree = {
        "crates/a/Cargo.toml": cargo("aperture-a"),
        "crates/a/src/lib.rs": "mod inner;\npub use inner::Thing;\n",
        "crates/a/src/inner.rs": "pub struct Thing;\n",
        "crates/b/Cargo.toml": cargo("aperture-b"),
        "crates/b/src/lib.rs": "pub fn make() -> aperture_a::Thing { aperture_a::Thing }\n",
    }
    with tempfile.TemporaryDirectory() as root:
        write_tree(root, tree)
        _, _, edges, _ = run_checker(root)
        assert edges["crates/b/src/lib.rs"] == {"crates/a/src/lib.rs"}, edges
        assert edges["crates/a/src/lib.rs"] == {"crates/a/src/inner.rs"}, edges


def test_output_reports_the_circle_and_fails():
    with tempfile.TemporaryDirectory() as root:
        write_tree(root, RENDER_LIKE)
        code, out, _, _ = run_checker(root)
        assert code == 1, out
        assert "import circles between files: 1\n" in out, out
        assert "  circle: crates/fake/src/bands.rs <-> crates/fake/src/render.rs\n" in out, out


if __name__ == "__main__":
    failed = 0
    for name, fn in sorted(globals().items()):
        if name.startswith("test_") and callable(fn):
            try:
                fn()
                print(f"ok   {name}")
            except AssertionError as e:
                failed += 1
                print(f"FAIL {name}: {e}")
    sys.exit(1 if failed else 0)
