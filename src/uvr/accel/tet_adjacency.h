// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <vector>

#include "uvr/mesh/tet_mesh.h"

namespace uvr {

/// Marks "no tetrahedron" (a boundary face, or a point outside the mesh).
inline constexpr std::uint32_t kNoTet = 0xffffffffu;

/// For every point, the smallest index of a point at exactly the same position (its own index
/// when no earlier point coincides); the same for any thread count.
std::vector<std::uint32_t> coincidentPointIds(const std::vector<Vec3f>& points);

/// Face neighbours: result[4 * t + i] is the tetrahedron sharing the face opposite vertex i of
/// tetrahedron t, or kNoTet on the boundary (or where more than two tetrahedra share a face).
/// Faces match on positions, not only on indices: coincident points count as one.
/// Faces are bucketed by their smallest vertex (a parallel counting sort); the same table for any
/// thread count.
std::vector<std::uint32_t> buildTetNeighbors(const TetMesh& mesh);

}  // namespace uvr
