# SPDX-License-Identifier: MIT OR Apache-2.0
"""The add-on's platform names (aperture_gltf_dof/platforms.py) as Windows, macOS and Linux
see them: the engine finds `aperture.exe` on Windows and `aperture` elsewhere. Plain Python,
no Blender: `python3 tools/blender/test_platforms.py`."""

import importlib.util
import os
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location(
    "platforms", os.path.join(HERE, "aperture_gltf_dof", "platforms.py"))
platforms = importlib.util.module_from_spec(spec)
spec.loader.exec_module(platforms)


def touch(*parts):
    path = os.path.join(*parts)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    open(path, "w").close()
    return path


def check(got, want, what):
    if got != want:
        sys.exit(f"FAIL {what}: got {got!r}, want {want!r}")
    print(f"ok {what}")


def main():
    with tempfile.TemporaryDirectory() as t:
        on_path = os.path.join(t, "path")
        home = os.path.join(t, "home")
        exe = touch(on_path, "aperture.exe")
        find = platforms.find_aperture
        check(find("", [on_path], home, "win32"), exe, "Windows finds aperture.exe on PATH")
        check(find("", [on_path], home, "linux"), None, "Linux does not take aperture.exe")
        check(find("", [on_path], home, "darwin"), None, "macOS does not take aperture.exe")
        check(find(os.path.join(on_path, "aperture"), [], home, "win32"), exe,
              "Windows: a setting without .exe")
        check(find(on_path, [], home, "win32"), exe, "Windows: a folder as the setting")
        check(find(os.path.join(t, "nothing"), [on_path], home, "win32"), None,
              "a setting that names nothing is not replaced by PATH")
        cargo = touch(home, ".cargo", "bin", "aperture")
        check(find("", ["", os.path.join(t, "empty")], home, "linux"), cargo,
              "Linux: cargo install's ~/.cargo/bin after PATH")
        check(find("", [], home, "darwin"), cargo, "macOS: ~/.cargo/bin")
    check(platforms.oidn_library("win32"), "OpenImageDenoise.dll", "OIDN on Windows")
    check(platforms.oidn_library("darwin"), "libOpenImageDenoise.2.dylib", "OIDN on macOS")
    check(platforms.oidn_library("linux"), "libOpenImageDenoise.so.2", "OIDN on Linux")
    check(platforms.blender_lib_dirs("win32"), ["blender.shared", "lib"], "Blender's DLL folders")


if __name__ == "__main__":
    main()
