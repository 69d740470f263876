// SPDX-License-Identifier: MIT
// The mixed-cell mesh (generateMixedCellMesh): blocks of hexahedra, pyramids, wedges and
// tetrahedra with conforming faces.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <sstream>

#include "uvr/core/error.h"
#include "uvr/mesh/cell_math.h"
#include "uvr/mesh/procedural.h"
#include "uvr/mesh/procedural_detail.h"

namespace uvr {

namespace {

using namespace procedural_detail;

/// Local point of a block: corners 0..7 (bit 0 = +x, bit 1 = +y, bit 2 = +z), 8 its centre.
constexpr std::uint8_t kBlockCentre = 8;

/// A cell of a block template over local points.
struct LocalCell {
    CellType type = CellType::Tetra;
    std::array<std::uint8_t, 8> v{};
};

/// How a block face is cut: one quadrilateral, or two triangles along the diagonal through its
/// corners (u, v) = (0, 0) and (1, 1) (Diag0) or (1, 0) and (0, 1) (Diag1), where u and v are the
/// face's two axes in x, y, z order (both blocks of a face see the same). Any: no preference.
enum class FaceCut : std::uint8_t { Quad, Diag0, Diag1, Any };

/// Cuts of a block's 6 faces, face f = 2 * axis + side.
using BlockCuts = std::array<FaceCut, 6>;

/// What a block would like to be; it is filled so only where its neighbours agree on its faces.
enum class BlockTemplate : std::uint8_t { Hex, Pyramids, Wedges, WedgePyramidTet, Centre };

CellKind cellKindOf(CellType type) {
    switch (type) {
        case CellType::Tetra:
            return CellKind::Tet;
        case CellType::Pyramid:
            return CellKind::Pyramid;
        case CellType::Wedge:
            return CellKind::Wedge;
        case CellType::Hexahedron:
            break;
    }
    return CellKind::Hex;
}

Vec3f localPosition(std::uint8_t v) {
    if (v == kBlockCentre) return {0.5f, 0.5f, 0.5f};
    return {float(v & 1), float((v >> 1) & 1), float((v >> 2) & 1)};
}

/// Local corner (u, v) of block face f, u and v its axes in x, y, z order.
std::uint8_t blockFaceCorner(int f, int u, int v) {
    const int axis = f / 2, ua = axis == 0 ? 1 : 0, va = axis == 2 ? 1 : 2;
    return static_cast<std::uint8_t>((f % 2) << axis | u << ua | v << va);
}

/// A cell over local points (flipped in x when mirror), its corner order mirrored where needed to
/// be positively oriented (VTK order) in the undistorted block.
LocalCell orientedCell(CellType type, std::initializer_list<std::uint8_t> ids,
                       bool mirror = false) {
    LocalCell c;
    c.type = type;
    std::size_t n = 0;
    for (std::uint8_t v : ids) c.v[n++] = v == kBlockCentre || !mirror ? v : v ^ 1;
    // A corner tetrahedron of each type, positive exactly when the cell is.
    auto p = [&](int i) { return localPosition(c.v[i]); };
    const bool hex = type == CellType::Hexahedron;
    const int d = type == CellType::Tetra || type == CellType::Wedge ? 3 : 4;
    // VTK's wedge has (0, 1, 2) turning away from (3, 4, 5), unlike the other types' first face.
    const double sign = type == CellType::Wedge ? -1.0 : 1.0;
    if (sign * signedVolume(p(0), p(1), p(hex ? 3 : 2), p(d)) > 0.0) return c;
    switch (type) {
        case CellType::Tetra:
            std::swap(c.v[2], c.v[3]);
            break;
        case CellType::Pyramid:
            std::swap(c.v[1], c.v[3]);
            break;
        case CellType::Wedge:
            std::swap(c.v[1], c.v[2]);
            std::swap(c.v[4], c.v[5]);
            break;
        case CellType::Hexahedron:
            std::swap(c.v[1], c.v[3]);
            std::swap(c.v[5], c.v[7]);
            break;
    }
    return c;
}

/// The cells of a template; mirror flips its corners in x (Diag0 and Diag1 swap on the z faces).
/// Centre blocks are built from their cuts instead (centreCells).
std::vector<LocalCell> templateCells(BlockTemplate t, bool mirror) {
    std::vector<LocalCell> cells;
    switch (t) {
        case BlockTemplate::Hex:
            cells.push_back(orientedCell(CellType::Hexahedron, {0, 1, 3, 2, 4, 5, 7, 6}));
            break;
        case BlockTemplate::Pyramids:
            for (int f = 0; f < 6; ++f)
                cells.push_back(orientedCell(
                    CellType::Pyramid,
                    {blockFaceCorner(f, 0, 0), blockFaceCorner(f, 1, 0), blockFaceCorner(f, 1, 1),
                     blockFaceCorner(f, 0, 1), kBlockCentre}));
            break;
        case BlockTemplate::Wedges:
            // Two prisms either side of the diagonal plane through corners 0, 3, 7, 4.
            cells.push_back(orientedCell(CellType::Wedge, {0, 1, 3, 4, 5, 7}, mirror));
            cells.push_back(orientedCell(CellType::Wedge, {0, 3, 2, 4, 7, 6}, mirror));
            break;
        case BlockTemplate::WedgePyramidTet:
            // The second prism split into a pyramid on the diagonal plane (apex corner 2) and
            // the tetrahedron left over it.
            cells.push_back(orientedCell(CellType::Wedge, {0, 1, 3, 4, 5, 7}, mirror));
            cells.push_back(orientedCell(CellType::Pyramid, {0, 3, 7, 4, 2}, mirror));
            cells.push_back(orientedCell(CellType::Tetra, {2, 6, 4, 7}, mirror));
            break;
        case BlockTemplate::Centre:
            break;
    }
    return cells;
}

/// The cut of each block face the cells imply (Any for faces no cell face lies on).
BlockCuts cutsOf(const std::vector<LocalCell>& cells) {
    BlockCuts cuts;
    cuts.fill(FaceCut::Any);
    for (const LocalCell& c : cells) {
        const CellKind kind = cellKindOf(c.type);
        for (int fi = 0; fi < kindFaces(kind); ++fi) {
            const std::uint32_t packed = packedFace(kind, fi);
            const int size = faceSize(packed);
            std::uint8_t ids[4];
            std::uint8_t all = 7, any = 0;  // bits set in all corners / in any corner
            bool centre = false;
            for (int i = 0; i < size; ++i) {
                ids[i] = c.v[faceCorner(packed, i)];
                centre = centre || ids[i] == kBlockCentre;
                all &= ids[i];
                any |= ids[i];
            }
            if (centre) continue;
            for (int axis = 0; axis < 3; ++axis) {
                const int bit = 1 << axis;
                if (!(all & bit) && (any & bit)) continue;  // not on a face of this axis
                const int f = 2 * axis + ((all & bit) ? 1 : 0);
                if (size == 4) {
                    cuts[f] = FaceCut::Quad;
                    break;
                }
                // A triangle's diagonal joins its two corners differing in both face axes.
                for (int a = 0; a < 3; ++a)
                    for (int b = a + 1; b < 3; ++b)
                        if (std::popcount(unsigned(ids[a] ^ ids[b])) == 2)
                            cuts[f] = (ids[a] == blockFaceCorner(f, 0, 0) ||
                                       ids[b] == blockFaceCorner(f, 0, 0))
                                          ? FaceCut::Diag0
                                          : FaceCut::Diag1;
                break;
            }
        }
    }
    return cuts;
}

/// Pyramids (quadrilateral faces) and tetrahedra (triangle pairs) from the centre over each face.
std::vector<LocalCell> centreCells(const BlockCuts& cuts) {
    std::vector<LocalCell> cells;
    for (int f = 0; f < 6; ++f) {
        const std::uint8_t c00 = blockFaceCorner(f, 0, 0), c10 = blockFaceCorner(f, 1, 0),
                           c11 = blockFaceCorner(f, 1, 1), c01 = blockFaceCorner(f, 0, 1);
        switch (cuts[f]) {
            case FaceCut::Diag0:
                cells.push_back(orientedCell(CellType::Tetra, {c00, c10, c11, kBlockCentre}));
                cells.push_back(orientedCell(CellType::Tetra, {c00, c11, c01, kBlockCentre}));
                break;
            case FaceCut::Diag1:
                cells.push_back(orientedCell(CellType::Tetra, {c00, c10, c01, kBlockCentre}));
                cells.push_back(orientedCell(CellType::Tetra, {c10, c11, c01, kBlockCentre}));
                break;
            default:
                cells.push_back(
                    orientedCell(CellType::Pyramid, {c00, c10, c11, c01, kBlockCentre}));
                break;
        }
    }
    return cells;
}

/// The template a block would like, by its place in a pattern repeating every 4 layers along z:
/// hexahedra and pyramid blocks; wedge blocks between hexahedra and pyramid blocks; wedge +
/// pyramid + tetrahedron blocks on top of the wedges, between centre blocks; wedges again.
BlockTemplate mixedBlockTemplate(int i, int j, int k) {
    const bool even = (i + j) % 2 == 0;
    switch (k % 4) {
        case 0:
            return (i + 2 * j) % 4 < 2 ? BlockTemplate::Pyramids : BlockTemplate::Hex;
        case 2:
            return even ? BlockTemplate::WedgePyramidTet : BlockTemplate::Centre;
        default:
            return even         ? BlockTemplate::Wedges
                   : i % 2 == 0 ? BlockTemplate::Hex
                                : BlockTemplate::Pyramids;
    }
}

/// The cut of a face from the wishes of its two blocks (Any beyond the boundary): triangles win
/// over a quadrilateral, the lower block's diagonal over the upper's; no wish either side takes
/// the face's hash.
FaceCut resolveCut(FaceCut lower, FaceCut upper, std::uint64_t hash) {
    if (lower == FaceCut::Any && upper == FaceCut::Any) return FaceCut(hash % 3);
    if (lower == FaceCut::Any) return upper;
    if (upper == FaceCut::Any || lower == upper) return lower;
    if (lower == FaceCut::Quad) return upper;
    return lower;
}

}  // namespace

Mesh generateMixedCellMesh(int n, float jitter, std::uint64_t seed, bool hexahedraOnly) {
    if (n < 1 || n > kMaxMixedCellBlocks)
        throwError(ErrorKind::Argument, "",
                   "mixed-cell mesh: blocks per axis must be in [1, " +
                       std::to_string(kMaxMixedCellBlocks) + "], got " + std::to_string(n));
    if (!(jitter >= 0.f && jitter <= kMaxMixedCellJitter))
        throwError(ErrorKind::Argument, "",
                   "mixed-cell mesh: jitter must be in [0, " + std::to_string(kMaxMixedCellJitter) +
                       "] block sizes, got " + std::to_string(jitter));

    // Each template's cells and the face cuts they need (Centre: none, it takes any).
    constexpr int kTemplates = 5;
    std::array<std::array<std::vector<LocalCell>, 2>, kTemplates> templateCellsOf;
    std::array<std::array<BlockCuts, 2>, kTemplates> templateCuts;
    for (int t = 0; t < kTemplates; ++t)
        for (int m = 0; m < 2; ++m) {
            templateCellsOf[t][m] = templateCells(BlockTemplate(t), m == 1);
            templateCuts[t][m] = cutsOf(templateCellsOf[t][m]);
        }
    const std::uint64_t N = static_cast<std::uint64_t>(n), P = N + 1;
    // The diagonal of a column's wedges (all its wedge blocks agree, so they stack).
    auto mirrored = [&](std::uint64_t i, std::uint64_t j) {
        return (mix64(seed ^ mix64(0x6d69786564ull + i + P * j)) & 1) != 0;
    };
    auto blockTemplate = [&](std::uint64_t i, std::uint64_t j, std::uint64_t k) {
        return hexahedraOnly ? BlockTemplate::Hex : mixedBlockTemplate(int(i), int(j), int(k));
    };

    // Face cuts: the faces normal to axis a have coordinate 0..N along a and 0..N-1 across.
    const std::uint64_t facesPerAxis = N * N * P;
    auto faceIndex = [&](int axis, std::uint64_t i, std::uint64_t j, std::uint64_t k) {
        const std::uint64_t dx = axis == 0 ? P : N, dy = axis == 1 ? P : N;
        return axis * facesPerAxis + i + dx * (j + dy * k);
    };
    std::vector<FaceCut> cuts(3 * facesPerAxis);
    for (int axis = 0; axis < 3; ++axis) {
        const std::uint64_t nx = axis == 0 ? P : N, ny = axis == 1 ? P : N, nz = axis == 2 ? P : N;
        for (std::uint64_t k = 0; k < nz; ++k)
            for (std::uint64_t j = 0; j < ny; ++j)
                for (std::uint64_t i = 0; i < nx; ++i) {
                    const std::uint64_t c[3] = {i, j, k};
                    FaceCut lower = FaceCut::Any, upper = FaceCut::Any;
                    if (c[axis] > 0) {
                        std::uint64_t b[3] = {i, j, k};
                        --b[axis];
                        lower = templateCuts[int(blockTemplate(b[0], b[1], b[2]))]
                                            [mirrored(b[0], b[1])][2 * axis + 1];
                    }
                    if (c[axis] < N)
                        upper = templateCuts[int(blockTemplate(i, j, k))][mirrored(i, j)][2 * axis];
                    const std::uint64_t f = faceIndex(axis, i, j, k);
                    cuts[f] = resolveCut(lower, upper, mix64(seed ^ mix64(f + 0x637574ull)));
                }
    }

    // Lattice points; interior coordinates jittered, boundary ones stay on the boundary.
    Mesh mesh;
    const double h = 2.0 / static_cast<double>(N);
    auto coord = [&](std::uint64_t i) { return i == N ? 1.0 : -1.0 + h * static_cast<double>(i); };
    mesh.points.reserve(P * P * P + N * N * N);
    for (std::uint64_t k = 0; k <= N; ++k)
        for (std::uint64_t j = 0; j <= N; ++j)
            for (std::uint64_t i = 0; i <= N; ++i) {
                const Vec3f d = unitBallSample(seed, mesh.points.size());
                auto jittered = [&](std::uint64_t a, float da) {
                    const bool interior = a > 0 && a < N;
                    return static_cast<float>(coord(a) + (interior ? jitter * h * da : 0.0));
                };
                mesh.points.push_back({jittered(i, d.x), jittered(j, d.y), jittered(k, d.z)});
            }

    // Blocks: the wished template where the face cuts agree with it, else cells to the centre.
    std::vector<float> blockIds;
    std::uint64_t typeCounts[4] = {};  // tetra, pyramid, wedge, hexahedron
    std::uint64_t fallbacks = 0;
    for (std::uint64_t k = 0; k < N; ++k)
        for (std::uint64_t j = 0; j < N; ++j)
            for (std::uint64_t i = 0; i < N; ++i) {
                const BlockCuts actual = {
                    cuts[faceIndex(0, i, j, k)], cuts[faceIndex(0, i + 1, j, k)],
                    cuts[faceIndex(1, i, j, k)], cuts[faceIndex(1, i, j + 1, k)],
                    cuts[faceIndex(2, i, j, k)], cuts[faceIndex(2, i, j, k + 1)]};
                const int t = int(blockTemplate(i, j, k));
                const int m = mirrored(i, j) ? 1 : 0;
                const bool fits =
                    BlockTemplate(t) != BlockTemplate::Centre && templateCuts[t][m] == actual;
                if (!fits && BlockTemplate(t) != BlockTemplate::Centre) ++fallbacks;
                const std::vector<LocalCell> cells =
                    fits ? templateCellsOf[t][m] : centreCells(actual);
                std::uint32_t centre = 0;
                if (std::any_of(cells.begin(), cells.end(), [](const LocalCell& c) {
                        return std::find(c.v.begin(), c.v.end(), kBlockCentre) != c.v.end();
                    })) {
                    centre = static_cast<std::uint32_t>(mesh.points.size());
                    const Vec3f d = unitBallSample(seed, mesh.points.size());
                    auto mid = [&](std::uint64_t a, float da) {
                        return static_cast<float>(coord(a) + h * (0.5 + jitter * da));
                    };
                    mesh.points.push_back({mid(i, d.x), mid(j, d.y), mid(k, d.z)});
                }
                for (const LocalCell& c : cells) {
                    std::uint32_t ids[8];
                    const int corners = cornerCount(c.type);
                    for (int v = 0; v < corners; ++v)
                        ids[v] =
                            c.v[v] == kBlockCentre
                                ? centre
                                : static_cast<std::uint32_t>((i + (c.v[v] & 1)) +
                                                             P * ((j + ((c.v[v] >> 1) & 1)) +
                                                                  P * (k + ((c.v[v] >> 2) & 1))));
                    mesh.addCell(c.type, std::span<const std::uint32_t>(ids, corners));
                    blockIds.push_back(static_cast<float>(i + N * (j + N * k)));
                    ++typeCounts[int(cellKindOf(c.type))];
                }
            }

    // Fields: two analytic point fields, the block and the VTK type of each cell.
    Field linear{proceduralFieldName(ProceduralField::Linear), Association::Point, 1, {}};
    Field product{"xyz", Association::Point, 1, {}};
    for (const Vec3f& p : mesh.points) {
        linear.values.push_back(proceduralFieldValue(ProceduralField::Linear, p));
        product.values.push_back(p.x * p.y * p.z);
    }
    Field types{"cell_type", Association::Cell, 1, {}};
    for (CellType t : mesh.cellTypes) types.values.push_back(static_cast<float>(t));
    mesh.fields.push_back(std::move(linear));
    mesh.fields.push_back(std::move(product));
    mesh.fields.push_back(Field{"block", Association::Cell, 1, std::move(blockIds)});
    mesh.fields.push_back(std::move(types));

    std::ostringstream note;
    note << "procedural mixed cells: " << n << "^3 blocks (" << fallbacks
         << " cut to their centre to fit their neighbours), " << typeCounts[3] << " hexahedra, "
         << typeCounts[2] << " wedges, " << typeCounts[1] << " pyramids, " << typeCounts[0]
         << " tetrahedra, seed " << seed << ", jitter " << jitter;
    mesh.notes.push_back(note.str());
    return mesh;
}

}  // namespace uvr
