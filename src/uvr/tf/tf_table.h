// SPDX-License-Identifier: MIT
#pragma once

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <vector>

#include "uvr/core/host_device.h"
#include "uvr/core/vec.h"

namespace uvr {

/// Position of value v on a table of count entries spread evenly over [lo, hi]: a number in
/// [0, count - 1], for any input. Values outside the range clamp to its ends (infinities too);
/// NaN, a zero-width or inverted range and a non-finite bound give 0. The width hi - lo of a
/// finite range may overflow float (a field spanning +-3e38): then both differences are taken
/// of halved values, which cannot overflow.
UVR_HOST_DEVICE inline float tfTablePosition(float v, float lo, float hi, int count) {
    float t = 0.f;
    if (hi > lo) {
        const float width = hi - lo;
        t = width <= FLT_MAX ? (v - lo) / width : (0.5f * v - 0.5f * lo) / (0.5f * hi - 0.5f * lo);
    }
    t = t > 0.f ? (t < 1.f ? t : 1.f) : 0.f;  // NaN -> 0
    return count > 1 ? t * static_cast<float>(count - 1) : 0.f;
}

/// How a transfer-function opacity alpha per opacity unit u becomes the extinction kappa (optical
/// depth per distance) along a ray; the emission is colour * kappa under both (docs/METHOD.md,
/// "Opacity law").
enum class OpacityLaw : std::uint8_t {
    /// kappa = alpha / u, linear between the transfer function's breakpoints: VTK's and
    /// ParaView's unstructured volume mappers (projected tetrahedra, Bunyk's ray caster). A slab L
    /// thick of constant alpha has opacity 1 - exp(-alpha L / u); alpha = 1 is finite.
    Attenuation,
    /// kappa = -ln(1 - alpha) / u: a slab L thick has opacity 1 - (1 - alpha)^(L / u) (the
    /// opacity correction of image-data ray casters: alpha is the opacity of one unit); alpha = 1
    /// is opaque at once.
    Transmittance,
};

/// The default law: what ParaView shows for unstructured data.
inline constexpr OpacityLaw kDefaultOpacityLaw = OpacityLaw::Attenuation;

/// Largest table opacity the transmittance law reads as finite: -ln(1e-6) = 13.8 optical depth
/// per unit (as good as infinite for a rate).
inline constexpr float kMaxFiniteOpacity = 0.999999f;

/// Extinction per opacity unit, kappa u, of a table opacity alpha (clamped to [0, 1]) under a
/// law; under the transmittance law alpha is capped at kMaxFiniteOpacity.
UVR_HOST_DEVICE inline float extinctionPerUnit(float alpha, OpacityLaw law) {
    const float a = alpha > 0.f ? (alpha < 1.f ? alpha : 1.f) : 0.f;
    if (law == OpacityLaw::Attenuation) return a;
    return -log1pf(-(a < kMaxFiniteOpacity ? a : kMaxFiniteOpacity));
}

/// The law's name as the front ends spell it ("attenuation", "transmittance").
const char* opacityLawName(OpacityLaw law);

/// The law of a name (opacityLawName's), false for any other name.
bool parseOpacityLaw(const char* name, OpacityLaw& law);

/// A baked transfer function: count RGBA entries spread evenly over the value range [lo, hi];
/// alpha is opacity per opacity unit distance, read by `law`. Plain data, usable on CPU and GPU.
struct TfTableView {
    const Vec4f* entries = nullptr;
    int count = 0;
    float lo = 0.f;
    float hi = 1.f;
    /// Optional breakpoints (tfTableBreaks): 2 * count indices, breaks[i] the first breakpoint
    /// above entry i, breaks[count + i] the last one below it. Between two consecutive
    /// breakpoints the table is linear to within kTfColorBreakTolerance in colour and
    /// kTfOpacityBreakTolerance in opacity, so the integrators need not split a segment at the
    /// entries in between. Null: every entry is a breakpoint.
    const std::int32_t* breaks = nullptr;
    /// Colour and opacity of NaN values (TransferFunction::nanColor, nanOpacity); opacity 0
    /// keeps NaN regions invisible.
    Vec4f nan = Vec4f(0.f, 0.f, 0.f, 0.f);
    /// How the opacities become extinction.
    OpacityLaw law = kDefaultOpacityLaw;

    /// The first breakpoint (a table position) above position g in [0, count - 1).
    UVR_HOST_DEVICE int breakAbove(double g) const {
        const int i = static_cast<int>(g);
        return breaks ? breaks[i] : i + 1;
    }
    /// The last breakpoint below position g in (0, count - 1].
    UVR_HOST_DEVICE int breakBelow(double g) const {
        const int i = static_cast<int>(ceil(g));
        return breaks ? breaks[count + i] : i - 1;
    }

    /// Linearly interpolated RGBA at value v (clamped to the range; a zero-width range maps
    /// everything to the first entry; NaN takes the NaN entry).
    UVR_HOST_DEVICE Vec4f sample(float v) const {
        if (!(v == v)) return nan;
        if (count < 1) return Vec4f(0.f, 0.f, 0.f, 0.f);
        const float f = tfTablePosition(v, lo, hi, count);
        const int i = static_cast<int>(f);  // f in [0, count - 1]: the conversion is defined
        if (i >= count - 1) return entries[count - 1];
        float w = f - static_cast<float>(i);
        return entries[i] * (1.f - w) + entries[i + 1] * w;
    }
};

/// Largest difference in opacity between a baked table and its linear interpolation between
/// breakpoints. An opacity error adds up along a ray (to this times the ray's length in opacity
/// units, in optical depth), so it is held tight.
inline constexpr float kTfOpacityBreakTolerance = 1e-4f;

/// Largest difference in each colour channel between a baked table and its linear interpolation
/// between breakpoints. A colour error does not add up: the composited colour is the colour
/// weighted by the emission fractions, which sum to the pixel's opacity, so the pixel is off by
/// at most this (a quarter of one 8-bit level). Integrating between breakpoints instead of
/// between all entries thus changes no pixel.
inline constexpr float kTfColorBreakTolerance = 1e-3f;

/// Breakpoints of a baked table (the layout of TfTableView::breaks): the entries where the
/// table stops being linear to within `colorTolerance` in a colour channel or
/// `opacityTolerance` in opacity, chosen greedily from the first entry in one O(count) pass (for
/// each run, the interval of chord slopes that keeps every entry inside the run within
/// tolerance); a run of entries of opacity 0 is one piece whatever their colours (it emits and
/// absorbs nothing). Both ends are always breakpoints.
std::vector<std::int32_t> tfTableBreaks(const Vec4f* entries, int count,
                                        float colorTolerance = kTfColorBreakTolerance,
                                        float opacityTolerance = kTfOpacityBreakTolerance);

}  // namespace uvr
