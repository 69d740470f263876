// SPDX-License-Identifier: MIT
// Polyhedron cells (VTK type 42) in .vtu and legacy .vtk files: VTK-written files read and
// decomposed around vertex centroids, checked against VTK's volumes, a linear field, face
// neighbours and the image of the same grid as hexahedra; malformed face streams refused.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "test_meshes.h"
#include "test_support.h"
#include "uvr/accel/tet_adjacency.h"
#include "uvr/core/error.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/mesh/tet_mesh.h"
#include "uvr/mesh/validate.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;

/// Folder of the files tests/tools/write_polyhedra.py writes, generated once per process ("" when
/// the system Python lacks vtk).
const std::string& polyDir() {
    static const std::string dir = [] {
        if (!testing::pythonHas("vtk")) return std::string();
        const std::filesystem::path out = std::filesystem::temp_directory_path() / "uvr_tests" /
                                          ("polyhedra_" + std::to_string(::getpid()));
        std::filesystem::remove_all(out);
        std::filesystem::create_directories(out);
        const std::string cmd = std::string(testing::systemPython()) + " " +
                                testing::testTool("write_polyhedra.py") + " " + out.string() +
                                " >" + (out / "log.txt").string() + " 2>&1";
        if (testing::runCommand(cmd) != 0) {
            ADD_FAILURE() << "write_polyhedra.py failed; see " << (out / "log.txt");
            return std::string();
        }
        return out.string();
    }();
    return dir;
}

/// Every encoding the script writes a mesh in.
const std::vector<std::string> kVariants = {"ascii.vtu",    "binary.vtu",    "appended.vtu",
                                            "51_ascii.vtk", "51_binary.vtk", "42_ascii.vtk",
                                            "42_binary.vtk"};

/// Boundary faces of the tetrahedra the renderer prepares from a mesh (faces without neighbour).
std::uint64_t boundaryFaces(const Mesh& m) {
    const TetMesh tets = tetrahedralize(m, selectScalarField(m, FieldSpec{}), {.splitCells = true});
    std::uint64_t n = 0;
    for (std::uint32_t t : buildTetNeighbors(tets)) n += t == kNoTet;
    return n;
}

/// Volume per source cell (the cell field 'id' each tetrahedron inherits) against VTK's, the
/// tetrahedra all positive; cells VTK's own (not decomposed) count as VTK's volume.
void expectVolumesPerSourceCell(const Mesh& m, const std::vector<double>& vtkVolumes,
                                double tolerance) {
    const Field* id = m.findField("id", Association::Cell);
    ASSERT_NE(id, nullptr);
    ASSERT_EQ(id->values.size(), m.cellCount());
    std::vector<double> volume(vtkVolumes.size(), 0.0);
    for (std::uint64_t c = 0; c < m.cellCount(); ++c) {
        const std::size_t source = static_cast<std::size_t>(id->values[c]);
        ASSERT_LT(source, volume.size());
        if (m.cellTypes[c] == CellType::Tetra) {
            const double v = testing::tetVolume(m, c);
            EXPECT_GT(v, 0.0) << "cell " << c;
            volume[source] += v;
        } else {
            volume[source] += vtkVolumes[source];
        }
    }
    for (std::size_t c = 0; c < volume.size(); ++c)
        EXPECT_NEAR(volume[c], vtkVolumes[c], tolerance) << "source cell " << c;
}

#define REQUIRE_POLY_DIR() \
    if (polyDir().empty()) GTEST_SKIP() << "no python3-vtk9 in the system python"

TEST(VtkPolyhedra, MixedMeshMatchesVtkVolumesFieldsAndNeighbours) {
    REQUIRE_POLY_DIR();
    std::vector<double> vtkVolumes;
    {
        std::ifstream in(polyDir() + "/mixed_volumes.txt");
        for (double v; in >> v;) vtkVolumes.push_back(v);
    }
    ASSERT_EQ(vtkVolumes.size(), 64u);  // 6 hex, 6 + 10 + 1 polyhedra, 10 wedges, 30 pyramids, tet
    for (const std::string& variant : kVariants) {
        SCOPED_TRACE(variant);
        const std::string path = polyDir() + "/mixed_" + variant;
        const Mesh m = readMesh(path);
        // 6 cubes as 6 * 12 tets, 10 prisms as 10 * 8, the octahedron as 8: 160 from 17 polyhedra.
        ASSERT_EQ(m.cellCount(), 64u - 17u + 160u);
        ASSERT_EQ(m.pointCount(), 64u + 5u + 7u + 17u);  // lattice, pyramid centres, octa+tet
        EXPECT_THAT(m.notes, ::testing::Contains(HasSubstr(
                                 "17 polyhedra decomposed into 160 tetrahedra around their "
                                 "vertex centroids")));
        const ValidationReport report = validateMesh(m, path);
        EXPECT_TRUE(report.findings().empty()) << ::testing::PrintToString(report.findings());

        expectVolumesPerSourceCell(m, vtkVolumes, 1e-6);

        // The point field at the original points as written, and x + 2y - z at every point:
        // the centroids' means of a linear field are the field at the centroid.
        const Field* f = m.findField("f", Association::Point);
        ASSERT_NE(f, nullptr);
        ASSERT_EQ(f->values.size(), m.pointCount());
        for (std::uint64_t p = 0; p < m.pointCount(); ++p) {
            const Vec3f q = m.points[p];
            EXPECT_NEAR(f->values[p], q.x + 2.f * q.y - q.z, 1e-5f) << "point " << p;
        }

        // Face neighbours: only the outer surface is boundary (the 3x3x3 grid's 54 squares as
        // 108 triangles; the octahedron's 7 free faces and the tetrahedron's 3).
        EXPECT_EQ(boundaryFaces(m), 108u + 7u + 3u);
    }
}

TEST(VtkPolyhedra, PentagonalAndHexagonalPrismsMatchVtkVolumes) {
    // VTK types 15 and 16, as VTK and ParaView read them (issue 35): decomposed as polyhedra.
    REQUIRE_POLY_DIR();
    std::vector<double> vtkVolumes;
    {
        std::ifstream in(polyDir() + "/prisms_volumes.txt");
        for (double v; in >> v;) vtkVolumes.push_back(v);
    }
    ASSERT_EQ(vtkVolumes.size(), 3u);  // the two prisms and the hexahedron on one
    for (const std::string& variant : kVariants) {
        SCOPED_TRACE(variant);
        const std::string path = polyDir() + "/prisms_" + variant;
        const Mesh m = readMesh(path);
        // The pentagonal prism: 2 x 3 + 5 x 2 face triangles, the hexagonal 2 x 4 + 6 x 2.
        ASSERT_EQ(m.cellCount(), 16u + 20u + 1u);
        ASSERT_EQ(m.pointCount(), 10u + 12u + 4u + 2u);
        EXPECT_THAT(m.notes, ::testing::Contains(
                                 HasSubstr("2 polyhedra (2 of them pentagonal or hexagonal prisms) "
                                           "decomposed into 36 tetrahedra")));
        const ValidationReport report = validateMesh(m, path);
        EXPECT_TRUE(report.findings().empty()) << ::testing::PrintToString(report.findings());
        expectVolumesPerSourceCell(m, vtkVolumes, 1e-5);  // ASCII files hold 6 digits
        const Field* f = m.findField("f", Association::Point);
        ASSERT_NE(f, nullptr);
        for (std::uint64_t p = 0; p < m.pointCount(); ++p) {
            const Vec3f q = m.points[p];
            EXPECT_NEAR(f->values[p], q.x + 2.f * q.y - q.z, 1e-4f) << "point " << p;
        }
        // Conforming where the hexahedron meets the hexagonal prism: only the shared square is
        // inside (16 + 20 face triangles of the prisms, 12 of the hexahedron, 2 + 2 shared).
        EXPECT_EQ(boundaryFaces(m), 16u + 20u + 12u - 4u);
    }
}

TEST(VtkGhosts, HiddenAndDuplicateCellsAreLeftOutAsParaViewDoes) {
    // vtkGhostType (issue 35): ParaView leaves out cells marked DUPLICATECELL (another piece's)
    // or HIDDENCELL, and cells with a HIDDENPOINT corner; EXTERIORCELL and DUPLICATEPOINT hide
    // nothing.
    REQUIRE_POLY_DIR();
    for (const std::string& variant : kVariants) {
        SCOPED_TRACE(variant);
        const Mesh m = readMesh(polyDir() + "/ghosts_" + variant);
        ASSERT_EQ(m.cellCount(), 24u);
        const Field* id = m.findField("id", Association::Cell);
        ASSERT_NE(id, nullptr);
        ASSERT_EQ(id->values.size(), 24u);
        for (std::uint64_t c = 0; c < 24; ++c) EXPECT_EQ(id->values[c], float(c + 2)) << c;
        EXPECT_THAT(m.notes,
                    ::testing::Contains(HasSubstr(
                        "left out 1 ghost cell(s) that vtkGhostType marks as duplicates")));
        EXPECT_THAT(m.notes, ::testing::Contains(
                                 HasSubstr("left out 2 cell(s) that vtkGhostType marks hidden")));
        // The corners only the left-out cells used: (0, 0, 0), (1, 0, 0) and (3, 3, 3).
        EXPECT_THAT(validateMesh(m, variant).findings(),
                    ::testing::ElementsAre(HasSubstr("3 point(s) used by no cell")));
    }
    // The same cells without the ghost arrays: all 27.
    EXPECT_EQ(readMesh(polyDir() + "/cubes_hex_ascii.vtu").cellCount(), 27u);
}

TEST(VtkGhosts, APolyhedronWithAHiddenPointCornerIsLeftOut) {
    // The same ghost flags on cubes written as polyhedra: the last cube's corner (3, 3, 3) is
    // HIDDENPOINT. In legacy files a polyhedron's cell list is its face stream, whose point ids
    // are read past the face counts; in .vtu files the faces array is read.
    REQUIRE_POLY_DIR();
    for (const std::string& variant : kVariants) {
        SCOPED_TRACE(variant);
        const Mesh m = readMesh(polyDir() + "/ghosts_poly_" + variant);
        const Field* id = m.findField("id", Association::Cell);
        ASSERT_NE(id, nullptr);
        const std::set<float> ids(id->values.begin(), id->values.end());
        std::set<float> expected;
        for (int c = 2; c < 26; ++c) expected.insert(float(c));
        EXPECT_EQ(ids, expected);
        EXPECT_THAT(m.notes, ::testing::Contains(
                                 HasSubstr("left out 2 cell(s) that vtkGhostType marks hidden")));
    }
}

TEST(VtkPolyhedra, PiecesOffsetTheFaceStreamsPointIndices) {
    REQUIRE_POLY_DIR();
    // Each Piece holds the whole mixed mesh: its face streams must index its own points (the
    // earlier Pieces' copies, at the same positions, would leave these unused).
    const Mesh m = readMesh(polyDir() + "/mixed_pieces.vtu");
    EXPECT_EQ(m.cellCount(), 3u * 207u);
    EXPECT_EQ(m.pointCount(), 3u * 93u);
    const ValidationReport report = validateMesh(m);
    EXPECT_EQ(report.unusedPoints, 0u);
    EXPECT_EQ(report.coincidentPoints, 2u * 93u);
    EXPECT_EQ(report.invertedCells + report.zeroVolumeCells, 0u);
}

TEST(VtkPolyhedra, CubeGridAsPolyhedraEqualsHexahedra) {
    REQUIRE_POLY_DIR();
    const Mesh hex = readMesh(polyDir() + "/cubes_hex_binary.vtu");
    EXPECT_EQ(boundaryFaces(hex), 108u);
    for (const std::string& variant : kVariants) {
        SCOPED_TRACE(variant);
        const Mesh m = readMesh(polyDir() + "/cubes_poly_" + variant);
        EXPECT_EQ(m.cellCount(), 27u * 12u);
        EXPECT_EQ(m.pointCount(), 64u + 27u);
        EXPECT_EQ(boundaryFaces(m), 108u);
        double total = 0.0;
        for (std::uint64_t c = 0; c < m.cellCount(); ++c) total += testing::tetVolume(m, c);
        EXPECT_NEAR(total, 27.0, 1e-9);
        // Cell values repeated onto each cube's 12 tetrahedra, in order.
        const Field* id = m.findField("id", Association::Cell);
        ASSERT_NE(id, nullptr);
        for (std::uint64_t c = 0; c < m.cellCount(); ++c)
            ASSERT_EQ(id->values[c], float(c / 12)) << "cell " << c;
        // The centroid of cube (i, j, k) is point 64 + its index, at (i + 0.5, j + 0.5, k + 0.5).
        for (int k = 0; k < 3; ++k)
            for (int j = 0; j < 3; ++j)
                for (int i = 0; i < 3; ++i)
                    testing::expectVec(m.points[64 + i + 3 * j + 9 * k],
                                       Vec3f(i + 0.5f, j + 0.5f, k + 0.5f), 0.f);
    }
}

TEST(VtkPolyhedra, PolyhedralGridRendersLikeHexahedra) {
    REQUIRE_POLY_DIR();
    const std::string dir = testing::scratchDir();
    const std::string args =
        " --field f --size 96x96 --opacity 0:0.2,1:0.8 --azimuth 30 --elevation 20 "
        "--opacity-unit 1 -o ";  // the default unit depends on the cell count, which grows
    auto uvr = [&](const std::string& a) {
        return testing::runCommand(testing::uvrBinary() + " " + a + " >>" + dir + "/log.txt 2>&1");
    };
    ASSERT_EQ(uvr("render " + polyDir() + "/cubes_hex_appended.vtu" + args + dir + "/hex.png"), 0);
    ASSERT_EQ(uvr("render " + polyDir() + "/cubes_poly_appended.vtu" + args + dir + "/poly.png"),
              0);
    ASSERT_EQ(uvr("render " + polyDir() + "/cubes_poly_51_binary.vtk" + args + dir + "/l.png"), 0);
    EXPECT_EQ(uvr("compare " + dir + "/hex.png " + dir + "/poly.png --min-ssim 0.99"), 0);
    EXPECT_EQ(uvr("compare " + dir + "/hex.png " + dir + "/l.png --min-ssim 0.99"), 0);
    // `uvr info` tells of the decomposition.
    ASSERT_EQ(uvr("info " + polyDir() + "/cubes_poly_ascii.vtu"), 0);
    std::ifstream in(dir + "/log.txt");
    const std::string log((std::istreambuf_iterator<char>(in)), {});
    EXPECT_THAT(log, HasSubstr("27 polyhedra decomposed into 324 tetrahedra"));
}

TEST(VtkPolyhedra, SmallVtkWrittenFilesInTestData) {
    // A cube and a pyramid as polyhedra sharing a square, a tetrahedron on a pyramid triangle
    // (VTK 9.1's ascii writers; the fuzz targets' seeds too). VTK's volumes: 1, 1/6, 1/3.
    for (const char* name : {"vtk/polyhedra.vtk", "vtk/polyhedra.vtu"}) {
        SCOPED_TRACE(name);
        const Mesh m = readMesh(testing::testData(name));
        ASSERT_EQ(m.cellCount(), 12u + 1u + 6u);
        const Field* c = m.findField("c", Association::Cell);
        ASSERT_NE(c, nullptr);
        std::map<float, double> volume;
        for (std::uint64_t t = 0; t < m.cellCount(); ++t)
            volume[c->values[t]] += testing::tetVolume(m, t);
        EXPECT_NEAR(volume[1.f], 1.0, 1e-6);
        EXPECT_NEAR(volume[11.f], 1.0 / 6.0, 1e-6);
        EXPECT_NEAR(volume[21.f], 1.0 / 3.0, 1e-6);
        EXPECT_EQ(boundaryFaces(m), 10u + 3u + 3u);
    }
}

// ---- hand-made files ----

/// A legacy file of 8 cube corners and the given CELLS lines (count, size, records).
std::string legacyCube(const std::string& cells, int cellCount, const std::string& types) {
    return "# vtk DataFile Version 4.2\ncube\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 8 float\n"
           "0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1\n" +
           cells + "\nCELL_TYPES " + std::to_string(cellCount) + "\n" + types + "\n";
}

/// "CELLS 1 size" and the record "k ids..." of one cell whose node list (or face stream) is ids.
std::string cellsRecord(const std::string& ids) {
    std::istringstream in(ids);
    std::size_t k = 0;
    for (std::string t; in >> t;) ++k;
    return "CELLS 1 " + std::to_string(k + 1) + "\n" + std::to_string(k) + " " + ids;
}

/// The cube's faces as one polyhedron's face stream.
const char* kCubeStream = "6 4 0 3 2 1 4 4 5 6 7 4 0 1 5 4 4 1 2 6 5 4 2 3 7 6 4 3 0 4 7";

TEST(VtkPolyhedra, HandMadeLegacyCubeWithCellAndPointData) {
    const std::string dir = testing::scratchDir();
    const std::string path = testing::writeFile(
        dir + "/cube.vtk",
        legacyCube(cellsRecord(kCubeStream), 1, "42") +
            "CELL_DATA 1\nSCALARS c float 2\nLOOKUP_TABLE default\n5 7\n"
            "POINT_DATA 8\nSCALARS p float\nLOOKUP_TABLE default\n0 1 2 3 4 5 6 7\n");
    const Mesh m = readMesh(path);
    ASSERT_EQ(m.cellCount(), 12u);
    ASSERT_EQ(m.pointCount(), 9u);
    const Field* c = m.findField("c", Association::Cell);
    ASSERT_NE(c, nullptr);
    ASSERT_EQ(c->values.size(), 24u);
    for (int t = 0; t < 12; ++t) EXPECT_EQ(c->values[2 * t] * 10 + c->values[2 * t + 1], 57.f);
    const Field* p = m.findField("p", Association::Point);
    ASSERT_NE(p, nullptr);
    EXPECT_EQ(p->values.back(), 3.5f);  // the mean of 0..7
    // Each quad face split along the diagonal through its smallest index, as hexahedra are.
    for (std::uint64_t t = 0; t < m.cellCount(); ++t) {
        const auto v = m.cell(t);
        EXPECT_EQ(v[3], 8u);
        EXPECT_EQ(std::min({v[0], v[1], v[2]}), v[0]) << "tet " << t << " fans from its min";
    }
}

TEST(VtkPolyhedra, InwardWoundStreamIsTurnedAndNonStarShapedIsNoted) {
    const std::string dir = testing::scratchDir();
    // The cube with every face reversed: turned to positive tetrahedra, nothing inverted.
    const std::string inward = testing::writeFile(
        dir + "/inward.vtk",
        legacyCube(cellsRecord("6 4 0 1 2 3 4 4 7 6 5 4 0 4 5 1 4 1 5 6 2 4 2 6 7 3 4 3 7 4 0"), 1,
                   "42"));
    const Mesh in = readMesh(inward);
    ASSERT_EQ(in.cellCount(), 12u);
    for (std::uint64_t t = 0; t < in.cellCount(); ++t) EXPECT_GT(testing::tetVolume(in, t), 0.0);
    EXPECT_EQ(in.notes.size(), 1u);

    // A U-shaped prism (area 7, height 1): its vertex centroid (1.5, 1.375) lies in the gap of
    // the U, so some tetrahedra are inverted; the signed volumes still add up to 7.
    const std::string u = testing::writeFile(
        dir + "/u.vtk",
        "# vtk DataFile Version 4.2\nu\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 16 float\n"
        "0 0 0 3 0 0 3 3 0 2 3 0 2 1 0 1 1 0 1 3 0 0 3 0\n"
        "0 0 1 3 0 1 3 3 1 2 3 1 2 1 1 1 1 1 1 3 1 0 3 1\n" +
            cellsRecord("10 8 7 6 5 4 3 2 1 0 8 8 9 10 11 12 13 14 15 4 0 1 9 8 4 1 2 10 9 "
                        "4 2 3 11 10 4 3 4 12 11 4 4 5 13 12 4 5 6 14 13 4 6 7 15 14 4 7 0 8 15") +
            "\nCELL_TYPES 1\n42\n");
    const Mesh m = readMesh(u);
    double total = 0.0;
    for (std::uint64_t t = 0; t < m.cellCount(); ++t) total += testing::tetVolume(m, t);
    EXPECT_NEAR(total, 7.0, 1e-9);
    const ValidationReport report = validateMesh(m, u);
    EXPECT_GT(report.invertedCells, 0u);
    EXPECT_THAT(m.notes, ::testing::Contains(HasSubstr(
                             std::to_string(report.invertedCells) +
                             " tetrahedra of polyhedra not star-shaped from their vertex centroid "
                             "are inverted")));
}

TEST(VtkPolyhedra, MalformedLegacyFaceStreamsAreRefused) {
    const std::string dir = testing::scratchDir();
    struct Case {
        std::string cells;  // the face stream
        std::string message;
    };
    const std::vector<Case> cases = {
        {"2 3 0 1 2", "cell 0 (polyhedron): face count 2, expected at least 4"},
        {"4 2 0 1 3", "face count 4 does not fit its face stream of 5 entries"},
        {"4 3 0 1 2 2 0 1 3 0 1 3 3 1 2 3 0", "face 1 of 4 lists 2 points, expected at least 3"},
        {"4 3 0 1 2 3 0 1 3 3 0 2 3 4 1 2 3", "face 3 of 4 lists 4 points, past the end"},
        {"4 3 0 1 2 3 0 1 3 3 0 2 3 3 1 2 9", "face 3 of 4: point index 9 out of range [0, 8)"},
        {"4 3 0 1 -2 3 0 1 3 3 0 2 3 3 1 2 3", "face 0 of 4: point index -2 out of range"},
        {"4 3 0 1 2 3 0 1 3 3 0 2 3 3 1 2 3 5",
         "its 4 faces use 17 entries of a face stream of 18"},
        {"-7", "face count -7, expected at least 4"},
        {"9223372036854775807 3", "does not fit its face stream of 2 entries"},
    };
    for (std::size_t k = 0; k < cases.size(); ++k) {
        const Case& c = cases[k];
        const std::string path = testing::writeFile(dir + "/bad" + std::to_string(k) + ".vtk",
                                                    legacyCube(cellsRecord(c.cells), 1, "42"));
        const Error e = testing::catchError([&] { readMesh(path); });
        EXPECT_THAT(e.what(), HasSubstr(c.message)) << c.cells;
        EXPECT_THAT(e.what(), HasSubstr("bad" + std::to_string(k) + ".vtk")) << c.cells;
    }
}

TEST(VtkPolyhedra, ShortOrOutOfRangePrismsAreRefused) {
    const std::string dir = testing::scratchDir();
    struct Case {
        std::string ids, type, message;
    };
    const std::vector<Case> cases = {
        {"0 1 2 3 4 5 6 7", "15", "cell 0 (pentagonal prism) lists 8 nodes, expected 10"},
        {"0 1 2 3 4 5 6 7 0 1", "16", "cell 0 (hexagonal prism) lists 10 nodes, expected 12"},
        {"0 1 2 3 4 5 6 7 0 9", "15", "cell 0 (pentagonal prism): face 1 of 7: point index 9"},
    };
    for (std::size_t k = 0; k < cases.size(); ++k) {
        const Case& c = cases[k];
        const std::string path = testing::writeFile(dir + "/prism" + std::to_string(k) + ".vtk",
                                                    legacyCube(cellsRecord(c.ids), 1, c.type));
        const Error e = testing::catchError([&] { readMesh(path); });
        EXPECT_THAT(e.what(), HasSubstr(c.message)) << k;
        EXPECT_THAT(e.what(), HasSubstr("prism" + std::to_string(k) + ".vtk")) << k;
    }
}

/// A .vtu of the 8 cube corners and the given <Cells> arrays (ascii Int64).
std::string vtuCube(int cells, const std::string& conn, const std::string& offsets,
                    const std::string& types, const std::string& faces,
                    const std::string& faceOffsets) {
    auto array = [](const std::string& name, const std::string& values) {
        return "<DataArray type=\"Int64\" Name=\"" + name + "\" format=\"ascii\">" + values +
               "</DataArray>\n";
    };
    std::string s =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
        "byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"8\" "
        "NumberOfCells=\"" +
        std::to_string(cells) +
        "\">\n<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">"
        "0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1</DataArray></Points>\n<Cells>\n" +
        array("connectivity", conn) + array("offsets", offsets) + array("types", types);
    if (!faces.empty()) s += array("faces", faces);
    if (!faceOffsets.empty()) s += array("faceoffsets", faceOffsets);
    return s + "</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
}

TEST(VtkPolyhedra, MalformedVtuFaceArraysAreRefused) {
    const std::string dir = testing::scratchDir();
    const std::string cube = kCubeStream;
    const std::string twoCubes = cube + " " + cube;
    const std::string conn = "0 1 2 3 4 5 6 7 0 1 2 3 4 5 6 7";
    struct Case {
        std::string offsets, types, faces, faceOffsets, message;
    };
    const std::vector<Case> cases = {
        {"8 16", "42 42", "", "", "need numeric <Cells> DataArrays 'faces' and 'faceoffsets'"},
        {"8 16", "42 42", twoCubes, "62 31",
         "cell 1 (polyhedron): end offset 31 lies before the end of the previous face stream, 62"},
        {"8 16", "42 42", twoCubes, "31 -1", "cell 1 (polyhedron): end offset -1 lies before"},
        {"8 16", "42 10", twoCubes, "31 62", "cell 1 (VTK type 10) is no polyhedron, expected -1"},
        {"8 16", "42 42", cube + " 6", "31 63", "DataArray 'faces' holds 32 values, expected 63"},
        {"8 16", "42 42", twoCubes, "30 62", "cell 0 (polyhedron): face 5 of 6 lists 4 points"},
        {"8 16", "42 42", twoCubes, "32 62", "cell 0 (polyhedron): its 6 faces use 31 entries"},
    };
    for (std::size_t k = 0; k < cases.size(); ++k) {
        const Case& c = cases[k];
        const std::string path =
            testing::writeFile(dir + "/bad" + std::to_string(k) + ".vtu",
                               vtuCube(2, conn, c.offsets, c.types, c.faces, c.faceOffsets));
        const Error e = testing::catchError([&] { readMesh(path); });
        EXPECT_THAT(e.what(), HasSubstr(c.message)) << k;
        EXPECT_THAT(e.what(), HasSubstr("bad" + std::to_string(k) + ".vtu")) << k;
    }
    // The same arrays, well formed, read.
    const std::string good =
        testing::writeFile(dir + "/good.vtu", vtuCube(2, conn, "8 16", "42 42", twoCubes, "31 62"));
    EXPECT_EQ(readMesh(good).cellCount(), 24u);
}

}  // namespace
}  // namespace uvr

#undef REQUIRE_POLY_DIR  // file-local: the unity build joins test files
