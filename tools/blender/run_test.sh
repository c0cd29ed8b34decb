#!/usr/bin/env bash
# Runs the Blender acceptance tests (tools/blender/test_export.py, test_animation.py,
# test_compositor.py, test_engine.py, test_materials.py, test_vector.py and test_motion_blur.py)
# with Blender as a Python
# module: bpy 5.0.1 (or APERTURE_BPY) on Python 3.11, in a cached virtual environment that is
# created and filled on first use. Never part of the Rust build.
#
#   tools/blender/run_test.sh [test_export.py options, e.g. --require-all --out DIR --spp 512]
#
# Environment:
#   APERTURE_BPY       the bpy version (default 5.0.1; 4.2.0 also passes part (a))
#   APERTURE_BPY_VENV  the virtual environment (default ${XDG_CACHE_HOME:-$HOME/.cache}/aperture/bpy-$APERTURE_BPY)
#   PYTHON311          the Python 3.11 interpreter to create it with (default: python3.11, else python3)
#   APERTURE_BIN       the aperture binary (default: target/release/aperture, built here when missing
#                      or older than the sources)
set -euo pipefail
cd "$(dirname "$0")/../.."

bpy_version="${APERTURE_BPY:-5.0.1}"
venv="${APERTURE_BPY_VENV:-${XDG_CACHE_HOME:-$HOME/.cache}/aperture/bpy-$bpy_version}"
python="${PYTHON311:-$(command -v python3.11 || command -v python3)}"
start=$(date +%s)

if ! "$venv/bin/python" -c 'import bpy' >/dev/null 2>&1; then
    version=$("$python" -c 'import sys; print("%d.%d" % sys.version_info[:2])')
    if [ "$version" != "3.11" ]; then
        echo "error: bpy $bpy_version needs Python 3.11; $python is $version (set PYTHON311)" >&2
        exit 1
    fi
    echo "== installing bpy $bpy_version into $venv (about 1 GB)"
    rm -rf "$venv"
    mkdir -p "$(dirname "$venv")"
    "$python" -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check "bpy==$bpy_version"
    echo "== bpy installed in $(($(date +%s) - start)) s"
fi
# OpenEXR's own Python reader, for the compositor test (numpy comes with bpy).
if ! "$venv/bin/python" -c 'import OpenEXR' >/dev/null 2>&1; then
    "$venv/bin/pip" install --quiet --disable-pip-version-check "OpenEXR==3.5.3"
fi

bin="${APERTURE_BIN:-target/release/aperture}"
if [ -z "${APERTURE_BIN:-}" ]; then
    echo "== cargo build --release -p aperture-cli"
    cargo build --release --quiet -p aperture-cli
fi

echo "== tools/blender/test_export.py"
status=0
"$venv/bin/python" tools/blender/test_export.py --aperture "$bin" "$@" || status=$?
# SPEC §7: --frame N is Blender's frame N, and a focus pull follows SPEC §2 (about 20 s).
echo "== tools/blender/test_animation.py"
anim_args=()
for a in "$@"; do [ "$a" = "--require-all" ] && anim_args+=(--require-all); done
"$venv/bin/python" tools/blender/test_animation.py --aperture "$bin" "${anim_args[@]}" || status=$?
# SPEC §6: the EXR passes in Blender's compositor, Cycles' pass names, OpenEXR's reader.
echo "== tools/blender/test_compositor.py"
"$venv/bin/python" tools/blender/test_compositor.py --aperture "$bin" "${anim_args[@]}" || status=$?
# Issue 20: the "aperture" render engine of the add-on (F12 renders with aperture).
echo "== tools/blender/test_engine.py"
"$venv/bin/python" tools/blender/test_engine.py --aperture "$bin" "${anim_args[@]}" || status=$?
# SPEC §5 (issue 14): Blender's glass and Principled spheres, Cycles against aperture (~1 min).
echo "== tools/blender/test_materials.py"
"$venv/bin/python" tools/blender/test_materials.py --aperture "$bin" "${anim_args[@]}" || status=$?
# SPEC §6 (issue 47): the Vector pass's order and signs against Cycles' (a few seconds).
echo "== tools/blender/test_vector.py"
"$venv/bin/python" tools/blender/test_vector.py "$bin" || status=$?
# SPEC §7 (issue 47): a translating and turning cube's motion blur against Cycles' (~30 s).
echo "== tools/blender/test_motion_blur.py"
"$venv/bin/python" tools/blender/test_motion_blur.py "$bin" || status=$?
# Issue 63's viewport test (tools/blender/test_viewport.py) needs the `aperture` wheel in this
# venv: tools/python/test.sh installs it and runs that test.
echo "== blender test: exit $status after $(($(date +%s) - start)) s"
exit $status
