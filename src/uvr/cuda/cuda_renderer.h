// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "uvr/cuda/cuda_device.h"
#include "uvr/cuda/scene_arrays.h"
#include "uvr/render/frame_setup.h"

namespace uvr {

/// A prepared mesh resident on the GPU: geometry, BVH, neighbours and partitions are uploaded
/// once; each render uploads only the baked transfer function and per-partition shading, so
/// transfer-function changes never touch geometry. The PreparedMesh must outlive it.
class CudaScene {
public:
    /// Uploads the mesh; throws Error(Resource) naming the need and the free memory when it does
    /// not fit, Error(Unsupported) when uvr was built without CUDA or no device is present.
    /// `progress` hears the fraction of the bytes uploaded.
    explicit CudaScene(const PreparedMesh& mesh, const FractionFn& progress = {});
    ~CudaScene();
    CudaScene(const CudaScene&) = delete;
    CudaScene& operator=(const CudaScene&) = delete;

    /// Renders a frame on the GPU with the integrator settings.method names (same results as
    /// renderCpu up to floating-point rounding).
    RenderResult render(const RenderSettings& settings);

    /// Re-uploads what depends on the field's values after updateFieldValues gave the
    /// PreparedMesh new ones (a time step): the values, the partition records (their value
    /// ranges), gradient spreads, NaN flags and macrocells. Points, tetrahedra, neighbours, BVHs,
    /// k-d nodes, cell lists and seed grids stay on the device untouched; buffers of unchanged
    /// size are reused. Throws Error(Resource) when the GPU lacks memory.
    void updateValues();
    /// Uploads the prepared mesh's smooth gradients (computeSmoothGradients; gradient shading
    /// computes them when it first needs them), or frees them when it has none.
    void uploadGradients();
    /// Seconds the last updateValues took (0 before the first).
    double valueUploadSeconds() const;

    /// Bytes of device memory holding the mesh, BVH, neighbours and partitions.
    std::uint64_t geometryBytes() const;
    /// Seconds the upload took.
    double uploadSeconds() const;

private:
    /// Computes the per-partition shading of the frame's transfer function on the GPU (the
    /// shared shadePartition per partition) into the device buffer and result.setup.shading.
    void updateShading(RenderResult& result);

    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace uvr
