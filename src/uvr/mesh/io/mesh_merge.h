// SPDX-License-Identifier: MIT
// Merging the pieces of one mesh (a .pvtu's pieces, a VTKHDF file's partitions, a time step's
// parts) into one Mesh.
#pragma once

#include <string>

#include "uvr/mesh/mesh.h"

namespace uvr {

/// Appends `piece` to `mesh`: points appended, corner indices offset by the points before it,
/// notes prefixed with the piece's label, fields concatenated by name and association. With
/// `first` (mesh empty), the piece's fields become the mesh's; every later piece must hold the
/// same fields with the same components, else Error(Parse) naming file, where (a line or byte)
/// and label. Error(Unsupported) beyond 2^32 - 1 points in all. `piece` is left moved-from.
void appendMeshPiece(Mesh& mesh, Mesh& piece, bool first, const std::string& file,
                     const std::string& where, const std::string& label);

}  // namespace uvr
