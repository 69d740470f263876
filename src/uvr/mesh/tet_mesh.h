// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <vector>

#include "uvr/core/bounds.h"
#include "uvr/core/host_device.h"
#include "uvr/core/vec.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// Four point indices of a positively oriented tetrahedron.
struct Tet {
    std::uint32_t v[4];
};

/// Bounding box of tetrahedron t.
UVR_HOST_DEVICE inline Bounds3f tetBounds(const Vec3f* points, const Tet& t) {
    Bounds3f b;
    for (int k = 0; k < 4; ++k) b.extend(points[t.v[k]]);
    return b;
}

/// Plain-data view of a TetMesh for CPU and GPU kernels.
struct TetMeshView {
    const Vec3f* points = nullptr;
    const Tet* tets = nullptr;
    const float* values = nullptr;  ///< per point, or per tet when cellCentered
    std::uint64_t tetCount = 0;
    bool cellCentered = false;

    /// Interpolated field value at p given barycentrics in tet t (piecewise constant for cell
    /// data).
    UVR_HOST_DEVICE float interpolate(std::uint64_t t, const float bary[4]) const {
        if (cellCentered) return values[t];
        const Tet& tet = tets[t];
        return bary[0] * values[tet.v[0]] + bary[1] * values[tet.v[1]] +
               bary[2] * values[tet.v[2]] + bary[3] * values[tet.v[3]];
    }
};

/// The rendering form of a mesh: every cell split into positively oriented tetrahedra (zero-volume
/// ones dropped) and one scalar field per point or per tetrahedron.
struct TetMesh {
    std::vector<Vec3f> points;
    std::vector<Tet> tets;
    std::vector<float> values;
    Association association = Association::Point;
    std::string fieldName;
    Bounds3f bounds;       ///< bounds of the points used by tets
    float valueMin = 0.f;  ///< finite range of the field over the tets' values
    float valueMax = 0.f;
    double totalVolume = 0.0;  ///< sum of tetrahedron volumes

    /// View for kernels; the TetMesh must outlive it.
    TetMeshView view() const {
        return {points.data(), tets.data(), values.data(), tets.size(),
                association == Association::Cell};
    }
};

/// Number of tetrahedra (at most 6) a cell splits into and their corners, as indices into the
/// cell's corner list. The split cones from the corner with the smallest global point index over
/// the faces not containing it, each quadrilateral face split along the diagonal through its
/// smallest global index, so cells sharing a face split it the same way (a conforming mesh).
/// Tetrahedra are positively oriented when the cell is (VTK's vertex order).
int splitCellIntoTets(CellType type, const std::uint32_t* ids, std::uint8_t out[6][4]);

/// Splits every cell of the mesh into tetrahedra and attaches the field; inverted cells are
/// re-oriented, zero-volume tetrahedra dropped (validateMesh reports both).
TetMesh tetrahedralize(const Mesh& mesh, const ScalarField& field);

}  // namespace uvr

namespace uvr {

/// Geometric state of one cell, from the signed volumes of its tetrahedra.
enum class CellShape : std::uint8_t {
    Valid,       ///< every tetrahedron positive
    Inverted,    ///< every non-degenerate tetrahedron negative (mirrored vertex order)
    ZeroVolume,  ///< total volume negligible against the cell's size
    Distorted,   ///< tetrahedra of both signs (a twisted or non-convex cell)
};

/// A cell split into tetrahedra (global point indices, each re-oriented to positive volume) with
/// its classification; zero-volume tetrahedra are left out of tets.
struct CellSplit {
    int count = 0;
    Tet tets[6];
    double volume6[6];  ///< six times each kept tetrahedron's (positive) volume
    CellShape shape = CellShape::Valid;
};

/// Splits and classifies cell c of the mesh (indices must be in range).
CellSplit splitCell(const Mesh& mesh, std::uint64_t c);

}  // namespace uvr
