#!/bin/sh
# SPDX-License-Identifier: MIT
# The paper's evaluation (Morrical et al. 2019, Figs. 4-6) on the real meshes: for Blunt Fin and
# the Oxygen Post, a semi-transparent and a "binary" transfer function, run `uvr bench` at
# 1024x1024 and keep its table (CSV, JSON) and images under OUT (default: eval/); the figures (time
# and SSIM against s2, the sample heat maps side by side) are drawn by bench/plot_bench.py with
# matplotlib (python3-matplotlib).
# Usage: bench/paper_eval.sh [BUILD_DIR] [OUT] [DATA_DIR]
set -eu
build=${1:-build/release}
out=${2:-eval}
data=${3:-../shared/data}
mkdir -p "$out"
# Debian's Python has matplotlib (another python3 earlier on PATH may not).
python=python3
[ -x /usr/bin/python3 ] && python=/usr/bin/python3
# semi-transparent: opacity rising linearly to 0.1 per unit distance (see-through);
# binary: transparent below a threshold, 0.5 above it (the middle of Blunt Fin's density range;
# the top 15% of the Oxygen Post's, whose high speeds fill most of its volume).
semi="0:0,1:0.1"
for mesh in bluntfin_tets post_tets; do
  case $mesh in
    bluntfin_tets) binary="step:0.5:0.5" ;;
    *) binary="step:0.85:0.5" ;;
  esac
  for tf in semi binary; do
    eval spec=\$$tf
    name="$mesh-$tf"
    mkdir -p "$out/$name"
    echo "== $name (opacity $spec)"
    "$build/uvr" -q bench "$data/$mesh.vtk" --size 1024x1024 --opacity "$spec" \
      --azimuth -30 --elevation 25 --background 1,1,1 --repeat 5 --sweep 2,4,8,16,32,64 \
      --csv "$out/$name.csv" --json "$out/$name.json" \
      --images "$out/$name" | tee "$out/$name.txt"
    "$python" "$(dirname "$0")/plot_bench.py" "$out/$name.json" --out "$out/$name.png" \
      --heatmaps "$out/$name-heatmaps.png"
  done
done
