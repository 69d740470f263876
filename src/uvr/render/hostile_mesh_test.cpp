// SPDX-License-Identifier: MIT
// Numerically hostile meshes and cameras through every CPU integrator (reference; partitions with
// and without adaptive steps): degenerate and inverted cells, coincident points, cells from 1e-6
// to 1e6, a camera inside the volume, rays running exactly along k-d split planes, faces and
// edges. The oracle: a constant field under a constant transfer function has an exact image. Every
// integrator composites the reference grid points t = k * s1 inside the mesh's box (the partition
// integrator's steps add up to the same distance), so a pixel's opacity is the slab opacity of a
// over n s1 for the n grid points in the ray's span of the (convex) mesh: one sample lost in a
// crack between cells (the start of a streak) or a NaN fails it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "on_each_device.h"
#include "test_meshes.h"
#include "test_support.h"
#include "uvr/accel/lbvh.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/render/adaptive_marcher.h"
#include "uvr/render/reference_marcher.h"

namespace uvr {
namespace {

constexpr float kAlpha = 0.2f;            // TF opacity per opacity unit
const Vec3f kColor(0.2f, 0.6f, 1.f);      // TF colour
constexpr float kColorTolerance = 1e-3f;  // straight colour of a pixel vs the TF colour
constexpr float kAlphaTolerance = 2e-4f;  // beyond the one-sample band of the oracle
constexpr std::uint32_t kCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                         {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

/// Grid coordinates along one axis.
using Planes = std::vector<float>;

/// Planes lo, lo + h, ..., hi (n cells).
Planes uniformPlanes(int n, float lo, float hi) {
    Planes p;
    for (int i = 0; i <= n; ++i) p.push_back(lo + (hi - lo) * i / n);
    return p;
}

/// Point index of grid corner (i, j, k) in a grid with n planes per axis.
std::uint32_t gridId(std::size_t n, std::size_t i, std::size_t j, std::size_t k) {
    return static_cast<std::uint32_t>((k * n + j) * n + i);
}

/// The grid points on the given planes (the same along x, y, z) appended to m, and cell(c) called
/// with the 8 corner ids (VTK hexahedron order) of every grid cell.
template <class Cell>
void gridOnPlanes(Mesh& m, const Planes& planes, Cell&& cell) {
    const std::size_t n = planes.size();
    for (std::size_t k = 0; k < n; ++k)
        for (std::size_t j = 0; j < n; ++j)
            for (std::size_t i = 0; i < n; ++i)
                m.points.emplace_back(planes[i], planes[j], planes[k]);
    for (std::size_t k = 0; k + 1 < n; ++k)
        for (std::size_t j = 0; j + 1 < n; ++j)
            for (std::size_t i = 0; i + 1 < n; ++i) {
                std::uint32_t c[8];
                for (int v = 0; v < 8; ++v)
                    c[v] = gridId(n, i + kCorner[v][0], j + kCorner[v][1], k + kCorner[v][2]);
                cell(c);
            }
}

/// A grid of hexahedra on the given planes (the same along x, y, z), split by uvr's loader; the
/// point field "f" is 1 everywhere.
Mesh hexGridOnPlanes(const Planes& planes) {
    Mesh m;
    gridOnPlanes(m, planes, [&](const auto& c) { m.addCell(CellType::Hexahedron, c); });
    m.fields.push_back({"f", Association::Point, 1, std::vector<float>(m.points.size(), 1.f)});
    return m;
}

/// The six Kuhn tetrahedra of a grid cube (corner bits x, y, z), along the 0-7 diagonal; they
/// match across neighbouring cubes. Half of them come out negatively oriented.
void addKuhnTets(Mesh& m, const std::uint32_t cube[8]) {
    // Corner of the cube with bits (x, y, z) -> index in kCorner order.
    auto at = [&](int x, int y, int z) {
        for (int v = 0; v < 8; ++v)
            if (int(kCorner[v][0]) == x && int(kCorner[v][1]) == y && int(kCorner[v][2]) == z)
                return cube[v];
        return cube[0];
    };
    const int axes[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (const auto& order : axes) {
        int b[3] = {0, 0, 0};
        std::uint32_t ids[4];
        ids[0] = at(0, 0, 0);
        for (int s = 0; s < 3; ++s) {
            b[order[s]] = 1;
            ids[s + 1] = at(b[0], b[1], b[2]);
        }
        m.addCell(CellType::Tetra, ids);
    }
}

/// Constant colour and opacity over the value range [0, 2]; early termination off, so the whole
/// path counts.
RenderSettings constantSettings(const Camera& camera, int width, int height) {
    RenderSettings s;
    s.method = RenderMethod::Partitions;  // the sampled method (tests of every method set theirs)
    s.width = width;
    s.height = height;
    s.camera = camera;
    s.tf.colors = {{0.f, kColor}, {1.f, kColor}};
    s.tf.opacities = {{0.f, kAlpha}, {1.f, kAlpha}};
    s.range = std::pair<float, float>(0.f, 2.f);
    s.opacityUnit = 1.f;
    s.terminationAlpha = 1.f;
    return s;
}

/// Opacity of a path of length L through the constant medium (the default opacity law).
double exactAlpha(double length, double unit) {
    return testing::slabOpacity(kAlpha, length, unit);
}

/// The ray's span [t0, t1] inside the box from the origin on (double precision); false if none.
bool raySpan(const Bounds3f& b, const Ray& ray, double& t0, double& t1) {
    t0 = 0.0;
    t1 = INFINITY;
    for (int a = 0; a < 3; ++a) {
        const double o = ray.org[a], d = ray.dir[a];
        if (d == 0.0) {
            if (o < b.lo[a] || o > b.hi[a]) return false;
            continue;
        }
        double u0 = (b.lo[a] - o) / d, u1 = (b.hi[a] - o) / d;
        if (u0 > u1) std::swap(u0, u1);
        t0 = std::max(t0, u0);
        t1 = std::min(t1, u1);
    }
    return t1 >= t0;
}

/// Describes how a pixel misses the oracle, or "" when it matches: finite, the TF colour, and
/// the opacity of the span [t0, t1]: pre-integrated runs start and end at the mesh's boundary
/// (sampleAtBoundary), so a constant medium's opacity is the chord's, to within kLengthSlack
/// steps (where the boundary is bisected for). A chord holding no grid point k * step (or one
/// within kGridSlack of an end: float and double ends differ by rounding) may take no sample at
/// all: its opacity lies between 0 and the chord's.
std::string checkPixel(Vec4f c, bool hit, double t0, double t1, double step, double unit) {
    if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z) || !std::isfinite(c.w))
        return "non-finite pixel";
    constexpr double kGridSlack = 1e-3, kLengthSlack = 2e-3;
    double nLo = 0.0, len = 0.0;
    if (hit) {
        const double k0 = t0 / step, k1 = t1 / step;
        nLo = std::max(0.0, std::floor(k1 - kGridSlack) - std::ceil(k0 + kGridSlack) + 1.0);
        len = std::max(0.0, t1 - t0);
    }
    const double lo =
        nLo > 0.0 ? exactAlpha(std::max(0.0, len - kLengthSlack * step), unit) - kAlphaTolerance
                  : -kAlphaTolerance;
    const double hi =
        hit ? exactAlpha(len + kLengthSlack * step, unit) + kAlphaTolerance : kAlphaTolerance;
    if (c.w < lo || c.w > hi)
        return "alpha " + std::to_string(c.w) + " outside [" + std::to_string(lo) + ", " +
               std::to_string(hi) + "] for the chord [" + std::to_string(t0) + ", " +
               std::to_string(t1) + "] (" + std::to_string(nLo) + " grid points)";
    if (c.w > 1e-3f)
        for (int i = 0; i < 3; ++i)
            if (std::fabs(c.xyz()[i] / c.w - kColor[i]) > kColorTolerance)
                return "colour " + std::to_string(c.xyz()[i] / c.w) + " vs " +
                       std::to_string(kColor[i]);
    return "";
}

/// One integrator configuration.
struct Method {
    const char* name;
    RenderMethod method;
    bool adaptive;
};
const Method kEachMethod[] = {{"reference", RenderMethod::Reference, false},
                              {"partitions", RenderMethod::Partitions, false},
                              {"partitions+adaptive", RenderMethod::Partitions, true}};

/// Renders the frame with one integrator on `device` and counts the pixels off the oracle for a
/// convex mesh filling `box`; covered receives the number of pixels whose ray meets the box, first
/// the first mismatch.
int badPixels(testing::TestDevice device, const PreparedMesh& pm, RenderSettings s,
              const Bounds3f& box, const Method& method, int& covered, std::string& first) {
    s.method = method.method;
    s.adaptive = method.adaptive;
    const RenderResult r = testing::renderOn(device, pm, s);
    int bad = 0;
    covered = 0;
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            const Ray ray = r.setup.rays.ray(x + 0.5f, y + 0.5f);
            double t0, t1;
            const bool hit = raySpan(box, ray, t0, t1);
            covered += hit && t1 > t0;
            const std::string why = checkPixel(r.image.at(x, y), hit, t0, t1, r.setup.params.step,
                                               r.setup.params.opacityUnit);
            if (!why.empty() && bad++ == 0)
                first = "pixel (" + std::to_string(x) + ", " + std::to_string(y) + "): " + why;
        }
    return bad;
}

/// Renders the frame with every integrator on `device` and expects every pixel on the oracle;
/// returns the number of pixels the mesh covers (so a test can insist that it saw the mesh).
int renderAndCheck(testing::TestDevice device, const PreparedMesh& pm, const RenderSettings& s,
                   const Bounds3f& box) {
    int covered = 0;
    for (const Method& method : kEachMethod) {
        std::string first;
        EXPECT_EQ(badPixels(device, pm, s, box, method, covered, first), 0)
            << method.name << ": " << first;
    }
    return covered;
}

PreparedMesh prepare(const Mesh& m, std::uint32_t leafCells = 32, bool lbvh = false) {
    PrepareOptions o;
    o.kd.leafCells = leafCells;
    if (lbvh) o.lbvh = buildLbvhCpu;  // the linear BVHs the GPU builds (bit-identical)
    return prepareMesh(m, selectScalarField(m, {}), o);
}

const Bounds3f kUnitBox{{0.f, 0.f, 0.f}, {1.f, 1.f, 1.f}};

Camera obliqueCamera(const Bounds3f& box) {
    return orbitCamera(resetCamera(box, 1.f), 33.f, 27.f);
}

/// The suite's frames render on every device (tests/on_each_device.h).
class HostileMesh : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(HostileMesh);

TEST_P(HostileMesh, OracleSeesAMissingCell) {
    // The check itself: a grid with one interior hexahedron left out (a hole the rays cross)
    // must fail the oracle in every integrator.
    Mesh full = hexGridOnPlanes(uniformPlanes(5, 0.f, 1.f));
    Mesh m;
    m.points = full.points;
    m.fields = full.fields;
    for (std::uint64_t c = 0; c < full.cellCount(); ++c)
        if (c != 62) m.addCell(CellType::Hexahedron, full.cell(c));  // cell (2, 2, 2)
    const PreparedMesh pm = prepare(m);
    for (const Method& method : kEachMethod) {
        int covered = 0;
        std::string first;
        EXPECT_GT(badPixels(device(), pm, constantSettings(obliqueCamera(kUnitBox), 41, 37),
                            kUnitBox, method, covered, first),
                  3)
            << method.name;
    }
}

TEST_P(HostileMesh, DegenerateAndInvertedCellsRenderTheExactImage) {
    // A 4^3 grid of Kuhn tetrahedra (half of them listed inverted), plus zero-volume cells on
    // internal faces: a flat tetrahedron on a face square, a needle with three collinear corners.
    const Planes planes = uniformPlanes(4, 0.f, 1.f);
    Mesh m;
    const std::size_t n = planes.size();
    gridOnPlanes(m, planes, [&](const auto& c) {
        addKuhnTets(m, c);
        const std::uint32_t flat[4] = {c[0], c[1], c[2], c[3]};
        m.addCell(CellType::Tetra, flat);
        const std::size_t j = c[0] / n % n, k = c[0] / (n * n);  // c[0] is corner (i, j, k)
        const std::uint32_t needle[4] = {gridId(n, 0, j, k), gridId(n, 1, j, k), gridId(n, 2, j, k),
                                         c[7]};
        m.addCell(CellType::Tetra, needle);
    });
    m.fields.push_back({"f", Association::Point, 1, std::vector<float>(m.points.size(), 1.f)});
    for (const bool lbvh : {false, true}) {  // SAH trees, linear BVHs
        const PreparedMesh pm = prepare(m, 32, lbvh);
        EXPECT_GT(renderAndCheck(device(), pm, constantSettings(obliqueCamera(kUnitBox), 41, 37),
                                 kUnitBox),
                  500)
            << (lbvh ? "LBVH" : "SAH");
    }
}

TEST_P(HostileMesh, CoincidentPointsRenderTheExactImage) {
    // Every cell has its own copies of its corners: no shared point ids, every shared face is a
    // pair of coincident triangles (face neighbours are found by position, buildTetNeighbors).
    const Mesh grid = hexGridOnPlanes(uniformPlanes(5, 0.f, 1.f));
    Mesh m;
    for (std::uint64_t c = 0; c < grid.cellCount(); ++c) {
        std::uint32_t ids[8];
        for (int v = 0; v < 8; ++v) {
            ids[v] = static_cast<std::uint32_t>(m.points.size());
            m.points.push_back(grid.points[grid.cell(c)[v]]);
        }
        m.addCell(CellType::Hexahedron, ids);
    }
    m.fields.push_back({"f", Association::Point, 1, std::vector<float>(m.points.size(), 1.f)});
    for (const bool lbvh : {false, true}) {  // SAH trees, linear BVHs
        const PreparedMesh pm = prepare(m, 32, lbvh);
        EXPECT_GT(renderAndCheck(device(), pm, constantSettings(obliqueCamera(kUnitBox), 41, 37),
                                 kUnitBox),
                  500)
            << (lbvh ? "LBVH" : "SAH");
    }
}

TEST_P(HostileMesh, CellsFromMicrometreToMegametreRenderTheExactImage) {
    // Planes 0, 1e-6, 1e-5, ..., 1e6 on every axis: cubes of 1e-6 beside slabs 1e12 times wider.
    Planes planes{0.f};
    for (int e = -6; e <= 6; ++e) planes.push_back(std::pow(10.f, float(e)));
    const Bounds3f box{{0.f, 0.f, 0.f}, {1e6f, 1e6f, 1e6f}};
    const Mesh m = hexGridOnPlanes(planes);
    EXPECT_GT(renderAndCheck(device(), prepare(m, 32, /*lbvh=*/true),
                             constantSettings(obliqueCamera(box), 41, 37), box),
              500);
    const PreparedMesh pm = prepare(m);
    EXPECT_GT(renderAndCheck(device(), pm, constantSettings(obliqueCamera(box), 41, 37), box), 500);
    // Also at a step resolving the small cells near the origin, looking at that corner.
    Camera close;
    close.position = {-2e-5f, -1e-5f, -3e-5f};
    close.focalPoint = {1e-5f, 1e-5f, 1e-5f};
    RenderSettings s = constantSettings(close, 21, 19);
    s.step = 1e-6f;
    s.opacityUnit = 1e-5f;
    // Steps this fine over a 1e6 mesh are refused (too many samples per ray, and the camera too
    // many steps away for a float grid count): a clear error, not an endless render.
    const Error e = testing::catchError([&] { (void)render(pm, s); });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_NE(std::string(e.what()).find("a larger `sample_distance`"), std::string::npos)
        << e.what();
}

TEST_P(HostileMesh, CameraInsideTheVolumeSeesItsPathToTheBoundary) {
    const PreparedMesh pm = prepare(hexGridOnPlanes(uniformPlanes(6, 0.f, 1.f)));
    Camera inside;
    inside.position = {0.41f, 0.53f, 0.37f};
    inside.focalPoint = {0.9f, 0.8f, 0.1f};
    inside.viewAngle = 100.f;
    EXPECT_EQ(renderAndCheck(device(), pm, constantSettings(inside, 33, 29), kUnitBox), 33 * 29);
}

TEST_P(HostileMesh, FarCameraFinishesOrIsRefused) {
    // The sample grid counts steps from the camera: 1e6 units away at a step of ~0.04, a float
    // counter would stop advancing (k + 1 == k above 2^24) and the render would never end.
    const PreparedMesh pm = prepare(hexGridOnPlanes(uniformPlanes(6, 0.f, 1.f)));
    Camera far;
    far.position = {0.5f, 0.5f, 1e6f};
    far.focalPoint = {0.5f, 0.5f, 0.5f};
    far.viewAngle = 5e-5f;
    const RenderSettings s = constantSettings(far, 9, 9);
    try {
        (void)renderAndCheck(device(), pm, s, kUnitBox);
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Argument) << e.what();
        EXPECT_NE(std::string(e.what()).find("camera"), std::string::npos) << e.what();
    }
}

TEST_P(HostileMesh, AxisAlignedCameraOnARegularGridHasNoStreaks) {
    // The image's middle row and column of rays run (nearly) in grid planes, which are cell
    // faces and k-d split planes; every other ray crosses them at grid edges.
    const Bounds3f box{{0.f, 0.f, 0.f}, {8.f, 8.f, 8.f}};
    const PreparedMesh pm = prepare(hexGridOnPlanes(uniformPlanes(8, 0.f, 8.f)), 16);
    for (int axis = 0; axis < 3; ++axis) {
        Camera c;
        c.focalPoint = {4.f, 4.f, 4.f};
        c.position = c.focalPoint;
        c.position[axis] += 30.f;
        c.viewUp = axis == 1 ? Vec3f(0.f, 0.f, 1.f) : Vec3f(0.f, 1.f, 0.f);
        SCOPED_TRACE("axis " + std::to_string(axis));
        EXPECT_GT(renderAndCheck(device(), pm, constantSettings(c, 33, 33), box), 300);
    }
}

TEST(HostileMeshRays, RaysExactlyAlongFacesEdgesAndSplitPlanesLoseNothing) {
    // Rays with exactly axis-aligned or in-plane diagonal directions, started on grid planes
    // (integers and half-integers): along cell faces, along cell edges, through grid vertices,
    // in the k-d split planes, through the marchers directly so the directions are exact.
    const Bounds3f box{{0.f, 0.f, 0.f}, {8.f, 8.f, 8.f}};
    for (bool jittered : {false, true}) {
        Mesh m = jittered ? testing::makeHexGrid(
                                8, 0.f, 8.f, [](Vec3f) { return 1.f; }, 0.3f)
                          : hexGridOnPlanes(uniformPlanes(8, 0.f, 8.f));
        const PreparedMesh pm = prepare(m, 16);
        ASSERT_TRUE(pm.kd.has_value());
        ASSERT_GT(pm.kd->partitions.size(), 8u);
        for (const Method& method : kEachMethod) {
            RenderSettings s = constantSettings(resetCamera(box, 1.f), 8, 8);
            s.method = method.method;
            s.adaptive = method.adaptive;
            const FrameSetup f = makeFrameSetup(pm, s);
            const SceneView scene = f.scene(pm);
            const PartitionSceneView parts = method.method == RenderMethod::Partitions
                                                 ? f.partitionScene(pm, true)
                                                 : PartitionSceneView{};
            int bad = 0, rays = 0;
            const float d = 1.f / std::sqrt(2.f);
            const Vec3f dirs[] = {{0, 0, -1}, {0, 0, 1},  {1, 0, 0}, {0, -1, 0},
                                  {d, d, 0},  {d, 0, -d}, {0, -d, d}};
            for (Vec3f dir : dirs)
                for (int i = 1; i < 16; ++i)
                    for (int j = 1; j < 16; ++j) {
                        // Start outside the box on the far side, in the plane the grid offers.
                        const float u = 0.5f * i, v = 0.5f * j;
                        Vec3f org;
                        if (dir.z != 0.f && dir.x == 0.f && dir.y == 0.f)
                            org = {u, v, dir.z < 0 ? 20.f : -12.f};
                        else if (dir.x != 0.f && dir.y == 0.f && dir.z == 0.f)
                            org = {-12.f, u, v};
                        else if (dir.y != 0.f && dir.x == 0.f && dir.z == 0.f)
                            org = {u, 20.f, v};
                        else if (dir.z == 0.f)
                            org = Vec3f(u, 0.f, v) - dir * 10.f;  // in the plane z = v
                        else if (dir.y == 0.f)
                            org = Vec3f(0.f, u, 8.f) + Vec3f(v - 4.f, 0.f, 0.f) - dir * 10.f;
                        else
                            org = Vec3f(u, 8.f, 0.f) + Vec3f(0.f, 0.f, v - 4.f) - dir * 10.f;
                        const Ray ray{org, dir};
                        double t0, t1;
                        if (!raySpan(box, ray, t0, t1) || !(t1 > t0)) continue;
                        ++rays;
                        RayCounters counters;
                        const Vec4f c = method.method == RenderMethod::Reference
                                            ? marchReference(scene, ray, counters)
                                            : marchPartitions(parts, ray, counters);
                        const std::string why = checkPixel(c, true, t0, t1, f.params.step, 1.0);
                        if (!why.empty() && ++bad <= 3)
                            ADD_FAILURE() << method.name << (jittered ? " jittered" : " regular")
                                          << ": ray from (" << org.x << ", " << org.y << ", "
                                          << org.z << ") along (" << dir.x << ", " << dir.y << ", "
                                          << dir.z << "): " << why;
                    }
            EXPECT_GT(rays, 1000);
            EXPECT_EQ(bad, 0) << method.name << (jittered ? " jittered" : " regular");
        }
    }
}

TEST_P(HostileMesh, FieldSpanningTheFloatRangeRendersLikeTheSameFieldScaledDown) {
    // A linear field from -S to S over a 2^3 hexahedron grid: the transfer function spans the
    // field's range, so the image must not depend on S. At S = 3e38 and FLT_MAX the range's
    // width overflows float (it used to make the table index NaN and crash every integrator).
    const auto meshScaled = [](float scale) {
        return testing::makeHexGrid(2, 0.f, 1.f, [scale](Vec3f p) {
            return p.x >= 1.f ? scale : (p.x <= 0.f ? -scale : (2.f * p.x - 1.f) * scale);
        });
    };
    const Mesh unit = meshScaled(1.f);
    RenderSettings s;
    s.width = s.height = 24;
    s.camera = obliqueCamera(kUnitBox);
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, "0:0.1,0.5:0.9,1:0.3");
    for (const Method& method : kEachMethod) {
        s.method = method.method;
        s.adaptive = method.adaptive;
        const RenderResult want = render(prepare(unit, 4), s);
        for (const float scale : {3e38f, std::numeric_limits<float>::max()}) {
            const RenderResult got = render(prepare(meshScaled(scale), 4), s);
            EXPECT_EQ(got.setup.rangeLo, -scale);
            EXPECT_EQ(got.setup.rangeHi, scale);
            int visible = 0;
            for (int y = 0; y < s.height; ++y)
                for (int x = 0; x < s.width; ++x) {
                    const Vec4f gv = got.image.at(x, y), wv = want.image.at(x, y);
                    const float g[4] = {gv.x, gv.y, gv.z, gv.w}, w[4] = {wv.x, wv.y, wv.z, wv.w};
                    for (int c = 0; c < 4; ++c) {
                        ASSERT_TRUE(std::isfinite(g[c])) << method.name << " " << scale;
                        ASSERT_NEAR(g[c], w[c], 1e-3f)
                            << method.name << " " << scale << " pixel (" << x << ", " << y << ")";
                    }
                    visible += gv.w > 0.05f;
                }
            EXPECT_GT(visible, 100) << method.name << " " << scale;
        }
    }
}

/// The grid [-0.5, 0.5]^3 of 4^3 hexahedra (diagonal sqrt(3), in [1, 2): it renders unscaled and
/// unmoved) mapped by p * scale + offset, with a point field varying across it; every coordinate
/// is exact in float for the scales and offsets used below.
Mesh gridScaledAndMoved(float scale, Vec3f offset) {
    Mesh m = hexGridOnPlanes(uniformPlanes(4, -0.5f, 0.5f));
    for (std::size_t i = 0; i < m.points.size(); ++i) {
        const Vec3f p = m.points[i];
        m.fields[0].values[i] = p.x + 2.f * p.y - p.z;
        m.points[i] = p * scale + offset;
    }
    return m;
}

TEST_P(HostileMesh, MeshesAtTheEdgesOfFloatRenderLikeTheUnitMesh) {
    // Coordinates near 1e38 (its default camera lies beyond float's range), 1e-30 and 1e-42
    // (denormal: cubed edges underflow float), and meshes far from the origin for their size
    // (float spacing 1/8 at 2^20): each renders scaled by a power of two and moved exactly onto
    // the unit grid, so the images are the unit grid's bit for bit. They used to be refused
    // with a camera at inf, "empty bounds" or "-9223372036854775808 steps".
    struct Case {
        float scale;
        Vec3f offset;
        bool exactCamera;  // the explicit camera maps exactly onto the unit grid's
    };
    const float far = std::ldexp(1.f, 20);
    const Case cases[] = {{std::ldexp(1.f, 127), Vec3f(0.f), false},
                          {std::ldexp(1.f, 126), Vec3f(0.f), true},
                          {std::ldexp(1.f, -100), Vec3f(0.f), true},
                          {std::ldexp(1.f, -140), Vec3f(0.f), false},
                          {1.f, Vec3f(far, 0.f, -far), false},
                          {std::ldexp(1.f, -100), Vec3f(0.f, std::ldexp(1.f, -80), 0.f), false}};
    const Mesh unit = gridScaledAndMoved(1.f, Vec3f(0.f));
    const PreparedMesh unitPm = prepare(unit, 16);
    ASSERT_TRUE(unitPm.tets.frame.identity());
    const Bounds3f box{Vec3f(-0.5f), Vec3f(0.5f)};
    const Camera oblique = obliqueCamera(box);
    RenderSettings s;
    s.width = 24;
    s.height = 20;
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, "0:0.1,0.5:0.9,1:0.3");
    for (const Method& method : kEachMethod) {
        s.method = method.method;
        s.adaptive = method.adaptive;
        for (const bool explicitCamera : {false, true}) {
            RenderSettings want = s;
            if (explicitCamera) want.camera = oblique;
            const RenderResult w = render(unitPm, want);
            int visible = 0;
            for (int y = 0; y < s.height; ++y)
                for (int x = 0; x < s.width; ++x) visible += w.image.at(x, y).w > 0.05f;
            EXPECT_GT(visible, 100) << method.name;
            for (const Case& c : cases) {
                if (explicitCamera && !c.exactCamera) continue;
                const PreparedMesh pm = prepare(gridScaledAndMoved(c.scale, c.offset), 16);
                ASSERT_EQ(pm.tets.tets.size(), unitPm.tets.tets.size()) << c.scale;
                ASSERT_EQ(pm.tets.hexCount, unitPm.tets.hexCount) << c.scale;
                EXPECT_FALSE(pm.tets.frame.identity()) << c.scale;
                RenderSettings got = s;
                if (explicitCamera) {
                    got.camera = oblique;
                    got.camera->position = oblique.position * c.scale + c.offset;
                    got.camera->focalPoint = oblique.focalPoint * c.scale + c.offset;
                }
                const RenderResult g = render(pm, got);
                const std::string what = std::string(method.name) + " scale " +
                                         std::to_string(std::log2(c.scale)) +
                                         (explicitCamera ? " explicit camera" : " default camera");
                EXPECT_FLOAT_EQ(g.setup.params.step / pm.tets.frame.scale,
                                w.setup.params.step * c.scale)
                    << what;
                int differ = 0;
                for (int y = 0; y < s.height; ++y)
                    for (int x = 0; x < s.width; ++x) {
                        const Vec4f a = g.image.at(x, y), b = w.image.at(x, y);
                        differ += !(a.x == b.x && a.y == b.y && a.z == b.z && a.w == b.w);
                    }
                EXPECT_EQ(differ, 0) << what;
            }
        }
    }
}

TEST_P(HostileMesh, CameraFarFromATinyMeshIsRefusedInStepsItCanCount) {
    // A mesh 1e-30 across and a camera 1 away: 1.9e32 steps (of the diagonal / 256), which
    // overflowed the message's integer ("the camera is -9223372036854775808 steps of 0.000000").
    const PreparedMesh pm = prepare(gridScaledAndMoved(std::ldexp(1.f, -100), Vec3f(0.f)));
    Camera far;
    far.position = {0.f, 0.f, 1.f};
    const RenderSettings s = constantSettings(far, 8, 8);
    const Error e = testing::catchError([&] { (void)render(pm, s); });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    const std::string what = e.what();
    EXPECT_NE(what.find("the camera is 1.87e+32 steps of 5.34e-33 from the far side"),
              std::string::npos)
        << what;
}

TEST_P(HostileMesh, ThinSlabRendersTheExactImage) {
    // A slab 1e-6 thick (its cells 1e-6 of their width, well above the zero-volume threshold),
    // seen edge-on: rays along the middle row run inside it.
    Mesh m = hexGridOnPlanes(uniformPlanes(4, 0.f, 1.f));
    for (Vec3f& p : m.points) p.z *= 1e-6f;
    const Bounds3f box{Vec3f(0.f), Vec3f(1.f, 1.f, 1e-6f)};
    const PreparedMesh pm = prepare(m);
    ASSERT_EQ(pm.tets.splitTetCount(), 6u * 64u);
    Camera edgeOn;
    edgeOn.position = {-1.2f, -0.7f, 0.5e-6f};
    edgeOn.focalPoint = {0.5f, 0.5f, 0.5e-6f};
    edgeOn.viewUp = {0.f, 0.f, 1.f};
    EXPECT_GT(renderAndCheck(device(), pm, constantSettings(edgeOn, 21, 9), box), 10);
    // The default camera looks through it (at most one sample per ray): it renders.
    RenderSettings s = constantSettings(edgeOn, 21, 9);
    s.camera.reset();
    EXPECT_NO_THROW((void)render(pm, s));
}

TEST_P(HostileMesh, MeshWithNothingToRenderIsRefusedOrTransparent) {
    // One sliver 1e-7 thick (below the zero-volume threshold: its volume is rounding noise in
    // float) and four identical points: no tetrahedron is left. The default camera has nothing
    // to frame (it used to say "cannot reset the camera to empty or non-finite bounds"); a
    // given camera sees nothing.
    for (const Vec3f apex : {Vec3f(0.3f, 0.3f, 1e-7f), Vec3f(0.f)}) {
        Mesh m;
        m.points = {{0, 0, 0},
                    apex == Vec3f(0.f) ? apex : Vec3f(1, 0, 0),
                    apex == Vec3f(0.f) ? apex : Vec3f(0, 1, 0),
                    apex};
        const std::uint32_t ids[4] = {0, 1, 2, 3};
        m.addCell(CellType::Tetra, ids);
        m.fields.push_back({"f", Association::Point, 1, {1.f, 1.f, 1.f, 1.f}});
        const PreparedMesh pm = prepare(m);
        ASSERT_TRUE(pm.tets.tets.empty());
        RenderSettings s = constantSettings(obliqueCamera(kUnitBox), 8, 8);
        for (const Method& method : kEachMethod) {
            s.method = method.method;
            s.adaptive = method.adaptive;
            const RenderResult r = render(pm, s);
            for (int y = 0; y < 8; ++y)
                for (int x = 0; x < 8; ++x) EXPECT_EQ(r.image.at(x, y).w, 0.f) << method.name;
        }
        s.camera.reset();
        const Error e = testing::catchError([&] { (void)render(pm, s); });
        EXPECT_NE(std::string(e.what()).find("no cell of non-zero volume"), std::string::npos)
            << e.what();
    }
}

TEST(HostileMeshSetup, DefaultStepOfAMeshOfSliversIsAtLeastATenThousandthOfTheDiagonal) {
    TetMesh t;
    t.tets.resize(1000);
    t.totalVolume = 1e-12;  // mean 1e-15: a step of 5e-6 without the floor
    t.bounds = kUnitBox;
    EXPECT_FLOAT_EQ(defaultStep(t), float(kMinDefaultStepFraction * std::sqrt(3.0)));
    t.totalVolume = 1.0 / 6;  // few cells: 256 samples across the diagonal
    EXPECT_FLOAT_EQ(defaultStep(t), float(std::sqrt(3.0) / 256));
    t.tets.resize(1000000);  // an ordinary mean: 0.5 cbrt(1 / 6e6)
    EXPECT_FLOAT_EQ(defaultStep(t), float(0.5 * std::cbrt(1.0 / 6e6)));
}

}  // namespace
}  // namespace uvr
