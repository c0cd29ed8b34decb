#!/usr/bin/env bash
# The checkers of the farm templates, in a virtualenv of their own (pinned, from PyPI):
# openjd-cli (`openjd check` and `openjd run`, the Open Job Description tools AWS Deadline
# Cloud's format comes with) and kubernetes-validate (the Kubernetes API's JSON schemas).
#
#   tools/farm/setup-tools.sh     # prints the folder to put on PATH (its bin/)
#
# The folder is APERTURE_FARM_VENV, default ~/.cache/aperture/farm-venv; installing takes
# about 20 s the first time and nothing after.
set -euo pipefail
venv=${APERTURE_FARM_VENV:-$HOME/.cache/aperture/farm-venv}
pins=("openjd-cli==0.8.0" "kubernetes-validate==1.37.0")
stamp=$venv/.aperture-pins
if [ ! -x "$venv/bin/openjd" ] || [ ! -x "$venv/bin/kubernetes-validate" ] ||
    [ "$(cat "$stamp" 2>/dev/null)" != "${pins[*]}" ]; then
    echo "setup-tools: installing ${pins[*]} into $venv" >&2
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check "${pins[@]}"
    echo "${pins[*]}" >"$stamp"
fi
echo "$venv/bin"
