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
    for (std::uint64_t c = 0; c < cells; ++c) {
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

ValidationReport validateMesh(const Mesh& mesh, const std::string& file) {
    validateStructure(mesh, file);
    ValidationReport r;
    // Cell geometry (the same split the renderer uses).
    std::vector<bool> used(mesh.pointCount(), false);
    for (std::uint64_t c = 0; c < mesh.cellCount(); ++c) {
        for (std::uint32_t id : mesh.cell(c)) used[id] = true;
        const CellSplit split = splitCell(mesh, c);
        for (int t = 0; t < split.count; ++t)
            for (std::uint32_t v : split.tets[t].v) r.bounds.extend(mesh.points[v]);
        switch (split.shape) {
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
