// SPDX-License-Identifier: MIT
#include "uvr/accel/tet_adjacency.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <type_traits>

#include "uvr/core/error.h"
#include "uvr/core/scratch_vector.h"

namespace uvr {

namespace {

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

std::vector<std::uint32_t> coincidentPointIds(std::span<const Vec3f> points,
                                              const FractionFn& progress) {
    const std::int64_t n = static_cast<std::int64_t>(points.size());
    ProgressCounter done(progress, 3 * n);  // three passes over the points
    std::vector<std::uint32_t> canon(points.size());
    // Points bucketed by a hash of their position (a parallel counting sort); each bucket sorted
    // by position and index on its own, so the result does not depend on the thread count.
    std::vector<std::uint32_t> offsets(points.size() + 1, 0);
    auto bucketOf = [&](std::int64_t i) { return positionHash(points[i]) % std::uint64_t(n); };
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < n; ++i) {
        std::atomic_ref<std::uint32_t>(offsets[bucketOf(i) + 1])
            .fetch_add(1, std::memory_order_relaxed);
        done.tick(i);
    }
    for (std::int64_t i = 0; i < n; ++i) offsets[i + 1] += offsets[i];
    ScratchVector<std::uint32_t> ids(points.size());
    {
        std::vector<std::uint32_t> fill(offsets.begin(), offsets.end() - 1);
#pragma omp parallel for schedule(static)
        for (std::int64_t i = 0; i < n; ++i) {
            ids[std::atomic_ref<std::uint32_t>(fill[bucketOf(i)])
                    .fetch_add(1, std::memory_order_relaxed)] = static_cast<std::uint32_t>(i);
            done.tick(i);
        }
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
        done.add(end - start);
    }
    done.finish();
    return canon;
}

namespace {

/// A tetrahedron's face in its smallest vertex's bucket: the other two vertex ids (sorted) and
/// the slot 4 * tet + opposite vertex (12 bytes: the pure-tetrahedron path).
struct TetFace {
    std::uint32_t b, c, slot;
    std::uint32_t key3() const { return 0; }
    std::uint32_t cell() const { return slot / 4; }
    std::uint64_t tableSlot(const TetMeshView&) const { return slot; }
};

/// A face of a mixed mesh in its smallest vertex's bucket: the other vertex ids (sorted; d is
/// kNoCell for a triangle, so a triangle never matches a quadrilateral), its cell and face.
struct MixedFace {
    std::uint32_t b, c, d, cellId;
    std::uint8_t face;
    std::uint32_t key3() const { return d; }
    std::uint32_t cell() const { return cellId; }
    std::uint64_t tableSlot(const TetMeshView& m) const { return m.faceBase(cellId) + face; }
};

/// Sorted welded vertex ids of face f of cell c (3 or 4; f[3] = kNoCell for a triangle).
void sortedFace(const TetMeshView& m, const std::uint32_t* canon, std::uint64_t c, int face,
                std::uint32_t f[4]) {
    std::uint32_t ids[kMaxCellCorners];
    m.corners(c, ids);
    const std::uint32_t packed = packedFace(m.kind(c), face);
    const int n = faceSize(packed);
    f[3] = kNoCell;  // a triangle's
    for (int i = 0; i < n; ++i) f[i] = canon[ids[faceCorner(packed, i)]];
    std::sort(f, f + n);
}

/// Face matching over every cell of the view: faces bucketed by their smallest vertex id (a
/// counting sort, vertex-to-face CSR), each bucket sorted on its own by its full key, equal
/// faces paired; the same table for any thread count. `progress` hears the fraction done (the
/// steps weighted by their seconds at 100M tetrahedra: 0.67, 1.63, 1.5).
template <typename Entry>
std::vector<std::uint32_t> matchFaces(const TetMeshView& m, const std::vector<std::uint32_t>& canon,
                                      std::size_t points, const FractionFn& progress) {
    const std::int64_t n = static_cast<std::int64_t>(m.cellCount());
    constexpr double kCountEnd = 0.67 / 3.8, kScatterEnd = 2.3 / 3.8;
    // Step 1: faces per smallest vertex.
    std::vector<std::uint64_t> offsets(points + 1, 0);
    auto forFaces = [&](std::int64_t c, auto&& fn) {
        const int faces = kindFaces(m.kind(std::uint64_t(c)));
        for (int i = 0; i < faces; ++i) {
            std::uint32_t f[4];
            sortedFace(m, canon.data(), std::uint64_t(c), i, f);
            fn(i, f);
        }
    };
    ProgressCounter counted(progress, n, 0.0, kCountEnd);
#pragma omp parallel for schedule(static)
    for (std::int64_t c = 0; c < n; ++c) {
        forFaces(c, [&](int, const std::uint32_t* f) {
            std::atomic_ref<std::uint64_t>(offsets[f[0] + 1])
                .fetch_add(1, std::memory_order_relaxed);
        });
        counted.tick(c);
    }
    counted.finish();
    for (std::size_t p = 0; p < points; ++p) offsets[p + 1] += offsets[p];
    // Step 2: scatter faces into their buckets (in any order; step 3 sorts each bucket by its
    // full key, so the result does not depend on the order).
    ScratchVector<Entry> faces(static_cast<std::size_t>(offsets[points]));
    {
        std::vector<std::uint64_t> fill(offsets.begin(), offsets.end() - 1);
        ProgressCounter scattered(progress, n, kCountEnd, kScatterEnd);
#pragma omp parallel for schedule(static)
        for (std::int64_t c = 0; c < n; ++c) {
            scattered.tick(c);
            forFaces(c, [&](int i, const std::uint32_t* f) {
                const std::uint64_t at = std::atomic_ref<std::uint64_t>(fill[f[0]])
                                             .fetch_add(1, std::memory_order_relaxed);
                if constexpr (std::is_same_v<Entry, TetFace>)
                    faces[at] = {f[1], f[2], static_cast<std::uint32_t>(4 * c + i)};
                else
                    faces[at] = {f[1], f[2], f[3], static_cast<std::uint32_t>(c),
                                 static_cast<std::uint8_t>(i)};
            });
        }
        scattered.finish();
    }
    // Step 3: sort each bucket and pair equal faces.
    std::vector<std::uint32_t> neighbors(static_cast<std::size_t>(m.faceSlots()), kNoCell);
    const std::int64_t pointCount = static_cast<std::int64_t>(points);
    ProgressCounter paired(progress, pointCount, kScatterEnd, 1.0);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t start = 0; start < pointCount; start += kChunk) {
        const std::int64_t end = std::min(pointCount, start + kChunk);
        for (std::int64_t p = start; p < end; ++p) {
            Entry* first = faces.data() + offsets[p];
            Entry* last = faces.data() + offsets[p + 1];
            std::sort(first, last, [&](const Entry& x, const Entry& y) {
                if (x.b != y.b) return x.b < y.b;
                if (x.c != y.c) return x.c < y.c;
                if (x.key3() != y.key3()) return x.key3() < y.key3();
                return x.tableSlot(m) < y.tableSlot(m);
            });
            for (Entry* i = first; i < last;) {
                Entry* j = i + 1;
                while (j < last && j->b == i->b && j->c == i->c && j->key3() == i->key3()) ++j;
                if (j - i == 2) {  // an interior face; non-manifold faces (3+) stay boundary
                    neighbors[i[0].tableSlot(m)] = i[1].cell();
                    neighbors[i[1].tableSlot(m)] = i[0].cell();
                }
                i = j;
            }
        }
        paired.add(end - start);
    }
    paired.finish();
    return neighbors;
}

}  // namespace

std::vector<std::uint32_t> buildTetNeighbors(const TetMesh& mesh, const FractionFn& progress) {
    UVR_CHECK(mesh.cellCount() < kNoCell / 4, "too many cells for 32-bit neighbour ids");
    // Faces are matched on welded point ids: cells meeting at a seam of duplicated points (an
    // O-grid's cut, a multi-block export) become neighbours, so walks cross the seam.
    // Progress: the weld, then matchFaces (0.37 and 3.8 seconds at 100M tetrahedra).
    constexpr double kWeldEnd = 0.37 / 4.17;
    const std::vector<std::uint32_t> canon =
        coincidentPointIds(mesh.points, subRange(progress, 0.0, kWeldEnd));
    const TetMeshView view = mesh.view();
    const FractionFn matching = subRange(progress, kWeldEnd, 1.0);
    return mesh.hasNative() ? matchFaces<MixedFace>(view, canon, mesh.points.size(), matching)
                            : matchFaces<TetFace>(view, canon, mesh.points.size(), matching);
}

CompactNeighbors compactNeighbors(const TetMesh& mesh, const std::vector<std::uint32_t>& neighbors,
                                  const FractionFn& progress) {
    const TetMeshView view = mesh.view();
    UVR_CHECK(neighbors.size() == view.faceSlots(),
              "compactNeighbors: " << neighbors.size() << " faces, expected " << view.faceSlots());
    CompactNeighbors out;
    const std::uint64_t n = mesh.tets.size();
    const std::int64_t blocks = static_cast<std::int64_t>((n + kTetBlockSize - 1) / kTetBlockSize);
    out.tetCodes.resize(n);
    // Per block: its codes and how many escapes; then the escapes in block order.
    std::vector<std::uint32_t> escapeCount(blocks, 0);
    ProgressCounter coded(progress, 2 * blocks);  // two passes over the blocks
#pragma omp parallel for schedule(static)
    for (std::int64_t b = 0; b < blocks; ++b) {
        const std::uint64_t first = std::uint64_t(b) * kTetBlockSize;
        const std::uint64_t end = std::min<std::uint64_t>(n, first + kTetBlockSize);
        std::uint32_t escapes = 0;
        for (std::uint64_t t = first; t < end; ++t)
            for (int f = 0; f < 4; ++f) {
                const std::uint32_t nb = neighbors[4 * t + f];
                std::uint16_t code;
                if (nb == kNoTet)
                    code = kNoNeighborCode;
                else if (nb < n && (nb >> kTetBlockBits) == std::uint64_t(b))
                    code = static_cast<std::uint16_t>(nb & (kTetBlockSize - 1u));
                else
                    code = static_cast<std::uint16_t>(kTetBlockSize + escapes++);
                out.tetCodes[t].c[f] = code;
            }
        escapeCount[b] = escapes;
        coded.add();
    }
    out.escapeBase.assign(blocks + 1, 0);
    std::uint64_t total = 0;
    for (std::int64_t b = 0; b < blocks; ++b) {
        total += escapeCount[b];
        UVR_CHECK(total <= 0xffffffffull, "neighbour escapes exceed 32-bit indices");
        out.escapeBase[b + 1] = static_cast<std::uint32_t>(total);
    }
    out.escapes.resize(total);
#pragma omp parallel for schedule(static)
    for (std::int64_t b = 0; b < blocks; ++b) {
        const std::uint64_t first = std::uint64_t(b) * kTetBlockSize;
        const std::uint64_t end = std::min<std::uint64_t>(n, first + kTetBlockSize);
        std::uint32_t at = out.escapeBase[b];
        for (std::uint64_t t = first; t < end; ++t)
            for (int f = 0; f < 4; ++f) {
                const std::uint16_t code = out.tetCodes[t].c[f];
                if (code >= kTetBlockSize && code != kNoNeighborCode)
                    out.escapes[at++] = neighbors[4 * t + f];
            }
        coded.add();
    }
    coded.finish();
    out.native.assign(neighbors.begin() + std::int64_t(4 * n), neighbors.end());
    return out;
}

}  // namespace uvr
