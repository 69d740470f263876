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

// matplotlib's viridis (Smith & van der Walt, CC0): every ~8th entry of the official 256-entry
// table, at its own position index / 255.
constexpr TableSample kViridis[] = {
    {0, 0.267004f, 0.004874f, 0.329415f},   {8, 0.277018f, 0.050344f, 0.375715f},
    {16, 0.282327f, 0.094955f, 0.417331f},  {25, 0.282623f, 0.140926f, 0.457517f},
    {33, 0.278012f, 0.180367f, 0.486697f},  {41, 0.269308f, 0.218818f, 0.509577f},
    {49, 0.257322f, 0.256130f, 0.526563f},  {58, 0.241237f, 0.296485f, 0.539709f},
    {66, 0.225863f, 0.330805f, 0.547314f},  {74, 0.210503f, 0.363727f, 0.552206f},
    {82, 0.195860f, 0.395433f, 0.555276f},  {90, 0.182256f, 0.426184f, 0.557120f},
    {99, 0.168126f, 0.459988f, 0.558082f},  {107, 0.156270f, 0.489624f, 0.557936f},
    {115, 0.144759f, 0.519093f, 0.556572f}, {123, 0.133743f, 0.548535f, 0.553541f},
    {132, 0.123463f, 0.581687f, 0.547445f}, {140, 0.119423f, 0.611141f, 0.538982f},
    {148, 0.124780f, 0.640461f, 0.527068f}, {156, 0.143303f, 0.669459f, 0.511215f},
    {165, 0.180653f, 0.701402f, 0.488189f}, {173, 0.226397f, 0.728888f, 0.462789f},
    {181, 0.281477f, 0.755203f, 0.432552f}, {189, 0.344074f, 0.780029f, 0.397381f},
    {197, 0.412913f, 0.803041f, 0.357269f}, {206, 0.496615f, 0.826376f, 0.306377f},
    {214, 0.575563f, 0.844566f, 0.256415f}, {222, 0.657642f, 0.860219f, 0.203082f},
    {230, 0.741388f, 0.873449f, 0.149561f}, {239, 0.835270f, 0.886029f, 0.102646f},
    {247, 0.916242f, 0.896091f, 0.100717f}, {255, 0.993248f, 0.906157f, 0.143936f},
};

// matplotlib's inferno (Smith & van der Walt, CC0), sampled like kViridis.
constexpr TableSample kInferno[] = {
    {0, 0.001462f, 0.000466f, 0.013866f},   {8, 0.013995f, 0.011225f, 0.071862f},
    {16, 0.042253f, 0.028139f, 0.141141f},  {25, 0.087411f, 0.044556f, 0.224813f},
    {33, 0.135778f, 0.046856f, 0.299776f},  {41, 0.190367f, 0.039309f, 0.361447f},
    {49, 0.244967f, 0.037055f, 0.400007f},  {58, 0.303568f, 0.049396f, 0.422182f},
    {66, 0.354032f, 0.066925f, 0.430906f},  {74, 0.403894f, 0.085580f, 0.433179f},
    {82, 0.453651f, 0.103848f, 0.430498f},  {90, 0.503493f, 0.121575f, 0.423356f},
    {99, 0.559624f, 0.141346f, 0.410078f},  {107, 0.609330f, 0.159474f, 0.393589f},
    {115, 0.658463f, 0.178962f, 0.372748f}, {123, 0.706500f, 0.200728f, 0.347777f},
    {132, 0.758422f, 0.229097f, 0.315266f}, {140, 0.801871f, 0.258674f, 0.283099f},
    {148, 0.841969f, 0.292933f, 0.248564f}, {156, 0.878001f, 0.332060f, 0.212268f},
    {165, 0.912966f, 0.381636f, 0.169755f}, {173, 0.938675f, 0.430091f, 0.130438f},
    {181, 0.959114f, 0.482014f, 0.089499f}, {189, 0.974176f, 0.536780f, 0.048392f},
    {197, 0.983779f, 0.593849f, 0.023770f}, {206, 0.987926f, 0.660250f, 0.051750f},
    {214, 0.985566f, 0.720782f, 0.112229f}, {222, 0.977497f, 0.782258f, 0.185923f},
    {230, 0.964394f, 0.843848f, 0.273391f}, {239, 0.948683f, 0.910473f, 0.395289f},
    {247, 0.951740f, 0.960587f, 0.524203f}, {255, 0.988362f, 0.998364f, 0.644924f},
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
