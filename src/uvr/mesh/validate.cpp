// SPDX-License-Identifier: MIT
#include "uvr/mesh/validate.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <numeric>
#include <tuple>
#include <utility>

#include "uvr/core/error.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

namespace {

/// Cells (or points, or values) per chunk of the parallel loops: fixed, so every count and
/// "first" index is the same for any thread count.
constexpr std::int64_t kChunk = 1 << 14;

/// Chunks of kChunk items covering n items.
std::int64_t chunkCount(std::uint64_t n) {
    return static_cast<std::int64_t>((n + kChunk - 1) / kChunk);
}

/// Items [begin, end) of chunk c of n items.
std::pair<std::uint64_t, std::uint64_t> chunkRange(std::int64_t c, std::uint64_t n) {
    const std::uint64_t begin = std::uint64_t(c) * kChunk;
    return {begin, std::min<std::uint64_t>(n, begin + kChunk)};
}

/// A coordinate's bits for hashing, with -0 as +0 (they compare equal).
std::uint32_t coordinateBits(float x) {
    if (x == 0.f) x = 0.f;
    std::uint32_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    return bits;
}

/// Hash of a point's position: equal positions (as floats compare) hash alike.
std::uint64_t positionHash(const Vec3f& p) {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (float x : {p.x, p.y, p.z}) {
        h ^= coordinateBits(x);
        h *= 0xff51afd7ed558ccdull;
        h ^= h >> 32;
    }
    return h;
}

/// Points coincident with an earlier point (points minus distinct positions) among the
/// finite points: the points are bucketed by a hash of their position (equal positions share a
/// bucket), then each bucket is sorted by position and its equal neighbours counted. The count
/// does not depend on the order within a bucket, so the parallel filling is deterministic in
/// its result.
std::uint64_t countCoincidentPoints(const std::vector<Vec3f>& points) {
    const std::uint64_t n = points.size();
    if (n < 2) return 0;
    // About 16 points per bucket, a power of two.
    int bits = 0;
    while ((std::uint64_t(1) << bits) < n / 16 + 1) ++bits;
    const std::uint64_t buckets = std::uint64_t(1) << bits;
    const int shift = 64 - std::max(bits, 1);
    auto bucketOf = [&](std::uint64_t i) -> std::uint64_t {
        return bits == 0 ? 0 : positionHash(points[i]) >> shift;
    };
    std::vector<std::atomic<std::uint32_t>> fill(buckets + 1);
    const std::int64_t chunks = chunkCount(n);
#pragma omp parallel for schedule(static)
    for (std::int64_t c = 0; c < chunks; ++c) {
        const auto [begin, end] = chunkRange(c, n);
        for (std::uint64_t i = begin; i < end; ++i)
            if (isFinite(points[i])) fill[bucketOf(i) + 1].fetch_add(1, std::memory_order_relaxed);
    }
    std::vector<std::uint64_t> start(buckets + 1, 0);
    for (std::uint64_t b = 0; b < buckets; ++b) {
        start[b + 1] = start[b] + fill[b + 1].load(std::memory_order_relaxed);
        fill[b].store(0, std::memory_order_relaxed);
    }
    std::vector<std::uint32_t> order(start[buckets]);
#pragma omp parallel for schedule(static)
    for (std::int64_t c = 0; c < chunks; ++c) {
        const auto [begin, end] = chunkRange(c, n);
        for (std::uint64_t i = begin; i < end; ++i)
            if (isFinite(points[i])) {
                const std::uint64_t b = bucketOf(i);
                order[start[b] + fill[b].fetch_add(1, std::memory_order_relaxed)] =
                    static_cast<std::uint32_t>(i);
            }
    }
    auto key = [&](std::uint32_t i) {
        const Vec3f& p = points[i];
        return std::tuple<float, float, float>(p.x, p.y, p.z);
    };
    const std::int64_t bucketChunks = chunkCount(buckets);
    std::uint64_t coincident = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : coincident)
    for (std::int64_t c = 0; c < bucketChunks; ++c) {
        const auto [first, last] = chunkRange(c, buckets);
        for (std::uint64_t b = first; b < last; ++b) {
            const auto begin = order.begin() + std::int64_t(start[b]);
            const auto end = order.begin() + std::int64_t(start[b + 1]);
            std::sort(begin, end,
                      [&](std::uint32_t x, std::uint32_t y) { return key(x) < key(y); });
            for (auto it = begin; it != end && it + 1 != end; ++it)
                if (key(*it) == key(*(it + 1))) ++coincident;
        }
    }
    return coincident;
}

/// Whether cell c passes validateCells' checks of its type, offsets and point indices.
bool cellIsValid(const MeshView& mesh, std::uint64_t c) {
    const int corners = cornerCount(mesh.cellTypes[c]);
    if (corners == 0) return false;
    const std::uint64_t begin = mesh.cellOffsets[c], end = mesh.cellOffsets[c + 1];
    if (end < begin || end - begin != static_cast<std::uint64_t>(corners) ||
        end > mesh.cellIndices.size())
        return false;
    for (std::uint64_t i = begin; i < end; ++i)
        if (mesh.cellIndices[i] >= mesh.pointCount()) return false;
    return true;
}

}  // namespace

void validateCells(const MeshView& mesh, const std::string& file) {
    const std::uint64_t cells = mesh.cellCount();
    const std::uint64_t points = mesh.pointCount();
    const std::uint64_t indices = mesh.cellIndices.size();
    auto fail = [&](const std::string& message) {
        throwError(ErrorKind::Validation, file, message);
    };
    if (points > 0xffffffffull)
        throwError(ErrorKind::Unsupported, file,
                   std::to_string(points) + " points: at most 2^32 - 1 are supported");
    if (mesh.cellOffsets.size() != cells + 1)
        fail("cellOffsets has " + std::to_string(mesh.cellOffsets.size()) +
             " entries, expected cellCount + 1 = " + std::to_string(cells + 1));
    if (mesh.cellOffsets[0] != 0)
        fail("cell 0: offset " + std::to_string(mesh.cellOffsets[0]) + ", expected 0");
    // The first invalid cell, found in parallel (per chunk in cell order, then the least).
    const std::int64_t chunks = chunkCount(cells);
    std::uint64_t firstBad = cells;
#pragma omp parallel for schedule(dynamic, 1) reduction(min : firstBad)
    for (std::int64_t c = 0; c < chunks; ++c) {
        const auto [begin, end] = chunkRange(c, cells);
        for (std::uint64_t i = begin; i < end; ++i)
            if (!cellIsValid(mesh, i)) {
                firstBad = std::min(firstBad, i);
                break;
            }
    }
    if (firstBad < cells) {
        // Its message.
        const std::uint64_t c = firstBad;
        const int corners = cornerCount(mesh.cellTypes[c]);
        if (corners == 0)
            fail("cell " + std::to_string(c) + ": type " +
                 std::to_string(static_cast<unsigned>(mesh.cellTypes[c])) +
                 ", expected 10 (tetra), 12 (hexahedron), 13 (wedge) or 14 (pyramid)");
        const std::uint64_t begin = mesh.cellOffsets[c], end = mesh.cellOffsets[c + 1];
        if (end < begin || end - begin != static_cast<std::uint64_t>(corners) || end > indices)
            fail("cell " + std::to_string(c) + ": offsets " + std::to_string(begin) + ".." +
                 std::to_string(end) + " do not span the " + std::to_string(corners) +
                 " corners of a " + cellTypeName(mesh.cellTypes[c]) + " within " +
                 std::to_string(indices) + " indices");
        for (std::uint64_t i = begin; i < end; ++i)
            if (mesh.cellIndices[i] >= points)
                fail("cell " + std::to_string(c) + " (" + cellTypeName(mesh.cellTypes[c]) +
                     "): corner " + std::to_string(i - begin) + " is point " +
                     std::to_string(mesh.cellIndices[i]) + ", expected below pointCount " +
                     std::to_string(points));
    }
    if (mesh.cellOffsets[cells] != indices)
        fail("last cell offset " + std::to_string(mesh.cellOffsets[cells]) +
             ", expected indexCount " + std::to_string(indices));
}

void validateStructure(const Mesh& mesh, const std::string& file) {
    validateCells(mesh, file);
    const std::uint64_t cells = mesh.cellCount();
    const std::uint64_t points = mesh.pointCount();
    auto fail = [&](const std::string& message) {
        throwError(ErrorKind::Validation, file, message);
    };
    for (const Field& f : mesh.fields) {
        const std::uint64_t tuples = f.association == Association::Point ? points : cells;
        if (f.components < 1 ||
            f.values.size() != tuples * static_cast<std::uint64_t>(f.components))
            fail("field '" + f.name + "': " + std::to_string(f.values.size()) +
                 " values, expected " + std::to_string(tuples) + " " +
                 associationName(f.association) + " tuples x " + std::to_string(f.components) +
                 " components");
    }
}

ValidationReport validateMesh(const Mesh& mesh, const std::string& file,
                              const FractionFn& progress) {
    // Progress: the cells to 0.7, the points (coincident ones among them) to 0.9, fields to 1.
    constexpr double kCellsEnd = 0.7, kPointsEnd = 0.9;
    validateStructure(mesh, file);
    ValidationReport r;
    // Cell geometry (the same split the renderer uses), per fixed chunk of cells in parallel,
    // then merged in chunk order: counts add up, the first offending cell is the first chunk's
    // first, and bounds (min/max) do not depend on the order.
    const std::uint64_t cellCount = mesh.cellCount();
    const std::int64_t chunks = chunkCount(cellCount);
    struct Chunk {
        std::uint64_t count[3] = {0, 0, 0};  ///< inverted, zero-volume, distorted
        std::uint64_t first[3] = {0, 0, 0};
        Bounds3f bounds;
    };
    std::vector<Chunk> parts(chunks);
    std::vector<std::uint8_t> used(mesh.pointCount(), 0);
    ProgressCounter cellsDone(progress, chunks, 0.0, kCellsEnd);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        Chunk& s = parts[c];
        const auto [begin, end] = chunkRange(c, cellCount);
        for (std::uint64_t i = begin; i < end; ++i) {
            for (std::uint32_t id : mesh.cell(i))
                std::atomic_ref<std::uint8_t>(used[id]).store(1, std::memory_order_relaxed);
            const CellSplit split = splitCell(mesh, i);
            for (int t = 0; t < split.count; ++t)
                for (std::uint32_t v : split.tets[t].v) s.bounds.extend(mesh.points[v]);
            const int kind = split.shape == CellShape::Inverted     ? 0
                             : split.shape == CellShape::ZeroVolume ? 1
                             : split.shape == CellShape::Distorted  ? 2
                                                                    : -1;
            if (kind >= 0 && s.count[kind]++ == 0) s.first[kind] = i;
        }
        cellsDone.add();
    }
    cellsDone.finish();
    std::uint64_t* counts[3] = {&r.invertedCells, &r.zeroVolumeCells, &r.distortedCells};
    std::uint64_t* firsts[3] = {&r.firstInvertedCell, &r.firstZeroVolumeCell,
                                &r.firstDistortedCell};
    for (const Chunk& s : parts) {
        for (int k = 0; k < 3; ++k) {
            if (s.count[k] && *counts[k] == 0) *firsts[k] = s.first[k];
            *counts[k] += s.count[k];
        }
        r.bounds.extend(s.bounds);
    }
    // Points: unused, non-finite coordinates, and coincident positions.
    const std::uint64_t pointCount = mesh.pointCount();
    const std::int64_t pointChunks = chunkCount(pointCount);
    std::uint64_t unused = 0, nonFinite = 0;
#pragma omp parallel for schedule(static) reduction(+ : unused, nonFinite)
    for (std::int64_t c = 0; c < pointChunks; ++c) {
        const auto [begin, end] = chunkRange(c, pointCount);
        for (std::uint64_t i = begin; i < end; ++i) {
            unused += used[i] == 0;
            nonFinite += !isFinite(mesh.points[i]);
        }
    }
    r.unusedPoints = unused;
    r.nonFinitePoints = nonFinite;
    r.coincidentPoints = countCoincidentPoints(mesh.points);
    if (progress) progress(kPointsEnd);
    // Fields: per chunk the count and first non-finite value.
    for (const Field& f : mesh.fields) {
        const std::uint64_t n = f.values.size();
        const std::int64_t valueChunks = chunkCount(n);
        std::uint64_t count = 0, first = n;
#pragma omp parallel for schedule(static) reduction(+ : count) reduction(min : first)
        for (std::int64_t c = 0; c < valueChunks; ++c) {
            const auto [begin, end] = chunkRange(c, n);
            for (std::uint64_t i = begin; i < end; ++i)
                if (!std::isfinite(f.values[i])) {
                    ++count;
                    first = std::min(first, i);
                }
        }
        if (count)
            r.nonFiniteFields.push_back(
                {f.name, f.association, count, first / static_cast<std::uint64_t>(f.components)});
    }
    if (progress) progress(1.0);
    return r;
}

std::vector<ValidationFinding> ValidationReport::structuredFindings() const {
    std::vector<ValidationFinding> out;
    auto cells = [&](const char* code, std::uint64_t n, const char* what, std::uint64_t first,
                     const char* action) {
        if (n)
            out.push_back({code, n, "cell", first, "", action,
                           std::to_string(n) + " " + what + " cell(s) (first: cell " +
                               std::to_string(first) + "): " + action});
    };
    cells("inverted_cells", invertedCells, "inverted", firstInvertedCell,
          "re-oriented for rendering");
    cells("zero_volume_cells", zeroVolumeCells, "zero-volume", firstZeroVolumeCell,
          "they contribute nothing");
    cells("distorted_cells", distortedCells, "distorted (twisted or non-convex)",
          firstDistortedCell, "split tetrahedra re-oriented individually");
    if (coincidentPoints)
        out.push_back({"coincident_points", coincidentPoints, "", 0, "", "",
                       std::to_string(coincidentPoints) +
                           " coincident point(s) (same position as an earlier point)"});
    if (nonFinitePoints)
        out.push_back({"non_finite_points", nonFinitePoints, "", 0, "",
                       "cells using them are dropped (the bounds leave them out)",
                       std::to_string(nonFinitePoints) +
                           " point(s) with NaN/Inf coordinates: cells using them are dropped (the "
                           "bounds leave them out)"});
    if (unusedPoints)
        out.push_back({"unused_points", unusedPoints, "", 0, "", "the bounds leave them out",
                       std::to_string(unusedPoints) +
                           " point(s) used by no cell (the bounds leave them out)"});
    for (const NonFiniteField& f : nonFiniteFields)
        out.push_back({"non_finite_field_values", f.count, associationName(f.association),
                       f.firstTuple, f.name, "rendered transparent",
                       std::string(associationName(f.association)) + " field '" + f.name +
                           "': " + std::to_string(f.count) + " NaN/Inf value(s) (first at " +
                           associationName(f.association) + " " + std::to_string(f.firstTuple) +
                           "): rendered transparent"});
    return out;
}

std::vector<std::string> ValidationReport::findings() const {
    std::vector<std::string> out;
    for (const ValidationFinding& f : structuredFindings()) out.push_back(f.message);
    return out;
}

}  // namespace uvr
