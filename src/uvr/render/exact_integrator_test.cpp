// SPDX-License-Identifier: MIT
// The exact integrator against closed forms (constant opacity, constant fields through convex and
// non-convex meshes), brute-force quadrature of its model (linear opacity, a transfer-function
// step crossing inside one tetrahedron) and the fixed-step reference at a tiny step.
#include "uvr/render/exact_integrator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "on_each_device.h"
#include "test_meshes.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/mesh/field_select.h"

namespace uvr {
namespace {

using testing::boxSpan;

/// Extinction per opacity unit of an opacity under a law, in double (opacity 1 under
/// transmittance: infinite).
double extinction(double alpha, OpacityLaw law) {
    return law == OpacityLaw::Attenuation ? alpha : -std::log1p(-alpha);
}

/// The model by brute force: a fine front-to-back composition over n steps of the marchers'
/// corrected opacity 1 - exp(-kappa h) under the table's law, in double (in float,
/// 1 - (1 - alpha)^1e-5 is mostly rounding); its error falls as 1 / n.
Vec4f fineComposite(const TfTableView& tf, float s0, float s1, double len, double unit, int n) {
    double acc[4] = {0.0, 0.0, 0.0, 0.0};
    const double h = len / n;
    for (int i = 0; i < n; ++i) {
        const float s = static_cast<float>(s0 + (s1 - s0) * (i + 0.5) / n);
        const Vec4f c = tf.sample(s);
        const double a = c.w >= 1.f && tf.law == OpacityLaw::Transmittance
                             ? 1.0
                             : -std::expm1(-h / unit * extinction(c.w, tf.law));
        const double w = (1.0 - acc[3]) * a;
        acc[0] += w * c.x, acc[1] += w * c.y, acc[2] += w * c.z, acc[3] += w;
    }
    return Vec4f(float(acc[0]), float(acc[1]), float(acc[2]), float(acc[3]));
}

void expectNear(Vec4f a, Vec4f b, float tol, const std::string& what) {
    EXPECT_NEAR(a.x, b.x, tol) << what;
    EXPECT_NEAR(a.y, b.y, tol) << what;
    EXPECT_NEAR(a.z, b.z, tol) << what;
    EXPECT_NEAR(a.w, b.w, tol) << what;
}

TEST(ExactIntegrator, ConstantOpacityIsTheClosedForm) {
    // alpha a per unit 0.5 over 1.7: 1 - (1 - a)^(1.7 / 0.5) under transmittance, 1 - exp(-a *
    // 1.7 / 0.5) under attenuation; the colour is c times that; in double and in float.
    for (const OpacityLaw law : {OpacityLaw::Attenuation, OpacityLaw::Transmittance})
        for (const double a : {0.0, 1e-6, 0.3, 0.999}) {
            const double want = law == OpacityLaw::Transmittance
                                    ? 1.0 - std::pow(1.0 - a, 1.7 / 0.5)
                                    : -std::expm1(-a * 1.7 / 0.5);
            const std::string what = std::string(opacityLawName(law)) + " " + std::to_string(a);
            Vec4f acc(0.f, 0.f, 0.f, 0.f);
            segment::compositePiece(Vec3f(0.2f, 0.4f, 0.8f), a, Vec3f(0.2f, 0.4f, 0.8f), a, 1.7,
                                    0.5, law, acc);
            EXPECT_NEAR(acc.w, want, 1e-6) << what;
            EXPECT_NEAR(acc.x, 0.2 * want, 1e-6) << what;
            EXPECT_NEAR(acc.z, 0.8 * want, 1e-6) << what;
            Vec4f fast(0.f, 0.f, 0.f, 0.f);
            segment::compositePieceFast(Vec3f(0.2f, 0.4f, 0.8f), float(a), Vec3f(0.2f, 0.4f, 0.8f),
                                        float(a), 1.7f, 0.5f, law, fast);
            EXPECT_NEAR(fast.w, want, 1e-6) << what;
            EXPECT_NEAR(fast.z, 0.8 * want, 1e-6) << what;
        }
    // Opacity 1 over an interval: under transmittance opaque at once, in the colour at its
    // start; under attenuation an extinction of 1 per unit (0.1 of a unit: 1 - e^-0.1).
    Vec4f acc(0.f, 0.f, 0.f, 0.f);
    segment::compositePiece(Vec3f(1.f, 0.f, 0.f), 1.0, Vec3f(0.f, 1.f, 0.f), 1.0, 0.1, 1.0,
                            OpacityLaw::Transmittance, acc);
    expectNear(acc, Vec4f(1.f, 0.f, 0.f, 1.f), 0.f, "opaque");
    for (const bool fast : {false, true}) {
        Vec4f one(0.f, 0.f, 0.f, 0.f);
        if (fast)
            segment::compositePieceFast(Vec3f(1.f, 0.f, 0.f), 1.f, Vec3f(1.f, 0.f, 0.f), 1.f, 0.1f,
                                        1.f, OpacityLaw::Attenuation, one);
        else
            segment::compositePiece(Vec3f(1.f, 0.f, 0.f), 1.0, Vec3f(1.f, 0.f, 0.f), 1.0, 0.1, 1.0,
                                    OpacityLaw::Attenuation, one);
        const double want = -std::expm1(-0.1);
        expectNear(one, Vec4f(float(want), 0.f, 0.f, float(want)), 1e-6f, "attenuation at 1");
    }
}

TEST(ExactIntegrator, LinearOpacityAndColourMatchBruteForce) {
    // A two-entry table: colour and opacity linear in the value, so one piece; the brute force
    // converges to the same integral.
    // Both laws, in double and in float (the renderers' pieces).
    const std::vector<Vec4f> entries{Vec4f(1.f, 0.f, 0.f, 0.05f), Vec4f(0.f, 0.f, 1.f, 0.95f)};
    for (const OpacityLaw law : {OpacityLaw::Attenuation, OpacityLaw::Transmittance}) {
        TfTableView tf{entries.data(), 2, 0.f, 1.f};
        tf.law = law;
        for (const auto& [s0, s1, len] : {std::tuple{0.f, 1.f, 2.0}, std::tuple{1.f, 0.f, 0.3},
                                          std::tuple{0.2f, 0.7f, 5.0}, std::tuple{0.5f, 0.5f, 1.0}})
            for (const bool fast : {false, true}) {
                Vec4f acc(0.f, 0.f, 0.f, 0.f);
                segment::integrate(tf, s0, s1, len, 0.4, acc, fast);
                const Vec4f want = fineComposite(tf, s0, s1, len, 0.4, 400000);
                expectNear(acc, want, fast ? 1e-4f : 2e-5f,
                           std::string(opacityLawName(law)) + (fast ? " fast" : "") + " segment " +
                               std::to_string(s0) + " -> " + std::to_string(s1));
            }
    }
    // An opacity reaching 1 at one end: finite optical depth under both laws (under
    // transmittance ln w is integrable at 0).
    const std::vector<Vec4f> toOne{Vec4f(1.f, 1.f, 1.f, 0.f), Vec4f(1.f, 1.f, 1.f, 1.f)};
    TfTableView tfOne{toOne.data(), 2, 0.f, 1.f};
    tfOne.law = OpacityLaw::Transmittance;
    Vec4f acc(0.f, 0.f, 0.f, 0.f);
    segment::integrate(tfOne, 0.f, 1.f, 0.2, 1.0, acc);
    // -integral_0^1 ln(1 - x) dx * 0.2 = 0.2: alpha = 1 - e^-0.2.
    EXPECT_NEAR(acc.w, 1.0 - std::exp(-0.2), 1e-6);
    // Attenuation: integral_0^1 x dx * 0.2 = 0.1.
    tfOne.law = OpacityLaw::Attenuation;
    acc = Vec4f(0.f, 0.f, 0.f, 0.f);
    segment::integrate(tfOne, 0.f, 1.f, 0.2, 1.0, acc);
    EXPECT_NEAR(acc.w, 1.0 - std::exp(-0.1), 1e-6);
}

TEST(ExactIntegrator, ASegmentEndingAtTheRangesTopIsNotMadeOpaqueByRounding) {
    // Issue 29: rays of disk_out_ref.ex2 ending on the hot wall (Temp at its maximum, opacity 1
    // there) turned opaque at once under the transmittance law in split cells, not in native
    // ones: with s1 the range's top in float, the table walk left a sliver of about 1e-16 of the
    // segment past the last entry, a piece of opacity 1 at both ends. The integral of -ln(1 - a)
    // is finite; the segment must read as the one ending a hair below the top, and as the
    // closed form, in double and in float.
    TransferFunction tf = transferFunctionPreset("grayscale");
    applyOpacitySpec(tf, "0:0,1:1");
    const float lo = 293.15f, hi = 913.15f;
    const std::vector<Vec4f> table = tf.bakeOverRange(1024, lo, hi);
    const std::vector<std::int32_t> breaks = tfTableBreaks(table.data(), 1024);
    for (const bool withBreaks : {false, true}) {
        TfTableView view{table.data(), 1024, lo, hi};
        view.law = OpacityLaw::Transmittance;
        if (withBreaks) view.breaks = breaks.data();
        for (const auto& [s0, len] : {std::pair{911.334595f, 0.00478162326},
                                      std::pair{902.846f, 0.023174}, std::pair{600.f, 0.5}})
            for (const bool fast : {false, true}) {
                const std::string what =
                    std::to_string(s0) + (fast ? " fast" : "") + (withBreaks ? " breaks" : "");
                Vec4f top(0.f, 0.f, 0.f, 0.5f), below(0.f, 0.f, 0.f, 0.5f);
                segment::integrate(view, s0, hi, len, 1.3249257802963257, top, fast);
                segment::integrate(view, s0, std::nextafter(hi, 0.f), len, 1.3249257802963257,
                                   below, fast);
                EXPECT_LT(top.w, 0.99f) << what;
                expectNear(top, below, 1e-5f, what);
                // The closed form: opacity a = (s - lo) / (hi - lo), linear along the segment
                // to 1, so w = 1 - a runs from w0 to 0 and the mean of -ln w is 1 - ln w0.
                const double w0 = 1.0 - (double(s0) - lo) / (double(hi) - lo);
                const double tau = len / 1.3249257802963257 * (1.0 - std::log(w0));
                EXPECT_NEAR(top.w, 0.5 - 0.5 * std::expm1(-tau), 1e-4) << what << " closed form";
            }
    }
}

TEST(ExactIntegrator, TransferFunctionStepInsideOneSegmentIsNotMissed) {
    // A narrow opacity band (0 outside [0.49, 0.51] of the range, 0.9 inside) crossed by one
    // segment: a point sample every 0.1 of the range misses it; the exact integral does not.
    TransferFunction tf = transferFunctionPreset("grayscale");
    applyOpacitySpec(tf, "0:0,0.4899:0,0.49:0.9,0.51:0.9,0.5101:0,1:0");
    const std::vector<Vec4f> table = tf.bake(1 << 16);
    const TfTableView view{table.data(), static_cast<int>(table.size()), 0.f, 1.f};
    Vec4f acc(0.f, 0.f, 0.f, 0.f);
    segment::integrate(view, 0.f, 1.f, 1.0, 1.0, acc);
    // 0.02 of the segment at alpha 0.9 per unit, plus the two 1e-4 ramps (about half each).
    const double inBand = 0.02 + 1e-4;
    EXPECT_NEAR(acc.w, -std::expm1(-0.9 * inBand), 2e-3);
    const Vec4f brute = fineComposite(view, 0.f, 1.f, 1.0, 1.0, 2000000);
    EXPECT_NEAR(acc.w, brute.w, 1e-4);
}

/// A grid of n^3 hexahedra over [lo, hi]^3 with the point field f, prepared for rendering.
PreparedMesh preparedGrid(int n, float lo, float hi, const std::function<float(Vec3f)>& f,
                          float jitter = 0.f) {
    const Mesh m = testing::makeHexGrid(n, lo, hi, f, jitter);
    return prepareMesh(m, selectScalarField(m, {}));
}

RenderSettings exactSettings(const Bounds3f& box, int size) {
    RenderSettings s;
    s.width = s.height = size;
    s.method = RenderMethod::Exact;
    s.camera = orbitCamera(resetCamera(box, 1.f), 33.f, 27.f);
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, "constant:0.2");
    s.opacityUnit = 0.5f;
    return s;
}

/// For a constant field under constant opacity 0.2 per unit 0.5 filling the boxes: the largest
/// difference of a pixel's alpha from 1 - exp(-kappa chord), kappa the extinction of 0.2 / 0.5
/// under the settings' law, the chord summed over the boxes; meetingAll receives the number of
/// pixels whose ray meets every box.
double worstChordError(const RenderResult& r, const RenderSettings& s,
                       const std::vector<Bounds3f>& boxes, int& meetingAll) {
    double worst = 0.0;
    meetingAll = 0;
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            const Ray ray = r.setup.rays.ray(x + 0.5f, y + 0.5f);
            double chord = 0.0;
            int met = 0;
            for (const Bounds3f& box : boxes) {
                double t0, t1;
                if (boxSpan(box, ray, t0, t1)) chord += t1 - t0, ++met;
            }
            meetingAll += met == int(boxes.size());
            const double want = -std::expm1(-extinction(0.2, s.opacityLaw) * chord / 0.5);
            worst = std::max(worst, double(std::fabs(r.image.at(x, y).w - want)));
        }
    return worst;
}

/// Frames of the exact integrator, on every device (tests/on_each_device.h).
class ExactFrame : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(ExactFrame);

TEST_P(ExactFrame, ConstantFieldThroughJitteredGridIsTheChordLength) {
    // Every pixel: alpha = 1 - exp(-kappa chord), the chord through the box; no sampling
    // band, no cracks between the 6 * 6^3 jittered tetrahedra.
    const Bounds3f box{Vec3f(0.f), Vec3f(1.f)};
    const PreparedMesh pm = preparedGrid(
        6, 0.f, 1.f, [](Vec3f) { return 1.f; }, 0.3f);
    const RenderSettings s = exactSettings(box, 48);
    const RenderResult r = render(pm, s);
    int covered = 0;
    const double worst = worstChordError(r, s, {box}, covered);
    EXPECT_GT(covered, 1000);
    EXPECT_LT(worst, 1e-4);
}

TEST_P(ExactFrame, ParallelRaysThroughTheEdgesOfASplitGridKeepTheirChord) {
    // A regular grid split into tetrahedra seen along +x in parallel projection: many rays pass
    // exactly through edges of the split (the faces' diagonals), where the walk's crossing is
    // degenerate and the ray is located again. Every ray crosses the whole unit chord.
    const Mesh m = testing::makeHexGrid(6, 0.f, 1.f, [](Vec3f) { return 1.f; });
    PrepareOptions options;
    options.cells.splitCells = true;
    const PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}), options);
    RenderSettings s = exactSettings(Bounds3f{Vec3f(0.f), Vec3f(1.f)}, 24);
    s.height = 16;
    Camera c;
    c.position = Vec3f(-2.f, 0.52f, 0.47f);
    c.focalPoint = Vec3f(0.5f, 0.52f, 0.47f);
    c.viewUp = Vec3f(0.f, 0.f, 1.f);
    c.parallelProjection = true;
    c.parallelScale = 0.2f;
    s.camera = c;
    const RenderResult r = render(pm, s);
    const double want = -std::expm1(-extinction(0.2, s.opacityLaw) / 0.5);
    int bad = 0;
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x)
            if (std::fabs(r.image.at(x, y).w - want) > 1e-4 && ++bad <= 5)
                ADD_FAILURE() << "pixel " << x << "," << y << ": alpha " << r.image.at(x, y).w
                              << ", want " << want << "; tetrahedra crossed "
                              << r.sampleCounts[std::size_t(y) * s.width + x];
    EXPECT_EQ(bad, 0);
}

TEST_P(ExactFrame, RaysLeavingANonConvexMeshAndReenteringKeepBothParts) {
    // Two unit cubes with a gap of 0.5 between them along x: rays through both integrate both.
    Mesh a = testing::makeHexGrid(3, 0.f, 1.f, [](Vec3f) { return 1.f; });
    testing::appendShifted(a, testing::makeHexGrid(3, 0.f, 1.f, [](Vec3f) { return 1.f; }),
                           Vec3f(1.5f, 0.f, 0.f));
    const PreparedMesh pm = prepareMesh(a, selectScalarField(a, {}));
    const Bounds3f boxA{Vec3f(0.f), Vec3f(1.f)}, boxB{Vec3f(1.5f, 0.f, 0.f), Vec3f(2.5f, 1.f, 1.f)};
    RenderSettings s = exactSettings(Bounds3f{Vec3f(0.f), Vec3f(2.5f, 1.f, 1.f)}, 48);
    s.camera = orbitCamera(resetCamera(Bounds3f{Vec3f(0.f), Vec3f(2.5f, 1.f, 1.f)}, 1.f), 70.f,
                           10.f);  // looking mostly along x, through both cubes
    const RenderResult r = render(pm, s);
    int both = 0;
    const double worst = worstChordError(r, s, {boxA, boxB}, both);
    EXPECT_GT(both, 100);
    EXPECT_LT(worst, 1e-4);
}

TEST_P(ExactFrame, LinearFieldMatchesTheReferenceAtATinyStep) {
    // A linear field under a ramp with two bands: the fixed-step reference converges to the
    // exact image as its step shrinks (its error falls about linearly with the step).
    const Bounds3f box{Vec3f(-1.f), Vec3f(1.f)};
    const PreparedMesh pm = preparedGrid(
        5, -1.f, 1.f, [](Vec3f p) { return p.x + 2.f * p.y - p.z; }, 0.25f);
    RenderSettings s = exactSettings(box, 32);
    applyOpacitySpec(s.tf, "0:0,0.3:0.6,0.35:0,0.6:0,0.7:0.8,0.8:0,1:0.2");
    const RenderResult e = render(pm, s);
    double errCoarse = 0.0, errFine = 0.0;
    for (const float factor : {1.f, 1.f / 32.f}) {
        RenderSettings ref = s;
        ref.method = RenderMethod::Reference;
        ref.step = defaultStep(pm.tets) * factor;
        ref.terminationAlpha = 1.f;
        const RenderResult r = render(pm, ref);
        double worst = 0.0;
        for (std::size_t i = 0; i < r.image.pixels.size(); ++i)
            for (int c = 0; c < 4; ++c) {
                const Vec4f a = r.image.pixels[i], b = e.image.pixels[i];
                const float av[4] = {a.x, a.y, a.z, a.w}, bv[4] = {b.x, b.y, b.z, b.w};
                worst = std::max(worst, double(std::fabs(av[c] - bv[c])));
            }
        (factor == 1.f ? errCoarse : errFine) = worst;
    }
    EXPECT_LT(errFine, 0.01) << "coarse " << errCoarse;
    EXPECT_LT(errFine, 0.25 * errCoarse);
}

}  // namespace
}  // namespace uvr
