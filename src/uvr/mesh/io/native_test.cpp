// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/native.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <span>
#include <type_traits>

#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/mesh/procedural.h"

namespace uvr {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

/// One tetra, hexahedron, wedge and pyramid sharing points, with point and cell fields.
Mesh mixedMesh() {
    Mesh m;
    for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i)
                m.points.push_back({0.5f * i - 0.1f * k, 1.f * j + 0.25f, 1.f * k});
    const std::uint32_t hex[8] = {0, 1, 3, 2, 4, 5, 7, 6};
    const std::uint32_t tet[4] = {4, 5, 6, 8};
    const std::uint32_t wedge[6] = {4, 5, 6, 8, 9, 10};
    const std::uint32_t pyramid[5] = {8, 9, 11, 10, 3};
    m.addCell(CellType::Hexahedron, hex);
    m.addCell(CellType::Tetra, tet);
    m.addCell(CellType::Wedge, wedge);
    m.addCell(CellType::Pyramid, pyramid);
    Field scalar{"temperature", Association::Point, 1, {}};
    for (size_t i = 0; i < m.points.size(); ++i) scalar.values.push_back(0.1f * i - 0.3f);
    scalar.values[3] = std::numeric_limits<float>::quiet_NaN();
    scalar.values[4] = -0.f;
    Field vector{"velocity vector", Association::Point, 3, {}};
    for (size_t i = 0; i < 3 * m.points.size(); ++i) vector.values.push_back(1e-30f * i);
    Field cellField{"pressure\xc2\xb0", Association::Cell, 2, {1, 2, 3, 4, 5, 6, 7, 8}};
    Field empty{"", Association::Cell, 1, {9, 8, 7, 6}};
    m.fields = {scalar, vector, cellField, empty};
    return m;
}

/// Bitwise equality of everything the native format stores.
void expectBitwiseSame(const Mesh& a, const Mesh& b) {
    ASSERT_EQ(a.points.size(), b.points.size());
    if (!a.points.empty()) {  // memcmp of empty vectors' null data is undefined
        EXPECT_EQ(0,
                  std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(Vec3f)));
    }
    EXPECT_EQ(a.cellTypes, b.cellTypes);
    EXPECT_EQ(a.cellOffsets, b.cellOffsets);
    EXPECT_EQ(a.cellIndices, b.cellIndices);
    ASSERT_EQ(a.fields.size(), b.fields.size());
    for (size_t f = 0; f < a.fields.size(); ++f) {
        EXPECT_EQ(a.fields[f].name, b.fields[f].name);
        EXPECT_EQ(a.fields[f].association, b.fields[f].association);
        EXPECT_EQ(a.fields[f].components, b.fields[f].components);
        ASSERT_EQ(a.fields[f].values.size(), b.fields[f].values.size());
        if (!a.fields[f].values.empty()) {
            EXPECT_EQ(0, std::memcmp(a.fields[f].values.data(), b.fields[f].values.data(),
                                     a.fields[f].values.size() * sizeof(float)))
                << a.fields[f].name;
        }
    }
}

/// Byte offsets of a native file's arrays, computed independently from docs/NATIVE_FORMAT.md.
struct FileLayout {
    std::uint64_t descriptors = 48, points = 0, types = 0, offsets = 0, indices = 0, end = 0;
    std::vector<std::uint64_t> fields;
};

FileLayout layoutOf(const Mesh& m) {
    auto align = [](std::uint64_t x) { return (x + 7) / 8 * 8; };
    FileLayout l;
    std::uint64_t at = 48;
    for (const Field& f : m.fields) at += 4 + f.name.size() + 1 + 4 + 8;
    l.points = align(at);
    l.types = align(l.points + 12 * m.pointCount());
    l.offsets = align(l.types + m.cellCount());
    l.indices = align(l.offsets + 8 * (m.cellCount() + 1));
    at = l.indices + 4 * m.cellIndices.size();
    for (const Field& f : m.fields) {
        l.fields.push_back(align(at));
        at = l.fields.back() + 4 * f.values.size();
    }
    l.end = at;
    return l;
}

std::string readBytes(const std::string& path) {
    std::vector<char> bytes = readFileBytes(path);
    return std::string(bytes.begin(), bytes.end());
}

template <typename T>
void patch(std::string& bytes, std::uint64_t offset, T value) {
    std::memcpy(bytes.data() + offset, &value, sizeof(T));  // the test hosts are little-endian
}

TEST(Native, MixedMeshRoundTripsExactly) {
    const std::string path = testing::scratchDir() + "/mixed.uvrm";
    const Mesh m = mixedMesh();
    writeNative(m, path);
    const Mesh back = readNative(path);
    expectBitwiseSame(m, back);
    EXPECT_TRUE(std::isnan(back.fields[0].values[3]));
    EXPECT_TRUE(std::signbit(back.fields[0].values[4]));
}

TEST(Native, APartIsTheWholeMeshsCellsWithTheirPointsAndFields) {
    const std::string path = testing::scratchDir() + "/part.uvrm";
    ProceduralSpec spec;
    spec.targetCells = 3000;
    Mesh m = generateMesh(spec);
    Field cellField{"c", Association::Cell, 2, {}};
    for (std::uint64_t c = 0; c < m.cellCount(); ++c)
        cellField.values.insert(cellField.values.end(), {float(c), -float(c)});
    m.fields.push_back(cellField);
    writeNative(m, path);
    const std::uint64_t n = m.cellCount();
    // Parts of many cells number their points over the band of ids they use; one cell's
    // corners lie farther apart than its corner count, and are sorted instead.
    for (auto [a, b] : {std::pair<std::uint64_t, std::uint64_t>{0, n / 3},
                        {n / 3, n},
                        {n, n},
                        {n / 2, n / 2 + 1}}) {
        if (b == a + 1) {
            const auto corners = m.cell(a);
            const auto [lo, hi] = std::minmax_element(corners.begin(), corners.end());
            ASSERT_GE(*hi - *lo, corners.size()) << "the one-cell part's band";
        }
        const MeshPart part = readNativePart(path, a, b);
        const MeshPart expected = meshPart(m, a, b);
        EXPECT_EQ(part.pointIds, expected.pointIds);
        EXPECT_EQ(part.cellIds, expected.cellIds);
        expectBitwiseSame(expected.mesh, part.mesh);
        ASSERT_EQ(part.mesh.cellCount(), b - a);
        // Each corner is the whole mesh's point.
        for (std::uint64_t c = 0; c < part.mesh.cellCount(); ++c)
            for (std::size_t k = 0; k < part.mesh.cell(c).size(); ++k)
                EXPECT_EQ(part.mesh.points[part.mesh.cell(c)[k]], m.points[m.cell(a + c)[k]]);
    }
    // A part reads its cells' offsets and indices itself: a corrupt one is refused there,
    // naming the byte.
    const FileLayout layout = layoutOf(m);
    std::string bytes = readBytes(path);
    patch(bytes, layout.indices + 4 * 5, std::uint32_t(m.pointCount()));
    const std::string badIndex = testing::writeFile(path + ".index.uvrm", bytes);
    testing::expectError([&] { readNativePart(badIndex, 0, 10); }, ErrorKind::Parse,
                         {"cell indices: index " + std::to_string(m.pointCount()),
                          "byte " + std::to_string(layout.indices + 20)});
    bytes = readBytes(path);
    patch(bytes, layout.offsets + 8 * 3, std::uint64_t(0));
    const std::string badOffset = testing::writeFile(path + ".offset.uvrm", bytes);
    testing::expectError([&] { readNativePart(badOffset, 0, 10); }, ErrorKind::Parse,
                         {"cell offsets: offset 0 of cell 3"});
    testing::expectError([&] { readNativePart(path, 10, n + 1); }, ErrorKind::Argument,
                         {"part.uvrm", "cells [10, " + std::to_string(n + 1) + ")"});
    testing::expectError([&] { readNativePart(path, 10, 5); }, ErrorKind::Argument,
                         {"cells [10, 5)"});
}

TEST(Native, HeaderAndArraysFollowTheDocumentedLayout) {
    const std::string dir = testing::scratchDir();
    const std::string path = dir + "/mixed.uvrm";
    const Mesh m = mixedMesh();
    writeNative(m, path);
    const std::string bytes = readBytes(path);
    const FileLayout l = layoutOf(m);
    ASSERT_EQ(bytes.size(), l.end);
    EXPECT_EQ(0, std::memcmp(bytes.data(), "UVRMESH\0", 8));
    auto u32 = [&](std::uint64_t at) {
        std::uint32_t v;
        std::memcpy(&v, bytes.data() + at, 4);
        return v;
    };
    auto u64 = [&](std::uint64_t at) {
        std::uint64_t v;
        std::memcpy(&v, bytes.data() + at, 8);
        return v;
    };
    EXPECT_EQ(u32(8), 1u);   // version
    EXPECT_EQ(u32(12), 0u);  // flags
    EXPECT_EQ(u64(16), m.pointCount());
    EXPECT_EQ(u64(24), m.cellCount());
    EXPECT_EQ(u64(32), m.cellIndices.size());
    EXPECT_EQ(u32(40), m.fields.size());
    EXPECT_EQ(u32(44), 0u);
    // First descriptor: name length, name, association, components, valueCount.
    EXPECT_EQ(u32(48), 11u);
    EXPECT_EQ(bytes.substr(52, 11), "temperature");
    EXPECT_EQ(bytes[63], 0);
    EXPECT_EQ(u32(64), 1u);
    EXPECT_EQ(u64(68), m.pointCount());
    float x;
    std::memcpy(&x, bytes.data() + l.points + 12 * 5, 4);
    EXPECT_EQ(x, m.points[5].x);
    EXPECT_EQ(static_cast<std::uint8_t>(bytes[l.types + 3]), 14);
    EXPECT_EQ(u64(l.offsets + 8 * 4), m.cellIndices.size());
    EXPECT_EQ(u32(l.indices + 4 * 8), m.cellIndices[8]);
    float v;
    std::memcpy(&v, bytes.data() + l.fields[2] + 4 * 5, 4);
    EXPECT_EQ(v, 6.f);
    for (std::uint64_t a : {l.points, l.types, l.offsets, l.indices, l.fields[0], l.fields[3]})
        EXPECT_EQ(a % 8, 0u);
    // The worked example of docs/NATIVE_FORMAT.md: only the "temperature" field, 416 bytes.
    Mesh example = m;
    example.fields.resize(1);
    const std::string examplePath = dir + "/example.uvrm";
    writeNative(example, examplePath);
    const std::string e = readBytes(examplePath);
    ASSERT_EQ(e.size(), 416u);
    EXPECT_EQ(e.substr(224, 4), "\x0c\x0a\x0d\x0e");
    std::uint64_t lastOffset;
    std::memcpy(&lastOffset, e.data() + 232 + 32, 8);
    EXPECT_EQ(lastOffset, 23u);
    float firstValue;
    std::memcpy(&firstValue, e.data() + 368, 4);
    EXPECT_EQ(firstValue, m.fields[0].values[0]);
}

TEST(Native, MillionTetrahedraRoundTrip) {
    ProceduralSpec spec;
    spec.targetCells = 1000000;
    const Mesh m = generateMesh(spec);
    ASSERT_GT(m.cellCount(), 900000u);
    const std::string path = testing::scratchDir() + "/big.uvrm";
    writeNative(m, path);
    EXPECT_EQ(fileSize(path), layoutOf(m).end);
    const Mesh back = readNative(path);
    expectBitwiseSame(m, back);
}

TEST(Native, EmptyMeshRoundTrips) {
    const std::string path = testing::scratchDir() + "/empty.uvrm";
    writeNative(Mesh{}, path);
    EXPECT_EQ(fileSize(path), 48u + 8u);  // header, then the single cell offset 0
    const Mesh back = readNative(path);
    EXPECT_EQ(back.pointCount(), 0u);
    EXPECT_EQ(back.cellCount(), 0u);
    EXPECT_EQ(back.cellOffsets.size(), 1u);
}

TEST(Native, TruncatedFilesAreParseErrorsNamingTheByte) {
    const std::string dir = testing::scratchDir();
    const Mesh m = mixedMesh();
    writeNative(m, dir + "/good.uvrm");
    const std::string bytes = readBytes(dir + "/good.uvrm");
    const FileLayout l = layoutOf(m);
    for (std::uint64_t length : std::vector<std::uint64_t>{
             0, 7, 8, 47, 48, 60, l.points, l.points + 5, l.indices + 3, l.end - 1}) {
        SCOPED_TRACE(length);
        const std::string path = testing::writeFile(dir + "/cut.uvrm", bytes.substr(0, length));
        testing::expectError([&] { readNative(path); }, ErrorKind::Parse, {path, "byte "});
    }
    const std::string longer = testing::writeFile(dir + "/long.uvrm", bytes + "x");
    testing::expectError([&] { readNative(longer); }, ErrorKind::Parse,
                         {longer, "byte " + std::to_string(l.end), "expected the file to end"});
}

TEST(Native, WrongMagicFutureVersionAndUnknownFlagsAreRefused) {
    const std::string dir = testing::scratchDir();
    const Mesh m = mixedMesh();
    writeNative(m, dir + "/good.uvrm");
    const std::string good = readBytes(dir + "/good.uvrm");

    std::string bytes = good;
    bytes[3] = 'X';
    std::string path = testing::writeFile(dir + "/magic.uvrm", bytes);
    testing::expectError([&] { readNative(path); }, ErrorKind::Parse,
                         {path, "byte 0", "magic", "got 55 56 52 58 45"});

    bytes = good;
    patch<std::uint32_t>(bytes, 8, 2);
    path = testing::writeFile(dir + "/version.uvrm", bytes);
    testing::expectError([&] { readNative(path); }, ErrorKind::Unsupported,
                         {path, "byte 8", "version 2"});

    bytes = good;
    patch<std::uint32_t>(bytes, 12, 4);
    path = testing::writeFile(dir + "/flags.uvrm", bytes);
    testing::expectError([&] { readNative(path); }, ErrorKind::Unsupported,
                         {path, "byte 12", "flags 4"});
}

TEST(Native, AbsurdCountsAreRefusedBeforeAllocating) {
    // Each would need terabytes or more if anything were allocated from the header's counts.
    const std::string dir = testing::scratchDir();
    const Mesh m = mixedMesh();
    Mesh plain = m;
    plain.fields.clear();
    writeNative(m, dir + "/good.uvrm");
    writeNative(plain, dir + "/plain.uvrm");
    const std::string good = readBytes(dir + "/good.uvrm");
    const std::string goodPlain = readBytes(dir + "/plain.uvrm");
    auto expectRefused = [&](const std::string& original, std::uint64_t offset, auto value,
                             const std::vector<std::string>& fragments) {
        std::string bytes = original;
        patch(bytes, offset, value);
        const std::string path = testing::writeFile(dir + "/bad.uvrm", bytes);
        std::vector<std::string> all = fragments;
        all.push_back(path);
        testing::expectError([&] { readNative(path); }, ErrorKind::Parse, all);
    };
    expectRefused(goodPlain, 16, std::uint64_t{1} << 60,
                  {"points: 1152921504606846976 x 12 bytes", "byte 48", "but it has 332"});
    expectRefused(goodPlain, 16, ~std::uint64_t{0}, {"points", "more than 2^64"});
    expectRefused(goodPlain, 24, std::uint64_t{1} << 62,
                  {"indexCount 23 is impossible", "byte 32"});
    expectRefused(goodPlain, 32, std::uint64_t{1} << 40, {"indexCount 1099511627776", "byte 32"});
    expectRefused(goodPlain, 40, std::uint32_t{0xffffffff}, {"fieldCount 4294967295", "byte 40"});
    // Descriptors of the mixed mesh: 'temperature' at 48 (name 52..62, association 63,
    // components 64, valueCount 68), 'velocity vector' at 76, 'pressure°' at 108 (valueCount at
    // 127), '' at 135 (valueCount at 144).
    expectRefused(good, 16, std::uint64_t{1} << 60, {"field 'temperature': valueCount 12"});
    expectRefused(good, 48, std::uint32_t{0xfffffff0},
                  {"field 0 descriptor: name length", "byte 48"});
    expectRefused(good, 68, std::uint64_t{1} << 61, {"field 'temperature': valueCount", "byte 68"});
    expectRefused(good, 64, std::uint32_t{0}, {"field 'temperature': components 0", "byte 64"});
    expectRefused(good, 63, std::uint8_t{7}, {"field 'temperature': association 7", "byte 63"});
    expectRefused(good, 144, std::uint64_t{5}, {"field '': valueCount 5, expected 4 cells x 1"});

    // Consistent counts that the file cannot hold: the cells and cell fields grow together.
    std::string bytes = good;
    const std::uint64_t cells = 1ull << 36;
    patch(bytes, 24, cells);
    patch(bytes, 32, 4 * cells);
    patch(bytes, 127, 2 * cells);
    patch(bytes, 144, cells);
    const std::string path = testing::writeFile(dir + "/huge.uvrm", bytes);
    testing::expectError([&] { readNative(path); }, ErrorKind::Parse,
                         {path, "cellTypes: 68719476736 x 1 bytes", "byte 296"});
}

TEST(Native, MemoryLimitIsAResourceError) {
    const std::string path = testing::scratchDir() + "/mixed.uvrm";
    writeNative(mixedMesh(), path);
    ReadOptions options;
    options.maxMemoryBytes = 100;  // the points need 12 x 12 = 144 bytes
    testing::expectError([&] { readNative(path, options); }, ErrorKind::Resource,
                         {path, "points", "memory limit"});
    options.maxMemoryBytes = 144;  // the limit bounds all arrays of the load together
    testing::expectError(
        [&] { readNative(path, options); }, ErrorKind::Resource,
        {path, "with the 144 bytes this load holds so far", "memory limit of 144"});
    options.maxMemoryBytes = meshBytes(mixedMesh());
    EXPECT_NO_THROW(readNative(path, options));
}

TEST(Native, BadCellsAreValidationErrorsNamingTheCell) {
    const std::string dir = testing::scratchDir();
    const Mesh m = mixedMesh();
    writeNative(m, dir + "/good.uvrm");
    const std::string good = readBytes(dir + "/good.uvrm");
    const FileLayout l = layoutOf(m);
    auto expectInvalid = [&](auto mutate, const std::vector<std::string>& fragments) {
        std::string bytes = good;
        mutate(bytes);
        const std::string path = testing::writeFile(dir + "/bad.uvrm", bytes);
        std::vector<std::string> all = fragments;
        all.push_back(path);
        testing::expectError([&] { readNative(path); }, ErrorKind::Validation, all);
    };
    // Cell 2 (the wedge), corner 4 -> point 12 of 12.
    expectInvalid([&](std::string& b) { patch<std::uint32_t>(b, l.indices + 4 * (12 + 4), 12); },
                  {"cell 2 (wedge): corner 4 is point 12", "pointCount 12"});
    expectInvalid([&](std::string& b) { patch<std::uint8_t>(b, l.types + 1, 11); },
                  {"cell 1: type 11"});
    expectInvalid([&](std::string& b) { patch<std::uint8_t>(b, l.types + 3, 0); },
                  {"cell 3: type 0"});
    // Cell 1 declared a tetra but its offsets span 5 indices.
    expectInvalid([&](std::string& b) { patch<std::uint64_t>(b, l.offsets + 16, 13); },
                  {"cell 1: offsets 8..13"});
    // Offsets running backwards.
    expectInvalid([&](std::string& b) { patch<std::uint64_t>(b, l.offsets + 16, 2); },
                  {"cell 1: offsets 8..2"});
    expectInvalid([&](std::string& b) { patch<std::uint64_t>(b, l.offsets, 1); },
                  {"cell 0: offset 1, expected 0"});
    // The last offset must equal indexCount.
    expectInvalid([&](std::string& b) { patch<std::uint64_t>(b, l.offsets + 32, 22); },
                  {"cell 3: offsets 18..22"});
}

TEST(Native, MissingFileIsAnIoError) {
    const std::string path = testing::scratchDir() + "/missing.uvrm";
    testing::expectError([&] { readNative(path); }, ErrorKind::Io, {path});
}

TEST(Native, FailedWritesLeaveNoFile) {
    const std::string dir = testing::scratchDir();
    const std::string path = dir + "/no/such/folder/out.uvrm";
    testing::expectError([&] { writeNative(mixedMesh(), path); }, ErrorKind::Io, {path});
    EXPECT_FALSE(std::filesystem::exists(dir + "/no"));

    Mesh bad = mixedMesh();
    bad.fields[1].values.pop_back();
    const std::string out = dir + "/bad.uvrm";
    testing::expectError(
        [&] { writeNative(bad, out); }, ErrorKind::Validation,
        {out, "field 'velocity vector'", "35 values, expected 12 point tuples x 3"});
    bad = mixedMesh();
    bad.cellIndices[3] = 99;
    testing::expectError([&] { writeNative(bad, out); }, ErrorKind::Validation,
                         {out, "cell 0", "corner 3"});
    EXPECT_TRUE(std::filesystem::is_empty(dir)) << "nothing, not even a temporary, is left";

    // An existing file is replaced only by a complete new one.
    writeNative(mixedMesh(), out);
    const std::string before = readBytes(out);
    testing::expectError([&] { writeNative(bad, out); }, ErrorKind::Validation, {out});
    EXPECT_EQ(readBytes(out), before);
}

TEST(NativeWriter, PiecesOfAnySizeGiveWriteNativesBytes) {
    const std::string dir = testing::scratchDir();
    Mesh mesh = generateMesh([] {
        ProceduralSpec spec;
        spec.targetCells = 2000;
        return spec;
    }());
    mesh.fields.push_back({"cellf", Association::Cell, 2, {}});
    mesh.fields.back().values.assign(2 * mesh.cellCount(), 0.5f);
    writeNative(mesh, dir + "/whole.uvrm");
    std::vector<FieldInfo> fields;
    for (const Field& f : mesh.fields) fields.push_back({f.name, f.association, f.components});
    NativeWriter out(dir + "/pieces.uvrm", mesh.pointCount(), mesh.cellCount(),
                     mesh.cellIndices.size(), fields);
    // Pieces of 1, 2, 3, ... values, an empty piece now and then.
    auto inPieces = [](const auto& values, auto&& put) {
        using T = typename std::decay_t<decltype(values)>::value_type;
        std::size_t at = 0;
        for (std::size_t n = 0; at < values.size(); ++n) {
            const std::size_t take = std::min(n % 7, values.size() - at);
            put(std::span<const T>(values.data() + at, take));
            at += take;
        }
    };
    inPieces(mesh.points, [&](std::span<const Vec3f> v) { out.points(v); });
    out.tetrahedronTypesAndOffsets();
    inPieces(mesh.cellIndices, [&](std::span<const std::uint32_t> v) { out.cellIndices(v); });
    for (const Field& f : mesh.fields)
        inPieces(f.values, [&](std::span<const float> v) { out.fieldValues(v); });
    out.commit();
    EXPECT_EQ(readBytes(dir + "/pieces.uvrm"), readBytes(dir + "/whole.uvrm"));
}

TEST(NativeWriter, MisuseIsAnInternalErrorAndLeavesNoFile) {
    const std::string dir = testing::scratchDir();
    auto expectInternal = [&](auto&& fn, const std::string& text) {
        try {
            fn();
            ADD_FAILURE() << "no error for " << text;
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::Internal);
            EXPECT_THAT(e.what(), HasSubstr(text));
        }
        EXPECT_TRUE(std::filesystem::is_empty(dir));
    };
    const std::vector<Vec3f> points(5);
    expectInternal(
        [&] {
            NativeWriter out(dir + "/x.uvrm", 4, 1, 4, {});
            out.points(points);
        },
        "15 values for array 0");  // 15 words for an array of 12
    expectInternal(
        [&] {
            NativeWriter out(dir + "/x.uvrm", 5, 1, 4, {});
            out.points(points);
            out.commit();
        },
        "has 0 of 1 values");
    expectInternal(
        [&] {
            NativeWriter out(dir + "/x.uvrm", 0, 1, 5, {});
            out.tetrahedronTypesAndOffsets();
        },
        "5 indices for 1 tetrahedra");
}

TEST(NativeWriter, AFileLargerThanTheFreeSpaceIsRefusedAtOnce) {
    const std::string dir = testing::scratchDir();
    try {
        NativeWriter out(dir + "/huge.uvrm", 1ull << 50, 1, 4, {});
        ADD_FAILURE() << "no error for a 12 PiB file";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Io);
        EXPECT_THAT(e.what(), AllOf(HasSubstr("huge.uvrm"), HasSubstr("the file needs 135107988"),
                                    HasSubstr("available")));
    }
    EXPECT_TRUE(std::filesystem::is_empty(dir));
}

}  // namespace
}  // namespace uvr
