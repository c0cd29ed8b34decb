#!/usr/bin/env bash
# Renders the demo and the test scenes with one `aperture` binary in the ways issue 58 asks to
# keep bit-identical (every pass, tiles, frame sequences, motion blur, PNG) and prints a hash of
# each image's pixels (not its header). Run it with two binaries and diff the outputs:
#   tools/bench/image_hashes.sh OLD_BIN > old.txt; tools/bench/image_hashes.sh NEW_BIN > new.txt
#   diff old.txt new.txt && echo identical
set -euo pipefail
bin=$(realpath "$1")
root=$(cd "$(dirname "$0")/../.." && pwd)
samples=${APERTURE_SAMPLES:-$root/../shared/gltf-samples}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
small=(--width 64 --height 36 --spp 8 --quiet)
r() { "$bin" render "$@" "${small[@]}"; }
demo=$root/assets/demo.glb
r "$demo" -o "$out/demo_all.exr" --passes all
r "$demo" -o "$out/demo.png"
r "$demo" -o "$out/demo_adaptive.exr" --noise-threshold 0.05 --min-spp 2
for k in 0 1 2; do r "$demo" -o "$out/demo_tile$k.exr" --tile "$k/3" --passes all; done
r "$demo" -o "$out/demo_batch.exr" --sample-offset 8 --passes all
box=$samples/animation/BoxAnimated/BoxAnimated.glb
r "$box" -o "$out/box_####.exr" --frames 1..3 --passes all --env 1,1,1
r "$box" -o "$out/box_blur.exr" --frame 12 --motion-blur --passes all --env 1,1,1
r "$box" -o "$out/box_blur_####.exr" --frames 10..11 --motion-blur --env 1,1,1
for s in correctness/Cubes-PointLight/Cubes.glb correctness/AlphaBlendModeTest/AlphaBlendModeTest.glb \
         correctness/EmissiveStrengthTest/EmissiveStrengthTest.glb benchmark/ToyCar/ToyCar.gltf; do
  name=$(basename "$s" | sed 's/\..*//')
  r "$samples/$s" -o "$out/$name.exr" --passes all --env 0.5,0.5,0.5
done
cd "$out"
cargo run -q --manifest-path "$root/Cargo.toml" -p aperture-tests --example exr_hash -- $(ls | sort)
