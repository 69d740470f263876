// SPDX-License-Identifier: MIT
#pragma once

#include <functional>
#include <string>
#include <string_view>

#include "uvr/core/error.h"

namespace uvr {

/// Library messages name settings in neutral words: a setting mentioned inside a message is its
/// name in backticks ("narrow it with `range`"), and each front end respells the mentions it
/// knows (respellMentions: the CLI's `--range`, Python's `log_scale` for `log`).

/// An error about one setting's value (an Argument error unless said otherwise), in neutral words:
/// the setting's name (as the settings vocabulary spells it: `quality`, `max_sample_distance`), the
/// value as given and what was expected. what() reads "quality 1.5: expected a number in [0.5,
/// 0.9999]"; a front end says it in its own spelling (spelledAs: the CLI's `--quality 1.5: ...`,
/// Python's `quality=1.5: ...`).
class SettingError : public Error {
public:
    SettingError(std::string setting, std::string value, std::string expected,
                 ErrorKind kind = ErrorKind::Argument);
    const std::string& setting() const { return setting_; }
    const std::string& value() const { return value_; }
    const std::string& expected() const { return expected_; }
    /// The message with the setting named `name` and `separator` before the value: ("--quality",
    /// " ") gives "--quality 1.5: expected ...", ("quality", "=") "quality=1.5: expected ...".
    std::string spelledAs(const std::string& name, const std::string& separator) const;

private:
    std::string setting_, value_, expected_;
};

/// `message` with every mention of a setting ("`name`", name of lower-case letters, digits and
/// '_') replaced by spell(name); spell returns the mention unchanged for a name it does not know.
std::string respellMentions(std::string_view message,
                            const std::function<std::string(std::string_view)>& spell);

}  // namespace uvr
