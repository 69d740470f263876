#!/bin/sh
# SPDX-License-Identifier: MIT
# Installs uvr's dependencies from Debian 12's packages (run as root). Without arguments, what
# building and running uvr needs: the compiler and CMake, the image, XML, compression and HDF5
# libraries, FreeType, fontconfig and the DejaVu fonts for the colour legend (`--legend`), Boost
# (Beast, headers only) and libturbojpeg for the browser viewer (`uvr view`), netCDF for Exodus II,
# Open MPI (libopenmpi-dev, and openmpi-bin's mpirun) for rendering over several ranks,
# python3-dev, pybind11-dev and numpy for the Python module (python/). With --tests, also what
# the test suite needs (about 1.3 GB more): GoogleTest and Google Benchmark; clang with libFuzzer
# (libclang-rt-14-dev) and its OpenMP (libomp-dev) for the sanitizer build and the fuzz targets;
# clang-format-14 for the style check; xvfb for VTK's oracle tests; chromium, chromium-driver and
# python3-selenium for the viewer page's browser test; pytest, meshio, python3-vtk9, scikit-image
# and matplotlib for the Python tests and benchmark figures; python3-h5py for the VTKHDF test
# files; mayavi2 for ParaView's disk_out_ref.ex2 the Exodus tests read; python3-mpi4py for the
# Python module under mpirun; paraview, paraview-dev and libglew-dev for the ParaView plugin
# (paraview/), whose CMake files and pvbatch also need python3-paraview's files: that package
# conflicts with python3-vtk9 (installing it removes python3-vtk9 and mayavi2), so its .deb is
# fetched from the package archive and unpacked into /opt/uvr/python3-paraview, not installed
# (docs/PARAVIEW.md, "Building").
set -eu
export DEBIAN_FRONTEND=noninteractive
PACKAGES="g++ cmake make ninja-build pkg-config
  zlib1g-dev libpng-dev libexpat1-dev libcli11-dev nlohmann-json3-dev
  liblz4-dev liblzma-dev
  libfreetype-dev libfontconfig-dev fonts-dejavu-core
  libboost-dev libturbojpeg0-dev
  libnetcdf-dev libhdf5-dev
  libopenmpi-dev openmpi-bin
  python3 python3-numpy python3-dev pybind11-dev"
TEST_PACKAGES="libgtest-dev libbenchmark-dev
  clang libclang-rt-14-dev libomp-dev clang-format-14
  python3-vtk9 python3-meshio python3-skimage python3-pytest python3-matplotlib
  xvfb xauth
  chromium chromium-driver python3-selenium
  python3-h5py mayavi2 python3-mpi4py
  paraview paraview-dev libglew-dev"
case "${1:-}" in
  --tests) PACKAGES="$PACKAGES $TEST_PACKAGES" ;;
  "") ;;
  *) echo "usage: scripts/install-deps.sh [--tests]" >&2; exit 2 ;;
esac
missing=""
for p in $PACKAGES; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  apt-get update -q
  apt-get install -y -q --no-install-recommends $missing
fi
# python3-paraview's files, unpacked beside the system's packages (see above).
PVPY=/opt/uvr/python3-paraview
if [ "${1:-}" = "--tests" ] && [ ! -d "$PVPY/usr/lib/python3/dist-packages/paraview/modules" ]; then
  tmp=$(mktemp -d)
  chmod 755 "$tmp"  # apt-get download writes as the _apt user
  trap 'rm -rf "$tmp"' EXIT
  version=$(dpkg-query -W -f='${Version}' paraview)
  (cd "$tmp" && apt-get download -q "python3-paraview=$version")
  rm -rf "$PVPY.partial"
  mkdir -p "$PVPY.partial"
  dpkg-deb -x "$tmp"/python3-paraview_*.deb "$PVPY.partial"
  rm -rf "$PVPY"
  mv "$PVPY.partial" "$PVPY"
fi
