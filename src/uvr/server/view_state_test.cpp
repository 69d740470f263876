// SPDX-License-Identifier: MIT
#include "uvr/server/view_state.h"

#include <gmock/gmock.h>

#include "test_support.h"
#include "uvr/core/error.h"

namespace uvr::server {
namespace {

using ::testing::HasSubstr;

ViewState startState() {
    ViewState s;
    s.camera = resetCamera(Bounds3f{Vec3f(0.f), Vec3f(1.f)}, 1.f);
    s.tf = transferFunctionPreset("cool-to-warm");
    s.range = {0.f, 2.f};
    s.field = "density";
    s.settings["opacity_unit"] = 0.5;
    return s;
}

/// The message the error of applying `message` carries; the state must be unchanged.
std::string refusal(const nlohmann::json& message) {
    ViewState s = startState();
    const nlohmann::json before = toJson(s);
    try {
        applySet(s, message);
    } catch (const Error& e) {
        EXPECT_EQ(toJson(s), before) << "state changed by a refused message";
        return e.what();
    }
    ADD_FAILURE() << "accepted " << message.dump();
    return "";
}

TEST(ViewState, EveryKeyAppliesAndTheJsonRoundTrips) {
    ViewState s = startState();
    const nlohmann::json msg = {{"type", "set"},
                                {"seq", 4},
                                {"interactive", true},
                                {"camera",
                                 {{"position", {1, 2, 3}},
                                  {"focal_point", {0, 0, 0}},
                                  {"view_up", {0, 0, 1}},
                                  {"view_angle", 20},
                                  {"parallel", true},
                                  {"parallel_scale", 0.75}}},
                                {"tf",
                                 {{"colors", {{0, 0, 0, 0}, {1, 1, 0.5, 0.25}}},
                                  {"opacity", {{0, 0}, {0.5, 1}, {1, 0}}},
                                  {"log", false},
                                  {"nan_color", {0.5, 0.5, 0.5}},
                                  {"nan_opacity", 0.2},
                                  {"name", "mine"},
                                  {"color_space", "Lab"}}},
                                {"range", {-1, 4}},
                                {"method", "exact"},
                                {"quality", 0.95},
                                {"heatmap", true},
                                {"clip_planes", {{0.5, 0, 0, -2, 0, 0}}},
                                {"size", {320, 200}},
                                {"opacity_unit", 0.25},
                                {"opacity_law", "transmittance"}};
    const SetResult r = applySet(s, msg);
    EXPECT_FALSE(r.fieldChanged);
    EXPECT_TRUE(r.rangeGiven);
    EXPECT_FALSE(r.echoState);
    EXPECT_EQ(s.camera.position, Vec3f(1.f, 2.f, 3.f));
    EXPECT_TRUE(s.camera.parallelProjection);
    EXPECT_FLOAT_EQ(s.camera.parallelScale, 0.75f);
    EXPECT_EQ(s.tf.colorSpace, ColorSpace::Lab);
    ASSERT_EQ(s.tf.opacities.size(), 3u);
    EXPECT_FLOAT_EQ(s.tf.opacityAt(0.25f), 0.5f);
    EXPECT_EQ(s.settings["method"], "exact");
    EXPECT_EQ(s.settings["opacity_law"], "transmittance");
    EXPECT_TRUE(s.heatmap);
    ASSERT_EQ(s.clipPlanes.size(), 1u);
    EXPECT_EQ(s.clipPlanes[0].normal, Vec3f(-2.f, 0.f, 0.f));
    EXPECT_EQ(s.width, 320);
    EXPECT_EQ(s.height, 200);
    // The state's JSON is itself a valid set message that changes nothing.
    ViewState again = startState();
    nlohmann::json asSet = toJson(s);
    applySet(again, asSet);
    EXPECT_EQ(toJson(again), toJson(s));
    // The frame settings carry it, at a reduced size too.
    RenderSettings base;
    base.step = 0.01f;
    const RenderSettings f = frameSettings(s, base, 3);
    EXPECT_EQ(f.width, 106);
    EXPECT_EQ(f.height, 66);
    EXPECT_EQ(f.step, 0.01f);
    EXPECT_EQ(f.method, RenderMethod::Exact);
    ASSERT_TRUE(f.range);
    EXPECT_EQ(f.range->second, 4.f);
    EXPECT_EQ(f.opacityUnit, 0.25f);
    EXPECT_EQ(f.opacityLaw, OpacityLaw::Transmittance);
    ASSERT_EQ(f.clipPlanes.size(), 1u);
    EXPECT_EQ(f.clipPlanes[0].origin, Vec3f(0.5f, 0.f, 0.f));
    // No clip planes: an empty list.
    applySet(s, {{"clip_planes", nlohmann::json::array()}});
    EXPECT_TRUE(s.clipPlanes.empty());
    EXPECT_EQ(toJson(s)["clip_planes"], nlohmann::json::array());
}

TEST(ViewState, FollowingRanksRebuildTheFrameSettingsBitForBit) {
    // A data-parallel viewer's other ranks get each frame's state as its JSON, applied to the
    // starting state (ViewServer::follow): their settings must be rank 0's exactly, or the
    // pieces would be composited from different pictures.
    ViewState s = startState();
    s.camera.position = Vec3f(0.1f + 1e-7f, -2.3456789f, 7.000001f);
    s.camera.viewAngle = 29.999998f;
    s.range = {0.123456789f, 2.000003f};
    s.tf.opacities = {{0.f, 0.f}, {0.3333333f, 0.7777777f}, {1.f, 0.1f}};
    s.tf.colors[1].rgb = Vec3f(0.1f, 0.2f, 0.3f);
    s.clipPlanes = {{Vec3f(0.31415927f, 0.f, 1e-8f), Vec3f(-0.6f, 0.8f, 1e-3f)}};
    s.isoSurfaces = {parseIsoSurface("1.2345679,0.3333333,#80ff01"),
                     parseIsoSurface("0.987654321")};
    s.settings["opacity_unit"] = 0.4258912801742554;
    s.settings["quality"] = 0.97;
    s.step = 0;
    ViewState follower = startState();
    applySet(follower, nlohmann::json::parse(toJson(s).dump()));
    RenderSettings base;
    base.step = 0.0123f;
    const RenderSettings a = frameSettings(s, base, 2), b = frameSettings(follower, base, 2);
    ASSERT_TRUE(a.camera && b.camera && a.range && b.range);
    EXPECT_EQ(a.camera->position, b.camera->position);
    EXPECT_EQ(a.camera->viewAngle, b.camera->viewAngle);
    EXPECT_EQ(*a.range, *b.range);
    ASSERT_EQ(a.tf.opacities.size(), b.tf.opacities.size());
    for (std::size_t i = 0; i < a.tf.opacities.size(); ++i) {
        EXPECT_EQ(a.tf.opacities[i].x, b.tf.opacities[i].x);
        EXPECT_EQ(a.tf.opacities[i].alpha, b.tf.opacities[i].alpha);
    }
    ASSERT_EQ(a.tf.colors.size(), b.tf.colors.size());
    for (std::size_t i = 0; i < a.tf.colors.size(); ++i)
        EXPECT_EQ(a.tf.colors[i].rgb, b.tf.colors[i].rgb);
    ASSERT_EQ(b.clipPlanes.size(), 1u);
    EXPECT_EQ(a.clipPlanes[0].origin, b.clipPlanes[0].origin);
    EXPECT_EQ(a.clipPlanes[0].normal, b.clipPlanes[0].normal);
    ASSERT_EQ(b.isoSurfaces.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(a.isoSurfaces[i].value, b.isoSurfaces[i].value);
        EXPECT_EQ(a.isoSurfaces[i].opacity, b.isoSurfaces[i].opacity);
        EXPECT_EQ(a.isoSurfaces[i].color, b.isoSurfaces[i].color);
    }
    EXPECT_EQ(a.opacityUnit, b.opacityUnit);
    EXPECT_EQ(a.quality, b.quality);
    EXPECT_EQ(a.width, b.width);
}

TEST(ViewState, IsosurfacesAreSetInTheirCommandLineFormAndReachTheFrame) {
    ViewState s = startState();
    EXPECT_EQ(toJson(s)["iso"], nlohmann::json::array());
    applySet(s, {{"iso", {0.5, "1.5,0.25", "2,1,#ff8000"}}});
    ASSERT_EQ(s.isoSurfaces.size(), 3u);
    EXPECT_EQ(s.isoSurfaces[0].value, 0.5f);
    EXPECT_EQ(s.isoSurfaces[1].opacity, 0.25f);
    EXPECT_FALSE(s.isoSurfaces[2].colorMapped);
    EXPECT_EQ(s.isoSurfaces[2].color, Vec3f(1.f, 128.f / 255.f, 0.f));
    // The state writes each as --iso does, and reads that back.
    EXPECT_EQ(toJson(s)["iso"], nlohmann::json({"0.5", "1.5,0.25", "2,1,#ff8000"}));
    ViewState again = startState();
    applySet(again, {{"iso", toJson(s)["iso"]}});
    EXPECT_EQ(toJson(again)["iso"], toJson(s)["iso"]);
    const RenderSettings f = frameSettings(s, RenderSettings{});
    ASSERT_EQ(f.isoSurfaces.size(), 3u);
    EXPECT_EQ(f.isoSurfaces[1].value, 1.5f);
    applySet(s, {{"iso", nlohmann::json::array()}});
    EXPECT_TRUE(frameSettings(s, RenderSettings{}).isoSurfaces.empty());
    // Bad ones are refused naming the entry, with the library's expected form.
    EXPECT_THAT(refusal({{"iso", {0.5, "1,2"}}}),
                HasSubstr("\"iso[1]\": 1,2: expected VALUE[,OPACITY[,#RRGGBB]]"));
    EXPECT_THAT(refusal({{"iso", {"1,0.5,#ff80"}}}), HasSubstr("iso[0]"));
    EXPECT_THAT(refusal({{"iso", {true}}}), HasSubstr("iso[0]"));
    EXPECT_THAT(refusal({{"iso", 0.5}}), HasSubstr("at most 8 isosurfaces"));
    EXPECT_THAT(refusal({{"iso", nlohmann::json::array({1, 2, 3, 4, 5, 6, 7, 8, 9})}}),
                HasSubstr("at most 8 isosurfaces"));
}

TEST(ViewState, AGradientOpacityIsSetInItsCommandLineFormAndReachesTheFrame) {
    ViewState s = startState();
    EXPECT_EQ(toJson(s)["gradient_opacity"], "");
    applySet(s, {{"gradient_opacity", "0:0,0.50:1"}});
    ASSERT_EQ(s.gradientOpacity.count, 2);
    EXPECT_EQ(toJson(s)["gradient_opacity"], "0:0,0.5:1");  // as --gradient-opacity writes it
    RenderSettings f = frameSettings(s, RenderSettings{});
    EXPECT_EQ(gradientOpacityText(f.gradientOpacity), "0:0,0.5:1");
    // The normals it reads may be set with shading off.
    applySet(s, {{"normals", "cell"}});
    EXPECT_FALSE(frameSettings(s, RenderSettings{}).lighting.smooth);
    applySet(s, {{"gradient_opacity", ""}});
    EXPECT_FALSE(frameSettings(s, RenderSettings{}).gradientOpacity.active());
    // Bad ones are refused naming the key, with the library's expected form.
    EXPECT_THAT(refusal({{"gradient_opacity", "1:2"}}),
                HasSubstr("\"gradient_opacity\": 1:2: expected MAGNITUDE:SCALE"));
    EXPECT_THAT(refusal({{"gradient_opacity", "2:1,1:0"}}), HasSubstr("non-decreasing"));
    EXPECT_THAT(refusal({{"gradient_opacity", 0.5}}), HasSubstr("gradient_opacity"));
    EXPECT_THAT(refusal({{"gradient_opacity", std::string(300, '1')}}),
                HasSubstr("gradient_opacity"));
}

TEST(ViewState, PresetsAndUploadedColourMapsReplaceColoursAndAskForTheStateBack) {
    ViewState s = startState();
    applySet(s, {{"tf", {{"opacity", {{0, 0}, {1, 0.3}}}}}});
    SetResult r = applySet(s, {{"preset", "viridis"}});
    EXPECT_TRUE(r.echoState);
    EXPECT_EQ(s.tf.name, "Viridis (matplotlib)");
    EXPECT_FLOAT_EQ(s.tf.opacityAt(1.f), 0.3f);  // the page's opacity stays
    // An uploaded map with Points and a range brings both.
    const std::string json = R"([{"Name": "up", "ColorSpace": "RGB",
        "RGBPoints": [10, 1, 0, 0, 20, 0, 0, 1], "Points": [10, 0, 0.5, 0, 20, 0.8, 0.5, 0]}])";
    r = applySet(s, {{"colormap_json", json}});
    EXPECT_TRUE(r.echoState);
    EXPECT_TRUE(r.rangeGiven);
    EXPECT_EQ(s.tf.name, "up");
    EXPECT_EQ(s.range, std::make_pair(10.f, 20.f));
    EXPECT_FLOAT_EQ(s.tf.opacityAt(1.f), 0.8f);
    // Without Points the opacity stays; a range in the same message wins.
    const std::string noPoints = R"({"Name": "np", "RGBPoints": [0, 0, 0, 0, 1, 1, 1, 1]})";
    applySet(s, {{"colormap_json", noPoints}, {"range", {1, 3}}});
    EXPECT_FLOAT_EQ(s.tf.opacityAt(1.f), 0.8f);
    EXPECT_EQ(s.range, std::make_pair(1.f, 3.f));
}

TEST(ViewState, BadValuesAreRefusedNamingTheKeyAndLeaveTheStateAlone) {
    EXPECT_THAT(refusal({{"camera", {{"position", {0, 0}}}}}), HasSubstr("camera.position"));
    EXPECT_THAT(refusal({{"camera", {{"position", {0, 0, "x"}}}}}),
                HasSubstr("camera.position[2]"));
    EXPECT_THAT(refusal({{"camera", {{"view_up", {0, 0, 1e39}}}}}), HasSubstr("float range"));
    EXPECT_THAT(refusal({{"camera", {{"view_up", {0, 0, -1}}}}}), HasSubstr("parallel"));
    EXPECT_THAT(refusal({{"camera", {{"view_angle", 180}}}}), HasSubstr("camera.view_angle"));
    EXPECT_THAT(refusal({{"camera", {{"zoom", 2}}}}), HasSubstr("zoom"));
    EXPECT_THAT(refusal({{"tf", {{"colors", nlohmann::json::array()}}}}), HasSubstr("tf.colors"));
    EXPECT_THAT(refusal({{"tf", {{"colors", {{0.5, 0, 0, 0}, {0.2, 0, 0, 0}}}}}}),
                HasSubstr("tf.colors[1]"));
    EXPECT_THAT(refusal({{"tf", {{"opacity", {{0, 2}}}}}}), HasSubstr("tf.opacity[0][1]"));
    EXPECT_THAT(refusal({{"tf", {{"color_space", "HSV"}}}}), HasSubstr("tf.color_space"));
    EXPECT_THAT(refusal({{"range", {2, 1}}}), HasSubstr("lo < hi"));
    EXPECT_THAT(refusal({{"range", {0, "1"}}}), HasSubstr("range[1]"));
    EXPECT_THAT(refusal({{"method", "fast"}}), HasSubstr("\"method\""));
    // The vocabulary's check, in the page's spelling of the key.
    EXPECT_EQ(refusal({{"quality", 1.5}}), "\"quality\": 1.5: expected a number in [0.5, 0.9999]");
    EXPECT_THAT(refusal({{"size", {8, 100}}}), HasSubstr("\"size\""));
    EXPECT_THAT(refusal({{"size", {100.5, 100}}}), HasSubstr("\"size\""));
    EXPECT_THAT(refusal({{"opacity_unit", -1}}), HasSubstr("opacity_unit"));
    EXPECT_THAT(refusal({{"opacity_law", "linear"}}), HasSubstr("\"opacity_law\""));
    EXPECT_THAT(refusal({{"opacity_law", 1}}), HasSubstr("\"opacity_law\""));
    EXPECT_THAT(refusal({{"field", "density:sideways"}}), HasSubstr("sideways"));
    EXPECT_THAT(refusal({{"preset", "no-such-map"}}), HasSubstr("no-such-map"));
    EXPECT_THAT(refusal({{"colormap_json", "{not json"}}), HasSubstr("the uploaded colour map"));
    EXPECT_THAT(refusal({{"colormap_name", "x"}}), HasSubstr("colormap_json"));
    EXPECT_THAT(refusal({{"tf", {{"log", true}}}, {"range", {-2, -1}}}),
                HasSubstr("reaching above 0"));
    EXPECT_THAT(refusal({{"camrea", {}}}), HasSubstr("camrea"));
    EXPECT_THAT(refusal(nlohmann::json::array({1, 2})), HasSubstr("object"));
    EXPECT_THAT(refusal({{"clip_planes", {{0, 0, 0, 1, 0}}}}), HasSubstr("clip_planes[0]"));
    EXPECT_THAT(refusal({{"clip_planes", {{0, 0, 0, 0, 0, 0}}}}),
                HasSubstr("\"clip_planes\": 0,0,0,0,0,0: expected a finite origin"));
    EXPECT_THAT(refusal({{"clip_planes",
                          nlohmann::json::array({nlohmann::json::array({0, 0, 0, 1, 0, 0}),
                                                 nlohmann::json::array({0, 0, 0, 1, 0, 0}),
                                                 nlohmann::json::array({0, 0, 0, 1, 0, 0}),
                                                 nlohmann::json::array({0, 0, 0, 1, 0, 0}),
                                                 nlohmann::json::array({0, 0, 0, 1, 0, 0}),
                                                 nlohmann::json::array({0, 0, 0, 1, 0, 0}),
                                                 nlohmann::json::array({0, 0, 0, 1, 0, 0})})}}),
                HasSubstr("at most 6 planes"));
    EXPECT_THAT(refusal({{"clip_planes", "x"}}), HasSubstr("clip_planes"));
    // A good key before a bad one changes nothing either.
    EXPECT_THAT(refusal({{"heatmap", true}, {"quality", 7}}), HasSubstr("quality"));
}

TEST(ViewState, AFieldChangeIsReported) {
    ViewState s = startState();
    EXPECT_FALSE(applySet(s, {{"field", "density"}}).fieldChanged);
    const SetResult r = applySet(s, {{"field", "velocity:x"}});
    EXPECT_TRUE(r.fieldChanged);
    EXPECT_FALSE(r.rangeGiven);
    EXPECT_EQ(s.field, "velocity:x");
}

TEST(ViewState, TheBackgroundIsAColourInTheUnitCube) {
    // Issue 35: what the page shows is what it saves; the background is the state's.
    ViewState s = startState();
    EXPECT_EQ(toJson(s)["background"], nlohmann::json::array({0.f, 0.f, 0.f}));
    applySet(s, {{"background", {0.25, 0.5, 1}}});
    EXPECT_EQ(s.background.x, 0.25f);
    EXPECT_EQ(s.background.z, 1.f);
    EXPECT_EQ(toJson(s)["background"], nlohmann::json::array({0.25f, 0.5f, 1.f}));
    for (const nlohmann::json& bad :
         {nlohmann::json(1), nlohmann::json::array({0, 0}), nlohmann::json::array({0, 0, 2}),
          nlohmann::json::array({0, "x", 0}), nlohmann::json::array({0, -0.1, 0})}) {
        SCOPED_TRACE(bad.dump());
        try {
            applySet(s, {{"background", bad}});
            ADD_FAILURE() << "accepted";
        } catch (const Error& e) {
            EXPECT_THAT(e.what(), ::testing::HasSubstr("\"background\": expected [r, g, b]"));
        }
        EXPECT_EQ(s.background.y, 0.5f);
    }
}

TEST(ViewState, TheStepIsOneOfTheFilesTimeSteps) {
    ViewState s = startState();
    applySet(s, {{"step", 2}}, 3);
    EXPECT_EQ(s.step, 2u);
    EXPECT_EQ(toJson(s)["step"], 2);
    for (const nlohmann::json& bad :
         {nlohmann::json(3), nlohmann::json(-1), nlohmann::json(1.5), nlohmann::json("1")}) {
        SCOPED_TRACE(bad.dump());
        try {
            applySet(s, {{"step", bad}, {"heatmap", true}}, 3);
            ADD_FAILURE() << "accepted";
        } catch (const Error& e) {
            EXPECT_THAT(e.what(),
                        ::testing::HasSubstr("\"step\": expected a time step from 0 to 2"));
        }
        EXPECT_EQ(s.step, 2u);
        EXPECT_FALSE(s.heatmap);  // all or nothing
    }
    ViewState one = startState();
    try {
        applySet(one, {{"step", 1}});
        ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
        EXPECT_THAT(e.what(), ::testing::HasSubstr("no other time step"));
    }
}

TEST(ViewState, AnUploadedColourMapHasAtMostTheStatesPoints) {
    // Issue 28: a 250,000-point map came in through colormap_json (kMaxTfPoints bounded only
    // the page's rows), and every `state` and `export` reply carried it.
    auto upload = [](std::size_t n, const char* space) {
        nlohmann::json rgb = nlohmann::json::array();
        for (std::size_t i = 0; i < n; ++i)
            for (double v : {double(i), 0.5, 0.5, 0.5}) rgb.push_back(v);
        return nlohmann::json{{"Name", "big"}, {"ColorSpace", space}, {"RGBPoints", rgb}}.dump();
    };
    ViewState s = startState();
    applySet(s, {{"colormap_json", upload(kMaxTfPoints, "RGB")}});
    EXPECT_EQ(s.tf.colors.size(), kMaxTfPoints);
    // The state it makes goes back to the page and comes back as rows: accepted again.
    ViewState again = startState();
    EXPECT_NO_THROW(applySet(again, {{"tf", toJson(s)["tf"]}}));
    for (const auto& [n, space] : {std::pair<std::size_t, const char*>{kMaxTfPoints + 1, "RGB"},
                                   {250000, "RGB"},
                                   {200, "HSV"}}) {  // resampled: 32 points a segment
        SCOPED_TRACE(std::to_string(n) + " " + space);
        ViewState t = startState();
        try {
            applySet(t, {{"colormap_json", upload(n, space)}, {"heatmap", true}});
            ADD_FAILURE() << "accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::Argument);
            EXPECT_THAT(e.what(), HasSubstr("at most " + std::to_string(kMaxTfPoints)));
        }
        EXPECT_FALSE(t.heatmap);
    }
}

TEST(ViewState, ErrorsDescribeHugeOrDeepValuesInFewBytes) {
    // Issue 28: the whole value was dumped (recursively) before being cut to 80 bytes.
    nlohmann::json deep = 1;
    for (int i = 0; i < 60; ++i) deep = nlohmann::json::array({deep});
    nlohmann::json wide = nlohmann::json::array();
    for (int i = 0; i < 100000; ++i) wide.push_back(std::string(100, 'x'));
    for (const nlohmann::json& v : {deep, wide, nlohmann::json(std::string(1 << 20, 'y'))}) {
        const std::string m = refusal({{"range", v}});
        EXPECT_THAT(m, HasSubstr("\"range\": expected [lo, hi], got "));
        EXPECT_LT(m.size(), 200u) << m;
    }
    EXPECT_THAT(refusal({{"range", {0, 1, {2, {3, {4, {5, 6}}}}}}}),
                HasSubstr("got [0,1,[2,[3,[4,[...]]]]]"));
    EXPECT_THAT(refusal({{"range", {0, 1, 2}}}), HasSubstr("got [0,1,2]"));
}

}  // namespace
}  // namespace uvr::server
