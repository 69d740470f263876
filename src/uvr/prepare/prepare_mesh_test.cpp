// SPDX-License-Identifier: MIT
// prepareMesh with a face matcher from elsewhere (the GPU's): it is given the points' weld,
// found beside the split, and the preparation equals the CPU's.
#include <gtest/gtest.h>

#include "test_meshes.h"

#include <string>
#include <vector>

#include "prepared_checks.h"
#include "uvr/accel/tet_adjacency.h"
#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/render/frame_setup.h"

namespace uvr {
namespace {

TEST(PrepareMesh, AFaceMatcherIsGivenTheWeldOfThePointsItReads) {
    // Near the origin (the split keeps the points) and far from it (the split moves them into a
    // frame, and they are welded again).
    for (const float shift : {0.f, 1e4f}) {
        SCOPED_TRACE("shifted by " + std::to_string(shift));
        Mesh seams = testing::seamMesh(20000);
        for (Vec3f& p : seams.points) p.x += shift;
        const ScalarField field = selectScalarField(seams, {});
        const PreparedMesh cpu = prepareMesh(seams, field);
        int calls = 0;
        std::vector<std::uint32_t> given;
        PrepareOptions o;
        o.faceMatcher = [&](const TetMesh& m, const std::vector<std::uint32_t>& welded,
                            const FractionFn& progress) {
            ++calls;
            given = welded;
            return buildTetNeighbors(m, progress);
        };
        // The caller frees the mesh once it is split, as the CLI does: the weld beside the split
        // is done by then.
        Mesh copy = seams;
        o.afterSplit = [&copy] { copy = Mesh(); };
        const PreparedMesh pm = prepareMesh(copy, selectScalarField(copy, {}), o);
        EXPECT_TRUE(copy.points.empty());
        ASSERT_EQ(calls, 1);
        EXPECT_EQ(pm.tets.frame.identity(), shift == 0.f);
        EXPECT_EQ(given, coincidentPointIds(pm.tets.points));
        // The seam's copies are welded to the first points.
        EXPECT_EQ(given[seams.points.size() / 2], 0u);
        EXPECT_EQ(pm.neighbors, cpu.neighbors);
    }
}

/// What a GPU builder throws when the card lacks the memory for `what`.
[[noreturn]] void outOfMemory(const std::string& what) {
    throw Error(ErrorKind::Resource,
                "out of GPU memory allocating " + what + ": need 1.00 GiB more");
}

TEST(PrepareMesh, WhatTheBuildersDeviceLacksMemoryForTheCpuBuilds) {
    const Mesh seams = testing::seamMesh(20000);
    const ScalarField field = selectScalarField(seams, {});
    PrepareOptions cpuOptions;
    cpuOptions.meshBvh = true;
    cpuOptions.kd.leafCells = 512;
    const PreparedMesh cpu = prepareMesh(seams, field, cpuOptions);
    // A device whose memory holds the face neighbours but not the rest.
    PrepareOptions o = cpuOptions;
    o.builderDevice = "the test device";
    o.cells.sorter = [](const std::uint64_t*, std::uint64_t, std::uint32_t*) {
        outOfMemory("the sort keys");
    };
    o.lbvh = [](const LbvhInput&) -> LbvhResult { outOfMemory("the Morton keys"); };
    int matched = 0;
    o.faceMatcher = [&](const TetMesh& m, const std::vector<std::uint32_t>&,
                        const FractionFn& progress) {
        ++matched;
        return buildTetNeighbors(m, progress);
    };
    o.kdSplitter = [](const TetMesh&, const KdBuildOptions&, const FractionFn&) -> KdTree {
        outOfMemory("the centre keys");
    };
    o.seedBuilder = [](const TetMesh&, const KdPartitions&, float, const FractionFn&) -> SeedGrids {
        outOfMemory("the seed keys");
    };
    o.macroBuilder = [](const TetMesh&, const KdPartitions&, const std::vector<std::uint32_t>&,
                        float, const FractionFn&) -> MacroBuild { outOfMemory("the macrocells"); };
    std::vector<std::string> heard;
    const PreparedMesh fell = prepareMesh(
        seams, field, o, ProgressFn([&](const std::string& line) { heard.push_back(line); }));
    EXPECT_EQ(matched, 1);
    EXPECT_TRUE(fell.builtElsewhere);  // the neighbours
    EXPECT_EQ(fell.builtOnCpuInstead,
              (std::vector<std::string>{"split", "bvh", "partitions", "seed_grids", "macrocells"}));
    EXPECT_NE(std::find(heard.begin(), heard.end(),
                        "out of GPU memory allocating the centre keys: need 1.00 GiB more; "
                        "building the partitions on the CPU instead of the test device"),
              heard.end());
    // The CPU's structures, so the CPU's frames.
    testing::expectSamePreparation(cpu, fell);
    // Any other failure of a builder is the preparation's.
    o.kdSplitter = [](const TetMesh&, const KdBuildOptions&, const FractionFn&) -> KdTree {
        throw Error(ErrorKind::Internal, "CUDA error in a kernel");
    };
    try {
        prepareMesh(seams, field, o);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Internal);
    }
}

TEST(PrepareMesh, RenderableMethodsAreThoseItsStructuresServe) {
    const Mesh m = testing::seamMesh(2000);
    const ScalarField field = selectScalarField(m, {});
    const auto methods = [&](bool partitions, bool meshBvh, bool forAuto) {
        PrepareOptions o;
        o.partitions = partitions;
        o.meshBvh = meshBvh;
        o.forAuto = forAuto;
        std::vector<std::string> names;
        for (RenderMethod r : renderableMethods(prepareMesh(m, field, o)))
            names.push_back(methodName(r));
        return names;
    };
    using V = std::vector<std::string>;
    EXPECT_EQ(methods(true, true, false), (V{"auto", "adaptive", "reference", "exact"}));
    EXPECT_EQ(methods(true, false, false), (V{"auto", "adaptive"}));
    EXPECT_EQ(methods(false, true, false), (V{"auto", "reference", "exact"}));
    // forAuto alone: what auto picked for this mesh, and auto.
    const V picked = methods(false, false, true);
    ASSERT_GE(picked.size(), 2u);
    EXPECT_EQ(picked[0], "auto");
}

}  // namespace
}  // namespace uvr
