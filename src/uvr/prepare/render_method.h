// SPDX-License-Identifier: MIT
#pragma once

// The integrators a frame renders with, their names in every front end, and RenderMethod::Auto,
// the default of every front end (issue 29): the exact integrator where it is the faster method,
// the adaptive partition method elsewhere. Exact is the yardstick the others are measured
// against, so where it is also faster nothing is lost by rendering it.
//
// Exact's cost per ray is the cells the ray crosses (it walks all of them, whatever the transfer
// function); the adaptive method's is its samples, a few tens at the defaults whatever the
// mesh's size. So the rule looks at the mesh only: exactCellsPerRay estimates the crossings before
// anything but the split is built, and autoMethod compares them with a per-device limit measured on
// the shared meshes (docs/PERFORMANCE.md, "The default method"). The choice is made once per
// prepared mesh: it does not change with the camera or the transfer function, and the same command
// gives the same picture every run.
//
// Where it picks adaptive on a device whose adaptive sample costs several of the reference's (the
// GPU), each frame then weighs the reference too (weighReference in render/frame_setup.h): once
// the partitions are shaded for the frame's transfer function, the samples each method would take
// are estimated from the partitions' steps, and the reference renders where the adaptive method
// would save fewer samples than its sample costs. That depends on the transfer function, not the
// camera, and is the same every run.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "uvr/mesh/tet_mesh.h"

namespace uvr {

/// Which integrator renders a frame.
enum class RenderMethod {
    Reference,   ///< fixed step s1 through the whole volume (the yardstick)
    Partitions,  ///< k-d partitions with space skipping and adaptive steps (Morrical et al. 2019)
    Exact,       ///< no sampling: each cell's segment integrated (the ground truth)
    /// Exact or Partitions, whichever autoMethod picks for the mesh and device (or Partitions
    /// when settings tune the adaptive method: tunesAdaptive). The default.
    Auto,
};

/// A method and its name as every front end spells it (--method, the viewer's "method",
/// Python's method=).
struct MethodName {
    RenderMethod method;
    const char* name;
};
/// Every method, the default first (as the front ends list them).
inline constexpr std::array<MethodName, 4> kMethods{{{RenderMethod::Auto, "auto"},
                                                     {RenderMethod::Partitions, "adaptive"},
                                                     {RenderMethod::Reference, "reference"},
                                                     {RenderMethod::Exact, "exact"}}};
/// The names of kMethods, in its order.
std::vector<std::string> methodNames();
/// The name of a method (kMethods).
const char* methodName(RenderMethod method);
/// The method of a name in kMethods; nullopt for any other.
std::optional<RenderMethod> parseMethod(std::string_view name);

/// At most this many cells, evenly spread, are measured by exactCellsPerRay.
inline constexpr std::uint64_t kAutoSampleCells = 1u << 16;

/// Per device, what a crossing costs the exact integrator and how many it may make per ray
/// before the adaptive method is the faster. Measured on the shared meshes at 1024x1024 at their
/// defaults (docs/PERFORMANCE.md, "The default method"): exact is the faster up to 16.6 cells per
/// ray (post.vtk) on both 2 CPU cores and an H200, and the slower from 58 on the CPU and from 70
/// on the GPU (Blunt Fin; disk_out_ref.ex2 at 58 is a tie there). A native cell's crossing
/// costs about 4 tetrahedra's on both (fire_ug and hexa, native, are exact's slowest per cell).
/// The two devices agree today; they are kept apart because each was measured on its own.
struct AutoMethodLimits {
    /// A native pyramid, wedge or hexahedron's crossing, in tetrahedron crossings (its exit is a
    /// Newton solve against bilinear faces, the tetrahedron's a plane test).
    double nativeCellCost;
    /// Exact where exactCellsPerRay is at most this.
    double maxExactCellsPerRay;
    /// Where adaptive is picked: what an adaptive sample costs in reference samples in a mesh of
    /// tetrahedra. Each frame renders the reference instead where the adaptive method would take
    /// fewer than this many times fewer samples (weighReference). 0: never.
    double adaptiveSampleCost;
    /// The same in native pyramids, wedges and hexahedra, whose reference samples cost more (a
    /// Newton solve to locate each); a mixed mesh weighs the two by its cells.
    double nativeAdaptiveSampleCost;
    /// ... on meshes of at most this many cells (split): the reference needs the mesh BVH beside
    /// the partitions, about 27 bytes more a cell, and above this the adaptive method is the
    /// faster (100M tetrahedra on the H100: 3.5x).
    std::uint64_t maxWeighCells;
};
/// On 2 CPU cores the adaptive method is the faster at the defaults on every shared mesh (Oxygen
/// Post a tie). On the H100, at the GPU's leaf size, the quality matrix (docs/PERFORMANCE.md,
/// "The GPU's auto weighs the reference each frame"): on meshes of tetrahedra the reference was
/// the faster in every case where the adaptive method saved under 9x its samples but one, and
/// an adaptive sample cost 3.7-5.2 reference samples where it saved 2.5-4.4x; on native
/// hexahedra (fire_ug, hexa) the adaptive method was the faster from 2.2x fewer samples.
inline constexpr AutoMethodLimits kAutoCpuLimits{4.0, 32.0, 0.0, 0.0, 0};
inline constexpr AutoMethodLimits kAutoGpuLimits{4.0, 32.0, 5.0, 2.0, std::uint64_t(1) << 25};

/// The mean number of cells a ray through the mesh's bounding box crosses, each native cell
/// counted AutoMethodLimits::nativeCellCost times: by Cauchy's formula, a convex cell is hit by
/// a random line through the box with probability (its surface area) / (the box's), so the
/// mean is the cells' summed surface over the box's. From at most kAutoSampleCells cells evenly
/// spread (a few milliseconds at any size). 0 for a mesh without cells.
double exactCellsPerRay(const TetMesh& mesh, double nativeCellCost);

/// The method RenderMethod::Auto renders `mesh` with on the GPU (gpu) or the CPU, with the
/// figures behind the choice.
struct AutoMethodChoice {
    RenderMethod method;
    double cellsPerRay = 0.0;  ///< exactCellsPerRay with the device's native-cell cost
    double limit = 0.0;        ///< the device's maxExactCellsPerRay
    bool gpu = false;          ///< chosen for the GPU (else the CPU)
    /// With adaptive: the device's AutoMethodLimits::adaptiveSampleCost and
    /// nativeAdaptiveSampleCost weighed by the mesh's cells, where it has at most maxWeighCells
    /// cells (each frame weighs the reference then), else 0.
    double adaptiveSampleCost = 0.0;
    /// One line saying why, e.g. "auto: exact (about 13.2 cells per ray, at most 32 on the
    /// CPU)".
    std::string reason() const;
};
AutoMethodChoice autoMethod(const TetMesh& mesh, bool gpu);

/// The estimate behind exactCellsPerRay before it is divided by the bounds' surface: the summed
/// surface of the mesh's cells (from at most kAutoSampleCells, scaled), each native cell counted
/// nativeCellCost times. Shares of a mesh add up to the whole mesh's.
double cellSurfaceEstimate(const TetMesh& mesh, double nativeCellCost);

/// autoMethod for a mesh whose cells' summed surface (cellSurfaceEstimate with the device's
/// native-cell cost) is `surface`, within `bounds`.
AutoMethodChoice autoMethodFor(double surface, const Bounds3f& bounds, bool gpu);

}  // namespace uvr
