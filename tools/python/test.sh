#!/usr/bin/env bash
# Issue 60's acceptance: builds the `aperture` wheel (one abi3 wheel, maturin) from this
# checkout, installs it into a cached venv and runs the pytest suite crates/python/tests
# against the command line's binary; then installs the same wheel into Blender 5.0's Python
# (bpy 5.0.1, tools/blender/run_test.sh's venv) and renders the demo from a bpy script.
#
#   tools/python/test.sh [pytest options]
#
# Environment:
#   APERTURE_PY_VENV   the venv (default ${XDG_CACHE_HOME:-$HOME/.cache}/aperture/py-venv)
#   APERTURE_BIN       the aperture binary the tests compare with (default target/debug/aperture,
#                      built here when missing)
#   APERTURE_BPY_VENV  Blender's venv (default ${XDG_CACHE_HOME:-$HOME/.cache}/aperture/bpy-5.0.1;
#                      installed by tools/blender/run_test.sh); APERTURE_SKIP_BLENDER=1 leaves it out
#   PYTHON311          the interpreter to create the venv with (default python3.11, else python3)
#   CI=true            anything missing (Blender's venv, a sample) fails instead of skipping
set -euo pipefail
cd "$(dirname "$0")/../.."
cache="${XDG_CACHE_HOME:-$HOME/.cache}/aperture"
venv="${APERTURE_PY_VENV:-$cache/py-venv}"
python="${PYTHON311:-$(command -v python3.11 || command -v python3)}"
start=$(date +%s)

if ! "$venv/bin/python" -c 'import maturin, numpy, pytest, hypothesis, OpenEXR' >/dev/null 2>&1; then
    echo "== creating $venv (maturin, numpy, pytest, hypothesis, OpenEXR)"
    rm -rf "$venv"
    mkdir -p "$(dirname "$venv")"
    "$python" -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check \
        "maturin>=1.9,<2" "numpy>=1.23" "pytest>=8" "hypothesis>=6" "OpenEXR==3.5.3"
fi

if [ -z "${APERTURE_BIN:-}" ]; then
    echo "== cargo build -p aperture-cli"
    cargo build --quiet -p aperture-cli
fi
export APERTURE_BIN="${APERTURE_BIN:-target/debug/aperture}"
APERTURE_BIN="$(realpath "$APERTURE_BIN")"

echo "== maturin build (crates/python, abi3)"
wheels=$(mktemp -d)
trap 'rm -rf "$wheels"' EXIT
"$venv/bin/maturin" build --quiet -m crates/python/Cargo.toml --out "$wheels" --interpreter "$venv/bin/python"
wheel=$(ls "$wheels"/aperture-*.whl)
echo "built $(basename "$wheel") in $(($(date +%s) - start)) s"
"$venv/bin/pip" install --quiet --disable-pip-version-check --force-reinstall --no-deps "$wheel"

echo "== pytest crates/python/tests"
status=0
"$venv/bin/python" -m pytest -q crates/python/tests "$@" || status=$?

# The same wheel inside Blender 5.0's Python (issue 60's acceptance), installed into a copy of
# nothing: pip puts it in Blender's venv, which tools/blender/run_test.sh creates.
if [ "${APERTURE_SKIP_BLENDER:-0}" != 1 ]; then
    bpy_venv="${APERTURE_BPY_VENV:-$cache/bpy-5.0.1}"
    if "$bpy_venv/bin/python" -c 'import bpy' >/dev/null 2>&1; then
        echo "== the wheel in Blender's Python ($bpy_venv)"
        "$bpy_venv/bin/pip" install --quiet --disable-pip-version-check --force-reinstall --no-deps "$wheel"
        "$bpy_venv/bin/python" tools/python/blender_render.py assets/demo.glb || status=$?
        # Issue 63: the add-on's viewport sync (depsgraph updates -> session edits -> film),
        # headless, through this wheel.
        echo "== tools/blender/test_viewport.py"
        "$bpy_venv/bin/python" tools/blender/test_viewport.py --require-all || status=$?
    elif [ "${CI:-}" = true ]; then
        echo "error: no bpy venv at $bpy_venv (tools/blender/run_test.sh installs it)" >&2
        status=1
    else
        echo "skipped: no bpy venv at $bpy_venv (tools/blender/run_test.sh installs it)"
    fi
fi
echo "python module checks: $(($(date +%s) - start)) s"
exit $status
