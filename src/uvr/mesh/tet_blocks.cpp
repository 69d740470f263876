// SPDX-License-Identifier: MIT
// The kernels' layout of the tetrahedra (issue 16): cells in Morton order, tetrahedra in blocks
// of kTetBlockSize with 16-bit corner indices into per-block vertex lists.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/core/morton.h"
#include "uvr/core/scratch_vector.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

namespace {

/// A sort key and the position it came from (ties broken by position: every pair is distinct).
struct KeyIndex {
    std::uint64_t key;
    std::uint32_t index;
    bool operator<(const KeyIndex& o) const {
        return key < o.key || (key == o.key && index < o.index);
    }
};

/// Bits of the key each radix pass of sortKeys buckets by.
constexpr int kRadixBits = 12;
constexpr std::size_t kBuckets = std::size_t(1) << kRadixBits;

/// Sorts pairs by (key, index), keys of at most 63 bits. Ranges are split by stable radix passes
/// over the key's high bits (each pass parallel over fixed chunks) until each is small, then the
/// small ranges are sorted in parallel; the result is the one sorted order, so it does not
/// depend on the thread count. Skewed keys (graded meshes) only take more passes. `done` counts
/// the pairs each pass and the final sorts place (2n when one pass leaves only small ranges).
void sortKeys(ScratchVector<KeyIndex>& a, ProgressCounter& done) {
    const std::size_t n = a.size();
    struct Range {
        std::size_t begin, end;
        int shift;  ///< the pass's lowest bit; below 0: sort the range whole
    };
    const std::size_t small = std::max<std::size_t>(std::size_t(1) << 16, n / 256);
    std::vector<Range> work{{0, n, 63 - kRadixBits}}, leaves;
    ScratchVector<KeyIndex> tmp;
    while (!work.empty()) {
        std::vector<Range> next;
        for (const Range& r : work) {
            const std::size_t len = r.end - r.begin;
            if (len <= small || r.shift < 0) {
                leaves.push_back(r);
                continue;
            }
            if (tmp.size() < n) tmp.resize(n);
            // Fixed chunks: per chunk a histogram, bucket-major offsets, a stable scatter.
            const std::size_t chunk = std::max<std::size_t>(std::size_t(1) << 16, len / 256);
            const std::int64_t chunks = static_cast<std::int64_t>((len + chunk - 1) / chunk);
            std::vector<std::uint64_t> counts(std::size_t(chunks) * kBuckets, 0);
            auto bucketOf = [&](const KeyIndex& k) { return (k.key >> r.shift) & (kBuckets - 1); };
#pragma omp parallel for schedule(static)
            for (std::int64_t c = 0; c < chunks; ++c) {
                const std::size_t b = r.begin + std::size_t(c) * chunk;
                const std::size_t e = std::min(r.end, b + chunk);
                std::uint64_t* h = counts.data() + std::size_t(c) * kBuckets;
                for (std::size_t i = b; i < e; ++i) ++h[bucketOf(a[i])];
            }
            std::vector<std::uint64_t> bucketBegin(kBuckets + 1, 0);
            std::uint64_t sum = r.begin;
            for (std::size_t k = 0; k < kBuckets; ++k) {
                bucketBegin[k] = sum;
                for (std::int64_t c = 0; c < chunks; ++c) {
                    const std::uint64_t v = counts[std::size_t(c) * kBuckets + k];
                    counts[std::size_t(c) * kBuckets + k] = sum;
                    sum += v;
                }
            }
            bucketBegin[kBuckets] = sum;
#pragma omp parallel for schedule(static)
            for (std::int64_t c = 0; c < chunks; ++c) {
                const std::size_t b = r.begin + std::size_t(c) * chunk;
                const std::size_t e = std::min(r.end, b + chunk);
                std::uint64_t* at = counts.data() + std::size_t(c) * kBuckets;
                for (std::size_t i = b; i < e; ++i) tmp[at[bucketOf(a[i])]++] = a[i];
                done.add(std::int64_t(e - b));
            }
#pragma omp parallel for schedule(static)
            for (std::int64_t i = std::int64_t(r.begin); i < std::int64_t(r.end); ++i)
                a[i] = tmp[i];
            for (std::size_t k = 0; k < kBuckets; ++k)
                if (bucketBegin[k + 1] > bucketBegin[k])
                    next.push_back({bucketBegin[k], bucketBegin[k + 1], r.shift - kRadixBits});
        }
        work = std::move(next);
    }
    tmp = {};
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t i = 0; i < std::int64_t(leaves.size()); ++i) {
        std::sort(a.begin() + leaves[i].begin, a.begin() + leaves[i].end);
        done.add(std::int64_t(leaves[i].end - leaves[i].begin));
    }
}

/// The Morton order of `count` cells of `corners` corners each from ids (corner point ids, one
/// cell after another): the cells' positions sorted by (key, position), by `sorter` when set;
/// `progress` hears the keys' fraction (first 1/4) and the sort's.
ScratchVector<std::uint32_t> mortonOrder(const std::vector<Vec3f>& points, const Bounds3f& bounds,
                                         const std::uint32_t* ids, std::uint64_t count, int corners,
                                         const CellOrderSorter& sorter,
                                         const FractionFn& progress) {
    const float inv = 1.f / static_cast<float>(corners);
    ProgressCounter keyed(progress, std::int64_t(count), 0.0, 0.25);
    // Every cell's key, given to store(c, key) (in parallel).
    auto makeKeys = [&](auto&& store) {
#pragma omp parallel for schedule(static)
        for (std::int64_t c = 0; c < std::int64_t(count); ++c) {
            Vec3f centroid(0.f);
            for (int k = 0; k < corners; ++k)
                centroid += points[ids[std::uint64_t(c) * corners + k]];
            store(c, morton63(centroid * inv, bounds));
            keyed.tick(c);
        }
        keyed.finish();
    };
    ScratchVector<std::uint32_t> order(count);
    if (sorter) {
        ScratchVector<std::uint64_t> keys(count);
        makeKeys([&](std::int64_t c, std::uint64_t key) { keys[c] = key; });
        sorter(keys.data(), count, order.data());
        if (progress) progress(1.0);
    } else {
        ScratchVector<KeyIndex> keys(count);
        makeKeys([&](std::int64_t c, std::uint64_t key) {
            keys[c] = {key, static_cast<std::uint32_t>(c)};
        });
        ProgressCounter sorted(progress, 2 * std::int64_t(count), 0.25, 1.0);
        sortKeys(keys, sorted);
        sorted.finish();
#pragma omp parallel for schedule(static)
        for (std::int64_t c = 0; c < std::int64_t(count); ++c) order[c] = keys[c].index;
    }
    return order;
}

}  // namespace

void sortCellsSpatially(TetMesh& mesh, const FractionFn& progress, const CellOrderSorter& sorter) {
    // The tetrahedra's order (keys and sort) to 0.7, their gather to 0.9, native cells to 1.
    if (mesh.bounds.empty()) {
        if (progress) progress(1.0);
        return;
    }
    // Tetrahedra.
    const std::uint64_t n = mesh.tets.size();
    if (n > 1) {
        static_assert(sizeof(Tet) == 4 * sizeof(std::uint32_t));
        const ScratchVector<std::uint32_t> order =
            mortonOrder(mesh.points, mesh.bounds, &mesh.tets[0].v[0], n, 4, sorter,
                        subRange(progress, 0.0, 0.7));
        // Gathered into new arrays (scratch vectors: not zeroed first).
        ScratchVector<Tet> sorted(n);
        const bool had = !mesh.tetSourceOrder.empty();
        ScratchVector<std::uint32_t> source(n);
        ProgressCounter gathered(progress, std::int64_t(n), 0.7, 0.9);
#pragma omp parallel for schedule(static)
        for (std::int64_t i = 0; i < std::int64_t(n); ++i) {
            const std::uint32_t from = order[i];
            sorted[i] = mesh.tets[from];
            source[i] = had ? mesh.tetSourceOrder[from] : from;
            gathered.tick(i);
        }
        gathered.finish();
        mesh.tets.swap(sorted);
        mesh.tetSourceOrder.swap(source);
    }
    // Native cells, each kind among its own.
    const std::uint64_t counts[3] = {mesh.pyramidCount, mesh.wedgeCount, mesh.hexCount};
    std::uint64_t firstCell = 0, firstCorner = 0;
    for (int kind = 0; kind < 3; ++kind) {
        const int corners = kindCorners(static_cast<CellKind>(kind + 1));
        const std::uint64_t m = counts[kind];
        if (m > 1) {
            std::uint32_t* ids = mesh.nativeCorners.data() + firstCorner;
            const ScratchVector<std::uint32_t> order =
                mortonOrder(mesh.points, mesh.bounds, ids, m, corners, sorter, {});
            std::vector<std::uint32_t> sortedIds(m * corners);
            std::vector<std::uint64_t> sortedSource(m);
#pragma omp parallel for schedule(static)
            for (std::int64_t i = 0; i < std::int64_t(m); ++i) {
                const std::uint64_t from = order[i];
                std::copy(ids + from * corners, ids + (from + 1) * corners,
                          sortedIds.begin() + std::uint64_t(i) * corners);
                sortedSource[i] = mesh.nativeSource[firstCell + from];
            }
            std::copy(sortedIds.begin(), sortedIds.end(), ids);
            std::copy(sortedSource.begin(), sortedSource.end(),
                      mesh.nativeSource.begin() + firstCell);
        }
        firstCell += m;
        firstCorner += m * corners;
    }
    if (progress) progress(1.0);
}

void encodeTetBlocks(TetMesh& mesh, const FractionFn& progress) {
    const std::uint64_t n = mesh.tets.size();
    const std::int64_t blocks = static_cast<std::int64_t>((n + kTetBlockSize - 1) / kTetBlockSize);
    const bool pointValues =
        mesh.association == Association::Point && mesh.values.size() == mesh.points.size();
    // Per block: its distinct points in the order its corners first name them (an open-addressing
    // table of 2^16 slots per thread: at most 32768 points, so it is never more than half full),
    // and each corner's index among them.
    std::vector<std::vector<std::uint32_t>> lists(blocks);
    mesh.tetCorners.resize(n);
    ProgressCounter listed(progress, blocks, 0.0, 0.7);
#pragma omp parallel
    {
        constexpr std::uint32_t kSlots = 1u << 16, kEmpty = 0xffffffffu;
        std::vector<std::uint32_t> keys(kSlots);
        std::vector<std::uint16_t> local(kSlots);
#pragma omp for schedule(dynamic, 4)
        for (std::int64_t b = 0; b < blocks; ++b) {
            std::fill(keys.begin(), keys.end(), kEmpty);
            const std::uint64_t first = std::uint64_t(b) * kTetBlockSize;
            const std::uint64_t end = std::min<std::uint64_t>(n, first + kTetBlockSize);
            std::vector<std::uint32_t>& ids = lists[b];
            for (std::uint64_t t = first; t < end; ++t)
                for (int k = 0; k < 4; ++k) {
                    const std::uint32_t id = mesh.tets[t].v[k];
                    std::uint32_t slot = (id * 2654435761u) >> 16;
                    while (keys[slot] != kEmpty && keys[slot] != id)
                        slot = (slot + 1) & (kSlots - 1);
                    if (keys[slot] == kEmpty) {
                        keys[slot] = id;
                        local[slot] = static_cast<std::uint16_t>(ids.size());
                        ids.push_back(id);
                    }
                    mesh.tetCorners[t].v[k] = local[slot];
                }
            listed.add();
        }
    }
    listed.finish();
    mesh.blockVertexBase.assign(blocks + 1, 0);
    std::uint64_t total = 0;
    for (std::int64_t b = 0; b < blocks; ++b) {
        total += lists[b].size();
        if (total > 0xffffffffull)
            throwError(ErrorKind::Unsupported, "",
                       "the mesh's tetrahedra have " + std::to_string(total) +
                           "+ block vertices, more than 32-bit indices hold");
        mesh.blockVertexBase[b + 1] = static_cast<std::uint32_t>(total);
    }
    mesh.blockVertices.resize(total);
    mesh.blockVertexPoint.resize(total);
    ProgressCounter copied(progress, blocks, 0.7, 1.0);
#pragma omp parallel for schedule(dynamic, 4)
    for (std::int64_t b = 0; b < blocks; ++b) {
        const std::uint32_t base = mesh.blockVertexBase[b];
        const std::vector<std::uint32_t>& ids = lists[b];
        for (std::size_t i = 0; i < ids.size(); ++i) {
            mesh.blockVertexPoint[base + i] = ids[i];
            mesh.blockVertices[base + i] = {mesh.points[ids[i]],
                                            pointValues ? mesh.values[ids[i]] : 0.f};
        }
        lists[b] = {};
        copied.add();
    }
    copied.finish();
}

}  // namespace uvr
