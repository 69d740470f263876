// SPDX-License-Identifier: MIT
#include "uvr/mesh/tet_mesh.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "uvr/core/error.h"
#include "uvr/mesh/tet_math.h"

namespace uvr {

namespace {

/// Faces of a positively oriented VTK cell, counter-clockwise seen from outside (VTK's face
/// lists); -1 pads triangles.
struct FaceList {
    int count;
    int v[6][4];
};

const FaceList& cellFaces(CellType type) {
    static const FaceList kTet{4, {{0, 2, 1, -1}, {0, 1, 3, -1}, {1, 2, 3, -1}, {0, 3, 2, -1}}};
    static const FaceList kHex{
        6, {{0, 4, 7, 3}, {1, 2, 6, 5}, {0, 1, 5, 4}, {3, 7, 6, 2}, {0, 3, 2, 1}, {4, 5, 6, 7}}};
    static const FaceList kWedge{
        5, {{0, 1, 2, -1}, {3, 5, 4, -1}, {0, 3, 4, 1}, {1, 4, 5, 2}, {2, 5, 3, 0}}};
    static const FaceList kPyramid{
        5, {{0, 3, 2, 1}, {0, 1, 4, -1}, {1, 2, 4, -1}, {2, 3, 4, -1}, {3, 0, 4, -1}}};
    switch (type) {
        case CellType::Tetra:
            return kTet;
        case CellType::Hexahedron:
            return kHex;
        case CellType::Wedge:
            return kWedge;
        case CellType::Pyramid:
            return kPyramid;
    }
    return kTet;
}

double det6(const Vec3f& a, const Vec3f& b, const Vec3f& c, const Vec3f& d) {
    const double bx = double(b.x) - a.x, by = double(b.y) - a.y, bz = double(b.z) - a.z;
    const double cx = double(c.x) - a.x, cy = double(c.y) - a.y, cz = double(c.z) - a.z;
    const double dx = double(d.x) - a.x, dy = double(d.y) - a.y, dz = double(d.z) - a.z;
    return bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx);
}

/// A tetrahedron whose |6V| is below this fraction of (longest edge)^3 counts as zero-volume.
constexpr double kZeroVolumeRelative = 1e-7;

/// Cells (or tetrahedra) per chunk of the parallel loops: fixed, so results do not depend on the
/// thread count.
constexpr std::int64_t kCellChunk = 1 << 14;

}  // namespace

int splitCellIntoTets(CellType type, const std::uint32_t* ids, std::uint8_t out[6][4]) {
    if (type == CellType::Tetra) {
        out[0][0] = 0, out[0][1] = 1, out[0][2] = 2, out[0][3] = 3;
        return 1;
    }
    const int n = cornerCount(type);
    int apex = 0;
    for (int i = 1; i < n; ++i)
        if (ids[i] < ids[apex]) apex = i;
    const FaceList& faces = cellFaces(type);
    int count = 0;
    auto emit = [&](int a, int b, int c) {
        // (a, b, c) is counter-clockwise from outside and apex lies inside: (a, c, b, apex) > 0.
        out[count][0] = static_cast<std::uint8_t>(a);
        out[count][1] = static_cast<std::uint8_t>(c);
        out[count][2] = static_cast<std::uint8_t>(b);
        out[count][3] = static_cast<std::uint8_t>(apex);
        ++count;
    };
    for (int f = 0; f < faces.count; ++f) {
        const int* v = faces.v[f];
        const int nv = v[3] < 0 ? 3 : 4;
        bool hasApex = false;
        for (int k = 0; k < nv; ++k) hasApex |= v[k] == apex;
        if (hasApex) continue;
        if (nv == 3) {
            emit(v[0], v[1], v[2]);
            continue;
        }
        // Quadrilateral: split along the diagonal through its smallest global index.
        int minK = 0;
        for (int k = 1; k < 4; ++k)
            if (ids[v[k]] < ids[v[minK]]) minK = k;
        if (minK % 2 == 0) {
            emit(v[0], v[1], v[2]);
            emit(v[0], v[2], v[3]);
        } else {
            emit(v[1], v[2], v[3]);
            emit(v[1], v[3], v[0]);
        }
    }
    return count;
}

CellSplit splitCell(const MeshView& mesh, std::uint64_t c) {
    const auto ids = mesh.cell(c);
    const CellType type = mesh.cellTypes[c];
    std::uint8_t local[6][4];
    const int n = splitCellIntoTets(type, ids.data(), local);
    CellSplit split;
    double total = 0.0, longest = 0.0;
    int positive = 0, negative = 0;
    double vols[6];
    for (int t = 0; t < n; ++t) {
        const Vec3f p[4] = {mesh.points[ids[local[t][0]]], mesh.points[ids[local[t][1]]],
                            mesh.points[ids[local[t][2]]], mesh.points[ids[local[t][3]]]};
        vols[t] = det6(p[0], p[1], p[2], p[3]);
        total += vols[t];
        double l = 0.0;
        for (int i = 0; i < 4; ++i)
            for (int j = i + 1; j < 4; ++j) {
                const double dx = double(p[i].x) - p[j].x, dy = double(p[i].y) - p[j].y,
                             dz = double(p[i].z) - p[j].z;
                l = std::fmax(l, dx * dx + dy * dy + dz * dz);
            }
        longest = std::fmax(longest, l);
    }
    const double scale = longest * std::sqrt(longest);  // (longest edge)^3
    const double eps = kZeroVolumeRelative * scale;
    for (int t = 0; t < n; ++t) {
        if (std::fabs(vols[t]) <= eps || !std::isfinite(vols[t])) continue;
        (vols[t] > 0 ? positive : negative)++;
        Tet tet{{ids[local[t][0]], ids[local[t][1]], ids[local[t][2]], ids[local[t][3]]}};
        if (vols[t] < 0) std::swap(tet.v[1], tet.v[2]);
        split.tets[split.count] = tet;
        split.volume6[split.count] = std::fabs(vols[t]);
        ++split.count;
    }
    if (!(std::fabs(total) > eps))
        split.shape = CellShape::ZeroVolume;
    else if (negative > 0 && positive > 0)
        split.shape = CellShape::Distorted;
    else if (negative > 0)
        split.shape = CellShape::Inverted;
    return split;
}

namespace {

/// The native kind of a VTK cell type (tetrahedra are never native cells).
CellKind nativeKind(CellType type) {
    return type == CellType::Pyramid ? CellKind::Pyramid
                                     : (type == CellType::Wedge ? CellKind::Wedge : CellKind::Hex);
}

}  // namespace

namespace {

/// Where each part of tetrahedralize ends in its progress fraction: split loop, gather, Morton
/// order, values, blocks (by their seconds at 100M tetrahedra on 16 cores: 1.0, 0.8, 1.4, 0.3,
/// 0.7).
constexpr double kSplitEnd = 1.0 / 4.2, kGatherEnd = 1.8 / 4.2, kSortEnd = 3.2 / 4.2,
                 kValuesEnd = 3.5 / 4.2;

}  // namespace

TetMesh tetrahedralize(const MeshView& mesh, const ScalarField& field,
                       const TetrahedralizeOptions& options, const FractionFn& progress) {
    TetMesh out;
    out.points.assign(mesh.points.begin(), mesh.points.end());
    const bool cellData = field.association == Association::Cell;
    UVR_CHECK(field.values.size() == (cellData ? mesh.cellCount() : mesh.pointCount()),
              "field '" << field.name << "' has " << field.values.size() << " values");
    // Fixed chunks of cells (so the result does not depend on the thread count), each split
    // into its own list with its volume and bounds; then the lists are moved into place in
    // chunk order (each freed as soon as it is copied).
    const std::int64_t cellCount = static_cast<std::int64_t>(mesh.cellCount());
    const std::int64_t chunks = (cellCount + kCellChunk - 1) / kCellChunk;
    struct Chunk {
        std::vector<Tet> tets;
        std::uint64_t kept = 0;                ///< tetrahedra written in place (tetrahedra only)
        std::vector<std::uint32_t> native[3];  ///< corners of pyramids, wedges, hexahedra
        std::vector<std::uint64_t> source[3];  ///< their source cells
        double volume = 0.0;
        Bounds3f bounds;
    };
    std::vector<Chunk> parts(chunks);
    out.cellTets.assign(mesh.cellCount(), 0);
    // A mesh of tetrahedra only (the common large case): each cell keeps at most its one
    // tetrahedron, written in place at its chunk's start; no lists to gather.
    bool tetsOnly = true;
#pragma omp parallel for schedule(static) reduction(&& : tetsOnly)
    for (std::int64_t i = 0; i < cellCount; ++i)
        tetsOnly = tetsOnly && mesh.cellTypes[i] == CellType::Tetra;
    if (tetsOnly) out.tets.resize(mesh.cellCount());
    ProgressCounter splitDone(progress, chunks, 0.0, kSplitEnd);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        Chunk& s = parts[c];
        const std::int64_t end = std::min(cellCount, (c + 1) * kCellChunk);
        if (!tetsOnly) s.tets.reserve(static_cast<std::size_t>(end - c * kCellChunk));
        for (std::int64_t i = c * kCellChunk; i < end; ++i) {
            const CellSplit split = splitCell(mesh, i);
            const CellType type = mesh.cellTypes[i];
            if (!options.splitCells && type != CellType::Tetra &&
                (split.shape == CellShape::Valid || split.shape == CellShape::Inverted)) {
                // Native: kept whole where its isoparametric map is one-to-one (either
                // orientation: a mirrored vertex order is read as it is).
                const auto ids = mesh.cell(i);
                const CellKind kind = nativeKind(type);
                const int n = kindCorners(kind);
                Vec3f x[kMaxCellCorners];
                for (int k = 0; k < n; ++k) x[k] = out.points[ids[k]];
                if (nativeOrientation(kind, x) != 0) {
                    const int slot = int(kind) - 1;
                    s.native[slot].insert(s.native[slot].end(), ids.begin(), ids.begin() + n);
                    s.source[slot].push_back(std::uint64_t(i));
                    for (int t = 0; t < split.count; ++t) s.volume += split.volume6[t] / 6.0;
                    for (int k = 0; k < n; ++k) s.bounds.extend(x[k]);
                    continue;
                }
            }
            out.cellTets[i] = static_cast<std::uint8_t>(split.count);
            for (int t = 0; t < split.count; ++t) {
                if (tetsOnly)
                    out.tets[c * kCellChunk + s.kept++] = split.tets[t];
                else
                    s.tets.push_back(split.tets[t]);
                s.volume += split.volume6[t] / 6.0;
                for (std::uint32_t v : split.tets[t].v) s.bounds.extend(out.points[v]);
            }
        }
        splitDone.add();
    }
    splitDone.finish();
    std::vector<std::uint64_t> chunkStart(chunks + 1, 0);
    for (std::int64_t c = 0; c < chunks; ++c)
        chunkStart[c + 1] = chunkStart[c] + parts[c].tets.size() + parts[c].kept;
    ProgressCounter gathered(progress, chunks, kSplitEnd, kGatherEnd);
    if (tetsOnly) {
        // Cells that kept no tetrahedron (zero volume) leave gaps: closed up in chunk order
        // (each chunk moves down, never over one not yet moved).
        if (chunkStart[chunks] != out.tets.size())
            for (std::int64_t c = 0; c < chunks; ++c)
                std::memmove(out.tets.data() + chunkStart[c], out.tets.data() + c * kCellChunk,
                             parts[c].kept * sizeof(Tet));
        out.tets.resize(chunkStart[chunks]);
    } else {
        out.tets.resize(chunkStart[chunks]);
#pragma omp parallel for schedule(dynamic, 1)
        for (std::int64_t c = 0; c < chunks; ++c) {
            Chunk& s = parts[c];
            std::copy(s.tets.begin(), s.tets.end(), out.tets.begin() + chunkStart[c]);
            s.tets = {};
            gathered.add();
        }
    }
    // Native cells by kind, each kind in chunk order.
    std::uint64_t* counts[3] = {&out.pyramidCount, &out.wedgeCount, &out.hexCount};
    for (int slot = 0; slot < 3; ++slot) {
        for (Chunk& s : parts) {
            out.nativeCorners.insert(out.nativeCorners.end(), s.native[slot].begin(),
                                     s.native[slot].end());
            out.nativeSource.insert(out.nativeSource.end(), s.source[slot].begin(),
                                    s.source[slot].end());
            *counts[slot] += s.source[slot].size();
            s.native[slot] = {};
            s.source[slot] = {};
        }
    }
    UVR_CHECK(out.cellCount() < kNoCell, "the mesh has " << out.cellCount() << " cells; at most "
                                                         << kNoCell - 1 << " can be rendered");
    for (const Chunk& s : parts) {
        out.totalVolume += s.volume;
        out.bounds.extend(s.bounds);
    }
    gathered.finish();
    if (options.spatialOrder)
        sortCellsSpatially(out, subRange(progress, kGatherEnd, kSortEnd), options.sorter);
    assignTetValues(out, field);
    if (progress) progress(kValuesEnd);
    out.frame = options.frame ? *options.frame : frameForBounds(out.bounds);
    if (!out.frame.identity()) {
        const MeshFrame& f = out.frame;
        const std::int64_t n = static_cast<std::int64_t>(out.points.size());
#pragma omp parallel for schedule(static)
        for (std::int64_t i = 0; i < n; ++i) {
            double p[3];
            f.toLocal(out.points[i], p);
            out.points[i] = Vec3f(float(p[0]), float(p[1]), float(p[2]));
        }
        double blo[3], bhi[3];
        f.toLocal(out.bounds.lo, blo);
        f.toLocal(out.bounds.hi, bhi);
        out.bounds = {Vec3f(float(blo[0]), float(blo[1]), float(blo[2])),
                      Vec3f(float(bhi[0]), float(bhi[1]), float(bhi[2]))};
        out.totalVolume *= f.scale * f.scale * f.scale;
    }
    encodeTetBlocks(out, subRange(progress, kValuesEnd, 1.0));
    return out;
}

void assignTetValues(TetMesh& mesh, const ScalarField& field) {
    const bool cellData = field.association == Association::Cell;
    const std::uint64_t expected = cellData ? mesh.cellTets.size() : mesh.points.size();
    const TetMeshView view = mesh.view();
    if (field.values.size() != expected)
        throwError(ErrorKind::Argument, "",
                   "field '" + field.name + "' has " + std::to_string(field.values.size()) + " " +
                       associationName(field.association) + " values, expected " +
                       std::to_string(expected) + " (one per " + (cellData ? "cell" : "point") +
                       " of the prepared mesh)");
    mesh.association = field.association;
    mesh.fieldName = field.name;
    if (cellData) {
        // Each cell's value onto its tetrahedra, which follow in cell order: per chunk of cells
        // the first tetrahedron, then the chunks in parallel.
        const std::int64_t cellCount = static_cast<std::int64_t>(mesh.cellTets.size());
        const std::int64_t chunks = (cellCount + kCellChunk - 1) / kCellChunk;
        std::vector<std::uint64_t> first(chunks + 1, 0);
#pragma omp parallel for schedule(static)
        for (std::int64_t c = 0; c < chunks; ++c) {
            std::uint64_t n = 0;
            const std::int64_t end = std::min(cellCount, (c + 1) * kCellChunk);
            for (std::int64_t i = c * kCellChunk; i < end; ++i) n += mesh.cellTets[i];
            first[c + 1] = n;
        }
        for (std::int64_t c = 0; c < chunks; ++c) first[c + 1] += first[c];
        UVR_CHECK(
            first[chunks] == mesh.tets.size(),
            "cellTets lists " << first[chunks] << " tetrahedra, the mesh has " << mesh.tets.size());
        mesh.values.resize(mesh.cellCount());
#pragma omp parallel for schedule(static)
        for (std::int64_t c = 0; c < chunks; ++c) {
            std::uint64_t t = first[c];
            const std::int64_t end = std::min(cellCount, (c + 1) * kCellChunk);
            for (std::int64_t i = c * kCellChunk; i < end; ++i)
                for (int k = 0; k < mesh.cellTets[i]; ++k) mesh.values[t++] = field.values[i];
        }
        if (!mesh.tetSourceOrder.empty()) {
            // From cell order to the tetrahedra's order (sortCellsSpatially).
            const std::int64_t n = static_cast<std::int64_t>(mesh.tets.size());
            std::vector<float> inCellOrder(mesh.values.begin(), mesh.values.begin() + n);
#pragma omp parallel for schedule(static)
            for (std::int64_t t = 0; t < n; ++t)
                mesh.values[t] = inCellOrder[mesh.tetSourceOrder[t]];
        }
        const std::int64_t nativeCount = static_cast<std::int64_t>(mesh.nativeSource.size());
#pragma omp parallel for schedule(static)
        for (std::int64_t j = 0; j < nativeCount; ++j)
            mesh.values[mesh.tets.size() + j] = field.values[mesh.nativeSource[j]];
    } else {
        mesh.values.assign(field.values.begin(), field.values.end());
    }
    // The finite range over the tetrahedra's values (points no tetrahedron uses left out), per
    // fixed chunk and then in chunk order: the same for any thread count.
    const std::int64_t allCells = static_cast<std::int64_t>(mesh.cellCount());
    const std::int64_t chunks = (allCells + kCellChunk - 1) / kCellChunk;
    std::vector<float> lo(chunks, INFINITY), hi(chunks, -INFINITY);
#pragma omp parallel for schedule(static)
    for (std::int64_t c = 0; c < chunks; ++c) {
        float l = INFINITY, h = -INFINITY;
        const std::int64_t end = std::min(allCells, (c + 1) * kCellChunk);
        for (std::int64_t t = c * kCellChunk; t < end; ++t) {
            if (cellData) {
                const float v = mesh.values[t];
                if (std::isfinite(v)) l = std::fmin(l, v), h = std::fmax(h, v);
                continue;
            }
            std::uint32_t ids[kMaxCellCorners];
            const int n = view.corners(std::uint64_t(t), ids);
            for (int k = 0; k < n; ++k) {
                const float v = mesh.values[ids[k]];
                if (std::isfinite(v)) l = std::fmin(l, v), h = std::fmax(h, v);
            }
        }
        lo[c] = l, hi[c] = h;
    }
    float l = INFINITY, h = -INFINITY;
    for (std::int64_t c = 0; c < chunks; ++c) l = std::fmin(l, lo[c]), h = std::fmax(h, hi[c]);
    mesh.valueMin = l <= h ? l : 0.f;
    mesh.valueMax = l <= h ? h : 0.f;
    // The blocks' copies of the point values.
    const std::int64_t blockVertices = static_cast<std::int64_t>(mesh.blockVertexPoint.size());
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < blockVertices; ++i)
        mesh.blockVertices[i].value = cellData ? 0.f : mesh.values[mesh.blockVertexPoint[i]];
}

std::string describeCells(const TetMesh& mesh) {
    if (!mesh.hasNative()) return std::to_string(mesh.tetCount()) + " tetrahedra";
    std::string parts;
    auto add = [&](std::uint64_t n, const char* what) {
        if (n == 0) return;
        parts += (parts.empty() ? "" : ", ") + std::to_string(n) + " " + what;
    };
    add(mesh.tetCount(), "tetrahedra");
    add(mesh.pyramidCount, "pyramids");
    add(mesh.wedgeCount, "wedges");
    add(mesh.hexCount, "hexahedra");
    return std::to_string(mesh.cellCount()) + " cells (" + parts + ")";
}

MeshFrame frameForBounds(const Bounds3f& bounds) {
    MeshFrame f;
    if (bounds.empty() || !isFinite(bounds.lo) || !isFinite(bounds.hi)) return f;
    double diag2 = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double e = double(bounds.hi[a]) - bounds.lo[a];
        diag2 += e * e;
    }
    const double diag = std::sqrt(diag2);
    if (!(diag > 0.0)) return f;  // a single point: nothing to render anyway
    if (diag < std::ldexp(1.0, -kFrameScaleExponent) || diag > std::ldexp(1.0, kFrameScaleExponent))
        f.scale = std::ldexp(1.0, -std::ilogb(diag));
    for (int a = 0; a < 3; ++a) {
        // The centre is at least 2^8 diagonals from 0, so every point p of the box lies within
        // [c / 2, 2 c] of it and p - c is exact (Sterbenz).
        const double c = 0.5 * (double(bounds.lo[a]) + bounds.hi[a]);
        if (std::fabs(c) > std::ldexp(diag, kFrameShiftExponent)) f.origin[a] = float(c);
    }
    return f;
}

}  // namespace uvr
