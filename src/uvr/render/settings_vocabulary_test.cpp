// SPDX-License-Identifier: MIT
#include "uvr/render/settings_vocabulary.h"

#include <gmock/gmock.h>

#include <cmath>
#include <set>

#include "uvr/core/error.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;

/// A value of d other than its default.
nlohmann::json otherValue(const SettingDef& d) {
    switch (d.type) {
        case SettingType::Choice:
            return d.choices.back();
        case SettingType::Flag:
            return !settingDefault(d).get<bool>();
        case SettingType::Integer:
            return static_cast<int>(d.max);
        case SettingType::Number:
            return std::isfinite(d.max) ? 0.5 * (d.min + d.max) : d.min + 0.25;
    }
    return nullptr;
}

/// The SettingError that applying value to a default RenderSettings throws.
SettingError settingRefusal(const std::string& name, const nlohmann::json& value) {
    RenderSettings s;
    try {
        applySetting(s, name, value);
    } catch (const SettingError& e) {
        return e;
    }
    ADD_FAILURE() << name << " accepted " << value.dump();
    return SettingError("", "", "");
}

TEST(SettingsVocabulary, EachSettingOnceWithItsDefaultFirstAndAccepted) {
    std::set<std::string> names;
    for (const SettingDef& d : settingsVocabulary()) {
        EXPECT_TRUE(names.insert(d.name).second) << d.name;
        EXPECT_NE(std::string(d.doc), "") << d.name;
        EXPECT_EQ(findSetting(d.name), &d);
        EXPECT_NO_THROW(checkSetting(d, settingDefault(d))) << d.name;
        if (d.type == SettingType::Choice) {
            EXPECT_EQ(settingDefault(d), d.choices.front());
        }
    }
    EXPECT_EQ(findSetting("qualty"), nullptr);
    // The library's defaults, as every front end now shows them.
    EXPECT_EQ(settingDefault(settingNamed("method")), "auto");
    EXPECT_FLOAT_EQ(settingDefault(settingNamed("quality")).get<float>(), kDefaultQuality);
    EXPECT_TRUE(settingDefault(settingNamed("sample_distance")).is_null());  // worked out per mesh
    EXPECT_EQ(cliFlag(settingNamed("max_sample_distance")), "--max-sample-distance");
    EXPECT_EQ(cliFlag(settingNamed("skip")), "--no-skip");
    EXPECT_EQ(cliFlag(settingNamed("jitter")), "--jitter");
}

TEST(SettingsVocabulary, AValueStoredIsTheValueReadBack) {
    for (const SettingDef& d : settingsVocabulary()) {
        RenderSettings s;
        const nlohmann::json v = otherValue(d);
        applySetting(s, d.name, v);
        if (v.is_number_float())
            EXPECT_FLOAT_EQ(d.get(s).get<float>(), v.get<float>()) << d.name;
        else
            EXPECT_EQ(d.get(s), v) << d.name;
        EXPECT_NE(d.get(s), settingDefault(d)) << d.name;
    }
    RenderSettings s;
    applySetting(s, "sample_distance", 0.5);
    applySetting(s, "sample_distance", nullptr);  // back to the per-mesh default
    EXPECT_EQ(s.step, 0.f);
}

TEST(SettingsVocabulary, TunesAdaptiveIsWhatTheTableSays) {
    EXPECT_FALSE(tunesAdaptive(RenderSettings{}));
    for (const SettingDef& d : settingsVocabulary()) {
        RenderSettings s;
        applySetting(s, d.name, otherValue(d));
        EXPECT_EQ(tunesAdaptive(s), d.tunesAdaptive) << d.name;
    }
    RenderSettings s;
    s.quality = kDefaultQuality;  // the default given explicitly tunes nothing
    EXPECT_FALSE(tunesAdaptive(s));
}

TEST(SettingsVocabulary, BadValuesNameTheSettingTheValueAndWhatWasExpected) {
    EXPECT_STREQ(settingRefusal("quality", 1.5).what(),
                 "quality 1.5: expected a number in [0.5, 0.9999]");
    EXPECT_STREQ(settingRefusal("method", "fast").what(),
                 "method 'fast': expected 'auto', 'adaptive', 'reference' or 'exact'");
    EXPECT_STREQ(settingRefusal("sample_distance", 0).what(),
                 "sample_distance 0: expected a positive finite number");
    EXPECT_STREQ(settingRefusal("sample_distance", -1).what(),
                 "sample_distance -1: expected a positive finite number");
    EXPECT_STREQ(settingRefusal("supersample", 9).what(),
                 "supersample 9: expected an integer in [1, 8]");
    EXPECT_STREQ(settingRefusal("supersample", 2.5).what(),
                 "supersample 2.5: expected an integer in [1, 8]");
    EXPECT_STREQ(settingRefusal("skip", "yes").what(), "skip 'yes': expected true or false");
    EXPECT_STREQ(settingRefusal("power", nullptr).what(),
                 "power null: expected a number in [1, 64]");
    EXPECT_THAT(settingRefusal("opacity_law", 3).what(),
                HasSubstr("expected 'attenuation' or 'transmittance'"));
    EXPECT_THAT(settingRefusal("max_sample_distance", 1e39).what(),
                HasSubstr("expected a positive finite number"));
    const SettingError unknown = settingRefusal("qualty", 0.9);
    EXPECT_EQ(unknown.setting(), "setting");
    EXPECT_THAT(unknown.what(), HasSubstr("'qualty': not a setting; the settings are 'method'"));
    EXPECT_EQ(unknown.kind(), ErrorKind::Argument);
    // Each front end in its own spelling.
    const SettingError e = settingRefusal("max_sample_distance", -2);
    EXPECT_EQ(e.spelledAs(cliFlag(settingNamed(e.setting())), " "),
              "--max-sample-distance -2: expected a positive finite number");
    EXPECT_EQ(e.spelledAs(e.setting(), "="),
              "max_sample_distance=-2: expected a positive finite number");
}

TEST(SettingsVocabulary, ValidateSettingsChecksEverySettingOfTheTable) {
    RenderSettings s;
    s.tf = transferFunctionPreset("viridis");
    s.supersample = 9;
    try {
        validateSettings(s);
        FAIL() << "supersample 9 passed";
    } catch (const SettingError& e) {
        EXPECT_EQ(e.setting(), "supersample");
    }
    s.supersample = 1;
    s.opacityUnit = NAN;
    EXPECT_THROW(validateSettings(s), SettingError);
    s.opacityUnit = 0.f;
    EXPECT_NO_THROW(validateSettings(s));
}

TEST(SettingsVocabulary, TheJsonFormListsEverySettingWithItsDefaultAndRange) {
    const nlohmann::json j = settingsVocabularyJson();
    ASSERT_EQ(j.size(), settingsVocabulary().size());
    for (const nlohmann::json& d : j) {
        const SettingDef& def = settingNamed(d["name"].get<std::string>());
        EXPECT_EQ(d["default"], settingDefault(def));
        EXPECT_EQ(d["tunes_adaptive"], def.tunesAdaptive);
    }
    EXPECT_EQ(j[0]["name"], "method");
    EXPECT_EQ(j[0]["choices"][0], "auto");
    const SettingDef& q = settingNamed("quality");
    const nlohmann::json* quality = nullptr;
    for (const nlohmann::json& d : j)
        if (d["name"] == "quality") quality = &d;
    ASSERT_NE(quality, nullptr);
    EXPECT_EQ((*quality)["min"], q.min);
    EXPECT_EQ((*quality)["max"], q.max);
    EXPECT_EQ((*quality)["read_by"], nlohmann::json::array({"adaptive"}));
    // A float default is written as it reads (0.99, not the float's 0.9900000095367432).
    EXPECT_EQ((*quality)["default"].dump(), "0.99");
}

TEST(SettingsVocabulary, SaysWhichMethodsReadEachSetting) {
    // Auto reads what any method reads; a setting with no list is read by every method.
    for (const SettingDef& d : settingsVocabulary()) {
        EXPECT_TRUE(settingReadBy(d, RenderMethod::Auto)) << d.name;
        for (RenderMethod m : d.readBy) EXPECT_NE(m, RenderMethod::Auto) << d.name;
    }
    EXPECT_FALSE(settingReadBy(settingNamed("quality"), RenderMethod::Reference));
    EXPECT_TRUE(settingReadBy(settingNamed("quality"), RenderMethod::Partitions));
    EXPECT_FALSE(settingReadBy(settingNamed("sampling"), RenderMethod::Exact));
    EXPECT_TRUE(settingReadBy(settingNamed("sampling"), RenderMethod::Reference));
    EXPECT_TRUE(settingReadBy(settingNamed("opacity_law"), RenderMethod::Exact));
    EXPECT_EQ(settingExpectation(settingNamed("supersample")), "an integer in [1, 8]");
    EXPECT_EQ(settingExpectation(settingNamed("skip")), "true or false");
}

TEST(SettingsVocabulary, LightingCoefficientsNeedShadeOn) {
    // Shading is off by default with ParaView's coefficients; each coefficient is read only
    // with `shade` on, and a front end that was given one with shading off is told so.
    EXPECT_EQ(settingDefault(settingNamed("shade")), false);
    EXPECT_EQ(cliFlag(settingNamed("shade")), "--shade");
    EXPECT_EQ(cliFlag(settingNamed("specular_power")), "--specular-power");
    EXPECT_EQ(settingDefault(settingNamed("diffuse")).dump(), "1.0");
    EXPECT_EQ(settingDefault(settingNamed("specular_power")).dump(), "100.0");
    RenderSettings s;
    for (const char* name : {"ambient", "diffuse", "specular", "specular_power"}) {
        const SettingDef& d = settingNamed(name);
        ASSERT_NE(d.needs, nullptr) << name;
        EXPECT_STREQ(d.needs, "shade");
        EXPECT_FALSE(settingNeedMet(d, s)) << name;
    }
    EXPECT_TRUE(settingNeedMet(settingNamed("quality"), s));
    applySetting(s, "ambient", 0.25);
    try {
        refuseUnreadSettings(s, {"quality", "ambient"});
        FAIL() << "ambient without shade passed";
    } catch (const SettingError& e) {
        EXPECT_EQ(std::string(e.what()),
                  "ambient 0.25: read only with `shade` on or an `iso` surface or "
                  "`clip_surface`");
    }
    // The cut face lights with them too, and needs something cut.
    applySetting(s, "clip_surface", true);
    try {
        refuseUnreadSettings(s, {"clip_surface", "ambient"});
        FAIL() << "clip_surface without a clip passed";
    } catch (const SettingError& e) {
        EXPECT_EQ(std::string(e.what()),
                  "clip_surface true: read only with clip planes or a clip box: there is no cut "
                  "face");
    }
    s.clipPlanes = {{Vec3f(0.f, 0.f, 0.f), Vec3f(1.f, 0.f, 0.f)}};
    EXPECT_NO_THROW(refuseUnreadSettings(s, {"clip_surface", "ambient"}));
    s.clipPlanes.clear();
    applySetting(s, "clip_surface", false);
    applySetting(s, "shade", true);
    EXPECT_NO_THROW(refuseUnreadSettings(s, {"quality", "ambient", "not_a_setting"}));
    EXPECT_EQ(s.lighting.ambient, 0.25f);
    EXPECT_TRUE(s.lighting.on);
    // Out of range.
    EXPECT_THAT(settingRefusal("diffuse", 1.5).what(), HasSubstr("expected a number in [0, 1]"));
    EXPECT_THAT(settingRefusal("specular_power", -1).what(), HasSubstr("[0, 128]"));
    // The JSON form says what each needs.
    for (const nlohmann::json& d : settingsVocabularyJson()) {
        if (d["name"] == "ambient") {
            EXPECT_EQ(d["needs"], "shade");
        }
    }
}

}  // namespace
}  // namespace uvr
