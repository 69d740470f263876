// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "uvr/mesh/mesh.h"

namespace uvr {

/// Most refinement levels refineMesh accepts (each multiplies the tetrahedra by 8).
inline constexpr int kMaxRefineLevels = 8;

/// Tetrahedra (and points) refineMesh produces at most: neighbour tables and k-d partitions
/// index 4 * tetrahedra with 32-bit ids.
inline constexpr std::uint64_t kMaxRefinedTets = 1ull << 30;

/// Tetrahedra of the output of refineMesh for a mesh of `tets` tetrahedra (after splitting).
inline std::uint64_t refinedTetCount(std::uint64_t tets, int levels) {
    return levels >= 0 && levels <= kMaxRefineLevels ? tets << (3 * levels) : 0;
}

/// Parent tetrahedra per piece of refineToNative (their children take 128 MiB of indices).
inline constexpr std::uint64_t kRefinePieceTets = 1ull << 20;

/// Host bytes refineMesh (or, with toNative, refineToNative) needs at its peak for `mesh` split
/// into `tets` tetrahedra, refined `levels` times: the input and the source-cell table, and for
/// refineMesh the output mesh (41 bytes per tetrahedron with the work copy still held, its cell
/// fields, about a quarter point per tetrahedron with the point fields), for refineToNative the
/// last level's input with its edge table and the pieces written; an upper estimate for
/// --max-memory.
std::uint64_t refineMemoryBytes(const Mesh& mesh, std::uint64_t tets, int levels,
                                bool toNative = false);

/// Uniform red refinement (Bey 1995, "Tetrahedral grid refinement"): every cell is first split
/// into positively oriented tetrahedra (splitCell: the conforming split of `uvr render`,
/// zero-volume tetrahedra dropped), then `levels` times every tetrahedron is split into 8 at its
/// edge midpoints (4 corner tetrahedra and the inner octahedron cut along its shortest diagonal).
/// Midpoints shared by neighbouring tetrahedra are made once, so the result is conforming. Point
/// fields are interpolated linearly at midpoints (every component), cell fields are copied to the
/// children. Parallel and deterministic: the same input gives the same output bit for bit
/// whatever the thread count. Points keep their indices; new points follow. progress(message) is
/// called at each step when given, fraction(done) after each step with the share of the work
/// done (each step weighted by the tetrahedra it makes). Throws Error(Argument) for levels outside
/// [0, kMaxRefineLevels] and Error(Resource) when the result would exceed kMaxRefinedTets
/// tetrahedra or 32-bit point indices.
Mesh refineMesh(const Mesh& mesh, int levels,
                const std::function<void(const std::string&)>& progress = {},
                const std::function<void(double)>& fraction = {});

/// refineMesh(mesh, levels) written to a native .uvrm file, byte for byte what writeNative of
/// refineMesh's result writes, without ever holding the output: the levels but the last are
/// refined in memory; of the last, the points are written (the old ones, then the edge
/// midpoints in edge order), then the 8 children of each tetrahedron piece by piece, then the
/// fields, in pieces of about pieceTets parents. Atomic (temporary file, then rename); progress
/// and errors as refineMesh.
void refineToNative(const Mesh& mesh, int levels, const std::string& path,
                    const std::function<void(const std::string&)>& progress = {},
                    const std::function<void(double)>& fraction = {},
                    std::uint64_t pieceTets = kRefinePieceTets);

}  // namespace uvr
