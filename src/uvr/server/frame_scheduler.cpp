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

void FrameDemand::measured(double frameMsPerPixel) {
    msPerPixel = msPerPixel > 0.0 ? 0.5 * (msPerPixel + frameMsPerPixel) : frameMsPerPixel;
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

int reducedScale(double msPerPixel, double pixels, const ScheduleOptions& options) {
    if (!(msPerPixel > 0.0)) return std::min(2, std::max(1, options.maxScale));  // none measured
    int scale = 1;
    while (scale < options.maxScale &&
           msPerPixel * pixels / (double(scale) * scale) > options.targetFrameMs)
        ++scale;
    return scale;
}

}  // namespace uvr::server
