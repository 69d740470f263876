// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/vtk_cells.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <span>

#include "uvr/core/error.h"

namespace uvr {

namespace {

constexpr int kPolyhedronType = 42;

/// A tetrahedron of a polyhedron's decomposition whose |6V| is below this fraction of its
/// (longest edge)^3 comes from a degenerate face triangle and is left out (tetrahedralize's rule).
constexpr double kZeroVolumeRelative = 1e-7;

constexpr int kPentagonalPrismType = 15, kHexagonalPrismType = 16;

/// Sides of the bases of a VTK pentagonal (15) or hexagonal (16) prism; 0 for other types.
int prismSides(std::int32_t type) {
    return type == kPentagonalPrismType ? 5 : type == kHexagonalPrismType ? 6 : 0;
}

std::string cellLabel(std::uint64_t c, std::int32_t type = kPolyhedronType) {
    const char* name = type == kPentagonalPrismType  ? "pentagonal prism"
                       : type == kHexagonalPrismType ? "hexagonal prism"
                                                     : "polyhedron";
    return "cell " + std::to_string(c) + " (" + name + ")";
}

/// The face stream of a prism whose bases have n sides, numbered as VTK's vtkPentagonalPrism and
/// vtkHexagonalPrism number them (the bottom base 0..n-1, the top n..2n-1 above it): the bottom
/// wound n-1, ..., 0, the top n, ..., 2n-1, the sides (i, i+1, n+i+1, n+i): one winding
/// throughout, as decomposePolyhedron needs.
void prismFaceStream(const std::int64_t* ids, int n, std::vector<std::int64_t>& out) {
    out.assign({n + 2, n});
    for (int i = n - 1; i >= 0; --i) out.push_back(ids[i]);
    out.push_back(n);
    for (int i = 0; i < n; ++i) out.push_back(ids[n + i]);
    for (int i = 0; i < n; ++i) {
        const int j = (i + 1) % n;
        out.insert(out.end(), {4, ids[i], ids[j], ids[n + j], ids[n + i]});
    }
}

/// VTK's ghost flags (vtkDataSetAttributes): cells flagged DUPLICATECELL (owned by another
/// piece) or HIDDENCELL (blanked), and cells using a point flagged HIDDENPOINT, are not part of
/// what ParaView shows.
constexpr unsigned kDuplicateCell = 1u, kHiddenCell = 32u, kHiddenPoint = 2u;
constexpr const char* kGhostArray = "vtkGhostType";

/// Checks one polyhedron's face stream [nFaces, n0, ids..., n1, ids...] and returns its number
/// of face triangles (sum of n_i - 2); throws Error(Parse) for a malformed stream and
/// Error(Validation) for a point index outside [0, pointCount).
std::uint64_t checkFaceStream(std::span<const std::int64_t> s, std::uint64_t c,
                              std::uint64_t pointCount, const std::string& file,
                              std::int32_t type = kPolyhedronType) {
    auto fail = [&](ErrorKind kind, const std::string& what) {
        throwError(kind, file, cellLabel(c, type) + ": " + what);
    };
    if (s.empty()) fail(ErrorKind::Parse, "empty face stream, expected a face count first");
    const std::int64_t faces = s[0];
    if (faces < 4)
        fail(ErrorKind::Parse, "face count " + std::to_string(faces) + ", expected at least 4");
    // Each face needs at least 4 entries (its count and 3 points).
    if (static_cast<std::uint64_t>(faces) > (s.size() - 1) / 4)
        fail(ErrorKind::Parse, "face count " + std::to_string(faces) +
                                   " does not fit its face stream of " + std::to_string(s.size()) +
                                   " entries");
    std::uint64_t k = 1, triangles = 0;
    for (std::int64_t f = 0; f < faces; ++f) {
        const std::string face = "face " + std::to_string(f) + " of " + std::to_string(faces);
        if (k >= s.size())
            fail(ErrorKind::Parse, face + " starts past the end of the face stream of " +
                                       std::to_string(s.size()) + " entries");
        const std::int64_t n = s[k];
        if (n < 3)
            fail(ErrorKind::Parse,
                 face + " lists " + std::to_string(n) + " points, expected at least 3");
        if (static_cast<std::uint64_t>(n) > s.size() - k - 1)
            fail(ErrorKind::Parse, face + " lists " + std::to_string(n) +
                                       " points, past the end of the face stream of " +
                                       std::to_string(s.size()) + " entries");
        for (std::int64_t j = 1; j <= n; ++j) {
            const std::int64_t id = s[k + j];
            if (id < 0 || static_cast<std::uint64_t>(id) >= pointCount)
                fail(ErrorKind::Validation, face + ": point index " + std::to_string(id) +
                                                " out of range [0, " + std::to_string(pointCount) +
                                                ")");
        }
        triangles += static_cast<std::uint64_t>(n) - 2;
        k += static_cast<std::uint64_t>(n) + 1;
    }
    if (k != s.size())
        fail(ErrorKind::Parse, "its " + std::to_string(faces) + " faces use " + std::to_string(k) +
                                   " entries of a face stream of " + std::to_string(s.size()));
    return triangles;
}

double det6(const double a[3], const double b[3], const double c[3], const double d[3]) {
    const double bx = b[0] - a[0], by = b[1] - a[1], bz = b[2] - a[2];
    const double cx = c[0] - a[0], cy = c[1] - a[1], cz = c[2] - a[2];
    const double dx = d[0] - a[0], dy = d[1] - a[1], dz = d[2] - a[2];
    return bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx);
}

/// What decomposing the polyhedra of one appendVtkCells call produced.
struct PolyhedraStats {
    std::uint64_t polyhedra = 0, tets = 0, inverted = 0, degenerate = 0;
    std::vector<std::uint32_t> vertices;          ///< distinct vertices of each polyhedron
    std::vector<std::uint64_t> vertexOffsets{0};  ///< polyhedra + 1 entries into vertices
};

/// Decomposes one (checked) polyhedron: a new point at the mean of its distinct vertices, each
/// face fanned from its smallest point index (for a quadrilateral the diagonal through it, as
/// splitCellIntoTets splits hexahedron, wedge and pyramid faces, so neighbours agree), each
/// triangle with the new point one tetrahedron, oriented positively when the faces wind
/// counter-clockwise seen from outside (VTK's rule; a stream wound the other way throughout
/// is turned). Tetrahedra of degenerate triangles are left out; those still negative (the
/// polyhedron is not star-shaped from its centroid) are counted and kept as they are.
void decomposePolyhedron(std::span<const std::int64_t> s, std::uint64_t c, Mesh& mesh,
                         std::vector<std::uint64_t>& source, PolyhedraStats& stats) {
    // Distinct vertices and their centroid.
    const std::size_t first = stats.vertices.size();
    const std::int64_t faces = s[0];
    for (std::size_t k = 1; k < s.size();) {
        const std::size_t n = static_cast<std::size_t>(s[k]);
        for (std::size_t j = 1; j <= n; ++j)
            stats.vertices.push_back(static_cast<std::uint32_t>(s[k + j]));
        k += n + 1;
    }
    std::sort(stats.vertices.begin() + first, stats.vertices.end());
    stats.vertices.erase(std::unique(stats.vertices.begin() + first, stats.vertices.end()),
                         stats.vertices.end());
    stats.vertexOffsets.push_back(stats.vertices.size());
    double centre[3] = {0.0, 0.0, 0.0};
    const std::size_t count = stats.vertices.size() - first;
    for (std::size_t i = first; i < stats.vertices.size(); ++i)
        for (int a = 0; a < 3; ++a) centre[a] += mesh.points[stats.vertices[i]][a];
    for (double& x : centre) x /= double(count);
    const std::uint32_t apex = static_cast<std::uint32_t>(mesh.points.size());
    mesh.points.emplace_back(float(centre[0]), float(centre[1]), float(centre[2]));
    const double apexPos[3] = {mesh.points[apex].x, mesh.points[apex].y, mesh.points[apex].z};

    // Face fans: tetrahedron (a, c, b, apex) for a counter-clockwise triangle (a, b, c).
    struct Candidate {
        std::uint32_t v[4];
        double det, eps;
    };
    std::vector<Candidate> tets;
    double total = 0.0;
    std::size_t k = 1;
    for (std::int64_t f = 0; f < faces; ++f) {
        const std::size_t n = static_cast<std::size_t>(s[k]);
        const std::int64_t* v = s.data() + k + 1;
        std::size_t m = 0;
        for (std::size_t j = 1; j < n; ++j)
            if (v[j] < v[m]) m = j;
        for (std::size_t j = 1; j + 1 < n; ++j) {
            const std::uint32_t a = static_cast<std::uint32_t>(v[m]);
            const std::uint32_t b = static_cast<std::uint32_t>(v[(m + j) % n]);
            const std::uint32_t d = static_cast<std::uint32_t>(v[(m + j + 1) % n]);
            Candidate t{{a, d, b, apex}, 0.0, 0.0};
            double p[4][3];
            for (int i = 0; i < 4; ++i)
                for (int x = 0; x < 3; ++x) p[i][x] = i == 3 ? apexPos[x] : mesh.points[t.v[i]][x];
            t.det = det6(p[0], p[1], p[2], p[3]);
            double longest = 0.0;
            for (int i = 0; i < 4; ++i)
                for (int j2 = i + 1; j2 < 4; ++j2) {
                    double l = 0.0;
                    for (int x = 0; x < 3; ++x) l += (p[i][x] - p[j2][x]) * (p[i][x] - p[j2][x]);
                    longest = std::fmax(longest, l);
                }
            t.eps = kZeroVolumeRelative * longest * std::sqrt(longest);
            total += t.det;
            tets.push_back(t);
        }
        k += n + 1;
    }

    // A stream wound clockwise throughout has a negative total: turn every tetrahedron.
    const bool turn = total < 0.0;
    for (Candidate& t : tets) {
        if (turn) std::swap(t.v[1], t.v[2]), t.det = -t.det;
        if (!(std::fabs(t.det) > t.eps)) {
            ++stats.degenerate;
            continue;
        }
        if (t.det < 0.0) ++stats.inverted;
        mesh.addCell(CellType::Tetra, t.v);
        source.push_back(c);
        ++stats.tets;
    }
    ++stats.polyhedra;
}

}  // namespace

std::vector<std::uint64_t> appendVtkCells(const VtkCellArrays& cells, Mesh& mesh,
                                          const std::string& file, LoadBudget* budget) {
    const std::uint64_t n = cells.types.size();
    if (cells.offsets.size() != n + 1)
        throwError(ErrorKind::Parse, file,
                   "cell offsets hold " + std::to_string(cells.offsets.size()) +
                       " entries, expected " + std::to_string(n + 1) + " for " + std::to_string(n) +
                       " cells");
    const bool separateFaces = cells.polyhedronFaces == PolyhedronFaces::Separate;
    if (separateFaces && cells.faceOffsets.size() != n + 1)
        throwError(ErrorKind::Parse, file,
                   "face offsets hold " + std::to_string(cells.faceOffsets.size()) +
                       " entries, expected " + std::to_string(n + 1) + " for " + std::to_string(n) +
                       " cells");
    const std::uint64_t pointCount = mesh.pointCount();
    // The face stream of polyhedron or prism c (a polyhedron's node list in legacy files).
    std::vector<std::int64_t> prismStream;
    auto faceStream = [&](std::uint64_t c) -> std::span<const std::int64_t> {
        if (const int sides = prismSides(cells.types[c])) {
            const std::int64_t begin = cells.offsets[c], nodes = cells.offsets[c + 1] - begin;
            if (nodes < 2 * sides)
                throwError(ErrorKind::Parse, file,
                           cellLabel(c, cells.types[c]) + " lists " + std::to_string(nodes) +
                               " nodes, expected " + std::to_string(2 * sides));
            prismFaceStream(cells.connectivity.data() + begin, sides, prismStream);
            return prismStream;
        }
        if (!separateFaces)
            return {cells.connectivity.data() + cells.offsets[c],
                    cells.connectivity.data() + cells.offsets[c + 1]};
        const std::int64_t b = cells.faceOffsets[c], e = cells.faceOffsets[c + 1];
        if (b < 0 || e < b || static_cast<std::uint64_t>(e) > cells.faces.size())
            throwError(ErrorKind::Parse, file,
                       cellLabel(c) + ": face stream range [" + std::to_string(b) + ", " +
                           std::to_string(e) + ") outside the faces array of " +
                           std::to_string(cells.faces.size()) + " entries");
        return {cells.faces.data() + b, cells.faces.data() + e};
    };

    // Check every cell's node range and every polyhedron's face stream first, and charge what
    // the polyhedra add before adding it.
    std::uint64_t polyhedra = 0, polyTriangles = 0;
    for (std::uint64_t c = 0; c < n; ++c) {
        const std::int64_t begin = cells.offsets[c], end = cells.offsets[c + 1];
        if (begin < 0 || end < begin || static_cast<std::uint64_t>(end) > cells.connectivity.size())
            throwError(ErrorKind::Parse, file,
                       "cell " + std::to_string(c) + ": node range [" + std::to_string(begin) +
                           ", " + std::to_string(end) + ") outside the connectivity array of " +
                           std::to_string(cells.connectivity.size()) + " entries");
        if (prismSides(cells.types[c])) {
            polyTriangles += checkFaceStream(faceStream(c), c, pointCount, file, cells.types[c]);
            ++polyhedra;
            continue;
        }
        if (cells.types[c] != kPolyhedronType) continue;
        if (cells.polyhedronFaces == PolyhedronFaces::None)
            throwError(ErrorKind::Unsupported, file,
                       "cell " + std::to_string(c) +
                           ": polyhedron cells (type 42) need their face streams, which these "
                           "arrays do not carry (write them to a .vtu or .vtk file)");
        polyTriangles += checkFaceStream(faceStream(c), c, pointCount, file);
        ++polyhedra;
    }
    if (polyhedra > 0) {
        if (pointCount + polyhedra > std::numeric_limits<std::uint32_t>::max())
            throwError(ErrorKind::Unsupported, file,
                       "more than 4294967295 points with the polyhedra's centroids are not "
                       "supported");
        if (budget) {
            std::uint64_t pointBytes = sizeof(Vec3f), cellBytes = 0;
            for (const Field& f : mesh.fields)
                (f.association == Association::Point ? pointBytes : cellBytes) +=
                    sizeof(float) * static_cast<std::uint64_t>(f.components);
            budget->charge(file, "the polyhedra's centroids", polyhedra, pointBytes);
            budget->charge(file, "the polyhedra's tetrahedra", polyTriangles,
                           sizeof(CellType) + sizeof(std::uint64_t) + 4 * sizeof(std::uint32_t) +
                               sizeof(std::uint64_t) + cellBytes);
        }
    }

    std::vector<std::uint64_t> source;  // per added cell, its cell in `cells`
    source.reserve(n - polyhedra + polyTriangles);
    std::map<std::string, std::uint64_t> dropped, reduced;
    std::uint64_t voxels = 0;
    PolyhedraStats poly;
    std::uint32_t ids[8];
    const std::uint64_t firstNewCell = mesh.cellCount();
    // VTK's ghost flags: this batch's cell flags and the points' (values checked by the reader
    // to be one per cell and point; flags are small integers, exact in float).
    const Field* cellGhosts = nullptr;
    const Field* pointGhosts = nullptr;
    for (const Field& f : mesh.fields) {
        if (f.name != kGhostArray || f.components != 1) continue;
        if (f.association == Association::Cell && f.values.size() == firstNewCell + n)
            cellGhosts = &f;
        if (f.association == Association::Point && f.values.size() == pointCount) pointGhosts = &f;
    }
    const auto flags = [](float v) { return v >= 0.f && v < 256.f ? unsigned(v) : 0u; };
    std::uint64_t duplicates = 0, hidden = 0, prisms = 0;
    for (std::uint64_t c = 0; c < n; ++c) {
        const std::int64_t begin = cells.offsets[c], end = cells.offsets[c + 1];
        if (cellGhosts) {
            const unsigned g = flags(cellGhosts->values[firstNewCell + c]);
            if (g & kDuplicateCell) {
                ++duplicates;
                continue;
            }
            if (g & kHiddenCell) {
                ++hidden;
                continue;
            }
        }
        if (pointGhosts) {
            const auto isHidden = [&](std::int64_t id) {
                return id >= 0 && static_cast<std::uint64_t>(id) < pointCount &&
                       (flags(pointGhosts->values[id]) & kHiddenPoint);
            };
            bool hiddenPoint = false;
            if (cells.types[c] == kPolyhedronType) {
                // [faces, (points, ids...) per face], checked above; in legacy files this is
                // the cell's own list, so the point ids lie between the counts.
                const std::span<const std::int64_t> s = faceStream(c);
                std::size_t k = 1;
                for (std::int64_t f = 0; f < s[0] && !hiddenPoint; ++f) {
                    const auto points = static_cast<std::size_t>(s[k++]);
                    for (std::size_t j = 0; j < points && !hiddenPoint; ++j)
                        hiddenPoint = isHidden(s[k + j]);
                    k += points;
                }
            } else {
                for (std::int64_t k = begin; k < end && !hiddenPoint; ++k)
                    hiddenPoint = isHidden(cells.connectivity[k]);
            }
            if (hiddenPoint) {
                ++hidden;
                continue;
            }
        }
        if (prismSides(cells.types[c])) {
            decomposePolyhedron(faceStream(c), c, mesh, source, poly);
            ++prisms;
            continue;
        }
        const VtkCellTypeInfo info = vtkCellTypeInfo(cells.types[c]);
        if (!info.known)
            throwError(ErrorKind::Parse, file,
                       "cell " + std::to_string(c) + ": unknown VTK cell type " +
                           std::to_string(cells.types[c]));
        if (cells.types[c] == kPolyhedronType) {
            if (separateFaces)  // the node list beside the faces: indices checked, not used
                for (std::int64_t k = begin; k < end; ++k)
                    if (cells.connectivity[k] < 0 ||
                        static_cast<std::uint64_t>(cells.connectivity[k]) >= pointCount)
                        throwError(ErrorKind::Validation, file,
                                   cellLabel(c) + ": point index " +
                                       std::to_string(cells.connectivity[k]) +
                                       " out of range [0, " + std::to_string(pointCount) + ")");
            decomposePolyhedron(faceStream(c), c, mesh, source, poly);
            continue;
        }
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
        source.push_back(c);
    }
    for (const auto& [name, count] : dropped)
        mesh.notes.push_back("dropped " + std::to_string(count) + " non-volumetric " + name +
                             " cell(s)");
    if (duplicates)
        mesh.notes.push_back("left out " + std::to_string(duplicates) +
                             " ghost cell(s) that vtkGhostType marks as duplicates of another "
                             "piece's (DUPLICATECELL), as ParaView does");
    if (hidden)
        mesh.notes.push_back("left out " + std::to_string(hidden) +
                             " cell(s) that vtkGhostType marks hidden (HIDDENCELL, or a "
                             "HIDDENPOINT corner), as ParaView does");
    if (voxels)
        mesh.notes.push_back("read " + std::to_string(voxels) +
                             " voxel cell(s) as hexahedra (the same cells, corners reordered)");
    for (const auto& [name, count] : reduced)
        mesh.notes.push_back(
            "reduced " + std::to_string(count) + " " + name +
            " cell(s) to their corner nodes: their mid-edge and higher-order nodes are used by "
            "no cell, and fields are interpolated between the corners");
    if (poly.polyhedra) {
        std::string note =
            std::to_string(poly.polyhedra) + " polyhedra" +
            (prisms ? " (" + std::to_string(prisms) + " of them pentagonal or hexagonal prisms)"
                    : std::string()) +
            " decomposed into " + std::to_string(poly.tets) +
            " tetrahedra around their vertex centroids (" + std::to_string(poly.polyhedra) +
            " points added; point fields there are the mean of the vertex "
            "values; docs/METHOD.md, Polyhedra)";
        if (poly.degenerate)
            note +=
                "; " + std::to_string(poly.degenerate) + " degenerate face triangle(s) left out";
        mesh.notes.push_back(note);
        if (poly.inverted)
            mesh.notes.push_back(
                std::to_string(poly.inverted) +
                " tetrahedra of polyhedra not star-shaped from their vertex centroid are "
                "inverted: validation reports them and rendering re-orients them, so those "
                "polyhedra render with overlapping tetrahedra");
    }

    // Point fields: each centroid gets the mean of its polyhedron's vertex values.
    if (poly.polyhedra) {
        for (Field& f : mesh.fields) {
            if (f.association != Association::Point) continue;
            const std::size_t comps = static_cast<std::size_t>(f.components);
            if (f.values.size() != pointCount * comps) continue;  // size checked by the reader
            f.values.resize((pointCount + poly.polyhedra) * comps);
            for (std::uint64_t p = 0; p < poly.polyhedra; ++p) {
                const std::uint64_t b = poly.vertexOffsets[p], e = poly.vertexOffsets[p + 1];
                for (std::size_t k = 0; k < comps; ++k) {
                    double sum = 0.0;
                    for (std::uint64_t i = b; i < e; ++i)
                        sum += f.values[poly.vertices[i] * comps + k];
                    f.values[(pointCount + p) * comps + k] = float(sum / double(e - b));
                }
            }
        }
    }
    // Cell fields of this batch (tuples beyond firstNewCell) onto the added cells.
    if (source.size() != n || poly.polyhedra) {
        for (Field& f : mesh.fields) {
            if (f.association != Association::Cell) continue;
            const std::size_t comps = static_cast<std::size_t>(f.components);
            const std::size_t base = firstNewCell * comps;
            if (f.values.size() != base + n * comps) continue;  // size checked by the reader
            std::vector<float> values(base + source.size() * comps);
            std::copy(f.values.begin(), f.values.begin() + base, values.begin());
            for (std::size_t i = 0; i < source.size(); ++i)
                for (std::size_t k = 0; k < comps; ++k)
                    values[base + i * comps + k] = f.values[base + source[i] * comps + k];
            f.values = std::move(values);
        }
    }
    return source;
}

}  // namespace uvr
