// SPDX-License-Identifier: MIT
#include "uvr/accel/macro_grid.h"

#include <algorithm>
#include <chrono>

#include "uvr/core/error.h"

namespace uvr {

MacroGrids buildMacroGrids(const TetMesh& mesh, const KdPartitions& kd,
                           const std::vector<std::uint32_t>& neighbors, float tetsPerCell,
                           const FractionFn& progress) {
    const auto start = std::chrono::steady_clock::now();
    UVR_CHECK(tetsPerCell > 0.f, "macrocell density must be positive");
    MacroGrids out;
    out.grids = layoutPartitionGrids(kd, tetsPerCell, "macrocell grids", mesh.meanSplitTets());
    fillMacroCells(mesh, kd, neighbors, out, progress);
    out.buildSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

void fillMacroCells(const TetMesh& mesh, const KdPartitions& kd,
                    const std::vector<std::uint32_t>& neighbors, MacroGrids& out,
                    const FractionFn& progress) {
    const TetMeshView view = mesh.view();
    UVR_CHECK(neighbors.size() == view.faceSlots(), "macrocells need the face neighbours");
    UVR_CHECK(out.grids.size() == kd.partitions.size(), "one macrocell grid per partition");
    const std::size_t n = kd.partitions.size();
    out.cells.assign(gridCellCount(out.grids), MacroCell{});
    out.nanCells.clear();
    const bool cellData = mesh.association == Association::Cell;
    const bool anyNan =
        std::any_of(mesh.values.begin(), mesh.values.end(), [](float v) { return v != v; });
    if (anyNan) out.nanCells.assign(out.cells.size(), 0);
    ProgressCounter done(progress, static_cast<std::int64_t>(kd.cells.size()));
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t p = 0; p < static_cast<std::int64_t>(n); ++p) {
        const KdPartition& part = kd.partitions[p];
        const PartitionGrid& g = out.grids[p];
        if (part.cellCount == 0 || part.box.empty()) continue;
        MacroCell* cells = out.cells.data() + g.first;
        const std::size_t count = std::size_t(g.dims[0]) * g.dims[1] * g.dims[2];
        std::vector<Bounds3f> gradients(count);  // bounding boxes of the gradients
        for (std::uint32_t i = 0; i < part.cellCount; ++i) {
            const std::uint32_t t = kd.cells[part.firstCell + i];
            const MacroContribution add = macroContribution(view, t, anyNan);
            const bool gradOk = !add.gradients.empty();
            bool boundary = false;
            const std::uint64_t faces = view.faceBase(t);
            for (int f = 0; f < kindFaces(view.kind(t)); ++f)
                boundary = boundary || neighbors[faces + f] == kNoTet;
            forOverlappedMacroCells(g, add.box, [&](std::uint64_t at) {
                const std::uint64_t c = at - g.first;
                MacroCell& m = cells[c];
                // A tetrahedron whose values are all NaN adds no range; nanCells records it
                // (shadeNan keeps the macrocell while NaN is visible).
                m.valueMin = std::fmin(m.valueMin, add.lo);
                m.valueMax = std::fmax(m.valueMax, add.hi);
                if (add.nan) out.nanCells[at] = 1;
                if (boundary) m.atBoundary = 1;
                if (cellData)
                    m.gradientSpread = INFINITY;
                else if (gradOk)
                    gradients[c].extend(add.gradients);
            });
        }
        if (!cellData)
            for (std::size_t c = 0; c < count; ++c)
                if (!gradients[c].empty())
                    cells[c].gradientSpread = length(gradients[c].hi - gradients[c].lo);
        done.add(part.cellCount);
    }
    done.finish();
}

}  // namespace uvr
