// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "uvr/core/bounds.h"
#include "uvr/core/host_device.h"
#include "uvr/core/progress.h"
#include "uvr/core/scratch_vector.h"
#include "uvr/core/vec.h"
#include "uvr/mesh/cell_math.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/mesh.h"
#include "uvr/mesh/tet_math.h"

namespace uvr {

/// Marks "no cell" (a boundary face, or a point outside the mesh); cell ids are below it.
inline constexpr std::uint32_t kNoCell = 0xffffffffu;

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

/// Kernels read tetrahedra in blocks of kTetBlockSize consecutive ids (issue 16): a tetrahedron
/// names its corners by 16-bit indices into its block's vertex list, which holds the positions
/// and point values side by side (TetMesh::tetCorners, encodeTetBlocks). A block's 4 * 8192
/// corners have at most 32768 distinct points, so 16 bits always suffice.
inline constexpr int kTetBlockBits = 13;
/// Tetrahedra per block.
inline constexpr std::uint32_t kTetBlockSize = 1u << kTetBlockBits;

/// A block's vertex: position and the point field's value (0 for cell data), one 16-byte load.
struct alignas(16) BlockVertex {
    Vec3f p;
    float value = 0.f;
};

/// A tetrahedron's four corners as indices into its block's vertices.
struct TetCorners16 {
    std::uint16_t v[4];
};

/// Plain-data view of a TetMesh for CPU and GPU kernels. Cell ids [0, tetCount) are
/// tetrahedra; the native cells follow (issue 14): pyramids, then wedges, then hexahedra, their
/// corners (5, 6, 8 point ids, VTK's order) one after another in nativeCorners. Face neighbour
/// tables hold faceCount(c) entries per cell from faceBase(c).
struct TetMeshView {
    const Vec3f* points = nullptr;
    const Tet* tets = nullptr;
    const float* values = nullptr;  ///< per point, or per cell (tetrahedra first) when cellCentered
    std::uint64_t tetCount = 0;
    bool cellCentered = false;
    const std::uint32_t* nativeCorners = nullptr;  ///< corners of the native cells, in id order
    std::uint64_t pyramidCount = 0, wedgeCount = 0, hexCount = 0;
    /// The kernels' tetrahedra (encodeTetBlocks): per tetrahedron its corners in its block, the
    /// blocks' vertices, and per block the index of its first vertex. Kernels read tetrahedra
    /// only through these (tetVertices); `tets` and point-data `values` serve host-side builds.
    const TetCorners16* tetCorners = nullptr;
    const BlockVertex* blockVertices = nullptr;
    const std::uint32_t* blockVertexBase = nullptr;
    /// Smooth gradients (computeSmoothGradients; null until computed): per block vertex for the
    /// tetrahedra, per point for the native cells.
    const Vec3f* blockGradients = nullptr;
    const Vec3f* pointGradients = nullptr;

    /// Every cell: tetrahedra and native cells.
    UVR_HOST_DEVICE std::uint64_t cellCount() const {
        return tetCount + pyramidCount + wedgeCount + hexCount;
    }
    /// True when the mesh has native cells.
    UVR_HOST_DEVICE bool hasNative() const { return pyramidCount + wedgeCount + hexCount > 0; }
    /// Tetrahedron t's corners (positions and point values) from its block.
    UVR_HOST_DEVICE UVR_INLINE void tetVertices(std::uint64_t t, BlockVertex out[4]) const {
        const TetCorners16 c = tetCorners[t];
        const BlockVertex* base = blockVertices + blockVertexBase[t >> kTetBlockBits];
        for (int k = 0; k < 4; ++k) out[k] = base[c.v[k]];
    }
    /// The kind of cell c.
    UVR_HOST_DEVICE CellKind kind(std::uint64_t c) const {
        if (c < tetCount) return CellKind::Tet;
        c -= tetCount;
        if (c < pyramidCount) return CellKind::Pyramid;
        c -= pyramidCount;
        return c < wedgeCount ? CellKind::Wedge : CellKind::Hex;
    }
    /// Point ids of cell c's corners into ids; returns their count (4, 5, 6 or 8).
    UVR_HOST_DEVICE int corners(std::uint64_t c, std::uint32_t ids[kMaxCellCorners]) const {
        if (c < tetCount) {
            const Tet& t = tets[c];
            ids[0] = t.v[0], ids[1] = t.v[1], ids[2] = t.v[2], ids[3] = t.v[3];
            return 4;
        }
        std::uint64_t j = c - tetCount, first = 0;
        int n = 5;
        if (j >= pyramidCount) {
            first = 5 * pyramidCount, j -= pyramidCount, n = 6;
            if (j >= wedgeCount) first += 6 * wedgeCount, j -= wedgeCount, n = 8;
        }
        const std::uint32_t* src = nativeCorners + first + std::uint64_t(n) * j;
        for (int i = 0; i < n; ++i) ids[i] = src[i];
        return n;
    }
    /// Cell c's corner positions into x and, when v is not null, their values into v (point
    /// data); returns the corner count.
    UVR_HOST_DEVICE int gather(std::uint64_t c, Vec3f x[kMaxCellCorners],
                               float* v = nullptr) const {
        std::uint32_t ids[kMaxCellCorners];
        const int n = corners(c, ids);
        for (int i = 0; i < n; ++i) x[i] = points[ids[i]];
        if (v)
            for (int i = 0; i < n; ++i) v[i] = values[ids[i]];
        return n;
    }
    /// gather as kernels read cells: a tetrahedron's corners from its block (where the blocks
    /// exist), a native cell's from the points; the same positions and point values.
    UVR_HOST_DEVICE int kernelGather(std::uint64_t c, Vec3f x[kMaxCellCorners],
                                     float* v = nullptr) const {
        if (c >= tetCount || !tetCorners) return gather(c, x, v);
        BlockVertex b[4];
        tetVertices(c, b);
        for (int k = 0; k < 4; ++k) x[k] = b[k].p;
        if (v)
            for (int k = 0; k < 4; ++k) v[k] = b[k].value;
        return 4;
    }
    /// Index of cell c's first face in a face-neighbour table (faceCount(c) entries follow).
    UVR_HOST_DEVICE std::uint64_t faceBase(std::uint64_t c) const {
        if (c < tetCount) return 4 * c;
        const std::uint64_t j = c - tetCount;
        const std::uint64_t pw = pyramidCount + wedgeCount;
        return 4 * tetCount + (j < pw ? 5 * j : 5 * pw + 6 * (j - pw));
    }
    /// Entries of a face-neighbour table over every cell.
    UVR_HOST_DEVICE std::uint64_t faceSlots() const {
        return 4 * tetCount + 5 * (pyramidCount + wedgeCount) + 6 * hexCount;
    }
    /// Bounding box of cell c.
    UVR_HOST_DEVICE Bounds3f cellBounds(std::uint64_t c) const {
        std::uint32_t ids[kMaxCellCorners];
        const int n = corners(c, ids);
        Bounds3f b;
        for (int i = 0; i < n; ++i) b.extend(points[ids[i]]);
        return b;
    }

    /// Interpolated field value in cell c at its local coordinates (piecewise constant for cell
    /// data): barycentrics bary[0..3] in a tetrahedron, parametric (r, s, t) = bary[0..2] in a
    /// native cell. kNative false: the mesh has tetrahedra only (the kernels' specialisation
    /// for them, without the native cells' code).
    template <bool kNative = true>
    UVR_HOST_DEVICE float interpolate(std::uint64_t t, const float bary[4]) const {
        if (cellCentered) return values[t];
        if (!kNative || t < tetCount) {
            BlockVertex x[4];
            tetVertices(t, x);
            return bary[0] * x[0].value + bary[1] * x[1].value + bary[2] * x[2].value +
                   bary[3] * x[3].value;
        }
        return interpolateNative(t, bary);
    }
    /// interpolate in native cell t (parametric coordinates bary[0..2]).
    UVR_HOST_DEVICE float interpolateNative(std::uint64_t t, const float bary[4]) const {
        std::uint32_t ids[kMaxCellCorners];
        const int n = corners(t, ids);
        float w[kMaxCellCorners];
        shapeFunctions(kind(t), bary[0], bary[1], bary[2], w);
        float v = 0.f;
        for (int i = 0; i < n; ++i) v += w[i] * values[ids[i]];
        return v;
    }
    /// Gradient of the interpolated field in cell c at its local coordinates (as interpolate
    /// takes them). Per cell (smooth false): a tetrahedron's constant gradient, a native cell's
    /// through the inverse of its Jacobian (cellGradient); non-finite for a degenerate cell.
    /// Smooth: the corners' smooth gradients (computeSmoothGradients) interpolated as the field
    /// is (the per-cell one where they were not computed). Zero for cell data (constant in each
    /// cell).
    template <bool kNative = true>
    UVR_HOST_DEVICE Vec3f gradient(std::uint64_t c, const float bary[4], bool smooth) const {
        if (cellCentered) return Vec3f(0.f);
        if (!kNative || c < tetCount) {
            if (smooth && blockGradients) {
                const TetCorners16 k = tetCorners[c];
                const Vec3f* g = blockGradients + blockVertexBase[c >> kTetBlockBits];
                return g[k.v[0]] * bary[0] + g[k.v[1]] * bary[1] + g[k.v[2]] * bary[2] +
                       g[k.v[3]] * bary[3];
            }
            BlockVertex x[4];
            tetVertices(c, x);
            return tetGradient(x[0].p, x[1].p, x[2].p, x[3].p, x[0].value, x[1].value, x[2].value,
                               x[3].value);
        }
        if (smooth && pointGradients) {
            std::uint32_t ids[kMaxCellCorners];
            const int n = corners(c, ids);
            float w[kMaxCellCorners];
            shapeFunctions(kind(c), bary[0], bary[1], bary[2], w);
            Vec3f g(0.f);
            for (int i = 0; i < n; ++i) g += pointGradients[ids[i]] * w[i];
            return g;
        }
        Vec3f x[kMaxCellCorners];
        float v[kMaxCellCorners];
        gather(c, x, v);
        return cellGradient(kind(c), x, v, Vec3f(bary[0], bary[1], bary[2]));
    }
};

/// The rendering form of a mesh: tetrahedra (positively oriented, zero-volume ones dropped) and,
/// unless cells are split (TetrahedralizeOptions::splitCells), native pyramids, wedges and
/// hexahedra after them (TetMeshView says how ids are numbered); one scalar field per point or
/// per cell.
struct TetMesh {
    std::vector<Vec3f> points;
    ScratchVector<Tet> tets;  ///< (scratch vectors: filled in parallel, never zeroed first)
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
    /// Per cell of the source mesh, how many tetrahedra it kept (0 to 6), in cell order: with
    /// tetSourceOrder this maps a cell field onto the tetrahedra (assignTetValues).
    std::vector<std::uint8_t> cellTets;
    /// Native cells' corners (5 per pyramid, 6 per wedge, 8 per hexahedron) in id order.
    std::vector<std::uint32_t> nativeCorners;
    std::uint64_t pyramidCount = 0, wedgeCount = 0, hexCount = 0;
    /// Per native cell, its cell of the source mesh (cell data is attached through it).
    std::vector<std::uint64_t> nativeSource;
    /// Per tetrahedron, its index in cell order (the tetrahedra of cell 0, then of cell 1, ...,
    /// as cellTets counts them) before sortCellsSpatially reordered them; empty: that order.
    ScratchVector<std::uint32_t> tetSourceOrder;
    /// The kernels' form of the tetrahedra (encodeTetBlocks; TetMeshView::tetCorners).
    ScratchVector<TetCorners16> tetCorners;
    std::vector<BlockVertex> blockVertices;
    std::vector<std::uint32_t> blockVertexBase;   ///< per block and one past the last
    std::vector<std::uint32_t> blockVertexPoint;  ///< point id of each block vertex
    /// Smooth gradients for shading (computeSmoothGradients; empty until asked for): per block
    /// vertex, and per point with native cells.
    std::vector<Vec3f> blockGradients;
    std::vector<Vec3f> pointGradients;

    /// Tetrahedra: those of `tets`, or of the kernels' blocks where `tets` is not held (a mesh
    /// read from a prepared cache).
    std::uint64_t tetCount() const {
        return tets.size() > tetCorners.size() ? tets.size() : tetCorners.size();
    }
    /// Every rendered cell: tetrahedra and native cells.
    std::uint64_t cellCount() const { return tetCount() + pyramidCount + wedgeCount + hexCount; }
    /// Tetrahedra the cells would split into (a pyramid 2, a wedge 3, a hexahedron 6): what the
    /// default step and memory estimates count, so a native mesh samples as its split does.
    std::uint64_t splitTetCount() const {
        return tetCount() + 2 * pyramidCount + 3 * wedgeCount + 6 * hexCount;
    }
    /// True when the mesh has native cells.
    bool hasNative() const { return pyramidCount + wedgeCount + hexCount > 0; }
    /// splitTetCount per cell (1 for tetrahedra only): grids sized by tetrahedra per grid cell
    /// scale a partition's cell count by it, so a native mesh gets its split's grids.
    double meanSplitTets() const {
        if (wholeMeanSplitTets > 0.0) return wholeMeanSplitTets;
        return cellCount() ? double(splitTetCount()) / double(cellCount()) : 1.0;
    }
    /// When > 0 (a data-parallel rank's piece of a mesh): the whole mesh's meanSplitTets, which
    /// meanSplitTets gives instead of the piece's own, so grids and leaves are sized as the whole
    /// mesh's.
    double wholeMeanSplitTets = 0.0;
    /// View for kernels; the TetMesh must outlive it.
    TetMeshView view() const {
        TetMeshView v{points.data(), tets.empty() ? nullptr : tets.data(), values.data(),
                      tetCount(), association == Association::Cell};
        v.nativeCorners = nativeCorners.data();
        v.pyramidCount = pyramidCount, v.wedgeCount = wedgeCount, v.hexCount = hexCount;
        v.tetCorners = tetCorners.data();
        v.blockVertices = blockVertices.data();
        v.blockVertexBase = blockVertexBase.data();
        v.blockGradients = blockGradients.empty() ? nullptr : blockGradients.data();
        v.pointGradients = pointGradients.empty() ? nullptr : pointGradients.data();
        return v;
    }
};

/// "N tetrahedra", or with native cells "N cells (a tetrahedra, b pyramids, c wedges, d
/// hexahedra)" leaving out kinds of none: for progress lines.
std::string describeCells(const TetMesh& mesh);

/// Sorts cells by 63-bit keys elsewhere (sortCellKeysCuda: on the GPU): writes to
/// order[0, count) the positions of keys[0, count) in ascending order of (key, position).
using CellOrderSorter =
    std::function<void(const std::uint64_t* keys, std::uint64_t count, std::uint32_t* order)>;

/// How tetrahedralize treats pyramids, wedges and hexahedra.
struct TetrahedralizeOptions {
    /// Split every cell into tetrahedra (`--split-cells`); false: keep pyramids, wedges and
    /// hexahedra whose isoparametric map is one-to-one (nativeOrientation) as native cells,
    /// splitting only those that fold or collapse.
    bool splitCells = false;
    /// Reorder the cells of each kind along a Morton curve (sortCellsSpatially); false: cell
    /// order (the tetrahedra of each source cell after those of the cells before it).
    bool spatialOrder = true;
    /// When set, the Morton order's sort runs there (the same order).
    CellOrderSorter sorter = nullptr;
    /// When set, the rendering frame instead of frameForBounds of the kept cells' bounds (a
    /// rank's piece of a mesh rendered data-parallel takes the whole mesh's).
    std::optional<MeshFrame> frame = std::nullopt;
};

/// Number of tetrahedra (at most 6) a cell splits into and their corners, as indices into the
/// cell's corner list. The split cones from the corner with the smallest global point index over
/// the faces not containing it, each quadrilateral face split along the diagonal through its
/// smallest global index, so cells sharing a face split it the same way (a conforming mesh).
/// Tetrahedra are positively oriented when the cell is (VTK's vertex order).
int splitCellIntoTets(CellType type, const std::uint32_t* ids, std::uint8_t out[6][4]);

/// Splits the cells of the mesh into tetrahedra (all of them, or only those that cannot stay
/// native: options) and attaches the field; inverted cells are re-oriented, zero-volume
/// tetrahedra (also those with a NaN/Inf corner) dropped (validateMesh reports both); points are
/// mapped by frameForBounds of the kept cells' bounds; cells are put in Morton order (unless
/// options say not) and the tetrahedra's blocks encoded (encodeTetBlocks). `progress` hears the
/// fraction done.
TetMesh tetrahedralize(const MeshView& mesh, const ScalarField& field,
                       const TetrahedralizeOptions& options = {}, const FractionFn& progress = {});

/// Reorders the tetrahedra, and the native cells of each kind among themselves, by the 63-bit
/// Morton code of their centroids over the mesh bounds (ties by their present order), so cells
/// close in id lie close in space: the blocks of the kernels' layout then share most of their
/// points and neighbours. Keeps tetSourceOrder (and nativeSource) so cell data still maps onto
/// the cells; call it before assignTetValues and encodeTetBlocks. Parallel; the same order for
/// any thread count. `progress` hears the fraction done; `sorter`, when set, sorts the keys.
void sortCellsSpatially(TetMesh& mesh, const FractionFn& progress = {},
                        const CellOrderSorter& sorter = {});

/// Builds the kernels' form of the tetrahedra: per block of kTetBlockSize consecutive ids its
/// distinct points (positions, point values) and each tetrahedron's corners as indices into
/// them. Throws Error(Unsupported) when the blocks' vertices exceed 32-bit indices. Parallel;
/// `progress` hears the fraction done.
void encodeTetBlocks(TetMesh& mesh, const FractionFn& progress = {});

/// The bounding box of the field's gradient over point-data cell c of m: a tetrahedron's one
/// constant gradient; a native cell's gradients at its corners and centre (a pyramid's apex,
/// where the map is singular, replaced by the middle of its axis), an estimate of their range.
/// Empty when one is not finite (a degenerate cell, NaN values).
UVR_HOST_DEVICE inline Bounds3f cellGradientBounds(const TetMeshView& m, std::uint64_t c) {
    Vec3f x[kMaxCellCorners];
    float v[kMaxCellCorners];
    const int n = m.kernelGather(c, x, v);
    const CellKind k = m.kind(c);
    Bounds3f box;
    if (k == CellKind::Tet) {
        const Vec3f g = tetGradient(x[0], x[1], x[2], x[3], v[0], v[1], v[2], v[3]);
        if (isFinite(g)) box.extend(g);
        return box;
    }
    for (int i = 0; i <= n; ++i) {
        Vec3f rst = i < n ? cornerParametric(k, i) : cellCentreParametric(k);
        if (k == CellKind::Pyramid && i == 4) rst = Vec3f(0.5f, 0.5f, 0.5f);
        const Vec3f g = cellGradient(k, x, v, rst);
        if (!isFinite(g)) return Bounds3f{};
        box.extend(g);
    }
    return box;
}

/// Attaches a field of the source mesh to the cells: values (a point field's as they are, a
/// cell field's copied onto each of its cell's tetrahedra through cellTets and onto native cells
/// through nativeSource), association, name and the finite value range over the cells' values;
/// the blocks' vertex values (encodeTetBlocks) when the blocks exist.
/// tetrahedralize ends with it, and a time step of the same mesh is attached with it without
/// splitting again. Throws Error(Argument) when the field does not hold one value per point (or per
/// source cell).
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
