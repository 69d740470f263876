// SPDX-License-Identifier: MIT
#include "uvr/core/file_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "test_support.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

TEST(FileUtil, AtomicWriteLeavesNothingWhenTheWriterFails) {
    const std::string dir = testing::scratchDir();
    const std::string path = dir + "/out.txt";
    EXPECT_THROW(writeFileAtomically(path,
                                     [](const std::string& tmp) {
                                         std::ofstream(tmp) << "half";
                                         throw Error(ErrorKind::Io, "disk full");
                                     }),
                 Error);
    EXPECT_TRUE(std::filesystem::is_empty(dir));
    writeFileAtomically(path, [](const std::string& tmp) { std::ofstream(tmp) << "whole"; });
    std::ifstream in(path);
    std::string s;
    in >> s;
    EXPECT_EQ(s, "whole");
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 1);
}

TEST(FileUtil, OutputPathChecksNameTheFolder) {
    const std::string dir = testing::scratchDir();
    EXPECT_NO_THROW(checkOutputPath(dir + "/a.png"));
    try {
        checkOutputPath(dir + "/missing/a.png");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Io);
        EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos);
    }
    EXPECT_THROW(checkOutputPath(dir), Error);
}

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

}  // namespace
}  // namespace uvr
