// SPDX-License-Identifier: MIT
#include "uvr/core/setting_error.h"

#include <utility>

namespace uvr {

SettingError::SettingError(std::string setting, std::string value, std::string expected,
                           ErrorKind kind)
    : Error(kind, (value.empty() ? setting : setting + " " + value) + ": " + expected),
      setting_(std::move(setting)),
      value_(std::move(value)),
      expected_(std::move(expected)) {}

std::string SettingError::spelledAs(const std::string& name, const std::string& separator) const {
    // A flag given bare ("--clip-surface") has no value to quote.
    return value_.empty() ? name + ": " + expected_ : name + separator + value_ + ": " + expected_;
}

std::string respellMentions(std::string_view message,
                            const std::function<std::string(std::string_view)>& spell) {
    const auto isNameChar = [](char c) {
        return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
    };
    std::string out;
    out.reserve(message.size());
    std::size_t i = 0;
    while (i < message.size()) {
        const std::size_t open = message.find('`', i);
        if (open == std::string_view::npos) break;
        std::size_t end = open + 1;
        while (end < message.size() && isNameChar(message[end])) ++end;
        out.append(message.substr(i, open - i));
        if (end < message.size() && message[end] == '`' && end > open + 1) {
            out += spell(message.substr(open + 1, end - open - 1));
            i = end + 1;
        } else {
            out += '`';
            i = open + 1;
        }
    }
    out.append(message.substr(i));
    return out;
}

}  // namespace uvr
