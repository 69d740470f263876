// SPDX-License-Identifier: MIT
#include "uvr/server/frame_scheduler.h"

#include <algorithm>

namespace uvr::server {

void FrameDemand::changed(bool fromInteraction, Clock::time_point now) {
    interactive = fromInteraction;
    lastChange = now;
    dirty = true;
}

void FrameDemand::start(FrameKind kind) {
    if (kind == FrameKind::Snapshot) {
        snapshot = false;
    } else {
        dirty = false;
        needsFull = kind == FrameKind::Reduced;
    }
    inFlight = true;
}

namespace {

/// An average that weighs the newest measurement as much as all before it.
void average(double& into, double value) {
    into = into > 0.0 ? 0.5 * (into + value) : value;
}

}  // namespace

void FrameDemand::measured(double frameMsPerPixel, int scale) {
    average(msPerPixel, frameMsPerPixel);
    if (scale >= 1 && scale <= kMaxReducedScale)
        average(reducedMsPerPixel[std::size_t(scale)], frameMsPerPixel);
}

FramePick pickFrame(const std::vector<const FrameDemand*>& tabs, std::size_t from,
                    Clock::time_point now, const ScheduleOptions& options) {
    FramePick pick;
    const std::size_t n = tabs.size();
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t at = (from + i) % n;
        const FrameDemand* d = tabs[at];
        if (!d || d->inFlight) continue;
        if (d->snapshot)
            pick.kind = FrameKind::Snapshot;
        else if (d->dirty)
            pick.kind = d->interactive ? FrameKind::Reduced : FrameKind::Full;
        else if (d->needsFull && d->lastChange + options.refineDelay <= now)
            pick.kind = FrameKind::Full;
        else {
            if (d->needsFull)
                pick.wakeAt = std::min(pick.wakeAt, d->lastChange + options.refineDelay);
            continue;
        }
        pick.tab = at;
        pick.wakeAt = Clock::time_point::max();
        return pick;
    }
    return pick;
}

int reducedScale(const FrameDemand& demand, double pixels, const ScheduleOptions& options) {
    const int most = std::clamp(options.maxScale, 1, kMaxReducedScale);
    if (!(demand.msPerPixel > 0.0)) return std::min(2, most);  // none measured
    const auto costAt = [&](int scale) {
        const double perPixel = demand.reducedMsPerPixel[std::size_t(scale)];
        return (perPixel > 0.0 ? perPixel : demand.msPerPixel) * pixels / (double(scale) * scale);
    };
    for (int scale = 1; scale < most; ++scale) {
        const bool measured = demand.reducedMsPerPixel[std::size_t(scale)] > 0.0;
        if (!measured && demand.reducedMsPerPixel[std::size_t(scale) + 1] > 0.0 &&
            costAt(scale + 1) <= 0.5 * options.targetFrameMs)
            return scale;  // worth a try: its frames then say what it costs
        if (costAt(scale) <= options.targetFrameMs) return scale;
    }
    return most;
}

}  // namespace uvr::server
