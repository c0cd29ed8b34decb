#!/bin/bash
# Submits a split aperture render to Slurm: a job array of N parts, then a merge that runs
# only if every part succeeded (afterok), and is cancelled if one failed.
#
#   tools/farm/slurm/submit.sh tiles   4 scene.glb frame.exr --width 3840 --spp 4096
#   tools/farm/slurm/submit.sh batches 8 scene.glb frame.exr --width 3840 --spp 512
#   tools/farm/slurm/submit.sh frames 10 shot.glb 'shot_####.exr' --frames 1..250 --spp 256
#
# tiles: N bands of rows (--tile K/N), each at --spp; batches: N sample batches of --spp
# each (--sample-offset K·spp), N·spp samples in all; frames: the --frames range cut into N
# chunks, each task rendering its chunk as one sequence (loaded once), no merge. The other
# options are passed to every `aperture render` as they are. Parts go to OUTPUT's name +
# .parts/ (PARTS_DIR to change), logs to the current folder. Prints the array's and the
# merge's job ids.
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
case $mode in tiles | batches | frames) ;; *)
    echo "submit.sh: unknown split '$mode': tiles, batches or frames" >&2
    exit 2
    ;;
esac
# --spp (default 64, as aperture render's) or, for frames, --frames from the render
# options: the part script takes it apart.
key=--spp
[ "$mode" = frames ] && key=--frames
value=64
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do
    case ${args[i]} in
    "$key") value=${args[i + 1]} ;;
    "$key"=*) value=${args[i]#"$key"=} ;;
    esac
done
if [ "$mode" = frames ] && [ "$value" = 64 ]; then
    echo "submit.sh: frames needs --frames A..B[:STEP]" >&2
    exit 2
fi
filtered=()
skip=0
for a in "$@"; do
    if [ $skip = 1 ]; then skip=0; continue; fi
    case $a in "$key") skip=1; continue ;; "$key"=*) continue ;; esac
    filtered+=("$a")
done
export APERTURE_FARM_DIR=${APERTURE_FARM_DIR:-$(dirname "$here")}
scene=$(realpath "$scene")
output=$(realpath -m "$output")
if [ "$mode" = frames ]; then
    array=$(sbatch --parsable --array="0-$((n - 1))" \
        "$here/aperture-part.sbatch" frames "$scene" "$output" "$value" "${filtered[@]}")
    echo "array ${array%%;*}"
    exit 0
fi
spp=$value
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
