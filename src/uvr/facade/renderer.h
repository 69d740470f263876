// SPDX-License-Identifier: MIT
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "uvr/mesh/field_select.h"
#include "uvr/mesh/mesh.h"
#include "uvr/render/frame_setup.h"

namespace uvr {

class CudaScene;
class Communicator;
struct CompositeBuffers;
struct Decomposition;
struct MeshShare;
struct ValueRoutes;

/// Where frames render, or where acceleration structures build.
enum class Device {
    Auto,  ///< CUDA when a CUDA device can be used (and, for frames, holds the mesh), else the CPU
    Cpu,
    Cuda,
};

/// Parses "auto", "cpu" or "cuda"; throws Error(Argument) naming `what` (a flag or argument)
/// and the choices otherwise.
Device parseDevice(const std::string& text, const std::string& what);

/// True for Device::Cuda, or for Device::Auto when a CUDA device can be used.
bool resolvesToCuda(Device device);

/// What a Renderer prepares and where.
struct RendererOptions {
    Device device = Device::Auto;  ///< where frames render
    /// Where the BVHs and the k-d tree build: Auto builds on the GPU when frames render there and
    /// the mesh has kAutoGpuBuildTets tetrahedra or more.
    Device buildDevice = Device::Auto;
    bool partitions = true;  ///< the k-d partitions of RenderMethod::Partitions
    bool meshBvh = true;     ///< the mesh BVH of RenderMethod::Reference and Exact
    /// Also what RenderMethod::Auto renders with on this device (PrepareOptions::forAuto): a
    /// front end whose frames are all Auto sets this and neither of the two above.
    bool forAuto = false;
    bool seedGrids = true;  ///< with partitions: seed grids for long steps
    /// Split pyramids, wedges and hexahedra into tetrahedra instead of rendering them natively.
    bool splitCells = false;
    std::uint32_t leafCells = 0;  ///< cells per k-d partition; 0: the device's default
    /// PrepareOptions::afterSplit: called once the source mesh is no longer read (it may be
    /// freed then).
    std::function<void()> afterSplit;
    /// Data-parallel over this communicator's ranks when it has more than one (issue 31): every
    /// rank constructs its Renderer together (with the whole mesh, or with its share of it), holds
    /// and renders the piece of it that the whole mesh's k-d tree gives it (dist/), and every
    /// frame is composited onto rank 0, whose RenderResult is the whole picture. Null: one
    /// process. Not owned.
    Communicator* communicator = nullptr;
    /// Data-parallel: the largest sample distance (file units) frames will ask for; the pieces'
    /// ghost cells reach that far past their boxes (at least 2 default steps, the default
    /// step's frames). Frames of a larger one are refused, naming the largest. 0: the default.
    float largestSampleDistance = 0.f;

    /// The preparation these options ask for (the builders of the GPU when buildDevice resolves
    /// to it, the device's default leaf size).
    PrepareOptions prepareOptions() const;
};

/// What a renderer holds on the GPU (Renderer::gpuResidency), for reports.
struct GpuResidency {
    /// Bytes of device memory holding the mesh, BVH, neighbours and partitions.
    std::uint64_t geometryBytes = 0;
    double uploadSeconds = 0.0;       ///< the upload's time
    double valueUploadSeconds = 0.0;  ///< the last setFieldValues' upload of new values
    /// The most device memory the GPU's builders held at once while this renderer prepared
    /// (beyond what uvr held before it began); 0 when nothing built on the GPU.
    std::uint64_t buildPeakBytes = 0;
};

/// The one renderer object of the library: a mesh prepared once for one field (tetrahedra,
/// BVHs, neighbours, partitions), resident on the GPU when it renders there, rendering any
/// number of frames. Camera, transfer function, range, method and quality are per-frame
/// settings: changing them rebuilds nothing geometric. The CLI, the server and the Python
/// module all render through it. One frame at a time (render is not reentrant).
class Renderer {
public:
    /// Prepares `field` of `mesh` (a Mesh or a view of arrays held elsewhere; neither need
    /// outlive the renderer) as `options` ask and uploads it when rendering on the GPU
    /// (`progress` hears prepareMesh's phases, then "uploading N MiB to the GPU"). Throws
    /// Error(Unsupported) for Device::Cuda without a usable CUDA device, Error(Resource) when
    /// the GPU lacks memory.
    Renderer(const MeshView& mesh, const ScalarField& field, const RendererOptions& options = {},
             const ProgressFn& progress = {});
    /// A data-parallel renderer from this rank's share of a mesh (dist/decompose.h: read by the
    /// rank, e.g. readNativePart, shareOfPart): collective over options.communicator, which must
    /// be set; no rank holds the whole mesh. Throws as the constructor above.
    Renderer(MeshShare share, const RendererOptions& options, const ProgressFn& progress = {});
    /// Renders an already prepared mesh, taking it over, on `device`.
    Renderer(PreparedMesh prepared, Device device);
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// Renders one frame; throws Error(Argument) for settings validateSettings refuses and for a
    /// method whose structures were not prepared. Data-parallel: a collective call on every
    /// rank with the same settings; a failure on any rank throws on every rank.
    RenderResult render(const RenderSettings& settings);

    /// Gives the prepared mesh new values of a field of the same mesh (a time step, or another
    /// field) without rebuilding anything geometric (updateFieldValues), and on the GPU
    /// re-uploads only the value-dependent arrays (CudaScene::updateValues). Frames then equal
    /// those of a renderer prepared with these values. Throws Error(Argument) when the field
    /// does not hold one value per point (or cell) of the mesh; the renderer is unchanged then.
    /// Data-parallel (collective): `field` holds the whole mesh's values on a renderer made from
    /// a whole mesh, else this rank's share's (one per point or cell of the MeshShare it was
    /// made from); the values reach the ranks' pieces over the routes the distribution noted
    /// (routeValues) and the whole field's range is reduced over the ranks.
    void setFieldValues(const ScalarField& field);

    /// The prepared mesh.
    const PreparedMesh& prepared() const { return *prepared_; }
    /// True when frames render on the GPU.
    bool onGpu() const { return gpu_ != nullptr; }
    /// "cpu" or "cuda".
    const char* deviceName() const { return gpu_ ? "cuda" : "cpu"; }
    /// Why frames render on the CPU though RendererOptions::device was Auto and a GPU is there:
    /// the GPU lacked the memory for the scene (the out-of-memory message); else empty.
    const std::string& deviceFallback() const { return deviceFallback_; }
    /// One line naming the device: the GPU and its memory, or the CPU threads.
    std::string deviceDescription() const;
    /// What the renderer holds on the GPU when it renders there (else nothing).
    std::optional<GpuResidency> gpuResidency() const;
    /// Seconds the preparation took (0 for a mesh prepared elsewhere).
    double prepareSeconds() const { return prepareSeconds_; }
    /// The communicator of a data-parallel renderer (RendererOptions::communicator), else null.
    Communicator* communicator() const { return comm_; }
    /// True on the rank whose frames are the whole picture (rank 0; any one-process renderer).
    bool isRoot() const;
    /// A data-parallel renderer's preparation seconds on every rank, in rank order (empty for
    /// one process).
    const std::vector<double>& rankPrepareSeconds() const { return rankPrepareSeconds_; }

private:
    /// This rank's frame: its piece's on a data-parallel renderer.
    RenderResult renderLocal(const RenderSettings& settings);
    /// Data-parallel: distributes this rank's share and prepares its piece (comm_ set).
    void prepareShare(MeshShare share, const RendererOptions& options, const ProgressFn& progress);
    /// When a preparation began, and the device memory uvr held then (the GPU builders' peak
    /// counts from there: the constructor resets it).
    struct PreparationStart {
        std::chrono::steady_clock::time_point time;
        std::uint64_t gpuBytes = 0;
    };
    static PreparationStart startPreparation();
    /// The upload to the GPU (when rendering there) after the preparation that began at start.
    void finishPreparation(const RendererOptions& options, const ProgressFn& progress,
                           const PreparationStart& start);

    std::unique_ptr<PreparedMesh> prepared_;
    std::unique_ptr<CudaScene> gpu_;
    double prepareSeconds_ = 0.0;
    Communicator* comm_ = nullptr;
    std::shared_ptr<const Decomposition> decomposition_;
    std::unique_ptr<ValueRoutes> routes_;  ///< data-parallel: how new values reach the piece
    /// Data-parallel: the compositing's messages and band, kept from frame to frame.
    std::unique_ptr<CompositeBuffers> compositeBuffers_;
    /// Data-parallel from a whole mesh: the whole mesh's point and cell indices of this rank's
    /// share (setFieldValues takes the whole mesh's values there).
    std::vector<std::uint64_t> wholePointIds_, wholeCellIds_;
    bool fromWhole_ = false;                                  ///< made from a whole mesh
    std::uint64_t wholePointCount_ = 0, wholeCellCount_ = 0;  ///< that mesh's
    std::vector<double> rankPrepareSeconds_;
    std::uint64_t buildPeakBytes_ = 0;  ///< GpuResidency::buildPeakBytes
    std::string deviceFallback_;        ///< deviceFallback()
};

}  // namespace uvr
