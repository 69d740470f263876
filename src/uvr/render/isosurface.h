// SPDX-License-Identifier: MIT
#pragma once

// Isosurfaces inside the volume (issue 32): surfaces where the field equals given values, each
// opaque or translucent, coloured by the transfer function's colour at its value or by a
// constant colour, lit by the headlight with the field's gradient as the normal (lighting.h's
// coefficients), and composited in depth order with the volume.
//
// Every integrator meets the field as linear pieces along the ray: the exact integrator per
// tetrahedron (and per piece of a native cell, where the crossing is then refined on the cell's
// own field), the sampling methods between consecutive samples. A piece crosses a value c where
// its ends lie on either side, at the fraction (c - v0) / (v1 - v0): exact in a linear
// tetrahedron, within the sampling's linear reading between samples otherwise (the adaptive
// method steps partitions and macrocells whose value range holds an iso value at most 4 s1 and
// bisects a long step across a surface to within s1: shadeIso, bisectIso). The piece is
// integrated up to the crossing, the surface composited, the rest integrated after it.

#include <cstdint>

#include "uvr/core/host_device.h"
#include "uvr/core/vec.h"
#include "uvr/render/lighting.h"

namespace uvr {

/// Most isosurfaces a frame takes.
inline constexpr int kMaxIsoSurfaces = 8;

/// One isosurface: the field's value, its opacity (1: opaque) and colour.
struct IsoSurface {
    float value = 0.f;
    float opacity = 1.f;  ///< in (0, 1]
    /// The transfer function's colour at the value (ParaView's "colour by the field"); false:
    /// `color`.
    bool colorMapped = true;
    Vec3f color{1.f, 1.f, 1.f};  ///< RGB in [0, 1] when not colorMapped
};

/// A frame's isosurfaces for the integrators, sorted by value (ascending), as plain data.
struct IsoView {
    IsoSurface surfaces[kMaxIsoSurfaces];
    int count = 0;

    UVR_HOST_DEVICE bool active() const { return count > 0; }

    /// True when some iso value lies in [lo, hi] (a partition's or macrocell's value range).
    UVR_HOST_DEVICE bool within(float lo, float hi) const {
        for (int i = 0; i < count; ++i)
            if (surfaces[i].value >= lo && surfaces[i].value <= hi) return true;
        return false;
    }

    /// Calls hit(i, f) for every surface i a field running linearly from v0 to v1 crosses, in
    /// the order met from v0, at the fraction f in [0, 1] of the way; a surface is crossed where
    /// v0 and v1 lie on its two sides or v1 (not v0) is its value, so consecutive pieces count a
    /// crossing at their shared end once. Returns the number crossed (NaN ends cross nothing).
    template <class Hit>
    UVR_HOST_DEVICE int crossings(float v0, float v1, Hit&& hit) const {
        int n = 0;
        const bool up = v1 > v0;
        for (int j = 0; j < count; ++j) {
            const int i = up ? j : count - 1 - j;
            const float c = surfaces[i].value;
            if ((v0 < c) == (v1 < c)) continue;
            float f = (c - v0) / (v1 - v0);
            f = f > 0.f ? (f < 1.f ? f : 1.f) : 0.f;
            hit(i, f);
            ++n;
        }
        return n;
    }

    /// True when a field running linearly from v0 to v1 crosses a surface (crossings).
    UVR_HOST_DEVICE bool crosses(float v0, float v1) const {
        return crossings(v0, v1, [](int, float) {}) > 0;
    }

    /// True when a field running linearly from v0 to v1 crosses an odd number of surfaces (a
    /// step whose ends lie on either side of one: bisectIso narrows it).
    UVR_HOST_DEVICE bool crossesOdd(float v0, float v1) const {
        return crossings(v0, v1, [](int, float) {}) % 2 == 1;
    }
};

/// Composites isosurface s, of colour `rgb` (the transfer function's at its value when
/// colorMapped) lit by `light`, into the premultiplied accumulator.
UVR_HOST_DEVICE inline void compositeIso(const IsoSurface& s, Vec3f mapped,
                                         const LightFactors& light, Vec4f& acc) {
    const Vec3f c = light.apply(s.colorMapped ? mapped : s.color);
    const float w = (1.f - acc.w) * s.opacity;
    acc.x += w * c.x;
    acc.y += w * c.y;
    acc.z += w * c.z;
    acc.w = s.opacity >= 1.f ? 1.f : acc.w + w;
}

/// The lighting of isosurfaces: the frame's coefficients, always on (a surface is lit whether or
/// not the volume is shaded; the volume's gradient opacity is not theirs).
UVR_HOST_DEVICE inline Lighting surfaceLighting(Lighting l) {
    l.on = true;
    return l;
}

}  // namespace uvr
