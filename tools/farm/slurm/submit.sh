#!/bin/bash
# Submits a split aperture render to Slurm: a job array of N parts, then a merge that runs
# only if every part succeeded (afterok), and is cancelled if one failed.
#
#   tools/farm/slurm/submit.sh tiles   4 scene.glb frame.exr --width 3840 --spp 4096
#   tools/farm/slurm/submit.sh batches 8 scene.glb frame.exr --width 3840 --spp 512
#
# tiles: N bands of rows (--tile K/N), each at --spp; batches: N sample batches of --spp
# each (--sample-offset K·spp), N·spp samples in all. The other options are passed to every
# `aperture render` as they are. Parts go to OUTPUT's name + .parts/ (PARTS_DIR to change),
# logs to the current folder. Prints the array's and the merge's job ids.
#
# Environment: APERTURE (the aperture binary, default aperture on PATH; it must be reachable
# from the compute nodes, as must the scene and the parts folder), SBATCH_PARTITION and
# the other SBATCH_* variables sbatch reads.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)

if [ $# -lt 4 ]; then
    sed -n '2,16p' "$0" >&2
    exit 2
fi
mode=$1 n=$2 scene=$3 output=$4
shift 4
case $mode in tiles | batches) ;; *)
    echo "submit.sh: unknown split '$mode': tiles or batches" >&2
    exit 2
    ;;
esac
# --spp from the render options (default 64, as aperture render's).
spp=64
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do
    case ${args[i]} in
    --spp) spp=${args[i + 1]} ;;
    --spp=*) spp=${args[i]#--spp=} ;;
    esac
done
filtered=()
skip=0
for a in "$@"; do
    if [ $skip = 1 ]; then skip=0; continue; fi
    case $a in --spp) skip=1; continue ;; --spp=*) continue ;; esac
    filtered+=("$a")
done
scene=$(realpath "$scene")
output=$(realpath -m "$output")
parts=${PARTS_DIR:-$output.parts}
mkdir -p "$parts"
parts=$(realpath "$parts")

array=$(sbatch --parsable --array="0-$((n - 1))" \
    "$here/aperture-part.sbatch" "$mode" "$scene" "$parts" "$spp" "${filtered[@]}")
array=${array%%;*}
merge=$(sbatch --parsable --dependency="afterok:$array" --kill-on-invalid-dep=yes \
    "$here/aperture-merge.sbatch" "$parts" "$n" "$output")
merge=${merge%%;*}
echo "array $array"
echo "merge $merge"
