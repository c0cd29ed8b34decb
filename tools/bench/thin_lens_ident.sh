#!/bin/bash
# Thin-lens images of two binaries: pixel-data hashes of the EXRs (header excluded).
cd "$(dirname "$0")/../.."
small=(--width 64 --height 36 --spp 8 --quiet --passes none)
for b in "$@"; do
  d=/tmp/ident-$(basename $b); mkdir -p $d
  $b render assets/demo.glb -o $d/demo.exr "${small[@]}"
  for k in 0 1 2; do $b render assets/demo.glb -o $d/tile$k.exr --tile $k/3 "${small[@]}"; done
  $b render assets/demo.glb -o $d/adaptive.exr --noise-threshold 0.05 --min-spp 2 "${small[@]}"
  $b render assets/demo.glb -o $d/round.exr --fstop 2.8 "${small[@]}"
  $b render assets/demo.glb -o $d/vig.exr --aperture-vignetting 0.5 --distortion -0.1 "${small[@]}"
  $b render assets/demo.glb -o $d/depth.exr --width 64 --height 36 --spp 4 --quiet --passes Depth,Position
  echo "== $b"; python3 tools/bench/exr_pixels.py $d/*.exr
done
