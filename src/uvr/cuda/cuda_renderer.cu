// SPDX-License-Identifier: MIT
// The CUDA backend: device memory, uploads and launches only; every ray's math is the shared
// UVR_HOST_DEVICE code of render/ (GUIDE.md §2).
#include "uvr/cuda/cuda_renderer.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <thread>

#include "uvr/core/error.h"
#include "uvr/core/setting_error.h"
#include "uvr/cuda/cuda_check.h"
#include "uvr/cuda/frame_launch.cuh"
#include "uvr/cuda/launch.cuh"
#include "uvr/render/frame_kernel.h"

namespace uvr {

namespace cuda {

namespace {

/// Walk length on the GPU before the BVH takes over.
constexpr int kGpuMaxWalkSteps = 64;

/// Transfer-function update, pass 1 (one element per partition): range statistics, and the
/// minimum and maximum variance over the visible partitions (as ordered bit patterns: variances
/// are non-negative, so their float bits order like unsigned integers).
struct PartitionStats {
    TfRangeView range;
    const KdPartition* partitions;
    RangeStats* stats;
    unsigned* varianceBounds;
    __device__ void operator()(std::uint64_t p) const {
        const RangeStats st = range.query(partitions[p].valueMin, partitions[p].valueMax);
        stats[p] = st;
        if (st.maxOpacity > 0.f) {
            atomicMin(&varianceBounds[0], __float_as_uint(st.variance));
            atomicMax(&varianceBounds[1], __float_as_uint(st.variance));
        }
    }
};

/// Transfer-function update, pass 2: the shared per-partition shading.
struct PartitionShade {
    const RangeStats* stats;
    const float* gradientSpread;
    const unsigned* varianceBounds;
    StepRuleParams rule;
    PartitionShading* shading;
    __device__ void operator()(std::uint64_t p) const {
        const float lo = __uint_as_float(varianceBounds[0]);
        const float hi = __uint_as_float(varianceBounds[1]);
        shading[p] = shadePartition(stats[p], gradientSpread[p], lo, hi, rule);
    }
};

/// Transfer-function update, macrocells (one element per macrocell): the error-bound shading.
struct MacroShade {
    TfRangeView range;
    const MacroCell* cells;
    StepRuleParams rule;
    PartitionShading* shading;
    __device__ void operator()(std::uint64_t c) const {
        shading[c] = shadeMacroCell(cells[c], range, rule);
    }
};

/// Transfer-function update, NaN values (one element per partition or macrocell): the shading
/// of those holding visible NaN values (shadeNan).
struct NanShade {
    const std::uint8_t* flags;
    float nanAlpha, s1;
    PartitionShading* shading;
    __device__ void operator()(std::uint64_t i) const {
        if (flags[i]) shadeNan(shading[i], nanAlpha, s1);
    }
};

/// Transfer-function update, isosurfaces (one element per partition): those an isosurface
/// crosses are visible and stepped at s1 (shadeIso).
struct PartitionIsoShade {
    const KdPartition* partitions;
    IsoView iso;
    float s1;
    PartitionShading* shading;
    __device__ void operator()(std::uint64_t p) const {
        shadeIso(shading[p], partitions[p].valueMin, partitions[p].valueMax, iso, s1);
    }
};

/// The same per macrocell.
struct MacroIsoShade {
    const MacroCell* cells;
    IsoView iso;
    float s1;
    PartitionShading* shading;
    __device__ void operator()(std::uint64_t c) const {
        shadeIso(shading[c], cells[c].valueMin, cells[c].valueMax, iso, s1);
    }
};

/// Transfer-function update, last pass (one element per partition): whether each partition
/// marches by its macrocells.
struct MacroChoice {
    const PartitionGrid* grids;
    const PartitionShading* cells;
    PartitionShading* shading;
    float* density;  ///< per partition: macroSampleDensity (weighReference's estimate)
    __device__ void operator()(std::uint64_t p) const {
        density[p] = macroSampleDensity(grids[p], cells);
        shading[p].byMacroCells = macroCellsPay(density[p], shading[p]);
    }
};

}  // namespace
}  // namespace cuda

namespace {

/// startCudaWarmUp's thread (joined at exit at the latest).
struct WarmUp {
    std::mutex mutex;
    std::thread thread;
    ~WarmUp() {
        if (thread.joinable()) thread.join();
    }
};

WarmUp& warmUp() {
    static WarmUp w;
    return w;
}

}  // namespace

void startCudaWarmUp() {
    WarmUp& w = warmUp();
    const std::lock_guard<std::mutex> lock(w.mutex);
    if (w.thread.joinable()) return;
    try {
        w.thread = std::thread([] {
            // The driver's initialisation and the primary context (cudaFree(0) creates it);
            // errors are left for the calls that need CUDA to report.
            int count = 0;
            if (cudaGetDeviceCount(&count) == cudaSuccess && count > 0) cudaFree(nullptr);
            cudaGetLastError();
        });
    } catch (...) {  // no thread: CUDA starts when first used, as without a warm-up
    }
}

void finishCudaWarmUp() {
    WarmUp& w = warmUp();
    const std::lock_guard<std::mutex> lock(w.mutex);
    if (w.thread.joinable()) w.thread.join();
}

bool cudaDeviceAvailable() {
    finishCudaWarmUp();
    int count = 0;
    return cudaGetDeviceCount(&count) == cudaSuccess && count > 0;
}

std::string cudaDeviceDescription() {
    finishCudaWarmUp();
    int count = 0;
    if (cudaGetDeviceCount(&count) != cudaSuccess || count == 0) {
        cudaGetLastError();
        return "none: no CUDA device found";
    }
    cudaDeviceProp prop{};
    UVR_CUDA_CHECK(cudaGetDeviceProperties(&prop, 0));
    char buf[sizeof prop.name + 128];  // the name, up to 256 bytes, and the figures
    std::snprintf(buf, sizeof buf, "%s, %.1f GiB, compute capability %d.%d, %d SMs", prop.name,
                  prop.totalGlobalMem / 1073741824.0, prop.major, prop.minor,
                  prop.multiProcessorCount);
    return buf;
}

struct CudaScene::Impl {
    const PreparedMesh& mesh;
    /// The prepared mesh's arrays (scene_arrays.h: declared and bound to the mesh once).
    SceneArrays<cuda::DeviceArray> a;
    // Per frame / transfer function.
    cuda::DeviceArray<Vec4f> tfTable;
    cuda::DeviceArray<std::int32_t> tfBreaks;
    cuda::DeviceArray<double> tfPrefix;
    cuda::DeviceArray<float> tfMaxLevels;
    cuda::DeviceArray<float> tfRateLevels;
    cuda::DeviceArray<RangeStats> partitionStats;
    cuda::DeviceArray<unsigned> varianceBounds;
    cuda::DeviceArray<PartitionShading> shading;
    cuda::DeviceArray<PartitionShading> macroShading;
    cuda::DeviceArray<float> macroDensity;  ///< per partition (MacroChoice)
    bool macroActive = false;  ///< macroShading holds this frame's shading (usesMacroCells)
    cuda::DeviceArray<Vec4f> pixels;
    cuda::DeviceArray<std::uint32_t> sampleCounts;
    cuda::DeviceArray<float> depth;        ///< depth out (RenderSettings::depthAlpha)
    cuda::DeviceArray<float> depthIn;      ///< depth in (RenderSettings::depthIn)
    cuda::DeviceArray<float> stopAlpha;    ///< stop in (RenderSettings::pixelStopAlpha)
    cuda::DeviceArray<float> depthAlphas;  ///< depth alpha in (RenderSettings::pixelDepthAlpha)
    cuda::DeviceArray<unsigned long long> totals;
    cuda::PinnedBuffer readBack;  ///< the frame's image, counts and depth on their way back
    double uploadSeconds = 0.0;
    double valueUploadSeconds = 0.0;

    explicit Impl(const PreparedMesh& m) : mesh(m) {}

    /// Uploads the arrays of `use` (forEachSceneArray; the constructor's and updateValues' one
    /// code path); one the mesh no longer has (a NaN flag array the field no longer needs) is
    /// freed. `uploaded` hears each array's upload.
    template <class Done>
    void upload(ArrayUse use, Done&& uploaded) {
        forEachSceneArray(mesh, a,
                          [&](auto& device, const auto* host, const char* name, ArrayUse u) {
                              if (u != use) return;
                              if (host)
                                  device.upload(*host, name);
                              else
                                  device.clear();
                              uploaded();
                          });
    }

    /// The host scene view with every pointer replaced by its device copy (the mesh's arrays
    /// through scene_arrays.h's table, the frame's transfer function here).
    SceneView deviceScene(const FrameSetup& setup) const {
        SceneView v = setup.scene(mesh);
        pointAtArrays(v, a);
        v.tf.entries = tfTable.data();
        v.tf.breaks = tfBreaks.data();
        return v;
    }

    /// The adaptive method's view on the device: as deviceScene, with this frame's shading and
    /// macrocells, and the GPU's walking limits.
    PartitionSceneView devicePartitionScene(const FrameSetup& setup, bool skip) const {
        PartitionSceneView v = setup.partitionScene(mesh, skip);
        pointAtArrays(v, a);
        v.base.tf.entries = tfTable.data();
        v.base.tf.breaks = tfBreaks.data();
        v.shading = shading.data();
        v.macro = macroActive ? MacroShadingView{a.macroGrids.data(), macroShading.data()}
                              : MacroShadingView{};
        if (!mesh.seeds) v.longStep = INFINITY;  // without seeds, walking beats BVH searches
        v.base.locator.maxWalkSteps = cuda::kGpuMaxWalkSteps;
        return v;
    }
};

CudaScene::CudaScene(const PreparedMesh& mesh, const FractionFn& progress)
    : impl_(std::make_unique<Impl>(mesh)) {
    if (!cudaDeviceAvailable())
        throw SettingError("device", "cuda", "no CUDA device found", ErrorKind::Unsupported);
    const auto start = std::chrono::steady_clock::now();
    Impl& d = *impl_;
    const double total = double(std::max<std::uint64_t>(1, cudaSceneBytes(mesh)));
    auto uploaded = [&] {
        if (progress) progress(std::min(0.99, double(geometryBytes()) / total));
    };
    d.upload(ArrayUse::Geometry, uploaded);
    d.upload(ArrayUse::Values, uploaded);
    d.upload(ArrayUse::Gradients, uploaded);
    d.totals.reserve(cuda::kCounters, "the frame counters");
    UVR_CUDA_CHECK(cudaDeviceSynchronize());
    d.uploadSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (progress) progress(1.0);
}

CudaScene::~CudaScene() = default;

std::uint64_t CudaScene::geometryBytes() const {
    const Impl& d = *impl_;
    std::uint64_t n = 0;
    forEachSceneArray(d.mesh, d.a, [&](const auto& device, const auto*, const char*, ArrayUse) {
        n += device.bytes();
    });
    return n;
}

double CudaScene::uploadSeconds() const {
    return impl_->uploadSeconds;
}

void CudaScene::updateValues() {
    const auto start = std::chrono::steady_clock::now();
    impl_->upload(ArrayUse::Values, [] {});
    impl_->upload(ArrayUse::Gradients, [] {});  // remade from the new values (or absent)
    UVR_CUDA_CHECK(cudaDeviceSynchronize());
    impl_->valueUploadSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void CudaScene::uploadGradients() {
    impl_->upload(ArrayUse::Gradients, [] {});
    UVR_CUDA_CHECK(cudaDeviceSynchronize());
}

double CudaScene::valueUploadSeconds() const {
    return impl_->valueUploadSeconds;
}

void CudaScene::updateShading(RenderResult& result) {
    Impl& d = *impl_;
    const auto start = std::chrono::steady_clock::now();
    FrameSetup& f = result.setup;
    const std::uint32_t n = static_cast<std::uint32_t>(d.mesh.kd->partitions.size());
    // Range tables of the baked table (O(entries log entries) on the host, ~100 KB up).
    const TfTableView hostTable = f.tfView();
    const TfRangeTables tables(hostTable);
    d.tfPrefix.upload(tables.prefix, "the transfer-function prefix sums");
    d.tfMaxLevels.upload(tables.maxLevels, "the transfer-function maxima");
    d.tfRateLevels.upload(tables.rateLevels, "the transfer-function rates");
    TfRangeView range = tables.view(hostTable);
    range.table.entries = d.tfTable.data();
    range.table.breaks = d.tfBreaks.data();
    range.prefix = d.tfPrefix.data();
    range.maxLevels = d.tfMaxLevels.data();
    range.rateLevels = d.tfRateLevels.data();
    d.partitionStats.reserve(n, "the partition statistics");
    d.varianceBounds.upload(std::vector<unsigned>{0x7f800000u, 0u}, "the variance bounds");
    d.shading.reserve(n, "the partition shading");
    cuda::forEachElement("partition statistics", n,
                         cuda::PartitionStats{range, d.a.partitions.data(), d.partitionStats.data(),
                                              d.varianceBounds.data()});
    cuda::forEachElement(
        "partition shading", n,
        cuda::PartitionShade{d.partitionStats.data(), d.a.gradientSpread.data(),
                             d.varianceBounds.data(), f.stepRule, d.shading.data()});
    if (!d.mesh.partitionNan.empty())
        cuda::forEachElement(
            "partition NaN shading", n,
            cuda::NanShade{d.a.partitionNan.data(), f.tfNan.w, f.stepRule.s1, d.shading.data()});
    if (f.params.iso.active())
        cuda::forEachElement("partition isosurface shading", n,
                             cuda::PartitionIsoShade{d.a.partitions.data(), f.params.iso,
                                                     f.stepRule.s1, d.shading.data()});
    // The macrocells' shading stays on the GPU.
    d.macroActive = false;
    if (usesMacroCells(d.mesh, f.stepRule)) {
        const std::uint32_t m = static_cast<std::uint32_t>(d.mesh.macro->cells.size());
        d.macroShading.reserve(m, "the macrocell shading");
        cuda::forEachElement(
            "macrocell shading", m,
            cuda::MacroShade{range, d.a.macroCells.data(), f.stepRule, d.macroShading.data()});
        if (!d.mesh.macro->nanCells.empty())
            cuda::forEachElement("macrocell NaN shading", m,
                                 cuda::NanShade{d.a.macroNan.data(), f.tfNan.w, f.stepRule.s1,
                                                d.macroShading.data()});
        if (f.params.iso.active())
            cuda::forEachElement("macrocell isosurface shading", m,
                                 cuda::MacroIsoShade{d.a.macroCells.data(), f.params.iso,
                                                     f.stepRule.s1, d.macroShading.data()});
        d.macroDensity.reserve(n, "the partitions' macrocell sample densities");
        cuda::forEachElement("macrocell choice", n,
                             cuda::MacroChoice{d.a.macroGrids.data(), d.macroShading.data(),
                                               d.shading.data(), d.macroDensity.data()});
        d.macroActive = true;
    }
    f.shading.resize(n);
    UVR_CUDA_CHECK(cudaMemcpy(f.shading.data(), d.shading.data(), n * sizeof(PartitionShading),
                              cudaMemcpyDeviceToHost));
    if (f.method.weighReference > 0.0) {
        std::vector<float> density(d.macroActive ? n : 0);
        if (d.macroActive)
            UVR_CUDA_CHECK(cudaMemcpy(density.data(), d.macroDensity.data(), n * sizeof(float),
                                      cudaMemcpyDeviceToHost));
        weighReference(f, d.mesh, density, /*gpu=*/true);
    }
    f.tfUpdateSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

RenderResult CudaScene::render(const RenderSettings& settings) {
    Impl& d = *impl_;
    RenderResult result;
    result.setup = makeFrameSetup(d.mesh, settings, /*gpu=*/true);
    // Transfer-function state: the only per-change upload (a few kilobytes).
    d.tfTable.upload(result.setup.tfTable, "the transfer function");
    d.tfBreaks.upload(result.setup.tfBreaks, "the transfer function's breakpoints");
    const std::size_t pixelCount = static_cast<std::size_t>(settings.width) * settings.height;
    d.pixels.reserve(pixelCount, "the image");
    d.sampleCounts.reserve(pixelCount, "the sample counts");
    const bool depthOut = settings.depthAlpha > 0.f;
    if (depthOut) d.depth.reserve(pixelCount, "the depth image");
    if (!settings.depthIn.empty()) d.depthIn.upload(settings.depthIn, "the depth image given");
    const bool stopIn = !settings.pixelStopAlpha.empty();
    if (stopIn) d.stopAlpha.upload(settings.pixelStopAlpha, "the pixels' stop opacities");
    const bool depthAlphaIn = !settings.pixelDepthAlpha.empty();
    if (depthAlphaIn) d.depthAlphas.upload(settings.pixelDepthAlpha, "the pixels' depth opacities");
    UVR_CUDA_CHECK(cudaMemset(d.totals.data(), 0, cuda::kCounters * sizeof(unsigned long long)));
    const FrameView frame = makeFrameView(
        settings, result.setup, d.pixels.data(), d.sampleCounts.data(),
        depthOut ? d.depth.data() : nullptr, settings.depthIn.empty() ? nullptr : d.depthIn.data(),
        stopIn ? d.stopAlpha.data() : nullptr, depthAlphaIn ? d.depthAlphas.data() : nullptr);
    const dim3 block(16, cuda::kFrameBlock / 16);
    const dim3 grid((settings.width + block.x - 1) / block.x,
                    (settings.height + block.y - 1) / block.y);
    if (result.setup.method.method == RenderMethod::Partitions && !d.mesh.kd)
        throwError(ErrorKind::Argument, "", "the partition method needs k-d partitions");
    // The transfer function's partition shading is timed on its own (tfUpdateSeconds), as on
    // the CPU: the events time the frame kernel only. Auto may turn to the reference then.
    if (result.setup.method.method == RenderMethod::Partitions) updateShading(result);
    const RenderMethod method = result.setup.method.method;
    cudaEvent_t begin, end;
    UVR_CUDA_CHECK(cudaEventCreate(&begin));
    UVR_CUDA_CHECK(cudaEventCreate(&end));
    UVR_CUDA_CHECK(cudaEventRecord(begin));
    const bool native = d.mesh.tets.hasNative();
    const bool lit = litKernel(result.setup.params);
    const bool surfaces = surfacesKernel(result.setup.params);
    // One translation unit per method (frame_launch.cuh): their kernels compile in parallel.
    if (method == RenderMethod::Reference)
        cuda::launchReference(grid, block, frame, d.deviceScene(result.setup), native, lit,
                              surfaces, d.totals.data());
    else if (method == RenderMethod::Exact)
        cuda::launchExact(grid, block, frame, d.deviceScene(result.setup), native, lit, surfaces,
                          d.totals.data());
    else
        cuda::launchPartitions(grid, block, frame,
                               d.devicePartitionScene(result.setup, settings.skip), native, lit,
                               surfaces, d.totals.data());
    UVR_CUDA_CHECK(cudaEventRecord(end));
    // While the kernel runs: the result's host arrays (their pages touched now, not during the
    // copies), and the page-locked buffer the copies stage through.
    result.image = Image(settings.width, settings.height);
    result.sampleCounts.resize(pixelCount);
    if (depthOut) result.depth.resize(pixelCount);
    const std::size_t imageBytes = pixelCount * sizeof(Vec4f);
    const std::size_t countBytes = pixelCount * sizeof(std::uint32_t);
    const std::size_t depthBytes = depthOut ? pixelCount * sizeof(float) : 0;
    d.readBack.reserve(imageBytes + countBytes + depthBytes,
                       "cudaMallocHost(the frame's read-back)");
    UVR_CUDA_CHECK(cudaEventSynchronize(end));
    float ms = 0.f;
    UVR_CUDA_CHECK(cudaEventElapsedTime(&ms, begin, end));
    UVR_CUDA_CHECK(cudaEventDestroy(begin));
    UVR_CUDA_CHECK(cudaEventDestroy(end));
    // Results back to the host: at the bus's speed into page-locked memory (pageable memory
    // copies at a fraction of it), then into the result on the CPU threads.
    unsigned char* staged = d.readBack.data();
    UVR_CUDA_CHECK(cudaMemcpy(staged, d.pixels.data(), imageBytes, cudaMemcpyDeviceToHost));
    UVR_CUDA_CHECK(
        cudaMemcpy(staged + imageBytes, d.sampleCounts.data(), countBytes, cudaMemcpyDeviceToHost));
    if (depthOut)
        UVR_CUDA_CHECK(cudaMemcpy(staged + imageBytes + countBytes, d.depth.data(), depthBytes,
                                  cudaMemcpyDeviceToHost));
    unsigned char* const targets[3] = {reinterpret_cast<unsigned char*>(result.image.pixels.data()),
                                       reinterpret_cast<unsigned char*>(result.sampleCounts.data()),
                                       reinterpret_cast<unsigned char*>(result.depth.data())};
    const std::size_t sizes[3] = {imageBytes, countBytes, depthBytes};
    constexpr std::size_t kChunk = std::size_t(1) << 18;
    std::size_t chunks[4] = {0, 0, 0, 0};  // chunks before each array
    for (int a = 0; a < 3; ++a) chunks[a + 1] = chunks[a] + (sizes[a] + kChunk - 1) / kChunk;
#pragma omp parallel for schedule(static)
    for (std::int64_t c = 0; c < std::int64_t(chunks[3]); ++c) {
        int a = 0;
        while (std::size_t(c) >= chunks[a + 1]) ++a;
        const std::size_t at = (std::size_t(c) - chunks[a]) * kChunk;
        const std::size_t offset = a == 0 ? 0 : a == 1 ? imageBytes : imageBytes + countBytes;
        std::memcpy(targets[a] + at, staged + offset + at, std::min(kChunk, sizes[a] - at));
    }
    unsigned long long totals[cuda::kCounters];
    UVR_CUDA_CHECK(cudaMemcpy(totals, d.totals.data(), sizeof totals, cudaMemcpyDeviceToHost));
    result.stats.seconds = ms * 1e-3;
    result.stats.width = settings.width;
    result.stats.height = settings.height;
    result.stats.supersample = settings.supersample;
    result.stats.samples = totals[0];
    result.stats.walkSteps = totals[1];
    result.stats.bvhQueries = totals[2];
    result.stats.partitionsVisited = totals[3];
    result.stats.partitionsSkipped = totals[4];
    return result;
}

}  // namespace uvr
