// SPDX-License-Identifier: MIT
#include "progress.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>

#include "cli_common.h"
#include "uvr/core/text.h"

namespace uvr::cli {

namespace {

using Clock = std::chrono::steady_clock;

std::mutex gStderr;       // one writer at a time: the main thread and a ticker
bool gLineShown = false;  // a progress line without newline is on the terminal

constexpr double kFirstShowSeconds = 1.0;
constexpr double kTerminalInterval = 0.25;
constexpr double kLinesInterval = 5.0;

std::string duration(double s) {
    char buf[32];
    if (s < 120.0)
        std::snprintf(buf, sizeof buf, "%.0f s", s);
    else if (s < 7200.0)
        std::snprintf(buf, sizeof buf, "%.0f min", s / 60.0);
    else
        std::snprintf(buf, sizeof buf, "%.1f h", s / 3600.0);
    return buf;
}

std::string rate(double perSecond, const std::string& unit) {
    char buf[64];
    if (perSecond >= 1e9)
        std::snprintf(buf, sizeof buf, "%.1f G %s/s", perSecond / 1e9, unit.c_str());
    else if (perSecond >= 1e6)
        std::snprintf(buf, sizeof buf, "%.1f M %s/s", perSecond / 1e6, unit.c_str());
    else if (perSecond >= 1e3)
        std::snprintf(buf, sizeof buf, "%.1f k %s/s", perSecond / 1e3, unit.c_str());
    else
        std::snprintf(buf, sizeof buf, "%.0f %s/s", perSecond, unit.c_str());
    return buf;
}

}  // namespace

void printStderrLine(const std::string& text) {
    std::lock_guard lock(gStderr);
    if (gLineShown) {
        std::fputs("\r\x1b[K", stderr);
        gLineShown = false;
    }
    std::fprintf(stderr, "%s\n", text.c_str());
}

std::string Progress::line(const std::string& what, double seconds, double fraction, double total,
                           const std::string& unit) {
    std::string s = what + ": ";
    if (!(fraction > 0.0)) return s + duration(seconds);  // unknown or not started
    fraction = std::min(fraction, 1.0);
    char percent[16];
    std::snprintf(percent, sizeof percent, "%d%%", static_cast<int>(fraction * 100.0));
    s += percent;
    s += " (";
    if (total > 0.0 && !unit.empty() && seconds > 0.0)
        s += rate(fraction * total / seconds, unit) + ", ";
    s += "ETA " + duration(seconds * (1.0 - fraction) / fraction) + ")";
    return s;
}

ProgressStyle Progress::styleFor(bool quiet) {
    if (quiet) return ProgressStyle::Off;
    return ::isatty(STDERR_FILENO) ? ProgressStyle::Terminal : ProgressStyle::Lines;
}

Progress::Progress(const Context& ctx, std::string what, double total, std::string unit)
    : ctx_(ctx),
      what_(std::move(what)),
      unit_(std::move(unit)),
      total_(total),
      style_(styleFor(ctx.quiet || !ctx.root())),
      start_(Clock::now()) {
    if (style_ != ProgressStyle::Off) ticker_ = std::thread([this] { run(); });
}

Progress::~Progress() {
    stop();
}

void Progress::set(double fraction) {
    double seen = fraction_.load(std::memory_order_relaxed);
    while (fraction > seen && !fraction_.compare_exchange_weak(seen, fraction)) {
    }
}

std::function<void(double)> Progress::callback() {
    return [this](double f) { set(f); };
}

void Progress::done(const std::string& message) {
    stop();
    ctx_.done(message, start_);
}

void Progress::stop() {
    {
        std::lock_guard lock(mutex_);
        if (stopping_) return;
        stopping_ = true;
    }
    wake_.notify_all();
    if (ticker_.joinable()) ticker_.join();
    std::lock_guard lock(gStderr);
    if (gLineShown) {
        std::fputs("\r\x1b[K", stderr);
        gLineShown = false;
    }
}

void Progress::run() {
    const double interval = style_ == ProgressStyle::Terminal ? kTerminalInterval : kLinesInterval;
    double next = kFirstShowSeconds;
    std::unique_lock lock(mutex_);
    while (true) {
        const auto due = start_ + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(next));
        if (wake_.wait_until(lock, due, [this] { return stopping_; })) return;
        const double t = std::chrono::duration<double>(Clock::now() - start_).count();
        next = t + interval;
        const std::string text =
            "uvr: " + printable(line(what_, t, fraction_.load(), total_, unit_));
        std::lock_guard out(gStderr);
        if (style_ == ProgressStyle::Terminal) {
            std::fprintf(stderr, "\r%s\x1b[K", text.c_str());
            gLineShown = true;
        } else {
            std::fprintf(stderr, "%s\n", text.c_str());
        }
        std::fflush(stderr);
    }
}

PhaseProgress::PhaseProgress(const Context& ctx, double doneAfterSeconds)
    : ctx_(ctx), doneAfter_(doneAfterSeconds) {}

PhaseProgress::~PhaseProgress() {
    finish();
}

ProgressFn PhaseProgress::callbacks() {
    return {[this](const std::string& name) { step(name); }, [this](double f) { fraction(f); }};
}

void PhaseProgress::step(const std::string& name) {
    std::lock_guard lock(mutex_);
    endPhase();
    ctx_.step(name);
    name_ = name;
    start_ = Clock::now();
    phase_ = std::make_unique<Progress>(ctx_, name);
}

void PhaseProgress::fraction(double f) {
    std::lock_guard lock(mutex_);
    if (phase_) phase_->set(f);
}

void PhaseProgress::finish() {
    std::lock_guard lock(mutex_);
    endPhase();
}

void PhaseProgress::endPhase() {
    if (!phase_) return;
    const double seconds = std::chrono::duration<double>(Clock::now() - start_).count();
    if (seconds >= doneAfter_) phase_->done(name_ + ": done");
    phase_.reset();
}

}  // namespace uvr::cli
