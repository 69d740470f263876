// SPDX-License-Identifier: MIT
#include "uvr/render/render_settings.h"

#include <cmath>
#include <string>

#include "uvr/core/error.h"
#include "uvr/core/setting_error.h"
#include "uvr/core/text.h"
#include "uvr/render/settings_vocabulary.h"

namespace uvr {

float toleranceForQuality(float quality) {
    checkSetting(settingNamed("quality"), quality);  // SettingError out of range
    return kToleranceScale * (1.f - quality);
}

[[noreturn]] void refuseLogRange(bool given, double lo, double hi) {
    const std::string range = "[" + formatG(lo, 6) + ", " + formatG(hi, 6) + "]";
    throwError(ErrorKind::Argument, "",
               "`log` needs positive values: " +
                   (given ? "`range` " + range : "the field's range " + range) +
                   " has none; give `range` LO,HI with 0 < LO <= HI");
}

bool tunesAdaptive(const RenderSettings& s) {
    const RenderSettings d;
    for (const SettingDef& def : settingsVocabulary())
        if (def.tunesAdaptive && def.get(s) != def.get(d)) return true;
    return false;
}

const char* stepRuleName(StepRule rule) {
    return rule == StepRule::Variance ? "variance" : "error";
}

const char* samplingName(bool preintegrated) {
    return preintegrated ? "preintegrated" : "point";
}

void validateSettings(const RenderSettings& s) {
    auto bad = [](const std::string& msg) { throwError(ErrorKind::Argument, "", msg); };
    constexpr int kMaxSide = 16384;
    if (s.width < 1 || s.height < 1 || s.width > kMaxSide || s.height > kMaxSide)
        throw SettingError("size", std::to_string(s.width) + "x" + std::to_string(s.height),
                           "each side must be between 1 and " + std::to_string(kMaxSide));
    // Every setting of the vocabulary within its range (SettingError names it).
    for (const SettingDef& def : settingsVocabulary()) checkSetting(def, def.get(s));
    if (!(s.terminationAlpha > 0.f && s.terminationAlpha <= 1.f))
        bad("early termination threshold must lie in (0, 1]");
    if (s.range && !(std::isfinite(s.range->first) && std::isfinite(s.range->second) &&
                     s.range->first <= s.range->second))
        throw SettingError("range", formatG(s.range->first, 6) + "," + formatG(s.range->second, 6),
                           "expected finite lo <= hi");
    if (s.tfTableSize < 2 || s.tfTableSize > (1 << 20))
        bad("transfer function table size out of range");
    if (s.tf.colors.empty() || s.tf.opacities.empty())
        bad("transfer function needs at least one colour and one opacity point");
    if (s.camera) validateCamera(*s.camera);
    if (s.tf.logScale && s.range && !(s.range->second > 0.f))  // the field's range: at setup
        refuseLogRange(true, s.range->first, s.range->second);
}

}  // namespace uvr
