// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/vtu.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/mesh/io/vtk_compression.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;

// ---- helpers ----

/// Folder of the files tests/tools/write_vtu_variants.py writes, generated once per process
/// ("" when the system Python lacks vtk or meshio).
const std::string& variantsDir() {
    static const std::string dir = [] {
        if (!uvr::testing::pythonHas("vtk") || !uvr::testing::pythonHas("meshio"))
            return std::string();
        const std::filesystem::path out = std::filesystem::temp_directory_path() / "uvr_tests" /
                                          ("vtu_variants_" + std::to_string(::getpid()));
        std::filesystem::remove_all(out);
        std::filesystem::create_directories(out);
        const std::string script = uvr::testing::testTool("write_vtu_variants.py");
        const std::string cmd = std::string(uvr::testing::systemPython()) + " " + script + " " +
                                out.string() + " >" + (out / "log.txt").string() + " 2>&1";
        if (uvr::testing::runCommand(cmd) != 0) {
            ADD_FAILURE() << "write_vtu_variants.py failed; see " << (out / "log.txt");
            return std::string();
        }
        return out.string();
    }();
    return dir;
}

/// Removes the generated folder when the test binary exits.
struct VariantsCleanup {
    ~VariantsCleanup() {
        std::error_code ec;
        std::filesystem::remove_all(std::filesystem::temp_directory_path() / "uvr_tests" /
                                        ("vtu_variants_" + std::to_string(::getpid())),
                                    ec);
    }
} variantsCleanup;

#define REQUIRE_VARIANTS()                                                               \
    do {                                                                                 \
        if (variantsDir().empty()) GTEST_SKIP() << "no vtk/meshio in the system python"; \
    } while (0)

std::string variantPath(const std::string& name) {
    return variantsDir() + "/" + name;
}

nlohmann::json loadJson(const std::string& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in);
}

/// Replaces the first occurrence of from (which must occur) with to.
std::string replaceOnce(std::string text, const std::string& from, const std::string& to) {
    const std::size_t pos = text.find(from);
    EXPECT_NE(pos, std::string::npos) << "'" << from << "' not found";
    if (pos != std::string::npos) text.replace(pos, from.size(), to);
    return text;
}

/// 1-based line number of byte offset pos in text.
std::uint64_t lineOf(const std::string& text, std::size_t pos) {
    return 1 + static_cast<std::uint64_t>(std::count(text.begin(), text.begin() + pos, '\n'));
}

/// Asserts that mesh equals the expected values (exact float32 equality).
void expectMatches(const Mesh& mesh, const nlohmann::json& exp) {
    const auto& pts = exp["points"];
    ASSERT_EQ(mesh.pointCount(), exp["pointCount"].get<std::uint64_t>());
    for (std::size_t i = 0; i < mesh.pointCount(); ++i) {
        EXPECT_EQ(mesh.points[i].x, pts[3 * i].get<float>()) << "point " << i;
        EXPECT_EQ(mesh.points[i].y, pts[3 * i + 1].get<float>()) << "point " << i;
        EXPECT_EQ(mesh.points[i].z, pts[3 * i + 2].get<float>()) << "point " << i;
    }
    std::vector<int> types;
    for (CellType t : mesh.cellTypes) types.push_back(static_cast<int>(t));
    EXPECT_EQ(types, exp["cellTypes"].get<std::vector<int>>());
    EXPECT_EQ(mesh.cellOffsets, exp["cellOffsets"].get<std::vector<std::uint64_t>>());
    EXPECT_EQ(mesh.cellIndices, exp["cellIndices"].get<std::vector<std::uint32_t>>());
    ASSERT_EQ(mesh.fields.size(), exp["fields"].size());
    for (const auto& f : exp["fields"]) {
        const Association assoc =
            f["association"] == "point" ? Association::Point : Association::Cell;
        const Field* field = mesh.findField(f["name"].get<std::string>(), assoc);
        ASSERT_NE(field, nullptr) << f["name"];
        EXPECT_EQ(field->components, f["components"].get<int>()) << f["name"];
        EXPECT_EQ(field->values, f["values"].get<std::vector<float>>()) << f["name"];
    }
}

// ---- real data ----

TEST(VtuSharedData, FireUgMatchesVtk) {
    if (!uvr::testing::haveSharedData()) GTEST_SKIP() << "no shared data";
    const Mesh mesh = readVtu(uvr::testing::sharedData("fire_ug.vtu"));
    // Values from /usr/bin/python3 + vtk 9.1 vtkXMLUnstructuredGridReader.
    EXPECT_EQ(mesh.pointCount(), 12323u);
    ASSERT_EQ(mesh.cellCount(), 10462u);
    EXPECT_TRUE(std::all_of(mesh.cellTypes.begin(), mesh.cellTypes.end(),
                            [](CellType t) { return t == CellType::Hexahedron; }));
    const Bounds3f b = mesh.bounds();
    EXPECT_EQ(b.lo.x, 0.0f);
    EXPECT_EQ(b.hi.x, 6.0f);
    EXPECT_EQ(b.lo.y, 0.0f);
    EXPECT_EQ(b.hi.y, 2.5f);
    EXPECT_EQ(b.lo.z, 0.0f);
    EXPECT_EQ(b.hi.z, 2.3999998569488525f);
    struct Range {
        const char* name;
        int component, components;
        double lo, hi;
    };
    const Range ranges[] = {{"t", 0, 1, 298.3812255859375, 692.2396850585938},
                            {"uvw", 0, 3, -1.1136356592178345, 2.084019184112549},
                            {"uvw", 1, 3, -1.1742392778396606, 3.8220272064208984},
                            {"uvw", 2, 3, -1.181658148765564, 2.0478460788726807},
                            {"u", 0, 1, -1.1136356592178345, 2.084019184112549},
                            {"v", 0, 1, -1.1742392778396606, 3.8220272064208984},
                            {"w", 0, 1, -1.181658148765564, 2.0478460788726807},
                            {"mfrac", 0, 1, 0.0, 0.5155896544456482}};
    EXPECT_EQ(mesh.fields.size(), 6u);
    for (const Range& r : ranges) {
        const Field* f = mesh.findField(r.name, Association::Point);
        ASSERT_NE(f, nullptr) << r.name;
        ASSERT_EQ(f->components, r.components);
        ASSERT_EQ(f->tupleCount(), 12323u);
        float lo = f->values[r.component], hi = lo;
        for (std::size_t i = r.component; i < f->values.size(); i += r.components) {
            lo = std::min(lo, f->values[i]);
            hi = std::max(hi, f->values[i]);
        }
        EXPECT_EQ(lo, static_cast<float>(r.lo)) << r.name << "[" << r.component << "]";
        EXPECT_EQ(hi, static_cast<float>(r.hi)) << r.name << "[" << r.component << "]";
    }
}

TEST(VtuSharedData, FireUgRefusesAnArrayAboveTheMemoryLimit) {
    if (!uvr::testing::haveSharedData()) GTEST_SKIP() << "no shared data";
    const std::string path = uvr::testing::sharedData("fire_ug.vtu");
    ReadOptions options;
    // The limit bounds the whole load: the file's 631781 bytes fit, the mesh it declares on top
    // does not (refused before any array is decoded).
    options.maxMemoryBytes = 700000;
    testing::expectError(
        [&] { readVtu(path, options); }, ErrorKind::Resource,
        {path + ": the mesh it declares (12323 points, 10462 cells and 98584 field values "
                "in 1 Pieces) needs 667756 bytes",
         "with the 631781 bytes this load holds so far", "memory limit of 700000"});
    options.maxMemoryBytes = 100000;  // below the file itself: refused before reading it
    testing::expectError([&] { readVtu(path, options); }, ErrorKind::Resource,
                         {path + ": the file needs 631781 bytes", "memory limit of 100000"});
}

TEST(VtuSharedData, ProgressRisesToOneAsTheArraysAreDecoded) {
    // Issue 35: a large .vtu showed only elapsed seconds; now the fraction of its arrays' bytes.
    if (!uvr::testing::haveSharedData()) GTEST_SKIP() << "no shared data";
    ReadOptions options;
    std::vector<double> heard;
    options.progress = [&](double f) { heard.push_back(f); };
    const Mesh mesh = readVtu(uvr::testing::sharedData("fire_ug.vtu"), options);
    EXPECT_EQ(mesh.cellCount(), 10462u);
    ASSERT_GE(heard.size(), 4u);  // points, connectivity, offsets, types, fields
    for (std::size_t i = 1; i < heard.size(); ++i) EXPECT_GE(heard[i], heard[i - 1]);
    EXPECT_GT(heard.front(), 0.0);
    EXPECT_LT(heard.front(), 1.0);
    EXPECT_DOUBLE_EQ(heard.back(), 1.0);
}

// ---- files written by VTK and meshio ----

void checkManifest(const std::string& kind, std::size_t expectedFiles) {
    const nlohmann::json manifest = loadJson(variantPath("manifest.json"));
    std::size_t seen = 0;
    for (const auto& entry : manifest) {
        if (entry["kind"] != kind) continue;
        const std::string path = entry["file"];
        SCOPED_TRACE(path);
        ++seen;
        const Mesh mesh = kind == "pvtu" ? readPvtu(path) : readVtu(path);
        expectMatches(mesh, loadJson(path + ".json"));
        EXPECT_TRUE(std::any_of(mesh.notes.begin(), mesh.notes.end(), [](const std::string& n) {
            return n.find("triangle") != std::string::npos;
        }));
    }
    EXPECT_EQ(seen, expectedFiles);
}

TEST(VtuVariants, EveryVtkWriterCombinationMatchesVtk) {
    REQUIRE_VARIANTS();
    // {ascii, binary, appended} x {base64, raw} x {none, zlib} x {UInt32, UInt64} x {LE, BE}.
    checkManifest("vtk", 48);
}

TEST(VtuVariants, MeshioFilesMatchVtk) {
    REQUIRE_VARIANTS();
    checkManifest("meshio", 3);
}

TEST(PvtuVariants, ThreePiecesMatchVtk) {
    REQUIRE_VARIANTS();
    checkManifest("pvtu", 1);
}

TEST(PvtuVariants, PartsArePiecesOfTheWholeReadWithIdsInItsOrder) {
    REQUIRE_VARIANTS();
    const std::string path = variantPath("three.pvtu");
    ASSERT_EQ(pvtuPieceCount(path), 3u);
    const Mesh whole = readPvtu(path);
    std::uint64_t points = 0, cells = 0;  // before the part, in the whole mesh
    for (auto [a, b] : {std::pair<std::size_t, std::size_t>{0, 1}, {1, 3}}) {
        const MeshPart part = readPvtuPart(path, a, b);
        ASSERT_EQ(part.pointIds.size(), part.mesh.pointCount());
        ASSERT_EQ(part.cellIds.size(), part.mesh.cellCount());
        EXPECT_TRUE(std::is_sorted(part.pointIds.begin(), part.pointIds.end()));
        // The part's points, cells and fields are the whole mesh's, from `points`/`cells` on.
        for (std::uint64_t i = 0; i < part.mesh.pointCount(); ++i)
            EXPECT_EQ(part.mesh.points[i], whole.points[points + i]);
        for (std::uint64_t c = 0; c < part.mesh.cellCount(); ++c) {
            EXPECT_EQ(part.mesh.cellTypes[c], whole.cellTypes[cells + c]);
            for (std::size_t k = 0; k < part.mesh.cell(c).size(); ++k)
                EXPECT_EQ(part.mesh.cell(c)[k] + points, whole.cell(cells + c)[k]);
        }
        ASSERT_EQ(part.mesh.fields.size(), whole.fields.size());
        points += part.mesh.pointCount(), cells += part.mesh.cellCount();
    }
    EXPECT_EQ(points, whole.pointCount());
    EXPECT_EQ(cells, whole.cellCount());
    EXPECT_EQ(testing::catchError([&] { readPvtuPart(path, 2, 4); }).kind(), ErrorKind::Argument);
    EXPECT_EQ(testing::catchError([&] { readPvtuPart(path, 1, 1); }).kind(), ErrorKind::Argument);
}

TEST(PvtuVariants, ReadVtuForwardsAPvtu) {
    REQUIRE_VARIANTS();
    expectMatches(readVtu(variantPath("three.pvtu")), loadJson(variantPath("three.pvtu.json")));
    // Progress over the pieces: each piece's fraction of the whole, rising to 1.
    ReadOptions options;
    std::vector<double> heard;
    options.progress = [&](double f) { heard.push_back(f); };
    (void)readVtu(variantPath("three.pvtu"), options);
    ASSERT_FALSE(heard.empty());
    for (std::size_t i = 1; i < heard.size(); ++i) EXPECT_GE(heard[i], heard[i - 1]);
    EXPECT_DOUBLE_EQ(heard.back(), 1.0);
}

TEST(VtuVariants, SeveralPiecesInOneFileAreMerged) {
    REQUIRE_VARIANTS();
    const std::string text = testing::readFile(variantPath("vtk_ascii_raw_none_UInt32_le.vtu"));
    const std::size_t begin = text.find("<Piece"), end = text.find("</Piece>") + 8;
    const std::string piece = text.substr(begin, end - begin);
    const std::string dir = uvr::testing::scratchDir();
    const std::string path = uvr::testing::writeFile(
        dir + "/two.vtu", text.substr(0, end) + "\n" + piece + text.substr(end));
    const Mesh mesh = readVtu(path);
    const nlohmann::json exp = loadJson(variantPath("vtk_ascii_raw_none_UInt32_le.vtu.json"));
    const std::uint64_t n = exp["pointCount"].get<std::uint64_t>();
    const auto indices = exp["cellIndices"].get<std::vector<std::uint32_t>>();
    ASSERT_EQ(mesh.pointCount(), 2 * n);
    ASSERT_EQ(mesh.cellIndices.size(), 2 * indices.size());
    for (std::size_t i = 0; i < indices.size(); ++i) {
        EXPECT_EQ(mesh.cellIndices[i], indices[i]);
        EXPECT_EQ(mesh.cellIndices[indices.size() + i], indices[i] + n);
    }
    const Field* f = mesh.findField("gradient", Association::Cell);
    ASSERT_NE(f, nullptr);
    EXPECT_EQ(f->tupleCount(), 2 * exp["cellTypes"].size());

    // A field missing in the second piece is an error naming that piece.
    const std::string bad = uvr::testing::writeFile(
        dir + "/bad.vtu",
        text.substr(0, end) + "\n" +
            std::regex_replace(piece,
                               std::regex("<DataArray type=\"Int8\" Name=\"i8\"[^]*?"
                                          "</DataArray>"),
                               "") +
            text.substr(end));
    testing::expectError([&] { readVtu(bad); }, ErrorKind::Parse,
                         {bad, "Piece 1 has no point DataArray 'i8', which Piece 0 has"});
}

// ---- bad inputs (edited copies of generated files) ----

class VtuErrors : public ::testing::Test {
protected:
    void SetUp() override {
        if (variantsDir().empty()) GTEST_SKIP() << "no vtk/meshio in the system python";
        dir_ = uvr::testing::scratchDir();
    }
    /// Writes text under the scratch folder and returns its path.
    std::string write(const std::string& name, const std::string& text) {
        return uvr::testing::writeFile(dir_ + "/" + name, text);
    }
    std::string dir_;
};

const char* const kAscii = "vtk_ascii_raw_none_UInt32_le.vtu";
const char* const kBinary = "vtk_binary_b64_none_UInt32_le.vtu";
const char* const kRaw = "vtk_appended_raw_none_UInt32_le.vtu";
const char* const kRawZlib = "vtk_appended_raw_zlib_UInt32_le.vtu";
const char* const kB64Zlib = "vtk_appended_b64_zlib_UInt64_be.vtu";

TEST_F(VtuErrors, MissingFileIsAnIoError) {
    const std::string path = dir_ + "/absent.vtu";
    testing::expectError([&] { readVtu(path); }, ErrorKind::Io, {path});
}

TEST_F(VtuErrors, XmlSyntaxErrorNamesLineAndColumn) {
    const std::string text = testing::readFile(variantPath(kAscii));
    const std::size_t pos = text.find("</Points>");
    const std::string path = write("syntax.vtu", replaceOnce(text, "</Points>", "</Pointz>"));
    testing::expectError(
        [&] { readVtu(path); }, ErrorKind::Parse,
        {path + ": " + "line " + std::to_string(lineOf(text, pos)), "column", "mismatched tag"});
}

TEST_F(VtuErrors, TruncatedInlineFileIsAnXmlError) {
    const std::string text = testing::readFile(variantPath(kBinary));
    const std::string path = write("cut.vtu", text.substr(0, text.size() / 2));
    testing::expectError([&] { readVtu(path); }, ErrorKind::Parse,
                         {path + ": line ", "XML syntax error"});
}

TEST_F(VtuErrors, TruncatedAppendedDataIsRefused) {
    const std::string text = testing::readFile(variantPath(kRaw));
    const std::string path = write("cut.vtu", text.substr(0, text.size() - 400));
    testing::expectError([&] { readVtu(path); }, ErrorKind::Parse,
                         {path + ": byte ", "expected </AppendedData>", "truncated"});
}

TEST_F(VtuErrors, AppendedDataWithoutUnderscoreIsRefused) {
    const std::string text = testing::readFile(variantPath(kRaw));
    const std::size_t tag = text.find("<AppendedData");
    const std::size_t underscore = text.find('_', tag);
    std::string edited = text;
    edited[underscore] = '#';
    const std::string path = write("underscore.vtu", edited);
    testing::expectError([&] { readVtu(path); }, ErrorKind::Parse,
                         {path + ": byte " + std::to_string(underscore), "expected '_'"});
}

TEST_F(VtuErrors, BadBase64CharacterNamesItsByteOffset) {
    std::string text = testing::readFile(variantPath(kBinary));
    const std::size_t tag = text.find("Name=\"u16\"");
    const std::size_t pos = text.find('>', tag) + 20;  // inside the base64 text
    text[pos] = '#';
    const std::string path = write("b64.vtu", text);
    testing::expectError(
        [&] { readVtu(path); }, ErrorKind::Parse,
        {path + ": byte " + std::to_string(pos), "Piece 0: DataArray 'u16'", "got '#'"});
}

/// File offset of the appended data of the array with this Name attribute, and the data start.
std::size_t appendedArrayStart(const std::string& text, const std::string& name) {
    const std::size_t tag = text.find("Name=\"" + name + "\"");
    const std::size_t off = text.find("offset=\"", tag) + 8;
    const std::uint64_t offset = std::stoull(text.substr(off, 20));
    return text.find('_', text.find("<AppendedData")) + 1 + offset;
}

std::uint32_t loadLe32(const std::string& text, std::size_t pos) {
    std::uint32_t v;
    std::memcpy(&v, text.data() + pos, 4);  // the test machine is little-endian, as is the file
    return v;
}

TEST_F(VtuErrors, CorruptZlibBlockIsNamed) {
    std::string text = testing::readFile(variantPath(kRawZlib));
    // Points: 26 x 3 Float64 = 624 bytes in blocks of 256: 3 blocks; corrupt the third.
    const std::size_t start = appendedArrayStart(text, "Points");
    ASSERT_EQ(loadLe32(text, start), 3u);
    const std::size_t block2 =
        start + 6 * 4 + loadLe32(text, start + 12) + loadLe32(text, start + 16);
    for (std::size_t k = 2; k < 8; ++k)
        text[block2 + k] = static_cast<char>(text[block2 + k] ^ 0x5a);
    const std::string path = write("zlib.vtu", text);
    testing::expectError([&] { readVtu(path); }, ErrorKind::Parse,
                         {path + ": byte ", "Piece 0: DataArray 'Points'",
                          "zlib block 2 of DataArray 'Points' is corrupt"});
}

TEST_F(VtuErrors, WrongPointCountIsASizeMismatch) {
    for (const char* name : {kAscii, kBinary, kRaw, kRawZlib, kB64Zlib}) {
        SCOPED_TRACE(name);
        const std::string text = testing::readFile(variantPath(name));
        const std::string path =
            write("count.vtu", replaceOnce(text, "NumberOfPoints=\"26\"", "NumberOfPoints=\"27\""));
        testing::expectError(
            [&] { readVtu(path); }, ErrorKind::Parse,
            {path + ": ", "Piece 0: DataArray 'Points' holds 78 values, expected 81"});
    }
}

TEST_F(VtuErrors, AbsurdCountsAreRefusedBeforeAllocating) {
    const std::string huge = "NumberOfPoints=\"900000000000000\"";
    for (const char* name : {kAscii, kBinary, kRaw, kRawZlib}) {
        SCOPED_TRACE(name);
        const std::string path =
            write("absurd.vtu",
                  replaceOnce(testing::readFile(variantPath(name)), "NumberOfPoints=\"26\"", huge));
        testing::expectError(
            [&] { readVtu(path); }, ErrorKind::Parse,
            {path + ": ", "DataArray 'Points' holds 78 values, expected 2700000000000000"});
    }
    // An uncompressed size header larger than the file.
    std::string text = testing::readFile(variantPath(kRaw));
    const std::size_t start = appendedArrayStart(text, "f64");
    text.replace(start, 4, std::string("\xf8\xff\xff\x7f", 4));
    const std::string path = write("header.vtu", text);
    testing::expectError(
        [&] { readVtu(path); }, ErrorKind::Parse,
        {path + ": byte ", "DataArray 'f64'", "holds 268435455 values, expected 26"});
    // A compressed header declaring 2^32 - 1 blocks.
    text = testing::readFile(variantPath(kRawZlib));
    text.replace(appendedArrayStart(text, "f64"), 4, std::string("\xff\xff\xff\xff", 4));
    const std::string path2 = write("blocks.vtu", text);
    testing::expectError([&] { readVtu(path2); }, ErrorKind::Parse,
                         {path2 + ": byte ", "DataArray 'f64'", "runs past the end of the data"});
}

TEST_F(VtuErrors, MemoryLimitIsAResourceError) {
    ReadOptions options;
    options.maxMemoryBytes = 300;  // less than each file: the load's total is bounded
    for (const char* name : {kAscii, kRaw, kB64Zlib}) {
        SCOPED_TRACE(name);
        const std::string path = variantPath(name);
        testing::expectError([&] { readVtu(path, options); }, ErrorKind::Resource,
                             {path, "memory limit of 300 bytes"});
    }
}

TEST_F(VtuErrors, MissingValueInAsciiArrayNamesTheLine) {
    const std::string text = testing::readFile(variantPath(kAscii));
    const std::size_t tag = text.find("Name=\"cell_id\"");
    const std::size_t textStart = text.find('>', tag) + 1;
    const std::size_t first = text.find_first_not_of(" \n", textStart);
    const std::size_t firstEnd = text.find_first_of(" \n", first);
    const std::string path = write("missing.vtu", text.substr(0, first) + text.substr(firstEnd));
    testing::expectError([&] { readVtu(path); }, ErrorKind::Parse,
                         {path + ": line " + std::to_string(lineOf(text, tag)),
                          "Piece 0: DataArray 'cell_id' holds 7 values, expected 8"});
}

TEST_F(VtuErrors, BadAsciiTokenNamesTheLine) {
    const std::string text = testing::readFile(variantPath(kAscii));
    const std::size_t tag = text.find("Name=\"f64\"");
    const std::size_t textStart = text.find('>', tag) + 1;
    const std::size_t secondLine = text.find('\n', text.find_first_not_of(" \n", textStart));
    const std::size_t token = text.find_first_not_of(" \n", secondLine);
    const std::size_t tokenEnd = text.find_first_of(" \n", token);
    const std::string path =
        write("token.vtu", text.substr(0, token) + "abc" + text.substr(tokenEnd));
    testing::expectError([&] { readVtu(path); }, ErrorKind::Parse,
                         {path + ": line " + std::to_string(lineOf(text, token)),
                          "Piece 0: DataArray 'f64': expected a number (Float64), got 'abc'"});
}

TEST_F(VtuErrors, MissingCellArrayIsNamed) {
    const std::string text = testing::readFile(variantPath(kAscii));
    const std::string path =
        write("noconn.vtu",
              std::regex_replace(text,
                                 std::regex("<DataArray type=\"Int64\" Name=\"connectivity\"[^]*?"
                                            "</DataArray>"),
                                 ""));
    testing::expectError([&] { readVtu(path); }, ErrorKind::Parse,
                         {path + ": line ", "Piece 0: missing <Cells> DataArray 'connectivity'"});
}

TEST_F(VtuErrors, UnknownTypeNameNamesTheLine) {
    const std::string text = testing::readFile(variantPath(kRaw));
    const std::size_t pos = text.find("type=\"Float64\" Name=\"f64\"");
    const std::string path = write("type.vtu", replaceOnce(text, "type=\"Float64\" Name=\"f64\"",
                                                           "type=\"Float128\" Name=\"f64\""));
    testing::expectError([&] { readVtu(path); }, ErrorKind::Parse,
                         {path + ": line " + std::to_string(lineOf(text, pos)),
                          "Piece 0: DataArray 'f64'", "got 'Float128'"});
}

TEST_F(VtuErrors, AppendedOffsetBeyondTheDataIsRefused) {
    const std::string text = testing::readFile(variantPath(kRaw));
    const std::size_t tag = text.find("Name=\"f64\"");
    const std::size_t off = text.find("offset=\"", tag);
    const std::size_t close = text.find('"', off + 8);
    const std::string path =
        write("offset.vtu", text.substr(0, off) + "offset=\"99999999" + text.substr(close));
    testing::expectError(
        [&] { readVtu(path); }, ErrorKind::Parse,
        {path + ": line " + std::to_string(lineOf(text, tag)),
         "Piece 0: DataArray 'f64': offset 99999999 lies beyond the appended data"});
}

/// The ascii file with the element text of the DataArray Name=name replaced.
std::string withAsciiArray(const std::string& text, const std::string& name,
                           const std::string& values) {
    const std::size_t tag = text.find("Name=\"" + name + "\"");
    const std::size_t begin = text.find('>', tag) + 1;
    const std::size_t end = text.find("</DataArray>", begin);
    return text.substr(0, begin) + values + text.substr(end);
}

TEST_F(VtuErrors, UnknownCellTypeIsNamed) {
    const std::string path = write(
        "celltype.vtu",
        withAsciiArray(testing::readFile(variantPath(kAscii)), "types", "10 12 13 14 24 5 99 10"));
    testing::expectError([&] { readVtu(path); }, ErrorKind::Parse,
                         {path, "cell 6: unknown VTK cell type 99"});
}

TEST_F(VtuErrors, OutOfRangePointIndexIsNamed) {
    const std::string text = testing::readFile(variantPath(kAscii));
    const std::size_t tag = text.find("Name=\"connectivity\"");
    const std::size_t first = text.find_first_not_of(" \n", text.find('>', tag) + 1);
    std::string edited = text;
    edited.replace(first, 1, "26");
    const std::string path = write("index.vtu", edited);
    testing::expectError([&] { readVtu(path); }, ErrorKind::Validation,
                         {path, "cell 0 (tetra): point index 26 out of range [0, 26)"});
}

TEST_F(VtuErrors, DecreasingOffsetsAreRefused) {
    const std::string path =
        write("offsets.vtu", withAsciiArray(testing::readFile(variantPath(kAscii)), "offsets",
                                            "4 12 18 23 33 30 44 48"));
    testing::expectError([&] { readVtu(path); }, ErrorKind::Parse,
                         {path + ": line ", "Piece 0: DataArray 'offsets'",
                          "end offset 30 of cell 5 is below the previous offset 33"});
}

TEST_F(VtuErrors, UnsupportedCompressorAndDatasetTypeAreNamed) {
    const std::string text = testing::readFile(variantPath(kRawZlib));
    const std::string other =
        write("other.vtu", replaceOnce(text, "vtkZLibDataCompressor", "vtkBZip2DataCompressor"));
    testing::expectError(
        [&] { readVtu(other); }, ErrorKind::Unsupported,
        {other + ": line " + std::to_string(lineOf(text, text.find("<VTKFile"))),
         "compressor 'vtkBZip2DataCompressor' is not supported: expected "
         "vtkZLibDataCompressor, vtkLZ4DataCompressor, vtkLZMADataCompressor or none"});
    const std::string poly =
        write("poly.vtu", replaceOnce(testing::readFile(variantPath(kAscii)),
                                      "type=\"UnstructuredGrid\"", "type=\"PolyData\""));
    testing::expectError([&] { readVtu(poly); }, ErrorKind::Unsupported, {poly, "'PolyData'"});
}

// ---- .pvtu errors ----

TEST_F(VtuErrors, PvtuPieceMissingAFieldIsNamed) {
    std::filesystem::copy_file(variantPath("three_0.vtu"), dir_ + "/three_0.vtu");
    std::filesystem::copy_file(variantPath("three_2.vtu"), dir_ + "/three_2.vtu");
    write("three_1.vtu",
          std::regex_replace(testing::readFile(variantPath("three_1.vtu")),
                             std::regex("<DataArray type=\"Int16\" Name=\"i16\"[^>]*/>"), ""));
    const std::string text = testing::readFile(variantPath("three.pvtu"));
    const std::string path = write("three.pvtu", text);
    testing::expectError(
        [&] { readPvtu(path); }, ErrorKind::Parse,
        {path + ": line " + std::to_string(lineOf(text, text.find("three_1.vtu"))),
         "Piece 1 ('three_1.vtu') has no point field 'i16', which the first piece has"});
}

TEST_F(VtuErrors, PvtuNamingItselfOrAMissingPieceIsRefused) {
    const std::string text = testing::readFile(variantPath("three.pvtu"));
    const std::string self = write("self.pvtu", replaceOnce(text, "three_0.vtu", "self.pvtu"));
    testing::expectError([&] { readPvtu(self); }, ErrorKind::Parse,
                         {self + ": line ", "Piece 0 ('self.pvtu') names the .pvtu file itself"});
    const std::string missing = write("missing.pvtu", text);  // pieces not copied here
    testing::expectError([&] { readPvtu(missing); }, ErrorKind::Io, {dir_ + "/three_0.vtu"});
    // A piece that is itself a .pvtu (which could recurse) is refused.
    write("other.pvtu", text);
    const std::string nested = write("nested.pvtu", replaceOnce(text, "three_0.vtu", "other.pvtu"));
    testing::expectError([&] { readPvtu(nested); }, ErrorKind::Unsupported,
                         {dir_ + "/other.pvtu", "a .pvtu piece must be an UnstructuredGrid .vtu"});
}

// ---- amplification: sizes a small file declares or reuses ----

/// Little-endian UInt32, as in a header_type="UInt32" payload header.
std::string le32(std::uint32_t v) {
    std::string s(4, '\0');
    for (int i = 0; i < 4; ++i) s[i] = static_cast<char>((v >> (8 * i)) & 0xff);
    return s;
}

/// A zlib-compressed UInt32 payload (one block) of n zero bytes: header + table + stream.
std::string zlibZerosPayload(std::uint32_t n) {
    const std::vector<unsigned char> zeros(n, 0);
    uLongf size = compressBound(n);
    std::string stream(size, '\0');
    EXPECT_EQ(compress2(reinterpret_cast<Bytef*>(stream.data()), &size, zeros.data(), n, 9), Z_OK);
    stream.resize(size);
    return le32(1) + le32(n) + le32(n) + le32(static_cast<std::uint32_t>(size)) + stream;
}

/// A Piece of `points` points and no cells whose Points lie at appended offset 0.
std::string pointsPiece(std::uint64_t points) {
    return "<Piece NumberOfPoints=\"" + std::to_string(points) +
           "\" NumberOfCells=\"0\"><Points><DataArray type=\"Float32\" "
           "NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/></Points></Piece>\n";
}

/// A zlib-compressed .vtu with raw appended data.
std::string appendedZlibVtu(const std::string& pieces, const std::string& data) {
    return "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
           "byte_order=\"LittleEndian\" header_type=\"UInt32\" "
           "compressor=\"vtkZLibDataCompressor\">\n<UnstructuredGrid>\n" +
           pieces + "</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_" + data +
           "\n</AppendedData>\n</VTKFile>\n";
}

TEST(VtuAmplification, BlockHeadersDeclaringGigabytesAreRefusedBeforeAllocating) {
    // 65536 blocks of 65532 bytes (4 GiB of points) whose compressed sizes are 1 byte each: a
    // 330 KB file. Deflate expands at most 1032:1, so block 0 is refused before any allocation.
    constexpr std::uint32_t kBlocks = 65536, kBlock = 65532;
    std::string data = le32(kBlocks) + le32(kBlock) + le32(0);
    for (std::uint32_t b = 0; b < kBlocks; ++b) data += le32(1);
    data += std::string(kBlocks, 'x');
    const std::uint64_t points = std::uint64_t(kBlocks) * kBlock / 12;
    const std::string text = appendedZlibVtu(pointsPiece(points), data);
    const std::string path = testing::writeFile(testing::scratchDir() + "/bomb.vtu", text);
    const std::uint64_t blocksAt = text.find("\n_") + 2 + 12 + 4 * std::uint64_t(kBlocks);
    testing::expectError(
        [&] { readVtu(path); }, ErrorKind::Parse,
        {path + ": byte " + std::to_string(blocksAt) + ": Piece 0: DataArray 'Points': ",
         "zlib block 0 of 65536: 1 compressed bytes cannot inflate to the 65532 bytes the "
         "header declares (at most 1032 at deflate's maximum ratio of 1032:1)"});
}

TEST(VtuAmplification, OneBlockReusedByManyPiecesIsRefusedBeforeDecodingItAgain) {
    // 40 Pieces of 100000 points each, all reading the same 1.2 MB block of zeros (about 1.2 KB
    // compressed): 48 MB of points from a 9 KB file.
    std::string pieces;
    for (int k = 0; k < 40; ++k) pieces += pointsPiece(100000);
    const std::string text = appendedZlibVtu(pieces, zlibZerosPayload(1200000));
    ASSERT_LT(text.size(), 12000u);
    const std::string dir = testing::scratchDir();
    const std::string path = testing::writeFile(dir + "/reuse.vtu", text);
    // Without a limit: the second Piece reading the block is refused before decoding it.
    const std::uint64_t data = text.find("\n_") + 2;
    testing::expectError(
        [&] { readVtu(path); }, ErrorKind::Parse,
        {path + ": byte " + std::to_string(data) +
             ": Piece 1: DataArray 'Points' (appended offset 0): its data (file bytes " +
             std::to_string(data) + " to ",
         ") overlap the data of Piece 0: DataArray 'Points' (bytes " + std::to_string(data) +
             " to ",
         "each DataArray must have data of its own"});
    // With a limit: the mesh the file declares is refused before any array is decoded.
    ReadOptions options;
    options.maxMemoryBytes = 4 << 20;
    testing::expectError(
        [&] { readVtu(path, options); }, ErrorKind::Resource,
        {path +
         ": the mesh it declares (4000000 points, 0 cells and 0 field values in 40 "
         "Pieces) needs 48000000 bytes, which with the " +
         std::to_string(text.size()) +
         " bytes this load holds so far exceed the "
         "memory limit of 4194304 bytes (`max_memory`)"});
    // One piece is a legitimate file (its 1.2 MB of zeros compress 1000:1).
    const std::string one = testing::writeFile(
        dir + "/one.vtu", appendedZlibVtu(pointsPiece(100000), zlibZerosPayload(1200000)));
    EXPECT_EQ(readVtu(one).pointCount(), 100000u);
}

/// What reading a file gave in a child process: the error ("" when it read) and how far the
/// child's peak resident memory grew meanwhile (getrusage's maxrss, KiB; -1 when it died).
struct ChildRead {
    std::string error;
    long growthKiB = -1;
};

ChildRead readVtuInChild(const std::string& path) {
    int fds[2];
    if (::pipe(fds) != 0) return {};
    const pid_t pid = ::fork();
    if (pid == 0) {
        ::close(fds[0]);
        rusage before{}, after{};
        ::getrusage(RUSAGE_SELF, &before);
        std::string error;
        try {
            (void)readVtu(path);
        } catch (const std::exception& e) {
            error = e.what();
        }
        ::getrusage(RUSAGE_SELF, &after);
        const std::string out = std::to_string(after.ru_maxrss - before.ru_maxrss) + "\n" + error;
        (void)!::write(fds[1], out.data(), out.size());
        ::_exit(0);
    }
    ::close(fds[1]);
    std::string text;
    char buf[4096];
    for (ssize_t n; (n = ::read(fds[0], buf, sizeof(buf))) > 0;) text.append(buf, std::size_t(n));
    ::close(fds[0]);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ChildRead r;
    const std::size_t nl = text.find('\n');
    if (nl == std::string::npos) return r;
    r.growthKiB = std::stol(text.substr(0, nl));
    r.error = text.substr(nl + 1);
    return r;
}

/// An xz stream of n zero bytes, as vtkLZMADataCompressor writes a block.
std::string xzZeros(std::size_t n) {
    const std::vector<unsigned char> zeros(n, 0);
    std::vector<unsigned char> out;
    compressBlock(VtuCompressor::Lzma, 6, zeros.data(), zeros.size(), out, "test");
    return std::string(out.begin(), out.end());
}

std::string asLzma(const std::string& zlibVtu) {
    return replaceOnce(zlibVtu, "vtkZLibDataCompressor", "vtkLZMADataCompressor");
}

TEST(VtuAmplification, LzmaBlockTableDeclaringGigabytesTouchesOnlyWhatItDecodes) {
    // 64 LZMA blocks of 32 MiB, each 1024 compressed bytes of garbage (within LZMA's 32768:1):
    // a 66 KB file declaring 2 GiB of points. The buffer sized from the header was zero-filled
    // before block 0 was found corrupt (6.3 GB for the 200 KB file).
    if (!vtuCompressorAvailable(VtuCompressor::Lzma)) GTEST_SKIP() << "built without LZMA";
    constexpr std::uint32_t kBlocks = 64, kBlock = 33554424, kCompressed = 1024;
    std::string data = le32(kBlocks) + le32(kBlock) + le32(0);
    for (std::uint32_t b = 0; b < kBlocks; ++b) data += le32(kCompressed);
    data += std::string(kBlocks * kCompressed, 'x');
    const std::uint64_t points = std::uint64_t(kBlocks) * kBlock / 12;
    const std::string path = testing::writeFile(testing::scratchDir() + "/lying.vtu",
                                                asLzma(appendedZlibVtu(pointsPiece(points), data)));
    const ChildRead read = readVtuInChild(path);
    EXPECT_THAT(read.error, HasSubstr(path + ": byte "));
    EXPECT_THAT(read.error,
                HasSubstr("LZMA block 0 of DataArray 'Points' is corrupt (not an xz stream)"));
    ASSERT_GE(read.growthKiB, 0) << "the reading process died";
    // AddressSanitizer keeps up to 256 MiB of freed memory in quarantine; the old reader grew
    // by 2.1 GB either way.
    const long limitKiB = testing::underAddressSanitizer() ? 768 * 1024 : 256 * 1024;
    EXPECT_LT(read.growthKiB, limitKiB) << "KiB of resident memory for a 66 KB file";
}

TEST(VtuAmplification, LzmaBlockReusedByThreeThousandPiecesIsRefused) {
    // 3,000 Pieces reading one LZMA block of 12 KB of zeros (about 100 bytes of xz): each Piece
    // decoded it again, bounded only by the file's size times LZMA's 32768:1.
    if (!vtuCompressorAvailable(VtuCompressor::Lzma)) GTEST_SKIP() << "built without LZMA";
    const std::string xz = xzZeros(12000);
    const std::string payload =
        le32(1) + le32(12000) + le32(12000) + le32(static_cast<std::uint32_t>(xz.size())) + xz;
    std::string pieces;
    for (int k = 0; k < 3000; ++k) pieces += pointsPiece(1000);
    const std::string path = testing::writeFile(testing::scratchDir() + "/lzma_reuse.vtu",
                                                asLzma(appendedZlibVtu(pieces, payload)));
    LoadBudget budget;
    ReadOptions options;
    options.budget = &budget;
    testing::expectError(
        [&] { readVtu(path, options); }, ErrorKind::Parse,
        {path + ": byte ", "Piece 1: DataArray 'Points' (appended offset 0): its data",
         "overlap the data of Piece 0: DataArray 'Points'"});
    EXPECT_LT(budget.peak(), std::filesystem::file_size(path) + (1u << 20));
}

TEST(VtuAmplification, ZlibPiecesReusingBlocksInALargeFileAreRefusedAtTheFirstReuse) {
    // 40,000 Pieces in a 17 MB file, reading 40 zlib blocks in turn: 1032 times the file's size
    // (17.5 GB) allowed 19.3 GB of decoding over 240 s before the file was refused.
    constexpr int kPieces = 40000, kBlocks = 40;
    std::string data;
    std::vector<std::size_t> offsets;
    for (int b = 0; b < kBlocks; ++b) {
        offsets.push_back(data.size());
        data += zlibZerosPayload(1200);
    }
    std::string pieces;
    const std::string padding = "<!--" + std::string(260, 'x') + "-->";
    for (int k = 0; k < kPieces; ++k)
        pieces += replaceOnce(pointsPiece(100), "offset=\"0\"",
                              "offset=\"" + std::to_string(offsets[k % kBlocks]) + "\"") +
                  padding;
    const std::string text = appendedZlibVtu(pieces, data);
    ASSERT_GT(text.size(), 16u << 20);
    const std::string path = testing::writeFile(testing::scratchDir() + "/zlib_reuse.vtu", text);
    LoadBudget budget;
    ReadOptions options;
    options.budget = &budget;
    testing::expectError(
        [&] { readVtu(path, options); }, ErrorKind::Parse,
        {path + ": byte ", "Piece 40: DataArray 'Points' (appended offset 0): its data",
         "overlap the data of Piece 0: DataArray 'Points'"});
    EXPECT_LT(budget.peak(), text.size() + (1u << 20));
    // Under a limit, the 4M points the Pieces declare are refused before any block is decoded.
    LoadBudget limited(text.size() + (16u << 20));
    options.budget = &limited;
    testing::expectError(
        [&] { readVtu(path, options); }, ErrorKind::Resource,
        {path + ": the mesh it declares (4000000 points, 0 cells and 0 field values in "
                "40000 Pieces) needs 48000000 bytes"});
    EXPECT_EQ(limited.peak(), text.size());
}

TEST(VtuAmplification, ConnectivityBeyondWhatTheCellsCanListIsRefusedBeforeReadingIt) {
    // One hexahedron among 8 points whose end offset declares a billion nodes.
    const std::string text =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\">\n"
        "<UnstructuredGrid><Piece NumberOfPoints=\"8\" NumberOfCells=\"1\">\n<Points><DataArray "
        "type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 1 1 0 0 1 0 0 0 "
        "1 1 0 1 1 1 1 0 1 1</DataArray></Points>\n<Cells>\n<DataArray type=\"Int64\" "
        "Name=\"connectivity\" format=\"ascii\">0 1 2 3 4 5 6 7</DataArray>\n<DataArray "
        "type=\"Int64\" Name=\"offsets\" format=\"ascii\">1000000000</DataArray>\n<DataArray "
        "type=\"UInt8\" Name=\"types\" format=\"ascii\">12</DataArray>\n</Cells></Piece>"
        "</UnstructuredGrid>\n</VTKFile>\n";
    const std::string path = testing::writeFile(testing::scratchDir() + "/conn.vtu", text);
    testing::expectError(
        [&] { readVtu(path); }, ErrorKind::Parse,
        {path + ": line 7: Piece 0: DataArray 'offsets': cell 0 (hexahedron) lists "
                "1000000000 nodes, more than the 8 points of its Piece"});
}

TEST(VtuAmplification, PvtuListingAPieceTwiceIsRefusedBeforeReadingIt) {
    const std::string dir = testing::scratchDir();
    const std::string piece = appendedZlibVtu(pointsPiece(10), zlibZerosPayload(120));
    testing::writeFile(dir + "/p.vtu", piece);
    std::filesystem::create_symlink("p.vtu", dir + "/link.vtu");
    auto pvtu = [&](const std::string& name, const std::vector<std::string>& sources) {
        std::string text =
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"0.1\">\n"
            "<PUnstructuredGrid GhostLevel=\"0\">\n<PPoints><PDataArray type=\"Float32\" "
            "NumberOfComponents=\"3\"/></PPoints>\n";
        for (const std::string& s : sources) text += "<Piece Source=\"" + s + "\"/>\n";
        return testing::writeFile(dir + "/" + name, text + "</PUnstructuredGrid>\n</VTKFile>\n");
    };
    const std::string twice = pvtu("twice.pvtu", {"p.vtu", "./sub/../p.vtu"});
    std::filesystem::create_directory(dir + "/sub");
    testing::expectError(
        [&] { readPvtu(twice); }, ErrorKind::Parse,
        {twice + ": line 6: Piece 1 ('./sub/../p.vtu') is listed twice: Piece 0 (line 5) "
                 "names the same file"});
    const std::string linked = pvtu("linked.pvtu", {"link.vtu", "p.vtu"});
    testing::expectError([&] { readPvtu(linked); }, ErrorKind::Parse,
                         {linked + ": line 6: Piece 1 ('p.vtu') is listed twice"});
    std::filesystem::create_hard_link(dir + "/p.vtu", dir + "/hard.vtu");
    const std::string hard = pvtu("hard.pvtu", {"p.vtu", "hard.vtu"});
    testing::expectError([&] { readPvtu(hard); }, ErrorKind::Parse,
                         {hard + ": line 6: Piece 1 ('hard.vtu') is listed twice"});
    // A piece naming the .pvtu through './', or a collection (which could recurse).
    const std::string self = pvtu("self.pvtu", {"./self.pvtu"});
    testing::expectError([&] { readPvtu(self); }, ErrorKind::Parse,
                         {self + ": line 5: Piece 0 ('./self.pvtu') names the .pvtu file itself"});
    testing::writeFile(dir + "/c.pvd",
                       "<VTKFile type=\"Collection\"><Collection><DataSet file=\"loop.pvtu\"/>"
                       "</Collection></VTKFile>\n");
    const std::string loop = pvtu("loop.pvtu", {"c.pvd"});
    testing::expectError([&] { readPvtu(loop); }, ErrorKind::Unsupported,
                         {loop + ": line 5: Piece 0 ('c.pvd'): " + dir +
                          "/c.pvd is a ParaView collection (.pvd); a .pvtu piece must be an "
                          "UnstructuredGrid .vtu file"});
    const std::vector<std::string> sixty(60, "p.vtu");
    const std::string many = pvtu("many.pvtu", sixty);
    testing::expectError([&] { readPvtu(many); }, ErrorKind::Parse, {many + ": line 6: Piece 1 "});
    EXPECT_EQ(readPvtu(pvtu("once.pvtu", {"p.vtu"})).pointCount(), 10u);
}

TEST(VtuAmplification, ManyFieldsInTwoPiecesMergeInLinearTime) {
    // 2 x 30000 point fields: merging Pieces by a linear search per field took ~10^9 string
    // comparisons (minutes under the sanitizers); a hash lookup takes ~10^5.
    constexpr int kFields = 30000;
    std::string piece =
        "<Piece NumberOfPoints=\"1\" NumberOfCells=\"0\"><Points><DataArray type=\"Float32\" "
        "NumberOfComponents=\"3\" format=\"ascii\">0 0 0</DataArray></Points><PointData>";
    for (int f = 0; f < kFields; ++f)
        piece += "<DataArray type=\"Float32\" Name=\"f" + std::to_string(f) +
                 "\" format=\"ascii\">" + std::to_string(f) + "</DataArray>";
    piece += "</PointData></Piece>\n";
    const std::string text =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\">\n"
        "<UnstructuredGrid>\n" +
        piece + piece + "</UnstructuredGrid>\n</VTKFile>\n";
    const std::string path = testing::writeFile(testing::scratchDir() + "/fields.vtu", text);
    const Mesh mesh = readVtu(path);
    ASSERT_EQ(mesh.fields.size(), std::size_t(kFields));
    EXPECT_EQ(mesh.fields.back().name, "f" + std::to_string(kFields - 1));
    EXPECT_EQ(mesh.fields.back().values, (std::vector<float>{kFields - 1, kFields - 1}));
}

}  // namespace
}  // namespace uvr

namespace uvr {
namespace {

// ---- numbers and compressors as VTK writes them ----

TEST(VtuNumbers, SignedCountsExponentsAndNanReadAsVtkReadsThem) {
    // The same values VTK 9.1's vtkXMLUnstructuredGridReader gets from the file.
    const Mesh m = readVtu(testing::testData("vtk/plus_counts.vtu"));
    ASSERT_EQ(m.pointCount(), 5u);
    ASSERT_EQ(m.cellCount(), 2u);
    EXPECT_EQ(m.points[1], Vec3f(1, 0, 0));
    EXPECT_EQ(m.points[2], Vec3f(0, 1, 0));
    EXPECT_EQ(m.points[4], Vec3f(1, 1, 1));
    EXPECT_EQ(m.cellIndices, (std::vector<std::uint32_t>{0, 1, 2, 3, 1, 2, 3, 4}));
    ASSERT_EQ(m.fields.size(), 3u);
    EXPECT_EQ(m.fields[0].name, "rho");
    EXPECT_EQ(m.fields[0].values[0], 1.0f);
    EXPECT_EQ(m.fields[0].values[1], 1.0f);
    EXPECT_EQ(m.fields[0].values[2], 1.5f);
    EXPECT_EQ(m.fields[0].values[3], 0.25f);
    EXPECT_TRUE(std::isnan(m.fields[0].values[4]));
    EXPECT_EQ(m.fields[1].values, (std::vector<float>{0, 1, -2, 3, 4}));
    EXPECT_EQ(m.fields[2].values, (std::vector<float>{1e-3f, -20.f, 0.5f, 5.f, 0.f, -0.f}));
}

TEST(VtuNumbers, GarbageCountsAndValuesKeepTheirMessages) {
    const std::string text = testing::readFile(testing::testData("vtk/plus_counts.vtu"));
    const std::string dir = testing::scratchDir();
    struct Case {
        std::string from, to, message;
    };
    for (const Case& c : std::vector<Case>{
             {"NumberOfPoints=\"+5\"", "NumberOfPoints=\"0x5\"",
              "Piece 0: expected NumberOfPoints to be a non-negative integer, got '0x5'"},
             {"NumberOfCells=\" +2 \"", "NumberOfCells=\"-2\"",
              "Piece 0: expected NumberOfCells to be a non-negative integer, got '-2'"},
             {"NumberOfComponents=\"+1\"", "NumberOfComponents=\"1abc\"",
              "expected NumberOfComponents to be a non-negative integer, got '1abc'"},
             {"+1.5E+00", "1.5d0", "DataArray 'rho': expected a number (Float64), got '1.5d0'"},
             {"+0 +1 -2", "+0 +1 0x2", "DataArray 'flag': expected an integer (Int32), got '0x2'"},
             {"+4 +8", "+4 +8.5", "DataArray 'offsets': expected an integer (Int64), got '+8.5'"},
         }) {
        SCOPED_TRACE(c.to);
        const std::string path =
            testing::writeFile(dir + "/bad.vtu", replaceOnce(text, c.from, c.to));
        testing::expectError([&] { readVtu(path); }, ErrorKind::Parse,
                             {path + ": line ", c.message});
    }
}

/// Overwrites the third block of the Points payload of a compressed .vtu written by writeVtu
/// (UInt64 header) with 0xff bytes: an LZ4 token whose literal run passes the block's end, not
/// an xz stream header.
std::string corruptThirdPointsBlock(std::string text) {
    const std::size_t start = appendedArrayStart(text, "Points");
    auto u64 = [&](std::size_t pos) {
        std::uint64_t v;
        std::memcpy(&v, text.data() + pos, 8);
        return v;
    };
    const std::uint64_t blocks = u64(start);
    const std::size_t block2 = start + 8 * (3 + blocks) + u64(start + 24) + u64(start + 32);
    for (std::size_t k = 0; k < u64(start + 40); ++k) text[block2 + k] = '\xff';
    return text;
}

TEST(VtuCompressors, CorruptLz4AndLzmaBlocksAreNamed) {
    Mesh m;
    for (int i = 0; i < 40; ++i) m.points.push_back({0.25f * i, std::sin(float(i)), 1.f / (i + 1)});
    const std::string dir = testing::scratchDir();
    for (const auto& [compressor, name] :
         {std::pair{VtuCompressor::Lz4, "LZ4"}, std::pair{VtuCompressor::Lzma, "LZMA"}}) {
        if (!vtuCompressorAvailable(compressor)) continue;
        SCOPED_TRACE(name);
        VtuWriteOptions options;
        options.compressor = compressor;
        options.blockSize = 64;
        const std::string good = dir + "/good.vtu";
        writeVtu(m, good, {}, options);
        EXPECT_EQ(readVtu(good).points, m.points);
        const std::string bad =
            testing::writeFile(dir + "/bad.vtu", corruptThirdPointsBlock(testing::readFile(good)));
        testing::expectError([&] { readVtu(bad); }, ErrorKind::Parse,
                             {bad + ": byte ", "Piece 0: DataArray 'Points': ",
                              std::string(name) + " block 2 of DataArray 'Points' is corrupt ("});
    }
}

TEST(VtuCompressors, BlocksDeclaringMoreThanTheRatioAreRefused) {
    // One LZ4 block of 1 compressed byte cannot stand for 4092 bytes (LZ4 expands at most 255:1).
    const std::string data = le32(1) + le32(4092) + le32(4092) + le32(1) + "x";
    const std::string text = replaceOnce(appendedZlibVtu(pointsPiece(341), data),
                                         "vtkZLibDataCompressor", "vtkLZ4DataCompressor");
    if (!vtuCompressorAvailable(VtuCompressor::Lz4)) GTEST_SKIP() << "built without LZ4";
    const std::string path = testing::writeFile(testing::scratchDir() + "/lz4.vtu", text);
    testing::expectError(
        [&] { readVtu(path); }, ErrorKind::Parse,
        {"LZ4 block 0 of 1: 1 compressed bytes cannot inflate to the 4092 bytes the header "
         "declares (at most 255 at LZ4's maximum ratio of 255:1)"});
}

}  // namespace
}  // namespace uvr

#undef REQUIRE_VARIANTS  // file-local: the unity build joins test files
