// SPDX-License-Identifier: MIT
#include "progress.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "cli_common.h"
#include "test_support.h"

namespace uvr::cli {
namespace {

TEST(Progress, LinesSayPercentRateAndEtaOrTheTimeSoFar) {
    EXPECT_EQ(Progress::line("refining", 10.0, 0.25, 8e6, "tetrahedra"),
              "refining: 25% (200.0 k tetrahedra/s, ETA 30 s)");
    EXPECT_EQ(Progress::line("writing x.uvrm", 3.0, 0.5, 0.0, ""), "writing x.uvrm: 50% (ETA 3 s)");
    EXPECT_EQ(Progress::line("reading x.vtk", 12.4, -1.0, 0.0, ""), "reading x.vtk: 12 s");
    EXPECT_EQ(Progress::line("rendering", 600.0, 0.1, 0.0, ""), "rendering: 10% (ETA 90 min)");
    EXPECT_EQ(Progress::line("rendering", 3600.0, 0.1, 0.0, ""), "rendering: 10% (ETA 9.0 h)");
    EXPECT_EQ(Progress::line("x", 1.0, 2.0, 0.0, ""), "x: 100% (ETA 0 s)");
}

TEST(Progress, ShortPhasesPrintOnlyTheirEndAndQuietPrintsNothing) {
    Context ctx;
    ::testing::internal::CaptureStderr();
    {
        Progress p(ctx, "generating");
        p.set(0.5);
        p.done("generated");
    }
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(err.rfind("uvr: generated (", 0), 0u) << err;
    EXPECT_EQ(err.find("generating"), std::string::npos) << err;

    ctx.quiet = true;
    ::testing::internal::CaptureStderr();
    {
        Progress p(ctx, "generating");
        std::this_thread::sleep_for(std::chrono::milliseconds(1300));
        p.done("generated");
    }
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

TEST(Progress, LongPhasesReportWhileTheyRunWhenNotATerminal) {
    Context ctx;
    ::testing::internal::CaptureStderr();  // a file: not a terminal, so plain lines
    {
        Progress p(ctx, "refining", 100.0, "tetrahedra");
        p.set(0.4);
        p.set(0.3);  // decreasing values are ignored
        std::this_thread::sleep_for(std::chrono::milliseconds(1300));
        p.done("refined");
    }
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("uvr: refining: 40% ("), std::string::npos) << err;
    EXPECT_EQ(err.find('\r'), std::string::npos) << err;
    EXPECT_NE(err.find("uvr: refined ("), std::string::npos) << err;
}

TEST(PhaseProgress, StepsPrintTheirNameAndOnlyLongPhasesTheirEnd) {
    Context ctx;
    ::testing::internal::CaptureStderr();
    {
        PhaseProgress phases(ctx);  // an end line after a second: none here
        const ProgressFn fn = phases.callbacks();
        fn("splitting 8 cells into tetrahedra");
        fn.fraction(0.5);
        fn.fraction(1.0);
        fn("finding face neighbours");
    }
    EXPECT_EQ(::testing::internal::GetCapturedStderr(),
              "uvr: splitting 8 cells into tetrahedra\nuvr: finding face neighbours\n");

    ::testing::internal::CaptureStderr();
    {
        PhaseProgress phases(ctx, 0.0);  // every phase long enough for its end line
        phases.fraction(0.3);            // before any step: ignored
        phases.step("a");
        phases.step("b");
        phases.finish();
        phases.finish();  // once
    }
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(err.rfind("uvr: a\nuvr: a: done (", 0), 0u) << err;
    const std::size_t b = err.find(" s)\nuvr: b\nuvr: b: done (");
    EXPECT_NE(b, std::string::npos) << err;
    EXPECT_EQ(err.find("b: done", err.find("b: done") + 1), std::string::npos) << err;
    EXPECT_EQ(testing::lineCount(err), 4) << err;
}

TEST(PhaseProgress, FractionsShowWithAnEtaInLongPhases) {
    Context ctx;
    ::testing::internal::CaptureStderr();  // a file: plain lines
    {
        PhaseProgress phases(ctx);
        phases.step("building k-d partitions");
        phases.fraction(0.25);
        std::this_thread::sleep_for(std::chrono::milliseconds(1300));
    }
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(err.rfind("uvr: building k-d partitions\n", 0), 0u) << err;
    EXPECT_NE(err.find("uvr: building k-d partitions: 25% (ETA "), std::string::npos) << err;
    EXPECT_NE(err.find("uvr: building k-d partitions: done (1."), std::string::npos) << err;
    ctx.quiet = true;
    ::testing::internal::CaptureStderr();
    {
        PhaseProgress phases(ctx, 0.0);
        phases.step("quiet");
        phases.fraction(0.5);
    }
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

}  // namespace
}  // namespace uvr::cli
