// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/time_series.h"

#include <gmock/gmock.h>

#include <cmath>
#include <filesystem>

#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/mesh/io/mesh_reader.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;
using uvr::testing::catchError;

/// A small hexahedral grid whose point field "f" is x + 10 t, and a cell field "c" = t.
Mesh stepMesh(double t, int n = 3) {
    Mesh m = testing::makeHexGrid(n, 0.f, 1.f, [t](Vec3f p) { return p.x + 10.f * float(t); });
    m.fields[0].name = "f";
    Field c{"c", Association::Cell, 1, std::vector<float>(m.cellCount(), float(t))};
    m.fields.push_back(std::move(c));
    return m;
}

float firstValue(const std::vector<Field>& fields, const std::string& name) {
    for (const Field& f : fields)
        if (f.name == name) return f.values.at(0);
    ADD_FAILURE() << "no field " << name;
    return NAN;
}

TEST(TimeSeries, AnyOtherFileIsOneStepAtTimeZero) {
    const std::string dir = testing::scratchDir();
    writeMesh(stepMesh(0.5), dir + "/one.vtu");
    auto s = openMeshSeries(dir + "/one.vtu");
    ASSERT_EQ(s->stepCount(), 1u);
    EXPECT_EQ(s->times()[0], 0.0);
    EXPECT_EQ(s->stepSource(0), dir + "/one.vtu");
    const Mesh m = s->readStep(0);
    EXPECT_FLOAT_EQ(firstValue(m.fields, "c"), 0.5f);
    EXPECT_THAT(catchError([&] { s->readStep(1); }).what(), HasSubstr("no time step 1"));
}

TEST(TimeSeries, PvdStepsAreOrderedByTimeAndPartsOfOneStepMerge) {
    const std::string dir = testing::scratchDir();
    for (int k = 0; k < 3; ++k) writeMesh(stepMesh(k), dir + "/s" + std::to_string(k) + ".vtu");
    writeMesh(stepMesh(7, 2), dir + "/extra.vtu");
    // Listed out of order, with '+' and spaces in a time as VTK accepts them, and a step of two
    // parts (a different geometry).
    testing::writeFile(dir + "/run.pvd", R"(<?xml version="1.0"?>
<VTKFile type="Collection" version="0.1">
  <Collection>
    <DataSet timestep="2.5" part="0" file="s2.vtu"/>
    <DataSet timestep=" +0.5" part="0" file="s0.vtu"/>
    <DataSet timestep="1e0" part="0" file="s1.vtu"/>
    <DataSet timestep="9" part="0" file="s1.vtu"/>
    <DataSet timestep="9" part="1" file="extra.vtu"/>
  </Collection>
</VTKFile>
)");
    auto s = openMeshSeries(dir + "/run.pvd");
    ASSERT_EQ(s->stepCount(), 4u);
    EXPECT_EQ(s->times(), (std::vector<double>{0.5, 1.0, 2.5, 9.0}));
    EXPECT_EQ(s->stepSource(3), dir + "/s1.vtu, " + dir + "/extra.vtu");
    const Mesh first = s->readStep(0);
    EXPECT_FLOAT_EQ(firstValue(first.fields, "c"), 0.f);
    // Same geometry: the fields alone, those the whole read gives.
    const auto fields = s->readFieldsIfSameGeometry(2, first);
    ASSERT_TRUE(fields.has_value());
    EXPECT_FLOAT_EQ(firstValue(*fields, "c"), 2.f);
    EXPECT_FLOAT_EQ(firstValue(*fields, "f"), firstValue(s->readStep(2).fields, "f"));
    // Two parts: another geometry, merged with the second part's indices offset.
    EXPECT_FALSE(s->readFieldsIfSameGeometry(3, first).has_value());
    const Mesh merged = s->readStep(3);
    const Mesh extra = stepMesh(7, 2);
    EXPECT_EQ(merged.cellCount(), first.cellCount() + extra.cellCount());
    EXPECT_EQ(merged.pointCount(), first.pointCount() + extra.pointCount());
    EXPECT_EQ(merged.cellIndices.back(), extra.cellIndices.back() + first.pointCount());
    EXPECT_FLOAT_EQ(merged.fields[1].values.back(), 7.f);
    // readMesh reads the first step of a .pvd, also of one named otherwise.
    EXPECT_TRUE(sameGeometry(readMesh(dir + "/run.pvd"), first));
    std::filesystem::copy_file(dir + "/run.pvd", dir + "/run.xml");
    EXPECT_TRUE(sameGeometry(readMesh(dir + "/run.xml"), first));
    EXPECT_EQ(openMeshSeries(dir + "/run.xml")->stepCount(), 4u);
    // ParaView's snapping: the last step at or before t.
    EXPECT_EQ(stepAtTime(s->times(), 0.0), 0u);
    EXPECT_EQ(stepAtTime(s->times(), 2.4), 1u);
    EXPECT_EQ(stepAtTime(s->times(), 2.5), 2u);
    EXPECT_EQ(stepAtTime(s->times(), 100), 3u);
    EXPECT_THAT(catchError([&] { stepAtTime(s->times(), NAN); }).what(), HasSubstr("finite"));
}

TEST(TimeSeries, NumberedFilesFollowTheirNumbers) {
    const std::string dir = testing::scratchDir();
    for (int k : {10, 2, 1}) writeMesh(stepMesh(k), dir + "/flow_" + std::to_string(k) + ".vtu");
    writeMesh(stepMesh(99), dir + "/flow_x.vtu");  // no number: not a step
    auto s = openMeshSeries(dir + "/flow_*.vtu");
    ASSERT_EQ(s->stepCount(), 3u);
    EXPECT_EQ(s->times(), (std::vector<double>{0, 1, 2}));
    EXPECT_EQ(s->stepSource(2), dir + "/flow_10.vtu");
    EXPECT_FLOAT_EQ(firstValue(s->readStep(1).fields, "c"), 2.f);
}

TEST(TimeSeries, BadCollectionsAndPatternsAreClearErrors) {
    const std::string dir = testing::scratchDir();
    writeMesh(stepMesh(0), dir + "/a.vtu");
    auto refused = [&](const std::string& name, const std::string& text) {
        testing::writeFile(dir + "/" + name, text);
        return std::string(catchError([&] { openMeshSeries(dir + "/" + name); }).what());
    };
    EXPECT_THAT(refused("x.pvd", "<Collection></Collection>"),
                HasSubstr("expected <VTKFile type=\"Collection\">"));
    EXPECT_THAT(refused("y.pvd",
                        "<VTKFile type=\"Collection\"><Collection>\n<DataSet "
                        "timestep=\"0\"/></Collection></VTKFile>"),
                HasSubstr("line 2: <DataSet> without a file attribute"));
    EXPECT_THAT(refused("z.pvd",
                        "<VTKFile type=\"Collection\"><Collection><DataSet "
                        "timestep=\"soon\" file=\"a.vtu\"/></Collection></VTKFile>"),
                HasSubstr("timestep=\"soon\""));
    EXPECT_THAT(refused("e.pvd", "<VTKFile type=\"Collection\"><Collection/></VTKFile>"),
                HasSubstr("lists no <DataSet"));
    EXPECT_THAT(refused("t.pvd", "<VTKFile type=\"Collection\"><Collection><DataSet"),
                HasSubstr("t.pvd: line 1"));
    EXPECT_THAT(refused("self.pvd",
                        "<VTKFile type=\"Collection\"><Collection><DataSet "
                        "file=\"self.pvd\"/></Collection></VTKFile>"),
                HasSubstr("names the .pvd itself"));
    // A missing step file is named when that step is read.
    testing::writeFile(dir + "/m.pvd",
                       "<VTKFile type=\"Collection\"><Collection><DataSet "
                       "file=\"a.vtu\"/><DataSet file=\"gone.vtu\"/>"
                       "</Collection></VTKFile>");
    auto s = openMeshSeries(dir + "/m.pvd");
    EXPECT_THAT(catchError([&] { s->readStep(1); }).what(), HasSubstr("gone.vtu"));
    EXPECT_THAT(catchError([&] { openMeshSeries(dir + "/none_*.vtu"); }).what(),
                HasSubstr("no file matches"));
    EXPECT_THAT(catchError([&] { openMeshSeries(dir + "/a*_*.vtu"); }).what(),
                HasSubstr("one '*'"));
    writeMesh(stepMesh(0), dir + "/d_1.vtu");
    writeMesh(stepMesh(0), dir + "/d_01.vtu");
    EXPECT_THAT(catchError([&] { openMeshSeries(dir + "/d_*.vtu"); }).what(),
                HasSubstr("two files have the number 1"));
    EXPECT_THAT(catchError([&] { openMeshSeries(dir + "/missing.vtu"); }).what(),
                HasSubstr("missing.vtu"));
}

TEST(TimeSeries, CollectionsNamingCollectionsAreRefusedWhereverTheStepIsRead) {
    // Two collections naming each other recursed readMesh -> openMeshSeries -> readStep ->
    // readMesh until the stack overflowed (SIGSEGV), from `uvr info`, `render --time`, Python
    // and a viewer tab moving to the step alike.
    namespace fs = std::filesystem;
    const std::string dir = testing::scratchDir();
    writeMesh(stepMesh(0), dir + "/a.vtu");
    auto collection = [&](const std::string& name, const std::vector<std::string>& files) {
        std::string text = "<VTKFile type=\"Collection\"><Collection>\n";
        for (std::size_t k = 0; k < files.size(); ++k)
            text += "<DataSet timestep=\"" + std::to_string(k) + "\" file=\"" + files[k] + "\"/>\n";
        return testing::writeFile(dir + "/" + name, text + "</Collection></VTKFile>\n");
    };
    const std::string a = collection("cycA.pvd", {"cycB.pvd"});
    collection("cycB.pvd", {"cycA.pvd"});
    const std::string expected =
        a + ": line 2: the step's file " + dir + "/cycB.pvd is itself a ParaView collection (.pvd)";
    EXPECT_THAT(catchError([&] { readMesh(a); }).what(), HasSubstr(expected));
    EXPECT_EQ(catchError([&] { readMesh(a); }).kind(), ErrorKind::Parse);
    EXPECT_THAT(catchError([&] { openMeshSeries(a)->readStep(0); }).what(), HasSubstr(expected));
    // A later step, as a viewer moving between steps reads it, whole or fields only.
    const std::string later = collection("later.pvd", {"a.vtu", "cycA.pvd"});
    auto s = openMeshSeries(later);
    const Mesh first = s->readStep(0);
    EXPECT_THAT(catchError([&] { s->readStep(1); }).what(),
                HasSubstr(later + ": line 3: the step's file " + a + " is itself a ParaView"));
    EXPECT_THAT(catchError([&] { s->readFieldsIfSameGeometry(1, first); }).what(),
                HasSubstr("is itself a ParaView collection"));
    // A numbered series of collections.
    collection("c_1.pvd", {"a.vtu"});
    EXPECT_THAT(catchError([&] { openMeshSeries(dir + "/c_*.pvd")->readStep(0); }).what(),
                HasSubstr("file " + dir + "/c_1.pvd: the step's file " + dir +
                          "/c_1.pvd is itself a ParaView collection"));
    // Naming itself through './', 'sub/../' (whether sub exists or not) or a hard link.
    fs::create_directories(dir + "/sub");
    for (const std::string self : {"./dot.pvd", "sub/../dot.pvd", "none/../dot.pvd"}) {
        SCOPED_TRACE(self);
        const std::string path = collection("dot.pvd", {"a.vtu", self});
        EXPECT_THAT(catchError([&] { openMeshSeries(path); }).what(),
                    HasSubstr(path + ": line 3: a DataSet names the .pvd itself"));
    }
    const std::string hard = collection("hard.pvd", {"alias.pvd"});
    fs::create_hard_link(hard, dir + "/alias.pvd");
    EXPECT_THAT(catchError([&] { readMesh(hard); }).what(),
                HasSubstr(hard + ": line 2: a DataSet names the .pvd itself"));
    // A series pattern as a DataSet.
    const std::string pattern = collection("pattern.pvd", {"run_*.vtu"});
    EXPECT_THAT(catchError([&] { openMeshSeries(pattern); }).what(),
                HasSubstr(pattern + ": line 2: <DataSet file=\"run_*.vtu\">: a file series "
                                    "pattern ('*'); a collection's DataSets are single datasets"));
}

}  // namespace
}  // namespace uvr
