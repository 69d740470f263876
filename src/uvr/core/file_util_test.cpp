// SPDX-License-Identifier: MIT
#include "uvr/core/file_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <sys/stat.h>

#include "test_support.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

TEST(FileUtil, ReadRefusesFilesAboveTheLimitBeforeReading) {
    const std::string path =
        testing::writeFile(testing::scratchDir() + "/big.json", std::string(100, 'x'));
    EXPECT_EQ(readFileBytes(path, 100).size(), 100u);
    try {
        readFileBytes(path, 99, "colour-map file");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Resource);
        EXPECT_EQ(std::string(e.what()),
                  path + ": colour-map file of 100 bytes exceeds the limit of 99 bytes");
    }
}

TEST(FileUtil, ReadErrorsNameTheFile) {
    try {
        readFileBytes("/nonexistent/x.vtk");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Io);
        EXPECT_EQ(std::string(e.what()).rfind("/nonexistent/x.vtk: cannot open", 0), 0u);
    }
    EXPECT_EQ(fileExtension("a/b.VTU"), ".vtu");
    EXPECT_THROW(checkAllocation("f", "points", 1ull << 40, 12, 1ull << 30), Error);
    EXPECT_NO_THROW(checkAllocation("f", "points", 1ull << 40, 12, 0));
}

TEST(FileUtil, DevicesAndPipesAreRefusedWithoutBlocking) {
    // A .pvtu piece or a --tf argument may name any path: a pipe would block the open forever and
    // /dev/zero has no size to read.
    const std::string dir = testing::scratchDir();
    const std::string fifo = dir + "/pipe.vtu";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    for (const std::string& path : {fifo, std::string("/dev/zero")}) {
        const Error e = testing::catchError([&] { (void)readFileBytes(path); });
        EXPECT_EQ(e.kind(), ErrorKind::Io) << e.what();
        EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    EXPECT_EQ(testing::catchError([&] { (void)readFileBytes(dir); }).kind(), ErrorKind::Io);
}

}  // namespace
}  // namespace uvr
