// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "uvr/accel/bvh.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/mesh.h"
#include "uvr/mesh/tet_mesh.h"
#include "uvr/render/camera.h"
#include "uvr/render/image.h"
#include "uvr/render/reference_marcher.h"
#include "uvr/tf/transfer_function.h"

namespace uvr {

/// A mesh made ready for rendering one field: tetrahedra, BVH and face neighbours, built once and
/// reused by every frame and transfer-function change.
struct PreparedMesh {
    TetMesh tets;
    Bvh bvh;
    std::vector<std::uint32_t> neighbors;
    std::uint64_t sourceCells = 0;  ///< cells of the mesh before splitting
    double splitSeconds = 0.0;      ///< time to split cells into tetrahedra
    double bvhSeconds = 0.0;        ///< time to build the BVH
    double adjacencySeconds = 0.0;  ///< time to find face neighbours

    /// Point locator over this mesh.
    TetLocator locator() const { return {tets.view(), bvh.view(), neighbors.data()}; }
};

/// Optional progress report: a step name ("splitting cells", ...) when a step starts.
using ProgressFn = std::function<void(const std::string&)>;

/// Splits cells, builds the BVH over the tetrahedra and the face-neighbour table.
PreparedMesh prepareMesh(const Mesh& mesh, const ScalarField& field,
                         const ProgressFn& progress = {});

/// Default sample spacing s1: half the edge of a cube with the mean tetrahedron volume,
/// 0.5 * cbrt(totalVolume / tetCount): about two to three samples per tetrahedron along a ray.
float defaultStep(const TetMesh& mesh);

/// ParaView's default ScalarOpacityUnitDistance: bounds diagonal / cbrt(cell count).
float defaultOpacityUnit(const Bounds3f& bounds, std::uint64_t cellCount);

/// What to render and how.
struct RenderSettings {
    int width = 1024;
    int height = 1024;
    std::optional<Camera> camera;  ///< default: resetCamera on the mesh bounds
    TransferFunction tf;
    std::optional<std::pair<float, float>> range;  ///< default: the field's finite range
    float step = 0.f;         ///< s1; 0 = defaultStep
    float opacityUnit = 0.f;  ///< 0 = defaultOpacityUnit
    float terminationAlpha = 0.99f;
    int tfTableSize = 1024;   ///< entries of the baked transfer function
};

/// Throws Error(Argument) for settings that cannot render: image size outside [1, 16384] per
/// side, non-finite or non-positive step or opacity unit, bad range, bad camera.
void validateSettings(const RenderSettings& settings);

/// Host-side frame state built from settings: the baked table, the camera and the parameters.
struct FrameSetup {
    std::vector<Vec4f> tfTable;
    Camera camera;
    CameraRays rays;
    MarchParams params;
    float rangeLo = 0.f, rangeHi = 1.f;

    /// Scene view over a prepared mesh; both must outlive it.
    SceneView scene(const PreparedMesh& mesh) const;
};

/// Resolves defaults and validates; throws Error(Argument) on bad settings.
FrameSetup makeFrameSetup(const PreparedMesh& mesh, const RenderSettings& settings);

/// Statistics of one rendered frame.
struct RenderStats {
    double seconds = 0.0;          ///< wall time of the frame (rendering only)
    std::uint64_t samples = 0;     ///< samples taken
    std::uint64_t walkSteps = 0;   ///< tetrahedra tested while walking
    std::uint64_t bvhQueries = 0;  ///< point locations that fell back to the BVH
    int width = 0, height = 0;
    double meanSamplesPerPixel() const {
        return width > 0 && height > 0 ? static_cast<double>(samples) / (double(width) * height)
                                          : 0.0;
    }
};

/// A rendered frame: image, per-pixel sample counts, statistics.
struct RenderResult {
    Image image;
    std::vector<std::uint32_t> sampleCounts;  ///< per pixel, row-major
    RenderStats stats;
    FrameSetup setup;
};

}  // namespace uvr
