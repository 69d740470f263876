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

namespace uvr {

namespace {

constexpr double kPi = std::numbers::pi;

// ---------------------------------------------------------------------------------------------
// Deterministic hashing (SplitMix64 finaliser) and value/gradient noise.

constexpr std::uint64_t mix64(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/// Uniform double in [-1, 1) from the top 53 bits of a hash.
double hashToSigned(std::uint64_t h) {
    return static_cast<double>(h >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

/// Deterministic point in the unit ball for (seed, point index), by rejection sampling a cube.
Vec3f unitBallSample(std::uint64_t seed, std::uint64_t pointIndex) {
    const std::uint64_t base = mix64(seed ^ mix64(pointIndex));
    for (std::uint64_t attempt = 0; attempt < 64; ++attempt) {
        const std::uint64_t h = base + 3 * attempt;
        const double x = hashToSigned(mix64(h));
        const double y = hashToSigned(mix64(h + 1));
        const double z = hashToSigned(mix64(h + 2));
        if (x * x + y * y + z * z <= 1.0)
            return {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)};
    }
    return {};  // unreachable in practice (probability 0.48^64)
}

/// Hash of an integer lattice point for the noise functions.
std::uint64_t latticeHash(std::int64_t ix, std::int64_t iy, std::int64_t iz) {
    std::uint64_t h = mix64(static_cast<std::uint64_t>(ix) + 0x632be59bd9b4e019ull);
    h = mix64(h ^ static_cast<std::uint64_t>(iy));
    return mix64(h ^ static_cast<std::uint64_t>(iz));
}

/// Gradient noise in the manner of Perlin (2002, "Improving Noise"): pseudo-random gradients from
/// the 12 cube-edge directions at lattice points, blended with the quintic fade 6t^5-15t^4+10t^3.
/// Smooth (C2), zero at lattice points, roughly in [-1, 1].
double gradientNoise(double x, double y, double z) {
    static constexpr int kGrad[12][3] = {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0},
                                         {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
                                         {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1}};
    const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy),
               iz = static_cast<std::int64_t>(fz);
    const double tx = x - fx, ty = y - fy, tz = z - fz;
    auto fade = [](double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); };
    auto corner = [&](int dx, int dy, int dz) {
        const int* g = kGrad[latticeHash(ix + dx, iy + dy, iz + dz) % 12];
        return g[0] * (tx - dx) + g[1] * (ty - dy) + g[2] * (tz - dz);
    };
    const double u = fade(tx), v = fade(ty), w = fade(tz);
    auto lerp = [](double a, double b, double t) { return a + t * (b - a); };
    const double x00 = lerp(corner(0, 0, 0), corner(1, 0, 0), u);
    const double x10 = lerp(corner(0, 1, 0), corner(1, 1, 0), u);
    const double x01 = lerp(corner(0, 0, 1), corner(1, 0, 1), u);
    const double x11 = lerp(corner(0, 1, 1), corner(1, 1, 1), u);
    return lerp(lerp(x00, x10, v), lerp(x01, x11, v), w);
}

/// Fractal Brownian motion: `octaves` octaves of gradient noise, each at twice the frequency and
/// `gain` times the amplitude of the previous; normalised to roughly [-1, 1].
double fbm(double x, double y, double z, int octaves, double gain = 0.5) {
    double sum = 0.0, amplitude = 1.0, norm = 0.0;
    for (int o = 0; o < octaves; ++o) {
        sum += amplitude * gradientNoise(x, y, z);
        norm += amplitude;
        amplitude *= gain;
        x = 2.0 * x + 17.13;  // shift each octave so lattice zeros do not line up
        y = 2.0 * y + 5.71;
        z = 2.0 * z + 11.37;
    }
    return sum / norm;
}

/// A turbulent plume: a Gaussian jet rising along +y from y = -1, its width growing with height,
/// its axis meandering and its edge broken up by fractal noise; values in [0, 1].
double jetValue(double x, double y, double z) {
    const double h = std::clamp((y + 1.0) * 0.5, 0.0, 1.0);  // 0 at the nozzle, 1 at the top
    // Meandering axis: low-frequency noise whose amplitude grows with height.
    const double ox = 0.3 * h * gradientNoise(0.3, 1.6 * y + 0.5, 4.7);
    const double oz = 0.3 * h * gradientNoise(7.9, 1.6 * y + 2.5, 0.3);
    const double width = 0.08 + 0.32 * h;
    const double dx = x - ox, dz = z - oz;
    // Turbulence: distorts the radius and modulates the intensity, stronger higher up.
    const double turb = fbm(3.0 * x + 1.3, 3.0 * y - 0.7, 3.0 * z + 2.1, 4);
    const double r = std::sqrt(dx * dx + dz * dz) * (1.0 + 0.6 * h * turb);
    const double core = std::exp(-(r * r) / (width * width));
    const double intensity = (1.0 - 0.5 * h) * (1.0 + 0.5 * turb);
    return std::clamp(core * intensity, 0.0, 1.0);
}

/// The multiscale field: octaves of gradient noise from wavelength 1 (half the domain) down to
/// cellSize, each 1/sqrt(2) of the previous in amplitude; values in [0, 1].
double multiscaleValue(double x, double y, double z, double cellSize) {
    int octaves = 8;
    if (cellSize > 0.0)
        octaves = std::clamp(static_cast<int>(std::ceil(-std::log2(cellSize))) + 1, 1, 30);
    return std::clamp(0.5 + 1.2 * fbm(x + 0.37, y + 0.61, z + 0.13, octaves, std::sqrt(0.5)), 0.0,
                      1.0);
}

/// Marschner & Lobb (1994), "An evaluation of reconstruction filters for volume rendering",
/// eq. 3 with alpha = 0.25 and f_M = 6, over [-1, 1]^3; values in [0, 1].
double marschnerLobbValue(double x, double y, double z) {
    constexpr double kAlpha = 0.25, kFm = 6.0;
    const double r = std::sqrt(x * x + y * y);
    const double rhoR = std::cos(2.0 * kPi * kFm * std::cos(kPi * r / 2.0));
    return (1.0 - std::sin(kPi * z / 2.0) + kAlpha * (1.0 + rhoR)) / (2.0 * (1.0 + kAlpha));
}

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

/// Signed volume of tetrahedron (a, b, c, d); positive when d sees a, b, c counter-clockwise.
double signedVolume(Vec3f a, Vec3f b, Vec3f c, Vec3f d) {
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
    const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
    const double wx = d.x - a.x, wy = d.y - a.y, wz = d.z - a.z;
    return (ux * (vy * wz - vz * wy) - uy * (vx * wz - vz * wx) + uz * (vx * wy - vy * wx)) / 6.0;
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

// ---------------------------------------------------------------------------------------------
// Mixed-cell mesh: blocks of hexahedra, pyramids, wedges and tetrahedra with conforming faces.

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

double proceduralCellSize(const ProceduralSpec& spec) {
    return 2.0 / std::cbrt(std::max(1.0, static_cast<double>(spec.targetCells) / 6.0));
}

float proceduralFieldValue(ProceduralField field, Vec3f p, double cellSize) {
    const double x = p.x, y = p.y, z = p.z;
    switch (field) {
        case ProceduralField::Constant:
            return 1.f;
        case ProceduralField::Linear:
            return static_cast<float>(x + 2.0 * y - z);
        case ProceduralField::Jet:
            return static_cast<float>(jetValue(x, y, z));
        case ProceduralField::MarschnerLobb:
            return static_cast<float>(marschnerLobbValue(x, y, z));
        case ProceduralField::Multiscale:
            return static_cast<float>(multiscaleValue(x, y, z, cellSize));
    }
    return 0.f;
}

const char* proceduralFieldName(ProceduralField field) {
    switch (field) {
        case ProceduralField::Constant:
            return "constant";
        case ProceduralField::Linear:
            return "linear";
        case ProceduralField::Jet:
            return "jet";
        case ProceduralField::MarschnerLobb:
            return "marschner_lobb";
        case ProceduralField::Multiscale:
            return "multiscale";
    }
    return "?";
}

const char* proceduralShapeName(ProceduralShape shape) {
    switch (shape) {
        case ProceduralShape::Box:
            return "box";
        case ProceduralShape::Shell:
            return "shell";
        case ProceduralShape::Graded:
            return "graded";
    }
    return "?";
}

ProceduralShape parseProceduralShape(const std::string& name) {
    for (ProceduralShape s :
         {ProceduralShape::Box, ProceduralShape::Shell, ProceduralShape::Graded})
        if (name == proceduralShapeName(s)) return s;
    throwError(ErrorKind::Argument, "",
               "unknown procedural shape '" + name + "': expected box, shell or graded");
}

ProceduralField parseProceduralField(const std::string& name) {
    for (ProceduralField f :
         {ProceduralField::Constant, ProceduralField::Linear, ProceduralField::Jet,
          ProceduralField::MarschnerLobb, ProceduralField::Multiscale})
        if (name == proceduralFieldName(f)) return f;
    throwError(ErrorKind::Argument, "",
               "unknown procedural field '" + name +
                   "': expected constant, linear, jet, marschner_lobb or multiscale");
}

}  // namespace uvr
