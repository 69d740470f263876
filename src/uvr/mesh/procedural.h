// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "uvr/core/vec.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// Shapes `uvr generate` can make; all lie inside [-1, 1]^3.
enum class ProceduralShape {
    Box,     ///< jittered tetrahedralised cube [-1,1]^3
    Shell,   ///< hollow, non-convex solid (a thick torus tube with an empty core)
    Graded,  ///< cube whose cell size varies 100x from one corner to the other
};

/// Analytic point fields; each is written as a point field of this name.
enum class ProceduralField {
    Constant,       ///< "constant": 1 everywhere
    Linear,         ///< "linear": x + 2y - z (reproduced exactly by linear interpolation)
    Jet,            ///< "jet": a turbulent plume rising along +y (smooth, deterministic noise)
    MarschnerLobb,  ///< "marschner_lobb": Marschner & Lobb 1994 test signal over [-1,1]^3
    /// "multiscale": gradient noise with octaves from half the domain down to the cell size, each
    /// 1/sqrt(2) of the previous in amplitude, so detail (and the steepest gradients) exists at
    /// every scale however fine the mesh (the jet is smooth at the cell size of large meshes,
    /// which flatters adaptive sampling); values in [0, 1].
    Multiscale,
};

/// Largest allowed ProceduralSpec::jitter: a Kuhn tetrahedron stays positively oriented while each
/// corner moves less than 0.28 cell sizes (worst case found by numerical optimisation).
inline constexpr float kMaxProceduralJitter = 0.25f;
/// Shell geometry: distance from the torus axis (z) to the centre of its tube.
inline constexpr float kShellMajorRadius = 0.65f;
/// Shell geometry: inner radius of the tube wall (the empty core of the tube).
inline constexpr float kShellInnerRadius = 0.12f;
/// Shell geometry: outer radius of the tube wall.
inline constexpr float kShellOuterRadius = 0.3f;

/// What to generate.
struct ProceduralSpec {
    ProceduralShape shape = ProceduralShape::Box;
    std::uint64_t targetCells = 100000;  ///< approximate tetrahedron count (result within ~2x)
    std::uint64_t seed = 1;              ///< same seed and spec, same mesh, bit for bit
    /// Interior points move inside a ball of this radius times the local spacing (at most
    /// kMaxProceduralJitter); boundary points move only along the boundary.
    float jitter = 0.2f;
    /// Fields written, in this order (the first is the default render field).
    std::vector<ProceduralField> fields{ProceduralField::Jet, ProceduralField::MarschnerLobb,
                                        ProceduralField::Linear, ProceduralField::Constant};
    /// Time of the fields: each is evaluated at the point turned by -time radians about the y
    /// axis (the flow turns about y as time goes on; the points stay where they are).
    double time = 0.0;
};

/// Generates a tetrahedral mesh with no inverted or zero-volume cells; progress(fraction in [0,1])
/// is called now and then when given.
Mesh generateMesh(const ProceduralSpec& spec, const std::function<void(double)>& progress = {});

/// Tetrahedra per slab of writeProceduralNative (128 MiB of corner indices).
inline constexpr std::uint64_t kProceduralSlabTets = 1ull << 23;

/// Writes generateMesh(spec) to a native .uvrm file (byte for byte what writeNative would write)
/// without holding it: points, cells and fields are computed slab by slab of layers of about
/// slabTets tetrahedra (each slab in parallel) and written as they come, so the memory needed
/// is a few slabs (about 300 MB) however large the mesh. Atomic (temporary file, then rename);
/// progress(fraction) now and then.
void writeProceduralNative(const ProceduralSpec& spec, const std::string& path,
                           const std::function<void(double)>& progress = {},
                           std::uint64_t slabTets = kProceduralSlabTets);

/// Bytes writeProceduralNative(spec) holds at its peak (its slabs), for a memory limit.
std::uint64_t proceduralStreamBytes(const ProceduralSpec& spec);

/// Replaces the mesh's fields by spec's fields at spec.time (what generateMesh(spec) stores); the
/// mesh must be generateMesh's of a spec differing at most in time and fields.
void setProceduralFields(Mesh& mesh, const ProceduralSpec& spec,
                         const std::function<void(double)>& progress = {});

/// Tetrahedra generateMesh(spec) makes (from the same grid it builds).
std::uint64_t proceduralTetCount(const ProceduralSpec& spec);

/// Bytes of the points, cells and fields of the mesh generateMesh(spec) makes, known before
/// generating (for a memory limit).
std::uint64_t proceduralMeshBytes(const ProceduralSpec& spec);

/// The analytic value of a procedural field at p (what the mesh stores at its points); cellSize is
/// the mesh's cell edge, the wavelength of the multiscale field's finest octave (0: 8 octaves).
float proceduralFieldValue(ProceduralField field, Vec3f p, double cellSize = 0.0);

/// Cell edge of a procedural mesh: the cube edge of its Kuhn grid over [-1, 1]^3 (6 tetrahedra per
/// cube; the graded mesh's cells vary about it).
double proceduralCellSize(const ProceduralSpec& spec);

/// Largest allowed jitter of generateMixedCellMesh, in block sizes: every hexahedron, wedge,
/// pyramid and tetrahedron of its templates stays positively oriented while each point moves less.
inline constexpr float kMaxMixedCellJitter = 0.15f;
/// Most blocks per axis of generateMixedCellMesh (its points must fit 32-bit indices).
inline constexpr int kMaxMixedCellBlocks = 1000;

/// A conforming mesh of [-1, 1]^3 with cells of all four types over n x n x n blocks, each block
/// a hexahedron, 6 pyramids to its centre, 2 wedges, a wedge + pyramid + tetrahedron, or (where
/// its neighbours cut its faces otherwise) pyramids and tetrahedra to its centre; for n >= 4 it
/// holds every pairing of cell types across quadrilateral faces (hexahedron, pyramid, wedge) and
/// triangles (tetrahedron, pyramid, wedge). Interior points move inside a ball of jitter (at most
/// kMaxMixedCellJitter) times the block size, boundary points along the boundary only, so
/// hexahedron faces are not planar. Point fields "linear" (x + 2y - z) and "xyz" (x y z), cell
/// fields "block" (the block's index, x fastest) and "cell_type" (the VTK type code). Same
/// arguments, same mesh; throws Error(Argument) for n outside [1, kMaxMixedCellBlocks] or jitter
/// outside [0, kMaxMixedCellJitter]. With hexahedraOnly every block is one hexahedron (a jittered
/// hexahedral grid with the same points and fields: `uvr generate hex`).
Mesh generateMixedCellMesh(int n, float jitter = 0.1f, std::uint64_t seed = 1,
                           bool hexahedraOnly = false);

/// Field name as written into the mesh ("jet", ...).
const char* proceduralFieldName(ProceduralField field);
/// Shape name as the CLI spells it ("box", "shell", "graded").
const char* proceduralShapeName(ProceduralShape shape);
/// Parses a shape name; throws Error(Argument) listing the valid names.
ProceduralShape parseProceduralShape(const std::string& name);
/// Parses a field name; throws Error(Argument) listing the valid names.
ProceduralField parseProceduralField(const std::string& name);

}  // namespace uvr
