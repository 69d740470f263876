// SPDX-License-Identifier: MIT
// The GPU's k-d tree build: one level of the tree at a time, every node of the level at once.
// Memory, sorts, scans and launches only: the split rules are the shared kdsplit:: functions of
// accel/kd_partitions.h, so the partitions are those of the CPU's build (same planes, same cells
// in the same order; only the numbering of nodes and partitions differs: breadth-first here).
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include <bit>

#include "uvr/core/error.h"
#include "uvr/core/runs.h"
#include "uvr/cuda/cuda_build.h"
#include "uvr/cuda/cuda_check.h"
#include "uvr/cuda/cuda_renderer.h"
#include "uvr/cuda/launch.cuh"

namespace uvr {

namespace cuda {
namespace {

/// Elements per thread of the bounds pass (runs of one node's cells are reduced locally first).
constexpr std::uint64_t kBoundsChunk = 256;

/// Adds a box to node s's bounds, kept as six order-preserving keys (atomic min / max).
__device__ void flushBounds(const Bounds3f& b, std::uint32_t* keys) {
    for (int a = 0; a < 3; ++a) {
        atomicMin(&keys[a], kdsplit::floatKey(b.lo[a]));
        atomicMax(&keys[3 + a], kdsplit::floatKey(b.hi[a]));
    }
}

/// Bounds of each node's cells over one chunk of kBoundsChunk consecutive elements, flushed
/// whenever the node changes.
__device__ void chunkBounds(std::uint64_t chunk, const std::uint32_t* cells,
                            const std::uint64_t* first, std::uint32_t m, std::uint64_t count,
                            const Bounds3f* boxes, std::uint32_t* keys) {
    const std::uint64_t begin = chunk * kBoundsChunk;
    const std::uint64_t end = begin + kBoundsChunk < count ? begin + kBoundsChunk : count;
    std::uint32_t node = runOf(first, m, begin);
    Bounds3f b;
    for (std::uint64_t i = begin; i < end; ++i) {
        if (i >= first[node + 1]) {
            flushBounds(b, keys + 6 * node);
            while (i >= first[node + 1]) ++node;
            b = Bounds3f{};
        }
        b.extend(boxes[cells[i]]);
    }
    flushBounds(b, keys + 6 * node);
}

/// Where a split node's children go in the next level.
struct ChildPlace {
    std::uint64_t belowBegin, aboveBegin;  ///< first element of each child
    std::uint64_t belowBase, aboveBase;    ///< the scans' values at the node's first element
    std::uint32_t split;                   ///< 0: the node became a leaf
};

/// Exclusive sum, in place, of count + 1 flags (the last is 0): data[count] is then the total,
/// and element i's flag is data[i + 1] - data[i].
void exclusiveSumInPlace(std::uint32_t* data, std::uint64_t count,
                         DeviceArray<unsigned char>& temp) {
    withScratch(temp, "the scan's scratch (GPU k-d build)", [&](void* scratch, std::size_t& bytes) {
        return cub::DeviceScan::ExclusiveSum(scratch, bytes, data, count + 1);
    });
}

/// A node of the level being split.
struct LevelNode {
    std::uint32_t node;  ///< its k-d node
    Bounds3f region;
    int depth;
};

}  // namespace
}  // namespace cuda

KdTree buildKdTreeCuda(const TetMesh& mesh, const KdBuildOptions& options,
                       const FractionFn& progress) {
    if (!cudaDeviceAvailable())
        throwError(ErrorKind::Unsupported, "", "GPU k-d build: no CUDA device found");
    UVR_CHECK(options.leafCells >= 1, "leaf size must be positive");
    const std::uint64_t n = mesh.cellCount();
    UVR_CHECK(n < (1ull << 30), "too many cells for k-d partitions");
    KdTree tree;
    tree.nodes.emplace_back();
    if (n == 0) {  // one empty partition, as the CPU's build makes
        tree.nodes[0].bits = 3u;
        tree.leafShrunk.push_back(kdsplit::shrunkRegion(mesh.bounds, Bounds3f{}));
        tree.leafBegin.push_back(0);
        return tree;
    }
    tree.leafCells.reserve(n + n / 4);
    // Device memory, c the cells of a level (n and more, cells reaching both sides of a plane
    // counted twice): the boxes (24 n bytes) and the level's cell list (4 c) throughout; the
    // sort's keys (16 c) while the medians are found; the side scans (8 c) and the next level's
    // list (4 c) while the cells move down. The node of an element is found from the level's
    // offsets (runOf), not kept per element. So the peak is about 24 n + 20 c bytes: 50 GB for
    // a billion graded tetrahedra, c = 1.32 n (docs/PERFORMANCE.md).
    cuda::DeviceArray<Bounds3f> boxes;
    cuda::DeviceArray<std::uint32_t> cells, nextCells;
    boxes.reserve(n, "the tetrahedron boxes (GPU k-d build)");
    cells.reserve(n, "the cell lists (GPU k-d build)");
    {
        cuda::DeviceArray<Vec3f> points;
        cuda::DeviceArray<Tet> tets;
        cuda::DeviceArray<std::uint32_t> nativeCorners;
        points.upload(mesh.points, "the mesh points (GPU k-d build)");
        tets.upload(mesh.tets, "the tetrahedra (GPU k-d build)");
        nativeCorners.upload(mesh.nativeCorners, "the native cells (GPU k-d build)");
        TetMeshView view = mesh.view();
        view.points = points.data(), view.tets = tets.data(), view.values = nullptr;
        view.nativeCorners = nativeCorners.data();
        // Cell boxes, and the first level: every cell in node 0.
        Bounds3f* b = boxes.data();
        std::uint32_t* c = cells.data();
        cuda::forEachElement("k-d cell boxes", n, [=] __device__(std::uint64_t t) {
            b[t] = view.cellBounds(t);
            c[t] = static_cast<std::uint32_t>(t);
        });
        UVR_CUDA_CHECK(cudaDeviceSynchronize());
    }
    cuda::DeviceArray<std::uint64_t> keys[2], begin, counts;
    cuda::DeviceArray<std::uint32_t> boundKeys, axis, splitting, belowScan, aboveScan;
    cuda::DeviceArray<float> planes;
    cuda::DeviceArray<cuda::ChildPlace> places;
    cuda::DeviceArray<unsigned char> temp;
    cuda::LevelNode top{0, mesh.bounds, 0};
    std::uint64_t count = n;
    if (const std::optional<KdSubtreeRoot>& root = options.root) {
        // A larger tree's node: the cells whose boxes reach its closed region, in id order (as
        // the CPU's build hands it them).
        top.region = root->region, top.depth = root->depth;
        belowScan.reserve(n + 1, "the offsets of the cells reaching the subtree (GPU k-d build)");
        UVR_CUDA_CHECK(cudaMemset(belowScan.data() + n, 0, sizeof(std::uint32_t)));
        const Bounds3f region = top.region;
        const Bounds3f* b = boxes.data();
        std::uint32_t* at = belowScan.data();
        cuda::forEachElement("k-d subtree cells", n, [=] __device__(std::uint64_t t) {
            bool in = true;
            for (int a = 0; a < 3; ++a)
                in = in && b[t].lo[a] <= region.hi[a] && b[t].hi[a] >= region.lo[a];
            at[t] = in;
        });
        cuda::exclusiveSumInPlace(at, n, temp);
        std::uint32_t* c = cells.data();
        cuda::forEachElement("k-d subtree cell list", n, [=] __device__(std::uint64_t t) {
            if (at[t + 1] != at[t]) c[at[t]] = static_cast<std::uint32_t>(t);  // at[t] <= t
        });
        std::uint32_t reaching = 0;
        UVR_CUDA_CHECK(
            cudaMemcpy(&reaching, belowScan.data() + n, sizeof reaching, cudaMemcpyDeviceToHost));
        count = reaching;
        if (count == 0) {  // one empty partition, as the CPU's build makes
            tree.nodes[0].bits = 3u;
            tree.leafShrunk.push_back(kdsplit::shrunkRegion(top.region, Bounds3f{}));
            tree.leafBegin.push_back(0);
            return tree;
        }
    }
    std::vector<cuda::LevelNode> level{top};
    std::vector<std::uint64_t> levelBegin{0, count};
    while (!level.empty()) {
        const std::uint32_t m = static_cast<std::uint32_t>(level.size());
        begin.upload(levelBegin, "the node offsets (GPU k-d build)");
        const std::uint64_t* first = begin.data();
        // Bounds of every node's cells, then the shrunk regions and split axes on the host.
        std::vector<std::uint32_t> hostKeys(6 * std::size_t(m));
        for (std::uint32_t s = 0; s < m; ++s)
            for (int a = 0; a < 3; ++a)
                hostKeys[6 * s + a] = 0xffffffffu, hostKeys[6 * s + 3 + a] = 0;
        boundKeys.upload(hostKeys, "the node bounds (GPU k-d build)");
        {
            const std::uint32_t* c = cells.data();
            const Bounds3f* b = boxes.data();
            std::uint32_t* k = boundKeys.data();
            cuda::forEachElement("k-d node bounds",
                                 (count + cuda::kBoundsChunk - 1) / cuda::kBoundsChunk,
                                 [=] __device__(std::uint64_t chunk) {
                                     cuda::chunkBounds(chunk, c, first, m, count, b, k);
                                 });
        }
        boundKeys.download(hostKeys.data(), hostKeys.size());
        std::vector<Bounds3f> shrunk(m);
        std::vector<std::uint32_t> hostAxis(m), hostSplitting(m);
        bool anySplit = false;
        for (std::uint32_t s = 0; s < m; ++s) {
            Bounds3f cellBounds;
            for (int a = 0; a < 3; ++a) {
                cellBounds.lo[a] = kdsplit::keyFloat(hostKeys[6 * s + a]);
                cellBounds.hi[a] = kdsplit::keyFloat(hostKeys[6 * s + 3 + a]);
            }
            shrunk[s] = kdsplit::shrunkRegion(level[s].region, cellBounds);
            hostAxis[s] = static_cast<std::uint32_t>(shrunk[s].longestAxis());
            hostSplitting[s] =
                kdsplit::wantsSplit(levelBegin[s + 1] - levelBegin[s], level[s].depth, shrunk[s],
                                    options.leafCells, options.maxDepth);
            anySplit = anySplit || hostSplitting[s];
        }
        std::vector<float> hostPlanes(m, 0.f);
        std::vector<std::uint64_t> hostCounts(4 * std::size_t(m), 0);
        if (anySplit) {
            // Median centres: one sort of (node, centre) keys for the whole level.
            axis.upload(hostAxis, "the split axes (GPU k-d build)");
            splitting.upload(hostSplitting, "the split flags (GPU k-d build)");
            keys[0].reserve(count, "the centre keys (GPU k-d build)");
            keys[1].reserve(count, "the sorted centre keys (GPU k-d build)");
            // Sort keys: the node in the high word, the cell centre on the node's axis in the low.
            const std::uint32_t *c = cells.data(), *ax = axis.data();
            const Bounds3f* b = boxes.data();
            std::uint64_t* k = keys[0].data();
            cuda::forEachElement("k-d centre keys", count, [=] __device__(std::uint64_t i) {
                const std::uint32_t s = runOf(first, m, i);
                k[i] = (static_cast<std::uint64_t>(s) << 32) |
                       kdsplit::floatKey(b[c[i]].center()[ax[s]]);
            });
            cub::DoubleBuffer<std::uint64_t> keyBuffer(keys[0].data(), keys[1].data());
            const int endBit = 32 + std::bit_width(m - 1);
            cuda::withScratch(temp, "the radix sort's scratch (GPU k-d build)",
                              [&](void* scratch, std::size_t& bytes) {
                                  return cub::DeviceRadixSort::SortKeys(scratch, bytes, keyBuffer,
                                                                        count, 0, endBit);
                              });
            planes.reserve(m, "the split planes (GPU k-d build)");
            // Each node's median centre: the (count / 2)-th smallest, as the CPU's selection
            // picks.
            const std::uint64_t* sorted = keyBuffer.Current();
            float* pl = planes.data();
            cuda::forEachElement("k-d medians", m, [=] __device__(std::uint64_t s) {
                const std::uint64_t cellsOfNode = first[s + 1] - first[s];
                pl[s] = kdsplit::keyFloat(
                    static_cast<std::uint32_t>(sorted[first[s] + cellsOfNode / 2]));
            });
            planes.download(hostPlanes.data(), m);
            // The keys' memory goes back before the sides take theirs (the build's peak).
            keys[0].clear();
            keys[1].clear();
            temp.clear();
            // Which side(s) of its node's plane each cell goes to (nodes not splitting: neither),
            // as flags scanned in place into each side's offsets.
            belowScan.reserve(count + 1, "the below offsets (GPU k-d build)");
            aboveScan.reserve(count + 1, "the above offsets (GPU k-d build)");
            UVR_CUDA_CHECK(cudaMemset(belowScan.data() + count, 0, sizeof(std::uint32_t)));
            UVR_CUDA_CHECK(cudaMemset(aboveScan.data() + count, 0, sizeof(std::uint32_t)));
            const std::uint32_t* split = splitting.data();
            std::uint32_t *lo = belowScan.data(), *hi = aboveScan.data();
            cuda::forEachElement("k-d sides", count, [=] __device__(std::uint64_t i) {
                const std::uint32_t s = runOf(first, m, i);
                const Bounds3f& box = b[c[i]];
                lo[i] = split[s] && kdsplit::goesBelow(box, static_cast<int>(ax[s]), pl[s]);
                hi[i] = split[s] && kdsplit::goesAbove(box, static_cast<int>(ax[s]), pl[s]);
            });
            cuda::exclusiveSumInPlace(lo, count, temp);
            cuda::exclusiveSumInPlace(hi, count, temp);
            counts.reserve(4 * std::size_t(m), "the side counts (GPU k-d build)");
            // Per node: how many cells go below and above (differences of the exclusive scans).
            const std::uint32_t *bs = lo, *as = hi;
            std::uint64_t* n4 = counts.data();
            cuda::forEachElement("k-d side counts", m, [=] __device__(std::uint64_t s) {
                n4[4 * s + 0] = bs[first[s]];
                n4[4 * s + 1] = bs[first[s + 1]] - bs[first[s]];
                n4[4 * s + 2] = as[first[s]];
                n4[4 * s + 3] = as[first[s + 1]] - as[first[s]];
            });
            counts.download(hostCounts.data(), hostCounts.size());
        }
        // The host decides each node: split (children to the next level) or leaf (its cells,
        // one contiguous run, copied out).
        std::vector<cuda::ChildPlace> hostPlaces(m);
        std::vector<cuda::LevelNode> next;
        std::vector<std::uint64_t> nextBegin{0};
        for (std::uint32_t s = 0; s < m; ++s) {
            const cuda::LevelNode& ln = level[s];
            const std::uint64_t nodeCount = levelBegin[s + 1] - levelBegin[s];
            const int a = static_cast<int>(hostAxis[s]);
            const float plane = hostPlanes[s];
            const std::uint64_t nBelow = hostCounts[4 * s + 1], nAbove = hostCounts[4 * s + 3];
            cuda::ChildPlace& p = hostPlaces[s];
            p = {};
            if (hostSplitting[s] &&
                kdsplit::keepsSplit(ln.region, a, plane, nBelow, nAbove, nodeCount)) {
                const std::uint32_t child = static_cast<std::uint32_t>(tree.nodes.size());
                tree.nodes[ln.node].split = plane;
                tree.nodes[ln.node].bits = (child << 2) | static_cast<std::uint32_t>(a);
                tree.nodes.emplace_back();
                tree.nodes.emplace_back();
                Bounds3f lower = ln.region, upper = ln.region;
                lower.hi[a] = plane;
                upper.lo[a] = plane;
                p.split = 1;
                p.belowBase = hostCounts[4 * s + 0];
                p.aboveBase = hostCounts[4 * s + 2];
                p.belowBegin = nextBegin.back();
                next.push_back({child, lower, ln.depth + 1});
                nextBegin.push_back(nextBegin.back() + nBelow);
                p.aboveBegin = nextBegin.back();
                next.push_back({child + 1, upper, ln.depth + 1});
                nextBegin.push_back(nextBegin.back() + nAbove);
                continue;
            }
            const std::uint32_t leaf = static_cast<std::uint32_t>(tree.leafShrunk.size());
            tree.nodes[ln.node].bits = (leaf << 2) | 3u;
            tree.leafShrunk.push_back(shrunk[s]);
            const std::size_t at = tree.leafCells.size();
            tree.leafCells.resize(at + nodeCount);
            UVR_CUDA_CHECK(cudaMemcpy(tree.leafCells.data() + at, cells.data() + levelBegin[s],
                                      nodeCount * sizeof(std::uint32_t), cudaMemcpyDeviceToHost));
            tree.leafBegin.push_back(tree.leafCells.size());
            if (progress) progress(0.98 * double(tree.leafCells.size()) / double(n));
            UVR_CHECK(tree.leafCells.size() < 0xffffffffull,
                      "partition cell lists exceed 32-bit indices");
        }
        if (next.empty()) break;
        const std::uint64_t nextCount = nextBegin.back();
        UVR_CHECK(nextCount < 0xffffffffull, "k-d cell lists exceed 32-bit offsets");
        places.upload(hostPlaces, "the child places (GPU k-d build)");
        nextCells.reserve(nextCount, "the next level's cells (GPU k-d build)");
        {
            // Order-preserving scatter of the cells of split nodes into the next level: a cell's
            // flag on a side is the step of that side's scan at it.
            const std::uint32_t *c = cells.data(), *bs = belowScan.data(), *as = aboveScan.data();
            const cuda::ChildPlace* pl = places.data();
            std::uint32_t* nc = nextCells.data();
            cuda::forEachElement("k-d scatter", count, [=] __device__(std::uint64_t i) {
                const cuda::ChildPlace& p = pl[runOf(first, m, i)];
                if (!p.split) return;
                if (bs[i + 1] != bs[i]) nc[p.belowBegin + bs[i] - p.belowBase] = c[i];
                if (as[i + 1] != as[i]) nc[p.aboveBegin + as[i] - p.aboveBase] = c[i];
            });
        }
        cells.swap(nextCells);
        // The scans' and the old list's memory goes back before the next level's sort.
        nextCells.clear();
        belowScan.clear();
        aboveScan.clear();
        level = std::move(next);
        levelBegin = std::move(nextBegin);
        count = nextCount;
    }
    UVR_CUDA_CHECK(cudaDeviceSynchronize());
    return tree;
}

}  // namespace uvr
