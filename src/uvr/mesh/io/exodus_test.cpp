// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/exodus.h"

#include <gtest/gtest.h>

#include "test_support.h"

namespace uvr {
namespace {

const char* const kDiskOutRef = "/usr/lib/python3/dist-packages/mayavi/tests/data/disk_out_ref.ex2";

TEST(Exodus, ReadsDiskOutRef) {
    if (!exodusSupported()) GTEST_SKIP() << "built without netCDF";
    const Mesh mesh = readExodus(kDiskOutRef);
    EXPECT_EQ(mesh.pointCount(), 8499u);
    EXPECT_EQ(mesh.cellCount(), 7472u);
}

}  // namespace
}  // namespace uvr
