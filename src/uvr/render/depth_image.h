// SPDX-License-Identifier: MIT
#pragma once

// Depth images (issue 32, "depth in and out"): per pixel a float32 distance along the view
// direction in the file's units, row 0 at the top, as NumPy .npy files (version 1.0, '<f4',
// C order, shape (height, width)), which numpy.load, ParaView's Python and most tools read.
// Infinity (or NaN, read) where there is nothing.

#include <string>
#include <vector>

namespace uvr {

class OutputFile;

/// Writes width x height depths as a .npy into an output the caller commits.
void writeDepthNpy(OutputFile& out, int width, int height, const std::vector<float>& depth);

/// Reads a depth image for a width x height frame: a .npy of little-endian float32 ('<f4'; or
/// '<f8', converted), C order, shape (height, width). Throws Error(Parse) naming the file and
/// what is wrong (not a .npy, another dtype or shape, truncated), Error(Io) when unreadable.
std::vector<float> readDepthNpy(const std::string& path, int width, int height);

}  // namespace uvr
