// SPDX-License-Identifier: MIT
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "uvr/core/bounds.h"
#include "uvr/core/ray.h"
#include "uvr/mesh/mesh.h"
#include "uvr/mesh/procedural.h"

namespace uvr::testing {

/// The span [t0, t1] of a ray inside a box, in double; false when it misses.
inline bool boxSpan(const Bounds3f& b, const Ray& ray, double& t0, double& t1) {
    t0 = 0.0, t1 = INFINITY;
    for (int a = 0; a < 3; ++a) {
        const double lo = (double(b.lo[a]) - ray.org[a]) / ray.dir[a];
        const double hi = (double(b.hi[a]) - ray.org[a]) / ray.dir[a];
        t0 = std::max(t0, std::min(lo, hi));
        t1 = std::min(t1, std::max(lo, hi));
    }
    return t0 < t1;
}

/// A procedural box of about 400k tetrahedra with a linear field (made once): several chunks of
/// every parallel loop of the preparation, and above the builders' one-thread subtree sizes.
inline const Mesh& box400k() {
    static const Mesh mesh = [] {
        ProceduralSpec spec;
        spec.targetCells = 400000;
        spec.fields = {ProceduralField::Linear};
        return generateMesh(spec);
    }();
    return mesh;
}

/// A procedural mesh of about `cells` cells whose every other cell names a second copy of the
/// points (a seam of duplicated points across their faces, which only a weld matches), with a
/// last cell on the first one's corners (a face shared by three cells).
inline Mesh seamMesh(std::uint64_t cells) {
    ProceduralSpec spec;
    spec.targetCells = cells;
    Mesh seams = generateMesh(spec);
    const std::size_t points = seams.points.size();
    seams.points.insert(seams.points.end(), seams.points.begin(), seams.points.end());
    for (Field& f : seams.fields) f.values.insert(f.values.end(), f.values.begin(), f.values.end());
    for (std::size_t c = 1; c < seams.cellCount(); c += 2)
        for (std::uint64_t k = seams.cellOffsets[c]; k < seams.cellOffsets[c + 1]; ++k)
            seams.cellIndices[k] += static_cast<std::uint32_t>(points);
    const std::vector<std::uint32_t> first(seams.cell(0).begin(), seams.cell(0).end());
    seams.cellIndices.insert(seams.cellIndices.end(), first.begin(), first.end());
    seams.cellOffsets.push_back(seams.cellIndices.size());
    seams.cellTypes.push_back(seams.cellTypes[0]);
    return seams;
}

/// An n x n x n grid of hexahedra over the box [lo, hi]^3 with a point field f(x, y, z) named
/// "f"; optional point jitter (fraction of the spacing, deterministic).
inline Mesh makeHexGrid(
    int n, float lo, float hi, const std::function<float(Vec3f)>& f = [](Vec3f) { return 1.f; },
    float jitter = 0.f) {
    Mesh mesh;
    const int np = n + 1;
    const float h = (hi - lo) / n;
    Field field{"f", Association::Point, 1, {}};
    for (int k = 0; k < np; ++k)
        for (int j = 0; j < np; ++j)
            for (int i = 0; i < np; ++i) {
                Vec3f p(lo + i * h, lo + j * h, lo + k * h);
                const bool interior = i > 0 && j > 0 && k > 0 && i < n && j < n && k < n;
                if (interior && jitter > 0.f) {
                    unsigned s = unsigned(i) * 73856093u ^ unsigned(j) * 19349663u ^
                                 unsigned(k) * 83492791u;  // wraps (no signed overflow)
                    for (int a = 0; a < 3; ++a) {
                        s = s * 1664525u + 1013904223u;
                        p[a] += jitter * h * ((s >> 8) * (1.f / 16777216.f) - 0.5f) * 2.f;
                    }
                }
                mesh.points.push_back(p);
                field.values.push_back(f(p));
            }
    auto id = [&](int i, int j, int k) {
        return static_cast<std::uint32_t>((k * np + j) * np + i);
    };
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const std::uint32_t c[8] = {id(i, j, k),
                                            id(i + 1, j, k),
                                            id(i + 1, j + 1, k),
                                            id(i, j + 1, k),
                                            id(i, j, k + 1),
                                            id(i + 1, j, k + 1),
                                            id(i + 1, j + 1, k + 1),
                                            id(i, j + 1, k + 1)};
                mesh.addCell(CellType::Hexahedron, c);
            }
    mesh.fields.push_back(std::move(field));
    return mesh;
}

/// Appends mesh b, moved by `shift`, to mesh a: its points, its cells (renumbered) and the values
/// of its first field after a's first field's (both point fields, as makeHexGrid makes them).
inline void appendShifted(Mesh& a, const Mesh& b, Vec3f shift) {
    const std::uint32_t base = static_cast<std::uint32_t>(a.points.size());
    for (Vec3f p : b.points) a.points.push_back(p + shift);
    for (std::uint64_t c = 0; c < b.cellCount(); ++c) {
        std::vector<std::uint32_t> ids;
        for (std::uint32_t id : b.cell(c)) ids.push_back(id + base);
        a.addCell(b.cellTypes[c], ids);
    }
    a.fields[0].values.insert(a.fields[0].values.end(), b.fields[0].values.begin(),
                              b.fields[0].values.end());
}

/// An n^3 grid of hexahedra over [-1, 1]^3, jittered by 0.3 of the spacing, with the point field
/// f = xy + z.
inline Mesh jitteredHexGrid(int n) {
    return makeHexGrid(
        n, -1.f, 1.f, [](Vec3f p) { return p.x * p.y + p.z; }, 0.3f);
}

/// Signed volume of tetrahedron c of a mesh (as stored, not re-oriented), in double.
inline double tetVolume(const Mesh& m, std::uint64_t c) {
    const auto v = m.cell(c);
    double e[3][3];
    for (int i = 0; i < 3; ++i)
        for (int a = 0; a < 3; ++a) e[i][a] = double(m.points[v[i + 1]][a]) - m.points[v[0]][a];
    return (e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
            e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
            e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0])) /
           6.0;
}

}  // namespace uvr::testing
