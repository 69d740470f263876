#!/bin/sh
# SPDX-License-Identifier: MIT
# GPU evaluation (issue 4) on a machine with an NVIDIA GPU: the CUDA tests, `uvr bench` on the real
# meshes and on large procedural / refined meshes, with and without seed grids, and an Nsight
# Compute profile of the frame kernels. Logs and tables go to OUT.
# Usage: bench/gpu_eval.sh BUILD_DIR DATA_DIR OUT STAGE...
#   STAGE: tests | real | ncu | box:CELLS | refine:MESH:LEVELS | graded:CELLS | leaves:MESH_FILE
# REPEAT (10) and SWEEP (8,16,32,64) set the timed frames and the s2 / s1 sweep of each bench;
# BUILD (auto) is its --build-device: where the BVHs and k-d partitions are built.
set -u
build=$1
data=$2
out=$3
shift 3
mkdir -p "$out"
uvr="$build/uvr"
here=$(dirname "$0")
python=python3
[ -x /usr/bin/python3 ] && python=/usr/bin/python3
# OPACITY replaces the semi-transparent transfer function of the box, graded and refine stages
# (e.g. OPACITY=step:0.5:0.5 for a binary one; TAG then names their outputs).
semi="0:0,1:0.1"
large=${OPACITY:-$semi}
tag=${TAG:-semi}
view="--size 1024x1024 --azimuth -30 --elevation 25 --background 1,1,1"
# The GPU machine's MemTotal can start small and grow: give loads a fixed budget.
mem="--max-memory 100G"
bench() {  # bench NAME MESH OPACITY [extra flags]
  name=$1 mesh=$2 spec=$3
  shift 3
  echo "== $name (opacity $spec) $*"
  "$uvr" -q bench "$mesh" $view $mem --device cuda --build-device "${BUILD:-auto}" \
    --opacity "$spec" --repeat "${REPEAT:-10}" --sweep "${SWEEP:-8,16,32,64}" \
    --json "$out/$name.json" "$@" 2>&1 | tee "$out/$name.txt"
  # The figure (time and SSIM against s2) where matplotlib is installed (bench/plot_bench.py).
  if "$python" -c "import matplotlib" 2>/dev/null; then
    "$python" "$here/plot_bench.py" "$out/$name.json" --out "$out/$name.png"
  else
    echo "(no matplotlib for $python: $name.png not drawn; run bench/plot_bench.py elsewhere)"
  fi
}
for stage in "$@"; do
  case $stage in
    tests)
      "$build/uvr_tests" --gtest_filter='Cuda*:SeedGrid*:PartitionIntegrator*:Lbvh*' 2>&1 |
        tee "$out/tests.txt" | tail -n 25
      ;;
    real)
      bench bluntfin-semi "$data/bluntfin_tets.vtk" "$semi"
      bench bluntfin-binary "$data/bluntfin_tets.vtk" step:0.5:0.5
      bench post-semi "$data/post_tets.vtk" "$semi"
      bench post-binary "$data/post_tets.vtk" step:0.85:0.5
      bench post-semi-noseed "$data/post_tets.vtk" "$semi" --no-seed-grid
      ;;
    ncu)
      ncu --section SpeedOfLight --section MemoryWorkloadAnalysis --section Occupancy \
        --section WarpStateStats --section LaunchStats -k regex:frameKernel -c 2 \
        "$uvr" -q render "$data/post_tets.vtk" -o /tmp/ncu.png $view --device cuda \
        --method adaptive --opacity "$semi" >"$out/ncu-adaptive.txt" 2>&1
      ncu --section SpeedOfLight --section MemoryWorkloadAnalysis --section WarpStateStats \
        -k regex:frameKernel -c 1 "$uvr" -q render "$data/post_tets.vtk" -o /tmp/ncu.png \
        $view --device cuda --opacity "$semi" >"$out/ncu-reference.txt" 2>&1
      grep -E "frameKernel|Duration|Memory Throughput|Compute \(SM\)|Achieved Occupancy|L2 Hit|L1/TEX Hit|Registers Per|Stall|Warp Cycles Per Issued" \
        "$out/ncu-adaptive.txt" "$out/ncu-reference.txt" | head -n 60
      ;;
    box:* | graded:*)
      shape=${stage%%:*} cells=${stage#*:}
      mesh=/tmp/$shape$cells.uvrm
      [ -f "$mesh" ] || /usr/bin/time -f "generate: %e s, %M KB peak" "$uvr" -q generate "$shape" \
        --cells "$cells" -o "$mesh" $mem
      bench "$shape$cells-$tag" "$mesh" "$large"
      ;;
    refine:*)
      rest=${stage#refine:} name=${rest%%:*} levels=${rest#*:}
      mesh=/tmp/$name-x$levels.uvrm
      [ -f "$mesh" ] || /usr/bin/time -f "refine: %e s, %M KB peak" "$uvr" -q refine \
        "$data/$name.vtk" "$mesh" --levels "$levels" $mem
      bench "$name-x$levels-$tag" "$mesh" "$large"
      ;;
    leaves:*)  # the k-d leaf size on the GPU, s2 = 16 and 64 s1
      mesh=${stage#leaves:}
      for n in 1024 4096 16384 65536; do
        echo "== $(basename "$mesh") --leaf-cells $n"
        "$uvr" -q bench "$mesh" $view $mem --device cuda --opacity "$semi" --repeat 10 \
          --sweep 16,64 --leaf-cells "$n" 2>&1 | grep -E "tetrahedra|reference|skipping only|both"
      done
      ;;
    *) echo "unknown stage $stage" >&2 ;;
  esac
done
