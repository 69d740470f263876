// SPDX-License-Identifier: MIT
#pragma once
// Checks of two preparations of one mesh (tests only).

#include <gtest/gtest.h>

#include "test_support.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/prepare/prepared_mesh.h"
#include "uvr/render/frame_setup.h"

namespace uvr::testing {

/// Expects `got` to hold the structures of `want` (the split's cells, face neighbours, the
/// partitions' cells, seeds, macrocells, gradient spreads and the BVH's size), and so to render
/// the same frames on the CPU, by the partitions and by the reference, bit for bit.
inline void expectSamePreparation(const PreparedMesh& want, const PreparedMesh& got) {
    EXPECT_TRUE(sameBytes(want.tets.tets, got.tets.tets));
    EXPECT_EQ(want.neighbors, got.neighbors);
    EXPECT_EQ(want.bvh.nodes.size(), got.bvh.nodes.size());
    ASSERT_TRUE(want.kd && got.kd && want.seeds && got.seeds && want.macro && got.macro);
    EXPECT_EQ(want.kd->cells, got.kd->cells);
    EXPECT_EQ(want.seeds->seeds, got.seeds->seeds);
    EXPECT_TRUE(sameBytes(want.macro->cells, got.macro->cells));
    EXPECT_EQ(want.gradientSpread, got.gradientSpread);
    RenderSettings s;
    s.width = 64;
    s.height = 48;
    s.tf = transferFunctionPreset("cool-to-warm");
    for (const RenderMethod method : {RenderMethod::Partitions, RenderMethod::Reference}) {
        s.method = method;
        EXPECT_TRUE(sameBytes(renderCpu(want, s).image.pixels, renderCpu(got, s).image.pixels))
            << methodName(method);
    }
}

}  // namespace uvr::testing
