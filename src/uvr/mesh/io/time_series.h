// SPDX-License-Identifier: MIT
// Time series: a file with several time steps (Exodus II, temporal VTKHDF), a `.pvd` collection
// or a numbered file series (name_0000.vtu, name_0001.vtu, ...), read one step at a time; a
// step whose points and cells equal the mesh already held gives only its fields, so a renderer
// refreshes values without rebuilding anything geometric.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "uvr/mesh/io/native.h"
#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// A mesh file or series opened for reading its time steps one at a time. Every file is a
/// series: one without time is one step at time 0. Not thread-safe: one reader at a time.
class MeshSeries {
public:
    virtual ~MeshSeries() = default;

    /// The path it was opened with (for messages).
    const std::string& path() const { return path_; }
    /// Step count (at least 1).
    std::size_t stepCount() const { return times_.size(); }
    /// Times of the steps, in file order (increasing for every format that orders them); a
    /// file without time values gives 0, 1, 2, ...
    const std::vector<double>& times() const { return times_; }
    /// Where step i's data come from when it is a file of its own (.pvd, numbered series),
    /// else the series' path.
    virtual std::string stepSource(std::size_t i) const { return (checkStep(i), path_); }

    /// The whole mesh at step i: its geometry and that step's fields; Error(Argument) when i
    /// is out of range, reader errors naming the file otherwise.
    virtual Mesh readStep(std::size_t i) = 0;

    /// The fields of step i when its points and cells equal `geometry` (the usual case: only
    /// values change), else nullopt (the caller reads the step whole with readStep). The fields
    /// are those readStep(i) would give. The default reads the step whole and compares.
    virtual std::optional<std::vector<Field>> readFieldsIfSameGeometry(std::size_t i,
                                                                       const MeshView& geometry);

    /// How many parts step i is stored in that readPart reads runs of (a data-parallel rank's
    /// share: a VTKHDF file's partitions, an Exodus II file's cells, the pieces of a step that is
    /// one .pvtu); 0 for a format read only whole.
    virtual std::uint64_t partCount(std::size_t i) const { return (checkStep(i), 0); }
    /// What those parts are, for messages: "partitions", "cells", "pieces".
    virtual const char* partName() const { return "parts"; }
    /// The parts [first, end) of step i and what they use, with the ids of their points and
    /// cells in the whole step (MeshPart). Throws Error(Argument) for a range beyond
    /// partCount(i), Error(Unsupported) for a format read only whole.
    virtual MeshPart readPart(std::size_t i, std::uint64_t first, std::uint64_t end);

protected:
    MeshSeries(std::string path, std::vector<double> times, ReadOptions options);
    /// Error(Argument) naming the series unless i < stepCount().
    void checkStep(std::size_t i) const;
    /// The options every step is read with.
    const ReadOptions& options() const { return options_; }

private:
    std::string path_;
    std::vector<double> times_;
    ReadOptions options_;
};

/// Opens a mesh file or series: a .pvd collection (its DataSets by timestep, parts of one
/// timestep merged), a numbered file series named by a pattern with one '*' in the file name
/// (`run_*.vtu`: the '*' stands for the step's number, one or more digits; times 0, 1, 2, ...
/// in numeric order), formats with time steps (Exodus II), and one step at time 0 for any other
/// file that readMesh reads. Reads no step yet (only what lists the steps); throws Error naming the
/// file.
std::unique_ptr<MeshSeries> openMeshSeries(const std::string& path,
                                           const ReadOptions& options = {});

/// True when path names a numbered file series ('*' in its file name) rather than one file.
bool isSeriesPattern(const std::string& path);

/// The step shown at time t, as ParaView snaps: the last step whose time is <= t (the first
/// step for t before it); Error(Argument) for a non-finite t.
std::size_t stepAtTime(const std::vector<double>& times, double t);

/// True when both views hold the same points (bit for bit), cell types, offsets and indices.
bool sameGeometry(const MeshView& a, const MeshView& b);

/// Whether a part read (readPart) holds the points and cells of another step's part, given by its
/// geometry and the ids of its points and cells in the whole mesh: the same ids, positions and
/// cells.
bool samePartGeometry(const MeshPart& part, const MeshView& geometry,
                      std::span<const std::uint64_t> pointIds,
                      std::span<const std::uint64_t> cellIds);

}  // namespace uvr
