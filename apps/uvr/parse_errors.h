// SPDX-License-Identifier: MIT
#pragma once

// Command-line parse errors in words a user can act on (issue 15): the unknown subcommand or
// option named, the closest known one suggested, and the --help of the subcommand in use.

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace uvr::cli {

/// The candidate closest to `word` within a few edits (about a third of its length, at least
/// 2), or "" when none is that close.
std::string closest(const std::string& word, const std::vector<std::string>& candidates);

/// The one-line message for a parse error of `app` over the arguments argv[1..argc): an unknown
/// subcommand or option with "did you mean ...?", else CLI11's own message; each ends with the
/// --help to read ("uvr render --help" inside a subcommand).
std::string describeParseError(CLI::App& app, const std::vector<std::string>& args,
                               const CLI::ParseError& error);

}  // namespace uvr::cli
