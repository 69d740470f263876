// SPDX-License-Identifier: MIT
#pragma once

#include <string>

#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// Reads a legacy VTK UNSTRUCTURED_GRID file (versions 1.0 to 5.1, ASCII or big-endian BINARY):
/// POINTS, CELLS (classic and 5.1 OFFSETS/CONNECTIVITY), CELL_TYPES, POINT_DATA / CELL_DATA with
/// SCALARS, VECTORS, NORMALS, FIELD arrays (other attributes are skipped). Throws Error naming
/// the file and line (ASCII) or byte offset (BINARY) on malformed input.
Mesh readVtkLegacy(const std::string& path, const ReadOptions& options = {});

}  // namespace uvr
