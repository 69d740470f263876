// SPDX-License-Identifier: MIT
#pragma once

// The data-parallel decomposition (issue 31): the whole mesh's k-d tree, the one a single process
// builds, cut into one subtree per rank; each rank renders its subtree's box, and the boxes'
// visibility order for a camera composites the ranks' images into the one-process picture.

#include <cstdint>
#include <memory>
#include <vector>

#include "uvr/accel/kd_partitions.h"
#include "uvr/core/bounds.h"
#include "uvr/core/vec.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/mesh.h"
#include "uvr/prepare/prepared_mesh.h"

namespace uvr {

/// The ranks' share of a whole k-d tree: the nodes each rank renders (a cut of the tree, every
/// partition below exactly one of them) and the tree above them, whose leaves name ranks.
struct Decomposition {
    /// The whole tree's nodes down to the ranks' (KdNode layout; a leaf names a rank).
    std::vector<KdNode> rankTree;
    std::vector<std::uint32_t> node;  ///< per rank: its node of the whole tree
    std::vector<Bounds3f> regions;    ///< per rank: that node's region (rendering units)
    std::vector<double> cost;         ///< per rank: its estimated share of the work (sums to 1)
};

/// Estimated rendering cost of each partition, summing to 1: half its share of the cells (the
/// memory, the preparation and the exact integrator's crossings), half its share of the occupied
/// volume (the samples of rays spread evenly over the mesh).
std::vector<double> partitionCosts(const KdPartitions& kd);

/// Cuts the whole tree `kd` (its root region kd.bounds) into `ranks` subtrees: starting from the
/// root, the costliest node that is not a partition is replaced by its two children until there
/// are `ranks` nodes, which get the ranks in the tree's left-to-right order. Any rank count works
/// (powers of two balance best). Throws Error(Argument) when the tree has fewer partitions than
/// ranks.
Decomposition decompose(const KdPartitions& kd, const std::vector<double>& partitionCost,
                        int ranks);

/// The ranks front to back along every ray of a camera: from the eye at `eye` (perspective),
/// or along the direction `dir` (parallel: eye unused). The boxes are a k-d tree's, so one order
/// holds for every pixel.
std::vector<int> visibilityOrder(const Decomposition& d, bool parallel, Vec3f eye, Vec3f dir);

/// A rank's piece of a whole mesh: its cells (every cell whose bounds reach its box, widened by
/// `ghostWidth`), the field on them, and what its preparation takes from the whole mesh.
struct RankPiece {
    Mesh mesh;          ///< the cells and the points they use (in the whole mesh's order)
    ScalarField field;  ///< the field on them
    std::shared_ptr<const MeshPiece> piece;
    std::uint64_t ownedCells = 0;  ///< cells of the whole tree's leaves below the rank's node
};

/// What the whole mesh decides for every rank (its split, frame, bounds, range, default step,
/// method choice and k-d tree), computed from the whole mesh as a single process prepares it
/// (`options`: the split, the leaf size). `progress` hears the phases.
struct WholeMesh {
    KdPartitions kd;
    MeshFrame frame;
    Bounds3f bounds;
    float valueMin = 0.f, valueMax = 0.f;
    float defaultStep = 0.f;
    std::uint64_t sourceCells = 0;
    AutoMethodChoice autoCpu{RenderMethod::Partitions}, autoGpu{RenderMethod::Partitions};
};
WholeMesh describeWholeMesh(const MeshView& mesh, const ScalarField& field,
                            const PrepareOptions& options, const ProgressFn& progress = {});

/// Rank `rank`'s piece of the whole mesh under decomposition `d`. The ghost cells reach
/// `ghostWidth` (rendering units) past the box, so the sample that ends a piece's last segment
/// (PieceView) finds its cell.
RankPiece extractPiece(const MeshView& mesh, const ScalarField& field, const WholeMesh& whole,
                       const Decomposition& d, int rank, float ghostWidth);

}  // namespace uvr
