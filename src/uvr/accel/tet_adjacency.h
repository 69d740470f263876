// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "uvr/mesh/tet_mesh.h"

namespace uvr {

/// Marks "no cell" (a boundary face, or a point outside the mesh): kNoCell.
inline constexpr std::uint32_t kNoTet = kNoCell;

/// For every point, the smallest index of a point at exactly the same position (its own index
/// when no earlier point coincides); the same for any thread count. `progress` hears the
/// fraction done.
std::vector<std::uint32_t> coincidentPointIds(std::span<const Vec3f> points,
                                              const FractionFn& progress = {});

/// Face neighbours: result[faceBase(c) + i] is the cell sharing face i (packedFace's numbering;
/// for a tetrahedron t, 4 t + i, the face opposite vertex i) of cell c, or kNoTet on the
/// boundary (or where more than two cells share a face). A quadrilateral matches only a
/// quadrilateral with the same corners, a triangle only a triangle: a hexahedron's quad face and
/// a pyramid's base, a wedge's and a tetrahedron's triangles.
/// Faces match on positions, not only on indices: coincident points count as one.
/// Faces are bucketed by their smallest vertex (a parallel counting sort); the same table for any
/// thread count. `progress` hears the fraction done.
std::vector<std::uint32_t> buildTetNeighbors(const TetMesh& mesh, const FractionFn& progress = {});

/// A tetrahedron's four face neighbours in the kernels' layout (issue 16): code c < kTetBlockSize
/// is tetrahedron c of its own block, kNoNeighborCode none, any other an entry of its block's
/// escape list (c - kTetBlockSize; at most 4 * kTetBlockSize of them, so 16 bits suffice).
struct NeighborCodes {
    std::uint16_t c[4];
};

/// NeighborCodes' "no neighbour" (a boundary face).
inline constexpr std::uint16_t kNoNeighborCode = 0xffffu;

/// Plain-data view of the face neighbours for kernels: 8 bytes per tetrahedron plus the
/// neighbours outside its block, and native cells' neighbours as full ids.
struct NeighborView {
    const NeighborCodes* tetCodes = nullptr;    ///< per tetrahedron
    const std::uint32_t* escapes = nullptr;     ///< neighbours outside the block, block by block
    const std::uint32_t* escapeBase = nullptr;  ///< per block, its first escape
    /// Per face of the native cells (TetMeshView::faceBase(c) - 4 tetCount + face).
    const std::uint32_t* native = nullptr;

    /// True when there are neighbours to walk across.
    UVR_HOST_DEVICE bool present() const { return tetCodes != nullptr || native != nullptr; }
    /// The cell across face `face` of tetrahedron t, or kNoTet.
    UVR_HOST_DEVICE std::uint32_t ofTet(std::uint32_t t, int face) const {
        const std::uint32_t code = tetCodes[t].c[face];
        if (code < kTetBlockSize) return (t & ~(kTetBlockSize - 1u)) | code;
        if (code == kNoNeighborCode) return kNoTet;
        return escapes[escapeBase[t >> kTetBlockBits] + (code - kTetBlockSize)];
    }
    /// The cell across face `face` of cell c (faces numbered as buildTetNeighbors does), or
    /// kNoTet; kNative false: c is a tetrahedron.
    template <bool kNative = true>
    UVR_HOST_DEVICE std::uint32_t across(const TetMeshView& mesh, std::uint32_t c, int face) const {
        if (kNative && c >= mesh.tetCount)
            return native[mesh.faceBase(c) - 4 * mesh.tetCount + std::uint64_t(face)];
        return ofTet(c, face);
    }
};

/// The face neighbours in the kernels' layout (compactNeighbors), owning its arrays.
struct CompactNeighbors {
    std::vector<NeighborCodes> tetCodes;
    std::vector<std::uint32_t> escapes;
    std::vector<std::uint32_t> escapeBase;  ///< per block and one past the last
    std::vector<std::uint32_t> native;

    /// View for kernels; this object must outlive it.
    NeighborView view() const {
        return {tetCodes.empty() ? nullptr : tetCodes.data(), escapes.data(),
                escapeBase.empty() ? nullptr : escapeBase.data(),
                native.empty() ? nullptr : native.data()};
    }
    /// Bytes of the arrays.
    std::uint64_t bytes() const {
        return tetCodes.size() * sizeof(NeighborCodes) +
               (escapes.size() + escapeBase.size() + native.size()) * sizeof(std::uint32_t);
    }
};

/// Encodes a face-neighbour table (buildTetNeighbors of the same mesh) in the kernels' layout:
/// a tetrahedron's neighbours in its own block as 16-bit codes, the others (other blocks, native
/// cells) through its block's escape list. Parallel; the same for any thread count. `progress`
/// hears the fraction done.
CompactNeighbors compactNeighbors(const TetMesh& mesh, const std::vector<std::uint32_t>& neighbors,
                                  const FractionFn& progress = {});

}  // namespace uvr
