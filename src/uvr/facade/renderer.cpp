// SPDX-License-Identifier: MIT
#include "uvr/facade/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "uvr/core/error.h"
#include "uvr/core/host_memory.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/cpu/threads.h"
#include "uvr/cuda/cuda_build.h"
#include "uvr/cuda/cuda_renderer.h"
#include "uvr/dist/communicator.h"
#include "uvr/dist/composite.h"
#include "uvr/dist/decompose.h"
#include "uvr/mesh/smooth_gradients.h"
#include "uvr/render/segment_integral.h"

namespace uvr {

namespace {

/// A data-parallel piece's ghost cells reach this many of the whole mesh's default steps past
/// its box: the sample ending a piece's last segment lies at most one step beyond it.
constexpr float kGhostSteps = 2.f;

}  // namespace

Device parseDevice(const std::string& text, const std::string& what) {
    if (text == "auto") return Device::Auto;
    if (text == "cpu") return Device::Cpu;
    if (text == "cuda") return Device::Cuda;
    throwError(ErrorKind::Argument, "",
               what + ": expected auto, cpu or cuda, got \"" + text + "\"");
}

bool resolvesToCuda(Device device) {
    return device == Device::Cuda || (device == Device::Auto && cudaDeviceAvailable());
}

PrepareOptions RendererOptions::prepareOptions() const {
    const bool renderOnCuda = resolvesToCuda(device);
    const bool buildOnCuda =
        buildDevice == Device::Cuda || (buildDevice == Device::Auto && renderOnCuda);
    PrepareOptions o;
    if (buildOnCuda) {
        o.lbvh = buildLbvhCuda;
        o.kdSplitter = buildKdTreeCuda;
        o.faceMatcher = [](const TetMesh& m, const std::vector<std::uint32_t>& welded,
                           const FractionFn& progress) {
            return buildTetNeighborsCuda(m, progress, 0, &welded);
        };
        o.seedBuilder = buildSeedGridsCuda;
        o.macroBuilder = buildMacroGridsCuda;
        o.cells.sorter = sortCellKeysCuda;
        o.builderDevice = "the GPU";
        if (buildDevice == Device::Auto) o.builderMinTets = kAutoGpuBuildTets;
    }
    o.partitions = partitions;
    o.meshBvh = meshBvh;
    o.forAuto = forAuto;
    o.autoOnGpu = renderOnCuda;
    o.seedGrids = seedGrids;
    o.cells.splitCells = splitCells;
    o.afterSplit = afterSplit;
    if (leafCells)
        o.kd.leafCells = leafCells;
    else if (renderOnCuda)
        o.kd.leafCells = kCudaDefaultLeafCells;
    // Memory-lean on large meshes (prepareMesh keeps the CPU's leaves on small ones).
    if (renderOnCuda) o.cellTreeLeaf = kCellTreeLeaf;
    return o;
}

namespace {

/// Throws Error(Unsupported) for Device::Cuda without a usable CUDA device.
void checkDeviceUsable(Device device) {
    if (device == Device::Cuda && !cudaDeviceAvailable())
        throwError(ErrorKind::Unsupported, "",
                   "rendering on CUDA was asked for, but " + cudaDeviceDescription());
}

/// The GPU's scene of the prepared mesh when frames render there, else null. Under
/// Device::Auto a GPU without the memory for the scene leaves the frames to the CPU, as a GPU
/// without the memory for a build leaves that build to the CPU (prepareMesh): the picture comes
/// without the user choosing another device. `fallback` then says why (the progress hears it),
/// and the mesh's Auto choice is made again for the CPU. Device::Cuda keeps the error.
std::unique_ptr<CudaScene> uploadIf(Device device, PreparedMesh& prepared,
                                    const ProgressFn& progress, std::string& fallback) {
    if (!resolvesToCuda(device)) return nullptr;
    try {
        return std::make_unique<CudaScene>(prepared, progress.fraction);
    } catch (const Error& e) {
        if (device != Device::Auto || e.kind() != ErrorKind::Resource) throw;
        fallback = std::string(e.what()) + "; rendering on the CPU instead";
        if (progress) progress(fallback);
        prepared.autoChoice =
            prepared.piece ? prepared.piece->autoCpu : autoMethod(prepared.tets, /*gpu=*/false);
        return nullptr;
    }
}

}  // namespace

Renderer::Renderer(const MeshView& mesh, const ScalarField& field, const RendererOptions& options,
                   const ProgressFn& progress) {
    checkDeviceUsable(options.device);
    const PreparationStart start = startPreparation();
    if (options.communicator && options.communicator->size() > 1) {
        // Data-parallel from a whole mesh every rank holds: each starts from its share.
        const Communicator& comm = *options.communicator;
        MeshShare share = shareOfMesh(mesh, field, comm.rank(), comm.size());
        wholePointIds_ = share.pointIds;
        wholeCellIds_ = share.cellIds;
        fromWhole_ = true;
        wholePointCount_ = mesh.pointCount();
        wholeCellCount_ = mesh.cellCount();
        prepareShare(std::move(share), options, progress);
    } else {
        prepared_ = std::make_unique<PreparedMesh>(
            prepareMesh(mesh, field, options.prepareOptions(), progress));
    }
    finishPreparation(options, progress, start);
}

Renderer::Renderer(MeshShare share, const RendererOptions& options, const ProgressFn& progress) {
    checkDeviceUsable(options.device);
    UVR_CHECK(options.communicator, "a renderer from a share needs a communicator");
    const PreparationStart start = startPreparation();
    prepareShare(std::move(share), options, progress);
    finishPreparation(options, progress, start);
}

void Renderer::prepareShare(MeshShare share, const RendererOptions& options,
                            const ProgressFn& progress) {
    // The whole mesh's k-d tree cut into the ranks' boxes, and this rank's piece prepared as one
    // process would prepare that box (dist/decompose.h).
    comm_ = options.communicator;
    PrepareOptions prepare = options.prepareOptions();
    RankPiece piece = distributeMesh(*comm_, std::move(share), prepare, kGhostSteps,
                                     options.largestSampleDistance, progress);
    decomposition_ = std::make_shared<Decomposition>(std::move(piece.decomposition));
    routes_ = std::make_unique<ValueRoutes>(std::move(piece.routes));
    prepare.piece = piece.piece;
    prepared_ = std::make_unique<PreparedMesh>(
        agreeOn(*comm_, [&] { return prepareMesh(piece.mesh, piece.field, prepare, progress); }));
    prepared_->phaseSeconds.insert(prepared_->phaseSeconds.begin(), piece.phaseSeconds.begin(),
                                   piece.phaseSeconds.end());
}

Renderer::PreparationStart Renderer::startPreparation() {
    resetCudaMemoryPeak();
    return {std::chrono::steady_clock::now(), cudaMemoryUse().bytes};
}

void Renderer::finishPreparation(const RendererOptions& options, const ProgressFn& progress,
                                 const PreparationStart& start) {
    prepareSeconds_ =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start.time).count();
    const std::uint64_t peak = cudaMemoryUse().peakBytes;
    buildPeakBytes_ = peak > start.gpuBytes ? peak - start.gpuBytes : 0;
    if (comm_) rankPrepareSeconds_ = comm_->allGatherValues(prepareSeconds_);
    if (progress && resolvesToCuda(options.device))
        progress("uploading " +
                 std::to_string((cudaSceneBytes(*prepared_) + (1u << 20) - 1) >> 20) +
                 " MiB to the GPU");
    gpu_ =
        comm_ ? agreeOn(
                    *comm_,
                    [&] { return uploadIf(options.device, *prepared_, progress, deviceFallback_); })
              : uploadIf(options.device, *prepared_, progress, deviceFallback_);
    if (comm_) {
        // The ranks render on one device (one method under Auto, one picture): where one rank's
        // GPU could not hold its piece, every rank renders on the CPU.
        const std::vector<std::uint64_t> fell =
            comm_->allGatherValues(std::uint64_t(!deviceFallback_.empty()));
        const auto first = std::find(fell.begin(), fell.end(), std::uint64_t(1));
        if (first != fell.end() && gpu_) {
            gpu_.reset();
            prepared_->autoChoice = prepared_->piece->autoCpu;
            deviceFallback_ = "rank " + std::to_string(first - fell.begin()) +
                              "'s GPU lacked the memory for its piece; rendering on the CPU";
            if (progress) progress(deviceFallback_);
        }
    }
}

Renderer::Renderer(PreparedMesh prepared, Device device)
    : prepared_(std::make_unique<PreparedMesh>(std::move(prepared))) {
    checkDeviceUsable(device);
    // RenderMethod::Auto's choice for this device, made once (a cache holds none).
    const bool cuda = resolvesToCuda(device);
    if (!prepared_->autoChoice || prepared_->autoChoice->gpu != cuda)
        prepared_->autoChoice = autoMethod(prepared_->tets, cuda);
    gpu_ = uploadIf(device, *prepared_, {}, deviceFallback_);
}

Renderer::~Renderer() = default;

bool Renderer::isRoot() const {
    return !comm_ || comm_->rank() == 0;
}

RenderResult Renderer::render(const RenderSettings& settings) {
    if (!comm_) return renderLocal(settings);
    RenderResult result = agreeOn(*comm_, [&] {
        // Depth in ends every rank's rays where one process's end (the same camera, the same
        // view depths); depth out asks a rank behind others' light for the depth of what that
        // light leaves, at one ray a pixel.
        if (settings.depthAlpha > 0.f && settings.supersample != 1)
            throwError(ErrorKind::Unsupported, "",
                       "the depth image out (`depth`) with supersample " +
                           std::to_string(settings.supersample) +
                           " is not rendered data-parallel: render it at supersample 1 or in "
                           "one process");
        return renderLocal(settings);
    });
    // Every rank's piece composited onto rank 0, front to back in the boxes' order.
    const Camera& camera = result.setup.camera;
    const std::vector<int> order = visibilityOrder(*decomposition_, camera.parallelProjection,
                                                   camera.position, result.setup.viewDirection);
    const double frameSeconds = result.stats.seconds;
    // A pixel stops taking ranks where one process's ray stops (exact integrates on to
    // kOpacityEnd, the sampling methods to the termination opacity).
    const bool exact = result.setup.method.method == RenderMethod::Exact;
    CompositeOptions composite;
    composite.stopAlpha = exact ? segment::kOpacityEnd : settings.terminationAlpha;
    // Where a rank's ray stopped behind other ranks' light, it renders the pixel again to
    // one process's stop (exact's stop, 1 - 1e-6, leaves nothing to redo; a supersampled
    // pixel's rays stop each on its own, which one opacity per pixel cannot follow).
    composite.restop = !exact && settings.supersample == 1;
    composite.depthAlpha = settings.depthAlpha;
    std::uint64_t samples = result.stats.samples;
    composite.rerender = [&](const PieceAsks& asks, PieceFrame& frame) {
        RenderSettings again = settings;
        again.pixelStopAlpha = asks.stops;
        again.pixelDepthAlpha = asks.depthAlphas;
        again.progress = {};
        RenderResult r = renderLocal(again);
        samples += r.stats.samples;
        frame.image = std::move(r.image);
        frame.counts = std::move(r.sampleCounts);
        frame.depth = std::move(r.depth);
    };
    if (!compositeBuffers_) compositeBuffers_ = std::make_unique<CompositeBuffers>();
    composite.buffers = compositeBuffers_.get();
    const CompositeStats composited =
        compositeFrame(*comm_, result.image, result.sampleCounts, result.depth, order, composite);
    result.stats.samples = samples;
    // The ranks' counters summed, and each rank's share.
    std::uint64_t counters[5] = {result.stats.samples, result.stats.walkSteps,
                                 result.stats.bvhQueries, result.stats.partitionsVisited,
                                 result.stats.partitionsSkipped};
    comm_->allReduce(counters, ReduceOp::Sum);
    result.stats.samples = counters[0], result.stats.walkSteps = counters[1];
    result.stats.bvhQueries = counters[2], result.stats.partitionsVisited = counters[3];
    result.stats.partitionsSkipped = counters[4];
    RankFrameStats mine;
    mine.frameSeconds = frameSeconds + composited.rerenderSeconds;
    mine.compositeSeconds = composited.seconds;
    mine.bytesSent = composited.bytesSent;
    mine.samples = samples;
    mine.rerenderedPixels = composited.rerenderedPixels;
    mine.peakHostBytes = peakResidentBytes();
    mine.cells = prepared_->tets.cellCount();
    result.ranks = comm_->allGatherValues(mine);
    double slowest = 0.0;
    for (const RankFrameStats& r : result.ranks)
        slowest = std::max(slowest, r.frameSeconds + r.compositeSeconds);
    result.stats.seconds = slowest;
    return result;
}

RenderResult Renderer::renderLocal(const RenderSettings& settings) {
    // Smooth shading's gradients are made when a frame first needs them (shaded, a gradient
    // opacity, or the isosurfaces' normals) and kept, remade with new values.
    const bool lit =
        readsGradient(settings.lighting, settings.gradientOpacity) || !settings.isoSurfaces.empty();
    if (lit && settings.lighting.smooth && !hasSmoothGradients(prepared_->tets)) {
        computeSmoothGradients(prepared_->tets);
        if (gpu_) gpu_->uploadGradients();
    }
    return gpu_ ? gpu_->render(settings) : renderCpu(*prepared_, settings);
}

void Renderer::setFieldValues(const ScalarField& field) {
    if (!comm_) {
        updateFieldValues(*prepared_, field);
        if (gpu_) gpu_->updateValues();
        return;
    }
    // Data-parallel: this rank's share of the values (from the whole mesh's when it was made
    // from one), moved to the pieces that hold those points or cells.
    const bool cells = field.association == Association::Cell;
    const std::vector<std::uint64_t>& ids = cells ? wholeCellIds_ : wholePointIds_;
    ScalarField share;
    agreeOn(*comm_, [&] {
        if (!fromWhole_) return;  // made from a share: the share's values
        checkNewValueCount(field, cells ? wholeCellCount_ : wholePointCount_, "the mesh");
        share.name = field.name;
        share.association = field.association;
        share.choice = field.choice;
        share.values.reserve(ids.size());
        for (std::uint64_t i : ids) share.values.push_back(field.values[i]);
    });
    ScalarField piece = routeValues(*comm_, *routes_, fromWhole_ ? share : field);
    share = ScalarField();
    // The whole field's finite range, as distributeMesh reduced it.
    double range[2] = {INFINITY, INFINITY};
    for (float v : piece.values)
        if (std::isfinite(v))
            range[0] = std::min(range[0], double(v)), range[1] = std::min(range[1], -double(v));
    comm_->allReduce(range, ReduceOp::Min);
    auto whole = std::make_shared<MeshPiece>(*prepared_->piece);
    whole->valueMin = std::isfinite(range[0]) ? static_cast<float>(range[0]) : 0.f;
    whole->valueMax = std::isfinite(range[1]) ? static_cast<float>(-range[1]) : 0.f;
    agreeOn(*comm_, [&] {
        updateFieldValues(*prepared_, piece);
        prepared_->piece = std::move(whole);
        if (gpu_) gpu_->updateValues();
    });
}

std::optional<GpuResidency> Renderer::gpuResidency() const {
    if (!gpu_) return std::nullopt;
    return GpuResidency{gpu_->geometryBytes(), gpu_->uploadSeconds(), gpu_->valueUploadSeconds(),
                        buildPeakBytes_};
}

std::string Renderer::deviceDescription() const {
    if (gpu_) return cudaDeviceDescription();
    return "CPU, " + std::to_string(cpu::threadCount()) + " threads";
}

}  // namespace uvr
