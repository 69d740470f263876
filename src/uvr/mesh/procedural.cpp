// SPDX-License-Identifier: MIT
#include "uvr/mesh/procedural.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "uvr/core/error.h"

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

/// Fills the mesh's cells with the Kuhn split of every cube of the block (reserved exactly; no
/// per-cell allocation) and checks that every tetrahedron has positive volume.
void emitKuhnCells(const Block& block, Mesh& mesh, ProgressReporter& progress) {
    const std::uint64_t cells = block.cellCount();
    mesh.cellTypes.assign(cells, CellType::Tetra);
    mesh.cellOffsets.resize(cells + 1);
    for (std::uint64_t c = 0; c <= cells; ++c) mesh.cellOffsets[c] = 4 * c;
    mesh.cellIndices.resize(4 * cells);
    const auto templates = kuhnTemplates();
    std::uint32_t* out = mesh.cellIndices.data();
    const Vec3f* pts = mesh.points.data();
    for (std::uint32_t k = 0; k < block.nz; ++k) {
        for (std::uint32_t j = 0; j < block.ny; ++j) {
            for (std::uint32_t i = 0; i < block.nx; ++i) {
                std::uint32_t corner[8];
                for (int b = 0; b < 8; ++b)
                    corner[b] = block.pointIndex(i + (b & 1), j + ((b >> 1) & 1), k + (b >> 2));
                for (const TetTemplate& t : templates) {
                    for (int v = 0; v < 4; ++v) out[v] = corner[t[v]];
                    const double volume =
                        signedVolume(pts[out[0]], pts[out[1]], pts[out[2]], pts[out[3]]);
                    UVR_CHECK(volume > 0.0, "procedural tetrahedron "
                                                << (out - mesh.cellIndices.data()) / 4
                                                << " has volume " << volume);
                    out += 4;
                }
            }
            progress.advance(6.0 * block.nx);
        }
    }
}

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

void generateBox(const ProceduralSpec& spec, bool graded, Mesh& mesh, ProgressReporter& progress) {
    const Block block = proceduralBlock(spec);
    const std::uint32_t n = block.nx;
    checkPointCount(block, spec);
    const AxisSamples axis = axisSamples(n, graded);
    mesh.points.resize(block.pointCount());
    std::uint64_t index = 0;
    for (std::uint32_t k = 0; k <= n; ++k) {
        for (std::uint32_t j = 0; j <= n; ++j) {
            for (std::uint32_t i = 0; i <= n; ++i, ++index) {
                // Boundary coordinates have jitterScale 0, so faces stay planar.
                const Vec3f d = unitBallSample(spec.seed, index);
                mesh.points[index] = {
                    static_cast<float>(axis.coord[i] + spec.jitter * axis.jitterScale[i] * d.x),
                    static_cast<float>(axis.coord[j] + spec.jitter * axis.jitterScale[j] * d.y),
                    static_cast<float>(axis.coord[k] + spec.jitter * axis.jitterScale[k] * d.z)};
            }
            progress.advance(n + 1.0);
        }
    }
    emitKuhnCells(block, mesh, progress);
    std::ostringstream note;
    note << "procedural " << (graded ? "graded" : "box") << ": " << n << "^3 cubes, Kuhn split, "
         << mesh.cellCount() << " tetrahedra, seed " << spec.seed << ", jitter " << spec.jitter;
    mesh.notes.push_back(note.str());
}

/// Shell: a torus around the z axis whose tube wall spans radii [kShellInnerRadius,
/// kShellOuterRadius], built from a (u, v, r) grid periodic in u (around the axis) and v (around
/// the tube). The map (u, v, r) -> ((R + r cos v) cos u, (R + r cos v) sin u, r sin v) has
/// Jacobian r (R + r cos v) > 0, so positively oriented Kuhn tetrahedra stay positive. The map is
/// not affine within a cell, which eats into the jitter margin of the Kuhn split: with the jitter
/// radius scaled by kShellJitterScale and at least 16 x 8 x 1 cubes, inversions first appeared
/// (over 1600 seeds and sizes at the largest jitter) only at a scale of 0.9 to 1.0.
void generateShell(const ProceduralSpec& spec, Mesh& mesh, ProgressReporter& progress) {
    constexpr double kR = kShellMajorRadius, kR0 = kShellInnerRadius;
    constexpr double kShellJitterScale = 0.6;
    const double jitter = kShellJitterScale * spec.jitter;
    const double lenR = kShellLenR;
    const Block block = proceduralBlock(spec);
    checkPointCount(block, spec);
    mesh.points.resize(block.pointCount());
    std::uint64_t index = 0;
    for (std::uint32_t k = 0; k <= block.nz; ++k) {
        const bool wall = k == 0 || k == block.nz;  // the wall surfaces stay on their radius
        for (std::uint32_t j = 0; j < block.ny; ++j) {
            for (std::uint32_t i = 0; i < block.nx; ++i, ++index) {
                const Vec3f d = unitBallSample(spec.seed, index);
                const double u = 2.0 * kPi * (i + jitter * d.x) / block.nx;
                const double v = 2.0 * kPi * (j + jitter * d.y) / block.ny;
                const double r = kR0 + lenR * (k + (wall ? 0.0 : jitter * d.z)) / block.nz;
                const double rho = kR + r * std::cos(v);
                mesh.points[index] = {static_cast<float>(rho * std::cos(u)),
                                      static_cast<float>(rho * std::sin(u)),
                                      static_cast<float>(r * std::sin(v))};
            }
            progress.advance(block.nx);
        }
    }
    emitKuhnCells(block, mesh, progress);
    std::ostringstream note;
    note << "procedural shell: " << block.nx << " x " << block.ny << " x " << block.nz
         << " (u, v, r) cubes, Kuhn split, " << mesh.cellCount() << " tetrahedra, seed "
         << spec.seed << ", jitter " << spec.jitter;
    mesh.notes.push_back(note.str());
}

}  // namespace

std::uint64_t proceduralMeshBytes(const ProceduralSpec& spec) {
    const Block block = proceduralBlock(spec);
    const std::uint64_t pointBytes = sizeof(Vec3f) + sizeof(float) * spec.fields.size();
    const std::uint64_t cellBytes =
        sizeof(CellType) + sizeof(std::uint64_t) + 4 * sizeof(std::uint32_t);
    return block.pointCount() * pointBytes + block.cellCount() * cellBytes;
}

std::uint64_t proceduralTetCount(const ProceduralSpec& spec) {
    return proceduralBlock(spec).cellCount();
}

Mesh generateMesh(const ProceduralSpec& spec, const std::function<void(double)>& progress) {
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

    // Work units: points and cells once, then every field at every point.
    const double estPoints = static_cast<double>(spec.targetCells) / 6.0;
    ProgressReporter reporter(progress, estPoints + static_cast<double>(spec.targetCells) +
                                            spec.fields.size() * estPoints);

    Mesh mesh;
    switch (spec.shape) {
        case ProceduralShape::Box:
            generateBox(spec, false, mesh, reporter);
            break;
        case ProceduralShape::Graded:
            generateBox(spec, true, mesh, reporter);
            break;
        case ProceduralShape::Shell:
            generateShell(spec, mesh, reporter);
            break;
    }

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
    const double c = std::cos(spec.time), s = std::sin(spec.time);
    mesh.fields.clear();
    mesh.fields.reserve(spec.fields.size());
    const double cellSize = proceduralCellSize(spec);
    for (ProceduralField f : spec.fields) {
        Field field;
        field.name = proceduralFieldName(f);
        field.association = Association::Point;
        field.components = 1;
        field.values.resize(mesh.points.size());
        constexpr size_t kChunk = 65536;
        for (size_t begin = 0; begin < mesh.points.size(); begin += kChunk) {
            const size_t end = std::min(begin + kChunk, mesh.points.size());
            for (size_t i = begin; i < end; ++i) {
                Vec3f p = mesh.points[i];
                if (spec.time != 0.0)  // turned by -time about y
                    p = Vec3f(float(c * p.x + s * p.z), p.y, float(-s * p.x + c * p.z));
                field.values[i] = proceduralFieldValue(f, p, cellSize);
            }
            done += double(end - begin);
            if (progress && total > 0) progress(done / total);
        }
        mesh.fields.push_back(std::move(field));
    }
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
