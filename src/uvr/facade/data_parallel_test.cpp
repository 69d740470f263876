// SPDX-License-Identifier: MIT
// Data-parallel frames (issue 31) against one process's: the ranks are threads of this process
// (InProcessGroup), each holding its piece of the whole mesh and composited onto rank 0.
#include <gmock/gmock.h>

#include <memory>
#include <mutex>
#include <tuple>

#include "test_meshes.h"
#include "test_support.h"
#include "uvr/cuda/cuda_device.h"
#include "uvr/dist/communicator.h"
#include "uvr/dist/decompose.h"
#include "uvr/dist/in_process_communicator.h"
#include "uvr/facade/renderer.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/render/image_metrics.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;
using uvr::testing::catchError;

/// The same picture: SSIM and the largest channel difference against one process.
constexpr double kMinSsim = 0.999;
constexpr double kMaxLevels = 2.0;

RenderSettings orbitFrameOf(const Bounds3f& bounds, RenderMethod method, float azimuth,
                            float elevation) {
    RenderSettings s;
    s.width = 160;
    s.height = 120;
    s.method = method;
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, "0:0,0.3:0.1,0.6:0.6,1:0.2");
    s.camera = orbitCamera(resetCamera(bounds, 160.f / 120.f), azimuth, elevation);
    return s;
}

/// Rank 0's frames of `ranks` in-process ranks, one per settings.
std::vector<RenderResult> dataParallelFrames(const Mesh& mesh, const ScalarField& field, int ranks,
                                             const RendererOptions& options,
                                             const std::vector<RenderSettings>& frames) {
    std::vector<RenderResult> out;
    InProcessGroup::run(ranks, [&](Communicator& comm) {
        RendererOptions o = options;
        o.communicator = &comm;
        Renderer r(mesh, field, o);
        for (const RenderSettings& s : frames) {
            RenderResult result = r.render(s);
            if (comm.rank() == 0) out.push_back(std::move(result));
        }
    });
    return out;
}

/// A mesh file, its default field and one CPU process's renderer of it.
struct OneProcess {
    Mesh mesh;
    ScalarField field;
    RendererOptions options;
    std::unique_ptr<Renderer> renderer;
    Bounds3f bounds;
    float radius = 0.f;  ///< half the bounds' diagonal

    explicit OneProcess(const std::string& path)
        : mesh(readMesh(path)), field(selectScalarField(mesh, {})), bounds(mesh.bounds()) {
        options.device = Device::Cpu;
        renderer = std::make_unique<Renderer>(mesh, field, options);
        radius = 0.5f * length(bounds.hi - bounds.lo);
    }
};

/// A mesh and the rank counts it is rendered on (Blunt Fin, the largest, on many; the others on
/// an uneven count, keeping the suite's time under the sanitizers).
struct MeshOnRanks {
    const char* file;
    const char* field;
    std::vector<int> ranks;
};

TEST(DataParallel, EveryMethodGivesOneProcessPictureOnRealMeshes) {
    const std::vector<MeshOnRanks> cases = {{"bluntfin_tets.vtk", "", {2, 3, 5, 8}},
                                            {"post.vtk", "", {3}},
                                            {"spx.vtk", "", {5}},
                                            {"hexa.vtk", "", {3}}};
    for (const MeshOnRanks& c : cases) {
        const std::string path = testing::sharedData(c.file);
        if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
        const Mesh mesh = readMesh(path);
        const ScalarField field = selectScalarField(mesh, parseFieldSpec(c.field));
        RendererOptions options;
        options.device = Device::Cpu;
        Renderer one(mesh, field, options);
        const Bounds3f bounds = mesh.bounds();
        std::vector<RenderSettings> frames;
        for (RenderMethod m :
             {RenderMethod::Reference, RenderMethod::Partitions, RenderMethod::Exact})
            for (auto [az, el] : {std::pair{30.f, 20.f}, std::pair{-120.f, -35.f}})
                frames.push_back(orbitFrameOf(bounds, m, az, el));
        std::vector<RenderResult> single;
        for (const RenderSettings& s : frames) {
            single.push_back(one.render(s));
            // A picture to compare: a good part of the frame is covered.
            std::size_t covered = 0;
            for (const Vec4f& p : single.back().image.pixels) covered += p.w > 0.1f;
            ASSERT_GT(covered, single.back().image.pixels.size() / 20) << c.file;
        }
        for (int ranks : c.ranks) {
            const std::vector<RenderResult> many =
                dataParallelFrames(mesh, field, ranks, options, frames);
            ASSERT_EQ(many.size(), frames.size());
            for (std::size_t i = 0; i < frames.size(); ++i) {
                const ImageComparison cmp =
                    compareImages(toRgb8(single[i].image), toRgb8(many[i].image));
                SCOPED_TRACE(std::string(c.file) + " " + methodName(frames[i].method) + " view " +
                             std::to_string(i % 2) + ", " + std::to_string(ranks) + " ranks");
                EXPECT_GE(cmp.ssim, kMinSsim);
                EXPECT_LE(cmp.maxAbsDifference, kMaxLevels) << differenceSummary(cmp);
                ASSERT_EQ(many[i].ranks.size(), std::size_t(ranks));
            }
        }
    }
}

TEST(DataParallel, DepthInEndsTheRaysOfEveryRankAsOneProcesss) {
    // Opaque geometry given as depth (a plane tilted across the view, cutting the volume): every
    // rank's rays end there, and the composite is one process's frame.
    const std::string path = testing::sharedData("bluntfin_tets.vtk");
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
    const OneProcess fin(path);
    std::vector<RenderSettings> frames;
    for (RenderMethod m :
         {RenderMethod::Reference, RenderMethod::Partitions, RenderMethod::Exact}) {
        RenderSettings s = orbitFrameOf(fin.bounds, m, 30.f, 20.f);
        const float focal = length(s.camera->focalPoint - s.camera->position);
        s.depthIn.resize(std::size_t(s.width) * s.height);
        for (int y = 0; y < s.height; ++y)
            for (int x = 0; x < s.width; ++x)
                s.depthIn[std::size_t(y) * s.width + x] =
                    focal - fin.radius + 2.f * fin.radius * float(x) / float(s.width);
        frames.push_back(s);
    }
    for (const RenderSettings& s : frames) {
        const RenderResult cut = fin.renderer->render(s);
        RenderSettings whole = s;
        whole.depthIn.clear();
        const ImageComparison against =
            compareImages(toRgb8(cut.image), toRgb8(fin.renderer->render(whole).image));
        EXPECT_GT(against.maxAbsDifference, 20.0) << "the depth cuts nothing";
        const std::vector<RenderResult> many =
            dataParallelFrames(fin.mesh, fin.field, 3, fin.options, {s});
        ASSERT_EQ(many.size(), 1u);
        const ImageComparison cmp = compareImages(toRgb8(cut.image), toRgb8(many[0].image));
        SCOPED_TRACE(methodName(s.method));
        EXPECT_GE(cmp.ssim, kMinSsim);
        EXPECT_LE(cmp.maxAbsDifference, kMaxLevels) << differenceSummary(cmp);
    }
}

TEST(DataParallel, DepthOutIsOneProcesssForEveryMethod) {
    // The depth where the whole opacity reaches depthAlpha: in the first rank whose light takes it
    // there, where that rank's own opacity reaches what the light in front leaves (a second pass
    // for the pixels behind others' light).
    const std::string path = testing::sharedData("bluntfin_tets.vtk");
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
    const OneProcess fin(path);
    // Every method at opacity 0.3, the adaptive one also at 0.6; the ranks distributed once.
    std::vector<RenderSettings> frames;
    for (const auto& [m, depthAlpha] :
         {std::pair{RenderMethod::Reference, 0.3f}, std::pair{RenderMethod::Partitions, 0.3f},
          std::pair{RenderMethod::Partitions, 0.6f}, std::pair{RenderMethod::Exact, 0.3f}}) {
        frames.push_back(orbitFrameOf(fin.bounds, m, 30.f, 20.f));
        frames.back().depthAlpha = depthAlpha;
    }
    const std::vector<RenderResult> many =
        dataParallelFrames(fin.mesh, fin.field, 3, fin.options, frames);
    ASSERT_EQ(many.size(), frames.size());
    for (std::size_t f = 0; f < frames.size(); ++f) {
        const RenderSettings& s = frames[f];
        const RenderResult single = fin.renderer->render(s);
        SCOPED_TRACE(std::string(methodName(s.method)) + " at opacity " +
                     std::to_string(s.depthAlpha));
        const ImageComparison cmp = compareImages(toRgb8(single.image), toRgb8(many[f].image));
        EXPECT_GE(cmp.ssim, kMinSsim);
        EXPECT_LE(cmp.maxAbsDifference, kMaxLevels) << differenceSummary(cmp);
        ASSERT_EQ(many[f].depth.size(), single.depth.size());
        std::size_t finite = 0, disagree = 0, far = 0;
        double worst = 0.0;
        for (std::size_t i = 0; i < single.depth.size(); ++i) {
            const float a = single.depth[i], b = many[f].depth[i];
            if ((a < INFINITY) != (b < INFINITY)) {
                ++disagree;
                continue;
            }
            if (!(a < INFINITY)) continue;
            ++finite;
            worst = std::max(worst, double(std::abs(a - b)));
            far += std::abs(a - b) > 1e-3f * fin.radius;
        }
        EXPECT_GT(finite, single.depth.size() / 20) << "the depth reaches too few pixels";
        EXPECT_LE(disagree, finite / 1000);
        // A piece's end also ends the stretch of the ray a depth is read in, as if its
        // extinction were constant: the sampling methods' depth moves there by less than their
        // step (exact's by far less), elsewhere by nothing to speak of.
        const double step = single.setup.params.step / single.setup.frame.scale;
        EXPECT_LE(worst, step);
        EXPECT_LE(far, finite / 100);
    }
    // Supersampled rays stop and note depth each on its own, which one opacity per pixel in
    // front cannot follow.
    RenderSettings s = orbitFrameOf(fin.bounds, RenderMethod::Reference, 30.f, 20.f);
    s.depthAlpha = 0.5f;
    s.supersample = 2;
    const Error e =
        catchError([&] { dataParallelFrames(fin.mesh, fin.field, 2, fin.options, {s}); });
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    EXPECT_THAT(e.what(), HasSubstr("supersample 2"));
}

TEST(DataParallel, IsosurfacesAtThePiecesEndsAreOneProcesss) {
    // Adaptive frames whose surfaces lie between a run's last sample and the mesh's boundary, at
    // a piece's start or end: the run starts at the boundary in the piece after a piece that
    // ended outside the mesh; a run whose share ends (at the boundary, or at the span's end in
    // another rank's piece) is probed for the surface as one process's is, whatever follows it;
    // no rank samples the next rank's first grid point. Before: Blunt Fin up to 105/255 in 15
    // pixels of 65,536 (the surface missing at a piece's start); SPX 5/255 on 3 ranks. Also a
    // shaded frame with a gradient opacity: the pieces' runs scale their segments as one
    // process's do.
    struct View {
        float azimuth, elevation;
        std::vector<const char*> isos;
        bool shaded;
        const char* gradientOpacity;  ///< or null
    };
    struct Scene {
        const char* file;
        int ranks;
        std::vector<View> views;
    };
    const std::vector<Scene> scenes = {
        {"bluntfin_tets.vtk",
         4,
         {{200.f, -30.f, {"0.8,0.5"}, false, nullptr},
          {200.f, -30.f, {"1.5,0.6", "3,1"}, true, nullptr},
          {60.f, 20.f, {"0.8,0.5", "2,0.7"}, true, nullptr},
          {35.f, 25.f, {}, true, "0:0,5:1"}}},
        {"spx.vtk", 3, {{320.f, 60.f, {"0.3381,0.4", "1.9159,1"}, false, nullptr}}}};
    for (const Scene& scene : scenes) {
        const std::string path = testing::sharedData(scene.file);
        if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
        const OneProcess one(path);
        std::vector<RenderSettings> frames;
        for (const View& v : scene.views) {
            RenderSettings s;
            s.width = s.height = 256;
            s.method = RenderMethod::Partitions;
            s.tf = transferFunctionPreset("cool-to-warm");
            s.camera = orbitCamera(resetCamera(one.bounds, 1.f), v.azimuth, v.elevation);
            for (const char* iso : v.isos) s.isoSurfaces.push_back(parseIsoSurface(iso));
            s.lighting.on = v.shaded;
            if (v.gradientOpacity) s.gradientOpacity = parseGradientOpacity(v.gradientOpacity);
            frames.push_back(s);
        }
        const std::vector<RenderResult> many =
            dataParallelFrames(one.mesh, one.field, scene.ranks, one.options, frames);
        ASSERT_EQ(many.size(), frames.size());
        for (std::size_t f = 0; f < frames.size(); ++f) {
            const RenderResult single = one.renderer->render(frames[f]);
            const ImageComparison cmp = compareImages(toRgb8(single.image), toRgb8(many[f].image));
            SCOPED_TRACE(std::string(scene.file) + " view " + std::to_string(f));
            EXPECT_GE(cmp.ssim, kMinSsim);
            EXPECT_LE(cmp.maxAbsDifference, kMaxLevels) << differenceSummary(cmp);
        }
    }
}

TEST(DataParallel, TheRanksPartitionsAreOneProcessPartitions) {
    for (const char* file : {"bluntfin_tets.vtk", "hexa.vtk"}) {
        const std::string path = testing::sharedData(file);
        if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
        const Mesh mesh = readMesh(path);
        const ScalarField field = selectScalarField(mesh, {});
        RendererOptions options;
        options.device = Device::Cpu;
        options.leafCells = 256;  // many partitions: deep ranks' subtrees
        const Renderer one(mesh, field, options);
        const auto key = [](const KdPartition& p) {
            return std::tuple(p.box.lo.x, p.box.lo.y, p.box.lo.z, p.box.hi.x, p.box.hi.y,
                              p.box.hi.z, p.cellCount, p.valueMin, p.valueMax);
        };
        std::vector<decltype(key(KdPartition{}))> whole;
        for (const KdPartition& p : one.prepared().kd->partitions) whole.push_back(key(p));
        std::sort(whole.begin(), whole.end());
        for (int ranks : {2, 3, 5, 8}) {
            std::vector<decltype(key(KdPartition{}))> pieces;
            std::vector<std::uint64_t> cells;
            std::mutex m;
            InProcessGroup::run(ranks, [&](Communicator& comm) {
                RendererOptions o = options;
                o.communicator = &comm;
                const Renderer r(mesh, field, o);
                const std::lock_guard<std::mutex> lock(m);
                for (const KdPartition& p : r.prepared().kd->partitions) pieces.push_back(key(p));
                cells.push_back(r.prepared().tets.cellCount());
            });
            std::sort(pieces.begin(), pieces.end());
            SCOPED_TRACE(std::string(file) + ", " + std::to_string(ranks) + " ranks");
            EXPECT_EQ(pieces.size(), whole.size());
            EXPECT_TRUE(pieces == whole);
            // No rank holds the whole mesh (the ghosts aside, about a rank's share of it).
            for (std::uint64_t c : cells) EXPECT_LT(c, one.prepared().tets.cellCount());
        }
    }
}

TEST(DataParallel, OnTheGpuEveryMethodGivesOneProcessPicture) {
    if (!cudaDeviceAvailable()) GTEST_SKIP() << "no CUDA device: " << cudaDeviceDescription();
    const std::string path = testing::sharedData("bluntfin_tets.vtk");
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
    const Mesh mesh = readMesh(path);
    const ScalarField field = selectScalarField(mesh, {});
    RendererOptions options;
    options.device = Device::Cuda;
    Renderer one(mesh, field, options);
    std::vector<RenderSettings> frames;
    for (RenderMethod m : {RenderMethod::Reference, RenderMethod::Partitions, RenderMethod::Exact})
        frames.push_back(orbitFrameOf(mesh.bounds(), m, 30.f, 20.f));
    for (int ranks : {2, 3}) {
        const std::vector<RenderResult> many =
            dataParallelFrames(mesh, field, ranks, options, frames);
        ASSERT_EQ(many.size(), frames.size());
        for (std::size_t i = 0; i < frames.size(); ++i) {
            const ImageComparison cmp =
                compareImages(toRgb8(one.render(frames[i]).image), toRgb8(many[i].image));
            SCOPED_TRACE(std::string(methodName(frames[i].method)) + ", " + std::to_string(ranks) +
                         " ranks on the GPU");
            EXPECT_GE(cmp.ssim, kMinSsim);
            EXPECT_LE(cmp.maxAbsDifference, kMaxLevels) << differenceSummary(cmp);
        }
    }
}

/// The unit cube of 8^3 hexahedra with field x, which two ranks split at the median cell centre
/// x = 0.125 (64 cells a partition, on the CPU).
struct SplitCube {
    Mesh mesh = testing::makeHexGrid(
        8, -1.f, 1.f, [](Vec3f p) { return p.x; }, 0.f);
    ScalarField field = selectScalarField(mesh, {});
    RendererOptions options = [] {
        RendererOptions o;
        o.device = Device::Cpu;
        o.leafCells = 64;
        return o;
    }();

    /// A 48 x 48 frame along the x axis from x = eyeX, constant opacity 0.5 over `unit`.
    static RenderSettings alongX(RenderMethod method, float eyeX, float unit) {
        RenderSettings s;
        s.width = s.height = 48;
        s.method = method;
        s.tf = transferFunctionPreset("viridis");
        applyOpacitySpec(s.tf, "constant:0.5");
        s.opacityUnit = unit;
        Camera c;
        c.position = Vec3f(eyeX, 0.f, 0.f);
        c.focalPoint = Vec3f(0.f, 0.f, 0.f);
        c.viewUp = Vec3f(0.f, 0.f, 1.f);
        s.camera = c;
        return s;
    }
};

TEST(DataParallel, ExactGoesOnBehindANearlyOpaqueFrontRankAsOneProcessDoes) {
    // Two ranks split the cube at the median cell centre, x = 0.125; seen from -x, the front
    // rank's opacity is 0.9905, above the sampling methods' termination (0.99) but below
    // exact's: one process's exact ray goes on into the back (about 2.3/255 of its colour), so
    // the composite must take the back rank too.
    const SplitCube cube;
    const Mesh& mesh = cube.mesh;
    const ScalarField& field = cube.field;
    const RendererOptions& options = cube.options;
    // 1 - exp(-0.5 * 1.125 / 0.1208) = 0.9905 in front
    const RenderSettings s = SplitCube::alongX(RenderMethod::Exact, -6.f, 0.1208f);
    const Image one = Renderer(mesh, field, options).render(s).image;
    const std::vector<RenderResult> many = dataParallelFrames(mesh, field, 2, options, {s});
    ASSERT_EQ(many.size(), 1u);
    const Vec4f centre = one.at(24, 24);
    EXPECT_GT(centre.w, 0.9995f);  // the back was reached
    const ImageComparison cmp = compareImages(toRgb8(one), toRgb8(many[0].image));
    EXPECT_LE(cmp.maxAbsDifference, 1.0) << differenceSummary(cmp);
}

TEST(DataParallel, ARayStopsBehindTheFrontRankWhereOneProcessStops) {
    // The cube split at x = 0.125 as above, seen from +x: the front rank (0.875 deep) leaves
    // opacity 0.5, the whole depth would reach 0.795, and the termination opacity 0.7 stops one
    // process's ray inside the back rank. The back rank's own ray, alone, never reaches 0.7:
    // without the second pass it would add all its light (alpha 0.795, not 0.7).
    const SplitCube cube;
    const Mesh& mesh = cube.mesh;
    const ScalarField& field = cube.field;
    const RendererOptions& options = cube.options;
    std::vector<RenderSettings> frames;
    for (RenderMethod method : {RenderMethod::Reference, RenderMethod::Partitions}) {
        // 1 - exp(-0.5 * 0.875 / u) = 0.5
        RenderSettings s = SplitCube::alongX(method, 6.f, 0.5f * 0.875f / std::log(2.f));
        s.terminationAlpha = 0.7f;
        frames.push_back(s);
    }
    const std::vector<RenderResult> many = dataParallelFrames(mesh, field, 2, options, frames);
    ASSERT_EQ(many.size(), frames.size());
    Renderer one(mesh, field, options);
    for (std::size_t i = 0; i < frames.size(); ++i) {
        SCOPED_TRACE(methodName(frames[i].method));
        const Image single = one.render(frames[i]).image;
        EXPECT_NEAR(single.at(24, 24).w, 0.7f, 0.03f);  // stopped at the termination opacity
        EXPECT_NEAR(many[i].image.at(24, 24).w, single.at(24, 24).w, 1e-4f);
        const ImageComparison cmp = compareImages(toRgb8(single), toRgb8(many[i].image));
        EXPECT_LE(cmp.maxAbsDifference, 1.0) << differenceSummary(cmp);
        // The back rank rendered the covered pixels again; the front rank none.
        ASSERT_EQ(many[i].ranks.size(), 2u);
        const std::uint64_t again =
            many[i].ranks[0].rerenderedPixels + many[i].ranks[1].rerenderedPixels;
        EXPECT_GT(again, 48u * 48u / 4);
        EXPECT_TRUE(many[i].ranks[0].rerenderedPixels == 0 ||
                    many[i].ranks[1].rerenderedPixels == 0);
    }
}

/// Rank 0's frame after new values: a data-parallel renderer prepared with `first`, then
/// given `then` (the whole mesh's values, or with fromShares each rank's share's).
RenderResult frameAfterNewValues(const Mesh& mesh, const ScalarField& first,
                                 const ScalarField& then, int ranks, bool fromShares,
                                 const RenderSettings& s) {
    RenderResult out;
    InProcessGroup::run(ranks, [&](Communicator& comm) {
        RendererOptions o;
        o.device = Device::Cpu;
        o.communicator = &comm;
        std::unique_ptr<Renderer> r;
        if (fromShares) {
            r = std::make_unique<Renderer>(shareOfMesh(mesh, first, comm.rank(), ranks), o);
            r->setFieldValues(shareOfMesh(mesh, then, comm.rank(), ranks).field);
        } else {
            r = std::make_unique<Renderer>(mesh, first, o);
            r->setFieldValues(then);
        }
        RenderResult result = r->render(s);
        if (comm.rank() == 0) out = std::move(result);
    });
    return out;
}

TEST(DataParallel, NewValuesReachThePiecesAsAFreshPreparationWould) {
    // A time step's new values (or another field) move to the pieces over the routes the
    // distribution noted; the frame equals one process's prepared with them from the start,
    // value range included (energy's is not density's).
    const std::string path = testing::sharedData("bluntfin_tets.vtk");
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
    const Mesh fin = readMesh(path);
    const ScalarField density = selectScalarField(fin, parseFieldSpec("density"));
    const ScalarField energy = selectScalarField(fin, parseFieldSpec("energy"));
    RendererOptions options;
    options.device = Device::Cpu;
    for (RenderMethod m : {RenderMethod::Partitions, RenderMethod::Reference}) {
        const RenderSettings s = orbitFrameOf(fin.bounds(), m, 30.f, 20.f);
        const Image one = Renderer(fin, energy, options).render(s).image;
        for (const auto& [ranks, fromShares] : {std::pair{3, false}, std::pair{2, true}}) {
            SCOPED_TRACE(std::string(methodName(m)) + ", " + std::to_string(ranks) + " ranks" +
                         (fromShares ? " from shares" : ""));
            const RenderResult many =
                frameAfterNewValues(fin, density, energy, ranks, fromShares, s);
            EXPECT_FLOAT_EQ(many.setup.rangeLo, 0.768957f);
            const ImageComparison cmp = compareImages(toRgb8(one), toRgb8(many.image));
            EXPECT_GE(cmp.ssim, kMinSsim);
            EXPECT_LE(cmp.maxAbsDifference, kMaxLevels) << differenceSummary(cmp);
        }
    }
    // A point field, then a cell field of the same mesh.
    Mesh grid = testing::makeHexGrid(
        10, -1.f, 1.f, [](Vec3f p) { return p.x * p.y + p.z; }, 0.2f);
    Field c{"c", Association::Cell, 1, {}};
    for (std::uint64_t i = 0; i < grid.cellCount(); ++i) {
        Vec3f centre(0.f, 0.f, 0.f);
        for (std::uint32_t id : grid.cell(i)) centre = centre + grid.points[id] * 0.125f;
        c.values.push_back(std::sin(3.f * centre.x) + centre.y * centre.z);
    }
    grid.fields.push_back(c);
    const ScalarField f = selectScalarField(grid, parseFieldSpec("f"));
    const ScalarField cells = selectScalarField(grid, parseFieldSpec("c"));
    const RenderSettings s = orbitFrameOf(grid.bounds(), RenderMethod::Partitions, -40.f, 25.f);
    const Image one = Renderer(grid, cells, options).render(s).image;
    const ImageComparison cmp =
        compareImages(toRgb8(one), toRgb8(frameAfterNewValues(grid, f, cells, 2, false, s).image));
    EXPECT_GE(cmp.ssim, kMinSsim);
    EXPECT_LE(cmp.maxAbsDifference, kMaxLevels) << differenceSummary(cmp);
    // The wrong count fails on every rank, naming it.
    ScalarField bad = energy;
    bad.values.pop_back();
    const Error e = catchError([&] { frameAfterNewValues(fin, density, bad, 2, false, s); });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_THAT(e.what(), HasSubstr("expected " + std::to_string(fin.pointCount())));
}

TEST(DataParallel, LongSampleDistancesAndSmoothShadingGiveOneProcessPicture) {
    // Sample distances of 6 and 12 default steps: a piece's closing sample lies that far past
    // its box (the ghosts reach RendererOptions::largestSampleDistance), the run its first
    // sample continues has its slope from the piece before's last sample (a lead sample in the
    // ghosts), and a run whose share ends before the next piece ends in its own. Smooth normals:
    // every cell around a ghost's outer points is a ghost too. The ramp's opacity reaches 1.
    const std::string path = testing::sharedData("bluntfin_tets.vtk");
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
    const Mesh mesh = readMesh(path);
    const ScalarField field = selectScalarField(mesh, {});
    RendererOptions options;
    options.device = Device::Cpu;
    options.largestSampleDistance = 1.f;
    std::vector<RenderSettings> frames;
    for (RenderMethod m : {RenderMethod::Reference, RenderMethod::Partitions}) {
        for (float step : {0.5f, 1.f}) {
            RenderSettings s = orbitFrameOf(mesh.bounds(), m, 35.f, 25.f);
            applyOpacitySpec(s.tf, "ramp");
            s.step = step;
            frames.push_back(s);
        }
        RenderSettings lit = orbitFrameOf(mesh.bounds(), m, -50.f, 20.f);
        lit.lighting.on = true;
        lit.lighting.specular = 0.3f;
        frames.push_back(lit);
    }
    Renderer one(mesh, field, options);
    for (int ranks : {2, 4}) {
        const std::vector<RenderResult> many =
            dataParallelFrames(mesh, field, ranks, options, frames);
        ASSERT_EQ(many.size(), frames.size());
        for (std::size_t i = 0; i < frames.size(); ++i) {
            SCOPED_TRACE(std::string(methodName(frames[i].method)) + ", sample distance " +
                         std::to_string(frames[i].step) +
                         (frames[i].lighting.on ? ", shaded" : "") + ", " + std::to_string(ranks) +
                         " ranks");
            const ImageComparison cmp =
                compareImages(toRgb8(one.render(frames[i]).image), toRgb8(many[i].image));
            EXPECT_GE(cmp.ssim, kMinSsim);
            EXPECT_LE(cmp.maxAbsDifference, kMaxLevels) << differenceSummary(cmp);
        }
    }
    // Past the ghosts' reach, a frame is refused on every rank, naming the largest.
    RenderSettings far = frames[0];
    far.step = 1.5f;
    options.largestSampleDistance = 0.f;  // 2 default steps (0.17)
    const Error e = catchError([&] { dataParallelFrames(mesh, field, 2, options, {far}); });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_THAT(e.what(), HasSubstr("sample_distance 1.5: expected at most 0.17"));
}

TEST(DataParallel, TooManyRanksForThePartitionsAreRefusedOnEveryRank) {
    const Mesh mesh = testing::makeHexGrid(
        3, -1.f, 1.f, [](Vec3f p) { return p.x; }, 0.f);
    const ScalarField field = selectScalarField(mesh, {});
    RendererOptions options;
    options.device = Device::Cpu;
    const Error e = catchError([&] {
        InProcessGroup::run(3, [&](Communicator& comm) {
            RendererOptions o = options;
            o.communicator = &comm;
            Renderer r(mesh, field, o);
        });
    });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_THAT(e.what(), HasSubstr("fewer than the 3 ranks"));
}

}  // namespace
}  // namespace uvr
