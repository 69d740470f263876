// SPDX-License-Identifier: MIT
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "uvr/uvr.h"

namespace uvr::cli {

/// The library's settings vocabulary (settingsVocabulary) as flags: one option per setting,
/// spelled as cliFlag ("--max-sample-distance", "--no-skip"), its help the setting's doc, its value
/// parsed by the setting's type and checked by the library (applySetting), so that a setting added
/// to the vocabulary is a flag of every command that registers these.
class SettingFlags {
public:
    SettingFlags() = default;
    SettingFlags(const SettingFlags&) = delete;  // the options point into this object
    SettingFlags& operator=(const SettingFlags&) = delete;

    /// Adds the flag of every setting but those named in `except` to a subcommand.
    void registerOn(CLI::App& app, const std::vector<std::string>& except = {});
    /// Adds the flags of the settings named in `names` only.
    void registerOnly(CLI::App& app, const std::vector<std::string>& names);
    /// True when the setting's flag was given (or set).
    bool given(std::string_view name) const;
    /// The value given, as the vocabulary writes it (a number, name or boolean; a text that is
    /// no number stays text, for the check to refuse), else the setting's default.
    nlohmann::json value(std::string_view name) const;
    /// The value as given on the command line ("0.5", "point"; "" for a flag); "" when not given.
    std::string text(std::string_view name) const;
    /// Sets a value as if given (a command's own choice, e.g. bench's method).
    void set(std::string_view name, nlohmann::json value);
    /// Stores every given value into `settings`; a value the setting refuses throws SettingError
    /// quoting it as given ("--sample-distance 0: expected a positive finite number").
    void applyTo(RenderSettings& settings) const;
    /// The settings given whose values `method` does not read (settingReadBy).
    std::vector<const SettingDef*> ignoredBy(RenderMethod method) const;

private:
    void add(CLI::App& app, const SettingDef& def);
    std::map<std::string, std::string, std::less<>> text_;
    std::map<std::string, bool, std::less<>> flag_;
    std::map<std::string, const CLI::Option*, std::less<>> option_;
    std::map<std::string, nlohmann::json, std::less<>> set_;
};

/// A setting's help for a command line: its doc (offDoc for a "--no-" flag) and detail with the
/// settings they mention spelled as flags, and its default.
std::string settingHelp(const SettingDef& def);

/// `text` with each setting it mentions ("`quality`") spelled as its flag ("--quality").
std::string spellAsFlags(const std::string& text);

}  // namespace uvr::cli
