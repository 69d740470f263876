// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/vtk_legacy.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/mesh/io/scalar_type.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;
using testing::haveSharedData;
using testing::pythonHas;
using testing::runCommand;
using testing::scratchDir;
using testing::sharedData;
using testing::systemPython;
using testing::writeFile;

/// Reads path expecting an Error of the given kind whose one-line message names the file and
/// holds every fragment (e.g. "line 7" and what was expected).
void expectReadError(const std::string& path, ErrorKind kind,
                     std::initializer_list<std::string> fragments, const ReadOptions& opts = {}) {
    try {
        readVtkLegacy(path, opts);
        ADD_FAILURE() << "no error reading " << path;
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_EQ(e.kind(), kind) << msg;
        EXPECT_THAT(msg, HasSubstr(path));
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        for (const std::string& f : fragments) EXPECT_THAT(msg, HasSubstr(f));
    }
}

/// Minimum and maximum over all values of a field.
std::pair<float, float> valueRange(const Field& f) {
    auto [lo, hi] = std::minmax_element(f.values.begin(), f.values.end());
    return {*lo, *hi};
}

// ---------------------------------------------------------------------------------------------
// Real files. Every expected number below was computed independently with Debian's
// /usr/bin/python3 and VTK 9.1's vtkUnstructuredGridReader (ReadAllScalars/Vectors/Fields on).

struct ExpectedField {
    const char* name;
    Association association;
    int components;
    float min, max;
};

struct ExpectedFile {
    const char* name;
    std::uint64_t points, cells;
    CellType type;
    float bounds[6];  // xmin xmax ymin ymax zmin zmax
    std::vector<std::uint32_t> firstCell, lastCell;
    std::vector<ExpectedField> fields;
};

const std::vector<ExpectedFile>& realFiles() {
    static const std::vector<ExpectedFile> files = {
        {"spx.vtk",
         2896,
         12936,
         CellType::Tetra,
         {-2.96967006f, 2.96967006f, -3.47328997f, 3.47328997f, -4.69750023f, 4.69750023f},
         {68, 69, 26, 17},
         {2790, 2533, 2791, 2532},
         {{"scalars", Association::Point, 1, 0.f, 2.25399995f}}},
        {"post.vtk",
         2288,
         8750,
         CellType::Tetra,
         {-2.83992553f, 2.86249709f, -2.85684848f, 2.85684848f, 0.f, 1.12554646f},
         {12, 1, 287, 0},
         {2000, 2287, 2286, 2275},
         {{"Pressure", Association::Point, 1, 0.35536769f, 1.64124048f}}},
        {"tetraMesh.vtk",
         55,
         160,
         CellType::Tetra,
         {-9.46570015f, 9.78032017f, -9.09060955f, 9.94653034f, -9.77106953f, 7.14071989f},
         {54, 32, 26, 7},
         {18, 14, 15, 13},
         {{"scalars", Association::Point, 1, 0.f, 4.f}}},
        {"bluntfin_tets.vtk",
         40960,
         187395,
         CellType::Tetra,
         {-7.81574726f, 14.3622036f, 0.f, 8.32755852f, 0.f, 5.72425127f},
         {0, 1, 40, 1280},
         {39639, 39678, 40918, 40959},
         {{"density", Association::Point, 1, 0.192599997f, 4.97749996f},
          {"speed", Association::Point, 1, 0.f, 3.12293196f},
          {"energy", Association::Point, 1, 0.768956959f, 25.1609993f},
          {"momentum", Association::Point, 3, -3.73390007f, 5.79029989f}}},
        {"post_tets.vtk",
         109744,
         513375,
         CellType::Tetra,
         {-14.9868422f, 15.f, -14.9967098f, 14.9967098f, 0.f, 4.82052517f},
         {0, 1, 38, 2888},
         {106817, 106854, 109704, 109743},
         {{"speed", Association::Point, 1, 0.f, 1.39144409f},
          {"density", Association::Point, 1, 1.f, 1.f},
          {"energy", Association::Point, 1, -0.54150629f, 4.39583731f},
          {"momentum", Association::Point, 3, -0.675631464f, 1.36175454f}}},
        {"cylinder_quadratic_as_tets.vtk",
         465,
         1522,
         CellType::Tetra,
         {-0.00999999978f, 0.00999999978f, -0.00999999978f, 0.00999999978f, 0.f, 0.100000001f},
         {223, 106, 24, 149},
         {105, 230, 28, 150},
         {{"velocity", Association::Point, 3, -1.00436854f, 0.158881634f},
          {"pressure", Association::Point, 1, -98.4391785f, 7234.48682f},
          {"velocity_norm", Association::Point, 1, 0.f, 1.00439858f},
          {"velocity", Association::Cell, 3, -0.909156322f, 0.079987593f},
          {"pressure", Association::Cell, 1, -13.8634644f, 5059.72705f},
          {"velocity_norm", Association::Cell, 1, 0.0649943948f, 0.909156978f},
          {"Re", Association::Cell, 1, 0.f, 0.f}}},
        {"hexa.vtk",
         12167,
         10648,
         CellType::Hexahedron,
         {0.f, 0.956521988f, 0.f, 0.956521988f, 0.f, 0.956521988f},
         {0, 1, 24, 23, 529, 530, 553, 552},
         {11613, 11614, 11637, 11636, 12142, 12143, 12166, 12165},
         {{"scalars", Association::Point, 1, 0.75306499f, 17.320507f}}},
    };
    return files;
}

class VtkLegacyRealData : public ::testing::TestWithParam<std::size_t> {};

TEST_P(VtkLegacyRealData, MatchesVtkReader) {
    if (!haveSharedData()) GTEST_SKIP() << "no shared data folder";
    const ExpectedFile& ex = realFiles()[GetParam()];
    const Mesh mesh = readVtkLegacy(sharedData(ex.name));
    ASSERT_EQ(mesh.pointCount(), ex.points);
    ASSERT_EQ(mesh.cellCount(), ex.cells);
    EXPECT_TRUE(std::all_of(mesh.cellTypes.begin(), mesh.cellTypes.end(),
                            [&](CellType t) { return t == ex.type; }));
    EXPECT_EQ(mesh.cellOffsets.back(), ex.cells * cornerCount(ex.type));
    const auto first = mesh.cell(0);
    const auto last = mesh.cell(ex.cells - 1);
    EXPECT_EQ(std::vector<std::uint32_t>(first.begin(), first.end()), ex.firstCell);
    EXPECT_EQ(std::vector<std::uint32_t>(last.begin(), last.end()), ex.lastCell);

    const Bounds3f b = mesh.bounds();
    EXPECT_FLOAT_EQ(b.lo.x, ex.bounds[0]);
    EXPECT_FLOAT_EQ(b.hi.x, ex.bounds[1]);
    EXPECT_FLOAT_EQ(b.lo.y, ex.bounds[2]);
    EXPECT_FLOAT_EQ(b.hi.y, ex.bounds[3]);
    EXPECT_FLOAT_EQ(b.lo.z, ex.bounds[4]);
    EXPECT_FLOAT_EQ(b.hi.z, ex.bounds[5]);

    ASSERT_EQ(mesh.fields.size(), ex.fields.size());
    for (const ExpectedField& ef : ex.fields) {
        SCOPED_TRACE(ef.name);
        const Field* f = mesh.findField(ef.name, ef.association);
        ASSERT_NE(f, nullptr);
        EXPECT_EQ(f->components, ef.components);
        EXPECT_EQ(f->tupleCount(), ef.association == Association::Point ? ex.points : ex.cells);
        const auto [lo, hi] = valueRange(*f);
        EXPECT_FLOAT_EQ(lo, ef.min);
        EXPECT_FLOAT_EQ(hi, ef.max);
    }
    EXPECT_TRUE(mesh.notes.empty());
}

INSTANTIATE_TEST_SUITE_P(VtkLegacy, VtkLegacyRealData, ::testing::Range<std::size_t>(0, 7),
                         [](const auto& p) {
                             std::string n = realFiles()[p.param].name;
                             n = n.substr(0, n.find('.'));
                             std::replace(n.begin(), n.end(), '-', '_');
                             return n;
                         });

// ---------------------------------------------------------------------------------------------
// Files written at test time by VTK's own vtkUnstructuredGridWriter (tests/tools script).

std::string writerScript() {
    return testing::testTool("write_legacy_vtk.py");
}

struct WriterCase {
    int version;
    const char* mode;
};

/// Prints a writer case readably in test names and failures.
void PrintTo(const WriterCase& wc, std::ostream* os) {
    *os << "version " << wc.version << " " << wc.mode;
}

class VtkLegacyVtkWritten : public ::testing::TestWithParam<WriterCase> {};

TEST_P(VtkLegacyVtkWritten, ReadsWhatVtkWrote) {
    if (!pythonHas("vtk") || !pythonHas("numpy")) GTEST_SKIP() << "no python vtk/numpy";
    const WriterCase wc = GetParam();
    const std::string path = scratchDir() + "/mixed.vtk";
    const std::string cmd = std::string(systemPython()) + " " + writerScript() + " " + path + " " +
                            std::to_string(wc.version) + " " + wc.mode;
    ASSERT_EQ(runCommand(cmd), 0) << cmd;
    std::ifstream js(path + ".json");
    const nlohmann::json expected = nlohmann::json::parse(js);

    const Mesh mesh = readVtkLegacy(path);

    const auto& pts = expected["points"];
    ASSERT_EQ(mesh.pointCount() * 3, pts.size());
    for (std::size_t i = 0; i < mesh.pointCount(); ++i)
        for (int k = 0; k < 3; ++k) {
            const double want = pts[3 * i + k].get<double>();
            EXPECT_NEAR(mesh.points[i][k], want, 1e-6 * std::max(1.0, std::abs(want)))
                << "point " << i;
        }

    const auto& cells = expected["cells"];
    ASSERT_EQ(mesh.cellCount(), cells.size());
    for (std::size_t c = 0; c < cells.size(); ++c) {
        EXPECT_EQ(static_cast<int>(mesh.cellTypes[c]), cells[c]["type"].get<int>());
        const auto ids = mesh.cell(c);
        EXPECT_EQ(std::vector<std::uint32_t>(ids.begin(), ids.end()),
                  cells[c]["ids"].get<std::vector<std::uint32_t>>())
            << "cell " << c;
    }
    ASSERT_EQ(expected["dropped"].get<int>(), 1);
    // The dropped triangle and the quadratic tetra reduced to its corners are both noted.
    ASSERT_EQ(mesh.notes.size(), 2u);
    EXPECT_THAT(mesh.notes[0], HasSubstr("dropped 1 non-volumetric triangle"));
    EXPECT_THAT(mesh.notes[1], HasSubstr("reduced 1 quadratic_tetra cell(s) to their corner"));

    const auto& fields = expected["fields"];
    ASSERT_EQ(mesh.fields.size(), fields.size());
    for (const auto& ef : fields) {
        const std::string name = ef["name"].get<std::string>();
        SCOPED_TRACE(name);
        const Association assoc =
            ef["association"] == "point" ? Association::Point : Association::Cell;
        const Field* f = mesh.findField(name, assoc);
        ASSERT_NE(f, nullptr);
        EXPECT_EQ(f->components, ef["components"].get<int>());
        const auto values = ef["values"].get<std::vector<double>>();
        ASSERT_EQ(f->values.size(), values.size());
        // ASCII floats carry 6 significant digits; binary values are exact.
        const double rel = std::string(wc.mode) == "ascii" ? 1e-5 : 0.0;
        for (std::size_t i = 0; i < values.size(); ++i)
            EXPECT_NEAR(f->values[i], values[i], rel * std::max(1.0, std::abs(values[i])))
                << "value " << i;
    }
}

INSTANTIATE_TEST_SUITE_P(VtkLegacy, VtkLegacyVtkWritten,
                         ::testing::Values(WriterCase{42, "ascii"}, WriterCase{42, "binary"},
                                           WriterCase{51, "ascii"}, WriterCase{51, "binary"}),
                         [](const auto& p) {
                             return "v" + std::to_string(p.param.version) + "_" + p.param.mode;
                         });

// ---------------------------------------------------------------------------------------------
// Hand-written variants VTK accepts.

TEST(VtkLegacyAscii, OldStyleAndSpellings) {
    // Version 1.0, lower-case keywords, SCALARS without LOOKUP_TABLE, nan/inf/+/e+ spellings,
    // dataset FIELD data (skipped), METADATA, a standalone LOOKUP_TABLE, NULL_ARRAY, CRLF.
    std::string text =
        "# vtk DataFile Version 1.0\n"
        "old style\n"
        "ascii\n"
        "dataset unstructured_grid\n"
        "FIELD FieldData 1\n"
        "Properties 1 2 float\n"
        "7 8\n"
        "points 4 double\n"
        "0 0 0 +1.5 0 0\n"
        "0 1e+10 0 0 0 -2.5E-3\n"
        "METADATA\n"
        "INFORMATION 1\n"
        "NAME L2_NORM_RANGE LOCATION vtkDataArray\n"
        "DATA 2 0 1e10\n"
        "\n"
        "cells 1 5\n"
        "4 0 1 2 3\n"
        "cell_types 1\n"
        "10\n"
        "cell_data 1\n"
        "color_scalars rgb 3\n"
        "1 0.5 0\n"
        "point_data 4\n"
        "scalars s float\n"
        "nan inf -inf 1e+10\n"
        "LOOKUP_TABLE my_table 2\n"
        "0 0 0 1 1 1 1 1\n"
        "field FieldData 2\n"
        "NULL_ARRAY\n"
        "my%20pair 2 4 int\n"
        "1 2 3 4 5 6 7 -8\n"
        "METADATA\n"
        "COMPONENT_NAMES\n"
        "\n"
        "second\n"
        "\n"
        "vectors v float\n"
        "1 2 3 4 5 6 7 8 9 10 11 12\n";
    std::string crlf;
    for (char c : text) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    for (const std::string& contents : {text, crlf}) {
        const std::string path = writeFile(scratchDir() + "/old.vtk", contents);
        const Mesh mesh = readVtkLegacy(path);
        ASSERT_EQ(mesh.pointCount(), 4u);
        EXPECT_FLOAT_EQ(mesh.points[1].x, 1.5f);
        EXPECT_FLOAT_EQ(mesh.points[2].y, 1e10f);
        EXPECT_FLOAT_EQ(mesh.points[3].z, -2.5e-3f);
        ASSERT_EQ(mesh.cellCount(), 1u);
        ASSERT_EQ(mesh.fields.size(), 4u);
        const Field* rgb = mesh.findField("rgb", Association::Cell);
        ASSERT_NE(rgb, nullptr);
        EXPECT_EQ(rgb->values, (std::vector<float>{255.f, 128.f, 0.f}));
        const Field* s = mesh.findField("s", Association::Point);
        ASSERT_NE(s, nullptr);
        EXPECT_TRUE(std::isnan(s->values[0]));
        EXPECT_EQ(s->values[1], std::numeric_limits<float>::infinity());
        EXPECT_EQ(s->values[2], -std::numeric_limits<float>::infinity());
        EXPECT_FLOAT_EQ(s->values[3], 1e10f);
        const Field* pair = mesh.findField("my pair", Association::Point);
        ASSERT_NE(pair, nullptr);
        EXPECT_EQ(pair->components, 2);
        EXPECT_EQ(pair->values, (std::vector<float>{1, 2, 3, 4, 5, 6, 7, -8}));
        const Field* v = mesh.findField("v", Association::Point);
        ASSERT_NE(v, nullptr);
        EXPECT_EQ(v->components, 3);
        EXPECT_FLOAT_EQ(v->values[11], 12.f);
    }
}

/// Appends big-endian bytes of a value, as legacy BINARY files store them.
template <typename T>
void appendBigEndian(std::string& out, T value) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    if (hostIsLittleEndian()) std::reverse(b, b + sizeof(T));
    out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

TEST(VtkLegacyBinary, NoNewlineAfterBlocks) {
    std::string f =
        "# vtk DataFile Version 2.0\nno newlines after binary blocks\nBINARY\n"
        "DATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n";
    for (int i = 0; i < 15; ++i) appendBigEndian<float>(f, 0.5f * static_cast<float>(i));
    f += "CELLS 2 11\n";
    for (std::int32_t v : {4, 0, 1, 2, 3, 5, 0, 1, 2, 3, 4}) appendBigEndian(f, v);
    f += "CELL_TYPES 2\n";
    appendBigEndian<std::int32_t>(f, 10);
    appendBigEndian<std::int32_t>(f, 14);
    f += "CELL_DATA 2\nSCALARS id short\nLOOKUP_TABLE default\n";
    appendBigEndian<std::int16_t>(f, -3);
    appendBigEndian<std::int16_t>(f, 300);
    f += "POINT_DATA 5\nSCALARS d double\nLOOKUP_TABLE default\n";
    for (int i = 0; i < 5; ++i) appendBigEndian<double>(f, 1.25 * i);
    const Mesh mesh = readVtkLegacy(writeFile(scratchDir() + "/b.vtk", f));
    ASSERT_EQ(mesh.pointCount(), 5u);
    EXPECT_FLOAT_EQ(mesh.points[4].z, 7.0f);
    ASSERT_EQ(mesh.cellCount(), 2u);
    EXPECT_EQ(mesh.cellTypes[1], CellType::Pyramid);
    ASSERT_NE(mesh.findField("id", Association::Cell), nullptr);
    EXPECT_EQ(mesh.findField("id", Association::Cell)->values, (std::vector<float>{-3, 300}));
    ASSERT_NE(mesh.findField("d", Association::Point), nullptr);
    EXPECT_FLOAT_EQ(mesh.findField("d", Association::Point)->values[4], 5.0f);
}

// ---------------------------------------------------------------------------------------------
// Bad ASCII input. The valid base file's lines:
//  1 header, 2 title, 3 ASCII, 4 DATASET, 5 POINTS, 6-8 points, 9 CELLS, 10-11 records,
//  12 CELL_TYPES, 13-14 types, 15 POINT_DATA, 16 SCALARS, 17 LOOKUP_TABLE, 18 values.

std::vector<std::string> baseLines() {
    return {"# vtk DataFile Version 3.0",
            "bad input test",
            "ASCII",
            "DATASET UNSTRUCTURED_GRID",
            "POINTS 5 float",
            "0 0 0  1 0 0",
            "0 1 0  0 0 1",
            "1 1 1",
            "CELLS 2 10",
            "4 0 1 2 3",
            "4 1 2 3 4",
            "CELL_TYPES 2",
            "10",
            "10",
            "POINT_DATA 5",
            "SCALARS s float 1",
            "LOOKUP_TABLE default",
            "0 1 2 3 4"};
}

/// The base file with line `number` (1-based) replaced, or cut after it when cut is set.
std::string variant(int number, const std::string& replacement, bool cut = false) {
    std::vector<std::string> lines = baseLines();
    lines[number - 1] = replacement;
    if (cut) lines.resize(number);
    std::string s;
    for (const std::string& l : lines) s += l + "\n";
    return s;
}

class VtkLegacyBadAscii : public ::testing::Test {
protected:
    std::string file(const std::string& contents) {
        return writeFile(scratchDir() + "/bad.vtk", contents);
    }
};

TEST_F(VtkLegacyBadAscii, BaseFileIsValid) {
    const Mesh mesh = readVtkLegacy(file(variant(1, baseLines()[0])));
    EXPECT_EQ(mesh.pointCount(), 5u);
    EXPECT_EQ(mesh.cellCount(), 2u);
    ASSERT_EQ(mesh.fields.size(), 1u);
}

TEST_F(VtkLegacyBadAscii, MissingFile) {
    expectReadError(scratchDir() + "/none.vtk", ErrorKind::Io, {});
}

TEST_F(VtkLegacyBadAscii, Header) {
    expectReadError(file(""), ErrorKind::Parse, {"line 1", "empty"});
    expectReadError(file(variant(1, "hello world")), ErrorKind::Parse,
                    {"line 1", "'# vtk DataFile Version X.Y'", "'hello world'"});
    expectReadError(file(variant(1, "# vtk DataFile Version x")), ErrorKind::Parse,
                    {"line 1", "file version"});
    expectReadError(file(variant(1, "# vtk DataFile Version 6.0")), ErrorKind::Unsupported,
                    {"line 1", "6.0"});
    expectReadError(file("# vtk DataFile Version 3.0\n"), ErrorKind::Parse, {"line 2", "title"});
    expectReadError(file(variant(3, "ASCI")), ErrorKind::Parse,
                    {"line 3", "expected ASCII or BINARY, got 'ASCI'"});
    expectReadError(file(variant(4, "DATASET POLYDATA")), ErrorKind::Unsupported,
                    {"line 4", "POLYDATA"});
    expectReadError(file(variant(4, "POINTS 5 float")), ErrorKind::Parse,
                    {"line 4", "expected keyword DATASET, got 'POINTS'"});
}

TEST_F(VtkLegacyBadAscii, Points) {
    expectReadError(file(variant(7, "0 1", true)), ErrorKind::Parse,
                    {"line 7", "expected 5 point triples, file ends after 2"});
    expectReadError(file(variant(6, "0 abc 0  1 0 0")), ErrorKind::Parse, {"line 6", "got 'abc'"});
    expectReadError(file(variant(5, "POINTS 99999999999 float")), ErrorKind::Resource,
                    {"line 5", "POINTS 99999999999"});
    expectReadError(file(variant(5, "POINTS -5 float")), ErrorKind::Parse, {"line 5", "negative"});
    expectReadError(file(variant(5, "POINTS five float")), ErrorKind::Parse,
                    {"line 5", "got 'five'"});
    expectReadError(file(variant(5, "POINTS 5 flaot")), ErrorKind::Parse,
                    {"line 5", "unknown data type 'flaot'"});
    expectReadError(file(variant(5, "POINTS 5 bit")), ErrorKind::Unsupported, {"line 5", "'bit'"});
    expectReadError(file(variant(5, "POINTS 5")), ErrorKind::Parse,
                    {"line 5", "POINTS count type"});
    // Too few points: the next keyword is not a number.
    expectReadError(file(variant(5, "POINTS 6 float")), ErrorKind::Parse,
                    {"line 9", "got 'CELLS'"});
}

TEST_F(VtkLegacyBadAscii, Cells) {
    expectReadError(file(variant(12, "FOO 2")), ErrorKind::Parse,
                    {"line 12", "expected keyword CELL_TYPES, got 'FOO'"});
    expectReadError(file(variant(11, "4 1 2 3 4", true)), ErrorKind::Parse,
                    {"line 12", "expected keyword CELL_TYPES, the file ends"});
    expectReadError(file(variant(12, "POINT_DATA 5")), ErrorKind::Parse,
                    {"line 12", "expected keyword CELL_TYPES, got 'POINT_DATA'"});
    expectReadError(file(variant(9, "CELLS 2 11")), ErrorKind::Parse,
                    {"line 9", "CELLS size 11 does not match"});
    expectReadError(file(variant(9, "CELLS 2 9")), ErrorKind::Parse,
                    {"line 11", "cell 1 lists 4 points, but only 3 integers remain"});
    expectReadError(file(variant(10, "-1 0 1 2 3")), ErrorKind::Parse,
                    {"line 10", "cell 0 lists -1 points"});
    expectReadError(file(variant(10, "4 0 1 2.5 3")), ErrorKind::Parse,
                    {"line 10", "expected an integer", "'2.5'"});
    expectReadError(file(variant(9, "CELLS 2 999999999")), ErrorKind::Resource,
                    {"line 9", "CELLS 2 999999999"});
    expectReadError(file(variant(11, "4 1 2 3 9")), ErrorKind::Validation,
                    {"cell 1", "point index 9"});
    expectReadError(file(variant(12, "CELL_TYPES 3")), ErrorKind::Parse,
                    {"line 12", "CELL_TYPES 3 does not match the 2 cells"});
    expectReadError(file(variant(14, "99")), ErrorKind::Parse, {"cell 1", "99"});
    expectReadError(file(variant(14, "10", true) + "1"), ErrorKind::Parse, {"line 15"});
}

TEST_F(VtkLegacyBadAscii, Attributes) {
    expectReadError(file(variant(15, "POINT_DATA 10")), ErrorKind::Parse,
                    {"line 15", "POINT_DATA 10 does not match 5 points"});
    expectReadError(file(variant(15, "CELL_DATA 3")), ErrorKind::Parse,
                    {"line 15", "CELL_DATA 3 does not match 2 cells"});
    expectReadError(file(variant(16, "SCALAR s float 1")), ErrorKind::Parse,
                    {"line 16", "got 'SCALAR'"});
    expectReadError(file(variant(18, "0 1 2")), ErrorKind::Parse,
                    {"line 18", "expected 5 tuples of SCALARS 's', file ends after 3"});
    expectReadError(file(variant(18, "0 1 x 3 4")), ErrorKind::Parse, {"line 18", "got 'x'"});
    expectReadError(file(variant(16, "SCALARS s float 0")), ErrorKind::Parse,
                    {"line 16", "component count 0"});
    expectReadError(file(variant(16, "SCALARS s double_ 1")), ErrorKind::Parse,
                    {"line 16", "unknown data type 'double_'"});
    // FIELD arrays must have one tuple per point.
    expectReadError(file(variant(16, "FIELD FieldData 1\nf 1 4 float\n0 1 2 3", true)),
                    ErrorKind::Parse, {"line 17", "has 4 tuples, expected 5"});
    expectReadError(file(variant(16, "FIELD FieldData 2\nf 1 5 float\n0 1 2 3 4", true)),
                    ErrorKind::Parse, {"line 19", "expected 2 FIELD arrays, file ends after 1"});
}

TEST_F(VtkLegacyBadAscii, OffsetsForm) {
    auto make = [](const std::string& offsets, const std::string& conn) {
        return "# vtk DataFile Version 5.1\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n"
               "POINTS 5 float\n0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\n"
               "CELLS 3 8\nOFFSETS vtktypeint64\n" +
               offsets + "\n" + conn + "\nCELL_TYPES 2\n10\n10\n";
    };
    const std::string goodConn = "CONNECTIVITY vtktypeint64\n0 1 2 3 1 2 3 4";
    EXPECT_EQ(readVtkLegacy(file(make("0 4 8", goodConn))).cellCount(), 2u);
    expectReadError(file(make("1 4 8", goodConn)), ErrorKind::Parse,
                    {"line 9", "OFFSETS must start at 0"});
    expectReadError(file(make("0 5 4", goodConn)), ErrorKind::Parse,
                    {"line 9", "OFFSETS entry 2 = 4 outside [5, 8]"});
    expectReadError(file(make("0 4 7", goodConn)), ErrorKind::Parse,
                    {"line 10", "OFFSETS end at 7"});
    expectReadError(file(make("0 4 8", "CONNECTIVITX vtktypeint64\n0 1 2 3 1 2 3 4")),
                    ErrorKind::Parse, {"line 10", "expected keyword CONNECTIVITY"});
    expectReadError(file(make("0 4 8", "CONNECTIVITY float\n0 1 2 3 1 2 3 4")), ErrorKind::Parse,
                    {"line 10", "integer type"});
    expectReadError(file(make("0 4 8", "CONNECTIVITY vtktypeint64\n0 1 2 3 1 2")), ErrorKind::Parse,
                    {"line 12", "CONNECTIVITY entries", "got 'CELL_TYPES'"});
}

TEST_F(VtkLegacyBadAscii, MemoryLimit) {
    ReadOptions opts;
    opts.maxMemoryBytes = 16;
    expectReadError(file(variant(1, baseLines()[0])), ErrorKind::Resource, {"memory limit"}, opts);
}

// ---------------------------------------------------------------------------------------------
// Bad BINARY input: truncated and altered copies of post.vtk (a real big-endian file).

class VtkLegacyBadBinary : public ::testing::Test {
protected:
    void SetUp() override {
        if (!haveSharedData()) GTEST_SKIP() << "no shared data folder";
        const std::vector<char> bytes = readFileBytes(sharedData("post.vtk"));
        original_.assign(bytes.begin(), bytes.end());
    }
    /// Byte offset just after the first line starting with key.
    std::size_t after(const std::string& key) const {
        const std::size_t at = original_.find("\n" + key);
        EXPECT_NE(at, std::string::npos) << key;
        return original_.find('\n', at + 1) + 1;
    }
    std::string file(const std::string& contents) {
        return writeFile(scratchDir() + "/post_bad.vtk", contents);
    }
    std::string original_;
};

TEST_F(VtkLegacyBadBinary, TruncatedInPoints) {
    const std::size_t data = after("POINTS 2288 float");
    // The whole cut file is smaller than POINTS alone would be: an absurd count.
    expectReadError(file(original_.substr(0, data + 1520 * 12 + 7)), ErrorKind::Resource,
                    {"byte " + std::to_string(data),
                     "expected 2288 point triples, file ends after 1520", "whole file"});
    // Cut in the last array: the file could have held it, so it is truncated.
    const std::size_t pd = after("Pressure 1 2288 float");
    expectReadError(file(original_.substr(0, pd + 2000 * 4 + 3)), ErrorKind::Parse,
                    {"byte " + std::to_string(pd),
                     "expected 2288 tuples of FIELD array 'Pressure', file ends after 2000"});
}

TEST_F(VtkLegacyBadBinary, TruncatedInCells) {
    const std::size_t data = after("CELLS 8750 43750");
    expectReadError(
        file(original_.substr(0, data + 100)), ErrorKind::Resource,
        {"byte " + std::to_string(data), "expected 43750 CELLS integers, file ends after 25"});
    const std::size_t types = after("CELL_TYPES 8750");
    expectReadError(
        file(original_.substr(0, types + 4 * 8000)), ErrorKind::Parse,
        {"byte " + std::to_string(types), "expected 8750 cell types, file ends after 8000"});
}

TEST_F(VtkLegacyBadBinary, TruncatedAnywhere) {
    // Every cut must give a clean one-line error naming the file and a place.
    for (std::size_t len = 0; len < original_.size(); len += 997) {
        SCOPED_TRACE(len);
        const std::string path = file(original_.substr(0, len));
        try {
            readVtkLegacy(path);
            ADD_FAILURE() << "no error for a cut at " << len;
        } catch (const Error& e) {
            const std::string msg = e.what();
            EXPECT_NE(e.kind(), ErrorKind::Internal) << msg;
            EXPECT_THAT(msg, HasSubstr(path));
            EXPECT_TRUE(msg.find("byte ") != std::string::npos ||
                        msg.find("line ") != std::string::npos ||
                        msg.find("cell ") != std::string::npos)
                << msg;
        }
    }
}

TEST_F(VtkLegacyBadBinary, AbsurdAndWrongCounts) {
    std::string s = original_;
    const std::size_t at = s.find("CELLS 8750 43750");
    std::string absurd = s;
    absurd.replace(at, 16, "CELLS 8750 4375000000");
    expectReadError(
        file(absurd), ErrorKind::Resource,
        {"byte " + std::to_string(at + 22), "'CELLS 8750 4375000000'", "more than the whole file"});
    std::string fewer = s;
    fewer.replace(at, 16, "CELLS 8750 43748");  // last record runs past the declared size
    expectReadError(file(fewer), ErrorKind::Parse,
                    {"byte " + std::to_string(after("CELLS 8750 43750") + 8749 * 20),
                     "cell 8749 lists 4 points, but only 2 integers remain"});
    std::string types = s;
    const std::size_t t = s.find("CELL_TYPES 8750");
    types.replace(t, 15, "CELL_TYPES 8751");
    expectReadError(file(types), ErrorKind::Parse,
                    {"byte " + std::to_string(t), "does not match the 8750 cells"});
    std::string pd = s;
    const std::size_t p = s.find("POINT_DATA 2288");
    pd.replace(p, 15, "POINT_DATA 2289");
    expectReadError(file(pd), ErrorKind::Parse,
                    {"byte " + std::to_string(p), "POINT_DATA 2289 does not match 2288 points"});
}

// ---------------------------------------------------------------------------------------------
// Memory and time: the limit bounds the whole load; many fields load in linear time.

TEST(VtkLegacyLimits, AFileLargerThanTheMemoryLimitIsRefusedUnread) {
    // A 2 GiB sparse file (a valid header, then holes): refused from its size, before reading.
    const std::string path = scratchDir() + "/sparse.vtk";
    writeFile(path, "# vtk DataFile Version 3.0\nsparse\nASCII\nDATASET UNSTRUCTURED_GRID\n");
    std::filesystem::resize_file(path, std::uint64_t(2) << 30);
    ReadOptions options;
    options.maxMemoryBytes = 64 << 20;
    try {
        readVtkLegacy(path, options);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Resource);
        EXPECT_EQ(std::string(e.what()), path +
                                             ": the file needs 2147483648 bytes, which exceed "
                                             "the memory limit of 67108864 bytes (`max_memory`)");
    }
    std::filesystem::remove(path);
}

TEST(VtkLegacyLimits, TheLimitBoundsAllArraysTogether) {
    // 40 point fields of 1000 values (4000 bytes each, 160 KB in all) under a 300 KB limit
    // that the 174 KB file fits: each array fits, all of them together do not.
    std::string text =
        "# vtk DataFile Version 3.0\nfields\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 1000 "
        "float\n" +
        std::string(12000, '\0') + "\nPOINT_DATA 1000\n";
    for (int f = 0; f < 40; ++f)
        text += "SCALARS f" + std::to_string(f) + " float 1\nLOOKUP_TABLE default\n" +
                std::string(4000, '\0') + "\n";
    const std::string path = writeFile(scratchDir() + "/fields.vtk", text);
    ReadOptions options;
    options.maxMemoryBytes = 300000;
    try {
        readVtkLegacy(path, options);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Resource);
        EXPECT_THAT(e.what(), HasSubstr(path + ": tuples of SCALARS 'f"));
        EXPECT_THAT(e.what(), HasSubstr("needs 4000 bytes, which with the "));
        EXPECT_THAT(e.what(), HasSubstr("exceed the memory limit of 300000 bytes (`max_memory`)"));
    }
    options.maxMemoryBytes = 0;
    EXPECT_EQ(readVtkLegacy(path, options).fields.size(), 40u);
}

}  // namespace
}  // namespace uvr

namespace uvr {
namespace {

TEST(VtkLegacyNumbers, SignedCountsAndExponentsReadAsVtkReadsThem) {
    // The same values VTK 9.1's vtkUnstructuredGridReader gets from the file.
    const std::string path = testing::testData("vtk/signed_numbers.vtk");
    const Mesh m = readVtkLegacy(path);
    ASSERT_EQ(m.pointCount(), 5u);
    EXPECT_EQ(m.points[1], Vec3f(1, 0, 0));
    EXPECT_EQ(m.points[2], Vec3f(0, 1, 0));
    EXPECT_EQ(m.points[4], Vec3f(1, 1, 1));
    EXPECT_EQ(m.cellIndices, (std::vector<std::uint32_t>{0, 1, 2, 3, 1, 2, 3, 4}));
    ASSERT_EQ(m.fields.size(), 2u);
    EXPECT_EQ(m.fields[0].values, (std::vector<float>{1, 1, 1.5f, 0.25f, -300}));
    EXPECT_EQ(m.fields[1].values, (std::vector<float>{1e-3f, -20.f, 0.5f, 5.f, 0.f, -0.f}));
    // Garbage keeps its message: hexadecimal, Fortran exponents, trailing letters.
    std::ifstream in(path);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string dir = testing::scratchDir();
    struct Case {
        std::string from, to, message;
    };
    for (const Case& c : std::vector<Case>{
             {"POINTS +5 float", "POINTS 0x5 float", "expected a point count in"},
             {"+1.5E+00", "1.5d0", "expected a number (value 3 of 5"},
             {"+10 +10", "+10 1e1x",
              "expected an integer (value 2 of 2 in cell types), got '1e1x'"},
         }) {
        SCOPED_TRACE(c.to);
        std::string edited = text;
        edited.replace(edited.find(c.from), c.from.size(), c.to);
        const std::string bad = testing::writeFile(dir + "/bad.vtk", edited);
        expectReadError(bad, ErrorKind::Parse, {c.message});
    }
}

TEST(VtkLegacyNumbers, MeshioTypeNamesAndNanAreRead) {
    // meshio writes 'vtktypeint32' (VTK 9.1 knows only the 64-bit vtktype names) and ASCII nan.
    const std::string path = testing::writeFile(
        testing::scratchDir() + "/meshio.vtk",
        "# vtk DataFile Version 5.1\nmeshio\nASCII\nDATASET UNSTRUCTURED_GRID\n"
        "POINTS 4 double\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 2 4\nOFFSETS vtktypeint64\n0 4\n"
        "CONNECTIVITY vtktypeint64\n0 1 2 3\nCELL_TYPES 1\n10\nPOINT_DATA 4\n"
        "FIELD FieldData 2\nid 1 4 vtktypeint32\n0 1 2 3\nt 1 4 vtktypefloat64\n1 nan -inf 2\n");
    const Mesh m = readVtkLegacy(path);
    ASSERT_EQ(m.fields.size(), 2u);
    EXPECT_EQ(m.fields[0].values, (std::vector<float>{0, 1, 2, 3}));
    EXPECT_TRUE(std::isnan(m.fields[1].values[1]));
    EXPECT_EQ(m.fields[1].values[2], -std::numeric_limits<float>::infinity());
}

}  // namespace
}  // namespace uvr
