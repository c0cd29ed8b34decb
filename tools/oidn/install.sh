#!/usr/bin/env bash
# Installs Intel Open Image Denoise (the CPU device only) for `aperture render --denoise` from
# the `pyoidn` wheel on PyPI, which ships the prebuilt OIDN 2.5.1 libraries (Apache-2.0):
#   ${XDG_CACHE_HOME:-~/.cache}/aperture/oidn/lib/libOpenImageDenoise.so.2 (+ core, CPU device, TBB)
# That folder is the third place aperture looks (README "Denoising"). Idempotent: a second run
# sees the version stamp and returns at once. Needs `pip` (or APERTURE_OIDN_WHEEL=FILE.whl, a
# wheel already downloaded) and `unzip` or `python3`.
set -euo pipefail
version=2.5.1.0
so=2.5.1
dest="${XDG_CACHE_HOME:-$HOME/.cache}/aperture/oidn"
lib="$dest/lib"
stamp="$dest/pyoidn-$version"

if [[ -f "$stamp" && -f "$lib/libOpenImageDenoise.so.2" ]]; then
    echo "OIDN $so already installed in $lib"
    exit 0
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
wheel="${APERTURE_OIDN_WHEEL:-}"
if [[ -z "$wheel" ]]; then
    echo "downloading pyoidn==$version (about 90 MB) from PyPI"
    python3 -m pip download --quiet --no-deps --only-binary=:all: \
        --platform manylinux2014_x86_64 --dest "$tmp" "pyoidn==$version"
    wheel=$(ls "$tmp"/pyoidn-*.whl)
fi

# Only the CPU device and what it needs (about 56 MB of the wheel's 300 MB unpacked): the GPU
# devices are optional modules OIDN skips when absent.
members=(
    "libOpenImageDenoise.so.$so"
    "libOpenImageDenoise_core.so.$so"
    "libOpenImageDenoise_device_cpu.so.$so"
    "libtbb.so.12"
)
mkdir -p "$tmp/x"
python3 - "$wheel" "$tmp/x" "${members[@]}" <<'PY'
import sys, zipfile, os
wheel, out, names = sys.argv[1], sys.argv[2], sys.argv[3:]
with zipfile.ZipFile(wheel) as z:
    for n in names:
        data = z.read("pyoidn/oidn/lib/" + n)
        with open(os.path.join(out, n), "wb") as f:
            f.write(data)
PY
mkdir -p "$lib"
for m in "${members[@]}"; do
    chmod 755 "$tmp/x/$m"
    mv -f "$tmp/x/$m" "$lib/$m"
done
ln -sf "libOpenImageDenoise.so.$so" "$lib/libOpenImageDenoise.so.2"
rm -f "$dest"/pyoidn-*
touch "$stamp"
echo "OIDN $so installed in $lib"
