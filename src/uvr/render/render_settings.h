// SPDX-License-Identifier: MIT
#pragma once

// What a frame renders and how (RenderSettings), with the defaults and checks every front end
// shares; settings_vocabulary.h names, types and documents the settings the front ends set.

#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "uvr/mesh/tet_mesh.h"
#include "uvr/prepare/render_method.h"
#include "uvr/render/adaptive_marcher.h"
#include "uvr/render/camera.h"
#include "uvr/render/clip.h"
#include "uvr/render/isosurface.h"
#include "uvr/render/lighting.h"
#include "uvr/tf/transfer_function.h"

namespace uvr {

/// Default quality: the error-bound rule's SSIM target against the exact integrator.
inline constexpr float kDefaultQuality = 0.99f;
/// Range of the quality.
inline constexpr float kMinQuality = 0.5f;
inline constexpr float kMaxQuality = 0.9999f;

/// Tolerance per unit of (1 - quality) (toleranceForQuality).
inline constexpr float kToleranceScale = 5.f;

/// The error-bound rule's tolerance (StepRuleParams::tolerance, optical depth error per opacity
/// unit) for a quality: measured on the evaluation matrix (docs/PERFORMANCE.md), the worst-case
/// SSIM against exact stays at or above the quality for tolerance kToleranceScale * (1 -
/// quality).
float toleranceForQuality(float quality);

/// What to render and how.
struct RenderSettings {
    RenderMethod method = RenderMethod::Auto;
    StepRule stepRule = StepRule::ErrorBound;  ///< how the partition method picks steps
    /// The error-bound rule's target: the SSIM against the exact integrator that it aims at for
    /// typical data (toleranceForQuality), in [kMinQuality, kMaxQuality].
    float quality = kDefaultQuality;
    /// Sample-based methods integrate between consecutive samples (false: point samples with
    /// opacity correction, as in Morrical et al. 2019).
    bool preintegrated = true;
    float maxStep = 0.f;   ///< s2 of the adaptive step; 0 = kDefaultMaxStepFactor * s1 (shaded
                           ///< or with a gradient opacity, limited by shadeLit)
    float power = 2.f;     ///< variance rule: adaptive power p >= 1
    bool skip = true;      ///< skip partitions of zero maximum opacity
    bool adaptive = true;  ///< adaptive steps (false: every partition at s1)
    int width = 1024;
    int height = 1024;
    std::optional<Camera> camera;  ///< default: resetCamera on the mesh bounds
    TransferFunction tf;
    std::optional<std::pair<float, float>> range;  ///< default: the field's finite range
    float step = 0.f;                              ///< s1; 0 = defaultStep
    float opacityUnit = 0.f;                       ///< 0 = defaultOpacityUnit
    /// How the transfer function's opacities become extinction (default: ParaView's reading for
    /// unstructured data).
    OpacityLaw opacityLaw = kDefaultOpacityLaw;
    float terminationAlpha = 0.99f;
    /// Entries of the baked transfer function (a log-scale one gets more: logTableSize).
    int tfTableSize = 1024;
    /// Anti-aliasing: N x N rays per pixel (N in [1, kMaxSupersample]), their premultiplied
    /// colours averaged; a pixel's sample count is the sum over its rays. 1: one ray through
    /// the pixel's centre.
    int supersample = 1;
    /// With supersample > 1: each ray at a fixed hashed position inside its cell of the N x N
    /// grid instead of its centre (deterministic: the same rays every frame, on every device).
    bool jitter = false;
    /// Clipping (issue 32), in the file's coordinates: up to kMaxClipPlanes planes, each keeping
    /// the side its normal points to, and a box keeping its inside. Every method integrates only
    /// the part of each ray inside all of them (the exact method cuts the cells there exactly).
    std::vector<ClipPlane> clipPlanes;
    std::optional<Bounds3f> clipBox;
    /// The cut face as an opaque surface coloured by the field (ClipView::surface), lit with
    /// the face's normal by the lighting coefficients.
    bool clipSurface = false;
    /// Gradient shading (issue 32; lighting.h): off by default; ParaView's Ambient, Diffuse,
    /// Specular and SpecularPower and their defaults.
    Lighting lighting;
    /// Gradient opacity (issue 32; lighting.h): off by default; magnitudes in the file's units.
    /// It reads the gradients `lighting.smooth` picks.
    GradientOpacity gradientOpacity;
    /// Isosurfaces inside the volume (issue 32; isosurface.h), at most kMaxIsoSurfaces, in any
    /// order: each lit by `lighting`'s coefficients whether or not the volume is shaded. A point
    /// field only.
    std::vector<IsoSurface> isoSurfaces;
    /// Depth out (issue 32): above 0, a frame also gives per pixel the distance along the view
    /// direction, in the file's units, at which the accumulated opacity first reaches this
    /// (RenderResult::depth; infinity where it never does). An opaque isosurface reaches any
    /// such opacity at the surface. In [0, 1]; 0: no depth.
    float depthAlpha = 0.f;
    /// Depth in: width x height distances along the view direction, in the file's units, row 0
    /// at the top, of opaque geometry rendered elsewhere: every ray of a pixel ends at its
    /// distance, so the frame composites over that geometry (infinity or NaN: none at that
    /// pixel). Empty: none.
    std::vector<float> depthIn;
    /// Stop in: width x height accumulated opacities, row 0 at the top, at which each pixel's
    /// ray stops instead of at terminationAlpha (the sampling methods; exact runs on to its
    /// opacity end): a data-parallel rank behind others re-renders the pixels where one
    /// process's ray stops inside its piece, each stopping at what the opacity in front leaves
    /// (docs/METHOD.md, "Data-parallel rendering"). 0: the pixel is not rendered (transparent,
    /// no samples). With supersample 1 only. Empty: none.
    std::vector<float> pixelStopAlpha;
    /// Depth alpha in: width x height opacities, row 0 at the top, each the opacity whose depth
    /// that pixel's ray notes instead of depthAlpha (which must be above 0): a data-parallel
    /// rank behind others' light notes the depth where one process's ray reaches depthAlpha,
    /// at what the opacity in front leaves. 0: no depth at that pixel. With supersample 1 only.
    /// Empty: none.
    std::vector<float> pixelDepthAlpha;
    /// Called during a CPU render with the fraction of the frame done, increasing, the last call
    /// with 1; from one thread at a time, and it must not throw. Empty: no reports. (A CUDA frame
    /// is one launch and reports nothing.)
    std::function<void(double)> progress;
};

/// The names every front end and report gives the step rules ("error", "variance") and the
/// sampling (RenderSettings::preintegrated: "preintegrated", else "point").
const char* stepRuleName(StepRule rule);
const char* samplingName(bool preintegrated);

/// The settings' clip planes and box in the rendering units of a mesh's frame (ClipView for the
/// integrators; each normal of unit length).
ClipView clipView(const RenderSettings& settings, const MeshFrame& frame);

/// Throws SettingError (clip_planes, clip_box) for more than kMaxClipPlanes planes, a plane
/// without a finite origin or a finite non-zero normal, or a box not finite with lo <= hi.
/// (validateSettings calls it.)
void checkClip(const RenderSettings& settings);

/// A clip plane as messages and reports write it: "ox,oy,oz,nx,ny,nz"; a clip box as
/// "x0,y0,z0,x1,y1,z1".
std::string clipPlaneText(const ClipPlane& plane);
std::string clipBoxText(const Bounds3f& box);

/// The settings' isosurfaces for the integrators, sorted by value.
IsoView isoView(const RenderSettings& settings);

/// Throws SettingError (iso) for more than kMaxIsoSurfaces isosurfaces, or one whose value is
/// not finite, opacity not in (0, 1] or colour not in [0, 1]. (validateSettings calls it.)
void checkIso(const RenderSettings& settings);

/// An isosurface as every front end writes it: "VALUE[,OPACITY[,#RRGGBB]]" (the opacity when
/// not 1, the colour when not mapped; shortest decimals).
std::string isoText(const IsoSurface& iso);

/// Reads isoText's form (an opacity in (0, 1], a colour as #RRGGBB); throws SettingError (iso)
/// naming the text and the form otherwise.
IsoSurface parseIsoSurface(const std::string& text);

/// A gradient opacity as every front end writes it: "MAGNITUDE:SCALE,..." (shortest decimals;
/// "" when off).
std::string gradientOpacityText(const GradientOpacity& g);

/// Reads gradientOpacityText's form (1 to kMaxGradientOpacityPoints points); throws
/// SettingError (gradient_opacity) naming the text and the form otherwise.
GradientOpacity parseGradientOpacity(const std::string& text);

/// Throws SettingError (gradient_opacity, naming `text`, else the function's own text) for a
/// point count above kMaxGradientOpacityPoints, a magnitude not finite, negative or below the
/// one before, or a scale outside [0, 1]. (validateSettings calls it.)
void checkGradientOpacity(const GradientOpacity& g, const std::string& text = "");

/// Throws SettingError (depth_alpha, depth_in) for an opacity outside [0, 1] or a depth image
/// that is not width x height. (validateSettings calls it.)
void checkDepth(const RenderSettings& settings);

/// Largest RenderSettings::supersample: 8 x 8 = 64 rays per pixel.
inline constexpr int kMaxSupersample = 8;

/// Throws Error(Argument) for settings that cannot render: image size outside [1, 16384] per
/// side, non-finite or non-positive step or opacity unit, bad range, bad camera, supersample
/// outside [1, kMaxSupersample].
void validateSettings(const RenderSettings& settings);

/// True when settings tune what only the sampling methods read, away from RenderSettings'
/// defaults (the step rule, quality, power, point sampling, s1 or s2, skipping or adaptive steps
/// off): RenderMethod::Auto then renders the adaptive method they tune.
bool tunesAdaptive(const RenderSettings& settings);

/// Throws the Argument error of a log-scale mapping over a range with no positive value [lo, hi]:
/// the `range` setting's when `given`, else the field's.
[[noreturn]] void refuseLogRange(bool given, double lo, double hi);

/// Default s2 / s1 of the adaptive step.
inline constexpr float kDefaultMaxStepFactor = 16.f;
/// The shortest of shadeLit's longest steps in shaded frames (Lighting::on), in s1: the
/// error-bound rule sees the transfer function and the field's gradients, not how fast their
/// direction turns, and long steps under a headlight lose the lit detail (Blunt Fin, shaded,
/// adaptive against exact: SSIM 0.96 at 16 s1, 0.993 at 3 s1; docs/PERFORMANCE.md, "Shaded
/// frames: the step rule"). Also with a gradient opacity, whose scale changes with the
/// gradient's magnitude, which the rule does not see either.
inline constexpr float kShadedMaxStepFactor = 3.f;
/// The share of a pixel's colour a shaded frame's step may get wrong by missing its light's
/// changes (shadeLit: a step of optical depth d, its light anywhere within the light's rate,
/// steps at most so far that rate x d stays below this). 0.2 keeps Blunt Fin's shaded images
/// those of 3 s1 steps; 0.5 lost SSIM 0.01 there (docs/PERFORMANCE.md).
inline constexpr float kLitError = 0.2f;

}  // namespace uvr
