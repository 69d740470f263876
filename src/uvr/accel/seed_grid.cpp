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

SeedGrids buildSeedGrids(const TetMesh& mesh, const KdPartitions& kd, float tetsPerCell) {
    const auto start = std::chrono::steady_clock::now();
    UVR_CHECK(tetsPerCell > 0.f, "seed grid density must be positive");
    SeedGrids out;
    const std::size_t n = kd.partitions.size();
    out.grids = layoutPartitionGrids(kd, tetsPerCell, "seed grids", mesh.meanSplitTets());
    const TetMeshView view = mesh.view();
    const TetLocator locator{view, {}, {}};
    out.seeds.assign(gridCellCount(out.grids), kNoTet);
    // Seeds: per cell the smallest key (squared distance of a tetrahedron's centroid to the cell
    // centre, 0 when the tetrahedron contains the centre; ties to the smaller id). Partitions are
    // independent, each filled by one thread in cell order: the result is deterministic.
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t p = 0; p < static_cast<std::int64_t>(n); ++p) {
        const KdPartition& part = kd.partitions[p];
        const PartitionGrid& g = out.grids[p];
        if (part.cellCount == 0 || part.box.empty()) continue;
        const std::size_t cells = std::size_t(g.dims[0]) * g.dims[1] * g.dims[2];
        std::vector<std::uint64_t> best(cells, ~std::uint64_t(0));
        Vec3f cellSize;
        for (int a = 0; a < 3; ++a)
            cellSize[a] = g.cellsPerUnit[a] > 0.f ? 1.f / g.cellsPerUnit[a] : 0.f;
        for (std::uint32_t i = 0; i < part.cellCount; ++i) {
            const std::uint32_t t = kd.cells[part.firstCell + i];
            std::uint32_t ids[kMaxCellCorners];
            const int corners = view.corners(t, ids);
            Bounds3f box;
            Vec3f centroid(0.f);
            for (int k = 0; k < corners; ++k) {
                box.extend(mesh.points[ids[k]]);
                centroid += mesh.points[ids[k]];
            }
            centroid = centroid * (1.f / float(corners));
            std::uint32_t lo[3], hi[3];
            for (int k = 0; k < 3; ++k) {
                lo[k] = SeedGridView::cellIndex(g, k, box.lo[k]);
                hi[k] = SeedGridView::cellIndex(g, k, box.hi[k]);
            }
            for (std::uint32_t z = lo[2]; z <= hi[2]; ++z)
                for (std::uint32_t y = lo[1]; y <= hi[1]; ++y)
                    for (std::uint32_t x = lo[0]; x <= hi[0]; ++x) {
                        std::uint64_t& slot =
                            best[(std::size_t(z) * g.dims[1] + y) * g.dims[0] + x];
                        // Every key of t is at least t: a cell whose best key is no larger
                        // (a containing cell of smaller id) keeps it, so t is not tested there.
                        if (slot <= t) continue;
                        const Vec3f centre(g.lo.x + (x + 0.5f) * cellSize.x,
                                           g.lo.y + (y + 0.5f) * cellSize.y,
                                           g.lo.z + (z + 0.5f) * cellSize.z);
                        float bary[4];
                        float dist2 = 0.f;
                        const bool inside = locator.inside(t, centre, bary);
                        if (!inside) {
                            const Vec3f e = centroid - centre;
                            dist2 = dot(e, e);
                        }
                        std::uint32_t bits;
                        std::memcpy(&bits, &dist2, sizeof bits);  // non-negative: orders as uint
                        const std::uint64_t key = (std::uint64_t(bits) << 32) | t;
                        slot = std::min(slot, key);
                    }
        }
        std::uint32_t* seeds = out.seeds.data() + g.first;
        for (std::size_t k = 0; k < cells; ++k)
            seeds[k] = best[k] == ~std::uint64_t(0) ? kNoTet : static_cast<std::uint32_t>(best[k]);
    }
    out.buildSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

}  // namespace uvr
