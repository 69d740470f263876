// SPDX-License-Identifier: MIT
#include "uvr/mesh/validate.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <tuple>

#include "uvr/core/error.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

void validateStructure(const Mesh& mesh, const std::string& file) {
    const std::uint64_t n = mesh.cellCount();
    if (mesh.cellOffsets.size() != n + 1 || mesh.cellOffsets.front() != 0 ||
        mesh.cellOffsets.back() != mesh.cellIndices.size())
        throwError(ErrorKind::Validation, file,
                   "cell offsets are inconsistent: " + std::to_string(mesh.cellOffsets.size()) +
                       " offsets for " + std::to_string(n) + " cells and " +
                       std::to_string(mesh.cellIndices.size()) + " indices");
    const std::uint64_t np = mesh.pointCount();
    if (np > 0xffffffffull)
        throwError(ErrorKind::Unsupported, file,
                   std::to_string(np) + " points: at most 2^32 - 1 are supported");
    for (std::uint64_t c = 0; c < n; ++c) {
        const int corners = cornerCount(mesh.cellTypes[c]);
        if (corners == 0)
            throwError(ErrorKind::Validation, file,
                       "cell " + std::to_string(c) + ": unsupported cell type " +
                           std::to_string(static_cast<int>(mesh.cellTypes[c])));
        if (mesh.cellOffsets[c + 1] - mesh.cellOffsets[c] != static_cast<std::uint64_t>(corners))
            throwError(ErrorKind::Validation, file,
                       "cell " + std::to_string(c) + " (" + cellTypeName(mesh.cellTypes[c]) +
                           ") lists " +
                           std::to_string(mesh.cellOffsets[c + 1] - mesh.cellOffsets[c]) +
                           " points, expected " + std::to_string(corners));
        for (std::uint32_t id : mesh.cell(c))
            if (id >= np)
                throwError(ErrorKind::Validation, file,
                           "cell " + std::to_string(c) + " (" + cellTypeName(mesh.cellTypes[c]) +
                               "): point index " + std::to_string(id) + " out of range [0, " +
                               std::to_string(np) + ")");
    }
    for (const Field& f : mesh.fields) {
        const std::uint64_t tuples = f.association == Association::Point ? np : n;
        if (f.components < 1 || f.values.size() != tuples * f.components)
            throwError(ErrorKind::Validation, file,
                       std::string(associationName(f.association)) + " field '" + f.name +
                           "' holds " + std::to_string(f.values.size()) + " values, expected " +
                           std::to_string(tuples) + " x " + std::to_string(f.components));
    }
}

ValidationReport validateMesh(const Mesh& mesh, const std::string& file) {
    validateStructure(mesh, file);
    ValidationReport r;
    // Cell geometry (the same split the renderer uses).
    std::vector<bool> used(mesh.pointCount(), false);
    for (std::uint64_t c = 0; c < mesh.cellCount(); ++c) {
        for (std::uint32_t id : mesh.cell(c)) used[id] = true;
        switch (splitCell(mesh, c).shape) {
            case CellShape::Valid:
                break;
            case CellShape::Inverted:
                if (r.invertedCells++ == 0) r.firstInvertedCell = c;
                break;
            case CellShape::ZeroVolume:
                if (r.zeroVolumeCells++ == 0) r.firstZeroVolumeCell = c;
                break;
            case CellShape::Distorted:
                if (r.distortedCells++ == 0) r.firstDistortedCell = c;
                break;
        }
    }
    r.unusedPoints = static_cast<std::uint64_t>(std::count(used.begin(), used.end(), false));
    // Points: non-finite coordinates, and coincident positions (sort indices by position).
    std::vector<std::uint32_t> order;
    order.reserve(mesh.pointCount());
    for (std::uint64_t i = 0; i < mesh.pointCount(); ++i) {
        if (!isFinite(mesh.points[i]))
            ++r.nonFinitePoints;
        else
            order.push_back(static_cast<std::uint32_t>(i));
    }
    auto key = [&](std::uint32_t i) {
        const Vec3f& p = mesh.points[i];
        return std::tuple<float, float, float>(p.x, p.y, p.z);
    };
    std::sort(order.begin(), order.end(),
              [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
    for (std::size_t i = 1; i < order.size(); ++i)
        if (key(order[i]) == key(order[i - 1])) ++r.coincidentPoints;
    // Fields.
    for (const Field& f : mesh.fields) {
        NonFiniteField nf{f.name, f.association, 0, 0};
        for (std::size_t i = 0; i < f.values.size(); ++i)
            if (!std::isfinite(f.values[i]) && nf.count++ == 0)
                nf.firstTuple = i / static_cast<std::size_t>(f.components);
        if (nf.count) r.nonFiniteFields.push_back(nf);
    }
    return r;
}

std::vector<std::string> ValidationReport::findings() const {
    std::vector<std::string> out;
    auto cells = [&](std::uint64_t n, const char* what, std::uint64_t first, const char* action) {
        if (n)
            out.push_back(std::to_string(n) + " " + what + " cell(s) (first: cell " +
                          std::to_string(first) + "): " + action);
    };
    cells(invertedCells, "inverted", firstInvertedCell, "re-oriented for rendering");
    cells(zeroVolumeCells, "zero-volume", firstZeroVolumeCell, "they contribute nothing");
    cells(distortedCells, "distorted (twisted or non-convex)", firstDistortedCell,
          "split tetrahedra re-oriented individually");
    if (coincidentPoints)
        out.push_back(std::to_string(coincidentPoints) +
                      " coincident point(s) (same position as an earlier point)");
    if (nonFinitePoints)
        out.push_back(std::to_string(nonFinitePoints) +
                      " point(s) with NaN/Inf coordinates: cells using them are dropped");
    if (unusedPoints) out.push_back(std::to_string(unusedPoints) + " point(s) used by no cell");
    for (const NonFiniteField& f : nonFiniteFields)
        out.push_back(std::string(associationName(f.association)) + " field '" + f.name +
                      "': " + std::to_string(f.count) + " NaN/Inf value(s) (first at " +
                      associationName(f.association) + " " + std::to_string(f.firstTuple) +
                      "): rendered transparent");
    return out;
}

}  // namespace uvr
