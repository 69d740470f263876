// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <vector>

#include "uvr/mesh/tet_mesh.h"

namespace uvr {

/// Marks "no tetrahedron" (a boundary face, or a point outside the mesh).
inline constexpr std::uint32_t kNoTet = 0xffffffffu;

/// Face neighbours: result[4 * t + i] is the tetrahedron sharing the face opposite vertex i of
/// tetrahedron t, or kNoTet on the boundary (or where more than two tetrahedra share a face).
/// Faces are bucketed by their smallest vertex (a parallel counting sort); the same table for any
/// thread count.
std::vector<std::uint32_t> buildTetNeighbors(const TetMesh& mesh);

}  // namespace uvr
