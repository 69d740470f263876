// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "uvr/accel/bvh.h"
#include "uvr/accel/kd_partitions.h"
#include "uvr/accel/seed_grid.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/mesh.h"
#include "uvr/mesh/tet_mesh.h"
#include "uvr/render/adaptive_marcher.h"
#include "uvr/render/camera.h"
#include "uvr/render/image.h"
#include "uvr/render/reference_marcher.h"
#include "uvr/tf/transfer_function.h"

namespace uvr {

/// What prepareMesh builds besides tetrahedra, BVH and neighbours.
struct PrepareOptions {
    bool meshBvh = true;     ///< build the BVH over all tetrahedra the reference marcher needs
    bool partitions = true;  ///< build the k-d partitions the partition integrator needs
    bool seedGrids = true;   ///< with partitions: the seed grids that long steps locate from
    KdBuildOptions kd;
    /// When set, the mesh BVH and the partitions' BVHs are LBVHs from this builder
    /// (buildLbvhCuda: on the GPU, in seconds for 100M+ tetrahedra); else binned SAH trees built
    /// on the CPU threads. It overrides kd.lbvh.
    LbvhBuilder lbvh;
    /// When set, the k-d tree comes from this splitter (buildKdTreeCuda: on the GPU); it
    /// overrides kd.splitter.
    KdSplitter kdSplitter;
    std::string builderDevice = "cpu";  ///< where lbvh and kdSplitter build (progress messages)
    std::uint64_t builderMinTets = 0;   ///< use them only from this many tetrahedra
};

/// A mesh made ready for rendering one field: tetrahedra, BVH, face neighbours and (optionally)
/// k-d partitions, built once and reused by every frame and transfer-function change.
struct PreparedMesh {
    TetMesh tets;
    Bvh bvh;  ///< over all tetrahedra; empty unless PrepareOptions::meshBvh
    std::vector<std::uint32_t> neighbors;
    std::optional<KdPartitions> kd;
    std::optional<SeedGrids> seeds;  ///< per-partition walk starts (with partitions)
    std::uint64_t sourceCells = 0;   ///< cells of the mesh before splitting
    double splitSeconds = 0.0;       ///< time to split cells into tetrahedra
    double bvhSeconds = 0.0;         ///< time to build the BVH
    double adjacencySeconds = 0.0;   ///< time to find face neighbours
    bool builtElsewhere = false;  ///< PrepareOptions' builders (the GPU's) made BVHs and k-d tree

    /// Point locator over this mesh.
    TetLocator locator() const { return {tets.view(), bvh.view(), neighbors.data()}; }
};

/// Optional progress report: a step name ("splitting cells", ...) when a step starts.
using ProgressFn = std::function<void(const std::string&)>;

/// Splits cells, builds the BVH over the tetrahedra and the face-neighbour table.
PreparedMesh prepareMesh(const Mesh& mesh, const ScalarField& field, const PrepareOptions& options,
                         const ProgressFn& progress = {});
/// prepareMesh with the default options.
PreparedMesh prepareMesh(const Mesh& mesh, const ScalarField& field);

/// Default sample spacing s1: half the edge of a cube with the mean tetrahedron volume,
/// 0.5 * cbrt(totalVolume / tetCount): about two to three samples per tetrahedron along a ray.
float defaultStep(const TetMesh& mesh);

/// ParaView's default ScalarOpacityUnitDistance: bounds diagonal / cbrt(cell count).
float defaultOpacityUnit(const Bounds3f& bounds, std::uint64_t cellCount);

/// Which integrator renders a frame.
enum class RenderMethod {
    Reference,   ///< fixed step s1 through the whole volume (the yardstick)
    Partitions,  ///< k-d partitions with space skipping and adaptive steps (Morrical et al. 2019)
};

/// What to render and how.
struct RenderSettings {
    RenderMethod method = RenderMethod::Reference;
    float maxStep = 0.f;   ///< s2 of the adaptive step; 0 = kDefaultMaxStepFactor * s1
    float power = 2.f;     ///< adaptive power p >= 1
    bool skip = true;      ///< skip partitions of zero maximum opacity
    bool adaptive = true;  ///< adaptive steps (false: every partition at s1)
    int width = 1024;
    int height = 1024;
    std::optional<Camera> camera;  ///< default: resetCamera on the mesh bounds
    TransferFunction tf;
    std::optional<std::pair<float, float>> range;  ///< default: the field's finite range
    float step = 0.f;                              ///< s1; 0 = defaultStep
    float opacityUnit = 0.f;                       ///< 0 = defaultOpacityUnit
    float terminationAlpha = 0.99f;
    int tfTableSize = 1024;  ///< entries of the baked transfer function
};

/// Throws Error(Argument) for settings that cannot render: image size outside [1, 16384] per
/// side, non-finite or non-positive step or opacity unit, bad range, bad camera.
void validateSettings(const RenderSettings& settings);

/// Default s2 / s1 of the adaptive step.
inline constexpr float kDefaultMaxStepFactor = 16.f;

/// Per-partition shading for a transfer function (Morrical et al. 2019, Sec. 2.1): each
/// partition's maximum opacity and colour variance over its value range (O(1) per partition from
/// the table's range statistics, independent of cell count), variances normalised to [0, 1] by
/// the minimum and maximum over the visible partitions, and the adaptive step from it (s1 for
/// every partition when adaptive is false; s2 for invisible partitions).
std::vector<PartitionShading> computePartitionShading(const KdPartitions& kd,
                                                      const TfRangeView& range, float s1, float s2,
                                                      float power, bool adaptive);

/// Host-side frame state built from settings: the baked table, the camera and the parameters.
struct FrameSetup {
    std::vector<Vec4f> tfTable;
    std::vector<PartitionShading> shading;  ///< per partition (partition method only)
    double tfUpdateSeconds = 0.0;           ///< range tables + shading of all partitions
    float maxStep = 0.f;                    ///< s2 in effect
    Camera camera;
    CameraRays rays;
    MarchParams params;
    float rangeLo = 0.f, rangeHi = 1.f;

    /// Scene view over a prepared mesh; both must outlive it.
    SceneView scene(const PreparedMesh& mesh) const;
    /// Partition scene view (the mesh must have partitions); both must outlive it.
    PartitionSceneView partitionScene(const PreparedMesh& mesh, bool skip) const;
};

/// Resolves defaults and validates; throws Error(Argument) on bad settings. For the partition
/// method it also computes the per-partition shading on the host unless shadePartitions is false
/// (the CUDA backend computes it on the GPU).
FrameSetup makeFrameSetup(const PreparedMesh& mesh, const RenderSettings& settings,
                          bool shadePartitions = true);

/// Statistics of one rendered frame.
struct RenderStats {
    double seconds = 0.0;                 ///< wall time of the frame (rendering only)
    std::uint64_t samples = 0;            ///< samples taken
    std::uint64_t walkSteps = 0;          ///< tetrahedra tested while walking
    std::uint64_t bvhQueries = 0;         ///< point locations that fell back to the BVH
    std::uint64_t partitionsVisited = 0;  ///< partitions entered by rays (partition method)
    std::uint64_t partitionsSkipped = 0;  ///< of those, skipped as fully transparent
    int width = 0, height = 0;

    /// Adds another frame part's counters.
    void merge(const RenderStats& o) {
        samples += o.samples;
        walkSteps += o.walkSteps;
        bvhQueries += o.bvhQueries;
        partitionsVisited += o.partitionsVisited;
        partitionsSkipped += o.partitionsSkipped;
    }
    /// Adds one ray's counters.
    void add(const RayCounters& c) {
        samples += c.samples;
        walkSteps += c.locate.walkSteps;
        bvhQueries += c.locate.bvhQueries;
        partitionsVisited += c.partitionsVisited;
        partitionsSkipped += c.partitionsSkipped;
    }
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
