// SPDX-License-Identifier: MIT
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/mesh/io/vtk_legacy.h"
#include "uvr/mesh/io/vtu.h"
#include "uvr/mesh/procedural.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;

/// Reads a .vtu with VTK's own vtkXMLUnstructuredGridReader and prints what it found as JSON:
/// counts, coordinates, cell types and connectivity, every array with its values and range, and
/// the summed cell volumes from vtkCellSizeFilter.
constexpr const char* kVtkDumpScript = R"PY(
import json, sys
import vtk
from vtk.util.numpy_support import vtk_to_numpy
legacy = sys.argv[1].endswith(".vtk")
r = vtk.vtkUnstructuredGridReader() if legacy else vtk.vtkXMLUnstructuredGridReader()
r.SetFileName(sys.argv[1])
r.Update()
if (legacy and r.GetHeader() is None) or r.GetErrorCode() != 0:
    sys.exit("vtk reader error %d" % r.GetErrorCode())
g = r.GetOutput()
out = {"points": g.GetNumberOfPoints(), "cells": g.GetNumberOfCells(), "types": [], "conn": []}
out["coords"] = vtk_to_numpy(g.GetPoints().GetData()).astype(float).ravel().tolist() \
    if g.GetNumberOfPoints() else []
out["bounds"] = list(g.GetBounds())
for c in range(g.GetNumberOfCells()):
    out["types"].append(g.GetCellType(c))
    ids = g.GetCell(c).GetPointIds()
    out["conn"].append([ids.GetId(i) for i in range(ids.GetNumberOfIds())])
for key, data in (("pointData", g.GetPointData()), ("cellData", g.GetCellData())):
    arrays = []
    for a in range(data.GetNumberOfArrays()):
        arr = data.GetArray(a)
        arrays.append({"name": arr.GetName(), "components": arr.GetNumberOfComponents(),
                       "type": arr.GetDataTypeAsString(), "range": list(arr.GetRange(-1)),
                       "values": vtk_to_numpy(arr).astype(float).ravel().tolist()})
    out[key] = arrays
    out[key + "Scalars"] = data.GetScalars().GetName() if data.GetScalars() else None
size = vtk.vtkCellSizeFilter()
size.SetInputData(g)
size.ComputeVolumeOn()
size.Update()
vol = size.GetOutput().GetCellData().GetArray("Volume")
out["volumes"] = [vol.GetValue(i) for i in range(vol.GetNumberOfTuples())]
print(json.dumps(out))
)PY";

/// Reads a .vtu or legacy .vtk with VTK in Debian's Python and returns the JSON dump.
nlohmann::json readWithVtk(const std::string& vtu, const std::string& dir) {
    const std::string script = testing::writeFile(dir + "/dump.py", kVtkDumpScript);
    const std::string json = dir + "/dump.json";
    const int status = testing::runCommand(std::string(testing::systemPython()) + " " + script +
                                           " " + vtu + " > " + json + " 2> " + dir + "/err.txt");
    std::ifstream in(json);
    std::ifstream err(dir + "/err.txt");
    std::string errText((std::istreambuf_iterator<char>(err)), std::istreambuf_iterator<char>());
    EXPECT_EQ(status, 0) << errText;
    EXPECT_EQ(errText.find("ERROR"), std::string::npos) << errText;
    return nlohmann::json::parse(in);
}

/// Writes the mesh as .vtu (zlib-compressed), reads it back with VTK and returns the JSON dump.
nlohmann::json writeAndReadWithVtk(const Mesh& mesh, const std::string& dir) {
    const std::string vtu = dir + "/mesh.vtu";
    writeVtu(mesh, vtu);
    return readWithVtk(vtu, dir);
}

/// One tetra, hexahedron, wedge and pyramid (positively oriented, sharing faces' points), with
/// point and cell fields whose names need XML escaping.
Mesh orientedMixedMesh() {
    Mesh m;
    // A 2 x 1 x 1 block of points (i, j, k) -> i + 3 (j + 2 k), plus an apex above it.
    for (int k = 0; k < 2; ++k)
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 3; ++i) m.points.push_back({1.f * i, 1.f * j, 1.f * k});
    m.points.push_back({0.5f, 0.5f, 2.f});  // 12: pyramid apex over the top face of the hexahedron
    m.points.push_back({2.f, 0.f, 2.f});    // 13
    const std::uint32_t hex[8] = {0, 1, 4, 3, 6, 7, 10, 9};
    const std::uint32_t wedge[6] = {1, 5, 2, 7, 11, 8};  // VTK: (0,1,2) turns away from (3,4,5)
    const std::uint32_t pyramid[5] = {6, 7, 10, 9, 12};
    const std::uint32_t tet[4] = {7, 8, 11, 13};
    m.addCell(CellType::Hexahedron, hex);
    m.addCell(CellType::Wedge, wedge);
    m.addCell(CellType::Pyramid, pyramid);
    m.addCell(CellType::Tetra, tet);
    Field temperature{"temperature", Association::Point, 1, {}};
    Field velocity{"velocity <m/s>", Association::Point, 3, {}};
    for (size_t i = 0; i < m.points.size(); ++i) {
        temperature.values.push_back(0.1f * i - 0.35f);
        for (int c = 0; c < 3; ++c) velocity.values.push_back(1e-3f * i + c);
    }
    Field pressure{"p & \"q\"", Association::Cell, 1, {5.5f, -1.25f, 3e10f, 1e-20f}};
    Field pair{"pair", Association::Cell, 2, {1, 2, 3, 4, 5, 6, 7, 8}};
    m.fields = {temperature, pressure, velocity, pair};
    return m;
}

void expectArray(const nlohmann::json& a, const Field& f) {
    EXPECT_EQ(a["name"], f.name);
    EXPECT_EQ(a["components"], f.components);
    EXPECT_EQ(a["type"], "float");
    const auto values = a["values"].get<std::vector<double>>();
    ASSERT_EQ(values.size(), f.values.size()) << f.name;
    for (size_t i = 0; i < values.size(); ++i)
        EXPECT_EQ(static_cast<float>(values[i]), f.values[i]) << f.name << " value " << i;
}

/// Checks VTK's dump of a file written from orientedMixedMesh() (m).
void expectMixedMesh(const nlohmann::json& j, const Mesh& m) {
    ASSERT_EQ(j["points"], m.pointCount());
    ASSERT_EQ(j["cells"], m.cellCount());
    const auto coords = j["coords"].get<std::vector<double>>();
    ASSERT_EQ(coords.size(), 3 * m.pointCount());
    for (size_t i = 0; i < m.pointCount(); ++i)
        for (int c = 0; c < 3; ++c)
            EXPECT_EQ(static_cast<float>(coords[3 * i + c]), m.points[i][c]) << "point " << i;
    for (std::uint64_t c = 0; c < m.cellCount(); ++c) {
        EXPECT_EQ(j["types"][c], static_cast<int>(m.cellTypes[c])) << "cell " << c;
        auto ids = m.cell(c);
        EXPECT_EQ(j["conn"][c].get<std::vector<std::uint32_t>>(),
                  std::vector<std::uint32_t>(ids.begin(), ids.end()))
            << "cell " << c;
    }
    ASSERT_EQ(j["pointData"].size(), 2u);
    expectArray(j["pointData"][0], m.fields[0]);
    expectArray(j["pointData"][1], m.fields[2]);
    ASSERT_EQ(j["cellData"].size(), 2u);
    expectArray(j["cellData"][0], m.fields[1]);
    expectArray(j["cellData"][1], m.fields[3]);
    EXPECT_EQ(j["pointDataScalars"], "temperature");
    EXPECT_EQ(j["cellDataScalars"], "p & \"q\"");
    // Unit hexahedron, half-unit wedge, pyramid of height 1 on a unit square, tet of volume 1/6.
    const auto volumes = j["volumes"].get<std::vector<double>>();
    ASSERT_EQ(volumes.size(), 4u);
    EXPECT_NEAR(volumes[0], 1.0, 1e-6);
    EXPECT_NEAR(volumes[1], 0.5, 1e-6);
    EXPECT_NEAR(volumes[2], 1.0 / 3.0, 1e-6);
    EXPECT_NEAR(volumes[3], 1.0 / 6.0, 1e-6);
}

TEST(VtuWriter, VtkReadsBackEveryCellPointAndField) {
    if (!testing::pythonHas("vtk")) GTEST_SKIP() << "system Python has no vtk module";
    const Mesh m = orientedMixedMesh();
    expectMixedMesh(writeAndReadWithVtk(m, testing::scratchDir()), m);
}

/// Expects a and b to hold the same points, cells and fields, bit for bit.
void expectSameMeshByFieldName(const Mesh& a, const Mesh& b) {
    ASSERT_EQ(a.points.size(), b.points.size());
    for (size_t i = 0; i < a.points.size(); ++i)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(a.points[i][c], b.points[i][c]) << "point " << i;
    EXPECT_EQ(a.cellTypes, b.cellTypes);
    EXPECT_EQ(a.cellOffsets, b.cellOffsets);
    EXPECT_EQ(a.cellIndices, b.cellIndices);
    ASSERT_EQ(a.fields.size(), b.fields.size());
    for (const Field& f : a.fields) {
        const auto g = std::find_if(b.fields.begin(), b.fields.end(), [&](const Field& x) {
            return x.name == f.name && x.association == f.association;
        });
        ASSERT_NE(g, b.fields.end()) << f.name;
        EXPECT_EQ(g->components, f.components) << f.name;
        EXPECT_EQ(g->values, f.values) << f.name;
    }
}

TEST(VtuWriter, EveryCompressorIsReadBackByVtkAndUvr) {
    const bool vtk = testing::pythonHas("vtk");
    const Mesh m = orientedMixedMesh();
    for (VtuCompressor c :
         {VtuCompressor::None, VtuCompressor::Zlib, VtuCompressor::Lz4, VtuCompressor::Lzma}) {
        SCOPED_TRACE(static_cast<int>(c));
        if (!vtuCompressorAvailable(c)) continue;
        const std::string dir = testing::scratchDir();
        const std::string path = dir + "/mesh.vtu";
        VtuWriteOptions options;
        options.compressor = c;
        options.blockSize = 64;  // several blocks per array, a partial last one
        writeVtu(m, path, {}, options);
        expectSameMeshByFieldName(m, readVtu(path));
        const std::vector<char> bytes = readFileBytes(path);
        const std::string text(bytes.begin(), bytes.end());
        EXPECT_EQ(text.find("compressor=") != std::string::npos, c != VtuCompressor::None);
        if (vtk) expectMixedMesh(readWithVtk(path, dir), m);
    }
}

TEST(VtuWriter, CompressionShrinksAProceduralMeshAndKeepsItExact) {
    ProceduralSpec spec;
    spec.targetCells = 50000;
    const Mesh m = generateMesh(spec);
    const std::string dir = testing::scratchDir();
    VtuWriteOptions plain;
    plain.compressor = VtuCompressor::None;
    writeVtu(m, dir + "/plain.vtu", {}, plain);
    writeVtu(m, dir + "/zlib.vtu");  // the default: zlib, 64 KiB blocks
    expectSameMeshByFieldName(m, readVtu(dir + "/zlib.vtu"));
    EXPECT_LT(std::filesystem::file_size(dir + "/zlib.vtu"),
              std::filesystem::file_size(dir + "/plain.vtu") * 6 / 10);
}

TEST(VtuWriter, BadBlockSizeIsAnArgumentError) {
    VtuWriteOptions options;
    options.blockSize = 12;
    const std::string path = testing::scratchDir() + "/mesh.vtu";
    try {
        writeVtu(orientedMixedMesh(), path, {}, options);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Argument);
        EXPECT_THAT(e.what(), HasSubstr("VTU block size 12 must be a positive multiple of 8"));
    }
}

TEST(VtkLegacyWriter, VtkAndUvrReadBackBothVersions) {
    const bool vtk = testing::pythonHas("vtk");
    const Mesh m = orientedMixedMesh();
    for (VtkLegacyVersion v :
         {VtkLegacyVersion::Auto, VtkLegacyVersion::V42, VtkLegacyVersion::V51}) {
        SCOPED_TRACE(static_cast<int>(v));
        const std::string dir = testing::scratchDir();
        const std::string path = dir + "/mesh.vtk";
        writeVtkLegacy(m, path, {}, v);
        const std::vector<char> bytes = readFileBytes(path);
        const std::string text(bytes.begin(), bytes.end());
        EXPECT_EQ(text.rfind(v == VtkLegacyVersion::V51 ? "# vtk DataFile Version 5.1\n"
                                                        : "# vtk DataFile Version 4.2\n",
                             0),
                  0u);
        EXPECT_THAT(text, HasSubstr("SCALARS temperature float 1\nLOOKUP_TABLE default\n"));
        EXPECT_THAT(text, HasSubstr("velocity%20<m/s> 3 14 float\n"));
        expectSameMeshByFieldName(m, readVtkLegacy(path));
        if (!vtk) continue;
        const nlohmann::json j = readWithVtk(path, dir);
        expectMixedMesh(j, m);
    }
}

TEST(VtkLegacyWriter, FailedWritesLeaveNoFile) {
    Mesh bad = orientedMixedMesh();
    bad.cellIndices[3] = 99;
    const std::string dir = testing::scratchDir();
    try {
        writeVtkLegacy(bad, dir + "/bad.vtk");
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Validation);
        EXPECT_THAT(e.what(), HasSubstr(dir + "/bad.vtk"));
    }
    EXPECT_TRUE(std::filesystem::is_empty(dir));
}

TEST(VtuWriter, VtkSeesTheCountsRangesAndVolumeOfAProceduralMesh) {
    if (!testing::pythonHas("vtk")) GTEST_SKIP() << "system Python has no vtk module";
    ProceduralSpec spec;
    spec.targetCells = 20000;
    const Mesh m = generateMesh(spec);
    const nlohmann::json j = writeAndReadWithVtk(m, testing::scratchDir());
    EXPECT_EQ(j["points"], m.pointCount());
    EXPECT_EQ(j["cells"], m.cellCount());
    const auto bounds = j["bounds"].get<std::vector<double>>();
    EXPECT_EQ(bounds, (std::vector<double>{-1, 1, -1, 1, -1, 1}));
    ASSERT_EQ(j["pointData"].size(), m.fields.size());
    for (size_t f = 0; f < m.fields.size(); ++f) {
        const auto [lo, hi] =
            std::minmax_element(m.fields[f].values.begin(), m.fields[f].values.end());
        EXPECT_EQ(j["pointData"][f]["name"], m.fields[f].name);
        EXPECT_EQ(static_cast<float>(j["pointData"][f]["range"][0].get<double>()), *lo);
        EXPECT_EQ(static_cast<float>(j["pointData"][f]["range"][1].get<double>()), *hi);
    }
    // Every tetrahedron keeps its orientation through VTK; together they fill [-1,1]^3.
    const auto volumes = j["volumes"].get<std::vector<double>>();
    double total = 0;
    for (double v : volumes) {
        ASSERT_GT(v, 0.0);
        total += v;
    }
    EXPECT_NEAR(total, 8.0, 1e-4);
}

TEST(VtuWriter, HeaderDeclaresTheAgreedEncoding) {
    const std::string path = testing::scratchDir() + "/mesh.vtu";
    writeVtu(orientedMixedMesh(), path);
    std::vector<char> bytes = readFileBytes(path);
    const std::string text(bytes.begin(), bytes.end());
    EXPECT_THAT(text, HasSubstr("type=\"UnstructuredGrid\" version=\"1.0\" "
                                "byte_order=\"LittleEndian\" header_type=\"UInt64\""));
    EXPECT_THAT(text, HasSubstr("<DataArray type=\"Int64\" Name=\"connectivity\""));
    EXPECT_THAT(text, HasSubstr("<DataArray type=\"Int64\" Name=\"offsets\""));
    EXPECT_THAT(text, HasSubstr("<DataArray type=\"UInt8\" Name=\"types\""));
    EXPECT_THAT(text, HasSubstr("Name=\"velocity &lt;m/s&gt;\" NumberOfComponents=\"3\""));
    EXPECT_THAT(text, HasSubstr("<AppendedData encoding=\"raw\">"));
    EXPECT_EQ(text.substr(text.size() - 30), "\n  </AppendedData>\n</VTKFile>\n");
}

TEST(VtuWriter, FailedWritesLeaveNoFile) {
    const std::string dir = testing::scratchDir();
    const std::string missing = dir + "/no/folder/mesh.vtu";
    try {
        writeVtu(orientedMixedMesh(), missing);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Io);
        EXPECT_THAT(e.what(), HasSubstr(missing));
    }
    Mesh bad = orientedMixedMesh();
    bad.fields[3].values.push_back(9.f);
    const std::string out = dir + "/bad.vtu";
    try {
        writeVtu(bad, out);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Validation);
        EXPECT_THAT(e.what(), HasSubstr(out));
        EXPECT_THAT(e.what(), HasSubstr("field 'pair': 9 values, expected 4 cell tuples x 2"));
    }
    EXPECT_TRUE(std::filesystem::is_empty(dir));
}

}  // namespace
}  // namespace uvr
