// SPDX-License-Identifier: MIT
// Benchmarks of mesh preparation (whole and step by step, with 1 or 2 threads), refinement and
// the CPU reference marcher on procedural meshes.
// Record results in docs/PERFORMANCE.md with device, commit, date and command.
#include <benchmark/benchmark.h>

#include <map>

#include "uvr/accel/tet_adjacency.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/cpu/threads.h"
#include "uvr/uvr.h"

namespace {

const uvr::Mesh& boxMesh(std::uint64_t cells) {
    static std::map<std::uint64_t, uvr::Mesh> cache;
    auto it = cache.find(cells);
    if (it == cache.end()) {
        uvr::ProceduralSpec spec;
        spec.targetCells = cells;
        it = cache.emplace(cells, uvr::generateMesh(spec)).first;
    }
    return it->second;
}

void BM_Generate(benchmark::State& state) {
    uvr::ProceduralSpec spec;
    spec.targetCells = static_cast<std::uint64_t>(state.range(0));
    for (auto _ : state) benchmark::DoNotOptimize(uvr::generateMesh(spec));
    state.counters["tets"] = static_cast<double>(spec.targetCells);
}

void BM_Prepare(benchmark::State& state) {
    const uvr::Mesh& mesh = boxMesh(static_cast<std::uint64_t>(state.range(0)));
    const uvr::ScalarField field = uvr::selectScalarField(mesh, {});
    for (auto _ : state) benchmark::DoNotOptimize(uvr::prepareMesh(mesh, field));
    state.counters["tets/s"] = benchmark::Counter(static_cast<double>(mesh.cellCount()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

void BM_RenderReference(benchmark::State& state) {
    const uvr::Mesh& mesh = boxMesh(static_cast<std::uint64_t>(state.range(0)));
    const uvr::PreparedMesh prepared = uvr::prepareMesh(mesh, uvr::selectScalarField(mesh, {}));
    uvr::RenderSettings settings;
    settings.width = settings.height = static_cast<int>(state.range(1));
    settings.tf = uvr::transferFunctionPreset("cool-to-warm");
    std::uint64_t samples = 0;
    for (auto _ : state) {
        const uvr::RenderResult r = uvr::renderCpu(prepared, settings);
        samples += r.stats.samples;
        state.SetIterationTime(r.stats.seconds);
    }
    state.counters["samples/s"] =
        benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
}

void BM_KdBuild(benchmark::State& state) {
    const uvr::Mesh& mesh = boxMesh(static_cast<std::uint64_t>(state.range(0)));
    uvr::PrepareOptions options;
    options.partitions = false;
    const uvr::PreparedMesh prepared =
        uvr::prepareMesh(mesh, uvr::selectScalarField(mesh, {}), options);
    std::size_t partitions = 0;
    for (auto _ : state) partitions = uvr::buildKdPartitions(prepared.tets).partitions.size();
    state.counters["partitions"] = static_cast<double>(partitions);
    state.counters["tets/s"] = benchmark::Counter(static_cast<double>(mesh.cellCount()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

/// Tetrahedra of a box mesh of about `cells` tetrahedra (split, no BVH), cached.
const uvr::TetMesh& boxTets(std::uint64_t cells) {
    static std::map<std::uint64_t, uvr::TetMesh> cache;
    auto it = cache.find(cells);
    if (it == cache.end()) {
        const uvr::Mesh& mesh = boxMesh(cells);
        it =
            cache.emplace(cells, uvr::tetrahedralize(mesh, uvr::selectScalarField(mesh, {}))).first;
    }
    return it->second;
}

/// Sets the thread count from a benchmark argument for the scope of one case.
struct Threads {
    explicit Threads(std::int64_t n) { uvr::cpu::setThreadCount(static_cast<int>(n)); }
    ~Threads() { uvr::cpu::setThreadCount(0); }
};

/// Preparation steps one at a time (args: tetrahedra, threads): splitting cells, per-tet boxes
/// plus the BVH, face neighbours, k-d partitions (65536 cells per leaf, the CUDA default).
void BM_PrepSplit(benchmark::State& state) {
    const uvr::Mesh& mesh = boxMesh(static_cast<std::uint64_t>(state.range(0)));
    const uvr::ScalarField field = uvr::selectScalarField(mesh, {});
    const Threads threads(state.range(1));
    for (auto _ : state) benchmark::DoNotOptimize(uvr::tetrahedralize(mesh, field));
    state.counters["tets/s"] = benchmark::Counter(static_cast<double>(mesh.cellCount()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

void BM_PrepBvh(benchmark::State& state) {
    const uvr::TetMesh& tets = boxTets(static_cast<std::uint64_t>(state.range(0)));
    const Threads threads(state.range(1));
    for (auto _ : state) {
        std::vector<uvr::Bounds3f> boxes;
        std::vector<uvr::Vec3f> centers;
        uvr::tetBoxesAndCenters(tets, boxes, centers);
        benchmark::DoNotOptimize(uvr::buildBvh(boxes, centers));
    }
    state.counters["tets/s"] = benchmark::Counter(static_cast<double>(tets.tets.size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

void BM_PrepNeighbors(benchmark::State& state) {
    const uvr::TetMesh& tets = boxTets(static_cast<std::uint64_t>(state.range(0)));
    const Threads threads(state.range(1));
    for (auto _ : state) benchmark::DoNotOptimize(uvr::buildTetNeighbors(tets));
    state.counters["tets/s"] = benchmark::Counter(static_cast<double>(tets.tets.size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

void BM_PrepKd(benchmark::State& state) {
    const uvr::TetMesh& tets = boxTets(static_cast<std::uint64_t>(state.range(0)));
    const Threads threads(state.range(1));
    uvr::KdBuildOptions options;
    options.leafCells = 65536;
    for (auto _ : state) benchmark::DoNotOptimize(uvr::buildKdPartitions(tets, options));
    state.counters["tets/s"] = benchmark::Counter(static_cast<double>(tets.tets.size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

/// Red refinement (args: source tetrahedra, levels, threads); output tetrahedra per second.
void BM_Refine(benchmark::State& state) {
    const uvr::Mesh& mesh = boxMesh(static_cast<std::uint64_t>(state.range(0)));
    const int levels = static_cast<int>(state.range(1));
    const Threads threads(state.range(2));
    std::uint64_t out = 0;
    for (auto _ : state) out = uvr::refineMesh(mesh, levels).cellCount();
    state.counters["out tets/s"] =
        benchmark::Counter(static_cast<double>(out), benchmark::Counter::kIsIterationInvariantRate);
}

/// Transfer-function update (Morrical et al. 2019, Sec. 2.1): range tables of the baked table,
/// and breakpoints of the baked table, then maximum opacity, rate, variance and step of every
/// partition; one thread.
void BM_TfUpdate(benchmark::State& state) {
    const uvr::Mesh& mesh = boxMesh(static_cast<std::uint64_t>(state.range(0)));
    uvr::PrepareOptions options;
    options.kd.leafCells = static_cast<std::uint32_t>(state.range(1));
    const uvr::PreparedMesh prepared =
        uvr::prepareMesh(mesh, uvr::selectScalarField(mesh, {}), options);
    uvr::TransferFunction tf = uvr::transferFunctionPreset("cool-to-warm");
    const std::vector<uvr::Vec4f> baked = tf.bake(1024);
    const uvr::TfTableView table{baked.data(), 1024, prepared.tets.valueMin,
                                 prepared.tets.valueMax};
    uvr::StepRuleParams rule;
    rule.s1 = 0.01f;
    rule.s2 = 0.16f;
    rule.valuePerEntry = (table.hi - table.lo) / 1023.f;
    for (auto _ : state) {
        const uvr::TfRangeTables ranges(table);
        const std::vector<std::int32_t> breaks = uvr::tfTableBreaks(baked.data(), 1024);
        benchmark::DoNotOptimize(breaks.data());
        benchmark::DoNotOptimize(uvr::computePartitionShading(*prepared.kd, prepared.gradientSpread,
                                                              ranges.view(table), rule));
    }
    state.counters["partitions"] = static_cast<double>(prepared.kd->partitions.size());
}

}  // namespace

BENCHMARK(BM_KdBuild)->Arg(1000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TfUpdate)->Args({1000, 64})->Args({1000000, 512})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PrepSplit)
    ->Args({1000, 1})
    ->ArgsProduct({{1000000}, {1, 2}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PrepBvh)
    ->Args({1000, 1})
    ->ArgsProduct({{1000000}, {1, 2}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PrepNeighbors)
    ->Args({1000, 1})
    ->ArgsProduct({{1000000}, {1, 2}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PrepKd)
    ->Args({1000, 1})
    ->ArgsProduct({{1000000}, {1, 2}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Refine)
    ->Args({1000, 1, 1})
    ->ArgsProduct({{100000}, {2}, {1, 2}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Generate)->Arg(1000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Prepare)->Arg(1000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RenderReference)
    ->Args({1000, 32})
    ->Args({1000000, 512})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
