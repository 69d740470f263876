// SPDX-License-Identifier: MIT
#pragma once

// Gradient shading (issue 32): ParaView's "Shade" for volumes, a white headlight at the camera
// lighting each point of the volume by the field's gradient as a surface normal (two-sided, as
// VTK's volume mappers light: the gradient's sign does not matter). A point light at the eye
// shines along every ray: the light and view directions are both -dir, so the half vector is the
// light's too, and with cosine c = |n . dir| a colour c_tf of the transfer function becomes
//
//     (ambient + diffuse c) c_tf + specular c^power
//
// (VTK's volume shading with a white light; no clamp to 1: with ambient + diffuse + specular <= 1,
// ParaView's defaults, none is needed). That is an affine map of the colour, constant wherever the
// gradient is: in a linear tetrahedron along a whole segment. So the emission-absorption integral
// of a lit segment is the unlit one's colour times `scale` plus its opacity times `add`
// (LightFactors): the exact and pre-integrated integrators stay exact per cell.

#include <cmath>

#include "uvr/core/host_device.h"
#include "uvr/core/vec.h"

namespace uvr {

/// ParaView's defaults for a volume's lighting (its representation's Ambient, Diffuse, Specular,
/// SpecularPower).
inline constexpr float kDefaultAmbient = 0.f;
inline constexpr float kDefaultDiffuse = 1.f;
inline constexpr float kDefaultSpecular = 0.f;
inline constexpr float kDefaultSpecularPower = 100.f;

/// The lighting of a frame, as plain data for the integrators.
struct Lighting {
    bool on = false;  ///< off: colours as the transfer function gives them
    /// Normals from the smooth gradients (computeSmoothGradients), interpolated in each cell;
    /// false: each cell's own gradient (constant in a linear tetrahedron: exact per cell).
    bool smooth = true;
    float ambient = kDefaultAmbient;
    float diffuse = kDefaultDiffuse;
    float specular = kDefaultSpecular;
    float specularPower = kDefaultSpecularPower;
};

/// A lit colour as an affine map of the transfer function's: scale c_tf + add (grey). The
/// identity ({1, 0}) leaves a colour as it is.
struct LightFactors {
    float scale = 1.f;
    float add = 0.f;

    UVR_HOST_DEVICE bool identity() const { return scale == 1.f && add == 0.f; }
    /// The mean of two (a segment lit by its two ends' lights).
    UVR_HOST_DEVICE LightFactors mean(const LightFactors& o) const {
        return {0.5f * (scale + o.scale), 0.5f * (add + o.add)};
    }
    UVR_HOST_DEVICE Vec3f apply(Vec3f c) const {
        return Vec3f(c.x * scale + add, c.y * scale + add, c.z * scale + add);
    }
};

/// |cos| of the angle between the gradient g and the ray's unit direction dir. A zero or
/// non-finite gradient (a constant field, cell data, a degenerate cell, NaN values) has no
/// normal: it is lit as facing the light (1).
UVR_HOST_DEVICE inline float lightCosine(Vec3f g, Vec3f dir) {
    // Scaled by its largest component first: a gradient of huge or tiny values neither
    // overflows nor underflows its squared length.
    const float m = fmaxf(fabsf(g.x), fmaxf(fabsf(g.y), fabsf(g.z)));
    if (!(m > 0.f) || !(m <= 3.4e38f)) return 1.f;
    const Vec3f n(g.x / m, g.y / m, g.z / m);  // (1 / m overflows for a subnormal m)
    const float c = fabsf(dot(n, dir)) / sqrtf(dot(n, n));
    return c < 1.f ? c : 1.f;
}

/// The light a point with field gradient g receives along a ray of unit direction dir (the
/// identity when lighting is off).
UVR_HOST_DEVICE inline LightFactors lightFactors(const Lighting& l, Vec3f g, Vec3f dir) {
    if (!l.on) return {};
    const float c = lightCosine(g, dir);
    const float spec = l.specular > 0.f ? l.specular * powf(c, l.specularPower) : 0.f;
    return {l.ambient + l.diffuse * c, spec};
}

/// Lights what a segment added to the premultiplied accumulator: `before` is the accumulator
/// before the segment, acc after it; the added colour is scaled and the added opacity, times
/// `add`, joins it as grey (the integral of (scale c + add) kappa T along the segment).
UVR_HOST_DEVICE inline void lightSegment(const Vec4f& before, const LightFactors& f, Vec4f& acc) {
    if (f.identity()) return;
    const float da = acc.w - before.w;
    acc.x = before.x + (acc.x - before.x) * f.scale + da * f.add;
    acc.y = before.y + (acc.y - before.y) * f.scale + da * f.add;
    acc.z = before.z + (acc.z - before.z) * f.scale + da * f.add;
}

}  // namespace uvr
