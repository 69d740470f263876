// SPDX-License-Identifier: MIT
#include "uvr/mesh/refine.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>

#include "uvr/core/error.h"
#include "uvr/core/scratch_vector.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

namespace {

/// Items per parallel chunk (fixed, so results never depend on the thread count).
constexpr std::int64_t kChunk = 1 << 14;

/// Local corners of a tetrahedron split into 8: 0-3 the corners, 4-9 the midpoints of edges
/// 01, 02, 03, 12, 13, 23.
constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

/// The 8 children of a positively oriented tetrahedron for each choice of octahedron diagonal
/// (m01-m23, m02-m13, m03-m12), all positively oriented.
using Children = std::array<std::array<std::uint8_t, 4>, 8>;

/// Derives the child templates on the reference tetrahedron (0,0,0), (2,0,0), (0,2,0), (0,0,2)
/// with exact integer arithmetic; an affine map of positive determinant keeps orientations.
std::array<Children, 3> makeTemplates() {
    int p[10][3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}};
    for (int e = 0; e < 6; ++e)
        for (int k = 0; k < 3; ++k) p[4 + e][k] = (p[kEdges[e][0]][k] + p[kEdges[e][1]][k]) / 2;
    auto det = [&](const std::array<std::uint8_t, 4>& t) {
        int m[3][3];
        for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 3; ++k) m[r][k] = p[t[r + 1]][k] - p[t[0]][k];
        return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
               m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    };
    // Opposite midpoints of the octahedron (its three diagonals): edges sharing no corner.
    constexpr int kDiagonals[3][2] = {{4, 9}, {5, 8}, {6, 7}};
    std::array<Children, 3> out{};
    for (int d = 0; d < 3; ++d) {
        Children& c = out[d];
        c[0] = {0, 4, 5, 6};
        c[1] = {4, 1, 7, 8};
        c[2] = {5, 7, 2, 9};
        c[3] = {6, 8, 9, 3};
        // The equator: the other four midpoints in cyclic order (consecutive ones not opposite).
        int equator[4], n = 0;
        for (int o = 0; o < 3; ++o)
            if (o != d) equator[n++] = kDiagonals[o][0];
        for (int o = 0; o < 3; ++o)
            if (o != d) equator[n++] = kDiagonals[o][1];
        // equator = {x0, x1, y0, y1} with x_i opposite y_i: the cycle x0, x1, y0, y1.
        for (int i = 0; i < 4; ++i) {
            std::array<std::uint8_t, 4> t = {static_cast<std::uint8_t>(kDiagonals[d][0]),
                                             static_cast<std::uint8_t>(kDiagonals[d][1]),
                                             static_cast<std::uint8_t>(equator[i]),
                                             static_cast<std::uint8_t>(equator[(i + 1) % 4])};
            if (det(t) < 0) std::swap(t[2], t[3]);
            c[4 + i] = t;
        }
        for (const auto& t : c) UVR_CHECK(det(t) > 0, "refinement template not positive");
    }
    return out;
}

const std::array<Children, 3>& templates() {
    static const std::array<Children, 3> t = makeTemplates();
    return t;
}

/// A tetrahedral mesh being refined: points, tetrahedra and the point fields' values.
struct Work {
    std::vector<Vec3f> points;
    ScratchVector<Tet> tets;
    std::vector<Field> pointFields;
};

/// One level of red refinement of `w` in place.
void refineOnce(Work& w) {
    const std::int64_t pointCount = static_cast<std::int64_t>(w.points.size());
    const std::int64_t tetCount = static_cast<std::int64_t>(w.tets.size());
    // Step 1: edges bucketed by their smaller vertex (counting sort), each bucket sorted and made
    // unique; edge ids follow bucket order, so they do not depend on the thread count.
    std::vector<std::uint64_t> offsets(pointCount + 1, 0);
#pragma omp parallel for schedule(static)
    for (std::int64_t t = 0; t < tetCount; ++t)
        for (const auto& e : kEdges) {
            const std::uint32_t a = std::min(w.tets[t].v[e[0]], w.tets[t].v[e[1]]);
            std::atomic_ref<std::uint64_t>(offsets[a + 1]).fetch_add(1, std::memory_order_relaxed);
        }
    for (std::int64_t p = 0; p < pointCount; ++p) offsets[p + 1] += offsets[p];
    std::vector<std::uint32_t> ends(pointCount);  // end of the unique run of each bucket
    ScratchVector<std::uint32_t> other(offsets[pointCount]);
    {
        std::vector<std::uint64_t> fill(offsets.begin(), offsets.end() - 1);
#pragma omp parallel for schedule(static)
        for (std::int64_t t = 0; t < tetCount; ++t)
            for (const auto& e : kEdges) {
                const std::uint32_t a = w.tets[t].v[e[0]], b = w.tets[t].v[e[1]];
                const std::uint64_t at = std::atomic_ref<std::uint64_t>(fill[std::min(a, b)])
                                             .fetch_add(1, std::memory_order_relaxed);
                other[at] = std::max(a, b);
            }
    }
    std::vector<std::uint64_t> edgeBase(pointCount + 1, 0);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t start = 0; start < pointCount; start += kChunk)
        for (std::int64_t p = start; p < std::min(pointCount, start + kChunk); ++p) {
            std::uint32_t* first = other.data() + offsets[p];
            std::uint32_t* last = other.data() + offsets[p + 1];
            std::sort(first, last);
            const std::uint32_t unique =
                static_cast<std::uint32_t>(std::unique(first, last) - first);
            ends[p] = unique;
            edgeBase[p + 1] = unique;
        }
    for (std::int64_t p = 0; p < pointCount; ++p) edgeBase[p + 1] += edgeBase[p];
    const std::uint64_t edgeCount = edgeBase[pointCount];
    if (static_cast<std::uint64_t>(pointCount) + edgeCount >= 0xffffffffull)
        throwError(ErrorKind::Resource, "",
                   "refinement would make " + std::to_string(pointCount + edgeCount) +
                       " points (32-bit point indices)");
    // Step 2: midpoints and their interpolated point-field values.
    w.points.resize(pointCount + edgeCount);
    for (Field& f : w.pointFields) f.values.resize((pointCount + edgeCount) * f.components);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t start = 0; start < pointCount; start += kChunk)
        for (std::int64_t a = start; a < std::min(pointCount, start + kChunk); ++a)
            for (std::uint32_t k = 0; k < ends[a]; ++k) {
                const std::uint32_t b = other[offsets[a] + k];
                const std::uint64_t m = pointCount + edgeBase[a] + k;
                w.points[m] = (w.points[a] + w.points[b]) * 0.5f;
                for (Field& f : w.pointFields)
                    for (int c = 0; c < f.components; ++c)
                        f.values[m * f.components + c] =
                            0.5f * (f.values[a * f.components + c] +
                                    f.values[std::uint64_t(b) * f.components + c]);
            }
    // Step 3: the 8 children of each tetrahedron, in place of children 8t .. 8t+7.
    ScratchVector<Tet> children(static_cast<std::size_t>(8 * tetCount));
    const auto& tmpl = templates();
#pragma omp parallel for schedule(static)
    for (std::int64_t t = 0; t < tetCount; ++t) {
        std::uint32_t v[10];
        for (int i = 0; i < 4; ++i) v[i] = w.tets[t].v[i];
        for (int e = 0; e < 6; ++e) {
            const std::uint32_t a = std::min(v[kEdges[e][0]], v[kEdges[e][1]]);
            const std::uint32_t b = std::max(v[kEdges[e][0]], v[kEdges[e][1]]);
            const std::uint32_t* first = other.data() + offsets[a];
            const std::uint32_t k =
                static_cast<std::uint32_t>(std::lower_bound(first, first + ends[a], b) - first);
            v[4 + e] = static_cast<std::uint32_t>(pointCount + edgeBase[a] + k);
        }
        // The shortest octahedron diagonal (better shaped children); ties take the first.
        int best = 0;
        double bestLength = INFINITY;
        constexpr int kDiagonals[3][2] = {{4, 9}, {5, 8}, {6, 7}};
        for (int d = 0; d < 3; ++d) {
            const Vec3f p = w.points[v[kDiagonals[d][0]]], q = w.points[v[kDiagonals[d][1]]];
            const double dx = double(p.x) - q.x, dy = double(p.y) - q.y, dz = double(p.z) - q.z;
            const double length = dx * dx + dy * dy + dz * dz;
            if (length < bestLength) bestLength = length, best = d;
        }
        for (int c = 0; c < 8; ++c)
            for (int i = 0; i < 4; ++i) children[8 * t + c].v[i] = v[tmpl[best][c][i]];
    }
    w.tets = std::move(children);
}

}  // namespace

std::uint64_t refineMemoryBytes(const Mesh& mesh, std::uint64_t tets, int levels) {
    const std::uint64_t outTets = refinedTetCount(tets, levels);
    std::uint64_t inBytes =
        12 * mesh.pointCount() + 9 * mesh.cellCount() + 4 * mesh.cellIndices.size();
    std::uint64_t pointComps = 0, cellComps = 0;
    for (const Field& f : mesh.fields) {
        inBytes += 4 * f.values.size();
        (f.association == Association::Point ? pointComps : cellComps) += f.components;
    }
    const std::uint64_t outPoints = mesh.pointCount() + outTets / 4;
    return inBytes + outTets * (41 + 4 * cellComps) + outPoints * (12 + 4 * pointComps) + 8 * tets;
}

Mesh refineMesh(const Mesh& mesh, int levels,
                const std::function<void(const std::string&)>& progress,
                const std::function<void(double)>& fraction) {
    if (levels < 0 || levels > kMaxRefineLevels)
        throwError(ErrorKind::Argument, "",
                   "--levels " + std::to_string(levels) + ": expected 0 to " +
                       std::to_string(kMaxRefineLevels));
    auto say = [&](const std::string& s) {
        if (progress) progress(s);
    };
    const std::int64_t cellCount = static_cast<std::int64_t>(mesh.cellCount());
    // Step 1: split cells into tetrahedra (two passes over fixed chunks: count, then fill).
    say("splitting " + std::to_string(cellCount) + " cells into tetrahedra");
    const std::int64_t chunks = (cellCount + kChunk - 1) / kChunk;
    std::vector<std::uint64_t> chunkStart(chunks + 1, 0);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        std::uint64_t count = 0;
        for (std::int64_t i = c * kChunk; i < std::min(cellCount, (c + 1) * kChunk); ++i)
            count += static_cast<std::uint64_t>(splitCell(mesh, i).count);
        chunkStart[c + 1] = count;
    }
    for (std::int64_t c = 0; c < chunks; ++c) chunkStart[c + 1] += chunkStart[c];
    const std::uint64_t baseTets = chunkStart[chunks];
    const std::uint64_t outTets = refinedTetCount(baseTets, levels);
    if (outTets > kMaxRefinedTets || (levels > 0 && (outTets >> (3 * levels)) != baseTets))
        throwError(ErrorKind::Resource, "",
                   std::to_string(baseTets) + " tetrahedra refined " + std::to_string(levels) +
                       " times would exceed " + std::to_string(kMaxRefinedTets) + " tetrahedra");
    // Work shares: the split makes baseTets, level L makes 8^(L+1) baseTets, assembling copies
    // the last level's tetrahedra once more.
    const double totalWork = double(baseTets) +
                             double(outTets) * (8.0 / 7.0) * (1.0 - std::pow(8.0, -levels)) +
                             double(outTets);
    double doneWork = 0.0;
    auto advance = [&](double work) {
        doneWork += work;
        if (fraction) fraction(std::min(1.0, doneWork / std::max(totalWork, 1.0)));
    };
    Work w;
    w.points = mesh.points;
    w.tets.resize(baseTets);
    std::vector<std::uint64_t> sourceCell(baseTets);  // cell of each base tetrahedron
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        std::uint64_t at = chunkStart[c];
        for (std::int64_t i = c * kChunk; i < std::min(cellCount, (c + 1) * kChunk); ++i) {
            const CellSplit split = splitCell(mesh, i);
            for (int t = 0; t < split.count; ++t) {
                w.tets[at] = split.tets[t];
                sourceCell[at++] = static_cast<std::uint64_t>(i);
            }
        }
    }
    for (const Field& f : mesh.fields)
        if (f.association == Association::Point) w.pointFields.push_back(f);
    advance(double(baseTets));
    // Step 2: the refinement levels.
    for (int level = 0; level < levels; ++level) {
        say("refinement level " + std::to_string(level + 1) + " of " + std::to_string(levels) +
            ": " + std::to_string(w.tets.size()) + " -> " + std::to_string(8 * w.tets.size()) +
            " tetrahedra");
        refineOnce(w);
        advance(double(w.tets.size()));
    }
    // Step 3: the output mesh; cell fields follow the source cell of each tetrahedron.
    say("assembling " + std::to_string(w.tets.size()) + " tetrahedra");
    Mesh out;
    out.points = std::move(w.points);
    const std::int64_t n = static_cast<std::int64_t>(w.tets.size());
    out.cellTypes.assign(n, CellType::Tetra);
    out.cellOffsets.resize(n + 1);
    out.cellIndices.resize(4 * n);
#pragma omp parallel for schedule(static)
    for (std::int64_t t = 0; t <= n; ++t) out.cellOffsets[t] = 4 * static_cast<std::uint64_t>(t);
#pragma omp parallel for schedule(static)
    for (std::int64_t t = 0; t < n; ++t)
        for (int i = 0; i < 4; ++i) out.cellIndices[4 * t + i] = w.tets[t].v[i];
    w.tets = {};
    std::size_t nextPointField = 0;
    for (const Field& f : mesh.fields) {
        if (f.association == Association::Point) {
            out.fields.push_back(std::move(w.pointFields[nextPointField++]));
            continue;
        }
        Field g{f.name, f.association, f.components, {}};
        g.values.resize(static_cast<std::size_t>(n) * f.components);
#pragma omp parallel for schedule(static)
        for (std::int64_t t = 0; t < n; ++t) {
            const std::uint64_t src = sourceCell[static_cast<std::uint64_t>(t) >> (3 * levels)];
            for (int c = 0; c < f.components; ++c)
                g.values[t * f.components + c] = f.values[src * f.components + c];
        }
        out.fields.push_back(std::move(g));
    }
    out.notes = mesh.notes;
    advance(double(n));
    return out;
}

}  // namespace uvr
