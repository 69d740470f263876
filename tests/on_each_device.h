// SPDX-License-Identifier: MIT
#pragma once

// The integrator suites on every device (issue 30, item 5; as Open VKL runs its tests): a suite
// whose fixture derives from OnEachDevice renders through render(), and UVR_ON_EACH_DEVICE runs
// each of its tests on the CPU and on CUDA ("Devices/Suite.Test/Cpu", ".../Cuda"). The CUDA case
// is skipped, saying why, where this uvr has no CUDA device (the build machine); a machine with
// a GPU runs it (README.md: --gtest_filter='Devices/*/Cuda').

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstring>
#include <ostream>
#include <string>

#include "uvr/cpu/cpu_renderer.h"
#include "uvr/cuda/cuda_renderer.h"

namespace uvr::testing {

/// Where a parameterised integrator test renders.
enum class TestDevice { Cpu, Cuda };

/// A frame of a prepared mesh on `device`: renderCpu, or the mesh uploaded (a CudaScene) and
/// rendered there.
inline RenderResult renderOn(TestDevice device, const PreparedMesh& mesh,
                             const RenderSettings& settings) {
    if (device == TestDevice::Cpu) return renderCpu(mesh, settings);
    CudaScene scene(mesh);
    return scene.render(settings);
}

/// The fixture of a suite that runs on every device.
class OnEachDevice : public ::testing::TestWithParam<TestDevice> {
protected:
    void SetUp() override {
        if (GetParam() == TestDevice::Cuda && !cudaDeviceAvailable())
            GTEST_SKIP() << "no CUDA device: " << cudaDeviceDescription();
    }
    /// The device this instance runs on.
    TestDevice device() const { return GetParam(); }
    /// A frame on this instance's device.
    RenderResult render(const PreparedMesh& mesh, const RenderSettings& settings) const {
        return renderOn(GetParam(), mesh, settings);
    }
};

/// Bit for bit the same pixels.
inline bool samePixels(const Image& a, const Image& b) {
    return a.pixels.size() == b.pixels.size() &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(Vec4f)) == 0;
}

/// The largest difference of two images' components.
inline float maxPixelDifference(const Image& a, const Image& b) {
    float d = 0.f;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        for (int c = 0; c < 4; ++c) d = std::fmax(d, std::fabs(a.pixels[i][c] - b.pixels[i][c]));
    return d;
}

/// How gtest prints the parameter ("cpu", "cuda") in test listings and failures.
inline void PrintTo(TestDevice device, std::ostream* os) {
    *os << (device == TestDevice::Cpu ? "cpu" : "cuda");
}

/// The name of an instance: "Cpu" or "Cuda".
inline std::string testDeviceName(const ::testing::TestParamInfo<TestDevice>& info) {
    return info.param == TestDevice::Cpu ? "Cpu" : "Cuda";
}

}  // namespace uvr::testing

/// Runs every TEST_P of `Suite` (a fixture deriving from OnEachDevice) on the CPU and on CUDA.
#define UVR_ON_EACH_DEVICE(Suite)                                                             \
    INSTANTIATE_TEST_SUITE_P(                                                                 \
        Devices, Suite,                                                                       \
        ::testing::Values(::uvr::testing::TestDevice::Cpu, ::uvr::testing::TestDevice::Cuda), \
        ::uvr::testing::testDeviceName)

/// Skips the test, saying why, where this uvr has no CUDA device.
#define UVR_REQUIRE_GPU()                                                         \
    do {                                                                          \
        if (!::uvr::cudaDeviceAvailable())                                        \
            GTEST_SKIP() << "no CUDA device: " << ::uvr::cudaDeviceDescription(); \
    } while (false)
