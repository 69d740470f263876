#!/bin/bash
# SPDX-License-Identifier: MIT
# Whole-process CPU seconds of the default method of two uvr binaries (alternated, two rounds:
# "before" and "after" in the same run) and of the reference and exact methods of the second, on
# every shared mesh at its defaults (1024x1024). Prints one line per run: mesh, what, wall s,
# user s, sys s. Run on a quiet machine (docs/PERFORMANCE.md says where the figures went).
#
# Usage: bench/cpu_methods.sh BEFORE_UVR AFTER_UVR [SHARED_DATA] [EXTRA_MESH...]
# e.g.   bench/cpu_methods.sh /tmp/uvr-6573732 build/release/uvr ../shared/data \
#            /usr/lib/python3/dist-packages/mayavi/tests/data/disk_out_ref.ex2
set -eu
before=$1 after=$2 data=${3:-../shared/data}
shift $(( $# < 3 ? $# : 3 ))
meshes=("$data"/bluntfin_tets.vtk "$data"/cylinder_quadratic_as_tets.vtk "$data"/fire_ug.vtu
        "$data"/hexa.vtk "$data"/post.vtk "$data"/post_tets.vtk "$data"/spx.vtk
        "$data"/tetraMesh.vtk "$@")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
run() {  # label binary mesh flags...
    local label=$1 bin=$2 mesh=$3
    shift 3
    /usr/bin/time -o "$tmp/t" -f "%e %U %S" "$bin" -q render "$mesh" --no-cache -o "$tmp/x.png" \
        "$@" >/dev/null 2>"$tmp/err" || { echo "$(basename "$mesh") $label failed:" >&2; cat "$tmp/err" >&2; }
    echo "$(basename "$mesh") $label $(tail -1 "$tmp/t")"
}
for mesh in "${meshes[@]}"; do
    for round in 1 2; do
        run default-before "$before" "$mesh"
        run default-after "$after" "$mesh"
    done
    run reference-after "$after" "$mesh" --method reference
    run exact-after "$after" "$mesh" --method exact
done
