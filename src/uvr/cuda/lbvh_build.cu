// SPDX-License-Identifier: MIT
// The GPU's LBVH builder: memory, the radix sort and launches only; the per-node math is the
// shared UVR_HOST_DEVICE code of accel/lbvh.h (GUIDE.md §2), as in buildLbvhCpu.
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include <bit>

#include "uvr/core/error.h"
#include "uvr/cuda/cuda_check.h"
#include "uvr/cuda/cuda_build.h"
#include "uvr/cuda/cuda_renderer.h"

namespace uvr {

namespace cuda {
namespace {

/// The inputs every kernel reads.
struct LbvhDeviceInput {
    const Vec3f* points;
    const Tet* tets;
    const std::uint32_t* tetIds;  ///< null: primitive i is tetrahedron i
    const std::uint64_t* segmentBegin;
    const Bounds3f* segmentBounds;
    std::uint32_t segments;
    std::int64_t leafSize;

    __device__ Bounds3f primBounds(std::uint64_t prim) const {
        return tetBounds(points, tets[tetIds ? tetIds[prim] : prim]);
    }
    __device__ std::uint32_t segmentOf(std::uint64_t x) const {
        return lbvhSegmentOf(segmentBegin, segments, x);
    }
};

__device__ std::uint64_t globalThread() {
    return static_cast<std::uint64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
}

/// Morton keys of the primitives and their positions.
__global__ void keysKernel(LbvhDeviceInput in, std::uint64_t n, std::uint64_t* keys,
                           std::uint32_t* positions) {
    const std::uint64_t i = globalThread();
    if (i >= n) return;
    keys[i] = morton63(in.primBounds(i).center(), in.segmentBounds[in.segmentOf(i)]);
    positions[i] = static_cast<std::uint32_t>(i);
}

/// The segment of each primitive, in the current order.
__global__ void segmentKeysKernel(LbvhDeviceInput in, std::uint64_t n,
                                  const std::uint32_t* positions, std::uint32_t* segmentKeys) {
    const std::uint64_t k = globalThread();
    if (k >= n) return;
    segmentKeys[k] = in.segmentOf(positions[k]);
}

/// The Morton keys in the final order.
__global__ void sortedKeysKernel(LbvhDeviceInput in, std::uint64_t n, const std::uint32_t* order,
                                 std::uint64_t* keys) {
    const std::uint64_t k = globalThread();
    if (k >= n) return;
    keys[k] = morton63(in.primBounds(order[k]).center(), in.segmentBounds[in.segmentOf(k)]);
}

/// Inner node g (element g of segment s: begin[s] + i) of its segment's radix tree.
__device__ LbvhInner innerOf(const LbvhDeviceInput& in, const std::uint64_t* keys,
                             std::uint64_t g, std::uint32_t s) {
    const std::int64_t b = static_cast<std::int64_t>(in.segmentBegin[s]);
    return lbvhInnerNode(keys + b, static_cast<std::int64_t>(in.segmentBegin[s + 1]) - b,
                         static_cast<std::int64_t>(g) - b);
}

/// Step 2 of buildLbvhCpu: kept[g + 1] = inner node g has more than leafSize primitives.
__global__ void keptKernel(LbvhDeviceInput in, std::uint64_t n, const std::uint64_t* keys,
                           std::uint32_t* kept) {
    const std::uint64_t g = globalThread();
    if (g >= n) return;
    const std::uint32_t s = in.segmentOf(g);
    std::uint32_t k = 0;
    if (g + 1 < in.segmentBegin[s + 1]) {
        const LbvhInner r = innerOf(in, keys, g, s);
        k = r.last - r.first + 1 > in.leafSize;
    }
    kept[g + 1] = k;
}

/// Each segment's base node (its root), and the single leaf of a segment of few primitives.
__global__ void rootsKernel(LbvhDeviceInput in, const std::uint32_t* rank,
                            const std::uint32_t* occupiedBefore, const std::uint32_t* order,
                            std::uint32_t* roots, BvhNode* nodes) {
    const std::uint64_t s = globalThread();
    if (s >= in.segments) return;
    const std::uint64_t b = in.segmentBegin[s], count = in.segmentBegin[s + 1] - b;
    roots[s] = 2 * rank[b] + occupiedBefore[s];
    if (count > 0 && count <= static_cast<std::uint64_t>(in.leafSize))
        nodes[roots[s]] = lbvhLeaf(in.points, in.tets, in.tetIds, order, b, count);
}

/// Step 3 of buildLbvhCpu: kept inner nodes name their children.
__global__ void childrenKernel(LbvhDeviceInput in, std::uint64_t n, const std::uint64_t* keys,
                               const std::uint32_t* rank, const std::uint32_t* roots,
                               const std::uint32_t* order, std::uint32_t* innerSlot,
                               std::uint32_t* innerParent, BvhNode* nodes) {
    const std::uint64_t g = globalThread();
    if (g >= n || rank[g + 1] == rank[g]) return;
    const std::uint32_t s = in.segmentOf(g);
    const std::uint64_t b = in.segmentBegin[s];
    const LbvhInner r = innerOf(in, keys, g, s);
    const std::uint32_t slot = roots[s] + 2 * (rank[g] - rank[b]) + 1;
    if (g == b) innerSlot[g] = roots[s], innerParent[g] = kLbvhNone;
    const std::int64_t lo[2] = {r.first, r.split + 1}, hi[2] = {r.split, r.last};
    for (int side = 0; side < 2; ++side) {
        const std::int64_t count = hi[side] - lo[side] + 1;
        if (count > in.leafSize) {
            const std::uint64_t child = b + r.split + side;
            innerSlot[child] = slot + side;
            innerParent[child] = static_cast<std::uint32_t>(g);
        } else {
            nodes[slot + side] = lbvhLeaf(in.points, in.tets, in.tetIds, order, b + lo[side], count);
        }
    }
}

/// A node's box as another thread wrote it (through L2, not this SM's L1).
__device__ Bounds3f loadBox(const BvhNode* node) {
    const float* f = reinterpret_cast<const float*>(&node->box);
    Bounds3f b;
    b.lo = Vec3f(__ldcg(f + 0), __ldcg(f + 1), __ldcg(f + 2));
    b.hi = Vec3f(__ldcg(f + 3), __ldcg(f + 4), __ldcg(f + 5));
    return b;
}

/// Step 4 of buildLbvhCpu: from each leaf up, the second child to arrive at a node computes its
/// box.
__global__ void refitKernel(LbvhDeviceInput in, std::uint64_t n, const std::uint64_t* keys,
                            const std::uint32_t* rank, const std::uint32_t* roots,
                            const std::uint32_t* innerSlot, const std::uint32_t* innerParent,
                            unsigned* arrived, BvhNode* nodes) {
    const std::uint64_t g = globalThread();
    if (g >= n || rank[g + 1] == rank[g]) return;
    const std::uint32_t s = in.segmentOf(g);
    const std::uint64_t b = in.segmentBegin[s];
    const LbvhInner r = innerOf(in, keys, g, s);
    const int leafChildren =
        (r.split - r.first + 1 <= in.leafSize) + (r.last - r.split <= in.leafSize);
    for (int k = 0; k < leafChildren; ++k) {
        for (std::uint32_t p = static_cast<std::uint32_t>(g); p != kLbvhNone; p = innerParent[p]) {
            __threadfence();  // this subtree's boxes before the count
            if (atomicAdd(&arrived[p], 1u) == 0) break;  // the sibling's last thread goes on
            __threadfence();
            const std::uint32_t left = roots[s] + 2 * (rank[p] - rank[b]) + 1;
            BvhNode inner;
            inner.box = loadBox(nodes + left);
            inner.box.extend(loadBox(nodes + left + 1));
            inner.first = left;
            inner.count = 0;
            nodes[innerSlot[p]] = inner;
        }
    }
}

int blocksFor(std::uint64_t n, int block) {
    return static_cast<int>((n + block - 1) / block);
}

}  // namespace
}  // namespace cuda

LbvhResult buildLbvhCuda(const LbvhInput& input) {
    if (!cudaDeviceAvailable())
        throwError(ErrorKind::Unsupported, "", "GPU build: no CUDA device found");
    const LbvhPlan plan = planLbvh(input);
    const std::uint64_t n = input.primCount();
    const std::uint32_t segments = static_cast<std::uint32_t>(input.segmentBounds.size());
    LbvhResult out;
    out.roots.assign(segments, 0u);
    if (n == 0) return out;
    const TetMesh& mesh = *input.mesh;
    cuda::DeviceArray<Vec3f> points;
    cuda::DeviceArray<Tet> tets;
    cuda::DeviceArray<std::uint32_t> tetIds, occupiedBefore;
    cuda::DeviceArray<std::uint64_t> segmentBegin;
    cuda::DeviceArray<Bounds3f> segmentBounds;
    points.upload(mesh.points, "the mesh points (GPU build)");
    tets.upload(mesh.tets, "the tetrahedra (GPU build)");
    tetIds.upload(input.tetIds.data(), input.tetIds.size(), "the primitive list (GPU build)");
    segmentBegin.upload(input.segmentBegin, "the segment offsets (GPU build)");
    segmentBounds.upload(input.segmentBounds, "the segment bounds (GPU build)");
    occupiedBefore.upload(plan.occupiedBefore, "the segment counts (GPU build)");
    const cuda::LbvhDeviceInput in{points.data(),        tets.data(), tetIds.data(),
                                   segmentBegin.data(),  segmentBounds.data(), segments,
                                   input.leafSize};
    constexpr int kBlock = 256;
    const int grid = cuda::blocksFor(n, kBlock);
    // Step 1: the order of the primitives by (segment, Morton key, position): a stable radix sort
    // by key, then a stable one by segment (ties keep their order, as the CPU's sort of
    // (key, position) pairs within each segment does).
    cuda::DeviceArray<std::uint32_t> positions[2];
    positions[0].reserve(n, "the primitive order (GPU build)");
    positions[1].reserve(n, "the sorted primitive order (GPU build)");
    cub::DoubleBuffer<std::uint32_t> positionBuffer(positions[0].data(), positions[1].data());
    auto sort = [&](auto& keyBuffer, int endBit) {
        std::size_t tempBytes = 0;
        UVR_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, tempBytes, keyBuffer,
                                                       positionBuffer, n, 0, endBit));
        cuda::DeviceArray<unsigned char> temp;
        temp.reserve(tempBytes, "the radix sort's scratch (GPU build)");
        UVR_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(temp.data(), tempBytes, keyBuffer,
                                                       positionBuffer, n, 0, endBit));
    };
    cuda::DeviceArray<std::uint64_t> keys[2];
    keys[0].reserve(n, "the Morton keys (GPU build)");
    keys[1].reserve(n, "the sorted Morton keys (GPU build)");
    cuda::keysKernel<<<grid, kBlock>>>(in, n, keys[0].data(), positions[0].data());
    UVR_CUDA_CHECK(cudaGetLastError());
    cub::DoubleBuffer<std::uint64_t> keyBuffer(keys[0].data(), keys[1].data());
    sort(keyBuffer, 63);
    if (segments > 1) {
        cuda::DeviceArray<std::uint32_t> segmentKeys[2];
        segmentKeys[0].reserve(n, "the segment keys (GPU build)");
        segmentKeys[1].reserve(n, "the sorted segment keys (GPU build)");
        cuda::segmentKeysKernel<<<grid, kBlock>>>(in, n, positionBuffer.Current(),
                                                  segmentKeys[0].data());
        UVR_CUDA_CHECK(cudaGetLastError());
        cub::DoubleBuffer<std::uint32_t> segmentBuffer(segmentKeys[0].data(),
                                                       segmentKeys[1].data());
        sort(segmentBuffer, std::bit_width(segments - 1));
    }
    cuda::DeviceArray<std::uint32_t>& order = positions[positionBuffer.selector];
    positions[1 - positionBuffer.selector].clear();
    cuda::DeviceArray<std::uint64_t>& sortedKeys = keys[keyBuffer.selector];
    keys[1 - keyBuffer.selector].clear();
    cuda::sortedKeysKernel<<<grid, kBlock>>>(in, n, order.data(), sortedKeys.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    // Step 2: kept inner nodes and their ranks (an exclusive scan), the node count and roots.
    cuda::DeviceArray<std::uint32_t> kept, rank, roots;
    kept.reserve(n + 1, "the kept-node flags (GPU build)");
    rank.reserve(n + 1, "the node ranks (GPU build)");
    UVR_CUDA_CHECK(cudaMemset(kept.data(), 0, sizeof(std::uint32_t)));
    cuda::keptKernel<<<grid, kBlock>>>(in, n, sortedKeys.data(), kept.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    {
        std::size_t tempBytes = 0;
        UVR_CUDA_CHECK(cub::DeviceScan::InclusiveSum(nullptr, tempBytes, kept.data(), rank.data(),
                                                     n + 1));
        cuda::DeviceArray<unsigned char> temp;
        temp.reserve(tempBytes, "the scan's scratch (GPU build)");
        UVR_CUDA_CHECK(cub::DeviceScan::InclusiveSum(temp.data(), tempBytes, kept.data(),
                                                     rank.data(), n + 1));
    }
    kept.clear();
    std::uint32_t keptCount = 0;
    UVR_CUDA_CHECK(cudaMemcpy(&keptCount, rank.data() + n, sizeof keptCount,
                              cudaMemcpyDeviceToHost));
    const std::uint64_t nodeCount = 2 * std::uint64_t(keptCount) + plan.occupiedBefore.back();
    cuda::DeviceArray<BvhNode> nodes;
    nodes.reserve(nodeCount, "the BVH nodes (GPU build)");
    roots.reserve(segments, "the segment roots (GPU build)");
    cuda::rootsKernel<<<cuda::blocksFor(segments, kBlock), kBlock>>>(
        in, rank.data(), occupiedBefore.data(), order.data(), roots.data(), nodes.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    // Steps 3 and 4: children, then the refit from the leaves up.
    cuda::DeviceArray<std::uint32_t> innerSlot, innerParent;
    cuda::DeviceArray<unsigned> arrived;
    innerSlot.reserve(n, "the inner node slots (GPU build)");
    innerParent.reserve(n, "the inner node parents (GPU build)");
    cuda::childrenKernel<<<grid, kBlock>>>(in, n, sortedKeys.data(), rank.data(), roots.data(),
                                           order.data(), innerSlot.data(), innerParent.data(),
                                           nodes.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    arrived.reserve(n, "the refit counters (GPU build)");
    UVR_CUDA_CHECK(cudaMemset(arrived.data(), 0, n * sizeof(unsigned)));
    cuda::refitKernel<<<grid, kBlock>>>(in, n, sortedKeys.data(), rank.data(), roots.data(),
                                        innerSlot.data(), innerParent.data(), arrived.data(),
                                        nodes.data());
    UVR_CUDA_CHECK(cudaGetLastError());
    UVR_CUDA_CHECK(cudaDeviceSynchronize());
    out.nodes.resize(nodeCount);
    out.order.resize(n);
    nodes.download(out.nodes.data(), nodeCount);
    order.download(out.order.data(), n);
    roots.download(out.roots.data(), segments);
    return out;
}

}  // namespace uvr
