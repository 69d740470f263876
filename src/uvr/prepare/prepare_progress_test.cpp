// SPDX-License-Identifier: MIT
// prepareMesh's progress (issue 16): every phase named as it starts, the long ones' fractions
// increasing to 1, one report at a time, and the same preparation with or without reports, with
// one thread or two.
#include <gtest/gtest.h>

#include "test_meshes.h"
#include "test_support.h"

#include <cstring>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "uvr/cpu/threads.h"
#include "uvr/mesh/procedural.h"
#include "uvr/render/frame_setup.h"

namespace uvr {
namespace {

/// The reports of one preparation: per phase its name and fractions.
struct Recorded {
    struct Phase {
        std::string name;
        std::vector<double> fractions;
    };
    std::vector<Phase> phases;
    int outsidePhase = 0;  ///< fractions before any step
    int overlapped = 0;    ///< fraction reports that ran while another did
    std::mutex m;
    int inside = 0;

    ProgressFn callbacks() {
        return {[this](const std::string& name) {
                    phases.push_back({name, {}});
                },
                [this](double f) {
                    {
                        std::lock_guard lk(m);
                        if (++inside > 1) ++overlapped;
                    }
                    if (phases.empty())
                        ++outsidePhase;
                    else
                        phases.back().fractions.push_back(f);
                    std::lock_guard lk(m);
                    --inside;
                }};
    }
};

PreparedMesh prepareWithProgress(int threads, const ProgressFn& progress) {
    cpu::setThreadCount(threads);
    PreparedMesh pm = prepareMesh(testing::box400k(), selectScalarField(testing::box400k(), {}),
                                  PrepareOptions{}, progress);
    cpu::setThreadCount(0);
    return pm;
}

TEST(PrepareProgress, EveryPhaseIsNamedAndTheLongOnesCountToOne) {
    const std::set<std::string> counted = {"split",     "neighbours", "partitions",
                                           "cell_tree", "seed_grids", "gradient_spreads",
                                           "macrocells"};
    for (int threads : {1, 2}) {
        Recorded r;
        const PreparedMesh pm = prepareWithProgress(threads, r.callbacks());
        ASSERT_GT(pm.tets.cellCount(), 262144u);
        EXPECT_EQ(r.outsidePhase, 0);
        EXPECT_EQ(r.overlapped, 0);
        // One step per phase of phaseSeconds, in its order (all of them: seed grids and
        // macrocells included).
        ASSERT_EQ(r.phases.size(), pm.phaseSeconds.size()) << threads << " threads";
        ASSERT_EQ(pm.phaseSeconds.size(), 9u);
        for (std::size_t i = 0; i < r.phases.size(); ++i) {
            const std::string& phase = pm.phaseSeconds[i].first;
            const std::vector<double>& f = r.phases[i].fractions;
            SCOPED_TRACE(phase + " (" + r.phases[i].name + "), " + std::to_string(threads) +
                         " threads");
            EXPECT_FALSE(r.phases[i].name.empty());
            for (std::size_t k = 0; k < f.size(); ++k) {
                EXPECT_GE(f[k], 0.0);
                EXPECT_LE(f[k], 1.0);
                if (k > 0) {
                    EXPECT_GT(f[k], f[k - 1]) << k;
                }
            }
            if (counted.count(phase)) {
                ASSERT_FALSE(f.empty());
                EXPECT_EQ(f.back(), 1.0);
                // Long phases report along the way, not only their end.
                EXPECT_GE(f.size(), 3u);
            }
        }
    }
}

TEST(PrepareProgress, ReportsChangeNothingPreparedWithOneOrTwoThreads) {
    Recorded r1, r2;
    const PreparedMesh a = prepareWithProgress(2, {});
    const PreparedMesh b = prepareWithProgress(1, r1.callbacks());
    const PreparedMesh c = prepareWithProgress(2, r2.callbacks());
    for (const PreparedMesh* x : {&b, &c}) {
        EXPECT_TRUE(testing::sameBytes(a.tets.tets, x->tets.tets));
        EXPECT_TRUE(testing::sameBytes(a.tets.tetCorners, x->tets.tetCorners));
        EXPECT_TRUE(testing::sameBytes(a.tets.blockVertices, x->tets.blockVertices));
        EXPECT_TRUE(testing::sameBytes(a.neighbors, x->neighbors));
        EXPECT_TRUE(testing::sameBytes(a.neighborCodes.tetCodes, x->neighborCodes.tetCodes));
        EXPECT_TRUE(testing::sameBytes(a.neighborCodes.escapes, x->neighborCodes.escapes));
        EXPECT_TRUE(testing::sameBytes(a.kd->nodes, x->kd->nodes));
        EXPECT_TRUE(testing::sameBytes(a.kd->cells, x->kd->cells));
        EXPECT_TRUE(testing::sameBytes(a.cellTree.nodes, x->cellTree.nodes));
        EXPECT_TRUE(testing::sameBytes(a.gradientSpread, x->gradientSpread));
    }
}

TEST(PrepareProgress, LambdasOfAStepNameStillConvert) {
    std::vector<std::string> steps;
    const ProgressFn onlySteps = [&](const std::string& s) { steps.push_back(s); };
    EXPECT_TRUE(onlySteps);
    EXPECT_FALSE(onlySteps.fraction);
    onlySteps("a");
    EXPECT_EQ(steps, std::vector<std::string>{"a"});
    const ProgressFn none;
    EXPECT_FALSE(none);
    none("ignored");
}

}  // namespace
}  // namespace uvr
