// SPDX-License-Identifier: MIT
#include "uvr/cpu/cpu_renderer.h"

#include <omp.h>

#include <chrono>
#include <vector>

#include "uvr/cpu/parallel_for.h"
#include "uvr/render/frame_kernel.h"

namespace uvr {

namespace cpu {
int threadCount() { return omp_get_max_threads(); }
int currentThread() { return omp_get_thread_num(); }
}  // namespace cpu

RenderResult renderReferenceCpu(const PreparedMesh& mesh, const RenderSettings& settings) {
    RenderResult result;
    result.setup = makeFrameSetup(mesh, settings);
    const SceneView scene = result.setup.scene(mesh);
    result.image = Image(settings.width, settings.height);
    result.sampleCounts.assign(result.image.pixels.size(), 0);
    FrameView frame{result.image.pixels.data(), result.sampleCounts.data(), settings.width,
                    settings.height, result.setup.rays};
    std::vector<RayCounters> perThread(cpu::threadCount());
    const auto start = std::chrono::steady_clock::now();
    // Tiles of 8x8 pixels keep neighbouring rays (and their tetrahedra) on one core.
    constexpr int kTile = 8;
    const int tilesX = (settings.width + kTile - 1) / kTile;
    const int tilesY = (settings.height + kTile - 1) / kTile;
    cpu::parallelFor(std::int64_t(tilesX) * tilesY, 1, [&](std::int64_t tile, int thread) {
        const int x0 = static_cast<int>(tile % tilesX) * kTile;
        const int y0 = static_cast<int>(tile / tilesX) * kTile;
        RayCounters& counters = perThread[thread];
        for (int y = y0; y < y0 + kTile && y < frame.height; ++y)
            for (int x = x0; x < x0 + kTile && x < frame.width; ++x)
                referencePixel(scene, frame, x, y, counters);
    });
    result.stats.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.stats.width = settings.width;
    result.stats.height = settings.height;
    for (std::uint32_t s : result.sampleCounts) result.stats.samples += s;
    for (const RayCounters& c : perThread) {
        result.stats.walkSteps += c.locate.walkSteps;
        result.stats.bvhQueries += c.locate.bvhQueries;
    }
    return result;
}

}  // namespace uvr
