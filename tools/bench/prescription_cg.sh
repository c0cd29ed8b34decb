#!/bin/bash
# Run from the repository root: tools/bench/prescription_cg.sh target/release/aperture
# usage: prescription-cg.sh BIN -> instructions per sample, thin lens and prescription (demo, 160x90, spp 8 - spp 1)
bin=$1
cg() { valgrind --tool=callgrind --callgrind-out-file=/dev/null $bin render assets/demo.glb "${@:2}" \
  -o /tmp/cg-pres.exr --width 160 --height 90 --spp $1 --threads 1 --passes none --quiet 2>&1 \
  | grep -o "Collected : [0-9]*" | grep -o "[0-9]*"; }
for variant in thin prescription; do
  extra=()
  [ $variant = prescription ] && extra=(--lens-prescription assets/lenses/dgauss-50mm.dat --fstop 2)
  a=$(cg 1 "${extra[@]}"); b=$(cg 8 "${extra[@]}")
  echo "$variant: $a $b per-sample $(( (b - a) / 7 / 14400 ))"
done
