// SPDX-License-Identifier: MIT
#include "uvr/facade/frame_report.h"

#include <gmock/gmock.h>

#include <algorithm>

#include "test_meshes.h"

namespace uvr {
namespace {

Mesh scaledGrid(float scale) {
    Mesh m = testing::jitteredHexGrid(8);
    for (Vec3f& p : m.points) p = p * scale;
    return m;
}

RenderSettings smallFrame(const Mesh& m, RenderMethod method) {
    RenderSettings s;
    s.width = 48;
    s.height = 32;
    s.method = method;
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, "0:0,1:0.5");
    s.camera = orbitCamera(resetCamera(m.bounds(), 48.f / 32.f), 25.f, 15.f);
    return s;
}

Renderer cpuRenderer(const Mesh& m) {
    RendererOptions o;
    o.device = Device::Cpu;
    o.leafCells = 32;
    return Renderer(m, selectScalarField(m, {}), o);
}

TEST(FrameReport, SaysWhatTheFrameAndThePreparedMeshHold) {
    const Mesh m = scaledGrid(1.f);
    Renderer r = cpuRenderer(m);
    const RenderSettings s = smallFrame(m, RenderMethod::Partitions);
    const RenderResult res = r.render(s);
    const nlohmann::json j = frameReport(r, s, res);
    EXPECT_EQ(j["method"], "adaptive");
    EXPECT_FALSE(j.contains("method_reason"));  // asked for by name
    EXPECT_EQ(j["device"], "cpu");
    EXPECT_EQ(j["sampling"], "preintegrated");
    EXPECT_EQ(j["step_rule"], "error");
    EXPECT_EQ(j["samples"].get<std::uint64_t>(), res.stats.samples);
    EXPECT_GT(res.stats.samples, 0u);
    EXPECT_DOUBLE_EQ(j["mean_samples_per_pixel"].get<double>(),
                     double(res.stats.samples) / (48 * 32));
    EXPECT_EQ(j["max_samples_per_pixel"].get<std::uint32_t>(),
              *std::max_element(res.sampleCounts.begin(), res.sampleCounts.end()));
    EXPECT_EQ(j["rays"].get<std::uint64_t>(), 48u * 32u);
    EXPECT_EQ(j["image"]["width"], 48);
    EXPECT_EQ(j["image"]["height"], 32);
    EXPECT_EQ(j["partitions"]["count"].get<std::size_t>(), r.prepared().kd->partitions.size());
    EXPECT_LE(j["partitions"]["cells_min"].get<std::uint32_t>(),
              j["partitions"]["cells_median"].get<std::uint32_t>());
    EXPECT_LE(j["partitions"]["cells_median"].get<std::uint32_t>(),
              j["partitions"]["cells_max"].get<std::uint32_t>());
    EXPECT_EQ(j["partitions"]["leaf_cells"].get<std::uint32_t>(), r.prepared().kd->leafCells);
    EXPECT_EQ(j["mesh"]["hexahedra"].get<std::uint64_t>(), 8u * 8u * 8u);
    EXPECT_TRUE(j["prepare_seconds"].contains("partitions"));
    EXPECT_EQ(j["empty_frame"], "");
    EXPECT_TRUE(j["notes"].is_array());
}

TEST(FrameReport, AutoSaysWhatItPickedAndWhyAndExactHasNoSampling) {
    const Mesh m = scaledGrid(1.f);
    Renderer r = cpuRenderer(m);
    RenderSettings s = smallFrame(m, RenderMethod::Auto);
    nlohmann::json j = frameReport(r, s, r.render(s));
    EXPECT_EQ(j["method_asked"], "auto");
    const RenderResult picked = r.render(s);
    EXPECT_EQ(j["method"], methodName(picked.setup.method.method));
    EXPECT_EQ(j["method_reason"], picked.setup.method.reason);
    EXPECT_FALSE(picked.setup.method.reason.empty());
    s.method = RenderMethod::Exact;
    j = frameReport(r, s, r.render(s));
    EXPECT_EQ(j["method"], "exact");
    EXPECT_FALSE(j.contains("method_reason"));
    EXPECT_FALSE(j.contains("sampling"));
}

TEST(FrameReport, LengthsAndPositionsAreInTheFilesUnits) {
    // The same grid 2^30 times larger renders in a scaled frame (kFrameScaleExponent), to the
    // same samples; its report's lengths and positions are 2^30 times larger.
    const float k = 1073741824.f;
    const Mesh small = scaledGrid(1.f), large = scaledGrid(k);
    Renderer a = cpuRenderer(small), b = cpuRenderer(large);
    ASSERT_EQ(a.prepared().tets.frame.scale, 1.0);
    ASSERT_LT(b.prepared().tets.frame.scale, 1.0 / k);
    const RenderSettings sa = smallFrame(small, RenderMethod::Partitions);
    const RenderSettings sb = smallFrame(large, RenderMethod::Partitions);
    const RenderResult ra = a.render(sa), rb = b.render(sb);
    EXPECT_EQ(ra.stats.samples, rb.stats.samples);
    const nlohmann::json ja = frameReport(a, sa, ra), jb = frameReport(b, sb, rb);
    for (const char* key : {"sample_distance", "max_sample_distance", "opacity_unit"})
        EXPECT_FLOAT_EQ(jb[key].get<float>(), ja[key].get<float>() * k) << key;
    for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(jb["camera"]["position"][i].get<double>(),
                    ja["camera"]["position"][i].get<double>() * k, 1e-5 * k)
            << i;
}

TEST(FrameReport, AnEmptyFrameSaysWhy) {
    const Mesh m = scaledGrid(1.f);
    Renderer r = cpuRenderer(m);
    RenderSettings s = smallFrame(m, RenderMethod::Reference);
    applyOpacitySpec(s.tf, "constant:0");
    const nlohmann::json j = frameReport(r, s, r.render(s));
    EXPECT_NE(j["empty_frame"].get<std::string>(), "");
}

}  // namespace
}  // namespace uvr
