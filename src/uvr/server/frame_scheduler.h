// SPDX-License-Identifier: MIT
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <optional>
#include <vector>

namespace uvr::server {

/// The viewer's frame scheduling, apart from the network and the renderer (docs/VIEWER.md,
/// "Frames"): one render thread serves every tab's newest state, round robin; a change made
/// while dragging gets a reduced-resolution frame first, refined to full resolution once the
/// state has been still for a while; a snapshot is one full-size PNG.

using Clock = std::chrono::steady_clock;

/// The coarsest reduction a reduced frame can have (ScheduleOptions::maxScale is capped to it).
inline constexpr int kMaxReducedScale = 16;

/// The kinds of frame a tab gets.
enum class FrameKind {
    Reduced,   ///< a change while interacting: fewer pixels (reducedScale), JPEG
    Full,      ///< the state at full resolution, PNG
    Snapshot,  ///< asked for by the tab: full resolution, its own PNG
};

/// What one tab asks of the render thread. Its server holds one per connection and changes it
/// under its lock.
struct FrameDemand {
    bool dirty = true;         ///< the state changed since the last frame started
    bool interactive = false;  ///< the last change came from an interaction (a drag)
    bool snapshot = false;     ///< a snapshot was asked for
    bool inFlight = false;     ///< a frame is being rendered or sent: the tab gets no other
    bool needsFull = false;    ///< the last frame was reduced: refine when still
    Clock::time_point lastChange = Clock::now();
    double msPerPixel = 0.0;  ///< what a frame costs per pixel, averaged (0: none measured)
    /// What a reduced frame at scale s costs per pixel, averaged (0: none at that scale yet). A
    /// part of a frame's cost does not grow with its pixels (launches, read-back, encoding's
    /// setup), so a finer scale costs less per pixel than a coarser one measured: what a scale
    /// was measured at is trusted over msPerPixel.
    std::array<double, kMaxReducedScale + 1> reducedMsPerPixel{};

    /// Records a change of the state at `now` (interactive: part of a drag).
    void changed(bool interactive, Clock::time_point now);
    /// A frame of `kind` starts: it answers the change (or the snapshot) and is in flight.
    void start(FrameKind kind);
    /// A frame has been sent (or failed): the tab may get the next.
    void finished() { inFlight = false; }
    /// Averages a frame's measured cost per pixel into msPerPixel, and for a reduced frame
    /// (`scale` > 0, its reduction) into reducedMsPerPixel[scale].
    void measured(double frameMsPerPixel, int scale = 0);
};

/// How frames are scheduled (ServerOptions' values).
struct ScheduleOptions {
    std::chrono::milliseconds refineDelay{150};  ///< still this long: the full frame
    double targetFrameMs = 30.0;                 ///< a reduced frame aims at this
    int maxScale = 8;                            ///< coarsest reduction: 1/maxScale a side
};

/// The scheduler's choice: a tab and its frame, or none and when to look again.
struct FramePick {
    std::optional<std::size_t> tab;  ///< index into the demands given
    FrameKind kind = FrameKind::Full;
    /// With no tab: when a still tab's refinement falls due (max(): wait for a change).
    Clock::time_point wakeAt = Clock::time_point::max();
};

/// The next tab with work at `now`, looking round robin from index `from` (wrapped): a
/// snapshot first of that tab's work, then a changed state (reduced when interactive), then a
/// reduced frame whose state has been still for refineDelay. Null entries (closed tabs) and
/// tabs with a frame in flight are passed over.
FramePick pickFrame(const std::vector<const FrameDemand*>& tabs, std::size_t from,
                    Clock::time_point now, const ScheduleOptions& options);

/// The reduction of a reduced frame of `pixels` pixels for a tab of `demand`: the smallest scale
/// (pixels / scale^2 rendered) whose cost fits targetFrameMs, at most maxScale; 2 before any
/// measurement. A scale's cost is what frames at it cost (reducedMsPerPixel), else what
/// msPerPixel makes of its pixels; a scale not measured yet is tried when the next coarser one
/// took at most half the target (so a GPU whose frames cost little beyond their launch gets
/// full-size moving frames, though the per-pixel estimate says otherwise).
int reducedScale(const FrameDemand& demand, double pixels, const ScheduleOptions& options);

}  // namespace uvr::server
