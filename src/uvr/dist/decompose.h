// SPDX-License-Identifier: MIT
#pragma once

// The data-parallel decomposition (issue 31): the top of the whole mesh's k-d tree, the one a
// single process builds, split by the ranks together until it has one node per rank; each rank
// then holds the cells reaching its node's box (with ghosts), builds the tree below its node as
// one process would, and renders that box. The boxes' visibility order for a camera composites
// the ranks' frames into the one-process picture.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "uvr/accel/kd_partitions.h"
#include "uvr/core/bounds.h"
#include "uvr/core/progress.h"
#include "uvr/core/vec.h"
#include "uvr/dist/communicator.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/io/native.h"
#include "uvr/mesh/io/time_series.h"
#include "uvr/mesh/mesh.h"
#include "uvr/prepare/prepared_mesh.h"

namespace uvr {

/// A rank's share of a mesh before it is distributed: some of the mesh's cells (each cell in
/// exactly one rank's share), the points they use, in the whole mesh's order, and the ids of both
/// in the whole mesh.
struct MeshShare {
    Mesh mesh;                            ///< the cells and the points they use
    ScalarField field;                    ///< the field on them
    std::vector<std::uint64_t> pointIds;  ///< per point: its index in the whole mesh (increasing)
    std::vector<std::uint64_t> cellIds;   ///< per cell: its index in the whole mesh (increasing)
};

/// The run [first, end) of `parts` parts (a file's cells, pieces or partitions) that rank `rank`
/// of `ranks` reads: [rank parts / ranks, (rank + 1) parts / ranks), as even as they allow.
std::pair<std::uint64_t, std::uint64_t> rankRun(std::uint64_t parts, int rank, int ranks);

/// This rank's run of time step `step`'s parts of a series read by parts (MeshSeries::partCount,
/// rankRun); Error(Unsupported) naming the step when it is stored in fewer parts than ranks.
std::pair<std::uint64_t, std::uint64_t> rankRunOfStep(const MeshSeries& series, std::size_t step,
                                                      const Communicator& comm);

/// Share `rank` of `ranks` of a mesh held whole: its cells rankRun(cells, rank, ranks).
MeshShare shareOfMesh(const MeshView& mesh, const ScalarField& field, int rank, int ranks);

/// The finite range of every rank's values (collective; 0, 0 where no rank holds a finite one,
/// as finiteRange gives for none).
std::pair<float, float> reduceFiniteRange(Communicator& comm, std::span<const float> values);

/// The smallest box holding every rank's box (collective; an empty box adds nothing).
Bounds3f reduceBounds(Communicator& comm, const Bounds3f& box);

/// fieldInfos of this rank's part with each field's constancy over every rank's part
/// (collective: one value when the finite values of every rank, NaN left out, are one value),
/// so every rank resolves the default field alike.
std::vector<FieldInfo> reducedFieldInfos(Communicator& comm, const Mesh& part);

/// A rank's share from the part of a file it read (readNativePart, meshPart) and the field
/// `spec` names (collective: the default field passes over fields constant over the whole mesh,
/// as one process's choice does, so every rank renders the same field). The share's mesh keeps
/// the part's fields with keepFields (a viewer switching fields), else none.
MeshShare shareOfPart(Communicator& comm, MeshPart part, const FieldSpec& spec,
                      bool keepFields = false);

/// How the ranks split the whole mesh: the top of its k-d tree down to one node per rank.
struct Decomposition {
    /// The whole tree's nodes down to the ranks' (KdNode layout; a leaf names a rank).
    std::vector<KdNode> rankTree;
    std::vector<Bounds3f> regions;  ///< per rank: its node's region (rendering units)
    std::vector<int> depths;        ///< per rank: its node's depth in the whole tree
    /// Per rank: its estimated share of the work (half its cells', half its occupied volume's
    /// share of the whole), summing to 1.
    std::vector<double> cost;
};

/// The ranks front to back along every ray of a camera: from the eye at `eye` (perspective),
/// or along the direction `dir` (parallel: eye unused). The boxes are a k-d tree's, so one order
/// holds for every pixel.
std::vector<int> visibilityOrder(const Decomposition& d, bool parallel, Vec3f eye, Vec3f dir);

/// How new values of a field (a time step, another field) reach the ranks' pieces: for every
/// pair of ranks, the sender's share points (cells) whose values the receiver's piece holds, in
/// one order both know (distributeMesh notes it while it moves the cells). Routes of an
/// association no field of the share has are left empty (points: the share's mesh has point
/// fields or the rendered field is one; cells likewise; both when the share's mesh lists no
/// fields, as a share of a MeshView). 4 bytes a share and a piece point (cell) on each rank.
struct ValueRoutes {
    std::uint64_t sharePoints = 0, shareCells = 0;  ///< this rank's share's
    std::uint64_t piecePoints = 0, pieceCells = 0;  ///< this rank's piece's
    bool points = false, cells = false;             ///< which routes were noted
    /// Per rank r: the share's point (cell) indices whose values go to r, in order.
    std::vector<std::vector<std::uint32_t>> sendPoints, sendCells;
    /// Per rank r: the piece's point (cell) indices r's values go to, in the same order.
    std::vector<std::vector<std::uint32_t>> receivePoints, receiveCells;
};

/// New values on the pieces (collective): `field` holds one value per point (cell) of this
/// rank's share, in its order; returns the field on this rank's piece (one value per piece
/// point or cell, as RankPiece::mesh orders them). Throws Error(Argument) on every rank when
/// any rank's field has the wrong count or an association whose routes were not noted.
ScalarField routeValues(Communicator& comm, const ValueRoutes& routes, const ScalarField& field);

/// A rank's piece of the whole mesh, ready for prepareMesh with PrepareOptions::piece.
struct RankPiece {
    Mesh mesh;          ///< every cell whose bounds reach the rank's box widened by the ghosts
    ScalarField field;  ///< the field on them
    std::shared_ptr<const MeshPiece> piece;  ///< what the whole mesh decides
    Decomposition decomposition;             ///< every rank's box
    std::uint64_t shareCells = 0;            ///< cells of this rank's share before
    ValueRoutes routes;                      ///< how later values reach the piece
    /// This rank's seconds in each step of distributeMesh ("distribute_split": its share split
    /// into tetrahedra; "distribute_tree": the ranks' boxes; "distribute_reach": which ranks each
    /// cell reaches, ghost rings included; "distribute_exchange": the messages packed and sent;
    /// "distribute_assemble": the piece made from those received).
    std::vector<std::pair<std::string, double>> phaseSeconds;
};

/// Distributes a mesh over the ranks of `comm` (collective; every rank passes its share):
/// the whole mesh's frame, bounds, field range, default step, cell counts and method choice are
/// reduced over the shares; the top of the whole k-d tree is built by every rank together with
/// the single-process build's rules (median of the cell centres on the longest axis of the
/// occupied region, the same leaf size and 90% rule) by splitting the costliest node until there
/// is one per rank (Decomposition); then each source cell goes to every rank whose box, widened
/// by the ghost width, its bounds reach, and every cell around a point those cells have
/// outside that box (so a piece's smooth normals are one process's). The ghost width is
/// ghostSteps default steps, or `reach` (file units; 0: none) when that is more: the largest
/// sample distance frames will ask for (MeshPiece::ghost). A failure on any rank throws on
/// every rank. Throws Error(Argument) when the tree cannot be split into as many nodes as ranks.
RankPiece distributeMesh(Communicator& comm, MeshShare share, const PrepareOptions& options,
                         float ghostSteps, float reach = 0.f, const ProgressFn& progress = {});

}  // namespace uvr
