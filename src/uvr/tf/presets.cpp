// SPDX-License-Identifier: MIT
#include <algorithm>
#include <cctype>

#include "uvr/core/error.h"
#include "uvr/tf/transfer_function.h"

namespace uvr {

namespace {

/// One entry of a 256-entry colour table: its index and sRGB colour.
struct TableSample {
    int index;
    float r, g, b;
};

// matplotlib's viridis (Smith & van der Walt, CC0): every 5th entry of the official 256-entry
// table at its own position index / 255; linear interpolation stays within 0.72 / 255 of the rest.
constexpr TableSample kViridis[] = {
    {0, 0.267004f, 0.004874f, 0.329415f},   {5, 0.273809f, 0.031497f, 0.358853f},
    {10, 0.278791f, 0.062145f, 0.386592f},  {15, 0.281924f, 0.089666f, 0.412415f},
    {20, 0.283197f, 0.115680f, 0.436115f},  {25, 0.282623f, 0.140926f, 0.457517f},
    {30, 0.280255f, 0.165693f, 0.476498f},  {35, 0.276194f, 0.190074f, 0.493001f},
    {40, 0.270595f, 0.214069f, 0.507052f},  {45, 0.263663f, 0.237631f, 0.518762f},
    {50, 0.255645f, 0.260703f, 0.528312f},  {55, 0.246811f, 0.283237f, 0.535941f},
    {60, 0.237441f, 0.305202f, 0.541921f},  {65, 0.227802f, 0.326594f, 0.546532f},
    {70, 0.218130f, 0.347432f, 0.550038f},  {75, 0.208623f, 0.367752f, 0.552675f},
    {80, 0.199430f, 0.387607f, 0.554642f},  {85, 0.190631f, 0.407061f, 0.556089f},
    {90, 0.182256f, 0.426184f, 0.557120f},  {95, 0.174274f, 0.445044f, 0.557792f},
    {100, 0.166617f, 0.463708f, 0.558119f}, {105, 0.159194f, 0.482237f, 0.558073f},
    {110, 0.151918f, 0.500685f, 0.557587f}, {115, 0.144759f, 0.519093f, 0.556572f},
    {120, 0.137770f, 0.537492f, 0.554906f}, {125, 0.131172f, 0.555899f, 0.552459f},
    {130, 0.125394f, 0.574318f, 0.549086f}, {135, 0.121148f, 0.592739f, 0.544641f},
    {140, 0.119423f, 0.611141f, 0.538982f}, {145, 0.121380f, 0.629492f, 0.531973f},
    {150, 0.128087f, 0.647749f, 0.523491f}, {155, 0.140210f, 0.665859f, 0.513427f},
    {160, 0.157851f, 0.683765f, 0.501686f}, {165, 0.180653f, 0.701402f, 0.488189f},
    {170, 0.208030f, 0.718701f, 0.472873f}, {175, 0.239374f, 0.735588f, 0.455688f},
    {180, 0.274149f, 0.751988f, 0.436601f}, {185, 0.311925f, 0.767822f, 0.415586f},
    {190, 0.352360f, 0.783011f, 0.392636f}, {195, 0.395174f, 0.797475f, 0.367757f},
    {200, 0.440137f, 0.811138f, 0.340967f}, {205, 0.487026f, 0.823929f, 0.312321f},
    {210, 0.535621f, 0.835785f, 0.281908f}, {215, 0.585678f, 0.846661f, 0.249897f},
    {220, 0.636902f, 0.856542f, 0.216620f}, {225, 0.688944f, 0.865448f, 0.182725f},
    {230, 0.741388f, 0.873449f, 0.149561f}, {235, 0.793760f, 0.880678f, 0.120005f},
    {240, 0.845561f, 0.887322f, 0.099702f}, {245, 0.896320f, 0.893616f, 0.096335f},
    {250, 0.945636f, 0.899815f, 0.112838f}, {255, 0.993248f, 0.906157f, 0.143936f},
};

// matplotlib's inferno (Smith & van der Walt, CC0), sampled like kViridis.
constexpr TableSample kInferno[] = {
    {0, 0.001462f, 0.000466f, 0.013866f},   {5, 0.007676f, 0.006136f, 0.046836f},
    {10, 0.019373f, 0.015133f, 0.088767f},  {15, 0.037668f, 0.025921f, 0.132232f},
    {20, 0.061340f, 0.036590f, 0.177642f},  {25, 0.087411f, 0.044556f, 0.224813f},
    {30, 0.116656f, 0.047574f, 0.272321f},  {35, 0.149073f, 0.045468f, 0.317085f},
    {40, 0.183429f, 0.040329f, 0.354971f},  {45, 0.217949f, 0.036615f, 0.383522f},
    {50, 0.251620f, 0.037705f, 0.403378f},  {55, 0.284321f, 0.043933f, 0.416608f},
    {60, 0.316282f, 0.053490f, 0.425116f},  {65, 0.347771f, 0.064616f, 0.430217f},
    {70, 0.379001f, 0.076253f, 0.432719f},  {75, 0.410113f, 0.087896f, 0.433098f},
    {80, 0.441207f, 0.099338f, 0.431594f},  {85, 0.472328f, 0.110547f, 0.428334f},
    {90, 0.503493f, 0.121575f, 0.423356f},  {95, 0.534683f, 0.132534f, 0.416667f},
    {100, 0.565854f, 0.143567f, 0.408258f}, {105, 0.596940f, 0.154848f, 0.398125f},
    {110, 0.627847f, 0.166575f, 0.386276f}, {115, 0.658463f, 0.178962f, 0.372748f},
    {120, 0.688653f, 0.192239f, 0.357603f}, {125, 0.718264f, 0.206636f, 0.340931f},
    {130, 0.747127f, 0.222378f, 0.322856f}, {135, 0.775059f, 0.239667f, 0.303526f},
    {140, 0.801871f, 0.258674f, 0.283099f}, {145, 0.827372f, 0.279517f, 0.261750f},
    {150, 0.851384f, 0.302260f, 0.239636f}, {155, 0.873741f, 0.326906f, 0.216886f},
    {160, 0.894305f, 0.353399f, 0.193584f}, {165, 0.912966f, 0.381636f, 0.169755f},
    {170, 0.929644f, 0.411479f, 0.145367f}, {175, 0.944285f, 0.442772f, 0.120354f},
    {180, 0.956852f, 0.475356f, 0.094695f}, {185, 0.967322f, 0.509078f, 0.068659f},
    {190, 0.975677f, 0.543798f, 0.043618f}, {195, 0.981895f, 0.579392f, 0.026250f},
    {200, 0.985952f, 0.615750f, 0.025592f}, {205, 0.987819f, 0.652773f, 0.045581f},
    {210, 0.987464f, 0.690366f, 0.079990f}, {215, 0.984865f, 0.728427f, 0.120785f},
    {220, 0.980032f, 0.766837f, 0.166353f}, {225, 0.973088f, 0.805409f, 0.216877f},
    {230, 0.964394f, 0.843848f, 0.273391f}, {235, 0.954997f, 0.881569f, 0.337475f},
    {240, 0.947594f, 0.917399f, 0.410665f}, {245, 0.947937f, 0.949318f, 0.491426f},
    {250, 0.961812f, 0.975924f, 0.571925f}, {255, 0.988362f, 0.998364f, 0.644924f},
};

template <size_t N>
std::vector<ColorPoint> fromTable(const TableSample (&table)[N]) {
    std::vector<ColorPoint> points;
    for (const TableSample& s : table)
        points.push_back({static_cast<float>(s.index) / 255.f, Vec3f(s.r, s.g, s.b)});
    return points;
}

/// Lower case without spaces, '-', '_' and a trailing parenthesised suffix.
std::string canonicalName(const std::string& name) {
    std::string s = name;
    size_t paren = s.find('(');
    if (paren != std::string::npos && s.back() == ')') s.erase(paren);
    std::string out;
    for (char c : s) {
        if (c == ' ' || c == '-' || c == '_' || c == '\t') continue;
        out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    return out;
}

TransferFunction makePreset(const std::string& name, ColorSpace space,
                            std::vector<ColorPoint> colors) {
    TransferFunction tf;
    tf.name = name;
    tf.colorSpace = space;
    tf.colors = std::move(colors);
    tf.opacities = {{0.f, 0.f}, {1.f, 1.f}};
    return tf;
}

}  // namespace

std::vector<std::string> transferFunctionPresetNames() {
    return {"cool-to-warm", "viridis", "inferno", "black-body", "grayscale"};
}

TransferFunction transferFunctionPreset(const std::string& name) {
    std::string key = canonicalName(name);
    if (key == "cooltowarm") {
        // ParaView's "Cool to Warm" (Moreland 2009), interpolated in Msh.
        return makePreset("cool-to-warm", ColorSpace::Diverging,
                          {{0.f, {0.23137254902f, 0.298039215686f, 0.752941176471f}},
                           {0.5f, {0.865f, 0.865f, 0.865f}},
                           {1.f, {0.705882352941f, 0.0156862745098f, 0.149019607843f}}});
    }
    if (key == "viridis") return makePreset("viridis", ColorSpace::RGB, fromTable(kViridis));
    if (key == "inferno") return makePreset("inferno", ColorSpace::RGB, fromTable(kInferno));
    if (key == "blackbody" || key == "blackbodyradiation") {
        // ParaView's "Black-Body Radiation" (ColorMaps.json).
        return makePreset("black-body", ColorSpace::RGB,
                          {{0.f, {0.f, 0.f, 0.f}},
                           {0.4f, {0.901960784314f, 0.f, 0.f}},
                           {0.8f, {0.901960784314f, 0.901960784314f, 0.f}},
                           {1.f, {1.f, 1.f, 1.f}}});
    }
    if (key == "grayscale" || key == "greyscale" || key == "gray" || key == "grey") {
        return makePreset("grayscale", ColorSpace::RGB,
                          {{0.f, {0.f, 0.f, 0.f}}, {1.f, {1.f, 1.f, 1.f}}});
    }
    std::string names;
    for (const std::string& n : transferFunctionPresetNames())
        names += (names.empty() ? "" : ", ") + n;
    throwError(ErrorKind::Argument, "",
               "unknown transfer function preset \"" + name + "\"; expected one of: " + names +
                   " (or a ParaView colour-map .json file)");
}

}  // namespace uvr
