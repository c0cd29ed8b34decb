#!/usr/bin/env bash
# SPDX-License-Identifier: MIT OR Apache-2.0
# Issue 62: the other platforms, checked from this x86-64 Linux machine.
#
#   tools/cross/check.sh [aarch64] [windows]     (both when none is named)
#
# 1. installs what it lacks: the rustup targets, Debian's aarch64 and mingw-w64 cross compilers
#    (C and C++: meshopt and FLIP are built from C++), qemu-user and wine;
# 2. clippy -D warnings for aarch64-unknown-linux-gnu and x86_64-pc-windows-gnu (all targets);
#    the same clippy for aarch64-apple-darwin (check only, no linking: no macOS SDK), with zig
#    from PyPI's `ziglang` wheel as its C and C++ compiler (tools/cross/zig_cc.py);
# 3. builds `aperture` (debug) for aarch64 and for Windows, renders the demo with each, under
#    qemu-aarch64 and wine, and compares the pixels bit for bit with the x86-64 build's
#    (target/debug/aperture, built here when missing); runs the aarch64 unit tests of budget,
#    denoise and accel (there the NEON kernels against the scalar ones) and the packet
#    queries' whole-scene tests under qemu-aarch64;
# 4. builds the Python module's abi3 wheel (maturin, debug) for both: the aarch64 wheel renders
#    the demo in Debian's arm64 CPython 3.11 and numpy under qemu-aarch64 (their packages are
#    downloaded with a private apt state and unpacked into a cached sysroot, nothing installed)
#    and joins the comparison; the Windows wheel (pyo3 links python3.dll as raw-dylib, so no
#    import library; no Windows Python here to load it) must link python3.dll and no MinGW
#    runtime DLL. macOS: clippy only, as a wheel does not link without Apple's SDK (sysinfo
#    links IOKit and CoreFoundation).
#
# Cross builds compile dependencies at opt-level 0 and without debug info (the dev profile's
# opt-level 3 is for tests): half the build time, and the same images, as Rust's float
# arithmetic does not depend on the optimisation level.
#
# Windows: the C++ runtime is linked statically (cc's CXXSTDLIB_STATIC), so aperture.exe needs
# no libstdc++-6.dll; Debian 12's wine 8 lacks bcryptprimitives.dll (ProcessPrng, which Rust's
# std calls for random seeds; wine has it from 9), so a stand-in built from
# tools/cross/bcryptprimitives.c is put beside the .exe for the test only.
set -euo pipefail
cd "$(dirname "$0")/../.."
export CARGO_TERM_COLOR=never
export CARGO_INCREMENTAL=0
start=$(date +%s)
step() { echo "== $* ($(($(date +%s) - start)) s; $(df -h --output=avail . | tail -1 | tr -d ' ') free)"; }
# Under CI (a fresh clone, deleted afterwards) each target's build is removed once its last
# step is done: the three cross builds together take about 2 GB, which a nearly full disk lacks.
done_with() { [ "${CI:-}" != true ] || rm -rf "$target_dir/$1"; }

ARM=aarch64-unknown-linux-gnu
WIN=x86_64-pc-windows-gnu
MAC=aarch64-apple-darwin
target_dir="${CARGO_TARGET_DIR:-target}"
cross=(--config 'profile.dev.package."*".opt-level=0' --config 'profile.dev.debug=false')
platforms=" ${*:-aarch64 windows} "
want() { [[ "$platforms" == *" $1 "* ]]; }
for p in $platforms; do
    [[ "$p" == aarch64 || "$p" == windows ]] || { echo "unknown platform: $p" >&2; exit 2; }
done

step "install: rustup targets, cross compilers, qemu-user, wine"
rustup target add "$ARM" "$WIN" "$MAC" 2>&1 | grep -v "is up to date" || true
missing=()
for p in gcc-aarch64-linux-gnu g++-aarch64-linux-gnu libc6-dev-arm64-cross \
    gcc-mingw-w64-x86-64 g++-mingw-w64-x86-64 qemu-user wine wine64; do
    dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER="qemu-aarch64 -L /usr/aarch64-linux-gnu"
export CXXSTDLIB_STATIC_x86_64_pc_windows_gnu=1

if want aarch64; then
    step "clippy $ARM"
    cargo clippy --workspace --all-targets --target "$ARM" -- -D warnings
fi
if want windows; then
    step "clippy $WIN"
    cargo clippy --workspace --all-targets --target "$WIN" -- -D warnings
fi
step "clippy $MAC (zig as the C/C++ compiler; no linking)"
zig_venv="${XDG_CACHE_HOME:-$HOME/.cache}/aperture/zig-venv"
if ! "$zig_venv/bin/python" -m ziglang version >/dev/null 2>&1; then
    python3 -m venv "$zig_venv"
    "$zig_venv/bin/pip" install --quiet --disable-pip-version-check "ziglang==0.17.1"
fi
zig_bin="$zig_venv/aperture-bin"
mkdir -p "$zig_bin"
ln -sf "$PWD/tools/cross/zig_cc.py" "$zig_bin/zig-cc"
ln -sf "$PWD/tools/cross/zig_cc.py" "$zig_bin/zig-c++"
printf '#!/bin/sh\nexec "%s" -m ziglang ar "$@"\n' "$zig_venv/bin/python" >"$zig_bin/zig-ar"
chmod +x "$zig_bin/zig-ar"
ZIG_PYTHON="$zig_venv/bin/python" CC_aarch64_apple_darwin="$zig_bin/zig-cc" \
    CXX_aarch64_apple_darwin="$zig_bin/zig-c++" AR_aarch64_apple_darwin="$zig_bin/zig-ar" \
    cargo clippy --workspace --all-targets --target "$MAC" -- -D warnings
done_with "$MAC"

out=$(mktemp -d)
export WINEPREFIX="$out/wine" WINEDEBUG=-all
trap 'wineserver -k >/dev/null 2>&1 || true; rm -rf "$out"' EXIT
args=(render assets/demo.glb --width 160 --height 90 --spp 4 --quiet)
step "render the demo on x86-64"
cargo build --quiet -p aperture-cli
"$target_dir/debug/aperture" "${args[@]}" -o "$out/x86_64.png"

if want aarch64; then
    step "build aperture for $ARM (debug); the budget, denoise and accel unit tests under qemu-aarch64"
    cargo build --quiet "${cross[@]}" -p aperture-cli --target "$ARM"
    # denoise's tests/library.rs loads OIDN, which exists here for x86-64 only (and under
    # CI=true a missing library fails): its unit tests (names, places, errors) run. accel's
    # unit tests check the NEON kernels (node box test, sheared vertices, spawn offset, AVX's
    # eight-float operations in NEON and the packet kernels built on them) against the scalar
    # ones bit for bit; packet_blocker and three of accel_brute_force's scenes (coherent lens
    # rays, rays grazing the bounds, instancing; the other three take minutes under qemu) check
    # the packet queries' answers against brute force and the one-ray queries on whole scenes.
    cargo test --quiet "${cross[@]}" --target "$ARM" -p aperture-budget -p aperture-denoise \
        -p aperture-accel --lib --test packet_blocker
    cargo test --quiet "${cross[@]}" --target "$ARM" -p aperture-tests --test accel_brute_force \
        -- thin_lens_like rays_grazing simple_instancing
    step "render the demo under qemu-aarch64"
    qemu-aarch64 -L /usr/aarch64-linux-gnu "$target_dir/$ARM/debug/aperture" "${args[@]}" \
        -o "$out/aarch64.png"
fi

if want windows; then
    step "build aperture.exe for $WIN (debug)"
    cargo build --quiet "${cross[@]}" -p aperture-cli --target "$WIN"
    exe="$target_dir/$WIN/debug/aperture.exe"
    if x86_64-w64-mingw32-objdump -p "$exe" | grep -iE "DLL Name: (libstdc|libgcc|libwinpthread)"; then
        echo "error: aperture.exe needs the MinGW runtime DLLs above" >&2
        exit 1
    fi
    x86_64-w64-mingw32-gcc -O2 -shared -o "$out/bcryptprimitives.dll" \
        tools/cross/bcryptprimitives.c -ladvapi32
    cp "$exe" "$out/aperture.exe"
    step "render the demo under wine"
    wine "$out/aperture.exe" "${args[@]}" -o "$out/windows.png"
fi

step "the Python wheels: maturin in $zig_venv"
if ! "$zig_venv/bin/python" -c 'import maturin' >/dev/null 2>&1; then
    "$zig_venv/bin/pip" install --quiet --disable-pip-version-check "maturin>=1.9,<2"
fi
wheel() { # TARGET DIR: the debug abi3 wheel for TARGET, unpacked into DIR
    "$zig_venv/bin/maturin" build --quiet -m crates/python/Cargo.toml --target "$1" \
        --out "$2/wheel" "${cross[@]}"
    (cd "$2" && python3 -m zipfile -e wheel/*.whl .)
}
if want aarch64; then
    step "the aarch64 wheel renders the demo in arm64 CPython under qemu-aarch64"
    wheel "$ARM" "$out/arm-wheel"
    apt_dir="${XDG_CACHE_HOME:-$HOME/.cache}/aperture/arm64-apt"
    sysroot="$apt_dir/sysroot"
    if [ ! -x "$sysroot/usr/bin/python3.11" ]; then
        mkdir -p "$apt_dir/state/lists/partial" "$apt_dir/cache/archives/partial"
        touch "$apt_dir/status"
        apt_opts=(-o "Dir::State=$apt_dir/state" -o "Dir::State::status=$apt_dir/status"
            -o "Dir::Cache=$apt_dir/cache" -o APT::Architecture=arm64
            -o APT::Architectures::=arm64 -o Debug::NoLocking=1)
        apt-get "${apt_opts[@]}" update -qq 2>&1 | grep -v "unsandboxed" || true
        apt-get "${apt_opts[@]}" install --download-only -y -qq python3.11 python3-numpy 2>&1 |
            grep -v "unsandboxed" || true
        rm -rf "$sysroot" && mkdir -p "$sysroot"
        for deb in "$apt_dir"/cache/archives/*.deb; do dpkg-deb -x "$deb" "$sysroot"; done
    fi
    # numpy finds BLAS and LAPACK through alternatives links that unpacking does not make.
    libs="$sysroot/usr/lib/aarch64-linux-gnu"
    qemu-aarch64 -L "$sysroot" -E "LD_LIBRARY_PATH=$libs/blas:$libs/lapack" \
        "$sysroot/usr/bin/python3.11" - "$out/arm-wheel" "$out/aarch64-python.png" <<'PY'
import sys
sys.path.insert(0, sys.argv[1])
import aperture
scene = aperture.load("assets/demo.glb")
aperture.write(sys.argv[2], scene.render(width=160, height=90, spp=4))
PY
    done_with "$ARM"
fi
if want windows; then
    step "the Windows wheel"
    wheel "$WIN" "$out/win-wheel"
    pyd="$out/win-wheel/aperture/aperture.pyd"
    dlls=$(x86_64-w64-mingw32-objdump -p "$pyd" | grep "DLL Name")
    if grep -iE "libstdc|libgcc|libwinpthread" <<<"$dlls"; then
        echo "error: aperture.pyd needs the MinGW runtime DLLs above" >&2
        exit 1
    fi
    grep -q "python3.dll" <<<"$dlls" || { echo "error: aperture.pyd is not abi3 (no python3.dll)" >&2; exit 1; }
    done_with "$WIN"
fi

step "compare with x86-64"
sha256sum "$out"/*.png
python3 tools/cross/png_pixels.py "$out"/*.png | tee "$out/pixels.txt"
# One image per platform, and the aarch64 wheel's.
if [ "$(wc -l <"$out/pixels.txt")" != $((1 + $(wc -w <<<"$platforms") + $(want aarch64 && echo 1 || echo 0))) ]; then
    echo "error: an image is missing" >&2
    exit 1
fi
if [ "$(cut -d' ' -f1 "$out/pixels.txt" | sort -u | wc -l)" != 1 ]; then
    echo "error: the platforms' images differ" >&2
    exit 1
fi
step "cross check passed: the images are bit-identical"
