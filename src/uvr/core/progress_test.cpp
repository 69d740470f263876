// SPDX-License-Identifier: MIT
// ProgressCounter: fractions from many threads, one report at a time, increasing, in range.
#include "uvr/core/progress.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>
#include <vector>

namespace uvr {
namespace {

/// Records reports and whether two ever overlapped.
struct Recorder {
    std::vector<double> seen;
    int inside = 0, overlapped = 0;
    FractionFn fn() {
        return [this](double f) {
            if (++inside > 1) ++overlapped;
            seen.push_back(f);
            std::this_thread::yield();  // widen the window another reporter could enter
            --inside;
        };
    }
};

/// Adds `total` units from `threads` threads, `units` at a time.
void addFromThreads(ProgressCounter& counter, int threads, std::int64_t total, std::int64_t units) {
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t)
        pool.emplace_back([&, t] {
            for (std::int64_t i = t * units; i < total; i += threads * units)
                counter.add(std::min(units, total - i));
        });
    for (std::thread& th : pool) th.join();
}

TEST(ProgressCounter, ManyThreadsReportOneAtATimeIncreasingWithinTheRange) {
    Recorder r;
    ProgressCounter counter(r.fn(), 100000, 0.25, 0.75);
    addFromThreads(counter, 8, 100000, 3);
    counter.finish();
    EXPECT_EQ(r.overlapped, 0);
    ASSERT_GE(r.seen.size(), 2u);
    EXPECT_LE(r.seen.size(), std::size_t(ProgressCounter::kSteps) + 1);
    for (std::size_t i = 0; i < r.seen.size(); ++i) {
        EXPECT_GT(r.seen[i], 0.25) << i;
        EXPECT_LE(r.seen[i], 0.75) << i;
        if (i > 0) {
            EXPECT_GT(r.seen[i], r.seen[i - 1]) << i;
        }
    }
    EXPECT_EQ(r.seen.back(), 0.75);
    // Nothing before finish() reached the range's end.
    for (std::size_t i = 0; i + 1 < r.seen.size(); ++i) EXPECT_LT(r.seen[i], 0.75);
}

TEST(ProgressCounter, ReportsOnlyAfterMovingBy1Over512) {
    Recorder r;
    ProgressCounter counter(r.fn(), 1024 * 1000);
    for (int i = 0; i < 1024 * 1000; ++i) counter.add();
    counter.finish();
    // One thread: a report each 2000 units (1/512), the last stride reaching the total held back.
    ASSERT_EQ(r.seen.size(), 512u);
    EXPECT_DOUBLE_EQ(r.seen[0], 2000.0 / 1024000.0);
    EXPECT_EQ(r.seen.back(), 1.0);
}

TEST(ProgressCounter, FinishReportsTheEndOnceAndEmptyCallbacksReportNothing) {
    Recorder r;
    ProgressCounter counter(r.fn(), 0, 0.0, 0.5);  // no units: only finish reports
    counter.add(5);
    counter.finish();
    counter.finish();
    ASSERT_EQ(r.seen.size(), 1u);
    EXPECT_EQ(r.seen[0], 0.5);
    ProgressCounter silent({}, 3);
    silent.add();
    silent.finish();
}

TEST(ProgressCounter, StepsOfOneCallbackCountIntoTheirParts) {
    Recorder r;
    const FractionFn report = r.fn();
    {
        ProgressCounter first(report, 1000, 0.0, 0.3);
        addFromThreads(first, 4, 1000, 1);
        first.finish();
    }
    {
        // A sub-range callback reaches the same parts through a nested function's own counter.
        ProgressCounter second(subRange(report, 0.3, 1.0), 1000, 0.0, 1.0);
        addFromThreads(second, 4, 1000, 10);
        second.finish();
    }
    ASSERT_GE(r.seen.size(), 3u);
    for (std::size_t i = 1; i < r.seen.size(); ++i) EXPECT_GT(r.seen[i], r.seen[i - 1]) << i;
    EXPECT_NE(std::find(r.seen.begin(), r.seen.end(), 0.3), r.seen.end());
    EXPECT_DOUBLE_EQ(r.seen.back(), 1.0);
    EXPECT_FALSE(subRange({}, 0.0, 1.0));
}

}  // namespace
}  // namespace uvr
