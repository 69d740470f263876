#!/bin/sh
# SPDX-License-Identifier: MIT
# docs/images/paraview_gui.png: ParaView 5.11's GUI under Xvfb with the plugin loaded, the Blunt
# Fin as uvr Volume (exact) and an opaque slice, screenshot of the whole display. Needs the
# release build, xvfb, x11-apps (xwd), x11-xserver-utils (xrefresh) and imagemagick (convert).
#   scripts/figures/paraview_gui.sh [OUT.png]
set -eu
cd "$(dirname "$0")/../.."
out=${1:-docs/images/paraview_gui.png}
export UVR_PLUGIN="$PWD/build/release/lib/paraview-5.11/plugins/UvrVolume/UvrVolume.so"
export UVR_DATA="$PWD/../shared/data"
export PYTHONPATH=/opt/uvr/python3-paraview/usr/lib/python3/dist-packages
tmp=$(mktemp -d)
trap 'kill "$pv" "$xvfb" 2>/dev/null || true; rm -rf "$tmp"' EXIT
Xvfb :77 -screen 0 1400x900x24 >/dev/null 2>&1 &
xvfb=$!
sleep 2
DISPLAY=:77 paraview --script="$PWD/scripts/figures/paraview_gui.py" >"$tmp/log" 2>&1 &
pv=$!
sleep "${UVR_GUI_WAIT:-40}"
# Qt repaints only what it thinks changed; Xvfb then still shows regions of earlier frames.
DISPLAY=:77 xrefresh
sleep 10
DISPLAY=:77 xwd -root -silent > "$tmp/screen.xwd"
convert "$tmp/screen.xwd" "$tmp/screen.png"
mv "$tmp/screen.png" "$out"
grep -E "uvr report|error" "$tmp/log" || true
echo "wrote $out"
