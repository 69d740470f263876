#!/bin/sh
# SPDX-License-Identifier: MIT
# Installs every build and test dependency of uvr from Debian 12's packages (run as root); clang
# with libFuzzer (libclang-rt-14-dev) and its OpenMP (libomp-dev) build the fuzz targets; xvfb
# (xvfb-run) gives VTK the X display the oracle test (tests/tools/vtk_oracle_test.py) needs;
# FreeType, fontconfig and the DejaVu fonts draw the colour legend (`--legend`); Boost (Beast,
# headers only) and libturbojpeg serve the browser viewer (`uvr view`); chromium,
# chromium-driver and python3-selenium run the browser test of its page
# (tests/web/view_page_test.py); python3-dev and pybind11-dev build the Python module (python/),
# python3-pytest runs its tests (with meshio and python3-vtk9 for the conversions),
# python3-matplotlib draws the benchmark figures (bench/plot_bench.py) and reads PNGs in the
# Python tests; liblz4-dev and liblzma-dev read and write LZ4/LZMA-compressed .vtu (optional);
# libnetcdf-dev reads Exodus II files, and mayavi2 ships ParaView's disk_out_ref.ex2 the Exodus
# tests read; libhdf5-dev reads and writes VTKHDF files (optional in CMake) and python3-h5py
# writes their test files; clang-format-14 checks the sources' style (tests/tools/check_format.sh).
set -eu
export DEBIAN_FRONTEND=noninteractive
PACKAGES="g++ cmake make ninja-build pkg-config
  zlib1g-dev libpng-dev libexpat1-dev libcli11-dev nlohmann-json3-dev
  liblz4-dev liblzma-dev
  libfreetype-dev libfontconfig-dev fonts-dejavu-core
  libboost-dev libturbojpeg0-dev
  libnetcdf-dev mayavi2
  libgtest-dev libbenchmark-dev
  clang libclang-rt-14-dev libomp-dev clang-format-14
  python3 python3-numpy python3-vtk9 python3-meshio python3-skimage
  python3-dev pybind11-dev python3-pytest python3-matplotlib
  xvfb xauth
  chromium chromium-driver python3-selenium
  libhdf5-dev python3-h5py"
missing=""
for p in $PACKAGES; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  apt-get update -q
  apt-get install -y -q --no-install-recommends $missing
fi
