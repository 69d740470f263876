// SPDX-License-Identifier: MIT
// The GPU's LBVH builder: memory, the radix sort and launches only; the per-node math is the
// shared UVR_HOST_DEVICE code of accel/lbvh.h (GUIDE.md §2), as in buildLbvhCpu.
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include <bit>

#include "uvr/core/error.h"
#include "uvr/cuda/cuda_build.h"
#include "uvr/cuda/cuda_check.h"
#include "uvr/cuda/cuda_renderer.h"
#include "uvr/cuda/launch.cuh"

namespace uvr {

namespace cuda {
namespace {

/// Step 4 of buildLbvhCpu: the refit, counting arrivals atomically and reading boxes other
/// threads wrote through L2 (not this SM's L1).
__device__ void refitNode(const LbvhBuildView& v, std::uint64_t g, unsigned* arrived) {
    if (!v.kept(static_cast<std::int64_t>(g))) return;
    auto firstArrival = [arrived](std::uint32_t p) {
        __threadfence();  // this subtree's boxes before the count
        const bool first = atomicAdd(&arrived[p], 1u) == 0;
        __threadfence();
        return first;
    };
    auto loadBox = [](const BvhNode* node) {
        const float* f = reinterpret_cast<const float*>(&node->box);
        Bounds3f b;
        b.lo = Vec3f(__ldcg(f + 0), __ldcg(f + 1), __ldcg(f + 2));
        b.hi = Vec3f(__ldcg(f + 3), __ldcg(f + 4), __ldcg(f + 5));
        return b;
    };
    v.refitFrom(static_cast<std::int64_t>(g), firstArrival, loadBox);
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
    cuda::DeviceArray<std::uint32_t> tetIds, occupiedBefore, nativeCorners;
    cuda::DeviceArray<std::uint64_t> segmentBegin;
    cuda::DeviceArray<Bounds3f> segmentBounds;
    points.upload(mesh.points, "the mesh points (GPU build)");
    tets.upload(mesh.tets, "the tetrahedra (GPU build)");
    nativeCorners.upload(mesh.nativeCorners, "the native cells (GPU build)");
    tetIds.upload(input.tetIds.data(), input.tetIds.size(), "the primitive list (GPU build)");
    segmentBegin.upload(input.segmentBegin, "the segment offsets (GPU build)");
    segmentBounds.upload(input.segmentBounds, "the segment bounds (GPU build)");
    occupiedBefore.upload(plan.occupiedBefore, "the segment counts (GPU build)");
    LbvhBuildView v;  // device pointers; the per-element work of every step
    v.mesh = mesh.view();
    v.mesh.points = points.data();
    v.mesh.tets = tets.data();
    v.mesh.nativeCorners = nativeCorners.data();
    v.mesh.values = nullptr;
    v.tetIds = tetIds.data();
    v.segmentBegin = segmentBegin.data();
    v.segmentBounds = segmentBounds.data();
    v.segments = segments;
    v.leafSize = input.leafSize;
    v.occupiedBefore = occupiedBefore.data();
    // Step 1: the order of the primitives by (segment, Morton key, position): a stable radix sort
    // by key, then a stable one by segment (ties keep their order, as the CPU's sort of
    // (key, position) pairs within each segment does).
    cuda::DeviceArray<std::uint32_t> positions[2];
    positions[0].reserve(n, "the primitive order (GPU build)");
    positions[1].reserve(n, "the sorted primitive order (GPU build)");
    cub::DoubleBuffer<std::uint32_t> positionBuffer(positions[0].data(), positions[1].data());
    cuda::DeviceArray<unsigned char> temp;
    auto sort = [&](auto& keyBuffer, int endBit) {
        cuda::withScratch(temp, "the radix sort's scratch (GPU build)",
                          [&](void* scratch, std::size_t& bytes) {
                              return cub::DeviceRadixSort::SortPairs(scratch, bytes, keyBuffer,
                                                                     positionBuffer, n, 0, endBit);
                          });
    };
    cuda::DeviceArray<std::uint64_t> keys[2];
    keys[0].reserve(n, "the Morton keys (GPU build)");
    keys[1].reserve(n, "the sorted Morton keys (GPU build)");
    // The primitives' Morton keys, and their positions.
    {
        std::uint64_t* k = keys[0].data();
        std::uint32_t* p = positions[0].data();
        cuda::forEachElement("lbvh keys", n, [=] __device__(std::uint64_t i) {
            k[i] = v.mortonKey(i, v.segmentOf(i));
            p[i] = static_cast<std::uint32_t>(i);
        });
    }
    cub::DoubleBuffer<std::uint64_t> keyBuffer(keys[0].data(), keys[1].data());
    sort(keyBuffer, 63);
    if (segments > 1) {
        cuda::DeviceArray<std::uint32_t> segmentKeys[2];
        segmentKeys[0].reserve(n, "the segment keys (GPU build)");
        segmentKeys[1].reserve(n, "the sorted segment keys (GPU build)");
        // The segment of each primitive, in the current order.
        const std::uint32_t* p = positionBuffer.Current();
        std::uint32_t* k = segmentKeys[0].data();
        cuda::forEachElement("lbvh segment keys", n,
                             [=] __device__(std::uint64_t i) { k[i] = v.segmentOf(p[i]); });
        cub::DoubleBuffer<std::uint32_t> segmentBuffer(segmentKeys[0].data(),
                                                       segmentKeys[1].data());
        sort(segmentBuffer, std::bit_width(segments - 1));
    }
    cuda::DeviceArray<std::uint32_t>& order = positions[positionBuffer.selector];
    positions[1 - positionBuffer.selector].clear();
    cuda::DeviceArray<std::uint64_t>& sortedKeys = keys[keyBuffer.selector];
    keys[1 - keyBuffer.selector].clear();
    v.order = order.data();
    // The Morton keys in the final order (v.order).
    {
        std::uint64_t* k = sortedKeys.data();
        cuda::forEachElement("lbvh sorted keys", n, [=] __device__(std::uint64_t i) {
            k[i] = v.mortonKey(v.order[i], v.segmentOf(i));
        });
    }
    // Steps 2-4 (LbvhBuildView): kept inner nodes, their ranks (an exclusive scan: kept[0] = 0)
    // and the roots; children; the refit.
    cuda::DeviceArray<std::uint32_t> kept, rank, roots, innerSlot, innerParent;
    cuda::DeviceArray<unsigned> arrived;
    kept.reserve(n + 1, "the kept-node flags (GPU build)");
    rank.reserve(n + 1, "the node ranks (GPU build)");
    roots.reserve(segments, "the segment roots (GPU build)");
    innerSlot.reserve(n, "the inner node slots (GPU build)");
    innerParent.reserve(n, "the inner node parents (GPU build)");
    v.keys = sortedKeys.data();
    v.rank = rank.data();
    v.roots = roots.data();
    v.innerSlot = innerSlot.data();
    v.innerParent = innerParent.data();
    UVR_CUDA_CHECK(cudaMemset(kept.data(), 0, sizeof(std::uint32_t)));
    // Step 2 of buildLbvhCpu: kept[g + 1] = element g is a kept inner node.
    {
        std::uint32_t* k = kept.data();
        cuda::forEachElement("lbvh kept nodes", n, [=] __device__(std::uint64_t g) {
            k[g + 1] = v.keepsInner(static_cast<std::int64_t>(g));
        });
    }
    cuda::withScratch(
        temp, "the scan's scratch (GPU build)", [&](void* scratch, std::size_t& bytes) {
            return cub::DeviceScan::InclusiveSum(scratch, bytes, kept.data(), rank.data(), n + 1);
        });
    kept.clear();
    std::uint32_t keptCount = 0;
    UVR_CUDA_CHECK(
        cudaMemcpy(&keptCount, rank.data() + n, sizeof keptCount, cudaMemcpyDeviceToHost));
    const std::uint64_t nodeCount = 2 * std::uint64_t(keptCount) + plan.occupiedBefore.back();
    cuda::DeviceArray<BvhNode> nodes;
    nodes.reserve(nodeCount, "the BVH nodes (GPU build)");
    v.nodes = nodes.data();
    // Each segment's root (and single leaf); step 3 of buildLbvhCpu: kept inner nodes name
    // their children.
    cuda::forEachElement("lbvh roots", segments, [=] __device__(std::uint64_t s) {
        v.placeRoot(static_cast<std::uint32_t>(s));
    });
    cuda::forEachElement("lbvh children", n, [=] __device__(std::uint64_t g) {
        if (v.kept(static_cast<std::int64_t>(g))) v.nameChildren(static_cast<std::int64_t>(g));
    });
    arrived.reserve(n, "the refit counters (GPU build)");
    UVR_CUDA_CHECK(cudaMemset(arrived.data(), 0, n * sizeof(unsigned)));
    {
        unsigned* a = arrived.data();
        cuda::forEachElement("lbvh refit", n,
                             [=] __device__(std::uint64_t g) { cuda::refitNode(v, g, a); });
    }
    UVR_CUDA_CHECK(cudaDeviceSynchronize());
    out.nodes.resize(nodeCount);
    out.order.resize(n);
    nodes.download(out.nodes.data(), nodeCount);
    order.download(out.order.data(), n);
    roots.download(out.roots.data(), segments);
    return out;
}

}  // namespace uvr
