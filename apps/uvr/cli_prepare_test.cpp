// SPDX-License-Identifier: MIT
// `uvr prepare` and `uvr render` from a prepared cache (issue 16).
#include <gmock/gmock.h>

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli_test_support.h"
#include "test_support.h"

namespace uvr {
namespace {

using cli_testing::CliRun;
using cli_testing::expectOneLineError;
using cli_testing::uvr;
using ::testing::HasSubstr;
using ::testing::Not;

/// A small procedural box in a scratch folder.
std::string makeBox(const std::string& dir) {
    const std::string mesh = dir + "/box.uvrm";
    EXPECT_EQ(uvr("-q generate box --cells 6000 -o " + mesh, dir).code, 0);
    return mesh;
}

constexpr const char* kFrame = " --device cpu --size 64x48 --azimuth 20 --elevation 10";

TEST(CliPrepare, RenderUsesTheCacheAndWritesTheSamePng) {
    const std::string dir = testing::scratchDir();
    const std::string mesh = makeBox(dir);
    for (const std::string method : {"adaptive", "reference"}) {
        const std::string m = " --method " + method;
        std::filesystem::remove(mesh + ".uvrprep");
        CliRun fresh = uvr("render " + mesh + kFrame + m + " -o a.png --stats a.json", dir);
        ASSERT_EQ(fresh.code, 0) << fresh.err;
        EXPECT_THAT(fresh.err, Not(HasSubstr("prepared cache")));
        CliRun prep = uvr("prepare " + mesh + " --device cpu" + m, dir);
        ASSERT_EQ(prep.code, 0) << prep.err;
        EXPECT_THAT(prep.err, HasSubstr("wrote " + mesh + ".uvrprep"));
        ASSERT_TRUE(std::filesystem::exists(mesh + ".uvrprep"));
        CliRun cached = uvr("render " + mesh + kFrame + m + " -o b.png --stats b.json", dir);
        ASSERT_EQ(cached.code, 0) << cached.err;
        EXPECT_THAT(cached.err,
                    HasSubstr("using the prepared cache " + mesh + ".uvrprep (read in"));
        EXPECT_THAT(cached.err, Not(HasSubstr("read " + mesh)));
        EXPECT_EQ(testing::readFile(dir + "/a.png"), testing::readFile(dir + "/b.png")) << method;
        EXPECT_THAT(testing::readFile(dir + "/a.json"), HasSubstr("\"used\": false"));
        EXPECT_THAT(testing::readFile(dir + "/b.json"), HasSubstr("\"used\": true"));
        // Both statistics describe the same mesh.
        EXPECT_THAT(testing::readFile(dir + "/b.json"), HasSubstr("\"tetrahedra\": "));
        // --no-cache reads the mesh.
        CliRun off = uvr("render " + mesh + kFrame + m + " -o c.png --no-cache", dir);
        ASSERT_EQ(off.code, 0) << off.err;
        EXPECT_THAT(off.err, Not(HasSubstr("using the prepared cache")));
        EXPECT_EQ(testing::readFile(dir + "/a.png"), testing::readFile(dir + "/c.png"));
    }
}

TEST(CliPrepare, AStaleDefaultCacheIsSetAsideWithTheReason) {
    const std::string dir = testing::scratchDir();
    const std::string mesh = makeBox(dir);
    ASSERT_EQ(uvr("-q prepare " + mesh + " --device cpu", dir).code, 0);
    // Another method: the cache lacks the mesh BVH.
    CliRun r = uvr("render " + mesh + kFrame + " --method exact -o a.png", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_THAT(r.err, HasSubstr("warning: not using the prepared cache " + mesh + ".uvrprep"));
    EXPECT_THAT(r.err, HasSubstr("mesh BVH"));
    // A touched mesh.
    std::filesystem::last_write_time(
        mesh, std::filesystem::last_write_time(mesh) + std::chrono::seconds(3));
    r = uvr("render " + mesh + kFrame + " -o b.png", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_THAT(r.err, HasSubstr("the mesh changed since the cache was prepared"));
    EXPECT_THAT(r.err, HasSubstr("read " + mesh + ": "));
}

TEST(CliPrepare, AnExplicitMismatchingCacheIsAnError) {
    const std::string dir = testing::scratchDir();
    const std::string mesh = makeBox(dir);
    ASSERT_EQ(uvr("-q prepare " + mesh + " --device cpu -o p.uvrprep", dir).code, 0);
    CliRun r = uvr("render " + mesh + kFrame + " --field linear --cache p.uvrprep -o a.png", dir);
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.err, HasSubstr("p.uvrprep: the prepared cache does not match"));
    EXPECT_THAT(r.err, HasSubstr("this asks for 'linear'"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/a.png"));
    // Not a cache at all.
    testing::writeFile(dir + "/junk.uvrprep", std::string(100, 'j'));
    r = uvr("render " + mesh + kFrame + " --cache junk.uvrprep -o a.png", dir);
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.err, HasSubstr("not a prepared cache"));
    // The matching one renders.
    r = uvr("render " + mesh + kFrame + " --cache p.uvrprep -o a.png", dir);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_THAT(r.err, HasSubstr("using the prepared cache p.uvrprep"));
}

TEST(CliPrepare, AnUntrustedDefaultCacheIsSetAsideAndAnExplicitOneRefused) {
    const std::string dir = testing::scratchDir();
    const std::string mesh = makeBox(dir);
    const std::string cache = mesh + ".uvrprep";
    // Written under a permissive umask, the cache is still writable by its owner only.
    ASSERT_EQ(uvr("-q prepare " + mesh + " --device cpu", dir, "umask 0; ").code, 0);
    struct stat st;
    ASSERT_EQ(::stat(cache.c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 022, 0u);
    CliRun r = uvr("render " + mesh + kFrame + " -o a.png", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_THAT(r.err, HasSubstr("using the prepared cache"));
    // Writable by others: anyone could have put anything there.
    ASSERT_EQ(::chmod(cache.c_str(), 0666), 0);
    r = uvr("render " + mesh + kFrame + " -o b.png", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_THAT(r.err, HasSubstr("warning: not using the prepared cache " + cache));
    EXPECT_THAT(r.err, HasSubstr("not trusted as a prepared cache: its group or other users may "
                                 "write it (mode 0666)"));
    EXPECT_THAT(r.err, HasSubstr("read " + mesh + ": "));
    EXPECT_EQ(testing::readFile(dir + "/a.png"), testing::readFile(dir + "/b.png"));
    expectOneLineError(uvr("-q render " + mesh + kFrame + " --cache " + cache + " -o c.png", dir),
                       {cache + ": not trusted as a prepared cache"}, "--cache, mode 0666");
    // Another user's (the planted cache).
    if (::geteuid() == 0) {
        ASSERT_EQ(::chmod(cache.c_str(), 0644), 0);
        ASSERT_EQ(::chown(cache.c_str(), 65534, 65534), 0);
        r = uvr("render " + mesh + kFrame + " -o d.png", dir);
        ASSERT_EQ(r.code, 0) << r.err;
        EXPECT_THAT(r.err, HasSubstr("it belongs to uid 65534"));
        EXPECT_THAT(r.err, HasSubstr("read " + mesh + ": "));
        expectOneLineError(
            uvr("-q render " + mesh + kFrame + " --cache " + cache + " -o c.png", dir),
            {cache + ": not trusted as a prepared cache: it belongs to uid 65534"},
            "--cache of another user");
    }
    EXPECT_FALSE(std::filesystem::exists(dir + "/c.png"));
}

TEST(CliPrepare, ADamagedDefaultCacheIsSetAsideAndAnExplicitOneIsAnError) {
    const std::string dir = testing::scratchDir();
    const std::string mesh = makeBox(dir);
    const std::string cache = mesh + ".uvrprep";
    ASSERT_EQ(uvr("-q prepare " + mesh + " --device cpu", dir).code, 0);
    const std::string good = testing::readFile(cache);
    ASSERT_EQ(uvr("-q render " + mesh + kFrame + " --no-cache -o fresh.png", dir).code, 0);
    std::string flipped = good;
    flipped[flipped.size() - 100] ^= 0x10;  // inside the last array: its CRC fails
    const struct {
        const char* what;
        std::string bytes;
        const char* message;
    } cases[] = {
        {"a truncated array", good.substr(0, good.size() - 300), "reaches beyond the file's"},
        {"a bad CRC", flipped, "fails its CRC32 check"},
    };
    for (const auto& k : cases) {
        testing::writeFile(cache, k.bytes);
        CliRun r = uvr("render " + mesh + kFrame + " -o a.png", dir);
        ASSERT_EQ(r.code, 0) << k.what << ": " << r.err;
        EXPECT_THAT(r.err, HasSubstr("warning: not using the prepared cache " + cache)) << k.what;
        EXPECT_THAT(r.err, HasSubstr(k.message)) << k.what;
        EXPECT_THAT(r.err, HasSubstr("read " + mesh + ": ")) << k.what;
        EXPECT_EQ(testing::readFile(dir + "/a.png"), testing::readFile(dir + "/fresh.png"))
            << k.what;
        std::filesystem::remove(dir + "/a.png");
        expectOneLineError(
            uvr("-q render " + mesh + kFrame + " --cache " + cache + " -o b.png", dir),
            {cache, k.message}, k.what);
        EXPECT_FALSE(std::filesystem::exists(dir + "/b.png")) << k.what;
    }
}

TEST(CliPrepare, FifosAndDevicesAreRefusedAsCaches) {
    const std::string dir = testing::scratchDir();
    const std::string mesh = makeBox(dir);
    const std::string fifo = dir + "/fifo.uvrprep";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    // `timeout`: before the fix these waited for a writer forever.
    expectOneLineError(
        uvr("-q render " + mesh + kFrame + " --cache " + fifo + " -o a.png", dir, "timeout 60 "),
        {fifo + ": not a regular file (a FIFO): a prepared cache must be a file"}, "--cache FIFO");
    expectOneLineError(
        uvr("-q render " + mesh + kFrame + " --cache /dev/zero -o a.png", dir, "timeout 60 "),
        {"/dev/zero: not a regular file (a character device)"}, "--cache /dev/zero");
    // A FIFO where the default cache goes: render ignores it, prepare refuses to write into it
    // (named with -o it is written, as every output: -o /dev/null).
    ASSERT_EQ(::mkfifo((mesh + ".uvrprep").c_str(), 0600), 0);
    CliRun r = uvr("render " + mesh + kFrame + " -o a.png", dir, "timeout 60 ");
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_THAT(r.err, Not(HasSubstr("prepared cache")));
    expectOneLineError(
        uvr("-q prepare " + mesh + " --device cpu", dir, "timeout 60 "),
        {mesh + ".uvrprep: the default prepared cache is not a regular file", "name it with -o"},
        "prepare onto a FIFO");
    r = uvr("-q prepare " + mesh + " --device cpu -o /dev/null", dir, "timeout 60 ");
    EXPECT_EQ(r.code, 0) << r.err;
}

TEST(CliPrepare, SeriesAreRefused) {
    const std::string dir = testing::scratchDir();
    testing::writeFile(dir + "/s.pvd", "<VTKFile/>");
    CliRun r = uvr("prepare s.pvd", dir);
    EXPECT_NE(r.code, 0);
    EXPECT_THAT(r.err, HasSubstr("a cache's key covers one file"));
}

}  // namespace
}  // namespace uvr
