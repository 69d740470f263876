// SPDX-License-Identifier: MIT
#include "uvr/accel/seed_grid.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "uvr/accel/point_locator.h"
#include "uvr/core/error.h"
#include "uvr/mesh/tet_math.h"

namespace uvr {

PartitionGrid layoutPartitionGrid(const Bounds3f& box, double target) {
    PartitionGrid g;
    g.lo = box.lo;
    const Vec3f ext = box.extent();
    const double maxExt = std::max({double(ext.x), double(ext.y), double(ext.z), 0.0});
    // Cell edge h: start from the cube root of volume / target and grow it until the grid holds
    // at most twice the target (flat boxes have no volume, so the loop does the work there).
    const double volume = double(ext.x) * ext.y * ext.z;
    double h = volume > 0.0 ? std::cbrt(volume / target) : maxExt / kMaxGridSide;
    if (!(h > 0.0)) h = 1.0;
    auto side = [&](float e) {
        const double n = std::round(double(e) / h);
        return static_cast<std::uint32_t>(std::clamp(n, 1.0, double(kMaxGridSide)));
    };
    for (int guard = 0; guard < 200; ++guard, h *= 1.25) {
        for (int a = 0; a < 3; ++a) g.dims[a] = side(ext[a]);
        if (double(g.dims[0]) * g.dims[1] * g.dims[2] <= 2.0 * target + 8.0) break;
    }
    for (int a = 0; a < 3; ++a)
        g.cellsPerUnit[a] = ext[a] > 0.f ? static_cast<float>(g.dims[a] / double(ext[a])) : 0.f;
    return g;
}

std::vector<PartitionGrid> layoutPartitionGrids(const KdPartitions& kd, float tetsPerCell,
                                                const char* what, double tetsPerMeshCell) {
    // Sequential: a few operations per partition.
    std::vector<PartitionGrid> grids(kd.partitions.size());
    std::uint64_t total = 0;
    for (std::size_t p = 0; p < grids.size(); ++p) {
        const KdPartition& part = kd.partitions[p];
        PartitionGrid g;
        if (part.cellCount > 0 && !part.box.empty())
            g = layoutPartitionGrid(part.box,
                                    std::max(1.0, part.cellCount * tetsPerMeshCell / tetsPerCell));
        else
            g.dims[0] = g.dims[1] = g.dims[2] = 1;
        g.first = static_cast<std::uint32_t>(total);
        total += std::uint64_t(g.dims[0]) * g.dims[1] * g.dims[2];
        UVR_CHECK(total < 0xffffffffull, what << " exceed 32-bit indices");
        grids[p] = g;
    }
    return grids;
}

SeedGrids buildSeedGrids(const TetMesh& mesh, const KdPartitions& kd, float tetsPerCell,
                         const FractionFn& progress) {
    const auto start = std::chrono::steady_clock::now();
    UVR_CHECK(tetsPerCell > 0.f, "seed grid density must be positive");
    SeedGrids out;
    const std::size_t n = kd.partitions.size();
    out.grids = layoutPartitionGrids(kd, tetsPerCell, "seed grids", mesh.meanSplitTets());
    const TetLocator locator{mesh.view(), {}, {}};
    out.seeds.assign(gridCellCount(out.grids), kNoTet);
    ProgressCounter done(progress, static_cast<std::int64_t>(kd.cells.size()));
    // Partitions are independent, each filled by one thread in cell order with the smallest key
    // offered (offerSeedKeys): the result is deterministic.
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t p = 0; p < static_cast<std::int64_t>(n); ++p) {
        const KdPartition& part = kd.partitions[p];
        const PartitionGrid& g = out.grids[p];
        if (part.cellCount == 0 || part.box.empty()) continue;
        const std::size_t cells = std::size_t(g.dims[0]) * g.dims[1] * g.dims[2];
        std::vector<std::uint64_t> best(cells, ~std::uint64_t(0));
        for (std::uint32_t i = 0; i < part.cellCount; ++i)
            offerSeedKeys(
                locator, g, kd.cells[part.firstCell + i], [&](std::uint64_t c) { return best[c]; },
                [&](std::uint64_t c, std::uint64_t key) { best[c] = std::min(best[c], key); });
        std::uint32_t* seeds = out.seeds.data() + g.first;
        for (std::size_t k = 0; k < cells; ++k)
            seeds[k] = best[k] == ~std::uint64_t(0) ? kNoTet : static_cast<std::uint32_t>(best[k]);
        done.add(part.cellCount);
    }
    done.finish();
    out.buildSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

}  // namespace uvr
