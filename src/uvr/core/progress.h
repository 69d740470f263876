// SPDX-License-Identifier: MIT
// Fractions of long host-side work (preparation phases, frames) for progress lines (issue 16).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <utility>

namespace uvr {

/// Receives how far a piece of work has come, in [0, 1], increasing; from one thread at a time
/// (any thread), and it must not throw. Empty: nothing is reported.
using FractionFn = std::function<void(double)>;

/// A callback reporting fraction f of `report` as from + (to - from) * f: the part [from, to] of
/// the whole that a step of a longer piece of work takes. Empty when `report` is.
inline FractionFn subRange(const FractionFn& report, double from, double to) {
    if (!report) return {};
    return [report, from, to](double f) { report(f >= 1.0 ? to : from + (to - from) * f); };
}

/// Counts units of work done by many threads (add: one atomic add) and reports the fraction
/// done, mapped onto [from, to], to a FractionFn: from one thread at a time (a thread finding
/// another reporting goes on without waiting), increasing, only after it moved by at least
/// 1/kSteps of the range and never `to` itself before finish(), which reports `to`. A step of a
/// longer piece of work counts into its part [from, to] of the whole.
class ProgressCounter {
public:
    /// Reports per 1/kSteps of the range at most (512 lines of a progress bar).
    static constexpr std::int64_t kSteps = 512;

    /// Reports to `report` (may be empty: then nothing is reported) out of `total` units, over
    /// [from, to] of its range.
    ProgressCounter(FractionFn report, std::int64_t total, double from = 0.0, double to = 1.0)
        : report_(std::move(report)),
          total_(std::max<std::int64_t>(total, 1)),
          from_(from),
          to_(to),
          stride_(std::max<std::int64_t>(total_ / kSteps, 1)),
          next_(report_ ? stride_ : INT64_MAX) {}
    ProgressCounter(const ProgressCounter&) = delete;
    ProgressCounter& operator=(const ProgressCounter&) = delete;

    /// Marks `units` more units done (thread-safe); reports when the fraction moved enough and
    /// no other thread is reporting.
    void add(std::int64_t units = 1) {
        const std::int64_t done = done_.fetch_add(units, std::memory_order_relaxed) + units;
        if (done < next_.load(std::memory_order_relaxed) || done >= total_ ||
            !reporting_.try_lock())
            return;
        const std::int64_t now = std::min(done_.load(std::memory_order_relaxed), total_ - 1);
        const double fraction = from_ + (to_ - from_) * (double(now) / double(total_));
        if (fraction > reported_ && fraction < to_) {
            reported_ = fraction;
            report_(fraction);
        }
        next_.store(now + stride_, std::memory_order_relaxed);
        reporting_.unlock();
    }

    /// Units tick() counts at a time.
    static constexpr std::int64_t kTick = 1 << 14;

    /// For loops over single elements: counts kTick units at every kTick-th element index i (from
    /// 0), so a loop over n elements adds about n.
    void tick(std::int64_t i) {
        if (((i + 1) & (kTick - 1)) == 0) add(kTick);
    }

    /// Reports `to` once (call after the parallel work).
    void finish() {
        const std::lock_guard<std::mutex> lock(reporting_);
        if (report_ && reported_ < to_) report_(to_);
        reported_ = to_;
        next_.store(INT64_MAX, std::memory_order_relaxed);
    }

private:
    FractionFn report_;
    std::int64_t total_;
    double from_, to_;
    std::int64_t stride_;  ///< units between reports
    std::atomic<std::int64_t> done_{0};
    std::atomic<std::int64_t> next_;  ///< units done at which to report next
    std::mutex reporting_;
    double reported_ = -1.0;
};

}  // namespace uvr
