// SPDX-License-Identifier: MIT
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "uvr/prepare/prepared_mesh.h"

namespace uvr::cli {

class Context;

/// Writes one line to stderr (a newline is added), first clearing a progress line a terminal
/// shows; every message of the CLI goes through it so lines never mix.
void printStderrLine(const std::string& text);

/// How a progress line is shown: redrawn in place on a terminal, a plain line now and then
/// otherwise (logs, pipes), nothing with --quiet.
enum class ProgressStyle { Terminal, Lines, Off };

/// The one progress reporter of every long phase (reading, generating, refining, rendering,
/// writing). Nothing is shown for a phase shorter than about a second; after that a line
/// "uvr: refining: 42% (3.1 M tetrahedra/s, ETA 8 s)" - or "uvr: reading x.vtk: 12 s" when the
/// phase cannot say how far it is - is redrawn four times a second on a terminal, or printed
/// every 5 seconds when stderr is not one. A ticker thread keeps the line alive while the work
/// reports nothing. done() ends the phase with one line and its time.
class Progress {
public:
    /// A phase named `what`; `total` units of `unit` (e.g. tetrahedra) make the rate, 0 for none.
    Progress(const Context& ctx, std::string what, double total = 0.0, std::string unit = "");
    /// Stops the ticker and clears the line (no message).
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    /// The fraction done, in [0, 1] (thread-safe; decreasing values are ignored).
    void set(double fraction);
    /// A callback for the library's progress(fraction) parameters; valid while this lives.
    std::function<void(double)> callback();
    /// Ends the phase: "uvr: MESSAGE (1.23 s)" (not with --quiet).
    void done(const std::string& message);

    /// The line shown after `seconds` at `fraction` (negative: unknown), for tests.
    static std::string line(const std::string& what, double seconds, double fraction, double total,
                            const std::string& unit);
    /// The style for stderr: Off when quiet, Terminal when stderr is a terminal, else Lines.
    static ProgressStyle styleFor(bool quiet);

private:
    void run();
    void stop();

    const Context& ctx_;
    std::string what_, unit_;
    double total_;
    ProgressStyle style_;
    std::chrono::steady_clock::time_point start_;
    std::atomic<double> fraction_{-1.0};
    std::mutex mutex_;
    std::condition_variable wake_;
    bool stopping_ = false;
    bool shown_ = false;  ///< a terminal line is on screen
    std::thread ticker_;
};

/// Shows the phases of a preparation (prepareMesh's ProgressFn) as Progress lines: each step
/// prints its name at once ("uvr: finding face neighbours"), as before, and runs a Progress of
/// that name that its fractions move ("uvr: finding face neighbours: 42% (ETA 8 s)", after a
/// second); the next step, finish() or the destructor end it, with a line and its time
/// ("uvr: finding face neighbours: done (2.31 s)") only when it lasted doneAfterSeconds or
/// more, so a small mesh's log does not double.
class PhaseProgress {
public:
    /// Reports through ctx (nothing with --quiet).
    explicit PhaseProgress(const Context& ctx, double doneAfterSeconds = 1.0);
    /// finish().
    ~PhaseProgress();
    PhaseProgress(const PhaseProgress&) = delete;
    PhaseProgress& operator=(const PhaseProgress&) = delete;

    /// The callbacks for prepareMesh, Renderer and the like; valid while this lives.
    ProgressFn callbacks();
    /// Ends the phase running and starts one named `name`.
    void step(const std::string& name);
    /// How far the phase running has come, in [0, 1] (thread-safe; ignored between phases).
    void fraction(double f);
    /// Ends the phase running, if any.
    void finish();

private:
    void endPhase();  // with mutex_ held

    const Context& ctx_;
    double doneAfter_;
    std::mutex mutex_;
    std::unique_ptr<Progress> phase_;
    std::string name_;
    std::chrono::steady_clock::time_point start_;
};

}  // namespace uvr::cli
