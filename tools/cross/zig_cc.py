#!/usr/bin/env python3
# SPDX-License-Identifier: MIT OR Apache-2.0
"""The C (`zig-cc`) and C++ (`zig-c++`) compiler for aarch64-apple-darwin in
tools/cross/check.sh: zig from the `ziglang` wheel (run by the Python in $ZIG_PYTHON) has
macOS's C headers and libc++, which Debian has no package for, so clippy builds meshopt's and
FLIP's C++ for macOS. cc-rs passes Apple clang's target flags (`--target=arm64-apple-macosx`,
`-arch`, `-mmacosx-version-min`); zig takes its own `-target` instead."""

import os
import sys


def main():
    args, skip = [], False
    for a in sys.argv[1:]:
        if skip:
            skip = False
        elif a == "-arch":
            skip = True
        elif not a.startswith(("--target=", "-mmacosx-version-min=")):
            args.append(a)
    tool = "c++" if sys.argv[0].endswith("++") else "cc"
    python = os.environ["ZIG_PYTHON"]
    os.execv(python, [python, "-m", "ziglang", tool, "-target", "aarch64-macos", *args])


if __name__ == "__main__":
    main()
