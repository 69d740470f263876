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

/// The exact similarity from a mesh file's coordinates to the rendering coordinates of its
/// TetMesh: local = (file - origin) * scale, with scale a power of two and origin a float beside
/// which every rendered point lies (so both steps are exact for them). The identity unless the
/// mesh is too large or too small for float32 kernels (cubed cell edges and squared distances
/// overflow or underflow) or lies too far from the origin for float32 to resolve its size
/// (frameForBounds).
struct MeshFrame {
    Vec3f origin{0.f, 0.f, 0.f};  ///< file position of the rendering origin
    double scale = 1.0;           ///< rendering units per file unit

    /// True for the identity (file coordinates are the rendering coordinates).
    bool identity() const { return scale == 1.0 && origin == Vec3f(0.f); }
    /// Rendering coordinates of a file position, in double (they may lie beyond float's range).
    void toLocal(Vec3f file, double out[3]) const {
        for (int a = 0; a < 3; ++a) out[a] = (double(file[a]) - origin[a]) * scale;
    }
    /// File coordinates of a rendering position, in double (they may lie beyond float's range).
    void toFile(Vec3f local, double out[3]) const {
        for (int a = 0; a < 3; ++a) out[a] = double(local[a]) / scale + origin[a];
    }
};

/// Mesh diagonals outside [2^-kFrameScaleExponent, 2^kFrameScaleExponent] are scaled to [1, 2):
/// within, float32 kernels keep cubed edges and squared distances in range for cells down to
/// 2^-18 of the mesh; beyond it, a 1e-30 mesh underflows and a 1e38 one overflows.
inline constexpr int kFrameScaleExponent = 24;
/// An axis whose centre lies more than 2^kFrameShiftExponent mesh diagonals from 0 is translated
/// to it: float32 resolves positions there to no better than 2^-16 of the mesh (a mesh at
/// x = 1e7 of size 1 has float spacing 1 in x).
inline constexpr int kFrameShiftExponent = 8;

/// The frame for a mesh with these (file) bounds: the identity for an empty box or one of
/// moderate size near the origin; else a power-of-two scale bringing the diagonal into [1, 2)
/// and, per far axis, a translation to the box's centre.
MeshFrame frameForBounds(const Bounds3f& bounds);

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
    /// Maps the file's coordinates to those of points, bounds and totalVolume (the identity for
    /// meshes of moderate size near the origin).
    MeshFrame frame;
    Bounds3f bounds;       ///< bounds of the points used by tets (finite)
    float valueMin = 0.f;  ///< finite range of the field over the tets' values
    float valueMax = 0.f;
    double totalVolume = 0.0;  ///< sum of tetrahedron volumes
    /// Per cell of the source mesh, how many tetrahedra it kept (0 to 6); tets lists them cell
    /// after cell, so this maps a cell field onto the tetrahedra (assignTetValues).
    std::vector<std::uint8_t> cellTets;

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
/// re-oriented, zero-volume tetrahedra (also those with a NaN/Inf corner) dropped (validateMesh
/// reports both); points are mapped by frameForBounds of the kept tetrahedra's bounds.
TetMesh tetrahedralize(const MeshView& mesh, const ScalarField& field);

/// Attaches a field of the source mesh to the tetrahedra: values (a point field's as they are, a
/// cell field's copied onto each of its cell's tetrahedra through cellTets), association, name
/// and the finite value range over the tetrahedra's values. tetrahedralize ends with it, and a
/// time step of the same mesh is attached with it without splitting again. Throws
/// Error(Argument) when the field does not hold one value per point (or per source cell).
void assignTetValues(TetMesh& mesh, const ScalarField& field);

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
CellSplit splitCell(const MeshView& mesh, std::uint64_t c);

}  // namespace uvr
