// SPDX-License-Identifier: MIT
// The CUDA entry points of a build without CUDA (UVR_ENABLE_CUDA=OFF): no device, clear errors.
#include "uvr/core/error.h"
#include "uvr/core/setting_error.h"
#include "uvr/cuda/cuda_build.h"
#include "uvr/cuda/cuda_device.h"
#include "uvr/cuda/cuda_renderer.h"

namespace uvr {

namespace {

/// The error of every GPU builder here.
[[noreturn]] void noCudaBuilders() {
    throw SettingError("build_device", "cuda",
                       "this uvr was built without CUDA (configure with a CUDA compiler and "
                       "UVR_ENABLE_CUDA=ON)",
                       ErrorKind::Unsupported);
}

}  // namespace

struct CudaScene::Impl {};

bool cudaDeviceAvailable() {
    return false;
}

std::string cudaDeviceDescription() {
    return "none: this uvr was built without CUDA";
}

void startCudaWarmUp() {}

void finishCudaWarmUp() {}

CudaMemoryUse cudaMemoryUse() {
    return {};
}

void resetCudaMemoryPeak() {}

void setCudaMemoryLimit(std::uint64_t) {}

CudaScene::CudaScene(const PreparedMesh&, const FractionFn&) {
    throw SettingError("device", "cuda",
                       "this uvr was built without CUDA (configure with a CUDA compiler and "
                       "UVR_ENABLE_CUDA=ON)",
                       ErrorKind::Unsupported);
}

CudaScene::~CudaScene() = default;

RenderResult CudaScene::render(const RenderSettings&) {
    return {};
}

void CudaScene::updateValues() {}

void CudaScene::uploadGradients() {}

double CudaScene::valueUploadSeconds() const {
    return 0.0;
}

std::uint64_t CudaScene::geometryBytes() const {
    return 0;
}

double CudaScene::uploadSeconds() const {
    return 0.0;
}

LbvhResult buildLbvhCuda(const LbvhInput&) {
    noCudaBuilders();
}

KdTree buildKdTreeCuda(const TetMesh&, const KdBuildOptions&, const FractionFn&) {
    noCudaBuilders();
}

void sortCellKeysCuda(const std::uint64_t*, std::uint64_t, std::uint32_t*) {
    noCudaBuilders();
}

std::vector<std::uint32_t> buildTetNeighborsCuda(const TetMesh&, const FractionFn&, std::uint64_t,
                                                 const std::vector<std::uint32_t>*) {
    noCudaBuilders();
}

SeedGrids buildSeedGridsCuda(const TetMesh&, const KdPartitions&, float, const FractionFn&) {
    noCudaBuilders();
}

MacroBuild buildMacroGridsCuda(const TetMesh&, const KdPartitions&,
                               const std::vector<std::uint32_t>&, float, const FractionFn&) {
    noCudaBuilders();
}

}  // namespace uvr
