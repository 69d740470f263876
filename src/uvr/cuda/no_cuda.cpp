// SPDX-License-Identifier: MIT
// The CUDA entry points of a build without CUDA (UVR_ENABLE_CUDA=OFF): no device, clear errors.
#include "uvr/core/error.h"
#include "uvr/cuda/cuda_build.h"
#include "uvr/cuda/cuda_renderer.h"

namespace uvr {

struct CudaScene::Impl {};

bool cudaDeviceAvailable() {
    return false;
}

std::string cudaDeviceDescription() {
    return "none: this uvr was built without CUDA";
}

void startCudaWarmUp() {}

void finishCudaWarmUp() {}

CudaScene::CudaScene(const PreparedMesh&) {
    throwError(ErrorKind::Unsupported, "",
               "--device cuda: this uvr was built without CUDA (configure with a CUDA compiler "
               "and UVR_ENABLE_CUDA=ON)");
}

CudaScene::~CudaScene() = default;

RenderResult CudaScene::render(const RenderSettings&) {
    return {};
}

void CudaScene::updateValues() {}

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
    throwError(ErrorKind::Unsupported, "",
               "--build-device cuda: this uvr was built without CUDA (configure with a CUDA "
               "compiler and UVR_ENABLE_CUDA=ON)");
}

KdTree buildKdTreeCuda(const TetMesh&, const KdBuildOptions&) {
    throwError(ErrorKind::Unsupported, "",
               "--build-device cuda: this uvr was built without CUDA (configure with a CUDA "
               "compiler and UVR_ENABLE_CUDA=ON)");
}

}  // namespace uvr
