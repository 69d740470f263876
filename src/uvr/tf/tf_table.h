// SPDX-License-Identifier: MIT
#pragma once

#include <cfloat>

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

/// A baked transfer function: count RGBA entries spread evenly over the value range [lo, hi];
/// alpha is opacity per opacity unit distance. Plain data, usable on CPU and GPU.
struct TfTableView {
    const Vec4f* entries = nullptr;
    int count = 0;
    float lo = 0.f;
    float hi = 1.f;

    /// Linearly interpolated RGBA at value v (clamped to the range; a zero-width range maps
    /// everything to the first entry; NaN maps to fully transparent).
    UVR_HOST_DEVICE Vec4f sample(float v) const {
        if (!(v == v) || count < 1) return Vec4f(0.f, 0.f, 0.f, 0.f);
        const float f = tfTablePosition(v, lo, hi, count);
        const int i = static_cast<int>(f);  // f in [0, count - 1]: the conversion is defined
        if (i >= count - 1) return entries[count - 1];
        float w = f - static_cast<float>(i);
        return entries[i] * (1.f - w) + entries[i + 1] * w;
    }
};

}  // namespace uvr
