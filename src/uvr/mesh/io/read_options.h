// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <functional>

#include "uvr/mesh/io/load_budget.h"

namespace uvr {

/// Options every mesh reader takes.
struct ReadOptions {
    /// Upper bound on the bytes one load holds at once, over all its arrays, pieces and file
    /// buffers (0 = no limit), charged before allocating. Readers also refuse counts that the
    /// file's size cannot hold before allocating anything.
    std::uint64_t maxMemoryBytes = 0;
    /// The budget the load charges (shared by the pieces of a .pvtu); when null, the reader makes
    /// one of maxMemoryBytes.
    LoadBudget* budget = nullptr;
    /// Called with the fraction of the file read so far, by readers that know it (.uvrm).
    std::function<void(double)> progress;
};

/// A reader's options with a budget: the caller's, or a new one of maxMemoryBytes.
class BudgetedOptions {
public:
    /// Copies options and points them at a budget.
    explicit BudgetedOptions(const ReadOptions& options)
        : local_(options.maxMemoryBytes), options_(options) {
        if (!options_.budget) options_.budget = &local_;
    }
    BudgetedOptions(const BudgetedOptions&) = delete;
    BudgetedOptions& operator=(const BudgetedOptions&) = delete;

    /// The options, with budget set.
    const ReadOptions& options() const { return options_; }
    /// The budget the load charges.
    LoadBudget& budget() const { return *options_.budget; }

private:
    LoadBudget local_;
    ReadOptions options_;
};

}  // namespace uvr
