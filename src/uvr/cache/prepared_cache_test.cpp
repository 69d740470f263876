// SPDX-License-Identifier: MIT
#include "uvr/cache/prepared_cache.h"

#include <gmock/gmock.h>
#include <zlib.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <thread>

#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/mesh/procedural.h"
#include "uvr/mesh/smooth_gradients.h"
#include "uvr/tf/transfer_function.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;
using uvr::testing::catchError;

RenderSettings cacheFrameOf(const Bounds3f& bounds, RenderMethod method) {
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
    // The values a histogram of the cache is made of: the fresh preparation's, each at least
    // once (a tetrahedral point field's come from the blocks).
    const auto distinct = [](std::vector<float> v) {
        std::sort(v.begin(), v.end());
        v.erase(std::unique(v.begin(), v.end()), v.end());
        return v;
    };
    EXPECT_EQ(distinct(preparedValues(loaded)), distinct(preparedValues(fresh)));
    EXPECT_EQ(renderableMethods(loaded), renderableMethods(fresh));
    for (RenderMethod method :
         {RenderMethod::Partitions, RenderMethod::Reference, RenderMethod::Exact}) {
        const RenderSettings s = cacheFrameOf(mesh.bounds(), method);
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

/// Smooth gradients made on a mesh read from its cache (which holds no point ids: the block
/// vertices weld by position) equal those of the fresh preparation.
void expectSameSmoothGradientsFromCache(const Mesh& mesh, const std::string& fieldSpec) {
    const std::string dir = testing::scratchDir();
    const ScalarField field = selectScalarField(mesh, parseFieldSpec(fieldSpec));
    const PrepareOptions options = bothMethods();
    PreparedMesh fresh = prepareMesh(mesh, field, options);
    const CacheKey key = makeCacheKey(sourceFile(dir), fieldSpec, "", options);
    const std::string cache = dir + "/mesh.uvrprep";
    writePreparedCache(fresh, key, SourceSummary{}, cache);
    LoadBudget budget;
    PreparedMesh loaded = readPreparedCache(cache, key, budget);
    ASSERT_TRUE(loaded.tets.blockVertexPoint.empty());
    computeSmoothGradients(fresh.tets);
    computeSmoothGradients(loaded.tets);
    ASSERT_TRUE(hasSmoothGradients(loaded.tets));
    ASSERT_EQ(loaded.tets.blockGradients.size(), fresh.tets.blockGradients.size());
    ASSERT_EQ(loaded.tets.pointGradients.size(), fresh.tets.pointGradients.size());
    auto near = [](Vec3f a, Vec3f b) { return length(a - b) <= 1e-5f * (1.f + length(b)); };
    for (std::size_t i = 0; i < fresh.tets.blockGradients.size(); ++i)
        ASSERT_TRUE(near(loaded.tets.blockGradients[i], fresh.tets.blockGradients[i]))
            << "block vertex " << i;
    for (std::size_t i = 0; i < fresh.tets.pointGradients.size(); ++i)
        ASSERT_TRUE(near(loaded.tets.pointGradients[i], fresh.tets.pointGradients[i]))
            << "point " << i;
    RenderSettings s = cacheFrameOf(mesh.bounds(), RenderMethod::Exact);
    s.lighting.on = true;
    const RenderResult a = renderCpu(fresh, s), b = renderCpu(loaded, s);
    float worst = 0.f;
    for (std::size_t i = 0; i < a.image.pixels.size(); ++i)
        for (int k = 0; k < 4; ++k)
            worst = std::max(worst, std::fabs(a.image.pixels[i][k] - b.image.pixels[i][k]));
    EXPECT_LT(worst, 1e-4f);
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

TEST(PreparedCache, SmoothGradientsFromTheCacheWeldTheBlockVerticesByPosition) {
    // Tetrahedra only (the cache holds no points) and mixed cells (it holds the points, which
    // the native cells' corners name).
    ProceduralSpec spec;
    spec.targetCells = 20000;
    expectSameSmoothGradientsFromCache(generateMesh(spec), "");
    expectSameSmoothGradientsFromCache(generateMixedCellMesh(4), "linear");
}

TEST(PreparedCache, HoldsAboutThirtyBytesPerTetrahedronForTheAdaptiveMethod) {
    const std::string dir = testing::scratchDir();
    ProceduralSpec spec;
    spec.targetCells = 200000;
    const Mesh mesh = generateMesh(spec);
    PrepareOptions options;
    options.meshBvh = false;  // what --method adaptive prepares
    // For a GPU renderer (RendererOptions::prepareOptions). A mesh this small keeps the CPU's
    // cell tree of 2-cell leaves (kCpuCellTreeLeaf: 32 bytes per cell); large ones get
    // kCellTreeLeaf's (2 bytes per cell): counted so here.
    options.cellTreeLeaf = kCellTreeLeaf;
    const PreparedMesh fresh = prepareMesh(mesh, selectScalarField(mesh, {}), options);
    const std::uint64_t bytes = writePreparedCache(
        fresh, makeCacheKey(sourceFile(dir), "", "", options), {}, dir + "/c.uvrprep");
    const double cells = double(fresh.tets.cellCount());
    const double tree = double(fresh.cellTree.nodes.size() * sizeof(BvhNode)) / cells;
    EXPECT_GT(tree, 16.0);  // the small mesh's 2-cell leaves
    const double perTet = double(bytes) / cells - tree + 2.0;
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
        {"seeds.seeds", 0, 0x7fffffffull, 4, "a seed is not a cell"},
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

TEST(PreparedCache, EveryCraftedFieldWithMatchingChecksumsIsRefused) {
    // A deliberate writer: the cache writer itself, handed a prepared mesh with one field
    // changed, so that every checksum matches (a CRC proves nothing against such a file).
    // Three blocks of tetrahedra (escape bases to cross), partitions, seeds and macrocells.
    const std::string dir = testing::scratchDir();
    ProceduralSpec spec;
    spec.targetCells = 20000;
    const Mesh mesh = generateMesh(spec);
    const PrepareOptions options = bothMethods();
    const PreparedMesh fresh = prepareMesh(mesh, selectScalarField(mesh, {}), options);
    ASSERT_GE(fresh.neighborCodes.escapeBase.size(), 3u);
    ASSERT_TRUE(fresh.kd && fresh.seeds && fresh.macro);
    ASSERT_GE(fresh.kd->partitions.size(), 2u);
    const CacheKey key = makeCacheKey(sourceFile(dir), "", "", options);
    const std::string path = dir + "/c.uvrprep";
    const float nan = std::nanf("");
    struct Case {
        const char* what;
        std::function<void(PreparedMesh&)> craft;
        const char* message;
    };
    const Case cases[] = {
        // Header scalars.
        {"a pyramid count beyond 32-bit ids",
         [](PreparedMesh& m) { m.tets.pyramidCount = 1ull << 62; },
         "a cell count of 4611686018427387904"},
        {"infinite bounds", [](PreparedMesh& m) { m.tets.bounds.hi.x = INFINITY; },
         "bounds that are not finite"},
        {"NaN k-d bounds", [=](PreparedMesh& m) { m.kd->bounds.lo.y = nan; },
         "bounds that are not finite"},
        {"a zero scale", [](PreparedMesh& m) { m.tets.frame.scale = 0.0; }, "the frame's scale"},
        {"seeds without partitions",
         [](PreparedMesh& m) {
             m.kd.reset();
             m.macro.reset();
         },
         "grids without k-d partitions"},
        // The seed grids (the dims[0] = 0: cellIndex clamped to 4294967295).
        {"a seed grid of 0 cells across", [](PreparedMesh& m) { m.seeds->grids[0].dims[0] = 0; },
         "the seed grids are malformed: grid 0 has 0 cells on axis 0"},
        {"a seed grid too wide", [](PreparedMesh& m) { m.seeds->grids[0].dims[1] = 5000; },
         "grid 0 has 5000 cells on axis 1 (1 to 1024)"},
        {"seed grids overlapping", [](PreparedMesh& m) { m.seeds->grids[1].first -= 1; },
         "grid 1 starts at cell"},
        {"a NaN seed grid origin", [=](PreparedMesh& m) { m.seeds->grids[1].lo.z = nan; },
         "grid 1 has an origin that is not finite"},
        {"a negative cell size", [](PreparedMesh& m) { m.seeds->grids[0].cellsPerUnit.x = -1.f; },
         "grid 0 has a negative or NaN cell size"},
        {"a seed missing", [](PreparedMesh& m) { m.seeds->seeds.pop_back(); },
         "the seed grids are malformed: the grids hold"},
        {"a seed grid missing", [](PreparedMesh& m) { m.seeds->grids.pop_back(); },
         "the seed grids do not match the partitions"},
        // The macrocell grids.
        {"a macrocell grid of 0 cells", [](PreparedMesh& m) { m.macro->grids.back().dims[2] = 0; },
         "the macrocell grids are malformed"},
        {"a macrocell missing", [](PreparedMesh& m) { m.macro->cells.pop_back(); },
         "the macrocell grids are malformed: the grids hold"},
        {"NaN flags of another length", [](PreparedMesh& m) { m.macro->nanCells.assign(3, 1); },
         "macro.nanCells is not one per macrocell"},
        // Partitions.
        {"a NaN partition box", [=](PreparedMesh& m) { m.kd->partitions[0].box.lo.x = nan; },
         "a partition's box is not finite"},
        {"a k-d leaf beyond the partitions",
         [](PreparedMesh& m) {
             for (KdNode& n : m.kd->nodes)
                 if (n.isLeaf()) n.bits = (1000000u << 2) | 3u;
         },
         "the k-d tree is malformed"},
        {"a gradient spread missing", [](PreparedMesh& m) { m.gradientSpread.pop_back(); },
         "gradientSpread is not one per partition"},
        {"NaN flags of partitions", [](PreparedMesh& m) { m.partitionNan.assign(1, 1); },
         "partitionNan is not one per partition"},
        // Tetrahedra, blocks and neighbours.
        {"a block base going back",
         [](PreparedMesh& m) { m.tets.blockVertexBase[1] = m.tets.blockVertexBase[2] + 1; },
         "tets.blockVertexBase is not increasing"},
        {"an escape base going back",
         [](PreparedMesh& m) {
             m.neighborCodes.escapeBase[1] = m.neighborCodes.escapeBase.back() + 100000;
         },
         "neighbors.escapeBase is not increasing"},
        {"an escape naming no cell", [](PreparedMesh& m) { m.neighborCodes.escapes[0] = 4000000; },
         "a face neighbour is not a cell"},
        {"a corner missing", [](PreparedMesh& m) { m.tets.tetCorners.pop_back(); },
         "tets.tetCorners does not hold one entry per tetrahedron"},
        // Trees.
        {"cell tree ids naming no cell",
         [](PreparedMesh& m) { m.cellTree.primIds.assign(64, 7000000); },
         "the cell tree is malformed"},
        {"a mesh BVH id naming no cell", [](PreparedMesh& m) { m.bvh.primIds[0] = 7000000; },
         "the mesh BVH is malformed"},
    };
    for (const Case& k : cases) {
        PreparedMesh crafted = fresh;
        k.craft(crafted);
        writePreparedCache(crafted, key, {}, path);
        const Error e = catchError([&] {
            LoadBudget budget;
            readPreparedCache(path, key, budget);
        });
        EXPECT_EQ(e.kind(), ErrorKind::Parse) << k.what << ": " << e.what();
        EXPECT_THAT(e.what(), HasSubstr(k.message)) << k.what;
        EXPECT_THAT(e.what(), HasSubstr(path)) << k.what;
    }
    writePreparedCache(fresh, key, {}, path);
    LoadBudget budget;
    EXPECT_NO_THROW(readPreparedCache(path, key, budget));
}

TEST(PreparedCache, FilesOfOtherUsersWritableByOthersOrNotRegularAreNotTrusted) {
    const SmallCache c;
    const auto both = [&] {
        const Error header = catchError([&] { readPreparedCacheHeader(c.path); });
        const Error full = c.readError();
        EXPECT_EQ(std::string(header.what()), full.what());
        return full;
    };
    // Writable by its group or by everyone.
    for (mode_t mode : {0664, 0646}) {
        ASSERT_EQ(::chmod(c.path.c_str(), mode), 0);
        const Error e = both();
        EXPECT_EQ(e.kind(), ErrorKind::Io);
        EXPECT_THAT(e.what(), HasSubstr(c.path + ": not trusted as a prepared cache: its group or "
                                                 "other users may write it"));
    }
    ASSERT_EQ(::chmod(c.path.c_str(), 0644), 0);
    LoadBudget budget;
    EXPECT_NO_THROW(readPreparedCache(c.path, c.key, budget));
    // Another user's.
    if (::geteuid() == 0) {
        ASSERT_EQ(::chown(c.path.c_str(), 65534, 65534), 0);
        EXPECT_THAT(both().what(), HasSubstr("not trusted as a prepared cache: it belongs to uid "
                                             "65534"));
    }
    // A FIFO is refused before it is opened for reading (which would wait for a writer).
    const std::string fifo = c.dir + "/fifo.uvrprep";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    const Error e = catchError([&] { readPreparedCacheHeader(fifo); });
    EXPECT_EQ(e.kind(), ErrorKind::Io);
    EXPECT_THAT(e.what(), HasSubstr(fifo + ": not a regular file (a FIFO)"));
    EXPECT_THAT(catchError([&] { readPreparedCacheHeader("/dev/zero"); }).what(),
                HasSubstr("not a regular file (a character device)"));
    // A FIFO as the mesh of a key is refused likewise.
    EXPECT_THAT(catchError([&] { makeCacheKey(fifo, "", "", {}); }).what(),
                HasSubstr("not a regular file (a FIFO)"));
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
    EXPECT_THAT(staleReason(c, k), HasSubstr("up to 64 cells (`leaf_cells`), this asks for 128"));
    k = c.key;
    k.meshBvh = false;
    EXPECT_THAT(staleReason(c, k), HasSubstr("mesh BVH"));
    k = c.key;
    k.splitCells = true;
    EXPECT_THAT(staleReason(c, k), HasSubstr("without `split_cells`"));
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
