// SPDX-License-Identifier: MIT
#include "uvr/core/setting_error.h"

#include <utility>

namespace uvr {

SettingError::SettingError(std::string setting, std::string value, std::string expected)
    : Error(ErrorKind::Argument, setting + " " + value + ": " + expected),
      setting_(std::move(setting)),
      value_(std::move(value)),
      expected_(std::move(expected)) {}

std::string SettingError::spelledAs(const std::string& name, const std::string& separator) const {
    return name + separator + value_ + ": " + expected_;
}

}  // namespace uvr
