#!/bin/sh
# Chunk K of N of a frame range: `chunk.sh A..B[:STEP] K N` prints `a..b:STEP`, the frames
# of chunk K (0-based) when the range's frames are cut into N runs of nearly equal length
# (frames ⌊K·F/N⌋ .. ⌊(K+1)·F/N⌋−1 of the F frames), or nothing when the chunk is empty
# (more chunks than frames). POSIX sh, so any job (Slurm, a Kubernetes pod) can use it.
set -eu
range=$1 k=$2 n=$3
case $range in *:*) step=${range##*:} span=${range%:*} ;; *) step=1 span=$range ;; esac
a=${span%%..*} b=${span##*..}
if [ "$step" -lt 1 ] || [ "$b" -lt "$a" ] || [ "$k" -ge "$n" ]; then
    echo "chunk.sh: bad range $range or chunk $k of $n" >&2
    exit 2
fi
f=$(((b - a) / step + 1))
i0=$((k * f / n)) i1=$(((k + 1) * f / n))
[ "$i1" -gt "$i0" ] || exit 0
echo "$((a + i0 * step))..$((a + (i1 - 1) * step)):$step"
