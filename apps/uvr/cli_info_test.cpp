// SPDX-License-Identifier: MIT
// End-to-end tests of what `uvr info` reads and prints, and of the default field every command
// chooses (issue 15: one rule whatever the format, the association named everywhere).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_test_support.h"
#include "test_support.h"

namespace uvr {
namespace {

using cli_testing::CliRun;
using cli_testing::expectOneLineError;
using cli_testing::uvr;

/// Cell data `pressure` and `GlobalElementId` first, then point data `GlobalNodeId` and
/// `pressure`: the layout of the files the issue names.
const std::string kCrashLike = cli_testing::fiveTetCubeVtk(
    "CELL_DATA 5\nSCALARS GlobalElementId int 1\nLOOKUP_TABLE default\n1 2 3 4 5\n"
    "SCALARS pressure float 1\nLOOKUP_TABLE default\n10 20 30 40 50\n"
    "POINT_DATA 8\nSCALARS GlobalNodeId int 1\nLOOKUP_TABLE default\n1 2 3 4 5 6 7 8\n"
    "SCALARS pressure float 1\nLOOKUP_TABLE default\n0 1 2 3 4 5 6 7\n");

/// The field `info --json` marks as the default, as "name:association".
std::string defaultOf(const nlohmann::json& info) {
    std::string found;
    for (const auto& f : info["fields"])
        if (f["default"].get<bool>()) {
            EXPECT_TRUE(found.empty()) << "two defaults in " << info["fields"];
            found = f["name"].get<std::string>() + ":" + f["association"].get<std::string>();
        }
    return found;
}

TEST(CliFields, DefaultIsThePhysicalPointFieldInEveryFormatAndSaysSo) {
    const std::string dir = testing::scratchDir();
    const std::string vtk = testing::writeFile(dir + "/crash.vtk", kCrashLike);
    ASSERT_EQ(uvr("-q convert " + vtk + " " + dir + "/crash.vtu", dir).code, 0);
    ASSERT_EQ(uvr("-q convert " + vtk + " " + dir + "/crash.uvrm", dir).code, 0);
    for (const char* name : {"crash.vtk", "crash.vtu", "crash.uvrm"}) {
        SCOPED_TRACE(name);
        const std::string file = dir + "/" + name;
        const CliRun info = uvr("-q info --json " + file, dir);
        ASSERT_EQ(info.code, 0) << info.err;
        EXPECT_EQ(defaultOf(nlohmann::json::parse(info.out)), "pressure:point");
        const CliRun text = uvr("-q info " + file, dir);
        const std::size_t line = text.out.find("  pressure                 point 1 component ");
        ASSERT_NE(line, std::string::npos) << text.out;
        const std::string pressure = text.out.substr(line, text.out.find('\n', line) - line);
        EXPECT_NE(pressure.find("(default)"), std::string::npos) << text.out;
        // The render log and --stats name the field and its association.
        const std::string stats = dir + "/" + name + ".json";
        const CliRun render = uvr("render " + file + " --size 16x16 --device cpu -o " + dir + "/" +
                                      name + ".png --stats " + stats,
                                  dir);
        ASSERT_EQ(render.code, 0) << render.err;
        EXPECT_NE(render.err.find("rendering pressure (point data), the default: the first "
                                  "point-data scalar field"),
                  std::string::npos)
            << render.err;
        std::ifstream in(stats);
        const auto j = nlohmann::json::parse(in);
        EXPECT_EQ(j["field"], "pressure");
        EXPECT_EQ(j["field_association"], "point");
        EXPECT_EQ(j["range"][1].get<float>(), 7.f);
    }
}

TEST(CliFields, ANameOfPointAndCellDataRendersThePointDataAndNamesTheOther) {
    const std::string dir = testing::scratchDir();
    const std::string vtk = testing::writeFile(dir + "/crash.vtk", kCrashLike);
    const std::string stats = dir + "/s.json";
    const CliRun r = uvr("render " + vtk + " --field pressure --size 16x16 --device cpu -o " + dir +
                             "/p.png --stats " + stats,
                         dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("--field pressure:cell selects it"), std::string::npos) << r.err;
    std::ifstream in(stats);
    EXPECT_EQ(nlohmann::json::parse(in)["field_association"], "point");
    const CliRun cell = uvr("-q render " + vtk + " --field pressure:cell --size 16x16 -o " + dir +
                                "/c.png --stats " + dir + "/c.json",
                            dir);
    ASSERT_EQ(cell.code, 0) << cell.err;
    std::ifstream cin(dir + "/c.json");
    const auto j = nlohmann::json::parse(cin);
    EXPECT_EQ(j["field_association"], "cell");
    EXPECT_EQ(j["range"][1].get<float>(), 50.f);
}

TEST(CliFields, IdArraysAreRenderedOnlyWhenNamedOrAlone) {
    const std::string dir = testing::scratchDir();
    const std::string ids = testing::writeFile(
        dir + "/ids.vtk",
        cli_testing::fiveTetCubeVtk(
            "POINT_DATA 8\nSCALARS GlobalNodeId int 1\nLOOKUP_TABLE default\n1 2 3 4 5 6 7 8\n"));
    const CliRun info = uvr("-q info --json " + ids, dir);
    ASSERT_EQ(info.code, 0) << info.err;
    EXPECT_EQ(defaultOf(nlohmann::json::parse(info.out)), "GlobalNodeId:point");
    const CliRun r = uvr("render " + ids + " --size 8x8 --device cpu -o " + dir + "/i.png", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("only id arrays"), std::string::npos) << r.err;
}

TEST(CliInfo, UvrmInfoReadsTheHeaderUnlessFull) {
    const std::string dir = testing::scratchDir();
    const std::string m = dir + "/m.uvrm";
    ASSERT_EQ(uvr("-q generate box --cells 3000 --fields jet,constant -o " + m, dir).code, 0);
    const CliRun head = uvr("-q info --json " + m, dir);
    ASSERT_EQ(head.code, 0) << head.err;
    const auto h = nlohmann::json::parse(head.out);
    EXPECT_EQ(h["read"], "header");
    EXPECT_GT(h["cells"].get<int>(), 2000);
    EXPECT_EQ(h["cell_types"]["tetra"], h["cells"]);
    ASSERT_EQ(h["fields"].size(), 2u);
    EXPECT_FALSE(h["fields"][0].contains("range"));
    EXPECT_FALSE(h.contains("bounds"));
    EXPECT_EQ(defaultOf(h), "jet:point");
    const CliRun text = uvr("-q info " + m, dir);
    EXPECT_NE(text.out.find("need --full"), std::string::npos) << text.out;

    const CliRun full = uvr("-q info --full --json " + m, dir);
    ASSERT_EQ(full.code, 0) << full.err;
    const auto f = nlohmann::json::parse(full.out);
    EXPECT_EQ(f["read"], "whole file");
    EXPECT_TRUE(f.contains("bounds"));
    EXPECT_EQ(f["fields"][1]["range"][0], f["fields"][1]["range"][1]);  // constant
    EXPECT_EQ(f["cells"], h["cells"]);

    // The header's checks stay: a truncated file is refused by the header-only read as well.
    const auto size = std::filesystem::file_size(m);
    std::filesystem::copy_file(m, dir + "/cut.uvrm");
    std::filesystem::resize_file(dir + "/cut.uvrm", size - 4);
    expectOneLineError(uvr("-q info " + dir + "/cut.uvrm", dir), {"cut.uvrm", "truncated"},
                       "truncated .uvrm");
}

TEST(CliInfo, VoxelsAndQuadraticCellsAreNamedAndFindingsAreStructured) {
    const std::string dir = testing::scratchDir();
    // One voxel (type 11) and one quadratic tetrahedron (type 24, 10 nodes) beside it.
    const std::string file = testing::writeFile(
        dir + "/mixed.vtk",
        "# vtk DataFile Version 3.0\nmixed\nASCII\nDATASET UNSTRUCTURED_GRID\n"
        "POINTS 14 float\n0 0 0 1 0 0 0 1 0 1 1 0 0 0 1 1 0 1 0 1 1 1 1 1\n"
        "2 0 0 3 0 0 2 1 0 2 0 1 2.5 0 0 2.5 0.5 0\n"
        "CELLS 2 20\n8 0 1 2 3 4 5 6 7\n10 8 9 10 11 12 13 12 12 12 12\n"
        "CELL_TYPES 2\n11 24\nPOINT_DATA 14\nSCALARS f float 1\nLOOKUP_TABLE default\n"
        "0 1 2 3 4 5 6 7 8 9 10 11 12 13\n");
    const CliRun r = uvr("-q info --json " + file, dir);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["cell_types"]["hexahedron"], 1);
    EXPECT_EQ(j["cell_types"]["tetra"], 1);
    const std::string notes = j["notes"].dump();
    EXPECT_NE(notes.find("read 1 voxel cell(s) as hexahedra"), std::string::npos) << notes;
    EXPECT_NE(notes.find("reduced 1 quadratic_tetra cell(s) to their corner nodes"),
              std::string::npos)
        << notes;
    // The two mid-edge nodes are used by no cell: a structured finding.
    bool unused = false;
    for (const auto& f : j["validation"])
        if (f["code"] == "unused_points") {
            unused = true;
            EXPECT_EQ(f["count"], 2);
            EXPECT_NE(f["message"].get<std::string>().find("used by no cell"), std::string::npos);
        }
    EXPECT_TRUE(unused) << j["validation"];
}

}  // namespace
}  // namespace uvr

namespace uvr {
namespace {

TEST(CliChecks, EveryBadFlagFailsBeforeTheMeshIsRead) {
    // Without -q a read prints "uvr: read ...": a one-line error means nothing was read.
    const std::string dir = testing::scratchDir();
    const std::string m = dir + "/m.uvrm";
    ASSERT_EQ(uvr("-q generate box --cells 3000 --fields jet -o " + m, dir).code, 0);
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"--size 0x0", "--size"},
        {"--range 2,1", "--range"},
        {"--tf nosuch", "nosuch"},
        {"--opacity bad", "--opacity"},
        {"--camera-position a", "--camera-position"},
        {"--camera-up 1,2", "--camera-up"},
        {"--background 2,2,2", "--background"},
        {"--field x:bad", "unknown qualifier"},
        {"--field nosuch", "--field 'nosuch': not found; available: jet:point"},
        {"--field jet:x", "a scalar field"},
        {"--field jet:cell", "--field 'jet:cell': not found"},
        {"--quality 5", "--quality"},
        {"--view-angle 500", "--view-angle"},
        {"--supersample 9", "--supersample"},
        {"--nan-color bad", "--nan-color"},
        {"--camera missing.pvcc", "missing.pvcc"},
        {"--tf missing.json", "missing.json"},
        {"--power 2", "--step-rule variance"},
        {"--heatmap-max 5", "--heatmap"},
        {"--log --range -5,-1", "--log needs positive values"},
        {"--elevation nan", "--elevation"},
        {"--parallel --view-angle 20", "--view-angle"},
        {"--parallel-scale 2", "--parallel-scale"},
        {"--stats s.txt", "*.json"},
        {"-o " + dir + "/missing/x.png", "missing"},
    };
    for (const auto& [flags, piece] : cases) {
        const std::string out = flags.rfind("-o ", 0) == 0 ? "" : " -o " + dir + "/x.png";
        expectOneLineError(uvr("render " + m + out + " " + flags, dir), {piece}, flags);
        EXPECT_FALSE(std::filesystem::exists(dir + "/x.png")) << flags;
    }
}

TEST(CliChecks, RefineAndGenerateEstimateTheirMemoryFirst) {
    const std::string dir = testing::scratchDir();
    const std::string m = dir + "/m.uvrm";
    ASSERT_EQ(uvr("-q generate box --cells 3000 -o " + m, dir).code, 0);
    // 3 levels make about 1.5M tetrahedra: far more than 10M bytes.
    expectOneLineError(
        uvr("-q --max-memory 10M refine " + m + " " + dir + "/r.uvrm --levels 3", dir),
        {"refining", "--max-memory"}, "refine");
    expectOneLineError(
        uvr("-q --max-memory 10M generate box --cells 4000000 -o " + dir + "/g.uvrm", dir),
        {"--cells 4000000", "--max-memory"}, "generate");
    EXPECT_FALSE(std::filesystem::exists(dir + "/r.uvrm"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/g.uvrm"));
    // The same commands within the limit work.
    ASSERT_EQ(uvr("-q --max-memory 200M refine " + m + " " + dir + "/r.uvrm --levels 1", dir).code,
              0);
}

}  // namespace
}  // namespace uvr
