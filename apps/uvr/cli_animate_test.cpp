// SPDX-License-Identifier: MIT
// Time series on the command line: `uvr animate`, `render --time/--step-index` and the time
// steps `uvr info` lists (issue 14).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_test_support.h"
#include "test_support.h"
#include "uvr/annotate/font.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/mesh/io/time_series.h"
#include "uvr/mesh/io/vtkhdf.h"
#include "uvr/render/image.h"

namespace uvr {
namespace {

using cli_testing::CliRun;
using cli_testing::expectOneLineError;
using cli_testing::uvr;

/// Three steps of a generated box, a blob moving along x (point field "blob"), as step_K.vtu
/// and run.pvd with times 0, 0.5 and 1.
void writeSeries(const std::string& dir) {
    ASSERT_EQ(uvr("-q generate box --cells 4000 --fields linear -o " + dir + "/base.vtu", dir).code,
              0);
    Mesh m = readMesh(dir + "/base.vtu");
    std::string pvd = "<VTKFile type=\"Collection\"><Collection>\n";
    for (int k = 0; k < 3; ++k) {
        Field blob{"blob", Association::Point, 1, {}};
        for (const Vec3f& p : m.points) {
            const float dx = p.x - 0.2f - 0.3f * k, dy = p.y - 0.5f, dz = p.z - 0.5f;
            blob.values.push_back(std::exp(-(dx * dx + dy * dy + dz * dz) / 0.03f));
        }
        Mesh step = m;
        step.fields.push_back(std::move(blob));
        writeMesh(step, dir + "/step_" + std::to_string(k) + ".vtu");
        pvd += "<DataSet timestep=\"" + std::to_string(0.5 * k) + "\" file=\"step_" +
               std::to_string(k) + ".vtu\"/>\n";
    }
    testing::writeFile(dir + "/run.pvd", pvd + "</Collection></VTKFile>\n");
}

const std::string kLook = " --field blob --size 64x48 --device cpu --opacity 0:0,1:0.8 --range 0,1";

TEST(CliAnimate, EveryStepIsTheFrameRenderWouldDrawWithTheGeometryPreparedOnce) {
    const std::string dir = testing::scratchDir();
    writeSeries(dir);
    const CliRun a = uvr("animate run.pvd -o frames" + kLook, dir);
    ASSERT_EQ(a.code, 0) << a.err;
    EXPECT_NE(a.err.find("step 1 (time 0.5): values refreshed"), std::string::npos) << a.err;
    EXPECT_NE(a.err.find("step 2 (time 1): values refreshed"), std::string::npos) << a.err;
    EXPECT_EQ(a.err.find("new geometry"), std::string::npos) << a.err;
    EXPECT_NE(a.err.find("wrote 3 frames"), std::string::npos) << a.err;
    std::string previous;
    for (int k = 0; k < 3; ++k) {
        SCOPED_TRACE(k);
        const std::string frame =
            testing::readFile(dir + "/frames/frame_000" + std::to_string(k) + ".png");
        ASSERT_FALSE(frame.empty());
        EXPECT_NE(frame, previous);  // the blob moves
        previous = frame;
        // The same PNG as one render of that step.
        const std::string one = "one" + std::to_string(k) + ".png";
        ASSERT_EQ(
            uvr("-q render run.pvd --step-index " + std::to_string(k) + " -o " + one + kLook, dir)
                .code,
            0);
        EXPECT_EQ(testing::readFile(dir + "/" + one), frame);
    }
    // --time snaps to the last step at or before it; a numbered series is the same steps.
    ASSERT_EQ(uvr("-q render run.pvd --time 0.9 -o t.png" + kLook, dir).code, 0);
    EXPECT_EQ(testing::readFile(dir + "/t.png"), testing::readFile(dir + "/frames/frame_0001.png"));
    const CliRun b = uvr("-q animate 'step_*.vtu' -o series --steps 1: --prefix s" + kLook, dir);
    ASSERT_EQ(b.code, 0) << b.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/series/s0000.png"));
    EXPECT_EQ(testing::readFile(dir + "/series/s0002.png"),
              testing::readFile(dir + "/frames/frame_0002.png"));
    // Without --range, one range over the steps: the log says it.
    const CliRun c = uvr("animate run.pvd -o auto --field blob --size 32x32 --device cpu", dir);
    ASSERT_EQ(c.code, 0) << c.err;
    EXPECT_NE(c.err.find("value range over the steps: [0"), std::string::npos) << c.err;
}

TEST(CliAnimate, InfoListsTheStepsWithTheirRanges) {
    const std::string dir = testing::scratchDir();
    writeSeries(dir);
    const CliRun info = uvr("-q info --json run.pvd", dir);
    ASSERT_EQ(info.code, 0) << info.err;
    const nlohmann::json j = nlohmann::json::parse(info.out);
    ASSERT_EQ(j["time_steps"].size(), 3u);
    for (int k = 0; k < 3; ++k) {
        const nlohmann::json& s = j["time_steps"][k];
        EXPECT_EQ(s["index"], k);
        EXPECT_DOUBLE_EQ(s["time"].get<double>(), 0.5 * k);
        EXPECT_TRUE(s["same_geometry"].get<bool>());
        EXPECT_EQ(s["source"], "step_" + std::to_string(k) + ".vtu");  // relative to the .pvd
        const nlohmann::json& blob = s["fields"][1];
        EXPECT_EQ(blob["name"], "blob");
        EXPECT_GT(blob["range"][1].get<double>(), 0.5);  // the blob is inside the box
    }
    const CliRun text = uvr("-q info run.pvd --step-index 2", dir);
    ASSERT_EQ(text.code, 0) << text.err;
    EXPECT_NE(text.out.find("time steps: 3 (time 0 to 1)"), std::string::npos) << text.out;
    // A file without time steps lists none.
    const CliRun plain = uvr("-q info --json base.vtu", dir);
    EXPECT_FALSE(nlohmann::json::parse(plain.out).contains("time_steps"));
}

TEST(CliAnimate, GenerateWritesATimeSeriesOfOneGeometry) {
    const std::string dir = testing::scratchDir();
    ASSERT_EQ(
        uvr("-q generate box --cells 3000 --fields jet,linear --steps 3 --dt 0.5 -o t.uvrm", dir)
            .code,
        0);
    ASSERT_EQ(uvr("-q generate box --cells 3000 --fields jet,linear -o one.uvrm", dir).code, 0);
    EXPECT_EQ(testing::readFile(dir + "/t_0000.uvrm"),
              testing::readFile(dir + "/one.uvrm"));  // time 0: the plain mesh
    const CliRun info = uvr("-q info --json t.pvd", dir);
    ASSERT_EQ(info.code, 0) << info.err;
    const nlohmann::json j = nlohmann::json::parse(info.out);
    ASSERT_EQ(j["time_steps"].size(), 3u);
    EXPECT_DOUBLE_EQ(j["time_steps"][2]["time"].get<double>(), 1.0);
    for (const auto& s : j["time_steps"]) EXPECT_TRUE(s["same_geometry"].get<bool>());
    // The fields turn: linear x + 2y - z at the point turned by -t about y.
    const Mesh m0 = readMesh(dir + "/t_0000.uvrm"), m2 = readMesh(dir + "/t_0002.uvrm");
    const Vec3f p = m2.points[7];
    const float c = std::cos(1.f), s = std::sin(1.f);
    const float x = c * p.x + s * p.z, z = -s * p.x + c * p.z;
    EXPECT_NEAR(m2.fields[1].values[7], x + 2.f * p.y - z, 1e-5f);
    EXPECT_NE(m0.fields[0].values, m2.fields[0].values);
    // A constant field has no common range: every frame as `uvr render` draws it (a warning).
    ASSERT_EQ(uvr("-q generate box --cells 2000 --fields constant --steps 2 -o c.uvrm", dir).code,
              0);
    const CliRun constant = uvr("animate c.pvd -o cf --size 32x32 --device cpu", dir);
    EXPECT_EQ(constant.code, 0) << constant.err;
    EXPECT_NE(constant.err.find("one value or none"), std::string::npos) << constant.err;
    EXPECT_TRUE(std::filesystem::exists(dir + "/cf/frame_0001.png"));
    // The same series as one temporal VTKHDF file: the geometry once, the same values per step.
    if (!vtkHdfSupported()) GTEST_SKIP() << "built without HDF5";
    ASSERT_EQ(
        uvr("-q generate box --cells 3000 --fields jet,linear --steps 3 --dt 0.5 -o t.vtkhdf", dir)
            .code,
        0);
    auto series = openMeshSeries(dir + "/t.vtkhdf");
    ASSERT_EQ(series->times(), (std::vector<double>{0.0, 0.5, 1.0}));
    const Mesh h0 = series->readStep(0);
    EXPECT_TRUE(sameGeometry(h0, m0));
    EXPECT_EQ(h0.fields[0].values, m0.fields[0].values);
    const auto fields2 = series->readFieldsIfSameGeometry(2, h0);  // the values alone
    ASSERT_TRUE(fields2.has_value());
    ASSERT_EQ(fields2->size(), 2u);
    EXPECT_EQ((*fields2)[0].values, m2.fields[0].values);
    EXPECT_EQ((*fields2)[1].values, m2.fields[1].values);
    const std::uint64_t oneStep = std::filesystem::file_size(dir + "/t_0000.uvrm");
    EXPECT_LT(std::filesystem::file_size(dir + "/t.vtkhdf"), 2 * oneStep);  // not 3 geometries
}

TEST(CliAnimate, ConvertWritesEveryTimeStepOrThePickedOne) {
    // Issue 35: `convert run.pvd run.vtkhdf` wrote step 0 alone and exited 0.
    const std::string dir = testing::scratchDir();
    ASSERT_EQ(
        uvr("-q generate box --cells 2000 --fields jet --steps 3 --dt 0.1 -o t.uvrm", dir).code, 0);
    // The .pvd's times as written: the shortest text that reads back exactly.
    EXPECT_NE(testing::readFile(dir + "/t.pvd").find("timestep=\"0.1\""), std::string::npos);
    // Every step as a file a step and a .pvd.
    const CliRun all = uvr("convert t.pvd c.vtu", dir);
    ASSERT_EQ(all.code, 0) << all.err;
    EXPECT_NE(all.err.find("3 time steps: converting them all"), std::string::npos) << all.err;
    auto converted = openMeshSeries(dir + "/c.pvd");
    ASSERT_EQ(converted->times(), (std::vector<double>{0.0, 0.1, 0.2}));
    for (std::size_t k = 0; k < 3; ++k) {
        char name[32];
        std::snprintf(name, sizeof name, "/t_%04zu.uvrm", k);
        EXPECT_EQ(converted->readStep(k).fields[0].values, readMesh(dir + name).fields[0].values)
            << k;
    }
    // --compress reaches every step's file.
    ASSERT_EQ(uvr("-q convert t.pvd raw.vtu --compress none", dir).code, 0);
    EXPECT_EQ(testing::readFile(dir + "/raw_0001.vtu").find("compressor="), std::string::npos);
    EXPECT_NE(testing::readFile(dir + "/c_0001.vtu").find("compressor="), std::string::npos);
    // One step when asked.
    ASSERT_EQ(uvr("-q convert t.pvd two.vtu --step-index 2", dir).code, 0);
    EXPECT_EQ(readMesh(dir + "/two.vtu").fields[0].values,
              readMesh(dir + "/t_0002.uvrm").fields[0].values);
    EXPECT_FALSE(std::filesystem::exists(dir + "/two.pvd"));
    if (!vtkHdfSupported()) GTEST_SKIP() << "built without HDF5";
    // One temporal .vtkhdf of the one geometry.
    ASSERT_EQ(uvr("-q convert t.pvd t.vtkhdf", dir).code, 0);
    auto hdf = openMeshSeries(dir + "/t.vtkhdf");
    ASSERT_EQ(hdf->times(), (std::vector<double>{0.0, 0.1, 0.2}));
    EXPECT_EQ(hdf->readStep(2).fields[0].values, readMesh(dir + "/t_0002.uvrm").fields[0].values);
    // Steps of other geometries do not fit one .vtkhdf: refused, nothing written.
    ASSERT_EQ(uvr("-q generate box --cells 900 --fields jet -o small.vtu", dir).code, 0);
    testing::writeFile(dir + "/mixed.pvd",
                       "<VTKFile type=\"Collection\"><Collection>\n"
                       "<DataSet timestep=\"0\" file=\"t_0000.uvrm\"/>\n"
                       "<DataSet timestep=\"1\" file=\"small.vtu\"/>\n"
                       "</Collection></VTKFile>\n");
    expectOneLineError(uvr("-q convert mixed.pvd m.vtkhdf", dir),
                       {"time step 1 has other points or cells than step 0", ".pvd"});
    EXPECT_FALSE(std::filesystem::exists(dir + "/m.vtkhdf"));
    ASSERT_EQ(uvr("-q convert mixed.pvd m.uvrm", dir).code, 0);  // a file a step: fine
    EXPECT_EQ(readMesh(dir + "/m_0001.uvrm").cellCount(), readMesh(dir + "/small.vtu").cellCount());
}

TEST(CliAnimate, TheTimeLabelIsWrittenAtTheTopLeft) {
    // Issue 35: ParaView's Annotate Time.
    if (!textEngineAvailable()) GTEST_SKIP() << "built without text (UVR_ENABLE_TEXT=OFF)";
    const std::string dir = testing::scratchDir();
    writeSeries(dir);
    const std::string look =
        " --field blob --size 160x128 --device cpu --opacity 0:0,1:0.8 --range 0,1 -q";
    ASSERT_EQ(uvr("animate run.pvd -o plain" + look, dir).code, 0);
    const CliRun r = uvr("animate run.pvd -o labelled --time-label" + look, dir);
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* frame : {"frame_0000.png", "frame_0002.png"}) {
        const Image a = readPng(dir + "/plain/" + frame), b = readPng(dir + "/labelled/" + frame);
        int topLeft = 0, rest = 0;
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width; ++x) {
                const Vec4f p = a.at(x, y), q = b.at(x, y);
                const bool differs = p.x != q.x || p.y != q.y || p.z != q.z || p.w != q.w;
                (x < a.width * 3 / 4 && y < a.height * 3 / 8 ? topLeft : rest) += differs;
            }
        EXPECT_GT(topLeft, 100) << frame;
        EXPECT_EQ(rest, 0) << frame;
    }
    // Different times write different labels.
    EXPECT_NE(testing::readFile(dir + "/labelled/frame_0000.png"),
              testing::readFile(dir + "/labelled/frame_0002.png"));
    expectOneLineError(uvr("-q animate run.pvd -o tiny --time-label --size 64x48", dir),
                       {"--time-label needs frames of at least 128x128"});
}

TEST(CliAnimate, BadStepsAndOutputsAreRefusedBeforeRendering) {
    const std::string dir = testing::scratchDir();
    writeSeries(dir);
    expectOneLineError(uvr("animate run.pvd -o f --steps 5:9", dir), {"--steps 5:9", "0 to 2"});
    expectOneLineError(uvr("animate run.pvd -o f --steps a:b", dir), {"--steps a:b"});
    expectOneLineError(uvr("animate run.pvd -o f --steps 0:2:0", dir), {"STRIDE is 0"});
    expectOneLineError(uvr("animate run.pvd -o f --range 0,1 --range-per-step", dir),
                       {"--range-per-step"});
    expectOneLineError(uvr("animate run.pvd -o base.vtu", dir), {"base.vtu", "not a folder"});
    expectOneLineError(uvr("animate run.pvd -o f --prefix a/b", dir), {"--prefix"});
    expectOneLineError(uvr("animate 'none_*.vtu' -o f", dir), {"no file matches"});
    expectOneLineError(uvr("render run.pvd -o x.png --step-index 7", dir),
                       {"--step-index 7", "3 time steps"});
    const CliRun both = uvr("render run.pvd -o x.png --step-index 1 --time 0", dir);
    EXPECT_EQ(both.code, 2);
    EXPECT_NE(both.err.find("excludes"), std::string::npos) << both.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/f"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/x.png"));
}

TEST(CliAnimate, CollectionsNamingEachOtherAreOneLineErrors) {
    // cycA.pvd lists cycB.pvd, which lists cycA.pvd: `uvr info cycA.pvd` died of a stack
    // overflow (SIGSEGV), as did every command reaching the step.
    const std::string dir = testing::scratchDir();
    writeSeries(dir);
    auto collection = [&](const std::string& name, const std::string& files) {
        testing::writeFile(dir + "/" + name, "<VTKFile type=\"Collection\"><Collection>\n" + files +
                                                 "</Collection></VTKFile>\n");
    };
    collection("cycA.pvd", "<DataSet timestep=\"0\" file=\"cycB.pvd\"/>\n");
    collection("cycB.pvd", "<DataSet timestep=\"0\" file=\"cycA.pvd\"/>\n");
    collection("later.pvd",
               "<DataSet timestep=\"0\" file=\"step_0.vtu\"/>\n"
               "<DataSet timestep=\"1\" file=\"./later.pvd\"/>\n");
    collection("mixed.pvd",
               "<DataSet timestep=\"0\" file=\"step_0.vtu\"/>\n"
               "<DataSet timestep=\"1\" file=\"cycA.pvd\"/>\n");
    const std::string cycle = "is itself a ParaView collection (.pvd)";
    expectOneLineError(uvr("info cycA.pvd", dir), {"cycA.pvd: line 2: ", "cycB.pvd", cycle});
    expectOneLineError(uvr("render cycA.pvd -o a.png" + kLook, dir), {"cycB.pvd", cycle});
    expectOneLineError(uvr("render mixed.pvd --time 1 -o b.png" + kLook, dir),
                       {"mixed.pvd: line 3: ", "cycA.pvd", cycle});
    expectOneLineError(uvr("info later.pvd", dir),
                       {"later.pvd: line 3: a DataSet names the .pvd itself"});
    EXPECT_FALSE(std::filesystem::exists(dir + "/a.png"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/b.png"));
}

}  // namespace
}  // namespace uvr
