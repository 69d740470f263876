// SPDX-License-Identifier: MIT
// The VTKHDF reader and writer against files written by h5py at test time
// (tests/tools/write_vtkhdf_cases.py: values known from their construction, repeated here), VTK's
// own vtkHDFReader (tests/tools/vtkhdf_oracle.py) and round trips of the real meshes.
#include "uvr/mesh/io/vtkhdf.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "test_support.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/mesh/io/time_series.h"

namespace uvr {
namespace {

using testing::catchError;

/// The h5py-written files, once per test process (tests run as separate processes in CTest);
/// empty when this build has no HDF5 or /usr/bin/python3 no h5py.
const std::string& casesDir() {
    static const std::string dir = [] {
        if (!vtkHdfSupported() || !testing::pythonHas("h5py") || !testing::pythonHas("numpy"))
            return std::string();
        const std::string d = (std::filesystem::temp_directory_path() / "uvr_tests" /
                               ("vtkhdf_cases_" + std::to_string(::getpid())))
                                  .string();
        std::filesystem::remove_all(d);
        static std::string removeAtExit;
        removeAtExit = d;
        std::atexit([] {
            std::error_code ec;
            std::filesystem::remove_all(removeAtExit, ec);
        });
        const std::string cmd = std::string(testing::systemPython()) + " " +
                                testing::testTool("write_vtkhdf_cases.py") + " " + d;
        return testing::runCommand(cmd) == 0 ? d : std::string();
    }();
    return dir;
}

std::string caseFile(const std::string& name) {
    return casesDir() + "/" + name;
}

#define REQUIRE_CASES()                                     \
    if (casesDir().empty())                                 \
    GTEST_SKIP() << "no HDF5 in this build, or no h5py in " \
                    "/usr/bin/python3"

// ---- The construction of write_vtkhdf_cases.py ----

/// Point k of the mixed partition (before its shift).
Vec3f mixedPoint(int k) {
    if (k == 12) return {0.5f, 0.5f, 2.f};
    if (k == 13) return {0.5f, 0.5f, -1.f};
    return {float(k % 3), float((k / 3) % 2), float(k / 6)};
}

struct ExpectedCell {
    int source;  // index among the file's cells (cell fields are per file cell)
    CellType type;
    std::vector<std::uint32_t> ids;
};

/// The volumetric cells uvr keeps (the triangle, cell 4, is dropped).
const std::vector<ExpectedCell>& mixedCells() {
    static const std::vector<ExpectedCell> cells = {
        {0, CellType::Hexahedron, {0, 1, 4, 3, 6, 7, 10, 9}},
        {1, CellType::Wedge, {1, 2, 4, 7, 8, 10}},
        {2, CellType::Tetra, {2, 5, 4, 8}},
        {3, CellType::Pyramid, {6, 7, 10, 9, 12}},
        {5, CellType::Tetra, {0, 1, 3, 13}},
    };
    return cells;
}

const Field& field(const Mesh& mesh, const std::string& name, Association a) {
    const Field* f = mesh.findField(name, a);
    if (!f) throw std::runtime_error("no field " + name);
    return *f;
}

/// Checks partition `part` of a merged mesh (points from 14 * part, cells from 5 * part): the
/// mixed partition moved by dx, cellid = cellBase + source cell, temp = x + 2y - z + tempAdd.
void expectPartition(const Mesh& mesh, int part, float dx, float cellBase, float tempAdd) {
    SCOPED_TRACE("partition " + std::to_string(part));
    const std::uint32_t p0 = 14u * part, c0 = 5u * part;
    const Field& temp = field(mesh, "temp", Association::Point);
    const Field& vel = field(mesh, "vel", Association::Point);
    const Field& cellid = field(mesh, "cellid", Association::Cell);
    const Field& pair = field(mesh, "pair", Association::Cell);
    ASSERT_EQ(vel.components, 3);
    ASSERT_EQ(pair.components, 2);
    for (int k = 0; k < 14; ++k) {
        const Vec3f e = mixedPoint(k) + Vec3f(dx, 0.f, 0.f);
        const Vec3f& p = mesh.points[p0 + k];
        EXPECT_EQ(p.x, e.x);
        EXPECT_EQ(p.y, e.y);
        EXPECT_EQ(p.z, e.z);
        EXPECT_FLOAT_EQ(temp.values[p0 + k], e.x + 2 * e.y - e.z + tempAdd) << "point " << k;
        EXPECT_EQ(vel.values[3 * (p0 + k)], e.x);
        EXPECT_EQ(vel.values[3 * (p0 + k) + 2], e.z);
    }
    for (std::size_t c = 0; c < mixedCells().size(); ++c) {
        const ExpectedCell& e = mixedCells()[c];
        EXPECT_EQ(mesh.cellTypes[c0 + c], e.type) << "cell " << c;
        const auto ids = mesh.cell(c0 + c);
        ASSERT_EQ(ids.size(), e.ids.size());
        for (std::size_t k = 0; k < ids.size(); ++k) EXPECT_EQ(ids[k], e.ids[k] + p0);
        EXPECT_EQ(cellid.values[c0 + c], cellBase + e.source);
        EXPECT_EQ(pair.values[2 * (c0 + c)], float(e.source));
        EXPECT_EQ(pair.values[2 * (c0 + c) + 1], -float(e.source));
    }
}

// ---- Reading ----

TEST(VtkHdf, ReadsMixedCellsAndFields) {
    REQUIRE_CASES();
    const Mesh mesh = readMesh(caseFile("mixed.vtkhdf"));
    ASSERT_EQ(mesh.pointCount(), 14u);
    ASSERT_EQ(mesh.cellCount(), 5u);
    expectPartition(mesh, 0, 0.f, 0.f, 0.f);
    EXPECT_EQ(mesh.fields.size(), 4u);  // FieldData is not read
    ASSERT_EQ(mesh.notes.size(), 1u);
    EXPECT_NE(mesh.notes[0].find("dropped 1 non-volumetric"), std::string::npos) << mesh.notes[0];
}

TEST(VtkHdf, MergesPartitions) {
    REQUIRE_CASES();
    const Mesh mesh = readMesh(caseFile("parts.vtkhdf"));
    ASSERT_EQ(mesh.pointCount(), 28u);
    ASSERT_EQ(mesh.cellCount(), 10u);
    expectPartition(mesh, 0, 0.f, 0.f, 0.f);
    expectPartition(mesh, 1, 10.f, 100.f, 0.f);
}

TEST(VtkHdf, ARankReadsItsRunOfThePartitions) {
    // A data-parallel rank's part: partition 1 alone is the merged mesh's second half, with ids
    // above kPieceIdShift; both parts together are the whole file's cells in order.
    REQUIRE_CASES();
    const std::string path = caseFile("parts.vtkhdf");
    EXPECT_EQ(vtkHdfPartitionCount(path), 2u);
    const Mesh whole = readMesh(path);
    const MeshPart second = readVtkHdfPart(path, 1, 2);
    ASSERT_EQ(second.mesh.pointCount(), 14u);
    ASSERT_EQ(second.mesh.cellCount(), 5u);
    EXPECT_EQ(second.pointIds.front(), std::uint64_t(1) << kPieceIdShift);
    EXPECT_EQ(second.cellIds.back(), (std::uint64_t(1) << kPieceIdShift) | 4u);
    for (std::uint32_t k = 0; k < 14; ++k) EXPECT_EQ(second.mesh.points[k], whole.points[14 + k]);
    for (std::uint64_t c = 0; c < 5; ++c) {
        EXPECT_EQ(second.mesh.cellTypes[c], whole.cellTypes[5 + c]);
        const auto a = second.mesh.cell(c), b = whole.cell(5 + c);
        ASSERT_EQ(a.size(), b.size());
        for (std::size_t k = 0; k < a.size(); ++k) EXPECT_EQ(a[k] + 14, b[k]);
    }
    EXPECT_EQ(field(second.mesh, "cellid", Association::Cell).values[0], 100.f);
    const MeshPart both = readVtkHdfPart(path, 0, 2);
    EXPECT_EQ(both.mesh.points, whole.points);
    EXPECT_EQ(both.mesh.cellIndices, whole.cellIndices);
    for (std::size_t k = 0; k < whole.fields.size(); ++k)
        EXPECT_EQ(both.mesh.fields[k].values, whole.fields[k].values) << whole.fields[k].name;
    // Ranges outside the partitions are refused, naming them.
    try {
        readVtkHdfPart(path, 1, 3);
        ADD_FAILURE() << "partitions [1, 3) of 2 were read";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Argument);
        EXPECT_NE(std::string(e.what()).find("it has 2"), std::string::npos) << e.what();
    }
}

TEST(VtkHdf, FileWithoutStepsIsOneStepAtTimeZero) {
    REQUIRE_CASES();
    auto series = openMeshSeries(caseFile("parts.vtkhdf"));
    ASSERT_EQ(series->stepCount(), 1u);
    EXPECT_EQ(series->times()[0], 0.0);
    const Mesh mesh = series->readStep(0);
    EXPECT_EQ(mesh.cellCount(), 10u);
    auto fields = series->readFieldsIfSameGeometry(0, mesh);
    ASSERT_TRUE(fields.has_value());
    EXPECT_EQ(fields->size(), 4u);
    for (std::size_t k = 0; k < fields->size(); ++k)
        EXPECT_EQ((*fields)[k].values, mesh.fields[k].values) << mesh.fields[k].name;
}

TEST(VtkHdf, PartitionOfDroppedCellsOnly) {
    REQUIRE_CASES();
    auto series = openMeshSeries(caseFile("parts_flat.vtkhdf"));
    const Mesh mesh = series->readStep(0);
    ASSERT_EQ(mesh.pointCount(), 17u);  // the triangle's 3 points stay, unused
    ASSERT_EQ(mesh.cellCount(), 5u);
    EXPECT_EQ(mesh.points[2].z, 5.f);
    const Field& cellid = field(mesh, "cellid", Association::Cell);
    ASSERT_EQ(cellid.values.size(), 5u);
    EXPECT_EQ(cellid.values[0], 0.f);  // the triangle's 7 is dropped with it
    EXPECT_EQ(mesh.cell(0)[0], 3u);    // the mixed partition's ids follow the 3 points
    // The field-only path drops the same tuples.
    auto fields = series->readFieldsIfSameGeometry(0, mesh);
    ASSERT_TRUE(fields.has_value());
    for (std::size_t k = 0; k < fields->size(); ++k)
        EXPECT_EQ((*fields)[k].values, mesh.fields[k].values) << mesh.fields[k].name;
}

/// The fields of a mesh equal those given (same names, associations, components, values).
void expectSameFields(const std::vector<Field>& a, const std::vector<Field>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
        EXPECT_EQ(a[k].name, b[k].name);
        EXPECT_EQ(a[k].association, b[k].association);
        EXPECT_EQ(a[k].components, b[k].components);
        EXPECT_EQ(a[k].values, b[k].values) << a[k].name;
    }
}

TEST(VtkHdf, TemporalStepsSharingGeometryGiveFieldsAlone) {
    REQUIRE_CASES();
    auto series = openMeshSeries(caseFile("temporal_shared.vtkhdf"));
    ASSERT_EQ(series->stepCount(), 3u);
    EXPECT_EQ(series->times(), (std::vector<double>{0.0, 0.5, 1.25}));
    const Mesh step0 = series->readStep(0);
    expectPartition(step0, 0, 0.f, 0.f, 0.f);
    for (std::size_t s = 1; s < 3; ++s) {
        SCOPED_TRACE("step " + std::to_string(s));
        auto fields = series->readFieldsIfSameGeometry(s, step0);
        ASSERT_TRUE(fields.has_value());
        Mesh withFields = step0;
        withFields.fields = *fields;
        expectPartition(withFields, 0, 0.f, 100.f * s, 10.f * s);
        // The same fields as the step read whole.
        const Mesh whole = series->readStep(s);
        EXPECT_TRUE(sameGeometry(whole, step0));
        expectSameFields(*fields, whole.fields);
    }
    // A geometry of other counts is not this file's: the caller reads the step whole.
    Mesh other = step0;
    other.points.pop_back();
    EXPECT_FALSE(series->readFieldsIfSameGeometry(1, other).has_value());
}

TEST(VtkHdf, TemporalStepWithNewGeometryIsReadWhole) {
    REQUIRE_CASES();
    auto series = openMeshSeries(caseFile("temporal_changing.vtkhdf"));
    ASSERT_EQ(series->stepCount(), 3u);
    EXPECT_EQ(series->times(), (std::vector<double>{0.0, 1.0, 2.0}));
    const Mesh step0 = series->readStep(0);
    expectPartition(step0, 0, 0.f, 0.f, 0.f);
    auto fields1 = series->readFieldsIfSameGeometry(1, step0);
    ASSERT_TRUE(fields1.has_value());
    EXPECT_FLOAT_EQ(field(step0, "temp", Association::Point).values[1] + 10.f,
                    (*fields1)[0].name == "temp" ? (*fields1)[0].values[1] : NAN);
    EXPECT_FALSE(series->readFieldsIfSameGeometry(2, step0).has_value());
    const Mesh step2 = series->readStep(2);
    ASSERT_EQ(step2.pointCount(), 28u);
    ASSERT_EQ(step2.cellCount(), 10u);
    expectPartition(step2, 0, 10.f, 400.f, 20.f);
    expectPartition(step2, 1, 20.f, 500.f, 20.f);
    // Now the held geometry is step 2's: steps 0 and 1 have another one.
    EXPECT_FALSE(series->readFieldsIfSameGeometry(1, step2).has_value());
    // readMesh reads the first step.
    expectPartition(readMesh(caseFile("temporal_changing.vtkhdf")), 0, 0.f, 0.f, 0.f);
}

TEST(VtkHdf, Version1WithoutTypeIsAnUnstructuredGridAsVtk91ReadsIt) {
    REQUIRE_CASES();
    const Mesh typeless = readMesh(caseFile("typeless_1_0.vtkhdf"));
    const Mesh typed = readMesh(caseFile("mixed.vtkhdf"));
    EXPECT_EQ(typeless.cellCount(), typed.cellCount());
    EXPECT_TRUE(testing::sameBytes(typeless.points, typed.points));
    EXPECT_TRUE(testing::sameBytes(typeless.cellIndices, typed.cellIndices));
}

TEST(VtkHdf, GhostFlagsLeaveOutHiddenCellsAsParaViewDoes) {
    // A HIDDENCELL hexahedron and a tetrahedron with a HIDDENPOINT corner are left out; an
    // EXTERIORCELL wedge and a DUPLICATEPOINT corner hide nothing (issue 35).
    REQUIRE_CASES();
    const Mesh mesh = readMesh(caseFile("ghosts.vtkhdf"));
    ASSERT_EQ(mesh.cellCount(), 3u);
    const Field& cellid = field(mesh, "cellid", Association::Cell);
    EXPECT_EQ(cellid.values, (std::vector<float>{1.f, 2.f, 3.f}));
    EXPECT_EQ(mesh.cellTypes,
              (std::vector<CellType>{CellType::Wedge, CellType::Tetra, CellType::Pyramid}));
    bool noted = false;
    for (const std::string& n : mesh.notes)
        noted |= n.find("left out 2 cell(s) that vtkGhostType marks hidden") != std::string::npos;
    EXPECT_TRUE(noted) << ::testing::PrintToString(mesh.notes);
}

TEST(VtkHdf, RecognisesHdf5ByItsVtkhdfGroup) {
    REQUIRE_CASES();
    const std::string dir = testing::scratchDir();
    std::filesystem::copy_file(caseFile("mixed.vtkhdf"), dir + "/mixed.h5");
    EXPECT_EQ(readMesh(dir + "/mixed.h5").cellCount(), 5u);
    EXPECT_EQ(openMeshSeries(dir + "/mixed.h5")->readStep(0).cellCount(), 5u);
    // Another HDF5 file (a netCDF-4 Exodus file, say) without the extension is not taken.
    std::filesystem::copy_file(caseFile("bad_no_vtkhdf.hdf"), dir + "/other.h5");
    EXPECT_FALSE(looksLikeVtkHdf(dir + "/other.h5"));
    const Error e = catchError([&] { (void)readMesh(dir + "/other.h5"); });
    EXPECT_NE(std::string(e.what()).find("unrecognised file format"), std::string::npos)
        << e.what();
}

TEST(VtkHdf, BadInputsGetClearErrors) {
    REQUIRE_CASES();
    struct Case {
        const char* file;
        ErrorKind kind;
        std::vector<std::string> expected;  // substrings of the message
    };
    const Case cases[] = {
        {"bad_not_hdf5.vtkhdf", ErrorKind::Parse, {"not an HDF5 file"}},
        {"bad_no_vtkhdf.hdf", ErrorKind::Parse, {"without a /VTKHDF group"}},
        {"bad_type.vtkhdf", ErrorKind::Unsupported, {"Type 'PolyData'", "UnstructuredGrid"}},
        {"bad_version.vtkhdf", ErrorKind::Unsupported, {"Version 3.0", "major version 1 or 2"}},
        {"bad_typeless_image.vtkhdf", ErrorKind::Unsupported, {"Type 'ImageData'"}},
        {"bad_missing_connectivity.vtkhdf",
         ErrorKind::Parse,
         {"/VTKHDF/Connectivity", "missing dataset"}},
        {"bad_offsets_decrease.vtkhdf",
         ErrorKind::Parse,
         {"/VTKHDF/Offsets", "offset 3 (2) is below the one before (14)"}},
        {"bad_connectivity_range.vtkhdf",
         ErrorKind::Validation,
         {"partition 0", "cell 0", "point index 99 out of range [0, 14)"}},
        {"bad_field_rows.vtkhdf",
         ErrorKind::Parse,
         {"/VTKHDF/PointData/temp", "has 10 rows", "needs rows [0, 14)"}},
        {"bad_partition_count.vtkhdf",
         ErrorKind::Parse,
         {"/VTKHDF/NumberOfCells", "lists 1 partition(s)", "NumberOfPoints lists 2"}},
        {"bad_absurd_count.vtkhdf",
         ErrorKind::Parse,
         {"/VTKHDF/Points", "has 14 rows", "needs rows [0, 1000000000000000)"}},
        {"bad_sparse_points.vtkhdf",
         ErrorKind::Parse,
         {"/VTKHDF/Points", "needs 1000000000 rows of 12 bytes", "stores only 12288 bytes"}},
        {"bad_cell_type.vtkhdf", ErrorKind::Parse, {"cell 5", "unknown VTK cell type 200"}},
        {"bad_points_shape.vtkhdf", ErrorKind::Parse, {"/VTKHDF/Points", "N x 3"}},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.file);
        const std::string path = caseFile(c.file);
        const Error e = catchError([&] { (void)readVtkHdf(path); });
        const std::string message = e.what();
        EXPECT_EQ(e.kind(), c.kind) << message;
        EXPECT_EQ(message.rfind(path, 0), 0u) << message;  // names the file first
        for (const std::string& s : c.expected)
            EXPECT_NE(message.find(s), std::string::npos) << message << "\nexpected: " << s;
    }
}

TEST(VtkHdf, MemoryLimitIsChargedBeforeReading) {
    REQUIRE_CASES();
    ReadOptions options;
    options.maxMemoryBytes = 200;  // the 14 points alone need 168 bytes, the fields more
    const Error e = catchError([&] { (void)readVtkHdf(caseFile("mixed.vtkhdf"), options); });
    EXPECT_EQ(e.kind(), ErrorKind::Resource) << e.what();
    EXPECT_NE(std::string(e.what()).find("(`max_memory`)"), std::string::npos) << e.what();
    options.maxMemoryBytes = 1 << 20;
    EXPECT_EQ(readVtkHdf(caseFile("mixed.vtkhdf"), options).cellCount(), 5u);
}

// ---- VTK's vtkHDFReader as the oracle ----

/// What VTK's vtkHDFReader reads from path (JSON of tests/tools/vtkhdf_oracle.py); null when
/// python3-vtk9 is missing.
nlohmann::json vtkRead(const std::string& path, const std::string& dir) {
    const std::string out = dir + "/oracle.json";
    const int status = testing::runCommand(std::string(testing::systemPython()) + " " +
                                           testing::testTool("vtkhdf_oracle.py") + " " + path +
                                           " > " + out + " 2>/dev/null");
    if (status == 77) return nullptr;
    EXPECT_EQ(status, 0) << "vtkhdf_oracle.py failed on " << path;
    std::ifstream in(out);
    return nlohmann::json::parse(in);
}

/// uvr's mesh equals VTK's reading of the same file: points, and the volumetric cells in order
/// (types, point ids), fields tuple by tuple (cell fields of the kept cells).
void expectSameAsVtk(const Mesh& mesh, const nlohmann::json& vtk) {
    const auto& pts = vtk["points"];
    ASSERT_EQ(pts.size(), 3 * mesh.pointCount());
    for (std::size_t i = 0; i < mesh.pointCount(); ++i) {
        EXPECT_EQ(mesh.points[i].x, float(pts[3 * i].get<double>()));
        EXPECT_EQ(mesh.points[i].y, float(pts[3 * i + 1].get<double>()));
        EXPECT_EQ(mesh.points[i].z, float(pts[3 * i + 2].get<double>()));
    }
    std::vector<std::size_t> kept;  // VTK's index of each uvr cell
    const auto& types = vtk["types"];
    const auto& offsets = vtk["offsets"];
    const auto& conn = vtk["connectivity"];
    for (std::size_t c = 0; c < types.size(); ++c)
        if (vtkCellTypeInfo(types[c].get<int>()).volumetric) kept.push_back(c);
    ASSERT_EQ(kept.size(), mesh.cellCount());
    for (std::size_t c = 0; c < kept.size(); ++c) {
        EXPECT_EQ(int(mesh.cellTypes[c]), types[kept[c]].get<int>()) << "cell " << c;
        const auto ids = mesh.cell(c);
        const std::size_t begin = offsets[kept[c]].get<std::size_t>();
        for (std::size_t k = 0; k < ids.size(); ++k)
            EXPECT_EQ(ids[k], conn[begin + k].get<std::uint32_t>()) << "cell " << c;
    }
    std::size_t compared = 0;
    for (const Field& f : mesh.fields) {
        const bool point = f.association == Association::Point;
        const auto& arrays = vtk[point ? "point_data" : "cell_data"];
        ASSERT_TRUE(arrays.contains(f.name)) << f.name;
        const auto& a = arrays[f.name];
        ASSERT_EQ(a["components"].get<int>(), f.components) << f.name;
        const auto& v = a["values"];
        const std::size_t comps = static_cast<std::size_t>(f.components);
        for (std::size_t t = 0; t < f.tupleCount(); ++t) {
            const std::size_t source = point ? t : kept[t];
            for (std::size_t k = 0; k < comps; ++k)
                EXPECT_EQ(f.values[t * comps + k], float(v[source * comps + k].get<double>()))
                    << f.name << " tuple " << t;
        }
        ++compared;
    }
    EXPECT_EQ(compared, mesh.fields.size());
}

TEST(VtkHdf, ReadsAsVtkHdfReaderDoes) {
    REQUIRE_CASES();
    const std::string dir = testing::scratchDir();
    for (const char* name : {"mixed.vtkhdf", "parts.vtkhdf"}) {
        SCOPED_TRACE(name);
        const nlohmann::json vtk = vtkRead(caseFile(name), dir);
        if (vtk.is_null()) GTEST_SKIP() << "no vtk module in /usr/bin/python3";
        expectSameAsVtk(readVtkHdf(caseFile(name)), vtk);
    }
}

// ---- Writing ----

void expectSameMesh(const Mesh& a, const Mesh& b) {
    ASSERT_EQ(a.pointCount(), b.pointCount());
    ASSERT_EQ(a.cellCount(), b.cellCount());
    EXPECT_TRUE(sameGeometry(a, b));
    expectSameFields(a.fields, b.fields);
}

TEST(VtkHdf, WrittenFilesReadBackIdentically) {
    if (!vtkHdfSupported()) GTEST_SKIP() << "built without HDF5";
    if (!testing::haveSharedData()) GTEST_SKIP() << "no shared data";
    const std::string dir = testing::scratchDir();
    for (const char* name : {"bluntfin_tets.vtk", "fire_ug.vtu", "hexa.vtk"}) {
        SCOPED_TRACE(name);
        const std::string source = testing::sharedData(name);
        if (!std::filesystem::exists(source)) continue;
        const Mesh mesh = readMesh(source);
        const std::string out = dir + "/out.vtkhdf";
        double last = -1;
        writeMesh(mesh, out, [&](double f) {
            EXPECT_GE(f, last);
            last = f;
        });
        EXPECT_EQ(last, 1.0);
        expectSameMesh(readMesh(out), mesh);
    }
}

TEST(VtkHdf, WrittenFilesReadByVtkHdfReader) {
    REQUIRE_CASES();
    const std::string dir = testing::scratchDir();
    const Mesh mesh = readVtkHdf(caseFile("parts.vtkhdf"));
    const std::string out = dir + "/written.vtkhdf";
    writeVtkHdf(mesh, out);
    const nlohmann::json vtk = vtkRead(out, dir);
    if (vtk.is_null()) GTEST_SKIP() << "no vtk module in /usr/bin/python3";
    EXPECT_EQ(vtk["types"].size(), mesh.cellCount());  // only volumetric cells were written
    // Version 1.0, which VTK 9.1 reads without a warning (2.2 made it warn; issue 35).
    EXPECT_EQ(vtk["messages"].get<std::string>(), "");
    expectSameAsVtk(mesh, vtk);
    expectSameMesh(readVtkHdf(out), mesh);
}

TEST(VtkHdf, WriterRefusesNamesHdf5CannotHold) {
    if (!vtkHdfSupported()) GTEST_SKIP() << "built without HDF5";
    const std::string dir = testing::scratchDir();
    Mesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const std::uint32_t ids[4] = {0, 1, 2, 3};
    mesh.addCell(CellType::Tetra, ids);
    mesh.fields.push_back({"a/b", Association::Point, 1, {1, 2, 3, 4}});
    const Error e = catchError([&] { writeVtkHdf(mesh, dir + "/x.vtkhdf"); });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_NE(std::string(e.what()).find("'a/b'"), std::string::npos) << e.what();
    EXPECT_FALSE(std::filesystem::exists(dir + "/x.vtkhdf"));
    mesh.fields[0].name = "a";
    mesh.fields.push_back({"a", Association::Point, 1, {1, 2, 3, 4}});
    EXPECT_EQ(catchError([&] { writeVtkHdf(mesh, dir + "/x.vtkhdf"); }).kind(),
              ErrorKind::Argument);
    mesh.fields[1].association = Association::Cell;  // one per association is fine
    mesh.fields[1].values = {7};
    writeVtkHdf(mesh, dir + "/x.vtkhdf");
    expectSameMesh(readVtkHdf(dir + "/x.vtkhdf"), mesh);
}

TEST(VtkHdf, ConvertWritesVtkhdf) {
    if (!vtkHdfSupported()) GTEST_SKIP() << "built without HDF5";
    if (!testing::haveSharedData()) GTEST_SKIP() << "no shared data";
    const std::string dir = testing::scratchDir();
    const std::string in = testing::sharedData("tetraMesh.vtk");
    ASSERT_EQ(
        testing::runCommand(testing::uvrBinary() + " -q convert " + in + " " + dir + "/t.vtkhdf"),
        0);
    expectSameMesh(readMesh(dir + "/t.vtkhdf"), readMesh(in));
}

}  // namespace
}  // namespace uvr

#undef REQUIRE_CASES  // file-local: the unity build joins test files
