// SPDX-License-Identifier: MIT
#include "uvr/prepare/render_method.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "uvr/mesh/cell_math.h"

namespace uvr {

std::vector<std::string> methodNames() {
    std::vector<std::string> out;
    for (const MethodName& m : kMethods) out.emplace_back(m.name);
    return out;
}

const char* methodName(RenderMethod method) {
    for (const MethodName& m : kMethods)
        if (m.method == method) return m.name;
    return "?";
}

std::optional<RenderMethod> parseMethod(std::string_view name) {
    for (const MethodName& m : kMethods)
        if (name == m.name) return m.method;
    return std::nullopt;
}

namespace {

/// Surface area of a cell of kind k with corners x: its faces', a quadrilateral's as half the
/// cross product of its diagonals (exact when planar; a bilinear face differs by little).
double cellSurface(CellKind k, const Vec3f* x) {
    double area = 0.0;
    for (int f = 0; f < kindFaces(k); ++f) {
        const std::uint32_t face = packedFace(k, f);
        const Vec3f a = x[faceCorner(face, 0)], b = x[faceCorner(face, 1)],
                    c = x[faceCorner(face, 2)];
        const Vec3f n =
            faceSize(face) == 3 ? cross(b - a, c - a) : cross(c - a, x[faceCorner(face, 3)] - b);
        area += 0.5 * std::sqrt(double(n.x) * n.x + double(n.y) * n.y + double(n.z) * n.z);
    }
    return area;
}

}  // namespace

double cellSurfaceEstimate(const TetMesh& mesh, double nativeCellCost) {
    const TetMeshView view = mesh.view();
    const std::uint64_t cells = view.cellCount();
    if (cells == 0) return 0.0;
    const std::uint64_t stride = std::max<std::uint64_t>(1, cells / kAutoSampleCells);
    double sum = 0.0;
    std::uint64_t measured = 0;
    for (std::uint64_t c = 0; c < cells; c += stride, ++measured) {
        Vec3f x[kMaxCellCorners];
        view.kernelGather(c, x);
        const CellKind k = view.kind(c);
        const double s = cellSurface(k, x);
        if (std::isfinite(s)) sum += k == CellKind::Tet ? s : nativeCellCost * s;
    }
    return sum * (double(cells) / double(measured));
}

namespace {

/// Mean cells a ray through the bounds crosses for cells of summed surface `surface`.
double cellsPerRayOf(double surface, const Bounds3f& bounds) {
    const Vec3f e = bounds.hi - bounds.lo;
    const double box = 2.0 * (double(e.x) * e.y + double(e.y) * e.z + double(e.z) * e.x);
    // A flat box (all cells in a plane) has no volume to cross: one cell per ray at most.
    return box > 0.0 ? surface / box : 1.0;
}

}  // namespace

double exactCellsPerRay(const TetMesh& mesh, double nativeCellCost) {
    if (mesh.cellCount() == 0) return 0.0;
    return cellsPerRayOf(cellSurfaceEstimate(mesh, nativeCellCost), mesh.bounds);
}

AutoMethodChoice autoMethodFor(double surface, const Bounds3f& bounds, bool gpu) {
    const AutoMethodLimits& limits = gpu ? kAutoGpuLimits : kAutoCpuLimits;
    AutoMethodChoice c;
    c.gpu = gpu;
    c.limit = limits.maxExactCellsPerRay;
    c.cellsPerRay = surface > 0.0 ? cellsPerRayOf(surface, bounds) : 0.0;
    c.method = c.cellsPerRay <= c.limit ? RenderMethod::Exact : RenderMethod::Partitions;
    return c;
}

AutoMethodChoice autoMethod(const TetMesh& mesh, bool gpu) {
    const AutoMethodLimits& limits = gpu ? kAutoGpuLimits : kAutoCpuLimits;
    AutoMethodChoice c =
        autoMethodFor(mesh.cellCount() ? cellSurfaceEstimate(mesh, limits.nativeCellCost) : 0.0,
                      mesh.bounds, gpu);
    if (c.method == RenderMethod::Partitions && mesh.cellCount() > 0 &&
        mesh.cellCount() <= limits.maxWeighCells) {
        const double native = double(mesh.cellCount() - mesh.tetCount()) / double(mesh.cellCount());
        c.adaptiveSampleCost =
            limits.adaptiveSampleCost * (1.0 - native) + limits.nativeAdaptiveSampleCost * native;
    }
    return c;
}

std::string AutoMethodChoice::reason() const {
    char line[160];
    std::snprintf(line, sizeof line, "auto: %s (about %.3g cells per ray, %s %.3g on the %s)",
                  method == RenderMethod::Exact ? "exact" : "adaptive", cellsPerRay,
                  method == RenderMethod::Exact ? "at most" : "more than", limit,
                  gpu ? "GPU" : "CPU");
    return line;
}

}  // namespace uvr
