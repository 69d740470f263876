// SPDX-License-Identifier: MIT
// The work estimate of a frame, its cap, and progress reports of CPU renders.
#include <gtest/gtest.h>

#include <omp.h>

#include <string>
#include <vector>

#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/render/frame_setup.h"
#include "uvr/tf/transfer_function.h"

namespace uvr {
namespace {

PreparedMesh unitCubes() {
    const Mesh m = testing::makeHexGrid(3, 0.f, 1.f);
    return prepareMesh(m, selectScalarField(m, {}));
}

TEST(FrameWork, EstimateIsPixelsTimesTheDiagonalOverTheStep) {
    const Bounds3f box{{0.f, 0.f, 0.f}, {3.f, 4.f, 12.f}};  // diagonal 13
    const FrameWork w = estimateFrameWork(box, 0.5f, 20, 10);
    EXPECT_DOUBLE_EQ(w.samplesPerRay, 26.0);
    EXPECT_DOUBLE_EQ(w.samples, 26.0 * 200);
    EXPECT_EQ(estimateFrameWork(Bounds3f{}, 0.5f, 20, 10).samples, 0.0);
}

TEST(FrameWork, AbsurdStepsAreRefusedNamingAStepThatIsAccepted) {
    const PreparedMesh mesh = unitCubes();  // diagonal sqrt(3)
    RenderSettings s;
    s.tf = transferFunctionPreset("viridis");
    s.width = s.height = 16;
    s.step = 1e-5f;  // 173,205 samples per ray
    Error e = testing::catchError([&] { (void)makeFrameSetup(mesh, s); });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_NE(std::string(e.what()).find(
                  "`sample_distance` 1e-05 would take up to 4.43e+07 samples (16x16 "
                  "pixels x 1.73e+05 per ray across the bounds' diagonal "
                  "1.73), more than the 100,000 samples per ray allowed: "
                  "use `sample_distance` 1.8e-05 or larger (the default here is "),
              std::string::npos)
        << e.what();
    s.step = 1.8e-5f;
    EXPECT_NO_THROW((void)makeFrameSetup(mesh, s));
    // 16384^2 pixels x 4330 samples per ray: more than 10^12 in all.
    s.width = s.height = 16384;
    s.step = 4e-4f;
    e = testing::catchError([&] { (void)makeFrameSetup(mesh, s); });
    EXPECT_NE(std::string(e.what()).find("more than the 10^12 samples per frame allowed: use "
                                         "`sample_distance` 0.00047 or larger"),
              std::string::npos)
        << e.what();
}

TEST(FrameWork, CpuRenderReportsIncreasingFractionsEndingWithOne) {
    const PreparedMesh mesh = unitCubes();
    RenderSettings s;
    s.method = RenderMethod::Partitions;
    s.tf = transferFunctionPreset("viridis");
    s.width = 61;
    s.height = 47;  // 8 x 6 tiles of 8x8
    std::vector<double> seen;
    s.progress = [&](double f) { seen.push_back(f); };
    const int threadsBefore = omp_get_max_threads();
    for (int threads : {1, 4}) {
        seen.clear();
        omp_set_num_threads(threads);
        (void)renderCpu(mesh, s);
        ASSERT_GE(seen.size(), 2u);
        EXPECT_GT(seen.front(), 0.0);
        for (std::size_t i = 1; i < seen.size(); ++i) EXPECT_GT(seen[i], seen[i - 1]);
        EXPECT_EQ(seen.back(), 1.0);
    }
    omp_set_num_threads(threadsBefore);
}

}  // namespace
}  // namespace uvr
