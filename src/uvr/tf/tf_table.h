// SPDX-License-Identifier: MIT
#pragma once

#include "uvr/core/host_device.h"
#include "uvr/core/vec.h"

namespace uvr {

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
        if (!(v == v)) return Vec4f(0.f, 0.f, 0.f, 0.f);
        float t = hi > lo ? (v - lo) / (hi - lo) : 0.f;
        t = t < 0.f ? 0.f : (t > 1.f ? 1.f : t);
        float f = t * static_cast<float>(count - 1);
        int i = static_cast<int>(f);
        if (i >= count - 1) return entries[count - 1];
        float w = f - static_cast<float>(i);
        return entries[i] * (1.f - w) + entries[i + 1] * w;
    }
};

}  // namespace uvr
