// SPDX-License-Identifier: MIT
// Transfer-function mappings every integrator must honour (issue 15): a log scale (--log) baked
// into the value-linear table, checked against where the log map puts an opacity band, and the
// NaN colour, checked against the chord through a NaN region; with partition skipping on.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "on_each_device.h"
#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/mesh/field_select.h"
#include "uvr/render/camera.h"
#include "uvr/render/frame_setup.h"

namespace uvr {
namespace {

using testing::boxSpan;

/// A 12^3 grid of hexahedra over [0, 1]^3 with the field 1 + 999 x (1 to 1000, exactly linear),
/// prepared with small partitions so that skipping has partitions to skip.
PreparedMesh linearXGrid() {
    const Mesh m = testing::makeHexGrid(12, 0.f, 1.f, [](Vec3f p) { return 1.f + 999.f * p.x; });
    PrepareOptions options;
    options.kd.leafCells = 64;
    return prepareMesh(m, selectScalarField(m, {}), options);
}

/// TfMapping's frames render on every device (tests/on_each_device.h).
class TfMapping : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(TfMapping);

TEST_P(TfMapping, LogScaleMovesAnOpacityBandWhereLog10PutsIt) {
    const PreparedMesh pm = linearXGrid();
    ASSERT_GT(pm.kd->partitions.size(), 8u);
    RenderSettings s;
    s.width = 48, s.height = 32;
    s.tf = transferFunctionPreset("Grayscale");
    // Opacity 0.5 for normalised positions in [0.6, 0.9], 0 elsewhere.
    applyOpacitySpec(s.tf, "0:0,0.6:0,0.6:0.5,0.9:0.5,0.9:0,1:0");
    s.opacityUnit = 0.25f;
    for (const bool log : {false, true}) {
        s.tf.logScale = log;
        // The band in x: values 1 + 999 x with t = log10(v) / 3 (log) or (v - 1) / 999 in it.
        const double v0 = log ? std::pow(10.0, 1.8) : 1.0 + 999.0 * 0.6;
        const double v1 = log ? std::pow(10.0, 2.7) : 1.0 + 999.0 * 0.9;
        const double x0 = (v0 - 1.0) / 999.0, x1 = (v1 - 1.0) / 999.0;
        for (const RenderMethod method :
             {RenderMethod::Reference, RenderMethod::Partitions, RenderMethod::Exact}) {
            s.method = method;
            const RenderResult r = render(pm, s);
            EXPECT_GE(r.setup.tfTable.size(), log ? 1024u * 16 : 1024u) << "table entries";
            int inside = 0, outside = 0;
            for (int y = 0; y < s.height; ++y)
                for (int x = 0; x < s.width; ++x) {
                    const Ray ray = r.setup.rays.ray(x + 0.5f, y + 0.5f);
                    double t0, t1;
                    if (!boxSpan(pm.tets.bounds, ray, t0, t1)) continue;
                    const double xa = ray.org.x + t0 * ray.dir.x, xb = ray.org.x + t1 * ray.dir.x;
                    const double lo = std::min(xa, xb), hi = std::max(xa, xb);
                    const float alpha = r.image.pixels[y * s.width + x].w;
                    const std::string where = std::string(log ? "log" : "linear") + " method " +
                                              std::to_string(int(method)) + " pixel " +
                                              std::to_string(x) + "," + std::to_string(y);
                    if (lo > x0 + 0.02 && hi < x1 - 0.02) {
                        // Wholly in the band: the slab opacity of 0.5 per unit over the chord.
                        const double want =
                            testing::slabOpacity(0.5, t1 - t0, s.opacityUnit, s.opacityLaw);
                        EXPECT_NEAR(alpha, want, 0.02) << where;
                        ++inside;
                    } else if (hi < x0 - 0.02 || lo > x1 + 0.02) {
                        EXPECT_EQ(alpha, 0.f) << where;
                        ++outside;
                    }
                }
            EXPECT_GT(inside, 50) << log;
            EXPECT_GT(outside, 50) << log;
        }
    }
}

TEST(TfMappingSetup, LogScaleRangeFromZeroStartsWhereParaViewStartsIt) {
    const PreparedMesh pm = linearXGrid();
    RenderSettings s;
    s.width = s.height = 8;
    s.tf = transferFunctionPreset("Grayscale");
    s.tf.logScale = true;
    s.range = std::make_pair(0.f, 1000.f);  // ParaView: lo = min(hi / 10^4, 1) = 0.1
    FrameSetup f = makeFrameSetup(pm, s);
    EXPECT_FLOAT_EQ(f.rangeLo, 0.1f);
    ASSERT_FALSE(f.notes.empty());
    EXPECT_NE(f.notes[0].find("`range` [0, 1000] is not positive; mapping [0.1, 1000]"),
              std::string::npos)
        << f.notes[0];
    s.range = std::make_pair(-5.f, 0.f);
    try {
        makeFrameSetup(pm, s);
        ADD_FAILURE() << "a range with no positive value was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Argument);
        EXPECT_NE(std::string(e.what()).find("`log` needs positive values: `range` [-5, 0] has "
                                             "none; give `range` LO,HI with 0 < LO <= HI"),
                  std::string::npos)
            << e.what();
    }
}

/// A 12^3 grid of hexahedra over [0, 1]^3 whose field is x, NaN at vertices with x > 0.5: every
/// cell in x >= 0.5 has a NaN vertex, so the NaN region is the box [0.5, 1] x [0, 1]^2.
PreparedMesh halfNanGrid() {
    const Mesh m = testing::makeHexGrid(12, 0.f, 1.f, [](Vec3f p) {
        return p.x > 0.51f ? std::numeric_limits<float>::quiet_NaN() : p.x;
    });
    PrepareOptions options;
    options.kd.leafCells = 64;
    return prepareMesh(m, selectScalarField(m, {}), options);
}

TEST_P(TfMapping, NanValuesTakeTheNanColourInEveryIntegrator) {
    const PreparedMesh pm = halfNanGrid();
    ASSERT_FALSE(pm.partitionNan.empty());
    ASSERT_TRUE(pm.macro && !pm.macro->nanCells.empty());
    Bounds3f nanBox, finiteBox;
    nanBox.lo = Vec3f(0.5f, 0.f, 0.f), nanBox.hi = Vec3f(1.f, 1.f, 1.f);
    finiteBox.lo = Vec3f(0.f, 0.f, 0.f), finiteBox.hi = Vec3f(0.5f, 1.f, 1.f);
    RenderSettings s;
    s.width = 40, s.height = 30;
    s.camera = orbitCamera(resetCamera(pm.tets.bounds, 40.f / 30.f), 35.f, 20.f);
    s.opacityUnit = 0.25f;
    s.tf = transferFunctionPreset("Grayscale");
    struct Case {
        const char* what;
        float opacity;  ///< of finite values (constant)
        float nanOpacity;
    };
    // NaN visible over a transparent field; then NaN invisible (the default) in a visible one.
    for (const Case c : {Case{"NaN visible", 0.f, 0.5f}, Case{"NaN invisible", 0.3f, 0.f}}) {
        applyOpacitySpec(s.tf, "constant:" + std::to_string(c.opacity));
        s.tf.nanColor = Vec3f(1.f, 0.f, 0.f);
        s.tf.nanOpacity = c.nanOpacity;
        const Bounds3f& seen = c.nanOpacity > 0.f ? nanBox : finiteBox;
        const float alphaPerUnit = c.nanOpacity > 0.f ? c.nanOpacity : c.opacity;
        for (const RenderMethod method :
             {RenderMethod::Reference, RenderMethod::Partitions, RenderMethod::Exact}) {
            for (const bool pre : {true, false}) {
                if (method == RenderMethod::Exact && !pre) continue;
                s.method = method;
                s.preintegrated = pre;
                const RenderResult r = render(pm, s);
                // Sample-based methods place the NaN region's edge to within a step s1.
                const double tol = method == RenderMethod::Exact ? 2e-3 : 0.03;
                double worst = 0.0;
                int hit = 0;
                for (int y = 0; y < s.height; ++y)
                    for (int x = 0; x < s.width; ++x) {
                        const Ray ray = r.setup.rays.ray(x + 0.5f, y + 0.5f);
                        double t0, t1;
                        const double chord = boxSpan(seen, ray, t0, t1) ? t1 - t0 : 0.0;
                        const double want =
                            testing::slabOpacity(alphaPerUnit, chord, s.opacityUnit, s.opacityLaw);
                        const Vec4f px = r.image.pixels[y * s.width + x];
                        worst = std::max(worst, std::fabs(px.w - want));
                        if (c.nanOpacity > 0.f) {
                            // Premultiplied NaN colour: red only.
                            EXPECT_NEAR(px.x, px.w, 1e-4) << c.what;
                            EXPECT_EQ(px.y, 0.f) << c.what;
                        }
                        hit += chord > 0.05;
                    }
                EXPECT_GT(hit, 100) << c.what;
                EXPECT_LE(worst, tol) << c.what << " method " << int(method) << " pre " << pre;
                if (method == RenderMethod::Partitions && c.nanOpacity > 0.f) {
                    EXPECT_GT(r.stats.partitionsSkipped, 0u) << "the finite half is skipped";
                }
            }
        }
    }
}

}  // namespace
}  // namespace uvr
