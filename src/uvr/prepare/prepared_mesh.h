// SPDX-License-Identifier: MIT
#pragma once

// The preparation: a mesh made ready for rendering one field once (cells, BVH, neighbours,
// partitions, seed grids, macrocells), and new values of the same mesh without rebuilding
// anything geometric. Every frame of every method and device reads a PreparedMesh.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "uvr/accel/bvh.h"
#include "uvr/accel/kd_partitions.h"
#include "uvr/accel/lbvh.h"
#include "uvr/accel/macro_grid.h"
#include "uvr/accel/point_locator.h"
#include "uvr/accel/seed_grid.h"
#include "uvr/core/progress.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/mesh.h"
#include "uvr/mesh/tet_mesh.h"
#include "uvr/prepare/render_method.h"

namespace uvr {

/// One rank's piece of a mesh rendered data-parallel (issue 31, dist/): the node of the whole
/// mesh's k-d tree whose box it renders, and what the whole mesh decides for every rank's frames
/// alike, so that each rank's frame setup (camera, step, range, method) is the one a single
/// process makes and its partitions (the tree below that node) are that process's in the box.
struct MeshPiece {
    int rank = 0, ranks = 1;  ///< this rank, of how many
    Bounds3f region;          ///< the rank's box (rendering units): a node of the whole tree
    int depth = 0;            ///< that node's depth in the whole tree
    MeshFrame frame;          ///< the whole mesh's rendering frame
    Bounds3f bounds;          ///< the whole mesh's bounds (rendering units)
    float valueMin = 0.f;     ///< the whole field's finite range
    float valueMax = 0.f;
    float defaultStep = 0.f;  ///< defaultStep of the whole mesh
    /// How far past the box its ghost cells reach (rendering units): frames of the sampling
    /// methods take a sample distance of at most this (the sample ending a piece's last
    /// segment lies one sample distance past the box).
    float ghost = 0.f;
    std::uint64_t sourceCells = 0;  ///< cells of the whole mesh
    double meanSplitTets = 1.0;     ///< the whole mesh's TetMesh::meanSplitTets
    /// autoMethod of the whole mesh for the CPU and the GPU.
    AutoMethodChoice autoCpu{RenderMethod::Partitions}, autoGpu{RenderMethod::Partitions};
};

/// What prepareMesh builds besides the cells, BVH and neighbours.
struct PrepareOptions {
    bool meshBvh = true;     ///< build the BVH over all cells the reference marcher needs
    bool partitions = true;  ///< build the k-d partitions the partition integrator needs
    /// Also what RenderMethod::Auto renders with (autoMethod for the device autoOnGpu names,
    /// decided once the cells are split): the mesh BVH or the partitions. A front end whose
    /// frames are all Auto sets this and neither meshBvh nor partitions.
    bool forAuto = false;
    /// The device PreparedMesh::autoChoice is made for: the GPU (else the CPU).
    bool autoOnGpu = false;
    bool seedGrids = true;   ///< with partitions: the seed grids that long steps locate from
    bool macroGrids = true;  ///< with partitions: the macrocells the error-bound rule steps by
    /// With partitions: cells per leaf of the cell tree (buildCellTree); the CPU's small leaves
    /// by default, kCellTreeLeaf where the renderer is a GPU (RendererOptions::prepareOptions).
    /// Meshes of up to 2^24 cells get leaves of at most kCpuCellTreeLeaf whatever this asks
    /// (searches are not rare on small non-convex meshes: prepareMesh).
    std::uint32_t cellTreeLeaf = kCpuCellTreeLeaf;
    TetrahedralizeOptions cells;  ///< native cells or the split into tetrahedra
    KdBuildOptions kd;
    /// When set, the mesh BVH is an LBVH from this builder (buildLbvhCuda: on the GPU, in
    /// seconds for 100M+ tetrahedra); else a binned SAH tree built on the CPU threads.
    LbvhBuilder lbvh;
    /// When set, the k-d tree comes from this splitter (buildKdTreeCuda: on the GPU); it
    /// overrides kd.splitter.
    KdSplitter kdSplitter;
    /// When set, the face neighbours come from this builder (buildTetNeighborsCuda: on the GPU),
    /// the same table as buildTetNeighbors. It is given the points' welded ids
    /// (coincidentPointIds of the tetrahedra's points), found on a thread of their own beside
    /// the split.
    std::function<std::vector<std::uint32_t>(const TetMesh&, const std::vector<std::uint32_t>&,
                                             const FractionFn&)>
        faceMatcher;
    /// When set, the seed grids come from this builder (buildSeedGridsCuda: on the GPU).
    SeedBuilder seedBuilder;
    /// When set (and with macroGrids), the macrocells and the partitions' gradient spreads come
    /// from this builder (buildMacroGridsCuda: on the GPU).
    MacroBuilder macroBuilder;
    /// Called once the cells are split (tetrahedralize), after which prepareMesh reads nothing of
    /// the source mesh: a caller holding the only copy may free it then, so a one-shot render of
    /// a billion cells does not hold the mesh as read beside the prepared one.
    std::function<void()> afterSplit;
    /// When set, the mesh is this rank's piece of a whole mesh (its cells reaching the piece's
    /// box, and more): it takes the whole mesh's frame and method choice, and its k-d partitions
    /// are the whole tree's below the piece's node (KdBuildOptions::root, on the CPU threads).
    std::shared_ptr<const MeshPiece> piece = nullptr;
    std::string builderDevice = "cpu";  ///< where the builders above build (progress messages)
    std::uint64_t builderMinTets = 0;   ///< use them only from this many cells
};

/// A mesh made ready for rendering one field: cells (tetrahedra, native cells), BVH, face
/// neighbours and (optionally)
/// k-d partitions, built once and reused by every frame and transfer-function change.
struct PreparedMesh {
    TetMesh tets;
    Bvh bvh;  ///< over all cells; empty unless PrepareOptions::meshBvh
    /// Face neighbours as buildTetNeighbors gives them (host-side builds: macrocells).
    std::vector<std::uint32_t> neighbors;
    /// The same neighbours in the kernels' layout (compactNeighbors).
    CompactNeighbors neighborCodes;
    /// With partitions: the tree of runs of consecutive cells (buildCellTree) that the partition
    /// method searches where walks and seeds do not locate a sample.
    Bvh cellTree;
    std::optional<KdPartitions> kd;
    std::optional<SeedGrids> seeds;  ///< per-partition walk starts (with partitions)
    /// Per-partition macrocells (with partitions): value ranges and gradient spreads finer than
    /// a partition's, for skipping and the error-bound rule's steps.
    std::optional<MacroGrids> macro;
    /// Per partition (with partitions): the spread of its cells' field gradients, the diagonal
    /// of their bounding box (partitionGradientSpread), for the error-bound step rule.
    std::vector<float> gradientSpread;
    /// Per partition (with partitions): 1 where a cell has a NaN value (partitionNanFlags);
    /// empty when the field has none.
    std::vector<std::uint8_t> partitionNan;
    std::uint64_t sourceCells = 0;  ///< cells of the mesh before splitting
    /// What RenderMethod::Auto renders it with on PrepareOptions::autoOnGpu's device (made once
    /// the cells are split; resolveMethod makes it again for the other device).
    std::optional<AutoMethodChoice> autoChoice;
    double splitSeconds = 0.0;      ///< time to split cells (or keep them native)
    double bvhSeconds = 0.0;        ///< time to build the BVH
    double adjacencySeconds = 0.0;  ///< time to find face neighbours
    bool builtElsewhere = false;    ///< PrepareOptions' builders (the GPU's) built parts of it
    /// The phases whose builder of PrepareOptions (the GPU's) ran out of its device's memory, so
    /// that the CPU built them instead ("split", "bvh", "neighbours", "partitions", "seed_grids",
    /// "macrocells"): the same structures, later.
    std::vector<std::string> builtOnCpuInstead;
    /// Wall seconds of every phase prepareMesh ran, in order: "split" (with the Morton order and
    /// the kernels' blocks), "bvh", "neighbours" (with their codes), "partitions" (with their
    /// value ranges), "cell_tree", "seed_grids", "gradient_spreads", "nan_flags", "macrocells"
    /// (with the gradient spreads, which then have no phase of their own, when
    /// PrepareOptions::macroBuilder builds them). With PrepareOptions::faceMatcher the cell tree
    /// is built beside the neighbours and the neighbours' codes ("neighbour_codes", last) beside
    /// the later phases, on threads of their own: their seconds overlap the others'.
    std::vector<std::pair<std::string, double>> phaseSeconds;
    /// The prepared cache it was read from (readPreparedCache), holding only what rendering
    /// reads; empty when prepared from a mesh. updateFieldValues refuses such a mesh.
    std::string cacheFile;
    /// A data-parallel rank's piece (PrepareOptions::piece), or null for a whole mesh.
    std::shared_ptr<const MeshPiece> piece = nullptr;
    std::uint64_t valueUpdates = 0;   ///< times updateFieldValues gave it new values
    double valueUpdateSeconds = 0.0;  ///< time the last updateFieldValues took

    /// The mesh as kernels read it: tetrahedra from their blocks only (tets null), points and
    /// values only where native cells or cell data need them (what the GPU holds, too).
    TetMeshView kernelMesh() const {
        TetMeshView v = tets.view();
        v.tets = nullptr;
        if (!v.hasNative()) {
            v.points = nullptr;
            v.pointGradients = nullptr;
            if (!v.cellCentered) v.values = nullptr;
        }
        return v;
    }
    /// The whole mesh's bounds (rendering units): a piece's whole mesh's, else the cells'.
    const Bounds3f& wholeBounds() const { return piece ? piece->bounds : tets.bounds; }
    /// The whole mesh's finite field range.
    float wholeValueMin() const { return piece ? piece->valueMin : tets.valueMin; }
    float wholeValueMax() const { return piece ? piece->valueMax : tets.valueMax; }
    /// Cells of the whole source mesh.
    std::uint64_t wholeSourceCells() const { return piece ? piece->sourceCells : sourceCells; }
    /// The whole mesh's default step s1 (defaultStep).
    float wholeDefaultStep() const;
    /// Point locator over this mesh, as kernels use it.
    TetLocator locator() const { return {kernelMesh(), bvh.view(), neighborCodes.view()}; }
};

/// Optional progress report of a preparation: `step` names each phase as it starts ("finding
/// face neighbours", ...) and `fraction` tells how far the phase named last has come, in [0, 1],
/// increasing within the phase (only phases that can take long report it, ending with 1; from
/// one thread at a time, any thread; it must not throw). Either may be empty. Any callable taking
/// a step name converts to one with only `step`.
struct ProgressFn {
    std::function<void(const std::string&)> step;  ///< a phase starts: its name
    FractionFn fraction;                           ///< how far the phase named last has come

    /// No reports.
    ProgressFn() = default;
    /// Both callbacks.
    ProgressFn(std::function<void(const std::string&)> onStep, FractionFn onFraction)
        : step(std::move(onStep)), fraction(std::move(onFraction)) {}
    /// Only step names, from any callable taking one (a lambda, a std::function).
    template <class F, class = std::enable_if_t<!std::is_same_v<std::decay_t<F>, ProgressFn> &&
                                                std::is_invocable_v<F&, const std::string&>>>
    ProgressFn(F&& onStep)  // NOLINT(google-explicit-constructor): lambdas convert
        : step(std::forward<F>(onStep)) {}

    /// Names a phase that starts (nothing when step is empty).
    void operator()(const std::string& name) const {
        if (step) step(name);
    }
    /// Whether anything is reported.
    explicit operator bool() const { return step || fraction; }
};

/// The k-d build options prepareMesh builds the partitions of `tets` with: options.kd, its leaf
/// size counted in tetrahedra of the split (a mesh of native cells gets fewer cells a leaf).
KdBuildOptions kdBuildOptions(const TetMesh& tets, const PrepareOptions& options);

/// Splits cells (or keeps them native), builds the BVH over them and the face-neighbour table,
/// and what options ask for besides. `progress` hears each phase of PreparedMesh::phaseSeconds
/// named as it starts, in that order, and the fraction done of the long ones (split,
/// neighbours, partitions, cell tree, gradient spreads).
PreparedMesh prepareMesh(const MeshView& mesh, const ScalarField& field,
                         const PrepareOptions& options, const ProgressFn& progress = {});
/// prepareMesh with the default options.
PreparedMesh prepareMesh(const MeshView& mesh, const ScalarField& field);

/// Gives a prepared mesh new values of a field of the same source mesh (a time step, or another
/// field), rebuilding nothing geometric: tetrahedra, BVHs, neighbours, k-d tree, partition cell
/// lists, seed grids and macrocell layouts stay as they are (not reallocated); the values, the
/// value range, the partitions' value ranges, gradient spreads and NaN flags and the macrocells
/// are recomputed by the same functions prepareMesh uses (assignTetValues,
/// computePartitionValueRanges, partitionGradientSpread, partitionNanFlags, fillMacroCells), so
/// frames equal those of a fresh prepareMesh of the new values bit for bit. Throws
/// Error(Argument) when the field does not hold one value per point (or cell) of the source
/// mesh, or when the mesh was read from a prepared cache (PreparedMesh::cacheFile: the arrays
/// new values need are not there); the prepared mesh is unchanged then.
void updateFieldValues(PreparedMesh& mesh, const ScalarField& field);

/// The methods a prepared mesh renders with, in kMethods' order: adaptive where its k-d
/// partitions were prepared, reference and exact where its mesh BVH was, auto where either was
/// (resolveMethod then takes the one prepared). A front end offers these alone, e.g. the viewer
/// serving a prepared cache.
std::vector<RenderMethod> renderableMethods(const PreparedMesh& mesh);

/// The field's values as prepared, for a histogram of them: TetMesh::values where held, else
/// (a prepared cache of tetrahedra with a point field keeps them in the blocks alone) the
/// blocks' vertex values, a point once per block that uses it.
std::vector<float> preparedValues(const PreparedMesh& mesh);

/// Throws Error(Argument) naming the field unless it holds `expected` values, one per point
/// (or cell, by its association) of `of` ("the prepared mesh", "this rank's share", ...): the
/// one check of new values for every place that takes them.
void checkNewValueCount(const ScalarField& field, std::uint64_t expected, const std::string& of);

/// Per partition, the diagonal of the bounding box of the field gradients of its cells (each
/// linear tetrahedron's constant gradient, a native cell's at its corners and centre:
/// cellGradientBounds): it bounds how much the derivative of the field along
/// any ray varies inside the partition. 0 for a partition without cells or with a linear field;
/// infinite for a cell-centred field (piecewise constant: its jumps have no gradient bound).
/// Cells with non-finite gradients (degenerate, or NaN values) are left out. `progress` hears the
/// fraction done.
std::vector<float> partitionGradientSpread(const TetMesh& tets, const KdPartitions& kd,
                                           const FractionFn& progress = {});

/// Per partition, 1 where one of its cells has a NaN value (a vertex's, or the cell's own for
/// cell data); empty when no cell has one. Partition value ranges leave NaN out, so skipping
/// needs these to keep NaN regions of non-zero NaN opacity (shadeNan).
std::vector<std::uint8_t> partitionNanFlags(const TetMesh& tets, const KdPartitions& kd);

/// Default sample spacing s1: half the edge of a cube with the mean tetrahedron volume of the
/// split, 0.5 * cbrt(totalVolume / splitTetCount): about two to three samples per tetrahedron along
/// a ray; at most the bounds' diagonal / kMinSamplesPerDiagonal (a mesh of few cells is cheap to
/// sample finely, and where a ray enters and leaves the mesh a sample's share is uncertain by a
/// step); at least kMinDefaultStepFraction of the diagonal (a mesh of slivers has a tiny mean
/// volume).
float defaultStep(const TetMesh& mesh);
/// defaultStep of a mesh of these bounds, summed tetrahedron volume and tetrahedra of the split
/// (TetMesh::splitTetCount), e.g. summed over the ranks' shares of a mesh.
float defaultStep(const Bounds3f& bounds, double totalVolume, double splitTets);

/// Fewest samples the default step takes across the bounds' diagonal (it decides the step of
/// meshes below about 400,000 tetrahedra).
inline constexpr double kMinSamplesPerDiagonal = 256;

/// Smallest default step relative to the bounds' diagonal: at most 10^4 samples across the mesh
/// (a uniform mesh reaches this at about 2 * 10^10 tetrahedra).
inline constexpr double kMinDefaultStepFraction = 1e-4;

/// ParaView's default ScalarOpacityUnitDistance: bounds diagonal / cbrt(cell count).
float defaultOpacityUnit(const Bounds3f& bounds, std::uint64_t cellCount);

/// Host bytes prepareMesh needs per tetrahedron, an upper estimate for memory limits: the
/// tetrahedra, the BVH with its build arrays, the neighbours, partitions and seed grids took
/// 120 to 130 bytes on 4-million-tetrahedron procedural meshes.
inline constexpr std::uint64_t kPrepareBytesPerTet = 160;

}  // namespace uvr
