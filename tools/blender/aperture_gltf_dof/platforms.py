# SPDX-License-Identifier: MIT OR Apache-2.0
"""What the aperture program and the Open Image Denoise library are called on each platform, and
where the engine looks for them. No `bpy` here: tools/blender/test_platforms.py runs it with a
plain Python, as Windows, macOS and Linux."""

import os
import sys

OIDN = {"win32": "OpenImageDenoise.dll", "darwin": "libOpenImageDenoise.2.dylib"}


def exe(name, platform=sys.platform):
    """A program's file name: `name.exe` on Windows."""
    return name + ".exe" if platform == "win32" else name


def oidn_library(platform=sys.platform):
    """Open Image Denoise 2.x's file name, as aperture loads it (crates/denoise)."""
    return OIDN.get(platform, "libOpenImageDenoise.so.2")


def blender_lib_dirs(platform=sys.platform):
    """Folders beside Blender's executable (or in the bpy module) holding its libraries."""
    return ["blender.shared", "lib"] if platform == "win32" else ["lib"]


def find_aperture(setting, path_dirs, home, platform=sys.platform):
    """The aperture program, or None: the setting when given (the program, its folder, or on
    Windows the program without `.exe`), else `aperture` (`aperture.exe`) in a folder of PATH,
    else where `cargo install` puts it (~/.cargo/bin)."""
    name = exe("aperture", platform)
    if setting:
        candidates = [setting, os.path.join(setting, name)]
        if platform == "win32" and not setting.lower().endswith(".exe"):
            candidates.append(setting + ".exe")
    else:
        dirs = [d for d in path_dirs if d]
        if home:
            dirs.append(os.path.join(home, ".cargo", "bin"))
        candidates = [os.path.join(d, name) for d in dirs]
    return next((c for c in candidates if os.path.isfile(c)), None)
