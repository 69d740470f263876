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
#include "uvr/render/segment_integral.h"

namespace uvr {

/// ParaView's defaults for a volume's lighting (its representation's Ambient, Diffuse, Specular,
/// SpecularPower).
inline constexpr float kDefaultAmbient = 0.f;
inline constexpr float kDefaultDiffuse = 1.f;
inline constexpr float kDefaultSpecular = 0.f;
inline constexpr float kDefaultSpecularPower = 100.f;

/// Most points of a gradient opacity function.
inline constexpr int kMaxGradientOpacityPoints = 8;

/// Gradient opacity (VTK's vtkVolumeProperty::SetGradientOpacity, ParaView's "gradient
/// opacity"): a piecewise linear function of the field gradient's magnitude, constant beyond its
/// first and last points, whose value in [0, 1] scales the transfer function's opacity where the
/// gradient has that magnitude: flat regions fade, boundaries between materials stay. It scales
/// the extinction (at a short step, VTK's product of a sample's two opacities), which over a
/// segment of constant magnitude is the segment's opacity unit divided by the scale: in a linear
/// tetrahedron the gradient is constant, so the exact and pre-integrated integrators stay exact.
struct GradientOpacity {
    int count = 0;  ///< points (0: off)
    /// The points, magnitudes non-decreasing (in the field's units per length: the file's in
    /// settings, the frame's in MarchParams); scales in [0, 1].
    float magnitude[kMaxGradientOpacityPoints] = {};
    float scale[kMaxGradientOpacityPoints] = {};

    UVR_HOST_DEVICE bool active() const { return count > 0; }
    /// The scale at gradient magnitude m (NaN: the first point's).
    UVR_HOST_DEVICE float at(float m) const {
        if (!(m > magnitude[0])) return scale[0];
        for (int i = 1; i < count; ++i) {
            if (m < magnitude[i]) {
                const float w = (m - magnitude[i - 1]) / (magnitude[i] - magnitude[i - 1]);
                return scale[i - 1] + (scale[i] - scale[i - 1]) * w;
            }
        }
        return scale[count - 1];
    }
};

/// The lighting of a frame, as plain data for the integrators.
struct Lighting {
    bool on = false;  ///< off: colours as the transfer function gives them
    /// Normals from the smooth gradients (computeSmoothGradients), interpolated in each cell;
    /// false: each cell's own gradient (constant in a linear tetrahedron: exact per cell). A
    /// gradient opacity reads the same gradients.
    bool smooth = true;
    float ambient = kDefaultAmbient;
    float diffuse = kDefaultDiffuse;
    float specular = kDefaultSpecular;
    float specularPower = kDefaultSpecularPower;
};

/// Whether a point's gradient changes what it adds: shaded, or with a gradient opacity. (The
/// gradient opacity is kept apart from the lighting: isosurfaces and the cut face copy the
/// lighting, and their opacity is their own.)
UVR_HOST_DEVICE inline bool readsGradient(const Lighting& l, const GradientOpacity& g) {
    return l.on || g.active();
}

/// What a point's gradient does to what it adds: its lit colour as an affine map of the transfer
/// function's, scale c_tf + add (grey), and its extinction times `opacity` (the gradient
/// opacity). The identity ({1, 0, 1}) leaves both as they are.
struct LightFactors {
    float scale = 1.f;
    float add = 0.f;
    float opacity = 1.f;

    UVR_HOST_DEVICE bool identity() const { return scale == 1.f && add == 0.f; }
    /// The mean of two (a segment lit by its two ends' lights).
    UVR_HOST_DEVICE LightFactors mean(const LightFactors& o) const {
        return {0.5f * (scale + o.scale), 0.5f * (add + o.add), 0.5f * (opacity + o.opacity)};
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

/// |g| without overflow or underflow (scaled by its largest component first); NaN for a
/// non-finite gradient.
UVR_HOST_DEVICE inline float gradientMagnitude(Vec3f g) {
    const float m = fmaxf(fabsf(g.x), fmaxf(fabsf(g.y), fabsf(g.z)));
    if (!(m > 0.f)) return m == 0.f ? 0.f : NAN;
    if (!(m <= 3.4e38f)) return NAN;
    const Vec3f n(g.x / m, g.y / m, g.z / m);
    return m * sqrtf(dot(n, n));
}

/// The light a point with field gradient g receives along a ray of unit direction dir (the
/// identity when lighting is off).
UVR_HOST_DEVICE inline LightFactors lightFactors(const Lighting& l, Vec3f g, Vec3f dir) {
    if (!l.on) return {};
    const float c = lightCosine(g, dir);
    const float spec = l.specular > 0.f ? l.specular * powf(c, l.specularPower) : 0.f;
    return {l.ambient + l.diffuse * c, spec};
}

/// The light and the gradient opacity of a point of the volume with field gradient g (its
/// opacity 1 without a gradient opacity).
UVR_HOST_DEVICE inline LightFactors lightFactors(const Lighting& l, const GradientOpacity& gop,
                                                 Vec3f g, Vec3f dir) {
    LightFactors f = lightFactors(l, g, dir);
    if (gop.active()) f.opacity = gop.at(gradientMagnitude(g));
    return f;
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

/// A segment of length len, the scalar linear from v0 to v1, integrated into acc
/// (segment::integrate) and lit by f (kLit; lightSegment): its gradient opacity scales the
/// extinction, so the segment integrates per opacity unit / f.opacity, and a scale of 0 leaves
/// it out.
template <bool kLit = true>
UVR_HOST_DEVICE UVR_INLINE void integrateLit(const TfTableView& tf, float v0, float v1, double len,
                                             double unit, const LightFactors& f, Vec4f& acc) {
    if constexpr (kLit) {
        if (f.opacity != 1.f) {
            if (!(f.opacity > 0.f)) return;
            unit /= f.opacity;
        }
        const Vec4f before = acc;
        segment::integrate(tf, v0, v1, len, unit, acc, true);
        lightSegment(before, f, acc);
    } else {
        segment::integrate(tf, v0, v1, len, unit, acc, true);
    }
}

}  // namespace uvr
