// SPDX-License-Identifier: MIT
#include "uvr/facade/series_player.h"

#include <gmock/gmock.h>

#include <cmath>

#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/dist/decompose.h"
#include "uvr/dist/in_process_communicator.h"
#include "uvr/mesh/io/exodus.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/mesh/io/native.h"
#include "uvr/render/image_metrics.h"

#ifdef UVR_HAVE_NETCDF
#include "exodus_file_writer.h"
#endif

namespace uvr {
namespace {

using ::testing::HasSubstr;
using uvr::testing::catchError;

/// A jittered hexahedral grid of n cells a side whose point field "f" moves with t.
Mesh movingMesh(float t, int n = 6, const std::string& name = "f") {
    Mesh m = testing::makeHexGrid(
        n, -1.f, 1.f, [t](Vec3f p) { return std::sin(3.f * p.x + t) * p.y + p.z; }, 0.2f);
    m.fields[0].name = name;
    return m;
}

RenderSettings seriesFrameOf(const Bounds3f& bounds) {
    RenderSettings s;
    s.width = 64;
    s.height = 48;
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, "0:0,1:0.6");
    s.range = std::pair{-2.f, 2.f};  // one range for every step
    s.camera = orbitCamera(resetCamera(bounds, 64.f / 48.f), 30.f, 20.f);
    return s;
}

/// The frame a renderer prepared from scratch gives for this mesh.
RenderResult freshFrame(const Mesh& m, const RenderSettings& s, const RendererOptions& o) {
    Renderer r(m, selectScalarField(m, parseFieldSpec("f")), o);
    return r.render(s);
}

void expectSameImage(const RenderResult& a, const RenderResult& b, const std::string& what) {
    ASSERT_EQ(a.image.pixels.size(), b.image.pixels.size()) << what;
    for (std::size_t i = 0; i < a.image.pixels.size(); ++i) {
        const Vec4f p = a.image.pixels[i], q = b.image.pixels[i];
        ASSERT_TRUE(p.x == q.x && p.y == q.y && p.z == q.z && p.w == q.w)
            << what << ": pixel " << i;
    }
}

TEST(SeriesPlayer, StepsOfOneGeometryRefreshValuesAndFramesEqualAFreshPreparation) {
    const std::string dir = testing::scratchDir();
    for (int k = 0; k < 3; ++k)
        writeMesh(movingMesh(float(k)), dir + "/s_" + std::to_string(k) + ".vtu");
    writeMesh(movingMesh(3.f, 5), dir + "/s_3.vtu");       // another geometry
    writeMesh(movingMesh(4.f, 6, "g"), dir + "/s_4.vtu");  // the field is missing
    RendererOptions o;
    o.device = Device::Cpu;
    SeriesPlayer player(openMeshSeries(dir + "/s_*.vtu"), parseFieldSpec("f"), o);
    ASSERT_EQ(player.series().stepCount(), 5u);
    EXPECT_EQ(player.step(), 0u);
    const RenderSettings s = seriesFrameOf(player.mesh().bounds());
    expectSameImage(player.renderer().render(s), freshFrame(movingMesh(0.f), s, o), "step 0");
    const PreparedMesh* prepared = &player.renderer().prepared();

    // Step 1, read in the background while step 0 rendered: values only.
    player.prefetch(1);
    const RenderResult during = player.renderer().render(s);
    StepUpdate u = player.show(1);
    EXPECT_TRUE(u.prefetched);
    EXPECT_FALSE(u.rebuilt);
    EXPECT_EQ(u.time, 1.0);
    EXPECT_EQ(&player.renderer().prepared(), prepared);  // nothing prepared anew
    const RenderResult one = player.renderer().render(s);
    expectSameImage(one, freshFrame(movingMesh(1.f), s, o), "step 1");
    double change = 0.0;
    for (std::size_t i = 0; i < one.image.pixels.size(); ++i)
        change += std::abs(one.image.pixels[i].x - during.image.pixels[i].x);
    EXPECT_GT(change, 1.0);  // the new values show

    // Step 2 without a prefetch, while a prefetch of another step is dropped; step 3's read
    // starts before step 2's values are refreshed.
    player.prefetch(4);
    u = player.show(2, 3);
    EXPECT_FALSE(u.prefetched);
    EXPECT_FALSE(u.rebuilt);
    expectSameImage(player.renderer().render(s), freshFrame(movingMesh(2.f), s, o), "step 2");

    // Step 3's geometry differs: prepared anew (its read was started by show(2, 3)).
    u = player.show(3);
    EXPECT_TRUE(u.rebuilt);
    EXPECT_TRUE(u.prefetched);
    EXPECT_EQ(player.mesh().cellCount(), 125u);
    expectSameImage(player.renderer().render(s), freshFrame(movingMesh(3.f, 5), s, o), "step 3");

    // Step 4 lacks the field: an error naming it, and step 3 stays shown.
    player.prefetch(4);
    EXPECT_THAT(catchError([&] { player.show(4); }).what(), HasSubstr("'f'"));
    EXPECT_EQ(player.step(), 3u);
    expectSameImage(player.renderer().render(s), freshFrame(movingMesh(3.f, 5), s, o),
                    "step 3 after the refused step");
    EXPECT_THAT(catchError([&] { player.show(5); }).what(), HasSubstr("no time step 5"));
    EXPECT_EQ(player.step(), 3u);
}

TEST(SeriesPlayer, TheDefaultFieldOfTheFirstStepStaysAtEveryStep) {
    // Field "a" is constant at step 0 and varies at step 1: the default passes over it at step
    // 0 (pinField) and the player keeps "f" at step 1 rather than switching fields.
    const std::string dir = testing::scratchDir();
    for (int k = 0; k < 2; ++k) {
        Mesh m = movingMesh(float(k));
        Field a{"a", Association::Point, 1, std::vector<float>(m.pointCount(), 1.f)};
        if (k == 1)
            for (std::size_t i = 0; i < a.values.size(); ++i) a.values[i] = float(i);
        m.fields.insert(m.fields.begin(), a);
        writeMesh(m, dir + "/s_" + std::to_string(k) + ".vtu");
    }
    RendererOptions o;
    o.device = Device::Cpu;
    SeriesPlayer player(openMeshSeries(dir + "/s_*.vtu"), parseFieldSpec(""), o);
    EXPECT_EQ(player.field().name, "f");
    EXPECT_THAT(player.field().choice, HasSubstr("a holds one value here"));
    EXPECT_EQ(player.spec().name, "f");
    player.show(1);
    EXPECT_EQ(player.field().name, "f");
    const RenderSettings s = seriesFrameOf(player.mesh().bounds());
    expectSameImage(player.renderer().render(s), freshFrame(movingMesh(1.f), s, o), "step 1");
}

/// A data-parallel series read by parts: on 3 in-process ranks each reads only its run of each
/// step's parts of `file` (three steps of one geometry of `cells` cells), no step is prepared
/// anew, and every step's frame and the value range over the ranks are one process's.
void expectPlayedByPartsAsOneProcess(const std::string& file, std::uint64_t cells) {
    RendererOptions o;
    o.device = Device::Cpu;
    SeriesPlayer one(openMeshSeries(file), parseFieldSpec(""), o);
    EXPECT_FALSE(one.byParts());
    const RenderSettings s = seriesFrameOf(one.mesh().bounds());
    std::vector<Image> expected;
    std::vector<std::pair<float, float>> ranges;
    for (std::size_t i = 0; i < 3; ++i) {
        if (i) one.show(i);
        expected.push_back(one.renderer().render(s).image);
        const std::vector<float> v = one.stepValues(i);
        ranges.push_back(
            {*std::min_element(v.begin(), v.end()), *std::max_element(v.begin(), v.end())});
    }
    std::vector<Image> got;
    std::vector<std::uint64_t> rankCells(3), rebuilt(3);
    std::vector<std::pair<float, float>> rankRanges(3);
    InProcessGroup::run(3, [&](Communicator& comm) {
        RendererOptions ro = o;
        ro.communicator = &comm;
        SeriesPlayer player(openMeshSeries(file), parseFieldSpec(""), ro);
        ASSERT_TRUE(player.byParts());
        rankCells[comm.rank()] = player.mesh().cellCount();
        for (std::size_t i = 0; i < 3; ++i) {
            if (i)
                rebuilt[comm.rank()] +=
                    player.show(i, i + 1 < 3 ? std::optional(i + 1) : std::nullopt).rebuilt;
            RenderResult r = player.renderer().render(s);
            if (comm.rank() == 0) got.push_back(std::move(r.image));
        }
        const std::vector<float> v = player.stepValues(2);
        double range[2] = {*std::min_element(v.begin(), v.end()),
                           -*std::max_element(v.begin(), v.end())};
        comm.allReduce(range, ReduceOp::Min);
        rankRanges[comm.rank()] = {float(range[0]), float(-range[1])};
    });
    // Each rank read about a third of the cells, and no step was prepared anew.
    EXPECT_EQ(rankCells[0] + rankCells[1] + rankCells[2], cells);
    for (std::uint64_t c : rankCells) EXPECT_LT(c, cells / 2);
    EXPECT_EQ(rebuilt, std::vector<std::uint64_t>(3, 0));
    ASSERT_EQ(got.size(), 3u);
    for (std::size_t i = 0; i < 3; ++i) {
        const ImageComparison cmp = compareImages(toRgb8(expected[i]), toRgb8(got[i]));
        EXPECT_GE(cmp.ssim, 0.999) << "step " << i;
        EXPECT_LE(cmp.maxAbsDifference, 2.0) << "step " << i << ": " << differenceSummary(cmp);
    }
    EXPECT_GT(compareImages(toRgb8(got[0]), toRgb8(got[2])).maxAbsDifference, 10.0);
    for (const auto& [lo, hi] : rankRanges) {
        EXPECT_EQ(lo, ranges[2].first);
        EXPECT_EQ(hi, ranges[2].second);
    }
}

#ifdef UVR_HAVE_NETCDF
TEST(SeriesPlayer, DataParallelAnExodusSeriesIsReadByItsCellsAsOneProcessShowsIt) {
    // An Exodus II series: its cells are its parts.
    if (!exodusSupported()) GTEST_SKIP() << "built without netCDF";
    const Mesh grid = movingMesh(0.f, 8);
    const std::string file = testing::scratchDir() + "/grid.exo";
    testing::writeExodusFile(file,
                             testing::hexSeriesSpec(grid, 3, [&](std::size_t step, std::size_t n) {
                                 const Vec3f p = grid.points[n];
                                 return double(std::sin(3.f * p.x + float(step)) * p.y + p.z);
                             }));
    expectPlayedByPartsAsOneProcess(file, grid.cellCount());
}
#endif

/// Writes time step k (movingMesh(k, 8)) as 6 .vtu pieces in `dir` (each a run of its cells),
/// returning their names.
std::vector<std::string> writeStepPieces(const std::string& dir, int k) {
    const Mesh step = movingMesh(float(k), 8);
    std::vector<std::string> names;
    for (int piece = 0; piece < 6; ++piece) {
        const auto [first, end] = rankRun(step.cellCount(), piece, 6);
        names.push_back("s" + std::to_string(k) + "_" + std::to_string(piece) + ".vtu");
        writeMesh(meshPart(step, first, end).mesh, dir + "/" + names.back());
    }
    return names;
}

constexpr const char* kPvdHead =
    "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
constexpr const char* kPvdTail = "</Collection>\n</VTKFile>\n";

TEST(SeriesPlayer, DataParallelACollectionOfPvtuStepsIsReadByPiecesAsOneProcessShowsIt) {
    // A parallel simulation's output: a .pvd listing one .pvtu a step, each of 6 pieces.
    const std::string dir = testing::scratchDir();
    std::string pvd = kPvdHead;
    for (int k = 0; k < 3; ++k) {
        std::string pvtu =
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"0.1\">\n"
            "<PUnstructuredGrid GhostLevel=\"0\">\n<PPointData><PDataArray type=\"Float32\" "
            "Name=\"f\"/></PPointData>\n<PPoints><PDataArray type=\"Float32\" "
            "NumberOfComponents=\"3\"/></PPoints>\n";
        for (const std::string& name : writeStepPieces(dir, k))
            pvtu += "<Piece Source=\"" + name + "\"/>\n";
        const std::string name = "s" + std::to_string(k) + ".pvtu";
        testing::writeFile(dir + "/" + name, pvtu + "</PUnstructuredGrid>\n</VTKFile>\n");
        pvd += "<DataSet timestep=\"" + std::to_string(k) + "\" file=\"" + name + "\"/>\n";
    }
    const std::string file = testing::writeFile(dir + "/run.pvd", pvd + kPvdTail);
    EXPECT_EQ(openMeshSeries(file)->partCount(1), 6u);
    expectPlayedByPartsAsOneProcess(file, movingMesh(0.f, 8).cellCount());
}

TEST(SeriesPlayer, DataParallelACollectionListingEachTimesPartsIsReadByPartsAsOneProcessShowsIt) {
    // ParaView's own parallel output: a .pvd listing each time's parts as DataSets of one
    // timestep (part="0", "1", ...), each part a .vtu of its own.
    const std::string dir = testing::scratchDir();
    std::string pvd = kPvdHead;
    for (int k = 0; k < 3; ++k) {
        const std::vector<std::string> names = writeStepPieces(dir, k);
        for (std::size_t part = 0; part < names.size(); ++part)
            pvd += "<DataSet timestep=\"" + std::to_string(k) + "\" part=\"" +
                   std::to_string(part) + "\" file=\"" + names[part] + "\"/>\n";
    }
    const std::string file = testing::writeFile(dir + "/parts.pvd", pvd + kPvdTail);
    const std::unique_ptr<MeshSeries> series = openMeshSeries(file);
    EXPECT_EQ(series->partCount(1), 6u);
    // A run of parts holds their cells and points, ids in the whole step's order.
    const MeshPart part = series->readPart(1, 2, 4);
    const Mesh whole = series->readStep(1);
    EXPECT_GT(part.mesh.cellCount(), 0u);
    EXPECT_LT(part.mesh.cellCount(), whole.cellCount());
    EXPECT_TRUE(std::is_sorted(part.cellIds.begin(), part.cellIds.end()));
    EXPECT_EQ(part.cellIds.size(), part.mesh.cellCount());
    EXPECT_EQ(part.pointIds.size(), part.mesh.points.size());
    EXPECT_EQ(catchError([&] { series->readPart(1, 5, 7); }).kind(), ErrorKind::Argument);
    expectPlayedByPartsAsOneProcess(file, movingMesh(0.f, 8).cellCount());
}

}  // namespace
}  // namespace uvr
