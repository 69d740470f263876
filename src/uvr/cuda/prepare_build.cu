// SPDX-License-Identifier: MIT
// The GPU's builds of face neighbours and seed grids (issue 16: the first image of 100M
// tetrahedra in seconds). Memory, atomics and launches only: the face rule is buildTetNeighbors'
// (faces bucketed by their smallest welded vertex, a face paired only with its one equal) and the
// seed rule is offerSeedKeys', so the tables equal the CPU's bit for bit. This file is compiled
// with --fmad=false: no multiply-add is fused, so the seeds' barycentrics and distances round as
// the CPU's do.
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include <algorithm>
#include <chrono>
#include <future>
#include <vector>

#include "uvr/accel/macro_grid.h"
#include "uvr/accel/tet_adjacency.h"
#include "uvr/core/error.h"
#include "uvr/cuda/cuda_build.h"
#include "uvr/cuda/cuda_check.h"
#include "uvr/cuda/cuda_renderer.h"
#include "uvr/cuda/launch.cuh"

namespace uvr {

namespace cuda {
namespace {

/// A face in its smallest welded vertex's bucket: the other vertex ids (sorted; d is kNoCell for
/// a triangle) and its slot in the neighbour table (TetMeshView::faceBase + face).
struct FaceEntry {
    std::uint32_t b, c, d, slot;
};

/// Sorted welded vertex ids of face `face` of cell c into f (f[3] = kNoCell for a triangle).
__device__ void sortedFace(const TetMeshView& m, const std::uint32_t* canon, std::uint64_t c,
                           int face, std::uint32_t f[4]) {
    std::uint32_t ids[kMaxCellCorners];
    m.corners(c, ids);
    const std::uint32_t packed = packedFace(m.kind(c), face);
    const int n = faceSize(packed);
    f[3] = kNoCell;
    for (int i = 0; i < n; ++i) f[i] = canon[ids[faceCorner(packed, i)]];
    for (int i = 1; i < n; ++i)  // insertion sort of 3 or 4
        for (int j = i; j > 0 && f[j - 1] > f[j]; --j) {
            const std::uint32_t s = f[j];
            f[j] = f[j - 1];
            f[j - 1] = s;
        }
}

/// The cell whose faces hold neighbour-table slot s (the inverse of TetMeshView::faceBase).
__device__ std::uint32_t cellOfSlot(const TetMeshView& m, std::uint64_t s) {
    if (s < 4 * m.tetCount) return static_cast<std::uint32_t>(s / 4);
    s -= 4 * m.tetCount;
    const std::uint64_t pw = m.pyramidCount + m.wedgeCount;
    if (s < 5 * pw) return static_cast<std::uint32_t>(m.tetCount + s / 5);
    return static_cast<std::uint32_t>(m.tetCount + pw + (s - 5 * pw) / 6);
}

/// Faces per smallest welded vertex.
__device__ void countFaces(std::uint64_t c, TetMeshView m, const std::uint32_t* canon,
                           unsigned long long* counts) {
    const int faces = kindFaces(m.kind(c));
    for (int i = 0; i < faces; ++i) {
        std::uint32_t f[4];
        sortedFace(m, canon, c, i, f);
        atomicAdd(&counts[f[0]], 1ull);
    }
}

/// Faces whose smallest vertex lies in [lo, hi) into their buckets (entries from offset `base`),
/// in any order: matchFaces' rule does not depend on it.
__device__ void scatterFaces(std::uint64_t c, TetMeshView m, const std::uint32_t* canon,
                             std::uint32_t lo, std::uint32_t hi, unsigned long long base,
                             unsigned long long* fill, FaceEntry* entries) {
    const int faces = kindFaces(m.kind(c));
    const std::uint64_t first = m.faceBase(c);
    for (int i = 0; i < faces; ++i) {
        std::uint32_t f[4];
        sortedFace(m, canon, c, i, f);
        if (f[0] < lo || f[0] >= hi) continue;
        const unsigned long long at = atomicAdd(&fill[f[0]], 1ull) - base;
        entries[at] = {f[1], f[2], f[3], static_cast<std::uint32_t>(first + i)};
    }
}

/// Vertex v (of a pass's range): each face of its bucket with exactly one equal face gets that
/// face's cell as its neighbour (a face shared by three or more cells stays a boundary, as on the
/// CPU).
__device__ void matchFaces(std::uint64_t v, TetMeshView m, const unsigned long long* offsets,
                           unsigned long long base, const FaceEntry* entries,
                           std::uint32_t* neighbors) {
    const std::uint64_t begin = offsets[v] - base, end = offsets[v + 1] - base;
    for (std::uint64_t i = begin; i < end; ++i) {
        const FaceEntry e = entries[i];
        std::uint32_t equal = 0, other = 0;
        for (std::uint64_t j = begin; j < end && equal < 2; ++j) {
            const FaceEntry o = entries[j];
            if (j != i && o.b == e.b && o.c == e.c && o.d == e.d) {
                ++equal;
                other = o.slot;
            }
        }
        if (equal == 1) neighbors[e.slot] = cellOfSlot(m, other);
    }
}

/// Seeds of every partition: one block per partition, its threads over the partition's cells,
/// each offering its keys by atomic minima.
__global__ void seedKernel(TetLocator locator, const KdPartition* partitions,
                           const std::uint32_t* kdCells, const PartitionGrid* grids,
                           unsigned long long* best) {
    const KdPartition part = partitions[blockIdx.x];
    const PartitionGrid g = grids[blockIdx.x];
    if (part.cellCount == 0 || part.box.empty()) return;
    unsigned long long* slots = best + g.first;
    for (std::uint32_t i = threadIdx.x; i < part.cellCount; i += blockDim.x)
        offerSeedKeys(
            locator, g, kdCells[part.firstCell + i],
            [&](std::uint64_t c) { return static_cast<std::uint64_t>(slots[c]); },
            [&](std::uint64_t c, std::uint64_t key) {
                atomicMin(&slots[c], static_cast<unsigned long long>(key));
            });
}

/// Order-preserving keys of a box's corners, folded into six keys (atomic min / max).
__device__ void foldBox(const Bounds3f& b, std::uint32_t* keys) {
    for (int a = 0; a < 3; ++a) {
        atomicMin(&keys[a], kdsplit::floatKey(b.lo[a]));
        atomicMax(&keys[3 + a], kdsplit::floatKey(b.hi[a]));
    }
}

/// The box of six keys (empty when nothing was folded in).
__device__ Bounds3f unfoldBox(const std::uint32_t* keys) {
    Bounds3f b;
    for (int a = 0; a < 3; ++a) {
        b.lo[a] = kdsplit::keyFloat(keys[a]);
        b.hi[a] = kdsplit::keyFloat(keys[3 + a]);
    }
    return b;
}

/// Empty boxes and ranges as keys: lows at +infinity, highs at -infinity, over `count` keys of
/// `perItem` each (the first half lows).
void clearKeys(const char* name, std::uint32_t* keys, std::uint64_t count, int perItem) {
    forEachElement(name, count, [=] __device__(std::uint64_t i) {
        const int k = static_cast<int>(i % perItem);
        keys[i] = kdsplit::floatKey(k < perItem / 2 ? INFINITY : -INFINITY);
    });
}

/// Macrocell flags.
constexpr std::uint32_t kUnboundedSpread = 1u, kHasNan = 2u, kAtBoundary = 4u;

/// Macrocells and partition gradient boxes: one block per partition, its threads over the
/// partition's cells, each folding its MacroContribution into the macrocells its box overlaps
/// (fillMacroCells' rule) and its gradients into its partition's box.
__global__ void macroKernel(TetMeshView m, const KdPartition* partitions,
                            const std::uint32_t* kdCells, const PartitionGrid* grids,
                            const std::uint8_t* boundary, bool anyNan, std::uint32_t* rangeKeys,
                            std::uint32_t* gradientKeys, std::uint32_t* flags,
                            std::uint32_t* partitionKeys) {
    const KdPartition part = partitions[blockIdx.x];
    const PartitionGrid g = grids[blockIdx.x];
    const bool macro = !part.box.empty();  // fillMacroCells skips empty boxes
    Bounds3f spread;                       // this thread's cells' gradients
    for (std::uint32_t i = threadIdx.x; i < part.cellCount; i += blockDim.x) {
        const std::uint32_t t = kdCells[part.firstCell + i];
        const MacroContribution add = macroContribution(m, t, anyNan);
        spread.extend(add.gradients);
        if (!macro) continue;
        const bool unbounded = m.cellCentered;
        forOverlappedMacroCells(g, add.box, [&](std::uint64_t c) {
            if (add.lo <= add.hi) {  // a range without NaN values
                atomicMin(&rangeKeys[2 * c], kdsplit::floatKey(add.lo));
                atomicMax(&rangeKeys[2 * c + 1], kdsplit::floatKey(add.hi));
            }
            const std::uint32_t f = (unbounded ? kUnboundedSpread : 0u) | (add.nan ? kHasNan : 0u) |
                                    (boundary[t] ? kAtBoundary : 0u);
            if (f) atomicOr(&flags[c], f);
            if (!unbounded && !add.gradients.empty()) foldBox(add.gradients, gradientKeys + 6 * c);
        });
    }
    if (!spread.empty()) foldBox(spread, partitionKeys + 6 * blockIdx.x);
}

/// Macrocells from their keys and flags (fillMacroCells' last step).
__device__ void macroCellOf(std::uint64_t c, const std::uint32_t* rangeKeys,
                            const std::uint32_t* gradientKeys, const std::uint32_t* flags,
                            MacroCell* cells) {
    MacroCell m;
    m.valueMin = kdsplit::keyFloat(rangeKeys[2 * c]);
    m.valueMax = kdsplit::keyFloat(rangeKeys[2 * c + 1]);
    const Bounds3f gradients = unfoldBox(gradientKeys + 6 * c);
    if (flags[c] & kUnboundedSpread)
        m.gradientSpread = INFINITY;
    else if (!gradients.empty())
        m.gradientSpread = length(gradients.hi - gradients.lo);
    m.atBoundary = (flags[c] & kAtBoundary) ? 1u : 0u;
    cells[c] = m;
}

/// Throws Error(Unsupported) naming the build when no CUDA device is present.
void requireDevice(const char* build) {
    if (!cudaDeviceAvailable())
        throwError(ErrorKind::Unsupported, "", std::string(build) + ": no CUDA device found");
}

/// The cells in the kernels' layout (the blocks' corners and vertices; the points and corners of
/// native cells; the values when `values` is true and the cells read them: cell data, native
/// cells) on the GPU, and a view of them: what the seed and macrocell builders read.
struct DeviceCells {
    DeviceArray<TetCorners16> corners;
    DeviceArray<BlockVertex> blockVertices;
    DeviceArray<std::uint32_t> blockBase, nativeCorners;
    DeviceArray<Vec3f> points;
    DeviceArray<float> values;
    TetMeshView view;

    DeviceCells(const TetMesh& mesh, bool withValues, const char* build) : view(mesh.view()) {
        auto what = [build](const char* array) { return std::string(array) + " (" + build + ")"; };
        corners.upload(mesh.tetCorners, what("the tetrahedra's corners").c_str());
        blockVertices.upload(mesh.blockVertices, what("the block vertices").c_str());
        blockBase.upload(mesh.blockVertexBase, what("the block offsets").c_str());
        view.tets = nullptr, view.values = nullptr, view.points = nullptr;
        view.nativeCorners = nullptr;
        if (withValues && (view.hasNative() || view.cellCentered)) {
            values.upload(mesh.values, what("the values").c_str());
            view.values = values.data();
        }
        if (view.hasNative()) {
            points.upload(mesh.points, what("the points").c_str());
            nativeCorners.upload(mesh.nativeCorners, what("the native cells").c_str());
            view.points = points.data(), view.nativeCorners = nativeCorners.data();
        }
        view.tetCorners = corners.data(), view.blockVertices = blockVertices.data();
        view.blockVertexBase = blockBase.data();
    }
};

}  // namespace
}  // namespace cuda

void sortCellKeysCuda(const std::uint64_t* keys, std::uint64_t count, std::uint32_t* order) {
    cuda::requireDevice("GPU sort of the cells");
    UVR_CHECK(count < (std::uint64_t(1) << 32), "too many cells to sort: " << count);
    if (count == 0) return;
    // A stable radix sort of (key, position) pairs by key: ties keep their positions' order.
    cuda::DeviceArray<std::uint64_t> keyArrays[2];
    cuda::DeviceArray<std::uint32_t> positions[2];
    cuda::DeviceArray<unsigned char> temp;
    keyArrays[0].upload(keys, count, "the cells' Morton keys (GPU sort)");
    keyArrays[1].reserve(count, "the sorted Morton keys (GPU sort)");
    positions[0].reserve(count, "the cells' positions (GPU sort)");
    positions[1].reserve(count, "the sorted positions (GPU sort)");
    {
        std::uint32_t* p = positions[0].data();
        cuda::forEachElement("cell sort positions", count, [=] __device__(std::uint64_t i) {
            p[i] = static_cast<std::uint32_t>(i);
        });
    }
    cub::DoubleBuffer<std::uint64_t> keyBuffer(keyArrays[0].data(), keyArrays[1].data());
    cub::DoubleBuffer<std::uint32_t> positionBuffer(positions[0].data(), positions[1].data());
    cuda::withScratch(temp, "the radix sort's scratch (GPU sort)", [&](void* s, std::size_t& b) {
        return cub::DeviceRadixSort::SortPairs(s, b, keyBuffer, positionBuffer,
                                               static_cast<std::int64_t>(count), 0, 63);
    });
    UVR_CUDA_CHECK(cudaMemcpy(order, positionBuffer.Current(), count * sizeof(std::uint32_t),
                              cudaMemcpyDeviceToHost));
}

std::vector<std::uint32_t> buildTetNeighborsCuda(const TetMesh& mesh, const FractionFn& progress,
                                                 std::uint64_t facesPerPass,
                                                 const std::vector<std::uint32_t>* welded) {
    cuda::requireDevice("GPU face neighbours");
    const TetMeshView host = mesh.view();
    const std::uint64_t n = host.cellCount(), slots = host.faceSlots();
    const std::size_t points = mesh.points.size();
    UVR_CHECK(n < kNoCell / 4 && slots < kNoCell, "too many cells for 32-bit neighbour ids: " << n);
    if (n == 0 || points == 0) return std::vector<std::uint32_t>(slots, kNoTet);
    UVR_CHECK(!welded || welded->size() == points,
              "welded ids for " << welded->size() << " points, the mesh has " << points);
    // On threads of their own while the cells go up: the welded ids (unless given), and the
    // host's table (zeroed by its constructor, on one thread).
    std::future<std::vector<std::uint32_t>> welding;
    if (!welded)
        welding = std::async(std::launch::async, [&] { return coincidentPointIds(mesh.points); });
    auto hostTable =
        std::async(std::launch::async, [slots] { return std::vector<std::uint32_t>(slots); });
    // The cells, welded ids, per-vertex counts and offsets, and the table.
    cuda::DeviceArray<Tet> tets;
    cuda::DeviceArray<std::uint32_t> nativeCorners, canonIds, table;
    cuda::DeviceArray<unsigned long long> counts, offsets;
    cuda::DeviceArray<unsigned char> temp;
    tets.upload(mesh.tets, "the tetrahedra (GPU face neighbours)");
    nativeCorners.upload(mesh.nativeCorners, "the native cells (GPU face neighbours)");
    const std::vector<std::uint32_t> own = welded ? std::vector<std::uint32_t>() : welding.get();
    canonIds.upload(welded ? *welded : own, "the welded point ids (GPU face neighbours)");
    if (progress) progress(0.3);  // the fractions: seconds measured at 100M tetrahedra
    table.reserve(slots, "the neighbour table (GPU face neighbours)");
    counts.reserve(points + 1, "the faces per point (GPU face neighbours)");
    offsets.reserve(points + 1, "the face offsets (GPU face neighbours)");
    UVR_CUDA_CHECK(cudaMemset(table.data(), 0xff, slots * sizeof(std::uint32_t)));
    UVR_CUDA_CHECK(cudaMemset(counts.data(), 0, (points + 1) * sizeof(unsigned long long)));
    TetMeshView view = host;
    view.tets = tets.data(), view.nativeCorners = nativeCorners.data();
    view.points = nullptr, view.values = nullptr, view.tetCorners = nullptr;
    view.blockVertices = nullptr, view.blockVertexBase = nullptr;
    const std::uint32_t* canon = canonIds.data();
    {
        unsigned long long* faces = counts.data();
        cuda::forEachElement("face counts", n, [=] __device__(std::uint64_t c) {
            cuda::countFaces(c, view, canon, faces);
        });
    }
    cuda::withScratch(
        temp, "the scan's scratch (GPU face neighbours)", [&](void* s, std::size_t& b) {
            return cub::DeviceScan::ExclusiveSum(s, b, counts.data(), offsets.data(), points + 1);
        });
    std::vector<unsigned long long> hostOffsets(points + 1);
    offsets.download(hostOffsets.data(), points + 1);
    if (progress) progress(0.4);
    // Passes over ranges of vertices whose faces fit in the free memory.
    const std::uint64_t budget = std::max<std::uint64_t>(
        std::uint64_t(1) << 20, static_cast<std::uint64_t>(0.8 * double(cuda::freeDeviceMemory())) /
                                    sizeof(cuda::FaceEntry));
    const std::uint64_t most =
        std::min<std::uint64_t>(facesPerPass > 0 ? facesPerPass : budget, slots);
    cuda::DeviceArray<cuda::FaceEntry> entries;
    entries.reserve(most, "the faces (GPU face neighbours)");
    UVR_CUDA_CHECK(cudaMemcpy(counts.data(), offsets.data(),
                              (points + 1) * sizeof(unsigned long long),
                              cudaMemcpyDeviceToDevice));  // counts now serve as fill pointers
    for (std::size_t lo = 0; lo < points;) {
        // The longest run of vertices from lo whose faces fit (at least one vertex).
        const unsigned long long base = hostOffsets[lo];
        const auto end =
            std::upper_bound(hostOffsets.begin() + lo + 1, hostOffsets.end(), base + most);
        std::size_t hi = std::size_t(end - hostOffsets.begin()) - 1;
        hi = std::max(hi, lo + 1);
        UVR_CHECK(hostOffsets[hi] - base <= most,
                  "one vertex has more faces than the GPU holds: " << hostOffsets[hi] - base);
        const std::uint32_t first = static_cast<std::uint32_t>(lo),
                            last = static_cast<std::uint32_t>(hi);
        unsigned long long* fill = counts.data();
        const unsigned long long* offset = offsets.data();
        cuda::FaceEntry* faces = entries.data();
        std::uint32_t* neighbours = table.data();
        cuda::forEachElement("face scatter", n, [=] __device__(std::uint64_t c) {
            cuda::scatterFaces(c, view, canon, first, last, base, fill, faces);
        });
        cuda::forEachElement("face matches", hi - lo, [=] __device__(std::uint64_t v) {
            cuda::matchFaces(first + v, view, offset, base, faces, neighbours);
        });
        lo = hi;
        if (progress) {
            UVR_CUDA_CHECK(cudaDeviceSynchronize());
            progress(0.4 + 0.3 * double(lo) / double(points));
        }
    }
    std::vector<std::uint32_t> neighbors = hostTable.get();
    table.download(neighbors.data(), slots);
    if (progress) progress(1.0);
    return neighbors;
}

SeedGrids buildSeedGridsCuda(const TetMesh& mesh, const KdPartitions& kd, float tetsPerCell,
                             const FractionFn& progress) {
    const auto start = std::chrono::steady_clock::now();
    cuda::requireDevice("GPU seed grids");
    UVR_CHECK(tetsPerCell > 0.f, "seed grid density must be positive");
    SeedGrids out;
    out.grids = layoutPartitionGrids(kd, tetsPerCell, "seed grids", mesh.meanSplitTets());
    const std::uint64_t cells = gridCellCount(out.grids);
    out.seeds.assign(cells, kNoTet);
    if (kd.partitions.empty() || cells == 0) return out;
    // The kernels' layout of the cells (what offerSeedKeys reads) and the partitions.
    const cuda::DeviceCells device(mesh, false, "GPU seed grids");
    cuda::DeviceArray<std::uint32_t> kdCells, seeds;
    cuda::DeviceArray<KdPartition> partitions;
    cuda::DeviceArray<PartitionGrid> grids;
    cuda::DeviceArray<unsigned long long> best;
    kdCells.upload(kd.cells, "the partitions' cells (GPU seed grids)");
    partitions.upload(kd.partitions, "the partitions (GPU seed grids)");
    grids.upload(out.grids, "the seed grids' layout (GPU seed grids)");
    best.reserve(cells, "the seed keys (GPU seed grids)");
    UVR_CUDA_CHECK(cudaMemset(best.data(), 0xff, cells * sizeof(unsigned long long)));
    if (progress) progress(0.5);
    const TetLocator locator{device.view, {}, {}};
    const auto seedStart = std::chrono::steady_clock::now();
    cuda::seedKernel<<<static_cast<unsigned>(kd.partitions.size()), cuda::kBlock>>>(
        locator, partitions.data(), kdCells.data(), grids.data(), best.data());
    cuda::finishLaunch("seed keys", kd.partitions.size(), seedStart);
    seeds.reserve(cells, "the seeds (GPU seed grids)");
    {
        // Best keys to seeds (the key's low half; kNoTet where no cell offered one).
        const unsigned long long* keys = best.data();
        std::uint32_t* seed = seeds.data();
        cuda::forEachElement("seeds", cells, [=] __device__(std::uint64_t i) {
            seed[i] = keys[i] == ~0ull ? kNoTet : static_cast<std::uint32_t>(keys[i]);
        });
    }
    seeds.download(out.seeds.data(), cells);
    if (progress) progress(1.0);
    out.buildSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

MacroBuild buildMacroGridsCuda(const TetMesh& mesh, const KdPartitions& kd,
                               const std::vector<std::uint32_t>& neighbors, float tetsPerCell,
                               const FractionFn& progress) {
    const auto start = std::chrono::steady_clock::now();
    cuda::requireDevice("GPU macrocells");
    UVR_CHECK(tetsPerCell > 0.f, "macrocell density must be positive");
    const TetMeshView host = mesh.view();
    UVR_CHECK(neighbors.size() == host.faceSlots(), "macrocells need the face neighbours");
    MacroBuild out;
    out.macro.grids =
        layoutPartitionGrids(kd, tetsPerCell, "macrocell grids", mesh.meanSplitTets());
    const std::uint64_t cells = gridCellCount(out.macro.grids);
    const std::size_t parts = kd.partitions.size();
    out.macro.cells.assign(cells, MacroCell{});
    out.gradientSpread.assign(parts, 0.f);
    if (parts == 0 || cells == 0) return out;
    // Per cell: a face on the mesh's boundary.
    const std::int64_t n = static_cast<std::int64_t>(host.cellCount());
    std::vector<std::uint8_t> boundary(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static)
    for (std::int64_t c = 0; c < n; ++c) {
        bool b = false;
        const std::uint64_t faces = host.faceBase(std::uint64_t(c));
        for (int f = 0; f < kindFaces(host.kind(std::uint64_t(c))); ++f)
            b = b || neighbors[faces + f] == kNoTet;
        boundary[c] = b;
    }
    const bool anyNan =
        std::any_of(mesh.values.begin(), mesh.values.end(), [](float v) { return v != v; });
    // The kernels' layout of the cells, values for cell data and native cells, the partitions.
    const cuda::DeviceCells device(mesh, true, "GPU macrocells");
    const TetMeshView& view = device.view;
    cuda::DeviceArray<std::uint32_t> kdCells;
    cuda::DeviceArray<std::uint32_t> rangeKeys, gradientKeys, flags, partitionKeys;
    cuda::DeviceArray<std::uint8_t> boundaryFlags;
    cuda::DeviceArray<KdPartition> partitions;
    cuda::DeviceArray<PartitionGrid> grids;
    cuda::DeviceArray<MacroCell> macroCells;
    boundaryFlags.upload(boundary, "the boundary cells (GPU macrocells)");
    kdCells.upload(kd.cells, "the partitions' cells (GPU macrocells)");
    partitions.upload(kd.partitions, "the partitions (GPU macrocells)");
    grids.upload(out.macro.grids, "the macrocell grids' layout (GPU macrocells)");
    rangeKeys.reserve(2 * cells, "the macrocells' ranges (GPU macrocells)");
    gradientKeys.reserve(6 * cells, "the macrocells' gradients (GPU macrocells)");
    flags.reserve(cells, "the macrocells' flags (GPU macrocells)");
    partitionKeys.reserve(6 * parts, "the partitions' gradients (GPU macrocells)");
    cuda::clearKeys("macrocell range keys", rangeKeys.data(), 2 * cells, 2);
    cuda::clearKeys("macrocell gradient keys", gradientKeys.data(), 6 * cells, 6);
    cuda::clearKeys("partition gradient keys", partitionKeys.data(), 6 * parts, 6);
    UVR_CUDA_CHECK(cudaMemset(flags.data(), 0, cells * sizeof(std::uint32_t)));
    if (progress) progress(0.5);
    const auto macroStart = std::chrono::steady_clock::now();
    cuda::macroKernel<<<static_cast<unsigned>(parts), cuda::kBlock>>>(
        view, partitions.data(), kdCells.data(), grids.data(), boundaryFlags.data(), anyNan,
        rangeKeys.data(), gradientKeys.data(), flags.data(), partitionKeys.data());
    cuda::finishLaunch("macrocell keys", parts, macroStart);
    macroCells.reserve(cells, "the macrocells (GPU macrocells)");
    {
        const std::uint32_t *ranges = rangeKeys.data(), *gradients = gradientKeys.data(),
                            *cellFlags = flags.data();
        MacroCell* macro = macroCells.data();
        cuda::forEachElement("macrocells", cells, [=] __device__(std::uint64_t c) {
            cuda::macroCellOf(c, ranges, gradients, cellFlags, macro);
        });
    }
    macroCells.download(out.macro.cells.data(), cells);
    if (anyNan) {
        std::vector<std::uint32_t> hostFlags(cells);
        flags.download(hostFlags.data(), cells);
        out.macro.nanCells.resize(cells);
        for (std::uint64_t c = 0; c < cells; ++c)
            out.macro.nanCells[c] = (hostFlags[c] & cuda::kHasNan) ? 1 : 0;
    }
    // The partitions' gradient spreads (partitionGradientSpread's rule).
    std::vector<std::uint32_t> keys(6 * parts);
    partitionKeys.download(keys.data(), keys.size());
    for (std::size_t p = 0; p < parts; ++p) {
        if (view.cellCentered) {
            out.gradientSpread[p] = kd.partitions[p].cellCount > 0 ? INFINITY : 0.f;
            continue;
        }
        Bounds3f box;
        for (int a = 0; a < 3; ++a) {
            box.lo[a] = kdsplit::keyFloat(keys[6 * p + a]);
            box.hi[a] = kdsplit::keyFloat(keys[6 * p + 3 + a]);
        }
        out.gradientSpread[p] = box.empty() ? 0.f : length(box.hi - box.lo);
    }
    if (progress) progress(1.0);
    out.macro.buildSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

}  // namespace uvr
