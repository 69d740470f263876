// SPDX-License-Identifier: MIT
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "uvr/facade/renderer.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/io/time_series.h"

namespace uvr {

/// What showing a time step did.
struct StepUpdate {
    std::size_t step = 0;
    double time = 0.0;
    bool rebuilt = false;        ///< the step's geometry differs: its mesh was prepared anew
    bool prefetched = false;     ///< its read had been started by prefetch
    double readSeconds = 0.0;    ///< reading the step (after a prefetch: only the wait for it)
    double updateSeconds = 0.0;  ///< refreshing the values, or preparing the new geometry
};

/// Plays a mesh series through one Renderer: the first step is read and prepared once; a later
/// step whose points and cells are the same gives the renderer only its new values
/// (Renderer::setFieldValues, nothing geometric rebuilt), one whose geometry differs is
/// prepared anew. prefetch(i) reads step i on a thread of its own while the caller renders.
/// One caller at a time. Data-parallel (RendererOptions::communicator): every rank plays the
/// series with the same calls, gives its piece the new values (Renderer::setFieldValues routes
/// them), and a rank's failure ends every rank. A series stored in parts, at least one a rank
/// (MeshSeries::partCount: a VTKHDF file's partitions, an Exodus II file's cells), is read by
/// parts: each rank reads only its run of each step's parts (byParts); any other series is read
/// whole on every rank.
class SeriesPlayer {
public:
    /// Reads step `first` of the series and prepares the field `spec` names for rendering;
    /// throws reader errors, Error(Argument) for an unknown field or step.
    SeriesPlayer(std::unique_ptr<MeshSeries> series, FieldSpec spec, const RendererOptions& options,
                 std::size_t first = 0, const ProgressFn& progress = {});
    ~SeriesPlayer();
    SeriesPlayer(const SeriesPlayer&) = delete;
    SeriesPlayer& operator=(const SeriesPlayer&) = delete;

    /// Makes the renderer show step i (a prefetched read of i is taken, one of another step is
    /// waited for and dropped). With `next`, the read of that step starts in the background as
    /// soon as step i's data are in, so that it overlaps step i's value refresh and frames. On
    /// an error (a bad file, the field missing at that step) the player still shows the step it
    /// showed before.
    StepUpdate show(std::size_t i, std::optional<std::size_t> next = std::nullopt);
    /// Starts reading step i in the background (fields only when its geometry is the current
    /// one); nothing when i is out of range or is the current step. Errors surface in show(i).
    void prefetch(std::size_t i);

    /// The renderer, prepared for the current step.
    Renderer& renderer() { return *renderer_; }
    /// The current step's mesh: the geometry and that step's fields (this rank's part when
    /// byParts()).
    const Mesh& mesh() const { return parts_ ? part_.mesh : mesh_; }
    /// The rendered field's values at the current step.
    const ScalarField& field() const { return field_; }
    /// The field spec every step renders: the one given, its default resolved at the first step
    /// (pinField).
    const FieldSpec& spec() const { return spec_; }
    /// Whether each rank reads only its parts of each step (data-parallel, a series stored in
    /// parts): mesh() and field() are then this rank's part's.
    bool byParts() const { return parts_.has_value(); }
    /// The rendered field's values at step i (a value range over the steps): of this rank's
    /// part when byParts(), else of the whole mesh. A prefetch is waited for and dropped.
    /// Collective data-parallel; throws reader errors, Error(Argument) for an unknown step or a
    /// step without the field.
    std::vector<float> stepValues(std::size_t i);
    /// The series.
    const MeshSeries& series() const { return *series_; }
    /// The step shown.
    std::size_t step() const { return step_; }

private:
    struct Read;
    Read readStep(std::size_t i);
    /// A renderer for this rank's part (byParts; collective): its share moved to the pieces,
    /// spec_ pinned to the field the ranks chose; sets field_.
    std::unique_ptr<Renderer> partRenderer(const MeshPart& part);
    /// The mesh of the current step: the part's (byParts) or the whole mesh.
    Mesh& current() { return parts_ ? part_.mesh : mesh_; }
    /// Runs work(); data-parallel (RendererOptions::communicator), agrees on its failures.
    template <class F>
    void agreed(F&& work);

    std::unique_ptr<MeshSeries> series_;
    FieldSpec spec_;
    RendererOptions options_;
    ProgressFn progress_;
    Mesh mesh_;  ///< the current step read whole (not byParts)
    /// byParts: this rank's parts of the current step, and what was read.
    std::optional<std::pair<std::uint64_t, std::uint64_t>> parts_;
    MeshPart part_;
    ScalarField field_;
    std::unique_ptr<Renderer> renderer_;
    std::size_t step_ = 0;
    struct Pending;
    std::unique_ptr<Pending> pending_;
};

}  // namespace uvr
