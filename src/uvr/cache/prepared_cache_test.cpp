// SPDX-License-Identifier: MIT
#include "uvr/cache/prepared_cache.h"

#include <gmock/gmock.h>
#include <zlib.h>

#include <cstring>
#include <filesystem>
#include <thread>

#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/mesh/procedural.h"
#include "uvr/tf/transfer_function.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;
using uvr::testing::catchError;

RenderSettings frameOf(const Bounds3f& bounds, RenderMethod method) {
    RenderSettings s;
    s.width = 48;
    s.height = 40;
    s.method = method;
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, "0:0,1:0.6");
    s.camera = orbitCamera(resetCamera(bounds, 48.f / 40.f), 25.f, 15.f);
    return s;
}

/// Both methods' structures (partitions and the mesh BVH), small partitions.
PrepareOptions bothMethods() {
    PrepareOptions o;
    o.kd.leafCells = 64;
    return o;
}

/// A source file for the key (its contents only matter to the fingerprint).
std::string sourceFile(const std::string& dir) {
    return testing::writeFile(dir + "/mesh.uvrm", std::string(3000, 'm'));
}

/// Renders every method the fresh preparation holds from it and from its cache and expects the
/// same frames bit for bit.
void expectSameFramesFromCache(const Mesh& mesh, const std::string& fieldSpec) {
    const std::string dir = testing::scratchDir();
    const ScalarField field = selectScalarField(mesh, parseFieldSpec(fieldSpec));
    const PrepareOptions options = bothMethods();
    const PreparedMesh fresh = prepareMesh(mesh, field, options);
    const CacheKey key = makeCacheKey(sourceFile(dir), fieldSpec, "", options);
    SourceSummary source;
    source.points = mesh.pointCount();
    source.cells = mesh.cellCount();
    source.bounds = mesh.bounds();
    source.fieldName = field.name;
    source.association = field.association;
    source.findings = {"3 inverted cells (first: cell 7)"};
    const std::string cache = dir + "/mesh.uvrprep";
    const std::uint64_t bytes = writePreparedCache(fresh, key, source, cache);
    EXPECT_EQ(bytes, std::filesystem::file_size(cache));

    LoadBudget budget;
    CacheHeader header;
    const PreparedMesh loaded = readPreparedCache(cache, key, budget, &header);
    EXPECT_EQ(loaded.cacheFile, cache);
    EXPECT_EQ(header.source.findings, source.findings);
    EXPECT_EQ(header.source.fieldName, field.name);
    EXPECT_EQ(header.cells, fresh.tets.cellCount());
    EXPECT_EQ(loaded.tets.cellCount(), fresh.tets.cellCount());
    EXPECT_EQ(describeCells(loaded.tets), describeCells(fresh.tets));
    EXPECT_TRUE(loaded.tets.tets.empty());  // host-only arrays are not stored
    EXPECT_TRUE(loaded.neighbors.empty());
    EXPECT_TRUE(loaded.kd->cells.empty());
    EXPECT_GT(budget.peak(), 0u);
    for (RenderMethod method :
         {RenderMethod::Partitions, RenderMethod::Reference, RenderMethod::Exact}) {
        const RenderSettings s = frameOf(mesh.bounds(), method);
        const RenderResult a = renderCpu(fresh, s), b = renderCpu(loaded, s);
        ASSERT_EQ(a.image.pixels.size(), b.image.pixels.size());
        EXPECT_EQ(a.stats.samples, b.stats.samples) << int(method);
        EXPECT_GT(a.stats.samples, 0u);
        for (std::size_t i = 0; i < a.image.pixels.size(); ++i) {
            const Vec4f p = a.image.pixels[i], q = b.image.pixels[i];
            ASSERT_TRUE(std::memcmp(&p, &q, sizeof p) == 0)
                << "pixel " << i << " method " << int(method) << " field " << fieldSpec;
        }
    }
}

TEST(PreparedCache, BoxRendersFromTheCacheAsFromAFreshPreparation) {
    ProceduralSpec spec;
    spec.targetCells = 20000;
    expectSameFramesFromCache(generateMesh(spec), "");
}

TEST(PreparedCache, MixedCellsRenderFromTheCacheAsFromAFreshPreparation) {
    expectSameFramesFromCache(generateMixedCellMesh(4), "linear");
}

TEST(PreparedCache, CellDataRendersFromTheCacheAsFromAFreshPreparation) {
    expectSameFramesFromCache(generateMixedCellMesh(4), "block");
}

TEST(PreparedCache, HoldsAboutThirtyBytesPerTetrahedronForTheAdaptiveMethod) {
    const std::string dir = testing::scratchDir();
    ProceduralSpec spec;
    spec.targetCells = 200000;
    const Mesh mesh = generateMesh(spec);
    PrepareOptions options;
    options.meshBvh = false;  // what --method adaptive prepares
    const PreparedMesh fresh = prepareMesh(mesh, selectScalarField(mesh, {}), options);
    const std::uint64_t bytes = writePreparedCache(
        fresh, makeCacheKey(sourceFile(dir), "", "", options), {}, dir + "/c.uvrprep");
    const double perTet = double(bytes) / double(fresh.tets.cellCount());
    EXPECT_LT(perTet, 32.0);
    EXPECT_GT(perTet, 16.0);
}

/// A cache of a small box in a scratch folder, with its key.
struct SmallCache {
    std::string dir, source, path;
    CacheKey key;
    SmallCache() : dir(testing::scratchDir()), source(sourceFile(dir)), path(dir + "/c.uvrprep") {
        ProceduralSpec spec;
        spec.targetCells = 3000;
        const Mesh mesh = generateMesh(spec);
        const PrepareOptions options = bothMethods();
        key = makeCacheKey(source, "", "", options);
        writePreparedCache(prepareMesh(mesh, selectScalarField(mesh, {}), options), key, {}, path);
    }
    Error readError() const {
        return catchError([&] {
            LoadBudget budget;
            readPreparedCache(path, key, budget);
        });
    }
};

std::uint64_t headerLength(const std::string& bytes) {
    std::uint64_t n;
    std::memcpy(&n, bytes.data() + 16, 8);
    return n;
}

/// Recomputes the header's CRC32 after an edit of the header (so that a later check fires).
void resealHeader(std::string& bytes) {
    const std::uint32_t crc = static_cast<std::uint32_t>(
        crc32(0L, reinterpret_cast<const Bytef*>(bytes.data() + 32), uInt(headerLength(bytes))));
    std::memcpy(bytes.data() + 24, &crc, 4);
}

TEST(PreparedCache, TruncatedFileIsRefused) {
    const SmallCache c;
    std::string bytes = testing::readFile(c.path);
    testing::writeFile(c.path, bytes.substr(0, bytes.size() - 200));
    const Error e = c.readError();
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr(c.path));
    EXPECT_THAT(e.what(), HasSubstr("reaches beyond the file's"));
    testing::writeFile(c.path, bytes.substr(0, 20));
    EXPECT_THAT(c.readError().what(), HasSubstr("shorter than its 32-byte preamble"));
}

TEST(PreparedCache, FlippedByteFailsItsArraysCrc) {
    const SmallCache c;
    std::string bytes = testing::readFile(c.path);
    // A byte of the first array (tets.tetCorners), which starts at the first multiple of 64
    // after the header.
    bytes[(32 + headerLength(bytes) + 63) / 64 * 64 + 10] ^= 0x10;
    testing::writeFile(c.path, bytes);
    const Error e = c.readError();
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr("fails its CRC32 check"));
    // A flipped byte of the header fails the header's CRC.
    bytes = testing::readFile(c.path);
    bytes[40] ^= 0x01;
    testing::writeFile(c.path, bytes);
    EXPECT_THAT(c.readError().what(), HasSubstr("the header's CRC32 does not match"));
}

TEST(PreparedCache, WrongMagicAndVersionAreRefused) {
    const SmallCache c;
    const std::string bytes = testing::readFile(c.path);
    std::string other = bytes;
    other[0] = 'X';
    testing::writeFile(c.path, other);
    EXPECT_THAT(c.readError().what(), HasSubstr("not a prepared cache"));
    other = bytes;
    const std::uint32_t version = kPreparedCacheVersion + 1;
    std::memcpy(other.data() + 8, &version, 4);
    testing::writeFile(c.path, other);
    const Error e = c.readError();
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr("format version " + std::to_string(version)));
    EXPECT_THAT(e.what(), HasSubstr("uvr prepare"));
}

TEST(PreparedCache, CountLargerThanTheFileIsRefusedBeforeAllocating) {
    const SmallCache c;
    std::string bytes = testing::readFile(c.path);
    // The table entry of tets.tetCorners: name, element size, count (docs/PREPARED_CACHE.md).
    const std::string name = "tets.tetCorners";
    const std::size_t at = bytes.find(name, 32);
    ASSERT_NE(at, std::string::npos);
    const std::uint64_t huge = 1ull << 60;
    std::memcpy(bytes.data() + at + name.size() + 8, &huge, 8);
    resealHeader(bytes);
    testing::writeFile(c.path, bytes);
    LoadBudget budget(1ull << 30);
    const Error e = catchError([&] { readPreparedCache(c.path, c.key, budget); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr("array 'tets.tetCorners' of 1152921504606846976 elements"));
    EXPECT_EQ(budget.peak(), 0u);
}

/// Overwrites `size` bytes at byte `at` of array `name` with `value` and reseals the array's
/// CRC32 and the header's: a crafted file whose checksums all match.
void craftBytes(std::string& bytes, const std::string& name, std::uint64_t at, const void* value,
                std::size_t size) {
    const std::size_t entry = bytes.find(name, 32);
    ASSERT_NE(entry, std::string::npos);
    std::uint64_t elementSize, count, offset;
    std::memcpy(&elementSize, bytes.data() + entry + name.size(), 8);
    std::memcpy(&count, bytes.data() + entry + name.size() + 8, 8);
    std::memcpy(&offset, bytes.data() + entry + name.size() + 16, 8);
    ASSERT_LE(at + size, count * elementSize);
    std::memcpy(bytes.data() + offset + at, value, size);
    const std::uint32_t crc = static_cast<std::uint32_t>(crc32(
        0L, reinterpret_cast<const Bytef*>(bytes.data() + offset), uInt(count * elementSize)));
    std::memcpy(bytes.data() + entry + name.size() + 24, &crc, 4);
    resealHeader(bytes);
}

TEST(PreparedCache, CraftedIndicesWithMatchingChecksumsAreRefused) {
    const SmallCache c;
    const std::string good = testing::readFile(c.path);
    struct Case {
        const char* array;
        std::uint64_t at;  ///< byte in the array
        std::uint64_t value;
        std::size_t size;
        const char* message;
    };
    const Case cases[] = {
        // Tetrahedron 1's second corner; tetrahedron 0's fourth neighbour code (an escape far
        // beyond its block's); the root's `first` (after its 24-byte box); the first seed.
        {"tets.tetCorners", 10, 0xffffull, 2, "corner lies outside its block"},
        {"neighbors.tetCodes", 6, 0x2000ull + 30000, 2, "neighbour code lies outside its block"},
        {"cellTree.nodes", 24, 0xfffffff0ull, 4, "the cell tree is malformed"},
        {"seeds.seeds", 0, 0x7fffffffull, 4, "name cells or seeds out of range"},
    };
    for (const Case& k : cases) {
        std::string bytes = good;
        craftBytes(bytes, k.array, k.at, &k.value, k.size);
        testing::writeFile(c.path, bytes);
        const Error e = c.readError();
        EXPECT_EQ(e.kind(), ErrorKind::Parse) << k.array;
        EXPECT_THAT(e.what(), HasSubstr(k.message)) << k.array;
        EXPECT_THAT(e.what(), HasSubstr(c.path)) << k.array;
    }
    testing::writeFile(c.path, good);
    LoadBudget budget;
    EXPECT_NO_THROW(readPreparedCache(c.path, c.key, budget));
}

TEST(PreparedCache, TheBudgetIsChargedBeforeAllocating) {
    const SmallCache c;
    LoadBudget budget(1000);
    const Error e = catchError([&] { readPreparedCache(c.path, c.key, budget); });
    EXPECT_EQ(e.kind(), ErrorKind::Resource);
    EXPECT_THAT(e.what(), HasSubstr("tets.tetCorners"));
}

/// The reason a stale cache is refused for `expected`.
std::string staleReason(const SmallCache& c, const CacheKey& expected) {
    LoadBudget budget;
    try {
        readPreparedCache(c.path, expected, budget);
    } catch (const StaleCacheError& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Argument);
        EXPECT_THAT(e.what(), HasSubstr(c.path));
        return e.reason();
    }
    ADD_FAILURE() << "a stale key was accepted";
    return "";
}

TEST(PreparedCache, StaleOrForeignKeysAreRefusedWithTheReason) {
    const SmallCache c;
    PrepareOptions options = bothMethods();
    // A touched mesh (same bytes, new modification time).
    std::filesystem::last_write_time(
        c.source, std::filesystem::last_write_time(c.source) + std::chrono::seconds(5));
    EXPECT_THAT(staleReason(c, makeCacheKey(c.source, "", "", options)),
                HasSubstr("modification time differs"));
    // Other contents of the same size.
    testing::writeFile(c.source, std::string(3000, 'n'));
    CacheKey k = makeCacheKey(c.source, "", "", options);
    k.sourceMtimeNs = c.key.sourceMtimeNs;
    EXPECT_THAT(staleReason(c, k), HasSubstr("first or last MiB differ"));
    // Another size, another file, another field, step, leaf size, method.
    k = c.key;
    k.sourceSize += 1;
    EXPECT_THAT(staleReason(c, k), HasSubstr("3000 bytes then, 3001 now"));
    k = c.key;
    k.sourcePath = "/elsewhere/other.vtu";
    EXPECT_THAT(staleReason(c, k), HasSubstr("not /elsewhere/other.vtu"));
    k = c.key;
    k.fieldSpec = "pressure";
    EXPECT_THAT(staleReason(c, k), HasSubstr("this asks for 'pressure'"));
    k = c.key;
    k.step = "index 2";
    EXPECT_THAT(staleReason(c, k), HasSubstr("time step"));
    k = c.key;
    k.leafCells = 128;
    EXPECT_THAT(staleReason(c, k), HasSubstr("up to 64 cells (--leaf-cells), this asks for 128"));
    k = c.key;
    k.meshBvh = false;
    EXPECT_THAT(staleReason(c, k), HasSubstr("mesh BVH"));
    k = c.key;
    k.splitCells = true;
    EXPECT_THAT(staleReason(c, k), HasSubstr("--split-cells"));
    EXPECT_EQ(cacheKeyMismatch(c.key, c.key), "");
}

TEST(PreparedCache, UpdateFieldValuesOnACacheLoadedMeshThrows) {
    const SmallCache c;
    LoadBudget budget;
    PreparedMesh m = readPreparedCache(c.path, c.key, budget);
    const ScalarField f{"x", Association::Point, std::vector<float>(10, 1.f)};
    const Error e = catchError([&] { updateFieldValues(m, f); });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_THAT(e.what(), HasSubstr("prepared from the cache " + c.path));
    EXPECT_THAT(e.what(), HasSubstr("preparing from the mesh"));
}

}  // namespace
}  // namespace uvr
