// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/vtk_cells.h"

#include <map>

#include "uvr/core/error.h"

namespace uvr {

void appendVtkCells(const VtkCellArrays& cells, Mesh& mesh, const std::string& file) {
    const std::uint64_t n = cells.types.size();
    if (cells.offsets.size() != n + 1)
        throwError(ErrorKind::Parse, file,
                   "cell offsets hold " + std::to_string(cells.offsets.size()) +
                       " entries, expected " + std::to_string(n + 1) + " for " + std::to_string(n) +
                       " cells");
    const std::uint64_t pointCount = mesh.pointCount();
    std::vector<std::uint64_t> kept;
    kept.reserve(n);
    std::map<std::string, std::uint64_t> dropped, reduced;
    std::uint64_t voxels = 0;
    std::uint32_t ids[8];
    const std::uint64_t firstNewCell = mesh.cellCount();
    for (std::uint64_t c = 0; c < n; ++c) {
        const std::int64_t begin = cells.offsets[c], end = cells.offsets[c + 1];
        if (begin < 0 || end < begin || static_cast<std::uint64_t>(end) > cells.connectivity.size())
            throwError(ErrorKind::Parse, file,
                       "cell " + std::to_string(c) + ": node range [" + std::to_string(begin) +
                           ", " + std::to_string(end) + ") outside the connectivity array of " +
                           std::to_string(cells.connectivity.size()) + " entries");
        const VtkCellTypeInfo info = vtkCellTypeInfo(cells.types[c]);
        if (!info.known)
            throwError(ErrorKind::Parse, file,
                       "cell " + std::to_string(c) + ": unknown VTK cell type " +
                           std::to_string(cells.types[c]));
        if (cells.types[c] == 42)
            throwError(
                ErrorKind::Unsupported, file,
                "cell " + std::to_string(c) + ": polyhedron cells (type 42) are not supported");
        if (!info.volumetric) {
            ++dropped[info.name];
            continue;
        }
        const std::int64_t nodes = end - begin;
        if (nodes < info.minNodes)
            throwError(ErrorKind::Parse, file,
                       "cell " + std::to_string(c) + " (" + info.name + ") lists " +
                           std::to_string(nodes) + " nodes, expected " +
                           std::to_string(info.minNodes));
        const int corners = cornerCount(info.linear);
        for (int k = 0; k < corners; ++k) {
            const std::int64_t id = cells.connectivity[begin + k];
            if (id < 0 || static_cast<std::uint64_t>(id) >= pointCount)
                throwError(ErrorKind::Validation, file,
                           "cell " + std::to_string(c) + " (" + info.name + "): point index " +
                               std::to_string(id) + " out of range [0, " +
                               std::to_string(pointCount) + ")");
            ids[k] = static_cast<std::uint32_t>(id);
        }
        if (cells.types[c] == 11) {  // voxel order 0,1,3,2,4,5,7,6 -> hexahedron order
            std::swap(ids[2], ids[3]);
            std::swap(ids[6], ids[7]);
            ++voxels;
        } else if (cells.types[c] != static_cast<int>(info.linear)) {
            ++reduced[info.name];  // quadratic or Lagrange: its corners only
        }
        mesh.addCell(info.linear, {ids, static_cast<std::size_t>(corners)});
        kept.push_back(c);
    }
    for (const auto& [name, count] : dropped)
        mesh.notes.push_back("dropped " + std::to_string(count) + " non-volumetric " + name +
                             " cell(s)");
    if (voxels)
        mesh.notes.push_back("read " + std::to_string(voxels) +
                             " voxel cell(s) as hexahedra (the same cells, corners reordered)");
    for (const auto& [name, count] : reduced)
        mesh.notes.push_back(
            "reduced " + std::to_string(count) + " " + name +
            " cell(s) to their corner nodes: their mid-edge and higher-order nodes are used by "
            "no cell, and fields are interpolated between the corners");
    // Filter cell data of this batch to the kept cells (tuples beyond firstNewCell belong to it).
    if (kept.size() != n) {
        for (Field& f : mesh.fields) {
            if (f.association != Association::Cell) continue;
            const std::size_t comps = static_cast<std::size_t>(f.components);
            std::size_t base = firstNewCell * comps;
            if (f.values.size() != base + n * comps) continue;  // size checked by the reader
            for (std::size_t i = 0; i < kept.size(); ++i)
                for (std::size_t k = 0; k < comps; ++k)
                    f.values[base + i * comps + k] = f.values[base + kept[i] * comps + k];
            f.values.resize(base + kept.size() * comps);
        }
    }
}

}  // namespace uvr
