// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/mesh_reader.h"

#include <gtest/gtest.h>

#include "test_support.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

TEST(MeshReader, DispatchesByContentNotJustExtension) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    // A legacy file under a misleading name is still read as legacy VTK.
    std::filesystem::copy_file(testing::sharedData("tetraMesh.vtk"), dir + "/mesh.dat");
    EXPECT_EQ(readMesh(dir + "/mesh.dat").cellCount(), 160u);
    // The native round trip through writeMesh/readMesh.
    const Mesh spx = readMesh(testing::sharedData("spx.vtk"));
    writeMesh(spx, dir + "/spx.uvrm");
    const Mesh back = readMesh(dir + "/spx.uvrm");
    EXPECT_EQ(back.points.size(), spx.points.size());
    EXPECT_EQ(back.cellIndices, spx.cellIndices);
}

TEST(MeshReader, UnknownFormatsAndOutputsAreClearErrors) {
    const std::string dir = testing::scratchDir();
    testing::writeFile(dir + "/x.stl", "solid nothing\n");
    try {
        readMesh(dir + "/x.stl");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Parse);
        EXPECT_NE(std::string(e.what()).find("unrecognised file format"), std::string::npos);
    }
    EXPECT_THROW(readMesh(dir + "/absent.vtk"), Error);
    EXPECT_THROW(writeMesh(Mesh{}, dir + "/out.obj"), Error);
}

TEST(MeshReader, WritesVtuAndLegacyVtkByExtensionWithTheirOptions) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const Mesh spx = readMesh(testing::sharedData("spx.vtk"));
    for (const char* name : {"/spx.vtk", "/spx.vtu"}) {
        writeMesh(spx, dir + name);
        const Mesh back = readMesh(dir + name);
        EXPECT_EQ(back.cellIndices, spx.cellIndices) << name;
        ASSERT_EQ(back.fields.size(), spx.fields.size()) << name;
        EXPECT_EQ(back.fields[0].values, spx.fields[0].values) << name;
    }
    MeshWriteOptions lz4;
    lz4.compressor = VtuCompressor::Lz4;
    try {
        checkMeshWritable(dir + "/spx.vtk", lz4);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Argument);
        EXPECT_NE(
            std::string(e.what()).find("a compressor applies to .vtu output only, not to .vtk"),
            std::string::npos)
            << e.what();
    }
    try {
        checkMeshWritable(dir + "/spx.obj");
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(
                      "must end in .uvrm (native), .vtu, .vtk (legacy) or .vtkhdf"),
                  std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace uvr
