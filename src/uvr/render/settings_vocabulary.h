// SPDX-License-Identifier: MIT
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <string_view>
#include <vector>

#include "uvr/core/setting_error.h"
#include "uvr/render/frame_setup.h"

namespace uvr {

/// How a setting's value is written.
enum class SettingType {
    Choice,   ///< one name of a list ("adaptive")
    Number,   ///< a finite number within [min, max] (above min when minOpen)
    Integer,  ///< an integer within [min, max]
    Flag,     ///< true or false
};

/// One setting of RenderSettings as every front end names, defaults, documents and checks it
/// (issue 30: "one vocabulary"). Its name is Python's keyword, the viewer's state key and the
/// frame report's key; the CLI's flag is the name with '-' for '_' (cliFlag). The table
/// (settingsVocabulary) defines each once; adding a setting is one entry there and its controls.
struct SettingDef {
    const char* name;
    SettingType type;
    const char* doc;  ///< one line, in neutral words
    /// More of the doc for a command's help and the docs (may be empty), in neutral words:
    /// another setting is named in backticks (`quality`) for each front end to spell.
    const char* detail = "";
    /// Flag on by default: what turning it off does (the CLI's "--no-" flag's help).
    const char* offDoc = "";
    std::vector<std::string> choices;  ///< Choice: every name, the default first
    double min = 0.0, max = 0.0;       ///< Number, Integer: the range
    bool minOpen = false;              ///< Number: the value must lie above min
    /// Number: JSON null (Python's None, the CLI's absent flag) is the default, worked out per
    /// mesh ("default" in docs); an explicit value must then lie in range.
    bool nullDefault = false;
    /// A value other than the default tunes the sampling methods: RenderMethod::Auto then renders
    /// the adaptive method it tunes (tunesAdaptive).
    bool tunesAdaptive = false;
    /// The methods that read the setting (empty: every method); a front end may refuse a value
    /// given for a method that ignores it (settingReadBy).
    std::vector<RenderMethod> readBy;
    /// A Flag setting that must be on for this one to be read (the lighting coefficients need
    /// `shade`), or null; a front end may refuse a value given while it is off (settingNeedMet).
    const char* needs = nullptr;
    /// The setting's value in `s` as JSON (a name, number or boolean; null for a per-mesh
    /// default).
    nlohmann::json (*get)(const RenderSettings& s) = nullptr;
    /// Stores a value checkSetting accepted (JSON null: the default).
    void (*set)(RenderSettings& s, const nlohmann::json& value) = nullptr;
};

/// Every setting of the vocabulary: method, sampling, step_rule, quality, sample_distance,
/// max_sample_distance, power,
/// opacity_unit, opacity_law, skip, adaptive, supersample, jitter, shade, normals, ambient,
/// diffuse, specular, specular_power.
const std::vector<SettingDef>& settingsVocabulary();

/// The setting called `name`, or null.
const SettingDef* findSetting(std::string_view name);

/// The setting called `name`; throws SettingError naming the known ones otherwise.
const SettingDef& settingNamed(std::string_view name);

/// Throws SettingError (an Argument error) when `value` is not a value of `def`: a name of its
/// choices, a finite number in range (an integer for Integer), a boolean; JSON null only where
/// nullDefault. The message names the setting and the value, and says what was expected.
void checkSetting(const SettingDef& def, const nlohmann::json& value);

/// Checks `value` (checkSetting) and stores it into `settings`.
void applySetting(RenderSettings& settings, std::string_view name, const nlohmann::json& value);

/// The default value of `def` (RenderSettings' own).
nlohmann::json settingDefault(const SettingDef& def);

/// The CLI's flag of a setting: "--" and the name with '-' for '_' ("--max-sample-distance"); a
/// flag that is on by default is turned off by "--no-" and its name ("--no-skip").
std::string cliFlag(const SettingDef& def);

/// True when `method` reads the setting (RenderMethod::Auto reads what any method reads).
bool settingReadBy(const SettingDef& def, RenderMethod method);

/// True unless the setting `def.needs` is off in `settings` (then `def` is not read).
bool settingNeedMet(const SettingDef& def, const RenderSettings& settings);

/// Throws SettingError for the first of the settings named in `given` (names of the
/// vocabulary; others are passed over) that `settings` would not read because the setting it
/// needs is off: "ambient 0.3: read only with `shade` on or an `iso` surface or
/// `clip_surface`".
void refuseUnreadSettings(const RenderSettings& settings, const std::vector<std::string>& given);

/// What a value of the setting must be, in words ("a number in [0.5, 0.9999]", "'point' or
/// 'preintegrated'", "true or false"), as checkSetting's errors say it.
std::string settingExpectation(const SettingDef& def);

/// The vocabulary as JSON for a page or a binding: per setting its name, type, doc, detail,
/// default, the methods that read it, the setting it needs and its choices or range.
nlohmann::json settingsVocabularyJson();

/// A value as a message quotes it: a string as 'text', anything else as JSON.
std::string settingValueText(const nlohmann::json& value);

}  // namespace uvr
