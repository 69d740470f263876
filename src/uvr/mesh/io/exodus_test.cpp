// SPDX-License-Identifier: MIT
// The Exodus II reader against VTK's vtkExodusIIReader (tests/tools/exodus_oracle.py) on the
// ParaView tutorial's disk_out_ref.ex2, on a file VTK's writer makes at test time and on files
// written here through netCDF (every block type, both old and new layouts, netCDF-4), value by
// value at several steps; and bad files, each with its message.
#include "uvr/mesh/io/exodus.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <tuple>

#include "test_support.h"
#include "uvr/core/file_util.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/mesh/io/time_series.h"
#include "uvr/mesh/validate.h"

#ifdef UVR_HAVE_NETCDF
#include "exodus_file_writer.h"
#endif

namespace uvr {
namespace {

using testing::catchError;

using testing::kDiskOutRef;

/// Skips the test unless this uvr reads Exodus files.
#define REQUIRE_EXODUS()                                                \
    do {                                                                \
        if (!exodusSupported()) GTEST_SKIP() << "built without netCDF"; \
    } while (0)

/// The oracle's reading of file at the steps, or an empty object when VTK is missing (the
/// caller skips).
nlohmann::json vtkReading(const std::string& file, const std::string& dir,
                          const std::vector<int>& steps) {
    if (!testing::pythonHas("vtk")) return {};
    const std::string out = dir + "/vtk.json";
    std::string cmd = std::string(testing::systemPython()) + " " +
                      testing::testTool("exodus_oracle.py") + " dump " + file + " " + out;
    for (int s : steps) cmd += " " + std::to_string(s);
    EXPECT_EQ(testing::runCommand(cmd + " > " + dir + "/vtk.log 2>&1"), 0) << cmd;
    std::ifstream in(out);
    return nlohmann::json::parse(in);
}

/// Expects a float read by uvr to be the file's value rounded to float (NaN for NaN).
void expectValue(float got, const nlohmann::json& want, const std::string& what) {
    if (want.is_null() || (want.is_number() && std::isnan(want.get<double>()))) {
        EXPECT_TRUE(std::isnan(got)) << what;
        return;
    }
    EXPECT_EQ(got, static_cast<float>(want.get<double>())) << what;
}

/// Expects fields of one association to equal the oracle's (names, components, values).
void expectFields(const Mesh& mesh, Association association, const nlohmann::json& want) {
    std::size_t count = 0;
    for (const Field& f : mesh.fields) {
        if (f.association != association) continue;
        ++count;
        ASSERT_TRUE(want.contains(f.name)) << "uvr's field " << f.name << " is not VTK's";
        const nlohmann::json& w = want[f.name];
        EXPECT_EQ(f.components, w["components"].get<int>()) << f.name;
        ASSERT_EQ(f.values.size(), w["values"].size()) << f.name;
        for (std::size_t k = 0; k < f.values.size(); ++k)
            expectValue(f.values[k], w["values"][k], f.name + "[" + std::to_string(k) + "]");
    }
    EXPECT_EQ(count, want.size()) << "fields of association " << associationName(association);
}

/// Expects a mesh to equal the oracle's reading of one step: points, cells (types and point
/// ids, cell by cell), point and cell fields value by value.
void expectSameAsVtkStep(const Mesh& mesh, const nlohmann::json& step) {
    const nlohmann::json& points = step["points"];
    ASSERT_EQ(mesh.pointCount() * 3, points.size());
    for (std::size_t i = 0; i < mesh.pointCount(); ++i)
        for (int d = 0; d < 3; ++d)
            expectValue(mesh.points[i][d], points[i * 3 + d], "point " + std::to_string(i));
    const nlohmann::json& types = step["types"];
    const nlohmann::json& ids = step["ids"];
    ASSERT_EQ(mesh.cellCount(), types.size());
    ASSERT_EQ(mesh.cellIndices.size(), ids.size());
    for (std::size_t c = 0; c < mesh.cellCount(); ++c) {
        EXPECT_EQ(static_cast<int>(mesh.cellTypes[c]), types[c].get<int>()) << "cell " << c;
        for (std::uint64_t k = mesh.cellOffsets[c]; k < mesh.cellOffsets[c + 1]; ++k)
            EXPECT_EQ(mesh.cellIndices[k], ids[k].get<std::uint32_t>()) << "cell " << c;
    }
    expectFields(mesh, Association::Point, step["point"]);
    expectFields(mesh, Association::Cell, step["cell"]);
}

/// True when a note contains text.
bool hasNote(const Mesh& mesh, const std::string& text) {
    for (const std::string& n : mesh.notes)
        if (n.find(text) != std::string::npos) return true;
    return false;
}

TEST(Exodus, DiskOutRefMatchesVtk) {
    REQUIRE_EXODUS();
    if (!std::filesystem::exists(kDiskOutRef)) GTEST_SKIP() << "mayavi2 is not installed";
    const Mesh mesh = readMesh(kDiskOutRef);  // sniffed as Exodus
    EXPECT_EQ(mesh.pointCount(), 8499u);
    EXPECT_EQ(mesh.cellCount(), 7472u);
    const Bounds3f b = mesh.bounds();
    EXPECT_FLOAT_EQ(b.lo.x, -5.75f);
    EXPECT_FLOAT_EQ(b.hi.z, 10.16f);
    const Field* v = mesh.findField("V", Association::Point);  // VX, VY, VZ
    ASSERT_NE(v, nullptr);
    EXPECT_EQ(v->components, 3);
    const ValidationReport report = validateMesh(mesh, kDiskOutRef);
    EXPECT_EQ(report.invertedCells, 0u);
    const std::string dir = testing::scratchDir();
    const nlohmann::json vtk = vtkReading(kDiskOutRef, dir, {0});
    if (vtk.is_null()) GTEST_SKIP() << "python3-vtk9 is missing";
    EXPECT_EQ(vtk["times"], nlohmann::json::array({0.0}));
    expectSameAsVtkStep(mesh, vtk["steps"][0]);
}

TEST(Exodus, VtkWrittenFileMatchesVtkAtEveryStep) {
    REQUIRE_EXODUS();
    if (!testing::pythonHas("vtk")) GTEST_SKIP() << "python3-vtk9 is missing";
    const std::string dir = testing::scratchDir();
    const std::string file = dir + "/vtk_written.e";
    ASSERT_EQ(testing::runCommand(std::string(testing::systemPython()) + " " +
                                  testing::testTool("exodus_oracle.py") + " write " + file + " > " +
                                  dir + "/write.log 2>&1"),
              0);
    const nlohmann::json vtk = vtkReading(file, dir, {0, 1, 2});
    auto series = openMeshSeries(file);
    ASSERT_EQ(series->stepCount(), 3u);
    EXPECT_EQ(series->times(), (std::vector<double>{0.0, 0.5, 1.5}));
    Mesh first;
    for (std::size_t s = 0; s < 3; ++s) {
        SCOPED_TRACE("step " + std::to_string(s));
        Mesh mesh = series->readStep(s);
        expectSameAsVtkStep(mesh, vtk["steps"][s]);
        EXPECT_TRUE(hasNote(mesh, "TRIANGLE element(s), not volume cells")) << mesh.notes.size();
        EXPECT_EQ(validateMesh(mesh, file).invertedCells, 0u);
        if (s == 0) first = std::move(mesh);
    }
    // Fields alone: the same as readStep's, and none for another geometry.
    const auto fields = series->readFieldsIfSameGeometry(2, first);
    ASSERT_TRUE(fields.has_value());
    const Mesh whole = series->readStep(2);
    ASSERT_EQ(fields->size(), whole.fields.size());
    for (std::size_t k = 0; k < fields->size(); ++k) {
        EXPECT_EQ((*fields)[k].name, whole.fields[k].name);
        EXPECT_EQ((*fields)[k].values, whole.fields[k].values);
    }
    Mesh other = first;
    other.points.pop_back();
    EXPECT_FALSE(series->readFieldsIfSameGeometry(1, other).has_value());
    EXPECT_EQ(catchError([&] { (void)series->readStep(3); }).kind(), ErrorKind::Argument);
}

#ifdef UVR_HAVE_NETCDF

/// A file of one cell per jittered unit cube: blocks of TETRA10 (higher order), HEX8, WEDGE6,
/// PYRAMID5, a SHELL4 block to drop and an empty block; nodal variables temp and vel_x/_y/_z,
/// element variables sx, sy, sz (not on the wedges) and id; two steps.
testing::ExoFileSpec mixedSpec() {
    testing::ExoFileSpec spec;
    const int cubes = 12;
    for (int k = 0; k < cubes; ++k)
        for (int b = 0; b < 8; ++b) {
            spec.x.push_back(2.0 * k + (b & 1) + 0.05 * std::sin(7.0 * k + b));
            spec.y.push_back(((b >> 1) & 1) + 0.05 * std::cos(3.0 * k + b));
            spec.z.push_back(((b >> 2) & 1) + 0.05 * std::sin(5.0 * k - b));
        }
    // Corners in VTK order (which Exodus shares) of the cube's nodes (x, y, z) bits; a wedge's
    // first triangle has its normal away from the second, as VTK's wedge.
    const std::vector<std::vector<int>> corners = {
        {0, 1, 2, 4}, {0, 1, 3, 2, 4, 5, 7, 6}, {0, 2, 1, 4, 6, 5}, {0, 1, 3, 2, 4}, {0, 1, 3, 2}};
    spec.blocks = {{100, "TETRA10", 10, {}, "tets"}, {200, "HEX8", 8, {}, "hexes"},
                   {300, "WEDGE", 6, {}, "wedges"},  {400, "PYRAMID5", 5, {}, ""},
                   {500, "SHELL4", 4, {}, "skin"},   {600, "NULL", 0, {}, "empty"}};
    for (int k = 0; k < cubes; ++k) {
        const int b = k % 5;
        testing::ExoBlock& block = spec.blocks[b];
        for (int c : corners[b]) block.connect.push_back(8 * k + c + 1);
        for (std::size_t extra = corners[b].size(); extra < block.nodesPerElement; ++extra)
            block.connect.push_back(8 * k + 1 + static_cast<int>(extra % 8));  // mid-edge nodes
    }
    spec.nodalVars = {"temp", "vel_x", "vel_y", "vel_z"};
    spec.elemVars = {"sx", "sy", "sz", "id"};
    spec.truthTable = {1, 1, 1, 1,  //
                       1, 1, 1, 1,  //
                       0, 0, 0, 1,  //
                       1, 1, 1, 1,  //
                       1, 1, 1, 1,  //
                       0, 0, 0, 0};
    spec.times = {0.25, 2.0};
    spec.nodal = [](std::size_t s, std::size_t v, std::size_t n) {
        return 1000.0 * v + 10.0 * s + 0.5 * n + 1.0 / 3.0;
    };
    spec.element = [](std::size_t s, std::size_t v, std::size_t b, std::size_t e) {
        return 100.0 * b + 10.0 * v + e + 0.1 * s;
    };
    return spec;
}

/// Writes the spec as NAME in dir and returns its path.
std::string writeSpec(const testing::ExoFileSpec& spec, const std::string& dir,
                      const std::string& name) {
    const std::string path = dir + "/" + name;
    testing::writeExodusFile(path, spec);
    return path;
}

TEST(Exodus, NetcdfWrittenFilesMatchVtk) {
    REQUIRE_EXODUS();
    const std::string dir = testing::scratchDir();
    struct Layout {
        const char* name;
        bool combinedCoord, combinedVars, netcdf4, doubles;
    };
    // The old layouts against the new one (VTK 9.1's reader misreads hand-written old layouts;
    // disk_out_ref.ex2 checks a real one against it).
    std::vector<Mesh> reference;
    for (const Layout layout : {Layout{"new.exo", false, false, false, false},
                                Layout{"oldcoord.ex2", true, false, false, false},
                                Layout{"oldvars.ex2", false, true, false, false},
                                Layout{"hdf5.e", false, false, true, true}}) {
        SCOPED_TRACE(layout.name);
        testing::ExoFileSpec spec = mixedSpec();
        spec.combinedCoord = layout.combinedCoord;
        spec.combinedNodalVars = layout.combinedVars;
        spec.netcdf4 = layout.netcdf4;
        spec.doubles = layout.doubles;
        const std::string file = writeSpec(spec, dir, layout.name);
        auto series = openMeshSeries(file);
        ASSERT_EQ(series->stepCount(), 2u);
        EXPECT_EQ(series->times(), spec.times);
        const Mesh mesh = series->readStep(1);
        EXPECT_EQ(mesh.cellCount(), 10u);  // 12 cubes less 2 shells
        EXPECT_EQ(validateMesh(mesh, file).invertedCells, 0u);
        const Field* vel = mesh.findField("vel_", Association::Point);
        ASSERT_NE(vel, nullptr);
        EXPECT_EQ(vel->components, 3);
        const Field* s = mesh.findField("s", Association::Cell);
        ASSERT_NE(s, nullptr);
        EXPECT_EQ(s->components, 3);
        EXPECT_TRUE(hasNote(mesh, "dropped block ID 500 ('skin') (connect5): 2 SHELL4"));
        EXPECT_TRUE(hasNote(mesh, "reduced 3 TETRA10 cell(s) of block ID 100"));
        EXPECT_TRUE(hasNote(mesh, "element variable s is not defined on block ID 300"));
        EXPECT_EQ(readMesh(file).fields[0].values[0], 1.0f / 3.0f);  // readMesh: step 0
        if (layout.combinedCoord || layout.combinedVars) {
            for (std::size_t step = 0; step < 2; ++step) {
                const Mesh old = series->readStep(step);
                EXPECT_TRUE(sameGeometry(old, reference[step]));
                ASSERT_EQ(old.fields.size(), reference[step].fields.size());
                for (std::size_t k = 0; k < old.fields.size(); ++k) {
                    EXPECT_EQ(old.fields[k].name, reference[step].fields[k].name);
                    EXPECT_EQ(old.fields[k].values.size(), reference[step].fields[k].values.size());
                    for (std::size_t i = 0; i < old.fields[k].values.size(); ++i) {
                        const float a = old.fields[k].values[i],
                                    b = reference[step].fields[k].values[i];
                        EXPECT_TRUE(a == b || (std::isnan(a) && std::isnan(b)))
                            << old.fields[k].name;
                    }
                }
            }
            continue;
        }
        if (reference.empty()) reference = {series->readStep(0), series->readStep(1)};
        const nlohmann::json vtk = vtkReading(file, dir, {0, 1});
        if (vtk.is_null()) continue;
        expectSameAsVtkStep(series->readStep(0), vtk["steps"][0]);
        expectSameAsVtkStep(mesh, vtk["steps"][1]);
    }
}

TEST(Exodus, ARankReadsItsRunOfTheCellsAsMeshPartTakesIt) {
    // A data-parallel rank's part, read over its rows only, equals the part meshPart takes from
    // the whole step: across blocks (a dropped shell block and a reduced TETRA10 one among
    // them), in every layout, for the nodal and element variables of step 1.
    REQUIRE_EXODUS();
    const std::string dir = testing::scratchDir();
    const auto same = [](const std::vector<float>& a, const std::vector<float>& b) {
        if (a.size() != b.size()) return false;
        for (std::size_t i = 0; i < a.size(); ++i)
            if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) return false;
        return true;
    };
    for (const auto& [name, combinedCoord, combinedVars, netcdf4] :
         {std::tuple{"new.exo", false, false, false},
          std::tuple{"oldcoord.ex2", true, false, false},
          std::tuple{"oldvars.ex2", false, true, false},
          std::tuple{"hdf5.e", false, false, true}}) {
        SCOPED_TRACE(name);
        testing::ExoFileSpec spec = mixedSpec();
        spec.combinedCoord = combinedCoord;
        spec.combinedNodalVars = combinedVars;
        spec.netcdf4 = netcdf4;
        const std::string file = writeSpec(spec, dir, name);
        const Mesh whole = openMeshSeries(file)->readStep(1);
        ASSERT_EQ(exodusCellCount(file), whole.cellCount());
        for (const auto& [a, b] :
             {std::pair<std::uint64_t, std::uint64_t>{0, 10}, {0, 3}, {3, 7}, {7, 10}, {5, 6}}) {
            SCOPED_TRACE("cells [" + std::to_string(a) + ", " + std::to_string(b) + ")");
            const MeshPart want = meshPart(whole, a, b);
            const MeshPart got = readExodusPart(file, a, b, {}, 1);
            EXPECT_EQ(got.pointIds, want.pointIds);
            EXPECT_EQ(got.cellIds, want.cellIds);
            EXPECT_EQ(got.mesh.points, want.mesh.points);
            EXPECT_EQ(got.mesh.cellTypes, want.mesh.cellTypes);
            EXPECT_EQ(got.mesh.cellOffsets, want.mesh.cellOffsets);
            EXPECT_EQ(got.mesh.cellIndices, want.mesh.cellIndices);
            ASSERT_EQ(got.mesh.fields.size(), want.mesh.fields.size());
            for (std::size_t k = 0; k < want.mesh.fields.size(); ++k) {
                EXPECT_EQ(got.mesh.fields[k].name, want.mesh.fields[k].name);
                EXPECT_EQ(got.mesh.fields[k].association, want.mesh.fields[k].association);
                EXPECT_TRUE(same(got.mesh.fields[k].values, want.mesh.fields[k].values))
                    << want.mesh.fields[k].name;
            }
            EXPECT_EQ(got.mesh.notes, whole.notes);
        }
        EXPECT_THROW(readExodusPart(file, 4, 11), Error);
    }
}

TEST(Exodus, NoTimeStepsIsOneStepAtTimeZero) {
    REQUIRE_EXODUS();
    testing::ExoFileSpec spec = mixedSpec();
    spec.times.clear();
    const std::string file = writeSpec(spec, testing::scratchDir(), "static.g");
    auto series = openMeshSeries(file);
    EXPECT_EQ(series->times(), std::vector<double>{0.0});
    const Mesh mesh = series->readStep(0);
    EXPECT_EQ(mesh.cellCount(), 10u);
    EXPECT_TRUE(mesh.fields.empty());
}

TEST(Exodus, DisplacementIsAFieldWithANote) {
    REQUIRE_EXODUS();
    testing::ExoFileSpec spec = mixedSpec();
    spec.nodalVars = {"temp", "DISPLX", "DISPLY", "DISPLZ"};
    const Mesh mesh = readExodus(writeSpec(spec, testing::scratchDir(), "disp.e"));
    EXPECT_NE(mesh.findField("DISPL", Association::Point), nullptr);
    EXPECT_TRUE(hasNote(mesh, "geometry is not displaced"));
    EXPECT_EQ(mesh.points[1][0], static_cast<float>(mixedSpec().x[1]));
}

TEST(Exodus, BadFilesNameFileAndPlace) {
    REQUIRE_EXODUS();
    const std::string dir = testing::scratchDir();
    auto message = [&](const testing::ExoFileSpec& spec, const std::string& name) {
        const std::string path = dir + "/" + name;
        testing::writeExodusFile(path, spec);
        SCOPED_TRACE(name);
        const Error e = catchError([&] { (void)readExodus(path); });
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        return std::string(e.what());
    };
    auto expectIn = [](const std::string& text, const std::string& part) {
        EXPECT_NE(text.find(part), std::string::npos) << text;
    };
    {
        testing::ExoFileSpec spec = mixedSpec();
        spec.writeCoordinates = false;
        expectIn(message(spec, "nocoords.e"), "no coordinates: expected the variables coordx");
    }
    {
        testing::ExoFileSpec spec = mixedSpec();
        spec.blocks[1].connect[8 + 3] = 9999;  // the second hexahedron's fourth corner
        expectIn(message(spec, "range.e"),
                 "block ID 200 ('hexes') (connect2), element 2: node 9999 out of range [1, 96]");
    }
    {
        testing::ExoFileSpec spec = mixedSpec();
        spec.blocks[1].elemType = "HEX20";
        expectIn(message(spec, "npe.e"),
                 "elem_type 'HEX20' with 8 nodes per element (num_nod_per_el2), expected 20");
        spec.blocks[1].elemType = "HEX";
        spec.blocks[1].nodesPerElement = 4;
        expectIn(message(spec, "npe2.e"), "expected one of 8, 9, 20, 27 for a HEX");
    }
    {
        testing::ExoFileSpec spec = mixedSpec();
        spec.firstNodalVarDim = "num_el_in_blk1";
        expectIn(message(spec, "shape.e"),
                 "variable vals_nod_var1 has shape (2, 3), expected (2, 96) (time_step, "
                 "num_nodes)");
    }
    {
        testing::ExoFileSpec spec = mixedSpec();
        spec.numDim = 2;
        SCOPED_TRACE("flat");
        expectIn(message(spec, "flat.e"), "num_dim is 2: a 2D mesh holds no volume cells");
    }
    {
        testing::ExoFileSpec spec = mixedSpec();
        spec.blocks.clear();
        const std::string path = dir + "/noblocks.e";
        testing::writeExodusFile(path, spec);
        EXPECT_EQ(readExodus(path).cellCount(), 0u);  // empty; validation reports it
    }
    // Not netCDF at all, and a netCDF file cut short.
    const std::string text = testing::writeFile(dir + "/text.e", "not a netCDF file\n");
    expectIn(catchError([&] { (void)readExodus(text); }).what(),
             "not a readable netCDF (Exodus II) file");
    expectIn(catchError([&] { (void)readMesh(text); }).what(), "unrecognised file format");
    const std::string whole = dir + "/whole.e";
    testing::writeExodusFile(whole, mixedSpec());
    const std::vector<char> bytes = readFileBytes(whole);
    // (A classic file cut by fewer bytes than its header holds is not caught: netCDF reads past
    // the end as fill values, and its API gives no variable's offset.)
    for (std::size_t keep : {std::size_t{6}, bytes.size() / 3, bytes.size() / 2}) {
        SCOPED_TRACE("cut to " + std::to_string(keep) + " bytes");
        const std::string cut = testing::writeFile(dir + "/cut.e", std::string(bytes.data(), keep));
        const Error e = catchError([&] {
            auto series = openMeshSeries(cut);
            for (std::size_t s = 0; s < series->stepCount(); ++s) (void)series->readStep(s);
        });
        expectIn(e.what(), cut);
    }
    // The memory limit is charged before allocating.
    ReadOptions small;
    small.maxMemoryBytes = 1000;
    EXPECT_EQ(catchError([&] { (void)readExodus(whole, small); }).kind(), ErrorKind::Resource);
}

#endif  // UVR_HAVE_NETCDF

TEST(Exodus, SniffsNetcdfAndHdf5WithAnExodusExtension) {
    EXPECT_TRUE(looksLikeExodus(std::string("CDF\x01", 4), "a.e"));
    EXPECT_TRUE(looksLikeExodus(std::string("CDF\x02", 4), "a.EXO"));
    EXPECT_TRUE(looksLikeExodus(std::string("CDF\x05", 4), "a.ex2"));
    EXPECT_TRUE(looksLikeExodus(std::string("\x89HDF\r\n\x1a\n", 8), "mesh.g"));
    EXPECT_FALSE(looksLikeExodus(std::string("CDF\x03", 4), "a.e"));
    EXPECT_FALSE(looksLikeExodus(std::string("CDF\x01", 4), "a.nc"));
    EXPECT_FALSE(looksLikeExodus(std::string("\x89HDF\r\n\x1a\n", 8), "a.vtkhdf"));
}

}  // namespace
}  // namespace uvr

#undef REQUIRE_EXODUS  // file-local: the unity build joins test files
