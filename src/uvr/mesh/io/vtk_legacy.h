// SPDX-License-Identifier: MIT
#pragma once

#include <string>

#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// Reads a legacy VTK UNSTRUCTURED_GRID file (versions 1.0 to 5.1, ASCII or big-endian BINARY):
/// POINTS, CELLS (classic and 5.1 OFFSETS/CONNECTIVITY), CELL_TYPES, POINT_DATA / CELL_DATA with
/// SCALARS, VECTORS, NORMALS, TENSORS, TEXTURE_COORDINATES, COLOR_SCALARS (kept as 0..255) and
/// FIELD arrays as float32 fields (lookup tables, dataset FIELD data and METADATA are skipped).
/// Throws Error naming the file and line (ASCII) or byte offset (BINARY) on malformed input;
/// counts the rest of the file cannot hold are refused before allocating (Resource when larger
/// than the whole file, Parse when the file is cut short).
Mesh readVtkLegacy(const std::string& path, const ReadOptions& options = {});

}  // namespace uvr
