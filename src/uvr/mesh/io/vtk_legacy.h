// SPDX-License-Identifier: MIT
#pragma once

#include <functional>
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

namespace uvr {

/// The file version writeVtkLegacy writes.
enum class VtkLegacyVersion {
    Auto,  ///< 4.2 (read by every VTK and ParaView) unless its int32 cell arrays cannot hold the
           ///< mesh, then 5.1
    V42,   ///< CELLS as int32 records "k id...", refused when they overflow int32
    V51,   ///< CELLS as int64 OFFSETS and CONNECTIVITY (VTK 9 and ParaView 5.9 or later)
};

/// Writes a legacy VTK UNSTRUCTURED_GRID file (BINARY, big-endian): float points, the cells,
/// and every field as float (the first one-component field of each association as SCALARS,
/// ParaView's default colouring, the others as FIELD arrays; names percent-encoded as VTK does),
/// atomically, reporting the fraction of bytes written to progress; VTK and ParaView read it.
void writeVtkLegacy(const Mesh& mesh, const std::string& path,
                    const std::function<void(double)>& progress = {},
                    VtkLegacyVersion version = VtkLegacyVersion::Auto);

}  // namespace uvr
