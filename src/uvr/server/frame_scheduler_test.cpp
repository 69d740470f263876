// SPDX-License-Identifier: MIT
#include "uvr/server/frame_scheduler.h"

#include <gtest/gtest.h>

namespace uvr::server {
namespace {

using std::chrono::milliseconds;

/// A tab that has been served and is still (no work).
FrameDemand idle(Clock::time_point t) {
    FrameDemand d;
    d.dirty = false;
    d.lastChange = t;
    return d;
}

TEST(FrameScheduler, ServesChangedTabsRoundRobinAndPassesOverBusyAndClosedOnes) {
    const Clock::time_point t0{};
    const ScheduleOptions o;
    FrameDemand a, b, c;  // all changed (a new tab's first frame)
    std::vector<const FrameDemand*> tabs = {&a, nullptr, &b, &c};
    FramePick p = pickFrame(tabs, 0, t0, o);
    ASSERT_TRUE(p.tab);
    EXPECT_EQ(*p.tab, 0u);
    EXPECT_EQ(p.kind, FrameKind::Full);
    a.start(p.kind);
    EXPECT_TRUE(a.inFlight);
    EXPECT_FALSE(a.dirty);
    // From the next index: the closed tab (null) and the busy one are passed over.
    p = pickFrame(tabs, 1, t0, o);
    ASSERT_TRUE(p.tab);
    EXPECT_EQ(*p.tab, 2u);
    b.start(p.kind);
    p = pickFrame(tabs, 3, t0, o);
    ASSERT_TRUE(p.tab);
    EXPECT_EQ(*p.tab, 3u);
    c.start(p.kind);
    // Everyone in flight: nothing, and nothing to wake for.
    p = pickFrame(tabs, 0, t0, o);
    EXPECT_FALSE(p.tab);
    EXPECT_EQ(p.wakeAt, Clock::time_point::max());
    // A change while a frame is in flight waits for it; then the tab is served again.
    a.changed(false, t0);
    EXPECT_FALSE(pickFrame(tabs, 0, t0, o).tab);
    a.finished();
    p = pickFrame(tabs, 1, t0, o);  // wraps around to it
    ASSERT_TRUE(p.tab);
    EXPECT_EQ(*p.tab, 0u);
}

TEST(FrameScheduler, ADragGetsReducedFramesRefinedOnceStill) {
    const Clock::time_point t0{};
    const ScheduleOptions o;  // refine after 150 ms
    FrameDemand d = idle(t0);
    d.changed(/*interactive=*/true, t0);
    std::vector<const FrameDemand*> tabs = {&d};
    FramePick p = pickFrame(tabs, 0, t0, o);
    ASSERT_TRUE(p.tab);
    EXPECT_EQ(p.kind, FrameKind::Reduced);
    d.start(p.kind);
    EXPECT_TRUE(d.needsFull);
    d.finished();
    // Still for less than the delay: nothing now, a wake-up when the refinement is due.
    p = pickFrame(tabs, 0, t0 + milliseconds(100), o);
    EXPECT_FALSE(p.tab);
    EXPECT_EQ(p.wakeAt, t0 + milliseconds(150));
    // Due: the full frame, after which the tab is done.
    p = pickFrame(tabs, 0, t0 + milliseconds(150), o);
    ASSERT_TRUE(p.tab);
    EXPECT_EQ(p.kind, FrameKind::Full);
    d.start(p.kind);
    d.finished();
    EXPECT_FALSE(d.needsFull);
    p = pickFrame(tabs, 0, t0 + milliseconds(1000), o);
    EXPECT_FALSE(p.tab);
    EXPECT_EQ(p.wakeAt, Clock::time_point::max());
}

TEST(FrameScheduler, ASnapshotComesBeforeTheTabsOtherWorkAndKeepsIt) {
    const Clock::time_point t0{};
    const ScheduleOptions o;
    FrameDemand d = idle(t0);
    d.changed(true, t0);
    d.snapshot = true;
    std::vector<const FrameDemand*> tabs = {&d};
    FramePick p = pickFrame(tabs, 0, t0, o);
    ASSERT_TRUE(p.tab);
    EXPECT_EQ(p.kind, FrameKind::Snapshot);
    d.start(p.kind);
    d.finished();
    EXPECT_FALSE(d.snapshot);
    EXPECT_TRUE(d.dirty);  // the change is still to be drawn
    p = pickFrame(tabs, 0, t0, o);
    ASSERT_TRUE(p.tab);
    EXPECT_EQ(p.kind, FrameKind::Reduced);
}

TEST(FrameScheduler, TheEarliestRefinementIsTheWakeUp) {
    const Clock::time_point t0{};
    const ScheduleOptions o{milliseconds(200), 30.0, 8};
    FrameDemand a = idle(t0), b = idle(t0);
    a.needsFull = true, a.lastChange = t0 + milliseconds(50);
    b.needsFull = true, b.lastChange = t0 + milliseconds(20);
    const FramePick p = pickFrame({&a, &b}, 0, t0 + milliseconds(60), o);
    EXPECT_FALSE(p.tab);
    EXPECT_EQ(p.wakeAt, t0 + milliseconds(220));
}

/// A tab whose frames cost msPerPixel, none reduced yet.
FrameDemand costing(double msPerPixel) {
    FrameDemand d;
    d.msPerPixel = msPerPixel;
    return d;
}

TEST(FrameScheduler, ReducedScaleFitsTheTargetTime) {
    const ScheduleOptions o{milliseconds(150), 30.0, 8};
    EXPECT_EQ(reducedScale(costing(0.0), 1e6, o), 2);  // nothing measured yet
    // 1e-5 ms a pixel: 1M pixels take 10 ms, within 30 ms at full size.
    EXPECT_EQ(reducedScale(costing(1e-5), 1e6, o), 1);
    // 1e-4 ms a pixel: 100 ms at full size; a quarter of the pixels (scale 2) take 25 ms.
    EXPECT_EQ(reducedScale(costing(1e-4), 1e6, o), 2);
    // 1e-3: 1000 ms; scale 6 renders 1/36 (27.8 ms), 5 would be 40 ms.
    EXPECT_EQ(reducedScale(costing(1e-3), 1e6, o), 6);
    // Never coarser than maxScale.
    EXPECT_EQ(reducedScale(costing(1.0), 1e6, o), 8);
}

TEST(FrameScheduler, AFinerScaleIsTriedWhenTheCoarserTookHalfTheTarget) {
    // The viewer at 100M tetrahedra on an H100 (docs/PERFORMANCE.md): 512x512 moving frames took
    // 9.4 ms, which per pixel says 37.6 ms at 1024x1024; full size took 17 ms.
    const ScheduleOptions o{milliseconds(150), 30.0, 8};
    const double pixels = 1024.0 * 1024.0;
    FrameDemand d;
    EXPECT_EQ(reducedScale(d, pixels, o), 2);
    d.measured(9.4 / (pixels / 4), 2);
    EXPECT_EQ(reducedScale(d, pixels, o), 1);  // 9.4 ms is under half the target: try
    d.measured(17.0 / pixels, 1);
    EXPECT_EQ(reducedScale(d, pixels, o), 1);  // and it fits
    // A full scale that did not fit is not tried again while its measure stands.
    FrameDemand slow;
    slow.measured(14.0 / (pixels / 4), 2);
    EXPECT_EQ(reducedScale(slow, pixels, o), 1);
    slow.measured(45.0 / pixels, 1);
    EXPECT_EQ(reducedScale(slow, pixels, o), 2);
    // Where the coarser scale took more than half the target, the per-pixel estimate decides.
    FrameDemand busy;
    busy.measured(20.0 / (pixels / 4), 2);
    EXPECT_EQ(reducedScale(busy, pixels, o), 2);
}

TEST(FrameScheduler, MeasuredCostsAreAveraged) {
    FrameDemand d;
    d.measured(4.0);
    EXPECT_DOUBLE_EQ(d.msPerPixel, 4.0);
    d.measured(2.0);
    EXPECT_DOUBLE_EQ(d.msPerPixel, 3.0);
    EXPECT_DOUBLE_EQ(d.reducedMsPerPixel[2], 0.0);  // full frames: no scale's
    d.measured(1.0, 2);
    EXPECT_DOUBLE_EQ(d.msPerPixel, 2.0);
    EXPECT_DOUBLE_EQ(d.reducedMsPerPixel[2], 1.0);
}

}  // namespace
}  // namespace uvr::server
