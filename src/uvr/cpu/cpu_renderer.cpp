// SPDX-License-Identifier: MIT
#include "uvr/cpu/cpu_renderer.h"

#include <omp.h>

#include <chrono>
#include <vector>

#include "uvr/cpu/parallel_for.h"
#include "uvr/render/frame_kernel.h"

namespace uvr {

namespace cpu {
int threadCount() {
    return omp_get_max_threads();
}
int maxThreadCount() {
    const int procs = omp_get_num_procs();
    return procs >= 256 ? 1024 : (procs >= 16 ? 4 * procs : 64);
}
void setThreadCount(int n) {
    const int cap = maxThreadCount();
    omp_set_num_threads(n >= 1 ? (n < cap ? n : cap) : omp_get_num_procs());
}
int currentThread() {
    return omp_get_thread_num();
}
}  // namespace cpu

namespace {

/// Runs the pixel kernel over the frame in 8x8 tiles (neighbouring rays, and their
/// tetrahedra, stay on one core), sums the counters and reports the tiles done. With several
/// marches (a split frame: launchPartitionMarches) each pixel runs each in turn.
template <class... March>
void launchFrame(const FrameView& frame, RenderStats& stats,
                 const std::function<void(double)>& report, const March&... marches) {
    std::vector<RenderStats> perThread(cpu::threadCount());
    constexpr int kTile = 8;
    const int tilesX = (frame.width + kTile - 1) / kTile;
    const int tilesY = (frame.height + kTile - 1) / kTile;
    ProgressCounter progress(report, std::int64_t(tilesX) * tilesY);
    cpu::parallelFor(std::int64_t(tilesX) * tilesY, 1, [&](std::int64_t tile, int thread) {
        const int x0 = static_cast<int>(tile % tilesX) * kTile;
        const int y0 = static_cast<int>(tile / tilesX) * kTile;
        RenderStats& s = perThread[thread];
        for (int y = y0; y < y0 + kTile && y < frame.height; ++y)
            for (int x = x0; x < x0 + kTile && x < frame.width; ++x)
                (s.add(frame.supersample == 1 ? shadePixel<false>(frame, x, y, marches)
                                              : shadePixel<true>(frame, x, y, marches)),
                 ...);
        progress.add();
    });
    progress.finish();
    for (const RenderStats& s : perThread) stats.merge(s);
}

}  // namespace

RenderResult renderCpu(const PreparedMesh& mesh, const RenderSettings& settings) {
    RenderResult result;
    result.setup = makeFrameSetup(mesh, settings);
    result.image = Image(settings.width, settings.height);
    result.sampleCounts.assign(result.image.pixels.size(), 0);
    if (settings.depthAlpha > 0.f) result.depth.assign(result.image.pixels.size(), INFINITY);
    const FrameView frame = makeFrameView(
        settings, result.setup, result.image.pixels.data(), result.sampleCounts.data(),
        result.depth.empty() ? nullptr : result.depth.data(),
        settings.depthIn.empty() ? nullptr : settings.depthIn.data(),
        settings.pixelStopAlpha.empty() ? nullptr : settings.pixelStopAlpha.data(),
        settings.pixelDepthAlpha.empty() ? nullptr : settings.pixelDepthAlpha.data());
    const auto start = std::chrono::steady_clock::now();
    dispatchKernel(
        mesh.tets.hasNative(), litKernel(result.setup.params), surfacesKernel(result.setup.params),
        [&](auto kNative, auto kLit, auto kSurf) {
            const RenderMethod method = result.setup.method.method;
            if (method == RenderMethod::Reference)
                launchFrame(frame, result.stats, settings.progress,
                            ReferenceMarch<kNative(), kLit(), kSurf()>{result.setup.scene(mesh)});
            else if (method == RenderMethod::Exact)
                launchFrame(frame, result.stats, settings.progress,
                            ExactMarch<kNative(), kLit(), kSurf()>{result.setup.scene(mesh)});
            else
                launchPartitionMarches<kNative(), kLit(), kSurf()>(
                    result.setup.partitionScene(mesh, settings.skip),
                    isoRaySplit(result.setup.params, frame), [&](const auto&... marches) {
                        launchFrame(frame, result.stats, settings.progress, marches...);
                    });
        });
    result.stats.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.stats.width = settings.width;
    result.stats.height = settings.height;
    result.stats.supersample = settings.supersample;
    return result;
}

}  // namespace uvr
