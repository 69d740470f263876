// SPDX-License-Identifier: MIT
#include "uvr/accel/tet_adjacency.h"

#include <algorithm>
#include <atomic>
#include <cstring>

#include "uvr/core/error.h"
#include "uvr/core/scratch_vector.h"

namespace uvr {

namespace {

/// A face in its smallest vertex's bucket: the other two vertex ids (sorted) and the slot
/// 4 * tet + opposite vertex.
struct FaceEntry {
    std::uint32_t b, c, slot;
};

/// Tetrahedra per parallel chunk (fixed, so results never depend on the thread count).
constexpr std::int64_t kChunk = 1 << 14;

/// Hash of a position (with -0 read as +0, so equal positions hash equally).
std::uint64_t positionHash(Vec3f p) {
    std::uint64_t h = 1469598103934665603ull;
    for (int a = 0; a < 3; ++a) {
        const float v = p[a] + 0.f;
        std::uint32_t bits;
        std::memcpy(&bits, &v, sizeof bits);
        h = (h ^ bits) * 1099511628211ull;
        h ^= h >> 29;
    }
    return h;
}

}  // namespace

std::vector<std::uint32_t> coincidentPointIds(const std::vector<Vec3f>& points) {
    const std::int64_t n = static_cast<std::int64_t>(points.size());
    std::vector<std::uint32_t> canon(points.size());
    // Points bucketed by a hash of their position (a parallel counting sort); each bucket sorted
    // by position and index on its own, so the result does not depend on the thread count.
    std::vector<std::uint32_t> offsets(points.size() + 1, 0);
    auto bucketOf = [&](std::int64_t i) { return positionHash(points[i]) % std::uint64_t(n); };
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < n; ++i)
        std::atomic_ref<std::uint32_t>(offsets[bucketOf(i) + 1])
            .fetch_add(1, std::memory_order_relaxed);
    for (std::int64_t i = 0; i < n; ++i) offsets[i + 1] += offsets[i];
    ScratchVector<std::uint32_t> ids(points.size());
    {
        std::vector<std::uint32_t> fill(offsets.begin(), offsets.end() - 1);
#pragma omp parallel for schedule(static)
        for (std::int64_t i = 0; i < n; ++i)
            ids[std::atomic_ref<std::uint32_t>(fill[bucketOf(i)])
                    .fetch_add(1, std::memory_order_relaxed)] = static_cast<std::uint32_t>(i);
    }
    auto less = [&](std::uint32_t a, std::uint32_t b) {
        const Vec3f p = points[a], q = points[b];
        if (p.x != q.x) return p.x < q.x;
        if (p.y != q.y) return p.y < q.y;
        if (p.z != q.z) return p.z < q.z;
        return a < b;
    };
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t start = 0; start < n; start += kChunk) {
        const std::int64_t end = std::min(n, start + kChunk);
        for (std::int64_t b = start; b < end; ++b) {
            std::uint32_t* first = ids.data() + offsets[b];
            std::uint32_t* last = ids.data() + offsets[b + 1];
            std::sort(first, last, less);
            // Runs of equal positions (NaN equals nothing and stays alone): the run's first,
            // smallest index stands for all.
            for (std::uint32_t* i = first; i < last;) {
                std::uint32_t* j = i + 1;
                while (j < last && points[*j] == points[*i]) ++j;
                for (std::uint32_t* k = i; k < j; ++k) canon[*k] = *i;
                i = j;
            }
        }
    }
    return canon;
}

std::vector<std::uint32_t> buildTetNeighbors(const TetMesh& mesh) {
    const std::int64_t n = static_cast<std::int64_t>(mesh.tets.size());
    UVR_CHECK(static_cast<std::uint64_t>(n) < kNoTet / 4,
              "too many tetrahedra for 32-bit neighbour ids");
    const std::size_t points = mesh.points.size();
    // Faces are matched on welded point ids: cells meeting at a seam of duplicated points (an
    // O-grid's cut, a multi-block export) become neighbours, so walks cross the seam.
    const std::vector<std::uint32_t> canon = coincidentPointIds(mesh.points);
    const Tet* tets = mesh.tets.data();
    // Faces bucketed by their smallest vertex id (a counting sort, vertex-to-face CSR), so each
    // bucket is a handful of faces sorted on its own instead of one sort of 4n faces.
    // Step 1: faces per smallest vertex.
    std::vector<std::uint32_t> offsets(points + 1, 0);
    auto faceOf = [&](std::int64_t t, int i, std::uint32_t f[3]) {
        int k = 0;
        for (int j = 0; j < 4; ++j)
            if (j != i) f[k++] = canon[tets[t].v[j]];
        if (f[0] > f[1]) std::swap(f[0], f[1]);
        if (f[1] > f[2]) std::swap(f[1], f[2]);
        if (f[0] > f[1]) std::swap(f[0], f[1]);
    };
#pragma omp parallel for schedule(static)
    for (std::int64_t t = 0; t < n; ++t)
        for (int i = 0; i < 4; ++i) {
            std::uint32_t f[3];
            faceOf(t, i, f);
            std::atomic_ref<std::uint32_t>(offsets[f[0] + 1])
                .fetch_add(1, std::memory_order_relaxed);
        }
    for (std::size_t p = 0; p < points; ++p) offsets[p + 1] += offsets[p];
    // Step 2: scatter faces into their buckets (in any order; step 3 sorts each bucket by its
    // full key, so the result does not depend on the order).
    ScratchVector<FaceEntry> faces(static_cast<std::size_t>(4 * n));
    {
        std::vector<std::uint32_t> fill(offsets.begin(), offsets.end() - 1);
#pragma omp parallel for schedule(static)
        for (std::int64_t t = 0; t < n; ++t)
            for (int i = 0; i < 4; ++i) {
                std::uint32_t f[3];
                faceOf(t, i, f);
                const std::uint32_t at = std::atomic_ref<std::uint32_t>(fill[f[0]])
                                             .fetch_add(1, std::memory_order_relaxed);
                faces[at] = {f[1], f[2], static_cast<std::uint32_t>(4 * t + i)};
            }
    }
    // Step 3: sort each bucket and pair equal faces.
    std::vector<std::uint32_t> neighbors(static_cast<std::size_t>(4 * n), kNoTet);
    const std::int64_t pointCount = static_cast<std::int64_t>(points);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t start = 0; start < pointCount; start += kChunk) {
        const std::int64_t end = std::min(pointCount, start + kChunk);
        for (std::int64_t p = start; p < end; ++p) {
            FaceEntry* first = faces.data() + offsets[p];
            FaceEntry* last = faces.data() + offsets[p + 1];
            std::sort(first, last, [](const FaceEntry& x, const FaceEntry& y) {
                if (x.b != y.b) return x.b < y.b;
                if (x.c != y.c) return x.c < y.c;
                return x.slot < y.slot;
            });
            for (FaceEntry* i = first; i < last;) {
                FaceEntry* j = i + 1;
                while (j < last && j->b == i->b && j->c == i->c) ++j;
                if (j - i == 2) {  // an interior face; non-manifold faces (3+) stay boundary
                    neighbors[i[0].slot] = i[1].slot / 4;
                    neighbors[i[1].slot] = i[0].slot / 4;
                }
                i = j;
            }
        }
    }
    return neighbors;
}

}  // namespace uvr
