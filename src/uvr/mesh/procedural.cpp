// SPDX-License-Identifier: MIT
#include "uvr/mesh/procedural.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>
#include <sstream>

#include "uvr/core/error.h"
#include "uvr/mesh/cell_math.h"
#include "uvr/mesh/io/native.h"
#include "uvr/mesh/procedural_detail.h"

namespace uvr {

namespace {

using namespace procedural_detail;

constexpr double kPi = std::numbers::pi;

// ---------------------------------------------------------------------------------------------
// Kuhn (Freudenthal) decomposition of a cube into 6 tetrahedra.

/// Corner bits of a cube: bit 0 = +x, bit 1 = +y, bit 2 = +z.
using TetTemplate = std::array<std::uint8_t, 4>;

/// The 6 Kuhn tetrahedra of a cube: for each permutation (a, b, c) of the axes, the path
/// 0 -> e_a -> e_a + e_b -> (1,1,1). All share the main diagonal 0-7, and the split of each cube
/// face is the same from both sides, so translated copies conform. det[e_a, e_a+e_b, 1] equals the
/// permutation's sign; odd permutations swap the last two corners to be positively oriented.
std::array<TetTemplate, 6> kuhnTemplates() {
    static constexpr int kPerms[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1},
                                         {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
    std::array<TetTemplate, 6> out{};
    for (int t = 0; t < 6; ++t) {
        const int a = 1 << kPerms[t][0], b = 1 << kPerms[t][1];
        out[t] = {0, static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(a | b), 7};
        if (t >= 3) std::swap(out[t][2], out[t][3]);  // odd permutations
    }
    return out;
}

/// Calls the user's callback about every 1% of the total work.
class ProgressReporter {
public:
    ProgressReporter(const std::function<void(double)>& callback, double totalWork)
        : callback_(callback), total_(std::max(totalWork, 1.0)) {
        if (callback_) callback_(0.0);
    }
    void advance(double work) {
        done_ += work;
        if (callback_ && done_ >= next_) {
            callback_(std::min(done_ / total_, 1.0));
            next_ = done_ + total_ / 100.0;
        }
    }
    void finish() {
        if (callback_) callback_(1.0);
    }

private:
    const std::function<void(double)>& callback_;
    double total_;
    double done_ = 0.0;
    double next_ = 0.0;
};

/// A structured block of nx * ny * nz cubes whose x and y axes may wrap around (periodic).
struct Block {
    std::uint32_t nx = 1, ny = 1, nz = 1;
    bool periodicX = false, periodicY = false;

    std::uint64_t pointsX() const { return periodicX ? nx : nx + 1ull; }
    std::uint64_t pointsY() const { return periodicY ? ny : ny + 1ull; }
    std::uint64_t pointCount() const { return pointsX() * pointsY() * (nz + 1ull); }
    std::uint64_t cellCount() const { return 6ull * nx * ny * nz; }
    std::uint32_t pointIndex(std::uint64_t i, std::uint64_t j, std::uint64_t k) const {
        if (periodicX && i == nx) i = 0;
        if (periodicY && j == ny) j = 0;
        return static_cast<std::uint32_t>(i + pointsX() * (j + pointsY() * k));
    }
};

/// Grid coordinates along one axis of the Box/Graded shapes and the jitter scale of each: the
/// smaller of the two neighbouring spacings (0 at the ends, which stay on the boundary).
struct AxisSamples {
    std::vector<double> coord;
    std::vector<double> jitterScale;
};

AxisSamples axisSamples(std::uint32_t n, bool graded) {
    AxisSamples a;
    a.coord.resize(n + 1);
    // Graded: g(u) = (e^{a u} - 1) / (e^a - 1) with e^a = 100, so spacing grows 100x along u.
    const double expA = 100.0, gradeA = std::log(expA);
    for (std::uint32_t i = 0; i <= n; ++i) {
        const double u = static_cast<double>(i) / n;
        const double g = graded ? std::expm1(gradeA * u) / (expA - 1.0) : u;
        a.coord[i] = i == n ? 1.0 : -1.0 + 2.0 * g;
    }
    a.jitterScale.assign(n + 1, 0.0);
    for (std::uint32_t i = 1; i < n; ++i)
        a.jitterScale[i] = std::min(a.coord[i] - a.coord[i - 1], a.coord[i + 1] - a.coord[i]);
    return a;
}

/// Number of cubes per axis whose 6 n^3 tetrahedra come closest (by ratio) to the target.
std::uint32_t cubeResolution(std::uint64_t targetCells) {
    const double c = std::cbrt(static_cast<double>(targetCells) / 6.0);
    const double lo = std::max(1.0, std::floor(c)), hi = lo + 1.0;
    const double target = static_cast<double>(targetCells);
    const double errLo = std::abs(std::log(6.0 * lo * lo * lo / target));
    const double errHi = std::abs(std::log(6.0 * hi * hi * hi / target));
    return static_cast<std::uint32_t>(errLo <= errHi ? lo : hi);
}

void checkPointCount(const Block& block, const ProceduralSpec& spec) {
    if (block.pointCount() > std::numeric_limits<std::uint32_t>::max())
        throwError(ErrorKind::Argument, "",
                   "procedural mesh of " + std::to_string(spec.targetCells) +
                       " target cells would need " + std::to_string(block.pointCount()) +
                       " points; at most 4294967295 (32-bit indices) are supported");
}

/// The shell's (u, v, r) extents: around the axis, around the tube, across the wall.
constexpr double kShellLenU = 2.0 * kPi * kShellMajorRadius;
constexpr double kShellLenV = 2.0 * kPi * 0.5 * (kShellInnerRadius + kShellOuterRadius);
constexpr double kShellLenR = kShellOuterRadius - kShellInnerRadius;

/// The block of cubes generateMesh splits for the spec's shape and target size.
Block proceduralBlock(const ProceduralSpec& spec) {
    if (spec.shape != ProceduralShape::Shell) {
        const std::uint32_t n = cubeResolution(spec.targetCells);
        return Block{n, n, n, false, false};
    }
    const double h = std::cbrt(6.0 * kShellLenU * kShellLenV * kShellLenR /
                               static_cast<double>(std::max<std::uint64_t>(spec.targetCells, 1)));
    auto cubes = [h](double len, double minimum) {
        return static_cast<std::uint32_t>(std::clamp(std::round(len / h), minimum, 1.0e6));
    };
    return Block{cubes(kShellLenU, 16.0), cubes(kShellLenV, 8.0), cubes(kShellLenR, 1.0), true,
                 true};
}

/// The points of a Box, Graded or Shell grid, each computed from its index alone (so that a file
/// can be written slab by slab without holding them): point i + pointsX (j + pointsY k).
class GridPoints {
public:
    explicit GridPoints(const ProceduralSpec& spec) : spec_(spec), block_(proceduralBlock(spec)) {
        checkPointCount(block_, spec);
        if (spec.shape != ProceduralShape::Shell)
            axis_ = axisSamples(block_.nx, spec.shape == ProceduralShape::Graded);
    }
    const Block& block() const { return block_; }
    /// Points per layer of constant k.
    std::uint64_t layerPoints() const { return block_.pointsX() * block_.pointsY(); }

    /// Points [begin, end) into out, in parallel.
    void fill(std::uint64_t begin, std::uint64_t end, Vec3f* out) const {
#pragma omp parallel for schedule(static)
        for (std::int64_t i = std::int64_t(begin); i < std::int64_t(end); ++i)
            out[std::uint64_t(i) - begin] = at(std::uint64_t(i));
    }

    Vec3f at(std::uint64_t index) const {
        const std::uint64_t i = index % block_.pointsX(), j = index / block_.pointsX();
        const std::uint64_t k = j / block_.pointsY();
        return spec_.shape == ProceduralShape::Shell ? shellPoint(index, i, j % block_.pointsY(), k)
                                                     : boxPoint(index, i, j % block_.pointsY(), k);
    }

private:
    /// Box and Graded: boundary coordinates have jitterScale 0, so faces stay planar.
    Vec3f boxPoint(std::uint64_t index, std::uint64_t i, std::uint64_t j, std::uint64_t k) const {
        const Vec3f d = unitBallSample(spec_.seed, index);
        return {static_cast<float>(axis_.coord[i] + spec_.jitter * axis_.jitterScale[i] * d.x),
                static_cast<float>(axis_.coord[j] + spec_.jitter * axis_.jitterScale[j] * d.y),
                static_cast<float>(axis_.coord[k] + spec_.jitter * axis_.jitterScale[k] * d.z)};
    }

    /// Shell: a torus around the z axis whose tube wall spans radii [kShellInnerRadius,
    /// kShellOuterRadius], built from a (u, v, r) grid periodic in u (around the axis) and v
    /// (around the tube). The map (u, v, r) -> ((R + r cos v) cos u, (R + r cos v) sin u, r sin v)
    /// has Jacobian r (R + r cos v) > 0, so positively oriented Kuhn tetrahedra stay positive. The
    /// map is not affine within a cell, which eats into the jitter margin of the Kuhn split: with
    /// the jitter radius scaled by kShellJitterScale and at least 16 x 8 x 1 cubes, inversions
    /// first appeared (over 1600 seeds and sizes at the largest jitter) only at a scale of 0.9
    /// to 1.0.
    Vec3f shellPoint(std::uint64_t index, std::uint64_t i, std::uint64_t j, std::uint64_t k) const {
        constexpr double kR = kShellMajorRadius, kR0 = kShellInnerRadius;
        constexpr double kShellJitterScale = 0.6;
        const double jitter = kShellJitterScale * spec_.jitter;
        const bool wall = k == 0 || k == block_.nz;  // the wall surfaces stay on their radius
        const Vec3f d = unitBallSample(spec_.seed, index);
        const double u = 2.0 * kPi * (double(i) + jitter * d.x) / block_.nx;
        const double v = 2.0 * kPi * (double(j) + jitter * d.y) / block_.ny;
        const double r = kR0 + kShellLenR * (double(k) + (wall ? 0.0 : jitter * d.z)) / block_.nz;
        const double rho = kR + r * std::cos(v);
        return {static_cast<float>(rho * std::cos(u)), static_cast<float>(rho * std::sin(u)),
                static_cast<float>(r * std::sin(v))};
    }

    const ProceduralSpec& spec_;
    Block block_;
    AxisSamples axis_;
};

/// Writes the Kuhn split of the cubes of layers [k0, k1) (6 tetrahedra a cube, x fastest) to out,
/// 4 indices each, in parallel, and checks that every tetrahedron has positive volume; pts holds
/// the points from index ptsBase on (at least those of layers k0 to k1).
void kuhnCells(const Block& block, std::uint32_t k0, std::uint32_t k1, const Vec3f* pts,
               std::uint64_t ptsBase, std::uint32_t* out) {
    const auto templates = kuhnTemplates();
    const std::int64_t rows = std::int64_t(k1 - k0) * block.ny;
    const std::uint64_t rowCells = 6ull * block.nx;
    std::atomic<std::uint64_t> firstBad{UINT64_MAX};  // no exception leaves the parallel loop
#pragma omp parallel for schedule(static)
    for (std::int64_t row = 0; row < rows; ++row) {
        const std::uint64_t k = k0 + std::uint64_t(row) / block.ny,
                            j = std::uint64_t(row) % block.ny;
        std::uint32_t* o = out + 4 * rowCells * std::uint64_t(row);
        for (std::uint64_t i = 0; i < block.nx; ++i) {
            std::uint32_t corner[8];
            for (int b = 0; b < 8; ++b)
                corner[b] = block.pointIndex(i + (b & 1), j + ((b >> 1) & 1), k + (b >> 2));
            for (const TetTemplate& t : templates) {
                for (int v = 0; v < 4; ++v) o[v] = corner[t[v]];
                if (!(signedVolume(pts[o[0] - ptsBase], pts[o[1] - ptsBase], pts[o[2] - ptsBase],
                                   pts[o[3] - ptsBase]) > 0.0)) {
                    const std::uint64_t cell = std::uint64_t(o - out) / 4;
                    std::uint64_t seen = firstBad.load();
                    while (cell < seen && !firstBad.compare_exchange_weak(seen, cell)) {
                    }
                }
                o += 4;
            }
        }
    }
    const std::uint64_t bad = firstBad.load();
    if (bad == UINT64_MAX) return;
    const std::uint32_t* o = out + 4 * bad;
    const double volume = signedVolume(pts[o[0] - ptsBase], pts[o[1] - ptsBase],
                                       pts[o[2] - ptsBase], pts[o[3] - ptsBase]);
    UVR_CHECK(volume > 0.0, "procedural tetrahedron " << 6ull * block.nx * block.ny * k0 + bad
                                                      << " has volume " << volume);
}

/// Layers of cubes per slab of a streamed write: about slabTets tetrahedra, at least one layer.
std::uint32_t layersPerChunk(const Block& block, std::uint64_t slabTets = kProceduralSlabTets) {
    const std::uint64_t layerCells = 6ull * block.nx * block.ny;
    return static_cast<std::uint32_t>(
        std::clamp<std::uint64_t>(slabTets / layerCells, 1, block.nz));
}

/// The Box, Graded and Shell meshes: a grid of points and the Kuhn split of its cubes.
void generateGrid(const ProceduralSpec& spec, Mesh& mesh, ProgressReporter& progress) {
    const GridPoints grid(spec);
    const Block& block = grid.block();
    const std::uint64_t layer = grid.layerPoints();
    mesh.points.resize(block.pointCount());
    for (std::uint64_t k = 0; k <= block.nz; ++k) {
        grid.fill(k * layer, (k + 1) * layer, mesh.points.data() + k * layer);
        progress.advance(double(layer));
    }
    const std::uint64_t cells = block.cellCount();
    mesh.cellTypes.assign(cells, CellType::Tetra);
    mesh.cellOffsets.resize(cells + 1);
    for (std::uint64_t c = 0; c <= cells; ++c) mesh.cellOffsets[c] = 4 * c;
    mesh.cellIndices.resize(4 * cells);
    const std::uint64_t layerCells = 6ull * block.nx * block.ny;
    for (std::uint32_t k = 0; k < block.nz; ++k) {
        kuhnCells(block, k, k + 1, mesh.points.data(), 0,
                  mesh.cellIndices.data() + 4 * layerCells * k);
        progress.advance(double(layerCells));
    }
    std::ostringstream note;
    note << "procedural " << proceduralShapeName(spec.shape) << ": ";
    if (spec.shape == ProceduralShape::Shell)
        note << block.nx << " x " << block.ny << " x " << block.nz << " (u, v, r) cubes";
    else
        note << block.nx << "^3 cubes";
    note << ", Kuhn split, " << mesh.cellCount() << " tetrahedra, seed " << spec.seed << ", jitter "
         << spec.jitter;
    mesh.notes.push_back(note.str());
}

/// Values of a procedural field at spec.time at the points, in parallel.
void fieldValues(const ProceduralSpec& spec, ProceduralField f, std::span<const Vec3f> points,
                 float* out) {
    const double c = std::cos(spec.time), s = std::sin(spec.time);
    const double cellSize = proceduralCellSize(spec);
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < std::int64_t(points.size()); ++i) {
        Vec3f p = points[i];
        if (spec.time != 0.0)  // turned by -time about y
            p = Vec3f(float(c * p.x + s * p.z), p.y, float(-s * p.x + c * p.z));
        out[i] = proceduralFieldValue(f, p, cellSize);
    }
}

/// Throws Error(Argument) for a spec generateMesh refuses.
void checkSpec(const ProceduralSpec& spec) {
    if (spec.targetCells == 0)
        throwError(ErrorKind::Argument, "", "procedural targetCells must be at least 1");
    if (!(spec.jitter >= 0.f && spec.jitter <= kMaxProceduralJitter))
        throwError(ErrorKind::Argument, "",
                   "procedural jitter must be in [0, " + std::to_string(kMaxProceduralJitter) +
                       "], got " + std::to_string(spec.jitter));
    for (size_t a = 0; a < spec.fields.size(); ++a)
        for (size_t b = 0; b < a; ++b)
            if (spec.fields[a] == spec.fields[b])
                throwError(ErrorKind::Argument, "",
                           std::string("procedural field '") + proceduralFieldName(spec.fields[a]) +
                               "' is listed twice");
}

/// Work units of generateMesh and writeProceduralNative: points and cells once, then every field
/// at every point.
double proceduralWork(const ProceduralSpec& spec) {
    const double estPoints = static_cast<double>(spec.targetCells) / 6.0;
    return estPoints + static_cast<double>(spec.targetCells) + spec.fields.size() * estPoints;
}

}  // namespace

std::uint64_t proceduralMeshBytes(const ProceduralSpec& spec) {
    const Block block = proceduralBlock(spec);
    const std::uint64_t pointBytes = sizeof(Vec3f) + sizeof(float) * spec.fields.size();
    const std::uint64_t cellBytes =
        sizeof(CellType) + sizeof(std::uint64_t) + 4 * sizeof(std::uint32_t);
    return block.pointCount() * pointBytes + block.cellCount() * cellBytes;
}

std::uint64_t proceduralStreamBytes(const ProceduralSpec& spec) {
    const Block block = proceduralBlock(spec);
    const std::uint64_t layers = layersPerChunk(block);
    const std::uint64_t layerPoints = block.pointsX() * block.pointsY();
    // A slab of points (one layer more for the cells) and its field values or cell indices, the
    // pieces of cell types and offsets.
    const std::uint64_t points = (layers + 1) * layerPoints * sizeof(Vec3f);
    const std::uint64_t values = layers * layerPoints * sizeof(float);
    const std::uint64_t indices = layers * 6ull * block.nx * block.ny * 4 * sizeof(std::uint32_t);
    const std::uint64_t typesAndOffsets =
        std::min<std::uint64_t>(1ull << 20, block.cellCount() + 1) * (1 + sizeof(std::uint64_t));
    return points + std::max(values, indices) + typesAndOffsets;
}

std::uint64_t proceduralTetCount(const ProceduralSpec& spec) {
    return proceduralBlock(spec).cellCount();
}

Mesh generateMesh(const ProceduralSpec& spec, const std::function<void(double)>& progress) {
    checkSpec(spec);
    ProgressReporter reporter(progress, proceduralWork(spec));
    Mesh mesh;
    generateGrid(spec, mesh, reporter);
    const double fieldWork = double(spec.fields.size()) * double(mesh.points.size());
    double reported = 0.0;
    setProceduralFields(mesh, spec, [&](double fraction) {
        reporter.advance(fraction * fieldWork - reported);
        reported = fraction * fieldWork;
    });
    reporter.finish();
    return mesh;
}

void setProceduralFields(Mesh& mesh, const ProceduralSpec& spec,
                         const std::function<void(double)>& progress) {
    const double total = double(mesh.points.size()) * double(spec.fields.size());
    double done = 0.0;
    mesh.fields.clear();
    mesh.fields.reserve(spec.fields.size());
    for (ProceduralField f : spec.fields) {
        Field field;
        field.name = proceduralFieldName(f);
        field.association = Association::Point;
        field.components = 1;
        field.values.resize(mesh.points.size());
        constexpr size_t kChunk = 8192;
        for (size_t begin = 0; begin < mesh.points.size(); begin += kChunk) {
            const size_t end = std::min(begin + kChunk, mesh.points.size());
            fieldValues(spec, f, std::span(mesh.points).subspan(begin, end - begin),
                        field.values.data() + begin);
            done += double(end - begin);
            if (progress && total > 0) progress(done / total);
        }
        mesh.fields.push_back(std::move(field));
    }
}

void writeProceduralNative(const ProceduralSpec& spec, const std::string& path,
                           const std::function<void(double)>& progress, std::uint64_t slabTets) {
    checkSpec(spec);
    const GridPoints grid(spec);
    const Block& block = grid.block();
    const std::uint64_t pointCount = block.pointCount(), cellCount = block.cellCount();
    std::vector<FieldInfo> fields;
    for (ProceduralField f : spec.fields)
        fields.push_back({proceduralFieldName(f), Association::Point, 1});
    ProgressReporter reporter(progress, proceduralWork(spec));
    NativeWriter out(path, pointCount, cellCount, 4 * cellCount, fields);

    // Points, then each field, in slabs of layers of points (recomputed for each array).
    const std::uint64_t layer = grid.layerPoints();
    const std::uint32_t slabLayers = layersPerChunk(block, slabTets);
    const std::uint64_t slabPoints = layer * slabLayers;
    std::vector<Vec3f> points;
    std::vector<float> values;
    auto pointSlabs = [&](auto&& use) {
        for (std::uint64_t begin = 0; begin < pointCount; begin += slabPoints) {
            const std::uint64_t end = std::min(pointCount, begin + slabPoints);
            points.resize(end - begin);
            grid.fill(begin, end, points.data());
            use();
        }
    };
    pointSlabs([&] {
        out.points(points);
        reporter.advance(double(points.size()));
    });

    // Cells: the types and offsets, then the indices in slabs of layers of cubes.
    out.tetrahedronTypesAndOffsets();
    const std::uint64_t layerCells = 6ull * block.nx * block.ny;
    std::vector<std::uint32_t> indices;
    for (std::uint32_t k0 = 0; k0 < block.nz; k0 += slabLayers) {
        const std::uint32_t k1 = std::min(block.nz, k0 + slabLayers);
        const std::uint64_t first = layer * k0, last = layer * (k1 + 1ull);
        points.resize(last - first);
        grid.fill(first, last, points.data());
        indices.resize(4 * layerCells * (k1 - k0));
        kuhnCells(block, k0, k1, points.data(), first, indices.data());
        out.cellIndices(indices);
        reporter.advance(double(layerCells * (k1 - k0)));
    }

    // Fields.
    for (ProceduralField f : spec.fields)
        pointSlabs([&] {
            values.resize(points.size());
            fieldValues(spec, f, points, values.data());
            out.fieldValues(values);
            reporter.advance(double(points.size()));
        });
    out.commit();
    reporter.finish();
}

}  // namespace uvr
