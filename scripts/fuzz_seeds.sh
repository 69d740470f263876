#!/bin/sh
# SPDX-License-Identifier: MIT
# Builds the fuzzing seed corpora in OUTDIR/<target>/ from the real meshes in ../shared/data (the
# small ones), meshes written by uvr itself (generate/convert), VTK's own writers (every VTU
# encoding, legacy 4.2/5.1 ASCII/BINARY, when python3-vtk9 is installed) and the hand-made seeds
# in fuzz/seeds/ and tests/data/vtk/, and the hostile inputs of tests/tools/write_hostile_seeds.py (deep nesting, zlib
# header bombs, reused blocks and pieces, many fields, extreme values for the render target). Real data is copied into OUTDIR (a build folder), never into the repository.
# Usage: scripts/fuzz_seeds.sh OUTDIR UVR_BINARY [SHARED_DATA_DIR]
set -eu
out=$1
uvr=$2
root=$(cd "$(dirname "$0")/.." && pwd)
data=${3:-$root/../shared/data}
# The fuzz build's CLI is instrumented; its leak checker is not what this script is about.
export ASAN_OPTIONS=detect_leaks=0
for t in vtk_legacy vtu pvtu pvd native colormap_json pvcc specs render view_message vtkhdf exodus; do mkdir -p "$out/$t"; done
for t in colormap_json pvcc specs pvtu pvd render view_message vtkhdf exodus; do cp "$root/fuzz/seeds/$t/"* "$out/$t/"; done
# Hand-made files with signed counts, exponent forms and nan, and small polyhedra (tests/data/vtk/).
cp "$root/tests/data/vtk/"*.vtu "$out/vtu/"
cp "$root/tests/data/vtk/"*.vtk "$out/vtk_legacy/"

# Real meshes (the large Blunt Fin and Oxygen Post files are left out: too slow per execution).
if [ -d "$data" ]; then
  for f in tetraMesh.vtk post.vtk cylinder_quadratic_as_tets.vtk spx.vtk hexa.vtk; do
    [ -f "$data/$f" ] && cp "$data/$f" "$out/vtk_legacy/real_$f"
  done
  [ -f "$data/fire_ug.vtu" ] && cp "$data/fire_ug.vtu" "$out/vtu/real_fire_ug.vtu"
  for f in tetraMesh.vtk post.vtk cylinder_quadratic_as_tets.vtk; do
    [ -f "$data/$f" ] || continue
    "$uvr" -q convert "$data/$f" "$out/native/real_${f%.vtk}.uvrm"
    "$uvr" -q convert "$data/$f" "$out/vtu/uvr_${f%.vtk}.vtu"
  done
  # uvr's LZ4 and LZMA blocks and its legacy writer (4.2 binary).
  for c in lz4 lzma; do
    "$uvr" -q convert "$data/tetraMesh.vtk" "$out/vtu/uvr_tetraMesh_$c.vtu" --compress $c
  done
  [ -f "$data/fire_ug.vtu" ] && "$uvr" -q convert "$data/fire_ug.vtu" "$out/vtk_legacy/uvr_fire_ug.vtk"
else
  echo "fuzz_seeds.sh: $data not found: no real meshes in the seeds" >&2
fi

# Small procedural meshes written by uvr (native and its own VTU flavour).
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for shape in box shell graded; do
  "$uvr" -q generate "$shape" --cells 60 --fields linear,constant -o "$out/native/gen_$shape.uvrm"
  "$uvr" -q generate "$shape" --cells 60 --fields linear -o "$out/vtu/gen_$shape.vtu"
done

# VTK's own writers: every VTU encoding and the legacy versions, on small mixed-cell grids.
if /usr/bin/python3 -c 'import vtk, meshio' 2>/dev/null; then
  /usr/bin/python3 "$root/tests/tools/write_vtu_variants.py" "$tmp/vtu" >/dev/null
  for f in "$tmp"/vtu/*.vtu; do cp "$f" "$out/vtu/"; done
  # The parallel file, pointed at the piece the pvtu target writes beside its input.
  sed 's/Source="[^"]*"/Source="piece0.vtu"/g' "$tmp/vtu/three.pvtu" > "$out/pvtu/vtk_three.pvtu"
  # Polyhedra (VTK type 42) with hexahedra, wedges, pyramids and a tetrahedron.
  /usr/bin/python3 "$root/tests/tools/write_polyhedra.py" "$tmp/poly" >/dev/null
  for f in "$tmp"/poly/mixed_*.vtu; do cp "$f" "$out/vtu/poly_${f##*/}"; done
  for f in "$tmp"/poly/mixed_*.vtk; do cp "$f" "$out/vtk_legacy/poly_${f##*/}"; done
  for v in 42 51; do
    for mode in ascii binary; do
      /usr/bin/python3 "$root/tests/tools/write_legacy_vtk.py" "$tmp/l.vtk" $v $mode >/dev/null
      cp "$tmp/l.vtk" "$out/vtk_legacy/vtk_${v}_$mode.vtk"
    done
  done
else
  echo "fuzz_seeds.sh: python3-vtk9/python3-meshio missing: no VTK-written seeds" >&2
fi
# Hostile inputs: nesting, amplification, extreme values (plain Python, no VTK needed).
/usr/bin/python3 "$root/tests/tools/write_hostile_seeds.py" "$out"
echo "fuzz_seeds.sh: seeds in $out: $(find "$out" -type f | wc -l) files"
