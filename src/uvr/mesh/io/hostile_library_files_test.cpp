// SPDX-License-Identifier: MIT
// Hostile Exodus (netCDF classic and netCDF-4) and VTKHDF files, which reach libnetcdf and
// libhdf5: counts a header declares without storing them, external links (into a FIFO),
// external storage, files on which the libraries crash or hang (tests/fuzz_regressions/
// netcdf_hdf5/), and a seeded structure-aware mutation fuzz of real files through the public
// readers: every input must give a uvr::Error or a mesh, never a crash or hang of this process.
// UVR_MUTATIONS=N runs N mutations per base file instead of the bounded CI count.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <random>

#include "test_support.h"
#include "uvr/core/file_util.h"
#include "uvr/mesh/io/exodus.h"
#include "uvr/mesh/io/isolated_probe.h"
#include "uvr/mesh/io/time_series.h"
#include "uvr/mesh/io/vtkhdf.h"
#include "uvr/mesh/procedural.h"
#include "uvr/mesh/validate.h"

#if defined(UVR_HAVE_NETCDF) && defined(UVR_HAS_HDF5)
#include <hdf5.h>

#include "exodus_file_writer.h"
#endif

namespace uvr {
namespace {

using testing::catchError;

#if defined(UVR_HAVE_NETCDF) && defined(UVR_HAS_HDF5)

using testing::kDiskOutRef;

#define REQUIRE_LIBRARIES()                                         \
    do {                                                            \
        if (!exodusSupported() || !vtkHdfSupported())               \
            GTEST_SKIP() << "built without netCDF or without HDF5"; \
    } while (0)

/// Two hexahedra with a nodal and an element variable at two steps.
testing::ExoFileSpec twoHexes(bool netcdf4) {
    testing::ExoFileSpec spec;
    for (int k = 0; k < 12; ++k) {
        spec.x.push_back(k % 2);
        spec.y.push_back((k / 2) % 2);
        spec.z.push_back(k / 4);
    }
    spec.blocks = {{7, "HEX8", 8, {1, 2, 4, 3, 5, 6, 8, 7, 5, 6, 8, 7, 9, 10, 12, 11}, "hexes"}};
    spec.nodalVars = {"temp"};
    spec.elemVars = {"stress"};
    spec.times = {0.0, 0.5};
    spec.nodal = [](std::size_t s, std::size_t, std::size_t n) { return double(s + n); };
    spec.element = [](std::size_t s, std::size_t, std::size_t, std::size_t e) {
        return double(10 * s + e);
    };
    spec.netcdf4 = netcdf4;
    return spec;
}

std::string writeExodus(const std::string& path, const testing::ExoFileSpec& spec) {
    testing::writeExodusFile(path, spec);
    return path;
}

/// Opens a series and reads every step (at most 4), validating each.
void readAll(const std::string& path, const ReadOptions& options = {}) {
    auto series = openMeshSeries(path, options);
    for (std::size_t s = 0; s < std::min<std::size_t>(series->stepCount(), 4); ++s) {
        const Mesh mesh = series->readStep(s);
        (void)validateMesh(mesh, path);
    }
}

void expectIn(const std::string& text, const std::string& part) {
    EXPECT_NE(text.find(part), std::string::npos) << text;
}

// --- Counts a file declares but does not store ------------------------------------------------

TEST(HostileLibraryFiles, ExodusCountsWithoutVariablesAreRefused) {
    REQUIRE_LIBRARIES();
    const std::string dir = testing::scratchDir();
    testing::ExoFileSpec spec = twoHexes(false);
    spec.nodalVars.clear();
    spec.elemVars.clear();
    const std::string path = writeExodus(dir + "/counts.e", spec);
    // 50 million nodal variables declared, none stored: their names alone were 1.6 GB.
    int nc = -1;
    ASSERT_EQ(nc_open(path.c_str(), NC_WRITE, &nc), NC_NOERR);
    ASSERT_EQ(nc_redef(nc), NC_NOERR);
    int d = -1;
    ASSERT_EQ(nc_def_dim(nc, "num_nod_var", 50'000'000, &d), NC_NOERR);
    ASSERT_EQ(nc_close(nc), NC_NOERR);
    const Error e = catchError([&] { readAll(path); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    expectIn(e.what(), path + ": num_nod_var is 50000000, but the file has ");
}

TEST(HostileLibraryFiles, Netcdf4ExodusDeclaringMoreThanItStoresIsRefused) {
    REQUIRE_LIBRARIES();
    const std::string dir = testing::scratchDir();
    const std::string path = writeExodus(dir + "/steps.e", twoHexes(true));
    // One time value written at record 4,999,999: the file declares 5 million steps and stores
    // the chunks of two (it was read as 5 million times, 40 MB, and as many steps).
    int nc = -1, v = -1;
    ASSERT_EQ(nc_open(path.c_str(), NC_WRITE, &nc), NC_NOERR);
    ASSERT_EQ(nc_inq_varid(nc, "time_whole", &v), NC_NOERR);
    const std::size_t last = 4'999'999;
    const float t = 9.0f;
    ASSERT_EQ(nc_put_var1_float(nc, v, &last, &t), NC_NOERR);
    ASSERT_EQ(nc_close(nc), NC_NOERR);
    ASSERT_LT(fileSize(path), 1u << 20);
    const Error e = catchError([&] { (void)openExodus(path); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    expectIn(e.what(), path + ": variable ");
    expectIn(e.what(), " declares ");
    expectIn(e.what(), "but the file stores only");
}

TEST(HostileLibraryFiles, ClassicExodusErrorsNameTheVariableBeyondTheFile) {
    REQUIRE_LIBRARIES();
    const std::string dir = testing::scratchDir();
    testing::ExoFileSpec spec = twoHexes(false);
    for (int k = 0; k < 3000; ++k) {  // points no cell uses: 36 KB of coordinates
        spec.x.push_back(k);
        spec.y.push_back(-k);
        spec.z.push_back(2 * k);
    }
    const std::string whole = writeExodus(dir + "/whole.e", spec);
    const std::vector<char> bytes = readFileBytes(whole);
    // The records cut off (netCDF would read their values as fill values).
    const std::size_t keep = bytes.size() - 20000;
    const std::string cut = testing::writeFile(dir + "/cut.e", std::string(bytes.data(), keep));
    const Error e = catchError([&] { readAll(cut); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    expectIn(e.what(), cut + ": variable ");
    expectIn(e.what(), " bytes: the file has " + std::to_string(keep));
}

// --- Links and storage in other files ----------------------------------------------------------

/// A one-partition VTKHDF file of a small procedural mesh.
std::string writeSmallVtkHdf(const std::string& path) {
    ProceduralSpec spec;
    spec.targetCells = 40;
    writeVtkHdf(generateMesh(spec), path);
    return path;
}

TEST(HostileLibraryFiles, VtkHdfExternalLinkIntoAFifoIsRefused) {
    REQUIRE_LIBRARIES();
    const std::string dir = testing::scratchDir();
    const std::string path = writeSmallVtkHdf(dir + "/linked.vtkhdf");
    const std::string fifo = dir + "/points.fifo";
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    {
        const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        ASSERT_GE(file, 0);
        ASSERT_GE(H5Ldelete(file, "VTKHDF/Points", H5P_DEFAULT), 0);
        ASSERT_GE(H5Lcreate_external(fifo.c_str(), "/Points", file, "VTKHDF/Points", H5P_DEFAULT,
                                     H5P_DEFAULT),
                  0);
        H5Fclose(file);
    }
    // (Followed, HDF5 opened the FIFO and waited for a writer forever.)
    const Error e = catchError([&] { readAll(path); });
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    EXPECT_EQ(std::string(e.what()),
              path + ": the external link '/VTKHDF/Points' to object '/Points' of the file '" +
                  fifo + "': uvr does not follow links into other files");
}

TEST(HostileLibraryFiles, VtkHdfExternalStorageIsRefused) {
    REQUIRE_LIBRARIES();
    const std::string dir = testing::scratchDir();
    const std::string path = writeSmallVtkHdf(dir + "/external.vtkhdf");
    const std::string raw = testing::writeFile(dir + "/raw.bin", std::string(4096, '\0'));
    {
        const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        ASSERT_GE(file, 0);
        const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
        ASSERT_GE(H5Pset_external(dcpl, raw.c_str(), 0, 4096), 0);
        const hsize_t n = 16;
        const hid_t space = H5Screate_simple(1, &n, nullptr);
        const hid_t d = H5Dcreate2(file, "VTKHDF/Elsewhere", H5T_IEEE_F32LE, space, H5P_DEFAULT,
                                   dcpl, H5P_DEFAULT);
        ASSERT_GE(d, 0);
        H5Dclose(d);
        H5Sclose(space);
        H5Pclose(dcpl);
        H5Fclose(file);
    }
    const Error e = catchError([&] { readAll(path); });
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    expectIn(e.what(),
             path + ": /VTKHDF/Elsewhere: a dataset stored externally, in the file '" + raw + "'");
}

TEST(HostileLibraryFiles, Netcdf4ExodusExternalLinkIsRefused) {
    REQUIRE_LIBRARIES();
    const std::string dir = testing::scratchDir();
    const std::string path = writeExodus(dir + "/linked.e", twoHexes(true));
    {
        const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        ASSERT_GE(file, 0);
        ASSERT_GE(
            H5Lcreate_external("/dev/zero", "/x", file, "elsewhere", H5P_DEFAULT, H5P_DEFAULT), 0);
        H5Fclose(file);
    }
    const Error e = catchError([&] { readAll(path); });
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    expectIn(e.what(), path +
                           ": the external link '/elsewhere' to object '/x' of the file "
                           "'/dev/zero'");
}

// --- Files the libraries crash or hang on ------------------------------------------------------

TEST(HostileLibraryFiles, FilesTheLibrariesCrashOnGiveAnError) {
    REQUIRE_LIBRARIES();
    const std::string folder = std::string(UVR_FUZZ_REGRESSIONS_DIR) + "/netcdf_hdf5";
    const ScopedProbeSeconds shortProbes(5);
    std::size_t files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
        if (entry.path().extension() == ".md") continue;
        ++files;
        const std::string path = entry.path().string();
        SCOPED_TRACE(path);
        const Error e = catchError([&] { readAll(path); });
        expectIn(e.what(), path + ": ");
        if (entry.path().filename().string().rfind("crash", 0) == 0)
            expectIn(e.what(), "library failed on this file (");
    }
    EXPECT_GE(files, 2u);
}

TEST(HostileLibraryFiles, TheCliExitsWithTwoWhenALibraryCrashes) {
    REQUIRE_LIBRARIES();
    const std::string dir = testing::scratchDir();
    const std::string folder = std::string(UVR_FUZZ_REGRESSIONS_DIR) + "/netcdf_hdf5/";
    for (const auto& [name, library] :
         {std::pair{"crash_global_heap_a.e", "netCDF"}, {"heap_link_table_free.vtkhdf", "HDF5"}}) {
        SCOPED_TRACE(name);
        const std::string log = dir + "/info.log";
        // (The library's SIGSEGV killed uvr: the shell's status 139.)
        const int status = testing::runCommand(testing::uvrBinary() + " info " + folder + name +
                                               " > " + log + " 2>&1");
        if (testing::underAddressSanitizer() && status == 0) {
            // The crash reads garbage whose contents depend on the allocator: under the
            // sanitizer's allocator these files may read without one. Never a signal, though.
            continue;
        }
        EXPECT_EQ(status, 2);
        // (signal 11 in a release build; a sanitizer's allocator may end the child itself.)
        expectIn(testing::readFile(log), "uvr: error: " + folder + name + ": the " + library +
                                             " library failed on this file (");
    }
}

// --- Structure-aware mutation of real files ----------------------------------------------------

/// A mutation of a netCDF or HDF5 file: header words set to telling values (lengths, counts,
/// offsets and addresses in netCDF's big-endian 4/8-byte fields, HDF5's little-endian ones),
/// bits flipped, bytes randomised, the file cut or extended.
class Mutator {
public:
    explicit Mutator(std::uint64_t seed) : rng_(seed) {}

    std::vector<char> mutate(const std::vector<char>& base, bool hdf5) {
        std::vector<char> b = base;
        const int edits = 1 + static_cast<int>(pick(4));
        for (int k = 0; k < edits; ++k) {
            // Most edits in the metadata (the first 4 KB and, in HDF5, near object headers).
            const std::size_t span =
                pick(4) == 0 ? b.size() : std::min<std::size_t>(b.size(), 4096);
            if (span < 16) break;
            switch (pick(6)) {
                case 0:
                case 1: {  // a word set to a telling value
                    const int width = pick(2) ? 4 : 8;
                    std::size_t at = pick(span - width);
                    if (!hdf5) at &= ~std::size_t{3};  // netCDF's header is 4-byte aligned
                    std::uint64_t old = 0;
                    for (int i = 0; i < width; ++i)
                        old |= std::uint64_t(std::uint8_t(b[at + i]))
                               << (8 * (hdf5 ? i : width - 1 - i));
                    const std::uint64_t values[] = {0,
                                                    1,
                                                    old + 1,
                                                    old - 1,
                                                    old * 2,
                                                    old + 4096,
                                                    0x7fffffffull,
                                                    0xffffffffull,
                                                    0x80000000ull,
                                                    0x7fffffffffffffffull,
                                                    ~0ull,
                                                    500'000'000ull,
                                                    b.size(),
                                                    b.size() - 8};
                    const std::uint64_t v = values[pick(std::size(values))];
                    for (int i = 0; i < width; ++i)
                        b[at + i] = static_cast<char>(v >> (8 * (hdf5 ? i : width - 1 - i)));
                    break;
                }
                case 2:  // bits flipped
                    b[pick(span)] ^= static_cast<char>(1u << pick(8));
                    break;
                case 3:  // random bytes
                    for (std::size_t i = 0, n = 1 + pick(8), at = pick(span - 8); i < n; ++i)
                        b[at + i] = static_cast<char>(pick(256));
                    break;
                case 4:  // cut
                    b.resize(std::max<std::size_t>(8, pick(b.size())));
                    break;
                default:  // a block copied elsewhere (headers repeated at other offsets)
                {
                    const std::size_t n = 1 + pick(64);
                    if (b.size() <= 2 * n) break;
                    const std::size_t from = pick(b.size() - n), to = pick(span > n ? span - n : 1);
                    std::memmove(b.data() + to, b.data() + from, std::min(n, b.size() - to));
                    break;
                }
            }
        }
        return b;
    }

private:
    std::size_t pick(std::size_t n) {
        return n ? std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_) : 0;
    }
    std::mt19937_64 rng_;
};

TEST(HostileLibraryFiles, MutatedRealFilesGiveErrorsNotCrashes) {
    REQUIRE_LIBRARIES();
    const std::string dir = testing::scratchDir();
    std::vector<std::pair<std::string, std::string> > bases;  // (path, extension)
    bases.emplace_back(writeExodus(dir + "/classic.e", twoHexes(false)), ".e");
    bases.emplace_back(writeExodus(dir + "/nc4.e", twoHexes(true)), ".e");
    bases.emplace_back(writeSmallVtkHdf(dir + "/one.vtkhdf"), ".vtkhdf");
    if (std::filesystem::exists(kDiskOutRef)) bases.emplace_back(kDiskOutRef, ".ex2");
    {
        // A temporal VTKHDF (Steps), two steps of one geometry.
        ProceduralSpec spec;
        spec.targetCells = 30;
        const Mesh mesh = generateMesh(spec);
        const std::string path = dir + "/steps.vtkhdf";
        writeVtkHdfSeries(
            mesh, {0.0, 1.0}, [&](std::size_t) { return mesh.fields; }, path);
        bases.emplace_back(path, ".vtkhdf");
    }
    const char* env = std::getenv("UVR_MUTATIONS");
    const std::size_t perBase = env ? std::strtoull(env, nullptr, 10) : 60;
    const ScopedProbeSeconds shortProbes(env ? 10 : 2);
    ReadOptions options;
    options.maxMemoryBytes = 1ull << 30;
    std::map<std::string, std::size_t> outcomes;
    std::size_t total = 0;
    for (std::size_t b = 0; b < bases.size(); ++b) {
        const auto& [base, ext] = bases[b];
        const std::vector<char> bytes = readFileBytes(base);
        const bool hdf5 =
            bytes.size() >= 4 && bytes[1] == 'H' && bytes[2] == 'D' && bytes[3] == 'F';
        Mutator mutator(0x5eed0000 + b);
        for (std::size_t m = 0; m < perBase; ++m) {
            const std::vector<char> mutated = mutator.mutate(bytes, hdf5);
            const std::string path = dir + "/mutant" + ext;
            testing::writeFile(path, std::string(mutated.data(), mutated.size()));
            std::string outcome = "read";
            try {
                readAll(path, options);
            } catch (const Error& e) {
                const std::string what = e.what();
                outcome = what.find("library failed on this file (signal") != std::string::npos
                              ? "library crash (isolated)"
                          : what.find("library failed on this file (no answer") != std::string::npos
                              ? "library hang (isolated)"
                              : "error kind " + std::to_string(int(e.kind()));
                EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
                if (env && outcome.rfind("library", 0) == 0) {
                    const std::string keep =
                        dir + "/found_" + std::to_string(b) + "_" + std::to_string(m) + ext;
                    std::filesystem::copy_file(path, keep);
                    std::printf("%s: %s\n", keep.c_str(), what.c_str());
                }
            }
            ++outcomes[std::filesystem::path(base).filename().string() + ": " + outcome];
            ++total;
        }
    }
    for (const auto& [what, count] : outcomes) std::printf("  %6zu  %s\n", count, what.c_str());
    std::printf("%zu mutations of %zu real files\n", total, bases.size());
}

/// Median milliseconds of n calls of f.
template <typename F>
double medianMs(int n, F&& f) {
    std::vector<double> ms;
    for (int k = 0; k < n; ++k) {
        const auto t0 = std::chrono::steady_clock::now();
        f();
        ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
    }
    std::sort(ms.begin(), ms.end());
    return ms[ms.size() / 2];
}

TEST(HostileLibraryFiles, ProbeCost) {
    REQUIRE_LIBRARIES();
    if (!std::getenv("UVR_PROBE_COST")) GTEST_SKIP() << "a measurement: set UVR_PROBE_COST=1";
    const std::string dir = testing::scratchDir();
    ProceduralSpec spec;
    spec.targetCells = 100000;
    const std::string vtkhdf = dir + "/cost.vtkhdf";
    writeVtkHdf(generateMesh(spec), vtkhdf);
    std::vector<std::string> files = {vtkhdf, writeExodus(dir + "/nc4.e", twoHexes(true))};
    if (std::filesystem::exists(kDiskOutRef)) files.insert(files.begin(), kDiskOutRef);
    for (const std::string& file : files) {
        double ms[2][2];
        for (int isolate = 0; isolate < 2; ++isolate) {
            ProbeLimits limits = probeLimits();
            const ProbeLimits saved = limits;
            limits.isolate = isolate == 1;
            setProbeLimits(limits);
            ms[isolate][0] = medianMs(20, [&] { (void)openMeshSeries(file); });
            ms[isolate][1] = medianMs(5, [&] { (void)openMeshSeries(file)->readStep(0); });
            setProbeLimits(saved);
        }
        std::printf(
            "%s (%llu bytes): open %.2f ms in-process, %.2f ms isolated; open + step 0 "
            "%.2f ms / %.2f ms\n",
            file.c_str(), static_cast<unsigned long long>(fileSize(file)), ms[0][0], ms[1][0],
            ms[0][1], ms[1][1]);
    }
}

#endif  // UVR_HAVE_NETCDF && UVR_HAS_HDF5

}  // namespace
}  // namespace uvr

#undef REQUIRE_LIBRARIES  // file-local: the unity build joins test files
