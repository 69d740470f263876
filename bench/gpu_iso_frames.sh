#!/bin/bash
# SPDX-License-Identifier: MIT
# The isosurface frames of issue 32 at 100M on a GPU, for two or more uvr binaries alternated in
# one run (the commit before a change against the change): seconds a frame of the adaptive method
# ("auto") and the reference, plain, with a surface outside the field's range (--iso 7: none of
# the surfaces' code runs), with one small surface (0.5), a larger one (0.1), and shaded; then
# each binary's image of three shaded surfaces against the first's. Set
# CUDA_MODULE_LOADING=EAGER (lazy loading lands in the first frame). docs/PERFORMANCE.md,
# "Isosurfaces: ...", holds the figures.
#
# Usage: bench/gpu_iso_frames.sh MESH UVR_BEFORE UVR_AFTER [UVR...]
#   MESH: made when missing, by `UVR_BEFORE generate graded --cells 100000000 -o MESH`.
set -eu
mesh=$1
shift
[ $# -ge 2 ] || { echo "usage: $0 MESH UVR_BEFORE UVR_AFTER [UVR...]" >&2; exit 2; }
[ -f "$mesh" ] || "$1" generate graded --cells 100000000 -o "$mesh" > /dev/null
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# The frames' flags are split into words on purpose.
# shellcheck disable=SC2086
for args in "" "--iso 7" "--iso 0.5" "--iso 0.1" "--iso 0.5 --shade"; do
    for bin in "$@"; do
        "$bin" bench "$mesh" --device cuda --size 1024x1024 --repeat 3 --sweep 16 $args \
            --csv "$tmp/o.csv" > "$tmp/o.txt" 2>&1 || { tail -3 "$tmp/o.txt"; exit 1; }
        echo "$bin [$args]: $(grep -h '^"reference"\|^"auto' "$tmp/o.csv" | cut -d, -f1,3 | tr '\n' ' ')"
    done
done
shaded="--iso 0.5,0.4 --iso 0.3 --shade"
# shellcheck disable=SC2086
for i in $(seq 1 $#); do
    "${!i}" render "$mesh" --device cuda --size 512x512 $shaded -o "$tmp/$i.png" > "$tmp/r.txt" 2>&1 ||
        { tail -3 "$tmp/r.txt"; exit 1; }
    [ "$i" = 1 ] || echo "${!i} against $1 [$shaded]: $("$1" compare "$tmp/1.png" "$tmp/$i.png" 2>&1 | tail -1)"
done
