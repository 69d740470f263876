// SPDX-License-Identifier: MIT
// One piece of host work run on a thread of its own while the caller goes on (reading the next
// time step while the current one renders).
#pragma once

#include <functional>
#include <future>
#include <optional>
#include <utility>

namespace uvr::cpu {

/// The result of a function started on its own thread; take() waits for it and rethrows what it
/// threw. Destroying an unfinished task waits for it (nothing outlives its owner).
template <class T>
class BackgroundTask {
public:
    BackgroundTask() = default;
    /// Starts fn() on a new thread.
    explicit BackgroundTask(std::function<T()> fn)
        : future_(std::async(std::launch::async, std::move(fn))) {}
    BackgroundTask(BackgroundTask&&) noexcept = default;
    BackgroundTask& operator=(BackgroundTask&& other) noexcept {
        wait();
        future_ = std::move(other.future_);
        return *this;
    }
    ~BackgroundTask() { wait(); }

    /// True while a started task's result has not been taken.
    bool pending() const { return future_.valid(); }
    /// Waits for the result and returns it (rethrowing the task's exception); once.
    T take() { return future_.get(); }

private:
    void wait() {
        if (future_.valid()) future_.wait();
    }
    std::future<T> future_;
};

}  // namespace uvr::cpu
