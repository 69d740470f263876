// SPDX-License-Identifier: MIT
#pragma once
// Scenes the integrator tests share (tests only): the linear field over the unit cube, its grid
// prepared with smooth gradients, a parallel view through it along +x, and the integrators.

#include "test_meshes.h"
#include "uvr/core/vec.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/smooth_gradients.h"
#include "uvr/prepare/prepared_mesh.h"
#include "uvr/prepare/render_method.h"
#include "uvr/render/camera.h"
#include "uvr/render/render_settings.h"
#include "uvr/tf/transfer_function.h"

namespace uvr::testing {

/// The integrators (every RenderMethod but Auto, which picks one of them).
inline constexpr RenderMethod kEveryMethod[] = {RenderMethod::Exact, RenderMethod::Reference,
                                                RenderMethod::Partitions};

/// The linear field's gradient (magnitude 0.856 per unit).
inline const Vec3f kLinearGradient(0.6f, 0.5f, -0.35f);

/// A linear field (one gradient everywhere), which the cells' interpolation reproduces exactly.
inline float linearField(Vec3f p) {
    return dot(kLinearGradient, p);
}

/// A constant field (no gradient).
inline float constantField(Vec3f) {
    return 0.5f;
}

/// A 6^3 grid of hexahedra over [0, size]^3 (jittered when asked) with the field f of the point
/// scaled to the unit cube times `valueScale` (so its gradient is f's times valueScale / size),
/// as native cells or split into tetrahedra, with its smooth gradients.
inline PreparedMesh smoothGradientGrid(float (*f)(Vec3f), bool split, float jitter = 0.f,
                                       float size = 1.f, float valueScale = 1.f) {
    const Mesh m = makeHexGrid(
        6, 0.f, size, [&](Vec3f p) { return valueScale * f(p * (1.f / size)); }, jitter);
    PrepareOptions options;
    options.kd.leafCells = 32;  // several partitions along each ray
    options.cells.splitCells = split;
    PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}), options);
    computeSmoothGradients(pm.tets);
    return pm;
}

/// A parallel view along +x through the middle of the cube [0, size]^3, opacity 0.6 per unit
/// (attenuation), 100 steps across: every ray crosses the cube inside it.
inline RenderSettings viewAlongX(RenderMethod method, float size = 1.f) {
    RenderSettings s;
    s.method = method;
    s.width = 24, s.height = 16;
    Camera c;
    c.position = Vec3f(-2.f, 0.52f, 0.47f) * size;
    c.focalPoint = Vec3f(0.5f, 0.52f, 0.47f) * size;
    c.viewUp = Vec3f(0.f, 0.f, 1.f);
    c.parallelProjection = true;
    c.parallelScale = 0.2f * size;
    s.camera = c;
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, "constant:0.6");
    s.range = {-0.5f, 1.2f};
    s.opacityUnit = size;
    s.opacityLaw = OpacityLaw::Attenuation;
    s.step = 0.01f * size;
    return s;
}

}  // namespace uvr::testing
