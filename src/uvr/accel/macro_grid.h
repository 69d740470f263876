// SPDX-License-Identifier: MIT
#pragma once

// Macrocell grids (issue 11, beyond the paper): a coarse uniform grid over each k-d partition
// whose cells record the field's value range and gradient spread over the tetrahedra that
// overlap them. The partition integrator skips transparent macrocells and takes each macrocell's
// own error-bounded step, so a partition of 65,536 tetrahedra is no longer one value range and
// one step (docs/METHOD.md).

#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "uvr/accel/kd_partitions.h"
#include "uvr/accel/seed_grid.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

/// Field statistics of one macrocell over the tetrahedra that overlap it (16 bytes).
struct MacroCell {
    /// Smallest vertex (or cell) value, NaN left out; above valueMax when no tetrahedron with a
    /// value overlaps the macrocell.
    float valueMin = INFINITY;
    float valueMax = -INFINITY;  ///< largest
    /// Diagonal of the bounding box of the tetrahedra's field gradients (see
    /// partitionGradientSpread); infinite for a cell-centred field (its jumps are not bounded).
    float gradientSpread = 0.f;
    /// 1 where a tetrahedron's face lies on the mesh's boundary: the integrand jumps there (to
    /// nothing), so the macrocell steps at most s1, as the reference does (a long step would
    /// miss a ray's short chords through the mesh near its silhouette); its gradient spread may
    /// still ask for less (shadeMacroCell).
    std::uint32_t atBoundary = 0;

    /// True when no tetrahedron with a value overlaps the macrocell (it is transparent).
    UVR_HOST_DEVICE bool empty() const { return !(valueMin <= valueMax); }
};

/// Tetrahedra per macrocell the builder aims for: about 6 default steps s1 across on a uniform
/// mesh. Chosen, not tuned: finer cells skip and adapt more finely but force a sample at every
/// macrocell a ray crosses and cost 16 bytes each.
inline constexpr float kTetsPerMacroCell = 48.f;

/// Macrocell grids of all partitions (the layout of seed grids: one PartitionGrid per partition,
/// its cells from `first` in x-fastest order).
struct MacroGrids {
    std::vector<PartitionGrid> grids;
    std::vector<MacroCell> cells;
    /// Per macrocell: 1 where a tetrahedron with a NaN value overlaps it (its value range leaves
    /// NaN out); empty when the field has no NaN value.
    std::vector<std::uint8_t> nanCells;
    double buildSeconds = 0.0;

    /// Bytes held.
    std::uint64_t bytes() const {
        return grids.size() * sizeof(PartitionGrid) + cells.size() * sizeof(MacroCell) +
               nanCells.size();
    }
};

/// Index of the macrocell of grid g holding p (clamped into the grid; idx receives the cell's
/// coordinates).
UVR_HOST_DEVICE inline std::uint32_t macroCellOf(const PartitionGrid& g, Vec3f p,
                                                 std::uint32_t idx[3]) {
    for (int a = 0; a < 3; ++a) idx[a] = SeedGridView::cellIndex(g, a, p[a]);
    return g.first + (idx[2] * g.dims[1] + idx[1]) * g.dims[0] + idx[0];
}

/// Calls fn(c) for every macrocell c of grid g (its index from g.first, x fastest) that box
/// overlaps (macroCellOf's clamped cells of its corners and all between).
template <class Fn>
UVR_HOST_DEVICE void forOverlappedMacroCells(const PartitionGrid& g, const Bounds3f& box, Fn&& fn) {
    std::uint32_t a[3], b[3];
    macroCellOf(g, box.lo, a);
    macroCellOf(g, box.hi, b);
    for (std::uint32_t z = a[2]; z <= b[2]; ++z)
        for (std::uint32_t y = a[1]; y <= b[1]; ++y)
            for (std::uint32_t x = a[0]; x <= b[0]; ++x)
                fn(g.first + (std::uint64_t(z) * g.dims[1] + y) * g.dims[0] + x);
}

/// What cell t adds to every macrocell its bounding box overlaps (fillMacroCells' rule, shared by
/// the CPU's build and the GPU's).
struct MacroContribution {
    Bounds3f box;                         ///< the cell's bounding box
    float lo = INFINITY, hi = -INFINITY;  ///< its value range, NaN left out
    Bounds3f gradients;                   ///< its field gradients (point data; cellGradientBounds)
    bool nan = false;                     ///< one of its values is NaN (looked for when anyNan)
};

/// Cell t's MacroContribution, read as kernels read cells (TetMeshView::kernelGather).
UVR_HOST_DEVICE inline MacroContribution macroContribution(const TetMeshView& m, std::uint32_t t,
                                                           bool anyNan) {
    MacroContribution out;
    Vec3f x[kMaxCellCorners];
    float v[kMaxCellCorners];
    const int corners = m.kernelGather(t, x, m.cellCentered ? nullptr : v);
    for (int k = 0; k < corners; ++k) out.box.extend(x[k]);
    if (m.cellCentered) {
        out.lo = out.hi = m.values[t];
        out.nan = anyNan && out.lo != out.lo;
        return out;
    }
    for (int k = 0; k < corners; ++k) {
        out.nan = out.nan || (anyNan && v[k] != v[k]);
        out.lo = fminf(out.lo, v[k]);  // NaN values are left out
        out.hi = fmaxf(out.hi, v[k]);
    }
    out.gradients = cellGradientBounds(m, t);
    return out;
}

/// Builds the macrocell grids of every partition of kd over mesh (in parallel over partitions;
/// the result does not depend on the thread count). Each tetrahedron of a partition adds its
/// values and gradient to every macrocell its bounding box overlaps; neighbors (4 per
/// tetrahedron, kNoTet on the boundary) mark the boundary's macrocells.
MacroGrids buildMacroGrids(const TetMesh& mesh, const KdPartitions& kd,
                           const std::vector<std::uint32_t>& neighbors,
                           float tetsPerCell = kTetsPerMacroCell, const FractionFn& progress = {});

/// The value-dependent part of the macrocell grids: recomputes every macrocell (value range,
/// gradient spread) and the NaN flags over the grids' existing layout (out.grids, which only the
/// geometry decides). buildMacroGrids ends with it; new values of the same mesh (a time step)
/// need only this. The capacity of out.cells is reused.
void fillMacroCells(const TetMesh& mesh, const KdPartitions& kd,
                    const std::vector<std::uint32_t>& neighbors, MacroGrids& out,
                    const FractionFn& progress = {});

/// Macrocell grids and the partitions' gradient spreads (partitionGradientSpread) at once.
struct MacroBuild {
    MacroGrids macro;
    std::vector<float> gradientSpread;
};

/// Builds macrocells and gradient spreads elsewhere (buildMacroGridsCuda: on the GPU): the same
/// as buildMacroGrids and partitionGradientSpread (zeros may differ in sign).
using MacroBuilder =
    std::function<MacroBuild(const TetMesh&, const KdPartitions&, const std::vector<std::uint32_t>&,
                             float, const FractionFn&)>;

}  // namespace uvr
