// SPDX-License-Identifier: MIT
#include "setting_flags.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace uvr::cli {

namespace {

using Json = nlohmann::json;

/// A number as the command line gave it, or the text itself when it is none (or not finite),
/// for checkSetting to refuse with the text quoted.
Json numberOrText(const SettingDef& def, const std::string& text) {
    if (text.empty()) return Json(text);
    char* end = nullptr;
    errno = 0;
    if (def.type == SettingType::Integer) {
        const long long v = std::strtoll(text.c_str(), &end, 10);
        if (*end == '\0' && errno == 0) return Json(v);
        return Json(text);
    }
    const double v = std::strtod(text.c_str(), &end);
    if (*end == '\0' && std::isfinite(v)) return Json(v);
    return Json(text);
}

/// True for a Flag setting turned off by its flag ("--no-skip").
bool negated(const SettingDef& def) {
    return def.type == SettingType::Flag && settingDefault(def) == true;
}

}  // namespace

std::string spellAsFlags(const std::string& text) {
    return respellMentions(text, [](std::string_view name) {
        if (const SettingDef* def = findSetting(name)) {
            std::string flag = cliFlag(*def);
            if (flag.rfind("--no-", 0) == 0) flag = "--" + flag.substr(5);
            return flag;
        }
        std::string flag = "--" + std::string(name);
        std::replace(flag.begin(), flag.end(), '_', '-');
        return flag;
    });
}

std::string settingHelp(const SettingDef& def) {
    std::string help = negated(def) ? def.offDoc : def.doc;
    if (*def.detail && !negated(def)) help += std::string("; ") + def.detail;
    if (def.type == SettingType::Number || def.type == SettingType::Integer)
        if (!def.nullDefault) help += " (" + settingExpectation(def) + ")";
    return spellAsFlags(help);
}

void SettingFlags::add(CLI::App& app, const SettingDef& def) {
    const std::string flag = cliFlag(def);
    if (def.type == SettingType::Flag) {
        option_[def.name] = app.add_flag(flag, flag_[def.name], settingHelp(def));
        return;
    }
    CLI::Option* o = app.add_option(flag, text_[def.name], settingHelp(def));
    if (def.type == SettingType::Choice) {
        std::string names;
        for (const std::string& c : def.choices) names += (names.empty() ? "" : ",") + c;
        o->type_name("TEXT:{" + names + "}");  // as CLI11 writes a choice
    } else {
        o->type_name(def.type == SettingType::Integer ? "INT" : "NUMBER");
    }
    const Json d = settingDefault(def);
    if (!d.is_null()) o->default_str(d.is_string() ? d.get<std::string>() : settingValueText(d));
    option_[def.name] = o;
}

void SettingFlags::registerOn(CLI::App& app, const std::vector<std::string>& except) {
    for (const SettingDef& def : settingsVocabulary())
        if (std::find(except.begin(), except.end(), def.name) == except.end()) add(app, def);
}

void SettingFlags::registerOnly(CLI::App& app, const std::vector<std::string>& names) {
    for (const std::string& name : names) add(app, settingNamed(name));
}

bool SettingFlags::given(std::string_view name) const {
    if (set_.find(name) != set_.end()) return true;
    const auto o = option_.find(name);
    return o != option_.end() && o->second->count() > 0;
}

std::string SettingFlags::text(std::string_view name) const {
    if (!given(name)) return "";
    if (const auto s = set_.find(name); s != set_.end())
        return s->second.is_string() ? s->second.get<std::string>() : s->second.dump();
    const auto t = text_.find(name);
    return t == text_.end() ? "" : t->second;
}

Json SettingFlags::value(std::string_view name) const {
    const SettingDef& def = settingNamed(name);
    if (const auto s = set_.find(name); s != set_.end()) return s->second;
    if (!given(name)) return settingDefault(def);
    switch (def.type) {
        case SettingType::Flag:
            return !negated(def);
        case SettingType::Choice:
            return text_.find(name)->second;
        case SettingType::Number:
        case SettingType::Integer:
            return numberOrText(def, text_.find(name)->second);
    }
    return settingDefault(def);
}

void SettingFlags::set(std::string_view name, Json value) {
    set_[std::string(settingNamed(name).name)] = std::move(value);
}

void SettingFlags::applyTo(RenderSettings& settings) const {
    for (const SettingDef& def : settingsVocabulary()) {
        if (!given(def.name)) continue;
        const Json v = value(def.name);
        try {
            checkSetting(def, v);
        } catch (const SettingError& e) {
            // The value as typed ("1e-7", not JSON's 1e-07).
            throw SettingError(def.name, text(def.name), e.expected());
        }
        def.set(settings, v);
    }
}

std::vector<const SettingDef*> SettingFlags::ignoredBy(RenderMethod method) const {
    std::vector<const SettingDef*> out;
    for (const SettingDef& def : settingsVocabulary())
        if (given(def.name) && !settingReadBy(def, method)) out.push_back(&def);
    return out;
}

}  // namespace uvr::cli
